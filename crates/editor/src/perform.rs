//! The perform tool: spatial keyframing (Igarashi, Moscovich and Hughes 2005, §5.3).
//! Key poses are placed at markers on the canvas; dragging the control cursor shows,
//! at every instant, the radial-basis blend of the key poses at the cursor
//! ([`animation::SpatialBlend`]). With recording armed, the drag becomes keys in time.

use egui::{Color32, CursorIcon, Painter, PointerButton, Pos2, Response, Shape, Stroke, Ui};
use glam::DVec2;
use project::{Pose, Project, SpatialKey};

use crate::document::Edit;
use crate::tool::{CanvasTool, Host};

/// How close the pointer must be to grab a marker, screen points.
const GRAB: f32 = 10.0;
const MARKER: Color32 = Color32::from_rgb(250, 210, 40);
const CURSOR: Color32 = Color32::from_rgb(235, 60, 50);

/// The perform tool's state.
#[derive(Default)]
pub struct PerformTool {
    /// Where the control cursor is, image pixels (`None` until first placed).
    pub cursor: Option<DVec2>,
    /// The next click on the canvas places a marker for the pose shown.
    pub placing: bool,
    drag: Option<Drag>,
    /// The blend of the markers it was made for.
    blend: Option<(Vec<[f64; 2]>, animation::SpatialBlend)>,
}

/// A drag under way.
struct Drag {
    /// The rig file before it (the drag is one undo step).
    before: Project,
    /// Which marker moves; `None`: the control cursor.
    marker: Option<usize>,
}

impl PerformTool {
    /// The pose markers (spatial keys) of `host`'s document.
    fn markers(host: &dyn Host) -> Vec<[f64; 2]> {
        host.document()
            .and_then(|d| d.project().animation.as_ref())
            .map(|a| a.spatial_keys.iter().map(|k| k.at).collect())
            .unwrap_or_default()
    }

    /// The marker under screen point `pos`, if any.
    fn hit(host: &dyn Host, pos: Pos2) -> Option<usize> {
        Self::markers(host)
            .iter()
            .map(|&at| host.viewport().to_screen(DVec2::from(at)).distance(pos))
            .enumerate()
            .filter(|&(_, d)| d <= GRAB)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    }

    /// The blend's pose with the cursor at `at` (image pixels).
    fn blended(&mut self, project: &Project, at: DVec2) -> Option<Pose> {
        let markers: Vec<[f64; 2]> = project
            .animation
            .as_ref()?
            .spatial_keys
            .iter()
            .map(|k| k.at)
            .collect();
        if self.blend.as_ref().is_none_or(|(m, _)| *m != markers) {
            self.blend = animation::SpatialBlend::new(&markers).map(|b| (markers, b));
        }
        self.blend.as_ref()?.1.pose(project, at.to_array())
    }

    /// Places a marker at `at` for the pose shown (one undo step); on an existing
    /// marker, gives it the pose shown instead.
    pub(crate) fn place(&mut self, host: &mut dyn Host, at: DVec2) {
        let Some(doc) = host.document() else { return };
        let pose = Pose::of(doc.project());
        let mut animation = doc.project().animation.clone().unwrap_or_default();
        let near = animation
            .spatial_keys
            .iter()
            .position(|k| DVec2::from(k.at).distance(at) < project::animation::MIN_MARKER_DISTANCE);
        let what = match near {
            Some(i) => {
                animation.spatial_keys[i].pose = pose;
                format!("marker {} takes the pose shown", i + 1)
            }
            None => {
                animation.spatial_keys.push(SpatialKey {
                    at: at.to_array(),
                    pose,
                });
                format!(
                    "marker {} placed for the pose shown: pose the handles again and place \
                     another, then drag the control cursor between them",
                    animation.spatial_keys.len()
                )
            }
        };
        self.placing = false;
        if host.edit(Edit::Animation(Some(Box::new(animation)))) {
            host.info(&what);
        }
    }

    /// Deletes marker `index` (one undo step).
    pub(crate) fn delete(&mut self, host: &mut dyn Host, index: usize) {
        let Some(doc) = host.document() else { return };
        let Some(mut animation) = doc.project().animation.clone() else {
            return;
        };
        if index >= animation.spatial_keys.len() {
            return;
        }
        animation.spatial_keys.remove(index);
        let keep = !animation.is_empty();
        if host.edit(Edit::Animation(keep.then(|| Box::new(animation)))) {
            host.info(&format!("marker {} deleted", index + 1));
        }
    }

    /// Moves the control cursor to `at` and shows the blend there (a preview: the
    /// drag's end makes the undo step).
    pub(crate) fn drive(&mut self, host: &mut dyn Host, at: DVec2) {
        self.cursor = Some(at);
        let Some(doc) = host.document() else { return };
        let mut project = doc.project().clone();
        let Some(pose) = self.blended(&project, at) else {
            return;
        };
        pose.apply(&mut project);
        host.preview(project);
    }
}

impl CanvasTool for PerformTool {
    fn input(&mut self, host: &mut dyn Host, ui: &Ui, response: &Response) {
        let (modifiers, space) = ui.input(|i| (i.modifiers, i.key_down(egui::Key::Space)));
        let press = ui
            .input(|i| i.pointer.press_origin())
            .or(response.interact_pointer_pos());
        if response.hovered() {
            let over = response
                .hover_pos()
                .and_then(|p| Self::hit(host, p))
                .is_some();
            ui.ctx().set_cursor_icon(if self.placing || modifiers.ctrl {
                CursorIcon::Cell
            } else if over {
                CursorIcon::Grab
            } else {
                CursorIcon::Crosshair
            });
        }
        if response.clicked_by(PointerButton::Primary)
            && let Some(pos) = response.interact_pointer_pos()
        {
            let at = host.viewport().to_image(pos);
            if self.placing || modifiers.command {
                self.place(host, at);
            } else if Self::markers(host).is_empty() {
                host.info(
                    "no pose markers yet: pose the handles, then Place marker (or Ctrl + click) \
                     where that pose should be",
                );
            } else {
                let before = host.document().map(|d| d.project().clone());
                self.drive(host, at);
                if let Some(before) = before {
                    host.record(before);
                }
            }
        }
        if response.secondary_clicked()
            && let Some(pos) = response.interact_pointer_pos()
            && let Some(i) = Self::hit(host, pos)
        {
            self.delete(host, i);
        }
        if response.drag_started_by(PointerButton::Primary)
            && !space
            && !host.panning()
            && let Some(pos) = press
            && let Some(doc) = host.document()
        {
            let marker = Self::hit(host, pos);
            if marker.is_none() && Self::markers(host).is_empty() {
                host.info("place two pose markers or more, then drag the control cursor");
            } else {
                self.drag = Some(Drag {
                    before: doc.project().clone(),
                    marker,
                });
            }
        }
        if response.dragged()
            && let Some(pos) = response.interact_pointer_pos()
            && let Some(drag) = &self.drag
        {
            let at = host.viewport().to_image(pos);
            match drag.marker {
                None => {
                    for (pos, time) in crate::tool::drag_path(host, ui, pos) {
                        host.set_pointer_time(time);
                        let at = host.viewport().to_image(pos);
                        self.drive(host, at);
                    }
                }
                Some(i) => {
                    // Not a live pose (no take starts): the marker moves, kept apart
                    // from the others.
                    if let Some(doc) = host.document_mut() {
                        let mut project = doc.project().clone();
                        if let Some(animation) = &mut project.animation
                            && i < animation.spatial_keys.len()
                            && animation.spatial_keys.iter().enumerate().all(|(j, k)| {
                                j == i
                                    || DVec2::from(k.at).distance(at)
                                        >= project::animation::MIN_MARKER_DISTANCE
                            })
                        {
                            animation.spatial_keys[i].at = at.to_array();
                            if let Err(e) = doc.restore(project) {
                                host.error(&e);
                            }
                        }
                    }
                }
            }
        }
        if response.drag_stopped()
            && let Some(drag) = self.drag.take()
        {
            host.record(drag.before);
        }
    }

    fn paint(&mut self, host: &mut dyn Host, painter: &Painter, _: Option<Pos2>, active: bool) {
        let markers = Self::markers(host);
        let weights = match (self.cursor, self.blend.as_ref()) {
            (Some(at), Some((m, blend))) if *m == markers => blend.weights(at.to_array()),
            _ => Vec::new(),
        };
        let alpha = if active { 255 } else { 110 };
        let font = egui::FontId::proportional(12.0);
        for (i, &at) in markers.iter().enumerate() {
            let p = host.viewport().to_screen(DVec2::from(at));
            let r = 7.0;
            let diamond = vec![
                p + egui::vec2(0.0, -r),
                p + egui::vec2(r, 0.0),
                p + egui::vec2(0.0, r),
                p + egui::vec2(-r, 0.0),
            ];
            let fill = Color32::from_rgba_unmultiplied(MARKER.r(), MARKER.g(), MARKER.b(), alpha);
            painter.add(Shape::convex_polygon(
                diamond,
                fill,
                Stroke::new(1.5, Color32::BLACK),
            ));
            let label = match weights.get(i) {
                Some(w) if active => format!("{} · {:.0}%", i + 1, 100.0 * w),
                _ => format!("{}", i + 1),
            };
            painter.text(
                p + egui::vec2(9.0, -9.0),
                egui::Align2::LEFT_BOTTOM,
                label,
                font.clone(),
                fill,
            );
        }
        if active && let Some(at) = self.cursor {
            let p = host.viewport().to_screen(at);
            painter.circle(p, 8.0, CURSOR, Stroke::new(2.0, Color32::WHITE));
            painter.line_segment(
                [p - egui::vec2(12.0, 0.0), p + egui::vec2(12.0, 0.0)],
                Stroke::new(1.5, CURSOR),
            );
            painter.line_segment(
                [p - egui::vec2(0.0, 12.0), p + egui::vec2(0.0, 12.0)],
                Stroke::new(1.5, CURSOR),
            );
        }
    }

    fn panel(&mut self, host: &mut dyn Host, ui: &mut Ui) {
        let markers = Self::markers(host);
        ui.label(
            "Spatial keyframing: each marker holds a pose; drag the red control cursor \
             to blend the poses of the markers near it.",
        );
        ui.horizontal_wrapped(|ui| {
            if ui
                .add(egui::Button::selectable(self.placing, "Place marker"))
                .on_hover_text(
                    "The next click on the canvas places a marker holding the pose shown \
                     (Ctrl + click does it at once; on a marker, it takes the pose shown)",
                )
                .clicked()
            {
                self.placing = !self.placing;
            }
            if ui
                .add_enabled(!markers.is_empty(), egui::Button::new("Clear markers"))
                .clicked()
                && let Some(doc) = host.document()
                && let Some(mut animation) = doc.project().animation.clone()
            {
                animation.spatial_keys.clear();
                let keep = !animation.is_empty();
                if host.edit(Edit::Animation(keep.then(|| Box::new(animation)))) {
                    host.info("pose markers cleared");
                }
            }
        });
        match markers.len() {
            0 => ui.label("No markers: pose the handles, then place one."),
            1 => ui.label("1 marker: place another for another pose."),
            n => ui.label(format!(
                "{n} markers: drag anywhere to perform; drag a marker to move it; right-click \
                 one to delete it."
            )),
        };
    }

    fn cancel(&mut self) {
        self.placing = false;
    }
}

/// Whether a drag of the perform tool is under way (the canvas keeps its fit).
impl PerformTool {
    pub(crate) fn dragging(&self) -> bool {
        self.drag.is_some()
    }

    /// Ends a drag under way as its undo step (the document is about to change).
    pub(crate) fn finish_gesture(&mut self, host: &mut dyn Host) {
        if let Some(drag) = self.drag.take() {
            host.record(drag.before);
        }
    }
}
