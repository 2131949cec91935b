//! The rig: handles on a domain, their weighted nodes (points, bar samples, pinned
//! border samples, virtual handles), the partition, weights and transforms, with
//! incremental insertion and removal of handles.

use std::collections::HashMap;
use std::time::Instant;

use geometry::{Similarity, segment_distance};
use glam::{DAffine2, DVec2};

use crate::basis::Basis;
use crate::domain::{Domain, Metric};
use crate::error::RigError;
use crate::harmonic::{Coefficients, Solved, dual_edges, harmonic_coordinates};
use crate::overlay::Overlay;
use crate::virtual_handles::{Placement, insert_virtual_handles};
use crate::voronoi::{CellStats, NONE, Partition};
use crate::weights::{Ball, Change, SampleSet, Weights, ball};

/// A handle the user places.
#[derive(Clone, Debug, PartialEq)]
pub enum Handle {
    /// A point handle at `rest` (pixels) with its current transform about `rest`.
    Point {
        /// Rest position in pixels.
        rest: DVec2,
        /// Current transform, about `rest`.
        transform: Similarity,
    },
    /// A bar (line-segment) handle from `rest[0]` to `rest[1]`, currently posed with its
    /// ends at `pose`.
    Bar {
        /// Rest end points in pixels.
        rest: [DVec2; 2],
        /// Current end points in pixels.
        pose: [DVec2; 2],
    },
}

impl Handle {
    /// A point handle at rest.
    pub fn point(rest: DVec2) -> Self {
        Self::Point {
            rest,
            transform: Similarity::IDENTITY,
        }
    }

    /// A bar handle at rest.
    pub fn bar(a: DVec2, b: DVec2) -> Self {
        Self::Bar {
            rest: [a, b],
            pose: [a, b],
        }
    }

    /// The same handle with its pose reset to rest.
    pub fn at_rest(&self) -> Self {
        match self {
            Self::Point { rest, .. } => Self::point(*rest),
            Self::Bar { rest, .. } => Self::bar(rest[0], rest[1]),
        }
    }

    /// The handle's transform as a similarity about `centre`, with its rotation angle
    /// and scale.
    fn similarity(&self) -> (Similarity, DVec2) {
        match *self {
            Self::Point { rest, transform } => (transform, rest),
            Self::Bar { rest, pose } => {
                let c = (rest[0] + rest[1]) * 0.5;
                (Similarity::from_segments(c, rest, pose), c)
            }
        }
    }

    fn rest_equal(&self, other: &Self) -> bool {
        match (self, other) {
            (Self::Point { rest: a, .. }, Self::Point { rest: b, .. }) => a == b,
            (Self::Bar { rest: a, .. }, Self::Bar { rest: b, .. }) => a == b,
            _ => false,
        }
    }
}

/// What a weighted node is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NodeKind {
    /// The node of point handle `handle`.
    Point {
        /// Index of the handle.
        handle: usize,
    },
    /// A sample of bar handle `handle` at parameter `t ∈ [0, 1]` along it.
    BarSample {
        /// Index of the handle.
        handle: usize,
        /// Parameter along the bar.
        t: f64,
    },
    /// A pinned sample of the domain's border (with a fixed boundary).
    Boundary,
    /// A virtual handle inserted by Algorithm 1.
    Virtual,
}

/// A weighted node: one of the handles the weights partition unity over.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    /// The sample the node sits on.
    pub vertex: u32,
    /// What the node is.
    pub kind: NodeKind,
}

/// Radii of one node, in pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeRadii {
    /// r_d: distance to the farthest sample of the node's Voronoi cell.
    pub r_d: f64,
    /// r_h: distance to the nearest other node (∞ if none is reachable).
    pub r_h: f64,
    /// The support radius (1 − α)·r_d + α·r_h: the weight is zero from there on.
    pub support: f64,
}

/// Options of the weighting.
#[derive(Clone, Debug, PartialEq)]
pub struct RigOptions {
    /// Shape factor α ∈ [0, 1]: support (1 − α)·r_d + α·r_h. Default 1.
    pub alpha: f64,
    /// The basis function. Default: degree 5.
    pub basis: Basis,
    /// Pin the domain's border in place (the paper's fixed boundary). Default off.
    pub fixed_boundary: bool,
    /// How Algorithm 1 places virtual handles. Default: as the paper writes it.
    pub placement: Placement,
}

impl Default for RigOptions {
    fn default() -> Self {
        Self {
            alpha: 1.0,
            basis: Basis::default(),
            fixed_boundary: false,
            placement: Placement::AsWritten,
        }
    }
}

/// Wall-clock time of the phases of the last full build, in milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BuildTimings {
    /// Nearest-node distances of all samples (multi-source Dijkstra or Euclidean).
    pub distances_ms: f64,
    /// Region decomposition: cells, r_d and r_h.
    pub voronoi_ms: f64,
    /// Virtual-handle insertion (Algorithm 1).
    pub virtual_ms: f64,
    /// Supports, sparse weights, dual graph and harmonic transforms.
    pub weights_ms: f64,
}

/// Wall-clock time of the phases of the last incremental update, in milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct UpdateTimings {
    /// Finding the nodes to add and remove, and the samples the removed ones reached.
    pub plan_ms: f64,
    /// Updating the partition (local Dijkstra) and the cells' radii.
    pub partition_ms: f64,
    /// Virtual handles inserted to restore r_d < r_h.
    pub virtual_ms: f64,
    /// Supports of the changed nodes and the rows of the samples they reach (with the
    /// wait for the last distance fields).
    pub weights_ms: f64,
    /// Dual graph, harmonic coordinates and node transforms. The harmonic coordinates
    /// are worked out on a free core while the last fields are searched, so this
    /// overlaps `weights_ms`.
    pub transforms_ms: f64,
}

impl UpdateTimings {
    /// Sum of the phases (more than the wall-clock time where phases overlap).
    pub fn total_ms(&self) -> f64 {
        self.plan_ms + self.partition_ms + self.virtual_ms + self.weights_ms + self.transforms_ms
    }
}

impl BuildTimings {
    /// Sum of the phases.
    pub fn total_ms(&self) -> f64 {
        self.distances_ms + self.voronoi_ms + self.virtual_ms + self.weights_ms
    }
}

/// The group (real handle, or after them the fixed border) whose transform node `n`
/// takes: `None` for a virtual handle.
fn group_of(n: &Node, handle_count: usize) -> Option<usize> {
    match n.kind {
        NodeKind::Point { handle } | NodeKind::BarSample { handle, .. } => Some(handle),
        NodeKind::Boundary => Some(handle_count),
        NodeKind::Virtual => None,
    }
}

/// Harmonic coordinates of the virtual nodes over the groups, on the dual graph of
/// `partition`.
/// `progress(done, total)` is told of the solves (one per group and part of the dual
/// graph), in order; parts solved `earlier` with the same inputs are taken as they
/// were. Returns the coordinates and the parts solved, for the next call.
fn harmonic_of(
    domain: &Domain,
    partition: &Partition,
    nodes: &[Node],
    handle_count: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
    earlier: &Solved,
) -> (Vec<Option<Coefficients>>, Solved) {
    let edges = dual_edges(domain, partition);
    let node_group: Vec<Option<usize>> = nodes.iter().map(|n| group_of(n, handle_count)).collect();
    let node_rank: Vec<u32> = (partition.node_vertex.iter())
        .map(|&v| domain.rank(v))
        .collect();
    harmonic_coordinates(
        domain.positions(),
        &partition.node_vertex,
        &node_rank,
        &node_group,
        &edges,
        progress,
        earlier,
    )
}

/// The most handles a rig takes; more are refused up front. On a mesh of the default
/// 20,000 samples that is a handle on every other sample, and the build stays under a
/// second however they lie (measured with the `many_handles` example of the pipeline
/// crate on the lizard: 0.6 s at worst, with every handle one pixel from another;
/// 1.3 s at 100,000 samples).
pub const MAX_HANDLES: usize = 10_000;

/// A virtual handle to build a rig with: its sample, and the handle it was placed for
/// (whose removal takes it along), if any.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct VirtualHandle {
    /// The sample it sits on.
    pub vertex: u32,
    /// Index of the handle it was placed for.
    pub placed_for: Option<usize>,
}

/// A phase of a rig build, in the order they run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Phase {
    /// Every sample's nearest node, the Voronoi cells and their radii.
    Partition,
    /// Virtual handles placed by Algorithm 1; how many it needs is known only at the
    /// end (up to one a sample, where two handles are a mesh edge apart).
    VirtualHandles,
    /// Supports and sparse weights.
    Weights,
    /// Harmonic coordinates of the virtual handles: one solve per real handle and part
    /// of the dual graph it touches.
    Transforms,
}

/// How far a build has come, as told to the callback of [`Rig::with_progress`].
///
/// Reports come in order: by phase, and within a phase by `done`; the last one is
/// [`Phase::Transforms`] with `done == total`, at [`Progress::fraction`] 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Progress {
    /// The phase under way.
    pub phase: Phase,
    /// Steps of the phase done.
    pub done: usize,
    /// Steps of the phase, when known (`None` while Algorithm 1 runs).
    pub total: Option<usize>,
}

impl Progress {
    /// The build's progress in [0, 1], never lower than at an earlier report: each
    /// phase has a share of the scale (a rough guess at its share of the time; the
    /// virtual handles' is filled ever more slowly, as their number is not known).
    pub fn fraction(&self) -> f64 {
        let (start, end) = match self.phase {
            Phase::Partition => (0.0, 0.1),
            Phase::VirtualHandles => (0.1, 0.4),
            Phase::Weights => (0.4, 0.6),
            Phase::Transforms => (0.6, 1.0),
        };
        let within = match self.total {
            Some(0) => 1.0,
            Some(total) => (self.done as f64 / total as f64).min(1.0),
            None => self.done as f64 / (self.done as f64 + 1000.0),
        };
        if within >= 1.0 {
            end
        } else {
            (start + (end - start) * within).min(end)
        }
    }
}

/// Algorithm 1 reports its progress once every this many virtual handles.
const PROGRESS_STEP: usize = 64;

/// For each of the `old` handles, its index among `new` if it is there (the same rest
/// geometry; equal handles are matched in order), `None` if it left.
fn match_handles(
    old: &[Handle],
    new: &[Handle],
    old_overlaid: &[bool],
    new_overlaid: &[bool],
) -> Vec<Option<usize>> {
    // Rest geometry as bits (+ 0.0 makes −0 and 0 alike, as == has them); a handle
    // that becomes overlaid, or stops being, leaves and arrives.
    let bits = |x: f64| (x + 0.0).to_bits();
    let key = |h: &Handle, overlaid: bool| match *h {
        Handle::Point { rest, .. } => (false, overlaid, [bits(rest.x), bits(rest.y), 0, 0]),
        Handle::Bar { rest: [a, b], .. } => {
            (true, overlaid, [bits(a.x), bits(a.y), bits(b.x), bits(b.y)])
        }
    };
    let mut waiting: HashMap<(bool, bool, [u64; 4]), std::collections::VecDeque<usize>> =
        HashMap::new();
    for (j, h) in new.iter().enumerate() {
        waiting
            .entry(key(h, new_overlaid.get(j) == Some(&true)))
            .or_default()
            .push_back(j);
    }
    old.iter()
        .enumerate()
        .map(|(i, h)| {
            waiting
                .get_mut(&key(h, old_overlaid.get(i) == Some(&true)))
                .and_then(|q| q.pop_front())
        })
        .collect()
}

/// `overlaid` (ascending handle indices) as a flag per handle.
fn overlaid_flags(overlaid: &[usize], handles: usize) -> Result<Vec<bool>, RigError> {
    let mut flags = vec![false; handles];
    for &i in overlaid {
        match flags.get_mut(i) {
            Some(f) => *f = true,
            None => return Err(RigError::NoSuchHandle { handle: i }),
        }
    }
    Ok(flags)
}

/// Sizes of a rig.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RigStats {
    /// Samples (mesh vertices).
    pub samples: usize,
    /// User handles.
    pub real_handles: usize,
    /// Nodes of the user handles (points and bar samples).
    pub handle_nodes: usize,
    /// Pinned border nodes.
    pub boundary_nodes: usize,
    /// Virtual handles.
    pub virtual_nodes: usize,
    /// Stored non-zero weights.
    pub nonzeros: usize,
    /// Bytes used by the sparse weights.
    pub weight_bytes: usize,
}

/// Handles on a domain with their C² weights.
///
/// ```
/// use glam::DVec2;
/// use weights_core::{Domain, Handle, Metric, Rig, RigOptions, Similarity};
///
/// // A 10 × 10 square of two triangles... refined into a 11 × 11 grid of samples.
/// let mut positions = Vec::new();
/// for y in 0..=10 {
///     for x in 0..=10 {
///         positions.push(DVec2::new(x as f64, y as f64));
///     }
/// }
/// let mut triangles = Vec::new();
/// for y in 0..10u32 {
///     for x in 0..10u32 {
///         let a = y * 11 + x;
///         triangles.push([a, a + 1, a + 12]);
///         triangles.push([a, a + 12, a + 11]);
///     }
/// }
/// let domain = Domain::new(positions, triangles, Metric::Euclidean).unwrap();
/// let handles = vec![Handle::point(DVec2::new(2.0, 2.0)), Handle::point(DVec2::new(8.0, 7.0))];
/// let mut rig = Rig::new(domain, handles, RigOptions::default()).unwrap();
/// let sum: f64 = rig.weights(60).map(|(_, w)| w).sum();
/// assert!((sum - 1.0).abs() < 1e-12);
///
/// rig.set_point_transform(0, Similarity::translate(DVec2::new(1.0, 0.0))).unwrap();
/// let moved = rig.deform();
/// assert_eq!(moved[2 * 11 + 2], DVec2::new(3.0, 2.0)); // the handle's sample follows it
/// ```
#[derive(Clone, Debug)]
pub struct Rig {
    domain: Domain,
    options: RigOptions,
    handles: Vec<Handle>,
    nodes: Vec<Node>,
    partition: Partition,
    radii: Vec<f64>,
    weights: Weights,
    harmonic: Vec<Option<Coefficients>>,
    /// The parts of the dual graph the harmonic coordinates were solved on, kept for
    /// the next update.
    solved: Solved,
    affines: Vec<DAffine2>,
    resolution: f64,
    timings: BuildTimings,
    update_timings: UpdateTimings,
    /// The virtual handles placed while a handle arrived, by sample, with that handle's
    /// index (renumbered when handles before it go): they go when it goes, so inserting
    /// and removing handles does not leave ever more virtual handles behind. (Virtual
    /// handles from a build, or placed while handles only left, stay until crowded
    /// out.)
    placed_for: HashMap<u32, usize>,
    /// Which handles are overlaid (placed in a posed state; see [`crate::overlay`]):
    /// they take no part in the partition.
    overlaid: Vec<bool>,
    /// The overlaid handles' nodes and bumps.
    overlay: Overlay,
    /// The partition's nodes, then the overlay's: the nodes weights and transforms
    /// are numbered over.
    all_nodes: Vec<Node>,
    /// With overlaid handles, the posed picture (what [`Rig::deform`] gives).
    picture: Vec<DVec2>,
}

impl Rig {
    /// Builds the rig: nodes for the handles, the partition, virtual handles, weights.
    ///
    /// # Errors
    /// Invalid options; a handle that is not finite, lies outside the domain, coincides
    /// with another (or lands on the same sample), a zero-length bar, a scale ≤ 0.
    pub fn new(
        domain: Domain,
        handles: Vec<Handle>,
        options: RigOptions,
    ) -> Result<Self, RigError> {
        Self::with_virtual_handles(domain, handles, &[], options)
    }

    /// Builds the rig with the given virtual handles (sample indices) already in place,
    /// adding more only where Algorithm 1 needs them: a saved rig reloads with exactly
    /// the weights it had.
    ///
    /// # Errors
    /// As [`Rig::new`], a virtual handle on a sample that does not exist, and more
    /// virtual handles than samples.
    pub fn with_virtual_handles(
        domain: Domain,
        handles: Vec<Handle>,
        virtual_vertices: &[u32],
        options: RigOptions,
    ) -> Result<Self, RigError> {
        let placed: Vec<VirtualHandle> = virtual_vertices
            .iter()
            .map(|&vertex| VirtualHandle {
                vertex,
                placed_for: None,
            })
            .collect();
        Self::with_progress(domain, handles, &placed, options, &|_| {})
    }

    /// As [`Rig::with_virtual_handles`], with the handle each virtual handle was placed
    /// for (as [`Rig::placed_virtual_handles`] lists them): removing that handle later
    /// takes them along, as it would have in the rig they were saved from.
    ///
    /// # Errors
    /// As [`Rig::with_virtual_handles`], and a `placed_for` that names no handle.
    pub fn with_placed_virtual_handles(
        domain: Domain,
        handles: Vec<Handle>,
        virtual_handles: &[VirtualHandle],
        options: RigOptions,
    ) -> Result<Self, RigError> {
        Self::with_progress(domain, handles, virtual_handles, options, &|_| {})
    }

    /// As [`Rig::with_placed_virtual_handles`], telling `progress` how far the build
    /// has come (see [`Progress`]); it is called from the building threads, often, so
    /// it should be quick (store the figure; draw elsewhere).
    ///
    /// ```
    /// use std::sync::Mutex;
    /// use glam::DVec2;
    /// use weights_core::{Domain, Handle, Metric, Progress, Rig, RigOptions};
    ///
    /// let positions: Vec<DVec2> =
    ///     (0..400).map(|i| DVec2::new((i % 20) as f64, (i / 20) as f64)).collect();
    /// let mut triangles = Vec::new();
    /// for y in 0..19u32 {
    ///     for x in 0..19u32 {
    ///         let a = y * 20 + x;
    ///         triangles.push([a, a + 1, a + 21]);
    ///         triangles.push([a, a + 21, a + 20]);
    ///     }
    /// }
    /// let domain = Domain::new(positions, triangles, Metric::Intrinsic).unwrap();
    /// let handles = vec![Handle::point(DVec2::new(2.0, 2.0)), Handle::point(DVec2::new(4.0, 2.0))];
    /// let last = Mutex::new(0.0);
    /// let rig = Rig::with_progress(domain, handles, &[], RigOptions::default(), &|p: Progress| {
    ///     *last.lock().unwrap() = p.fraction();
    /// })
    /// .unwrap();
    /// assert_eq!(*last.lock().unwrap(), 1.0);
    /// assert!(rig.stats().virtual_nodes > 0);
    /// ```
    ///
    /// # Errors
    /// As [`Rig::with_placed_virtual_handles`].
    pub fn with_progress(
        domain: Domain,
        handles: Vec<Handle>,
        virtual_handles: &[VirtualHandle],
        options: RigOptions,
        progress: &(dyn Fn(Progress) + Sync),
    ) -> Result<Self, RigError> {
        Self::with_overlaid(domain, handles, &[], virtual_handles, options, progress)
    }

    /// As [`Rig::with_progress`], with the handles `overlaid` (indices, ascending)
    /// laid over the weights of the others instead of joining the partition: what a
    /// handle placed in a posed state is, so that placing it moves nothing away from
    /// it (see [`Rig::set_handles_overlaid`]).
    ///
    /// # Errors
    /// As [`Rig::with_placed_virtual_handles`], an overlaid index that names no
    /// handle, and an overlaid handle on the sample of another handle's node.
    pub fn with_overlaid(
        domain: Domain,
        handles: Vec<Handle>,
        overlaid: &[usize],
        virtual_handles: &[VirtualHandle],
        options: RigOptions,
        progress: &(dyn Fn(Progress) + Sync),
    ) -> Result<Self, RigError> {
        check_options(&options)?;
        let overlaid = overlaid_flags(overlaid, handles.len())?;
        if virtual_handles.len() > domain.len() {
            return Err(RigError::TooManyVirtual {
                count: virtual_handles.len(),
                samples: domain.len(),
            });
        }
        domain.prepare();
        let resolution = domain.mean_edge_length();
        let (mut nodes, overlaid_nodes) =
            real_nodes(&domain, &handles, &overlaid, &options, resolution)?;
        let mut taken: std::collections::HashSet<u32> = nodes.iter().map(|n| n.vertex).collect();
        let mut placed_for = HashMap::new();
        for (i, v) in virtual_handles.iter().enumerate() {
            if v.vertex as usize >= domain.len() {
                return Err(RigError::BadVirtual(v.vertex));
            }
            if let Some(h) = v.placed_for.filter(|&h| h >= handles.len()) {
                return Err(RigError::BadPlacedFor {
                    index: i,
                    handle: h,
                });
            }
            if taken.insert(v.vertex) {
                nodes.push(Node {
                    vertex: v.vertex,
                    kind: NodeKind::Virtual,
                });
                if let Some(h) = v.placed_for {
                    placed_for.insert(v.vertex, h);
                }
            }
        }
        let report = |phase, done, total| {
            progress(Progress { phase, done, total });
        };
        report(Phase::Partition, 0, Some(1));
        let mut timings = BuildTimings::default();
        let clock = Instant::now();
        let mut partition = Partition::distances(&domain, nodes.iter().map(|n| n.vertex).collect());
        timings.distances_ms = ms(clock);
        let clock = Instant::now();
        partition.decompose(&domain);
        timings.voronoi_ms = ms(clock);
        report(Phase::Partition, 1, Some(1));
        report(Phase::VirtualHandles, 0, None);
        let clock = Instant::now();
        let mut placed = 0;
        // While Algorithm 1 runs on this core, the other cores search the distance
        // fields of the nodes it is done with: each from the frontier of its own
        // cell, as in an insertion, for each new virtual node and every cell that meets
        // r_d < r_h already (a violator is about to be crowded by a virtual node, its
        // support to shrink). Radii only shrink from there on, so a field searched
        // now covers the final support; `Weights::build` searches again any
        // that falls short.
        let searched = std::sync::Mutex::new(Vec::new());
        let (domain_ref, alpha) = (&domain, options.alpha);
        let added = rayon::scope(|scope| {
            let searched = &searched;
            let search = |partition: &Partition, k: usize| {
                let v = partition.node_vertex[k];
                let radius = support_radius(&partition.stats[k], alpha);
                let cell = partition.cell_field(domain_ref, k);
                search_aside(scope, searched, v, move || {
                    Some(Ball::compute_from(domain_ref, v, radius, cell))
                });
            };
            if domain_ref.metric() == Metric::Intrinsic {
                for k in 0..partition.len() {
                    let s = &partition.stats[k];
                    if s.r_d < s.r_h {
                        search(&partition, k);
                    }
                }
            }
            insert_virtual_handles(
                domain_ref,
                &mut partition,
                options.placement,
                |partition, k| {
                    placed += 1;
                    if placed % PROGRESS_STEP == 0 {
                        report(Phase::VirtualHandles, placed, None);
                    }
                    if domain_ref.metric() == Metric::Intrinsic {
                        search(partition, k);
                    }
                },
            )
        });
        report(Phase::VirtualHandles, added.len(), Some(added.len()));
        nodes.extend(added.into_iter().map(|v| Node {
            vertex: v,
            kind: NodeKind::Virtual,
        }));
        timings.virtual_ms = ms(clock);
        report(Phase::Weights, 0, Some(1));
        let clock = Instant::now();
        let radii = support_radii(&partition, options.alpha);
        let weights = Weights::build(
            &domain,
            &partition,
            &radii,
            &options.basis,
            searched.into_inner().expect("not poisoned"),
        );
        report(Phase::Weights, 1, Some(1));
        let mut rig = Self {
            domain,
            options,
            handles,
            nodes,
            partition,
            radii,
            weights,
            harmonic: Vec::new(),
            solved: Solved::default(),
            affines: Vec::new(),
            resolution,
            timings,
            update_timings: UpdateTimings::default(),
            placed_for,
            overlaid,
            overlay: Overlay::default(),
            all_nodes: Vec::new(),
            picture: Vec::new(),
        };
        rig.overlay = Overlay::build(
            &rig.domain,
            &rig.options.basis,
            &rig.handles,
            &rig.nodes,
            overlaid_nodes,
        )?;
        rig.all_nodes = rig
            .nodes
            .iter()
            .chain(&rig.overlay.nodes)
            .copied()
            .collect();
        (rig.harmonic, rig.solved) = harmonic_of(
            &rig.domain,
            &rig.partition,
            &rig.nodes,
            rig.handles.len(),
            &|done, total| report(Phase::Transforms, done, Some(total)),
            &Solved::default(),
        );
        rig.update_affines();
        rig.timings.weights_ms = ms(clock);
        Ok(rig)
    }

    /// Inserts a handle and brings everything up to date, touching only the cells and
    /// supports the new handle changes. Returns the new handle's index.
    ///
    /// Virtual handles already in place stay, so the warp elsewhere does not jump; the
    /// result equals [`Rig::with_virtual_handles`] with the same handles and virtual
    /// handles.
    ///
    /// # Errors
    /// As [`Rig::new`] for the new handle; the rig is unchanged on error.
    pub fn insert_handle(&mut self, handle: Handle) -> Result<usize, RigError> {
        let mut handles = self.handles.clone();
        handles.push(handle);
        self.set_handles(handles)?;
        Ok(self.handles.len() - 1)
    }

    /// Removes handle `index` (later handles shift down by one) and brings everything
    /// up to date locally. The virtual handles placed when it was inserted go with it
    /// (and Algorithm 1 adds what the remaining nodes need), so trying a handle at many
    /// places does not pile up virtual handles.
    ///
    /// # Errors
    /// [`RigError::NoSuchHandle`]; the rig is unchanged on error.
    pub fn remove_handle(&mut self, index: usize) -> Result<Handle, RigError> {
        if index >= self.handles.len() {
            return Err(RigError::NoSuchHandle { handle: index });
        }
        let mut handles = self.handles.clone();
        let removed = handles.remove(index);
        self.set_handles(handles)?;
        Ok(removed)
    }

    /// Replaces the handles. Poses alone are cheap; handles whose rest geometry changed
    /// are removed and inserted incrementally. Removing every handle rebuilds the rig
    /// empty, virtual handles included.
    ///
    /// # Errors
    /// As [`Rig::new`]; the rig is unchanged on error.
    pub fn set_handles(&mut self, handles: Vec<Handle>) -> Result<(), RigError> {
        // An overlaid handle stays overlaid while it is there, at the same rest place.
        let mut overlaid: Vec<usize> = match_handles(
            &self.handles,
            &handles,
            &vec![false; self.handles.len()],
            &vec![false; handles.len()],
        )
        .into_iter()
        .zip(&self.overlaid)
        .filter_map(|(j, &o)| j.filter(|_| o))
        .collect();
        overlaid.sort_unstable();
        self.set_handles_overlaid(handles, &overlaid)
    }

    /// Replaces the handles, with the handles `overlaid` (indices into `handles`,
    /// ascending) laid over the others' weights: each takes its share from the weights
    /// under its bump (the paper's support: the distance to the nearest node) instead
    /// of joining the partition, so that nothing outside the bump changes. The handles
    /// placed in a posed state are overlaid in the editor, so that placing one holds
    /// the picture where it is.
    ///
    /// # Errors
    /// As [`Rig::set_handles`], and an overlaid index that names no handle or a sample
    /// that another handle's node takes; the rig is unchanged on error.
    pub fn set_handles_overlaid(
        &mut self,
        handles: Vec<Handle>,
        overlaid: &[usize],
    ) -> Result<(), RigError> {
        let flags = overlaid_flags(overlaid, handles.len())?;
        let same_rest = flags == self.overlaid
            && handles.len() == self.handles.len()
            && handles
                .iter()
                .zip(&self.handles)
                .all(|(a, b)| a.rest_equal(b));
        if same_rest {
            check_handles(&handles)?;
            self.handles = handles;
            self.update_affines();
            return Ok(());
        }
        if handles.is_empty() {
            // Virtual handles serve real ones: with none left, none stay (as a fresh
            // build would have it).
            let clock = Instant::now();
            *self = Rig::new(self.domain.clone(), handles, self.options.clone())?;
            self.update_timings = UpdateTimings {
                weights_ms: ms(clock),
                ..UpdateTimings::default()
            };
            return Ok(());
        }
        let clock = Instant::now();
        let (target, overlaid_nodes) = real_nodes(
            &self.domain,
            &handles,
            &flags,
            &self.options,
            self.resolution,
        )?;
        let kept = match_handles(&self.handles, &handles, &self.overlaid, &flags);
        self.update_timings = UpdateTimings::default();
        self.update_timings.plan_ms = ms(clock);
        self.handles = handles;
        self.overlaid = flags;
        self.apply(target, &kept);
        let clock = Instant::now();
        // (An overlaid sample on another handle's, the one error, was refused above.)
        self.overlay = Overlay::build(
            &self.domain,
            &self.options.basis,
            &self.handles,
            &self.nodes,
            overlaid_nodes,
        )
        .unwrap_or_default();
        self.all_nodes = self
            .nodes
            .iter()
            .chain(&self.overlay.nodes)
            .copied()
            .collect();
        self.update_timings.weights_ms += ms(clock);
        let clock = Instant::now();
        self.update_affines();
        self.update_timings.transforms_ms += ms(clock);
        Ok(())
    }

    /// Sets the transform of point handle `index`.
    ///
    /// # Errors
    /// No such handle, not a point handle, or a non-finite / non-positive-scale transform.
    pub fn set_point_transform(
        &mut self,
        index: usize,
        transform: Similarity,
    ) -> Result<(), RigError> {
        self.set_pose(index, |h| match *h {
            Handle::Point { rest, .. } => Some(Handle::Point { rest, transform }),
            Handle::Bar { .. } => None,
        })
        .map_err(|e| {
            e.unwrap_or(RigError::WrongKind {
                handle: index,
                expected: "bar",
            })
        })
    }

    /// Sets the posed end points of bar handle `index`.
    ///
    /// # Errors
    /// No such handle, not a bar, or non-finite end points.
    pub fn set_bar_pose(&mut self, index: usize, pose: [DVec2; 2]) -> Result<(), RigError> {
        self.set_pose(index, |h| match *h {
            Handle::Bar { rest, .. } => Some(Handle::Bar { rest, pose }),
            Handle::Point { .. } => None,
        })
        .map_err(|e| {
            e.unwrap_or(RigError::WrongKind {
                handle: index,
                expected: "point",
            })
        })
    }

    /// Replaces handle `index` by `posed(handle)` (same rest geometry, new pose) and
    /// updates the node transforms. `Err(None)` when `posed` refuses the handle's kind.
    fn set_pose(
        &mut self,
        index: usize,
        posed: impl FnOnce(&Handle) -> Option<Handle>,
    ) -> Result<(), Option<RigError>> {
        let current = self
            .handles
            .get(index)
            .ok_or(Some(RigError::NoSuchHandle { handle: index }))?;
        let h = posed(current).ok_or(None)?;
        check_handle(index, &h).map_err(Some)?;
        self.handles[index] = h;
        self.update_affines();
        Ok(())
    }

    /// Moves the node set to `target` real nodes (virtual nodes kept unless a real node
    /// takes their sample), updating partition, virtual handles and weights locally.
    /// `kept[i]` is the new index of the old handle `i`, `None` if it left; new
    /// handles that no old one became have arrived.
    fn apply(&mut self, target: Vec<Node>, kept: &[Option<usize>]) {
        let clock = Instant::now();
        let target_vertices: std::collections::HashSet<u32> =
            target.iter().map(|n| n.vertex).collect();
        // New real nodes replace the virtual nodes they crowd: any virtual node a new one
        // lands within r_d of (inside the reach of its cell). Left in place, a node beside
        // a virtual one would make Algorithm 1 refine the whole neighbourhood down to
        // their spacing (at one edge apart, every sample would become a node); removed,
        // it is re-placed where the new node needs it. A virtual node farther away than
        // its r_d stays valid as it is: its cell only shrinks, and its new nearest
        // neighbour is no nearer than the cell reaches. (Replacing every virtual node
        // within its r_h instead gives about 4% fewer virtual handles, but re-places
        // three or four of them on a typical insertion, a quarter of the median one.)
        let present: std::collections::HashSet<u32> = self.nodes.iter().map(|n| n.vertex).collect();
        let positions = self.domain.positions();
        let arrivals: Vec<DVec2> = target
            .iter()
            .filter(|n| !present.contains(&n.vertex))
            .map(|n| positions[n.vertex as usize])
            .collect();
        let replaced: std::collections::HashSet<u32> = self
            .nodes
            .iter()
            .enumerate()
            .filter(|(_, n)| n.kind == NodeKind::Virtual)
            .filter(|&(k, n)| {
                let p = positions[n.vertex as usize];
                let r_d = self.partition.stats[k].r_d;
                arrivals.iter().any(|q| (*q - p).length() < r_d)
            })
            .map(|(_, n)| n.vertex)
            .collect();
        // Handles that leave take the virtual handles placed for them along.
        let doomed: Vec<usize> = (0..self.nodes.len())
            .filter(|&k| {
                let n = self.nodes[k];
                if n.kind != NodeKind::Virtual {
                    return !target_vertices.contains(&n.vertex);
                }
                target_vertices.contains(&n.vertex)
                    || replaced.contains(&n.vertex)
                    || self
                        .placed_for
                        .get(&n.vertex)
                        .is_some_and(|&h| kept.get(h).copied().flatten().is_none())
            })
            .collect();
        for &k in &doomed {
            self.placed_for.remove(&self.nodes[k].vertex);
        }
        for h in self.placed_for.values_mut() {
            *h = kept.get(*h).copied().flatten().unwrap_or(*h);
        }
        // The first handle that arrives gets the virtual handles placed now.
        let mut stays = vec![false; self.handles.len()];
        for &i in kept.iter().flatten() {
            stays[i] = true;
        }
        let first_arrival = stays.iter().position(|s| !s);
        // Support radii and distances to the nearest other node (which bounds the
        // support exactly) of the surviving nodes, by sample (node numbers change
        // below).
        let old_radius: HashMap<u32, (f64, f64)> = (0..self.nodes.len())
            .filter(|k| doomed.binary_search(k).is_err())
            .map(|k| {
                let r_h = self.partition.stats[k].r_h;
                (self.nodes[k].vertex, (self.radii[k], r_h))
            })
            .collect();
        // Samples the doomed nodes reach: their rows must be redone.
        let dirty: Vec<u32> = doomed
            .iter()
            .flat_map(|&k| {
                self.weights
                    .reached(&self.domain, k, self.nodes[k].vertex, self.radii[k])
            })
            .collect();
        self.update_timings.plan_ms += ms(clock);
        let old_vertex: Vec<u32> = self.nodes.iter().map(|n| n.vertex).collect();
        // The node samples once the removals and the real nodes are in (a bit per
        // sample: searches ask for every sample they reach), and the new real nodes
        // among them.
        let mut settled = SampleSet::new(self.domain.len());
        for v in (0..self.nodes.len())
            .filter(|k| doomed.binary_search(k).is_err())
            .map(|k| self.nodes[k].vertex)
            .chain(target_vertices.iter().copied())
        {
            settled.insert(v);
        }
        let is_settled = |v: u32| settled.contains(v);
        let arriving: Vec<u32> = target
            .iter()
            .map(|n| n.vertex)
            .filter(|v| !present.contains(v))
            .collect();
        // Surviving nodes whose nearest node may be a removed one (no closer in a
        // straight line than their r_h): their supports may grow.
        let leaving: Vec<DVec2> = doomed
            .iter()
            .map(|&k| positions[self.nodes[k].vertex as usize])
            .collect();
        let growing: Vec<(u32, usize)> = (0..self.nodes.len())
            .filter(|k| doomed.binary_search(k).is_err())
            .filter(|&k| {
                let p = positions[self.nodes[k].vertex as usize];
                let r_h = self.partition.stats[k].r_h;
                leaving.iter().any(|q| (*q - p).length() <= r_h)
            })
            .map(|k| (self.nodes[k].vertex, k))
            .collect();
        // Each node's number before the removals, by sample (for its cached field).
        let cached: HashMap<u32, usize> = old_vertex
            .iter()
            .enumerate()
            .map(|(k, &v)| (v, k))
            .collect();
        let mut map: Vec<u32> = (0..self.nodes.len() as u32).collect();
        let handle_count = self.handles.len();
        let Self {
            domain,
            options,
            nodes,
            partition,
            weights,
            update_timings,
            placed_for,
            solved,
            ..
        } = &mut *self;
        let (domain, weights, alpha) = (&*domain, &*weights, options.alpha);
        let placement = options.placement;
        // Distance fields are searched on the other cores while the partition changes:
        // once the removals and the real nodes are in, Algorithm 1 only adds nodes, so
        // radii only shrink, and a field searched to a node's radius at that point
        // covers its final support.
        let searched = std::sync::Mutex::new(Vec::new());
        let transforms = std::sync::Mutex::new(None);
        let mut weights_clock = Instant::now();
        rayon::scope(|scope| {
            let searched = &searched;
            // Searched on from the cached field, if there is one.
            let search = |v: u32, radius: f64, cached: Option<usize>| {
                search_aside(scope, searched, v, move || {
                    Some(match cached {
                        Some(k) => weights.field(k).extend(domain, v, radius),
                        None => Ball::compute(domain, v, radius),
                    })
                });
            };
            // A node's support is at most its distance to the nearest settled node:
            // the fields of new real nodes, and of nodes whose nearest node may be
            // leaving, can be searched that far before the partition knows it.
            let mut ahead = std::collections::HashSet::new();
            if domain.metric() == Metric::Intrinsic {
                let is_settled = &is_settled;
                for &q in &arriving {
                    ahead.insert(q);
                    search_aside(scope, searched, q, move || {
                        Ball::to_nearest(domain, q, &|v| v != q && is_settled(v))
                    });
                }
                for &(q, old) in &growing {
                    ahead.insert(q);
                    search_aside(scope, searched, q, move || {
                        let is_node = |v: u32| v != q && is_settled(v);
                        weights.field(old).extend_to_nearest(domain, q, &is_node)
                    });
                }
            }
            let clock = Instant::now();
            for &k in doomed.iter().rev() {
                nodes.remove(k);
                map[k] = NONE;
            }
            for (next, m) in map.iter_mut().filter(|m| **m != NONE).enumerate() {
                *m = next as u32;
            }
            // Give every surviving real node its (possibly renumbered) kind from the
            // target, and swap the doomed nodes for the new real ones in one pass.
            let present: HashMap<u32, usize> = nodes
                .iter()
                .enumerate()
                .map(|(k, n)| (n.vertex, k))
                .collect();
            let mut joining = Vec::new();
            for n in &target {
                match present.get(&n.vertex) {
                    Some(&k) => nodes[k].kind = n.kind,
                    None => joining.push(*n),
                }
            }
            let joining_vertices: Vec<u32> = joining.iter().map(|n| n.vertex).collect();
            if !doomed.is_empty() || !joining.is_empty() {
                partition.replace_nodes(domain, &doomed, &joining_vertices);
            }
            nodes.extend(joining);
            for (k, n) in nodes.iter().enumerate() {
                let radius = support_radius(&partition.stats[k], alpha);
                let old = cached.get(&n.vertex).copied();
                if !ahead.contains(&n.vertex)
                    && old.is_none_or(|k| weights.field(k).radius() < radius)
                {
                    search(n.vertex, radius, old);
                }
            }
            update_timings.partition_ms = ms(clock);
            let clock = Instant::now();
            // A new virtual node's cell holds its field already: the search goes on
            // from the cell's frontier.
            let added = insert_virtual_handles(domain, partition, placement, |partition, k| {
                let v = partition.node_vertex[k];
                let radius = support_radius(&partition.stats[k], alpha);
                let cell = partition.cell_field(domain, k);
                search_aside(scope, searched, v, move || {
                    Some(Ball::compute_from(domain, v, radius, cell))
                });
            });
            if let Some(first) = first_arrival {
                placed_for.extend(added.iter().map(|&v| (v, first)));
            }
            nodes.extend(added.into_iter().map(|v| Node {
                vertex: v,
                kind: NodeKind::Virtual,
            }));
            update_timings.virtual_ms = ms(clock);
            weights_clock = Instant::now();
            // The virtual handles' harmonic coordinates depend on the finished partition
            // only: worked out by whichever core is free while the last fields are
            // searched.
            let (partition, nodes): (&Partition, &Vec<Node>) = (&*partition, &*nodes);
            let (transforms, solved) = (&transforms, &*solved);
            scope.spawn(move |_| {
                let clock = Instant::now();
                let harmonic =
                    harmonic_of(domain, partition, nodes, handle_count, &|_, _| {}, solved);
                *transforms.lock().expect("not poisoned") = Some((harmonic, ms(clock)));
            });
        });
        let clock = weights_clock;
        self.weights
            .offer(searched.into_inner().expect("not poisoned"));
        self.radii = support_radii(&self.partition, self.options.alpha);
        let changes: Vec<Change> = self
            .nodes
            .iter()
            .enumerate()
            .filter_map(|(k, n)| {
                let old = old_radius.get(&n.vertex).copied();
                let now = (self.radii[k], self.partition.stats[k].r_h);
                let unchanged = old == Some(now);
                (!unchanged).then_some(Change {
                    node: k,
                    old_radius: old.map(|(radius, _)| radius),
                })
            })
            .collect();
        self.weights.renumber_fields(&map, &old_vertex);
        self.weights.update(
            &self.domain,
            &self.partition,
            &self.radii,
            &self.options.basis,
            &changes,
            &map,
            &dirty,
        );
        let ((harmonic, solved), transforms_ms) = transforms
            .into_inner()
            .expect("not poisoned")
            .expect("computed in the scope");
        self.harmonic = harmonic;
        self.solved = solved;
        self.update_timings.weights_ms = ms(clock);
        self.update_timings.transforms_ms = transforms_ms;
    }

    fn group_of(&self, n: &Node) -> Option<usize> {
        group_of(n, self.handles.len())
    }

    /// Node transforms from the handles' poses (virtual ones blended harmonically).
    fn update_affines(&mut self) {
        let mut groups: Vec<GroupPose> = self
            .handles
            .iter()
            .map(|h| GroupPose::new(h.similarity()))
            .collect();
        if self.options.fixed_boundary {
            groups.push(GroupPose::new((Similarity::IDENTITY, DVec2::ZERO)));
        }
        let positions = self.domain.positions();
        self.affines = self
            .all_nodes
            .iter()
            .enumerate()
            .map(|(k, n)| match self.group_of(n) {
                Some(g) => groups[g].affine,
                None => {
                    let c = positions[n.vertex as usize];
                    let Some(coefficients) = self.harmonic.get(k).and_then(Option::as_ref) else {
                        return DAffine2::IDENTITY;
                    };
                    blend(&groups, coefficients, c)
                }
            })
            .collect();
        self.picture = if self.overlay.is_empty() {
            Vec::new()
        } else {
            self.deform()
        };
    }

    /// The posed picture when handles are overlaid (it is no longer a blend of node
    /// transforms at the rest positions: see [`Rig::set_handles_overlaid`]); `None`
    /// otherwise, when [`Rig::weight_table`] and [`Rig::node_affines`] give it.
    pub fn overlaid_picture(&self) -> Option<&[DVec2]> {
        (!self.overlay.is_empty()).then_some(self.picture.as_slice())
    }

    /// Deformed positions of all samples.
    pub fn deform(&self) -> Vec<DVec2> {
        let mut out = vec![DVec2::ZERO; self.domain.len()];
        self.deform_into(&mut out);
        out
    }

    /// Writes the deformed position of every sample into `out` (length = samples).
    ///
    /// # Panics
    /// If `out` has the wrong length.
    pub fn deform_into(&self, out: &mut [DVec2]) {
        assert_eq!(out.len(), self.domain.len(), "output length");
        self.weights.deform(
            self.domain.positions(),
            &self.partition.owner,
            &self.affines,
            out,
        );
        self.overlay
            .pose(&self.handles, self.domain.positions(), out);
    }

    /// Where the rest point `p` goes, interpolated barycentrically from the deformed
    /// samples `deformed` (as returned by [`Rig::deform`]); `None` outside the domain.
    pub fn deform_point(&self, deformed: &[DVec2], p: DVec2) -> Option<DVec2> {
        let (t, bary) = self.domain.locate(p)?;
        let tri = self.domain.triangles()[t];
        Some(
            (0..3)
                .map(|i| deformed.get(tri[i] as usize).copied().unwrap_or(p) * bary[i])
                .sum(),
        )
    }

    /// The non-zero weights of sample `v` as (node index, weight).
    ///
    /// # Panics
    /// If `v` is not a sample index.
    pub fn weights(&self, v: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let base = self.weights.row(v, &self.partition.owner);
        let overlaid = if !self.overlay.touches(v as u32) {
            None
        } else {
            let mut row: Vec<(usize, f64)> = self.weights.row(v, &self.partition.owner).collect();
            self.overlay.apply(v as u32, &mut row, self.nodes.len());
            Some(row)
        };
        let (base, overlaid) = match overlaid {
            Some(row) => (None, Some(row.into_iter())),
            None => (Some(base), None),
        };
        base.into_iter()
            .flatten()
            .chain(overlaid.into_iter().flatten())
    }

    /// The normalised weights of every sample as compressed rows for a GPU to blend:
    /// row `v` is `nodes[rows[v]..rows[v + 1]]` with `weights[…]` (f32; each row sums
    /// to one up to f32 rounding).
    pub fn weight_table(&self) -> (Vec<u32>, Vec<u32>, Vec<f32>) {
        let n = self.domain.len();
        let mut rows = Vec::with_capacity(n + 1);
        let mut nodes = Vec::with_capacity(self.weights.nonzeros() + n / 64);
        let mut weights = Vec::with_capacity(nodes.capacity());
        rows.push(0);
        for v in 0..n {
            for (k, w) in self.weights(v) {
                nodes.push(k as u32);
                weights.push(w as f32);
            }
            rows.push(nodes.len() as u32);
        }
        (rows, nodes, weights)
    }

    /// Every node's transform as `[a₀₀, a₁₀, a₀₁, a₁₁, t₀, t₁]` (columns of the linear
    /// part, then the translation) in f32: what a GPU needs per pose.
    pub fn node_affines(&self) -> Vec<[f32; 6]> {
        self.affines
            .iter()
            .map(|a| {
                let m = a.matrix2;
                let t = a.translation;
                [m.x_axis.x, m.x_axis.y, m.y_axis.x, m.y_axis.y, t.x, t.y].map(|x| x as f32)
            })
            .collect()
    }

    /// Distances from node `k` to every sample (∞ where unreachable), in the rig's
    /// metric: for heat maps, isolines and tests.
    pub fn distances_from_node(&self, k: usize) -> Vec<f64> {
        let mut out = vec![f64::INFINITY; self.domain.len()];
        for (v, d) in ball(&self.domain, self.all_nodes[k].vertex, f64::INFINITY) {
            out[v as usize] = d;
        }
        out
    }

    /// The weighted nodes: the partition's, then the overlaid handles' samples.
    #[expect(
        clippy::misnamed_getters,
        reason = "the field `nodes` is the partition's alone; every node is in `all_nodes`"
    )]
    pub fn nodes(&self) -> &[Node] {
        &self.all_nodes
    }

    /// The overlaid handles (ascending): placed in a posed state, laid over the
    /// others' weights (see [`Rig::set_handles_overlaid`]).
    pub fn overlaid(&self) -> Vec<usize> {
        (0..self.overlaid.len())
            .filter(|&i| self.overlaid[i])
            .collect()
    }

    /// The user handles.
    pub fn handles(&self) -> &[Handle] {
        &self.handles
    }

    /// The domain.
    pub fn domain(&self) -> &Domain {
        &self.domain
    }

    /// The options.
    pub fn options(&self) -> &RigOptions {
        &self.options
    }

    /// Radii of node `k`.
    pub fn radii(&self, k: usize) -> NodeRadii {
        if let Some(&r) = k
            .checked_sub(self.nodes.len())
            .and_then(|j| self.overlay.radii.get(j))
        {
            // An overlaid handle's sample has no cell: its support is r_h.
            return NodeRadii {
                r_d: 0.0,
                r_h: r,
                support: r,
            };
        }
        let s = self.partition.stats[k];
        NodeRadii {
            r_d: s.r_d,
            r_h: s.r_h,
            support: self.radii[k],
        }
    }

    /// The Voronoi cell (owning node) of every sample.
    pub fn cells(&self) -> &[u32] {
        &self.partition.owner
    }

    /// The dual graph of the cells: node pairs whose cells touch.
    pub fn dual_graph(&self) -> Vec<(u32, u32)> {
        dual_edges(&self.domain, &self.partition)
    }

    /// Harmonic coordinates of virtual node `k` over the real handles (and, numbered
    /// after them, the fixed border) as `(handle, coefficient)` pairs: handles
    /// ascending, coefficients positive and summing to one. The handles left out have
    /// coefficient zero: those out of reach of the node's part of the dual graph, and
    /// those below 1e-10 (dropped, so that thousands of handles do not cost a number
    /// each per virtual handle). The list is empty when no real handle is reachable.
    /// `None` for the nodes of real handles.
    pub fn harmonic_coordinates(&self, k: usize) -> Option<&[(u32, f64)]> {
        self.harmonic.get(k).and_then(|c| c.as_deref())
    }

    /// The harmonic coordinate of virtual node `k` for handle `handle` (zero when the
    /// node is not virtual or the handle has no share in it).
    pub fn harmonic_coordinate(&self, k: usize, handle: usize) -> f64 {
        self.harmonic_coordinates(k)
            .and_then(|c| c.iter().find(|e| e.0 as usize == handle))
            .map_or(0.0, |e| e.1)
    }

    /// The transform of node `k` as an affine map of image coordinates.
    pub fn node_transform(&self, k: usize) -> DAffine2 {
        self.affines[k]
    }

    /// The real handle a node belongs to: its own for points and bar samples, the one
    /// with the largest harmonic coordinate for a virtual handle.
    pub fn owner_handle(&self, k: usize) -> Option<usize> {
        match self.all_nodes[k].kind {
            NodeKind::Point { handle } | NodeKind::BarSample { handle, .. } => Some(handle),
            NodeKind::Boundary => None,
            NodeKind::Virtual => self.harmonic_coordinates(k).and_then(|c| {
                c.iter()
                    .filter(|e| (e.0 as usize) < self.handles.len())
                    .max_by(|a, b| a.1.total_cmp(&b.1))
                    .map(|e| e.0 as usize)
            }),
        }
    }

    /// Sizes.
    pub fn stats(&self) -> RigStats {
        let count = |f: fn(&NodeKind) -> bool| self.all_nodes.iter().filter(|n| f(&n.kind)).count();
        RigStats {
            samples: self.domain.len(),
            real_handles: self.handles.len(),
            handle_nodes: count(|k| {
                matches!(k, NodeKind::Point { .. } | NodeKind::BarSample { .. })
            }),
            boundary_nodes: count(|k| matches!(k, NodeKind::Boundary)),
            virtual_nodes: count(|k| matches!(k, NodeKind::Virtual)),
            nonzeros: self.weights.nonzeros(),
            weight_bytes: self.weights.memory_bytes(),
        }
    }

    /// Phase timings of the full build.
    pub fn timings(&self) -> BuildTimings {
        self.timings
    }

    /// Phase timings of the last insertion, removal or other change of handles.
    pub fn update_timings(&self) -> UpdateTimings {
        self.update_timings
    }

    /// Samples of the virtual handles, in node order (to save and rebuild exactly).
    pub fn virtual_vertices(&self) -> Vec<u32> {
        self.nodes
            .iter()
            .filter(|n| n.kind == NodeKind::Virtual)
            .map(|n| n.vertex)
            .collect()
    }

    /// The virtual handles in node order (as [`Rig::virtual_vertices`]), each with the
    /// handle it was placed for, if any: the handle whose insertion placed it, which
    /// takes it along when removed. Save this and rebuild with
    /// [`Rig::with_placed_virtual_handles`] to get back a rig that also removes the
    /// same virtual handles with each handle.
    pub fn placed_virtual_handles(&self) -> Vec<VirtualHandle> {
        self.nodes
            .iter()
            .filter(|n| n.kind == NodeKind::Virtual)
            .map(|n| VirtualHandle {
                vertex: n.vertex,
                placed_for: self.placed_for.get(&n.vertex).copied(),
            })
            .collect()
    }

    /// Whether the rig equals `other` node for node (up to node numbering) and weight
    /// for weight, bit for bit. For tests of incremental updates.
    pub fn same_weights_as(&self, other: &Rig) -> Result<(), String> {
        if !self.overlay.same_as(&other.overlay) {
            return Err("the overlaid handles' bumps differ".to_owned());
        }
        self.weights.same_as(
            (&self.partition.node_vertex, &self.partition.owner),
            &other.weights,
            (&other.partition.node_vertex, &other.partition.owner),
        )
    }
}

fn ms(since: Instant) -> f64 {
    since.elapsed().as_secs_f64() * 1e3
}

/// Support radius per node: (1 − α)·r_d + α·r_h, never beyond r_h, ∞ for a node alone
/// in its component.
fn support_radii(partition: &Partition, alpha: f64) -> Vec<f64> {
    partition
        .stats
        .iter()
        .map(|s| support_radius(s, alpha))
        .collect()
}

/// Runs `search` (the distance field of the node on sample `v`) on another core of
/// `scope`, adding what it finds to `found`.
fn search_aside<'s>(
    scope: &rayon::Scope<'s>,
    found: &'s std::sync::Mutex<Vec<(u32, Ball)>>,
    v: u32,
    search: impl FnOnce() -> Option<Ball> + Send + 's,
) {
    scope.spawn(move |_| {
        if let Some(field) = search() {
            found.lock().expect("not poisoned").push((v, field));
        }
    });
}

/// The support radius of a cell with radii `s`: (1 − α)·r_d + α·r_h.
fn support_radius(s: &CellStats, alpha: f64) -> f64 {
    if s.r_h.is_infinite() {
        f64::INFINITY
    } else {
        // Rounded up to an f32 value: distances are kept as f32, and a distance at or
        // beyond a representable radius rounds to at or beyond it.
        round_up_f32(((1.0 - alpha) * s.r_d + alpha * s.r_h).min(s.r_h))
    }
}

/// The smallest f32 value at or above `x`, as f64.
fn round_up_f32(x: f64) -> f64 {
    let f = x as f32;
    if f64::from(f) < x {
        f64::from(f.next_up())
    } else {
        f64::from(f)
    }
}

/// A group's pose, worked out once for all the nodes that blend it.
struct GroupPose {
    /// The similarity and the centre it is taken about.
    similarity: Similarity,
    centre: DVec2,
    /// Its rotation as a unit complex number.
    rotation: DVec2,
    /// Its linear part.
    linear: glam::DMat2,
    /// The whole map in image coordinates.
    affine: DAffine2,
}

impl GroupPose {
    fn new((similarity, centre): (Similarity, DVec2)) -> Self {
        Self {
            similarity,
            centre,
            rotation: DVec2::from_angle(similarity.rotation),
            linear: similarity.linear(),
            affine: similarity.to_affine(centre),
        }
    }
}

/// The virtual handle at `c`: the groups' rotations (unit complex numbers), scales and
/// the images of `c` blended with the harmonic coefficients.
fn blend(groups: &[GroupPose], coefficients: &[(u32, f64)], c: DVec2) -> DAffine2 {
    let (mut rot, mut scale, mut pos, mut total) = (DVec2::ZERO, 0.0, DVec2::ZERO, 0.0);
    for &(g, w) in coefficients {
        let Some(group) = groups.get(g as usize) else {
            continue;
        };
        rot += w * group.rotation;
        scale += w * group.similarity.scale;
        // As Similarity::apply, with the linear part worked out once.
        pos +=
            w * (group.centre + group.similarity.translation + group.linear * (c - group.centre));
        total += w;
    }
    if total <= 0.0 {
        return DAffine2::IDENTITY;
    }
    let angle = if rot.length_squared() > 0.0 {
        rot.to_angle()
    } else {
        0.0
    };
    let blended = Similarity {
        translation: pos / total - c,
        rotation: angle,
        scale: scale / total,
    };
    blended.to_affine(c)
}

fn check_options(o: &RigOptions) -> Result<(), RigError> {
    if !(0.0..=1.0).contains(&o.alpha) {
        return Err(RigError::Options(format!(
            "alpha must be in [0, 1], got {}",
            o.alpha
        )));
    }
    Ok(())
}

/// The largest pose coordinate (pixels) or angle (radians) a handle may have: far
/// beyond any picture, and small enough that blending transforms can never overflow.
pub const MAX_POSE: f64 = 1e9;
/// The smallest scale a point handle may have.
pub const MIN_SCALE: f64 = 1e-9;

/// Handles closer than this (pixels) are the same place, and refused
/// ([`RigError::Coincident`]); any farther apart can be placed (a picture's mesh is
/// refined around them).
pub const COINCIDENT: f64 = 1e-6;
/// The largest scale a point handle may have.
pub const MAX_SCALE: f64 = 1e9;

fn check_handle(i: usize, h: &Handle) -> Result<(), RigError> {
    let in_range = |x: f64| x.abs() <= MAX_POSE;
    match h {
        Handle::Point { rest, transform } => {
            if !rest.is_finite() || !transform.is_finite() {
                return Err(RigError::NonFinite { handle: i });
            }
            if transform.scale <= 0.0 {
                return Err(RigError::BadScale { handle: i });
            }
            if !(MIN_SCALE..=MAX_SCALE).contains(&transform.scale)
                || !in_range(transform.rotation)
                || !transform.translation.to_array().into_iter().all(in_range)
            {
                return Err(RigError::PoseOutOfRange { handle: i });
            }
        }
        Handle::Bar { rest, pose } => {
            if !rest.iter().chain(pose).all(|p| p.is_finite()) {
                return Err(RigError::NonFinite { handle: i });
            }
            if rest[0] == rest[1] {
                return Err(RigError::ZeroLengthBar { handle: i });
            }
            if !pose.iter().flat_map(|p| p.to_array()).all(in_range) {
                return Err(RigError::PoseOutOfRange { handle: i });
            }
        }
    }
    Ok(())
}

fn check_handles(handles: &[Handle]) -> Result<(), RigError> {
    handles
        .iter()
        .enumerate()
        .try_for_each(|(i, h)| check_handle(i, h))
}

/// The closest two handles `(a, b, distance)` with `a < b`, by segment distance (of
/// equally close pairs, the lowest `b`, then the lowest `a`).
fn closest_pair(handles: &[Handle]) -> Option<(usize, usize, f64)> {
    let segments: Vec<[DVec2; 2]> = handles.iter().map(segment_of).collect();
    crate::nearest::closest_pair(&segments)
}

/// The finest a bar is cut: into this many pieces.
///
/// The paper samples bars at the smallest distance between two handles. A point placed
/// a few pixels from a long bar would then cut it into a hundred samples, each with a
/// tiny r_h, and Algorithm 1 would ring every one of them with virtual handles (seconds
/// of work and thousands of nodes). Sixteen pieces keep a bar straight in practice.
pub const MAX_BAR_PIECES: f64 = 16.0;

/// The sample spacing d of bar handle `bar`: its distance to the nearest other handle
/// (the paper takes the smallest distance between any two handles; measured from each
/// bar, a handle placed far from every bar leaves their samples alone, so inserting it
/// stays local), but no finer than the bar over [`MAX_BAR_PIECES`], or an eighth of the
/// bar when it is the only handle. A rig never samples finer than its mesh's mean edge
/// length. (For a point handle: the distance to the nearest other handle.)
pub fn bar_spacing(handles: &[Handle], bar: usize) -> f64 {
    let own = segment_of(&handles[bar]);
    let nearest = (0..handles.len())
        .filter(|&j| j != bar)
        .map(|j| segment_distance(own, segment_of(&handles[j])))
        .fold(f64::INFINITY, f64::min);
    spacing_of(own, nearest)
}

/// [`bar_spacing`] in a rig with the handles `overlaid` (ascending indices): a bar
/// of the partition counts the partition's other handles; an overlaid bar those and
/// the overlaid handles before it.
pub fn bar_spacing_overlaid(handles: &[Handle], overlaid: &[usize], bar: usize) -> f64 {
    let is_overlaid = |i: usize| overlaid.binary_search(&i).is_ok();
    let own = segment_of(&handles[bar]);
    let nearest = (0..handles.len())
        .filter(|&j| j != bar && (!is_overlaid(j) || (is_overlaid(bar) && j < bar)))
        .map(|j| segment_distance(own, segment_of(&handles[j])))
        .fold(f64::INFINITY, f64::min);
    spacing_of(own, nearest)
}

/// [`bar_spacing`] of the bar `own` with its nearest other handle `nearest` away.
fn spacing_of(own: [DVec2; 2], nearest: f64) -> f64 {
    let length = (own[1] - own[0]).length();
    if nearest.is_finite() {
        nearest.max(length / MAX_BAR_PIECES)
    } else {
        length / 8.0
    }
}

/// The spacing of pinned border samples with a fixed boundary: the smallest distance
/// between two handles, but no finer than the longest bar over [`MAX_BAR_PIECES`] (an
/// eighth of it, or of nothing, with a single handle).
fn boundary_spacing(handles: &[Handle]) -> f64 {
    let longest_bar = handles
        .iter()
        .map(|h| match h {
            Handle::Bar { rest, .. } => (rest[1] - rest[0]).length(),
            Handle::Point { .. } => 0.0,
        })
        .fold(0.0, f64::max);
    match closest_pair(handles) {
        Some((_, _, d)) => d.max(longest_bar / MAX_BAR_PIECES),
        None => longest_bar / 8.0,
    }
}

/// The ⌈L/d⌉ + 1 samples `(t, point)` of the bar `rest` at spacing `d`, ends included.
pub fn bar_samples(rest: [DVec2; 2], spacing: f64) -> Vec<(f64, DVec2)> {
    let ratio = (rest[1] - rest[0]).length() / spacing;
    let pieces = if ratio.is_finite() {
        ratio.ceil().clamp(1.0, 1e6) as usize
    } else {
        1
    };
    (0..=pieces)
        .map(|s| {
            let t = s as f64 / pieces as f64;
            (t, rest[0].lerp(rest[1], t))
        })
        .collect()
}

fn segment_of(h: &Handle) -> [DVec2; 2] {
    match *h {
        Handle::Point { rest, .. } => [rest, rest],
        Handle::Bar { rest, .. } => rest,
    }
}

/// Checks the handles apart from any shape: at most [`MAX_HANDLES`], finite, no two at
/// one place ([`COINCIDENT`]).
fn check_handle_set(handles: &[Handle]) -> Result<(), RigError> {
    if handles.len() > MAX_HANDLES {
        return Err(RigError::TooManyHandles {
            count: handles.len(),
            max: MAX_HANDLES,
        });
    }
    check_handles(handles)?;
    if let Some((a, b)) = closest_pair(handles)
        .filter(|p| p.2 < COINCIDENT)
        .map(|p| (p.0, p.1))
    {
        return Err(RigError::Coincident { a, b });
    }
    Ok(())
}

/// Where the bar `rest` leaves `domain`'s shape (an end off it, else the second end),
/// or `None` when the whole bar lies on it.
fn bar_off_shape(domain: &Domain, rest: [DVec2; 2]) -> Option<DVec2> {
    (!domain.contains_segment(rest[0], rest[1])).then(|| {
        if domain.locate(rest[0]).is_none() {
            rest[0]
        } else {
            rest[1]
        }
    })
}

/// Checks `handles` as a rig on `domain` would take them, without building one: at
/// most [`MAX_HANDLES`], finite, no two at one place ([`COINCIDENT`]), every point on
/// the shape and every bar wholly on it. What another method set up on the same mesh
/// refuses alike.
///
/// # Errors
/// The first handle refused, as [`Rig::new`] names it.
pub fn check_handles_on(domain: &Domain, handles: &[Handle]) -> Result<(), RigError> {
    check_handle_set(handles)?;
    for (handle, h) in handles.iter().enumerate() {
        let outside = match h {
            Handle::Point { rest, .. } => domain.locate(*rest).is_none().then_some(*rest),
            Handle::Bar { rest, .. } => bar_off_shape(domain, *rest),
        };
        if let Some(p) = outside {
            return Err(RigError::OutsideDomain {
                handle,
                x: p.x,
                y: p.y,
            });
        }
    }
    Ok(())
}

/// The nodes of the handles (and of the pinned border), each on a sample: a point on
/// the nearest corner of the triangle containing it, bars split into ⌈L/d⌉ pieces with
/// d from [`bar_spacing`] (no smaller than the mean edge length).
///
/// Returns the partition's nodes, and apart the samples of the `overlaid` handles (in
/// handle order). A bar is cut at its distance to the nearest handle that counts for
/// it: for a partition bar the other partition handles; for an overlaid one those and
/// the overlaid handles before it (so a handle placed later re-cuts nothing).
fn real_nodes(
    domain: &Domain,
    handles: &[Handle],
    overlaid: &[bool],
    options: &RigOptions,
    resolution: f64,
) -> Result<(Vec<Node>, Vec<Node>), RigError> {
    check_handle_set(handles)?;
    let snap = |i: usize, p: DVec2| -> Result<u32, RigError> {
        let (t, bary) = domain.locate(p).ok_or(RigError::OutsideDomain {
            handle: i,
            x: p.x,
            y: p.y,
        })?;
        let tri = domain.triangles()[t];
        let best = (0..3)
            .max_by(|&a, &b| {
                bary[a]
                    .total_cmp(&bary[b])
                    .then(domain.rank(tri[b]).cmp(&domain.rank(tri[a])))
            })
            .unwrap_or(0);
        Ok(tri[best])
    };
    // The nearest other partition handle of each bar, through a grid of them.
    let is_overlaid = |i: usize| overlaid.get(i) == Some(&true);
    let base: Vec<usize> = (0..handles.len()).filter(|&i| !is_overlaid(i)).collect();
    let segments: Vec<[DVec2; 2]> = base.iter().map(|&i| segment_of(&handles[i])).collect();
    let bars = crate::nearest::SegmentGrid::new(&segments);
    let nearest = |i: usize| -> f64 {
        if is_overlaid(i) {
            let own = segment_of(&handles[i]);
            (0..handles.len())
                .filter(|&j| j != i && (!is_overlaid(j) || j < i))
                .map(|j| segment_distance(own, segment_of(&handles[j])))
                .fold(f64::INFINITY, f64::min)
        } else {
            bars.nearest(base.binary_search(&i).unwrap_or(0))
        }
    };
    let mut nodes: Vec<Node> = Vec::new();
    let mut over: Vec<Node> = Vec::new();
    let mut used: HashMap<u32, usize> = HashMap::new();
    for (i, h) in handles.iter().enumerate() {
        let mut own: Vec<Node> = Vec::new();
        match *h {
            Handle::Point { rest, .. } => own.push(Node {
                vertex: snap(i, rest)?,
                kind: NodeKind::Point { handle: i },
            }),
            Handle::Bar { rest, .. } => {
                // The whole bar must lie on the shape, not only its samples.
                if let Some(p) = bar_off_shape(domain, rest) {
                    return Err(RigError::OutsideDomain {
                        handle: i,
                        x: p.x,
                        y: p.y,
                    });
                }
                let spacing = spacing_of(rest, nearest(i)).max(resolution);
                for (t, p) in bar_samples(rest, spacing) {
                    let v = snap(i, p)?;
                    if own.iter().all(|n| n.vertex != v) {
                        own.push(Node {
                            vertex: v,
                            kind: NodeKind::BarSample { handle: i, t },
                        });
                    }
                }
            }
        }
        for n in own {
            if let Some(&j) = used.get(&n.vertex) {
                return Err(RigError::SameSample { a: j, b: i });
            }
            used.insert(n.vertex, i);
            if is_overlaid(i) {
                over.push(n);
            } else {
                nodes.push(n);
            }
        }
    }
    if options.fixed_boundary {
        let partition_handles: Vec<Handle> = base.iter().map(|&i| handles[i].clone()).collect();
        let spacing = boundary_spacing(&partition_handles).max(resolution);
        let positions = domain.positions();
        for ring in domain.boundary_loops() {
            let mut since = f64::INFINITY;
            let mut prev = positions[ring[0] as usize];
            for &v in ring {
                since += (positions[v as usize] - prev).length();
                prev = positions[v as usize];
                if since >= spacing && !used.contains_key(&v) {
                    used.insert(v, usize::MAX);
                    nodes.push(Node {
                        vertex: v,
                        kind: NodeKind::Boundary,
                    });
                    since = 0.0;
                }
            }
        }
    }
    Ok((nodes, over))
}
