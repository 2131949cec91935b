//! The editor driven as a user drives it: widgets found by their accessible labels,
//! pointer and keys simulated, the canvas drawn by the real wgpu paint callback on the
//! software adapter (snapshots in `tests/snapshots`, tolerances in `kittest.toml`).
//!
//! File dialogs are answered by `support::Scripted` with paths in a temporary folder.

use crate::support;

use std::path::Path;

use egui::{Key, Modifiers, Vec2};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use glam::DVec2;
use project::{HandleSpec, Project};

use editor::{EditorApp, Tool};
use support::{
    Dropped, at, click_at, click_label, drag, editor, handles, settle, translate, write_lizard,
};

#[test]
fn the_editor_opens_on_the_built_in_picture() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    let doc = h.state().document().expect("the built-in picture");
    assert_eq!(doc.project().handles.len(), 7);
    assert!(doc.rig().expect("a C² rig").stats().samples > 10_000);
    h.get_by_label("Select");
    h.get_by_label("Show mesh");
    // Hovering the picture shows the weights there.
    let body = at(&h, 300.0, 300.0);
    h.hover_at(body);
    h.run();
    let readout = h
        .state()
        .hover_readout
        .clone()
        .expect("weights under the pointer");
    assert!(readout.starts_with("vertex "), "{readout}");
    assert!(readout.contains("handle"), "{readout}");
    h.snapshot("editor_default");
}

#[test]
fn an_editing_session() {
    let dir = tempfile::tempdir().expect("temp dir");
    let lizard = write_lizard(dir.path());
    let mut h = editor(dir.path());
    // Work on the picture as a file, so the saved project names it.
    h.get_by_label("File").click();
    h.run();
    click_label(&mut h, "Open image…");
    settle(&mut h);
    assert_eq!(
        h.state().document().and_then(|d| d.image_path.clone()),
        Some(lizard.clone())
    );
    assert!(handles(&h).is_empty());

    // Two point handles and a bar.
    click_label(&mut h, "Add point");
    assert_eq!(h.state().tool, Tool::AddPoint);
    let arm = at(&h, 440.0, 238.0);
    click_at(&mut h, arm);
    let leg = at(&h, 190.0, 470.0);
    click_at(&mut h, leg);
    assert_eq!(handles(&h).len(), 2, "{:?}", h.state().message);
    click_label(&mut h, "Add bar");
    let (a, b) = (at(&h, 110.0, 130.0), at(&h, 250.0, 250.0));
    drag(&mut h, a, b, Modifiers::NONE);
    assert_eq!(handles(&h).len(), 3, "{:?}", h.state().message);
    assert!(matches!(handles(&h)[2], HandleSpec::Bar { .. }));

    // Drag the first point: it follows the pointer; one undo step for the whole drag.
    click_label(&mut h, "Select");
    let target = at(&h, 470.0, 200.0);
    drag(&mut h, arm, target, Modifiers::NONE);
    let moved = translate(&handles(&h)[0]);
    assert!((moved - DVec2::new(30.0, -38.0)).length() < 2.0, "{moved}");
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    assert_eq!(translate(&handles(&h)[0]), DVec2::ZERO, "undo");
    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    h.run();
    assert_eq!(translate(&handles(&h)[0]), moved, "redo");

    // Alt-drag rotates (near the centre, by as much as the drag is long).
    let now = at(&h, 470.0, 200.0);
    drag(
        &mut h,
        now + Vec2::new(4.0, 0.0),
        now + Vec2::new(0.0, 16.0),
        Modifiers::ALT,
    );
    match handles(&h)[0] {
        HandleSpec::Point { rotate, .. } => assert!(rotate > 0.5, "{rotate}"),
        HandleSpec::Bar { .. } => unreachable!(),
    }

    // Insert a handle in the posed state: the picture under it does not move.
    click_label(&mut h, "Add point");
    let before = h.state().document().map(|d| d.node_position(0));
    let inside = at(&h, 330.0, 330.0);
    click_at(&mut h, inside);
    assert_eq!(handles(&h).len(), 4, "{:?}", h.state().message);
    assert_eq!(before, h.state().document().map(|d| d.node_position(0)));

    // Delete the new handle with the Delete key (it is selected after adding).
    h.key_press(Key::Delete);
    h.run();
    assert_eq!(handles(&h).len(), 3);

    // Overlays.
    click_label(&mut h, "Select");
    let leg = at(&h, 190.0, 470.0);
    click_at(&mut h, leg);
    assert_eq!(h.state().selected, Some(1));
    for label in ["Show mesh", "Dual graph", "Weight heat map"] {
        click_label(&mut h, label);
    }
    assert!(h.state().show.mesh && h.state().show.dual_graph && h.state().show.heat);
    h.snapshot("editor_overlays");
    click_label(&mut h, "Weight heat map");
    click_label(&mut h, "Show mesh");
    click_label(&mut h, "Voronoi cells");
    h.snapshot("editor_cells");
    click_label(&mut h, "Voronoi cells");
    click_label(&mut h, "Dual graph");

    // Save, export, reload.
    h.get_by_label("File").click();
    h.run();
    click_label(&mut h, "Save project as…");
    assert!(!h.state().is_dirty());
    let saved_text = std::fs::read_to_string(dir.path().join("project.json")).expect("saved");
    let saved = Project::from_json(&saved_text).expect("a valid project");
    assert_eq!(saved.image.as_deref(), Some(Path::new("lizard.png")));
    assert_eq!(saved.handles, handles(&h));

    let exported = support::export_png(&mut h, dir.path());
    // `c2warp render lizard.png --rig project.json` runs exactly this.
    let picture = pipeline::load_image(&lizard).expect("picture");
    let project = pipeline::load_project(&dir.path().join("project.json")).expect("project");
    let prepared = pipeline::prepare(&picture, &project, None).expect("rig");
    let expected =
        pipeline::warp(&picture, &pipeline::Warper::on_rig(prepared.rig, &project)).expect("warp");
    assert_eq!(exported.dimensions(), picture.dimensions());
    assert!(
        exported == expected,
        "the export equals the command-line render"
    );

    click_label(&mut h, "Clear all handles");
    assert!(handles(&h).is_empty() && h.state().is_dirty());
    h.get_by_label("File").click();
    h.run();
    click_label(&mut h, "Open project…");
    // Unsaved changes: the editor asks first.
    assert!(h.state().pending.is_some());
    click_label(&mut h, "Discard");
    settle(&mut h);
    assert_eq!(handles(&h), saved.handles, "{:?}", h.state().message);
    assert!(!h.state().is_dirty());
}

#[test]
fn bad_files_leave_the_work_untouched() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    let before = handles(&h);
    let png = pipeline::DEFAULT_IMAGE;
    let cases: [(&str, &[u8]); 5] = [
        ("corrupt.png", b"not a picture at all"),
        ("truncated.png", &png[..png.len() / 3]),
        ("huge.png", &huge_png_header()),
        (
            "broken.json",
            b"{\"version\": 1, \"handles\": [ {\"type\": ",
        ),
        (
            "no-image.json",
            b"{\"version\": 1, \"image\": \"missing.png\", \"handles\": []}",
        ),
    ];
    for (name, bytes) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).expect("write");
        h.state_mut().request_open(path);
        settle(&mut h);
        let message = h.state().message.clone().expect("a message");
        assert!(message.is_error, "{name}: {message:?}");
        assert!(message.text.contains(name), "{name}: {}", message.text);
        assert_eq!(handles(&h), before, "{name}");
    }
    h.state_mut()
        .request_open(dir.path().join("does-not-exist.png"));
    settle(&mut h);
    assert!(h.state().message.as_ref().is_some_and(|m| m.is_error));
    assert_eq!(handles(&h), before);
}

#[test]
fn unsaved_changes_can_be_kept() {
    let dir = tempfile::tempdir().expect("temp dir");
    let lizard = write_lizard(dir.path());
    let mut h = editor(dir.path());
    click_label(&mut h, "Reset pose");
    assert!(h.state().is_dirty());
    h.state_mut().request_open(lizard.clone());
    h.run();
    assert!(h.state().pending.is_some());
    click_label(&mut h, "Cancel");
    assert!(h.state().pending.is_none());
    assert_eq!(handles(&h).len(), 7, "the work is still there");
    assert!(h.state().document().is_some_and(|d| d.image_path.is_none()));
    // Escape is Cancel too.
    h.state_mut().request_open(lizard.clone());
    h.run();
    assert!(h.state().pending.is_some());
    h.key_press(Key::Escape);
    h.run();
    assert!(h.state().pending.is_none());
    assert_eq!(handles(&h).len(), 7);
    // Save: the project is saved (its dialog answered with a file in `dir`), then the
    // picture opens.
    h.state_mut().request_open(lizard.clone());
    h.run();
    click_label(&mut h, "Save");
    settle(&mut h);
    let saved = std::fs::read_to_string(dir.path().join("project.json")).expect("saved");
    assert_eq!(
        Project::from_json(&saved).expect("a project").handles.len(),
        7,
        "the work was saved"
    );
    assert_eq!(
        h.state().document().and_then(|d| d.image_path.clone()),
        Some(lizard),
        "then the picture opened"
    );
}

#[test]
fn escape_closes_the_windows_over_the_canvas() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    h.key_press(Key::F1);
    h.run();
    assert!(h.state().help_open);
    h.state_mut().log_open = true;
    h.state_mut().selected = Some(0);
    h.run();
    h.key_press(Key::Escape);
    h.run();
    assert!(!h.state().help_open && !h.state().log_open);
    // Only the windows: the selection stays until the next Escape.
    assert_eq!(h.state().selected, Some(0));
    h.key_press(Key::Escape);
    h.run();
    assert_eq!(h.state().selected, None);
}

#[test]
fn re_meshing_runs_in_the_background_and_undoes() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    let vertices = |h: &Harness<'_, EditorApp>| {
        h.state()
            .document()
            .map_or(0, |d| d.rig().expect("a C² rig").stats().samples)
    };
    let before = vertices(&h);
    let mut settings = h.state().document().expect("a document").settings();
    settings.density = 5000;
    assert!(h.state_mut().edit(editor::Edit::Settings(settings)));
    assert!(h.state().is_busy(), "the re-mesh runs on a worker thread");
    // While it runs, edits are refused and the canvas says what is going on.
    assert!(!h.state_mut().edit(editor::Edit::Clear));
    h.step();
    assert!(
        h.query_all_by_label_contains("Meshing at 5000 vertices")
            .next()
            .is_some()
    );
    settle(&mut h);
    let after = vertices(&h);
    assert!((4500..5500).contains(&after), "{after} vertices");
    assert_eq!(handles(&h).len(), 7);
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.step();
    assert!(h.state().is_busy(), "the undo re-meshes on the worker too");
    settle(&mut h);
    assert_eq!(vertices(&h), before, "undo brings the old mesh back");
}

#[test]
fn auto_rotation_turns_the_other_points_during_a_drag() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    click_label(&mut h, "Reset pose");
    click_label(&mut h, "Auto-rotate points");
    assert!(h.state().auto_rotate);
    let rotations = |h: &Harness<'_, EditorApp>| -> Vec<f64> {
        handles(h)
            .iter()
            .filter_map(|p| match p {
                HandleSpec::Point { rotate, .. } => Some(*rotate),
                HandleSpec::Bar { .. } => None,
            })
            .collect()
    };
    assert!(rotations(&h).iter().all(|r| *r == 0.0));
    // Drag the head (handle 1, at rest) far to the right.
    let head = at(&h, 40.0, 40.0);
    let away = at(&h, 200.0, 40.0);
    drag(&mut h, head, away, Modifiers::NONE);
    let turned = rotations(&h);
    assert!(
        turned.iter().filter(|r| r.abs() > 0.01).count() >= 2,
        "{turned:?}"
    );
    // One undo step takes the whole drag back, rotations included.
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    assert!(rotations(&h).iter().all(|r| *r == 0.0));
}

#[test]
fn dropping_a_picture_opens_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let lizard = write_lizard(dir.path());
    let mut h = editor(dir.path());
    h.input_mut()
        .dropped_files
        .push(std::sync::Arc::new(Dropped(lizard.clone())));
    h.step();
    assert!(h.state().is_busy(), "opening");
    settle(&mut h);
    assert_eq!(
        h.state().document().and_then(|d| d.image_path.clone()),
        Some(lizard)
    );
    assert!(handles(&h).is_empty());
}

#[test]
fn dropping_several_pictures_opens_them_as_the_layers_of_one_and_saves_them_all() {
    let dir = tempfile::tempdir().expect("temp dir");
    let lizard = write_lizard(dir.path());
    // A second picture: a small opaque square, on top.
    let square = dir.path().join("square.png");
    image::RgbaImage::from_pixel(40, 40, image::Rgba([250, 200, 0, 255]))
        .save(&square)
        .expect("write the square");
    let mut h = editor(dir.path());
    for path in [&lizard, &square] {
        h.input_mut()
            .dropped_files
            .push(std::sync::Arc::new(Dropped(path.clone())));
    }
    h.step();
    settle(&mut h);
    let message = h.state().message.clone().expect("a message");
    assert!(
        message.text.contains("2 pictures as layers"),
        "{}",
        message.text
    );
    let doc = h.state().document().expect("a document");
    assert_eq!(doc.layers.as_ref().map(|l| l.layers.len()), Some(2));
    assert_eq!(doc.image.get_pixel(10, 10).0, [250, 200, 0, 255], "on top");
    // Saved, the project names both pictures, bottom first, and reopens so.
    h.state_mut().save_to(&dir.path().join("project.json"));
    let saved = std::fs::read_to_string(dir.path().join("project.json")).expect("saved");
    let project = Project::from_json(&saved).expect("a project");
    assert_eq!(
        project.images,
        [std::path::PathBuf::from("lizard.png"), "square.png".into()]
    );
    h.state_mut().request_open(dir.path().join("project.json"));
    settle(&mut h);
    let doc = h.state().document().expect("reopened");
    assert_eq!(doc.pictures().count(), 2);
    assert_eq!(doc.image.get_pixel(10, 10).0, [250, 200, 0, 255]);
}

#[test]
fn the_help_window_lists_the_shortcuts() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    h.key_press(Key::F1);
    h.run();
    assert!(h.state().help_open);
    for (keys, _) in editor::SHORTCUTS {
        h.get_by_label(keys);
    }
    h.get_by_label("Pan");
}

/// A PNG header claiming 100000 × 100000 pixels.
fn huge_png_header() -> Vec<u8> {
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = b"IHDR".to_vec();
    ihdr.extend(100_000u32.to_be_bytes());
    ihdr.extend(100_000u32.to_be_bytes());
    ihdr.extend([8, 6, 0, 0, 0]);
    png.extend(13u32.to_be_bytes());
    png.extend(&ihdr);
    png.extend(crc(&ihdr).to_be_bytes());
    png
}

fn crc(bytes: &[u8]) -> u32 {
    let mut c = 0xffff_ffffu32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xedb8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

#[test]
fn alt_drag_turns_a_pin_from_its_centre_or_anywhere_on_its_ring() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    click_label(&mut h, "Clear all handles");
    click_label(&mut h, "Add point");
    let pin = at(&h, 440.0, 238.0);
    click_at(&mut h, pin);
    click_label(&mut h, "Select");
    h.state_mut().selected = None;
    let rotation = |h: &Harness<'_, EditorApp>| match handles(h)[0] {
        HandleSpec::Point { rotate, .. } => rotate,
        HandleSpec::Bar { .. } => unreachable!(),
    };
    // From the centre: the turn is measured from where the pointer first leaves it.
    let origin = h.state().viewport.origin;
    drag(&mut h, pin, pin + Vec2::new(0.0, -20.0), Modifiers::ALT);
    // Then a quarter turn around it… from the top to the right.
    drag(
        &mut h,
        pin + Vec2::new(0.0, -20.0),
        pin + Vec2::new(20.0, 0.0),
        Modifiers::ALT,
    );
    let turned = rotation(&h);
    assert!(
        (turned - std::f64::consts::FRAC_PI_2).abs() < 0.2,
        "{turned}"
    );
    // From inside the ring but off the dot (12 points out): a turn, not a pan.
    drag(
        &mut h,
        pin + Vec2::new(12.0, 0.0),
        pin + Vec2::new(0.0, 12.0),
        Modifiers::ALT,
    );
    assert_eq!(h.state().viewport.origin, origin, "the view did not pan");
    assert!(
        (rotation(&h) - turned - std::f64::consts::FRAC_PI_2).abs() < 0.2,
        "{}",
        rotation(&h)
    );
    // A plain drag there pans, as before.
    drag(
        &mut h,
        pin + Vec2::new(15.0, 0.0),
        pin + Vec2::new(40.0, 0.0),
        Modifiers::NONE,
    );
    assert_ne!(h.state().viewport.origin, origin);
}

#[test]
fn scaling_and_turning_change_by_the_length_of_the_drag_and_never_pan() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    click_label(&mut h, "Clear all handles");
    click_label(&mut h, "Add point");
    let pin = at(&h, 440.0, 238.0);
    click_at(&mut h, pin);
    click_label(&mut h, "Select");
    h.state_mut().selected = None;
    let pose = |h: &Harness<'_, EditorApp>| match handles(h)[0] {
        HandleSpec::Point { rotate, scale, .. } => (rotate, scale),
        HandleSpec::Bar { .. } => unreachable!(),
    };
    let origin = h.state().viewport.origin;
    // Shift-drag 20 points out from the centre: a little larger (2^(20/100) at most),
    // not twenty times.
    drag(&mut h, pin, pin + Vec2::new(20.0, 0.0), Modifiers::SHIFT);
    let (_, scale) = pose(&h);
    assert!(scale > 1.0 && scale < 1.2, "{scale}");
    // From 6 points off the centre, the same: bounded by the drag's length.
    drag(
        &mut h,
        pin + Vec2::new(6.0, 0.0),
        pin + Vec2::new(26.0, 0.0),
        Modifiers::SHIFT,
    );
    let (_, twice) = pose(&h);
    assert!(
        twice / scale > 1.1 && twice / scale < 1.16,
        "{scale} -> {twice}"
    );
    // Back towards the centre shrinks it.
    drag(
        &mut h,
        pin + Vec2::new(20.0, 0.0),
        pin + Vec2::new(8.0, 0.0),
        Modifiers::SHIFT,
    );
    assert!(pose(&h).1 < twice, "{:?}", pose(&h));
    // A short turn near the centre is a small one (6 points out, 5 across).
    let (before, _) = pose(&h);
    drag(
        &mut h,
        pin + Vec2::new(6.0, 0.0),
        pin + Vec2::new(6.0, 5.0),
        Modifiers::ALT,
    );
    let turned = pose(&h).0 - before;
    assert!(turned > 0.1 && turned < 0.45, "{turned}");
    // A Shift-drag from the ring of a handle that is not selected scales that handle
    // and does not pan the view.
    h.state_mut().selected = None;
    h.run();
    let scale = pose(&h).1;
    drag(
        &mut h,
        pin + Vec2::new(0.0, 26.0),
        pin + Vec2::new(0.0, 46.0),
        Modifiers::SHIFT,
    );
    assert_eq!(h.state().viewport.origin, origin, "the view did not pan");
    assert!(pose(&h).1 > scale * 1.1, "{scale} -> {:?}", pose(&h));
}

#[test]
fn undo_redo_and_method_switches_say_what_they_did() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    let text = |h: &Harness<'_, EditorApp>| {
        h.state()
            .message
            .as_ref()
            .map(|m| m.text.clone())
            .unwrap_or_default()
    };
    click_label(&mut h, "ARAP");
    assert!(text(&h).starts_with("ARAP: "), "{}", text(&h));
    click_label(&mut h, "Add point");
    let p = at(&h, 330.0, 330.0);
    click_at(&mut h, p);
    assert!(text(&h).starts_with("added a point handle"), "{}", text(&h));
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    // Undo and redo name the step they undid or redid.
    assert_eq!(text(&h), "undone: 1 handle added");
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    assert_eq!(text(&h), "undone: the method: ARAP");
    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    h.run();
    assert_eq!(text(&h), "redone: the method: ARAP");
}

#[test]
fn a_density_typed_in_applies_when_the_field_is_left() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    let before = h.state().document().expect("doc").settings().density;
    h.get_by_value(&before.to_string()).click();
    h.run();
    h.key_press_modifiers(Modifiers::COMMAND, Key::A);
    h.run();
    // Keystroke by keystroke, nothing is re-meshed…
    for digit in ["4", "1", "0", "0", "0"] {
        h.event(egui::Event::Text(digit.to_owned()));
        h.run();
        assert!(!h.state().is_busy(), "re-meshing at a partial number");
        assert_eq!(
            h.state().document().expect("doc").settings().density,
            before
        );
    }
    // …until Enter leaves the field.
    h.key_press(Key::Enter);
    h.step();
    support::settle(&mut h);
    assert_eq!(
        h.state().document().expect("doc").settings().density,
        41_000
    );
}

#[test]
fn a_click_with_the_bar_tool_says_how_to_draw_a_bar() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    click_label(&mut h, "Add bar");
    let before = handles(&h).len();
    let p = at(&h, 300.0, 300.0);
    click_at(&mut h, p);
    assert_eq!(handles(&h).len(), before);
    let message = h.state().message.clone().expect("a message");
    assert!(message.text.contains("drag from one end"), "{message:?}");
}

#[test]
fn the_shortcuts_window_fits_the_window_and_scrolls() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    h.key_press(Key::F1);
    h.run();
    h.run();
    let screen = h.ctx.content_rect();
    let title = h.get_by_label("Keyboard shortcuts").rect();
    // The last shortcut is reachable by scrolling, and the window ends on screen.
    let last = editor::SHORTCUTS.last().expect("shortcuts").1;
    h.get_by_label(last).scroll_to_me();
    h.run();
    let row = h.get_by_label(last).rect();
    assert!(row.max.y <= screen.max.y, "{row:?} beyond {screen:?}");
    assert!(title.min.y >= screen.min.y);
}

#[test]
fn a_density_the_shape_cannot_hold_says_why() {
    let dir = tempfile::tempdir().expect("temp dir");
    // A disc of radius 30 px: about 3,000 px², so at most about 12,000 vertices.
    let picture = dir.path().join("disc.png");
    image::RgbaImage::from_fn(100, 100, |x, y| {
        let inside = (f64::from(x) - 50.0).hypot(f64::from(y) - 50.0) < 30.0;
        image::Rgba([200, 60, 60, if inside { 255 } else { 0 }])
    })
    .save(&picture)
    .expect("write");
    let mut app = EditorApp::headless(false);
    app.open(&picture);
    app.wait_for_job();
    let mut settings = app.document().expect("doc").settings();
    settings.density = 50_000;
    assert!(app.edit(editor::Edit::Settings(settings)));
    app.wait_for_job();
    let message = app.message.clone().expect("a message");
    assert!(
        message.text.contains("asked for 50000")
            && message.text.contains("holds at most 4 vertices a pixel"),
        "{message:?}"
    );
}

#[test]
fn the_cut_tool_splits_the_mesh_along_a_stroke_in_one_undo_step() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    let vertices = |h: &Harness<'_, EditorApp>| {
        h.state()
            .document()
            .map_or(0, |d| d.rig().expect("a C² rig").stats().samples)
    };
    // Vertices that share their place with another: a cut's two sides.
    let doubled = |h: &Harness<'_, EditorApp>| {
        let doc = h.state().document().expect("a document");
        let mut places: Vec<(u64, u64)> = doc
            .rig()
            .expect("a C² rig")
            .domain()
            .positions()
            .iter()
            .map(|p| (p.x.to_bits(), p.y.to_bits()))
            .collect();
        let n = places.len();
        places.sort_unstable();
        places.dedup();
        n - places.len()
    };
    let before = vertices(&h);
    assert_eq!(doubled(&h), 0);
    click_label(&mut h, "Cut");
    assert_eq!(h.state().tool, Tool::Cut);
    // Across the lizard's body, starting and ending off it.
    let (from, to) = (at(&h, 300.0, 150.0), at(&h, 300.0, 450.0));
    drag(&mut h, from, to, Modifiers::NONE);
    settle(&mut h);
    let doc = h.state().document().expect("a document");
    assert_eq!(doc.project().cuts.len(), 1, "{:?}", h.state().message);
    assert!(doc.project().cuts[0].stroke.len() >= 2);
    // The vertices along the cut are doubled (a body about 100 px across, a vertex
    // every few pixels).
    assert!(doubled(&h) > 10, "{} vertices doubled", doubled(&h));
    h.state()
        .document()
        .expect("doc")
        .check_reopens()
        .expect("reopens as shown");
    // Pull the front foot (right of the cut) down: the other side stays.
    click_label(&mut h, "Puppet");
    let viewport = h.state().viewport;
    let near = viewport.to_image(egui::pos2(856.0, 209.0));
    let foot = h
        .state()
        .document()
        .expect("a document")
        .project()
        .handles
        .iter()
        .flat_map(editor::posed)
        .min_by(|a, b| a.distance(near).total_cmp(&b.distance(near)))
        .expect("handles");
    let foot = viewport.to_screen(foot);
    drag(&mut h, foot, foot + egui::vec2(0.0, 90.0), Modifiers::NONE);
    h.run();
    h.snapshot("editor_cut");
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.step();
    settle(&mut h);
    let doc = h.state().document().expect("a document");
    assert!(doc.project().cuts.is_empty(), "undone");
    assert_eq!(vertices(&h), before, "undo brings the old mesh back");
    assert_eq!(
        h.state().message.as_ref().map(|m| m.text.as_str()),
        Some("undone: a cut")
    );
}
