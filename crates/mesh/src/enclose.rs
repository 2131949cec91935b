//! A simple polygon of few vertices around everything visible in a picture: what a
//! cage drawn around a cut-out must be.
//!
//! The alpha mask is dilated by the margin asked for, made well-composed, its pieces
//! joined into one by one-pixel bridges (a minimum spanning tree over the shortest
//! gaps between pieces), and its outer boundary traced along pixel edges. That ring
//! encloses every visible pixel; it is then brought down to the number of vertices
//! asked for by steps that only ever **add** area, so the result still does:
//! - a reflex (or straight) vertex is removed: the new edge runs outside the old two;
//! - an edge between two convex vertices is replaced by the point where the lines of
//!   its neighbouring edges meet (when they meet beyond it, inside the picture): the
//!   corner grows outwards over the edge.
//!
//! Each step is the one that adds the least area, and none may make the ring cross or
//! touch itself. Where no step is left before the count is reached, the ring keeps
//! more vertices than asked for.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap, VecDeque};

use geometry::{lattice, orient, segments_touch, signed_area};
use glam::DVec2;

use crate::domain::{dilate, label_components, make_well_composed};
use crate::error::MeshError;
use crate::trace::trace;

/// The ring found by [`enclosing_ring`].
#[derive(Clone, Debug, PartialEq)]
pub struct Enclosure {
    /// The polygon's vertices in image pixels, a simple ring with no repeated vertex,
    /// every pixel with alpha > 0 inside it (or on it).
    pub ring: Vec<DVec2>,
    /// Pieces of the picture the margin left apart, joined by bridges.
    pub pieces: usize,
}

/// Which pixels of a picture are visible (alpha > 0): one bit a pixel, so that a
/// 16384 × 16384 picture costs 32 MB. What [`enclosing_ring_of`] encloses.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Coverage {
    width: usize,
    height: usize,
    /// 64-bit words a row.
    stride: usize,
    bits: Vec<u64>,
}

impl Coverage {
    /// A `width × height` picture with nothing visible.
    pub fn new(width: u32, height: u32) -> Self {
        let (width, height) = (width as usize, height as usize);
        let stride = width.div_ceil(64);
        Self {
            width,
            height,
            stride,
            bits: vec![0; stride * height],
        }
    }

    /// The visible pixels of `image`.
    pub fn of_image(image: &image::RgbaImage) -> Self {
        let mut coverage = Self::new(image.width(), image.height());
        let mut alpha = Vec::with_capacity(coverage.width);
        for (y, row) in image.rows().enumerate() {
            alpha.clear();
            alpha.extend(row.map(|p| p.0[3]));
            coverage.set_row(y as u32, &alpha);
        }
        coverage
    }

    /// Sets row `y` from its pixels' alpha values (visible where above 0). Pixels
    /// beyond the row's width are ignored; a row beyond the height is.
    pub fn set_row(&mut self, y: u32, alpha: &[u8]) {
        let y = y as usize;
        if y >= self.height {
            return;
        }
        let row = &mut self.bits[y * self.stride..(y + 1) * self.stride];
        row.fill(0);
        for (x, &a) in alpha.iter().take(self.width).enumerate() {
            if a > 0 {
                row[x / 64] |= 1 << (x % 64);
            }
        }
    }

    /// The picture's width and height in pixels.
    pub fn dimensions(&self) -> (u32, u32) {
        (self.width as u32, self.height as u32)
    }

    /// Whether pixel `(x, y)` is visible.
    pub fn get(&self, x: usize, y: usize) -> bool {
        self.bits[y * self.stride + x / 64] >> (x % 64) & 1 == 1
    }

    /// Whether every pixel is visible.
    pub fn is_opaque(&self) -> bool {
        self.extent()
            .is_some_and(|(_, count)| count == self.width * self.height)
    }

    /// The visible pixels' bounding box `[x0, x1) × [y0, y1)` and their count, or
    /// `None` when nothing is visible.
    fn extent(&self) -> Option<([usize; 4], usize)> {
        let mut count = 0;
        let mut bounds: Option<[usize; 4]> = None;
        for y in 0..self.height {
            let row = &self.bits[y * self.stride..(y + 1) * self.stride];
            let first = row.iter().position(|&w| w != 0);
            let Some(first) = first else { continue };
            let last = row.iter().rposition(|&w| w != 0).unwrap_or(first);
            count += row.iter().map(|w| w.count_ones() as usize).sum::<usize>();
            let x0 = first * 64 + row[first].trailing_zeros() as usize;
            let x1 = last * 64 + 64 - row[last].leading_zeros() as usize;
            bounds = Some(match bounds {
                None => [x0, y, x1, y + 1],
                Some([a, b, c, _]) => [a.min(x0), b, c.max(x1), y + 1],
            });
        }
        bounds.map(|b| (b, count))
    }
}

/// The most pixels the working mask of [`enclosing_ring_of`] holds (4096²): a larger
/// region around the visible pixels is worked on in cells of several pixels.
const MAX_WORKING_PIXELS: usize = 4096 * 4096;

/// A simple polygon of `vertices` vertices (more where that few cannot enclose the
/// shape without crossing itself) around every pixel of `image` with alpha > 0, at
/// least `margin` pixels outside them, within the picture's rectangle.
///
/// An opaque picture gives its rectangle. Pieces apart from one another (specks, a
/// detached hand) are all enclosed. The ring has fewer than `vertices` vertices only
/// when the traced outline itself has (a small shape): callers may split its edges.
/// See [`enclosing_ring_of`], which this calls on the picture's [`Coverage`].
///
/// # Errors
/// [`MeshError::EmptyDomain`] for a picture with no visible pixel;
/// [`MeshError::InvalidOption`] for fewer than 3 vertices or a margin that is not a
/// finite, non-negative number.
pub fn enclosing_ring(
    image: &image::RgbaImage,
    vertices: usize,
    margin: f64,
) -> Result<Enclosure, MeshError> {
    enclosing_ring_of(&Coverage::of_image(image), vertices, margin)
}

/// [`enclosing_ring`] of the visible pixels `coverage` marks.
///
/// The work is done on the visible pixels' bounding box grown by the margin, not on
/// the whole picture; where that region holds more than 4096² pixels it is worked on
/// in square cells of several pixels (a cell counts as visible when any pixel in it
/// is, and the margin is kept in whole cells), so that the ring may run up to a cell
/// or two farther out, and time and memory stay bounded whatever the picture's size.
///
/// # Errors
/// As [`enclosing_ring`].
pub fn enclosing_ring_of(
    coverage: &Coverage,
    vertices: usize,
    margin: f64,
) -> Result<Enclosure, MeshError> {
    if vertices < 3 {
        return Err(MeshError::InvalidOption(format!(
            "an enclosing polygon needs at least 3 vertices, not {vertices}"
        )));
    }
    if !(margin.is_finite() && margin >= 0.0) {
        return Err(MeshError::InvalidOption(format!(
            "the margin must be a number of pixels, not {margin}"
        )));
    }
    let (w, h) = (coverage.width, coverage.height);
    let ([bx0, by0, bx1, by1], count) = coverage.extent().ok_or(MeshError::EmptyDomain)?;
    let (fw, fh) = (w as f64, h as f64);
    if count == w * h {
        let ring = vec![
            DVec2::ZERO,
            DVec2::new(fw, 0.0),
            DVec2::new(fw, fh),
            DVec2::new(0.0, fh),
        ];
        return Ok(Enclosure { ring, pieces: 1 });
    }
    // The working region: the bounding box, the margin and two cells more around it
    // (so that dilation, well-composing and bridges stay inside), within the picture.
    let reach = margin.ceil() as usize;
    let cell = (1..)
        .find(|&s: &usize| {
            let grown = |a: usize, b: usize, n: usize| (b - a + 2 * (reach + 2 * s)).min(n);
            grown(bx0, bx1, w).div_ceil(s) * grown(by0, by1, h).div_ceil(s) <= MAX_WORKING_PIXELS
        })
        .unwrap_or(1);
    let pad = reach + 2 * cell;
    let (x0, y0) = (bx0.saturating_sub(pad), by0.saturating_sub(pad));
    let (x1, y1) = ((bx1 + pad).min(w), (by1 + pad).min(h));
    let (cw, ch) = ((x1 - x0).div_ceil(cell), (y1 - y0).div_ceil(cell));
    let mut mask = vec![false; cw * ch];
    for y in by0..by1 {
        let row = &coverage.bits[y * coverage.stride..(y + 1) * coverage.stride];
        let cy = (y - y0) / cell;
        for (k, &word) in row.iter().enumerate() {
            let mut word = word;
            while word != 0 {
                let x = k * 64 + word.trailing_zeros() as usize;
                word &= word - 1;
                mask[cy * cw + (x - x0) / cell] = true;
            }
        }
    }
    dilate(&mut mask, cw, ch, reach.div_ceil(cell));
    make_well_composed(&mut mask, cw, ch);
    let pieces = join_pieces(&mut mask, cw, ch);
    let outer = trace(&mask, cw, ch)
        .into_iter()
        .map(|r| r.pts)
        .max_by_key(|pts| lattice::twice_signed_area(pts))
        .ok_or(MeshError::EmptyDomain)?;
    // Cell corners back to pixels (the last cell of a row or column may be narrower).
    let to_x = |c: i64| (x0 + c as usize * cell).min(x1) as f64;
    let to_y = |c: i64| (y0 + c as usize * cell).min(y1) as f64;
    let ring: Vec<DVec2> = outer
        .iter()
        .map(|p| DVec2::new(to_x(p[0]), to_y(p[1])))
        .collect();
    let ring = Reducer::new(ring, DVec2::new(fw, fh)).reduce(vertices);
    Ok(Enclosure { ring, pieces })
}

/// A gap between two pieces: its length in pixels and the two pixels where the searches
/// from either side met.
type Gap = (u32, usize, usize);

/// Joins the 4-connected pieces of a well-composed `mask` into one with one-pixel,
/// 4-connected bridges along the shortest gaps (a minimum spanning tree of the pieces
/// by their grid distance, from one breadth-first search out of all of them), and
/// makes the mask well-composed again. Returns how many pieces there were.
fn join_pieces(mask: &mut [bool], w: usize, h: usize) -> usize {
    let (labels, sizes) = label_components(mask, w, h, true, false);
    let pieces = sizes.len();
    if pieces <= 1 {
        return pieces;
    }
    // Every pixel: the piece it is nearest to, its distance and where it came from.
    let mut owner = labels;
    let mut from = vec![usize::MAX; w * h];
    let mut dist = vec![u32::MAX; w * h];
    let mut queue = VecDeque::new();
    for (i, &l) in owner.iter().enumerate() {
        if l != u32::MAX {
            dist[i] = 0;
            queue.push_back(i);
        }
    }
    // The shortest gap found between each pair of pieces.
    let mut gaps: HashMap<(u32, u32), Gap> = HashMap::new();
    while let Some(i) = queue.pop_front() {
        let (x, y) = (i % w, i / w);
        let near = [
            (x > 0).then(|| i - 1),
            (x + 1 < w).then(|| i + 1),
            (y > 0).then(|| i - w),
            (y + 1 < h).then(|| i + w),
        ];
        for j in near.into_iter().flatten() {
            if owner[j] == u32::MAX {
                owner[j] = owner[i];
                dist[j] = dist[i] + 1;
                from[j] = i;
                queue.push_back(j);
            } else if owner[j] != owner[i] {
                let (a, b) = (owner[i].min(owner[j]), owner[i].max(owner[j]));
                let length = dist[i] + dist[j] + 1;
                let gap = gaps.entry((a, b)).or_insert((u32::MAX, i, j));
                if length < gap.0 {
                    *gap = (length, i, j);
                }
            }
        }
    }
    // Kruskal over the gaps, in a fixed order.
    let mut edges: Vec<((u32, u32), Gap)> = gaps.into_iter().collect();
    edges.sort_unstable_by_key(|&(pair, (length, i, j))| (length, pair, i, j));
    let mut parent: Vec<u32> = (0..pieces as u32).collect();
    fn root(parent: &mut [u32], mut a: u32) -> u32 {
        while parent[a as usize] != a {
            parent[a as usize] = parent[parent[a as usize] as usize];
            a = parent[a as usize];
        }
        a
    }
    for ((a, b), (_, i, j)) in edges {
        let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
        if ra == rb {
            continue;
        }
        parent[ra as usize] = rb;
        // The bridge: both pixels and their paths back to their pieces.
        for start in [i, j] {
            let mut k = start;
            while k != usize::MAX && !mask[k] {
                mask[k] = true;
                k = from[k];
            }
        }
    }
    make_well_composed(mask, w, h);
    pieces
}

/// `o` is the ring's orientation: +1 when its signed area (shoelace, y down) is
/// positive. A vertex is convex when `o·cross(b − a, c − b) > 0`.
struct Reducer {
    points: Vec<DVec2>,
    prev: Vec<usize>,
    next: Vec<usize>,
    alive: Vec<bool>,
    /// Bumped when a vertex's neighbourhood changes; stale heap entries are skipped.
    stamp: Vec<u32>,
    orientation: f64,
    /// The picture's far corner: new vertices stay within `[0, size]`.
    size: DVec2,
    grid: EdgeGrid,
    left: usize,
}

/// A step that adds area: remove vertex `i`, or replace the edge from `i` to its next
/// vertex by the meeting point of its neighbouring edges.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Step {
    Remove,
    Extend,
}

impl Reducer {
    fn new(points: Vec<DVec2>, size: DVec2) -> Self {
        let n = points.len();
        let orientation = signed_area(&points).signum();
        let prev = (0..n).map(|i| (i + n - 1) % n).collect();
        let next: Vec<usize> = (0..n).map(|i| (i + 1) % n).collect();
        let mut grid = EdgeGrid::new(size, n);
        for i in 0..n {
            grid.insert(i, points[i], points[next[i]]);
        }
        Self {
            points,
            prev,
            next,
            alive: vec![true; n],
            stamp: vec![0; n],
            orientation,
            size,
            grid,
            left: n,
        }
    }

    fn turn(&self, i: usize) -> f64 {
        let (a, b, c) = (
            self.points[self.prev[i]],
            self.points[i],
            self.points[self.next[i]],
        );
        self.orientation * (b - a).perp_dot(c - b)
    }

    /// The area step `step` at `i` adds, and the new point for [`Step::Extend`];
    /// `None` where the step does not apply.
    fn cost(&self, step: Step, i: usize) -> Option<(f64, DVec2)> {
        if self.left <= 3 {
            return None;
        }
        match step {
            Step::Remove => {
                if self.turn(i) > 0.0 {
                    return None;
                }
                let (a, b, c) = (
                    self.points[self.prev[i]],
                    self.points[i],
                    self.points[self.next[i]],
                );
                Some((0.5 * orient(a, b, c).abs(), b))
            }
            Step::Extend => {
                let j = self.next[i];
                if self.turn(i) <= 0.0 || self.turn(j) <= 0.0 {
                    return None;
                }
                let (a, b, c, d) = (
                    self.points[self.prev[i]],
                    self.points[i],
                    self.points[j],
                    self.points[self.next[j]],
                );
                // b + t·(b − a) = c + u·(c − d), t, u > 0.
                let (r, s) = (b - a, c - d);
                let det = r.perp_dot(-s);
                if det.abs() < 1e-12 * r.length() * s.length() {
                    return None;
                }
                let q = c - b;
                let t = q.perp_dot(-s) / det;
                let u = r.perp_dot(q) / det;
                if !(t > 0.0 && u > 0.0) {
                    return None;
                }
                let e = b + t * r;
                if !e.is_finite() || e.cmplt(DVec2::ZERO).any() || e.cmpgt(self.size).any() {
                    return None;
                }
                Some((0.5 * orient(b, e, c).abs(), e))
            }
        }
    }

    fn push(&self, heap: &mut BinaryHeap<Reverse<(u64, Step, u32, usize)>>, i: usize) {
        for step in [Step::Remove, Step::Extend] {
            if let Some((cost, _)) = self.cost(step, i) {
                // Non-negative finite costs order like their bits.
                heap.push(Reverse((cost.to_bits(), step, self.stamp[i], i)));
            }
        }
    }

    /// Whether the segment `p → q` would touch an edge of the ring other than those
    /// in `skip`; the edges in `ends` meet it at an end and may only not fold back
    /// over it.
    fn blocked(&self, p: DVec2, q: DVec2, skip: &[usize], ends: &[(usize, DVec2)]) -> bool {
        self.grid.any(p, q, |k| {
            if !self.alive[k] || skip.contains(&k) {
                return false;
            }
            let (s, t) = (self.points[k], self.points[self.next[k]]);
            if let Some(&(_, at)) = ends.iter().find(|(e, _)| *e == k) {
                // Shares the end `at`: only an overlap along the same line counts.
                let other = if s == at { t } else { s };
                let (u, v) = if p == at { (p, q) } else { (q, p) };
                return orient(u, v, other) == 0.0 && (v - u).dot(other - u) > 0.0;
            }
            segments_touch(p, q, s, t)
        })
    }

    fn reduce(mut self, target: usize) -> Vec<DVec2> {
        // A step blocked by an edge far away is dropped, and tried again only when its
        // own neighbourhood changes; so when the steps run out, every vertex is tried
        // once more, until a whole round brings no step.
        loop {
            let before = self.left;
            self.round(target);
            if self.left <= target || self.left == before {
                break;
            }
        }
        let start = (0..self.points.len()).find(|&i| self.alive[i]).unwrap_or(0);
        let mut out = vec![self.points[start]];
        let mut k = self.next[start];
        while k != start {
            out.push(self.points[k]);
            k = self.next[k];
        }
        out
    }

    /// Takes the cheapest steps left until `target` vertices are left or none is.
    fn round(&mut self, target: usize) {
        let mut heap = BinaryHeap::new();
        for i in 0..self.points.len() {
            if self.alive[i] {
                self.push(&mut heap, i);
            }
        }
        while self.left > target
            && let Some(Reverse((_, step, stamp, i))) = heap.pop()
        {
            if !self.alive[i] || stamp != self.stamp[i] {
                continue;
            }
            let Some((_, e)) = self.cost(step, i) else {
                continue;
            };
            let (pa, j) = (self.prev[i], self.next[i]);
            match step {
                Step::Remove => {
                    // The new edge a → c replaces a → b → c.
                    let (a, c) = (self.points[pa], self.points[j]);
                    let ends = [(self.prev[pa], a), (j, c)];
                    if self.blocked(a, c, &[pa, i], &ends) {
                        continue;
                    }
                    self.alive[i] = false;
                    self.next[pa] = j;
                    self.prev[j] = pa;
                    self.left -= 1;
                    self.changed(&mut heap, &[pa], &[pa, j]);
                }
                Step::Extend => {
                    // a → e → d replaces a → b → c → d; e takes b's slot.
                    let jd = self.next[j];
                    let (a, d) = (self.points[pa], self.points[jd]);
                    let skip = [pa, i, j];
                    if self.blocked(a, e, &skip, &[(self.prev[pa], a)])
                        || self.blocked(e, d, &skip, &[(jd, d)])
                    {
                        continue;
                    }
                    self.alive[j] = false;
                    self.points[i] = e;
                    self.next[i] = jd;
                    self.prev[jd] = i;
                    self.left -= 1;
                    self.changed(&mut heap, &[pa, i], &[pa, i, jd]);
                }
            }
        }
    }

    /// After a step: `edges` start new segments (put in the grid anew), and the
    /// vertices within two of `around` have new costs.
    fn changed(
        &mut self,
        heap: &mut BinaryHeap<Reverse<(u64, Step, u32, usize)>>,
        edges: &[usize],
        around: &[usize],
    ) {
        for &k in edges {
            let (p, q) = (self.points[k], self.points[self.next[k]]);
            self.grid.insert(k, p, q);
        }
        let mut touched: Vec<usize> = Vec::new();
        for &k in around {
            let (p, pp) = (self.prev[k], self.prev[self.prev[k]]);
            let (n, nn) = (self.next[k], self.next[self.next[k]]);
            touched.extend([pp, p, k, n, nn]);
        }
        touched.sort_unstable();
        touched.dedup();
        for k in touched {
            if self.alive[k] {
                self.stamp[k] += 1;
                self.push(heap, k);
            }
        }
    }
}

/// The ring's edges by the grid cells their bounding boxes cover, so a new edge is
/// tested against the edges near it only. Entries go stale when an edge is put in
/// anew (its version moves on) and are skipped, never removed.
struct EdgeGrid {
    cell: f64,
    columns: usize,
    rows: usize,
    cells: Vec<Vec<(usize, u32)>>,
    /// The current version of each edge (by its first vertex).
    current: Vec<u32>,
}

impl EdgeGrid {
    fn new(size: DVec2, edges: usize) -> Self {
        // About one edge per cell along the outline.
        let cell = (size.x.max(size.y) / (edges as f64).sqrt().max(1.0)).max(4.0);
        let columns = (size.x / cell).ceil().max(1.0) as usize;
        let rows = (size.y / cell).ceil().max(1.0) as usize;
        Self {
            cell,
            columns,
            rows,
            cells: vec![Vec::new(); columns * rows],
            current: vec![0; edges],
        }
    }

    fn span(&self, p: DVec2, q: DVec2) -> (usize, usize, usize, usize) {
        let clamp = |v: f64, n: usize| ((v / self.cell).floor().max(0.0) as usize).min(n - 1);
        let (lo, hi) = (p.min(q), p.max(q));
        (
            clamp(lo.x, self.columns),
            clamp(hi.x, self.columns),
            clamp(lo.y, self.rows),
            clamp(hi.y, self.rows),
        )
    }

    fn insert(&mut self, edge: usize, p: DVec2, q: DVec2) {
        self.current[edge] += 1;
        let stamp = self.current[edge];
        let (x0, x1, y0, y1) = self.span(p, q);
        for y in y0..=y1 {
            for x in x0..=x1 {
                self.cells[y * self.columns + x].push((edge, stamp));
            }
        }
    }

    /// Whether `hit` holds for an edge stored near the segment `p → q`.
    fn any(&self, p: DVec2, q: DVec2, mut hit: impl FnMut(usize) -> bool) -> bool {
        let (x0, x1, y0, y1) = self.span(p, q);
        for y in y0..=y1 {
            for x in x0..=x1 {
                for &(edge, stamp) in &self.cells[y * self.columns + x] {
                    if stamp == self.current[edge] && hit(edge) {
                        return true;
                    }
                }
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geometry::point_segment_distance;

    /// Whether every corner of every visible pixel lies inside `ring` or on it.
    fn encloses(image: &image::RgbaImage, ring: &[DVec2]) -> Result<(), (u32, u32)> {
        let n = ring.len();
        let on_or_inside = |p: DVec2| {
            let mut inside = false;
            for i in 0..n {
                let (a, b) = (ring[i], ring[(i + 1) % n]);
                if point_segment_distance(p, a, b) < 1e-9 {
                    return true;
                }
                if (a.y > p.y) != (b.y > p.y) && a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) > p.x
                {
                    inside = !inside;
                }
            }
            inside
        };
        for (x, y, p) in image.enumerate_pixels() {
            if p.0[3] > 0 {
                for (dx, dy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
                    if !on_or_inside(DVec2::new(f64::from(x) + dx, f64::from(y) + dy)) {
                        return Err((x, y));
                    }
                }
            }
        }
        Ok(())
    }

    fn simple(ring: &[DVec2]) -> bool {
        let n = ring.len();
        for i in 0..n {
            for j in i + 1..n {
                if j == i + 1 || (i == 0 && j == n - 1) {
                    continue;
                }
                let (a, b) = (ring[i], ring[(i + 1) % n]);
                let (c, d) = (ring[j], ring[(j + 1) % n]);
                if segments_touch(a, b, c, d) {
                    return false;
                }
            }
        }
        true
    }

    /// A figure with thin limbs, specks, and a hand a pixel from the picture's edge.
    fn figure() -> image::RgbaImage {
        image::RgbaImage::from_fn(160, 120, |x, y| {
            let (fx, fy) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
            let body = (fx - 80.0).hypot(fy - 60.0) < 22.0;
            let arm = (fy - 50.0).abs() < 1.5 && (20.0..140.0).contains(&fx);
            let hand = (fx - 158.5).hypot(fy - 50.0) < 2.0;
            let leg = (fx - 70.0 + 0.3 * (fy - 80.0)).abs() < 1.0 && (60.0..115.0).contains(&fy);
            let speck = (x, y) == (10, 10) || (x, y) == (150, 110) || (x, y) == (30, 100);
            let a = if body || arm || hand || leg || speck {
                255
            } else {
                0
            };
            image::Rgba([10, 20, 30, a])
        })
    }

    #[test]
    fn every_visible_pixel_is_enclosed_for_every_count() {
        let image = figure();
        for n in [3, 4, 5, 8, 12, 16, 24, 32, 48, 64] {
            let e = enclosing_ring(&image, n, 3.0).expect("a ring");
            assert!(e.ring.len() <= n.max(4), "{n}: {} vertices", e.ring.len());
            assert!(simple(&e.ring), "{n}: the ring crosses itself");
            assert_eq!(encloses(&image, &e.ring), Ok(()), "{n} vertices");
            assert!(
                e.ring
                    .iter()
                    .all(|p| p.x >= 0.0 && p.y >= 0.0 && p.x <= 160.0 && p.y <= 120.0)
            );
            assert_eq!(e.pieces, 5, "body with limbs, the hand, three specks");
        }
    }

    #[test]
    fn an_opaque_picture_gives_its_rectangle() {
        let image = image::RgbaImage::from_pixel(30, 20, image::Rgba([1, 1, 1, 255]));
        let e = enclosing_ring(&image, 8, 2.0).expect("a ring");
        assert_eq!(e.ring.len(), 4);
        assert_eq!(e.ring[2], DVec2::new(30.0, 20.0));
    }

    #[test]
    fn a_concave_shape_keeps_its_notch_when_vertices_allow() {
        // A U: the cage should not fill the notch when it has vertices to spare.
        let image = image::RgbaImage::from_fn(100, 100, |x, y| {
            let u = (10..90).contains(&x)
                && (10..90).contains(&y)
                && !((35..65).contains(&x) && y < 70);
            image::Rgba([0, 0, 0, if u { 255 } else { 0 }])
        });
        let e = enclosing_ring(&image, 16, 2.0).expect("a ring");
        assert_eq!(encloses(&image, &e.ring), Ok(()));
        let area = signed_area(&e.ring).abs();
        // The U covers 80² − 30·60 = 4600 px²; its hull 6400.
        assert!(area < 5600.0, "area {area}");
    }

    #[test]
    fn bad_requests_are_refused() {
        let image = figure();
        assert!(enclosing_ring(&image, 2, 3.0).is_err());
        assert!(enclosing_ring(&image, 8, f64::NAN).is_err());
        assert!(enclosing_ring(&image, 8, -1.0).is_err());
        assert!(matches!(
            enclosing_ring(&image::RgbaImage::new(5, 5), 8, 1.0),
            Err(MeshError::EmptyDomain)
        ));
    }
}
