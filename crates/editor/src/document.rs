//! The document: the picture, its rig file ([`Project`]) and the weighted rig built from
//! them. Every change goes through [`Document::apply`] with an [`Edit`]; the rig is
//! brought up to date incrementally (handles) or rebuilt (parameters), and a failed
//! edit leaves the document as it was.
//!
//! With LBC chosen the rig file's cage warps the picture. Its coordinates are solved
//! on request (seconds, on the editor's worker: [`solve_cage`]) and kept by
//! [`CageKey`] — the rest cage, τ and the vertex count inside — so a new pose costs
//! nothing but the cage's positions, and an undo back to an earlier cage finds its
//! coordinates again.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use glam::DVec2;
use image::RgbaImage;
use pipeline::cage::CageCoordinates;
use pipeline::carried::Keep;
use pipeline::{ArapRig, Controls, Deformer, Follow, Method, PartsDeformer};
use project::{
    CageSpec, HandleSpec, LbcSettings, MetricChoice, Middle, Placement, Project, RigidityStroke,
};
use weights_core::{Domain, NodeKind, Rig, VirtualHandle};

mod animation;
mod cage;
mod checks;
mod depth;
mod rigging;
mod shown;
#[cfg(test)]
mod tests;

pub use animation::PosedMesh;
pub use cage::{CageKey, solve_cage};
pub use shown::Shown;

/// The parameters of the weighting a user can change in the side panel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Shape factor α ∈ [0, 1].
    pub alpha: f64,
    /// Basis degree (5…25).
    pub degree: u32,
    /// Middle controls of the basis.
    pub middle: Middle,
    /// Pin the image border.
    pub fixed_boundary: bool,
    /// Distance: auto, Euclidean or intrinsic (shape-aware).
    pub metric: MetricChoice,
    /// Target number of mesh vertices.
    pub density: usize,
    /// How Algorithm 1 places virtual handles.
    pub placement: Placement,
}

impl Settings {
    /// The parameters `project` asks for (the default density where it names none).
    pub fn of(project: &Project) -> Self {
        Self {
            alpha: project.alpha,
            degree: project.degree,
            middle: project.middle,
            fixed_boundary: project.fixed_boundary,
            metric: project.metric,
            density: project.density.unwrap_or(pipeline::DEFAULT_DENSITY),
            placement: project.placement,
        }
    }

    /// Writes these parameters into `project`.
    pub fn write_to(self, project: &mut Project) {
        project.alpha = self.alpha;
        project.degree = self.degree;
        project.middle = self.middle;
        project.fixed_boundary = self.fixed_boundary;
        project.metric = self.metric;
        project.density = Some(self.density);
        project.placement = self.placement;
    }
}

/// One change to the document.
#[derive(Clone, Debug, PartialEq)]
pub enum Edit {
    /// Appends a handle.
    Add(HandleSpec),
    /// Appends a handle bound to one part alone (a layer's index), not to every part
    /// under it (the layers drawn as parts).
    AddBound(HandleSpec, usize),
    /// Removes handle `index`.
    Remove(usize),
    /// Replaces handle `index` with the same rest geometry and a new pose.
    Pose(usize, HandleSpec),
    /// Removes every handle.
    Clear,
    /// Puts every handle back at rest.
    ResetPose,
    /// New weighting parameters (a new density re-meshes the picture).
    Settings(Settings),
    /// Another warping method, on the same picture, handles and pose.
    Method(Method),
    /// New painted rigidity (ARAP).
    Rigidity(Vec<RigidityStroke>),
    /// New cuts: the picture is re-meshed, split along them.
    Cuts(Vec<project::Cut>),
    /// A new cage at rest, in image pixels: LBC becomes the method, and a rig file
    /// without a count of mesh vertices inside the cage (`lbc.density`) takes
    /// `vertices`. Its coordinates are solved separately ([`Document::solve_cage`], or
    /// [`solve_cage`] on a worker).
    Cage {
        /// The cage's vertices at rest.
        rest: Vec<[f64; 2]>,
        /// Mesh vertices inside, unless the rig file names a count.
        vertices: usize,
    },
    /// No cage (the method goes back to C² if it was LBC).
    ClearCage,
    /// The cage's pose: where each of its vertices goes (image pixels).
    CagePose(Vec<[f64; 2]>),
    /// LBC's settings: τ and the vertex count inside the cage.
    Lbc(LbcSettings),
    /// The frame of exports: the picture's own, or grown to fit the warp.
    Canvas(project::Canvas),
    /// Moving least squares' settings: α and the class of map fitted.
    Mls(project::MlsSettings),
    /// The animation: keys in time and on the canvas, rate, interpolation (`None`:
    /// none).
    Animation(Option<Box<project::Animation>>),
    /// Automatic depth (the ARAP paper's §5.1) on or off.
    AutoDepth(bool),
    /// A layered picture drawn as parts (their order, visibility and bindings), or
    /// as one picture (`None`).
    Parts(Option<project::PartsSpec>),
}

/// An open picture with its rig. Cloning copies the rig (tens of megabytes at a
/// million vertices): the editor does it to rebuild a large rig on a worker thread.
#[derive(Clone)]
pub struct Document {
    /// The rig file as it would be saved (virtual handles are filled in on save).
    project: Project,
    /// The picture, at full resolution, 8 bits per channel (meshing, the view).
    pub image: Arc<RgbaImage>,
    /// The picture as its file has it when that has 16 bits per channel: exports are
    /// drawn from it, so they keep the depth.
    pub deep: Option<Arc<render::Picture>>,
    /// The picture's layers, as its file has them (one for a flat picture; `None`
    /// for the built-in picture): *Export layers…* warps each on its own.
    pub layers: Option<Arc<pipeline::Artwork>>,
    /// Where the picture came from (`None`: the built-in picture, or several pictures).
    pub image_path: Option<PathBuf>,
    /// The pictures drawn as the layers of one (a rig file's `"images"`), bottom first;
    /// empty unless the picture came from several files.
    pub image_paths: Vec<PathBuf>,
    /// Where the project was last saved or loaded from.
    pub project_path: Option<PathBuf>,
    /// What the picture file holds that is drawn otherwise than it asks (layers whose
    /// blend mode is drawn as normal), one line each; said when it is opened.
    pub picture_notes: Vec<String>,
    /// The picture's mesh, and C²'s weights of it where the method uses them.
    base: Base,
    /// Bumped whenever the nodes or weights change (the GPU mesh must be re-uploaded).
    pub weights_version: u64,
    /// Bumped whenever a node transform changes.
    pub pose_version: u64,
    /// Milliseconds the last change of handles or parameters took to bring the weights
    /// up to date.
    pub last_update_ms: f64,
    /// Deformed samples, and the (pose, weights) versions they were computed for.
    deformed: Option<((u64, u64), Vec<DVec2>)>,
    /// Bumped when the picture is meshed anew.
    mesh_version: u64,
    /// With a handle method other than C² chosen: its deformer, and the mesh version
    /// it was set up on ([`pipeline::on_mesh`]).
    method: Option<(u64, Box<dyn Deformer>)>,
    /// Solved cages, the most recent last (at most [`SOLUTIONS_KEPT`]).
    solutions: Vec<(CageKey, Arc<CageCoordinates>)>,
    /// Automatic depth's arrangement of the shown mesh (`None` with it off).
    depth: Option<depth::Depth>,
    /// Bumped whenever the drawing order may have changed.
    pub order_version: u64,
    /// Whether the poses come from a live drag (or playback).
    live: bool,
    /// Whether a live pose was left unarranged (a large mesh): the drag's end
    /// arranges it.
    depth_deferred: bool,
    /// The parts set up for an edit being made, when working that out set them up
    /// already (a pin placed on a part that followed another): taken when the
    /// deformer is brought in line with the edit.
    primed: Option<Box<dyn Deformer>>,
    /// The mesh working out an edit meshed the picture anew with (a shape carried
    /// over a re-mesh), with the project it is for, `carried` aside: taken when the
    /// edit is made rather than meshed again.
    primed_mesh: Option<(Project, Domain)>,
}

/// The picture's mesh, and C²'s weights of it where they are used.
#[derive(Clone)]
enum Base {
    /// The C² rig, which holds the mesh: under C².
    Rig(Box<Rig>),
    /// The mesh alone, under every other method (ARAP and MLS set up on it; under a
    /// cage the handles stay on it, for going back to them), which weighs nothing of
    /// C²'s; `virtuals` keeps the C² rig's virtual handles (the rig file's `virtual_*`
    /// fields alone), carried through the edits as a save carries them, so that going
    /// back to C² builds the rig a reopen would build.
    Mesh {
        mesh: Box<Domain>,
        virtuals: Box<Project>,
    },
}

impl Base {
    /// `project`'s on `image`: its rig under C², else its mesh alone.
    fn of(image: &RgbaImage, project: &Project) -> Result<Self> {
        if !project.method.uses_virtual_handles() {
            let mesh = pipeline::mesh_picture_for(image, project)?;
            weights_core::check_handles_on(&mesh, &pipeline::handles(project))?;
            Ok(Base::Mesh {
                mesh: Box::new(mesh),
                virtuals: Box::new(virtuals_of(project)),
            })
        } else {
            Ok(Base::Rig(Box::new(
                pipeline::prepare(image, project, None)?.rig,
            )))
        }
    }

    fn mesh(&self) -> &Domain {
        match self {
            Base::Rig(rig) => rig.domain(),
            Base::Mesh { mesh, .. } => mesh,
        }
    }
}

/// What going from the rig file to another changes, as far as the work it takes goes.
struct Change {
    /// Every handle keeps its kind and rest geometry (a pose, at most).
    same_rest: bool,
    /// A handle's depth changed (another drawing order).
    depths: bool,
    /// The picture is meshed anew: another density, other cuts, or handles that crowd
    /// together otherwise.
    remesh: bool,
}

/// `rest`, found by following the pose back from `at`; `at` itself where the two are
/// within rounding (the picture is not posed there), so a handle added to a picture at
/// rest is exactly at rest.
pub(crate) fn unmoved(rest: DVec2, at: DVec2) -> DVec2 {
    if rest.distance(at) < 1e-9 { at } else { rest }
}

/// A handle's rest geometry as a segment (a point's: of no length).
fn rest_segment(handle: &HandleSpec) -> [DVec2; 2] {
    match *handle {
        HandleSpec::Point { rest, .. } => [DVec2::from(rest); 2],
        HandleSpec::Bar { rest, .. } => rest.map(DVec2::from),
    }
}

/// `project`'s virtual handles alone (its `virtual_*` fields).
fn virtuals_of(project: &Project) -> Project {
    Project {
        virtual_handles: project.virtual_handles.clone(),
        virtual_placed_for: project.virtual_placed_for.clone(),
        virtual_copy: project.virtual_copy.clone(),
        ..Project::default()
    }
}

impl Document {
    /// Meshes `image` and builds the rig of `project` on it.
    ///
    /// # Errors
    /// Handles off the picture or the shape, coincident handles, a picture with no
    /// opaque pixel, bad parameters.
    pub fn new(image: RgbaImage, image_path: Option<PathBuf>, project: Project) -> Result<Self> {
        Self::with_image(Arc::new(image), image_path, project)
    }

    /// As [`Document::new`], sharing a picture already in memory.
    ///
    /// # Errors
    /// As [`Document::new`].
    pub fn with_image(
        image: Arc<RgbaImage>,
        image_path: Option<PathBuf>,
        project: Project,
    ) -> Result<Self> {
        Self::with_layers(image, None, image_path, project)
    }

    /// As [`Document::with_image`], with the layers the picture was flattened from
    /// (a rig file drawing them as parts is set up as parts).
    ///
    /// # Errors
    /// As [`Document::new`], and what setting the parts up refuses.
    pub fn with_layers(
        image: Arc<RgbaImage>,
        layers: Option<Arc<pipeline::Artwork>>,
        image_path: Option<PathBuf>,
        mut project: Project,
    ) -> Result<Self> {
        let clock = Instant::now();
        // The cage's density as the command line reads it, before the picture's
        // density is filled in below (which it would otherwise follow).
        if project.cage.is_some() {
            let vertices = pipeline::cage::cage_vertices(&project, None);
            project.lbc = Some(LbcSettings {
                density: Some(vertices),
                ..project.lbc.unwrap_or_default()
            });
        }
        project.density = Some(project.density.unwrap_or(pipeline::DEFAULT_DENSITY));
        // Drawn as parts under handles, the parts are set up beside the picture's own
        // mesh and rig, on the other core.
        let parts_layers = (layers.as_deref()).filter(|_| {
            project.parts.is_some()
                && rigging::rigging(project.method.controls()).parts_set_up_on_opening()
        });
        let (base, parts) = rayon::join(
            || Base::of(&image, &project),
            || parts_layers.map(|layers| PartsDeformer::new(layers, &project, None, &())),
        );
        let base = base?;
        let method = (parts.transpose()?).map(|parts| (1, Box::new(parts) as Box<dyn Deformer>));
        // Virtual handles live in the rig while editing; they are written out on save.
        project.virtual_handles.clear();
        project.virtual_placed_for.clear();
        project.virtual_copy.clear();
        Self {
            project,
            image,
            deep: None,
            layers,
            image_path,
            image_paths: Vec::new(),
            project_path: None,
            picture_notes: Vec::new(),
            base,
            weights_version: 1,
            pose_version: 1,
            last_update_ms: ms(clock),
            deformed: None,
            mesh_version: 1,
            method,
            solutions: Vec::new(),
            depth: None,
            order_version: 1,
            live: false,
            depth_deferred: false,
            primed: None,
            primed_mesh: None,
        }
        .with_method()
    }

    /// This document with its method's deformer set up (an LBC cage is solved
    /// separately: [`Document::solve_cage`]).
    fn with_method(mut self) -> Result<Self> {
        self.sync_method()?;
        Ok(self)
    }

    /// Brings the method's deformer in line with the rig file: a handle method other
    /// than C² follows the rig file's handles and settings (set up anew on a new mesh,
    /// when first chosen or with new settings); C² is the rig itself; a cage method is
    /// the solved cage's ([`Document::cage_solution`]).
    fn sync_method(&mut self) -> Result<()> {
        self.sync_deformer()?;
        self.rearrange();
        Ok(())
    }

    /// [`Document::sync_method`]'s first half: the deformer alone.
    fn sync_deformer(&mut self) -> Result<()> {
        let rigging = self.rigging();
        rigging.sync(self)
    }

    /// [`Document::sync_deformer`] under handles: the method set up on the picture's
    /// mesh or on the parts (C²: the rig itself, no deformer).
    fn sync_handles(&mut self) -> Result<()> {
        // Set up already where working out an edit did (a shape carried).
        if let Some(mut primed) = self.primed.take()
            && primed.method() == self.project.method
            && primed.follow(&self.project)? == Follow::Followed
        {
            self.method = Some((self.mesh_version, primed));
            return Ok(());
        }
        if let Some(layers) = self.layers.clone().filter(|_| self.project.parts.is_some()) {
            // Drawn as parts: each part set up by the method with its own handles,
            // the parts joined into the mesh shown.
            let mut previous = None;
            if let Some((mesh, deformer)) = &mut self.method
                && *mesh == self.mesh_version
                && deformer.as_any().is::<PartsDeformer>()
            {
                if deformer.follow(&self.project)? == Follow::Followed {
                    return Ok(());
                }
                previous = deformer.as_any().downcast_ref::<PartsDeformer>();
            }
            // The parts whose own setup is the same are kept (a pin added sets up the
            // parts it binds).
            let parts = match previous {
                Some(previous) => previous.update(&layers, &self.project, None, &())?,
                None => PartsDeformer::new(&layers, &self.project, None, &())?,
            };
            self.method = Some((self.mesh_version, Box::new(parts)));
            return Ok(());
        }
        if let Some((mesh, deformer)) = &mut self.method
            && *mesh == self.mesh_version
            && deformer.method() == self.project.method
            && !deformer.as_any().is::<PartsDeformer>()
            && deformer.follow(&self.project)? == Follow::Followed
        {
            return Ok(());
        }
        self.method = pipeline::on_mesh(&self.project, self.mesh(), Some(&self.image))?
            .map(|deformer| (self.mesh_version, deformer));
        Ok(())
    }

    /// Bumped whenever the picture is meshed anew.
    pub fn mesh_version(&self) -> u64 {
        self.mesh_version
    }

    /// The mesh's triangles in drawing order, back to front, by the handles' depths
    /// and automatic depth (see [`pipeline::order`]).
    pub fn draw_order(&self) -> Vec<[u32; 3]> {
        if let Some(depth) = self.depth.as_ref().filter(|d| !d.is_cage()) {
            return depth.order.clone();
        }
        if let Some(parts) = self.parts() {
            // The parts back to front in the draw order, each in its own order.
            return parts.triangles().to_vec();
        }
        let order = self.predefined_order();
        pipeline::order::as_triangles(&order, self.mesh().triangles())
    }

    /// The method in use.
    pub fn method(&self) -> Method {
        self.project.method
    }

    /// The handle method's deformer: the C² rig itself, or the one set up on the mesh.
    pub fn deformer(&self) -> &dyn Deformer {
        match (&self.method, &self.base) {
            (Some((_, deformer)), _) => deformer.as_ref(),
            (None, Base::Rig(rig)) => rig.as_ref(),
            // A bare mesh always has its method set up beside it (set up before the
            // mesh is taken, in `Document::restore_bare`).
            (None, Base::Mesh { .. }) => unreachable!("a bare mesh without its method"),
        }
    }

    /// The handles' predefined drawing order on the picture's mesh (triangle indices):
    /// by C²'s cells under C², by the handle nearest each vertex otherwise.
    pub(crate) fn predefined_order(&self) -> Vec<u32> {
        let depths: Vec<i32> = self.project.handles.iter().map(HandleSpec::depth).collect();
        match &self.base {
            Base::Rig(rig) if self.project.method == Method::C2 => {
                pipeline::order::predefined_order(rig, &depths)
            }
            _ => pipeline::order::nearest_handle_order(
                self.mesh(),
                &pipeline::handles(&self.project),
                &depths,
            ),
        }
    }

    /// The parts, when the picture is drawn as parts (the rig file's `"parts"`).
    pub fn parts(&self) -> Option<&PartsDeformer> {
        self.method
            .as_ref()
            .and_then(|(_, deformer)| deformer.as_any().downcast_ref::<PartsDeformer>())
    }

    /// Drawn as parts: the part (a layer's index) shown at `p` in the current pose,
    /// the topmost there.
    pub fn part_at(&mut self, p: DVec2) -> Option<usize> {
        self.deformed();
        let deformed = self.deformed.as_ref().map(|(_, d)| d.as_slice())?;
        let parts = self.parts()?;
        let mut order = self.draw_order();
        order.reverse();
        let ([a, ..], _) = locate(deformed, &order, p)?;
        parts.part_of_vertex(a).map(|k| k as usize)
    }

    /// The ARAP rig, when ARAP is in use (its step times, its rigidity per triangle).
    pub fn arap(&self) -> Option<&ArapRig> {
        self.method
            .as_ref()
            .and_then(|(_, deformer)| deformer.as_any().downcast_ref::<ArapRig>())
    }

    /// The built-in picture with its sample rig.
    ///
    /// # Errors
    /// Only if the embedded files are broken.
    pub fn built_in() -> Result<Self> {
        let image = render::decode_image(pipeline::DEFAULT_IMAGE, &render::ImageLimits::default())?;
        let project = Project::from_json(pipeline::DEFAULT_RIG).context("built-in rig")?;
        Self::new(image, None, project)
    }

    /// A picture file with no handles.
    ///
    /// # Errors
    /// An unreadable, corrupt, unsupported or oversized picture, or one that cannot be
    /// meshed (no opaque pixel).
    pub fn open_image(path: &Path) -> Result<Self> {
        let artwork = pipeline::load_artwork(path)?;
        let project = Project {
            image: Some(path.to_path_buf()),
            ..Project::default()
        };
        Self::from_artwork(artwork, Some(path.to_path_buf()), project)
    }

    /// Pictures drawn as the layers of one, bottom first, with no handles (one: as
    /// [`Document::open_image`]); the project names them all (`"images"`).
    ///
    /// # Errors
    /// What [`pipeline::load_artworks`] refuses, or a picture that cannot be meshed.
    pub fn open_pictures(paths: &[PathBuf]) -> Result<Self> {
        if let [one] = paths {
            return Self::open_image(one);
        }
        let artwork = pipeline::load_artworks(paths)?;
        let project = Project {
            images: paths.to_vec(),
            ..Project::default()
        };
        let mut document = Self::from_artwork(artwork, None, project)?;
        document.image_paths = paths.to_vec();
        Ok(document)
    }

    /// As [`Document::new`] for a decoded picture of either depth (a 16-bit one is
    /// kept for exports).
    ///
    /// # Errors
    /// As [`Document::new`].
    pub fn from_picture(
        picture: render::Picture,
        image_path: Option<PathBuf>,
        project: Project,
    ) -> Result<Self> {
        Self::from_layers(picture, None, image_path, project)
    }

    /// As [`Document::from_picture`] for `artwork` flattened, its layers kept (what
    /// its reading noted too): a rig file drawing them as parts is set up as parts.
    ///
    /// # Errors
    /// As [`Document::new`], and what setting the parts up refuses.
    pub fn from_artwork(
        mut artwork: pipeline::Artwork,
        image_path: Option<PathBuf>,
        project: Project,
    ) -> Result<Self> {
        let notes = std::mem::take(&mut artwork.notes);
        let picture = artwork.flatten();
        let mut document =
            Self::from_layers(picture, Some(Arc::new(artwork)), image_path, project)?;
        document.picture_notes = notes;
        Ok(document)
    }

    /// [`Document::from_picture`] with the layers it was flattened from, set before
    /// the method is set up (so that parts are set up once, from the saved orders).
    fn from_layers(
        picture: render::Picture,
        layers: Option<Arc<pipeline::Artwork>>,
        image_path: Option<PathBuf>,
        project: Project,
    ) -> Result<Self> {
        let (image, deep) = match picture {
            render::Picture::Rgba8(image) => (image, None),
            deep @ render::Picture::Rgba16(_) => {
                (deep.to_rgba8().into_owned(), Some(Arc::new(deep)))
            }
        };
        let mut document = Self::with_layers(Arc::new(image), layers, image_path, project)?;
        document.deep = deep;
        Ok(document)
    }

    /// A project file and the picture it names (relative to the project file).
    ///
    /// # Errors
    /// An unreadable or malformed project, a project without a picture, or a missing
    /// or bad picture, each naming the file.
    pub fn open_project(path: &Path) -> Result<Self> {
        let project = pipeline::load_project(path)?;
        let folder = path.parent().unwrap_or(Path::new(""));
        let named: Vec<PathBuf> = (project.image.iter().chain(&project.images))
            .map(|p| folder.join(p))
            .collect();
        if named.is_empty() {
            bail!("{} names no image", path.display());
        }
        let artwork = pipeline::load_artworks(&named)
            .with_context(|| format!("the image of project {}", path.display()))?;
        let image_path = project.image.is_some().then(|| named[0].clone());
        let mut document = Self::from_artwork(artwork, image_path, project)
            .with_context(|| format!("project {}", path.display()))?;
        if document.image_path.is_none() {
            document.image_paths = named;
        }
        document.project_path = Some(path.to_path_buf());
        Ok(document)
    }

    /// The rig file as it stands (without virtual handles).
    pub fn project(&self) -> &Project {
        &self.project
    }

    /// The C² rig (its weights, virtual handles, cells and dual graph), kept under C²
    /// and under a cage (for going back to the handles); `None` under ARAP and MLS,
    /// which set up on the mesh alone.
    pub fn rig(&self) -> Option<&Rig> {
        match &self.base {
            Base::Rig(rig) => Some(rig),
            Base::Mesh { .. } => None,
        }
    }

    /// The picture's mesh at rest, which every handle method is set up on and the view
    /// draws (what asks for the mesh alone asks here, not for the C² rig that holds it).
    pub fn mesh(&self) -> &Domain {
        self.base.mesh()
    }

    /// The weighting parameters.
    pub fn settings(&self) -> Settings {
        Settings::of(&self.project)
    }

    /// Whether going to `project` (same picture and density) rebuilds the rig rather
    /// than updating it: new weighting parameters, ARAP set up or repainted, or — for
    /// a step through the history, `exact` — another set of handles.
    pub fn rebuilds_for(&self, project: &Project, exact: bool) -> bool {
        let new = Settings::of(project);
        if new != self.settings() {
            return true;
        }
        let rigidity = project.method.reads_rigidity();
        if rigidity
            && (!self.project.method.reads_rigidity() || project.rigidity != self.project.rigidity)
        {
            return true;
        }
        exact
            && (project.handles.len() != self.project.handles.len()
                || project
                    .handles
                    .iter()
                    .zip(&self.project.handles)
                    .any(|(a, b)| !same_rest(a, b)))
    }

    /// The files the picture came from (none for the built-in picture).
    pub fn pictures(&self) -> impl Iterator<Item = &Path> {
        (self.image_path.iter().chain(&self.image_paths)).map(PathBuf::as_path)
    }

    /// The rig file to save next to `path`: the picture's path relative to the file's
    /// folder where possible, and the virtual handles, so it reloads with the same
    /// weights.
    pub fn project_for_saving(&self, path: Option<&Path>) -> Project {
        let mut project = self.snapshot();
        let folder = path.and_then(Path::parent).unwrap_or(Path::new(""));
        project.image =
            (self.image_path.as_ref()).map(|image| pipeline::relative_path(image, folder));
        project.images = (self.image_paths.iter())
            .map(|image| pipeline::relative_path(image, folder))
            .collect();
        project
    }

    /// Applies an edit. On error nothing changes.
    ///
    /// # Errors
    /// What the rig rejects: a handle off the shape, coincident handles, a zero-length
    /// bar, non-finite values, a missing handle; or a re-mesh that fails.
    pub fn apply(&mut self, edit: Edit) -> Result<()> {
        let applied = self.apply_edit(edit);
        // What working out the edit set up is for it alone (taken as the edit is
        // made, dropped if it fails).
        self.primed = None;
        self.primed_mesh = None;
        applied
    }

    /// [`Document::apply`]'s work.
    fn apply_edit(&mut self, edit: Edit) -> Result<()> {
        let mut project = self.project.clone();
        match edit {
            Edit::Add(handle) => self.push_handle(&mut project, handle, None)?,
            Edit::AddBound(handle, part) => {
                let Some(parts) = &project.parts else {
                    bail!("a handle is bound to one part when the layers are drawn as parts");
                };
                parts.check_layers(self.layers.as_ref().map_or(0, |l| l.layers.len()))?;
                if self.layers.as_ref().is_none_or(|l| part >= l.layers.len()) {
                    bail!("there is no part {part}");
                }
                self.push_handle(&mut project, handle, Some(part))?;
            }
            Edit::Remove(index) => {
                if index >= project.handles.len() {
                    bail!("there is no handle {index}");
                }
                // An overlaid handle takes its layer along and nothing else.
                let overlaid = project.overlaid.contains(&index);
                let partition_left = (0..project.handles.len())
                    .any(|i| i != index && !project.overlaid.contains(&i));
                let posed = project.is_posed();
                let removed = project.handles[index].clone();
                project.remove_handle(index);
                self.drop_shapes_of_unbound(&mut project)?;
                if posed {
                    // What it moved relaxes and the picture away from it stays where
                    // it was: under ARAP and MLS on one picture, and on each part it
                    // bound under every method.
                    let others: Vec<_> = project.handles.iter().map(rest_segment).collect();
                    let away = pipeline::carried::away_from(rest_segment(&removed), &others);
                    self.carry_shape(&mut project, &away)?;
                    self.keep_parts(&mut project, index, &removed)?;
                }
                if !overlaid && posed && partition_left {
                    // In a posed state a handle of the partition leaves its nodes
                    // behind as virtual handles: the cells and weights stay as they
                    // are, and what it held follows the remaining handles
                    // harmonically, as the paper's virtual handles do.
                    return self.remove_keeping_nodes(project, index);
                }
                if !overlaid && !partition_left {
                    // The last handle of the partition: the overlaid ones join it (left
                    // over an empty partition they would hold their bumps alone).
                    project.overlaid.clear();
                }
            }
            Edit::Pose(index, handle) => match project.handles.get_mut(index) {
                Some(slot) if same_rest(slot, &handle) => *slot = handle,
                Some(_) => bail!("a pose change may not move handle {index} at rest"),
                None => bail!("there is no handle {index}"),
            },
            Edit::Clear => {
                project.handles.clear();
                project.holds.clear();
                project.overlaid.clear();
                if let Some(animation) = &mut project.animation {
                    animation.poses_mut().for_each(|pose| pose.handles.clear());
                }
            }
            Edit::ResetPose => {
                for h in &mut project.handles {
                    *h = h.at_rest();
                }
                // At rest, nothing is held away from it, and no part carries a shape
                // from following; without keys, every handle joins the paper's weights
                // again.
                project.holds.clear();
                project.carried.clear();
                if project
                    .animation
                    .as_ref()
                    .is_none_or(|a| a.keys.is_empty() && a.spatial_keys.is_empty())
                {
                    project.overlaid.clear();
                }
            }
            Edit::Settings(settings) => settings.write_to(&mut project),
            Edit::Method(method) => {
                if let Some(why) = rigging::rigging(method.controls()).refusal(method, &project) {
                    bail!(why);
                }
                if method != project.method {
                    // The picture's shape is carried on its method's warp.
                    project.carried.retain(|c| c.part.is_some());
                }
                project.method = method;
            }
            Edit::Rigidity(strokes) => {
                // New paint on a locked part is refused; erasing (what is left of
                // strokes already there) is not.
                let kept = |s: &RigidityStroke| {
                    (project.rigidity.iter())
                        .any(|o| o.part == s.part && s.stroke.iter().all(|p| o.stroke.contains(p)))
                };
                let locked = (strokes.iter())
                    .filter(|s| !kept(s))
                    .find_map(|s| s.part.filter(|&k| self.is_locked(k)));
                if let Some(k) = locked {
                    bail!(
                        "{} is locked: unlock it under Layers to paint it",
                        self.part_name(k)
                    );
                }
                project.rigidity = strokes;
            }
            Edit::Cuts(cuts) => project.cuts = cuts,
            Edit::Cage { rest, vertices } => {
                if project.lbc.and_then(|l| l.density).is_none() {
                    // The first cage's count; a cage of very many vertices gets fewer
                    // inside, so that the default is never refused as too much work.
                    let vertices = vertices.min(pipeline::cage::default_cage_vertices(rest.len()));
                    project.lbc = Some(LbcSettings {
                        density: Some(vertices),
                        ..project.lbc.unwrap_or_default()
                    });
                }
                project.cage = Some(CageSpec { rest, pose: None });
                // A new rest cage: the keys' cage poses no longer fit it.
                if let Some(animation) = &mut project.animation {
                    animation.poses_mut().for_each(|pose| pose.cage = None);
                }
                if project.method.controls() != Controls::Cage {
                    project.method = Method::for_controls(Controls::Cage);
                }
                self.check_cage(&project)?;
            }
            Edit::ClearCage => {
                project.cage = None;
                if let Some(animation) = &mut project.animation {
                    animation.poses_mut().for_each(|pose| pose.cage = None);
                }
                if project.method.controls() == Controls::Cage {
                    project.method = Method::for_controls(Controls::Handles);
                }
            }
            Edit::CagePose(pose) => {
                let Some(cage) = &mut project.cage else {
                    bail!("there is no cage to pose");
                };
                if pose.len() != cage.rest.len() {
                    bail!(
                        "a pose of {} points for a cage of {} vertices",
                        pose.len(),
                        cage.rest.len()
                    );
                }
                // At rest is no pose, so that a reset compares equal to a fresh cage.
                cage.pose = (pose != cage.rest).then_some(pose);
                self.check_cage(&project)?;
            }
            Edit::Lbc(settings) => {
                project.lbc = Some(settings);
                self.check_cage(&project)?;
            }
            Edit::Canvas(canvas) => project.canvas = canvas,
            Edit::AutoDepth(on) => {
                project.auto_depth = on;
                project.overlaps.clear();
            }
            Edit::Parts(parts) => {
                if let (Some(spec), Some(layers)) = (&parts, &self.layers) {
                    spec.check_layers(layers.layers.len())?;
                } else if parts.is_some() {
                    bail!("the built-in picture has no layers to draw as parts");
                }
                // The orders automatic depth kept name places on the mesh drawn
                // before: the parts' mesh is another.
                if parts.is_some() != project.parts.is_some() {
                    project.overlaps.clear();
                    project.carried.clear();
                }
                project.parts = parts;
                project
                    .validate(Some(self.image.dimensions()))
                    .context("the parts")?;
            }
            Edit::Mls(settings) => {
                project.mls = Some(settings);
                project
                    .validate(Some(self.image.dimensions()))
                    .context("MLS's settings")?;
            }
            Edit::Animation(animation) => {
                project.animation = animation.map(|a| *a);
                project
                    .validate(Some(self.image.dimensions()))
                    .context("the animation")?;
            }
        }
        // Drawn as parts, every handle must bind a part shown: checked before anything
        // changes.
        if let Some(layers) = self.layers.as_ref().filter(|_| project.parts.is_some()) {
            pipeline::parts::bindings(layers, &project)?;
        }
        self.drop_shapes_of_unbound(&mut project)?;
        self.restore(project)
    }

    /// Drops the shapes carried by parts that no handle binds any more (a part shown
    /// that follows again; a hidden part keeps its shape for when it is shown).
    fn drop_shapes_of_unbound(&self, project: &mut Project) -> Result<()> {
        let Some(layers) = self.layers.as_deref() else {
            return Ok(());
        };
        let Some(spec) = project.parts.clone() else {
            return Ok(());
        };
        if project.carried.iter().all(|c| c.part.is_none()) {
            return Ok(());
        }
        let bindings = pipeline::parts::bindings(layers, project)?;
        let bound = |k: usize| bindings.get(k).is_some_and(|b| !b.is_empty());
        let shown = |k: usize| {
            layers
                .layers
                .get(k)
                .is_some_and(|l| spec.shows(k, l.visible))
        };
        (project.carried).retain(|c| c.part.is_none_or(|k| bound(k) || !shown(k)));
        Ok(())
    }

    /// Appends `handle` to `project` (the document's, being edited) with what goes with
    /// it: its place in every key, and in a posed state what holds the picture where
    /// it is (C² lays it over the weights it is placed on, ARAP pins what is under it).
    fn push_handle(
        &mut self,
        project: &mut Project,
        handle: HandleSpec,
        only: Option<usize>,
    ) -> Result<()> {
        // Drawn as parts: bound to chosen parts (`only`, or the unlocked ones under it
        // where a locked part lies under it too), else to every part under it.
        let chosen = self.parts_to_bind(project, &handle, only)?;
        // Every key gets the new handle where its pose takes it.
        let fitted = self.fit_into_keys(&handle)?;
        if let Some(animation) = &mut project.animation {
            for (pose, fit) in animation.poses_mut().zip(fitted) {
                pose.handles.push(fit);
            }
        }
        let posed = project.is_posed();
        project.handles.push(handle);
        let index = project.handles.len() - 1;
        if posed {
            project.overlaid.push(index);
        }
        if let (Some(parts), Some(spec)) = (chosen, &mut project.parts) {
            spec.bindings.push(project::Binding {
                handle: index,
                parts,
            });
        }
        let holds = match (self.parts(), self.layers.as_deref()) {
            // Drawn as parts: held on each part it binds.
            (Some(parts), Some(layers)) => parts.rig().holds(layers, project, index)?,
            _ => self.deformer().holds(project, index),
        };
        project.holds.extend(holds);
        // A part it binds that followed another until now keeps the shape following
        // gave it; under MLS, which cannot hold a part, and under C², whose overlaid
        // handle holds it to within its fit, every part it binds keeps the shape it has
        // (ARAP's holds keep it already). The parts set up for it are posed from when
        // the edit is made.
        if let (Some(parts), Some(layers)) = (self.parts(), self.layers.as_deref()) {
            let all = |_: DVec2| 1.0;
            let rig = parts.rig();
            let targets: Vec<(usize, &Keep)> = (pipeline::parts::bindings(layers, project)?
                .iter()
                .enumerate())
            .filter(|(k, bound)| {
                bound.contains(&index)
                    && (rig.followed().get(*k).is_some_and(Option::is_some)
                        || (project.method != Method::Arap && rig.bound(*k).is_some()))
            })
            .map(|(k, _)| (k, &all as &Keep))
            .collect();
            self.primed = parts
                .keep(layers, project, &targets, None)?
                .map(|parts| Box::new(parts) as Box<dyn Deformer>);
        }
        if posed && project.method == Method::Mls {
            // MLS cannot hold the picture where it is (a new handle is a new term in
            // every point's fit): the picture carries what it would lose.
            self.carry_shape(project, &|_| 1.0)?;
        }
        Ok(())
    }

    /// Drawn as parts in a posed state, with handle `index` (`removed`) just taken out
    /// of `project`: each part it bound that other handles still bind keeps the shape
    /// it has away from it (beyond twice its distance to the nearest handle binding
    /// the part), and lets go near it; the shapes are written to `project`'s
    /// `carried`, the parts set up for it kept to be taken when the edit is made.
    fn keep_parts(
        &mut self,
        project: &mut Project,
        index: usize,
        removed: &HandleSpec,
    ) -> Result<()> {
        let (Some(parts), Some(layers)) = (self.parts(), self.layers.as_deref()) else {
            return Ok(());
        };
        let after = pipeline::parts::bindings(layers, project)?;
        let aways: Vec<(usize, Box<Keep>)> = (parts.rig().bindings().iter())
            .enumerate()
            .filter(|(k, bound)| {
                bound.contains(&index) && after.get(*k).is_some_and(|b| !b.is_empty())
            })
            .map(|(k, _)| {
                let others: Vec<_> = (after[k].iter())
                    .map(|&h| rest_segment(&project.handles[h]))
                    .collect();
                let away = pipeline::carried::away_from(rest_segment(removed), &others);
                (k, Box::new(away) as Box<Keep>)
            })
            .collect();
        let targets: Vec<(usize, &Keep)> =
            aways.iter().map(|(k, away)| (*k, away.as_ref())).collect();
        if let Some(kept) = parts.keep(layers, project, &targets, None)? {
            self.primed = Some(Box::new(kept));
        }
        Ok(())
    }

    /// Under ARAP and MLS on one picture in a posed state, the shape that keeps the
    /// picture shown where `keep` says (1: where it is, 0: where the method now puts
    /// it) once `project` (the edit being made) is followed: written to `project`'s
    /// `carried`. Where the edit meshes the picture anew (handles crowding together),
    /// the new mesh is shown where the old one showed the picture; otherwise the
    /// method that followed the edit is kept, to be taken when the edit is made.
    fn carry_shape(&mut self, project: &mut Project, keep: &Keep) -> Result<()> {
        if self.parts().is_some()
            || !project.method.sets_up_on_the_mesh()
            || project.method != self.project.method
        {
            return Ok(());
        }
        let Some((_, method)) = &self.method else {
            return Ok(());
        };
        let shown = method.deformed();
        let without = without_carried(project);
        let remesh = self.change_to(project).remesh;
        let (trial, before, mesh) = if remesh {
            // Meshed anew (as restoring the edit will mesh it): set up there.
            let mesh = pipeline::mesh_picture_for(&self.image, &without)?;
            let before = pipeline::carried::resample(self.mesh(), &shown, mesh.positions());
            let Some(trial) = pipeline::on_mesh(&without, &mesh, Some(&self.image))? else {
                return Ok(());
            };
            (trial, before, Some(mesh))
        } else {
            let mut trial = method.clone_box();
            if trial.follow(&without)? == Follow::NeedsSetup {
                return Ok(());
            }
            (trial, shown, None)
        };
        let old = pipeline::carried::picture_shape(&self.project);
        let shape = pipeline::carried::keep(trial.as_ref(), &before, old, keep)?;
        project.carried.clone_from(&without.carried);
        project.carried.extend(shape);
        project.carried.sort_by_key(|c| c.part);
        // The method as the edit leaves it, on the mesh the edit makes (kept with the
        // project it is for, where that is a new one).
        self.primed_mesh = mesh.map(|mesh| (without, mesh));
        self.primed = Some(trial);
        Ok(())
    }

    /// The parts a new `handle` binds when that is not every part under it: `only`
    /// (which must not be locked), or the unlocked parts under it where a locked one
    /// lies under it too (none unlocked: refused). `None`: every part under it, or
    /// not drawn as parts.
    fn parts_to_bind(
        &self,
        project: &Project,
        handle: &HandleSpec,
        only: Option<usize>,
    ) -> Result<Option<Vec<usize>>> {
        let (Some(spec), Some(layers)) = (&project.parts, self.layers.as_deref()) else {
            return Ok(None);
        };
        if let Some(k) = only {
            if spec.is_locked(k) {
                bail!(
                    "{} is locked: unlock it under Layers to pin it",
                    self.part_name(k)
                );
            }
            return Ok(Some(vec![k]));
        }
        let under = pipeline::parts::layers_under(layers, spec, handle);
        if !under.iter().any(|&k| spec.is_locked(k)) {
            return Ok(None);
        }
        let free: Vec<usize> = under
            .iter()
            .copied()
            .filter(|&k| !spec.is_locked(k))
            .collect();
        if free.is_empty() {
            let names: Vec<String> = under.iter().map(|&k| self.part_name(k)).collect();
            match names.as_slice() {
                [one] => bail!("{one} is locked: unlock it under Layers to pin it"),
                _ => bail!(
                    "{} are locked: unlock one under Layers to pin it",
                    names.join(", ")
                ),
            }
        }
        Ok(Some(free))
    }

    /// Whether part `k` is locked (drawn as parts).
    pub fn is_locked(&self, k: usize) -> bool {
        self.project.parts.as_ref().is_some_and(|p| p.is_locked(k))
    }

    /// Layer `k`'s name, as the Layers panel shows it.
    pub fn part_name(&self, k: usize) -> String {
        match self.layers.as_deref().and_then(|l| l.layers.get(k)) {
            Some(layer) => layer.name.clone(),
            None => format!("part {k}"),
        }
    }

    /// Makes `project` (the document's, with handle `removed` of the partition taken
    /// out) the document's rig file, with that handle's nodes kept as virtual handles.
    fn remove_keeping_nodes(&mut self, mut project: Project, removed: usize) -> Result<()> {
        let Base::Rig(rig) = &self.base else {
            // No C² rig to keep them in: the virtual handles placed for it go with it.
            return self.restore(project);
        };
        let renumber = |h: Option<usize>| match h {
            Some(h) if h > removed => Some(h - 1),
            Some(h) if h == removed => None,
            other => other,
        };
        let kept = (rig.placed_virtual_handles().into_iter()).map(|v| VirtualHandle {
            placed_for: renumber(v.placed_for),
            ..v
        });
        let left = (0..rig.nodes().len())
            .filter(|&k| {
                rig.owner_handle(k) == Some(removed)
                    && matches!(
                        rig.nodes()[k].kind,
                        weights_core::NodeKind::Point { .. }
                            | weights_core::NodeKind::BarSample { .. }
                    )
            })
            .map(|k| VirtualHandle {
                vertex: rig.nodes()[k].vertex,
                placed_for: None,
            });
        let virtuals: Vec<VirtualHandle> = kept.chain(left).collect();
        pipeline::write_virtual_handles(rig.domain(), &virtuals, &mut project);
        if project.virtual_placed_for.iter().all(Option::is_none) {
            project.virtual_placed_for.clear();
        }
        self.restore_with(project, true)
    }

    /// Refuses a cage off the picture, with too few or too many vertices, or with
    /// non-finite points (a cage that crosses itself is kept: it is refused when
    /// solved, so the user can fix it).
    fn check_cage(&self, project: &Project) -> Result<()> {
        project
            .validate(Some(self.image.dimensions()))
            .context("the cage")?;
        Ok(())
    }

    /// Makes `project` (same picture) the document's rig file, updating the rig as
    /// cheaply as the difference allows: poses only, handles added or removed
    /// incrementally, a rebuild for new parameters, a re-mesh for a new density.
    ///
    /// # Errors
    /// As [`Document::apply`]; on error nothing changes.
    pub fn restore(&mut self, project: Project) -> Result<()> {
        self.set_live(false)?;
        self.restore_with(project, false)
    }

    /// [`Document::restore`] for a frame of a live drag: an iterative method starts
    /// from the previous frame's answer and stops early ([`Deformer::set_live`]);
    /// [`Document::settle`] finishes the pose when the drag ends.
    ///
    /// # Errors
    /// As [`Document::restore`].
    pub fn preview(&mut self, project: Project) -> Result<()> {
        self.set_live(true)?;
        self.restore_with(project, false)
    }

    /// Ends a live drag: the pose shown is solved in full, as a file of it renders.
    ///
    /// # Errors
    /// What the method refuses in the pose (as [`Document::restore`]).
    pub fn settle(&mut self) -> Result<()> {
        let live = self.live.then(|| self.deformer().deformed());
        self.set_live(false)?;
        if live.is_some_and(|live| live != self.deformer().deformed()) {
            // The pose solved in full moved the vertices (ARAP's): shown and arranged
            // anew.
            self.pose_version += 1;
            self.rearrange_now(true);
        } else {
            self.arrange_deferred();
        }
        Ok(())
    }

    fn set_live(&mut self, live: bool) -> Result<()> {
        self.live = live;
        if let Some((_, deformer)) = &mut self.method {
            deformer.set_live(live)?;
        }
        Ok(())
    }

    /// The rig file with the rig's virtual handles: a state that [`Document::undo_to`]
    /// brings back exactly.
    pub fn snapshot(&self) -> Project {
        let mut project = self.project.clone();
        match &self.base {
            Base::Rig(rig) => {
                let placed = rig.placed_virtual_handles();
                pipeline::write_virtual_handles(rig.domain(), &placed, &mut project);
            }
            Base::Mesh { virtuals, .. } => {
                project
                    .virtual_handles
                    .clone_from(&virtuals.virtual_handles);
                project
                    .virtual_placed_for
                    .clone_from(&virtuals.virtual_placed_for);
                project.virtual_copy.clone_from(&virtuals.virtual_copy);
            }
        }
        project
    }

    /// Goes back (or forward) to a [`Document::snapshot`]: like [`Document::restore`],
    /// but when handles were added or removed the rig is rebuilt with the snapshot's
    /// virtual handles, so the weights are exactly those of that state rather than
    /// keeping the virtual handles placed since.
    ///
    /// # Errors
    /// As [`Document::apply`]; on error nothing changes.
    pub fn undo_to(&mut self, snapshot: Project) -> Result<()> {
        self.restore_with(snapshot, true)
    }

    fn restore_with(&mut self, mut project: Project, exact: bool) -> Result<()> {
        let saved_virtuals = Project {
            virtual_handles: std::mem::take(&mut project.virtual_handles),
            virtual_placed_for: std::mem::take(&mut project.virtual_placed_for),
            virtual_copy: std::mem::take(&mut project.virtual_copy),
            ..Project::default()
        };
        if !project.method.uses_virtual_handles() {
            return self.restore_bare(project, saved_virtuals, exact);
        }
        if let Base::Mesh { mesh, .. } = &self.base {
            // Back to C² from a method that keeps the mesh alone: the rig built on it
            // from the handles and virtual handles kept, as a reopen of the rig file
            // saved now would build it; then on as from C².
            let mut with = self.snapshot();
            with.method = Method::C2;
            let mesh = pipeline::with_metric(Domain::clone(mesh), &with)?;
            let rig = pipeline::rig_on_domain(mesh, &with, &|_| {})?;
            self.base = Base::Rig(Box::new(rig));
            self.weights_version += 1;
        }
        // Another method or another rest cage draws another mesh; another cage pose
        // moves it.
        let cage_mesh_changed = project.method != self.project.method
            || CageKey::of(&project) != CageKey::of(&self.project);
        let clock = Instant::now();
        let old = self.settings();
        let new = Settings::of(&project);
        let handles = pipeline::handles(&project);
        let change = self.change_to(&project);
        let same_rest = change.same_rest && project.overlaid == self.project.overlaid;
        let depths_changed = change.depths;
        if change.remesh {
            let mut with_virtuals = project.clone();
            if exact {
                with_virtuals.virtual_handles = saved_virtuals.virtual_handles;
                with_virtuals.virtual_placed_for = saved_virtuals.virtual_placed_for;
                with_virtuals.virtual_copy = saved_virtuals.virtual_copy;
            } else if new.density == old.density {
                // The same lattice: the virtual handles stay where they were (those
                // placed for a handle that is gone go with it), and Algorithm 1 adds
                // what the new handles need.
                (
                    with_virtuals.virtual_handles,
                    with_virtuals.virtual_placed_for,
                    with_virtuals.virtual_copy,
                ) = carried_virtuals(&self.snapshot(), &project);
            }
            self.base = Base::Rig(Box::new(
                pipeline::prepare(&self.image, &with_virtuals, None)?.rig,
            ));
            self.mesh_version += 1;
        } else if new == old && exact && !same_rest {
            let domain = self.mesh();
            let placed = pipeline::virtual_handles_on(domain, &saved_virtuals);
            self.base = Base::Rig(Box::new(Rig::with_overlaid(
                domain.clone(),
                handles,
                &project.overlaid,
                &placed,
                pipeline::rig_options(&project)?,
                &|_| {},
            )?));
        } else if new != old {
            let domain = self.mesh();
            let metric = pipeline::metric(new.metric, domain.is_convex());
            let domain = if metric == domain.metric() {
                domain.clone()
            } else {
                Domain::new(
                    domain.positions().to_vec(),
                    domain.triangles().to_vec(),
                    metric,
                )?
            };
            self.base = Base::Rig(Box::new(Rig::with_overlaid(
                domain,
                handles,
                &project.overlaid,
                &[],
                pipeline::rig_options(&project)?,
                &|_| {},
            )?));
        } else {
            if (project.handles != self.project.handles
                || project.overlaid != self.project.overlaid)
                && let Base::Rig(rig) = &mut self.base
            {
                rig.set_handles_overlaid(handles, &project.overlaid)?;
            }
            if same_rest {
                self.project = project;
                self.pose_version += 1;
                if depths_changed || cage_mesh_changed {
                    // The triangles' drawing order changed, or the cage's mesh is
                    // drawn instead: the mesh is uploaded anew.
                    self.weights_version += 1;
                }
                return self.sync_method();
            }
        }

        self.project = project;
        self.weights_version += 1;
        self.pose_version += 1;
        self.sync_method()?;
        self.last_update_ms = ms(clock);
        Ok(())
    }

    /// How `project` differs from the rig file in what decides the work of going to
    /// it (see [`Change`]).
    fn change_to(&self, project: &Project) -> Change {
        let same_rest = project.handles.len() == self.project.handles.len()
            && project
                .handles
                .iter()
                .zip(&self.project.handles)
                .all(|(a, b)| same_rest(a, b));
        let depths = project.handles.iter().map(HandleSpec::depth).ne(self
            .project
            .handles
            .iter()
            .map(HandleSpec::depth));
        // Handles that crowd together refine the mesh around them (the C² paper's
        // up-sampling): another set of crowded handles is another mesh. (A function of
        // the handles' rest places and the density: a pose, every drag frame, leaves it
        // as it is.) A cut splits the mesh along it.
        let (w, h) = self.image.dimensions();
        let refined =
            |p: &Project| pipeline::crowding::refinement(p, w, h, Settings::of(p).density);
        let density = Settings::of(project).density != self.settings().density;
        let remesh = density
            || project.cuts != self.project.cuts
            || (!same_rest && refined(project) != refined(&self.project));
        Change {
            same_rest,
            depths,
            remesh,
        }
    }

    /// [`Document::restore_with`] under a method that keeps the mesh alone (ARAP and
    /// MLS, which set up on it; a cage, which leaves the handles on it): the mesh anew
    /// where the density, the crowding of handles or the cuts ask for another (the
    /// rule [`pipeline::prepare`] meshes by), the handles checked as C²'s rig checks
    /// them, the virtual handles kept for going back to C² carried as a rig would carry
    /// them; a handle method new to the mesh is set up before anything changes.
    fn restore_bare(
        &mut self,
        project: Project,
        saved_virtuals: Project,
        exact: bool,
    ) -> Result<()> {
        let clock = Instant::now();
        let (old, new) = (self.settings(), Settings::of(&project));
        let Change {
            same_rest,
            depths: depths_changed,
            remesh,
        } = self.change_to(&project);
        // The virtual handles kept for C²: `None` keeps them as they are (a pose, every
        // drag frame).
        let virtuals = if exact {
            Some(saved_virtuals)
        } else if new.density != old.density {
            // Another lattice: Algorithm 1 places them afresh when C² comes back.
            Some(Project::default())
        } else if !same_rest || matches!(self.base, Base::Rig(_)) {
            let (virtual_handles, virtual_placed_for, virtual_copy) =
                carried_virtuals(&self.snapshot(), &project);
            Some(Project {
                virtual_handles,
                virtual_placed_for,
                virtual_copy,
                ..Project::default()
            })
        } else {
            None
        };
        // Meshed anew while the edit was worked out, or now.
        let primed_mesh = (self.primed_mesh.take())
            .filter(|(key, _)| remesh && *key == without_carried(&project))
            .map(|(_, mesh)| mesh);
        let reused = primed_mesh.is_some();
        if remesh && !reused {
            // Set up on another mesh than this edit's.
            self.primed = None;
        }
        let new_mesh = if let Some(mesh) = primed_mesh {
            Some(mesh)
        } else if remesh {
            Some(pipeline::mesh_picture_for(&self.image, &project)?)
        } else if matches!(self.base, Base::Rig(_)) || new.metric != old.metric {
            Some(pipeline::with_metric(self.mesh().clone(), &project)?)
        } else {
            None
        };
        let mesh = new_mesh.as_ref().unwrap_or(self.mesh());
        weights_core::check_handles_on(mesh, &pipeline::handles(&project))?;
        let parts = self.layers.is_some() && project.parts.is_some();
        // (The method set up on a mesh made while the edit was worked out is taken
        // when the deformer is brought in line, `primed`.)
        let primed = reused && self.primed.is_some();
        let fresh = if project.method.sets_up_on_the_mesh()
            && !parts
            && !primed
            && (new_mesh.is_some() || self.method.is_none())
        {
            pipeline::on_mesh(&project, mesh, Some(&self.image))?
        } else {
            None
        };
        // Another method, or another rest cage, draws another mesh.
        let method_changed = project.method != self.project.method
            || CageKey::of(&project) != CageKey::of(&self.project);
        match (new_mesh, &mut self.base) {
            (Some(mesh), _) => {
                let virtuals = virtuals.unwrap_or_else(|| virtuals_of(&self.snapshot()));
                self.base = Base::Mesh {
                    mesh: Box::new(mesh),
                    virtuals: Box::new(virtuals),
                }
            }
            (None, Base::Mesh { virtuals: kept, .. }) => {
                if let Some(virtuals) = virtuals {
                    **kept = virtuals;
                }
            }
            (None, Base::Rig(_)) => {}
        }
        if remesh {
            self.mesh_version += 1;
        }
        if let Some(deformer) = fresh {
            self.method = Some((self.mesh_version, deformer));
        }
        if !(same_rest && !depths_changed && !remesh && !method_changed) {
            // Another mesh, other handles or another order: uploaded anew.
            self.weights_version += 1;
        }
        self.project = project;
        self.pose_version += 1;
        self.sync_method()?;
        self.last_update_ms = ms(clock);
        Ok(())
    }

    /// Every sample's deformed position (cached per pose).
    pub fn deformed(&mut self) -> &[DVec2] {
        let version = (self.pose_version, self.weights_version);
        if self.deformed.as_ref().is_none_or(|(v, _)| *v != version) {
            self.deformed = Some((version, self.deformer().deformed()));
        }
        self.deformed.as_ref().map_or(&[], |(_, d)| d)
    }

    /// [`Document::deformed`] as last brought up to date, if it is for the current pose
    /// and weights (for readers that hold the document shared, after calling it).
    pub fn current_deformed(&self) -> Option<&[DVec2]> {
        let version = (self.pose_version, self.weights_version);
        (self.deformed.as_ref())
            .filter(|(v, _)| *v == version)
            .map(|(_, d)| d.as_slice())
    }

    /// The point handle a click at `at` (image pixels, current pose) places: at rest
    /// where the picture shown there lies, with the rotation and scale the pose has
    /// around it ([`Document::local_pose`]). `None` off the picture.
    pub fn point_at(&mut self, at: DVec2) -> Option<HandleSpec> {
        let (rest, _, _) = self.unwarp(at)?;
        let rest = unmoved(rest, at);
        let (rotate, scale) = self.local_pose(rest, at);
        Some(HandleSpec::Point {
            rest: rest.to_array(),
            translate: (at - rest).to_array(),
            rotate,
            scale,
            depth: 0,
        })
    }

    /// The rest position under `p` in the current pose, and the local similarity the
    /// pose applies there (rotation, scale), found from the deformed triangle that
    /// contains `p` (the first one, where folds overlap). `None` off the picture.
    pub fn unwarp(&mut self, p: DVec2) -> Option<(DVec2, f64, f64)> {
        self.deformed();
        // Drawn as parts, the parts' joined mesh, the topmost triangle first.
        let on_top: Option<Vec<[u32; 3]>> = self.parts().map(|_| {
            let mut order = self.draw_order();
            order.reverse();
            order
        });
        let deformed = self.deformed.as_ref().map(|(_, d)| d.as_slice())?;
        // Else the mesh the method moves (the picture's, or a cage's inside).
        let (rest, triangles) = match (self.parts(), &on_top) {
            (Some(parts), Some(order)) => (parts.rest(), order.as_slice()),
            _ => (self.deformer().rest(), self.deformer().triangles()),
        };
        let ([a, b, c], [u, v, w]) = locate(deformed, triangles, p)?;
        let [pa, pb, pc] = [a, b, c].map(|v| deformed[v as usize]);
        let [ra, rb, rc] = [a, b, c].map(|v| rest[v as usize]);
        let at_rest = ra * u + rb * v + rc * w;
        // The affine map rest → deformed of this triangle, as its similarity part.
        let rest_frame = glam::DMat2::from_cols(rb - ra, rc - ra);
        let pose_frame = glam::DMat2::from_cols(pb - pa, pc - pa);
        let (angle, scale) = if rest_frame.determinant().abs() > 1e-12 {
            let j = pose_frame * rest_frame.inverse();
            let angle = (j.x_axis.y - j.y_axis.x).atan2(j.x_axis.x + j.y_axis.y);
            let scale = j.determinant().max(0.0).sqrt();
            (angle, if scale > 1e-6 { scale } else { 1.0 })
        } else {
            (0.0, 1.0)
        };
        Some((at_rest, angle, scale))
    }

    /// The rotation and scale a new point handle at rest position `rest`, placed at
    /// `at` in the current pose, should start with so that inserting it moves the
    /// picture as little as it can: the similarity (about `rest`, taking `rest` to
    /// `at`) that best fits where the current pose puts the vertices the new handle's
    /// weight will reach. Its support will be about the distance to the nearest node
    /// (the support radius r_h), so the vertices within that distance are fitted, each
    /// weighted by the basis φ(d/r) as the weights will be. `(0, 1)` where nothing is
    /// posed or nothing is there to fit.
    pub fn local_pose(&mut self, rest: DVec2, at: DVec2) -> (f64, f64) {
        if self.parts().is_some() {
            // Drawn as parts: the similarity of the part's triangle under `at`.
            return self
                .unwarp(at)
                .map_or((0.0, 1.0), |(_, angle, scale)| (angle, scale));
        }
        self.deformed();
        let deformed = self
            .deformed
            .as_ref()
            .map_or(&[][..], |(_, d)| d.as_slice());
        let Some(rig) = self.rig() else {
            // No C² weights to fit by: the similarity of the triangle under `at`.
            return self
                .unwarp(at)
                .map_or((0.0, 1.0), |(_, angle, scale)| (angle, scale));
        };
        let positions = rig.domain().positions();
        let reach = rig
            .nodes()
            .iter()
            .map(|n| positions[n.vertex as usize].distance(rest))
            .fold(f64::INFINITY, f64::min);
        let reach = if reach.is_finite() {
            reach
        } else {
            // No node: the picture is at rest.
            return (0.0, 1.0);
        };
        // The same fit the rig gives a handle it lays over a posed picture, so that
        // placing one moves nothing.
        let Some((rotate, scale)) = weights_core::similarity_fit(
            rig.domain(),
            &rig.options().basis,
            deformed,
            rest,
            at,
            reach,
        ) else {
            // Nothing to fit, or folded flat there: keep the handle's own frame.
            return (0.0, 1.0);
        };
        let round = |x: f64, unit: f64| if (x - unit).abs() < 1e-9 { unit } else { x };
        (
            round(rotate, 0.0),
            round(scale.clamp(project::MIN_SCALE, project::MAX_SCALE), 1.0),
        )
    }

    /// Where node `k` of the C² rig is in the current pose (`None` without a rig, or
    /// no such node).
    pub fn node_position(&self, k: usize) -> Option<DVec2> {
        let rig = self.rig()?;
        let vertex = rig.nodes().get(k)?.vertex as usize;
        Some(
            rig.node_transform(k)
                .transform_point2(rig.domain().positions()[vertex]),
        )
    }

    /// The share of handle `handle` in every sample's position: its own nodes'
    /// weights plus the virtual nodes' weights times their harmonic coordinate for it.
    pub fn influence(&self, handle: usize) -> Vec<f32> {
        let of_part = |rig: &Rig, own: Option<usize>| match own {
            Some(own) => influence_of(rig, own),
            None => vec![0.0; rig.domain().len()],
        };
        self.per_part(0.0, handle, of_part)
            .or_else(|| self.rig().map(|rig| influence_of(rig, handle)))
            .unwrap_or_default()
    }

    /// Each vertex's Voronoi cell, as the mesh vertex of its node (distinct for every
    /// node of every part drawn as parts); `None` for a sample no node reaches.
    pub fn cell_keys(&self) -> Vec<Option<u32>> {
        let cells = |rig: &Rig, base: u32| -> Vec<Option<u32>> {
            (rig.cells().iter())
                .map(|&k| rig.nodes().get(k as usize).map(|node| base + node.vertex))
                .collect()
        };
        let mut base = 0;
        let of_part = |rig: &Rig, _| {
            let keys = cells(rig, base);
            base += rig.domain().len() as u32;
            keys
        };
        self.per_part(None, 0, of_part)
            .or_else(|| self.rig().map(|rig| cells(rig, 0)))
            .unwrap_or_default()
    }

    /// Drawn as parts, for each vertex of the parts' mesh: what `of_part` gives for
    /// its part's own C² rig (a part set up by C²), with the index `handle` has among
    /// that part's handles if it binds it; `none` for a part without one (another
    /// method's, a follower). `None` when not drawn as parts.
    fn per_part<T: Clone>(
        &self,
        none: T,
        handle: usize,
        mut of_part: impl FnMut(&Rig, Option<usize>) -> Vec<T>,
    ) -> Option<Vec<T>> {
        let parts = self.parts()?;
        let mut values = Vec::with_capacity(parts.rest().len());
        for (k, run) in parts.runs() {
            let own = (parts.rig().bound(k))
                .and_then(|(deformer, bound)| {
                    let rig = deformer.as_any().downcast_ref::<Rig>()?;
                    Some((rig, bound.iter().position(|&h| h == handle)))
                })
                .map(|(rig, local)| of_part(rig, local))
                .filter(|v| v.len() == run.len());
            match own {
                Some(own) => values.extend(own),
                None => values.extend(std::iter::repeat_n(none.clone(), run.len())),
            }
        }
        Some(values)
    }
}

/// How much handle `handle` of `rig` moves each vertex: its nodes' weights, and the
/// virtual nodes' by their harmonic coordinate of it, within [0, 1].
fn influence_of(rig: &Rig, handle: usize) -> Vec<f32> {
    let share: Vec<f64> = (0..rig.nodes().len())
        .map(|k| match rig.nodes()[k].kind {
            NodeKind::Point { handle: h } | NodeKind::BarSample { handle: h, .. } => {
                f64::from(u8::from(h == handle))
            }
            NodeKind::Virtual => rig.harmonic_coordinate(k, handle),
            NodeKind::Boundary => 0.0,
        })
        .collect();
    (0..rig.domain().len())
        .map(|v| {
            rig.weights(v)
                .map(|(k, w)| w * share[k])
                .sum::<f64>()
                .clamp(0.0, 1.0) as f32
        })
        .collect()
}

/// `project` with the shapes carried by the picture as a whole left out (the parts'
/// kept): what a shape carried over an edit is worked out from.
fn without_carried(project: &Project) -> Project {
    let mut without = project.clone();
    without.carried.retain(|c| c.part.is_some());
    without
}

/// The first of `triangles` (corners indexing `points`) that contains `p`, and `p`'s
/// barycentric coordinates in it; flat triangles are skipped.
pub(crate) fn locate(
    points: &[DVec2],
    triangles: &[[u32; 3]],
    p: DVec2,
) -> Option<([u32; 3], [f64; 3])> {
    triangles.iter().find_map(|&[a, b, c]| {
        let corner = |v: u32| points.get(v as usize).copied();
        let (pa, pb, pc) = (corner(a)?, corner(b)?, corner(c)?);
        // A point the test below takes (barycentric coordinates down to −10⁻⁹) lies
        // within the corners' box widened by 2·10⁻⁹ of its size; widened by 10⁻⁶ of it
        // here, for rounding. Most triangles are passed over on that alone, without
        // the divisions (a click searched the 37k triangles of the default density in
        // 0.8 ms).
        let (lo, hi) = (pa.min(pb).min(pc), pa.max(pb).max(pc));
        let margin = 1e-6 * (hi - lo).max_element() + 1e-9;
        if p.cmplt(lo - margin).any() || p.cmpgt(hi + margin).any() {
            return None;
        }
        let area = (pb - pa).perp_dot(pc - pa);
        if area.abs() < 1e-12 {
            return None;
        }
        let u = (pb - p).perp_dot(pc - p) / area;
        let v = (pc - p).perp_dot(pa - p) / area;
        let w = 1.0 - u - v;
        let eps = -1e-9;
        (u >= eps && v >= eps && w >= eps).then_some(([a, b, c], [u, v, w]))
    })
}

/// The virtual handles of `from` (a snapshot) that go on into `to`, a rig file for
/// the same picture whose handles are `from`'s with some added or removed: every
/// virtual handle, except those placed for a handle `to` no longer has, each naming
/// its handle's index in `to`.
fn carried_virtuals(
    from: &Project,
    to: &Project,
) -> (Vec<[f64; 2]>, Vec<Option<usize>>, Vec<usize>) {
    // Old handle → new index, matching handles of the same rest geometry in order.
    let mut next = 0;
    let index: Vec<Option<usize>> = from
        .handles
        .iter()
        .map(|h| {
            let found = (next..to.handles.len()).find(|&j| same_rest(h, &to.handles[j]));
            if let Some(j) = found {
                next = j + 1;
            }
            found
        })
        .collect();
    let mut kept = (Vec::new(), Vec::new(), Vec::new());
    for (i, &p) in from.virtual_handles.iter().enumerate() {
        let placed = match from.virtual_placed_for.get(i).copied().flatten() {
            // Placed for a handle: it goes where that handle goes, or with it.
            Some(h) => match index.get(h).copied().flatten() {
                Some(j) => Some(j),
                None => continue,
            },
            None => None,
        };
        kept.0.push(p);
        kept.1.push(placed);
        kept.2.push(from.virtual_copy.get(i).copied().unwrap_or(0));
    }
    if kept.1.iter().all(Option::is_none) {
        kept.1.clear();
    }
    if kept.2.iter().all(|&c| c == 0) {
        kept.2.clear();
    }
    kept
}

/// Whether two handles have the same kind and rest geometry.
pub fn same_rest(a: &HandleSpec, b: &HandleSpec) -> bool {
    match (a, b) {
        (HandleSpec::Point { rest: r, .. }, HandleSpec::Point { rest: s, .. }) => r == s,
        (HandleSpec::Bar { rest: r, .. }, HandleSpec::Bar { rest: s, .. }) => r == s,
        _ => false,
    }
}

/// Where a handle is now: a point handle's position, or a bar's two ends.
pub fn posed(h: &HandleSpec) -> [DVec2; 2] {
    match *h {
        HandleSpec::Point {
            rest, translate, ..
        } => {
            let p = DVec2::from(rest) + DVec2::from(translate);
            [p, p]
        }
        HandleSpec::Bar { rest, pose, .. } => pose.unwrap_or(rest).map(DVec2::from),
    }
}

/// `path` relative to `folder` when it lies inside it, else `path` made absolute.
fn ms(clock: Instant) -> f64 {
    clock.elapsed().as_secs_f64() * 1e3
}
