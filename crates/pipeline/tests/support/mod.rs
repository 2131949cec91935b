//! Helpers shared by the pipeline's integration tests.

pub mod energy;
pub mod figure;
pub mod pins;
