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
use pipeline::cage::{CageCoordinates, CageDeformer, CageMesh};
use pipeline::{ArapRig, Controls, Deformer, Follow, Method};
use project::{
    CageSpec, HandleSpec, LbcSettings, MetricChoice, Middle, Placement, Project, RigidityStroke,
    Tau,
};
use weights_core::{Domain, NodeKind, Rig, VirtualHandle};

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
}

/// What a cage's coordinates are solved for: the rest cage, τ and the number of mesh
/// vertices inside it (as `c2warp render` reads them from the rig file).
#[derive(Clone, Debug, PartialEq)]
pub struct CageKey {
    /// The rest cage, image pixels.
    pub rest: Vec<[f64; 2]>,
    /// The locality weighting.
    pub tau: Tau,
    /// Target mesh vertices inside the cage.
    pub vertices: usize,
}

impl CageKey {
    /// The key of `project`'s cage (`None` without a cage).
    pub fn of(project: &Project) -> Option<Self> {
        let cage = project.cage.as_ref()?;
        Some(Self {
            rest: cage.rest.clone(),
            tau: project.lbc.unwrap_or_default().tau,
            vertices: pipeline::cage::cage_vertices(project, None),
        })
    }

    /// Why this cage cannot be solved (not a simple polygon), if it cannot.
    pub fn problem(&self) -> Option<String> {
        let points = self.rest.iter().map(|&p| DVec2::from(p)).collect();
        lbc::Cage::new(points).err().map(|e| {
            let hint = match e {
                lbc::LbcError::SelfIntersection { .. } => {
                    ": move a vertex so that no two edges cross"
                }
                lbc::LbcError::RepeatedVertex { .. } => ": move or remove one of them",
                _ => "",
            };
            format!("the cage cannot be solved: {e}{hint}")
        })
    }
}

/// Solves the local barycentric coordinates of `key`'s cage, telling `progress` each
/// ADMM iteration (it returns `false` to cancel). The same computation as `c2warp
/// render` does for a rig file with that cage, τ and density.
///
/// # Errors
/// A cage that is not a simple polygon, or a cancelled solve.
pub fn solve_cage(
    key: &CageKey,
    progress: &mut dyn FnMut(&lbc::Progress) -> bool,
) -> Result<Arc<CageCoordinates>> {
    let project = Project {
        method: Method::Lbc,
        cage: Some(CageSpec {
            rest: key.rest.clone(),
            pose: None,
        }),
        lbc: Some(LbcSettings {
            tau: key.tau,
            density: Some(key.vertices),
        }),
        ..Project::default()
    };
    let mesh = CageMesh::Triangulate {
        target_vertices: key.vertices,
    };
    Ok(Arc::new(pipeline::cage::cage_coordinates(
        &project, mesh, progress,
    )?))
}

/// Solved cages kept, so an undo or a redo across cage edits needs no new solve.
const SOLUTIONS_KEPT: usize = 4;

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
    /// Where the picture came from (`None`: the built-in picture).
    pub image_path: Option<PathBuf>,
    /// Where the project was last saved or loaded from.
    pub project_path: Option<PathBuf>,
    rig: Rig,
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
    /// it was set up on ([`pipeline::beside_rig`]). The C² rig stays beside it: it
    /// holds the mesh and the handles, and its heat maps.
    method: Option<(u64, Box<dyn Deformer>)>,
    /// Solved cages, the most recent last (at most [`SOLUTIONS_KEPT`]).
    solutions: Vec<(CageKey, Arc<CageCoordinates>)>,
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
        let prepared = pipeline::prepare(&image, &project, None)?;
        // Virtual handles live in the rig while editing; they are written out on save.
        project.virtual_handles.clear();
        project.virtual_placed_for.clear();
        Self {
            project,
            image,
            deep: None,
            image_path,
            project_path: None,
            rig: prepared.rig,
            weights_version: 1,
            pose_version: 1,
            last_update_ms: ms(clock),
            deformed: None,
            mesh_version: 1,
            method: None,
            solutions: Vec::new(),
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
        if self.project.method.controls() == Controls::Cage {
            return self.sync_cage();
        }
        if let Some((mesh, deformer)) = &mut self.method
            && *mesh == self.mesh_version
            && deformer.method() == self.project.method
            && deformer.follow(&self.project)? == Follow::Followed
        {
            return Ok(());
        }
        self.method = pipeline::beside_rig(&self.project, &self.rig, Some(&self.image))?
            .map(|deformer| (self.mesh_version, deformer));
        Ok(())
    }

    /// The cage method's deformer: the rig file's cage posed by its solved coordinates
    /// (kept while the solution stays the same; none until the cage is solved).
    fn sync_cage(&mut self) -> Result<()> {
        let Some(solution) = self.cage_solution().cloned() else {
            self.method = None;
            return Ok(());
        };
        if let Some((_, deformer)) = &mut self.method
            && deformer
                .as_any()
                .downcast_ref::<CageDeformer>()
                .is_some_and(|cage| Arc::ptr_eq(cage.solution(), &solution))
            && deformer.follow(&self.project)? == Follow::Followed
        {
            return Ok(());
        }
        let deformer = CageDeformer::new(solution, self.cage_pose())?;
        self.method = Some((self.mesh_version, Box::new(deformer)));
        Ok(())
    }

    /// The cage method's deformer, when the rig file's cage is solved and LBC chosen.
    pub fn cage_deformer(&self) -> Option<&CageDeformer> {
        let (_, deformer) = self.method.as_ref()?;
        deformer.as_any().downcast_ref::<CageDeformer>()
    }

    /// Bumped whenever the picture is meshed anew.
    pub fn mesh_version(&self) -> u64 {
        self.mesh_version
    }

    /// The mesh's triangles in drawing order, back to front, by the handles' depths
    /// (see [`pipeline::order`]).
    pub fn draw_order(&self) -> Vec<[u32; 3]> {
        let depths: Vec<i32> = self.project.handles.iter().map(HandleSpec::depth).collect();
        pipeline::draw_order(&self.rig, &depths)
    }

    /// The method in use.
    pub fn method(&self) -> Method {
        self.project.method
    }

    /// The handle method's deformer: the C² rig itself, or the one set up beside it.
    pub fn deformer(&self) -> &dyn Deformer {
        match &self.method {
            Some((_, deformer)) => deformer.as_ref(),
            None => &self.rig,
        }
    }

    /// The ARAP rig, when ARAP is in use (its step times, its rigidity per triangle).
    pub fn arap(&self) -> Option<&ArapRig> {
        self.method
            .as_ref()
            .and_then(|(_, deformer)| deformer.as_any().downcast_ref::<ArapRig>())
    }

    /// The cage, if the rig file has one.
    pub fn cage(&self) -> Option<&CageSpec> {
        self.project.cage.as_ref()
    }

    /// The cage at rest (empty without a cage).
    pub fn cage_rest(&self) -> Vec<DVec2> {
        self.cage()
            .map(|c| c.rest.iter().map(|&p| DVec2::from(p)).collect())
            .unwrap_or_default()
    }

    /// Where the cage's vertices are posed (at rest where the rig file gives no pose;
    /// empty without a cage).
    pub fn cage_pose(&self) -> Vec<DVec2> {
        self.cage()
            .map(|c| {
                c.pose
                    .as_ref()
                    .unwrap_or(&c.rest)
                    .iter()
                    .map(|&p| DVec2::from(p))
                    .collect()
            })
            .unwrap_or_default()
    }

    /// The solved coordinates of the rig file's cage, if they have been solved for
    /// this rest cage, τ and density.
    pub fn cage_solution(&self) -> Option<&Arc<CageCoordinates>> {
        let key = CageKey::of(&self.project)?;
        self.solution_for(&key)
    }

    /// The coordinates solved for `key`, if kept.
    pub fn solution_for(&self, key: &CageKey) -> Option<&Arc<CageCoordinates>> {
        self.solutions
            .iter()
            .rev()
            .find(|(k, _)| k == key)
            .map(|(_, s)| s)
    }

    /// Whether the picture is warped by a solved cage: LBC chosen and its cage solved.
    pub fn cage_warps(&self) -> bool {
        self.cage_deformer().is_some()
    }

    /// Keeps coordinates solved for `key` (the oldest kept are forgotten). If `key` is
    /// the rig file's cage, the picture is now warped by it.
    ///
    /// # Errors
    /// Coordinates that do not fit `key` (another number of cage vertices).
    pub fn add_solution(&mut self, key: CageKey, solution: Arc<CageCoordinates>) -> Result<()> {
        if solution.weights.cage_vertices() != key.rest.len() {
            bail!(
                "coordinates for {} cage vertices solved for a cage of {}",
                solution.weights.cage_vertices(),
                key.rest.len()
            );
        }
        self.solutions.retain(|(k, _)| *k != key);
        if self.solutions.len() >= SOLUTIONS_KEPT {
            self.solutions.remove(0);
        }
        let current = CageKey::of(&self.project).as_ref() == Some(&key);
        self.solutions.push((key, solution));
        if current {
            self.weights_version += 1;
            self.pose_version += 1;
            self.sync_method()?;
        }
        Ok(())
    }

    /// Takes over the solved cages of `other` (the same picture, rebuilt): solutions
    /// depend only on the cage, not on the picture's mesh.
    ///
    /// # Errors
    /// A kept solution that does not fit the rig file's cage pose.
    pub(crate) fn keep_solutions_of(&mut self, other: &Document) -> Result<()> {
        self.solutions.clone_from(&other.solutions);
        self.sync_method()
    }

    /// Solves the rig file's cage here and now (seconds; the editor does it on its
    /// worker), unless it is solved already.
    ///
    /// # Errors
    /// No cage, a cage that is not a simple polygon, or a cancelled solve.
    pub fn solve_cage(&mut self, progress: &mut dyn FnMut(&lbc::Progress) -> bool) -> Result<()> {
        let Some(key) = CageKey::of(&self.project) else {
            bail!("there is no cage to solve");
        };
        if self.solution_for(&key).is_some() {
            return Ok(());
        }
        if let Some(problem) = key.problem() {
            bail!(problem);
        }
        let solution = solve_cage(&key, progress)?;
        self.add_solution(key, solution)
    }

    /// Every vertex of the solved cage's mesh where the cage's pose takes it; `None`
    /// unless LBC is chosen and its cage solved.
    pub fn cage_deformed(&self) -> Option<&[DVec2]> {
        self.cage_deformer().map(CageDeformer::positions)
    }

    /// Cage vertex `i`'s coordinate function at every vertex of the solved cage's mesh
    /// (its compact rows: zero where the weight fell below `10⁻³/n`); `None` unless the
    /// cage is solved and has that vertex.
    pub fn cage_influence(&self, i: usize) -> Option<Vec<f32>> {
        let weights = &self.cage_solution()?.weights;
        if i >= weights.cage_vertices() {
            return None;
        }
        Some(
            (0..weights.vertices())
                .map(|v| {
                    weights
                        .row(v)
                        .iter()
                        .find(|&&(k, _)| k as usize == i)
                        .map_or(0.0, |&(_, w)| w as f32)
                })
                .collect(),
        )
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
        let picture = pipeline::load_picture(path)?;
        let project = Project {
            image: Some(path.to_path_buf()),
            ..Project::default()
        };
        Self::from_picture(picture, Some(path.to_path_buf()), project)
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
        match picture {
            render::Picture::Rgba8(image) => Self::new(image, image_path, project),
            deep @ render::Picture::Rgba16(_) => {
                let mut document = Self::new(deep.to_rgba8().into_owned(), image_path, project)?;
                document.deep = Some(Arc::new(deep));
                Ok(document)
            }
        }
    }

    /// A project file and the picture it names (relative to the project file).
    ///
    /// # Errors
    /// An unreadable or malformed project, a project without a picture, or a missing
    /// or bad picture, each naming the file.
    pub fn open_project(path: &Path) -> Result<Self> {
        let project = pipeline::load_project(path)?;
        let Some(image) = &project.image else {
            bail!("{} names no image", path.display());
        };
        let image_path = path.parent().unwrap_or(Path::new("")).join(image);
        let picture = pipeline::load_picture(&image_path)
            .with_context(|| format!("the image of project {}", path.display()))?;
        let mut document = Self::from_picture(picture, Some(image_path), project)
            .with_context(|| format!("project {}", path.display()))?;
        document.project_path = Some(path.to_path_buf());
        Ok(document)
    }

    /// The rig file as it stands (without virtual handles).
    pub fn project(&self) -> &Project {
        &self.project
    }

    /// The weighted rig.
    pub fn rig(&self) -> &Rig {
        &self.rig
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
        if project.method == Method::Arap
            && (self.project.method != Method::Arap || project.rigidity != self.project.rigidity)
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

    /// The rig file to save next to `path`: the picture's path relative to the file's
    /// folder where possible, and the virtual handles, so it reloads with the same
    /// weights.
    pub fn project_for_saving(&self, path: Option<&Path>) -> Project {
        let mut project = self.snapshot();
        project.image = self.image_path.as_ref().map(|image| {
            let folder = path.and_then(Path::parent).unwrap_or(Path::new(""));
            pipeline::relative_path(image, folder)
        });
        project
    }

    /// Applies an edit. On error nothing changes.
    ///
    /// # Errors
    /// What the rig rejects: a handle off the shape, coincident handles, a zero-length
    /// bar, non-finite values, a missing handle; or a re-mesh that fails.
    pub fn apply(&mut self, edit: Edit) -> Result<()> {
        let mut project = self.project.clone();
        match edit {
            Edit::Add(handle) => {
                self.check_room(&handle)?;
                project.handles.push(handle);
            }
            Edit::Remove(index) => {
                if index >= project.handles.len() {
                    bail!("there is no handle {index}");
                }
                project.handles.remove(index);
            }
            Edit::Pose(index, handle) => match project.handles.get_mut(index) {
                Some(slot) if same_rest(slot, &handle) => *slot = handle,
                Some(_) => bail!("a pose change may not move handle {index} at rest"),
                None => bail!("there is no handle {index}"),
            },
            Edit::Clear => project.handles.clear(),
            Edit::ResetPose => {
                for h in &mut project.handles {
                    *h = at_rest(h);
                }
            }
            Edit::Settings(settings) => settings.write_to(&mut project),
            Edit::Method(Method::Lbc) if project.cage.is_none() => {
                bail!("LBC warps by a cage: draw one first with the cage tool (K)")
            }
            Edit::Method(method) => project.method = method,
            Edit::Rigidity(strokes) => project.rigidity = strokes,
            Edit::Cage { rest, vertices } => {
                if project.lbc.and_then(|l| l.density).is_none() {
                    project.lbc = Some(LbcSettings {
                        density: Some(vertices),
                        ..project.lbc.unwrap_or_default()
                    });
                }
                project.cage = Some(CageSpec { rest, pose: None });
                project.method = Method::Lbc;
                self.check_cage(&project)?;
            }
            Edit::ClearCage => {
                project.cage = None;
                if project.method == Method::Lbc {
                    project.method = Method::C2;
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
            Edit::Mls(settings) => {
                project.mls = Some(settings);
                project
                    .validate(Some(self.image.dimensions()))
                    .context("MLS's settings")?;
            }
        }
        self.restore(project)
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

    /// Refuses a new handle closer to an existing one than two mesh edges: nodes one
    /// edge apart leave no room for graded virtual handles between them, and Algorithm 1
    /// would turn nearly every sample into a node.
    fn check_room(&self, handle: &HandleSpec) -> Result<()> {
        let room = 2.0 * self.rig.domain().mean_edge_length();
        let segment = |h: &HandleSpec| match *h {
            HandleSpec::Point { rest, .. } => [DVec2::from(rest); 2],
            HandleSpec::Bar { rest, .. } => rest.map(DVec2::from),
        };
        let new = segment(handle);
        for (i, other) in self.project.handles.iter().enumerate() {
            let d = segment_distance(new, segment(other));
            if d < room {
                bail!(
                    "too close to handle {}: at this mesh density handles need {room:.1} px \
                     between them (raise the density for finer work)",
                    i + 1
                );
            }
        }
        Ok(())
    }

    /// Makes `project` (same picture) the document's rig file, updating the rig as
    /// cheaply as the difference allows: poses only, handles added or removed
    /// incrementally, a rebuild for new parameters, a re-mesh for a new density.
    ///
    /// # Errors
    /// As [`Document::apply`]; on error nothing changes.
    pub fn restore(&mut self, project: Project) -> Result<()> {
        self.restore_with(project, false)
    }

    /// The rig file with the rig's virtual handles: a state that [`Document::undo_to`]
    /// brings back exactly.
    pub fn snapshot(&self) -> Project {
        let mut project = self.project.clone();
        let positions = self.rig.domain().positions();
        let placed = self.rig.placed_virtual_handles();
        project.virtual_handles = placed
            .iter()
            .map(|v| positions[v.vertex as usize].to_array())
            .collect();
        project.virtual_placed_for = placed.iter().map(|v| v.placed_for).collect();
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
        let virtuals = std::mem::take(&mut project.virtual_handles);
        let placed_for = std::mem::take(&mut project.virtual_placed_for);
        // Another method or another rest cage draws another mesh; another cage pose
        // moves it.
        let cage_mesh_changed = project.method != self.project.method
            || CageKey::of(&project) != CageKey::of(&self.project);
        let clock = Instant::now();
        let old = self.settings();
        let new = Settings::of(&project);
        let handles = pipeline::handles(&project);
        let same_rest = project.handles.len() == self.project.handles.len()
            && project
                .handles
                .iter()
                .zip(&self.project.handles)
                .all(|(a, b)| same_rest(a, b));
        let depths_changed = project.handles.iter().map(HandleSpec::depth).ne(self
            .project
            .handles
            .iter()
            .map(HandleSpec::depth));
        if new.density != old.density {
            let mut with_virtuals = project.clone();
            if exact {
                with_virtuals.virtual_handles = virtuals;
                with_virtuals.virtual_placed_for = placed_for;
            }
            self.rig = pipeline::prepare(&self.image, &with_virtuals, None)?.rig;
            self.mesh_version += 1;
        } else if new == old && exact && !same_rest {
            let domain = self.rig.domain();
            let placed: Vec<VirtualHandle> = virtuals
                .iter()
                .enumerate()
                .filter_map(|(i, &p)| {
                    Some(VirtualHandle {
                        vertex: domain.nearest_vertex(DVec2::from(p))?,
                        placed_for: placed_for.get(i).copied().flatten(),
                    })
                })
                .collect();
            self.rig = Rig::with_placed_virtual_handles(
                domain.clone(),
                handles,
                &placed,
                pipeline::rig_options(&project)?,
            )?;
        } else if new != old {
            let domain = self.rig.domain();
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
            self.rig = Rig::new(domain, handles, pipeline::rig_options(&project)?)?;
        } else {
            if project.handles != self.project.handles {
                self.rig.set_handles(handles)?;
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

    /// Checks the document's invariants: the rig file is valid for the picture, the
    /// rig has exactly its handles, nodes sit on samples, weights are non-negative and
    /// sum to one wherever a node reaches, and the pose deforms every sample to a
    /// finite point. Used by tests after every step of a session.
    ///
    /// # Errors
    /// The first broken invariant, in words.
    pub fn sanity_check(&self) -> Result<()> {
        let (width, height) = self.image.dimensions();
        self.project
            .validate(Some((width, height)))
            .context("the rig file")?;
        if !self.project.virtual_handles.is_empty() {
            bail!("virtual handles belong to the rig while editing, not to the rig file");
        }
        let expected = pipeline::handles(&self.project);
        if self.rig.handles() != expected.as_slice() {
            bail!(
                "the rig's {} handles are not the rig file's {}",
                self.rig.handles().len(),
                expected.len()
            );
        }
        let samples = self.rig.domain().len();
        let nodes = self.rig.nodes();
        if let Some(node) = nodes.iter().find(|n| n.vertex as usize >= samples) {
            bail!("a node sits on sample {} of {samples}", node.vertex);
        }
        // Every sample on small pictures; a spread of them on large ones.
        let stride = (samples / 4000).max(1);
        for v in (0..samples).step_by(stride) {
            let mut sum = 0.0;
            let mut any = false;
            for (k, w) in self.rig.weights(v) {
                if k >= nodes.len() || !w.is_finite() || w < 0.0 {
                    bail!("sample {v} has weight {w} on node {k} of {}", nodes.len());
                }
                sum += w;
                any = true;
            }
            if any && (sum - 1.0).abs() > 1e-9 {
                bail!("the weights of sample {v} sum to {sum}");
            }
        }
        if let Some(v) = self.rig.deform().iter().position(|p| !p.is_finite()) {
            bail!("sample {v} deforms to a non-finite point");
        }
        self.method_sanity_check()?;
        if self.weights_version == 0 || self.pose_version == 0 {
            bail!("versions start at 1");
        }
        self.cage_sanity_check()
    }

    /// The method's deformer is in step with the rig file: set up on this mesh for the
    /// method chosen, and following the rig file again changes nothing.
    fn method_sanity_check(&self) -> Result<()> {
        let method = self.project.method;
        let Some((mesh, deformer)) = &self.method else {
            // The rig is the deformer (C²), or the cage is not solved yet.
            let ok = match method.controls() {
                Controls::Handles => Deformer::method(&self.rig) == method,
                Controls::Cage => self.cage_solution().is_none(),
            };
            if !ok {
                bail!("method {} has no deformer", method.name());
            }
            return Ok(());
        };
        if deformer.method() != method {
            bail!(
                "method {} with a deformer of {}",
                method.name(),
                deformer.method().name()
            );
        }
        match method.controls() {
            Controls::Handles => {
                if *mesh != self.mesh_version || deformer.rest() != self.rig.domain().positions() {
                    bail!("the {} deformer was set up on another mesh", method.name());
                }
            }
            Controls::Cage => {
                let solved = self.cage_solution();
                if self
                    .cage_deformer()
                    .is_none_or(|cage| solved.is_none_or(|s| !Arc::ptr_eq(cage.solution(), s)))
                {
                    bail!("the cage deformer is not the rig file's solved cage");
                }
            }
        }
        let deformed = deformer.deformed();
        if let Some(v) = deformed.iter().position(|p| !p.is_finite()) {
            bail!("{} sends sample {v} to a non-finite point", method.label());
        }
        let mut again = deformer.clone_box();
        if again.follow(&self.project)? != Follow::Followed || again.deformed() != deformed {
            bail!(
                "the {} deformer is out of step with the rig file",
                method.label()
            );
        }
        Ok(())
    }

    /// Checks that the rig file this document saves gives back what the document
    /// shows: reopened (through the JSON text, as a file would be), it builds the same
    /// mesh, handles, virtual handles and weights bit for bit, and the method puts every
    /// vertex in the same place. This is what an export, a reopened project and `c2warp
    /// render` of the saved file draw, so they are the picture on screen. Used by tests
    /// (the monkey runs it at random points of its walks).
    ///
    /// # Errors
    /// The first difference, in words.
    pub fn check_reopens(&self) -> Result<()> {
        let text = self.project_for_saving(None).to_json();
        let saved = Project::from_json(&text).context("the saved rig file does not load")?;
        let mut fresh = Document::with_image(self.image.clone(), self.image_path.clone(), saved)
            .context("the saved rig file does not build")?;
        // Solved cages are not saved (`c2warp render` solves again, to the same
        // coordinates): the reopened document finds this one's for its cage, if the
        // saved cage, τ and density are the same.
        fresh.keep_solutions_of(self)?;
        let (a, b) = (self.rig.domain(), fresh.rig.domain());
        if a.positions() != b.positions() || a.triangles() != b.triangles() {
            bail!(
                "reopened, the picture meshes to {} vertices and {} triangles, not {} and {}",
                b.len(),
                b.triangles().len(),
                a.len(),
                a.triangles().len()
            );
        }
        if self.rig.handles() != fresh.rig.handles() {
            bail!("reopened, the rig has other handles");
        }
        if self.rig.virtual_vertices() != fresh.rig.virtual_vertices() {
            bail!(
                "reopened, the rig has {} virtual handles, not {}",
                fresh.rig.virtual_vertices().len(),
                self.rig.virtual_vertices().len()
            );
        }
        self.rig
            .same_weights_as(&fresh.rig)
            .map_err(|e| anyhow::anyhow!("reopened, the weights differ: {e}"))?;
        if self.deformer().deformed() != fresh.deformer().deformed() {
            bail!(
                "reopened, {} puts the vertices elsewhere",
                self.project.method.label()
            );
        }
        if self.draw_order() != fresh.draw_order() {
            bail!("reopened, the triangles are drawn in another order");
        }
        Ok(())
    }

    /// The cage's part of [`Document::sanity_check`]: kept solutions fit their keys,
    /// the current one's rows are coordinates, and the pose deforms its mesh to finite
    /// points.
    fn cage_sanity_check(&self) -> Result<()> {
        if self.project.method == Method::Lbc && self.project.cage.is_none() {
            bail!("LBC without a cage");
        }
        if self.solutions.len() > SOLUTIONS_KEPT {
            bail!("{} solved cages kept", self.solutions.len());
        }
        for (i, (key, solution)) in self.solutions.iter().enumerate() {
            if self.solutions[..i].iter().any(|(k, _)| k == key) {
                bail!("a cage is kept solved twice");
            }
            let (n, weights) = (key.rest.len(), &solution.weights);
            if weights.cage_vertices() != n || solution.domain.cage().len() != n {
                bail!("coordinates of another cage kept for a cage of {n} vertices");
            }
            if weights.vertices() != solution.domain.positions().len() {
                bail!(
                    "{} rows for a cage mesh of {} vertices",
                    weights.vertices(),
                    solution.domain.positions().len()
                );
            }
        }
        if let Some(solution) = self.cage_solution() {
            let weights = &solution.weights;
            let rows = weights.vertices();
            let stride = (rows / 2000).max(1);
            for v in (0..rows).step_by(stride) {
                let row = weights.row(v);
                let mut sum = 0.0;
                for &(k, w) in row {
                    if k as usize >= weights.cage_vertices() || !w.is_finite() || w < 0.0 {
                        bail!("cage mesh vertex {v} has weight {w} on cage vertex {k}");
                    }
                    sum += w;
                }
                if (sum - 1.0).abs() > 1e-9 {
                    bail!("the coordinates of cage mesh vertex {v} sum to {sum}");
                }
            }
            let deformed = weights
                .deform(&self.cage_pose())
                .context("the cage's pose")?;
            if let Some(v) = deformed.iter().position(|p| !p.is_finite()) {
                bail!("the cage sends its mesh vertex {v} to a non-finite point");
            }
        }
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

    /// The rest position under `p` in the current pose, and the local similarity the
    /// pose applies there (rotation, scale), found from the deformed triangle that
    /// contains `p` (the first one, where folds overlap). `None` off the picture.
    pub fn unwarp(&mut self, p: DVec2) -> Option<(DVec2, f64, f64)> {
        self.deformed();
        let deformed = self.deformed.as_ref().map(|(_, d)| d.as_slice())?;
        let domain = self.rig.domain();
        let rest = domain.positions();
        for &[a, b, c] in domain.triangles() {
            let [pa, pb, pc] = [a, b, c].map(|v| deformed[v as usize]);
            let area = (pb - pa).perp_dot(pc - pa);
            if area.abs() < 1e-12 {
                continue;
            }
            let u = (pb - p).perp_dot(pc - p) / area;
            let v = (pc - p).perp_dot(pa - p) / area;
            let w = 1.0 - u - v;
            let eps = -1e-9;
            if u < eps || v < eps || w < eps {
                continue;
            }
            let [ra, rb, rc] = [a, b, c].map(|v| rest[v as usize]);
            let at_rest = ra * u + rb * v + rc * w;
            // The affine map rest → deformed of this triangle, as its similarity part.
            let rest_frame = glam::DMat2::from_cols(rb - ra, rc - ra);
            let pose_frame = glam::DMat2::from_cols(pb - pa, pc - pa);
            let rotation_scale = if rest_frame.determinant().abs() > 1e-12 {
                let j = pose_frame * rest_frame.inverse();
                let angle = (j.x_axis.y - j.y_axis.x).atan2(j.x_axis.x + j.y_axis.y);
                let scale = j.determinant().max(0.0).sqrt();
                (angle, if scale > 1e-6 { scale } else { 1.0 })
            } else {
                (0.0, 1.0)
            };
            return Some((at_rest, rotation_scale.0, rotation_scale.1));
        }
        None
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
        self.deformed();
        let deformed = self
            .deformed
            .as_ref()
            .map_or(&[][..], |(_, d)| d.as_slice());
        let rig = &self.rig;
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
        let near = rig.domain().vertices_near_segment(rest, rest, reach);
        let basis = &rig.options().basis;
        let (mut dot, mut cross, mut norm) = (0.0, 0.0, 0.0);
        for v in near {
            let Some(&q) = deformed.get(v as usize) else {
                continue;
            };
            let d = positions[v as usize] - rest;
            let e = q - at;
            let w = basis.eval(d.length() / reach);
            dot += w * d.dot(e);
            cross += w * d.perp_dot(e);
            norm += w * d.length_squared();
        }
        if !(norm > 0.0 && dot.is_finite() && cross.is_finite()) {
            return (0.0, 1.0);
        }
        let (a, b) = (dot / norm, cross / norm);
        let scale = a.hypot(b);
        if !(scale > 1e-6 && scale.is_finite()) {
            // Folded flat there: keep the handle's own frame.
            return (0.0, 1.0);
        }
        let round = |x: f64, unit: f64| if (x - unit).abs() < 1e-9 { unit } else { x };
        (
            round(b.atan2(a), 0.0),
            round(scale.clamp(project::MIN_SCALE, project::MAX_SCALE), 1.0),
        )
    }

    /// Where node `k` is in the current pose.
    pub fn node_position(&self, k: usize) -> DVec2 {
        let vertex = self.rig.nodes()[k].vertex as usize;
        self.rig
            .node_transform(k)
            .transform_point2(self.rig.domain().positions()[vertex])
    }

    /// The share of handle `handle` in every sample's position: its own nodes'
    /// weights plus the virtual nodes' weights times their harmonic coordinate for it.
    pub fn influence(&self, handle: usize) -> Vec<f32> {
        let rig = &self.rig;
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
}

/// Distance between two segments (a point is a segment with equal ends); NaN-free for
/// finite input.
fn segment_distance(a: [DVec2; 2], b: [DVec2; 2]) -> f64 {
    let point_segment = |p: DVec2, [s, t]: [DVec2; 2]| {
        let st = t - s;
        let u = if st.length_squared() > 0.0 {
            ((p - s).dot(st) / st.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (p - (s + st * u)).length()
    };
    let cross = |[p, q]: [DVec2; 2], [r, s]: [DVec2; 2]| {
        let d = |a: DVec2, b: DVec2, c: DVec2| (b - a).perp_dot(c - a);
        d(p, q, r) * d(p, q, s) < 0.0 && d(r, s, p) * d(r, s, q) < 0.0
    };
    if cross(a, b) {
        return 0.0;
    }
    point_segment(a[0], b)
        .min(point_segment(a[1], b))
        .min(point_segment(b[0], a))
        .min(point_segment(b[1], a))
}

/// Whether two handles have the same kind and rest geometry.
pub fn same_rest(a: &HandleSpec, b: &HandleSpec) -> bool {
    match (a, b) {
        (HandleSpec::Point { rest: r, .. }, HandleSpec::Point { rest: s, .. }) => r == s,
        (HandleSpec::Bar { rest: r, .. }, HandleSpec::Bar { rest: s, .. }) => r == s,
        _ => false,
    }
}

/// The handle with its pose reset.
pub fn at_rest(h: &HandleSpec) -> HandleSpec {
    match *h {
        HandleSpec::Point { rest, depth, .. } => HandleSpec::Point {
            rest,
            translate: [0.0; 2],
            rotate: 0.0,
            scale: 1.0,
            depth,
        },
        HandleSpec::Bar { rest, depth, .. } => HandleSpec::Bar {
            rest,
            pose: None,
            depth,
        },
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

#[cfg(test)]
mod tests {
    use super::*;

    fn point(x: f64, y: f64) -> HandleSpec {
        HandleSpec::Point {
            rest: [x, y],
            translate: [0.0; 2],
            rotate: 0.0,
            scale: 1.0,
            depth: 0,
        }
    }

    fn document() -> Document {
        let image = RgbaImage::from_pixel(64, 48, image::Rgba([200, 100, 50, 255]));
        let project = Project {
            density: Some(2000),
            handles: vec![point(10.0, 10.0), point(50.0, 30.0)],
            ..Project::default()
        };
        Document::new(image, None, project).expect("a simple document")
    }

    #[test]
    fn a_rejected_edit_changes_nothing() {
        let mut doc = document();
        let before = doc.project().clone();
        let version = doc.weights_version;
        assert!(
            doc.apply(Edit::Add(point(10.0, 10.0))).is_err(),
            "coincident"
        );
        assert!(doc.apply(Edit::Add(point(f64::NAN, 3.0))).is_err(), "NaN");
        assert!(
            doc.apply(Edit::Add(point(500.0, 3.0))).is_err(),
            "off the picture"
        );
        assert!(doc.apply(Edit::Remove(7)).is_err());
        assert!(
            doc.apply(Edit::Pose(0, point(11.0, 10.0))).is_err(),
            "moves rest"
        );
        let bar = HandleSpec::Bar {
            rest: [[20.0, 20.0], [20.0, 20.0]],
            pose: None,
            depth: 0,
        };
        assert!(doc.apply(Edit::Add(bar)).is_err(), "zero-length bar");
        let close = doc.rig().domain().mean_edge_length();
        assert!(
            doc.apply(Edit::Add(point(10.0 + close, 10.0))).is_err(),
            "too close"
        );
        assert_eq!(doc.project(), &before);
        assert_eq!(doc.weights_version, version);
        assert_eq!(doc.rig().handles().len(), 2);
    }

    /// Handle 0 of [`document`] posed.
    fn first_posed(translate: [f64; 2], rotate: f64, scale: f64) -> Edit {
        Edit::Pose(
            0,
            HandleSpec::Point {
                rest: [10.0, 10.0],
                translate,
                rotate,
                scale,
                depth: 0,
            },
        )
    }

    #[test]
    fn pose_edits_keep_weights_and_insertions_update_them() {
        let mut doc = document();
        let w = doc.weights_version;
        doc.apply(first_posed([5.0, 0.0], 0.2, 1.1)).expect("pose");
        assert_eq!(doc.weights_version, w, "a pose leaves the weights");
        // The handle's node sits on the vertex nearest its rest position and goes where
        // the handle's similarity about (10, 10) takes it.
        let vertex = doc.rig().nodes()[0].vertex as usize;
        let rest = doc.rig().domain().positions()[vertex];
        let expected = weights_core::Similarity {
            translation: DVec2::new(5.0, 0.0),
            rotation: 0.2,
            scale: 1.1,
        }
        .apply(DVec2::new(10.0, 10.0), rest);
        let at = doc.node_position(0);
        assert!((at - expected).length() < 1e-9, "{at} vs {expected}");
        doc.apply(Edit::Add(point(30.0, 40.0))).expect("insert");
        assert!(doc.weights_version > w);
        assert_eq!(doc.rig().handles().len(), 3);
        doc.apply(Edit::ResetPose).expect("reset");
        let at = doc.node_position(0);
        assert!((at - rest).length() < 1e-9);
        doc.apply(Edit::Clear).expect("clear");
        assert!(doc.project().handles.is_empty());
        assert_eq!(
            doc.rig().stats().virtual_nodes,
            0,
            "no virtual handles without handles"
        );
    }

    #[test]
    fn a_handle_inserted_under_a_similarity_takes_it_and_nothing_moves() {
        // Every handle moved by one similarity (a rigid motion for ARAP, which keeps
        // sizes): the picture is that similarity, a new handle must start with it, and
        // inserting it must move nothing.
        for (method, scale) in [(Method::C2, 1.3), (Method::Arap, 1.0)] {
            let mut doc = document();
            doc.apply(Edit::Method(method)).expect("method");
            let motion = weights_core::Similarity {
                translation: DVec2::new(3.0, -2.0),
                rotation: 0.4,
                scale,
            };
            let centre = DVec2::new(30.0, 20.0);
            for (i, rest) in [DVec2::new(10.0, 10.0), DVec2::new(50.0, 30.0)]
                .into_iter()
                .enumerate()
            {
                let at = motion.apply(centre, rest);
                let pose = HandleSpec::Point {
                    rest: rest.to_array(),
                    translate: (at - rest).to_array(),
                    rotate: 0.4,
                    scale,
                    depth: 0,
                };
                doc.apply(Edit::Pose(i, pose)).expect("pose");
            }
            let before = doc.deformed().to_vec();
            let rest = DVec2::new(30.0, 38.0);
            let at = motion.apply(centre, rest);
            let (rotate, scale_found) = doc.local_pose(rest, at);
            assert!((rotate - 0.4).abs() < 1e-9, "{method:?}: {rotate}");
            assert!(
                (scale_found - scale).abs() < 1e-9,
                "{method:?}: {scale_found}"
            );
            let new = HandleSpec::Point {
                rest: rest.to_array(),
                translate: (at - rest).to_array(),
                rotate,
                scale: scale_found,
                depth: 0,
            };
            doc.apply(Edit::Add(new)).expect("insert");
            let jump = before
                .iter()
                .zip(doc.deformed())
                .map(|(a, b)| a.distance(*b))
                .fold(0.0, f64::max);
            assert!(jump < 1e-6, "{method:?}: the picture jumped by {jump}");
        }
    }

    #[test]
    fn a_new_handle_fits_the_pose_around_it_not_one_triangle() {
        // A picture sheared around the new handle: the pose there is no similarity, and
        // the fitted one is the least-squares similarity of the vertices within reach,
        // which for a symmetric neighbourhood of a shear x' = x + k·y is a turn of
        // atan(−k/2) and a scale of √(1 + k²/4).
        let mut doc = document();
        let k = 0.3;
        doc.apply(Edit::Settings(Settings {
            density: 8000,
            ..doc.settings()
        }))
        .expect("finer");
        let rest = DVec2::new(32.0, 24.0);
        let reach = doc
            .rig()
            .nodes()
            .iter()
            .map(|n| doc.rig().domain().positions()[n.vertex as usize].distance(rest))
            .fold(f64::INFINITY, f64::min);
        // Shear the deformed picture directly (the cache the fit reads).
        let shear: Vec<DVec2> = doc
            .rig()
            .domain()
            .positions()
            .iter()
            .map(|p| DVec2::new(p.x + k * (p.y - rest.y), p.y))
            .collect();
        let version = (doc.pose_version, doc.weights_version);
        doc.deformed = Some((version, shear));
        let (rotate, scale) = doc.local_pose(rest, rest);
        assert!(reach > 5.0, "{reach}");
        assert!((rotate - (-k / 2.0).atan()).abs() < 0.02, "{rotate}");
        assert!((scale - (1.0 + k * k / 4.0).sqrt()).abs() < 0.02, "{scale}");
    }

    #[test]
    fn unwarp_inverts_the_pose() {
        let mut doc = document();
        doc.apply(first_posed([4.0, 3.0], 0.0, 1.0)).expect("pose");
        let rest = DVec2::new(20.0, 15.0);
        let now = doc
            .rig()
            .deform_point(&doc.rig().deform(), rest)
            .expect("inside");
        let (back, _, scale) = doc.unwarp(now).expect("on the picture");
        assert!((back - rest).length() < 1e-6, "{back} vs {rest}");
        assert!((scale - 1.0).abs() < 0.2);
        assert!(doc.unwarp(DVec2::new(-50.0, -50.0)).is_none());
    }

    #[test]
    fn settings_rebuild_and_influence_partitions_unity() {
        let mut doc = document();
        let mut settings = doc.settings();
        settings.alpha = 0.5;
        settings.metric = MetricChoice::Intrinsic;
        doc.apply(Edit::Settings(settings)).expect("rebuild");
        assert_eq!(doc.rig().options().alpha, 0.5);
        settings.placement = Placement::Symmetric;
        doc.apply(Edit::Settings(settings)).expect("rebuild");
        assert_eq!(
            doc.rig().options().placement,
            weights_core::Placement::Symmetric
        );
        assert_eq!(doc.project().placement, Placement::Symmetric);
        settings.density = 1000;
        doc.apply(Edit::Settings(settings)).expect("re-mesh");
        assert!(doc.rig().domain().len() < 1500);
        let a = doc.influence(0);
        let b = doc.influence(1);
        for (x, y) in a.iter().zip(&b) {
            assert!((x + y - 1.0).abs() < 1e-4, "{x} + {y}");
        }
    }

    #[test]
    fn undo_to_a_snapshot_restores_the_virtual_handles() {
        let mut doc = document();
        let before = doc.snapshot();
        let virtuals = doc.rig().virtual_vertices();
        doc.apply(Edit::Add(point(14.0, 14.0)))
            .expect("a close handle");
        assert_ne!(
            doc.rig().virtual_vertices(),
            virtuals,
            "virtual handles added"
        );
        doc.undo_to(before.clone()).expect("undo");
        assert_eq!(doc.rig().virtual_vertices(), virtuals);
        assert_eq!(doc.snapshot(), before);
    }

    /// Which handle placed each virtual handle survives an undo, a redo and a save, so
    /// removing that handle afterwards still takes its virtual handles along.
    #[test]
    fn removal_after_redo_or_reload_takes_the_virtual_handles_along() {
        let mut doc = document();
        let before = doc.rig().virtual_vertices();
        let undo = doc.snapshot();
        doc.apply(Edit::Add(point(14.0, 14.0)))
            .expect("a close handle");
        let redo = doc.snapshot();
        assert!(
            redo.virtual_placed_for.contains(&Some(2)),
            "the new handle placed virtual handles: {:?}",
            redo.virtual_placed_for
        );
        assert_eq!(redo.virtual_placed_for.len(), redo.virtual_handles.len());

        doc.undo_to(undo).expect("undo");
        doc.undo_to(redo.clone()).expect("redo");
        assert_eq!(doc.snapshot(), redo, "redo restores the owners too");
        let mut reloaded = Document::new((*doc.image).clone(), None, doc.project_for_saving(None))
            .expect("reload");
        for doc in [&mut doc, &mut reloaded] {
            doc.apply(Edit::Remove(2)).expect("remove");
            assert_eq!(
                doc.rig().virtual_vertices(),
                before,
                "the removed handle's virtual handles go with it"
            );
        }
    }

    /// A rectangle on [`document`]'s picture.
    fn cage(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<[f64; 2]> {
        vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]]
    }

    #[test]
    fn a_cage_is_solved_once_per_rest_cage_and_found_again_after_an_undo() {
        let mut doc = document();
        let rest = cage(8.0, 8.0, 56.0, 40.0);
        doc.apply(Edit::Cage {
            rest: rest.clone(),
            vertices: 120,
        })
        .expect("a cage");
        assert_eq!(doc.method(), Method::Lbc);
        assert_eq!(doc.project().lbc.and_then(|l| l.density), Some(120));
        assert!(doc.cage_solution().is_none(), "not solved until asked");
        doc.solve_cage(&mut |_| true).expect("solved");
        let solved = doc.cage_solution().expect("solved").clone();
        doc.sanity_check().expect("consistent");

        // A pose moves the cage's mesh and keeps the coordinates.
        let (weights, pose_version) = (doc.weights_version, doc.pose_version);
        let mut pose = rest.clone();
        pose[2] = [60.0, 46.0];
        doc.apply(Edit::CagePose(pose.clone())).expect("posed");
        assert!(Arc::ptr_eq(doc.cage_solution().expect("kept"), &solved));
        assert_eq!(doc.weights_version, weights);
        assert!(doc.pose_version > pose_version);
        let corner = solved.domain.cage_vertices()[2] as usize;
        let moved = doc.cage_deformed().expect("solved")[corner];
        assert!((moved - DVec2::new(60.0, 46.0)).length() < 1e-9, "{moved}");
        let posed = doc.snapshot();

        // Another rest cage needs a solve; the pose goes back to rest.
        doc.apply(Edit::Cage {
            rest: cage(4.0, 4.0, 30.0, 30.0),
            vertices: 500,
        })
        .expect("another cage");
        assert!(doc.cage_solution().is_none());
        assert_eq!(doc.cage().and_then(|c| c.pose.clone()), None);
        assert_eq!(
            doc.project().lbc.and_then(|l| l.density),
            Some(120),
            "the project's count stays"
        );
        // Back to the solved cage: its coordinates are found, not solved again.
        doc.undo_to(posed.clone()).expect("undo");
        assert!(Arc::ptr_eq(doc.cage_solution().expect("found"), &solved));
        assert_eq!(doc.snapshot(), posed);
        doc.sanity_check().expect("consistent");
    }

    #[test]
    fn bad_cage_edits_change_nothing() {
        let mut doc = document();
        assert!(
            doc.apply(Edit::Method(Method::Lbc)).is_err(),
            "LBC needs a cage"
        );
        assert!(doc.apply(Edit::CagePose(cage(0.0, 0.0, 1.0, 1.0))).is_err());
        let off = Edit::Cage {
            rest: cage(8.0, 8.0, 90.0, 40.0),
            vertices: 100,
        };
        assert!(doc.apply(off).is_err(), "off the picture");
        let two = Edit::Cage {
            rest: vec![[1.0, 1.0], [5.0, 5.0]],
            vertices: 100,
        };
        assert!(doc.apply(two).is_err(), "two vertices");
        assert!(doc.cage().is_none());
        let rest = cage(8.0, 8.0, 56.0, 40.0);
        doc.apply(Edit::Cage {
            rest: rest.clone(),
            vertices: 100,
        })
        .expect("a cage");
        let before = doc.project().clone();
        assert!(doc.apply(Edit::CagePose(vec![[1.0, 1.0]])).is_err());
        assert!(
            doc.apply(Edit::CagePose(vec![[f64::NAN, 1.0]; 4])).is_err(),
            "NaN"
        );
        assert_eq!(doc.project(), &before);
        // A crossing cage is kept (to be fixed) but cannot be solved.
        let bow = vec![[8.0, 8.0], [56.0, 8.0], [8.0, 40.0], [56.0, 40.0]];
        doc.apply(Edit::Cage {
            rest: bow,
            vertices: 100,
        })
        .expect("kept");
        let err = doc.solve_cage(&mut |_| true).expect_err("crossing");
        assert!(err.to_string().contains("intersect"), "{err}");
        // Clearing the cage goes back to C².
        doc.apply(Edit::ClearCage).expect("cleared");
        assert_eq!(doc.method(), Method::C2);
        assert!(doc.cage().is_none());
        doc.sanity_check().expect("consistent");
    }

    #[test]
    fn segment_distances() {
        let p = |x, y| DVec2::new(x, y);
        assert_eq!(segment_distance([p(0.0, 0.0); 2], [p(3.0, 4.0); 2]), 5.0);
        assert_eq!(
            segment_distance([p(0.0, 1.0), p(4.0, 1.0)], [p(2.0, 3.0); 2]),
            2.0
        );
        assert_eq!(
            segment_distance([p(0.0, 0.0), p(2.0, 2.0)], [p(0.0, 2.0), p(2.0, 0.0)]),
            0.0
        );
    }

    #[test]
    fn saved_projects_name_the_picture_relative_to_the_file() {
        let mut doc = document();
        doc.image_path = Some(PathBuf::from("/tmp/pictures/cat.png"));
        let saved = doc.project_for_saving(Some(Path::new("/tmp/pictures/cat.json")));
        assert_eq!(saved.image.as_deref(), Some(Path::new("cat.png")));
        let saved = doc.project_for_saving(Some(Path::new("/elsewhere/cat.json")));
        assert_eq!(
            saved.image.as_deref(),
            Some(Path::new("/tmp/pictures/cat.png"))
        );
    }
}
