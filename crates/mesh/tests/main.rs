//! The integration tests, built as one binary: each file is a module.

mod constraints;
mod cutout;
mod degenerate;
mod fine_content;
mod obj;
mod rectangle;
mod support;
