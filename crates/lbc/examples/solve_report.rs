//! Solves the timing cages of `benches/cases/mod.rs` once each and prints what every
//! stage took, the iterations, the objective and the compact rows' size:
//!
//! ```text
//! cargo run --release -p lbc --example solve_report -- [--tolerance T] [--only NAME]
//!     [--vertices N] [--penalty MU] [--relaxation ALPHA] [--trace] [--narrow]
//! ```
//!
//! `--penalty` fixes `μ` (no residual balancing); `--trace` prints the residuals as
//! the solve goes; `--narrow` runs the passes as compiled for the baseline x86-64
//! even where the CPU has AVX2.

#[path = "../benches/cases/mod.rs"]
mod cases;

use std::time::Instant;

use lbc::{Domain, Settings, solve};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let number = |flag: &str| value(flag).and_then(|v| v.parse::<f64>().ok());
    let penalty = number("--penalty");
    let settings = Settings {
        tolerance: number("--tolerance").unwrap_or(lbc::DEFAULT_TOLERANCE),
        initial_penalty: penalty,
        adaptive_penalty: penalty.is_none(),
        relaxation: number("--relaxation").unwrap_or(Settings::default().relaxation),
        wide_vectors: !args.iter().any(|a| a == "--narrow"),
        ..Settings::default()
    };
    let trace = args.iter().any(|a| a == "--trace");
    for case in cases::cases() {
        if value("--only").is_some_and(|o| !case.name.starts_with(&o)) {
            continue;
        }
        let target = number("--vertices").map_or(case.target, |v| v as usize);
        let domain = Domain::triangulate(&case.cage, target).expect("triangulates");
        let start = Instant::now();
        let solved = solve(&domain, &settings, &mut |p| {
            if trace && p.iteration % 25 == 0 {
                println!(
                    "  {:5}  primal/threshold {:8.3}  dual/threshold {:8.3}  μ {:.4}",
                    p.iteration,
                    p.primal_residual / p.primal_threshold,
                    p.dual_residual / p.dual_threshold,
                    p.penalty
                );
            }
            true
        })
        .expect("solves");
        let total = start.elapsed();
        let r = &solved.report;
        let compact = solved.compact();
        let pose: Vec<glam::DVec2> = case.cage.vertices().iter().map(|p| *p * 1.1).collect();
        let mut deform: Vec<f64> = (0..15)
            .map(|_| {
                let clock = Instant::now();
                std::hint::black_box(compact.deform(&pose).expect("pose fits"));
                clock.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        deform.sort_by(f64::total_cmp);
        println!(
            "{:12} {:2} cage vertices, {:6} mesh vertices: {:6.3} s (geodesics {:.3} s, \
             factorisation {:.3} s, ADMM {:.3} s = {} iterations × {:.2} ms on {} threads, projection {:.3} s), \
             converged {}, objective {:.6e}, {:.2} weights per vertex, deformation {:.2} ms",
            case.name,
            case.cage.len(),
            domain.positions().len(),
            total.as_secs_f64(),
            r.geodesics.as_secs_f64(),
            r.factorisation.as_secs_f64(),
            r.admm.as_secs_f64(),
            r.iterations,
            r.admm.as_secs_f64() * 1e3 / r.iterations.max(1) as f64,
            r.threads,
            r.projection.as_secs_f64(),
            r.converged,
            r.objective,
            compact.len() as f64 / compact.vertices() as f64,
            deform[deform.len() / 2],
        );
    }
}
