//! Layered artwork warped as parts (`pipeline::warp_parts`): a handle binds the layers
//! under it, a part moves with its own handles only, a joint binds both parts, and at
//! rest the parts composite to the layers flattened.

use image::{Rgba, RgbaImage};
use pipeline::{Artwork, Layer, warp_parts};
use project::{HandleSpec, Project};
use render::Picture;

/// A layer of `w × h` opaque pixels of `colour` at (`x`, `y`).
fn block(name: &str, x: i32, y: i32, w: u32, h: u32, colour: [u8; 3]) -> Layer {
    let [r, g, b] = colour;
    Layer {
        name: name.into(),
        x,
        y,
        opacity: 1.0,
        visible: true,
        pixels: Picture::Rgba8(RgbaImage::from_pixel(w, h, Rgba([r, g, b, 255]))),
    }
}

/// Two parts side by side on a 200 × 120 canvas: `left` (x 10..90) and `right` (x 80..190),
/// overlapping on x 80..90, the right one on top.
fn two_parts() -> Artwork {
    Artwork {
        width: 200,
        height: 120,
        layers: vec![
            block("left", 10, 20, 80, 80, [200, 40, 40]),
            block("right", 80, 20, 110, 80, [40, 40, 200]),
        ],
        notes: Vec::new(),
    }
}

fn rig(handles: &str) -> Project {
    Project::from_json(&format!(
        r#"{{"version": 1, "density": 1200, "handles": [{handles}]}}"#
    ))
    .expect("a rig")
}

/// A warped layer on the 200 × 120 canvas (the warped parts come cut to their own
/// rectangles, with their offsets).
fn rgba8(layer: &Layer) -> RgbaImage {
    let Picture::Rgba8(pixels) = &layer.pixels else {
        panic!("8-bit test layers");
    };
    let mut canvas = RgbaImage::new(200, 120);
    image::imageops::replace(&mut canvas, pixels, i64::from(layer.x), i64::from(layer.y));
    canvas
}

/// The largest difference of one channel of one pixel between two pictures.
fn worst_level(a: &RgbaImage, b: &RgbaImage) -> u8 {
    a.pixels()
        .zip(b.pixels())
        .flat_map(|(p, q)| (0..4).map(move |c| p[c].abs_diff(q[c])))
        .max()
        .unwrap_or(0)
}

#[test]
fn a_handle_binds_the_layers_under_it_and_a_joint_binds_both() {
    let project = rig(r#"{"type": "point", "rest": [30, 60]},
           {"type": "point", "rest": [85, 60]},
           {"type": "point", "rest": [170, 60]},
           {"type": "bar", "rest": [[120, 40], [160, 80]]}"#);
    let parts = warp_parts(&two_parts(), &project, None, &()).expect("warps");
    assert_eq!(parts.bindings, vec![vec![0, 1], vec![1, 2, 3]]);
}

#[test]
fn moving_one_parts_handle_leaves_the_other_part_where_it_was() {
    for method in ["c2", "arap", "mls"] {
        let project = rig(r#"{"type": "point", "rest": [30, 40]},
               {"type": "point", "rest": [30, 80], "translate": [-8, 25], "rotate": 0.3},
               {"type": "point", "rest": [120, 60]},
               {"type": "point", "rest": [170, 60]}"#);
        let mut project = project;
        project.method = method.parse().expect("a method");
        let artwork = two_parts();
        let parts = warp_parts(&artwork, &project, None, &()).expect("warps");
        // The right part: its own handles did not move, so it is the layer as it was,
        // pixel for pixel, at its place on the canvas.
        let right = rgba8(&parts.warped.layers[1]);
        for (x, y, p) in right.enumerate_pixels() {
            let inside = (80..190).contains(&x) && (20..100).contains(&y);
            let expected = if inside { [40, 40, 200, 255] } else { [0; 4] };
            assert_eq!(p.0, expected, "{method}: the right part at ({x}, {y})");
        }
        // The left part moved: its bottom-left corner went down with its handle.
        let left = rgba8(&parts.warped.layers[0]);
        let below = (0..200).any(|x| left.get_pixel(x, 110)[3] > 0);
        assert!(below, "{method}: the left part's moved handle took it down");
    }
}

#[test]
fn at_rest_the_parts_composite_to_the_layers_flattened() {
    let project = rig(r#"{"type": "point", "rest": [30, 60]},
           {"type": "point", "rest": [85, 60]},
           {"type": "point", "rest": [170, 60]}"#);
    let artwork = two_parts();
    let parts = warp_parts(&artwork, &project, None, &()).expect("warps");
    let (a, b) = (
        parts.warped.flatten().into_rgba8(),
        artwork.flatten().into_rgba8(),
    );
    let worst = worst_level(&a, &b);
    assert!(
        worst <= 1,
        "differs from the layers flattened by {worst} levels"
    );
    // Drawn as one mesh (their overlap at rest in the layers' order), the same.
    let joined = parts.composite.clone().into_rgba8();
    let worst = worst_level(&joined, &b);
    assert!(worst <= 1, "the composite differs by {worst} levels");
    // Each part comes cut to the rectangle its mesh can touch, not the whole canvas.
    let right = &parts.warped.layers[1];
    let (w, h) = right.dimensions();
    assert!(
        right.x >= 76 && right.y >= 16 && w <= 118 && h <= 88,
        "{:?}",
        (right.x, right.y, w, h)
    );
}

#[test]
fn a_handle_on_no_part_or_a_cage_is_refused() {
    let project = rig(r#"{"type": "point", "rest": [195, 5]}"#);
    let error = warp_parts(&two_parts(), &project, None, &())
        .err()
        .expect("refused")
        .to_string();
    assert!(
        error.contains("handle 1 lies on no visible layer"),
        "{error}"
    );
}

#[test]
fn a_cage_moves_every_part_inside_it() {
    // A cage around the right part (and the left part's overlapping end), moved down
    // by 6 px: LBC reproduces a translation exactly.
    let cage = Project::from_json(
        r#"{"version": 1, "method": "lbc", "density": 1200, "handles": [],
            "cage": {"rest": [[75, 10], [199, 10], [199, 110], [75, 110]],
                     "pose": [[75, 16], [199, 16], [199, 116], [75, 116]]}}"#,
    )
    .expect("a cage rig");
    let parts = warp_parts(&two_parts(), &cage, None, &()).expect("caged parts");
    let right = rgba8(&parts.warped.layers[1]);
    for (x, y, p) in right.enumerate_pixels() {
        let inside = (80..190).contains(&x) && (26..106).contains(&y);
        let expected = if inside { [40, 40, 200, 255] } else { [0; 4] };
        assert_eq!(
            p.0, expected,
            "the right part moved down 6 px, at ({x}, {y})"
        );
    }
    // The left part outside the cage stays where it was.
    let left = rgba8(&parts.warped.layers[0]);
    assert_eq!(left.get_pixel(30, 20).0, [200, 40, 40, 255]);
    assert_eq!(left.get_pixel(30, 19).0, [0; 4]);
    assert_eq!(left.get_pixel(30, 99).0, [200, 40, 40, 255]);
}

#[test]
fn a_hidden_layer_is_kept_as_it_was() {
    let mut artwork = two_parts();
    artwork.layers[0].visible = false;
    let project = rig(r#"{"type": "point", "rest": [170, 60], "translate": [5, 0]}"#);
    let parts = warp_parts(&artwork, &project, None, &()).expect("warps");
    let hidden = &parts.warped.layers[0];
    assert!(!hidden.visible);
    assert_eq!((hidden.x, hidden.y), (10, 20));
    assert_eq!(hidden.pixels, artwork.layers[0].pixels);
    assert!(parts.bindings[0].is_empty());
}

#[test]
fn a_part_no_handle_binds_follows_the_part_beneath_it() {
    // A patch on the left part, and a lone dot over nothing.
    let mut artwork = two_parts();
    artwork
        .layers
        .push(block("patch", 30, 40, 20, 16, [20, 160, 20]));
    artwork.layers.push(block("dot", 194, 2, 4, 4, [0, 0, 0]));
    let project = rig(
        r#"{"type": "point", "rest": [20, 30], "translate": [10, 6]},
           {"type": "point", "rest": [70, 90], "translate": [10, 6]},
           {"type": "point", "rest": [170, 60]}"#,
    );
    let parts = warp_parts(&artwork, &project, None, &()).expect("warps");
    assert_eq!(parts.followed, vec![None, None, Some(0), None]);
    // The left part moved by (10, 6) as a whole, and the patch with it.
    let patch = rgba8(&parts.warped.layers[2]);
    for (x, y, p) in patch.enumerate_pixels() {
        let inside = (40..60).contains(&x) && (46..62).contains(&y);
        let expected = if inside { [20, 160, 20, 255] } else { [0; 4] };
        let worst = (0..4)
            .map(|c| p[c].abs_diff(expected[c]))
            .max()
            .unwrap_or(0);
        assert!(worst <= 1, "the patch at ({x}, {y}): {:?}", p.0);
    }
    // The dot overlaps no part: it stays.
    let dot = rgba8(&parts.warped.layers[3]);
    assert_eq!(dot.get_pixel(195, 3).0, [0, 0, 0, 255]);
    assert_eq!(dot.get_pixel(190, 3).0, [0; 4]);
}

#[test]
fn virtual_handles_of_the_whole_picture_do_not_reach_the_parts() {
    // A project saved from the flattened picture keeps its virtual handles; one lies
    // on the left part only, for the right part's handle.
    let mut project = rig(r#"{"type": "point", "rest": [30, 60]},
           {"type": "point", "rest": [170, 60], "translate": [4, 0]}"#);
    project.virtual_handles = vec![[20.0, 30.0]];
    project.virtual_placed_for = vec![Some(1)];
    let parts = warp_parts(&two_parts(), &project, None, &()).expect("warps");
    assert_eq!(parts.bindings, vec![vec![0], vec![1]]);
}

/// An arm (the bottom layer, green) beside a body (blue) on the 200 × 120 canvas.
fn arm_and_body() -> Artwork {
    Artwork {
        width: 200,
        height: 120,
        layers: vec![
            block("arm", 10, 50, 40, 20, [40, 200, 40]),
            block("body", 80, 20, 110, 80, [40, 40, 200]),
        ],
        notes: Vec::new(),
    }
}

#[test]
fn parts_are_composited_as_one_mesh_with_overlaps_ordered_between_them() {
    // At rest: the layers flattened.
    let still = rig(r#"{"type": "point", "rest": [20, 60]},
           {"type": "point", "rest": [170, 60]}"#);
    let artwork = arm_and_body();
    let parts = warp_parts(&artwork, &still, None, &()).expect("warps");
    let (a, b) = (
        parts.composite.clone().into_rgba8(),
        artwork.flatten().into_rgba8(),
    );
    let worst = worst_level(&a, &b);
    assert!(
        worst <= 1,
        "differs from the layers flattened by {worst} levels"
    );
    assert!(parts.overlaps.is_empty());
    // The arm laid over the body: the body's layer is above, so the new overlap puts
    // the body in front.
    let moved = rig(
        r#"{"type": "point", "rest": [20, 60], "translate": [110, 0]},
           {"type": "point", "rest": [170, 60]}"#,
    );
    let parts = warp_parts(&artwork, &moved, None, &()).expect("warps");
    let at = |p: &Picture| p.to_rgba8().get_pixel(135, 60).0;
    assert_eq!(
        at(&parts.composite),
        [40, 40, 200, 255],
        "the body in front"
    );
    assert_eq!(parts.overlaps.len(), 1);
    let order = &parts.overlaps[0];
    assert_eq!((order.front.part, order.back.part), (Some(1), Some(0)));
    // Kept the other way round (the arm swung in over the body earlier), it stays so.
    let flipped = Project {
        overlaps: vec![project::OverlapOrder {
            front: order.back,
            back: order.front,
        }],
        ..moved.clone()
    };
    let json = flipped.to_json();
    let reopened = Project::from_json(&json).expect("reads");
    let parts = warp_parts(&artwork, &reopened, None, &()).expect("warps");
    assert_eq!(at(&parts.composite), [40, 200, 40, 255], "the arm in front");
    // Without automatic depth, the layers' order alone.
    let fixed = Project {
        auto_depth: false,
        ..reopened
    };
    let parts = warp_parts(&artwork, &fixed, None, &()).expect("warps");
    assert_eq!(at(&parts.composite), [40, 40, 200, 255]);
}

#[test]
fn the_rig_files_parts_reorder_hide_and_bind() {
    let handles = r#"{"type": "point", "rest": [30, 60]},
           {"type": "point", "rest": [85, 60], "translate": [0, 30]},
           {"type": "point", "rest": [170, 60]}"#;
    let artwork = two_parts();
    let at = |p: &Picture, x, y| p.clone().into_rgba8().get_pixel(x, y).0;
    // As the file has it, the right part is drawn over the left where they overlap.
    let mut project = rig(handles.replace(r#", "translate": [0, 30]"#, "").as_str());
    let plain = warp_parts(&artwork, &project, None, &()).expect("warps");
    assert_eq!(at(&plain.composite, 85, 60), [40, 40, 200, 255]);
    // Sent backward: the left part is in front, and the layers come in that order.
    project.parts = Some(project::PartsSpec {
        order: vec![1, 0],
        ..Default::default()
    });
    let reordered = warp_parts(&artwork, &project, None, &()).expect("warps");
    assert_eq!(at(&reordered.composite, 85, 60), [200, 40, 40, 255]);
    let names: Vec<&str> = (reordered.warped.layers.iter())
        .map(|l| l.name.as_str())
        .collect();
    assert_eq!(names, ["right", "left"]);
    // Hidden: the right part is not drawn, and its layer is kept hidden as it was.
    project.parts = Some(project::PartsSpec {
        hidden: vec![1],
        ..Default::default()
    });
    project.handles.pop();
    let hidden = warp_parts(&artwork, &project, None, &()).expect("warps");
    assert_eq!(at(&hidden.composite, 150, 60), [0; 4]);
    assert_eq!(at(&hidden.composite, 85, 60), [200, 40, 40, 255]);
    let kept = &hidden.warped.layers[1];
    assert!(!kept.visible && kept.x == 80 && kept.dimensions() == (110, 80));
    // The middle handle (over both) moved down: a joint pulls both parts; bound to
    // the left part alone, the right part stays where it was, pixel for pixel.
    let mut project = rig(handles);
    let joint = warp_parts(&artwork, &project, None, &()).expect("warps");
    assert_eq!(joint.bindings, vec![vec![0, 1], vec![1, 2]]);
    let moved = rgba8(&joint.warped.layers[1]);
    assert!(
        (0..200).any(|x| moved.get_pixel(x, 105)[3] > 0),
        "the joint took the right part down"
    );
    project.parts = Some(project::PartsSpec {
        bindings: vec![project::Binding {
            handle: 1,
            parts: vec![0],
        }],
        ..Default::default()
    });
    let bound = warp_parts(&artwork, &project, None, &()).expect("warps");
    assert_eq!(bound.bindings, vec![vec![0, 1], vec![2]]);
    let right = rgba8(&bound.warped.layers[1]);
    for (x, y, p) in right.enumerate_pixels() {
        let inside = (80..190).contains(&x) && (20..100).contains(&y);
        let expected = if inside { [40, 40, 200, 255] } else { [0; 4] };
        assert_eq!(p.0, expected, "the right part at ({x}, {y})");
    }
    // An order for other layers than the picture has is refused, naming it.
    project.parts = Some(project::PartsSpec {
        order: vec![0, 1, 2],
        ..Default::default()
    });
    let error = warp_parts(&artwork, &project, None, &())
        .err()
        .expect("refused")
        .to_string();
    assert!(error.contains("parts.order lists 3 layers"), "{error}");
}

#[test]
fn the_parts_deformer_poses_the_joined_mesh_and_knows_a_new_setup() {
    use pipeline::{Deformer, Follow, PartsDeformer, WeightsListing};
    let handles = r#"{"type": "point", "rest": [30, 60]},
           {"type": "point", "rest": [85, 60]},
           {"type": "point", "rest": [170, 60]}"#;
    let artwork = two_parts();
    let mut project = rig(handles);
    project.parts = Some(project::PartsSpec::default());
    let mut parts = PartsDeformer::new(&artwork, &project, None, &()).expect("set up");
    // At rest: the joined mesh is the parts' meshes, bottom first, where they lie.
    let set = pipeline::set_up_parts(&artwork, &project, None, &()).expect("parts");
    let joined: Vec<_> = set
        .meshes
        .iter()
        .flatten()
        .flat_map(|m| m.rest.clone())
        .collect();
    assert!(parts.rest() == joined.as_slice(), "the joined rest mesh");
    let far = |a: &[glam::DVec2], b: &[glam::DVec2]| {
        assert_eq!(a.len(), b.len());
        (a.iter().zip(b))
            .map(|(p, q)| p.distance(*q))
            .fold(0.0, f64::max)
    };
    assert!(
        far(&parts.deformed(), &joined) < 1e-6,
        "at rest where it lies"
    );
    assert_eq!(parts.rest().len(), parts.composer().uv().len());
    // A pose moves the left part's vertices near its handle, the right part's stay.
    let HandleSpec::Point { translate, .. } = &mut project.handles[0] else {
        unreachable!()
    };
    *translate = [0.0, 20.0];
    assert_eq!(parts.follow(&project).expect("posed"), Follow::Followed);
    let left = set.meshes[0].as_ref().expect("left").rest.len();
    let moved = parts.deformed();
    assert!(
        moved[..left]
            .iter()
            .zip(&joined)
            .any(|(a, b)| a.distance(*b) > 5.0)
    );
    let right_still = moved[left..].iter().zip(&joined[left..]);
    let worst = right_still.map(|(a, b)| a.distance(*b)).fold(0.0, f64::max);
    assert!(worst < 1e-9, "the right part moved {worst} px");
    // Its posed positions are what render --parts draws: the same as the parts posed.
    let posed = pipeline::set_up_parts(&artwork, &project, None, &()).expect("parts");
    let expected: Vec<_> = posed
        .meshes
        .iter()
        .flatten()
        .flat_map(|m| m.deformed.clone())
        .collect();
    assert!(moved == expected, "the parts posed");
    // A handle moved at rest, another order or another method: a new setup.
    for change in 0..3 {
        let mut other = project.clone();
        match change {
            0 => {
                let HandleSpec::Point { rest, .. } = &mut other.handles[2] else {
                    unreachable!()
                };
                rest[0] += 3.0;
            }
            1 => {
                other.parts = Some(project::PartsSpec {
                    order: vec![1, 0],
                    ..Default::default()
                })
            }
            _ => other.method = project::Method::Mls,
        }
        assert_eq!(
            parts.follow(&other).expect("asks"),
            Follow::NeedsSetup,
            "{change}"
        );
    }
    assert_eq!(
        parts.deformed(),
        expected,
        "a new setup asked for moves nothing"
    );
    // Weights are listed by part, in the draw order, with the handles that bind each.
    let listing = WeightsListing {
        file_vertices: 0,
        positions: true,
    };
    let weights = parts.weights(listing).expect("C² weights");
    let listed = weights["parts"].as_array().expect("parts");
    assert_eq!(listed.len(), 2);
    assert_eq!(listed[0]["name"], "left");
    assert_eq!(listed[0]["handles"], serde_json::json!([0, 1]));
    assert_eq!(listed[1]["handles"], serde_json::json!([1, 2]));
    let report = parts.bench(&project, 3).expect("timed");
    assert_eq!(report["parts"], 2);
    assert_eq!(report["poses"], 3);
    assert_eq!(
        parts.deformed(),
        expected,
        "the bench leaves the pose as it was"
    );
}

#[test]
fn rigidity_painted_on_a_part_stiffens_that_part_alone() {
    // Under ARAP, each part pulled by its own handle, a joint between them; a stroke
    // over the joint, where both parts lie.
    let mut project = rig(r#"{"type": "point", "rest": [20, 60]},
           {"type": "point", "rest": [85, 60]},
           {"type": "point", "rest": [60, 90], "translate": [-10, 20]},
           {"type": "point", "rest": [180, 60]},
           {"type": "point", "rest": [120, 90], "translate": [12, 18]}"#);
    project.method = project::Method::Arap;
    let artwork = two_parts();
    let drawn = |project: &Project| {
        let parts = warp_parts(&artwork, project, None, &()).expect("warps");
        [0, 1].map(|k| rgba8(&parts.warped.layers[k]))
    };
    let plain = drawn(&project);
    let stroke = |part| project::RigidityStroke {
        stroke: vec![[70.0, 50.0], [100.0, 70.0]],
        radius: 18.0,
        weight: 10_000.0,
        part,
    };
    // Painted on the left part: the right one is drawn as without it.
    project.rigidity = vec![stroke(Some(0))];
    let [left, right] = drawn(&project);
    assert!(left != plain[0], "the left part is stiffer");
    assert!(right == plain[1], "the right part is not painted");
    // On every part it reaches: both.
    project.rigidity = vec![stroke(None)];
    let [left, right] = drawn(&project);
    assert!(left != plain[0] && right != plain[1]);
    // It round-trips through the rig file.
    let reread = Project::from_json(&project.to_json()).expect("reads");
    assert_eq!(reread.rigidity, project.rigidity);
}

/// A smooth blob (an ellipse with a bar through it) of `w × h` pixels at (`x`, `y`).
fn blob(k: usize, x: i32, y: i32, w: u32, h: u32) -> Layer {
    let pixels = RgbaImage::from_fn(w, h, |px, py| {
        let (u, v) = (
            (f64::from(px) + 0.5) / f64::from(w) * 2.0 - 1.0,
            (f64::from(py) + 0.5) / f64::from(h) * 2.0 - 1.0,
        );
        let inside = u * u + v * v <= 1.0 || u.abs() < 0.2;
        Rgba([30, 90, 150, if inside { 255 } else { 0 }])
    });
    Layer {
        name: format!("blob {k}"),
        x,
        y,
        opacity: 1.0,
        visible: true,
        pixels: Picture::Rgba8(pixels),
    }
}

#[test]
fn the_parts_share_the_density_and_keep_every_visible_pixel() {
    // Twelve smooth blobs over 1200 × 900 at 4,000 vertices in all: a share of about
    // 330 each, which their exact outlines (the pixel staircase of a smooth edge, a few
    // hundred vertices each) would take whole, and the mesh graded from them more than
    // twice over (9,189 vertices before).
    let layers: Vec<Layer> = (0..12)
        .map(|k| {
            let (col, row) = ((k % 4) as i32, (k / 4) as i32);
            blob(k, 20 + 290 * col, 20 + 290 * row, 250 + 3 * k as u32, 260)
        })
        .collect();
    let artwork = Artwork {
        width: 1200,
        height: 900,
        layers,
        notes: Vec::new(),
    };
    let project = rig(r#"{"type": "point", "rest": [145, 150]}"#);
    let parts = pipeline::parts::PartRig::new(&artwork, &project, Some(4_000), &()).expect("parts");
    let meshes = parts.meshes();
    let total: usize = meshes.iter().flatten().map(|m| m.rest.len()).sum();
    assert!(total <= 4_800, "{total} vertices for 4,000");
    for (layer, part) in artwork.layers.iter().zip(&meshes) {
        let part = part.as_ref().expect("every layer is shown");
        let domain = weights_core::Domain::new(
            part.rest.clone(),
            part.triangles.clone(),
            weights_core::Metric::Euclidean,
        )
        .expect("a mesh");
        let Picture::Rgba8(pixels) = &layer.pixels else {
            unreachable!("8-bit blobs")
        };
        for (x, y, p) in pixels.enumerate_pixels() {
            let centre = glam::DVec2::new(
                f64::from(layer.x) + f64::from(x) + 0.5,
                f64::from(layer.y) + f64::from(y) + 0.5,
            );
            assert!(
                p[3] == 0 || domain.locate(centre).is_some(),
                "{}: pixel ({x}, {y}) is off its mesh",
                layer.name
            );
        }
    }
}
