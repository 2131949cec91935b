//! Layered files written by other programs open with their layers' offsets, opacity,
//! visibility and order: each is flattened and compared with that program's own
//! composite (psd-tools) or one made independently (Pillow, for the Krita-like ORA).

use std::path::PathBuf;

use layers::{Artwork, LayerError};
use render::{ImageLimits, Picture};

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn load(name: &str) -> Artwork {
    layers::load(&data(name), &ImageLimits::default()).expect(name)
}

fn reference(name: &str) -> image::RgbaImage {
    image::open(data(name)).expect(name).to_rgba8()
}

/// The largest difference of premultiplied values over the canvas, in 8-bit levels.
fn premultiplied_difference(a: &image::RgbaImage, b: &image::RgbaImage) -> u32 {
    assert_eq!(a.dimensions(), b.dimensions());
    a.pixels()
        .zip(b.pixels())
        .map(|(p, q)| {
            let pre =
                |p: &image::Rgba<u8>, c: usize| (u32::from(p[c]) * u32::from(p[3]) + 127) / 255;
            (0..3)
                .map(|c| pre(p, c).abs_diff(pre(q, c)))
                .chain([u32::from(p[3]).abs_diff(u32::from(q[3]))])
                .max()
                .unwrap_or(0)
        })
        .max()
        .unwrap_or(0)
}

#[test]
fn a_psd_written_by_psd_tools_flattens_as_psd_tools_composites_it() {
    let artwork = load("psd-tools-8bit.psd");
    assert_eq!((artwork.width, artwork.height), (64, 48));
    let names: Vec<&str> = artwork.layers.iter().map(|l| l.name.as_str()).collect();
    assert_eq!(names, ["ground", "arm", "hidden", "torso", "leg", "shade"]);
    let find = |name: &str| artwork.layers.iter().find(|l| l.name == name).expect(name);
    let arm = find("arm");
    assert_eq!((arm.x, arm.y), (10, 5));
    assert!((arm.opacity - 128.0 / 255.0).abs() < 1e-6);
    assert!(!find("hidden").visible);
    // The group's opacity reaches its layers.
    assert!((find("torso").opacity - 200.0 / 255.0).abs() < 1e-6);
    // Clipped to the canvas: 30 × 20 at (50, 40) keeps 14 × 8.
    let leg = find("leg");
    assert_eq!((leg.x, leg.y, leg.dimensions()), (50, 40, (14, 8)));
    assert_eq!(artwork.notes.len(), 1, "{:?}", artwork.notes);
    assert!(
        artwork.notes[0].contains("\"shade\" (mul "),
        "{:?}",
        artwork.notes
    );

    let flat = artwork.flatten();
    assert_eq!(flat.bits_per_channel(), 8);
    let diff = premultiplied_difference(&flat.into_rgba8(), &reference("psd-tools-8bit.png"));
    // psd-tools composites in floating point; here a layer's alpha times its opacity
    // is rounded, then the over: two roundings.
    assert!(
        diff <= 2,
        "differs from psd-tools' composite by {diff} levels"
    );
}

#[test]
fn a_16_bit_psd_keeps_its_depth() {
    let artwork = load("psd-tools-16bit.psd");
    assert_eq!(artwork.layers.len(), 2);
    assert!(artwork.is_16_bit());
    let Picture::Rgba16(flat) = artwork.flatten() else {
        panic!("a 16-bit PSD flattens to 16 bits");
    };
    // Outside the glaze: the gradient's own 16-bit values.
    assert_eq!(flat.get_pixel(0, 0).0, [0, 1234, 40000, 65535]);
    assert_eq!(flat.get_pixel(39, 29).0, [65535, 1234, 40000, 65535]);
    // Under the glaze (red at alpha 30000 over an opaque pixel).
    let under = flat.get_pixel(25, 10).0;
    let base = artwork.layers[0].pixels.clone();
    let Picture::Rgba16(base) = base else {
        panic!("16 bits")
    };
    let b = base.get_pixel(25, 10).0;
    let expected = |top: u16, base: u16| {
        ((f64::from(top) * 30000.0 + f64::from(base) * (65535.0 - 30000.0)) / 65535.0).round()
    };
    assert!(
        (f64::from(under[0]) - expected(65535, b[0])).abs() <= 1.0,
        "{under:?}"
    );
    assert!(
        (f64::from(under[1]) - expected(0, b[1])).abs() <= 1.0,
        "{under:?}"
    );
    assert_eq!(under[3], 65535);
}

#[test]
fn an_ora_laid_out_as_krita_writes_it_flattens_as_its_layers_composite() {
    let artwork = load("krita-like.ora");
    assert_eq!((artwork.width, artwork.height), (64, 40));
    let names: Vec<&str> = artwork.layers.iter().map(|l| l.name.as_str()).collect();
    assert_eq!(names, ["tail", "ghost", "body", "head"], "bottom first");
    let body = &artwork.layers[2];
    // The group's offset (4, 2) and opacity 0.5 apply to what it holds.
    assert_eq!((body.x, body.y), (24, 12));
    assert!((body.opacity - 0.5).abs() < 1e-6);
    assert!(!artwork.layers[1].visible);
    let diff = premultiplied_difference(
        &artwork.flatten().into_rgba8(),
        &reference("krita-like.png"),
    );
    assert!(
        diff <= 1,
        "differs from the reference composite by {diff} levels"
    );
}

#[test]
fn written_ora_reads_back_layer_for_layer() {
    let artwork = load("psd-tools-8bit.psd");
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("out.ora");
    layers::write_ora(&path, &artwork).expect("write");
    let back = layers::load(&path, &ImageLimits::default()).expect("read back");
    assert_eq!((back.width, back.height), (artwork.width, artwork.height));
    assert_eq!(back.layers.len(), artwork.layers.len());
    for (a, b) in artwork.layers.iter().zip(&back.layers) {
        assert_eq!(
            (&a.name, a.x, a.y, a.visible),
            (&b.name, b.x, b.y, b.visible)
        );
        assert!((a.opacity - b.opacity).abs() < 1e-6);
        assert_eq!(a.pixels, b.pixels, "layer {}", a.name);
    }
    assert_eq!(back.flatten(), artwork.flatten());
    // What readers that take only the merged picture see.
    let zip = std::fs::read(&path).expect("read");
    assert_eq!(layers::sniff(&zip), Some(layers::Format::Ora));
}

#[test]
fn a_flat_picture_is_one_layer() {
    let picture = Picture::Rgba8(image::RgbaImage::from_pixel(
        3,
        2,
        image::Rgba([1, 2, 3, 4]),
    ));
    let artwork = Artwork::from_picture("flat", picture.clone());
    assert_eq!(artwork.flatten(), picture);
}

fn refused(bytes: &[u8]) -> String {
    match layers::decode(bytes, &ImageLimits::default()) {
        Err(e) => e.to_string(),
        Ok(a) => panic!("accepted: {} layers", a.layers.len()),
    }
}

#[test]
fn bad_psds_are_refused_with_one_line_naming_what_is_wrong() {
    let good = std::fs::read(data("psd-tools-8bit.psd")).expect("read");
    // Truncated anywhere: refused, never a panic.
    for len in (0..good.len()).step_by(97) {
        let message = match layers::decode(&good[..len], &ImageLimits::default()) {
            Err(e) => e.to_string(),
            // A cut in the merged picture after the layers is not read.
            Ok(_) => continue,
        };
        assert!(!message.contains('\n'), "{message}");
    }
    let mut header = good[..26].to_vec();
    let set = |bytes: &mut Vec<u8>, at: usize, value: u16| {
        bytes[at..at + 2].copy_from_slice(&value.to_be_bytes());
    };
    let mut psb = header.clone();
    set(&mut psb, 4, 2);
    assert!(refused(&psb).contains("PSB"), "{}", refused(&psb));
    for (mode, name) in [(4, "CMYK"), (2, "indexed"), (9, "Lab")] {
        let mut bytes = header.clone();
        set(&mut bytes, 24, mode);
        assert!(refused(&bytes).contains(name), "{}", refused(&bytes));
    }
    set(&mut header, 22, 32);
    assert!(refused(&header).contains("32 bits"), "{}", refused(&header));
    let mut huge = good[..26].to_vec();
    huge[14..18].copy_from_slice(&100_000u32.to_be_bytes());
    assert!(refused(&huge).contains("limit"), "{}", refused(&huge));
}

#[test]
fn bad_oras_are_refused_with_one_line_naming_what_is_wrong() {
    use std::io::Write;
    let ora = |stack: &str, entries: &[(&str, &[u8])]| {
        let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
        let stored = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Stored);
        zip.start_file("mimetype", stored).expect("zip");
        zip.write_all(b"image/openraster").expect("zip");
        zip.start_file("stack.xml", stored).expect("zip");
        zip.write_all(stack.as_bytes()).expect("zip");
        for (name, bytes) in entries {
            zip.start_file(*name, stored).expect("zip");
            zip.write_all(bytes).expect("zip");
        }
        zip.finish().expect("zip").into_inner()
    };
    let outside = ora(
        r#"<image w="4" h="4"><stack><layer src="../x.png"/></stack></image>"#,
        &[("../x.png", b"")],
    );
    assert!(
        refused(&outside).contains("outside the archive"),
        "{}",
        refused(&outside)
    );
    let missing = ora(
        r#"<image w="4" h="4"><stack><layer src="a.png"/></stack></image>"#,
        &[],
    );
    assert!(
        refused(&missing).contains("no entry"),
        "{}",
        refused(&missing)
    );
    let not_png = ora(
        r#"<image w="4" h="4"><stack><layer name="a" src="a.png"/></stack></image>"#,
        &[("a.png", b"not a png")],
    );
    assert!(
        refused(&not_png).starts_with("layer \"a\""),
        "{}",
        refused(&not_png)
    );
    let huge = ora(r#"<image w="100000" h="4"><stack/></image>"#, &[]);
    assert!(refused(&huge).contains("limit"), "{}", refused(&huge));
    let broken = ora(
        r#"<image w="4" h="4"><stack><layer src="a.png" x="1e400"/>"#,
        &[],
    );
    assert!(
        refused(&broken).contains("not a number"),
        "{}",
        refused(&broken)
    );
    let many = format!(
        r#"<image w="4" h="4"><stack>{}</stack></image>"#,
        r#"<layer src="a.png"/>"#.repeat(1001)
    );
    assert!(refused(&ora(&many, &[])).contains("1001 layers"));
    let good = std::fs::read(data("krita-like.ora")).expect("read");
    for len in (0..good.len()).step_by(53) {
        if let Err(e) = layers::decode(&good[..len], &ImageLimits::default()) {
            assert!(!e.to_string().contains('\n'), "{e}");
        }
    }
    assert!(matches!(
        layers::decode(b"PK\x03\x04", &ImageLimits::default()),
        Err(LayerError::NotLayered)
    ));
}

#[test]
fn an_entry_inflating_past_the_memory_limit_is_refused_before_inflating() {
    use std::io::Write;
    // A 64 MiB layer of zeros deflates to ~64 KiB; with a 16 MiB limit it is refused
    // from its declared size.
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let deflated = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    zip.start_file(
        "mimetype",
        deflated.compression_method(zip::CompressionMethod::Stored),
    )
    .expect("zip");
    zip.write_all(b"image/openraster").expect("zip");
    zip.start_file("stack.xml", deflated).expect("zip");
    zip.write_all(br#"<image w="4" h="4"><stack><layer src="big.png"/></stack></image>"#)
        .expect("zip");
    zip.start_file("big.png", deflated).expect("zip");
    zip.write_all(&vec![0; 64 << 20]).expect("zip");
    let bytes = zip.finish().expect("zip").into_inner();
    let limits = ImageLimits {
        max_alloc_bytes: 16 << 20,
        ..ImageLimits::default()
    };
    let error = layers::decode(&bytes, &limits).expect_err("refused");
    assert!(matches!(error, LayerError::MemoryLimit { .. }), "{error}");
}

#[test]
fn empty_layers_are_skipped_and_layers_past_the_canvas_clipped() {
    let layer = |name: &str, x: i32, alpha: u8| layers::Layer {
        name: name.to_owned(),
        x,
        y: 0,
        opacity: 1.0,
        visible: true,
        pixels: Picture::Rgba8(image::RgbaImage::from_pixel(
            4,
            4,
            image::Rgba([9, 9, 9, alpha]),
        )),
    };
    let artwork = Artwork {
        width: 6,
        height: 4,
        layers: vec![
            layer("empty", 0, 0),
            layer("half off", 4, 255),
            layer("off", 9, 255),
        ],
        notes: Vec::new(),
    };
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("clip.ora");
    layers::write_ora(&path, &artwork).expect("write");
    let back = layers::load(&path, &ImageLimits::default()).expect("read");
    let kept: Vec<(&str, i32, (u32, u32))> = back
        .layers
        .iter()
        .map(|l| (l.name.as_str(), l.x, l.dimensions()))
        .collect();
    assert_eq!(kept, [("half off", 4, (2, 4))]);
}

#[test]
fn the_sample_character_opens_as_its_parts_in_order() {
    // assets/puppet.ora (scripts/puppet_ora.py): seven parts, each drawn whole on its
    // own layer and cropped to its pixels, as Krita writes them.
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets/puppet.ora");
    let artwork = layers::load(&path, &ImageLimits::default()).expect("the sample opens");
    assert_eq!((artwork.width, artwork.height), (640, 720));
    let names: Vec<&str> = artwork.layers.iter().map(|l| l.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "tail",
            "arm (back)",
            "leg (back)",
            "body",
            "leg (front)",
            "head",
            "arm (front)"
        ],
        "bottom first"
    );
    assert!(artwork.layers.iter().all(|l| l.visible && l.opacity == 1.0));
    // The front arm starts under the body's outline: drawn whole, partly hidden.
    let arm = &artwork.layers[6];
    let body = &artwork.layers[3];
    let (aw, ah) = arm.dimensions();
    let (bw, _) = body.dimensions();
    assert!(arm.x + aw as i32 > body.x && arm.x < body.x + bw as i32);
    assert!(arm.y < body.y + 40 && arm.y + ah as i32 > body.y);
    // Its layers flattened are the merged picture the file carries (Pillow's).
    let bytes = std::fs::read(&path).expect("read");
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes)).expect("a zip");
    let mut merged = Vec::new();
    std::io::Read::read_to_end(
        &mut zip.by_name("mergedimage.png").expect("merged"),
        &mut merged,
    )
    .expect("merged picture");
    let merged = image::load_from_memory(&merged).expect("png").to_rgba8();
    let diff = premultiplied_difference(&artwork.flatten().into_rgba8(), &merged);
    assert!(
        diff <= 1,
        "differs from the file's merged picture by {diff} levels"
    );
}
