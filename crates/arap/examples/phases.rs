//! Times the three phases on a cut-out mesh (as the benchmarks build it) and prints
//! one line each: `cargo run --release -p arap --example phases [VERTICES]`.
//!
//! Besides wall time it prints the process's time on a CPU, all threads together
//! (from `/proc/self/task/*/schedstat`, Linux only), which a busy machine disturbs
//! less than wall time.

#[path = "../tests/support/mod.rs"]
mod support;

use std::time::Instant;

use arap::{ArapError, Deformation, Registration};

/// This process's time on a CPU over all its threads, in nanoseconds (0 where the
/// kernel does not say).
fn cpu_ns() -> u64 {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
        return 0;
    };
    tasks
        .flatten()
        .filter_map(|task| std::fs::read_to_string(task.path().join("schedstat")).ok())
        .filter_map(|s| {
            s.split_whitespace()
                .next()
                .and_then(|t| t.parse::<u64>().ok())
        })
        .sum()
}

/// Runs `f`, returning its result with wall and CPU milliseconds.
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64, f64) {
    let (wall, cpu) = (Instant::now(), cpu_ns());
    let out = f();
    let cpu = (cpu_ns() - cpu) as f64 / 1e6;
    (out, wall.elapsed().as_secs_f64() * 1e3, cpu)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> Result<(), ArapError> {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(100_000);
    let mesh = support::cut_out(n, 7);
    println!(
        "{} vertices, {} triangles",
        mesh.rest.len(),
        mesh.triangles.len()
    );
    let (registration, wall, cpu) = timed(|| Registration::new(&mesh.rest, &mesh.triangles));
    let registration = registration?;
    println!("registration  {wall:8.3} ms wall  {cpu:8.3} ms cpu");
    let handles = support::spread_handles(&mesh);
    let (compiled, wall, cpu) = timed(|| registration.compile(&handles, None));
    let compiled = compiled?;
    println!("compilation   {wall:8.3} ms wall  {cpu:8.3} ms cpu");
    let mut out = Deformation::default();
    let (mut walls, mut cpus) = (Vec::new(), Vec::new());
    for k in 0..31 {
        let targets = support::drag_pose(&mesh, &handles, k as f64 / 30.0);
        let (result, wall, cpu) = timed(|| compiled.update_into(&targets, &mut out));
        result?;
        walls.push(wall);
        cpus.push(cpu);
    }
    println!(
        "update        {:8.3} ms wall  {:8.3} ms cpu  (median of 31 poses)",
        median(walls),
        median(cpus)
    );
    Ok(())
}
