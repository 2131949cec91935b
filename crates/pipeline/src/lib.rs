//! Image + project → mesh → rig → warped image: the path the `c2warp` command line and
//! the editor share, so an export from either gives the same pixels.

use anyhow::{Context, Result, bail};
use glam::{DVec2, Vec2};
use image::RgbaImage;
use mesh::{Constraints, DomainOptions, MeshOptions};
use project::{HandleSpec, MetricChoice, Middle, Project};
use weights_core::{Basis, Domain, Handle, Metric, MiddleControls, Rig, RigOptions, Similarity};

/// The picture the editor opens with and the demo warps (public domain, see
/// `assets/LICENSES.md`).
pub const DEFAULT_IMAGE: &[u8] = include_bytes!("../../../assets/lizard.png");
/// The sample rig on [`DEFAULT_IMAGE`].
pub const DEFAULT_RIG: &str = include_str!("../../../assets/lizard-rig.json");

/// Reads and parses a rig file.
///
/// # Errors
/// An unreadable file or malformed rig, naming the file.
pub fn load_project(path: &std::path::Path) -> Result<Project> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read rig file {}", path.display()))?;
    Project::from_json(&text).with_context(|| format!("rig file {}", path.display()))
}

/// Decodes an image file under the default size limits.
///
/// # Errors
/// A missing, corrupt, truncated, unsupported or oversized image, as one sentence.
pub fn load_image(path: &std::path::Path) -> Result<RgbaImage> {
    Ok(render::load_image(path, &render::ImageLimits::default())?)
}

/// Target vertex count of the mesh when neither the project nor the command says.
pub const DEFAULT_DENSITY: usize = 20_000;

/// The user handles of a project.
pub fn handles(project: &Project) -> Vec<Handle> {
    project
        .handles
        .iter()
        .map(|h| match *h {
            HandleSpec::Point {
                rest,
                translate,
                rotate,
                scale,
            } => Handle::Point {
                rest: DVec2::from(rest),
                transform: Similarity {
                    translation: DVec2::from(translate),
                    rotation: rotate,
                    scale,
                },
            },
            HandleSpec::Bar { rest, pose } => {
                let rest = rest.map(DVec2::from);
                Handle::Bar {
                    rest,
                    pose: pose.map_or(rest, |p| p.map(DVec2::from)),
                }
            }
        })
        .collect()
}

/// The weighting options of a project.
pub fn rig_options(project: &Project) -> Result<RigOptions> {
    let middle = match project.middle {
        Middle::Half => MiddleControls::Half,
        Middle::Linear => MiddleControls::Linear,
    };
    let basis = Basis::new(project.degree, middle)
        .with_context(|| format!("unsupported basis degree {}", project.degree))?;
    Ok(RigOptions {
        alpha: project.alpha,
        basis,
        fixed_boundary: project.fixed_boundary,
    })
}

/// The metric for a mesh: the project's choice, or Euclidean exactly when the domain
/// is convex.
pub fn metric(choice: MetricChoice, convex: bool) -> Metric {
    match choice {
        MetricChoice::Euclidean => Metric::Euclidean,
        MetricChoice::Intrinsic => Metric::Intrinsic,
        MetricChoice::Auto if convex => Metric::Euclidean,
        MetricChoice::Auto => Metric::Intrinsic,
    }
}

/// Points the mesh must have as vertices: point handles, then virtual handles; and one
/// polyline of samples per bar.
fn constraints(project: &Project, handles: &[Handle]) -> (Vec<DVec2>, Vec<Vec<DVec2>>) {
    let mut points = Vec::new();
    let mut bars = Vec::new();
    for (i, h) in handles.iter().enumerate() {
        match h {
            Handle::Point { rest, .. } => points.push(*rest),
            Handle::Bar { rest, .. } => bars.push(
                weights_core::bar_samples(*rest, weights_core::bar_spacing(handles, i))
                    .into_iter()
                    .map(|(_, p)| p)
                    .collect(),
            ),
        }
    }
    points.extend(project.virtual_handles.iter().map(|&p| DVec2::from(p)));
    (points, bars)
}

/// A project's rig on an image: the image meshed with its handles as vertices, then
/// weighted.
pub struct Prepared {
    /// The weighted rig (its domain is the mesh).
    pub rig: Rig,
}

/// Meshes `image` for `project` (at `density` vertices, else the project's, else the
/// default) and builds the rig.
///
/// # Errors
/// Handles off the image or the shape, coincident handles, an image with no opaque
/// pixel, and the like, each as one sentence.
pub fn prepare(image: &RgbaImage, project: &Project, density: Option<usize>) -> Result<Prepared> {
    project.validate(Some(image.dimensions()))?;
    let handles = handles(project);
    let (points, bars) = constraints(project, &handles);
    let options = MeshOptions {
        target_vertices: density.or(project.density).unwrap_or(DEFAULT_DENSITY),
        ..MeshOptions::default()
    };
    let mesh = mesh::mesh_image(
        image,
        &DomainOptions::default(),
        &options,
        &Constraints {
            points: &points,
            polylines: &bars,
        },
    )
    .context("cannot mesh the image")?;
    let virtual_vertices: Vec<u32> =
        mesh.point_vertices[points.len() - project.virtual_handles.len()..].to_vec();
    let domain = Domain::new(
        mesh.mesh.vertices.clone(),
        mesh.mesh.triangles.clone(),
        metric(project.metric, mesh.is_convex),
    )?;
    let rig = Rig::with_virtual_handles(domain, handles, &virtual_vertices, rig_options(project)?)?;
    Ok(Prepared { rig })
}

/// The rig's samples at rest in f32: the texture coordinates of the mesh.
fn rest_positions(rig: &Rig) -> Vec<Vec2> {
    rig.domain()
        .positions()
        .iter()
        .map(|p| p.as_vec2())
        .collect()
}

/// The image warped by the rig's current pose on the GPU (or a software adapter): the
/// vertex shader blends the node transforms with the sparse weights.
///
/// # Errors
/// No adapter, or a GPU failure.
pub fn warp_gpu(image: &RgbaImage, rig: &Rig) -> Result<RgbaImage> {
    let gpu = render::GpuContext::new()?;
    let (rows, nodes, weights) = rig.weight_table();
    let rest = rest_positions(rig);
    let mesh = render::SkinnedMesh {
        rest: &rest,
        rows: &rows,
        nodes: &nodes,
        weights: &weights,
        triangles: rig.domain().triangles(),
    };
    let (w, h) = image.dimensions();
    Ok(gpu.warp_skinned(image, &mesh, &rig.node_affines(), w, h)?)
}

/// The image warped by the rig's current pose, at the image's full resolution.
///
/// # Errors
/// Only if the deformation produced non-finite positions.
pub fn warp(image: &RgbaImage, rig: &Rig) -> Result<RgbaImage> {
    let deformed = rig.deform();
    if deformed.iter().any(|p| !p.is_finite()) {
        bail!("the deformation produced non-finite positions");
    }
    let rest = rest_positions(rig);
    let deformed: Vec<Vec2> = deformed.iter().map(|p| p.as_vec2()).collect();
    let mesh = render::WarpMesh {
        rest: &rest,
        deformed: &deformed,
        triangles: rig.domain().triangles(),
    };
    let (w, h) = image.dimensions();
    Ok(render::warp_cpu(
        image,
        &mesh,
        w,
        h,
        &render::RasterOptions::default(),
    )?)
}
