//! Criterion benchmarks of the speed targets: full rig builds (convex and non-convex),
//! inserting one handle, and deforming every sample.

#[path = "../tests/support/mod.rs"]
mod support;

use std::hint::black_box;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use glam::DVec2;
use support::{Rng, Shape, grid_domain};
use weights_core::{Domain, Handle, Rig, RigOptions, Similarity};

/// A jittered grid domain with about `samples` vertices at unit spacing.
fn domain(samples: usize, shape: Shape) -> Domain {
    let side = (samples as f64
        * if matches!(shape, Shape::Holed) {
            1.1
        } else {
            1.0
        })
    .sqrt();
    let nx = (side * 1.25).round() as usize;
    let ny = (samples as f64 / nx as f64).round() as usize;
    let d = grid_domain(nx, ny, 1.0, 0.3, shape, 42);
    d.prepare();
    d
}

/// `count` point handles at random samples, spread out.
fn handles(domain: &Domain, count: usize, seed: u64) -> Vec<Handle> {
    let mut rng = Rng(seed);
    let p = domain.positions();
    let (lo, hi) = domain.bounds();
    let min_gap = (hi - lo).length() / (count as f64 * 2.0);
    let mut out: Vec<DVec2> = Vec::new();
    while out.len() < count {
        let q = p[rng.below(p.len())];
        if out.iter().all(|o| (*o - q).length() > min_gap) {
            out.push(q);
        }
    }
    out.into_iter()
        .map(|rest| Handle::Point {
            rest,
            transform: Similarity::translate(DVec2::new(3.0, -2.0)),
        })
        .collect()
}

fn build(c: &mut Criterion) {
    let mut group = c.benchmark_group("build");
    group.sample_size(10);
    for (name, samples, shape) in [
        ("convex_100k", 100_000, Shape::Rectangle),
        ("convex_1m", 1_000_000, Shape::Rectangle),
        ("non_convex_100k", 100_000, Shape::Holed),
        ("non_convex_620k", 620_000, Shape::Holed),
    ] {
        let d = domain(samples, shape);
        let h = handles(&d, 10, 7);
        group.bench_function(name, |b| {
            b.iter_batched(
                || (d.clone(), h.clone()),
                |(d, h)| black_box(Rig::new(d, h, RigOptions::default()).expect("valid")),
                BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

fn insert(c: &mut Criterion) {
    let mut group = c.benchmark_group("insert_one_handle");
    group.sample_size(20);
    let d = domain(100_000, Shape::Holed);
    let rig = Rig::new(d.clone(), handles(&d, 10, 7), RigOptions::default()).expect("valid");
    // A fixed set of random samples, visited in turn, so that every run averages over
    // the same positions (some need many virtual handles, most few).
    let mut rng = Rng(99);
    let positions: Vec<DVec2> = (0..64).map(|_| d.positions()[rng.below(d.len())]).collect();
    let mut next = 0;
    group.bench_function("non_convex_100k_10_handles", |b| {
        b.iter_batched(
            || {
                next = (next + 1) % positions.len();
                (rig.clone(), positions[next])
            },
            |(mut rig, p)| {
                // A position that collides with a node is refused quickly; both count.
                let _ = black_box(rig.insert_handle(Handle::point(p)));
                rig
            },
            BatchSize::LargeInput,
        )
    });
    group.finish();
}

fn deform(c: &mut Criterion) {
    let mut group = c.benchmark_group("deform");
    let d = domain(1_000_000, Shape::Rectangle);
    let rig = Rig::new(d.clone(), handles(&d, 10, 7), RigOptions::default()).expect("valid");
    let mut out = vec![DVec2::ZERO; d.len()];
    group.bench_function("samples_1m", |b| {
        b.iter(|| rig.deform_into(black_box(&mut out)))
    });
    group.finish();
}

criterion_group!(benches, build, insert, deform);
criterion_main!(benches);
