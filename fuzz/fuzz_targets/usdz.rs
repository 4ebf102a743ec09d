//! Fuzz target: see `wpbgi::fuzzing::usd`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    // libfuzzer-sys's panic hook aborts at once, even where the importer catches the panic
    // (it does for openusd's crate reader, see docs/fuzzing.md). A hook that only prints lets
    // a caught panic count as handled; an uncaught one still ends in libfuzzer-sys's abort.
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| std::panic::set_hook(Box::new(|info| eprintln!("{info}"))));
    wpbgi::fuzzing::usd(data, "usdz")
});
