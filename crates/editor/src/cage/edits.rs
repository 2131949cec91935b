//! The cage tool's edits of the cage: close the polygon drawn, make one from the
//! picture's outline, remove vertices, solve, reset the pose, edit at rest, clear.
//! Each is one undo step, applied through the host.

use glam::DVec2;

use super::{CageState, CageTool};
use crate::document::{CageKey, Edit};
use crate::tool::Host;

impl CageTool {
    /// Applies `edit` through the host. The tool is lent out while it runs, so it ends
    /// its own gesture first (as the app ends the gestures it holds), and keeps its
    /// selection to the vertices the cage then has.
    pub(super) fn edit(&mut self, host: &mut dyn Host, edit: Edit) -> bool {
        if !host.busy() {
            self.finish_gesture(host);
        }
        let applied = host.edit(edit);
        if applied {
            let count = host
                .document()
                .and_then(|d| d.cage())
                .map_or(0, |c| c.rest.len());
            self.retain_valid(count);
        }
        applied
    }

    /// Replaces the rest cage (one undo step; the pose goes back to rest and the cage
    /// must be solved again).
    pub(super) fn set_rest(&mut self, host: &mut dyn Host, rest: Vec<DVec2>) -> bool {
        let rest = rest.iter().map(|p| p.to_array()).collect();
        let vertices = self.inside_vertices;
        self.edit(host, Edit::Cage { rest, vertices })
    }

    /// Closes the polygon being drawn into the rig file's cage (LBC becomes the
    /// method). A polygon that is not simple is refused, and stays to be fixed.
    pub(crate) fn close(&mut self, host: &mut dyn Host) {
        let Some(draft) = self.draft.take() else {
            return;
        };
        if draft.len() < 3 {
            host.error(&anyhow::anyhow!(
                "a cage needs at least 3 vertices: click around the subject"
            ));
            self.draft = Some(draft);
            return;
        }
        if let Err(e) = lbc::Cage::new(draft.clone()) {
            host.error(&anyhow::anyhow!(
                "the cage was not closed: {e} (Backspace removes the last vertex)"
            ));
            self.draft = Some(draft);
            return;
        }
        let n = draft.len();
        if self.set_rest(host, draft.clone()) {
            self.selected.clear();
            self.edit_rest = false;
            host.info(&format!(
                "a cage of {n} vertices: drag its vertices to adjust it (click an edge to \
                 add one, Alt-click to remove one), then Solve (Enter)"
            ));
        } else {
            self.draft = Some(draft);
        }
    }

    /// Removes the selected cage vertices (at rest; at least three stay).
    pub(crate) fn delete_vertices(&mut self, host: &mut dyn Host) {
        let Some(doc) = host.document() else { return };
        if self.selected.is_empty() {
            return;
        }
        if self.state(Some(doc)) == CageState::Posed {
            host.error(&anyhow::anyhow!(
                "vertices are removed at rest: choose Edit the rest cage first"
            ));
            return;
        }
        let rest = doc.cage_rest();
        let left: Vec<DVec2> = rest
            .iter()
            .enumerate()
            .filter(|(i, _)| !self.selected.contains(i))
            .map(|(_, p)| *p)
            .collect();
        if left.len() < 3 {
            host.error(&anyhow::anyhow!("a cage keeps at least 3 vertices"));
            return;
        }
        let removed = rest.len() - left.len();
        if self.set_rest(host, left) {
            self.selected.clear();
            host.info(&format!("removed {removed} cage vertices"));
        }
    }

    /// Solves the cage's coordinates on the worker (Escape cancels); then a drag
    /// poses it.
    pub(crate) fn solve(&mut self, host: &mut dyn Host) {
        let Some(key) = host.document().and_then(|d| CageKey::of(d.project())) else {
            host.error(&anyhow::anyhow!(
                "there is no cage to solve: draw one first"
            ));
            return;
        };
        self.edit_rest = false;
        if host
            .document()
            .is_some_and(|d| d.solution_for(&key).is_some())
        {
            return;
        }
        let busy = host.busy();
        host.solve_cage(key);
        if !busy && host.busy() {
            // The solve started: the document may change when it is in, so the
            // gesture under way ends (as the app ends its own).
            self.finish_gesture(host);
        }
    }

    /// A cage around the picture's visible shape, with [`CageTool::outline_vertices`]
    /// vertices (one undo step).
    pub(crate) fn make_from_outline(&mut self, host: &mut dyn Host) {
        let Some(doc) = host.document() else { return };
        let (w, h) = doc.image.dimensions();
        let offset = pipeline::cage::outline_offset(w, h);
        let vertices = self.outline_vertices;
        match pipeline::cage::cage_from_outline(&doc.image, vertices, offset) {
            Ok(ring) => {
                self.draft = None;
                let note = pipeline::cage::outline_note(vertices, ring.len())
                    .map_or(String::new(), |n| format!(" ({n})"));
                let count = ring.len();
                if self.set_rest(host, ring) {
                    self.selected.clear();
                    self.edit_rest = false;
                    host.info(&format!(
                        "a cage of {count} vertices around everything visible{note}: adjust \
                         it, then Solve (Enter)"
                    ));
                }
            }
            Err(e) => host.error(&e.context("no cage from the outline")),
        }
    }

    /// Removes the cage (one undo step; LBC gives way to C²).
    pub(crate) fn clear(&mut self, host: &mut dyn Host) {
        self.draft = None;
        if host.document().is_some_and(|d| d.cage().is_some()) && self.edit(host, Edit::ClearCage) {
            self.selected.clear();
            self.edit_rest = false;
            host.info("the cage is gone: click to draw a new one");
        }
    }

    /// Puts the cage's vertices back at rest (one undo step).
    pub(crate) fn reset_pose(&mut self, host: &mut dyn Host) {
        let Some(doc) = host.document() else { return };
        let Some(cage) = doc.cage() else { return };
        if cage.pose.is_some() {
            let rest = cage.rest.clone();
            let _ = self.edit(host, Edit::CagePose(rest));
        }
    }

    /// Edits the solved cage at rest (its pose goes back to rest first), or poses it
    /// again.
    pub(crate) fn toggle_rest(&mut self, host: &mut dyn Host) {
        if self.edit_rest {
            self.edit_rest = false;
            if self.state(host.document()) == CageState::Rest {
                self.solve(host);
            }
            return;
        }
        self.reset_pose(host);
        self.edit_rest = true;
    }

    /// Starts a new polygon (the cage stays until the new one is closed).
    pub(super) fn start_new(&mut self) {
        self.selected.clear();
        self.draft = Some(Vec::new());
    }
}
