//! Times `warp_cpu` on a swirled 317×317-cell grid (about 200k triangles).
//!
//! `cargo run -p render --release --example warp_timing [runs] [sizes...]`
//! (defaults: 5 runs at 1024 and 4096). Set `RAYON_NUM_THREADS` to vary the
//! thread count. The Criterion benchmark `benches/warp.rs` measures the same.

#[path = "../tests/support/mod.rs"]
mod support;

use std::time::Instant;

use render::{RasterOptions, WarpMesh, warp_cpu};
use support::{Grid, gradient_texture, swirl};

fn main() {
    let args: Vec<u32> = std::env::args()
        .skip(1)
        .filter_map(|s| s.parse().ok())
        .collect();
    let runs = args.first().copied().unwrap_or(5).max(1) as usize;
    let sizes = match args.get(1..) {
        Some(sizes) if !sizes.is_empty() => sizes.to_vec(),
        _ => vec![1024, 4096],
    };
    println!("rayon threads: {}", rayon::current_num_threads());
    for size in sizes {
        let texture = gradient_texture(size);
        let grid = Grid::new(size as f32, size as f32, 317, 317);
        let swirled = swirl(&grid.positions, size as f32);
        for (label, deformed) in [("swirl", &swirled), ("identity", &grid.positions)] {
            let mesh = WarpMesh {
                rest: &grid.positions,
                deformed,
                triangles: &grid.triangles,
            };
            let mut times = Vec::new();
            for _ in 0..runs {
                let start = Instant::now();
                let out = warp_cpu(&texture, &mesh, size, size, &RasterOptions::default());
                times.push(start.elapsed().as_secs_f64() * 1e3);
                if let Err(e) = out {
                    eprintln!("warp failed: {e}");
                    return;
                }
            }
            times.sort_by(f64::total_cmp);
            println!(
                "{size}x{size}, {} triangles, {label}: median {:.1} ms (min {:.1}, max {:.1})",
                grid.triangles.len(),
                times[times.len() / 2],
                times[0],
                times[times.len() - 1]
            );
        }
    }
}
