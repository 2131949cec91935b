//! Algorithm 1 of the paper: insert virtual handles until every node's cell fits
//! inside the ball that reaches its nearest neighbour (r_d < r_h).
//!
//! We insert while r_d ≥ r_h (the paper writes r_d > r_h): with a strict r_d < r_h
//! every sample lies strictly inside its own node's support when α = 1, so the sum of
//! basis values never vanishes. (With r_d = r_h allowed, a node at 0 with its nearest
//! neighbour at 2 on a segment from −2 to 3 keeps its cell's end −2 exactly on the rim
//! of its support, and no other support reaches it.) Each insertion puts a node on a
//! sample that carried none (the farthest sample of a cell with r_d > 0), so the loop
//! ends after at most as many insertions as there are samples.
//!
//! [`Placement::AsWritten`] (the default) is the paper's loop: one virtual handle a
//! round, at the farthest sample of the worst cell. [`Placement::Symmetric`] fixes
//! tied worst cells together and merges their close candidates (see below), so that
//! a mirror-symmetric rig gets mirror-symmetric virtual handles.

use std::collections::{BinaryHeap, HashMap, HashSet};

use crate::domain::{Domain, Metric};
use crate::voronoi::Partition;

/// How Algorithm 1 chooses the virtual handles of a round.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Placement {
    /// The paper's Algorithm 1 as written: each round, one virtual handle, at the
    /// farthest sample of the cell with the largest (r_d − r_h)/r_d (ties: the node
    /// on the sample of lower rank; its farthest sample of lowest rank).
    #[default]
    AsWritten,
    /// Each round, every cell within a relative 10⁻⁹ of the worst ratio, each at all
    /// its tied farthest samples (up to four); candidates closer together than their
    /// cell's r_h merge into one at the sample nearest their centroid, placed only if
    /// it keeps that distance from every node. A mirror-symmetric rig keeps
    /// mirror-symmetric virtual handles (the paper's loop breaks the tie to one side).
    Symmetric,
}

/// Relative tolerance under which two violation ratios count as tied. Tied violators
/// (and tied farthest samples of one cell) are fixed together, so that a
/// mirror-symmetric rig keeps its symmetry.
const TIE: f64 = 1e-9;
/// At most this many tied farthest samples of one cell get a virtual handle at once.
const MAX_TIED_PER_CELL: usize = 4;

/// A cheap hash for grid squares (a multiply and a fold), in place of the default
/// keyed one: the keys are small integers of our own, never adversarial.
#[derive(Clone, Copy, Default)]
struct SquareHash;

impl std::hash::BuildHasher for SquareHash {
    type Hasher = SquareHasher;
    fn build_hasher(&self) -> SquareHasher {
        SquareHasher(0)
    }
}

/// The hasher of [`SquareHash`].
struct SquareHasher(u64);

impl std::hash::Hasher for SquareHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_i64(&mut self, x: i64) {
        self.write_u64(x as u64);
    }
    fn write_u32(&mut self, x: u32) {
        self.write_u64(u64::from(x));
    }
    fn write_usize(&mut self, x: usize) {
        self.write_u64(x as u64);
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

/// A node violating r_d < r_h, ordered worst first: by ratio (r_d − r_h)/r_d, then by
/// the lower rank of its sample.
#[derive(Clone, Copy, Debug)]
struct Violator {
    ratio: f64,
    key: u32,
    node: usize,
}

impl PartialEq for Violator {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == std::cmp::Ordering::Equal
    }
}

impl Eq for Violator {}

impl PartialOrd for Violator {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Violator {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.ratio
            .total_cmp(&other.ratio)
            .then(other.key.cmp(&self.key))
    }
}

/// Inserts virtual nodes into `partition` until the r_d < r_h condition holds for every
/// node, and every sample is reached by some node. Returns the new nodes' samples in
/// insertion order (they are appended to the partition's nodes in that order).
/// `inserted` is told of each new node (its index) as soon as it is in: its radii can
/// only shrink from there on.
pub(crate) fn insert_virtual_handles(
    domain: &Domain,
    partition: &mut Partition,
    placement: Placement,
    mut inserted: impl FnMut(&Partition, usize),
) -> Vec<u32> {
    let as_written = placement == Placement::AsWritten;
    let mut added = Vec::new();
    if partition.len() == 0 {
        // No handles: nothing moves, nothing to weigh.
        return added;
    }
    if domain.metric() == Metric::Intrinsic {
        // One node for every component of the sample graph that no node reaches.
        for v in partition.unreached(domain) {
            if partition.owner[v as usize] == crate::voronoi::NONE {
                partition.add_node(domain, v);
                inserted(partition, partition.len() - 1);
                added.push(v);
            }
        }
    }
    // The violators by ratio, worst first: a heap with an entry pushed whenever a
    // cell's radii change (add_node says which), entries no longer current skipped
    // when they come up. (Scanning every node each round cost nodes × rounds: 14 s
    // where two handles a quarter pixel apart turn a 100k-sample mesh into nodes.)
    let ratio = |partition: &Partition, k: usize| -> Option<f64> {
        let s = &partition.stats[k];
        (s.r_d > 0.0 && s.r_d >= s.r_h).then(|| (s.r_d - s.r_h) / s.r_d)
    };
    let mut heap: BinaryHeap<Violator> = (0..partition.len())
        .filter_map(|k| {
            ratio(partition, k).map(|r| Violator {
                ratio: r,
                key: domain.rank(partition.node_vertex[k]),
                node: k,
            })
        })
        .collect();
    let mut taken = vec![false; partition.len()];
    // Each cell's farthest samples (up to MAX_TIED_PER_CELL), kept until add_node says
    // the cell changed: where thousands of cells tie, most of a round's violators are
    // merged and come up again unchanged next round.
    let mut farthest: Vec<Option<Vec<u32>>> = vec![None; partition.len()];
    loop {
        let round_start = added.len();
        // The current violators within TIE of the worst, worst first, then by sample.
        let mut violators: Vec<(f64, usize)> = Vec::new();
        let mut threshold = f64::NEG_INFINITY;
        while let Some(top) = heap.peek().copied() {
            if top.ratio < threshold {
                break;
            }
            heap.pop();
            if taken[top.node] || ratio(partition, top.node) != Some(top.ratio) {
                continue;
            }
            if violators.is_empty() {
                threshold = top.ratio - TIE * top.ratio.abs().max(TIE);
            }
            taken[top.node] = true;
            violators.push((top.ratio, top.node));
            if as_written {
                break;
            }
        }
        if violators.is_empty() {
            break;
        }
        let mut touched: Vec<usize> = Vec::new();
        for &(_, k) in &violators {
            taken[k] = false;
        }
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
        // Members by grid square, a square as wide as the largest reach of the round,
        // so a candidate's groups lie in the 3 × 3 squares around it (a linear search
        // through every group cost candidates² where thousands of cells tie).
        let width = violators
            .iter()
            .map(|&(_, k)| partition.stats[k].r_h)
            .fold(0.0, f64::max);
        let square = |p: glam::DVec2| {
            if width > 0.0 && width.is_finite() {
                ((p.x / width).floor() as i64, (p.y / width).floor() as i64)
            } else {
                (0, 0)
            }
        };
        let mut grid: HashMap<(i64, i64), Vec<(u32, usize)>, SquareHash> = HashMap::default();
        // (group, sample) pairs already in, so that a group that draws hundreds of
        // candidates does not search its member list for each.
        let mut joined: HashSet<(usize, u32), SquareHash> = HashSet::default();
        for &(_, k) in &violators {
            let r_h = partition.stats[k].r_h;
            let samples = farthest[k].get_or_insert_with(|| {
                let stats = &partition.stats[k];
                if as_written {
                    // The first of the cell's farthest samples, which its radii keep
                    // (a violator has r_d > 0, so it has one).
                    debug_assert_eq!(
                        partition.farthest_samples(domain, k).first(),
                        Some(&stats.farthest)
                    );
                    return vec![stats.farthest];
                }
                let mut all = partition.farthest_samples(domain, k);
                all.truncate(MAX_TIED_PER_CELL);
                all
            });
            for &far in samples.iter() {
                let p = positions[far as usize];
                let (sx, sy) = square(p);
                // The first group (in order of creation) with a member closer than the
                // larger of this violator's r_h and the group's reach.
                let near = (sx - 1..=sx + 1)
                    .flat_map(|x| (sy - 1..=sy + 1).map(move |y| (x, y)))
                    .filter_map(|key| grid.get(&key))
                    .flatten()
                    .filter(|&&(b, g)| (positions[b as usize] - p).length() < r_h.max(groups[g].1))
                    .map(|&(_, g)| g)
                    .min();
                match near {
                    Some(g) => {
                        if joined.insert((g, far)) {
                            groups[g].0.push(far);
                            grid.entry((sx, sy)).or_default().push((far, g));
                        }
                    }
                    None => {
                        joined.insert((groups.len(), far));
                        grid.entry((sx, sy)).or_default().push((far, groups.len()));
                        groups.push((vec![far], r_h));
                    }
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
            touched.extend(partition.add_node(domain, members[0]));
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
                touched.extend(partition.add_node(domain, v));
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
        // The violators of this round that are left, and every cell whose radii may
        // have changed, come up again with their current ratio.
        taken.resize(partition.len(), false);
        farthest.resize(partition.len(), None);
        touched.sort_unstable();
        touched.dedup();
        for &k in &touched {
            farthest[k] = None;
        }
        touched.extend(violators.iter().map(|v| v.1));
        touched.sort_unstable();
        touched.dedup();
        heap.extend(touched.into_iter().filter_map(|k| {
            ratio(partition, k).map(|r| Violator {
                ratio: r,
                key: domain.rank(partition.node_vertex[k]),
                node: k,
            })
        }));
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
        for (metric, placement) in [Metric::Intrinsic, Metric::Euclidean]
            .into_iter()
            .flat_map(|m| [(m, Placement::AsWritten), (m, Placement::Symmetric)])
        {
            let (p, t) = grid_mesh(40, 30, 1.0);
            let d = Domain::new(p, t, metric).expect("valid");
            let mut part = Partition::new(&d, vec![41 * 10 + 20, 41 * 10 + 21]);
            let added = insert_virtual_handles(&d, &mut part, placement, |_, _| {});
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
        for (metric, placement) in [Metric::Intrinsic, Metric::Euclidean]
            .into_iter()
            .flat_map(|m| [(m, Placement::AsWritten), (m, Placement::Symmetric)])
        {
            let (p, t) = grid_mesh(80, 60, 1.0);
            let samples = p.len();
            let d = Domain::new(p, t, metric).expect("valid");
            let id = |i: u32, j: u32| j * 81 + i;
            let mut nodes: Vec<u32> = (10..=70).step_by(2).map(|i| id(i, 30)).collect();
            nodes.push(id(40, 32));
            let mut part = Partition::new(&d, nodes);
            let added = insert_virtual_handles(&d, &mut part, placement, |_, _| {});
            assert!(
                added.len() < samples / 4,
                "{metric:?} {placement:?}: {} of {samples}",
                added.len()
            );
            for s in &part.stats {
                assert!(
                    s.r_h >= 2.0 - 1e-9,
                    "{metric:?} {placement:?}: nodes {} apart",
                    s.r_h
                );
                assert!(s.r_d < s.r_h, "{s:?}");
            }
        }
    }

    /// The paper's loop, written plainly: the partition rebuilt from scratch after each
    /// insertion, every cell's ratio compared. The incremental, heap-driven version
    /// must place the same virtual handles in the same order.
    fn algorithm_1_from_scratch(d: &Domain, nodes: Vec<u32>) -> Vec<u32> {
        let mut nodes = nodes;
        let first = nodes.len();
        loop {
            let part = Partition::new(d, nodes.clone());
            let worst = (0..nodes.len())
                .filter_map(|k| {
                    let s = &part.stats[k];
                    (s.r_d > 0.0 && s.r_d >= s.r_h).then(|| ((s.r_d - s.r_h) / s.r_d, k))
                })
                .max_by(|a, b| a.0.total_cmp(&b.0).then(nodes[b.1].cmp(&nodes[a.1])));
            let Some((_, k)) = worst else {
                return nodes.split_off(first);
            };
            nodes.push(part.farthest_samples(d, k)[0]);
        }
    }

    #[test]
    fn as_written_is_the_papers_loop() {
        // Close pairs and a line of close nodes on a jittered (tie-free) grid and on a
        // regular one (many ties, broken by sample).
        for (jitter, metric) in [
            (0.3, Metric::Intrinsic),
            (0.3, Metric::Euclidean),
            (0.0, Metric::Intrinsic),
        ] {
            let (mut p, t) = grid_mesh(30, 24, 1.0);
            let mut seed = 7u64;
            for q in &mut p {
                seed = seed
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let a = (seed >> 11) as f64 / (1u64 << 53) as f64 * std::f64::consts::TAU;
                *q += DVec2::new(a.cos(), a.sin()) * jitter * 0.5;
            }
            let d = Domain::new(p, t, metric).expect("valid");
            let id = |i: u32, j: u32| j * 31 + i;
            for nodes in [
                vec![id(10, 10), id(12, 10)],
                vec![id(4, 4), id(5, 6), id(25, 20)],
                (8..=20).step_by(3).map(|i| id(i, 12)).collect(),
            ] {
                let mut part = Partition::new(&d, nodes.clone());
                let added = insert_virtual_handles(&d, &mut part, Placement::AsWritten, |_, _| {});
                assert_eq!(
                    added,
                    algorithm_1_from_scratch(&d, nodes.clone()),
                    "{metric:?}, jitter {jitter}, nodes {nodes:?}"
                );
                assert!(!added.is_empty());
            }
        }
    }

    #[test]
    fn a_single_handle_needs_nothing() {
        let (p, t) = grid_mesh(10, 10, 1.0);
        let d = Domain::new(p, t, Metric::Intrinsic).expect("valid");
        let mut part = Partition::new(&d, vec![0]);
        assert!(insert_virtual_handles(&d, &mut part, Placement::AsWritten, |_, _| {}).is_empty());
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
        let added = insert_virtual_handles(&d, &mut part, Placement::AsWritten, |_, _| {});
        assert!(added.contains(&n));
        assert!(part.unreached(&d).is_empty());
    }
}
