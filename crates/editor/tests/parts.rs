//! A layered picture drawn as parts in the editor: the Layers section's toggle, the
//! view equal to the export, a part brought forward and saved.

use std::path::{Path, PathBuf};

use egui_kittest::kittest::Queryable;

use crate::support::{self, changed, click_label, editor, settle, shot};

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
    let gpu = render::GpuContext::new().expect("the software adapter");
    let view = h.state_mut().view_offscreen(&gpu).expect("the view");
    let exported = support::export_png(&mut h, dir.path());
    let differ = changed(&view, &exported);
    assert!(
        differ < 0.01,
        "the view differs from the export at {differ}"
    );
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
