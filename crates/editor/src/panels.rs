//! The frame around the canvas: menu bar, side panel (tools, parameters, overlays),
//! status bar, keyboard shortcuts, the help window and the unsaved-changes question.

use std::time::Instant;

use egui::{Key, KeyboardShortcut, Modifiers, Ui};
use project::{Method, MetricChoice, Middle, Placement};

use crate::app::{EditorApp, Pending, Tool};
use crate::dialogs::FileAction;
use crate::document::Edit;
use crate::tool::CanvasTool;

/// Every shortcut, as the help window lists them.
pub const SHORTCUTS: &[(&str, &str)] = &[
    (
        "W",
        "Puppet tool: click the picture to add a handle, click a handle to select it",
    ),
    ("V", "Select tool: like Puppet, but a click only selects"),
    ("P", "Add point handle tool"),
    ("B", "Add bar handle tool (drag from end to end)"),
    (
        "R",
        "Rigidity brush (ARAP): drag to paint stiffness, Alt + drag to erase",
    ),
    (
        "X",
        "Cut tool: drag across where parts touch to separate them, Alt + click removes a cut",
    ),
    (
        "K",
        "Cage tool (LBC): click a polygon around the subject, adjust it, solve, pose it",
    ),
    (
        "Cage: click, Enter",
        "Add a vertex; click the first vertex, double-click or Enter closes the cage",
    ),
    (
        "Cage: Enter",
        "Solve the closed cage (Escape cancels the solve)",
    ),
    (
        "Cage: drag a vertex",
        "At rest: adjust the cage; solved: pose it (a selected group moves together)",
    ),
    (
        "Cage: drag empty canvas",
        "Select vertices in a box (Shift adds to the selection)",
    ),
    (
        "Cage: click an edge, Alt + click",
        "At rest: add a vertex there, remove the vertex",
    ),
    (
        "Cage: Backspace / Delete",
        "Remove the last vertex drawn, or the selected vertices at rest",
    ),
    (
        "Drag a handle",
        "Move it (a bar's end: turn and stretch the bar)",
    ),
    (
        "Alt + drag near a point, or drag the ring",
        "Rotate the handle (Alt shows its ring; a drag anywhere on or in it turns)",
    ),
    ("Shift + drag", "Scale the handle"),
    ("Alt + click a handle", "Delete it"),
    ("Drag empty canvas", "Pan (Puppet and Select tools)"),
    (
        "Y",
        "Perform tool: place pose markers, drag the control cursor to blend them",
    ),
    ("I", "Set a key: the pose shown, at the time shown"),
    ("Space (tap)", "Play or pause the keys"),
    (", / .", "Previous / next frame"),
    ("Shift + , / Shift + .", "Previous / next key"),
    ("Right click", "Handle menu: delete, reset pose"),
    ("Delete / Backspace", "Delete the selected handle"),
    ("Middle drag, Space + drag", "Pan"),
    ("Mouse wheel, pinch", "Zoom about the pointer"),
    ("F", "Fit the picture to the window"),
    ("M", "Show or hide the mesh"),
    ("H", "Show or hide the selected handle's weight (heat map)"),
    ("C", "Show or hide the Voronoi cells"),
    ("G", "Show or hide the dual graph"),
    (
        "N, Shift + N",
        "Select the next / previous handle (cage vertex)",
    ),
    ("Ctrl + Z", "Undo"),
    ("Ctrl + Shift + Z, Ctrl + Y", "Redo"),
    ("Ctrl + O", "Open an image"),
    ("Ctrl + Shift + O", "Open a project"),
    ("Ctrl + S", "Save the project"),
    ("Ctrl + Shift + S", "Save the project as"),
    ("Ctrl + E", "Export the warped PNG"),
    (
        "Escape",
        "Deselect; cancel a bar, a question or a running job",
    ),
    ("F1", "This window"),
];

mod timeline;
mod windows;

impl eframe::App for EditorApp {
    fn ui(&mut self, ui: &mut Ui, _frame: &mut eframe::Frame) {
        let clock = Instant::now();
        let ctx = ui.ctx().clone();
        self.poll_job();
        // An edit of a large mesh is drawn with its overlaps arranged from the frame
        // after it (automatic depth).
        if let Some(doc) = &mut self.doc {
            doc.arrange_deferred();
        }
        self.sync_tool();
        self.tick(&ctx);
        self.dropped_files(&ctx);
        let idle = !self.is_busy();
        if !idle {
            if ctx.input_mut(|i| i.consume_key(Modifiers::NONE, Key::Escape)) {
                self.cancel_job();
            }
            // Keep the elapsed time and the spinner moving, four times a second: more
            // often, drawing the window (in software, on a machine without a GPU) took
            // the cores a solve on the worker needs.
            ctx.request_repaint_after(std::time::Duration::from_millis(250));
        } else if self.pending.is_none() && self.file_dialog.is_none() {
            // A question or a dialog takes the keys: nothing acts on the document
            // behind it.
            self.shortcuts(&ctx);
        } else if self.pending.is_some()
            && ctx.input_mut(|i| i.consume_key(Modifiers::NONE, Key::Escape))
        {
            self.pending = None;
        }
        self.close_request(&ctx);
        egui::Panel::top("menu").show(ui, |ui| {
            ui.add_enabled_ui(idle, |ui| self.menu_bar(ui));
        });
        egui::Panel::bottom("status").show(ui, |ui| self.status_bar(ui));
        egui::Panel::left("tools")
            .resizable(false)
            .default_size(220.0)
            .show(ui, |ui| {
                ui.add_enabled_ui(idle, |ui| {
                    egui::ScrollArea::vertical().show(ui, |ui| self.side_panel(ui));
                });
            });
        // Beside the cage tool's view whenever it shows, so that solving does not
        // resize the canvas under the pointer.
        if self.set(self.in_hand()).has_aside(self.show) {
            egui::Panel::right("locality")
                .resizable(false)
                .default_size(300.0)
                .show(ui, |ui| {
                    egui::ScrollArea::vertical().show(ui, |ui| {
                        self.with_controls(|controls, host| controls.aside(host, ui));
                    });
                });
        }
        // Under the canvas only: the side panels keep their height.
        if self.doc.is_some() {
            egui::Panel::bottom("timeline").show(ui, |ui| {
                ui.add_enabled_ui(idle, |ui| self.timeline_ui(ui));
            });
        }
        egui::CentralPanel::default()
            .frame(egui::Frame::NONE)
            .show(ui, |ui| self.canvas_ui(ui));
        self.animation_export_window(&ctx);
        self.help_window(&ctx);
        self.log_window(&ctx);
        self.file_dialog_ui(&ctx);
        self.pending_modal(&ctx);
        // A save the unsaved-changes question asked for, done or given up (its dialog
        // cancelled, or the write failed): go on, or forget it.
        if self.after_save.is_some() && self.file_dialog.is_none() && self.pending.is_none() {
            if self.dirty {
                self.after_save = None;
            } else {
                self.continue_after_save(&ctx);
            }
        }
        self.frame_ms = clock.elapsed().as_secs_f64() * 1e3;
    }
}

impl EditorApp {
    fn dropped_files(&mut self, ctx: &egui::Context) {
        let dropped: Vec<_> = ctx.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_path_buf())
                .filter(|p| !p.as_os_str().is_empty())
                .collect()
        });
        let Some(path) = dropped.first().cloned() else {
            return;
        };
        let is_json = |p: &std::path::PathBuf| {
            p.extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("json"))
        };
        let several_pictures = dropped.len() > 1 && !dropped.iter().any(is_json);
        if dropped.len() > 1 && !several_pictures {
            self.info(format!(
                "{} files dropped, a project among them: opening the first, {}",
                dropped.len(),
                path.display()
            ));
        }
        if let Some((what, _)) = self.busy_with() {
            let what = what.to_owned();
            self.error(&anyhow::anyhow!(
                "{} was not opened: {what}… is still running (wait for it, or press \
                 Escape to cancel it, then drop the file again)",
                path.display()
            ));
        } else if self.pending.is_some() || self.file_dialog.is_some() {
            self.error(&anyhow::anyhow!(
                "{} was not opened: answer the open question or dialog first",
                path.display()
            ));
        } else if several_pictures {
            // Several pictures: the layers of one, in the order dropped.
            self.request_open_all(dropped);
        } else {
            self.request_open(path);
        }
    }

    fn close_request(&mut self, ctx: &egui::Context) {
        if ctx.input(|i| i.viewport().close_requested()) && self.dirty && !self.allow_close {
            ctx.send_viewport_cmd(egui::ViewportCommand::CancelClose);
            self.pending = Some(Pending::Close);
        }
    }

    fn shortcuts(&mut self, ctx: &egui::Context) {
        if ctx.egui_wants_keyboard_input() {
            return;
        }
        let ctrl = Modifiers::COMMAND;
        let ctrl_shift = Modifiers::COMMAND | Modifiers::SHIFT;
        let pressed = |modifiers, key| {
            ctx.input_mut(|i| i.consume_shortcut(&KeyboardShortcut::new(modifiers, key)))
        };
        // Escape closes the windows open over the canvas first (and does nothing else).
        let windows = self.help_open || self.log_open || self.animation_export.is_some();
        if windows && pressed(Modifiers::NONE, Key::Escape) {
            self.help_open = false;
            self.log_open = false;
            self.animation_export = None;
            return;
        }
        // Longer combinations first: Ctrl+Shift+Z must not read as Ctrl+Z.
        if pressed(ctrl_shift, Key::Z) || pressed(ctrl, Key::Y) {
            self.redo();
        } else if pressed(ctrl, Key::Z) {
            self.undo();
        }
        if pressed(ctrl_shift, Key::S) {
            self.save_as();
        } else if pressed(ctrl, Key::S) {
            self.save();
        }
        if pressed(ctrl_shift, Key::O) {
            self.ask_file(FileAction::OpenProject);
        } else if pressed(ctrl, Key::O) {
            self.ask_file(FileAction::OpenImage);
        }
        if pressed(ctrl, Key::E) {
            self.export();
        }
        if self.tool == Tool::Cage {
            self.with_cage(|cage, host| cage.keys(host, ctx));
        }
        let none = Modifiers::NONE;
        if pressed(none, Key::Delete) || pressed(none, Key::Backspace) {
            self.delete_selected();
        }
        if pressed(none, Key::W) {
            self.set_tool(Tool::Puppet);
        }
        if pressed(none, Key::V) {
            self.set_tool(Tool::Select);
        }
        if pressed(none, Key::P) {
            self.set_tool(Tool::AddPoint);
        }
        if pressed(none, Key::B) {
            self.set_tool(Tool::AddBar);
        }
        if pressed(none, Key::R) {
            self.set_tool(Tool::Rigidity);
        }
        if pressed(none, Key::X) {
            self.set_tool(Tool::Cut);
        }
        if pressed(none, Key::K) {
            self.set_tool(Tool::Cage);
        }
        if pressed(none, Key::Y) {
            self.set_tool(Tool::Perform);
        }
        if pressed(none, Key::I) {
            self.set_key();
        }
        if pressed(Modifiers::SHIFT, Key::Comma) {
            self.step_key(true);
        } else if pressed(none, Key::Comma) {
            self.step_frames(-1);
        }
        if pressed(Modifiers::SHIFT, Key::Period) {
            self.step_key(false);
        } else if pressed(none, Key::Period) {
            self.step_frames(1);
        }
        // Space: a tap plays or pauses; held, it pans with a drag.
        if ctx.input(|i| i.key_released(Key::Space)) {
            if !self.space_panned {
                self.toggle_play();
            }
            self.space_panned = false;
        }
        if pressed(none, Key::F) {
            self.needs_fit = true;
        }
        if pressed(none, Key::M) {
            self.show.mesh = !self.show.mesh;
        }
        if pressed(none, Key::H) {
            self.show.heat = !self.show.heat;
        }
        if pressed(none, Key::C) {
            self.show.cells = !self.show.cells;
        }
        if pressed(none, Key::G) {
            self.show.dual_graph = !self.show.dual_graph;
        }
        let count = self.doc.as_ref().map_or(0, |d| d.project().handles.len());
        if count > 0 {
            if pressed(Modifiers::SHIFT, Key::N) {
                self.selected = Some(self.selected.map_or(count - 1, |s| (s + count - 1) % count));
            } else if pressed(none, Key::N) {
                self.selected = Some(self.selected.map_or(0, |s| (s + 1) % count));
            }
        }
        if pressed(none, Key::F1) {
            self.help_open = !self.help_open;
        }
        if pressed(none, Key::Escape) {
            self.selected = None;
            self.handles.cancel();
            self.brush.cancel();
            self.pending = None;
        }
    }

    fn menu_bar(&mut self, ui: &mut Ui) {
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                if ui.button("Open image…").clicked() {
                    ui.close();
                    self.ask_file(FileAction::OpenImage);
                }
                if ui.button("Open project…").clicked() {
                    ui.close();
                    self.ask_file(FileAction::OpenProject);
                }
                ui.separator();
                if ui.button("Save project").clicked() {
                    ui.close();
                    self.save();
                }
                if ui.button("Save project as…").clicked() {
                    ui.close();
                    self.save_as();
                }
                if ui.button("Export PNG…").clicked() {
                    ui.close();
                    self.export();
                }
                if ui
                    .button("Export layers…")
                    .on_hover_text(
                        "Each layer of the picture warped on a layer of its own, as an \
                         OpenRaster file (Krita and GIMP open it)",
                    )
                    .clicked()
                {
                    ui.close();
                    self.export_layers();
                }
                if ui
                    .button("Export animation…")
                    .on_hover_text(
                        "The keys played as an animated PNG, WebP or GIF, or a PNG sequence, \
                         at full resolution",
                    )
                    .clicked()
                {
                    ui.close();
                    self.ask_animation_export();
                }
                if let Some(doc) = &self.doc {
                    let canvas = doc.project().canvas;
                    let mut grow = canvas == project::Canvas::Fit;
                    let changed = ui
                        .checkbox(&mut grow, "Grow the canvas to fit the warp")
                        .on_hover_text(
                            "Export (and c2warp render of the saved project) at a size that \
                             holds all of the warped picture, instead of cutting off what \
                             the warp moves beyond the picture's edge",
                        )
                        .changed();
                    if changed {
                        let canvas = if grow {
                            project::Canvas::Fit
                        } else {
                            project::Canvas::Keep
                        };
                        if self.edit(Edit::Canvas(canvas)) {
                            self.info(if grow {
                                "exports grow the canvas to hold the whole warped picture"
                            } else {
                                "exports keep the picture's size"
                            });
                        }
                    }
                }
                ui.separator();
                ui.checkbox(&mut self.builtin_dialogs, "Built-in file dialogs")
                    .on_hover_text(
                        "Choose files in the editor's own dialog instead of the desktop's \
                         (used anyway where the desktop has none)",
                    );
                ui.separator();
                if ui.button("Quit").clicked() {
                    ui.close();
                    ui.ctx().send_viewport_cmd(egui::ViewportCommand::Close);
                }
            });
            ui.menu_button("Edit", |ui| {
                self.history_buttons(ui);
                ui.separator();
                self.edit_buttons(ui);
            });
            ui.menu_button("View", |ui| {
                if ui.button("Fit to window").clicked() {
                    self.needs_fit = true;
                }
                ui.separator();
                self.overlay_toggles(ui);
            });
            ui.menu_button("Help", |ui| {
                if ui.button("Keyboard shortcuts").clicked() {
                    self.help_open = true;
                    ui.close();
                }
                if ui.button("Messages").clicked() {
                    self.log_open = true;
                    ui.close();
                }
            });
        });
    }

    fn history_buttons(&mut self, ui: &mut Ui) {
        let undo = egui::Button::new("Undo");
        if ui.add_enabled(self.history.can_undo(), undo).clicked() {
            self.undo();
        }
        let redo = egui::Button::new("Redo");
        if ui.add_enabled(self.history.can_redo(), redo).clicked() {
            self.redo();
        }
    }

    /// The edit buttons of the controls that move the picture.
    fn edit_buttons(&mut self, ui: &mut Ui) {
        self.with_set(self.controls(), |controls, host| {
            controls.edit_buttons(host, ui)
        });
    }

    /// The overlays' checkboxes; with the cage tool's view, the ones that apply to it.
    fn overlay_toggles(&mut self, ui: &mut Ui) {
        let controls = self.set(self.in_hand());
        let (weighted, heat_hint) = (controls.uses_weights(), controls.heat_hint());
        ui.checkbox(&mut self.show.mesh, "Show mesh");
        if weighted {
            // Virtual handles and their dual graph belong to the C² weights.
            let c2 = self
                .doc
                .as_ref()
                .is_none_or(|d| d.method().uses_virtual_handles());
            let c2_only = "The C² weights' own: other methods have no virtual handles";
            ui.add_enabled_ui(c2, |ui| {
                ui.checkbox(&mut self.show.virtual_handles, "Virtual handles")
                    .on_disabled_hover_text(c2_only);
            });
            ui.checkbox(&mut self.show.cells, "Voronoi cells")
                .on_hover_text("The C² cells, which also decide the overlap order");
            ui.add_enabled_ui(c2, |ui| {
                ui.checkbox(&mut self.show.dual_graph, "Dual graph")
                    .on_disabled_hover_text(c2_only);
            });
        }
        ui.checkbox(&mut self.show.heat, "Weight heat map")
            .on_hover_text(heat_hint);
        ui.checkbox(&mut self.show.folds, "Fold-overs");
        ui.checkbox(&mut self.show.overlaps, "Overlap regions")
            .on_hover_text(
                "Where the warped picture overlaps itself: the part drawn in front outlined in \
             yellow, the part behind in blue (automatic depth)",
            );
        ui.checkbox(&mut self.show.hover_weights, "Weights under cursor");
        if weighted {
            ui.checkbox(&mut self.show.rigidity, "Painted rigidity");
        }
    }

    fn side_panel(&mut self, ui: &mut Ui) {
        ui.heading("Tools");
        ui.horizontal_wrapped(|ui| {
            let mut tool = self.tool;
            let tools = [
                (
                    Tool::Puppet,
                    "Puppet",
                    "Click the picture to add a handle; drag a handle to move it; \
                     Alt-click a handle to delete it; drag empty canvas to pan",
                ),
                (
                    Tool::Select,
                    "Select",
                    "Like Puppet, but a click on the picture adds nothing",
                ),
                (Tool::AddPoint, "Add point", "Click to add a point handle"),
                (
                    Tool::AddBar,
                    "Add bar",
                    "Drag from one end of the bar to the other",
                ),
                (
                    Tool::Rigidity,
                    "Rigidity",
                    "Paint stiffness (ARAP): painted parts keep their shape; Alt-drag \
                     erases. One undo step per stroke",
                ),
                (
                    Tool::Cut,
                    "Cut",
                    "Cut (X): drag across where parts touch to separate them (C², ARAP); \
                     Alt-click a cut to remove it",
                ),
                (
                    Tool::Cage,
                    "Cage",
                    "LBC's cage (K): click a polygon around the subject, adjust it, \
                     solve it, then drag its vertices to warp what lies inside",
                ),
                (
                    Tool::Perform,
                    "Perform",
                    "Spatial keyframing (Y): place markers that hold poses, then drag the \
                     control cursor to blend them; with Record on, the drag becomes keys",
                ),
            ];
            for (t, label, hover) in tools {
                // Under LBC the cage moves the picture: handles wait for C² or ARAP.
                let refusal = self.tool_refusal(t);
                let button = egui::Button::selectable(tool == t, label);
                if ui
                    .add_enabled(refusal.is_none(), button)
                    .on_hover_text(hover)
                    .on_disabled_hover_text(refusal.unwrap_or_default())
                    .clicked()
                {
                    tool = t;
                }
            }
            if tool != self.tool {
                self.set_tool(tool);
            }
        });
        ui.horizontal_wrapped(|ui| self.edit_buttons(ui));
        ui.horizontal(|ui| {
            self.history_buttons(ui);
            if ui.button("Fit to window").clicked() {
                self.needs_fit = true;
            }
        });
        if self.tool == Tool::Rigidity {
            self.with_brush(|brush, host| brush.panel(host, ui));
        }
        if self.tool == Tool::Cut {
            self.with_cut(|cut, host| cut.panel(host, ui));
        }
        if self.tool == Tool::Perform {
            ui.separator();
            ui.heading("Perform");
            self.with_perform(|perform, host| perform.panel(host, ui));
            ui.separator();
        }
        ui.checkbox(&mut self.auto_rotate, "Auto-rotate points")
            .on_hover_text("Point handles turn with their neighbours' motion");
        // The section of the controls in hand (the selected handle, or the cage)
        // right under the tools, so it shows whatever else the panel holds.
        self.with_controls(|controls, host| controls.panel(host, ui));
        // A cage begun from the panel (New cage, under the perform tool) is drawn
        // with the cage tool.
        if self.cage.draft().is_some() && self.tool != Tool::Cage {
            self.set_tool(Tool::Cage);
        }
        ui.separator();
        ui.heading("Method");
        self.method_choice(ui);
        ui.separator();
        if self
            .doc
            .as_ref()
            .and_then(|d| d.layers.as_ref())
            .is_some_and(|l| l.layers.len() > 1)
        {
            ui.heading("Layers");
            self.layers_panel(ui);
            ui.separator();
        }
        if self.doc.as_ref().is_some_and(|d| d.method() == Method::Mls) {
            ui.heading("MLS");
            self.mls_panel(ui);
            ui.separator();
        }
        if self.set(self.controls()).uses_weights() {
            ui.heading("Weights");
            self.parameters(ui);
            ui.separator();
        }
        ui.heading("Show");
        self.overlay_toggles(ui);
    }

    /// A layered picture's layers: drawn as one picture or as parts; as parts, each
    /// part's visibility and place in the draw order (each change one undo step, saved
    /// in the rig file's `"parts"`).
    fn layers_panel(&mut self, ui: &mut Ui) {
        let Some(doc) = &self.doc else { return };
        let Some(layers) = doc.layers.clone() else {
            return;
        };
        let spec = doc.project().parts.clone();
        let mut as_parts = spec.is_some();
        let mut chosen = None;
        let mut select = None;
        if ui
            .checkbox(&mut as_parts, "Draw as parts")
            .on_hover_text(
                "Each layer meshed along its own outline and moved by the handles on it; \
                 a handle where two layers overlap binds both",
            )
            .changed()
        {
            chosen = Some(as_parts.then(project::PartsSpec::default));
        }
        if let Some(spec) = &spec {
            let order = spec.order_of(layers.layers.len());
            // Top first, as layer panels list them.
            for (at, &k) in order.iter().enumerate().rev() {
                let layer = &layers.layers[k];
                ui.horizontal(|ui| {
                    let mut shown = spec.shows(k, layer.visible);
                    if ui
                        .checkbox(&mut shown, "")
                        .on_hover_text(format!("Show {}", layer.name))
                        .changed()
                    {
                        chosen = Some(Some(with_shown(spec, k, layer.visible, shown)));
                    }
                    // Named for what they do to which part (hover text, and the
                    // name a screen reader says).
                    let step = |ui: &mut Ui, enabled: bool, arrow: &str, what: String| {
                        let button = ui.add_enabled(enabled, egui::Button::new(arrow));
                        button.widget_info(|| {
                            egui::WidgetInfo::labeled(egui::Role::Button, enabled, &what)
                        });
                        button.on_hover_text(what).clicked()
                    };
                    let locked = spec.is_locked(k);
                    let lock = egui::Button::selectable(locked, if locked { "🔒" } else { "🔓" });
                    let what = format!("Lock {} against new pins and paint", layer.name);
                    let response = ui.add(lock);
                    response.widget_info(|| {
                        egui::WidgetInfo::selected(egui::Role::CheckBox, true, locked, &what)
                    });
                    if response.on_hover_text(what).clicked() {
                        chosen = Some(Some(with_locked(spec, k, !locked)));
                    }
                    let (top, bottom) = (at + 1 == order.len(), at == 0);
                    if step(ui, !top, "⏶", format!("Bring {} forward", layer.name)) {
                        chosen = Some(Some(with_order(spec, &order, at, at + 1)));
                    }
                    if step(ui, !bottom, "⏷", format!("Send {} backward", layer.name)) {
                        chosen = Some(Some(with_order(spec, &order, at, at - 1)));
                    }
                    let selected = self.selected_part == Some(k);
                    if ui
                        .selectable_label(selected, &layer.name)
                        .on_hover_text("Select: outlined on the canvas, its pins listed")
                        .clicked()
                    {
                        select = Some((!selected).then_some(k));
                    }
                });
            }
            if let Some(k) = self.selected_part.filter(|&k| k < layers.layers.len()) {
                ui.label(part_summary(doc, k)).on_hover_text(
                    "A part is moved by the pins that bind it (those placed on it, a joint \
                     where two parts overlap); a part no pin binds follows the part beneath \
                     it that it overlaps most",
                );
            }
        }
        if let Some(part) = select {
            self.selected_part = part;
        }
        if let Some(parts) = chosen {
            // Refused, the status line says why.
            let _ = self.edit(Edit::Parts(parts));
        }
    }

    /// The method the method selector shows: the document's, or LBC while the cage
    /// tool draws a cage (drawing one is LBC's, even before it exists).
    pub fn method_shown(&self) -> Option<Method> {
        let doc = self.doc.as_ref()?;
        let in_hand = self.in_hand();
        Some(if in_hand == doc.controls() {
            doc.method()
        } else {
            Method::for_controls(in_hand)
        })
    }

    /// The warping method: one undo step; the picture, handles and pose stay.
    fn method_choice(&mut self, ui: &mut Ui) {
        let Some(current) = self.method_shown() else {
            return;
        };
        let mut chosen = current;
        ui.horizontal_wrapped(|ui| {
            for m in Method::ALL {
                ui.selectable_value(&mut chosen, m, m.label())
                    .on_hover_text(m.about());
            }
        });
        if chosen != current {
            self.choose_method(chosen);
        }
    }

    /// Moving least squares' settings: the class of map fitted and α (applied when
    /// the slider is released, as the weighting's are).
    fn mls_panel(&mut self, ui: &mut Ui) {
        let Some(doc) = &self.doc else { return };
        let saved = doc.project().mls.unwrap_or_default();
        let current = (
            saved.alpha.unwrap_or(1.0),
            saved.variant.unwrap_or_default(),
        );
        let (mut alpha, mut variant) = self.mls_draft.unwrap_or(current);
        let r = ui
            .add(
                egui::Slider::new(&mut alpha, 0.1..=project::MAX_MLS_ALPHA)
                    .logarithmic(true)
                    .text("α (falloff)"),
            )
            .on_hover_text("A handle at distance r weighs 1/r^(2α): larger α, more local handles");
        let mut commit = released(&r);
        egui::ComboBox::from_label("Fit")
            .selected_text(variant.label())
            .show_ui(ui, |ui| {
                for v in project::MlsVariant::ALL {
                    commit |= ui.selectable_value(&mut variant, v, v.label()).clicked();
                }
            })
            .response
            .on_hover_text("The class of map fitted at every point: rigid keeps shapes, similarity also scales, affine also shears");
        let draft = (alpha, variant);
        if commit && draft != current {
            self.mls_draft = None;
            let _ = self.edit(Edit::Mls(project::MlsSettings {
                alpha: Some(alpha),
                variant: Some(variant),
            }));
        } else if draft != current {
            self.mls_draft = Some(draft);
        } else {
            self.mls_draft = None;
        }
    }

    /// Sliders and choices of the weighting. Sliders apply when released, so a drag
    /// across them does not rebuild the rig every frame.
    fn parameters(&mut self, ui: &mut Ui) {
        let Some(doc) = &self.doc else { return };
        let current = doc.settings();
        let mut draft = self.settings_draft.unwrap_or(current);
        let mut commit = false;
        let r = ui.add(egui::Slider::new(&mut draft.alpha, 0.0..=1.0).text("α (shape factor)"));
        commit |= released(&r);
        let r = ui.add(egui::Slider::new(&mut draft.degree, 5..=25).text("Basis degree"));
        commit |= released(&r);
        let r = ui.add(
            egui::Slider::new(&mut draft.density, 500..=500_000)
                .logarithmic(true)
                .text("Mesh density"),
        );
        commit |= released(&r);
        let before = draft;
        ui.checkbox(&mut draft.fixed_boundary, "Fixed boundary");
        let mut symmetric = draft.placement == Placement::Symmetric;
        ui.checkbox(&mut symmetric, "Symmetric virtual handles")
            .on_hover_text(
                "Place tied virtual handles together, so that a mirror-symmetric rig gets \
                 mirror-symmetric virtual handles; off, Algorithm 1 places one at a time, \
                 as the paper writes it",
            );
        draft.placement = if symmetric {
            Placement::Symmetric
        } else {
            Placement::AsWritten
        };
        egui::ComboBox::from_label("Distance")
            .selected_text(metric_name(draft.metric))
            .show_ui(ui, |ui| {
                for m in [
                    MetricChoice::Auto,
                    MetricChoice::Intrinsic,
                    MetricChoice::Euclidean,
                ] {
                    ui.selectable_value(&mut draft.metric, m, metric_name(m));
                }
            });
        egui::ComboBox::from_label("Middle controls")
            .selected_text(middle_name(draft.middle))
            .show_ui(ui, |ui| {
                for m in [Middle::Half, Middle::Linear] {
                    ui.selectable_value(&mut draft.middle, m, middle_name(m));
                }
            });
        commit |= draft != before;
        if commit && draft != current {
            self.settings_draft = None;
            let _ = self.edit(Edit::Settings(draft));
        } else if draft != current {
            self.settings_draft = Some(draft);
        }
    }
}

fn metric_name(m: MetricChoice) -> &'static str {
    match m {
        MetricChoice::Auto => "Auto",
        MetricChoice::Intrinsic => "Shape-aware (intrinsic)",
        MetricChoice::Euclidean => "Euclidean",
    }
}

fn middle_name(m: Middle) -> &'static str {
    match m {
        Middle::Half => "Half",
        Middle::Linear => "Linear",
    }
}

/// Whether a slider's new value is to be applied: its drag ended, or a value typed into
/// its field was left (Enter, Tab or a click elsewhere), not at every keystroke: typing
/// 41000 must not re-mesh at 4, 41 and 410 on the way.
fn released(r: &egui::Response) -> bool {
    r.drag_stopped() || r.lost_focus() || (r.changed() && !r.dragged() && !r.has_focus())
}

/// `spec` with layer `k` (which the file shows or not: `in_file`) shown or hidden.
fn with_shown(
    spec: &project::PartsSpec,
    k: usize,
    in_file: bool,
    shown: bool,
) -> project::PartsSpec {
    let mut spec = spec.clone();
    spec.hidden.retain(|&h| h != k);
    spec.shown.retain(|&h| h != k);
    match (in_file, shown) {
        (true, false) => spec.hidden.push(k),
        (false, true) => spec.shown.push(k),
        _ => {}
    }
    spec.hidden.sort_unstable();
    spec.shown.sort_unstable();
    spec
}

/// `spec` with layer `k` locked or not.
fn with_locked(spec: &project::PartsSpec, k: usize, locked: bool) -> project::PartsSpec {
    let mut spec = spec.clone();
    spec.locked.retain(|&l| l != k);
    if locked {
        spec.locked.push(k);
        spec.locked.sort_unstable();
    }
    spec
}

/// What moves part `k` of `doc`, in a line: the pins that bind it, the part it
/// follows, or the cage.
fn part_summary(doc: &crate::document::Document, k: usize) -> String {
    let name = doc.part_name(k);
    let Some(parts) = doc.parts() else {
        return format!("{name}: hidden");
    };
    let rig = parts.rig();
    let pins = rig.bindings().get(k).map_or(&[][..], Vec::as_slice);
    let numbers: Vec<String> = pins.iter().map(|h| (h + 1).to_string()).collect();
    let locked = if doc.is_locked(k) { " (locked)" } else { "" };
    if !parts.part_of().iter().any(|&p| p as usize == k) {
        format!("{name}{locked}: hidden")
    } else if rig.cage().is_some() {
        format!("{name}{locked}: moved by the cage")
    } else if let [one] = numbers.as_slice() {
        format!("{name}{locked}: pinned by handle {one}")
    } else if !numbers.is_empty() {
        format!("{name}{locked}: pinned by handles {}", numbers.join(", "))
    } else if let Some(leader) = rig.followed().get(k).copied().flatten() {
        format!(
            "{name}{locked}: no pin binds it; follows {}",
            doc.part_name(leader)
        )
    } else {
        format!("{name}{locked}: no pin binds it; stays where it is")
    }
}

/// `spec` with the layer at place `from` of the draw order `order` swapped with the
/// one at place `to`.
fn with_order(
    spec: &project::PartsSpec,
    order: &[usize],
    from: usize,
    to: usize,
) -> project::PartsSpec {
    let mut order = order.to_vec();
    order.swap(from, to);
    let mut spec = spec.clone();
    // The file's own order is kept as no order at all.
    spec.order = if order.iter().enumerate().all(|(i, &k)| i == k) {
        Vec::new()
    } else {
        order
    };
    spec
}
