//! The handle tools' pointer input: adding, selecting, dragging and deleting handles,
//! drawing a bar, the right-click menu, and the cursor.

use egui::{CursorIcon, Key, PointerButton, Pos2, Response, Ui};
use glam::DVec2;
use project::HandleSpec;

use super::{Grip, HandleDrag, HandleTool};
use crate::document::posed;
use crate::tool::{Host, Tool};

/// How close the pointer must be to grab a handle, screen points.
pub(super) const GRAB: f32 = 9.0;
/// Radius of the rotation ring around a point handle (shown on the selected one and
/// the one under the pointer), screen points.
pub(super) const RING: f32 = 26.0;
/// The shortest lever a turn or a scale is measured with, screen points: a drag that
/// starts nearer a handle's centre turns and scales it as if it had started this far
/// out (farther out, the turn follows the pointer around the centre).
const LEVER: f32 = RING / 2.0;
/// Screen points of drag, away from a handle's centre, that double its scale (towards
/// it, halve it): scaling is exponential in the drag's length wherever it starts.
const SCALE_DOUBLING: f64 = 100.0;

impl HandleTool {
    /// This frame's pointer input (see [`crate::tool::CanvasTool::input`]).
    pub(super) fn pointer_input(&mut self, host: &mut dyn Host, ui: &Ui, response: &Response) {
        let tool = host.tool();
        let (modifiers, space) = ui.input(|i| (i.modifiers, i.key_down(Key::Space)));
        let press = ui
            .input(|i| i.pointer.press_origin())
            .or(response.interact_pointer_pos());
        if tool == Tool::AddBar {
            self.bar_input(host, ui, response);
        }
        // A drag the canvas made a pan (the middle button, or Space) is not the tool's.
        let canvas_pans = response.drag_started_by(PointerButton::Middle)
            || (response.drag_started_by(PointerButton::Primary) && space);
        if !canvas_pans
            && response.drag_started_by(PointerButton::Primary)
            && matches!(tool, Tool::Puppet | Tool::Select | Tool::AddPoint)
            && let Some(pos) = press
        {
            // With Alt, a drag anywhere on or inside a point handle's ring turns it.
            let turn = modifiers
                .alt
                .then(|| self.rotation_target(host, pos))
                .flatten()
                .map(|i| (i, Grip::Rotate));
            match turn.or_else(|| self.hit(host, pos)) {
                Some((index, grip)) => self.start_drag(host, index, grip, pos, modifiers),
                None => {
                    if matches!(tool, Tool::Puppet | Tool::Select) {
                        host.pan();
                    }
                }
            }
        }
        if response.dragged()
            && !host.panning()
            && let Some(pos) = response.interact_pointer_pos()
        {
            for (pos, time) in crate::tool::drag_path(host, ui, pos) {
                host.set_pointer_time(time);
                let at = host.viewport().to_image(pos);
                self.drag_to(host, at);
            }
        }
        let stopped = response.drag_stopped();
        if stopped && let Some(drag) = self.drag.take() {
            host.record(drag.before);
        }
        if response.clicked_by(PointerButton::Primary)
            && let Some(pos) = response.interact_pointer_pos()
        {
            self.click(host, pos, modifiers.alt);
        }
        if tool == Tool::Cage {
            // The cage tool sets its own cursor and has no handle menu.
            return;
        }
        if response.secondary_clicked()
            && let Some(pos) = response.interact_pointer_pos()
        {
            let selected = self.hit(host, pos).map(|(i, _)| i);
            host.select(selected);
            self.context_point = Some(host.viewport().to_image(pos));
            self.context_handle = selected.and_then(|i| {
                let handle = host.document()?.project().handles.get(i)?.clone();
                Some((i, handle))
            });
        }
        response.context_menu(|ui| self.context_menu(host, ui));
        // The canvas ends a pan when the drag stops, after this.
        let panning = host.panning() && !stopped;
        let cursor = if panning || self.drag.is_some() {
            Some(CursorIcon::Grabbing)
        } else if response
            .hover_pos()
            .and_then(|p| self.hit(host, p))
            .is_some()
        {
            Some(CursorIcon::Grab)
        } else if matches!(tool, Tool::AddPoint | Tool::AddBar | Tool::Rigidity)
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

    /// A primary click at `pos` (screen): selects the handle there (Alt: deletes it),
    /// else adds a point handle or deselects, as the tool calls for.
    fn click(&mut self, host: &mut dyn Host, pos: Pos2, alt: bool) {
        let hit = self.hit(host, pos).map(|(i, _)| i);
        match (host.tool(), hit) {
            (Tool::AddBar | Tool::Rigidity | Tool::Cut | Tool::Cage | Tool::Perform, _) => {}
            (_, Some(i)) if alt => {
                // The Puppet Warp convention: Alt-click deletes a handle.
                host.select(Some(i));
                self.delete_selected(host);
            }
            (_, Some(i)) => host.select(Some(i)),
            (Tool::Puppet, None) => {
                let at = host.viewport().to_image(pos);
                if on_picture(host, at) && alt {
                    // Drawn as parts: on the part under the pointer alone.
                    self.add_point_alone(host, at);
                } else if on_picture(host, at) {
                    self.add_point(host, at);
                } else {
                    // Off the picture a click deselects; say so, as a pin was
                    // probably meant.
                    host.select(None);
                    host.info("no picture under the pointer: nothing pinned");
                }
            }
            (Tool::Select, None) => host.select(None),
            (Tool::AddPoint, None) => {
                let at = host.viewport().to_image(pos);
                if alt {
                    self.add_point_alone(host, at);
                } else {
                    self.add_point(host, at);
                }
            }
        }
    }

    /// The bar tool, from the pointer's own press and release rather than egui's drag
    /// detection: a quick stroke (press, a big move and release within a frame or
    /// two) is a bar too, not a click that does nothing.
    fn bar_input(&mut self, host: &mut dyn Host, ui: &Ui, response: &Response) {
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
            self.bar_start = Some(host.viewport().to_image(origin));
        }
        if released && let Some(a) = self.bar_start.take() {
            let Some(end) = latest else { return };
            if host.viewport().to_screen(a).distance(end) > 4.0 {
                let b = host.viewport().to_image(end);
                self.add_bar(host, a, b);
            } else {
                host.info("to add a bar, drag from one end of it to the other");
            }
        }
    }

    /// The handle under `pos` (screen), and which grip: a handle itself (a point's
    /// dot, a bar's ends or body), else the rotation ring of a point handle (every
    /// point handle's ring shows when the pointer is over it, so a drag from it turns
    /// that handle, and never pans).
    pub(super) fn hit(&self, host: &dyn Host, pos: Pos2) -> Option<(usize, Grip)> {
        let doc = host.document()?;
        let viewport = host.viewport();
        let mut best: Option<(f32, usize, Grip)> = None;
        let mut ring: Option<(f32, usize)> = None;
        let mut consider = |d: f32, i: usize, grip: Grip| {
            if d < GRAB && best.is_none_or(|(bd, _, _)| d < bd) {
                best = Some((d, i, grip));
            }
        };
        for (i, h) in doc.project().handles.iter().enumerate() {
            let [a, b] = posed(h).map(|p| viewport.to_screen(p));
            match h {
                HandleSpec::Point { .. } => {
                    let d = a.distance(pos);
                    consider(d, i, Grip::Move);
                    let off = (d - RING).abs();
                    if off < GRAB && ring.is_none_or(|(bd, _)| off < bd) {
                        ring = Some((off, i));
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
            .or(ring.map(|(_, i)| (i, Grip::Rotate)))
    }

    /// The point handle a drag from `pos` with Alt held turns: the nearest one whose
    /// rotation ring (or anything inside it) is under the pointer, as in Puppet Warp.
    pub(super) fn rotation_target(&self, host: &dyn Host, pos: Pos2) -> Option<usize> {
        let doc = host.document()?;
        let viewport = host.viewport();
        doc.project()
            .handles
            .iter()
            .enumerate()
            .filter(|(_, h)| matches!(h, HandleSpec::Point { .. }))
            .map(|(i, h)| (i, viewport.to_screen(posed(h)[0]).distance(pos)))
            .filter(|&(_, d)| d < RING + GRAB)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    }

    /// The right-click menu. It stays open across frames, so it acts on the handle it
    /// was opened on only if that handle is still where it was (an undo or a new
    /// document may have changed the list since).
    fn context_menu(&mut self, host: &mut dyn Host, ui: &mut Ui) {
        if let Some((i, opened_on)) = self.context_handle.clone() {
            let still_there = host
                .document()
                .and_then(|d| d.project().handles.get(i))
                .is_some_and(|h| crate::document::same_rest(h, &opened_on));
            if !still_there {
                ui.label("(this handle is gone)");
                return;
            }
            if ui.button("Delete handle").clicked() {
                host.select(Some(i));
                self.delete_selected(host);
                ui.close();
            }
            if ui.button("Reset handle pose").clicked() {
                let rest = opened_on.at_rest();
                let _ = self.edit(host, crate::document::Edit::Pose(i, rest));
                ui.close();
            }
            ui.separator();
            if ui.button("Bring forward").clicked() {
                self.change_depth(host, i, 1);
                ui.close();
            }
            if ui.button("Send backward").clicked() {
                self.change_depth(host, i, -1);
                ui.close();
            }
        } else if let Some(at) = self.context_point
            && ui.button("Add point handle here").clicked()
        {
            self.add_point(host, at);
            ui.close();
        }
    }

    fn start_drag(
        &mut self,
        host: &mut dyn Host,
        index: usize,
        grip: Grip,
        pos: Pos2,
        modifiers: egui::Modifiers,
    ) {
        let Some(doc) = host.document() else { return };
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
        let before = doc.snapshot();
        let pointer = host.viewport().to_image(pos);
        host.select(Some(index));
        self.drag = Some(HandleDrag {
            index,
            grip,
            start,
            pointer,
            before,
        });
    }

    /// Moves the dragged handle so the grabbed point follows the pointer; a turn or a
    /// scale changes by an amount proportional to the drag, wherever it started.
    fn drag_to(&mut self, host: &mut dyn Host, pointer: DVec2) {
        let Some(drag) = &mut self.drag else { return };
        let [a, b] = posed(&drag.start);
        let centre = (a + b) * 0.5;
        // Image pixels a screen point.
        let pixel = 1.0 / f64::from(host.viewport().zoom.max(1e-6));
        if matches!(drag.grip, Grip::Rotate | Grip::Scale) {
            // A turn or a scale started on the centre has no direction yet: it is
            // measured from where the pointer first is a few screen points away.
            let near = 4.0 * pixel;
            if (drag.pointer - centre).length() < near {
                if (pointer - centre).length() >= near {
                    drag.pointer = pointer;
                }
                return;
            }
        }
        let delta = pointer - drag.pointer;
        // The lever a turn and a scale are measured with: from the centre to where the
        // drag started, at least LEVER long, so that a short drag near the centre makes
        // a small change, not a half turn.
        let outwards = (drag.pointer - centre).normalize_or(DVec2::X);
        let lever = outwards
            * (drag.pointer - centre)
                .length()
                .max(f64::from(LEVER) * pixel);
        let turn = angle_between(lever, lever + delta);
        let stretch = (std::f64::consts::LN_2 * delta.dot(outwards) / pixel / SCALE_DOUBLING).exp();
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
                    Grip::Scale => {
                        // No shorter than a hundredth of a pixel.
                        let stretch = stretch.max(0.01 / (b - a).length().max(1e-9));
                        [
                            centre + (a - centre) * stretch,
                            centre + (b - centre) * stretch,
                        ]
                    }
                };
                HandleSpec::Bar {
                    rest,
                    pose: Some(pose.map(|p| p.to_array())),
                    depth,
                }
            }
        };
        let index = drag.index;
        Self::set_pose(host, index, handle);
    }
}

/// Whether image point `at` (in the current pose) shows the picture.
fn on_picture(host: &mut dyn Host, at: DVec2) -> bool {
    host.document_mut()
        .is_some_and(|doc| doc.unwarp(at).is_some())
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
