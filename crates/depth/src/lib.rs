//! Automatic depth adjustment, after §5.1 of Igarashi, Moscovich and Hughes,
//! *As-Rigid-As-Possible Shape Manipulation* (2005).
//!
//! Where a warped mesh overlaps itself — an arm bent across the body, a tail laid over
//! a leg, one part over another — some order must say which is in front. No static
//! depth holds for every pose (the paper's Fig. 8: a region brought between two others
//! whose depths straddle its own is drawn partly in front and partly behind). So the
//! order is decided per *overlap region*, as the pose is:
//!
//! 1. **Find the overlaps**: every pair of triangles whose warped interiors share an
//!    area (a grid over their boxes, then one triangle clipped to the other;
//!    triangles that share a vertex are a fold, not two regions).
//! 2. **Grow the regions** from them: two overlapping pairs belong to one region when
//!    each triangle of one is, or shares a vertex with, a triangle of the other. A
//!    region has two *sheets*, the triangles on either side of it.
//!    (The paper starts from the boundary intersections and searches the overlapping
//!    regions from there; growing from the overlapping triangles finds the same
//!    regions, including those whose boundaries do not cross — one part wholly over
//!    another.)
//! 3. **Order each region**, one sheet wholly in front of the other: a region that
//!    continues one of the previous pose's ([`arrange`]'s `remembered`: it shares
//!    triangles with both of its sheets) keeps that region's order, so nothing pops
//!    while an overlap lasts; a new one takes the order the predefined drawing order
//!    gives most of its area (the paper: "a statically predefined order as a starting
//!    point").
//! 4. **Draw**: the triangles of the regions sorted so that every front triangle comes
//!    after every back triangle it overlaps (a topological sort, ties in the
//!    predefined order; orders that contradict one another — three sheets in a cycle —
//!    give way in that order too), put back into the predefined order's places.
//!    Triangles that overlap nothing keep their places.
//!
//! The crate knows no pictures: it takes positions and triangles and gives an order.

mod overlap;
mod topology;

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::DVec2;
pub use overlap::PairCache;
pub use topology::Topology;

/// One overlap region: the triangles (indices into the mesh's list, sorted) of the
/// sheet drawn in front and of the sheet behind.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Region {
    /// The sheet in front.
    pub front: Vec<u32>,
    /// The sheet behind.
    pub back: Vec<u32>,
}

/// What [`arrange`] decided for a pose.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Arrangement {
    /// Every triangle (its index into the mesh's list) in drawing order, back to front.
    pub order: Vec<u32>,
    /// The overlap regions, in the order they were found, each with its order: what
    /// the next pose's [`arrange`] is given to keep them.
    pub regions: Vec<Region>,
}

/// Orders the triangles of the mesh `triangles` warped to `positions` for drawing
/// (see the crate documentation). `predefined` is the order without adjustment (every
/// triangle once, back to front: layer order, then handle depth, then the mesh's);
/// `remembered` is the previous pose's regions (empty for none), whose orders hold
/// while their regions last. A region of `remembered` may also be given by one
/// triangle of each sheet (what a saved pose keeps).
///
/// # Panics
/// If `predefined` is not a permutation of the triangles' indices, or a triangle names
/// a vertex past `positions`.
pub fn arrange(
    positions: &[DVec2],
    triangles: &[[u32; 3]],
    predefined: &[u32],
    remembered: &[Region],
) -> Arrangement {
    arrange_on(None, positions, triangles, predefined, remembered)
}

/// As [`arrange`], first asking `topology` (made once for the mesh: its boundary,
/// pieces and orientations) whether the pose can overlap at all — what a pose without
/// overlaps costs is then a pass over the triangles' orientations and the boundary.
///
/// # Panics
/// As [`arrange`].
pub fn arrange_on(
    topology: Option<&Topology>,
    positions: &[DVec2],
    triangles: &[[u32; 3]],
    predefined: &[u32],
    remembered: &[Region],
) -> Arrangement {
    arrange_cached(topology, None, positions, triangles, predefined, remembered)
}

/// As [`arrange_on`], finding the overlapping triangles through `pairs`, the pairs of
/// the mesh's last pose: only those with a triangle that moved since are tested again
/// (the same arrangement, sooner when most of the mesh stands still).
///
/// # Panics
/// As [`arrange`].
pub fn arrange_cached(
    topology: Option<&Topology>,
    pairs: Option<&mut PairCache>,
    positions: &[DVec2],
    triangles: &[[u32; 3]],
    predefined: &[u32],
    remembered: &[Region],
) -> Arrangement {
    if let Some(topology) = topology.filter(|t| t.is_for(triangles))
        && !topology.may_overlap(positions)
    {
        assert_eq!(
            predefined.len(),
            triangles.len(),
            "the predefined order lists every triangle"
        );
        return Arrangement {
            order: predefined.to_vec(),
            regions: Vec::new(),
        };
    }
    let n = triangles.len();
    assert_eq!(
        predefined.len(),
        n,
        "the predefined order lists every triangle"
    );
    let mut rank = vec![u32::MAX; n];
    for (r, &t) in predefined.iter().enumerate() {
        assert_eq!(rank[t as usize], u32::MAX, "triangle {t} listed twice");
        rank[t as usize] = r as u32;
    }
    let pairs = match pairs {
        Some(cache) => cache.pairs(positions, triangles),
        None => overlap::overlapping_pairs(positions, triangles),
    };
    if pairs.is_empty() {
        return Arrangement {
            order: predefined.to_vec(),
            regions: Vec::new(),
        };
    }
    let involved = Involved::new(triangles, &pairs);
    let grown = grow_regions(&involved, &pairs);
    let fronts = decide(&involved, &grown, &pairs, &rank, remembered);
    // Each overlapping pair as (behind, in front), and each region's sheets.
    let mut constraints: Vec<(u32, u32)> = Vec::with_capacity(pairs.len());
    let mut regions: Vec<Region> = vec![Region::default(); grown.count];
    for (p, &(region, s_in_a)) in pairs.iter().zip(&grown.sides) {
        let (a, b) = if s_in_a { (p.s, p.t) } else { (p.t, p.s) };
        let (front, back) = if fronts[region] { (a, b) } else { (b, a) };
        constraints.push((back, front));
        regions[region].front.push(front);
        regions[region].back.push(back);
    }
    for region in &mut regions {
        for sheet in [&mut region.front, &mut region.back] {
            sheet.sort_unstable();
            sheet.dedup();
        }
    }
    let order = sorted(predefined, &rank, &constraints);
    Arrangement { order, regions }
}

/// The triangles that overlap something, numbered densely in increasing order, with
/// the pairs each is in and the ones at each of their vertices: what growing and
/// ordering the regions look up, in arrays rather than hashes.
struct Involved {
    /// The triangles, increasing.
    triangles: Vec<u32>,
    /// Each mesh triangle's dense number (`u32::MAX`: not involved).
    local: Vec<u32>,
    /// Pair lists: `pairs[pair_starts[i]..pair_starts[i + 1]]` for triangle `i`.
    pair_starts: Vec<usize>,
    pairs: Vec<usize>,
    /// For each mesh vertex, the involved triangles (dense numbers) around it:
    /// `around[around_starts[v]..around_starts[v + 1]]`.
    around_starts: Vec<u32>,
    around: Vec<u32>,
    /// Each involved triangle's vertices.
    corners: Vec<[u32; 3]>,
}

impl Involved {
    fn new(triangles: &[[u32; 3]], pairs: &[overlap::Pair]) -> Self {
        let mut local = vec![u32::MAX; triangles.len()];
        for p in pairs {
            local[p.s as usize] = 0;
            local[p.t as usize] = 0;
        }
        let mut involved = Vec::new();
        for (t, slot) in local.iter_mut().enumerate() {
            if *slot == 0 {
                *slot = involved.len() as u32;
                involved.push(t as u32);
            }
        }
        let k = involved.len();
        let mut pair_starts = vec![0usize; k + 1];
        for p in pairs {
            pair_starts[local[p.s as usize] as usize + 1] += 1;
            pair_starts[local[p.t as usize] as usize + 1] += 1;
        }
        for i in 0..k {
            pair_starts[i + 1] += pair_starts[i];
        }
        let mut filled = pair_starts.clone();
        let mut of = vec![0usize; pair_starts[k]];
        for (j, p) in pairs.iter().enumerate() {
            for t in [p.s, p.t] {
                let slot = &mut filled[local[t as usize] as usize];
                of[*slot] = j;
                *slot += 1;
            }
        }
        let corners: Vec<[u32; 3]> = involved.iter().map(|&t| triangles[t as usize]).collect();
        let vertices = corners
            .iter()
            .flatten()
            .max()
            .map_or(0, |&v| v as usize + 1);
        let mut around_starts = vec![0u32; vertices + 1];
        for c in &corners {
            for &v in c {
                around_starts[v as usize + 1] += 1;
            }
        }
        for v in 0..vertices {
            around_starts[v + 1] += around_starts[v];
        }
        let mut filled = around_starts.clone();
        let mut around = vec![0u32; around_starts[vertices] as usize];
        for (i, c) in corners.iter().enumerate() {
            for &v in c {
                let slot = &mut filled[v as usize];
                around[*slot as usize] = i as u32;
                *slot += 1;
            }
        }
        Self {
            triangles: involved,
            local,
            pair_starts,
            pairs: of,
            around_starts,
            around,
            corners,
        }
    }

    /// The dense number of triangle `t` (which is involved).
    fn index(&self, t: u32) -> usize {
        self.local[t as usize] as usize
    }

    /// The dense number of triangle `t`, if it is involved.
    fn find(&self, t: u32) -> Option<usize> {
        self.local
            .get(t as usize)
            .filter(|&&i| i != u32::MAX)
            .map(|&i| i as usize)
    }

    /// The pairs triangle `i` is in.
    fn pairs_of(&self, i: usize) -> &[usize] {
        &self.pairs[self.pair_starts[i]..self.pair_starts[i + 1]]
    }

    /// The involved triangles that share a vertex with triangle `i` (itself included,
    /// once per shared vertex).
    fn around(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        self.corners[i].into_iter().flat_map(move |v| {
            let (from, to) = (
                self.around_starts[v as usize] as usize,
                self.around_starts[v as usize + 1] as usize,
            );
            self.around[from..to].iter().map(|&j| j as usize)
        })
    }

    /// Whether triangles `i` and `j` share a vertex (or are one).
    fn touch(&self, i: usize, j: usize) -> bool {
        self.corners[i].iter().any(|v| self.corners[j].contains(v))
    }
}

/// The overlapping pairs grouped into regions.
struct Grown {
    /// How many regions.
    count: usize,
    /// For each pair, its region and whether its `s` lies on the region's sheet A.
    sides: Vec<(usize, bool)>,
}

/// Groups the overlapping `pairs` into regions: two pairs are neighbours when each
/// triangle of one is, or shares a vertex with, a triangle of the other, the triangles
/// that touch staying on the same sheet. (Stepping one triangle across an edge at a
/// time would be enough in general position, but meshes laid on one lattice — parts
/// meshed on the picture's grid — overlap with edges and vertices in common.) A pair
/// that would put a triangle on both sheets of the region being grown (where a fold's
/// crease joins them) is left to a region of its own.
fn grow_regions(involved: &Involved, pairs: &[overlap::Pair]) -> Grown {
    let dense: Vec<(usize, usize)> = pairs
        .iter()
        .map(|p| (involved.index(p.s), involved.index(p.t)))
        .collect();
    let mut sides: Vec<Option<(usize, bool)>> = vec![None; pairs.len()];
    // How many of each triangle's pairs are not in a region yet: a triangle with none
    // left is not looked through again.
    let mut left: Vec<usize> = (0..involved.triangles.len())
        .map(|i| involved.pairs_of(i).len())
        .collect();
    let take = |j: usize, left: &mut [usize]| {
        let (x, y) = dense[j];
        left[x] -= 1;
        left[y] -= 1;
    };
    // Each triangle's sheet in the region being grown (0: none yet, 1: A, 2: B), and
    // the triangles given one, to clear before the next region.
    let mut sheet = vec![0u8; involved.triangles.len()];
    let mut marked: Vec<usize> = Vec::new();
    let mut count = 0;
    let mut stack = Vec::new();
    for start in 0..pairs.len() {
        if sides[start].is_some() {
            continue;
        }
        for &i in &marked {
            sheet[i] = 0;
        }
        marked.clear();
        let (s, t) = dense[start];
        sides[start] = Some((count, true));
        take(start, &mut left);
        sheet[s] = 1;
        sheet[t] = 2;
        marked.extend([s, t]);
        stack.push(start);
        while let Some(k) = stack.pop() {
            let (_, s_in_a) = sides[k].expect("visited");
            let (a, b) = if s_in_a {
                dense[k]
            } else {
                (dense[k].1, dense[k].0)
            };
            for a2 in involved.around(a) {
                if left[a2] == 0 {
                    continue;
                }
                for &j in involved.pairs_of(a2) {
                    if sides[j].is_some() {
                        continue;
                    }
                    let (x, y) = dense[j];
                    let other = if x == a2 { y } else { x };
                    let fits = |i: usize, side: u8| sheet[i] == 0 || sheet[i] == side;
                    if involved.touch(other, b) && fits(a2, 1) && fits(other, 2) {
                        sides[j] = Some((count, x == a2));
                        take(j, &mut left);
                        for (i, side) in [(a2, 1), (other, 2)] {
                            if sheet[i] == 0 {
                                sheet[i] = side;
                                marked.push(i);
                            }
                        }
                        stack.push(j);
                    }
                }
            }
        }
        count += 1;
    }
    Grown {
        count,
        sides: sides
            .into_iter()
            .map(|s| s.expect("every pair visited"))
            .collect(),
    }
}

/// For each region, whether its sheet A is in front: as the remembered region it
/// continues has it (the one sharing triangles with both its sheets; with several, the
/// most shared, and the majority of those that share as much), else as the predefined
/// order has most of its area.
fn decide(
    involved: &Involved,
    grown: &Grown,
    pairs: &[overlap::Pair],
    rank: &[u32],
    remembered: &[Region],
) -> Vec<bool> {
    // Where each involved triangle was: (dense triangle, remembered region, in front),
    // sorted by triangle.
    let mut was: Vec<(usize, usize, bool)> = Vec::new();
    for (r, region) in remembered.iter().enumerate() {
        for (sheet, front) in [(&region.front, true), (&region.back, false)] {
            for &t in sheet {
                if let Some(i) = involved.find(t) {
                    was.push((i, r, front));
                }
            }
        }
    }
    was.sort_unstable();
    let mut vote = vec![0.0f64; grown.count];
    for (p, &(region, s_in_a)) in pairs.iter().zip(&grown.sides) {
        let (a, b) = if s_in_a { (p.s, p.t) } else { (p.t, p.s) };
        vote[region] += if rank[a as usize] > rank[b as usize] {
            p.area
        } else {
            -p.area
        };
    }
    // For each region and remembered region: triangles of A seen in its front and
    // back, of B in its front and back, each triangle once.
    let mut seen: Vec<Vec<(usize, [u64; 4])>> = vec![Vec::new(); grown.count];
    // The region (plus one) in which each triangle was last counted, per sheet: the
    // pairs are visited region by region (a counting sort by region), so that a
    // triangle in many pairs of a region is counted once there however the pairs
    // were found (counted again each time another region's pair came between, it
    // weighed each remembered triangle by its number of pairs, which a rig file's
    // saved orders, one pair of triangles each, do not know).
    let mut counted = vec![[0usize; 2]; involved.triangles.len()];
    let by_region = if was.is_empty() {
        Vec::new()
    } else {
        let mut start = vec![0usize; grown.count + 1];
        for &(region, _) in &grown.sides {
            start[region + 1] += 1;
        }
        for r in 0..grown.count {
            start[r + 1] += start[r];
        }
        let mut by_region = vec![0usize; grown.sides.len()];
        for (k, &(region, _)) in grown.sides.iter().enumerate() {
            by_region[start[region]] = k;
            start[region] += 1;
        }
        by_region
    };
    for &k in &by_region {
        let (p, (region, s_in_a)) = (&pairs[k], grown.sides[k]);
        let (a, b) = if s_in_a { (p.s, p.t) } else { (p.t, p.s) };
        for (t, on_a) in [(a, true), (b, false)] {
            let i = involved.index(t);
            let mark = &mut counted[i][usize::from(!on_a)];
            if *mark == region + 1 {
                continue;
            }
            *mark = region + 1;
            let from = was.partition_point(|&(j, _, _)| j < i);
            for &(_, r, front) in was[from..].iter().take_while(|&&(j, _, _)| j == i) {
                let list = &mut seen[region];
                let at = match list.iter().position(|&(q, _)| q == r) {
                    Some(at) => at,
                    None => {
                        list.push((r, [0; 4]));
                        list.len() - 1
                    }
                };
                list[at].1[usize::from(!on_a) * 2 + usize::from(!front)] += 1;
            }
        }
    }
    (0..grown.count)
        .map(|region| {
            // What each remembered region says: its triangles found in this one's
            // sheets the same way round, and turned over.
            let says = seen[region]
                .iter()
                .map(|&(_, [a_front, a_back, b_front, b_back])| {
                    let same = if a_front > 0 && b_back > 0 {
                        a_front + b_back
                    } else {
                        0
                    };
                    let swapped = if a_back > 0 && b_front > 0 {
                        a_back + b_front
                    } else {
                        0
                    };
                    (same, swapped)
                });
            // The region continues the remembered one it shares most with; where
            // several share as much (a file's saved orders: one pair of triangles
            // each), they decide by majority. (Summed over every remembered region,
            // the regions that share only some of its triangles — a sheet that is also
            // the middle of a stack of three — could outvote the one it continues.)
            let most = says.clone().map(|(a, b)| a.max(b)).max().unwrap_or(0);
            let (same, swapped) = says
                .filter(|&(a, b)| most > 0 && a.max(b) == most)
                .fold((0, 0), |(s, w), (a, b)| (s + a, w + b));
            match same.cmp(&swapped) {
                std::cmp::Ordering::Greater => true,
                std::cmp::Ordering::Less => false,
                std::cmp::Ordering::Equal => vote[region] > 0.0,
            }
        })
        .collect()
}

/// `predefined` with the triangles that take part in `constraints` (behind, in front)
/// sorted so that each comes after those it must be in front of — ties, and the
/// constraints of a cycle, in the predefined order — and put back into the places
/// they held there.
fn sorted(predefined: &[u32], rank: &[u32], constraints: &[(u32, u32)]) -> Vec<u32> {
    let mut involved: Vec<u32> = constraints.iter().flat_map(|&(a, b)| [a, b]).collect();
    involved.sort_unstable_by_key(|&t| rank[t as usize]);
    involved.dedup();
    let mut dense = vec![usize::MAX; rank.len()];
    for (i, &t) in involved.iter().enumerate() {
        dense[t as usize] = i;
    }
    let local = |t: u32| dense[t as usize];
    let k = involved.len();
    let mut starts = vec![0usize; k + 1];
    let mut indegree = vec![0usize; k];
    for &(a, b) in constraints {
        starts[local(a) + 1] += 1;
        indegree[local(b)] += 1;
    }
    for i in 1..=k {
        starts[i] += starts[i - 1];
    }
    let mut filled = starts.clone();
    let mut after = vec![0usize; constraints.len()];
    for &(a, b) in constraints {
        let slot = &mut filled[local(a)];
        after[*slot] = local(b);
        *slot += 1;
    }
    // Local indices follow the predefined order, so the smallest available index is
    // the one the predefined order draws first.
    let mut ready: BinaryHeap<Reverse<usize>> =
        (0..k).filter(|&i| indegree[i] == 0).map(Reverse).collect();
    let mut done = vec![false; k];
    let mut next_forced = 0;
    let mut out = Vec::with_capacity(k);
    while out.len() < k {
        let i = match ready.pop() {
            Some(Reverse(i)) if !done[i] => i,
            Some(_) => continue,
            None => {
                // A cycle: the earliest left is drawn first.
                while done[next_forced] {
                    next_forced += 1;
                }
                next_forced
            }
        };
        done[i] = true;
        out.push(involved[i]);
        for &j in &after[starts[i]..starts[i + 1]] {
            indegree[j] = indegree[j].saturating_sub(1);
            if indegree[j] == 0 && !done[j] {
                ready.push(Reverse(j));
            }
        }
    }
    let mut order = predefined.to_vec();
    let mut slots: Vec<usize> = involved
        .iter()
        .map(|&t| rank[t as usize] as usize)
        .collect();
    slots.sort_unstable();
    for (slot, t) in slots.into_iter().zip(out) {
        order[slot] = t;
    }
    order
}
