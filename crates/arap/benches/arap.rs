//! Criterion benchmarks of the three phases — registration, compilation, update (one
//! drag frame: both steps) — on jittered cut-out meshes (two holes and a notch) of
//! about 300, 20k and 100k vertices with four point handles, and updates with four
//! turning handles (each pinning its one-ring).

#[path = "../tests/support/mod.rs"]
mod support;

use std::hint::black_box;

use arap::{Deformation, Registration, Similarity, ring_constraints};
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

/// Four point handles that also turn: each pins its one-ring by a similarity
/// (`ring_constraints`), about 28 constrained vertices, so step one back-substitutes
/// instead of using the product form.
fn update_turning_handles(c: &mut Criterion) {
    let mut group = c.benchmark_group("update_turning_handles");
    for n in SIZES {
        let mesh = cut_out(n, 7);
        let registration = Registration::new(&mesh.rest, &mesh.triangles).expect("valid mesh");
        let handles = spread_handles(&mesh);
        let pins = |t: f64| -> Vec<(u32, DVec2)> {
            let moved = drag_pose(&mesh, &handles, t);
            handles
                .iter()
                .zip(moved)
                .flat_map(|(&h, to)| {
                    let turn = Similarity {
                        translation: to - mesh.rest[h as usize],
                        rotation: 0.5 * t,
                        scale: 1.0,
                    };
                    ring_constraints(&registration, h, &turn).expect("valid handle")
                })
                .collect()
        };
        let vertices: Vec<u32> = pins(0.0).iter().map(|p| p.0).collect();
        let compiled = registration.compile(&vertices, None).expect("compiles");
        let poses: Vec<Vec<DVec2>> = (0..16)
            .map(|k| pins(k as f64 / 15.0).iter().map(|p| p.1).collect())
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

criterion_group!(
    benches,
    registration,
    compilation,
    update,
    update_turning_handles
);
criterion_main!(benches);
