//! The integration tests, built as one binary: each file is a module.

mod behaviour;
mod degenerate;
mod local_global;
mod properties;
mod reference;
mod support;
