//! The per-vertex part of moving least squares that depends on rest positions only
//! (§2.1–2.3 and §4 of the paper).
//!
//! At a vertex `v` every variant's answer is linear in the posed control positions
//! `q_j` (a posed point, or one end of a posed bar) — for rigid, the unnormalised
//! vector `f⃗_r(v)` and the centroid `q*` are. With the weighted centroid
//! `p* = Σ m_j y_j / Σ m_j` of the rest positions `y_j` (masses `m_j`: a point's
//! weight `w_i`; a bar's ends `δ00 + δ01` and `δ01 + δ11`), `p̂_j = y_j − p*`, and the
//! *moment vector* of each position
//!
//! ```text
//! point i:         e = w_i p̂_i
//! bar end a (c):   e = δ00 â + δ01 b̂
//! bar end b (d):   e = δ01 â + δ11 b̂
//! ```
//!
//! the paper's sums and integrals are `Σ_j p̂_jᵀ e_j` (the 2×2 moment matrix of
//! affine), `μ_s = Σ_j p̂_j · e_j` (similarity) and `Σ_j q̂_j ⊗ e_j` (both). Written
//! with complex numbers (a row vector times `[[α, β], [−β, α]]` is a complex product
//! by `α + iβ`), the paper's matrix `A_j` of §2.2 is the complex number
//! `conj(e_j)·(v − p*)`, so
//!
//! ```text
//! affine      f(v) = Σ_j (A_j + m_j/W) q_j,      A_j = (v − p*) G⁻¹ e_jᵀ   (real)
//! similarity  f(v) = Σ_j (c_j/μ_s + m_j/W) q_j,  c_j = conj(e_j)(v − p*)  (complex)
//! rigid       f(v) = |v − p*| f⃗/|f⃗| + q*,  f⃗ = Σ_j c_j q_j,  q* = Σ_j (m_j/W) q_j
//! ```
//!
//! (`q̂_j` may be replaced by `q_j` because `Σ_j e_j = 0`.) This module finds these
//! coefficients for one vertex; `table` stores them and applies a pose.

use glam::DVec2;

use crate::segment::{Deltas, Frame, Weight, deltas};
use crate::{Control, Variant};

/// Relative size of the on-control tolerance: a vertex within
/// `ON_CONTROL · (1 + |v|∞)` pixels of a point handle or of a bar counts as on it.
pub(crate) const ON_CONTROL: f64 = 1e-12;

/// The affine moment matrix `G` counts as singular when
/// `det G ≤ AFFINE_SINGULAR · (tr G)²` (its eigenvalues more than about 4·10¹²
/// apart).
pub(crate) const AFFINE_SINGULAR: f64 = 1e-12;

/// The on-control tolerance at `v`, pixels.
pub(crate) fn tolerance(v: DVec2) -> f64 {
    ON_CONTROL * (1.0 + v.abs().max_element())
}

/// One posed position's coefficients at one vertex.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Coef {
    /// Real part of the linear-part coefficient (affine `A_j`; similarity `c_j/μ_s`;
    /// rigid `c_j`).
    pub re: f64,
    /// Imaginary part of the same (0 for affine).
    pub im: f64,
    /// The centroid weight `m_j / W` (or, for a vertex on a control, the share of
    /// that posed position in the answer).
    pub om: f64,
}

/// How a vertex's coefficients combine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Header {
    /// On a control: `f(v) = Σ om_j q_j`.
    Snap,
    /// The linear part is undetermined (all controls at one rest position, as seen
    /// from `v`): `f(v) = (v − p*) + Σ om_j q_j`.
    Translation(DVec2),
    /// `f(v) = Σ (re_j + om_j) q_j`.
    Affine,
    /// `f(v) = Σ (re_j + i·im_j + om_j) ⊗ q_j`.
    Similarity,
    /// `f(v) = |d| f⃗/|f⃗| + Σ om_j q_j`, `f⃗ = Σ (re_j + i·im_j) ⊗ q_j`, `d = v − p*`;
    /// `spread = Σ |c_j|`, for telling a vanishing `f⃗` from rounding.
    Rigid {
        /// `v − p*`.
        d: DVec2,
        /// `Σ_j |c_j|`.
        spread: f64,
    },
}

/// Rest controls flattened for the per-vertex work.
#[derive(Clone, Debug)]
pub(crate) struct Rest {
    /// The controls as given.
    pub controls: Vec<Control>,
    /// Every rest position: a point's, or a bar's two ends (a then b).
    pub positions: Vec<DVec2>,
    /// Index in `positions` of each control's first position.
    pub first: Vec<usize>,
}

impl Rest {
    pub fn new(controls: &[Control]) -> Rest {
        let mut positions = Vec::with_capacity(controls.len() * 2);
        let mut first = Vec::with_capacity(controls.len());
        for control in controls {
            first.push(positions.len());
            match *control {
                Control::Point(p) => positions.push(p),
                Control::Bar([a, b]) => {
                    positions.push(a);
                    positions.push(b);
                }
            }
        }
        Rest {
            controls: controls.to_vec(),
            positions,
            first,
        }
    }
}

/// Reusable per-thread buffers.
#[derive(Default)]
pub(crate) struct Scratch {
    frames: Vec<Option<Frame>>,
    mass: Vec<f64>,
    moment: Vec<DVec2>,
    hat: Vec<DVec2>,
    deltas: Vec<Deltas>,
}

/// Fills `coef` (one per rest position) for vertex `v` and says how they combine.
pub(crate) fn fit_vertex(
    v: DVec2,
    rest: &Rest,
    alpha: f64,
    variant: Variant,
    scratch: &mut Scratch,
    coef: &mut [Coef],
) -> Header {
    coef.fill(Coef::default());
    let tol = tolerance(v);
    let tol2 = tol * tol;

    // On a point handle: the mean of the posed positions of all point handles
    // there (the limit of the least-squares fit as v approaches them).
    let on_point = |(control, _): &(&Control, &usize)| match control {
        Control::Point(p) => (*p - v).length_squared() <= tol2,
        Control::Bar(_) => false,
    };
    let on = rest.controls.iter().zip(&rest.first).filter(on_point).count();
    if on > 0 {
        let share = 1.0 / on as f64;
        for (_, j) in rest.controls.iter().zip(&rest.first).filter(on_point) {
            coef[*j].om = share;
        }
        return Header::Snap;
    }

    // Bar frames; on a bar (α ≥ ½, where the bar's weight diverges there): the
    // matching point of the posed bar(s).
    scratch.frames.clear();
    for control in &rest.controls {
        scratch.frames.push(match *control {
            Control::Point(_) => None,
            Control::Bar([a, b]) => Some(Frame::new(v, a, b)),
        });
    }
    if alpha >= 0.5 {
        let on = scratch
            .frames
            .iter()
            .flatten()
            .filter(|f| f.dist2 <= tol2)
            .count();
        if on > 0 {
            let share = 1.0 / on as f64;
            for (frame, j) in scratch.frames.iter().zip(&rest.first) {
                if let Some(frame) = frame
                    && frame.dist2 <= tol2
                {
                    let t = frame.nearest_t();
                    coef[*j].om += share * (1.0 - t);
                    coef[*j + 1].om += share * t;
                }
            }
            return Header::Snap;
        }
    }

    // The common weight scale: the nearest control at distance 1.
    let mut near2 = f64::INFINITY;
    for (control, frame) in rest.controls.iter().zip(&scratch.frames) {
        let d2 = match (control, frame) {
            (Control::Point(p), _) => (*p - v).length_squared(),
            (_, Some(frame)) => frame.dist2,
            _ => f64::INFINITY,
        };
        near2 = near2.min(d2);
    }
    let inv_scale2 = if near2 > 0.0 && (1.0 / near2).is_finite() {
        1.0 / near2
    } else {
        1.0
    };
    let weight = Weight {
        alpha,
        inv_scale2,
    };

    // Masses of the rest positions, and the bars' integrals.
    let k = rest.positions.len();
    scratch.mass.clear();
    scratch.mass.resize(k, 0.0);
    scratch.deltas.clear();
    let mut j = 0;
    for (control, frame) in rest.controls.iter().zip(&scratch.frames) {
        match (control, frame) {
            (Control::Point(p), _) => {
                scratch.mass[j] = weight.of_squared((*p - v).length_squared());
                j += 1;
            }
            (Control::Bar(_), Some(frame)) => {
                let d = deltas(frame, &weight);
                scratch.mass[j] = d.d00 + d.d01;
                scratch.mass[j + 1] = d.d01 + d.d11;
                scratch.deltas.push(d);
                j += 2;
            }
            (Control::Bar(_), None) => j += 2,
        }
    }
    let total: f64 = scratch.mass.iter().sum();
    if !(total > 0.0 && total.is_finite()) || scratch.mass.iter().any(|m| !m.is_finite()) {
        // Not reached for valid input (the nearest control has a weight of order
        // one); a defined answer all the same: translation by the mean motion.
        let share = 1.0 / k as f64;
        let mean = rest.positions.iter().copied().sum::<DVec2>() * share;
        for c in coef.iter_mut() {
            c.om = share;
        }
        return Header::Translation(v - mean);
    }

    // Differences from the heaviest position, so that a dominant mass does not
    // drown the others' p̂ in rounding.
    let mut heaviest = 0;
    for (i, m) in scratch.mass.iter().enumerate() {
        if *m > scratch.mass[heaviest] {
            heaviest = i;
        }
    }
    let origin = rest.positions[heaviest];
    let mut shift = DVec2::ZERO;
    for (y, m) in rest.positions.iter().zip(&scratch.mass) {
        shift += (*y - origin) * (*m / total);
    }
    // p* = origin + shift; v − p*:
    let d = (v - origin) - shift;
    scratch.hat.clear();
    scratch
        .hat
        .extend(rest.positions.iter().map(|y| (*y - origin) - shift));

    // Moment vectors e_j.
    scratch.moment.clear();
    scratch.moment.resize(k, DVec2::ZERO);
    let mut j = 0;
    let mut bars = scratch.deltas.iter();
    for control in &rest.controls {
        match control {
            Control::Point(_) => {
                scratch.moment[j] = scratch.hat[j] * scratch.mass[j];
                j += 1;
            }
            Control::Bar(_) => {
                let dl = bars.next().copied().unwrap_or_default();
                let (ah, bh) = (scratch.hat[j], scratch.hat[j + 1]);
                scratch.moment[j] = ah * dl.d00 + bh * dl.d01;
                scratch.moment[j + 1] = ah * dl.d01 + bh * dl.d11;
                j += 2;
            }
        }
    }
    for (c, m) in coef.iter_mut().zip(&scratch.mass) {
        c.om = *m / total;
    }

    if variant == Variant::Affine {
        // G = Σ p̂_jᵀ e_j (symmetric).
        let (mut g11, mut g12, mut g22) = (0.0, 0.0, 0.0);
        for (p, e) in scratch.hat.iter().zip(&scratch.moment) {
            g11 += p.x * e.x;
            g12 += 0.5 * (p.x * e.y + p.y * e.x);
            g22 += p.y * e.y;
        }
        let det = g11 * g22 - g12 * g12;
        let trace = g11 + g22;
        if trace > 0.0 && det > AFFINE_SINGULAR * trace * trace && det.is_finite() {
            // Row vector (v − p*) G⁻¹.
            let r = DVec2::new(d.x * g22 - d.y * g12, d.y * g11 - d.x * g12) / det;
            for (c, e) in coef.iter_mut().zip(&scratch.moment) {
                c.re = r.dot(*e);
            }
            return Header::Affine;
        }
        // Singular moment matrix (fewer than three non-collinear positions in
        // effect): the similarity fit, below.
    }

    // c_j = conj(e_j)·(v − p*).
    let mut mu = 0.0;
    for (p, e) in scratch.hat.iter().zip(&scratch.moment) {
        mu += p.dot(*e);
    }
    for (c, e) in coef.iter_mut().zip(&scratch.moment) {
        c.re = e.dot(d);
        c.im = e.perp_dot(d);
    }
    match variant {
        Variant::Rigid => {
            let spread = coef.iter().map(|c| c.re.hypot(c.im)).sum();
            Header::Rigid { d, spread }
        }
        Variant::Similarity | Variant::Affine => {
            if mu > 0.0 && mu.is_finite() {
                for c in coef.iter_mut() {
                    c.re /= mu;
                    c.im /= mu;
                }
                Header::Similarity
            } else {
                for c in coef.iter_mut() {
                    c.re = 0.0;
                    c.im = 0.0;
                }
                Header::Translation(d)
            }
        }
    }
}

/// Below this fraction of `Σ|c_j| · max|q_j − o|`, the rigid vector `f⃗` is taken
/// for zero (its direction would be rounding) and the vertex is translated by
/// `q* − p*`.
pub(crate) const RIGID_VANISHING: f64 = 1e-12;

/// The answer at one vertex from its coefficients and the posed positions, given as
/// `q_j − o` with `o` their mean and `reach = max_j |q_j − o|`.
pub(crate) fn apply(header: Header, coef: &[Coef], centred: &[DVec2], o: DVec2, reach: f64) -> DVec2 {
    match header {
        Header::Snap => o + sum_real(coef.iter().map(|c| c.om), centred),
        Header::Translation(d) => o + d + sum_real(coef.iter().map(|c| c.om), centred),
        Header::Affine => o + sum_real(coef.iter().map(|c| c.re + c.om), centred),
        Header::Similarity => {
            o + sum_complex(coef.iter().map(|c| (c.re + c.om, c.im)), centred)
        }
        Header::Rigid { d, spread } => {
            let f = sum_complex(coef.iter().map(|c| (c.re, c.im)), centred);
            let q_star = o + sum_real(coef.iter().map(|c| c.om), centred);
            rigid(f, q_star, d, spread, reach)
        }
    }
}

/// `|d| f/|f| + q*`, or `d + q*` where `f` vanishes.
#[inline]
pub(crate) fn rigid(f: DVec2, q_star: DVec2, d: DVec2, spread: f64, reach: f64) -> DVec2 {
    let len = f.length();
    if len > RIGID_VANISHING * spread * reach && len > 0.0 {
        q_star + f * (d.length() / len)
    } else {
        q_star + d
    }
}

fn sum_real(k: impl Iterator<Item = f64>, q: &[DVec2]) -> DVec2 {
    k.zip(q).fold(DVec2::ZERO, |acc, (k, q)| acc + *q * k)
}

fn sum_complex(k: impl Iterator<Item = (f64, f64)>, q: &[DVec2]) -> DVec2 {
    k.zip(q).fold(DVec2::ZERO, |acc, ((re, im), q)| {
        acc + DVec2::new(q.x * re - q.y * im, q.x * im + q.y * re)
    })
}
