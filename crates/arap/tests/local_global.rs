//! Local/global minimisation (Sorkine and Alexa 2007) from the two-step result, plain
//! and accelerated: it never raises the ARAP energy, and it reaches the minimum a
//! plain reference finds — local and global steps written from their definitions,
//! the global one by the dense solver of `support::dense`.

use crate::support;

use arap::{Minimise, Registration};
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
    // Plain local/global, one iteration at a time: never up.
    let plain = Minimise {
        iterations: 1,
        tolerance: 0.0,
        history: 0,
    };
    let mut last = two_step;
    for i in 0..300 {
        compiled
            .minimise_into(&targets, &mut pose, &plain)
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
    // Accelerated, run to a tolerance: it stops early, in far fewer iterations than
    // plain iteration needs, on the same minimum.
    let settings = Minimise {
        iterations: 1000,
        tolerance: 1e-9,
        history: 5,
    };
    let mut pose = compiled.update(&targets).expect("two steps");
    let accelerated = compiled
        .minimise_into(&targets, &mut pose, &settings)
        .expect("minimised");
    let mut plain_pose = compiled.update(&targets).expect("two steps");
    let plainly = compiled
        .minimise_into(
            &targets,
            &mut plain_pose,
            &Minimise {
                history: 0,
                ..settings
            },
        )
        .expect("minimised");
    assert!(
        accelerated.iterations < 1000 && 2 * accelerated.iterations < plainly.iterations,
        "accelerated {} iterations, plain {}",
        accelerated.iterations,
        plainly.iterations
    );
    for e in [energy(&mesh, &pose.positions), accelerated.energy] {
        assert!((e - last).abs() <= 1e-6 * last, "{e} against {last}");
    }
    for (a, b) in pose.positions.iter().zip(&plain_pose.positions) {
        assert!(a.distance(*b) < 1e-6, "{a} against {b}");
    }
    // The energies it accepts never rise: a run of k + 1 iterations ends no higher
    // than one of k.
    let mut last = f64::INFINITY;
    for k in 1..40 {
        let mut pose = compiled.update(&targets).expect("two steps");
        let run = compiled
            .minimise_into(
                &targets,
                &mut pose,
                &Minimise {
                    iterations: k,
                    ..settings
                },
            )
            .expect("minimised");
        assert!(
            run.energy <= last * (1.0 + 1e-12),
            "{k} iterations: {last} → {}",
            run.energy
        );
        assert!(energy(&mesh, &pose.positions) <= run.energy * (1.0 + 1e-12) + 1e-12);
        last = run.energy;
    }
}
