//! Helpers shared by the editor's UI tests: the real app in an egui_kittest harness,
//! file dialogs answered by script, pointer gestures in image pixels.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use egui::{Modifiers, Pos2, Vec2};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use glam::DVec2;
use project::HandleSpec;

use editor::{Answer, Dialogs, EditorApp, FileAction};

/// A cage clicked around the lizard's body (image pixels, at rest).
pub const BODY: [[f64; 2]; 6] = [
    [220.0, 200.0],
    [390.0, 190.0],
    [450.0, 300.0],
    [390.0, 430.0],
    [240.0, 430.0],
    [170.0, 320.0],
];

/// Answers every file dialog with a fixed file in `dir`.
pub struct Scripted {
    pub dir: PathBuf,
}

impl Dialogs for Scripted {
    fn ask(&mut self, action: FileAction, _suggested: &str) -> Answer {
        let name = match action {
            FileAction::OpenImage => "lizard.png",
            FileAction::OpenProject | FileAction::SaveProject => "project.json",
            FileAction::ExportPng => "warped.png",
            FileAction::ExportLayers => "warped.ora",
            FileAction::ExportAnimation => "animation.png",
        };
        Answer::Chosen(self.dir.join(name))
    }
}

/// The editor on the built-in picture, drawn through wgpu (the software adapter), its
/// file dialogs answered with files in `dir`.
pub fn editor(dir: &Path) -> Harness<'static, EditorApp> {
    editor_with(
        Box::new(Scripted {
            dir: dir.to_path_buf(),
        }),
        true,
    )
}

/// The editor on the built-in picture with these dialogs; with `gpu`, the canvas is
/// drawn through wgpu, else only the CPU side of each frame runs (faster).
pub fn editor_with(dialogs: Box<dyn Dialogs>, gpu: bool) -> Harness<'static, EditorApp> {
    build(Harness::builder(), dialogs, gpu)
}

/// As [`editor_with`], from a harness builder set up by the caller.
pub fn build(
    builder: egui_kittest::HarnessBuilder<EditorApp>,
    dialogs: Box<dyn Dialogs>,
    gpu: bool,
) -> Harness<'static, EditorApp> {
    let mut dialogs = Some(dialogs);
    let builder = builder.with_size(Vec2::new(1200.0, 800.0));
    let builder = if gpu { builder.wgpu() } else { builder };
    let mut harness = builder.build_eframe(move |cc| {
        let mut app = EditorApp::new(cc, &[]);
        // What the built-in dialog saves lands in a scratch folder, not in the crate.
        app.default_folder = Some(scratch_folder());
        if let Some(dialogs) = dialogs.take() {
            app.set_dialogs(dialogs);
        }
        app
    });
    harness.run();
    harness
}

/// A folder of this test process's own for files the built-in dialog writes.
pub fn scratch_folder() -> PathBuf {
    static FOLDER: OnceLock<tempfile::TempDir> = OnceLock::new();
    FOLDER
        .get_or_init(|| tempfile::tempdir().expect("temp dir"))
        .path()
        .to_path_buf()
}

/// Dialogs of a desktop that has none (a bare X session).
pub struct NoDesktop;

impl Dialogs for NoDesktop {
    fn ask(&mut self, _action: FileAction, _suggested: &str) -> Answer {
        Answer::Unavailable
    }
}

/// Where image pixel (x, y) is on screen.
pub fn at(h: &Harness<'_, EditorApp>, x: f64, y: f64) -> Pos2 {
    h.state().viewport.to_screen(DVec2::new(x, y))
}

pub fn click_at(h: &mut Harness<'_, EditorApp>, pos: Pos2) {
    h.hover_at(pos);
    h.run();
    h.drag_at(pos);
    h.run();
    h.drop_at(pos);
    h.run();
}

pub fn drag(h: &mut Harness<'_, EditorApp>, from: Pos2, to: Pos2, modifiers: Modifiers) {
    h.event(egui::Event::ModifiersChanged(modifiers));
    h.hover_at(from);
    h.run();
    h.event(egui::Event::PointerButton {
        pos: from,
        button: egui::PointerButton::Primary,
        pressed: true,
        modifiers,
    });
    h.run();
    for i in 1..=8 {
        h.hover_at(from + (to - from) * (i as f32 / 8.0));
        h.run();
    }
    h.event(egui::Event::PointerButton {
        pos: to,
        button: egui::PointerButton::Primary,
        pressed: false,
        modifiers,
    });
    h.run();
    h.remove_cursor();
    h.event(egui::Event::ModifiersChanged(Modifiers::NONE));
    h.run();
}

/// Steps the UI until the background job (opening, re-meshing) is in.
pub fn settle(h: &mut Harness<'_, EditorApp>) {
    let start = std::time::Instant::now();
    while h.state().is_busy() {
        assert!(start.elapsed().as_secs() < 120, "the job never finished");
        h.step();
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    h.run();
}

pub fn click_label(h: &mut Harness<'_, EditorApp>, label: &str) {
    h.get_by_label(label).click();
    h.step();
    if h.state().is_busy() {
        // The click started a job; the test waits for it where it needs to.
        return;
    }
    h.run();
}

pub fn handles(h: &Harness<'_, EditorApp>) -> Vec<HandleSpec> {
    h.state()
        .document()
        .map(|d| d.project().handles.clone())
        .unwrap_or_default()
}

pub fn translate(h: &HandleSpec) -> DVec2 {
    match h {
        HandleSpec::Point { translate, .. } => DVec2::from(*translate),
        HandleSpec::Bar { .. } => panic!("a point handle"),
    }
}

/// Writes the built-in picture to `dir/lizard.png`.
pub fn write_lizard(dir: &Path) -> PathBuf {
    let path = dir.join("lizard.png");
    std::fs::write(&path, pipeline::DEFAULT_IMAGE).expect("write the picture");
    path
}

/// A file dropped on the window, as the windowing layer reports it.
#[derive(Debug)]
pub struct Dropped(pub PathBuf);

impl egui::DroppedFile for Dropped {
    fn path(&self) -> &Path {
        &self.0
    }
    fn bytes(&self) -> Result<Vec<u8>, String> {
        std::fs::read(&self.0).map_err(|e| e.to_string())
    }
}

/// The share of pixels that differ by more than 8 in some channel.
pub fn changed(a: &image::RgbaImage, b: &image::RgbaImage) -> f64 {
    assert_eq!(a.dimensions(), b.dimensions());
    let differ = a
        .pixels()
        .zip(b.pixels())
        .filter(|(p, q)| p.0.iter().zip(q.0).any(|(x, y)| x.abs_diff(y) > 8))
        .count();
    differ as f64 / (a.width() * a.height()) as f64
}

/// The canvas as drawn (the panels around it show times and messages that differ).
pub fn shot(h: &mut Harness<'_, EditorApp>) -> image::RgbaImage {
    h.run();
    let frame = h.render().expect("a frame drawn on the software adapter");
    let scale = h.ctx.pixels_per_point();
    let canvas = h.state().viewport.canvas;
    let [x, y] = [canvas.min.x * scale, canvas.min.y * scale].map(|v| v.max(0.0) as u32);
    let w = ((canvas.width() * scale) as u32).min(frame.width() - x);
    let h = ((canvas.height() * scale) as u32).min(frame.height() - y);
    image::imageops::crop_imm(&frame, x, y, w, h).to_image()
}

/// File > Export PNG… (the scripted dialog answers `dir/warped.png`), waited for, and
/// the exported picture read back.
pub fn export_png(h: &mut Harness<'_, EditorApp>, dir: &Path) -> image::RgbaImage {
    h.get_by_label("File").click();
    h.run();
    click_label(h, "Export PNG…");
    settle(h);
    image::open(dir.join("warped.png"))
        .expect("an exported PNG")
        .to_rgba8()
}
