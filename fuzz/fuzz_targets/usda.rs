//! Fuzz target: see `wpbgi::fuzzing::usd`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| wpbgi::fuzzing::usd(data, "usda"));
