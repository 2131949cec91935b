//! The integration tests, built as one binary: each file is a module.

mod animation;
mod cage;
mod edge_states;
mod methods;
mod monkey;
mod parts;
mod support;
mod ui;
