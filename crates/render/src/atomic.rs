//! Atomic file replacement: write beside the target, sync, rename over it; and
//! writing through to what cannot be replaced (devices, FIFOs) or to a link's target.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard, PoisonError};

use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageEncoder, ImageError, RgbaImage};

use crate::{Picture, RenderError, Rgba16Image};

/// Writes `bytes` to `path` atomically: readers see either the old file or
/// the complete new one, never a partial write.
///
/// The data goes to a uniquely named temporary file in the same directory
/// (`.<name>.c2warp-<pid>-<n>.tmp`), which is flushed to disk and then renamed over
/// `path`. An existing target keeps its permissions. On any error the
/// temporary file is removed and an existing `path` is left untouched.
///
/// What is already at `path` is respected:
/// * a symbolic link stays a link: its target (followed through any chain of
///   links) is written, atomically as above when it is a regular file or does not
///   exist yet;
/// * a device or a FIFO (`/dev/null`, `/dev/stdout`, a named pipe) is opened and
///   written through, since it cannot be replaced (opening a FIFO waits for a
///   reader); such a write is not atomic.
///
/// # Errors
/// * [`RenderError::InvalidPath`] if `path` names no file;
/// * [`RenderError::MissingDirectory`] if its directory does not exist;
/// * [`RenderError::Io`] for any other failure (permissions, full disk, a
///   directory in the way, a loop of symbolic links, …).
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

/// An image [`save_png_atomic`] and [`write_png`] can encode: RGBA with 8 or 16
/// bits per channel ([`RgbaImage`], [`Rgba16Image`] or a [`Picture`]).
pub trait PngPixels {
    /// Width, height, the colour type and the samples as bytes (16-bit samples in
    /// native byte order, as [`ImageEncoder::write_image`] takes them).
    fn png_layout(&self) -> (u32, u32, ExtendedColorType, &[u8]);
}

impl PngPixels for RgbaImage {
    fn png_layout(&self) -> (u32, u32, ExtendedColorType, &[u8]) {
        (
            self.width(),
            self.height(),
            ExtendedColorType::Rgba8,
            self.as_raw(),
        )
    }
}

impl PngPixels for Rgba16Image {
    fn png_layout(&self) -> (u32, u32, ExtendedColorType, &[u8]) {
        (
            self.width(),
            self.height(),
            ExtendedColorType::Rgba16,
            bytemuck::cast_slice(self.as_raw()),
        )
    }
}

impl PngPixels for Picture {
    fn png_layout(&self) -> (u32, u32, ExtendedColorType, &[u8]) {
        match self {
            Picture::Rgba8(image) => image.png_layout(),
            Picture::Rgba16(image) => image.png_layout(),
        }
    }
}

/// Encodes `image` as an RGBA PNG of its depth (8 or 16 bits per channel) into
/// `writer` (for example standard output); `path` only names the destination in
/// errors.
///
/// # Errors
/// [`RenderError::Encode`] if the encoder rejects the image (for example one with
/// a zero dimension), [`RenderError::Io`] if writing fails.
pub fn write_png<P, W>(writer: W, image: &P, path: &Path) -> Result<(), RenderError>
where
    P: PngPixels + ?Sized,
    W: Write,
{
    let (width, height, color, bytes) = image.png_layout();
    if width == 0 || height == 0 {
        return Err(RenderError::Encode {
            path: path.to_owned(),
            detail: format!("a PNG cannot be {width}x{height} pixels"),
        });
    }
    let io_error = |source| RenderError::Io {
        path: path.to_owned(),
        action: "write",
        source,
    };
    let mut writer = BufWriter::new(writer);
    PngEncoder::new(&mut writer)
        .write_image(bytes, width, height, color)
        .map_err(|error| match error {
            ImageError::IoError(source) => io_error(source),
            other => RenderError::Encode {
                path: path.to_owned(),
                detail: other.to_string(),
            },
        })?;
    writer.flush().map_err(io_error)
}

/// Encodes `image` as an RGBA PNG of its depth (8 bits per channel for an
/// [`RgbaImage`], 16 for an [`Rgba16Image`]; a [`Picture`] in its own) and writes
/// it to `path` as [`write_atomic`] does (atomically for a regular file, through to
/// a device or FIFO, to the target of a symbolic link).
///
/// # Errors
/// The errors of [`write_atomic`], and [`RenderError::Encode`] if the encoder
/// rejects the image (for example one with a zero dimension); in every case
/// an existing `path` is left untouched.
pub fn save_png_atomic<P: PngPixels + ?Sized>(path: &Path, image: &P) -> Result<(), RenderError> {
    let (width, height, _, _) = image.png_layout();
    if width == 0 || height == 0 {
        return Err(RenderError::Encode {
            path: path.to_owned(),
            detail: format!("a PNG cannot be {width}x{height} pixels"),
        });
    }
    replace_with(path, |file| write_png(file, image, path))
}

/// Removes the temporary file when dropped, unless it was renamed.
struct TempFile {
    path: PathBuf,
    renamed: bool,
}

impl Drop for TempFile {
    fn drop(&mut self) {
        let mut live = live_temporaries();
        if !self.renamed {
            // Best effort: the original error is the one worth reporting.
            let _ = fs::remove_file(&self.path);
        }
        if let Some(i) = live.iter().position(|p| *p == self.path) {
            live.swap_remove(i);
        }
    }
}

/// What marks a temporary file as this program's: `.<name>.c2warp-<pid>-<n>.tmp`.
const TEMP_MARK: &str = ".c2warp-";

/// The temporary files this process has open now, to be removed if it is
/// interrupted ([`remove_temporary_files`]). Files are created and forgotten under
/// this lock.
fn live_temporaries() -> MutexGuard<'static, Vec<PathBuf>> {
    static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
    LIVE.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Removes every temporary file of an atomic write in progress in this process
/// (see [`write_atomic`]) and keeps any other from being created: for a signal
/// handler that is about to end the process (Ctrl-C, `SIGTERM`), so that an
/// interrupted run leaves no temporary file behind and every target as it was.
///
/// A write that starts after this call waits forever: call it only on the way out.
pub fn remove_temporary_files() {
    let mut live = live_temporaries();
    for path in live.drain(..) {
        let _ = fs::remove_file(path);
    }
    // Hold the lock until the process ends: no new temporary file can appear.
    std::mem::forget(live);
}

/// Removes, once per directory and process, temporary files of this program that a
/// run which no longer exists left in `dir` (killed before it could clean up).
/// Only names of the form `.<name>.c2warp-<pid>-<n>.tmp` whose process is gone are
/// removed (Linux: no `/proc/<pid>`; elsewhere nothing is removed).
fn remove_stale_temporaries(dir: &Path, live: &[PathBuf]) {
    static SWEPT: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
    let mut swept = SWEPT.lock().unwrap_or_else(PoisonError::into_inner);
    if swept.iter().any(|d| d == dir) {
        return;
    }
    swept.push(dir.to_owned());
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    let own = std::process::id();
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(temporary_owner) else {
            continue;
        };
        let path = entry.path();
        let gone = if pid == own {
            !live.contains(&path)
        } else {
            !process_exists(pid)
        };
        if gone && entry.file_type().is_ok_and(|kind| kind.is_file()) {
            let _ = fs::remove_file(&path);
        }
    }
}

/// The process that made the temporary file `name`, if it is one of this program's.
fn temporary_owner(name: &str) -> Option<u32> {
    let rest = name.strip_prefix('.')?.strip_suffix(".tmp")?;
    let (_, tail) = rest.rsplit_once(TEMP_MARK)?;
    let (pid, n) = tail.split_once('-')?;
    n.parse::<u64>().ok()?;
    pid.parse().ok()
}

/// Whether process `pid` is running (always true where that cannot be told).
fn process_exists(pid: u32) -> bool {
    if cfg!(target_os = "linux") {
        Path::new("/proc").join(pid.to_string()).exists()
    } else {
        true
    }
}

/// Creates a new, uniquely named file in `dir` for replacing `target`, after
/// removing temporary files that earlier runs left there.
fn create_temp(dir: &Path, target: &Path, name: &str) -> Result<(TempFile, File), RenderError> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    // Keep the name well below the usual 255-byte limit.
    let stem: String = name.chars().take(100).collect();
    let pid = std::process::id();
    let mut last_error = None;
    let mut live = live_temporaries();
    remove_stale_temporaries(dir, &live);
    for _ in 0..64 {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let candidate = dir.join(format!(".{stem}{TEMP_MARK}{pid}-{n}.tmp"));
        match OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&candidate)
        {
            Ok(file) => {
                live.push(candidate.clone());
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

/// The file a write to `path` lands in: `path` itself, or, when it is a symbolic
/// link, the end of its chain of links (relative links are read from the link's
/// directory).
fn follow_links(path: &Path) -> Result<PathBuf, RenderError> {
    let mut current = path.to_path_buf();
    // Linux gives up after 40 links too.
    for _ in 0..40 {
        match fs::symlink_metadata(&current) {
            Ok(meta) if meta.file_type().is_symlink() => {
                let link = fs::read_link(&current).map_err(|source| RenderError::Io {
                    path: path.to_owned(),
                    action: "follow the symbolic link",
                    source,
                })?;
                current = match current.parent() {
                    Some(dir) if link.is_relative() => dir.join(link),
                    _ => link,
                };
            }
            _ => return Ok(current),
        }
    }
    Err(RenderError::Io {
        path: path.to_owned(),
        action: "follow the symbolic link",
        source: io::Error::other("too many levels of symbolic links"),
    })
}

/// The shared mechanism of [`write_atomic`] and [`save_png_atomic`]: `fill`
/// writes the content into the file (the temporary one, or the device).
fn replace_with<F>(path: &Path, fill: F) -> Result<(), RenderError>
where
    F: FnOnce(&mut File) -> Result<(), RenderError>,
{
    let (replacement, mut file) = Replacement::begin(path)?;
    fill(&mut file)?;
    replacement.commit(file)
}

/// A file being replaced, for writers that fill it piece by piece (animations):
/// [`begin`](Self::begin) opens a temporary file beside the target (or the target
/// itself when it cannot be replaced), [`commit`](Self::commit) puts it in place.
/// Dropped before that, the temporary file is removed and the target is untouched.
pub(crate) struct Replacement {
    /// The path as the caller gave it, for errors.
    path: PathBuf,
    /// Where the data lands (`path`, or the end of its chain of links).
    target: PathBuf,
    /// The directory the temporary file is in, synced after the rename.
    dir: PathBuf,
    /// The temporary file; `None` when writing through to a device or FIFO.
    temp: Option<TempFile>,
}

impl Replacement {
    /// Opens the file to fill for replacing `path`, as [`write_atomic`] does: a new
    /// temporary file in the target's directory, or the device or FIFO at `path`.
    ///
    /// # Errors
    /// [`RenderError::InvalidPath`], [`RenderError::MissingDirectory`] or
    /// [`RenderError::Io`], as for [`write_atomic`].
    pub(crate) fn begin(path: &Path) -> Result<(Self, File), RenderError> {
        let invalid = || RenderError::InvalidPath {
            path: path.to_owned(),
        };
        path.file_name().ok_or_else(invalid)?;
        let target = follow_links(path)?;
        match fs::metadata(&target) {
            // A device, FIFO or socket cannot be replaced: write through to it. (A
            // directory falls through, and the rename reports it.)
            Ok(meta) if !meta.is_file() && !meta.is_dir() => {
                let file = OpenOptions::new()
                    .write(true)
                    .open(&target)
                    .map_err(|source| RenderError::Io {
                        path: path.to_owned(),
                        action: "open",
                        source,
                    })?;
                let replacement = Self {
                    path: path.to_owned(),
                    dir: PathBuf::new(),
                    target,
                    temp: None,
                };
                Ok((replacement, file))
            }
            _ => {
                let name = target.file_name().ok_or_else(invalid)?.to_string_lossy();
                let dir = match target.parent() {
                    Some(parent) if !parent.as_os_str().is_empty() => parent.to_owned(),
                    _ => PathBuf::from("."),
                };
                let (temp, file) = create_temp(&dir, path, &name)?;
                let replacement = Self {
                    path: path.to_owned(),
                    target,
                    dir,
                    temp: Some(temp),
                };
                Ok((replacement, file))
            }
        }
    }

    /// Whether the data goes straight to a device or FIFO (no temporary file, not
    /// atomic, possibly not seekable).
    pub(crate) fn writes_through(&self) -> bool {
        self.temp.is_none()
    }

    /// Makes the filled `file` durable: gives it the permissions of the file it
    /// replaces and syncs it to disk (for a device or FIFO: flushes it). It is
    /// not yet in place; [`publish`](Self::publish) does that.
    ///
    /// # Errors
    /// [`RenderError::Io`] if syncing fails.
    pub(crate) fn seal(&self, mut file: File) -> Result<(), RenderError> {
        let io_error = |source| RenderError::Io {
            path: self.path.clone(),
            action: "write",
            source,
        };
        if self.temp.is_none() {
            return file.flush().map_err(io_error);
        }
        if let Ok(meta) = fs::metadata(&self.target)
            && meta.is_file()
        {
            // Best effort: failing to copy the mode is no reason to lose the data.
            let _ = file.set_permissions(meta.permissions());
        }
        file.sync_all().map_err(io_error)
    }

    /// Renames the sealed temporary file over the target (nothing to do for a
    /// device or FIFO).
    ///
    /// # Errors
    /// [`RenderError::Io`] if the rename fails (the temporary file is then removed).
    pub(crate) fn publish(mut self) -> Result<(), RenderError> {
        let Some(temp) = self.temp.as_mut() else {
            return Ok(());
        };
        fs::rename(&temp.path, &self.target).map_err(|source| RenderError::Io {
            path: self.path.clone(),
            action: "replace",
            source,
        })?;
        temp.renamed = true;

        // Make the rename itself durable (best effort; not possible everywhere).
        if let Ok(dir) = File::open(&self.dir) {
            let _ = dir.sync_all();
        }
        Ok(())
    }

    /// [`seal`](Self::seal) then [`publish`](Self::publish).
    ///
    /// # Errors
    /// Theirs.
    pub(crate) fn commit(self, file: File) -> Result<(), RenderError> {
        self.seal(file)?;
        self.publish()
    }
}
