//! The CPU side of what the canvas draws: the [`GpuFrame`] brought up to date with the
//! document each frame, part by part, each part with a new version only when it
//! changed (the paint callback in [`crate::scene`] uploads what has a new version).
//!
//! The mesh is what the document shows for the controls in hand ([`Shown`]), through
//! the method seam: the handle methods draw the picture's mesh skinned by the C² rig
//! (its weights also feed the heat map and cells), with the positions a method solves
//! for laid over it ([`pipeline::Output::Positions`]); parts draw their joined mesh by
//! positions over their packed texture; a cage method draws its own mesh skinned by its
//! own table, over its backdrop ([`pipeline::backdrop_of`]). While a cage is drawn or
//! not yet solved, the picture is shown at rest with no mesh.

use std::sync::Arc;

use anyhow::{Result, bail};
use glam::DVec2;
use pipeline::{Controls, Deformer, Output};

use crate::document::{Document, Shown};
use crate::scene::{GpuFrame, MeshData, Versioned};
use crate::show::Show;

/// What the view shows, as the app decides it this frame.
#[derive(Clone, Copy, Debug)]
pub(crate) struct View {
    /// The controls the tools act on (the cage's view: the cage tool, or LBC chosen).
    pub in_hand: Controls,
    /// Whether the handles' weights apply (cells, the dual graph, the handles' heat).
    pub uses_weights: bool,
    /// A solved cage warps the picture (no new polygon being drawn).
    pub warping: bool,
    /// The handle or cage vertex whose weights the heat map shows.
    pub shown: Option<usize>,
    /// Which overlays are on.
    pub show: Show,
}

/// The frame with the versions it was built from.
#[derive(Clone, Default)]
pub(crate) struct FrameBuilder {
    /// What the GPU draws.
    pub frame: GpuFrame,
    next_version: u64,
    seen: Seen,
    /// The dual graph's edges, keyed by the GPU mesh's version.
    pub dual_graph: (u64, Arc<Vec<(u32, u32)>>),
}

/// Versions (and keys) the frame was last built from.
#[derive(Default, Clone)]
struct Seen {
    weights: u64,
    /// The document's drawing order.
    order: u64,
    pose: u64,
    heat: Option<(usize, u64)>,
    cells: u64,
    /// The controls in hand the frame was drawn for.
    in_hand: Option<Controls>,
    /// Whether a solved cage warped it.
    warping: bool,
    /// The picture and rest mesh the backdrop was made for.
    backdrop: Option<(Arc<image::RgbaImage>, Vec<DVec2>)>,
    /// Drawn as parts: the packed texture shown (keyed by the parts' composer).
    parts: Option<(usize, Arc<image::RgbaImage>)>,
}

impl FrameBuilder {
    fn bump(&mut self) -> u64 {
        self.next_version += 1;
        self.next_version
    }

    /// Brings the frame up to date with `doc` as `view` shows it: the mesh after a
    /// structural change, transforms or positions after a pose change, overlay values
    /// when asked for.
    pub fn update(&mut self, doc: &Document, view: &View) {
        let shown = doc.shown(view.in_hand, view.warping);
        let weights = doc.weights_version;
        // Drawn as parts: the joined mesh samples the layers' pixels packed together.
        let parts = match shown {
            Shown::Parts(parts) => Some(parts),
            _ => None,
        };
        let parts_key = parts.map(|p| std::ptr::from_ref(p.composer()) as usize);
        let parts_changed = parts_key != self.seen.parts.as_ref().map(|(key, _)| *key);
        if parts_changed {
            self.seen.parts = parts.zip(parts_key).map(|(p, key)| {
                (
                    key,
                    Arc::new(p.composer().texture().to_rgba8().into_owned()),
                )
            });
        }
        let picture = match &self.seen.parts {
            Some((_, texture)) => texture.clone(),
            None => doc.image.clone(),
        };
        let image_is_new =
            self.frame.image.version == 0 || !Arc::ptr_eq(&self.frame.image.value, &picture);
        if image_is_new {
            let version = self.bump();
            self.frame.image = Versioned {
                version,
                value: picture,
            };
        }
        let mesh_changed = image_is_new
            || parts_changed
            || weights != self.seen.weights
            || doc.order_version != self.seen.order
            || Some(view.in_hand) != self.seen.in_hand
            || view.warping != self.seen.warping;
        if mesh_changed {
            self.update_mesh(doc, shown);
        }
        if mesh_changed || doc.pose_version != self.seen.pose {
            self.update_pose(shown);
        }
        self.update_overlays(doc, shown, view);
        self.seen.weights = weights;
        self.seen.order = doc.order_version;
        self.seen.pose = doc.pose_version;
        self.seen.in_hand = Some(view.in_hand);
        self.seen.warping = view.warping;
    }

    /// The mesh with its weight rows and triangles in drawing order; in the cage's
    /// view, the backdrop under it.
    fn update_mesh(&mut self, doc: &Document, shown: Shown) {
        let size = [doc.image.width(), doc.image.height()];
        let mesh = match shown {
            // The joined mesh at the texture's places, moved by positions alone.
            Shown::Parts(parts) => {
                let texture = parts.composer().texture().dimensions();
                MeshData {
                    rest: parts.composer().uv().to_vec(),
                    rows: vec![0; parts.rest().len() + 1],
                    triangles: doc.draw_order(),
                    source_size: [texture.0, texture.1],
                    ..MeshData::default()
                }
            }
            Shown::Cage(Some(cage)) => {
                let order = doc
                    .cage_draw_order()
                    .unwrap_or_else(|| cage.triangles().to_vec());
                skinned_mesh(cage, order, size)
            }
            // No cage to warp by: the picture at rest alone.
            Shown::Cage(None) => MeshData {
                rows: vec![0],
                source_size: size,
                ..MeshData::default()
            },
            Shown::Picture(deformer) => skinned_mesh(deformer, doc.draw_order(), size),
        };
        let version = self.bump();
        self.frame.mesh = Versioned {
            version,
            value: Arc::new(mesh),
        };
        self.seen.heat = None;
        self.seen.cells = 0;
        if let Shown::Parts(_) = shown {
            // Overlay values for another mesh are not the parts' (see
            // `update_overlays`).
            self.frame.heat.value = Arc::new(Vec::new());
            self.frame.cells.value = Arc::new(Vec::new());
        }
        let Shown::Cage(cage) = shown else {
            self.frame.backdrop = None;
            self.seen.backdrop = None;
            return;
        };
        let rest = cage.map(|c| c.rest().to_vec()).unwrap_or_default();
        let same = self
            .seen
            .backdrop
            .as_ref()
            .is_some_and(|(image, seen)| Arc::ptr_eq(image, &doc.image) && *seen == rest);
        if self.frame.backdrop.is_some() && same {
            return;
        }
        let backdrop = cage
            .and_then(|cage| pipeline::backdrop_of(&doc.image, cage).ok().flatten())
            .map_or_else(|| doc.image.clone(), Arc::new);
        let version = self.bump();
        self.frame.backdrop = Some(Versioned {
            version,
            value: backdrop,
        });
        self.seen.backdrop = Some((doc.image.clone(), rest));
    }

    /// The node transforms, and the positions a method solves for.
    fn update_pose(&mut self, shown: Shown) {
        let positions = |deformer: &dyn Deformer| match deformer.output() {
            Output::Positions(p) => p.iter().map(|p| p.as_vec2()).collect(),
            Output::Skinned(_) => Vec::new(),
        };
        let (affines, positions) = match shown {
            Shown::Parts(parts) => (Vec::new(), positions(parts)),
            Shown::Cage(Some(cage)) => (transforms(cage), Vec::new()),
            Shown::Cage(None) => (Vec::new(), Vec::new()),
            Shown::Picture(deformer) => (transforms(deformer), positions(deformer)),
        };
        let version = self.bump();
        self.frame.pose = Versioned {
            version,
            value: Arc::new(affines),
        };
        let version = self.bump();
        self.frame.positions = Versioned {
            version,
            value: Arc::new(positions),
        };
    }

    /// The heat map of the shown handle or cage vertex, the cells, the dual graph: each
    /// when on and out of date.
    fn update_overlays(&mut self, doc: &Document, shown: Shown, view: &View) {
        // Drawn as parts: the heat map and cells are each part's own C² rig's, on the
        // parts' mesh (none for a part another method moves, or under a cage); the
        // cage's heat map and the dual graph are on other meshes than the parts'.
        let weights = doc.weights_version;
        let heat_key = view.shown.filter(|_| view.show.heat).map(|s| (s, weights));
        if let Some((subject, _)) = heat_key
            && heat_key != self.seen.heat
        {
            let values = match shown {
                Shown::Cage(_) => doc.cage_influence(subject).unwrap_or_default(),
                _ if !view.uses_weights => Vec::new(),
                _ => doc.influence(subject),
            };
            let version = self.bump();
            self.frame.heat = Versioned {
                version,
                value: Arc::new(values),
            };
            self.seen.heat = heat_key;
        }
        if view.show.cells && view.uses_weights && self.seen.cells != weights {
            // A sample that no node reaches (a rig without nodes, or a piece of the
            // shape without a handle) has no cell: grey.
            let colors = (doc.cell_keys().into_iter())
                .map(|key| key.map_or(NO_CELL, cell_color))
                .collect();
            let version = self.bump();
            self.frame.cells = Versioned {
                version,
                value: Arc::new(colors),
            };
            self.seen.cells = weights;
        }
        // Keyed by the GPU mesh's version, which no other document shares.
        let mesh_version = self.frame.mesh.version;
        if view.show.dual_graph
            && view.uses_weights
            && matches!(shown, Shown::Picture(_))
            && self.dual_graph.0 != mesh_version
        {
            let graph = doc
                .rig()
                .map(weights_core::Rig::dual_graph)
                .unwrap_or_default();
            self.dual_graph = (mesh_version, Arc::new(graph));
        }
    }

    /// The frame's part of the editor's invariants: a mesh built for the document's
    /// current weights has one vertex per vertex of what it shows, and the cage's
    /// view has the picture under it.
    pub fn sanity_check(&self, doc: &Document) -> Result<()> {
        if self.seen.weights != doc.weights_version || self.frame.mesh.version == 0 {
            return Ok(());
        }
        let Some(in_hand) = self.seen.in_hand else {
            return Ok(());
        };
        let mesh = &self.frame.mesh.value;
        let shown = doc.shown(in_hand, self.seen.warping);
        let (samples, what) = match shown {
            Shown::Parts(parts) => (parts.rest().len(), "the parts"),
            Shown::Picture(_) => (doc.mesh().len(), "the rig"),
            Shown::Cage(Some(cage)) => (cage.rest().len(), "the cage's mesh"),
            Shown::Cage(None) => (0, "no mesh (a cage being drawn)"),
        };
        if mesh.rest.len() != samples || mesh.rows.len() != samples + 1 {
            bail!(
                "the GPU mesh has {} vertices, {what} {samples}",
                mesh.rest.len()
            );
        }
        if shown.over_backdrop() && self.frame.backdrop.is_none() {
            bail!("the cage's view without the picture at rest under it");
        }
        Ok(())
    }
}

/// `deformer`'s rest mesh skinned by its own table, with `triangles` in drawing order.
fn skinned_mesh(
    deformer: &dyn Deformer,
    triangles: Vec<[u32; 3]>,
    source_size: [u32; 2],
) -> MeshData {
    let table = match deformer.output() {
        Output::Skinned(skin) => skin.table(),
        // A method that solves for positions draws the rest mesh, moved per vertex.
        Output::Positions(_) => pipeline::SkinTable {
            rows: vec![0; deformer.rest().len() + 1],
            nodes: Vec::new(),
            weights: Vec::new(),
        },
    };
    MeshData {
        rest: deformer.rest().iter().map(|p| p.as_vec2()).collect(),
        rows: table.rows,
        nodes: table.nodes,
        weights: table.weights,
        triangles,
        source_size,
    }
}

/// The node transforms of a skinned method (none for one that solves positions).
fn transforms(deformer: &dyn Deformer) -> Vec<render::Affine> {
    match deformer.output() {
        Output::Skinned(skin) => skin.transforms(),
        Output::Positions(_) => Vec::new(),
    }
}

/// The colour of samples in no node's cell.
const NO_CELL: [u8; 4] = [128, 128, 128, 255];

/// A stable, well-spread colour for a node (keyed by its sample, so it survives
/// renumbering).
pub(crate) fn cell_color(key: u32) -> [u8; 4] {
    let hue = (key.wrapping_mul(2_654_435_761) >> 8) as f32 / (1u32 << 24) as f32;
    let rgb = egui::ecolor::Hsva::new(hue, 0.75, 0.95, 1.0).to_srgb();
    [rgb[0], rgb[1], rgb[2], 255]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cell_colours_are_opaque_and_differ() {
        let colors: Vec<[u8; 4]> = (0..64).map(cell_color).collect();
        assert!(colors.iter().all(|c| c[3] == 255));
        for (i, a) in colors.iter().enumerate() {
            for b in &colors[i + 1..] {
                assert_ne!(a, b);
            }
        }
    }
}
