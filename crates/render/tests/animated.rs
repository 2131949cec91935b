//! Animations: each format written frame by frame, decoded back and compared.

use crate::support;

use std::fs::{self, File};
use std::io::BufReader;
use std::path::{Path, PathBuf};

use image::codecs::gif::GifDecoder;
use image::codecs::png::PngDecoder;
use image::codecs::webp::WebPDecoder;
use image::{AnimationDecoder, Delay, Frame, Rgba, RgbaImage};
use render::{
    AnimationFormat, AnimationWriter, ImageLimits, Picture, RenderError, Rgba16Image, load_picture,
    save_png_atomic,
};
use support::random_image;

const FPS: f64 = 24.0;

/// Files in `dir`, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = fs::read_dir(dir)
        .expect("list dir")
        .map(|e| {
            e.expect("dir entry")
                .file_name()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    names.sort();
    names
}

/// Writes `frames` to `path` as `format` at [`FPS`].
fn write(path: &Path, format: AnimationFormat, frames: &[Picture]) -> Result<(), RenderError> {
    let (width, height) = frames[0].dimensions();
    let mut writer = AnimationWriter::create(path, format, width, height, frames.len(), FPS)?;
    for frame in frames {
        writer.push(frame)?;
    }
    writer.finish()
}

/// Three distinct 8-bit frames of random colours and alphas (some transparent).
fn random_frames(width: u32, height: u32) -> Vec<Picture> {
    (0..3)
        .map(|seed| Picture::from(random_image(width, height, 10 + seed)))
        .collect()
}

/// Three distinct 16-bit frames with transparent pixels and values that 8 bits
/// cannot hold.
fn frames16(width: u32, height: u32) -> Vec<Picture> {
    (0..3u16)
        .map(|k| {
            Picture::from(Rgba16Image::from_fn(width, height, |x, y| {
                let v = (x as u16 * 4099 + y as u16 * 257 + k * 1001) | 1;
                let alpha = if (x + y + u32::from(k)) % 3 == 0 {
                    0
                } else {
                    v ^ 0x5a5a
                };
                Rgba([v, v.wrapping_mul(3), 65535 - v, alpha])
            }))
        })
        .collect()
}

/// The total duration of `frames` in milliseconds.
fn total_ms(frames: &[Frame]) -> f64 {
    frames
        .iter()
        .map(|frame| {
            let (num, den) = frame.delay().numer_denom_ms();
            f64::from(num) / f64::from(den)
        })
        .sum()
}

/// Whether the big-endian 16-bit samples `decoded` are those of `picture` (a 16-bit
/// frame).
fn is_frame(decoded: &[u8], picture: &Picture) -> bool {
    let Picture::Rgba16(expected) = picture else {
        panic!("16-bit frames")
    };
    decoded
        .chunks_exact(2)
        .map(|b| u16::from_be_bytes([b[0], b[1]]))
        .eq(expected.as_raw().iter().copied())
}

fn decode_apng(path: &Path) -> Vec<Frame> {
    let file = BufReader::new(File::open(path).expect("open"));
    PngDecoder::new(file)
        .expect("png")
        .apng()
        .expect("apng")
        .into_frames()
        .collect_frames()
        .expect("frames")
}

fn decode_webp(path: &Path) -> Vec<Frame> {
    let file = BufReader::new(File::open(path).expect("open"));
    WebPDecoder::new(file)
        .expect("webp")
        .into_frames()
        .collect_frames()
        .expect("frames")
}

fn decode_gif(path: &Path) -> Vec<Frame> {
    let file = BufReader::new(File::open(path).expect("open"));
    GifDecoder::new(file)
        .expect("gif")
        .into_frames()
        .collect_frames()
        .expect("frames")
}

#[test]
fn formats_from_paths() {
    let dir = tempfile::tempdir().expect("tempdir");
    let format = |p: &Path| AnimationFormat::from_path(p).expect("format");
    assert_eq!(format(Path::new("a/walk.png")), AnimationFormat::Apng);
    assert_eq!(format(Path::new("walk.PNG")), AnimationFormat::Apng);
    assert_eq!(format(Path::new("walk.webp")), AnimationFormat::WebP);
    assert_eq!(format(Path::new("walk.gif")), AnimationFormat::Gif);
    assert_eq!(format(Path::new("frames/")), AnimationFormat::PngSequence);
    assert_eq!(format(dir.path()), AnimationFormat::PngSequence);
    for bad in ["walk.mp4", "walk", "frames.png.tmp"] {
        let error = AnimationFormat::from_path(Path::new(bad)).expect_err(bad);
        let message = error.to_string();
        assert!(matches!(error, RenderError::Animation { .. }), "{message}");
        assert!(
            message.contains(bad) && message.contains(".webp"),
            "{message}"
        );
        assert!(!message.contains('\n'), "{message}");
    }
    assert_eq!(AnimationFormat::Apng.label(), "animated PNG");
    assert_eq!(AnimationFormat::Gif.max_fps(), 50.0);
}

#[test]
fn apng_8_bit_round_trip() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("walk.png");
    let frames = random_frames(13, 7);
    write(&path, AnimationFormat::Apng, &frames).expect("write");
    assert_eq!(listing(dir.path()), ["walk.png"]);

    let decoded = decode_apng(&path);
    assert_eq!(decoded.len(), 3);
    for (frame, picture) in decoded.iter().zip(&frames) {
        assert_eq!(frame.buffer(), &*picture.to_rgba8());
        assert_eq!(frame.delay(), Delay::from_numer_denom_ms(1000, 24));
    }
    assert!((total_ms(&decoded) - 3000.0 / FPS).abs() < 1e-6);
    // A PNG viewer without APNG support sees the first frame.
    let still = load_picture(&path, &ImageLimits::default()).expect("load");
    assert_eq!(still, frames[0]);
}

#[test]
fn apng_16_bit_round_trip_is_exact() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("walk.png");
    let frames = frames16(9, 6);
    write(&path, AnimationFormat::Apng, &frames).expect("write");

    let mut reader = png::Decoder::new(BufReader::new(File::open(&path).expect("open")))
        .read_info()
        .expect("png header");
    let info = reader.info();
    assert_eq!(info.bit_depth, png::BitDepth::Sixteen);
    assert_eq!(info.color_type, png::ColorType::Rgba);
    let animation = info.animation_control.expect("acTL");
    assert_eq!((animation.num_frames, animation.num_plays), (3, 0));
    let mut buffer = vec![0; reader.output_buffer_size().expect("size")];
    for picture in &frames {
        let output = reader.next_frame(&mut buffer).expect("frame");
        let control = reader.info().frame_control.expect("fcTL");
        assert_eq!((control.delay_num, control.delay_den), (1, 24));
        assert_eq!(control.blend_op, png::BlendOp::Source);
        assert_eq!(control.dispose_op, png::DisposeOp::None);
        assert!(is_frame(&buffer[..output.buffer_size()], picture));
    }
}

/// Frames of 16-bit noise too big for one chunk of image data (the low bytes do
/// not compress), so each frame spans several `fdAT` chunks.
#[test]
fn apng_16_bit_frames_of_many_chunks_round_trip_exactly() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("noise.png");
    let (width, height) = (420, 360);
    let frames: Vec<Picture> = (0..3u64)
        .map(|seed| {
            let mut random = support::Rng::new(seed + 5);
            Picture::from(Rgba16Image::from_fn(width, height, |_, _| {
                let v = random.next_u64();
                Rgba([
                    v as u16,
                    (v >> 16) as u16,
                    (v >> 32) as u16,
                    (v >> 48) as u16 | 1,
                ])
            }))
        })
        .collect();
    write(&path, AnimationFormat::Apng, &frames).expect("write");
    assert!(fs::metadata(&path).expect("written").len() > 3 << 20);
    let mut reader = png::Decoder::new(BufReader::new(File::open(&path).expect("open")))
        .read_info()
        .expect("png header");
    let mut buffer = vec![0; reader.output_buffer_size().expect("size")];
    for picture in &frames {
        let output = reader.next_frame(&mut buffer).expect("frame");
        assert!(is_frame(&buffer[..output.buffer_size()], picture));
    }
}

/// Frames pushed a run at a time (encoded side by side) make the same file, byte for
/// byte, as frames pushed one by one, in every format.
#[test]
fn pushing_runs_of_frames_writes_what_pushing_each_writes() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut eight = random_frames(12, 7);
    eight.extend(random_frames(12, 7).into_iter().rev());
    let mut sixteen = frames16(12, 7);
    sixteen.extend(frames16(12, 7).into_iter().rev());
    for (name, frames) in [
        ("walk.png", &eight),
        ("deep.png", &sixteen),
        ("walk.webp", &eight),
        ("walk.gif", &eight),
        ("walk/", &sixteen),
    ] {
        let one = dir.path().join("one").join(name);
        let runs = dir.path().join("runs").join(name);
        for path in [&one, &runs] {
            fs::create_dir_all(path.parent().expect("parent")).expect("folder");
        }
        write(
            &one,
            AnimationFormat::from_path(&one).expect("format"),
            frames,
        )
        .expect("write");
        let format = AnimationFormat::from_path(&runs).expect("format");
        let mut writer =
            AnimationWriter::create(&runs, format, 12, 7, frames.len(), FPS).expect("created");
        writer.push_all(&frames[..4]).expect("four");
        writer.push(&frames[4]).expect("one");
        writer.push_all(&frames[5..]).expect("the rest");
        writer.finish().expect("finished");
        let bytes = |path: &Path| -> Vec<Vec<u8>> {
            if path.is_dir() {
                listing(path)
                    .iter()
                    .map(|name| fs::read(path.join(name)).expect("read"))
                    .collect()
            } else {
                vec![fs::read(path).expect("read")]
            }
        };
        assert!(bytes(&one) == bytes(&runs), "{name}");
    }
}

/// A run that would take the animation past its frame count is refused whole, and
/// the animation goes on.
#[test]
fn a_run_of_too_many_frames_is_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("walk.png");
    let frames = random_frames(8, 8);
    let mut writer =
        AnimationWriter::create(&path, AnimationFormat::Apng, 8, 8, 3, FPS).expect("created");
    writer.push(&frames[0]).expect("one");
    let error = writer.push_all(&frames).expect_err("four of three");
    assert!(error.to_string().contains("one too many"), "{error}");
    writer.push_all(&frames[1..]).expect("the rest");
    writer.finish().expect("finished");
    assert_eq!(decode_apng(&path).len(), 3);
}

#[test]
fn apng_of_one_frame_is_a_png() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("still.png");
    let frame = frames16(5, 4).remove(1);
    write(&path, AnimationFormat::Apng, std::slice::from_ref(&frame)).expect("write");
    let loaded = load_picture(&path, &ImageLimits::default()).expect("load");
    assert_eq!(loaded, frame);
}

#[test]
fn webp_round_trip_is_lossless() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("walk.webp");
    let mut frames = random_frames(11, 8);
    // A 16-bit frame is rounded to 8 bits.
    frames[1] = frames16(11, 8).remove(1);
    write(&path, AnimationFormat::WebP, &frames).expect("write");
    assert_eq!(listing(dir.path()), ["walk.webp"]);

    let bytes = fs::read(&path).expect("read");
    assert_eq!(&bytes[..4], b"RIFF");
    let riff_size = u32::from_le_bytes([bytes[4], bytes[5], bytes[6], bytes[7]]);
    assert_eq!(riff_size as usize, bytes.len() - 8);

    let decoded = decode_webp(&path);
    assert_eq!(decoded.len(), 3);
    for (frame, picture) in decoded.iter().zip(&frames) {
        assert_eq!(frame.buffer(), &*picture.to_rgba8());
    }
    let delays: Vec<_> = decoded.iter().map(|f| f.delay().numer_denom_ms()).collect();
    assert_eq!(delays, [(42, 1), (41, 1), (42, 1)]);
    assert!((total_ms(&decoded) - 3000.0 / FPS).abs() <= 0.5);
}

#[test]
fn gif_keeps_flat_colours_and_transparency() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("walk.gif");
    let colours = [
        Rgba([200, 30, 40, 255]),
        Rgba([10, 220, 90, 200]),
        Rgba([0, 0, 255, 255]),
    ];
    let frames: Vec<Picture> = (0..3u32)
        .map(|k| {
            Picture::from(RgbaImage::from_fn(16, 10, |x, y| {
                if (x + k) % 4 == 0 {
                    Rgba([255, 255, 255, 100]) // transparent: alpha below 128
                } else if y < 5 {
                    colours[k as usize]
                } else {
                    colours[(k as usize + 1) % 3]
                }
            }))
        })
        .collect();
    write(&path, AnimationFormat::Gif, &frames).expect("write");

    let decoded = decode_gif(&path);
    assert_eq!(decoded.len(), 3);
    for (frame, picture) in decoded.iter().zip(&frames) {
        for (got, want) in frame.buffer().pixels().zip(picture.to_rgba8().pixels()) {
            if want[3] < 128 {
                assert_eq!(got[3], 0, "transparent stays transparent");
            } else {
                assert_eq!(*got, Rgba([want[0], want[1], want[2], 255]));
            }
        }
    }
    let delays: Vec<_> = decoded.iter().map(|f| f.delay().numer_denom_ms()).collect();
    assert_eq!(delays, [(40, 1), (40, 1), (50, 1)]);
    assert!((total_ms(&decoded) - 3000.0 / FPS).abs() <= 10.0);
}

#[test]
fn gif_quantises_many_colours() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("smooth.gif");
    let frames: Vec<Picture> = (0..3u32)
        .map(|k| {
            Picture::from(RgbaImage::from_fn(64, 48, |x, y| {
                let a = if x < 8 { 0 } else { 255 };
                Rgba([(x * 4) as u8, (y * 5) as u8, (k * 60) as u8, a])
            }))
        })
        .collect();
    // 16-bit frames are rounded to 8 bits first.
    let mut frames = frames;
    frames[2] = Picture::from(Rgba16Image::from_fn(64, 48, |x, y| {
        let a = if x < 8 { 0 } else { 65535 };
        Rgba([(x * 4 * 257) as u16, (y * 5 * 257) as u16, 120 * 257, a])
    }));
    write(&path, AnimationFormat::Gif, &frames).expect("write");
    let decoded = decode_gif(&path);
    assert_eq!(decoded.len(), 3);
    for (frame, picture) in decoded.iter().zip(&frames) {
        let mut error = 0u64;
        let mut opaque = 0u64;
        for (got, want) in frame.buffer().pixels().zip(picture.to_rgba8().pixels()) {
            if want[3] == 0 {
                assert_eq!(got[3], 0);
            } else {
                assert_eq!(got[3], 255);
                opaque += 1;
                error += (0..3).map(|c| got[c].abs_diff(want[c]) as u64).sum::<u64>();
            }
        }
        let mean = error as f64 / (3 * opaque) as f64;
        // NeuQuant without dithering, learning from few pixels.
        assert!(mean < 10.0, "mean error {mean}");
    }
}

/// A frame with more opaque pixels than NeuQuant learns from, in smooth gradients
/// with noise (a photograph's colours): the palette still fits it closely.
#[test]
fn gif_of_a_large_photograph_stays_close() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("photo.gif");
    let mut random = support::Rng::new(3);
    let photo = RgbaImage::from_fn(640, 480, |x, y| {
        let (x, y) = (x as f32, y as f32);
        let noise = |random: &mut support::Rng| random.range(-4.0, 4.0);
        Rgba([
            (128.0 + 90.0 * (x / 97.0).sin() + noise(&mut random)) as u8,
            (128.0 + 90.0 * ((x + y) / 151.0).sin() + noise(&mut random)) as u8,
            (100.0 + 80.0 * (x / 31.0).cos() * (y / 47.0).sin() + noise(&mut random)) as u8,
            255,
        ])
    });
    let frame = Picture::from(photo.clone());
    write(&path, AnimationFormat::Gif, std::slice::from_ref(&frame)).expect("write");
    let decoded = decode_gif(&path);
    let mut error = 0u64;
    for (got, want) in decoded[0].buffer().pixels().zip(photo.pixels()) {
        assert_eq!(got[3], 255);
        error += (0..3).map(|c| got[c].abs_diff(want[c]) as u64).sum::<u64>();
    }
    let mean = error as f64 / (3 * photo.len() / 4) as f64;
    assert!(mean < 6.0, "mean error {mean}");
}

#[test]
fn gif_refuses_rates_it_cannot_play() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("fast.gif");
    let error = AnimationWriter::create(&path, AnimationFormat::Gif, 4, 4, 3, 60.0)
        .err()
        .expect("60 fps GIF refused");
    assert!(error.to_string().contains("50"), "{error}");
    let error = AnimationWriter::create(&path, AnimationFormat::Gif, 4, 4, 3, 0.001)
        .err()
        .expect("1000 s frames refused");
    assert!(error.to_string().contains("655.35 s"), "{error}");
    AnimationWriter::create(&path, AnimationFormat::Apng, 4, 4, 3, 60.0).expect("60 fps APNG");
    assert!(listing(dir.path()).is_empty());
}

#[test]
fn png_sequence_round_trip_replaces_a_longer_one() {
    let dir = tempfile::tempdir().expect("tempdir");
    let frames_dir = dir.path().join("frames");
    fs::create_dir(&frames_dir).expect("mkdir");
    // An earlier, longer sequence of the writer's, and files that are not frames.
    let old = Picture::from(random_image(3, 3, 99));
    let format = AnimationFormat::PngSequence;
    let mut writer = AnimationWriter::create(&frames_dir, format, 3, 3, 5, FPS).expect("old");
    for _ in 0..5 {
        writer.push(&old).expect("old frame");
    }
    writer.finish().expect("old sequence");
    fs::write(frames_dir.join("frame_1.png"), b"mine").expect("other");
    fs::write(frames_dir.join("notes.txt"), b"mine").expect("other");

    let mut frames = random_frames(6, 5);
    frames[2] = frames16(6, 5).remove(0);
    let mut with_slash = frames_dir.clone().into_os_string();
    with_slash.push("/");
    let path = PathBuf::from(with_slash);
    let format = AnimationFormat::from_path(&path).expect("format");
    assert_eq!(format, AnimationFormat::PngSequence);

    let mut writer = AnimationWriter::create(&path, format, 6, 5, 3, FPS).expect("create");
    for frame in &frames {
        writer.push(frame).expect("push");
    }
    // Nothing replaced before the end.
    let before = listing(&frames_dir);
    assert_eq!(
        before.iter().filter(|n| !n.starts_with('.')).count(),
        7,
        "{before:?}"
    );
    assert_eq!(
        load_picture(&frames_dir.join("frame_00000.png"), &ImageLimits::default()).expect("old"),
        old
    );
    writer.finish().expect("finish");

    assert_eq!(
        listing(&frames_dir),
        [
            ".c2warp-frames",
            "frame_00000.png",
            "frame_00001.png",
            "frame_00002.png",
            "frame_1.png",
            "notes.txt"
        ]
    );
    let expected_dir = dir.path().join("expected");
    fs::create_dir(&expected_dir).expect("mkdir");
    for (i, frame) in frames.iter().enumerate() {
        let name = format!("frame_{i:05}.png");
        let loaded = load_picture(&frames_dir.join(&name), &ImageLimits::default()).expect("load");
        assert_eq!(&loaded, frame);
        // Byte for byte what save_png_atomic writes.
        save_png_atomic(&expected_dir.join(&name), frame).expect("save");
        assert_eq!(
            fs::read(frames_dir.join(&name)).expect("read"),
            fs::read(expected_dir.join(&name)).expect("read")
        );
    }
}

#[test]
fn png_sequence_never_replaces_or_removes_frames_it_did_not_write() {
    let dir = tempfile::tempdir().expect("tempdir");
    let frames_dir = dir.path().join("frames");
    fs::create_dir(&frames_dir).expect("mkdir");
    // Someone else's frames: one the new sequence would replace, one it would leave.
    fs::write(frames_dir.join("frame_00000.png"), b"theirs").expect("theirs");
    fs::write(frames_dir.join("frame_00030.png"), b"theirs").expect("theirs");
    let error = AnimationWriter::create(&frames_dir, AnimationFormat::PngSequence, 4, 4, 3, FPS)
        .err()
        .expect("a folder of other frames is refused");
    let message = error.to_string();
    assert!(
        message.contains("frame_00000.png and 1 more") && message.contains("empty folder"),
        "{message}"
    );
    assert_eq!(listing(&frames_dir), ["frame_00000.png", "frame_00030.png"]);
    assert_eq!(
        fs::read(frames_dir.join("frame_00030.png")).expect("kept"),
        b"theirs"
    );
}

#[test]
fn png_sequence_directory_is_created_and_removed_if_abandoned() {
    let dir = tempfile::tempdir().expect("tempdir");
    let frames_dir = dir.path().join("new");
    let frames = random_frames(4, 4);
    let mut writer =
        AnimationWriter::create(&frames_dir, AnimationFormat::PngSequence, 4, 4, 3, FPS)
            .expect("create");
    assert!(frames_dir.is_dir());
    writer.push(&frames[0]).expect("push");
    drop(writer);
    assert!(listing(dir.path()).is_empty());

    write(&frames_dir, AnimationFormat::PngSequence, &frames).expect("write");
    // Three frames and the list of them.
    assert_eq!(listing(&frames_dir).len(), 4);

    let orphan = dir.path().join("no").join("such");
    let error = AnimationWriter::create(&orphan, AnimationFormat::PngSequence, 4, 4, 3, FPS)
        .err()
        .expect("missing parent");
    assert!(
        matches!(&error, RenderError::MissingDirectory { dir: d, .. } if d == &dir.path().join("no")),
        "{error}"
    );
}

#[test]
fn an_unfinished_sequence_leaves_the_old_one() {
    let dir = tempfile::tempdir().expect("tempdir");
    let old = Picture::from(random_image(4, 4, 7));
    write(
        dir.path(),
        AnimationFormat::PngSequence,
        &[old.clone(), old.clone(), old],
    )
    .expect("old");
    let before: Vec<Vec<u8>> = listing(dir.path())
        .iter()
        .map(|name| fs::read(dir.path().join(name)).expect("read"))
        .collect();
    let frames = random_frames(4, 4);
    let mut writer =
        AnimationWriter::create(dir.path(), AnimationFormat::PngSequence, 4, 4, 3, FPS)
            .expect("create");
    writer.push(&frames[0]).expect("push");
    writer.push(&frames[1]).expect("push");
    let error = writer.finish().expect_err("too few");
    assert!(error.to_string().contains("only 2 of its 3"), "{error}");
    let after: Vec<Vec<u8>> = listing(dir.path())
        .iter()
        .map(|name| fs::read(dir.path().join(name)).expect("read"))
        .collect();
    assert_eq!(listing(dir.path()).len(), 4);
    assert_eq!(after, before);
}

#[test]
fn bad_requests_are_refused_and_leave_the_old_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    let frames = random_frames(5, 4);
    let wrong = Picture::from(random_image(4, 5, 3));
    for format in [
        AnimationFormat::Apng,
        AnimationFormat::WebP,
        AnimationFormat::Gif,
    ] {
        let path = dir.path().join(match format {
            AnimationFormat::Apng => "old.png",
            AnimationFormat::WebP => "old.webp",
            _ => "old.gif",
        });
        fs::write(&path, b"precious").expect("old file");
        let check = |error: RenderError, needle: &str| {
            let message = error.to_string();
            assert!(matches!(error, RenderError::Animation { .. }), "{message}");
            assert!(message.contains(needle), "{message}");
            assert!(message.contains("old."), "{message}");
            assert!(!message.contains('\n'), "{message}");
            assert_eq!(fs::read(&path).expect("old file"), b"precious");
        };
        let create = |frames: usize, fps: f64| {
            AnimationWriter::create(&path, format, 5, 4, frames, fps).map(|_| ())
        };
        check(create(0, FPS).expect_err("no frames"), "at least one frame");
        for fps in [f64::NAN, f64::INFINITY, 0.0, -1.0, 241.0] {
            check(create(3, fps).expect_err("bad rate"), "frames per second");
        }
        check(
            AnimationWriter::create(&path, format, 0, 4, 3, FPS)
                .map(|_| ())
                .expect_err("empty"),
            "0x4",
        );

        let mut writer = AnimationWriter::create(&path, format, 5, 4, 2, FPS).expect("create");
        check(
            writer.push(&wrong).expect_err("wrong size"),
            "4x5 pixels, not 5x4",
        );
        writer.push(&frames[0]).expect("push");
        check(writer.finish().expect_err("too few"), "only 1 of its 2");

        let mut writer = AnimationWriter::create(&path, format, 5, 4, 2, FPS).expect("create");
        writer.push(&frames[0]).expect("push");
        writer.push(&frames[1]).expect("push");
        check(
            writer.push(&frames[2]).expect_err("too many"),
            "one too many",
        );
        drop(writer);

        // A dropped writer leaves nothing behind.
        let mut writer = AnimationWriter::create(&path, format, 5, 4, 3, FPS).expect("create");
        writer.push(&frames[0]).expect("push");
        drop(writer);
        assert_eq!(fs::read(&path).expect("old file"), b"precious");
        fs::remove_file(&path).expect("remove");
        assert!(listing(dir.path()).is_empty(), "{:?}", listing(dir.path()));
    }
}

#[cfg(unix)]
#[test]
fn a_link_is_followed() {
    let dir = tempfile::tempdir().expect("tempdir");
    let real = dir.path().join("real.webp");
    let link = dir.path().join("link.webp");
    fs::write(&real, b"old").expect("old");
    std::os::unix::fs::symlink("real.webp", &link).expect("symlink");
    let frames = random_frames(3, 3);
    write(&link, AnimationFormat::WebP, &frames).expect("write");
    assert!(fs::symlink_metadata(&link).expect("link").is_symlink());
    assert_eq!(decode_webp(&real).len(), 3);
}
