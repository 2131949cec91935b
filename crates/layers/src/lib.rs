//! Layered artwork: a picture made of layers, as Photoshop (`.psd`) and OpenRaster
//! (`.ora`: Krita, GIMP, MyPaint) files hold it.
//!
//! [`decode`] reads either format from untrusted bytes under [`render::ImageLimits`]
//! (the canvas and every layer within the dimension limits, the pixels within the
//! memory limit, at most [`MAX_LAYERS`] layers) into [`Artwork`]: the canvas size and
//! its layers bottom first, each with its offset, opacity, visibility and pixels
//! (straight alpha, 8 or 16 bits per channel). Groups are flattened into their layers
//! in order (a hidden group hides its layers; a group's opacity multiplies theirs).
//! Layers are clipped to the canvas; layers with no visible pixel left are dropped.
//! [`Artwork::flatten`] composites the visible layers back to front (premultiplied
//! over); [`write_ora`] writes layers as an OpenRaster file.
//!
//! Blend modes other than normal are read and drawn as normal; [`Artwork::notes`]
//! names the layers this concerns.

mod composite;
mod error;
mod ora;
mod psd;

use std::path::Path;

use render::{ImageLimits, Picture};

pub use error::LayerError;
pub use ora::write_ora;

/// The most layers a file may hold (groups and their markers included).
pub const MAX_LAYERS: usize = 1000;

/// One layer of a layered picture.
#[derive(Clone, Debug, PartialEq)]
pub struct Layer {
    /// Its name in the file.
    pub name: String,
    /// Where its pixel (0, 0) lies on the canvas.
    pub x: i32,
    /// Where its pixel (0, 0) lies on the canvas.
    pub y: i32,
    /// Its opacity, 0 to 1 (a group's opacity multiplied in).
    pub opacity: f32,
    /// Whether it is shown (and every group around it).
    pub visible: bool,
    /// Its pixels, straight alpha, clipped to the canvas.
    pub pixels: Picture,
}

impl Layer {
    /// Width and height of its pixels.
    pub fn dimensions(&self) -> (u32, u32) {
        self.pixels.dimensions()
    }
}

/// A layered picture: a canvas and its layers, bottom first.
#[derive(Clone, Debug, PartialEq)]
pub struct Artwork {
    /// Canvas width in pixels.
    pub width: u32,
    /// Canvas height in pixels.
    pub height: u32,
    /// The layers, bottom first.
    pub layers: Vec<Layer>,
    /// What was read but is drawn otherwise than the file asks (one line each), e.g.
    /// the layers whose blend mode is drawn as normal.
    pub notes: Vec<String>,
}

impl Artwork {
    /// A one-layer artwork of a flat picture, at the origin.
    pub fn from_picture(name: &str, picture: Picture) -> Self {
        let (width, height) = picture.dimensions();
        Self {
            width,
            height,
            layers: vec![Layer {
                name: name.to_owned(),
                x: 0,
                y: 0,
                opacity: 1.0,
                visible: true,
                pixels: picture,
            }],
            notes: Vec::new(),
        }
    }

    /// The visible layers composited back to front over transparency (premultiplied
    /// over, each layer's opacity applied): 16 bits per channel when any visible
    /// layer has them, else 8.
    pub fn flatten(&self) -> Picture {
        composite::flatten(self)
    }

    /// Whether any layer has 16 bits per channel.
    pub fn is_16_bit(&self) -> bool {
        self.layers
            .iter()
            .any(|l| l.pixels.bits_per_channel() == 16)
    }
}

/// The layered formats [`decode`] reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Photoshop's `.psd` (not the large-document `.psb`).
    Psd,
    /// OpenRaster's `.ora`.
    Ora,
}

/// The layered format `bytes` are in, from their content (a PSD signature, or a zip
/// whose first entry is OpenRaster's `mimetype`); `None` for anything else, which is
/// left to the image decoders.
pub fn sniff(bytes: &[u8]) -> Option<Format> {
    if bytes.starts_with(b"8BPS") {
        return Some(Format::Psd);
    }
    // A local file header, then the name `mimetype` (30 bytes in), stored, then the
    // type: what the OpenRaster specification asks the first entry to be.
    let is_zip = bytes.starts_with(b"PK\x03\x04");
    let name = bytes.get(30..38);
    (is_zip && name == Some(b"mimetype")).then_some(Format::Ora)
}

/// Reads a layered picture from bytes in either format ([`sniff`]), under `limits`.
///
/// # Errors
/// [`LayerError`]: not a layered file, a corrupt or truncated one, a variant this
/// reader refuses (PSB, a colour mode other than RGB, 1 or 32 bits per channel),
/// too many layers, sizes past `limits`, an archive entry named outside the archive.
pub fn decode(bytes: &[u8], limits: &ImageLimits) -> Result<Artwork, LayerError> {
    match sniff(bytes) {
        Some(Format::Psd) => psd::decode(bytes, limits),
        Some(Format::Ora) => ora::decode(bytes, limits),
        None => Err(LayerError::NotLayered),
    }
}

/// Reads a layered file ([`decode`]); the file itself must be a regular file no
/// larger than `limits.max_alloc_bytes`.
///
/// # Errors
/// Those of [`decode`], and the file's own ([`LayerError::Read`]).
pub fn load(path: &Path, limits: &ImageLimits) -> Result<Artwork, LayerError> {
    let bytes = render::read_regular_file(path, "picture", limits.max_alloc_bytes)
        .map_err(LayerError::Read)?;
    decode(&bytes, limits)
}

/// Keeps the part of a layer at (`x`, `y`) of `width` × `height` pixels that lies on
/// a `canvas_width` × `canvas_height` canvas and within the layer's visible pixels'
/// bounding box: the rectangle to keep, in the layer's own pixels, or `None` when
/// nothing visible is left. `alpha(x, y)` reads the layer's alpha.
fn visible_window(
    (x, y, width, height): (i64, i64, u32, u32),
    (canvas_width, canvas_height): (u32, u32),
    alpha: impl Fn(u32, u32) -> bool,
) -> Option<[u32; 4]> {
    let x0 = (-x).clamp(0, i64::from(width)) as u32;
    let y0 = (-y).clamp(0, i64::from(height)) as u32;
    let x1 = (i64::from(canvas_width) - x).clamp(0, i64::from(width)) as u32;
    let y1 = (i64::from(canvas_height) - y).clamp(0, i64::from(height)) as u32;
    let (mut left, mut top, mut right, mut bottom) = (u32::MAX, u32::MAX, 0, 0);
    for py in y0..y1 {
        for px in x0..x1 {
            if alpha(px, py) {
                left = left.min(px);
                right = right.max(px + 1);
                top = top.min(py);
                bottom = bottom.max(py + 1);
            }
        }
    }
    (left < right).then(|| [left, top, right - left, bottom - top])
}

/// The layer made of `pixels` at (`x`, `y`), clipped to the canvas and to its visible
/// pixels (`None` when none is left).
fn clipped(
    name: String,
    (x, y): (i64, i64),
    opacity: f32,
    visible: bool,
    pixels: Picture,
    canvas: (u32, u32),
) -> Option<Layer> {
    let (width, height) = pixels.dimensions();
    let window = match &pixels {
        Picture::Rgba8(image) => visible_window((x, y, width, height), canvas, |px, py| {
            image.get_pixel(px, py)[3] > 0
        }),
        Picture::Rgba16(image) => visible_window((x, y, width, height), canvas, |px, py| {
            image.get_pixel(px, py)[3] > 0
        }),
    }?;
    let [left, top, w, h] = window;
    let pixels = if [left, top, w, h] == [0, 0, width, height] {
        pixels
    } else {
        match pixels {
            Picture::Rgba8(image) => {
                Picture::Rgba8(image::imageops::crop_imm(&image, left, top, w, h).to_image())
            }
            Picture::Rgba16(image) => {
                Picture::Rgba16(image::imageops::crop_imm(&image, left, top, w, h).to_image())
            }
        }
    };
    // Inside the canvas, so within i32.
    let at = |origin: i64, offset: u32| (origin + i64::from(offset)) as i32;
    Some(Layer {
        name,
        x: at(x, left),
        y: at(y, top),
        opacity: opacity.clamp(0.0, 1.0),
        visible,
        pixels,
    })
}

/// The note that names the layers (`"name" (mode)` each) drawn with normal blending
/// instead of the mode their file asks for; none when there are none.
fn blend_notes(blended: &[String]) -> Vec<String> {
    if blended.is_empty() {
        return Vec::new();
    }
    vec![format!(
        "drawn with normal blending: {}",
        blended.join(", ")
    )]
}

/// Checks a canvas or layer size against `limits` before anything is allocated.
fn check_size(what: &str, width: u64, height: u64, limits: &ImageLimits) -> Result<(), LayerError> {
    if width > u64::from(limits.max_width) || height > u64::from(limits.max_height) {
        return Err(LayerError::TooLarge {
            what: what.to_owned(),
            width,
            height,
            max_width: limits.max_width,
            max_height: limits.max_height,
        });
    }
    Ok(())
}

/// The bytes `count` pixels of RGBA at `bits` bits per channel take.
fn pixel_bytes(count: u64, bits: u8) -> u64 {
    count.saturating_mul(4 * u64::from(bits / 8))
}

/// Keeps a running total of the pixel memory allocated, refusing past the limit.
struct Budget {
    used: u64,
    limit: u64,
}

impl Budget {
    fn new(limits: &ImageLimits) -> Self {
        Self {
            used: 0,
            limit: limits.max_alloc_bytes,
        }
    }

    fn take(&mut self, bytes: u64) -> Result<(), LayerError> {
        self.used = self.used.saturating_add(bytes);
        if self.used > self.limit {
            return Err(LayerError::MemoryLimit { limit: self.limit });
        }
        Ok(())
    }
}
