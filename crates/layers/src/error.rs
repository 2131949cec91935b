//! The crate's one error type.

/// Everything that can go wrong reading layered artwork. Each message is one line.
#[derive(thiserror::Error, Debug)]
#[non_exhaustive]
pub enum LayerError {
    /// The file could not be read (missing, not a regular file, too large, …).
    #[error(transparent)]
    Read(render::RenderError),

    /// The bytes are neither a PSD nor an OpenRaster file.
    #[error("not a layered picture (neither a PSD nor an OpenRaster file)")]
    NotLayered,

    /// The file is malformed or ends early.
    #[error("{format} is corrupt: {detail}")]
    Corrupt {
        /// `"PSD"` or `"OpenRaster file"`.
        format: &'static str,
        /// What is wrong, and where.
        detail: String,
    },

    /// A variant of the format this reader does not take.
    #[error("{format}: {detail} is not supported")]
    Unsupported {
        /// `"PSD"` or `"OpenRaster file"`.
        format: &'static str,
        /// The variant, named as the file names it.
        detail: String,
    },

    /// The canvas or a layer is larger than the limits.
    #[error("{what} is {width} × {height} pixels; the limit is {max_width} × {max_height}")]
    TooLarge {
        /// `"the canvas"` or the layer, named.
        what: String,
        /// Its width.
        width: u64,
        /// Its height.
        height: u64,
        /// The widest accepted.
        max_width: u32,
        /// The tallest accepted.
        max_height: u32,
    },

    /// The layers' pixels (or an archive entry) need more memory than allowed.
    #[error("the layers need more than {} MiB of memory; refused", limit >> 20)]
    MemoryLimit {
        /// The limit, in bytes.
        limit: u64,
    },

    /// More layers than [`MAX_LAYERS`](crate::MAX_LAYERS).
    #[error("{count} layers; at most {max} are read")]
    TooManyLayers {
        /// How many the file declares.
        count: usize,
        /// The most accepted.
        max: usize,
    },

    /// A layer's picture inside an OpenRaster file could not be decoded.
    #[error("layer {name:?}: {source}")]
    Layer {
        /// The layer's name.
        name: String,
        /// Why.
        source: render::RenderError,
    },
}
