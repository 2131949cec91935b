//! What the paper shows its method doing: step two's scale adjustment keeps
//! triangles near their rest size where step one alone inflates and shrinks them
//! (Fig. 15, squash and stretch), and painted rigidity keeps a region from distorting
//! (§5.2, Fig. 9).

use crate::support;

use arap::Registration;
use glam::DVec2;
use support::{Diagonals, MeshData, grid, mean_area_deviation, rigidity_error};

/// A bar of 24 × 4 unit cells, jittered, pinned at both ends by the two corners of
/// each end.
fn bar() -> (MeshData, [u32; 4]) {
    let mesh = grid(24, 4, 1.0, 0.2, Diagonals::Alternating, 11);
    let id = |i: u32, j: u32| j * 25 + i;
    (mesh, [id(0, 0), id(0, 4), id(24, 0), id(24, 4)])
}

/// Mean `|area/rest area − 1|` of step one and of the final result when the bar's
/// right end is moved to `x`.
fn area_deviation(x: f64) -> (f64, f64) {
    let (mesh, ends) = bar();
    let targets = [
        DVec2::new(0.0, 0.0),
        DVec2::new(0.0, 4.0),
        DVec2::new(x, 0.0),
        DVec2::new(x, 4.0),
    ];
    let out = Registration::new(&mesh.rest, &mesh.triangles)
        .and_then(|r| r.compile(&ends, None))
        .and_then(|c| c.update(&targets))
        .expect("poses");
    (
        mean_area_deviation(&mesh, &out.step_one),
        mean_area_deviation(&mesh, &out.positions),
    )
}

#[test]
fn stretch_keeps_areas_closer_to_rest_than_step_one() {
    let (one, two) = area_deviation(36.0);
    assert!(two < 0.5 * one, "step one {one}, final {two}");
}

#[test]
fn squash_keeps_areas_closer_to_rest_than_step_one() {
    // Pinned at both ends, the bar cannot buckle out of its line (the linearity the
    // paper's Fig. 19 shows), so it keeps less of its area than when stretched.
    let (one, two) = area_deviation(15.0);
    assert!(two < 0.7 * one, "step one {one}, final {two}");
}

/// Mean distance of each triangle's deformation gradient from its closest rotation
/// over the middle of a bent bar, with and without rigidity painted there.
fn middle_distortion(painted: f64) -> f64 {
    let (mesh, ends) = bar();
    let middle = |t: &[u32; 3]| {
        let c = t.iter().map(|&v| mesh.rest[v as usize]).sum::<DVec2>() / 3.0;
        (9.0..15.0).contains(&c.x)
    };
    let rigidity: Vec<f64> = mesh
        .triangles
        .iter()
        .map(|t| if middle(t) { painted } else { 1.0 })
        .collect();
    // Bend: the right end swung down and turned, a little closer.
    let targets = [
        DVec2::new(0.0, 0.0),
        DVec2::new(0.0, 4.0),
        DVec2::new(18.0, 12.0),
        DVec2::new(14.5, 14.0),
    ];
    let out = Registration::new(&mesh.rest, &mesh.triangles)
        .and_then(|r| r.compile(&ends, Some(&rigidity)))
        .and_then(|c| c.update(&targets))
        .expect("poses");
    let errors: Vec<f64> = mesh
        .triangles
        .iter()
        .filter(|t| middle(t))
        .map(|t| {
            rigidity_error(
                t.map(|v| mesh.rest[v as usize]),
                t.map(|v| out.positions[v as usize]),
            )
        })
        .collect();
    errors.iter().sum::<f64>() / errors.len() as f64
}

#[test]
fn painted_region_distorts_less() {
    let plain = middle_distortion(1.0);
    let painted = middle_distortion(10000.0);
    assert!(
        painted < 0.2 * plain,
        "painted {painted}, unpainted {plain}"
    );
}

#[test]
fn pins_added_where_a_solve_put_their_vertices_change_nothing() {
    // The bar bent: its right end raised and moved in.
    let (mesh, ends) = bar();
    let registration = Registration::new(&mesh.rest, &mesh.triangles).expect("registers");
    let targets = [
        DVec2::new(0.0, 0.0),
        DVec2::new(0.0, 4.0),
        DVec2::new(18.0, 9.0),
        DVec2::new(17.0, 13.0),
    ];
    let before = registration
        .compile(&ends, None)
        .and_then(|c| c.update(&targets))
        .expect("poses");
    // Pin a middle cell's corners (and, a few at a time, more) where the solve put
    // them: step one's vertices at step one's answer, the final ones at the final one.
    let id = |i: u32, j: u32| j * 25 + i;
    for added in [
        vec![id(12, 2)],
        vec![id(8, 1), id(9, 1), id(8, 2), id(9, 2)],
    ] {
        let mut pinned = ends.to_vec();
        pinned.extend(&added);
        let compiled = registration.compile(&pinned, None).expect("compiles");
        let order = compiled.constrained().to_vec();
        let at =
            |list: &[DVec2]| -> Vec<DVec2> { order.iter().map(|&v| list[v as usize]).collect() };
        let mut after = arap::Deformation::default();
        compiled
            .update_split_into(&at(&before.step_one), &at(&before.positions), &mut after)
            .expect("poses");
        let worst = |a: &[DVec2], b: &[DVec2]| {
            a.iter()
                .zip(b)
                .map(|(p, q)| p.distance(*q))
                .fold(0.0, f64::max)
        };
        assert!(worst(&after.step_one, &before.step_one) < 1e-9);
        assert!(worst(&after.positions, &before.positions) < 1e-9);
        // Pinned at the final answer in both steps instead, the answer moves: step one
        // needs its own.
        let mut both = arap::Deformation::default();
        compiled
            .update_into(&at(&before.positions), &mut both)
            .expect("poses");
        assert!(worst(&both.positions, &before.positions) > 1e-3);
    }
}
