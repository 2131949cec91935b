//! Prints where the time of a rig build, an insertion and a deformation goes, on the
//! benchmark domains: `cargo run --release -p weights-core --example phases [samples] [holed]`.

#[path = "../tests/support/mod.rs"]
mod support;

use std::time::Instant;

use glam::DVec2;
use support::{Rng, Shape, grid_domain};
use weights_core::{Handle, Rig, RigOptions};

fn main() {
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
    let repeats: usize = std::env::var("INSERTS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(12);
    for _ in 0..repeats {
        let mut rig = base.clone();
        let p = d.positions()[rng.below(d.len())];
        let before = rig.stats().virtual_nodes;
        let t = Instant::now();
        let Ok(i) = rig.insert_handle(Handle::point(p)) else {
            continue;
        };
        let ins = t.elapsed().as_secs_f64() * 1e3;
        totals.push(ins);
        let timings = rig.update_timings();
        let added = rig.stats().virtual_nodes as i64 - before as i64;
        let t = Instant::now();
        rig.remove_handle(i).expect("exists");
        println!(
            "insert {ins:.2} ms (+{added} virtual) {timings:?}\n  remove {:.2} ms",
            t.elapsed().as_secs_f64() * 1e3
        );
    }
    totals.sort_by(f64::total_cmp);
    println!("median insert {:.2} ms", totals[totals.len() / 2]);
}
