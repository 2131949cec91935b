//! Image loading under limits, and atomic writes.

use crate::support;

use std::fs;
use std::path::Path;
use std::time::{Duration, Instant};

use image::{Rgba, RgbaImage};
use render::{
    ImageLimits, Picture, RenderError, decode_image, decode_picture, load_image, load_picture,
    read_regular_file, save_png_atomic, write_atomic,
};
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
        b"P6\n1 1\n255\nabc",
        b"\0\0\x01\0junk",
    ] {
        let err = decode_image(bytes, &limits).expect_err("not an image");
        assert!(
            matches!(err, RenderError::UnsupportedFormat { .. }),
            "{err}"
        );
        assert_eq!(
            err.to_string(),
            "<memory>: not a PNG, JPEG, WebP, TIFF, BMP or GIF image"
        );
    }
    // Known formats with broken data are corrupt, not a panic.
    for bytes in [
        &b"GIF89a\x01\x00\x01\x00\x00\x00\x00"[..],
        b"BM\x1e\x00\x00\x00\x00\x00",
        b"II*\x00\x08\x00\x00\x00",
        b"RIFF\x10\x00\x00\x00WEBPVP8 ",
    ] {
        let err = decode_image(bytes, &limits).expect_err("broken");
        assert!(
            matches!(
                err,
                RenderError::Corrupt { .. } | RenderError::UnsupportedVariant { .. }
            ),
            "{err}"
        );
    }
}

/// Encodes `image` in `format` in memory.
fn encode(image: &image::DynamicImage, format: image::ImageFormat) -> Vec<u8> {
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write_to(&mut bytes, format).expect("encode");
    bytes.into_inner()
}

#[test]
fn webp_tiff_bmp_and_gif_open_too() {
    // Few colours (a GIF keeps up to 256 exactly), some transparent.
    let image = RgbaImage::from_fn(23, 17, |x, y| {
        let k = ((x / 4 + y / 3) % 5) as u8;
        Rgba([k * 50, 255 - k * 40, k * 13, if k == 4 { 0 } else { 255 }])
    });
    let dynamic = image::DynamicImage::ImageRgba8(image.clone());
    for format in [
        image::ImageFormat::WebP,
        image::ImageFormat::Tiff,
        image::ImageFormat::Bmp,
        image::ImageFormat::Gif,
    ] {
        let bytes = encode(&dynamic, format);
        let decoded = decode_image(&bytes, &ImageLimits::default())
            .unwrap_or_else(|e| panic!("{format:?}: {e}"));
        assert_eq!(decoded.dimensions(), (23, 17), "{format:?}");
        for (got, want) in decoded.pixels().zip(image.pixels()) {
            // Fully transparent pixels may lose their colour (GIF).
            if want[3] == 0 {
                assert_eq!(got[3], 0, "{format:?}");
            } else {
                assert_eq!(got, want, "{format:?}");
            }
        }
        let tiny = ImageLimits {
            max_width: 20,
            ..ImageLimits::default()
        };
        let err = decode_image(&bytes, &tiny).expect_err("too wide");
        assert!(
            matches!(err, RenderError::TooLarge { .. }),
            "{format:?}: {err}"
        );
    }
}

#[test]
fn a_gif_opens_on_its_first_frame() {
    use image::codecs::gif::GifEncoder;
    let frame = |c: u8| image::Frame::new(RgbaImage::from_pixel(4, 3, Rgba([c, 0, 0, 255])));
    let mut bytes = Vec::new();
    {
        let mut encoder = GifEncoder::new(&mut bytes);
        encoder
            .encode_frames([frame(200), frame(50)])
            .expect("encode frames");
    }
    let decoded = decode_image(&bytes, &ImageLimits::default()).expect("decode");
    assert_eq!(decoded.get_pixel(1, 1).0, [200, 0, 0, 255]);
}

#[test]
fn sixteen_bit_pictures_keep_their_depth() {
    let wide = render::Rgba16Image::from_fn(9, 7, |x, y| {
        Rgba([
            (x * 7001 + y * 13) as u16,
            (y * 9001 + 1) as u16,
            65535 - (x * y * 300) as u16,
            if x == 0 { 0 } else { 40000 + x as u16 },
        ])
    });
    let dir = tempfile::tempdir().expect("tempdir");
    // A 16-bit PNG written from a Picture reads back as the same 16-bit picture.
    let path = dir.path().join("wide.png");
    save_png_atomic(&path, &Picture::Rgba16(wide.clone())).expect("save");
    let back = load_picture(&path, &ImageLimits::default()).expect("load");
    assert_eq!(back, Picture::Rgba16(wide.clone()));
    let decoded = image::open(&path).expect("open");
    assert_eq!(decoded.color(), image::ColorType::Rgba16);
    // A 16-bit TIFF too.
    let tiff = encode(
        &image::DynamicImage::ImageRgba16(wide.clone()),
        image::ImageFormat::Tiff,
    );
    let back = decode_picture(&tiff, &ImageLimits::default()).expect("tiff");
    assert_eq!(back, Picture::Rgba16(wide.clone()));
    // 16-bit grey becomes 16-bit RGBA; 8-bit stays 8-bit.
    let grey = image::ImageBuffer::<image::Luma<u16>, _>::from_fn(3, 2, |x, y| {
        image::Luma([(x * 20000 + y) as u16])
    });
    let png = encode(
        &image::DynamicImage::ImageLuma16(grey),
        image::ImageFormat::Png,
    );
    match decode_picture(&png, &ImageLimits::default()).expect("grey") {
        Picture::Rgba16(p) => assert_eq!(p.get_pixel(2, 1).0, [40001, 40001, 40001, 65535]),
        other => panic!("expected 16 bits, got {}", other.bits_per_channel()),
    }
    let narrow = encode_png(&random_image(5, 5, 9));
    assert_eq!(
        decode_picture(&narrow, &ImageLimits::default())
            .expect("narrow")
            .bits_per_channel(),
        8
    );
    // The RGBA8 view rounds.
    assert_eq!(
        decode_image(&tiff, &ImageLimits::default()).expect("rgba8"),
        Picture::Rgba16(wide).into_rgba8()
    );
}

/// A baseline JPEG of a smooth picture.
fn jpeg(width: u32, height: u32) -> Vec<u8> {
    let image = image::RgbImage::from_fn(width, height, |x, y| {
        image::Rgb([(x * 3) as u8, (y * 5) as u8, ((x + y) * 2) as u8])
    });
    encode(
        &image::DynamicImage::ImageRgb8(image),
        image::ImageFormat::Jpeg,
    )
}

#[test]
fn a_jpeg_cut_short_is_refused_as_truncated() {
    let whole = jpeg(80, 60);
    assert!(decode_image(&whole, &ImageLimits::default()).is_ok());
    for cut in [whole.len() / 2, whole.len() - 2, whole.len() - 1, 700] {
        let err = decode_image(&whole[..cut], &ImageLimits::default()).expect_err("truncated");
        assert!(
            matches!(err, RenderError::Corrupt { .. }),
            "cut at {cut}: {err}"
        );
        assert!(err.to_string().contains("truncated"), "cut at {cut}: {err}");
    }
}

#[test]
fn a_tiny_jpeg_claiming_a_huge_size_is_refused_before_decoding() {
    let mut forged = jpeg(16, 16);
    let sof = forged
        .windows(2)
        .position(|w| w == [0xFF, 0xC0])
        .expect("a baseline frame header");
    forged[sof + 5..sof + 7].copy_from_slice(&16000u16.to_be_bytes());
    forged[sof + 7..sof + 9].copy_from_slice(&16000u16.to_be_bytes());
    let start = Instant::now();
    let err = decode_image(&forged, &ImageLimits::default()).expect_err("too short");
    assert!(
        start.elapsed() < Duration::from_secs(5), // refused up front, not decoded
        "{:?}",
        start.elapsed()
    );
    assert!(matches!(err, RenderError::Corrupt { .. }), "{err}");
    assert_eq!(
        err.to_string(),
        "<memory>: truncated or corrupt image data (its data is too short for 16000×16000 pixels)"
    );
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
    assert!(start.elapsed() < Duration::from_secs(5), "refused up front");
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
    assert!(start.elapsed() < Duration::from_secs(5), "refused up front");
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
        format!(
            "{}: not a PNG, JPEG, WebP, TIFF, BMP or GIF image",
            text.display()
        )
    );

    let err = load_image(dir.path(), &ImageLimits::default()).expect_err("a directory");
    assert!(matches!(err, RenderError::NotRegularFile { .. }), "{err}");

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

#[cfg(unix)]
fn mkfifo(path: &Path) {
    let status = std::process::Command::new("mkfifo")
        .arg(path)
        .status()
        .expect("mkfifo runs");
    assert!(status.success(), "mkfifo {}", path.display());
}

#[cfg(unix)]
#[test]
fn fifos_and_devices_are_refused_without_reading() {
    let dir = tempfile::tempdir().expect("tempdir");
    let fifo = dir.path().join("pipe.png");
    mkfifo(&fifo);
    let start = Instant::now();
    // Opening the FIFO would block: nothing writes to it.
    let err = load_image(&fifo, &ImageLimits::default()).expect_err("a FIFO");
    assert_eq!(
        err.to_string(),
        format!("image {} is not a regular file (a FIFO)", fifo.display())
    );
    let err = load_image(Path::new("/dev/zero"), &ImageLimits::default()).expect_err("a device");
    assert_eq!(
        err.to_string(),
        "image /dev/zero is not a regular file (a character device)"
    );
    // Through a symbolic link too.
    let link = dir.path().join("link.json");
    std::os::unix::fs::symlink("/dev/zero", &link).expect("symlink");
    let err = read_regular_file(&link, "rig file", 8 << 20).expect_err("a device");
    assert!(matches!(err, RenderError::NotRegularFile { .. }), "{err}");
    assert!(
        start.elapsed() < Duration::from_secs(5),
        "refused, not read"
    );
}

#[test]
fn reads_are_capped_before_reading() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("big.json");
    let file = fs::File::create(&path).expect("create");
    // A sparse file: 52.4 MB claimed, nothing written.
    file.set_len(52_400_000).expect("set_len");
    let err = read_regular_file(&path, "rig file", 8 << 20).expect_err("too large");
    assert_eq!(
        err.to_string(),
        format!(
            "rig file {} is 52.4 MB; rig files over 8 MiB are refused",
            path.display()
        )
    );
    assert!(matches!(
        err,
        RenderError::FileTooLarge {
            len: 52_400_000,
            ..
        }
    ));
    fs::write(&path, b"small").expect("write");
    assert_eq!(
        read_regular_file(&path, "rig file", 8 << 20).expect("read"),
        b"small"
    );
    let err = read_regular_file(&dir.path().join("nope"), "rig file", 8).expect_err("missing");
    assert!(matches!(err, RenderError::NotFound { .. }), "{err}");
}

#[cfg(unix)]
#[test]
fn writing_to_a_device_writes_through_and_keeps_the_device() {
    use std::os::unix::fs::FileTypeExt;
    let null = Path::new("/dev/null");
    write_atomic(null, b"nothing to see").expect("write to /dev/null");
    save_png_atomic(null, &random_image(4, 4, 6)).expect("png to /dev/null");
    let meta = fs::metadata(null).expect("stat");
    assert!(meta.file_type().is_char_device(), "/dev/null was replaced");
}

#[cfg(unix)]
#[test]
fn writing_to_a_symlink_writes_its_target_and_keeps_the_link() {
    let dir = tempfile::tempdir().expect("tempdir");
    let target = dir.path().join("real.png");
    fs::write(&target, b"old").expect("write");
    let link = dir.path().join("link.png");
    std::os::unix::fs::symlink("real.png", &link).expect("symlink");
    let image = random_image(6, 5, 7);
    save_png_atomic(&link, &image).expect("save through the link");
    assert!(
        fs::symlink_metadata(&link)
            .expect("lstat")
            .file_type()
            .is_symlink()
    );
    assert_eq!(
        load_image(&target, &ImageLimits::default()).expect("load"),
        image
    );
    // A chain of links, the last one dangling: the file is created where it points.
    let second = dir.path().join("second.json");
    std::os::unix::fs::symlink("new.json", &second).expect("symlink");
    let first = dir.path().join("first.json");
    std::os::unix::fs::symlink(&second, &first).expect("symlink");
    write_atomic(&first, b"{}").expect("write through two links");
    assert_eq!(fs::read(dir.path().join("new.json")).expect("read"), b"{}");
    assert!(
        fs::symlink_metadata(&first)
            .expect("lstat")
            .file_type()
            .is_symlink()
    );
    assert!(
        fs::symlink_metadata(&second)
            .expect("lstat")
            .file_type()
            .is_symlink()
    );
    let mut names = leftovers(dir.path(), &[]);
    names.sort();
    assert_eq!(
        names,
        [
            "first.json",
            "link.png",
            "new.json",
            "real.png",
            "second.json"
        ]
    );
    // A loop of links is an error, not a hang.
    let a = dir.path().join("a");
    let b = dir.path().join("b");
    std::os::unix::fs::symlink("b", &a).expect("symlink");
    std::os::unix::fs::symlink("a", &b).expect("symlink");
    let err = write_atomic(&a, b"x").expect_err("a loop");
    assert!(err.to_string().contains("symbolic link"), "{err}");
}

#[cfg(unix)]
#[test]
fn writing_to_a_fifo_reaches_its_reader() {
    let dir = tempfile::tempdir().expect("tempdir");
    let fifo = dir.path().join("out.png");
    mkfifo(&fifo);
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || fs::read(&fifo).expect("read the FIFO"))
    };
    let image = random_image(7, 3, 8);
    save_png_atomic(&fifo, &image).expect("save to the FIFO");
    let bytes = reader.join().expect("reader thread");
    assert_eq!(
        decode_image(&bytes, &ImageLimits::default()).expect("decode"),
        image
    );
    assert!(
        fs::metadata(&fifo)
            .expect("stat")
            .file_type()
            .is_fifo_like()
    );
}

/// `FileType::is_fifo` behind a name that reads well above.
#[cfg(unix)]
trait FifoLike {
    fn is_fifo_like(&self) -> bool;
}

#[cfg(unix)]
impl FifoLike for fs::FileType {
    fn is_fifo_like(&self) -> bool {
        std::os::unix::fs::FileTypeExt::is_fifo(self)
    }
}

#[test]
fn an_output_that_is_an_input_is_refused_through_links_and_dots() {
    let dir = tempfile::tempdir().expect("tempdir");
    let picture = dir.path().join("cat.png");
    fs::write(&picture, b"picture").expect("write");
    fs::create_dir(dir.path().join("sub")).expect("mkdir");
    let refused = |output: &Path| {
        let err = render::refuse_input_as_output(output, &[Path::new("rig.json"), &picture])
            .expect_err("the output is the picture");
        assert!(matches!(err, RenderError::OutputIsInput { .. }), "{err}");
        let message = err.to_string();
        assert!(
            message.contains("cat.png, one of the inputs") && !message.contains('\n'),
            "{message}"
        );
    };
    refused(&picture);
    refused(&dir.path().join("sub/../cat.png"));
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(&picture, dir.path().join("link.png")).expect("symlink");
        refused(&dir.path().join("link.png"));
        fs::hard_link(&picture, dir.path().join("hard.png")).expect("hard link");
        refused(&dir.path().join("hard.png"));
    }
    // Other outputs, a new file and standard output replace nothing.
    for fine in ["other.png", "-", "sub"] {
        let output = if fine == "-" {
            Path::new("-").to_path_buf()
        } else {
            dir.path().join(fine)
        };
        render::refuse_input_as_output(&output, &[&picture]).expect("not an input");
    }
    // A folder of frames refuses an input that is one of its frames.
    let frame = dir.path().join("sub/frame_00000.png");
    fs::write(&frame, b"frame").expect("write");
    let err = render::refuse_input_as_output(&dir.path().join("sub/"), &[&frame])
        .expect_err("the frames would replace their input");
    assert!(err.to_string().contains("frames would replace"), "{err}");
    assert_eq!(fs::read(&picture).expect("kept"), b"picture");
}

#[test]
fn temporary_files_of_dead_runs_are_removed_by_the_next_write_there() {
    let dir = tempfile::tempdir().expect("tempdir");
    // A run that was killed (no such process: above Linux's largest pid), one that is
    // still running (this test), and files that are not this program's.
    let dead = ".old.png.c2warp-4294967-0.tmp";
    let running = format!(".old.png.c2warp-{}-999.tmp", std::process::id());
    let alive_pid = String::from(".old.png.c2warp-1-0.tmp");
    let theirs = [
        ".old.png.1234-0.tmp",
        "notes.c2warp-1-0.tmp",
        ".x.c2warp-9-y.tmp",
    ];
    for name in [dead, &running, &alive_pid].into_iter().chain(theirs) {
        fs::write(dir.path().join(name), b"partial").expect("write");
    }
    write_atomic(&dir.path().join("new.json"), b"{}").expect("write");
    let mut left = leftovers(dir.path(), &["new.json"]);
    left.sort();
    let mut expected: Vec<String> = theirs.iter().map(|s| (*s).to_owned()).collect();
    if cfg!(target_os = "linux") {
        // pid 1 is running; this process's own leftover is not one of its live files.
        expected.push(alive_pid);
    } else {
        expected.extend([dead.to_owned(), running, alive_pid]);
    }
    expected.sort();
    assert_eq!(left, expected);
}
