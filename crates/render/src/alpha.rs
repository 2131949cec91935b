//! Reading which pixels of an image file are visible, a row at a time: for work that
//! needs the alpha channel alone (a cage around a picture) on pictures too large to
//! hold as RGBA.

use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use crate::{ImageLimits, Picture, RenderError, load_picture, open_regular_file};

/// The alpha channel of an image file, row by row from the top.
///
/// A non-interlaced PNG is streamed: no more than a row of it is held at a time, so
/// a 16384 × 16384 picture costs a few kilobytes instead of a gigabyte. Other files
/// (and PNGs that are interlaced or carry an EXIF orientation) are decoded whole
/// with [`load_picture`], under the same limits, and read from memory.
///
/// # Example
/// ```
/// use image::{Rgba, RgbaImage};
/// # let dir = tempfile::tempdir()?;
/// let path = dir.path().join("dot.png");
/// let mut image = RgbaImage::new(3, 2);
/// image.put_pixel(1, 1, Rgba([9, 9, 9, 200]));
/// image.save(&path)?;
/// let mut reader = render::AlphaReader::open(&path, &render::ImageLimits::default())?;
/// assert_eq!(reader.dimensions(), (3, 2));
/// let mut row = Vec::new();
/// assert!(reader.next_row(&mut row)?);
/// assert_eq!(row, [0, 0, 0]);
/// assert!(reader.next_row(&mut row)?);
/// assert_eq!(row, [0, 200, 0]);
/// assert!(!reader.next_row(&mut row)?);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct AlphaReader {
    path: PathBuf,
    width: u32,
    height: u32,
    next: u32,
    source: Source,
}

enum Source {
    /// A PNG streamed row by row (expanded to 8 bits per channel), with its
    /// channels per pixel and which of them is alpha (`None`: opaque).
    Png {
        reader: Box<png::Reader<BufReader<File>>>,
        channels: usize,
        alpha: Option<usize>,
    },
    /// A picture decoded whole.
    Decoded(Picture),
}

impl AlphaReader {
    /// Opens `path` for reading its alpha channel.
    ///
    /// # Errors
    /// As [`load_picture`]: a missing, non-regular, unsupported, oversized or
    /// corrupt image, naming the file.
    pub fn open(path: &Path, limits: &ImageLimits) -> Result<Self, RenderError> {
        match Self::stream_png(path, limits)? {
            Some(reader) => Ok(reader),
            None => {
                let picture = load_picture(path, limits)?;
                let (width, height) = picture.dimensions();
                Ok(Self {
                    path: path.to_owned(),
                    width,
                    height,
                    next: 0,
                    source: Source::Decoded(picture),
                })
            }
        }
    }

    /// The picture's width and height in pixels.
    pub fn dimensions(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Puts the next row's alpha values (0 transparent, 255 opaque; 16-bit alpha
    /// rounded down to 8 bits, so only 0 reads as 0) into `alpha`, and says whether
    /// there was one.
    ///
    /// # Errors
    /// [`RenderError::Corrupt`] for data that ends early or is malformed.
    pub fn next_row(&mut self, alpha: &mut Vec<u8>) -> Result<bool, RenderError> {
        if self.next == self.height {
            return Ok(false);
        }
        alpha.clear();
        match &mut self.source {
            Source::Png {
                reader,
                channels,
                alpha: at,
            } => {
                let row = reader
                    .next_row()
                    .map_err(|e| corrupt(&self.path, &e))?
                    .ok_or_else(|| RenderError::Corrupt {
                        path: self.path.clone(),
                        detail: format!("the image data ends at row {}", self.next),
                    })?;
                match *at {
                    Some(at) => alpha.extend(row.data().chunks_exact(*channels).map(|p| p[at])),
                    None => alpha.resize(self.width as usize, 255),
                }
            }
            Source::Decoded(Picture::Rgba8(image)) => {
                let y = self.next;
                alpha.extend((0..self.width).map(|x| image.get_pixel(x, y).0[3]));
            }
            Source::Decoded(Picture::Rgba16(image)) => {
                let y = self.next;
                alpha.extend((0..self.width).map(|x| {
                    // Any alpha above 0 stays visible.
                    let a = image.get_pixel(x, y).0[3];
                    if a == 0 { 0 } else { (a >> 8).max(1) as u8 }
                }));
            }
        }
        self.next += 1;
        Ok(true)
    }

    /// A streaming reader for a plain PNG, `None` for anything else.
    fn stream_png(path: &Path, limits: &ImageLimits) -> Result<Option<Self>, RenderError> {
        let (mut file, _) = open_regular_file(path, "image", u64::MAX)?;
        let mut signature = [0u8; 8];
        let is_png = file.read_exact(&mut signature).is_ok() && signature == *b"\x89PNG\r\n\x1a\n";
        file.seek(SeekFrom::Start(0))
            .map_err(|source| RenderError::Io {
                path: path.to_owned(),
                action: "read",
                source,
            })?;
        if !is_png {
            return Ok(None);
        }
        let mut decoder = png::Decoder::new_with_limits(
            BufReader::new(file),
            png::Limits {
                bytes: usize::try_from(limits.max_alloc_bytes).unwrap_or(usize::MAX),
            },
        );
        decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
        let reader = match decoder.read_info() {
            Ok(reader) => reader,
            // Let the whole decoder say what is wrong, as it does for other reads.
            Err(_) => return Ok(None),
        };
        let info = reader.info();
        let (width, height) = (info.width, info.height);
        if width > limits.max_width || height > limits.max_height {
            return Err(RenderError::TooLarge {
                path: path.to_owned(),
                width,
                height,
                limit: (limits.max_width, limits.max_height),
            });
        }
        if info.interlaced || info.exif_metadata.is_some() {
            return Ok(None);
        }
        let (color, _) = reader.output_color_type();
        let (channels, alpha) = match color {
            png::ColorType::Rgba => (4, Some(3)),
            png::ColorType::GrayscaleAlpha => (2, Some(1)),
            png::ColorType::Rgb => (3, None),
            png::ColorType::Grayscale => (1, None),
            // EXPAND turns a palette into RGB(A); anything else is decoded whole.
            png::ColorType::Indexed => return Ok(None),
        };
        Ok(Some(Self {
            path: path.to_owned(),
            width,
            height,
            next: 0,
            source: Source::Png {
                reader: Box::new(reader),
                channels,
                alpha,
            },
        }))
    }
}

/// The error for a PNG that could not be read on.
fn corrupt(path: &Path, error: &png::DecodingError) -> RenderError {
    RenderError::Corrupt {
        path: path.to_owned(),
        detail: error.to_string(),
    }
}
