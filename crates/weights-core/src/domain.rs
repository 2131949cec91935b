//! The sampled domain: sample positions, the triangles between them, the sample graph
//! (topology with edge lengths) and spatial grids for point queries.

use std::sync::OnceLock;

use geometry::{orient, segment_distance};
use glam::DVec2;

use crate::error::DomainError;

/// How distances inside the domain are measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    /// Straight-line distance: exact for a convex domain (a full rectangular image).
    Euclidean,
    /// Shortest paths along the sample graph: for holes, concave outlines and cuts.
    Intrinsic,
}

/// One directed edge of the sample graph.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Edge {
    pub to: u32,
    pub len: f32,
}

/// Adjacency of the samples in compressed rows: the edges of vertex `v` are
/// `edges[offsets[v]..offsets[v + 1]]`, sorted by target.
#[derive(Clone, Debug)]
pub(crate) struct Graph {
    offsets: Vec<u32>,
    edges: Vec<Edge>,
    /// The longest edge.
    max_len: f32,
    /// The shortest edge.
    min_len: f32,
}

impl Graph {
    fn from_triangles(positions: &[DVec2], triangles: &[[u32; 3]]) -> Self {
        let n = positions.len();
        let mut degree = vec![0u32; n + 1];
        for t in triangles {
            for &v in t {
                degree[v as usize] += 2;
            }
        }
        let mut offsets = Vec::with_capacity(n + 1);
        let mut acc = 0u32;
        for d in &degree[..n] {
            offsets.push(acc);
            acc += d;
        }
        offsets.push(acc);
        let mut fill: Vec<u32> = offsets[..n].to_vec();
        let mut targets = vec![0u32; acc as usize];
        for t in triangles {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                targets[fill[a as usize] as usize] = b;
                fill[a as usize] += 1;
                targets[fill[b as usize] as usize] = a;
                fill[b as usize] += 1;
            }
        }
        // Sort and deduplicate each row (an interior edge is seen from both triangles).
        let mut new_offsets = Vec::with_capacity(n + 1);
        let mut edges = Vec::with_capacity(acc as usize / 2 + n);
        for v in 0..n {
            new_offsets.push(edges.len() as u32);
            let row = &mut targets[offsets[v] as usize..offsets[v + 1] as usize];
            row.sort_unstable();
            let mut last = u32::MAX;
            for &to in row.iter() {
                if to != last {
                    let len = (positions[v] - positions[to as usize]).length() as f32;
                    edges.push(Edge { to, len });
                    last = to;
                }
            }
        }
        new_offsets.push(edges.len() as u32);
        let max_len = edges.iter().map(|e| e.len).fold(0.0, f32::max);
        let min_len = edges.iter().map(|e| e.len).fold(f32::INFINITY, f32::min);
        Self {
            offsets: new_offsets,
            edges,
            max_len,
            min_len,
        }
    }

    /// The length of the longest edge.
    pub fn max_edge_length(&self) -> f64 {
        f64::from(self.max_len)
    }

    /// The length of the shortest edge (∞ without edges).
    pub fn min_edge_length(&self) -> f64 {
        f64::from(self.min_len)
    }

    /// Asks the processor to fetch the edges of `v` into its cache ahead of a
    /// [`Graph::neighbors`] call: a search queues a sample long before it visits it,
    /// and the visit otherwise waits on memory.
    #[inline]
    pub fn prefetch(&self, v: u32) {
        #[cfg(target_arch = "x86_64")]
        if let Some(&start) = self.offsets.get(v as usize) {
            let edges = self.edges[start as usize..].as_ptr();
            // SAFETY: a prefetch is a hint; it reads nothing the program sees and
            // cannot fault, and the pointer lies inside the edge list.
            #[allow(unsafe_code)]
            unsafe {
                use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
                _mm_prefetch::<_MM_HINT_T0>(edges.cast());
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = v;
    }

    #[inline]
    pub fn neighbors(&self, v: u32) -> &[Edge] {
        let v = v as usize;
        &self.edges[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }

    #[cfg(test)]
    pub fn edge_count(&self) -> usize {
        self.edges.len() / 2
    }
}

/// A uniform grid over the domain's bounding box whose cells list items (vertex or
/// triangle indices) in compressed rows.
#[derive(Clone, Debug)]
pub(crate) struct Grid {
    origin: DVec2,
    cell: f64,
    pub nx: usize,
    pub ny: usize,
    starts: Vec<u32>,
    items: Vec<u32>,
}

impl Grid {
    fn shape(min: DVec2, max: DVec2, count: usize, per_cell: f64) -> (DVec2, f64, usize, usize) {
        let size = (max - min).max(DVec2::splat(1e-9));
        let cells = (count as f64 / per_cell).max(1.0);
        let cell = (size.x * size.y / cells)
            .sqrt()
            .max(size.max_element() / 4096.0);
        let nx = ((size.x / cell).ceil() as usize).clamp(1, 4096);
        let ny = ((size.y / cell).ceil() as usize).clamp(1, 4096);
        (min, cell, nx, ny)
    }

    fn build(
        (origin, cell, nx, ny): (DVec2, f64, usize, usize),
        count: usize,
        cells_of: impl Fn(usize) -> (usize, usize, usize, usize),
    ) -> Self {
        let mut counts = vec![0u32; nx * ny + 1];
        for i in 0..count {
            let (x0, y0, x1, y1) = cells_of(i);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    counts[y * nx + x] += 1;
                }
            }
        }
        let mut starts = Vec::with_capacity(nx * ny + 1);
        let mut acc = 0u32;
        for c in &counts[..nx * ny] {
            starts.push(acc);
            acc += c;
        }
        starts.push(acc);
        let mut fill = starts[..nx * ny].to_vec();
        let mut items = vec![0u32; acc as usize];
        for i in 0..count {
            let (x0, y0, x1, y1) = cells_of(i);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let c = y * nx + x;
                    items[fill[c] as usize] = i as u32;
                    fill[c] += 1;
                }
            }
        }
        Self {
            origin,
            cell,
            nx,
            ny,
            starts,
            items,
        }
    }

    /// The cell coordinates of `p`, clamped to the grid.
    #[inline]
    pub fn cell_of(&self, p: DVec2) -> (usize, usize) {
        let q = (p - self.origin) / self.cell;
        (
            (q.x.max(0.0) as usize).min(self.nx - 1),
            (q.y.max(0.0) as usize).min(self.ny - 1),
        )
    }

    #[inline]
    pub fn items(&self, x: usize, y: usize) -> &[u32] {
        let c = y * self.nx + x;
        &self.items[self.starts[c] as usize..self.starts[c + 1] as usize]
    }

    pub fn cell_count(&self) -> usize {
        self.nx * self.ny
    }

    /// Items of cell index `c` (row-major).
    #[inline]
    pub fn items_of_cell(&self, c: usize) -> &[u32] {
        &self.items[self.starts[c] as usize..self.starts[c + 1] as usize]
    }

    /// Squared distance from `p` to the closed box of cell `c`.
    #[inline]
    pub fn cell_distance_squared(&self, c: usize, p: DVec2) -> f64 {
        let (x, y) = (c % self.nx, c / self.nx);
        let lo = self.origin + DVec2::new(x as f64, y as f64) * self.cell;
        let hi = lo + DVec2::splat(self.cell);
        let d = (lo - p).max(p - hi).max(DVec2::ZERO);
        d.length_squared()
    }

    /// Squared distance from `p` to the farthest point of the box of cell `c`.
    #[inline]
    pub fn cell_far_distance_squared(&self, c: usize, p: DVec2) -> f64 {
        let (x, y) = (c % self.nx, c / self.nx);
        let lo = self.origin + DVec2::new(x as f64, y as f64) * self.cell;
        let hi = lo + DVec2::splat(self.cell);
        let d = (p - lo).abs().max((hi - p).abs());
        d.length_squared()
    }

    /// The inclusive range of cells overlapping the disc of radius `r` around `p`.
    pub fn cells_in_disc(&self, p: DVec2, r: f64) -> (usize, usize, usize, usize) {
        let (x0, y0) = self.cell_of(p - DVec2::splat(r));
        let (x1, y1) = self.cell_of(p + DVec2::splat(r));
        (x0, y0, x1, y1)
    }

    pub fn cell_size(&self) -> f64 {
        self.cell
    }
}

/// The domain the weights live on: samples (mesh vertices) in image pixel coordinates
/// and the triangles between them.
///
/// Samples are connected by the triangles' edges; that graph carries the intrinsic
/// (inside-the-shape) distance when the metric is [`Metric::Intrinsic`].
///
/// Wherever two samples tie (equally near, equally far), the one of lower rank wins:
/// its index, or for a domain made by [`Domain::in_local_order`] the number the caller
/// gave it, so that a renumbered mesh is weighed as the caller's numbering would have
/// it.
#[derive(Clone, Debug)]
pub struct Domain {
    positions: Vec<DVec2>,
    triangles: Vec<[u32; 3]>,
    metric: Metric,
    /// The caller's number of each sample ([`Domain::in_local_order`]); `None`: its
    /// index.
    rank: Option<Vec<u32>>,
    min: DVec2,
    max: DVec2,
    graph: OnceLock<Graph>,
    vertex_grid: OnceLock<Grid>,
    triangle_grid: OnceLock<Grid>,
    boundary: OnceLock<Vec<Vec<u32>>>,
    mean_edge: OnceLock<f64>,
}

impl Domain {
    /// A domain from sample positions (pixels) and triangles (indices into `positions`).
    ///
    /// # Errors
    /// Non-finite positions, out-of-range or repeated indices, or no triangles at all.
    pub fn new(
        positions: Vec<DVec2>,
        triangles: Vec<[u32; 3]>,
        metric: Metric,
    ) -> Result<Self, DomainError> {
        check(&positions, &triangles)?;
        Ok(Self::new_unchecked(positions, triangles, metric))
    }

    /// The domain [`Domain::new`] makes of `positions` and `triangles`, its samples
    /// numbered along a Z-order curve (samples at one place in the given order), and
    /// the new number of each given vertex. The graph searches of a rig walk from
    /// sample to neighbouring sample: numbered so, neighbours sit near each other in
    /// memory, where a mesh generator's numbering scatters them. The triangles keep
    /// their order. Ties between samples are broken by the given numbering
    /// ([`Domain::rank`]), so a rig on this domain has the weights of a rig on
    /// `Domain::new(positions, triangles, metric)`, sample for renumbered sample.
    ///
    /// # Errors
    /// As [`Domain::new`], with the given numbering.
    pub fn in_local_order(
        positions: Vec<DVec2>,
        triangles: Vec<[u32; 3]>,
        metric: Metric,
    ) -> Result<(Self, Vec<u32>), DomainError> {
        check(&positions, &triangles)?;
        let order = geometry::z_order(&positions);
        let mut renumber = vec![0u32; positions.len()];
        for (new, &old) in order.iter().enumerate() {
            renumber[old as usize] = new as u32;
        }
        let mut domain = Self::new_unchecked(
            order.iter().map(|&old| positions[old as usize]).collect(),
            triangles
                .iter()
                .map(|t| t.map(|v| renumber[v as usize]))
                .collect(),
            metric,
        );
        domain.rank = Some(order);
        Ok((domain, renumber))
    }

    fn new_unchecked(positions: Vec<DVec2>, triangles: Vec<[u32; 3]>, metric: Metric) -> Self {
        let (min, max) = positions.iter().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        Self {
            positions,
            triangles,
            metric,
            rank: None,
            min,
            max,
            graph: OnceLock::new(),
            vertex_grid: OnceLock::new(),
            triangle_grid: OnceLock::new(),
            boundary: OnceLock::new(),
            mean_edge: OnceLock::new(),
        }
    }

    /// The rank of sample `v` among samples that tie: the caller's number of it (see
    /// [`Domain::in_local_order`]), else `v` itself.
    #[inline]
    pub fn rank(&self, v: u32) -> u32 {
        match &self.rank {
            Some(rank) => rank[v as usize],
            None => v,
        }
    }

    /// Whether sample `v` wins a tie against sample `w` (`w` may be `u32::MAX`: none,
    /// which every sample beats).
    #[inline]
    pub(crate) fn ranks_before(&self, v: u32, w: u32) -> bool {
        w == u32::MAX || self.rank(v) < self.rank(w)
    }

    /// Sample positions in pixels.
    pub fn positions(&self) -> &[DVec2] {
        &self.positions
    }

    /// Triangles as vertex index triples.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The distance in use.
    pub fn metric(&self) -> Metric {
        self.metric
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// Whether there are no samples (never true for a constructed domain).
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Bounding box `(min, max)` of the samples.
    pub fn bounds(&self) -> (DVec2, DVec2) {
        (self.min, self.max)
    }

    /// Mean length of the triangles' edges: the sampling resolution.
    pub fn mean_edge_length(&self) -> f64 {
        *self.mean_edge.get_or_init(|| {
            use rayon::prelude::*;
            let total: f64 = self
                .triangles
                .par_iter()
                .map(|t| {
                    let [a, b, c] = t.map(|v| self.positions[v as usize]);
                    (a - b).length() + (b - c).length() + (c - a).length()
                })
                .sum();
            total / (3 * self.triangles.len()).max(1) as f64
        })
    }

    /// Builds the lazily computed structures the chosen metric needs, so that later
    /// timings do not include them.
    pub fn prepare(&self) {
        self.mean_edge_length();
        self.vertex_grid();
        self.triangle_grid();
        if self.metric == Metric::Intrinsic {
            self.graph();
        }
    }

    pub(crate) fn graph(&self) -> &Graph {
        self.graph
            .get_or_init(|| Graph::from_triangles(&self.positions, &self.triangles))
    }

    pub(crate) fn vertex_grid(&self) -> &Grid {
        self.vertex_grid.get_or_init(|| {
            let shape = Grid::shape(self.min, self.max, self.positions.len(), 8.0);
            let probe = Grid::build(shape, 0, |_| (0, 0, 0, 0));
            Grid::build(shape, self.positions.len(), |i| {
                let (x, y) = probe.cell_of(self.positions[i]);
                (x, y, x, y)
            })
        })
    }

    fn triangle_grid(&self) -> &Grid {
        self.triangle_grid.get_or_init(|| {
            let shape = Grid::shape(self.min, self.max, self.triangles.len(), 4.0);
            let probe = Grid::build(shape, 0, |_| (0, 0, 0, 0));
            Grid::build(shape, self.triangles.len(), |i| {
                let [a, b, c] = self.triangle_corners(i);
                let (x0, y0) = probe.cell_of(a.min(b).min(c));
                let (x1, y1) = probe.cell_of(a.max(b).max(c));
                (x0, y0, x1, y1)
            })
        })
    }

    fn triangle_corners(&self, t: usize) -> [DVec2; 3] {
        self.triangles[t].map(|v| self.positions[v as usize])
    }

    /// The triangle containing `p` and `p`'s barycentric coordinates in it, allowing a
    /// tolerance of `1e-9` (relative to the domain size) on its edges; `None` outside.
    pub fn locate(&self, p: DVec2) -> Option<(usize, [f64; 3])> {
        if !p.is_finite() {
            return None;
        }
        let grid = self.triangle_grid();
        let (x, y) = grid.cell_of(p);
        let eps = 1e-9;
        let mut best: Option<(usize, [f64; 3], f64)> = None;
        for &t in grid.items(x, y) {
            let Some(bary) = barycentric(self.triangle_corners(t as usize), p) else {
                continue;
            };
            let worst = bary.iter().copied().fold(f64::INFINITY, f64::min);
            if worst >= -eps && best.as_ref().is_none_or(|b| worst > b.2) {
                best = Some((t as usize, bary, worst));
                if worst >= 0.0 {
                    break;
                }
            }
        }
        best.map(|(t, b, _)| (t, b))
    }

    /// The sample nearest to `p` (ties to the lower rank).
    pub fn nearest_vertex(&self, p: DVec2) -> Option<u32> {
        if !p.is_finite() {
            return None;
        }
        let grid = self.vertex_grid();
        let (cx, cy) = grid.cell_of(p);
        let mut best: Option<(f64, u32)> = None;
        for ring in 0..grid.nx.max(grid.ny) {
            // Every point of ring k is at least (k − 1) cells away from p.
            if let Some((d2, _)) = best {
                let reach = (ring as f64 - 1.0).max(0.0) * grid.cell_size();
                if reach * reach > d2 {
                    break;
                }
            }
            let (x0, x1) = (cx.saturating_sub(ring), (cx + ring).min(grid.nx - 1));
            let (y0, y1) = (cy.saturating_sub(ring), (cy + ring).min(grid.ny - 1));
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let on_ring = x.abs_diff(cx) == ring || y.abs_diff(cy) == ring;
                    if !on_ring {
                        continue;
                    }
                    for &v in grid.items(x, y) {
                        let d2 = (self.positions[v as usize] - p).length_squared();
                        if best
                            .is_none_or(|(b, bv)| d2 < b || (d2 == b && self.ranks_before(v, bv)))
                        {
                            best = Some((d2, v));
                        }
                    }
                }
            }
        }
        best.map(|(_, v)| v)
    }

    /// The samples at exactly sample `v`'s place, `v` among them, in rank order: more
    /// than one where the mesh was split along a cut (the vertices on it doubled, one
    /// for each side).
    pub fn coincident(&self, v: u32) -> Vec<u32> {
        let Some(&p) = self.positions.get(v as usize) else {
            return Vec::new();
        };
        let grid = self.vertex_grid();
        let (x, y) = grid.cell_of(p);
        let mut out: Vec<u32> = (grid.items(x, y).iter().copied())
            .filter(|&u| self.positions[u as usize] == p)
            .collect();
        out.sort_unstable_by_key(|&u| self.rank(u));
        out
    }

    /// The samples within `r` of the segment from `a` to `b` (of the point `a` when
    /// `a == b`), in rank order; none for a non-finite segment or radius.
    pub fn vertices_near_segment(&self, a: DVec2, b: DVec2, r: f64) -> Vec<u32> {
        if !(a.is_finite() && b.is_finite() && r.is_finite() && r >= 0.0) {
            return Vec::new();
        }
        let grid = self.vertex_grid();
        let (x0, y0) = grid.cell_of(a.min(b) - DVec2::splat(r));
        let (x1, y1) = grid.cell_of(a.max(b) + DVec2::splat(r));
        let mut out = Vec::new();
        for y in y0..=y1 {
            for x in x0..=x1 {
                for &v in grid.items(x, y) {
                    let p = self.positions[v as usize];
                    if segment_distance([p, p], [a, b]) <= r {
                        out.push(v);
                    }
                }
            }
        }
        out.sort_unstable_by_key(|&v| self.rank(v));
        out
    }

    /// Closed boundary loops (edges used by exactly one triangle), each as a vertex
    /// sequence without repeating the first vertex, each starting at its sample of
    /// lowest rank.
    pub fn boundary_loops(&self) -> &[Vec<u32>] {
        self.boundary.get_or_init(|| match &self.rank {
            None => boundary_loops(&self.triangles),
            // Traced in the caller's numbering, so that loops start, and turn at a
            // vertex where two meet, as they would there.
            Some(rank) => {
                let ranked: Vec<[u32; 3]> = (self.triangles.iter())
                    .map(|t| t.map(|v| rank[v as usize]))
                    .collect();
                let mut sample = vec![0u32; rank.len()];
                for (v, &r) in rank.iter().enumerate() {
                    sample[r as usize] = v as u32;
                }
                let mut loops = boundary_loops(&ranked);
                for v in loops.iter_mut().flatten() {
                    *v = sample[*v as usize];
                }
                loops
            }
        })
    }

    /// Whether the segment from `a` to `b` lies in the domain: both ends inside and no
    /// boundary edge crossed (touching the boundary is allowed).
    pub fn contains_segment(&self, a: DVec2, b: DVec2) -> bool {
        if self.locate(a).is_none() || self.locate(b).is_none() {
            return false;
        }
        let scale = (self.max - self.min).length().max(1e-12);
        let tol = 1e-12 * scale * scale;
        let side = |p: DVec2, q: DVec2, r: DVec2| {
            let c = orient(p, q, r);
            if c > tol {
                1
            } else if c < -tol {
                -1
            } else {
                0
            }
        };
        let crosses = |p: DVec2, q: DVec2| {
            let (s1, s2) = (side(a, b, p), side(a, b, q));
            let (s3, s4) = (side(p, q, a), side(p, q, b));
            s1 * s2 < 0 && s3 * s4 < 0
        };
        let positions = &self.positions;
        !self.boundary_loops().iter().any(|ring| {
            (0..ring.len()).any(|i| {
                let p = positions[ring[i] as usize];
                let q = positions[ring[(i + 1) % ring.len()] as usize];
                crosses(p, q)
            })
        }) && self.locate((a + b) * 0.5).is_some()
    }

    /// Whether the domain is one region bounded by a single convex loop (collinear
    /// boundary vertices allowed): then [`Metric::Euclidean`] is exact.
    pub fn is_convex(&self) -> bool {
        let loops = self.boundary_loops();
        if loops.len() != 1 {
            return false;
        }
        let ring: Vec<DVec2> = loops[0]
            .iter()
            .map(|&v| self.positions[v as usize])
            .collect();
        let n = ring.len();
        let scale = (self.max - self.min).length().max(1e-12);
        let (mut pos, mut neg) = (false, false);
        for i in 0..n {
            let (a, b, c) = (ring[i], ring[(i + 1) % n], ring[(i + 2) % n]);
            let cross = (b - a).perp_dot(c - b);
            let tol = 1e-9 * scale * (b - a).length().max((c - b).length());
            if cross > tol {
                pos = true;
            } else if cross < -tol {
                neg = true;
            } else if (b - a).dot(c - b) < 0.0 {
                // The boundary doubles back on itself: a cut.
                return false;
            }
        }
        !(pos && neg)
    }
}

/// Barycentric coordinates of `p` in the triangle, `None` for a degenerate triangle.
pub(crate) fn barycentric([a, b, c]: [DVec2; 3], p: DVec2) -> Option<[f64; 3]> {
    let area = (b - a).perp_dot(c - a);
    if area.abs() <= f64::EPSILON * (b - a).length_squared().max((c - a).length_squared()) {
        return None;
    }
    let u = (b - p).perp_dot(c - p) / area;
    let v = (c - p).perp_dot(a - p) / area;
    Some([u, v, 1.0 - u - v])
}

fn boundary_loops(triangles: &[[u32; 3]]) -> Vec<Vec<u32>> {
    // Undirected edge keys with the directed edge as seen from one triangle.
    let mut keys: Vec<(u64, u32, u32)> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| {
            let key = (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
            (key, a, b)
        })
        .collect();
    keys.sort_unstable_by_key(|k| k.0);
    let mut next: std::collections::HashMap<u32, Vec<u32>> = std::collections::HashMap::new();
    let mut i = 0;
    while i < keys.len() {
        let mut j = i + 1;
        while j < keys.len() && keys[j].0 == keys[i].0 {
            j += 1;
        }
        if j - i == 1 {
            next.entry(keys[i].1).or_default().push(keys[i].2);
        }
        i = j;
    }
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    let mut loops = Vec::new();
    for start in starts {
        while let Some(first) = next.get_mut(&start).and_then(|v| v.pop()) {
            let mut ring = vec![start];
            let mut at = first;
            while at != start {
                ring.push(at);
                match next.get_mut(&at).and_then(|v| v.pop()) {
                    Some(n) => at = n,
                    None => break,
                }
            }
            loops.push(ring);
        }
    }
    loops
}

/// Checks what [`Domain::new`] requires of `positions` and `triangles`.
fn check(positions: &[DVec2], triangles: &[[u32; 3]]) -> Result<(), DomainError> {
    if triangles.is_empty() {
        return Err(DomainError::Empty);
    }
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(DomainError::NonFinite { vertex: i });
    }
    for (i, t) in triangles.iter().enumerate() {
        if t.iter().any(|&v| v as usize >= positions.len()) {
            return Err(DomainError::IndexOutOfRange {
                triangle: i,
                vertices: positions.len(),
            });
        }
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            return Err(DomainError::DegenerateTriangle { triangle: i });
        }
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A regular grid of `nx × ny` cells of size `h`, two triangles per cell, with the
    /// diagonal mirrored about the vertical centre line.
    pub fn grid_mesh(nx: usize, ny: usize, h: f64) -> (Vec<DVec2>, Vec<[u32; 3]>) {
        let mut positions = Vec::new();
        for y in 0..=ny {
            for x in 0..=nx {
                positions.push(DVec2::new(x as f64 * h, y as f64 * h));
            }
        }
        let id = |x: usize, y: usize| (y * (nx + 1) + x) as u32;
        let mut triangles = Vec::new();
        for y in 0..ny {
            for x in 0..nx {
                let (a, b, c, d) = (id(x, y), id(x + 1, y), id(x + 1, y + 1), id(x, y + 1));
                if 2 * x < nx {
                    triangles.push([a, b, c]);
                    triangles.push([a, c, d]);
                } else {
                    triangles.push([a, b, d]);
                    triangles.push([b, c, d]);
                }
            }
        }
        (positions, triangles)
    }

    #[test]
    fn graph_of_a_grid() {
        let (p, t) = grid_mesh(3, 2, 1.0);
        let d = Domain::new(p, t, Metric::Intrinsic).expect("valid");
        let g = d.graph();
        // 3x2 cells: 17 horizontal+vertical edges + 6 diagonals.
        assert_eq!(g.edge_count(), 4 * 2 + 3 * 3 + 6);
        for v in 0..d.len() as u32 {
            for e in g.neighbors(v) {
                assert!(g.neighbors(e.to).iter().any(|b| b.to == v));
            }
        }
    }

    #[test]
    fn convexity_and_boundary() {
        let (p, t) = grid_mesh(4, 3, 1.0);
        let d = Domain::new(p.clone(), t.clone(), Metric::Euclidean).expect("valid");
        assert_eq!(d.boundary_loops().len(), 1);
        assert_eq!(d.boundary_loops()[0].len(), 14);
        assert!(d.is_convex());
        // Remove the two triangles of the top-right cell's neighbour: an L shape.
        let l: Vec<_> = t
            .iter()
            .copied()
            .filter(|tri| {
                let c = tri.iter().map(|&v| p[v as usize]).sum::<DVec2>() / 3.0;
                !(c.x > 2.0 && c.y < 1.0)
            })
            .collect();
        let d = Domain::new(p, l, Metric::Intrinsic).expect("valid");
        assert!(!d.is_convex());
    }

    #[test]
    fn segments_that_cut_a_corner_of_a_hole_are_outside() {
        // A 6 × 6 grid without the cell [2, 3] × [2, 3].
        let (p, t) = grid_mesh(6, 6, 1.0);
        let kept: Vec<_> = t
            .iter()
            .copied()
            .filter(|tri| {
                let c = tri.iter().map(|&v| p[v as usize]).sum::<DVec2>() / 3.0;
                !(c.x > 2.0 && c.x < 3.0 && c.y > 2.0 && c.y < 3.0)
            })
            .collect();
        let d = Domain::new(p, kept, Metric::Intrinsic).expect("valid");
        // Its ends and every point a coarse walk would test are inside; it clips the
        // hole's corner at (2, 2).
        assert!(!d.contains_segment(DVec2::new(1.5, 2.7), DVec2::new(2.7, 1.5)));
        assert!(d.contains_segment(DVec2::new(1.5, 2.4), DVec2::new(2.4, 1.5)));
        // Along the hole's edge is allowed.
        assert!(d.contains_segment(DVec2::new(2.0, 1.0), DVec2::new(2.0, 4.0)));
        assert!(!d.contains_segment(DVec2::new(1.0, 2.5), DVec2::new(4.0, 2.5)));
    }

    #[test]
    fn locate_and_nearest() {
        let (p, t) = grid_mesh(10, 10, 2.0);
        let d = Domain::new(p, t, Metric::Euclidean).expect("valid");
        let (tri, bary) = d.locate(DVec2::new(3.1, 7.3)).expect("inside");
        let corners = d.triangle_corners(tri);
        let back = corners[0] * bary[0] + corners[1] * bary[1] + corners[2] * bary[2];
        assert!((back - DVec2::new(3.1, 7.3)).length() < 1e-12);
        assert!(d.locate(DVec2::new(-1.0, 3.0)).is_none());
        assert!(d.locate(DVec2::new(20.0, 20.0)).is_some());
        let v = d.nearest_vertex(DVec2::new(3.1, 7.3)).expect("some");
        assert_eq!(d.positions()[v as usize], DVec2::new(4.0, 8.0));
        let v = d.nearest_vertex(DVec2::new(100.0, -50.0)).expect("some");
        assert_eq!(d.positions()[v as usize], DVec2::new(20.0, 0.0));
    }

    #[test]
    fn bad_input_is_refused() {
        let p = vec![DVec2::ZERO, DVec2::X, DVec2::Y];
        assert!(Domain::new(p.clone(), vec![], Metric::Euclidean).is_err());
        assert!(Domain::new(p.clone(), vec![[0, 1, 3]], Metric::Euclidean).is_err());
        assert!(Domain::new(p.clone(), vec![[0, 1, 1]], Metric::Euclidean).is_err());
        let mut bad = p;
        bad[1].x = f64::NAN;
        assert!(Domain::new(bad, vec![[0, 1, 2]], Metric::Euclidean).is_err());
    }
}
