//! End-to-end tests of the `c2warp` command: golden images, identity, weights export,
//! benchmarks, and clear errors on bad input.

use crate::support;

use std::ffi::OsStr;
use std::fs;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use support::{
    c2warp, c2warp_within, data, difference, fails, fails_within, load, mkfifo, ok, os, render_args,
};

#[test]
/// The expected image comes from this renderer; regenerate it (and look at it) when the
/// mesher or the weights change on purpose:
/// `c2warp render tests/data/dino.png --rig tests/data/dino-rig.json -o tests/data/dino-warped.png`.
fn render_matches_the_golden_image() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("dino-warped.png");
    ok(&render_args(
        &data("dino.png"),
        &data("dino-rig.json"),
        &out,
        &[],
    ));
    let got = load(&out);
    let expected = load(&data("dino-warped.png"));
    let (worst, share) = difference(&got, &expected, 8);
    assert!(
        share < 0.002,
        "{:.3}% of channels differ by more than 8 (largest {worst})",
        share * 100.0
    );
    // The warp really moved something: it differs from the input.
    let (_, moved) = difference(&got, &load(&data("dino.png")), 8);
    assert!(moved > 0.01, "the warp changed almost nothing ({moved})");
}

#[test]
fn the_gpu_draws_what_the_cpu_draws() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (cpu, gpu) = (dir.path().join("cpu.png"), dir.path().join("gpu.png"));
    let (image, rig) = (data("dino.png"), data("dino-rig.json"));
    for (out, flag) in [(&cpu, None), (&gpu, Some("--gpu"))] {
        ok(&render_args(&image, &rig, out, flag.as_slice()));
    }
    // Same rasterisation rules; the GPU blends transforms in f32 and filters with
    // 8-bit texels, so edges may land a pixel apart here and there.
    let (worst, share) = difference(&load(&cpu), &load(&gpu), 8);
    assert!(
        share < 0.01,
        "{:.3}% of channels differ by more than 8 (largest {worst})",
        share * 100.0
    );
}

#[test]
fn identity_rig_gives_back_the_input() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("same.png");
    ok(&render_args(
        &data("opaque.png"),
        &data("opaque-identity-rig.json"),
        &out,
        &[],
    ));
    assert_eq!(load(&out), load(&data("opaque.png")));
}

#[test]
fn a_cut_out_at_rest_keeps_its_pixels() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rig = dir.path().join("rest.json");
    fs::write(
        &rig,
        r#"{"version":1,"density":3000,"handles":[{"type":"point","rest":[60,60]},{"type":"point","rest":[250,120]}]}"#,
    )
    .expect("write rig");
    let out = dir.path().join("same.png");
    ok(&render_args(&data("dino.png"), &rig, &out, &[]));
    let (worst, share) = difference(&load(&out), &load(&data("dino.png")), 0);
    assert_eq!(share, 0.0, "largest difference {worst}");
}

/// The picture with its colours multiplied by its alpha (what shows).
fn premultiplied(image: &image::RgbaImage) -> image::RgbaImage {
    let mut out = image.clone();
    for p in out.pixels_mut() {
        for c in 0..3 {
            p[c] = ((u32::from(p[c]) * u32::from(p[3]) + 127) / 255) as u8;
        }
    }
    out
}

/// A layered file written by another program.
fn layered(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../layers/tests/data")
        .join(name)
}

#[test]
fn a_layered_file_at_rest_renders_as_its_layers_flattened() {
    let dir = tempfile::tempdir().expect("temp dir");
    // Each file, its composite by the program that wrote it, two pins on its layers.
    for (file, flat, [a, b]) in [
        ("krita-like.ora", "krita-like.png", [[34, 8], [30, 25]]),
        (
            "psd-tools-8bit.psd",
            "psd-tools-8bit.png",
            [[5, 35], [60, 40]],
        ),
    ] {
        let rig = dir.path().join("rest.json");
        let pin = |p: [i32; 2]| format!(r#"{{"type":"point","rest":[{},{}]}}"#, p[0], p[1]);
        let text = format!(r#"{{"version":1,"handles":[{},{}]}}"#, pin(a), pin(b));
        fs::write(&rig, text).expect("write rig");
        let out = dir.path().join(format!("{file}.png"));
        ok(&render_args(&layered(file), &rig, &out, &[]));
        let layers = layers::load(&layered(file), &render::ImageLimits::default()).expect(file);
        let got = premultiplied(&load(&out));
        let (worst, share) = difference(&got, &premultiplied(&layers.flatten().into_rgba8()), 1);
        assert_eq!(share, 0.0, "{file}: largest difference {worst}");
        // And the other program's own composite, within rounding.
        let (worst, _) = difference(&got, &premultiplied(&load(&layered(flat))), 255);
        assert!(worst <= 3, "{file}: {worst} levels from its reference");
    }
}

/// The Krita-like ORA rendered by the rig `rig` (JSON) with `-o` and `--layers`: the
/// source's layers, the written layers and the PNG.
fn render_layered(rig: &str) -> (layers::Artwork, layers::Artwork, image::RgbaImage) {
    let dir = tempfile::tempdir().expect("temp dir");
    let rig_path = dir.path().join("pose.json");
    fs::write(&rig_path, rig).expect("write rig");
    let (png, ora) = (dir.path().join("posed.png"), dir.path().join("posed.ora"));
    let source = layered("krita-like.ora");
    ok(&render_args(
        &source,
        &rig_path,
        &png,
        &["--layers", ora.to_str().expect("a path")],
    ));
    let limits = render::ImageLimits::default();
    let before = layers::load(&source, &limits).expect("the source");
    let after = layers::load(&ora, &limits).expect("the written layers");
    (before, after, load(&png))
}

/// The written layers flattened are the PNG within `tolerance` levels (premultiplied),
/// and each hidden layer is kept as it was, moved by `shift`.
fn assert_layers_match(
    before: &layers::Artwork,
    after: &layers::Artwork,
    warped: &image::RgbaImage,
    tolerance: u8,
    shift: (i32, i32),
) {
    let (worst, share) = difference(
        &premultiplied(&after.flatten().into_rgba8()),
        &premultiplied(warped),
        tolerance,
    );
    assert_eq!(share, 0.0, "largest difference {worst}");
    // A hidden layer is not meshed: it is kept as it was, nothing of it lost.
    for (kept, was) in after.layers.iter().zip(&before.layers) {
        if !was.visible {
            assert_eq!((kept.x, kept.y), (was.x + shift.0, was.y + shift.1));
            assert!(kept.pixels == was.pixels, "{}", was.name);
        }
    }
}

/// `render --layers OUT.ora` writes each layer warped on its own: the file another
/// program wrote, posed, comes back with its layers' names, order, opacity and
/// visibility, and those layers flattened are the picture `-o` writes.
#[test]
fn render_writes_the_warped_layers_as_openraster() {
    let (before, after, warped) = render_layered(
        r#"{"version":1,"handles":[{"type":"point","rest":[34,8]},{"type":"point","rest":[30,25],"translate":[6,3]}]}"#,
    );
    assert_eq!((after.width, after.height), (before.width, before.height));
    let describe = |artwork: &layers::Artwork| -> Vec<(String, bool, f32)> {
        artwork
            .layers
            .iter()
            .map(|l| (l.name.clone(), l.visible, l.opacity))
            .collect()
    };
    assert_eq!(describe(&after), describe(&before));
    assert_layers_match(&before, &after, &warped, 1, (0, 0));
    // Each layer moved: the pose is in every visible layer, not only the composite.
    let (_, moved) = difference(&warped, &premultiplied(&before.flatten().into_rgba8()), 8);
    assert!(moved > 0.01, "the pose moved almost nothing ({moved})");
    // `--layers` alone; a flat picture is one layer.
    let dir = tempfile::tempdir().expect("temp dir");
    let alone = dir.path().join("flat.ora");
    ok(&[
        os("render"),
        data("dino.png").as_os_str(),
        os("--rig"),
        data("dino-rig.json").as_os_str(),
        os("--layers"),
        alone.as_os_str(),
    ]);
    let flat = layers::load(&alone, &render::ImageLimits::default()).expect("one layer");
    assert_eq!(flat.layers.len(), 1);
    let golden = load(&data("dino-warped.png"));
    let (_, share) = difference(&flat.flatten().into_rgba8(), &golden, 8);
    assert!(share < 0.002, "{share}");
}

/// With the canvas grown to fit the warp, the layers are drawn into the same grown
/// frame as the PNG, and hidden layers keep their place on the picture.
#[test]
fn warped_layers_grow_with_the_canvas() {
    // The body pulled up and left, past the canvas's corner.
    let (before, after, warped) = render_layered(
        r#"{"version":1,"canvas":"fit","handles":[{"type":"point","rest":[60,35]},{"type":"point","rest":[30,20],"translate":[-40,-25]}]}"#,
    );
    assert_eq!((after.width, after.height), warped.dimensions());
    assert!(after.width > before.width && after.height > before.height);
    // The canvas grew left and up by as much as it grew (the warp went nowhere else),
    // so the hidden layer moves with the picture's origin by that much. Within
    // rounding: each layer's edge pixels are filtered before its opacity is applied,
    // the flattened picture's after.
    let grown = (
        (after.width - before.width) as i32,
        (after.height - before.height) as i32,
    );
    assert_layers_match(&before, &after, &warped, 2, grown);
}

#[test]
fn render_refuses_layers_it_cannot_write() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (image, rig) = (data("dino.png"), data("dino-rig.json"));
    let png = dir.path().join("out.png");
    let line = fails(&render_args(
        &image,
        &rig,
        &png,
        &["--layers", png.to_str().expect("a path")],
    ));
    assert!(line.contains("OUT.ora"), "{line}");
    let ora = dir.path().join("out.ora");
    let line = fails(&render_args(
        &image,
        &rig,
        &ora,
        &["--layers", ora.to_str().expect("a path")],
    ));
    assert!(line.contains("different files"), "{line}");
    assert!(!ora.exists() && !png.exists());
}

#[test]
fn render_parts_warps_the_sample_character_part_by_part() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rig = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets/puppet-rig.json");
    let (png, ora) = (dir.path().join("cat.png"), dir.path().join("cat.ora"));
    let arg = |p: &Path| p.as_os_str().to_owned();
    let args = [
        "render".into(),
        arg(&rig),
        "--parts".into(),
        "--density".into(),
        "6000".into(),
        "-o".into(),
        arg(&png),
        "--layers".into(),
        arg(&ora),
    ];
    let args: Vec<&OsStr> = args.iter().map(|a| a.as_os_str()).collect();
    ok(&args);
    let warped = layers::load(&ora, &render::ImageLimits::default()).expect("the parts");
    assert_eq!(warped.layers.len(), 7);
    // The layers written flatten to the PNG written.
    let (worst, _) = difference(
        &premultiplied(&warped.flatten().into_rgba8()),
        &premultiplied(&load(&png)),
        1,
    );
    assert!(
        worst <= 1,
        "the parts flatten to the PNG within {worst} levels"
    );
    // The back leg's handles (its hip, a joint with the body, and its foot) do not
    // move: it is drawn where it was, pixel for pixel.
    let source = layers::load(
        &PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets/puppet.ora"),
        &render::ImageLimits::default(),
    )
    .expect("the sample");
    let rest = &source.layers[2];
    let moved = &warped.layers[2];
    assert_eq!(
        (moved.x, moved.y, moved.dimensions()),
        (rest.x, rest.y, rest.dimensions()),
        "the back leg keeps its place and size"
    );
    assert_eq!(
        moved.pixels.to_rgba8(),
        rest.pixels.to_rgba8(),
        "the back leg, pixel for pixel"
    );
    // Refused: the GPU, a grown canvas.
    let mut gpu = args.clone();
    gpu.push(OsStr::new("--gpu"));
    assert!(fails(&gpu).contains("--gpu"));
}

#[test]
fn deform_parts_writes_one_object_per_part() {
    let dir = tempfile::tempdir().expect("temp dir");
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let rig = root.join("assets/puppet-rig.json");
    let obj = dir.path().join("cat.obj");
    let deform_parts = |rig: &Path, obj: &Path| {
        ok(&[
            OsStr::new("deform"),
            OsStr::new("--parts"),
            OsStr::new("--rig"),
            rig.as_os_str(),
            OsStr::new("-o"),
            obj.as_os_str(),
        ]);
    };
    deform_parts(&rig, &obj);
    let text = fs::read_to_string(&obj).expect("the OBJ");
    // Objects in the layers' order, each with its own vertices and triangles.
    /// An OBJ object: its name, vertices and faces.
    type Object = (String, Vec<[f64; 2]>, Vec<[usize; 3]>);
    let mut objects: Vec<Object> = Vec::new();
    let mut total = 0;
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("o") => objects.push((line[2..].to_owned(), Vec::new(), Vec::new())),
            Some("v") => {
                let mut n = || {
                    words
                        .next()
                        .expect("a coordinate")
                        .parse()
                        .expect("a number")
                };
                objects.last_mut().expect("an object").1.push([n(), n()]);
                total += 1;
            }
            Some("f") => {
                let mut n = || {
                    words
                        .next()
                        .expect("an index")
                        .parse::<usize>()
                        .expect("an index")
                };
                let f = [n(), n(), n()];
                assert!(
                    f.iter().all(|&i| i >= 1 && i <= total),
                    "a face of its own vertices"
                );
                objects.last_mut().expect("an object").2.push(f);
            }
            _ => {}
        }
    }
    // The sample's layers, bottom first (their names checked in the layers crate).
    let sample = layers::load(
        &root.join("assets/puppet.ora"),
        &render::ImageLimits::default(),
    )
    .expect("the sample");
    let names: Vec<&str> = objects.iter().map(|o| o.0.as_str()).collect();
    let layer_names: Vec<&str> = sample.layers.iter().map(|l| l.name.as_str()).collect();
    assert_eq!(names, layer_names);
    assert_eq!(names.len(), 7);
    assert!(objects.iter().all(|o| !o.1.is_empty() && !o.2.is_empty()));
    // The back leg's handles stay: its vertices are where the rig at rest puts them.
    let posed = fs::read_to_string(&rig).expect("the rig");
    let project = project::Project::from_json(&posed).expect("a rig");
    let mut rest = project.clone();
    for h in &mut rest.handles {
        match h {
            project::HandleSpec::Point {
                translate,
                rotate,
                scale,
                ..
            } => (*translate, *rotate, *scale) = ([0.0; 2], 0.0, 1.0),
            project::HandleSpec::Bar { pose, .. } => *pose = None,
        }
    }
    rest.image = Some(root.join("assets/puppet.ora"));
    let rest_rig = dir.path().join("rest.json");
    fs::write(&rest_rig, rest.to_json()).expect("write the rest rig");
    let rest_obj = dir.path().join("rest.obj");
    deform_parts(&rest_rig, &rest_obj);
    let at_rest = fs::read_to_string(&rest_obj).expect("the OBJ at rest");
    let object = |text: &str, name: &str| -> Vec<String> {
        text.lines()
            .skip_while(|l| *l != format!("o {name}"))
            .skip(1)
            .take_while(|l| !l.starts_with("o "))
            .map(str::to_owned)
            .collect()
    };
    assert_eq!(object(&text, "leg (back)"), object(&at_rest, "leg (back)"));
    assert_ne!(
        object(&text, "arm (front)"),
        object(&at_rest, "arm (front)")
    );
}

#[test]
fn weights_from_a_mesh_are_a_partition_of_unity_that_interpolates() {
    let dir = tempfile::tempdir().expect("temp dir");
    // A 4 × 3 grid of unit squares.
    let mut obj = String::new();
    for y in 0..=3 {
        for x in 0..=4 {
            obj += &format!("v {} {} 0\n", x * 10, y * 10);
        }
    }
    for y in 0..3 {
        for x in 0..4 {
            let a = y * 5 + x + 1;
            obj += &format!("f {} {} {}\nf {} {} {}\n", a, a + 1, a + 6, a, a + 6, a + 5);
        }
    }
    let mesh = dir.path().join("grid.obj");
    fs::write(&mesh, obj).expect("write mesh");
    let rig = dir.path().join("rig.json");
    // One handle on a vertex, one inside a triangle (inserted as a new vertex).
    fs::write(
        &rig,
        r#"{"version":1,"handles":[{"type":"point","rest":[0,0]},{"type":"point","rest":[33,17]}]}"#,
    )
    .expect("write rig");
    let out = dir.path().join("weights.json");
    ok(&[
        os("weights"),
        os("--mesh"),
        mesh.as_os_str(),
        os("--rig"),
        rig.as_os_str(),
        os("-o"),
        out.as_os_str(),
    ]);
    let json: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(&out).expect("read")).expect("json");
    assert_eq!(json["file_vertices"], 20);
    assert_eq!(
        json["samples"], 21,
        "the off-vertex handle became vertex 20"
    );
    let nodes = json["nodes"].as_array().expect("nodes");
    assert_eq!(nodes[0]["vertex"], 0);
    assert_eq!(nodes[1]["vertex"], 20);
    assert_eq!(nodes[1]["position"], serde_json::json!([33.0, 17.0]));
    let weights = json["weights"].as_array().expect("weights");
    assert_eq!(weights.len(), 21);
    for (v, row) in weights.iter().enumerate() {
        let sum: f64 = row
            .as_array()
            .expect("row")
            .iter()
            .map(|p| p[1].as_f64().expect("weight"))
            .sum();
        assert!((sum - 1.0).abs() < 1e-9, "vertex {v}: {sum}");
    }
    for node in nodes {
        let v = node["vertex"].as_u64().expect("vertex") as usize;
        let row = weights[v].as_array().expect("row");
        assert_eq!(row.len(), 1);
        assert_eq!(row[0][0], node["index"]);
        assert_eq!(row[0][1], 1.0);
    }
}

#[test]
fn weights_from_an_image_list_the_vertices() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("weights.json");
    ok(&[
        os("weights"),
        os("--image"),
        data("dino.png").as_os_str(),
        os("--density"),
        os("1500"),
        os("--rig"),
        data("dino-rig.json").as_os_str(),
        os("-o"),
        out.as_os_str(),
    ]);
    let json: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(&out).expect("read")).expect("json");
    assert_eq!(json["metric"], "intrinsic");
    let n = json["samples"].as_u64().expect("samples") as usize;
    assert_eq!(json["vertices"].as_array().expect("vertices").len(), n);
    assert!(
        json["nodes"]
            .as_array()
            .expect("nodes")
            .iter()
            .any(|n| n["kind"] == "bar_sample")
    );
}

#[test]
fn bench_prints_one_json_object() {
    let out = ok(&[
        os("bench"),
        os("--image"),
        data("dino.png").as_os_str(),
        os("--density"),
        os("2000"),
        os("--rig"),
        data("dino-rig.json").as_os_str(),
        os("--positions"),
        os("5"),
    ]);
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    for key in [
        "samples",
        "real_handles",
        "virtual_handles",
        "insert_ms_median",
        "remove_ms_median",
        "deform_ms_median",
    ] {
        assert!(json.get(key).is_some(), "missing {key}");
    }
    for (median, p90) in [
        ("insert_ms_median", "insert_ms_p90"),
        ("remove_ms_median", "remove_ms_p90"),
    ] {
        let (m, p) = (json[median].as_f64(), json[p90].as_f64());
        assert!(
            m.zip(p).is_some_and(|(m, p)| p >= m),
            "{p90} ({p:?}) is at least {median} ({m:?})"
        );
    }
    for phase in [
        "distances",
        "voronoi",
        "virtual_handles",
        "weights",
        "total",
    ] {
        assert!(
            json["build_ms"][phase].as_f64().is_some(),
            "missing phase {phase}"
        );
    }
    assert_eq!(json["positions"], 5);
}

#[test]
fn demo_writes_a_png_and_says_where() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("demo.png");
    let run = ok(&[os("demo"), os("-o"), out.as_os_str()]);
    let said = String::from_utf8_lossy(&run.stdout);
    assert!(said.contains("demo.png"), "{said}");
    let img = load(&out);
    assert_eq!(img.dimensions(), (746, 669));
}

#[test]
fn bad_input_gives_one_clear_line_and_keeps_the_old_output() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let out = d.join("out.png");
    fs::write(&out, b"precious").expect("write");
    let good_rig = data("dino-rig.json");
    let dino = data("dino.png");
    let write = |name: &str, bytes: &[u8]| {
        let p = d.join(name);
        fs::write(&p, bytes).expect("write");
        p
    };
    let png = fs::read(&dino).expect("read");
    let corrupt = write("corrupt.png", b"\x89PNG\r\n\x1a\nthis is not a png at all");
    let truncated = write("truncated.png", &png[..png.len() / 3]);
    let text = write("text.png", b"hello");
    // A valid PNG header claiming 100000 x 100000 pixels.
    let mut huge = png[..33].to_vec();
    huge[16..20].copy_from_slice(&100_000u32.to_be_bytes());
    huge[20..24].copy_from_slice(&100_000u32.to_be_bytes());
    let crc = crc32fast::hash(&huge[12..29]);
    huge[29..33].copy_from_slice(&crc.to_be_bytes());
    huge.extend_from_slice(&png[33..]);
    let huge = write("huge.png", &huge);
    let rig = |name: &str, json: &str| write(name, json.as_bytes());
    let cases = [
        (dino.clone(), d.join("missing.json"), "cannot read rig file"),
        (d.join("missing.png"), good_rig.clone(), "missing.png"),
        (corrupt, good_rig.clone(), ""),
        (truncated, good_rig.clone(), ""),
        (text, good_rig.clone(), ""),
        (huge, good_rig.clone(), "100000"),
        (
            dino.clone(),
            rig("malformed.json", "{\"version\":1,"),
            "malformed",
        ),
        (
            dino.clone(),
            rig(
                "nan.json",
                r#"{"version":1,"handles":[{"type":"point","rest":[NaN,3]}]}"#,
            ),
            "malformed",
        ),
        (
            dino.clone(),
            rig(
                "outside.json",
                r#"{"version":1,"handles":[{"type":"point","rest":[900,3]}]}"#,
            ),
            "outside",
        ),
        (
            dino.clone(),
            rig(
                "off-shape.json",
                r#"{"version":1,"handles":[{"type":"point","rest":[2,2]}]}"#,
            ),
            "outside the shape",
        ),
        (
            dino.clone(),
            rig(
                "coincident.json",
                r#"{"version":1,"handles":[{"type":"point","rest":[60,60]},{"type":"point","rest":[60,60]}]}"#,
            ),
            "coincide",
        ),
        (
            dino.clone(),
            rig(
                "zero-bar.json",
                r#"{"version":1,"handles":[{"type":"bar","rest":[[60,60],[60,60]]}]}"#,
            ),
            "zero length",
        ),
        (
            dino.clone(),
            rig("version.json", r#"{"version":7,"handles":[]}"#),
            "version 7",
        ),
    ];
    for (image, rig, expected) in cases {
        let line = fails(&render_args(&image, &rig, &out, &[]));
        assert!(line.contains(expected), "{}: {line}", rig.display());
        assert_eq!(
            fs::read(&out).expect("read"),
            b"precious",
            "output was touched"
        );
    }
    // A mesh that is not OBJ.
    let bad_mesh = write("bad.obj", b"v 0 0\nv 1 0\nf 1 2 9\n");
    let line = fails(&[
        os("weights"),
        os("--mesh"),
        bad_mesh.as_os_str(),
        os("--rig"),
        good_rig.as_os_str(),
        os("-o"),
        out.as_os_str(),
    ]);
    assert!(line.contains("bad.obj"), "{line}");
    // No arguments to a subcommand: usage, not a panic.
    let usage = c2warp(&[os("render")]);
    assert!(!usage.status.success());
    assert!(!String::from_utf8_lossy(&usage.stderr).contains("panicked"));
}

#[test]
/// What the editor shows, exports and saves is one picture: after insertions and
/// removals in posed states, density changes and method switches, the export equals
/// `c2warp render` of the saved project pixel for pixel, the view (the editor's own GPU
/// frame drawn at full size) equals it up to filtering, and the saved project reopens
/// with the same mesh, virtual handles and weights (`Document::check_reopens`).
fn the_editor_exports_what_the_command_renders() {
    let dir = tempfile::tempdir().expect("temp dir");
    let picture = dir.path().join("lizard.png");
    fs::write(&picture, pipeline::DEFAULT_IMAGE).expect("write the picture");
    let gpu = render::GpuContext::new().expect("a wgpu adapter (run scripts/setup.sh)");
    let mut app = editor::EditorApp::headless(false);
    app.open(&picture);
    app.wait_for_job();
    let fine = |app: &editor::EditorApp| {
        assert!(
            app.message.as_ref().is_some_and(|m| !m.is_error),
            "{:?}",
            app.message
        );
    };
    fine(&app);
    let set_density = |app: &mut editor::EditorApp, density: usize| {
        let mut settings = app.document().expect("a document").settings();
        settings.density = density;
        assert!(
            app.edit(editor::Edit::Settings(settings)),
            "{:?}",
            app.message
        );
        app.wait_for_job();
    };
    let mut round = 0;
    let mut same = |app: &mut editor::EditorApp, what: &str| {
        round += 1;
        let doc = app.document().expect("a document");
        doc.check_reopens()
            .unwrap_or_else(|e| panic!("{what}: {e:#}"));
        let project = dir.path().join(format!("lizard-{round}.json"));
        let exported = dir.path().join(format!("exported-{round}.png"));
        app.save_to(&project);
        app.export_to(&exported);
        fine(app);
        let rendered = dir.path().join(format!("rendered-{round}.png"));
        ok(&render_args(&picture, &project, &rendered, &[]));
        let exported = load(&exported);
        assert!(exported == load(&rendered), "{what}: identical pixels");
        // The view, as the GPU draws it at full size, is the export up to filtering.
        let view = app.view_offscreen(&gpu).expect("the view drawn offscreen");
        let (worst, share) = difference(&view, &exported, 8);
        assert!(
            share < 0.01,
            "{what}: the view differs from the export in {:.2}% of channels (largest {worst})",
            share * 100.0
        );
    };
    set_density(&mut app, 4000);
    // A point on the hind leg, posed; a bar added in the posed state; a point added and
    // removed again.
    app.add_point(glam::DVec2::new(190.0, 470.0));
    // Posed where it was put (its rest is the picture point under the click).
    let handles = &app.document().expect("a document").project().handles;
    let leg = handles.len() - 1;
    let project::HandleSpec::Point { rest, .. } = handles[leg] else {
        panic!("a point handle");
    };
    let posed = project::HandleSpec::Point {
        rest,
        translate: [40.0, -35.0],
        rotate: 0.3,
        scale: 1.1,
        depth: 0,
    };
    assert!(
        app.edit(editor::Edit::Pose(leg, posed)),
        "{:?}",
        app.message
    );
    app.add_bar(
        glam::DVec2::new(330.0, 230.0),
        glam::DVec2::new(430.0, 330.0),
    );
    app.add_point(glam::DVec2::new(600.0, 520.0));
    same(&mut app, "insertions in a posed state");
    let last = app.document().expect("a document").project().handles.len() - 1;
    assert!(app.edit(editor::Edit::Remove(last)), "{:?}", app.message);
    same(&mut app, "a removal");
    // Another density: the picture is meshed anew, and a handle inserted on it.
    set_density(&mut app, 6000);
    app.add_point(glam::DVec2::new(640.0, 560.0));
    same(&mut app, "a new density");
    // Method switches, and an insertion under ARAP and under MLS.
    assert!(
        app.edit(editor::Edit::Method(pipeline::Method::Arap)),
        "{:?}",
        app.message
    );
    app.add_point(glam::DVec2::new(300.0, 150.0));
    same(&mut app, "ARAP");
    assert!(
        app.edit(editor::Edit::Method(pipeline::Method::Mls)),
        "{:?}",
        app.message
    );
    app.add_point(glam::DVec2::new(420.0, 380.0));
    same(&mut app, "MLS");
    assert!(
        app.edit(editor::Edit::Method(pipeline::Method::C2)),
        "{:?}",
        app.message
    );
    same(&mut app, "back to C²");
    // The tail pulled beyond the picture's edge, and the canvas grown to hold it.
    let tail = project::HandleSpec::Point {
        rest: [685.0, 590.0],
        translate: [330.0, 40.0],
        rotate: 0.0,
        scale: 1.0,
        depth: 0,
    };
    assert!(
        app.edit(editor::Edit::Add(tail.clone())),
        "{:?}",
        app.message
    );
    assert!(
        app.edit(editor::Edit::Canvas(project::Canvas::Fit)),
        "{:?}",
        app.message
    );
    same(&mut app, "a grown canvas");
    let grown = load(&dir.path().join(format!("exported-{round}.png")));
    let (w, h) = pipeline::load_image(&picture)
        .expect("picture")
        .dimensions();
    assert!(
        grown.width() > w && grown.height() >= h,
        "{:?}",
        grown.dimensions()
    );
}

/// How long a refusal may take at most (a hang or a 2 GB read takes far longer).
const PROMPT: Duration = Duration::from_secs(20);

/// The arguments of `c2warp weights --mesh MESH --rig RIG -o OUT`.
fn weights_mesh_args<'a>(mesh: &'a Path, rig: &'a Path, out: &'a Path) -> Vec<&'a OsStr> {
    vec![
        os("weights"),
        os("--mesh"),
        mesh.as_os_str(),
        os("--rig"),
        rig.as_os_str(),
        os("-o"),
        out.as_os_str(),
    ]
}

/// `dino.png` re-encoded as a JPEG in `dir`.
fn dino_jpeg(dir: &Path) -> (PathBuf, Vec<u8>) {
    let mut bytes = std::io::Cursor::new(Vec::new());
    image::DynamicImage::ImageRgb8(
        image::DynamicImage::ImageRgba8(load(&data("dino.png"))).to_rgb8(),
    )
    .write_to(&mut bytes, image::ImageFormat::Jpeg)
    .expect("encode a JPEG");
    let path = dir.join("dino.jpg");
    fs::write(&path, bytes.get_ref()).expect("write");
    (path, bytes.into_inner())
}

#[test]
fn inputs_that_are_not_regular_files_are_refused_at_once() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let out = d.join("out.png");
    fs::write(&out, b"precious").expect("write");
    let (dino, rig) = (data("dino.png"), data("dino-rig.json"));
    let fifo = d.join("fifo");
    mkfifo(&fifo);
    // A rig file of 52.4 MB (sparse: nothing is written).
    let big = d.join("big.json");
    fs::File::create(&big)
        .and_then(|f| f.set_len(52_400_000))
        .expect("a sparse file");
    let zero = PathBuf::from("/dev/zero");
    let cases = [
        (
            &fifo,
            &rig,
            format!("image {} is not a regular file (a FIFO)", fifo.display()),
        ),
        (
            &dino,
            &fifo,
            format!("rig file {} is not a regular file (a FIFO)", fifo.display()),
        ),
        (
            &zero,
            &rig,
            "image /dev/zero is not a regular file (a character device)".into(),
        ),
        (
            &dino,
            &zero,
            "rig file /dev/zero is not a regular file (a character device)".into(),
        ),
        (
            &dino,
            &big,
            format!(
                "rig file {} is 52.4 MB; rig files over 8 MiB are refused",
                big.display()
            ),
        ),
    ];
    for (image, rig, expected) in cases {
        let start = Instant::now();
        let line = fails_within(&render_args(image, rig, &out, &[]), PROMPT);
        assert_eq!(line, format!("error: {expected}"));
        assert!(
            start.elapsed() < Duration::from_secs(5),
            "{:?}",
            start.elapsed()
        );
        assert_eq!(
            fs::read(&out).expect("read"),
            b"precious",
            "output was touched"
        );
    }
    // The mesh of `weights` and `bench` too.
    for mesh in [&fifo, &zero] {
        let line = fails_within(&weights_mesh_args(mesh, &rig, &out), PROMPT);
        assert!(line.contains("is not a regular file"), "{line}");
        let line = fails_within(
            &[
                os("bench"),
                os("--mesh"),
                mesh.as_os_str(),
                os("--rig"),
                rig.as_os_str(),
            ],
            PROMPT,
        );
        assert!(line.contains("is not a regular file"), "{line}");
    }
}

#[test]
fn a_rig_file_may_start_with_a_byte_order_mark() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rig = dir.path().join("bom.json");
    let mut text = "\u{feff}".as_bytes().to_vec();
    text.extend(fs::read(data("opaque-identity-rig.json")).expect("read"));
    fs::write(&rig, text).expect("write");
    let out = dir.path().join("same.png");
    ok(&render_args(&data("opaque.png"), &rig, &out, &[]));
    assert_eq!(load(&out), load(&data("opaque.png")));
}

#[test]
fn density_zero_is_refused_alike_from_the_rig_and_the_command_line() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("out.png");
    let rig = dir.path().join("zero.json");
    fs::write(
        &rig,
        r#"{"version":1,"density":0,"handles":[{"type":"point","rest":[60,60]}]}"#,
    )
    .expect("write rig");
    let from_rig = fails(&render_args(&data("dino.png"), &rig, &out, &[]));
    let rule = "density must be between 16 and 4000000 vertices, got 0";
    assert_eq!(
        from_rig,
        format!("error: rig file {}: {rule}", rig.display())
    );
    let good = data("dino-rig.json");
    for density in ["0", "4000001"] {
        let line = fails(&render_args(
            &data("dino.png"),
            &good,
            &out,
            &["--density", density],
        ));
        let rule = rule.replace("got 0", &format!("got {density}"));
        assert_eq!(
            line,
            format!("error: invalid value '{density}' for '--density <DENSITY>': {rule}")
        );
        let line = fails(&[
            os("weights"),
            os("--image"),
            data("dino.png").as_os_str(),
            os("--density"),
            os(density),
            os("--rig"),
            good.as_os_str(),
            os("-o"),
            out.as_os_str(),
        ]);
        assert!(
            line.ends_with(&format!("'--density <DENSITY>': {rule}")),
            "{line}"
        );
    }
    assert!(!out.exists());
}

#[test]
fn a_mesh_that_is_not_obj_says_so() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let out = d.join("weights.json");
    let rig = data("dino-rig.json");
    let write = |name: &str, bytes: &[u8]| {
        let p = d.join(name);
        fs::write(&p, bytes).expect("write");
        p
    };
    let empty = write("empty.obj", b"");
    let text = write("notes.obj", b"hello\nworld\n");
    let no_faces = write("points.obj", b"v 0 0\nv 10 0\nv 0 10\n");
    let cases = [
        (
            empty.clone(),
            format!("{} is not an OBJ mesh (it is empty)", empty.display()),
        ),
        (
            data("dino.png"),
            format!(
                "{} is not an OBJ mesh (it is not text)",
                data("dino.png").display()
            ),
        ),
        (
            text.clone(),
            format!(
                "{} is not an OBJ mesh (it has no `v` vertex lines)",
                text.display()
            ),
        ),
        (
            no_faces.clone(),
            format!(
                "mesh {} has no triangles (no `f` face lines)",
                no_faces.display()
            ),
        ),
    ];
    for (mesh, expected) in cases {
        let line = fails(&weights_mesh_args(&mesh, &rig, &out));
        assert_eq!(line, format!("error: {expected}"));
        let line = fails(&[
            os("bench"),
            os("--mesh"),
            mesh.as_os_str(),
            os("--rig"),
            rig.as_os_str(),
        ]);
        assert_eq!(line, format!("error: {expected}"));
    }
    assert!(!out.exists());
}

#[test]
fn a_truncated_jpeg_is_refused_and_keeps_the_old_output() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let (jpeg, bytes) = dino_jpeg(d);
    let rig = data("dino-rig.json");
    let out = d.join("out.png");
    // The whole JPEG renders.
    ok(&render_args(&jpeg, &rig, &out, &[]));
    let good = fs::read(&out).expect("read");
    let cut = d.join("cut.jpg");
    fs::write(&cut, &bytes[..bytes.len() / 2]).expect("write");
    let line = fails(&render_args(&cut, &rig, &out, &[]));
    assert_eq!(
        line,
        format!(
            "error: {}: truncated or corrupt image data (truncated: the JPEG ends before its end-of-image marker)",
            cut.display()
        )
    );
    assert_eq!(fs::read(&out).expect("read"), good, "output was touched");
}

#[test]
fn a_tiny_jpeg_claiming_16000_squared_pixels_is_refused_fast() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let mut bytes = std::io::Cursor::new(Vec::new());
    image::RgbImage::from_fn(64, 64, |x, y| {
        image::Rgb([(x * 4) as u8, (y * 4) as u8, 90])
    })
    .write_to(&mut bytes, image::ImageFormat::Jpeg)
    .expect("encode");
    let mut forged = bytes.into_inner();
    let sof = forged
        .windows(2)
        .position(|w| w == [0xFF, 0xC0])
        .expect("a baseline frame header");
    forged[sof + 5..sof + 7].copy_from_slice(&16000u16.to_be_bytes());
    forged[sof + 7..sof + 9].copy_from_slice(&16000u16.to_be_bytes());
    assert!(forged.len() < 3000, "{} bytes", forged.len());
    let jpeg = d.join("forged.jpg");
    fs::write(&jpeg, &forged).expect("write");
    let rig = d.join("rig.json");
    fs::write(
        &rig,
        r#"{"version":1,"handles":[{"type":"point","rest":[60,60]}]}"#,
    )
    .expect("write");
    let out = d.join("out.png");
    fs::write(&out, b"precious").expect("write");
    let start = Instant::now();
    let line = fails_within(&render_args(&jpeg, &rig, &out, &[]), PROMPT);
    let took = start.elapsed();
    assert_eq!(
        line,
        format!(
            "error: {}: truncated or corrupt image data (its data is too short for 16000×16000 pixels)",
            jpeg.display()
        )
    );
    assert!(took < Duration::from_secs(2), "took {took:?}");
    assert_eq!(fs::read(&out).expect("read"), b"precious");
}

#[cfg(unix)]
#[test]
fn outputs_that_are_not_regular_files_are_written_through() {
    use std::os::unix::fs::FileTypeExt;
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let (image, rig) = (data("opaque.png"), data("opaque-identity-rig.json"));
    let expected = load(&image);

    // /dev/null takes the PNG and stays a device.
    let null = Path::new("/dev/null");
    ok(&render_args(&image, &rig, null, &[]));
    assert!(
        fs::metadata(null)
            .expect("stat")
            .file_type()
            .is_char_device()
    );

    // A symbolic link stays a link; its target gets the PNG.
    let target = d.join("target.png");
    fs::write(&target, b"old").expect("write");
    let link = d.join("link.png");
    std::os::unix::fs::symlink(&target, &link).expect("symlink");
    ok(&render_args(&image, &rig, &link, &[]));
    assert!(
        fs::symlink_metadata(&link)
            .expect("lstat")
            .file_type()
            .is_symlink()
    );
    assert_eq!(load(&target), expected);

    // A FIFO reaches its reader.
    let fifo = d.join("pipe.png");
    mkfifo(&fifo);
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || fs::read(&fifo).expect("read the FIFO"))
    };
    ok(&render_args(&image, &rig, &fifo, &[]));
    let bytes = reader.join().expect("reader");
    let got = image::load_from_memory(&bytes).expect("a PNG").to_rgba8();
    assert_eq!(got, expected);
    assert!(fs::metadata(&fifo).expect("stat").file_type().is_fifo());

    // `-` is standard output.
    let run = ok(&render_args(&image, &rig, Path::new("-"), &[]));
    assert!(run.stdout.starts_with(b"\x89PNG\r\n\x1a\n"));
    let got = image::load_from_memory(&run.stdout)
        .expect("a PNG")
        .to_rgba8();
    assert_eq!(got, expected);
    assert!(!d.join("-").exists());

    // The weights JSON too.
    let mut obj = String::new();
    for (x, y) in [(0, 0), (10, 0), (10, 10), (0, 10)] {
        obj += &format!("v {x} {y}\n");
    }
    obj += "f 1 2 3\nf 1 3 4\n";
    let mesh = d.join("square.obj");
    fs::write(&mesh, obj).expect("write");
    let square_rig = d.join("square.json");
    fs::write(
        &square_rig,
        r#"{"version":1,"handles":[{"type":"point","rest":[0,0]}]}"#,
    )
    .expect("write");
    let run = ok(&weights_mesh_args(&mesh, &square_rig, Path::new("-")));
    let json: serde_json::Value = serde_json::from_slice(&run.stdout).expect("JSON on stdout");
    assert_eq!(json["samples"], 4);
    let json_link = d.join("weights.json");
    std::os::unix::fs::symlink("weights-target.json", &json_link).expect("symlink");
    ok(&weights_mesh_args(&mesh, &square_rig, &json_link));
    assert!(
        fs::symlink_metadata(&json_link)
            .expect("lstat")
            .file_type()
            .is_symlink()
    );
    let json: serde_json::Value =
        serde_json::from_slice(&fs::read(d.join("weights-target.json")).expect("read"))
            .expect("json");
    assert_eq!(json["samples"], 4);
    ok(&weights_mesh_args(&mesh, &square_rig, null));
    assert!(
        fs::metadata(null)
            .expect("stat")
            .file_type()
            .is_char_device()
    );
}

#[test]
fn a_good_gpu_run_prints_no_error_without_xdg_runtime_dir() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("gpu.png");
    let (image, rig) = (data("dino.png"), data("dino-rig.json"));
    let args = render_args(&image, &rig, &out, &["--gpu"]);
    let run = c2warp_within(&args, Duration::from_secs(300), |command| {
        command.env_remove("XDG_RUNTIME_DIR");
    });
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(!stderr.to_lowercase().contains("error"), "{stderr}");
    assert_eq!(
        load(&out).dimensions(),
        load(&data("dino.png")).dimensions()
    );
}

#[test]
fn a_sixteen_bit_png_renders_to_a_sixteen_bit_png() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let narrow = load(&data("dino.png"));
    // Widened with low bits 8 bits cannot hold.
    let wide = image::ImageBuffer::<image::Rgba<u16>, Vec<u16>>::from_fn(
        narrow.width(),
        narrow.height(),
        |x, y| {
            let p = narrow.get_pixel(x, y).0;
            let low = ((x + y) % 64) as u16;
            image::Rgba(p.map(|c| (u16::from(c) * 257).saturating_sub(low)))
        },
    );
    let source = d.join("wide.png");
    wide.save(&source).expect("save a 16-bit PNG");
    let rig = data("dino-rig.json");
    let (out16, out8) = (d.join("out16.png"), d.join("out8.png"));
    ok(&render_args(&source, &rig, &out16, &[]));
    ok(&render_args(&data("dino.png"), &rig, &out8, &[]));
    let got = image::open(&out16).expect("open");
    assert_eq!(got.color(), image::ColorType::Rgba16);
    let got = got.into_rgba16();
    // Low bits survive: some output channels are no multiple of 257.
    assert!(got.as_raw().iter().any(|&c| c % 257 != 0));
    // And it is the 8-bit render, up to rounding.
    let (worst, share) = difference(
        &image::DynamicImage::ImageRgba16(got).to_rgba8(),
        &load(&out8),
        2,
    );
    assert!(
        share < 0.002,
        "{:.3}% differ by more than 2 (largest {worst})",
        share * 100.0
    );
    // --gpu draws in 8 bits.
    let gpu = d.join("gpu.png");
    ok(&render_args(&source, &rig, &gpu, &["--gpu"]));
    assert_eq!(
        image::open(&gpu).expect("open").color(),
        image::ColorType::Rgba8
    );
}

#[test]
fn webp_tiff_bmp_and_gif_pictures_render() {
    let dir = tempfile::tempdir().expect("temp dir");
    let picture = load(&data("opaque.png"));
    for (format, name) in [
        (image::ImageFormat::WebP, "opaque.webp"),
        (image::ImageFormat::Tiff, "opaque.tiff"),
        (image::ImageFormat::Bmp, "opaque.bmp"),
        (image::ImageFormat::Gif, "opaque.gif"),
    ] {
        // Named .png on purpose: the format is found from the content.
        let path = dir.path().join(format!("{name}.png"));
        image::DynamicImage::ImageRgba8(picture.clone())
            .save_with_format(&path, format)
            .expect("encode");
        let out = dir.path().join(format!("{name}-out.png"));
        ok(&render_args(
            &path,
            &data("opaque-identity-rig.json"),
            &out,
            &[],
        ));
        let expected = image::load_from_memory(&fs::read(&path).expect("read"))
            .expect("decode")
            .to_rgba8();
        assert_eq!(load(&out), expected, "{name}");
    }
}

#[test]
fn a_directory_where_a_file_belongs_is_refused_once() {
    let dir = tempfile::tempdir().expect("temp dir");
    let folder = dir.path().join("folder.png");
    fs::create_dir(&folder).expect("mkdir");
    let rig = data("dino-rig.json");
    let line = fails(&render_args(&data("dino.png"), &rig, &folder, &[]));
    assert!(line.contains("Is a directory"), "{line}");
    let line = fails(&render_args(
        &data("dino.png"),
        &folder,
        &dir.path().join("o.png"),
        &[],
    ));
    assert!(line.contains("not a regular file"), "{line}");
    let line = fails(&render_args(&folder, &rig, &dir.path().join("o.png"), &[]));
    assert!(line.contains("not a regular file"), "{line}");
}

#[test]
fn a_rig_file_that_is_not_an_object_says_what_it_is() {
    let dir = tempfile::tempdir().expect("temp dir");
    for (text, expected) in [
        ("null", "a rig file is one JSON object"),
        ("[]", "not a list"),
        ("7", "not a number"),
    ] {
        let rig = dir.path().join("rig.json");
        fs::write(&rig, text).expect("write");
        let line = fails(&render_args(
            &data("dino.png"),
            &rig,
            &dir.path().join("o.png"),
            &[],
        ));
        assert!(
            line.contains(expected) && !line.contains("Probe"),
            "{text}: {line}"
        );
    }
}

/// Copies `name` from the test data into `dir`.
fn copy_data(dir: &Path, name: &str) -> PathBuf {
    let to = dir.join(name);
    fs::copy(data(name), &to).expect("copy test data");
    to
}

#[test]
fn no_command_writes_over_its_input() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let pic = copy_data(d, "dino.png");
    let rig = copy_data(d, "dino-rig.json");
    let mesh = copy_data(d, "strip.obj");
    fs::create_dir(d.join("sub")).expect("mkdir");
    #[cfg(unix)]
    std::os::unix::fs::symlink(&pic, d.join("link.png")).expect("symlink");
    let originals: Vec<(PathBuf, Vec<u8>)> = [&pic, &rig, &mesh]
        .iter()
        .map(|p| ((*p).clone(), fs::read(p).expect("read")))
        .collect();
    let through_dots = d.join("sub/../dino.png");
    let mut cases: Vec<(Vec<&OsStr>, &Path)> = vec![
        (render_args(&pic, &rig, &pic, &[]), &pic),
        (render_args(&pic, &rig, &rig, &[]), &rig),
        (render_args(&pic, &rig, &through_dots, &[]), &pic),
        (
            vec![os("cage"), pic.as_os_str(), os("-o"), pic.as_os_str()],
            &pic,
        ),
        (
            vec![
                os("cage"),
                pic.as_os_str(),
                os("--rig"),
                rig.as_os_str(),
                os("-o"),
                rig.as_os_str(),
            ],
            &rig,
        ),
        (
            vec![
                os("weights"),
                os("--image"),
                pic.as_os_str(),
                os("--rig"),
                rig.as_os_str(),
                os("-o"),
                rig.as_os_str(),
            ],
            &rig,
        ),
        (
            vec![
                os("deform"),
                os("--mesh"),
                mesh.as_os_str(),
                os("--rig"),
                rig.as_os_str(),
                os("-o"),
                mesh.as_os_str(),
            ],
            &mesh,
        ),
    ];
    #[cfg(unix)]
    let link = d.join("link.png");
    #[cfg(unix)]
    cases.push((render_args(&pic, &rig, &link, &[]), &pic));
    for (args, input) in &cases {
        let line = fails(args);
        let name = input.file_name().and_then(OsStr::to_str).expect("name");
        assert!(
            line.contains("one of the inputs") && line.contains(name),
            "{args:?}: {line}"
        );
    }
    for (path, bytes) in &originals {
        assert_eq!(
            &fs::read(path).expect("read"),
            bytes,
            "{} changed",
            path.display()
        );
    }
    assert_eq!(fs::read_dir(d.join("sub")).expect("list").count(), 0);
}

#[test]
fn numeric_flags_give_one_line_naming_the_flag_and_its_range() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("out.json");
    let pic = data("dino.png");
    let rig = data("dino-rig.json");
    let cage = |extra: &[&str]| {
        let mut args = vec![os("cage"), pic.as_os_str(), os("-o"), out.as_os_str()];
        args.extend(extra.iter().map(|e| os(e)));
        fails(&args)
    };
    for (line, flag, range) in [
        (cage(&["--vertices", "-1"]), "--vertices", "from 3 to 1,000"),
        (cage(&["--vertices=-1"]), "--vertices", "from 3 to 1,000"),
        (
            cage(&["--vertices", "2.5"]),
            "--vertices",
            "from 3 to 1,000",
        ),
        (cage(&["--offset", "-5"]), "--offset", "from 0 to 10,000 px"),
        (
            cage(&["--offset", "1e9"]),
            "--offset",
            "from 0 to 10,000 px",
        ),
        (
            cage(&["--offset", "NaN"]),
            "--offset",
            "from 0 to 10,000 px",
        ),
        (
            fails(&render_args(&pic, &rig, &out, &["--density", "-5"])),
            "--density",
            "from 16 to 4,000,000",
        ),
        (
            fails(&[
                os("bench"),
                os("--image"),
                pic.as_os_str(),
                os("--rig"),
                rig.as_os_str(),
                os("--positions"),
                os("-3"),
            ]),
            "--positions",
            "from 1 to 10,000",
        ),
        (
            fails(&[
                os("animate"),
                rig.as_os_str(),
                os("-o"),
                out.as_os_str(),
                os("--fps"),
                os("-24"),
            ]),
            "--fps",
            "above 0 to 240 frames per second",
        ),
        (
            fails(&[
                os("animate"),
                rig.as_os_str(),
                os("-o"),
                out.as_os_str(),
                os("--from"),
                os("-1"),
            ]),
            "--from",
            "from 0 to 86,400 s",
        ),
    ] {
        assert!(
            line.contains(&format!("'{flag} <")) && line.contains(range),
            "{flag}: {line}"
        );
    }
    assert!(!out.exists());
}

#[test]
fn render_takes_a_project_alone_or_a_picture_and_its_rig() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let pic = copy_data(d, "dino.png");
    fs::create_dir(d.join("rigs")).expect("mkdir");
    // `cage` names the picture relative to the rig's folder, even outside it.
    let project = d.join("rigs/dino.json");
    ok(&[os("cage"), pic.as_os_str(), os("-o"), project.as_os_str()]);
    let text = fs::read_to_string(&project).expect("read");
    let json: serde_json::Value = serde_json::from_str(&text).expect("json");
    assert_eq!(json["image"], "../dino.png", "{text}");
    let alone = d.join("alone.png");
    let both = d.join("both.png");
    ok(&[
        os("render"),
        project.as_os_str(),
        os("-o"),
        alone.as_os_str(),
        os("--density"),
        os("300"),
    ]);
    ok(&render_args(&pic, &project, &both, &["--density", "300"]));
    assert_eq!(
        fs::read(&alone).expect("read"),
        fs::read(&both).expect("read")
    );
    // The other commands that read a project find its picture the same way.
    let obj = d.join("out.obj");
    ok(&[
        os("deform"),
        os("--rig"),
        project.as_os_str(),
        os("--density"),
        os("300"),
        os("-o"),
        obj.as_os_str(),
    ]);
    // A picture without its rig says what to give.
    let line = fails(&[os("render"), pic.as_os_str(), os("-o"), alone.as_os_str()]);
    assert!(line.contains("--rig"), "{line}");
}

#[test]
fn animate_parts_draws_each_frame_as_render_parts_draws_its_pose() {
    use project::{Animation, HandlePose, Key, Pose, Project};
    let dir = tempfile::tempdir().expect("temp dir");
    let assets = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets");
    let text = fs::read_to_string(assets.join("puppet-rig.json")).expect("the sample rig");
    let mut posed = Project::from_json(&text).expect("a rig");
    posed.image = Some(assets.join("puppet.ora"));
    posed.density = Some(4_000);
    let mut rest = posed.clone();
    Pose {
        handles: posed.handles.iter().map(HandlePose::rest).collect(),
        cage: None,
        overlaps: Vec::new(),
    }
    .apply(&mut rest);
    let key = |time: f64, p: &Project| Key {
        time,
        hold: false,
        pose: Pose::of(p),
    };
    let animated = Project {
        animation: Some(Animation {
            fps: 8.0,
            keys: vec![key(0.0, &rest), key(0.25, &posed)],
            ..Animation::default()
        }),
        ..posed.clone()
    };
    let write = |name: &str, p: &Project| {
        let path = dir.path().join(name);
        fs::write(&path, p.to_json()).expect("write");
        path
    };
    let (anim, at_rest, at_end) = (
        write("anim.json", &animated),
        write("rest.json", &rest),
        write("end.json", &posed),
    );
    let frames = dir.path().join("frames");
    fs::create_dir(&frames).expect("a folder");
    ok(&[
        os("animate"),
        anim.as_os_str(),
        os("--parts"),
        os("-o"),
        frames.as_os_str(),
    ]);
    let drawn: Vec<PathBuf> = (0..3)
        .map(|i| frames.join(format!("frame_{i:05}.png")))
        .collect();
    assert!(drawn.iter().all(|f| f.exists()));
    assert!(!frames.join("frame_00003.png").exists());
    for (frame, project) in [(&drawn[0], &at_rest), (&drawn[2], &at_end)] {
        let png = dir.path().join("render.png");
        ok(&[
            os("render"),
            project.as_os_str(),
            os("--parts"),
            os("-o"),
            png.as_os_str(),
        ]);
        assert!(
            load(frame) == load(&png),
            "{} is render --parts of its pose",
            frame.display()
        );
    }
    // The middle frame lies between them.
    assert!(load(&drawn[1]) != load(&drawn[0]) && load(&drawn[1]) != load(&drawn[2]));
    let refused = fails(&[
        os("animate"),
        anim.as_os_str(),
        os("--parts"),
        os("--gpu"),
        os("-o"),
        frames.as_os_str(),
    ]);
    assert!(refused.contains("--gpu"), "{refused}");
}

#[test]
fn a_project_of_several_pictures_with_parts_renders_them_in_its_order() {
    let dir = tempfile::tempdir().expect("temp dir");
    let block = |name: &str, x0: u32, colour: [u8; 4]| {
        let picture = image::RgbaImage::from_fn(200, 120, |x, y| {
            let inside = (x0..x0 + 100).contains(&x) && (20..100).contains(&y);
            image::Rgba(if inside { colour } else { [0; 4] })
        });
        picture
            .save(dir.path().join(name))
            .expect("write a picture");
    };
    block("left.png", 10, [200, 40, 40, 255]);
    block("right.png", 80, [40, 40, 200, 255]);
    let project = dir.path().join("pair.json");
    let rig = |parts: &str| {
        format!(
            r#"{{"version": 1, "images": ["left.png", "right.png"], "density": 800,
                "handles": [{{"type": "point", "rest": [30, 60]}},
                            {{"type": "point", "rest": [170, 60]}}]{parts}}}"#
        )
    };
    let (png, obj) = (dir.path().join("out.png"), dir.path().join("out.obj"));
    // With "parts" in the rig file, no --parts is needed, and its order holds: the
    // left picture sent to the front covers the right one where they overlap.
    fs::write(&project, rig(r#", "parts": {"order": [1, 0]}"#)).expect("write the rig");
    ok(&[os("render"), project.as_os_str(), os("-o"), png.as_os_str()]);
    assert_eq!(load(&png).get_pixel(85, 60).0, [200, 40, 40, 255]);
    ok(&[
        os("deform"),
        os("--rig"),
        project.as_os_str(),
        os("-o"),
        obj.as_os_str(),
    ]);
    let objects: Vec<String> = (fs::read_to_string(&obj).expect("the OBJ").lines())
        .filter_map(|l| l.strip_prefix("o ").map(str::to_owned))
        .collect();
    assert_eq!(
        objects,
        ["right", "left"],
        "one object a part, in the draw order"
    );
    // Weights and timings by part.
    let weights = dir.path().join("weights.json");
    ok(&[
        os("weights"),
        os("--rig"),
        project.as_os_str(),
        os("-o"),
        weights.as_os_str(),
    ]);
    let listed: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(&weights).expect("weights")).expect("JSON");
    let parts = listed["parts"].as_array().expect("by part");
    let names: Vec<_> = parts.iter().map(|p| p["name"].as_str()).collect();
    assert_eq!(names, [Some("right"), Some("left")]);
    let out = ok(&[
        os("bench"),
        os("--rig"),
        project.as_os_str(),
        os("--positions"),
        os("2"),
    ]);
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    assert_eq!(
        (report["parts"].as_u64(), report["poses"].as_u64()),
        (Some(2), Some(2))
    );
    // Without "parts" the pictures are one picture, the later on top.
    fs::write(&project, rig("")).expect("write the rig");
    ok(&[os("render"), project.as_os_str(), os("-o"), png.as_os_str()]);
    assert_eq!(load(&png).get_pixel(85, 60).0, [40, 40, 200, 255]);
    // Every picture named is an input no output may replace.
    let left = dir.path().join("left.png");
    let line = fails(&[
        os("render"),
        project.as_os_str(),
        os("-o"),
        left.as_os_str(),
    ]);
    assert!(line.contains("one of the inputs"), "{line}");
}

#[test]
fn a_carried_shape_is_drawn_by_deform_under_arap_and_mls_and_ignored_under_c2() {
    let dir = tempfile::tempdir().expect("temp dir");
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    fs::copy(
        root.join("assets/lizard.png"),
        dir.path().join("lizard.png"),
    )
    .expect("copy");
    // A shape of one offset everywhere (three listed vertices around the picture,
    // which no mesh of it matches: interpolated), on a rig at rest.
    let rig = |method: &str, carried: bool| {
        let shape = r#","carried":[{"rest":[[-1e4,-1e4],[1e4,-1e4],[0,1e4]],
            "offset":[[1.5,-0.5],[1.5,-0.5],[1.5,-0.5]]}]"#;
        format!(
            r#"{{"version":1,"image":"lizard.png","method":"{method}","density":2000,
            "handles":[{{"type":"point","rest":[300,300]}},{{"type":"point","rest":[450,240]}}]{}}}"#,
            if carried { shape } else { "" }
        )
    };
    let deformed = |method: &str, carried: bool| -> Vec<[f64; 2]> {
        let path = dir.path().join(format!("{method}-{carried}.json"));
        fs::write(&path, rig(method, carried)).expect("write the rig");
        let obj = dir.path().join(format!("{method}-{carried}.obj"));
        ok(&[
            OsStr::new("deform"),
            OsStr::new("--rig"),
            path.as_os_str(),
            OsStr::new("-o"),
            obj.as_os_str(),
        ]);
        (fs::read_to_string(&obj).expect("the OBJ").lines())
            .filter_map(|l| l.strip_prefix("v "))
            .map(|l| {
                let mut n = l
                    .split_whitespace()
                    .map(|w| w.parse::<f64>().expect("a number"));
                [n.next().expect("x"), n.next().expect("y")]
            })
            .collect()
    };
    for method in ["arap", "mls"] {
        let (plain, carried) = (deformed(method, false), deformed(method, true));
        assert_eq!(plain.len(), carried.len());
        // At rest the local frames are the identity: every vertex moved by the offset.
        for (p, q) in plain.iter().zip(&carried) {
            let d = [q[0] - p[0], q[1] - p[1]];
            assert!(
                (d[0] - 1.5).abs() < 1e-6 && (d[1] + 0.5).abs() < 1e-6,
                "{method}: {p:?} went to {q:?}"
            );
        }
    }
    assert_eq!(
        deformed("c2", true),
        deformed("c2", false),
        "C² draws no shape"
    );
}
