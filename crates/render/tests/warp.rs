//! Behaviour of `warp_cpu` and `coverage_counts` on whole meshes.

use crate::support;

use glam::Vec2;
use image::{Rgba, RgbaImage};
use render::{RasterOptions, RenderError, WarpMesh, coverage_counts, warp_cpu};
use support::{Grid, random_image};

fn warp(
    texture: &RgbaImage,
    rest: &[Vec2],
    deformed: &[Vec2],
    triangles: &[[u32; 3]],
    size: (u32, u32),
    background: [u8; 4],
) -> RgbaImage {
    let mesh = WarpMesh {
        rest,
        deformed,
        triangles,
    };
    warp_cpu(
        texture,
        &mesh,
        size.0,
        size.1,
        &RasterOptions { background },
    )
    .expect("warp succeeds")
}

#[test]
fn identity_on_a_whole_pixel_grid_is_byte_exact() {
    let image = random_image(67, 43, 1);
    let grid = Grid::new(67.0, 43.0, 67, 43);
    let out = warp(
        &image,
        &grid.positions,
        &grid.positions,
        &grid.triangles,
        (67, 43),
        [9, 9, 9, 9],
    );
    assert!(out == image, "identity warp changed the image");
}

#[test]
fn identity_on_fractional_and_jittered_grids_is_byte_exact() {
    let image = random_image(101, 77, 2);
    for (cols, rows, seed) in [(7, 5, 3), (13, 11, 4), (40, 31, 5)] {
        let mut grid = Grid::new(101.0, 77.0, cols, rows);
        let cell = Vec2::new(101.0 / cols as f32, 77.0 / rows as f32);
        // Arbitrary (not 1/256-aligned) interior positions.
        grid.jitter(0.3, 1e-6, seed, cell);
        let out = warp(
            &image,
            &grid.positions,
            &grid.positions,
            &grid.triangles,
            (101, 77),
            [9, 9, 9, 9],
        );
        assert!(
            out == image,
            "identity warp changed the image ({cols}x{rows} grid)"
        );
    }
}

#[test]
fn integer_translation_shifts_exactly() {
    let image = random_image(40, 30, 6);
    let grid = Grid::new(40.0, 30.0, 8, 6);
    let (dx, dy) = (3i64, -2i64);
    let shifted: Vec<Vec2> = grid
        .positions
        .iter()
        .map(|p| *p + Vec2::new(dx as f32, dy as f32))
        .collect();
    let background = [1, 2, 3, 4];
    let out = warp(
        &image,
        &grid.positions,
        &shifted,
        &grid.triangles,
        (40, 30),
        background,
    );
    for (x, y, px) in out.enumerate_pixels() {
        let (sx, sy) = (i64::from(x) - dx, i64::from(y) - dy);
        let expected = if (0..40).contains(&sx) && (0..30).contains(&sy) {
            image.get_pixel(sx as u32, sy as u32).0
        } else {
            background
        };
        assert_eq!(px.0, expected, "pixel ({x}, {y})");
    }
}

#[test]
fn scaling_a_checkerboard_by_two_keeps_cells() {
    const CELL: u32 = 4;
    let black = [0, 0, 0, 255];
    let white = [255, 255, 255, 255];
    let colour = |cx: u32, cy: u32| {
        if (cx + cy).is_multiple_of(2) {
            black
        } else {
            white
        }
    };
    let texture = RgbaImage::from_fn(32, 32, |x, y| Rgba(colour(x / CELL, y / CELL)));
    let grid = Grid::new(32.0, 32.0, 5, 3);
    let scaled: Vec<Vec2> = grid.positions.iter().map(|p| *p * 2.0).collect();
    let out = warp(
        &texture,
        &grid.positions,
        &scaled,
        &grid.triangles,
        (64, 64),
        [0; 4],
    );
    let out_cell = 2 * CELL;
    let mut checked = 0;
    for (x, y, px) in out.enumerate_pixels() {
        // Away from cell edges the bilinear footprint stays inside one cell.
        let (ix, iy) = (x % out_cell, y % out_cell);
        if ix == 0 || iy == 0 || ix == out_cell - 1 || iy == out_cell - 1 {
            continue;
        }
        assert_eq!(px.0, colour(x / out_cell, y / out_cell), "pixel ({x}, {y})");
        checked += 1;
    }
    assert_eq!(checked, 64 * 64 * 36 / 64);
}

#[test]
fn horizontal_mirror_is_exact_and_draws_flipped_triangles() {
    let image = random_image(50, 20, 7);
    let grid = Grid::new(50.0, 20.0, 10, 4);
    let mirrored: Vec<Vec2> = grid
        .positions
        .iter()
        .map(|p| Vec2::new(50.0 - p.x, p.y))
        .collect();
    let out = warp(
        &image,
        &grid.positions,
        &mirrored,
        &grid.triangles,
        (50, 20),
        [0; 4],
    );
    for (x, y, px) in out.enumerate_pixels() {
        assert_eq!(px.0, image.get_pixel(49 - x, y).0, "pixel ({x}, {y})");
    }
}

/// Pixels on many edges and vertices: vertices on multiples of 1/2 pixel
/// (pixel centres and corners) and 1/8 pixel.
fn awkward_grids() -> Vec<Grid> {
    let mut grids = Vec::new();
    for (cols, rows, quantum, seed) in [
        (16, 12, 0.5, 10),
        (33, 29, 0.125, 11),
        (32, 24, 0.5, 12),
        (9, 7, 1.0, 13),
    ] {
        let mut grid = Grid::new(64.0, 48.0, cols, rows);
        let cell = Vec2::new(64.0 / cols as f32, 48.0 / rows as f32);
        grid.jitter(0.2, quantum, seed, cell);
        // The jittered grid must still tile the rectangle.
        for t in &grid.triangles {
            let [a, b, c] = t.map(|i| grid.positions[i as usize].as_dvec2());
            assert!((b - a).perp_dot(c - a) > 0.0, "test grid folds over");
        }
        grids.push(grid);
    }
    // A fan of 24 triangles around a vertex exactly on a pixel centre.
    let centre = Vec2::new(20.5, 20.5);
    let mut positions = vec![centre];
    let ring: Vec<Vec2> = (0..24)
        .map(|k| {
            let angle = k as f32 / 24.0 * std::f32::consts::TAU;
            let p = centre + 30.0 * Vec2::new(angle.cos(), angle.sin());
            (p * 2.0).round() / 2.0
        })
        .collect();
    positions.extend(&ring);
    let triangles = (0..24u32).map(|k| [0, 1 + k, 1 + (k + 1) % 24]).collect();
    grids.push(Grid {
        positions,
        triangles,
        cols: 0,
        rows: 0,
    });
    grids
}

#[test]
fn fill_rule_covers_every_pixel_exactly_once() {
    for (g, grid) in awkward_grids().iter().enumerate() {
        let mesh = WarpMesh {
            rest: &grid.positions,
            deformed: &grid.positions,
            triangles: &grid.triangles,
        };
        let counts = coverage_counts(&mesh, 64, 48).expect("coverage");
        if grid.cols == 0 {
            // The fan covers a disc: no pixel twice, its centre once.
            assert!(counts.iter().all(|&c| c <= 1), "fan covers a pixel twice");
            assert_eq!(counts[20 * 64 + 20], 1);
            assert!(counts.iter().filter(|&&c| c == 1).count() > 2000);
        } else {
            for (i, &c) in counts.iter().enumerate() {
                assert_eq!(
                    c,
                    1,
                    "grid {g}: pixel ({}, {}) covered {c} times",
                    i % 64,
                    i / 64
                );
            }
        }
    }
}

#[test]
fn opaque_texture_leaves_no_gap() {
    let texture = RgbaImage::from_pixel(64, 48, Rgba([10, 200, 30, 255]));
    for grid in awkward_grids().iter().filter(|g| g.cols > 0) {
        let out = warp(
            &texture,
            &grid.positions,
            &grid.positions,
            &grid.triangles,
            (64, 48),
            [0; 4],
        );
        assert!(out.pixels().all(|p| p.0 == [10, 200, 30, 255]));
    }
}

#[test]
fn premultiplied_filtering_gives_no_dark_fringe() {
    let texture = RgbaImage::from_fn(2, 1, |x, _| {
        if x == 0 {
            Rgba([255, 0, 0, 255])
        } else {
            Rgba([0, 0, 0, 0])
        }
    });
    // The output pixel centre (0.5, 0.5) maps to (1.0, 0.5): half-way between texel centres.
    let rest = [
        Vec2::new(0.5, 0.0),
        Vec2::new(1.5, 0.0),
        Vec2::new(1.5, 1.0),
        Vec2::new(0.5, 1.0),
    ];
    let deformed = [
        Vec2::new(0.0, 0.0),
        Vec2::new(1.0, 0.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(0.0, 1.0),
    ];
    let out = warp(
        &texture,
        &rest,
        &deformed,
        &[[0, 1, 2], [0, 2, 3]],
        (1, 1),
        [0; 4],
    );
    assert_eq!(out.get_pixel(0, 0).0, [255, 0, 0, 128]);
}

#[test]
fn later_triangle_wins_and_fold_overs_are_drawn() {
    // Left half red, right half blue.
    let texture = RgbaImage::from_fn(2, 1, |x, _| {
        if x == 0 {
            Rgba([255, 0, 0, 255])
        } else {
            Rgba([0, 0, 255, 255])
        }
    });
    // Each triangle reads one texel centre only (the rest triangles are points).
    let red = [Vec2::new(0.5, 0.5); 3];
    let blue = [Vec2::new(1.5, 0.5); 3];
    let mut rest = red.to_vec();
    rest.extend(blue);
    let big = [
        Vec2::new(0.0, 0.0),
        Vec2::new(16.0, 0.0),
        Vec2::new(0.0, 16.0),
    ];
    // The second (blue) triangle is the first mirrored: a fold-over.
    let mut deformed = big.to_vec();
    deformed.extend(big.map(|p| Vec2::new(p.y, p.x)));
    let out = warp(
        &texture,
        &rest,
        &deformed,
        &[[0, 1, 2], [3, 4, 5]],
        (16, 16),
        [0; 4],
    );
    assert_eq!(out.get_pixel(2, 2).0, [0, 0, 255, 255]);
    let out = warp(
        &texture,
        &rest,
        &deformed,
        &[[3, 4, 5], [0, 1, 2]],
        (16, 16),
        [0; 4],
    );
    assert_eq!(out.get_pixel(2, 2).0, [255, 0, 0, 255]);
    assert_eq!(out.get_pixel(15, 15).0, [0, 0, 0, 0]);
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let texture = RgbaImage::from_pixel(4, 4, Rgba([1, 2, 3, 4]));
    let rest = [Vec2::ZERO, Vec2::new(4.0, 0.0), Vec2::new(0.0, 4.0)];
    let opts = RasterOptions::default();
    let mesh = |deformed, triangles| WarpMesh {
        rest: &rest,
        deformed,
        triangles,
    };

    let nan = [Vec2::ZERO, Vec2::new(f32::NAN, 0.0), Vec2::Y];
    let err = warp_cpu(&texture, &mesh(&nan, &[[0, 1, 2]]), 4, 4, &opts).expect_err("must fail");
    assert!(
        matches!(err, RenderError::NonFinitePosition { vertex: 1, .. }),
        "{err}"
    );

    let inf = [Vec2::ZERO, Vec2::X, Vec2::new(0.0, f32::INFINITY)];
    assert!(warp_cpu(&texture, &mesh(&inf, &[]), 4, 4, &opts).is_err());

    let err = warp_cpu(&texture, &mesh(&rest, &[[0, 1, 7]]), 4, 4, &opts).expect_err("must fail");
    assert!(
        matches!(err, RenderError::MeshIndexOutOfRange { index: 7, .. }),
        "{err}"
    );
    assert!(err.to_string().contains("vertex 7"));

    let err = warp_cpu(&texture, &mesh(&rest[..2], &[]), 4, 4, &opts).expect_err("must fail");
    assert!(
        matches!(err, RenderError::MeshLengthMismatch { .. }),
        "{err}"
    );

    let empty = RgbaImage::new(0, 3);
    let err = warp_cpu(&empty, &mesh(&rest, &[[0, 1, 2]]), 4, 4, &opts).expect_err("must fail");
    assert!(matches!(err, RenderError::EmptyTexture { .. }), "{err}");

    let err = warp_cpu(
        &texture,
        &mesh(&rest, &[[0, 1, 2]]),
        u32::MAX,
        u32::MAX,
        &opts,
    )
    .expect_err("must fail");
    assert!(matches!(err, RenderError::OutputTooLarge { .. }), "{err}");
}

#[test]
fn degenerate_and_empty_cases_have_defined_answers() {
    let texture = RgbaImage::from_pixel(4, 4, Rgba([1, 2, 3, 255]));
    let rest = [
        Vec2::ZERO,
        Vec2::new(4.0, 4.0),
        Vec2::new(8.0, 8.0),
        Vec2::new(1e30, -1e30),
    ];
    // Zero-area triangles are skipped.
    let out = warp(
        &texture,
        &rest,
        &rest,
        &[[0, 1, 2], [0, 0, 0]],
        (4, 4),
        [7, 7, 7, 7],
    );
    assert!(out.pixels().all(|p| p.0 == [7, 7, 7, 7]));
    // Zero-sized outputs are fine.
    let out = warp(&texture, &rest, &rest, &[[0, 1, 3]], (0, 5), [0; 4]);
    assert_eq!(out.dimensions(), (0, 5));
    // Far-away vertices are clamped, not overflowed.
    let out = warp(
        &texture,
        &rest,
        &rest,
        &[[0, 1, 3], [3, 1, 0]],
        (4, 4),
        [0; 4],
    );
    assert_eq!(out.dimensions(), (4, 4));
}

#[test]
fn parallel_bands_match_a_single_thread() {
    let image = random_image(96, 200, 20);
    let mut grid = Grid::new(96.0, 200.0, 12, 25);
    let rest = grid.positions.clone();
    grid.jitter(0.45, 0.01, 21, Vec2::new(8.0, 8.0)); // may fold over
    let mesh = WarpMesh {
        rest: &rest,
        deformed: &grid.positions,
        triangles: &grid.triangles,
    };
    let opts = RasterOptions::default();
    let parallel = warp_cpu(&image, &mesh, 96, 200, &opts).expect("warp");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let serial = pool
        .install(|| warp_cpu(&image, &mesh, 96, 200, &opts))
        .expect("warp");
    assert!(parallel == serial);
}

#[test]
fn fill_rule_holds_on_many_random_grids() {
    let mut rng = support::Rng::new(99);
    let mut tested = 0;
    for seed in 0..60 {
        let cols = 3 + (rng.next_u64() % 40) as u32;
        let rows = 3 + (rng.next_u64() % 30) as u32;
        let quantum = [1.0, 0.5, 0.25, 1.0 / 256.0, 1e-3][seed as usize % 5];
        let (w, h) = (53.0, 41.0);
        let mut grid = Grid::new(w, h, cols, rows);
        grid.jitter(
            0.25,
            quantum,
            seed,
            Vec2::new(w / cols as f32, h / rows as f32),
        );
        let valid = grid.triangles.iter().all(|t| {
            let [a, b, c] = t.map(|i| grid.positions[i as usize].as_dvec2());
            (b - a).perp_dot(c - a) > 0.0
        });
        if !valid {
            continue;
        }
        tested += 1;
        let mesh = WarpMesh {
            rest: &grid.positions,
            deformed: &grid.positions,
            triangles: &grid.triangles,
        };
        let counts = coverage_counts(&mesh, 53, 41).expect("coverage");
        if let Some(i) = counts.iter().position(|&c| c != 1) {
            panic!(
                "seed {seed}: pixel ({}, {}) covered {} times",
                i % 53,
                i / 53,
                counts[i]
            );
        }
    }
    assert!(tested > 30, "only {tested} grids were valid");
}

#[test]
fn wild_but_valid_meshes_never_panic() {
    let mut rng = support::Rng::new(7);
    let texture = random_image(5, 3, 8);
    let scales = [1e-30f32, 1e-3, 1.0, 10.0, 1e4, 1e7, 1e20, 3e38];
    let value = |rng: &mut support::Rng| {
        let scale = scales[(rng.next_u64() % scales.len() as u64) as usize];
        rng.range(-1.0, 1.0) * scale + rng.range(0.0, 12.0)
    };
    for round in 0..300 {
        let n = 3 + (rng.next_u64() % 6) as usize;
        let rest: Vec<Vec2> = (0..n)
            .map(|_| Vec2::new(value(&mut rng), value(&mut rng)))
            .collect();
        let deformed: Vec<Vec2> = (0..n)
            .map(|_| Vec2::new(value(&mut rng), value(&mut rng)))
            .collect();
        let triangles: Vec<[u32; 3]> = (0..4)
            .map(|_| [0, 1, 2].map(|_| (rng.next_u64() % n as u64) as u32))
            .collect();
        let mesh = WarpMesh {
            rest: &rest,
            deformed: &deformed,
            triangles: &triangles,
        };
        let (w, h) = (
            1 + (rng.next_u64() % 12) as u32,
            1 + (rng.next_u64() % 12) as u32,
        );
        let out = warp_cpu(&texture, &mesh, w, h, &RasterOptions::default());
        assert!(out.is_ok(), "round {round}: {:?}", out.err());
        let counts = coverage_counts(&mesh, w, h).expect("coverage");
        assert_eq!(counts.len(), (w * h) as usize);
    }
}

/// `image` widened to 16 bits per channel, with low bits that 8 bits cannot hold.
fn widen(image: &RgbaImage) -> render::Rgba16Image {
    render::Rgba16Image::from_fn(image.width(), image.height(), |x, y| {
        let p = image.get_pixel(x, y).0;
        let fine = |c: u8| (u16::from(c) * 257).saturating_sub(((x * 31 + y * 17) % 97) as u16);
        Rgba([fine(p[0]), fine(p[1]), fine(p[2]), fine(p[3])])
    })
}

#[test]
fn sixteen_bit_pictures_warp_in_sixteen_bits() {
    let image = random_image(61, 47, 11);
    let wide = widen(&image);
    let mut grid = Grid::new(61.0, 47.0, 9, 7);
    grid.jitter(0.3, 1e-6, 12, Vec2::new(61.0 / 9.0, 47.0 / 7.0));
    let mesh = |deformed: &[Vec2]| -> (Vec<Vec2>, Vec<Vec2>) {
        (grid.positions.clone(), deformed.to_vec())
    };
    let opts = RasterOptions {
        background: [1, 2, 3, 4],
    };
    // At rest, 16 bits come back exactly (8 bits could not hold them).
    let (rest, deformed) = mesh(&grid.positions);
    let warp_mesh = WarpMesh {
        rest: &rest,
        deformed: &deformed,
        triangles: &grid.triangles,
    };
    let out = render::warp_picture(
        &render::Picture::Rgba16(wide.clone()),
        &warp_mesh,
        61,
        47,
        &opts,
    )
    .expect("warp");
    assert_eq!(out, render::Picture::Rgba16(wide.clone()));

    // Swirled, the 16-bit result rounded to 8 bits is the 8-bit result within a
    // level or two (the two filter the same positions at different precision), and
    // an 8-bit picture goes through `warp_picture` exactly as through `warp_cpu`.
    let swirled = support::swirl(&grid.positions, 47.0);
    let (rest, deformed) = mesh(&swirled);
    let warp_mesh = WarpMesh {
        rest: &rest,
        deformed: &deformed,
        triangles: &grid.triangles,
    };
    let narrow16 = render::Picture::Rgba16(wide.clone()).into_rgba8();
    let eight = warp_cpu(&narrow16, &warp_mesh, 70, 50, &opts).expect("warp 8");
    let via_picture = render::warp_picture(
        &render::Picture::Rgba8(narrow16.clone()),
        &warp_mesh,
        70,
        50,
        &opts,
    )
    .expect("warp picture 8");
    assert_eq!(via_picture, render::Picture::Rgba8(eight.clone()));
    let sixteen = render::warp_picture(&render::Picture::Rgba16(wide), &warp_mesh, 70, 50, &opts)
        .expect("warp 16");
    let render::Picture::Rgba16(sixteen) = sixteen else {
        panic!("a 16-bit picture warps to a 16-bit picture");
    };
    assert_eq!(
        sixteen.get_pixel(69, 49).0,
        [257, 514, 771, 1028],
        "background"
    );
    let rounded = render::Picture::Rgba16(sixteen).into_rgba8();
    // Alpha agrees within a level; colour too where alpha is not so low that
    // un-premultiplying magnifies the rounding of 8-bit filtering.
    for (a, b) in rounded.pixels().zip(eight.pixels()) {
        assert!(a[3].abs_diff(b[3]) <= 1, "{a:?} vs {b:?}");
        if b[3] >= 64 {
            for k in 0..3 {
                assert!(a[k].abs_diff(b[k]) <= 2, "{a:?} vs {b:?}");
            }
        }
    }
}

#[test]
fn overlapping_opaque_parts_keep_their_alpha() {
    // The part in front has a transparent margin and an anti-aliased rim: drawn over
    // the part behind, they must let it show through, not cut a crack into it.
    let (s, shift) = (48, 40.0);
    let (texture, rest, deformed, triangles) = support::overlapping_parts(s, shift);
    let out = warp(&texture, &rest, &deformed, &triangles, (2 * s, s), [0; 4]);
    let cracks = support::cracks(&out, s, shift);
    assert!(
        cracks.is_empty(),
        "{} pixels lost alpha: {:?}",
        cracks.len(),
        &cracks[..cracks.len().min(8)]
    );
    // Where the front disc's rim lies over the back disc, both colours mix.
    let rim = out
        .enumerate_pixels()
        .filter(|(_, _, p)| p[0] > 40 && p[2] > 60 && p[3] == 255)
        .count();
    assert!(
        rim > 0,
        "the front disc's rim shows the back disc through it"
    );
    // Where nothing overlaps, the picture is drawn as before: the left disc alone,
    // away from the other, is exactly its texels.
    assert_eq!(out.get_pixel(4, s / 2), texture.get_pixel(4, s / 2));
    assert_eq!(out.get_pixel(s / 4, s / 2), texture.get_pixel(s / 4, s / 2));
}

#[test]
fn a_background_fills_only_what_nothing_covers() {
    let (s, shift) = (32, 20.0);
    let (texture, rest, deformed, triangles) = support::overlapping_parts(s, shift);
    let background = [9, 8, 7, 6];
    let out = warp(
        &texture,
        &rest,
        &deformed,
        &triangles,
        (2 * s, s),
        background,
    );
    // The right part moved left: its old place at the right edge is uncovered.
    assert_eq!(out.get_pixel(2 * s - 1, 0).0, background);
    // A transparent texel of the mesh keeps its own value, not the background.
    assert_eq!(out.get_pixel(0, 0), texture.get_pixel(0, 0));
    assert!(support::cracks(&out, s, shift).is_empty());
}

#[test]
fn warp_over_keeps_what_it_does_not_cover_and_composites_the_rest() {
    let (s, shift) = (32, 20.0);
    let (texture, rest, deformed, triangles) = support::overlapping_parts(s, shift);
    let mesh = WarpMesh {
        rest: &rest,
        deformed: &deformed,
        triangles: &triangles,
    };
    let alone = warp(&texture, &rest, &deformed, &triangles, (2 * s, s), [0; 4]);
    // Over a transparent picture whose colours differ: the same as drawing alone where
    // drawn, the picture's own pixels where not.
    let mut target = RgbaImage::from_fn(2 * s, s, |x, y| Rgba([x as u8, y as u8, 7, 0]));
    let before = target.clone();
    render::warp_over(&texture, &mesh, &mut target).expect("warp");
    let counts = coverage_counts(&mesh, 2 * s, s).expect("coverage");
    for (i, (x, y, p)) in target.enumerate_pixels().enumerate() {
        if counts[i] == 0 {
            assert_eq!(p, before.get_pixel(x, y));
        } else {
            assert_eq!(p, alone.get_pixel(x, y));
        }
    }
    // Over an opaque picture, everything stays opaque.
    let mut opaque = RgbaImage::from_pixel(2 * s, s, Rgba([9, 9, 9, 255]));
    render::warp_over(&texture, &mesh, &mut opaque).expect("warp");
    assert!(opaque.pixels().all(|p| p[3] == 255));
}

#[test]
fn a_picture_cleared_where_a_mesh_covers_it_comes_back_when_the_mesh_is_drawn_at_rest() {
    let image = random_image(40, 30, 5);
    let wide = render::Picture::Rgba16(widen(&image));
    // A mesh over part of the picture only: its left two thirds.
    let grid = Grid::new(26.0, 30.0, 4, 3);
    let mesh = WarpMesh {
        rest: &grid.positions,
        deformed: &grid.positions,
        triangles: &grid.triangles,
    };
    for picture in [render::Picture::Rgba8(image.clone()), wide] {
        let mut cleared = picture.clone();
        render::clear_covered(&mut cleared, &mesh).expect("clear");
        let counts = coverage_counts(&mesh, 40, 30).expect("coverage");
        let narrow = cleared.to_rgba8();
        for (i, p) in narrow.pixels().enumerate() {
            let (x, y) = (i as u32 % 40, i as u32 / 40);
            if counts[i] > 0 {
                assert_eq!(p.0, [0; 4], "({x}, {y}) is cleared");
            } else {
                assert_eq!(p, image.get_pixel(x, y), "({x}, {y}) is kept");
            }
        }
        assert!(counts.contains(&0) && counts.iter().any(|&c| c > 0));
        // Drawn back at rest over the cleared picture: exactly the picture, in its
        // own depth.
        render::warp_picture_over(&picture, &mesh, &mut cleared).expect("warp");
        assert_eq!(cleared, picture);
    }
    // Depths must agree.
    let mut narrow = render::Picture::Rgba8(image.clone());
    let err =
        render::warp_picture_over(&render::Picture::Rgba16(widen(&image)), &mesh, &mut narrow)
            .expect_err("16 over 8");
    assert!(
        matches!(
            err,
            RenderError::DepthMismatch {
                texture: 16,
                target: 8
            }
        ),
        "{err}"
    );
}
