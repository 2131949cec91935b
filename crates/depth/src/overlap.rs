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
    // Each row of cells on a thread of its own.
    let row_pairs = |y: usize| {
        let mut pairs = Vec::new();
        for x in 0..columns {
            let cell = y * columns + x;
            let cell_members = &members[starts[cell] as usize..starts[cell + 1] as usize];
            for (k, &i) in cell_members.iter().enumerate() {
                let (pi, min_i, max_i, area_i) = shapes[i as usize].expect("live");
                for &j in &cell_members[k + 1..] {
                    let (pj, min_j, max_j, area_j) = shapes[j as usize].expect("live");
                    let (min, max) = (min_i.max(min_j), max_i.min(max_j));
                    // Boxes apart or only touching (no area in common), or the pair
                    // is tested in the cell where their boxes' overlap starts.
                    if min.x >= max.x || min.y >= max.y || index(min) != (x, y) {
                        continue;
                    }
                    let (ti, tj) = (triangles[i as usize], triangles[j as usize]);
                    if ti.iter().any(|v| tj.contains(v)) {
                        continue;
                    }
                    let area = common_area(pi, pj);
                    if area > SLIVER * area_i.min(area_j) {
                        let (s, t) = if i < j { (i, j) } else { (j, i) };
                        pairs.push(Pair { s, t, area });
                    }
                }
            }
        }
        pairs
    };
    let mut pairs: Vec<Pair> = (0..rows).into_par_iter().flat_map_iter(row_pairs).collect();
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
