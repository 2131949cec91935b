//! The integrals a bar (line-segment handle) contributes at one vertex (§4 of the
//! paper): with the rest bar `p(t) = (1 − t)·a + t·b`, `t ∈ [0, 1]`, of length `L`,
//! and the weight `w(t) = 1 / |p(t) − v|^{2α}` taken with respect to arc length
//! (`ds = L dt`),
//!
//! ```text
//! δ00 = ∫ w (1 − t)² ds,   δ01 = ∫ w (1 − t) t ds,   δ11 = ∫ w t² ds.
//! ```
//!
//! Every integrand is positive, so every δ is computed to a relative accuracy of
//! about 1e-13 for any α > 0 and any position of the vertex: the paper's closed forms
//! exist for α = 2 only and cancel badly near the bar's line.
//!
//! With `h` the distance from `v` to the bar's line and `s` the signed arc-length
//! coordinate from the foot of the perpendicular, `|p − v|² = h² + s²`. The range
//! of `s` is cut in three:
//! - the *core* `|s| ≤ h`, integrated in `θ` with `s = h·tan θ` (`|θ| ≤ π/4`), where
//!   the integrand `h·sec²θ·(h·sec θ)^{−2α}·poly(h tan θ)` is smooth; one
//!   sub-interval;
//! - each *flank* `h ≤ |s|`, integrated in `|s|` on geometrically growing
//!   sub-intervals `[u, 2u]` (the nearest singularities, `s = ±i·h`, stay well
//!   outside each sub-interval's Bernstein ellipse); this also covers a vertex on the
//!   line beyond the bar's end, where `h` is tiny or zero next to the distance;
//! - only for α < ½ and a vertex exactly on the bar (`h = 0`, foot inside) is the
//!   integral finite with a singular integrand; there `∫ |s|^{−2α} sᵏ ds` is taken
//!   in closed form. For α ≥ ½ such a vertex is never integrated: it lies on the bar
//!   and goes to the posed bar (see `precompute`).
//!
//! Sub-intervals use the 16-point Gauss–Legendre rule; for large α they are
//! subdivided further (the integrand's dynamic range on a sub-interval grows like
//! `2^{2α}`).

use glam::DVec2;

use crate::quadrature::RULE;

/// The three integrals of one bar at one vertex (already multiplied by the common
/// weight scale, see [`Weight`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Deltas {
    /// `∫ w (1 − t)² ds`.
    pub d00: f64,
    /// `∫ w (1 − t) t ds`.
    pub d01: f64,
    /// `∫ w t² ds`.
    pub d11: f64,
}

impl Deltas {
    /// Adds `weight · [(1 − t)², (1 − t) t, t²]`.
    #[inline]
    fn add(&mut self, weight: f64, t: f64, omt: f64) {
        let (t, omt) = (t.clamp(0.0, 1.0), omt.clamp(0.0, 1.0));
        self.d00 += weight * omt * omt;
        self.d01 += weight * omt * t;
        self.d11 += weight * t * t;
    }
}

/// The weight of a squared distance `x`: `(x · inv_scale2)^{−α}`. The scale is one
/// common factor for every control at a vertex (it cancels in every formula) and
/// keeps the largest point weight at 1, so nothing overflows.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Weight {
    /// The exponent α (> 0).
    pub alpha: f64,
    /// `1 / scale²`, pixels⁻².
    pub inv_scale2: f64,
}

impl Weight {
    /// `(x · inv_scale2)^{−α}`.
    #[inline]
    pub fn of_squared(&self, x: f64) -> f64 {
        let y = x * self.inv_scale2;
        if self.alpha == 1.0 {
            1.0 / y
        } else if self.alpha == 2.0 {
            1.0 / (y * y)
        } else {
            y.powf(-self.alpha)
        }
    }

    /// How many equal parts (in θ, or in `log |s|`) each basic sub-interval is cut
    /// into, so that the integrand's dynamic range on a part stays that of α ≈ 3.
    fn parts(&self) -> usize {
        ((self.alpha / 3.0).ceil() as usize).clamp(1, 64)
    }
}

/// Where a bar lies as seen from a vertex `v`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Frame {
    /// Distance from `v` to the bar's line, pixels.
    pub h: f64,
    /// Signed arc-length coordinate of the end `a`, from the foot of the
    /// perpendicular from `v`, pixels.
    pub s_a: f64,
    /// The same for the end `b` (`s_b > s_a`).
    pub s_b: f64,
    /// Squared distance from `v` to the nearest point of the bar, pixels².
    pub dist2: f64,
}

impl Frame {
    /// The frame of the bar `a → b` (`a ≠ b`) seen from `v`.
    pub fn new(v: DVec2, a: DVec2, b: DVec2) -> Frame {
        let dir = (b - a).normalize_or_zero();
        let (va, vb) = (a - v, b - v);
        let s_a = va.dot(dir);
        let s_b = vb.dot(dir);
        // The perpendicular distance from the nearer end loses the fewest digits.
        let h = if va.length_squared() <= vb.length_squared() {
            va.perp_dot(dir).abs()
        } else {
            vb.perp_dot(dir).abs()
        };
        let dist2 = if s_a >= 0.0 {
            va.length_squared()
        } else if s_b <= 0.0 {
            vb.length_squared()
        } else {
            h * h
        };
        Frame { h, s_a, s_b, dist2 }
    }

    /// The bar's parameter `t ∈ [0, 1]` of the point nearest to `v`.
    pub fn nearest_t(&self) -> f64 {
        let span = self.s_b - self.s_a;
        if span > 0.0 {
            (-self.s_a / span).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }
}

/// `δ00, δ01, δ11` of the bar with frame `frame` under `weight`.
///
/// The caller never asks for a vertex on the bar (`h = 0` with the foot inside)
/// with α ≥ ½, where the integrals diverge; those give infinities.
pub(crate) fn deltas(frame: &Frame, weight: &Weight) -> Deltas {
    let Frame { h, s_a, s_b, .. } = *frame;
    let span = s_b - s_a;
    let mut acc = Deltas::default();
    if span <= 0.0 {
        return acc;
    }
    let parts = weight.parts();

    // Core, |s| ≤ h, in θ.
    if h > 0.0 {
        let lo = s_a.max(-h);
        let hi = s_b.min(h);
        if lo < hi {
            let (t0, t1) = ((lo / h).atan(), (hi / h).atan());
            let step = (t1 - t0) / parts as f64;
            for part in 0..parts {
                let a = t0 + step * part as f64;
                let half = 0.5 * step;
                let mid = a + half;
                for &(x, wq) in RULE.iter() {
                    let theta = mid + half * x;
                    let (sin, cos) = theta.sin_cos();
                    let s = h * sin / cos;
                    let sec2 = 1.0 / (cos * cos);
                    // ds = h sec²θ dθ, |p − v|² = h² sec²θ.
                    let w = weight.of_squared(h * h * sec2) * h * sec2 * wq * half;
                    acc.add(w, (s - s_a) / span, (s_b - s) / span);
                }
            }
        }
    }

    // Flanks, |s| ≥ h: s = +u and s = −u.
    for sign in [1.0, -1.0] {
        let (lo, hi) = if sign > 0.0 {
            (s_a.max(h), s_b)
        } else {
            ((-s_b).max(h), -s_a)
        };
        if lo >= hi {
            continue;
        }
        if lo <= 0.0 {
            // h = 0 and the foot is on the bar: only finite for α < ½.
            closed_form_from_foot(&mut acc, sign, hi, s_a, s_b, weight);
            continue;
        }
        let mut a = lo;
        while a < hi {
            let b = if hi <= 2.5 * a { hi } else { 2.0 * a };
            // Cut [a, b] geometrically into `parts` pieces.
            let ratio = (b / a).powf(1.0 / parts as f64);
            let mut u0 = a;
            for part in 0..parts {
                let u1 = if part + 1 == parts { b } else { u0 * ratio };
                let half = 0.5 * (u1 - u0);
                let mid = u0 + half;
                for &(x, wq) in RULE.iter() {
                    let u = mid + half * x;
                    let s = sign * u;
                    let w = weight.of_squared(h * h + u * u) * wq * half;
                    acc.add(w, (s - s_a) / span, (s_b - s) / span);
                }
                u0 = u1;
            }
            a = b;
        }
    }
    acc
}

/// Adds `∫_0^U` over `u = |s|` on the side `sign` of the foot, for a vertex on the
/// bar's line with the foot inside the bar (`h = 0`): the weight is
/// `(u² · inv_scale2)^{−α}`, the integrands are quadratics in `u`, and
/// `∫_0^U u^{k−2α} du = U^{k+1−2α} / (k + 1 − 2α)` (finite for α < ½ only).
fn closed_form_from_foot(acc: &mut Deltas, sign: f64, big_u: f64, s_a: f64, s_b: f64, weight: &Weight) {
    let span = s_b - s_a;
    let beta = 1.0 - 2.0 * weight.alpha;
    if beta <= 0.0 {
        acc.d00 = f64::INFINITY;
        acc.d01 = f64::INFINITY;
        acc.d11 = f64::INFINITY;
        return;
    }
    let factor = weight.inv_scale2.powf(-weight.alpha);
    let m = [0.0, 1.0, 2.0].map(|k| big_u.powf(k + beta) / (k + beta) * factor);
    // t = t0 + t1 u, 1 − t = o0 + o1 u.
    let (t0, t1) = (-s_a / span, sign / span);
    let (o0, o1) = (s_b / span, -sign / span);
    acc.d00 += o0 * o0 * m[0] + 2.0 * o0 * o1 * m[1] + o1 * o1 * m[2];
    acc.d01 += t0 * o0 * m[0] + (t0 * o1 + t1 * o0) * m[1] + t1 * o1 * m[2];
    acc.d11 += t0 * t0 * m[0] + 2.0 * t0 * t1 * m[1] + t1 * t1 * m[2];
}

#[cfg(test)]
mod tests;
