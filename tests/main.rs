//! The integration tests, built as one binary: each file is a module.

mod animate;
mod cli;
mod methods;
mod support;
mod window;
