//! A C ABI over wpbgi for pipeline hosts: a DCC plugin, a farm worker, a Python tool.
//! `plugin/include/wpbgi.h` is generated from this crate by cbindgen; `docs/plugin.md` is the
//! guide.
//!
//! The contract, for every function:
//!
//! - It returns a status: [`WPBGI_OK`] or an error code. On an error, [`wpbgi_last_error`]
//!   gives one sentence naming what failed (the file and object, as the CLI's messages do).
//! - No panic crosses the boundary. Each body runs under `catch_unwind`; a caught panic is
//!   [`WPBGI_INTERNAL_ERROR`] and leaves the library usable.
//! - Every pointer is checked for NULL, every buffer for its length and alignment, and every
//!   settings struct for its `struct_size`, before anything is read or written.
//! - Handles (`WpbgiScene`, `WpbgiCache`) are freed by their `_free` function, which accepts
//!   NULL. A handle may be used from any thread, by one call at a time or by several reading
//!   calls at once.
//! - The progress callback runs on the thread that called [`wpbgi_bake`], never on a worker,
//!   so a host may touch its UI from it.
//!
//! Results do not depend on `threads`: the same inputs give byte-identical caches and images.

mod guard;
mod handles;
mod operations;
mod settings;

pub use guard::wpbgi_last_error;
pub use handles::{
    wpbgi_cache_free, wpbgi_cache_hash, wpbgi_cache_open, wpbgi_scene_edit, wpbgi_scene_free,
    wpbgi_scene_load, wpbgi_scene_load_at, wpbgi_scene_set_environment, WpbgiCache, WpbgiScene,
};
pub use operations::{
    wpbgi_bake, wpbgi_bake_hash, wpbgi_preview, wpbgi_relight, wpbgi_render, wpbgi_render_to_file,
    WpbgiProgressFn,
};
pub use settings::{
    wpbgi_bake_settings_init, wpbgi_render_settings_init, WpbgiBakeSettings, WpbgiRenderSettings,
};

/// The version of this ABI. It changes whenever a function, struct or constant of `wpbgi.h`
/// changes incompatibly; a host compares it with the `WPBGI_ABI_VERSION` it was compiled
/// against.
pub const WPBGI_ABI_VERSION: u32 = 1;

/// The call succeeded.
pub const WPBGI_OK: i32 = 0;
/// An argument was wrong: a NULL pointer, a buffer of the wrong length, a settings struct
/// whose `struct_size` does not match, a setting out of range, a file name that is not a
/// supported format. Nothing was done.
pub const WPBGI_INVALID_ARGUMENT: i32 = 1;
/// The operation failed: a file that cannot be read or written, a malformed scene, a cache
/// baked from another scene, no Vulkan device.
pub const WPBGI_FAILED: i32 = 2;
/// The progress callback asked the bake to stop; nothing was written.
pub const WPBGI_CANCELLED: i32 = 3;
/// A bug in wpbgi (a panic, caught). The message says where; please report it.
pub const WPBGI_INTERNAL_ERROR: i32 = 4;

/// The ABI version of the loaded library (`WPBGI_ABI_VERSION` when it was built).
#[no_mangle]
pub extern "C" fn wpbgi_abi_version() -> u32 {
    WPBGI_ABI_VERSION
}

/// The library's version, e.g. "0.1.0" (a static string; do not free).
#[no_mangle]
pub extern "C" fn wpbgi_version() -> *const std::ffi::c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
}
