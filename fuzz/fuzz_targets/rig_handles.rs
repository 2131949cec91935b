//! Fuzz target: see `fuzzing::rig_handles` for what it checks.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| fuzzing::rig_handles(data));
