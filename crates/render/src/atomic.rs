//! Atomic file replacement: write beside the target, sync, rename over it.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageEncoder, ImageError, RgbaImage};

use crate::RenderError;

/// Writes `bytes` to `path` atomically: readers see either the old file or
/// the complete new one, never a partial write.
///
/// The data goes to a uniquely named temporary file in the same directory
/// (`.<name>.<pid>-<n>.tmp`), which is flushed to disk and then renamed over
/// `path`. An existing target keeps its permissions. On any error the
/// temporary file is removed and an existing `path` is left untouched. If
/// `path` is a symbolic link, the link itself is replaced.
///
/// # Errors
/// * [`RenderError::InvalidPath`] if `path` names no file;
/// * [`RenderError::MissingDirectory`] if its directory does not exist;
/// * [`RenderError::Io`] for any other failure (permissions, full disk, a
///   directory in the way, …).
///
/// # Example
/// ```
/// # let dir = tempfile::tempdir()?;
/// let path = dir.path().join("rig.json");
/// render::write_atomic(&path, b"{\"version\": 1}")?;
/// assert_eq!(std::fs::read(&path)?, b"{\"version\": 1}");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), RenderError> {
    replace_with(path, |file| {
        file.write_all(bytes).map_err(|source| RenderError::Io {
            path: path.to_owned(),
            action: "write",
            source,
        })
    })
}

/// Encodes `image` as an 8-bit RGBA PNG and writes it to `path` atomically,
/// as [`write_atomic`] does.
///
/// # Errors
/// The errors of [`write_atomic`], and [`RenderError::Encode`] if the encoder
/// rejects the image (for example one with a zero dimension); in every case
/// an existing `path` is left untouched.
pub fn save_png_atomic(path: &Path, image: &RgbaImage) -> Result<(), RenderError> {
    if image.width() == 0 || image.height() == 0 {
        return Err(RenderError::Encode {
            path: path.to_owned(),
            detail: format!(
                "a PNG cannot be {}x{} pixels",
                image.width(),
                image.height()
            ),
        });
    }
    replace_with(path, |file| {
        let io_error = |source| RenderError::Io {
            path: path.to_owned(),
            action: "write",
            source,
        };
        let mut writer = BufWriter::new(file);
        PngEncoder::new(&mut writer)
            .write_image(
                image.as_raw(),
                image.width(),
                image.height(),
                ExtendedColorType::Rgba8,
            )
            .map_err(|error| match error {
                ImageError::IoError(source) => io_error(source),
                other => RenderError::Encode {
                    path: path.to_owned(),
                    detail: other.to_string(),
                },
            })?;
        writer.flush().map_err(io_error)
    })
}

/// Removes the temporary file when dropped, unless it was renamed.
struct TempFile {
    path: PathBuf,
    renamed: bool,
}

impl Drop for TempFile {
    fn drop(&mut self) {
        if !self.renamed {
            // Best effort: the original error is the one worth reporting.
            let _ = fs::remove_file(&self.path);
        }
    }
}

/// Creates a new, uniquely named file in `dir` for replacing `target`.
fn create_temp(dir: &Path, target: &Path, name: &str) -> Result<(TempFile, File), RenderError> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    // Keep the name well below the usual 255-byte limit.
    let stem: String = name.chars().take(100).collect();
    let pid = std::process::id();
    let mut last_error = None;
    for _ in 0..64 {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let candidate = dir.join(format!(".{stem}.{pid}-{n}.tmp"));
        match OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&candidate)
        {
            Ok(file) => {
                return Ok((
                    TempFile {
                        path: candidate,
                        renamed: false,
                    },
                    file,
                ));
            }
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => last_error = Some(e),
            Err(e) if e.kind() == io::ErrorKind::NotFound && !dir.is_dir() => {
                return Err(RenderError::MissingDirectory {
                    path: target.to_owned(),
                    dir: dir.to_owned(),
                });
            }
            Err(source) => {
                return Err(RenderError::Io {
                    path: target.to_owned(),
                    action: "create a temporary file for",
                    source,
                });
            }
        }
    }
    Err(RenderError::Io {
        path: target.to_owned(),
        action: "create a temporary file for",
        source: last_error.unwrap_or_else(|| io::Error::other("no free temporary name")),
    })
}

/// The shared mechanism of [`write_atomic`] and [`save_png_atomic`]: `fill`
/// writes the content into the temporary file.
fn replace_with<F>(path: &Path, fill: F) -> Result<(), RenderError>
where
    F: FnOnce(&mut File) -> Result<(), RenderError>,
{
    let invalid = || RenderError::InvalidPath {
        path: path.to_owned(),
    };
    let name = path.file_name().ok_or_else(invalid)?.to_string_lossy();
    let dir = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    };
    let (mut temp, mut file) = create_temp(dir, path, &name)?;
    let io_error = |action, source| RenderError::Io {
        path: path.to_owned(),
        action,
        source,
    };

    fill(&mut file)?;
    if let Ok(meta) = fs::metadata(path)
        && meta.is_file()
    {
        // Best effort: failing to copy the mode is no reason to lose the data.
        let _ = file.set_permissions(meta.permissions());
    }
    file.sync_all().map_err(|e| io_error("write", e))?;
    drop(file);

    fs::rename(&temp.path, path).map_err(|e| io_error("replace", e))?;
    temp.renamed = true;

    // Make the rename itself durable (best effort; not possible everywhere).
    if let Ok(dir) = File::open(dir) {
        let _ = dir.sync_all();
    }
    Ok(())
}
