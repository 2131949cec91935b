//! Harmonic coordinates of the virtual handles with respect to the real handles, on
//! the dual (Delaunay) graph of the Voronoi cells: one harmonic field per real handle,
//! 1 on that handle's nodes and 0 on every other real node.

use glam::DVec2;
use rayon::prelude::*;

use crate::domain::{Domain, Metric};
use crate::voronoi::{NONE, Partition};

/// The dual graph: pairs of nodes whose closed cells share a mesh edge, each pair once
/// with the lower node index first, sorted.
///
/// A sample at exactly equal distance from two nodes belongs to one cell by the
/// tie-break but to both closed cells, so it also links the other node to the cells
/// around it; this keeps the graph of a mirror-symmetric rig symmetric.
pub(crate) fn dual_edges(domain: &Domain, partition: &Partition) -> Vec<(u32, u32)> {
    let owner = &partition.owner;
    let dist = &partition.dist;
    let positions = domain.positions();
    // Whether sample `w` is as close to node `k` (owner of its neighbour `u`) as to its own.
    let tied = |w: u32, u: u32, k: u32| -> bool {
        let dw = dist[w as usize];
        match domain.metric() {
            Metric::Euclidean => {
                (positions[w as usize] - positions[partition.node_vertex[k as usize] as usize])
                    .length()
                    == dw
            }
            Metric::Intrinsic => {
                let len = (positions[w as usize] - positions[u as usize]).length() as f32;
                dist[u as usize] + f64::from(len) == dw
            }
        }
    };
    let (mut pairs, ties) = domain
        .triangles()
        .par_chunks(4096)
        .fold(
            || (Vec::new(), Vec::new()),
            |(mut acc, mut ties), chunk| {
                for t in chunk {
                    for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                        let (oa, ob) = (owner[a as usize], owner[b as usize]);
                        if oa != ob && oa != NONE && ob != NONE {
                            acc.push((oa.min(ob), oa.max(ob)));
                            if tied(a, b, ob) {
                                ties.push((a, ob));
                            }
                            if tied(b, a, oa) {
                                ties.push((b, oa));
                            }
                        }
                    }
                }
                acc.sort_unstable();
                acc.dedup();
                (acc, ties)
            },
        )
        .reduce(
            || (Vec::new(), Vec::new()),
            |(mut a, mut ta), (b, tb)| {
                a.extend(b);
                ta.extend(tb);
                (a, ta)
            },
        );
    if !ties.is_empty() {
        // Link each tied sample's other node to every cell around the sample.
        let mut tied_with: std::collections::HashMap<u32, Vec<u32>> =
            std::collections::HashMap::new();
        let mut is_tied = vec![false; owner.len()];
        for (w, k) in ties {
            is_tied[w as usize] = true;
            tied_with.entry(w).or_default().push(k);
        }
        for t in domain.triangles() {
            for (i, &w) in t.iter().enumerate() {
                if !is_tied[w as usize] {
                    continue;
                }
                for &k in &tied_with[&w] {
                    for &u in [t[(i + 1) % 3], t[(i + 2) % 3]].iter() {
                        let o = owner[u as usize];
                        if o != k && o != NONE {
                            pairs.push((o.min(k), o.max(k)));
                        }
                    }
                }
            }
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    pairs
}

/// Harmonic coefficients: for every node, `None` for a real node (it has a group of its
/// own) or the coefficients over the `groups` real handles (summing to 1, or all zero
/// when no real handle is connected to it).
pub(crate) fn harmonic_coordinates(
    positions: &[DVec2],
    node_vertex: &[u32],
    node_group: &[Option<usize>],
    groups: usize,
    edges: &[(u32, u32)],
) -> Vec<Option<Vec<f64>>> {
    let n = node_vertex.len();
    // Free nodes in a canonical order (by sample), so results do not depend on how the
    // nodes happen to be numbered.
    let mut free: Vec<usize> = (0..n).filter(|&k| node_group[k].is_none()).collect();
    free.sort_unstable_by_key(|&k| node_vertex[k]);
    let mut index = vec![usize::MAX; n];
    for (i, &k) in free.iter().enumerate() {
        index[k] = i;
    }
    let mut adjacency: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
    for &(a, b) in edges {
        let (a, b) = (a as usize, b as usize);
        let len = (positions[node_vertex[a] as usize] - positions[node_vertex[b] as usize])
            .length()
            .max(1e-12);
        adjacency[a].push((b, 1.0 / len));
        adjacency[b].push((a, 1.0 / len));
    }
    for list in adjacency.iter_mut() {
        list.sort_unstable_by_key(|&(j, _)| node_vertex[j]);
    }
    // Free nodes connected (through free nodes) to some real node.
    let mut anchored = vec![false; free.len()];
    let mut stack: Vec<usize> = free
        .iter()
        .enumerate()
        .filter(|(_, k)| adjacency[**k].iter().any(|&(j, _)| node_group[j].is_some()))
        .map(|(i, _)| i)
        .collect();
    for &i in &stack {
        anchored[i] = true;
    }
    while let Some(i) = stack.pop() {
        for &(j, _) in &adjacency[free[i]] {
            let fj = index[j];
            if fj != usize::MAX && !anchored[fj] {
                anchored[fj] = true;
                stack.push(fj);
            }
        }
    }
    let diag: Vec<f64> = free
        .iter()
        .map(|&k| adjacency[k].iter().map(|&(_, w)| w).sum())
        .collect();
    let apply = |x: &[f64], out: &mut [f64]| {
        for (i, &k) in free.iter().enumerate() {
            if !anchored[i] {
                out[i] = 0.0;
                continue;
            }
            let mut s = diag[i] * x[i];
            for &(j, w) in &adjacency[k] {
                let fj = index[j];
                if fj != usize::MAX {
                    s -= w * x[fj];
                }
            }
            out[i] = s;
        }
    };
    let columns: Vec<Vec<f64>> = (0..groups)
        .into_par_iter()
        .map(|g| {
            let b: Vec<f64> = free
                .iter()
                .enumerate()
                .map(|(i, &k)| {
                    if !anchored[i] {
                        return 0.0;
                    }
                    adjacency[k]
                        .iter()
                        .filter(|&&(j, _)| node_group[j] == Some(g))
                        .map(|&(_, w)| w)
                        .sum()
                })
                .collect();
            conjugate_gradient(&apply, &diag, &b)
        })
        .collect();
    let mut out: Vec<Option<Vec<f64>>> = vec![None; n];
    for (i, &k) in free.iter().enumerate() {
        let mut coefficients: Vec<f64> = columns.iter().map(|c| c[i].max(0.0)).collect();
        let sum: f64 = coefficients.iter().sum();
        if sum > 0.0 {
            coefficients.iter_mut().for_each(|c| *c /= sum);
        }
        out[k] = Some(coefficients);
    }
    out
}

/// Jacobi-preconditioned conjugate gradients for the symmetric positive definite
/// system `A x = b`, to a relative residual of 1e-13.
fn conjugate_gradient(apply: &dyn Fn(&[f64], &mut [f64]), diag: &[f64], b: &[f64]) -> Vec<f64> {
    let n = b.len();
    let mut x = vec![0.0; n];
    let mut r = b.to_vec();
    let precondition = |r: &[f64]| -> Vec<f64> {
        r.iter()
            .zip(diag)
            .map(|(r, d)| if *d > 0.0 { r / d } else { 0.0 })
            .collect()
    };
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(a, b)| a * b).sum::<f64>();
    let norm_b = dot(b, b).sqrt();
    if norm_b == 0.0 {
        return x;
    }
    let mut z = precondition(&r);
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut ap = vec![0.0; n];
    for _ in 0..(10 * n + 100) {
        apply(&p, &mut ap);
        let pap = dot(&p, &ap);
        if pap <= 0.0 {
            break;
        }
        let alpha = rz / pap;
        for i in 0..n {
            x[i] += alpha * p[i];
            r[i] -= alpha * ap[i];
        }
        if dot(&r, &r).sqrt() <= 1e-13 * norm_b {
            break;
        }
        z = precondition(&r);
        let rz_next = dot(&r, &z);
        let beta = rz_next / rz;
        rz = rz_next;
        for i in 0..n {
            p[i] = z[i] + beta * p[i];
        }
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn path_graph_interpolates_linearly() {
        // Nodes 0..5 on a line at x = 0..4; 0 is group 0, 4 is group 1.
        let positions: Vec<DVec2> = (0..5).map(|i| DVec2::new(i as f64, 0.0)).collect();
        let node_vertex: Vec<u32> = (0..5).collect();
        let groups = [Some(0), None, None, None, Some(1)];
        let edges = [(0, 1), (1, 2), (2, 3), (3, 4)];
        let h = harmonic_coordinates(&positions, &node_vertex, &groups, 2, &edges);
        for (i, c) in h.iter().enumerate().take(4).skip(1) {
            let c = c.as_ref().expect("free");
            assert!((c[0] - (1.0 - i as f64 / 4.0)).abs() < 1e-12, "{c:?}");
            assert!((c[0] + c[1] - 1.0).abs() < 1e-12);
        }
        assert!(h[0].is_none() && h[4].is_none());
    }

    #[test]
    fn unanchored_nodes_get_nothing() {
        let positions: Vec<DVec2> = (0..4).map(|i| DVec2::new(i as f64, 0.0)).collect();
        let node_vertex: Vec<u32> = (0..4).collect();
        let groups = [Some(0), None, None, None];
        let edges = [(0, 1), (2, 3)];
        let h = harmonic_coordinates(&positions, &node_vertex, &groups, 1, &edges);
        assert_eq!(h[1].as_deref(), Some(&[1.0][..]));
        assert_eq!(h[2].as_deref(), Some(&[0.0][..]));
    }
}
