//! From an image's alpha channel to the polygons of its visible shape.

use geometry::signed_area;
use glam::DVec2;

use crate::cover;
use crate::segments::RingBands;
use crate::simplify::simplify_rings;
use crate::trace::{TracedRing, trace};
use crate::{MeshError, MeshOptions};

/// The region of the image that gets meshed: one or more polygons with holes, in pixel
/// coordinates.
///
/// Polygons must not overlap each other, and rings must be simple and pairwise disjoint
/// (touching at isolated vertices is tolerated by [`triangulate`](crate::triangulate)).
/// Outer rings produced by [`domain_from_image`] have positive signed area (shoelace in
/// pixel coordinates, the orientation of [`Mesh`](crate::Mesh) triangles) and holes
/// negative; hand-made domains may use either orientation: inside-ness is even-odd.
#[derive(Debug, Clone, PartialEq)]
pub struct Domain {
    /// The connected pieces of the shape.
    pub polygons: Vec<Polygon>,
    /// `true` when the domain is exactly the image rectangle `[0, width] × [0, height]`
    /// (so it is convex and straight-line distances are intrinsic distances).
    pub is_full_rectangle: bool,
    /// Width of the source image in pixels.
    pub width: u32,
    /// Height of the source image in pixels.
    pub height: u32,
}

/// A polygon with holes; each ring is closed implicitly (last vertex back to the first).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Polygon {
    /// The outer boundary.
    pub outer: Vec<DVec2>,
    /// Boundaries of the holes, each inside `outer`.
    pub holes: Vec<Vec<DVec2>>,
}

impl Polygon {
    /// Area in px²: the outer ring's area minus the holes' (orientation ignored).
    pub fn area(&self) -> f64 {
        signed_area(&self.outer).abs()
            - self.holes.iter().map(|h| signed_area(h).abs()).sum::<f64>()
    }

    /// All rings: the outer one first, then the holes.
    pub fn rings(&self) -> impl Iterator<Item = &[DVec2]> {
        std::iter::once(self.outer.as_slice()).chain(self.holes.iter().map(Vec::as_slice))
    }
}

impl Domain {
    /// The whole image rectangle `[0, width] × [0, height]` as a domain.
    pub fn full_rectangle(width: u32, height: u32) -> Domain {
        let (w, h) = (f64::from(width), f64::from(height));
        Domain {
            polygons: vec![Polygon {
                outer: vec![
                    DVec2::new(0.0, 0.0),
                    DVec2::new(w, 0.0),
                    DVec2::new(w, h),
                    DVec2::new(0.0, h),
                ],
                holes: Vec::new(),
            }],
            is_full_rectangle: true,
            width,
            height,
        }
    }

    /// Total area in px².
    pub fn area(&self) -> f64 {
        self.polygons.iter().map(Polygon::area).sum()
    }

    /// All rings of all polygons.
    pub fn rings(&self) -> impl Iterator<Item = &[DVec2]> {
        self.polygons.iter().flat_map(Polygon::rings)
    }

    /// Whether `p` lies in the domain, boundary included (even-odd rule over all rings).
    ///
    /// Builds an index on every call; fine for a few queries.
    pub fn contains(&self, p: DVec2) -> bool {
        p.is_finite() && RingBands::new(self.rings(), 1.0).contains(p)
    }
}

/// How [`domain_from_image`] reads the alpha channel.
#[derive(Debug, Clone)]
pub struct DomainOptions {
    /// A pixel is inside the shape when its alpha is strictly greater than this.
    /// Default 0: every pixel that shows at all is carried.
    pub alpha_threshold: u8,
    /// Douglas–Peucker tolerance for the outlines, in pixels. Default 0.75. The mask is
    /// dilated by `max(1, ceil(tolerance - 0.5))` pixels first, so simplification never
    /// uncovers an inside pixel's centre.
    pub simplify_tolerance: f64,
    /// Holes smaller than this (px², after dilation) are filled. Default 16. (Islands,
    /// however small, are never dropped.)
    pub min_hole_area: f64,
}

impl Default for DomainOptions {
    fn default() -> Self {
        DomainOptions {
            alpha_threshold: 0,
            simplify_tolerance: 0.75,
            min_hole_area: 16.0,
        }
    }
}

/// Finds the visible shape of an image, for a mesh of the default density
/// ([`MeshOptions::default`](crate::MeshOptions)'s `target_vertices`): the same as
/// [`domain_for_density`] with that target.
///
/// # Errors
/// As [`domain_for_density`].
///
/// # Example
/// ```
/// let mut img = image::RgbaImage::new(40, 30);
/// for (x, y, p) in img.enumerate_pixels_mut() {
///     let inside = (x as f64 - 20.0).hypot(y as f64 - 15.0) < 10.0;
///     *p = image::Rgba([255, 0, 0, if inside { 255 } else { 0 }]);
/// }
/// let domain = mesh::domain_from_image(&img, &mesh::DomainOptions::default())?;
/// assert_eq!(domain.polygons.len(), 1);
/// assert!(!domain.is_full_rectangle);
/// assert!(domain.contains(glam::DVec2::new(20.0, 15.0)));
/// # Ok::<(), mesh::MeshError>(())
/// ```
pub fn domain_from_image(
    image: &image::RgbaImage,
    opts: &DomainOptions,
) -> Result<Domain, MeshError> {
    domain_for_density(image, opts, MeshOptions::default().target_vertices)
}

/// Finds the visible shape of an image: the pixels with alpha above the threshold (by
/// default every pixel with alpha > 0), outlined for a mesh of about `target_vertices`
/// vertices.
///
/// * If every pixel is inside, the domain is the image rectangle `[0, W] × [0, H]` with
///   [`Domain::is_full_rectangle`] set.
/// * Otherwise the mask is **dilated by one pixel** (more for tolerances above 1.5 px;
///   see [`DomainOptions::simplify_tolerance`]) so the outline runs outside the visible
///   pixels and the soft, semi-transparent fringe of a cut-out is kept, made
///   *well-composed* (wherever two inside pixels touch only at a corner, the two outside
///   pixels of that 2×2 block are added, so 4- and 8-connectivity agree and no outline
///   touches itself or another), cleared of small holes, then traced along pixel edges.
///   Each outline is simplified with Douglas–Peucker; a simplified segment that would
///   cross or touch another gets some of its original vertices back, so rings stay
///   simple and disjoint, and outline vertices on the image border are kept.
/// * **Fine content is covered, never dropped.** A piece whose mean width (twice the
///   area over the perimeter, margin included) is under two lattice spacings for
///   `target_vertices` and under 8 px (specks, one-pixel lines, hair, text) keeps its
///   exact outline while the fine pieces' outlines cost at most half the target in
///   vertices (at least 1024), the splits along them included. Beyond that the fine
///   pieces are replaced by a coarser cover: the cells of a square grid that hold one of
///   their pixels, grown by one cell, so pieces less than about a cell apart merge into
///   one polygon (with any piece they touch); the cell size is the smallest power of two
///   (from 2 px, and wider than the piece) whose outline fits that budget, and the
///   cover's outline is simplified at three quarters of a cell. When no grid fits, or
///   the grid would cover more than the fine pieces' bounding rectangle, that rectangle
///   covers them. Wider pieces keep their exact outlines at every density.
///
/// Every pixel with alpha above the threshold has its centre strictly inside the domain
/// (at least 0.75 px from the boundary with the defaults, unless it lies against the
/// image border). The domain never leaves the image rectangle.
///
/// # Errors
/// [`MeshError::EmptyDomain`] for an image without pixels or without a pixel above the
/// threshold.
///
/// # Example
/// ```
/// // A thousand specks of one pixel, scattered: all of them stay visible.
/// let mut img = image::RgbaImage::new(300, 200);
/// for k in 0..1000u32 {
///     img.put_pixel(k * 7919 % 300, k * 104_729 % 200, image::Rgba([0, 0, 0, 255]));
/// }
/// let domain = mesh::domain_for_density(&img, &mesh::DomainOptions::default(), 500)?;
/// for (x, y, p) in img.enumerate_pixels() {
///     if p.0[3] > 0 {
///         assert!(domain.contains(glam::DVec2::new(x as f64 + 0.5, y as f64 + 0.5)));
///     }
/// }
/// // ... with far fewer outline vertices than a thousand separate squares would take.
/// assert!(domain.rings().map(|r| r.len()).sum::<usize>() < 1100);
/// # Ok::<(), mesh::MeshError>(())
/// ```
pub fn domain_for_density(
    image: &image::RgbaImage,
    opts: &DomainOptions,
    target_vertices: usize,
) -> Result<Domain, MeshError> {
    let (width, height) = image.dimensions();
    let (w, h) = (width as usize, height as usize);
    if w == 0 || h == 0 {
        return Err(MeshError::EmptyDomain);
    }
    let mut mask: Vec<bool> = image
        .pixels()
        .map(|p| p.0[3] > opts.alpha_threshold)
        .collect();
    let count = mask.iter().filter(|&&m| m).count();
    if count == 0 {
        return Err(MeshError::EmptyDomain);
    }
    if count == w * h {
        return Ok(Domain::full_rectangle(width, height));
    }
    let min_hole = if opts.min_hole_area.is_finite() {
        opts.min_hole_area.max(0.0)
    } else {
        0.0
    };
    let tol = if opts.simplify_tolerance.is_finite() {
        opts.simplify_tolerance.clamp(0.0, 1000.0)
    } else {
        0.0
    };
    let radius = ((tol - 0.5).ceil().max(1.0)) as usize;
    dilate(&mut mask, w, h, radius);
    make_well_composed(&mut mask, w, h);
    fill_small_holes(&mut mask, w, h, min_hole);
    if mask.iter().all(|&m| m) {
        return Ok(Domain::full_rectangle(width, height));
    }

    let pieces = label_components(&mask, w, h, true, false);
    let mut outline = Outline::new(&mask, w, h, pieces, |_| tol);
    if let Some(cover) = cover::plan(
        &outline.labels,
        w,
        h,
        &outline.pieces(),
        (tol, radius),
        target_vertices,
    ) {
        // Which pixels belong to pieces that keep their exact outlines.
        let exact: Vec<bool> = outline
            .labels
            .iter()
            .map(|&l| l != u32::MAX && !cover.covered[l as usize])
            .collect();
        cover.paint(&mut mask, w);
        make_well_composed(&mut mask, w, h);
        fill_small_holes(&mut mask, w, h, min_hole);
        if mask.iter().all(|&m| m) {
            return Ok(Domain::full_rectangle(width, height));
        }
        // A piece of the new mask that holds an exact piece keeps the fine tolerance.
        let (labels, sizes) = label_components(&mask, w, h, true, false);
        let mut holds_exact = vec![false; sizes.len()];
        for (&l, &e) in labels.iter().zip(&exact) {
            if e {
                holds_exact[l as usize] = true;
            }
        }
        outline = Outline::new(&mask, w, h, (labels, sizes), |l| {
            if holds_exact[l as usize] {
                tol
            } else {
                cover.tolerance
            }
        });
    }
    outline.into_domain(width, height)
}

/// The traced and simplified outlines of a well-composed mask, with its pieces.
struct Outline {
    w: usize,
    /// Piece (4-connected component) of each pixel, `u32::MAX` outside.
    labels: Vec<u32>,
    /// Pixels in each piece.
    sizes: Vec<usize>,
    traced: Vec<TracedRing>,
    simplified: Vec<Vec<[i64; 2]>>,
}

impl Outline {
    /// Traces the mask, whose pieces are `(labels, sizes)` as [`label_components`] gives
    /// them, and simplifies each ring with the tolerance `tolerance(piece)`.
    fn new(
        mask: &[bool],
        w: usize,
        h: usize,
        (labels, sizes): (Vec<u32>, Vec<usize>),
        tolerance: impl Fn(u32) -> f64,
    ) -> Outline {
        let traced = trace(mask, w, h);
        let raw: Vec<Vec<[i64; 2]>> = traced.iter().map(|r| r.pts.clone()).collect();
        let tols: Vec<f64> = traced
            .iter()
            .map(|r| {
                let (x, y) = r.fg_pixel;
                tolerance(labels[y * w + x])
            })
            .collect();
        let simplified = simplify_rings(&raw, &tols, [w as i64, h as i64]);
        Outline {
            w,
            labels,
            sizes,
            traced,
            simplified,
        }
    }

    /// Area, perimeter and simplified vertex count of each piece.
    fn pieces(&self) -> Vec<cover::Piece> {
        let mut pieces: Vec<cover::Piece> = self
            .sizes
            .iter()
            .map(|&area| cover::Piece {
                area,
                ..cover::Piece::default()
            })
            .collect();
        for (r, s) in self.traced.iter().zip(&self.simplified) {
            let (x, y) = r.fg_pixel;
            let piece = &mut pieces[self.labels[y * self.w + x] as usize];
            let n = r.pts.len();
            piece.perimeter += (0..n)
                .map(|i| {
                    let (a, b) = (r.pts[i], r.pts[(i + 1) % n]);
                    ((b[0] - a[0]).abs() + (b[1] - a[1]).abs()) as usize
                })
                .sum::<usize>();
            piece.vertices += s.len();
        }
        pieces
    }

    /// The polygons: one outer ring (positive area) and its holes (negative area) per
    /// piece.
    fn into_domain(self, width: u32, height: u32) -> Result<Domain, MeshError> {
        let Outline {
            w,
            labels,
            sizes,
            traced,
            simplified,
        } = self;
        let to_f = |ring: &[[i64; 2]]| -> Vec<DVec2> {
            ring.iter()
                .map(|p| DVec2::new(p[0] as f64, p[1] as f64))
                .collect()
        };
        let ncomp = sizes.len();
        let mut outers: Vec<Vec<usize>> = vec![Vec::new(); ncomp];
        let mut holes: Vec<Vec<usize>> = vec![Vec::new(); ncomp];
        let areas: Vec<f64> = simplified.iter().map(|r| signed_area(&to_f(r))).collect();
        for (i, r) in traced.iter().enumerate() {
            let (x, y) = r.fg_pixel;
            let l = labels[y * w + x];
            if l == u32::MAX {
                continue;
            }
            if areas[i] > 0.0 {
                outers[l as usize].push(i);
            } else {
                holes[l as usize].push(i);
            }
        }
        let mut polygons = Vec::new();
        for (os, hs) in outers.iter().zip(&holes) {
            match os.as_slice() {
                [] => {}
                [o] => polygons.push(Polygon {
                    outer: to_f(&simplified[*o]),
                    holes: hs.iter().map(|&h| to_f(&simplified[h])).collect(),
                }),
                _ => {
                    // Not expected for a well-composed mask; assign holes by containment.
                    let mut polys: Vec<Polygon> = os
                        .iter()
                        .map(|&o| Polygon {
                            outer: to_f(&simplified[o]),
                            holes: Vec::new(),
                        })
                        .collect();
                    for &hi in hs {
                        let hole = to_f(&simplified[hi]);
                        let probe = hole[0];
                        let best = polys
                            .iter()
                            .enumerate()
                            .filter(|(_, p)| {
                                RingBands::new([p.outer.as_slice()], 1.0).contains(probe)
                            })
                            .min_by(|a, b| a.1.area().total_cmp(&b.1.area()))
                            .map(|(k, _)| k);
                        if let Some(k) = best {
                            polys[k].holes.push(hole);
                        }
                    }
                    polygons.extend(polys);
                }
            }
        }
        if polygons.is_empty() {
            return Err(MeshError::EmptyDomain);
        }
        Ok(Domain {
            polygons,
            is_full_rectangle: false,
            width,
            height,
        })
    }
}

/// Labels connected components of pixels equal to `value` (8-connected when `eight`,
/// else 4-connected); returns per-pixel labels (`u32::MAX` for other pixels) and the size
/// of each component. Components are numbered in the order of their first pixel in rows
/// from the top, left to right.
///
/// Works on runs of equal pixels along rows, joined with a union-find where they touch
/// a run of the row above.
pub(crate) fn label_components(
    mask: &[bool],
    w: usize,
    h: usize,
    value: bool,
    eight: bool,
) -> (Vec<u32>, Vec<usize>) {
    // Runs `[x0, x1)` of each row, rows in order; `row_start[y]..row_start[y + 1]`.
    let mut runs: Vec<(u32, u32)> = Vec::new();
    let mut row_start = Vec::with_capacity(h + 1);
    for row in mask.chunks_exact(w) {
        row_start.push(runs.len());
        let mut x = 0;
        while x < w {
            if row[x] != value {
                x += 1;
                continue;
            }
            let x0 = x;
            while x < w && row[x] == value {
                x += 1;
            }
            runs.push((x0 as u32, x as u32));
        }
    }
    row_start.push(runs.len());
    let mut parent: Vec<u32> = (0..runs.len() as u32).collect();
    fn root(parent: &mut [u32], mut i: u32) -> u32 {
        let mut r = i;
        while parent[r as usize] != r {
            r = parent[r as usize];
        }
        while parent[i as usize] != r {
            let next = parent[i as usize];
            parent[i as usize] = r;
            i = next;
        }
        r
    }
    // Diagonal neighbours count for 8-connectivity: runs then touch when they merely
    // meet at a corner.
    let reach = u32::from(eight);
    for y in 1..h {
        let (above, here) = (
            row_start[y - 1]..row_start[y],
            row_start[y]..row_start[y + 1],
        );
        let mut i = above.start;
        for j in here {
            let (x0, x1) = runs[j];
            // Skip runs above that end before this one starts.
            while i < above.end && runs[i].1 + reach <= x0 {
                i += 1;
            }
            let mut k = i;
            while k < above.end && runs[k].0 < x1 + reach {
                let (a, b) = (root(&mut parent, k as u32), root(&mut parent, j as u32));
                if a != b {
                    let (lo, hi) = (a.min(b), a.max(b));
                    parent[hi as usize] = lo;
                }
                k += 1;
            }
        }
    }
    // Number components by their first run; the root of a set is its first run.
    let mut labels = vec![u32::MAX; w * h];
    let mut sizes: Vec<usize> = Vec::new();
    let mut number = vec![u32::MAX; runs.len()];
    for (y, span) in row_start.windows(2).enumerate() {
        for (j, &(x0, x1)) in runs.iter().enumerate().take(span[1]).skip(span[0]) {
            let r = root(&mut parent, j as u32) as usize;
            if number[r] == u32::MAX {
                number[r] = sizes.len() as u32;
                sizes.push(0);
            }
            let l = number[r];
            sizes[l as usize] += (x1 - x0) as usize;
            labels[y * w + x0 as usize..y * w + x1 as usize].fill(l);
        }
    }
    (labels, sizes)
}

/// Dilates the mask with a `(2r+1)²` square, clipped to the image.
pub(crate) fn dilate(mask: &mut [bool], w: usize, h: usize, r: usize) {
    // Rows: a sliding count of inside pixels in [x - r, x + r].
    let mut tmp = vec![false; w];
    for row in mask.chunks_exact_mut(w) {
        let mut count = 0usize;
        for &v in &row[..r.min(w)] {
            count += usize::from(v);
        }
        for x in 0..w {
            if x + r < w {
                count += usize::from(row[x + r]);
            }
            if x > r {
                count -= usize::from(row[x - r - 1]);
            }
            tmp[x] = count > 0;
        }
        row.copy_from_slice(&tmp);
    }
    // Columns, a row at a time (in memory order): per-column counts of inside pixels in
    // rows [y - r, y + r].
    let rows: Vec<bool> = mask.to_vec();
    let row = |y: usize| &rows[y * w..(y + 1) * w];
    let mut count = vec![0u32; w];
    for y in 0..r.min(h) {
        for (c, &v) in count.iter_mut().zip(row(y)) {
            *c += u32::from(v);
        }
    }
    for y in 0..h {
        if y + r < h {
            for (c, &v) in count.iter_mut().zip(row(y + r)) {
                *c += u32::from(v);
            }
        }
        if y > r {
            for (c, &v) in count.iter_mut().zip(row(y - r - 1)) {
                *c -= u32::from(v);
            }
        }
        for (m, &c) in mask[y * w..(y + 1) * w].iter_mut().zip(&count) {
            *m = c > 0;
        }
    }
}

/// Fills the outside pixels of every 2×2 block whose inside pixels touch only
/// diagonally, until there is none.
///
/// Blocks are visited from the last (bottom right) to the first, and the blocks around
/// every pixel a fix sets are checked again before going on; the order matters (a fix
/// can turn a later diagonal block into a three-pixel one), so it is kept fixed.
pub(crate) fn make_well_composed(mask: &mut [bool], w: usize, h: usize) {
    if w < 2 || h < 2 {
        return;
    }
    // Blocks are named by their top-left pixel.
    let bw = w - 1;
    let mut todo: Vec<(usize, usize)> = Vec::new();
    for block in (0..bw * (h - 1)).rev() {
        todo.push((block % bw, block / bw));
        while let Some((x, y)) = todo.pop() {
            let (a, b) = (mask[y * w + x], mask[y * w + x + 1]);
            let (c, d) = (mask[(y + 1) * w + x], mask[(y + 1) * w + x + 1]);
            if a == d && b == c && a != b {
                for (px, py) in [(x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1)] {
                    if !mask[py * w + px] {
                        mask[py * w + px] = true;
                        // Re-check the blocks around the changed pixel.
                        for by in py.saturating_sub(1)..=py.min(h - 2) {
                            for bx in px.saturating_sub(1)..=px.min(w - 2) {
                                todo.push((bx, by));
                            }
                        }
                    }
                }
            }
        }
    }
}

/// Fills 4-connected outside regions that do not touch the image border and are smaller
/// than `min_area` pixels.
fn fill_small_holes(mask: &mut [bool], w: usize, h: usize, min_area: f64) {
    if min_area <= 0.0 {
        return;
    }
    let (labels, sizes) = label_components(mask, w, h, false, false);
    let mut touches = vec![false; sizes.len()];
    for x in 0..w {
        for y in [0, h - 1] {
            let l = labels[y * w + x];
            if l != u32::MAX {
                touches[l as usize] = true;
            }
        }
    }
    for y in 0..h {
        for x in [0, w - 1] {
            let l = labels[y * w + x];
            if l != u32::MAX {
                touches[l as usize] = true;
            }
        }
    }
    for (m, &l) in mask.iter_mut().zip(&labels) {
        if l != u32::MAX && !touches[l as usize] && (sizes[l as usize] as f64) < min_area {
            *m = true;
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn dilation_grows_by_radius() {
        let (w, h) = (7, 5);
        let mut m = vec![false; w * h];
        m[2 * w + 3] = true;
        dilate(&mut m, w, h, 1);
        assert_eq!(m.iter().filter(|&&v| v).count(), 9);
        assert!(m[w + 2] && m[3 * w + 4] && !m[2 * w + 5]);
        dilate(&mut m, w, h, 2);
        assert_eq!(m.iter().filter(|&&v| v).count(), 35);
    }

    #[test]
    fn diagonal_contacts_are_filled() {
        let (w, h) = (4, 4);
        let mut m = vec![false; w * h];
        m[w + 1] = true;
        m[2 * w + 2] = true;
        make_well_composed(&mut m, w, h);
        assert!(m[w + 2] && m[2 * w + 1]);
        for y in 0..h - 1 {
            for x in 0..w - 1 {
                let (a, b, c, d) = (
                    m[y * w + x],
                    m[y * w + x + 1],
                    m[(y + 1) * w + x],
                    m[(y + 1) * w + x + 1],
                );
                assert!(!(a == d && b == c && a != b));
            }
        }
    }

    /// The labels of a plain flood fill.
    fn flood_labels(mask: &[bool], w: usize, h: usize, eight: bool) -> (Vec<u32>, Vec<usize>) {
        let mut labels = vec![u32::MAX; w * h];
        let mut sizes = Vec::new();
        for start in 0..w * h {
            if !mask[start] || labels[start] != u32::MAX {
                continue;
            }
            let l = sizes.len() as u32;
            let mut stack = vec![start];
            labels[start] = l;
            let mut size = 0;
            while let Some(i) = stack.pop() {
                size += 1;
                let (x, y) = ((i % w) as isize, (i / w) as isize);
                for (dx, dy) in [
                    (-1, -1),
                    (0, -1),
                    (1, -1),
                    (-1, 0),
                    (1, 0),
                    (-1, 1),
                    (0, 1),
                    (1, 1),
                ] {
                    let (nx, ny) = (x + dx, y + dy);
                    if (!eight && dx != 0 && dy != 0)
                        || nx < 0
                        || ny < 0
                        || nx >= w as isize
                        || ny >= h as isize
                    {
                        continue;
                    }
                    let j = ny as usize * w + nx as usize;
                    if mask[j] && labels[j] == u32::MAX {
                        labels[j] = l;
                        stack.push(j);
                    }
                }
            }
            sizes.push(size);
        }
        (labels, sizes)
    }

    #[test]
    fn labels_match_a_flood_fill() {
        let (w, h) = (37, 23);
        let mut state = 0x1357_9bdfu32;
        for density in [2, 3, 5] {
            let mask: Vec<bool> = (0..w * h)
                .map(|_| {
                    state ^= state << 13;
                    state ^= state >> 17;
                    state ^= state << 5;
                    !state.is_multiple_of(density)
                })
                .collect();
            for eight in [false, true] {
                assert_eq!(
                    label_components(&mask, w, h, true, eight),
                    flood_labels(&mask, w, h, eight)
                );
                let inverse: Vec<bool> = mask.iter().map(|m| !m).collect();
                assert_eq!(
                    label_components(&mask, w, h, false, eight),
                    flood_labels(&inverse, w, h, eight)
                );
            }
        }
    }

    /// Every vertex of a traced outline lies within the tolerance of the simplified
    /// segment that replaced it, also where rings came close and vertices were put back.
    #[test]
    fn simplified_outlines_follow_the_traced_ones() {
        let (w, h) = (90, 70);
        let mut state = 0x2468_ace1u32;
        for (density, tol) in [(7, 1.3), (11, 0.75), (23, 2.5), (5, 3.0)] {
            let mut mask: Vec<bool> = (0..w * h)
                .map(|_| {
                    state ^= state << 13;
                    state ^= state >> 17;
                    state ^= state << 5;
                    state.is_multiple_of(density)
                })
                .collect();
            dilate(&mut mask, w, h, 1);
            make_well_composed(&mut mask, w, h);
            let rings: Vec<Vec<[i64; 2]>> = trace(&mask, w, h).into_iter().map(|r| r.pts).collect();
            let tols = vec![tol; rings.len()];
            let simplified = simplify_rings(&rings, &tols, [w as i64, h as i64]);
            for (ring, kept) in rings.iter().zip(&simplified) {
                // Walk the ring; between two kept vertices, check the ones dropped.
                let at = |p: [i64; 2]| DVec2::new(p[0] as f64, p[1] as f64);
                let start = ring.iter().position(|p| *p == kept[0]).unwrap();
                let mut next = 1;
                let mut from = kept[0];
                for k in 1..=ring.len() {
                    let p = ring[(start + k) % ring.len()];
                    let to = kept[next % kept.len()];
                    if p == to {
                        from = to;
                        next += 1;
                    } else {
                        let d = geometry::point_segment_distance_squared(at(p), at(from), at(to));
                        assert!(
                            d.sqrt() <= tol + 1e-9,
                            "{p:?} is {} from {from:?}-{to:?}",
                            d.sqrt()
                        );
                    }
                }
                assert_eq!(next, kept.len() + 1);
            }
        }
    }

    #[test]
    fn small_holes_are_filled() {
        let (w, h) = (20, 20);
        let mut m = vec![false; w * h];
        for y in 2..12 {
            for x in 2..12 {
                m[y * w + x] = !(x == 6 && y == 6);
            }
        }
        m[15 * w + 15] = true;
        fill_small_holes(&mut m, w, h, 4.0);
        assert!(m[6 * w + 6]);
        assert!(m[15 * w + 15] && !m[15 * w + 14]);
    }
}
