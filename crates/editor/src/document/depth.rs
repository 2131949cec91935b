//! Automatic depth in the editor (the ARAP paper's §5.1, `pipeline::order`): after
//! every change the shown mesh's overlap regions are arranged, continuing the last
//! pose's, and their orders are written into the rig file (`overlaps`), so what is
//! shown is what a save, an export or `c2warp render` draws.

use glam::DVec2;
use pipeline::Deformer;
use pipeline::order::{Arranger, as_triangles};
use project::{HandleSpec, OverlapOrder};

use super::Document;

/// The most triangles arranged on every frame of a live drag and at once after every
/// edit (a few milliseconds where the pose overlaps itself). A larger mesh keeps the
/// drag's first order until the drag ends, and is arranged then; after another edit
/// (an insertion, an undo) it is arranged on the next frame
/// ([`Document::arrange_deferred`]). A mesh new to the document is arranged at once.
const LIVE_TRIANGLES: usize = 12_000;

/// The arrangement of the mesh shown, and what it was made for.
#[derive(Clone)]
pub(super) struct Depth {
    /// Whether it is the cage's mesh (else the picture's, under handles).
    cage: bool,
    /// The handles' depths the predefined order came from.
    depths: Vec<i32>,
    /// The method whose predefined order it is.
    method: project::Method,
    /// The weights version it was made at: the C² rig's cells, which the predefined
    /// order follows, change with the handles and the weighting parameters.
    weights: u64,
    /// The mesh's triangles (in its own order).
    triangles: Vec<[u32; 3]>,
    /// The mesh's rest positions: parts reordered join their meshes in another order,
    /// which can list the same triangles over other places (two parts of the same
    /// shape) or on other parts (two at the same place), and what the arranger
    /// remembers names triangles by index (and its parts by triangle).
    rest: Vec<DVec2>,
    /// Where the shown mesh's triangles lay, how many, and the mesh's version.
    mesh: (usize, usize, u64),
    arranger: Arranger,
    /// The triangles in drawing order.
    pub(super) order: Vec<[u32; 3]>,
    /// The orders written into the rig file: a rig file that holds others (an undo,
    /// a file opened) starts the arrangement afresh from its own.
    wrote: Vec<OverlapOrder>,
}

impl Depth {
    /// Whether it arranges the cage's mesh.
    pub(super) fn is_cage(&self) -> bool {
        self.cage
    }
}

impl Document {
    /// Arranges the shown mesh's overlaps for the current pose (see the module
    /// documentation); bumps [`Document::order_version`] when the drawing order
    /// changed.
    pub(super) fn rearrange(&mut self) {
        self.rearrange_now(false);
    }

    /// Arranges a pose whose arrangement waited (see [`LIVE_TRIANGLES`]): the app
    /// calls it at the start of every frame, so an edit of a large mesh is drawn
    /// arranged from the frame after it. Returns whether it arranged.
    pub fn arrange_deferred(&mut self) -> bool {
        if !self.depth_deferred || self.live {
            return false;
        }
        self.rearrange_now(true);
        true
    }

    /// [`Document::rearrange`]; on the mesh arranged last, a large one waits for the
    /// drag's end or the next frame unless `now`.
    pub(super) fn rearrange_now(&mut self, now: bool) {
        let (cage, arranged) = self.arranged();
        // (Compared by where the shown mesh's triangles lie, not element by element:
        // a pose keeps the mesh, and this runs on every frame of a drag.)
        let shown = arranged.map(Deformer::triangles);
        let rest = arranged.map(Deformer::rest);
        // A pin added to parts sets up a new deformer over the same joined mesh (the
        // parts it binds posed again, not meshed): the same mesh, element by element.
        let key = shown.map(|t| (t.as_ptr() as usize, t.len(), self.mesh_version));
        let same_mesh = self.depth.as_ref().is_some_and(|d| {
            d.cage == cage
                && d.triangles.len() > LIVE_TRIANGLES
                && (Some(d.mesh) == key
                    || (d.mesh.2 == self.mesh_version
                        && shown == Some(&d.triangles[..])
                        && rest == Some(&d.rest[..])))
        });
        if (self.live || !now) && same_mesh && self.project.auto_depth {
            self.depth_deferred = true;
            if let (Some(depth), Some(key)) = (&mut self.depth, key) {
                depth.mesh = key;
            }
            return;
        }
        self.depth_deferred = false;
        let mut previous = self.depth.take();
        let old_order = previous.as_mut().map(|d| std::mem::take(&mut d.order));
        let Some(deformer) = self.arranged().1.filter(|_| self.project.auto_depth) else {
            if !self.project.auto_depth {
                self.project.overlaps.clear();
            }
            if previous.is_some() {
                self.order_version += 1;
            }
            return;
        };
        // Parts: each triangle's part, the joined mesh already in the predefined order
        // (the parts' draw order, each part's own by its handles' depths).
        let part_of = (self.parts())
            .filter(|_| !cage)
            .map(|p| p.part_of().to_vec());
        let depths: Vec<i32> = if cage || part_of.is_some() {
            Vec::new()
        } else {
            self.project.handles.iter().map(HandleSpec::depth).collect()
        };
        let triangles = deformer.triangles();
        // A handle's depth changed (not a file's or an undo's orders restored): the
        // artist asks for another order, and every overlap is decided afresh by it.
        let new_depths = previous.as_ref().is_some_and(|d| {
            d.cage == cage
                && d.depths.len() == depths.len()
                && d.depths != depths
                && d.wrote == self.project.overlaps
        });
        let joined = part_of.is_some();
        let method = self.project.method;
        let predefined = || {
            if cage || joined {
                (0..triangles.len() as u32).collect()
            } else {
                self.predefined_order()
            }
        };
        // The same mesh keeps its arranger (its topology, and what it remembers: a
        // handle added or removed changes no overlap's order).
        let kept = previous.filter(|d| {
            d.cage == cage
                && d.triangles == triangles
                && d.rest == deformer.rest()
                && d.arranger.part_of() == part_of.as_deref()
        });
        let mut arranger = match kept {
            Some(depth) => {
                let mut arranger = depth.arranger;
                // (Another handle method finds each triangle's handle its own way; new
                // weights are new cells.)
                if depth.depths != depths
                    || depth.method != method
                    || depth.weights != self.weights_version
                {
                    arranger.set_predefined(predefined());
                }
                if new_depths {
                    arranger.restart(&[], deformer.rest(), triangles);
                } else if depth.wrote != self.project.overlaps {
                    arranger.restart(&self.project.overlaps, deformer.rest(), triangles);
                }
                arranger
            }
            None => {
                let saved: &[OverlapOrder] = if new_depths {
                    &[]
                } else {
                    &self.project.overlaps
                };
                match part_of {
                    Some(part_of) => Arranger::with_parts(
                        predefined(),
                        saved,
                        deformer.rest(),
                        triangles,
                        part_of,
                    ),
                    None => Arranger::new(predefined(), saved, deformer.rest(), triangles),
                }
            }
        };
        let order = as_triangles(
            &arranger.arrange(&deformer.deformed(), triangles),
            triangles,
        );
        let wrote = arranger.overlaps(deformer.rest(), triangles);
        let depth = Depth {
            cage,
            depths,
            method,
            weights: self.weights_version,
            mesh: (
                triangles.as_ptr() as usize,
                triangles.len(),
                self.mesh_version,
            ),
            triangles: triangles.to_vec(),
            rest: deformer.rest().to_vec(),
            arranger,
            order,
            wrote: wrote.clone(),
        };
        self.project.overlaps = wrote;
        if old_order.as_ref() != Some(&depth.order) {
            self.order_version += 1;
        }
        self.depth = Some(depth);
    }

    /// The mesh automatic depth arranges — what the view shows for the document's own
    /// controls: the picture's mesh or the parts' under handles, the cage's mesh under
    /// LBC (the parts' joined mesh, when a cage moves parts) — and whether it is a
    /// cage's (`None`: an unsolved cage, nothing to arrange).
    fn arranged(&self) -> (bool, Option<&dyn Deformer>) {
        let shown = self.shown(self.controls(), true);
        (shown.over_backdrop(), shown.deformer())
    }

    /// The cage's mesh's triangles in drawing order (with LBC chosen and solved).
    pub fn cage_draw_order(&self) -> Option<Vec<[u32; 3]>> {
        let cage = self.cage_deformer()?;
        Some(match self.depth.as_ref().filter(|d| d.is_cage()) {
            Some(depth) => depth.order.clone(),
            None => cage.triangles().to_vec(),
        })
    }

    /// The overlap regions of the shown pose, each as the triangles (indices into the
    /// shown mesh's list) of its front and back sheets: the overlap view.
    pub fn overlap_regions(&self) -> &[depth::Region] {
        self.depth.as_ref().map_or(&[], |d| d.arranger.regions())
    }
}
