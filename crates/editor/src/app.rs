//! The editor application: the document, its undo history, the view and tool state,
//! and the one place where edits are applied ([`EditorApp::edit`]).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context as _, Result};
use glam::DVec2;
use project::Project;

use crate::brush::Brush;
use crate::cage::CageTool;
use crate::dialogs::{Answer, BuiltinDialog, Dialogs, FileAction, NativeDialogs, Shown};
use crate::document::{CageKey, Document, Edit};
use crate::gpu_frame::{FrameBuilder, View};
use crate::handles::HandleTool;
use crate::history::History;
use crate::jobs::{CancelFlag, Job, Outcome, Rebuild, SolveProgress};
use crate::onion::Onion;
use crate::perform::PerformTool;
use crate::scene::SceneResources;
use crate::show::Show;
use crate::timeline::Timeline;
pub use crate::tool::Tool;
use crate::tool::{CanvasTool, Host};
use crate::viewport::Viewport;

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
    /// Open this picture or project, or these pictures as the layers of one.
    Open(Vec<PathBuf>),
    /// Close the window.
    Close,
    /// Write over this existing file (chosen in the built-in dialog).
    Replace(FileAction, PathBuf),
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
    /// The window's size last frame: a change of it (a resize) is told apart from the
    /// panels around the canvas changing.
    pub(crate) window_size: Option<egui::Vec2>,
    /// Frames left in which a fresh fit follows the panels' first layout.
    pub(crate) fit_settling: u8,
    /// The active tool.
    pub tool: Tool,
    /// The selected handle.
    pub selected: Option<usize>,
    /// The part (a layer's index) selected in the Layers panel: outlined on the canvas.
    pub selected_part: Option<usize>,
    /// The handle tools: a drag or a bar under way, the right-click menu's handle.
    pub(crate) handles: HandleTool,
    /// The drag under way pans the view.
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
    /// What the unsaved-changes question was about, waiting for the save it asked for
    /// (a project never saved first asks where).
    pub(crate) after_save: Option<Pending>,
    /// Whether this document was told what MLS does on a cut-out.
    pub(crate) mls_warned: bool,
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
    /// The cut tool: the stroke under way.
    pub cut: crate::cut::CutTool,
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
    /// The timeline: the time shown, playback, recording.
    pub timeline: Timeline,
    /// The perform tool: pose markers and the control cursor (spatial keyframing).
    pub(crate) perform: PerformTool,
    /// Space was held for a pan since it went down (its release then does not play).
    pub(crate) space_panned: bool,
    /// The onion skin's ghosts.
    pub(crate) onion: Onion,
    /// The animation export window, while open: what it asks.
    pub animation_export: Option<AnimationExport>,
}

mod animate;
mod animation_export;

pub use animation_export::AnimationExport;
mod files;
mod host;
mod work;

impl EditorApp {
    /// The editor on `path` (a picture, or a `.json` project), or on the built-in
    /// picture. Sets up the GPU resources when eframe runs on wgpu.
    pub fn new(cc: &eframe::CreationContext<'_>, paths: &[PathBuf]) -> Self {
        let has_gpu = if let Some(state) = &cc.wgpu_render_state {
            let resources = SceneResources::new(&state.device, &state.queue, state.target_format);
            state.renderer.write().callback_resources.insert(resources);
            true
        } else {
            false
        };
        let mut app = Self::headless(has_gpu);
        app.wake = Some(cc.egui_ctx.clone());
        if !paths.is_empty() {
            app.open_all_in_background(paths.to_vec());
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
            window_size: None,
            fit_settling: 0,
            tool: Tool::Puppet,
            selected: None,
            selected_part: None,
            handles: HandleTool::default(),
            panning: false,
            show: Show::default(),
            hover_readout: None,
            auto_rotate: false,
            log: message.iter().cloned().collect(),
            message,
            log_open: false,
            pending: None,
            after_save: None,
            mls_warned: false,
            allow_close: false,
            help_open: false,
            dialogs: Box::new(NativeDialogs::new()),
            large_mesh: 100_000,
            builtin_dialogs: false,
            file_dialog: None,
            brush: Brush::default(),
            cut: crate::cut::CutTool::default(),
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
            timeline: Timeline::default(),
            perform: PerformTool::default(),
            space_panned: false,
            onion: Onion::default(),
            animation_export: None,
        }
    }

    /// Moves handle `index` `by` steps forward in the overlap order (negative:
    /// backward): where the warped picture overlaps itself, the part nearest the
    /// handle of greater depth is drawn in front. One undo step.
    pub fn change_depth(&mut self, index: usize, by: i32) {
        self.with_handles(|handles, host| handles.change_depth(host, index, by));
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
            if self.selected.is_some() {
                anyhow::bail!("a selection or drag without a document");
            }
            return self.handles.sanity_check(None, self.tool);
        };
        doc.sanity_check()?;
        let handles = &doc.project().handles;
        if let Some(s) = self.selected
            && s >= handles.len()
        {
            anyhow::bail!("handle {s} is selected, but there are {}", handles.len());
        }
        self.handles.sanity_check(Some(doc), self.tool)?;
        self.cage_sanity_check(doc)?;
        self.timeline_sanity_check(doc)?;
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
        // Under LBC the cage moves the picture: its tool, or the perform tool's markers.
        if let Some(why) = self.set(doc.controls()).refusal(self.tool) {
            anyhow::bail!("the {:?} tool is in use, but {why}", self.tool);
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
        // Every action replaces the message (what this one says, if anything, follows).
        self.message = None;
        if let (Edit::Settings(settings), Some(doc)) = (&edit, &self.doc) {
            if settings.density != doc.settings().density {
                self.rebuild_in_background(*settings);
                return true;
            }
            if *settings != doc.settings() {
                // A rebuild can take seconds (a large mesh, a fixed boundary's many
                // nodes): on the worker, so the window keeps answering.
                let copy = doc.clone();
                self.apply_on_worker("Re-weighting".to_owned(), copy, edit);
                return true;
            }
        }
        // Setting a method up on the mesh (ARAP's factorisation, MLS's fits), or
        // repainting the rigidity a method reads, takes a noticeable time on a large
        // mesh: on the worker too.
        let heavy = match &edit {
            Edit::Method(method) => method.sets_up_on_the_mesh(),
            // A cut re-meshes the picture; parts are meshed and set up each on its own.
            Edit::Cuts(_) | Edit::Parts(_) => true,
            Edit::Rigidity(_) => self
                .doc
                .as_ref()
                .is_some_and(|d| d.method().reads_rigidity()),
            _ => false,
        };
        if heavy
            && let Some(doc) = &self.doc
            && doc.mesh().len() > self.large_mesh
        {
            let label = match edit {
                Edit::Method(method) => format!("Setting up {}", method.label()),
                Edit::Cuts(_) => "Cutting the mesh".to_owned(),
                _ => "Repainting rigidity".to_owned(),
            };
            let copy = doc.clone();
            self.apply_on_worker(label, copy, edit);
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
        let poses = matches!(edit, Edit::Pose(..) | Edit::ResetPose | Edit::CagePose(_));
        match doc.apply(edit) {
            Ok(()) => {
                if poses {
                    // With keys, a pose changed is keyed at the time shown (this step).
                    self.autokey(&before);
                }
                let Some(doc) = &self.doc else { return false };
                if doc.project() != &without_virtuals(&before) {
                    let label = crate::history::describe_change(&before, doc.project());
                    self.history.push(before, label);
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
                if !poses {
                    // A handle added takes the keys' fitted pose at the time shown.
                    self.show_current_time();
                }
                true
            }
            Err(e) => {
                self.error(&e);
                false
            }
        }
    }

    /// Applies `edit` to `copy` (the open document, cloned) on the worker, labelled
    /// `label`; the history moves when the result is in.
    fn apply_on_worker(&mut self, label: String, mut copy: Document, edit: Edit) {
        let before = copy.snapshot();
        self.start_job(label, CancelFlag::default(), move || {
            let document = copy.apply(edit).map(|()| copy);
            Outcome::Rebuilt {
                cause: Rebuild::Edit {
                    before: Box::new(before),
                },
                document,
            }
        });
    }

    /// Adds a point handle under `at` (image pixels, current pose): its rest position is
    /// the point of the picture shown there, and it starts with the rotation and scale
    /// the pose has around it ([`Document::local_pose`]), so the warp jumps as little as
    /// the method allows.
    pub fn add_point(&mut self, at: DVec2) {
        self.with_handles(|handles, host| handles.add_point(host, at));
    }

    /// Adds a bar from `a` to `b` (image pixels, current pose).
    pub fn add_bar(&mut self, a: DVec2, b: DVec2) {
        self.with_handles(|handles, host| handles.add_bar(host, a, b));
    }

    /// Deletes the selected handle.
    pub fn delete_selected(&mut self) {
        self.with_handles(|handles, host| handles.delete_selected(host));
    }

    /// Ends whatever pointer gesture is in progress — a handle drag (one undo step if
    /// it changed anything), a bar being drawn, a cage drag — because the document is
    /// about to change under it.
    pub(crate) fn end_gesture(&mut self) {
        self.with_handles(|handles, host| handles.finish_gesture(host));
        self.with_perform(|perform, host| perform.finish_gesture(host));
        self.end_key_drag();
        self.end_cage_gesture();
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
        if target.cage.as_ref().is_some_and(|c| c.pose.is_some())
            && let Some(key) = CageKey::in_use(target)
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
        if new_settings || (doc.mesh().len() > self.large_mesh && doc.rebuilds_for(target, true)) {
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
        let Some((target, what)) = taken else { return };
        let was = doc.controls();
        match doc.undo_to(target.clone()) {
            Ok(()) => {
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
                self.sync_tool_after_history(was);
                self.show_current_time();
                self.info(format!(
                    "{}: {what}",
                    if back { "undone" } else { "redone" }
                ));
            }
            Err(e) => {
                self.history.unpop(back, (target, what));
                self.error(&e);
            }
        }
    }

    /// The canvas as the GPU draws it (no overlays), one image pixel to one output
    /// pixel, in the frame an export has (the picture's, or grown to fit the warp), on
    /// `gpu` (any adapter): to compare the view with an export.
    ///
    /// # Errors
    /// No picture open, a grown canvas too large, or a GPU failure.
    pub fn view_offscreen(&mut self, gpu: &render::GpuContext) -> Result<image::RgbaImage> {
        let (in_hand, warping) = (self.in_hand(), self.cage_warping());
        let Some(doc) = &mut self.doc else {
            anyhow::bail!("no picture is open");
        };
        let (w, h) = doc.image.dimensions();
        let canvas = doc.project().canvas;
        // The frame of what the view draws (a cage's mesh, or the picture's or parts').
        let cage: Option<Vec<glam::Vec2>> = match doc.shown(in_hand, warping) {
            crate::document::Shown::Cage(Some(cage)) => {
                Some(cage.positions().iter().map(|p| p.as_vec2()).collect())
            }
            _ => None,
        };
        let deformed = cage.unwrap_or_else(|| doc.deformed().iter().map(|p| p.as_vec2()).collect());
        let frame = pipeline::Frame::new(w, h, &deformed, canvas)?;
        self.update_gpu_frame();
        Ok(self.gpu.frame.draw_offscreen(gpu, frame)?)
    }

    /// Brings the GPU frame up to date with the document as the view shows it (see
    /// [`FrameBuilder::update`]); the canvas calls it every frame.
    pub fn update_gpu_frame(&mut self) {
        let in_hand = self.in_hand();
        let controls = self.set(in_hand);
        let view = View {
            in_hand,
            uses_weights: controls.uses_weights(),
            warping: self.cage_warping(),
            shown: controls.heat_subject(self),
            show: self.show,
        };
        if let Some(doc) = &self.doc {
            self.gpu.update(doc, &view);
        }
    }
}

/// `project` without its virtual handles (what [`Document::project`] holds).
pub(crate) fn without_virtuals(project: &project::Project) -> project::Project {
    project::Project {
        virtual_handles: Vec::new(),
        virtual_placed_for: Vec::new(),
        virtual_copy: Vec::new(),
        ..project.clone()
    }
}
