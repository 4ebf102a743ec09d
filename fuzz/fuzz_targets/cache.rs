//! Fuzz target: see `wpbgi::fuzzing::cache`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| wpbgi::fuzzing::cache(data));
