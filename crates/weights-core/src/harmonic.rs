//! Harmonic coordinates of the virtual handles with respect to the real handles, on
//! the dual (Delaunay) graph of the Voronoi cells: one harmonic field per real handle,
//! 1 on that handle's nodes and 0 on every other real node, solved directly per
//! component of the virtual handles and stored sparse.

use glam::DVec2;
use rayon::prelude::*;

use crate::domain::{Domain, Metric};
use crate::ldl::{BLOCK, Ldl, dissection_order};
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

/// Coefficients below this are left out (and the others scaled to sum to one).
///
/// A group's field falls off exponentially with the real nodes between it and a
/// virtual one; where thousands of virtual handles surround thousands of handles,
/// keeping every coefficient would cost a number per handle per virtual handle (25
/// million for 2,000 random handles on the lizard at 20k samples; 2.3 million, 180 a
/// virtual handle, at this threshold). Even with 10,000 handles the mass left out is
/// under 1e-6 of a node's, and it moves a virtual handle by less than a millionth of
/// the largest difference between two handles' motions.
pub(crate) const NEGLIGIBLE: f64 = 1e-10;

/// The harmonic coefficients of one virtual node: `(group, coefficient)` pairs, groups
/// ascending, coefficients at least [`NEGLIGIBLE`] and summing to 1; empty when no real
/// handle is connected to the node.
pub(crate) type Coefficients = Box<[(u32, f64)]>;

/// Harmonic coefficients: for every node, `None` for a real node (it has a group of its
/// own) or its coefficients over the `groups` real handles.
///
/// The field of group g is 1 on g's nodes, 0 on the other real nodes and harmonic
/// (with edge weights 1/length) at the free nodes. Free nodes fall into components
/// joined by free–free edges: a component's values depend only on the groups it
/// touches (every other group's field is exactly zero on it), so each component is
/// solved on its own, for the groups it touches, by one sparse LDLᵀ factorisation and
/// one solve per group. (A global iterative solve per group cost groups × iterations ×
/// nodes: minutes for thousands of virtual handles around hundreds of handles.)
pub(crate) fn harmonic_coordinates(
    positions: &[DVec2],
    node_vertex: &[u32],
    node_rank: &[u32],
    node_group: &[Option<usize>],
    edges: &[(u32, u32)],
    progress: &(dyn Fn(usize, usize) + Sync),
    earlier: &Solved,
) -> (Vec<Option<Coefficients>>, Solved) {
    let n = node_vertex.len();
    // Free nodes in a canonical order (by the rank of their samples), so results do not
    // depend on how the nodes happen to be numbered.
    let mut free: Vec<usize> = (0..n).filter(|&k| node_group[k].is_none()).collect();
    free.sort_unstable_by_key(|&k| node_rank[k]);
    let mut index = vec![u32::MAX; n];
    for (i, &k) in free.iter().enumerate() {
        index[k] = i as u32;
    }
    let mut adjacency: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
    for &(a, b) in edges {
        let (a, b) = (a as usize, b as usize);
        if node_group[a].is_some() && node_group[b].is_some() {
            continue;
        }
        let len = (positions[node_vertex[a] as usize] - positions[node_vertex[b] as usize])
            .length()
            .max(1e-12);
        adjacency[a].push((b, 1.0 / len));
        adjacency[b].push((a, 1.0 / len));
    }
    for list in adjacency.iter_mut() {
        list.sort_unstable_by_key(|&(j, _)| node_rank[j]);
    }
    // Components of the free nodes, each listed in free order, in the order of their
    // first member.
    let mut component = vec![u32::MAX; free.len()];
    let mut components: Vec<Vec<u32>> = Vec::new();
    for start in 0..free.len() {
        if component[start] != u32::MAX {
            continue;
        }
        let c = components.len() as u32;
        component[start] = c;
        let mut members = vec![start as u32];
        let mut next = 0;
        while next < members.len() {
            let i = members[next] as usize;
            next += 1;
            for &(j, _) in &adjacency[free[i]] {
                let fj = index[j];
                if fj != u32::MAX && component[fj as usize] == u32::MAX {
                    component[fj as usize] = c;
                    members.push(fj);
                }
            }
        }
        members.sort_unstable();
        components.push(members);
    }
    // The groups each component touches, and a solve per group and component.
    let touched: Vec<Vec<u32>> = components
        .par_iter()
        .map(|members| {
            let mut groups: Vec<u32> = members
                .iter()
                .flat_map(|&i| adjacency[free[i as usize]].iter())
                .filter_map(|&(j, _)| node_group[j].map(|g| g as u32))
                .collect();
            groups.sort_unstable();
            groups.dedup();
            groups
        })
        .collect();
    let total: usize = touched.iter().map(Vec::len).sum();
    progress(0, total);
    // Solves done so far, told in order.
    let done = std::sync::Mutex::new(0usize);
    let solved_some = |count: usize| {
        let mut done = done
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        for _ in 0..count {
            *done += 1;
            progress(*done, total);
        }
    };
    // A component solved before, with the same inputs, is taken as it was.
    let solved: Vec<(Vec<u64>, SolvedRows)> = components
        .par_iter()
        .zip(&touched)
        .map(|(members, groups)| {
            let key = component_key(
                node_vertex,
                node_group,
                (&free, &index, &adjacency),
                members,
                groups,
            );
            if let Some(rows) = earlier.0.get(&key) {
                solved_some(groups.len());
                return (key, rows.clone());
            }
            let rows = solve_component(
                positions,
                node_vertex,
                node_group,
                (&free, &index, &adjacency),
                members,
                groups,
                &solved_some,
            );
            (key, rows.into())
        })
        .collect();
    let mut out: Vec<Option<Coefficients>> = vec![None; n];
    for ((members, groups), (_, rows)) in components.iter().zip(&touched).zip(&solved) {
        for (&i, row) in members.iter().zip(rows.iter()) {
            let named: Coefficients = row
                .iter()
                .map(|&(rank, v)| (groups[rank as usize], v))
                .collect();
            out[free[i as usize]] = Some(named);
        }
    }
    (out, Solved(solved.into_iter().collect()))
}

/// A component's rows, each coefficient with the rank of its group among those the
/// component touches.
type SolvedRows = std::sync::Arc<[Coefficients]>;

/// The components solved by a call of [`harmonic_coordinates`], by their inputs: the
/// next call takes those it meets again as they are. An insertion changes the dual
/// graph only near the new handle, so with thousands of handles it re-solves a few
/// components instead of all.
#[derive(Clone, Debug, Default)]
pub(crate) struct Solved(std::collections::HashMap<Vec<u64>, SolvedRows>);

/// Everything a component's solution depends on: its members' samples, and for each
/// member its neighbours in order, free ones by sample, real ones by sample and the
/// rank of their group among those the component touches (ranks, not group numbers,
/// so that handles renumbered after a removal do not count as a change). The edge
/// weights and the ordering follow from the samples' positions.
fn component_key(
    node_vertex: &[u32],
    node_group: &[Option<usize>],
    (free, _, adjacency): FreeGraph,
    members: &[u32],
    groups: &[u32],
) -> Vec<u64> {
    let mut key = Vec::with_capacity(members.len() * 8);
    for &i in members {
        let k = free[i as usize];
        key.push(u64::from(node_vertex[k]) | (adjacency[k].len() as u64) << 32);
        for &(j, _) in &adjacency[k] {
            let sample = u64::from(node_vertex[j]);
            key.push(match node_group[j] {
                None => sample,
                Some(g) => {
                    let rank = groups.binary_search(&(g as u32)).unwrap_or(0) as u64;
                    1 << 63 | rank << 32 | sample
                }
            });
        }
    }
    key
}

/// The free nodes in canonical order, each node's index among them, and the dual graph
/// with edge weights.
type FreeGraph<'a> = (&'a [usize], &'a [u32], &'a [Vec<(usize, f64)>]);

/// The coefficients of one component of free nodes (`members`: free indices,
/// ascending), in the members' order, over the groups it touches (`groups`,
/// ascending), each named by its rank among them; `solved` is called after each
/// group's solve.
fn solve_component(
    positions: &[DVec2],
    node_vertex: &[u32],
    node_group: &[Option<usize>],
    (free, index, adjacency): FreeGraph,
    members: &[u32],
    groups: &[u32],
    solved: &(dyn Fn(usize) + Sync),
) -> Vec<Coefficients> {
    let m = members.len();
    // Local numbering: position in `members`.
    let local = |fj: u32| members.binary_search(&fj).map(|l| l as u32).ok();
    if groups.is_empty() {
        return vec![Box::default(); m];
    }
    // The system: diagonal = all edge weights of the node, off-diagonal −w to free
    // neighbours; right-hand side of group g: the weights of the edges to g's nodes.
    let mut diagonal = Vec::with_capacity(m);
    let mut inner: Vec<Vec<(u32, f64)>> = Vec::with_capacity(m);
    let mut rhs: Vec<Vec<(u32, f64)>> = vec![Vec::new(); groups.len()];
    for (l, &i) in members.iter().enumerate() {
        let k = free[i as usize];
        let mut row = Vec::with_capacity(adjacency[k].len());
        let mut d = 0.0;
        for &(j, w) in &adjacency[k] {
            d += w;
            match node_group[j] {
                Some(g) => {
                    let c = groups.binary_search(&(g as u32)).unwrap_or(0);
                    rhs[c].push((l as u32, w));
                }
                None => {
                    if let Some(lj) = local(index[j]) {
                        row.push((lj, w));
                    }
                }
            }
        }
        diagonal.push(d);
        inner.push(row);
    }
    let points: Vec<DVec2> = members
        .iter()
        .map(|&i| positions[node_vertex[free[i as usize]] as usize])
        .collect();
    let order = dissection_order(&points, &inner);
    let Some(ldl) = Ldl::factor(&diagonal, &inner, order) else {
        // Not reached: a component with an edge to a real node is positive definite.
        solved(groups.len());
        return vec![Box::default(); m];
    };
    // One solve per group, in parallel; each group's values kept where positive.
    let columns: Vec<Vec<(u32, f64)>> = rhs
        .par_chunks(BLOCK)
        .map_init(
            || (vec![[0.0; BLOCK]; m], vec![[0.0; BLOCK]; m]),
            |(x, work), block| {
                let bs: Vec<&[(u32, f64)]> = block.iter().map(Vec::as_slice).collect();
                ldl.solve_block(&bs, x, work);
                let columns: Vec<Vec<(u32, f64)>> = (0..block.len())
                    .map(|r| {
                        x.iter()
                            .enumerate()
                            .filter(|(_, v)| v[r] >= NEGLIGIBLE)
                            .map(|(l, v)| (l as u32, v[r]))
                            .collect()
                    })
                    .collect();
                solved(block.len());
                columns
            },
        )
        .flatten()
        .collect();
    let mut rows: Vec<Vec<(u32, f64)>> = vec![Vec::new(); m];
    for (c, column) in columns.iter().enumerate() {
        for &(l, v) in column {
            rows[l as usize].push((c as u32, v));
        }
    }
    rows.into_iter()
        .map(|mut row| {
            let sum: f64 = row.iter().map(|e| e.1).sum();
            if sum > 0.0 {
                row.iter_mut().for_each(|e| e.1 /= sum);
            }
            row.into_boxed_slice()
        })
        .collect()
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
        let h = harmonic_coordinates(
            &positions,
            &node_vertex,
            &node_vertex,
            &groups,
            &edges,
            &|_, _| {},
            &Solved::default(),
        )
        .0;
        for (i, c) in h.iter().enumerate().take(4).skip(1) {
            let c = c.as_ref().expect("free");
            assert_eq!((c[0].0, c[1].0), (0, 1));
            assert!((c[0].1 - (1.0 - i as f64 / 4.0)).abs() < 1e-15, "{c:?}");
            assert!((c[0].1 + c[1].1 - 1.0).abs() < 1e-15);
        }
        assert!(h[0].is_none() && h[4].is_none());
    }

    #[test]
    fn unanchored_nodes_get_nothing() {
        let positions: Vec<DVec2> = (0..4).map(|i| DVec2::new(i as f64, 0.0)).collect();
        let node_vertex: Vec<u32> = (0..4).collect();
        let groups = [Some(0), None, None, None];
        let edges = [(0, 1), (2, 3)];
        let h = harmonic_coordinates(
            &positions,
            &node_vertex,
            &node_vertex,
            &groups,
            &edges,
            &|_, _| {},
            &Solved::default(),
        )
        .0;
        assert_eq!(h[1].as_deref(), Some(&[(0, 1.0)][..]));
        assert_eq!(h[2].as_deref(), Some(&[][..]));
    }

    #[test]
    fn a_component_sees_only_the_groups_it_touches() {
        // Free chain 1–2 between groups 0 and 1; free node 4 hangs off group 2 alone.
        let positions: Vec<DVec2> = (0..6).map(|i| DVec2::new(i as f64, 0.0)).collect();
        let node_vertex: Vec<u32> = (0..6).collect();
        let node_group = [Some(0), None, None, Some(1), None, Some(2)];
        let edges = [(0, 1), (1, 2), (2, 3), (4, 5)];
        let h = harmonic_coordinates(
            &positions,
            &node_vertex,
            &node_vertex,
            &node_group,
            &edges,
            &|_, _| {},
            &Solved::default(),
        )
        .0;
        let groups_of =
            |k: usize| -> Vec<u32> { h[k].as_deref().expect("free").iter().map(|e| e.0).collect() };
        assert_eq!(groups_of(1), vec![0, 1]);
        assert_eq!(groups_of(2), vec![0, 1]);
        assert_eq!(h[4].as_deref(), Some(&[(2, 1.0)][..]));
    }

    #[test]
    fn harmonic_fields_satisfy_the_mean_value_property() {
        use crate::domain::tests::grid_mesh;
        // Free nodes on a grid with a few real nodes of three groups: at every free node
        // each group's coefficient is the weighted mean of its neighbours'.
        let (p, _) = grid_mesh(30, 20, 1.0);
        let id = |i: u32, j: u32| j * 31 + i;
        let node_vertex: Vec<u32> = (0..p.len() as u32).collect();
        let mut node_group = vec![None; p.len()];
        for (g, v) in [
            (0, id(3, 3)),
            (1, id(25, 15)),
            (2, id(10, 18)),
            (2, id(11, 18)),
        ] {
            node_group[v as usize] = Some(g);
        }
        let mut edges = Vec::new();
        for j in 0..=20 {
            for i in 0..=30 {
                if i < 30 {
                    edges.push((id(i, j), id(i + 1, j)));
                }
                if j < 20 {
                    edges.push((id(i, j), id(i, j + 1)));
                }
            }
        }
        let h = harmonic_coordinates(
            &p,
            &node_vertex,
            &node_vertex,
            &node_group,
            &edges,
            &|_, _| {},
            &Solved::default(),
        )
        .0;
        let value = |k: usize, g: u32| -> f64 {
            match node_group[k] {
                Some(own) => f64::from(u8::from(own as u32 == g)),
                None => h[k]
                    .as_deref()
                    .and_then(|c| c.iter().find(|e| e.0 == g))
                    .map_or(0.0, |e| e.1),
            }
        };
        let mut neighbours = vec![Vec::new(); p.len()];
        for &(a, b) in &edges {
            neighbours[a as usize].push(b as usize);
            neighbours[b as usize].push(a as usize);
        }
        for k in (0..p.len()).filter(|&k| node_group[k].is_none()) {
            let c = h[k].as_deref().expect("free");
            assert_eq!(c.len(), 3);
            assert!((c.iter().map(|e| e.1).sum::<f64>() - 1.0).abs() < 1e-14);
            for g in 0..3 {
                let mean = neighbours[k].iter().map(|&j| value(j, g)).sum::<f64>()
                    / neighbours[k].len() as f64;
                assert!((value(k, g) - mean).abs() < 1e-12, "node {k}, group {g}");
            }
        }
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
