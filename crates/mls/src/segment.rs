//! The integrals a bar (line-segment handle) contributes at one vertex (§4 of the
//! paper). With the rest bar `p(t) = (1 − t)·a + t·b`, `t ∈ [0, 1]`, of length `L`,
//! the weight `w = 1 / |p(t) − v|^{2α}` is integrated with respect to arc length
//! (`ds = L dt`); the paper's `W` matrix holds
//!
//! ```text
//! δ00 = ∫ w (1 − t)² ds,   δ01 = ∫ w (1 − t) t ds,   δ11 = ∫ w t² ds.
//! ```
//!
//! The deformation itself uses the same integrals regrouped as moments about the
//! bar's point nearest to the vertex ([`Moments`]); see `precompute` for why.
//!
//! Every integral is computed to a relative accuracy of about 1e-13 for any α > 0
//! and any position of the vertex (the paper's closed forms hold for α = 2 only and
//! cancel badly near the bar's line). With `h` the distance from `v` to the bar's
//! line and `s` the signed arc-length coordinate from the foot of the
//! perpendicular, `|p − v|² = h² + s²`, and the range of `s` is cut in three:
//! - the *core* `|s| ≤ h`, integrated in `θ` with `s = h·tan θ` (`|θ| ≤ π/4`), where
//!   the integrand `h·sec²θ·(h·sec θ)^{−2α}·g(h tan θ)` is smooth;
//! - each *flank* `|s| ≥ h`, integrated in `|s|` on geometrically growing
//!   sub-intervals `[u, 2u]` (the nearest singularities, `s = ±i·h`, stay well
//!   outside each sub-interval's Bernstein ellipse); this also covers a vertex on the
//!   line beyond the bar's end, where `h` is tiny or zero next to the distance;
//! - only for α < ½ and a vertex exactly on the bar (`h = 0`, foot inside) is the
//!   integral finite with a singular integrand `|s|^{−2α}·g(s)`; there the 2-point
//!   Gauss–Jacobi rule for the weight `|s|^{−2α}` is exact (every `g` here is a
//!   polynomial of degree ≤ 2). For α ≥ ½ such a vertex is never integrated: it lies
//!   on the bar and goes to the posed bar (see `precompute`).
//!
//! Sub-intervals use the 16-point Gauss–Legendre rule; for α > 3 they are cut into
//! `⌈α/3⌉` parts (the integrand's dynamic range on a sub-interval grows like
//! `2^{2α}`).

use glam::DVec2;

use crate::quadrature::RULE;

/// The three integrals of one bar at one vertex (already multiplied by the common
/// weight scale, see [`Weight`]).
#[cfg(test)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Deltas {
    /// `∫ w (1 − t)² ds`.
    pub d00: f64,
    /// `∫ w (1 − t) t ds`.
    pub d01: f64,
    /// `∫ w t² ds`.
    pub d11: f64,
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
    /// The coordinate of the bar's point nearest to `v`: `0` clamped to
    /// `[s_a, s_b]`.
    pub s_c: f64,
    /// Squared distance from `v` to the nearest point of the bar, pixels².
    pub dist2: f64,
    /// Unit vector from `a` to `b`.
    pub dir: DVec2,
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
        let (s_c, dist2) = if s_a >= 0.0 {
            (s_a, va.length_squared())
        } else if s_b <= 0.0 {
            (s_b, vb.length_squared())
        } else {
            (0.0, h * h)
        };
        Frame {
            h,
            s_a,
            s_b,
            s_c,
            dist2,
            dir,
        }
    }

    /// The bar's parameter `t ∈ [0, 1]` of the point nearest to `v`.
    pub fn nearest_t(&self) -> f64 {
        let span = self.s_b - self.s_a;
        if span > 0.0 {
            ((self.s_c - self.s_a) / span).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }

    /// The bar's point nearest to `v` (an end exactly where it is one).
    pub fn nearest(&self, a: DVec2, b: DVec2) -> DVec2 {
        if self.s_c == self.s_a {
            a
        } else if self.s_c == self.s_b {
            b
        } else {
            a - self.dir * self.s_a
        }
    }
}

/// Calls `visit(s, w)` for the nodes of a quadrature of `∫ w(s) g(s) ds` over the
/// bar, for any smooth `g`: `s` is the signed arc-length coordinate from the foot
/// of the perpendicular, `w` the node's share (the quadrature weight times the
/// Jacobian times the weight function). See the module documentation.
///
/// The caller never asks for a vertex on the bar (`h = 0` with the foot inside)
/// with α ≥ ½, where the integrals diverge; those visit infinite weights.
fn visit_nodes(frame: &Frame, weight: &Weight, mut visit: impl FnMut(f64, f64)) {
    let Frame { h, s_a, s_b, .. } = *frame;
    if s_b <= s_a {
        return;
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
                let half = 0.5 * step;
                let mid = t0 + step * part as f64 + half;
                for &(x, wq) in RULE.iter() {
                    let theta = mid + half * x;
                    let (sin, cos) = theta.sin_cos();
                    let sec2 = 1.0 / (cos * cos);
                    // s = h tan θ, ds = h sec²θ dθ, |p − v|² = h² sec²θ.
                    visit(
                        h * sin / cos,
                        weight.of_squared(h * h * sec2) * h * sec2 * wq * half,
                    );
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
            visit_from_foot(sign, hi, weight, &mut visit);
            continue;
        }
        let mut a = lo;
        while a < hi {
            let b = if hi <= 2.5 * a { hi } else { 2.0 * a };
            // Cut [a, b] geometrically into `parts` pieces (one: [a, b] itself).
            let ratio = if parts > 1 {
                (b / a).powf(1.0 / parts as f64)
            } else {
                1.0
            };
            let mut u0 = a;
            for part in 0..parts {
                let u1 = if part + 1 == parts { b } else { u0 * ratio };
                let half = 0.5 * (u1 - u0);
                let mid = u0 + half;
                for &(x, wq) in RULE.iter() {
                    let u = mid + half * x;
                    visit(sign * u, weight.of_squared(h * h + u * u) * wq * half);
                }
                u0 = u1;
            }
            a = b;
        }
    }
}

/// The nodes of `∫_0^U` over `u = |s|` on the side `sign` of the foot, for a vertex
/// on the bar's line with the foot inside the bar (`h = 0`), where the weight is
/// `(u² · inv_scale2)^{−α} = inv_scale2^{−α} · u^{−2α}`: the 2-point Gauss–Jacobi
/// rule for the weight `x^{−2α}` on [0, 1], exact for the cubics and lower that the
/// callers integrate (finite for α < ½ only).
fn visit_from_foot(sign: f64, big_u: f64, weight: &Weight, visit: &mut impl FnMut(f64, f64)) {
    let beta = -2.0 * weight.alpha;
    if beta <= -1.0 {
        visit(0.0, f64::INFINITY);
        return;
    }
    // Moments m_k = ∫_0^1 x^{k+β} dx; the monic orthogonal quadratic x² + p x + q.
    let m = [0.0, 1.0, 2.0, 3.0].map(|k| 1.0 / (k + 1.0 + beta));
    let det = m[1] * m[1] - m[0] * m[2];
    let p = (m[0] * m[3] - m[1] * m[2]) / det;
    let q = (m[2] * m[2] - m[1] * m[3]) / det;
    let root = (0.25 * p * p - q).max(0.0).sqrt();
    let (x1, x2) = (-0.5 * p - root, -0.5 * p + root);
    let w2 = (m[1] - x1 * m[0]) / (x2 - x1);
    let w1 = m[0] - w2;
    let scale = big_u.powf(1.0 + beta) * weight.inv_scale2.powf(-weight.alpha);
    visit(sign * big_u * x1, w1 * scale);
    visit(sign * big_u * x2, w2 * scale);
}

/// `δ00, δ01, δ11` of the bar with frame `frame` under `weight` (the paper's `W`
/// matrix entries, §4).
#[cfg(test)]
pub(crate) fn deltas(frame: &Frame, weight: &Weight) -> Deltas {
    let Frame { s_a, s_b, .. } = *frame;
    let span = s_b - s_a;
    let mut acc = Deltas::default();
    visit_nodes(frame, weight, |s, w| {
        let (t, omt) = (
            ((s - s_a) / span).clamp(0.0, 1.0),
            ((s_b - s) / span).clamp(0.0, 1.0),
        );
        acc.d00 += w * omt * omt;
        acc.d01 += w * omt * t;
        acc.d11 += w * t * t;
    });
    acc
}

/// A bar's integrals at one vertex about its point nearest to the vertex: with
/// `σ = s − s_c` the arc-length coordinate from that point,
/// `a0 = ∫ w (1 − t)`, `a1 = ∫ w t`, `b0 = ∫ w σ (1 − t)`, `b1 = ∫ w σ t`,
/// `c = ∫ w σ²` (all `ds`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Moments {
    pub a0: f64,
    pub a1: f64,
    pub b0: f64,
    pub b1: f64,
    pub c: f64,
}

impl Moments {
    /// Every integral times `factor` (the same integrals under weights `factor` times
    /// as large).
    pub fn scaled(self, factor: f64) -> Moments {
        Moments {
            a0: self.a0 * factor,
            a1: self.a1 * factor,
            b0: self.b0 * factor,
            b1: self.b1 * factor,
            c: self.c * factor,
        }
    }
}

/// The [`Moments`] of the bar with frame `frame` under `weight`.
pub(crate) fn moments(frame: &Frame, weight: &Weight) -> Moments {
    let Frame { s_a, s_b, s_c, .. } = *frame;
    let span = s_b - s_a;
    let mut acc = Moments::default();
    visit_nodes(frame, weight, |s, w| {
        let (t, omt) = (
            ((s - s_a) / span).clamp(0.0, 1.0),
            ((s_b - s) / span).clamp(0.0, 1.0),
        );
        let sigma = s - s_c;
        acc.a0 += w * omt;
        acc.a1 += w * t;
        acc.b0 += w * sigma * omt;
        acc.b1 += w * sigma * t;
        acc.c += w * sigma * sigma;
    });
    acc
}

#[cfg(test)]
mod tests;
