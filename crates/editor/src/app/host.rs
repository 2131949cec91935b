//! The app as the tools' host ([`Host`]): what a tool may use of it, and the lenders
//! that hand a tool its host.

use super::*;
use crate::timeline::Record;

impl Host for EditorApp {
    fn document(&self) -> Option<&Document> {
        self.doc.as_ref()
    }

    fn document_mut(&mut self) -> Option<&mut Document> {
        self.doc.as_mut()
    }

    fn viewport(&self) -> &Viewport {
        &self.viewport
    }

    fn shows(&self) -> Show {
        self.show
    }

    fn shows_mut(&mut self) -> &mut Show {
        &mut self.show
    }

    fn edit(&mut self, edit: Edit) -> bool {
        EditorApp::edit(self, edit)
    }

    fn busy(&self) -> bool {
        self.is_busy()
    }

    fn preview(&mut self, project: Project) {
        // A drag takes over from playback.
        self.timeline.playing = None;
        // A live drag: recording, when armed, starts with it (from the pose before
        // it), and samples every pose it shows.
        self.start_take();
        let Some(doc) = &mut self.doc else { return };
        if let Err(e) = doc.preview(project) {
            self.error(&e);
        }
        self.sample_take();
    }

    fn taking(&self) -> bool {
        self.timeline.is_taking() || matches!(self.timeline.record, Record::Armed)
    }

    fn set_pointer_time(&mut self, time: f64) {
        self.timeline.clock = time;
    }

    fn record(&mut self, before: Project) {
        // The drag is over: what it shows is solved in full.
        if let Some(doc) = &mut self.doc
            && let Err(e) = doc.settle()
        {
            self.error(&e);
        }
        if self.end_take() {
            return;
        }
        self.record_step(before, None);
    }

    fn solve_cage(&mut self, key: CageKey) {
        self.start_cage_solve(key, None);
    }

    fn panning(&self) -> bool {
        self.panning
    }

    fn pan(&mut self) {
        self.panning = true;
    }

    fn info(&mut self, text: &str) {
        EditorApp::info(self, text);
    }

    fn error(&mut self, error: &anyhow::Error) {
        EditorApp::error(self, error);
    }

    fn mesh_version(&self) -> u64 {
        self.gpu.frame.mesh.version
    }

    fn tool(&self) -> Tool {
        self.tool
    }

    fn selected(&self) -> Option<usize> {
        self.selected
    }

    fn select(&mut self, index: Option<usize>) {
        self.selected = index;
    }

    fn auto_rotate(&self) -> bool {
        self.auto_rotate
    }

    fn dual_graph(&self) -> &[(u32, u32)] {
        &self.gpu.dual_graph.1
    }
}

impl EditorApp {
    /// Runs `f` on the rigidity brush with the app as its host (the brush is lent out
    /// for the call, so it and the host can both be changed).
    pub(crate) fn with_brush<R>(&mut self, f: impl FnOnce(&mut Brush, &mut dyn Host) -> R) -> R {
        let mut brush = std::mem::take(&mut self.brush);
        let out = f(&mut brush, self);
        self.brush = brush;
        out
    }

    /// Runs `f` on the cut tool with the app as its host (lent out for the call).
    pub(crate) fn with_cut<R>(
        &mut self,
        f: impl FnOnce(&mut crate::cut::CutTool, &mut dyn Host) -> R,
    ) -> R {
        let mut cut = std::mem::take(&mut self.cut);
        let out = f(&mut cut, self);
        self.cut = cut;
        out
    }

    /// Runs `f` on the handle tools with the app as their host (the tool is lent out
    /// for the call, so it and the host can both be changed).
    pub(crate) fn with_handles<R>(
        &mut self,
        f: impl FnOnce(&mut HandleTool, &mut dyn Host) -> R,
    ) -> R {
        let mut handles = std::mem::take(&mut self.handles);
        let out = f(&mut handles, self);
        self.handles = handles;
        out
    }

    /// Runs `f` on the tool that acts as `tool` with the app as its host (lent out
    /// for the call): the handle tools for theirs, the brush, the cut tool, the cage
    /// tool, the perform tool.
    pub(crate) fn with_tool<R>(
        &mut self,
        tool: Tool,
        f: impl FnOnce(&mut dyn CanvasTool, &mut dyn Host) -> R,
    ) -> R {
        match tool {
            Tool::Puppet | Tool::Select | Tool::AddPoint | Tool::AddBar => {
                self.with_handles(|t, host| f(t, host))
            }
            Tool::Rigidity => self.with_brush(|t, host| f(t, host)),
            Tool::Cut => self.with_cut(|t, host| f(t, host)),
            Tool::Cage => self.with_cage(|t, host| f(t, host)),
            Tool::Perform => self.with_perform(|t, host| f(t, host)),
        }
    }

    /// Runs `f` on the perform tool with the app as its host (lent out for the call).
    pub(crate) fn with_perform<R>(
        &mut self,
        f: impl FnOnce(&mut PerformTool, &mut dyn Host) -> R,
    ) -> R {
        let mut perform = std::mem::take(&mut self.perform);
        let out = f(&mut perform, self);
        self.perform = perform;
        out
    }

    /// The triangles the painted-rigidity overlay drew last (their corners).
    pub fn painted_triangles(&self) -> Vec<[u32; 3]> {
        self.brush.painted_triangles()
    }
}
