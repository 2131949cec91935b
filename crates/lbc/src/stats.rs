//! The paper's locality statistics (§5, eqs. 19–21): how much of the cage's inside
//! each coordinate function leaves (nearly) untouched, and how many control points
//! reach each part of it.

use geometry::orient;
use rayon::prelude::*;

use crate::compact::Coordinates;
use crate::domain::Domain;

/// `P(t)` and `Q(k)` of a set of coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct Locality {
    /// The `t` at which `P` was evaluated.
    pub t: Vec<f64>,
    /// `P(t) = (1/n) Σ_i φ_i(t)`, `φ_i(t)` the share of the inside's area where
    /// `|w_i| ≤ t` (eqs. 19–20), one per `t`.
    pub p: Vec<f64>,
    /// `Q(k)`, the share of the inside's area where at least `k` coordinates exceed
    /// the negligible `10⁻³/n` (eq. 21), for `k = 0 ..= n`.
    pub q: Vec<f64>,
}

/// The share of a triangle where a linear function with corner values `values` is at
/// most `t` (the function's distribution over the triangle: piecewise quadratic in
/// `t`).
fn share_at_most(mut values: [f64; 3], t: f64) -> f64 {
    values.sort_by(f64::total_cmp);
    let [a, b, c] = values;
    if t < a {
        0.0
    } else if t >= c {
        1.0
    } else if t <= b {
        // A corner triangle similar to the whole, cut at t on the two edges from a.
        if b > a {
            (t - a) * (t - a) / ((b - a) * (c - a))
        } else {
            0.0
        }
    } else {
        1.0 - (c - t) * (c - t) / ((c - a) * (c - b))
    }
}

/// The locality statistics of `coordinates` on `domain`, with `P` at each of `t`.
///
/// `P` is exact for the piecewise-linear coordinate functions (each triangle's share
/// where `|w_i| ≤ t` in closed form). `Q` counts at the mesh vertices, each standing
/// for a third of the area of its triangles (`σ` of eq. 21 is not piecewise linear).
pub fn locality(domain: &Domain, coordinates: &Coordinates, t: &[f64]) -> Locality {
    let n = coordinates.cage_vertices();
    let positions = domain.positions();
    let area_of = |tri: &[u32; 3]| {
        let [a, b, c] = tri.map(|v| positions[v as usize]);
        0.5 * orient(a, b, c).abs()
    };
    let mut vertex_area = vec![0.0; positions.len()];
    let mut total = 0.0;
    for tri in domain.triangles() {
        let area = area_of(tri);
        total += area;
        for &v in tri {
            vertex_area[v as usize] += area / 3.0;
        }
    }
    // `P`'s sums over fixed runs of triangles on all threads, then added in order (the
    // same numbers on any number of threads). Most coordinates are zero on most
    // triangles, where the share is 1 at every `t ≥ 0`.
    let partial: Vec<Vec<f64>> = domain
        .triangles()
        .par_chunks(1024)
        .map(|run| {
            let mut p = vec![0.0; t.len()];
            for tri in run {
                let area = area_of(tri);
                let rows = tri.map(|v| coordinates.row(v as usize));
                for i in 0..n {
                    let values = rows.map(|r| r[i].abs());
                    if values == [0.0; 3] {
                        for (pk, &tk) in p.iter_mut().zip(t) {
                            *pk += if tk >= 0.0 { area } else { 0.0 };
                        }
                        continue;
                    }
                    for (pk, &tk) in p.iter_mut().zip(t) {
                        *pk += area * share_at_most(values, tk);
                    }
                }
            }
            p
        })
        .collect();
    let mut p = vec![0.0; t.len()];
    for run in &partial {
        for (pk, r) in p.iter_mut().zip(run) {
            *pk += r;
        }
    }
    let total = if total > 0.0 { total } else { 1.0 };
    for pk in &mut p {
        *pk /= total * n.max(1) as f64;
    }
    let threshold = 1e-3 / n.max(1) as f64;
    let mut reach = vec![0.0; n + 2];
    for (v, &area) in vertex_area.iter().enumerate() {
        let sigma = coordinates
            .row(v)
            .iter()
            .filter(|&&w| w > threshold)
            .count();
        reach[sigma] += area;
    }
    // Q(k): the area where σ ≥ k, a suffix sum.
    let mut q = vec![0.0; n + 1];
    let mut running = reach[n + 1];
    for k in (0..=n).rev() {
        running += reach[k];
        q[k] = running / total;
    }
    Locality {
        t: t.to_vec(),
        p,
        q,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_linear_functions_share_below_t() {
        // Values 0, 0, 1: the area where w ≤ t is 1 − (1 − t)².
        for t in [0.0, 0.25, 0.5, 0.9, 1.0] {
            let expected = 1.0 - (1.0 - t) * (1.0 - t);
            assert!((share_at_most([0.0, 1.0, 0.0], t) - expected).abs() < 1e-12);
        }
        // Values 0, 1, 1: the area where w ≤ t is t².
        assert!((share_at_most([1.0, 0.0, 1.0], 0.5) - 0.25).abs() < 1e-12);
        assert_eq!(share_at_most([2.0, 2.0, 2.0], 1.0), 0.0);
        assert_eq!(share_at_most([2.0, 2.0, 2.0], 2.0), 1.0);
    }
}
