//! The integration tests, built as one binary: each file is a module.

mod build;
mod overlaid;
mod properties;
mod support;
