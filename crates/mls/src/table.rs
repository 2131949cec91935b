//! The precomputed deformation of a set of rest vertices ([`Mls`]): validation, the
//! per-vertex coefficient tables, and applying a pose.

use std::sync::Arc;

use glam::DVec2;
use rayon::prelude::*;

use crate::precompute::{
    Coef, Header, Moments, Rest, Scratch, apply, bar_moments, fit_vertex, rigid, tolerance,
};
use crate::{Control, MlsError, MlsOptions, Variant};

/// Vertices per parallel work item.
const CHUNK: usize = 1024;

/// A table keeps its bars' integrals at every vertex (for [`Mls::renewed`]) while
/// they number at most this many (40 bytes each: 40 MiB).
const KEPT_INTEGRALS: usize = 1 << 20;

/// Moving least squares deformation, precomputed for one set of rest vertices and
/// rest controls (positions in pixels, image space).
///
/// [`Mls::new`] does all the work that depends on rest positions only: the weights
/// (including the bars' integrals), centroids and moment matrices, leaving per
/// vertex one small coefficient per posed control position (a point, or each end
/// of a bar). [`Mls::deform`] then costs a few multiply-adds per vertex and
/// control position, in parallel over vertices.
///
/// ```
/// use glam::DVec2;
/// use mls::{Control, Mls, MlsOptions};
///
/// // A horizontal strip of vertices, held at its left end and a bar along its
/// // right half.
/// let vertices: Vec<DVec2> = (0..=10).map(|i| DVec2::new(10.0 * i as f64, 0.0)).collect();
/// let rest = [
///     Control::Point(DVec2::new(0.0, 0.0)),
///     Control::Bar([DVec2::new(50.0, 0.0), DVec2::new(100.0, 0.0)]),
/// ];
/// let mls = Mls::new(&vertices, &rest, &MlsOptions::default())?; // rigid, α = 1
///
/// // Bend the bar upwards.
/// let posed = [
///     Control::Point(DVec2::new(0.0, 0.0)),
///     Control::Bar([DVec2::new(50.0, 0.0), DVec2::new(85.0, 35.0)]),
/// ];
/// let mut out = vec![DVec2::ZERO; vertices.len()];
/// mls.deform(&posed, &mut out)?;
/// assert!(out[0].length() < 1e-9); // on the point handle
/// assert!((out[10] - DVec2::new(85.0, 35.0)).length() < 1e-9); // on the bar's end
/// assert!((out[8] - DVec2::new(71.0, 21.0)).length() < 1e-9); // 3/5 along the bar
/// # Ok::<(), mls::MlsError>(())
/// ```
#[derive(Clone, Debug)]
pub struct Mls {
    /// Whether each control is a bar (the pose must have the same shape).
    bars: Vec<bool>,
    /// Number of control positions `K` (points, plus two per bar).
    positions: usize,
    /// Number of vertices.
    vertices: usize,
    options: MlsOptions,
    table: Table,
    /// The bars' integrals at every vertex, where kept.
    kept: Option<Kept>,
}

/// What a table keeps of its precomputation for the next one: each bar's integrals
/// at every vertex ([`bar_moments`]), which depend on the vertex, the bar and α alone.
/// Adding a point handle then costs the fits, not the bars' quadrature again.
#[derive(Clone, Debug)]
struct Kept {
    vertices: Arc<[DVec2]>,
    alpha: f64,
    /// Each bar's ends, and its integrals per vertex.
    bars: Vec<([DVec2; 2], Arc<[Moments]>)>,
}

/// Per-vertex coefficients, `K` per vertex, vertex-major.
#[derive(Clone, Debug)]
enum Table {
    /// No controls: every vertex stays put.
    Identity(Vec<DVec2>),
    /// Affine (no vertex fell back to similarity): `f = o + Σ k_j (q_j − o)`.
    Real(Vec<f64>),
    /// Similarity, or affine with fallbacks: `f = o + offset + Σ k_j ⊗ (q_j − o)`.
    Complex {
        k: Vec<[f64; 2]>,
        offset: Vec<DVec2>,
    },
    /// Rigid: `c_j` and `ω_j` per position, `v − p*` and `Σ|c_j|` per vertex.
    Rigid {
        c: Vec<[f64; 3]>,
        frame: Vec<[f64; 3]>,
    },
}

impl Mls {
    /// Precomputes the deformation of `vertices` (rest positions, pixels) by
    /// `controls` (rest positions of the handles, pixels) under `options`.
    ///
    /// Errors: α not finite and positive, a non-finite vertex or control, a bar of
    /// zero length ([`MlsError::ZeroLengthBar`]). No controls is allowed (every pose
    /// is then the identity).
    pub fn new(
        vertices: &[DVec2],
        controls: &[Control],
        options: &MlsOptions,
    ) -> Result<Mls, MlsError> {
        Self::build(vertices, controls, options, None, KEPT_INTEGRALS)
    }

    /// [`Mls::new`] for other controls or options, taking the bars' integrals this
    /// table kept where `vertices`, α and a bar are the same: the answer is the very
    /// same, in less time (a bar's quadrature is most of a precomputation).
    ///
    /// Errors: as [`Mls::new`].
    pub fn renewed(
        &self,
        vertices: &[DVec2],
        controls: &[Control],
        options: &MlsOptions,
    ) -> Result<Mls, MlsError> {
        Self::build(
            vertices,
            controls,
            options,
            self.kept.as_ref(),
            KEPT_INTEGRALS,
        )
    }

    /// [`Mls::new`], reusing `previous` where it applies, keeping the bars' integrals
    /// while there are at most `keep` of them.
    fn build(
        vertices: &[DVec2],
        controls: &[Control],
        options: &MlsOptions,
        previous: Option<&Kept>,
        keep: usize,
    ) -> Result<Mls, MlsError> {
        validate_options(options)?;
        if let Some(vertex) = vertices.iter().position(|v| !v.is_finite()) {
            return Err(MlsError::NonFiniteVertex { vertex });
        }
        validate_rest(controls)?;
        let rest = Rest::new(controls);
        let k = rest.positions.len();
        let n = vertices.len();
        let bars = controls
            .iter()
            .map(|c| matches!(c, Control::Bar(_)))
            .collect();
        if k == 0 {
            return Ok(Mls {
                bars,
                positions: 0,
                vertices: n,
                options: *options,
                table: Table::Identity(vertices.to_vec()),
                kept: None,
            });
        }
        let alpha = options.alpha;
        let ends: Vec<[DVec2; 2]> = controls
            .iter()
            .filter_map(|c| match *c {
                Control::Bar(ends) => Some(ends),
                Control::Point(_) => None,
            })
            .collect();
        // The bars' integrals at every vertex, taken from `previous` or worked out
        // (where they are to be kept; otherwise each vertex works out its own).
        let kept = (n * ends.len() <= keep && !ends.is_empty()).then(|| {
            let previous =
                previous.filter(|p| p.alpha == alpha && same_bits(&p.vertices, vertices));
            let vertices: Arc<[DVec2]> = match previous {
                Some(p) => p.vertices.clone(),
                None => vertices.into(),
            };
            let bars = ends
                .iter()
                .map(|&[a, b]| {
                    let known = previous
                        .and_then(|p| p.bars.iter().find(|(e, _)| same_bits(e, &[a, b])))
                        .map(|(_, m)| m.clone());
                    let column = known.unwrap_or_else(|| {
                        vertices
                            .par_iter()
                            .map(|&v| bar_moments(v, [a, b], alpha))
                            .collect()
                    });
                    ([a, b], column)
                })
                .collect();
            Kept {
                vertices,
                alpha,
                bars,
            }
        });

        let mut coef = vec![Coef::default(); n * k];
        let mut headers = vec![Header::Snap; n];
        coef.par_chunks_mut(CHUNK * k)
            .zip(headers.par_chunks_mut(CHUNK))
            .zip(vertices.par_chunks(CHUNK))
            .enumerate()
            .for_each_init(
                || (Scratch::default(), Vec::new()),
                |(scratch, moments), (chunk, ((coef, headers), vertices))| {
                    let rows = vertices.iter().zip(headers).zip(coef.chunks_mut(k));
                    for (i, ((v, header), coef)) in rows.enumerate() {
                        moments.clear();
                        match &kept {
                            Some(kept) => {
                                moments.extend(kept.bars.iter().map(|(_, m)| m[chunk * CHUNK + i]))
                            }
                            None => moments
                                .extend(ends.iter().map(|&ends| bar_moments(*v, ends, alpha))),
                        }
                        *header =
                            fit_vertex(*v, &rest, alpha, options.variant, moments, scratch, coef);
                    }
                },
            );

        let table = match options.variant {
            Variant::Rigid => {
                let c = coef.par_iter().map(|c| [c.re, c.im, c.om]).collect();
                let frame = headers
                    .par_iter()
                    .map(|h| match *h {
                        Header::Rigid { d, spread } => [d.x, d.y, spread],
                        Header::Translation(d) => [d.x, d.y, 0.0],
                        _ => [0.0; 3],
                    })
                    .collect();
                Table::Rigid { c, frame }
            }
            Variant::Affine
                if headers
                    .iter()
                    .all(|h| matches!(h, Header::Affine | Header::Snap)) =>
            {
                Table::Real(coef.par_iter().map(|c| c.re + c.om).collect())
            }
            Variant::Affine | Variant::Similarity => {
                let k = coef.par_iter().map(|c| [c.re + c.om, c.im]).collect();
                let offset = headers
                    .par_iter()
                    .map(|h| match *h {
                        Header::Translation(d) => d,
                        _ => DVec2::ZERO,
                    })
                    .collect();
                Table::Complex { k, offset }
            }
        };
        Ok(Mls {
            bars,
            positions: k,
            vertices: n,
            options: *options,
            table,
            kept,
        })
    }

    /// Number of vertices this deformation moves.
    pub fn vertex_count(&self) -> usize {
        self.vertices
    }

    /// The options it was built with.
    pub fn options(&self) -> &MlsOptions {
        &self.options
    }

    /// Writes the deformed position of every vertex (pixels) into `out`, for the
    /// controls at `posed` (same number and kinds as the rest controls, in the same
    /// order; a posed bar's ends match the rest bar's ends in order).
    ///
    /// Errors: a pose of the wrong shape, a non-finite posed position, an `out` of the
    /// wrong length. Never writes NaN for valid input.
    pub fn deform(&self, posed: &[Control], out: &mut [DVec2]) -> Result<(), MlsError> {
        if out.len() != self.vertices {
            return Err(MlsError::OutputLength {
                got: out.len(),
                vertices: self.vertices,
            });
        }
        let q = flatten_pose(&self.bars, posed)?;
        let (o, centred, reach) = centre(&q);
        let k = self.positions;
        match &self.table {
            Table::Identity(rest) => out.copy_from_slice(rest),
            Table::Real(coef) => {
                out.par_chunks_mut(CHUNK)
                    .zip(coef.par_chunks(CHUNK * k))
                    .for_each(|(out, coef)| {
                        for (f, coef) in out.iter_mut().zip(coef.chunks_exact(k)) {
                            let mut acc = o;
                            for (kj, qj) in coef.iter().zip(&centred) {
                                acc += *qj * *kj;
                            }
                            *f = acc;
                        }
                    });
            }
            Table::Complex { k: coef, offset } => {
                out.par_chunks_mut(CHUNK)
                    .zip(coef.par_chunks(CHUNK * k))
                    .zip(offset.par_chunks(CHUNK))
                    .for_each(|((out, coef), offset)| {
                        for ((f, coef), off) in out.iter_mut().zip(coef.chunks_exact(k)).zip(offset)
                        {
                            let (mut x, mut y) = (o.x + off.x, o.y + off.y);
                            for ([re, im], qj) in coef.iter().zip(&centred) {
                                x += qj.x * re - qj.y * im;
                                y += qj.x * im + qj.y * re;
                            }
                            *f = DVec2::new(x, y);
                        }
                    });
            }
            Table::Rigid { c, frame } => {
                out.par_chunks_mut(CHUNK)
                    .zip(c.par_chunks(CHUNK * k))
                    .zip(frame.par_chunks(CHUNK))
                    .for_each(|((out, coef), frame)| {
                        for ((f, coef), [dx, dy, spread]) in
                            out.iter_mut().zip(coef.chunks_exact(k)).zip(frame)
                        {
                            let (mut fx, mut fy, mut sx, mut sy) = (0.0, 0.0, 0.0, 0.0);
                            for ([re, im, om], qj) in coef.iter().zip(&centred) {
                                fx += qj.x * re - qj.y * im;
                                fy += qj.x * im + qj.y * re;
                                sx += qj.x * om;
                                sy += qj.y * om;
                            }
                            *f = rigid(
                                DVec2::new(fx, fy),
                                o + DVec2::new(sx, sy),
                                DVec2::new(*dx, *dy),
                                *spread,
                                reach,
                            );
                        }
                    });
            }
        }
        Ok(())
    }
}

/// The deformed position (pixels) of one point `v` for rest controls `controls`
/// and posed controls `posed`, without a precomputed table: the same answer as
/// [`Mls::new`] on `[v]` followed by [`Mls::deform`], at the cost of the whole
/// per-vertex fit. Errors as those two.
pub fn deform_point(
    v: DVec2,
    controls: &[Control],
    posed: &[Control],
    options: &MlsOptions,
) -> Result<DVec2, MlsError> {
    validate_options(options)?;
    if !v.is_finite() {
        return Err(MlsError::NonFiniteVertex { vertex: 0 });
    }
    validate_rest(controls)?;
    let bars: Vec<bool> = controls
        .iter()
        .map(|c| matches!(c, Control::Bar(_)))
        .collect();
    let q = flatten_pose(&bars, posed)?;
    if q.is_empty() {
        return Ok(v);
    }
    let rest = Rest::new(controls);
    let mut coef = vec![Coef::default(); q.len()];
    let moments: Vec<Moments> = controls
        .iter()
        .filter_map(|c| match *c {
            Control::Bar(ends) => Some(bar_moments(v, ends, options.alpha)),
            Control::Point(_) => None,
        })
        .collect();
    let header = fit_vertex(
        v,
        &rest,
        options.alpha,
        options.variant,
        &moments,
        &mut Scratch::default(),
        &mut coef,
    );
    let (o, centred, reach) = centre(&q);
    Ok(apply(header, &coef, &centred, o, reach))
}

/// Whether two lists of points are the same to the bit (so that what was worked out
/// from one is what the other would give, signed zeros included).
fn same_bits(a: &[DVec2], b: &[DVec2]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(p, q)| p.x.to_bits() == q.x.to_bits() && p.y.to_bits() == q.y.to_bits())
}

fn validate_options(options: &MlsOptions) -> Result<(), MlsError> {
    if options.alpha.is_finite() && options.alpha > 0.0 {
        Ok(())
    } else {
        Err(MlsError::InvalidAlpha {
            alpha: options.alpha,
        })
    }
}

fn validate_rest(controls: &[Control]) -> Result<(), MlsError> {
    for (control, c) in controls.iter().enumerate() {
        match *c {
            Control::Point(p) => {
                if !p.is_finite() {
                    return Err(MlsError::NonFiniteControl { control });
                }
            }
            Control::Bar([a, b]) => {
                if !(a.is_finite() && b.is_finite()) {
                    return Err(MlsError::NonFiniteControl { control });
                }
                let scale = a.abs().max(b.abs()).max_element();
                if (b - a).length() <= tolerance(DVec2::splat(scale)) {
                    return Err(MlsError::ZeroLengthBar { control });
                }
            }
        }
    }
    Ok(())
}

/// The posed positions in the order of the rest positions.
fn flatten_pose(bars: &[bool], posed: &[Control]) -> Result<Vec<DVec2>, MlsError> {
    if posed.len() != bars.len() {
        return Err(MlsError::PoseLength {
            posed: posed.len(),
            rest: bars.len(),
        });
    }
    let mut q = Vec::with_capacity(bars.len() * 2);
    for (control, (c, bar)) in posed.iter().zip(bars).enumerate() {
        match (*c, *bar) {
            (Control::Point(p), false) => {
                if !p.is_finite() {
                    return Err(MlsError::NonFinitePosed { control });
                }
                q.push(p);
            }
            (Control::Bar([a, b]), true) => {
                if !(a.is_finite() && b.is_finite()) {
                    return Err(MlsError::NonFinitePosed { control });
                }
                q.push(a);
                q.push(b);
            }
            _ => return Err(MlsError::PoseKind { control }),
        }
    }
    Ok(q)
}

/// The mean `o` of the posed positions, the positions less `o`, and their largest
/// distance from `o`. Working relative to `o` keeps the sums `Σ k_j q_j` (whose
/// coefficients add up to 1 or 0) free of the cancellation that large absolute
/// coordinates would bring.
fn centre(q: &[DVec2]) -> (DVec2, Vec<DVec2>, f64) {
    if q.is_empty() {
        return (DVec2::ZERO, Vec::new(), 0.0);
    }
    let o = q.iter().copied().sum::<DVec2>() / q.len() as f64;
    let centred: Vec<DVec2> = q.iter().map(|p| *p - o).collect();
    let reach = centred.iter().map(|p| p.length()).fold(0.0, f64::max);
    (o, centred, reach)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene() -> (Vec<DVec2>, Vec<Control>, Vec<Control>) {
        let vertices: Vec<DVec2> = (0..400)
            .map(|i| DVec2::new(f64::from(i % 20) * 7.3, f64::from(i / 20) * 5.1))
            .collect();
        let rest = vec![
            Control::Point(DVec2::new(10.0, 10.0)),
            Control::Bar([DVec2::new(30.0, 40.0), DVec2::new(120.0, 60.0)]),
            Control::Bar([DVec2::new(20.0, 90.0), DVec2::new(20.0, 30.0)]),
        ];
        let posed = vec![
            Control::Point(DVec2::new(15.0, 5.0)),
            Control::Bar([DVec2::new(30.0, 45.0), DVec2::new(110.0, 90.0)]),
            Control::Bar([DVec2::new(25.0, 90.0), DVec2::new(10.0, 35.0)]),
        ];
        (vertices, rest, posed)
    }

    fn deformed(mls: &Mls, posed: &[Control]) -> Vec<DVec2> {
        let mut out = vec![DVec2::ZERO; mls.vertex_count()];
        mls.deform(posed, &mut out).expect("a valid pose");
        out
    }

    /// A renewed table takes the bars' integrals the table before kept, rather than
    /// working them out again; a bar that moved gets its own.
    #[test]
    fn a_renewed_table_shares_the_integrals_kept() {
        let (vertices, rest, _) = scene();
        let options = MlsOptions::default();
        let before = Mls::new(&vertices, &rest, &options).expect("valid");
        let mut more = rest.clone();
        more.push(Control::Point(DVec2::new(70.0, 20.0)));
        more[2] = Control::Bar([DVec2::new(21.0, 90.0), DVec2::new(20.0, 30.0)]);
        let after = before.renewed(&vertices, &more, &options).expect("valid");
        let (was, now) = (
            before.kept.as_ref().expect("kept"),
            after.kept.as_ref().expect("kept"),
        );
        assert!(Arc::ptr_eq(&was.vertices, &now.vertices));
        assert!(Arc::ptr_eq(&was.bars[0].1, &now.bars[0].1));
        assert!(!Arc::ptr_eq(&was.bars[1].1, &now.bars[1].1));
        // Under another α nothing applies.
        let other = MlsOptions {
            alpha: 2.0,
            ..options
        };
        let again = before.renewed(&vertices, &more, &other).expect("valid");
        assert!(!Arc::ptr_eq(
            &was.bars[0].1,
            &again.kept.expect("kept").bars[0].1
        ));
    }

    /// Past the memory the kept integrals may take, each vertex works out its own,
    /// to the same bits.
    #[test]
    fn integrals_kept_or_not_give_the_same_table() {
        let (vertices, rest, posed) = scene();
        for variant in [Variant::Affine, Variant::Similarity, Variant::Rigid] {
            let options = MlsOptions {
                variant,
                ..MlsOptions::default()
            };
            let kept = Mls::build(&vertices, &rest, &options, None, usize::MAX).expect("valid");
            let not = Mls::build(&vertices, &rest, &options, None, 0).expect("valid");
            assert!(kept.kept.is_some() && not.kept.is_none());
            let (a, b) = (deformed(&kept, &posed), deformed(&not, &posed));
            assert!(
                a.iter()
                    .zip(&b)
                    .all(|(p, q)| p.to_array().map(f64::to_bits) == q.to_array().map(f64::to_bits)),
                "{variant:?}"
            );
        }
    }
}
