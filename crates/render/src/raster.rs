//! Scan conversion: which output pixels each triangle covers.
//!
//! Vertices are snapped to a fixed-point grid of 1/256 pixel and the edge
//! functions are evaluated exactly in integers at pixel centres. With the
//! top-left fill rule this makes coverage watertight: a pixel centre on an
//! edge shared by two triangles belongs to exactly one of them, whatever the
//! floating-point history of the shared vertices.
//!
//! Work is split into horizontal bands of [`BAND_ROWS`] rows. Triangles are
//! binned into the bands their bounding boxes touch (in list order, so a later
//! triangle overwrites an earlier one), and bands are drawn in parallel, each
//! setting up its triangles as it meets them.

use std::ops::Range;

use glam::Vec2;
use rayon::prelude::*;

use crate::WarpMesh;

/// Fractional bits of the fixed-point vertex positions.
const SUBPIXEL_BITS: u32 = 8;
/// One pixel in fixed point.
const ONE: i64 = 1 << SUBPIXEL_BITS;
/// Half a pixel in fixed point: pixel `x` has its centre at `x * ONE + HALF`.
const HALF: i64 = ONE / 2;
/// Deformed positions are clamped to `±COORD_LIMIT` pixels before snapping so
/// that every edge-function product fits in an `i64` (|value| < 2^60).
pub(crate) const COORD_LIMIT: f64 = (1u64 << 20) as f64;
/// Height of one unit of parallel work, in output rows.
const BAND_ROWS: u32 = 32;

/// One edge function `E(X, Y) = a·X + b·Y + c` in fixed point, positive inside,
/// arranged for scanning pixel centres row by row.
#[derive(Clone, Copy, Debug)]
struct Edge {
    /// `E` grows by `step` from one pixel centre to the next on a row (`a·ONE`).
    step: i64,
    /// `1 / step`, to estimate span ends without an integer division.
    inv_step: f64,
    /// `E` at column 0 of a row is `base + b·Y` (`base = a·HALF + c`).
    base: i64,
    b: i64,
    /// A pixel centre is inside this edge when `E >= min` (0 on a top or left
    /// edge, which owns the centres lying exactly on it; 1 otherwise).
    min: i64,
}

impl Edge {
    /// The edge from `p` to `q` of a triangle with positive orientation.
    fn new(p: [i64; 2], q: [i64; 2]) -> Self {
        let dx = q[0] - p[0];
        let dy = q[1] - p[1];
        // With y pointing down and positive orientation (cross(b-a, c-a) > 0),
        // the interior lies to the right of p→q as seen on screen: a left edge
        // runs upwards (dy < 0) and a top edge runs rightwards (dy = 0, dx > 0).
        let top_left = dy < 0 || (dy == 0 && dx > 0);
        let (a, b, c) = (-dy, dx, dy * p[0] - dx * p[1]);
        let step = a * ONE;
        Self {
            step,
            inv_step: if step == 0 { 0.0 } else { 1.0 / step as f64 },
            base: a * HALF + c,
            b,
            min: if top_left { 0 } else { 1 },
        }
    }

    /// Narrows the columns `lo..=hi` of the row with centre `y_fixed` to those
    /// whose centres are inside this edge (empty when `lo > hi`).
    ///
    /// The span end is estimated in floating point and then settled exactly
    /// with integer tests, so the result is exact and division-free.
    #[inline]
    fn clip(&self, y_fixed: i64, lo: i64, hi: i64) -> (i64, i64) {
        // Inside ⇔ step·x >= need.
        let need = self.min - (self.base + self.b * y_fixed);
        let inside = |x: i64| self.step * x >= need;
        // `as` saturates, and the clamp bounds every product below.
        let estimate = (need as f64 * self.inv_step) as i64;
        if self.step > 0 {
            // The first inside column in lo..=hi+1.
            let mut x = estimate.clamp(lo, hi + 1);
            while x > lo && inside(x - 1) {
                x -= 1;
            }
            while x <= hi && !inside(x) {
                x += 1;
            }
            (x, hi)
        } else if self.step < 0 {
            // The last inside column in lo-1..=hi.
            let mut x = estimate.clamp(lo - 1, hi);
            while x < hi && inside(x + 1) {
                x += 1;
            }
            while x >= lo && !inside(x) {
                x -= 1;
            }
            (lo, x)
        } else if need <= 0 {
            (lo, hi)
        } else {
            (lo, lo - 1)
        }
    }
}

/// `floor(n / d)` for `d > 0`.
#[inline]
fn div_floor(n: i64, d: i64) -> i64 {
    n.div_euclid(d)
}

/// `ceil(n / d)` for `d > 0`.
#[inline]
fn div_ceil(n: i64, d: i64) -> i64 {
    -(-n).div_euclid(d)
}

/// A triangle ready to be scanned, with its texture mapping.
#[derive(Clone, Debug)]
pub(crate) struct TriangleSetup {
    edges: [Edge; 3],
    /// Covered-row candidates, inclusive, already clipped to the output.
    y_min: u32,
    y_max: u32,
    /// Covered-column candidates, inclusive, already clipped to the output.
    x_min: u32,
    x_max: u32,
    /// Affine map from an output position `p` (pixels) to a texture position:
    /// `uv = origin + du·(p.x - anchor.x) + dv·(p.y - anchor.y)`.
    pub(crate) map: AffineMap,
}

/// Output-pixel position → source-pixel position, for one triangle.
#[derive(Clone, Copy, Debug)]
pub(crate) struct AffineMap {
    anchor: [f64; 2],
    origin: [f64; 2],
    /// Derivative of `uv` with respect to output x.
    pub(crate) du: [f64; 2],
    /// Derivative of `uv` with respect to output y.
    dv: [f64; 2],
}

impl AffineMap {
    /// The triangle-to-triangle map taking `deformed[i]` to `rest[i]`, or
    /// `None` when the deformed triangle is (numerically) degenerate.
    fn new(deformed: [[f64; 2]; 3], rest: [[f64; 2]; 3]) -> Option<Self> {
        let [d0, d1, d2] = deformed;
        let e1 = [d1[0] - d0[0], d1[1] - d0[1]];
        let e2 = [d2[0] - d0[0], d2[1] - d0[1]];
        let det = e1[0] * e2[1] - e1[1] * e2[0];
        if det == 0.0 {
            return None;
        }
        let f1 = [rest[1][0] - rest[0][0], rest[1][1] - rest[0][1]];
        let f2 = [rest[2][0] - rest[0][0], rest[2][1] - rest[0][1]];
        // Barycentric derivatives: s along e1, t along e2.
        let inv = 1.0 / det;
        let (ds_dx, ds_dy) = (e2[1] * inv, -e2[0] * inv);
        let (dt_dx, dt_dy) = (-e1[1] * inv, e1[0] * inv);
        let du = [f1[0] * ds_dx + f2[0] * dt_dx, f1[1] * ds_dx + f2[1] * dt_dx];
        let dv = [f1[0] * ds_dy + f2[0] * dt_dy, f1[1] * ds_dy + f2[1] * dt_dy];
        let map = Self {
            anchor: d0,
            origin: rest[0],
            du,
            dv,
        };
        map.is_finite().then_some(map)
    }

    fn is_finite(&self) -> bool {
        let [a, b] = self.du;
        let [c, d] = self.dv;
        let [e, f] = self.origin;
        let [g, h] = self.anchor;
        // A sum of finite numbers can overflow to infinity, so test each.
        a.is_finite()
            && b.is_finite()
            && c.is_finite()
            && d.is_finite()
            && e.is_finite()
            && f.is_finite()
            && g.is_finite()
            && h.is_finite()
    }

    /// Texture position at output `(0, y)` with `y` the row's centre, so that
    /// the position at column centre `x` is `row + du·x`.
    #[inline]
    pub(crate) fn row_start(&self, y_centre: f64) -> [f64; 2] {
        let dy = y_centre - self.anchor[1];
        let dx = -self.anchor[0];
        [
            self.origin[0] + self.du[0] * dx + self.dv[0] * dy,
            self.origin[1] + self.du[1] * dx + self.dv[1] * dy,
        ]
    }
}

/// A position in fixed point, clamped to `±COORD_LIMIT` pixels and rounded
/// to nearest (half away from zero, without a libm call).
fn snap(p: Vec2) -> [i64; 2] {
    let s = |v: f32| {
        let scaled = f64::from(v).clamp(-COORD_LIMIT, COORD_LIMIT) * ONE as f64;
        (scaled + 0.5f64.copysign(scaled)) as i64
    };
    [s(p.x), s(p.y)]
}

fn to_f64(p: Vec2) -> [f64; 2] {
    [f64::from(p.x), f64::from(p.y)]
}

/// First and last pixel index whose centre lies in `[lo, hi]` (fixed point),
/// clipped to `0..size`; `None` if empty.
fn pixel_range(lo: i64, hi: i64, size: u32) -> Option<(u32, u32)> {
    let first = div_ceil(lo - HALF, ONE).max(0);
    let last = div_floor(hi - HALF, ONE).min(i64::from(size) - 1);
    (first <= last).then_some((first as u32, last as u32))
}

impl TriangleSetup {
    /// Prepares triangle `tri` of a validated mesh whose deformed positions
    /// snap to `snapped`, or returns `None` when it has zero area after
    /// snapping or misses the `width × height` output.
    fn new(
        mesh: &WarpMesh,
        snapped: &[[i64; 2]],
        tri: [u32; 3],
        width: u32,
        height: u32,
    ) -> Option<Self> {
        let mut ids = tri.map(|i| i as usize);
        let mut v = [snapped[ids[0]], snapped[ids[1]], snapped[ids[2]]];
        let cross =
            (v[1][0] - v[0][0]) * (v[2][1] - v[0][1]) - (v[1][1] - v[0][1]) * (v[2][0] - v[0][0]);
        if cross == 0 {
            return None;
        }
        if cross < 0 {
            // A fold-over: rasterise it with the opposite winding.
            v.swap(1, 2);
            ids.swap(1, 2);
        }
        let min_x = v.iter().map(|p| p[0]).min()?;
        let max_x = v.iter().map(|p| p[0]).max()?;
        let min_y = v.iter().map(|p| p[1]).min()?;
        let max_y = v.iter().map(|p| p[1]).max()?;
        let (x_min, x_max) = pixel_range(min_x, max_x, width)?;
        let (y_min, y_max) = pixel_range(min_y, max_y, height)?;

        let rest = ids.map(|i| to_f64(mesh.rest[i]));
        // Map from the exact deformed positions (so that deformed == rest is
        // the identity up to rounding); fall back to the snapped ones when the
        // unsnapped triangle is degenerate in floating point.
        let map = AffineMap::new(ids.map(|i| to_f64(mesh.deformed[i])), rest).or_else(|| {
            let snapped = v.map(|p| p.map(|c| c as f64 / ONE as f64));
            AffineMap::new(snapped, rest)
        })?;

        Some(Self {
            edges: [
                Edge::new(v[0], v[1]),
                Edge::new(v[1], v[2]),
                Edge::new(v[2], v[0]),
            ],
            y_min,
            y_max,
            x_min,
            x_max,
            map,
        })
    }

    /// The covered columns of row `y` (half-open), possibly empty.
    #[inline]
    fn span(&self, y: u32) -> Range<u32> {
        let y_fixed = i64::from(y) * ONE + HALF;
        let mut lo = i64::from(self.x_min);
        let mut hi = i64::from(self.x_max);
        for edge in &self.edges {
            (lo, hi) = edge.clip(y_fixed, lo, hi);
            if lo > hi {
                return 0..0;
            }
        }
        // lo and hi lie within x_min..=x_max, so both fit in u32.
        lo as u32..hi as u32 + 1
    }
}

/// Rows whose centres a triangle with snapped vertices `v` may cover,
/// inclusive and clipped to `0..height`, or `None`.
fn row_range(v: [[i64; 2]; 3], height: u32) -> Option<(u32, u32)> {
    let min_y = v[0][1].min(v[1][1]).min(v[2][1]);
    let max_y = v[0][1].max(v[1][1]).max(v[2][1]);
    pixel_range(min_y, max_y, height)
}

/// A mesh prepared for scanning into a `width × height` output.
///
/// Triangles are set up lazily, in the band that draws them (a triangle
/// spanning several bands is set up once per band), which keeps memory small
/// and the setup work parallel.
pub(crate) struct Raster<'a> {
    mesh: WarpMesh<'a>,
    /// Deformed positions in fixed point.
    snapped: Vec<[i64; 2]>,
    width: u32,
    height: u32,
}

impl<'a> Raster<'a> {
    /// Prepares a **validated** mesh.
    pub(crate) fn new(mesh: &WarpMesh<'a>, width: u32, height: u32) -> Self {
        let snapped = mesh.deformed.par_iter().map(|&p| snap(p)).collect();
        Self {
            mesh: *mesh,
            snapped,
            width,
            height,
        }
    }

    fn vertices(&self, tri: [u32; 3]) -> [[i64; 2]; 3] {
        tri.map(|i| self.snapped[i as usize])
    }

    /// Triangle indices per band (compressed: band `b` owns
    /// `items[offsets[b]..offsets[b + 1]]`), each band in list order.
    fn bins(&self) -> (Vec<usize>, Vec<usize>) {
        let bands = self.height.div_ceil(BAND_ROWS) as usize;
        let rows: Vec<Option<(u32, u32)>> = self
            .mesh
            .triangles
            .par_iter()
            .with_min_len(4096)
            .map(|&tri| row_range(self.vertices(tri), self.height))
            .collect();
        let band_range = |&(y_min, y_max): &(u32, u32)| {
            (y_min / BAND_ROWS) as usize..=(y_max / BAND_ROWS) as usize
        };
        let mut offsets = vec![0usize; bands + 1];
        for range in rows.iter().flatten() {
            for band in band_range(range) {
                offsets[band + 1] += 1;
            }
        }
        for b in 0..bands {
            offsets[b + 1] += offsets[b];
        }
        let mut cursor = offsets.clone();
        let mut items = vec![0usize; offsets[bands]];
        for (index, range) in rows.iter().enumerate() {
            if let Some(range) = range {
                for band in band_range(range) {
                    items[cursor[band]] = index;
                    cursor[band] += 1;
                }
            }
        }
        (offsets, items)
    }

    /// Scans every triangle into `buffer` (row-major, `channels` elements per
    /// pixel, `width × height` pixels), bands in parallel.
    ///
    /// `init` is called once per band on the band's rows before any triangle;
    /// `shade(setup, y, columns, row)` is called for each non-empty span with
    /// the whole of row `y`. Within a band, triangles come in list order.
    pub(crate) fn scan<T, I, S>(&self, buffer: &mut [T], channels: usize, init: I, shade: S)
    where
        T: Send,
        I: Fn(&mut [T]) + Sync,
        S: Fn(&TriangleSetup, u32, Range<u32>, &mut [T]) + Sync,
    {
        let row_len = self.width as usize * channels;
        if row_len == 0 || self.height == 0 {
            return;
        }
        let (offsets, items) = self.bins();
        buffer
            .par_chunks_mut(row_len * BAND_ROWS as usize)
            .enumerate()
            .for_each(|(band, chunk)| {
                init(chunk);
                let band_y0 = band as u32 * BAND_ROWS;
                let rows_here = (chunk.len() / row_len) as u32;
                let band_y1 = band_y0 + rows_here; // exclusive
                for &index in &items[offsets[band]..offsets[band + 1]] {
                    let tri = self.mesh.triangles[index];
                    let Some(setup) =
                        TriangleSetup::new(&self.mesh, &self.snapped, tri, self.width, self.height)
                    else {
                        continue;
                    };
                    let setup = &setup;
                    let y0 = setup.y_min.max(band_y0);
                    let y1 = (setup.y_max + 1).min(band_y1);
                    for y in y0..y1 {
                        let columns = setup.span(y);
                        if columns.is_empty() {
                            continue;
                        }
                        let start = (y - band_y0) as usize * row_len;
                        shade(setup, y, columns, &mut chunk[start..start + row_len]);
                    }
                }
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn covered(deformed: &[Vec2], width: u32, height: u32) -> Vec<u32> {
        let tris: Vec<[u32; 3]> = (0..deformed.len() as u32 / 3)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect();
        let mesh = WarpMesh {
            rest: deformed,
            deformed,
            triangles: &tris,
        };
        let raster = Raster::new(&mesh, width, height);
        let mut counts = vec![0u32; (width * height) as usize];
        raster.scan(
            &mut counts,
            1,
            |_| {},
            |_, _, cols, row| {
                for c in &mut row[cols.start as usize..cols.end as usize] {
                    *c += 1;
                }
            },
        );
        counts
    }

    #[test]
    fn top_left_rule_on_axis_aligned_square() {
        // Two triangles whose edges pass exactly through pixel centres.
        let a = Vec2::new(0.5, 0.5);
        let b = Vec2::new(2.5, 0.5);
        let c = Vec2::new(2.5, 2.5);
        let d = Vec2::new(0.5, 2.5);
        let counts = covered(&[a, b, c, a, c, d], 4, 4);
        #[rustfmt::skip]
        let expected = [
            1, 1, 0, 0,
            1, 1, 0, 0,
            0, 0, 0, 0,
            0, 0, 0, 0,
        ];
        assert_eq!(counts, expected);
    }

    #[test]
    fn winding_does_not_matter() {
        let a = Vec2::new(0.3, 0.2);
        let b = Vec2::new(7.1, 1.4);
        let c = Vec2::new(2.2, 6.9);
        assert_eq!(covered(&[a, b, c], 8, 8), covered(&[a, c, b], 8, 8));
        assert!(covered(&[a, b, c], 8, 8).contains(&1));
    }

    #[test]
    fn degenerate_and_offscreen_triangles_are_skipped() {
        let line = [Vec2::ZERO, Vec2::splat(4.0), Vec2::splat(8.0)];
        assert!(covered(&line, 8, 8).iter().all(|&c| c == 0));
        let far = [
            Vec2::new(-50.0, -50.0),
            Vec2::new(-40.0, -50.0),
            Vec2::new(-40.0, -40.0),
        ];
        assert!(covered(&far, 8, 8).iter().all(|&c| c == 0));
    }

    #[test]
    fn huge_coordinates_do_not_overflow() {
        let tri = [
            Vec2::new(-3.0e38, -3.0e38),
            Vec2::new(3.0e38, -3.0e38),
            Vec2::new(0.0, 3.0e38),
        ];
        let counts = covered(&tri, 8, 8);
        assert!(counts.iter().all(|&c| c == 1));
    }

    #[test]
    fn division_helpers_round_correctly() {
        assert_eq!(div_floor(-7, 2), -4);
        assert_eq!(div_floor(7, 2), 3);
        assert_eq!(div_ceil(-7, 2), -3);
        assert_eq!(div_ceil(7, 2), 4);
        assert_eq!(div_ceil(6, 2), 3);
    }
}
