//! The cage tool's input: a click draws a vertex, or selects one, or adds one on an
//! edge; a drag moves vertices (at rest or posed) or selects them by box; the keys
//! close, solve, remove and step through vertices.

use egui::{Context, Key, Modifiers, PointerButton, Pos2, Response, Ui};
use glam::DVec2;

use super::{CageDrag, CageState, CageTool, GRAB, edge_at, on_image, vertex_at};
use crate::tool::Host;

impl CageTool {
    /// This frame's pointer input on the canvas (pan with the middle button or Space
    /// is the canvas's).
    pub(super) fn pointer_input(&mut self, host: &mut dyn Host, ui: &Ui, response: &Response) {
        let (modifiers, space) = ui.input(|i| (i.modifiers, i.key_down(Key::Space)));
        let press = ui
            .input(|i| i.pointer.press_origin())
            .or(response.interact_pointer_pos());
        let state = self.state(host.document());
        if response.drag_started_by(PointerButton::Primary)
            && !space
            && let Some(pos) = press
        {
            self.start_drag(host, state, pos, modifiers);
        }
        if response.dragged()
            && !host.panning()
            && let Some(pos) = response.interact_pointer_pos()
        {
            let at = host.viewport().to_image(pos);
            if self.drag.is_some() {
                for (pos, time) in crate::tool::drag_path(host, ui, pos) {
                    host.set_pointer_time(time);
                    let at = host.viewport().to_image(pos);
                    self.drag_to(host, at);
                }
            } else if let Some((_, end, _)) = &mut self.boxing {
                *end = at;
            }
        }
        if response.drag_stopped() {
            self.finish_gesture(host);
        }
        if response.double_clicked_by(PointerButton::Primary) && state == CageState::Drawing {
            if self.draft.as_ref().is_some_and(|d| d.len() >= 3) {
                self.close(host);
            }
        } else if response.clicked_by(PointerButton::Primary)
            && let Some(pos) = response.interact_pointer_pos()
        {
            self.click(host, state, pos, modifiers);
        }
        let hovering_vertex = response
            .hover_pos()
            .is_some_and(|p| vertex_at(host.viewport(), &self.shown(host.document()), p).is_some());
        let cursor = if self.drag.is_some() {
            Some(egui::CursorIcon::Grabbing)
        } else if hovering_vertex {
            Some(egui::CursorIcon::Grab)
        } else if response.hovered() {
            Some(egui::CursorIcon::Crosshair)
        } else {
            None
        };
        if let Some(cursor) = cursor {
            ui.ctx().set_cursor_icon(cursor);
        }
    }

    fn start_drag(
        &mut self,
        host: &mut dyn Host,
        state: CageState,
        pos: Pos2,
        modifiers: Modifiers,
    ) {
        let Some(doc) = host.document() else { return };
        if state == CageState::Drawing {
            // Dragging while drawing pans, as with the Puppet tool.
            host.pan();
            return;
        }
        let points = self.shown(Some(doc));
        let at = host.viewport().to_image(pos);
        match vertex_at(host.viewport(), &points, pos) {
            Some(v) => {
                if !self.selected.contains(&v) {
                    if !modifiers.shift {
                        self.selected.clear();
                    }
                    self.selected.push(v);
                } else {
                    // The grabbed vertex shows its heat map.
                    self.selected.retain(|&i| i != v);
                    self.selected.push(v);
                }
                let vertices = self
                    .selected
                    .iter()
                    .filter_map(|&i| Some((i, *points.get(i)?)))
                    .collect();
                self.drag = Some(CageDrag {
                    vertices,
                    rest: state == CageState::Rest,
                    pointer: at,
                    count: points.len(),
                    before: doc.snapshot(),
                });
            }
            None => self.boxing = Some((at, at, modifiers.shift)),
        }
    }

    /// Moves the dragged vertices so the grabbed one follows the pointer.
    fn drag_to(&self, host: &mut dyn Host, pointer: DVec2) {
        let Some(drag) = &self.drag else { return };
        let Some(doc) = host.document() else { return };
        let mut points = if drag.rest {
            doc.cage_rest()
        } else {
            doc.cage_pose()
        };
        if points.len() != drag.count {
            debug_assert!(false, "the cage changed under a drag");
            return;
        }
        let delta = pointer - drag.pointer;
        let rest = drag.rest;
        for &(i, start) in &drag.vertices {
            points[i] = if rest {
                on_image(Some(doc), start + delta)
            } else {
                start + delta
            };
        }
        set_points(host, rest, &points);
    }

    /// Ends a drag of cage vertices (one undo step if it changed anything) or a box
    /// selection (selecting the vertices inside the box): the app calls it before the
    /// document changes under the gesture.
    pub(crate) fn finish_gesture(&mut self, host: &mut dyn Host) {
        if let Some(drag) = self.drag.take() {
            host.record(drag.before);
        }
        if let Some((a, b, add)) = self.boxing.take() {
            let (lo, hi) = (a.min(b), a.max(b));
            let inside: Vec<usize> = self
                .shown(host.document())
                .iter()
                .enumerate()
                .filter(|(_, p)| p.cmpge(lo).all() && p.cmple(hi).all())
                .map(|(i, _)| i)
                .collect();
            if !add {
                self.selected.clear();
            }
            for i in inside {
                if !self.selected.contains(&i) {
                    self.selected.push(i);
                }
            }
        }
    }

    fn click(&mut self, host: &mut dyn Host, state: CageState, pos: Pos2, modifiers: Modifiers) {
        let viewport = *host.viewport();
        let at = on_image(host.document(), viewport.to_image(pos));
        match state {
            CageState::Drawing => {
                let near = |p: &DVec2| viewport.to_screen(*p).distance(pos) < GRAB;
                let draft = self.draft.get_or_insert_with(Vec::new);
                if draft.len() >= 3 && draft.first().is_some_and(near) {
                    self.close(host);
                } else if !draft.iter().any(near) {
                    // A click on a vertex already drawn adds none on top of it.
                    draft.push(at);
                }
            }
            CageState::Rest | CageState::Posed => {
                let points = self.shown(host.document());
                if let Some(v) = vertex_at(&viewport, &points, pos) {
                    if modifiers.alt && state == CageState::Rest {
                        self.selected = vec![v];
                        self.delete_vertices(host);
                    } else if modifiers.shift && self.selected.contains(&v) {
                        self.selected.retain(|&i| i != v);
                    } else {
                        if !modifiers.shift {
                            self.selected.clear();
                        }
                        self.selected.retain(|&i| i != v);
                        self.selected.push(v);
                    }
                } else if state == CageState::Rest
                    && let Some((edge, p)) = edge_at(&viewport, &points, pos)
                {
                    let mut rest = points;
                    rest.insert(edge + 1, on_image(host.document(), p));
                    if self.set_rest(host, rest) {
                        self.selected = vec![edge + 1];
                    }
                } else if !modifiers.shift {
                    self.selected.clear();
                }
            }
        }
    }

    /// The tool's keys (see [`crate::tool::CanvasTool::keys`]).
    pub(super) fn key_input(&mut self, host: &mut dyn Host, ctx: &Context) {
        let pressed = |modifiers, key| {
            ctx.input_mut(|i| i.consume_shortcut(&egui::KeyboardShortcut::new(modifiers, key)))
        };
        let none = Modifiers::NONE;
        let state = self.state(host.document());
        if pressed(none, Key::Enter) {
            match state {
                CageState::Drawing => self.close(host),
                CageState::Rest => self.solve(host),
                CageState::Posed => {}
            }
        }
        if pressed(none, Key::Delete) || pressed(none, Key::Backspace) {
            if state == CageState::Drawing {
                if let Some(draft) = &mut self.draft {
                    draft.pop();
                }
            } else {
                self.delete_vertices(host);
            }
        }
        if pressed(none, Key::Escape) {
            self.finish_gesture(host);
            self.draft = None;
            self.selected.clear();
        }
        let count = self.shown(host.document()).len();
        if count > 0 {
            let focus = self.focus();
            let next = if pressed(Modifiers::SHIFT, Key::N) {
                Some(focus.map_or(count - 1, |s| (s + count - 1) % count))
            } else if pressed(none, Key::N) {
                Some(focus.map_or(0, |s| (s + 1) % count))
            } else {
                None
            };
            if let Some(next) = next {
                self.selected = vec![next];
            }
        }
    }
}

/// Sets the cage's rest vertices (the pose goes back to rest) or its pose, without an
/// undo step (the gesture makes one when it ends).
fn set_points(host: &mut dyn Host, rest: bool, points: &[DVec2]) {
    let Some(doc) = host.document() else { return };
    let mut project = doc.project().clone();
    let Some(cage) = &mut project.cage else {
        return;
    };
    let points: Vec<[f64; 2]> = points.iter().map(|p| p.to_array()).collect();
    if rest {
        cage.rest = points;
        cage.pose = None;
    } else {
        cage.pose = (points != cage.rest).then_some(points);
    }
    host.preview(project);
}
