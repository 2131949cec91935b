//! The real editor window, run under Xvfb and driven with xdotool: it opens on the
//! built-in picture, draws it through wgpu (Mesa's lavapipe without a GPU), and answers
//! the keyboard. Needs what `scripts/setup.sh` installs (Xvfb, xdotool, ImageMagick).

use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::thread::sleep;
use std::time::{Duration, Instant};

/// Kills its processes when dropped, so a failing test leaves nothing running.
struct Running(Vec<Child>);

impl Drop for Running {
    fn drop(&mut self) {
        for child in self.0.iter_mut().rev() {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

fn run(display: &str, program: &str, args: &[&str]) -> std::process::Output {
    Command::new(program)
        .args(args)
        .env("DISPLAY", display)
        .output()
        .unwrap_or_else(|e| panic!("{program}: {e} (run scripts/setup.sh)"))
}

fn screenshot(display: &str, path: &Path) -> image::RgbaImage {
    let out = run(
        display,
        "import",
        &["-window", "root", path.to_str().expect("utf-8 path")],
    );
    assert!(out.status.success(), "import: {out:?}");
    image::open(path).expect("a screenshot").to_rgba8()
}

/// Pixels of the heat map's cold end (deep blue), which nothing else on screen has.
fn deep_blue(image: &image::RgbaImage) -> usize {
    image
        .pixels()
        .filter(|p| p[2] > 90 && p[0] < 60 && p[1] < 50)
        .count()
}

/// Pixels of the lizard's orange stripes.
fn orange(image: &image::RgbaImage) -> usize {
    image
        .pixels()
        .filter(|p| p[0] > 180 && p[1] > 90 && p[1] < 190 && p[2] < 90)
        .count()
}

#[test]
fn the_window_draws_the_picture_and_answers_keys() {
    let dir = tempfile::tempdir().expect("temp dir");
    // A display number no server holds, nor left its lock or socket behind (a
    // server killed outright leaves both, and a new one on that number would not start).
    let free = |n: u32| {
        !Path::new(&format!("/tmp/.X{n}-lock")).exists()
            && !Path::new(&format!("/tmp/.X11-unix/X{n}")).exists()
    };
    let number = (0..400)
        .map(|k| 100 + (std::process::id() + k) % 400)
        .find(|&n| free(n))
        .expect("a free display number");
    let display = format!(":{number}");
    let xvfb = Command::new("Xvfb")
        .args([
            display.as_str(),
            "-screen",
            "0",
            "1280x820x24",
            "-nolisten",
            "tcp",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("Xvfb (run scripts/setup.sh)");
    let mut running = Running(vec![xvfb]);
    let socket = format!("/tmp/.X11-unix/X{number}");
    let start = Instant::now();
    while !Path::new(&socket).exists() {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "Xvfb did not start"
        );
        let exited = running.0[0].try_wait().expect("Xvfb's status");
        assert!(exited.is_none(), "Xvfb exited at once: {exited:?}");
        sleep(Duration::from_millis(100));
    }
    let app = Command::new(env!("CARGO_BIN_EXE_c2warp"))
        .env("DISPLAY", &display)
        .env("WGPU_BACKEND", "vulkan")
        .env("XDG_RUNTIME_DIR", dir.path())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the c2warp binary");
    running.0.push(app);
    let found = run(
        &display,
        "timeout",
        &["120", "xdotool", "search", "--sync", "--name", "C2Warp"],
    );
    assert!(found.status.success(), "no editor window: {found:?}");
    let window = String::from_utf8_lossy(&found.stdout)
        .lines()
        .next()
        .unwrap_or_default()
        .to_owned();
    sleep(Duration::from_secs(4));

    let first = screenshot(&display, &dir.path().join("first.png"));
    assert!(
        orange(&first) > 500,
        "the lizard is drawn ({} orange pixels)",
        orange(&first)
    );
    assert!(deep_blue(&first) < 100, "no heat map yet");

    // Focus the window (there is no window manager), select a handle, show its weight.
    run(&display, "xdotool", &["windowfocus", &window]);
    run(
        &display,
        "xdotool",
        &["mousemove", "1150", "760", "click", "1"],
    );
    for key in ["n", "h"] {
        sleep(Duration::from_millis(500));
        run(&display, "xdotool", &["key", key]);
    }
    sleep(Duration::from_secs(2));
    let second = screenshot(&display, &dir.path().join("second.png"));
    assert!(
        deep_blue(&second) > 2000,
        "the heat map shows ({} deep blue pixels)",
        deep_blue(&second)
    );
    let app = &mut running.0[1];
    assert!(
        app.try_wait().expect("process state").is_none(),
        "the editor is still running"
    );
}
