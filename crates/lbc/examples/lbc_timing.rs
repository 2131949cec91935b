//! Times the stages on a star-shaped cage: `cargo run --release -p lbc --example
//! lbc_timing -- [cage vertices] [mesh vertices] [tolerance]`.

use std::time::Instant;

use glam::DVec2;
use lbc::{Cage, Domain, Settings, geodesic_distances, solve_with_distances};

fn main() -> Result<(), lbc::LbcError> {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(20);
    let target: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(3000);
    let tolerance: f64 = args
        .get(3)
        .and_then(|a| a.parse().ok())
        .unwrap_or(lbc::DEFAULT_TOLERANCE);
    // A star: alternate radii 300 and 150 (strongly concave).
    let cage = Cage::new(
        (0..n)
            .map(|i| {
                let a = i as f64 / n as f64 * std::f64::consts::TAU;
                let r = if i % 2 == 0 { 300.0 } else { 150.0 };
                DVec2::new(400.0 + r * a.cos(), 300.0 + r * a.sin())
            })
            .collect(),
    )?;
    let t = Instant::now();
    let domain = Domain::triangulate(&cage, target)?;
    println!(
        "mesh: {} vertices, {} triangles in {:.3} s",
        domain.positions().len(),
        domain.triangles().len(),
        t.elapsed().as_secs_f64()
    );
    let t = Instant::now();
    let d = geodesic_distances(&domain)?;
    println!("geodesics: {:.3} s", t.elapsed().as_secs_f64());
    let settings = Settings {
        tolerance,
        ..Settings::default()
    };
    let c = solve_with_distances(&domain, &d, &settings, &mut |_| true)?;
    let r = &c.report;
    println!(
        "factorisation {:.3} s, ADMM {} iterations in {:.3} s ({:.2} ms each), projection {:.3} s, converged {}, objective {:.6}",
        r.factorisation.as_secs_f64(),
        r.iterations,
        r.admm.as_secs_f64(),
        1e3 * r.admm.as_secs_f64() / r.iterations.max(1) as f64,
        r.projection.as_secs_f64(),
        r.converged,
        r.objective
    );
    println!("last: {:?}", r.last);
    let compact = c.compact();
    println!(
        "compact: {:.2} weights per vertex",
        compact.len() as f64 / compact.vertices() as f64
    );
    Ok(())
}
