//! The canvas tools' one interface. A tool owns its state (a stroke under way, a
//! cache of what it draws) and sees the editor only through [`Host`]: the document,
//! the view and its overlays, the one edit path (with a drag's preview and the undo
//! step that ends it), the worker's jobs, and the status line. So a tool needs nothing
//! of the app's other state, and the app holds its tools without the tools knowing
//! the app.

use egui::{Context, Painter, Pos2, Response, Ui};
use project::Project;

use crate::document::{CageKey, Document, Edit};
use crate::show::Show;
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
    /// Draw cuts that separate the shape (`CutTool`); Alt-click removes one.
    Cut,
    /// Draw, adjust, solve and pose an LBC cage (the cage tool, `CageTool`).
    Cage,
    /// Spatial keyframing: place key poses at markers, drag the control cursor to
    /// blend them (`PerformTool`).
    Perform,
}

/// What a tool may use of the editor.
pub(crate) trait Host {
    /// The open document, if any.
    fn document(&self) -> Option<&Document>;
    /// The open document, for its caches (deformed positions); it changes only through
    /// [`Host::edit`].
    fn document_mut(&mut self) -> Option<&mut Document>;
    /// Pan and zoom: picture pixels to screen points and back.
    fn viewport(&self) -> &Viewport;
    /// Which overlays are on.
    fn shows(&self) -> Show;
    /// The overlay switches, to turn them on or off.
    fn shows_mut(&mut self) -> &mut Show;
    /// Applies `edit` as every edit is applied (one undo step, the rebuild it needs, a
    /// message if it is refused); whether it was applied. The host ends the gestures
    /// it holds first; a tool, lent out while it runs, ends its own before it calls
    /// this.
    fn edit(&mut self, edit: Edit) -> bool;
    /// Whether a job runs on the worker (opening, re-meshing, solving): until it is
    /// done, [`Host::edit`] refuses edits.
    fn busy(&self) -> bool;
    /// Shows `project` as the document while a gesture (a drag) is under way, without
    /// an undo step: the gesture makes one when it ends, with [`Host::record`]. A
    /// project the document cannot take is refused in the status bar.
    fn preview(&mut self, project: Project);
    /// Ends a gesture that began on `before` (the document's
    /// [`Document::snapshot`] then): one undo step back to it, if the document has
    /// changed since.
    fn record(&mut self, before: Project);
    /// Solves the coordinates of the cage of `key` on the worker, showing the solve's
    /// progress (Escape cancels); the document takes them when they are in. A cage
    /// that cannot be solved, or a job already running, is refused in the status bar.
    fn solve_cage(&mut self, key: CageKey);
    /// Whether the drag under way pans the view (a tool then leaves it alone).
    fn panning(&self) -> bool;
    /// Makes the drag just started pan the view.
    fn pan(&mut self);
    /// A line in the status bar.
    fn info(&mut self, text: &str);
    /// A line in the status bar, in red: why something was refused or failed.
    fn error(&mut self, error: &anyhow::Error);
    /// The GPU mesh's version: new for every mesh of every document, so it keys what
    /// a tool caches about the mesh.
    fn mesh_version(&self) -> u64;
    /// The active tool (the handle tools are one [`CanvasTool`] that acts as it says).
    fn tool(&self) -> Tool;
    /// The selected handle (its panel section, its heat map, what Delete removes).
    fn selected(&self) -> Option<usize>;
    /// Selects handle `index`, or none.
    fn select(&mut self, index: Option<usize>);
    /// Whether point handles turn with their neighbours' motion while one is dragged.
    fn auto_rotate(&self) -> bool;
    /// The edges of the C² weights' dual graph (rig node pairs), as the GPU frame last
    /// found them: found only while the dual graph is shown.
    fn dual_graph(&self) -> &[(u32, u32)];
    /// Whether a take is being recorded: a drag then follows every pointer event of
    /// the frame ([`drag_path`]), each at its own time, so the take has the hand's path
    /// and timing however slowly the editor draws.
    fn taking(&self) -> bool;
    /// The time (seconds, on the input's clock) of the pointer event the next
    /// [`Host::preview`] shows: a take samples the pose at it.
    fn set_pointer_time(&mut self, time: f64);
}

/// Where a drag's pointer went this frame, each place with its time on the input's
/// clock: with a take being recorded ([`Host::taking`]), every pointer move of the
/// frame, their times spread evenly over the time since the last frame (events carry
/// none of their own); else the latest place alone, at the frame's time.
pub(crate) fn drag_path(host: &dyn Host, ui: &Ui, latest: Pos2) -> Vec<(Pos2, f64)> {
    let (now, dt, moves) = ui.input(|i| {
        let moves: Vec<Pos2> = i
            .events
            .iter()
            .filter_map(|e| match e {
                egui::Event::PointerMoved(p) => Some(*p),
                _ => None,
            })
            .collect();
        (i.time, f64::from(i.unstable_dt), moves)
    });
    if !host.taking() || moves.len() < 2 {
        return vec![(latest, now)];
    }
    let n = moves.len() as f64;
    let mut path: Vec<(Pos2, f64)> = moves
        .into_iter()
        .enumerate()
        .map(|(k, p)| (p, now - dt + dt * (k + 1) as f64 / n))
        .collect();
    if let Some(last) = path.last_mut() {
        *last = (latest, now);
    }
    path
}

/// A tool of the canvas.
pub(crate) trait CanvasTool {
    /// This frame's pointer input on the canvas (`response`), while the tool is active.
    fn input(&mut self, host: &mut dyn Host, ui: &Ui, response: &Response);
    /// Paints over the picture: what the tool shows, and under `pointer` (screen
    /// points, when it hovers the canvas) its cursor; `active` when it is the tool in
    /// use.
    fn paint(
        &mut self,
        host: &mut dyn Host,
        painter: &Painter,
        pointer: Option<Pos2>,
        active: bool,
    );
    /// The tool's part of the side panel.
    fn panel(&mut self, host: &mut dyn Host, ui: &mut Ui);
    /// The tool's keyboard shortcuts, while it is active and the keys are the
    /// editor's: called before the editor's own, so a key the tool consumes does
    /// nothing else. None by default.
    fn keys(&mut self, host: &mut dyn Host, ctx: &Context) {
        let _ = (host, ctx);
    }
    /// Drops the gesture under way, if any (Escape, another tool, a new document).
    fn cancel(&mut self);
}
