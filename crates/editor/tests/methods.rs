//! The method switch and the rigidity brush, driven as a user drives them, on the
//! built-in picture with its posed sample rig; the canvas drawn by the real wgpu paint
//! callback on the software adapter.

use crate::support;

use egui::{Key, Modifiers};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use glam::DVec2;
use project::Method;

use editor::{EditorApp, Tool};
use support::{at, changed, click_label, drag, editor, shot};

fn method(h: &Harness<'_, EditorApp>) -> Method {
    h.state().document().expect("a document").method()
}

fn positions(h: &Harness<'_, EditorApp>) -> Vec<DVec2> {
    h.state()
        .document()
        .expect("a document")
        .deformer()
        .deformed()
}

#[test]
fn switching_methods_keeps_the_pose_and_comes_back_and_undoes() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    let handles = h.state().document().expect("doc").project().handles.clone();
    let c2 = shot(&mut h);
    let c2_positions = positions(&h);

    click_label(&mut h, "ARAP");
    assert_eq!(method(&h), Method::Arap);
    let doc = h.state().document().expect("doc");
    assert_eq!(doc.project().handles, handles, "same handles and pose");
    let times = doc
        .arap()
        .map(pipeline::ArapRig::times)
        .expect("ARAP is set up");
    assert!(times.compile_ms > 0.0);
    // The editor's ARAP is the method's own answer for the rig's mesh and handles.
    let project = doc.project();
    let own = pipeline::on_mesh(project, doc.mesh(), Some(&doc.image))
        .expect("ARAP")
        .expect("not the rig")
        .deformed();
    assert_eq!(positions(&h), own);
    let arap = shot(&mut h);
    assert!(
        changed(&c2, &arap) > 0.002,
        "ARAP draws another picture ({})",
        changed(&c2, &arap)
    );
    let moved = positions(&h)
        .iter()
        .zip(&c2_positions)
        .filter(|(a, b)| a.distance(**b) > 1.0)
        .count();
    assert!(moved > c2_positions.len() / 10, "{moved} vertices moved");

    click_label(&mut h, "C² weights");
    assert_eq!(method(&h), Method::C2);
    assert_eq!(positions(&h), c2_positions);
    assert_eq!(
        changed(&c2, &shot(&mut h)),
        0.0,
        "the C² picture comes back"
    );

    // Each switch is one undo step.
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    assert_eq!(method(&h), Method::Arap);
    assert_eq!(changed(&arap, &shot(&mut h)), 0.0);
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    assert_eq!(method(&h), Method::C2);
    // The method is saved with the project.
    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    h.run();
    let saved = h
        .state()
        .document()
        .expect("doc")
        .project_for_saving(None)
        .to_json();
    assert!(saved.contains(r#""method": "arap""#), "{saved}");
    h.state().sanity_check().expect("consistent");
}

#[test]
fn a_drag_under_arap_moves_the_handle_and_keeps_the_compiled_system() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    click_label(&mut h, "ARAP");
    click_label(&mut h, "Select");
    let compile = h
        .state()
        .document()
        .and_then(|d| d.arap().map(pipeline::ArapRig::times))
        .expect("ARAP");
    // Handle 2 is a point at (440, 238) moved by (-20, -60); drag it 20 px right and
    // 10 px down.
    let translate = |h: &Harness<'_, EditorApp>| support::translate(&support::handles(h)[2]);
    let before = translate(&h);
    let now = DVec2::new(440.0, 238.0) + before;
    let (from, to) = (at(&h, now.x, now.y), at(&h, now.x + 20.0, now.y + 10.0));
    drag(&mut h, from, to, Modifiers::NONE);
    let moved = translate(&h) - before;
    assert!(
        (moved - DVec2::new(20.0, 10.0)).length() < 2.0,
        "moved by {moved}"
    );
    let doc = h.state().document().expect("doc");
    let after = doc.arap().map(pipeline::ArapRig::times).expect("ARAP");
    assert_eq!(
        after.compile_ms, compile.compile_ms,
        "a translation drag recompiles nothing"
    );
    // The handle's vertex sits exactly where the handle's translation puts it.
    let domain = doc.mesh();
    let v = domain
        .nearest_vertex(DVec2::new(440.0, 238.0))
        .expect("a vertex") as usize;
    let expected = domain.positions()[v] + translate(&h);
    assert!((doc.deformer().deformed()[v] - expected).length() < 1e-9);
    h.state().sanity_check().expect("consistent");
}

#[test]
fn painted_rigidity_is_one_undo_step_and_erases() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    click_label(&mut h, "ARAP");
    let before = positions(&h);
    let unpainted = shot(&mut h);
    h.key_press(Key::R);
    h.run();
    assert_eq!(h.state().tool, Tool::Rigidity);
    // A stroke along the tail, which the pose bends.
    let (a, b) = (at(&h, 300.0, 420.0), at(&h, 420.0, 520.0));
    drag(&mut h, a, b, Modifiers::NONE);
    let strokes = h
        .state()
        .document()
        .expect("doc")
        .project()
        .rigidity
        .clone();
    assert_eq!(strokes.len(), 1, "{:?}", h.state().message);
    assert!(strokes[0].stroke.len() > 2);
    assert_eq!(strokes[0].weight, 10_000.0);
    let painted = positions(&h);
    assert_ne!(painted, before, "the paint changed the warp");
    assert!(changed(&unpainted, &shot(&mut h)) > 0.0);
    let stiff = h
        .state()
        .document()
        .and_then(|d| d.arap())
        .map(pipeline::ArapRig::rigidity)
        .expect("ARAP")
        .iter()
        .filter(|w| **w > 1.0)
        .count();
    assert!(stiff > 10, "{stiff} painted triangles");
    // The painted region shows with its outline (dark and light, so it shows on any
    // picture), and the brush with its own where the pointer hovers.
    h.hover_at(at(&h, 250.0, 300.0));
    h.run();
    h.snapshot("editor_rigidity");

    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    assert!(
        h.state()
            .document()
            .expect("doc")
            .project()
            .rigidity
            .is_empty()
    );
    assert_eq!(positions(&h), before, "undo takes the paint back");
    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    h.run();
    assert_eq!(positions(&h), painted, "and redo puts it back");

    // Alt-drag along the same path erases it.
    drag(&mut h, a, b, Modifiers::ALT);
    let doc = h.state().document().expect("doc");
    assert!(
        doc.project().rigidity.is_empty(),
        "{:?}",
        doc.project().rigidity
    );
    assert_eq!(positions(&h), before);
    h.state().sanity_check().expect("consistent");
}

#[test]
fn arap_with_no_handles_one_handle_and_paint_under_c2() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    click_label(&mut h, "ARAP");
    click_label(&mut h, "Clear all handles");
    let doc = h.state().document().expect("doc");
    let rest = doc.mesh().positions().to_vec();
    let at_rest = positions(&h);
    let worst = at_rest
        .iter()
        .zip(&rest)
        .map(|(a, b)| a.distance(*b))
        .fold(0.0, f64::max);
    assert!(worst < 1e-9, "no handles: the rest shape ({worst})");
    h.state().sanity_check().expect("consistent");
    // Paint under C²: kept, with a word that it is for ARAP.
    click_label(&mut h, "C² weights");
    h.key_press(Key::R);
    h.run();
    let (a, b) = (at(&h, 300.0, 300.0), at(&h, 340.0, 320.0));
    drag(&mut h, a, b, Modifiers::NONE);
    let state = h.state();
    assert_eq!(state.document().expect("doc").project().rigidity.len(), 1);
    let message = state.message.as_ref().map(|m| m.text.clone());
    assert!(
        message.as_deref().is_some_and(|m| m.contains("ARAP")),
        "{message:?}"
    );
    state.sanity_check().expect("consistent");
}

#[test]
fn bringing_a_handle_forward_puts_its_part_in_front() {
    let dir = tempfile::tempdir().expect("temp dir");
    support::write_lizard(dir.path());
    // The hind leg dragged over the body.
    std::fs::write(
        dir.path().join("project.json"),
        r#"{"version": 1, "image": "lizard.png", "density": 4000, "handles": [
            {"type": "bar", "rest": [[110, 130], [250, 250]]},
            {"type": "point", "rest": [440, 238]},
            {"type": "point", "rest": [685, 590]},
            {"type": "point", "rest": [190, 470], "translate": [140, -150], "depth": -1}]}"#,
    )
    .expect("write project");
    let mut h = editor(dir.path());
    h.get_by_label("File").click();
    h.run();
    click_label(&mut h, "Open project…");
    support::settle(&mut h);
    assert_eq!(
        h.state().document().expect("doc").project().handles.len(),
        4
    );
    h.state_mut().selected = Some(3);
    h.run();
    let behind = shot(&mut h);
    click_label(&mut h, "Bring forward");
    click_label(&mut h, "Bring forward");
    let doc = h.state().document().expect("doc");
    assert_eq!(doc.project().handles[3].depth(), 1);
    let in_front = shot(&mut h);
    assert!(
        changed(&behind, &in_front) > 0.0005,
        "the leg comes in front ({})",
        changed(&behind, &in_front)
    );
    h.snapshot("editor_leg_in_front");
    // One undo step each.
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    assert_eq!(
        h.state().document().expect("doc").project().handles[3].depth(),
        -1
    );
    assert_eq!(changed(&behind, &shot(&mut h)), 0.0);
    h.state().sanity_check().expect("consistent");
}

#[test]
fn an_arap_export_is_what_the_pipeline_draws_for_the_saved_project() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    click_label(&mut h, "ARAP");
    let exported = support::export_png(&mut h, dir.path());
    let doc = h.state().document().expect("doc");
    let project = doc.project_for_saving(None);
    assert_eq!(project.method, Method::Arap);
    let warper = pipeline::prepare_warper(&doc.image, &project, None, &()).expect("ARAP");
    let expected = pipeline::warp(&doc.image, &warper).expect("warp");
    assert!(exported == expected, "the export is ARAP's picture");
    let c2 = {
        let mut project = project.clone();
        project.method = Method::C2;
        let warper = pipeline::prepare_warper(&doc.image, &project, None, &()).expect("C²");
        pipeline::warp(&doc.image, &warper).expect("warp")
    };
    assert!(changed(&c2, &exported) > 0.001, "and not C²'s");
}

#[test]
fn on_a_large_mesh_arap_is_set_up_on_the_worker_and_undone_there() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    // Count the built-in picture's mesh as large.
    h.state_mut().large_mesh = 1000;
    h.get_by_label("ARAP").click();
    h.step();
    assert!(h.state().is_busy(), "set up on the worker");
    assert_eq!(
        h.state().busy_with().map(|(l, _)| l),
        Some("Setting up ARAP")
    );
    support::settle(&mut h);
    assert_eq!(method(&h), Method::Arap);
    h.state().sanity_check().expect("consistent");
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    assert_eq!(method(&h), Method::C2, "switching back is instant");
    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    h.step();
    assert!(h.state().is_busy(), "redo sets ARAP up on the worker");
    support::settle(&mut h);
    assert_eq!(method(&h), Method::Arap);
    h.state().sanity_check().expect("consistent");
}

/// Found by the monkey: the painted overlay kept the triangles of the mesh it was
/// painted on after a new density re-meshed the picture.
#[test]
fn painted_rigidity_survives_a_new_density() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    h.key_press(Key::R);
    h.run();
    // A wide stroke over most of the picture, so the painted triangles' indices run
    // past the smaller mesh's.
    h.state_mut().brush.radius = 200.0;
    let (a, b) = (at(&h, 100.0, 100.0), at(&h, 600.0, 500.0));
    drag(&mut h, a, b, Modifiers::NONE);
    let mut settings = h.state().document().expect("doc").settings();
    settings.density = 3000;
    assert!(h.state_mut().edit(editor::Edit::Settings(settings)));
    support::settle(&mut h);
    for _ in 0..3 {
        h.run();
    }
    let doc = h.state().document().expect("doc");
    assert!(doc.mesh().len() < 4000);
    assert_eq!(doc.project().rigidity.len(), 1);
    // The overlay shows the triangles painted on the new mesh.
    let domain = doc.mesh();
    let fresh: Vec<[u32; 3]> = pipeline::arap::rigidity_weights(domain, &doc.project().rigidity)
        .iter()
        .zip(domain.triangles())
        .filter(|(w, _)| **w != 1.0)
        .map(|(_, &t)| t)
        .collect();
    assert!(!fresh.is_empty());
    assert_eq!(h.state().painted_triangles(), fresh);
    h.state().sanity_check().expect("consistent");
}

#[test]
fn mls_is_chosen_dragged_undone_and_exported_as_the_pipeline_draws_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    let c2 = shot(&mut h);
    let c2_positions = positions(&h);
    click_label(&mut h, "MLS");
    assert_eq!(method(&h), Method::Mls);
    // The editor's MLS is the method's own answer for the rig's mesh and handles.
    let doc = h.state().document().expect("doc");
    let own = pipeline::on_mesh(doc.project(), doc.mesh(), Some(&doc.image))
        .expect("MLS")
        .expect("not the rig")
        .deformed();
    assert_eq!(positions(&h), own);
    let mls = shot(&mut h);
    assert!(changed(&c2, &mls) > 0.002, "MLS draws another picture");

    // A drag moves the picture at the handle with it: MLS interpolates its handles.
    click_label(&mut h, "Select");
    let translate = |h: &Harness<'_, EditorApp>| support::translate(&support::handles(h)[2]);
    let before = translate(&h);
    let now = DVec2::new(440.0, 238.0) + before;
    let (from, to) = (at(&h, now.x, now.y), at(&h, now.x + 20.0, now.y + 10.0));
    drag(&mut h, from, to, Modifiers::NONE);
    let moved = translate(&h) - before;
    assert!(
        (moved - DVec2::new(20.0, 10.0)).length() < 2.0,
        "moved by {moved}"
    );
    let doc = h.state().document().expect("doc");
    let domain = doc.mesh();
    let v = domain
        .nearest_vertex(DVec2::new(440.0, 238.0))
        .expect("a vertex") as usize;
    let gap = domain.positions()[v].distance(DVec2::new(440.0, 238.0));
    let went = doc.deformer().deformed()[v] - domain.positions()[v];
    assert!(
        went.distance(translate(&h)) < 0.2 * gap + 1e-9,
        "the vertex {gap:.2} px from the handle went by {went}, the handle by {}",
        translate(&h)
    );
    h.state().sanity_check().expect("consistent");

    // The export is the pipeline's MLS for the saved project, and saved as MLS.
    let exported = support::export_png(&mut h, dir.path());
    let doc = h.state().document().expect("doc");
    let project = doc.project_for_saving(None);
    assert_eq!(project.method, Method::Mls);
    assert!(project.to_json().contains(r#""method": "mls""#));
    let warper = pipeline::prepare_warper(&doc.image, &project, None, &()).expect("MLS");
    assert!(exported == pipeline::warp(&doc.image, &warper).expect("warp"));

    // Undo the drag, then the switch: the C² picture comes back.
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    assert_eq!(positions(&h), own, "the drag undone, MLS is where it was");
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    assert_eq!(method(&h), Method::C2);
    assert_eq!(positions(&h), c2_positions);
}

#[test]
fn mls_fit_and_alpha_are_settings_of_the_rig_and_undo() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    click_label(&mut h, "MLS");
    let rigid = positions(&h);
    let settings = |h: &Harness<'_, EditorApp>| {
        h.state()
            .document()
            .expect("doc")
            .project()
            .mls
            .unwrap_or_default()
    };
    assert_eq!(settings(&h), project::MlsSettings::default());
    // The Fit menu: from rigid to affine.
    click_label(&mut h, "Fit");
    click_label(&mut h, "Affine");
    assert_eq!(settings(&h).variant, Some(project::MlsVariant::Affine));
    let affine = positions(&h);
    assert_ne!(affine, rigid, "another fit, another warp");
    // α, as a typed value: more local handles.
    assert!(h.state_mut().edit(editor::Edit::Mls(project::MlsSettings {
        alpha: Some(2.5),
        variant: Some(project::MlsVariant::Affine),
    })));
    h.run();
    assert_ne!(positions(&h), affine);
    h.state().sanity_check().expect("consistent");
    // Out of range is refused and changes nothing.
    assert!(!h.state_mut().edit(editor::Edit::Mls(project::MlsSettings {
        alpha: Some(0.0),
        variant: None,
    })));
    assert_eq!(settings(&h).alpha, Some(2.5));
    // One undo step each.
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    assert_eq!(positions(&h), affine);
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    assert_eq!(positions(&h), rigid);
}

#[test]
fn mls_on_a_cut_out_says_once_what_it_does_across_gaps() {
    let mut h = support::editor_with(Box::new(support::NoDesktop), false);
    let text = |h: &Harness<'_, EditorApp>| {
        h.state()
            .message
            .as_ref()
            .map(|m| m.text.clone())
            .unwrap_or_default()
    };
    click_label(&mut h, "MLS");
    assert!(text(&h).starts_with("MLS on a cut-out"), "{}", text(&h));
    assert!(text(&h).contains("needle"), "{}", text(&h));
    click_label(&mut h, "C² weights");
    click_label(&mut h, "MLS");
    assert!(!text(&h).contains("cut-out"), "said once: {}", text(&h));
}
