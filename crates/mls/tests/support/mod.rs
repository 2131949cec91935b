//! Scenes made in code, a seeded generator, and an independent reference: the
//! moving least squares fit at one point solved directly (normal equations, or a
//! search over the angle), with bars sampled by adaptive quadrature. Shared by the
//! integration tests and the benchmark.
#![allow(dead_code)]

use glam::DVec2;
use mls::{Control, Variant};

/// SplitMix64: small, seeded, good enough for test data.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    /// Uniform in the rectangle [0, w) × [0, h).
    pub fn point(&mut self, w: f64, h: f64) -> DVec2 {
        DVec2::new(self.range(0.0, w), self.range(0.0, h))
    }

    /// Uniform in 0..n.
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

/// A rest scene in a 1000 × 700 pixel region: `points` point handles and `bars`
/// bars (20 to 300 px long), all at least 30 px apart, and its posed version: each
/// control moved by up to `reach` px (a bar's ends independently).
pub fn scene(
    rng: &mut Rng,
    points: usize,
    bars: usize,
    reach: f64,
) -> (Vec<Control>, Vec<Control>) {
    let mut rest = Vec::new();
    let far_enough = |rest: &[Control], p: DVec2| {
        rest.iter().all(|c| match c {
            Control::Point(q) => (*q - p).length() > 30.0,
            Control::Bar([a, b]) => segment_distance(p, *a, *b) > 30.0,
        })
    };
    while rest.len() < points {
        let p = rng.point(1000.0, 700.0);
        if far_enough(&rest, p) {
            rest.push(Control::Point(p));
        }
    }
    while rest.len() < points + bars {
        let a = rng.point(1000.0, 700.0);
        let angle = rng.range(0.0, std::f64::consts::TAU);
        let b = a + DVec2::from_angle(angle) * rng.range(20.0, 300.0);
        let ok = (0..=10).all(|k| far_enough(&rest, a.lerp(b, k as f64 / 10.0)));
        if ok {
            rest.push(Control::Bar([a, b]));
        }
    }
    let mut jitter = |p: DVec2| p + DVec2::new(rng.range(-reach, reach), rng.range(-reach, reach));
    let posed = rest
        .iter()
        .map(|c| match *c {
            Control::Point(p) => Control::Point(jitter(p)),
            Control::Bar([a, b]) => Control::Bar([jitter(a), jitter(b)]),
        })
        .collect();
    (rest, posed)
}

/// Distance from `p` to the segment `a → b`.
pub fn segment_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    let t = ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
    (a + d * t - p).length()
}

/// Applies `f` to every position of every control.
pub fn map_controls(controls: &[Control], f: impl Fn(DVec2) -> DVec2) -> Vec<Control> {
    controls
        .iter()
        .map(|c| match *c {
            Control::Point(p) => Control::Point(f(p)),
            Control::Bar([a, b]) => Control::Bar([f(a), f(b)]),
        })
        .collect()
}

/// Random vertices in the region, plus some near every control (1e-6 to 3 px away,
/// and beyond the bars' ends).
pub fn vertices_around(rng: &mut Rng, controls: &[Control], random: usize) -> Vec<DVec2> {
    let mut out: Vec<DVec2> = (0..random).map(|_| rng.point(1000.0, 700.0)).collect();
    for c in controls {
        match *c {
            Control::Point(p) => {
                for r in [1e-6, 0.01, 3.0] {
                    out.push(p + DVec2::from_angle(rng.range(0.0, 6.3)) * r);
                }
            }
            Control::Bar([a, b]) => {
                let n = (b - a).normalize().perp();
                for (t, off) in [
                    (0.3, 1e-6),
                    (0.5, 0.01),
                    (0.8, 3.0),
                    (1.02, 0.0),
                    (-0.1, 1e-3),
                ] {
                    out.push(a.lerp(b, t) + n * off);
                }
            }
        }
    }
    out
}

/// One weighted correspondence `p ↦ q` of the direct least-squares problem.
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    pub w: f64,
    pub p: DVec2,
    pub q: DVec2,
}

/// The weighted correspondences of the fit at `v`: a point handle is one sample with
/// weight `|p − v|^{−2α}`; a bar is the nodes of an adaptive Gauss quadrature of
/// `∫ |p(t) − v|^{−2α} ds` (bisected until each piece agrees with its halves to
/// 1e-14 in the weight's zeroth, first and second moments in `t`).
pub fn samples(v: DVec2, rest: &[Control], posed: &[Control], alpha: f64) -> Vec<Sample> {
    let mut out = Vec::new();
    for (r, q) in rest.iter().zip(posed) {
        match (*r, *q) {
            (Control::Point(p), Control::Point(q)) => out.push(Sample {
                w: (p - v).length_squared().powf(-alpha),
                p,
                q,
            }),
            (Control::Bar([a, b]), Control::Bar([c, d])) => {
                let len = (b - a).length();
                let weight = |t: f64| len * (a.lerp(b, t) - v).length_squared().powf(-alpha);
                let mut pieces = Vec::new();
                bisect(&weight, 0.0, 1.0, 0, &mut pieces);
                for (t, w) in pieces {
                    out.push(Sample {
                        w,
                        p: a.lerp(b, t),
                        q: c.lerp(d, t),
                    });
                }
            }
            _ => panic!("pose does not match"),
        }
    }
    out
}

fn gauss10() -> [(f64, f64); 10] {
    // Nodes and weights of the 10-point Gauss–Legendre rule on [−1, 1].
    const X: [f64; 5] = [
        0.148_874_338_981_631_2,
        0.433_395_394_129_247_2,
        0.679_409_568_299_024_4,
        0.865_063_366_688_984_5,
        0.973_906_528_517_171_7,
    ];
    const W: [f64; 5] = [
        0.295_524_224_714_752_9,
        0.269_266_719_309_996_3,
        0.219_086_362_515_982_04,
        0.149_451_349_150_580_6,
        0.066_671_344_308_688_14,
    ];
    let mut rule = [(0.0, 0.0); 10];
    for k in 0..5 {
        rule[2 * k] = (-X[k], W[k]);
        rule[2 * k + 1] = (X[k], W[k]);
    }
    rule
}

fn bisect(weight: &dyn Fn(f64) -> f64, lo: f64, hi: f64, depth: u32, out: &mut Vec<(f64, f64)>) {
    let rule = gauss10();
    let nodes = |lo: f64, hi: f64| -> Vec<(f64, f64)> {
        let (mid, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
        rule.iter()
            .map(|(x, w)| {
                let t = mid + half * x;
                (t, w * half * weight(t))
            })
            .collect()
    };
    let moments = |nodes: &[(f64, f64)]| {
        nodes.iter().fold([0.0; 3], |m, (t, w)| {
            [m[0] + w, m[1] + w * t, m[2] + w * t * t]
        })
    };
    let whole = moments(&nodes(lo, hi));
    let mid = 0.5 * (lo + hi);
    let (left, right) = (nodes(lo, mid), nodes(mid, hi));
    let (ml, mr) = (moments(&left), moments(&right));
    let close = (0..3).all(|k| (ml[k] + mr[k] - whole[k]).abs() <= 1e-14 * (ml[k] + mr[k]));
    if close || depth >= 50 {
        out.extend(left);
        out.extend(right);
    } else {
        bisect(weight, lo, mid, depth + 1, out);
        bisect(weight, mid, hi, depth + 1, out);
    }
}

/// Weighted centroids `(p*, q*)` of the samples.
fn centroids(s: &[Sample]) -> (DVec2, DVec2) {
    let total: f64 = s.iter().map(|s| s.w).sum();
    let p = s.iter().map(|s| s.p * s.w).sum::<DVec2>() / total;
    let q = s.iter().map(|s| s.q * s.w).sum::<DVec2>() / total;
    (p, q)
}

/// `l_v(v)` for the best map of `variant`'s class, found directly:
/// - affine: the 6-unknown weighted linear least squares (3×3 normal equations per
///   coordinate);
/// - similarity: the 4-unknown one over `x ↦ x·[[a, b], [−b, a]] + T`;
/// - rigid: the same with `a² + b² = 1`: the energy is a sinusoid in the angle, so a
///   grid of 64 angles brackets its one minimum and bisection on the energy's slope
///   refines it; the translation is fitted for the angle found.
pub fn direct(v: DVec2, s: &[Sample], variant: Variant) -> DVec2 {
    // Work relative to v: then l_v(v) is the translation part.
    let local: Vec<Sample> = s
        .iter()
        .map(|s| Sample {
            w: s.w,
            p: s.p - v,
            q: s.q - v,
        })
        .collect();
    let t = match variant {
        Variant::Affine => {
            let mut n = [[0.0; 3]; 3];
            let mut rx = [0.0; 3];
            let mut ry = [0.0; 3];
            for s in &local {
                let row = [s.p.x, s.p.y, 1.0];
                for i in 0..3 {
                    for j in 0..3 {
                        n[i][j] += s.w * row[i] * row[j];
                    }
                    rx[i] += s.w * row[i] * s.q.x;
                    ry[i] += s.w * row[i] * s.q.y;
                }
            }
            let bx = solve::<3>(n, rx);
            let by = solve::<3>(n, ry);
            DVec2::new(bx[2], by[2])
        }
        Variant::Similarity => {
            let mut n = [[0.0; 4]; 4];
            let mut r = [0.0; 4];
            for s in &local {
                // Unknowns (a, b, tx, ty): x' = a·px − b·py + tx, y' = b·px + a·py + ty.
                let rows = [
                    ([s.p.x, -s.p.y, 1.0, 0.0], s.q.x),
                    ([s.p.y, s.p.x, 0.0, 1.0], s.q.y),
                ];
                for (row, rhs) in rows {
                    for i in 0..4 {
                        for j in 0..4 {
                            n[i][j] += s.w * row[i] * row[j];
                        }
                        r[i] += s.w * row[i] * rhs;
                    }
                }
            }
            let u = solve::<4>(n, r);
            DVec2::new(u[2], u[3])
        }
        Variant::Rigid => {
            let (ps, qs) = centroids(&local);
            let energy = |theta: f64| {
                let rot = DVec2::from_angle(theta);
                local
                    .iter()
                    .map(|s| s.w * (rot.rotate(s.p - ps) - (s.q - qs)).length_squared())
                    .sum::<f64>()
            };
            let steps = 64;
            let step = std::f64::consts::TAU / steps as f64;
            let best = (0..steps)
                .map(|k| k as f64 * step)
                .min_by(|a, b| energy(*a).total_cmp(&energy(*b)))
                .unwrap_or(0.0);
            // The energy is flat at its minimum, so refine on its derivative's sign
            // instead: dE/dθ = −2 Σ w (R p̂)⊥ · q̂ crosses zero sharply.
            let slope = |theta: f64| {
                let rot = DVec2::from_angle(theta);
                -local
                    .iter()
                    .map(|s| s.w * rot.rotate(s.p - ps).perp().dot(s.q - qs))
                    .sum::<f64>()
            };
            let (mut lo, mut hi) = (best - 2.0 * step, best + 2.0 * step);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if slope(mid) > 0.0 {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            let theta = 0.5 * (lo + hi);
            // l(x) = R(x − p*) + q*, at x = 0 (that is, at v).
            qs - DVec2::from_angle(theta).rotate(ps)
        }
    };
    v + t
}

/// Solves `a x = b` by Gaussian elimination with partial pivoting.
pub fn solve<const N: usize>(mut a: [[f64; N]; N], mut b: [f64; N]) -> [f64; N] {
    for col in 0..N {
        let pivot = (col..N)
            .max_by(|i, j| a[*i][col].abs().total_cmp(&a[*j][col].abs()))
            .unwrap_or(col);
        a.swap(col, pivot);
        b.swap(col, pivot);
        for row in col + 1..N {
            let f = a[row][col] / a[col][col];
            let pivot_row = a[col];
            for (x, p) in a[row][col..].iter_mut().zip(&pivot_row[col..]) {
                *x -= f * p;
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; N];
    for row in (0..N).rev() {
        let mut acc = b[row];
        for k in row + 1..N {
            acc -= a[row][k] * x[k];
        }
        x[row] = acc / a[row][row];
    }
    x
}

/// All three variants.
pub const VARIANTS: [Variant; 3] = [Variant::Affine, Variant::Similarity, Variant::Rigid];
