//! Constraint points and polylines become exact vertices and edges; insert_point.

#![allow(clippy::unwrap_used)] // Tests unwrap freely.

use crate::support;

use glam::DVec2;
use mesh::{
    Constraints, Domain, DomainOptions, MeshError, MeshOptions, Polygon, domain_from_image,
    triangulate,
};
use proptest::prelude::*;
use support::{Locator, disc_with_hole_and_island, edges};

fn opts(target: usize) -> MeshOptions {
    MeshOptions {
        target_vertices: target,
        ..MeshOptions::default()
    }
}

#[test]
fn points_and_polylines_are_exact_vertices_and_edges() {
    let domain = Domain::full_rectangle(400, 300);
    let points = [
        DVec2::new(10.25, 20.125),
        DVec2::new(1.0 / 3.0, 200.0 / 7.0),
        DVec2::new(0.0, 0.0),       // a corner
        DVec2::new(400.0, 123.456), // on the boundary
        DVec2::new(10.25, 20.125),  // duplicate of the first
        DVec2::new(150.0, 100.0),   // also on a polyline
    ];
    let polylines = vec![
        vec![
            DVec2::new(100.0, 100.0),
            DVec2::new(200.0, 100.0),
            DVec2::new(250.3, 180.7),
        ],
        // Crosses the first polyline.
        vec![DVec2::new(170.0, 40.0), DVec2::new(170.0, 160.0)],
        // Along the top edge of the image.
        vec![DVec2::new(300.0, 0.0), DVec2::new(390.0, 0.0)],
        vec![DVec2::new(50.0, 250.0)],
        vec![],
        // Repeated point.
        vec![
            DVec2::new(60.0, 60.0),
            DVec2::new(60.0, 60.0),
            DVec2::new(80.0, 61.0),
        ],
    ];
    let c = Constraints {
        points: &points,
        polylines: &polylines,
    };
    let t = triangulate(&domain, &c, &opts(5_000)).unwrap();
    t.mesh.sanity_check().unwrap();
    assert!((t.mesh.area() - 120_000.0).abs() < 1e-6 * 120_000.0);

    for (p, &v) in points.iter().zip(&t.point_vertices) {
        assert_eq!(t.mesh.vertices[v as usize], *p);
    }
    assert_eq!(t.point_vertices[0], t.point_vertices[4]);
    assert_eq!(t.polyline_vertices.len(), polylines.len());
    for (line, ids) in polylines.iter().zip(&t.polyline_vertices) {
        assert_eq!(line.len(), ids.len());
        for (p, &v) in line.iter().zip(ids) {
            assert_eq!(t.mesh.vertices[v as usize], *p);
        }
    }
    assert_eq!(t.polyline_vertices[5][0], t.polyline_vertices[5][1]);

    // Paths: consecutive vertices are mesh edges, lie on the polyline, and pass through
    // every polyline point in order.
    let e = edges(&t.mesh);
    for (k, (line, path)) in polylines.iter().zip(&t.polyline_paths).enumerate() {
        if line.is_empty() {
            assert!(path.is_empty());
            continue;
        }
        assert_eq!(path.first(), t.polyline_vertices[k].first());
        assert_eq!(path.last(), t.polyline_vertices[k].last());
        for w in path.windows(2) {
            assert!(
                e.contains(&(w[0].min(w[1]), w[0].max(w[1]))),
                "polyline {k}: {w:?} is no edge"
            );
        }
        let mut at = 0;
        for &v in &t.polyline_vertices[k] {
            let found = path[at..].iter().position(|&p| p == v);
            assert!(found.is_some(), "polyline {k} path misses vertex {v}");
            at += found.unwrap_or(0);
        }
        for &v in path {
            let p = t.mesh.vertices[v as usize];
            let d = line
                .windows(2)
                .map(|w| {
                    let (a, b) = (w[0], w[1]);
                    let ab = b - a;
                    let s = if ab.length_squared() > 0.0 {
                        ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                    (a + ab * s).distance(p)
                })
                .fold(
                    if line.len() == 1 {
                        line[0].distance(p)
                    } else {
                        f64::INFINITY
                    },
                    f64::min,
                );
            assert!(
                d < 1e-9,
                "polyline {k} path vertex {p} is {d} px off the line"
            );
        }
    }
    // The two crossing polylines share a vertex at (170, 100).
    let crossing = DVec2::new(170.0, 100.0);
    let on0 = t.polyline_paths[0]
        .iter()
        .any(|&v| t.mesh.vertices[v as usize].distance(crossing) < 1e-9);
    let on1 = t.polyline_paths[1]
        .iter()
        .any(|&v| t.mesh.vertices[v as usize].distance(crossing) < 1e-9);
    assert!(on0 && on1);
}

#[test]
fn constraints_in_a_cut_out() {
    let img = disc_with_hole_and_island();
    let domain = domain_from_image(&img, &DomainOptions::default()).unwrap();
    let points = [DVec2::new(40.5, 80.5), DVec2::new(170.0, 40.0)];
    let bar = vec![DVec2::new(40.0, 40.0), DVec2::new(60.0, 130.0)];
    let c = Constraints {
        points: &points,
        polylines: std::slice::from_ref(&bar),
    };
    let t = triangulate(&domain, &c, &opts(4_000)).unwrap();
    t.mesh.sanity_check().unwrap();
    assert_eq!(t.mesh.vertices[t.point_vertices[1] as usize], points[1]);
    assert_eq!(t.mesh.vertices[t.polyline_vertices[0][1] as usize], bar[1]);

    // A bar across the hole leaves the shape.
    let across = vec![DVec2::new(50.0, 80.0), DVec2::new(110.0, 80.0)];
    let c = Constraints {
        points: &[],
        polylines: std::slice::from_ref(&across),
    };
    assert!(matches!(
        triangulate(&domain, &c, &opts(4_000)),
        Err(MeshError::PolylineOutsideDomain {
            polyline: 0,
            segment: 0
        })
    ));
    // A point in the hole is outside.
    let c = Constraints {
        points: &[DVec2::new(40.5, 80.5), DVec2::new(80.0, 80.0)],
        polylines: &[],
    };
    assert!(matches!(
        triangulate(&domain, &c, &opts(4_000)),
        Err(MeshError::PointOutsideDomain { index: 1, .. })
    ));
}

#[test]
fn bad_constraints_are_errors() {
    let domain = Domain::full_rectangle(100, 100);
    let o = opts(500);
    let check = |points: &[DVec2], polylines: &[Vec<DVec2>]| {
        triangulate(&domain, &Constraints { points, polylines }, &o).unwrap_err()
    };
    assert!(matches!(
        check(&[DVec2::new(10.0, 10.0), DVec2::new(100.5, 3.0)], &[]),
        MeshError::PointOutsideDomain { index: 1, .. }
    ));
    assert!(matches!(
        check(&[DVec2::new(f64::NAN, 10.0)], &[]),
        MeshError::NonFinite { .. }
    ));
    assert!(matches!(
        check(&[DVec2::new(f64::INFINITY, 10.0)], &[]),
        MeshError::NonFinite { .. }
    ));
    assert!(matches!(
        check(&[], &[vec![DVec2::new(1.0, 1.0), DVec2::new(-1.0, 1.0)]]),
        MeshError::PolylinePointOutsideDomain {
            polyline: 0,
            index: 1,
            ..
        }
    ));
    assert!(matches!(
        check(&[], &[vec![], vec![DVec2::new(1.0, f64::NAN)]]),
        MeshError::NonFinite { .. }
    ));
    let msg = check(&[DVec2::new(-3.0, 4.0)], &[]).to_string();
    assert!(msg.contains("outside"), "{msg}");
}

#[test]
fn hand_made_domains() {
    // An L shape (concave) with a triangular hole.
    let l_shape = Polygon {
        outer: vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(60.0, 0.0),
            DVec2::new(60.0, 20.0),
            DVec2::new(20.0, 20.0),
            DVec2::new(20.0, 60.0),
            DVec2::new(0.0, 60.0),
        ],
        holes: vec![vec![
            DVec2::new(5.0, 5.0),
            DVec2::new(12.0, 5.0),
            DVec2::new(5.0, 12.0),
        ]],
    };
    let domain = Domain {
        polygons: vec![l_shape],
        is_full_rectangle: false,
        width: 60,
        height: 60,
    };
    // A bar along the inner corner's edges is fine; one cutting the notch is not.
    let inside = vec![
        DVec2::new(30.0, 20.0),
        DVec2::new(20.0, 20.0),
        DVec2::new(20.0, 40.0),
    ];
    let t = triangulate(
        &domain,
        &Constraints {
            points: &[DVec2::new(20.0, 20.0)],
            polylines: std::slice::from_ref(&inside),
        },
        &opts(800),
    )
    .unwrap();
    t.mesh.sanity_check().unwrap();
    let expected = 60.0 * 20.0 + 20.0 * 40.0 - 24.5;
    assert!((t.mesh.area() - expected).abs() < 1e-9 * expected);
    let notch = vec![DVec2::new(50.0, 10.0), DVec2::new(10.0, 50.0)];
    assert!(matches!(
        triangulate(
            &domain,
            &Constraints {
                points: &[],
                polylines: std::slice::from_ref(&notch)
            },
            &opts(800)
        ),
        Err(MeshError::PolylineOutsideDomain { .. })
    ));

    // Crossing rings, too few vertices, empty domains.
    let bowtie = Domain {
        polygons: vec![
            Polygon {
                outer: vec![
                    DVec2::new(0.0, 0.0),
                    DVec2::new(10.0, 0.0),
                    DVec2::new(10.0, 10.0),
                    DVec2::new(0.0, 10.0),
                ],
                holes: vec![],
            },
            Polygon {
                outer: vec![
                    DVec2::new(5.0, 5.0),
                    DVec2::new(15.0, 5.0),
                    DVec2::new(15.0, 15.0),
                    DVec2::new(5.0, 15.0),
                ],
                holes: vec![],
            },
        ],
        is_full_rectangle: false,
        width: 20,
        height: 20,
    };
    assert!(matches!(
        triangulate(&bowtie, &Constraints::default(), &opts(300)),
        Err(MeshError::InvalidDomain(_))
    ));
    let mut tiny = domain.clone();
    tiny.polygons[0].outer.truncate(2);
    assert!(matches!(
        triangulate(&tiny, &Constraints::default(), &opts(300)),
        Err(MeshError::InvalidDomain(_))
    ));
    let empty = Domain {
        polygons: vec![],
        is_full_rectangle: false,
        width: 0,
        height: 0,
    };
    assert!(matches!(
        triangulate(&empty, &Constraints::default(), &opts(300)),
        Err(MeshError::EmptyDomain)
    ));
}

#[test]
fn insert_point_splits_and_preserves_area() {
    let domain = Domain::full_rectangle(50, 40);
    let mut m = triangulate(&domain, &Constraints::default(), &opts(200))
        .unwrap()
        .mesh;
    let area = m.area();
    let n = m.vertices.len();
    // Inside a triangle, on an interior edge, on the boundary, on a vertex.
    let (t, _) = m.locate(DVec2::new(17.3, 11.9)).unwrap();
    let [a, b, c] = m.triangle_positions(t);
    let inside = (a + b + c) / 3.0;
    let v = m.insert_point(inside).unwrap();
    assert_eq!(v as usize, n);
    assert_eq!(m.vertices[v as usize], inside);
    let [a, b, _] = m.triangle_positions(t);
    let mid = (a + b) / 2.0;
    let tris = m.triangles.len();
    let w = m.insert_point(mid).unwrap();
    assert_eq!(m.vertices[w as usize], mid);
    assert!(m.triangles.len() == tris + 2 || m.triangles.len() == tris + 1);
    let on_boundary = DVec2::new(0.0, 13.37);
    let u = m.insert_point(on_boundary).unwrap();
    assert_eq!(m.vertices[u as usize], on_boundary);
    assert_eq!(m.insert_point(DVec2::new(50.0, 40.0)).unwrap() as usize, {
        m.vertices
            .iter()
            .position(|&p| p == DVec2::new(50.0, 40.0))
            .unwrap()
    });
    m.sanity_check().unwrap();
    assert!((m.area() - area).abs() < 1e-9 * area);
    assert!(matches!(
        m.insert_point(DVec2::new(-1.0, 3.0)),
        Err(MeshError::PointOutsideMesh { .. })
    ));
}

#[test]
fn locate_agrees_with_the_mesh() {
    let img = disc_with_hole_and_island();
    let t = mesh::mesh_image(
        &img,
        &DomainOptions::default(),
        &opts(1_500),
        &Constraints::default(),
    )
    .unwrap();
    let loc = Locator::new(&t.mesh);
    for k in 0..200 {
        let p = DVec2::new((k * 37 % 200) as f64 + 0.3, (k * 53 % 160) as f64 + 0.7);
        match t.mesh.locate(p) {
            Some((tri, w)) => {
                let [a, b, c] = t.mesh.triangle_positions(tri);
                assert!((a * w[0] + b * w[1] + c * w[2]).distance(p) < 1e-9);
                assert!(loc.contains(p));
            }
            None => assert!(!loc.contains(p)),
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn random_points_become_vertices(
        w in 1u32..300,
        h in 1u32..300,
        raw in prop::collection::vec((0.0f64..=1.0, 0.0f64..=1.0), 0..40),
        snap in prop::collection::vec(any::<bool>(), 40),
        target in 1usize..3_000,
    ) {
        let domain = Domain::full_rectangle(w, h);
        // Some points snapped to the pixel grid (duplicates and boundary points likely).
        let points: Vec<DVec2> = raw
            .iter()
            .zip(&snap)
            .map(|(&(x, y), &s)| {
                let p = DVec2::new(x * w as f64, y * h as f64);
                if s { p.round() } else { p }
            })
            .collect();
        let c = Constraints { points: &points, polylines: &[] };
        let t = triangulate(&domain, &c, &MeshOptions { target_vertices: target, ..Default::default() })
            .unwrap();
        t.mesh.sanity_check().unwrap();
        for (p, &v) in points.iter().zip(&t.point_vertices) {
            prop_assert_eq!(t.mesh.vertices[v as usize], *p);
        }
        let area = (w * h) as f64;
        prop_assert!((t.mesh.area() - area).abs() <= 1e-6 * area);
    }

    #[test]
    fn random_bars_become_edges(
        bars in prop::collection::vec(((0.0f64..=200.0, 0.0f64..=100.0), (0.0f64..=200.0, 0.0f64..=100.0)), 1..6),
    ) {
        let domain = Domain::full_rectangle(200, 100);
        let polylines: Vec<Vec<DVec2>> = bars
            .iter()
            .map(|&((ax, ay), (bx, by))| vec![DVec2::new(ax, ay), DVec2::new(bx, by)])
            .collect();
        let c = Constraints { points: &[], polylines: &polylines };
        let t = triangulate(&domain, &c, &MeshOptions { target_vertices: 1_000, ..Default::default() })
            .unwrap();
        t.mesh.sanity_check().unwrap();
        let e = edges(&t.mesh);
        for (line, path) in polylines.iter().zip(&t.polyline_paths) {
            prop_assert_eq!(t.mesh.vertices[path[0] as usize], line[0]);
            prop_assert_eq!(t.mesh.vertices[*path.last().unwrap() as usize], line[1]);
            for w in path.windows(2) {
                prop_assert!(e.contains(&(w[0].min(w[1]), w[0].max(w[1]))));
            }
        }
    }
}
