//! The integration tests, built as one binary: each file is a module.

mod arap_energy;
mod arap_pins;
mod close_handles;
mod cuts;
mod depth;
mod given_mesh;
mod parts;
mod support;
mod visible_content;
