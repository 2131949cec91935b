//! Criterion benchmarks of the CPU warp: full-resolution export of a swirled
//! mesh of about 200k triangles, at 1024² and 4096².

#[path = "../tests/support/mod.rs"]
mod support;

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use render::{RasterOptions, WarpMesh, warp_cpu};
use support::{Grid, gradient_texture, swirl};

fn warp_200k_triangles(c: &mut Criterion) {
    let mut group = c.benchmark_group("warp_cpu_200k_triangles");
    group.sample_size(10);
    for size in [1024u32, 4096] {
        let texture = gradient_texture(size);
        let grid = Grid::new(size as f32, size as f32, 317, 317);
        let swirled = swirl(&grid.positions, size as f32);
        let mesh = WarpMesh {
            rest: &grid.positions,
            deformed: &swirled,
            triangles: &grid.triangles,
        };
        group.bench_function(format!("swirl_{size}"), |b| {
            b.iter(|| {
                warp_cpu(
                    black_box(&texture),
                    &mesh,
                    size,
                    size,
                    &RasterOptions::default(),
                )
            })
        });
    }
    group.finish();
}

criterion_group!(benches, warp_200k_triangles);
criterion_main!(benches);
