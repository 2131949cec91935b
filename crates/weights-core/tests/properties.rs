//! The invariants of the weights on random rigs, incremental updates against rebuilds,
//! consistency, symmetry and a bank of degenerate rigs.

use crate::support;

use glam::DVec2;
use proptest::prelude::*;
use support::{Rng, Shape, grid_domain};
use weights_core::{
    Domain, Handle, MAX_BAR_PIECES, Metric, NodeKind, Placement, Rig, RigError, RigOptions,
    Similarity, bar_spacing,
};

/// Checks every invariant the weights promise; returns a description of the first
/// violation.
fn check_invariants(rig: &Rig) -> Result<(), String> {
    let n = rig.domain().len();
    let nodes = rig.nodes();
    if nodes.is_empty() {
        // No handles: no weights, and nothing moves.
        return match (0..n).find(|&v| rig.weights(v).next().is_some()) {
            Some(v) => Err(format!("sample {v} has weights without handles")),
            None => Ok(()),
        };
    }
    // Partition of unity and non-negativity.
    for v in 0..n {
        let mut sum = 0.0;
        for (k, w) in rig.weights(v) {
            if w.is_nan() || w < 0.0 {
                return Err(format!("negative weight {w} of node {k} at sample {v}"));
            }
            sum += w;
        }
        if (sum - 1.0).abs() > 1e-9 {
            return Err(format!("weights at sample {v} sum to {sum}"));
        }
    }
    // Interpolation: exactly δ at the nodes.
    for (k, node) in nodes.iter().enumerate() {
        let row: Vec<(usize, f64)> = rig.weights(node.vertex as usize).collect();
        if row != vec![(k, 1.0)] {
            return Err(format!(
                "node {k} ({:?}) has weights {row:?} at its own sample",
                node.kind
            ));
        }
    }
    // r_d < r_h after virtual-handle insertion.
    for k in 0..nodes.len() {
        let r = rig.radii(k);
        if r.r_d.is_nan() || r.r_d >= r.r_h {
            return Err(format!("node {k}: r_d = {} ≥ r_h = {}", r.r_d, r.r_h));
        }
    }
    // Zero beyond the support.
    let mut positive: Vec<Vec<u32>> = vec![Vec::new(); nodes.len()];
    for v in 0..n {
        for (k, w) in rig.weights(v) {
            if w > 0.0 {
                positive[k].push(v as u32);
            }
        }
    }
    for (k, samples) in positive.iter().enumerate() {
        let d = rig.distances_from_node(k);
        let support = rig.radii(k).support;
        for &v in samples {
            let dv = d[v as usize];
            let owner_fallback = rig.cells()[v as usize] as usize == k;
            if dv > support || (dv == support && !owner_fallback) {
                return Err(format!(
                    "node {k} weighs sample {v} at distance {dv} beyond its support {support}"
                ));
            }
        }
    }
    Ok(())
}

/// A random rig of point and bar handles on sample positions.
/// `rig` built from scratch with its handles and virtual handles (default options).
fn rebuild_of(rig: &Rig) -> Rig {
    Rig::with_virtual_handles(
        rig.domain().clone(),
        rig.handles().to_vec(),
        &rig.virtual_vertices(),
        RigOptions::default(),
    )
    .expect("valid")
}

fn random_handles(domain: &Domain, rng: &mut Rng, points: usize, bars: usize) -> Vec<Handle> {
    let p = domain.positions();
    let mut handles = Vec::new();
    let mut tries = 0;
    while handles.len() < points + bars && tries < 1000 {
        tries += 1;
        let a = p[rng.below(p.len())];
        let h = if handles.len() < points {
            Handle::point(a)
        } else {
            let b = p[rng.below(p.len())];
            if (a - b).length() < 1.0 || (a - b).length() > 30.0 {
                continue;
            }
            Handle::bar(a, b)
        };
        let mut candidate = handles.clone();
        candidate.push(h);
        if Rig::new(domain.clone(), candidate.clone(), RigOptions::default()).is_ok() {
            handles = candidate;
        }
    }
    handles
}

fn shape_of(convex: bool) -> Shape {
    if convex {
        Shape::Rectangle
    } else {
        Shape::Holed
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, .. ProptestConfig::default() })]

    #[test]
    fn random_rigs_keep_every_invariant(
        seed in any::<u64>(),
        convex in any::<bool>(),
        points in 1usize..6,
        bars in 0usize..3,
        alpha in prop_oneof![Just(1.0), Just(0.0), 0.0f64..1.0],
        degree in 5u32..9,
    ) {
        let domain = grid_domain(40, 30, 1.0, 0.3, shape_of(convex), seed);
        let mut rng = Rng(seed ^ 0xABCD);
        let handles = random_handles(&domain, &mut rng, points, bars);
        let options = RigOptions {
            alpha,
            basis: weights_core::Basis::new(degree, weights_core::MiddleControls::Linear).expect("valid"),
            fixed_boundary: seed % 3 == 0,
            placement: if seed % 2 == 0 { Placement::AsWritten } else { Placement::Symmetric },
        };
        let rig = Rig::new(domain, handles, options).expect("valid rig");
        if let Err(e) = check_invariants(&rig) {
            prop_assert!(false, "{e}");
        }
    }

    #[test]
    fn insertion_and_removal_equal_a_rebuild(
        seed in any::<u64>(),
        convex in any::<bool>(),
        renumbered in any::<bool>(),
    ) {
        // Also on the mesh renumbered along the curve, its ties broken by the grid's
        // numbering.
        let domain = grid_domain(36, 28, 1.0, 0.3, shape_of(convex), seed);
        let domain = support::renumbered_if(domain, renumbered);
        let mut rng = Rng(seed);
        let handles = random_handles(&domain, &mut rng, 4, 1);
        let mut rig = Rig::new(domain.clone(), handles, RigOptions::default()).expect("valid");
        for step in 0..4 {
            if step % 2 == 0 {
                let p = domain.positions()[rng.below(domain.len())];
                if rig.insert_handle(Handle::point(p)).is_err() {
                    continue;
                }
            } else {
                let i = rng.below(rig.handles().len());
                rig.remove_handle(i).expect("exists");
            }
            let rebuilt = rebuild_of(&rig);
            prop_assert_eq!(rig.stats(), rebuilt.stats());
            if let Err(e) = rig.same_weights_as(&rebuilt) {
                prop_assert!(false, "step {}: {}", step, e);
            }
            if let Err(e) = check_invariants(&rig) {
                prop_assert!(false, "step {}: {}", step, e);
            }
        }
    }

    #[test]
    fn one_transform_on_every_handle_moves_every_point_by_it(
        seed in any::<u64>(),
        convex in any::<bool>(),
        angle in -3.0f64..3.0,
        scale in 0.5f64..2.0,
        shift in (-20.0f64..20.0, -20.0f64..20.0),
    ) {
        let domain = grid_domain(30, 24, 1.0, 0.3, shape_of(convex), seed);
        let mut rng = Rng(seed);
        let handles = random_handles(&domain, &mut rng, 4, 1);
        let global = glam::DAffine2::from_scale_angle_translation(
            DVec2::splat(scale),
            angle,
            DVec2::new(shift.0, shift.1),
        );
        let posed: Vec<Handle> = handles
            .iter()
            .map(|h| match *h {
                Handle::Point { rest, .. } => Handle::Point {
                    rest,
                    transform: Similarity {
                        translation: global.transform_point2(rest) - rest,
                        rotation: angle,
                        scale,
                    },
                },
                Handle::Bar { rest, .. } => Handle::Bar {
                    rest,
                    pose: rest.map(|p| global.transform_point2(p)),
                },
            })
            .collect();
        let mut rig = Rig::new(domain.clone(), handles, RigOptions::default()).expect("valid");
        rig.set_handles(posed).expect("same rest");
        let moved = rig.deform();
        for (v, q) in moved.iter().enumerate() {
            let expected = global.transform_point2(domain.positions()[v]);
            prop_assert!((*q - expected).length() < 1e-6, "sample {}: {} vs {}", v, q, expected);
        }
    }
}

/// A mirror-symmetric grid domain (mirror line x = nx / 2, nx even), jittered by
/// multiples of 1/256 so that mirrored coordinates are exact, with a centred hole and two
/// mirrored notches when `holed`.
fn symmetric_domain(nx: usize, ny: usize, holed: bool, metric: Metric) -> Domain {
    let mut rng = Rng(5);
    let mut jitter = std::collections::HashMap::new();
    let mut positions = Vec::new();
    for y in 0..=ny {
        for x in 0..=nx {
            let interior = x > 0 && y > 0 && x < nx && y < ny;
            let mirror_x = x.min(nx - x);
            let j = *jitter.entry((mirror_x, y)).or_insert_with(|| {
                let q = |r: &mut Rng| ((r.unit() - 0.5) * 0.5 * 256.0).round() / 256.0;
                DVec2::new(q(&mut rng), q(&mut rng))
            });
            let mut p = DVec2::new(x as f64, y as f64);
            if interior {
                let jx = if 2 * x == nx {
                    0.0
                } else if 2 * x < nx {
                    j.x
                } else {
                    -j.x
                };
                p += DVec2::new(jx, j.y);
            }
            positions.push(p);
        }
    }
    let keep = |x: usize, y: usize| {
        if !holed {
            return true;
        }
        let mx = x.min(nx - 1 - x);
        let hole = mx >= nx * 2 / 5 && y >= ny / 3 && y < ny * 2 / 3;
        let notch = mx >= nx / 8 && mx < nx / 8 + 2 && y < ny / 2;
        !hole && !notch
    };
    let triangles = support::grid_triangles(nx, ny, keep);
    support::compact(positions, triangles, metric)
}

#[test]
fn mirror_symmetric_rigs_give_mirror_symmetric_weights_and_warps() {
    for (holed, metric) in [
        (false, Metric::Euclidean),
        (false, Metric::Intrinsic),
        (true, Metric::Intrinsic),
    ] {
        let domain = symmetric_domain(40, 30, holed, metric);
        let width = 40.0;
        let mirror = |p: DVec2| DVec2::new(width - p.x, p.y);
        let positions = domain.positions();
        let index: std::collections::HashMap<(u64, u64), usize> = positions
            .iter()
            .enumerate()
            .map(|(i, p)| ((p.x.to_bits(), p.y.to_bits()), i))
            .collect();
        let find = |p: DVec2| index[&(p.x.to_bits(), p.y.to_bits())];
        let at = |x: usize, y: usize| positions[find_grid(&domain, x, y)];
        let left = [at(5, 6), at(12, 25)];
        let bar = [at(3, 15), at(9, 18)];
        let mut handles = Vec::new();
        for p in left {
            for (sign, rest) in [(1.0, p), (-1.0, mirror(p))] {
                handles.push(Handle::Point {
                    rest,
                    transform: Similarity {
                        translation: DVec2::new(-2.0 * sign, 1.5),
                        rotation: 0.2 * sign,
                        scale: 1.1,
                    },
                });
            }
        }
        let pose = [DVec2::new(1.0, 14.0), DVec2::new(8.0, 20.0)];
        handles.push(Handle::Bar { rest: bar, pose });
        handles.push(Handle::Bar {
            rest: bar.map(mirror),
            pose: pose.map(mirror),
        });
        // Tied cells are fixed together: the paper's one-at-a-time loop would break
        // each tie to one side.
        let options = RigOptions {
            placement: Placement::Symmetric,
            ..RigOptions::default()
        };
        let rig = Rig::new(domain.clone(), handles, options).expect("valid");
        check_invariants(&rig).expect("invariants");
        let node_at: std::collections::HashMap<u32, usize> = rig
            .nodes()
            .iter()
            .enumerate()
            .map(|(k, n)| (n.vertex, k))
            .collect();
        for (k, n) in rig.nodes().iter().enumerate() {
            let m = find(mirror(positions[n.vertex as usize])) as u32;
            assert!(
                node_at.contains_key(&m),
                "{metric:?}, holed {holed}: node {k} ({:?}) has no mirror image",
                n.kind
            );
        }
        let moved = rig.deform();
        for v in 0..domain.len() {
            let mv = find(mirror(positions[v]));
            for (k, w) in rig.weights(v) {
                let mk = find(mirror(positions[rig.nodes()[k].vertex as usize])) as u32;
                let k2 = node_at[&mk];
                let w2 = rig
                    .weights(mv)
                    .find(|&(k, _)| k == k2)
                    .map_or(0.0, |(_, w)| w);
                assert!(
                    (w - w2).abs() < 1e-6,
                    "holed {holed}: w at {v} = {w}, mirrored {w2}"
                );
            }
            assert!(
                (moved[mv] - mirror(moved[v])).length() < 1e-6,
                "holed {holed}: warp not symmetric at sample {v}"
            );
        }
    }
}

/// The sample nearest to grid point (x, y).
fn find_grid(domain: &Domain, x: usize, y: usize) -> usize {
    domain
        .nearest_vertex(DVec2::new(x as f64, y as f64))
        .expect("some sample") as usize
}

#[test]
fn degenerate_rigs_never_panic() {
    let convex = grid_domain(20, 15, 1.0, 0.2, Shape::Rectangle, 3);
    let holed = grid_domain(20, 20, 1.0, 0.2, Shape::Holed, 3);
    let tiny = Domain::new(
        vec![DVec2::ZERO, DVec2::new(1.0, 0.0), DVec2::new(0.0, 1.0)],
        vec![[0, 1, 2]],
        Metric::Euclidean,
    )
    .expect("valid");
    let nan = DVec2::new(f64::NAN, 1.0);
    /// Name, domain, handles, and the error expected (if any).
    type Case<'a> = (
        &'a str,
        &'a Domain,
        Vec<Handle>,
        Option<fn(&RigError) -> bool>,
    );
    let cases: Vec<Case> = vec![
        ("no handles", &convex, vec![], None),
        (
            "one handle",
            &convex,
            vec![Handle::point(DVec2::new(3.0, 3.0))],
            None,
        ),
        (
            "corner handles",
            &convex,
            vec![
                Handle::point(DVec2::ZERO),
                Handle::point(DVec2::new(20.0, 15.0)),
            ],
            None,
        ),
        (
            "boundary handles",
            &holed,
            vec![
                Handle::point(DVec2::new(0.0, 7.0)),
                Handle::point(DVec2::new(8.0, 8.0)),
            ],
            None,
        ),
        (
            "one sample apart",
            &holed,
            vec![
                Handle::point(DVec2::new(2.0, 2.0)),
                Handle::point(DVec2::new(3.0, 2.0)),
            ],
            None,
        ),
        (
            "one sample apart, convex",
            &convex,
            vec![
                Handle::point(DVec2::new(0.0, 0.0)),
                Handle::point(DVec2::new(1.0, 0.0)),
            ],
            None,
        ),
        (
            "collinear",
            &convex,
            (0..8)
                .map(|i| Handle::point(DVec2::new(2.0 + 2.0 * i as f64, 0.0)))
                .collect(),
            None,
        ),
        (
            "bar on the border",
            &convex,
            vec![Handle::bar(DVec2::new(0.0, 0.0), DVec2::new(20.0, 0.0))],
            None,
        ),
        (
            "bar across the hole",
            &holed,
            vec![Handle::bar(DVec2::new(1.0, 10.0), DVec2::new(19.0, 10.0))],
            Some(|e| matches!(e, RigError::OutsideDomain { .. })),
        ),
        (
            "every sample a handle",
            &tiny,
            (0..3).map(|i| Handle::point(tiny.positions()[i])).collect(),
            None,
        ),
        (
            "coincident",
            &convex,
            vec![
                Handle::point(DVec2::new(3.0, 3.0)),
                Handle::point(DVec2::new(3.0, 3.0)),
            ],
            Some(|e| matches!(e, RigError::Coincident { .. })),
        ),
        (
            "same sample",
            &convex,
            vec![
                Handle::point(DVec2::new(3.0, 3.0)),
                Handle::point(DVec2::new(3.01, 3.0)),
            ],
            Some(|e| matches!(e, RigError::SameSample { .. })),
        ),
        (
            "zero-length bar",
            &convex,
            vec![Handle::bar(DVec2::ONE, DVec2::ONE)],
            Some(|e| matches!(e, RigError::ZeroLengthBar { .. })),
        ),
        (
            "NaN",
            &convex,
            vec![Handle::point(nan)],
            Some(|e| matches!(e, RigError::NonFinite { .. })),
        ),
        (
            "outside",
            &convex,
            vec![Handle::point(DVec2::new(-5.0, 3.0))],
            Some(|e| matches!(e, RigError::OutsideDomain { .. })),
        ),
        (
            "in the hole",
            &holed,
            vec![Handle::point(DVec2::new(10.0, 10.0))],
            Some(|e| matches!(e, RigError::OutsideDomain { .. })),
        ),
        (
            "a pose that would overflow",
            &convex,
            vec![
                Handle::point(DVec2::new(3.0, 3.0)),
                Handle::Point {
                    rest: DVec2::new(12.0, 8.0),
                    transform: Similarity {
                        translation: DVec2::new(1e300, 0.0),
                        rotation: 0.0,
                        scale: 1.0,
                    },
                },
            ],
            Some(|e| matches!(e, RigError::PoseOutOfRange { handle: 1 })),
        ),
        (
            "a scale that would overflow",
            &convex,
            vec![Handle::Point {
                rest: DVec2::new(12.0, 8.0),
                transform: Similarity {
                    translation: DVec2::ZERO,
                    rotation: 0.0,
                    scale: 1e300,
                },
            }],
            Some(|e| matches!(e, RigError::PoseOutOfRange { .. })),
        ),
        (
            "a bar posed far away",
            &convex,
            vec![Handle::Bar {
                rest: [DVec2::new(2.0, 2.0), DVec2::new(10.0, 2.0)],
                pose: [DVec2::new(2.0, 2.0), DVec2::new(2e9, 2.0)],
            }],
            Some(|e| matches!(e, RigError::PoseOutOfRange { .. })),
        ),
        (
            "crossing bars",
            &convex,
            vec![
                Handle::bar(DVec2::new(2.0, 2.0), DVec2::new(10.0, 10.0)),
                Handle::bar(DVec2::new(2.0, 10.0), DVec2::new(10.0, 2.0)),
            ],
            Some(|e| matches!(e, RigError::Coincident { .. })),
        ),
    ];
    for (name, domain, handles, expected_error) in cases {
        for fixed_boundary in [false, true] {
            let options = RigOptions {
                fixed_boundary,
                ..RigOptions::default()
            };
            match (
                Rig::new(domain.clone(), handles.clone(), options),
                expected_error,
            ) {
                (Ok(rig), None) => {
                    check_invariants(&rig).unwrap_or_else(|e| panic!("{name}: {e}"));
                    let _ = rig.deform();
                }
                (Err(e), Some(matches)) => assert!(matches(&e), "{name}: unexpected error {e}"),
                (Ok(_), Some(_)) => panic!("{name}: expected an error"),
                (Err(e), None) => panic!("{name}: unexpected error {e}"),
            }
        }
    }
    let bad_alpha = RigOptions {
        alpha: 1.5,
        ..RigOptions::default()
    };
    assert!(Rig::new(convex.clone(), vec![], bad_alpha).is_err());
}

#[test]
fn bars_are_sampled_and_follow_their_pose() {
    let domain = grid_domain(30, 20, 1.0, 0.0, Shape::Rectangle, 0);
    let handles = vec![
        Handle::bar(DVec2::new(5.0, 10.0), DVec2::new(25.0, 10.0)),
        Handle::point(DVec2::new(15.0, 5.0)),
    ];
    let mut rig = Rig::new(domain, handles, RigOptions::default()).expect("valid");
    let samples = rig
        .nodes()
        .iter()
        .filter(|n| matches!(n.kind, NodeKind::BarSample { .. }))
        .count();
    // d = 5 (point to bar): ⌈20 / 5⌉ = 4 pieces, 5 samples.
    assert_eq!(samples, 5);
    let pose = [DVec2::new(5.0, 12.0), DVec2::new(25.0, 14.0)];
    rig.set_bar_pose(0, pose).expect("bar");
    let moved = rig.deform();
    for n in rig.nodes() {
        if let NodeKind::BarSample { t, .. } = n.kind {
            assert!((moved[n.vertex as usize] - pose[0].lerp(pose[1], t)).length() < 1e-9);
        }
    }
}

/// A bar is cut at its own distance to the nearest other handle: two points close
/// together far from it leave it alone, a point near it cuts it finer.
#[test]
fn a_bar_is_cut_by_the_handles_near_it_only() {
    let bar = Handle::bar(DVec2::new(5.0, 10.0), DVec2::new(25.0, 10.0));
    let mut handles = vec![bar, Handle::point(DVec2::new(15.0, 2.0))];
    assert_eq!(bar_spacing(&handles, 0), 8.0);
    handles.push(Handle::point(DVec2::new(17.0, 1.0)));
    assert_eq!(bar_spacing(&handles, 0), 8.0, "points far from the bar");
    handles.push(Handle::point(DVec2::new(10.0, 13.0)));
    assert_eq!(bar_spacing(&handles, 0), 3.0, "a point 3 from the bar");
    handles.push(Handle::point(DVec2::new(20.0, 10.5)));
    assert_eq!(
        bar_spacing(&handles, 0),
        20.0 / MAX_BAR_PIECES,
        "no finer than 16 pieces"
    );
    assert_eq!(bar_spacing(&handles[..1], 0), 20.0 / 8.0, "alone");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, .. ProptestConfig::default() })]

    /// A handle dropped right beside a virtual handle replaces it instead of making
    /// Algorithm 1 refine the neighbourhood down to one edge (which, on a discrete
    /// mesh, turns nearly every sample into a handle).
    #[test]
    fn inserting_beside_a_virtual_handle_stays_local(seed in any::<u64>(), convex in any::<bool>()) {
        let domain = grid_domain(40, 30, 1.0, 0.3, shape_of(convex), seed);
        let mut rng = Rng(seed);
        let handles = random_handles(&domain, &mut rng, 4, 1);
        let mut rig = Rig::new(domain.clone(), handles, RigOptions::default()).expect("valid");
        let virtuals: Vec<u32> = rig.virtual_vertices();
        prop_assume!(!virtuals.is_empty());
        let v = virtuals[rng.below(virtuals.len())];
        // The sample next to it.
        let p = domain.positions()[v as usize];
        let beside = (0..domain.len())
            .filter(|&u| u != v as usize)
            .min_by(|&a, &b| {
                (domain.positions()[a] - p)
                    .length()
                    .total_cmp(&(domain.positions()[b] - p).length())
            })
            .expect("another sample");
        let before = rig.stats().virtual_nodes;
        // (A point nearer a bar than anything else re-cuts that whole bar, which is not
        // local by design; see `bar_spacing`.)
        let new_point = Handle::point(domain.positions()[beside]);
        let mut with_it = rig.handles().to_vec();
        with_it.push(new_point.clone());
        prop_assume!((0..rig.handles().len()).all(|i| bar_spacing(&with_it, i) == bar_spacing(rig.handles(), i)));
        if rig.insert_handle(new_point).is_ok() {
            let after = rig.stats().virtual_nodes;
            prop_assert!(after < before + domain.len() / 20, "{} virtual handles became {}", before, after);
            if let Err(e) = check_invariants(&rig) {
                prop_assert!(false, "{}", e);
            }
        }
    }
}

#[test]
fn points_between_samples_follow_the_mesh_and_samples_follow_their_weights() {
    let domain = grid_domain(20, 16, 1.0, 0.25, Shape::Holed, 9);
    let mut rng = Rng(9);
    let handles = random_handles(&domain, &mut rng, 3, 1);
    let mut rig = Rig::new(domain.clone(), handles, RigOptions::default()).expect("valid");
    rig.set_point_transform(
        0,
        Similarity {
            translation: DVec2::new(2.0, -1.0),
            rotation: 0.3,
            scale: 1.2,
        },
    )
    .expect("point handle");
    let moved = rig.deform();
    // A sample moves to the weighted blend of its nodes' transforms.
    for v in (0..domain.len()).step_by(7) {
        let p = domain.positions()[v];
        let blend: DVec2 = rig
            .weights(v)
            .map(|(k, w)| w * rig.node_transform(k).transform_point2(p))
            .sum();
        assert!((blend - moved[v]).length() < 1e-9, "sample {v}");
        // At a sample, the point deformation is the sample's own.
        let at = rig.deform_point(&moved, p).expect("inside");
        assert!((at - moved[v]).length() < 1e-9);
    }
    // Between samples: the barycentric blend of the triangle's corners.
    let t = domain.triangles()[5];
    let corners = t.map(|v| domain.positions()[v as usize]);
    let p = (corners[0] + corners[1] + corners[2]) / 3.0;
    let expected = t.iter().map(|&v| moved[v as usize]).sum::<DVec2>() / 3.0;
    let got = rig.deform_point(&moved, p).expect("inside");
    assert!((got - expected).length() < 1e-9);
    // Off the shape there is no answer.
    assert!(rig.deform_point(&moved, DVec2::new(10.0, 8.0)).is_none());
}

#[test]
fn a_fixed_boundary_stays_put() {
    for shape in [Shape::Rectangle, Shape::Holed] {
        let domain = grid_domain(24, 18, 1.0, 0.2, shape, 4);
        let mut rng = Rng(4);
        let handles = random_handles(&domain, &mut rng, 3, 0);
        let options = RigOptions {
            fixed_boundary: true,
            ..RigOptions::default()
        };
        let mut rig = Rig::new(domain.clone(), handles, options).expect("valid");
        let pinned: Vec<u32> = rig
            .nodes()
            .iter()
            .filter(|n| n.kind == NodeKind::Boundary)
            .map(|n| n.vertex)
            .collect();
        assert!(!pinned.is_empty(), "{shape:?}: no border pins");
        for i in 0..3 {
            rig.set_point_transform(i, Similarity::translate(DVec2::new(3.0, 2.0)))
                .expect("point handle");
        }
        let moved = rig.deform();
        for v in pinned {
            assert_eq!(
                moved[v as usize],
                domain.positions()[v as usize],
                "{shape:?}"
            );
        }
        // The handles themselves still move.
        for n in rig
            .nodes()
            .iter()
            .filter(|n| matches!(n.kind, NodeKind::Point { .. }))
        {
            let p = domain.positions()[n.vertex as usize];
            assert!((moved[n.vertex as usize] - p - DVec2::new(3.0, 2.0)).length() < 1e-9);
        }
    }
}

#[test]
fn a_cut_separates_its_two_sides() {
    // A 20 × 20 square with a vertical slit from the top edge down to y = 14 at x = 10:
    // the vertices on the slit are doubled, one copy for each side.
    let n = 20usize;
    let mut positions: Vec<DVec2> = Vec::new();
    for y in 0..=n {
        for x in 0..=n {
            positions.push(DVec2::new(x as f64, y as f64));
        }
    }
    let id = |x: usize, y: usize| (y * (n + 1) + x) as u32;
    let mut twin = std::collections::HashMap::new();
    for y in 0..14 {
        twin.insert(id(10, y), positions.len() as u32);
        positions.push(DVec2::new(10.0, y as f64));
    }
    let mut triangles = Vec::new();
    for y in 0..n {
        for x in 0..n {
            // Cells right of the slit use the twin copies of its vertices.
            let v = |xx: usize, yy: usize| {
                let i = id(xx, yy);
                if x == 10 && xx == 10 {
                    twin.get(&i).copied().unwrap_or(i)
                } else {
                    i
                }
            };
            let (a, b, c, d) = (v(x, y), v(x + 1, y), v(x + 1, y + 1), v(x, y + 1));
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    let domain = Domain::new(positions, triangles, Metric::Intrinsic).expect("valid");
    assert!(!domain.is_convex(), "a slit makes the boundary non-convex");
    let handles = vec![
        Handle::point(DVec2::new(8.0, 2.0)),
        Handle::point(DVec2::new(12.0, 2.0)),
    ];
    let rig = Rig::new(domain.clone(), handles, RigOptions::default()).expect("valid");
    check_invariants(&rig).expect("invariants");
    // The handles are 4 px apart in the plane but must go around the slit's end.
    let d = rig.distances_from_node(0);
    let other = rig.nodes()[1].vertex as usize;
    assert!(
        d[other] > 2.0 * 12.0,
        "distance across the slit {} should go around it",
        d[other]
    );
    // Across the slit the left handle weighs far less than straight-line distance
    // (which ignores the cut) would make it.
    let right = domain
        .positions()
        .iter()
        .position(|p| *p == DVec2::new(11.0, 2.0))
        .expect("sample");
    let weight_of_left = |rig: &Rig| {
        rig.weights(right)
            .find(|&(k, _)| k == 0)
            .map_or(0.0, |(_, w)| w)
    };
    let straight = Domain::new(
        domain.positions().to_vec(),
        domain.triangles().to_vec(),
        Metric::Euclidean,
    )
    .expect("valid");
    let handles = rig.handles().to_vec();
    let euclidean = Rig::new(straight, handles, RigOptions::default()).expect("valid");
    let (through, around) = (weight_of_left(&euclidean), weight_of_left(&rig));
    assert!(through > 0.01, "straight-line weight {through}");
    assert!(
        around < through / 10.0,
        "weight around the slit {around} vs straight {through}"
    );
}

#[test]
fn the_warp_does_not_depend_on_where_the_origin_is() {
    let domain = grid_domain(24, 18, 1.0, 0.25, Shape::Holed, 12);
    let shift = DVec2::new(1000.0, -250.0);
    let moved_domain = Domain::new(
        domain.positions().iter().map(|p| *p + shift).collect(),
        domain.triangles().to_vec(),
        Metric::Intrinsic,
    )
    .expect("valid");
    let mut rng = Rng(12);
    let handles = random_handles(&domain, &mut rng, 3, 1);
    let posed = |h: &Handle, offset: DVec2| match *h {
        Handle::Point { rest, .. } => Handle::Point {
            rest: rest + offset,
            transform: Similarity {
                translation: DVec2::new(1.5, -2.0),
                rotation: 0.4,
                scale: 0.9,
            },
        },
        Handle::Bar { rest, .. } => Handle::Bar {
            rest: rest.map(|p| p + offset),
            pose: [
                rest[0] + offset + DVec2::new(1.0, 1.0),
                rest[1] + offset + DVec2::new(-2.0, 0.5),
            ],
        },
    };
    let a = Rig::new(
        domain,
        handles.iter().map(|h| posed(h, DVec2::ZERO)).collect(),
        RigOptions::default(),
    )
    .expect("valid")
    .deform();
    let b = Rig::new(
        moved_domain,
        handles.iter().map(|h| posed(h, shift)).collect(),
        RigOptions::default(),
    )
    .expect("valid")
    .deform();
    for (p, q) in a.iter().zip(&b) {
        assert!((*p + shift - *q).length() < 1e-6, "{p} + shift != {q}");
    }
}

#[test]
fn removing_every_handle_leaves_no_virtual_handles() {
    let domain = grid_domain(40, 30, 1.0, 0.3, Shape::Holed, 5);
    let handles = vec![
        Handle::point(domain.positions()[find_grid(&domain, 10, 10)]),
        Handle::point(domain.positions()[find_grid(&domain, 12, 10)]),
    ];
    let mut rig = Rig::new(domain.clone(), handles, RigOptions::default()).expect("valid");
    assert!(
        rig.stats().virtual_nodes > 0,
        "close handles need virtual ones"
    );
    rig.set_handles(Vec::new()).expect("no handles");
    assert_eq!(rig.stats().virtual_nodes, 0);
    let fresh = Rig::new(domain, Vec::new(), RigOptions::default()).expect("valid");
    rig.same_weights_as(&fresh).expect("as a fresh empty rig");
}

/// Inserting and removing handles over and over (an artist trying places) does not pile
/// up virtual handles: a removed handle takes along those placed for it, so the count
/// stays near that of a fresh build, and the rig stays exactly a rebuild of its nodes.
#[test]
fn inserting_and_removing_handles_does_not_pile_up_virtual_handles() {
    for (shape, seed) in [(Shape::Holed, 3), (Shape::Rectangle, 4)] {
        let domain = grid_domain(60, 45, 1.0, 0.3, shape, seed);
        let mut rng = Rng(seed);
        let handles = random_handles(&domain, &mut rng, 4, 0);
        let mut rig = Rig::new(domain.clone(), handles, RigOptions::default()).expect("valid");
        let fresh = rig.stats().virtual_nodes;
        let mut most = fresh;
        for _ in 0..60 {
            let p = domain.positions()[rng.below(domain.len())];
            if let Ok(i) = rig.insert_handle(Handle::point(p)) {
                rig.remove_handle(i).expect("exists");
            }
            most = most.max(rig.stats().virtual_nodes);
        }
        assert!(
            most <= fresh + 12,
            "{shape:?}: {fresh} virtual handles grew to {most}"
        );
        check_invariants(&rig).expect("invariants");
        rig.same_weights_as(&rebuild_of(&rig)).expect("a rebuild");
    }
}
