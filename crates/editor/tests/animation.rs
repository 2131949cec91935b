//! Animation in the editor, driven as a user drives it: keys set on the timeline and
//! by posing at a time, playback, undo, handles added and removed while keys exist,
//! spatial keys blended by the control cursor, a recorded performance, and the
//! animation saved and reopened — on the built-in lizard, for every method.

use crate::support;

use egui::{Key, Modifiers};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use glam::DVec2;
use project::{HandlePose, Pose};

use editor::{EditorApp, Tool};
use support::{at, click_label, drag, editor, handles, settle};

fn pose(h: &Harness<'_, EditorApp>) -> Pose {
    Pose::of(h.state().document().expect("a document").project())
}

fn keys(h: &Harness<'_, EditorApp>) -> Vec<project::Key> {
    h.state().keys().to_vec()
}

/// Where handle `i` is drawn now (a point's position; a bar's first end).
fn handle_at(h: &Harness<'_, EditorApp>, i: usize) -> DVec2 {
    editor::posed(&handles(h)[i])[0]
}

/// Moves the time shown by `frames` frames with the keyboard.
fn step(h: &mut Harness<'_, EditorApp>, frames: i32) {
    let key = if frames < 0 { Key::Comma } else { Key::Period };
    for _ in 0..frames.abs() {
        h.key_press(key);
        h.run();
    }
}

/// Drags handle `i` by `by` image pixels.
fn drag_handle(h: &mut Harness<'_, EditorApp>, i: usize, by: DVec2) {
    let from = handle_at(h, i);
    let to = from + by;
    let (a, b) = (at(h, from.x, from.y), at(h, to.x, to.y));
    drag(h, a, b, Modifiers::NONE);
}

/// Three keys on the lizard: at rest at 0 s, handle 0 dragged at 0.5 s, handle 1 at
/// 1 s. Returns the three poses.
fn three_keys(h: &mut Harness<'_, EditorApp>) -> [Pose; 3] {
    click_label(h, "Set key");
    let rest = pose(h);
    step(h, 12);
    drag_handle(h, 0, DVec2::new(30.0, -20.0));
    let second = pose(h);
    step(h, 12);
    drag_handle(h, 1, DVec2::new(-25.0, 15.0));
    let third = pose(h);
    [rest, second, third]
}

#[test]
fn keys_set_by_posing_at_a_time_play_back_and_undo() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    let [rest, second, third] = three_keys(&mut h);
    let keys = keys(&h);
    assert_eq!(
        keys.iter().map(|k| k.time).collect::<Vec<_>>(),
        [0.0, 0.5, 1.0],
        "a key set with the button, two by posing at a time with no key"
    );
    assert_eq!(keys[1].pose, second);
    assert_eq!(keys[2].pose, third);
    assert_ne!(second, rest);

    // Back to a quarter second: the pose halfway between the first two keys.
    step(&mut h, -18);
    assert!((h.state().timeline.time - 0.25).abs() < 1e-9);
    let project = h.state().document().expect("doc").project().clone();
    assert_eq!(
        pose(&h),
        animation::pose_at(&project, 0.25).expect("a pose")
    );
    let (HandlePose::Point { translate: a, .. }, HandlePose::Point { translate: b, .. }) =
        (rest.handles[0], second.handles[0])
    else {
        panic!("point handles");
    };
    let HandlePose::Point { translate: mid, .. } = pose(&h).handles[0] else {
        panic!("a point");
    };
    for k in 0..2 {
        assert!((mid[k] - 0.5 * (a[k] + b[k])).abs() < 1e-9);
    }

    // Play: the time moves on and the pose follows the keys.
    h.key_press(Key::Space);
    h.step();
    assert!(h.state().timeline.is_playing());
    std::thread::sleep(std::time::Duration::from_millis(120));
    h.step();
    let time = h.state().timeline.time;
    assert!(time > 0.25, "playback moved the time ({time})");
    let project = h.state().document().expect("doc").project().clone();
    assert_eq!(
        pose(&h),
        animation::pose_at(&project, time).expect("a pose")
    );
    h.key_press(Key::Space);
    h.run();
    assert!(!h.state().timeline.is_playing());

    // The drag that made the last key is one undo step, key and pose together.
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    assert_eq!(self::keys(&h).len(), 2);
    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    h.run();
    assert_eq!(self::keys(&h).len(), 3);
}

#[test]
fn a_key_set_between_frames_keeps_the_pose_shown() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    three_keys(&mut h);
    step(&mut h, -18);
    // Playback paused leaves the time between two frames.
    h.key_press(Key::Space);
    h.step();
    std::thread::sleep(std::time::Duration::from_millis(130));
    h.step();
    h.key_press(Key::Space);
    h.run();
    let fps = 24.0;
    let off_frame = |t: f64| (t * fps - (t * fps).round()).abs();
    let between = h.state().timeline.time;
    assert!(
        off_frame(between) > 1e-6,
        "paused between frames ({between} s)"
    );
    let shown = pose(&h);

    // I: a key at the frame, holding the pose shown, which stays shown (it showed
    // the new key blended with the next one, the pose at the time it was).
    h.key_press(Key::I);
    h.run();
    let time = h.state().timeline.time;
    assert!(off_frame(time) < 1e-9, "the key's frame ({time} s)");
    let key = keys(&h)
        .into_iter()
        .find(|k| (k.time - time).abs() < 1e-9)
        .expect("a key at the frame");
    assert_eq!(key.pose, shown, "the key holds the pose shown");
    assert_eq!(pose(&h), shown, "and the pose shown stays");
    h.state().sanity_check().expect("the editor's invariants");
}

#[test]
fn reset_pose_with_record_armed_is_keyed_as_any_pose() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    three_keys(&mut h);
    // At the last key, with *Record* armed but no take under way (no drag).
    click_label(&mut h, "⏺ Record");
    assert!(h.state().timeline.is_recording() && !h.state().timeline.is_taking());
    let before = pose(&h);
    click_label(&mut h, "Reset pose");
    let shown = pose(&h);
    assert_ne!(shown, before, "the pose went back to rest");
    let time = h.state().timeline.time;
    let project = h.state().document().expect("doc").project().clone();
    assert_eq!(
        animation::pose_at(&project, time).expect("a pose").handles,
        shown.handles,
        "the keys show the pose shown at {time} s"
    );
    h.state().sanity_check().expect("the editor's invariants");
}

#[test]
fn handles_added_or_removed_keep_every_key() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    let poses = three_keys(&mut h);
    let count = handles(&h).len();
    // Add a point handle on the lizard's body while posed at the last key.
    let spot = handle_at(&h, 0) + DVec2::new(0.0, 60.0);
    h.state_mut().add_point(spot);
    h.run();
    assert_eq!(handles(&h).len(), count + 1, "{:?}", h.state().message);
    for key in keys(&h) {
        assert_eq!(key.pose.handles.len(), count + 1);
    }
    // In the key shown (the last) the new handle's pose is near the one the puppet
    // tool gave it; in each key it sits where that key's pose takes its rest point.
    let added = handles(&h)[count].clone();
    let (
        HandlePose::Point {
            translate: t,
            rotate: r,
            ..
        },
        project::HandleSpec::Point {
            translate: u,
            rotate: q,
            ..
        },
    ) = (keys(&h)[2].pose.handles[count], &added)
    else {
        panic!("a point handle");
    };
    assert!((t[0] - u[0]).hypot(t[1] - u[1]) < 1.0, "{t:?} vs {u:?}");
    assert!((r - q).abs() < 0.05);
    for (key, old) in keys(&h).iter().zip(&poses) {
        assert_eq!(key.pose.handles[..count], old.handles[..]);
    }
    // Removing handle 0 removes its track; the others keep theirs.
    h.state_mut().selected = Some(0);
    h.state_mut().delete_selected();
    h.run();
    for (key, old) in keys(&h).iter().zip(&poses) {
        assert_eq!(key.pose.handles.len(), count);
        assert_eq!(key.pose.handles[..count - 1], old.handles[1..]);
    }
}

#[test]
fn the_control_cursor_blends_the_pose_markers_and_a_take_records_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    h.key_press(Key::Y);
    h.run();
    assert_eq!(h.state().tool, Tool::Perform);
    // Three markers, each for a pose made with the puppet tool.
    let spots = [(60.0, 60.0), (400.0, 60.0), (230.0, 380.0)];
    let mut poses = Vec::new();
    for (i, &(x, y)) in spots.iter().enumerate() {
        if i > 0 {
            h.key_press(Key::W);
            h.run();
            drag_handle(&mut h, i - 1, DVec2::new(20.0, 25.0));
            h.key_press(Key::Y);
            h.run();
        }
        poses.push(pose(&h));
        let p = at(&h, x, y);
        h.hover_at(p);
        h.event(egui::Event::ModifiersChanged(Modifiers::COMMAND));
        h.event(egui::Event::PointerButton {
            pos: p,
            button: egui::PointerButton::Primary,
            pressed: true,
            modifiers: Modifiers::COMMAND,
        });
        h.event(egui::Event::PointerButton {
            pos: p,
            button: egui::PointerButton::Primary,
            pressed: false,
            modifiers: Modifiers::COMMAND,
        });
        h.run();
        h.event(egui::Event::ModifiersChanged(Modifiers::NONE));
        h.run();
    }
    let project = h.state().document().expect("doc").project().clone();
    let markers = &project.animation.as_ref().expect("animation").spatial_keys;
    assert_eq!(markers.len(), 3, "{:?}", h.state().message);
    for (marker, pose) in markers.iter().zip(&poses) {
        assert_eq!(&marker.pose, pose);
    }
    // Drag the cursor onto the second marker: its pose exactly.
    let (a, b) = (at(&h, 150.0, 200.0), at(&h, 400.0, 60.0));
    drag(&mut h, a, b, Modifiers::NONE);
    let project = h.state().document().expect("doc").project().clone();
    let blend = animation::SpatialBlend::of(&project).expect("a blend");
    let cursor = h.state().viewport.to_image(b);
    assert_eq!(
        pose(&h),
        blend.pose(&project, cursor.to_array()).expect("a pose")
    );
    h.hover_at(at(&h, 300.0, 250.0));
    h.run();
    h.snapshot("editor_perform");

    // Record a take: the drag becomes keys from the time shown.
    click_label(&mut h, "⏺ Record");
    let (a, b) = (at(&h, 100.0, 90.0), at(&h, 230.0, 330.0));
    h.hover_at(a);
    h.run();
    h.event(egui::Event::PointerButton {
        pos: a,
        button: egui::PointerButton::Primary,
        pressed: true,
        modifiers: Modifiers::NONE,
    });
    h.step();
    for i in 1..=10 {
        h.hover_at(a + (b - a) * (i as f32 / 10.0));
        h.step();
        std::thread::sleep(std::time::Duration::from_millis(30));
    }
    h.event(egui::Event::PointerButton {
        pos: b,
        button: egui::PointerButton::Primary,
        pressed: false,
        modifiers: Modifiers::NONE,
    });
    h.run();
    let keys = keys(&h);
    assert!(
        keys.len() >= 2,
        "a take makes keys ({:?})",
        h.state().message
    );
    assert_eq!(keys[0].time, 0.0);
    assert!(!h.state().timeline.is_recording());
    // The take is one undo step.
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    assert!(self::keys(&h).is_empty());
}

#[test]
fn an_animation_saved_reopens_the_same_and_the_timeline_looks_right() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    // The built-in picture, as a file the saved project can name.
    let lizard = support::write_lizard(dir.path());
    h.state_mut().document_mut().expect("doc").image_path = Some(lizard);
    three_keys(&mut h);
    let saved = h.state().document().expect("doc").project().clone();
    h.key_press_modifiers(Modifiers::COMMAND, Key::S);
    h.run();
    let path = dir.path().join("project.json");
    let reopened = pipeline::load_project(&path).expect("the saved project");
    assert_eq!(reopened.animation, saved.animation);
    h.state_mut().open(&path);
    settle(&mut h);
    assert_eq!(
        h.state().document().expect("doc").project().animation,
        saved.animation
    );
    assert!(
        !h.state().message.as_ref().is_some_and(|m| m.is_error),
        "{:?}",
        h.state().message
    );
    // Between the second and third keys, with their pictures ghosted behind.
    h.state_mut().timeline.onion = true;
    step(&mut h, 15);
    let _ = h.get_by_label("Timeline");
    h.snapshot("editor_timeline");
}

#[test]
fn every_handle_method_shows_its_own_answer_between_keys() {
    let dir = tempfile::tempdir().expect("temp dir");
    for label in ["C² weights", "ARAP", "MLS"] {
        let mut h = support::editor_with(
            Box::new(support::Scripted {
                dir: dir.path().to_path_buf(),
            }),
            false,
        );
        click_label(&mut h, label);
        settle(&mut h);
        click_label(&mut h, "Set key");
        step(&mut h, 12);
        drag_handle(&mut h, 0, DVec2::new(40.0, -30.0));
        step(&mut h, -6);
        let doc = h.state().document().expect("doc");
        let project = doc.project().clone();
        assert_eq!(keys(&h).len(), 2, "{label}");
        let between = animation::pose_at(&project, 0.25).expect("a pose");
        assert!(
            Pose::of(&project).same_controls(&between),
            "{label}: {:?} {between:?}",
            Pose::of(&project)
        );
        // What the view draws between the keys is the method's answer for the rig
        // posed at that time, set up afresh.
        let shown = doc.deformer().deformed();
        let fresh = set_up_afresh(doc, &animation::posed_at(&project, 0.25));
        assert_eq!(shown, fresh, "{label}");
        // Played (live frames, as a drag's) and paused: what shows is again the
        // method's answer set up afresh for the time shown.
        h.key_press(Key::Space);
        h.step();
        std::thread::sleep(std::time::Duration::from_millis(80));
        h.step();
        assert!(h.state().timeline.is_playing(), "{label}");
        h.key_press(Key::Space);
        h.run();
        let time = h.state().timeline.time;
        let doc = h.state().document().expect("doc");
        let project = doc.project().clone();
        assert!(
            Pose::of(&project).same_controls(&animation::pose_at(&project, time).expect("a pose")),
            "{label}"
        );
        let fresh = set_up_afresh(doc, &animation::posed_at(&project, time));
        assert_eq!(doc.deformer().deformed(), fresh, "{label} after playback");
    }
}

/// The document's handle method set up afresh on its mesh for `project` (C²: its rig,
/// following `project`).
fn set_up_afresh(doc: &editor::Document, project: &project::Project) -> Vec<DVec2> {
    match pipeline::on_mesh(project, doc.mesh(), Some(&doc.image)).expect("the method") {
        Some(deformer) => deformer.deformed(),
        None => {
            let mut rig = doc.rig().expect("a C² rig").clone();
            pipeline::Deformer::follow(&mut rig, project).expect("C² follows");
            pipeline::Deformer::deformed(&rig)
        }
    }
}

#[test]
fn a_cage_is_keyed_and_played_under_lbc() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = support::editor_with(
        Box::new(support::Scripted {
            dir: dir.path().to_path_buf(),
        }),
        false,
    );
    h.state_mut().cage.inside_vertices = 300;
    h.key_press(Key::K);
    h.run();
    let cage = support::BODY;
    for p in cage.iter().chain(&cage[..1]) {
        let pos = at(&h, p[0], p[1]);
        support::click_at(&mut h, pos);
    }
    h.key_press(Key::Enter);
    h.step();
    settle(&mut h);
    click_label(&mut h, "Set key");
    step(&mut h, 12);
    let (a, b) = (at(&h, 390.0, 190.0), at(&h, 420.0, 150.0));
    drag(&mut h, a, b, Modifiers::NONE);
    assert_eq!(keys(&h).len(), 2, "{:?}", h.state().message);
    let posed = keys(&h)[1].pose.cage.clone().expect("a cage pose");
    assert!((posed[1][0] - 420.0).abs() < 2.0 && (posed[1][1] - 150.0).abs() < 2.0);
    step(&mut h, -6);
    let doc = h.state().document().expect("doc");
    let halfway = doc.cage().and_then(|c| c.pose.clone()).expect("posed");
    // Where the click put the vertex at rest (within a pixel of 390, 190).
    let rest = doc.cage().expect("a cage").rest[1];
    assert!((rest[0] - 390.0).abs() < 1.0 && (rest[1] - 190.0).abs() < 1.0);
    assert!((halfway[1][0] - 0.5 * (rest[0] + posed[1][0])).abs() < 1e-9);
    assert!((halfway[1][1] - 0.5 * (rest[1] + posed[1][1])).abs() < 1e-9);
    // Perform works under LBC too: a marker holds the cage's pose.
    h.key_press(Key::Y);
    h.run();
    assert_eq!(h.state().tool, Tool::Perform);
}

#[test]
fn an_exported_animation_is_what_render_draws_for_each_frame() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = editor(dir.path());
    // A small picture and mesh, so that drawing the frames is quick.
    let mut settings = h.state().document().expect("doc").settings();
    settings.density = 2000;
    assert!(h.state_mut().edit(editor::Edit::Settings(settings)));
    settle(&mut h);
    three_keys(&mut h);
    h.get_by_label("File").click();
    h.run();
    click_label(&mut h, "Export animation…");
    h.snapshot("editor_export_animation");
    let export = h.state().animation_export.expect("the export window");
    assert_eq!((export.from, export.to, export.fps), (0.0, 1.0, 24.0));
    // Every third frame, to keep the test short.
    h.state_mut().animation_export = Some(editor::AnimationExport { fps: 8.0, ..export });
    click_label(&mut h, "Export…");
    assert!(h.state().is_busy(), "{:?}", h.state().message);
    settle(&mut h);
    assert!(
        !h.state().message.as_ref().is_some_and(|m| m.is_error),
        "{:?}",
        h.state().message
    );
    let file = std::fs::File::open(dir.path().join("animation.png")).expect("the APNG");
    let decoder =
        image::codecs::png::PngDecoder::new(std::io::BufReader::new(file)).expect("a PNG");
    use image::AnimationDecoder as _;
    let frames: Vec<image::RgbaImage> = decoder
        .apng()
        .expect("an APNG")
        .into_frames()
        .map(|f| f.expect("a frame").into_buffer())
        .collect();
    assert_eq!(frames.len(), 9);
    let project = h.state().document().expect("doc").project_for_saving(None);
    let image = h.state().document().expect("doc").image.clone();
    for (i, frame) in frames.iter().enumerate().step_by(4) {
        let posed = animation::posed_at(&project, i as f64 / 8.0);
        let warper = pipeline::prepare_warper(&image, &posed, None, &()).expect("set up");
        let rendered = pipeline::warp(&image, &warper).expect("drawn");
        assert!(*frame == rendered, "frame {i} differs from the render");
    }
}

#[test]
fn the_timeline_in_edge_states() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = support::editor_with(
        Box::new(support::Scripted {
            dir: dir.path().to_path_buf(),
        }),
        false,
    );
    // Nothing to play, nothing to export, no key to delete: each says so.
    h.key_press(Key::Space);
    h.run();
    assert!(!h.state().timeline.is_playing());
    h.state_mut().ask_animation_export();
    assert!(h.state().animation_export.is_none());
    h.state_mut().delete_key();
    assert!(keys(&h).is_empty());
    // No handles: keys hold empty poses, and play.
    click_label(&mut h, "Clear all handles");
    assert!(handles(&h).is_empty());
    h.key_press(Key::I);
    h.run();
    step(&mut h, 6);
    h.key_press(Key::I);
    h.run();
    assert_eq!(keys(&h).len(), 2);
    assert!(keys(&h).iter().all(|k| k.pose.handles.is_empty()));
    h.key_press(Key::Space);
    h.step();
    assert!(h.state().timeline.is_playing());
    h.key_press(Key::Space);
    h.step();
    // One handle added while keys exist: every key gets it, at rest here (nothing is
    // posed).
    h.state_mut().add_point(DVec2::new(300.0, 300.0));
    h.run();
    assert_eq!(handles(&h).len(), 1, "{:?}", h.state().message);
    assert!(keys(&h).iter().all(|k| k.pose.handles.len() == 1));
    // A job running: keys wait, with a message, and nothing changes.
    let mut s = h.state().document().expect("doc").settings();
    s.density = 3000;
    assert!(h.state_mut().edit(editor::Edit::Settings(s)));
    assert!(h.state().is_busy());
    let before = keys(&h);
    h.state_mut().set_key();
    assert_eq!(keys(&h), before);
    settle(&mut h);
    // Clear the handles again: the tracks go, the keys stay.
    click_label(&mut h, "Clear all handles");
    assert!(keys(&h).iter().all(|k| k.pose.handles.is_empty()));
    assert_eq!(keys(&h).len(), 2);
    // Record armed and disarmed without a drag leaves the keys alone.
    click_label(&mut h, "⏺ Record");
    assert!(h.state().timeline.is_recording());
    click_label(&mut h, "⏺ Record");
    assert!(!h.state().timeline.is_recording());
    assert_eq!(keys(&h).len(), 2);
    h.state().sanity_check().expect("sane");
}

#[test]
fn a_cancelled_animation_export_writes_nothing() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = support::editor_with(
        Box::new(support::Scripted {
            dir: dir.path().to_path_buf(),
        }),
        false,
    );
    three_keys(&mut h);
    let target = dir.path().join("animation.png");
    std::fs::write(&target, b"an older file").expect("write");
    h.state_mut().ask_animation_export();
    h.state_mut().export_animation_to(target.clone());
    assert!(h.state().is_busy());
    h.state_mut().cancel_job();
    // The worker stops at its next frame; give it time to finish.
    std::thread::sleep(std::time::Duration::from_millis(1500));
    assert_eq!(std::fs::read(&target).expect("read"), b"an older file");
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .expect("list")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name())
        .collect();
    assert_eq!(leftovers.len(), 1, "{leftovers:?}");
}

/// Records a take of handle 0 dragged along `path` (image pixels at `t` seconds, for
/// one second; the hand's pointer events come at 240 a second) while the editor draws
/// `fps` frames a second, and returns the project with its keys.
fn record_path(fps: f64, path: impl Fn(f64) -> DVec2) -> project::Project {
    let mut h = support::editor_with(Box::new(support::NoDesktop), false);
    click_label(&mut h, "⏺ Record");
    let screen = |h: &Harness<'_, EditorApp>, t: f64| {
        let p = path(t);
        at(h, p.x, p.y)
    };
    h.input_mut().time = Some(0.0);
    h.hover_at(screen(&h, 0.0));
    h.input_mut().time = Some(0.0);
    let first = screen(&h, 0.0);
    h.input_mut().events.push(egui::Event::PointerButton {
        pos: first,
        button: egui::PointerButton::Primary,
        pressed: true,
        modifiers: Modifiers::NONE,
    });
    h.step();
    let events_per_frame = (240.0 / fps).round() as usize;
    let frames = fps.round() as usize;
    for frame in 1..=frames {
        for k in 1..=events_per_frame {
            let t = ((frame - 1) * events_per_frame + k) as f64 / 240.0;
            let p = screen(&h, t);
            h.input_mut().events.push(egui::Event::PointerMoved(p));
        }
        h.input_mut().time = Some(frame as f64 / fps);
        h.step();
    }
    h.input_mut().time = Some(1.0 + 1.0 / fps);
    let last = screen(&h, 1.0);
    h.input_mut().events.push(egui::Event::PointerButton {
        pos: last,
        button: egui::PointerButton::Primary,
        pressed: false,
        modifiers: Modifiers::NONE,
    });
    h.step();
    h.run();
    h.state().document().expect("doc").project().clone()
}

#[test]
fn a_take_plays_as_performed_however_slowly_the_editor_draws() {
    let start =
        editor::posed(&handles(&support::editor_with(Box::new(support::NoDesktop), false))[0])[0];
    // A curved stroke at an uneven speed.
    let path =
        move |t: f64| start + DVec2::new(120.0 * t * t, 50.0 * (std::f64::consts::PI * t).sin());
    let slow = record_path(5.0, path);
    let fast = record_path(60.0, path);
    let keys = |p: &project::Project| p.animation.as_ref().map_or(0, |a| a.keys.len());
    assert!(
        keys(&slow) >= 3 && keys(&fast) >= 3,
        "{} / {}",
        keys(&slow),
        keys(&fast)
    );
    // Replayed frame by frame, both takes follow the hand: the same place at the same
    // time within the tolerance (0.5 px each) and the hand's own sampling.
    let (mut worst, mut off_hand): (f64, f64) = (0.0, 0.0);
    for i in 0..=48 {
        let t = f64::from(i) / 48.0 * 0.95;
        let (a, b) = (animation::posed_at(&slow, t), animation::posed_at(&fast, t));
        let (a, b) = (
            editor::posed(&a.handles[0])[0],
            editor::posed(&b.handles[0])[0],
        );
        worst = worst.max(a.distance(b));
        // Where the hand was then (the handle follows the pointer from where it was
        // pressed, the picture's pixels a little off the screen's).
        off_hand = off_hand.max(a.distance(path(t)));
    }
    eprintln!("replays differ by {worst:.2} px, slow one off the hand by {off_hand:.2} px");
    assert!(worst < 1.5, "the replays differ by up to {worst:.2} px");
    assert!(
        off_hand < 1.5,
        "the slow replay strays {off_hand:.2} px from the hand"
    );
}

#[test]
fn every_action_replaces_the_message_and_undo_names_the_take() {
    let mut h = support::editor_with(Box::new(support::NoDesktop), false);
    let text = |h: &Harness<'_, EditorApp>| {
        h.state()
            .message
            .as_ref()
            .map(|m| (m.text.clone(), m.is_error))
    };
    // A refusal in red, then a drag that works: the red line goes.
    click_label(&mut h, "Add bar");
    let p = at(&h, 20.0, 20.0);
    drag(&mut h, p, p + egui::Vec2::new(40.0, 0.0), Modifiers::NONE);
    assert!(text(&h).is_some_and(|(_, red)| red), "{:?}", text(&h));
    click_label(&mut h, "Puppet");
    drag_handle(&mut h, 0, DVec2::new(10.0, 5.0));
    assert!(!text(&h).is_some_and(|(_, red)| red), "{:?}", text(&h));
    // Keys: the automatic ones say so too, each in turn.
    click_label(&mut h, "Set key");
    assert!(
        text(&h).is_some_and(|(t, _)| t.contains("(1 key)")),
        "{:?}",
        text(&h)
    );
    step(&mut h, 6);
    drag_handle(&mut h, 1, DVec2::new(8.0, 0.0));
    assert!(
        text(&h).is_some_and(|(t, _)| t == "key set at 0.25 s (2 keys)"),
        "{:?}",
        text(&h)
    );
    // A recorded take is one step, and undo and redo say which.
    click_label(&mut h, "⏺ Record");
    let from = handle_at(&h, 2);
    let (a, b) = (at(&h, from.x, from.y), at(&h, from.x + 30.0, from.y + 20.0));
    // Stepped, not run: a take keeps the editor drawing.
    let press = |h: &mut Harness<'_, EditorApp>, pos, pressed| {
        h.event(egui::Event::PointerButton {
            pos,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: Modifiers::NONE,
        });
        h.step();
    };
    h.hover_at(a);
    h.step();
    press(&mut h, a, true);
    for i in 1..=8 {
        h.hover_at(a + (b - a) * (i as f32 / 8.0));
        h.step();
    }
    press(&mut h, b, false);
    h.run();
    let count = keys(&h).len();
    assert!(count >= 2, "{:?}", text(&h));
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    let (undone, _) = text(&h).expect("a message");
    assert!(undone.starts_with("undone: a recorded take: "), "{undone}");
    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    h.run();
    let (redone, _) = text(&h).expect("a message");
    assert_eq!(redone, undone.replace("undone", "redone"));
}
