//! The work: bake (progress on the caller's thread, cancel from the callback), the bake's hash,
//! the final render to a buffer or a file, and the headless preview.

use crate::guard::{
    call, checked_buffer, checked_list, checked_path, checked_ref, checked_settings, checked_str,
    Failure,
};
use crate::handles::{write_hash, WpbgiCache, WpbgiScene};
use crate::settings::{WpbgiBakeSettings, WpbgiRenderSettings};
use std::ffi::{c_char, c_void, CString};
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use wpbgi::bake::bake_cancellable;
use wpbgi::bake::relight::{relight, Relighting};
use wpbgi::bake::store::save;
use wpbgi::cache::store::{bake_hash, BakedCache};
use wpbgi::image::{write_exr, write_png, Image};
use wpbgi::preview::device::Gpu;
use wpbgi::preview::{bounds, framing_camera, Preview, Show, DEFAULT_CUT_PIXELS};
use wpbgi::progress::{on_threads, relay, Progress};
use wpbgi::render::render_final;
use wpbgi::scene::{Camera, Scene};

/// Called with the running stage's name ("surfels", "direct light", "coding", "bounces") and
/// how far it is (0 … 1), on the thread that called `wpbgi_bake`. Return 0 to go on, anything
/// else to cancel: the bake stops soon after and `wpbgi_bake` returns WPBGI_CANCELLED.
pub type WpbgiProgressFn = Option<
    unsafe extern "C" fn(stage: *const c_char, fraction: f32, user_data: *mut c_void) -> i32,
>;

/// Run `work` on `threads` workers while this thread passes its progress to `progress`, so
/// that the callback runs where the host called from; a non-zero answer cancels.
fn reporting<R: Send>(
    threads: u32,
    progress: WpbgiProgressFn,
    user_data: *mut c_void,
    work: impl FnOnce(Progress, &AtomicBool) -> wpbgi::error::Result<R> + Send,
) -> Result<R, Failure> {
    let listen = |stage: &str, fraction: f32| {
        let Some(callback) = progress else {
            return false;
        };
        let stage = CString::new(stage).unwrap_or_default();
        // SAFETY: the host's callback, called as its type declares.
        unsafe { callback(stage.as_ptr(), fraction, user_data) != 0 }
    };
    let (result, cancelled) = relay(threads as usize, work, listen)?;
    let result = result?;
    // A cancel asked on the last reports, after the work's last look at the flag, still
    // holds: the host said it does not want the result.
    if cancelled {
        return Err(Failure::Cancelled);
    }
    Ok(result)
}

/// Bake `scene` with `settings` and write the cache to `cache_path` (atomically: a failed or
/// cancelled bake leaves whatever was there before, and no partial file). `progress` may be
/// NULL; `user_data` is passed to it untouched. The cache is byte-identical to what
/// `wpbgi bake` writes with the same settings.
///
/// # Safety
/// `scene` must be NULL or a live handle; `settings` NULL or an initialised struct;
/// `cache_path` NULL or a NUL-terminated string; `progress` NULL or a function of its type.
#[no_mangle]
pub unsafe extern "C" fn wpbgi_bake(
    scene: *const WpbgiScene,
    settings: *const WpbgiBakeSettings,
    cache_path: *const c_char,
    progress: WpbgiProgressFn,
    user_data: *mut c_void,
) -> i32 {
    call(|| {
        // SAFETY: the caller's contract; NULL and wrong sizes are refused.
        let scene = unsafe { checked_ref(scene, "scene") }?;
        let settings = unsafe { checked_settings(settings, "settings") }?;
        let path = unsafe { checked_path(cache_path, "cache_path") }?;
        let library = settings.to_library()?;
        let baked = reporting(settings.threads, progress, user_data, |report, cancel| {
            bake_cancellable(&scene.scene, &library, report, cancel)
        })?;
        save(&path, &scene.scene, &baked)?;
        Ok(())
    })
}

/// Relight `cache`, a fresh bake of `scene`, for `scene` with `edits` applied (`edit_count`
/// strings in the syntax of `wpbgi_scene_edit`), and write the new cache to `output_path`
/// atomically: where the edits multiply every emitter by one factor, the cache rescaled (in
/// the time of copying it, `*rescaled_out` = 1); otherwise the edited scene baked again with
/// the cache's settings (`*rescaled_out` = 0; `progress` and `user_data` as for `wpbgi_bake`).
/// The new cache opens for a scene given the same edits (`wpbgi_scene_edit`) and is refused
/// for `scene`. `rescaled_out` may be NULL.
///
/// # Safety
/// `scene`, `cache` must be NULL or live handles; `edits` NULL or `edit_count` pointers to
/// NUL-terminated strings; `output_path` NULL or a NUL-terminated string; `progress` NULL or
/// a function of its type; `rescaled_out` NULL or writable.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn wpbgi_relight(
    scene: *const WpbgiScene,
    cache: *const WpbgiCache,
    edits: *const *const c_char,
    edit_count: usize,
    output_path: *const c_char,
    threads: u32,
    progress: WpbgiProgressFn,
    user_data: *mut c_void,
    rescaled_out: *mut i32,
) -> i32 {
    call(|| {
        // SAFETY: the caller's contract; NULL is refused.
        let scene = unsafe { checked_ref(scene, "scene") }?;
        // SAFETY: the caller's contract; NULL is refused.
        let cache = unsafe { checked_ref(cache, "cache") }?;
        // SAFETY: the caller's contract; NULL is refused.
        let output = unsafe { checked_path(output_path, "output_path") }?;
        if edit_count == 0 {
            return Err(Failure::InvalidArgument(
                "edit_count is 0: there is nothing to relight".into(),
            ));
        }
        // SAFETY: the caller's contract: `edit_count` pointers; NULL is refused.
        let list = unsafe { checked_list(edits, edit_count, "edits") }?;
        let edits = list
            .iter()
            .enumerate()
            .map(|(i, &e)| {
                // SAFETY: the caller's contract; NULL is refused.
                let text = unsafe { checked_str(e, &format!("edits[{i}]")) }?;
                Ok(text.parse::<wpbgi::scene::edit::Edit>()?)
            })
            .collect::<Result<Vec<_>, Failure>>()?;
        let (scene, cache) = (&scene.scene, &cache.cache);
        let relit = reporting(threads, progress, user_data, |report, cancel| {
            relight(scene, cache, &edits, &output, report, cancel)
        })?;
        // SAFETY: the caller's contract; NULL means not wanted.
        if let Some(out) = unsafe { rescaled_out.as_mut() } {
            *out = i32::from(matches!(relit.how, Relighting::Rescaled { .. }));
        }
        Ok(())
    })
}

/// The content hash a bake of `scene` with `settings` would have: 32 hexadecimal digits and a
/// NUL written to `hash_out` (`size` ≥ 33 bytes). Equal to `wpbgi_cache_hash` of a cache
/// exactly when that cache is this bake, so a pipeline can tell whether a recorded cache is
/// still good without baking.
///
/// # Safety
/// `scene` must be NULL or a live handle; `settings` NULL or an initialised struct; `hash_out`
/// NULL or `size` writable bytes.
#[no_mangle]
pub unsafe extern "C" fn wpbgi_bake_hash(
    scene: *const WpbgiScene,
    settings: *const WpbgiBakeSettings,
    hash_out: *mut c_char,
    size: usize,
) -> i32 {
    call(|| {
        // SAFETY: the caller's contract; NULL and wrong sizes are refused.
        let scene = unsafe { checked_ref(scene, "scene") }?;
        let settings = unsafe { checked_settings(settings, "settings") }?;
        let hash = bake_hash(&scene.scene, &settings.to_library()?.to_json());
        // SAFETY: the caller's contract.
        unsafe { write_hash(hash, hash_out, size) }
    })
}

/// The checked arguments of a render.
struct RenderJob<'a> {
    scene: &'a Scene,
    cache: &'a BakedCache,
    settings: WpbgiRenderSettings,
    camera: Camera,
}

/// # Safety
/// As the exported render functions' arguments.
unsafe fn render_job<'a>(
    scene: *const WpbgiScene,
    cache: *const WpbgiCache,
    settings: *const WpbgiRenderSettings,
) -> Result<RenderJob<'a>, Failure> {
    // SAFETY: the caller's contract; NULL and wrong sizes are refused.
    let scene = unsafe { checked_ref(scene, "scene") }?;
    let cache = unsafe { checked_ref(cache, "cache") }?;
    let settings = *unsafe { checked_settings(settings, "settings") }?;
    let (w, h) = settings.size()?;
    let camera = scene.scene.camera(settings.camera_name()?, w, h)?;
    Ok(RenderJob {
        scene: &scene.scene,
        cache: &cache.cache,
        settings,
        camera,
    })
}

impl RenderJob<'_> {
    fn render(&self) -> Result<Image, Failure> {
        let settings = self.settings.to_final()?;
        // Only what the workers need crosses to them (the settings hold a C pointer).
        let (scene, cache, camera) = (self.scene, self.cache, &self.camera);
        let out = on_threads(self.settings.threads as usize, || {
            render_final(scene, cache, camera, &settings, &|_, _| {})
        })??;
        Ok(out.beauty)
    }
}

/// Copy `image` into the caller's buffer of RGB floats.
fn copy_rgb(image: &Image, out: &mut [f32]) {
    for (dst, p) in out.chunks_exact_mut(3).zip(&image.pixels) {
        dst.copy_from_slice(&p.to_array());
    }
}

/// The final render of `scene` from `cache` (which must be fresh for it), into `rgb_out`:
/// width × height × 3 floats (`floats` of them), linear RGB, rows top to bottom. The same
/// image as `wpbgi render` with the same settings.
///
/// # Safety
/// `scene`, `cache` must be NULL or live handles; `settings` NULL or an initialised struct;
/// `rgb_out` NULL or `floats` writable floats.
#[no_mangle]
pub unsafe extern "C" fn wpbgi_render(
    scene: *const WpbgiScene,
    cache: *const WpbgiCache,
    settings: *const WpbgiRenderSettings,
    rgb_out: *mut f32,
    floats: usize,
) -> i32 {
    call(|| {
        // SAFETY: the caller's contract.
        let job = unsafe { render_job(scene, cache, settings) }?;
        let need = rgb_floats(&job.settings)?;
        // SAFETY: the caller's contract for `floats`; checked against the size.
        let out = unsafe { checked_buffer(rgb_out, floats, need, "rgb_out") }?;
        copy_rgb(&job.render()?, out);
        Ok(())
    })
}

/// width × height × 3.
fn rgb_floats(settings: &WpbgiRenderSettings) -> Result<usize, Failure> {
    let (w, h) = settings.size()?;
    Ok(w as usize * h as usize * 3)
}

/// The final render, as `wpbgi_render`, written to `path`: OpenEXR (float) for .exr, sRGB
/// 8-bit for .png. Written atomically.
///
/// # Safety
/// As `wpbgi_render`; `path` NULL or a NUL-terminated string.
#[no_mangle]
pub unsafe extern "C" fn wpbgi_render_to_file(
    scene: *const WpbgiScene,
    cache: *const WpbgiCache,
    settings: *const WpbgiRenderSettings,
    path: *const c_char,
) -> i32 {
    call(|| {
        // SAFETY: the caller's contract.
        let job = unsafe { render_job(scene, cache, settings) }?;
        let path = unsafe { checked_path(path, "path") }?;
        let write: fn(&Path, &Image) -> wpbgi::error::Result<()> = match extension(&path) {
            Some("exr") => write_exr,
            Some("png") => write_png,
            _ => {
                return Err(Failure::InvalidArgument(format!(
                    "{}: the image must end in .exr or .png",
                    path.display()
                )))
            }
        };
        write(&path, &job.render()?)?;
        Ok(())
    })
}

fn extension(path: &Path) -> Option<&'static str> {
    let e = path.extension()?.to_str()?;
    ["exr", "png"]
        .into_iter()
        .find(|x| e.eq_ignore_ascii_case(x))
}

/// The headless Vulkan preview of `cache` (splatted onto `scene`'s surfaces; with a NULL
/// scene, the cache's points, framed) into `rgb_out` as `wpbgi_render` lays it out. Only
/// `width`, `height` and `camera` of `settings` are used. Needs a Vulkan driver (lavapipe
/// will do); WPBGI_VALIDATE=1 in the environment turns on the validation layer.
///
/// # Safety
/// `scene` NULL or a live handle; otherwise as `wpbgi_render`.
#[no_mangle]
pub unsafe extern "C" fn wpbgi_preview(
    scene: *const WpbgiScene,
    cache: *const WpbgiCache,
    settings: *const WpbgiRenderSettings,
    rgb_out: *mut f32,
    floats: usize,
) -> i32 {
    call(|| {
        // SAFETY: the caller's contract; NULL and wrong sizes are refused.
        let cache = &unsafe { checked_ref(cache, "cache") }?.cache;
        let scene = unsafe { scene.as_ref() }.map(|s| &s.scene);
        let settings = unsafe { checked_settings(settings, "settings") }?;
        let (w, h) = settings.size()?;
        let out = unsafe { checked_buffer(rgb_out, floats, rgb_floats(settings)?, "rgb_out") }?;
        let camera = match (scene, settings.camera_name()?) {
            (Some(s), name) => s.camera(name, w, h)?,
            (None, Some(_)) => {
                return Err(Failure::InvalidArgument(
                    "settings->camera names a scene camera, but scene is NULL".into(),
                ))
            }
            (None, None) => framing_camera(bounds(cache, None), w, h)
                .ok_or_else(|| Failure::Failed("the cache holds no surfels to frame".into()))?,
        };
        let failed = |e: &dyn std::fmt::Display| Failure::Failed(e.to_string());
        let gpu = Arc::new(Gpu::from_env().map_err(|e| failed(&e))?);
        let mut preview = Preview::new(gpu, cache, scene, (w, h)).map_err(|e| failed(&e))?;
        let frame = preview
            .frame(&camera, Show::Total, DEFAULT_CUT_PIXELS)
            .map_err(|e| failed(&e))?;
        copy_rgb(&frame.image, out);
        Ok(())
    })
}
