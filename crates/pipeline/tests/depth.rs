//! Automatic depth (the ARAP paper's §5.1) through the whole path: a strip folded back
//! over itself where two handles of different depths meet is drawn wholly in front or
//! wholly behind, for every method; the order is saved with the pose (`overlaps`) and
//! a file of that pose renders it.

use glam::DVec2;
use pipeline::Warper;
use project::{HandleSpec, Method, Project};

/// A U: two arms 24 pixels wide joined at the bottom.
fn strip() -> image::RgbaImage {
    image::RgbaImage::from_fn(200, 200, |x, y| {
        let left = (18..42).contains(&x) && (10..190).contains(&y);
        let right = (158..182).contains(&x) && (10..190).contains(&y);
        let bottom = (18..182).contains(&x) && (160..190).contains(&y);
        let inside = left || right || bottom;
        image::Rgba([x as u8, y as u8, 40, if inside { 255 } else { 0 }])
    })
}

fn point(rest: [f64; 2], translate: [f64; 2], depth: i32) -> HandleSpec {
    HandleSpec::Point {
        rest,
        translate,
        rotate: 0.0,
        scale: 1.0,
        depth,
    }
}

/// The U's right arm, whose handle lies between the left arm's two in depth, laid
/// over the left arm where their cells meet (the paper's Fig. 8).
fn folded(method: Method, auto_depth: bool) -> Project {
    Project {
        density: Some(1_500),
        method,
        handles: vec![
            point([30.0, 25.0], [0.0, 0.0], 0),
            point([30.0, 135.0], [0.0, 0.0], 2),
            point([100.0, 175.0], [0.0, 0.0], 0),
            point([170.0, 25.0], [-140.0, 55.0], 1),
        ],
        auto_depth,
        ..Project::default()
    }
}

/// Whether two triangles overlap with a positive area (no separating edge normal).
fn overlap(a: [DVec2; 3], b: [DVec2; 3]) -> bool {
    let separated_by = |t: [DVec2; 3]| {
        (0..3).any(|i| {
            let n = (t[(i + 1) % 3] - t[i]).perp();
            let project = |s: [DVec2; 3]| {
                let d = s.map(|p| n.dot(p));
                (d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2]))
            };
            let ((a0, a1), (b0, b1)) = (project(a), project(b));
            let slack = 1e-9 * n.length_squared().max(1.0);
            a1 <= b0 + slack || b1 <= a0 + slack
        })
    };
    !separated_by(a) && !separated_by(b)
}

/// Over the triangles of the right arm (rest x > 140, above the bottom) and of the
/// left arm (rest x < 60) that overlap: how many pairs draw the end in front, and how many behind.
fn fronts(warper: &Warper) -> (usize, usize) {
    let rest = warper.deformer.rest();
    let deformed = warper.deformer.deformed();
    let centre = |t: &[u32; 3]| t.iter().map(|&v| rest[v as usize]).sum::<DVec2>() / 3.0;
    let corners = |t: &[u32; 3]| t.map(|v| deformed[v as usize]);
    let (mut ahead, mut behind) = (0, 0);
    let drawn = &warper.triangles;
    for (i, s) in drawn.iter().enumerate() {
        if centre(s).x <= 140.0 || centre(s).y > 155.0 {
            continue;
        }
        for (j, t) in drawn.iter().enumerate() {
            if centre(t).x < 60.0 && overlap(corners(s), corners(t)) {
                if i > j {
                    ahead += 1;
                } else {
                    behind += 1;
                }
            }
        }
    }
    (ahead, behind)
}

fn warper(project: &Project) -> Warper {
    pipeline::prepare_warper(&strip(), project, None, &())
        .unwrap_or_else(|e| panic!("{}", pipeline::error_line(&e)))
}

#[test]
fn a_region_folded_between_two_depths_is_drawn_wholly_on_one_side() {
    // By the handles' depths alone, the end (depth 1) is in front of the first cell
    // (depth 0) and behind the second (depth 2): partly in front, partly behind.
    let (ahead, behind) = fronts(&warper(&folded(Method::C2, false)));
    assert!(ahead > 0 && behind > 0, "{ahead} {behind}");
    for method in [Method::C2, Method::Arap, Method::Mls] {
        let project = folded(method, true);
        let warper = warper(&project);
        let (ahead, behind) = fronts(&warper);
        assert!(
            ahead + behind > 0,
            "{}: the end overlaps the base",
            method.name()
        );
        assert!(
            ahead == 0 || behind == 0,
            "{}: {ahead} pairs in front, {behind} behind",
            method.name()
        );
        assert!(!warper.overlaps().is_empty(), "{}", method.name());
    }
}

#[test]
fn the_order_saved_with_the_pose_is_the_order_drawn() {
    let project = folded(Method::C2, true);
    let warper = warper(&project);
    let (ahead, _) = fronts(&warper);
    let decided_in_front = ahead > 0;
    // Saved as decided, the file draws the same picture.
    let saved = Project {
        overlaps: warper.overlaps(),
        ..project.clone()
    };
    let json = saved.to_json();
    let reopened = Project::from_json(&json).expect("reads");
    assert_eq!(reopened.overlaps, saved.overlaps);
    let again = self::warper(&reopened);
    assert_eq!(again.triangles, warper.triangles);
    // Saved the other way round (a region that slid in from the other side), the
    // file draws it the other way round, wholly.
    let flipped = Project {
        overlaps: warper
            .overlaps()
            .into_iter()
            .map(|o| project::OverlapOrder {
                front: o.back,
                back: o.front,
            })
            .collect(),
        ..project
    };
    let (ahead, behind) = fronts(&self::warper(&flipped));
    assert_eq!(
        (ahead > 0, behind > 0),
        (!decided_in_front, decided_in_front)
    );
    let picture = |p: &Project| pipeline::warp(&strip(), &self::warper(p)).expect("drawn");
    assert_ne!(picture(&saved), picture(&flipped));
}
