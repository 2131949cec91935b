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
        let mut app = EditorApp::new(cc, None);
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
