//! The canvas tools' one interface. A tool owns its state (a stroke under way, a
//! cache of what it draws) and sees the editor only through [`Host`]: the document,
//! the view, the one edit path, and the status line. So a tool needs nothing of the
//! app's other state, and the app holds its tools without the tools knowing the app.

use egui::{Painter, Pos2, Response, Ui};

use crate::document::{Document, Edit};
use crate::show::Show;
use crate::viewport::Viewport;

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
    /// Applies `edit` as every edit is applied (one undo step, the rebuild it needs, a
    /// message if it is refused); whether it was applied.
    fn edit(&mut self, edit: Edit) -> bool;
    /// A line in the status bar.
    fn info(&mut self, text: &str);
    /// The GPU mesh's version: new for every mesh of every document, so it keys what
    /// a tool caches about the mesh.
    fn mesh_version(&self) -> u64;
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
    /// Drops the gesture under way, if any (Escape, another tool, a new document).
    fn cancel(&mut self);
}
