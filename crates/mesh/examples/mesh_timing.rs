//! Times `domain_for_density` + `triangulate` on an opaque image, on cut-outs (a wobbly
//! blob with a hole at 1024² and 4096², and the built-in lizard) and on pictures of
//! small specks, for several target vertex counts, and reports mesh quality.
//!
//! Run with `cargo run --release -p mesh --example mesh_timing`.

use std::time::Instant;

use glam::DVec2;
use mesh::{Constraints, DomainOptions, MeshOptions, domain_for_density, triangulate};

fn cutout(size: u32) -> image::RgbaImage {
    let c = size as f64 / 2.0;
    image::RgbaImage::from_fn(size, size, |x, y| {
        let p = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
        // A wobbly blob with a square hole, and a separate small disc.
        let d = p - DVec2::splat(c * 0.9);
        let r = c * 0.7 * (1.0 + 0.15 * (5.0 * d.y.atan2(d.x)).sin());
        let in_blob = d.length() < r;
        let in_hole = (d.x - 40.0).abs() < 60.0 && (d.y + 30.0).abs() < 60.0;
        let in_disc = (p - DVec2::new(c * 1.75, c * 1.75)).length() < c * 0.2;
        let a = if (in_blob && !in_hole) || in_disc {
            255
        } else {
            0
        };
        image::Rgba([128, 64, 32, a])
    })
}

/// `count` specks of 1 to 3 px on a side, scattered over a `size²` transparent picture.
fn specks(size: u32, count: usize) -> image::RgbaImage {
    let mut img = image::RgbaImage::new(size, size);
    let mut state = 0x2545_f491_u64;
    let mut next = move |n: u32| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state % u64::from(n)) as u32
    };
    for _ in 0..count {
        let (x, y, s) = (next(size - 3), next(size - 3), 1 + next(3));
        for dy in 0..s {
            for dx in 0..s {
                img.put_pixel(x + dx, y + dy, image::Rgba([20, 30, 40, 255]));
            }
        }
    }
    img
}

fn min_angle_deg(m: &mesh::Mesh) -> (f64, f64) {
    let mut worst = 180.0f64;
    let mut below = 0usize;
    for t in 0..m.triangles.len() {
        let [a, b, c] = m.triangle_positions(t);
        for (p, q, r) in [(a, b, c), (b, c, a), (c, a, b)] {
            let ang = (q - p).angle_to(r - p).abs().to_degrees();
            worst = worst.min(ang);
            if ang < 20.0 {
                below += 1;
            }
        }
    }
    (worst, below as f64 / m.triangles.len() as f64)
}

fn main() {
    let lizard = image::load_from_memory(include_bytes!("../../../assets/lizard.png"))
        .expect("the built-in lizard decodes")
        .to_rgba8();
    let images = [
        (
            "opaque 1024²",
            image::RgbaImage::from_pixel(1024, 1024, image::Rgba([1, 2, 3, 255])),
        ),
        ("cut-out 1024²", cutout(1024)),
        ("cut-out 4096²", cutout(4096)),
        ("lizard", lizard),
        ("3000 specks 2048²", specks(2048, 3000)),
        ("20000 specks 1024²", specks(1024, 20_000)),
    ];
    for (name, img) in &images {
        println!("{name}:");
        for target in [500usize, 20_000, 100_000, 600_000] {
            let t0 = Instant::now();
            let domain =
                domain_for_density(img, &DomainOptions::default(), target).expect("domain");
            let t_domain = t0.elapsed();
            let rings: usize = domain.rings().map(|r| r.len()).sum();
            let opts = MeshOptions {
                target_vertices: target,
                ..MeshOptions::default()
            };
            let t1 = Instant::now();
            let t = triangulate(&domain, &Constraints::default(), &opts).expect("mesh");
            let el = t1.elapsed();
            let (worst, frac) = min_angle_deg(&t.mesh);
            println!(
                "  target {target:>7}: domain {:>7.1} ms ({} polygons, {} ring vertices, area {:.0}); \
                 mesh {:>7.1} ms, {:>7} vertices ({:+.1}%), {:>8} triangles; min angle {:.1}°, \
                 {:.3}% angles < 20°",
                t_domain.as_secs_f64() * 1e3,
                domain.polygons.len(),
                rings,
                domain.area(),
                el.as_secs_f64() * 1e3,
                t.mesh.vertices.len(),
                (t.mesh.vertices.len() as f64 / target as f64 - 1.0) * 100.0,
                t.mesh.triangles.len(),
                worst,
                frac * 100.0 / 3.0
            );
        }
    }
}
