//! How close ARAP's solvers come to the energy's minimum, and how fast: `cargo run
//! --release -p pipeline --example arap_energy`. For each picture of
//! `tests/support/energy.rs` it prints, for the two steps and the local/global solver
//! at several settings, the energy over ARAP's mesh against a plain converged
//! local/global solve, Σ area·‖J − R‖² over the picture's mesh, turned-over
//! triangles, iterations and time.

#[path = "../tests/support/energy.rs"]
mod energy;
#[path = "../tests/support/figure.rs"]
mod figure;

use std::time::Instant;

use energy::{ControlMesh, jacobian_energy, local_global};
use pipeline::ArapRig;

fn main() {
    let drag = std::env::args().nth(1).as_deref() == Some("--drag");
    for case in energy::cases(r#"{"solver": "local-global"}"#) {
        let warper = pipeline::prepare_warper(&case.image, &case.project, None, &())
            .unwrap_or_else(|e| panic!("{}: {e:#}", case.name));
        if drag && std::env::args().nth(2).is_none() {
            drag_report(&case, &warper);
            continue;
        }
        let rig: &ArapRig = warper.deformer.as_any().downcast_ref().expect("ARAP");
        let mesh = rig.arap_mesh();
        let weights = rig.rigidity().to_vec();
        let control = ControlMesh {
            rest: mesh.positions(),
            triangles: mesh.triangles(),
            weights: &weights,
        };
        let mut pinned = vec![false; mesh.len()];
        for &(v, _) in rig.pins() {
            pinned[v as usize] = true;
        }
        // The plain reference: from the rest shape with the pins placed.
        let mut start = mesh.positions().to_vec();
        let posed = rig.arap_positions();
        for &(v, _) in rig.pins() {
            start[v as usize] = posed[v as usize];
        }
        let clock = Instant::now();
        let reference = local_global(&control, &pinned, &start, if drag { 1 } else { 3000 });
        let reference_energy = energy::energy(&control, &reference);
        println!(
            "{}: {} picture vertices, {} ARAP vertices, {} pinned; reference {:.1} ({:.0} s)",
            case.name,
            rig.positions().len(),
            mesh.len(),
            rig.pins().len(),
            reference_energy,
            clock.elapsed().as_secs_f64()
        );
        let (_, ref_folds) = jacobian_energy(mesh.positions(), mesh.triangles(), &reference);
        println!("  reference: {ref_folds} ARAP triangles turned over");
        for (label, settings) in [
            (
                "two steps",
                arap::Minimise {
                    iterations: 0,
                    ..Default::default()
                },
            ),
            (
                "plain ×20",
                arap::Minimise {
                    iterations: 20,
                    tolerance: 0.0,
                    history: 0,
                },
            ),
            (
                "plain ×200",
                arap::Minimise {
                    iterations: 200,
                    tolerance: 0.0,
                    history: 0,
                },
            ),
            (
                "AA5 ×10",
                arap::Minimise {
                    iterations: 10,
                    tolerance: 0.0,
                    history: 5,
                },
            ),
            (
                "AA5 ×20",
                arap::Minimise {
                    iterations: 20,
                    tolerance: 0.0,
                    history: 5,
                },
            ),
            (
                "AA5 ×50",
                arap::Minimise {
                    iterations: 50,
                    tolerance: 0.0,
                    history: 5,
                },
            ),
            (
                "AA5 0.01px",
                arap::Minimise {
                    iterations: 500,
                    tolerance: 0.01,
                    history: 5,
                },
            ),
            (
                "AA8 0.01px",
                arap::Minimise {
                    iterations: 500,
                    tolerance: 0.01,
                    history: 8,
                },
            ),
            ("default", pipeline::arap::SETTLED),
        ] {
            let mut rig = rig.clone();
            let clock = Instant::now();
            rig.set_minimise(settings, pipeline::arap::LIVE)
                .expect("pose");
            let ms = clock.elapsed().as_secs_f64() * 1e3;
            let e = energy::energy(&control, rig.arap_positions());
            let (je, folds) = jacobian_energy(
                warper.deformer.rest(),
                warper.deformer.triangles(),
                rig.positions(),
            );
            let (_, arap_folds) =
                jacobian_energy(mesh.positions(), mesh.triangles(), rig.arap_positions());
            let c = rig.convergence().expect("local/global");

            println!(
                "  {label:>12}: energy ×{:.3}, picture ΣA‖J−R‖² {je:.1}, {folds} picture / {arap_folds} ARAP folds, {} iterations, moved {:.4}, {ms:.1} ms",
                e / reference_energy,
                c.iterations,
                c.moved
            );
        }
    }
}

/// A drag of the case's moved handles from rest to their pose over 30 frames, live,
/// at several iteration budgets a frame: the worst energy against the settled one of
/// the same frame, the median frame time, and how far the drag's end jumps when it
/// settles.
fn drag_report(case: &energy::EnergyCase, warper: &pipeline::Warper) {
    use pipeline::Deformer;
    let base: &ArapRig = warper.deformer.as_any().downcast_ref().expect("ARAP");
    let frames = 30;
    let poses: Vec<project::Project> = (1..=frames)
        .map(|f| {
            let mut p = case.project.clone();
            for (h, target) in p.handles.iter_mut().zip(&case.project.handles) {
                if let (
                    project::HandleSpec::Point { translate, .. },
                    project::HandleSpec::Point { translate: to, .. },
                ) = (h, target)
                {
                    *translate = to.map(|t| t * f64::from(f) / f64::from(frames));
                }
            }
            p
        })
        .collect();
    let mut rest = case.project.clone();
    for h in &mut rest.handles {
        if let project::HandleSpec::Point { translate, .. } = h {
            *translate = [0.0, 0.0];
        }
    }
    // The settled energy of every frame.
    let mut settled = base.clone();
    let settled_energy: Vec<(f64, Vec<glam::DVec2>)> = poses
        .iter()
        .map(|p| {
            settled.follow(p).expect("pose");
            (
                settled.convergence().expect("local/global").energy,
                settled.positions().to_vec(),
            )
        })
        .collect();
    for budget in [2, 4, 8, 12, 20] {
        let mut rig = base.clone();
        rig.set_minimise(
            pipeline::arap::SETTLED,
            arap::Minimise {
                iterations: budget,
                ..pipeline::arap::LIVE
            },
        )
        .expect("settings");
        rig.follow(&rest).expect("rest");
        rig.set_live(true).expect("live");
        let mut worst: f64 = 0.0;
        let mut times = Vec::new();
        for (p, (e, _)) in poses.iter().zip(&settled_energy) {
            let clock = Instant::now();
            rig.follow(p).expect("pose");
            times.push(clock.elapsed().as_secs_f64() * 1e3);
            worst = worst.max(rig.convergence().expect("local/global").energy / e.max(1e-12));
        }
        let before = rig.positions().to_vec();
        rig.set_live(false).expect("settle");
        let jump = before
            .iter()
            .zip(rig.positions())
            .map(|(a, b)| a.distance(*b))
            .fold(0.0, f64::max);
        let end = settled_energy.last().expect("frames");
        let off = end
            .1
            .iter()
            .zip(rig.positions())
            .map(|(a, b)| a.distance(*b))
            .fold(0.0, f64::max);
        times.sort_by(f64::total_cmp);
        println!(
            "{}: {budget} iterations a frame: worst energy ×{worst:.3} of settled, frame median {:.2} ms p90 {:.2} ms, release jump {jump:.2} px, settled off {off:.2e} px",
            case.name,
            times[times.len() / 2],
            times[times.len() * 9 / 10]
        );
    }
}
