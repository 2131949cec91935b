//! What the handle tools draw over the canvas: the handles, the rotation ring, the C²
//! weights' virtual handles and dual graph, the bar being drawn.

use egui::{Color32, Painter, Pos2, Shape, Stroke, StrokeKind, Vec2};
use project::HandleSpec;
use weights_core::NodeKind;

use super::input::RING;
use super::{Grip, HandleTool};
use crate::document::posed;
use crate::tool::Host;

/// Radius of a point handle's dot, screen points.
const DOT: f32 = 6.0;

const HANDLE: Color32 = Color32::from_rgb(255, 255, 255);
const SELECTED: Color32 = Color32::from_rgb(255, 212, 0);
const OUTLINE: Color32 = Color32::from_rgb(20, 20, 20);
const VIRTUAL: Color32 = Color32::from_rgb(255, 80, 220);
const DUAL: Color32 = Color32::from_rgba_premultiplied(0, 200, 255, 200);

impl HandleTool {
    /// Paints the handles and the bar being drawn (see
    /// [`crate::tool::CanvasTool::paint`]); `pointer` is where the pointer is, on the
    /// canvas or not.
    pub(super) fn paint_handles(
        &self,
        host: &mut dyn Host,
        painter: &Painter,
        pointer: Option<Pos2>,
    ) {
        let host: &dyn Host = host;
        let alt = painter.ctx().input(|i| i.modifiers.alt);
        // The ring a drag turns (or, with Shift, scales) a point handle by shows on the
        // handle under the pointer (with Alt, anywhere inside its ring).
        let turning = match &self.drag {
            Some(drag) if matches!(drag.grip, Grip::Rotate | Grip::Scale) => Some(drag.index),
            Some(_) => None,
            None => pointer.and_then(|p| {
                if alt {
                    self.rotation_target(host, p)
                } else {
                    self.hit(host, p).map(|(i, _)| i)
                }
            }),
        };
        paint_overlays(host, painter, turning);
        if let (Some(a), Some(b)) = (self.bar_start, pointer) {
            let a = host.viewport().to_screen(a);
            painter.line_segment([a, b], Stroke::new(4.0, SELECTED));
        }
    }
}

/// Paints the handles (with the rotation ring of `turning`, the point handle Alt is
/// over or being turned), and for the C² weights the virtual handles and the dual
/// graph when asked for.
fn paint_overlays(host: &dyn Host, painter: &Painter, turning: Option<usize>) {
    let Some(doc) = host.document() else { return };
    let v = host.viewport();
    let show = host.shows();
    let selected = host.selected();
    // (Drawn as parts, each part places virtual handles of its own: the whole
    // picture's are not what warps it.)
    let rig = doc
        .rig()
        .filter(|_| doc.method().uses_virtual_handles() && doc.parts().is_none());
    if let Some(rig) = rig.filter(|_| show.dual_graph) {
        for &(a, b) in host.dual_graph() {
            let (a, b) = (a as usize, b as usize);
            if let (Some(a), Some(b)) = (doc.node_position(a), doc.node_position(b)) {
                painter.line_segment([v.to_screen(a), v.to_screen(b)], Stroke::new(1.5, DUAL));
            }
        }
        let _ = rig;
    }
    if let Some(rig) = rig.filter(|_| show.virtual_handles) {
        for (k, node) in rig.nodes().iter().enumerate() {
            if matches!(node.kind, NodeKind::Virtual)
                && let Some(at) = doc.node_position(k)
            {
                let c = v.to_screen(at);
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
        let fill = if selected == Some(i) {
            SELECTED
        } else {
            HANDLE
        };
        let [a, b] = posed(h).map(|p| v.to_screen(p));
        match h {
            HandleSpec::Point { rotate, scale, .. } => {
                if selected == Some(i) || turning == Some(i) {
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
