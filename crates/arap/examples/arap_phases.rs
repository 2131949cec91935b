//! Times the three phases on a cut-out mesh (as the benchmarks build it) with four
//! point handles, and with four turning handles (each pinning its one-ring), and
//! prints the median and the fastest of several runs:
//! `cargo run --release -p arap --example arap_phases [VERTICES]`.
//!
//! On a busy machine the fastest run says more about the code than the median.

#[path = "../tests/support/mod.rs"]
mod support;

use std::time::Instant;

use arap::{ArapError, Deformation, Registration, Similarity, ring_constraints};
use glam::DVec2;

/// Runs `f` `times` times; returns the last result with the median and the fastest
/// run in milliseconds.
fn timed<T>(times: usize, mut f: impl FnMut() -> T) -> (T, f64, f64) {
    let mut runs = Vec::with_capacity(times);
    let mut out = None;
    for _ in 0..times {
        let start = Instant::now();
        out = Some(f());
        runs.push(start.elapsed().as_secs_f64() * 1e3);
    }
    runs.sort_by(f64::total_cmp);
    let out = out.expect("at least one run");
    (out, runs[runs.len() / 2], runs[0])
}

fn main() -> Result<(), ArapError> {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(100_000);
    let mesh = support::cut_out(n, 7);
    println!(
        "{} vertices, {} triangles (median / fastest)",
        mesh.rest.len(),
        mesh.triangles.len()
    );
    let (registration, median, fastest) =
        timed(3, || Registration::new(&mesh.rest, &mesh.triangles));
    let registration = registration?;
    println!("registration           {median:9.3} / {fastest:9.3} ms");

    let handles = support::spread_handles(&mesh);
    let (compiled, median, fastest) = timed(5, || registration.compile(&handles, None));
    let compiled = compiled?;
    println!("compilation            {median:9.3} / {fastest:9.3} ms");
    let poses: Vec<Vec<DVec2>> = (0..31)
        .map(|k| support::drag_pose(&mesh, &handles, k as f64 / 30.0))
        .collect();
    let mut out = Deformation::default();
    let mut k = 0;
    let (result, median, fastest) = timed(31, || {
        k = (k + 1) % poses.len();
        compiled.update_into(&poses[k], &mut out)
    });
    result?;
    println!("update                 {median:9.3} / {fastest:9.3} ms");

    // Turning handles: each pins its one-ring by a similarity.
    let pins = |t: f64| -> Result<Vec<(u32, DVec2)>, ArapError> {
        let moved = support::drag_pose(&mesh, &handles, t);
        let mut all = Vec::new();
        for (&h, to) in handles.iter().zip(moved) {
            let turn = Similarity {
                translation: to - mesh.rest[h as usize],
                rotation: 0.5 * t,
                scale: 1.0,
            };
            all.extend(ring_constraints(&registration, h, &turn)?);
        }
        Ok(all)
    };
    let vertices: Vec<u32> = pins(0.0)?.iter().map(|p| p.0).collect();
    let (compiled, median, fastest) = timed(5, || registration.compile(&vertices, None));
    let compiled = compiled?;
    println!(
        "compilation, turning   {median:9.3} / {fastest:9.3} ms  ({} constrained vertices)",
        vertices.len()
    );
    let poses = (0..31)
        .map(|k| Ok(pins(k as f64 / 30.0)?.iter().map(|p| p.1).collect()))
        .collect::<Result<Vec<Vec<DVec2>>, ArapError>>()?;
    let mut k = 0;
    let (result, median, fastest) = timed(31, || {
        k = (k + 1) % poses.len();
        compiled.update_into(&poses[k], &mut out)
    });
    result?;
    println!("update, turning        {median:9.3} / {fastest:9.3} ms");
    Ok(())
}
