//! Fuzz target: see `fuzzing::obj_mesh` for what it checks.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| fuzzing::obj_mesh(data));
