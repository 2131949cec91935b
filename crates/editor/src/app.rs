//! The editor application: the document, its undo history, the view and tool state,
//! and the one place where edits are applied ([`EditorApp::edit`]).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context as _, Result};
use glam::DVec2;
use project::{HandleSpec, Method, Project};

use crate::brush::Brush;
use crate::cage::CageTool;
use crate::dialogs::{Answer, BuiltinDialog, Dialogs, FileAction, NativeDialogs, Shown};
use crate::document::{CageKey, Document, Edit, posed};
use crate::gpu_frame::{FrameBuilder, View};
use crate::history::History;
use crate::jobs::{CancelFlag, Job, Outcome, Rebuild, SolveProgress};
use crate::scene::SceneResources;
use crate::show::Show;
use crate::tool::{CanvasTool, Host};
use crate::viewport::Viewport;

/// What a primary click or drag on the canvas does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tool {
    /// The Puppet Warp convention: a click on the picture adds a point handle, a click
    /// on a handle selects it, dragging a handle moves it (Alt-drag rotates, Shift-drag
    /// scales), Alt-click on a handle deletes it, dragging empty canvas pans.
    Puppet,
    /// As [`Tool::Puppet`], but a click on the picture only deselects.
    Select,
    /// Click to add a point handle.
    AddPoint,
    /// Drag to add a bar handle.
    AddBar,
    /// Paint rigidity (ARAP); Alt-drag erases.
    Rigidity,
    /// Draw, adjust, solve and pose an LBC cage (see [`crate::cage`]).
    Cage,
}

/// Messages the log keeps before the oldest is forgotten.
pub const LOG_LIMIT: usize = 200;

/// A message in the status bar.
#[derive(Clone, Debug, PartialEq)]
pub struct Message {
    /// One line.
    pub text: String,
    /// Shown in red.
    pub is_error: bool,
}

/// Something that would discard unsaved changes, waiting for the user's answer.
#[derive(Clone, Debug, PartialEq)]
pub enum Pending {
    /// Open this picture or project.
    Open(PathBuf),
    /// Close the window.
    Close,
    /// Write over this existing file (chosen in the built-in dialog).
    Replace(FileAction, PathBuf),
}

/// A drag of a handle in progress.
#[derive(Clone, Debug)]
pub(crate) struct HandleDrag {
    pub index: usize,
    pub grip: Grip,
    /// The handle when the drag began.
    pub start: HandleSpec,
    /// The pointer when the drag began (image pixels).
    pub pointer: DVec2,
    /// The document before the drag, recorded in the history if the drag changed it.
    pub before: project::Project,
}

/// What part of a handle is being dragged, and how.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Grip {
    /// Move the whole handle.
    Move,
    /// Move one end of a bar.
    End(usize),
    /// Rotate about the handle's centre.
    Rotate,
    /// Scale about the handle's centre.
    Scale,
}

/// The editor.
pub struct EditorApp {
    pub(crate) doc: Option<Document>,
    pub(crate) history: History,
    pub(crate) dirty: bool,
    /// The view: pan and zoom.
    pub viewport: Viewport,
    pub(crate) needs_fit: bool,
    /// The view is as the last fit left it (no pan or zoom since).
    pub(crate) view_fitted: bool,
    /// The active tool.
    pub tool: Tool,
    /// The selected handle.
    pub selected: Option<usize>,
    pub(crate) drag: Option<HandleDrag>,
    pub(crate) bar_start: Option<DVec2>,
    pub(crate) context_point: Option<DVec2>,
    /// The handle the right-click menu was opened on, and its index then.
    pub(crate) context_handle: Option<(usize, HandleSpec)>,
    pub(crate) panning: bool,
    /// Overlays.
    pub show: Show,
    /// The weights under the pointer, as shown beside it (`None` when not hovering the
    /// picture).
    pub hover_readout: Option<String>,
    /// Point handles turn with their neighbours' motion.
    pub auto_rotate: bool,
    /// The status line: the latest message.
    pub message: Option<Message>,
    /// Every message so far (the newest last, at most [`LOG_LIMIT`]), for the messages
    /// window.
    pub log: Vec<Message>,
    /// The messages window is open.
    pub log_open: bool,
    /// A question waiting for an answer.
    pub pending: Option<Pending>,
    pub(crate) allow_close: bool,
    /// The keyboard shortcuts window is open.
    pub help_open: bool,
    pub(crate) dialogs: Box<dyn Dialogs>,
    /// An undo or redo that rebuilds a rig with more samples than this (it brings
    /// back other handles) runs on the worker thread, so the window keeps answering.
    /// (New parameters always rebuild on the worker.)
    pub large_mesh: usize,
    /// Use the built-in file dialog (the desktop has none, or the user prefers it).
    pub builtin_dialogs: bool,
    pub(crate) file_dialog: Option<BuiltinDialog>,
    /// The rigidity brush: its radius and weight, the stroke under way.
    pub brush: Brush,
    /// The cage tool: its settings (the vertices of a cage from the outline, the mesh
    /// vertices inside a new cage), the polygon being drawn, the selection.
    pub cage: CageTool,
    /// Where the built-in file dialog starts when the document has no file of its own
    /// (else the current folder).
    pub default_folder: Option<PathBuf>,
    /// What the canvas hands the GPU, kept up to date with the document.
    pub(crate) gpu: FrameBuilder,
    pub(crate) has_gpu: bool,
    pub(crate) settings_draft: Option<crate::document::Settings>,
    /// MLS's α and fit while its slider is dragged.
    pub(crate) mls_draft: Option<(f64, project::MlsVariant)>,
    pub(crate) job: Option<Job>,
    /// The checkerboard behind transparent pixels.
    pub(crate) checker: Option<egui::TextureHandle>,
    /// Repaints the window when a job finishes.
    wake: Option<egui::Context>,
    /// Milliseconds the last frame's logic took on the CPU.
    pub frame_ms: f64,
}

impl EditorApp {
    /// The editor on `path` (a picture, or a `.json` project), or on the built-in
    /// picture. Sets up the GPU resources when eframe runs on wgpu.
    pub fn new(cc: &eframe::CreationContext<'_>, path: Option<&Path>) -> Self {
        let has_gpu = if let Some(state) = &cc.wgpu_render_state {
            let resources = SceneResources::new(&state.device, &state.queue, state.target_format);
            state.renderer.write().callback_resources.insert(resources);
            true
        } else {
            false
        };
        let mut app = Self::headless(has_gpu);
        app.wake = Some(cc.egui_ctx.clone());
        if let Some(path) = path {
            app.open_in_background(path.to_path_buf());
        }
        app
    }

    /// The editor on the built-in picture, without GPU resources (nothing is drawn
    /// through the GPU unless `has_gpu`).
    pub fn headless(has_gpu: bool) -> Self {
        match Document::built_in() {
            Ok(doc) => Self::build(Some(doc), None, has_gpu),
            Err(e) => Self::build(
                None,
                Some(Message {
                    text: format!("cannot open the built-in picture: {e:#}"),
                    is_error: true,
                }),
                has_gpu,
            ),
        }
    }

    /// The editor on `doc`, without GPU resources (for tests and benchmarks).
    pub fn with_document(doc: Document) -> Self {
        Self::build(Some(doc), None, false)
    }

    fn build(doc: Option<Document>, message: Option<Message>, has_gpu: bool) -> Self {
        Self {
            doc,
            history: History::default(),
            dirty: false,
            viewport: Viewport::default(),
            needs_fit: true,
            view_fitted: false,
            tool: Tool::Puppet,
            selected: None,
            drag: None,
            bar_start: None,
            context_point: None,
            context_handle: None,
            panning: false,
            show: Show::default(),
            hover_readout: None,
            auto_rotate: false,
            log: message.iter().cloned().collect(),
            message,
            log_open: false,
            pending: None,
            allow_close: false,
            help_open: false,
            dialogs: Box::new(NativeDialogs::new()),
            large_mesh: 100_000,
            builtin_dialogs: false,
            file_dialog: None,
            brush: Brush::default(),
            cage: CageTool::default(),
            default_folder: None,
            gpu: FrameBuilder::default(),
            has_gpu,
            settings_draft: None,
            mls_draft: None,
            job: None,
            checker: None,
            wake: None,
            frame_ms: 0.0,
        }
    }

    /// Moves handle `index` `by` steps forward in the overlap order (negative:
    /// backward): where the warped picture overlaps itself, the part nearest the
    /// handle of greater depth is drawn in front. One undo step.
    pub fn change_depth(&mut self, index: usize, by: i32) {
        let Some(handle) = self
            .doc
            .as_ref()
            .and_then(|d| d.project().handles.get(index))
        else {
            return;
        };
        let depth = handle.depth().saturating_add(by);
        let moved = handle.with_depth(depth);
        if self.edit(Edit::Pose(index, moved)) {
            self.info(format!("handle {} now has depth {depth}", index + 1));
        }
    }

    /// Replaces the file dialogs (tests answer them with fixed paths).
    pub fn set_dialogs(&mut self, dialogs: Box<dyn Dialogs>) {
        self.dialogs = dialogs;
    }

    /// The open document.
    pub fn document(&self) -> Option<&Document> {
        self.doc.as_ref()
    }

    /// The open document, to change it directly (edits made this way bypass the undo
    /// history).
    pub fn document_mut(&mut self) -> Option<&mut Document> {
        self.doc.as_mut()
    }

    /// Checks the editor's invariants — the document's ([`Document::sanity_check`]),
    /// and that every index the editor holds (the selection, the handle being dragged)
    /// points at a handle that exists, that a bar is drawn only with the bar tool, and
    /// that the GPU frame, once brought up to date, matches the mesh. Used by tests
    /// after every step of a session.
    ///
    /// # Errors
    /// The first broken invariant, in words.
    pub fn sanity_check(&self) -> Result<()> {
        let Some(doc) = &self.doc else {
            if self.selected.is_some() || self.drag.is_some() {
                anyhow::bail!("a selection or drag without a document");
            }
            return Ok(());
        };
        doc.sanity_check()?;
        let handles = &doc.project().handles;
        if let Some(s) = self.selected
            && s >= handles.len()
        {
            anyhow::bail!("handle {s} is selected, but there are {}", handles.len());
        }
        if let Some(drag) = &self.drag {
            match handles.get(drag.index) {
                Some(h) if crate::document::same_rest(h, &drag.start) => {}
                _ => anyhow::bail!("the drag holds handle {}, which is gone", drag.index),
            }
        }
        if self.bar_start.is_some() && self.tool != Tool::AddBar {
            anyhow::bail!("a bar is being drawn with the {:?} tool", self.tool);
        }
        self.cage_sanity_check(doc)?;
        self.gpu.sanity_check(doc)?;
        if self.log.len() > LOG_LIMIT {
            anyhow::bail!("the message log outgrew its limit");
        }
        if !self.viewport.zoom.is_finite() || !self.viewport.origin.is_finite() {
            anyhow::bail!("the view is not finite: {:?}", self.viewport);
        }
        Ok(())
    }

    /// The cage tool's part of [`EditorApp::sanity_check`]: the tool's own
    /// ([`CageTool::sanity_check`]), and a polygon is drawn, or LBC used, only with
    /// the cage tool.
    fn cage_sanity_check(&self, doc: &Document) -> Result<()> {
        self.cage.sanity_check(doc)?;
        if self.cage.draft().is_some() && self.tool != Tool::Cage {
            anyhow::bail!("a cage is being drawn with the {:?} tool", self.tool);
        }
        if doc.method() == Method::Lbc && self.tool != Tool::Cage {
            anyhow::bail!("LBC with the {:?} tool", self.tool);
        }
        Ok(())
    }

    /// How many steps can be undone and redone.
    pub fn history_len(&self) -> (usize, usize) {
        self.history.len()
    }

    /// Whether there are changes not saved to a project file.
    pub fn is_dirty(&self) -> bool {
        self.dirty
    }

    pub(crate) fn info(&mut self, text: impl Into<String>) {
        self.say(Message {
            text: text.into(),
            is_error: false,
        });
    }

    pub(crate) fn error(&mut self, error: &anyhow::Error) {
        self.say(Message {
            text: pipeline::error_line(error),
            is_error: true,
        });
    }

    /// Shows `message` in the status line and keeps it in the log.
    fn say(&mut self, message: Message) {
        if self.log.len() >= LOG_LIMIT {
            self.log.remove(0);
        }
        self.log.push(message.clone());
        self.message = Some(message);
    }

    /// Applies an edit as one undo step. Errors go to the status line; the document is
    /// then unchanged. Returns whether the edit was applied. A new mesh density is
    /// applied on a worker thread (see [`EditorApp::is_busy`]).
    #[must_use = "false when the edit was refused (the status line says why)"]
    pub fn edit(&mut self, edit: Edit) -> bool {
        if let Some(job) = &self.job {
            let label = job.label.clone();
            self.error(&anyhow::anyhow!(
                "not now: {label}… is running (wait for it, or cancel it with Escape)"
            ));
            return false;
        }
        // The document changes under any gesture in progress: a drag ends here (as
        // its own undo step), so its handle index cannot go stale.
        self.end_gesture();
        if let (Edit::Settings(settings), Some(doc)) = (&edit, &self.doc) {
            if settings.density != doc.settings().density {
                self.rebuild_in_background(*settings);
                return true;
            }
            if *settings != doc.settings() {
                // A rebuild can take seconds (a large mesh, a fixed boundary's many
                // nodes): on the worker, so the window keeps answering.
                let before = doc.snapshot();
                let mut copy = doc.clone();
                let label = "Re-weighting".to_owned();
                self.start_job(label, CancelFlag::default(), move || {
                    let document = copy.apply(edit).map(|()| copy);
                    Outcome::Rebuilt {
                        cause: Rebuild::Edit {
                            before: Box::new(before),
                        },
                        document,
                    }
                });
                return true;
            }
        }
        // Setting up ARAP (registration and factorisation) or repainting it takes a
        // noticeable time on a large mesh: on the worker too.
        if let (Edit::Method(Method::Arap) | Edit::Rigidity(_), Some(doc)) = (&edit, &self.doc)
            && doc.rig().domain().len() > self.large_mesh
            && (doc.method() == Method::Arap || matches!(edit, Edit::Method(_)))
        {
            let before = doc.snapshot();
            let mut copy = doc.clone();
            let label = match edit {
                Edit::Method(_) => "Setting up ARAP",
                _ => "Repainting rigidity",
            }
            .to_owned();
            self.start_job(label, CancelFlag::default(), move || {
                let document = copy.apply(edit).map(|()| copy);
                Outcome::Rebuilt {
                    cause: Rebuild::Edit {
                        before: Box::new(before),
                    },
                    document,
                }
            });
            return true;
        }
        let Some(doc) = &mut self.doc else {
            return false;
        };
        let before = doc.snapshot();
        let removes = match edit {
            Edit::Remove(i) => Some(i),
            Edit::Clear => Some(0),
            _ => None,
        };
        match doc.apply(edit) {
            Ok(()) => {
                if doc.project() != &without_virtuals(&before) {
                    self.history.push(before);
                    self.dirty = true;
                }
                self.cage
                    .retain_valid(doc.cage().map_or(0, |c| c.rest.len()));
                if let Some(i) = removes {
                    self.selected = match self.selected {
                        Some(s) if s > i && doc.project().handles.len() > s - 1 => Some(s - 1),
                        Some(s) if s < i => Some(s),
                        _ => None,
                    };
                }
                self.settings_draft = None;
                self.sync_tool();
                true
            }
            Err(e) => {
                self.error(&e);
                false
            }
        }
    }

    /// Adds a point handle under `at` (image pixels, current pose): its rest position is
    /// the point of the picture shown there, and it starts with the rotation and scale
    /// the pose has around it ([`Document::local_pose`]), so the warp jumps as little as
    /// the method allows.
    pub fn add_point(&mut self, at: DVec2) {
        let Some(doc) = &mut self.doc else { return };
        let Some((rest, _, _)) = doc.unwarp(at) else {
            self.error(&anyhow::anyhow!("click on the picture to add a handle"));
            return;
        };
        let (rotate, scale) = doc.local_pose(rest, at);
        let handle = HandleSpec::Point {
            rest: rest.to_array(),
            translate: (at - rest).to_array(),
            rotate,
            scale,
            depth: 0,
        };
        if self.edit(Edit::Add(handle))
            && let Some(doc) = &self.doc
        {
            self.selected = Some(doc.project().handles.len() - 1);
            let ms = doc.last_update_ms;
            self.info(format!(
                "added a point handle; weights updated in {ms:.1} ms"
            ));
        }
    }

    /// Adds a bar from `a` to `b` (image pixels, current pose).
    pub fn add_bar(&mut self, a: DVec2, b: DVec2) {
        let Some(doc) = &mut self.doc else { return };
        let (Some((ra, _, _)), Some((rb, _, _))) = (doc.unwarp(a), doc.unwarp(b)) else {
            self.error(&anyhow::anyhow!("a bar must start and end on the picture"));
            return;
        };
        let handle = HandleSpec::Bar {
            rest: [ra.to_array(), rb.to_array()],
            pose: Some([a.to_array(), b.to_array()]),
            depth: 0,
        };
        if self.edit(Edit::Add(handle))
            && let Some(doc) = &self.doc
        {
            self.selected = Some(doc.project().handles.len() - 1);
            let ms = doc.last_update_ms;
            self.info(format!("added a bar handle; weights updated in {ms:.1} ms"));
        }
    }

    /// Switches tools; a bar or a cage being drawn is dropped, a cage drag ends. The
    /// cage tool is LBC's: picking it with a cage kept in the project chooses LBC (one
    /// undo step); under LBC, the handle tools wait until C² or ARAP is chosen.
    pub fn set_tool(&mut self, tool: Tool) {
        let lbc = self.doc.as_ref().is_some_and(|d| d.method() == Method::Lbc);
        if lbc && tool != Tool::Cage {
            self.info(
                "under LBC the cage moves the picture: choose C² weights or ARAP under Method \
                 to work with handles (the cage stays in the project)",
            );
            return;
        }
        if tool != Tool::Cage {
            self.with_cage(|cage, host| {
                cage.finish_gesture(host);
                cage.cancel();
            });
        }
        self.tool = tool;
        self.bar_start = None;
        if tool == Tool::Cage
            && !lbc
            && let Some(doc) = &self.doc
        {
            if doc.cage().is_some() {
                if self.edit(Edit::Method(Method::Lbc)) {
                    self.info("LBC cage: the cage kept in the project warps the picture");
                }
            } else {
                self.info(
                    "draw a cage: click around the subject, then click the first vertex \
                     (or double-click, or press Enter) to close it — or use Cage from \
                     outline",
                );
            }
        }
    }

    /// Under LBC the cage tool is the tool (handles act under C² and ARAP): after any
    /// change that may have chosen LBC (an undo, an opened project), it is picked.
    pub(crate) fn sync_tool(&mut self) {
        let lbc = self.doc.as_ref().is_some_and(|d| d.method() == Method::Lbc);
        if lbc && self.tool != Tool::Cage {
            self.finish_drag();
            self.tool = Tool::Cage;
            self.bar_start = None;
            self.brush.cancel();
        }
    }

    /// After a step through the history: the tool the new state calls for. Into LBC,
    /// the cage tool; out of LBC with no cage being drawn, the cage tool has nothing
    /// left to act on, so the puppet tool.
    fn sync_tool_after_history(&mut self, was_lbc: bool) {
        let lbc = self.doc.as_ref().is_some_and(|d| d.method() == Method::Lbc);
        if was_lbc && !lbc && self.tool == Tool::Cage && self.cage.draft().is_none() {
            self.end_cage_gesture();
            self.tool = Tool::Puppet;
        }
        self.sync_tool();
    }

    /// Chooses a warping method (one undo step). LBC without a cage starts the cage
    /// tool, to draw one; leaving LBC leaves the cage tool and keeps the cage.
    pub fn choose_method(&mut self, method: Method) {
        let Some(doc) = &self.doc else { return };
        if method == doc.method() {
            // Drawing a cage for LBC, and back to the method already in use.
            if method != Method::Lbc && self.tool == Tool::Cage {
                self.set_tool(Tool::Puppet);
                self.info(format!("{}: drawing the cage dropped", method.label()));
            }
            return;
        }
        if method == Method::Lbc {
            self.set_tool(Tool::Cage);
            if !matches!(self.message.as_ref(), Some(m) if m.is_error) {
                let has_cage = self.doc.as_ref().is_some_and(|d| d.cage().is_some());
                if !has_cage {
                    self.info(
                        "LBC cage: click a polygon around the subject (or Cage from outline), \
                         then Solve",
                    );
                }
            }
            return;
        }
        if self.edit(Edit::Method(method)) {
            if self.tool == Tool::Cage {
                self.set_tool(Tool::Puppet);
            }
            self.info(format!("{}: {}", method.label(), method.about()));
        }
    }

    /// Deletes the selected handle.
    pub fn delete_selected(&mut self) {
        if let Some(i) = self.selected
            && self.edit(Edit::Remove(i))
            && let Some(doc) = &self.doc
        {
            let ms = doc.last_update_ms;
            self.info(format!("removed a handle; weights updated in {ms:.1} ms"));
        }
    }

    /// Sets the pose of handle `index` during a drag (no undo step; the drag makes one
    /// when it ends). With auto-rotation, other point handles turn with their
    /// neighbours.
    pub(crate) fn set_pose(&mut self, index: usize, handle: HandleSpec) {
        let Some(doc) = &mut self.doc else { return };
        let mut project = doc.project().clone();
        let Some(slot) = project.handles.get_mut(index) else {
            debug_assert!(false, "the dragged handle {index} is gone");
            return;
        };
        // A drag poses its own handle; one at another rest means the index went stale.
        let own = crate::document::same_rest(slot, &handle);
        debug_assert!(own, "a drag may not move handle {index} at rest");
        if !own {
            return;
        }
        *slot = handle;
        if self.auto_rotate {
            auto_rotate(&mut project.handles);
        }
        if let Err(e) = doc.restore(project) {
            self.error(&e);
        }
    }

    /// Ends whatever pointer gesture is in progress — a handle drag (one undo step if
    /// it changed anything) or a bar being drawn — because the document is about to
    /// change under it.
    pub(crate) fn end_gesture(&mut self) {
        self.finish_drag();
        self.end_cage_gesture();
        self.bar_start = None;
    }

    /// Ends a handle drag: one undo step if it changed anything.
    pub(crate) fn finish_drag(&mut self) {
        if let Some(drag) = self.drag.take() {
            Host::record(self, drag.before);
        }
    }

    /// Steps back one edit.
    pub fn undo(&mut self) {
        self.step_history(true);
    }

    /// Steps forward one edit.
    pub fn redo(&mut self) {
        self.step_history(false);
    }

    fn step_history(&mut self, back: bool) {
        if self.job.is_some() {
            return;
        }
        self.end_gesture();
        let Some(doc) = &mut self.doc else { return };
        let Some(target) = self.history.peek(back) else {
            return;
        };
        // A posed cage whose coordinates are no longer kept is solved first, on the
        // worker; the history moves when they are in.
        if target.method == Method::Lbc
            && target.cage.as_ref().is_some_and(|c| c.pose.is_some())
            && let Some(key) = CageKey::of(target)
            && doc.solution_for(&key).is_none()
            && key.problem().is_none()
        {
            self.start_cage_solve(key, Some(back));
            return;
        }
        if crate::document::Settings::of(target).density != doc.settings().density {
            // A new mesh: built on the worker, like the same change from the slider.
            let target = target.clone();
            self.restore_in_background(back, target);
            return;
        }
        let new_settings = crate::document::Settings::of(target) != doc.settings();
        if new_settings
            || (doc.rig().domain().len() > self.large_mesh && doc.rebuilds_for(target, true))
        {
            // A rebuild for other parameters, or of a large rig: on the worker, on a
            // copy.
            let target = target.clone();
            let mut copy = doc.clone();
            let label = if back { "Undoing" } else { "Redoing" }.to_owned();
            self.start_job(label, CancelFlag::default(), move || {
                let document = copy.undo_to(target).map(|()| copy);
                Outcome::Rebuilt {
                    cause: Rebuild::History { back },
                    document,
                }
            });
            return;
        }
        let current = doc.snapshot();
        let taken = if back {
            self.history.undo(current)
        } else {
            self.history.redo(current)
        };
        let Some(target) = taken else { return };
        let from = doc.project().clone();
        let was_lbc = from.method == Method::Lbc;
        match doc.undo_to(target.clone()) {
            Ok(()) => {
                let what = crate::history::describe_change(&from, doc.project());
                self.dirty = true;
                self.settings_draft = None;
                self.cage
                    .retain_valid(doc.cage().map_or(0, |c| c.rest.len()));
                if self
                    .selected
                    .is_some_and(|s| s >= doc.project().handles.len())
                {
                    self.selected = None;
                }
                self.sync_tool_after_history(was_lbc);
                self.info(format!(
                    "{}: {what}",
                    if back { "undone" } else { "redone" }
                ));
            }
            Err(e) => {
                self.history.unpop(back, target);
                self.error(&e);
            }
        }
    }

    /// Opens a picture or (for `.json`) a project, asking first if there are unsaved
    /// changes.
    pub fn request_open(&mut self, path: PathBuf) {
        if self.dirty {
            self.pending = Some(Pending::Open(path));
        } else {
            self.open_in_background(path);
        }
    }

    /// Opens a picture or (for `.json`) a project now, waiting for it. On failure the
    /// current document stays and the status line says why.
    pub fn open(&mut self, path: &Path) {
        let outcome = open_outcome(
            path.to_path_buf(),
            &CancelFlag::default(),
            &SolveProgress::default(),
        );
        self.finish(outcome);
    }

    /// Opens a picture or project on a worker thread (an LBC project's cage is solved
    /// there too); the editor shows progress and takes no edits until it is in.
    pub fn open_in_background(&mut self, path: PathBuf) {
        let label = format!("Opening {}", file_name(&path));
        let (cancel, progress) = (CancelFlag::default(), SolveProgress::default());
        let (flag, steps) = (cancel.clone(), progress.clone());
        let work = move || open_outcome(path, &flag, &steps);
        self.start_job(label, cancel, work);
        if let Some(job) = &mut self.job {
            job.progress = Some(progress);
        }
    }

    /// Solves the cage of `key` on the worker, showing its iterations and residuals;
    /// `then`: undo (`true`) or redo once it is in.
    pub(crate) fn start_cage_solve(&mut self, key: CageKey, then: Option<bool>) {
        if let Some(problem) = key.problem() {
            self.error(&anyhow::anyhow!(problem));
            return;
        }
        let (cancel, progress) = (CancelFlag::default(), SolveProgress::default());
        let (flag, steps) = (cancel.clone(), progress.clone());
        let label = format!("Solving the cage ({} vertices inside)", key.vertices);
        self.start_job(label, cancel, move || {
            let clock = Instant::now();
            let solution = crate::document::solve_cage(&key, &mut |step| {
                steps.set(*step);
                !flag.is_set()
            });
            Outcome::CageSolved {
                key,
                solution,
                then,
                ms: clock.elapsed().as_secs_f64() * 1e3,
            }
        });
        if let Some(job) = &mut self.job {
            job.progress = Some(progress);
        }
    }

    /// The first and latest iteration of a cage's solve under way.
    pub fn solve_progress(&self) -> Option<(lbc::Progress, lbc::Progress)> {
        self.job.as_ref()?.progress.as_ref()?.get()
    }

    /// Starts `work` on a worker thread unless a job is running (then says so). Any
    /// gesture in progress ends first: the document may change when the job is in.
    fn start_job(
        &mut self,
        label: String,
        cancel: CancelFlag,
        work: impl FnOnce() -> Outcome + Send + 'static,
    ) {
        if let Some(job) = &self.job {
            let running = job.label.clone();
            self.error(&anyhow::anyhow!(
                "{label} waits: {running}… is still running (cancel it with Escape)"
            ));
            return;
        }
        self.end_gesture();
        self.job = Some(Job::spawn_cancellable(
            label,
            self.wake.clone(),
            cancel,
            work,
        ));
    }

    /// Re-meshes and re-weights the picture for `settings` on a worker thread.
    fn rebuild_in_background(&mut self, settings: crate::document::Settings) {
        let Some(doc) = &self.doc else { return };
        let before = doc.snapshot();
        let mut project = doc.project().clone();
        settings.write_to(&mut project);
        let label = format!("Meshing at {} vertices", settings.density);
        let work = remesh(
            doc,
            project,
            Rebuild::Edit {
                before: Box::new(before),
            },
        );
        self.start_job(label, CancelFlag::default(), work);
    }

    /// Steps through the history to `target`, whose density differs from the
    /// document's, on a worker thread. The history moves when the new mesh is in.
    fn restore_in_background(&mut self, back: bool, target: project::Project) {
        let Some(doc) = &self.doc else { return };
        let density = crate::document::Settings::of(&target).density;
        let label = format!(
            "{} a density change: meshing at {density} vertices",
            if back { "Undoing" } else { "Redoing" }
        );
        let work = remesh(doc, target, Rebuild::History { back });
        self.start_job(label, CancelFlag::default(), work);
    }

    /// Whether a job (opening, re-meshing, exporting) is running.
    pub fn is_busy(&self) -> bool {
        self.job.is_some()
    }

    /// What the running job does, and for how long it has run (seconds).
    pub fn busy_with(&self) -> Option<(&str, f64)> {
        self.job
            .as_ref()
            .map(|j| (j.label.as_str(), j.started.elapsed().as_secs_f64()))
    }

    /// Gives up on the running job, if any: the document stays as it was, and an
    /// export writes nothing (unless it was already writing).
    pub fn cancel_job(&mut self) {
        if let Some(job) = self.job.take() {
            let label = job.label.clone();
            job.cancel();
            self.info(format!("cancelled: {label}"));
        }
    }

    /// Takes in the running job's result if it is done.
    pub(crate) fn poll_job(&mut self) {
        if let Some(outcome) = self.job.as_ref().and_then(Job::poll) {
            self.job = None;
            self.finish(outcome);
        }
    }

    /// Waits for the running job, if any, and takes in its result.
    pub fn wait_for_job(&mut self) {
        if let Some(outcome) = self.job.take().and_then(Job::wait) {
            self.finish(outcome);
        }
    }

    fn finish(&mut self, outcome: Outcome) {
        self.finish_outcome(outcome);
        self.sync_tool();
    }

    fn finish_outcome(&mut self, outcome: Outcome) {
        match outcome {
            Outcome::Opened {
                path,
                is_project,
                document: Ok(doc),
            } => {
                let stats = doc.rig().stats();
                let what = if is_project { "project" } else { "image" };
                self.end_gesture();
                let lbc = doc.method() == Method::Lbc;
                let unsolved = lbc && doc.cage_solution().is_none();
                let problem = CageKey::of(doc.project()).and_then(|k| k.problem());
                self.doc = Some(doc);
                self.history.clear();
                self.dirty = false;
                self.selected = None;
                self.cage.forget_document();
                if lbc {
                    self.tool = Tool::Cage;
                }
                self.needs_fit = true;
                self.settings_draft = None;
                self.info(format!(
                    "opened {what} {} ({} mesh vertices)",
                    path.display(),
                    stats.samples
                ));
                if unsolved {
                    let why = problem.unwrap_or_else(|| {
                        "the cage is not solved: press Solve (Enter) to warp".to_owned()
                    });
                    self.error(&anyhow::anyhow!(why));
                }
            }
            Outcome::Opened {
                path,
                document: Err(e),
                ..
            } => self.error(&e.context(format!("cannot open {}", path.display()))),
            Outcome::Rebuilt {
                cause,
                document: Ok(mut doc),
            } => {
                self.end_gesture();
                let was_lbc = self.doc.as_ref().is_some_and(|d| d.method() == Method::Lbc);
                let history = match &cause {
                    Rebuild::History { back } => self.doc.as_ref().map(|old| {
                        let what = crate::history::describe_change(old.project(), doc.project());
                        format!("{}: {what}; ", if *back { "undone" } else { "redone" })
                    }),
                    Rebuild::Edit { .. } => None,
                };
                let mut kept = Ok(());
                if let Some(old) = &self.doc {
                    kept = doc.keep_solutions_of(old);
                    doc.project_path.clone_from(&old.project_path);
                    doc.weights_version = old.weights_version + 1;
                    doc.pose_version = old.pose_version + 1;
                    let current = old.snapshot();
                    match cause {
                        Rebuild::Edit { before } => self.history.push(*before),
                        Rebuild::History { back: true } => {
                            self.history.undo(current);
                        }
                        Rebuild::History { back: false } => {
                            self.history.redo(current);
                        }
                    }
                }
                if let Err(e) = kept {
                    self.error(&e.context("the solved cage does not fit the rebuilt picture"));
                }
                let stats = doc.rig().stats();
                let ms = doc.last_update_ms;
                let handles = doc.project().handles.len();
                let remeshed = self
                    .doc
                    .as_ref()
                    .is_none_or(|old| old.settings().density != doc.settings().density);
                let short = remeshed
                    .then(|| {
                        pipeline::density_shortfall(doc.rig().domain(), doc.settings().density)
                    })
                    .flatten();
                self.doc = Some(doc);
                if self.selected.is_some_and(|s| s >= handles) {
                    self.selected = None;
                }
                if let Some(doc) = &self.doc {
                    self.cage
                        .retain_valid(doc.cage().map_or(0, |c| c.rest.len()));
                }
                self.dirty = true;
                self.settings_draft = None;
                let what = if remeshed { "re-meshed" } else { "rebuilt" };
                self.info(format!(
                    "{}{what}: {} vertices, weights in {ms:.0} ms{}",
                    history.unwrap_or_default(),
                    stats.samples,
                    short.unwrap_or_default()
                ));
                self.sync_tool_after_history(was_lbc);
            }
            Outcome::Rebuilt {
                document: Err(e), ..
            } => {
                self.settings_draft = None;
                self.error(&e.context("cannot rebuild the weights"));
            }
            Outcome::Exported {
                path,
                result: Ok(()),
                ms,
            } => self.info(format!("exported {} in {ms:.0} ms", path.display())),
            Outcome::Exported { result: Err(e), .. } => self.error(&e),
            Outcome::CageSolved {
                key,
                solution: Ok(solution),
                then,
                ms,
            } => {
                let Some(doc) = &mut self.doc else { return };
                let report = solution.report.clone();
                let vertices = solution.domain.positions().len();
                if let Err(e) = doc.add_solution(key, solution) {
                    self.error(&e);
                    return;
                }
                self.info(format!(
                    "solved the cage in {:.1} s: {vertices} vertices inside, {} ADMM \
                     iterations{}; drag a vertex to warp",
                    ms / 1e3,
                    report.iterations,
                    if report.converged {
                        ""
                    } else {
                        " (stopped at the iteration cap, not converged)"
                    }
                ));
                if let Some(back) = then {
                    self.step_history(back);
                }
            }
            Outcome::CageSolved {
                solution: Err(e), ..
            } => self.error(&e.context("cannot solve the cage")),
        }
    }

    /// Asks for a file for `action` — with the desktop's dialog where there is one,
    /// else with the built-in one — and acts on it when chosen.
    pub fn ask_file(&mut self, action: FileAction) {
        if self.file_dialog.is_some() {
            return;
        }
        let suggested = match action {
            FileAction::SaveProject => self.suggested_name("json"),
            FileAction::ExportPng => self.suggested_name("warped.png"),
            FileAction::OpenImage | FileAction::OpenProject => String::new(),
        };
        if !self.builtin_dialogs {
            match self.dialogs.ask(action, &suggested) {
                Answer::Chosen(path) => return self.file_chosen(action, path),
                Answer::Cancelled => return,
                Answer::Unavailable => {
                    self.builtin_dialogs = true;
                    self.info("the desktop offers no file dialog here: using the built-in one");
                }
            }
        }
        let folder = self.working_folder();
        self.file_dialog = Some(BuiltinDialog::open(action, &folder, &suggested));
    }

    /// Whether the built-in file dialog is open.
    pub fn file_dialog_open(&self) -> bool {
        self.file_dialog.is_some()
    }

    /// Shows the built-in file dialog, if open, and acts on its answer.
    pub(crate) fn file_dialog_ui(&mut self, ctx: &egui::Context) {
        let Some(dialog) = &mut self.file_dialog else {
            return;
        };
        let action = dialog.action;
        match dialog.show(ctx) {
            Shown::Open => {}
            Shown::Cancelled => self.file_dialog = None,
            Shown::Chosen(path) => {
                self.file_dialog = None;
                if action.writes() && path.exists() {
                    // The desktop's dialogs ask before replacing a file; so does this one.
                    self.pending = Some(Pending::Replace(action, path));
                } else {
                    self.file_chosen(action, path);
                }
            }
        }
    }

    /// Acts on a file the user chose for `action`.
    pub(crate) fn file_chosen(&mut self, action: FileAction, path: PathBuf) {
        match action {
            FileAction::OpenImage | FileAction::OpenProject => self.request_open(path),
            FileAction::SaveProject => self.save_to(&path),
            FileAction::ExportPng => self.export_in_background(path),
        }
    }

    /// The folder dialogs start in: the project's or the picture's, else the current one.
    fn working_folder(&self) -> PathBuf {
        let from_doc = self.doc.as_ref().and_then(|d| {
            d.project_path
                .as_deref()
                .or(d.image_path.as_deref())
                .and_then(Path::parent)
                .filter(|p| !p.as_os_str().is_empty())
                .map(Path::to_path_buf)
        });
        from_doc
            .or_else(|| self.default_folder.clone())
            .or_else(|| std::env::current_dir().ok())
            .unwrap_or_else(|| PathBuf::from("."))
    }

    /// Saves the project where it was last saved, or asks where.
    pub fn save(&mut self) {
        match self.doc.as_ref().and_then(|d| d.project_path.clone()) {
            Some(path) => self.save_to(&path),
            None => self.ask_file(FileAction::SaveProject),
        }
    }

    /// Asks where to save the project, then saves it.
    pub fn save_as(&mut self) {
        self.ask_file(FileAction::SaveProject);
    }

    /// Writes the project to `path` atomically (a failure leaves any old file intact).
    pub fn save_to(&mut self, path: &Path) {
        let Some(doc) = &mut self.doc else { return };
        let project = doc.project_for_saving(Some(path));
        match render::write_atomic(path, project.to_json().as_bytes()) {
            Ok(()) => {
                doc.project_path = Some(path.to_path_buf());
                self.dirty = false;
                self.info(format!("saved {}", path.display()));
            }
            Err(e) => self.error(&anyhow::Error::from(e)),
        }
    }

    /// Asks where to export, then writes the warped PNG.
    pub fn export(&mut self) {
        self.ask_file(FileAction::ExportPng);
    }

    /// Writes the warped picture at full resolution to `path` atomically, now: the
    /// same pixels as `c2warp render` of the saved project.
    pub fn export_to(&mut self, path: &Path) {
        let Some(work) = self.export_work(path.to_path_buf(), CancelFlag::default()) else {
            return;
        };
        self.finish(work());
    }

    /// As [`EditorApp::export_to`], on a worker thread (the editor shows progress).
    pub fn export_in_background(&mut self, path: PathBuf) {
        let cancel = CancelFlag::default();
        let Some(work) = self.export_work(path.clone(), cancel.clone()) else {
            return;
        };
        self.start_job(format!("Exporting {}", file_name(&path)), cancel, work);
    }

    /// The export of the current document to `path`, ready to run anywhere; it writes
    /// nothing once `cancel` is set.
    fn export_work(
        &self,
        path: PathBuf,
        cancel: CancelFlag,
    ) -> Option<impl FnOnce() -> Outcome + Send + 'static> {
        let doc = self.doc.as_ref()?;
        let project = doc.project_for_saving(None);
        let image = doc.image.clone();
        let deep = doc.deep.clone();
        let cage = CageKey::of(&project)
            .filter(|_| project.method == Method::Lbc)
            .map(|key| (doc.solution_for(&key).cloned(), key, doc.cage_pose()));
        Some(move || {
            let clock = Instant::now();
            let result = (|| -> Result<()> {
                let warper = match cage {
                    // The cage's coordinates already solved for it (else solved here).
                    Some((solution, key, pose)) => {
                        let solution = match solution {
                            Some(solution) => solution,
                            None => crate::document::solve_cage(&key, &mut |_| !cancel.is_set())?,
                        };
                        let deformer = pipeline::cage::CageDeformer::new(solution, pose)?;
                        pipeline::Warper::in_mesh_order(Box::new(deformer), project.canvas)
                    }
                    None => pipeline::prepare_warper(&image, &project, None, &())?,
                };
                // A 16-bit picture exports with 16 bits, as `c2warp render` does.
                let warped = match &deep {
                    Some(deep) => pipeline::warp_picture(deep, &warper)?,
                    None => render::Picture::Rgba8(pipeline::warp(&image, &warper)?),
                };
                if cancel.is_set() {
                    anyhow::bail!("cancelled");
                }
                render::save_png_atomic(&path, &warped)?;
                Ok(())
            })()
            .with_context(|| format!("cannot export {}", path.display()));
            Outcome::Exported {
                path,
                result,
                ms: clock.elapsed().as_secs_f64() * 1e3,
            }
        })
    }

    fn suggested_name(&self, extension: &str) -> String {
        let stem = self
            .doc
            .as_ref()
            .and_then(|d| d.image_path.as_ref())
            .and_then(|p| p.file_stem())
            .map_or_else(|| "lizard".to_owned(), |s| s.to_string_lossy().into_owned());
        if extension.contains('.') {
            format!("{stem}-{extension}")
        } else {
            format!("{stem}.{extension}")
        }
    }

    /// The canvas as the GPU draws it (no overlays), one image pixel to one output
    /// pixel, in the frame an export has (the picture's, or grown to fit the warp), on
    /// `gpu` (any adapter): to compare the view with an export.
    ///
    /// # Errors
    /// No picture open, a grown canvas too large, or a GPU failure.
    pub fn view_offscreen(&mut self, gpu: &render::GpuContext) -> Result<image::RgbaImage> {
        let Some(doc) = &mut self.doc else {
            anyhow::bail!("no picture is open");
        };
        let (w, h) = doc.image.dimensions();
        let canvas = doc.project().canvas;
        let lbc = doc.method() == Method::Lbc;
        let deformed: Vec<glam::Vec2> = match doc.cage_deformed() {
            Some(cage) if lbc => cage.iter().map(|p| p.as_vec2()).collect(),
            _ => doc.deformed().iter().map(|p| p.as_vec2()).collect(),
        };
        let frame = pipeline::Frame::new(w, h, &deformed, canvas)?;
        self.update_gpu_frame();
        Ok(self.gpu.frame.draw_offscreen(gpu, frame)?)
    }

    /// Brings the GPU frame up to date with the document as the view shows it (see
    /// [`FrameBuilder::update`]); the canvas calls it every frame.
    pub fn update_gpu_frame(&mut self) {
        let cage_view = self.cage_view();
        let view = View {
            cage_view,
            warping: self.cage_warping(),
            shown: if cage_view {
                self.cage.focus()
            } else {
                self.selected
            },
            show: self.show,
        };
        if let Some(doc) = &self.doc {
            self.gpu.update(doc, &view);
        }
    }
}

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
        let Some(doc) = &mut self.doc else { return };
        if let Err(e) = doc.restore(project) {
            self.error(&e);
        }
    }

    fn record(&mut self, before: Project) {
        if let Some(doc) = &self.doc
            && doc.project() != &without_virtuals(&before)
        {
            self.history.push(before);
            self.dirty = true;
        }
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

    /// The triangles the painted-rigidity overlay drew last (their corners).
    pub fn painted_triangles(&self) -> Vec<[u32; 3]> {
        self.brush.painted_triangles()
    }
}

/// A path's file name, for messages.
fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// The re-mesh of `doc`'s picture for `project` (with its virtual handles, so a step
/// through the history gets exactly that state's weights), ready to run anywhere.
fn remesh(
    doc: &Document,
    project: project::Project,
    cause: Rebuild,
) -> impl FnOnce() -> Outcome + Send + 'static {
    let image = doc.image.clone();
    let deep = doc.deep.clone();
    let image_path = doc.image_path.clone();
    move || Outcome::Rebuilt {
        cause,
        document: Document::with_image(image, image_path, project).map(|mut d| {
            d.deep = deep;
            d
        }),
    }
}

/// Opens a picture or (for `.json`) a project; an LBC project's cage is solved (a cage
/// that cannot be is left unsolved, for the user to fix).
fn open_outcome(path: PathBuf, cancel: &CancelFlag, progress: &SolveProgress) -> Outcome {
    let is_project = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"));
    let document = if is_project {
        Document::open_project(&path).map(|mut doc| {
            let solvable = CageKey::of(doc.project()).is_some_and(|k| k.problem().is_none());
            if doc.method() == Method::Lbc && solvable {
                // Failing (cancelled) leaves the cage unsolved.
                let _ = doc.solve_cage(&mut |step| {
                    progress.set(*step);
                    !cancel.is_set()
                });
            }
            doc
        })
    } else {
        Document::open_image(&path)
    };
    Outcome::Opened {
        path,
        is_project,
        document,
    }
}

/// `project` without its virtual handles (what [`Document::project`] holds).
pub(crate) fn without_virtuals(project: &project::Project) -> project::Project {
    project::Project {
        virtual_handles: Vec::new(),
        virtual_placed_for: Vec::new(),
        ..project.clone()
    }
}

/// Sets each point handle's rotation to the one that best turns the directions to its
/// neighbours (all other handles, nearer ones weighing more) from rest to now: the
/// pseudo-edge heuristic of bounded biharmonic weights.
pub(crate) fn auto_rotate(handles: &mut [HandleSpec]) {
    let centres: Vec<(DVec2, DVec2)> = handles
        .iter()
        .map(|h| match *h {
            HandleSpec::Point { rest, .. } => {
                let now = posed(h)[0];
                (DVec2::from(rest), now)
            }
            HandleSpec::Bar { rest, .. } => {
                let [a, b] = posed(h);
                (
                    (DVec2::from(rest[0]) + DVec2::from(rest[1])) * 0.5,
                    (a + b) * 0.5,
                )
            }
        })
        .collect();
    for (i, h) in handles.iter_mut().enumerate() {
        let HandleSpec::Point { rotate, .. } = h else {
            continue;
        };
        let (mut dot, mut cross) = (0.0, 0.0);
        for (j, &(rest_j, now_j)) in centres.iter().enumerate() {
            if i == j {
                continue;
            }
            let r = rest_j - centres[i].0;
            let c = now_j - centres[i].1;
            let w = 1.0 / r.length_squared().max(1e-9);
            dot += w * r.dot(c);
            cross += w * r.perp_dot(c);
        }
        if dot != 0.0 || cross != 0.0 {
            *rotate = cross.atan2(dot);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(rest: [f64; 2], translate: [f64; 2]) -> HandleSpec {
        HandleSpec::Point {
            rest,
            translate,
            rotate: 0.0,
            scale: 1.0,
            depth: 0,
        }
    }

    #[test]
    fn auto_rotation_follows_a_turn_of_the_neighbours() {
        // Three handles turned by 90° about the first: the first turns by 90°.
        let mut handles = vec![
            point([0.0, 0.0], [0.0, 0.0]),
            point([10.0, 0.0], [-10.0, 10.0]),
            point([0.0, 10.0], [-10.0, -10.0]),
        ];
        auto_rotate(&mut handles);
        let HandleSpec::Point { rotate, .. } = handles[0] else {
            unreachable!()
        };
        assert!(
            (rotate - std::f64::consts::FRAC_PI_2).abs() < 1e-9,
            "{rotate}"
        );
        // A pure translation turns nothing.
        let mut handles = vec![
            point([0.0, 0.0], [5.0, 5.0]),
            point([10.0, 0.0], [5.0, 5.0]),
        ];
        auto_rotate(&mut handles);
        assert!(
            handles
                .iter()
                .all(|h| matches!(h, HandleSpec::Point { rotate, .. } if rotate.abs() < 1e-12))
        );
    }
}
