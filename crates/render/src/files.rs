//! Reading input files safely: regular files only, and no more than a cap.
//!
//! Opening a FIFO for reading blocks until a writer appears, and a device such as
//! `/dev/zero` never ends, so the kind of file is checked with [`fs::metadata`]
//! (which follows symbolic links) *before* it is opened, and every read is capped.

use std::fs::{self, File, Metadata};
use std::io::{self, Read};
use std::path::Path;

use crate::RenderError;

/// What kind of file `meta` describes, in words, when it is not a regular file.
fn kind_of(meta: &Metadata) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let kind = meta.file_type();
        if kind.is_fifo() {
            return "a FIFO";
        }
        if kind.is_char_device() {
            return "a character device";
        }
        if kind.is_block_device() {
            return "a block device";
        }
        if kind.is_socket() {
            return "a socket";
        }
    }
    if meta.is_dir() {
        "a directory"
    } else {
        "not a plain file"
    }
}

/// The error for a failed `stat` or `open` of `path`.
fn open_error(path: &Path, source: io::Error) -> RenderError {
    if source.kind() == io::ErrorKind::NotFound {
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
}

/// Refuses anything `meta` says is not a regular file.
fn require_regular(path: &Path, what: &'static str, meta: &Metadata) -> Result<(), RenderError> {
    if meta.is_file() {
        Ok(())
    } else {
        Err(RenderError::NotRegularFile {
            what,
            path: path.to_owned(),
            kind: kind_of(meta),
        })
    }
}

/// Opens `path` for reading if it is a regular file (symbolic links followed) of at
/// most `max_bytes` bytes, and returns it with its length.
///
/// The kind and size are checked before the file is opened, so a FIFO, a device or a
/// directory is refused at once instead of blocking or reading forever; they are
/// checked again on the open file, in case it was swapped in between. The caller
/// should still read at most `max_bytes` (the file may grow).
///
/// `what` names the file in messages ("rig file", "mesh", ...).
///
/// # Errors
/// * [`RenderError::NotFound`] if there is no such file;
/// * [`RenderError::NotRegularFile`] for a FIFO, device, socket or directory;
/// * [`RenderError::FileTooLarge`] if it holds more than `max_bytes` bytes;
/// * [`RenderError::Io`] if it cannot be examined or opened.
pub fn open_regular_file(
    path: &Path,
    what: &'static str,
    max_bytes: u64,
) -> Result<(File, u64), RenderError> {
    let check = |meta: &Metadata| {
        require_regular(path, what, meta)?;
        if meta.len() > max_bytes {
            return Err(RenderError::FileTooLarge {
                what,
                path: path.to_owned(),
                len: meta.len(),
                limit: max_bytes,
            });
        }
        Ok(meta.len())
    };
    check(&fs::metadata(path).map_err(|e| open_error(path, e))?)?;
    let file = File::open(path).map_err(|e| open_error(path, e))?;
    let len = check(&file.metadata().map_err(|e| open_error(path, e))?)?;
    Ok((file, len))
}

/// Reads the whole of `path`, a regular file of at most `max_bytes` bytes (see
/// [`open_regular_file`]), without ever holding more than `max_bytes + 1` bytes.
///
/// # Errors
/// Those of [`open_regular_file`], and [`RenderError::FileTooLarge`] if the file grew
/// beyond `max_bytes` while being read.
///
/// # Example
/// ```
/// # let dir = tempfile::tempdir()?;
/// let path = dir.path().join("rig.json");
/// std::fs::write(&path, "{}")?;
/// assert_eq!(render::read_regular_file(&path, "rig file", 8 << 20)?, b"{}");
/// let err = render::read_regular_file(dir.path(), "rig file", 8 << 20).expect_err("a directory");
/// assert!(err.to_string().ends_with("is not a regular file (a directory)"));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn read_regular_file(
    path: &Path,
    what: &'static str,
    max_bytes: u64,
) -> Result<Vec<u8>, RenderError> {
    let (file, len) = open_regular_file(path, what, max_bytes)?;
    let too_large = |len| RenderError::FileTooLarge {
        what,
        path: path.to_owned(),
        len,
        limit: max_bytes,
    };
    let mut bytes = Vec::new();
    bytes
        .try_reserve_exact(usize::try_from(len).map_err(|_| too_large(len))?)
        .map_err(|_| too_large(len))?;
    file.take(max_bytes.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| open_error(path, e))?;
    if bytes.len() as u64 > max_bytes {
        return Err(too_large(bytes.len() as u64));
    }
    Ok(bytes)
}

/// A byte count for people: `52.4 MB`, `8 MiB` for exact powers of two.
pub(crate) fn human_bytes(n: u64) -> String {
    const UNITS: [(u64, &str); 3] = [(1 << 30, "GiB"), (1 << 20, "MiB"), (1 << 10, "KiB")];
    for (unit, name) in UNITS {
        if n >= unit && n.is_multiple_of(unit) {
            return format!("{} {name}", n / unit);
        }
    }
    match n {
        0..1_000 => format!("{n} bytes"),
        1_000..1_000_000 => format!("{:.1} kB", n as f64 / 1e3),
        1_000_000..1_000_000_000 => format!("{:.1} MB", n as f64 / 1e6),
        _ => format!("{:.1} GB", n as f64 / 1e9),
    }
}

/// Whether `a` and `b` name the same existing file: the same device and inode on Unix
/// (so symbolic links, hard links and `..` are seen through), the same canonical path
/// elsewhere. A path that does not exist is no file at all.
pub fn same_file(a: &Path, b: &Path) -> bool {
    let (Ok(ma), Ok(mb)) = (fs::metadata(a), fs::metadata(b)) else {
        return false;
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        ma.dev() == mb.dev() && ma.ino() == mb.ino()
    }
    #[cfg(not(unix))]
    {
        let _ = (ma, mb);
        matches!((fs::canonicalize(a), fs::canonicalize(b)), (Ok(x), Ok(y)) if x == y)
    }
}

/// Whether `name` is one a PNG sequence's frame could have: `frame_`, 5 digits or
/// more, `.png`.
pub(crate) fn is_frame_name(name: &str) -> bool {
    name.strip_prefix("frame_")
        .and_then(|rest| rest.strip_suffix(".png"))
        .is_some_and(|digits| digits.len() >= 5 && digits.bytes().all(|b| b.is_ascii_digit()))
}

/// Refuses to write `output` when that would replace one of `inputs`: when it is the
/// same file as an input ([`same_file`]: through links and `..`), or, for a directory
/// (a PNG sequence's), when an input is a frame file (`frame_<5+ digits>.png`) in it. An
/// output that does not exist yet, or `-` (standard output), replaces nothing.
///
/// Commands call it before any work, so that no run ever writes over what it reads.
///
/// # Errors
/// [`RenderError::OutputIsInput`] naming the output and the input.
///
/// # Example
/// ```
/// # let dir = tempfile::tempdir()?;
/// let picture = dir.path().join("cat.png");
/// std::fs::write(&picture, b"...")?;
/// let through_dots = dir.path().join("sub/../cat.png");
/// std::fs::create_dir(dir.path().join("sub"))?;
/// assert!(render::refuse_input_as_output(&through_dots, &[&picture]).is_err());
/// assert!(render::refuse_input_as_output(&dir.path().join("out.png"), &[&picture]).is_ok());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn refuse_input_as_output(output: &Path, inputs: &[&Path]) -> Result<(), RenderError> {
    if output.as_os_str() == "-" {
        return Ok(());
    }
    let is_dir = fs::metadata(output).is_ok_and(|meta| meta.is_dir());
    for &input in inputs {
        let clash = if is_dir {
            let in_it = input
                .parent()
                .map(|p| {
                    if p.as_os_str().is_empty() {
                        Path::new(".")
                    } else {
                        p
                    }
                })
                .is_some_and(|parent| same_file(parent, output));
            in_it
                && input
                    .file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(is_frame_name)
        } else {
            same_file(output, input)
        };
        if clash {
            return Err(RenderError::OutputIsInput {
                output: output.to_owned(),
                input: input.to_owned(),
                folder: is_dir,
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn byte_counts_read_well() {
        assert_eq!(human_bytes(8 << 20), "8 MiB");
        assert_eq!(human_bytes(52_400_000), "52.4 MB");
        assert_eq!(human_bytes(999), "999 bytes");
        assert_eq!(human_bytes(1_536), "1.5 kB");
        assert_eq!(human_bytes(3 << 30), "3 GiB");
    }
}
