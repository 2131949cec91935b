//! A bank of degenerate inputs, each with the answer the crate documents: no
//! constraints, one handle, components and flaps without enough handles, collinear,
//! border and neighbouring handles, collapsed poses, zero-area triangles, isolated
//! vertices, empty meshes, and every input error.

use crate::support;

use arap::{ArapError, Registration, Similarity, ring_constraints, similarity_constraints};
use glam::DVec2;
use support::{
    Diagonals, MeshData, all_finite, grid, holed, max_distance, side_by_side, similarity,
};

fn square() -> MeshData {
    grid(4, 4, 1.0, 0.2, Diagonals::Alternating, 3)
}

#[test]
fn no_constraints_give_the_rest_shape() {
    let mesh = holed(8, 6, 2.0, 0.3, 1);
    let registration = Registration::new(&mesh.rest, &mesh.triangles).expect("valid");
    let compiled = registration.compile(&[], None).expect("compiles");
    assert_eq!(compiled.free_count(), 0);
    let out = compiled.update(&[]).expect("updates");
    assert_eq!(out.step_one, mesh.rest);
    assert_eq!(out.positions, mesh.rest);
}

#[test]
fn one_constraint_translates_the_shape() {
    for mesh in [square(), holed(9, 7, 3.0, 0.3, 2)] {
        let registration = Registration::new(&mesh.rest, &mesh.triangles).expect("valid");
        let v = 7u32;
        let compiled = registration.compile(&[v], None).expect("compiles");
        assert_eq!(compiled.loose_triangles().len(), mesh.triangles.len());
        let target = mesh.rest[v as usize] + DVec2::new(12.5, -3.25);
        let out = compiled.update(&[target]).expect("updates");
        let shift = target - mesh.rest[v as usize];
        let expect: Vec<DVec2> = mesh.rest.iter().map(|&p| p + shift).collect();
        assert!(max_distance(&out.step_one, &expect) < 1e-9);
        assert!(max_distance(&out.positions, &expect) < 1e-9);
    }
}

#[test]
fn a_component_without_constraints_stays_at_rest() {
    let a = square();
    let b = holed(7, 7, 2.0, 0.2, 4);
    let mesh = side_by_side(&a, &b, DVec2::new(10.0, 0.0));
    let registration = Registration::new(&mesh.rest, &mesh.triangles).expect("valid");
    let constrained = [0u32, 24];
    let compiled = registration.compile(&constrained, None).expect("compiles");
    assert_eq!(compiled.free_count(), a.rest.len() - 2);
    let targets = [DVec2::new(-1.0, 0.5), DVec2::new(6.0, 5.0)];
    let out = compiled.update(&targets).expect("updates");
    let shift = a.rest.len();
    assert_eq!(&out.step_one[shift..], &mesh.rest[shift..]);
    assert_eq!(&out.positions[shift..], &mesh.rest[shift..]);
    assert!(all_finite(&out.positions));
}

#[test]
fn each_component_follows_its_own_handles() {
    let a = square();
    let b = square();
    let mesh = side_by_side(&a, &b, DVec2::new(10.0, 0.0));
    let registration = Registration::new(&mesh.rest, &mesh.triangles).expect("valid");
    let n = a.rest.len() as u32;
    // Two handles on the first square turn it rigidly; one on the second moves it.
    let turn = similarity(0.7, 1.0, DVec2::new(3.0, -1.0));
    let constrained = [0u32, 24, n + 12];
    let targets = [
        turn(mesh.rest[0]),
        turn(mesh.rest[24]),
        mesh.rest[(n + 12) as usize] + DVec2::new(0.0, 4.0),
    ];
    let out = registration
        .compile(&constrained, None)
        .and_then(|c| c.update(&targets))
        .expect("poses");
    for v in 0..mesh.rest.len() {
        let expect = if v < n as usize {
            turn(mesh.rest[v])
        } else {
            mesh.rest[v] + DVec2::new(0.0, 4.0)
        };
        assert!((out.positions[v] - expect).length() < 1e-9);
    }
}

/// Two squares sharing one corner vertex: the flap without handles of its own can
/// only be moved through that vertex, so it follows by translation.
#[test]
fn a_flap_joined_by_one_vertex_follows_by_translation() {
    let a = square();
    let b = square();
    let mut mesh = side_by_side(&a, &b, DVec2::new(4.0, 4.0));
    // Vertex 0 of the second square lies on the first's corner 24: merge them.
    let n = a.rest.len() as u32;
    for t in &mut mesh.triangles {
        for v in t.iter_mut() {
            if *v == n {
                *v = 24;
            }
        }
    }
    let registration = Registration::new(&mesh.rest, &mesh.triangles).expect("valid");
    let constrained = [0u32, 4];
    let compiled = registration.compile(&constrained, None).expect("compiles");
    let flap: Vec<u32> = (a.triangles.len() as u32..mesh.triangles.len() as u32).collect();
    assert_eq!(compiled.loose_triangles(), &flap[..]);
    let targets = [DVec2::new(0.0, 0.0), DVec2::new(3.0, -2.0)];
    let out = compiled.update(&targets).expect("updates");
    for result in [&out.step_one, &out.positions] {
        let shift = result[24] - mesh.rest[24];
        for (p, r) in result.iter().zip(&mesh.rest).skip(n as usize + 1) {
            assert!((*p - (*r + shift)).length() < 1e-9);
        }
        assert!(all_finite(result));
    }
}

#[test]
fn collinear_constraints() {
    let mesh = grid(8, 3, 1.0, 0.0, Diagonals::Same, 0);
    // Four handles along the bottom row, pulled apart along a slanted line.
    let constrained = [0u32, 3, 5, 8];
    let dir = DVec2::new(1.0, 0.3);
    let targets: Vec<DVec2> = constrained.iter().map(|&v| dir * 1.4 * v as f64).collect();
    let out = Registration::new(&mesh.rest, &mesh.triangles)
        .and_then(|r| r.compile(&constrained, None))
        .and_then(|c| c.update(&targets))
        .expect("poses");
    assert!(all_finite(&out.step_one) && all_finite(&out.positions));
    for (&v, &t) in constrained.iter().zip(&targets) {
        assert_eq!(out.positions[v as usize], t);
    }
}

#[test]
fn every_border_vertex_constrained() {
    let mesh = grid(5, 5, 1.0, 0.3, Diagonals::Alternating, 8);
    let border: Vec<u32> = (0..mesh.rest.len() as u32)
        .filter(|&v| {
            let (i, j) = (v % 6, v / 6);
            i == 0 || j == 0 || i == 5 || j == 5
        })
        .collect();
    let squash = |p: DVec2| DVec2::new(p.x * 1.3, p.y * 0.6 + 0.1 * p.x * p.x);
    let targets: Vec<DVec2> = border
        .iter()
        .map(|&v| squash(mesh.rest[v as usize]))
        .collect();
    let compiled = Registration::new(&mesh.rest, &mesh.triangles)
        .and_then(|r| r.compile(&border, None))
        .expect("compiles");
    assert_eq!(compiled.free_count(), 16);
    let out = compiled.update(&targets).expect("updates");
    assert!(all_finite(&out.positions));
}

/// Two handles on neighbours of one vertex (and of each other), and a vertex whose
/// whole one-ring is pinned by a similarity.
#[test]
fn handles_next_to_each_other_and_a_pinned_ring() {
    let mesh = square();
    let registration = Registration::new(&mesh.rest, &mesh.triangles).expect("valid");
    let ring = registration.neighbours(12).expect("vertex exists");
    let constrained = [ring[0], ring[1]];
    let targets = [
        mesh.rest[ring[0] as usize] + DVec2::new(2.0, 0.0),
        mesh.rest[ring[1] as usize] + DVec2::new(-2.0, 1.0),
    ];
    let out = registration
        .compile(&constrained, None)
        .and_then(|c| c.update(&targets))
        .expect("poses");
    assert!(all_finite(&out.positions));

    let turn = Similarity {
        translation: DVec2::new(1.0, 2.0),
        rotation: 0.8,
        scale: 1.5,
    };
    let pins = ring_constraints(&registration, 12, &turn).expect("vertex exists");
    assert_eq!(pins[0].0, 12);
    assert_eq!(pins.len(), ring.len() + 1);
    // Leave the centre free: its ring alone pins it in step one.
    let (vertices, targets): (Vec<u32>, Vec<DVec2>) = pins[1..].iter().copied().unzip();
    let out = registration
        .compile(&vertices, None)
        .and_then(|c| c.update(&targets))
        .expect("poses");
    assert!((out.step_one[12] - pins[0].1).length() < 1e-9);
    assert!(all_finite(&out.positions));
}

#[test]
fn similarity_constraints_send_each_vertex_by_the_similarity() {
    let mesh = square();
    let registration = Registration::new(&mesh.rest, &mesh.triangles).expect("valid");
    let turn = Similarity {
        translation: DVec2::new(0.5, -0.5),
        rotation: std::f64::consts::FRAC_PI_2,
        scale: 2.0,
    };
    let pins = similarity_constraints(&registration, 6, &[6, 7, 11], &turn).expect("valid");
    assert_eq!(pins.iter().map(|p| p.0).collect::<Vec<_>>(), [6, 7, 11]);
    let c = mesh.rest[6];
    for (v, t) in pins {
        let d = mesh.rest[v as usize] - c;
        let expect = c + DVec2::new(0.5, -0.5) + 2.0 * DVec2::new(-d.y, d.x);
        assert!((t - expect).length() < 1e-12);
    }
}

#[test]
fn every_handle_on_one_point_collapses_without_nan() {
    let mesh = holed(8, 8, 2.0, 0.3, 6);
    let constrained = [0u32, 30, 60];
    let targets = [DVec2::new(3.0, 3.0); 3];
    let out = Registration::new(&mesh.rest, &mesh.triangles)
        .and_then(|r| r.compile(&constrained, None))
        .and_then(|c| c.update(&targets))
        .expect("poses");
    // Step one shrinks everything onto the point; step two then has no rotation to
    // read and keeps the rest orientation.
    assert!(max_distance(&out.step_one, &vec![DVec2::new(3.0, 3.0); mesh.rest.len()]) < 1e-9);
    assert!(all_finite(&out.positions));
}

/// Zero-area rest triangles (collinear corners, a repeated vertex) are left out:
/// the result is the one without them.
#[test]
fn zero_area_triangles_are_skipped() {
    let mesh = square();
    let mut with = mesh.clone();
    with.triangles.push([0, 1, 2]); // along the bottom border: collinear
    with.triangles.push([6, 6, 7]); // a repeated vertex
    with.triangles.insert(3, [12, 12, 12]);
    let constrained = [0u32, 24, 9];
    let targets = [
        DVec2::new(0.0, 0.0),
        DVec2::new(5.0, 3.0),
        DVec2::new(4.0, 0.5),
    ];
    let registration = Registration::new(&with.rest, &with.triangles).expect("valid");
    assert_eq!(registration.skipped_triangles(), &[3, 33, 34]);
    let rigidity = vec![2.0; with.triangles.len()];
    let got = registration
        .compile(&constrained, Some(&rigidity))
        .and_then(|c| c.update(&targets))
        .expect("poses");
    let expect = Registration::new(&mesh.rest, &mesh.triangles)
        .and_then(|r| r.compile(&constrained, None))
        .and_then(|c| c.update(&targets))
        .expect("poses");
    assert!(max_distance(&got.step_one, &expect.step_one) < 1e-12);
    assert!(max_distance(&got.positions, &expect.positions) < 1e-12);
}

#[test]
fn isolated_vertices() {
    let mut mesh = square();
    mesh.rest.push(DVec2::new(-5.0, -5.0));
    mesh.rest.push(DVec2::new(-6.0, -5.0));
    let (lonely, pinned) = (mesh.rest.len() as u32 - 2, mesh.rest.len() as u32 - 1);
    let constrained = [0u32, 24, pinned];
    let targets = [DVec2::ZERO, DVec2::new(4.0, 4.5), DVec2::new(9.0, 9.0)];
    let out = Registration::new(&mesh.rest, &mesh.triangles)
        .and_then(|r| r.compile(&constrained, None))
        .and_then(|c| c.update(&targets))
        .expect("poses");
    assert_eq!(out.positions[lonely as usize], mesh.rest[lonely as usize]);
    assert_eq!(out.positions[pinned as usize], DVec2::new(9.0, 9.0));
    assert!(all_finite(&out.positions));
}

#[test]
fn empty_meshes() {
    let registration = Registration::new(&[], &[]).expect("valid");
    let out = registration
        .compile(&[], None)
        .and_then(|c| c.update(&[]))
        .expect("poses");
    assert!(out.positions.is_empty() && out.step_one.is_empty());
    // Vertices without triangles.
    let rest = [DVec2::ZERO, DVec2::X];
    let registration = Registration::new(&rest, &[]).expect("valid");
    let out = registration
        .compile(&[1], None)
        .and_then(|c| c.update(&[DVec2::new(2.0, 2.0)]))
        .expect("poses");
    assert_eq!(out.positions, [DVec2::ZERO, DVec2::new(2.0, 2.0)]);
}

#[test]
fn bad_input_is_refused() {
    let mesh = square();
    let registration = Registration::new(&mesh.rest, &mesh.triangles).expect("valid");
    let t = mesh.triangles.len();
    assert_eq!(
        registration.compile(&[3, 7, 3], None).err(),
        Some(ArapError::DuplicateConstraint {
            vertex: 3,
            first: 0,
            second: 2
        })
    );
    assert_eq!(
        registration.compile(&[3, 25], None).err(),
        Some(ArapError::VertexOutOfRange {
            vertex: 25,
            vertices: 25
        })
    );
    assert_eq!(
        registration.compile(&[3], Some(&[1.0; 5])).err(),
        Some(ArapError::RigidityLength {
            got: 5,
            triangles: t
        })
    );
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let mut w = vec![1.0; t];
        w[4] = bad;
        assert!(matches!(
            registration.compile(&[3], Some(&w)),
            Err(ArapError::BadRigidity { triangle: 4, .. })
        ));
    }
    let compiled = registration.compile(&[3, 7], None).expect("compiles");
    assert_eq!(
        compiled.update(&[DVec2::ZERO]).err(),
        Some(ArapError::TargetCount {
            got: 1,
            expected: 2
        })
    );
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        assert_eq!(
            compiled.update(&[DVec2::ZERO, DVec2::new(1.0, bad)]).err(),
            Some(ArapError::NonFiniteTarget { constraint: 1 })
        );
    }
    let mut rest = mesh.rest.clone();
    rest[5].x = f64::NAN;
    assert_eq!(
        Registration::new(&rest, &mesh.triangles).err(),
        Some(ArapError::NonFiniteRest { vertex: 5 })
    );
    assert_eq!(
        Registration::new(&mesh.rest, &[[0, 1, 99]]).err(),
        Some(ArapError::TriangleVertexOutOfRange {
            triangle: 0,
            vertex: 99,
            vertices: 25
        })
    );
    let nan_turn = Similarity {
        rotation: f64::NAN,
        ..Similarity::IDENTITY
    };
    assert_eq!(
        ring_constraints(&registration, 3, &nan_turn).err(),
        Some(ArapError::NonFiniteSimilarity)
    );
    assert_eq!(
        ring_constraints(&registration, 30, &Similarity::IDENTITY).err(),
        Some(ArapError::VertexOutOfRange {
            vertex: 30,
            vertices: 25
        })
    );
    // Every error says what is wrong in words.
    let message = ArapError::DuplicateConstraint {
        vertex: 3,
        first: 0,
        second: 2,
    }
    .to_string();
    assert!(message.contains("constrained twice"), "{message}");
}

/// Handles on two vertices that share one rest position (the two lips of a slit):
/// step one's similarity is not pinned down by them, so the shape follows by its
/// rest edges, and the slit opens.
#[test]
fn handles_sharing_one_rest_position() {
    let mut mesh = grid(4, 2, 1.0, 0.0, Diagonals::Alternating, 0);
    // Cut the edge (2, 0)–(2, 1): the cell right of it gets its own copy of (2, 0).
    let lip = mesh.rest.len() as u32;
    mesh.rest.push(mesh.rest[2]);
    for t in &mut mesh.triangles[4..6] {
        for v in t.iter_mut() {
            if *v == 2 {
                *v = lip;
            }
        }
    }
    let registration = Registration::new(&mesh.rest, &mesh.triangles).expect("valid");
    let compiled = registration.compile(&[2, lip], None).expect("compiles");
    assert_eq!(compiled.loose_triangles().len(), mesh.triangles.len());
    let targets = [DVec2::new(1.5, -0.5), DVec2::new(2.5, -0.5)];
    let out = compiled.update(&targets).expect("updates");
    assert!(all_finite(&out.step_one) && all_finite(&out.positions));
    assert_eq!(out.positions[2], targets[0]);
    assert_eq!(out.positions[lip as usize], targets[1]);
}

#[test]
fn compiled_systems_can_be_shared_between_threads() {
    fn shareable<T: Send + Sync>() {}
    shareable::<Registration>();
    shareable::<arap::Compiled>();
    shareable::<arap::Deformation>();
}
