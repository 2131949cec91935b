//! Fuzz target: see `fuzzing::layered` for what it checks.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| fuzzing::layered(data));
