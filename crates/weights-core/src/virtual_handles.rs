//! Algorithm 1 of the paper: insert virtual handles until every node's cell fits
//! inside the ball that reaches its nearest neighbour (r_d < r_h).
//!
//! We insert while r_d ≥ r_h (the paper writes r_d > r_h): with a strict r_d < r_h
//! every sample lies strictly inside its own node's support when α = 1, so the sum of
//! basis values never vanishes. Each insertion puts a node on a sample that carried
//! none (the farthest sample of a cell with r_d > 0), so the loop ends after at most as
//! many insertions as there are samples.

use crate::domain::{Domain, Metric};
use crate::voronoi::Partition;

/// Relative tolerance under which two violation ratios count as tied. Tied violators
/// (and tied farthest samples of one cell) are fixed together, so that a
/// mirror-symmetric rig keeps its symmetry.
const TIE: f64 = 1e-9;
/// At most this many tied farthest samples of one cell get a virtual handle at once.
const MAX_TIED_PER_CELL: usize = 4;

/// Inserts virtual nodes into `partition` until the r_d < r_h condition holds for every
/// node, and every sample is reached by some node. Returns the new nodes' samples in
/// insertion order (they are appended to the partition's nodes in that order).
/// `inserted` is told of each new node (its index) as soon as it is in: its radii can
/// only shrink from there on.
pub(crate) fn insert_virtual_handles(
    domain: &Domain,
    partition: &mut Partition,
    mut inserted: impl FnMut(&Partition, usize),
) -> Vec<u32> {
    let mut added = Vec::new();
    if partition.len() == 0 {
        // No handles: nothing moves, nothing to weigh.
        return added;
    }
    if domain.metric() == Metric::Intrinsic {
        // One node for every component of the sample graph that no node reaches.
        for v in partition.unreached() {
            if partition.owner[v as usize] == crate::voronoi::NONE {
                partition.add_node(domain, v);
                inserted(partition, partition.len() - 1);
                added.push(v);
            }
        }
    }
    loop {
        let round_start = added.len();
        let mut violators: Vec<(f64, usize)> = partition
            .stats
            .iter()
            .enumerate()
            .filter(|(_, s)| s.r_d > 0.0 && s.r_d >= s.r_h)
            .map(|(k, s)| ((s.r_d - s.r_h) / s.r_d, k))
            .collect();
        if violators.is_empty() {
            break;
        }
        let key = |k: usize| partition.node_vertex[k];
        violators.sort_by(|a, b| b.0.total_cmp(&a.0).then(key(a.1).cmp(&key(b.1))));
        let top = violators[0].0;
        // Tied violators are fixed together, so that mirror images of a symmetric rig
        // get mirror-image virtual handles; a cell whose farthest samples tie (a
        // symmetric cell) offers all of them, up to a few (perfectly regular grids can
        // tie many). Candidates closer together than the violator's r_h are merged into
        // one handle at the sample nearest their centroid: two new nodes that close would
        // lower the rig's smallest r_h (the plain greedy never does), and Algorithm 1
        // would then refine everything around them to that spacing. A mirror pair merges
        // onto the mirror line, which keeps the symmetry.
        let positions = domain.positions();
        let mut groups: Vec<(Vec<u32>, f64)> = Vec::new();
        for &(ratio, k) in &violators {
            if ratio < top - TIE * top.abs().max(TIE) {
                break;
            }
            let r_h = partition.stats[k].r_h;
            for far in partition
                .farthest_samples(domain, k)
                .into_iter()
                .take(MAX_TIED_PER_CELL)
            {
                let p = positions[far as usize];
                let near = groups.iter_mut().find(|(members, reach)| {
                    members
                        .iter()
                        .any(|&b| (positions[b as usize] - p).length() < r_h.max(*reach))
                });
                match near {
                    Some((members, _)) => {
                        if !members.contains(&far) {
                            members.push(far);
                        }
                    }
                    None => groups.push((vec![far], r_h)),
                }
            }
        }
        // Single candidates are farthest samples: each lies in its cell (at least its
        // violator's r_h from every node) and, by the grouping, at least that far from
        // the other groups' members, so they go in as they are. A merged group's
        // centroid need not keep that distance, from the nodes or from this round's
        // other candidates: it goes in last, only if it does (else the group's first
        // member, if that still does; else the group waits for the next round). So no
        // insertion brings two nodes closer than the smallest r_h so far, and the
        // refinement stays graded instead of filling the shape.
        let (singles, merged): (Vec<_>, Vec<_>) = groups
            .into_iter()
            .partition(|(members, _)| members.len() == 1);
        for (members, _) in singles {
            partition.add_node(domain, members[0]);
            inserted(partition, partition.len() - 1);
            added.push(members[0]);
        }
        for (members, r_h) in merged {
            let centroid = members
                .iter()
                .map(|&b| positions[b as usize])
                .sum::<glam::DVec2>()
                / members.len() as f64;
            let candidate = domain
                .nearest_vertex(centroid)
                .into_iter()
                .chain(members.first().copied())
                .find(|&v| partition.dist[v as usize] >= r_h);
            if let Some(v) = candidate {
                partition.add_node(domain, v);
                inserted(partition, partition.len() - 1);
                added.push(v);
            }
        }
        // Every round places a node (a violator's farthest sample always qualifies when
        // nothing else went in); a round that placed none could only repeat itself.
        if added.len() == round_start {
            debug_assert!(false, "Algorithm 1 made no progress");
            break;
        }
    }
    added
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::domain::tests::grid_mesh;
    use glam::DVec2;

    #[test]
    fn two_handles_one_sample_apart_terminate() {
        for metric in [Metric::Intrinsic, Metric::Euclidean] {
            let (p, t) = grid_mesh(40, 30, 1.0);
            let d = Domain::new(p, t, metric).expect("valid");
            let mut part = Partition::new(&d, vec![41 * 10 + 20, 41 * 10 + 21]);
            let added = insert_virtual_handles(&d, &mut part, |_, _| {});
            assert!(!added.is_empty());
            for s in &part.stats {
                assert!(s.r_d < s.r_h, "{s:?}");
            }
            part.assert_matches_rebuild(&d);
        }
    }

    #[test]
    fn close_nodes_refine_locally_without_filling_the_shape() {
        // A line of nodes two edges apart (a finely sampled bar) with a node two edges
        // beside it: no node may end up nearer another than that (in the metric), and
        // the refinement must stay far from one node per sample.
        for metric in [Metric::Intrinsic, Metric::Euclidean] {
            let (p, t) = grid_mesh(80, 60, 1.0);
            let samples = p.len();
            let d = Domain::new(p, t, metric).expect("valid");
            let id = |i: u32, j: u32| j * 81 + i;
            let mut nodes: Vec<u32> = (10..=70).step_by(2).map(|i| id(i, 30)).collect();
            nodes.push(id(40, 32));
            let mut part = Partition::new(&d, nodes);
            let added = insert_virtual_handles(&d, &mut part, |_, _| {});
            assert!(
                added.len() < samples / 4,
                "{metric:?}: {} of {samples}",
                added.len()
            );
            for s in &part.stats {
                assert!(s.r_h >= 2.0 - 1e-9, "{metric:?}: nodes {} apart", s.r_h);
                assert!(s.r_d < s.r_h, "{s:?}");
            }
        }
    }

    #[test]
    fn a_single_handle_needs_nothing() {
        let (p, t) = grid_mesh(10, 10, 1.0);
        let d = Domain::new(p, t, Metric::Intrinsic).expect("valid");
        let mut part = Partition::new(&d, vec![0]);
        assert!(insert_virtual_handles(&d, &mut part, |_, _| {}).is_empty());
    }

    #[test]
    fn unreached_components_get_a_node() {
        // Two separate squares.
        let (mut p, mut t) = grid_mesh(3, 3, 1.0);
        let n = p.len() as u32;
        let (p2, t2) = grid_mesh(3, 3, 1.0);
        p.extend(p2.iter().map(|q| *q + DVec2::new(10.0, 0.0)));
        t.extend(t2.iter().map(|tri| tri.map(|v| v + n)));
        let d = Domain::new(p, t, Metric::Intrinsic).expect("valid");
        let mut part = Partition::new(&d, vec![5]);
        let added = insert_virtual_handles(&d, &mut part, |_, _| {});
        assert!(added.contains(&n));
        assert!(part.unreached().is_empty());
    }
}
