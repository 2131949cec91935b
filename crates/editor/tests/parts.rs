//! A layered picture drawn as parts in the editor: the Layers section's toggle, the
//! view equal to the export, a part brought forward and saved.

use std::path::{Path, PathBuf};

use egui_kittest::kittest::Queryable;

use crate::support::{self, at, changed, click_label, drag, editor, settle, shot};

/// The sample character and its rig (at a low density) in `dir`; the rig's path.
fn puppet(dir: &Path) -> PathBuf {
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
    std::fs::copy(assets.join("puppet.ora"), dir.join("puppet.ora")).expect("the sample");
    let mut rig: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(assets.join("puppet-rig.json")).expect("its rig"),
    )
    .expect("JSON");
    rig["density"] = 3_000.into();
    let path = dir.join("puppet.json");
    std::fs::write(&path, rig.to_string()).expect("write the rig");
    path
}

#[test]
fn drawn_as_parts_the_view_is_the_export_and_a_part_brought_forward_is_saved() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    h.state_mut().request_open(puppet(dir.path()));
    settle(&mut h);
    let flat = shot(&mut h);
    click_label(&mut h, "Draw as parts");
    settle(&mut h);
    assert!(h.state().document().is_some_and(|d| d.parts().is_some()));
    h.state().sanity_check().expect("consistent");
    let parts = shot(&mut h);
    if let Ok(folder) = std::env::var("C2WARP_SHOTS") {
        parts
            .save(Path::new(&folder).join("parts-view.png"))
            .expect("a shot");
        let window = h.render().expect("the window");
        (window.save(Path::new(&folder).join("parts-window.png"))).expect("a shot");
    }
    assert!(changed(&flat, &parts) > 0.001, "parts draw another picture");
    // The view at full size is the export, which is `render` of the saved project.
    assert_view_is_export(&mut h, dir.path());
    // Undo goes back to one picture; redo to parts.
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    settle(&mut h);
    assert!(h.state().document().is_some_and(|d| d.parts().is_none()));
    h.key_press_modifiers(
        egui::Modifiers::COMMAND | egui::Modifiers::SHIFT,
        egui::Key::Z,
    );
    settle(&mut h);
    assert!(h.state().document().is_some_and(|d| d.parts().is_some()));
    // The tail (the bottom layer) brought forward: one step up the draw order, saved.
    h.get_by_label("Bring tail forward").click();
    h.step();
    settle(&mut h);
    let project = h.state().document().expect("doc").project_for_saving(None);
    let order = project.parts.map(|p| p.order);
    assert_eq!(order, Some(vec![1, 0, 2, 3, 4, 5, 6]));
    h.state().sanity_check().expect("consistent");
    // Saved, reopened and exported: the picture `c2warp render` draws of the saved
    // file, bit for bit.
    let saved = dir.path().join("saved.json");
    h.state_mut().save_to(&saved);
    h.state_mut().request_open(saved.clone());
    settle(&mut h);
    assert!(h.state().document().is_some_and(|d| d.parts().is_some()));
    let exported = support::export_png(&mut h, dir.path());
    let project = pipeline::load_project(&saved).expect("the saved rig");
    let artwork = pipeline::load_artwork(&dir.path().join("puppet.ora")).expect("the layers");
    let rendered = pipeline::warp_parts(&artwork, &project, None, &())
        .expect("render")
        .composite
        .into_rgba8();
    assert!(
        exported == rendered,
        "the reopened export is render of the saved file"
    );
}

/// Asserts that the view, drawn off screen at full size, is the picture *Export PNG*
/// writes (into `dir`), within a hundredth of its pixels.
fn assert_view_is_export(h: &mut egui_kittest::Harness<'static, editor::EditorApp>, dir: &Path) {
    let gpu = render::GpuContext::new().expect("the software adapter");
    let view = h.state_mut().view_offscreen(&gpu).expect("the view");
    let exported = support::export_png(h, dir);
    let differ = changed(&view, &exported);
    assert!(
        differ < 0.01,
        "the view differs from the export at {differ}"
    );
}

/// The editor on the sample character in `dir`, drawn as parts.
fn puppet_as_parts(dir: &Path) -> egui_kittest::Harness<'static, editor::EditorApp> {
    let mut h = editor(dir);
    h.state_mut().request_open(puppet(dir));
    settle(&mut h);
    click_label(&mut h, "Draw as parts");
    settle(&mut h);
    assert!(h.state().document().is_some_and(|d| d.parts().is_some()));
    h
}

#[test]
fn a_cage_over_parts_moves_the_parts_in_the_view_as_the_export_draws_them() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = puppet_as_parts(dir.path());
    // A cage around the raised arm and the head, solved on the worker, then posed.
    let rest = vec![
        [100.0, 120.0],
        [420.0, 120.0],
        [420.0, 380.0],
        [100.0, 380.0],
    ];
    assert!(h.state_mut().edit(editor::Edit::Cage {
        rest: rest.clone(),
        vertices: 600,
    }));
    h.state_mut().solve_cage();
    settle(&mut h);
    let doc = h.state().document().expect("doc");
    assert!(doc.cage_deformer().is_some(), "solved");
    assert!(doc.parts().is_some(), "the cage moves the parts");
    let at_rest = shot(&mut h);
    let mut pose = rest.clone();
    pose[1] = [450.0, 90.0];
    assert!(h.state_mut().edit(editor::Edit::CagePose(pose)));
    settle(&mut h);
    h.state().sanity_check().expect("consistent");
    let posed = shot(&mut h);
    if let Ok(folder) = std::env::var("C2WARP_SHOTS") {
        let window = h.render().expect("the window");
        (window.save(Path::new(&folder).join("parts-cage-window.png"))).expect("a shot");
    }
    assert!(
        changed(&at_rest, &posed) > 0.001,
        "the cage moved the parts"
    );
    let doc = h.state().document().expect("doc");
    doc.check_reopens().expect("reopens as shown");
    // The view at full size is the export, `render` of the saved project.
    assert_view_is_export(&mut h, dir.path());
}

#[test]
fn rigidity_painted_on_parts_paints_the_part_under_the_brush() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = puppet_as_parts(dir.path());
    click_label(&mut h, "ARAP");
    settle(&mut h);
    h.key_press(egui::Key::R);
    h.run();
    // From the body's middle across to the shoulder, where the back arm lies under
    // the body: the stroke paints the body, the part where it began.
    let (from, to) = ((320.0, 420.0), (362.0, 345.0));
    let body = h
        .state_mut()
        .document_mut()
        .and_then(|d| d.part_at(glam::DVec2::new(from.0, from.1)));
    assert!(body.is_some());
    let (a, b) = (at(&h, from.0, from.1), at(&h, to.0, to.1));
    drag(&mut h, a, b, egui::Modifiers::NONE);
    settle(&mut h);
    let doc = h.state().document().expect("doc");
    let strokes = &doc.project().rigidity;
    assert_eq!(strokes.len(), 1, "{:?}", h.state().message);
    assert_eq!(strokes[0].part, body, "the part under the brush");
    // The overlay shows the painted triangles of that part, on the mesh shown.
    let joined = doc.parts().expect("parts");
    let painted = h.state().brush.painted_triangles();
    assert!(!painted.is_empty(), "the painted triangles are shown");
    let of_body = painted
        .iter()
        .all(|t| joined.part_of_vertex(t[0]).map(|k| k as usize) == body);
    assert!(of_body, "only the body's triangles are shown painted");

    doc.check_reopens().expect("reopens painted");
    h.state().sanity_check().expect("consistent");
    if let Ok(folder) = std::env::var("C2WARP_SHOTS") {
        let window = h.render().expect("the window");
        (window.save(Path::new(&folder).join("parts-rigidity-window.png"))).expect("a shot");
    }
}

#[test]
fn a_locked_part_lets_pins_through_and_a_selected_part_says_what_moves_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = puppet_as_parts(dir.path());
    // At rest, so that what shows under a point is the point itself.
    click_label(&mut h, "Reset pose");
    settle(&mut h);
    let handles = |h: &egui_kittest::Harness<'static, editor::EditorApp>| {
        h.state().document().expect("doc").project().handles.len()
    };
    // The body locked: one undo step, saved in the rig file.
    h.get_by_label("Lock body against new pins and paint")
        .click();
    h.step();
    settle(&mut h);
    let locked = |h: &egui_kittest::Harness<'static, editor::EditorApp>| {
        let doc = h.state().document().expect("doc");
        doc.project_for_saving(None).parts.map(|p| p.locked)
    };
    assert_eq!(locked(&h), Some(vec![3]));
    // A click on the body alone pins nothing, and says why.
    let before = handles(&h);
    let body = at(&h, 300.0, 420.0);
    support::click_at(&mut h, body);
    settle(&mut h);
    assert_eq!(handles(&h), before, "no pin on a locked part");
    let said = h.state().message.as_ref().map(|m| m.text.clone());
    assert!(
        said.as_deref().is_some_and(|m| m.contains("locked")),
        "{said:?}"
    );
    // Where the front arm lies over the body: a pin on the arm alone.
    let shoulder = at(&h, 233.0, 398.0);
    support::click_at(&mut h, shoulder);
    settle(&mut h);
    assert_eq!(handles(&h), before + 1, "{:?}", h.state().message);
    let doc = h.state().document().expect("doc");
    let spec = doc.project().parts.clone().expect("parts");
    assert_eq!(spec.binding(before), Some(&[6][..]), "the arm alone");
    // The body selected: outlined, and what moves it said.
    h.get_by_label("body").click();
    h.step();
    settle(&mut h);
    assert_eq!(h.state().selected_part, Some(3));
    let summary = h
        .query_by_label_contains("body (locked): pinned by handles")
        .is_some();
    assert!(summary, "the selected part's pins are listed");
    if let Ok(folder) = std::env::var("C2WARP_SHOTS") {
        let window = h.render().expect("the window");
        (window.save(Path::new(&folder).join("parts-locked-window.png"))).expect("a shot");
    }
    // Undone: the pin gone, unlocked again.
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    settle(&mut h);
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    settle(&mut h);
    assert_eq!(handles(&h), before);
    assert_eq!(locked(&h), Some(Vec::new()));
    h.state().sanity_check().expect("consistent");
}
