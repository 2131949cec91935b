//! The cut tool: a stroke that separates the shape along it (the rig file's `cuts`),
//! so that parts of a flat picture that touch — a tail against a leg — move apart. The
//! picture is re-meshed with the mesh split along the stroke's parts inside the shape
//! (`pipeline::mesh_picture`); C² and ARAP measure nothing across a cut. Alt-click on a
//! cut removes it. One undo step per stroke.

use egui::{Color32, Painter, Pos2, Response, Stroke, Ui};
use glam::DVec2;

use crate::document::Edit;
use crate::tool::{CanvasTool, Host};

/// Screen points a stroke's points are apart at least.
const SPACING: f32 = 4.0;

/// How near (screen points) an Alt-click must be to a cut to remove it.
const PICK: f32 = 8.0;

/// The cut tool's state: the stroke under way.
#[derive(Default)]
pub struct CutTool {
    /// The stroke being drawn: rest points (image pixels), and where they showed.
    stroke: Option<(Vec<[f64; 2]>, Vec<DVec2>)>,
}

impl CanvasTool for CutTool {
    /// Draws a stroke while the primary button is down; on release it becomes a cut.
    /// Alt-click removes the cut under the pointer.
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
        if response.hovered() {
            ui.ctx().set_cursor_icon(egui::CursorIcon::Crosshair);
        }
        if pressed && alt && response.contains_pointer() {
            if let Some(pos) = latest {
                self.remove_near(host, pos);
            }
            return;
        }
        if pressed && !space && response.contains_pointer() {
            self.stroke = Some((Vec::new(), Vec::new()));
        }
        if (down || released)
            && let (Some(pos), Some(_)) = (latest, &self.stroke)
        {
            self.add_point(host, pos);
        }
        if released && let Some((stroke, _)) = self.stroke.take() {
            commit(host, stroke);
        }
    }

    /// The cuts (where the pose puts them) and the stroke under way, as dashed red
    /// lines over a dark one.
    fn paint(&mut self, host: &mut dyn Host, painter: &Painter, _: Option<Pos2>, active: bool) {
        let Some(doc) = host.document() else { return };
        if !active && doc.project().cuts.is_empty() {
            return;
        }
        let viewport = *host.viewport();
        for stroke in shown_cuts(host) {
            let points: Vec<Pos2> = stroke.iter().map(|&p| viewport.to_screen(p)).collect();
            draw(painter, &points);
        }
        if let Some((_, posed)) = &self.stroke {
            let points: Vec<Pos2> = posed.iter().map(|&p| viewport.to_screen(p)).collect();
            draw(painter, &points);
        }
    }

    fn panel(&mut self, host: &mut dyn Host, ui: &mut Ui) {
        ui.label(
            "Cut: drag across where parts touch to separate them; Alt-click a cut to remove it",
        );
        if host
            .document()
            .is_some_and(|doc| !doc.project().cuts.is_empty())
            && ui.button("Clear cuts").clicked()
        {
            let _ = host.edit(Edit::Cuts(Vec::new()));
        }
    }

    fn cancel(&mut self) {
        self.stroke = None;
    }
}

impl CutTool {
    /// Adds the rest point under screen point `pos` to the stroke (off the picture,
    /// the point itself: a cut may start and end outside the shape).
    fn add_point(&mut self, host: &mut dyn Host, pos: Pos2) {
        let at = host.viewport().to_image(pos);
        let zoom = f64::from(host.viewport().zoom.max(1e-6));
        let rest = host
            .document_mut()
            .and_then(|doc| doc.unwarp(at))
            .map_or(at, |(rest, _, _)| rest);
        let Some((points, posed)) = &mut self.stroke else {
            return;
        };
        if posed
            .last()
            .is_none_or(|&last| last.distance(at) * zoom >= f64::from(SPACING))
        {
            points.push(rest.to_array());
            posed.push(at);
        }
    }

    /// Removes the cut nearest screen point `pos`, if one is within [`PICK`].
    fn remove_near(&mut self, host: &mut dyn Host, pos: Pos2) {
        let Some(doc) = host.document() else { return };
        let cuts = doc.project().cuts.clone();
        let viewport = *host.viewport();
        let distance = |stroke: &[DVec2]| {
            stroke
                .windows(2)
                .map(|w| segment_distance(pos, viewport.to_screen(w[0]), viewport.to_screen(w[1])))
                .fold(f32::INFINITY, f32::min)
        };
        let nearest = shown_cuts(host)
            .iter()
            .enumerate()
            .map(|(i, stroke)| (i, distance(stroke)))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((i, d)) = nearest
            && d <= PICK
        {
            let mut cuts = cuts;
            cuts.remove(i);
            if host.edit(Edit::Cuts(cuts)) {
                host.info("cut removed");
            }
        }
    }
}

/// Makes `stroke` a cut (one undo step), if it has length.
fn commit(host: &mut dyn Host, stroke: Vec<[f64; 2]>) {
    let Some(doc) = host.document() else { return };
    let length: f64 = stroke
        .windows(2)
        .map(|w| DVec2::from(w[0]).distance(DVec2::from(w[1])))
        .sum();
    if stroke.len() < 2 || length < 1.0 {
        return;
    }
    let mut cuts = doc.project().cuts.clone();
    cuts.push(project::Cut { stroke });
    if host.edit(Edit::Cuts(cuts)) {
        let method = host.document().map(crate::document::Document::method);
        if method == Some(project::Method::Mls) {
            host.info("cut made; MLS measures straight-line distance, so it moves both sides alike: choose C² or ARAP");
        } else {
            host.info("cut made: the parts on either side move apart");
        }
    }
}

/// The cuts' strokes where the pose shows them (image pixels; a point off the picture
/// as it is).
fn shown_cuts(host: &mut dyn Host) -> Vec<Vec<DVec2>> {
    let Some(doc) = host.document_mut() else {
        return Vec::new();
    };
    let cuts = doc.project().cuts.clone();
    cuts.iter()
        .map(|cut| {
            cut.stroke
                .iter()
                .map(|&p| {
                    let p = DVec2::from(p);
                    doc.forward(p).unwrap_or(p)
                })
                .collect()
        })
        .collect()
}

/// A dashed red line over a dark one.
fn draw(painter: &Painter, points: &[Pos2]) {
    if points.len() < 2 {
        return;
    }
    painter.add(egui::Shape::line(
        points.to_vec(),
        Stroke::new(4.0, Color32::from_black_alpha(160)),
    ));
    painter.add(egui::Shape::line(
        points.to_vec(),
        Stroke::new(2.0, Color32::from_rgb(255, 70, 70)),
    ));
}

/// Distance from `p` to the segment `a`–`b`.
fn segment_distance(p: Pos2, a: Pos2, b: Pos2) -> f32 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_sq().max(1e-12)).clamp(0.0, 1.0);
    (a + ab * t - p).length()
}
