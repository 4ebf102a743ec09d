//! The opaque handles: a loaded scene and an opened cache.

use crate::guard::{call, checked_mut, checked_path, checked_ref, checked_str, Failure};
use std::ffi::c_char;
use wpbgi::cache::store::BakedCache;
use wpbgi::scene::Scene;

/// A scene loaded from a glTF or USD file. Free it with `wpbgi_scene_free`.
pub struct WpbgiScene {
    pub(crate) scene: Scene,
}

/// A baked cache, opened and validated. Free it with `wpbgi_cache_free`.
pub struct WpbgiCache {
    pub(crate) cache: BakedCache,
}

/// Bytes a content hash takes as text: 32 hexadecimal digits and the NUL.
pub(crate) const HASH_TEXT: usize = 33;

/// Write `hash` as 32 lowercase hexadecimal digits and a NUL into the caller's `out`.
///
/// # Safety
/// A non-NULL `out` must point to `size` writable bytes.
pub(crate) unsafe fn write_hash(
    hash: [u8; 16],
    out: *mut c_char,
    size: usize,
) -> Result<(), Failure> {
    if out.is_null() {
        return Err(Failure::InvalidArgument("hash_out is NULL".into()));
    }
    if size < HASH_TEXT {
        return Err(Failure::InvalidArgument(format!(
            "hash_out holds {size} bytes where {HASH_TEXT} are needed (32 digits and the NUL)"
        )));
    }
    let text = wpbgi::cache::hash_hex(hash);
    // SAFETY: `out` holds at least HASH_TEXT bytes, by the caller's contract and the check.
    let out = unsafe { std::slice::from_raw_parts_mut(out.cast::<u8>(), HASH_TEXT) };
    out[..32].copy_from_slice(text.as_bytes());
    out[32] = 0;
    Ok(())
}

/// Load the scene at `path` (.gltf, .glb, .usd, .usda, .usdc or .usdz) into `*scene_out`.
/// On failure `*scene_out` is set to NULL.
///
/// # Safety
/// `path` must be NULL or a NUL-terminated string; `scene_out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn wpbgi_scene_load(
    path: *const c_char,
    scene_out: *mut *mut WpbgiScene,
) -> i32 {
    call(|| {
        // SAFETY: the caller's contract; NULL is refused.
        let out = unsafe { checked_mut(scene_out, "scene_out") }?;
        *out = std::ptr::null_mut();
        // SAFETY: the caller's contract.
        let path = unsafe { checked_path(path, "path") }?;
        let scene = Scene::load(&path)?;
        *out = Box::into_raw(Box::new(WpbgiScene { scene }));
        Ok(())
    })
}

/// Load the scene at `path` as [`wpbgi_scene_load`] does, a USD stage at time code
/// `time_code` (a frame of a shot: its animated transforms, cameras and attributes at that
/// time; glTF scenes have no time and ignore it). `time_code` must be finite.
///
/// # Safety
/// `path` must be NULL or a NUL-terminated string; `scene_out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn wpbgi_scene_load_at(
    path: *const c_char,
    time_code: f64,
    scene_out: *mut *mut WpbgiScene,
) -> i32 {
    call(|| {
        // SAFETY: the caller's contract; NULL is refused.
        let out = unsafe { checked_mut(scene_out, "scene_out") }?;
        *out = std::ptr::null_mut();
        // SAFETY: the caller's contract.
        let path = unsafe { checked_path(path, "path") }?;
        if !time_code.is_finite() {
            return Err(wpbgi::Error::InvalidSetting(format!(
                "time_code must be a finite number, got {time_code}"
            ))
            .into());
        }
        let scene = Scene::load_at(&path, Some(time_code))?;
        *out = Box::into_raw(Box::new(WpbgiScene { scene }));
        Ok(())
    })
}

/// Light `scene` with an environment, replacing its own (a USD dome light), as the command
/// line's `--env` does: `spec` is `R,G,B` or `V` (one radiance from every direction) or the
/// path of a latitude-longitude .exr or .hdr image (OpenEXR's orientation), times `intensity`,
/// an image turned by `rotate_degrees` about +Y. It is part of the scene, so of the bake's
/// hash. Handles are otherwise read-only: call it before sharing `scene` between threads.
///
/// # Safety
/// `scene` must be NULL or a live handle that no other thread uses during the call; `spec`
/// NULL or a NUL-terminated string.
#[no_mangle]
pub unsafe extern "C" fn wpbgi_scene_set_environment(
    scene: *mut WpbgiScene,
    spec: *const c_char,
    intensity: f32,
    rotate_degrees: f32,
) -> i32 {
    call(|| {
        // SAFETY: the caller's contract; NULL is refused.
        let scene = unsafe { checked_mut(scene, "scene") }?;
        // SAFETY: the caller's contract; NULL is refused.
        let spec = unsafe { checked_str(spec, "spec") }?;
        let env = wpbgi::scene::Environment::from_spec(spec, intensity, rotate_degrees)?;
        scene.scene.environment = Some(env);
        Ok(())
    })
}

/// Edit `scene` in place as the command line's `--set` does: `edit` is
/// `NAME.PARAMETER=VALUE` or `NAME.PARAMETER*=VALUE` (NAME a material, light or the
/// environment; VALUE one number or `r,g,b`; the parameters are those of `wpbgi --help`). The
/// edit is part of the scene, so of the bake's hash: a cache from `wpbgi_relight` with the same
/// edits opens for the edited scene. An edit that names nothing is refused with
/// WPBGI_INVALID_ARGUMENT, the message saying what the scene has. Call it before sharing
/// `scene` between threads.
///
/// # Safety
/// `scene` must be NULL or a live handle that no other thread uses during the call; `edit`
/// NULL or a NUL-terminated string.
#[no_mangle]
pub unsafe extern "C" fn wpbgi_scene_edit(scene: *mut WpbgiScene, edit: *const c_char) -> i32 {
    call(|| {
        // SAFETY: the caller's contract; NULL is refused.
        let scene = unsafe { checked_mut(scene, "scene") }?;
        // SAFETY: the caller's contract; NULL is refused.
        let edit: wpbgi::scene::edit::Edit = unsafe { checked_str(edit, "edit") }?.parse()?;
        edit.apply(&mut scene.scene)?;
        Ok(())
    })
}

/// Free a scene (NULL is allowed and does nothing).
///
/// # Safety
/// `scene` must be NULL or a handle from `wpbgi_scene_load` not freed before.
#[no_mangle]
pub unsafe extern "C" fn wpbgi_scene_free(scene: *mut WpbgiScene) {
    if !scene.is_null() {
        // A panic in a destructor would be a bug; it must still not unwind into C.
        // SAFETY: the caller's contract: a live handle from Box::into_raw.
        let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            drop(unsafe { Box::from_raw(scene) })
        }));
    }
}

/// Open the cache at `path` into `*cache_out`. With a `scene`, the cache is refused unless it
/// was baked from that scene as it is now (with the settings stored in the cache); with NULL,
/// it is only validated. On failure `*cache_out` is set to NULL.
///
/// # Safety
/// `scene` must be NULL or a live handle; `path` NULL or a NUL-terminated string; `cache_out`
/// NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn wpbgi_cache_open(
    scene: *const WpbgiScene,
    path: *const c_char,
    cache_out: *mut *mut WpbgiCache,
) -> i32 {
    call(|| {
        // SAFETY: the caller's contract; NULL is refused.
        let out = unsafe { checked_mut(cache_out, "cache_out") }?;
        *out = std::ptr::null_mut();
        // SAFETY: the caller's contract.
        let path = unsafe { checked_path(path, "path") }?;
        // SAFETY: the caller's contract; NULL means no scene.
        let cache = match unsafe { scene.as_ref() } {
            Some(s) => BakedCache::open_fresh(&s.scene, &path)?,
            None => BakedCache::read(&path, None)?,
        };
        *out = Box::into_raw(Box::new(WpbgiCache { cache }));
        Ok(())
    })
}

/// The content hash the cache was baked with (as `wpbgi inspect` prints it): 32 hexadecimal
/// digits and a NUL written to `hash_out`, which holds `size` ≥ 33 bytes.
///
/// # Safety
/// `cache` must be NULL or a live handle; `hash_out` NULL or `size` writable bytes.
#[no_mangle]
pub unsafe extern "C" fn wpbgi_cache_hash(
    cache: *const WpbgiCache,
    hash_out: *mut c_char,
    size: usize,
) -> i32 {
    call(|| {
        // SAFETY: the caller's contract; NULL is refused.
        let cache = unsafe { checked_ref(cache, "cache") }?;
        // SAFETY: the caller's contract.
        unsafe { write_hash(cache.cache.cache.hash, hash_out, size) }
    })
}

/// Free a cache (NULL is allowed and does nothing).
///
/// # Safety
/// `cache` must be NULL or a handle from `wpbgi_cache_open` not freed before.
#[no_mangle]
pub unsafe extern "C" fn wpbgi_cache_free(cache: *mut WpbgiCache) {
    if !cache.is_null() {
        // SAFETY: the caller's contract: a live handle from Box::into_raw.
        let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            drop(unsafe { Box::from_raw(cache) })
        }));
    }
}
