//! The handle tools — puppet, select, add point, add bar ([`Tool::Puppet`],
//! [`Tool::Select`], [`Tool::AddPoint`], [`Tool::AddBar`]) — as one tool: click to add
//! or select a point handle, drag a handle to move it (Alt turns, Shift scales), drag
//! out a bar, right-click a handle for its menu.
//!
//! [`HandleTool`] owns the gesture under way (a drag, a bar being drawn, what the
//! right-click menu was opened on) and sees the editor through [`Host`]; the selected
//! handle is the editor's ([`Host::selected`]), as the panel, the keys and the GPU's
//! heat map read it too. Its pointer input is in `input`, what it draws over the
//! canvas in `paint`.

mod input;
mod paint;
mod status;

use egui::{Painter, Pos2, Response, Ui};
use glam::DVec2;
use project::HandleSpec;

use crate::document::{Document, Edit, posed, unmoved};
use crate::tool::{CanvasTool, Host, Tool};

/// A drag of a handle in progress.
#[derive(Clone, Debug)]
struct HandleDrag {
    index: usize,
    grip: Grip,
    /// The handle when the drag began.
    start: HandleSpec,
    /// The pointer when the drag began (image pixels).
    pointer: DVec2,
    /// The document before the drag, recorded in the history if the drag changed it.
    before: project::Project,
}

/// What part of a handle is being dragged, and how.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Grip {
    /// Move the whole handle.
    Move,
    /// Move one end of a bar.
    End(usize),
    /// Rotate about the handle's centre.
    Rotate,
    /// Scale about the handle's centre.
    Scale,
}

/// The handle tools: the drag under way, the bar being drawn, and what the right-click
/// menu was opened on (none of it is saved).
#[derive(Clone, Debug, Default)]
pub struct HandleTool {
    drag: Option<HandleDrag>,
    /// Where the bar being drawn starts (image pixels).
    bar_start: Option<DVec2>,
    /// Where the right-click menu was opened (image pixels).
    context_point: Option<DVec2>,
    /// The handle the right-click menu was opened on, and its index then.
    context_handle: Option<(usize, HandleSpec)>,
}

impl HandleTool {
    /// Whether a handle is being dragged.
    pub fn dragging(&self) -> bool {
        self.drag.is_some()
    }

    /// Ends the gesture under way — a handle drag (one undo step if it changed
    /// anything) or a bar being drawn — because the document is about to change under
    /// it.
    pub(crate) fn finish_gesture(&mut self, host: &mut dyn Host) {
        if let Some(drag) = self.drag.take() {
            host.record(drag.before);
        }
        self.bar_start = None;
    }

    /// Applies `edit` through the host, ending this tool's own gesture first as the
    /// host would (it cannot while the tool is lent out); whether it was applied.
    fn edit(&mut self, host: &mut dyn Host, edit: Edit) -> bool {
        // The host refuses an edit while busy, before it ends any gesture.
        if !host.busy() {
            self.finish_gesture(host);
        }
        host.edit(edit)
    }

    /// The tool's invariants in `doc` with `tool` active: the drag holds a handle that
    /// exists, and a bar is drawn only with the bar tool.
    ///
    /// # Errors
    /// The first broken invariant, in words.
    pub(crate) fn sanity_check(&self, doc: Option<&Document>, tool: Tool) -> anyhow::Result<()> {
        let Some(doc) = doc else {
            if self.drag.is_some() {
                anyhow::bail!("a selection or drag without a document");
            }
            return Ok(());
        };
        let handles = &doc.project().handles;
        if let Some(drag) = &self.drag {
            match handles.get(drag.index) {
                Some(h) if crate::document::same_rest(h, &drag.start) => {}
                _ => anyhow::bail!("the drag holds handle {}, which is gone", drag.index),
            }
        }
        if self.bar_start.is_some() && tool != Tool::AddBar {
            anyhow::bail!("a bar is being drawn with the {tool:?} tool");
        }
        Ok(())
    }

    /// Adds a point handle under `at` (image pixels, current pose) and selects it: its
    /// rest position is the point of the picture shown there, and it starts with the
    /// rotation and scale the pose has around it ([`Document::local_pose`]).
    pub(crate) fn add_point(&mut self, host: &mut dyn Host, at: DVec2) {
        if let Some(handle) = point_under(host, at) {
            self.add_and_select(host, Edit::Add(handle), "a point handle");
        }
    }

    /// Adds a point handle under `at` as [`HandleTool::add_point`] does, bound to the
    /// part shown there alone (the topmost) rather than to every part under it:
    /// Alt-click with the layers drawn as parts (otherwise a plain point handle).
    pub(crate) fn add_point_alone(&mut self, host: &mut dyn Host, at: DVec2) {
        let Some(part) = host.document_mut().and_then(|doc| doc.part_at(at)) else {
            return self.add_point(host, at);
        };
        let Some(handle) = point_under(host, at) else {
            return;
        };
        let name = (host.document().and_then(|d| d.layers.as_ref()))
            .map_or_else(String::new, |l| l.layers[part].name.clone());
        let what = format!("a point handle on {name} alone");
        self.add_and_select(host, Edit::AddBound(handle, part), &what);
    }

    /// Adds a bar from `a` to `b` (image pixels, current pose) and selects it.
    pub(crate) fn add_bar(&mut self, host: &mut dyn Host, a: DVec2, b: DVec2) {
        let Some(doc) = host.document_mut() else {
            return;
        };
        let (Some((ra, _, _)), Some((rb, _, _))) = (doc.unwarp(a), doc.unwarp(b)) else {
            host.error(&anyhow::anyhow!("a bar must start and end on the picture"));
            return;
        };
        let (ra, rb) = (unmoved(ra, a), unmoved(rb, b));
        let handle = HandleSpec::Bar {
            rest: [ra.to_array(), rb.to_array()],
            pose: Some([a.to_array(), b.to_array()]),
            depth: 0,
        };
        self.add_and_select(host, Edit::Add(handle), "a bar handle");
    }

    /// Adds `handle` (one undo step), selects it and says so, naming it `what`.
    fn add_and_select(&mut self, host: &mut dyn Host, add: Edit, what: &str) {
        if self.edit(host, add)
            && let Some(doc) = host.document()
        {
            let (count, ms) = (doc.project().handles.len(), doc.last_update_ms);
            host.select(Some(count - 1));
            host.info(&format!("added {what}; weights updated in {ms:.1} ms"));
        }
    }

    /// Deletes the selected handle.
    pub(crate) fn delete_selected(&mut self, host: &mut dyn Host) {
        if let Some(i) = host.selected()
            && self.edit(host, Edit::Remove(i))
            && let Some(doc) = host.document()
        {
            let ms = doc.last_update_ms;
            // In a pose, what it moved lets go and the picture away from it keeps its
            // shape (carried where the method alone would move it).
            let kept = if doc.project().is_posed() && !doc.project().carried.is_empty() {
                "; what it moved let go, the rest kept its shape"
            } else {
                ""
            };
            host.info(&format!(
                "removed a handle{kept}; weights updated in {ms:.1} ms"
            ));
        }
    }

    /// Moves handle `index` `by` steps forward in the overlap order (negative:
    /// backward). One undo step.
    pub(crate) fn change_depth(&mut self, host: &mut dyn Host, index: usize, by: i32) {
        let Some(handle) = host.document().and_then(|d| d.project().handles.get(index)) else {
            return;
        };
        let depth = handle.depth().saturating_add(by);
        let moved = handle.with_depth(depth);
        if self.edit(host, Edit::Pose(index, moved)) {
            host.info(&format!("handle {} now has depth {depth}", index + 1));
        }
    }

    /// Shows handle `index` posed as `handle` during a drag (no undo step; the drag
    /// makes one when it ends). With auto-rotation, other point handles turn with
    /// their neighbours.
    fn set_pose(host: &mut dyn Host, index: usize, handle: HandleSpec) {
        let Some(doc) = host.document() else { return };
        let mut project = doc.project().clone();
        let Some(slot) = project.handles.get_mut(index) else {
            debug_assert!(false, "the dragged handle {index} is gone");
            return;
        };
        // A drag poses its own handle; one at another rest means the index went stale.
        let own = crate::document::same_rest(slot, &handle);
        debug_assert!(own, "a drag may not move handle {index} at rest");
        if !own {
            return;
        }
        *slot = handle;
        if host.auto_rotate() {
            auto_rotate(&mut project.handles);
        }
        host.preview(project);
    }

    /// The selected handle: where it is, how it is posed, its overlap depth.
    fn handle_section(&mut self, host: &mut dyn Host, ui: &mut Ui) {
        let mut forward = None;
        let mut toggled = None;
        if let Some(i) = host.selected()
            && let Some(doc) = host.document()
            && let Some(h) = doc.project().handles.get(i)
        {
            ui.separator();
            ui.heading(format!("Handle {}", i + 1));
            let depth = h.depth();
            // Wrapped, so selecting a handle never widens the panel (which would
            // shrink the canvas and refit the view under the pointer mid-drag).
            ui.horizontal_wrapped(|ui| {
                ui.label(format!("depth {depth}"))
                    .on_hover_text("Where the warped picture overlaps itself, handles of greater depth are in front");
                if ui.button("Bring forward").clicked() {
                    forward = Some(1);
                }
                if ui.button("Send backward").clicked() {
                    forward = Some(-1);
                }
                let mut automatic = doc.project().auto_depth;
                if ui
                    .checkbox(&mut automatic, "Automatic depth")
                    .on_hover_text(
                        "Where the warped picture overlaps itself, each overlap is drawn \
                         wholly in front or wholly behind (by the depths when it appears) \
                         and keeps its order while it lasts (the ARAP paper's §5.1)",
                    )
                    .changed()
                {
                    toggled = Some(automatic);
                }
            });
            match h {
                HandleSpec::Point {
                    rest,
                    translate,
                    rotate,
                    scale,
                    ..
                } => {
                    ui.label(format!("point at ({:.1}, {:.1})", rest[0], rest[1]));
                    // No "-0.0" for a move that rounds to nothing.
                    let tidy = |v: f64| if v.abs() < 0.05 { 0.0 } else { v };
                    ui.label(format!(
                        "moved by ({:.1}, {:.1})",
                        tidy(translate[0]),
                        tidy(translate[1])
                    ));
                    ui.label(format!(
                        "rotated {:.1}°, scaled {:.2}×",
                        rotate.to_degrees(),
                        scale
                    ));
                }
                HandleSpec::Bar { rest, .. } => {
                    ui.label(format!(
                        "bar from ({:.1}, {:.1}) to ({:.1}, {:.1})",
                        rest[0][0], rest[0][1], rest[1][0], rest[1][1]
                    ));
                }
            }
        }
        if let (Some(i), Some(by)) = (host.selected(), forward) {
            self.change_depth(host, i, by);
        }
        if let Some(on) = toggled
            && self.edit(host, Edit::AutoDepth(on))
        {
            host.info(if on {
                "automatic depth on: overlaps keep their order while they last"
            } else {
                "automatic depth off: overlaps are drawn by the handles' depths alone"
            });
        }
    }
}

impl CanvasTool for HandleTool {
    /// Adds, selects, drags and deletes handles as the active tool calls for. The
    /// canvas calls it under every tool, after starting a pan with the middle button
    /// or Space: a drag begun before a switch of tools goes on, and a handle's
    /// right-click menu and the cursor over it serve the brush too (not the cage).
    fn input(&mut self, host: &mut dyn Host, ui: &Ui, response: &Response) {
        self.pointer_input(host, ui, response);
    }

    /// The handles (the rotation ring of the selected one, or of the one Alt is over
    /// or turning), the C² weights' virtual handles and dual graph when shown, and the
    /// bar being drawn; whatever the tool, wherever the canvas shows the handles.
    fn paint(&mut self, host: &mut dyn Host, painter: &Painter, pointer: Option<Pos2>, _: bool) {
        self.paint_handles(host, painter, pointer);
    }

    /// The selected handle's section.
    fn panel(&mut self, host: &mut dyn Host, ui: &mut Ui) {
        self.handle_section(host, ui);
    }

    /// Drops the bar being drawn. A drag has changed the document already:
    /// [`HandleTool::finish_gesture`] ends it, as an undo step.
    fn cancel(&mut self) {
        self.bar_start = None;
    }
}

/// Sets each point handle's rotation to the one that best turns the directions to its
/// neighbours (all other handles, nearer ones weighing more) from rest to now: the
/// pseudo-edge heuristic of bounded biharmonic weights.
pub(crate) fn auto_rotate(handles: &mut [HandleSpec]) {
    let centres: Vec<(DVec2, DVec2)> = handles
        .iter()
        .map(|h| match *h {
            HandleSpec::Point { rest, .. } => {
                let now = posed(h)[0];
                (DVec2::from(rest), now)
            }
            HandleSpec::Bar { rest, .. } => {
                let [a, b] = posed(h);
                (
                    (DVec2::from(rest[0]) + DVec2::from(rest[1])) * 0.5,
                    (a + b) * 0.5,
                )
            }
        })
        .collect();
    for (i, h) in handles.iter_mut().enumerate() {
        let HandleSpec::Point { rotate, .. } = h else {
            continue;
        };
        let (mut dot, mut cross) = (0.0, 0.0);
        for (j, &(rest_j, now_j)) in centres.iter().enumerate() {
            if i == j {
                continue;
            }
            let r = rest_j - centres[i].0;
            let c = now_j - centres[i].1;
            let w = 1.0 / r.length_squared().max(1e-9);
            dot += w * r.dot(c);
            cross += w * r.perp_dot(c);
        }
        if dot != 0.0 || cross != 0.0 {
            *rotate = cross.atan2(dot);
        }
    }
}

/// The point handle a click at `at` (image pixels, current pose) places: at rest where
/// the picture shown there lies, with the rotation and scale the pose has around it
/// ([`Document::local_pose`]). `None` (and a message) off the picture.
fn point_under(host: &mut dyn Host, at: DVec2) -> Option<HandleSpec> {
    let point = host.document_mut()?.point_at(at);
    if point.is_none() {
        host.error(&anyhow::anyhow!("click on the picture to add a handle"));
    }
    point
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(rest: [f64; 2], translate: [f64; 2]) -> HandleSpec {
        HandleSpec::Point {
            rest,
            translate,
            rotate: 0.0,
            scale: 1.0,
            depth: 0,
        }
    }

    #[test]
    fn auto_rotation_follows_a_turn_of_the_neighbours() {
        // Three handles turned by 90° about the first: the first turns by 90°.
        let mut handles = vec![
            point([0.0, 0.0], [0.0, 0.0]),
            point([10.0, 0.0], [-10.0, 10.0]),
            point([0.0, 10.0], [-10.0, -10.0]),
        ];
        auto_rotate(&mut handles);
        let HandleSpec::Point { rotate, .. } = handles[0] else {
            unreachable!()
        };
        assert!(
            (rotate - std::f64::consts::FRAC_PI_2).abs() < 1e-9,
            "{rotate}"
        );
        // A pure translation turns nothing.
        let mut handles = vec![
            point([0.0, 0.0], [5.0, 5.0]),
            point([10.0, 0.0], [5.0, 5.0]),
        ];
        auto_rotate(&mut handles);
        assert!(
            handles
                .iter()
                .all(|h| matches!(h, HandleSpec::Point { rotate, .. } if rotate.abs() < 1e-12))
        );
    }
}
