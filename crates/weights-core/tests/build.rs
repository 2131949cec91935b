//! Building a rig: progress reports, the virtual handles saved with the handle they were
//! placed for, and the limits refused up front.

use crate::support;

use std::sync::Mutex;

use glam::DVec2;
use proptest::prelude::*;
use support::{Rng, Shape, grid_domain};
use weights_core::{
    Domain, Handle, MAX_HANDLES, Phase, Progress, Rig, RigError, RigOptions, VirtualHandle,
};

/// The sample nearest to grid point (x, y).
fn at(domain: &Domain, x: f64, y: f64) -> DVec2 {
    let v = domain
        .nearest_vertex(DVec2::new(x, y))
        .expect("a non-empty domain");
    domain.positions()[v as usize]
}

/// Builds with a progress callback and returns the rig and every report.
fn build_reporting(domain: Domain, handles: Vec<Handle>) -> (Rig, Vec<Progress>) {
    let reports = Mutex::new(Vec::new());
    let rig = Rig::with_progress(domain, handles, &[], RigOptions::default(), &|p| {
        reports.lock().expect("not poisoned").push(p);
    })
    .expect("valid");
    (rig, reports.into_inner().expect("not poisoned"))
}

#[test]
fn progress_is_reported_in_order_and_reaches_the_end() {
    for shape in [Shape::Holed, Shape::Rectangle] {
        let domain = grid_domain(90, 70, 1.0, 0.3, shape, 11);
        // Two handles one edge apart (thousands of virtual handles) and a few more.
        let handles = vec![
            Handle::point(at(&domain, 10.0, 10.0)),
            Handle::point(at(&domain, 11.0, 10.0)),
            Handle::point(at(&domain, 80.0, 60.0)),
            Handle::bar(at(&domain, 20.0, 60.0), at(&domain, 30.0, 62.0)),
        ];
        let (rig, reports) = build_reporting(domain, handles);
        assert!(reports.len() > 10, "{shape:?}: {} reports", reports.len());
        for pair in reports.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            assert!(
                (a.phase, a.done) <= (b.phase, b.done),
                "{shape:?}: {a:?} then {b:?}"
            );
            assert!(a.fraction() <= b.fraction(), "{shape:?}: {a:?} then {b:?}");
            assert!(b.total.is_none_or(|t| b.done <= t), "{b:?}");
        }
        let last = reports.last().expect("reports");
        assert_eq!(last.phase, Phase::Transforms);
        assert_eq!(Some(last.done), last.total);
        assert_eq!(last.fraction(), 1.0);
        // The virtual handles' phase ends with their number.
        let placed = reports
            .iter()
            .rfind(|p| p.phase == Phase::VirtualHandles)
            .expect("the phase is reported");
        assert_eq!(placed.total, Some(rig.stats().virtual_nodes));
        assert!(rig.stats().virtual_nodes > 64, "{:?}", rig.stats());
        // Every phase shows up, in order.
        let mut phases: Vec<Phase> = reports.iter().map(|p| p.phase).collect();
        phases.dedup();
        assert_eq!(
            phases,
            [
                Phase::Partition,
                Phase::VirtualHandles,
                Phase::Weights,
                Phase::Transforms
            ]
        );
    }
}

#[test]
fn a_rig_without_handles_reports_its_end_too() {
    let domain = grid_domain(10, 8, 1.0, 0.3, Shape::Rectangle, 1);
    let (_, reports) = build_reporting(domain, Vec::new());
    let last = reports.last().expect("reports");
    assert_eq!((last.phase, last.fraction()), (Phase::Transforms, 1.0));
}

/// A rig built from scratch with the virtual handles of `rig` and the handles they were
/// placed for.
fn rebuild_with_placed(rig: &Rig) -> Rig {
    Rig::with_placed_virtual_handles(
        rig.domain().clone(),
        rig.handles().to_vec(),
        &rig.placed_virtual_handles(),
        RigOptions::default(),
    )
    .expect("valid")
}

/// The virtual handles of a rig as a sorted list (node order may differ).
fn placed_sorted(rig: &Rig) -> Vec<VirtualHandle> {
    let mut list = rig.placed_virtual_handles();
    list.sort_by_key(|v| v.vertex);
    list
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, .. ProptestConfig::default() })]

    /// Removing a handle from a rig rebuilt from its saved virtual handles (with the
    /// handles they were placed for) takes the same virtual handles away as removing it
    /// from the rig that placed them, and leaves the same weights.
    #[test]
    fn a_rebuild_with_placed_virtual_handles_removes_what_the_original_removes(
        seed in any::<u64>(),
        convex in any::<bool>(),
    ) {
        let shape = if convex { Shape::Rectangle } else { Shape::Holed };
        let domain = grid_domain(40, 30, 1.0, 0.3, shape, seed);
        let mut rng = Rng(seed);
        let p = |rng: &mut Rng| domain.positions()[rng.below(domain.len())];
        let mut rig = Rig::new(
            domain.clone(),
            vec![Handle::point(at(&domain, 30.0, 6.0)), Handle::bar(at(&domain, 5.0, 25.0), at(&domain, 15.0, 27.0))],
            RigOptions::default(),
        )
        .expect("valid");
        // Insert handles, some beside others, so that they place virtual handles.
        let mut tries = 0;
        while rig.handles().len() < 6 && tries < 50 {
            tries += 1;
            let near = rig.handles()[rng.below(rig.handles().len())].clone();
            let q = match near {
                Handle::Point { rest, .. } => rest,
                Handle::Bar { rest, .. } => rest[0],
            } + DVec2::new(rng.unit() * 8.0 - 4.0, rng.unit() * 8.0 - 4.0);
            let q = if rng.below(2) == 0 { q } else { p(&mut rng) };
            let _ = rig.insert_handle(Handle::point(q));
        }
        let rebuilt = rebuild_with_placed(&rig);
        prop_assert_eq!(rig.stats(), rebuilt.stats());
        prop_assert_eq!(placed_sorted(&rig), placed_sorted(&rebuilt));
        if let Err(e) = rig.same_weights_as(&rebuilt) {
            prop_assert!(false, "rebuilt: {}", e);
        }
        for i in 0..rig.handles().len() {
            let (mut a, mut b) = (rig.clone(), rebuilt.clone());
            a.remove_handle(i).expect("exists");
            b.remove_handle(i).expect("exists");
            prop_assert_eq!(a.stats(), b.stats(), "removing handle {}", i);
            prop_assert_eq!(placed_sorted(&a), placed_sorted(&b), "removing handle {}", i);
            if let Err(e) = a.same_weights_as(&b) {
                prop_assert!(false, "removing handle {}: {}", i, e);
            }
            // Handles after the removed one are renumbered in the saved list too.
            for v in a.placed_virtual_handles() {
                prop_assert!(v.placed_for.is_none_or(|h| h < a.handles().len()));
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, .. ProptestConfig::default() })]

    /// After insertions and removals (which take the parts of the dual graph they did
    /// not change from the previous solve), the virtual handles' harmonic coordinates and
    /// the node transforms equal a rebuild's, bit for bit.
    #[test]
    fn harmonic_coordinates_after_updates_equal_a_rebuild(
        seed in any::<u64>(),
        convex in any::<bool>(),
        renumbered in any::<bool>(),
    ) {
        let shape = if convex { Shape::Rectangle } else { Shape::Holed };
        let domain = grid_domain(44, 32, 1.0, 0.3, shape, seed);
        let domain = support::renumbered_if(domain, renumbered);
        let mut rng = Rng(seed);
        let mut rig = Rig::new(
            domain.clone(),
            vec![
                Handle::point(at(&domain, 30.0, 6.0)),
                Handle::bar(at(&domain, 5.0, 25.0), at(&domain, 15.0, 27.0)),
            ],
            RigOptions::default(),
        )
        .expect("valid");
        for step in 0..8 {
            if step % 3 == 2 && rig.handles().len() > 1 {
                rig.remove_handle(rng.below(rig.handles().len())).expect("exists");
            } else {
                let p = domain.positions()[rng.below(domain.len())];
                if rig.insert_handle(Handle::point(p)).is_err() {
                    continue;
                }
            }
            // Pose the handles, so that the transforms blend different motions.
            for i in 0..rig.handles().len() {
                if let Handle::Point { .. } = rig.handles()[i] {
                    let t = weights_core::Similarity {
                        translation: DVec2::new(i as f64, -(i as f64) * 0.5),
                        rotation: 0.1 * i as f64,
                        scale: 1.0 + 0.01 * i as f64,
                    };
                    rig.set_point_transform(i, t).expect("a point");
                }
            }
            let mut rebuilt = rebuild_with_placed(&rig);
            rebuilt.set_handles(rig.handles().to_vec()).expect("same rest");
            let index: std::collections::HashMap<u32, usize> = rebuilt
                .nodes()
                .iter()
                .enumerate()
                .map(|(k, n)| (n.vertex, k))
                .collect();
            for (k, n) in rig.nodes().iter().enumerate() {
                let j = index[&n.vertex];
                prop_assert_eq!(rig.harmonic_coordinates(k), rebuilt.harmonic_coordinates(j));
                prop_assert_eq!(rig.node_transform(k), rebuilt.node_transform(j));
            }
        }
    }
}

#[test]
fn a_removed_handle_takes_its_virtual_handles_along_after_a_reload() {
    let domain = grid_domain(60, 45, 1.0, 0.3, Shape::Holed, 9);
    let handles = vec![
        Handle::point(at(&domain, 8.0, 8.0)),
        Handle::point(at(&domain, 50.0, 40.0)),
    ];
    let mut rig = Rig::new(domain, handles, RigOptions::default()).expect("valid");
    let before = rig.stats().virtual_nodes;
    // Beside handle 0: rings of virtual handles, placed for the new handle 2.
    let new = rig
        .insert_handle(Handle::point(at(rig.domain(), 10.0, 8.0)))
        .expect("room");
    let placed: Vec<VirtualHandle> = rig
        .placed_virtual_handles()
        .into_iter()
        .filter(|v| v.placed_for == Some(new))
        .collect();
    assert!(placed.len() > 3, "{placed:?}");
    // Removing handle 0 first renumbers the new one to 1.
    rig.remove_handle(0).expect("exists");
    let renumbered = rig
        .placed_virtual_handles()
        .into_iter()
        .filter(|v| v.placed_for == Some(new - 1))
        .count();
    assert!(renumbered > 0);
    // After a reload with only the positions, they would stay; with the handles they
    // were placed for, they go with it.
    let mut plain = Rig::with_virtual_handles(
        rig.domain().clone(),
        rig.handles().to_vec(),
        &rig.virtual_vertices(),
        RigOptions::default(),
    )
    .expect("valid");
    let mut placed_rig = rebuild_with_placed(&rig);
    plain.remove_handle(new - 1).expect("exists");
    placed_rig.remove_handle(new - 1).expect("exists");
    rig.remove_handle(new - 1).expect("exists");
    assert!(
        placed_rig
            .placed_virtual_handles()
            .iter()
            .all(|v| v.placed_for.is_none())
    );
    assert_eq!(placed_sorted(&placed_rig), placed_sorted(&rig));
    assert!(plain.stats().virtual_nodes > placed_rig.stats().virtual_nodes);
    assert!(
        rig.stats().virtual_nodes <= before + 2,
        "{before} -> {:?}",
        rig.stats()
    );
}

#[test]
fn limits_are_refused_up_front() {
    let domain = grid_domain(20, 15, 1.0, 0.3, Shape::Rectangle, 2);
    // More handles than the rig takes: refused before anything is computed.
    let many: Vec<Handle> = (0..=MAX_HANDLES)
        .map(|i| Handle::point(DVec2::new((i % 100) as f64 * 0.2, (i / 100) as f64 * 0.15)))
        .collect();
    let clock = std::time::Instant::now();
    let err = Rig::new(domain.clone(), many, RigOptions::default()).expect_err("too many");
    assert_eq!(
        err,
        RigError::TooManyHandles {
            count: MAX_HANDLES + 1,
            max: MAX_HANDLES
        }
    );
    assert!(err.to_string().contains(&MAX_HANDLES.to_string()), "{err}");
    // Refused up front: the build itself would take minutes.
    assert!(clock.elapsed().as_secs_f64() < 10.0);
    // The same through an insertion.
    let mut rig = Rig::new(
        domain.clone(),
        vec![Handle::point(at(&domain, 5.0, 5.0))],
        RigOptions::default(),
    )
    .expect("valid");
    let mut handles = rig.handles().to_vec();
    handles.extend((0..MAX_HANDLES).map(|i| Handle::point(DVec2::new(i as f64 * 1e-3, 10.0))));
    assert!(matches!(
        rig.set_handles(handles),
        Err(RigError::TooManyHandles { .. })
    ));
    // More virtual handles than samples.
    let virtuals: Vec<u32> = (0..=domain.len() as u32).collect();
    let err =
        Rig::with_virtual_handles(domain.clone(), Vec::new(), &virtuals, RigOptions::default())
            .expect_err("too many");
    assert!(matches!(err, RigError::TooManyVirtual { .. }), "{err}");
    // A virtual handle placed for a handle that is not there.
    let err = Rig::with_placed_virtual_handles(
        domain.clone(),
        vec![Handle::point(at(&domain, 5.0, 5.0))],
        &[VirtualHandle {
            vertex: 40,
            placed_for: Some(1),
        }],
        RigOptions::default(),
    )
    .expect_err("no handle 1");
    assert_eq!(
        err,
        RigError::BadPlacedFor {
            index: 0,
            handle: 1
        }
    );
}
