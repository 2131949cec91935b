//! Prints where the time of a rig build, an insertion and a deformation goes, on the
//! benchmark domains: `cargo run --release -p weights-core --example phases [samples] [holed]`
//! (`INSERTS=N REPEAT=R`: N insertion positions, each timed R times; `ONE_THREAD=1`: all
//! work on the main thread, for counting instructions with
//! `valgrind --tool=callgrind --toggle-collect='*Rig::insert_handle*'`).

#[path = "../tests/support/mod.rs"]
mod support;

use std::time::Instant;

use glam::DVec2;
use support::{Rng, Shape, grid_domain};
use weights_core::{Handle, Rig, RigOptions};

fn main() {
    if std::env::var_os("ONE_THREAD").is_some() {
        rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .use_current_thread()
            .build_global()
            .expect("the first pool");
    }
    let args: Vec<String> = std::env::args().collect();
    let samples: usize = args
        .get(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    let shape = if args.get(2).is_some_and(|s| s == "holed") {
        Shape::Holed
    } else {
        Shape::Rectangle
    };
    let side = (samples as f64).sqrt();
    let nx = (side * 1.25).round() as usize;
    let ny = (samples as f64 / nx as f64).round() as usize;
    let t = Instant::now();
    let d = grid_domain(nx, ny, 1.0, 0.3, shape, 42);
    println!(
        "mesh: {} samples, {:.1} ms",
        d.len(),
        t.elapsed().as_secs_f64() * 1e3
    );
    let t = Instant::now();
    d.prepare();
    println!(
        "prepare (graph, grids): {:.1} ms",
        t.elapsed().as_secs_f64() * 1e3
    );
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
    let t = Instant::now();
    let rig = Rig::new(d.clone(), handles, RigOptions::default()).expect("valid");
    println!(
        "Rig::new: {:.1} ms  {:?}",
        t.elapsed().as_secs_f64() * 1e3,
        rig.timings()
    );
    println!("{:?}", rig.stats());
    let mut out = vec![DVec2::ZERO; d.len()];
    for _ in 0..3 {
        let t = Instant::now();
        rig.deform_into(&mut out);
        println!("deform: {:.2} ms", t.elapsed().as_secs_f64() * 1e3);
    }
    let base = rig.clone();
    let mut totals = Vec::new();
    let env = |name: &str, default: usize| {
        std::env::var(name)
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(default)
    };
    // Each position is inserted `REPEAT` times into a fresh copy and the fastest run
    // counts: on a shared machine the minimum is the stable statistic.
    let (inserts, repeat) = (env("INSERTS", 12), env("REPEAT", 3).max(1));
    for _ in 0..inserts {
        let p = d.positions()[rng.below(d.len())];
        let mut best = f64::INFINITY;
        let mut report = String::new();
        for _ in 0..repeat {
            let mut rig = base.clone();
            let before = rig.stats().virtual_nodes;
            let t = Instant::now();
            let Ok(i) = rig.insert_handle(Handle::point(p)) else {
                break;
            };
            let ins = t.elapsed().as_secs_f64() * 1e3;
            if ins < best {
                best = ins;
                let timings = rig.update_timings();
                let added = rig.stats().virtual_nodes as i64 - before as i64;
                let t = Instant::now();
                rig.remove_handle(i).expect("exists");
                report = format!(
                    "insert {ins:.2} ms (+{added} virtual) {timings:?}\n  remove {:.2} ms",
                    t.elapsed().as_secs_f64() * 1e3
                );
            }
        }
        if best.is_finite() {
            println!("{report}");
            totals.push(best);
        }
    }
    if totals.is_empty() {
        return;
    }
    totals.sort_by(f64::total_cmp);
    let mean = totals.iter().sum::<f64>() / totals.len() as f64;
    let p90 = totals[(totals.len() * 9).div_ceil(10) - 1];
    println!(
        "insert over {} positions (best of {repeat}): median {:.2} ms, p90 {p90:.2} ms, mean {mean:.2} ms",
        totals.len(),
        totals[totals.len() / 2]
    );
}
