//! Fuzz target: see `fuzzing::image_mesh` for what it checks.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| fuzzing::image_mesh(data));
