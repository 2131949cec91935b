//! Compositing the visible layers into one picture.

use image::RgbaImage;
use render::{Picture, Rgba16Image};

use crate::{Artwork, Layer};

/// The visible layers back to front over transparency (see [`Artwork::flatten`]).
pub(crate) fn flatten(artwork: &Artwork) -> Picture {
    let visible = || {
        artwork
            .layers
            .iter()
            .filter(|l| l.visible && l.opacity > 0.0)
    };
    let deep = visible().any(|l| l.pixels.bits_per_channel() == 16);
    if deep {
        let mut out = Rgba16Image::new(artwork.width, artwork.height);
        for layer in visible() {
            draw(
                layer,
                out.dimensions(),
                &mut out,
                widen,
                |a| scale16(a, layer.opacity),
                render::over16,
            );
        }
        Picture::Rgba16(out)
    } else {
        let mut out = RgbaImage::new(artwork.width, artwork.height);
        let dims = out.dimensions();
        for layer in visible() {
            let Picture::Rgba8(pixels) = &layer.pixels else {
                continue;
            };
            draw(
                layer,
                dims,
                &mut out,
                |_, x, y| pixels.get_pixel(x, y).0,
                |a| scale8(a, layer.opacity),
                render::over,
            );
        }
        Picture::Rgba8(out)
    }
}

/// Draws `layer` over `out`: `read` gives its pixel (x, y), `fade` scales an alpha
/// by its opacity, `over` composites.
fn draw<T: Copy>(
    layer: &Layer,
    (canvas_width, canvas_height): (u32, u32),
    out: &mut [T],
    read: impl Fn(&Layer, u32, u32) -> [T; 4],
    fade: impl Fn(T) -> T,
    over: impl Fn([T; 4], [T; 4]) -> [T; 4],
) {
    let (width, height) = layer.dimensions();
    for y in 0..height {
        let cy = i64::from(layer.y) + i64::from(y);
        if !(0..i64::from(canvas_height)).contains(&cy) {
            continue;
        }
        for x in 0..width {
            let cx = i64::from(layer.x) + i64::from(x);
            if !(0..i64::from(canvas_width)).contains(&cx) {
                continue;
            }
            let mut top = read(layer, x, y);
            top[3] = fade(top[3]);
            let at = (cy as usize * canvas_width as usize + cx as usize) * 4;
            let pixel = &mut out[at..at + 4];
            let base = [pixel[0], pixel[1], pixel[2], pixel[3]];
            pixel.copy_from_slice(&over(top, base));
        }
    }
}

/// A layer's pixel at 16 bits per channel.
fn widen(layer: &Layer, x: u32, y: u32) -> [u16; 4] {
    match &layer.pixels {
        Picture::Rgba8(image) => image.get_pixel(x, y).0.map(|c| u16::from(c) * 257),
        Picture::Rgba16(image) => image.get_pixel(x, y).0,
    }
}

/// An 8-bit alpha times an opacity, rounded (exact at opacity 1).
fn scale8(alpha: u8, opacity: f32) -> u8 {
    if opacity >= 1.0 {
        alpha
    } else {
        (f32::from(alpha) * opacity).round() as u8
    }
}

/// A 16-bit alpha times an opacity, rounded (exact at opacity 1).
fn scale16(alpha: u16, opacity: f32) -> u16 {
    if opacity >= 1.0 {
        alpha
    } else {
        (f32::from(alpha) * opacity).round() as u16
    }
}
