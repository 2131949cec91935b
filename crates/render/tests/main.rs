//! The integration tests, built as one binary: each file is a module.

mod animated;
mod gpu;
mod image_io;
mod support;
mod view;
mod warp;
