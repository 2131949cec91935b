//! One triangle's share of the method: the local coordinates of §4.1 (eq. 1), step
//! one's error of a corner predicted from the other two (eqs. 2–4), and step two's
//! fitting matrix (eqs. 9–11), inverted once at registration.
//!
//! Every 2×2 block that appears here is of the form `a·I + b·R90`, where
//! `R90 = [[0, 1], [−1, 0]]` is the rotation the paper prints (eq. 2): such blocks
//! commute and multiply like complex numbers (`R90² = −I`), which keeps the
//! assembled matrices small.

use geometry::orient;
use glam::DVec2;

/// `R90 · v` with the paper's `R90 = [[0, 1], [−1, 0]]`: a quarter turn, counter-
/// clockwise on screen in image coordinates (y down).
#[inline]
pub(crate) fn r90(v: DVec2) -> DVec2 {
    DVec2::new(v.y, -v.x)
}

/// The coordinates `(x, y)` of `vi` in the frame of the edge `vj → vk` (eq. 1):
/// `vi = vj + x·(vk − vj) + y·R90·(vk − vj)`. `vj` and `vk` must differ.
#[inline]
pub(crate) fn local_coordinates(vi: DVec2, vj: DVec2, vk: DVec2) -> DVec2 {
    let d = vk - vj;
    let rel = vi - vj;
    let len2 = d.length_squared();
    DVec2::new(rel.dot(d) / len2, rel.dot(r90(d)) / len2)
}

/// Whether a rest triangle spans no area up to rounding: twice its area is at most
/// `1e-12` times its longest edge squared (this also covers a repeated vertex and
/// coincident corners). Such triangles are left out of both steps.
pub(crate) fn is_degenerate(p: [DVec2; 3]) -> bool {
    let e = [p[1] - p[0], p[2] - p[1], p[0] - p[2]];
    let longest = e.iter().map(|e| e.length_squared()).fold(0.0_f64, f64::max);
    let twice_area = orient(p[0], p[1], p[2]).abs();
    // Written so that a NaN counts as degenerate.
    let spans_area = twice_area > 1e-12 * longest;
    !spans_area
}

/// Step one's error of corner `c` predicted from corners `c + 1` and `c + 2` (eqs. 2,
/// 3): the residual `vc' − vc,desired` is `Σ_a (α_a·I + β_a·R90)·v_a'` over the three
/// corners `a = c, c + 1, c + 2`, with `(α, β)` as returned (in that corner order),
/// where `(x, y)` are the local coordinates of corner `c`.
#[inline]
pub(crate) fn corner_error_coefficients(local: DVec2) -> [(f64, f64); 3] {
    let (x, y) = (local.x, local.y);
    // vc,desired = vj + x (vk − vj) + y R90 (vk − vj)
    //            = ((1 − x) I − y R90) vj + (x I + y R90) vk.
    [(1.0, 0.0), (-(1.0 - x), y), (-x, -y)]
}

/// Step one's error matrix of one triangle (eq. 5 restricted to it): the sum over
/// its three corners of `AᵀA`, `A` the 2×6 map from the triangle's corners to that
/// corner's error (eqs. 2, 3). Its 3×3 blocks are `p·I + q·R90`; returned are the
/// diagonal ones' `p` (their `q` is zero) and the blocks `(0, 1)`, `(1, 2)`, `(0, 2)`
/// as `(p, q)`, the ones below the diagonal being their transposes `p·I − q·R90`:
/// `[p00, p11, p22, p01, q01, p12, q12, p02, q02]`.
pub(crate) fn step_one_matrix(p: [DVec2; 3]) -> [f64; 9] {
    let mut blocks = [[(0.0, 0.0); 3]; 3];
    for c in 0..3 {
        let local = local_coordinates(p[c], p[(c + 1) % 3], p[(c + 2) % 3]);
        let coef = corner_error_coefficients(local);
        for k1 in 0..3 {
            for k2 in 0..3 {
                let (bp, bq) = block_product(coef[k1], coef[k2]);
                let b = &mut blocks[(c + k1) % 3][(c + k2) % 3];
                b.0 += bp;
                b.1 += bq;
            }
        }
    }
    [
        blocks[0][0].0,
        blocks[1][1].0,
        blocks[2][2].0,
        blocks[0][1].0,
        blocks[0][1].1,
        blocks[1][2].0,
        blocks[1][2].1,
        blocks[0][2].0,
        blocks[0][2].1,
    ]
}

/// The block `A_aᵀ·A_b` for blocks `A_a = α_a·I + β_a·R90`, returned as `(p, q)`
/// meaning `p·I + q·R90`.
#[inline]
pub(crate) fn block_product(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    // (αa I + βa R)ᵀ (αb I + βb R) = (αa I − βa R)(αb I + βb R)
    //   = (αa αb + βa βb) I + (αa βb − βa αb) R.
    (a.0 * b.0 + a.1 * b.1, a.0 * b.1 - a.1 * b.0)
}

/// Step two's fitting (§4.2.1) folded into two complex coefficients `(c1, c2)`: for
/// step-one corners `v0', v1', v2'` (as complex numbers `x + i·y`),
/// `z = c1·(v1' − v0') + c2·(v2' − v0')` is the complex factor of the similarity
/// that fits the rest triangle to them — the fitted edge `v1,fitted − v0,fitted`
/// divided by the rest edge `v1 − v0` — and `z/|z|` is the rotation of the fitted
/// triangle scaled back to its rest size.
///
/// Built as the paper does: with `v2,fitted` written through `v0,fitted` and
/// `v1,fitted` by the local coordinates `(x01, y01)` of corner 2 (eq. 10), the fitting
/// functional (eq. 9) is a quadratic in `w = (v0,fitted, v1,fitted)` whose minimiser
/// solves `F·w = Bᵀ·v'` (eq. 11, with `C = −Bᵀ·v'`); `F` is inverted here, once, and
/// the map `v' ↦ z` (a 2×6 matrix) is formed. Its 2×2 blocks are `p·I + q·R90`, the
/// real form of complex numbers, so it is three complex coefficients; fitting a
/// translated triangle gives the translated fit, so they sum to zero and two are kept.
/// `F = I + Σ AᵢᵀAᵢ ≥ I` is always invertible, so this returns `None` only when the
/// rest edge `v0 → v1` has zero length (a degenerate triangle).
pub(crate) fn fitting_coefficients(p: [DVec2; 3]) -> Option<[DVec2; 2]> {
    let m = fitting_matrix(p)?;
    // Block k is [[p, q], [−q, p]] = p·I + q·R90, i.e. the complex number p − i·q.
    let c = |k: usize| DVec2::new(m[0][2 * k], -m[0][2 * k + 1]);
    Some([c(1), c(2)])
}

/// The 2×6 matrix `M` with `z = M·(v0'x, v0'y, v1'x, v1'y, v2'x, v2'y)` (see
/// [`fitting_coefficients`]).
fn fitting_matrix(p: [DVec2; 3]) -> Option<[[f64; 6]; 2]> {
    let e = p[1] - p[0];
    let len2 = e.length_squared();
    if len2.is_nan() || len2 <= 0.0 {
        return None;
    }
    let local = local_coordinates(p[2], p[0], p[1]);
    // v2,fitted = P·v0,fitted + Q·v1,fitted with P = (1 − x) I − y R, Q = x I + y R.
    let pb = (1.0 - local.x, -local.y);
    let qb = (local.x, local.y);
    // The three corners as rows of A (2×4 each): A0 = [I 0], A1 = [0 I], A2 = [P Q].
    // F = Σ Aᵢᵀ Aᵢ, and Σ Aᵢᵀ vᵢ' = [v0' + Pᵀ v2'; v1' + Qᵀ v2'].
    let pp = block_product(pb, pb);
    let pq = block_product(pb, qb);
    let qp = block_product(qb, pb);
    let qq = block_product(qb, qb);
    let mut f = [[0.0; 4]; 4];
    put_block(&mut f, 0, 0, (1.0 + pp.0, pp.1));
    put_block(&mut f, 0, 1, pq);
    put_block(&mut f, 1, 0, qp);
    put_block(&mut f, 1, 1, (1.0 + qq.0, qq.1));
    let f_inv = invert4(f)?;
    // Bᵀ (4×6): rows [I 0 Pᵀ; 0 I Qᵀ].
    let mut bt = [[0.0; 6]; 4];
    put_block_rect(&mut bt, 0, 0, (1.0, 0.0));
    put_block_rect(&mut bt, 1, 1, (1.0, 0.0));
    put_block_rect(&mut bt, 0, 2, (pb.0, -pb.1));
    put_block_rect(&mut bt, 1, 2, (qb.0, -qb.1));
    // w = F⁻¹ Bᵀ v'; the fitted edge is w[2..4] − w[0..2].
    let mut edge = [[0.0; 6]; 2];
    for (r, row) in edge.iter_mut().enumerate() {
        for (c, out) in row.iter_mut().enumerate() {
            let mut s = 0.0;
            for k in 0..4 {
                let d = f_inv[2 + r][k] - f_inv[r][k];
                s += d * bt[k][c];
            }
            *out = s;
        }
    }
    // z = fitted edge · conj(e) / |e|².
    let a = DVec2::new(e.x, -e.y) / len2;
    let mut m = [[0.0; 6]; 2];
    for c in 0..6 {
        let (re, im) = (edge[0][c], edge[1][c]);
        m[0][c] = a.x * re - a.y * im;
        m[1][c] = a.y * re + a.x * im;
    }
    Some(m)
}

/// The rotation of step two's fitted-and-rescaled triangle: `z/|z|` for
/// `z = c1·(v1' − v0') + c2·(v2' − v0')`, or no rotation when the step-one triangle
/// collapsed to a point (`z = 0` up to the rounding of the positions).
#[inline]
pub(crate) fn fitted_rotation(c: &[DVec2; 2], v: [DVec2; 3]) -> DVec2 {
    let (d1, d2) = (v[1] - v[0], v[2] - v[0]);
    let z = rotate(c[0], d1) + rotate(c[1], d2);
    let l1 = |p: DVec2| p.x.abs() + p.y.abs();
    let magnitude = (l1(c[0]) + l1(c[1])) * (l1(v[0]) + l1(v[1]) + l1(v[2]));
    if l1(z) <= 1e-13 * magnitude {
        return DVec2::X;
    }
    z.try_normalize().unwrap_or(DVec2::X)
}

/// Complex product `a·b` of `(re, im)` pairs: `b` turned and scaled by `a`.
#[inline]
pub(crate) fn rotate(a: DVec2, b: DVec2) -> DVec2 {
    DVec2::new(a.x * b.x - a.y * b.y, a.y * b.x + a.x * b.y)
}

/// Writes the 2×2 block `p·I + q·R90 = [[p, q], [−q, p]]` at block row `br`, block
/// column `bc` of a 4×4 matrix.
fn put_block(m: &mut [[f64; 4]; 4], br: usize, bc: usize, (p, q): (f64, f64)) {
    m[2 * br][2 * bc] = p;
    m[2 * br][2 * bc + 1] = q;
    m[2 * br + 1][2 * bc] = -q;
    m[2 * br + 1][2 * bc + 1] = p;
}

fn put_block_rect(m: &mut [[f64; 6]; 4], br: usize, bc: usize, (p, q): (f64, f64)) {
    m[2 * br][2 * bc] = p;
    m[2 * br][2 * bc + 1] = q;
    m[2 * br + 1][2 * bc] = -q;
    m[2 * br + 1][2 * bc + 1] = p;
}

/// Inverse of a 4×4 matrix by Gauss–Jordan elimination with partial pivoting; `None`
/// when a pivot vanishes.
fn invert4(mut a: [[f64; 4]; 4]) -> Option<[[f64; 4]; 4]> {
    let mut inv = [[0.0; 4]; 4];
    for (i, row) in inv.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for col in 0..4 {
        let pivot = (col..4).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col] == 0.0 || a[pivot][col].is_nan() {
            return None;
        }
        a.swap(col, pivot);
        inv.swap(col, pivot);
        let d = 1.0 / a[col][col];
        for k in 0..4 {
            a[col][k] *= d;
            inv[col][k] *= d;
        }
        for r in 0..4 {
            if r != col {
                let f = a[r][col];
                if f != 0.0 {
                    for k in 0..4 {
                        a[r][k] -= f * a[col][k];
                        inv[r][k] -= f * inv[col][k];
                    }
                }
            }
        }
    }
    Some(inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(seed: u64) -> [DVec2; 3] {
        let mut s = seed;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 4.0 - 2.0
        };
        [
            DVec2::new(next(), next()),
            DVec2::new(next(), next()),
            DVec2::new(next(), next()),
        ]
    }

    #[test]
    fn local_coordinates_rebuild_the_vertex() {
        for seed in 0..50 {
            let p = tri(seed);
            for c in 0..3 {
                let (i, j, k) = (p[c], p[(c + 1) % 3], p[(c + 2) % 3]);
                let l = local_coordinates(i, j, k);
                let back = j + l.x * (k - j) + l.y * r90(k - j);
                assert!((back - i).length() < 1e-12, "{back} vs {i}");
            }
        }
    }

    #[test]
    fn corner_error_vanishes_under_a_similarity() {
        let p = tri(7);
        let z = DVec2::new(0.3, -1.7);
        let t = DVec2::new(5.0, 2.0);
        let q = p.map(|v| rotate(z, v) + t);
        for c in 0..3 {
            let l = local_coordinates(p[c], p[(c + 1) % 3], p[(c + 2) % 3]);
            let coef = corner_error_coefficients(l);
            let mut r = DVec2::ZERO;
            for (a, &(al, be)) in coef.iter().enumerate() {
                let v = q[(c + a) % 3];
                r += al * v + be * r90(v);
            }
            assert!(r.length() < 1e-12, "{r}");
        }
    }

    /// The triangle's error matrix vanishes on similarities of the rest triangle and
    /// is symmetric positive semidefinite.
    #[test]
    fn step_one_matrix_vanishes_on_similarities() {
        for seed in 0..20 {
            let p = tri(seed);
            let m = step_one_matrix(p);
            let block = |a: usize, b: usize| -> (f64, f64) {
                match (a, b) {
                    (0, 0) => (m[0], 0.0),
                    (1, 1) => (m[1], 0.0),
                    (2, 2) => (m[2], 0.0),
                    (0, 1) => (m[3], m[4]),
                    (1, 2) => (m[5], m[6]),
                    (0, 2) => (m[7], m[8]),
                    (a, b) => {
                        let (p, q) = block_at(&m, b, a);
                        (p, -q)
                    }
                }
            };
            fn block_at(m: &[f64; 9], a: usize, b: usize) -> (f64, f64) {
                match (a, b) {
                    (0, 1) => (m[3], m[4]),
                    (1, 2) => (m[5], m[6]),
                    _ => (m[7], m[8]),
                }
            }
            let energy = |v: [DVec2; 3]| {
                let mut e = 0.0;
                for a in 0..3 {
                    for b in 0..3 {
                        let (bp, bq) = block(a, b);
                        e += v[a].dot(bp * v[b] + bq * r90(v[b]));
                    }
                }
                e
            };
            let z = DVec2::new(0.8, 0.6) * 1.7;
            let t = DVec2::new(-3.0, 2.0);
            assert!(energy(p.map(|v| rotate(z, v) + t)).abs() < 1e-9);
            assert!(energy(tri(seed + 99)) > 0.0);
        }
    }

    #[test]
    fn block_product_matches_matrices() {
        let (a, b) = ((0.7, -1.3), (2.1, 0.4));
        let m = |(p, q): (f64, f64)| [[p, q], [-q, p]];
        let (ma, mb) = (m(a), m(b));
        let mut prod = [[0.0; 2]; 2];
        for i in 0..2 {
            for j in 0..2 {
                for k in 0..2 {
                    prod[i][j] += ma[k][i] * mb[k][j];
                }
            }
        }
        assert_eq!(
            m(block_product(a, b)).map(|r| r.map(|v| (v * 1e12).round())),
            prod.map(|r| r.map(|v| (v * 1e12).round()))
        );
    }

    /// The paper's 4×4 fit equals the textbook closed form (Procrustes about the
    /// centroids, `z = Σ conj(rᵢ − r̄)(vᵢ' − v̄') / Σ |rᵢ − r̄|²`), and its matrix is
    /// complex-linear and blind to translation.
    #[test]
    fn fitting_is_the_similarity_procrustes_fit() {
        for seed in 0..50 {
            let p = tri(seed);
            let q = tri(seed + 1000);
            let m = fitting_matrix(p).expect("non-degenerate");
            let mut sum = DVec2::ZERO;
            for k in 0..3 {
                assert!((m[1][2 * k] + m[0][2 * k + 1]).abs() < 1e-12);
                assert!((m[1][2 * k + 1] - m[0][2 * k]).abs() < 1e-12);
                sum += DVec2::new(m[0][2 * k], m[0][2 * k + 1]);
            }
            assert!(sum.length() < 1e-12, "{sum}");
            let c = fitting_coefficients(p).expect("non-degenerate");
            let z = rotate(c[0], q[1] - q[0]) + rotate(c[1], q[2] - q[0]);
            let (pc, qc) = ((p[0] + p[1] + p[2]) / 3.0, (q[0] + q[1] + q[2]) / 3.0);
            let mut num = DVec2::ZERO;
            let mut den = 0.0;
            for i in 0..3 {
                let r = p[i] - pc;
                num += rotate(DVec2::new(r.x, -r.y), q[i] - qc);
                den += r.length_squared();
            }
            let expect = num / den;
            assert!(
                (z - expect).length() < 1e-9 * (1.0 + expect.length()),
                "{z} vs {expect}"
            );
            assert!((fitted_rotation(&c, q) - expect.normalize()).length() < 1e-9);
        }
    }

    #[test]
    fn degenerate_triangles_are_recognised() {
        let a = DVec2::new(0.0, 0.0);
        let b = DVec2::new(1.0, 0.0);
        assert!(is_degenerate([a, b, DVec2::new(2.0, 0.0)]));
        assert!(is_degenerate([a, a, b]));
        assert!(is_degenerate([a, a, a]));
        assert!(is_degenerate([a, b, DVec2::new(0.5, f64::NAN)]));
        assert!(!is_degenerate([a, b, DVec2::new(0.5, 1e-3)]));
        assert!(fitting_coefficients([a, a, b]).is_none());
    }

    #[test]
    fn collapsed_triangle_keeps_its_orientation() {
        let c = fitting_coefficients(tri(3)).expect("non-degenerate");
        let p = DVec2::new(4.0, 4.0);
        assert_eq!(fitted_rotation(&c, [p, p, p]), DVec2::X);
        let q = p + DVec2::splat(1e-17);
        assert_eq!(fitted_rotation(&c, [p, q, p]), DVec2::X);
    }
}
