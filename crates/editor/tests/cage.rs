//! The cage tool (LBC) driven as a user drives it, on the built-in picture: a cage
//! clicked around the lizard's body, solved on the worker, posed by dragging a vertex
//! and a box-selected group, undone, saved and opened again, exported; refusals and a
//! cancelled solve. The canvas is drawn by the real wgpu paint callback on the software
//! adapter.

use crate::support;

use egui::{Key, Modifiers, Pos2, Vec2};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use glam::DVec2;
use project::{LbcSettings, Method, Tau};

use editor::{CageKey, CageState, Edit, EditorApp, Tool};
use support::{BODY, at, changed, click_at, click_label, drag, editor, settle, shot};

/// Mesh vertices inside the cage in these tests: few, so a debug build solves in
/// seconds.
const DENSITY: usize = 300;

/// The canvas pixel that shows image point `p`.
fn pixel(h: &Harness<'_, EditorApp>, shot: &image::RgbaImage, p: DVec2) -> image::Rgba<u8> {
    let scale = h.ctx.pixels_per_point();
    let canvas = h.state().viewport.canvas;
    let s = h.state().viewport.to_screen(p);
    let (x, y) = ((s.x - canvas.min.x) * scale, (s.y - canvas.min.y) * scale);
    *shot.get_pixel(x as u32, y as u32)
}

/// Whether two canvas shots agree at every image point of `points`, within 8 per
/// channel.
fn same_at(
    h: &Harness<'_, EditorApp>,
    a: &image::RgbaImage,
    b: &image::RgbaImage,
    points: &[DVec2],
) -> bool {
    points.iter().all(|&p| {
        let (x, y) = (pixel(h, a, p), pixel(h, b, p));
        x.0.iter().zip(y.0).all(|(u, v)| u.abs_diff(v) <= 8)
    })
}

fn pose(h: &Harness<'_, EditorApp>) -> Option<Vec<[f64; 2]>> {
    h.state()
        .document()
        .and_then(|d| d.cage())
        .and_then(|c| c.pose.clone())
}

/// Clicks the cage `points` (image pixels) with the cage tool and closes it on its
/// first vertex.
fn draw_cage(h: &mut Harness<'_, EditorApp>, points: &[[f64; 2]]) {
    if h.state().tool != Tool::Cage {
        h.key_press(Key::K);
        h.run();
    }
    assert_eq!(h.state().tool, Tool::Cage);
    for p in points {
        let pos = at(h, p[0], p[1]);
        click_at(h, pos);
    }
    let first = at(h, points[0][0], points[0][1]);
    click_at(h, first);
}

/// The built-in picture with the body cage drawn, at a small density, solved.
fn solved_body(dir: &std::path::Path) -> Harness<'static, EditorApp> {
    let mut h = editor(dir);
    h.state_mut().cage.inside_vertices = DENSITY;
    draw_cage(&mut h, &BODY);
    assert_eq!(h.state().cage_state(), CageState::Rest);
    solve_with_enter(&mut h);
    h
}

/// Enter solves the cage at rest, on the worker; waits for it to be solved.
fn solve_with_enter(h: &mut Harness<'_, EditorApp>) {
    h.key_press(Key::Enter);
    h.step();
    // The solve runs on the worker; a small one may be done by the end of the frame
    // that started it, so only a frame that neither waits nor has it done is wrong.
    assert!(
        h.state().is_busy() || h.state().cage_state() == CageState::Posed,
        "Enter solves the cage: {:?}",
        h.state().message
    );
    settle(h);
    assert_eq!(
        h.state().cage_state(),
        CageState::Posed,
        "{:?}",
        h.state().message
    );
}

#[test]
fn a_cage_is_drawn_solved_posed_undone_saved_and_opened_again() {
    let dir = tempfile::tempdir().expect("temp dir");
    support::write_lizard(dir.path());
    let mut h = editor(dir.path());
    // Without the locality panel, the canvas keeps its size whatever the tool.
    h.state_mut().show.locality = false;
    let c2 = shot(&mut h);
    // The cage tool shows the picture at rest, not the sample rig's C² pose.
    h.key_press(Key::K);
    h.run();
    let at_rest = shot(&mut h);
    assert!(changed(&c2, &at_rest) > 0.01);
    draw_cage(&mut h, &BODY);
    let doc = h.state().document().expect("doc");
    assert_eq!(doc.method(), Method::Lbc, "closing the cage chooses LBC");
    let rest: Vec<[f64; 2]> = doc.cage().expect("a cage").rest.clone();
    assert_eq!(rest.len(), BODY.len());
    for (r, b) in rest.iter().zip(&BODY) {
        assert!(
            DVec2::from(*r).distance(DVec2::from(*b)) < 1.0,
            "{r:?} vs {b:?}"
        );
    }
    assert!(doc.cage_solution().is_none(), "not solved before asked");
    // Unsolved, nothing moves: only the cage's outline is new.
    let drawn = shot(&mut h);
    assert!(
        changed(&at_rest, &drawn) < 0.01,
        "{}",
        changed(&at_rest, &drawn)
    );

    let settings = LbcSettings {
        tau: Tau::Square,
        density: Some(DENSITY),
    };
    assert!(h.state_mut().edit(Edit::Lbc(settings)));
    click_label(&mut h, "Solve");
    settle(&mut h);
    let doc = h.state().document().expect("doc");
    let solution = doc.cage_solution().expect("solved").clone();
    assert!(solution.domain.positions().len() > DENSITY / 2);
    assert_eq!(solution.weights.cage_vertices(), BODY.len());
    // Solved at rest, the view is the picture at rest (the inside drawn where it was).
    let solved = shot(&mut h);
    assert!(
        changed(&drawn, &solved) < 0.01,
        "{}",
        changed(&drawn, &solved)
    );

    // Drag vertex 1 (top right) 40 px right and 30 px up.
    let from = at(&h, BODY[1][0], BODY[1][1]);
    let to = from + Vec2::new(40.0, -30.0) * h.state().viewport.zoom;
    drag(&mut h, from, to, Modifiers::NONE);
    let posed = pose(&h).expect("posed");
    let moved = DVec2::from(posed[1]) - DVec2::from(BODY[1]);
    assert!((moved - DVec2::new(40.0, -30.0)).length() < 1.5, "{moved}");
    for i in [0, 2, 3, 4, 5] {
        assert_eq!(posed[i], rest[i], "only the dragged vertex moves");
    }
    let warped = shot(&mut h);
    // Inside the cage near the dragged vertex, the picture moved; outside the cage,
    // nothing did.
    assert!(
        !same_at(&h, &solved, &warped, &[DVec2::new(360.0, 230.0)]),
        "the inside near the vertex moved"
    );
    let outside = [
        DVec2::new(60.0, 60.0),
        DVec2::new(650.0, 600.0),
        DVec2::new(500.0, 500.0),
        DVec2::new(120.0, 500.0),
    ];
    assert!(same_at(&h, &solved, &warped, &outside), "the outside stays");
    // Far from the dragged vertex, inside the cage, LBC's locality keeps the picture.
    assert!(same_at(&h, &solved, &warped, &[DVec2::new(250.0, 400.0)]));
    h.state().sanity_check().expect("consistent");

    // Undo takes the pose back; redo puts it again.
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    assert_eq!(pose(&h), None);
    // Escape drops the selection, so the vertices look as they did.
    h.key_press(Key::Escape);
    h.run();
    assert!(h.state().cage_selection().is_empty());
    assert_eq!(changed(&solved, &shot(&mut h)), 0.0);
    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    h.run();
    assert_eq!(pose(&h).as_ref(), Some(&posed));
    let before_saving = shot(&mut h);

    // Save, open again: the same cage, pose and view.
    h.key_press_modifiers(Modifiers::COMMAND, Key::S);
    h.run();
    let saved = std::fs::read_to_string(dir.path().join("project.json")).expect("saved");
    assert!(saved.contains(r#""method": "lbc""#), "{saved}");
    h.get_by_label("File").click();
    h.run();
    click_label(&mut h, "Open project…");
    settle(&mut h);
    let doc = h.state().document().expect("doc");
    assert_eq!(doc.method(), Method::Lbc);
    assert_eq!(doc.cage().expect("a cage").rest, rest);
    assert_eq!(pose(&h).as_ref(), Some(&posed));
    assert!(doc.cage_solution().is_some(), "opening solves the cage");
    assert_eq!(h.state().tool, Tool::Cage);
    let reopened = shot(&mut h);
    assert!(
        changed(&before_saving, &reopened) < 0.0005,
        "{}",
        changed(&before_saving, &reopened)
    );
    h.state().sanity_check().expect("consistent");
}

#[test]
fn a_box_selected_group_moves_together_and_reset_pose_brings_it_back() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = solved_body(dir.path());
    // A box around the two right-hand vertices (1 and 2).
    let (a, b) = (at(&h, 370.0, 170.0), at(&h, 470.0, 320.0));
    drag(&mut h, a, b, Modifiers::NONE);
    let mut selected = h.state().cage_selection().to_vec();
    selected.sort_unstable();
    assert_eq!(selected, vec![1, 2]);
    assert_eq!(pose(&h), None, "a box selects; it moves nothing");
    let from = at(&h, BODY[2][0], BODY[2][1]);
    drag(&mut h, from, from + Vec2::new(30.0, 0.0), Modifiers::NONE);
    let posed = pose(&h).expect("posed");
    let rest = h.state().document().expect("doc").cage_rest();
    let dx = |i: usize| posed[i][0] - rest[i].x;
    assert!(dx(1) > 10.0 && (dx(1) - dx(2)).abs() < 1e-9, "{posed:?}");
    assert_eq!(posed[0], rest[0].to_array());
    click_label(&mut h, "Reset pose");
    assert_eq!(pose(&h), None);
    h.state().sanity_check().expect("consistent");

    // Clearing the solved cage goes back to C²; undoing it finds the coordinates
    // again, with no new solve.
    click_label(&mut h, "Clear cage");
    let doc = h.state().document().expect("doc");
    assert!(doc.cage().is_none());
    assert_eq!(doc.method(), Method::C2);
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.step();
    assert!(!h.state().is_busy());
    assert_eq!(h.state().cage_state(), CageState::Posed);
    h.state().sanity_check().expect("consistent");
}

#[test]
fn a_crossing_cage_is_refused_and_can_be_fixed() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    // Two vertices are no cage (a click on the first adds nothing).
    draw_cage(&mut h, &[[200.0, 200.0], [400.0, 200.0]]);
    assert_eq!(h.state().cage_draft().map(<[DVec2]>::len), Some(2));
    h.key_press(Key::Enter);
    h.run();
    let message = h.state().message.clone().expect("a message");
    assert!(message.text.contains("at least 3"), "{message:?}");
    h.key_press(Key::Escape);
    h.run();
    assert!(h.state().cage_draft().is_none(), "Escape drops the polygon");
    // A bow tie.
    let bow = [
        [200.0, 200.0],
        [400.0, 200.0],
        [200.0, 400.0],
        [400.0, 400.0],
    ];
    draw_cage(&mut h, &bow);
    let message = h.state().message.clone().expect("a message");
    assert!(
        message.is_error && message.text.contains("intersect"),
        "{message:?}"
    );
    assert_eq!(h.state().cage_draft().map(<[DVec2]>::len), Some(4));
    assert!(h.state().document().expect("doc").cage().is_none());
    assert_eq!(h.state().document().expect("doc").method(), Method::C2);
    // Backspace removes the last two; two clicks make a square, Enter closes it.
    h.key_press(Key::Backspace);
    h.key_press(Key::Backspace);
    h.run();
    for p in [[400.0, 400.0], [200.0, 400.0]] {
        let pos = at(&h, p[0], p[1]);
        click_at(&mut h, pos);
    }
    h.key_press(Key::Enter);
    h.run();
    let doc = h.state().document().expect("doc");
    assert_eq!(doc.cage().expect("closed").rest.len(), 4);
    assert_eq!(h.state().cage_state(), CageState::Rest);
    // Dragging a vertex across makes it cross again: shown, and refused at Solve.
    let (from, to) = (at(&h, 200.0, 400.0), at(&h, 450.0, 300.0));
    drag(&mut h, from, to, Modifiers::NONE);
    h.state_mut().solve_cage();
    assert!(!h.state().is_busy());
    let message = h.state().message.clone().expect("a message");
    assert!(message.text.contains("intersect"), "{message:?}");
    h.state().sanity_check().expect("consistent");
}

#[test]
fn a_cancelled_solve_leaves_everything_as_it_was() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    // A solve long enough that Escape always comes before it ends (a small one could
    // finish between two frames on a fast or an idle machine).
    h.state_mut().cage.inside_vertices = 10_000;
    draw_cage(&mut h, &BODY);
    let before = h.state().document().expect("doc").project().clone();
    let undo = h.state().history_len();
    h.key_press(Key::Enter);
    h.step();
    assert!(h.state().is_busy());
    h.key_press(Key::Escape);
    h.run();
    assert!(!h.state().is_busy(), "Escape cancels the solve");
    let doc = h.state().document().expect("doc");
    assert!(doc.cage_solution().is_none());
    assert_eq!(doc.project(), &before);
    assert_eq!(h.state().history_len(), undo);
    assert_eq!(h.state().cage_state(), CageState::Rest);
    h.state().sanity_check().expect("consistent");
    // Undo and the method switch during a solve wait for it.
    h.key_press(Key::Enter);
    h.step();
    assert!(h.state().is_busy());
    assert!(!h.state_mut().edit(Edit::Method(Method::C2)));
    h.state_mut().undo();
    assert_eq!(h.state().history_len(), undo, "no undo under a solve");
    h.state_mut().cancel_job();
    h.run();
    assert_eq!(h.state().document().expect("doc").method(), Method::Lbc);
}

#[test]
fn an_lbc_export_is_what_the_pipeline_draws_for_the_saved_project() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = solved_body(dir.path());
    let from = at(&h, BODY[3][0], BODY[3][1]);
    drag(&mut h, from, from + Vec2::new(-20.0, 25.0), Modifiers::NONE);
    assert!(pose(&h).is_some());
    let exported = support::export_png(&mut h, dir.path());
    // What `c2warp render` does with the saved project: mesh the cage's inside to the
    // project's count, solve, warp.
    let doc = h.state().document().expect("doc");
    let project = doc.project_for_saving(None);
    assert_eq!(pipeline::cage::cage_vertices(&project, None), DENSITY);
    let warper = pipeline::prepare_warper(&doc.image, &project, None, &()).expect("solved");
    let expected = pipeline::warp(&doc.image, &warper).expect("warp");
    assert!(
        changed(&exported, &expected) < 1e-4,
        "{}",
        changed(&exported, &expected)
    );
    assert!(changed(&exported, &doc.image) > 0.001, "and warped");
}

#[test]
fn a_cage_from_the_outline_encloses_the_lizard() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    click_label(&mut h, "Cage");
    assert_eq!(h.state().tool, Tool::Cage);
    click_label(&mut h, "Cage from outline");
    let doc = h.state().document().expect("doc");
    let cage = doc.cage().expect("a cage").rest.clone();
    assert_eq!(cage.len(), 16);
    assert_eq!(doc.method(), Method::Lbc);
    assert!(
        CageKey::of(doc.project())
            .expect("a key")
            .problem()
            .is_none(),
        "a simple polygon"
    );
    h.state().sanity_check().expect("consistent");
    // Undo takes it away, and LBC with it.
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    let doc = h.state().document().expect("doc");
    assert!(doc.cage().is_none());
    assert_eq!(doc.method(), Method::C2);
}

#[test]
fn an_lbc_project_with_a_crossing_cage_opens_unsolved_with_a_message() {
    let dir = tempfile::tempdir().expect("temp dir");
    support::write_lizard(dir.path());
    std::fs::write(
        dir.path().join("project.json"),
        r#"{"version": 1, "image": "lizard.png", "method": "lbc", "handles": [],
            "cage": {"rest": [[200, 200], [400, 200], [200, 400], [400, 400]]}}"#,
    )
    .expect("write project");
    let mut h = editor(dir.path());
    h.get_by_label("File").click();
    h.run();
    click_label(&mut h, "Open project…");
    settle(&mut h);
    let doc = h.state().document().expect("the project opens");
    assert_eq!(doc.method(), Method::Lbc);
    assert!(doc.cage_solution().is_none());
    let message = h.state().message.clone().expect("a message");
    assert!(
        message.is_error && message.text.contains("intersect"),
        "{message:?}"
    );
    assert_eq!(h.state().cage_state(), CageState::Rest);
    h.state().sanity_check().expect("consistent");
}

#[test]
fn the_cage_view_shows_the_heat_map_contour_and_locality_plots() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = solved_body(dir.path());
    h.state_mut().show.heat = true;
    let vertex = at(&h, BODY[1][0], BODY[1][1]);
    click_at(&mut h, vertex);
    assert_eq!(h.state().cage_selection(), &[1]);
    let from = at(&h, BODY[1][0], BODY[1][1]);
    drag(&mut h, from, from + Vec2::new(30.0, -25.0), Modifiers::NONE);
    h.hover_at(Pos2::new(5.0, 5.0));
    h.run();
    assert!(h.query_by_label("P(t) plot").is_some());
    assert!(h.query_by_label("Q(k) plot").is_some());
    let doc = h.state().document().expect("doc");
    let locality = &doc.cage_solution().expect("solved").locality;
    assert!((locality.q[0] - 1.0).abs() < 1e-9, "every point has σ ≥ 0");
    assert!(
        locality.p.windows(2).all(|w| w[0] <= w[1] + 1e-12),
        "P grows"
    );
    h.snapshot("editor_cage");
}

#[test]
fn undo_to_a_posed_cage_whose_coordinates_were_forgotten_solves_it_first() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = solved_body(dir.path());
    let from = at(&h, BODY[1][0], BODY[1][1]);
    drag(&mut h, from, from + Vec2::new(25.0, -20.0), Modifiers::NONE);
    let posed = pose(&h).expect("posed");
    // Four more cages, each solved: the editor keeps four, so the first is forgotten.
    for shift in 1..=4 {
        let rest = BODY
            .iter()
            .map(|p| [p[0] + 5.0 * f64::from(shift), p[1]])
            .collect();
        assert!(h.state_mut().edit(Edit::Cage {
            rest,
            vertices: DENSITY
        }));
        h.state_mut().solve_cage();
        settle(&mut h);
        assert_eq!(h.state().cage_state(), CageState::Posed);
    }
    let (undo, _) = h.state().history_len();
    // Back through the later cages (kept, so at once), then to the posed first one.
    for _ in 0..3 {
        h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
        h.step();
        assert!(!h.state().is_busy(), "a kept cage needs no solve");
    }
    // Called directly rather than through a frame, so that a solve quick enough to
    // finish within the frame cannot be mistaken for none.
    h.state_mut().undo();
    assert!(
        h.state().is_busy(),
        "the forgotten cage is solved on the worker"
    );
    assert_eq!(
        h.state().history_len().0,
        undo - 3,
        "the history waits for the solve"
    );
    assert_eq!(pose(&h), None);
    settle(&mut h);
    assert_eq!(h.state().history_len().0, undo - 4);
    assert_eq!(pose(&h).as_ref(), Some(&posed));
    assert_eq!(h.state().cage_state(), CageState::Posed);
    h.state().sanity_check().expect("consistent");
}

#[test]
fn after_a_cage_from_the_outline_enter_solves_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    h.state_mut().cage.inside_vertices = DENSITY;
    click_label(&mut h, "LBC cage");
    // Drawing a cage is LBC's: the method shows as LBC before the cage exists.
    assert_eq!(h.state().tool, Tool::Cage);
    assert_eq!(h.state().method_shown(), Some(Method::Lbc));
    click_label(&mut h, "Cage from outline");
    let first = h.state().document().and_then(|d| d.cage()).cloned();
    assert!(first.is_some());
    // The button gave up the keys: Enter solves, it does not make the cage anew.
    solve_with_enter(&mut h);
    assert_eq!(h.state().document().and_then(|d| d.cage()).cloned(), first);
    h.state().sanity_check().expect("consistent");
}

#[test]
fn undoing_out_of_lbc_leaves_the_cage_tool_and_says_what_it_undid() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = solved_body(dir.path());
    assert_eq!(h.state().tool, Tool::Cage);
    // Back to before the cage: C², nothing for the cage tool to act on.
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    settle(&mut h);
    let doc = h.state().document().expect("doc");
    assert_eq!(doc.method(), Method::C2);
    assert_eq!(h.state().tool, Tool::Puppet);
    let message = h.state().message.clone().expect("a message");
    assert!(message.text.starts_with("undone: "), "{message:?}");
    // It names the step undone: the one that made the cage.
    assert!(message.text.contains("a cage"), "{message:?}");
    assert!(!message.text.contains("drag a vertex"), "{message:?}");
    // Redo comes back to LBC and its tool.
    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    h.run();
    settle(&mut h);
    assert_eq!(h.state().tool, Tool::Cage);
    let message = h.state().message.clone().expect("a message");
    assert!(message.text.starts_with("redone: "), "{message:?}");
    h.state().sanity_check().expect("consistent");
}

#[test]
fn a_new_cage_being_drawn_hides_the_old_cages_statistics() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = solved_body(dir.path());
    h.state_mut().show.locality = true;
    h.run();
    assert!(
        h.query_by_label_contains("statistics (§5) of the coordinates of this cage")
            .is_some()
    );
    click_label(&mut h, "New cage");
    h.run();
    assert!(
        h.query_by_label_contains("statistics (§5) of the coordinates of this cage")
            .is_none()
    );
    assert!(
        h.query_by_label_contains("Once the cage is solved")
            .is_some()
    );
}
