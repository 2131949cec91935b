//! Helpers shared by the pipeline's integration tests.

pub mod energy;
pub mod figure;
pub mod pins;

/// A point handle at `rest`, moved by `translate`.
pub fn point(rest: [f64; 2], translate: [f64; 2]) -> project::HandleSpec {
    project::HandleSpec::Point {
        rest,
        translate,
        rotate: 0.0,
        scale: 1.0,
        depth: 0,
    }
}
