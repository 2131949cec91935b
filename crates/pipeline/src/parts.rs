//! Layered artwork warped as parts: every visible layer meshed along its own outline
//! and deformed by the handles that bind it, then composited in the draw order
//! (`c2warp render --parts`, or a rig file with `"parts"`).
//!
//! A handle binds every visible layer with a visible pixel under it (for a bar: under
//! both ends and its middle), so a handle placed where two layers overlap — a shoulder,
//! a hip — binds both: a joint. Each part is set up by the project's method on its own
//! layer alone, with the handles that bind it, so distances stay inside the part; the
//! rig's density is shared among the parts by visible area. A part that no handle
//! binds follows the part beneath it that it overlaps most at rest (the most pixels
//! visible in both; the nearer layer on a tie): its own mesh's vertices go where that
//! part's warped mesh takes them (barycentrically inside it; outside it, by the
//! displacement of its nearest vertex). A part that no handle binds and that overlaps
//! no bound part beneath it stays where it is. Hidden layers are kept as they are.
//!
//! The rig file's `"parts"` ([`project::PartsSpec`]) changes three things: the draw
//! order (`order`, bottom first; "beneath" is in that order), which layers are shown
//! (`hidden`, `shown`, against the file's visibility) and which parts a handle binds
//! (`bindings`: the parts named, whatever lies under the handle).
//!
//! The composite is drawn as one mesh ([`composite`]), so automatic depth (the ARAP
//! paper's §5.1) orders overlaps between parts as within one. [`PartsDeformer`] is
//! the parts behind the method seam (what the editor shows). Under a cage (LBC), every
//! part's vertices are tied to the cage's inside mesh and move with it.

use std::sync::Arc;

use anyhow::{Context, Result, bail};
use glam::{DVec2, Vec2};
use project::{Canvas, CarriedShape, Controls, HandleSpec, Hold, Project};
use render::Picture;
use weights_core::{Domain, Metric};

use crate::carried::Carried;
use crate::deformer::{Deformer, Follow, Method, Output, WeightsListing, json, median, quantile};
use crate::{DEFAULT_DENSITY, Frame, Listener, Warper, blank, placed, prepare_part_warper};

/// The fewest vertices a part is meshed with, whatever its share of the density.
const MIN_PART_DENSITY: usize = 200;

/// One part's mesh, at rest and warped (canvas pixels).
#[derive(Clone, Debug)]
pub struct PartMesh {
    /// Its vertices at rest.
    pub rest: Vec<DVec2>,
    /// Where the warp takes them.
    pub deformed: Vec<DVec2>,
    /// Its triangles, in the order they are drawn (back to front).
    pub triangles: Vec<[u32; 3]>,
}

/// The parts of a layered picture, set up and posed ([`set_up_parts`]).
pub struct PartSet {
    /// The layers' draw order (indices, bottom first): the rig file's `parts.order`,
    /// else the file's.
    pub order: Vec<usize>,
    /// For each layer, its part's mesh; `None` for a hidden layer.
    pub meshes: Vec<Option<PartMesh>>,
    /// For each layer, the handles (indices into the project's) that bind it; empty
    /// for a hidden layer.
    pub bindings: Vec<Vec<usize>>,
    /// For each layer that no handle binds, the layer it follows (if any).
    pub followed: Vec<Option<usize>>,
}

/// What [`warp_parts`] made.
pub struct Parts {
    /// The parts composited: every part's warped mesh drawn as one, back to front in
    /// the layers' order, with automatic depth between and within parts where the
    /// project has it on ([`composite`]).
    pub composite: Picture,
    /// The orders automatic depth gave the overlap regions (between parts and within
    /// them), as a rig file keeps them.
    pub overlaps: Vec<project::OverlapOrder>,
    /// The layers warped, each cut to what its warped mesh covers (hidden layers as
    /// they were), in the draw order.
    pub warped: layers::Artwork,
    /// For each layer, the handles (indices into the project's) that bind it; empty
    /// for a hidden layer.
    pub bindings: Vec<Vec<usize>>,
    /// For each layer that no handle binds, the layer it follows (if any).
    pub followed: Vec<Option<usize>>,
}

/// Warps each visible layer of `artwork` as a part by `project`'s handles (see the
/// module documentation); `density` (else the project's, else the default) is the
/// total over the parts. The canvas is kept (the artwork's).
///
/// # Errors
/// As [`set_up_parts`], and a warp that cannot be drawn (non-finite positions).
pub fn warp_parts(
    artwork: &layers::Artwork,
    project: &Project,
    density: Option<usize>,
    listener: &dyn Listener,
) -> Result<Parts> {
    let set = set_up_parts(artwork, project, density, listener)?;
    let canvas = canvas_of(artwork);
    let mut warped = Vec::with_capacity(artwork.layers.len());
    for &k in &set.order {
        let (layer, mesh) = (&artwork.layers[k], &set.meshes[k]);
        let (x, y, pixels) = match mesh {
            None => (layer.x, layer.y, layer.pixels.clone()),
            Some(mesh) => {
                let on_canvas = on(layer, canvas)?;
                let drawn =
                    draw(&on_canvas, mesh).with_context(|| format!("part \"{}\"", layer.name))?;
                cropped(drawn, &mesh.deformed)
            }
        };
        warped.push(layers::Layer {
            name: layer.name.clone(),
            x,
            y,
            opacity: layer.opacity,
            visible: mesh.is_some(),
            pixels,
        });
    }
    let (composite, overlaps) = composite(artwork, &set, project)?;
    Ok(Parts {
        composite,
        overlaps,
        warped: layers::Artwork {
            width: artwork.width,
            height: artwork.height,
            layers: warped,
            notes: Vec::new(),
        },
        bindings: set.bindings,
        followed: set.followed,
    })
}

/// Meshes, sets up and poses each visible layer of `artwork` as a part by `project`'s
/// handles (see the module documentation); `density` (else the project's, else the
/// default) is the total over the parts.
///
/// # Errors
/// As [`PartRig::new`].
pub fn set_up_parts(
    artwork: &layers::Artwork,
    project: &Project,
    density: Option<usize>,
    listener: &dyn Listener,
) -> Result<PartSet> {
    Ok(PartRig::new(artwork, project, density, listener)?.set())
}

/// The parts of a layered picture set up once — each bound part's method on its own
/// layer, each unbound part's vertices tied to the part it follows — to be posed
/// again and again ([`PartRig::pose`]: an animation's frames).
#[derive(Clone)]
pub struct PartRig {
    /// The layers' draw order (indices, bottom first).
    order: Vec<usize>,
    /// With a cage (LBC): the cage solved on the canvas, which moves every part's
    /// vertices inside it (each tied to the cage's inside mesh).
    cage: Option<Box<crate::cage::CageDeformer>>,
    /// For each layer, what moves it.
    parts: Vec<Part>,
    /// For each layer, the handles (indices into the project's) that bind it.
    bindings: Vec<Vec<usize>>,
    /// For each layer that no handle binds, the layer it follows (if any).
    followed: Vec<Option<usize>>,
    /// Whether the parts follow a live drag ([`PartRig::set_live`]).
    live: bool,
}

/// What moves one layer.
#[derive(Clone)]
enum Part {
    /// A hidden layer: nothing.
    Hidden,
    /// Its own method, on its layer, with the handles that bind it (shared with the
    /// parts this was set up from while it follows the same rig file).
    Bound(Arc<Bound>),
    /// Its own mesh, each vertex where the part it follows takes it.
    Follows {
        mesh: PartMesh,
        /// The part followed, and each vertex's place on it.
        leader: Option<usize>,
        ties: Vec<Tie>,
        /// The vertices it was meshed with.
        density: usize,
    },
}

/// A part set up by its own method, on its own rectangle of the canvas: the layer's
/// pixels with the handles that bind it, a margin around them (so meshing and
/// weighting cost the part's size, not the canvas's).
#[derive(Clone)]
struct Bound {
    /// The method, in the rectangle's pixels.
    warper: Warper,
    /// The rectangle's top-left corner on the canvas.
    origin: DVec2,
    /// The vertices it was meshed with (its share of the density).
    density: usize,
    /// The part's own rig file it follows ([`part_project`], canvas pixels): a rig
    /// file that gives the part the same is not followed again.
    own: Project,
    /// What its mesh was made from: a setup that asks for the same mesh keeps it.
    mesh: MeshKey,
    /// The shape it carries from following another part, if it does
    /// ([`crate::carried`]).
    carried: Option<Carried>,
}

/// What a part's mesh depends on: the rectangle of the canvas it is meshed on (its
/// corner and size), the vertices asked for, the points refined around crowded
/// handles, the cuts and the metric asked for (all in the rectangle's pixels).
#[derive(Clone, PartialEq)]
struct MeshKey {
    origin: DVec2,
    size: (u32, u32),
    density: usize,
    refine: Vec<DVec2>,
    cuts: Vec<project::Cut>,
    metric: project::MetricChoice,
}

impl MeshKey {
    fn of(project: &Project, origin: DVec2, size: (u32, u32), density: usize) -> Self {
        Self {
            origin,
            size,
            density,
            refine: crate::crowding::refinement(project, size.0, size.1, density),
            cuts: project.cuts.clone(),
            metric: project.metric,
        }
    }
}

impl Bound {
    /// The mesh's vertices at rest, on the canvas.
    fn rest(&self) -> Vec<DVec2> {
        self.warper
            .deformer
            .rest()
            .iter()
            .map(|&p| p + self.origin)
            .collect()
    }

    /// Where the warp takes them, on the canvas (with the shape the part carries).
    fn deformed(&self) -> Vec<DVec2> {
        let mut moved = self.placed();
        if let Some(carried) = &self.carried {
            let triangles = self.warper.deformer.triangles();
            carried.apply(self.warper.deformer.rest(), triangles, &mut moved);
        }
        moved
    }

    /// Where its method alone takes them, on the canvas.
    fn placed(&self) -> Vec<DVec2> {
        let mut moved = self.warper.deformer.deformed();
        moved.iter_mut().for_each(|p| *p += self.origin);
        moved
    }

    /// This part carrying the shape `record` (none: carrying none), on its mesh.
    ///
    /// # Errors
    /// A record whose triangles are not a mesh.
    fn carrying(self: Arc<Self>, record: Option<&Arc<CarriedShape>>) -> Result<Arc<Self>> {
        if crate::carried::same_shape(self.carried.as_ref(), record) {
            return Ok(self);
        }
        let carried = record.map(|r| Carried::on(r, &self.rest())).transpose()?;
        let mut bound = Arc::unwrap_or_clone(self);
        bound.carried = carried;
        Ok(Arc::new(bound))
    }

    /// Follows `project` (canvas pixels), this part's own.
    fn follow(&mut self, project: &Project) -> Result<Follow> {
        if *project == self.own {
            return Ok(Follow::Followed);
        }
        let followed = self.warper.follow(&shifted(project, -self.origin))?;
        if followed == Follow::Followed {
            self.own = project.clone();
        }
        Ok(followed)
    }
}

/// What [`PartRig::keep`] gives: each target's new shape (`None`: none) and the parts
/// set up with them.
pub type Kept = (Vec<(usize, Option<Arc<CarriedShape>>)>, PartRig);

/// Where a follower's vertex lies on the mesh of the part it follows.
#[derive(Clone, Copy)]
enum Tie {
    /// In a triangle (the leader's vertices), barycentrically.
    In([u32; 3], [f64; 3]),
    /// Outside the leader's mesh: moved as its nearest vertex moves.
    Near(u32),
    /// Nowhere (no leader): where it is.
    Still,
}

impl PartRig {
    /// Sets every visible layer of `artwork` up as a part for `project`'s handles (see
    /// the module documentation), in `project`'s pose.
    ///
    /// # Errors
    /// An LBC project (its cage deforms the picture as a whole), a handle bound to no
    /// part (off every visible layer), or what setting up a part fails with, naming
    /// the layer.
    pub fn new(
        artwork: &layers::Artwork,
        project: &Project,
        density: Option<usize>,
        listener: &dyn Listener,
    ) -> Result<Self> {
        Self::set_up(artwork, project, density, listener, None)
    }

    /// These parts set up for `project` (another set of handles, another order or
    /// visibility), as [`PartRig::new`] sets them up, keeping each part whose own
    /// setup is the same (the same handles at rest, the same share of the density)
    /// and each follower whose part followed is kept: adding a pin sets up the parts
    /// it binds, not all of them.
    ///
    /// # Errors
    /// As [`PartRig::new`].
    pub fn update(
        &self,
        artwork: &layers::Artwork,
        project: &Project,
        density: Option<usize>,
        listener: &dyn Listener,
    ) -> Result<Self> {
        Self::set_up(artwork, project, density, listener, Some(self))
    }

    /// [`PartRig::new`], keeping what can be kept of `previous` (see
    /// [`PartRig::update`]).
    fn set_up(
        artwork: &layers::Artwork,
        project: &Project,
        density: Option<usize>,
        listener: &dyn Listener,
        previous: Option<&Self>,
    ) -> Result<Self> {
        if project.method.controls() == Controls::Cage {
            return Self::caged(artwork, project, density, listener, previous, None);
        }
        let canvas = canvas_of(artwork);
        let spec = project.parts.clone().unwrap_or_default();
        spec.check_layers(artwork.layers.len())?;
        let order = spec.order_of(artwork.layers.len());
        let shown: Vec<bool> = (artwork.layers.iter().enumerate())
            .map(|(k, layer)| spec.shows(k, layer.visible))
            .collect();
        let bindings = bindings(artwork, project)?;
        let areas: Vec<u64> = (artwork.layers.iter().enumerate())
            .map(|(k, l)| {
                if shown[k] {
                    visible_pixels(&l.pixels)
                } else {
                    0
                }
            })
            .collect();
        let total_area = areas.iter().sum::<u64>().max(1);
        let total = density.or(project.density).unwrap_or(DEFAULT_DENSITY);
        let share = |area: u64| {
            ((total as u128 * u128::from(area) / u128::from(total_area)) as usize)
                .max(MIN_PART_DENSITY)
        };
        // The bound parts set up, each layer put on the canvas only while it is meshed.
        let mut parts: Vec<Part> = Vec::with_capacity(artwork.layers.len());
        // Which bound parts are kept from `previous`.
        let mut kept = vec![false; artwork.layers.len()];
        for (k, ((layer, bound), &area)) in
            (artwork.layers.iter().zip(&bindings).zip(&areas)).enumerate()
        {
            if !shown[k] || bound.is_empty() {
                parts.push(Part::Hidden);
                continue;
            }
            let part = part_project(project, k, bound);
            let density = share(area);
            // The same part with the same setup (method, share of the density, handles
            // at rest): posed, not set up again.
            let same = previous.and_then(|old| match old.parts.get(k)? {
                Part::Bound(b)
                    if b.density == density && b.warper.deformer.method() == project.method =>
                {
                    if b.own == part {
                        // Nothing of this part changed: shared as it is.
                        return Some(b.clone());
                    }
                    if !same_but_poses(&b.own, &part) {
                        // Handles added or removed (or held, or painted): set up anew,
                        // as the saved file is reopened — an incremental update keeps
                        // what its own history placed (C²'s virtual handles, which a
                        // part does not save).
                        return None;
                    }
                    let mut b = Bound::clone(b);
                    (b.follow(&part).ok()? == Follow::Followed).then(|| Arc::new(b))
                }
                _ => None,
            });
            // The shape it carries from following, if it does.
            let carried = project.carried.iter().find(|c| c.part == Some(k));
            let carrying = |b: Arc<Bound>| {
                (b.carrying(carried)).with_context(|| format!("part \"{}\"", layer.name))
            };
            if let Some(b) = same {
                kept[k] = true;
                parts.push(Part::Bound(carrying(b)?));
                continue;
            }
            let probes: Vec<DVec2> = bound
                .iter()
                .flat_map(|&h| probes(&project.handles[h]))
                .collect();
            let (placed_layer, origin) = own_rectangle(layer, canvas, &probes)?;
            let placed = shifted(&part, -origin);
            let picture = placed_layer.to_rgba8();
            let mesh = MeshKey::of(&placed, origin, picture.dimensions(), density);
            // C² on the mesh it had (a pin that asks for no refinement there): the rig
            // built again on it, as a build on the picture gives it.
            let old_domain = previous
                .and_then(|old| match old.parts.get(k)? {
                    Part::Bound(b) if b.mesh == mesh && project.method == Method::C2 => b
                        .warper
                        .deformer
                        .as_any()
                        .downcast_ref::<weights_core::Rig>(),
                    _ => None,
                })
                .map(|rig| rig.domain().clone());
            let warper = match old_domain {
                Some(domain) => placed
                    .validate(Some(picture.dimensions()))
                    .map_err(anyhow::Error::from)
                    .and_then(|()| {
                        crate::rig_on_domain(domain, &placed, &|p| listener.weighting(p))
                    })
                    .map(|rig| Warper::on_rig(rig, &placed)),
                None => prepare_part_warper(&picture, &placed, density, listener),
            }
            .with_context(|| format!("part \"{}\"", layer.name))?;
            parts.push(Part::Bound(carrying(Arc::new(Bound {
                warper,
                origin,
                density,
                own: part,
                mesh,
                carried: None,
            }))?));
        }
        // The parts no handle binds follow the bound part beneath them (in the draw
        // order) they overlap most.
        let mut followed = vec![None; artwork.layers.len()];
        for (at, &k) in order.iter().enumerate() {
            let layer = &artwork.layers[k];
            if !shown[k] || matches!(parts[k], Part::Bound(_)) {
                continue;
            }
            let beneath = (order[..at].iter().rev().copied())
                .filter(|&j| matches!(parts[j], Part::Bound(_)))
                .map(|j| (j, overlap(layer, &artwork.layers[j])))
                .filter(|&(_, n)| n > 0)
                .fold(None, |best: Option<(usize, u64)>, (j, n)| match best {
                    Some((_, m)) if m >= n => best,
                    _ => Some((j, n)),
                });
            followed[k] = beneath.map(|(j, _)| j);
            let density = share(areas[k]);
            // The same follower of a part kept: tied as it was.
            let same = previous.and_then(|old| match old.parts.get(k)? {
                Part::Follows {
                    mesh,
                    leader,
                    ties,
                    density: d,
                } if *leader == followed[k] && *d == density && leader.is_none_or(|j| kept[j]) => {
                    Some((mesh.clone(), ties.clone()))
                }
                _ => None,
            });
            let (mesh, ties) = match same {
                Some(tied) => tied,
                None => {
                    let leader = beneath.and_then(|(j, _)| match &parts[j] {
                        Part::Bound(b) => Some(b.as_ref()),
                        _ => None,
                    });
                    follow(layer, canvas, leader, project, density)
                        .with_context(|| format!("part \"{}\"", layer.name))?
                }
            };
            parts[k] = Part::Follows {
                mesh,
                leader: followed[k],
                ties,
                density,
            };
        }
        let mut rig = Self {
            order,
            cage: None,
            parts,
            bindings,
            followed,
            live: false,
        };
        rig.move_followers();
        Ok(rig)
    }

    /// What handle `index` of `project` (just placed, in the pose shown, on `artwork`
    /// these parts were set up on) must hold on each part it binds so that the part
    /// stays where it is: the part's method's holds ([`Deformer::holds`]: ARAP pins
    /// what is under it where the current solve has it), on the canvas, naming the
    /// part. A part that no handle bound until now follows another, and has no solve
    /// of its own to hold.
    ///
    /// # Errors
    /// A handle bound to no part.
    pub fn holds(
        &self,
        artwork: &layers::Artwork,
        project: &Project,
        index: usize,
    ) -> Result<Vec<Hold>> {
        let mut holds = Vec::new();
        for (k, bound) in bindings(artwork, project)?.iter().enumerate() {
            let Some(local) = bound.iter().position(|&h| h == index) else {
                continue;
            };
            let Some(Part::Bound(b)) = self.parts.get(k) else {
                continue;
            };
            let own = shifted(&part_project(project, k, bound), -b.origin);
            for mut hold in b.warper.deformer.holds(&own, local) {
                let mv = |p: &mut [f64; 2]| *p = (DVec2::from(*p) + b.origin).to_array();
                (hold.rest.iter_mut())
                    .chain(&mut hold.at)
                    .chain(&mut hold.step_one)
                    .for_each(mv);
                hold.handle = index;
                hold.part = Some(k);
                holds.push(hold);
            }
        }
        Ok(holds)
    }

    /// The shapes an edit in a posed state makes the parts carry, so that what
    /// `keep` says stays where it is shown: `edited` is the rig file after the edit
    /// (on `artwork` these parts were set up on, with what its handles hold already),
    /// and for each part of `targets` (a layer's index), `keep` gives at each of its
    /// rest points (canvas pixels) how much of what is shown now stays (1: all, 0:
    /// what its method gives after the edit, with the shape it carried until now) —
    /// a part that followed another keeps the shape following gave it when a pin
    /// first binds it (all of it), a part a removed handle bound lets go near it. A
    /// target that no handle binds after the edit follows (or stays) and carries
    /// nothing. Returns each target's new shape (`None`: none) and the parts set up for
    /// `edited` with them; `None` where `edited` is not posed.
    ///
    /// # Errors
    /// As [`PartRig::update`].
    pub fn keep(
        &self,
        artwork: &layers::Artwork,
        edited: &Project,
        targets: &[(usize, &crate::carried::Keep)],
        density: Option<usize>,
    ) -> Result<Option<Kept>> {
        if targets.is_empty() || !edited.is_posed() {
            return Ok(None);
        }
        let mut rig = self.update(artwork, edited, density, &())?;
        let mut shapes = Vec::new();
        for &(k, keep) in targets {
            let Some(Part::Bound(bound)) = rig.parts.get(k) else {
                continue;
            };
            // What is shown now of the part, and where that shows the new mesh's
            // vertices (at rest, the same mesh but for handles that crowd together).
            let (rest, triangles, shown) = match self.parts.get(k) {
                Some(Part::Follows {
                    mesh,
                    leader: Some(_),
                    ..
                }) => (
                    mesh.rest.clone(),
                    mesh.triangles.clone(),
                    mesh.deformed.clone(),
                ),
                Some(Part::Bound(old)) => (
                    old.rest(),
                    old.warper.deformer.triangles().to_vec(),
                    old.deformed(),
                ),
                _ => continue,
            };
            let new_rest = bound.rest();
            let before = if rest == new_rest {
                shown
            } else {
                let old = Domain::new(rest, triangles, Metric::Euclidean)
                    .map_err(|e| anyhow::anyhow!("part {k}: {e}"))?;
                crate::carried::resample(&old, &shown, &new_rest)
            };
            let new_triangles = bound.warper.deformer.triangles();
            let record = crate::carried::between(
                Some(k),
                &new_rest,
                new_triangles,
                &bound.placed(),
                &bound.deformed(),
                &before,
                keep,
            )
            .map(Arc::new);
            rig.parts[k] = Part::Bound(Arc::clone(bound).carrying(record.as_ref())?);
            shapes.push((k, record));
        }
        rig.move_followers();
        Ok(Some((shapes, rig)))
    }

    /// Poses every part as `project` (the rig file set up, in another pose) has it.
    ///
    /// # Errors
    /// What a part's method refuses of the pose, naming the part's layer index.
    pub fn pose(&mut self, project: &Project) -> Result<()> {
        if self.follow(project)? == Follow::NeedsSetup {
            bail!("the pose asks for a new setup of the parts");
        }
        Ok(())
    }

    /// Poses every part as `project` has it, or says that a part needs setting up
    /// again for it (its handles' rests or its method's settings changed): the parts
    /// are then to be set up anew ([`PartRig::new`]), as some may be posed already
    /// and some not.
    ///
    /// # Errors
    /// What a part's method refuses of the pose, naming the part's layer index.
    pub fn follow(&mut self, project: &Project) -> Result<Follow> {
        if let Some(cage) = &mut self.cage {
            if cage.follow(project)? == Follow::NeedsSetup {
                return Ok(Follow::NeedsSetup);
            }
            self.move_followers();
            return Ok(Follow::Followed);
        }
        for (k, part) in self.parts.iter_mut().enumerate() {
            if let Part::Bound(bound) = part {
                let own = part_project(project, k, &self.bindings[k]);
                if own == bound.own {
                    // A pose that leaves this part's handles as they were.
                    continue;
                }
                if !same_but_poses(&bound.own, &own) {
                    // More than a pose (a handle laid over the weights or held, new
                    // settings): the part is set up anew, as a reopen sets it up.
                    return Ok(Follow::NeedsSetup);
                }
                let bound = Arc::make_mut(bound);
                if bound.follow(&own).with_context(|| format!("part {k}"))? == Follow::NeedsSetup {
                    return Ok(Follow::NeedsSetup);
                }
            }
        }
        self.move_followers();
        Ok(Follow::Followed)
    }

    /// Moves each follower's vertices where its leader's mesh now takes them.
    fn move_followers(&mut self) {
        // The rest and moved vertices of each part some follower follows (of the
        // cage's inside, under a cage), once.
        let followed = |j: usize| self.followed.contains(&Some(j));
        let leaders: Vec<Option<(Vec<DVec2>, Vec<DVec2>)>> = (self.parts.iter().enumerate())
            .map(|(j, p)| match p {
                Part::Bound(b) if followed(j) => Some((b.rest(), b.deformed())),
                _ => None,
            })
            .collect();
        let caged = (self.cage.as_ref()).map(|c| {
            (
                c.solution().domain.positions().to_vec(),
                c.positions().to_vec(),
            )
        });
        for part in &mut self.parts {
            let Part::Follows {
                mesh, leader, ties, ..
            } = part
            else {
                continue;
            };
            let lead = match &caged {
                Some(cage) => Some(cage),
                None => leader.and_then(|j| leaders[j].as_ref()),
            };
            mesh.deformed = mesh
                .rest
                .iter()
                .zip(ties.iter())
                .map(|(&p, tie)| match (tie, lead) {
                    (Tie::In(tri, b), Some((_, moved))) => {
                        (0..3).map(|i| moved[tri[i] as usize] * b[i]).sum()
                    }
                    (Tie::Near(v), Some((rest, moved))) => {
                        p + moved[*v as usize] - rest[*v as usize]
                    }
                    _ => p,
                })
                .collect();
        }
    }

    /// Puts every part's method in or out of live mode (a drag: ARAP's parts start
    /// from the previous frame's answer; out of it, each part's pose is solved in
    /// full, as a file of it renders). Returns whether the parts may have moved (out
    /// of live mode), their followers moved with them.
    ///
    /// # Errors
    /// What a part's method refuses of its pose, naming the part's layer index.
    pub fn set_live(&mut self, live: bool) -> Result<bool> {
        if live == self.live {
            return Ok(false);
        }
        self.live = live;
        let mut moved = false;
        for (k, part) in self.parts.iter_mut().enumerate() {
            if let Part::Bound(bound) = part {
                let bound = Arc::make_mut(bound);
                bound
                    .warper
                    .set_live(live)
                    .with_context(|| format!("part {k}"))?;
                moved |= !live;
            }
        }
        if moved {
            self.move_followers();
        }
        Ok(moved)
    }

    /// For each layer, the handles (indices into the rig file's) that bind it.
    pub fn bindings(&self) -> &[Vec<usize>] {
        &self.bindings
    }

    /// For each layer that no handle binds, the layer it follows (if any).
    pub fn followed(&self) -> &[Option<usize>] {
        &self.followed
    }

    /// Part `k`'s own method (set up on its own rectangle of the canvas) and the
    /// handles that bind it (the rig file's indices); `None` for a part that follows
    /// another, or is hidden, or moves with a cage.
    pub fn bound(&self, k: usize) -> Option<(&dyn Deformer, &[usize])> {
        match self.parts.get(k)? {
            Part::Bound(b) => Some((b.warper.deformer.as_ref(), &self.bindings[k])),
            _ => None,
        }
    }

    /// The cage that moves the parts (LBC), if a cage does.
    pub fn cage(&self) -> Option<&crate::cage::CageDeformer> {
        self.cage.as_deref()
    }

    /// The parts' meshes in the current pose, and what binds them.
    pub fn set(&self) -> PartSet {
        PartSet {
            order: self.order.clone(),
            meshes: self.meshes(),
            bindings: self.bindings.clone(),
            followed: self.followed.clone(),
        }
    }

    /// Part `k`'s triangles in its drawing order (none for a hidden layer).
    fn triangles_of(&self, k: usize) -> &[[u32; 3]] {
        match &self.parts[k] {
            Part::Hidden => &[],
            Part::Bound(b) => &b.warper.triangles,
            Part::Follows { mesh, .. } => &mesh.triangles,
        }
    }

    /// Where the warp takes part `k`'s vertices (none for a hidden layer).
    fn deformed_of(&self, k: usize) -> Vec<DVec2> {
        match &self.parts[k] {
            Part::Hidden => Vec::new(),
            Part::Bound(b) => b.deformed(),
            Part::Follows { mesh, .. } => mesh.deformed.clone(),
        }
    }

    /// For each layer, its part's mesh in the current pose; `None` for a hidden layer.
    pub fn meshes(&self) -> Vec<Option<PartMesh>> {
        self.parts
            .iter()
            .map(|p| match p {
                Part::Hidden => None,
                Part::Bound(b) => Some(PartMesh {
                    rest: b.rest(),
                    deformed: b.deformed(),
                    triangles: b.warper.triangles.clone(),
                }),
                Part::Follows { mesh, .. } => Some(mesh.clone()),
            })
            .collect()
    }
}

/// The visible parts of `set` (meshed from `artwork`) drawn as one mesh onto the
/// canvas: their layers' pixels packed side by side into one texture (each layer's
/// opacity in its alpha), their meshes joined, their triangles back to front in the
/// layers' order and each part's own order — and, where `project` has automatic depth
/// on, the overlap regions of the joined mesh ordered by it (between parts as within
/// one, starting from the `overlaps` the project saved), so that a part swung over
/// another keeps its place while it lies there. Returns the picture, in 16 bits per
/// channel where any visible layer has them, and the regions' orders.
///
/// # Errors
/// Non-finite positions, or not enough memory for the texture or the canvas.
pub fn composite(
    artwork: &layers::Artwork,
    set: &PartSet,
    project: &Project,
) -> Result<(Picture, Vec<project::OverlapOrder>)> {
    Composer::new(artwork, set)?.draw(&set.meshes, project)
}

/// What [`composite`] draws with that does not change with the pose: the texture of
/// the visible parts and where each part's vertices sample it, made once for an
/// animation's frames.
pub struct Composer {
    /// The layers drawn (indices), in order.
    shown: Vec<usize>,
    /// Each drawn layer's pixels, packed.
    texture: Picture,
    /// Each drawn layer's vertices' places in the texture, in order.
    uv: Vec<Vec2>,
    /// The canvas.
    canvas: Frame,
}

impl Composer {
    /// Packs the visible parts of `set` (their layers' pixels, meshed from `artwork`).
    ///
    /// # Errors
    /// Not enough memory for the texture.
    pub fn new(artwork: &layers::Artwork, set: &PartSet) -> Result<Self> {
        /// Transparent pixels around each layer in the texture, so that sampling at a
        /// part's edge sees what lies around it on the canvas: nothing.
        const PAD: u32 = 2;
        let shown: Vec<(usize, &layers::Layer, &PartMesh)> = (set.order.iter())
            .filter_map(|&k| {
                let (layer, mesh) = (artwork.layers.get(k)?, set.meshes.get(k)?.as_ref()?);
                Some((k, layer, mesh)).filter(|_| layer.opacity > 0.0)
            })
            .collect();
        let deep = shown
            .iter()
            .any(|(_, l, _)| l.pixels.bits_per_channel() == 16);
        // Shelves as wide as the widest layer or the square root of the area,
        // whichever is more.
        let area: u64 = shown
            .iter()
            .map(|(_, l, _)| {
                let (w, h) = l.dimensions();
                u64::from(w + 2 * PAD) * u64::from(h + 2 * PAD)
            })
            .sum();
        let widest = shown
            .iter()
            .map(|(_, l, _)| l.dimensions().0 + 2 * PAD)
            .max()
            .unwrap_or(1);
        let width = widest.max((area as f64).sqrt().ceil() as u32);
        let (mut x, mut y, mut shelf) = (0u32, 0u32, 0u32);
        let mut slots = Vec::with_capacity(shown.len());
        for (_, layer, _) in &shown {
            let (w, h) = layer.dimensions();
            let (w, h) = (w + 2 * PAD, h + 2 * PAD);
            if x + w > width {
                (x, y, shelf) = (0, y + shelf, 0);
            }
            slots.push((x + PAD, y + PAD));
            x += w;
            shelf = shelf.max(h);
        }
        let height = (y + shelf).max(1);
        let texture_frame = Frame {
            origin: [0, 0],
            width,
            height,
        };
        let mut texture = blank(if deep { 16 } else { 8 }, texture_frame)?;
        let mut uv = Vec::new();
        for ((_, layer, mesh), &(sx, sy)) in shown.iter().zip(&slots) {
            put(&mut texture, layer, sx, sy);
            let shift = DVec2::new(
                f64::from(sx) - f64::from(layer.x),
                f64::from(sy) - f64::from(layer.y),
            );
            uv.extend(mesh.rest.iter().map(|&p| (p + shift).as_vec2()));
        }
        Ok(Self {
            shown: shown.iter().map(|&(k, _, _)| k).collect(),
            texture,
            uv,
            canvas: canvas_of(artwork),
        })
    }

    /// The drawn parts' `meshes` (the same parts and meshes, in any pose) joined into
    /// one, in the draw order.
    ///
    /// # Errors
    /// Meshes not the ones packed.
    pub fn join(&self, meshes: &[Option<PartMesh>]) -> Result<Joined> {
        let mut joined = Joined::default();
        for &k in &self.shown {
            let Some(mesh) = meshes.get(k).and_then(Option::as_ref) else {
                bail!("part {k} has no mesh to draw");
            };
            let base = joined.rest.len() as u32;
            joined.starts.push((base, k as u32));
            joined.rest.extend_from_slice(&mesh.rest);
            joined.deformed.extend_from_slice(&mesh.deformed);
            (joined.triangles).extend(mesh.triangles.iter().map(|t| t.map(|v| v + base)));
            (joined.part_of).extend(std::iter::repeat_n(k as u32, mesh.triangles.len()));
        }
        if joined.rest.len() != self.uv.len() {
            bail!("the parts' meshes are not the ones their texture was packed for");
        }
        Ok(joined)
    }

    /// The layers drawn (indices), in the draw order.
    pub fn shown(&self) -> &[usize] {
        &self.shown
    }

    /// The texture the joined mesh samples: every drawn layer's pixels, packed.
    pub fn texture(&self) -> &Picture {
        &self.texture
    }

    /// Where each vertex of the joined mesh samples [`Composer::texture`] (pixels).
    pub fn uv(&self) -> &[Vec2] {
        &self.uv
    }

    /// Draws the parts' `meshes` (the same parts and meshes, in any pose), as
    /// [`composite`] does.
    ///
    /// # Errors
    /// Non-finite positions, meshes not the ones packed, or not enough memory for
    /// the canvas.
    pub fn draw(
        &self,
        meshes: &[Option<PartMesh>],
        project: &Project,
    ) -> Result<(Picture, Vec<project::OverlapOrder>)> {
        let Joined {
            rest,
            deformed,
            triangles,
            part_of,
            ..
        } = self.join(meshes)?;
        if deformed.iter().any(|p| !p.is_finite()) {
            bail!("the deformation produced non-finite positions");
        }
        let predefined: Vec<u32> = (0..triangles.len() as u32).collect();
        let (order, overlaps) = if project.auto_depth {
            let mut arranger = crate::order::Arranger::with_parts(
                predefined,
                &project.overlaps,
                &rest,
                &triangles,
                part_of,
            );
            let order = arranger.arrange(&deformed, &triangles);
            (order, arranger.overlaps(&rest, &triangles))
        } else {
            (predefined, Vec::new())
        };
        let drawn = crate::order::as_triangles(&order, &triangles);
        let moved: Vec<Vec2> = deformed.iter().map(|p| p.as_vec2()).collect();
        let mut canvas = blank(self.texture.bits_per_channel(), self.canvas)?;
        render::warp_picture_over(
            &self.texture,
            &render::WarpMesh {
                rest: &self.uv,
                deformed: &moved,
                triangles: &drawn,
            },
            &mut canvas,
        )?;
        Ok((canvas, overlaps))
    }
}

/// The drawn parts' meshes joined into one ([`Composer::join`]).
#[derive(Clone, Debug, Default)]
pub struct Joined {
    /// Every vertex at rest (canvas pixels).
    pub rest: Vec<DVec2>,
    /// Where the warp takes it.
    pub deformed: Vec<DVec2>,
    /// The triangles, the parts back to front in the draw order, each in its own order.
    pub triangles: Vec<[u32; 3]>,
    /// For each triangle, its part (the layer's index).
    pub part_of: Vec<u32>,
    /// Each part's first vertex, and the part, in the draw order.
    pub starts: Vec<(u32, u32)>,
}

/// Layered artwork's parts behind the method seam: one mesh, the parts' meshes joined
/// in the draw order ([`Composer::join`]), each part posed by the handles that bind
/// it ([`PartRig`]), its positions the joined mesh's. The joined mesh samples
/// [`PartsDeformer::composer`]'s texture, not the flattened picture: where parts
/// overlap at rest, each keeps its own pixels.
#[derive(Clone)]
pub struct PartsDeformer {
    rig: PartRig,
    composer: Arc<Composer>,
    joined: Joined,
    /// The layers' names, for what is listed by part.
    names: Vec<String>,
    /// What the parts were set up for: the method, the parts' spec, each handle's
    /// rest and the shapes the parts carry, so that [`Deformer::follow`] tells a pose
    /// from a new setup.
    setup: Setup,
    /// How long setting the parts up took, ms.
    setup_ms: f64,
}

impl PartsDeformer {
    /// Sets every visible layer of `artwork` up as a part for `project` ([`PartRig`])
    /// and joins them.
    ///
    /// # Errors
    /// As [`PartRig::new`]; not enough memory for the texture.
    pub fn new(
        artwork: &layers::Artwork,
        project: &Project,
        density: Option<usize>,
        listener: &dyn Listener,
    ) -> Result<Self> {
        Self::with_rig(
            artwork,
            project,
            |listener| PartRig::new(artwork, project, density, listener),
            listener,
        )
    }

    /// These parts set up for `project` as [`PartsDeformer::new`] does, keeping the
    /// parts whose own setup is the same ([`PartRig::update`]).
    ///
    /// # Errors
    /// As [`PartsDeformer::new`].
    pub fn update(
        &self,
        artwork: &layers::Artwork,
        project: &Project,
        density: Option<usize>,
        listener: &dyn Listener,
    ) -> Result<Self> {
        Self::with_rig(
            artwork,
            project,
            |listener| self.rig.update(artwork, project, density, listener),
            listener,
        )
    }

    /// The parts `set_up` sets up, joined.
    fn with_rig(
        artwork: &layers::Artwork,
        project: &Project,
        set_up: impl FnOnce(&dyn Listener) -> Result<PartRig>,
        listener: &dyn Listener,
    ) -> Result<Self> {
        let clock = std::time::Instant::now();
        let rig = set_up(listener)?;
        let composer = Composer::new(artwork, &rig.set())?;
        let joined = composer.join(&rig.meshes())?;
        Ok(Self {
            setup_ms: clock.elapsed().as_secs_f64() * 1e3,
            rig,
            composer: Arc::new(composer),
            joined,
            names: artwork.layers.iter().map(|l| l.name.clone()).collect(),
            setup: setup_of(project),
        })
    }

    /// Every visible layer of `artwork` as a part inside `project`'s cage, posed by
    /// `cage` (its coordinates solved already, as the editor solves them in the
    /// background; the same as [`PartsDeformer::new`] solves): the parts of
    /// `previous` tied to the same solve are kept.
    ///
    /// # Errors
    /// A cage that is not `project`'s; as [`PartsDeformer::new`].
    pub fn with_cage(
        artwork: &layers::Artwork,
        project: &Project,
        cage: crate::cage::CageDeformer,
        previous: Option<&Self>,
    ) -> Result<Self> {
        Self::with_rig(
            artwork,
            project,
            |listener| {
                let previous = previous.map(|p| &p.rig);
                PartRig::caged(artwork, project, None, listener, previous, Some(cage))
            },
            &(),
        )
    }

    /// The joined mesh's positions (and triangles) from the parts' current ones.
    ///
    /// # Errors
    /// Parts meshed anew without a new setup.
    fn rejoin(&mut self) -> Result<()> {
        // A pose moves the vertices; the joined triangles change only where a part's
        // own drawing order did (a fold within it), and are kept otherwise, so that a
        // caller keeping them (the editor's automatic depth) sees the same mesh.
        let mut deformed = std::mem::take(&mut self.joined.deformed);
        deformed.clear();
        let mut triangles = Vec::with_capacity(self.joined.triangles.len());
        for &k in &self.composer.shown {
            let base = deformed.len() as u32;
            deformed.extend(self.rig.deformed_of(k));
            triangles.extend(self.rig.triangles_of(k).iter().map(|t| t.map(|v| v + base)));
        }
        anyhow::ensure!(
            deformed.len() == self.joined.rest.len(),
            "the parts' meshes changed without a new setup"
        );
        self.joined.deformed = deformed;
        if triangles != self.joined.triangles {
            self.joined.triangles = triangles;
        }
        Ok(())
    }

    /// [`PartRig::keep`] for these parts: the shapes are written to `project`'s
    /// `carried` (a target left without one loses its own), and the parts set up for
    /// it returned; `None` (`project` untouched) where nothing is kept.
    ///
    /// # Errors
    /// As [`PartsDeformer::update`].
    pub fn keep(
        &self,
        artwork: &layers::Artwork,
        project: &mut Project,
        targets: &[(usize, &crate::carried::Keep)],
        density: Option<usize>,
    ) -> Result<Option<Self>> {
        let Some((shapes, rig)) = self.rig.keep(artwork, project, targets, density)? else {
            return Ok(None);
        };
        for (k, shape) in shapes {
            (project.carried).retain(|c| c.part != Some(k));
            project.carried.extend(shape);
        }
        project.carried.sort_by_key(|c| c.part);
        Self::with_rig(artwork, project, |_| Ok(rig), &()).map(Some)
    }

    /// The packed texture and where the joined mesh samples it.
    pub fn composer(&self) -> &Composer {
        &self.composer
    }

    /// How long setting the parts up took (the last setup, not a pose), ms.
    pub fn setup_ms(&self) -> f64 {
        self.setup_ms
    }

    /// The parts set up.
    pub fn rig(&self) -> &PartRig {
        &self.rig
    }

    /// For each triangle, its part (the layer's index).
    pub fn part_of(&self) -> &[u32] {
        &self.joined.part_of
    }

    /// Each part drawn (a layer's index) with its vertices in the joined mesh, in the
    /// draw order.
    pub fn runs(&self) -> Vec<(usize, std::ops::Range<usize>)> {
        let starts = &self.joined.starts;
        (starts.iter().enumerate())
            .map(|(i, &(start, k))| {
                let end = starts
                    .get(i + 1)
                    .map_or(self.joined.rest.len(), |s| s.0 as usize);
                (k as usize, start as usize..end)
            })
            .collect()
    }

    /// The part (the layer's index) vertex `v` of the joined mesh belongs to.
    pub fn part_of_vertex(&self, v: u32) -> Option<u32> {
        // Each part's vertices are one run, in the draw order.
        let at = self.joined.starts.partition_point(|&(start, _)| start <= v);
        let (_, part) = *self.joined.starts.get(at.checked_sub(1)?)?;
        (v < self.joined.rest.len() as u32).then_some(part)
    }
}

/// Whether two rig files of a part differ in their handles' poses alone.
fn same_but_poses(a: &Project, b: &Project) -> bool {
    let at_rest = |p: &Project| Project {
        handles: p.handles.iter().map(HandleSpec::at_rest).collect(),
        ..p.clone()
    };
    a.handles.len() == b.handles.len() && at_rest(a) == at_rest(b)
}

/// What a part setup depends on beyond the pose: the method, the parts' spec, the
/// handles at rest, the shapes the parts carry.
fn setup_of(project: &Project) -> Setup {
    let at_rest = project.handles.iter().map(HandleSpec::at_rest);
    // (Locking a part changes what new handles bind, not what moves the parts.)
    let spec = (project.parts.clone()).map(|spec| project::PartsSpec {
        locked: Vec::new(),
        ..spec
    });
    (
        project.method,
        spec,
        at_rest.collect(),
        project.carried.clone(),
    )
}

/// [`setup_of`]'s answer.
type Setup = (
    Method,
    Option<project::PartsSpec>,
    Vec<HandleSpec>,
    Vec<Arc<CarriedShape>>,
);

impl Deformer for PartsDeformer {
    fn method(&self) -> Method {
        self.setup.0
    }

    fn rest(&self) -> &[DVec2] {
        &self.joined.rest
    }

    fn triangles(&self) -> &[[u32; 3]] {
        &self.joined.triangles
    }

    fn follow(&mut self, project: &Project) -> Result<Follow> {
        if setup_of(project) != self.setup || self.rig.follow(project)? == Follow::NeedsSetup {
            return Ok(Follow::NeedsSetup);
        }
        self.rejoin()?;
        Ok(Follow::Followed)
    }

    fn set_live(&mut self, live: bool) -> Result<()> {
        // Out of live mode, the parts solved in full (ARAP's) move their vertices.
        if self.rig.set_live(live)? {
            self.rejoin()?;
        }
        Ok(())
    }

    fn deformed(&self) -> Vec<DVec2> {
        self.joined.deformed.clone()
    }

    fn output(&self) -> Output<'_> {
        Output::Positions(&self.joined.deformed)
    }

    fn weights(&self, listing: WeightsListing) -> Result<serde_json::Value> {
        let mut parts = Vec::new();
        for &k in &self.rig.order {
            let name = &self.names[k];
            let entry = match &self.rig.parts[k] {
                Part::Hidden => continue,
                Part::Bound(bound) => {
                    let deformer = &bound.warper.deformer;
                    let own = WeightsListing {
                        file_vertices: deformer.rest().len(),
                        ..listing
                    };
                    serde_json::json!({
                        "layer": k,
                        "name": name,
                        "handles": self.rig.bindings[k],
                        "origin": bound.origin.to_array(),
                        "weights": deformer.weights(own).with_context(|| format!("part \"{name}\""))?,
                    })
                }
                Part::Follows { leader, .. } => serde_json::json!({
                    "layer": k,
                    "name": name,
                    "follows": leader,
                }),
            };
            parts.push(entry);
        }
        Ok(serde_json::json!({ "parts": parts }))
    }

    fn bench(&mut self, project: &Project, poses: usize) -> Result<serde_json::Value> {
        let mut sequence = crate::deformer::Sequence::new();
        let scale = crate::mls::mean_edge(&self.joined.rest, &self.joined.triangles) * 10.0;
        let mut times = Vec::new();
        for _ in 0..poses.max(1) {
            let mut posed = project.clone();
            for h in &mut posed.handles {
                let d = [sequence.next() * scale, sequence.next() * scale];
                match h {
                    HandleSpec::Point { translate, .. } => {
                        *translate = [translate[0] + d[0], translate[1] + d[1]];
                    }
                    HandleSpec::Bar { rest, pose, .. } => {
                        let p = pose.unwrap_or(*rest);
                        *pose = Some(p.map(|e| [e[0] + d[0], e[1] + d[1]]));
                    }
                }
            }
            let clock = std::time::Instant::now();
            if self.follow(&posed)? == Follow::NeedsSetup {
                bail!("a pose asked for a new setup of the parts");
            }
            times.push(clock.elapsed().as_secs_f64() * 1e3);
        }
        self.follow(project)?;
        json(&PartsReport {
            method: self.setup.0.name(),
            parts: self
                .rig
                .order
                .iter()
                .filter(|&&k| !matches!(self.rig.parts[k], Part::Hidden))
                .count(),
            samples: self.joined.rest.len(),
            triangles: self.joined.triangles.len(),
            real_handles: project.handles.len(),
            setup_ms: self.setup_ms,
            pose_ms_median: median(times.clone()),
            pose_ms_p90: quantile(times.clone(), 0.9),
            poses: times.len(),
        })
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }

    fn clone_box(&self) -> Box<dyn Deformer> {
        Box::new(self.clone())
    }
}

/// `c2warp bench` of a picture drawn as parts.
#[derive(serde::Serialize)]
struct PartsReport {
    method: &'static str,
    /// The parts drawn (visible layers).
    parts: usize,
    /// Vertices of the parts' meshes together.
    samples: usize,
    triangles: usize,
    real_handles: usize,
    /// Setting every part up (meshing, the methods' setups, the followers tied, the
    /// texture packed), ms.
    setup_ms: f64,
    /// One pose of every part (and every follower moved), ms.
    pose_ms_median: f64,
    pose_ms_p90: f64,
    poses: usize,
}

/// `layer`'s pixels written into `texture` at `(x, y)`, in the texture's depth, its
/// opacity taken into their alpha (as flattening takes it).
fn put(texture: &mut Picture, layer: &layers::Layer, x: u32, y: u32) {
    let opacity = layer.opacity;
    match (texture, &layer.pixels) {
        (Picture::Rgba8(t), Picture::Rgba8(p)) => {
            for (px, py, pixel) in p.enumerate_pixels() {
                let mut c = pixel.0;
                if opacity < 1.0 {
                    c[3] = (f32::from(c[3]) * opacity).round() as u8;
                }
                t.put_pixel(x + px, y + py, image::Rgba(c));
            }
        }
        (Picture::Rgba16(t), pixels) => {
            let (w, h) = pixels.dimensions();
            for py in 0..h {
                for px in 0..w {
                    let mut c = match pixels {
                        Picture::Rgba8(p) => p.get_pixel(px, py).0.map(|v| u16::from(v) * 257),
                        Picture::Rgba16(p) => p.get_pixel(px, py).0,
                    };
                    if opacity < 1.0 {
                        c[3] = (f32::from(c[3]) * opacity).round() as u16;
                    }
                    t.put_pixel(x + px, y + py, image::Rgba(c));
                }
            }
        }
        (Picture::Rgba8(_), Picture::Rgba16(_)) => {
            unreachable!("a texture with a 16-bit layer has 16 bits")
        }
    }
}

/// Draws `frames` of `project`'s animation of `artwork` as parts and writes them to
/// `output` as `format` (atomically, as [`crate::animate::Animator::write`] does): the
/// parts set up once (for the first frame's pose), each frame posed
/// ([`PartRig::pose`]) and composited ([`composite`]) as `render --parts` draws that
/// pose. `progress(done, total)` hears of each frame written.
///
/// # Errors
/// What setting the parts up or posing them refuses; what the writer refuses.
pub fn animate_parts(
    artwork: &layers::Artwork,
    project: &Project,
    frames: &crate::animate::Frames,
    output: &std::path::Path,
    format: render::AnimationFormat,
    progress: &dyn Fn(usize, usize),
    listener: &dyn Listener,
) -> Result<()> {
    let first = animation::posed_at(project, frames.times.first().copied().unwrap_or(0.0));
    let mut rig = PartRig::new(artwork, &first, None, listener)?;
    let composer = Composer::new(artwork, &rig.set())?;
    let total = frames.times.len();
    let mut writer = render::AnimationWriter::create(
        output,
        format,
        artwork.width,
        artwork.height,
        total,
        frames.fps,
    )?;
    progress(0, total);
    for (i, &time) in frames.times.iter().enumerate() {
        let posed = animation::posed_at(project, time);
        rig.pose(&posed)
            .with_context(|| format!("the pose at {time} s"))?;
        let (picture, _) = composer.draw(&rig.meshes(), &posed)?;
        writer.push(&picture)?;
        progress(i + 1, total);
    }
    writer.finish()?;
    Ok(())
}

/// The artwork's canvas as a frame.
fn canvas_of(artwork: &layers::Artwork) -> Frame {
    Frame {
        origin: [0, 0],
        width: artwork.width,
        height: artwork.height,
    }
}

/// `layer` on the canvas, at its offset.
fn on(layer: &layers::Layer, canvas: Frame) -> Result<Picture> {
    placed(
        &layer.pixels,
        canvas,
        [i64::from(layer.x), i64::from(layer.y)],
    )
}

/// `drawn` (a part on the whole canvas) cut to the pixels its warped mesh `deformed`
/// can touch, with their offset on the canvas: flattening and writing the parts then
/// handles each part's own rectangle, not the canvas.
fn cropped(drawn: Picture, deformed: &[DVec2]) -> (i32, i32, Picture) {
    let (w, h) = drawn.dimensions();
    let lo = deformed.iter().copied().fold(DVec2::INFINITY, DVec2::min);
    let hi = deformed
        .iter()
        .copied()
        .fold(DVec2::NEG_INFINITY, DVec2::max);
    // A pixel is touched where its square meets a triangle: one pixel of margin.
    let x0 = (lo.x.floor() - 1.0).clamp(0.0, f64::from(w)) as u32;
    let y0 = (lo.y.floor() - 1.0).clamp(0.0, f64::from(h)) as u32;
    let x1 = (hi.x.ceil() + 1.0).clamp(f64::from(x0), f64::from(w)) as u32;
    let y1 = (hi.y.ceil() + 1.0).clamp(f64::from(y0), f64::from(h)) as u32;
    if (x0, y0, x1, y1) == (0, 0, w, h) {
        return (0, 0, drawn);
    }
    let (cw, ch) = (x1 - x0, y1 - y0);
    let pixels = match &drawn {
        Picture::Rgba8(im) => {
            Picture::Rgba8(image::imageops::crop_imm(im, x0, y0, cw, ch).to_image())
        }
        Picture::Rgba16(im) => {
            Picture::Rgba16(image::imageops::crop_imm(im, x0, y0, cw, ch).to_image())
        }
    };
    (x0 as i32, y0 as i32, pixels)
}

/// `picture` (on the canvas) drawn through `mesh` onto a transparent canvas.
fn draw(picture: &Picture, mesh: &PartMesh) -> Result<Picture> {
    if mesh.deformed.iter().any(|p| !p.is_finite()) {
        bail!("the deformation produced non-finite positions");
    }
    let rest: Vec<Vec2> = mesh.rest.iter().map(|p| p.as_vec2()).collect();
    let moved: Vec<Vec2> = mesh.deformed.iter().map(|p| p.as_vec2()).collect();
    let (width, height) = picture.dimensions();
    let mut out = blank(
        picture.bits_per_channel(),
        Frame {
            origin: [0, 0],
            width,
            height,
        },
    )?;
    render::warp_picture_over(
        picture,
        &render::WarpMesh {
            rest: &rest,
            deformed: &moved,
            triangles: &mesh.triangles,
        },
        &mut out,
    )?;
    Ok(out)
}

/// `layer` meshed on its own (in its own rectangle of `canvas`), each vertex tied to
/// where it lies on `leader`'s rest mesh (still, without a leader).
fn follow(
    layer: &layers::Layer,
    canvas: Frame,
    leader: Option<&Bound>,
    project: &Project,
    density: usize,
) -> Result<(PartMesh, Vec<Tie>)> {
    let lead = leader.map(|b| (b.rest(), b.warper.deformer.triangles().to_vec()));
    let lead = lead.as_ref().map(|(rest, triangles)| (rest, triangles));
    tie(layer, canvas, lead, false, project, density)
}

/// `layer` meshed on its own (in its own rectangle of `canvas`), each vertex tied to
/// where it lies on the mesh `leader` (rest positions and triangles; outside it, to
/// its nearest vertex, or left still where `outside_still`); still without a leader.
fn tie(
    layer: &layers::Layer,
    canvas: Frame,
    leader: Option<(&Vec<DVec2>, &Vec<[u32; 3]>)>,
    outside_still: bool,
    project: &Project,
    density: usize,
) -> Result<(PartMesh, Vec<Tie>)> {
    // Its own mesh, as a bound part's is meshed (no handle crowds it), in the mesh's
    // order: nothing of its own moves it.
    let (part, origin) = own_rectangle(layer, canvas, &[])?;
    let cuts = shifted(&part_project(project, usize::MAX, &[]), -origin).cuts;
    let options = mesh::MeshOptions {
        target_vertices: density,
        ..mesh::MeshOptions::default()
    };
    let (own, _) = crate::mesh_part(&part.to_rgba8(), &options, &cuts)?;
    let rest: Vec<DVec2> = own.vertices.iter().map(|&p| p + origin).collect();
    let ties = match leader {
        None => vec![Tie::Still; rest.len()],
        Some((rest_of_leader, triangles)) => {
            let lead = Domain::new(rest_of_leader.clone(), triangles.clone(), Metric::Euclidean)
                .map_err(|e| anyhow::anyhow!("the part beneath: {e}"))?;
            rest.iter()
                .map(|&p| match lead.locate(p) {
                    Some((t, b)) => Tie::In(lead.triangles()[t], [b[0], b[1], b[2]]),
                    None if outside_still => Tie::Still,
                    None => lead.nearest_vertex(p).map_or(Tie::Still, Tie::Near),
                })
                .collect()
        }
    };
    Ok((
        PartMesh {
            deformed: rest.clone(),
            rest,
            triangles: own.triangles,
        },
        ties,
    ))
}

/// The number of canvas pixels where both layers have a visible pixel.
fn overlap(a: &layers::Layer, b: &layers::Layer) -> u64 {
    let rect = |l: &layers::Layer| {
        let (w, h) = l.dimensions();
        (
            i64::from(l.x),
            i64::from(l.y),
            i64::from(l.x) + i64::from(w),
            i64::from(l.y) + i64::from(h),
        )
    };
    let ((ax0, ay0, ax1, ay1), (bx0, by0, bx1, by1)) = (rect(a), rect(b));
    let mut n = 0;
    for y in ay0.max(by0)..ay1.min(by1) {
        for x in ax0.max(bx0)..ax1.min(bx1) {
            let seen = |l: &layers::Layer| {
                alpha(
                    &l.pixels,
                    (x - i64::from(l.x)) as u32,
                    (y - i64::from(l.y)) as u32,
                ) > 0
            };
            n += u64::from(seen(a) && seen(b));
        }
    }
    n
}

/// For each layer of `artwork`, the handles of `project` that bind it (none for a
/// layer hidden there): those its `"parts"` binds to it, and the others with a visible
/// pixel of it under them (under a bar's ends and middle).
///
/// # Errors
/// A handle that binds no layer shown, or parts that name other layers than
/// `artwork` has.
pub fn bindings(artwork: &layers::Artwork, project: &Project) -> Result<Vec<Vec<usize>>> {
    let spec = project.parts.clone().unwrap_or_default();
    spec.check_layers(artwork.layers.len())?;
    let bindings: Vec<Vec<usize>> = (artwork.layers.iter().enumerate())
        .map(|(k, layer)| {
            if !spec.shows(k, layer.visible) {
                return Vec::new();
            }
            (0..project.handles.len())
                .filter(|&h| match spec.binding(h) {
                    Some(parts) => parts.contains(&k),
                    None => probes(&project.handles[h])
                        .iter()
                        .all(|p| covers(layer, *p)),
                })
                .collect()
        })
        .collect();
    if let Some(h) = (0..project.handles.len()).find(|h| !bindings.iter().any(|b| b.contains(h))) {
        bail!(
            "handle {} lies on no visible layer: place it on a part",
            h + 1
        );
    }
    Ok(bindings)
}

impl PartRig {
    /// Every shown layer of `artwork` meshed on its own, each vertex tied to where it
    /// lies on the inside of `project`'s cage (solved once, on the canvas): the cage
    /// (LBC) deforms every part inside it; what lies outside the rest cage stays, as
    /// it does for one picture. A part that `previous` tied the same way is kept.
    fn caged(
        artwork: &layers::Artwork,
        project: &Project,
        density: Option<usize>,
        listener: &dyn Listener,
        previous: Option<&Self>,
        solved: Option<crate::cage::CageDeformer>,
    ) -> Result<Self> {
        let canvas = canvas_of(artwork);
        let spec = project.parts.clone().unwrap_or_default();
        spec.check_layers(artwork.layers.len())?;
        let order = spec.order_of(artwork.layers.len());
        let old_cage = previous.and_then(|old| old.cage.as_ref());
        // The cage: given solved, or kept when it is the same, else solved on the
        // canvas.
        let (kept_cage, same_cage) = match solved {
            Some(mut cage) => {
                if cage.follow(project)? == Follow::NeedsSetup {
                    bail!("the cage given is not the rig file's");
                }
                let same = old_cage.is_some_and(|old| Arc::ptr_eq(old.solution(), cage.solution()));
                (Some(cage), same)
            }
            None => {
                let kept = old_cage
                    .map(|cage| cage.as_ref().clone())
                    .and_then(|mut cage| {
                        (cage.follow(project).ok()? == Follow::Followed).then_some(cage)
                    });
                let same = kept.is_some();
                (kept, same)
            }
        };
        let cage = match kept_cage {
            Some(cage) => cage,
            None => {
                let blank = image::RgbaImage::new(artwork.width, artwork.height);
                let source = crate::Source::Picture {
                    image: &blank,
                    density,
                };
                crate::cage::CageDeformer::set_up(source, project, listener)?
            }
        };
        let areas: Vec<u64> = (artwork.layers.iter().enumerate())
            .map(|(k, l)| {
                if spec.shows(k, l.visible) {
                    visible_pixels(&l.pixels)
                } else {
                    0
                }
            })
            .collect();
        let total_area = areas.iter().sum::<u64>().max(1);
        let total = density.or(project.density).unwrap_or(DEFAULT_DENSITY);
        let inside = (
            cage.solution().domain.positions().to_vec(),
            cage.solution().domain.triangles().to_vec(),
        );
        let mut parts = Vec::with_capacity(artwork.layers.len());
        for (k, layer) in artwork.layers.iter().enumerate() {
            if !spec.shows(k, layer.visible) {
                parts.push(Part::Hidden);
                continue;
            }
            let density = ((total as u128 * u128::from(areas[k]) / u128::from(total_area))
                as usize)
                .max(MIN_PART_DENSITY);
            let same = previous
                .filter(|_| same_cage)
                .and_then(|old| match old.parts.get(k)? {
                    Part::Follows {
                        mesh,
                        ties,
                        density: d,
                        ..
                    } if *d == density => Some((mesh.clone(), ties.clone())),
                    _ => None,
                });
            let (mesh, ties) = match same {
                Some(tied) => tied,
                None => tie(
                    layer,
                    canvas,
                    Some((&inside.0, &inside.1)),
                    true,
                    project,
                    density,
                )
                .with_context(|| format!("part \"{}\"", layer.name))?,
            };
            parts.push(Part::Follows {
                mesh,
                leader: None,
                ties,
                density,
            });
        }
        let mut rig = Self {
            order,
            cage: Some(Box::new(cage)),
            bindings: vec![Vec::new(); parts.len()],
            followed: vec![None; parts.len()],
            parts,
            live: false,
        };
        rig.move_followers();
        Ok(rig)
    }
}

/// `project` for layer `layer`'s part with the handles `bound` alone (their overlay
/// and their holds on this part kept, renumbered, as the part's own), the rigidity
/// painted on it, no virtual handle, no animation, on the canvas as it is.
fn part_project(project: &Project, layer: usize, bound: &[usize]) -> Project {
    let index = |h: usize| bound.iter().position(|&b| b == h);
    let mut part = project.clone();
    part.handles = bound.iter().map(|&h| project.handles[h].clone()).collect();
    part.overlaid = project.overlaid.iter().filter_map(|&h| index(h)).collect();
    part.holds = project
        .holds
        .iter()
        .filter(|hold| hold.is_on(Some(layer)))
        .filter_map(|hold| {
            index(hold.handle).map(|handle| Hold {
                handle,
                part: None,
                ..hold.clone()
            })
        })
        .collect();
    // The rigidity painted on this part, or on every part.
    part.rigidity
        .retain(|stroke| stroke.part.is_none_or(|k| k == layer));
    // Virtual handles were placed on the whole picture, some off this part: each part
    // places its own (the C² paper's Algorithm 1 on its shape).
    part.virtual_handles.clear();
    part.virtual_placed_for.clear();
    part.virtual_copy.clear();
    part.animation = None;
    part.canvas = Canvas::Keep;
    // The saved overlap orders name places on the parts drawn together
    // ([`composite`]), not on one part's own mesh.
    part.overlaps.clear();
    // A part is one picture: the parts' order, visibility and bindings are the whole's,
    // and the shape it carries is drawn over its method's warp (`Bound::carried`).
    part.parts = None;
    part.carried.clear();
    // A cage kept while handles move the parts is the whole canvas's (a cage moves
    // the parts through `PartRig::caged`, not through a part's own rig file).
    part.cage = None;
    part
}

/// `layer`'s own rectangle of `canvas` — its pixels, and `points` (the handles that
/// bind it), with a margin of transparent pixels — and the rectangle's top-left
/// corner on the canvas: the picture a part is meshed and weighted on.
///
/// # Errors
/// Not enough memory for the picture.
fn own_rectangle(
    layer: &layers::Layer,
    canvas: Frame,
    points: &[DVec2],
) -> Result<(Picture, DVec2)> {
    /// Transparent pixels around the layer, so that it is meshed as the cut-out it is
    /// on the canvas.
    const MARGIN: i64 = 2;
    let (w, h) = layer.dimensions();
    let (mut x0, mut y0) = (i64::from(layer.x), i64::from(layer.y));
    let (mut x1, mut y1) = (x0 + i64::from(w), y0 + i64::from(h));
    for p in points.iter().filter(|p| p.is_finite()) {
        x0 = x0.min(p.x.floor() as i64);
        y0 = y0.min(p.y.floor() as i64);
        x1 = x1.max(p.x.ceil() as i64 + 1);
        y1 = y1.max(p.y.ceil() as i64 + 1);
    }
    let x0 = (x0 - MARGIN).max(0);
    let y0 = (y0 - MARGIN).max(0);
    let x1 = (x1 + MARGIN).min(i64::from(canvas.width)).max(x0 + 1);
    let y1 = (y1 + MARGIN).min(i64::from(canvas.height)).max(y0 + 1);
    let frame = Frame {
        origin: [0, 0],
        width: (x1 - x0) as u32,
        height: (y1 - y0) as u32,
    };
    let picture = placed(
        &layer.pixels,
        frame,
        [i64::from(layer.x) - x0, i64::from(layer.y) - y0],
    )?;
    Ok((picture, DVec2::new(x0 as f64, y0 as f64)))
}

/// `project` with everything placed on the picture moved by `by`: the handles, what
/// they hold, the cuts and the painted rigidity (a part set up on its own rectangle).
fn shifted(project: &Project, by: DVec2) -> Project {
    let mv = |p: &mut [f64; 2]| *p = (DVec2::from(*p) + by).to_array();
    let mut moved = project.clone();
    for handle in &mut moved.handles {
        match handle {
            HandleSpec::Point { rest, .. } => mv(rest),
            HandleSpec::Bar { rest, pose, .. } => {
                rest.iter_mut().for_each(mv);
                pose.iter_mut().flatten().for_each(mv);
            }
        }
    }
    for hold in &mut moved.holds {
        (hold
            .rest
            .iter_mut()
            .chain(&mut hold.at)
            .chain(&mut hold.step_one))
        .for_each(mv);
    }
    for cut in &mut moved.cuts {
        cut.stroke.iter_mut().for_each(mv);
    }
    for stroke in &mut moved.rigidity {
        stroke.stroke.iter_mut().for_each(mv);
    }
    moved.virtual_handles.iter_mut().for_each(mv);
    moved
}

/// The rest points a layer must cover for a handle to bind it: a point's place; a
/// bar's ends and middle.
fn probes(handle: &HandleSpec) -> Vec<DVec2> {
    match handle {
        HandleSpec::Point { rest, .. } => vec![DVec2::from(*rest)],
        HandleSpec::Bar { rest, .. } => {
            let (a, b) = (DVec2::from(rest[0]), DVec2::from(rest[1]));
            vec![a, (a + b) / 2.0, b]
        }
    }
}

/// The shown layers under `handle` at rest (each with a visible pixel under every
/// point it is probed at: a point's place, a bar's ends and middle), bottom first by
/// index: the parts it binds unless the rig file binds it to chosen ones.
pub fn layers_under(
    artwork: &layers::Artwork,
    spec: &project::PartsSpec,
    handle: &HandleSpec,
) -> Vec<usize> {
    let probes = probes(handle);
    (artwork.layers.iter().enumerate())
        .filter(|(k, layer)| {
            spec.shows(*k, layer.visible) && probes.iter().all(|p| covers(layer, *p))
        })
        .map(|(k, _)| k)
        .collect()
}

/// Whether `layer` has a visible pixel (alpha > 0) at canvas point `p`.
fn covers(layer: &layers::Layer, p: DVec2) -> bool {
    let (x, y) = (
        p.x.floor() - f64::from(layer.x),
        p.y.floor() - f64::from(layer.y),
    );
    let (w, h) = layer.dimensions();
    if !(x >= 0.0 && y >= 0.0 && x < f64::from(w) && y < f64::from(h)) {
        return false;
    }
    alpha(&layer.pixels, x as u32, y as u32) > 0
}

fn alpha(picture: &Picture, x: u32, y: u32) -> u16 {
    match picture {
        Picture::Rgba8(im) => u16::from(im.get_pixel(x, y)[3]),
        Picture::Rgba16(im) => im.get_pixel(x, y)[3],
    }
}

/// The number of pixels with alpha > 0.
fn visible_pixels(picture: &Picture) -> u64 {
    let (w, h) = picture.dimensions();
    let mut n = 0;
    for y in 0..h {
        for x in 0..w {
            n += u64::from(alpha(picture, x, y) > 0);
        }
    }
    n
}
