//! Bars against their halves, the degenerate scenes an editor produces (no handles,
//! one handle, coincident handles, a vertex on a handle), and refused input.

use crate::support;

use glam::DVec2;
use mls::{Control, Mls, MlsError, MlsOptions, Variant, deform_point};
use support::{Rng, VARIANTS, scene};

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

/// Every bar `a → b` (posed `c → d`) cut at parameter `t` into two bars.
fn halve(controls: &[Control], t: f64) -> Vec<Control> {
    controls
        .iter()
        .flat_map(|c| match *c {
            Control::Point(p) => vec![Control::Point(p)],
            Control::Bar([a, b]) => {
                let m = a.lerp(b, t);
                vec![Control::Bar([a, m]), Control::Bar([m, b])]
            }
        })
        .collect()
}

#[test]
fn a_bar_equals_its_two_halves() {
    let mut rng = Rng(21);
    for variant in VARIANTS {
        for alpha in [0.5, 1.0, 1.7, 2.0] {
            let (rest, posed) = scene(&mut rng, 2, 2, 140.0);
            let vertices: Vec<DVec2> = (0..300).map(|_| rng.point(1000.0, 700.0)).collect();
            let options = MlsOptions { alpha, variant };
            let whole = deform(&vertices, &rest, &posed, options);
            for t in [0.5, 0.3] {
                let split = deform(&vertices, &halve(&rest, t), &halve(&posed, t), options);
                for (i, (w, s)) in whole.iter().zip(&split).enumerate() {
                    let scale = 1.0 + (vertices[i] - *w).length();
                    assert!(
                        (*w - *s).length() < 1e-9 * scale,
                        "{variant:?} α {alpha} cut at {t}, vertex {i}: {w} vs {s}"
                    );
                }
            }
        }
    }
}

#[test]
fn no_handles_is_the_identity() {
    let vertices = [DVec2::new(1.0, 2.0), DVec2::new(-300.0, 4e4)];
    for variant in VARIANTS {
        let out = deform(
            &vertices,
            &[],
            &[],
            MlsOptions {
                alpha: 1.0,
                variant,
            },
        );
        assert_eq!(out, vertices);
    }
}

#[test]
fn one_point_handle_translates_everything() {
    let rest = [Control::Point(DVec2::new(100.0, 100.0))];
    let posed = [Control::Point(DVec2::new(130.0, 60.0))];
    let vertices = [
        DVec2::new(0.0, 0.0),
        DVec2::new(100.0, 100.0),
        DVec2::new(512.0, -7.5),
    ];
    for variant in VARIANTS {
        let out = deform(
            &vertices,
            &rest,
            &posed,
            MlsOptions {
                alpha: 1.0,
                variant,
            },
        );
        for (v, f) in vertices.iter().zip(&out) {
            assert!(
                (*f - (*v + DVec2::new(30.0, -40.0))).length() < 1e-9,
                "{variant:?}: {v} → {f}"
            );
        }
    }
}

#[test]
fn coincident_point_handles_act_as_one_with_their_mean() {
    // Two handles pinned at one place and pulled apart: a vertex there goes to the
    // mean of their posed positions, vertices elsewhere stay finite.
    let p = DVec2::new(200.0, 150.0);
    let rest = [
        Control::Point(p),
        Control::Point(p),
        Control::Point(DVec2::new(600.0, 400.0)),
    ];
    let posed = [
        Control::Point(p + DVec2::new(-20.0, 0.0)),
        Control::Point(p + DVec2::new(40.0, 10.0)),
        Control::Point(DVec2::new(600.0, 400.0)),
    ];
    for variant in VARIANTS {
        let options = MlsOptions {
            alpha: 1.0,
            variant,
        };
        let at = deform_point(p, &rest, &posed, &options).expect("valid");
        assert!(
            (at - (p + DVec2::new(10.0, 5.0))).length() < 1e-9,
            "{variant:?}: {at}"
        );
        let mut rng = Rng(22);
        let vertices: Vec<DVec2> = (0..200).map(|_| rng.point(800.0, 600.0)).collect();
        assert!(
            deform(&vertices, &rest, &posed, options)
                .iter()
                .all(|f| f.is_finite())
        );
    }
}

#[test]
fn collinear_points_fall_back_without_nan() {
    // Three collinear handles leave the affine fit undetermined across the line; the
    // answer is the similarity fit there, never NaN.
    let rest: Vec<Control> = (0..3)
        .map(|i| Control::Point(DVec2::new(100.0 * i as f64, 50.0)))
        .collect();
    let posed: Vec<Control> = (0..3)
        .map(|i| Control::Point(DVec2::new(100.0 * i as f64, 50.0 + 10.0 * i as f64)))
        .collect();
    let mut rng = Rng(23);
    for _ in 0..50 {
        let v = rng.point(400.0, 300.0);
        let affine = deform_point(
            v,
            &rest,
            &posed,
            &MlsOptions {
                alpha: 1.0,
                variant: Variant::Affine,
            },
        )
        .expect("valid");
        let similarity = deform_point(
            v,
            &rest,
            &posed,
            &MlsOptions {
                alpha: 1.0,
                variant: Variant::Similarity,
            },
        )
        .expect("valid");
        assert!(affine.is_finite());
        assert!(
            (affine - similarity).length() < 1e-6,
            "{v}: {affine} vs {similarity}"
        );
    }
}

#[test]
fn a_vertex_on_a_bar_goes_to_the_matching_point_of_the_posed_bar() {
    let (a, b) = (DVec2::new(50.0, 50.0), DVec2::new(350.0, 170.0));
    let (c, d) = (DVec2::new(80.0, 20.0), DVec2::new(300.0, 300.0));
    let rest = [
        Control::Bar([a, b]),
        Control::Point(DVec2::new(500.0, 500.0)),
    ];
    let posed = [
        Control::Bar([c, d]),
        Control::Point(DVec2::new(520.0, 480.0)),
    ];
    for variant in VARIANTS {
        for alpha in [0.5, 1.0, 2.5] {
            for t in [0.0, 0.25, 0.6, 1.0] {
                let options = MlsOptions { alpha, variant };
                let f = deform_point(a.lerp(b, t), &rest, &posed, &options).expect("valid");
                assert!(
                    (f - c.lerp(d, t)).length() < 1e-9,
                    "{variant:?} α {alpha} t {t}: {f}"
                );
            }
        }
    }
}

#[test]
fn bad_input_is_refused_with_its_reason() {
    let point = Control::Point(DVec2::new(1.0, 1.0));
    let v = [DVec2::ZERO];
    for alpha in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let options = MlsOptions {
            alpha,
            variant: Variant::Rigid,
        };
        assert!(matches!(
            Mls::new(&v, &[point], &options),
            Err(MlsError::InvalidAlpha { .. })
        ));
    }
    let options = MlsOptions::default();
    assert_eq!(
        Mls::new(&[DVec2::ZERO, DVec2::NAN], &[point], &options).err(),
        Some(MlsError::NonFiniteVertex { vertex: 1 })
    );
    assert_eq!(
        Mls::new(
            &v,
            &[point, Control::Point(DVec2::new(f64::INFINITY, 0.0))],
            &options
        )
        .err(),
        Some(MlsError::NonFiniteControl { control: 1 })
    );
    let p = DVec2::new(10.0, 10.0);
    assert_eq!(
        Mls::new(&v, &[point, Control::Bar([p, p])], &options).err(),
        Some(MlsError::ZeroLengthBar { control: 1 })
    );

    let mls = Mls::new(&v, &[point, Control::Bar([p, p + DVec2::X])], &options).expect("valid");
    let mut out = [DVec2::ZERO];
    assert_eq!(
        mls.deform(&[point], &mut out).err(),
        Some(MlsError::PoseLength { posed: 1, rest: 2 })
    );
    assert_eq!(
        mls.deform(&[point, point], &mut out).err(),
        Some(MlsError::PoseKind { control: 1 })
    );
    assert_eq!(
        mls.deform(
            &[Control::Point(DVec2::NAN), Control::Bar([p, p])],
            &mut out
        )
        .err(),
        Some(MlsError::NonFinitePosed { control: 0 })
    );
    assert_eq!(
        mls.deform(&[point, Control::Bar([p, p])], &mut []).err(),
        Some(MlsError::OutputLength {
            got: 0,
            vertices: 1
        })
    );
    // A posed bar may collapse to a point: that is a pose, not a mistake.
    mls.deform(&[point, Control::Bar([p, p])], &mut out)
        .expect("a collapsed posed bar is a pose");
    assert!(out[0].is_finite());
}
