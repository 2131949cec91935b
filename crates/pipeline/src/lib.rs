//! Image + project → mesh → rig → warped image: the path the `c2warp` command line and
//! the editor share, so an export from either gives the same pixels.

use anyhow::{Context, Result, bail};
use glam::{DVec2, Vec2};
use image::RgbaImage;
use mesh::{Constraints, DomainOptions, MeshOptions};
use project::{HandleSpec, MetricChoice, Middle, Project};
use weights_core::{
    Basis, Domain, Handle, Metric, MiddleControls, Rig, RigOptions, Similarity, VirtualHandle,
};

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

/// The most virtual handles a rig file may list for each vertex the mesh aims at
/// (its density): each virtual handle takes a vertex of its own, and a mesh lands
/// within about 30% of its target, so a file with more was not saved from a rig at
/// this density. Such a file is refused before meshing (2.5 million virtual handles
/// would take minutes and gigabytes).
pub const MAX_VIRTUAL_PER_VERTEX: usize = 2;

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
/// Handles off the image or the shape, coincident handles, more handles than
/// [`project::MAX_HANDLES`], more virtual handles than [`MAX_VIRTUAL_PER_VERTEX`] times
/// the density, an image with no opaque pixel, and the like, each as one sentence.
pub fn prepare(image: &RgbaImage, project: &Project, density: Option<usize>) -> Result<Prepared> {
    prepare_with_progress(image, project, density, &|_| {})
}

/// As [`prepare`], telling `progress` how far the rig build has come (see
/// [`weights_core::Progress`]; meshing, before it, is not reported). It is called from
/// the building threads, often: it should only store the figure.
///
/// # Errors
/// As [`prepare`].
pub fn prepare_with_progress(
    image: &RgbaImage,
    project: &Project,
    density: Option<usize>,
    progress: &(dyn Fn(weights_core::Progress) + Sync),
) -> Result<Prepared> {
    project.validate(Some(image.dimensions()))?;
    let target_vertices = density.or(project.density).unwrap_or(DEFAULT_DENSITY);
    let most = MAX_VIRTUAL_PER_VERTEX.saturating_mul(target_vertices);
    if project.virtual_handles.len() > most {
        bail!(
            "the rig lists {} virtual handles, more than a mesh of about {target_vertices} \
             vertices can carry (each takes a vertex; C2Warp accepts up to twice the \
             density, {most}); leave out \"virtual_handles\" to have them placed afresh",
            project.virtual_handles.len()
        );
    }
    let handles = handles(project);
    let (points, bars) = constraints(project, &handles);
    let options = MeshOptions {
        target_vertices,
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
    let first_virtual = points.len() - project.virtual_handles.len();
    let virtual_handles: Vec<VirtualHandle> = mesh.point_vertices[first_virtual..]
        .iter()
        .enumerate()
        .map(|(i, &vertex)| VirtualHandle {
            vertex,
            placed_for: project.virtual_placed_for.get(i).copied().flatten(),
        })
        .collect();
    let domain = Domain::new(
        mesh.mesh.vertices.clone(),
        mesh.mesh.triangles.clone(),
        metric(project.metric, mesh.is_convex),
    )?;
    let rig = Rig::with_progress(
        domain,
        handles,
        &virtual_handles,
        rig_options(project)?,
        progress,
    )?;
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

#[cfg(test)]
mod tests {
    use super::*;

    fn lizard() -> RgbaImage {
        image::load_from_memory(DEFAULT_IMAGE)
            .expect("the built-in picture decodes")
            .to_rgba8()
    }

    #[test]
    fn the_handle_limits_agree() {
        assert_eq!(project::MAX_HANDLES, weights_core::MAX_HANDLES);
    }

    #[test]
    fn a_rig_with_more_virtual_handles_than_its_mesh_can_carry_is_refused_before_meshing() {
        let mut project = Project::from_json(DEFAULT_RIG).expect("the built-in rig");
        project.density = Some(2000);
        project.virtual_handles = (0..4001)
            .map(|i| [300.0 + (i % 50) as f64 * 0.1, 250.0])
            .collect();
        let clock = std::time::Instant::now();
        let err = prepare(&lizard(), &project, None)
            .err()
            .expect("too many virtual handles")
            .to_string();
        assert!(
            err.contains("4001 virtual handles") && err.contains("up to twice the density, 4000"),
            "{err}"
        );
        assert!(clock.elapsed().as_secs_f64() < 1.0);
    }

    #[test]
    fn virtual_handles_keep_the_handle_they_were_placed_for_through_a_file() {
        let image = lizard();
        let mut project = Project::from_json(DEFAULT_RIG).expect("the built-in rig");
        project.density = Some(5000);
        let mut rig = prepare(&image, &project, None).expect("builds").rig;
        // A handle beside another: virtual handles placed for it.
        let new = rig
            .insert_handle(Handle::point(DVec2::new(446.0, 238.0)))
            .expect("room");
        let placed = rig.placed_virtual_handles();
        let positions = rig.domain().positions();
        assert!(
            placed.iter().any(|v| v.placed_for == Some(new)),
            "{placed:?}"
        );
        let point = |p: DVec2| project::HandleSpec::Point {
            rest: p.to_array(),
            translate: [0.0, 0.0],
            rotate: 0.0,
            scale: 1.0,
        };
        project.handles.push(point(DVec2::new(446.0, 238.0)));
        project.virtual_handles = placed
            .iter()
            .map(|v| positions[v.vertex as usize].to_array())
            .collect();
        project.virtual_placed_for = placed.iter().map(|v| v.placed_for).collect();
        let saved = Project::from_json(&project.to_json()).expect("round trip");
        let mut reloaded = prepare(&image, &saved, None).expect("builds").rig;
        let at = |rig: &Rig, v: &VirtualHandle| {
            let p = rig.domain().positions()[v.vertex as usize];
            ((p.x * 1e6).round() as i64, (p.y * 1e6).round() as i64)
        };
        let theirs: Vec<_> = placed
            .iter()
            .filter(|v| v.placed_for == Some(new))
            .map(|v| at(&rig, v))
            .collect();
        let reloaded_theirs: Vec<_> = reloaded
            .placed_virtual_handles()
            .iter()
            .filter(|v| v.placed_for == Some(new))
            .map(|v| at(&reloaded, v))
            .collect();
        assert_eq!(reloaded_theirs, theirs);
        reloaded.remove_handle(new).expect("exists");
        let left: Vec<_> = reloaded
            .placed_virtual_handles()
            .iter()
            .map(|v| at(&reloaded, v))
            .collect();
        assert!(theirs.iter().all(|p| !left.contains(p)), "{left:?}");
        assert!(
            reloaded
                .placed_virtual_handles()
                .iter()
                .all(|v| v.placed_for.is_none())
        );
    }
}
