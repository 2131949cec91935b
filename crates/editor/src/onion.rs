//! Onion skin: the previous and next keys' pictures ghosted behind the current one.
//! Each ghost is drawn on the CPU (at most [`GHOST_SIZE`] pixels across) when the
//! keys around the time shown, the pose of a key or the mesh change, and kept as a
//! texture until then.

use egui::{Color32, ColorImage, TextureHandle, TextureOptions};
use glam::Vec2;
use project::Pose;

use crate::document::Document;

/// The longest side of a ghost, pixels.
pub const GHOST_SIZE: u32 = 768;
/// How opaque a ghost is.
const OPACITY: f32 = 0.4;
/// The previous key's tint, and the next's.
const TINTS: [[f32; 3]; 2] = [[1.0, 0.45, 0.45], [0.45, 0.75, 1.0]];

/// The ghosts and what they were drawn for.
#[derive(Default)]
pub struct Onion {
    /// The poses ghosted (previous, next), the mesh and method they were drawn on.
    drawn: Option<(Vec<Option<Pose>>, u64, u64, project::Method)>,
    /// The textures, previous first.
    pub ghosts: Vec<TextureHandle>,
}

impl Onion {
    /// Brings the ghosts up to date for `time` in `doc` (the keys just before and just
    /// after it). Errors drop the ghosts.
    pub fn update(&mut self, doc: &mut Document, time: f64, ctx: &egui::Context) {
        let keys = doc.keys();
        let before = keys
            .iter()
            .rev()
            .find(|k| k.time < time - 1e-9)
            .map(|k| k.pose.clone());
        let after = keys
            .iter()
            .find(|k| k.time > time + 1e-9)
            .map(|k| k.pose.clone());
        let wanted = (
            vec![before, after],
            doc.weights_version,
            doc.mesh_version(),
            doc.method(),
        );
        if self.drawn.as_ref() == Some(&wanted) {
            return;
        }
        self.ghosts.clear();
        for (i, pose) in wanted.0.iter().enumerate() {
            let Some(pose) = pose else { continue };
            match ghost(doc, pose, TINTS[i]) {
                Ok(image) => self.ghosts.push(ctx.load_texture(
                    format!("onion {i}"),
                    image,
                    TextureOptions::LINEAR,
                )),
                Err(_) => {
                    self.ghosts.clear();
                    break;
                }
            }
        }
        self.drawn = Some(wanted);
    }

    /// Forgets the ghosts (the onion skin was turned off).
    pub fn clear(&mut self) {
        self.drawn = None;
        self.ghosts.clear();
    }
}

/// `doc`'s picture in `pose`, scaled to fit [`GHOST_SIZE`], tinted and faded.
fn ghost(doc: &mut Document, pose: &Pose, tint: [f32; 3]) -> anyhow::Result<ColorImage> {
    let mesh = doc.posed_mesh(pose)?;
    let (w, h) = doc.image.dimensions();
    let scale = (GHOST_SIZE as f32 / w.max(h) as f32).min(1.0);
    let (gw, gh) = (
        ((w as f32 * scale).round() as u32).max(1),
        ((h as f32 * scale).round() as u32).max(1),
    );
    let rest: Vec<Vec2> = mesh.rest.iter().map(|p| p.as_vec2()).collect();
    let deformed: Vec<Vec2> = mesh
        .deformed
        .iter()
        .map(|p| p.as_vec2() * Vec2::new(gw as f32 / w as f32, gh as f32 / h as f32))
        .collect();
    let warped = render::warp_cpu(
        &doc.image,
        &render::WarpMesh {
            rest: &rest,
            deformed: &deformed,
            triangles: &mesh.triangles,
        },
        gw,
        gh,
        &render::RasterOptions::default(),
    )?;
    let pixels = warped
        .pixels()
        .map(|p| {
            let [r, g, b, a] = p.0;
            let a = f32::from(a) * OPACITY;
            let c = |v: u8, t: f32| (f32::from(v) * t).round() as u8;
            Color32::from_rgba_unmultiplied(c(r, tint[0]), c(g, tint[1]), c(b, tint[2]), a as u8)
        })
        .collect();
    Ok(ColorImage::new([gw as usize, gh as usize], pixels))
}
