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
//! line in [`on_mesh`] (a handle method) or [`setup`] (a cage method).

use anyhow::{Result, bail};
use image::RgbaImage;
use project::Project;
use weights_core::Domain;

use crate::Warper;
use crate::arap::ArapRig;
use crate::cage::CageDeformer;
use crate::carried::Carrying;
pub use crate::deformer::{
    Backdrop, Deformer, Follow, Listener, Output, SkinTable, Skinning, SolveProgress, Source,
    Still, WeightsListing,
};
use crate::mls::MlsRig;
pub use project::{Controls, Method};

/// Sets up `project`'s method on `source`, with its triangles in drawing order: the
/// whole way from a picture (or a mesh) and a rig file to something to draw.
///
/// # Errors
/// What meshing, the rig build or the method refuses, each as one sentence.
pub fn setup(source: Source<'_>, project: &Project, listener: &dyn Listener) -> Result<Warper> {
    match (project.method.controls(), source) {
        // LBC is the one cage method.
        (Controls::Cage, source) => {
            let deformer = CageDeformer::set_up(source, project, listener)?;
            Ok(Warper::in_mesh_order(Box::new(deformer), project))
        }
        (Controls::Handles, Source::Picture { image, density }) => {
            let domain = crate::mesh_for(image, project, density, crate::mesh_picture)?;
            Warper::on_domain(domain, project, Some(image), listener)
        }
        // A given mesh: C² keeps the virtual handles inserted into it.
        (Controls::Handles, Source::Mesh(mesh)) if project.method == Method::C2 => {
            let rig = crate::rig_on_mesh(mesh, project, &|p| listener.weighting(p))?;
            Ok(Warper::on_mesh_rig(rig, project))
        }
        (Controls::Handles, Source::Mesh(mesh)) => {
            let (domain, _) = crate::mesh_with_handles(mesh, project)?;
            Warper::on_domain(domain, project, None, listener)
        }
    }
}

/// **The one place a handle method is chosen.** `project`'s handle method set up on
/// `domain`, the picture's mesh with the rig file's handles (`picture`: the picture,
/// which ARAP meshes its own way, the picture's mesh following; `None` for a mesh given
/// as such, which ARAP solves on): `None` for C², whose deformer is the rig weighing
/// that mesh ([`crate::rig_on_domain`]; the editor keeps it for every method).
///
/// # Errors
/// What the method refuses, and a cage method (set up by [`setup`], or from its solved
/// coordinates: [`CageDeformer::new`]).
pub fn on_mesh(
    project: &Project,
    domain: &Domain,
    picture: Option<&RgbaImage>,
) -> Result<Option<Box<dyn Deformer>>> {
    let method: Box<dyn Deformer> = match project.method {
        Method::C2 => return Ok(None),
        Method::Arap => Box::new(ArapRig::on_mesh(project, domain, picture)?),
        Method::Mls => Box::new(MlsRig::on_mesh(project, domain)?),
        Method::Lbc => bail!("LBC warps by a cage, not by handles"),
    };
    // Drawn with the shape the picture carries, if it carries one.
    Ok(Some(Box::new(Carrying::new(method, project)?)))
}
