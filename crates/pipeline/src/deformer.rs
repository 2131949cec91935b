//! What every warping method gives, whatever the artist moves (handles or a cage):
//! [`Deformer`] — its mesh at rest (the texture coordinates), where its vertices go
//! ([`Output`]: sparse skinning rows and one transform per control, or a position per
//! vertex), what shows behind it ([`Backdrop`]) — and what a setup is given
//! ([`Source`]) and tells ([`Listener`]). The methods (`c2.rs`, `arap.rs`, `mls.rs`,
//! `cage.rs`) implement it; `method.rs` chooses among them. This module knows none of
//! them.

use std::any::Any;

use anyhow::{Context, Result};
use glam::DVec2;
use image::RgbaImage;
pub use lbc::Progress as SolveProgress;
use project::Project;
pub use project::{Controls, Method};

/// How a method's result is drawn.
pub enum Output<'a> {
    /// Sparse weights and one transform per control, blended per vertex (on the GPU,
    /// in the vertex shader): only the transforms change during a drag.
    Skinned(&'a dyn Skinning),
    /// A deformed position per mesh vertex (8 bytes a vertex to upload in f32).
    Positions(&'a [DVec2]),
}

/// A method whose result is a linear blend of transforms: every vertex `x` goes to
/// `Σ wᵢ Aᵢ x` over the rows of [`Skinning::table`] and the transforms of
/// [`Skinning::transforms`].
pub trait Skinning {
    /// Every vertex's weights: row `v` is `nodes[rows[v]..rows[v + 1]]` with
    /// `weights` alongside, as [`render::SkinnedMesh`] takes them.
    fn table(&self) -> SkinTable;

    /// One affine map per node in the current pose, in image pixels.
    fn transforms(&self) -> Vec<render::Affine>;
}

/// Sparse skinning rows (see [`Skinning::table`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SkinTable {
    /// Row starts, one more than the vertices.
    pub rows: Vec<u32>,
    /// The node of each entry.
    pub nodes: Vec<u32>,
    /// The weight of each entry.
    pub weights: Vec<f32>,
}

/// What shows behind a method's warped mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backdrop {
    /// Nothing: the mesh covers every visible pixel of the picture, and what it leaves
    /// uncovered in the warp is transparent.
    Transparent,
    /// The picture where the mesh does not cover it at rest (a cage's outside), kept in
    /// place; the pixels the rest mesh covers are cleared
    /// ([`render::clear_covered`]) and the warped mesh is drawn over them.
    PictureOutsideMesh,
}

/// Whether a method followed a rig file ([`Deformer::follow`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Follow {
    /// It is up to date: posed, or set up again where handles came or went.
    Followed,
    /// The rig file asks for what only a new [`setup`](crate::method::setup) gives (new settings, another
    /// rest cage); nothing changed.
    NeedsSetup,
}

/// What `c2warp weights` lists beside a method's weights.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WeightsListing {
    /// Vertices the mesh file had (vertices after them were inserted for handles);
    /// for a picture, the mesh's vertex count.
    pub file_vertices: usize,
    /// Whether to list the vertices' positions (the mesh was made, not given).
    pub positions: bool,
}

/// A warping method set up on a rest mesh for a rig file's controls. (`Sync`, so that
/// layered parts can share a part's setup between the parts of one rig file and the
/// next while it is unchanged.)
pub trait Deformer: Send + Sync {
    /// Which method this is.
    fn method(&self) -> Method;

    /// The mesh it moves, at rest: vertex positions in image pixels (the texture
    /// coordinates of the drawing).
    fn rest(&self) -> &[DVec2];

    /// The mesh's triangles (indices into [`Deformer::rest`]), in the mesh's order.
    fn triangles(&self) -> &[[u32; 3]];

    /// Follows `project`, a rig file for the same picture and density as the one set
    /// up: a new pose of the same controls is cheap; handles added or removed set up
    /// what they need. On error nothing changes.
    ///
    /// # Errors
    /// Controls the method refuses (off the shape, coincident, non-finite).
    fn follow(&mut self, project: &Project) -> Result<Follow>;

    /// Whether the poses to follow come from a live drag: an iterative method may then
    /// start each from its previous answer and stop early. Leaving live mode solves
    /// the current pose in full, as [`Deformer::follow`] does outside it, so what
    /// shows after a drag is what a file of that pose renders.
    ///
    /// # Errors
    /// As [`Deformer::follow`].
    fn set_live(&mut self, live: bool) -> Result<()> {
        let _ = live;
        Ok(())
    }

    /// Where every vertex of [`Deformer::rest`] goes in the current pose.
    fn deformed(&self) -> Vec<DVec2>;

    /// The result, in the form that draws best.
    fn output(&self) -> Output<'_>;

    /// What shows behind the warped mesh.
    fn backdrop(&self) -> Backdrop {
        Backdrop::Transparent
    }

    /// What a user should hear about the setup (a solve that did not converge).
    fn notes(&self) -> Vec<String> {
        Vec::new()
    }

    /// Handle `index` of `project` has just been placed, in the pose shown (this
    /// deformer's, which has not followed `project` yet): what it must hold so that
    /// the picture stays where it is (none: nothing, as at rest). ARAP's answer pins
    /// the new handle's points where the current solve puts them (on each part the
    /// handle binds, drawn as parts).
    fn holds(&self, project: &Project, index: usize) -> Vec<project::Hold> {
        let _ = (project, index);
        Vec::new()
    }

    /// `c2warp weights`: the nodes and every vertex's non-zero weights, as JSON.
    ///
    /// # Errors
    /// A method without weights per control.
    fn weights(&self, listing: WeightsListing) -> Result<serde_json::Value>;

    /// `c2warp bench`: the method's steps timed (its setup as it was measured, then
    /// `poses` poses or insertions), as JSON.
    ///
    /// # Errors
    /// What the method refuses while being timed.
    fn bench(&mut self, project: &Project, poses: usize) -> Result<serde_json::Value>;

    /// The concrete type, for what only one method shows (the editor's overlays).
    fn as_any(&self) -> &dyn Any;

    /// A copy (a document copied to a worker thread takes its method along).
    fn clone_box(&self) -> Box<dyn Deformer>;
}

impl Clone for Box<dyn Deformer> {
    fn clone(&self) -> Self {
        self.clone_box()
    }
}

/// Where a method's mesh comes from.
#[derive(Clone, Copy)]
pub enum Source<'a> {
    /// A picture, meshed (at `density` vertices, else the rig file's, else the
    /// default); a cage method meshes the inside of its cage.
    Picture {
        /// The picture.
        image: &'a RgbaImage,
        /// Target vertex count, overriding the rig file's.
        density: Option<usize>,
    },
    /// A given mesh (`--mesh`): its vertices as they are; handles that miss its
    /// vertices are inserted after them ([`crate::rig_on_mesh`]); a cage method takes
    /// it as the cage's inside.
    Mesh(&'a mesh::Mesh),
}

impl<'a> Source<'a> {
    /// The picture, if the mesh is made from one.
    pub fn picture(&self) -> Option<&'a RgbaImage> {
        match *self {
            Source::Picture { image, .. } => Some(image),
            Source::Mesh(_) => None,
        }
    }
}

/// Hears how a setup is coming along. Called from the setup's threads: keep it short.
pub trait Listener: Sync {
    /// The rig build's progress (see [`weights_core::Progress`]).
    fn weighting(&self, _progress: weights_core::Progress) {}

    /// A cage solve's iteration; `false` cancels the solve.
    fn solving(&self, _progress: &SolveProgress) -> bool {
        true
    }
}

/// Hears nothing.
impl Listener for () {}

/// The median of `values` (NaN for none): for the benchmarks' reports.
pub(crate) fn median(values: Vec<f64>) -> f64 {
    quantile(values, 0.5)
}

/// The `q`-quantile (nearest rank) of `values`; NaN for none.
pub(crate) fn quantile(mut values: Vec<f64>, q: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    let rank = ((q * values.len() as f64).ceil() as usize).clamp(1, values.len());
    values[rank - 1]
}

/// A report as JSON.
pub(crate) fn json(report: &impl serde::Serialize) -> Result<serde_json::Value> {
    serde_json::to_value(report).context("cannot write the report as JSON")
}

/// A fixed sequence of numbers in [−0.5, 0.5) (xorshift), so that benchmark runs
/// compare.
pub(crate) struct Sequence(u64);

impl Sequence {
    /// The sequence every benchmark starts from.
    pub(crate) fn new() -> Self {
        Self(0x2545_F491_4F6C_DD1D)
    }

    /// The next raw 64-bit value.
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    /// The next number in [−0.5, 0.5).
    pub(crate) fn next(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }

    /// A random pose for benchmarks: every handle moved by its own random offset of up
    /// to `scale / 2` per axis (a point's translation, a bar's two ends alike).
    pub(crate) fn jiggle(
        &mut self,
        handles: &[weights_core::Handle],
        scale: f64,
    ) -> Vec<weights_core::Handle> {
        use weights_core::Handle;
        handles
            .iter()
            .map(|h| {
                let d = DVec2::new(self.next(), self.next()) * scale;
                match *h {
                    Handle::Point {
                        rest,
                        mut transform,
                    } => {
                        transform.translation += d;
                        Handle::Point { rest, transform }
                    }
                    Handle::Bar { rest, pose } => Handle::Bar {
                        rest,
                        pose: [pose[0] + d, pose[1] + d],
                    },
                }
            })
            .collect()
    }
}

/// A mesh that nothing moves: what a method shows while it has nothing to warp by (a
/// cage chosen and not solved yet), the picture at rest.
#[derive(Clone)]
pub struct Still {
    method: Method,
    rest: Vec<DVec2>,
    triangles: Vec<[u32; 3]>,
}

impl Still {
    /// `mesh` (its rest positions and triangles) at rest, standing for `method`.
    pub fn new(method: Method, rest: Vec<DVec2>, triangles: Vec<[u32; 3]>) -> Self {
        Self {
            method,
            rest,
            triangles,
        }
    }
}

impl Deformer for Still {
    fn method(&self) -> Method {
        self.method
    }

    fn rest(&self) -> &[DVec2] {
        &self.rest
    }

    fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    fn follow(&mut self, project: &Project) -> Result<Follow> {
        Ok(if project.method == self.method {
            Follow::Followed
        } else {
            Follow::NeedsSetup
        })
    }

    fn deformed(&self) -> Vec<DVec2> {
        self.rest.clone()
    }

    fn output(&self) -> Output<'_> {
        Output::Positions(&self.rest)
    }

    fn weights(&self, _listing: WeightsListing) -> Result<serde_json::Value> {
        anyhow::bail!("{} has nothing set up to weigh by yet", self.method.label())
    }

    fn bench(&mut self, _project: &Project, _poses: usize) -> Result<serde_json::Value> {
        anyhow::bail!("{} has nothing set up to time yet", self.method.label())
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn clone_box(&self) -> Box<dyn Deformer> {
        Box::new(self.clone())
    }
}
