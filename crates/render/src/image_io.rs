//! Decoding images from untrusted files with limits on size and memory.

use std::io::{Cursor, Read};
use std::path::Path;

use image::error::LimitErrorKind;
use image::metadata::Orientation;
use image::{
    ColorType, DynamicImage, ImageDecoder, ImageError, ImageFormat, ImageReader, RgbaImage,
};

use crate::RenderError;

/// What `<memory>` errors name instead of a path (see [`decode_image`]).
const IN_MEMORY: &str = "<memory>";

/// Bounds on what [`load_image`] and [`decode_image`] accept.
///
/// The dimension limits are checked against the image header before any pixel
/// buffer is allocated, so a file claiming to be 100000×100000 pixels fails
/// at once. The memory limit bounds the decoder's pixel buffer plus the RGBA8
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

/// Reads and decodes a PNG or JPEG file (format guessed from its content, not
/// its name) into RGBA8, applying the EXIF orientation of JPEGs.
///
/// # Errors
/// [`RenderError::NotFound`] if there is no such file, [`RenderError::Io`] if
/// it cannot be read, and the errors of [`decode_image`] naming `path`.
pub fn load_image(path: &Path, limits: &ImageLimits) -> Result<RgbaImage, RenderError> {
    let io_error = |source: std::io::Error| {
        if source.kind() == std::io::ErrorKind::NotFound {
            RenderError::NotFound {
                path: path.to_owned(),
            }
        } else {
            RenderError::Io {
                path: path.to_owned(),
                action: "read",
                source,
            }
        }
    };
    let file = std::fs::File::open(path).map_err(io_error)?;
    let memory_limit = || RenderError::MemoryLimit {
        path: path.to_owned(),
        limit: limits.max_alloc_bytes,
    };
    let expected_len = file.metadata().map_err(io_error)?.len();
    if expected_len > limits.max_alloc_bytes {
        return Err(memory_limit());
    }
    let mut bytes = Vec::new();
    bytes
        .try_reserve_exact(usize::try_from(expected_len).map_err(|_| memory_limit())?)
        .map_err(|_| memory_limit())?;
    // `take` guards against a file that grows while being read.
    file.take(limits.max_alloc_bytes.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(io_error)?;
    if bytes.len() as u64 > limits.max_alloc_bytes {
        return Err(memory_limit());
    }
    decode(&bytes, limits, path)
}

/// Decodes a PNG or JPEG image held in memory (format guessed from the
/// content) into RGBA8, applying the EXIF orientation of JPEGs.
///
/// Errors name the placeholder path `<memory>`.
///
/// # Errors
/// * [`RenderError::UnsupportedFormat`] if the data is neither PNG nor JPEG;
/// * [`RenderError::TooLarge`] if the header claims dimensions beyond `limits`;
/// * [`RenderError::MemoryLimit`] if decoding would allocate more than allowed;
/// * [`RenderError::Corrupt`] for truncated or malformed data;
/// * [`RenderError::UnsupportedVariant`] for a PNG/JPEG feature the decoder lacks.
///
/// # Example
/// ```
/// use render::{decode_image, ImageLimits, RenderError};
///
/// let err = decode_image(b"GIF89a...", &ImageLimits::default()).expect_err("must fail");
/// assert!(matches!(err, RenderError::UnsupportedFormat { .. }));
/// ```
pub fn decode_image(bytes: &[u8], limits: &ImageLimits) -> Result<RgbaImage, RenderError> {
    decode(bytes, limits, Path::new(IN_MEMORY))
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

fn decode(bytes: &[u8], limits: &ImageLimits, path: &Path) -> Result<RgbaImage, RenderError> {
    let format = match image::guess_format(bytes) {
        Ok(format @ (ImageFormat::Png | ImageFormat::Jpeg)) => format,
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
    let rgba_copy = if decoder.color_type() == ColorType::Rgba8 {
        0
    } else {
        u64::from(width) * u64::from(height) * 4
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
    Ok(image.into_rgba8())
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
