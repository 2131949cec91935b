//! The rigidity brush (ARAP, the paper's §5.2): strokes painted on the picture make
//! the triangles under them stiffer. A stroke is stored in rest pixels, so the paint
//! stays on the same part of the picture whatever the pose; one stroke is one undo
//! step. Alt erases.

use std::sync::Arc;

use egui::{Color32, Mesh, PointerButton, Pos2, Response, Shape, Ui};
use glam::DVec2;
use pipeline::Deformer as _;
use pipeline::arap::polyline_distance_squared;
use project::RigidityStroke;

use crate::document::Edit;
use crate::tool::{CanvasTool, Host};

/// The rigidity brush: its settings, the stroke under way, and the painted triangles
/// it last drew.
#[derive(Clone)]
pub struct Brush {
    /// Radius in picture pixels.
    pub radius: f64,
    /// The weight painted (the paper paints 10000; 1 is unpainted).
    pub weight: f64,
    stroke: Option<BrushStroke>,
    painted: PaintedCache,
}

impl Default for Brush {
    fn default() -> Self {
        Self {
            radius: 20.0,
            weight: 10_000.0,
            stroke: None,
            painted: PaintedCache::default(),
        }
    }
}

/// A stroke being painted (or erased), in rest pixels.
#[derive(Clone, Debug, Default)]
struct BrushStroke {
    erase: bool,
    /// The stroke in rest pixels, as it is stored.
    points: Vec<[f64; 2]>,
    /// The same points where the pose shows them, for drawing the stroke under way.
    posed: Vec<DVec2>,
    /// Drawn as parts: the part under the brush where the stroke began, which it
    /// paints alone.
    part: Option<usize>,
}

/// The painted triangles, by the (GPU mesh version, strokes) they were found for: the
/// GPU mesh's version is new for every mesh of every document.
#[derive(Clone, Default)]
struct PaintedCache {
    key: Option<(u64, Vec<RigidityStroke>)>,
    /// Each painted triangle's corners with its weight.
    triangles: Arc<Vec<([u32; 3], f64)>>,
    /// The edges around the painted region (used by one painted triangle only).
    outline: Arc<Vec<[u32; 2]>>,
}

/// `strokes` with every point within `radius` plus the stroke's own radius of the
/// polyline `eraser` removed, a stroke split where points go: what remains paints
/// nothing within `radius` of the eraser's path.
pub fn erase(strokes: &[RigidityStroke], eraser: &[[f64; 2]], radius: f64) -> Vec<RigidityStroke> {
    let eraser: Vec<DVec2> = eraser.iter().map(|&p| DVec2::from(p)).collect();
    let mut out = Vec::new();
    for stroke in strokes {
        let reach = radius + stroke.radius;
        let mut piece = Vec::new();
        for &p in &stroke.stroke {
            if polyline_distance_squared(&eraser, DVec2::from(p)) < reach * reach {
                if !piece.is_empty() {
                    out.push(RigidityStroke {
                        stroke: std::mem::take(&mut piece),
                        ..stroke.clone()
                    });
                }
            } else {
                piece.push(p);
            }
        }
        if !piece.is_empty() {
            out.push(RigidityStroke {
                stroke: piece,
                ..stroke.clone()
            });
        }
    }
    out
}

impl CanvasTool for Brush {
    /// Paints or erases (with Alt) while the primary button is down on the canvas, and
    /// commits the stroke when it is released. Space or the middle button still pan.
    fn input(&mut self, host: &mut dyn Host, ui: &Ui, response: &Response) {
        let (pressed, down, released, latest, alt, space) = ui.input(|i| {
            (
                i.pointer.primary_pressed(),
                i.pointer.primary_down(),
                i.pointer.primary_released(),
                i.pointer.latest_pos(),
                i.modifiers.alt,
                i.key_down(egui::Key::Space),
            )
        });
        if pressed
            && !space
            && response.contains_pointer()
            && !response.drag_started_by(PointerButton::Middle)
        {
            self.stroke = Some(BrushStroke {
                erase: alt,
                ..BrushStroke::default()
            });
        }
        if (down || released)
            && let (Some(pos), Some(_)) = (latest, &self.stroke)
        {
            self.add_point(host, pos);
        }
        if released && let Some(stroke) = self.stroke.take() {
            self.commit(host, stroke);
        }
    }

    /// The painted triangles (when that overlay is on), translucent, where the pose
    /// puts them, with the stroke under way; while the brush is in use, its outline
    /// around the pointer.
    fn paint(
        &mut self,
        host: &mut dyn Host,
        painter: &egui::Painter,
        pointer: Option<Pos2>,
        active: bool,
    ) {
        if host.shows().rigidity {
            self.paint_rigidity(host, painter);
        }
        if active && let Some(p) = pointer {
            let erase = painter.ctx().input(|i| i.modifiers.alt);
            self.paint_outline(host, painter, p, erase);
        }
    }

    fn panel(&mut self, host: &mut dyn Host, ui: &mut Ui) {
        ui.add(
            egui::Slider::new(&mut self.radius, 1.0..=200.0)
                .logarithmic(true)
                .text("Brush radius (px)"),
        );
        ui.add(
            egui::Slider::new(&mut self.weight, 2.0..=100_000.0)
                .logarithmic(true)
                .text("Stiffness"),
        )
        .on_hover_text("The paper paints 10000; unpainted triangles have 1");
        if host
            .document()
            .is_some_and(|doc| !doc.project().rigidity.is_empty())
            && ui.button("Clear rigidity").clicked()
        {
            let _ = host.edit(Edit::Rigidity(Vec::new()));
        }
    }

    fn cancel(&mut self) {
        self.stroke = None;
    }
}

impl Brush {
    /// Adds the rest point under screen point `pos` to the stroke, at most every
    /// quarter radius.
    fn add_point(&mut self, host: &mut dyn Host, pos: Pos2) {
        let at = host.viewport().to_image(pos);
        let Some(doc) = host.document_mut() else {
            return;
        };
        let Some((rest, _, _)) = doc.unwarp(at) else {
            return;
        };
        let spacing = self.radius * 0.25;
        let Some(stroke) = &mut self.stroke else {
            return;
        };
        if stroke.points.is_empty() {
            stroke.part = doc.part_at(at);
        }
        if stroke
            .points
            .last()
            .is_none_or(|&last| DVec2::from(last).distance(rest) >= spacing)
        {
            stroke.points.push(rest.to_array());
            stroke.posed.push(at);
        }
    }

    fn commit(&mut self, host: &mut dyn Host, stroke: BrushStroke) {
        let Some(doc) = host.document() else { return };
        if stroke.points.is_empty() {
            return;
        }
        let current = doc.project().rigidity.clone();
        let strokes = if stroke.erase {
            erase(&current, &stroke.points, self.radius)
        } else {
            let mut strokes = current.clone();
            strokes.push(RigidityStroke {
                stroke: stroke.points,
                radius: self.radius,
                weight: self.weight,
                part: stroke.part,
            });
            strokes
        };
        if strokes == current {
            return;
        }
        let method = doc.method();
        if host.edit(Edit::Rigidity(strokes)) && !method.reads_rigidity() {
            host.info("rigidity is painted for ARAP: choose ARAP under Method to see its effect");
        }
    }

    /// The brush's outline around the pointer: white, light blue for the eraser (Alt),
    /// over a dark line.
    fn paint_outline(&self, host: &dyn Host, painter: &egui::Painter, pointer: Pos2, erase: bool) {
        let radius = self.radius as f32 * host.viewport().zoom;
        painter.circle_stroke(pointer, radius, egui::Stroke::new(3.0, Color32::BLACK));
        let light = if erase {
            Color32::from_rgb(120, 200, 255)
        } else {
            Color32::WHITE
        };
        painter.circle_stroke(pointer, radius, egui::Stroke::new(1.5, light));
    }

    /// The triangles the painted-rigidity overlay drew last (their corners).
    pub fn painted_triangles(&self) -> Vec<[u32; 3]> {
        self.painted.triangles.iter().map(|&(t, _)| t).collect()
    }

    /// Draws the painted triangles, translucent, where the pose puts them (and the
    /// stroke being painted).
    fn paint_rigidity(&mut self, host: &mut dyn Host, painter: &egui::Painter) {
        let mesh = host.mesh_version();
        let viewport = *host.viewport();
        let Some(doc) = host.document_mut() else {
            return;
        };
        let strokes = &doc.project().rigidity;
        if strokes.is_empty() && self.stroke.is_none() {
            return;
        }
        let fresh = self
            .painted
            .key
            .as_ref()
            .is_some_and(|(version, painted)| *version == mesh && painted == strokes);
        if !fresh {
            let key = (mesh, strokes.clone());
            // The mesh shown: drawn as parts, the parts' joined mesh (a stroke paints
            // its own part).
            let (weights, triangles) = match doc.parts() {
                Some(parts) => {
                    let (rest, triangles) = (parts.rest(), parts.triangles());
                    let part_of = Some(parts.part_of());
                    let weights =
                        pipeline::arap::rigidity_weights_of(rest, triangles, strokes, part_of);
                    (weights, triangles)
                }
                None => {
                    let domain = doc.mesh();
                    let weights = pipeline::arap::rigidity_weights(domain, strokes);
                    (weights, domain.triangles())
                }
            };
            let painted: Vec<([u32; 3], f64)> = weights
                .iter()
                .zip(triangles)
                .filter(|(w, _)| **w != 1.0)
                .map(|(&w, &t)| (t, w))
                .collect();
            let mut edges: std::collections::HashMap<[u32; 2], u32> = Default::default();
            for (t, _) in &painted {
                for k in 0..3 {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    *edges.entry([a.min(b), a.max(b)]).or_default() += 1;
                }
            }
            let mut outline: Vec<[u32; 2]> = edges
                .into_iter()
                .filter(|&(_, n)| n == 1)
                .map(|(e, _)| e)
                .collect();
            outline.sort_unstable();
            self.painted = PaintedCache {
                key: Some(key),
                triangles: Arc::new(painted),
                outline: Arc::new(outline),
            };
        }
        let painted = self.painted.triangles.clone();
        let outline = self.painted.outline.clone();
        let deformed = doc.deformed();
        let mut mesh = Mesh::default();
        for &(t, w) in painted.iter() {
            let Some(corners) = t
                .iter()
                .map(|&v| deformed.get(v as usize))
                .collect::<Option<Vec<_>>>()
            else {
                continue;
            };
            // Stiffer is more opaque: 10 → faint, 10⁴ → strong; below 1 blue.
            let strength = (w.log10().abs() / 4.0).clamp(0.15, 1.0);
            let alpha = (40.0 + 70.0 * strength) as u8;
            let color = if w >= 1.0 {
                Color32::from_rgba_unmultiplied(255, 140, 0, alpha)
            } else {
                Color32::from_rgba_unmultiplied(40, 140, 255, alpha)
            };
            let base = mesh.vertices.len() as u32;
            for &&p in &corners {
                mesh.colored_vertex(viewport.to_screen(p), color);
            }
            mesh.add_triangle(base, base + 1, base + 2);
        }
        if !mesh.is_empty() {
            painter.add(Shape::mesh(mesh));
        }
        // The painted region's outline, dark under light, so it shows on any picture
        // (an orange tint alone vanishes on an orange subject).
        for (width, color) in [(3.0, Color32::BLACK), (1.5, Color32::WHITE)] {
            for &[a, b] in outline.iter() {
                if let (Some(&p), Some(&q)) = (deformed.get(a as usize), deformed.get(b as usize)) {
                    painter.line_segment(
                        [viewport.to_screen(p), viewport.to_screen(q)],
                        egui::Stroke::new(width, color),
                    );
                }
            }
        }
        if let Some(stroke) = &self.stroke {
            let color = if stroke.erase {
                Color32::from_white_alpha(90)
            } else {
                Color32::from_rgba_unmultiplied(255, 140, 0, 90)
            };
            let radius = self.radius as f32 * viewport.zoom;
            for &p in &stroke.posed {
                painter.circle_filled(viewport.to_screen(p), radius, color);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stroke(points: &[[f64; 2]], radius: f64) -> RigidityStroke {
        RigidityStroke {
            stroke: points.to_vec(),
            radius,
            weight: 100.0,
            part: None,
        }
    }

    #[test]
    fn erasing_splits_strokes_and_clears_the_eraser_path() {
        let line: Vec<[f64; 2]> = (0..=10).map(|i| [f64::from(i) * 10.0, 0.0]).collect();
        let strokes = [stroke(&line, 5.0), stroke(&[[0.0, 100.0]], 5.0)];
        // An eraser across the middle of the line.
        let out = erase(&strokes, &[[50.0, -20.0], [50.0, 20.0]], 5.0);
        assert_eq!(out.len(), 3, "{out:?}");
        let left = &out[0].stroke;
        let right = &out[1].stroke;
        assert_eq!(left.last(), Some(&[40.0, 0.0]));
        assert_eq!(right.first(), Some(&[60.0, 0.0]));
        // Nothing left within the eraser's reach of its path.
        for s in &out {
            for p in &s.stroke {
                assert!((p[0] - 50.0).abs() >= 10.0 || p[1] == 100.0, "{p:?}");
            }
        }
        assert_eq!(out[2], strokes[1], "a stroke out of reach stays whole");
        // Erasing everything leaves nothing.
        assert!(erase(&strokes, &[[0.0, 0.0], [100.0, 0.0], [0.0, 100.0]], 50.0).is_empty());
    }
}
