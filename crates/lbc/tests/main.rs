//! The integration tests, built as one binary: each file is a module.

mod optimality;
mod properties;
