//! Handles laid over a posed rig (placed in a posed state): the weights keep their
//! invariants, placing one moves nothing, it moves the picture when it moves, its
//! point stays under it, and a rebuild equals the incremental update.

use crate::support;

use glam::DVec2;
use support::{Shape, grid_domain};
use weights_core::{Domain, Handle, Rig, RigOptions, Similarity, similarity_fit};

/// A posed rig of three point handles and a bar on a holed grid (intrinsic metric).
fn posed_rig(shape: Shape) -> Rig {
    let domain = grid_domain(40, 30, 5.0, 0.2, shape, 7);
    let handles = vec![
        Handle::Point {
            rest: DVec2::new(20.0, 20.0),
            transform: Similarity {
                translation: DVec2::new(12.0, -5.0),
                rotation: 0.3,
                scale: 1.1,
            },
        },
        Handle::Point {
            rest: DVec2::new(180.0, 30.0),
            transform: Similarity::translate(DVec2::new(-10.0, 20.0)),
        },
        Handle::Point {
            rest: DVec2::new(170.0, 130.0),
            transform: Similarity {
                translation: DVec2::new(5.0, 5.0),
                rotation: -0.5,
                scale: 0.9,
            },
        },
        Handle::Bar {
            rest: [DVec2::new(30.0, 120.0), DVec2::new(80.0, 135.0)],
            pose: [DVec2::new(25.0, 110.0), DVec2::new(70.0, 140.0)],
        },
    ];
    Rig::new(domain, handles, RigOptions::default()).expect("a rig")
}

/// A point handle placed at `rest` where the rig's picture has it, with the fit the
/// editor gives it.
fn placed_point(rig: &Rig, picture: &[DVec2], rest: DVec2) -> Handle {
    let at = rig.deform_point(picture, rest).expect("on the shape");
    let positions = rig.domain().positions();
    let reach = rig
        .nodes()
        .iter()
        .map(|n| positions[n.vertex as usize].distance(rest))
        .fold(f64::INFINITY, f64::min);
    let (rotation, scale) =
        similarity_fit(rig.domain(), &rig.options().basis, picture, rest, at, reach)
            .expect("a fit");
    Handle::Point {
        rest,
        transform: Similarity {
            translation: at - rest,
            rotation,
            scale,
        },
    }
}

fn largest_move(a: &[DVec2], b: &[DVec2]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| p.distance(*q))
        .fold(0.0, f64::max)
}

fn check_weights(rig: &Rig) {
    for v in 0..rig.domain().len() {
        let row: Vec<(usize, f64)> = rig.weights(v).collect();
        let sum: f64 = row.iter().map(|e| e.1).sum();
        assert!((sum - 1.0).abs() < 1e-9, "sample {v}: weights sum to {sum}");
        assert!(row.iter().all(|e| e.1 >= 0.0), "sample {v}: {row:?}");
    }
    // Every handle's own samples are its alone.
    for (k, node) in rig.nodes().iter().enumerate() {
        let Some(h) = rig.owner_handle(k) else {
            continue;
        };
        if node.kind == weights_core::NodeKind::Virtual {
            continue;
        }
        let row: Vec<(usize, f64)> = rig.weights(node.vertex as usize).collect();
        let own: f64 = row
            .iter()
            .filter(|e| {
                rig.owner_handle(e.0) == Some(h)
                    && rig.nodes()[e.0].kind != weights_core::NodeKind::Virtual
            })
            .map(|e| e.1)
            .sum();
        assert!(
            (own - 1.0).abs() < 1e-12,
            "handle {h}'s node {k} holds {own} of its sample"
        );
    }
}

#[test]
fn placing_a_handle_in_a_posed_state_moves_nothing() {
    for shape in [Shape::Rectangle, Shape::Holed] {
        let mut rig = posed_rig(shape);
        let before = rig.deform();
        let mut handles = rig.handles().to_vec();
        handles.push(placed_point(&rig, &before, DVec2::new(105.0, 42.0)));
        handles.push(Handle::Bar {
            rest: [DVec2::new(120.0, 20.0), DVec2::new(150.0, 40.0)],
            pose: [
                rig.deform_point(&before, DVec2::new(120.0, 20.0))
                    .expect("on the shape"),
                rig.deform_point(&before, DVec2::new(150.0, 40.0))
                    .expect("on the shape"),
            ],
        });
        rig.set_handles_overlaid(handles.clone(), &[4, 5])
            .expect("overlaid");
        assert_eq!(rig.overlaid(), vec![4, 5]);
        let after = rig.deform();
        let moved = largest_move(&before, &after);
        assert!(
            moved < 1e-6,
            "{shape:?}: placing two handles moved the picture {moved} px"
        );
        check_weights(&rig);

        // The same handles not overlaid: the paper's re-partition moves it.
        let mut plain = posed_rig(shape);
        plain.set_handles(handles.clone()).expect("inserted");
        let jump = largest_move(&before, &plain.deform());
        assert!(
            jump > 0.5,
            "{shape:?}: the paper's insertion moved only {jump} px"
        );

        // A rebuild with the same handles, overlaid, is the same rig.
        let rebuilt = Rig::with_overlaid(
            rig.domain().clone(),
            handles,
            &[4, 5],
            &rig.placed_virtual_handles(),
            RigOptions::default(),
            &|_| {},
        )
        .expect("rebuilt");
        rig.same_weights_as(&rebuilt).expect("the same weights");
        assert_eq!(rebuilt.deform(), after, "the same picture");
    }
}

#[test]
fn an_overlaid_handle_moves_the_picture_under_it_and_holds_its_point() {
    let mut rig = posed_rig(Shape::Holed);
    let picture = rig.deform();
    let rest = DVec2::new(105.0, 42.0);
    let mut handles = rig.handles().to_vec();
    handles.push(placed_point(&rig, &picture, rest));
    rig.set_handles_overlaid(handles.clone(), &[4])
        .expect("overlaid");

    // Dragged by (15, −8): its point follows exactly, far away nothing moves.
    let Handle::Point { transform, .. } = handles[4] else {
        unreachable!()
    };
    let dragged = Similarity {
        translation: transform.translation + DVec2::new(15.0, -8.0),
        ..transform
    };
    rig.set_point_transform(4, dragged).expect("posed");
    let moved = rig.deform();
    let at = rig.deform_point(&moved, rest).expect("on the shape");
    let expected = rest + dragged.translation;
    assert!(
        at.distance(expected) < 0.5,
        "its point is at {at}, the handle at {expected}"
    );
    let positions = rig.domain().positions();
    let last = rig.nodes().len() - 1;
    let (r, centre) = (
        rig.radii(last).support,
        positions[rig.nodes()[last].vertex as usize],
    );
    for v in 0..positions.len() {
        if positions[v].distance(centre) > r {
            assert!(
                moved[v].distance(picture[v]) < 1e-9,
                "sample {v} beyond the bump moved"
            );
        }
    }

    // Another handle moved: the new one's point stays under it.
    let mut handles = rig.handles().to_vec();
    if let Handle::Point { transform, .. } = &mut handles[1] {
        transform.translation += DVec2::new(-30.0, 25.0);
    }
    rig.set_handles_overlaid(handles, &[4]).expect("posed");
    let moved = rig.deform();
    let at = rig.deform_point(&moved, rest).expect("on the shape");
    assert!(
        at.distance(expected) < 0.5,
        "its point went to {at}, the handle is at {expected}"
    );
    check_weights(&rig);
}

#[test]
fn removing_an_overlaid_handle_restores_the_picture_and_bad_indices_are_refused() {
    let mut rig = posed_rig(Shape::Holed);
    let picture = rig.deform();
    let mut handles = rig.handles().to_vec();
    handles.push(placed_point(&rig, &picture, DVec2::new(105.0, 42.0)));
    rig.set_handles_overlaid(handles.clone(), &[4])
        .expect("overlaid");
    assert!(rig.set_handles_overlaid(handles.clone(), &[5]).is_err());
    assert_eq!(rig.overlaid(), vec![4], "unchanged on error");
    rig.remove_handle(4).expect("removed");
    assert!(rig.overlaid().is_empty());
    assert!(largest_move(&picture, &rig.deform()) < 1e-9);
    // Removing a handle before it renumbers it and keeps it overlaid.
    rig.set_handles_overlaid(handles, &[4]).expect("overlaid");
    rig.remove_handle(0).expect("removed");
    assert_eq!(rig.overlaid(), vec![3]);
    let _: &Domain = rig.domain();
}
