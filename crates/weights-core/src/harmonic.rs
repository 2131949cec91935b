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
    let (mut pairs, ties) = match domain.metric() {
        Metric::Intrinsic => frontier_pairs(domain, partition),
        Metric::Euclidean => triangle_pairs(domain, partition),
    };
    if !ties.is_empty() {
        // Link each tied sample's other node to every cell around the sample (its graph
        // neighbours are the other corners of its triangles).
        let owner = &partition.owner;
        let mut around = |k: u32, u: u32| {
            let o = owner[u as usize];
            if o != k && o != NONE {
                pairs.push((o.min(k), o.max(k)));
            }
        };
        match domain.metric() {
            Metric::Intrinsic => {
                let graph = domain.graph();
                for &(w, k) in &ties {
                    for e in graph.neighbors(w) {
                        around(k, e.to);
                    }
                }
            }
            Metric::Euclidean => {
                let mut tied_with: std::collections::HashMap<u32, Vec<u32>> =
                    std::collections::HashMap::new();
                let mut is_tied = vec![false; owner.len()];
                for &(w, k) in &ties {
                    is_tied[w as usize] = true;
                    tied_with.entry(w).or_default().push(k);
                }
                for t in domain.triangles() {
                    for (i, &w) in t.iter().enumerate() {
                        if !is_tied[w as usize] {
                            continue;
                        }
                        let nodes = &tied_with[&w];
                        for &k in nodes {
                            around(k, t[(i + 1) % 3]);
                            around(k, t[(i + 2) % 3]);
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

/// Node pairs whose cells share a mesh edge (possibly repeated), and tied samples with
/// the other node they are tied with.
type PairsAndTies = (Vec<(u32, u32)>, Vec<(u32, u32)>);

/// Node pairs and ties, intrinsic metric: from the cells' frontier samples, the only
/// ones with an edge into another cell. A sample `w` is tied with node `k` when the
/// path through its neighbour `u` in `k`'s cell reaches it at exactly its distance.
fn frontier_pairs(domain: &Domain, partition: &Partition) -> PairsAndTies {
    let (owner, dist) = (&partition.owner, &partition.dist);
    let graph = domain.graph();
    let mut pairs = Vec::new();
    let mut ties = Vec::new();
    // Each pair is seen from both cells; the lower one records it, once.
    let mut recorded = vec![NONE; partition.len()];
    for k in 0..partition.len() as u32 {
        for &u in partition.frontier(k as usize) {
            for e in graph.neighbors(u) {
                let o = owner[e.to as usize];
                if o != k && o != NONE {
                    if k < o && recorded[o as usize] != k {
                        recorded[o as usize] = k;
                        pairs.push((k, o));
                    }
                    if dist[e.to as usize] + f64::from(e.len) == dist[u as usize] {
                        ties.push((u, o));
                    }
                }
            }
        }
    }
    (pairs, ties)
}

/// Node pairs and ties, straight-line metric: from every triangle edge. A sample is
/// tied with node `k` when it is exactly as far from `k` as from its own node.
fn triangle_pairs(domain: &Domain, partition: &Partition) -> PairsAndTies {
    let owner = &partition.owner;
    let dist = &partition.dist;
    let positions = domain.positions();
    let tied = |w: u32, k: u32| -> bool {
        (positions[w as usize] - positions[partition.node_vertex[k as usize] as usize]).length()
            == dist[w as usize]
    };
    domain
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
                            if tied(a, ob) {
                                ties.push((a, ob));
                            }
                            if tied(b, oa) {
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
        )
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

    /// The dual graph by brute force: every triangle edge, with the closed-cell ties
    /// of the intrinsic metric.
    fn dual_by_scan(domain: &Domain, partition: &Partition) -> Vec<(u32, u32)> {
        let (owner, dist) = (&partition.owner, &partition.dist);
        let positions = domain.positions();
        let mut pairs = Vec::new();
        let mut ties = Vec::new();
        for t in domain.triangles() {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                let (oa, ob) = (owner[a as usize], owner[b as usize]);
                if oa != ob {
                    pairs.push((oa.min(ob), oa.max(ob)));
                    let len =
                        f64::from((positions[a as usize] - positions[b as usize]).length() as f32);
                    if dist[b as usize] + len == dist[a as usize] {
                        ties.push((a, ob));
                    }
                    if dist[a as usize] + len == dist[b as usize] {
                        ties.push((b, oa));
                    }
                }
            }
        }
        for t in domain.triangles() {
            for (i, &w) in t.iter().enumerate() {
                for &(tw, k) in ties.iter().filter(|(tw, _)| *tw == w) {
                    debug_assert_eq!(tw, w);
                    for u in [t[(i + 1) % 3], t[(i + 2) % 3]] {
                        let o = owner[u as usize];
                        if o != k {
                            pairs.push((o.min(k), o.max(k)));
                        }
                    }
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        pairs
    }

    #[test]
    fn dual_graph_from_frontiers_matches_a_scan_of_every_triangle() {
        use crate::domain::tests::grid_mesh;
        // A regular grid (many exact ties) and nodes added and removed one by one, so
        // the frontier lists are the incrementally kept ones.
        let (p, t) = grid_mesh(24, 18, 1.0);
        let d = Domain::new(p, t, Metric::Intrinsic).expect("valid");
        let mut part = Partition::new(&d, vec![0, 60, 200, 333]);
        assert_eq!(dual_edges(&d, &part), dual_by_scan(&d, &part));
        for v in [12, 130, 250, 300, 77] {
            part.add_node(&d, v);
            assert_eq!(dual_edges(&d, &part), dual_by_scan(&d, &part));
        }
        for k in [2, 0, 5] {
            part.remove_node(&d, k);
            assert_eq!(dual_edges(&d, &part), dual_by_scan(&d, &part));
        }
        assert!(dual_edges(&d, &part).len() >= part.len() - 1);
        // Cells that touch only through a sample at equal distance from both nodes.
        for nodes in [vec![113, 219, 294, 372], vec![56, 175, 187, 407]] {
            let part = Partition::new(&d, nodes);
            assert_eq!(dual_edges(&d, &part), dual_by_scan(&d, &part));
        }
    }
}
