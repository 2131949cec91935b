//! The nearest other handle of every handle, and the closest pair of handles, through
//! a grid of square cells instead of comparing every pair (10,000 handles are 50
//! million pairs: over a second, on every insertion).
//!
//! Handles are segments (a point handle is a segment of length zero). Each segment is
//! listed in every cell its bounding box overlaps, except a long one (overlapping
//! more than [`LONG`] cells), which is compared with every handle directly. A search
//! looks at rings of cells around the segment's own until the ring is farther than
//! the nearest segment found: everything closer lies in the cells already seen.

use geometry::segment_distance;
use glam::DVec2;

/// A segment overlapping more cells than this is compared with every other directly.
const LONG: usize = 16;

/// Below this many handles, every pair is compared.
const FEW: usize = 32;

/// Segments filed by grid cell.
pub(crate) struct SegmentGrid<'a> {
    segments: &'a [[DVec2; 2]],
    cell: f64,
    nx: usize,
    ny: usize,
    /// Cell `c` lists `items[start[c]..start[c + 1]]`.
    start: Vec<u32>,
    items: Vec<u32>,
    /// Cell range `[x0, y0, x1, y1]` (inclusive) of each segment's bounding box.
    span: Vec<[usize; 4]>,
    /// Segments compared with every other directly.
    long: Vec<u32>,
    is_long: Vec<bool>,
}

impl<'a> SegmentGrid<'a> {
    /// Files `segments` (finite coordinates).
    pub(crate) fn new(segments: &'a [[DVec2; 2]]) -> Self {
        let n = segments.len().max(1);
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for s in segments {
            lo = lo.min(s[0].min(s[1]));
            hi = hi.max(s[0].max(s[1]));
        }
        if segments.is_empty() {
            (lo, hi) = (DVec2::ZERO, DVec2::ZERO);
        }
        let size = hi - lo;
        // About one segment a cell: at most n + 2·n + 1 cells.
        let cell = (size.x * size.y / n as f64)
            .sqrt()
            .max(size.max_element() / n as f64)
            .max(1e-9 * (1.0 + size.max_element()));
        let nx = (size.x / cell) as usize + 1;
        let ny = (size.y / cell) as usize + 1;
        let index = |p: DVec2| {
            let q = (p - lo) / cell;
            [
                (q.x.max(0.0) as usize).min(nx - 1),
                (q.y.max(0.0) as usize).min(ny - 1),
            ]
        };
        let span: Vec<[usize; 4]> = segments
            .iter()
            .map(|s| {
                let (a, b) = (index(s[0].min(s[1])), index(s[0].max(s[1])));
                [a[0], a[1], b[0], b[1]]
            })
            .collect();
        let cells_of = |s: &[usize; 4]| (s[2] - s[0] + 1) * (s[3] - s[1] + 1);
        let is_long: Vec<bool> = span.iter().map(|s| cells_of(s) > LONG).collect();
        let long: Vec<u32> = (0..segments.len() as u32)
            .filter(|&i| is_long[i as usize])
            .collect();
        let mut count = vec![0u32; nx * ny + 1];
        let each_cell = |s: &[usize; 4], f: &mut dyn FnMut(usize)| {
            for y in s[1]..=s[3] {
                for x in s[0]..=s[2] {
                    f(y * nx + x);
                }
            }
        };
        for (i, s) in span.iter().enumerate() {
            if !is_long[i] {
                each_cell(s, &mut |c| count[c + 1] += 1);
            }
        }
        for c in 0..nx * ny {
            count[c + 1] += count[c];
        }
        let start = count.clone();
        let mut items = vec![0u32; start[nx * ny] as usize];
        for (i, s) in span.iter().enumerate() {
            if !is_long[i] {
                each_cell(s, &mut |c| {
                    items[count[c] as usize] = i as u32;
                    count[c] += 1;
                });
            }
        }
        Self {
            segments,
            cell,
            nx,
            ny,
            start,
            items,
            span,
            long,
            is_long,
        }
    }

    /// Calls `f(j, distance)` for every other segment `j` that may lie within `radius`
    /// of segment `i` (some farther ones too, some more than once), nearest rings
    /// first; `f` returns the radius still of interest, which may shrink.
    fn search(&self, i: usize, mut radius: f64, f: &mut dyn FnMut(usize, f64) -> f64) {
        let own = self.segments[i];
        let mut visit = |j: usize, radius: &mut f64| {
            if j != i {
                *radius = f(j, segment_distance(own, self.segments[j])).min(*radius);
            }
        };
        if self.is_long[i] {
            for j in 0..self.segments.len() {
                visit(j, &mut radius);
            }
            return;
        }
        for &j in &self.long {
            visit(j as usize, &mut radius);
        }
        let [x0, y0, x1, y1] = self.span[i];
        let mut r = 0usize;
        loop {
            // Cells at index distance r from the segment's own cell range.
            let (ax, ay) = (x0.saturating_sub(r), y0.saturating_sub(r));
            let (bx, by) = ((x1 + r).min(self.nx - 1), (y1 + r).min(self.ny - 1));
            for y in ay..=by {
                let edge_row = r > 0 && (y + r == y0 || y == y1 + r);
                for x in ax..=bx {
                    let on_ring = r == 0 || edge_row || x + r == x0 || x == x1 + r;
                    if !on_ring {
                        continue;
                    }
                    let c = y * self.nx + x;
                    for &j in &self.items[self.start[c] as usize..self.start[c + 1] as usize] {
                        visit(j as usize, &mut radius);
                    }
                }
            }
            let everything = ax == 0 && ay == 0 && bx == self.nx - 1 && by == self.ny - 1;
            // Every segment within r cells' width of this one has been seen (within
            // r − 1, allowing for rounding in the cell of a point; a segment touching
            // this one shares a cell with it).
            let seen = if r == 0 {
                0.0
            } else {
                (r - 1) as f64 * self.cell
            };
            if everything || radius <= seen {
                return;
            }
            r += 1;
        }
    }

    /// The distance from segment `i` to the nearest other (∞ if it is alone).
    pub(crate) fn nearest(&self, i: usize) -> f64 {
        let mut best = f64::INFINITY;
        self.search(i, f64::INFINITY, &mut |_, d| {
            best = best.min(d);
            best
        });
        best
    }

    /// The lowest `j < i` exactly `distance` from segment `i`, if any.
    fn lowest_at(&self, i: usize, distance: f64) -> Option<usize> {
        let mut lowest: Option<usize> = None;
        self.search(i, distance, &mut |j, d| {
            if j < i && d == distance && lowest.is_none_or(|l| j < l) {
                lowest = Some(j);
            }
            distance
        });
        lowest
    }
}

/// The closest two segments `(a, b, distance)` with `a < b`; of several pairs equally
/// close, the one with the lowest `b`, then the lowest `a`. `None` for fewer than two.
pub(crate) fn closest_pair(segments: &[[DVec2; 2]]) -> Option<(usize, usize, f64)> {
    if segments.len() <= FEW {
        let mut best: Option<(usize, usize, f64)> = None;
        for i in 0..segments.len() {
            for j in 0..i {
                let d = segment_distance(segments[i], segments[j]);
                if best.is_none_or(|b| d < b.2) {
                    best = Some((j, i, d));
                }
            }
        }
        return best;
    }
    let grid = SegmentGrid::new(segments);
    let nearest: Vec<f64> = (0..segments.len()).map(|i| grid.nearest(i)).collect();
    let least = nearest.iter().copied().fold(f64::INFINITY, f64::min);
    (0..segments.len())
        .filter(|&i| nearest[i] == least)
        .find_map(|i| grid.lowest_at(i, least).map(|j| (j, i, least)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small generator, for repeatable random segments.
    fn random_segments(seed: u64, n: usize, bars: usize, spread: f64) -> Vec<[DVec2; 2]> {
        let mut state = seed | 1;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n)
            .map(|i| {
                // Coordinates on a coarse lattice, so that equal distances (ties) occur.
                let p = DVec2::new((next() * spread).round(), (next() * spread).round());
                if i % (n / bars.max(1)).max(1) == 0 && bars > 0 {
                    let q = p + DVec2::new((next() * 40.0).round(), (next() * 40.0).round());
                    [p, q]
                } else {
                    [p, p]
                }
            })
            .collect()
    }

    fn brute_pair(segments: &[[DVec2; 2]]) -> Option<(usize, usize, f64)> {
        let mut best: Option<(usize, usize, f64)> = None;
        for i in 0..segments.len() {
            for j in 0..i {
                let d = segment_distance(segments[i], segments[j]);
                if best.is_none_or(|b| d < b.2) {
                    best = Some((j, i, d));
                }
            }
        }
        best
    }

    #[test]
    fn the_grid_finds_what_comparing_every_pair_finds() {
        for seed in 1..40u64 {
            let n = 33 + (seed as usize * 37) % 400;
            let spread = [20.0, 200.0, 5000.0][seed as usize % 3];
            let segments = random_segments(seed, n, (seed % 4) as usize * 3, spread);
            assert_eq!(
                closest_pair(&segments),
                brute_pair(&segments),
                "seed {seed}"
            );
            let grid = SegmentGrid::new(&segments);
            for i in 0..n {
                let brute = (0..n)
                    .filter(|&j| j != i)
                    .map(|j| segment_distance(segments[i], segments[j]))
                    .fold(f64::INFINITY, f64::min);
                assert_eq!(grid.nearest(i), brute, "seed {seed}, segment {i}");
            }
        }
    }

    #[test]
    fn degenerate_layouts() {
        // All on one vertical line, all on one point but one, one long bar across all.
        let line: Vec<[DVec2; 2]> = (0..100)
            .map(|i| [DVec2::new(3.0, i as f64 * 1.5); 2])
            .collect();
        assert_eq!(closest_pair(&line), brute_pair(&line));
        let mut pile: Vec<[DVec2; 2]> = (0..60).map(|_| [DVec2::new(1.0, 1.0); 2]).collect();
        pile.push([DVec2::new(1e6, -1e6); 2]);
        assert_eq!(closest_pair(&pile), Some((0, 1, 0.0)));
        let mut crossed = line.clone();
        crossed.push([DVec2::new(-50.0, 75.0), DVec2::new(50.0, 75.2)]);
        assert_eq!(closest_pair(&crossed), brute_pair(&crossed));
        let grid = SegmentGrid::new(&crossed);
        let brute = (0..100)
            .map(|j| segment_distance(crossed[100], crossed[j]))
            .fold(f64::INFINITY, f64::min);
        assert_eq!(grid.nearest(100), brute);
        assert_eq!(SegmentGrid::new(&line[..1]).nearest(0), f64::INFINITY);
    }
}
