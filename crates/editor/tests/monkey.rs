//! The monkey: the real editor driven by a seeded random sequence of everything a user
//! can do — every shortcut, toolbar button and checkbox, clicks, drags (plain, Alt,
//! Shift, middle), Delete or undo in the middle of a drag, new parameters and
//! densities, opening, saving, exporting, dropped files, cancelled jobs, the cage tool
//! (polygons clicked and closed or not, cages from the outline, solves finished and
//! cancelled, vertices and boxes dragged at rest and posed) — in every state (no
//! handles, one, many, after Clear, no cage, a cage drawn, solved, posed, during a
//! background job). After every action the editor must not have panicked and
//! [`EditorApp::sanity_check`] must hold; at random points the project is saved and
//! reopened ([`editor::Document::check_reopens`]) and must build the same mesh, virtual
//! handles and weights, bit for bit, and put every vertex in the same place.
//!
//! CI runs a short walk. A long one:
//! `MONKEY_ACTIONS=5000 MONKEY_SEEDS=1,2,3,4,5,6,7,8 cargo test --release -p editor
//! --test integration monkey -- --nocapture` (a failing walk prints its seed and last actions;
//! `MONKEY_SEEDS=<seed>` replays it).

use crate::support;

use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::time::Instant;

use egui::{Key, Modifiers, Pos2, Vec2};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use glam::DVec2;
use project::{LbcSettings, MetricChoice, Tau};

use editor::{Answer, Dialogs, Edit, EditorApp, FileAction};
use support::{Dropped, build, settle};

/// A small, seedable generator (xorshift64*), so a walk replays exactly.
struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1)
    }

    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    /// Uniform in `0..n`.
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    /// Uniform in `[0, 1)`.
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }

    fn chance(&mut self, p: f32) -> bool {
        self.unit() < p
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// Answers file dialogs with files in a folder (some missing, some broken), or, for
/// some walks, as a desktop without dialogs (the built-in one opens).
struct MonkeyDialogs {
    dir: PathBuf,
    rng: Rng,
    desktop: bool,
}

impl Dialogs for MonkeyDialogs {
    fn ask(&mut self, action: FileAction, _suggested: &str) -> Answer {
        if !self.desktop {
            return Answer::Unavailable;
        }
        if self.rng.chance(0.15) {
            return Answer::Cancelled;
        }
        let names: &[&str] = match action {
            FileAction::OpenImage => &[
                "small.png",
                "lizard.png",
                "layers.ora",
                "corrupt.png",
                "missing.png",
            ],
            FileAction::OpenProject => &["project.json", "broken.json", "missing.json"],
            FileAction::SaveProject => &["project.json", "project.json", "no-folder/p.json"],
            FileAction::ExportPng => &["warped.png", "no-folder/w.png"],
            FileAction::ExportLayers => &["warped.ora", "no-folder/w.ora", "small.png"],
            FileAction::ExportAnimation => &["anim.png", "anim.gif", "no-folder/a.webp"],
        };
        Answer::Chosen(self.dir.join(self.rng.pick(names)))
    }
}

/// The files the walk opens and drops.
fn write_files(dir: &Path) {
    std::fs::write(dir.join("lizard.png"), pipeline::DEFAULT_IMAGE).expect("write");
    std::fs::write(dir.join("corrupt.png"), b"\x89PNG but not really").expect("write");
    std::fs::write(dir.join("broken.json"), b"{\"version\": 1, \"handles\": [").expect("write");
    // A small cut-out: a disc with a hole and a stray speck.
    let small = image::RgbaImage::from_fn(120, 90, |x, y| {
        let d = (x as f32 - 60.0).hypot(y as f32 - 45.0);
        let inside = (d < 40.0 && d > 8.0) || (x == 5 && y == 5);
        image::Rgba([
            200,
            (x * 2) as u8,
            (y * 2) as u8,
            if inside { 255 } else { 0 },
        ])
    });
    small.save(dir.join("small.png")).expect("write");
    // Two layers that overlap, to be drawn as parts and reordered.
    let disc = |cx: f32, colour: [u8; 3]| {
        let [r, g, b] = colour;
        render::Picture::Rgba8(image::RgbaImage::from_fn(120, 90, |x, y| {
            let inside = (x as f32 - cx).hypot(y as f32 - 45.0) < 30.0;
            image::Rgba([r, g, b, if inside { 255 } else { 0 }])
        }))
    };
    let layer = |name: &str, pixels| pipeline::Layer {
        name: name.into(),
        x: 0,
        y: 0,
        opacity: 1.0,
        visible: true,
        pixels,
    };
    let artwork = pipeline::Artwork {
        width: 120,
        height: 90,
        layers: vec![
            layer("back", disc(45.0, [200, 60, 40])),
            layer("front", disc(75.0, [40, 60, 200])),
        ],
        notes: Vec::new(),
    };
    pipeline::write_ora(&dir.join("layers.ora"), &artwork).expect("write");
}

struct Monkey {
    h: Harness<'static, EditorApp>,
    rng: Rng,
    dir: PathBuf,
    trail: Vec<String>,
}

const LABELS: &[&str] = &[
    "Puppet",
    "Select",
    "Add point",
    "Add bar",
    "Rigidity",
    "Cut",
    "Clear cuts",
    "C² weights",
    "ARAP",
    "MLS",
    "Clear rigidity",
    "Bring forward",
    "Send backward",
    "Automatic depth",
    "Overlap regions",
    "Draw as parts",
    "Bring back forward",
    "Send back backward",
    "Bring front forward",
    "Send front backward",
    "Lock back against new pins and paint",
    "Lock front against new pins and paint",
    "back",
    "front",
    "Painted rigidity",
    "Delete handle",
    "Clear all handles",
    "Reset pose",
    "Undo",
    "Redo",
    "Fit to window",
    "Auto-rotate points",
    "Fixed boundary",
    "Show mesh",
    "Virtual handles",
    "Voronoi cells",
    "Dual graph",
    "Weight heat map",
    "Fold-overs",
    "Weights under cursor",
    "Cancel",
    "Discard",
    "Replace",
    "Save",
    "Open",
    "Cage",
    "LBC cage",
    "Close cage",
    "Cancel drawing",
    "Use the kept cage",
    "Solve",
    "Edit the rest cage",
    "Pose the cage",
    "New cage",
    "Clear cage",
    "Cage from outline",
    "Cage from outline",
    "Support contour (0.001/n)",
    "Locality plots",
    "Perform",
    "Place marker",
    "Clear markers",
    "Set key",
    "Set key",
    "Delete key",
    "Hold",
    "Copy pose",
    "Paste key",
    "Loop",
    "Onion skin",
    "⏺ Record",
    "Every frame",
    "▶ Play",
    "⏸ Pause",
    "⏮",
    "⏭",
    "⏴",
    "⏵",
    "Export animation…",
    "Export…",
];

const KEYS: &[(Modifiers, Key)] = &[
    (Modifiers::NONE, Key::W),
    (Modifiers::NONE, Key::V),
    (Modifiers::NONE, Key::P),
    (Modifiers::NONE, Key::B),
    (Modifiers::NONE, Key::R),
    (Modifiers::NONE, Key::X),
    (Modifiers::NONE, Key::K),
    (Modifiers::NONE, Key::K),
    (Modifiers::NONE, Key::Enter),
    (Modifiers::NONE, Key::Enter),
    (Modifiers::NONE, Key::F),
    (Modifiers::NONE, Key::M),
    (Modifiers::NONE, Key::H),
    (Modifiers::NONE, Key::C),
    (Modifiers::NONE, Key::G),
    (Modifiers::NONE, Key::N),
    (Modifiers::SHIFT, Key::N),
    (Modifiers::NONE, Key::Delete),
    (Modifiers::NONE, Key::Backspace),
    (Modifiers::NONE, Key::Escape),
    (Modifiers::NONE, Key::F1),
    (Modifiers::COMMAND, Key::Z),
    (Modifiers::COMMAND, Key::Y),
    (Modifiers::COMMAND.plus(Modifiers::SHIFT), Key::Z),
    (Modifiers::COMMAND, Key::S),
    (Modifiers::COMMAND.plus(Modifiers::SHIFT), Key::S),
    (Modifiers::COMMAND, Key::E),
    (Modifiers::COMMAND, Key::O),
    (Modifiers::COMMAND.plus(Modifiers::SHIFT), Key::O),
    (Modifiers::NONE, Key::Y),
    (Modifiers::NONE, Key::I),
    (Modifiers::NONE, Key::I),
    (Modifiers::NONE, Key::Comma),
    (Modifiers::NONE, Key::Period),
    (Modifiers::NONE, Key::Period),
    (Modifiers::SHIFT, Key::Comma),
    (Modifiers::SHIFT, Key::Period),
    (Modifiers::NONE, Key::Space),
];

impl Monkey {
    fn frames(&mut self, n: usize) {
        for _ in 0..n {
            self.h.step();
        }
    }

    /// A point on the canvas: often on or near a handle or a cage vertex (at rest or
    /// posed), else anywhere.
    fn somewhere(&mut self) -> Pos2 {
        let app = self.h.state();
        let canvas = app.viewport.canvas;
        let handles: Vec<DVec2> = app
            .document()
            .map(|d| {
                let mut points: Vec<DVec2> =
                    d.project().handles.iter().flat_map(editor::posed).collect();
                points.extend(d.cage_rest());
                points.extend(d.cage_pose());
                points.extend(app.cage_draft().unwrap_or_default());
                points.extend(
                    d.project()
                        .animation
                        .iter()
                        .flat_map(|a| a.spatial_keys.iter().map(|k| DVec2::from(k.at))),
                );
                points
            })
            .unwrap_or_default();
        if !handles.is_empty() && self.rng.chance(0.5) {
            let p = *self.rng.pick(&handles);
            let jitter = Vec2::new(self.rng.unit() - 0.5, self.rng.unit() - 0.5) * 8.0;
            return app.viewport.to_screen(p) + jitter;
        }
        // Slightly beyond the canvas now and then.
        let r = canvas.expand(20.0);
        Pos2::new(
            r.min.x + self.rng.unit() * r.width(),
            r.min.y + self.rng.unit() * r.height(),
        )
    }

    fn modifiers(&mut self) -> Modifiers {
        *self.rng.pick(&[
            Modifiers::NONE,
            Modifiers::NONE,
            Modifiers::NONE,
            Modifiers::ALT,
            Modifiers::SHIFT,
        ])
    }

    fn button(&self, pos: Pos2, button: egui::PointerButton, pressed: bool, modifiers: Modifiers) {
        self.h.event(egui::Event::PointerButton {
            pos,
            button,
            pressed,
            modifiers,
        });
    }

    /// One random action; returns what it did.
    fn act(&mut self) -> String {
        match self.rng.below(100) {
            0..=8 => self.cage(),
            9..=24 => {
                let (modifiers, key) = *self.rng.pick(KEYS);
                self.h.key_press_modifiers(modifiers, key);
                self.frames(2);
                format!("key {modifiers:?} {key:?}")
            }
            25..=39 => {
                let label = *self.rng.pick(LABELS);
                // A label can show twice (the Edit menu and the side panel).
                let count = self.h.query_all_by_label(label).count();
                let found = count > 0;
                if found {
                    let which = self.rng.below(count);
                    if let Some(node) = self.h.query_all_by_label(label).nth(which) {
                        node.click();
                    }
                }
                self.frames(2);
                format!("click {label:?}{}", if found { "" } else { " (absent)" })
            }
            40..=54 => {
                let pos = self.somewhere();
                let modifiers = self.modifiers();
                self.h.event(egui::Event::ModifiersChanged(modifiers));
                self.h.hover_at(pos);
                self.frames(1);
                self.button(pos, egui::PointerButton::Primary, true, modifiers);
                self.frames(1);
                self.button(pos, egui::PointerButton::Primary, false, modifiers);
                self.h.event(egui::Event::ModifiersChanged(Modifiers::NONE));
                self.frames(2);
                format!("click {pos:?} {modifiers:?}")
            }
            55..=79 => self.drag(),
            80..=84 => {
                let pos = self.somewhere();
                self.h.hover_at(pos);
                self.h.event(egui::Event::MouseWheel {
                    unit: egui::MouseWheelUnit::Point,
                    delta: Vec2::new(0.0, (self.rng.unit() - 0.5) * 400.0),
                    phase: egui::TouchPhase::Move,
                    modifiers: Modifiers::NONE,
                    source: egui::MouseWheelSource::Wheel,
                });
                self.frames(2);
                format!("wheel at {pos:?}")
            }
            85..=87 => self.settings(),
            88..=89 => self.cage_settings(),
            90..=92 => {
                let name = *self
                    .rng
                    .pick(&["small.png", "lizard.png", "corrupt.png", "nope.png"]);
                let path = self.dir.join(name);
                self.h
                    .input_mut()
                    .dropped_files
                    .push(std::sync::Arc::new(Dropped(path)));
                self.frames(2);
                format!("drop {name}")
            }
            93..=96 => {
                // Let a running job finish (or not start anything).
                self.wait_for_job();
                "wait for the job".to_owned()
            }
            97 => self.perform(),
            98 => self.pin_in_pose(),
            99 if self.rng.chance(0.5) => self.remove_in_pose(),
            _ => {
                let size = *self.rng.pick(&[
                    Vec2::new(1200.0, 800.0),
                    Vec2::new(700.0, 500.0),
                    Vec2::new(1500.0, 950.0),
                ]);
                self.h.set_size(size);
                self.frames(2);
                format!("window {size:?}")
            }
        }
    }

    /// Steps the editor until its background job is done (a minute at most), then a
    /// frame more.
    fn wait_for_job(&mut self) {
        let start = Instant::now();
        while self.h.state().is_busy() && start.elapsed().as_secs() < 60 {
            self.h.step();
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        self.frames(1);
    }

    /// A handle removed in a posed state, as the Delete key removes the one selected
    /// (the walk checks that the picture away from it does not move).
    fn remove_in_pose(&mut self) -> String {
        let app = self.h.state();
        let Some(count) = (app.document())
            .filter(|d| !app.is_busy() && d.project().is_posed())
            .map(|d| d.project().handles.len())
            .filter(|&n| n > 0)
        else {
            return "remove in a pose (not now)".to_owned();
        };
        let i = self.rng.below(count);
        let done = self.h.state_mut().edit(Edit::Remove(i));
        self.frames(2);
        format!("remove handle {i} in a pose (applied={done})")
    }

    /// A pin clicked onto the picture under a handle method, in whatever pose it is in
    /// (the walk checks that it moves nothing): the Puppet tool, a click on a vertex of
    /// the picture where it is shown.
    fn pin_in_pose(&mut self) -> String {
        let app = self.h.state();
        let usable = !app.is_busy()
            && app
                .document()
                .is_some_and(|d| d.method().controls() == project::Controls::Handles);
        if !usable {
            return "pin in a pose (not now)".to_owned();
        }
        if self.h.state().tool != editor::Tool::Puppet {
            // (A tool changes nothing on the picture: on to the click.)
            self.h.key_press(Key::W);
            self.frames(1);
        }
        let Some(doc) = self.h.state_mut().document_mut() else {
            return "pin in a pose (no picture)".to_owned();
        };
        let shown = doc.deformed().to_vec();
        if shown.is_empty() {
            return "pin in a pose (no mesh)".to_owned();
        }
        let at = shown[self.rng.below(shown.len())];
        let pos = self.h.state().viewport.to_screen(at);
        self.h.hover_at(pos);
        self.frames(1);
        self.button(pos, egui::PointerButton::Primary, true, Modifiers::NONE);
        self.frames(1);
        self.button(pos, egui::PointerButton::Primary, false, Modifiers::NONE);
        self.frames(2);
        format!("pin in a pose at {at}")
    }

    /// The perform tool: a pose marker placed (with the button or Ctrl + click), or the
    /// control cursor dragged.
    fn perform(&mut self) -> String {
        if self.h.state().tool != editor::Tool::Perform {
            self.h.key_press(Key::Y);
            self.frames(1);
        }
        let pos = self.somewhere();
        match self.rng.below(3) {
            0 => {
                if let Some(node) = self.h.query_by_label("Place marker") {
                    node.click();
                    self.frames(1);
                }
                self.h.hover_at(pos);
                self.frames(1);
                self.button(pos, egui::PointerButton::Primary, true, Modifiers::NONE);
                self.frames(1);
                self.button(pos, egui::PointerButton::Primary, false, Modifiers::NONE);
                self.frames(2);
                format!("place a marker at {pos:?}")
            }
            1 => {
                let ctrl = Modifiers::COMMAND;
                self.h.event(egui::Event::ModifiersChanged(ctrl));
                self.h.hover_at(pos);
                self.frames(1);
                self.button(pos, egui::PointerButton::Primary, true, ctrl);
                self.frames(1);
                self.button(pos, egui::PointerButton::Primary, false, ctrl);
                self.h.event(egui::Event::ModifiersChanged(Modifiers::NONE));
                self.frames(2);
                format!("Ctrl + click at {pos:?}")
            }
            _ => format!("perform: {}", self.drag()),
        }
    }

    /// A drag with a random button, modifiers and length; sometimes Delete, undo or a
    /// tool switch arrives in the middle, sometimes it ends off the canvas.
    fn drag(&mut self) -> String {
        // Now and then along the timeline: scrubbing, or moving a key.
        let strip = if self.rng.chance(0.12) {
            self.h.query_by_label("Timeline").map(|node| node.rect())
        } else {
            None
        };
        let in_strip = |rng: &mut Rng, r: egui::Rect| {
            Pos2::new(
                r.min.x + rng.unit() * r.width(),
                r.min.y + rng.unit() * r.height(),
            )
        };
        let from = match strip {
            Some(r) => in_strip(&mut self.rng, r),
            None => self.somewhere(),
        };
        let to = if let Some(r) = strip {
            in_strip(&mut self.rng, r.expand(30.0))
        } else if self.rng.chance(0.8) {
            from + Vec2::new(self.rng.unit() - 0.5, self.rng.unit() - 0.5) * 300.0
        } else {
            self.somewhere()
        };
        let button = if self.rng.chance(0.1) {
            egui::PointerButton::Middle
        } else {
            egui::PointerButton::Primary
        };
        let modifiers = self.modifiers();
        let steps = 2 + self.rng.below(8);
        let interrupt = if self.rng.chance(0.4) {
            Some(*self.rng.pick(&[
                (Modifiers::NONE, Key::Delete),
                (Modifiers::NONE, Key::Delete),
                (Modifiers::COMMAND, Key::Z),
                (Modifiers::COMMAND.plus(Modifiers::SHIFT), Key::Z),
                (Modifiers::NONE, Key::B),
                (Modifiers::NONE, Key::Escape),
                (Modifiers::NONE, Key::C),
                (Modifiers::COMMAND, Key::O),
                (Modifiers::NONE, Key::I),
                (Modifiers::NONE, Key::Space),
                (Modifiers::NONE, Key::Y),
            ]))
        } else {
            None
        };
        let at_step = self.rng.below(steps - 1);
        // Several events in one frame now and then: a quick gesture.
        let quick = self.rng.chance(0.2);
        self.h.event(egui::Event::ModifiersChanged(modifiers));
        self.h.hover_at(from);
        if !quick {
            self.frames(1);
        }
        self.button(from, button, true, modifiers);
        for i in 1..=steps {
            self.h
                .hover_at(from + (to - from) * (i as f32 / steps as f32));
            if !quick {
                self.frames(1);
            }
            if i - 1 == at_step
                && let Some((m, k)) = interrupt
            {
                self.h.key_press_modifiers(m, k);
                self.frames(1);
            }
        }
        self.button(to, button, false, modifiers);
        self.h.event(egui::Event::ModifiersChanged(Modifiers::NONE));
        self.frames(2);
        format!(
            "drag {button:?} {from:?} -> {to:?} {modifiers:?} in {steps} quick={quick} interrupt={interrupt:?}"
        )
    }

    /// Something with the cage tool: a polygon clicked (closed on its first vertex,
    /// by Enter, by a double click, or left open), a cage from the outline, a solve
    /// (waited for or not), or a drag from a cage vertex.
    fn cage(&mut self) -> String {
        if self.h.state().tool != editor::Tool::Cage {
            self.h.key_press(Key::K);
            self.frames(2);
        }
        match self.rng.below(6) {
            0 | 1 => {
                let canvas = self.h.state().viewport.canvas;
                let centre = Pos2::new(
                    canvas.min.x + self.rng.unit() * canvas.width(),
                    canvas.min.y + self.rng.unit() * canvas.height(),
                );
                let n = 3 + self.rng.below(6);
                let radius = 20.0 + self.rng.unit() * 200.0;
                // Now and then out of order, so that edges cross.
                let shuffle = self.rng.chance(0.2);
                let mut points = Vec::new();
                for i in 0..n {
                    let turn = if shuffle {
                        self.rng.unit()
                    } else {
                        i as f32 / n as f32
                    };
                    let angle = turn * std::f32::consts::TAU;
                    let pos = centre + Vec2::angled(angle) * radius;
                    points.push(pos);
                    self.h.hover_at(pos);
                    self.frames(1);
                    self.button(pos, egui::PointerButton::Primary, true, Modifiers::NONE);
                    self.frames(1);
                    self.button(pos, egui::PointerButton::Primary, false, Modifiers::NONE);
                    self.frames(1);
                }
                let close = self.rng.below(4);
                match close {
                    0 => {
                        let first = points[0];
                        self.h.hover_at(first);
                        self.frames(1);
                        self.button(first, egui::PointerButton::Primary, true, Modifiers::NONE);
                        self.frames(1);
                        self.button(first, egui::PointerButton::Primary, false, Modifiers::NONE);
                    }
                    1 => self.h.key_press(Key::Enter),
                    2 => {
                        let last = points[n - 1];
                        self.button(last, egui::PointerButton::Primary, true, Modifiers::NONE);
                        self.button(last, egui::PointerButton::Primary, false, Modifiers::NONE);
                    }
                    _ => {}
                }
                self.frames(2);
                format!("cage of {n} clicked around {centre:?} (shuffled {shuffle}, close {close})")
            }
            2 => {
                let found = self.h.query_by_label("Cage from outline").is_some();
                if let Some(node) = self.h.query_by_label("Cage from outline") {
                    node.click();
                }
                self.frames(2);
                format!("cage from outline (found {found})")
            }
            3 => {
                self.h.key_press(Key::Enter);
                self.frames(1);
                let wait = self.rng.chance(0.7);
                let start = Instant::now();
                while wait && self.h.state().is_busy() && start.elapsed().as_secs() < 60 {
                    self.h.step();
                    std::thread::sleep(std::time::Duration::from_millis(5));
                }
                self.frames(1);
                format!("Enter with the cage tool, waited {wait}")
            }
            _ => {
                // From a cage vertex (somewhere() picks them often) or from empty canvas.
                self.drag()
            }
        }
    }

    /// New LBC settings (τ, a few mesh vertices inside the cage), as the side panel
    /// applies them.
    fn cage_settings(&mut self) -> String {
        let tau = *self
            .rng
            .pick(&[Tau::Square, Tau::Linear, Tau::Sqrt, Tau::Constant]);
        let density = *self.rng.pick(&[60, 120, 200]);
        let settings = LbcSettings {
            tau,
            density: Some(density),
        };
        let applied = self.h.state_mut().edit(Edit::Lbc(settings));
        self.frames(2);
        format!("cage settings {settings:?} applied={applied}")
    }

    /// New weighting parameters, as the side panel applies them.
    fn settings(&mut self) -> String {
        let Some(doc) = self.h.state().document() else {
            return "settings (no document)".to_owned();
        };
        let mut s = doc.settings();
        match self.rng.below(6) {
            0 => s.alpha = f64::from(self.rng.unit()),
            1 => s.degree = 5 + self.rng.below(21) as u32,
            2 => s.fixed_boundary = !s.fixed_boundary,
            3 => {
                s.metric = *self.rng.pick(&[
                    MetricChoice::Auto,
                    MetricChoice::Euclidean,
                    MetricChoice::Intrinsic,
                ])
            }
            _ => s.density = *self.rng.pick(&[500, 1500, 3000, 6000]),
        }
        let applied = self.h.state_mut().edit(Edit::Settings(s));
        self.frames(2);
        format!("settings {s:?} applied={applied}")
    }
}

fn walk(seed: u64, actions: usize) {
    let dir = tempfile::tempdir().expect("temp dir");
    write_files(dir.path());
    let mut rng = Rng::new(seed);
    let dialogs = MonkeyDialogs {
        dir: dir.path().to_path_buf(),
        rng: Rng::new(seed ^ 0xd1a1),
        desktop: !rng.chance(0.3),
    };
    let gpu = seed.is_multiple_of(4);
    // The built-in dialog's text fields carry no accessible names.
    let builder = Harness::builder()
        .with_accessibility_check(false)
        .with_max_steps(10_000);
    let mut h = build(builder, Box::new(dialogs), gpu);
    // New cages are solved on a small mesh, so a debug build solves in a second.
    h.state_mut().cage.inside_vertices = 120;
    let mut monkey = Monkey {
        h,
        rng,
        dir: dir.path().to_path_buf(),
        trail: Vec::new(),
    };
    // Start smaller than the built-in 20k vertices now and then, to walk faster.
    if monkey.rng.chance(0.5) {
        let mut s = monkey.h.state().document().expect("built-in").settings();
        s.density = 3000;
        assert!(monkey.h.state_mut().edit(Edit::Settings(s)));
    }
    // A third of the walks (seeds 2, 5, 8, …) start on a layered picture drawn as
    // parts.
    if seed % 3 == 2 {
        let layered = monkey.dir.join("layers.ora");
        // (After the new density's rebuild, if one was asked for above.)
        settle(&mut monkey.h);
        monkey.h.state_mut().open(&layered);
        let parts = Some(project::PartsSpec::default());
        assert!(monkey.h.state_mut().edit(Edit::Parts(parts)));
        settle(&mut monkey.h);
        let drawn = monkey
            .h
            .state()
            .document()
            .is_some_and(|d| d.parts().is_some());
        println!("monkey seed {seed}: starts on a layered picture drawn as parts: {drawn}");
    }
    let clock = Instant::now();
    let mut slowest: Vec<(f64, String)> = Vec::new();
    // Actions taken in each state of the cage tool: drawing, at rest, posed.
    let mut cage_states = [0usize; 3];
    // Times the project was saved and reopened to compare.
    let mut reopened = 0usize;
    // Actions taken with two keys or more, the most keys seen, actions with markers.
    let (mut keyed, mut most_keys, mut marked) = (0usize, 0usize, 0usize);
    // Actions taken with cuts in the project, and with a layered picture drawn as parts.
    let (mut with_cuts, mut with_parts) = (0usize, 0usize);
    // Pins placed under ARAP or C², each checked to have moved nothing.
    let mut held = 0usize;
    // Handles removed in a posed state under C², each checked to have moved nothing
    // away from it.
    let mut removed_checked = 0usize;
    for step in 0..actions {
        let result = std::panic::catch_unwind(AssertUnwindSafe(|| {
            // What the picture was, to check that a pin placed under ARAP or C² (in
            // any pose) moves nothing. Not while a job runs: one that lands during the
            // action (a rig rebuilt for new settings) moves the picture by its own
            // change, and the canvas takes clicks again the moment it has landed.
            let idle = !monkey.h.state().is_busy();
            let before = monkey
                .h
                .state_mut()
                .document_mut()
                .filter(|d| idle && d.method().controls() == project::Controls::Handles)
                .map(|d| {
                    let handles = d.project().handles.clone();
                    // Posed, with a handle of the partition left after any removal.
                    let project = d.project();
                    let posed =
                        project.is_posed() && project.handles.len() >= project.overlaid.len() + 2;
                    // Drawn as parts: the joined mesh.
                    let parts = d.parts().map(|p| {
                        use pipeline::Deformer as _;
                        p.rest().to_vec()
                    });
                    (
                        handles,
                        d.mesh_version(),
                        d.deformed().to_vec(),
                        posed,
                        parts,
                    )
                });
            let started = Instant::now();
            let what = monkey.act();
            // (Only the action that clicks one pin onto the picture is checked: others
            // that add a handle may also move the playhead or pose.)
            let pinned = what.starts_with("pin in a pose at");
            slowest.push((started.elapsed().as_secs_f64(), what.clone()));
            monkey.trail.push(what);
            let reopen = monkey.rng.chance(0.08);
            let app = monkey.h.state();
            if app.tool == editor::Tool::Cage {
                cage_states[app.cage_state() as usize] += 1;
            }
            let keys = app.keys().len();
            keyed += usize::from(keys >= 2);
            most_keys = most_keys.max(keys);
            marked += usize::from(app.document().is_some_and(|d| {
                d.project()
                    .animation
                    .as_ref()
                    .is_some_and(|a| !a.spatial_keys.is_empty())
            }));
            with_cuts += usize::from(app.document().is_some_and(|d| !d.project().cuts.is_empty()));
            with_parts += usize::from(app.document().is_some_and(|d| d.parts().is_some()));
            app.sanity_check()?;
            if let (Some((handles, mesh, shown, posed, parts)), Some(doc)) =
                (before, monkey.h.state_mut().document_mut())
            {
                let now = doc.project().handles.clone();
                let placed = now.len() == handles.len() + 1 && now[..handles.len()] == handles[..];
                // On one picture a new pin holds it where it was under every handle
                // method (MLS by a shape carried). Drawn as parts it holds each part
                // it binds (ARAP by its holds, C² and MLS by shapes carried), and a
                // part that only followed another until then carries the shape
                // following gave it — unless its parts were meshed anew (C² meshes a
                // pin's point in).
                let holding = match doc.parts() {
                    None => true,
                    Some(now) => {
                        use pipeline::Deformer as _;
                        parts
                            .as_ref()
                            .is_some_and(|rest| now.rest() == rest.as_slice())
                    }
                };
                if pinned && placed && doc.mesh_version() == mesh && holding {
                    held += 1;
                    let moved = shown
                        .iter()
                        .zip(doc.deformed())
                        .map(|(a, b)| a.distance(*b))
                        .fold(0.0, f64::max);
                    anyhow::ensure!(
                        moved <= 0.1,
                        "a pin placed under {} moved the picture by {moved} px ({} handles, \
                         overlaid {:?}, keys {})",
                        doc.method().label(),
                        now.len(),
                        doc.project().overlaid,
                        doc.keys().len()
                    );
                }
                // A handle removed in a posed state under ARAP and MLS moves nothing
                // farther than twice its distance to the next handle (the picture keeps
                // its shape there); under C² nothing there by more than 5 px (the
                // issue's target; measured 1.63 px at most on three cut-outs), nor by more than
                // its own points move: what it held now follows the others, and the
                // virtual handles' transforms change by the harmonic extension of that
                // (a bar held at rest among handles dragged 40–150 px moved 17.8 px, and
                // the picture twice its distance away 9.9 px).
                let removed = (now.len() + 1 == handles.len())
                    .then(|| {
                        (0..now.len())
                            .find(|&i| now[i] != handles[i])
                            .unwrap_or(now.len())
                    })
                    .filter(|&i| now[i..] == handles[i + 1..]);
                if let Some(i) = removed
                    && posed
                    && doc.mesh_version() == mesh
                    && doc.parts().is_none()
                    // (A fixed border is sampled at the closest pair's distance: a
                    // removal may re-sample it, as the paper has it.)
                    && !doc.project().fixed_boundary
                {
                    removed_checked += 1;
                    let ends = |h: &project::HandleSpec| match *h {
                        project::HandleSpec::Point { rest, .. } => [rest; 2].map(DVec2::from),
                        project::HandleSpec::Bar { rest, .. } => rest.map(DVec2::from),
                    };
                    let gone = ends(&handles[i]);
                    let reach = 2.0
                        * now
                            .iter()
                            .map(|h| {
                                let e = ends(h);
                                geometry::segment_distance(gone, e)
                            })
                            .fold(f64::INFINITY, f64::min);
                    let rest = doc.mesh().positions().to_vec();
                    let edge = doc.mesh().mean_edge_length();
                    let (mut moved, mut own) = (0.0f64, 0.0f64);
                    for ((a, b), p) in shown.iter().zip(doc.deformed()).zip(&rest) {
                        let from = geometry::point_segment_distance(*p, gone[0], gone[1]);
                        if from > reach {
                            moved = moved.max(a.distance(*b));
                        } else if from <= edge {
                            own = own.max(a.distance(*b));
                        }
                    }
                    // Under ARAP and MLS the picture keeps its shape there exactly (a
                    // shape carried, to 10⁻⁷ px).
                    let bound = match doc.method() {
                        project::Method::C2 => own.max(5.0),
                        _ => 1e-5,
                    };
                    anyhow::ensure!(
                        moved <= bound,
                        "removing handle {i} under {} moved the picture {moved} px away from \
                         it, its own points {own} px",
                        doc.method().label()
                    );
                }
            }
            let app = monkey.h.state();
            // Saved and reopened at random points, the project builds what is on screen.
            match app.document() {
                Some(doc) if reopen && !app.is_busy() => {
                    reopened += 1;
                    doc.check_reopens()
                }
                _ => Ok(()),
            }
        }));
        let failure = match result {
            Ok(Ok(())) => None,
            Ok(Err(e)) => Some(format!("{e:#}")),
            Err(panic) => Some(
                panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| (*s).to_owned()))
                    .unwrap_or_else(|| "a panic".to_owned()),
            ),
        };
        if let Some(failure) = failure {
            let from = monkey.trail.len().saturating_sub(25);
            panic!(
                "seed {seed}, action {step}: {failure}\nlast actions:\n  {}",
                monkey.trail[from..].join("\n  ")
            );
        }
    }
    // Walk the whole history back and forth.
    let walk_history = |monkey: &mut Monkey, back: bool| {
        for _ in 0..600 {
            while monkey.h.state().is_busy() {
                monkey.h.step();
                std::thread::sleep(std::time::Duration::from_millis(5));
            }
            if back {
                monkey.h.state_mut().undo();
            } else {
                monkey.h.state_mut().redo();
            }
            monkey.frames(1);
            if let Err(e) = monkey.h.state().sanity_check() {
                panic!("seed {seed}, walking the history: {e:#}");
            }
        }
    };
    walk_history(&mut monkey, true);
    walk_history(&mut monkey, false);
    let seconds = clock.elapsed().as_secs_f64();
    println!(
        "monkey seed {seed}: {actions} actions in {seconds:.1} s ({:.0} actions/s), gpu={gpu}",
        actions as f64 / seconds
    );
    println!(
        "  with the cage tool: {} actions drawing, {} at rest, {} posed; reopened {reopened} \
         times",
        cage_states[0], cage_states[1], cage_states[2]
    );
    println!(
        "  with two keys or more: {keyed} actions (at most {most_keys} keys); with pose \
         markers: {marked}; pins placed in a pose, none moving the picture: {held}; handles removed in a pose, checked: \
         {removed_checked}; with cuts: {with_cuts}; with parts: {with_parts}"
    );
    slowest.sort_by(|a, b| b.0.total_cmp(&a.0));
    for (s, what) in slowest.iter().take(3) {
        println!("  slowest: {s:.2} s  {what}");
    }
}

fn env_list(name: &str, default: &[u64]) -> Vec<u64> {
    std::env::var(name).map_or_else(
        |_| default.to_vec(),
        |v| v.split(',').filter_map(|s| s.trim().parse().ok()).collect(),
    )
}

/// Walks the seeds `MONKEY_SEEDS` names, or `default` (one test per default seed, so
/// that the walks run side by side on a machine's cores).
fn walk_seeds(default: u64) {
    let actions = env_list("MONKEY_ACTIONS", &[200])[0] as usize;
    match std::env::var("MONKEY_SEEDS") {
        // Named seeds are walked once, by the first test.
        Ok(_) if default != 1 => {}
        Ok(_) => env_list("MONKEY_SEEDS", &[])
            .into_iter()
            .for_each(|s| walk(s, actions)),
        Err(_) => walk(default, actions),
    }
}

#[test]
fn the_monkey_finds_nothing() {
    walk_seeds(1);
}

#[test]
fn the_monkey_finds_nothing_drawing_cages() {
    walk_seeds(2);
}

#[test]
fn the_monkey_finds_nothing_on_the_gpu() {
    walk_seeds(4);
}
