//! The C² weights of Xian, Jin and Wang (`weights-core`) behind the method seam: a
//! [`Rig`] is its own deformer. It draws skinned: sparse weights per vertex and one
//! affine map per node (handle, bar sample, border pin or virtual handle).

use std::any::Any;
use std::time::Instant;

use anyhow::Result;
use glam::DVec2;
use project::Project;
use serde::Serialize;
use weights_core::{Handle, Metric, NodeKind, Rig};

use crate::deformer::{
    Deformer, Follow, Method, Output, SkinTable, Skinning, WeightsListing, json, median, quantile,
};

impl Skinning for Rig {
    fn table(&self) -> SkinTable {
        let (rows, nodes, weights) = self.weight_table();
        SkinTable {
            rows,
            nodes,
            weights,
        }
    }

    fn transforms(&self) -> Vec<render::Affine> {
        self.node_affines()
    }
}

impl Deformer for Rig {
    fn method(&self) -> Method {
        Method::C2
    }

    fn rest(&self) -> &[DVec2] {
        self.domain().positions()
    }

    fn triangles(&self) -> &[[u32; 3]] {
        self.domain().triangles()
    }

    fn follow(&mut self, project: &Project) -> Result<Follow> {
        if crate::rig_options(project)? != *self.options() {
            return Ok(Follow::NeedsSetup);
        }
        self.set_handles_overlaid(crate::handles(project), &project.overlaid)?;
        Ok(Follow::Followed)
    }

    fn deformed(&self) -> Vec<DVec2> {
        match self.overlaid_picture() {
            Some(picture) => picture.to_vec(),
            None => self.deform(),
        }
    }

    fn output(&self) -> Output<'_> {
        match self.overlaid_picture() {
            Some(picture) => Output::Positions(picture),
            None => Output::Skinned(self),
        }
    }

    fn weights(&self, listing: WeightsListing) -> Result<serde_json::Value> {
        weights_json(self, listing, None)
    }

    /// The build's phases (as measured when it was built), insertions and removals of
    /// a point handle at `poses` random samples, and deformation.
    fn bench(&mut self, _project: &Project, poses: usize) -> Result<serde_json::Value> {
        let positions = self.domain().positions().to_vec();
        bench(self, poses, &positions)
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn clone_box(&self) -> Box<dyn Deformer> {
        Box::new(self.clone())
    }
}

/// A C² rig on a given mesh (`--mesh`), built on the mesh renumbered along a Z-order
/// curve ([`weights_core::Domain::in_local_order`]) and answering in the file's
/// numbering (the file's vertices in its order, the vertices inserted for handles
/// after them): the weights, rest mesh and deformed vertices of a rig built on the
/// file as numbered, ties between vertices broken by the file's numbers as there.
///
/// A mesh generator numbers its vertices in the order it makes them: Triangle puts a
/// triangle's corners a median 2,000 numbers apart on a 100k-vertex mesh, so every
/// step of the rig's graph searches (Algorithm 1's Voronoi updates, the supports'
/// distance fields) reads memory far from the last. A picture's own mesh is numbered
/// along the curve already.
#[derive(Clone)]
pub struct MeshRig {
    rig: Rig,
    /// The rig's sample of each file vertex…
    sample: Vec<u32>,
    /// …and the file vertex of each sample.
    vertex: Vec<u32>,
    /// The file's vertices (with the inserted ones) and triangles.
    rest: Vec<DVec2>,
    triangles: Vec<[u32; 3]>,
    /// The overlaid picture's positions, by file vertex (see [`Rig::overlaid_picture`]).
    overlaid: Option<Vec<DVec2>>,
}

impl MeshRig {
    /// `rig`, built on a renumbering of the mesh `rest`, `triangles` (the file's, with
    /// the vertices inserted for handles after its own): `sample[v]` is the rig's
    /// sample of vertex `v`, and the rig's triangles are the file's in the same order,
    /// renumbered.
    pub fn new(rig: Rig, sample: Vec<u32>, rest: Vec<DVec2>, triangles: Vec<[u32; 3]>) -> Self {
        debug_assert_eq!(sample.len(), rig.domain().len());
        let mut vertex = vec![0; sample.len()];
        for (v, &s) in sample.iter().enumerate() {
            vertex[s as usize] = v as u32;
        }
        let mut this = Self {
            rig,
            sample,
            vertex,
            rest,
            triangles,
            overlaid: None,
        };
        this.overlaid = this.rig.overlaid_picture().map(|p| this.in_file_order(p));
        this
    }

    /// The rig (in its own numbering).
    pub fn rig(&self) -> &Rig {
        &self.rig
    }

    /// Per-sample values of the rig, by file vertex.
    fn in_file_order<T: Copy>(&self, by_sample: &[T]) -> Vec<T> {
        self.sample.iter().map(|&s| by_sample[s as usize]).collect()
    }
}

impl Skinning for MeshRig {
    fn table(&self) -> SkinTable {
        let (rows, nodes, weights) = self.rig.weight_table();
        let mut table = SkinTable {
            rows: Vec::with_capacity(rows.len()),
            nodes: Vec::with_capacity(nodes.len()),
            weights: Vec::with_capacity(weights.len()),
        };
        table.rows.push(0);
        for &s in &self.sample {
            let row = rows[s as usize] as usize..rows[s as usize + 1] as usize;
            table.nodes.extend_from_slice(&nodes[row.clone()]);
            table.weights.extend_from_slice(&weights[row]);
            table.rows.push(table.nodes.len() as u32);
        }
        table
    }

    fn transforms(&self) -> Vec<render::Affine> {
        self.rig.node_affines()
    }
}

impl Deformer for MeshRig {
    fn method(&self) -> Method {
        Method::C2
    }

    fn rest(&self) -> &[DVec2] {
        &self.rest
    }

    fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    fn follow(&mut self, project: &Project) -> Result<Follow> {
        let follow = self.rig.follow(project)?;
        self.overlaid = self.rig.overlaid_picture().map(|p| self.in_file_order(p));
        Ok(follow)
    }

    fn deformed(&self) -> Vec<DVec2> {
        self.in_file_order(&self.rig.deformed())
    }

    fn output(&self) -> Output<'_> {
        match &self.overlaid {
            Some(picture) => Output::Positions(picture),
            None => Output::Skinned(self),
        }
    }

    fn weights(&self, listing: WeightsListing) -> Result<serde_json::Value> {
        weights_json(&self.rig, listing, Some((&self.sample, &self.vertex)))
    }

    /// As a rig on the file's numbering times it: the same positions, by file vertex.
    fn bench(&mut self, _project: &Project, poses: usize) -> Result<serde_json::Value> {
        bench(&mut self.rig, poses, &self.rest)
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn clone_box(&self) -> Box<dyn Deformer> {
        Box::new(self.clone())
    }
}

/// `c2warp weights` for `rig`: with `numbering` (the rig's sample of each file vertex,
/// and the file vertex of each sample), by file vertex.
fn weights_json(
    rig: &Rig,
    listing: WeightsListing,
    numbering: Option<(&[u32], &[u32])>,
) -> Result<serde_json::Value> {
    let positions = rig.domain().positions();
    let n = rig.domain().len();
    let sample = |v: usize| numbering.map_or(v, |(sample, _)| sample[v] as usize);
    let vertex = |s: u32| numbering.map_or(s, |(_, vertex)| vertex[s as usize]);
    let nodes = rig
        .nodes()
        .iter()
        .enumerate()
        .map(|(k, n)| NodeOut {
            index: k,
            kind: match n.kind {
                NodeKind::Point { .. } => "point",
                NodeKind::BarSample { .. } => "bar_sample",
                NodeKind::Boundary => "boundary",
                NodeKind::Virtual => "virtual",
            },
            vertex: vertex(n.vertex),
            position: positions[n.vertex as usize].to_array(),
            handle: rig.owner_handle(k),
            support: Some(rig.radii(k).support).filter(|r| r.is_finite()),
        })
        .collect();
    json(&WeightsOut {
        samples: n,
        file_vertices: listing.file_vertices,
        metric: metric_name(rig.domain().metric()),
        nodes,
        vertices: listing
            .positions
            .then(|| (0..n).map(|v| positions[sample(v)].to_array()).collect()),
        weights: (0..n).map(|v| rig.weights(sample(v)).collect()).collect(),
    })
}

/// `c2warp bench` for `rig`: the build's phases (as measured when it was built),
/// insertions and removals of a point handle at `poses` of `positions` (the mesh's
/// vertices, in the order whose random picks the runs share), and deformation.
fn bench(rig: &mut Rig, poses: usize, positions: &[DVec2]) -> Result<serde_json::Value> {
    let timings = rig.timings();
    let stats = rig.stats();
    let mut deform = Vec::new();
    let mut out = vec![DVec2::ZERO; rig.domain().len()];
    for _ in 0..15 {
        let t = Instant::now();
        rig.deform_into(&mut out);
        deform.push(ms(t));
    }
    let n = positions.len() as u64;
    let mut sequence = crate::deformer::Sequence::new();
    let (mut insert, mut remove) = (Vec::new(), Vec::new());
    let mut tries = 0;
    while insert.len() < poses && tries < poses * 10 {
        tries += 1;
        let p = positions[(sequence.next_u64() % n) as usize];
        let t = Instant::now();
        let Ok(index) = rig.insert_handle(Handle::point(p)) else {
            continue;
        };
        insert.push(ms(t));
        let t = Instant::now();
        rig.remove_handle(index)?;
        remove.push(ms(t));
    }
    json(&Report {
        samples: stats.samples,
        triangles: rig.domain().triangles().len(),
        metric: metric_name(rig.domain().metric()),
        real_handles: stats.real_handles,
        handle_nodes: stats.handle_nodes,
        boundary_nodes: stats.boundary_nodes,
        virtual_handles: stats.virtual_nodes,
        build_ms: Phases {
            distances: timings.distances_ms,
            voronoi: timings.voronoi_ms,
            virtual_handles: timings.virtual_ms,
            weights: timings.weights_ms,
            total: timings.total_ms(),
        },
        positions: insert.len(),
        insert_ms_p90: quantile(insert.clone(), 0.9),
        insert_ms_median: median(insert),
        remove_ms_p90: quantile(remove.clone(), 0.9),
        remove_ms_median: median(remove),
        deform_ms_median: median(deform),
        nonzeros: stats.nonzeros,
        weight_bytes_per_nonzero: stats.weight_bytes as f64 / stats.nonzeros.max(1) as f64,
    })
}

fn metric_name(metric: Metric) -> &'static str {
    match metric {
        Metric::Euclidean => "euclidean",
        Metric::Intrinsic => "intrinsic",
    }
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

#[derive(Serialize)]
struct NodeOut {
    /// Index used in the weight lists.
    index: usize,
    /// "point", "bar_sample", "boundary" or "virtual".
    kind: &'static str,
    /// Mesh vertex the node sits on.
    vertex: u32,
    /// Rest position in pixels.
    position: [f64; 2],
    /// The real handle it belongs to (for a virtual handle: the one with the largest
    /// harmonic coordinate); null for border pins.
    handle: Option<usize>,
    /// Support radius in pixels (null when unbounded).
    support: Option<f64>,
}

#[derive(Serialize)]
struct WeightsOut {
    samples: usize,
    file_vertices: usize,
    metric: &'static str,
    nodes: Vec<NodeOut>,
    /// Vertex positions (only when the mesh was made from an image).
    #[serde(skip_serializing_if = "Option::is_none")]
    vertices: Option<Vec<[f64; 2]>>,
    /// Per vertex, in order: the non-zero `[node index, weight]` pairs.
    weights: Vec<Vec<(usize, f64)>>,
}

#[derive(Serialize)]
struct Phases {
    distances: f64,
    voronoi: f64,
    virtual_handles: f64,
    weights: f64,
    total: f64,
}

#[derive(Serialize)]
struct Report {
    samples: usize,
    triangles: usize,
    metric: &'static str,
    real_handles: usize,
    handle_nodes: usize,
    boundary_nodes: usize,
    virtual_handles: usize,
    /// Full build (distances, Voronoi, virtual handles, weights), ms.
    build_ms: Phases,
    /// Median time to insert one point handle at a random sample, weights up to date.
    insert_ms_median: f64,
    /// 90th percentile of the insertions.
    insert_ms_p90: f64,
    /// Median time to remove it again.
    remove_ms_median: f64,
    /// 90th percentile of the removals.
    remove_ms_p90: f64,
    /// Positions tried.
    positions: usize,
    /// Median time to deform every sample with the sparse weights.
    deform_ms_median: f64,
    nonzeros: usize,
    weight_bytes_per_nonzero: f64,
}
