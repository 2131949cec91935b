//! The C2Warp editor: open a picture, pin point and bar handles on it, drag, rotate and
//! scale them, insert and remove them while posed, and export the warped PNG; or draw
//! an LBC cage around the subject, solve it, and pose its vertices.
//!
//! The picture is meshed ([`mesh`]), weighted ([`weights_core`]) and drawn as a
//! skinned textured mesh through an egui wgpu paint callback ([`render::MeshView`]):
//! a drag uploads only the node transforms. The [`EditorApp`] holds a [`Document`]
//! (picture + rig file + weighted rig) and an undo history of whole rig files; widgets
//! turn input into [`Edit`]s that one place applies.

mod app;
mod brush;
mod cage;
mod cage_commands;
mod canvas;
mod controls;
mod cut;
mod dialogs;
mod document;
mod gpu_frame;
mod handles;
mod history;
mod jobs;
mod onion;
mod panels;
mod perform;
mod scene;
mod show;
mod timeline;
mod tool;
mod viewport;

use std::path::PathBuf;

pub use app::{AnimationExport, EditorApp, Message, Pending, Tool};
pub use brush::{Brush, erase};
pub use cage::{CageState, CageTool, contour, crossing_edges};
pub use dialogs::{Answer, Dialogs, FileAction, IMAGES, NativeDialogs, desktop_has_dialogs};
pub use document::{CageKey, Document, Edit, PosedMesh, Settings, Shown, posed, solve_cage};
pub use panels::SHORTCUTS;
pub use perform::PerformTool;
pub use scene::SceneResources;
pub use show::Show;
pub use timeline::Timeline;
pub use viewport::Viewport;

/// Opens the editor window on `paths` (a picture, several pictures as the layers of
/// one, or a `.json` project) or, with none, on the
/// built-in picture, and returns when the window closes.
///
/// # Errors
/// No window or no GPU adapter could be had.
pub fn run(paths: Vec<PathBuf>) -> anyhow::Result<()> {
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("C2Warp")
            .with_inner_size([1280.0, 820.0])
            .with_min_inner_size([640.0, 420.0])
            .with_drag_and_drop(true),
        renderer: eframe::Renderer::Wgpu,
        // The mesh pipelines are built for one sample and no depth buffer.
        multisampling: 0,
        depth_buffer: 0,
        ..Default::default()
    };
    eframe::run_native(
        "C2Warp",
        options,
        Box::new(move |cc| Ok(Box::new(EditorApp::new(cc, &paths)))),
    )
    .map_err(|e| {
        anyhow::anyhow!(
            "cannot open the editor window ({e}); without a display, `c2warp render` warps \
             pictures from the command line"
        )
    })
}
