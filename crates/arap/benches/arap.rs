//! Criterion benchmarks of the three phases — registration, compilation, update (one
//! drag frame: both steps) — on jittered cut-out meshes (two holes and a notch) of
//! about 300, 20k and 100k vertices with four handles.

#[path = "../tests/support/mod.rs"]
mod support;

use std::hint::black_box;

use arap::{Deformation, Registration};
use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec2;
use support::{cut_out, drag_pose, spread_handles};

const SIZES: [usize; 3] = [300, 20_000, 100_000];

fn registration(c: &mut Criterion) {
    let mut group = c.benchmark_group("registration");
    group.sample_size(10);
    for n in SIZES {
        let mesh = cut_out(n, 7);
        group.bench_function(format!("{n}"), |b| {
            b.iter(|| Registration::new(black_box(&mesh.rest), black_box(&mesh.triangles)))
        });
    }
    group.finish();
}

fn compilation(c: &mut Criterion) {
    let mut group = c.benchmark_group("compilation");
    group.sample_size(10);
    for n in SIZES {
        let mesh = cut_out(n, 7);
        let registration = Registration::new(&mesh.rest, &mesh.triangles).expect("valid mesh");
        let handles = spread_handles(&mesh);
        group.bench_function(format!("{n}"), |b| {
            b.iter(|| registration.compile(black_box(&handles), None))
        });
    }
    group.finish();
}

fn update(c: &mut Criterion) {
    let mut group = c.benchmark_group("update");
    for n in SIZES {
        let mesh = cut_out(n, 7);
        let registration = Registration::new(&mesh.rest, &mesh.triangles).expect("valid mesh");
        let handles = spread_handles(&mesh);
        let compiled = registration.compile(&handles, None).expect("compiles");
        let poses: Vec<Vec<DVec2>> = (0..16)
            .map(|k| drag_pose(&mesh, &handles, k as f64 / 15.0))
            .collect();
        let mut out = Deformation::default();
        let mut k = 0;
        group.bench_function(format!("{n}"), |b| {
            b.iter(|| {
                k = (k + 1) % poses.len();
                compiled
                    .update_into(black_box(&poses[k]), &mut out)
                    .expect("updates");
            })
        });
    }
    group.finish();
}

criterion_group!(benches, registration, compilation, update);
criterion_main!(benches);
