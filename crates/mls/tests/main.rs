//! The integration tests, built as one binary: each file is a module.

mod edges;
mod interpolation;
mod reference;
mod renewed;
mod support;
