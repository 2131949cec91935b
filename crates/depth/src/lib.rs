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

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};

use glam::DVec2;

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
    let pairs = overlap::overlapping_pairs(positions, triangles);
    if pairs.is_empty() {
        return Arrangement {
            order: predefined.to_vec(),
            regions: Vec::new(),
        };
    }
    let grown = grow_regions(triangles, &pairs);
    let fronts = decide(&grown, &pairs, &rank, remembered);
    // Each overlapping pair as (behind, in front).
    let constraints: Vec<(u32, u32)> = pairs
        .iter()
        .zip(&grown.sides)
        .map(|(p, &(region, s_in_a))| {
            let (a, b) = if s_in_a { (p.s, p.t) } else { (p.t, p.s) };
            if fronts[region] { (b, a) } else { (a, b) }
        })
        .collect();
    let order = sorted(predefined, &rank, &constraints);
    let regions = (0..grown.count)
        .map(|region| {
            let (mut a, mut b) = (Vec::new(), Vec::new());
            for (p, &(r, s_in_a)) in pairs.iter().zip(&grown.sides) {
                if r == region {
                    let (x, y) = if s_in_a { (p.s, p.t) } else { (p.t, p.s) };
                    a.push(x);
                    b.push(y);
                }
            }
            for sheet in [&mut a, &mut b] {
                sheet.sort_unstable();
                sheet.dedup();
            }
            if fronts[region] {
                Region { front: a, back: b }
            } else {
                Region { front: b, back: a }
            }
        })
        .collect();
    Arrangement { order, regions }
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
/// meshed on the picture's grid — overlap with edges and vertices in common.)
fn grow_regions(triangles: &[[u32; 3]], pairs: &[overlap::Pair]) -> Grown {
    // The pairs each triangle is in, and the triangles (that are in a pair) at each
    // vertex.
    let mut pairs_of: HashMap<u32, Vec<usize>> = HashMap::new();
    for (k, p) in pairs.iter().enumerate() {
        pairs_of.entry(p.s).or_default().push(k);
        pairs_of.entry(p.t).or_default().push(k);
    }
    // (In the triangles' order: the regions must not depend on a hash's order.)
    let mut involved: Vec<u32> = pairs_of.keys().copied().collect();
    involved.sort_unstable();
    let mut at_vertex: HashMap<u32, Vec<u32>> = HashMap::new();
    for &t in &involved {
        for v in triangles[t as usize] {
            at_vertex.entry(v).or_default().push(t);
        }
    }
    let touch = |x: u32, y: u32| {
        let (x, y) = (triangles[x as usize], triangles[y as usize]);
        x.iter().any(|v| y.contains(v))
    };
    let mut sides: Vec<Option<(usize, bool)>> = vec![None; pairs.len()];
    let mut count = 0;
    let mut stack = Vec::new();
    // The sheet (true: A) each triangle is on in the region being grown: a pair that
    // would put a triangle on both sheets (where a fold's crease joins them) is left
    // to a region of its own.
    let mut sheet: HashMap<u32, bool> = HashMap::new();
    for start in 0..pairs.len() {
        if sides[start].is_some() {
            continue;
        }
        sheet.clear();
        sides[start] = Some((count, true));
        sheet.insert(pairs[start].s, true);
        sheet.insert(pairs[start].t, false);
        stack.push(start);
        while let Some(k) = stack.pop() {
            let (_, s_in_a) = sides[k].expect("visited");
            let (a, b) = if s_in_a {
                (pairs[k].s, pairs[k].t)
            } else {
                (pairs[k].t, pairs[k].s)
            };
            for v in triangles[a as usize] {
                for &a2 in &at_vertex[&v] {
                    for &j in &pairs_of[&a2] {
                        if sides[j].is_some() {
                            continue;
                        }
                        let other = if pairs[j].s == a2 {
                            pairs[j].t
                        } else {
                            pairs[j].s
                        };
                        let fits = |t: u32, on_a: bool| sheet.get(&t).is_none_or(|&s| s == on_a);
                        if touch(other, b) && fits(a2, true) && fits(other, false) {
                            sides[j] = Some((count, pairs[j].s == a2));
                            sheet.insert(a2, true);
                            sheet.insert(other, false);
                            stack.push(j);
                        }
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
/// continues has it, else as the predefined order has most of its area.
fn decide(
    grown: &Grown,
    pairs: &[overlap::Pair],
    rank: &[u32],
    remembered: &[Region],
) -> Vec<bool> {
    // Each triangle's places in the remembered regions: (region, in front).
    let mut was: HashMap<u32, Vec<(usize, bool)>> = HashMap::new();
    for (r, region) in remembered.iter().enumerate() {
        for &t in &region.front {
            was.entry(t).or_default().push((r, true));
        }
        for &t in &region.back {
            was.entry(t).or_default().push((r, false));
        }
    }
    // Per region: for each remembered region, triangles of A seen in its front and
    // back, of B in its front and back.
    let mut seen: Vec<HashMap<usize, [u64; 4]>> = vec![HashMap::new(); grown.count];
    let mut vote = vec![0.0f64; grown.count];
    let mut counted = vec![std::collections::HashSet::new(); grown.count];
    for (p, &(region, s_in_a)) in pairs.iter().zip(&grown.sides) {
        let (a, b) = if s_in_a { (p.s, p.t) } else { (p.t, p.s) };
        vote[region] += if rank[a as usize] > rank[b as usize] {
            p.area
        } else {
            -p.area
        };
        for (t, on_a) in [(a, true), (b, false)] {
            if !counted[region].insert((t, on_a)) {
                continue;
            }
            for &(r, front) in was.get(&t).into_iter().flatten() {
                let counts = seen[region].entry(r).or_default();
                counts[usize::from(!on_a) * 2 + usize::from(!front)] += 1;
            }
        }
    }
    (0..grown.count)
        .map(|region| {
            let (mut same, mut swapped) = (0u64, 0u64);
            for &[a_front, a_back, b_front, b_back] in seen[region].values() {
                if a_front > 0 && b_back > 0 {
                    same += a_front + b_back;
                }
                if a_back > 0 && b_front > 0 {
                    swapped += a_back + b_front;
                }
            }
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
    let local: HashMap<u32, usize> = involved.iter().enumerate().map(|(i, &t)| (t, i)).collect();
    let k = involved.len();
    let mut starts = vec![0usize; k + 1];
    let mut indegree = vec![0usize; k];
    for &(a, b) in constraints {
        starts[local[&a] + 1] += 1;
        indegree[local[&b]] += 1;
    }
    for i in 1..=k {
        starts[i] += starts[i - 1];
    }
    let mut filled = starts.clone();
    let mut after = vec![0usize; constraints.len()];
    for &(a, b) in constraints {
        let slot = &mut filled[local[&a]];
        after[*slot] = local[&b];
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
