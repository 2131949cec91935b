//! Sparse per-sample weights: for each sample the nodes whose support reaches it with
//! their unnormalised basis values φ(d/r), and the sum that normalises them.
//!
//! Storage is compressed rows of (node: u32, φ: f32) — 8 bytes per non-zero — plus one
//! f64 sum per sample. Normalising in f64 keeps Σw = 1 to rounding, whatever the
//! precision of φ. Rows are ordered by the node's sample index, so a row (and its sum)
//! does not depend on how nodes are numbered. A sample that no support reaches (only
//! possible exactly on a support boundary) has an empty row and takes its own cell's
//! node with weight 1.

use std::collections::BinaryHeap;

use glam::{DAffine2, DVec2};
use rayon::prelude::*;

use crate::basis::Basis;
use crate::domain::{Domain, Metric};
use crate::voronoi::{Entry, NONE, Partition};

/// Reusable buffers for bounded Dijkstra searches, one set per thread. `dist` is all
/// infinite between searches (each search resets what it touched).
struct Scratch {
    dist: Vec<f64>,
    touched: Vec<u32>,
    heap: BinaryHeap<Entry>,
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Scratch> = const {
        std::cell::RefCell::new(Scratch {
            dist: Vec::new(),
            touched: Vec::new(),
            heap: BinaryHeap::new(),
        })
    };
}

/// The samples within `radius` of node sample `source` (and the source itself), with
/// their distances, in order of distance for the intrinsic metric.
pub(crate) fn ball(domain: &Domain, source: u32, radius: f64) -> Vec<(u32, f64)> {
    search(domain, source, radius, None)
}

/// [`ball`], continuing from `known`: every sample closer than `known_radius`, with its
/// exact distance. Along the graph only the samples near the known ball's rim are put
/// back on the queue (the others have no neighbour outside it), and the distances found
/// beyond are the ones a search from scratch finds: each is the same minimum over the
/// same neighbours.
fn search(
    domain: &Domain,
    source: u32,
    radius: f64,
    known: Option<(&[(u32, f64)], f64)>,
) -> Vec<(u32, f64)> {
    let mut out = Vec::new();
    match domain.metric() {
        Metric::Intrinsic => SCRATCH.with(|scratch| {
            let mut scratch = scratch.borrow_mut();
            let Scratch {
                dist,
                touched,
                heap,
            } = &mut *scratch;
            if dist.len() != domain.len() {
                *dist = vec![f64::INFINITY; domain.len()];
            }
            let graph = domain.graph();
            // Samples closer than this are known and final.
            let mut known_radius = f64::NEG_INFINITY;
            match known {
                Some((entries, r)) => {
                    known_radius = r;
                    // A known sample with a neighbour beyond the known ball is at most
                    // one edge inside its rim.
                    let rim = r - 2.0 * graph.max_edge_length();
                    for &(v, d) in entries {
                        dist[v as usize] = d;
                        touched.push(v);
                        if d >= rim {
                            heap.push(Entry::new(d, 0, v));
                        }
                    }
                    out.extend_from_slice(entries);
                }
                None => {
                    dist[source as usize] = 0.0;
                    touched.push(source);
                    heap.push(Entry::new(0.0, 0, source));
                }
            }
            while let Some(entry) = heap.pop() {
                let (d, v) = (entry.d(), entry.v());
                if d > dist[v as usize] {
                    continue;
                }
                if d >= known_radius && v != source || known.is_none() {
                    out.push((v, d));
                }
                for e in graph.neighbors(v) {
                    let nd = d + f64::from(e.len);
                    let w = e.to as usize;
                    if nd < dist[w] && nd < radius {
                        if dist[w].is_infinite() {
                            touched.push(e.to);
                        }
                        dist[w] = nd;
                        heap.push(Entry::new(nd, 0, e.to));
                    }
                }
            }
            heap.clear();
            for &v in touched.iter() {
                dist[v as usize] = f64::INFINITY;
            }
            touched.clear();
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
    out
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

    /// This field (of the node on `source`) searched on to `radius`.
    pub fn extend(&self, domain: &Domain, source: u32, radius: f64) -> Self {
        if self.radius < 0.0 || self.entries.is_empty() {
            return Self::compute(domain, source, radius);
        }
        Self {
            radius,
            entries: search(domain, source, radius, Some((&self.entries, self.radius))),
        }
    }

    /// How far the field reaches (negative: nothing cached).
    pub fn radius(&self) -> f64 {
        self.radius
    }

    fn covers(&self, radius: f64) -> bool {
        self.radius >= radius
    }

    /// Support entries from the cached field.
    fn support(
        &self,
        basis: &Basis,
        radius: f64,
        partition: &Partition,
        source: u32,
    ) -> Vec<(u32, f32)> {
        self.entries
            .iter()
            .filter_map(|&(v, d)| {
                support_entry(basis, partition, source, v, d as f32, radius).map(|f| (v, f))
            })
            .collect()
    }
}

/// The basis value node `source` gives sample `v` at (rounded) distance `d` with support
/// `radius` (an f32-representable value), or `None`: 1 at its own sample, nothing at any
/// other node's sample (so weights interpolate exactly), φ(d / radius) for d < radius.
/// Every path that makes weights goes through here.
#[inline]
fn support_entry(
    basis: &Basis,
    partition: &Partition,
    source: u32,
    v: u32,
    d: f32,
    radius: f64,
) -> Option<f32> {
    if v == source {
        return Some(1.0);
    }
    let d = f64::from(d);
    if d >= radius || partition.is_node(v) {
        return None;
    }
    let phi = basis.eval(d / radius) as f32;
    (phi > 0.0).then_some(phi)
}

/// The sparse weights of every sample.
#[derive(Clone, Debug, Default)]
pub(crate) struct Weights {
    offsets: Vec<u32>,
    nodes: Vec<u32>,
    phi: Vec<f32>,
    sums: Vec<f64>,
    /// Per node, its cached distance field.
    balls: Vec<Ball>,
    /// Fields of nodes removed since the last update, by sample (Algorithm 1 often puts
    /// a virtual handle back where one was removed), and fields searched ahead of it.
    spare: std::collections::HashMap<u32, Ball>,
    /// Buffers of [`Weights::update`], kept between updates.
    scratch: UpdateBuffers,
}

/// Buffers [`Weights::update`] reuses: allocating them anew each time costs more than
/// filling them (fresh pages are mapped on first touch). A copy of the weights starts
/// without them.
#[derive(Debug, Default)]
struct UpdateBuffers {
    dirty_mark: Vec<bool>,
    fresh_start: Vec<u32>,
    fill: Vec<u32>,
    fresh: Vec<(u32, f32)>,
    /// Row arrays (offsets, nodes, φ) swapped with the current ones at each update.
    back: (Vec<u32>, Vec<u32>, Vec<f32>),
}

impl Clone for UpdateBuffers {
    fn clone(&self) -> Self {
        Self::default()
    }
}

/// A per-node change for [`Weights::update`]: the node, its radius before the change
/// (`None` for a new node) and after.
pub(crate) struct Change {
    pub node: usize,
    pub old_radius: Option<f64>,
}

impl Weights {
    /// Weights from scratch.
    pub fn build(domain: &Domain, partition: &Partition, radii: &[f64], basis: &Basis) -> Self {
        if domain.metric() == Metric::Euclidean {
            return Self::build_euclidean(domain, partition, radii, basis);
        }
        let n = domain.len();
        let balls: Vec<Ball> = (0..partition.len())
            .into_par_iter()
            .map(|k| Ball::compute(domain, partition.node_vertex[k], radii[k]))
            .collect();
        let supports: Vec<Vec<(u32, f32)>> = balls
            .par_iter()
            .enumerate()
            .map(|(k, b)| b.support(basis, radii[k], partition, partition.node_vertex[k]))
            .collect();
        let mut order: Vec<usize> = (0..partition.len()).collect();
        order.sort_unstable_by_key(|&k| partition.node_vertex[k]);
        let mut counts = vec![0u32; n];
        for s in &supports {
            for &(v, _) in s {
                counts[v as usize] += 1;
            }
        }
        let mut offsets = Vec::with_capacity(n + 1);
        let mut acc = 0u32;
        for c in &counts {
            offsets.push(acc);
            acc += c;
        }
        offsets.push(acc);
        let mut nodes = vec![NONE; acc as usize];
        let mut phi = vec![0f32; acc as usize];
        let mut fill: Vec<u32> = offsets[..n].to_vec();
        for &k in &order {
            for &(v, f) in &supports[k] {
                let at = fill[v as usize] as usize;
                nodes[at] = k as u32;
                phi[at] = f;
                fill[v as usize] += 1;
            }
        }
        let mut w = Self {
            offsets,
            nodes,
            phi,
            sums: Vec::new(),
            balls,
            spare: Default::default(),
            scratch: UpdateBuffers::default(),
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
        let grid = domain.vertex_grid();
        let positions = domain.positions();
        // Per cell, the nodes whose support disc meets it (or whose sample is in it), in
        // order of the nodes' samples: nodes visited in that order, bucketed by cell.
        let mut order: Vec<u32> = (0..partition.len() as u32).collect();
        order.sort_unstable_by_key(|&k| partition.node_vertex[k as usize]);
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
        const CHUNK: usize = 16384;
        /// One chunk of rows: lengths, nodes, φ and sums.
        type Rows = (Vec<u32>, Vec<u32>, Vec<f32>, Vec<f64>);
        let parts: Vec<Rows> = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|chunk| {
                let (lo, hi) = (chunk * CHUNK, ((chunk + 1) * CHUNK).min(n));
                let (mut lens, mut nodes, mut phi, mut sums) = (
                    Vec::with_capacity(hi - lo),
                    Vec::new(),
                    Vec::new(),
                    Vec::with_capacity(hi - lo),
                );
                for v in lo..hi {
                    let p = positions[v];
                    let (x, y) = grid.cell_of(p);
                    let c = y * grid.nx + x;
                    let before = nodes.len();
                    let mut sum = 0.0;
                    for &k in &by_cell[cell_start[c] as usize..cell_start[c + 1] as usize] {
                        let source = partition.node_vertex[k as usize];
                        let d = (positions[source as usize] - p).length() as f32;
                        if let Some(f) =
                            support_entry(basis, partition, source, v as u32, d, radii[k as usize])
                        {
                            nodes.push(k);
                            phi.push(f);
                            sum += f64::from(f);
                        }
                    }
                    lens.push((nodes.len() - before) as u32);
                    sums.push(sum);
                }
                (lens, nodes, phi, sums)
            })
            .collect();
        let total: usize = parts.iter().map(|p| p.1.len()).sum();
        let mut w = Self {
            offsets: Vec::with_capacity(n + 1),
            nodes: Vec::with_capacity(total),
            phi: Vec::with_capacity(total),
            sums: Vec::with_capacity(n),
            balls: vec![
                Ball {
                    radius: -1.0,
                    entries: Vec::new()
                };
                partition.len()
            ],
            spare: Default::default(),
            scratch: UpdateBuffers::default(),
        };
        let mut at = 0u32;
        for (lens, nodes, phi, sums) in parts {
            for len in lens {
                w.offsets.push(at);
                at += len;
            }
            w.nodes.extend_from_slice(&nodes);
            w.phi.extend_from_slice(&phi);
            w.sums.extend_from_slice(&sums);
        }
        w.offsets.push(at);
        w
    }

    fn row_sum(&self, v: usize) -> f64 {
        let (a, b) = (self.offsets[v] as usize, self.offsets[v + 1] as usize);
        self.phi[a..b].iter().map(|&f| f64::from(f)).sum()
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
            if self.spare.get(&v).is_none_or(|b| b.radius < field.radius) {
                self.spare.insert(v, field);
            }
        }
    }

    /// Renumbers nodes after a removal: `map[old] = new` (or `NONE` for a removed node);
    /// `old_vertex` are the nodes' samples before it.
    pub fn renumber(&mut self, map: &[u32], old_vertex: &[u32]) {
        self.nodes.par_iter_mut().for_each(|k| {
            if *k != NONE {
                *k = map[*k as usize];
            }
        });
        let balls = std::mem::take(&mut self.balls);
        self.balls = Vec::with_capacity(balls.len());
        for ((ball, &m), &v) in balls.into_iter().zip(map).zip(old_vertex) {
            if m != NONE {
                self.balls.push(ball);
            } else if ball.radius >= 0.0 {
                self.spare.insert(v, ball);
            }
        }
    }

    /// Brings the weights up to date after the nodes in `changes` got new radii (or
    /// appeared), and after nodes were removed (their entries already renumbered to
    /// `NONE`; `dirty` lists the samples they reached). Rows of other samples are kept.
    pub fn update(
        &mut self,
        domain: &Domain,
        partition: &Partition,
        radii: &[f64],
        basis: &Basis,
        changes: &[Change],
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
        /// A changed node, a fresh ball if the cached one was too small, the samples
        /// whose rows it may change, and its new support entries.
        type Reach = (usize, Option<Ball>, Vec<u32>, Vec<(u32, f32)>);
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
                let touched = ball
                    .entries
                    .iter()
                    .filter(|&&(_, d)| f64::from(d as f32) < reach)
                    .map(|&(v, _)| v)
                    .chain(std::iter::once(source))
                    .collect();
                let entries = ball.support(basis, r, partition, source);
                (c.node, fresh, touched, entries)
            })
            .collect();
        let mut changed_node = vec![false; partition.len()];
        for c in changes {
            changed_node[c.node] = true;
        }
        let mut scratch = std::mem::take(&mut self.scratch);
        let UpdateBuffers {
            dirty_mark,
            fresh_start,
            fill,
            fresh,
            back,
        } = &mut scratch;
        // Dirty samples: every sample a changed or removed node reaches or reached.
        dirty_mark.clear();
        dirty_mark.resize(n, false);
        for &v in dirty.iter().chain(results.iter().flat_map(|r| r.2.iter())) {
            dirty_mark[v as usize] = true;
        }
        // The changed nodes' new entries, bucketed by sample (counting sort).
        fresh_start.clear();
        fresh_start.resize(n + 1, 0);
        for (_, _, _, entries) in &results {
            for &(v, _) in entries {
                fresh_start[v as usize + 1] += 1;
            }
        }
        for v in 0..n {
            fresh_start[v + 1] += fresh_start[v];
        }
        fill.clear();
        fill.extend_from_slice(fresh_start);
        fresh.clear();
        fresh.resize(fresh_start[n] as usize, (0, 0.0));
        for (node, _, _, entries) in &results {
            for &(v, f) in entries {
                fresh[fill[v as usize] as usize] = (*node as u32, f);
                fill[v as usize] += 1;
            }
        }
        let (dirty_mark, fresh_start, fresh) = (&*dirty_mark, &*fresh_start, &*fresh);
        // Rebuild the rows in parallel chunks: runs of clean rows are copied in bulk,
        // dirty rows merged from their kept entries and the fresh ones.
        const CHUNK: usize = 8192;
        let this = &*self;
        /// One chunk of rebuilt rows: row starts (relative to the chunk), nodes, φ, and
        /// the new sums of dirty rows.
        type Part = (Vec<u32>, Vec<u32>, Vec<f32>, Vec<(usize, f64)>);
        let parts: Vec<Part> = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let (lo, hi) = (c * CHUNK, ((c + 1) * CHUNK).min(n));
                let (a0, a1) = (this.offsets[lo] as usize, this.offsets[hi] as usize);
                let mut starts = Vec::with_capacity(hi - lo);
                let mut nodes = Vec::with_capacity(a1 - a0 + a1 / 16 - a0 / 16);
                let mut phi = Vec::with_capacity(nodes.capacity());
                let mut sums = Vec::new();
                let mut row: Vec<(u32, f32)> = Vec::new();
                let mut v = lo;
                while v < hi {
                    if !dirty_mark[v] {
                        let run = v;
                        while v < hi && !dirty_mark[v] {
                            v += 1;
                        }
                        let (a, b) = (this.offsets[run], this.offsets[v]);
                        let base = nodes.len() as u32;
                        starts.extend(this.offsets[run..v].iter().map(|&o| o - a + base));
                        nodes.extend_from_slice(&this.nodes[a as usize..b as usize]);
                        phi.extend_from_slice(&this.phi[a as usize..b as usize]);
                        continue;
                    }
                    let (a, b) = (this.offsets[v] as usize, this.offsets[v + 1] as usize);
                    row.clear();
                    row.extend(
                        (a..b)
                            .map(|i| (this.nodes[i], this.phi[i]))
                            .filter(|&(k, _)| k != NONE && !changed_node[k as usize]),
                    );
                    row.extend_from_slice(
                        &fresh[fresh_start[v] as usize..fresh_start[v + 1] as usize],
                    );
                    row.sort_unstable_by_key(|&(k, _)| partition.node_vertex[k as usize]);
                    starts.push(nodes.len() as u32);
                    let mut sum = 0.0;
                    for &(k, f) in &row {
                        nodes.push(k);
                        phi.push(f);
                        sum += f64::from(f);
                    }
                    sums.push((v, sum));
                    v += 1;
                }
                (starts, nodes, phi, sums)
            })
            .collect();
        // Assembled in the back buffers (kept from the last update, so their memory is
        // mapped already), which then swap with the current rows.
        let (offsets, nodes, phi) = back;
        offsets.clear();
        nodes.clear();
        phi.clear();
        for (starts, part_nodes, part_phi, sums) in parts {
            let at = nodes.len() as u32;
            offsets.extend(starts.iter().map(|&s| s + at));
            nodes.extend_from_slice(&part_nodes);
            phi.extend_from_slice(&part_phi);
            for (v, s) in sums {
                self.sums[v] = s;
            }
        }
        offsets.push(nodes.len() as u32);
        std::mem::swap(offsets, &mut self.offsets);
        std::mem::swap(nodes, &mut self.nodes);
        std::mem::swap(phi, &mut self.phi);
        self.scratch = scratch;
        for (node, ball, _, _) in results {
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
        let (a, b) = (self.offsets[v] as usize, self.offsets[v + 1] as usize);
        let s = self.sums[v];
        let fallback = (a == b && owner[v] != NONE).then_some((owner[v] as usize, 1.0));
        (a..b)
            .map(move |i| (self.nodes[i] as usize, f64::from(self.phi[i]) / s))
            .chain(fallback)
    }

    /// Number of stored non-zeros.
    pub fn nonzeros(&self) -> usize {
        self.nodes.len()
    }

    /// Bytes used by the weights.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * 4 + self.phi.len() * 4 + self.offsets.len() * 4 + self.sums.len() * 8
    }

    /// Linear blend of the node transforms at every sample: `out[v] = Σ w_k(v) A_k p_v`.
    pub fn deform(
        &self,
        positions: &[DVec2],
        owner: &[u32],
        affines: &[DAffine2],
        out: &mut [DVec2],
    ) {
        out.par_chunks_mut(8192)
            .enumerate()
            .for_each(|(chunk, out)| {
                let start = chunk * 8192;
                for (i, o) in out.iter_mut().enumerate() {
                    let v = start + i;
                    let p = positions[v];
                    let (a, b) = (self.offsets[v] as usize, self.offsets[v + 1] as usize);
                    if a == b {
                        *o = match owner[v] {
                            NONE => p,
                            k => affines[k as usize].transform_point2(p),
                        };
                        continue;
                    }
                    let mut acc = DVec2::ZERO;
                    for j in a..b {
                        let t = &affines[self.nodes[j] as usize];
                        acc += f64::from(self.phi[j]) * t.transform_point2(p);
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
