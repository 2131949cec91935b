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

/// Reusable per-thread buffers for bounded Dijkstra searches.
pub(crate) struct Scratch {
    dist: Vec<f64>,
    touched: Vec<u32>,
    heap: BinaryHeap<Entry>,
}

impl Scratch {
    pub fn new(n: usize) -> Self {
        Self {
            dist: vec![f64::INFINITY; n],
            touched: Vec::new(),
            heap: BinaryHeap::new(),
        }
    }
}

/// The samples within `radius` of node sample `source` (and the source itself), with
/// their distances, in order of distance; and `cut`, the distance of the nearest other
/// node sample (∞ if none is within `radius`).
pub(crate) fn ball(
    domain: &Domain,
    partition: &Partition,
    source: u32,
    radius: f64,
    scratch: &mut Scratch,
) -> (Vec<(u32, f64)>, f64) {
    let mut out = Vec::new();
    let mut cut = f64::INFINITY;
    match domain.metric() {
        Metric::Intrinsic => {
            let graph = domain.graph();
            let Scratch {
                dist,
                touched,
                heap,
            } = scratch;
            dist[source as usize] = 0.0;
            touched.push(source);
            heap.push(Entry {
                d: 0.0,
                key: 0,
                v: source,
            });
            while let Some(Entry { d, v, .. }) = heap.pop() {
                if d > dist[v as usize] {
                    continue;
                }
                if d >= radius && v != source {
                    break;
                }
                if v != source && cut.is_infinite() && partition.is_node(v) {
                    cut = d;
                }
                out.push((v, d));
                for e in graph.neighbors(v) {
                    let nd = d + f64::from(e.len);
                    let w = e.to as usize;
                    if nd < dist[w] && nd < radius {
                        if dist[w].is_infinite() {
                            touched.push(e.to);
                        }
                        dist[w] = nd;
                        heap.push(Entry {
                            d: nd,
                            key: 0,
                            v: e.to,
                        });
                    }
                }
            }
            heap.clear();
            for &v in touched.iter() {
                dist[v as usize] = f64::INFINITY;
            }
            touched.clear();
        }
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
    (out, cut)
}

/// Support entries of one node: samples strictly closer than both `radius` and `cut`
/// (and the node's own sample), with φ(d / radius) as f32, zeros dropped.
fn support(basis: &Basis, ball: &[(u32, f64)], radius: f64, cut: f64) -> Vec<(u32, f32)> {
    let limit = radius.min(cut);
    ball.iter()
        .filter(|&&(_, d)| d == 0.0 || d < limit)
        .filter_map(|&(v, d)| {
            let phi = if d == 0.0 {
                1.0
            } else {
                basis.eval(d / radius) as f32
            };
            (phi > 0.0).then_some((v, phi))
        })
        .collect()
}

/// The sparse weights of every sample.
#[derive(Clone, Debug, Default)]
pub(crate) struct Weights {
    offsets: Vec<u32>,
    nodes: Vec<u32>,
    phi: Vec<f32>,
    sums: Vec<f64>,
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
        let n = domain.len();
        let supports: Vec<Vec<(u32, f32)>> = (0..partition.len())
            .into_par_iter()
            .map_init(
                || {
                    Scratch::new(if domain.metric() == Metric::Intrinsic {
                        n
                    } else {
                        0
                    })
                },
                |scratch, k| {
                    let r = radii[k];
                    let (ball, cut) = ball(domain, partition, partition.node_vertex[k], r, scratch);
                    support(basis, &ball, r, cut)
                },
            )
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
        };
        w.sums = (0..n).map(|v| w.row_sum(v)).collect();
        w
    }

    fn row_sum(&self, v: usize) -> f64 {
        let (a, b) = (self.offsets[v] as usize, self.offsets[v + 1] as usize);
        self.phi[a..b].iter().map(|&f| f64::from(f)).sum()
    }

    /// Renumbers nodes after a removal: `map[old] = new` (or `NONE` for a removed node).
    pub fn renumber(&mut self, map: &[u32]) {
        self.nodes.par_iter_mut().for_each(|k| {
            if *k != NONE {
                *k = map[*k as usize];
            }
        });
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
        /// A changed node, the samples it reaches and its new support entries.
        type Reach = (usize, Vec<(u32, f64)>, Vec<(u32, f32)>);
        let results: Vec<Reach> = changes
            .par_iter()
            .map_init(
                || {
                    Scratch::new(if domain.metric() == Metric::Intrinsic {
                        n
                    } else {
                        0
                    })
                },
                |scratch, c| {
                    let r = radii[c.node];
                    let reach = c.old_radius.map_or(r, |o| o.max(r));
                    let (ball, cut) = ball(
                        domain,
                        partition,
                        partition.node_vertex[c.node],
                        reach,
                        scratch,
                    );
                    let entries = support(basis, &ball, r, cut);
                    (c.node, ball, entries)
                },
            )
            .collect();
        let mut changed_node = vec![false; partition.len()];
        for c in changes {
            changed_node[c.node] = true;
        }
        // Dirty samples and their new entries from changed nodes.
        let mut slot = vec![u32::MAX; n];
        let mut fresh: Vec<Vec<(u32, f32)>> = Vec::new();
        let mark = |v: u32, slot: &mut Vec<u32>, fresh: &mut Vec<Vec<(u32, f32)>>| {
            if slot[v as usize] == u32::MAX {
                slot[v as usize] = fresh.len() as u32;
                fresh.push(Vec::new());
            }
            slot[v as usize] as usize
        };
        for &v in dirty {
            mark(v, &mut slot, &mut fresh);
        }
        for (node, ball, entries) in &results {
            for &(v, _) in ball {
                mark(v, &mut slot, &mut fresh);
            }
            for &(v, f) in entries {
                let s = mark(v, &mut slot, &mut fresh);
                fresh[s].push((*node as u32, f));
            }
        }
        // Rebuild the rows: copy clean rows, merge dirty ones.
        let mut offsets = Vec::with_capacity(n + 1);
        let mut nodes = Vec::with_capacity(self.nodes.len() + self.nodes.len() / 8);
        let mut phi = Vec::with_capacity(nodes.capacity());
        let mut row: Vec<(u32, f32)> = Vec::new();
        for (v, &s) in slot.iter().enumerate() {
            offsets.push(nodes.len() as u32);
            let (a, b) = (self.offsets[v] as usize, self.offsets[v + 1] as usize);
            if s == u32::MAX {
                nodes.extend_from_slice(&self.nodes[a..b]);
                phi.extend_from_slice(&self.phi[a..b]);
                continue;
            }
            row.clear();
            // Entries of changed and removed nodes are replaced by the fresh ones.
            row.extend(
                (a..b)
                    .map(|i| (self.nodes[i], self.phi[i]))
                    .filter(|&(k, _)| k != NONE && !changed_node[k as usize]),
            );
            row.extend_from_slice(&fresh[s as usize]);
            row.sort_unstable_by_key(|&(k, _)| partition.node_vertex[k as usize]);
            for &(k, f) in &row {
                nodes.push(k);
                phi.push(f);
            }
        }
        offsets.push(nodes.len() as u32);
        self.offsets = offsets;
        self.nodes = nodes;
        self.phi = phi;
        for (v, &s) in slot.iter().enumerate() {
            if s != u32::MAX {
                self.sums[v] = self.row_sum(v);
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
