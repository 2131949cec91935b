//! What any moving least squares deformation must do: interpolate the handles, keep
//! the rest pose, and reproduce the transformations of its class.

use crate::support;

use glam::{DMat2, DVec2};
use mls::{Control, Mls, MlsOptions, Variant};
use support::{Rng, VARIANTS, map_controls, scene, vertices_around};

fn deform(
    vertices: &[DVec2],
    rest: &[Control],
    posed: &[Control],
    options: MlsOptions,
) -> Vec<DVec2> {
    let mls = Mls::new(vertices, rest, &options).expect("valid scene");
    let mut out = vec![DVec2::ZERO; vertices.len()];
    mls.deform(posed, &mut out).expect("valid pose");
    out
}

#[test]
fn handles_go_where_they_are_posed() {
    let mut rng = Rng(1);
    for variant in VARIANTS {
        for alpha in [0.5, 1.0, 2.0] {
            let (rest, posed) = scene(&mut rng, 5, 3, 150.0);
            // Every point handle, and points along every bar (ends included).
            let mut vertices = Vec::new();
            let mut want = Vec::new();
            for (r, q) in rest.iter().zip(&posed) {
                match (*r, *q) {
                    (Control::Point(p), Control::Point(q)) => {
                        vertices.push(p);
                        want.push(q);
                    }
                    (Control::Bar([a, b]), Control::Bar([c, d])) => {
                        for t in [0.0, 0.1, 0.5, 0.77, 1.0] {
                            vertices.push(a.lerp(b, t));
                            want.push(c.lerp(d, t));
                        }
                    }
                    _ => unreachable!(),
                }
            }
            let out = deform(&vertices, &rest, &posed, MlsOptions { alpha, variant });
            for (i, (f, w)) in out.iter().zip(&want).enumerate() {
                assert!(
                    (*f - *w).length() < 1e-9,
                    "{variant:?} α {alpha} #{i}: {f} vs {w}"
                );
            }
        }
    }
}

#[test]
fn near_a_handle_is_near_its_posed_position() {
    // Interpolation is the limit of the fit, not only the snap on the handle.
    let mut rng = Rng(2);
    let (rest, posed) = scene(&mut rng, 4, 2, 150.0);
    for variant in VARIANTS {
        for alpha in [1.0, 2.0] {
            for (r, q) in rest.iter().zip(&posed) {
                let (v, w) = match (*r, *q) {
                    (Control::Point(p), Control::Point(q)) => (p, q),
                    (Control::Bar([a, b]), Control::Bar([c, d])) => {
                        (a.lerp(b, 0.4), c.lerp(d, 0.4))
                    }
                    _ => unreachable!(),
                };
                let mut last = f64::INFINITY;
                for off in [1e-2, 1e-4, 1e-6] {
                    let f = deform(
                        &[v + DVec2::new(off, 0.7 * off)],
                        &rest,
                        &posed,
                        MlsOptions { alpha, variant },
                    )[0];
                    let gap = (f - w).length();
                    assert!(gap < last, "{variant:?} α {alpha}: {gap} after {last}");
                    last = gap;
                }
                assert!(last < 1e-3, "{variant:?} α {alpha}: {last}");
            }
        }
    }
}

#[test]
fn the_rest_pose_is_the_identity() {
    let mut rng = Rng(3);
    for variant in VARIANTS {
        for alpha in [0.5, 1.0, 1.5, 3.0] {
            let (rest, _) = scene(&mut rng, 4, 2, 0.0);
            let vertices = vertices_around(&mut rng, &rest, 200);
            let out = deform(&vertices, &rest, &rest, MlsOptions { alpha, variant });
            for (v, f) in vertices.iter().zip(&out) {
                assert!(
                    (*v - *f).length() < 1e-7,
                    "{variant:?} α {alpha}: {v} → {f}"
                );
            }
        }
    }
}

/// Random vertices, handles and a transformation `map`: every vertex must follow
/// `map` to within 1e-9 px.
fn reproduces(variant: Variant, map: impl Fn(DVec2) -> DVec2, seed: u64) {
    let mut rng = Rng(seed);
    for (points, bars) in [(3, 0), (6, 0), (0, 2), (3, 2), (8, 3)] {
        for alpha in [0.5, 1.0, 2.0] {
            let (rest, _) = scene(&mut rng, points, bars, 0.0);
            let posed = map_controls(&rest, &map);
            let vertices = vertices_around(&mut rng, &rest, 300);
            let out = deform(&vertices, &rest, &posed, MlsOptions { alpha, variant });
            for (v, f) in vertices.iter().zip(&out) {
                let want = map(*v);
                assert!(
                    (*f - want).length() < 1e-9,
                    "{variant:?} α {alpha} {points}+{bars}: {v} → {f}, not {want}"
                );
            }
        }
    }
}

#[test]
fn rigid_reproduces_rigid_motions() {
    let rot = DVec2::from_angle(0.83);
    reproduces(
        Variant::Rigid,
        |p| rot.rotate(p) + DVec2::new(-240.0, 75.5),
        4,
    );
}

#[test]
fn similarity_reproduces_similarities() {
    let m = DVec2::from_angle(-2.1) * 1.37;
    reproduces(
        Variant::Similarity,
        |p| m.rotate(p) + DVec2::new(31.0, -410.0),
        5,
    );
}

#[test]
fn affine_reproduces_affine_maps() {
    let m = DMat2::from_cols(DVec2::new(1.3, -0.4), DVec2::new(0.7, 0.6));
    reproduces(Variant::Affine, |p| m * p + DVec2::new(12.0, 88.0), 6);
}

#[test]
fn rigid_keeps_lengths_where_similarity_scales() {
    // A uniform scaling of all handles about their centre: similarity reproduces it,
    // rigid cannot (it keeps |v − p*|), so the two must differ.
    let mut rng = Rng(7);
    let (rest, _) = scene(&mut rng, 5, 1, 0.0);
    let posed = map_controls(&rest, |p| {
        DVec2::new(500.0, 350.0) + (p - DVec2::new(500.0, 350.0)) * 1.5
    });
    let v = [DVec2::new(420.0, 300.0)];
    let s = deform(
        &v,
        &rest,
        &posed,
        MlsOptions {
            alpha: 1.0,
            variant: Variant::Similarity,
        },
    )[0];
    let r = deform(
        &v,
        &rest,
        &posed,
        MlsOptions {
            alpha: 1.0,
            variant: Variant::Rigid,
        },
    )[0];
    assert!(
        (s - (DVec2::new(500.0, 350.0) + (v[0] - DVec2::new(500.0, 350.0)) * 1.5)).length() < 1e-9
    );
    assert!((s - r).length() > 1.0);
}
