//! The editor's side of the cage tool: lending it out with the app as its host, and
//! the editor's cage commands and queries (for the menus, tests and scripts), each
//! run by the tool.

use glam::DVec2;

use crate::app::EditorApp;
use crate::cage::{CageState, CageTool};
use crate::tool::Host;

impl EditorApp {
    /// Runs `f` on the cage tool with the app as its host (the tool is lent out for
    /// the call, so it and the host can both be changed).
    pub(crate) fn with_cage<R>(&mut self, f: impl FnOnce(&mut CageTool, &mut dyn Host) -> R) -> R {
        let mut cage = std::mem::take(&mut self.cage);
        let out = f(&mut cage, self);
        self.cage = cage;
        out
    }

    /// What the cage tool does now.
    pub fn cage_state(&self) -> CageState {
        self.cage.state(self.doc.as_ref())
    }

    /// The cage tool's selection (cage vertex indices; the last is the heat map's).
    pub fn cage_selection(&self) -> &[usize] {
        self.cage.selection()
    }

    /// The polygon being drawn, if any (image pixels).
    pub fn cage_draft(&self) -> Option<&[DVec2]> {
        self.cage.draft()
    }

    /// Whether a solved cage warps the view: LBC with its cage solved, and no new
    /// polygon being drawn (that is drawn over the picture at rest).
    pub(crate) fn cage_warping(&self) -> bool {
        self.cage.warping(self.doc.as_ref())
    }

    /// Ends a cage drag (one undo step if it changed anything) or box selection in
    /// progress: the document is about to change under it.
    pub(crate) fn end_cage_gesture(&mut self) {
        self.with_cage(|cage, host| cage.finish_gesture(host));
    }

    /// Closes the polygon being drawn into the rig file's cage (LBC becomes the
    /// method). A polygon that is not simple is refused, and stays to be fixed.
    pub fn close_cage(&mut self) {
        self.with_cage(|cage, host| cage.close(host));
    }

    /// Removes the selected cage vertices (at rest; at least three stay).
    pub fn delete_cage_vertices(&mut self) {
        self.with_cage(|cage, host| cage.delete_vertices(host));
    }

    /// Solves the cage's coordinates on the worker (Escape cancels); then a drag
    /// poses it.
    pub fn solve_cage(&mut self) {
        self.with_cage(|cage, host| cage.solve(host));
    }

    /// A cage around the picture's visible shape, with as many vertices as the panel
    /// asks (one undo step).
    pub fn cage_from_outline(&mut self) {
        self.with_cage(|cage, host| cage.make_from_outline(host));
    }

    /// Removes the cage (one undo step; LBC gives way to C²).
    pub fn clear_cage(&mut self) {
        self.with_cage(|cage, host| cage.clear(host));
    }

    /// Puts the cage's vertices back at rest (one undo step).
    pub fn reset_cage_pose(&mut self) {
        self.with_cage(|cage, host| cage.reset_pose(host));
    }

    /// Edits the solved cage at rest (its pose goes back to rest first), or poses it
    /// again.
    pub fn toggle_cage_rest(&mut self) {
        self.with_cage(|cage, host| cage.toggle_rest(host));
    }
}
