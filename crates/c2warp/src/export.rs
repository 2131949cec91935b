//! `c2warp weights`: the nodes and sparse weights of a rig, as JSON.

use std::path::Path;

use anyhow::{Context, Result};
use glam::DVec2;
use project::Project;
use serde::Serialize;
use weights_core::{Domain, Handle, NodeKind, Rig, VirtualHandle};

use crate::Source;
use pipeline::{load_image, load_project};

/// A rig built from a `--mesh` or `--image` source.
pub struct Built {
    /// The rig.
    pub rig: Rig,
    /// Vertices the mesh file had; later ones were inserted for handles.
    pub file_vertices: usize,
    /// The picture meshed (`--image`), for a method that meshes it again its own way.
    pub picture: Option<image::RgbaImage>,
}

/// Builds the rig of `project` on the source's samples.
///
/// With `--mesh`, the file's vertices are used as given, in file order; a handle (or
/// bar sample) that coincides with a vertex uses it, and one that does not is inserted
/// as a new vertex, splitting the triangle (or edge) it lies on. Inserted vertices come
/// after the file's.
///
/// `progress` hears how far the rig build has come (see [`weights_core::Progress`]).
pub fn build(
    source: &Source,
    project: &Project,
    progress: &(dyn Fn(weights_core::Progress) + Sync),
) -> Result<Built> {
    if let Some(density) = source.density {
        project::validate_density(density)?;
    }
    if let Some(path) = &source.image {
        let picture = load_image(path)?;
        let prepared =
            pipeline::prepare_with_progress(&picture, project, source.density, progress)?;
        let file_vertices = prepared.rig.domain().len();
        return Ok(Built {
            rig: prepared.rig,
            file_vertices,
            picture: Some(picture),
        });
    }
    let path = source.mesh.as_deref().context("give --mesh or --image")?;
    let mut mesh = pipeline::load_obj(path)?;
    mesh.sanity_check()
        .with_context(|| format!("mesh {}", path.display()))?;
    project.validate(None)?;
    let file_vertices = mesh.vertices.len();
    // Each virtual handle takes a vertex of its own; more than the mesh has cannot have
    // been saved on it (and would each be inserted into it, one by one).
    anyhow::ensure!(
        project.virtual_handles.len() <= file_vertices,
        "the rig lists {} virtual handles, more than the {file_vertices} vertices of mesh {} \
         (at most one a vertex); leave out \"virtual_handles\" to have them placed afresh",
        project.virtual_handles.len(),
        path.display()
    );
    let handles = pipeline::handles(project);
    let mut points: Vec<DVec2> = Vec::new();
    for (i, h) in handles.iter().enumerate() {
        match h {
            Handle::Point { rest, .. } => points.push(*rest),
            Handle::Bar { rest, .. } => points.extend(
                weights_core::bar_samples(*rest, weights_core::bar_spacing(&handles, i))
                    .into_iter()
                    .map(|(_, p)| p),
            ),
        }
    }
    points.extend(project.virtual_handles.iter().map(|&p| DVec2::from(p)));
    let mut virtual_handles = Vec::new();
    let first_virtual = points.len() - project.virtual_handles.len();
    for (i, p) in points.into_iter().enumerate() {
        let v = mesh
            .insert_point(p)
            .with_context(|| format!("handle point ({}, {}) is not on the mesh", p.x, p.y))?;
        if i >= first_virtual {
            virtual_handles.push(VirtualHandle {
                vertex: v,
                placed_for: project
                    .virtual_placed_for
                    .get(i - first_virtual)
                    .copied()
                    .flatten(),
            });
        }
    }
    let provisional = Domain::new(
        mesh.vertices.clone(),
        mesh.triangles.clone(),
        weights_core::Metric::Intrinsic,
    )?;
    let metric = pipeline::metric(project.metric, provisional.is_convex());
    let domain = Domain::new(mesh.vertices, mesh.triangles, metric)?;
    let rig = Rig::with_progress(
        domain,
        handles,
        &virtual_handles,
        pipeline::rig_options(project)?,
        progress,
    )?;
    Ok(Built {
        rig,
        file_vertices,
        picture: None,
    })
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

/// Runs `c2warp weights`.
pub fn weights(source: &Source, rig_path: &Path, output: &Path) -> Result<()> {
    let project = load_project(rig_path)?;
    if project.method == project::Method::Lbc {
        return crate::lbc::weights(source, &project, output);
    }
    let progress = crate::progress::Steps::new(2);
    progress.step("meshing and weighting");
    let Built {
        rig, file_vertices, ..
    } = build(source, &project, &progress.weighting())?;
    progress.step("writing");
    let positions = rig.domain().positions();
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
            vertex: n.vertex,
            position: positions[n.vertex as usize].to_array(),
            handle: rig.owner_handle(k),
            support: Some(rig.radii(k).support).filter(|r| r.is_finite()),
        })
        .collect();
    let out = WeightsOut {
        samples: rig.domain().len(),
        file_vertices,
        metric: match rig.domain().metric() {
            weights_core::Metric::Euclidean => "euclidean",
            weights_core::Metric::Intrinsic => "intrinsic",
        },
        nodes,
        vertices: source
            .image
            .as_ref()
            .map(|_| positions.iter().map(|p| p.to_array()).collect()),
        weights: (0..rig.domain().len())
            .map(|v| rig.weights(v).collect())
            .collect(),
    };
    let text = serde_json::to_string(&out)?;
    crate::write_text(output, text.as_bytes())?;
    progress.finish();
    Ok(())
}
