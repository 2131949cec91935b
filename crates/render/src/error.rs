//! The crate's one error type.

use std::path::PathBuf;

/// Everything that can go wrong while loading, drawing or saving an image.
///
/// Each message is one line and names the file (or, for in-memory data, the
/// placeholder `<memory>`) so that an application can show it as is.
#[derive(thiserror::Error, Debug)]
#[non_exhaustive]
pub enum RenderError {
    /// The file to read does not exist.
    #[error("{}: no such file", path.display())]
    NotFound {
        /// The file that was asked for.
        path: PathBuf,
    },

    /// The file to read is a FIFO, a device, a socket or a directory: it is refused
    /// before it is opened (opening a FIFO blocks; a device may never end).
    #[error("{what} {} is not a regular file ({kind})", path.display())]
    NotRegularFile {
        /// What the file was to be, e.g. `"image"` or `"rig file"`.
        what: &'static str,
        /// The file that was asked for.
        path: PathBuf,
        /// What it is instead, e.g. `"a FIFO"`.
        kind: &'static str,
    },

    /// The file to read is larger than the caller accepts for its kind.
    #[error(
        "{what} {} is {}; {what}s over {} are refused",
        path.display(), crate::files::human_bytes(*len), crate::files::human_bytes(*limit)
    )]
    FileTooLarge {
        /// What the file was to be, e.g. `"rig file"`.
        what: &'static str,
        /// The file that was asked for.
        path: PathBuf,
        /// Its length in bytes.
        len: u64,
        /// The largest length accepted, in bytes.
        limit: u64,
    },

    /// The directory a file should be written into does not exist.
    #[error("cannot write {}: directory {} does not exist", path.display(), dir.display())]
    MissingDirectory {
        /// The file that was to be written.
        path: PathBuf,
        /// Its parent directory, which is missing.
        dir: PathBuf,
    },

    /// An output that would replace one of the command's inputs (see
    /// [`refuse_input_as_output`](crate::refuse_input_as_output)).
    #[error(
        "will not write {}: {}; choose another output",
        output.display(),
        if *folder {
            format!("the frames would replace {}, one of the inputs", input.display())
        } else {
            format!("it is {}, one of the inputs", input.display())
        }
    )]
    OutputIsInput {
        /// The output asked for.
        output: PathBuf,
        /// The input it would replace, as given.
        input: PathBuf,
        /// Whether the output is a folder of frames holding the input.
        folder: bool,
    },

    /// The path names no file (empty, `/`, or ending in `..`).
    #[error("{}: not a file path", path.display())]
    InvalidPath {
        /// The offending path.
        path: PathBuf,
    },

    /// Any other operating-system error while reading or writing a file.
    #[error("cannot {action} {}: {source}", path.display())]
    Io {
        /// The file involved.
        path: PathBuf,
        /// What was being done, e.g. `"read"` or `"replace"`.
        action: &'static str,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },

    /// The data is not in a format this crate decodes (PNG, JPEG, WebP, TIFF, BMP, GIF).
    #[error("{}: not a PNG, JPEG, WebP, TIFF, BMP or GIF image", path.display())]
    UnsupportedFormat {
        /// The file (or `<memory>`).
        path: PathBuf,
    },

    /// The data is in a known format but uses a feature the decoder does not support.
    #[error("{}: unsupported image variant ({detail})", path.display())]
    UnsupportedVariant {
        /// The file (or `<memory>`).
        path: PathBuf,
        /// The decoder's explanation.
        detail: String,
    },

    /// The data is truncated or malformed (for a JPEG: it ends before its end-of-image
    /// marker, or holds too few bytes for the pixels its header claims).
    #[error("{}: truncated or corrupt image data ({detail})", path.display())]
    Corrupt {
        /// The file (or `<memory>`).
        path: PathBuf,
        /// The decoder's explanation.
        detail: String,
    },

    /// The image's header claims dimensions beyond [`ImageLimits`](crate::ImageLimits).
    #[error(
        "{}: image is {width}x{height} pixels, larger than the {}x{} limit",
        path.display(), limit.0, limit.1
    )]
    TooLarge {
        /// The file (or `<memory>`).
        path: PathBuf,
        /// Claimed width in pixels.
        width: u32,
        /// Claimed height in pixels.
        height: u32,
        /// The limit (maximum width, maximum height) in pixels.
        limit: (u32, u32),
    },

    /// Decoding would need more memory than [`ImageLimits::max_alloc_bytes`](crate::ImageLimits).
    #[error(
        "{}: decoding needs more memory than the limit of {limit} bytes",
        path.display()
    )]
    MemoryLimit {
        /// The file (or `<memory>`).
        path: PathBuf,
        /// The configured limit in bytes.
        limit: u64,
    },

    /// The PNG encoder refused the image (for example an image with a zero dimension).
    #[error("cannot encode {} as PNG: {detail}", path.display())]
    Encode {
        /// The file that was to be written.
        path: PathBuf,
        /// The encoder's explanation.
        detail: String,
    },

    /// An animation cannot be written as asked: an unknown output path, no frames, a
    /// frame rate out of range, a frame of the wrong size, too many or too few frames.
    #[error("cannot write animation {}: {detail}", path.display())]
    Animation {
        /// The animation's file (or directory, for a PNG sequence).
        path: PathBuf,
        /// What is wrong, e.g. `"frame 3 is 64x64 pixels, not 128x128"`.
        detail: String,
    },

    /// `rest` and `deformed` have different lengths.
    #[error("mesh has {rest} rest positions but {deformed} deformed positions")]
    MeshLengthMismatch {
        /// Length of `rest`.
        rest: usize,
        /// Length of `deformed`.
        deformed: usize,
    },

    /// A triangle names a vertex that does not exist.
    #[error(
        "triangle {triangle} uses vertex {index}, but the mesh has only {vertex_count} vertices"
    )]
    MeshIndexOutOfRange {
        /// Index of the triangle in `triangles`.
        triangle: usize,
        /// The offending vertex index.
        index: u32,
        /// Number of vertices in the mesh.
        vertex_count: usize,
    },

    /// A vertex position is NaN or infinite.
    #[error("{which} position of vertex {vertex} is not finite")]
    NonFinitePosition {
        /// `"rest"` or `"deformed"`.
        which: &'static str,
        /// The vertex index.
        vertex: usize,
    },

    /// The texture has no pixels, so there is nothing to sample.
    #[error("texture is empty ({width}x{height})")]
    EmptyTexture {
        /// Texture width in pixels.
        width: u32,
        /// Texture height in pixels.
        height: u32,
    },

    /// A picture drawn over one of another depth.
    #[error("a {texture}-bit picture cannot be drawn over a {target}-bit one")]
    DepthMismatch {
        /// Bits per channel of the picture drawn.
        texture: u8,
        /// Bits per channel of the picture drawn over.
        target: u8,
    },

    /// The requested output image cannot be allocated.
    #[error("output image {width}x{height} is too large to allocate")]
    OutputTooLarge {
        /// Requested width in pixels.
        width: u32,
        /// Requested height in pixels.
        height: u32,
    },

    /// No GPU adapter or device could be opened (not even a software one).
    #[error("no GPU adapter: {0} (install a Vulkan driver such as Mesa's lavapipe)")]
    NoAdapter(String),

    /// The GPU failed while drawing or reading back.
    #[error("GPU error: {0}")]
    Gpu(String),
}
