//! OpenRaster (`.ora`): a zip holding `mimetype` (first, stored), `stack.xml` (the
//! layers, top first, in nested `<stack>`s) and a PNG per layer, as the OpenRaster
//! specification has it and Krita, GIMP and MyPaint write it.
//!
//! Read: each `<layer>`'s `src`, `name`, `x`, `y`, `opacity`, `visibility` and
//! `composite-op`; a `<stack>`'s own offset, opacity and visibility apply to what it
//! holds. Refused: an entry named outside the archive (`../x`, an absolute path), an
//! entry that would inflate past its declared size or past the memory limit (checked
//! before inflating and while inflating).

use std::borrow::Cow;
use std::io::{Cursor, Read, Write};
use std::path::Path;

use image::imageops::FilterType;
use quick_xml::events::{BytesStart, Event};
use render::{ImageLimits, Picture, RenderError};
use zip::ZipArchive;
use zip::write::SimpleFileOptions;

use crate::{Artwork, Budget, LayerError, MAX_LAYERS, check_size, clipped};

const FORMAT: &str = "OpenRaster file";

fn corrupt(detail: impl Into<String>) -> LayerError {
    LayerError::Corrupt {
        format: FORMAT,
        detail: detail.into(),
    }
}

/// A `<layer>` of `stack.xml`, with its stacks' offsets, opacities and visibility
/// applied.
struct Entry {
    src: String,
    name: String,
    x: i64,
    y: i64,
    opacity: f32,
    visible: bool,
    op: String,
}

/// What a `<stack>` passes down to what it holds.
#[derive(Clone, Copy)]
struct Frame {
    x: i64,
    y: i64,
    opacity: f32,
    visible: bool,
}

impl Frame {
    /// What the outermost stack's parent passes down: nothing.
    const ROOT: Self = Self {
        x: 0,
        y: 0,
        opacity: 1.0,
        visible: true,
    };
}

/// Reads an OpenRaster file (see the module's documentation).
pub(crate) fn decode(bytes: &[u8], limits: &ImageLimits) -> Result<Artwork, LayerError> {
    let mut archive =
        ZipArchive::new(Cursor::new(bytes)).map_err(|e| corrupt(format!("not a zip: {e}")))?;
    let mut budget = Budget::new(limits);
    let stack = read_entry(&mut archive, "stack.xml", 16 << 20, &mut budget)?;
    let stack = std::str::from_utf8(&stack).map_err(|_| corrupt("stack.xml is not UTF-8"))?;
    let (width, height, entries) = parse_stack(stack)?;
    check_size("the canvas", width, height, limits)?;
    let (width, height) = (width as u32, height as u32);
    let mut layers = Vec::new();
    let mut blended = Vec::new();
    // stack.xml lists the top first.
    for entry in entries.into_iter().rev() {
        check_source(&entry.src)?;
        let max = limits.max_alloc_bytes.saturating_sub(budget.used);
        let png = read_entry(&mut archive, &entry.src, max, &mut budget)?;
        let picture = render::decode_picture(&png, limits).map_err(|source| LayerError::Layer {
            name: entry.name.clone(),
            source,
        })?;
        drop(png);
        let (w, h) = picture.dimensions();
        budget.take(crate::pixel_bytes(
            u64::from(w) * u64::from(h),
            picture.bits_per_channel(),
        ))?;
        if !matches!(entry.op.as_str(), "" | "svg:src-over") {
            blended.push(format!("{:?} ({})", entry.name, entry.op));
        }
        layers.extend(clipped(
            entry.name,
            (entry.x, entry.y),
            entry.opacity,
            entry.visible,
            picture,
            (width, height),
        ));
    }
    let notes = if blended.is_empty() {
        Vec::new()
    } else {
        vec![format!(
            "drawn with normal blending: {}",
            blended.join(", ")
        )]
    };
    Ok(Artwork {
        width,
        height,
        layers,
        notes,
    })
}

/// Refuses a layer source that names something outside the archive.
fn check_source(src: &str) -> Result<(), LayerError> {
    let outside = src.is_empty()
        || src.starts_with('/')
        || src.contains('\\')
        || src
            .split('/')
            .any(|part| part == ".." || part.contains(':'));
    if outside {
        return Err(LayerError::Unsupported {
            format: FORMAT,
            detail: format!("a layer source outside the archive ({src:?})"),
        });
    }
    Ok(())
}

/// One archive entry's bytes, refused before inflating when it declares more than
/// `max` bytes, and while inflating when it holds more than it declares.
fn read_entry(
    archive: &mut ZipArchive<Cursor<&[u8]>>,
    name: &str,
    max: u64,
    budget: &mut Budget,
) -> Result<Vec<u8>, LayerError> {
    let mut file = archive.by_name(name).map_err(|e| match e {
        zip::result::ZipError::FileNotFound => corrupt(format!("it has no entry {name:?}")),
        other => corrupt(format!("entry {name:?}: {other}")),
    })?;
    let declared = file.size();
    if declared > max {
        return Err(LayerError::MemoryLimit { limit: max });
    }
    budget.take(declared)?;
    let mut bytes = Vec::with_capacity(declared as usize);
    (&mut file)
        .take(declared + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| corrupt(format!("entry {name:?}: {e}")))?;
    if bytes.len() as u64 != declared {
        return Err(corrupt(format!(
            "entry {name:?} holds {} bytes where it declares {declared}",
            bytes.len()
        )));
    }
    Ok(bytes)
}

/// The canvas size and the layers of `stack.xml`, top first.
fn parse_stack(xml: &str) -> Result<(u64, u64, Vec<Entry>), LayerError> {
    let mut reader = quick_xml::Reader::from_str(xml);
    let mut size = None;
    let mut frames: Vec<Frame> = Vec::new();
    let mut entries = Vec::new();
    loop {
        let event = reader
            .read_event()
            .map_err(|e| corrupt(format!("stack.xml: {e}")))?;
        let (element, opens) = match &event {
            Event::Start(e) => (e, true),
            Event::Empty(e) => (e, false),
            Event::End(e) if e.name().as_ref() == b"stack" => {
                frames.pop();
                continue;
            }
            Event::Eof => break,
            _ => continue,
        };
        let attrs = Attributes::of(element)?;
        match element.name().as_ref() {
            b"image" => {
                let w = attrs
                    .number("w")?
                    .ok_or_else(|| corrupt("<image> has no w"))?;
                let h = attrs
                    .number("h")?
                    .ok_or_else(|| corrupt("<image> has no h"))?;
                if !(w >= 1.0 && h >= 1.0 && w.fract() == 0.0 && h.fract() == 0.0) {
                    return Err(corrupt(format!("a canvas of {w} × {h}")));
                }
                size = Some((w.min(u64::MAX as f64) as u64, h.min(u64::MAX as f64) as u64));
            }
            b"stack" => {
                let parent = frames.last().copied().unwrap_or(Frame::ROOT);
                let frame = attrs.frame(parent)?;
                if opens {
                    frames.push(frame);
                }
            }
            b"layer" => {
                let parent = frames.last().copied().unwrap_or(Frame::ROOT);
                let frame = attrs.frame(parent)?;
                let src = attrs
                    .get("src")
                    .ok_or_else(|| corrupt("a <layer> has no src"))?;
                entries.push(Entry {
                    name: attrs.get("name").unwrap_or_else(|| src.clone()),
                    src,
                    x: frame.x,
                    y: frame.y,
                    opacity: frame.opacity,
                    visible: frame.visible,
                    op: attrs.get("composite-op").unwrap_or_default(),
                });
                if entries.len() > MAX_LAYERS {
                    return Err(LayerError::TooManyLayers {
                        count: entries.len(),
                        max: MAX_LAYERS,
                    });
                }
            }
            _ => {}
        }
    }
    let (w, h) = size.ok_or_else(|| corrupt("stack.xml has no <image>"))?;
    Ok((w, h, entries))
}

/// An element's attributes, unescaped.
struct Attributes(Vec<(String, String)>);

impl Attributes {
    fn of(element: &BytesStart) -> Result<Self, LayerError> {
        element
            .attributes()
            .map(|a| {
                let a = a.map_err(|e| corrupt(format!("stack.xml: {e}")))?;
                let key = String::from_utf8_lossy(a.key.as_ref()).into_owned();
                let value = a
                    .normalized_value(quick_xml::XmlVersion::Implicit1_0)
                    .map_err(|e| corrupt(format!("stack.xml: {e}")))?;
                Ok((key, value.into_owned()))
            })
            .collect::<Result<_, _>>()
            .map(Self)
    }

    fn get(&self, key: &str) -> Option<String> {
        self.0
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.clone())
    }

    fn number(&self, key: &str) -> Result<Option<f64>, LayerError> {
        self.get(key)
            .map(|v| {
                v.trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|n| n.is_finite())
                    .ok_or_else(|| corrupt(format!("{key}={v:?} is not a number")))
            })
            .transpose()
    }

    /// What this element passes down: its offset added to its parent's, its opacity
    /// times its parent's, hidden if either is.
    fn frame(&self, parent: Frame) -> Result<Frame, LayerError> {
        let offset = |key| -> Result<i64, LayerError> {
            let v = self.number(key)?.unwrap_or(0.0);
            if v.abs() > 1e9 {
                return Err(corrupt(format!("{key}={v} is out of range")));
            }
            Ok(v.round() as i64)
        };
        let opacity = self.number("opacity")?.unwrap_or(1.0).clamp(0.0, 1.0) as f32;
        Ok(Frame {
            x: parent.x + offset("x")?,
            y: parent.y + offset("y")?,
            opacity: parent.opacity * opacity,
            visible: parent.visible && self.get("visibility").as_deref() != Some("hidden"),
        })
    }
}

/// Writes `artwork` as an OpenRaster file at `path`, atomically: each layer as a PNG
/// of its depth at its offset, opacity and visibility, with the merged picture and a
/// thumbnail, as Krita and GIMP open it.
///
/// # Errors
/// [`RenderError`] when a layer cannot be encoded or the file cannot be written (an
/// existing `path` is then left as it was).
pub fn write_ora(path: &Path, artwork: &Artwork) -> Result<(), RenderError> {
    let io = |e: zip::result::ZipError| RenderError::Encode {
        path: path.to_owned(),
        detail: e.to_string(),
    };
    let write_err = |source| RenderError::Io {
        path: path.to_owned(),
        action: "write",
        source,
    };
    let stored = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
    let deflated =
        SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    let mut zip = zip::ZipWriter::new(Cursor::new(Vec::new()));
    zip.start_file("mimetype", stored).map_err(io)?;
    zip.write_all(b"image/openraster").map_err(write_err)?;

    let mut xml = format!(
        "<?xml version='1.0' encoding='UTF-8'?>\n<image version=\"0.0.5\" w=\"{}\" h=\"{}\">\n <stack>\n",
        artwork.width, artwork.height
    );
    // Top first, as stack.xml lists them.
    for (i, layer) in artwork.layers.iter().enumerate().rev() {
        xml.push_str(&format!(
            "  <layer name=\"{}\" src=\"data/layer{i:03}.png\" x=\"{}\" y=\"{}\" opacity=\"{}\" visibility=\"{}\" composite-op=\"svg:src-over\"/>\n",
            quick_xml::escape::escape(layer.name.as_str()),
            layer.x,
            layer.y,
            layer.opacity,
            if layer.visible { "visible" } else { "hidden" },
        ));
    }
    xml.push_str(" </stack>\n</image>\n");
    zip.start_file("stack.xml", deflated).map_err(io)?;
    zip.write_all(xml.as_bytes()).map_err(write_err)?;

    let png = |picture: &Picture| -> Result<Vec<u8>, RenderError> {
        let mut bytes = Vec::new();
        render::write_png(&mut bytes, picture, path)?;
        Ok(bytes)
    };
    for (i, layer) in artwork.layers.iter().enumerate() {
        zip.start_file(format!("data/layer{i:03}.png"), stored)
            .map_err(io)?;
        zip.write_all(&png(&layer.pixels)?).map_err(write_err)?;
    }
    let merged = artwork.flatten();
    zip.start_file("mergedimage.png", stored).map_err(io)?;
    zip.write_all(&png(&merged)?).map_err(write_err)?;
    let thumbnail = thumbnail(&merged);
    zip.start_file("Thumbnails/thumbnail.png", stored)
        .map_err(io)?;
    zip.write_all(&png(&Picture::Rgba8(thumbnail))?)
        .map_err(write_err)?;
    let bytes = zip.finish().map_err(io)?.into_inner();
    render::write_atomic(path, &bytes)
}

/// The picture fitted within 256 × 256 pixels, 8 bits per channel.
fn thumbnail(picture: &Picture) -> image::RgbaImage {
    let image: Cow<'_, image::RgbaImage> = picture.to_rgba8();
    let (w, h) = image.dimensions();
    let scale = (256.0 / f64::from(w.max(h))).min(1.0);
    let (tw, th) = (
        ((f64::from(w) * scale).round() as u32).max(1),
        ((f64::from(h) * scale).round() as u32).max(1),
    );
    image::imageops::resize(image.as_ref(), tw, th, FilterType::Triangle)
}
