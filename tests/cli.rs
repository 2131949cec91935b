//! End-to-end tests of the `c2warp` command: golden images, identity, weights export,
//! benchmarks, and clear errors on bad input.

mod support;

use std::ffi::OsStr;
use std::fs;

use support::{c2warp, data, difference, fails, load, ok, render_args};

fn os(s: &str) -> &OsStr {
    OsStr::new(s)
}

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
/// The editor's export and `c2warp render` of the project it saved give the same pixels.
fn the_editor_exports_what_the_command_renders() {
    let dir = tempfile::tempdir().expect("temp dir");
    let picture = dir.path().join("dino.png");
    fs::copy(data("dino.png"), &picture).expect("copy the picture");
    let mut app = editor::EditorApp::headless(false);
    app.open(&picture);
    assert!(
        app.message.as_ref().is_some_and(|m| !m.is_error),
        "{:?}",
        app.message
    );
    // A point, then a bar, inserted live, and the point posed: the rig the editor
    // holds has live-inserted handles and virtual handles.
    app.add_point(glam::DVec2::new(250.0, 120.0));
    app.add_bar(
        glam::DVec2::new(130.0, 100.0),
        glam::DVec2::new(160.0, 160.0),
    );
    let posed = project::HandleSpec::Point {
        rest: [250.0, 120.0],
        translate: [12.0, -25.0],
        rotate: 0.3,
        scale: 1.1,
    };
    assert!(app.edit(editor::Edit::Pose(0, posed)), "{:?}", app.message);
    let handles = app.document().map_or(0, |d| d.project().handles.len());
    assert_eq!(handles, 2, "{:?}", app.message);
    let project = dir.path().join("dino.json");
    let exported = dir.path().join("exported.png");
    app.save_to(&project);
    app.export_to(&exported);
    assert!(
        app.message.as_ref().is_some_and(|m| !m.is_error),
        "{:?}",
        app.message
    );
    let rendered = dir.path().join("rendered.png");
    ok(&render_args(&picture, &project, &rendered, &[]));
    assert!(load(&exported) == load(&rendered), "identical pixels");
}
