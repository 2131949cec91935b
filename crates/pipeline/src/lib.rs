//! Image + project → mesh → rig → warped image: the path the `c2warp` command line and
//! the editor share, so an export from either gives the same pixels.

pub mod animate;
pub mod arap;
mod c2;
pub mod cage;
pub mod carried;
pub mod crowding;
pub mod deformer;
pub mod method;
pub mod mls;
pub mod order;
pub mod parts;

use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use glam::{DVec2, Vec2};
use image::RgbaImage;
use mesh::{Constraints, DomainOptions, MeshError, MeshOptions};
use project::{Canvas, HandleSpec, MetricChoice, Middle, Project};
use render::Picture;

pub use arap::{ArapOptions, ArapRig, ArapTimes};
pub use c2::MeshRig;
pub use layers::{Artwork, Layer, write_ora};
pub use mesh::Mesh;
pub use method::{
    Backdrop, Controls, Deformer, Follow, Listener, Method, Output, SkinTable, Skinning,
    SolveProgress, Source, Still, WeightsListing, on_mesh, setup,
};
pub use order::draw_order;
pub use parts::{
    Composer, Joined, PartMesh, PartRig, PartSet, Parts, PartsDeformer, animate_parts,
    set_up_parts, warp_parts,
};

use weights_core::{
    Basis, Domain, Handle, Metric, MiddleControls, Placement, Rig, RigOptions, Similarity,
    VirtualHandle,
};

/// The picture the editor opens with and the demo warps (public domain, see
/// `assets/LICENSES.md`).
pub const DEFAULT_IMAGE: &[u8] = include_bytes!("../../../assets/lizard.png");
/// The sample rig on [`DEFAULT_IMAGE`].
pub const DEFAULT_RIG: &str = include_str!("../../../assets/lizard-rig.json");

/// The largest rig file read: a rig is a few kilobytes, even with thousands of
/// handles.
pub const MAX_RIG_BYTES: u64 = 8 << 20;

/// The largest OBJ mesh read (about 25 million vertices with their triangles).
pub const MAX_OBJ_BYTES: u64 = 1 << 30;

/// The error for an input file that could not be read, naming it as `what`.
pub(crate) fn read_error(error: render::RenderError, what: &str) -> anyhow::Error {
    match error {
        render::RenderError::NotFound { path } => {
            anyhow!("cannot read {what} {}: no such file", path.display())
        }
        render::RenderError::Io { path, source, .. } => {
            anyhow!("cannot read {what} {}: {source}", path.display())
        }
        // These name the file already.
        other => other.into(),
    }
}

/// Reads and parses a rig file.
///
/// Only a regular file of at most [`MAX_RIG_BYTES`] is read: a FIFO, a device or a
/// directory is refused before it is opened. A leading UTF-8 byte-order mark is
/// ignored.
///
/// # Errors
/// A missing, unreadable, non-regular, oversized or non-UTF-8 file, or a malformed
/// rig, naming the file.
pub fn load_project(path: &Path) -> Result<Project> {
    let bytes = render::read_regular_file(path, "rig file", MAX_RIG_BYTES)
        .map_err(|e| read_error(e, "rig file"))?;
    let text = String::from_utf8(bytes)
        .map_err(|_| anyhow!("rig file {} is not UTF-8 text", path.display()))?;
    Project::from_json(&text).with_context(|| format!("rig file {}", path.display()))
}

/// Decodes an image file under the default size limits into RGBA8 (a 16-bit picture
/// is rounded to 8 bits; see [`load_picture`]).
///
/// # Errors
/// A missing, non-regular, corrupt, truncated, unsupported or oversized image, as
/// one sentence.
pub fn load_image(path: &Path) -> Result<RgbaImage> {
    Ok(load_picture(path)?.into_rgba8())
}

/// Decodes a picture file under the default size limits, keeping 16 bits per channel
/// where the file has them: an image (PNG, JPEG, WebP, TIFF, BMP, GIF), or layered
/// artwork (PSD, OpenRaster) flattened ([`load_artwork`]).
///
/// # Errors
/// As [`load_image`].
pub fn load_picture(path: &Path) -> Result<Picture> {
    Ok(load_artwork(path)?.flatten())
}

/// Reads a picture file as layers: a PSD or OpenRaster file's layers (the format found
/// from the content, see [`layers::sniff`]), or any other picture as one layer named
/// after the file. Its `notes` say what is drawn otherwise than the file asks.
///
/// # Errors
/// A missing, non-regular, corrupt, truncated, unsupported or oversized file, as one
/// sentence naming it.
pub fn load_artwork(path: &Path) -> Result<layers::Artwork> {
    let limits = render::ImageLimits::default();
    let bytes = render::read_regular_file(path, "image", limits.max_alloc_bytes).map_err(|e| {
        let e = match e {
            render::RenderError::FileTooLarge { .. } => render::RenderError::MemoryLimit {
                path: path.to_owned(),
                limit: limits.max_alloc_bytes,
            },
            other => other,
        };
        read_error(e, "image")
    })?;
    if layers::sniff(&bytes).is_some() {
        return layers::decode(&bytes, &limits).with_context(|| path.display().to_string());
    }
    let picture =
        render::decode_picture_named(&bytes, &limits, path).map_err(|e| read_error(e, "image"))?;
    let name = path.file_stem().map_or_else(
        || "picture".to_owned(),
        |s| s.to_string_lossy().into_owned(),
    );
    Ok(layers::Artwork::from_picture(&name, picture))
}

/// Reads several pictures as the layers of one, bottom first ([`load_artwork`] each:
/// a flat picture is one layer at the origin, a layered file brings its layers at
/// their offsets); the canvas is the largest width and height among them. One path
/// is [`load_artwork`] of it.
///
/// # Errors
/// No path, what reading one refuses (naming it), more than [`layers::MAX_LAYERS`]
/// layers together, or a canvas past the picture limits.
pub fn load_artworks(paths: &[PathBuf]) -> Result<layers::Artwork> {
    let [first, rest @ ..] = paths else {
        bail!("no picture to read");
    };
    let mut artwork = load_artwork(first)?;
    let limit = render::ImageLimits::default();
    for path in rest {
        let more = load_artwork(path)?;
        artwork.width = artwork.width.max(more.width);
        artwork.height = artwork.height.max(more.height);
        artwork.layers.extend(more.layers);
        artwork.notes.extend(
            more.notes
                .into_iter()
                .map(|n| format!("{}: {n}", path.display())),
        );
        if artwork.layers.len() > layers::MAX_LAYERS {
            bail!(
                "the pictures have more than {} layers together",
                layers::MAX_LAYERS
            );
        }
    }
    let bytes: u64 = (artwork.layers.iter())
        .map(|l| {
            let (w, h) = l.dimensions();
            // Four channels a pixel.
            u64::from(w) * u64::from(h) * 4 * u64::from(l.pixels.bits_per_channel() / 8)
        })
        .sum();
    if bytes > limit.max_alloc_bytes {
        bail!(
            "the pictures need {} MiB together; the limit is {} MiB",
            bytes >> 20,
            limit.max_alloc_bytes >> 20
        );
    }
    Ok(artwork)
}

/// Meshes a picture at `options` (its outline traced from the alpha channel, or its
/// rectangle), split along the rig file's `cuts` (each stroke's parts inside the shape
/// meshed as edges, then the vertices along them doubled, [`mesh::split_along`]).
/// Returns the mesh and whether the shape is convex (never with a cut).
///
/// # Errors
/// A picture with nothing visible, or a failure of the triangulator.
pub fn mesh_picture(
    image: &RgbaImage,
    options: &MeshOptions,
    cuts: &[project::Cut],
) -> Result<(Mesh, bool), mesh::MeshError> {
    if cuts.is_empty() {
        let meshed = mesh::mesh_image(
            image,
            &DomainOptions::default(),
            options,
            &Constraints::default(),
        )?;
        return Ok((meshed.mesh, meshed.is_convex));
    }
    let domain =
        mesh::domain_for_density(image, &DomainOptions::default(), options.target_vertices)?;
    mesh_along_cuts(&domain, options, cuts)
}

/// The outline tolerance (pixels) of a layer meshed as a part whose exact outline
/// would take more than [`PART_OUTLINE_SHARE`] of its vertices: it keeps the one-pixel
/// margin of the exact outline (every visible pixel's centre stays at least 0.25 px
/// inside), but no longer follows each step of a pixel staircase.
pub const PART_OUTLINE_TOLERANCE: f64 = 1.25;

/// The share of a part's vertices its exact outline may take before the part is
/// outlined at [`PART_OUTLINE_TOLERANCE`] instead.
pub const PART_OUTLINE_SHARE: f64 = 0.25;

/// A layer meshed as a part ([`mesh_picture`], with one difference): its share of the
/// density is often small, and the exact outline of a smooth edge (0.75 px from the
/// traced one, each step of the pixel staircase kept) would then take most of it,
/// and the mesh, graded from that fine outline to the coarse inside, two to three
/// times the vertices asked for. Such a part is outlined at
/// [`PART_OUTLINE_TOLERANCE`] px instead, so the parts share the density as one
/// picture would spend it.
///
/// # Errors
/// As [`mesh_picture`].
pub fn mesh_part(
    image: &RgbaImage,
    options: &MeshOptions,
    cuts: &[project::Cut],
) -> Result<(Mesh, bool), MeshError> {
    let exact = DomainOptions::default();
    let mut domain = mesh::domain_for_density(image, &exact, options.target_vertices)?;
    let outline: usize = domain.rings().map(<[DVec2]>::len).sum();
    if outline as f64 > PART_OUTLINE_SHARE * options.target_vertices as f64 {
        let coarser = DomainOptions {
            simplify_tolerance: PART_OUTLINE_TOLERANCE,
            ..exact
        };
        domain = mesh::domain_for_density(image, &coarser, options.target_vertices)?;
    }
    mesh_along_cuts(&domain, options, cuts)
}

/// `domain` meshed at `options` with each of `cuts`' parts inside it as edges, then
/// split along them ([`mesh::split_along`]); and whether the result is convex (never
/// with a cut inside).
///
/// # Errors
/// A failure of the triangulator.
pub(crate) fn mesh_along_cuts(
    domain: &mesh::Domain,
    options: &MeshOptions,
    cuts: &[project::Cut],
) -> Result<(Mesh, bool), mesh::MeshError> {
    let pieces: Vec<Vec<DVec2>> = cuts
        .iter()
        .flat_map(|cut| {
            let stroke: Vec<DVec2> = cut.stroke.iter().map(|&p| DVec2::from(p)).collect();
            mesh::clip_to_domain(domain, &stroke)
        })
        .collect();
    let constraints = Constraints {
        points: &[],
        polylines: &pieces,
    };
    let mut meshed = mesh::triangulate(domain, &constraints, options)?;
    mesh::split_along(&mut meshed.mesh, &meshed.polyline_paths);
    let convex = meshed.is_convex && pieces.is_empty();
    Ok((meshed.mesh, convex))
}

/// Reads a 2-D mesh from a Wavefront OBJ file (see [`mesh::Mesh::read_obj`]).
///
/// Only a regular file of at most [`MAX_OBJ_BYTES`] is read.
///
/// # Errors
/// A missing, unreadable, non-regular or oversized file; one that is not an OBJ
/// mesh (not text, or no vertex lines); one with no faces; a malformed line.
pub fn load_obj(path: &Path) -> Result<Mesh> {
    let (file, _) = render::open_regular_file(path, "mesh file", MAX_OBJ_BYTES)
        .map_err(|e| read_error(e, "mesh file"))?;
    let mut reader = BufReader::new(file.take(MAX_OBJ_BYTES + 1));
    let mesh = match Mesh::read_obj(&mut reader) {
        Ok(mesh) => mesh,
        Err(MeshError::Io(e)) if e.kind() == std::io::ErrorKind::InvalidData => {
            bail!("{} is not an OBJ mesh (it is not text)", path.display())
        }
        Err(e) => return Err(e).with_context(|| format!("mesh {}", path.display())),
    };
    if reader.get_ref().limit() == 0 {
        bail!(
            "mesh file {} grew beyond {MAX_OBJ_BYTES} bytes while being read",
            path.display()
        );
    }
    if mesh.vertices.is_empty() {
        let why = if reader
            .get_ref()
            .get_ref()
            .metadata()
            .is_ok_and(|m| m.len() == 0)
        {
            "it is empty"
        } else {
            "it has no `v` vertex lines"
        };
        bail!("{} is not an OBJ mesh ({why})", path.display());
    }
    if mesh.triangles.is_empty() {
        bail!(
            "mesh {} has no triangles (no `f` face lines)",
            path.display()
        );
    }
    Ok(mesh)
}

/// An error with its causes on one line, as a user reads it: `message: cause: …`, each
/// cause once. A cause whose text the line already holds is left out (an error that
/// prints its source, such as an I/O error naming the file, would otherwise say it
/// twice: "Is a directory (os error 21): Is a directory (os error 21)").
///
/// ```
/// let io = std::io::Error::other("disk full");
/// let e = anyhow::Error::new(io).context("cannot write out.png: disk full");
/// assert_eq!(pipeline::error_line(&e), "cannot write out.png: disk full");
/// let e = anyhow::anyhow!("bad value").context("rig file a.json");
/// assert_eq!(pipeline::error_line(&e), "rig file a.json: bad value");
/// ```
pub fn error_line(error: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in error.chain() {
        let text = cause.to_string();
        if text.is_empty() || line.contains(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}

/// `path` relative to `folder` (with `..` where it lies outside it), or absolute when
/// the two share nothing but the root: how a rig file names its picture, relative to the rig's own
/// folder. `.` and `..` in either are resolved as written (links are not followed).
///
/// ```
/// use std::path::Path;
/// let rel = |p, f| pipeline::relative_path(Path::new(p), Path::new(f));
/// assert_eq!(rel("/art/cat.png", "/art"), Path::new("cat.png"));
/// assert_eq!(rel("/art/pics/cat.png", "/art/rigs"), Path::new("../pics/cat.png"));
/// assert_eq!(rel("/art/./x/../cat.png", "/art/rigs/"), Path::new("../cat.png"));
/// assert_eq!(rel("/home/cat.png", "/tmp/rigs"), Path::new("/home/cat.png"));
/// ```
pub fn relative_path(path: &Path, folder: &Path) -> std::path::PathBuf {
    use std::path::{Component, PathBuf};
    let resolved = |p: &Path| {
        let absolute = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
        let mut out = PathBuf::new();
        for part in absolute.components() {
            match part {
                Component::CurDir => {}
                Component::ParentDir => {
                    out.pop();
                }
                other => out.push(other),
            }
        }
        out
    };
    let (path, folder) = (resolved(path), resolved(folder));
    let shared = path
        .components()
        .zip(folder.components())
        .take_while(|(a, b)| a == b)
        .count();
    // Sharing no more than the root (or a drive): the absolute path says it better.
    let roots = path
        .components()
        .take_while(|c| matches!(c, Component::RootDir | Component::Prefix(_)))
        .count();
    if shared <= roots {
        return path;
    }
    let mut relative = PathBuf::new();
    for _ in folder.components().skip(shared) {
        relative.push("..");
    }
    for part in path.components().skip(shared) {
        relative.push(part);
    }
    relative
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
                ..
            } => Handle::Point {
                rest: DVec2::from(rest),
                transform: Similarity {
                    translation: DVec2::from(translate),
                    rotation: rotate,
                    scale,
                },
            },
            HandleSpec::Bar { rest, pose, .. } => {
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
        placement: match project.placement {
            project::Placement::AsWritten => Placement::AsWritten,
            project::Placement::Symmetric => Placement::Symmetric,
        },
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

/// A project's rig on an image: the image meshed, then weighted.
pub struct Prepared {
    /// The weighted rig (its domain is the mesh).
    pub rig: Rig,
}

/// Meshes `image` for `project` (at `density` vertices, else the project's, else the
/// default) and builds the rig.
///
/// **One rule gives the mesh and the rig from what the rig file holds**, so that the
/// editor's view, its export, a reopened project and `c2warp render` of the saved file
/// are one picture: the picture is meshed at its density, refined only around handles
/// that crowd together ([`crowding::refinement`], a function of the handles' rest
/// places: handles posed, or added and removed away from others, leave the mesh as it
/// is); each handle takes the vertex nearest its rest position (each bar sample, the
/// vertex nearest it), as the editor's insertions do; the saved virtual handles take
/// the vertices at their positions (a saved position is a vertex of this very mesh), and
/// Algorithm 1 adds only what they leave undone. A rig built so equals the editor's
/// incrementally updated one bit for bit (the weights depend on the set of nodes alone).
///
/// `density` follows the rule of a rig file's `density`
/// ([`project::validate_density`]), with the same message.
///
/// # Errors
/// A density out of range, handles off the image or the shape, coincident handles,
/// more handles than [`project::MAX_HANDLES`], more virtual handles than
/// [`MAX_VIRTUAL_PER_VERTEX`] times the density, an image with no visible pixel, and the
/// like, each as one sentence.
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
    prepare_meshed(image, project, density, progress, mesh_picture)
}

/// How a picture is meshed: [`mesh_picture`], or [`mesh_part`] for a layer of parts.
type Mesher = fn(&RgbaImage, &MeshOptions, &[project::Cut]) -> Result<(Mesh, bool), MeshError>;

/// [`prepare_with_progress`], meshing by `mesher`.
fn prepare_meshed(
    image: &RgbaImage,
    project: &Project,
    density: Option<usize>,
    progress: &(dyn Fn(weights_core::Progress) + Sync),
    mesher: Mesher,
) -> Result<Prepared> {
    let domain = mesh_for(image, project, density, mesher)?;
    Ok(Prepared {
        rig: rig_on_domain(domain, project, progress)?,
    })
}

/// The picture's mesh for `project` as [`prepare`] makes it, without the rig: what
/// ARAP and MLS set up on.
///
/// # Errors
/// As [`prepare`], up to the weighting.
pub fn mesh_picture_for(image: &RgbaImage, project: &Project) -> Result<Domain> {
    mesh_for(image, project, None, mesh_picture)
}

/// `domain` in the metric `project` asks for (its `metric`, `"auto"` by the shape's
/// convexity), as [`prepare`] would mesh it.
///
/// # Errors
/// A degenerate mesh.
pub fn with_metric(domain: Domain, project: &Project) -> Result<Domain> {
    let metric = metric(project.metric, domain.is_convex());
    if metric == domain.metric() {
        return Ok(domain);
    }
    Ok(Domain::new(
        domain.positions().to_vec(),
        domain.triangles().to_vec(),
        metric,
    )?)
}

/// [`prepare_meshed`]'s first half: `image` meshed by `mesher` as `project` asks (its
/// density, the refinement around crowded handles, its cuts), in the shape's metric —
/// the mesh every handle method sets up on.
///
/// # Errors
/// As [`prepare`], up to the weighting.
pub(crate) fn mesh_for(
    image: &RgbaImage,
    project: &Project,
    density: Option<usize>,
    mesher: Mesher,
) -> Result<Domain> {
    if let Some(density) = density {
        project::validate_density(density)?;
    }
    project.validate(Some(image.dimensions()))?;
    let target_vertices = density.or(project.density).unwrap_or(DEFAULT_DENSITY);
    // Vertices added around crowded handles take virtual handles too.
    let (width, height) = image.dimensions();
    let refine = crowding::refinement(project, width, height, target_vertices);
    let most = MAX_VIRTUAL_PER_VERTEX.saturating_mul(target_vertices + refine.len());
    if project.virtual_handles.len() > most {
        bail!(
            "the rig lists {} virtual handles, more than a mesh of about {target_vertices} \
             vertices can carry (each takes a vertex; C2Warp accepts up to twice the \
             density, {most}); leave out \"virtual_handles\" to have them placed afresh",
            project.virtual_handles.len()
        );
    }
    let options = MeshOptions {
        target_vertices,
        // Refined where handles crowd together, so each has samples of its own.
        refine,
        ..MeshOptions::default()
    };
    let (mesh, convex) = mesher(image, &options, &project.cuts).context("cannot mesh the image")?;
    Ok(Domain::new(
        mesh.vertices,
        mesh.triangles,
        metric(project.metric, convex),
    )?)
}

/// [`prepare_with_progress`]'s second half: `project`'s rig built on `domain`, the
/// mesh [`prepare_with_progress`] made of its picture (a part set up again with a pin
/// that asks for no other mesh keeps its mesh: the rig is what a build gives).
///
/// # Errors
/// As [`prepare`], past meshing.
pub fn rig_on_domain(
    domain: Domain,
    project: &Project,
    progress: &(dyn Fn(weights_core::Progress) + Sync),
) -> Result<Rig> {
    let handles = handles(project);
    // A saved virtual handle sits on a vertex of this mesh; one off the shape was not
    // saved from it, and is refused as a handle off the shape is.
    if let Some((i, p)) = project
        .virtual_handles
        .iter()
        .enumerate()
        .find(|(_, p)| domain.locate(DVec2::from(**p)).is_none())
    {
        bail!(
            "virtual handle {i} at ({}, {}) lies outside the shape; leave out \
             \"virtual_handles\" to have them placed afresh",
            p[0],
            p[1]
        );
    }
    let virtual_handles = virtual_handles_on(&domain, project);
    Ok(Rig::with_overlaid(
        domain,
        handles,
        &project.overlaid,
        &virtual_handles,
        rig_options(project)?,
        progress,
    )?)
}

/// `project`'s saved virtual handles on `domain`: each on the vertex at its place
/// (the nearest), the copy [`Project::virtual_copy`] names where a cut doubled it (the
/// first where the mesh has no such copy: a file saved from another mesh, whose
/// places are taken to the nearest vertex anyway).
pub fn virtual_handles_on(domain: &Domain, project: &Project) -> Vec<VirtualHandle> {
    (project.virtual_handles.iter().enumerate())
        .filter_map(|(i, &p)| {
            let nearest = domain.nearest_vertex(DVec2::from(p))?;
            Some(VirtualHandle {
                vertex: copy_at(domain, nearest, project.virtual_copy.get(i).copied()),
                placed_for: project.virtual_placed_for.get(i).copied().flatten(),
            })
        })
        .collect()
}

/// Copy `copy` (0 when `None`) of the vertices at vertex `v`'s place, or `v` where
/// there is no such copy.
fn copy_at(domain: &Domain, v: u32, copy: Option<usize>) -> u32 {
    (domain.coincident(v).get(copy.unwrap_or(0)).copied()).unwrap_or(v)
}

/// Writes `placed` (virtual handles on `domain`'s vertices) into `project` as a rig
/// file keeps them: their places, the handle each was placed for, and which of the
/// vertices at its place each sits on ([`Project::virtual_copy`], left out when every
/// one is on the first), so that [`virtual_handles_on`] finds the same vertices.
pub fn write_virtual_handles(domain: &Domain, placed: &[VirtualHandle], project: &mut Project) {
    let positions = domain.positions();
    project.virtual_handles = (placed.iter())
        .map(|v| positions[v.vertex as usize].to_array())
        .collect();
    project.virtual_placed_for = placed.iter().map(|v| v.placed_for).collect();
    project.virtual_copy = (placed.iter())
        .map(|v| {
            let there = domain.coincident(v.vertex);
            there.iter().position(|&u| u == v.vertex).unwrap_or(0)
        })
        .collect();
    if project.virtual_copy.iter().all(|&c| c == 0) {
        project.virtual_copy.clear();
    }
}

/// Builds `project`'s C² rig on a given mesh (`--mesh`), as [`mesh_with_handles`]
/// gives it, renumbered for the rig's graph searches ([`Domain::in_local_order`]) and
/// answering in the file's numbering (see [`MeshRig`]).
///
/// # Errors
/// As [`mesh_with_handles`], and what the rig refuses.
pub fn rig_on_mesh(
    mesh: &Mesh,
    project: &Project,
    progress: &(dyn Fn(weights_core::Progress) + Sync),
) -> Result<MeshRig> {
    let (domain, mut virtual_handles) = mesh_with_handles(mesh, project)?;
    let (rest, triangles) = (domain.positions().to_vec(), domain.triangles().to_vec());
    let (domain, sample) =
        Domain::in_local_order(rest.clone(), triangles.clone(), domain.metric())?;
    for v in &mut virtual_handles {
        v.vertex = sample[v.vertex as usize];
    }
    let rig = Rig::with_overlaid(
        domain,
        handles(project),
        &project.overlaid,
        &virtual_handles,
        rig_options(project)?,
        progress,
    )?;
    Ok(MeshRig::new(rig, sample, rest, triangles))
}

/// A given mesh (`--mesh`) with `project`'s handles on it: its vertices are used as
/// given, in file order; a handle (or bar sample, or saved virtual handle) that
/// coincides with a vertex uses it, and one that does not is inserted as a new vertex,
/// splitting the triangle (or edge) it lies on. Inserted vertices come after the
/// file's. Returns the mesh, in the shape's metric, and the saved virtual handles on
/// it.
///
/// # Errors
/// Invalid handles, a handle off the mesh, more virtual handles than the mesh has
/// vertices, a degenerate mesh.
pub(crate) fn mesh_with_handles(
    mesh: &Mesh,
    project: &Project,
) -> Result<(Domain, Vec<VirtualHandle>)> {
    project.validate(None)?;
    let mut mesh = mesh.clone();
    let file_vertices = mesh.vertices.len();
    // Each virtual handle takes a vertex of its own; more than the mesh has cannot have
    // been saved on it (and would each be inserted into it, one by one).
    anyhow::ensure!(
        project.virtual_handles.len() <= file_vertices,
        "the rig lists {} virtual handles, more than the mesh's {file_vertices} vertices \
         (at most one a vertex); leave out \"virtual_handles\" to have them placed afresh",
        project.virtual_handles.len(),
    );
    let handles = handles(project);
    let mut points: Vec<DVec2> = Vec::new();
    for (i, h) in handles.iter().enumerate() {
        match h {
            Handle::Point { rest, .. } => points.push(*rest),
            Handle::Bar { rest, .. } => points.extend(
                weights_core::bar_samples(
                    *rest,
                    weights_core::bar_spacing_overlaid(&handles, &project.overlaid, i),
                )
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
        Metric::Intrinsic,
    )?;
    let metric = metric(project.metric, provisional.is_convex());
    let domain = Domain::new(mesh.vertices, mesh.triangles, metric)?;
    // A mesh with vertices at one place (split along a cut): the copy saved.
    for (i, v) in virtual_handles.iter_mut().enumerate() {
        v.vertex = copy_at(&domain, v.vertex, project.virtual_copy.get(i).copied());
    }
    Ok((domain, virtual_handles))
}

/// A method set up on a picture, with its mesh's triangles in the order they are
/// drawn: what [`warp`], [`warp_picture`] and [`warp_gpu`] draw, the same way for every
/// method. A clone is a method of its own, to pose apart (an animation's frames are
/// drawn on several threads, each with its own).
#[derive(Clone)]
pub struct Warper {
    /// The method, posed.
    pub deformer: Box<dyn Deformer>,
    /// The mesh's triangles, back to front (see [`order`]).
    pub triangles: Vec<[u32; 3]>,
    /// The frame drawn: the picture's own, or grown to fit the warp.
    pub canvas: Canvas,
    /// Automatic depth (see [`order`]); `None` where the project turns it off.
    arranger: Option<order::Arranger>,
    /// The overlap orders of the rig file followed last, which an arrangement starts
    /// from.
    overlaps: Vec<project::OverlapOrder>,
}

impl Warper {
    /// C² on `rig` (as [`prepare`] builds it), drawn in the order of its handles'
    /// depths over its cells.
    pub fn on_rig(rig: Rig, project: &Project) -> Self {
        let depths: Vec<i32> = project.handles.iter().map(HandleSpec::depth).collect();
        let predefined = order::predefined_order(&rig, &depths);
        Self::arranged(Box::new(rig), predefined, project)
    }

    /// A C² rig on a given mesh (see [`rig_on_mesh`]), drawn as [`Warper::on_rig`]
    /// draws its rig (the two number the triangles alike).
    pub fn on_mesh_rig(rig: MeshRig, project: &Project) -> Self {
        let depths: Vec<i32> = project.handles.iter().map(HandleSpec::depth).collect();
        let predefined = order::predefined_order(rig.rig(), &depths);
        Self::arranged(Box::new(rig), predefined, project)
    }

    /// `project`'s handle method set up on `domain`, the picture's mesh (`picture`:
    /// the picture, which ARAP meshes its own way; `None` for a mesh given as such):
    /// C² weighs it ([`rig_on_domain`]: Algorithm 1 places the virtual handles), ARAP
    /// and MLS set up on it ([`on_mesh`]), no C² rig made for them.
    ///
    /// # Errors
    /// What the rig build or the method refuses.
    pub fn on_domain(
        domain: Domain,
        project: &Project,
        picture: Option<&RgbaImage>,
        listener: &dyn Listener,
    ) -> Result<Self> {
        if project.method != project::Method::C2 {
            // What C²'s rig refuses, every handle method refuses.
            weights_core::check_handles_on(&domain, &handles(project))?;
        }
        match on_mesh(project, &domain, picture)? {
            Some(deformer) => {
                let depths: Vec<i32> = project.handles.iter().map(HandleSpec::depth).collect();
                let predefined = order::nearest_handle_order(&domain, &handles(project), &depths);
                Ok(Self::arranged(deformer, predefined, project))
            }
            None => {
                let rig = rig_on_domain(domain, project, &|p| listener.weighting(p))?;
                Ok(Self::on_rig(rig, project))
            }
        }
    }

    /// `deformer` with its triangles drawn in the mesh's order (and, with automatic
    /// depth on in `project`, its overlaps arranged).
    pub fn in_mesh_order(deformer: Box<dyn Deformer>, project: &Project) -> Self {
        let predefined = (0..deformer.triangles().len() as u32).collect();
        Self::arranged(deformer, predefined, project)
    }

    /// `deformer` drawn in the `predefined` order, adjusted by automatic depth where
    /// `project` has it on, from the overlap orders it saved.
    fn arranged(deformer: Box<dyn Deformer>, predefined: Vec<u32>, project: &Project) -> Self {
        let triangles = order::as_triangles(&predefined, deformer.triangles());
        let arranger = project.auto_depth.then(|| {
            order::Arranger::new(
                predefined,
                &project.overlaps,
                deformer.rest(),
                deformer.triangles(),
            )
        });
        let mut warper = Self {
            deformer,
            triangles,
            canvas: project.canvas,
            arranger,
            overlaps: project.overlaps.clone(),
        };
        warper.arrange();
        warper
    }

    /// Follows `project`'s pose ([`Deformer::follow`]) and arranges its overlaps
    /// from the orders `project` keeps (as a new setup for `project` would: an
    /// animation's frame is `render` of its pose).
    ///
    /// # Errors
    /// As [`Deformer::follow`].
    pub fn follow(&mut self, project: &Project) -> Result<Follow> {
        let followed = self.deformer.follow(project)?;
        if followed == Follow::Followed {
            self.overlaps.clone_from(&project.overlaps);
            if let Some(arranger) = &mut self.arranger {
                arranger.restart(
                    &project.overlaps,
                    self.deformer.rest(),
                    self.deformer.triangles(),
                );
            }
            self.arrange();
        }
        Ok(followed)
    }

    /// Puts the method in or out of live mode ([`Deformer::set_live`]); out of it,
    /// the pose solved in full is arranged again.
    ///
    /// # Errors
    /// As [`Deformer::set_live`].
    pub fn set_live(&mut self, live: bool) -> Result<()> {
        self.deformer.set_live(live)?;
        if !live {
            // As a new setup for the rig file followed last arranges it.
            if let Some(arranger) = &mut self.arranger {
                arranger.restart(
                    &self.overlaps,
                    self.deformer.rest(),
                    self.deformer.triangles(),
                );
            }
            self.arrange();
        }
        Ok(())
    }

    /// Draws the current pose's overlaps in the order automatic depth gives them.
    fn arrange(&mut self) {
        if let Some(arranger) = &mut self.arranger {
            let order = arranger.arrange(&self.deformer.deformed(), self.deformer.triangles());
            self.triangles = order::as_triangles(&order, self.deformer.triangles());
        }
    }

    /// The overlap regions' orders in the current pose, as a rig file keeps them
    /// (none with automatic depth off).
    pub fn overlaps(&self) -> Vec<project::OverlapOrder> {
        self.arranger.as_ref().map_or_else(Vec::new, |a| {
            a.overlaps(self.deformer.rest(), self.deformer.triangles())
        })
    }

    /// The mesh's vertices at rest in f32: its texture coordinates.
    fn rest(&self) -> Vec<Vec2> {
        self.deformer.rest().iter().map(|p| p.as_vec2()).collect()
    }

    /// The deformed positions in f32 for drawing.
    fn deformed(&self) -> Result<Vec<Vec2>> {
        let deformed = self.deformer.deformed();
        if deformed.iter().any(|p| !p.is_finite()) {
            bail!("the deformation produced non-finite positions");
        }
        Ok(deformed.iter().map(|p| p.as_vec2()).collect())
    }

    /// What shows behind the warped mesh, in `frame`, in `picture`'s depth: nothing
    /// (transparent), or the picture with what the rest mesh covers cleared.
    fn backdrop(&self, picture: &Picture, frame: Frame) -> Result<Picture> {
        let blank = |picture: &Picture| blank(picture.bits_per_channel(), frame);
        match self.deformer.backdrop() {
            Backdrop::Transparent => blank(picture),
            Backdrop::PictureOutsideMesh => {
                let rest = self.rest();
                let mut outside = picture.clone();
                render::clear_covered(
                    &mut outside,
                    &render::WarpMesh {
                        rest: &rest,
                        deformed: &rest,
                        triangles: &self.triangles,
                    },
                )?;
                if frame.origin == [0, 0] && (frame.width, frame.height) == picture.dimensions() {
                    return Ok(outside);
                }
                placed(&outside, frame, [-frame.origin[0], -frame.origin[1]])
            }
        }
    }
}

/// A transparent picture the size of `frame`, in `picture`'s depth, with `picture`
/// drawn at pixel `at` of it (what falls outside is cut off).
///
/// # Errors
/// Not enough memory for it.
pub(crate) fn placed(picture: &Picture, frame: Frame, at: [i64; 2]) -> Result<Picture> {
    let mut out = blank(picture.bits_per_channel(), frame)?;
    let [x, y] = at;
    match (&mut out, picture) {
        (Picture::Rgba8(out), Picture::Rgba8(picture)) => {
            image::imageops::replace(out, picture, x, y);
        }
        (Picture::Rgba16(out), Picture::Rgba16(picture)) => {
            image::imageops::replace(out, picture, x, y);
        }
        _ => unreachable!("a blank picture of the same depth"),
    }
    Ok(out)
}

/// A transparent picture of `bits` per channel (8 or 16) the size of `frame`.
///
/// # Errors
/// Not enough memory for it.
pub(crate) fn blank(bits: u8, frame: Frame) -> Result<Picture> {
    let (width, height) = (frame.width, frame.height);
    let len = 4 * width as usize * height as usize;
    let too_large = || anyhow!("a {width} × {height} picture is too large to allocate");
    fn zeros<T: Clone + Default>(len: usize) -> Option<Vec<T>> {
        let mut v = Vec::new();
        v.try_reserve_exact(len).ok()?;
        v.resize(len, T::default());
        Some(v)
    }
    Ok(if bits == 16 {
        let data = zeros::<u16>(len).ok_or_else(too_large)?;
        Picture::Rgba16(render::Rgba16Image::from_raw(width, height, data).ok_or_else(too_large)?)
    } else {
        let data = zeros::<u8>(len).ok_or_else(too_large)?;
        Picture::Rgba8(RgbaImage::from_raw(width, height, data).ok_or_else(too_large)?)
    })
}

/// Meshes `image` for `project`, weights it and sets up the project's method: the
/// whole way from a picture and a rig file to something to draw ([`setup`] on a
/// picture).
///
/// # Errors
/// As [`prepare`], and what the method refuses.
pub fn prepare_warper(
    image: &RgbaImage,
    project: &Project,
    density: Option<usize>,
    listener: &dyn Listener,
) -> Result<Warper> {
    setup(Source::Picture { image, density }, project, listener)
}

/// [`prepare_warper`] for a layer drawn as a part, meshed by [`mesh_part`] (a handle
/// method; a cage deforms the parts on the canvas, [`parts`]).
///
/// # Errors
/// As [`prepare_warper`].
pub(crate) fn prepare_part_warper(
    image: &RgbaImage,
    project: &Project,
    density: usize,
    listener: &dyn Listener,
) -> Result<Warper> {
    let domain = mesh_for(image, project, Some(density), mesh_part)?;
    Warper::on_domain(domain, project, Some(image), listener)
}

/// Where an output picture lies over the source's pixels: its pixel `(0, 0)` is the
/// source's pixel `origin`, and it is `width × height` pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frame {
    /// The source pixel at the output's top-left corner (negative when the canvas grew
    /// up or left).
    pub origin: [i64; 2],
    /// Output width in pixels.
    pub width: u32,
    /// Output height in pixels.
    pub height: u32,
}

impl Frame {
    /// The frame for a `width × height` picture whose warped mesh lies at `deformed`:
    /// the picture's own rectangle ([`Canvas::Keep`]), or that rectangle grown to the
    /// whole pixels holding every deformed position ([`Canvas::Fit`]).
    ///
    /// # Errors
    /// A grown canvas beyond [`render::ImageLimits`]' 16384 × 16384 pixels.
    pub fn new(width: u32, height: u32, deformed: &[Vec2], canvas: Canvas) -> Result<Self> {
        let own = Self {
            origin: [0, 0],
            width,
            height,
        };
        if canvas == Canvas::Keep || deformed.is_empty() {
            return Ok(own);
        }
        let (lo, hi) = deformed.iter().fold(
            (Vec2::ZERO, Vec2::new(width as f32, height as f32)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        let (lo, hi) = (lo.floor(), hi.ceil());
        let limits = render::ImageLimits::default();
        let (w, h) = (f64::from(hi.x - lo.x), f64::from(hi.y - lo.y));
        if w > f64::from(limits.max_width) || h > f64::from(limits.max_height) {
            bail!(
                "the canvas grown to fit the warped picture would be {w} × {h} pixels, more \
                 than the {} × {} a picture may have: keep the picture's canvas, or pose the \
                 handles nearer the picture",
                limits.max_width,
                limits.max_height
            );
        }
        Ok(Self {
            origin: [lo.x as i64, lo.y as i64],
            width: w as u32,
            height: h as u32,
        })
    }

    /// The offset that takes source pixel coordinates to this frame's.
    pub fn shift(&self) -> Vec2 {
        -Vec2::new(self.origin[0] as f32, self.origin[1] as f32)
    }

    /// `positions` in this frame's pixels.
    pub fn place(&self, positions: &[Vec2]) -> Vec<Vec2> {
        let shift = self.shift();
        positions.iter().map(|&p| p + shift).collect()
    }
}

impl Warper {
    /// The frame this warper draws a `width × height` picture into.
    ///
    /// # Errors
    /// As [`Frame::new`], and non-finite deformed positions.
    pub fn frame(&self, width: u32, height: u32) -> Result<Frame> {
        match self.canvas {
            // No need to deform anything for the picture's own frame.
            Canvas::Keep => Frame::new(width, height, &[], Canvas::Keep),
            Canvas::Fit => Frame::new(width, height, &self.deformed()?, Canvas::Fit),
        }
    }
}

/// The image warped by the current pose on the GPU (or a software adapter), 8 bits
/// per channel: a skinned method's weights and transforms are blended in the vertex
/// shader; a method that gives positions has them drawn as they are; over the
/// method's backdrop.
///
/// # Errors
/// No adapter, or a GPU failure.
pub fn warp_gpu(image: &RgbaImage, warper: &Warper) -> Result<RgbaImage> {
    warp_gpu_with(&render::GpuContext::new()?, image, warper)
}

/// As [`warp_gpu`], on a GPU context already made (an animation makes one for all
/// its frames).
pub(crate) fn warp_gpu_with(
    gpu: &render::GpuContext,
    image: &RgbaImage,
    warper: &Warper,
) -> Result<RgbaImage> {
    let rest = warper.rest();
    let triangles = &warper.triangles;
    let (w, h) = image.dimensions();
    let deformed = warper.deformed()?;
    let frame = Frame::new(w, h, &deformed, warper.canvas)?;
    let (fw, fh) = (frame.width, frame.height);
    let layer = match warper.deformer.output() {
        Output::Skinned(skin) => {
            let table = skin.table();
            let mesh = render::SkinnedMesh {
                rest: &rest,
                rows: &table.rows,
                nodes: &table.nodes,
                weights: &table.weights,
                triangles,
            };
            // The frame's shift folded into every node's translation.
            let shift = frame.shift();
            let affines: Vec<render::Affine> = skin
                .transforms()
                .into_iter()
                .map(|[a, b, c, d, x, y]| [a, b, c, d, x + shift.x, y + shift.y])
                .collect();
            gpu.warp_skinned(image, &mesh, &affines, fw, fh)?
        }
        Output::Positions(_) => {
            let deformed = frame.place(&deformed);
            let mesh = render::WarpMesh {
                rest: &rest,
                deformed: &deformed,
                triangles,
            };
            gpu.warp(image, &mesh, fw, fh)?
        }
    };
    Ok(match warper.deformer.backdrop() {
        Backdrop::Transparent => layer,
        Backdrop::PictureOutsideMesh => {
            let base = warper.backdrop(&Picture::Rgba8(image.clone()), frame)?;
            let mut out = base.into_rgba8();
            for (base, top) in out.pixels_mut().zip(layer.pixels()) {
                if top.0[3] > 0 {
                    *base = render::over(top.0, base.0).into();
                }
            }
            out
        }
    })
}

/// Why a picture's mesh has far fewer vertices than the density `asked` for, if it
/// has, as a clause for a message: the mesh holds at most
/// [`mesh::MAX_VERTICES_PER_PIXEL`] vertices a pixel of the shape.
pub fn density_shortfall(domain: &weights_core::Domain, asked: usize) -> Option<String> {
    let got = domain.len();
    if got as f64 >= 0.7 * asked as f64 {
        return None;
    }
    let positions = domain.positions();
    let area: f64 = domain
        .triangles()
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| positions[v as usize]);
            0.5 * (b - a).perp_dot(c - a).abs()
        })
        .sum();
    // Only the cap explains it; otherwise the mesh is as close as meshes come.
    (mesh::MAX_VERTICES_PER_PIXEL * area < asked as f64).then(|| {
        format!(
            " (asked for {asked}: the picture's visible shape, {area:.0} px², holds at most \
             {} vertices a pixel)",
            mesh::MAX_VERTICES_PER_PIXEL
        )
    })
}

/// What `deformer` draws behind its warped mesh, on `image` in the picture's own frame:
/// nothing (`None`, transparent), or `image` with every pixel its rest mesh covers
/// cleared by the rasteriser's own rule (pixel centres, top-left fill rule), so that at
/// rest every cleared pixel is drawn again from itself. The editor's view draws it
/// under the mesh, as the exports do.
///
/// # Errors
/// A rest mesh the rasteriser refuses (an index out of range).
pub fn backdrop_of(
    image: &image::RgbaImage,
    deformer: &dyn Deformer,
) -> Result<Option<image::RgbaImage>> {
    match deformer.backdrop() {
        Backdrop::Transparent => Ok(None),
        Backdrop::PictureOutsideMesh => {
            let rest: Vec<Vec2> = deformer.rest().iter().map(|p| p.as_vec2()).collect();
            let mut picture = Picture::Rgba8(image.clone());
            render::clear_covered(
                &mut picture,
                &render::WarpMesh {
                    rest: &rest,
                    deformed: &rest,
                    triangles: deformer.triangles(),
                },
            )?;
            Ok(Some(picture.into_rgba8()))
        }
    }
}

/// The picture warped by the current pose on the CPU, at its full resolution and in
/// its own depth, over the method's backdrop, in the warper's frame (the picture's
/// own, or grown to fit the warp: see [`Frame`]): a 16-bit picture gives a 16-bit
/// picture (write it with [`render::save_png_atomic`] for a 16-bit PNG); an 8-bit one
/// exactly what [`warp`] gives.
///
/// # Errors
/// Non-finite deformed positions, or a grown canvas too large.
pub fn warp_picture(picture: &Picture, warper: &Warper) -> Result<Picture> {
    let rest = warper.rest();
    let (w, h) = picture.dimensions();
    let deformed = warper.deformed()?;
    let frame = Frame::new(w, h, &deformed, warper.canvas)?;
    let deformed = frame.place(&deformed);
    let mesh = render::WarpMesh {
        rest: &rest,
        deformed: &deformed,
        triangles: &warper.triangles,
    };
    let mut out = warper.backdrop(picture, frame)?;
    render::warp_picture_over(picture, &mesh, &mut out)?;
    Ok(out)
}

/// Each visible layer of `artwork` warped by the current pose on its own layer, as
/// [`warp_picture`] draws the flattened picture: the layer is put on the canvas at its
/// offset and drawn through the same warped mesh, in its own depth, into the same
/// frame. Hidden layers are kept as they are (they are not meshed, so nothing warps
/// them), at their place on the canvas. The result keeps the layers' order, names,
/// opacity and visibility. Flattening it gives the warped flattened picture (exactly
/// where triangles of the warped mesh do not overlap; where they fold over, each layer
/// is drawn in the mesh's order on its own).
///
/// `warper` must be set up on `artwork`'s flattened picture (its mesh covers every
/// visible pixel of every visible layer).
///
/// # Errors
/// As [`warp_picture`], for any layer.
pub fn warp_layers(artwork: &layers::Artwork, warper: &Warper) -> Result<layers::Artwork> {
    let canvas = Frame {
        origin: [0, 0],
        width: artwork.width,
        height: artwork.height,
    };
    let frame = Frame::new(
        artwork.width,
        artwork.height,
        &warper.deformed()?,
        warper.canvas,
    )?;
    let shift = |at: i32, origin: i64| i32::try_from(i64::from(at) - origin);
    let mut warped = Vec::with_capacity(artwork.layers.len());
    for layer in &artwork.layers {
        let (x, y, pixels) = if layer.visible {
            let on_canvas = placed(
                &layer.pixels,
                canvas,
                [i64::from(layer.x), i64::from(layer.y)],
            )?;
            let pixels = warp_picture(&on_canvas, warper)
                .with_context(|| format!("layer \"{}\"", layer.name))?;
            (0, 0, pixels)
        } else {
            let x = shift(layer.x, frame.origin[0]).context("a layer far off the canvas")?;
            let y = shift(layer.y, frame.origin[1]).context("a layer far off the canvas")?;
            (x, y, layer.pixels.clone())
        };
        warped.push(layers::Layer {
            name: layer.name.clone(),
            x,
            y,
            opacity: layer.opacity,
            visible: layer.visible,
            pixels,
        });
    }
    Ok(layers::Artwork {
        width: frame.width,
        height: frame.height,
        layers: warped,
        notes: Vec::new(),
    })
}

/// The image warped by the current pose, at the image's full resolution, 8 bits per
/// channel (see [`warp_picture`]).
///
/// # Errors
/// As [`warp_picture`].
pub fn warp(image: &RgbaImage, warper: &Warper) -> Result<RgbaImage> {
    let rest = warper.rest();
    let (w, h) = image.dimensions();
    let deformed = warper.deformed()?;
    let frame = Frame::new(w, h, &deformed, warper.canvas)?;
    let deformed = frame.place(&deformed);
    let mesh = render::WarpMesh {
        rest: &rest,
        deformed: &deformed,
        triangles: &warper.triangles,
    };
    let mut out = match warper.deformer.backdrop() {
        Backdrop::Transparent => blank(8, frame)?.into_rgba8(),
        Backdrop::PictureOutsideMesh => warper
            .backdrop(&Picture::Rgba8(image.clone()), frame)?
            .into_rgba8(),
    };
    render::warp_over(image, &mesh, &mut out)?;
    Ok(out)
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
        // Refused before meshing: the build itself would take minutes.
        assert!(clock.elapsed().as_secs_f64() < 10.0);
    }

    #[test]
    fn a_virtual_handle_off_the_shape_is_refused_as_a_handle_off_it_is() {
        let image = image::RgbaImage::from_fn(60, 40, |x, _| {
            image::Rgba([90, 90, 90, if x < 30 { 255 } else { 0 }])
        });
        let mut project = Project::from_json(
            r#"{"version":1,"density":400,"handles":[{"type":"point","rest":[10,20]}]}"#,
        )
        .expect("a rig");
        for off in [[-500.0, -500.0], [50.0, 20.0]] {
            project.virtual_handles = vec![[20.0, 20.0], off];
            let error = prepare(&image, &project, None).err().expect("refused");
            let line = error_line(&error);
            assert!(
                line.contains("virtual handle 1 at") && line.contains("outside the shape"),
                "{line}"
            );
        }
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
        assert!(
            placed.iter().any(|v| v.placed_for == Some(new)),
            "{placed:?}"
        );
        let point = |p: DVec2| project::HandleSpec::Point {
            rest: p.to_array(),
            translate: [0.0, 0.0],
            rotate: 0.0,
            scale: 1.0,
            depth: 0,
        };
        project.handles.push(point(DVec2::new(446.0, 238.0)));
        write_virtual_handles(rig.domain(), &placed, &mut project);
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
        // Removing the handle from the reloaded rig takes its virtual handles along:
        // the same as building, on the reloaded mesh, the other handles with the
        // other virtual handles (the handle is the last one, so nothing renumbers).
        let others: Vec<VirtualHandle> = reloaded
            .placed_virtual_handles()
            .into_iter()
            .filter(|v| v.placed_for != Some(new))
            .collect();
        assert!(others.len() < reloaded.placed_virtual_handles().len());
        let mut handles = reloaded.handles().to_vec();
        handles.remove(new);
        let expected = Rig::with_placed_virtual_handles(
            reloaded.domain().clone(),
            handles,
            &others,
            reloaded.options().clone(),
        )
        .expect("builds");
        reloaded.remove_handle(new).expect("exists");
        assert_eq!(reloaded.virtual_vertices(), expected.virtual_vertices());
        assert!(
            reloaded
                .placed_virtual_handles()
                .iter()
                .all(|v| v.placed_for.is_none_or(|h| h < new))
        );
        // Without the owners in the file, they would have stayed.
        let mut unowned = saved.clone();
        unowned.virtual_placed_for.clear();
        let mut unowned = prepare(&image, &unowned, None).expect("builds").rig;
        unowned.remove_handle(new).expect("exists");
        assert_ne!(unowned.virtual_vertices(), expected.virtual_vertices());
    }
}
