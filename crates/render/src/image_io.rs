//! Decoding images from untrusted files with limits on size and memory.

use std::io::Cursor;
use std::path::Path;

use image::error::LimitErrorKind;
use image::metadata::Orientation;
use image::{
    ColorType, DynamicImage, ImageDecoder, ImageError, ImageFormat, ImageReader, RgbaImage,
};

use crate::{Picture, RenderError, jpeg, read_regular_file};

/// What `<memory>` errors name instead of a path (see [`decode_image`]).
const IN_MEMORY: &str = "<memory>";

/// Bounds on what [`load_image`] and [`decode_image`] accept.
///
/// The dimension limits are checked against the image header before any pixel
/// buffer is allocated, so a file claiming to be 100000×100000 pixels fails
/// at once. The memory limit bounds the decoder's pixel buffer plus the RGBA
/// copy returned (and, for [`load_image`], the size of the file itself).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ImageLimits {
    /// Widest accepted image, in pixels (default 16384).
    pub max_width: u32,
    /// Tallest accepted image, in pixels (default 16384).
    pub max_height: u32,
    /// Most bytes decoding may allocate (default 2 GiB).
    pub max_alloc_bytes: u64,
}

impl Default for ImageLimits {
    fn default() -> Self {
        Self {
            max_width: 16384,
            max_height: 16384,
            max_alloc_bytes: 2 << 30,
        }
    }
}

impl ImageLimits {
    fn to_image_limits(&self) -> image::Limits {
        let mut limits = image::Limits::default();
        limits.max_image_width = Some(self.max_width);
        limits.max_image_height = Some(self.max_height);
        limits.max_alloc = Some(self.max_alloc_bytes);
        limits
    }
}

/// Reads and decodes an image file (PNG, JPEG, WebP, TIFF, BMP, or the first frame
/// of a GIF; the format is found from the content, not the name) into RGBA8,
/// applying the EXIF orientation.
///
/// A 16-bit picture is rounded to 8 bits; [`load_picture`] keeps its depth.
///
/// # Errors
/// Those of [`load_picture`].
pub fn load_image(path: &Path, limits: &ImageLimits) -> Result<RgbaImage, RenderError> {
    load_picture(path, limits).map(Picture::into_rgba8)
}

/// Reads and decodes an image file as [`load_image`] does, keeping 16 bits per
/// channel where the file has more than 8 (16-bit PNG or TIFF, floating-point TIFF).
///
/// Only a regular file is read (a FIFO or a device is refused before it is opened),
/// and no more of it than `limits.max_alloc_bytes`.
///
/// # Errors
/// [`RenderError::NotFound`] if there is no such file,
/// [`RenderError::NotRegularFile`] if it is a FIFO, device, socket or directory,
/// [`RenderError::MemoryLimit`] if it is larger than `limits.max_alloc_bytes`,
/// [`RenderError::Io`] if it cannot be read, and the errors of [`decode_picture`]
/// naming `path`.
pub fn load_picture(path: &Path, limits: &ImageLimits) -> Result<Picture, RenderError> {
    let bytes = read_regular_file(path, "image", limits.max_alloc_bytes).map_err(|e| match e {
        RenderError::FileTooLarge { .. } => RenderError::MemoryLimit {
            path: path.to_owned(),
            limit: limits.max_alloc_bytes,
        },
        other => other,
    })?;
    decode(&bytes, limits, path)
}

/// Decodes an image held in memory (format guessed from the content) into RGBA8, as
/// [`load_image`] does.
///
/// Errors name the placeholder path `<memory>`.
///
/// # Errors
/// Those of [`decode_picture`].
///
/// # Example
/// ```
/// use render::{decode_image, ImageLimits, RenderError};
///
/// let err = decode_image(b"hello, world", &ImageLimits::default()).expect_err("must fail");
/// assert!(matches!(err, RenderError::UnsupportedFormat { .. }));
/// ```
pub fn decode_image(bytes: &[u8], limits: &ImageLimits) -> Result<RgbaImage, RenderError> {
    decode(bytes, limits, Path::new(IN_MEMORY)).map(Picture::into_rgba8)
}

/// Decodes an image held in memory, keeping 16 bits per channel where the data has
/// more than 8 (see [`load_picture`]). Errors name the placeholder path `<memory>`.
///
/// # Errors
/// * [`RenderError::UnsupportedFormat`] if the data is none of PNG, JPEG, WebP,
///   TIFF, BMP or GIF;
/// * [`RenderError::TooLarge`] if the header claims dimensions beyond `limits`;
/// * [`RenderError::MemoryLimit`] if decoding would allocate more than allowed;
/// * [`RenderError::Corrupt`] for truncated or malformed data (a JPEG is refused
///   before decoding when it ends before its end-of-image marker, or when it holds
///   too few bytes for the pixels its header claims);
/// * [`RenderError::UnsupportedVariant`] for a feature the decoder lacks.
pub fn decode_picture(bytes: &[u8], limits: &ImageLimits) -> Result<Picture, RenderError> {
    decode(bytes, limits, Path::new(IN_MEMORY))
}

/// Decodes an image held in memory as [`decode_picture`] does, its errors naming
/// `path` (where the bytes were read from).
///
/// # Errors
/// Those of [`decode_picture`].
pub fn decode_picture_named(
    bytes: &[u8],
    limits: &ImageLimits,
    path: &Path,
) -> Result<Picture, RenderError> {
    decode(bytes, limits, path)
}

/// The dimensions an image header claims, read without decoding pixels.
fn claimed_dimensions(bytes: &[u8], format: ImageFormat) -> Option<(u32, u32)> {
    match format {
        // Signature (8), chunk length (4), "IHDR", width, height (big-endian).
        ImageFormat::Png => {
            let be = |at: usize| {
                let b: [u8; 4] = bytes.get(at..at + 4)?.try_into().ok()?;
                Some(u32::from_be_bytes(b))
            };
            (bytes.get(12..16)? == b"IHDR").then_some((be(16)?, be(20)?))
        }
        _ => {
            let mut limits = image::Limits::default();
            limits.max_alloc = Some(64 << 20);
            let mut reader = ImageReader::with_format(Cursor::new(bytes), format);
            reader.limits(limits);
            reader.into_dimensions().ok()
        }
    }
}

fn decode(bytes: &[u8], limits: &ImageLimits, path: &Path) -> Result<Picture, RenderError> {
    let format = match image::guess_format(bytes) {
        Ok(
            format @ (ImageFormat::Png
            | ImageFormat::Jpeg
            | ImageFormat::WebP
            | ImageFormat::Tiff
            | ImageFormat::Bmp
            | ImageFormat::Gif),
        ) => format,
        _ => {
            return Err(RenderError::UnsupportedFormat {
                path: path.to_owned(),
            });
        }
    };
    let classify = |error: ImageError| classify(error, bytes, format, limits, path);
    let too_large = |width, height| RenderError::TooLarge {
        path: path.to_owned(),
        width,
        height,
        limit: (limits.max_width, limits.max_height),
    };
    // Decoders accept JPEG data cut short (the missing rows come out grey) and spend
    // what the header claims on a few bytes; refuse such data before decoding.
    if format == ImageFormat::Jpeg
        && let Err(problem) = jpeg::check(bytes)
    {
        return Err(RenderError::Corrupt {
            path: path.to_owned(),
            detail: problem.detail(),
        });
    }
    // Fail on the header's claim before the decoder allocates anything.
    if format == ImageFormat::Png
        && let Some((w, h)) = claimed_dimensions(bytes, format)
        && (w > limits.max_width || h > limits.max_height)
    {
        return Err(too_large(w, h));
    }

    let mut image_limits = limits.to_image_limits();
    let mut reader = ImageReader::with_format(Cursor::new(bytes), format);
    reader.limits(image_limits.clone());
    let mut decoder = reader.into_decoder().map_err(classify)?;

    let (width, height) = decoder.dimensions();
    let decoded = decoder.total_bytes();
    let color = decoder.color_type();
    // More than 8 bits per channel are kept as 16.
    let wide = color.bits_per_pixel() > 8 * u16::from(color.channel_count());
    let rgba_copy = match (color, wide) {
        (ColorType::Rgba8, _) | (ColorType::Rgba16, _) => 0,
        (_, false) => u64::from(width) * u64::from(height) * 4,
        (_, true) => u64::from(width) * u64::from(height) * 8,
    };
    let memory_limit = || RenderError::MemoryLimit {
        path: path.to_owned(),
        limit: limits.max_alloc_bytes,
    };
    if decoded.saturating_add(rgba_copy) > limits.max_alloc_bytes {
        return Err(memory_limit());
    }
    image_limits.reserve(decoded).map_err(|_| memory_limit())?;
    decoder.set_limits(image_limits).map_err(classify)?;
    // Broken metadata should not make an otherwise good image unreadable.
    let orientation = decoder.orientation().unwrap_or(Orientation::NoTransforms);
    let mut image = DynamicImage::from_decoder(decoder).map_err(classify)?;
    image.apply_orientation(orientation);
    Ok(if wide {
        Picture::Rgba16(image.into_rgba16())
    } else {
        Picture::Rgba8(image.into_rgba8())
    })
}

/// Turns a decoder error into the crate's error for `path`.
fn classify(
    error: ImageError,
    bytes: &[u8],
    format: ImageFormat,
    limits: &ImageLimits,
    path: &Path,
) -> RenderError {
    let path = path.to_owned();
    match error {
        ImageError::Limits(e) => match e.kind() {
            LimitErrorKind::DimensionError => {
                let (width, height) = claimed_dimensions(bytes, format).unwrap_or((0, 0));
                RenderError::TooLarge {
                    path,
                    width,
                    height,
                    limit: (limits.max_width, limits.max_height),
                }
            }
            LimitErrorKind::InsufficientMemory => RenderError::MemoryLimit {
                path,
                limit: limits.max_alloc_bytes,
            },
            _ => RenderError::UnsupportedVariant {
                path,
                detail: e.to_string(),
            },
        },
        ImageError::Unsupported(e) => RenderError::UnsupportedVariant {
            path,
            detail: e.to_string(),
        },
        // The data is in memory, so a read error can only mean it ended early.
        ImageError::IoError(e) => RenderError::Corrupt {
            path,
            detail: e.to_string(),
        },
        other => RenderError::Corrupt {
            path,
            detail: other.to_string(),
        },
    }
}
