//! The timeline strip under the canvas: transport buttons, the keys' commands, the
//! animation's settings, and the strip itself (a ruler in seconds, the keys as
//! diamonds, the time shown as a line; click or drag to scrub, drag a key to move it).

use egui::{Color32, Pos2, Sense, Shape, Stroke, Ui, vec2};
use project::Interpolation;

use crate::app::EditorApp;

const KEY: Color32 = Color32::from_rgb(250, 210, 40);
const HELD: Color32 = Color32::from_rgb(240, 140, 40);
const PLAYHEAD: Color32 = Color32::from_rgb(235, 60, 50);
/// Width of the time shown (" 133.25 s · frame  3198"), screen points: fixed, so
/// nothing moves as the time grows.
const TIME_WIDTH: f32 = 200.0;
/// Width of the rate field, screen points.
const FIELD_WIDTH: f32 = 62.0;

impl EditorApp {
    /// The timeline panel.
    pub(super) fn timeline_ui(&mut self, ui: &mut Ui) {
        let fps = self.fps();
        let time = self.timeline.time;
        let keys = self.keys().len();
        // Two rows of fixed contents and widths that never wrap (a narrow window
        // scrolls them sideways), so the panel's height, and with it the canvas, never
        // changes with the values shown.
        egui::ScrollArea::horizontal()
            .id_salt("timeline rows")
            .show(ui, |ui| {
                ui.horizontal(|ui| self.transport_row(ui, time, fps, keys));
                ui.horizontal(|ui| self.keys_row(ui, fps));
            });
        self.strip(ui);
    }

    /// The timeline's first row: transport, the time shown, and the key at it.
    fn transport_row(&mut self, ui: &mut Ui, time: f64, fps: f64, keys: usize) {
        let at_key = self.key_index_at(time);
        if ui
            .button("⏮")
            .on_hover_text("First key (Shift + ,)")
            .clicked()
        {
            let first = self.keys().first().map_or(0.0, |k| k.time);
            self.timeline.playing = None;
            self.set_time(first);
        }
        if ui.button("⏴").on_hover_text("Previous frame (,)").clicked() {
            self.step_frames(-1);
        }
        let playing = self.timeline.is_playing();
        let label = if playing { "⏸ Pause" } else { "▶ Play" };
        if ui
            .add_enabled(keys >= 2 || playing, egui::Button::new(label))
            .on_hover_text("Play the keys at the project's rate (Space)")
            .clicked()
        {
            self.toggle_play();
        }
        if ui.button("⏵").on_hover_text("Next frame (.)").clicked() {
            self.step_frames(1);
        }
        if ui
            .button("⏭")
            .on_hover_text("Last key (Shift + .)")
            .clicked()
        {
            let last = self.keys().last().map_or(0.0, |k| k.time);
            self.timeline.playing = None;
            self.set_time(last);
        }
        ui.checkbox(&mut self.timeline.looping, "Loop");
        let shown = egui::RichText::new(format!(
            "{time:>8.2} s · frame {:>6}",
            (time * fps).round() as i64
        ))
        .monospace();
        ui.add_sized(
            [TIME_WIDTH, ui.spacing().interact_size.y],
            egui::Label::new(shown).truncate(),
        );
        ui.separator();
        if ui
            .button("Set key")
            .on_hover_text(
                "Key the pose shown at this time (I). Once keys exist, a pose changed at \
                 any time is keyed there",
            )
            .clicked()
        {
            self.set_key();
        }
        if ui
            .add_enabled(at_key.is_some(), egui::Button::new("Delete key"))
            .clicked()
        {
            self.delete_key();
        }
        // Looked up again: the button above may have deleted the key.
        let at_key = self.key_index_at(time);
        let mut hold = at_key
            .and_then(|i| self.keys().get(i))
            .is_some_and(|k| k.hold);
        if ui
            .add_enabled(at_key.is_some(), egui::Checkbox::new(&mut hold, "Hold"))
            .on_hover_text("Keep this key's pose until the next key (no in-between)")
            .changed()
        {
            self.set_hold(hold);
        }
    }

    /// The timeline's second row: the clipboard, interpolation, rate, onion skin and
    /// recording.
    fn keys_row(&mut self, ui: &mut Ui, fps: f64) {
        if ui
            .button("Copy pose")
            .on_hover_text("Copy the pose shown, to paste as a key at another time")
            .clicked()
        {
            self.copy_pose();
        }
        if ui
            .add_enabled(
                self.timeline.clipboard.is_some(),
                egui::Button::new("Paste key"),
            )
            .clicked()
        {
            self.paste_key();
        }
        ui.separator();
        let current = self
            .doc
            .as_ref()
            .and_then(|d| d.project().animation.as_ref())
            .map_or(Interpolation::Linear, |a| a.interpolation);
        let mut chosen = current;
        egui::ComboBox::from_id_salt("interpolation")
            .width(70.0)
            .selected_text(current.label())
            .show_ui(ui, |ui| {
                for i in Interpolation::ALL {
                    ui.selectable_value(&mut chosen, i, i.label());
                }
            })
            .response
            .on_hover_text("Between keys: straight lines, or smooth curves that ease in and out");
        if chosen != current {
            self.set_interpolation(chosen);
        }
        let mut rate = fps;
        let response = ui.add_sized(
            [FIELD_WIDTH, ui.spacing().interact_size.y],
            egui::DragValue::new(&mut rate)
                .range(1.0..=project::animation::MAX_FPS)
                .speed(0.2)
                .max_decimals(3)
                .suffix(" fps"),
        );
        // Typed, or at the end of a drag: one undo step.
        if rate != fps && ((response.changed() && !response.dragged()) || response.drag_stopped()) {
            self.set_fps(rate);
        }
        ui.checkbox(&mut self.timeline.onion, "Onion skin")
            .on_hover_text("Show the previous and next keys' pictures ghosted behind");
        ui.separator();
        let recording = self.timeline.is_recording();
        let record = egui::Button::selectable(recording, "⏺ Record").fill(if recording {
            Color32::from_rgb(150, 30, 30)
        } else {
            Color32::TRANSPARENT
        });
        if ui
            .add(record)
            .on_hover_text(
                "Record the next drag (a handle, cage vertices, or the control cursor of \
                 Perform): every frame of it becomes the animation from this time",
            )
            .clicked()
        {
            self.toggle_record();
        }
        ui.checkbox(&mut self.timeline.keep_every_frame, "Every frame")
            .on_hover_text(
                "Keep a key per recorded frame instead of the fewest keys that replay \
                 the take within the tolerance",
            );
        ui.add_enabled_ui(!self.timeline.keep_every_frame, |ui| {
            ui.add_sized(
                [FIELD_WIDTH + 40.0, ui.spacing().interact_size.y],
                egui::DragValue::new(&mut self.timeline.tolerance)
                    .range(0.05..=20.0)
                    .speed(0.05)
                    .max_decimals(2)
                    .prefix("within ")
                    .suffix(" px"),
            )
            .on_hover_text("How far a recorded take's keys may stray from what was performed");
        });
    }

    /// The strip: ruler, keys, time shown; scrubbing and moving keys.
    fn strip(&mut self, ui: &mut Ui) {
        let (rect, response) =
            ui.allocate_exact_size(vec2(ui.available_width(), 34.0), Sense::click_and_drag());
        response.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Slider, true, "Timeline"));
        let last = self.keys().last().map_or(0.0, |k| k.time);
        let span = (last * 1.2).max(last + 1.0).max(4.0);
        let margin = 10.0;
        let x_of =
            |t: f64| rect.left() + margin + (t / span) as f32 * (rect.width() - 2.0 * margin);
        let t_of =
            |x: f32| f64::from((x - rect.left() - margin) / (rect.width() - 2.0 * margin)) * span;
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 3.0, Color32::from_gray(30));
        // Seconds, and tenths where there is room.
        let per_second = (rect.width() - 2.0 * margin) / span as f32;
        let step = if per_second > 80.0 { 0.1 } else { 1.0 };
        let ticks = (span / step).floor() as usize;
        for i in 0..=ticks {
            let t = i as f64 * step;
            let x = x_of(t);
            let whole = (t - t.round()).abs() < 1e-9;
            let h = if whole { 10.0 } else { 5.0 };
            painter.line_segment(
                [Pos2::new(x, rect.top()), Pos2::new(x, rect.top() + h)],
                Stroke::new(1.0, Color32::from_gray(110)),
            );
            if whole {
                painter.text(
                    Pos2::new(x + 2.0, rect.top() + 1.0),
                    egui::Align2::LEFT_TOP,
                    format!("{t:.0}"),
                    egui::FontId::proportional(10.0),
                    Color32::from_gray(150),
                );
            }
        }
        let y = rect.center().y + 5.0;
        let keys: Vec<(f64, bool)> = self.keys().iter().map(|k| (k.time, k.hold)).collect();
        for (i, &(t, hold)) in keys.iter().enumerate() {
            let x = x_of(t);
            if let Some(&(next, _)) = keys.get(i + 1) {
                let colour = if hold { HELD } else { Color32::from_gray(90) };
                painter.line_segment(
                    [Pos2::new(x, y), Pos2::new(x_of(next), y)],
                    Stroke::new(if hold { 3.0 } else { 1.0 }, colour),
                );
            }
            let r = 6.0;
            let diamond = vec![
                Pos2::new(x, y - r),
                Pos2::new(x + r, y),
                Pos2::new(x, y + r),
                Pos2::new(x - r, y),
            ];
            painter.add(Shape::convex_polygon(
                diamond,
                if hold { HELD } else { KEY },
                Stroke::new(1.0, Color32::BLACK),
            ));
        }
        let x = x_of(self.timeline.time);
        painter.line_segment(
            [Pos2::new(x, rect.top()), Pos2::new(x, rect.bottom())],
            Stroke::new(2.0, PLAYHEAD),
        );
        // A press on a key moves it; elsewhere it scrubs.
        let key_at = |pos: Pos2| {
            keys.iter()
                .position(|&(t, _)| (x_of(t) - pos.x).abs() <= 7.0 && (pos.y - y).abs() <= 9.0)
        };
        if response.drag_started()
            && let Some(pos) = ui.input(|i| i.pointer.press_origin())
            && let Some(i) = key_at(pos)
        {
            self.timeline.playing = None;
            self.timeline.key_drag = self.doc.as_ref().map(|d| (i, d.snapshot()));
        }
        if (response.dragged() || response.clicked())
            && let Some(pos) = response.interact_pointer_pos()
        {
            let t = t_of(pos.x).clamp(0.0, span);
            match self.timeline.key_drag.as_ref().map(|(i, _)| *i) {
                Some(i) => self.drag_key(i, t),
                None => {
                    self.timeline.playing = None;
                    self.set_time(t);
                }
            }
        }
        if response.drag_stopped() {
            self.end_key_drag();
        }
        if response.hovered()
            && let Some(pos) = response.hover_pos()
            && key_at(pos).is_some()
        {
            ui.ctx().set_cursor_icon(egui::CursorIcon::Grab);
        }
    }
}
