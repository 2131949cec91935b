//! The seam where the editor and the command line choose a warping method.
//!
//! Every method answers one question — given this rest mesh and these handles, where
//! does every vertex go? — through [`Deformer`]. Each has an expensive step when the
//! set of handles (or the method's parameters) changes: building weights, factorising
//! systems; and a cheap step when only the handles' poses change, as in a drag. Both
//! happen in [`Deformer::set_handles`], which tells them apart by comparing the
//! handles' rest positions.
//!
//! The methods:
//! - [`Method::C2`]: the C² weights of `weights-core` ([`Rig`]); its result is best
//!   drawn skinned (sparse weights and one transform per node, blended per vertex).
//! - [`Method::Arap`]: as-rigid-as-possible manipulation of the `arap` crate
//!   ([`ArapRig`], in [`crate::arap`]); its result is a position per vertex.
//!
//! To add a method: a variant of [`Method`] (in the `project` crate, with its rig-file
//! name), a type implementing [`Deformer`], and a case in [`deformer`].

use anyhow::Result;
use glam::DVec2;
pub use project::Method;
use project::Project;
use weights_core::{Domain, Handle, Rig};

use crate::arap::{ArapOptions, ArapRig};

/// How a method's result is best drawn.
pub enum Output<'a> {
    /// Sparse weights and node transforms, blended per vertex (on the GPU, in the
    /// vertex shader): only the transforms change during a drag.
    Skinned(&'a Rig),
    /// A deformed position per mesh vertex (8 bytes a vertex to upload in f32).
    Positions(&'a [DVec2]),
}

/// A warping method set up on a rest mesh and a set of handles.
pub trait Deformer: Send {
    /// Which method this is.
    fn method(&self) -> Method;

    /// The rest mesh.
    fn domain(&self) -> &Domain;

    /// The handles, in their current poses.
    fn handles(&self) -> &[Handle];

    /// Takes new handles: the expensive step when handles were added, removed or moved
    /// at rest, else the cheap one (a new pose). On error nothing changes.
    ///
    /// # Errors
    /// Handles the method refuses (off the shape, coincident, non-finite).
    fn set_handles(&mut self, handles: &[Handle]) -> Result<()>;

    /// Where every mesh vertex goes in the current pose.
    fn deformed(&self) -> Vec<DVec2>;

    /// The result, in the form that draws best.
    fn output(&self) -> Output<'_>;
}

impl Deformer for Rig {
    fn method(&self) -> Method {
        Method::C2
    }

    fn domain(&self) -> &Domain {
        Rig::domain(self)
    }

    fn handles(&self) -> &[Handle] {
        Rig::handles(self)
    }

    fn set_handles(&mut self, handles: &[Handle]) -> Result<()> {
        Ok(Rig::set_handles(self, handles.to_vec())?)
    }

    fn deformed(&self) -> Vec<DVec2> {
        self.deform()
    }

    fn output(&self) -> Output<'_> {
        Output::Skinned(self)
    }
}

/// Sets up the rig file's method (`project.method`) on the mesh of `rig` (the C² rig
/// built by [`crate::prepare`]) with its handles: for ARAP, on its own mesh of
/// `picture` (see [`crate::arap`]), or on the rig's mesh itself without a picture (a
/// mesh given as such, `c2warp deform --mesh`).
///
/// # Errors
/// What the method refuses.
pub fn deformer(
    project: &Project,
    rig: Rig,
    picture: Option<&image::RgbaImage>,
) -> Result<Box<dyn Deformer>> {
    Ok(match project.method {
        Method::C2 => Box::new(rig),
        Method::Arap => {
            let (domain, handles) = (rig.domain().clone(), rig.handles());
            let strokes = &project.rigidity;
            Box::new(match picture {
                Some(picture) => {
                    let options = ArapOptions::for_picture(project, picture);
                    ArapRig::with_own_mesh(picture, domain, handles, strokes, options)?
                }
                None => ArapRig::new(domain, handles, strokes, ArapOptions::of(project, None))?,
            })
        }
        Method::Lbc => anyhow::bail!("LBC warps by a cage, not by handles (see pipeline::cage)"),
    })
}
