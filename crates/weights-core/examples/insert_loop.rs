//! Inserts a handle at random samples of the benchmark's non-convex 100k domain, each
//! time into a copy of the same rig, for profiling (`perf record`).
//! `cargo run --release -p weights-core --example insert_loop [count]`

#[path = "../tests/support/mod.rs"]
mod support;

use std::time::Instant;

use glam::DVec2;
use support::{Rng, Shape, grid_domain};
use weights_core::{Handle, Rig, RigOptions};

fn main() {
    let count: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(200);
    let samples = 100_000f64;
    let side = (samples * 1.1).sqrt();
    let nx = (side * 1.25).round() as usize;
    let ny = (samples / nx as f64).round() as usize;
    let d = grid_domain(nx, ny, 1.0, 0.3, Shape::Holed, 42);
    d.prepare();
    let mut rng = Rng(7);
    let (lo, hi) = d.bounds();
    let gap = (hi - lo).length() / 20.0;
    let mut pts: Vec<DVec2> = Vec::new();
    while pts.len() < 10 {
        let q = d.positions()[rng.below(d.len())];
        if pts.iter().all(|o| (*o - q).length() > gap) {
            pts.push(q);
        }
    }
    let handles: Vec<Handle> = pts.into_iter().map(Handle::point).collect();
    let base = Rig::new(d.clone(), handles, RigOptions::default()).expect("valid");
    let mut times = Vec::new();
    for _ in 0..count {
        let p = d.positions()[rng.below(d.len())];
        let mut rig = base.clone();
        let clock = Instant::now();
        if rig.insert_handle(Handle::point(p)).is_ok() {
            times.push(clock.elapsed().as_secs_f64() * 1e3);
        }
    }
    times.sort_by(f64::total_cmp);
    println!(
        "{} insertions: median {:.2} ms, mean {:.2} ms",
        times.len(),
        times[times.len() / 2],
        times.iter().sum::<f64>() / times.len() as f64
    );
}
