//! The GPU path (wgpu, on a software adapter where there is no GPU) draws what the CPU
//! path draws. Needs a wgpu adapter: `scripts/setup.sh` installs Mesa's lavapipe.

use crate::support;

use glam::Vec2;
use render::{GpuContext, RasterOptions, WarpMesh, warp_cpu};
use support::{Grid, gradient_texture, swirl};

/// Share of premultiplied channels that differ by more than `tolerance`, and the
/// largest difference (the colour under a fully transparent pixel does not count).
fn compare(a: &image::RgbaImage, b: &image::RgbaImage, tolerance: u8) -> (f64, u8) {
    let premultiplied = |p: &image::Rgba<u8>| {
        let m = |c: u8| ((u16::from(c) * u16::from(p[3]) + 127) / 255) as u8;
        [m(p[0]), m(p[1]), m(p[2]), p[3]]
    };
    let mut over = 0usize;
    let mut worst = 0u8;
    for (x, y) in a.pixels().zip(b.pixels()) {
        for (u, v) in premultiplied(x).into_iter().zip(premultiplied(y)) {
            let d = u.abs_diff(v);
            worst = worst.max(d);
            if d > tolerance {
                over += 1;
            }
        }
    }
    (over as f64 / a.as_raw().len() as f64, worst)
}

#[test]
fn gpu_and_cpu_draw_the_same_warp() {
    let gpu = GpuContext::new().expect("a wgpu adapter (run scripts/setup.sh for lavapipe)");
    eprintln!("adapter: {:?}", gpu.adapter_info());
    let size = 256u32;
    let texture = gradient_texture(size);
    let grid = Grid::new(size as f32, size as f32, 24, 24);
    let cases: [(&str, Vec<Vec2>); 2] = [
        ("identity", grid.positions.clone()),
        ("swirl", swirl(&grid.positions, size as f32)),
    ];
    for (name, deformed) in cases {
        let mesh = WarpMesh {
            rest: &grid.positions,
            deformed: &deformed,
            triangles: &grid.triangles,
        };
        let cpu = warp_cpu(&texture, &mesh, size, size, &RasterOptions::default()).expect("cpu");
        let out = gpu.warp(&texture, &mesh, size, size).expect("gpu");
        // Rasterisation rules are the same; filtering precision differs a little
        // (8-bit premultiplied texels and the GPU's sub-texel precision).
        let (share, worst) = compare(&cpu, &out, 3);
        assert!(
            share < 0.01,
            "{name}: {:.3}% of channels differ by more than 3 (largest {worst})",
            share * 100.0
        );
    }
}

#[test]
fn gpu_identity_of_an_opaque_image_is_exact() {
    let gpu = GpuContext::new().expect("a wgpu adapter (run scripts/setup.sh for lavapipe)");
    let size = 128u32;
    let texture = image::RgbaImage::from_fn(size, size, |x, y| {
        image::Rgba([(x * 2) as u8, (y * 2) as u8, ((x * y) % 251) as u8, 255])
    });
    let grid = Grid::new(size as f32, size as f32, 9, 7);
    let mesh = WarpMesh {
        rest: &grid.positions,
        deformed: &grid.positions,
        triangles: &grid.triangles,
    };
    let out = gpu.warp(&texture, &mesh, size, size).expect("gpu");
    let (share, worst) = compare(&texture, &out, 0);
    assert_eq!(share, 0.0, "largest difference {worst}");
}

#[test]
fn gpu_composites_overlapping_parts_as_the_cpu_does() {
    let gpu = GpuContext::new().expect("a wgpu adapter (run scripts/setup.sh for lavapipe)");
    let (s, shift) = (48, 40.0);
    let (texture, rest, deformed, triangles) = support::overlapping_parts(s, shift);
    let mesh = WarpMesh {
        rest: &rest,
        deformed: &deformed,
        triangles: &triangles,
    };
    let out = gpu.warp(&texture, &mesh, 2 * s, s).expect("gpu");
    let cracks = support::cracks(&out, s, shift);
    assert!(
        cracks.is_empty(),
        "{} pixels lost alpha: {:?}",
        cracks.len(),
        &cracks[..cracks.len().min(8)]
    );
    let cpu = warp_cpu(&texture, &mesh, 2 * s, s, &RasterOptions::default()).expect("cpu");
    let (share, worst) = compare(&cpu, &out, 3);
    assert!(
        share < 0.01,
        "{:.3}% of channels differ by more than 3 (largest {worst})",
        share * 100.0
    );
}

#[test]
fn gpu_refuses_bad_input() {
    let gpu = GpuContext::new().expect("a wgpu adapter (run scripts/setup.sh for lavapipe)");
    let texture = gradient_texture(16);
    let rest = [Vec2::ZERO, Vec2::X, Vec2::Y];
    let bad = [Vec2::ZERO, Vec2::new(f32::NAN, 0.0), Vec2::Y];
    let mesh = WarpMesh {
        rest: &rest,
        deformed: &bad,
        triangles: &[[0, 1, 2]],
    };
    assert!(gpu.warp(&texture, &mesh, 16, 16).is_err());
    let mesh = WarpMesh {
        rest: &rest,
        deformed: &rest,
        triangles: &[[0, 1, 5]],
    };
    assert!(gpu.warp(&texture, &mesh, 16, 16).is_err());
    let mesh = WarpMesh {
        rest: &rest,
        deformed: &rest,
        triangles: &[[0, 1, 2]],
    };
    assert!(gpu.warp(&texture, &mesh, 0, 16).is_err());
    assert!(gpu.warp(&texture, &mesh, 1 << 20, 16).is_err());
}

/// Rows of weights over `centres`: each vertex weighs its three nearest centres by
/// inverse distance, normalised.
fn weight_rows(positions: &[Vec2], centres: &[Vec2]) -> (Vec<u32>, Vec<u32>, Vec<f32>) {
    let (mut rows, mut nodes, mut weights) = (vec![0u32], Vec::new(), Vec::new());
    for p in positions {
        let mut near: Vec<(f32, u32)> = centres
            .iter()
            .enumerate()
            .map(|(k, c)| ((*c - *p).length(), k as u32))
            .collect();
        near.sort_by(|a, b| a.0.total_cmp(&b.0));
        let raw: Vec<f32> = near[..3].iter().map(|(d, _)| 1.0 / (d + 1.0)).collect();
        let sum: f32 = raw.iter().sum();
        for (i, (_, k)) in near[..3].iter().enumerate() {
            nodes.push(*k);
            weights.push(raw[i] / sum);
        }
        rows.push(nodes.len() as u32);
    }
    (rows, nodes, weights)
}

#[test]
fn vertex_shader_skinning_matches_blending_on_the_cpu() {
    let gpu = GpuContext::new().expect("a wgpu adapter (run scripts/setup.sh for lavapipe)");
    let size = 256u32;
    let texture = gradient_texture(size);
    let grid = Grid::new(size as f32, size as f32, 20, 20);
    let centres = [
        Vec2::new(40.0, 40.0),
        Vec2::new(200.0, 60.0),
        Vec2::new(128.0, 128.0),
        Vec2::new(60.0, 210.0),
        Vec2::new(220.0, 220.0),
    ];
    // Small rotations, scales and shifts about each centre.
    let transforms: Vec<[f32; 6]> = centres
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let angle = 0.08 * (i as f32 - 2.0);
            let scale = 1.0 + 0.03 * i as f32;
            let a = glam::Mat2::from_angle(angle) * scale;
            let shift = Vec2::new(6.0 - 3.0 * i as f32, 2.0 * i as f32 - 4.0);
            let t = *c + shift - a * *c;
            [a.x_axis.x, a.x_axis.y, a.y_axis.x, a.y_axis.y, t.x, t.y]
        })
        .collect();
    let (rows, nodes, weights) = weight_rows(&grid.positions, &centres);
    let blended: Vec<Vec2> = grid
        .positions
        .iter()
        .enumerate()
        .map(|(v, p)| {
            (rows[v] as usize..rows[v + 1] as usize)
                .map(|i| {
                    let t = transforms[nodes[i] as usize];
                    let q = Vec2::new(t[0], t[1]) * p.x
                        + Vec2::new(t[2], t[3]) * p.y
                        + Vec2::new(t[4], t[5]);
                    weights[i] * q
                })
                .sum()
        })
        .collect();
    let cpu = warp_cpu(
        &texture,
        &WarpMesh {
            rest: &grid.positions,
            deformed: &blended,
            triangles: &grid.triangles,
        },
        size,
        size,
        &RasterOptions::default(),
    )
    .expect("cpu");
    let skinned = render::SkinnedMesh {
        rest: &grid.positions,
        rows: &rows,
        nodes: &nodes,
        weights: &weights,
        triangles: &grid.triangles,
    };
    let out = gpu
        .warp_skinned(&texture, &skinned, &transforms, size, size)
        .expect("gpu");
    let (share, worst) = compare(&cpu, &out, 3);
    assert!(
        share < 0.01,
        "{:.3}% of channels differ by more than 3 (largest {worst})",
        share * 100.0
    );
    // The same rows with a node missing its transform are refused.
    assert!(
        gpu.warp_skinned(&texture, &skinned, &transforms[..2], size, size)
            .is_err()
    );
}
