//! The editor's speed targets, measured on the real code paths:
//! - inserting a handle on the built-in picture at the default density, from the click
//!   to weights ready for the GPU (`insert_handle`);
//! - the CPU cost of one frame of a handle drag at 200k mesh vertices, a whole egui
//!   frame of the real app (input, layout, the edit, the pose upload data, overlays,
//!   tessellation) (`drag_frame`);
//! - exporting a 4096 × 4096 picture: mesh, weights, full-resolution CPU drawing, PNG
//!   encoding, atomic write (`export`);
//! - switching the built-in picture's posed rig from C² weights to ARAP (registration,
//!   compilation, the pose, the positions for the GPU) and one ARAP drag frame's
//!   update (`method_switch`);
//! - layered pictures drawn as parts: a 2048 × 2048 picture of 50 layers opened and set
//!   up as parts, and one drag frame of a character of 12 parts at a total density of
//!   20,000, a whole egui frame of the real app (`parts`).

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use editor::{Document, Edit, EditorApp};
use egui::{Pos2, Vec2};
use egui_kittest::Harness;
use glam::DVec2;
use image::{Rgba, RgbaImage};
use project::{HandleSpec, Method, Project};

/// Criterion's default 100 samples take minutes for the slower groups; 20 tell enough.
fn quick() -> Criterion {
    Criterion::default().sample_size(20)
}

fn insert_handle(c: &mut Criterion) {
    for method in [Method::C2, Method::Arap, Method::Mls] {
        insert_handle_by(c, method);
    }
}

/// Insertion from the click to the GPU under `method` (C²'s under the plain name).
fn insert_handle_by(c: &mut Criterion, method: Method) {
    let mut app = EditorApp::headless(true);
    if method != Method::C2 {
        (app.document_mut().expect("the built-in picture"))
            .apply(Edit::Method(method))
            .expect("a handle method");
    }
    app.update_gpu_frame();
    // Mesh vertices in a fixed pseudo-random order: clicks spread over the picture.
    let vertices = app.document().map_or(0, |d| d.mesh().len());
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next_click = |app: &mut EditorApp| {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1);
        let v = (state >> 33) as usize % vertices;
        let doc = app.document_mut().expect("a document");
        doc.deformed()[v]
    };
    let (mut refused, mut inserted) = (0, 0);
    let (mut remeshed, mut remeshing) = (0, Duration::ZERO);
    let name = match method {
        Method::C2 => "editor/insert_handle/lizard_20k".to_owned(),
        _ => format!("editor/insert_handle/lizard_20k_{}", method.name()),
    };
    c.bench_function(&name, |b| {
        b.iter_custom(|iterations| {
            let mut total = Duration::ZERO;
            let mut done = 0;
            while done < iterations {
                let at = next_click(&mut app);
                let mesh = app.document().map(Document::mesh_version);
                let clock = Instant::now();
                app.add_point(at);
                app.update_gpu_frame();
                let elapsed = clock.elapsed();
                if app.message.as_ref().is_some_and(|m| m.is_error) {
                    // Refused at once (off the picture), not an insertion.
                    refused += 1;
                    continue;
                }
                // A click within two of the picture's lattice spacings of another
                // handle refines the mesh there and meshes the picture anew (a rarer
                // case, timed apart): the common insertion is timed here.
                if app.document().map(Document::mesh_version) != mesh {
                    remeshed += 1;
                    remeshing += elapsed;
                } else {
                    inserted += 1;
                    total += elapsed;
                    done += 1;
                }
                app.undo();
                app.update_gpu_frame();
            }
            total
        });
    });
    eprintln!(
        "insertions: {inserted}, refused: {refused}; meshing the picture anew: {remeshed}, {:.1} ms \
         each on average",
        remeshing.as_secs_f64() * 1e3 / f64::from(remeshed.max(1))
    );
}

fn drag_frame(c: &mut Criterion) {
    let mut doc = Document::built_in().expect("the built-in picture");
    let mut settings = doc.settings();
    settings.density = 200_000;
    doc.apply(Edit::Settings(settings)).expect("200k vertices");
    let vertices = doc.rig().expect("a C² rig").stats().samples;
    let mut h = Harness::builder()
        .with_size(Vec2::new(1280.0, 820.0))
        .build_eframe(move |_cc| EditorApp::with_document(doc));
    h.run();
    let grab = h
        .state()
        .viewport
        .to_screen(DVec2::new(440.0, 238.0) + DVec2::new(-20.0, -60.0));
    h.hover_at(grab);
    h.run();
    h.drag_at(grab);
    h.run();
    h.hover_at(grab + Vec2::new(10.0, 0.0));
    h.run();
    assert_eq!(h.state().selected, Some(2), "the drag holds handle 3");
    let mut k = 0u32;
    c.bench_function(
        &format!("editor/drag_frame/{}k_vertices", vertices / 1000),
        |b| {
            b.iter(|| {
                k += 1;
                let wiggle = Vec2::new(12.0 * ((k % 8) as f32 - 4.0), 6.0);
                h.hover_at(Pos2::new(grab.x, grab.y) + wiggle);
                h.step();
            });
        },
    );
    let moved = h.state().document().map(|d| d.project().handles[2].clone());
    assert!(
        matches!(moved, Some(HandleSpec::Point { translate, .. }) if translate != [-20.0, -60.0]),
        "the handle follows the pointer: {moved:?}"
    );
}

fn export(c: &mut Criterion) {
    let size = 4096;
    let picture = RgbaImage::from_fn(size, size, |x, y| {
        Rgba([(x / 16) as u8, (y / 16) as u8, ((x ^ y) & 255) as u8, 255])
    });
    let point = |rest: [f64; 2], translate: [f64; 2]| HandleSpec::Point {
        rest,
        translate,
        rotate: 0.2,
        scale: 1.0,
        depth: 0,
    };
    let project = Project {
        handles: vec![
            point([800.0, 800.0], [100.0, 50.0]),
            point([3200.0, 900.0], [-80.0, 120.0]),
            point([2000.0, 3000.0], [0.0, -200.0]),
        ],
        ..Project::default()
    };
    let doc = Document::new(picture, None, project).expect("a 4096² document");
    let mut app = EditorApp::with_document(doc);
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("warped.png");
    let mut group = c.benchmark_group("editor/export");
    group.sample_size(10);
    group.bench_function("4096x4096", |b| {
        b.iter(|| {
            app.export_to(black_box(&out));
        });
    });
    group.finish();
    // (Nothing ran when the group was filtered out.)
    assert!(
        app.message.as_ref().is_none_or(|m| !m.is_error),
        "{:?}",
        app.message
    );
}

fn method_switch(c: &mut Criterion) {
    let mut doc = Document::built_in().expect("the built-in picture");
    c.bench_function("editor/switch_to_arap/lizard_20k", |b| {
        b.iter(|| {
            doc.apply(Edit::Method(project::Method::Arap))
                .expect("ARAP");
            black_box(doc.deformer().deformed());
            doc.apply(Edit::Method(project::Method::C2)).expect("C²");
        })
    });
    doc.apply(Edit::Method(project::Method::Arap))
        .expect("ARAP");
    let mut dx = 0.0;
    c.bench_function("editor/arap_drag_update/lizard_20k", |b| {
        b.iter(|| {
            dx = if dx > 20.0 { 0.0 } else { dx + 1.0 };
            let handle = HandleSpec::Point {
                rest: [440.0, 238.0],
                translate: [-20.0 + dx, -60.0],
                rotate: 0.0,
                scale: 1.0,
                depth: 0,
            };
            // As a drag frame poses it: live, on from the previous frame.
            let mut project = doc.project().clone();
            project.handles[2] = handle;
            doc.preview(project).expect("pose");
            black_box(doc.deformer().deformed().len())
        })
    });
    // The drag's end: the pose solved in full from the two steps.
    c.bench_function("editor/arap_settle/lizard_20k", |b| {
        b.iter(|| {
            dx = if dx > 20.0 { 0.0 } else { dx + 1.0 };
            let mut project = doc.project().clone();
            if let HandleSpec::Point { translate, .. } = &mut project.handles[2] {
                *translate = [-20.0 + dx, -60.0];
            }
            doc.preview(project).expect("pose");
            doc.settle().expect("settled");
            black_box(doc.deformer().deformed().len())
        })
    });
}

/// A layer of `w × h` at (`x`, `y`) on the canvas: an ellipse with a bar across it, in
/// a colour of its own (as scattered cut-out parts are).
fn blob(name: String, x: i32, y: i32, w: u32, h: u32, k: u32) -> pipeline::Layer {
    let colour = [
        (k * 53 % 255) as u8,
        (k * 97 % 255) as u8,
        (k * 151 % 255) as u8,
    ];
    let pixels = RgbaImage::from_fn(w, h, |px, py| {
        let (u, v) = (
            (px as f64 + 0.5) / f64::from(w) * 2.0 - 1.0,
            (py as f64 + 0.5) / f64::from(h) * 2.0 - 1.0,
        );
        let inside = u * u + v * v <= 1.0 || (u.abs() < 0.2);
        let [r, g, b] = colour;
        Rgba([r, g, b, if inside { 255 } else { 0 }])
    });
    pipeline::Layer {
        name,
        x,
        y,
        opacity: 1.0,
        visible: true,
        pixels: render::Picture::Rgba8(pixels),
    }
}

fn parts(c: &mut Criterion) {
    // 50 layers scattered over a 2048 × 2048 canvas, overlapping, two pins.
    let mut seed = 7u64;
    let mut next = |n: u32| {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed % u64::from(n)) as u32
    };
    let layers: Vec<pipeline::Layer> = (0..50)
        .map(|k| {
            let (w, h) = (200 + next(500), 200 + next(700));
            let (x, y) = (next(2048 - w), next(2048 - h));
            blob(format!("part {k}"), x as i32, y as i32, w, h, k)
        })
        .collect();
    let scattered = pipeline::Artwork {
        width: 2048,
        height: 2048,
        layers,
        notes: Vec::new(),
    };
    let first = &scattered.layers[0];
    let (w, h) = first.dimensions();
    let centre = [
        f64::from(first.x) + f64::from(w) / 2.0,
        f64::from(first.y) + f64::from(h) / 2.0,
    ];
    let project = Project {
        handles: vec![
            point(centre[0], centre[1]),
            point(centre[0], centre[1] - 40.0),
        ],
        parts: Some(project::PartsSpec::default()),
        ..Project::default()
    };
    let mut group = c.benchmark_group("editor/parts");
    group.sample_size(10);
    group.bench_function("open_50_layers_2048", |b| {
        b.iter(|| {
            let doc = Document::from_artwork(scattered.clone(), None, project.clone())
                .expect("opens as parts");
            black_box(doc.deformer().deformed().len())
        });
    });
    group.finish();

    // A character of 12 parts: a chain of limbs, each overlapping the next at a joint,
    // a pin at every joint and at both ends; the last pin dragged.
    let limbs: Vec<pipeline::Layer> = (0..12u32)
        .map(|k| blob(format!("limb {k}"), 40 + 80 * k as i32, 300, 120, 60, k))
        .collect();
    let character = pipeline::Artwork {
        width: 1100,
        height: 700,
        layers: limbs,
        notes: Vec::new(),
    };
    let pins: Vec<HandleSpec> = (0..13)
        .map(|k| point(50.0 + 80.0 * k as f64, 330.0))
        .collect();
    let project = Project {
        handles: pins,
        density: Some(20_000),
        parts: Some(project::PartsSpec::default()),
        ..Project::default()
    };
    let mut doc = Document::from_artwork(character, None, project).expect("12 parts");
    let vertices = doc.parts().map_or(0, |p| pipeline::Deformer::rest(p).len());
    // A pin inserted on one limb (the parts it binds set up again, the others kept),
    // then removed again; then the same, each followed by the arrangement of the
    // joined mesh's overlaps, which an insertion leaves to the next frame
    // (`Document::arrange_deferred`).
    let mut n = 0u32;
    for (name, arranged) in [
        ("insert_and_remove_pin", false),
        ("insert_and_remove_pin_arranged", true),
    ] {
        let step = |doc: &mut Document, edit: Edit| {
            doc.apply(edit).expect("inserted or removed");
            if arranged {
                doc.arrange_deferred();
            }
        };
        c.bench_function(
            &format!("editor/parts/{name}/12_parts_{}k_vertices", vertices / 1000),
            |b| {
                b.iter(|| {
                    n += 1;
                    let at = 250.0 + f64::from(n % 7) * 80.0;
                    step(&mut doc, Edit::Add(point(at, 320.0)));
                    let last = doc.project().handles.len() - 1;
                    step(&mut doc, Edit::Remove(last));
                });
            },
        );
    }
    let mut h = Harness::builder()
        .with_size(Vec2::new(1280.0, 820.0))
        .build_eframe(move |_cc| EditorApp::with_document(doc));
    h.run();
    let grab = h.state().viewport.to_screen(DVec2::new(1010.0, 330.0));
    h.hover_at(grab);
    h.run();
    h.drag_at(grab);
    h.run();
    h.hover_at(grab + Vec2::new(10.0, 0.0));
    h.run();
    assert_eq!(h.state().selected, Some(12), "the drag holds the last pin");
    let mut k = 0u32;
    c.bench_function(
        &format!(
            "editor/parts/drag_frame/12_parts_{}k_vertices",
            vertices / 1000
        ),
        |b| {
            b.iter(|| {
                k += 1;
                // The chain's end swung up and down.
                let wiggle = Vec2::new(4.0, 10.0 * ((k % 8) as f32 - 4.0));
                h.hover_at(Pos2::new(grab.x, grab.y) + wiggle);
                h.step();
            });
        },
    );
    let moved = h
        .state()
        .document()
        .map(|d| d.project().handles[12].clone());
    assert!(
        matches!(moved, Some(HandleSpec::Point { translate, .. }) if translate != [0.0; 2]),
        "the pin follows the pointer: {moved:?}"
    );
}

criterion_group! {
    name = benches;
    config = quick();
    targets = insert_handle, drag_frame, export, method_switch, parts
}
criterion_main!(benches);

/// A point handle at rest at (`x`, `y`).
fn point(x: f64, y: f64) -> HandleSpec {
    HandleSpec::Point {
        rest: [x, y],
        translate: [0.0; 2],
        rotate: 0.0,
        scale: 1.0,
        depth: 0,
    }
}
