//! What the cage tool draws over the canvas: the polygon being drawn, the cage at rest
//! or posed (with crossing edges, the selection, a box selection), the support contour
//! of the heat map's vertex; and the coordinates under the pointer, as text.

use std::sync::Arc;

use egui::{Color32, Painter, Pos2, Rect, Shape, Stroke, StrokeKind};
use project::Controls;

use super::{
    CAGE, CAGE_REST, CONTOUR, CROSSING, CageState, CageTool, ContourSegment, EdgePoint, GRAB,
    OUTLINE, SELECTED, VERTEX, contour, crossing_edges,
};
use crate::document::Document;
use crate::tool::Host;
use crate::viewport::Viewport;

impl CageTool {
    /// Draws the cage (and the polygon being drawn, a box selection, the support
    /// contour) over the canvas; `pointer` is where the pointer is, in screen points.
    pub(super) fn paint_cage(
        &mut self,
        host: &mut dyn Host,
        painter: &Painter,
        pointer: Option<Pos2>,
    ) {
        let state = self.state(host.document());
        let v = *host.viewport();
        let warps = self.warping(host.document());
        let show = host.shows();
        if warps && show.heat && show.contour {
            self.paint_contour(host, painter);
        }
        let Some(doc) = host.document() else { return };
        match state {
            CageState::Drawing => {
                self.paint_drawing(doc, &v, painter, pointer);
                if self.draft.is_none() {
                    return;
                }
            }
            CageState::Rest | CageState::Posed => self.paint_closed(doc, &v, painter, state, warps),
        }
        if let Some((a, b, _)) = self.boxing {
            let rect = Rect::from_two_pos(v.to_screen(a), v.to_screen(b));
            painter.rect(
                rect,
                0.0,
                Color32::from_rgba_unmultiplied(120, 230, 255, 30),
                Stroke::new(1.0, CAGE),
                StrokeKind::Middle,
            );
        }
    }

    /// While drawing: a cage kept from LBC, faint; the polygon being drawn, with a
    /// line on to the pointer, and its first vertex large when a click closes it.
    fn paint_drawing(
        &self,
        doc: &Document,
        v: &Viewport,
        painter: &Painter,
        pointer: Option<Pos2>,
    ) {
        if doc.method().controls() != Controls::Cage && doc.cage().is_some() && self.draft.is_none()
        {
            // A cage kept from LBC: faint, for reference.
            let rest: Vec<Pos2> = doc.cage_rest().iter().map(|p| v.to_screen(*p)).collect();
            painter.add(Shape::closed_line(rest, Stroke::new(1.0, CAGE_REST)));
        }
        let Some(draft) = &self.draft else {
            return;
        };
        let points: Vec<Pos2> = draft.iter().map(|p| v.to_screen(*p)).collect();
        painter.add(Shape::line(points.clone(), Stroke::new(3.0, OUTLINE)));
        painter.add(Shape::line(points.clone(), Stroke::new(1.5, CAGE)));
        if let (Some(last), Some(pointer)) = (points.last(), pointer) {
            painter.line_segment([*last, pointer], Stroke::new(1.0, CAGE));
        }
        for (i, p) in points.iter().enumerate() {
            let closing =
                i == 0 && points.len() >= 3 && pointer.is_some_and(|q| q.distance(*p) < GRAB);
            let fill = if closing { SELECTED } else { CAGE };
            let r = if closing { VERTEX + 2.0 } else { VERTEX };
            painter.rect(
                Rect::from_center_size(*p, egui::Vec2::splat(2.0 * r)),
                0.0,
                fill,
                Stroke::new(1.0, OUTLINE),
                StrokeKind::Middle,
            );
        }
    }

    /// The closed cage, at rest (crossing edges in red, orange while unsolved) or
    /// posed (over the rest cage, faint), with its vertices and the selection.
    fn paint_closed(
        &self,
        doc: &Document,
        v: &Viewport,
        painter: &Painter,
        state: CageState,
        warps: bool,
    ) {
        if state == CageState::Posed && doc.cage().is_some_and(|c| c.pose.is_some()) {
            // The rest cage, faint, to see how far the pose has gone.
            let rest: Vec<Pos2> = doc.cage_rest().iter().map(|p| v.to_screen(*p)).collect();
            painter.add(Shape::closed_line(rest, Stroke::new(1.0, CAGE_REST)));
        }
        let points = if state == CageState::Posed {
            doc.cage_pose()
        } else {
            doc.cage_rest()
        };
        let screen: Vec<Pos2> = points.iter().map(|p| v.to_screen(*p)).collect();
        let n = screen.len();
        painter.add(Shape::closed_line(
            screen.clone(),
            Stroke::new(3.0, OUTLINE),
        ));
        let color = if state == CageState::Rest && !warps {
            Color32::from_rgb(255, 170, 60)
        } else {
            CAGE
        };
        painter.add(Shape::closed_line(screen.clone(), Stroke::new(1.5, color)));
        if state == CageState::Rest {
            for (i, j) in crossing_edges(&points) {
                for e in [i, j] {
                    painter
                        .line_segment([screen[e], screen[(e + 1) % n]], Stroke::new(2.5, CROSSING));
                }
            }
        }
        let focus = self.focus();
        for (i, p) in screen.iter().enumerate() {
            let fill = if self.selected.contains(&i) {
                SELECTED
            } else {
                CAGE
            };
            painter.rect(
                Rect::from_center_size(*p, egui::Vec2::splat(2.0 * VERTEX)),
                0.0,
                fill,
                Stroke::new(1.0, OUTLINE),
                StrokeKind::Middle,
            );
            if focus == Some(i) {
                painter.circle_stroke(*p, VERTEX + 4.0, Stroke::new(1.5, SELECTED));
            }
        }
    }

    /// The support contour of cage vertex `focus`'s coordinate function at `10⁻³/n`,
    /// cached per vertex and weights.
    fn support_contour(
        &mut self,
        doc: &Document,
        focus: usize,
    ) -> Option<Arc<Vec<ContourSegment>>> {
        let key = (focus, doc.weights_version);
        if let Some((k, segments)) = &self.contour
            && *k == key
        {
            return Some(segments.clone());
        }
        let solution = doc.cage_solution()?;
        let values = doc.cage_influence(focus)?;
        let n = solution.weights.cage_vertices().max(1);
        let level = 1e-3 / n as f32;
        let segments = Arc::new(contour(solution.domain.triangles(), &values, level));
        self.contour = Some((key, segments.clone()));
        Some(segments)
    }

    /// The support contour of the heat map's vertex, where the pose puts it.
    fn paint_contour(&mut self, host: &mut dyn Host, painter: &Painter) {
        let Some(focus) = self.focus() else {
            return;
        };
        let Some(segments) = host
            .document()
            .and_then(|doc| self.support_contour(doc, focus))
        else {
            return;
        };
        let v = *host.viewport();
        let Some(deformed) = host.document_mut().and_then(|d| d.cage_deformed()) else {
            return;
        };
        let point = |(a, b, t): EdgePoint| {
            let (pa, pb) = (deformed.get(a as usize), deformed.get(b as usize));
            pa.zip(pb)
                .map(|(pa, pb)| v.to_screen(*pa + (*pb - *pa) * t))
        };
        let shapes: Vec<Shape> = segments
            .iter()
            .filter_map(|&[p, q]| Some([point(p)?, point(q)?]))
            .map(|line| Shape::line_segment(line, Stroke::new(2.0, CONTOUR)))
            .collect();
        painter.extend(shapes);
    }

    /// The coordinates of the cage mesh's vertex under screen point `pointer`, as the
    /// text shown beside it: none while a gesture is under way or no solved cage warps
    /// the view.
    pub(crate) fn coordinates_readout(&self, host: &mut dyn Host, pointer: Pos2) -> Option<String> {
        if self.gesture_under_way() {
            return None;
        }
        let at = host.viewport().to_image(pointer);
        if !self.warping(host.document()) {
            return None;
        }
        let doc = host.document_mut()?;
        let deformed = doc.cage_deformed()?.to_vec();
        let solution = doc.cage_solution()?.clone();
        let positions = solution.domain.positions();
        // The posed triangle under the pointer, then its corner nearest the pointer.
        let vertex = solution.domain.triangles().iter().find_map(|&[a, b, c]| {
            let [pa, pb, pc] = [a, b, c].map(|k| deformed[k as usize]);
            let area = (pb - pa).perp_dot(pc - pa);
            if area.abs() < 1e-12 {
                return None;
            }
            let u = (pb - at).perp_dot(pc - at) / area;
            let w = (pc - at).perp_dot(pa - at) / area;
            if u < -1e-9 || w < -1e-9 || 1.0 - u - w < -1e-9 {
                return None;
            }
            [a, b, c].into_iter().min_by(|&x, &y| {
                deformed[x as usize]
                    .distance(at)
                    .total_cmp(&deformed[y as usize].distance(at))
            })
        })? as usize;
        let mut row = solution.weights.row(vertex).to_vec();
        row.sort_by(|a, b| b.1.total_cmp(&a.1));
        let rest = positions[vertex];
        let mut text = format!(
            "vertex {vertex} at ({:.1}, {:.1}): {} coordinates",
            rest.x,
            rest.y,
            row.len()
        );
        for &(k, w) in row.iter().take(5) {
            text.push_str(&format!("\n{w:>6.3}  cage vertex {}", k + 1));
        }
        if row.len() > 5 {
            text.push_str(&format!("\n… and {} smaller", row.len() - 5));
        }
        Some(text)
    }
}
