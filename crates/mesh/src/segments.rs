//! Segment helpers of the meshing (exact collinearity, where one segment meets
//! another) and two spatial indices over segments; the plain predicates (orientation,
//! areas, distances) are the `geometry` crate's.
//!
//! * [`SegmentGrid`]: uniform grid for "which segments lie near this point" queries.
//! * [`RingBands`]: horizontal bands for even-odd point-in-domain tests and scanline
//!   crossings.

use geometry::point_segment_distance_squared;
use glam::DVec2;

/// `a + (b - a) * t`: exact on axis-aligned segments (unlike `DVec2::lerp`), so points
/// split off a straight image edge stay exactly on it.
#[inline]
pub(crate) fn lerp(a: DVec2, b: DVec2, t: f64) -> DVec2 {
    a + (b - a) * t
}

/// `a - b` if it is exact in floating point (TwoDiff error term zero).
fn exact_diff(a: f64, b: f64) -> Option<f64> {
    let s = a - b;
    let bv = a - s;
    let av = s + bv;
    let err = (a - av) + (bv - b);
    (err == 0.0 && s.is_finite()).then_some(s)
}

/// Whether `p` lies exactly on the line through `a` and `b` (exact arithmetic; `false`
/// when it cannot be decided exactly). The split points of a segment that pass this test
/// create no sliver triangles against it.
pub(crate) fn exactly_collinear(a: DVec2, b: DVec2, p: DVec2) -> bool {
    let (Some(ux), Some(uy), Some(vx), Some(vy)) = (
        exact_diff(b.x, a.x),
        exact_diff(b.y, a.y),
        exact_diff(p.x, a.x),
        exact_diff(p.y, a.y),
    ) else {
        return false;
    };
    // ux * vy == uy * vx, each product as an exact two-term expansion.
    let p1 = ux * vy;
    let e1 = ux.mul_add(vy, -p1);
    let p2 = uy * vx;
    let e2 = uy.mul_add(vx, -p2);
    p1.is_finite() && p2.is_finite() && p1 == p2 && e1 == e2
}

/// Parameters `t` in `[0, 1]` along `p q` where it meets the segment `a b` (both ends of
/// an overlap when collinear).
pub(crate) fn segment_hits(p: DVec2, q: DVec2, a: DVec2, b: DVec2, out: &mut Vec<f64>) {
    let d = q - p;
    let e = b - a;
    let denom = d.perp_dot(e);
    let len2 = d.length_squared();
    if len2 == 0.0 {
        return;
    }
    if denom.abs() > 1e-14 * d.length() * e.length() {
        let t = (a - p).perp_dot(e) / denom;
        let u = (a - p).perp_dot(d) / denom;
        let eps = 1e-12;
        if (-eps..=1.0 + eps).contains(&t) && (-eps..=1.0 + eps).contains(&u) {
            out.push(t.clamp(0.0, 1.0));
        }
    } else if (a - p).perp_dot(d).abs() <= 1e-12 * len2.max(1.0) {
        // Collinear: the overlap's ends.
        for c in [a, b] {
            let t = (c - p).dot(d) / len2;
            if (0.0..=1.0).contains(&t) {
                out.push(t);
            }
        }
    }
}

/// A uniform grid over segments (points are zero-length segments).
pub(crate) struct SegmentGrid {
    origin: DVec2,
    cell: f64,
    nx: usize,
    ny: usize,
    start: Vec<u32>,
    items: Vec<u32>,
    segs: Vec<[DVec2; 2]>,
}

impl SegmentGrid {
    /// Builds a grid with cells of about `cell_hint` pixels (coarser when that would make
    /// more than about 4M cells).
    pub(crate) fn new(segs: Vec<[DVec2; 2]>, cell_hint: f64) -> Self {
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        for s in &segs {
            lo = lo.min(s[0]).min(s[1]);
            hi = hi.max(s[0]).max(s[1]);
        }
        if segs.is_empty() {
            lo = DVec2::ZERO;
            hi = DVec2::ONE;
        }
        let ext = (hi - lo).max(DVec2::splat(1e-9));
        let mut cell = if cell_hint.is_finite() && cell_hint > 0.0 {
            cell_hint
        } else {
            ext.max_element()
        };
        let max_cells_per_axis = 2048.0;
        cell = cell
            .max(ext.x / max_cells_per_axis)
            .max(ext.y / max_cells_per_axis);
        let nx = ((ext.x / cell).floor() as usize + 1).max(1);
        let ny = ((ext.y / cell).floor() as usize + 1).max(1);
        let mut grid = SegmentGrid {
            origin: lo,
            cell,
            nx,
            ny,
            start: Vec::new(),
            items: Vec::new(),
            segs,
        };
        grid.fill();
        grid
    }

    /// Calls `f(cell)` for each cell a segment passes near, possibly twice for one cell.
    fn cells_of(&self, s: [DVec2; 2], mut f: impl FnMut(usize)) {
        let len = (s[1] - s[0]).length();
        let pieces = ((len / self.cell).ceil() as usize).max(1);
        let mut last = usize::MAX;
        for k in 0..pieces {
            let a = lerp(s[0], s[1], k as f64 / pieces as f64);
            let b = lerp(s[0], s[1], (k + 1) as f64 / pieces as f64);
            let (x0, y0) = self.cell_xy(a.min(b));
            let (x1, y1) = self.cell_xy(a.max(b));
            for cy in y0..=y1 {
                for cx in x0..=x1 {
                    let c = cy * self.nx + cx;
                    if c != last {
                        f(c);
                        last = c;
                    }
                }
            }
        }
    }

    fn fill(&mut self) {
        let ncell = self.nx * self.ny;
        let mut count = vec![0u32; ncell + 1];
        let mut seen = vec![u32::MAX; ncell];
        for (i, &s) in self.segs.iter().enumerate() {
            self.cells_of(s, |c| {
                if seen[c] != i as u32 {
                    seen[c] = i as u32;
                    count[c + 1] += 1;
                }
            });
        }
        for c in 0..ncell {
            count[c + 1] += count[c];
        }
        let mut pos = count.clone();
        let mut items = vec![0u32; count[ncell] as usize];
        seen.iter_mut().for_each(|v| *v = u32::MAX);
        for (i, &s) in self.segs.iter().enumerate() {
            self.cells_of(s, |c| {
                if seen[c] != i as u32 {
                    seen[c] = i as u32;
                    items[pos[c] as usize] = i as u32;
                    pos[c] += 1;
                }
            });
        }
        self.start = count;
        self.items = items;
    }

    #[inline]
    fn cell_xy(&self, p: DVec2) -> (usize, usize) {
        let q = (p - self.origin) / self.cell;
        let cx = q.x.floor().clamp(0.0, (self.nx - 1) as f64) as usize;
        let cy = q.y.floor().clamp(0.0, (self.ny - 1) as f64) as usize;
        (cx, cy)
    }

    /// The indexed segments.
    pub(crate) fn segments(&self) -> &[[DVec2; 2]] {
        &self.segs
    }

    /// Calls `f(index)` for every segment registered in a cell overlapping the square of
    /// half-width `r` around `p` (a segment may be reported more than once); stops early
    /// when `f` returns `true`. Returns whether it stopped early.
    pub(crate) fn any_near(&self, p: DVec2, r: f64, mut f: impl FnMut(usize) -> bool) -> bool {
        if self.segs.is_empty() {
            return false;
        }
        let (x0, y0) = self.cell_xy(p - DVec2::splat(r));
        let (x1, y1) = self.cell_xy(p + DVec2::splat(r));
        for cy in y0..=y1 {
            for cx in x0..=x1 {
                let c = cy * self.nx + cx;
                for &i in &self.items[self.start[c] as usize..self.start[c + 1] as usize] {
                    if f(i as usize) {
                        return true;
                    }
                }
            }
        }
        false
    }

    /// Whether some segment passes within distance `r` of `p` (strictly closer).
    pub(crate) fn any_within(&self, p: DVec2, r: f64) -> bool {
        let r2 = r * r;
        self.any_near(p, r, |i| {
            let [a, b] = self.segs[i];
            point_segment_distance_squared(p, a, b) < r2
        })
    }

    /// Calls `f(cell_items)` for each non-empty cell: the segments registered in it.
    pub(crate) fn for_each_cell(&self, mut f: impl FnMut(&[u32])) {
        for c in 0..self.nx * self.ny {
            let items = &self.items[self.start[c] as usize..self.start[c + 1] as usize];
            if items.len() > 1 {
                f(items);
            }
        }
    }
}

/// Horizontal bands over the segments of closed rings, for even-odd inside tests.
pub(crate) struct RingBands {
    y0: f64,
    band_h: f64,
    nb: usize,
    start: Vec<u32>,
    items: Vec<u32>,
    segs: Vec<[DVec2; 2]>,
    eps: f64,
}

impl RingBands {
    /// Indexes the segments of the given closed rings with bands about `band_hint` high.
    pub(crate) fn new<'a>(rings: impl IntoIterator<Item = &'a [DVec2]>, band_hint: f64) -> Self {
        let mut segs = Vec::new();
        for ring in rings {
            let n = ring.len();
            for i in 0..n {
                let a = ring[i];
                let b = ring[(i + 1) % n];
                if a != b {
                    segs.push([a, b]);
                }
            }
        }
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        let mut ext = 0.0f64;
        for s in &segs {
            for p in s {
                lo = lo.min(p.y);
                hi = hi.max(p.y);
                ext = ext.max(p.x.abs()).max(p.y.abs());
            }
        }
        if segs.is_empty() {
            lo = 0.0;
            hi = 1.0;
        }
        let span = (hi - lo).max(1e-9);
        let mut band_h = if band_hint.is_finite() && band_hint > 0.0 {
            band_hint
        } else {
            span
        };
        band_h = band_h.max(span / 4096.0);
        let nb = (span / band_h).floor() as usize + 1;
        let mut count = vec![0u32; nb + 1];
        let band_of = |y: f64| ((y - lo) / band_h).floor().clamp(0.0, (nb - 1) as f64) as usize;
        for s in &segs {
            let (b0, b1) = (band_of(s[0].y.min(s[1].y)), band_of(s[0].y.max(s[1].y)));
            for b in b0..=b1 {
                count[b + 1] += 1;
            }
        }
        for b in 0..nb {
            count[b + 1] += count[b];
        }
        let mut pos = count.clone();
        let mut items = vec![0u32; count[nb] as usize];
        for (i, s) in segs.iter().enumerate() {
            let (b0, b1) = (band_of(s[0].y.min(s[1].y)), band_of(s[0].y.max(s[1].y)));
            for b in b0..=b1 {
                items[pos[b] as usize] = i as u32;
                pos[b] += 1;
            }
        }
        RingBands {
            y0: lo,
            band_h,
            nb,
            start: count,
            items,
            segs,
            eps: 1e-12 * (1.0 + ext),
        }
    }

    fn band(&self, y: f64) -> Option<&[u32]> {
        let b = ((y - self.y0) / self.band_h).floor();
        if !(b >= 0.0 && b < self.nb as f64) {
            return None;
        }
        let b = b as usize;
        Some(&self.items[self.start[b] as usize..self.start[b + 1] as usize])
    }

    /// The x coordinates where the horizontal line at `y` crosses the rings (half-open
    /// rule on vertices), sorted.
    pub(crate) fn crossings(&self, y: f64, out: &mut Vec<f64>) {
        out.clear();
        let Some(items) = self.band(y) else { return };
        for &i in items {
            let [a, b] = self.segs[i as usize];
            if (a.y > y) != (b.y > y) {
                let t = (y - a.y) / (b.y - a.y);
                out.push(a.x + t * (b.x - a.x));
            }
        }
        out.sort_by(f64::total_cmp);
    }

    /// Whether `p` lies within `tol` of a ring (`tol` at most the band height).
    pub(crate) fn near_boundary(&self, p: DVec2, tol: f64) -> bool {
        let t2 = tol * tol;
        [p.y - tol, p.y, p.y + tol].iter().any(|&y| {
            self.band(y).is_some_and(|items| {
                items.iter().any(|&i| {
                    let [a, b] = self.segs[i as usize];
                    point_segment_distance_squared(p, a, b) <= t2
                })
            })
        })
    }

    /// Even-odd test; points on a ring count as inside.
    pub(crate) fn contains(&self, p: DVec2) -> bool {
        let Some(items) = self.band(p.y) else {
            return false;
        };
        let e2 = self.eps * self.eps;
        let mut inside = false;
        for &i in items {
            let [a, b] = self.segs[i as usize];
            if point_segment_distance_squared(p, a, b) <= e2 {
                return true;
            }
            if (a.y > p.y) != (b.y > p.y) {
                let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                if x > p.x {
                    inside = !inside;
                }
            }
        }
        inside
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn square_inside_outside_boundary() {
        let ring = [
            DVec2::new(0.0, 0.0),
            DVec2::new(4.0, 0.0),
            DVec2::new(4.0, 4.0),
            DVec2::new(0.0, 4.0),
        ];
        let bands = RingBands::new([&ring[..]], 1.0);
        assert!(bands.contains(DVec2::new(2.0, 2.0)));
        assert!(bands.contains(DVec2::new(0.0, 2.0)));
        assert!(bands.contains(DVec2::new(4.0, 4.0)));
        assert!(!bands.contains(DVec2::new(4.5, 2.0)));
        assert!(!bands.contains(DVec2::new(2.0, -0.1)));
        let mut xs = Vec::new();
        bands.crossings(1.5, &mut xs);
        assert_eq!(xs, vec![0.0, 4.0]);
    }

    #[test]
    fn exact_collinearity() {
        let a = DVec2::new(3.0, 7.0);
        let b = DVec2::new(103.0, 14.0);
        assert!(exactly_collinear(a, b, lerp(a, b, 0.375)));
        assert!(exactly_collinear(a, b, a));
        assert!(!exactly_collinear(
            a,
            b,
            lerp(a, b, 0.3) + DVec2::new(0.0, 1e-13)
        ));
    }

    #[test]
    fn grid_near() {
        let segs = vec![
            [DVec2::new(0.0, 0.0), DVec2::new(100.0, 0.0)],
            [DVec2::new(50.0, 50.0), DVec2::new(50.0, 50.0)],
        ];
        let g = SegmentGrid::new(segs, 3.0);
        assert!(g.any_within(DVec2::new(70.0, 1.0), 1.5));
        assert!(!g.any_within(DVec2::new(70.0, 2.0), 1.5));
        assert!(g.any_within(DVec2::new(50.5, 50.5), 1.0));
        assert!(!g.any_within(DVec2::new(30.0, 30.0), 5.0));
    }
}
