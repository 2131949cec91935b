//! The editor in its empty and edge states, and gestures that the document changes
//! under: each test here reproduces something a user ran into.

use crate::support;

use egui::{Key, Modifiers, Pos2, Vec2};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use glam::DVec2;
use project::HandleSpec;

use editor::{Edit, EditorApp, Tool};
use support::{
    Dropped, NoDesktop, at, click_at, click_label, editor, editor_with, handles, settle,
    write_lizard,
};

fn press(h: &mut Harness<'_, EditorApp>, pos: Pos2, pressed: bool, modifiers: Modifiers) {
    h.event(egui::Event::PointerButton {
        pos,
        button: egui::PointerButton::Primary,
        pressed,
        modifiers,
    });
}

/// Where handle `i` is drawn now (a bar: its first end).
fn handle_at(h: &Harness<'_, EditorApp>, i: usize) -> Pos2 {
    let p = editor::posed(&handles(h)[i])[0];
    at(h, p.x, p.y)
}

#[test]
fn the_cells_view_survives_every_way_to_lose_the_last_node() {
    let dir = tempfile::tempdir().expect("temp dir");
    let lizard = write_lizard(dir.path());
    let mut h = editor(dir.path());
    click_label(&mut h, "Voronoi cells");
    assert!(h.state().show.cells);
    // Clear all handles.
    click_label(&mut h, "Clear all handles");
    assert!(handles(&h).is_empty());
    // Undo, redo.
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    assert_eq!(handles(&h).len(), 7);
    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    h.run();
    assert!(handles(&h).is_empty());
    // A picture with no handles, the cells view toggled by its key.
    h.state_mut().open_in_background(lizard);
    settle(&mut h);
    h.key_press(Key::C);
    h.run();
    h.key_press(Key::C);
    h.run();
    assert!(h.state().show.cells);
    // Add the first handle, delete it; add it again and undo the insertion.
    let body = at(&h, 330.0, 330.0);
    click_at(&mut h, body);
    assert_eq!(handles(&h).len(), 1, "{:?}", h.state().message);
    h.key_press(Key::Delete);
    h.run();
    assert!(handles(&h).is_empty());
    click_at(&mut h, body);
    assert_eq!(handles(&h).len(), 1);
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    assert!(handles(&h).is_empty());
    h.snapshot("editor_cells_empty");
}

#[test]
fn deleting_a_handle_mid_drag_ends_the_drag() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor_with(Box::new(NoDesktop), false);
    let before = handles(&h);
    let from = handle_at(&h, 0);
    h.hover_at(from);
    h.run();
    press(&mut h, from, true, Modifiers::NONE);
    h.run();
    for i in 1..=4 {
        h.hover_at(from + Vec2::new(10.0 * i as f32, 0.0));
        h.run();
    }
    assert_eq!(h.state().selected, Some(0));
    h.key_press(Key::Delete);
    h.run();
    for i in 5..=8 {
        h.hover_at(from + Vec2::new(10.0 * i as f32, 5.0));
        h.run();
    }
    press(&mut h, from + Vec2::new(80.0, 5.0), false, Modifiers::NONE);
    h.run();
    let after = handles(&h);
    assert_eq!(after.len(), 6);
    assert_eq!(
        after,
        before[1..],
        "the handle that took index 0 must not take the dragged one's pose"
    );
    // Two undo steps: the deletion, then the drag.
    h.state_mut().undo();
    let undone = handles(&h);
    assert_eq!(undone.len(), 7);
    assert_ne!(undone[0], before[0], "the drag up to the deletion is kept");
    h.state_mut().undo();
    assert_eq!(handles(&h), before);
    drop(dir);
}

#[test]
fn undo_across_a_density_change_re_meshes_on_the_worker() {
    let mut h = editor_with(Box::new(NoDesktop), false);
    let vertices = |h: &Harness<'_, EditorApp>| {
        h.state()
            .document()
            .map_or(0, |d| d.rig().expect("a C² rig").stats().samples)
    };
    let before = vertices(&h);
    let mut settings = h.state().document().expect("a document").settings();
    // (Fine enough that a re-mesh takes the worker more than one frame.)
    settings.density = 12_000;
    assert!(h.state_mut().edit(Edit::Settings(settings)));
    settle(&mut h);
    let coarse = vertices(&h);
    assert!(coarse < 15_000, "{coarse}");
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.step();
    assert!(h.state().is_busy(), "the undo re-meshes in the background");
    assert_eq!(vertices(&h), coarse, "nothing changes until the mesh is in");
    // Another undo or redo waits: the history moves once the mesh is in.
    h.state_mut().redo();
    settle(&mut h);
    assert_eq!(vertices(&h), before);
    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    h.step();
    assert!(h.state().is_busy(), "the redo too");
    settle(&mut h);
    assert_eq!(vertices(&h), coarse);
    h.state_mut().undo();
    settle(&mut h);
    assert_eq!(vertices(&h), before);
    // A cancelled undo leaves both the document and the history as they were.
    h.state_mut().redo();
    assert!(h.state().is_busy());
    h.key_press(Key::Escape);
    h.step();
    assert!(!h.state().is_busy());
    assert_eq!(vertices(&h), before);
    h.state_mut().redo();
    settle(&mut h);
    assert_eq!(vertices(&h), coarse, "the redo is still there");
}

#[test]
fn rebuilding_a_large_rig_runs_on_the_worker() {
    let mut h = editor_with(Box::new(NoDesktop), false);
    let alpha = |h: &Harness<'_, EditorApp>| h.state().document().map(|d| d.settings().alpha);
    let mut settings = h.state().document().expect("a document").settings();
    settings.alpha = 0.25;
    assert!(h.state_mut().edit(Edit::Settings(settings)));
    assert!(h.state().is_busy(), "new parameters rebuild on the worker");
    assert_eq!(alpha(&h), Some(1.0));
    settle(&mut h);
    assert_eq!(alpha(&h), Some(0.25));
    h.state_mut().undo();
    assert!(h.state().is_busy(), "so does their undo");
    settle(&mut h);
    assert_eq!(alpha(&h), Some(1.0));
    // Undoing a removal rebuilds with the old virtual handles: on the worker too when
    // the rig is large (treat the built-in 20k-vertex rig as large).
    h.state_mut().large_mesh = 1000;
    let before = h
        .state()
        .document()
        .expect("doc")
        .rig()
        .expect("a C² rig")
        .virtual_vertices();
    assert!(h.state_mut().edit(Edit::Remove(0)));
    h.state_mut().undo();
    assert!(h.state().is_busy());
    settle(&mut h);
    assert_eq!(handles(&h).len(), 7);
    assert_eq!(
        h.state()
            .document()
            .expect("doc")
            .rig()
            .expect("a C² rig")
            .virtual_vertices(),
        before
    );
    h.state().sanity_check().expect("sane");
}

#[test]
fn a_quick_bar_stroke_makes_a_bar() {
    let mut h = editor_with(Box::new(NoDesktop), false);
    // The first stroke right after choosing the tool, its press, moves and release
    // in one frame.
    click_label(&mut h, "Reset pose");
    click_label(&mut h, "Add bar");
    assert_eq!(h.state().tool, Tool::AddBar);
    let (a, b) = (at(&h, 200.0, 300.0), at(&h, 280.0, 290.0));
    h.hover_at(a);
    press(&mut h, a, true, Modifiers::NONE);
    h.hover_at(a + (b - a) * 0.5);
    h.hover_at(b);
    press(&mut h, b, false, Modifiers::NONE);
    h.run();
    let all = handles(&h);
    assert_eq!(all.len(), 8, "{:?}", h.state().message);
    let HandleSpec::Bar { rest, .. } = all[7] else {
        panic!("a bar");
    };
    assert!(rest[0] != rest[1]);
    // Two big moves, each in its own frame.
    let (a, b) = (at(&h, 360.0, 400.0), at(&h, 390.0, 450.0));
    h.hover_at(a);
    h.run();
    press(&mut h, a, true, Modifiers::NONE);
    h.run();
    h.hover_at(a + (b - a) * 0.5);
    h.run();
    h.hover_at(b);
    h.run();
    press(&mut h, b, false, Modifiers::NONE);
    h.run();
    assert_eq!(handles(&h).len(), 9, "{:?}", h.state().message);
    // A click makes no bar, and says how.
    let spot = at(&h, 200.0, 300.0);
    click_at(&mut h, spot);
    assert_eq!(handles(&h).len(), 9);
    let message = h.state().message.clone().expect("a hint");
    assert!(message.text.contains("drag"), "{}", message.text);
}

#[test]
fn without_a_desktop_dialog_the_built_in_one_saves_exports_and_opens() {
    let dir = tempfile::tempdir().expect("temp dir");
    let lizard = write_lizard(dir.path());
    // The dialog's text fields (from egui_file) carry no accessible names.
    let builder = Harness::builder().with_accessibility_check(false);
    let mut h = support::build(builder, Box::new(NoDesktop), false);
    h.state_mut().open_in_background(lizard);
    settle(&mut h);
    let body = at(&h, 330.0, 330.0);
    click_at(&mut h, body);
    assert_eq!(handles(&h).len(), 1);

    h.key_press_modifiers(Modifiers::COMMAND, Key::S);
    h.run();
    assert!(h.state().file_dialog_open(), "{:?}", h.state().message);
    click_label(&mut h, "Save");
    let saved = dir.path().join("lizard.json");
    assert!(saved.is_file(), "{:?}", h.state().message);
    assert!(!h.state().is_dirty());

    h.key_press_modifiers(Modifiers::COMMAND, Key::E);
    h.run();
    click_label(&mut h, "Save");
    settle(&mut h);
    let exported = dir.path().join("lizard-warped.png");
    assert!(exported.is_file(), "{:?}", h.state().message);

    // Exporting again asks before replacing the file.
    h.key_press_modifiers(Modifiers::COMMAND, Key::E);
    h.run();
    click_label(&mut h, "Save");
    assert!(h.state().pending.is_some());
    click_label(&mut h, "Replace");
    settle(&mut h);
    assert!(h.state().message.as_ref().is_some_and(|m| !m.is_error));

    // Open the saved project: pick it in the list, then Open.
    click_label(&mut h, "Clear all handles");
    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::O);
    h.run();
    assert!(h.state().file_dialog_open());
    h.get_by_label_contains("lizard.json").click();
    h.run();
    click_label(&mut h, "Open");
    assert!(h.state().pending.is_some(), "unsaved changes: asks first");
    click_label(&mut h, "Discard");
    settle(&mut h);
    assert_eq!(handles(&h).len(), 1, "{:?}", h.state().message);
    assert_eq!(
        h.state().document().and_then(|d| d.project_path.clone()),
        Some(saved)
    );
}

#[test]
fn a_running_job_can_be_cancelled() {
    let mut h = editor_with(Box::new(NoDesktop), false);
    let before = handles(&h);
    let vertices = h
        .state()
        .document()
        .map(|d| d.rig().expect("a C² rig").stats().samples);
    let mut settings = h.state().document().expect("a document").settings();
    settings.density = 400_000;
    assert!(h.state_mut().edit(Edit::Settings(settings)));
    h.step();
    assert!(h.state().is_busy());
    h.get_by_label("Cancel");
    h.key_press(Key::Escape);
    h.step();
    assert!(!h.state().is_busy());
    h.run();
    assert_eq!(
        h.state()
            .document()
            .map(|d| d.rig().expect("a C² rig").stats().samples),
        vertices
    );
    assert_eq!(handles(&h), before);
    let message = h.state().message.clone().expect("a message");
    assert!(message.text.starts_with("cancelled"), "{}", message.text);
    // Edits work again at once.
    assert!(h.state_mut().edit(Edit::ResetPose));
    // The button does the same.
    assert!(h.state_mut().edit(Edit::Settings(settings)));
    h.step();
    click_label(&mut h, "Cancel");
    assert!(!h.state().is_busy());
}

#[test]
fn messages_are_readable_and_nothing_goes_unsaid() {
    let dir = tempfile::tempdir().expect("temp dir");
    let lizard = write_lizard(dir.path());
    let mut h = editor_with(Box::new(NoDesktop), false);
    // A long error: the status line cuts it, the log keeps it whole.
    let deep = dir.path().join("a".repeat(120)).join("missing-picture.png");
    h.state_mut().request_open(deep.clone());
    settle(&mut h);
    let last = h.state().log.last().cloned().expect("logged");
    assert!(last.is_error);
    assert!(last.text.contains("missing-picture.png"), "{}", last.text);
    assert!(
        last.text.len() > deep.display().to_string().len(),
        "the reason follows the path: {}",
        last.text
    );
    let text = last.text.clone();
    h.get_by_label(&text).click();
    h.run();
    assert!(h.state().log_open, "a click on the message opens the log");

    // A file dropped while a job runs is refused, with a word.
    let mut settings = h.state().document().expect("a document").settings();
    settings.density = 6000;
    assert!(h.state_mut().edit(Edit::Settings(settings)));
    h.input_mut()
        .dropped_files
        .push(std::sync::Arc::new(Dropped(lizard.clone())));
    h.step();
    let message = h.state().message.clone().expect("a message");
    assert!(
        message.is_error && message.text.contains("lizard.png"),
        "{}",
        message.text
    );
    settle(&mut h);

    // Shortcuts do not act on the document behind the unsaved-changes question.
    assert!(h.state().is_dirty());
    h.key_press(Key::N);
    h.run();
    assert_eq!(h.state().selected, Some(0));
    h.state_mut().request_open(lizard);
    h.run();
    assert!(h.state().pending.is_some());
    for key in [Key::Delete, Key::Backspace, Key::C] {
        h.key_press(key);
        h.run();
    }
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    assert_eq!(handles(&h).len(), 7);
    assert!(!h.state().show.cells);
    assert!(h.state().pending.is_some());
    h.key_press(Key::Escape);
    h.run();
    assert!(h.state().pending.is_none(), "Escape answers Cancel");
    assert_eq!(handles(&h).len(), 7);
}

#[test]
fn the_puppet_tool_adds_selects_moves_deletes_and_pans() {
    let mut h = editor_with(Box::new(NoDesktop), false);
    assert_eq!(h.state().tool, Tool::Puppet, "the default tool");
    // A click on the picture adds a handle there.
    let body = at(&h, 330.0, 330.0);
    click_at(&mut h, body);
    assert_eq!(handles(&h).len(), 8, "{:?}", h.state().message);
    assert_eq!(h.state().selected, Some(7));
    // A click on a handle selects it.
    let head = handle_at(&h, 0);
    click_at(&mut h, head);
    assert_eq!(h.state().selected, Some(0));
    assert_eq!(handles(&h).len(), 8);
    // Dragging a handle moves it.
    let before = editor::posed(&handles(&h)[2])[0];
    let arm = handle_at(&h, 2);
    support::drag(&mut h, arm, arm + Vec2::new(30.0, 0.0), Modifiers::NONE);
    let moved = editor::posed(&handles(&h)[2])[0];
    assert!(moved.x > before.x + 10.0, "{before} -> {moved}");
    // Alt-click deletes it.
    let new = handle_at(&h, 7);
    h.event(egui::Event::ModifiersChanged(Modifiers::ALT));
    h.hover_at(new);
    h.run();
    press(&mut h, new, true, Modifiers::ALT);
    h.run();
    press(&mut h, new, false, Modifiers::ALT);
    h.run();
    h.event(egui::Event::ModifiersChanged(Modifiers::NONE));
    h.run();
    assert_eq!(handles(&h).len(), 7, "{:?}", h.state().message);
    // Dragging empty canvas pans.
    let origin = h.state().viewport.origin;
    let corner = h.state().viewport.canvas.max - Vec2::new(10.0, 10.0);
    support::drag(
        &mut h,
        corner,
        corner - Vec2::new(50.0, 20.0),
        Modifiers::NONE,
    );
    assert_eq!(handles(&h).len(), 7);
    let panned = h.state().viewport.origin - origin;
    assert!(
        (panned - Vec2::new(-50.0, -20.0)).length() < 1.0,
        "{panned:?}"
    );
    // Off the picture, a click deselects and adds nothing.
    click_at(&mut h, corner);
    assert_eq!(handles(&h).len(), 7);
    assert_eq!(h.state().selected, None);
}

#[test]
fn an_opened_picture_is_fitted_and_stays_fitted_when_the_window_changes() {
    let dir = tempfile::tempdir().expect("temp dir");
    let lizard = write_lizard(dir.path());
    let mut h = editor_with(Box::new(NoDesktop), false);
    // Zoom away from the fit, then open: the picture is fitted again.
    h.state_mut().viewport.zoom = 0.2;
    h.input_mut()
        .dropped_files
        .push(std::sync::Arc::new(Dropped(lizard)));
    h.step();
    settle(&mut h);
    let fitted = |h: &Harness<'_, EditorApp>| {
        let v = h.state().viewport;
        let image = v.to_screen(DVec2::ZERO);
        let far = v.to_screen(DVec2::new(746.0, 669.0));
        v.canvas.expand(1.0).contains(image)
            && v.canvas.expand(1.0).contains(far)
            && ((far.x - image.x) > v.canvas.width() * 0.8
                || (far.y - image.y) > v.canvas.height() * 0.8)
    };
    assert!(fitted(&h), "{:?}", h.state().viewport);
    // The window grows (a maximise): still fitted.
    h.set_size(Vec2::new(1600.0, 1000.0));
    h.run();
    assert!(fitted(&h), "{:?}", h.state().viewport);
}

#[test]
fn a_sixteen_bit_picture_exports_with_sixteen_bits() {
    let dir = tempfile::tempdir().expect("temp dir");
    let source = dir.path().join("deep.png");
    let deep = image::ImageBuffer::<image::Rgba<u16>, _>::from_fn(64, 48, |x, y| {
        image::Rgba([(x * 1000 + 7) as u16, (y * 1300 + 3) as u16, 40_001, 65_535])
    });
    deep.save(&source).expect("write a 16-bit PNG");
    let mut h = editor_with(Box::new(NoDesktop), false);
    h.state_mut().open_in_background(source);
    settle(&mut h);
    assert_eq!(
        h.state()
            .document()
            .and_then(|d| d.deep.as_ref())
            .map(|p| p.bits_per_channel()),
        Some(16),
        "{:?}",
        h.state().message
    );
    let out = dir.path().join("out.png");
    h.state_mut().export_to(&out);
    let exported = image::open(&out).expect("an exported PNG");
    assert_eq!(exported.color(), image::ColorType::Rgba16);
    // At rest (no handles) the export is the picture itself, all 16 bits of it.
    assert_eq!(exported.to_rgba16(), deep);
}

/// *Export layers…* of a layered file written by another program: at rest, every
/// layer comes back as it was (names, order, opacity, visibility, offsets, pixels), and
/// the built-in picture exports as one layer.
#[test]
fn export_layers_writes_each_layer_on_its_own() {
    let dir = tempfile::tempdir().expect("temp dir");
    let source = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../layers/tests/data/krita-like.ora");
    let mut h = editor_with(Box::new(NoDesktop), false);
    h.state_mut().open_in_background(source.clone());
    settle(&mut h);
    let out = dir.path().join("layers.ora");
    h.state_mut().export_layers_to(&out);
    let read = |path: &std::path::Path| pipeline::load_artwork(path).expect("layers");
    let (before, after) = (read(&source), read(&out));
    assert_eq!(after.layers.len(), 4, "{:?}", h.state().message);
    // What shows of a pixel: a fully transparent one's colour is not kept.
    let shown = |layer: &pipeline::Layer| {
        let mut pixels = layer.pixels.to_rgba8().into_owned();
        for p in pixels.pixels_mut().filter(|p| p[3] == 0) {
            *p = image::Rgba([0, 0, 0, 0]);
        }
        (
            layer.name.clone(),
            layer.x,
            layer.y,
            layer.opacity,
            layer.visible,
            pixels,
        )
    };
    let described =
        |artwork: &pipeline::Artwork| artwork.layers.iter().map(shown).collect::<Vec<_>>();
    assert!(described(&after) == described(&before));
    // The built-in picture in its pose: one layer, what *Export PNG…* writes.
    let mut h = editor_with(Box::new(NoDesktop), false);
    h.state_mut().export_layers_to(&out);
    let flat = read(&out);
    assert_eq!(flat.layers.len(), 1);
    let png = dir.path().join("warped.png");
    h.state_mut().export_to(&png);
    let exported = image::open(&png).expect("the PNG").to_rgba8();
    assert!(flat.flatten().into_rgba8() == exported);
}

#[test]
fn a_fifo_or_a_device_is_refused_at_once() {
    let dir = tempfile::tempdir().expect("temp dir");
    let fifo = dir.path().join("picture.png");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo runs");
    assert!(made.success());
    let project = dir.path().join("fifo.json");
    std::fs::write(
        &project,
        r#"{"version": 1, "image": "picture.png", "handles": []}"#,
    )
    .expect("write");
    let mut h = editor_with(Box::new(NoDesktop), false);
    let before = handles(&h);
    for path in [fifo, project, std::path::PathBuf::from("/dev/zero")] {
        h.state_mut().request_open(path.clone());
        settle(&mut h);
        let message = h.state().message.clone().expect("a message");
        assert!(
            message.is_error && message.text.contains("not a regular file"),
            "{}: {}",
            path.display(),
            message.text
        );
        assert_eq!(handles(&h), before);
    }
}

#[test]
fn no_save_or_export_replaces_the_picture_or_the_project() {
    let dir = tempfile::tempdir().expect("temp dir");
    let source = dir.path().join("cat.png");
    let picture = image::RgbaImage::from_pixel(40, 30, image::Rgba([200, 100, 50, 255]));
    picture.save(&source).expect("write a picture");
    let original = std::fs::read(&source).expect("read");
    let mut h = editor_with(Box::new(NoDesktop), false);
    h.state_mut().open_in_background(source.clone());
    settle(&mut h);
    let project = dir.path().join("cat.json");
    h.state_mut().save_to(&project);
    let saved = std::fs::read(&project).expect("saved");
    // Saving the project over its picture, exporting over the picture or the project
    // (also through `..`): refused, said, nothing written.
    std::fs::create_dir(dir.path().join("sub")).expect("mkdir");
    let through_dots = dir.path().join("sub/../cat.png");
    for (target, export) in [
        (&source, false),
        (&through_dots, false),
        (&source, true),
        (&project, true),
    ] {
        if export {
            h.state_mut().export_to(target);
        } else {
            h.state_mut().save_to(target);
        }
        let message = h.state().message.clone().expect("a message");
        assert!(
            message.is_error && message.text.contains("one of the inputs"),
            "{}: {}",
            target.display(),
            message.text
        );
    }
    assert_eq!(std::fs::read(&source).expect("read"), original);
    assert_eq!(std::fs::read(&project).expect("read"), saved);
    // Saving the project over itself is what Save is for.
    h.state_mut().save_to(&project);
    assert!(!h.state().message.clone().expect("a message").is_error);
}

#[test]
fn the_canvas_never_moves_under_the_hand() {
    // 1024 points wide: the narrowest window the layout is made for.
    let mut h = editor_with(Box::new(NoDesktop), false);
    h.set_size(Vec2::new(1024.0, 720.0));
    h.run();
    let place = |h: &Harness<'_, EditorApp>| {
        let v = h.state().viewport;
        (v.canvas, v.to_screen(DVec2::new(300.0, 300.0)))
    };
    let (canvas, point) = place(&h);
    // The time shown grows from 0 to hours, frames to five digits, the rate to three
    // decimals, keys appear: no panel changes size, nothing moves.
    h.state_mut().set_key();
    for time in [0.75, 10.0, 133.25, 3599.9] {
        h.state_mut().set_time(time);
        h.run();
        assert_eq!(place(&h), (canvas, point), "at {time} s");
    }
    h.state_mut().set_fps(23.976);
    h.state_mut().set_key();
    h.run();
    assert_eq!(place(&h), (canvas, point), "a rate of 23.976");
    // A window resize keeps the image point under the canvas's centre there (a view
    // the user panned, so not fitted).
    let corner = h.state().viewport.canvas.max - Vec2::new(10.0, 10.0);
    support::drag(
        &mut h,
        corner,
        corner - Vec2::new(30.0, 12.0),
        Modifiers::NONE,
    );
    let centre = |h: &Harness<'_, EditorApp>| {
        let v = h.state().viewport;
        v.to_image(v.canvas.center())
    };
    let under = centre(&h);
    h.set_size(Vec2::new(1300.0, 900.0));
    h.run();
    assert!(
        centre(&h).distance(under) < 0.5,
        "{under} -> {}",
        centre(&h)
    );
}
