//! Image loading under limits, and atomic writes.

mod support;

use std::fs;
use std::path::Path;
use std::time::{Duration, Instant};

use image::{Rgba, RgbaImage};
use render::{ImageLimits, RenderError, decode_image, load_image, save_png_atomic, write_atomic};
use support::{encode_png, png_with_header, random_image};

/// Files in `dir` other than `keep`.
fn leftovers(dir: &Path, keep: &[&str]) -> Vec<String> {
    fs::read_dir(dir)
        .expect("list dir")
        .map(|e| {
            e.expect("dir entry")
                .file_name()
                .to_string_lossy()
                .into_owned()
        })
        .filter(|name| !keep.contains(&name.as_str()))
        .collect()
}

#[test]
fn png_round_trip() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("out.png");
    let image = random_image(37, 21, 1);
    save_png_atomic(&path, &image).expect("save");
    assert_eq!(
        load_image(&path, &ImageLimits::default()).expect("load"),
        image
    );
    assert_eq!(
        decode_image(&fs::read(&path).expect("read"), &ImageLimits::default()).expect("decode"),
        image
    );
    assert_eq!(leftovers(dir.path(), &["out.png"]), Vec::<String>::new());
}

#[test]
fn other_pixel_formats_become_rgba() {
    let grey = image::GrayImage::from_fn(5, 4, |x, y| image::Luma([(x * 40 + y) as u8]));
    let mut bytes = std::io::Cursor::new(Vec::new());
    grey.write_to(&mut bytes, image::ImageFormat::Png)
        .expect("encode");
    let rgba = decode_image(bytes.get_ref(), &ImageLimits::default()).expect("decode");
    assert_eq!(rgba.get_pixel(2, 3).0, [83, 83, 83, 255]);
}

#[test]
fn jpeg_loads() {
    let image = image::RgbImage::from_pixel(20, 10, image::Rgb([200, 100, 50]));
    let mut bytes = std::io::Cursor::new(Vec::new());
    image
        .write_to(&mut bytes, image::ImageFormat::Jpeg)
        .expect("encode");
    let decoded = decode_image(bytes.get_ref(), &ImageLimits::default()).expect("decode");
    assert_eq!(decoded.dimensions(), (20, 10));
    let [r, g, b, a] = decoded.get_pixel(10, 5).0;
    assert!(r.abs_diff(200) < 8 && g.abs_diff(100) < 8 && b.abs_diff(50) < 8 && a == 255);

    let small = ImageLimits {
        max_width: 16,
        ..ImageLimits::default()
    };
    let err = decode_image(bytes.get_ref(), &small).expect_err("too wide");
    assert!(
        matches!(
            err,
            RenderError::TooLarge {
                width: 20,
                height: 10,
                limit: (16, 16384),
                ..
            }
        ),
        "{err}"
    );
}

#[test]
fn garbage_and_other_formats_are_unsupported() {
    let limits = ImageLimits::default();
    for bytes in [
        &b""[..],
        b"hello, world",
        b"GIF89a\x01\x00\x01\x00\x00\x00\x00",
        b"BM\x1e\x00\x00\x00\x00\x00",
    ] {
        let err = decode_image(bytes, &limits).expect_err("not an image");
        assert!(
            matches!(err, RenderError::UnsupportedFormat { .. }),
            "{err}"
        );
        assert_eq!(err.to_string(), "<memory>: not a PNG or JPEG image");
    }
}

#[test]
fn corrupt_and_truncated_png_are_reported() {
    let limits = ImageLimits::default();
    let good = encode_png(&random_image(30, 30, 2));

    for cut in [10, 30, good.len() / 2, good.len() - 13] {
        let err = decode_image(&good[..cut], &limits).expect_err("truncated");
        assert!(
            matches!(err, RenderError::Corrupt { .. }),
            "cut at {cut}: {err}"
        );
        assert!(err.to_string().contains("truncated or corrupt image data"));
    }

    let mut flipped = good.clone();
    let middle = flipped.len() / 2;
    for b in &mut flipped[middle..middle + 16] {
        *b ^= 0x5a;
    }
    let err = decode_image(&flipped, &limits).expect_err("corrupt");
    assert!(matches!(err, RenderError::Corrupt { .. }), "{err}");

    let mut junk = b"\x89PNG\r\n\x1a\n".to_vec();
    junk.extend_from_slice(&[0xAB; 64]);
    let err = decode_image(&junk, &limits).expect_err("corrupt");
    assert!(matches!(err, RenderError::Corrupt { .. }), "{err}");
}

#[test]
fn huge_header_fails_fast() {
    let bytes = png_with_header(100_000, 100_000);
    let start = Instant::now();
    let err = decode_image(&bytes, &ImageLimits::default()).expect_err("too large");
    assert!(start.elapsed() < Duration::from_secs(1));
    assert!(
        matches!(
            err,
            RenderError::TooLarge {
                width: 100_000,
                height: 100_000,
                limit: (16384, 16384),
                ..
            }
        ),
        "{err}"
    );
    assert_eq!(
        err.to_string(),
        "<memory>: image is 100000x100000 pixels, larger than the 16384x16384 limit"
    );

    // Within the dimension limits but beyond the memory limit.
    let bytes = png_with_header(16_000, 16_000);
    let limits = ImageLimits {
        max_alloc_bytes: 256 << 20,
        ..ImageLimits::default()
    };
    let start = Instant::now();
    let err = decode_image(&bytes, &limits).expect_err("too much memory");
    assert!(start.elapsed() < Duration::from_secs(1));
    assert!(matches!(err, RenderError::MemoryLimit { .. }), "{err}");

    // Within both limits, the tiny IDAT is simply not enough data.
    let err = decode_image(&png_with_header(300, 200), &ImageLimits::default()).expect_err("short");
    assert!(matches!(err, RenderError::Corrupt { .. }), "{err}");
}

#[test]
fn load_names_the_path() {
    let dir = tempfile::tempdir().expect("tempdir");
    let missing = dir.path().join("nope.png");
    let err = load_image(&missing, &ImageLimits::default()).expect_err("missing");
    assert!(matches!(err, RenderError::NotFound { .. }), "{err}");
    assert!(err.to_string().contains("nope.png"));

    let text = dir.path().join("notes.png");
    fs::write(&text, "not really a png").expect("write");
    let err = load_image(&text, &ImageLimits::default()).expect_err("not an image");
    assert_eq!(
        err.to_string(),
        format!("{}: not a PNG or JPEG image", text.display())
    );

    let err = load_image(dir.path(), &ImageLimits::default()).expect_err("a directory");
    assert!(matches!(err, RenderError::Io { .. }), "{err}");

    let big = dir.path().join("big.png");
    fs::write(&big, encode_png(&random_image(64, 64, 3))).expect("write");
    let tiny = ImageLimits {
        max_alloc_bytes: 1000,
        ..ImageLimits::default()
    };
    let err = load_image(&big, &tiny).expect_err("memory");
    assert!(
        matches!(err, RenderError::MemoryLimit { limit: 1000, .. }),
        "{err}"
    );
}

#[test]
fn failed_encode_leaves_old_file_and_no_temp() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("keep.png");
    fs::write(&path, b"old content").expect("write");
    let err = save_png_atomic(&path, &RgbaImage::new(0, 0)).expect_err("empty image");
    assert!(matches!(err, RenderError::Encode { .. }), "{err}");
    assert_eq!(fs::read(&path).expect("read"), b"old content");
    assert_eq!(leftovers(dir.path(), &["keep.png"]), Vec::<String>::new());
}

#[test]
fn failed_rename_leaves_no_temp() {
    let dir = tempfile::tempdir().expect("tempdir");
    let target = dir.path().join("occupied");
    fs::create_dir(&target).expect("mkdir");
    fs::write(target.join("inside"), b"x").expect("write");
    let err = write_atomic(&target, b"data").expect_err("a directory is in the way");
    assert!(
        matches!(
            err,
            RenderError::Io {
                action: "replace",
                ..
            }
        ),
        "{err}"
    );
    assert_eq!(leftovers(dir.path(), &["occupied"]), Vec::<String>::new());
    assert_eq!(fs::read(target.join("inside")).expect("read"), b"x");
}

#[cfg(unix)]
#[test]
fn read_only_directory_keeps_old_file() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("keep.png");
    fs::write(&path, b"old content").expect("write");
    fs::set_permissions(dir.path(), fs::Permissions::from_mode(0o555)).expect("chmod");
    let result = save_png_atomic(&path, &random_image(8, 8, 4));
    // Root ignores directory permissions; then the save simply succeeds.
    let root_like = fs::write(dir.path().join("probe"), b"").is_ok();
    fs::set_permissions(dir.path(), fs::Permissions::from_mode(0o755)).expect("chmod back");
    if root_like {
        let _ = fs::remove_file(dir.path().join("probe"));
        assert!(result.is_ok());
    } else {
        let err = result.expect_err("read-only directory");
        assert!(matches!(err, RenderError::Io { .. }), "{err}");
        assert_eq!(fs::read(&path).expect("read"), b"old content");
    }
    assert_eq!(leftovers(dir.path(), &["keep.png"]), Vec::<String>::new());
}

#[test]
fn missing_directory_is_a_clean_error() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("no/such/dir/out.png");
    let err = save_png_atomic(&path, &random_image(2, 2, 5)).expect_err("missing dir");
    assert!(matches!(err, RenderError::MissingDirectory { .. }), "{err}");
    assert!(err.to_string().contains("does not exist"));
    let err = write_atomic(Path::new("/"), b"x").expect_err("no file name");
    assert!(matches!(err, RenderError::InvalidPath { .. }), "{err}");
}

#[test]
fn write_atomic_replaces_and_keeps_permissions() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("rig.json");
    write_atomic(&path, b"first").expect("write");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        fs::set_permissions(&path, fs::Permissions::from_mode(0o640)).expect("chmod");
    }
    write_atomic(&path, b"second, longer").expect("write");
    assert_eq!(fs::read(&path).expect("read"), b"second, longer");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = fs::metadata(&path).expect("stat").permissions().mode() & 0o777;
        assert_eq!(mode, 0o640);
    }
    assert_eq!(leftovers(dir.path(), &["rig.json"]), Vec::<String>::new());
}

#[test]
fn opaque_red_png_decodes_to_red() {
    let image = RgbaImage::from_pixel(3, 3, Rgba([255, 0, 0, 255]));
    let decoded = decode_image(&encode_png(&image), &ImageLimits::default()).expect("decode");
    assert_eq!(decoded, image);
}
