//! Invariants over seeded random meshes (grids, jittered grids, an L, a holed
//! square) and random constraint sets: rigid motions and similarities are reproduced
//! exactly, constraints are met exactly, mirror symmetry is kept, and nothing is ever
//! NaN.

use crate::support;

use arap::{Deformation, Registration};
use glam::DVec2;
use proptest::prelude::*;
use support::{
    Diagonals, MeshData, Rng, all_finite, grid, holed, l_shape, max_distance, similarity,
};

/// A mesh from a kind, a size and a seed.
fn mesh(kind: u8, size: usize, seed: u64) -> MeshData {
    let jitter = 0.35 * ((seed % 4) as f64 / 3.0);
    match kind {
        0 => grid(size + 1, size / 2 + 1, 1.0, jitter, Diagonals::Same, seed),
        1 => grid(
            size + 1,
            size + 1,
            1.0,
            jitter,
            Diagonals::Alternating,
            seed,
        ),
        2 => l_shape(size / 2 + 1, jitter, seed),
        _ => holed(size + 4, size + 4, 2.0, jitter, seed),
    }
}

/// `count` distinct vertices, chosen by `seed`.
fn some_vertices(mesh: &MeshData, count: usize, seed: u64) -> Vec<u32> {
    let mut rng = Rng(seed);
    let count = count.min(mesh.rest.len());
    let mut out = Vec::new();
    while out.len() < count {
        let v = rng.below(mesh.rest.len()) as u32;
        if !out.contains(&v) {
            out.push(v);
        }
    }
    out
}

fn pose(mesh: &MeshData, constrained: &[u32], targets: &[DVec2]) -> Deformation {
    Registration::new(&mesh.rest, &mesh.triangles)
        .and_then(|r| r.compile(constrained, None))
        .and_then(|c| c.update(targets))
        .expect("a valid mesh, constraints and targets")
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// A rotation and translation of every constraint moves every vertex by exactly
    /// that motion, in step one and in the final result.
    #[test]
    fn rigid_motion_is_reproduced_exactly(
        kind in 0u8..4,
        size in 2usize..7,
        seed in any::<u64>(),
        handles in 2usize..7,
        angle in -std::f64::consts::PI..std::f64::consts::PI,
        tx in -50.0..50.0f64,
        ty in -50.0..50.0f64,
    ) {
        let mesh = mesh(kind, size, seed);
        let constrained = some_vertices(&mesh, handles, seed ^ 1);
        let motion = similarity(angle, 1.0, DVec2::new(tx, ty));
        let targets: Vec<DVec2> = constrained.iter().map(|&v| motion(mesh.rest[v as usize])).collect();
        let out = pose(&mesh, &constrained, &targets);
        let expect: Vec<DVec2> = mesh.rest.iter().map(|&p| motion(p)).collect();
        prop_assert!(max_distance(&out.step_one, &expect) < 1e-9);
        prop_assert!(max_distance(&out.positions, &expect) < 1e-9);
    }

    /// Step one alone reproduces a uniform similarity (rotation, uniform scale,
    /// translation) of the constraints exactly.
    #[test]
    fn step_one_reproduces_a_similarity(
        kind in 0u8..4,
        size in 2usize..7,
        seed in any::<u64>(),
        handles in 2usize..7,
        angle in -std::f64::consts::PI..std::f64::consts::PI,
        scale in 0.2..4.0f64,
        tx in -50.0..50.0f64,
        ty in -50.0..50.0f64,
    ) {
        let mesh = mesh(kind, size, seed);
        let constrained = some_vertices(&mesh, handles, seed ^ 2);
        let motion = similarity(angle, scale, DVec2::new(tx, ty));
        let targets: Vec<DVec2> = constrained.iter().map(|&v| motion(mesh.rest[v as usize])).collect();
        let out = pose(&mesh, &constrained, &targets);
        let expect: Vec<DVec2> = mesh.rest.iter().map(|&p| motion(p)).collect();
        prop_assert!(max_distance(&out.step_one, &expect) < 1e-9);
        prop_assert!(all_finite(&out.positions));
    }

    /// Constrained vertices sit exactly on their targets, and no position is NaN,
    /// whatever the targets (also far apart, folded over, or from one handle).
    #[test]
    fn constraints_are_met_exactly_and_nothing_is_nan(
        kind in 0u8..4,
        size in 2usize..7,
        seed in any::<u64>(),
        handles in 1usize..9,
        spread in prop_oneof![Just(0.0), Just(1.0), Just(100.0), Just(1e6)],
    ) {
        let mesh = mesh(kind, size, seed);
        let constrained = some_vertices(&mesh, handles, seed ^ 3);
        let mut rng = Rng(seed ^ 4);
        let targets: Vec<DVec2> = constrained
            .iter()
            .map(|&v| mesh.rest[v as usize] + spread * DVec2::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)))
            .collect();
        let out = pose(&mesh, &constrained, &targets);
        for (&v, &t) in constrained.iter().zip(&targets) {
            prop_assert_eq!(out.step_one[v as usize], t);
            prop_assert_eq!(out.positions[v as usize], t);
        }
        prop_assert!(all_finite(&out.step_one));
        prop_assert!(all_finite(&out.positions));
    }

    /// A mesh and constraints symmetric about a vertical line give a result
    /// symmetric about the mirrored line.
    #[test]
    fn mirror_symmetric_input_gives_a_mirror_symmetric_result(
        half in 2usize..5,
        ny in 2usize..5,
        seed in any::<u64>(),
        pairs in 1usize..4,
    ) {
        let nx = 2 * half;
        let mesh = grid(nx, ny, 1.0, 0.0, Diagonals::Mirrored, 0);
        let mirror_vertex = |v: u32| {
            let (i, j) = (v as usize % (nx + 1), v as usize / (nx + 1));
            (j * (nx + 1) + (nx - i)) as u32
        };
        let mirror = |p: DVec2| DVec2::new(nx as f64 - p.x, p.y);
        let mut rng = Rng(seed);
        let mut constrained = Vec::new();
        let mut targets = Vec::new();
        // Pairs off the axis, and one vertex on the axis kept on it.
        while constrained.len() < 2 * pairs {
            let i = rng.below(half);
            let j = rng.below(ny + 1);
            let v = (j * (nx + 1) + i) as u32;
            if constrained.contains(&v) {
                continue;
            }
            let t = mesh.rest[v as usize] + DVec2::new(rng.range(-2.0, 2.0), rng.range(-2.0, 2.0));
            constrained.extend([v, mirror_vertex(v)]);
            targets.extend([t, mirror(t)]);
        }
        let axis = (rng.below(ny + 1) * (nx + 1) + half) as u32;
        constrained.push(axis);
        targets.push(mesh.rest[axis as usize] + DVec2::new(0.0, rng.range(-2.0, 2.0)));
        let out = pose(&mesh, &constrained, &targets);
        for v in 0..mesh.rest.len() as u32 {
            let m = mirror_vertex(v) as usize;
            let v = v as usize;
            prop_assert!((out.step_one[m] - mirror(out.step_one[v])).length() < 1e-9);
            prop_assert!((out.positions[m] - mirror(out.positions[v])).length() < 1e-9);
        }
    }
}

/// Far from the origin, rigid motions still come out exact to the precision the
/// coordinates carry.
#[test]
fn rigid_motion_far_from_the_origin() {
    let mut mesh = grid(6, 4, 3.0, 0.3, Diagonals::Alternating, 9);
    for p in &mut mesh.rest {
        *p += DVec2::new(1e6, -2e6);
    }
    let constrained = [0u32, 20, 34];
    let motion = similarity(2.0, 1.0, DVec2::new(-5e5, 3e5));
    let targets: Vec<DVec2> = constrained
        .iter()
        .map(|&v| motion(mesh.rest[v as usize]))
        .collect();
    let out = pose(&mesh, &constrained, &targets);
    let expect: Vec<DVec2> = mesh.rest.iter().map(|&p| motion(p)).collect();
    assert!(max_distance(&out.step_one, &expect) < 1e-9 * 3e6);
    assert!(max_distance(&out.positions, &expect) < 1e-9 * 3e6);
}

/// `update_into` reuses its buffers and gives what `update` gives.
#[test]
fn update_into_equals_update() {
    let mesh = holed(8, 8, 3.0, 0.3, 5);
    let registration = Registration::new(&mesh.rest, &mesh.triangles).expect("valid");
    let constrained = some_vertices(&mesh, 4, 8);
    let compiled = registration.compile(&constrained, None).expect("compiles");
    let mut out = Deformation::default();
    for k in 0..4 {
        let targets: Vec<DVec2> = constrained
            .iter()
            .map(|&v| {
                mesh.rest[v as usize] + DVec2::new(k as f64, -0.5 * k as f64 * (v % 3) as f64)
            })
            .collect();
        compiled.update_into(&targets, &mut out).expect("updates");
        let fresh = compiled.update(&targets).expect("updates");
        assert_eq!(out.step_one, fresh.step_one);
        assert_eq!(out.positions, fresh.positions);
    }
}
