//! Criterion benchmarks of the animation writers: one 1024×1024 frame written in each
//! format (animated PNG in 8 and 16 bits, WebP, GIF, a PNG sequence), for a cut-out on
//! transparency (the giraffe, as warped output is) and an opaque picture of many
//! colours (the editor's screenshot). `cargo bench -p render --bench animated`.

use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use image::{Rgba, RgbaImage};
use render::{AnimationFormat, AnimationWriter, Picture, Rgba16Image};

/// A 1024×1024 picture from `assets/<name>`, scaled to 1024 pixels high and centred
/// on a transparent square.
fn asset_square(name: &str) -> RgbaImage {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets")
        .join(name);
    let picture = image::open(&path).expect("the asset decodes").to_rgba8();
    let (w, h) = picture.dimensions();
    let scaled_w = (w * 1024 / h).min(1024);
    let scaled = image::imageops::resize(&picture, scaled_w, 1024, image::imageops::Triangle);
    let mut canvas = RgbaImage::new(1024, 1024);
    image::imageops::overlay(&mut canvas, &scaled, i64::from((1024 - scaled_w) / 2), 0);
    canvas
}

fn one_frame(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let mut group = c.benchmark_group("write_one_1024_frame");
    group.sample_size(10);
    for asset in ["giraffe.png", "screenshot.png"] {
        let canvas = asset_square(asset);
        let deep = Picture::from(Rgba16Image::from_fn(1024, 1024, |x, y| {
            let p = canvas.get_pixel(x, y);
            Rgba(p.0.map(|v| u16::from(v) * 257 + (x as u16 & 0xff)))
        }));
        let frame = Picture::from(canvas);
        for (name, format, picture) in [
            ("apng8", AnimationFormat::Apng, &frame),
            ("apng16", AnimationFormat::Apng, &deep),
            ("webp", AnimationFormat::WebP, &frame),
            ("gif", AnimationFormat::Gif, &frame),
            ("png_sequence", AnimationFormat::PngSequence, &frame),
        ] {
            let path = dir.path().join(match format {
                AnimationFormat::Apng => "a.png",
                AnimationFormat::WebP => "a.webp",
                AnimationFormat::Gif => "a.gif",
                AnimationFormat::PngSequence => "frames",
            });
            group.bench_function(format!("{asset}/{name}"), |b| {
                b.iter(|| {
                    let mut writer = AnimationWriter::create(&path, format, 1024, 1024, 1, 24.0)
                        .expect("a writer");
                    writer.push(picture).expect("a frame");
                    writer.finish().expect("written");
                });
            });
        }
    }
    group.finish();
}

criterion_group!(benches, one_frame);
criterion_main!(benches);
