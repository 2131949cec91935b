//! End-to-end tests of the method switch: `c2warp deform` for every method, `render
//! --method`, and the bad-input bank of the method's fields.

use crate::support;

use std::ffi::OsStr;
use std::fs;
use std::path::Path;

use support::{c2warp, data, difference, fails, load, ok, os, render_args};

/// The vertices and faces of an OBJ file written by `c2warp deform`.
fn read_obj(path: &Path) -> (Vec<[f64; 2]>, Vec<[usize; 3]>) {
    let text = fs::read_to_string(path).expect("read OBJ");
    let (mut vertices, mut faces) = (Vec::new(), Vec::new());
    for line in text.lines() {
        let fields: Vec<&str> = line.split_whitespace().collect();
        match fields.first() {
            Some(&"v") => {
                assert_eq!(fields.len(), 4, "v x y 0: {line}");
                assert_eq!(fields[3], "0");
                vertices.push([fields[1].parse().expect("x"), fields[2].parse().expect("y")]);
            }
            Some(&"f") => faces.push([1, 2, 3].map(|i| fields[i].parse().expect("index"))),
            Some(&"#") | None => {}
            Some(other) => panic!("unexpected line {other}: {line}"),
        }
    }
    (vertices, faces)
}

fn deform(source: &[&OsStr], rig: &Path, method: Option<&str>, out: &Path) {
    let mut args = vec![os("deform")];
    args.extend_from_slice(source);
    args.extend([os("--rig"), rig.as_os_str(), os("-o"), out.as_os_str()]);
    if let Some(method) = method {
        args.extend([os("--method"), os(method)]);
    }
    ok(&args);
}

/// The strip's rest vertices, in file order.
fn strip_rest() -> Vec<[f64; 2]> {
    let (rest, _) = read_obj(&data("strip.obj"));
    assert_eq!(rest.len(), 52);
    rest
}

#[test]
fn deform_moves_the_mesh_rigidly_under_a_rigid_motion_for_every_method() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rig = dir.path().join("rig.json");
    // Every handle translated by (7, -3) and the bar with them: a rigid motion.
    fs::write(
        &rig,
        r#"{"version":1,"handles":[
            {"type":"point","rest":[0,0],"translate":[7,-3]},
            {"type":"point","rest":[120,30],"translate":[7,-3]},
            {"type":"bar","rest":[[60,0],[60,30]],"pose":[[67,-3],[67,27]]}]}"#,
    )
    .expect("write rig");
    let mesh = data("strip.obj");
    let rest = strip_rest();
    for method in ["c2", "arap", "mls"] {
        let out = dir.path().join(format!("{method}.obj"));
        deform(&[os("--mesh"), mesh.as_os_str()], &rig, Some(method), &out);
        let (moved, faces) = read_obj(&out);
        assert_eq!(moved.len(), rest.len(), "{method}: no vertex inserted");
        assert_eq!(faces.len(), 72);
        for (v, (p, r)) in moved.iter().zip(&rest).enumerate() {
            let (dx, dy) = (p[0] - r[0] - 7.0, p[1] - r[1] + 3.0);
            assert!(
                dx.abs() < 1e-9 && dy.abs() < 1e-9,
                "{method}: vertex {v} at {p:?}, rest {r:?}"
            );
        }
    }
}

#[test]
fn deform_keeps_the_file_order_and_puts_inserted_vertices_after() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rig = dir.path().join("rig.json");
    // One handle on a vertex and one inside a square (inserted), both at rest.
    fs::write(
        &rig,
        r#"{"version":1,"method":"arap","handles":[
            {"type":"point","rest":[0,0]},{"type":"point","rest":[33,17]}]}"#,
    )
    .expect("write rig");
    let rest = strip_rest();
    for method in [None, Some("c2")] {
        let out = dir.path().join("rest.obj");
        deform(
            &[os("--mesh"), data("strip.obj").as_os_str()],
            &rig,
            method,
            &out,
        );
        let (at, faces) = read_obj(&out);
        assert_eq!(at.len(), rest.len() + 1, "{method:?}");
        // At rest, every vertex comes back where the file had it, in its order (up to
        // the solver's rounding).
        let close = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]) < 1e-9;
        for (v, (p, r)) in at.iter().zip(&rest).enumerate() {
            assert!(close(*p, *r), "{method:?}: vertex {v} at {p:?}, file {r:?}");
        }
        assert!(close(at[rest.len()], [33.0, 17.0]), "{:?}", at[rest.len()]);
        assert!(faces.iter().flatten().all(|&i| i >= 1 && i <= at.len()));
        // The inserted vertex split a triangle into three.
        assert_eq!(faces.len(), 74);
    }
}

#[test]
fn deform_from_an_image_gives_the_methods_own_answers() {
    let dir = tempfile::tempdir().expect("temp dir");
    let image = data("dino.png");
    let source = [os("--image"), image.as_os_str()];
    let rig = data("dino-rig.json");
    let methods = ["c2", "arap", "mls"];
    let meshes: Vec<_> = methods
        .iter()
        .map(|method| {
            let out = dir.path().join(format!("{method}.obj"));
            deform(&source, &rig, Some(method), &out);
            read_obj(&out)
        })
        .collect();
    let (a, fa) = &meshes[0];
    for (method, (b, fb)) in methods.iter().zip(&meshes).skip(1) {
        assert_eq!(fa, fb, "{method}: the same mesh");
        assert_eq!(a.len(), b.len());
        let apart = a
            .iter()
            .zip(b)
            .filter(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]) > 0.5)
            .count();
        assert!(
            apart > a.len() / 10,
            "{method} differs from c2: {apart} vertices"
        );
        // The point handle at (250, 120) went by (10, -30): its vertex (the one
        // nearest it, within half a mesh edge) moved exactly so under C² and ARAP,
        // which pin it. MLS interpolates at the handle's own position, which the
        // vertex need not be at, so there it moved so up to the warp's slope over
        // that little distance.
        let tolerance = if *method == "mls" { 1.0 } else { 1e-9 };
        let pinned = a
            .iter()
            .zip(b)
            .position(|(p, q)| {
                (p[0] - 10.0 - 250.0).hypot(p[1] + 30.0 - 120.0) < 4.0
                    && (p[0] - q[0]).hypot(p[1] - q[1]) < tolerance
            })
            .unwrap_or_else(|| panic!("c2 and {method} move the handle's vertex with it"));
        assert!((a[pinned][0] - 260.0).hypot(a[pinned][1] - 90.0) < 4.0);
    }
}

#[test]
/// The expected image comes from this renderer; regenerate it (and look at it) when
/// the mesher or the method change on purpose: `c2warp render tests/data/dino.png
/// --rig tests/data/dino-rig.json --method arap -o tests/data/dino-arap.png`.
fn render_arap_matches_the_golden_image_and_the_flag_overrides_the_rig() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("arap.png");
    ok(&render_args(
        &data("dino.png"),
        &data("dino-rig.json"),
        &out,
        &["--method", "arap"],
    ));
    let got = load(&out);
    let (worst, share) = difference(&got, &load(&data("dino-arap.png")), 8);
    assert!(
        share < 0.002,
        "{:.3}% of channels differ by more than 8 (largest {worst})",
        share * 100.0
    );
    let (_, apart) = difference(&got, &load(&data("dino-warped.png")), 8);
    assert!(apart > 0.005, "ARAP differs from C² ({apart})");
    // A rig that asks for ARAP gives the same picture; --method c2 overrides it.
    let text = fs::read_to_string(data("dino-rig.json")).expect("read");
    let arap_rig = dir.path().join("arap.json");
    fs::write(
        &arap_rig,
        text.replacen(
            "\"version\": 1,",
            "\"version\": 1, \"method\": \"arap\",",
            1,
        ),
    )
    .expect("write");
    let by_rig = dir.path().join("by-rig.png");
    ok(&render_args(&data("dino.png"), &arap_rig, &by_rig, &[]));
    assert_eq!(load(&by_rig), got);
    let overridden = dir.path().join("c2.png");
    ok(&render_args(
        &data("dino.png"),
        &arap_rig,
        &overridden,
        &["--method", "c2"],
    ));
    let (worst, share) = difference(&load(&overridden), &load(&data("dino-warped.png")), 8);
    assert!(share < 0.002, "--method c2 draws C² ({worst})");
}

#[test]
fn painted_rigidity_changes_the_arap_render() {
    let dir = tempfile::tempdir().expect("temp dir");
    let text = fs::read_to_string(data("dino-rig.json")).expect("read");
    let painted = dir.path().join("painted.json");
    fs::write(
        &painted,
        text.replacen(
            "\"version\": 1,",
            r#""version": 1, "method": "arap", "rigidity": [{"stroke": [[150, 180], [200, 200]], "radius": 40, "weight": 10000}],"#,
            1,
        ),
    )
    .expect("write");
    let out = dir.path().join("painted.png");
    ok(&render_args(&data("dino.png"), &painted, &out, &[]));
    let (_, apart) = difference(&load(&out), &load(&data("dino-arap.png")), 8);
    assert!(apart > 0.0005, "the paint changed the picture ({apart})");
}

#[test]
fn bad_method_fields_give_one_clear_line_and_keep_the_old_output() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("out.png");
    fs::write(&out, b"precious").expect("write");
    let handles = r#""handles":[{"type":"point","rest":[60,60]}]"#;
    let cases = [
        (
            r#""method":"lbc3""#,
            r#"method: invalid value: string "lbc3", expected a method: "c2", "arap", "mls" or "lbc""#,
        ),
        (
            r#""method":2"#,
            r#"method: invalid type: integer `2`, expected a method"#,
        ),
        (
            r#""rigidity":[{"stroke":[[1,NaN]],"radius":2,"weight":3}]"#,
            "malformed",
        ),
        (
            r#""rigidity":[{"stroke":[[1,1]],"radius":-2,"weight":3}]"#,
            "radius must be a positive number of pixels, got -2",
        ),
        (
            r#""rigidity":[{"stroke":[[1,1]],"radius":2,"weight":0}]"#,
            "weight must be between 0.001 and 1e8",
        ),
        (
            r#""mls":{"alpha":0}"#,
            "mls.alpha must be a number above 0 and at most 10, got 0",
        ),
        (
            r#""mls":{"variant":"stiff"}"#,
            r#"expected an MLS variant: "rigid", "similarity" or "affine""#,
        ),
    ];
    for (i, (field, expected)) in cases.into_iter().enumerate() {
        let rig = dir.path().join(format!("bad{i}.json"));
        fs::write(&rig, format!(r#"{{"version":1,{field},{handles}}}"#)).expect("write");
        for extra in [&[][..], &["--method", "arap"][..], &["--method", "mls"][..]] {
            let line = fails(&render_args(&data("dino.png"), &rig, &out, extra));
            assert!(line.contains(expected), "{field}: {line}");
        }
    }
    assert_eq!(fs::read(&out).expect("read"), b"precious");
    // An unknown --method is refused by the argument parser, naming the known ones.
    let rig = data("dino-rig.json");
    let refused = c2warp(&render_args(
        &data("dino.png"),
        &rig,
        &out,
        &["--method", "c3"],
    ));
    assert!(!refused.status.success());
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(
        stderr.contains("invalid value 'c3' for '--method <METHOD>'")
            && stderr.contains(&format!("[possible values: {}]", project::Method::names())),
        "{stderr}"
    );
    assert_eq!(fs::read(&out).expect("read"), b"precious");
}

/// The lizard with its hind leg dragged over its body; `depth` is the leg's handle's.
fn folded_rig(dir: &Path, depth: i32) -> std::path::PathBuf {
    let rig = dir.join(format!("fold{depth}.json"));
    fs::write(
        &rig,
        format!(
            r#"{{"version": 1, "density": 4000, "handles": [
                {{"type": "bar", "rest": [[110, 130], [250, 250]]}},
                {{"type": "point", "rest": [440, 238]}},
                {{"type": "point", "rest": [685, 590]}},
                {{"type": "point", "rest": [190, 470], "translate": [140, -150], "depth": {depth}}}]}}"#
        ),
    )
    .expect("write rig");
    rig
}

#[test]
fn handle_depth_decides_what_is_in_front_on_the_cpu_and_the_gpu_alike() {
    let dir = tempfile::tempdir().expect("temp dir");
    let lizard = dir.path().join("lizard.png");
    fs::write(&lizard, pipeline::DEFAULT_IMAGE).expect("write");
    let (front, back) = (folded_rig(dir.path(), 1), folded_rig(dir.path(), -1));
    for method in ["c2", "arap"] {
        let out = |rig: &Path, extra: &[&'static str]| {
            let out = dir.path().join(format!(
                "{method}-{}{}.png",
                rig.file_stem().and_then(|s| s.to_str()).unwrap_or(""),
                extra.len()
            ));
            let mut flags = vec!["--method", method];
            flags.extend_from_slice(extra);
            ok(&render_args(&lizard, rig, &out, &flags));
            load(&out)
        };
        let (in_front, behind) = (out(&front, &[]), out(&back, &[]));
        let (_, share) = difference(&in_front, &behind, 8);
        assert!(
            share > 0.0005,
            "{method}: the leg in front or behind differs ({share})"
        );
        // The GPU draws the triangles in the same order.
        let gpu = out(&front, &["--gpu"]);
        let (worst, share) = difference(&in_front, &gpu, 8);
        assert!(
            share < 0.01,
            "{method}: GPU and CPU differ in {share} (largest {worst})"
        );
        let (_, wrong) = difference(&behind, &gpu, 8);
        assert!(wrong > share, "{method}: the GPU puts the leg in front too");
    }
}

/// Where a cage's vertices go.
type CageMap = fn([f64; 2]) -> [f64; 2];

/// A rig with `method: lbc` and the strip's corners as the cage (posed by `map`).
fn cage_rig(dir: &Path, name: &str, map: impl Fn([f64; 2]) -> [f64; 2]) -> std::path::PathBuf {
    let rest = [[0.0, 0.0], [120.0, 0.0], [120.0, 30.0], [0.0, 30.0]];
    let pose = rest.map(&map);
    let rig = dir.join(name);
    fs::write(
        &rig,
        serde_json::json!({
            "version": 1, "method": "lbc", "handles": [],
            "cage": {"rest": rest, "pose": pose}
        })
        .to_string(),
    )
    .expect("write rig");
    rig
}

#[test]
fn lbc_weights_on_a_given_mesh_are_local_barycentric_coordinates() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rig = cage_rig(dir.path(), "cage.json", |p| p);
    let out = dir.path().join("weights.json");
    let mesh = data("strip.obj");
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
    assert_eq!(json["method"], "lbc");
    assert_eq!(json["samples"], 52);
    assert_eq!(json["converged"], true);
    let nodes = json["nodes"].as_array().expect("nodes");
    // The cage's corners, in the cage's order, found among the file's vertices.
    let vertices: Vec<u64> = nodes
        .iter()
        .map(|n| n["vertex"].as_u64().expect("v"))
        .collect();
    assert_eq!(vertices, [0, 12, 51, 39]);
    let weights = json["weights"].as_array().expect("weights");
    let rest = strip_rest();
    for (v, row) in weights.iter().enumerate() {
        let row: Vec<(usize, f64)> = row
            .as_array()
            .expect("row")
            .iter()
            .map(|p| {
                (
                    p[0].as_u64().expect("i") as usize,
                    p[1].as_f64().expect("w"),
                )
            })
            .collect();
        let sum: f64 = row.iter().map(|p| p.1).sum();
        assert!((sum - 1.0).abs() < 1e-9, "vertex {v}: {sum}");
        assert!(row.iter().all(|p| p.1 > 0.0), "vertex {v}: {row:?}");
        // Linear along the cage's edges: on the bottom edge, only its two corners.
        if rest[v][1] == 0.0 {
            assert!(row.iter().all(|p| p.0 <= 1), "vertex {v}: {row:?}");
            let t = rest[v][0] / 120.0;
            let w1 = row.iter().find(|p| p.0 == 1).map_or(0.0, |p| p.1);
            assert!((w1 - t).abs() < 1e-9, "vertex {v}: {w1} vs {t}");
        }
    }
    for (i, &v) in vertices.iter().enumerate() {
        let row = weights[v as usize].as_array().expect("row");
        assert_eq!(row.len(), 1, "Lagrange at cage vertex {i}");
        assert_eq!(row[0][0], i);
    }
}

#[test]
fn lbc_deform_follows_the_cage() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mesh = data("strip.obj");
    let rest = strip_rest();
    // Every affine motion of the cage is reproduced to rounding, rest included: the
    // compact rows keep partition of unity and linear precision.
    let cases: [(&str, CageMap, f64); 4] = [
        ("rest.json", |p| p, 1e-9),
        ("shift.json", |p| [p[0] + 7.0, p[1] - 3.0], 1e-9),
        (
            "shear.json",
            |p| [1.2 * p[0] + 0.3 * p[1], 0.9 * p[1] + 5.0],
            1e-9,
        ),
        (
            "turn.json",
            |p| {
                let (s, c) = 0.5f64.sin_cos();
                [c * p[0] - s * p[1] + 40.0, s * p[0] + c * p[1] - 10.0]
            },
            1e-9,
        ),
    ];
    for (name, map, tolerance) in cases {
        let rig = cage_rig(dir.path(), name, map);
        let out = dir.path().join("deformed.obj");
        deform(&[os("--mesh"), mesh.as_os_str()], &rig, None, &out);
        let (moved, faces) = read_obj(&out);
        assert_eq!(moved.len(), rest.len());
        assert_eq!(faces.len(), 72);
        for (p, r) in moved.iter().zip(&rest) {
            let q = map(*r);
            assert!(
                (p[0] - q[0]).hypot(p[1] - q[1]) < tolerance,
                "{name}: {r:?} went to {p:?}, not {q:?}"
            );
        }
    }
}

#[test]
fn bad_cages_give_one_clear_line() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("out.obj");
    let mesh = data("strip.obj");
    let cases = [
        (
            r#"{"version":1,"method":"lbc","handles":[]}"#,
            "needs a \"cage\"",
        ),
        (
            r#"{"version":1,"method":"lbc","handles":[],"cage":{"rest":[[0,0],[1,1]]}}"#,
            "a cage needs 3 to 1000 vertices, got 2",
        ),
        (
            r#"{"version":1,"method":"lbc","handles":[],"cage":{"rest":[[0,0],[120,30],[120,0],[0,30]]}}"#,
            "intersect",
        ),
        (
            r#"{"version":1,"method":"lbc","handles":[],"cage":{"rest":[[0,0],[120,0],[120,30]],"pose":[[0,0]]}}"#,
            "pose has 1 points for 3 rest vertices",
        ),
        (
            r#"{"version":1,"method":"lbc","handles":[],"cage":{"rest":[[0,0],[121,0],[121,30],[0,30]]}}"#,
            "not a vertex of the mesh",
        ),
        (
            r#"{"version":1,"method":"lbc","handles":[],"cage":{"rest":[[0,0],[60,0],[60,30],[0,30]]}}"#,
            "lies outside the cage",
        ),
    ];
    for (i, (text, expected)) in cases.into_iter().enumerate() {
        let rig = dir.path().join(format!("bad{i}.json"));
        fs::write(&rig, text).expect("write");
        let line = fails(&[
            os("deform"),
            os("--mesh"),
            mesh.as_os_str(),
            os("--rig"),
            rig.as_os_str(),
            os("-o"),
            out.as_os_str(),
        ]);
        assert!(line.contains(expected), "{text}: {line}");
        assert!(!out.exists());
    }
}

#[test]
fn bench_times_the_cage_solve() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rig = cage_rig(dir.path(), "cage.json", |p| p);
    let mesh = data("strip.obj");
    let out = ok(&[
        os("bench"),
        os("--mesh"),
        mesh.as_os_str(),
        os("--rig"),
        rig.as_os_str(),
    ]);
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    assert_eq!(json["method"], "lbc");
    assert_eq!(json["cage_vertices"], 4);
    for key in [
        "geodesics_ms",
        "factorisation_ms",
        "admm_ms",
        "deform_ms_median",
    ] {
        assert!(
            json[key].as_f64().is_some_and(|t| t >= 0.0),
            "{key}: {json}"
        );
    }
    assert!(json["admm_iterations"].as_u64().is_some_and(|n| n > 0));
    // P(t) rises from near 0 to 1; Q(1) = 1 (every point has some weight).
    let p = json["locality_p"].as_array().expect("P");
    assert_eq!(p.last().and_then(|l| l[1].as_f64()), Some(1.0));
    let q = json["locality_q"].as_array().expect("Q");
    assert_eq!(q.len(), 5);
    assert!((q[1].as_f64().expect("Q(1)") - 1.0).abs() < 1e-9);
}

#[test]
fn render_by_a_cage_moves_the_inside_and_keeps_the_outside() {
    let dir = tempfile::tempdir().expect("temp dir");
    let opaque = data("opaque.png");
    let picture = load(&opaque);
    let (w, h) = (f64::from(picture.width()), f64::from(picture.height()));
    // A quadrilateral in the middle third of the picture.
    let rest = [
        [w / 3.0, h / 3.0],
        [2.0 * w / 3.0, h / 3.0],
        [2.0 * w / 3.0, 2.0 * h / 3.0],
        [w / 3.0, 2.0 * h / 3.0],
    ];
    let write = |name: &str, pose: [[f64; 2]; 4]| {
        let rig = dir.path().join(name);
        fs::write(
            &rig,
            serde_json::json!({
                "version": 1, "method": "lbc", "handles": [], "density": 600,
                "cage": {"rest": rest, "pose": pose}
            })
            .to_string(),
        )
        .expect("write rig");
        rig
    };
    // At rest: the picture comes back (up to the odd pixel on the cage's outline).
    let out = dir.path().join("same.png");
    ok(&render_args(&opaque, &write("rest.json", rest), &out, &[]));
    let (_, share) = difference(&load(&out), &picture, 8);
    assert!(share < 0.01, "{share}");
    // One corner pulled out: pixels far from both cages stay exactly as they were.
    let mut pose = rest;
    pose[2] = [0.8 * w, 0.8 * h];
    let out = dir.path().join("pulled.png");
    ok(&render_args(
        &opaque,
        &write("pulled.json", pose),
        &out,
        &[],
    ));
    let warped = load(&out);
    let (_, moved) = difference(&warped, &picture, 8);
    assert!(moved > 0.01, "the inside moved ({moved})");
    for (x, y, p) in picture.enumerate_pixels() {
        let (fx, fy) = (f64::from(x) / w, f64::from(y) / h);
        if fx < 0.3 || fy < 0.3 || fx > 0.85 || fy > 0.85 {
            assert_eq!(
                warped.get_pixel(x, y),
                p,
                "({x}, {y}) is outside both cages"
            );
        }
    }
    // The GPU draws the same picture through its skinning shader, the compact rows
    // as weight rows (single precision: the odd edge pixel may differ by a step).
    let gpu = dir.path().join("gpu.png");
    ok(&render_args(
        &opaque,
        &write("gpu.json", pose),
        &gpu,
        &["--gpu"],
    ));
    let (worst, share) = difference(&load(&gpu), &warped, 8);
    assert!(
        share < 0.002,
        "{share} of the pixels differ, by up to {worst}"
    );
}

/// The editor's export of an LBC project (a cage on the built-in lizard, solved and
/// posed) is what `c2warp render` draws for the project the editor saved: the same
/// count of mesh vertices inside the cage (`lbc.density`, ahead of the picture's
/// `density` the editor also writes), the same solve, the same warp.
#[test]
fn the_editors_cage_export_is_what_render_draws_for_its_saved_project() {
    let dir = tempfile::tempdir().expect("temp dir");
    let picture = dir.path().join("lizard.png");
    fs::write(&picture, pipeline::DEFAULT_IMAGE).expect("write the picture");
    let mut doc = editor::Document::built_in().expect("the built-in picture");
    let rest = vec![
        [220.0, 200.0],
        [390.0, 190.0],
        [450.0, 300.0],
        [390.0, 430.0],
        [240.0, 430.0],
        [170.0, 320.0],
    ];
    doc.apply(editor::Edit::Cage {
        rest: rest.clone(),
        vertices: 300,
    })
    .expect("a cage");
    doc.solve_cage(&mut |_| true).expect("solved");
    let mut pose = rest.clone();
    pose[1] = [430.0, 160.0];
    pose[3] = [370.0, 460.0];
    doc.apply(editor::Edit::CagePose(pose)).expect("posed");
    let mut app = editor::EditorApp::with_document(doc);
    let project = dir.path().join("project.json");
    app.save_to(&project);
    let exported = dir.path().join("editor.png");
    app.export_to(&exported);
    assert!(exported.exists(), "{:?}", app.message);
    let saved = fs::read_to_string(&project).expect("saved");
    assert!(saved.contains(r#""density": 300"#), "{saved}");

    let rendered = dir.path().join("render.png");
    ok(&render_args(&picture, &project, &rendered, &[]));
    let (worst, share) = difference(&load(&exported), &load(&rendered), 0);
    assert!(
        share < 1e-4,
        "{share} of the pixels differ, by up to {worst}"
    );
    let (_, warped) = difference(&load(&rendered), &load(&picture), 8);
    assert!(warped > 0.001, "the cage moved the picture ({warped})");
}

#[test]
fn cage_writes_a_rig_whose_cage_encloses_the_picture_and_renders_it_unchanged_at_rest() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rig = dir.path().join("cage.json");
    let picture = data("dino.png");
    ok(&[
        os("cage"),
        picture.as_os_str(),
        os("--vertices"),
        os("12"),
        os("-o"),
        rig.as_os_str(),
    ]);
    let project =
        project::Project::from_json(&fs::read_to_string(&rig).expect("read")).expect("a valid rig");
    assert_eq!(project.method, project::Method::Lbc);
    let cage = project.cage.expect("a cage");
    assert_eq!(cage.rest.len(), 12);
    assert!(cage.pose.is_none());
    // The picture, named so that the rig finds it from its own folder.
    let named = rig
        .parent()
        .expect("a folder")
        .join(project.image.expect("an image"));
    assert_eq!(
        named.canonicalize().expect("exists"),
        picture.canonicalize().expect("exists")
    );
    // Every visible pixel lies inside the cage (its centre at least).
    let image = load(&picture);
    let ring: Vec<glam::DVec2> = cage.rest.iter().map(|&p| glam::DVec2::from(p)).collect();
    let polygon = lbc::Cage::new(ring).expect("a simple polygon");
    for (x, y, p) in image.enumerate_pixels() {
        if p[3] > 0 {
            let c = glam::DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
            assert!(polygon.contains(c), "({x}, {y}) is outside the cage");
        }
    }
    // At rest the cage gives the picture back exactly.
    let out = dir.path().join("rest.png");
    ok(&render_args(&picture, &rig, &out, &["--density", "800"]));
    assert_eq!(load(&out), image);
    // A rig to start from keeps its handles; the cage and the method are new.
    let with = dir.path().join("with.json");
    let original = data("dino-rig.json");
    ok(&[
        os("cage"),
        picture.as_os_str(),
        os("--rig"),
        original.as_os_str(),
        os("-o"),
        with.as_os_str(),
    ]);
    let kept = project::Project::from_json(&fs::read_to_string(&with).expect("read"))
        .expect("a valid rig");
    let before = project::Project::from_json(&fs::read_to_string(&original).expect("read"))
        .expect("a valid rig");
    assert_eq!(kept.handles, before.handles);
    assert_eq!(kept.cage.expect("a cage").rest.len(), 16);
    // Bad requests: one line, nothing written.
    let refused = dir.path().join("refused.json");
    let line = fails(&[
        os("cage"),
        picture.as_os_str(),
        os("--vertices"),
        os("2"),
        os("-o"),
        refused.as_os_str(),
    ]);
    assert!(line.contains("from 3 to 1,000"), "{line}");
    assert!(!refused.exists());
}

#[test]
fn cages_too_big_or_too_thin_to_solve_are_refused_at_once() {
    let dir = tempfile::tempdir().expect("temp dir");
    let picture = dir.path().join("square.png");
    image::RgbaImage::from_pixel(256, 256, image::Rgba([200, 100, 50, 255]))
        .save(&picture)
        .expect("write");
    let out = dir.path().join("out.png");
    // 64 cage vertices around a disc, 200,000 mesh vertices asked inside: minutes.
    let ring: Vec<[f64; 2]> = (0..64)
        .map(|k| {
            let a = f64::from(k) / 64.0 * std::f64::consts::TAU;
            [128.0 + 100.0 * a.cos(), 128.0 + 100.0 * a.sin()]
        })
        .collect();
    let rig = dir.path().join("big.json");
    fs::write(
        &rig,
        serde_json::json!({
            "version": 1, "method": "lbc", "handles": [],
            "cage": {"rest": ring}, "lbc": {"density": 200000}
        })
        .to_string(),
    )
    .expect("write");
    let clock = std::time::Instant::now();
    let line = fails(&render_args(&picture, &rig, &out, &[]));
    assert!(line.contains("would take minutes to solve"), "{line}");
    assert!(
        line.contains("ask for at most 46875 mesh vertices"),
        "{line}"
    );
    assert!(clock.elapsed().as_secs() < 10, "refused before meshing");
    // A 60 px square cage asked for 4,000,000 vertices inside: capped at 4 a pixel
    // (14,400), so it solves in seconds.
    let rig = dir.path().join("dense.json");
    fs::write(
        &rig,
        r#"{"version":1,"method":"lbc","handles":[],"cage":{"rest":[[48,48],[108,48],[108,108],[48,108]]}}"#,
    )
    .expect("write");
    let clock = std::time::Instant::now();
    ok(&render_args(
        &picture,
        &rig,
        &out,
        &["--density", "4000000"],
    ));
    assert!(clock.elapsed().as_secs() < 60, "{:?}", clock.elapsed());
    // A sliver 216 px long and a billionth of a pixel wide.
    let rig = dir.path().join("sliver.json");
    fs::write(
        &rig,
        r#"{"version":1,"method":"lbc","handles":[],"cage":{"rest":[[20,100],[236,100],[236,100.000000001],[20,100.000000001]]}}"#,
    )
    .expect("write");
    let line = fails(&render_args(&picture, &rig, &out, &[]));
    assert!(line.contains("the cage is a sliver"), "{line}");
}

#[test]
fn a_grown_canvas_holds_the_whole_warp_for_every_method() {
    let dir = tempfile::tempdir().expect("temp dir");
    let picture = data("dino.png");
    let (w, h) = load(&picture).dimensions();
    // The tail's handle pulled 120 px past the right edge.
    let rig = dir.path().join("out.json");
    fs::write(
        &rig,
        r#"{"version":1,"density":3000,"handles":[
            {"type":"point","rest":[60,60]},
            {"type":"point","rest":[150,250]},
            {"type":"point","rest":[250,120],"translate":[140,-20]}]}"#,
    )
    .expect("write");
    for method in ["c2", "arap"] {
        let kept = dir.path().join(format!("{method}-keep.png"));
        let grown = dir.path().join(format!("{method}-fit.png"));
        let gpu = dir.path().join(format!("{method}-fit-gpu.png"));
        ok(&render_args(&picture, &rig, &kept, &["--method", method]));
        ok(&render_args(
            &picture,
            &rig,
            &grown,
            &["--method", method, "--canvas", "fit"],
        ));
        ok(&render_args(
            &picture,
            &rig,
            &gpu,
            &["--method", method, "--canvas", "fit", "--gpu"],
        ));
        let (kept, grown, gpu) = (load(&kept), load(&grown), load(&gpu));
        assert_eq!(kept.dimensions(), (w, h));
        assert!(grown.width() > w + 100 && grown.height() >= h, "{method}");
        // The grown canvas starts where the warped mesh reaches furthest up and left
        // (or at the picture's corner): the picture's frame sits there in it, with the
        // same pixels, and more visible ones around.
        let mesh = dir.path().join(format!("{method}.obj"));
        deform(
            &[os("--image"), picture.as_os_str()],
            &rig,
            Some(method),
            &mesh,
        );
        let (moved, _) = read_obj(&mesh);
        let least = |k: usize| {
            moved
                .iter()
                .map(|p| p[k] as f32)
                .fold(0.0f32, f32::min)
                .floor()
        };
        let (ox, oy) = (-least(0) as u32, -least(1) as u32);
        let frame = image::imageops::crop_imm(&grown, ox, oy, w, h).to_image();
        assert!(
            frame == kept,
            "{method}: the kept canvas lies in the grown one at ({ox}, {oy})"
        );
        let visible = |img: &image::RgbaImage| img.pixels().filter(|p| p[3] > 0).count();
        assert!(visible(&grown) > visible(&kept) + 1000, "{method}");
        let (worst, share) = difference(&grown, &gpu, 8);
        assert!(share < 0.01, "{method}: GPU {share} (largest {worst})");
    }
    // At rest, a grown canvas is the picture's own.
    let rest = dir.path().join("rest.json");
    fs::write(
        &rest,
        r#"{"version":1,"density":3000,"handles":[],"canvas":"fit"}"#,
    )
    .expect("write");
    let out = dir.path().join("rest.png");
    ok(&render_args(&picture, &rest, &out, &[]));
    assert_eq!(load(&out).dimensions(), (w, h));
    let refused = c2warp(&render_args(&picture, &rest, &out, &["--canvas", "huge"]));
    assert!(!refused.status.success());
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(
        stderr.contains("unknown canvas \"huge\" (known: keep, fit)"),
        "{stderr}"
    );
}

/// Every method draws a 16-bit picture in 16 bits on the CPU (the low bits 8 bits
/// cannot hold survive), through the one drawing path of the method seam.
#[test]
fn every_method_renders_a_sixteen_bit_picture_in_sixteen_bits() {
    let dir = tempfile::tempdir().expect("temp dir");
    let narrow = load(&data("opaque.png"));
    let (w, h) = narrow.dimensions();
    let wide = image::ImageBuffer::<image::Rgba<u16>, Vec<u16>>::from_fn(w, h, |x, y| {
        let p = narrow.get_pixel(x, y).0;
        let low = ((x + y) % 64) as u16;
        image::Rgba(p.map(|c| (u16::from(c) * 257).saturating_sub(low)))
    });
    let source = dir.path().join("wide.png");
    wide.save(&source).expect("save a 16-bit PNG");
    let (fw, fh) = (f64::from(w), f64::from(h));
    let rest = [
        [fw / 4.0, fh / 4.0],
        [3.0 * fw / 4.0, fh / 4.0],
        [3.0 * fw / 4.0, 3.0 * fh / 4.0],
        [fw / 4.0, 3.0 * fh / 4.0],
    ];
    let mut pose = rest;
    pose[2] = [0.8 * fw, 0.85 * fh];
    let rig = dir.path().join("rig.json");
    fs::write(
        &rig,
        serde_json::json!({
            "version": 1, "density": 800,
            "handles": [
                {"type": "point", "rest": [fw * 0.2, fh * 0.2]},
                {"type": "point", "rest": [fw * 0.7, fh * 0.6], "translate": [9.0, -6.0]}
            ],
            "cage": {"rest": rest, "pose": pose}, "lbc": {"density": 400}
        })
        .to_string(),
    )
    .expect("write rig");
    for method in project::Method::ALL {
        let out = dir.path().join(format!("{}.png", method.name()));
        ok(&render_args(
            &source,
            &rig,
            &out,
            &["--method", method.name()],
        ));
        let got = image::open(&out).expect("open");
        assert_eq!(got.color(), image::ColorType::Rgba16, "{}", method.name());
        let got = got.into_rgba16();
        assert!(
            got.as_raw().iter().any(|&c| c % 257 != 0),
            "{}: low bits survive",
            method.name()
        );
        // And it moved something.
        assert_ne!(got.as_raw(), wide.as_raw(), "{}", method.name());
    }
}

#[test]
fn mls_reads_its_variant_from_the_rig_and_reproduces_that_class() {
    // The handles moved by one similarity (turned 0.4 rad, scaled 1.3, shifted): the
    // similarity variant moves every vertex of the strip by it exactly; the rigid
    // one cannot scale, so it does not.
    let (turn, scale, shift) = (0.4f64, 1.3, [12.0, -5.0]);
    let map = |[x, y]: [f64; 2]| {
        let (s, c) = turn.sin_cos();
        [
            scale * (c * x - s * y) + shift[0],
            scale * (s * x + c * y) + shift[1],
        ]
    };
    let dir = tempfile::tempdir().expect("temp dir");
    let points = [[0.0, 0.0], [120.0, 30.0], [30.0, 25.0]];
    let bar = [[60.0, 0.0], [60.0, 30.0]];
    let handles: Vec<serde_json::Value> = points
        .iter()
        .map(|&p| {
            let q = map(p);
            serde_json::json!({"type": "point", "rest": p, "translate": [q[0] - p[0], q[1] - p[1]]})
        })
        .chain([serde_json::json!({"type": "bar", "rest": bar, "pose": bar.map(map)})])
        .collect();
    let rest = strip_rest();
    for (variant, reproduces) in [("similarity", true), ("rigid", false)] {
        let rig = dir.path().join(format!("{variant}.json"));
        let file = serde_json::json!({
            "version": 1, "method": "mls", "handles": handles,
            "mls": {"alpha": 1.5, "variant": variant}
        });
        fs::write(&rig, file.to_string()).expect("write rig");
        let out = dir.path().join(format!("{variant}.obj"));
        deform(
            &[os("--mesh"), data("strip.obj").as_os_str()],
            &rig,
            None,
            &out,
        );
        let (moved, _) = read_obj(&out);
        let worst = moved
            .iter()
            .zip(&rest)
            .map(|(p, r)| {
                let want = map(*r);
                (p[0] - want[0]).hypot(p[1] - want[1])
            })
            .fold(0.0, f64::max);
        assert_eq!(
            worst < 1e-9,
            reproduces,
            "{variant}: {worst} px from the similarity"
        );
    }
}

#[test]
fn mls_renders_and_benches_through_the_seam() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rig = data("dino-rig.json");
    let image = data("dino.png");
    let out = ok(&[
        os("bench"),
        os("--image"),
        image.as_os_str(),
        os("--rig"),
        rig.as_os_str(),
        os("--method"),
        os("mls"),
    ]);
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    assert_eq!(json["method"], "mls", "{json}");
    assert_eq!(json["variant"], "rigid");
    assert_eq!(json["alpha"], 1.0);
    assert_eq!(json["real_handles"], 4);
    assert!(json["samples"].as_u64().is_some_and(|n| n > 1000), "{json}");
    for key in ["precompute_ms", "pose_ms_median", "pose_ms_p90"] {
        assert!(
            json[key].as_f64().is_some_and(|t| t >= 0.0),
            "{key}: {json}"
        );
    }
    // The render differs from C²'s (the weights are Euclidean, not the shape's) but
    // not wildly: the same handles pull the same way, so most channels agree.
    let (mls, c2) = (dir.path().join("mls.png"), dir.path().join("c2.png"));
    ok(&render_args(&image, &rig, &mls, &["--method", "mls"]));
    ok(&render_args(&image, &rig, &c2, &["--method", "c2"]));
    let (a, b) = (load(&mls), load(&c2));
    assert_eq!(a.dimensions(), b.dimensions());
    let (worst, over) = difference(&a, &b, 8);
    assert!(worst > 8 && over < 0.2, "{worst}, {over}");
}
