//! Douglas–Peucker simplification of traced outlines that keeps them simple and disjoint.

use geometry::lattice::{self, Point as P};
use geometry::{douglas_peucker, farthest_from_chord, signed_area};
use glam::DVec2;

use crate::segments::SegmentGrid;

fn to_f(p: P) -> DVec2 {
    DVec2::new(p[0] as f64, p[1] as f64)
}

/// Simplifies closed rings with Douglas–Peucker, ring `i` at tolerance `tols[i]`
/// (pixels), keeping every vertex on the border of the image `[0, size[0]] × [0,
/// size[1]]`.
///
/// The input rings must be simple and pairwise disjoint (as traced outlines are). Where a
/// simplified ring would cross or touch itself or another ring, the offending segments
/// get back some of their original vertices until no conflict is left, so the output
/// rings are simple and disjoint too (the two segments a vertex brought back makes are
/// simplified again, so they follow the outline within the tolerance as well).
/// Orientation and the sign of the area are kept.
///
/// Every original vertex lies within its ring's tolerance of the simplified segment
/// that replaces it, so no point farther than its ring's tolerance from the ring changes sides, except
/// against the image border: a segment along the border is never replaced, so a
/// simplified segment cannot shave off a sliver along it (pixels there lie only half a
/// pixel from the outline).
pub(crate) fn simplify_rings(rings: &[Vec<P>], tols: &[f64], size: P) -> Vec<Vec<P>> {
    let float: Vec<Vec<DVec2>> = rings
        .iter()
        .map(|r| r.iter().map(|&p| to_f(p)).collect())
        .collect();
    let mut keep: Vec<Vec<bool>> = rings
        .iter()
        .zip(&float)
        .zip(tols)
        .map(|((r, f), &tol)| simplify_ring(r, f, tol, size))
        .collect();
    // Resolve conflicts; each round keeps at least one more original vertex, so this ends.
    loop {
        let conflicts = find_conflicts(rings, &keep);
        if conflicts.is_empty() {
            break;
        }
        let mut progress = false;
        for (r, i, j) in conflicts {
            if let Some((k, _)) = farthest_from_chord(&float[r], i, j)
                && !keep[r][k]
            {
                keep[r][k] = true;
                progress = true;
                // The two new segments must follow the outline within the tolerance too.
                douglas_peucker(&float[r], &mut keep[r], vec![(i, k), (k, j)], tols[r]);
            }
        }
        if !progress {
            break; // Only original segments conflict: the input was not simple.
        }
    }
    rings
        .iter()
        .zip(&keep)
        .map(|(ring, k)| {
            ring.iter()
                .zip(k)
                .filter(|(_, k)| **k)
                .map(|(p, _)| *p)
                .collect()
        })
        .collect()
}

/// Douglas–Peucker on a closed ring (`float` is `ring` in `f64`), keeping the vertices on
/// the border of the image `[0, size[0]] × [0, size[1]]`; returns which vertices to keep
/// (at least 3, with the sign of the area preserved, or all of them).
fn simplify_ring(ring: &[P], float: &[DVec2], tol: f64, size: P) -> Vec<bool> {
    let n = ring.len();
    if n <= 4 || tol <= 0.0 {
        return vec![true; n];
    }
    let p0 = float[0];
    let far = (1..n)
        .max_by(|&a, &b| {
            float[a]
                .distance_squared(p0)
                .total_cmp(&float[b].distance_squared(p0))
        })
        .unwrap_or(n / 2);
    let mut keep: Vec<bool> = ring
        .iter()
        .map(|p| p[0] == 0 || p[1] == 0 || p[0] == size[0] || p[1] == size[1])
        .collect();
    keep[0] = true;
    keep[far] = true;
    // Spans between consecutive kept vertices, the last one back to vertex 0.
    let mut spans: Vec<(usize, usize)> = Vec::new();
    let mut prev = 0;
    for k in (1..n).filter(|&k| keep[k]).chain([n]) {
        spans.push((prev, k % n));
        prev = k;
    }
    douglas_peucker(float, &mut keep, spans, tol);
    let kept: Vec<DVec2> = float
        .iter()
        .zip(&keep)
        .filter(|(_, k)| **k)
        .map(|(p, _)| *p)
        .collect();
    let before = signed_area(float);
    let after = signed_area(&kept);
    if kept.len() < 3 || after == 0.0 || after.signum() != before.signum() {
        return vec![true; n];
    }
    keep
}

/// Simplified segments `(ring, from, to)` (original indices) that touch a segment they
/// should not.
fn find_conflicts(rings: &[Vec<P>], keep: &[Vec<bool>]) -> Vec<(usize, usize, usize)> {
    // Segment list: ring, position in the kept list, original from/to indices.
    struct Seg {
        ring: usize,
        pos: usize,
        count: usize,
        i: usize,
        j: usize,
    }
    let mut segs = Vec::new();
    let mut geo = Vec::new();
    for (r, (ring, k)) in rings.iter().zip(keep).enumerate() {
        let idx: Vec<usize> = (0..ring.len()).filter(|&i| k[i]).collect();
        let m = idx.len();
        for p in 0..m {
            let (i, j) = (idx[p], idx[(p + 1) % m]);
            segs.push(Seg {
                ring: r,
                pos: p,
                count: m,
                i,
                j,
            });
            geo.push([to_f(ring[i]), to_f(ring[j])]);
        }
    }
    let grid = SegmentGrid::new(geo, 8.0);
    let mut bad = vec![false; segs.len()];
    grid.for_each_cell(|items| {
        for (x, &s) in items.iter().enumerate() {
            for &t in &items[x + 1..] {
                let (si, ti) = (s as usize, t as usize);
                let (s, t) = (&segs[si], &segs[ti]);
                let (a, b) = (rings[s.ring][s.i], rings[s.ring][s.j]);
                let (c, d) = (rings[t.ring][t.i], rings[t.ring][t.j]);
                let conflict = if s.ring == t.ring && (s.pos + 1) % s.count == t.pos {
                    // t follows s: they share b == c; conflict if t folds back onto s.
                    lattice::orient(a, b, d) == 0 && dot(a, b, c, d) < 0
                } else if s.ring == t.ring && (t.pos + 1) % t.count == s.pos {
                    lattice::orient(c, d, b) == 0 && dot(c, d, a, b) < 0
                } else {
                    lattice::segments_touch(a, b, c, d)
                };
                if conflict {
                    bad[si] = true;
                    bad[ti] = true;
                }
            }
        }
    });
    segs.iter()
        .zip(&bad)
        .filter(|(_, b)| **b)
        .map(|(s, _)| (s.ring, s.i, s.j))
        .collect()
}

fn dot(a: P, b: P, c: P, d: P) -> i128 {
    i128::from(b[0] - a[0]) * i128::from(d[0] - c[0])
        + i128::from(b[1] - a[1]) * i128::from(d[1] - c[1])
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn staircase_simplifies_and_stays_simple() {
        // A staircase ring: a right triangle traced along pixel edges.
        let mut ring = vec![[0, 0]];
        for k in 0..20 {
            ring.push([k, k + 1]);
            ring.push([k + 1, k + 1]);
        }
        ring.push([20, 0]);
        // Orientation for positive area in the crate's convention.
        let out = simplify_rings(&[ring.clone()], &[0.75], [100, 100]);
        assert!(out[0].len() >= 3 && out[0].len() < ring.len());
    }

    #[test]
    fn no_sliver_is_shaved_off_along_the_image_border() {
        // The shape runs down the left border, steps in by 3 px and goes on: the chord
        // from (0, 0) to (3, 200) passes within 1.5 px of both step corners, so plain
        // Douglas–Peucker at 2 px would cut off the pixels along the border above the
        // step, though their centres lie 2.5 px from any outline edge not on the border.
        let ring: Vec<P> = vec![[0, 0], [0, 100], [3, 100], [3, 200], [50, 200], [50, 0]];
        let inside = |ring: &[P], p: DVec2| {
            let mut odd = false;
            for i in 0..ring.len() {
                let (a, b) = (to_f(ring[i]), to_f(ring[(i + 1) % ring.len()]));
                if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x)
                {
                    odd = !odd;
                }
            }
            odd
        };
        let pixel = DVec2::new(0.5, 97.5);
        // The same outline away from the border loses its corner, and the pixel with it.
        let moved: Vec<P> = ring.iter().map(|p| [p[0] + 10, p[1] + 10]).collect();
        let free = simplify_rings(&[moved], &[2.0], [100, 300]);
        assert_eq!(free[0].len(), 4);
        assert!(!inside(&free[0], pixel + DVec2::splat(10.0)));
        // On the image border the vertices stay.
        let kept = simplify_rings(&[ring], &[2.0], [50, 200]);
        assert!(inside(&kept[0], pixel));
    }

    #[test]
    fn close_rings_do_not_cross_after_simplification() {
        // Two thin combs interleaved closely would cross if simplified independently.
        let outer: Vec<P> = vec![[0, 0], [0, 10], [1, 10], [1, 1], [30, 1], [30, 0]];
        let inner: Vec<P> = vec![[2, 2], [2, 3], [15, 3], [15, 2]];
        let out = simplify_rings(&[outer, inner], &[3.0, 3.0], [100, 100]);
        let ids: Vec<Vec<bool>> = out.iter().map(|r| vec![true; r.len()]).collect();
        assert!(find_conflicts(&out, &ids).is_empty());
    }
}
