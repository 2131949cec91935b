//! What the handle tools add to the editor as a set of controls
//! ([`crate::controls::ControlSet`]): the edit buttons, the readout under the pointer,
//! the status bar's fields.

use egui::{Pos2, Ui};
use pipeline::{ArapRig, Deformer, Output};
use weights_core::NodeKind;

use super::HandleTool;
use crate::controls::StatusField;
use crate::document::{Document, Edit};
use crate::tool::Host;

impl HandleTool {
    /// Delete the selected handle, clear every handle, reset the pose.
    pub(crate) fn handle_buttons(&mut self, host: &mut dyn Host, ui: &mut Ui) {
        if ui
            .add_enabled(
                host.selected().is_some(),
                egui::Button::new("Delete handle"),
            )
            .clicked()
        {
            self.delete_selected(host);
        }
        if ui.button("Clear all handles").clicked() {
            let _ = self.edit(host, Edit::Clear);
            host.select(None);
        }
        if ui.button("Reset pose").clicked() {
            let _ = self.edit(host, Edit::ResetPose);
        }
    }

    /// The mesh vertex under screen point `pointer`: its C² weights, or where a method
    /// that solves for positions takes it (none drawn as parts: the mesh shown is the
    /// parts', not the picture's).
    pub(crate) fn weights_readout(&self, host: &mut dyn Host, pointer: Pos2) -> Option<String> {
        if self.dragging() {
            return None;
        }
        let at = host.viewport().to_image(pointer);
        let doc = host.document_mut().filter(|d| d.parts().is_none())?;
        let (rest, _, _) = doc.unwarp(at)?;
        let vertex = doc.mesh().nearest_vertex(rest)? as usize;
        if matches!(doc.deformer().output(), Output::Positions(_)) {
            let method = doc.method().label();
            let from = doc.mesh().positions()[vertex];
            let to = *doc.deformed().get(vertex)?;
            return Some(format!(
                "vertex {vertex} at ({:.1}, {:.1})\n{method} moves it to ({:.1}, {:.1})",
                from.x, from.y, to.x, to.y
            ));
        }
        let rig = doc.rig()?;
        let mut weights: Vec<(usize, f64)> = rig.weights(vertex).collect();
        weights.sort_by(|a, b| b.1.total_cmp(&a.1));
        let mut text = format!(
            "vertex {vertex} at ({:.1}, {:.1}): {} weights",
            rest.x,
            rest.y,
            weights.len()
        );
        for &(k, w) in weights.iter().take(5) {
            text.push_str(&format!("\n{:>6.3}  {}", w, node_name(rig, k)));
        }
        let more = weights.len().saturating_sub(5);
        if more > 0 {
            text.push_str(&format!("\n… and {more} smaller"));
        }
        Some(text)
    }

    /// The status bar's fields (each with its hover text): the mesh, the handles,
    /// the time of the last update.
    pub(crate) fn status_fields(&self, doc: &Document) -> Vec<StatusField> {
        let field = |text: String| (text, None);
        let mut fields = if let Some(parts) = doc.parts() {
            vec![
                field(format!(
                    "{} parts, {} vertices",
                    parts.composer().shown().len(),
                    parts.rest().len()
                )),
                field(format!("{} handles", doc.project().handles.len())),
                field(format!("parts set up in {:.1} ms", parts.setup_ms())),
            ]
        } else if let Some(stats) = doc.rig().map(weights_core::Rig::stats) {
            vec![
                field(format!("{} vertices", stats.samples)),
                field(format!(
                    "{} handles ({} nodes) + {} virtual",
                    stats.real_handles, stats.handle_nodes, stats.virtual_nodes
                )),
                field(format!("weights updated in {:.1} ms", doc.last_update_ms)),
            ]
        } else {
            // ARAP or MLS on the mesh alone.
            vec![
                field(format!("{} vertices", doc.mesh().len())),
                field(format!("{} handles", doc.project().handles.len())),
                field(format!("updated in {:.1} ms", doc.last_update_ms)),
            ]
        };
        if let Some(times) = doc.arap().map(ArapRig::times) {
            fields.push((
                format!(
                    "ARAP: compiled in {:.1} ms, updated in {:.2} ms",
                    times.compile_ms, times.update_ms
                ),
                Some(format!(
                    "registration {:.1} ms (once per mesh); compilation when handles \
                     are added or removed or rigidity is painted; an update every \
                     drag frame",
                    times.registration_ms
                )),
            ));
        }
        fields
    }
}

/// How a node is called in the user interface.
fn node_name(rig: &weights_core::Rig, k: usize) -> String {
    match rig.nodes()[k].kind {
        NodeKind::Point { handle } => format!("point handle {}", handle + 1),
        NodeKind::BarSample { handle, t } => format!("bar {} at {:.0}%", handle + 1, t * 100.0),
        NodeKind::Boundary => "pinned border".to_owned(),
        NodeKind::Virtual => match rig.owner_handle(k) {
            Some(h) => format!("virtual node {k} (mostly handle {})", h + 1),
            None => format!("virtual node {k}"),
        },
    }
}
