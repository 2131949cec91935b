//! End-to-end tests of `c2warp animate`: every frame is what `c2warp render` draws for
//! the rig posed at its time, for every method; the animated files hold the same
//! frames as the PNG sequence; bad requests fail at once and leave files alone.

use crate::support;

use std::fs;
use std::path::{Path, PathBuf};

use image::AnimationDecoder as _;
use support::{data, fails, ok, os, render_args};

/// A rig on `opaque.png` (96 × 64) for `method`, with three point handles and a bar, a
/// cage around the middle, and three keys (at 0, 0.5 and 1 s; smooth, so that the
/// frames between keys are curves, not blends of two). Small meshes keep it quick.
fn animated_rig(dir: &Path, method: &str) -> PathBuf {
    let rest_cage = [[24.0, 16.0], [72.0, 16.0], [72.0, 48.0], [24.0, 48.0]];
    let rig = serde_json::json!({
        "version": 1,
        "method": method,
        "image": data("opaque.png"),
        "density": 300,
        "arap": {"density": 200},
        "lbc": {"density": 200},
        "handles": [
            {"type": "point", "rest": [20, 20]},
            {"type": "point", "rest": [76, 44], "depth": 1},
            {"type": "bar", "rest": [[30, 52], [60, 52]]}
        ],
        "cage": {"rest": rest_cage},
        "animation": {
            "fps": 4,
            "interpolation": "smooth",
            "keys": [
                {"time": 0, "pose": [{}, {}, {"pose": [[30, 52], [60, 52]]}]},
                {"time": 0.5, "pose": [
                    {"translate": [3, -2], "rotate": 0.2},
                    {"translate": [-4, 3], "scale": 1.1},
                    {"pose": [[31, 50], [62, 55]]}],
                 "cage": [[24, 16], [76, 14], [74, 50], [24, 48]]},
                {"time": 1, "pose": [
                    {"translate": [-2, 2]},
                    {"translate": [5, -3], "rotate": -0.3},
                    {"pose": [[28, 53], [59, 51]]}],
                 "cage": [[22, 18], [72, 16], [70, 46], [26, 48]]}
            ]
        }
    });
    let path = dir.join(format!("{method}.json"));
    fs::write(&path, rig.to_string()).expect("write rig");
    path
}

/// `c2warp animate RIG -o OUT` followed by `extra`.
fn animate(rig: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec![os("animate"), rig.as_os_str(), os("-o"), out.as_os_str()];
    args.extend(extra.iter().map(|e| os(e)));
    ok(&args)
}

/// The frames of a PNG sequence, in order.
fn sequence(dir: &Path) -> Vec<PathBuf> {
    let mut frames: Vec<PathBuf> = fs::read_dir(dir)
        .expect("list the sequence")
        .map(|e| e.expect("entry").path())
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("frame_"))
        })
        .collect();
    frames.sort();
    frames
}

/// The frames of an animated PNG, WebP or GIF, decoded.
fn decoded(path: &Path) -> Vec<image::RgbaImage> {
    let file = std::io::BufReader::new(fs::File::open(path).expect("open"));
    let frames = match path.extension().and_then(|e| e.to_str()) {
        Some("png") => image::codecs::png::PngDecoder::new(file)
            .expect("a PNG")
            .apng()
            .expect("an animated PNG")
            .into_frames(),
        Some("webp") => image::codecs::webp::WebPDecoder::new(file)
            .expect("a WebP")
            .into_frames(),
        _ => image::codecs::gif::GifDecoder::new(file)
            .expect("a GIF")
            .into_frames(),
    };
    frames.map(|f| f.expect("a frame").into_buffer()).collect()
}

#[test]
fn every_frame_is_what_render_draws_for_the_pose_at_its_time_for_every_method() {
    let dir = tempfile::tempdir().expect("temp dir");
    for method in project::Method::ALL {
        let name = method.name();
        let rig = animated_rig(dir.path(), name);
        // A trailing separator names a folder: a PNG sequence.
        let out = dir.path().join(format!("{name}-frames/"));
        animate(&rig, &out, &[]);
        let frames = sequence(&out);
        // 0 to 1 s at 4 frames a second: the three keys and the frames between them.
        let names: Vec<_> = frames
            .iter()
            .map(|f| f.file_name().expect("a name").to_string_lossy().to_string())
            .collect();
        assert_eq!(
            names,
            (0..5)
                .map(|i| format!("frame_{i:05}.png"))
                .collect::<Vec<_>>()
        );
        let project = pipeline::load_project(&rig).expect("the rig");
        let mut previous: Option<Vec<u8>> = None;
        for (i, frame) in frames.iter().enumerate() {
            let time = i as f64 / 4.0;
            let posed = dir.path().join(format!("{name}-posed-{i}.json"));
            fs::write(&posed, animation::posed_at(&project, time).to_json()).expect("write");
            let single = dir.path().join(format!("{name}-{i}.png"));
            ok(&render_args(&data("opaque.png"), &posed, &single, &[]));
            let got = fs::read(frame).expect("read frame");
            assert!(
                got == fs::read(&single).expect("read render"),
                "{name}: frame {i} ({time} s) is not what render draws"
            );
            assert_ne!(previous.as_ref(), Some(&got), "{name}: frame {i} moved");
            previous = Some(got);
        }
    }
}

#[test]
fn animated_files_hold_the_frames_of_the_sequence() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rig = animated_rig(dir.path(), "c2");
    let frames = dir.path().join("frames/");
    animate(&rig, &frames, &["--fps", "8", "--from", "0.25"]);
    let expected: Vec<image::RgbaImage> =
        sequence(&frames).iter().map(|f| support::load(f)).collect();
    // 0.25 s to 1 s at 8 frames a second.
    assert_eq!(expected.len(), 7);
    for name in ["walk.png", "walk.webp"] {
        let out = dir.path().join(name);
        animate(&rig, &out, &["--fps", "8", "--from", "0.25"]);
        let got = decoded(&out);
        assert_eq!(got.len(), expected.len(), "{name}");
        for (i, (a, b)) in got.iter().zip(&expected).enumerate() {
            assert!(a == b, "{name}: frame {i} differs from the sequence's");
        }
    }
    // A GIF has a palette of 256 colours and one bit of alpha: its frames are near
    // (this picture has 5,229 colours: NeuQuant misses them by 10 a channel on average).
    let gif = dir.path().join("walk.gif");
    animate(&rig, &gif, &["--fps", "8", "--from", "0.25"]);
    let got = decoded(&gif);
    assert_eq!(got.len(), expected.len());
    for (i, (a, b)) in got.iter().zip(&expected).enumerate() {
        assert_eq!(a.dimensions(), b.dimensions());
        let total: u64 = a
            .as_raw()
            .iter()
            .zip(b.as_raw())
            .map(|(x, y)| u64::from(x.abs_diff(*y)))
            .sum();
        let mean = total as f64 / a.as_raw().len() as f64;
        assert!(mean < 16.0, "GIF frame {i}: mean difference {mean}");
    }
}

#[test]
fn the_project_names_its_picture_and_image_overrides_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    // A project beside its picture, naming it relatively (as the editor saves it).
    fs::copy(data("opaque.png"), dir.path().join("pic.png")).expect("copy");
    let mut rig: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(animated_rig(dir.path(), "mls")).expect("read"))
            .expect("JSON");
    rig["image"] = "pic.png".into();
    let project = dir.path().join("project.json");
    fs::write(&project, rig.to_string()).expect("write");
    let first = dir.path().join("first.png");
    animate(&project, &first, &["--to", "0"]);
    assert_eq!(decoded(&first).len(), 1);
    // --image overrides it; without either, a clear line.
    let other = dir.path().join("other.png");
    let blank = dir.path().join("blank.png");
    image::RgbaImage::from_pixel(96, 64, image::Rgba([9, 9, 9, 255]))
        .save(&blank)
        .expect("save");
    animate(
        &project,
        &other,
        &["--to", "0", "--image", blank.to_str().expect("UTF-8")],
    );
    assert_ne!(decoded(&other), decoded(&first));
    rig.as_object_mut().expect("an object").remove("image");
    fs::write(&project, rig.to_string()).expect("write");
    let line = fails(&[
        os("animate"),
        project.as_os_str(),
        os("-o"),
        other.as_os_str(),
    ]);
    assert!(
        line.contains("names no picture") && line.contains("--image"),
        "{line}"
    );
}

#[test]
fn bad_requests_fail_at_once_with_one_line_and_leave_the_output_alone() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rig = animated_rig(dir.path(), "c2");
    let out = dir.path().join("out.png");
    fs::write(&out, b"keep me").expect("write");
    let no_keys = dir.path().join("still.json");
    fs::write(
        &no_keys,
        r#"{"version":1,"handles":[{"type":"point","rest":[20,20]}]}"#,
    )
    .expect("write");
    let cases: &[(&Path, &str, &[&str], &str)] = &[
        (
            &no_keys,
            "out.png",
            &[],
            "has no animation keys: set keys in the editor's timeline",
        ),
        (
            &rig,
            "out.png",
            &["--from", "0.8", "--to", "0.2"],
            "would run backwards: from 0.8 s to 0.2 s",
        ),
        (
            &rig,
            "out.png",
            &["--from", "2"],
            "from 2 s to 1 s (the last key's time; give an end time)",
        ),
        (
            &rig,
            "out.png",
            &["--from", "-1"],
            "'--from <FROM>': expected a number from 0 to 86,400 s",
        ),
        (
            &rig,
            "out.png",
            &["--to", "nan"],
            "'--to <TO>': expected a number from 0 to 86,400 s",
        ),
        (
            &rig,
            "out.png",
            &["--fps", "0"],
            "'--fps <FPS>': expected a number above 0 to 240 frames per second",
        ),
        (
            &rig,
            "out.png",
            &["--fps", "300"],
            "invalid value '300' for '--fps <FPS>'",
        ),
        (&rig, "out.png", &["--fps", "inf"], "invalid value 'inf'"),
        (
            &rig,
            "out.gif",
            &["--fps", "60"],
            "a GIF plays at most 50 frames per second, not 60",
        ),
        (
            &rig,
            "out.jpg",
            &[],
            "must end in .png (animated PNG), .webp (animated WebP) or .gif",
        ),
        (&rig, "missing/out.png", &[], "missing"),
    ];
    for (rig, name, extra, expected) in cases {
        let target = dir.path().join(name);
        let mut args = vec![os("animate"), rig.as_os_str(), os("-o"), target.as_os_str()];
        args.extend(extra.iter().map(|e| os(e)));
        let line = fails(&args);
        assert!(line.contains(expected), "{extra:?}: {line}");
    }
    assert_eq!(fs::read(&out).expect("read"), b"keep me");
    // Nothing else was left in the folder (no temporary files, no sequence).
    let mut left: Vec<_> = fs::read_dir(dir.path())
        .expect("list")
        .map(|e| e.expect("entry").file_name())
        .collect();
    left.sort();
    assert_eq!(left, ["c2.json", "out.png", "still.json"]);
}

#[test]
fn with_gpu_every_frame_is_what_render_draws_with_gpu() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rig = animated_rig(dir.path(), "c2");
    let out = dir.path().join("gpu/");
    // One GPU context for the frames at 0.5 s (a key) and 0.75 s (between keys).
    animate(&rig, &out, &["--gpu", "--from", "0.5"]);
    let frames = sequence(&out);
    assert_eq!(frames.len(), 3);
    let project = pipeline::load_project(&rig).expect("the rig");
    for (i, frame) in frames.iter().enumerate().take(2) {
        let time = 0.5 + i as f64 / 4.0;
        let posed = dir.path().join(format!("posed-{i}.json"));
        fs::write(&posed, animation::posed_at(&project, time).to_json()).expect("write");
        let single = dir.path().join(format!("{i}.png"));
        ok(&render_args(
            &data("opaque.png"),
            &posed,
            &single,
            &["--gpu"],
        ));
        // The same adapter draws the same pixels (lavapipe, here and in CI).
        let (worst, share) = support::difference(&support::load(frame), &support::load(&single), 0);
        assert!(
            worst == 0,
            "frame {i}: {share} of the channels differ, by up to {worst}"
        );
    }
}

/// The names of the hidden temporary files in `dir`.
fn temporaries(dir: &Path) -> Vec<String> {
    fs::read_dir(dir)
        .expect("list")
        .map(|e| e.expect("entry").file_name().to_string_lossy().to_string())
        .filter(|n| n.ends_with(".tmp"))
        .collect()
}

/// Starts `c2warp animate` on the lizard's walk at 240 frames a second (hundreds of
/// frames: long enough to be interrupted) into `out`, and waits until it has a
/// temporary file in `watch`.
#[cfg(unix)]
fn start_a_long_animation(out: &Path, watch: &Path) -> std::process::Child {
    let walk = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/lizard-walk.json");
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_c2warp"))
        .args([os("animate"), walk.as_os_str(), os("-o"), out.as_os_str()])
        .args(["--fps", "240"])
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("start c2warp");
    let start = std::time::Instant::now();
    while temporaries(watch).is_empty() {
        assert!(
            start.elapsed() < std::time::Duration::from_secs(120),
            "no temporary file appeared"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child
}

/// Sends `signal` to `child` and waits for it to end.
#[cfg(unix)]
fn signal(mut child: std::process::Child, signal: &str) -> std::process::ExitStatus {
    let sent = std::process::Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(sent.success());
    child.wait().expect("wait")
}

#[cfg(unix)]
#[test]
fn an_interrupted_animation_keeps_the_old_output_and_leaves_no_temporary_file() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("walk.png");
    fs::write(&out, b"the old animation").expect("write");
    for sig in ["-TERM", "-INT"] {
        let child = start_a_long_animation(&out, dir.path());
        let status = signal(child, sig);
        assert!(!status.success(), "{sig}: {status}");
        assert_eq!(temporaries(dir.path()), Vec::<String>::new(), "{sig}");
        assert_eq!(fs::read(&out).expect("read"), b"the old animation");
    }
    // A PNG sequence: its frames' temporary files go too.
    let frames = dir.path().join("frames");
    fs::create_dir(&frames).expect("mkdir");
    let status = signal(start_a_long_animation(&frames, &frames), "-TERM");
    assert!(!status.success());
    assert_eq!(temporaries(&frames), Vec::<String>::new());
    // Killed outright, a run cannot clean up; the next run into the same place does.
    let child = start_a_long_animation(&out, dir.path());
    signal(child, "-KILL");
    assert_eq!(temporaries(dir.path()).len(), 1);
    let rig = animated_rig(dir.path(), "c2");
    animate(&rig, &out, &["--to", "0.25"]);
    assert_eq!(temporaries(dir.path()), Vec::<String>::new());
}

#[test]
fn a_folder_of_frames_never_loses_a_file_it_did_not_write() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rig = animated_rig(dir.path(), "c2");
    let frames = dir.path().join("frames/");
    animate(&rig, &frames, &[]);
    assert_eq!(sequence(&frames).len(), 5);
    // A frame of its own as the picture: the frames would replace it.
    let first = frames.join("frame_00000.png");
    let before = fs::read(&first).expect("read");
    let line = fails(&[
        os("animate"),
        rig.as_os_str(),
        os("--image"),
        first.as_os_str(),
        os("-o"),
        frames.as_os_str(),
    ]);
    assert!(line.contains("one of the inputs"), "{line}");
    assert_eq!(fs::read(&first).expect("read"), before);
    // Someone else's frame in the folder: refused, nothing touched.
    fs::write(frames.join("frame_00030.png"), b"theirs").expect("write");
    let line = fails(&[os("animate"), rig.as_os_str(), os("-o"), frames.as_os_str()]);
    assert!(line.contains("frame_00030.png"), "{line}");
    assert_eq!(
        fs::read(frames.join("frame_00030.png")).expect("kept"),
        b"theirs"
    );
    fs::remove_file(frames.join("frame_00030.png")).expect("remove");
    // A shorter run replaces its own earlier frames and removes the rest of them.
    animate(&rig, &frames, &["--to", "0.5"]);
    assert_eq!(sequence(&frames).len(), 3);
}

#[test]
fn the_sample_characters_wave_animates_its_parts() {
    let dir = tempfile::tempdir().expect("temp dir");
    let assets = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets");
    let rig = assets.join("puppet-wave.json");
    let project = project::Project::from_json(&fs::read_to_string(&rig).expect("the rig"))
        .expect("a rig file");
    assert!(project.parts.is_some(), "drawn as parts");
    // Two frames a second over the wave's middle: the arm is up, then down again.
    let frames = dir.path().join("frames/");
    animate(
        &rig,
        &frames,
        &["--fps", "2", "--from", "1.5", "--to", "3.5"],
    );
    let shots: Vec<image::RgbaImage> = sequence(&frames)
        .iter()
        .map(|p| image::open(p).expect("a frame").to_rgba8())
        .collect();
    assert_eq!(shots.len(), 5);
    let differ = |a: &image::RgbaImage, b: &image::RgbaImage| {
        a.pixels().zip(b.pixels()).filter(|(p, q)| p != q).count()
    };
    assert!(differ(&shots[0], &shots[2]) > 1000, "the character moves");
    // Each frame is `render` of the rig posed at its time.
    let at = dir.path().join("at-2.5.json");
    let mut posed = animation::posed_at(&project, 2.5);
    posed.image = Some(assets.join("puppet.ora"));
    fs::write(&at, posed.to_json()).expect("the posed rig");
    let png = dir.path().join("at-2.5.png");
    ok(&[os("render"), at.as_os_str(), os("-o"), png.as_os_str()]);
    assert_eq!(
        differ(&image::open(&png).expect("render").to_rgba8(), &shots[2]),
        0,
        "the frame at 2.5 s is render of the pose at 2.5 s"
    );
}
