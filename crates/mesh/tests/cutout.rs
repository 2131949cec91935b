//! Cut-out images: the mesh follows the alpha outline, covers every opaque pixel and
//! respects holes.

#![allow(clippy::unwrap_used)] // Tests unwrap freely.

use crate::support;

use glam::DVec2;
use mesh::{
    Constraints, DomainOptions, MeshError, MeshOptions, domain_for_density, domain_from_image,
    mesh_image, triangulate,
};
use proptest::prelude::*;
use support::{
    Locator, disc_with_hole_and_island, disc_with_hole_and_island_scaled,
    in_disc_with_hole_and_island,
};

#[test]
fn disc_with_hole_and_island_meshes_well() {
    let img = disc_with_hole_and_island_scaled(2);
    let domain = domain_from_image(&img, &DomainOptions::default()).unwrap();
    assert!(!domain.is_full_rectangle);
    assert_eq!(domain.polygons.len(), 2);
    let holes: usize = domain.polygons.iter().map(|p| p.holes.len()).sum();
    assert_eq!(holes, 1);

    let opts = MeshOptions {
        target_vertices: 12_000,
        ..Default::default()
    };
    let t = triangulate(&domain, &Constraints::default(), &opts).unwrap();
    assert!(!t.is_convex);
    t.mesh.sanity_check().unwrap();
    let n = t.mesh.vertices.len() as f64;
    assert!((n / 12_000.0 - 1.0).abs() < 0.3, "{n} vertices");

    // Area: the alpha area plus the one-pixel outward margin (about perimeter × 1 px,
    // 3.4% here).
    let alpha_area = img.pixels().filter(|p| p.0[3] > 8).count() as f64;
    let area = t.mesh.area();
    assert!((area - domain.area()).abs() < 1e-6 * area);
    assert!(area > alpha_area, "{area} vs {alpha_area}");
    assert!(
        area < alpha_area * 1.06,
        "mesh area {area}, alpha area {alpha_area}"
    );

    // Every opaque pixel centre is inside the mesh.
    let loc = Locator::new(&t.mesh);
    for (x, y, p) in img.enumerate_pixels() {
        if p.0[3] > 8 {
            let c = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
            assert!(loc.contains(c), "opaque pixel ({x}, {y}) is not covered");
        }
    }
    // No triangle lies far from the opaque pixels: every centroid is within 2 px of one.
    let opaque = |x: i64, y: i64| {
        x >= 0 && y >= 0 && x < 400 && y < 320 && img.get_pixel(x as u32, y as u32).0[3] > 8
    };
    for k in 0..t.mesh.triangles.len() {
        let [a, b, c] = t.mesh.triangle_positions(k);
        let g = (a + b + c) / 3.0;
        let near = (-3i64..=3).any(|dy| {
            (-3i64..=3).any(|dx| {
                let (px, py) = (g.x.floor() as i64 + dx, g.y.floor() as i64 + dy);
                let centre = DVec2::new(px as f64 + 0.5, py as f64 + 0.5);
                opaque(px, py) && centre.distance(g) <= 2.0 + 0.71
            })
        });
        assert!(near, "triangle {k} centroid {g} is far from the shape");
    }
    // The hole is a hole, and the gap between the components stays empty.
    assert!(!loc.contains(DVec2::new(160.0, 160.0)));
    assert!(!loc.contains(DVec2::new(301.0, 121.0)));
    assert!(!loc.contains(DVec2::new(10.0, 10.0)));
    assert!(in_disc_with_hole_and_island(DVec2::new(170.0, 40.0)));
    assert!(loc.contains(DVec2::new(340.0, 80.0)));
    // Hole: the mesh has a hole ring around the square hole, 1 px in from its edges.
    let hole = domain
        .polygons
        .iter()
        .flat_map(|p| &p.holes)
        .next()
        .unwrap();
    for v in hole {
        assert!(
            (v.x - 160.0).abs() <= 30.0 && (v.y - 160.0).abs() <= 30.0,
            "hole vertex {v}"
        );
    }
}

#[test]
fn rings_are_oriented_and_disjoint() {
    let img = disc_with_hole_and_island();
    let domain = domain_from_image(&img, &DomainOptions::default()).unwrap();
    let signed = |r: &[DVec2]| {
        0.5 * (0..r.len())
            .map(|i| r[i].perp_dot(r[(i + 1) % r.len()]))
            .sum::<f64>()
    };
    for p in &domain.polygons {
        assert!(signed(&p.outer) > 0.0);
        for h in &p.holes {
            assert!(signed(h) < 0.0);
        }
    }
    // Every ring vertex lies in the image rectangle.
    for r in domain.rings() {
        for v in r {
            assert!(v.x >= 0.0 && v.y >= 0.0 && v.x <= 200.0 && v.y <= 160.0);
        }
    }
}

#[test]
fn small_islands_are_kept_and_small_holes_filled() {
    let img = support::image_from(100, 100, |p| {
        let big = (p.x - 50.0).abs() < 30.0 && (p.y - 50.0).abs() < 30.0;
        // 5 × 5 pixels; 3 × 3 once the shape is dilated.
        let pinhole = (p.x - 40.0).abs() < 2.5 && (p.y - 40.0).abs() < 2.5;
        let speck = (p.x - 95.5).abs() < 1.0 && (p.y - 95.5).abs() < 1.0;
        (big && !pinhole) || speck
    });
    let d = domain_from_image(&img, &DomainOptions::default()).unwrap();
    assert_eq!(d.polygons.len(), 2, "the one-pixel speck is kept");
    assert!(d.polygons.iter().all(|p| p.holes.is_empty()));
    assert!(d.contains(DVec2::new(95.5, 95.5)));
    let keep_holes = DomainOptions {
        min_hole_area: 0.0,
        ..Default::default()
    };
    let d = domain_from_image(&img, &keep_holes).unwrap();
    assert_eq!(d.polygons.len(), 2);
    assert_eq!(d.polygons.iter().map(|p| p.holes.len()).sum::<usize>(), 1);
}

#[test]
fn soft_edges_are_inside() {
    // Anti-aliased disc: every pixel with alpha above the threshold is covered.
    let img = image::RgbaImage::from_fn(64, 64, |x, y| {
        let d = DVec2::new(x as f64 + 0.5, y as f64 + 0.5).distance(DVec2::splat(32.0));
        let a = ((20.0 - d + 0.5).clamp(0.0, 1.0) * 255.0) as u8;
        image::Rgba([255, 255, 255, a])
    });
    let t = mesh_image(
        &img,
        &DomainOptions::default(),
        &MeshOptions {
            target_vertices: 1_000,
            ..Default::default()
        },
        &Constraints::default(),
    )
    .unwrap();
    t.mesh.sanity_check().unwrap();
    let loc = Locator::new(&t.mesh);
    for (x, y, p) in img.enumerate_pixels() {
        if p.0[3] > 8 {
            // Corners of the pixel too, not just the centre.
            for (dx, dy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.5, 0.5)] {
                let q = DVec2::new(x as f64 + dx, y as f64 + dy);
                assert!(loc.contains(q), "pixel ({x}, {y}) corner {q} uncovered");
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    /// Random blobs, holes and speckle: the mesh is valid, matches the domain and covers
    /// every pixel above the threshold, at every density.
    #[test]
    fn random_images(
        w in 1u32..200,
        h in 1u32..160,
        shapes in prop::collection::vec((0.0f64..1.0, 0.0f64..1.0, 0.5f64..30.0, any::<bool>()), 1..8),
        noise in 0u32..4,
        tol in 0.0f64..2.5,
        min_hole in 0.0f64..30.0,
        target in 10usize..5000,
        pts in prop::collection::vec((0.0f64..1.0, 0.0f64..1.0), 0..10),
    ) {
        let mut state = 0x9e37_79b9_u32 ^ w ^ (h << 8);
        let img = image::RgbaImage::from_fn(w, h, |x, y| {
            let p = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
            let mut inside = false;
            for &(cx, cy, r, add) in &shapes {
                if p.distance(DVec2::new(cx * w as f64, cy * h as f64)) < r {
                    inside = add;
                }
            }
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            if noise > 0 && state.is_multiple_of(40 / noise) {
                inside = !inside;
            }
            image::Rgba([0, 0, 0, if inside { 200 } else { 3 }])
        });
        let dopts = DomainOptions {
            alpha_threshold: 8,
            simplify_tolerance: tol,
            min_hole_area: min_hole,
        };
        let d = match domain_for_density(&img, &dopts, target) {
            Ok(d) => d,
            Err(MeshError::EmptyDomain) => {
                prop_assert!(img.pixels().all(|p| p.0[3] <= 8));
                return Ok(());
            }
            Err(e) => panic!("{e}"),
        };
        let points: Vec<DVec2> = pts
            .iter()
            .map(|&(x, y)| DVec2::new(x * w as f64, y * h as f64))
            .filter(|&p| d.contains(p))
            .collect();
        let c = Constraints { points: &points, polylines: &[] };
        let opts = MeshOptions { target_vertices: target, ..Default::default() };
        let t = triangulate(&d, &c, &opts).unwrap();
        t.mesh.sanity_check().unwrap();
        prop_assert!((t.mesh.area() - d.area()).abs() < 1e-6 * d.area());
        for (p, &v) in points.iter().zip(&t.point_vertices) {
            prop_assert_eq!(t.mesh.vertices[v as usize], *p);
        }
        let loc = Locator::new(&t.mesh);
        for (x, y, p) in img.enumerate_pixels() {
            if p.0[3] > 8 {
                let centre = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                prop_assert!(loc.contains(centre), "pixel ({x}, {y}) uncovered");
            }
        }
    }
}

/// Vertices come in Z order, so mesh neighbours are near in memory too (graph searches
/// over the mesh run from cache): most edges join vertices a few rows of the curve
/// apart, far fewer than a random numbering would give.
#[test]
fn mesh_neighbours_are_numbered_close_together() {
    let img = disc_with_hole_and_island_scaled(2);
    let domain = domain_from_image(&img, &DomainOptions::default()).unwrap();
    let opts = MeshOptions {
        target_vertices: 20_000,
        ..Default::default()
    };
    let t = triangulate(&domain, &Constraints::default(), &opts).unwrap();
    let n = t.mesh.vertices.len();
    let mut gaps: Vec<usize> = t
        .mesh
        .triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a as usize).abs_diff(b as usize))
        .collect();
    gaps.sort_unstable();
    let median = gaps[gaps.len() / 2];
    let ninth_decile = gaps[gaps.len() * 9 / 10];
    // A numbering by rows would put a row's neighbours about √n apart.
    let row = (n as f64).sqrt() as usize;
    assert!(median < row / 4, "median gap {median} of {n} vertices");
    assert!(
        ninth_decile < 2 * row,
        "90% of gaps under {ninth_decile} of {n} vertices"
    );
}
