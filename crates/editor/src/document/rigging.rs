//! What moves the picture, handles or a cage, as the document's work tells them apart:
//! [`rigging`] is the one place the document decides by the kind of controls, and
//! [`Rigging`] lists everything that differs between the two — setting the method's
//! state up, refusing a method that has nothing to move, checking the state, what the
//! view draws, how a new handle enters the keys and which triangles a posed mesh is
//! drawn with. Each is worked out in the document's own module for it (the cage's in
//! `cage.rs`); this table only says which way each kind goes. The editor's tools,
//! panels and buttons for each kind are chosen in one place of their own
//! ([`crate::controls`]).

use anyhow::{Result, bail};
use pipeline::{Controls, Deformer};
use project::{HandlePose, HandleSpec, Method, Pose, Project};

use super::{Document, Shown};

/// What differs between the kinds of controls, for the document (see the module
/// documentation). Its two implementations are stateless: the state is the
/// document's, which keeps the handles' mesh under a cage and the solved cages under
/// handles, so that switching back and forth costs nothing.
pub(super) trait Rigging {
    /// Why `method` cannot be chosen for `project` (`None`: it can).
    fn refusal(&self, method: Method, project: &Project) -> Option<String>;

    /// Whether opening a rig file drawn as parts sets the parts up with the picture's
    /// mesh (under handles they are the method's; under a cage they wait for the
    /// cage's solve).
    fn parts_set_up_on_opening(&self) -> bool;

    /// Brings the method's state in line with the rig file.
    ///
    /// # Errors
    /// What the method refuses of the rig file.
    fn sync(&self, doc: &mut Document) -> Result<()>;

    /// Whether no method state is right for the document as it is (the C² rig is its
    /// own deformer; a cage not solved yet has none).
    fn may_have_no_state(&self, doc: &Document) -> bool;

    /// Checks that `deformer`, set up on mesh version `mesh`, is the one the rig file
    /// asks for ([`Document::sanity_check`]).
    ///
    /// # Errors
    /// What is out of step, in words.
    fn check(&self, doc: &Document, mesh: u64, deformer: &dyn Deformer) -> Result<()>;

    /// What the view draws with these controls in hand ([`Document::shown`]).
    fn shown<'a>(&self, doc: &'a Document, warping: bool) -> Shown<'a>;

    /// `handle`'s pose in each of `poses`, a handle placed now (see
    /// [`Document::fit_into_keys`]).
    ///
    /// # Errors
    /// A pose the method refuses.
    fn fit_into(
        &self,
        doc: &mut Document,
        handle: &HandleSpec,
        poses: &[Pose],
    ) -> Result<Vec<HandlePose>>;

    /// The triangles the document's deformer is drawn with in its current pose, back
    /// to front ([`Document::posed_mesh`]).
    fn drawn_triangles(&self, doc: &Document) -> Vec<[u32; 3]>;
}

/// The document's way for `controls`: the one place it is chosen.
pub(super) fn rigging(controls: Controls) -> &'static dyn Rigging {
    match controls {
        Controls::Handles => &ByHandles,
        Controls::Cage => &ByCage,
    }
}

impl Document {
    /// The way the document's own controls go.
    pub(super) fn rigging(&self) -> &'static dyn Rigging {
        rigging(self.controls())
    }
}

/// Point and bar handles on the picture: C² (the rig), ARAP and MLS (a deformer set
/// up on the picture's mesh), or the parts, each set up by the method.
struct ByHandles;

impl Rigging for ByHandles {
    fn refusal(&self, _: Method, _: &Project) -> Option<String> {
        None
    }

    fn parts_set_up_on_opening(&self) -> bool {
        true
    }

    fn sync(&self, doc: &mut Document) -> Result<()> {
        doc.sync_handles()
    }

    fn may_have_no_state(&self, doc: &Document) -> bool {
        doc.rig()
            .is_some_and(|rig| Deformer::method(rig) == doc.project.method)
    }

    fn check(&self, doc: &Document, mesh: u64, deformer: &dyn Deformer) -> Result<()> {
        if doc.project.parts.is_some() {
            return doc.parts_sanity_check(mesh);
        }
        if mesh != doc.mesh_version || deformer.rest() != doc.mesh().positions() {
            bail!(
                "the {} deformer was set up on another mesh",
                doc.project.method.name()
            );
        }
        Ok(())
    }

    fn shown<'a>(&self, doc: &'a Document, _: bool) -> Shown<'a> {
        match doc.parts() {
            Some(parts) => Shown::Parts(parts),
            None => Shown::Picture(doc.deformer()),
        }
    }

    fn fit_into(
        &self,
        doc: &mut Document,
        handle: &HandleSpec,
        poses: &[Pose],
    ) -> Result<Vec<HandlePose>> {
        let current = doc.project.clone();
        let fitted = poses
            .iter()
            .map(|pose| {
                doc.show_pose(pose)?;
                Ok(doc.fit(handle))
            })
            .collect::<Result<Vec<_>>>();
        doc.restore(current)?;
        fitted
    }

    fn drawn_triangles(&self, doc: &Document) -> Vec<[u32; 3]> {
        doc.draw_order()
    }
}

/// A cage around the picture (LBC): its solved coordinates, or the parts inside it.
struct ByCage;

impl Rigging for ByCage {
    fn refusal(&self, method: Method, project: &Project) -> Option<String> {
        project.cage.is_none().then(|| {
            format!(
                "{} warps by a cage: draw one first with the cage tool (K)",
                method.name().to_uppercase()
            )
        })
    }

    fn parts_set_up_on_opening(&self) -> bool {
        false
    }

    fn sync(&self, doc: &mut Document) -> Result<()> {
        doc.sync_cage()
    }

    fn may_have_no_state(&self, doc: &Document) -> bool {
        doc.cage_solution().is_none()
    }

    fn check(&self, doc: &Document, _: u64, deformer: &dyn Deformer) -> Result<()> {
        doc.cage_deformer_check(deformer)
    }

    fn shown<'a>(&self, doc: &'a Document, warping: bool) -> Shown<'a> {
        // The parts are drawn when the cage is the document's own controls and moves
        // them; a cage drawn over a handle method shows the picture at rest.
        match doc.parts() {
            Some(parts) if doc.controls() == Controls::Cage => Shown::Parts(parts),
            _ => Shown::Cage(doc.cage_deformer().filter(|_| warping)),
        }
    }

    fn fit_into(
        &self,
        _: &mut Document,
        handle: &HandleSpec,
        poses: &[Pose],
    ) -> Result<Vec<HandlePose>> {
        // The cage moves the picture; a handle waits at rest for the handles to come
        // back.
        Ok(vec![HandlePose::rest(handle); poses.len()])
    }

    fn drawn_triangles(&self, doc: &Document) -> Vec<[u32; 3]> {
        doc.deformer().triangles().to_vec()
    }
}
