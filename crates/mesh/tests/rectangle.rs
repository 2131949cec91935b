//! Opaque images mesh to the full rectangle; degenerate images have defined answers.

#![allow(clippy::unwrap_used)] // Tests unwrap freely.

use crate::support;

use glam::DVec2;
use mesh::{Constraints, DomainOptions, MeshError, MeshOptions, domain_from_image, mesh_image};

fn opts(target: usize) -> MeshOptions {
    MeshOptions {
        target_vertices: target,
        ..MeshOptions::default()
    }
}

#[test]
fn opaque_rectangle_covers_the_image_exactly() {
    for (w, h, target) in [
        (320u32, 200u32, 5_000usize),
        (97, 331, 2_000),
        (640, 480, 20_000),
    ] {
        let img = image::RgbaImage::from_pixel(w, h, image::Rgba([10, 20, 30, 255]));
        let t = mesh_image(
            &img,
            &DomainOptions::default(),
            &opts(target),
            &Constraints::default(),
        )
        .unwrap();
        assert!(t.is_convex);
        t.mesh.sanity_check().unwrap();
        let area = (w * h) as f64;
        assert!(
            (t.mesh.area() - area).abs() <= 1e-6 * area,
            "area {}",
            t.mesh.area()
        );
        for c in [
            DVec2::new(0.0, 0.0),
            DVec2::new(w as f64, 0.0),
            DVec2::new(w as f64, h as f64),
            DVec2::new(0.0, h as f64),
        ] {
            assert!(t.mesh.vertices.contains(&c), "corner {c} is not a vertex");
        }
        let (lo, hi) = t.mesh.bounding_box();
        assert_eq!((lo, hi), (DVec2::ZERO, DVec2::new(w as f64, h as f64)));
        let n = t.mesh.vertices.len() as f64;
        assert!(
            (n / target as f64 - 1.0).abs() < 0.3,
            "{n} vertices for target {target}"
        );
    }
}

#[test]
fn opaque_domain_is_the_full_rectangle() {
    let img = image::RgbaImage::from_pixel(5, 3, image::Rgba([0, 0, 0, 9]));
    let d = domain_from_image(&img, &DomainOptions::default()).unwrap();
    assert!(d.is_full_rectangle);
    assert_eq!((d.width, d.height), (5, 3));
    assert_eq!(d.area(), 15.0);
    // By default the faintest visible pixel is inside.
    let img = image::RgbaImage::from_pixel(5, 3, image::Rgba([0, 0, 0, 1]));
    let d = domain_from_image(&img, &DomainOptions::default()).unwrap();
    assert!(d.is_full_rectangle);
    // Alpha equal to the threshold is outside.
    let img = image::RgbaImage::from_pixel(5, 3, image::Rgba([0, 0, 0, 8]));
    let faint_out = DomainOptions {
        alpha_threshold: 8,
        ..Default::default()
    };
    assert!(matches!(
        domain_from_image(&img, &faint_out),
        Err(MeshError::EmptyDomain)
    ));
    let clear = image::RgbaImage::from_pixel(5, 3, image::Rgba([0, 0, 0, 0]));
    assert!(matches!(
        domain_from_image(&clear, &DomainOptions::default()),
        Err(MeshError::EmptyDomain)
    ));
}

#[test]
fn minimum_angle_is_respected_in_the_interior() {
    let img = image::RgbaImage::from_pixel(300, 300, image::Rgba([1, 1, 1, 255]));
    let t = mesh_image(
        &img,
        &DomainOptions::default(),
        &opts(10_000),
        &Constraints::default(),
    )
    .unwrap();
    let mut worst = 180.0f64;
    for k in 0..t.mesh.triangles.len() {
        let [a, b, c] = t.mesh.triangle_positions(k);
        for (p, q, r) in [(a, b, c), (b, c, a), (c, a, b)] {
            worst = worst.min((q - p).angle_to(r - p).abs().to_degrees());
        }
    }
    assert!(worst > 20.0, "smallest angle {worst}°");
}

#[test]
fn degenerate_images() {
    let o = DomainOptions::default();
    let m = MeshOptions::default();
    let c = Constraints::default();
    let empty = image::RgbaImage::new(0, 0);
    assert!(matches!(
        mesh_image(&empty, &o, &m, &c),
        Err(MeshError::EmptyDomain)
    ));
    let wide_empty = image::RgbaImage::new(10, 0);
    assert!(matches!(
        mesh_image(&wide_empty, &o, &m, &c),
        Err(MeshError::EmptyDomain)
    ));
    let clear = image::RgbaImage::new(30, 20);
    assert!(matches!(
        mesh_image(&clear, &o, &m, &c),
        Err(MeshError::EmptyDomain)
    ));

    let one = image::RgbaImage::from_pixel(1, 1, image::Rgba([1, 2, 3, 255]));
    let t = mesh_image(&one, &o, &m, &c).unwrap();
    t.mesh.sanity_check().unwrap();
    assert!((t.mesh.area() - 1.0).abs() < 1e-12);

    // One opaque pixel in a transparent image: the dilated pixel is meshed.
    let mut dot = image::RgbaImage::new(9, 9);
    dot.put_pixel(4, 4, image::Rgba([0, 0, 0, 255]));
    let t = mesh_image(&dot, &o, &m, &c).unwrap();
    t.mesh.sanity_check().unwrap();
    assert!((t.mesh.area() - 9.0).abs() < 1e-9, "area {}", t.mesh.area());

    // An opaque pixel in a corner, and a one-pixel-wide line.
    let mut corner = image::RgbaImage::new(4, 4);
    corner.put_pixel(0, 0, image::Rgba([0, 0, 0, 255]));
    mesh_image(&corner, &o, &m, &c)
        .unwrap()
        .mesh
        .sanity_check()
        .unwrap();
    let line = image::RgbaImage::from_pixel(50, 1, image::Rgba([0, 0, 0, 255]));
    mesh_image(&line, &o, &m, &c)
        .unwrap()
        .mesh
        .sanity_check()
        .unwrap();
    let column =
        image::RgbaImage::from_fn(1, 40, |_, y| image::Rgba([0, 0, 0, (y % 3 * 120) as u8]));
    mesh_image(&column, &o, &m, &c)
        .unwrap()
        .mesh
        .sanity_check()
        .unwrap();

    // Silly options still give an answer.
    let weird = MeshOptions {
        target_vertices: 0,
        min_angle_deg: f64::NAN,
        refine: vec![DVec2::NAN, DVec2::new(-5.0, 1e300)],
    };
    mesh_image(&one, &o, &weird, &c)
        .unwrap()
        .mesh
        .sanity_check()
        .unwrap();
    let weird = MeshOptions {
        target_vertices: usize::MAX,
        min_angle_deg: 89.0,
        refine: Vec::new(),
    };
    let t = mesh_image(&one, &o, &weird, &c).unwrap();
    t.mesh.sanity_check().unwrap();
    let weird_domain = DomainOptions {
        alpha_threshold: 0,
        simplify_tolerance: f64::NAN,
        min_hole_area: f64::INFINITY,
    };
    mesh_image(&dot, &weird_domain, &m, &c)
        .unwrap()
        .mesh
        .sanity_check()
        .unwrap();
}

#[test]
fn noisy_alpha_does_not_break_anything() {
    // Pseudo-random speckle: many tiny islands, holes and diagonal contacts.
    let mut state = 0x1234_5678u32;
    let img = image::RgbaImage::from_fn(120, 90, |_, _| {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        image::Rgba([0, 0, 0, if state % 5 < 2 { 255 } else { 0 }])
    });
    for tol in [0.0, 0.75, 2.0] {
        for min_hole in [0.0, 16.0] {
            let o = DomainOptions {
                simplify_tolerance: tol,
                min_hole_area: min_hole,
                ..Default::default()
            };
            let t = mesh_image(&img, &o, &opts(3_000), &Constraints::default()).unwrap();
            t.mesh.sanity_check().unwrap();
            let loc = support::Locator::new(&t.mesh);
            for (x, y, p) in img.enumerate_pixels() {
                if p.0[3] > 0 {
                    let c = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                    assert!(loc.contains(c), "opaque pixel ({x}, {y}) not covered");
                }
            }
        }
    }
}
