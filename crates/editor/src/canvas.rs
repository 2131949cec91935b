//! The canvas: the warped picture (drawn by the GPU through a paint callback), the
//! handles and overlays on top, and the pointer input that turns into edits.

use egui::{
    Color32, CursorIcon, Key, PointerButton, Pos2, Rect, Sense, Shape, Stroke, StrokeKind, Ui, Vec2,
};
use glam::DVec2;
use project::HandleSpec;
use weights_core::NodeKind;

use crate::app::{EditorApp, Grip, HandleDrag, Tool};
use crate::document::posed;
use crate::scene::MeshCallback;
use crate::tool::CanvasTool;

/// Radius of a point handle's dot, screen points.
const DOT: f32 = 6.0;
/// How close the pointer must be to grab a handle, screen points.
const GRAB: f32 = 9.0;
/// Radius of the rotation ring around the selected point handle, screen points.
pub const RING: f32 = 26.0;

const HANDLE: Color32 = Color32::from_rgb(255, 255, 255);
const SELECTED: Color32 = Color32::from_rgb(255, 212, 0);
const OUTLINE: Color32 = Color32::from_rgb(20, 20, 20);
const VIRTUAL: Color32 = Color32::from_rgb(255, 80, 220);
const DUAL: Color32 = Color32::from_rgba_premultiplied(0, 200, 255, 200);

impl EditorApp {
    /// Lays out the canvas in the remaining space, handles its input, and paints it.
    pub(crate) fn canvas_ui(&mut self, ui: &mut Ui) {
        let (rect, response) = ui.allocate_exact_size(ui.available_size(), Sense::click_and_drag());
        response.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Canvas, true, "Canvas"));
        let resized = self.viewport.canvas.size() != rect.size();
        self.viewport.canvas = rect;
        // A fitted view stays fitted when the window changes size (the first frames of
        // a new window, a maximise), until the user pans or zooms.
        // Not in the middle of a drag: the picture would move under the pointer.
        if (self.needs_fit || (resized && self.view_fitted && self.drag.is_none()))
            && let Some(doc) = &self.doc
        {
            self.viewport.fit([doc.image.width(), doc.image.height()]);
            self.needs_fit = false;
            self.view_fitted = true;
        }
        if !self.is_busy() {
            self.canvas_input(ui, &response);
        }
        self.update_gpu_frame();

        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 0.0, Color32::from_gray(38));
        if let Some(doc) = &self.doc {
            // The picture's frame, so a transparent picture still shows its extent.
            let frame = Rect::from_two_pos(
                self.viewport.to_screen(DVec2::ZERO),
                self.viewport.to_screen(DVec2::new(
                    f64::from(doc.image.width()),
                    f64::from(doc.image.height()),
                )),
            );
            // A checkerboard where the picture is transparent, 8-point squares.
            let checker = self.checker.get_or_insert_with(|| {
                let (light, dark) = (Color32::from_gray(72), Color32::from_gray(56));
                ui.ctx().load_texture(
                    "checker",
                    egui::ColorImage::new([2, 2], vec![light, dark, dark, light]),
                    egui::TextureOptions {
                        magnification: egui::TextureFilter::Nearest,
                        minification: egui::TextureFilter::Nearest,
                        wrap_mode: egui::TextureWrapMode::Repeat,
                        mipmap_mode: None,
                    },
                )
            });
            let visible = frame.intersect(rect);
            if visible.is_positive() {
                let square = 8.0;
                let uv = Rect::from_min_max(
                    ((visible.min - frame.min) / (2.0 * square)).to_pos2(),
                    ((visible.max - frame.min) / (2.0 * square)).to_pos2(),
                );
                painter.image(checker.id(), visible, uv, Color32::WHITE);
            }
        }
        let cage_view = self.cage_view();
        if self.has_gpu {
            let (scale, offset) = self.viewport.device_map();
            let shown = if cage_view {
                self.cage.focus().filter(|_| self.cage_warping())
            } else {
                self.selected
            };
            let overlay = if self.show.heat && shown.is_some() {
                render::Overlay::Heat
            } else if self.show.cells && !cage_view {
                render::Overlay::Cells
            } else {
                render::Overlay::None
            };
            let params = render::ViewParams {
                scale,
                offset,
                overlay,
                show_folds: self.show.folds,
                wireframe: self.show.mesh,
            };
            painter.add(egui_wgpu::Callback::new_paint_callback(
                rect,
                MeshCallback {
                    frame: self.gpu.frame.clone(),
                    params,
                },
            ));
        } else {
            painter.text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                "No GPU renderer: the picture cannot be shown",
                egui::FontId::proportional(16.0),
                Color32::LIGHT_RED,
            );
        }
        if cage_view {
            let pointer = ui.input(|i| i.pointer.latest_pos());
            let active = self.tool == Tool::Cage;
            self.with_cage(|cage, host| cage.paint(host, &painter, pointer, active));
        } else {
            let (pointer, alt) = ui.input(|i| (i.pointer.latest_pos(), i.modifiers.alt));
            let brushing = self.tool == Tool::Rigidity;
            let hover = pointer.filter(|p| rect.contains(*p));
            self.with_brush(|brush, host| brush.paint(host, &painter, hover, brushing));
            // Alt over a point handle shows the ring a drag turns it by.
            let turning = match &self.drag {
                Some(drag) if drag.grip == Grip::Rotate => Some(drag.index),
                _ => pointer
                    .filter(|_| alt && self.drag.is_none())
                    .and_then(|p| self.rotation_target(p)),
            };
            self.paint_overlays(&painter, turning);
        }
        if let (Some(a), Some(b)) = (self.bar_start, ui.input(|i| i.pointer.latest_pos())) {
            let a = self.viewport.to_screen(a);
            painter.line_segment([a, b], Stroke::new(4.0, SELECTED));
        }
        if let Some((what, seconds)) = self.busy_with().filter(|(_, s)| *s > 0.25) {
            // A short job (a rebuild at a low density) shows only in the status bar.
            painter.rect_filled(rect, 0.0, Color32::from_black_alpha(120));
            let mut text = format!("{what}… {seconds:.1} s");
            if let Some((_, last)) = self.solve_progress() {
                text.push_str(&format!(
                    "\niteration {}: residuals {:.1e} / {:.1e} (to reach {:.1e} / {:.1e})\nEscape cancels",
                    last.iteration,
                    last.primal_residual,
                    last.dual_residual,
                    last.primal_threshold,
                    last.dual_threshold
                ));
            }
            painter.text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                text,
                egui::FontId::proportional(20.0),
                Color32::WHITE,
            );
        } else if !self.is_busy() {
            self.hover_weights(ui, &response);
        }
    }

    /// The bar tool, from the pointer's own press and release rather than egui's drag
    /// detection: a quick stroke (press, a big move and release within a frame or
    /// two) is a bar too, not a click that does nothing.
    fn bar_input(&mut self, ui: &Ui, response: &egui::Response) {
        let (pressed, released, origin, latest) = ui.input(|i| {
            (
                i.pointer.primary_pressed(),
                i.pointer.primary_released(),
                i.pointer.press_origin(),
                i.pointer.latest_pos(),
            )
        });
        let space = ui.input(|i| i.key_down(Key::Space));
        if pressed
            && !space
            && let Some(origin) = origin
            && response.rect.contains(origin)
            && (response.contains_pointer() || response.is_pointer_button_down_on())
        {
            self.bar_start = Some(self.viewport.to_image(origin));
        }
        if released && let Some(a) = self.bar_start.take() {
            let Some(end) = latest else { return };
            if self.viewport.to_screen(a).distance(end) > 4.0 {
                self.add_bar(a, self.viewport.to_image(end));
            } else {
                self.info("to add a bar, drag from one end of it to the other");
            }
        }
    }

    /// Whether image point `at` (in the current pose) shows the picture.
    fn on_picture(&mut self, at: DVec2) -> bool {
        self.doc
            .as_mut()
            .is_some_and(|doc| doc.unwarp(at).is_some())
    }

    /// The handle under `pos` (screen), and which grip.
    pub(crate) fn hit(&self, pos: Pos2) -> Option<(usize, Grip)> {
        let doc = self.doc.as_ref()?;
        let mut best: Option<(f32, usize, Grip)> = None;
        let mut consider = |d: f32, i: usize, grip: Grip| {
            if d < GRAB && best.is_none_or(|(bd, _, _)| d < bd) {
                best = Some((d, i, grip));
            }
        };
        for (i, h) in doc.project().handles.iter().enumerate() {
            let [a, b] = posed(h).map(|p| self.viewport.to_screen(p));
            match h {
                HandleSpec::Point { .. } => {
                    let d = a.distance(pos);
                    consider(d, i, Grip::Move);
                    if self.selected == Some(i) {
                        consider((d - RING).abs(), i, Grip::Rotate);
                    }
                }
                HandleSpec::Bar { .. } => {
                    // Ends win over the body at equal distance.
                    consider(a.distance(pos) - 0.5, i, Grip::End(0));
                    consider(b.distance(pos) - 0.5, i, Grip::End(1));
                    consider(segment_distance(pos, a, b), i, Grip::Move);
                }
            }
        }
        best.map(|(_, i, g)| (i, g))
    }

    /// The point handle a drag from `pos` with Alt held turns: the nearest one whose
    /// rotation ring (or anything inside it) is under the pointer, as in Puppet Warp.
    pub(crate) fn rotation_target(&self, pos: Pos2) -> Option<usize> {
        let doc = self.doc.as_ref()?;
        doc.project()
            .handles
            .iter()
            .enumerate()
            .filter(|(_, h)| matches!(h, HandleSpec::Point { .. }))
            .map(|(i, h)| (i, self.viewport.to_screen(posed(h)[0]).distance(pos)))
            .filter(|&(_, d)| d < RING + GRAB)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    }

    fn canvas_input(&mut self, ui: &Ui, response: &egui::Response) {
        let (modifiers, space, scroll, zoom) = ui.input(|i| {
            (
                i.modifiers,
                i.key_down(Key::Space),
                i.smooth_scroll_delta.y,
                i.zoom_delta(),
            )
        });
        if let Some(hover) = response.hover_pos() {
            let factor = zoom * (scroll * 0.0015).exp();
            if (factor - 1.0).abs() > 1e-4 {
                self.viewport.zoom_about(hover, factor);
                self.view_fitted = false;
            }
        }
        let press = ui
            .input(|i| i.pointer.press_origin())
            .or(response.interact_pointer_pos());
        if self.tool == Tool::AddBar {
            self.bar_input(ui, response);
        }
        if self.tool == Tool::Rigidity {
            self.with_brush(|brush, host| brush.input(host, ui, response));
        }
        if self.tool == Tool::Cage {
            self.with_cage(|cage, host| cage.input(host, ui, response));
        }
        if response.drag_started_by(PointerButton::Middle)
            || (response.drag_started_by(PointerButton::Primary) && space)
        {
            self.panning = true;
        } else if response.drag_started_by(PointerButton::Primary)
            && !matches!(self.tool, Tool::AddBar | Tool::Rigidity | Tool::Cage)
            && let Some(pos) = press
        {
            // With Alt, a drag anywhere on or inside a point handle's ring turns it.
            let turn = modifiers
                .alt
                .then(|| self.rotation_target(pos))
                .flatten()
                .map(|i| (i, Grip::Rotate));
            match turn.or_else(|| self.hit(pos)) {
                Some((index, grip)) => self.start_drag(index, grip, pos, modifiers),
                None => self.panning = matches!(self.tool, Tool::Puppet | Tool::Select),
            }
        }
        if response.dragged() {
            if self.panning {
                self.viewport.origin += response.drag_delta();
                self.view_fitted = false;
            } else if let Some(pos) = response.interact_pointer_pos() {
                self.drag_to(self.viewport.to_image(pos));
            }
        }
        if response.drag_stopped() {
            self.panning = false;
            self.finish_drag();
        }
        if response.clicked_by(PointerButton::Primary)
            && let Some(pos) = response.interact_pointer_pos()
        {
            let hit = self.hit(pos).map(|(i, _)| i);
            match (self.tool, hit) {
                (Tool::AddBar | Tool::Rigidity | Tool::Cage, _) => {}
                (_, Some(i)) if modifiers.alt => {
                    // The Puppet Warp convention: Alt-click deletes a handle.
                    self.selected = Some(i);
                    self.delete_selected();
                }
                (_, Some(i)) => self.selected = Some(i),
                (Tool::Puppet, None) => {
                    let at = self.viewport.to_image(pos);
                    if self.on_picture(at) {
                        self.add_point(at);
                    } else {
                        self.selected = None;
                    }
                }
                (Tool::Select, None) => self.selected = None,
                (Tool::AddPoint, None) => self.add_point(self.viewport.to_image(pos)),
            }
        }
        if self.tool == Tool::Cage {
            // The cage tool sets its own cursor and has no handle menu.
            return;
        }
        if response.secondary_clicked()
            && let Some(pos) = response.interact_pointer_pos()
        {
            self.selected = self.hit(pos).map(|(i, _)| i);
            self.context_point = Some(self.viewport.to_image(pos));
            self.context_handle = self.selected.and_then(|i| {
                let handle = self.doc.as_ref()?.project().handles.get(i)?.clone();
                Some((i, handle))
            });
        }
        response.context_menu(|ui| self.context_menu(ui));
        let cursor = if self.panning || self.drag.is_some() {
            Some(CursorIcon::Grabbing)
        } else if response.hover_pos().and_then(|p| self.hit(p)).is_some() {
            Some(CursorIcon::Grab)
        } else if matches!(self.tool, Tool::AddPoint | Tool::AddBar | Tool::Rigidity)
            && response.hovered()
        {
            Some(CursorIcon::Crosshair)
        } else {
            None
        };
        if let Some(cursor) = cursor {
            ui.ctx().set_cursor_icon(cursor);
        }
    }

    /// The right-click menu. It stays open across frames, so it acts on the handle it
    /// was opened on only if that handle is still where it was (an undo or a new
    /// document may have changed the list since).
    fn context_menu(&mut self, ui: &mut Ui) {
        if let Some((i, opened_on)) = self.context_handle.clone() {
            let still_there = self
                .doc
                .as_ref()
                .and_then(|d| d.project().handles.get(i))
                .is_some_and(|h| crate::document::same_rest(h, &opened_on));
            if !still_there {
                ui.label("(this handle is gone)");
                return;
            }
            if ui.button("Delete handle").clicked() {
                self.selected = Some(i);
                self.delete_selected();
                ui.close();
            }
            if ui.button("Reset handle pose").clicked() {
                let rest = crate::document::at_rest(&opened_on);
                let _ = self.edit(crate::document::Edit::Pose(i, rest));
                ui.close();
            }
            ui.separator();
            if ui.button("Bring forward").clicked() {
                self.change_depth(i, 1);
                ui.close();
            }
            if ui.button("Send backward").clicked() {
                self.change_depth(i, -1);
                ui.close();
            }
        } else if let Some(at) = self.context_point
            && ui.button("Add point handle here").clicked()
        {
            self.add_point(at);
            ui.close();
        }
    }

    fn start_drag(&mut self, index: usize, grip: Grip, pos: Pos2, modifiers: egui::Modifiers) {
        let Some(doc) = &self.doc else { return };
        let Some(start) = doc.project().handles.get(index).cloned() else {
            return;
        };
        let grip = if modifiers.alt {
            Grip::Rotate
        } else if modifiers.shift {
            Grip::Scale
        } else {
            grip
        };
        self.selected = Some(index);
        self.drag = Some(HandleDrag {
            index,
            grip,
            start,
            pointer: self.viewport.to_image(pos),
            before: doc.snapshot(),
        });
    }

    /// Moves the dragged handle so the grabbed point follows the pointer.
    pub(crate) fn drag_to(&mut self, pointer: DVec2) {
        let Some(drag) = &mut self.drag else { return };
        let [a, b] = posed(&drag.start);
        let centre = (a + b) * 0.5;
        if drag.grip == Grip::Rotate {
            // A turn started on the centre has no direction yet: it is measured from
            // where the pointer first is a few screen points away.
            let near = 4.0 / f64::from(self.viewport.zoom.max(1e-6));
            if (drag.pointer - centre).length() < near {
                if (pointer - centre).length() >= near {
                    drag.pointer = pointer;
                }
                return;
            }
        }
        let delta = pointer - drag.pointer;
        let turn = angle_between(drag.pointer - centre, pointer - centre);
        let stretch = ((pointer - centre).length() / (drag.pointer - centre).length().max(1e-9))
            .clamp(0.05, 20.0);
        let handle = match (drag.start.clone(), drag.grip) {
            (
                HandleSpec::Point {
                    rest,
                    translate,
                    rotate,
                    scale,
                    depth,
                },
                grip,
            ) => {
                let (mut translate, mut rotate, mut scale) = (translate, rotate, scale);
                match grip {
                    Grip::Move | Grip::End(_) => {
                        translate = (DVec2::from(translate) + delta).to_array();
                    }
                    Grip::Rotate => rotate += turn,
                    Grip::Scale => scale = (scale * stretch).clamp(0.01, 100.0),
                }
                HandleSpec::Point {
                    rest,
                    translate,
                    rotate,
                    scale,
                    depth,
                }
            }
            (HandleSpec::Bar { rest, depth, .. }, grip) => {
                let pose = match grip {
                    Grip::Move => [a + delta, b + delta],
                    Grip::End(0) => [a + delta, b],
                    Grip::End(_) => [a, b + delta],
                    Grip::Rotate => {
                        let r = DVec2::from_angle(turn);
                        [centre + r.rotate(a - centre), centre + r.rotate(b - centre)]
                    }
                    Grip::Scale => [
                        centre + (a - centre) * stretch,
                        centre + (b - centre) * stretch,
                    ],
                };
                HandleSpec::Bar {
                    rest,
                    pose: Some(pose.map(|p| p.to_array())),
                    depth,
                }
            }
        };
        let index = drag.index;
        self.set_pose(index, handle);
    }

    /// Paints the handles (with the rotation ring of `turning`, the point handle Alt
    /// is over or being turned), and for the C² weights the virtual handles and the
    /// dual graph when asked for.
    fn paint_overlays(&self, painter: &egui::Painter, turning: Option<usize>) {
        let Some(doc) = &self.doc else { return };
        let rig = doc.rig();
        let v = &self.viewport;
        let c2 = doc.method().uses_virtual_handles();
        if self.show.dual_graph && c2 {
            for &(a, b) in self.gpu.dual_graph.1.iter() {
                let (a, b) = (a as usize, b as usize);
                if a < rig.nodes().len() && b < rig.nodes().len() {
                    painter.line_segment(
                        [
                            v.to_screen(doc.node_position(a)),
                            v.to_screen(doc.node_position(b)),
                        ],
                        Stroke::new(1.5, DUAL),
                    );
                }
            }
        }
        if self.show.virtual_handles && c2 {
            for (k, node) in rig.nodes().iter().enumerate() {
                if matches!(node.kind, NodeKind::Virtual) {
                    let c = v.to_screen(doc.node_position(k));
                    let r = 4.5;
                    painter.add(Shape::convex_polygon(
                        vec![
                            c + Vec2::new(0.0, -r),
                            c + Vec2::new(r, 0.0),
                            c + Vec2::new(0.0, r),
                            c + Vec2::new(-r, 0.0),
                        ],
                        VIRTUAL,
                        Stroke::new(1.0, OUTLINE),
                    ));
                }
            }
        }
        for (i, h) in doc.project().handles.iter().enumerate() {
            let fill = if self.selected == Some(i) {
                SELECTED
            } else {
                HANDLE
            };
            let [a, b] = posed(h).map(|p| v.to_screen(p));
            match h {
                HandleSpec::Point { rotate, scale, .. } => {
                    if self.selected == Some(i) || turning == Some(i) {
                        painter.circle_stroke(a, RING, Stroke::new(2.0, OUTLINE));
                        painter.circle_stroke(a, RING, Stroke::new(1.0, SELECTED));
                        let tick = Vec2::angled(*rotate as f32) * RING;
                        painter.line_segment([a, a + tick], Stroke::new(2.0, SELECTED));
                        painter.circle_filled(a + tick, 4.0, SELECTED);
                    } else if rotate.abs() > 1e-6 || (scale - 1.0).abs() > 1e-6 {
                        let tick = Vec2::angled(*rotate as f32) * (DOT + 6.0 * *scale as f32);
                        painter.line_segment([a, a + tick], Stroke::new(2.0, OUTLINE));
                    }
                    painter.circle(a, DOT, fill, Stroke::new(2.0, OUTLINE));
                }
                HandleSpec::Bar { .. } => {
                    painter.line_segment([a, b], Stroke::new(6.0, OUTLINE));
                    painter.line_segment([a, b], Stroke::new(3.0, fill));
                    painter.circle(a, DOT - 1.0, fill, Stroke::new(2.0, OUTLINE));
                    painter.circle(b, DOT - 1.0, fill, Stroke::new(2.0, OUTLINE));
                }
            }
        }
        painter.rect_stroke(
            v.canvas,
            0.0,
            Stroke::new(1.0, Color32::from_gray(70)),
            StrokeKind::Inside,
        );
    }

    /// Where ARAP takes the mesh vertex under screen point `pos`, as text.
    fn positions_readout_at(&mut self, pos: Pos2) -> Option<String> {
        let doc = self.doc.as_mut()?;
        let method = doc.method().label();
        let (rest, _, _) = doc.unwarp(self.viewport.to_image(pos))?;
        let vertex = doc.rig().domain().nearest_vertex(rest)? as usize;
        let at = doc.rig().domain().positions()[vertex];
        let to = *doc.deformed().get(vertex)?;
        Some(format!(
            "vertex {vertex} at ({:.1}, {:.1})\n{method} moves it to ({:.1}, {:.1})",
            at.x, at.y, to.x, to.y
        ))
    }

    /// The C² weights of the mesh vertex under screen point `pos`, as text.
    fn handle_weights_at(&mut self, pos: Pos2) -> Option<String> {
        let doc = self.doc.as_mut()?;
        let (rest, _, _) = doc.unwarp(self.viewport.to_image(pos))?;
        let rig = doc.rig();
        let vertex = rig.domain().nearest_vertex(rest)?;
        let mut weights: Vec<(usize, f64)> = rig.weights(vertex as usize).collect();
        weights.sort_by(|a, b| b.1.total_cmp(&a.1));
        let lines: Vec<String> = weights
            .iter()
            .take(5)
            .map(|&(k, w)| format!("{:>6.3}  {}", w, node_name(rig, k)))
            .collect();
        let more = weights.len().saturating_sub(5);
        let mut text = format!(
            "vertex {vertex} at ({:.1}, {:.1}): {} weights",
            rest.x,
            rest.y,
            weights.len()
        );
        for line in &lines {
            text.push('\n');
            text.push_str(line);
        }
        if more > 0 {
            text.push_str(&format!("\n… and {more} smaller"));
        }
        Some(text)
    }

    /// A box beside the pointer with the weights of the mesh vertex under it.
    fn hover_weights(&mut self, ui: &Ui, response: &egui::Response) {
        self.hover_readout = None;
        if !self.show.hover_weights || self.drag.is_some() || self.panning {
            return;
        }
        let Some(pos) = response.hover_pos() else {
            return;
        };
        let text = if self.cage_view() {
            match self.with_cage(|cage, host| cage.readout(host, pos)) {
                Some(text) => text,
                None => return,
            }
        } else if self
            .doc
            .as_ref()
            .is_some_and(|d| matches!(d.deformer().output(), pipeline::Output::Positions(_)))
        {
            // A method that solves for positions has no weights: where it takes the
            // vertex under the pointer.
            match self.positions_readout_at(pos) {
                Some(text) => text,
                None => return,
            }
        } else {
            match self.handle_weights_at(pos) {
                Some(text) => text,
                None => return,
            }
        };
        // Painted rather than an egui tooltip: it follows the pointer at once, also
        // while the pointer moves.
        let painter = ui.painter_at(self.viewport.canvas);
        let galley = painter.layout_no_wrap(
            text.clone(),
            egui::FontId::monospace(12.0),
            Color32::from_gray(230),
        );
        let mut corner = pos + Vec2::new(16.0, 16.0);
        let size = galley.size() + Vec2::splat(12.0);
        let canvas = self.viewport.canvas;
        if corner.x + size.x > canvas.max.x {
            corner.x = pos.x - 16.0 - size.x;
        }
        if corner.y + size.y > canvas.max.y {
            corner.y = pos.y - 16.0 - size.y;
        }
        // Never past the canvas's left or top edge, where it would be cut.
        corner = corner.max(canvas.min);
        let frame = Rect::from_min_size(corner, size);
        painter.rect_filled(frame, 4.0, Color32::from_black_alpha(200));
        painter.galley(corner + Vec2::splat(6.0), galley, Color32::from_gray(230));
        self.hover_readout = Some(text);
    }
}

/// How a node is called in the user interface.
pub(crate) fn node_name(rig: &weights_core::Rig, k: usize) -> String {
    match rig.nodes()[k].kind {
        NodeKind::Point { handle } => format!("point handle {}", handle + 1),
        NodeKind::BarSample { handle, t } => format!("bar {} at {:.0}%", handle + 1, t * 100.0),
        NodeKind::Boundary => "pinned border".to_owned(),
        NodeKind::Virtual => match rig.owner_handle(k) {
            Some(h) => format!("virtual node {k} (mostly handle {})", h + 1),
            None => format!("virtual node {k}"),
        },
    }
}

/// The signed angle that turns `from` onto `to`.
fn angle_between(from: DVec2, to: DVec2) -> f64 {
    from.perp_dot(to).atan2(from.dot(to))
}

/// Distance from `p` to the segment `a`–`b`.
fn segment_distance(p: Pos2, a: Pos2, b: Pos2) -> f32 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_sq().max(1e-9)).clamp(0.0, 1.0);
    p.distance(a + ab * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angles_and_distances() {
        let a = angle_between(DVec2::X, DVec2::Y);
        assert!((a - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        let d = segment_distance(Pos2::new(5.0, 3.0), Pos2::ZERO, Pos2::new(10.0, 0.0));
        assert!((d - 3.0).abs() < 1e-6);
        let d = segment_distance(Pos2::new(-4.0, 3.0), Pos2::ZERO, Pos2::new(10.0, 0.0));
        assert!((d - 5.0).abs() < 1e-6);
    }
}
