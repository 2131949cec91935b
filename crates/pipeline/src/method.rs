//! The seam where the editor and the command line choose a warping method.
//!
//! Every method answers one question — where does every point of the picture go? —
//! through [`Deformer`], whatever the artist moves: handles (C², ARAP) or a cage
//! (LBC; see [`project::Method::controls`]). A method is set up once on a picture (or
//! a given mesh) for a rig file ([`setup`]: meshing, weights, factorisations, a cage's
//! solve), then follows the rig file's poses cheaply ([`Deformer::follow`]). What it
//! gives is drawn the same way for every method ([`crate::Warper`]): a mesh at rest
//! (the texture coordinates), where its vertices go ([`Output`]: sparse skinning rows
//! and one transform per control, or a position per vertex), and what shows behind it
//! ([`Backdrop`]).
//!
//! The methods, each in its own file:
//! - [`Method::C2`] (`c2.rs`): the C² weights of `weights-core`, a [`Rig`] as it is.
//! - [`Method::Arap`] (`arap.rs`): as-rigid-as-possible manipulation, [`ArapRig`].
//! - [`Method::Mls`] (`mls.rs`): moving least squares, [`MlsRig`].
//! - [`Method::Lbc`] (`cage.rs`): local barycentric coordinates of a cage,
//!   [`CageDeformer`].
//!
//! To add a method: a variant of [`Method`] (in the `project` crate, with its rig-file
//! name and its controls), a file here with a type implementing [`Deformer`], and its
//! line in [`beside_rig`] (a handle method) or [`setup`] (a cage method).

use anyhow::{Result, bail};
use image::RgbaImage;
use project::Project;
use weights_core::Rig;

use crate::Warper;
use crate::arap::ArapRig;
use crate::cage::CageDeformer;
pub use crate::deformer::{
    Backdrop, Deformer, Follow, Listener, Output, SkinTable, Skinning, SolveProgress, Source,
    WeightsListing,
};
use crate::mls::MlsRig;
pub use project::{Controls, Method};

/// Sets up `project`'s method on `source`, with its triangles in drawing order: the
/// whole way from a picture (or a mesh) and a rig file to something to draw.
///
/// # Errors
/// What meshing, the rig build or the method refuses, each as one sentence.
pub fn setup(source: Source<'_>, project: &Project, listener: &dyn Listener) -> Result<Warper> {
    match project.method.controls() {
        // LBC is the one cage method.
        Controls::Cage => {
            let deformer = CageDeformer::set_up(source, project, listener)?;
            Ok(Warper::in_mesh_order(Box::new(deformer), project))
        }
        Controls::Handles => {
            let weighting = |p| listener.weighting(p);
            let rig = match source {
                Source::Picture { image, density } => {
                    crate::prepare_with_progress(image, project, density, &weighting)?.rig
                }
                Source::Mesh(mesh) => crate::rig_on_mesh(mesh, project, &weighting)?,
            };
            Warper::on_rig(rig, project, source.picture())
        }
    }
}

/// Sets up `project`'s handle method on `rig` (the picture's mesh with the rig file's
/// handles, as [`crate::prepare`] builds it): C² is the rig itself; ARAP meshes
/// `picture` its own way and the rig's mesh follows (without a picture it solves on
/// the rig's mesh: a mesh given as such).
///
/// # Errors
/// As [`beside_rig`].
pub fn on_handles(
    project: &Project,
    rig: Rig,
    picture: Option<&RgbaImage>,
) -> Result<Box<dyn Deformer>> {
    Ok(match beside_rig(project, &rig, picture)? {
        Some(deformer) => deformer,
        None => Box::new(rig),
    })
}

/// **The one place a handle method is chosen.** `project`'s handle method set up beside
/// `rig` (which the editor keeps for its mesh, its handles and its overlays): `None`
/// where the rig is the method's deformer itself (C²).
///
/// # Errors
/// What the method refuses, and a cage method (set up by [`setup`], or from its solved
/// coordinates: [`CageDeformer::new`]).
pub fn beside_rig(
    project: &Project,
    rig: &Rig,
    picture: Option<&RgbaImage>,
) -> Result<Option<Box<dyn Deformer>>> {
    Ok(match project.method {
        Method::C2 => None,
        Method::Arap => Some(Box::new(ArapRig::on_rig(project, rig, picture)?)),
        Method::Mls => Some(Box::new(MlsRig::on_rig(project, rig)?)),
        Method::Lbc => bail!("LBC warps by a cage, not by handles"),
    })
}
