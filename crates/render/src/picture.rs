//! A decoded picture with 8 or 16 bits per channel.

use std::borrow::Cow;

use image::{ImageBuffer, Rgba, RgbaImage};

/// An RGBA image with 16 bits per channel (straight alpha).
pub type Rgba16Image = ImageBuffer<Rgba<u16>, Vec<u16>>;

/// A decoded picture in the depth its file had: 8 bits per channel, or 16 for a
/// 16-bit (or floating-point) source, so that a 16-bit picture can be warped and
/// written back without losing precision.
#[derive(Clone, Debug, PartialEq)]
pub enum Picture {
    /// 8 bits per channel.
    Rgba8(RgbaImage),
    /// 16 bits per channel.
    Rgba16(Rgba16Image),
}

impl Picture {
    /// Width and height in pixels.
    pub fn dimensions(&self) -> (u32, u32) {
        match self {
            Self::Rgba8(image) => image.dimensions(),
            Self::Rgba16(image) => image.dimensions(),
        }
    }

    /// Bits per channel: 8 or 16.
    pub fn bits_per_channel(&self) -> u8 {
        match self {
            Self::Rgba8(_) => 8,
            Self::Rgba16(_) => 16,
        }
    }

    /// The picture with 8 bits per channel (for previews, meshing by alpha and the
    /// GPU): borrowed when it already is, else rounded from 16 bits.
    pub fn to_rgba8(&self) -> Cow<'_, RgbaImage> {
        match self {
            Self::Rgba8(image) => Cow::Borrowed(image),
            Self::Rgba16(image) => Cow::Owned(narrow(image)),
        }
    }

    /// The picture with 8 bits per channel, rounded from 16 bits if need be.
    pub fn into_rgba8(self) -> RgbaImage {
        match self {
            Self::Rgba8(image) => image,
            Self::Rgba16(image) => narrow(&image),
        }
    }
}

impl From<RgbaImage> for Picture {
    fn from(image: RgbaImage) -> Self {
        Self::Rgba8(image)
    }
}

impl From<Rgba16Image> for Picture {
    fn from(image: Rgba16Image) -> Self {
        Self::Rgba16(image)
    }
}

/// Rounds 16-bit channels to 8 bits (`v · 255 / 65535`, to nearest).
fn narrow(image: &Rgba16Image) -> RgbaImage {
    let (width, height) = image.dimensions();
    let data = image
        .as_raw()
        .iter()
        .map(|&v| ((u32::from(v) * 255 + 32767) / 65535) as u8)
        .collect();
    RgbaImage::from_raw(width, height, data).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn narrowing_rounds_to_nearest() {
        let wide =
            Rgba16Image::from_raw(1, 1, vec![0, 257 * 200, 65535, 257 * 3 + 128]).expect("1x1");
        let picture = Picture::from(wide);
        assert_eq!(picture.bits_per_channel(), 16);
        assert_eq!(picture.to_rgba8().as_raw(), &vec![0, 200, 255, 3]);
        let narrow = RgbaImage::from_raw(1, 1, vec![1, 2, 3, 4]).expect("1x1");
        assert!(matches!(Picture::from(narrow).to_rgba8(), Cow::Borrowed(_)));
    }
}
