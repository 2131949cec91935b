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
        let positions = self.domain().positions();
        let nodes = self
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
                vertex: n.vertex,
                position: positions[n.vertex as usize].to_array(),
                handle: self.owner_handle(k),
                support: Some(self.radii(k).support).filter(|r| r.is_finite()),
            })
            .collect();
        json(&WeightsOut {
            samples: self.domain().len(),
            file_vertices: listing.file_vertices,
            metric: metric_name(self.domain().metric()),
            nodes,
            vertices: listing
                .positions
                .then(|| positions.iter().map(|p| p.to_array()).collect()),
            weights: (0..self.domain().len())
                .map(|v| self.weights(v).collect())
                .collect(),
        })
    }

    /// The build's phases (as measured when it was built), insertions and removals of
    /// a point handle at `poses` random samples, and deformation.
    fn bench(&mut self, _project: &Project, poses: usize) -> Result<serde_json::Value> {
        let timings = self.timings();
        let stats = self.stats();
        let mut deform = Vec::new();
        let mut out = vec![DVec2::ZERO; self.domain().len()];
        for _ in 0..15 {
            let t = Instant::now();
            self.deform_into(&mut out);
            deform.push(ms(t));
        }
        let n = self.domain().len() as u64;
        let mut sequence = crate::deformer::Sequence::new();
        let (mut insert, mut remove) = (Vec::new(), Vec::new());
        let mut tries = 0;
        while insert.len() < poses && tries < poses * 10 {
            tries += 1;
            let p = self.domain().positions()[(sequence.next_u64() % n) as usize];
            let t = Instant::now();
            let Ok(index) = self.insert_handle(Handle::point(p)) else {
                continue;
            };
            insert.push(ms(t));
            let t = Instant::now();
            self.remove_handle(index)?;
            remove.push(ms(t));
        }
        json(&Report {
            samples: stats.samples,
            triangles: self.domain().triangles().len(),
            metric: metric_name(self.domain().metric()),
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

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn clone_box(&self) -> Box<dyn Deformer> {
        Box::new(self.clone())
    }
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
