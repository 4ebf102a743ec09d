//! Fuzz target: see `wpbgi::fuzzing::gltf`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| wpbgi::fuzzing::gltf(data));
