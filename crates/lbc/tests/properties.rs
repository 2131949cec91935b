//! The coordinates' defining properties on convex and strongly concave cages, the
//! solver's convergence, and refusal of bad cages.

use glam::DVec2;
use lbc::{
    Cage, Coordinates, DEFAULT_TOLERANCE, Domain, LbcError, Settings, geodesic_distances, solve,
    solve_with_distances,
};
use proptest::prelude::*;

fn square() -> Cage {
    cage(&[(0.0, 0.0), (3.0, 0.0), (3.0, 2.0), (0.0, 2.0)])
}

fn cage(points: &[(f64, f64)]) -> Cage {
    Cage::new(points.iter().map(|&(x, y)| DVec2::new(x, y)).collect()).expect("valid cage")
}

/// A star with alternating radii (strongly concave), clockwise when `reverse`.
fn star(n: usize, reverse: bool) -> Cage {
    let mut v: Vec<DVec2> = (0..n)
        .map(|i| {
            let a = i as f64 / n as f64 * std::f64::consts::TAU;
            let r = if i % 2 == 0 { 100.0 } else { 45.0 };
            DVec2::new(500.0 + r * a.cos(), -20.0 + r * a.sin())
        })
        .collect();
    if reverse {
        v.reverse();
    }
    Cage::new(v).expect("valid star")
}

/// A U shape: two long arms joined at the bottom.
fn u_shape() -> Cage {
    cage(&[
        (0.0, 0.0),
        (10.0, 0.0),
        (10.0, 10.0),
        (7.0, 10.0),
        (7.0, 3.0),
        (3.0, 3.0),
        (3.0, 10.0),
        (0.0, 10.0),
    ])
}

fn solved(cage: &Cage, target: usize) -> (Domain, Coordinates) {
    let domain = Domain::triangulate(cage, target).expect("triangulates");
    let c = solve(&domain, &Settings::default(), &mut |_| true).expect("solves");
    (domain, c)
}

fn check_properties(cage: &Cage, domain: &Domain, c: &Coordinates) {
    let n = cage.len();
    let (lo, hi) = cage.bounds();
    let size = (hi - lo).length();
    assert!(c.report.converged, "{:?}", c.report);
    for v in 0..domain.positions().len() {
        let row = c.row(v);
        let sum: f64 = row.iter().sum();
        assert!((sum - 1.0).abs() < 1e-9, "partition of unity at {v}: {sum}");
        assert!(row.iter().all(|&w| w >= 0.0), "negative weight at {v}");
        let reproduced: DVec2 = row.iter().zip(cage.vertices()).map(|(w, p)| *w * *p).sum();
        assert!(
            reproduced.distance(domain.positions()[v]) < 1e-9 * size,
            "reproduction at {v}: off by {}",
            reproduced.distance(domain.positions()[v]) / size
        );
    }
    // Lagrange property.
    for (i, &v) in domain.cage_vertices().iter().enumerate() {
        for (j, &w) in c.row(v as usize).iter().enumerate() {
            let want = if i == j { 1.0 } else { 0.0 };
            assert!((w - want).abs() < 1e-9, "w_{j}(c_{i}) = {w}");
        }
    }
    // Linearity on cage edges.
    let mut on_edges = 0;
    for (v, on) in domain.on_cage().iter().enumerate() {
        let Some(at) = on else { continue };
        on_edges += 1;
        let e = at.edge as usize;
        for (j, &w) in c.row(v).iter().enumerate() {
            let want = if j == e {
                1.0 - at.t
            } else if j == (e + 1) % n {
                at.t
            } else {
                0.0
            };
            assert!((w - want).abs() < 1e-9, "edge value at {v}");
        }
    }
    assert!(on_edges > n, "cage edges are split into chains");
    // Linear precision: an affine map of the cage is reproduced inside.
    let map = |p: DVec2| DVec2::new(1.3 * p.x - 0.4 * p.y + 7.0, 0.2 * p.x + 0.9 * p.y - 3.0);
    let pose: Vec<DVec2> = cage.vertices().iter().map(|&p| map(p)).collect();
    let moved = c.deform(&pose).expect("pose fits");
    for (p, q) in domain.positions().iter().zip(&moved) {
        assert!(map(*p).distance(*q) < 1e-6 * size, "linear precision");
    }
}

#[test]
fn properties_on_a_convex_cage() {
    let cage = square();
    let (domain, c) = solved(&cage, 300);
    check_properties(&cage, &domain, &c);
}

#[test]
fn properties_on_concave_cages_either_orientation() {
    for reverse in [false, true] {
        let cage = star(10, reverse);
        let (domain, c) = solved(&cage, 400);
        check_properties(&cage, &domain, &c);
    }
    let cage = u_shape();
    let (domain, c) = solved(&cage, 400);
    check_properties(&cage, &domain, &c);
}

#[test]
fn a_triangle_gives_barycentric_coordinates() {
    let cage = cage(&[(0.0, 0.0), (4.0, 0.0), (1.0, 3.0)]);
    let (domain, c) = solved(&cage, 60);
    check_properties(&cage, &domain, &c);
}

/// On the U, the vertex at the top of the left arm has no weight over the right arm
/// (mean value coordinates are positive there: they reach across the gap).
#[test]
fn locality_on_a_concave_cage() {
    let cage = u_shape();
    let (domain, c) = solved(&cage, 600);
    let i = 7; // (0, 10), top of the left arm.
    let mut zero_area = 0.0;
    let mut total = 0.0;
    let mut right_arm_nonzero = 0;
    for t in domain.triangles() {
        let p = t.map(|v| domain.positions()[v as usize]);
        let area = 0.5 * (p[1] - p[0]).perp_dot(p[2] - p[0]);
        total += area;
        if t.iter().all(|&v| c.row(v as usize)[i] == 0.0) {
            zero_area += area;
        }
    }
    for (v, p) in domain.positions().iter().enumerate() {
        if p.x > 7.0 && p.y > 3.0 && domain.on_cage()[v].is_none() {
            let w = c.row(v)[i];
            assert!(mean_value(&cage, *p)[i] > 1e-6, "MVC is global at {p}");
            if w != 0.0 {
                right_arm_nonzero += 1;
            }
        }
    }
    assert_eq!(right_arm_nonzero, 0, "the far arm ignores the vertex");
    assert!(
        zero_area > 0.5 * total,
        "exactly zero on {:.0}% of the area",
        100.0 * zero_area / total
    );
    // `P(0)` is the mean share of the area where a coordinate is exactly zero (on a
    // triangle with a corner above zero, the zeros have no area), and `P(1)` is 1.
    let n = cage.len();
    let mut zero = 0.0;
    for t in domain.triangles() {
        let p = t.map(|v| domain.positions()[v as usize]);
        let area = 0.5 * (p[1] - p[0]).perp_dot(p[2] - p[0]);
        zero += area
            * (0..n)
                .filter(|&i| t.iter().all(|&v| c.row(v as usize)[i] == 0.0))
                .count() as f64;
    }
    let stats = lbc::locality(&domain, &c, &[0.0, 1.0]);
    let expected = zero / (total * n as f64);
    assert!(
        (stats.p[0] - expected).abs() < 1e-12,
        "P(0) = {}, not {expected}",
        stats.p[0]
    );
    assert!((stats.p[1] - 1.0).abs() < 1e-12, "P(1) = {}", stats.p[1]);
}

/// Mean value coordinates (Hormann and Floater 2006) at an interior point.
fn mean_value(cage: &Cage, x: DVec2) -> Vec<f64> {
    let c = cage.vertices();
    let n = c.len();
    let s: Vec<DVec2> = c.iter().map(|p| *p - x).collect();
    let r: Vec<f64> = s.iter().map(|v| v.length()).collect();
    let tan_half = |i: usize| {
        let j = (i + 1) % n;
        let a = s[i].perp_dot(s[j]);
        let d = s[i].dot(s[j]);
        a / (r[i] * r[j] + d)
    };
    let mut w: Vec<f64> = (0..n)
        .map(|i| (tan_half((i + n - 1) % n) + tan_half(i)) / r[i])
        .collect();
    let sum: f64 = w.iter().sum();
    w.iter_mut().for_each(|x| *x /= sum);
    w
}

#[test]
fn converged_objective_is_stable() {
    let cage = star(12, false);
    let domain = Domain::triangulate(&cage, 700).expect("triangulates");
    let d = geodesic_distances(&domain).expect("geodesics");
    let run = |tolerance: f64| {
        let settings = Settings {
            tolerance,
            ..Settings::default()
        };
        solve_with_distances(&domain, &d, &settings, &mut |_| true).expect("solves")
    };
    let normal = run(DEFAULT_TOLERANCE);
    let tight = run(DEFAULT_TOLERANCE / 10.0);
    for c in [&normal, &tight] {
        let last = c.report.last.expect("iterated");
        assert!(c.report.converged);
        assert!(last.primal_residual <= last.primal_threshold);
        assert!(last.dual_residual <= last.dual_threshold);
    }
    let (a, b) = (normal.report.objective, tight.report.objective);
    assert!(
        (a - b).abs() <= 0.005 * b,
        "objective {a} vs {b} with a 10× tighter threshold"
    );
}

/// The iterations run on all of rayon's threads or on one, whichever the first few
/// find faster: either way the iterates are the same, and every sum (the residuals',
/// the objective's) is added in one order, so a solve on one thread and solves on
/// two give the same coordinates and report to the bit, run after run.
#[test]
fn one_thread_or_two_solve_alike() {
    let domain = Domain::triangulate(&star(10, false), 1500).expect("triangulates");
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a pool");
        pool.install(|| solve(&domain, &Settings::default(), &mut |_| true).expect("solves"))
    };
    let one = run(1);
    assert_eq!(one.report.threads, 1);
    assert!(
        one.report.iterations > 15,
        "the solve outlasts the trials ({} iterations)",
        one.report.iterations
    );
    for _ in 0..3 {
        let two = run(2);
        assert_eq!(one.report.iterations, two.report.iterations);
        assert_eq!(
            one.report.objective.to_bits(),
            two.report.objective.to_bits()
        );
        assert_eq!(one.report.last, two.report.last, "the last residuals");
        for v in 0..one.vertices() {
            assert_eq!(one.row(v), two.row(v), "vertex {v}");
        }
    }
}

/// `a` and `b` took the same iterations to the same coordinates (to 10⁻¹²).
fn assert_solved_alike(a: &Coordinates, b: &Coordinates) {
    assert_eq!(a.report.iterations, b.report.iterations);
    assert!((a.report.objective - b.report.objective).abs() < 1e-12);
    for v in 0..a.vertices() {
        for (x, y) in a.row(v).iter().zip(b.row(v)) {
            assert!((x - y).abs() < 1e-12, "vertex {v}: {x} vs {y}");
        }
    }
}

/// The iterations' passes compiled for AVX2 (where the CPU has it) and for the
/// baseline give the same coordinates: no operation is fused or reordered.
#[test]
fn wide_vectors_or_not_solve_alike() {
    let domain = Domain::triangulate(&star(10, false), 1500).expect("triangulates");
    let run = |wide_vectors: bool| {
        let settings = Settings {
            wide_vectors,
            ..Settings::default()
        };
        solve(&domain, &settings, &mut |_| true).expect("solves")
    };
    assert_solved_alike(&run(false), &run(true));
}

#[test]
fn progress_can_cancel() {
    let domain = Domain::triangulate(&star(8, false), 200).expect("triangulates");
    let mut seen = 0;
    let result = solve(&domain, &Settings::default(), &mut |p| {
        seen = p.iteration;
        p.iteration < 5
    });
    assert_eq!(result.err(), Some(LbcError::Cancelled));
    assert_eq!(seen, 5);
}

#[test]
fn compact_rows_drop_small_weights_and_still_reproduce_exactly() {
    for (cage, target) in [
        (star(10, false), 400),
        (u_shape(), 600),
        (star(16, true), 900),
    ] {
        let (domain, c) = solved(&cage, target);
        let compact = c.compact();
        let n = cage.len();
        let (lo, hi) = cage.bounds();
        let size = (hi - lo).length();
        let dense = (0..domain.positions().len())
            .map(|v| c.row(v).iter().filter(|w| **w > 0.0).count())
            .sum::<usize>();
        assert!(compact.len() < dense, "{} of {dense} kept", compact.len());
        let threshold = 1e-3 / n as f64;
        let mut small = 0;
        for v in 0..compact.vertices() {
            let row = compact.row(v);
            let sum: f64 = row.iter().map(|e| e.1).sum();
            assert!((sum - 1.0).abs() < 1e-12, "row {v} sums to {sum}");
            assert!(row.iter().all(|e| e.1 >= 0.0));
            // Only weights the solve had are kept.
            assert!(row.iter().all(|&(i, _)| c.row(v)[i as usize] > 0.0));
            small += row.iter().filter(|e| e.1 < threshold).count();
        }
        // The correction keeps the dropped weights out (a handful of rows where it
        // cannot keep every weight as solved).
        assert!(small * 50 < compact.len(), "{small} small weights kept");
        // Rest is the identity, and affine motions of the cage are reproduced, to
        // rounding (dropping alone moved vertices by up to 10⁻³ of the cage's size).
        let affine =
            |p: DVec2| DVec2::new(1.3 * p.x - 0.4 * p.y + 17.0, 0.2 * p.x + 0.9 * p.y - 3.0);
        let rotate = |p: DVec2| glam::DMat2::from_angle(0.52) * (p - lo) + DVec2::new(40.0, -7.0);
        for (name, motion) in [
            ("rest", &(|p: DVec2| p) as &dyn Fn(DVec2) -> DVec2),
            ("affine", &affine),
            ("rotation", &rotate),
        ] {
            let pose: Vec<DVec2> = cage.vertices().iter().map(|&p| motion(p)).collect();
            let moved = compact.deform(&pose).expect("pose fits");
            let worst = domain
                .positions()
                .iter()
                .zip(&moved)
                .map(|(p, q)| motion(*p).distance(*q))
                .fold(0.0, f64::max);
            assert!(worst < 1e-9 * size, "{name}: off by {worst}");
        }
        let pose = cage.vertices().to_vec();
        assert!(matches!(
            compact.deform(&pose[1..]),
            Err(LbcError::BadPose { .. })
        ));
    }
}

#[test]
fn a_mesh_that_reaches_beyond_the_cage_is_refused() {
    // A grid over [−1, 4] × [0, 2]: a column of vertices on each side of the square.
    let mut positions = Vec::new();
    for y in 0..3 {
        for x in -1..5 {
            positions.push(DVec2::new(x as f64, y as f64));
        }
    }
    let mut triangles = Vec::new();
    for y in 0..2u32 {
        for x in 0..5u32 {
            let a = y * 6 + x;
            triangles.push([a, a + 1, a + 7]);
            triangles.push([a, a + 7, a + 6]);
        }
    }
    let err = Domain::from_mesh(&square(), positions, triangles).expect_err("outside");
    assert!(
        matches!(err, LbcError::OutsideCage { vertex: 0, .. }),
        "{err}"
    );
    assert!(err.to_string().contains("outside the cage"), "{err}");
    // A triangle across the notch of a U whose corners all lie on the cage.
    let u = u_shape();
    let positions = vec![
        DVec2::new(3.0, 3.0),
        DVec2::new(7.0, 3.0),
        DVec2::new(7.0, 10.0),
        DVec2::new(3.0, 10.0),
    ];
    let err = Domain::from_mesh(&u, positions, vec![[0, 1, 2], [0, 2, 3]]).expect_err("notch");
    assert!(matches!(err, LbcError::OutsideCage { .. }), "{err}");
}

#[test]
fn a_given_mesh_is_used_as_is() {
    // A 3 × 2 grid of unit squares over [0, 3] × [0, 2], vertices shuffled.
    let mut positions = Vec::new();
    for y in 0..3 {
        for x in 0..4 {
            positions.push(DVec2::new(x as f64, y as f64));
        }
    }
    let mut triangles = Vec::new();
    for y in 0..2u32 {
        for x in 0..3u32 {
            let a = y * 4 + x;
            triangles.push([a, a + 1, a + 5]);
            triangles.push([a, a + 5, a + 4]);
        }
    }
    let perm: Vec<u32> = (0..12u32).map(|v| (v * 5) % 12).collect();
    let mut shuffled = vec![DVec2::ZERO; 12];
    for (old, &new) in perm.iter().enumerate() {
        shuffled[new as usize] = positions[old];
    }
    let triangles: Vec<[u32; 3]> = triangles
        .iter()
        .map(|t| t.map(|v| perm[v as usize]))
        .collect();
    let cage = square();
    let domain = Domain::from_mesh(&cage, shuffled, triangles).expect("valid mesh");
    assert_eq!(
        domain.cage_vertices(),
        &[perm[0], perm[3], perm[11], perm[8]]
    );
    let c = solve(&domain, &Settings::default(), &mut |_| true).expect("solves");
    check_properties_small(&cage, &domain, &c);
    let missing = Domain::from_mesh(
        &cage,
        vec![DVec2::ZERO, DVec2::X, DVec2::Y],
        vec![[0, 1, 2]],
    );
    assert!(matches!(
        missing,
        Err(LbcError::CageVertexNotInMesh { vertex: 1 })
    ));
}

/// A given mesh is solved renumbered for locality and its rows returned in its own
/// numbering: the crate's own mesh of a star, given back with its vertices shuffled
/// and each triangle's corners rotated, solves to the same coordinates, vertex for
/// vertex (to rounding: the sums run in another order).
#[test]
fn a_given_mesh_solves_alike_in_any_numbering() {
    let cage = star(14, false);
    let (domain, ours) = solved(&cage, 1500);
    let nv = domain.positions().len();
    // new = (old · 7919 + 13) mod nv, a permutation when nv is not a multiple of 7919.
    let perm: Vec<u32> = (0..nv).map(|v| ((v * 7919 + 13) % nv) as u32).collect();
    let mut positions = vec![DVec2::ZERO; nv];
    for (old, &new) in perm.iter().enumerate() {
        positions[new as usize] = domain.positions()[old];
    }
    let triangles: Vec<[u32; 3]> = domain
        .triangles()
        .iter()
        .enumerate()
        .map(|(s, t)| {
            let t = t.map(|v| perm[v as usize]);
            [t[s % 3], t[(s + 1) % 3], t[(s + 2) % 3]]
        })
        .collect();
    let given = Domain::from_mesh(&cage, positions, triangles).expect("valid mesh");
    let theirs = solve(&given, &Settings::default(), &mut |_| true).expect("solves");
    check_properties(&cage, &given, &theirs);
    assert_eq!(theirs.report.iterations, ours.report.iterations);
    let objective = ours.report.objective;
    assert!((theirs.report.objective - objective).abs() <= 1e-9 * objective);
    for (old, &new) in perm.iter().enumerate() {
        for (a, b) in ours.row(old).iter().zip(theirs.row(new as usize)) {
            assert!((a - b).abs() < 1e-6, "vertex {old}: {a} against {b}");
        }
    }
}

fn check_properties_small(cage: &Cage, domain: &Domain, c: &Coordinates) {
    for v in 0..domain.positions().len() {
        let row = c.row(v);
        assert!((row.iter().sum::<f64>() - 1.0).abs() < 1e-9);
        assert!(row.iter().all(|&w| w >= 0.0));
        let p: DVec2 = row.iter().zip(cage.vertices()).map(|(w, p)| *w * *p).sum();
        assert!(p.distance(domain.positions()[v]) < 1e-9);
    }
}

#[test]
fn bad_cages_are_refused() {
    let v = |pts: &[(f64, f64)]| pts.iter().map(|&(x, y)| DVec2::new(x, y)).collect();
    assert_eq!(
        Cage::new(v(&[(0.0, 0.0), (1.0, 0.0)])),
        Err(LbcError::TooFewVertices { vertices: 2 })
    );
    assert_eq!(
        Cage::new(v(&[(0.0, 0.0), (1.0, f64::NAN), (0.0, 1.0)])),
        Err(LbcError::NonFinite { vertex: 1 })
    );
    assert_eq!(
        Cage::new(v(&[(0.0, 0.0), (1.0, 0.0), (2.0, 0.0)])),
        Err(LbcError::ZeroArea)
    );
    assert_eq!(
        Cage::new(v(&[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (1.0, 0.0)])),
        Err(LbcError::RepeatedVertex {
            first: 1,
            second: 3
        })
    );
    // A bow tie.
    assert!(matches!(
        Cage::new(v(&[(0.0, 0.0), (1.0, 1.0), (1.0, 0.0), (0.0, 1.0)])),
        Err(LbcError::SelfIntersection { .. })
    ));
    // A vertex touching a non-adjacent edge.
    assert!(matches!(
        Cage::new(v(&[
            (0.0, 0.0),
            (4.0, 0.0),
            (4.0, 4.0),
            (2.0, 0.0),
            (0.0, 4.0)
        ])),
        Err(LbcError::SelfIntersection { .. })
    ));
    // An edge folding back on its neighbour.
    assert!(matches!(
        Cage::new(v(&[(0.0, 0.0), (4.0, 0.0), (2.0, 0.0), (2.0, 3.0)])),
        Err(LbcError::SelfIntersection { .. })
    ));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(std::env::var("LBC_CASES").ok().and_then(|c| c.parse().ok()).unwrap_or(8)))]

    /// Random star-shaped cages (simple by construction): the hard constraints hold.
    #[test]
    fn random_star_shaped_cages(
        radii in proptest::collection::vec(0.3f64..1.0, 5..9),
        rotation in 0.0f64..6.0,
    ) {
        let n = radii.len();
        let cage = Cage::new(
            radii
                .iter()
                .enumerate()
                .map(|(i, r)| {
                    let a = rotation + i as f64 / n as f64 * std::f64::consts::TAU;
                    DVec2::new(10.0 * r * a.cos(), 10.0 * r * a.sin())
                })
                .collect(),
        ).expect("star-shaped polygons are simple");
        let (domain, c) = solved(&cage, 150);
        check_properties(&cage, &domain, &c);
    }
}

/// On a triangle the coordinates are the barycentric ones, linear: `P(t)` is
/// `1 − (1 − t)²` exactly, and every point but the corners has at least two
/// non-negligible coordinates.
#[test]
fn locality_statistics_of_a_triangle() {
    let cage = lbc::Cage::new(vec![
        glam::DVec2::new(0.0, 0.0),
        glam::DVec2::new(4.0, 0.0),
        glam::DVec2::new(1.0, 3.0),
    ])
    .expect("a triangle");
    let domain = lbc::Domain::triangulate(&cage, 200).expect("meshed");
    let coordinates =
        lbc::solve(&domain, &lbc::Settings::default(), &mut |_| true).expect("solved");
    let t = [0.0, 0.1, 0.5, 0.9, 1.0];
    let stats = lbc::locality(&domain, &coordinates, &t);
    for (&tk, &pk) in t.iter().zip(&stats.p) {
        let expected = 1.0 - (1.0 - tk) * (1.0 - tk);
        assert!(
            (pk - expected).abs() < 1e-6,
            "P({tk}) = {pk}, not {expected}"
        );
    }
    assert_eq!(stats.q.len(), 4);
    assert!((stats.q[0] - 1.0).abs() < 1e-12);
    assert!((stats.q[1] - 1.0).abs() < 1e-12);
    assert!(stats.q[2] > 0.9, "{:?}", stats.q);
    assert!(stats.q.windows(2).all(|w| w[0] >= w[1]), "{:?}", stats.q);
}

/// A cage's inside in two pieces (cut through, its vertices along the cut doubled):
/// from a cage vertex, the piece it does not lie in is at distance 1, the farthest,
/// and the distances in its own piece are as without the other.
#[test]
fn a_piece_out_of_reach_is_the_farthest() {
    let cage = Cage::new(vec![
        DVec2::new(0.0, 0.0),
        DVec2::new(1.0, 0.0),
        DVec2::new(2.0, 0.0),
        DVec2::new(2.0, 1.0),
        DVec2::new(1.0, 1.0),
        DVec2::new(0.0, 1.0),
    ])
    .expect("a cage");
    let positions = vec![
        // The left square and its centre.
        DVec2::new(0.0, 0.0),
        DVec2::new(1.0, 0.0),
        DVec2::new(1.0, 1.0),
        DVec2::new(0.0, 1.0),
        DVec2::new(0.5, 0.5),
        // The right square, its own copies of the cut's ends, and its centre.
        DVec2::new(1.0, 0.0),
        DVec2::new(2.0, 0.0),
        DVec2::new(2.0, 1.0),
        DVec2::new(1.0, 1.0),
        DVec2::new(1.5, 0.5),
    ];
    let triangles = vec![
        [0, 1, 4],
        [1, 2, 4],
        [2, 3, 4],
        [3, 0, 4],
        [5, 6, 9],
        [6, 7, 9],
        [7, 8, 9],
        [8, 5, 9],
    ];
    let domain = Domain::from_mesh(&cage, positions, triangles).expect("a mesh in two pieces");
    let d = geodesic_distances(&domain).expect("geodesics");
    // Cage vertex 2 is (2, 0), in the right piece; cage vertex 0, (0, 0), in the left.
    for v in [0, 3, 4] {
        assert_eq!(d[2][v], 1.0, "vertex {v} is out of reach of (2, 0)");
        assert!(d[0][v] < 1.0 || v == 0 && d[0][v] == 0.0);
    }
    for v in [6, 7, 9] {
        assert_eq!(d[0][v], 1.0, "vertex {v} is out of reach of (0, 0)");
        assert!(d[2][v] < 1.0, "vertex {v}: {}", d[2][v]);
    }
    assert!(
        d.iter()
            .flatten()
            .all(|x| x.is_finite() && (0.0..=1.0).contains(x))
    );
}
