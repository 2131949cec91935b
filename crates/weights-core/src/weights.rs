//! Sparse per-sample weights: for each sample the nodes whose support reaches it with
//! their unnormalised basis values φ(d/r), and the sum that normalises them.
//!
//! Storage is compressed rows of (node: u32, φ: f32) — 8 bytes per non-zero — in chunks
//! of 4096 samples (an update rewrites only the chunks it touches), plus one f64 sum per
//! sample. Normalising in f64 keeps Σw = 1 to rounding, whatever the
//! precision of φ. Rows are ordered by the node's sample index, so a row (and its sum)
//! does not depend on how nodes are numbered. A sample that no support reaches (only
//! possible exactly on a support boundary) has an empty row and takes its own cell's
//! node with weight 1.

use glam::{DAffine2, DVec2};
use rayon::prelude::*;
use std::sync::atomic::Ordering::Relaxed;

use crate::basis::Basis;
use crate::domain::{Domain, Metric};
use crate::queue::{Entry, Queue};
use crate::voronoi::{CellField, NONE, Partition};

/// Reusable buffers for bounded Dijkstra searches, one set per thread. `dist` is all
/// infinite between searches (each search resets what it set: the samples it returns,
/// and those it reached beyond a radius that shrank).
struct Scratch {
    dist: Vec<f64>,
    queue: Queue,
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Scratch> = const {
        std::cell::RefCell::new(Scratch {
            dist: Vec::new(),
            queue: Queue::new(),
        })
    };
}

/// The samples within `radius` of node sample `source` (and the source itself), with
/// their distances (for the intrinsic metric in order of distance to within a bucket of
/// the search queue: half the shortest edge).
pub(crate) fn ball(domain: &Domain, source: u32, radius: f64) -> Vec<(u32, f64)> {
    search(domain, source, radius, Known::Nothing, None).0
}

/// The distance from sample `source` to the nearest other sample `is_node` accepts
/// (intrinsic metric; ∞ if none is reachable).
pub(crate) fn nearest_node_distance(
    domain: &Domain,
    source: u32,
    is_node: &dyn Fn(u32) -> bool,
) -> f64 {
    search(domain, source, f64::INFINITY, Known::Nothing, Some(is_node))
        .0
        .iter()
        .filter(|&&(v, _)| v != source && is_node(v))
        .map(|&(_, d)| d)
        .fold(f64::INFINITY, f64::min)
}

/// What a search already knows of the source's distance field.
#[derive(Clone, Copy)]
enum Known<'a> {
    /// Nothing: the search starts at the source.
    Nothing,
    /// Every sample closer than `radius`, with its exact distance. Along the graph only
    /// the samples near the ball's rim are put back on the queue (the others have no
    /// neighbour outside it).
    Ball {
        entries: &'a [(u32, f64)],
        radius: f64,
    },
    /// Every sample of the source's Voronoi cell, with its exact distance (its distance
    /// to the cell's node), and `seeds`, the cell's samples with a neighbour in another
    /// cell. A shortest path from the node to a sample outside the cell leaves it for
    /// good at some sample; that sample is a seed (its next one lies in another cell),
    /// so the search goes on from the seeds only.
    Cell {
        entries: &'a [(u32, f64)],
        seeds: &'a [u32],
    },
}

/// [`ball`], continuing from what is `known`. The distances found beyond are the ones a
/// search from scratch finds: each is the same minimum over the same neighbours.
///
/// With `nearest`, the search stops at the nearest sample it accepts (other than the
/// source) instead: at its distance times 1 + 10⁻⁶, beyond any f32 rounding of that
/// distance, so that the field covers a support radius of at most that distance (any
/// other node's). Returns the field and the radius it was searched to.
fn search(
    domain: &Domain,
    source: u32,
    mut radius: f64,
    known: Known<'_>,
    nearest: Option<&dyn Fn(u32) -> bool>,
) -> (Vec<(u32, f64)>, f64) {
    let mut out = Vec::new();
    match domain.metric() {
        Metric::Intrinsic => SCRATCH.with(|scratch| {
            let mut scratch = scratch.borrow_mut();
            let Scratch { dist, queue } = &mut *scratch;
            if dist.len() != domain.len() {
                *dist = vec![f64::INFINITY; domain.len()];
            }
            let graph = domain.graph();
            queue.prepare(graph.min_edge_length(), graph.max_edge_length());
            // Entries put back on the queue carry key 1: they are in `out` already.
            const KNOWN: u32 = 1;
            // How many of `out`'s entries came from a known cell.
            let mut known_out = 0;
            match known {
                Known::Ball { entries, radius: r } => {
                    if let Some(accept) = nearest {
                        // The nearest accepted sample may lie inside the known ball.
                        let inside = entries
                            .iter()
                            .filter(|&&(v, _)| v != source && accept(v))
                            .map(|&(_, d)| d)
                            .fold(f64::INFINITY, f64::min);
                        radius = inside * (1.0 + 1e-6);
                        if radius <= r {
                            // Reached already: nothing to search.
                            return;
                        }
                    }
                    // A known sample with a neighbour beyond the known ball is at most
                    // one edge inside its rim.
                    let rim = r - 2.0 * graph.max_edge_length();
                    for &(v, d) in entries {
                        dist[v as usize] = d;
                        if d >= rim {
                            queue.push(Entry::new(d, KNOWN, v));
                        }
                    }
                    out.extend_from_slice(entries);
                }
                Known::Cell { entries, seeds } => {
                    debug_assert!(nearest.is_none(), "a cell's search goes to a radius");
                    for &(v, d) in entries {
                        dist[v as usize] = d;
                    }
                    for &v in seeds {
                        let d = dist[v as usize];
                        if d < radius {
                            queue.push(Entry::new(d, KNOWN, v));
                        }
                    }
                    out.extend(entries.iter().copied().filter(|&(_, d)| d < radius));
                    known_out = out.len();
                }
                Known::Nothing => {
                    dist[source as usize] = 0.0;
                    queue.push(Entry::new(0.0, 0, source));
                }
            }
            while let Some(entry) = queue.pop() {
                let (d, v) = (entry.d(), entry.v());
                if d > dist[v as usize] {
                    continue;
                }
                if d >= radius && v != source {
                    // Reached before the radius shrank: not returned, so reset here.
                    dist[v as usize] = f64::INFINITY;
                    continue;
                }
                if let Some(accept) = nearest
                    && d * (1.0 + 1e-6) < radius
                    && v != source
                    && accept(v)
                {
                    // (Samples come out of the queue in order only to within a bucket:
                    // a nearer accepted one may still follow, and farther ones already
                    // out are dropped below.)
                    radius = d * (1.0 + 1e-6);
                }
                if entry.key() != KNOWN {
                    out.push((v, d));
                }
                for e in graph.neighbors(v) {
                    let nd = d + f64::from(e.len);
                    let w = e.to as usize;
                    if nd < dist[w] && nd < radius {
                        dist[w] = nd;
                        graph.prefetch(e.to);
                        queue.push(Entry::new(nd, 0, e.to));
                    }
                }
            }
            queue.clear();
            // Reset what was set: the cell's samples (those beyond the radius were set
            // but not returned) and what the search found, or everything returned.
            let found = match known {
                Known::Cell { entries, .. } => {
                    for &(v, _) in entries {
                        dist[v as usize] = f64::INFINITY;
                    }
                    &out[known_out..]
                }
                _ => &out[..],
            };
            for &(v, _) in found {
                dist[v as usize] = f64::INFINITY;
            }
            if nearest.is_some() {
                out.retain(|&(v, d)| d < radius || v == source);
            }
        }),
        Metric::Euclidean => {
            let grid = domain.vertex_grid();
            let positions = domain.positions();
            let p = positions[source as usize];
            let reach = if radius.is_finite() {
                radius
            } else {
                f64::MAX / 4.0
            };
            let (x0, y0, x1, y1) = grid.cells_in_disc(p, reach);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    for &v in grid.items(x, y) {
                        let d = (positions[v as usize] - p).length();
                        if d < radius || v == source {
                            out.push((v, d));
                        }
                    }
                }
            }
        }
    }
    (out, radius)
}

/// A node's distance field near it, kept so that a new support radius needs no new
/// search (and a larger one only a search beyond it): the samples closer than `radius`
/// with their exact distances. Weights are computed from the distances rounded to f32
/// on every path, so rebuilds and updates agree bit for bit; how far a field was
/// searched does not matter.
#[derive(Clone, Debug, Default)]
pub(crate) struct Ball {
    /// How far the search went (negative: nothing cached).
    radius: f64,
    entries: Vec<(u32, f64)>,
}

impl Ball {
    /// The samples closer than `radius` to sample `source`, searched now.
    pub fn compute(domain: &Domain, source: u32, radius: f64) -> Self {
        Self {
            radius,
            entries: ball(domain, source, radius),
        }
    }

    /// The field of a node on `source` to `radius`, searched on from its Voronoi cell
    /// (see [`Partition::cell_field`]) if there is one.
    pub fn compute_from(
        domain: &Domain,
        source: u32,
        radius: f64,
        cell: Option<CellField>,
    ) -> Self {
        match cell {
            Some(cell) if !cell.entries.is_empty() => {
                let known = Known::Cell {
                    entries: &cell.entries,
                    seeds: &cell.seeds,
                };
                Self {
                    radius,
                    entries: search(domain, source, radius, known, None).0,
                }
            }
            _ => Self::compute(domain, source, radius),
        }
    }

    /// The field of a node on `source` searched to the nearest sample `is_node`
    /// accepts: it covers any support radius the node can have while those samples
    /// carry nodes. (Straight-line distance needs no search ahead: `None`.)
    pub fn to_nearest(domain: &Domain, source: u32, is_node: &dyn Fn(u32) -> bool) -> Option<Self> {
        if domain.metric() != Metric::Intrinsic {
            return None;
        }
        let (entries, radius) =
            search(domain, source, f64::INFINITY, Known::Nothing, Some(is_node));
        Some(Self { radius, entries })
    }

    /// This field (of the node on `source`) searched on to the nearest sample `is_node`
    /// accepts, if that lies beyond it: `None` when the field reaches that far already
    /// (or distances are straight-line).
    pub fn extend_to_nearest(
        &self,
        domain: &Domain,
        source: u32,
        is_node: &dyn Fn(u32) -> bool,
    ) -> Option<Self> {
        if domain.metric() != Metric::Intrinsic || self.radius < 0.0 || self.entries.is_empty() {
            return None;
        }
        let known = Known::Ball {
            entries: &self.entries,
            radius: self.radius,
        };
        let (entries, radius) = search(domain, source, f64::INFINITY, known, Some(is_node));
        (radius > self.radius).then_some(Self { radius, entries })
    }

    /// This field (of the node on `source`) searched on to `radius`.
    pub fn extend(&self, domain: &Domain, source: u32, radius: f64) -> Self {
        if self.radius < 0.0 || self.entries.is_empty() {
            return Self::compute(domain, source, radius);
        }
        Self {
            radius,
            entries: search(
                domain,
                source,
                radius,
                Known::Ball {
                    entries: &self.entries,
                    radius: self.radius,
                },
                None,
            )
            .0,
        }
    }

    /// How far the field reaches (negative: nothing cached).
    pub fn radius(&self) -> f64 {
        self.radius
    }

    fn covers(&self, radius: f64) -> bool {
        self.radius >= radius
    }

    /// Support entries from the cached field (`r_h`: the node's distance to its
    /// nearest other node).
    fn support(
        &self,
        basis: &Basis,
        (radius, r_h): (f64, f64),
        nodes: &SampleSet,
        source: u32,
    ) -> Vec<(u32, f32)> {
        self.entries
            .iter()
            .filter_map(|&(v, d)| {
                support_entry(basis, nodes, source, v, d, (radius, r_h)).map(|f| (v, f))
            })
            .collect()
    }
}

/// A set of samples, a bit each: one load to ask (the partition answers whether a
/// sample carries a node from two tables; [`support_entry`] asks for every sample a
/// support reaches).
pub(crate) struct SampleSet(Vec<u64>);

impl SampleSet {
    /// The empty set of a domain of `samples` samples.
    pub fn new(samples: usize) -> Self {
        Self(vec![0; samples.div_ceil(64)])
    }

    /// The samples that carry a node of `partition`.
    pub fn nodes_of(samples: usize, partition: &Partition) -> Self {
        let mut set = Self::new(samples);
        for &v in &partition.node_vertex {
            set.insert(v);
        }
        set
    }

    pub fn insert(&mut self, v: u32) {
        self.0[v as usize / 64] |= 1 << (v % 64);
    }

    #[inline]
    pub fn contains(&self, v: u32) -> bool {
        self.0[v as usize / 64] >> (v % 64) & 1 == 1
    }
}

/// The basis value node `source` gives sample `v` at distance `d` with support
/// `radius` (an f32-representable value, at or above the exact support) and `r_h` (its
/// distance to its nearest other node), or `None`: 1 at its own sample, nothing at any
/// other node's sample (so weights interpolate exactly) nor at or beyond `r_h`,
/// φ(d / radius) for d (rounded to f32) < radius. Every path that makes weights goes
/// through here.
///
/// (Distances are kept as f32, and the support is rounded up to match; without the
/// exact `r_h` limit, a sample just beyond the nearest node could round inside it —
/// and one that stops carrying a node would then take entries that an update, which
/// keeps the entries of nodes that did not change, could not give it.)
#[inline]
fn support_entry(
    basis: &Basis,
    nodes: &SampleSet,
    source: u32,
    v: u32,
    exact: f64,
    (radius, r_h): (f64, f64),
) -> Option<f32> {
    if v == source {
        return Some(1.0);
    }
    let d = f64::from(exact as f32);
    if d >= radius || exact >= r_h || nodes.contains(v) {
        return None;
    }
    let phi = basis.eval(d / radius) as f32;
    (phi > 0.0).then_some(phi)
}

/// Rows per chunk of [`Rows`].
const CHUNK: usize = 4096;

/// Compressed rows of (node, φ) in chunks of [`CHUNK`] consecutive samples, each chunk
/// with arrays of its own: an update rewrites only the chunks whose rows change.
#[derive(Clone, Debug, Default)]
struct Rows {
    chunks: Vec<Chunk>,
}

/// The rows of one chunk: row `i` is `nodes[offsets[i]..offsets[i + 1]]` with `phi[…]`.
#[derive(Clone, Debug, Default)]
struct Chunk {
    offsets: Vec<u32>,
    nodes: Vec<u32>,
    phi: Vec<f32>,
}

impl Chunk {
    fn new() -> Self {
        Self {
            offsets: vec![0],
            nodes: Vec::new(),
            phi: Vec::new(),
        }
    }

    /// Appends a row.
    fn push(&mut self, row: impl IntoIterator<Item = (u32, f32)>) {
        for (k, f) in row {
            self.nodes.push(k);
            self.phi.push(f);
        }
        self.offsets.push(self.nodes.len() as u32);
    }

    fn row(&self, i: usize) -> (&[u32], &[f32]) {
        let (a, b) = (self.offsets[i] as usize, self.offsets[i + 1] as usize);
        (&self.nodes[a..b], &self.phi[a..b])
    }
}

impl Rows {
    fn row(&self, v: usize) -> (&[u32], &[f32]) {
        self.chunks[v / CHUNK].row(v % CHUNK)
    }

    fn nonzeros(&self) -> usize {
        self.chunks.iter().map(|c| c.nodes.len()).sum()
    }

    fn memory_bytes(&self) -> usize {
        self.chunks
            .iter()
            .map(|c| c.offsets.len() * 4 + c.nodes.len() * 4 + c.phi.len() * 4)
            .sum()
    }
}

/// The sparse weights of every sample.
#[derive(Clone, Debug, Default)]
pub(crate) struct Weights {
    rows: Rows,
    sums: Vec<f64>,
    /// Per node, its cached distance field.
    balls: Vec<Ball>,
    /// Fields of nodes removed since the last update, by sample (Algorithm 1 often puts
    /// a virtual handle back where one was removed), and fields searched ahead of it.
    spare: std::collections::HashMap<u32, Ball>,
}

/// Entries `(sample, node, φ)` of the samples `lo..hi` bucketed by row (a counting
/// sort that keeps their order within a row): row `v` gets
/// `by_row[start[v - lo]..start[v - lo + 1]]`.
fn bucket_rows<'a>(
    lo: usize,
    hi: usize,
    parts: impl Iterator<Item = &'a [(u32, u32, f32)]> + Clone,
) -> (Vec<u32>, Vec<(u32, f32)>) {
    let mut start = vec![0u32; hi - lo + 1];
    for e in parts.clone().flatten() {
        start[e.0 as usize - lo + 1] += 1;
    }
    for i in 0..hi - lo {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut by_row = vec![(0u32, 0f32); start[hi - lo] as usize];
    for &(v, k, f) in parts.flatten() {
        let at = &mut fill[v as usize - lo];
        by_row[*at as usize] = (k, f);
        *at += 1;
    }
    (start, by_row)
}

/// A per-node change for [`Weights::update`]: the node, its radius before the change
/// (`None` for a new node) and after.
pub(crate) struct Change {
    pub node: usize,
    pub old_radius: Option<f64>,
}

impl Weights {
    /// Weights from scratch, with the distance fields already searched (by node
    /// sample; a node without one, or whose field does not reach its support radius,
    /// is searched here).
    pub fn build(
        domain: &Domain,
        partition: &Partition,
        radii: &[f64],
        basis: &Basis,
        searched: Vec<(u32, Ball)>,
    ) -> Self {
        if domain.metric() == Metric::Euclidean {
            return Self::build_euclidean(domain, partition, radii, basis);
        }
        let n = domain.len();
        let mut found: std::collections::HashMap<u32, Ball> = searched.into_iter().collect();
        let found: Vec<Option<Ball>> = (0..partition.len())
            .map(|k| {
                found
                    .remove(&partition.node_vertex[k])
                    .filter(|b| b.covers(radii[k]))
            })
            .collect();
        let balls: Vec<Ball> = found
            .into_par_iter()
            .enumerate()
            .map(|(k, ball)| {
                ball.unwrap_or_else(|| {
                    let cell = partition.cell_field(domain, k);
                    Ball::compute_from(domain, partition.node_vertex[k], radii[k], cell)
                })
            })
            .collect();
        let nodes = SampleSet::nodes_of(n, partition);
        let supports: Vec<Vec<(u32, f32)>> = balls
            .par_iter()
            .enumerate()
            .map(|(k, b)| {
                let limits = (radii[k], partition.stats[k].r_h);
                b.support(basis, limits, &nodes, partition.node_vertex[k])
            })
            .collect();
        let mut order: Vec<usize> = (0..partition.len()).collect();
        order.sort_unstable_by_key(|&k| domain.rank(partition.node_vertex[k]));
        // Every support's entries bucketed by chunk, nodes in rank order.
        let mut by_chunk: Vec<Vec<(u32, u32, f32)>> = vec![Vec::new(); n.div_ceil(CHUNK)];
        for &k in &order {
            for &(v, f) in &supports[k] {
                by_chunk[v as usize / CHUNK].push((v, k as u32, f));
            }
        }
        let chunks: Vec<Chunk> = by_chunk
            .into_par_iter()
            .enumerate()
            .map(|(c, entries)| {
                let (lo, hi) = (c * CHUNK, ((c + 1) * CHUNK).min(n));
                let (start, by_row) = bucket_rows(lo, hi, std::iter::once(&entries[..]));
                let mut chunk = Chunk::new();
                for i in 0..hi - lo {
                    chunk.push(
                        by_row[start[i] as usize..start[i + 1] as usize]
                            .iter()
                            .copied(),
                    );
                }
                chunk
            })
            .collect();
        let mut w = Self {
            rows: Rows { chunks },
            sums: Vec::new(),
            balls,
            spare: Default::default(),
        };
        w.sums = (0..n).map(|v| w.row_sum(v)).collect();
        w
    }

    /// Euclidean weights row by row: each vertex-grid cell lists the nodes whose support
    /// reaches it, and each sample evaluates only those. Node fields are left to be
    /// cached on demand.
    fn build_euclidean(
        domain: &Domain,
        partition: &Partition,
        radii: &[f64],
        basis: &Basis,
    ) -> Self {
        let n = domain.len();
        let nodes = SampleSet::nodes_of(n, partition);
        let grid = domain.vertex_grid();
        let positions = domain.positions();
        // Per cell, the nodes whose support disc meets it (or whose sample is in it), in
        // order of the nodes' samples: nodes visited in that order, bucketed by cell.
        let mut order: Vec<u32> = (0..partition.len() as u32).collect();
        order.sort_unstable_by_key(|&k| domain.rank(partition.node_vertex[k as usize]));
        let reached: Vec<Vec<u32>> = order
            .par_iter()
            .map(|&k| {
                let p = positions[partition.node_vertex[k as usize] as usize];
                let r = radii[k as usize];
                let reach = if r.is_finite() { r } else { f64::MAX / 4.0 };
                let (x0, y0, x1, y1) = grid.cells_in_disc(p, reach);
                let own = grid.cell_of(p);
                let mut cells = Vec::new();
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        let c = y * grid.nx + x;
                        if grid.cell_distance_squared(c, p) < reach * reach || (x, y) == own {
                            cells.push(c as u32);
                        }
                    }
                }
                cells
            })
            .collect();
        let mut cell_start = vec![0u32; grid.cell_count() + 1];
        for cells in &reached {
            for &c in cells {
                cell_start[c as usize + 1] += 1;
            }
        }
        for c in 0..grid.cell_count() {
            cell_start[c + 1] += cell_start[c];
        }
        let mut fill = cell_start.clone();
        let mut by_cell = vec![0u32; cell_start[grid.cell_count()] as usize];
        for (&k, cells) in order.iter().zip(&reached) {
            for &c in cells {
                by_cell[fill[c as usize] as usize] = k;
                fill[c as usize] += 1;
            }
        }
        let parts: Vec<(Chunk, Vec<f64>)> = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|chunk| {
                let (lo, hi) = (chunk * CHUNK, ((chunk + 1) * CHUNK).min(n));
                let mut rows = Chunk::new();
                let mut sums = Vec::with_capacity(hi - lo);
                for v in lo..hi {
                    let p = positions[v];
                    let (x, y) = grid.cell_of(p);
                    let c = y * grid.nx + x;
                    let mut sum = 0.0;
                    for &k in &by_cell[cell_start[c] as usize..cell_start[c + 1] as usize] {
                        let source = partition.node_vertex[k as usize];
                        let d = (positions[source as usize] - p).length();
                        let limits = (radii[k as usize], partition.stats[k as usize].r_h);
                        if let Some(f) = support_entry(basis, &nodes, source, v as u32, d, limits) {
                            rows.nodes.push(k);
                            rows.phi.push(f);
                            sum += f64::from(f);
                        }
                    }
                    rows.offsets.push(rows.nodes.len() as u32);
                    sums.push(sum);
                }
                (rows, sums)
            })
            .collect();
        let mut w = Self {
            rows: Rows::default(),
            sums: Vec::with_capacity(n),
            balls: vec![
                Ball {
                    radius: -1.0,
                    entries: Vec::new()
                };
                partition.len()
            ],
            spare: Default::default(),
        };
        for (rows, sums) in parts {
            w.rows.chunks.push(rows);
            w.sums.extend_from_slice(&sums);
        }
        w
    }

    fn row_sum(&self, v: usize) -> f64 {
        self.rows.row(v).1.iter().map(|&f| f64::from(f)).sum()
    }

    /// Samples node `k` (on sample `source`) reached within `radius`, from its cached
    /// distance field (searched now if none is cached).
    pub fn reached(&self, domain: &Domain, k: usize, source: u32, radius: f64) -> Vec<u32> {
        let fresh;
        let ball = if self.balls[k].covers(radius) {
            &self.balls[k]
        } else {
            fresh = Ball::compute(domain, source, radius);
            &fresh
        };
        ball.entries
            .iter()
            .filter(|&&(_, d)| f64::from(d as f32) < radius || d == 0.0)
            .map(|&(v, _)| v)
            .collect()
    }

    /// Node `k`'s cached distance field (how far it reaches: [`Ball::radius`]).
    pub fn field(&self, k: usize) -> &Ball {
        &self.balls[k]
    }

    /// Distance fields searched ahead of the next [`Weights::update`], by sample: it
    /// uses them where its cached ones fall short.
    pub fn offer(&mut self, fields: Vec<(u32, Ball)>) {
        for (v, field) in fields {
            self.keep_spare(v, field);
        }
    }

    /// Keeps `field` (of the node on sample `v`) for the next update, unless a wider
    /// one is kept already.
    fn keep_spare(&mut self, v: u32, field: Ball) {
        if self.spare.get(&v).is_none_or(|b| b.radius < field.radius) {
            self.spare.insert(v, field);
        }
    }

    /// Renumbers the cached distance fields after a removal: `map[old] = new` (or
    /// `NONE` for a removed node); `old_vertex` are the nodes' samples before it. The
    /// rows are renumbered by the next [`Weights::update`], which gets the same map.
    pub fn renumber_fields(&mut self, map: &[u32], old_vertex: &[u32]) {
        let balls = std::mem::take(&mut self.balls);
        self.balls = Vec::with_capacity(balls.len());
        for ((ball, &m), &v) in balls.into_iter().zip(map).zip(old_vertex) {
            if m != NONE {
                self.balls.push(ball);
            } else if ball.radius >= 0.0 {
                self.keep_spare(v, ball);
            }
        }
    }

    /// Brings the weights up to date after the nodes in `changes` got new radii (or
    /// appeared), and after nodes were removed (`map[old] = new` numbers the nodes the
    /// rows still hold, `NONE` for a removed one; `dirty` lists the samples removed
    /// nodes reached). Only chunks with rows that change are rewritten; the others are
    /// renumbered in place if nodes were removed.
    #[allow(clippy::too_many_arguments)]
    pub fn update(
        &mut self,
        domain: &Domain,
        partition: &Partition,
        radii: &[f64],
        basis: &Basis,
        changes: &[Change],
        map: &[u32],
        dirty: &[u32],
    ) {
        let n = domain.len();
        self.balls.resize_with(partition.len(), || Ball {
            radius: -1.0,
            entries: Vec::new(),
        });
        for c in changes {
            let reach = c.old_radius.map_or(radii[c.node], |o| o.max(radii[c.node]));
            if !self.balls[c.node].covers(reach)
                && let Some(ball) = self.spare.remove(&partition.node_vertex[c.node])
                && ball.covers(reach)
            {
                self.balls[c.node] = ball;
            }
        }
        self.spare.clear();
        // Dirty samples (every sample a changed or removed node reaches or reached) as a
        // bit set, marked by the parallel passes below.
        let dirty_bits: Vec<std::sync::atomic::AtomicU64> = (0..n.div_ceil(64))
            .map(|_| std::sync::atomic::AtomicU64::new(0))
            .collect();
        let mark = |v: u32| {
            let bit = 1 << (v % 64);
            let word = &dirty_bits[v as usize / 64];
            if word.load(Relaxed) & bit == 0 {
                word.fetch_or(bit, Relaxed);
            }
        };
        dirty
            .par_chunks(CHUNK)
            .for_each(|vs| vs.iter().for_each(|&v| mark(v)));
        /// A changed node, a fresh ball if the cached one was too small, and its new
        /// support entries `(sample, node, φ)` bucketed by chunk.
        type Reach = (usize, Option<Ball>, Vec<Vec<(u32, u32, f32)>>);
        let chunk_count = n.div_ceil(CHUNK);
        let nodes = SampleSet::nodes_of(n, partition);
        let balls = &self.balls;
        let results: Vec<Reach> = changes
            .par_iter()
            .map(|c| {
                let r = radii[c.node];
                let source = partition.node_vertex[c.node];
                let reach = c.old_radius.map_or(r, |o| o.max(r));
                let fresh = (!balls[c.node].covers(reach))
                    .then(|| balls[c.node].extend(domain, source, reach));
                let ball = fresh.as_ref().unwrap_or(&balls[c.node]);
                // Every sample the node reaches or reached gets its row redone.
                mark(source);
                let mut by_chunk = vec![Vec::new(); chunk_count];
                let limits = (r, partition.stats[c.node].r_h);
                for &(v, d) in &ball.entries {
                    if f64::from(d as f32) >= reach && v != source {
                        // Beyond the support now and before: no row changes.
                        continue;
                    }
                    mark(v);
                    if let Some(f) = support_entry(basis, &nodes, source, v, d, limits) {
                        by_chunk[v as usize / CHUNK].push((v, c.node as u32, f));
                    }
                }
                (c.node, fresh, by_chunk)
            })
            .collect();
        let dirty_bits: Vec<u64> = dirty_bits.into_iter().map(|w| w.into_inner()).collect();
        let mut changed_node = vec![false; partition.len()];
        for c in changes {
            changed_node[c.node] = true;
        }
        let renumbered = map.iter().enumerate().any(|(i, &m)| m != i as u32);
        let dirty_bits = &dirty_bits;
        let changed_node = &changed_node;
        self.rows
            .chunks
            .par_iter_mut()
            .zip(self.sums.par_chunks_mut(CHUNK))
            .enumerate()
            .for_each(|(c, (chunk, sums))| {
                let (lo, hi) = (c * CHUNK, ((c + 1) * CHUNK).min(n));
                let is_dirty = |v: usize| dirty_bits[v / 64] >> (v % 64) & 1 == 1;
                if !(lo..hi).step_by(64).any(|v| dirty_bits[v / 64] != 0) {
                    if renumbered {
                        for k in chunk.nodes.iter_mut() {
                            *k = map[*k as usize];
                        }
                    }
                    return;
                }
                let fresh = results.iter().map(|r| &r.2[c][..]);
                let (start, by_row) = bucket_rows(lo, hi, fresh);
                let mut rebuilt = Chunk::new();
                // At most every old entry and every new one.
                let most = chunk.nodes.len() + by_row.len();
                rebuilt.nodes.reserve(most);
                rebuilt.phi.reserve(most);
                rebuilt.offsets.reserve(hi - lo);
                let mut v = lo;
                while v < hi {
                    if !is_dirty(v) {
                        // A run of clean rows, copied in bulk.
                        let run = v;
                        while v < hi && !is_dirty(v) {
                            v += 1;
                        }
                        let (a, b) = (chunk.offsets[run - lo], chunk.offsets[v - lo]);
                        let base = rebuilt.nodes.len() as u32;
                        rebuilt.offsets.pop();
                        rebuilt.offsets.extend(
                            chunk.offsets[run - lo..=v - lo]
                                .iter()
                                .map(|&o| o - a + base),
                        );
                        let kept = &chunk.nodes[a as usize..b as usize];
                        if renumbered {
                            rebuilt.nodes.extend(kept.iter().map(|&k| map[k as usize]));
                        } else {
                            rebuilt.nodes.extend_from_slice(kept);
                        }
                        rebuilt
                            .phi
                            .extend_from_slice(&chunk.phi[a as usize..b as usize]);
                        continue;
                    }
                    // A dirty row: its entries of unchanged nodes (in the order of
                    // their samples' ranks already), then each changed node's new
                    // entry put in its place.
                    let i = v - lo;
                    let (a, b) = (chunk.offsets[i] as usize, chunk.offsets[i + 1] as usize);
                    let base = rebuilt.nodes.len();
                    for (&k, &f) in chunk.nodes[a..b].iter().zip(&chunk.phi[a..b]) {
                        let k = map[k as usize];
                        if k != NONE && !changed_node[k as usize] {
                            rebuilt.nodes.push(k);
                            rebuilt.phi.push(f);
                        }
                    }
                    for &(k, f) in &by_row[start[i] as usize..start[i + 1] as usize] {
                        let rank = |k: u32| domain.rank(partition.node_vertex[k as usize]);
                        let key = rank(k);
                        let mut at = rebuilt.nodes.len();
                        rebuilt.nodes.push(k);
                        rebuilt.phi.push(f);
                        while at > base && rank(rebuilt.nodes[at - 1]) > key {
                            rebuilt.nodes[at] = rebuilt.nodes[at - 1];
                            rebuilt.phi[at] = rebuilt.phi[at - 1];
                            at -= 1;
                        }
                        rebuilt.nodes[at] = k;
                        rebuilt.phi[at] = f;
                    }
                    sums[i] = rebuilt.phi[base..].iter().map(|&f| f64::from(f)).sum();
                    rebuilt.offsets.push(rebuilt.nodes.len() as u32);
                    v += 1;
                }
                *chunk = rebuilt;
            });
        for (node, ball, _) in results {
            if let Some(ball) = ball {
                self.balls[node] = ball;
            }
        }
    }

    /// The normalised weights of sample `v` as (node, weight) pairs; `owner` is the
    /// partition's owner array (for the empty-row fallback).
    pub fn row<'a>(
        &'a self,
        v: usize,
        owner: &'a [u32],
    ) -> impl Iterator<Item = (usize, f64)> + 'a {
        let (nodes, phi) = self.rows.row(v);
        let s = self.sums[v];
        let fallback = (nodes.is_empty() && owner[v] != NONE).then_some((owner[v] as usize, 1.0));
        nodes
            .iter()
            .zip(phi)
            .map(move |(&k, &f)| (k as usize, f64::from(f) / s))
            .chain(fallback)
    }

    /// Number of stored non-zeros.
    pub fn nonzeros(&self) -> usize {
        self.rows.nonzeros()
    }

    /// Bytes used by the weights.
    pub fn memory_bytes(&self) -> usize {
        self.rows.memory_bytes() + self.sums.len() * 8
    }

    /// Linear blend of the node transforms at every sample: `out[v] = Σ w_k(v) A_k p_v`.
    pub fn deform(
        &self,
        positions: &[DVec2],
        owner: &[u32],
        affines: &[DAffine2],
        out: &mut [DVec2],
    ) {
        out.par_chunks_mut(CHUNK)
            .zip(&self.rows.chunks)
            .enumerate()
            .for_each(|(c, (out, rows))| {
                let start = c * CHUNK;
                for (i, o) in out.iter_mut().enumerate() {
                    let v = start + i;
                    let p = positions[v];
                    let (nodes, phi) = rows.row(i);
                    if nodes.is_empty() {
                        *o = match owner[v] {
                            NONE => p,
                            k => affines[k as usize].transform_point2(p),
                        };
                        continue;
                    }
                    let mut acc = DVec2::ZERO;
                    for (&k, &f) in nodes.iter().zip(phi) {
                        acc += f64::from(f) * affines[k as usize].transform_point2(p);
                    }
                    *o = acc / self.sums[v];
                }
            });
    }

    /// Whether two weight sets are identical up to the numbering of nodes, given each
    /// node's sample (its identity).
    pub fn same_as(
        &self,
        (a_keys, a_owner): (&[u32], &[u32]),
        other: &Self,
        (b_keys, b_owner): (&[u32], &[u32]),
    ) -> Result<(), String> {
        if self.sums.len() != other.sums.len() {
            return Err("different sample counts".into());
        }
        for v in 0..self.sums.len() {
            let ra: Vec<(u32, u64)> = self
                .row(v, a_owner)
                .map(|(k, w)| (a_keys[k], w.to_bits()))
                .collect();
            let rb: Vec<(u32, u64)> = other
                .row(v, b_owner)
                .map(|(k, w)| (b_keys[k], w.to_bits()))
                .collect();
            if ra != rb {
                return Err(format!("sample {v}: {ra:?} vs {rb:?}"));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::domain::tests::grid_mesh;

    #[test]
    fn a_field_searched_to_the_nearest_node_covers_the_support_the_node_gets() {
        // Jittered grid, intrinsic metric, a few nodes; a new node anywhere.
        let (mut p, t) = grid_mesh(30, 20, 1.0);
        let mut s = 5u64;
        for q in p
            .iter_mut()
            .filter(|q| q.x > 0.0 && q.y > 0.0 && q.x < 30.0 && q.y < 20.0)
        {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            q.x += ((s >> 33) as f64 / (1u64 << 31) as f64 - 0.5) * 0.4;
        }
        let d = Domain::new(p, t, Metric::Intrinsic).expect("valid");
        let nodes = vec![40, 300, 555];
        for q in [41u32, 200, 400, 620] {
            let is_node = |v: u32| nodes.contains(&v);
            let field = Ball::to_nearest(&d, q, &is_node).expect("intrinsic");
            let mut part = Partition::new(&d, nodes.clone());
            part.add_node(&d, q);
            let r_h = part.stats[3].r_h;
            assert!(field.radius() >= r_h, "{} < {r_h}", field.radius());
            assert!(field.radius() <= r_h * (1.0 + 1e-5));
            // The same samples and distances as a search to that radius.
            let mut a = field.entries.clone();
            let mut b = ball(&d, q, field.radius());
            a.sort_by_key(|e| e.0);
            b.sort_by_key(|e| e.0);
            assert_eq!(a, b);
        }
    }

    #[test]
    fn a_field_searched_on_to_the_nearest_node_covers_it() {
        let (p, t) = grid_mesh(30, 20, 1.0);
        let d = Domain::new(p, t, Metric::Intrinsic).expect("valid");
        let nodes = [205u32, 500];
        let is_node = |v: u32| nodes.contains(&v);
        // Node 200 is 5 edges from node 205: a field of radius 3.5 must grow to 5.
        let near = Ball::compute(&d, 200, 3.5);
        let grown = near.extend_to_nearest(&d, 200, &is_node).expect("grows");
        assert!(grown.radius() >= 5.0 && grown.radius() <= 5.0 * (1.0 + 1e-5));
        let mut a = grown.entries.clone();
        let mut b = ball(&d, 200, grown.radius());
        a.sort_by_key(|e| e.0);
        b.sort_by_key(|e| e.0);
        assert_eq!(a, b);
        // A field that reaches the nearest node already needs nothing more.
        let wide = Ball::compute(&d, 200, 6.0);
        assert!(wide.extend_to_nearest(&d, 200, &is_node).is_none());
    }

    #[test]
    fn a_field_searched_on_equals_one_searched_at_once() {
        let (p, t) = grid_mesh(30, 20, 1.0);
        let d = Domain::new(p, t, Metric::Intrinsic).expect("valid");
        let near = Ball::compute(&d, 200, 3.5);
        let far = near.extend(&d, 200, 9.25);
        let mut a = far.entries.clone();
        let mut b = ball(&d, 200, 9.25);
        a.sort_by_key(|e| e.0);
        b.sort_by_key(|e| e.0);
        assert_eq!(a, b);
        assert!(a.len() > near.entries.len());
    }

    #[test]
    fn a_field_searched_on_from_its_cell_equals_one_searched_at_once() {
        // A regular grid (distances tie everywhere) and a jittered one, with nodes in
        // clusters and apart; some at exactly even spacing.
        let (p, t) = grid_mesh(40, 30, 1.0);
        let regular = Domain::new(p.clone(), t.clone(), Metric::Intrinsic).expect("valid");
        let mut s = 11u64;
        let jittered: Vec<DVec2> = p
            .iter()
            .map(|&q| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let inside = q.x > 0.0 && q.y > 0.0 && q.x < 40.0 && q.y < 30.0;
                let a = ((s >> 33) as f64 / (1u64 << 31) as f64 - 0.5) * 0.3;
                let b = ((s >> 13 & 0xfffff) as f64 / (1u64 << 20) as f64 - 0.5) * 0.3;
                if inside { q + DVec2::new(a, b) } else { q }
            })
            .collect();
        let jittered = Domain::new(jittered, t, Metric::Intrinsic).expect("valid");
        for d in [&regular, &jittered] {
            let mut part = Partition::new(d, vec![0, 2, 4, 300, 345, 606, 1000, 1234]);
            // Cells made by the incremental paths too: nodes added one by one (as
            // Algorithm 1 does) and one removed (its samples handed to its neighbours).
            part.add_node(d, 700);
            part.add_node(d, 20);
            part.remove_node(d, 4);
            for k in 0..part.len() {
                let source = part.node_vertex[k];
                let r_h = part.stats[k].r_h;
                // Radii inside the cell, across its rim, and well beyond it.
                for radius in [r_h * 0.3, r_h, r_h * 1.5, f64::INFINITY] {
                    let from = Ball::compute_from(d, source, radius, part.cell_field(d, k));
                    let mut a = from.entries.clone();
                    let mut b = ball(d, source, radius);
                    a.sort_by_key(|e| e.0);
                    b.sort_by_key(|e| e.0);
                    assert_eq!(a, b, "node {k}, radius {radius}");
                }
            }
        }
    }
}
