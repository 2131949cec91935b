//! What the paper shows its method doing: step two's scale adjustment keeps
//! triangles near their rest size where step one alone inflates and shrinks them
//! (Fig. 15, squash and stretch), and painted rigidity keeps a region from distorting
//! (§5.2, Fig. 9).

mod support;

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
