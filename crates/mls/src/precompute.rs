//! The per-vertex part of moving least squares that depends on rest positions only
//! (§2.1–2.3 and §4 of the paper).
//!
//! At a vertex `v` every variant's answer is linear in the posed control positions
//! `q_j` (a posed point, or one end of a posed bar) — for rigid, the unnormalised
//! vector `f⃗_r(v)` and the centroid `q*` are. With the weights `w_i` of the point
//! handles, the bar integrals, the weighted centroid `p*`, `p̂ = p − p*`, and for each
//! posed position its *moment vector*
//!
//! ```text
//! point i:           e = w_i p̂_i
//! bar end a (→ c):   e = ∫ w p̂(t) (1 − t) ds   (= δ00 â + δ01 b̂ in the paper's terms)
//! bar end b (→ d):   e = ∫ w p̂(t) t ds         (= δ01 â + δ11 b̂)
//! ```
//!
//! the paper's sums over handles become sums over positions:
//! `Σ w_i p̂_iᵀ q̂_i = Σ_j e_jᵀ q_j` (affine), `Σ w_i q̂_i A_i = Σ_j q_j ⊗ conj(e_j)(v − p*)`
//! (similarity and rigid; a row vector times `[[α, β], [−β, α]]` is the complex
//! product by `α + iβ`, and the paper's `A_i` of §2.2 is `conj(w_i p̂_i)·(v − p*)`),
//! and `q* = Σ_j (m_j / W) q_j` with the masses `m_j` (`w_i`; `∫ w (1 − t)`,
//! `∫ w t`) and `W = Σ m_j`. (`q̂_j` may be replaced by `q_j` because `Σ_j e_j = 0`.)
//! So
//!
//! ```text
//! affine      f(v) = Σ_j (A_j + m_j/W) q_j,      A_j = (v − p*) G⁻¹ e_jᵀ   (real)
//! similarity  f(v) = Σ_j (c_j/μ_s + m_j/W) q_j,  c_j = conj(e_j)(v − p*)  (complex)
//! rigid       f(v) = |v − p*| f⃗/|f⃗| + q*,  f⃗ = Σ_j c_j q_j
//! ```
//!
//! with `G = Σ w_i p̂_iᵀ p̂_i + Σ_bars ∫ w p̂(t)ᵀ p̂(t) ds` and `μ_s` its trace.
//!
//! A bar's share of `p*`, `G` and `μ_s`, and its moment vectors, are taken from its
//! integrals about its point nearest to `v` ([`Moments`]) rather than from the
//! paper's `δ00, δ01, δ11` and the end offsets `â, b̂`: the two are equal, but near
//! the bar the latter form `∫ w |p̂|²` (of order `h^{1−2α}·h²`) as a difference of
//! terms of order `h^{1−2α}·L²` and lose every digit, where the former add terms of
//! the size of the result.

use glam::DVec2;

pub(crate) use crate::segment::Moments;
use crate::segment::{Frame, Weight, moments};
use crate::{Control, Variant};

/// Relative size of the on-control tolerance: a vertex within
/// `ON_CONTROL · (1 + |v|∞)` pixels of a point handle or of a bar counts as on it.
pub(crate) const ON_CONTROL: f64 = 1e-12;

/// The affine moment matrix `G` counts as singular when
/// `det G ≤ AFFINE_SINGULAR · (tr G)²` (its eigenvalues about 4·10¹³ or more apart;
/// exactly singular matrices come out near 1e-16 after rounding).
pub(crate) const AFFINE_SINGULAR: f64 = 1e-13;

/// Below this fraction of `Σ|c_j| · max|q_j − o|`, the rigid vector `f⃗` is taken
/// for zero (its direction would be rounding) and the vertex is translated by
/// `q* − p*`.
pub(crate) const RIGID_VANISHING: f64 = 1e-12;

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
    /// `f(v) = |d| f⃗/|f⃗| + Σ om_j q_j`, `f⃗ = Σ (re_j + i·im_j) ⊗ q_j`, `d = v − p*`.
    Rigid {
        /// `v − p*`.
        d: DVec2,
        /// `Σ_j |c_j|`, for telling a vanishing `f⃗` from rounding.
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

/// A control as the fit at one vertex sees it: an anchor point, a direction (zero
/// for a point handle) and its integrals about the anchor. A point handle is an
/// element whose only non-zero moment is `a0 = w_i`.
#[derive(Clone, Copy, Debug)]
struct Element {
    /// Index of its first posed position.
    first: usize,
    /// Whether it has a second (a bar).
    bar: bool,
    anchor: DVec2,
    dir: DVec2,
    m: Moments,
}

/// Reusable per-thread buffers.
#[derive(Default)]
pub(crate) struct Scratch {
    frames: Vec<Option<Frame>>,
    elements: Vec<Element>,
    moment: Vec<DVec2>,
}

/// `1 / d²`, or 1 where that is not finite (`d` zero: a vertex on the control).
fn inverse_scale(d2: f64) -> f64 {
    if d2 > 0.0 && (1.0 / d2).is_finite() {
        1.0 / d2
    } else {
        1.0
    }
}

/// The integrals ([`Moments`]) at vertex `v` of the bar from `a` to `b`, with the
/// weights scaled so that the bar's point nearest to the vertex is at distance 1: a
/// function of the vertex and the bar alone, which a table built again for other
/// controls can keep ([`crate::Mls::renewed`]). [`fit_vertex`] scales them to the
/// vertex's common scale.
pub(crate) fn bar_moments(v: DVec2, [a, b]: [DVec2; 2], alpha: f64) -> Moments {
    let frame = Frame::new(v, a, b);
    moments(
        &frame,
        &Weight {
            alpha,
            inv_scale2: inverse_scale(frame.dist2),
        },
    )
}

/// Fills `coef` (one per rest position) for vertex `v` and says how they combine.
/// `bars` holds [`bar_moments`] at `v` of each bar among the controls, in order.
pub(crate) fn fit_vertex(
    v: DVec2,
    rest: &Rest,
    alpha: f64,
    variant: Variant,
    bars: &[Moments],
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
    let on = rest
        .controls
        .iter()
        .zip(&rest.first)
        .filter(on_point)
        .count();
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
    let weight = Weight {
        alpha,
        inv_scale2: inverse_scale(near2),
    };

    // Every control as an element.
    scratch.elements.clear();
    let mut bars = bars.iter();
    for ((control, frame), first) in rest.controls.iter().zip(&scratch.frames).zip(&rest.first) {
        let bar = match control {
            Control::Bar(_) => bars.next().copied().unwrap_or_default(),
            Control::Point(_) => Moments::default(),
        };
        let element = match (*control, frame) {
            (Control::Point(p), _) => Element {
                first: *first,
                bar: false,
                anchor: p,
                dir: DVec2::ZERO,
                m: Moments {
                    a0: weight.of_squared((p - v).length_squared()),
                    ..Moments::default()
                },
            },
            (Control::Bar([a, b]), Some(frame)) => Element {
                first: *first,
                bar: true,
                anchor: frame.nearest(a, b),
                dir: frame.dir,
                // From the bar's own scale to the common one: the weights differ by
                // a constant factor.
                m: bar.scaled(weight.of_squared(1.0 / inverse_scale(frame.dist2))),
            },
            (Control::Bar([a, _]), None) => Element {
                first: *first,
                bar: true,
                anchor: a,
                dir: DVec2::ZERO,
                m: Moments::default(),
            },
        };
        scratch.elements.push(element);
    }
    let total: f64 = scratch.elements.iter().map(|e| e.m.a0 + e.m.a1).sum();
    let finite = scratch.elements.iter().all(|e| {
        let m = e.m;
        (m.a0 + m.a1 + m.b0.abs() + m.b1.abs() + m.c).is_finite()
    });
    if !(total > 0.0 && total.is_finite() && finite) {
        // Not reached for valid input (the nearest control has a weight of order
        // one); a defined answer all the same: translation by the mean motion.
        let share = 1.0 / rest.positions.len() as f64;
        let mean = rest.positions.iter().copied().sum::<DVec2>() * share;
        for c in coef.iter_mut() {
            c.om = share;
        }
        return Header::Translation(v - mean);
    }

    // The weighted centroid p*, relative to the anchor of the heaviest element so
    // that a dominant weight does not drown the others' offsets in rounding.
    let heaviest = scratch
        .elements
        .iter()
        .enumerate()
        .max_by(|(_, x), (_, y)| (x.m.a0 + x.m.a1).total_cmp(&(y.m.a0 + y.m.a1)))
        .map_or(0, |(i, _)| i);
    let origin = scratch.elements[heaviest].anchor;
    let mut shift = DVec2::ZERO;
    for e in &scratch.elements {
        let (m0, m1) = (e.m.a0 + e.m.a1, e.m.b0 + e.m.b1);
        shift += (e.anchor - origin) * (m0 / total) + e.dir * (m1 / total);
    }
    // v − p*.
    let d = (v - origin) - shift;

    // Moment vectors e_j, the moment matrix G and μ_s = tr G.
    scratch.moment.clear();
    scratch.moment.resize(rest.positions.len(), DVec2::ZERO);
    let (mut g11, mut g12, mut g22) = (0.0, 0.0, 0.0);
    for e in &scratch.elements {
        let Moments { a0, a1, b0, b1, c } = e.m;
        let (m0, m1) = (a0 + a1, b0 + b1);
        // p̂ at the anchor; along the bar p̂ = f + σ·dir.
        let f = (e.anchor - origin) - shift;
        let u = e.dir;
        g11 += m0 * f.x * f.x + 2.0 * m1 * f.x * u.x + c * u.x * u.x;
        g12 += m0 * f.x * f.y + m1 * (f.x * u.y + u.x * f.y) + c * u.x * u.y;
        g22 += m0 * f.y * f.y + 2.0 * m1 * f.y * u.y + c * u.y * u.y;
        scratch.moment[e.first] = f * a0 + u * b0;
        coef[e.first].om = a0 / total;
        if e.bar {
            scratch.moment[e.first + 1] = f * a1 + u * b1;
            coef[e.first + 1].om = a1 / total;
        }
    }

    if variant == Variant::Affine {
        let det = g11 * g22 - g12 * g12;
        let trace = g11 + g22;
        if trace > 0.0 && det > AFFINE_SINGULAR * trace * trace && det.is_finite() {
            // The row vector (v − p*) G⁻¹.
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
    for (c, e) in coef.iter_mut().zip(&scratch.moment) {
        c.re = e.dot(d);
        c.im = e.perp_dot(d);
    }
    match variant {
        Variant::Rigid => {
            // (`hypot`'s guard against overflow is not needed at these sizes, and it
            // took a fifth of a precomputation.)
            let spread = coef
                .iter()
                .map(|c| (c.re * c.re + c.im * c.im).sqrt())
                .sum();
            Header::Rigid { d, spread }
        }
        Variant::Similarity | Variant::Affine => {
            let mu = g11 + g22;
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

/// The answer at one vertex from its coefficients and the posed positions, given as
/// `q_j − o` with `o` their mean and `reach = max_j |q_j − o|`.
pub(crate) fn apply(
    header: Header,
    coef: &[Coef],
    centred: &[DVec2],
    o: DVec2,
    reach: f64,
) -> DVec2 {
    match header {
        Header::Snap => o + sum_real(coef.iter().map(|c| c.om), centred),
        Header::Translation(d) => o + d + sum_real(coef.iter().map(|c| c.om), centred),
        Header::Affine => o + sum_real(coef.iter().map(|c| c.re + c.om), centred),
        Header::Similarity => o + sum_complex(coef.iter().map(|c| (c.re + c.om, c.im)), centred),
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
