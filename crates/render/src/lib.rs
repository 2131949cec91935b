//! Draws a deformed textured triangle mesh into an RGBA image, and reads and
//! writes image files safely.
//!
//! This crate knows nothing of how the deformed positions were computed: it
//! takes a [`WarpMesh`] (rest positions = texture coordinates in source
//! pixels, deformed positions in output pixels, triangles) and draws it.
//!
//! * [`warp_cpu`] rasterises at full resolution on the CPU (in parallel with
//!   rayon), for export on machines without a GPU.
//! * [`MeshView`] draws the mesh into a caller's render pass (an editor's window),
//!   skinned in the vertex shader, with heat-map, cell, wireframe and fold-over
//!   overlays.
//! * [`load_picture`] / [`decode_picture`] decode PNG, JPEG, WebP, TIFF, BMP and
//!   GIF under [`ImageLimits`] into a [`Picture`] of 8 or 16 bits per channel,
//!   failing fast on hostile headers and refusing truncated JPEGs;
//!   [`load_image`] / [`decode_image`] give RGBA8. [`read_regular_file`] reads
//!   other inputs the same careful way (regular files only, capped).
//! * [`save_png_atomic`] / [`write_atomic`] replace files atomically, so a
//!   crash or a full disk never leaves a half-written file over a good one.
//! * [`AnimationWriter`] streams an animation frame by frame, at full resolution
//!   with alpha, as animated PNG, animated WebP, GIF or a PNG sequence
//!   ([`AnimationFormat`]), put in place atomically when finished.
//!
//! Coordinates follow one convention throughout: origin at the top-left
//! corner, y down, pixel `(x, y)` covering `[x, x+1] × [y, y+1]` with its
//! centre at `(x + 0.5, y + 0.5)`.

#![warn(missing_docs)]

mod alpha;
mod animated;
mod atomic;
mod composite;
mod error;
mod files;
mod gpu;
mod image_io;
mod jpeg;
mod mesh;
mod picture;
mod raster;
mod sample;
mod view;
mod warp;

pub use alpha::AlphaReader;
pub use animated::{AnimationFormat, AnimationWriter};
pub use atomic::{PngPixels, remove_temporary_files, save_png_atomic, write_atomic, write_png};
pub use composite::{over, over16};
pub use error::RenderError;
pub use files::{open_regular_file, read_regular_file, refuse_input_as_output, same_file};
pub use gpu::{Affine, GpuContext, SkinnedMesh};
pub use image_io::{
    ImageLimits, decode_image, decode_picture, decode_picture_named, load_image, load_picture,
};
pub use mesh::WarpMesh;
pub use picture::{Picture, Rgba16Image};
pub use view::{MeshView, Overlay, ViewParams};
pub use warp::{
    RasterOptions, clear_covered, coverage_counts, warp_cpu, warp_over, warp_picture,
    warp_picture_over,
};
