//! The compiled solver against a from-scratch dense minimisation of the paper's
//! energies (tests/support/dense.rs), pose after pose.

use crate::support;

use arap::Registration;
use glam::DVec2;
use support::{Diagonals, MeshData, Rng, dense, grid, holed, l_shape, max_distance};

/// Random constraint vertices (distinct) and poses: the rest positions moved by a
/// smooth bend plus noise.
fn check_against_dense(mesh: &MeshData, weights: Option<&[f64]>, handles: usize, seed: u64) {
    let registration = Registration::new(&mesh.rest, &mesh.triangles).expect("valid mesh");
    let mut rng = Rng(seed);
    let mut constrained: Vec<u32> = Vec::new();
    while constrained.len() < handles {
        let v = rng.below(mesh.rest.len()) as u32;
        if !constrained.contains(&v) {
            constrained.push(v);
        }
    }
    let compiled = registration
        .compile(&constrained, weights)
        .expect("compiles");
    assert!(compiled.loose_triangles().is_empty());
    let ones = vec![1.0; mesh.triangles.len()];
    let w = weights.unwrap_or(&ones);
    for pose in 0..3 {
        let targets: Vec<DVec2> = constrained
            .iter()
            .map(|&v| {
                let p = mesh.rest[v as usize];
                let bend = DVec2::new(0.3 * p.y * pose as f64, -0.2 * p.x * pose as f64);
                p + bend + DVec2::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0))
            })
            .collect();
        let got = compiled.update(&targets).expect("updates");
        let (one, two) = dense::two_steps(mesh, w, &constrained, &targets);
        let scale = 1.0 + max_distance(&one, &mesh.rest);
        let e1 = max_distance(&got.step_one, &one);
        let e2 = max_distance(&got.positions, &two);
        assert!(e1 < 1e-8 * scale, "step one differs by {e1} (pose {pose})");
        assert!(e2 < 1e-8 * scale, "final differs by {e2} (pose {pose})");
    }
}

#[test]
fn grid_matches_dense_minimisation() {
    let mesh = grid(6, 4, 1.0, 0.25, Diagonals::Alternating, 1);
    check_against_dense(&mesh, None, 3, 10);
    check_against_dense(&mesh, None, 2, 11);
}

#[test]
fn l_shape_matches_dense_minimisation() {
    check_against_dense(&l_shape(3, 0.3, 2), None, 4, 20);
}

#[test]
fn holed_mesh_matches_dense_minimisation() {
    check_against_dense(&holed(7, 7, 3.0, 0.2, 3), None, 3, 30);
}

#[test]
fn rigidity_weights_match_dense_minimisation() {
    let mesh = grid(6, 5, 1.0, 0.2, Diagonals::Same, 4);
    let mut rng = Rng(5);
    let weights: Vec<f64> = (0..mesh.triangles.len())
        .map(|_| {
            if rng.unit() < 0.3 {
                10000.0
            } else {
                rng.range(0.5, 2.0)
            }
        })
        .collect();
    check_against_dense(&mesh, Some(&weights), 3, 40);
}

/// Triangles given in either winding give the same result.
#[test]
fn winding_does_not_matter() {
    let mesh = grid(5, 4, 1.0, 0.3, Diagonals::Alternating, 6);
    let mut flipped = mesh.clone();
    for t in flipped.triangles.iter_mut().step_by(3) {
        t.swap(1, 2);
    }
    let constrained = [0u32, 29, 17];
    let targets = [
        DVec2::new(0.5, -0.5),
        DVec2::new(6.0, 5.0),
        DVec2::new(2.0, 3.5),
    ];
    let a = Registration::new(&mesh.rest, &mesh.triangles)
        .and_then(|r| r.compile(&constrained, None))
        .and_then(|c| c.update(&targets))
        .expect("poses");
    let b = Registration::new(&flipped.rest, &flipped.triangles)
        .and_then(|r| r.compile(&constrained, None))
        .and_then(|c| c.update(&targets))
        .expect("poses");
    assert!(max_distance(&a.step_one, &b.step_one) < 1e-9);
    assert!(max_distance(&a.positions, &b.positions) < 1e-9);
}
