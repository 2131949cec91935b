//! Cuts separate a flat picture's parts that touch: a pin moved on one side leaves the
//! other side where it was, under C² and ARAP; the cut is part of the rig file, so a
//! reopened project builds the same mesh.

use project::{Cut, Method, Project};

use crate::support::point;

/// Two blobs that touch along x = 60 for y in 20..40 only (a tail against a leg).
fn touching() -> image::RgbaImage {
    image::RgbaImage::from_fn(120, 60, |x, y| {
        let left = (8..60).contains(&x) && (8..52).contains(&y);
        let right = (60..112).contains(&x) && (20..40).contains(&y);
        image::Rgba([180, 90, 40, if left || right { 255 } else { 0 }])
    })
}

/// The largest move of a vertex of the left blob (x < 59) when the right blob's pin
/// is pulled down.
fn left_moves(method: Method, cuts: Vec<Cut>) -> f64 {
    let project = Project {
        density: Some(3_000),
        method,
        handles: vec![
            point([20.0, 30.0], [0.0, 0.0]),
            point([100.0, 30.0], [0.0, 25.0]),
        ],
        cuts,
        ..Project::default()
    };
    largest_move(&project, |x| x < 59.0)
}

/// The largest move of a vertex of `touching()` whose rest x is `where_`, warped by
/// `project`'s method (every position finite).
fn largest_move(project: &Project, where_: impl Fn(f64) -> bool) -> f64 {
    let method = project.method;
    let warper = pipeline::prepare_warper(&touching(), project, None, &())
        .unwrap_or_else(|e| panic!("{}: {}", method.name(), pipeline::error_line(&e)));
    let rest = warper.deformer.rest().to_vec();
    let deformed = warper.deformer.deformed();
    assert!(deformed.iter().all(|p| p.is_finite()), "{}", method.name());
    rest.iter()
        .zip(&deformed)
        .filter(|(r, _)| where_(r.x))
        .map(|(r, d)| r.distance(*d))
        .fold(0.0, f64::max)
}

fn across() -> Vec<Cut> {
    vec![Cut {
        stroke: vec![[60.0, -5.0], [60.0, 65.0]],
    }]
}

#[test]
fn a_cut_lets_touching_parts_move_apart() {
    for method in [Method::C2, Method::Arap] {
        let joined = left_moves(method, Vec::new());
        let cut = left_moves(method, across());
        assert!(
            joined > 2.0,
            "{}: without the cut the left blob is pulled ({joined})",
            method.name()
        );
        assert!(
            cut <= 0.5,
            "{}: with the cut the left blob stays ({cut} px)",
            method.name()
        );
    }
}

#[test]
fn a_cut_round_trips_and_bad_strokes_are_refused() {
    let project = Project {
        handles: vec![point([20.0, 30.0], [0.0, 0.0])],
        cuts: across(),
        ..Project::default()
    };
    let again = Project::from_json(&project.to_json()).expect("its JSON parses");
    assert_eq!(again, project);
    for (stroke, says) in [
        ("[[1,2]]", "2 to"),
        ("[[1,2],[1,2]]", "no length"),
        ("[[1,2],[1e300,2]]", "finite"),
    ] {
        let text = format!(r#"{{"version":1,"handles":[],"cuts":[{{"stroke":{stroke}}}]}}"#);
        let error = Project::from_json(&text).expect_err(stroke).to_string();
        assert!(error.contains(says), "{stroke}: {error}");
    }
}

#[test]
fn a_piece_cut_free_of_every_handle_stays_where_it_is_except_under_mls() {
    for method in [Method::C2, Method::Arap, Method::Mls] {
        let project = Project {
            density: Some(2_000),
            method,
            handles: vec![
                point([20.0, 30.0], [5.0, 3.0]),
                point([40.0, 15.0], [5.0, 3.0]),
            ],
            cuts: across(),
            ..Project::default()
        };
        let right = largest_move(&project, |x| x > 61.0);
        if method == Method::Mls {
            // MLS measures straight-line distance: a cut changes nothing for it.
            assert!(right > 1.0, "mls: {right}");
        } else {
            assert!(
                right < 1e-6,
                "{}: the free piece moves {right} px",
                method.name()
            );
        }
    }
}

/// Under LBC a cut splits the cage's inside too: cut through from one cage vertex to
/// another, the inside is two pieces, each moved by its own cage vertices; the cut's
/// vertices are doubled, and the copies part where the pieces move apart.
#[test]
fn a_cut_splits_the_inside_of_a_cage() {
    let warped = |cuts: Vec<Cut>| {
        let rest = vec![
            [4.0, 4.0],
            [60.0, 4.0],
            [116.0, 16.0],
            [116.0, 44.0],
            [60.0, 56.0],
            [4.0, 56.0],
        ];
        let mut pose = rest.clone();
        pose[2][1] += 25.0;
        pose[3][1] += 25.0;
        let project = Project {
            method: Method::Lbc,
            cage: Some(project::CageSpec {
                rest,
                pose: Some(pose),
            }),
            lbc: Some(project::LbcSettings {
                density: Some(1_500),
                ..project::LbcSettings::default()
            }),
            cuts,
            ..Project::default()
        };
        let warper = pipeline::prepare_warper(&touching(), &project, None, &())
            .unwrap_or_else(|e| panic!("{}", pipeline::error_line(&e)));
        let deformed = warper.deformer.deformed();
        assert!(deformed.iter().all(|p| p.is_finite()));
        (warper.deformer.rest().to_vec(), deformed)
    };
    // The largest distance between two vertices at the same rest position, and the
    // largest move of a vertex left of the cut.
    let measure = |(rest, deformed): (Vec<glam::DVec2>, Vec<glam::DVec2>)| {
        let mut gap = 0.0f64;
        let mut order: Vec<usize> = (0..rest.len()).collect();
        order.sort_by(|&a, &b| {
            rest[a]
                .x
                .total_cmp(&rest[b].x)
                .then(rest[a].y.total_cmp(&rest[b].y))
        });
        for pair in order.windows(2) {
            if rest[pair[0]] == rest[pair[1]] {
                gap = gap.max(deformed[pair[0]].distance(deformed[pair[1]]));
            }
        }
        let left = rest
            .iter()
            .zip(&deformed)
            .filter(|(r, _)| r.x < 59.0)
            .map(|(r, d)| r.distance(*d))
            .fold(0.0, f64::max);
        (gap, left)
    };
    let (joined_gap, joined_left) = measure(warped(Vec::new()));
    let (cut_gap, cut_left) = measure(warped(across()));
    assert_eq!(joined_gap, 0.0, "no vertex is doubled without a cut");
    assert!(cut_gap > 0.5, "the cut opens ({cut_gap} px)");
    // The left piece's cage vertices stay; what moves it is the solve's tolerance.
    assert!(
        cut_left < 1.5 && joined_left < 1.5,
        "{joined_left} / {cut_left}"
    );
}

/// Algorithm 1 may place a virtual handle on either side of a cut, on vertices at one
/// place: the rig file says which, so a reopened project has the same weights.
#[test]
fn virtual_handles_on_either_side_of_a_cut_reopen_on_their_side() {
    let image = touching();
    let mut later_copies = 0;
    for density in [600, 900, 1_500, 2_400] {
        let project = Project {
            density: Some(density),
            degree: 14,
            fixed_boundary: true,
            handles: vec![point([20.0, 30.0], [0.0, 0.0])],
            cuts: across(),
            ..Project::default()
        };
        let rig = pipeline::prepare(&image, &project, None)
            .expect("builds")
            .rig;
        let mut saved = project.clone();
        pipeline::write_virtual_handles(rig.domain(), &rig.placed_virtual_handles(), &mut saved);
        later_copies += saved.virtual_copy.iter().filter(|&&c| c > 0).count();
        let saved = Project::from_json(&saved.to_json()).expect("round trip");
        let reopened = pipeline::prepare(&image, &saved, None)
            .expect("reopens")
            .rig;
        assert_eq!(
            reopened.virtual_vertices(),
            rig.virtual_vertices(),
            "density {density}"
        );
        let weights = |rig: &weights_core::Rig| -> Vec<Vec<(usize, f64)>> {
            (0..rig.domain().positions().len())
                .map(|v| rig.weights(v).collect())
                .collect()
        };
        assert!(weights(&reopened) == weights(&rig), "density {density}");
    }
    assert!(later_copies > 0, "no virtual handle on a cut's second side");
}

/// ARAP and MLS are set up without a C² rig, and refuse the handles it would: one off
/// the shape, two at one place.
#[test]
fn every_handle_method_refuses_a_handle_off_the_shape_or_two_at_one_place() {
    for method in [Method::C2, Method::Arap, Method::Mls] {
        for (handles, says) in [
            (
                vec![
                    point([20.0, 30.0], [0.0, 0.0]),
                    point([2.0, 2.0], [0.0, 0.0]),
                ],
                "outside the shape",
            ),
            (
                vec![
                    point([20.0, 30.0], [0.0, 0.0]),
                    point([20.0, 30.0], [5.0, 0.0]),
                ],
                "coincide",
            ),
        ] {
            let project = Project {
                method,
                handles,
                ..Project::default()
            };
            let error = pipeline::prepare_warper(&touching(), &project, None, &())
                .err()
                .map(|e| pipeline::error_line(&e))
                .unwrap_or_default();
            assert!(error.contains(says), "{}: {error:?}", method.name());
        }
    }
}
