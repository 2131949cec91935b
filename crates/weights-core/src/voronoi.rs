//! The graph Voronoi decomposition of the samples by handle (one cell per weighted
//! handle node), kept up to date when nodes are added or removed, and the per-cell
//! radii r_d (farthest sample of the cell) and r_h (nearest other node).
//!
//! With the intrinsic metric each cell also keeps its frontier (its samples with a
//! graph neighbour in another cell, which every boundary edge starts from) and its
//! farthest member, so that a change re-reads a few hundred samples per touched cell.
//!
//! Ties between nodes at equal distance go to the node on the sample of lower rank
//! ([`Domain::rank`]: its index, unless the domain was renumbered), so the partition
//! depends on the set of nodes, not on the order they were added in.

use glam::DVec2;

use crate::domain::{Domain, Metric};
use crate::queue::{Entry, Queue};

thread_local! {
    /// The queue of the partition's searches, kept between them.
    static QUEUE: std::cell::RefCell<Queue> = const { std::cell::RefCell::new(Queue::new()) };
}

/// Runs `f` with this thread's search queue, empty and set up for `domain`'s graph.
fn with_queue<R>(domain: &Domain, f: impl FnOnce(&mut Queue) -> R) -> R {
    QUEUE.with(|q| {
        let mut q = q.borrow_mut();
        let graph = domain.graph();
        q.prepare(graph.min_edge_length(), graph.max_edge_length());
        f(&mut q)
    })
}

/// "No node": an unreachable sample, or a removed node.
pub(crate) const NONE: u32 = u32::MAX;

/// Keeps the items `i` of `list` with `map[i] != NONE`, in order.
fn retain_kept<T>(list: &mut Vec<T>, map: &[u32]) {
    let mut i = 0;
    list.retain(|_| {
        i += 1;
        map[i - 1] != NONE
    });
}

/// Renumbers cell indices after the cells `doomed` (ascending, none of them in
/// `indices`) are removed: an index drops by one for every removed index below it
/// (`map` holds the new index of every old one); `NONE` stays. For a few removed cells,
/// one branch-free (vectorised) pass per removed index, highest first, so that an index
/// already shifted still compares as it did; for many, one pass through `map`.
fn shift_down(indices: &mut [u32], doomed: &[usize], map: &[u32]) {
    const PASSES: usize = 8;
    if doomed.len() > PASSES {
        for x in indices.iter_mut().filter(|x| **x != NONE) {
            *x = map[*x as usize];
        }
        return;
    }
    for &d in doomed.iter().rev() {
        let d = d as u32;
        for x in indices.iter_mut() {
            *x -= u32::from(*x > d && *x != NONE);
        }
    }
}

/// One list of samples per cell, with each listed sample's position in its list, so
/// that a sample moves between lists in constant time. Which list holds a sample is
/// kept by the caller (the owner for members, `frontier_cell` for frontiers).
#[derive(Clone, Debug, Default)]
struct CellLists {
    lists: Vec<Vec<u32>>,
    slot: Vec<u32>,
}

impl CellLists {
    fn new(cells: usize, samples: usize) -> Self {
        Self {
            lists: vec![Vec::new(); cells],
            slot: vec![0; samples],
        }
    }

    fn add_cell(&mut self) {
        self.lists.push(Vec::new());
    }

    fn push(&mut self, cell: u32, v: u32) {
        let list = &mut self.lists[cell as usize];
        self.slot[v as usize] = list.len() as u32;
        list.push(v);
    }

    /// Moves sample `v` from list `from` to list `to` (either may be `NONE`: none).
    fn relocate(&mut self, v: u32, from: u32, to: u32) {
        if from != NONE {
            let list = &mut self.lists[from as usize];
            let at = self.slot[v as usize] as usize;
            list.swap_remove(at);
            if let Some(&moved) = list.get(at) {
                self.slot[moved as usize] = at as u32;
            }
        }
        if to != NONE {
            self.push(to, v);
        }
    }
}

impl std::ops::Index<usize> for CellLists {
    type Output = [u32];

    fn index(&self, cell: usize) -> &[u32] {
        &self.lists[cell]
    }
}

/// Radii of one cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct CellStats {
    /// Distance from the node to the farthest sample of its cell.
    pub r_d: f64,
    /// That farthest sample (`NONE` for an empty cell).
    pub farthest: u32,
    /// Distance to the nearest other node (∞ when no other node is reachable).
    pub r_h: f64,
}

/// A cell's samples with their distances to its node, and its frontier samples: the
/// head start of a search of the node's distance field.
#[derive(Clone, Debug, Default)]
pub(crate) struct CellField {
    pub entries: Vec<(u32, f64)>,
    pub seeds: Vec<u32>,
}

/// The partition of samples into cells, one per node.
#[derive(Clone, Debug)]
pub(crate) struct Partition {
    /// The sample each node sits on; also the node's tie-break key.
    pub node_vertex: Vec<u32>,
    /// Owning node of each sample (`NONE` if unreachable).
    pub owner: Vec<u32>,
    /// Distance from each sample to its owning node.
    pub dist: Vec<f64>,
    /// Samples of each cell (unordered).
    members: CellLists,
    /// Intrinsic metric only: the samples of each cell with a graph neighbour in another
    /// cell. Every boundary edge of a cell starts at one of them, so r_h, the closed-cell
    /// ties and the dual graph need only these (a few hundred of a cell's thousands).
    frontier: CellLists,
    /// The cell whose frontier list holds each sample (`NONE`: none).
    frontier_cell: Vec<u32>,
    /// Intrinsic metric only: the farthest member of each cell and its distance (the
    /// member part of r_d). Adding a node only takes samples from cells and removing
    /// one only gives them, so this is rescanned only when a cell loses it.
    far: Vec<(f64, u32)>,
    /// Euclidean metric only: the largest `dist` in each vertex-grid cell.
    bin_max: Vec<f64>,
    /// Radii of each cell.
    pub stats: Vec<CellStats>,
    /// Scratch: a flag per cell, all clear between calls.
    noted: Vec<bool>,
}

#[inline]
fn less(a: (f64, u32), b: (f64, u32)) -> bool {
    a.0 < b.0 || (a.0 == b.0 && a.1 < b.1)
}

/// Each sample's nearest of the samples `sources` (its index in `sources`) in
/// `domain`'s metric — the cells a C² rig's nodes have, for any set of samples — or
/// `u32::MAX` where none reaches (a piece without sources). A sample listed twice is
/// its first listing's.
pub fn nearest_source(domain: &Domain, sources: Vec<u32>) -> Vec<u32> {
    Partition::distances(domain, sources).owner
}

impl Partition {
    /// The partition of `domain` by nodes on the given samples, built in one pass.
    #[cfg(test)]
    pub fn new(domain: &Domain, node_vertex: Vec<u32>) -> Self {
        let mut p = Self::distances(domain, node_vertex);
        p.decompose(domain);
        p
    }

    /// Nearest-node distances and cells of all samples; radii are left for
    /// [`Partition::decompose`].
    pub fn distances(domain: &Domain, node_vertex: Vec<u32>) -> Self {
        let n = domain.len();
        let mut p = Self {
            node_vertex: Vec::new(),
            owner: vec![NONE; n],
            dist: vec![f64::INFINITY; n],
            members: CellLists::default(),
            frontier: CellLists::default(),
            frontier_cell: Vec::new(),
            far: Vec::new(),
            bin_max: Vec::new(),
            stats: Vec::new(),
            noted: Vec::new(),
        };
        match domain.metric() {
            Metric::Intrinsic => {
                p.node_vertex = node_vertex;
                p.members = CellLists::new(p.node_vertex.len(), n);
                with_queue(domain, |queue| {
                    for (k, &v) in p.node_vertex.iter().enumerate() {
                        let key = domain.rank(v);
                        let entry = Entry::new(0.0, key, v);
                        if less((0.0, key), (p.dist[v as usize], p.key_of(domain, v))) {
                            p.dist[v as usize] = 0.0;
                            p.owner[v as usize] = k as u32;
                            queue.push(entry);
                        }
                    }
                    p.propagate(domain, queue, None, None);
                });
                for v in 0..n {
                    let o = p.owner[v];
                    if o != NONE {
                        p.members.push(o, v as u32);
                    }
                }
                p.build_frontier(domain);
            }
            Metric::Euclidean => p.nearest_euclidean(domain, node_vertex),
        }
        p
    }

    /// Radii r_d and r_h of every cell.
    pub fn decompose(&mut self, domain: &Domain) {
        use rayon::prelude::*;
        if domain.metric() == Metric::Intrinsic {
            let this = &*self;
            self.far = (0..this.node_vertex.len())
                .into_par_iter()
                .map(|k| this.farthest(domain, k))
                .collect();
        }
        let this = &*self;
        self.stats = (0..this.node_vertex.len())
            .into_par_iter()
            .map(|k| this.cell_stats(domain, k))
            .collect();
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.node_vertex.len()
    }

    /// Whether sample `v` carries a node.
    #[cfg(test)]
    pub fn is_node(&self, v: u32) -> bool {
        let o = self.owner[v as usize];
        o != NONE && self.node_vertex[o as usize] == v
    }

    /// The tie-break key of sample `v`'s node: the rank of its sample (`NONE` for
    /// none).
    #[inline]
    fn key_of(&self, domain: &Domain, v: u32) -> u32 {
        let o = self.owner[v as usize];
        if o == NONE {
            NONE
        } else {
            domain.rank(self.node_vertex[o as usize])
        }
    }

    fn set_owner(&mut self, v: u32, k: u32) {
        let old = self.owner[v as usize];
        if old == k {
            return;
        }
        self.members.relocate(v, old, k);
        self.owner[v as usize] = k;
    }

    /// Multi-source Dijkstra from the entries in `queue`, claiming samples for the
    /// popped entry's owner wherever that is lexicographically closer. With `changed`,
    /// member lists are kept current and each sample whose owner changed is recorded
    /// with its previous owner. With `bordering`, each sample settled with a neighbour
    /// in another cell (or in none) at that moment is recorded: with one node
    /// searching, whose cell only grows meanwhile, a settled sample not recorded has
    /// its whole neighbourhood in its cell for good.
    fn propagate(
        &mut self,
        domain: &Domain,
        queue: &mut Queue,
        mut changed: Option<&mut Vec<(u32, u32)>>,
        mut bordering: Option<&mut Vec<u32>>,
    ) {
        let graph = domain.graph();
        while let Some(entry) = queue.pop() {
            let (d, key, v) = (entry.d(), entry.key(), entry.v());
            if d != self.dist[v as usize] || key != self.key_of(domain, v) {
                continue;
            }
            let k = self.owner[v as usize];
            let mut foreign = false;
            for e in graph.neighbors(v) {
                let nd = d + f64::from(e.len);
                let w = e.to as usize;
                let dw = self.dist[w];
                // (The tie-break key is looked up only on a tie.)
                if !(nd < dw || (nd == dw && key < self.key_of(domain, e.to))) {
                    foreign |= bordering.is_some() && self.owner[w] != k;
                    continue;
                }
                self.dist[w] = nd;
                if let Some(changed) = changed.as_deref_mut() {
                    let old = self.owner[w];
                    if old != k {
                        changed.push((e.to, old));
                        self.set_owner(e.to, k);
                    }
                } else {
                    self.owner[w] = k;
                }
                graph.prefetch(e.to);
                queue.push(Entry::new(nd, key, e.to));
            }
            if foreign && let Some(bordering) = bordering.as_deref_mut() {
                bordering.push(v);
            }
        }
    }

    /// Adds a node on sample `v` (which must not carry one) and returns the indices of
    /// the cells whose radii may have changed (the new one included).
    pub fn add_node(&mut self, domain: &Domain, v: u32) -> Vec<usize> {
        match domain.metric() {
            Metric::Intrinsic => self.replace_nodes(domain, &[], &[v]),
            Metric::Euclidean => self.add_node_euclidean(domain, v),
        }
    }

    /// Removes the nodes `doomed` (distinct indices, ascending; the others keep their
    /// order) and appends nodes on the samples `added` (distinct, carrying no node once
    /// the doomed ones are gone), and returns the cells whose radii may have changed,
    /// the new ones included.
    ///
    /// With the intrinsic metric this is one Dijkstra: the freed samples and whatever
    /// the new nodes take are settled together, so a sample a new node takes from a
    /// removed one is visited once, not handed to a neighbour first and taken back.
    pub fn replace_nodes(
        &mut self,
        domain: &Domain,
        doomed: &[usize],
        added: &[u32],
    ) -> Vec<usize> {
        if domain.metric() == Metric::Euclidean {
            let mut touched = if doomed.is_empty() {
                Vec::new()
            } else {
                self.remove_nodes_euclidean(domain, doomed)
            };
            for &v in added {
                touched.extend(self.add_node_euclidean(domain, v));
            }
            touched.sort_unstable();
            touched.dedup();
            return touched;
        }
        // (The freed samples leave the frontier lists with their cells.)
        let freed = self.drop_nodes(doomed);
        let graph = domain.graph();
        let mut seeds = Vec::new();
        // Samples next to the freed ones offer their (unchanged) distances to them.
        for (i, &v) in freed.iter().enumerate() {
            if let Some(&ahead) = freed.get(i + 8) {
                graph.prefetch(ahead);
            }
            for e in graph.neighbors(v) {
                let o = self.owner[e.to as usize];
                if o != NONE {
                    seeds.push(Entry::new(
                        self.dist[e.to as usize],
                        domain.rank(self.node_vertex[o as usize]),
                        e.to,
                    ));
                }
            }
        }
        // Each changed sample with its previous owner.
        let mut changed = Vec::new();
        let first_new = self.node_vertex.len();
        for &v in added {
            let k = self.node_vertex.len() as u32;
            self.node_vertex.push(v);
            self.members.add_cell();
            self.frontier.add_cell();
            self.far.push((0.0, NONE));
            self.stats.push(CellStats {
                r_d: 0.0,
                farthest: NONE,
                r_h: f64::INFINITY,
            });
            let key = domain.rank(v);
            if less((0.0, key), (self.dist[v as usize], self.key_of(domain, v))) {
                changed.push((v, self.owner[v as usize]));
                self.dist[v as usize] = 0.0;
                self.set_owner(v, k);
                seeds.push(Entry::new(0.0, key, v));
            }
        }
        // One node added and none removed (each of Algorithm 1's): only the samples
        // it settled beside another cell need their neighbourhoods read again.
        let mut bordering = (freed.is_empty() && added.len() == 1).then(Vec::new);
        with_queue(domain, |queue| {
            seeds.into_iter().for_each(|e| queue.push(e));
            self.propagate(domain, queue, Some(&mut changed), bordering.as_mut());
        });
        // A surviving cell only gained freed samples and lost samples to the new
        // nodes (a sample that stays keeps its distance): its farthest member is the
        // old one, unless that was taken, or a gained one.
        if !freed.is_empty() {
            for &(v, _) in &changed {
                let o = self.owner[v as usize];
                if o != NONE && (o as usize) < first_new {
                    let (r, f) = self.far[o as usize];
                    let d = self.dist[v as usize];
                    if d > r || (d == r && domain.ranks_before(v, f)) {
                        self.far[o as usize] = (d, v);
                    }
                }
            }
        }
        let mut touched = self.settle(domain, &changed, first_new, bordering.as_deref());
        for &j in &touched {
            let f = self.far[j].1;
            if j < first_new && f != NONE && self.owner[f as usize] != j as u32 {
                self.far[j] = self.farthest(domain, j);
            }
        }
        for k in first_new..self.node_vertex.len() {
            self.far[k] = self.farthest(domain, k);
            touched.push(k);
        }
        self.refresh(domain, touched)
    }

    /// Nearest node of every sample by straight-line distance, all nodes at once: each
    /// vertex-grid cell keeps only the nodes that can be nearest somewhere in it.
    fn nearest_euclidean(&mut self, domain: &Domain, node_vertex: Vec<u32>) {
        use rayon::prelude::*;
        let grid = domain.vertex_grid();
        let positions = domain.positions();
        let node_pos: Vec<DVec2> = node_vertex.iter().map(|&v| positions[v as usize]).collect();
        let cells = grid.cell_count();
        // Candidates per cell: nodes whose nearest point of the cell is no farther than
        // the best farthest point (any node farther than that loses everywhere in it).
        let candidates: Vec<Vec<u32>> = (0..cells)
            .into_par_iter()
            .map(|c| {
                if grid.items_of_cell(c).is_empty() {
                    return Vec::new();
                }
                let bound = node_pos
                    .iter()
                    .map(|&q| grid.cell_far_distance_squared(c, q))
                    .fold(f64::INFINITY, f64::min);
                (0..node_pos.len() as u32)
                    .filter(|&k| grid.cell_distance_squared(c, node_pos[k as usize]) <= bound)
                    .collect()
            })
            .collect();
        let n = positions.len();
        let nearest: Vec<(f64, u32)> = (0..n)
            .into_par_iter()
            .map(|v| {
                let p = positions[v];
                let (x, y) = grid.cell_of(p);
                let mut best = (f64::INFINITY, NONE, NONE);
                for &k in &candidates[y * grid.nx + x] {
                    let d = (node_pos[k as usize] - p).length();
                    let key = domain.rank(node_vertex[k as usize]);
                    if less((d, key), (best.0, best.1)) {
                        best = (d, key, k);
                    }
                }
                (best.0, best.2)
            })
            .collect();
        self.members = CellLists::new(node_vertex.len(), n);
        for (v, &(d, k)) in nearest.iter().enumerate() {
            self.dist[v] = d;
            self.owner[v] = k;
            if k != NONE {
                self.members.push(k, v as u32);
            }
        }
        self.node_vertex = node_vertex;
        self.bin_max = (0..cells)
            .into_par_iter()
            .map(|c| {
                grid.items_of_cell(c)
                    .iter()
                    .map(|&w| self.dist[w as usize])
                    .fold(0.0, f64::max)
            })
            .collect();
    }

    /// Adds a node by straight-line distance and returns the cells whose radii may have
    /// changed (the new one included).
    fn add_node_euclidean(&mut self, domain: &Domain, v: u32) -> Vec<usize> {
        let mut touched = self.claim_euclidean(domain, v);
        let k = self.node_vertex.len() - 1;
        touched.push(k);
        self.stats.push(CellStats {
            r_d: 0.0,
            farthest: NONE,
            r_h: f64::INFINITY,
        });
        // Exact shortcuts. A cell that lost samples keeps its r_d unless its farthest
        // sample was taken (then it is rescanned); r_h can only drop, to the distance
        // from the new node (a minimum over one more element).
        self.stats[k] = self.cell_stats(domain, k);
        let p = domain.positions()[v as usize];
        for j in 0..k {
            let d = (domain.positions()[self.node_vertex[j] as usize] - p).length();
            if d < self.stats[j].r_h {
                self.stats[j].r_h = d;
                touched.push(j);
            }
        }
        touched.sort_unstable();
        touched.dedup();
        for &j in &touched {
            let s = self.stats[j];
            if j != k && s.farthest != NONE && self.owner[s.farthest as usize] != j as u32 {
                let (r_d, farthest) = self.farthest(domain, j);
                self.stats[j].r_d = r_d;
                self.stats[j].farthest = farthest;
            }
        }
        touched
    }

    /// Appends a node on sample `v` and gives it the samples closer to it than to their
    /// node; returns the cells that lost samples. Floods the vertex-grid cells from the
    /// node's own, entering a cell only if it may hold a sample closer to the new node
    /// than to its current one. The new cell is convex and distance to the old nodes is
    /// 1-Lipschitz, so every cell the new cell meets passes the test
    /// `box distance < largest distance in the cell + cell diagonal`, and those cells are
    /// connected.
    fn claim_euclidean(&mut self, domain: &Domain, v: u32) -> Vec<usize> {
        let k = self.node_vertex.len() as u32;
        self.node_vertex.push(v);
        self.members.add_cell();
        let grid = domain.vertex_grid();
        let p = domain.positions()[v as usize];
        let diagonal = grid.cell_size() * std::f64::consts::SQRT_2;
        let mut touched = Vec::new();
        let mut seen = vec![false; grid.cell_count()];
        let (sx, sy) = grid.cell_of(p);
        let mut stack = vec![sy * grid.nx + sx];
        seen[sy * grid.nx + sx] = true;
        while let Some(c) = stack.pop() {
            let items = grid.items_of_cell(c);
            let near = grid.cell_distance_squared(c, p).sqrt();
            if !items.is_empty() && near >= self.bin_max[c] + diagonal {
                continue;
            }
            let (cx, cy) = (c % grid.nx, c / grid.nx);
            for (dx, dy) in [
                (-1i64, -1i64),
                (0, -1),
                (1, -1),
                (-1, 0),
                (1, 0),
                (-1, 1),
                (0, 1),
                (1, 1),
            ] {
                let (x, y) = (cx as i64 + dx, cy as i64 + dy);
                if x >= 0 && y >= 0 && (x as usize) < grid.nx && (y as usize) < grid.ny {
                    let n = y as usize * grid.nx + x as usize;
                    if !seen[n] {
                        seen[n] = true;
                        stack.push(n);
                    }
                }
            }
            if items.is_empty() || near >= self.bin_max[c] {
                continue;
            }
            let mut max = 0.0f64;
            let positions = domain.positions();
            for &w in grid.items_of_cell(c) {
                let d = (positions[w as usize] - p).length();
                let wi = w as usize;
                let dw = self.dist[wi];
                // (The tie-break key is looked up only on a tie.)
                if d < dw || (d == dw && domain.rank(v) < self.key_of(domain, w)) {
                    let old = self.owner[wi];
                    if old != NONE && touched.last() != Some(&(old as usize)) {
                        touched.push(old as usize);
                    }
                    self.dist[wi] = d;
                    self.set_owner(w, k);
                }
                max = max.max(self.dist[wi]);
            }
            self.bin_max[c] = max;
        }
        touched
    }

    /// Removes node `k` (later nodes shift down by one), hands its samples to the
    /// remaining nodes, and returns the cells whose radii may have changed.
    #[cfg(test)]
    pub fn remove_node(&mut self, domain: &Domain, k: usize) -> Vec<usize> {
        self.remove_nodes(domain, &[k])
    }

    /// Removes the nodes `doomed` (distinct indices, ascending; the others keep their
    /// order), hands their samples to the remaining nodes in one pass, and returns the
    /// cells whose radii may have changed.
    #[cfg(test)]
    pub fn remove_nodes(&mut self, domain: &Domain, doomed: &[usize]) -> Vec<usize> {
        match domain.metric() {
            Metric::Intrinsic => self.replace_nodes(domain, doomed, &[]),
            Metric::Euclidean => self.remove_nodes_euclidean(domain, doomed),
        }
    }

    /// Takes the nodes `doomed` out of the node list (renumbering the rest) and returns
    /// their samples, now owned by no node.
    fn drop_nodes(&mut self, doomed: &[usize]) -> Vec<u32> {
        let mut freed = Vec::new();
        if doomed.is_empty() {
            return freed;
        }
        let mut map = vec![0u32; self.node_vertex.len()];
        for &k in doomed {
            map[k] = NONE;
        }
        for (next, m) in map.iter_mut().filter(|m| **m != NONE).enumerate() {
            *m = next as u32;
        }
        for &k in doomed {
            freed.append(&mut self.members.lists[k]);
        }
        // (Frontiers are kept with the intrinsic metric only.)
        let intrinsic = !self.frontier_cell.is_empty();
        for &v in &freed {
            self.owner[v as usize] = NONE;
            self.dist[v as usize] = f64::INFINITY;
            if intrinsic {
                // (A cell's frontier samples are among its members.)
                self.frontier_cell[v as usize] = NONE;
            }
        }
        retain_kept(&mut self.members.lists, &map);
        retain_kept(&mut self.node_vertex, &map);
        retain_kept(&mut self.stats, &map);
        shift_down(&mut self.owner, doomed, &map);
        if intrinsic {
            retain_kept(&mut self.frontier.lists, &map);
            retain_kept(&mut self.far, &map);
            shift_down(&mut self.frontier_cell, doomed, &map);
        }
        freed
    }

    /// Removes the nodes `doomed` by straight-line distance (see
    /// [`Partition::replace_nodes`]).
    fn remove_nodes_euclidean(&mut self, domain: &Domain, doomed: &[usize]) -> Vec<usize> {
        let freed = self.drop_nodes(doomed);
        let mut touched = Vec::new();
        let positions = domain.positions();
        for &v in &freed {
            let p = positions[v as usize];
            let mut best = (f64::INFINITY, NONE, NONE);
            for (j, &nv) in self.node_vertex.iter().enumerate() {
                let d = (positions[nv as usize] - p).length();
                let key = domain.rank(nv);
                if less((d, key), (best.0, best.1)) {
                    best = (d, key, j as u32);
                }
            }
            self.dist[v as usize] = best.0;
            self.set_owner(v, best.2);
            if best.2 != NONE {
                touched.push(best.2 as usize);
            }
        }
        let grid = domain.vertex_grid();
        let mut cells: Vec<usize> = freed
            .iter()
            .map(|&v| {
                let (x, y) = grid.cell_of(positions[v as usize]);
                y * grid.nx + x
            })
            .collect();
        cells.sort_unstable();
        cells.dedup();
        for c in cells {
            self.bin_max[c] = grid
                .items_of_cell(c)
                .iter()
                .map(|&w| self.dist[w as usize])
                .fold(0.0, f64::max);
        }
        // Any node may have had the removed one as its nearest.
        touched.extend(0..self.node_vertex.len());
        self.refresh(domain, touched)
    }

    /// Whether sample `v` belongs to a cell and has a graph neighbour in another one.
    fn on_frontier(&self, graph: &crate::domain::Graph, v: u32) -> bool {
        let o = self.owner[v as usize];
        o != NONE
            && graph.neighbors(v).iter().any(|e| {
                let w = self.owner[e.to as usize];
                w != o && w != NONE
            })
    }

    /// The frontier lists of every cell, from scratch.
    fn build_frontier(&mut self, domain: &Domain) {
        use rayon::prelude::*;
        let graph = domain.graph();
        let n = self.owner.len();
        let flags: Vec<bool> = (0..n as u32)
            .into_par_iter()
            .map(|v| self.on_frontier(graph, v))
            .collect();
        self.frontier = CellLists::new(self.node_vertex.len(), n);
        self.frontier_cell = vec![NONE; n];
        for (v, _) in flags.iter().enumerate().filter(|(_, f)| **f) {
            let o = self.owner[v];
            self.frontier_cell[v] = o;
            self.frontier.push(o, v as u32);
        }
    }

    /// After the samples in `changed` changed owner (each listed with its previous
    /// owner, all moves done): brings the frontier lists up to date and returns the
    /// cells whose radii may have changed, each once — the owners before and after of
    /// the changed samples and the owners of their neighbours.
    ///
    /// With `bordering` (one node added, see [`Partition::propagate`]), the changed
    /// samples not in it have every neighbour in their own cell: off every frontier,
    /// and nothing else to see.
    ///
    /// Only the changed samples and their neighbours can enter or leave a frontier. A
    /// changed sample is checked in full; a neighbour in another cell is on a frontier
    /// now; a neighbour in the same cell may have lost its only foreign neighbour, which
    /// matters only if it is on a frontier list, and not at all in cells from `fresh`
    /// on (new cells, whose samples all changed and are checked in full).
    fn settle(
        &mut self,
        domain: &Domain,
        changed: &[(u32, u32)],
        fresh: usize,
        bordering: Option<&[u32]>,
    ) -> Vec<usize> {
        let graph = domain.graph();
        // A flag per cell, kept between calls and cleared after: a fresh one each time
        // would cost a pass over every cell for each new node (quadratic where Algorithm
        // 1 turns nearly every sample into a node).
        let mut seen = std::mem::take(&mut self.noted);
        seen.resize(self.node_vertex.len(), false);
        let mut cells = Vec::new();
        let mut note = |o: u32| {
            if o != NONE && !seen[o as usize] {
                seen[o as usize] = true;
                cells.push(o as usize);
            }
        };
        /// How far ahead of a visit the edges are fetched.
        const AHEAD: usize = 8;
        match bordering {
            None => {
                for (i, &(v, old)) in changed.iter().enumerate() {
                    if let Some(&(ahead, _)) = changed.get(i + AHEAD) {
                        graph.prefetch(ahead);
                    }
                    note(old);
                    self.settle_sample(graph, v, fresh, &mut note);
                }
            }
            Some(bordering) => {
                for &(v, old) in changed {
                    note(old);
                    note(self.owner[v as usize]);
                    self.set_frontier(v, NONE);
                }
                for (i, &v) in bordering.iter().enumerate() {
                    if let Some(&ahead) = bordering.get(i + AHEAD) {
                        graph.prefetch(ahead);
                    }
                    self.settle_sample(graph, v, fresh, &mut note);
                }
            }
        }
        for &c in &cells {
            seen[c] = false;
        }
        self.noted = seen;
        cells
    }

    /// [`Partition::settle`] for one changed sample `v`: notes its cell and its
    /// neighbours' (`note`), and puts it and its neighbours on the frontiers they now
    /// belong to.
    fn settle_sample(
        &mut self,
        graph: &crate::domain::Graph,
        v: u32,
        fresh: usize,
        note: &mut impl FnMut(u32),
    ) {
        let o = self.owner[v as usize];
        note(o);
        let mut front = false;
        for e in graph.neighbors(v) {
            let ow = self.owner[e.to as usize];
            if ow == o {
                // (Its cell is noted already.)
                if o != NONE
                    && (o as usize) < fresh
                    && self.frontier_cell[e.to as usize] != NONE
                    && !self.on_frontier(graph, e.to)
                {
                    self.set_frontier(e.to, NONE);
                }
                continue;
            }
            note(ow);
            if ow == NONE || o == NONE {
                continue;
            }
            front = true;
            if self.frontier_cell[e.to as usize] != ow {
                self.set_frontier(e.to, ow);
            }
        }
        self.set_frontier(v, if front { o } else { NONE });
    }

    /// Puts sample `v` on the frontier list of cell `cell` (`NONE`: on none).
    fn set_frontier(&mut self, v: u32, cell: u32) {
        let current = self.frontier_cell[v as usize];
        if current == cell {
            return;
        }
        self.frontier.relocate(v, current, cell);
        self.frontier_cell[v as usize] = cell;
    }

    /// The frontier samples of cell `k` (intrinsic metric): its samples with a graph
    /// neighbour in another cell.
    pub fn frontier(&self, k: usize) -> &[u32] {
        &self.frontier[k]
    }

    /// Recomputes the radii of the given cells and returns them, deduplicated.
    fn refresh(&mut self, domain: &Domain, mut cells: Vec<usize>) -> Vec<usize> {
        cells.sort_unstable();
        cells.dedup();
        cells.retain(|&c| c < self.node_vertex.len());
        for &c in &cells {
            self.stats[c] = self.cell_stats(domain, c);
        }
        cells
    }

    /// r_d and the farthest sample of cell `k` (ties to the lower rank).
    fn farthest(&self, domain: &Domain, k: usize) -> (f64, u32) {
        let mut r_d = 0.0;
        let mut farthest = NONE;
        for &v in &self.members[k] {
            let d = self.dist[v as usize];
            if d > r_d || (d == r_d && domain.ranks_before(v, farthest)) {
                r_d = d;
                farthest = v;
            }
        }
        (r_d, farthest)
    }

    /// r_d, the farthest sample and r_h of cell `k` (from the kept farthest member with
    /// the intrinsic metric, else from scratch).
    ///
    /// With the intrinsic metric, a sample of a neighbouring cell that this node reaches
    /// at exactly its distance (a tie the tie-break gave away) counts toward r_d too:
    /// cells are closed, so mirror-image nodes get mirror-image radii.
    fn cell_stats(&self, domain: &Domain, k: usize) -> CellStats {
        let (mut r_d, mut farthest) = match domain.metric() {
            Metric::Intrinsic => self.far[k],
            Metric::Euclidean => self.farthest(domain, k),
        };
        let r_h = match domain.metric() {
            Metric::Intrinsic => {
                let graph = domain.graph();
                let k32 = k as u32;
                let mut best = f64::INFINITY;
                for &u in &self.frontier[k] {
                    let du = self.dist[u as usize];
                    for e in graph.neighbors(u) {
                        let o = self.owner[e.to as usize];
                        if o != k32 && o != NONE {
                            let dw = self.dist[e.to as usize];
                            let reach = du + f64::from(e.len);
                            best = best.min(reach + dw);
                            if reach == dw
                                && (dw > r_d || (dw == r_d && domain.ranks_before(e.to, farthest)))
                            {
                                r_d = dw;
                                farthest = e.to;
                            }
                        }
                    }
                }
                best
            }
            Metric::Euclidean => {
                let positions = domain.positions();
                let p: DVec2 = positions[self.node_vertex[k] as usize];
                self.node_vertex
                    .iter()
                    .enumerate()
                    .filter(|&(j, _)| j != k)
                    .map(|(_, &v)| (positions[v as usize] - p).length())
                    .fold(f64::INFINITY, f64::min)
            }
        };
        CellStats { r_d, farthest, r_h }
    }

    /// Every sample of the closed cell `k` at distance exactly r_d (its farthest samples,
    /// ties included), lowest rank first.
    pub fn farthest_samples(&self, domain: &Domain, k: usize) -> Vec<u32> {
        let r_d = self.stats[k].r_d;
        let mut out: Vec<u32> = self.members[k]
            .iter()
            .copied()
            .filter(|&v| self.dist[v as usize] == r_d)
            .collect();
        if domain.metric() == Metric::Intrinsic {
            let graph = domain.graph();
            for &u in &self.frontier[k] {
                let du = self.dist[u as usize];
                for e in graph.neighbors(u) {
                    let (o, dw) = (self.owner[e.to as usize], self.dist[e.to as usize]);
                    if o != k as u32 && o != NONE && dw == r_d && du + f64::from(e.len) == dw {
                        out.push(e.to);
                    }
                }
            }
        }
        out.sort_unstable_by_key(|&v| domain.rank(v));
        out.dedup();
        out
    }

    /// The samples of cell `k` with their distances (each a complete shortest-path
    /// distance from the cell's node: every sample on a shortest path to a member is
    /// a member), and the cell's frontier, from which a search from the node goes on
    /// beyond the cell (see `weights::Known::Cell`). `None` with straight-line
    /// distances, whose searches need no head start.
    pub fn cell_field(&self, domain: &Domain, k: usize) -> Option<CellField> {
        if domain.metric() != Metric::Intrinsic {
            return None;
        }
        Some(CellField {
            entries: self.members[k]
                .iter()
                .map(|&v| (v, self.dist[v as usize]))
                .collect(),
            seeds: self.frontier[k].to_vec(),
        })
    }

    /// Samples no node reaches (other components of the graph), lowest rank first.
    pub fn unreached(&self, domain: &Domain) -> Vec<u32> {
        // (Counted first: every sample is reached, nearly always.)
        let reached: usize = self.members.lists.iter().map(Vec::len).sum();
        if reached == self.owner.len() {
            return Vec::new();
        }
        let mut out: Vec<u32> = (0..self.owner.len() as u32)
            .filter(|&v| self.owner[v as usize] == NONE)
            .collect();
        out.sort_unstable_by_key(|&v| domain.rank(v));
        out
    }

    /// Checks the partition against a rebuild from scratch; for tests.
    #[cfg(test)]
    pub fn assert_matches_rebuild(&self, domain: &Domain) {
        let fresh = Partition::new(domain, self.node_vertex.clone());
        assert_eq!(self.owner, fresh.owner, "owners differ from a rebuild");
        assert_eq!(self.dist, fresh.dist, "distances differ from a rebuild");
        assert_eq!(self.stats, fresh.stats, "cell radii differ from a rebuild");
        for k in 0..self.len() {
            let mut a = self.members[k].to_vec();
            let mut b = fresh.members[k].to_vec();
            a.sort_unstable();
            b.sort_unstable();
            assert_eq!(a, b);
        }
        if domain.metric() == Metric::Intrinsic {
            for k in 0..self.len() {
                let mut a = self.frontier[k].to_vec();
                let mut b = fresh.frontier[k].to_vec();
                a.sort_unstable();
                b.sort_unstable();
                assert_eq!(a, b, "frontier of cell {k}");
                for (i, &v) in self.frontier[k].iter().enumerate() {
                    assert_eq!(self.frontier_cell[v as usize], k as u32);
                    assert_eq!(self.frontier.slot[v as usize], i as u32);
                }
            }
            assert_eq!(self.frontier_cell, fresh.frontier_cell);
            assert_eq!(
                self.far, fresh.far,
                "farthest members differ from a rebuild"
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::domain::tests::grid_mesh;
    use std::collections::BinaryHeap;

    fn jittered(nx: usize, ny: usize, seed: u64, metric: Metric) -> Domain {
        let (mut p, t) = grid_mesh(nx, ny, 1.0);
        let mut s = seed;
        for q in p.iter_mut() {
            if q.x > 0.0 && q.y > 0.0 && q.x < nx as f64 && q.y < ny as f64 {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let a = ((s >> 33) as f64 / (1u64 << 31) as f64 - 0.5) * 0.3;
                let b = ((s >> 13 & 0xfffff) as f64 / (1u64 << 20) as f64 - 0.5) * 0.3;
                *q += DVec2::new(a, b);
            }
        }
        Domain::new(p, t, metric).expect("valid")
    }

    #[test]
    fn removing_cells_renumbers_the_rest() {
        // Both ways of renumbering (a pass per removed cell, and a table for many).
        for doomed in [vec![1usize, 4], (0..40).filter(|k| k % 3 == 0).collect()] {
            let cells = 60u32;
            let mut map = vec![0u32; cells as usize];
            let mut next = 0;
            for (k, m) in map.iter_mut().enumerate() {
                if doomed.contains(&k) {
                    *m = NONE;
                } else {
                    *m = next;
                    next += 1;
                }
            }
            let kept: Vec<u32> = (0..cells).filter(|&k| map[k as usize] != NONE).collect();
            let mut indices: Vec<u32> = kept.iter().rev().copied().chain([NONE]).collect();
            shift_down(&mut indices, &doomed, &map);
            let expected: Vec<u32> = (0..kept.len() as u32).rev().chain([NONE]).collect();
            assert_eq!(indices, expected, "{} removed", doomed.len());
        }
    }

    #[test]
    fn incremental_add_and_remove_match_rebuilds() {
        for metric in [Metric::Intrinsic, Metric::Euclidean] {
            let d = jittered(30, 20, 7, metric);
            let mut p = Partition::new(&d, vec![5, 300, 77]);
            p.assert_matches_rebuild(&d);
            for v in [400u32, 123, 601, 2] {
                p.add_node(&d, v);
                p.assert_matches_rebuild(&d);
            }
            p.remove_node(&d, 1);
            p.assert_matches_rebuild(&d);
            p.remove_node(&d, 3);
            p.assert_matches_rebuild(&d);
            // Several at once, adjacent cells among them.
            p.add_node(&d, 401);
            p.add_node(&d, 3);
            p.remove_nodes(&d, &[0, 2, 5, 6]);
            p.assert_matches_rebuild(&d);
            // Removed and added in one pass: a new node on a removed node's sample,
            // one elsewhere in a removed cell, one in a surviving cell.
            let (a, b) = (p.node_vertex[0], p.node_vertex[1]);
            let inside = p.members[1]
                .iter()
                .copied()
                .find(|&v| v != b)
                .expect("a member");
            let elsewhere = p.members[2]
                .iter()
                .copied()
                .find(|&v| !p.is_node(v))
                .expect("one");
            p.replace_nodes(&d, &[0, 1], &[a, inside, elsewhere]);
            p.assert_matches_rebuild(&d);
        }
    }

    #[test]
    fn nodes_added_one_by_one_keep_the_frontiers_of_a_rebuild() {
        // Each single addition settles only the samples it claimed beside another
        // cell; the frontier lists must still be every cell's.
        for metric in [Metric::Intrinsic, Metric::Euclidean] {
            let d = jittered(30, 20, 11, metric);
            let mut p = Partition::new(&d, vec![0]);
            for i in 1..40 {
                let v = (i * 7919 + 13) % d.len() as u32;
                if !p.is_node(v) {
                    p.add_node(&d, v);
                    p.assert_matches_rebuild(&d);
                }
            }
            assert!(p.len() > 30);
        }
    }

    #[test]
    fn the_farthest_member_of_a_cell_breaks_ties_by_sample() {
        // One node in the middle of a regular grid: with straight-line distance the four
        // corners tie, and the first in sample order is the farthest member.
        let (p, t) = grid_mesh(250, 200, 1.0);
        for metric in [Metric::Euclidean, Metric::Intrinsic] {
            let d = Domain::new(p.clone(), t.clone(), metric).expect("valid");
            let part = Partition::new(&d, vec![100 * 251 + 125]);
            let mut expected = (0.0, NONE);
            for (v, &dv) in part.dist.iter().enumerate() {
                if dv > expected.0 {
                    expected = (dv, v as u32);
                }
            }
            assert_eq!(part.farthest(&d, 0), expected, "{metric:?}");
            // Given in reverse (the top-right corner first) and renumbered along the
            // curve (which starts at the bottom left), the tie still goes to the corner
            // first in the given numbering.
            let last = p.len() as u32 - 1;
            let reversed: Vec<DVec2> = p.iter().rev().copied().collect();
            let flipped: Vec<[u32; 3]> = t.iter().map(|t| t.map(|v| last - v)).collect();
            let (r, renumber) = Domain::in_local_order(reversed, flipped, metric).expect("valid");
            let part = Partition::new(&r, vec![renumber[(last - (100 * 251 + 125)) as usize]]);
            let (far, v) = part.farthest(&r, 0);
            assert_eq!(far, expected.0, "{metric:?}");
            assert_eq!(r.positions()[v as usize], p[last as usize], "{metric:?}");
        }
    }

    #[test]
    fn intrinsic_r_h_is_the_graph_distance_between_nodes() {
        let d = jittered(12, 9, 3, Metric::Intrinsic);
        let p = Partition::new(&d, vec![0, 50, 100]);
        // Plain single-source Dijkstra from node 0.
        let mut dist = vec![f64::INFINITY; d.len()];
        let mut heap = BinaryHeap::new();
        dist[0] = 0.0;
        heap.push(Entry::new(0.0, 0, 0));
        while let Some(entry) = heap.pop() {
            let (du, v) = (entry.d(), entry.v());
            if du > dist[v as usize] {
                continue;
            }
            for e in d.graph().neighbors(v) {
                let nd = du + f64::from(e.len);
                if nd < dist[e.to as usize] {
                    dist[e.to as usize] = nd;
                    heap.push(Entry::new(nd, 0, e.to));
                }
            }
        }
        let expected = dist[50].min(dist[100]);
        assert!((p.stats[0].r_h - expected).abs() < 1e-9);
    }
}
