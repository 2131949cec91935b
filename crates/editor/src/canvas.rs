//! The canvas: its layout, pan and zoom, the checkerboard, the warped picture (drawn by
//! the GPU through a paint callback), the readouts under the pointer and the busy
//! overlay; the pointer input and the overlays of the tools (the handle tools, the
//! brush, the cage) are theirs, dispatched from here.

use egui::{Color32, Key, PointerButton, Pos2, Rect, Sense, Ui, Vec2};
use glam::DVec2;

use crate::app::{EditorApp, Tool};
use crate::scene::MeshCallback;
use crate::tool::CanvasTool;

/// Frames after a requested fit during which the fit follows the panels being laid
/// out around the canvas.
const FIT_SETTLING_FRAMES: u8 = 4;

impl EditorApp {
    /// Lays out the canvas in the remaining space, handles its input, and paints it.
    pub(crate) fn canvas_ui(&mut self, ui: &mut Ui) {
        let (rect, response) = ui.allocate_exact_size(ui.available_size(), Sense::click_and_drag());
        response.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Canvas, true, "Canvas"));
        self.place_canvas(rect, ui.ctx().content_rect().size());
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
        self.paint_onion(ui, &painter);
        let in_hand = self.in_hand();
        if self.has_gpu {
            let (scale, offset) = self.viewport.device_map();
            let controls = self.set(in_hand);
            let shown = controls.heat_subject(self);
            let overlay = if self.show.heat && shown.is_some() {
                render::Overlay::Heat
            } else if self.show.cells && controls.uses_weights() {
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
        if self.show.overlaps {
            self.paint_overlaps(&painter);
        }
        self.paint_selected_part(&painter);
        // The controls in hand, and the marks of the tools beside them (painted
        // rigidity, cuts), each shown as in use when it is the tool.
        let pointer = ui.input(|i| i.pointer.latest_pos());
        let hover = pointer.filter(|p| rect.contains(*p));
        for &companion in self.set(in_hand).companions() {
            let active = self.tool == companion;
            self.with_tool(companion, |tool, host| {
                tool.paint(host, &painter, hover, active);
            });
        }
        let active = self.set(in_hand).owns(self.tool);
        self.with_controls(|controls, host| controls.paint(host, &painter, pointer, active));
        let pointer = ui.input(|i| i.pointer.latest_pos());
        let performing = self.tool == Tool::Perform;
        if performing || self.perform.cursor.is_some() {
            self.with_perform(|perform, host| perform.paint(host, &painter, pointer, performing));
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

    /// Takes the canvas's rectangle for this frame, keeping the picture where the hand
    /// expects it: when the window changes size, a fitted view is fitted again (its
    /// centre stays the centre) and any other keeps the image point under the canvas's
    /// centre; when only the panels around the canvas change (the window as it was),
    /// nothing moves on screen. Nothing moves during a drag either.
    fn place_canvas(&mut self, rect: egui::Rect, window: egui::Vec2) {
        let old = self.viewport.canvas;
        let window_resized = self.window_size.is_some_and(|w| w != window);
        self.window_size = Some(window);
        self.viewport.canvas = rect;
        // The first frames after a fit lay the panels out: the fit follows them.
        let settling = self.fit_settling > 0;
        self.fit_settling = self.fit_settling.saturating_sub(1);
        if old.size() == rect.size() && old.min == rect.min && !self.needs_fit {
            return;
        }
        let dragging = self.handles.dragging() || self.perform.dragging();
        let refit = (window_resized || settling) && self.view_fitted && !dragging;
        if self.needs_fit || refit {
            if let Some(doc) = &self.doc {
                self.viewport.fit([doc.image.width(), doc.image.height()]);
                if self.needs_fit {
                    self.fit_settling = FIT_SETTLING_FRAMES;
                }
                self.needs_fit = false;
                self.view_fitted = true;
            }
            return;
        }
        if window_resized && !dragging {
            // The image point under the old centre goes under the new one.
            self.viewport.origin += (rect.size() - old.size()) * 0.5;
        } else {
            // The same screen position for every image point.
            self.viewport.origin -= rect.min - old.min;
            // Unless a fitted picture would no longer fit (a panel opened beside it):
            // then it is fitted again, between gestures.
            if let Some(doc) = &self.doc
                && self.view_fitted
                && !dragging
            {
                let (w, h) = doc.image.dimensions();
                let far = self
                    .viewport
                    .to_screen(DVec2::new(f64::from(w), f64::from(h)));
                let near = self.viewport.to_screen(DVec2::ZERO);
                if !rect.expand(0.5).contains(near) || !rect.expand(0.5).contains(far) {
                    self.viewport.fit([w, h]);
                }
            }
        }
    }

    /// The canvas's own input (zoom, and a pan with the middle button or Space), and
    /// the active tool's. The handle tools' input runs under every tool: a handle's
    /// right-click menu and the cursor over it serve the brush too, and a drag begun
    /// before a switch of tools goes on.
    fn canvas_input(&mut self, ui: &Ui, response: &egui::Response) {
        let (space, scroll, zoom) = ui.input(|i| {
            (
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
        if self.tool == Tool::Rigidity {
            self.with_brush(|brush, host| brush.input(host, ui, response));
        }
        if self.tool == Tool::Cut {
            self.with_cut(|cut, host| cut.input(host, ui, response));
        }
        if self.tool == Tool::Cage {
            self.with_cage(|cage, host| cage.input(host, ui, response));
        }
        if response.drag_started_by(PointerButton::Middle)
            || (response.drag_started_by(PointerButton::Primary) && space)
        {
            self.panning = true;
            self.space_panned |= space;
        }
        if self.tool == Tool::Perform {
            self.with_perform(|perform, host| perform.input(host, ui, response));
        } else {
            // A drag the handle tools start on empty canvas pans too (Puppet, Select).
            self.with_handles(|handles, host| handles.input(host, ui, response));
        }
        if response.dragged() && self.panning {
            self.viewport.origin += response.drag_delta();
            self.view_fitted = false;
        }
        if response.drag_stopped() {
            self.panning = false;
        }
    }

    /// A box beside the pointer with the weights of the mesh vertex under it.
    fn hover_weights(&mut self, ui: &Ui, response: &egui::Response) {
        self.hover_readout = None;
        // Performing, the pointer drives the cursor: no readout in its way.
        if !self.show.hover_weights
            || self.handles.dragging()
            || self.panning
            || self.tool == Tool::Perform
        {
            return;
        }
        let Some(pos) = response.hover_pos() else {
            return;
        };
        let Some(text) = self.with_controls(|controls, host| controls.readout(host, pos)) else {
            return;
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

impl EditorApp {
    /// The overlap regions of the shown pose outlined: each sheet's boundary (its
    /// triangles' edges that no other triangle of the sheet shares), the front sheet
    /// in yellow, the back one in blue.
    fn paint_overlaps(&mut self, painter: &egui::Painter) {
        let (in_hand, warping) = (self.in_hand(), self.cage_warping());
        let Some(doc) = &mut self.doc else { return };
        // (The method's positions, kept between frames.)
        doc.deformed();
        let doc = &*doc;
        // The mesh the view draws (none: the picture at rest, nothing overlaps).
        let shown = doc.shown(in_hand, warping);
        let (Some(mesh), Some(positions)) = (shown.deformer(), shown.positions(doc)) else {
            return;
        };
        let triangles = mesh.triangles();
        let outline = |sheet: &[u32], colour: Color32| {
            let sheet = sheet.iter().filter_map(|&t| triangles.get(t as usize));
            outline(painter, &self.viewport, positions, sheet, colour);
        };
        for region in doc.overlap_regions() {
            outline(&region.back, Color32::from_rgb(90, 160, 255));
            outline(&region.front, Color32::from_rgb(255, 220, 60));
        }
    }

    /// The part selected in the Layers panel outlined where the view draws it (drawn
    /// as parts).
    fn paint_selected_part(&mut self, painter: &egui::Painter) {
        let (in_hand, warping) = (self.in_hand(), self.cage_warping());
        let (Some(doc), Some(k)) = (&mut self.doc, self.selected_part) else {
            return;
        };
        // (The parts' positions, kept between frames.)
        doc.deformed();
        let doc = &*doc;
        let shown = doc.shown(in_hand, warping);
        let (crate::document::Shown::Parts(parts), Some(positions)) = (shown, shown.positions(doc))
        else {
            return;
        };
        let part = (pipeline::Deformer::triangles(parts).iter())
            .zip(parts.part_of())
            .filter(|&(_, &p)| p as usize == k)
            .map(|(t, _)| t);
        outline(
            painter,
            &self.viewport,
            positions,
            part,
            Color32::from_rgb(255, 120, 200),
        );
    }

    /// The onion skin, when on (and not while playing): the previous and next keys'
    /// pictures ghosted under the current one.
    fn paint_onion(&mut self, ui: &Ui, painter: &egui::Painter) {
        if !self.timeline.onion {
            self.onion.clear();
            return;
        }
        if self.timeline.is_playing() || self.timeline.is_taking() {
            return;
        }
        let Some(doc) = &mut self.doc else { return };
        self.onion.update(doc, self.timeline.time, ui.ctx());
        let frame = Rect::from_two_pos(
            self.viewport.to_screen(DVec2::ZERO),
            self.viewport.to_screen(DVec2::new(
                f64::from(doc.image.width()),
                f64::from(doc.image.height()),
            )),
        );
        let uv = Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
        for ghost in &self.onion.ghosts {
            painter.image(ghost.id(), frame, uv, Color32::WHITE);
        }
    }
}

/// The outline of a sheet of `triangles` (its edges that no other triangle of it
/// shares) at `positions`, in `colour`.
fn outline<'a>(
    painter: &egui::Painter,
    viewport: &crate::viewport::Viewport,
    positions: &[DVec2],
    triangles: impl Iterator<Item = &'a [u32; 3]>,
    colour: Color32,
) {
    let mut edges: std::collections::HashMap<(u32, u32), u32> = std::collections::HashMap::new();
    for &[a, b, c] in triangles {
        for (u, v) in [(a, b), (b, c), (c, a)] {
            *edges.entry((u.min(v), u.max(v))).or_default() += 1;
        }
    }
    for ((u, v), count) in edges {
        let (Some(&p), Some(&q)) = (positions.get(u as usize), positions.get(v as usize)) else {
            continue;
        };
        if count == 1 {
            painter.line_segment(
                [viewport.to_screen(p), viewport.to_screen(q)],
                egui::Stroke::new(1.5, colour),
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Where image pixel (300, 300) is on screen.
    fn point(app: &EditorApp) -> egui::Pos2 {
        app.viewport.to_screen(DVec2::new(300.0, 300.0))
    }

    #[test]
    fn panels_keep_the_picture_in_place_unless_it_would_be_hidden() {
        let mut app = EditorApp::headless(false);
        let window = egui::vec2(1200.0, 800.0);
        let canvas = egui::Rect::from_min_max(egui::pos2(273.0, 25.0), egui::pos2(1200.0, 690.0));
        for _ in 0..=FIT_SETTLING_FRAMES {
            app.place_canvas(canvas, window);
        }
        let fitted = point(&app);
        // The timeline grows a row: nothing moves.
        let shorter = egui::Rect::from_min_max(canvas.min, canvas.max - egui::vec2(0.0, 12.0));
        app.place_canvas(shorter, window);
        assert_eq!(point(&app), fitted);
        // A panel opens on the right, over part of the picture: fitted again.
        let narrower = egui::Rect::from_min_max(canvas.min, egui::pos2(900.0, 678.0));
        app.place_canvas(narrower, window);
        let v = app.viewport;
        assert!(v.to_screen(DVec2::new(746.0, 669.0)).x <= 900.5, "{v:?}");
        // Panned by the user, the view is theirs: a panel changes nothing.
        app.view_fitted = false;
        let before = point(&app);
        app.place_canvas(
            egui::Rect::from_min_max(canvas.min, egui::pos2(700.0, 678.0)),
            window,
        );
        assert_eq!(point(&app), before);
    }
}
