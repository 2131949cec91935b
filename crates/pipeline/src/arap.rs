//! As-rigid-as-possible manipulation (the `arap` crate) with C2Warp's handles, at the
//! scale the paper works at, whatever the picture's density.
//!
//! The paper pins single vertices of a mesh of a few hundred vertices. Its energy is of
//! first order, so on a fine mesh a single pinned vertex holds almost nothing: the pin
//! pulls a needle out of the picture and the rest swirls around it, the more so the
//! finer the mesh. So, as Photoshop's Puppet Warp does with its "density":
//! - ARAP solves on **its own mesh** of the picture, [`ArapOptions::density`] vertices
//!   (3,000 by default), the same whatever the density of the picture's mesh; every
//!   vertex of the picture's mesh follows the ARAP triangle it lies in (by its
//!   barycentric coordinates there), so 5,000 and 80,000 vertices give the same warp;
//! - each handle **holds a disc** ([`ArapOptions::pin_radius`], 2% of the picture's
//!   diagonal by default): every ARAP vertex within that distance of a point handle
//!   (of a bar's segment), and the corners of the triangles the handle lies in, are
//!   pinned to where the handle's similarity takes them, so what lies under a pin
//!   moves with it, turning and scaling too.
//!
//! With `pin_radius` 0 a point handle pins its nearest vertex alone, as the paper does
//! (and, turned or scaled, that vertex's one-ring). [`ArapRig::new`] solves on a given
//! mesh itself (`c2warp deform --mesh`), where the pin radius is 0 unless the rig file
//! names one: a mesh given as such is taken at its word, and the paper's exact
//! behaviour stays reachable.

use std::any::Any;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use geometry::point_segment_distance;
use glam::DVec2;
use project::{Project, RigidityStroke};
use serde::Serialize;
use weights_core::{Domain, Handle, Metric, Similarity};

use crate::deformer::{
    Deformer, Follow, Method, Output, Sequence, WeightsListing, json, median, quantile,
};

/// How far a brush stroke reaches: the squared distance from a point to the stroke's
/// polyline.
pub use geometry::polyline_distance_squared;

/// ARAP's own mesh when the rig file names no `arap.density`.
pub const DEFAULT_ARAP_DENSITY: usize = 3000;

/// How the local/global solver (`"solver": "local-global"`) settles a pose: from the
/// two steps' answer, until an iteration moves no vertex farther than 3·10⁻⁵ pixel (at
/// most 1,000 iterations), five earlier iterates accelerating it. A long limb's turn
/// converges slowly, so a step of a hundredth of a pixel can still be a pixel from
/// the minimum; at 3·10⁻⁵ a pin placed in a posed state, which leaves the minimum where
/// it was, moves the picture by less than a tenth of a pixel.
pub const SETTLED: arap::Minimise = arap::Minimise {
    iterations: 1000,
    tolerance: 3e-5,
    history: 5,
};

/// How it follows a live drag: from the previous frame's answer, at most this many
/// iterations a frame (the drag's end settles the pose in full, [`SETTLED`]).
pub const LIVE: arap::Minimise = arap::Minimise {
    iterations: 8,
    tolerance: 0.01,
    history: 5,
};

/// What a handle holds when the rig file names no `arap.pin_radius`: this share of the
/// picture's diagonal.
pub const DEFAULT_PIN_RADIUS: f64 = 0.02;

/// ARAP's settings, resolved for one picture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArapOptions {
    /// What a handle holds, in pixels (see the module docs); 0: the nearest vertex.
    pub pin_radius: f64,
    /// Target vertex count of ARAP's own mesh.
    pub density: usize,
    /// How a pose is solved.
    pub solver: project::ArapSolver,
}

impl ArapOptions {
    /// The rig file's settings (its `"arap"` field, defaults where absent) for a
    /// picture whose diagonal is `diagonal` pixels, or for a mesh given as ARAP's own
    /// (`None`: `c2warp deform --mesh`), where a handle pins its nearest vertex unless
    /// the rig file says otherwise, as the paper's handles do.
    pub fn of(project: &Project, diagonal: Option<f64>) -> Self {
        let settings = project.arap.unwrap_or_default();
        Self {
            pin_radius: settings
                .pin_radius
                .unwrap_or_else(|| diagonal.map_or(0.0, |d| DEFAULT_PIN_RADIUS * d)),
            density: settings.density.unwrap_or(DEFAULT_ARAP_DENSITY),
            // The energy's minimum on a picture; the paper's algorithm exactly on a
            // mesh given as ARAP's own.
            solver: settings.solver.unwrap_or(if diagonal.is_some() {
                project::ArapSolver::LocalGlobal
            } else {
                project::ArapSolver::TwoStep
            }),
        }
    }

    /// [`ArapOptions::of`] for a picture.
    pub fn for_picture(project: &Project, picture: &image::RgbaImage) -> Self {
        let (w, h) = picture.dimensions();
        Self::of(project, Some(f64::from(w).hypot(f64::from(h))))
    }
}

/// Milliseconds an ARAP rig spent in each of its steps, most recently.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ArapTimes {
    /// Registration (once per mesh), meshing the picture for ARAP included.
    pub registration_ms: f64,
    /// Compilation (when the pinned vertices or the rigidity change).
    pub compile_ms: f64,
    /// The last update (every pose), the picture's mesh following included.
    pub update_ms: f64,
}

/// ARAP's own mesh of a picture and where the picture's mesh lies in it.
struct Control {
    domain: Domain,
    /// For every vertex of the picture's mesh: the corners of the ARAP triangle it lies
    /// in and its barycentric coordinates there (outside ARAP's mesh, those of the
    /// nearest triangle, extrapolated).
    places: Vec<([u32; 3], [f64; 3])>,
}

impl Control {
    /// ARAP's mesh of `image` at `density` vertices, and the places of `picture`'s
    /// vertices in it.
    fn new(
        image: &image::RgbaImage,
        cuts: &[project::Cut],
        picture: &Domain,
        density: usize,
    ) -> Result<Self> {
        let options = mesh::MeshOptions {
            target_vertices: density,
            ..mesh::MeshOptions::default()
        };
        let (meshed, _) = crate::mesh_picture(image, &options, cuts)
            .context("cannot mesh the picture for ARAP")?;
        let domain = Domain::new(meshed.vertices, meshed.triangles, Metric::Euclidean)
            .context("cannot set up ARAP's mesh")?;
        let mut around: Vec<Vec<u32>> = vec![Vec::new(); domain.len()];
        for (t, tri) in domain.triangles().iter().enumerate() {
            for &v in tri {
                around[v as usize].push(t as u32);
            }
        }
        // A vertex on a cut is looked up from just inside one of its own triangles, so
        // that each side's copy follows ARAP's triangle on its side.
        let mut inward = vec![None; picture.len()];
        if !cuts.is_empty() {
            let positions = picture.positions();
            for tri in picture.triangles() {
                let centroid = tri.iter().map(|&v| positions[v as usize]).sum::<DVec2>() / 3.0;
                for &v in tri {
                    inward[v as usize].get_or_insert(centroid);
                }
            }
        }
        let places = picture
            .positions()
            .iter()
            .zip(&inward)
            .map(|(&p, toward)| place(&domain, &around, p, *toward))
            .collect::<Option<Vec<_>>>()
            .context("ARAP's mesh has no triangle near the picture's")?;
        Ok(Self { domain, places })
    }

    /// Where the picture's vertices go when ARAP's go to `moved`.
    fn follow(&self, moved: &[DVec2], out: &mut Vec<DVec2>) {
        out.clear();
        out.extend(self.places.iter().map(|(tri, bary)| {
            moved[tri[0] as usize] * bary[0]
                + moved[tri[1] as usize] * bary[1]
                + moved[tri[2] as usize] * bary[2]
        }));
    }
}

/// The triangle of `domain` holding `p` and `p`'s barycentric coordinates in it, or,
/// outside, the triangle around `p`'s nearest vertex where `p` is least outside. With
/// `toward`, the triangle is the one holding a point a hair from `p` toward it (the side
/// of a cut `p` belongs to).
fn place(
    domain: &Domain,
    around: &[Vec<u32>],
    p: DVec2,
    toward: Option<DVec2>,
) -> Option<([u32; 3], [f64; 3])> {
    let triangles = domain.triangles();
    if let Some(toward) = toward
        && let Some((t, _)) = domain.locate(p.lerp(toward, 1e-6))
    {
        let tri = triangles[t];
        let corners = tri.map(|k| domain.positions()[k as usize]);
        if let Some(bary) = barycentric(corners, p) {
            return Some((tri, bary));
        }
    }
    if let Some((t, bary)) = domain.locate(p) {
        return Some((triangles[t], bary));
    }
    let v = domain.nearest_vertex(p)?;
    around[v as usize]
        .iter()
        .filter_map(|&t| {
            let tri = triangles[t as usize];
            barycentric(tri.map(|k| domain.positions()[k as usize]), p).map(|b| (tri, b))
        })
        .max_by(|a, b| least(&a.1).total_cmp(&least(&b.1)))
}

fn least(b: &[f64; 3]) -> f64 {
    b[0].min(b[1]).min(b[2])
}

/// Barycentric coordinates of `p` in the triangle `c` (`None` if it has no area).
fn barycentric(c: [DVec2; 3], p: DVec2) -> Option<[f64; 3]> {
    let area = (c[1] - c[0]).perp_dot(c[2] - c[0]);
    if area == 0.0 || !area.is_finite() {
        return None;
    }
    let u = (c[1] - p).perp_dot(c[2] - p) / area;
    let v = (c[2] - p).perp_dot(c[0] - p) / area;
    Some([u, v, 1.0 - u - v])
}

/// As-rigid-as-possible manipulation with C2Warp's handles (see the module docs).
///
/// The paper's handles are mesh vertices that carry a position. Here a handle pins
/// the ARAP vertices it holds (within [`ArapOptions::pin_radius`] of a point handle or
/// a bar's segment, and the corners of the triangles it lies in), each to where the
/// handle's similarity takes it: a point handle's transform about its rest position;
/// for a bar, the similarity taking its rest ends to its posed ends. A vertex two
/// handles hold belongs to the nearer (the first, at equal distance). With a pin
/// radius of 0 a point handle pins its nearest vertex, and a turned or scaled one that
/// vertex's one-ring too; a bar its samples' nearest vertices ([`weights_core::bar_samples`]
/// at [`weights_core::bar_spacing`]).
///
/// Changing which vertices are pinned recompiles (factorises); a pose of the same pins
/// only updates. Cloning shares the factorised systems and ARAP's mesh.
#[derive(Clone)]
pub struct ArapRig {
    /// The picture's mesh: what is drawn, and what [`Deformer::deformed`] answers for.
    picture: Domain,
    /// ARAP's own mesh, when it is not the picture's.
    control: Option<Arc<Control>>,
    options: ArapOptions,
    registration: arap::Registration,
    handles: Vec<Handle>,
    /// The painted strokes, and the rigidity they give each ARAP triangle (1 where
    /// nothing is painted).
    strokes: Vec<RigidityStroke>,
    rigidity: Vec<f64>,
    /// The pinned ARAP vertices, each with the handle that pins it, by vertex.
    pins: Vec<(u32, usize)>,
    /// What handles placed in a posed state hold (the rig file's `holds`).
    holds: Vec<project::Hold>,
    /// For each pin, where its handle holds it in its own frame (final, step one)
    /// when the handle holds the picture as it was placed; `None`: its rest position.
    held: Vec<Option<(DVec2, DVec2)>>,
    compiled: Arc<arap::Compiled>,
    pose: arap::Deformation,
    /// The picture's vertices in the current pose (with ARAP on the picture's own
    /// mesh, a copy of the pose's positions).
    positions: Vec<DVec2>,
    times: ArapTimes,
    /// When the local/global solver stops when it settles a pose and in a live drag,
    /// and how its last pose went.
    minimise: (arap::Minimise, arap::Minimise),
    convergence: Option<arap::Convergence>,
    /// In a live drag; `warm`: the current pose came from the previous one rather
    /// than settled from the two steps.
    live: bool,
    warm: bool,
    /// The diagonal of the picture ARAP meshed, pixels (`None` on a given mesh): what
    /// the rig file's default pin radius resolves against.
    diagonal: Option<f64>,
}

impl ArapRig {
    /// ARAP on `picture`'s mesh itself (the paper's setting; `options.density` is not
    /// used): registers it, compiles for `handles` and poses it.
    ///
    /// # Errors
    /// A degenerate mesh, or handles that cannot be pinned (non-finite, off the mesh).
    pub fn new(
        picture: Domain,
        handles: &[Handle],
        rigidity_strokes: &[RigidityStroke],
        options: ArapOptions,
    ) -> Result<Self> {
        Self::set_up(
            picture,
            None,
            handles,
            rigidity_strokes,
            options,
            Instant::now(),
        )
        .map(|rig| Self {
            diagonal: None,
            ..rig
        })
    }

    /// ARAP on its own mesh of `image` at `options.density` vertices, with `picture`
    /// (the picture's mesh, as drawn) following it.
    ///
    /// # Errors
    /// As [`ArapRig::new`], and a picture that cannot be meshed.
    pub fn with_own_mesh(
        image: &image::RgbaImage,
        picture: Domain,
        handles: &[Handle],
        rigidity_strokes: &[RigidityStroke],
        options: ArapOptions,
    ) -> Result<Self> {
        Self::with_own_mesh_cut(image, &[], picture, handles, rigidity_strokes, options)
    }

    /// [`ArapRig::with_own_mesh`] with ARAP's mesh split along `cuts` as the picture's
    /// is ([`crate::mesh_picture`]).
    ///
    /// # Errors
    /// As [`ArapRig::with_own_mesh`].
    pub fn with_own_mesh_cut(
        image: &image::RgbaImage,
        cuts: &[project::Cut],
        picture: Domain,
        handles: &[Handle],
        rigidity_strokes: &[RigidityStroke],
        options: ArapOptions,
    ) -> Result<Self> {
        let clock = Instant::now();
        let control = Control::new(image, cuts, &picture, options.density)?;
        Self::set_up(
            picture,
            Some(Arc::new(control)),
            handles,
            rigidity_strokes,
            options,
            clock,
        )
        .map(|rig| {
            let (w, h) = image.dimensions();
            Self {
                diagonal: Some(f64::from(w).hypot(f64::from(h))),
                ..rig
            }
        })
    }

    fn set_up(
        picture: Domain,
        control: Option<Arc<Control>>,
        handles: &[Handle],
        rigidity_strokes: &[RigidityStroke],
        options: ArapOptions,
        clock: Instant,
    ) -> Result<Self> {
        if !(options.pin_radius.is_finite() && options.pin_radius >= 0.0) {
            bail!(
                "ARAP's pin radius must be a number of pixels, 0 or more, not {}",
                options.pin_radius
            );
        }
        let mesh = control.as_ref().map_or(&picture, |c| &c.domain);
        let registration = arap::Registration::new(mesh.positions(), mesh.triangles())
            .context("cannot set up ARAP on this mesh")?;
        let rigidity = rigidity_weights(mesh, rigidity_strokes);
        let pins = pins(mesh, &registration, handles, options.pin_radius)?;
        let registration_ms = ms(clock);
        let clock = Instant::now();
        let compiled = Arc::new(compile(&registration, &pins, &rigidity)?);
        let compile_ms = ms(clock);
        let mut rig = Self {
            picture,
            control,
            options,
            registration,
            handles: handles.to_vec(),
            strokes: rigidity_strokes.to_vec(),
            rigidity,
            held: vec![None; pins.len()],
            pins,
            holds: Vec::new(),
            compiled,
            pose: arap::Deformation::default(),
            positions: Vec::new(),
            times: ArapTimes {
                registration_ms,
                compile_ms,
                update_ms: 0.0,
            },
            minimise: (SETTLED, LIVE),
            convergence: None,
            live: false,
            warm: false,
            diagonal: None,
        };
        rig.update()?;
        Ok(rig)
    }

    /// `project`'s ARAP (its handles, rigidity and `"arap"` settings) on the picture's
    /// mesh `domain`: on its own mesh of `picture`, which the picture's follows
    /// ([`ArapRig::with_own_mesh`]), or without a picture on `domain` itself
    /// ([`ArapRig::new`]: a mesh given as such).
    ///
    /// # Errors
    /// As [`ArapRig::with_own_mesh`].
    pub fn on_mesh(
        project: &Project,
        domain: &Domain,
        picture: Option<&image::RgbaImage>,
    ) -> Result<Self> {
        let handles = crate::handles(project);
        let (domain, strokes) = (domain.clone(), &project.rigidity);
        let mut arap = match picture {
            Some(picture) => {
                let options = ArapOptions::for_picture(project, picture);
                let cuts = &project.cuts;
                Self::with_own_mesh_cut(picture, cuts, domain, &handles, strokes, options)?
            }
            None => Self::new(domain, &handles, strokes, ArapOptions::of(project, None))?,
        };
        arap.set_handles_and_holds(&handles, &own_holds(project))?;
        Ok(arap)
    }

    /// The picture's mesh at rest (what is drawn).
    pub fn domain(&self) -> &Domain {
        &self.picture
    }

    /// The handles, in their current poses.
    pub fn handles(&self) -> &[Handle] {
        &self.handles
    }

    /// The mesh ARAP solves on: its own, or the picture's.
    pub fn arap_mesh(&self) -> &Domain {
        self.control.as_ref().map_or(&self.picture, |c| &c.domain)
    }

    /// The settings in use.
    pub fn options(&self) -> ArapOptions {
        self.options
    }

    /// When the local/global solver stops (`"solver": "local-global"`): settling a
    /// pose ([`SETTLED`] unless set here) and in a live drag ([`LIVE`]); poses again
    /// with the new settings. For measurements: the rig file does not set these.
    ///
    /// # Errors
    /// As a pose can fail.
    pub fn set_minimise(&mut self, settled: arap::Minimise, live: arap::Minimise) -> Result<()> {
        self.minimise = (settled, live);
        self.update()
    }

    /// How the local/global solver's last pose converged; `None` under the two steps.
    pub fn convergence(&self) -> Option<arap::Convergence> {
        self.convergence
    }

    /// The times of the last registration, compilation and update.
    pub fn times(&self) -> ArapTimes {
        self.times
    }

    /// How many ARAP vertices the handles pin.
    pub fn pinned(&self) -> usize {
        self.pins.len()
    }

    /// The pinned ARAP vertices, each with the handle that pins it, by vertex.
    pub fn pins(&self) -> &[(u32, usize)] {
        &self.pins
    }

    /// The rigidity of each triangle of ARAP's mesh (1 where nothing is painted).
    pub fn rigidity(&self) -> &[f64] {
        &self.rigidity
    }

    /// Step one's result on ARAP's mesh for the current pose (the scale-free fit of the
    /// paper's §4.1).
    pub fn step_one(&self) -> &[DVec2] {
        &self.pose.step_one
    }

    /// ARAP's mesh in the current pose.
    pub fn arap_positions(&self) -> &[DVec2] {
        &self.pose.positions
    }

    /// The picture's vertices in the current pose.
    pub fn positions(&self) -> &[DVec2] {
        &self.positions
    }

    /// Paints new rigidity (recompiles).
    ///
    /// # Errors
    /// As [`ArapRig::new`].
    pub fn set_rigidity(&mut self, strokes: &[RigidityStroke]) -> Result<()> {
        if strokes == self.strokes {
            return Ok(());
        }
        let rigidity = rigidity_weights(self.arap_mesh(), strokes);
        if rigidity != self.rigidity {
            let clock = Instant::now();
            self.compiled = Arc::new(compile(&self.registration, &self.pins, &rigidity)?);
            self.times.compile_ms = ms(clock);
            self.rigidity = rigidity;
            self.update()?;
        }
        self.strokes = strokes.to_vec();
        Ok(())
    }

    /// The strokes the rigidity comes from.
    pub fn strokes(&self) -> &[RigidityStroke] {
        &self.strokes
    }

    /// Takes new handles (the holds kept): a new pose of the same pins only updates;
    /// other pins recompile. On error nothing changes.
    ///
    /// # Errors
    /// Handles that cannot be pinned (non-finite, off the mesh), or a failed
    /// factorisation.
    pub fn set_handles(&mut self, handles: &[Handle]) -> Result<()> {
        let holds = self.holds.clone();
        self.set_handles_and_holds(handles, &holds)
    }

    /// Takes new handles and what those placed in a posed state hold (a rig file's
    /// `holds`, whose indices name `handles`): a new pose of the same pins and holds
    /// only updates; other pins recompile. On error nothing changes.
    ///
    /// # Errors
    /// As [`ArapRig::set_handles`].
    pub fn set_handles_and_holds(
        &mut self,
        handles: &[Handle],
        holds: &[project::Hold],
    ) -> Result<()> {
        let pins = self.pins_of(handles)?;
        let held = if pins == self.pins && holds == self.holds {
            self.held.clone()
        } else {
            held_places(self.arap_mesh(), &pins, holds)
        };
        let old = (
            std::mem::replace(&mut self.handles, handles.to_vec()),
            std::mem::replace(&mut self.holds, holds.to_vec()),
            std::mem::replace(&mut self.held, held),
        );
        let result = if pins == self.pins {
            self.update()
        } else {
            let clock = Instant::now();
            match compile(&self.registration, &pins, &self.rigidity) {
                Ok(compiled) => {
                    self.times.compile_ms = ms(clock);
                    let old_compiled = std::mem::replace(&mut self.compiled, Arc::new(compiled));
                    let old_pins = std::mem::replace(&mut self.pins, pins);
                    let result = self.update();
                    if result.is_err() {
                        self.compiled = old_compiled;
                        self.pins = old_pins;
                    }
                    result
                }
                Err(e) => Err(e),
            }
        };
        if result.is_err() {
            (self.handles, self.holds, self.held) = old;
            // The previous pose stands; recompute it so the buffers match it.
            let _ = self.update();
        }
        result
    }

    /// The ARAP vertices `handles` pin on this rig's mesh, each with its handle.
    fn pins_of(&self, handles: &[Handle]) -> Result<Vec<(u32, usize)>> {
        pins(
            self.arap_mesh(),
            &self.registration,
            handles,
            self.options.pin_radius,
        )
    }

    /// What handle `index` of `handles` (just placed, in the pose the rig shows now)
    /// must hold so that the picture stays where it is: the ARAP vertices it pins,
    /// where the current solve puts them (both steps' answers), in the handle's own
    /// frame. `None` when the current solve has them where the handle's pose takes
    /// their rest positions anyway (at rest, or a pose the handle follows exactly).
    ///
    /// # Errors
    /// Handles that cannot be pinned.
    pub fn hold_for(&self, handles: &[Handle], index: usize) -> Result<Option<project::Hold>> {
        let Some(handle) = handles.get(index) else {
            return Ok(None);
        };
        let Some(inverse) = handle_affine(handle).and_then(invert) else {
            return Ok(None);
        };
        let pins = self.pins_of(handles)?;
        let rest = self.arap_mesh().positions();
        let (final_now, one_now) = (&self.pose.positions, &self.pose.step_one);
        let mut hold = project::Hold {
            handle: index,
            rest: Vec::new(),
            at: Vec::new(),
            step_one: Vec::new(),
            part: None,
        };
        // How far from its rest place a point may be before it counts as held away.
        let tiny = 1e-9 * self.arap_mesh().mean_edge_length().max(1.0);
        let mut away = false;
        for &(v, h) in &pins {
            let v = v as usize;
            if h != index || v >= final_now.len() || v >= one_now.len() {
                continue;
            }
            let at = inverse.transform_point2(final_now[v]);
            let one = inverse.transform_point2(one_now[v]);
            away |= at.distance(rest[v]) > tiny || one.distance(rest[v]) > tiny;
            hold.rest.push(rest[v].to_array());
            hold.at.push(at.to_array());
            hold.step_one.push(one.to_array());
        }
        Ok(away.then_some(hold))
    }

    /// Poses the compiled system for the current handles, and the picture with it.
    fn update(&mut self) -> Result<()> {
        let clock = Instant::now();
        let positions = self.arap_mesh().positions();
        let (mut one, mut targets) = (Vec::new(), Vec::new());
        for (&(v, h), held) in self.pins.iter().zip(&self.held) {
            let handle = &self.handles[h];
            let rest = positions[v as usize];
            let (at, at_one) = held.unwrap_or((rest, rest));
            targets.push(handle_map(handle, at));
            one.push(handle_map(handle, at_one));
        }
        let local_global = self.options.solver == project::ArapSolver::LocalGlobal;
        self.warm = local_global && self.live && self.pose.positions.len() == positions.len();
        if self.warm {
            // A drag frame: on from the previous frame's answer.
            self.convergence = Some(self.compiled.minimise_into(
                &targets,
                &mut self.pose,
                &self.minimise.1,
            )?);
        } else {
            self.compiled
                .update_split_into(&one, &targets, &mut self.pose)?;
            // On to the energy's minimum.
            self.convergence = if local_global {
                Some(
                    self.compiled
                        .minimise_into(&targets, &mut self.pose, &self.minimise.0)?,
                )
            } else {
                None
            };
        }
        match &self.control {
            Some(control) => control.follow(&self.pose.positions, &mut self.positions),
            None => self.positions.clone_from(&self.pose.positions),
        }
        self.times.update_ms = ms(clock);
        Ok(())
    }
}

impl Deformer for ArapRig {
    fn method(&self) -> Method {
        Method::Arap
    }

    fn rest(&self) -> &[DVec2] {
        self.picture.positions()
    }

    fn triangles(&self) -> &[[u32; 3]] {
        self.picture.triangles()
    }

    fn follow(&mut self, project: &Project) -> Result<Follow> {
        if ArapOptions::of(project, self.diagonal) != self.options {
            return Ok(Follow::NeedsSetup);
        }
        let before = (self.strokes.clone(), self.handles.clone());
        self.set_rigidity(&project.rigidity)?;
        if let Err(e) = self.set_handles_and_holds(&crate::handles(project), &own_holds(project)) {
            // Leave it as it was: the old rigidity with the old handles.
            let _ = self.set_rigidity(&before.0);
            return Err(e);
        }
        Ok(Follow::Followed)
    }

    fn set_live(&mut self, live: bool) -> Result<()> {
        self.live = live;
        if !live && self.warm {
            self.update()?;
        }
        Ok(())
    }

    fn deformed(&self) -> Vec<DVec2> {
        self.positions.clone()
    }

    fn output(&self) -> Output<'_> {
        Output::Positions(&self.positions)
    }

    fn holds(&self, project: &Project, index: usize) -> Vec<project::Hold> {
        self.hold_for(&crate::handles(project), index)
            .ok()
            .flatten()
            .into_iter()
            .collect()
    }

    fn weights(&self, _listing: WeightsListing) -> Result<serde_json::Value> {
        bail!(
            "ARAP has no weights per handle (it solves for positions): `c2warp weights` lists \
             C² weights (\"method\": \"c2\") or LBC coordinates (\"method\": \"lbc\")"
        )
    }

    /// Registration (as it was measured), compilation by dropping and restoring the
    /// last handle, updates over `poses` random poses.
    fn bench(&mut self, _project: &Project, poses: usize) -> Result<serde_json::Value> {
        let handles = self.handles.clone();
        let registration_ms = self.times.registration_ms;
        let mut compile = vec![self.times.compile_ms];
        if let Some((_, fewer)) = handles.split_last() {
            for _ in 0..4 {
                self.set_handles(fewer)?;
                self.set_handles(&handles)?;
                compile.push(self.times.compile_ms);
            }
        }
        let pinned_vertices = self.pinned();
        let scale = self.picture.mean_edge_length() * 10.0;
        let mut sequence = Sequence::new();
        let poses: Vec<Vec<Handle>> = (0..poses.max(1))
            .map(|_| sequence.jiggle(&handles, scale))
            .collect();
        // Drag frames, live.
        self.live = true;
        let mut update = Vec::new();
        for posed in &poses {
            self.set_handles(posed)?;
            update.push(self.times.update_ms);
        }
        self.live = false;
        let (mut settle, mut iterations) = (Vec::new(), Vec::new());
        for posed in &poses {
            self.set_handles(posed)?;
            settle.push(self.times.update_ms);
            iterations.push(self.convergence.map_or(0.0, |c| c.iterations as f64));
        }
        self.set_handles(&handles)?;
        json(&ArapReport {
            method: "arap",
            samples: self.picture.len(),
            triangles: self.picture.triangles().len(),
            real_handles: handles.len(),
            arap_vertices: self.arap_mesh().len(),
            pin_radius: self.options.pin_radius,
            pinned_vertices,
            registration_ms,
            compile_ms_median: median(compile),
            solver: self.options.solver,
            update_ms_p90: quantile(update.clone(), 0.9),
            update_ms_median: median(update.clone()),
            settle_ms_p90: quantile(settle.clone(), 0.9),
            settle_ms_median: median(settle),
            settle_iterations_median: median(iterations),
            poses: update.len(),
        })
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn clone_box(&self) -> Box<dyn Deformer> {
        Box::new(self.clone())
    }
}

/// ARAP's steps, timed (`c2warp bench`).
#[derive(Serialize)]
struct ArapReport {
    method: &'static str,
    samples: usize,
    triangles: usize,
    real_handles: usize,
    /// Vertices of the mesh ARAP solves on (its own mesh of the picture, or the given
    /// mesh).
    arap_vertices: usize,
    /// What each handle holds, pixels (0: its nearest vertex).
    pin_radius: f64,
    /// Vertices the handles pin.
    pinned_vertices: usize,
    /// Registration (once per mesh; ARAP's meshing of the picture included), ms.
    registration_ms: f64,
    /// Median compilation (factorising both steps' systems), ms.
    compile_ms_median: f64,
    /// How a pose is solved: `"local-global"` or `"two-step"`.
    solver: project::ArapSolver,
    /// Median update of a drag frame (live: on from the previous pose, at most
    /// [`LIVE`]'s iterations; under the two steps, the two steps), the picture's
    /// vertices following included, ms.
    update_ms_median: f64,
    /// 90th percentile of the drag frames, ms.
    update_ms_p90: f64,
    /// Median and 90th percentile of a pose settled in full (from the two steps to
    /// the energy's minimum; under the two steps, the two steps), ms.
    settle_ms_median: f64,
    settle_ms_p90: f64,
    /// Median local/global iterations a settled pose took.
    settle_iterations_median: f64,
    /// Poses timed.
    poses: usize,
}

/// Compiles ARAP for `pins` and `rigidity`.
fn compile(
    registration: &arap::Registration,
    pins: &[(u32, usize)],
    rigidity: &[f64],
) -> Result<arap::Compiled> {
    let vertices: Vec<u32> = pins.iter().map(|&(v, _)| v).collect();
    Ok(registration.compile(&vertices, Some(rigidity))?)
}

/// Where `handle` takes the rest point `p`: a point handle's similarity about its rest
/// position, or for a bar the similarity taking its rest ends to its posed ends.
pub fn handle_map(handle: &Handle, p: DVec2) -> DVec2 {
    match *handle {
        Handle::Point { rest, transform } => transform.apply(rest, p),
        Handle::Bar { rest, pose } => {
            let c = (rest[0] + rest[1]) * 0.5;
            Similarity::from_segments(c, rest, pose).apply(c, p)
        }
    }
}

/// A handle's map ([`handle_map`]) as an affine transform of the plane (`None` for a
/// bar whose posed ends coincide).
fn handle_affine(handle: &Handle) -> Option<glam::DAffine2> {
    match *handle {
        Handle::Point { rest, transform } => Some(transform.to_affine(rest)),
        Handle::Bar { rest, pose } => {
            let c = (rest[0] + rest[1]) * 0.5;
            Some(Similarity::from_segments(c, rest, pose).to_affine(c))
        }
    }
}

/// `map`'s inverse, when it has one.
fn invert(map: glam::DAffine2) -> Option<glam::DAffine2> {
    let det = map.matrix2.determinant();
    (det.is_finite() && det.abs() > 1e-300).then(|| map.inverse())
}

/// A held point this close to a vertex (squared pixels) is that vertex: far below a
/// mesh edge, far above a coordinate's rounding.
const SAME_POINT_SQUARED: f64 = 1e-12;

/// `project`'s holds on the picture's own mesh (not those of a part's, which
/// [`crate::parts`] hands each part as its own).
fn own_holds(project: &Project) -> Vec<project::Hold> {
    project
        .holds
        .iter()
        .filter(|hold| hold.is_on(None))
        .cloned()
        .collect()
}

/// For each of `pins`, where its handle holds it (final, step one), from `holds`: the
/// hold's own entry for the vertex at that rest position, or — on another mesh of
/// ARAP's (a new `arap.density`) — the affine map that best fits the hold's points,
/// applied to the vertex's rest position. `None` for a handle that holds nothing.
fn held_places(
    mesh: &Domain,
    pins: &[(u32, usize)],
    holds: &[project::Hold],
) -> Vec<Option<(DVec2, DVec2)>> {
    let positions = mesh.positions();
    let key = |p: [f64; 2]| (p[0].to_bits(), p[1].to_bits());
    let mut by_handle: std::collections::HashMap<usize, HeldLookup> = Default::default();
    for hold in holds {
        let entries = hold
            .rest
            .iter()
            .enumerate()
            .map(|(i, &r)| (key(r), i))
            .collect();
        let fit = |to: &[[f64; 2]]| fit_affine(&hold.rest, to);
        by_handle.insert(
            hold.handle,
            HeldLookup {
                entries,
                hold,
                fits: (fit(&hold.at), fit(&hold.step_one)),
            },
        );
    }
    pins.iter()
        .map(|&(v, h)| {
            let lookup = by_handle.get(&h)?;
            let rest = positions[v as usize];
            // The vertex itself, or (a part's hold, saved on the canvas and moved into
            // the part's own rectangle and back) within a rounding of it.
            let listed = lookup
                .entries
                .get(&key(rest.to_array()))
                .copied()
                .or_else(|| {
                    (lookup.hold.rest.iter())
                        .position(|&r| DVec2::from(r).distance_squared(rest) < SAME_POINT_SQUARED)
                });
            match listed {
                Some(i) => Some((
                    DVec2::from(lookup.hold.at[i]),
                    DVec2::from(lookup.hold.step_one[i]),
                )),
                None => Some((
                    lookup.fits.0.transform_point2(rest),
                    lookup.fits.1.transform_point2(rest),
                )),
            }
        })
        .collect()
}

/// A hold, looked up by its points' rest positions, with the affine fits of its
/// points (final, step one) for vertices it does not list.
struct HeldLookup<'a> {
    entries: std::collections::HashMap<(u64, u64), usize>,
    hold: &'a project::Hold,
    fits: (glam::DAffine2, glam::DAffine2),
}

/// The affine map that takes `from` nearest `to` in least squares (a translation for
/// fewer than three points or points on a line; the identity for none).
fn fit_affine(from: &[[f64; 2]], to: &[[f64; 2]]) -> glam::DAffine2 {
    let n = from.len().min(to.len());
    if n == 0 {
        return glam::DAffine2::IDENTITY;
    }
    let mean =
        |pts: &[[f64; 2]]| pts[..n].iter().map(|&p| DVec2::from(p)).sum::<DVec2>() / n as f64;
    let (cf, ct) = (mean(from), mean(to));
    // Normal equations of x ↦ A (x − cf) + ct.
    let (mut xx, mut xy) = (glam::DMat2::ZERO, glam::DMat2::ZERO);
    for (&f, &t) in from[..n].iter().zip(&to[..n]) {
        let (f, t) = (DVec2::from(f) - cf, DVec2::from(t) - ct);
        xx += glam::DMat2::from_cols(f * f.x, f * f.y);
        xy += glam::DMat2::from_cols(t * f.x, t * f.y);
    }
    let linear = if xx.determinant().abs() > 1e-12 * (1.0 + xx.x_axis.x + xx.y_axis.y).powi(2) {
        xy * xx.inverse()
    } else {
        glam::DMat2::IDENTITY
    };
    glam::DAffine2::from_mat2_translation(linear, ct - linear * cf)
}

/// The vertices of `mesh` the handles pin (see [`ArapRig`]), each with its handle,
/// sorted by vertex.
fn pins(
    mesh: &Domain,
    registration: &arap::Registration,
    handles: &[Handle],
    radius: f64,
) -> Result<Vec<(u32, usize)>> {
    // Each vertex goes to the nearest handle that claims it.
    let mut claims: std::collections::BTreeMap<u32, (f64, usize)> = Default::default();
    let mut claim = |v: u32, h: usize, d: f64| {
        let slot = claims.entry(v).or_insert((d, h));
        if d < slot.0 {
            *slot = (d, h);
        }
    };
    for (h, handle) in handles.iter().enumerate() {
        let segment = match *handle {
            Handle::Point { rest, transform } => {
                if !(rest.is_finite() && transform.is_finite()) {
                    bail!("handle {h} has a non-finite position or pose");
                }
                [rest, rest]
            }
            Handle::Bar { rest, pose } => {
                if !rest.iter().chain(&pose).all(|p| p.is_finite()) {
                    bail!("bar {h} has a non-finite position or pose");
                }
                rest
            }
        };
        let off = || format!("handle {h} is off the mesh");
        if radius == 0.0 {
            match *handle {
                Handle::Point { rest, transform } => {
                    let v = mesh.nearest_vertex(rest).with_context(off)?;
                    claim(v, h, 0.0);
                    if transform.rotation != 0.0 || transform.scale != 1.0 {
                        for n in registration.neighbours(v)? {
                            claim(n, h, 0.0);
                        }
                    }
                }
                Handle::Bar { rest, .. } => {
                    let spacing = weights_core::bar_spacing(handles, h);
                    for (_, p) in weights_core::bar_samples(rest, spacing) {
                        claim(mesh.nearest_vertex(p).with_context(off)?, h, 0.0);
                    }
                }
            }
            continue;
        }
        let distance = |p: DVec2| point_segment_distance(p, segment[0], segment[1]);
        let positions = mesh.positions();
        for v in mesh.vertices_near_segment(segment[0], segment[1], radius) {
            claim(v, h, distance(positions[v as usize]));
        }
        // The triangles the handle lies in, whole, so the handle itself moves exactly
        // with its similarity even where the disc holds no vertex.
        let length = (segment[1] - segment[0]).length();
        let step = 0.5 * mesh.mean_edge_length().max(1e-9);
        let samples = ((length / step).ceil() as usize).clamp(1, 10_000);
        let mut found = false;
        for k in 0..=samples {
            let p = segment[0].lerp(segment[1], k as f64 / samples as f64);
            if let Some((t, _)) = mesh.locate(p) {
                found = true;
                for v in mesh.triangles()[t] {
                    claim(v, h, distance(positions[v as usize]));
                }
            }
        }
        if !found {
            let v = mesh.nearest_vertex(segment[0]).with_context(off)?;
            claim(v, h, distance(positions[v as usize]));
        }
    }
    Ok(claims.into_iter().map(|(v, (_, h))| (v, h)).collect())
}

/// The rigidity of every triangle of `mesh`: the largest weight of the strokes that
/// reach it, 1 where none does. A stroke reaches a triangle when its polyline passes
/// within its radius of the triangle's centroid, a corner or the middle of an edge,
/// or a point of the stroke lies inside the triangle (so a thin stroke still paints
/// the coarse triangles of ARAP's own mesh it crosses).
pub fn rigidity_weights(mesh: &Domain, strokes: &[RigidityStroke]) -> Vec<f64> {
    rigidity_weights_of(mesh.positions(), mesh.triangles(), strokes, None)
}

/// [`rigidity_weights`] of the mesh `positions` and `triangles`; with `part_of` (each
/// triangle's part, a mesh joined from parts), a stroke that names a part paints that
/// part's triangles alone.
pub fn rigidity_weights_of(
    positions: &[DVec2],
    triangles: &[[u32; 3]],
    strokes: &[RigidityStroke],
    part_of: Option<&[u32]>,
) -> Vec<f64> {
    let corners: Vec<[DVec2; 3]> = triangles
        .iter()
        .map(|t| t.map(|v| positions[v as usize]))
        .collect();
    let mut weights = vec![1.0; corners.len()];
    let mut painted = vec![false; corners.len()];
    for stroke in strokes {
        let points: Vec<DVec2> = stroke.stroke.iter().map(|&p| DVec2::from(p)).collect();
        let Some(first) = points.first() else {
            continue;
        };
        let (lo, hi) = points
            .iter()
            .fold((*first, *first), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
        let (lo, hi) = (lo - stroke.radius, hi + stroke.radius);
        let r2 = stroke.radius * stroke.radius;
        let other_part = |t: usize| match (stroke.part, part_of) {
            (Some(k), Some(parts)) => parts.get(t).is_none_or(|&p| p as usize != k),
            _ => false,
        };
        for (t, c) in corners.iter().enumerate() {
            let (tlo, thi) = (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2]));
            if thi.cmplt(lo).any() || tlo.cmpgt(hi).any() || other_part(t) {
                continue;
            }
            let centroid = (c[0] + c[1] + c[2]) / 3.0;
            let samples = [
                centroid,
                c[0],
                c[1],
                c[2],
                (c[0] + c[1]) * 0.5,
                (c[1] + c[2]) * 0.5,
                (c[2] + c[0]) * 0.5,
            ];
            let reached = samples
                .iter()
                .any(|&q| polyline_distance_squared(&points, q) <= r2)
                || points
                    .iter()
                    .any(|&p| barycentric(*c, p).is_some_and(|b| least(&b) >= 0.0));
            if reached {
                weights[t] = if painted[t] {
                    f64::max(weights[t], stroke.weight)
                } else {
                    stroke.weight
                };
                painted[t] = true;
            }
        }
    }
    weights
}

fn ms(clock: Instant) -> f64 {
    clock.elapsed().as_secs_f64() * 1000.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use weights_core::Metric;

    /// The paper's pins: a point handle holds its nearest vertex.
    const PAPER: ArapOptions = ArapOptions {
        pin_radius: 0.0,
        density: DEFAULT_ARAP_DENSITY,
        solver: project::ArapSolver::TwoStep,
    };

    /// A `w × h` grid of unit squares, each cut into two triangles.
    fn grid(w: u32, h: u32) -> Domain {
        let positions = (0..=h)
            .flat_map(|y| (0..=w).map(move |x| DVec2::new(f64::from(x), f64::from(y))))
            .collect();
        let mut triangles = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let v = y * (w + 1) + x;
                triangles.push([v, v + 1, v + w + 2]);
                triangles.push([v, v + w + 2, v + w + 1]);
            }
        }
        Domain::new(positions, triangles, Metric::Euclidean).expect("a grid")
    }

    fn point(rest: DVec2, translation: DVec2, rotation: f64, scale: f64) -> Handle {
        Handle::Point {
            rest,
            transform: Similarity {
                translation,
                rotation,
                scale,
            },
        }
    }

    #[test]
    fn a_rigid_motion_of_every_handle_moves_every_vertex_by_it() {
        let domain = grid(12, 6);
        let (angle, centre, shift) = (0.7, DVec2::new(6.0, 3.0), DVec2::new(3.0, -2.0));
        let motion = |p: DVec2| centre + shift + glam::DMat2::from_angle(angle) * (p - centre);
        let rests = [
            DVec2::new(1.0, 1.0),
            DVec2::new(11.0, 5.0),
            DVec2::new(6.0, 0.0),
        ];
        let mut handles: Vec<Handle> = rests
            .iter()
            .map(|&r| point(r, motion(r) - r, angle, 1.0))
            .collect();
        let bar = [DVec2::new(2.0, 5.0), DVec2::new(5.0, 5.0)];
        handles.push(Handle::Bar {
            rest: bar,
            pose: bar.map(motion),
        });
        let arap = ArapRig::new(domain.clone(), &handles, &[], PAPER).expect("ARAP");
        for (p, r) in arap.positions().iter().zip(domain.positions()) {
            assert!((*p - motion(*r)).length() < 1e-9, "{r} went to {p}");
        }
    }

    #[test]
    fn the_local_global_solver_lowers_the_energy_and_keeps_the_pins() {
        let domain = grid(16, 4);
        // One end held, the other lifted and turned: a bend.
        let handles = [
            point(DVec2::new(0.0, 2.0), DVec2::ZERO, 0.0, 1.0),
            point(DVec2::new(16.0, 2.0), DVec2::new(-5.0, 6.0), 1.3, 1.0),
        ];
        let two = ArapRig::new(domain.clone(), &handles, &[], PAPER).expect("two steps");
        let options = ArapOptions {
            solver: project::ArapSolver::LocalGlobal,
            ..PAPER
        };
        let refined = ArapRig::new(domain.clone(), &handles, &[], options).expect("refined");
        let energy = |arap: &ArapRig| arap.compiled.energy(&arap.pose.positions);
        assert!(
            energy(&refined) < 0.9 * energy(&two),
            "local/global {} against the two steps' {}",
            energy(&refined),
            energy(&two)
        );
        let rest = refined.arap_mesh().positions();
        for &(v, h) in &refined.pins {
            let target = handle_map(&handles[h], rest[v as usize]);
            assert!(refined.pose.positions[v as usize].distance(target) < 1e-9);
        }
        // Parsed from the rig file.
        let project =
            Project::from_json(r#"{"version":1,"handles":[],"arap":{"solver":"local-global"}}"#)
                .expect("a rig file");
        assert_eq!(
            ArapOptions::of(&project, None).solver,
            project::ArapSolver::LocalGlobal
        );
    }

    #[test]
    fn a_plain_point_handle_pins_one_vertex_and_a_turned_one_its_ring() {
        let domain = grid(8, 8);
        let centre = DVec2::new(4.0, 4.0);
        let plain = ArapRig::new(
            domain.clone(),
            &[point(centre, DVec2::new(1.0, 0.0), 0.0, 1.0)],
            &[],
            PAPER,
        )
        .expect("ARAP");
        assert_eq!(plain.pinned(), 1);
        // One handle: the whole shape translates with it.
        for (p, r) in plain.positions().iter().zip(domain.positions()) {
            assert!((*p - *r - DVec2::new(1.0, 0.0)).length() < 1e-9);
        }
        let mut turned = plain.clone();
        turned
            .set_handles(&[point(centre, DVec2::new(1.0, 0.0), 0.5, 1.2)])
            .expect("turned");
        assert_eq!(turned.pinned(), 7, "the vertex and its six neighbours");
        let v = domain
            .nearest_vertex(DVec2::new(5.0, 4.0))
            .expect("a vertex") as usize;
        let expected = Similarity {
            translation: DVec2::new(1.0, 0.0),
            rotation: 0.5,
            scale: 1.2,
        }
        .apply(centre, DVec2::new(5.0, 4.0));
        assert!((turned.positions()[v] - expected).length() < 1e-9);
    }

    #[test]
    fn no_handles_give_the_rest_shape_and_crowded_handles_stay_finite() {
        let domain = grid(6, 3);
        let arap = ArapRig::new(domain.clone(), &[], &[], PAPER).expect("ARAP");
        assert_eq!(arap.positions(), domain.positions());
        // Turned handles whose rings overlap, a collinear row, a bar along the border.
        let handles = [
            point(DVec2::new(2.0, 1.0), DVec2::new(0.0, 1.0), 1.0, 2.0),
            point(DVec2::new(3.0, 1.0), DVec2::new(0.0, -1.0), -1.0, 0.5),
            point(DVec2::new(4.0, 1.0), DVec2::ZERO, 0.0, 1.0),
            Handle::Bar {
                rest: [DVec2::new(0.0, 3.0), DVec2::new(6.0, 3.0)],
                pose: [DVec2::new(0.0, 4.0), DVec2::new(6.0, 2.0)],
            },
        ];
        let arap = ArapRig::new(domain, &handles, &[], PAPER).expect("ARAP");
        assert!(arap.positions().iter().all(|p| p.is_finite()));
        // A non-finite pose is refused and the last one stays.
        let mut same = arap.clone();
        let mut bad = handles.to_vec();
        bad[0] = point(DVec2::new(2.0, 1.0), DVec2::new(f64::NAN, 0.0), 0.0, 1.0);
        assert!(same.set_handles(&bad).is_err());
        assert_eq!(same.positions(), arap.positions());
        assert_eq!(same.handles(), &handles);
    }

    #[test]
    fn rigidity_takes_the_largest_stroke_that_reaches_each_triangle() {
        // Coarse triangles: 10 × 1 unit squares scaled by 10.
        let domain = {
            let d = grid(10, 1);
            let positions = d.positions().iter().map(|p| *p * 10.0).collect();
            Domain::new(positions, d.triangles().to_vec(), Metric::Euclidean).expect("grid")
        };
        let stroke = |points: Vec<[f64; 2]>, radius, weight| RigidityStroke {
            stroke: points,
            radius,
            weight,
            part: None,
        };
        let centroid = |t: usize| {
            domain.triangles()[t]
                .iter()
                .map(|&v| domain.positions()[v as usize])
                .sum::<DVec2>()
                / 3.0
        };
        let holding = |p: DVec2| domain.locate(p).expect("on the mesh").0;
        // A thin stroke through the middle of a big triangle paints it, though it
        // passes far from its centroid's radius.
        let thin = centroid(3) + DVec2::new(0.3, -0.2);
        let weights = rigidity_weights(&domain, &[stroke(vec![thin.to_array()], 0.1, 50.0)]);
        assert_eq!(weights[holding(thin)], 50.0);
        assert_eq!(weights.iter().filter(|&&w| w != 1.0).count(), 1);
        // A wide disc at a corner reaches every triangle around it; a far one none.
        let weights = rigidity_weights(&domain, &[stroke(vec![[30.0, 0.0]], 2.0, 7.0)]);
        let around = domain
            .triangles()
            .iter()
            .filter(|t| {
                t.iter()
                    .any(|&v| domain.positions()[v as usize] == DVec2::new(30.0, 0.0))
            })
            .count();
        assert_eq!(weights.iter().filter(|&&w| w == 7.0).count(), around);
        let weights = rigidity_weights(&domain, &[stroke(vec![[500.0, 500.0]], 2.0, 7.0)]);
        assert!(weights.iter().all(|&w| w == 1.0));
        // Overlapping strokes: the largest weight wins; a weight below 1 softens.
        let weights = rigidity_weights(
            &domain,
            &[
                stroke(vec![[5.0, 5.0], [75.0, 5.0]], 1.0, 10.0),
                stroke(vec![[75.0, 5.0]], 1.0, 1000.0),
                stroke(vec![[95.0, 5.0]], 1.0, 0.01),
            ],
        );
        assert_eq!(weights[holding(DVec2::new(75.0, 5.0))], 1000.0);
        assert_eq!(weights[holding(DVec2::new(40.0, 5.0))], 10.0);
        assert_eq!(weights[holding(DVec2::new(95.0, 5.0))], 0.01);
    }
}
