//! Helpers shared by the end-to-end tests: running the binary, comparing images.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The workspace's `tests/data` folder.
pub fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data")
        .join(name)
}

/// Runs `c2warp` with the given arguments.
pub fn c2warp(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_c2warp"))
        .args(args)
        .output()
        .expect("the c2warp binary runs")
}

/// Runs `c2warp` and expects success.
pub fn ok(args: &[&std::ffi::OsStr]) -> Output {
    let out = c2warp(args);
    assert!(
        out.status.success(),
        "c2warp {:?} failed: {}",
        args,
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Runs `c2warp`, expects failure with one clear line on stderr (no panic), and
/// returns that line.
pub fn fails(args: &[&std::ffi::OsStr]) -> String {
    let out = c2warp(args);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!out.status.success(), "c2warp {args:?} should fail");
    assert!(
        !stderr.contains("panicked"),
        "c2warp {args:?} panicked: {stderr}"
    );
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "one line of error expected, got: {stderr}");
    assert!(lines[0].starts_with("error: "), "{stderr}");
    // Each reason once: no part of the line between ": " says again what another says.
    let parts: Vec<&str> = lines[0].split(": ").filter(|p| p.len() >= 8).collect();
    for (i, part) in parts.iter().enumerate() {
        assert!(
            !parts[..i].contains(part),
            "the line says {part:?} twice: {stderr}"
        );
    }
    lines[0].to_string()
}

/// A command-line argument.
pub fn os(s: &str) -> &std::ffi::OsStr {
    std::ffi::OsStr::new(s)
}

/// The arguments of `c2warp render IMAGE --rig RIG -o OUT` followed by `extra`.
pub fn render_args<'a>(
    image: &'a Path,
    rig: &'a Path,
    out: &'a Path,
    extra: &[&'a str],
) -> Vec<&'a std::ffi::OsStr> {
    let mut args: Vec<&std::ffi::OsStr> = vec![
        "render".as_ref(),
        image.as_os_str(),
        "--rig".as_ref(),
        rig.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ];
    args.extend(extra.iter().map(|e| std::ffi::OsStr::new(*e)));
    args
}

/// Per-channel differences between two images of the same size: (largest, share of
/// channels differing by more than `tolerance`).
pub fn difference(a: &image::RgbaImage, b: &image::RgbaImage, tolerance: u8) -> (u8, f64) {
    assert_eq!(a.dimensions(), b.dimensions(), "image sizes differ");
    let mut worst = 0u8;
    let mut over = 0usize;
    for (x, y) in a.as_raw().iter().zip(b.as_raw()) {
        let d = x.abs_diff(*y);
        worst = worst.max(d);
        if d > tolerance {
            over += 1;
        }
    }
    (worst, over as f64 / a.as_raw().len() as f64)
}

/// Loads a PNG as RGBA.
pub fn load(path: &Path) -> image::RgbaImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("cannot open {}: {e}", path.display()))
        .to_rgba8()
}

/// Runs `c2warp` with `configure` applied to the command, killing it if it has not
/// finished within `limit` (so a run that would hang fails the test instead).
pub fn c2warp_within(
    args: &[&std::ffi::OsStr],
    limit: std::time::Duration,
    configure: impl FnOnce(&mut Command),
) -> Output {
    use std::process::Stdio;
    let mut command = Command::new(env!("CARGO_BIN_EXE_c2warp"));
    command
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    configure(&mut command);
    let child = command.spawn().expect("the c2warp binary runs");
    let id = child.id();
    let (done, wait) = std::sync::mpsc::channel();
    let waiter = std::thread::spawn(move || {
        let out = child.wait_with_output().expect("wait for c2warp");
        let _ = done.send(());
        out
    });
    if wait.recv_timeout(limit).is_err() {
        // Kill only the child this test started, by its id.
        let _ = Command::new("kill").arg("-9").arg(id.to_string()).status();
        let _ = waiter.join();
        panic!("c2warp {args:?} did not finish within {limit:?}");
    }
    waiter.join().expect("waiter thread")
}

/// As [`fails`], but the run must end within `limit`.
pub fn fails_within(args: &[&std::ffi::OsStr], limit: std::time::Duration) -> String {
    let out = c2warp_within(args, limit, |_| {});
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!out.status.success(), "c2warp {args:?} should fail");
    assert!(
        !stderr.contains("panicked"),
        "c2warp {args:?} panicked: {stderr}"
    );
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "one line of error expected, got: {stderr}");
    assert!(lines[0].starts_with("error: "), "{stderr}");
    // Each reason once: no part of the line between ": " says again what another says.
    let parts: Vec<&str> = lines[0].split(": ").filter(|p| p.len() >= 8).collect();
    for (i, part) in parts.iter().enumerate() {
        assert!(
            !parts[..i].contains(part),
            "the line says {part:?} twice: {stderr}"
        );
    }
    lines[0].to_string()
}

/// Creates a FIFO at `path`.
pub fn mkfifo(path: &Path) {
    let status = Command::new("mkfifo")
        .arg(path)
        .status()
        .expect("mkfifo runs");
    assert!(status.success(), "mkfifo {}", path.display());
}
