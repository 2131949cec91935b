//! The bar integrals against the α = 2 closed form and against brute-force adaptive
//! quadrature in the bar's own parameter.

use glam::DVec2;

use super::{Deltas, Frame, Moments, Weight, deltas, moments};
use crate::quadrature::gauss_legendre;

/// `∫ g` over `[lo, hi]` for a positive vector integrand `g`, by adaptive bisection
/// with a 10-point Gauss rule until each piece agrees with its two halves to 1e-14
/// relative (the integrands are positive, so that bounds the whole's relative error
/// too).
fn adaptive<const N: usize>(g: &dyn Fn(f64) -> [f64; N], lo: f64, hi: f64) -> [f64; N] {
    let rule = gauss_legendre(10);
    let gauss = |lo: f64, hi: f64| {
        let (mid, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
        let mut acc = [0.0; N];
        for (x, w) in &rule {
            let y = g(mid + half * x);
            for k in 0..N {
                acc[k] += w * half * y[k];
            }
        }
        acc
    };
    fn recurse<const N: usize>(
        gauss: &dyn Fn(f64, f64) -> [f64; N],
        lo: f64,
        hi: f64,
        whole: [f64; N],
        depth: u32,
        budget: &mut u32,
    ) -> [f64; N] {
        *budget = budget.saturating_sub(1);
        let mid = 0.5 * (lo + hi);
        let (left, right) = (gauss(lo, mid), gauss(mid, hi));
        let halves: [f64; N] = std::array::from_fn(|k| left[k] + right[k]);
        let close = (0..N).all(|k| (halves[k] - whole[k]).abs() <= 1e-14 * halves[k].abs());
        if close || depth >= 60 || *budget == 0 {
            halves
        } else {
            let l = recurse(gauss, lo, mid, left, depth + 1, budget);
            let r = recurse(gauss, mid, hi, right, depth + 1, budget);
            std::array::from_fn(|k| l[k] + r[k])
        }
    }
    let mut budget = 1_000_000;
    let out = recurse(&gauss, lo, hi, gauss(lo, hi), 0, &mut budget);
    assert!(budget > 0, "brute force did not converge on [{lo}, {hi}]");
    out
}

/// `[δ00, δ01, δ11]` of the bar `a → b` at `v` for exponent `alpha`, by [`adaptive`]
/// quadrature in the bar's own parameter `t` (`ds = L dt`), split at the bar's point
/// nearest to `v` and measured from it (so that the nodes near the peak of the
/// weight are exact). Shares nothing with `deltas` but the Gauss rule.
fn brute(v: DVec2, a: DVec2, b: DVec2, alpha: f64) -> [f64; 3] {
    let all = brute_all(v, a, b, alpha);
    [all[0], all[1], all[2]]
}

/// [`Moments`] by the same brute force: `[a0, a1, b0, b1, c]` about the bar's point
/// nearest to `v`. (The signed `b0, b1` are compared with an absolute tolerance
/// scaled by `∫ w |σ|`, returned last.)
fn brute_moments(v: DVec2, a: DVec2, b: DVec2, alpha: f64) -> ([f64; 5], f64) {
    let all = brute_all(v, a, b, alpha);
    ([all[3], all[4], all[5], all[6], all[7]], all[8])
}

/// `[δ00, δ01, δ11, a0, a1, b0, b1, c, ∫ w |σ|]`.
fn brute_all(v: DVec2, a: DVec2, b: DVec2, alpha: f64) -> [f64; 9] {
    let d = b - a;
    let len = d.length();
    // The nearest point of the bar (parameter tf, 1 − tf = omf, each from its own
    // end), and the vector to it from v, as exactly as the coordinates allow.
    let l2 = d.length_squared();
    let (mut tf, mut omf) = ((v - a).dot(d) / l2, (b - v).dot(d) / l2);
    if tf <= 0.0 {
        (tf, omf) = (0.0, 1.0);
    } else if omf <= 0.0 {
        (tf, omf) = (1.0, 0.0);
    }
    let to_near = if tf <= 0.5 {
        (a - v) + d * tf
    } else {
        (b - v) - d * omf
    };
    let g = |u: f64| {
        let r = to_near + d * u;
        let w = len / r.length_squared().powf(alpha);
        let (t, omt) = (tf + u, omf - u);
        let sigma = u * len;
        [
            w * omt * omt,
            w * omt * t,
            w * t * t,
            w * omt,
            w * t,
            w * sigma * omt,
            w * sigma * t,
            w * sigma * sigma,
            w * sigma.abs(),
        ]
    };
    let (lo, hi) = (-tf, omf);
    if lo < 0.0 && hi > 0.0 {
        let (l, r) = (adaptive(&g, lo, 0.0), adaptive(&g, 0.0, hi));
        std::array::from_fn(|k| l[k] + r[k])
    } else {
        adaptive(&g, lo, hi)
    }
}

/// The closed form of the bar integrals for α = 2 (with arc length):
///
/// ```text
/// δ00 = L/(2Δ²)·(β01/β00 + β11·θ/Δ)
/// δ01 = L/(2Δ²)·(1 + β01·θ/Δ)
/// δ11 = L/(2Δ²)·(β01/β11 + β00·θ/Δ)
/// ```
///
/// with `L = |b − a|`, `Δ = |(a − v) × (b − v)|`, `θ` the angle the bar subtends at
/// `v`, `β00 = |a − v|²`, `β01 = (a − v)·(v − b)`, `β11 = |v − b|²`. (It follows from
/// `∫₀¹ dt/|p(t) − v|² = θ/Δ` by differentiating with respect to `β00`, `a − v · b − v`
/// and `β11`; the paper prints it with signed `Δ` and `θ`.)
fn closed_form_alpha_2(v: DVec2, a: DVec2, b: DVec2) -> [f64; 3] {
    let (av, bv, vb) = (a - v, b - v, v - b);
    let cross = av.perp_dot(bv);
    let delta = cross.abs();
    let theta = cross.atan2(av.dot(bv)).abs();
    let (b00, b01, b11) = (av.length_squared(), av.dot(vb), vb.length_squared());
    let k = (b - a).length() / (2.0 * delta * delta);
    [
        k * (b01 / b00 + b11 * theta / delta),
        k * (1.0 + b01 * theta / delta),
        k * (b01 / b11 + b00 * theta / delta),
    ]
}

fn ours(v: DVec2, a: DVec2, b: DVec2, alpha: f64) -> [f64; 3] {
    let Deltas { d00, d01, d11 } = deltas(
        &Frame::new(v, a, b),
        &Weight {
            alpha,
            inv_scale2: 1.0,
        },
    );
    [d00, d01, d11]
}

fn our_moments(v: DVec2, a: DVec2, b: DVec2, alpha: f64) -> [f64; 5] {
    let Moments { a0, a1, b0, b1, c } = moments(
        &Frame::new(v, a, b),
        &Weight {
            alpha,
            inv_scale2: 1.0,
        },
    );
    [a0, a1, b0, b1, c]
}

/// Relative error of the positive moments (`a0, a1, c`), and a tenth of the error
/// of the signed ones (`b0, b1`) relative to `scale = ∫ w |σ|`, the size of their
/// terms: they cancel between the two sides of the nearest point, and are only
/// ever used next to terms of that size (so both sum with an absolute error of a
/// few ulps of `scale`, here and in the brute force).
fn moments_err(got: [f64; 5], want: [f64; 5], scale: f64) -> f64 {
    (0..5)
        .map(|k| {
            if k == 2 || k == 3 {
                0.1 * (got[k] - want[k]).abs() / scale.max(f64::MIN_POSITIVE)
            } else {
                (got[k] - want[k]).abs() / want[k].abs().max(f64::MIN_POSITIVE)
            }
        })
        .fold(0.0, f64::max)
}

fn rel_err(got: [f64; 3], want: [f64; 3]) -> f64 {
    (0..3)
        .map(|k| (got[k] - want[k]).abs() / want[k].abs().max(f64::MIN_POSITIVE))
        .fold(0.0, f64::max)
}

/// Vertices around the bar `a → b`: on all sides, near its line (down to `min_off`
/// of its length), near and beyond its ends, and far away. (How near the line a
/// probe can be and still have a well-defined distance to it depends on how far
/// from the origin the bar is: coordinates carry an absolute rounding of about
/// 1e-16 of their size.)
fn probes(a: DVec2, b: DVec2, min_off: f64) -> Vec<DVec2> {
    let (dir, len) = ((b - a).normalize(), (b - a).length());
    let n = dir.perp();
    let mut out = Vec::new();
    for along in [
        -3.0, -1.0, -0.2, -1e-6, 0.0, 1e-7, 0.013, 0.3, 0.5, 0.77, 0.999_999, 1.0, 1.2, 4.0, 30.0,
    ] {
        for off in [1e-9, 1e-6, 1e-3, 0.05, 0.5, 2.0, 40.0] {
            if off < min_off {
                continue;
            }
            for side in [-1.0, 1.0] {
                out.push(a + dir * (along * len) + n * (side * off * len));
            }
        }
    }
    // On the line, beyond the ends.
    for along in [-5.0, -1.0, -0.01, 1.0 + 1e-6, 1.01, 2.0, 50.0] {
        out.push(a + dir * (along * len));
    }
    out
}

#[test]
fn the_closed_form_is_alpha_2_with_arc_length() {
    let (a, b) = (DVec2::new(3.0, -2.0), DVec2::new(40.0, 25.0));
    for v in [
        DVec2::new(10.0, 30.0),
        DVec2::new(-20.0, 4.0),
        DVec2::new(60.0, 20.0),
        DVec2::new(25.0, 5.0),
    ] {
        let closed = closed_form_alpha_2(v, a, b);
        let reference = brute(v, a, b, 2.0);
        assert!(
            rel_err(closed, reference) < 1e-11,
            "{v}: {closed:?} vs {reference:?}"
        );
        // ... and not α = 1, nor the parameter measure (without the length factor).
        assert!(rel_err(closed, brute(v, a, b, 1.0)) > 1e-3);
        let len = (b - a).length();
        assert!(rel_err(closed, reference.map(|d| d / len)) > 1e-3);
    }
}

#[test]
fn quadrature_matches_the_closed_form_for_alpha_2() {
    let (a, b) = (DVec2::new(-7.0, 11.0), DVec2::new(93.0, -4.0));
    let mut checked = 0;
    for v in probes(a, b, 0.0) {
        // Where the bar subtends a fair angle, so that the closed form keeps its
        // digits (it cancels as sin θ → 0).
        let (av, bv) = (a - v, b - v);
        if av.perp_dot(bv).abs() < 0.1 * av.length() * bv.length() {
            continue;
        }
        let got = ours(v, a, b, 2.0);
        let want = closed_form_alpha_2(v, a, b);
        assert!(rel_err(got, want) < 1e-11, "{v}: {got:?} vs {want:?}");
        checked += 1;
    }
    assert!(checked > 60, "{checked}");
}

#[test]
fn quadrature_matches_brute_force_for_any_alpha() {
    // Axis-aligned bars have exact distances down to 1e-9 of their length.
    let bars = [
        (DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), 0.0),
        (DVec2::new(0.0, 5.0), DVec2::new(0.0, -95.0), 0.0),
        (DVec2::new(-7.0, 11.0), DVec2::new(93.0, -4.0), 1e-3),
        (DVec2::new(500.0, 300.0), DVec2::new(512.0, 700.0), 0.05),
    ];
    let mut worst: f64 = 0.0;
    for alpha in [
        0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 6.0, 10.0, 16.0,
    ] {
        for (a, b, min_off) in bars {
            for v in probes(a, b, min_off) {
                let got = ours(v, a, b, alpha);
                let want = brute(v, a, b, alpha);
                let err = rel_err(got, want);
                worst = worst.max(err);
                assert!(
                    err < 1e-12,
                    "α {alpha}, bar {a}→{b}, v {v}: {got:?} vs {want:?} ({err:e})"
                );
                let got = our_moments(v, a, b, alpha);
                let (want, scale) = brute_moments(v, a, b, alpha);
                let err = moments_err(got, want, scale);
                worst = worst.max(err);
                assert!(
                    err < 1e-12,
                    "α {alpha}, bar {a}→{b}, v {v}: {got:?} vs {want:?} ({err:e})"
                );
            }
        }
    }
    eprintln!("worst relative error {worst:e}");
}

#[test]
fn on_the_bar_below_one_half_is_finite_and_right() {
    // α < ½: the integrals converge on the bar itself. The reference substitutes
    // |s| = x^m, m = 1/(1 − 2α), which leaves a polynomial integrand for these α.
    // (An axis-aligned bar, so that its points are exactly on it.)
    let (a, b) = (DVec2::new(2.0, 1.0), DVec2::new(12.0, 1.0));
    let len = (b - a).length();
    for (alpha, m) in [(0.25, 2.0), (1.0 / 3.0, 3.0), (0.375, 4.0)] {
        for tf in [0.0, 0.3, 0.5, 0.9, 1.0] {
            let v = a + (b - a) * tf;
            let mut want = [0.0; 8];
            for (sign, extent) in [(-1.0, tf * len), (1.0, (1.0 - tf) * len)] {
                if extent <= 0.0 {
                    continue;
                }
                // ∫₀^E u^{−2α} g(u) du = ∫₀^{E^{1/m}} m g(x^m) dx.
                let g = |x: f64| {
                    let u: f64 = x.powf(m);
                    let sigma = sign * u;
                    let t = tf + sigma / len;
                    let omt = (1.0 - tf) - sigma / len;
                    [
                        omt * omt,
                        omt * t,
                        t * t,
                        omt,
                        t,
                        sigma * omt,
                        sigma * t,
                        sigma * sigma,
                    ]
                    .map(|y| m * y)
                };
                let part = adaptive(&g, 0.0, extent.powf(1.0 / m));
                for k in 0..8 {
                    want[k] += part[k];
                }
            }
            let got = ours(v, a, b, alpha);
            assert!(got.iter().all(|d| d.is_finite() && *d >= 0.0));
            let err = rel_err(got, [want[0], want[1], want[2]]);
            assert!(err < 1e-12, "α {alpha} t {tf}: {got:?} vs {want:?}");
            let got = our_moments(v, a, b, alpha);
            let scale = want[3] * len;
            let err = moments_err(got, [want[3], want[4], want[5], want[6], want[7]], scale);
            assert!(err < 1e-12, "α {alpha} t {tf}: {got:?} vs {want:?}");
        }
    }
}

#[test]
fn nearest_point_and_distance() {
    let (a, b) = (DVec2::new(0.0, 0.0), DVec2::new(10.0, 0.0));
    let f = Frame::new(DVec2::new(3.0, 4.0), a, b);
    assert!((f.h - 4.0).abs() < 1e-15 && (f.dist2 - 16.0).abs() < 1e-12);
    assert!((f.nearest_t() - 0.3).abs() < 1e-15);
    let f = Frame::new(DVec2::new(13.0, 4.0), a, b);
    assert!((f.dist2 - 25.0).abs() < 1e-12 && f.nearest_t() == 1.0);
    let f = Frame::new(DVec2::new(-3.0, -4.0), a, b);
    assert!((f.dist2 - 25.0).abs() < 1e-12 && f.nearest_t() == 0.0);
}
