//! Content finer than the mesh (specks, one-pixel lines, text, faint pixels) is covered,
//! never dropped, at every density, without the outline vertices running away; large
//! pieces keep their exact outlines.

#![allow(clippy::unwrap_used)] // Tests unwrap freely.

use crate::support;

use glam::DVec2;
use image::{Rgba, RgbaImage};
use mesh::{
    Constraints, Domain, DomainOptions, MeshOptions, domain_for_density, domain_from_image,
    triangulate,
};
use support::Locator;

/// Densities from the smallest a project allows to far above the pictures' pixel counts.
const DENSITIES: [usize; 5] = [16, 500, 3_000, 20_000, 200_000];

fn xorshift(state: &mut u64) -> u64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    *state
}

/// `count` specks of 1 to 3 px on a side.
fn specks(w: u32, h: u32, count: usize, seed: u64) -> RgbaImage {
    let mut s = seed;
    let mut img = RgbaImage::new(w, h);
    for _ in 0..count {
        let size = 1 + (xorshift(&mut s) % 3) as u32;
        let x = (xorshift(&mut s) % u64::from(w - size + 1)) as u32;
        let y = (xorshift(&mut s) % u64::from(h - size + 1)) as u32;
        for dy in 0..size {
            for dx in 0..size {
                img.put_pixel(x + dx, y + dy, Rgba([9, 9, 9, 255]));
            }
        }
    }
    img
}

/// One-pixel sine curves and diagonal lines, crossing each other.
fn hair(w: u32, h: u32) -> RgbaImage {
    let mut img = RgbaImage::new(w, h);
    for k in 0..20 {
        let (phase, y0) = (
            f64::from(k) * 0.7,
            f64::from(h) * (0.1 + 0.04 * f64::from(k)),
        );
        for x in 0..w {
            let y = y0 + 12.0 * (f64::from(x) / 17.0 + phase).sin();
            if y >= 0.0 && y < f64::from(h) {
                img.put_pixel(x, y as u32, Rgba([200, 150, 90, 255]));
            }
        }
    }
    for k in 0..w.min(h) {
        img.put_pixel(k, k, Rgba([0, 0, 0, 255]));
        img.put_pixel(w - 1 - k, k, Rgba([0, 0, 0, 255]));
    }
    img
}

/// Rows of 3×5 glyphs of one-pixel strokes, one pixel apart, words three pixels apart.
fn text(w: u32, h: u32, seed: u64) -> RgbaImage {
    let mut s = seed;
    let mut img = RgbaImage::new(w, h);
    for y0 in (2..h.saturating_sub(6)).step_by(8) {
        let mut x0 = 2;
        while x0 + 3 < w {
            let bits = xorshift(&mut s) | 1;
            for k in 0..15 {
                if bits >> k & 1 == 1 {
                    img.put_pixel(x0 + k % 3, y0 + k / 3, Rgba([0, 0, 0, 255]));
                }
            }
            x0 += if xorshift(&mut s).is_multiple_of(5) {
                7
            } else {
                4
            };
        }
    }
    img
}

/// Every other pixel visible, and faint pixels (alpha 1 to 8) scattered beside it.
fn checkerboard_and_faint(seed: u64) -> RgbaImage {
    let mut s = seed;
    RgbaImage::from_fn(180, 120, |x, y| {
        if x < 90 {
            Rgba([255, 255, 255, if (x + y) % 2 == 0 { 255 } else { 0 }])
        } else if xorshift(&mut s).is_multiple_of(9) {
            Rgba([255, 255, 255, 1 + (xorshift(&mut s) % 8) as u8])
        } else {
            Rgba([0, 0, 0, 0])
        }
    })
}

/// A large disc with a one-pixel tail, and a dot far away.
fn tail_and_dot() -> RgbaImage {
    RgbaImage::from_fn(260, 200, |x, y| {
        let c = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
        let disc = c.distance(DVec2::new(90.0, 100.0)) < 60.0;
        let tail = y == 100 && (150..240).contains(&x);
        let dot = (x, y) == (250, 10);
        Rgba([50, 60, 70, if disc || tail || dot { 255 } else { 0 }])
    })
}

/// The pictures, and whether they hold fine content only (no piece the mesh resolves).
fn pictures() -> Vec<(&'static str, RgbaImage, bool)> {
    vec![
        ("400 specks", specks(160, 120, 400, 1), true),
        ("5000 specks", specks(600, 450, 5_000, 2), true),
        ("hair", hair(300, 220), true),
        ("text", text(420, 300, 3), true),
        (
            "checkerboard and faint pixels",
            checkerboard_and_faint(4),
            false,
        ),
        ("tail and dot", tail_and_dot(), false),
    ]
}

fn ring_vertices(d: &Domain) -> usize {
    d.rings().map(<[DVec2]>::len).sum()
}

#[test]
fn every_visible_pixel_is_inside_the_mesh_at_every_density() {
    for (name, img, fine_only) in pictures() {
        let (w, h) = (f64::from(img.width()), f64::from(img.height()));
        for target in DENSITIES {
            let d = domain_for_density(&img, &DomainOptions::default(), target).unwrap();
            let opts = MeshOptions {
                target_vertices: target,
                ..MeshOptions::default()
            };
            let t = triangulate(&d, &Constraints::default(), &opts).unwrap();
            t.mesh.sanity_check().unwrap();
            for v in d.rings().flatten() {
                assert!(
                    v.x >= 0.0 && v.y >= 0.0 && v.x <= w && v.y <= h,
                    "{name}: {v}"
                );
            }
            let loc = Locator::new(&t.mesh);
            for (x, y, p) in img.enumerate_pixels() {
                if p.0[3] > 0 {
                    let c = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
                    assert!(
                        loc.contains(c),
                        "{name} at {target}: pixel ({x}, {y}) dropped"
                    );
                }
            }
            // Fine content's outlines stay within the budget (half the target, at least
            // 1024 vertices), and the mesh near the target or what the outlines need
            // (their vertices, the splits along them and the refinement next to them).
            let rings = ring_vertices(&d);
            let n = t.mesh.vertices.len();
            if fine_only {
                assert!(
                    rings <= (target / 2).max(1024),
                    "{name} at {target}: {rings} outline vertices"
                );
            }
            assert!(
                n as f64 <= 1.3 * target as f64 + 4.0 * rings as f64 + 64.0,
                "{name} at {target}: {n} vertices, {rings} on the outlines"
            );
        }
    }
}

/// Thousands of specks at a low density: a few cover polygons instead of thousands of
/// squares; at a high one, every speck on its own.
#[test]
fn specks_merge_at_low_density_and_stay_apart_at_high_density() {
    let img = specks(600, 450, 3_000, 9);
    let low = domain_for_density(&img, &DomainOptions::default(), 500).unwrap();
    assert!(low.polygons.len() < 20, "{} polygons", low.polygons.len());
    assert!(ring_vertices(&low) <= 1024);
    let high = domain_for_density(&img, &DomainOptions::default(), 1_000_000).unwrap();
    assert!(
        high.polygons.len() > 1_000,
        "{} polygons",
        high.polygons.len()
    );
    // Exact outlines: each speck's square with its one-pixel margin.
    assert!(high.area() < 0.2 * 600.0 * 450.0, "area {}", high.area());
}

/// A large shape keeps its exact outline when specks far from it are covered.
#[test]
fn large_pieces_keep_their_exact_outline() {
    let (w, h) = (500u32, 300u32);
    let disc = |x: u32, y: u32| {
        DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5).distance(DVec2::new(100.0, 150.0)) < 80.0
    };
    let alone = RgbaImage::from_fn(w, h, |x, y| {
        Rgba([1, 2, 3, if disc(x, y) { 255 } else { 0 }])
    });
    let dusty = specks(w, h, 2_000, 5);
    let with_specks = RgbaImage::from_fn(w, h, |x, y| {
        if disc(x, y) || (x > 260 && dusty.get_pixel(x, y).0[3] > 0) {
            Rgba([1, 2, 3, 255])
        } else {
            Rgba([0, 0, 0, 0])
        }
    });
    for target in [500, 3_000] {
        let a = domain_for_density(&alone, &DomainOptions::default(), target).unwrap();
        let b = domain_for_density(&with_specks, &DomainOptions::default(), target).unwrap();
        assert!(b.polygons.len() < 50, "the specks are covered");
        let centre = DVec2::new(100.0, 150.0);
        let inside = |d: &Domain| {
            d.polygons
                .iter()
                .find(|p| {
                    Domain {
                        polygons: vec![(*p).clone()],
                        ..d.clone()
                    }
                    .contains(centre)
                })
                .cloned()
                .unwrap()
        };
        assert_eq!(
            inside(&a),
            inside(&b),
            "the disc's outline changed at {target}"
        );
    }
}

/// The built-in lizard: one piece, its exact outline at every density (its legs nearly
/// touch and stay apart), and within a hair of the outline of its pixels with alpha > 8.
#[test]
fn the_lizard_keeps_its_outline_at_every_density() {
    let lizard = image::load_from_memory(include_bytes!("../../../assets/lizard.png"))
        .unwrap()
        .to_rgba8();
    let d = domain_from_image(&lizard, &DomainOptions::default()).unwrap();
    assert_eq!(d.polygons.len(), 1);
    for target in [16, 500, 600_000] {
        assert_eq!(
            domain_for_density(&lizard, &DomainOptions::default(), target).unwrap(),
            d
        );
    }
    let faint_out = DomainOptions {
        alpha_threshold: 8,
        ..DomainOptions::default()
    };
    let strong = domain_from_image(&lizard, &faint_out).unwrap();
    assert_eq!(strong.polygons.len(), 1);
    assert!((d.area() / strong.area() - 1.0).abs() < 0.01);
    let (n, m) = (ring_vertices(&d) as f64, ring_vertices(&strong) as f64);
    assert!((n / m - 1.0).abs() < 0.05, "{n} vs {m} outline vertices");
}

/// Points on specks that used to be dropped, and between covered specks, are accepted as
/// mesh vertices.
#[test]
fn handles_on_covered_content_are_accepted() {
    let img = specks(400, 300, 2_500, 21);
    let d = domain_for_density(&img, &DomainOptions::default(), 500).unwrap();
    let mut points: Vec<DVec2> = img
        .enumerate_pixels()
        .filter(|(_, _, p)| p.0[3] > 0)
        .step_by(97)
        .map(|(x, y, _)| DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5))
        .collect();
    points.dedup();
    // A transparent pixel the cover took in.
    let gap = img
        .enumerate_pixels()
        .map(|(x, y, _)| DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5))
        .find(|&c| img.get_pixel(c.x as u32, c.y as u32).0[3] == 0 && d.contains(c) && c.x > 50.0)
        .unwrap();
    points.push(gap);
    let opts = MeshOptions {
        target_vertices: 500,
        ..MeshOptions::default()
    };
    let c = Constraints {
        points: &points,
        polylines: &[],
    };
    let t = triangulate(&d, &c, &opts).unwrap();
    t.mesh.sanity_check().unwrap();
    for (p, &v) in points.iter().zip(&t.point_vertices) {
        assert_eq!(t.mesh.vertices[v as usize], *p);
    }
}
