//! Local/global refinement (Sorkine and Alexa 2007) of the two-step result: it never
//! raises the ARAP energy, and it reaches the minimum a plain reference finds — local
//! and global steps written from their definitions, the global one by the dense
//! solver of `support::dense`.

mod support;

use arap::Registration;
use glam::DVec2;
use support::dense::{fitted_rotation, minimise, step_two_energy};
use support::{Diagonals, MeshData, grid};

/// The ARAP energy of `v`: every triangle's edges against its rest edges turned by
/// the rotation fitted to it.
fn energy(mesh: &MeshData, v: &[DVec2]) -> f64 {
    let rotations: Vec<DVec2> = mesh
        .triangles
        .iter()
        .map(|t| fitted_rotation(t.map(|i| mesh.rest[i as usize]), t.map(|i| v[i as usize])))
        .collect();
    step_two_energy(mesh, &vec![1.0; mesh.triangles.len()], &rotations, v)
}

/// Plain local/global iterations from `start`.
fn reference(
    mesh: &MeshData,
    constrained: &[u32],
    targets: &[DVec2],
    start: &[DVec2],
) -> Vec<DVec2> {
    let ones = vec![1.0; mesh.triangles.len()];
    let mut v = start.to_vec();
    for _ in 0..60 {
        let rotations: Vec<DVec2> = mesh
            .triangles
            .iter()
            .map(|t| fitted_rotation(t.map(|i| mesh.rest[i as usize]), t.map(|i| v[i as usize])))
            .collect();
        v = minimise(mesh.rest.len(), constrained, targets, |p| {
            step_two_energy(mesh, &ones, &rotations, p)
        });
    }
    v
}

/// A strip bent: its left end held, its right end lifted and turned.
fn bent_strip() -> (MeshData, Vec<u32>, Vec<DVec2>) {
    let mesh = grid(7, 2, 1.0, 0.15, Diagonals::Alternating, 5);
    let (nx, ny) = (7usize, 2usize);
    let mut constrained = Vec::new();
    let mut targets = Vec::new();
    let turn = DVec2::from_angle(1.2);
    for j in 0..=ny {
        let left = (j * (nx + 1)) as u32;
        constrained.push(left);
        targets.push(mesh.rest[left as usize]);
        let right = (j * (nx + 1) + nx) as u32;
        constrained.push(right);
        let p = mesh.rest[right as usize] - DVec2::new(7.0, 0.0);
        targets.push(DVec2::new(4.0, 3.5) + turn.rotate(p));
    }
    (mesh, constrained, targets)
}

#[test]
fn local_global_lowers_the_energy_to_the_reference_minimum() {
    let (mesh, constrained, targets) = bent_strip();
    let registration = Registration::new(&mesh.rest, &mesh.triangles).expect("a mesh");
    let compiled = registration.compile(&constrained, None).expect("compiled");
    let mut pose = compiled.update(&targets).expect("two steps");
    let two_step = energy(&mesh, &pose.positions);
    // The crate's energy is the reference's.
    let ours = compiled.energy(&pose.positions);
    assert!(
        (ours - two_step).abs() <= 1e-9 * two_step.max(1.0),
        "energy {ours}, the reference's {two_step}"
    );
    // One iteration at a time: never up.
    let mut last = two_step;
    for i in 0..300 {
        compiled
            .refine_into(&targets, &mut pose, 1, 0.0)
            .expect("an iteration");
        let e = energy(&mesh, &pose.positions);
        assert!(
            e <= last * (1.0 + 1e-12) + 1e-12,
            "iteration {i}: {last} → {e}"
        );
        last = e;
    }
    for (&v, t) in constrained.iter().zip(&targets) {
        assert_eq!(pose.positions[v as usize], *t, "pins stay on their targets");
    }
    let start = compiled.update(&targets).expect("two steps").positions;
    let expected = energy(&mesh, &reference(&mesh, &constrained, &targets, &start));
    assert!(
        last < 0.9 * two_step,
        "the two steps' {two_step} only fell to {last}"
    );
    assert!(
        last <= 1.001 * expected && expected <= 1.001 * last,
        "local/global reached {last}, the reference {expected} (two steps: {two_step})"
    );
    // Run to a tolerance, it stops early and lands on the same minimum.
    let mut pose = compiled.update(&targets).expect("two steps");
    let ran = compiled
        .refine_into(&targets, &mut pose, 1000, 1e-9)
        .expect("refined");
    assert!(ran < 1000, "converged in {ran}");
    let converged = energy(&mesh, &pose.positions);
    assert!(
        (converged - last).abs() <= 1e-6 * last,
        "{converged} against {last}"
    );
}
