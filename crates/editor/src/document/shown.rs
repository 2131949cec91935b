//! What the view draws of the document for the controls in hand: the one place that
//! picks the mesh the GPU frame, the overlap outlines and the offscreen view draw.

use pipeline::cage::CageDeformer;
use pipeline::{Controls, Deformer, PartsDeformer};

use super::Document;

/// The mesh the view draws.
#[derive(Clone, Copy)]
pub enum Shown<'a> {
    /// The picture's mesh moved by the handle method: the C² rig's skin, with the
    /// positions a method solves for laid over it.
    Picture(&'a dyn Deformer),
    /// The parts' joined mesh over their packed texture, moved by the handles or by
    /// the cage that moves them.
    Parts(&'a PartsDeformer),
    /// The cage's view: the picture at rest, the solved cage's inside warped over it
    /// (`None`: no solved cage warps it — a new cage being drawn, or one not solved).
    Cage(Option<&'a CageDeformer>),
}

impl Document {
    /// The controls that move the picture: the method's ([`project::Method::controls`]).
    pub fn controls(&self) -> Controls {
        self.project.method.controls()
    }

    /// What the view draws with `in_hand` the controls the tools act on
    /// ([`crate::EditorApp`]'s), `warping` when a solved cage may warp it (no new
    /// cage being drawn). Parts are drawn under handles, and under a cage that moves
    /// them; a cage drawn over a handle method shows the picture at rest.
    pub fn shown(&self, in_hand: Controls, warping: bool) -> Shown<'_> {
        super::rigging::rigging(in_hand).shown(self, warping)
    }
}

impl<'a> Shown<'a> {
    /// The method whose mesh is drawn (`None`: the picture at rest alone).
    pub fn deformer(&self) -> Option<&'a dyn Deformer> {
        match *self {
            Shown::Picture(deformer) => Some(deformer),
            Shown::Parts(parts) => Some(parts),
            Shown::Cage(cage) => cage.map(|c| c as &dyn Deformer),
        }
    }

    /// Where the mesh drawn lies in the current pose: the cage's mesh as the cage
    /// moves it, else the method's positions as [`Document::deformed`] last brought
    /// them up to date (`None` if it has not since the pose changed, or for the
    /// picture at rest alone).
    pub fn positions(&self, doc: &'a Document) -> Option<&'a [glam::DVec2]> {
        match *self {
            Shown::Cage(cage) => cage.map(CageDeformer::positions),
            Shown::Picture(_) | Shown::Parts(_) => doc.current_deformed(),
        }
    }

    /// Whether the cage's view is drawn: the picture at rest under the cage's
    /// mesh.
    pub fn over_backdrop(&self) -> bool {
        matches!(self, Shown::Cage(_))
    }
}
