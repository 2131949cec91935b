//! What moves the picture: handles (C², ARAP, MLS) or a cage (LBC), as
//! [`project::Method::controls`] names them. This is the one place the editor tells
//! the two apart:
//!
//! - [`EditorApp::controls`] is the set that moves the document's picture (its
//!   method's, [`Document::controls`]), and [`EditorApp::in_hand`] the set the view
//!   and the tools act on now: the document's, or the cage while the cage tool draws or
//!   adjusts one under a handle method.
//! - [`ControlSet`] is everything that differs between the two sets in the editor:
//!   the tools that may act, the panel section, the edit buttons, what is painted over
//!   the picture, the readout under the pointer, the heat map's subject, the status
//!   line and the overlays that apply. The handle tools ([`HandleTool`]) and the cage
//!   tool ([`CageTool`]) implement it, each in its own module;
//!   [`EditorApp::with_controls`] lends out the set in hand.
//! - What the GPU draws for the set in hand is the document's answer,
//!   [`Document::shown`] (the picture's mesh, the parts' or the cage's).
//!
//! Elsewhere the editor asks the set rather than naming it.

use egui::{Pos2, Ui};
use pipeline::{Controls, Method};

use crate::app::EditorApp;
use crate::cage::CageTool;
use crate::document::{Document, Edit};
use crate::handles::HandleTool;
use crate::show::Show;
use crate::tool::{CanvasTool, Host, Tool};

/// A field of the status bar: its text, and what hovering it tells.
pub(crate) type StatusField = (String, Option<String>);

/// One set of controls, as the editor's panels, canvas and status bar use it.
pub(crate) trait ControlSet: CanvasTool {
    /// The tools that may be used while these controls move the document's picture;
    /// the first is the one picked when they come into use.
    fn tools(&self) -> &'static [Tool];
    /// Why `tool` cannot be used while these controls move the picture (`None`: it
    /// can).
    fn refusal(&self, tool: Tool) -> Option<&'static str> {
        let _ = tool;
        None
    }
    /// Whether `tool` is these controls' own (their paint shows them as in use).
    fn owns(&self, tool: Tool) -> bool;
    /// The tools whose marks are painted beside these controls, in use or not
    /// (painted rigidity, cuts).
    fn companions(&self) -> &'static [Tool] {
        &[]
    }
    /// The edit buttons under the tools (delete, clear, reset the pose).
    fn edit_buttons(&mut self, host: &mut dyn Host, ui: &mut Ui);
    /// The control whose influence the heat map shows.
    fn heat_subject(&self, host: &dyn Host) -> Option<usize>;
    /// What the heat map's checkbox says it shows.
    fn heat_hint(&self) -> &'static str;
    /// The text beside the pointer at screen point `pointer`: the weights or the
    /// motion of the mesh vertex under it (`None`: nothing to say there).
    fn readout(&self, host: &mut dyn Host, pointer: Pos2) -> Option<String>;
    /// The status bar's account of these controls in `doc` (counts, times), as
    /// separate fields.
    fn status(&self, doc: &Document) -> Vec<StatusField>;
    /// Whether these controls have a panel beside the canvas, open with `show`'s
    /// overlays (the cage: its locality statistics).
    fn has_aside(&self, show: Show) -> bool {
        let _ = show;
        false
    }
    /// That panel's contents.
    fn aside(&self, host: &dyn Host, ui: &mut Ui) {
        let _ = (host, ui);
    }
    /// Whether the handles' C² weights apply: their parameters, cells, virtual
    /// handles, the dual graph, painted rigidity.
    fn uses_weights(&self) -> bool;
}

impl EditorApp {
    /// The controls that move the document's picture (handles, with no document).
    pub(crate) fn controls(&self) -> Controls {
        self.doc
            .as_ref()
            .map_or(Controls::Handles, Document::controls)
    }

    /// The controls the view and the tools act on now: the document's, or the cage
    /// while the cage tool is in use (a cage drawn, or the one kept, before LBC is
    /// chosen).
    pub(crate) fn in_hand(&self) -> Controls {
        if self.tool == Tool::Cage {
            Controls::Cage
        } else {
            self.controls()
        }
    }

    /// Runs `f` on the set of `controls` with the app as its host (lent out for the
    /// call).
    pub(crate) fn with_set<R>(
        &mut self,
        controls: Controls,
        f: impl FnOnce(&mut dyn ControlSet, &mut dyn Host) -> R,
    ) -> R {
        match controls {
            Controls::Handles => self.with_handles(|set, host| f(set, host)),
            Controls::Cage => self.with_cage(|set, host| f(set, host)),
        }
    }

    /// Runs `f` on the set in hand ([`EditorApp::in_hand`]).
    pub(crate) fn with_controls<R>(
        &mut self,
        f: impl FnOnce(&mut dyn ControlSet, &mut dyn Host) -> R,
    ) -> R {
        self.with_set(self.in_hand(), f)
    }

    /// The set of `controls`, to ask.
    pub(crate) fn set(&self, controls: Controls) -> &dyn ControlSet {
        match controls {
            Controls::Handles => &self.handles,
            Controls::Cage => &self.cage,
        }
    }

    /// Why `tool` cannot be used with the document's controls (`None`: it can).
    pub(crate) fn tool_refusal(&self, tool: Tool) -> Option<&'static str> {
        self.set(self.controls()).refusal(tool)
    }
}

impl EditorApp {
    /// Switches tools; a bar or a cage being drawn is dropped, a cage drag ends. The
    /// cage tool is LBC's: picking it with a cage kept in the project chooses LBC (one
    /// undo step); under LBC, the handle tools wait until C² or ARAP is chosen.
    pub fn set_tool(&mut self, tool: Tool) {
        if let Some(why) = self.tool_refusal(tool) {
            self.info(why);
            return;
        }
        if tool != Tool::Cage {
            self.with_cage(|cage, host| {
                cage.finish_gesture(host);
                cage.cancel();
            });
        }
        if self.tool == Tool::Perform && tool != Tool::Perform {
            // The control cursor previews poses; with keys, the timeline's pose is back.
            self.with_perform(|perform, host| perform.finish_gesture(host));
            self.show_current_time();
        }
        self.tool = tool;
        self.handles.cancel();
        if tool == Tool::Cage
            && self.controls() == Controls::Handles
            && let Some(doc) = &self.doc
        {
            if doc.cage().is_some() {
                if self.edit(Edit::Method(Method::for_controls(Controls::Cage))) {
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

    /// After any change that may have chosen other controls (an undo, an opened
    /// project): a tool they refuse gives way to their first (under LBC, the cage
    /// tool).
    pub(crate) fn sync_tool(&mut self) {
        if self.tool_refusal(self.tool).is_some() {
            self.with_handles(|handles, host| handles.finish_gesture(host));
            self.tool = self.set(self.controls()).tools()[0];
            self.brush.cancel();
        }
    }

    /// After a step through the history from a state moved by `was`: the tool the new
    /// state calls for. Into LBC, the cage tool; out of LBC with no cage being drawn,
    /// the cage tool has nothing left to act on, so the puppet tool.
    pub(crate) fn sync_tool_after_history(&mut self, was: Controls) {
        if was != self.controls() && self.tool == Tool::Cage && self.cage.draft().is_none() {
            self.end_cage_gesture();
            self.tool = Tool::Puppet;
        }
        self.sync_tool();
    }

    /// Chooses a warping method (one undo step). LBC without a cage starts the cage
    /// tool, to draw one; leaving LBC leaves the cage tool and keeps the cage.
    pub fn choose_method(&mut self, method: Method) {
        let Some(doc) = &self.doc else { return };
        let controls = method.controls();
        if method == doc.method() {
            // Drawing a cage for LBC, and back to the method already in use.
            if !self.set(controls).owns(self.tool) && self.tool == Tool::Cage {
                self.set_tool(Tool::Puppet);
                self.info(format!("{}: drawing the cage dropped", method.label()));
            }
            return;
        }
        if controls == Controls::Cage {
            // The cage is drawn, or the kept one chosen, by its tool.
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
            let cut_out = self.doc.as_ref().is_some_and(|d| !d.mesh().is_convex());
            if method == Method::Mls && cut_out && !self.mls_warned {
                // Once a document: the one surprise MLS has in store on a cut-out.
                self.mls_warned = true;
                self.info(
                    "MLS on a cut-out: its distances are straight lines, not paths inside \
                     the shape, so a pin moved far from a part it does not hold, across a \
                     gap, pulls a needle out of that part; pin the parts, or use ARAP or C² \
                     weights, which keep to the shape",
                );
            } else {
                self.info(format!("{}: {}", method.label(), method.about()));
            }
        }
    }
}

/// Every tool: under handles, each acts (the cage tool draws a cage, to switch to it).
const ALL_TOOLS: &[Tool] = &[
    Tool::Puppet,
    Tool::Select,
    Tool::AddPoint,
    Tool::AddBar,
    Tool::Rigidity,
    Tool::Cut,
    Tool::Cage,
    Tool::Perform,
];

/// The handle tools' own tools.
pub(crate) const HANDLE_TOOLS: &[Tool] =
    &[Tool::Puppet, Tool::Select, Tool::AddPoint, Tool::AddBar];

/// Under a cage: its tool, and the perform tool's markers.
const CAGE_TOOLS: &[Tool] = &[Tool::Cage, Tool::Perform];

impl ControlSet for HandleTool {
    fn tools(&self) -> &'static [Tool] {
        ALL_TOOLS
    }

    fn owns(&self, tool: Tool) -> bool {
        HANDLE_TOOLS.contains(&tool)
    }

    fn companions(&self) -> &'static [Tool] {
        &[Tool::Rigidity, Tool::Cut]
    }

    fn edit_buttons(&mut self, host: &mut dyn Host, ui: &mut Ui) {
        self.handle_buttons(host, ui);
    }

    fn heat_subject(&self, host: &dyn Host) -> Option<usize> {
        host.selected()
    }

    fn heat_hint(&self) -> &'static str {
        "The selected handle's weight, with isolines every 0.1"
    }

    fn readout(&self, host: &mut dyn Host, pointer: Pos2) -> Option<String> {
        self.weights_readout(host, pointer)
    }

    fn status(&self, doc: &Document) -> Vec<StatusField> {
        self.status_fields(doc)
    }

    fn uses_weights(&self) -> bool {
        true
    }
}

impl ControlSet for CageTool {
    fn tools(&self) -> &'static [Tool] {
        CAGE_TOOLS
    }

    fn refusal(&self, tool: Tool) -> Option<&'static str> {
        (!CAGE_TOOLS.contains(&tool)).then_some(
            "under LBC the cage moves the picture: choose C² weights or ARAP under Method \
             to work with handles (the cage stays in the project)",
        )
    }

    fn owns(&self, tool: Tool) -> bool {
        tool == Tool::Cage
    }

    fn edit_buttons(&mut self, host: &mut dyn Host, ui: &mut Ui) {
        self.cage_buttons(host, ui);
    }

    fn heat_subject(&self, host: &dyn Host) -> Option<usize> {
        self.focus().filter(|_| self.warping(host.document()))
    }

    fn heat_hint(&self) -> &'static str {
        "The selected cage vertex's coordinate, with isolines every 0.1"
    }

    fn readout(&self, host: &mut dyn Host, pointer: Pos2) -> Option<String> {
        self.coordinates_readout(host, pointer)
    }

    fn status(&self, doc: &Document) -> Vec<StatusField> {
        self.status_fields(doc)
    }

    fn has_aside(&self, show: Show) -> bool {
        show.locality
    }

    fn aside(&self, host: &dyn Host, ui: &mut Ui) {
        self.locality_panel(host, ui);
    }

    fn uses_weights(&self) -> bool {
        false
    }
}
