//! Which triangles of a warped mesh overlap one another — a positive area in common —
//! found through a uniform grid over their bounding boxes, each candidate pair tested
//! once, by clipping one triangle to the other.

use glam::DVec2;
use rayon::prelude::*;

/// Two triangles (indices into the mesh's list, `s < t`) that overlap, and the area
/// they have in common.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Pair {
    pub s: u32,
    pub t: u32,
    pub area: f64,
}

/// An overlap smaller than this share of the smaller triangle is rounding where two
/// triangles touch along an edge, not an overlap.
const SLIVER: f64 = 1e-6;

/// The most grid cells per triangle, on average: a few triangles stretched across the
/// picture must not make the grid the picture's size in cells.
const CELLS_PER_TRIANGLE: f64 = 4.0;

/// A triangle counter-clockwise, its bounding box's corners and its area.
type Shape = ([DVec2; 3], DVec2, DVec2, f64);

/// Every pair of triangles that overlap and share no vertex (neighbours that fold over
/// one another are a fold, drawn in the mesh's order, not two regions), in increasing
/// `(s, t)`. Triangles with a non-finite corner or no area take no part.
pub(crate) fn overlapping_pairs(positions: &[DVec2], triangles: &[[u32; 3]]) -> Vec<Pair> {
    pairs_among(positions, triangles, None)
}

/// The overlapping pairs of the mesh's last pose, kept so that the next pose tests
/// again only the pairs with a triangle that moved: when most of a mesh stands still
/// (a pin added to one part of many), its pairs are not tested again.
#[derive(Clone, Debug, Default)]
pub struct PairCache {
    /// The positions and triangles the pairs were found for.
    positions: Vec<DVec2>,
    triangles: Vec<[u32; 3]>,
    pairs: Vec<Pair>,
}

impl PairCache {
    /// [`overlapping_pairs`] of `positions` and `triangles`, the same pairs with the
    /// same areas, testing only the pairs with a triangle that moved since the last
    /// call (all of them the first time, or for other triangles).
    pub(crate) fn pairs(&mut self, positions: &[DVec2], triangles: &[[u32; 3]]) -> Vec<Pair> {
        let same_mesh =
            self.triangles.as_slice() == triangles && self.positions.len() == positions.len();
        let pairs = if same_mesh {
            let moved_vertex: Vec<bool> = (positions.iter().zip(&self.positions))
                .map(|(a, b)| a != b)
                .collect();
            let moved: Vec<bool> = triangles
                .iter()
                .map(|t| t.iter().any(|&v| moved_vertex[v as usize]))
                .collect();
            let count = moved.iter().filter(|&&m| m).count();
            if count == 0 {
                self.pairs.clone()
            } else if count > triangles.len() / 2 {
                overlapping_pairs(positions, triangles)
            } else {
                // The pairs of two triangles that stood still, as they were; the others
                // tested again.
                let mut pairs: Vec<Pair> = (self.pairs.iter())
                    .filter(|p| !moved[p.s as usize] && !moved[p.t as usize])
                    .copied()
                    .collect();
                pairs.extend(pairs_among(positions, triangles, Some(&moved)));
                pairs.sort_unstable_by_key(|p| (p.s, p.t));
                pairs
            }
        } else {
            self.triangles = triangles.to_vec();
            overlapping_pairs(positions, triangles)
        };
        self.positions.clear();
        self.positions.extend_from_slice(positions);
        self.pairs.clone_from(&pairs);
        pairs
    }
}

/// [`overlapping_pairs`], or with `moved` only the pairs with a triangle it marks.
fn pairs_among(positions: &[DVec2], triangles: &[[u32; 3]], moved: Option<&[bool]>) -> Vec<Pair> {
    let corners = |t: &[u32; 3]| t.map(|v| positions[v as usize]);
    // Each triangle counter-clockwise, with its bounding box; None where it cannot
    // overlap anything.
    let shapes: Vec<Option<Shape>> = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = corners(t);
            let area = geometry::orient(a, b, c) / 2.0;
            if !(a.is_finite() && b.is_finite() && c.is_finite()) || area == 0.0 {
                return None;
            }
            let ccw = if area > 0.0 { [a, b, c] } else { [a, c, b] };
            Some((ccw, a.min(b).min(c), a.max(b).max(c), area.abs()))
        })
        .collect();
    let live: Vec<u32> = (0..triangles.len() as u32)
        .filter(|&i| shapes[i as usize].is_some())
        .collect();
    if live.len() < 2 {
        return Vec::new();
    }
    let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
    let mut extents: Vec<f64> = Vec::with_capacity(live.len());
    for &i in &live {
        let (_, min, max, _) = shapes[i as usize].expect("live");
        lo = lo.min(min);
        hi = hi.max(max);
        extents.push((max - min).max_element());
    }
    // Cells the size of a typical triangle, no more of them than a few a triangle.
    let middle = extents.len() / 2;
    let typical = *extents.select_nth_unstable_by(middle, f64::total_cmp).1;
    let span = (hi - lo).max(DVec2::splat(f64::MIN_POSITIVE));
    let fewest = (span.x * span.y / (CELLS_PER_TRIANGLE * live.len() as f64)).sqrt();
    let cell = typical.max(fewest).max(f64::MIN_POSITIVE);
    let columns = ((span.x / cell).floor() as usize + 1).max(1);
    let rows = ((span.y / cell).floor() as usize + 1).max(1);
    let index = |p: DVec2| {
        let q = (p - lo) / cell;
        (
            (q.x.max(0.0) as usize).min(columns - 1),
            (q.y.max(0.0) as usize).min(rows - 1),
        )
    };
    // The grid as rows of triangle lists (counted, then filled).
    let mut starts = vec![0u32; columns * rows + 1];
    let range = |i: u32| {
        let (_, min, max, _) = shapes[i as usize].expect("live");
        (index(min), index(max))
    };
    for &i in &live {
        let ((x0, y0), (x1, y1)) = range(i);
        for y in y0..=y1 {
            for x in x0..=x1 {
                starts[y * columns + x + 1] += 1;
            }
        }
    }
    for k in 1..starts.len() {
        starts[k] += starts[k - 1];
    }
    let mut filled = starts.clone();
    let mut members = vec![0u32; starts[columns * rows] as usize];
    for &i in &live {
        let ((x0, y0), (x1, y1)) = range(i);
        for y in y0..=y1 {
            for x in x0..=x1 {
                let slot = &mut filled[y * columns + x];
                members[*slot as usize] = i;
                *slot += 1;
            }
        }
    }
    // The pair of triangles `a < b`, if they overlap, tested in cell (x, y) alone: the
    // cell where their boxes' overlap starts.
    let test = |a: u32, b: u32, x: usize, y: usize| -> Option<Pair> {
        let (pa, min_a, max_a, area_a) = shapes[a as usize].expect("live");
        let (pb, min_b, max_b, area_b) = shapes[b as usize].expect("live");
        let (min, max) = (min_a.max(min_b), max_a.min(max_b));
        // Boxes apart or only touching (no area in common), or another cell's pair.
        if min.x >= max.x || min.y >= max.y || index(min) != (x, y) {
            return None;
        }
        let (ta, tb) = (triangles[a as usize], triangles[b as usize]);
        if ta.iter().any(|v| tb.contains(v)) {
            return None;
        }
        let area = common_area(pa, pb);
        (area > SLIVER * area_a.min(area_b)).then_some(Pair { s: a, t: b, area })
    };
    let cell_members = |x: usize, y: usize| {
        let cell = y * columns + x;
        &members[starts[cell] as usize..starts[cell + 1] as usize]
    };
    let mut pairs: Vec<Pair> = match moved {
        // Each row of cells on a thread of its own (a cell's members are increasing).
        None => (0..rows)
            .into_par_iter()
            .flat_map_iter(|y| {
                let mut pairs = Vec::new();
                for x in 0..columns {
                    let members = cell_members(x, y);
                    for (k, &a) in members.iter().enumerate() {
                        pairs.extend(members[k + 1..].iter().filter_map(|&b| test(a, b, x, y)));
                    }
                }
                pairs
            })
            .collect(),
        // Each moved triangle with the triangles in its cells (a pair of two moved
        // ones from the lower's side).
        Some(moved) => live
            .par_iter()
            .filter(|&&a| moved[a as usize])
            .flat_map_iter(|&a| {
                let mut pairs = Vec::new();
                let ((x0, y0), (x1, y1)) = range(a);
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        for &b in cell_members(x, y) {
                            if b == a || (moved[b as usize] && b < a) {
                                continue;
                            }
                            pairs.extend(test(a.min(b), a.max(b), x, y));
                        }
                    }
                }
                pairs
            })
            .collect(),
    };
    pairs.sort_unstable_by_key(|p| (p.s, p.t));
    pairs
}

/// The area two counter-clockwise triangles have in common: `a` clipped to each edge
/// of `b` in turn (Sutherland–Hodgman; both convex).
pub(crate) fn common_area(a: [DVec2; 3], b: [DVec2; 3]) -> f64 {
    // A triangle clipped by three half-planes has at most six corners.
    let mut polygon = [DVec2::ZERO; 9];
    let mut clipped = [DVec2::ZERO; 9];
    polygon[..3].copy_from_slice(&a);
    let mut len = 3;
    for e in 0..3 {
        let (p, q) = (b[e], b[(e + 1) % 3]);
        let side = |x: DVec2| geometry::orient(p, q, x);
        let mut out = 0;
        for k in 0..len {
            let (u, v) = (polygon[k], polygon[(k + 1) % len]);
            let (su, sv) = (side(u), side(v));
            if su >= 0.0 {
                clipped[out] = u;
                out += 1;
            }
            if (su >= 0.0) != (sv >= 0.0) {
                clipped[out] = u + (v - u) * (su / (su - sv));
                out += 1;
            }
        }
        std::mem::swap(&mut polygon, &mut clipped);
        len = out;
        if len < 3 {
            return 0.0;
        }
    }
    geometry::signed_area(&polygon[..len]).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(points: [[f64; 2]; 3]) -> [DVec2; 3] {
        points.map(DVec2::from)
    }

    #[test]
    fn common_area_of_triangles() {
        let a = tri([[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]]);
        assert!((common_area(a, a) - 2.0).abs() < 1e-12);
        // Half of a's square corner: the unit square's lower-left triangle.
        let b = tri([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
        assert!((common_area(a, b) - 0.5).abs() < 1e-12);
        assert!((common_area(b, a) - 0.5).abs() < 1e-12);
        // Apart, and touching along an edge.
        let far = tri([[5.0, 5.0], [6.0, 5.0], [5.0, 6.0]]);
        assert_eq!(common_area(a, far), 0.0);
        let beside = tri([[2.0, 0.0], [2.0, 2.0], [0.0, 2.0]]);
        assert!(common_area(a, beside) < 1e-12);
    }

    /// Two sheets of `n × n` squares (two triangles each), the second over the first,
    /// shifted: every triangle of one overlaps some of the other.
    fn sheets(n: u32) -> (Vec<DVec2>, Vec<[u32; 3]>) {
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for (sheet, shift) in [(0u32, 0.0), (1, 0.37)] {
            let base = sheet * (n + 1) * (n + 1);
            for y in 0..=n {
                for x in 0..=n {
                    positions.push(DVec2::new(f64::from(x) + shift, f64::from(y) + shift));
                }
            }
            let at = |x: u32, y: u32| base + y * (n + 1) + x;
            for y in 0..n {
                for x in 0..n {
                    triangles.push([at(x, y), at(x + 1, y), at(x + 1, y + 1)]);
                    triangles.push([at(x, y), at(x + 1, y + 1), at(x, y + 1)]);
                }
            }
        }
        (positions, triangles)
    }

    #[test]
    fn the_cache_finds_the_pairs_a_full_search_finds() {
        let (mut positions, triangles) = sheets(12);
        let mut cache = PairCache::default();
        assert_eq!(
            cache.pairs(&positions, &triangles),
            overlapping_pairs(&positions, &triangles)
        );
        // Nothing moved; then a few vertices of the top sheet, then of both; then one
        // back where it was.
        assert_eq!(
            cache.pairs(&positions, &triangles),
            overlapping_pairs(&positions, &triangles)
        );
        let top = 13 * 13;
        for (v, by) in [
            (top + 20, [0.6, -0.3]),
            (top + 100, [-2.5, 1.0]),
            (7, [0.2, 3.0]),
        ] {
            positions[v] += DVec2::from(by);
            let cached = cache.pairs(&positions, &triangles);
            let full = overlapping_pairs(&positions, &triangles);
            assert!(!full.is_empty());
            assert_eq!(cached, full, "the same pairs, the same areas to the bit");
        }
        positions[7] -= DVec2::new(0.2, 3.0);
        assert_eq!(
            cache.pairs(&positions, &triangles),
            overlapping_pairs(&positions, &triangles)
        );
        // Another mesh: searched afresh.
        let fewer = &triangles[..triangles.len() - 2];
        assert_eq!(
            cache.pairs(&positions, fewer),
            overlapping_pairs(&positions, fewer)
        );
    }

    #[test]
    fn pairs_are_found_once_and_neighbours_are_left_out() {
        // Two unit squares of two triangles each, the second shifted by half.
        let positions: Vec<DVec2> = [
            [0.0, 0.0],
            [1.0, 0.0],
            [1.0, 1.0],
            [0.0, 1.0],
            [0.5, 0.25],
            [1.5, 0.25],
            [1.5, 1.25],
            [0.5, 1.25],
        ]
        .map(DVec2::from)
        .to_vec();
        let triangles = vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]];
        let pairs = overlapping_pairs(&positions, &triangles);
        let found: Vec<(u32, u32)> = pairs.iter().map(|p| (p.s, p.t)).collect();
        // The squares' triangles that share a vertex (0-1, 2-3) are neighbours.
        assert!(!found.contains(&(0, 1)) && !found.contains(&(2, 3)));
        let total: f64 = pairs.iter().map(|p| p.area).sum();
        assert!((total - 0.5 * 0.75).abs() < 1e-12, "{total}");
        let mut unique = found.clone();
        unique.dedup();
        assert_eq!(unique, found);
    }
}
