//! A bank of degenerate inputs: each has a defined answer and never panics.

#![allow(clippy::unwrap_used)] // Tests unwrap freely.

use crate::support;

use glam::DVec2;
use mesh::{Constraints, Domain, DomainOptions, MeshError, MeshOptions, Polygon, triangulate};
use proptest::prelude::*;

fn opts(target: usize) -> MeshOptions {
    MeshOptions {
        target_vertices: target,
        ..MeshOptions::default()
    }
}

fn triangle_domain(scale: f64) -> Domain {
    Domain {
        polygons: vec![Polygon {
            outer: vec![
                DVec2::new(0.0, 0.0),
                DVec2::new(100.0 * scale, 7.0 * scale),
                DVec2::new(31.0 * scale, 77.0 * scale),
            ],
            holes: vec![],
        }],
        is_full_rectangle: false,
        width: (100.0 * scale) as u32,
        height: (77.0 * scale) as u32,
    }
}

/// Checks the invariants and that constraints sit at their exact coordinates.
fn check(domain: &Domain, points: &[DVec2], polylines: &[Vec<DVec2>], target: usize) {
    let c = Constraints { points, polylines };
    let t = triangulate(domain, &c, &opts(target)).unwrap();
    t.mesh.sanity_check().unwrap();
    let area = domain.area();
    assert!(
        (t.mesh.area() - area).abs() <= 1e-6 * area,
        "{} vs {area}",
        t.mesh.area()
    );
    for (p, &v) in points.iter().zip(&t.point_vertices) {
        assert_eq!(t.mesh.vertices[v as usize], *p);
    }
    for (line, ids) in polylines.iter().zip(&t.polyline_vertices) {
        for (p, &v) in line.iter().zip(ids) {
            assert_eq!(t.mesh.vertices[v as usize], *p);
        }
    }
    let e = support::edges(&t.mesh);
    for path in &t.polyline_paths {
        for w in path.windows(2) {
            assert!(e.contains(&(w[0].min(w[1]), w[0].max(w[1]))));
        }
    }
}

#[test]
fn points_close_together() {
    let d = Domain::full_rectangle(100, 100);
    let p = DVec2::new(50.0, 50.0);
    check(
        &d,
        &[
            p,
            p + DVec2::new(1e-9, 0.0),
            p + DVec2::new(0.0, 1e-7),
            p + DVec2::splat(1e-3),
        ],
        &[],
        2_000,
    );
}

#[test]
fn points_and_bars_on_a_slanted_boundary() {
    let d = triangle_domain(1.0);
    let a = DVec2::new(0.0, 0.0);
    let b = DVec2::new(100.0, 7.0);
    let c = DVec2::new(31.0, 77.0);
    let on_ab = a + (b - a) * 0.37;
    let on_bc = b + (c - b) * (1.0 / 3.0);
    check(&d, &[on_ab, on_bc, a, b, c], &[], 1_500);
    check(&d, &[], &[vec![on_ab, on_bc]], 1_500);
    check(&d, &[], &[vec![a, b]], 1_500);
    check(
        &d,
        &[],
        &[vec![a + (b - a) * 0.1, a + (b - a) * 0.9]],
        1_500,
    );
    check(&d, &[], &[vec![a, (a + b + c) / 3.0, c]], 1_500);
}

#[test]
fn overlapping_and_touching_polylines() {
    let d = Domain::full_rectangle(200, 120);
    let lines = vec![
        vec![DVec2::new(20.0, 60.0), DVec2::new(180.0, 60.0)],
        vec![DVec2::new(50.0, 60.0), DVec2::new(120.0, 60.0)], // overlaps the first
        vec![DVec2::new(100.0, 10.0), DVec2::new(100.0, 60.0)], // ends on the first
        vec![DVec2::new(0.0, 0.0), DVec2::new(200.0, 120.0)],  // corner to corner
        vec![DVec2::new(10.0, 10.0), DVec2::new(10.0, 10.0)],  // zero length
        vec![
            DVec2::new(30.0, 100.0),
            DVec2::new(60.0, 100.0),
            DVec2::new(30.0, 100.0),
        ], // folds back
    ];
    check(
        &d,
        &[DVec2::new(100.0, 60.0), DVec2::new(70.0, 60.0)],
        &lines,
        3_000,
    );
}

#[test]
fn closed_polyline_does_not_carve_a_hole() {
    let d = Domain::full_rectangle(100, 100);
    let cage = vec![
        DVec2::new(20.0, 20.0),
        DVec2::new(80.0, 20.0),
        DVec2::new(80.0, 80.0),
        DVec2::new(20.0, 80.0),
        DVec2::new(20.0, 20.0),
    ];
    check(&d, &[], &[cage], 2_000);
}

#[test]
fn tiny_and_huge_domains() {
    check(&triangle_domain(1e-3), &[], &[], 1_000);
    check(&triangle_domain(1e4), &[DVec2::new(5e5, 1e5)], &[], 1_000);
    let d = Domain::full_rectangle(1, 1);
    check(
        &d,
        &[
            DVec2::new(0.5, 0.5),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 0.3),
        ],
        &[],
        20_000,
    );
    let d = Domain::full_rectangle(3000, 2);
    check(
        &d,
        &[DVec2::new(1500.0, 1.0)],
        &[vec![DVec2::new(0.0, 1.0), DVec2::new(3000.0, 1.0)]],
        5_000,
    );
}

#[test]
fn cut_out_ring_vertices_as_handles() {
    let img = support::disc_with_hole_and_island();
    let d = mesh::domain_from_image(&img, &DomainOptions::default()).unwrap();
    let ring = &d.polygons[0].outer;
    let pts: Vec<DVec2> = ring.iter().step_by(7).copied().collect();
    let mid: Vec<DVec2> = ring
        .windows(2)
        .step_by(5)
        .map(|w| (w[0] + w[1]) / 2.0)
        .collect();
    check(&d, &pts, &[], 3_000);
    check(&d, &mid, &[], 3_000);
    // Along the boundary from one ring vertex to the next.
    check(&d, &[], &[vec![ring[3], ring[4]]], 3_000);
}

#[test]
fn domain_errors() {
    let mut d = Domain::full_rectangle(10, 10);
    d.polygons[0].outer[2].x = f64::NAN;
    assert!(matches!(
        triangulate(&d, &Constraints::default(), &opts(100)),
        Err(MeshError::NonFinite { .. })
    ));
    let flat = Domain {
        polygons: vec![Polygon {
            outer: vec![DVec2::ZERO, DVec2::new(1.0, 1.0), DVec2::new(2.0, 2.0)],
            holes: vec![],
        }],
        is_full_rectangle: false,
        width: 2,
        height: 2,
    };
    assert!(matches!(
        triangulate(&flat, &Constraints::default(), &opts(100)),
        Err(MeshError::InvalidDomain(_))
    ));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]

    #[test]
    fn random_constraints_in_a_cut_out(
        seeds in prop::collection::vec((0.0f64..200.0, 0.0f64..160.0), 0..30),
        bars in prop::collection::vec(((0.0f64..200.0, 0.0f64..160.0), (0.0f64..200.0, 0.0f64..160.0)), 0..4),
        target in 200usize..4_000,
    ) {
        let img = support::disc_with_hole_and_island();
        let d = mesh::domain_from_image(&img, &DomainOptions::default()).unwrap();
        // Keep the points inside; keep bars whose segments stay inside.
        let points: Vec<DVec2> = seeds.iter().map(|&(x, y)| DVec2::new(x, y)).filter(|&p| d.contains(p)).collect();
        let polylines: Vec<Vec<DVec2>> = bars
            .iter()
            .map(|&((ax, ay), (bx, by))| vec![DVec2::new(ax, ay), DVec2::new(bx, by)])
            .filter(|l| (0..=50).all(|k| d.contains(l[0].lerp(l[1], k as f64 / 50.0))))
            .collect();
        let c = Constraints { points: &points, polylines: &polylines };
        match triangulate(&d, &c, &opts(target)) {
            Ok(t) => {
                t.mesh.sanity_check().unwrap();
                for (p, &v) in points.iter().zip(&t.point_vertices) {
                    prop_assert_eq!(t.mesh.vertices[v as usize], *p);
                }
            }
            // A bar may graze the boundary between the sampled points.
            Err(MeshError::PolylineOutsideDomain { .. }) => {}
            Err(e) => prop_assert!(false, "{e}"),
        }
    }
}

#[test]
fn coordinates_out_of_range() {
    let d = Domain::full_rectangle(10, 10);
    let c = Constraints {
        points: &[DVec2::new(1e-300, 5.0)],
        polylines: &[],
    };
    assert!(matches!(
        triangulate(&d, &c, &opts(100)),
        Err(MeshError::CoordinateOutOfRange { .. })
    ));
    let mut huge = Domain::full_rectangle(10, 10);
    huge.polygons[0].outer[2] = DVec2::new(1e200, 1e200);
    assert!(matches!(
        triangulate(&huge, &Constraints::default(), &opts(100)),
        Err(MeshError::CoordinateOutOfRange { .. })
    ));
}
