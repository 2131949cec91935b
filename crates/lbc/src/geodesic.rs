//! Geodesic distance inside the cage by the heat method (Crane, Weischedel and
//! Wardetzky 2013), as the paper computes it (its §5).

use glam::DVec2;
use rayon::prelude::*;

use crate::domain::Domain;
use crate::error::LbcError;
use crate::fem::{Elements, Pattern, RowFactor};

/// For each cage vertex `i`, the geodesic distance inside the cage from it to every
/// mesh vertex, divided by its own maximum (the paper's eq. 12): `D[i][v] ∈ [0, 1]`,
/// 0 at cage vertex `i`.
///
/// The heat method: one factorisation of `M + t·K` (lumped mass `M`, stiffness `K`,
/// `t = h²` with `h` the mean edge length, Neumann boundary), one solve per cage
/// vertex (all as columns of one solve) for the heat `u` after time `t` from a unit
/// impulse there, the per-triangle field `X = −∇u/|∇u|`, and one Poisson solve
/// `K·φ = ∇·X` with a second factorisation (`K + 10⁻⁸·M/|Ω|`, the constant mode fixed
/// by the tiny mass term: the divergence of any field sums to zero exactly). `φ` is
/// shifted to zero at the source, negative values (rounding) clamped to zero.
///
/// A mesh in pieces (a cage's inside cut through) has no path from a source to the
/// pieces it does not lie in: there the distance is 1, the farthest, so that no
/// coordinate reaches across (the heat never gets there, and the Poisson solve leaves
/// an arbitrary constant).
///
/// # Errors
/// [`LbcError::Factorization`] only on a bug.
pub fn geodesic_distances(domain: &Domain) -> Result<Vec<Vec<f64>>, LbcError> {
    Ok(geodesics(domain, |_| ())?.0)
}

/// [`geodesic_distances`], with `beside` run on the elimination order of the mesh's
/// vertices that its factorisations follow (see [`Pattern::order`]) while they run
/// (on two threads, the heat and the Poisson matrix are factorised on one and
/// `beside` runs on the other); returns what `beside` returned too.
pub(crate) fn geodesics<R: Send>(
    domain: &Domain,
    beside: impl FnOnce(&[u32]) -> R + Send,
) -> Result<(Vec<Vec<f64>>, R), LbcError> {
    let positions = domain.positions();
    let triangles = domain.triangles();
    let nv = positions.len();
    let n = domain.cage().len();
    let elements = Elements::new(positions, triangles);
    let mass = elements.lumped_mass(triangles, nv);
    let mut edge_sum = 0.0;
    for t in triangles {
        for k in 0..3 {
            edge_sum += positions[t[k] as usize].distance(positions[t[(k + 1) % 3] as usize]);
        }
    }
    let h = edge_sum / (3 * triangles.len()).max(1) as f64;
    let all = |v: u32| Some(v as usize);
    // The solves run on rows of `n` (a column per cage vertex), as the ADMM's do.
    let wide = crate::wide::available();
    let mut scratch = Vec::new();
    // The heat and the Poisson matrix: one pattern, one ordering.
    let lower = elements.lower(triangles, &all, &mass);
    let pattern = Pattern::new(nv, &lower, None)?;
    // The mass term is relative to the domain's area, so that the frame does not matter.
    let total: f64 = mass.iter().sum();
    let order = pattern.order();
    let ((heat, poisson), side) = rayon::join(
        || {
            rayon::join(
                || RowFactor::new(&pattern, &lower.values(h * h, 1.0)),
                || RowFactor::new(&pattern, &lower.values(1.0, 1e-8 / total)),
            )
        },
        || beside(&order),
    );
    let (heat, poisson) = (heat?, poisson?);
    let mut u = vec![0.0; nv * n];
    for (i, &v) in domain.cage_vertices().iter().enumerate() {
        u[v as usize * n + i] = 1.0;
    }
    heat.solve_rows(wide, &mut u, n, &mut scratch);
    let u = columns_of(&u, n);

    // Divergence of the normalised field, per source (columns independent).
    let columns: Vec<Vec<f64>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let u = &u[i];
            let mut div = vec![0.0; nv];
            for (s, t) in triangles.iter().enumerate() {
                let g = &elements.grad[s];
                let grad_u: DVec2 = (0..3).map(|k| u[t[k] as usize] * g[k]).sum();
                let x = -grad_u.normalize_or_zero();
                for k in 0..3 {
                    div[t[k] as usize] += elements.area[s] * g[k].dot(x);
                }
            }
            div
        })
        .collect();
    let mut phi = vec![0.0; nv * n];
    for (i, div) in columns.iter().enumerate() {
        for (v, &d) in div.iter().enumerate() {
            phi[v * n + i] = d;
        }
    }
    drop(columns);
    poisson.solve_rows(wide, &mut phi, n, &mut scratch);
    let phi = columns_of(&phi, n);

    let piece = pieces(nv, triangles);
    let distances = (0..n)
        .into_par_iter()
        .map(|i| {
            let source = domain.cage_vertices()[i] as usize;
            let phi = &phi[i];
            let at = phi[source];
            let reached = |v: usize| piece[v] == piece[source];
            let mut d: Vec<f64> = phi.iter().map(|&p| (p - at).max(0.0)).collect();
            let max = (0..nv)
                .filter(|&v| reached(v))
                .map(|v| d[v])
                .fold(0.0, f64::max);
            for (v, x) in d.iter_mut().enumerate() {
                *x = match (reached(v), max > 0.0) {
                    (false, _) => 1.0,
                    (true, true) => *x / max,
                    (true, false) => *x,
                };
            }
            d
        })
        .collect();
    Ok((distances, side))
}

/// The columns of `rows` (row-major, `n` values a row), each as one vector.
fn columns_of(rows: &[f64], n: usize) -> Vec<Vec<f64>> {
    (0..n)
        .into_par_iter()
        .map(|i| rows.iter().skip(i).step_by(n).copied().collect())
        .collect()
}

/// The connected piece of each of `nv` vertices (a representative vertex), joined
/// through `triangles`.
fn pieces(nv: usize, triangles: &[[u32; 3]]) -> Vec<u32> {
    let mut parent: Vec<u32> = (0..nv as u32).collect();
    fn root(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            let up = parent[parent[v as usize] as usize];
            parent[v as usize] = up;
            v = up;
        }
        v
    }
    for t in triangles {
        let a = root(&mut parent, t[0]);
        for &w in &t[1..] {
            let b = root(&mut parent, w);
            if a != b {
                parent[b as usize] = a;
            }
        }
    }
    (0..nv as u32).map(|v| root(&mut parent, v)).collect()
}
