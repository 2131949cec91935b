//! Times `warp_cpu` on a swirled grid mesh of about 200k triangles.
//!
//! `cargo run -p render --release --example warp_timing [runs] [sizes...]`

use std::time::Instant;

use glam::Vec2;
use image::RgbaImage;
use render::{RasterOptions, WarpMesh, warp_cpu};

/// A `size × size` texture with smooth gradients and some alpha.
fn texture(size: u32) -> RgbaImage {
    RgbaImage::from_fn(size, size, |x, y| {
        image::Rgba([
            (x * 255 / size) as u8,
            (y * 255 / size) as u8,
            ((x ^ y) & 0xff) as u8,
            if (x / 64 + y / 64) % 3 == 0 { 0 } else { 255 },
        ])
    })
}

/// A grid of `cells × cells` quads (two triangles each) over `size × size`,
/// and a swirl of it about the centre.
fn swirl_mesh(size: f32, cells: u32) -> (Vec<Vec2>, Vec<Vec2>, Vec<[u32; 3]>) {
    let mut rest = Vec::new();
    for j in 0..=cells {
        for i in 0..=cells {
            rest.push(Vec2::new(i as f32, j as f32) * size / cells as f32);
        }
    }
    let centre = Vec2::splat(size / 2.0);
    let deformed = rest
        .iter()
        .map(|&p| {
            let d = p - centre;
            let t = (1.0 - d.length() / (size / 2.0)).max(0.0);
            centre + Vec2::from_angle(1.2 * t * t).rotate(d)
        })
        .collect();
    let id = |i: u32, j: u32| j * (cells + 1) + i;
    let mut triangles = Vec::new();
    for j in 0..cells {
        for i in 0..cells {
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (rest, deformed, triangles)
}

fn main() {
    let args: Vec<u32> = std::env::args()
        .skip(1)
        .filter_map(|s| s.parse().ok())
        .collect();
    let runs = args.first().copied().unwrap_or(5) as usize;
    let sizes = match args.get(1..) {
        Some(sizes) if !sizes.is_empty() => sizes.to_vec(),
        _ => vec![1024, 4096],
    };
    println!("rayon threads: {}", rayon::current_num_threads());
    for size in sizes {
        let tex = texture(size);
        let (rest, deformed, triangles) = swirl_mesh(size as f32, 317);
        for (label, positions) in [("swirl", &deformed), ("identity", &rest)] {
            let mesh = WarpMesh {
                rest: &rest,
                deformed: positions,
                triangles: &triangles,
            };
            let mut times = Vec::new();
            for _ in 0..runs {
                let start = Instant::now();
                let out = warp_cpu(&tex, &mesh, size, size, &RasterOptions::default());
                times.push(start.elapsed().as_secs_f64() * 1e3);
                if let Err(e) = out {
                    eprintln!("warp failed: {e}");
                    return;
                }
            }
            times.sort_by(f64::total_cmp);
            println!(
                "{size}x{size}, {} triangles, {label}: median {:.1} ms (min {:.1}, max {:.1})",
                triangles.len(),
                times[times.len() / 2],
                times[0],
                times[times.len() - 1]
            );
        }
    }
}
