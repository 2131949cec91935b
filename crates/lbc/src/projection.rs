//! The projection of a row of weights onto the barycentric constraints, which the
//! solve ends with and the compact form repeats on a smaller support.

use glam::{DMat3, DVec3};

/// The Euclidean projection of `w0` onto `{w ≥ 0, Kᵀw = b}`: `w = max(0, w0 + Kν)`
/// with `ν` minimising the (convex, piecewise quadratic) dual
/// `½‖max(0, w0 + Kν)‖² − b·ν`, by Newton's method with backtracking. Partition of
/// unity is then made exact by dividing by the sum (a change of the order of
/// rounding).
///
/// With `support`, entries outside it are held at zero; the result is `None` (or,
/// without `support`, `Err` with the best row found) when the constraints cannot be
/// met to `10⁻¹²`.
pub(crate) fn project_row(
    w0: &[f64],
    k: &[DVec3],
    b: DVec3,
    support: Option<&[bool]>,
) -> ProjectResult {
    let free = |i: usize| support.is_none_or(|s| s[i]);
    let eval = |nu: DVec3| -> (f64, DVec3, DMat3) {
        let mut q = -b.dot(nu);
        let mut grad = -b;
        let mut hess = DMat3::from_diagonal(DVec3::splat(1e-12));
        for (i, (w, ki)) in w0.iter().zip(k).enumerate() {
            if !free(i) {
                continue;
            }
            let v = w + ki.dot(nu);
            if v > 0.0 {
                q += 0.5 * v * v;
                grad += v * *ki;
                hess += DMat3::from_cols(*ki * ki.x, *ki * ki.y, *ki * ki.z);
            }
        }
        (q, grad, hess)
    };
    let mut nu = DVec3::ZERO;
    let (mut q, mut grad, mut hess) = eval(nu);
    for _ in 0..200 {
        if grad.length() <= 1e-15 {
            break;
        }
        let step = -(hess.inverse() * grad);
        let slope = grad.dot(step);
        let mut t = 1.0;
        let mut moved = false;
        while t > 1e-12 {
            let candidate = nu + t * step;
            let (qc, gc, hc) = eval(candidate);
            if qc <= q + 1e-4 * t * slope {
                nu = candidate;
                (q, grad, hess) = (qc, gc, hc);
                moved = true;
                break;
            }
            t *= 0.5;
        }
        if !moved {
            break;
        }
    }
    let mut w: Vec<f64> = w0
        .iter()
        .zip(k)
        .enumerate()
        .map(|(i, (w, ki))| {
            if free(i) {
                (w + ki.dot(nu)).max(0.0)
            } else {
                0.0
            }
        })
        .collect();
    // Polish: on the support found, the projection is the equality-constrained one,
    // in closed form. It meets the constraints to rounding even where Newton's line
    // search stalled short of its tolerance (a kink of the piecewise-quadratic dual).
    let polished = polish(w0, k, b, &w);
    let polished_ok = polished.is_some();
    if let Some(p) = polished {
        w = p;
    }
    let sum: f64 = w.iter().sum();
    if sum > 0.0 && !polished_ok {
        w.iter_mut().for_each(|x| *x /= sum);
    }
    let met = (polished_ok || grad.length() <= 1e-12) && sum > 0.0;
    match (met, support) {
        (true, _) => Ok(w),
        (false, Some(_)) => Err(None),
        (false, None) => Err(Some(w)),
    }
}

/// The projection of `w0` onto `{w : Σ w_i k_i = b}` with `w_i = 0` off a support
/// `S`, starting from the positive entries of `w`: `w0_S + K_S λ` with
/// `(K_Sᵀ K_S) λ = b − K_Sᵀ w0_S`. `None` if no support reached that way carries the
/// constraints with non-negative weights.
fn polish(w0: &[f64], k: &[DVec3], b: DVec3, w: &[f64]) -> Option<Vec<f64>> {
    let mut support: Vec<usize> = (0..w.len()).filter(|&i| w[i] > 0.0).collect();
    // An entry that comes out negative leaves the support, and the rest is solved
    // again (a few rounds of an active-set method, from Newton's nearly right guess).
    for _ in 0..w.len() {
        if support.len() < 3 {
            return None;
        }
        let mut gram = DMat3::ZERO;
        let mut residual = b;
        for &i in &support {
            let ki = k[i];
            gram += DMat3::from_cols(ki * ki.x, ki * ki.y, ki * ki.z);
            residual -= w0[i] * ki;
        }
        if gram.determinant().abs() < 1e-14 {
            return None;
        }
        let lambda = gram.inverse() * residual;
        let values: Vec<(usize, f64)> = support
            .iter()
            .map(|&i| (i, w0[i] + k[i].dot(lambda)))
            .collect();
        if values.iter().all(|&(_, v)| v >= 0.0) {
            let mut out = vec![0.0; w.len()];
            for (i, v) in values {
                out[i] = v;
            }
            return Some(out);
        }
        support = values
            .iter()
            .filter(|&&(_, v)| v > 0.0)
            .map(|&(i, _)| i)
            .collect();
    }
    None
}

/// A projected row, or (failing) the best row found without a support restriction.
pub(crate) type ProjectResult = Result<Vec<f64>, Option<Vec<f64>>>;
