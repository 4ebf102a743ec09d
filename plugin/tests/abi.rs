//! The C ABI called as a C host calls it: results equal to the Rust API's byte for byte,
//! cancelling from the progress callback, and an error code and a readable message for every
//! wrong argument.

mod common;

use common::*;
use std::ffi::{c_char, c_void, CStr, CString};
use std::ptr::{null, null_mut};
use std::time::{Duration, Instant};
use wpbgi_plugin::*;

fn last_error() -> String {
    // SAFETY: never NULL, valid until this thread's next call.
    unsafe { CStr::from_ptr(wpbgi_last_error()) }
        .to_string_lossy()
        .into_owned()
}

fn c(s: &str) -> CString {
    CString::new(s).expect("no NUL")
}

fn path_c(p: &std::path::Path) -> CString {
    c(p.to_str().expect("UTF-8 path"))
}

/// A settings struct as its `_init` function fills it.
fn initialised<T>(init: unsafe extern "C" fn(*mut T) -> i32) -> T {
    let mut s = std::mem::MaybeUninit::<T>::uninit();
    // SAFETY: a writable struct of the type `init` fills.
    assert_eq!(unsafe { init(s.as_mut_ptr()) }, WPBGI_OK);
    // SAFETY: initialised by the call.
    unsafe { s.assume_init() }
}

fn bake_settings(points: u64, bounces: i32) -> WpbgiBakeSettings {
    WpbgiBakeSettings {
        points,
        bounces,
        ..initialised(wpbgi_bake_settings_init)
    }
}

fn render_settings(size: u32) -> WpbgiRenderSettings {
    WpbgiRenderSettings {
        width: size,
        height: size,
        ..initialised(wpbgi_render_settings_init)
    }
}

struct Scene(*mut WpbgiScene);

impl Scene {
    fn load(path: &std::path::Path) -> Scene {
        let mut s = null_mut();
        // SAFETY: valid string and out pointer.
        let status = unsafe { wpbgi_scene_load(path_c(path).as_ptr(), &mut s) };
        assert_eq!(status, WPBGI_OK, "{}", last_error());
        Scene(s)
    }
}

impl Drop for Scene {
    fn drop(&mut self) {
        // SAFETY: a live handle.
        unsafe { wpbgi_scene_free(self.0) }
    }
}

struct Cache(*mut WpbgiCache);

impl Cache {
    fn open(scene: &Scene, path: &std::path::Path) -> Result<Cache, (i32, String)> {
        let mut out = null_mut();
        // SAFETY: live scene, valid string and out pointer.
        match unsafe { wpbgi_cache_open(scene.0, path_c(path).as_ptr(), &mut out) } {
            WPBGI_OK => Ok(Cache(out)),
            status => {
                assert!(out.is_null(), "a failed open leaves *cache_out NULL");
                Err((status, last_error()))
            }
        }
    }

    fn hash(&self) -> String {
        let mut text = [0 as c_char; 33];
        // SAFETY: live cache, 33 writable bytes.
        assert_eq!(
            unsafe { wpbgi_cache_hash(self.0, text.as_mut_ptr(), 33) },
            WPBGI_OK
        );
        // SAFETY: NUL-terminated by the call.
        unsafe { CStr::from_ptr(text.as_ptr()) }
            .to_string_lossy()
            .into_owned()
    }
}

impl Drop for Cache {
    fn drop(&mut self) {
        // SAFETY: a live handle.
        unsafe { wpbgi_cache_free(self.0) }
    }
}

fn bake_to(scene: &Scene, settings: &WpbgiBakeSettings, path: &std::path::Path) -> i32 {
    // SAFETY: live scene, initialised settings, valid string, no callback.
    unsafe { wpbgi_bake(scene.0, settings, path_c(path).as_ptr(), None, null_mut()) }
}

/// Bake `scene` to `path` and open the cache for it.
fn baked(scene: &Scene, settings: &WpbgiBakeSettings, path: &std::path::Path) -> Cache {
    assert_eq!(bake_to(scene, settings, path), WPBGI_OK, "{}", last_error());
    Cache::open(scene, path).expect("the fresh cache opens")
}

/// The hash a bake of `scene` with `settings` would have (`wpbgi_bake_hash`).
fn hash_of(scene: &Scene, settings: &WpbgiBakeSettings) -> String {
    let mut text = [0 as c_char; 40];
    // SAFETY: live scene, initialised settings, 40 writable bytes.
    let status = unsafe { wpbgi_bake_hash(scene.0, settings, text.as_mut_ptr(), text.len()) };
    assert_eq!(status, WPBGI_OK, "{}", last_error());
    // SAFETY: NUL-terminated by the call.
    unsafe { CStr::from_ptr(text.as_ptr()) }
        .to_string_lossy()
        .into_owned()
}

#[test]
fn abi_version_and_library_version() {
    assert_eq!(wpbgi_abi_version(), WPBGI_ABI_VERSION);
    // SAFETY: a static NUL-terminated string.
    let v = unsafe { CStr::from_ptr(wpbgi_version()) };
    assert_eq!(v.to_str(), Ok(env!("CARGO_PKG_VERSION")));
}

#[test]
fn bake_and_render_equal_the_rust_api_byte_for_byte() {
    let dir = scratch("equal");
    let scene = Scene::load(&scene_path());
    let cache_path = dir.join("abi.wpc");
    // Two worker threads here; the Rust API's reference ran on the global pool.
    let mut settings = bake_settings(POINTS, BOUNCES);
    settings.threads = 2;
    let cache = baked(&scene, &settings, &cache_path);

    let mut rgb = vec![f32::NAN; (SIZE * SIZE * 3) as usize];
    let mut rs = render_settings(SIZE);
    rs.threads = 3;
    // SAFETY: live handles, initialised settings, a buffer of the stated length.
    let status = unsafe { wpbgi_render(scene.0, cache.0, &rs, rgb.as_mut_ptr(), rgb.len()) };
    assert_eq!(status, WPBGI_OK, "{}", last_error());

    let (rust_cache, rust_rgb) = rust_api_result(POINTS, BOUNCES, SIZE);
    let abi_cache = std::fs::read(&cache_path).expect("read the cache");
    assert!(
        abi_cache == rust_cache,
        "the ABI's cache differs from the Rust API's"
    );
    assert!(
        same_bits(&rgb, &rust_rgb),
        "the ABI's image differs from the Rust API's"
    );
    assert!(rgb.iter().all(|v| v.is_finite()) && rgb.iter().any(|&v| v > 0.0));

    // The hash a bake would have is the cache's hash; another seed changes it.
    let mut text = [0 as c_char; 40];
    // SAFETY: live scene, initialised settings, 40 writable bytes.
    let status = unsafe { wpbgi_bake_hash(scene.0, &settings, text.as_mut_ptr(), text.len()) };
    assert_eq!(status, WPBGI_OK);
    // SAFETY: NUL-terminated by the call.
    let predicted = unsafe { CStr::from_ptr(text.as_ptr()) }
        .to_string_lossy()
        .into_owned();
    assert_eq!(predicted, cache.hash());
    assert_eq!(predicted.len(), 32);
    let mut other = settings;
    other.seed = 1;
    // SAFETY: as above.
    unsafe { wpbgi_bake_hash(scene.0, &other, text.as_mut_ptr(), text.len()) };
    // SAFETY: NUL-terminated by the call.
    assert_ne!(
        unsafe { CStr::from_ptr(text.as_ptr()) }.to_string_lossy(),
        predicted
    );

    // The same render through a file.
    let exr = dir.join("abi.exr");
    // SAFETY: live handles, initialised settings, valid string.
    let status = unsafe { wpbgi_render_to_file(scene.0, cache.0, &rs, path_c(&exr).as_ptr()) };
    assert_eq!(status, WPBGI_OK, "{}", last_error());
    let read = wpbgi::image::read_exr(&exr).expect("read the EXR");
    let from_file: Vec<f32> = read.pixels.iter().flat_map(|p| p.to_array()).collect();
    assert!(
        same_bits(&from_file, &rust_rgb),
        "the EXR holds the same floats"
    );
}

/// When to ask for a stop, given the stage and its fraction.
type StopWhen = fn(&str, f32) -> bool;

/// What the progress callback saw, and when it asked to stop.
struct Watch {
    reports: Vec<(String, f32)>,
    off_thread: bool,
    caller: std::thread::ThreadId,
    cancel_when: StopWhen,
    cancelled: Option<Instant>,
}

unsafe extern "C" fn watch(stage: *const c_char, fraction: f32, user_data: *mut c_void) -> i32 {
    // SAFETY: user_data is the test's &mut Watch, and the call comes on its thread (checked).
    let w = unsafe { &mut *user_data.cast::<Watch>() };
    w.off_thread |= std::thread::current().id() != w.caller;
    // SAFETY: a NUL-terminated stage name.
    let stage = unsafe { CStr::from_ptr(stage) }
        .to_string_lossy()
        .into_owned();
    let stop = (w.cancel_when)(&stage, fraction);
    w.reports.push((stage, fraction));
    if stop && w.cancelled.is_none() {
        w.cancelled = Some(Instant::now());
    }
    i32::from(w.cancelled.is_some())
}

fn watched_bake(
    cancel_when: fn(&str, f32) -> bool,
    path: &std::path::Path,
) -> (i32, Watch, Duration) {
    let scene = Scene::load(&scene_path());
    let settings = bake_settings(8000, 2);
    let mut w = Watch {
        reports: Vec::new(),
        off_thread: false,
        caller: std::thread::current().id(),
        cancel_when,
        cancelled: None,
    };
    let start = Instant::now();
    // SAFETY: live scene, initialised settings, valid string; the callback's user data is `w`,
    // alive for the call.
    let status = unsafe {
        wpbgi_bake(
            scene.0,
            &settings,
            path_c(path).as_ptr(),
            Some(watch),
            (&mut w as *mut Watch).cast(),
        )
    };
    let end = Instant::now();
    let after_cancel = w.cancelled.map_or(end - start, |t| end - t);
    (status, w, after_cancel)
}

#[test]
fn cancelling_from_the_callback_stops_promptly_and_writes_nothing() {
    let dir = scratch("cancel");
    let full_path = dir.join("full.wpc");
    let (status, full, full_time) = watched_bake(|_, _| false, &full_path);
    assert_eq!(status, WPBGI_OK, "{}", last_error());
    assert!(!full.off_thread, "the callback runs on the caller's thread");
    let stages: Vec<&str> = full.reports.iter().map(|r| r.0.as_str()).collect();
    for s in ["surfels", "direct light", "coding", "bounces"] {
        assert!(stages.contains(&s), "reported {s}: {stages:?}");
    }
    // Within a bounce, the receivers report their progress (not only its start and end).
    let inside = full
        .reports
        .iter()
        .filter(|(s, f)| s == "bounces" && *f > 0.0 && *f < 0.5)
        .count();
    assert!(
        inside >= 2,
        "progress within the first bounce: {:?}",
        full.reports
    );

    let within: [(&str, StopWhen); 2] = [
        ("direct light", |s, f| s == "direct light" && f > 0.0),
        ("bounces", |s, f| s == "bounces" && f > 0.0),
    ];
    for (stage, when) in within {
        let path = dir.join(format!("cancelled-{}.wpc", stage.replace(' ', "-")));
        let (status, w, after) = watched_bake(when, &path);
        assert_eq!(status, WPBGI_CANCELLED, "cancelled in {stage}");
        assert_eq!(last_error(), "the bake was cancelled");
        assert!(w.cancelled.is_some());
        // Promptly: the surfel loops look at the flag per surfel and per receiver group, so the
        // rest of a stage is skipped. A full bake of this scene takes seconds; allow a tenth.
        assert!(
            after < full_time / 10,
            "cancelled in {stage}: returned {after:?} after the request (a full bake: {full_time:?})"
        );
        assert!(!path.exists(), "a cancelled bake writes no cache");
        eprintln!("cancelled in {stage}: returned {after:?} after the request (a full bake: {full_time:?})");
    }
    // A stop asked on the bake's very last report, when its loops are done, still holds.
    let path = dir.join("cancelled-last.wpc");
    let (status, w, _) = watched_bake(|s, f| s == "bounces" && f >= 1.0, &path);
    assert_eq!(status, WPBGI_CANCELLED);
    assert_eq!(w.reports.last().map(|r| r.1), Some(1.0));
    assert!(!path.exists(), "a cancelled bake writes no cache");

    // Nothing else was left behind (no temporary file of an atomic write).
    let mut left: Vec<String> = std::fs::read_dir(&dir)
        .expect("list")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(left, ["full.wpc"]);
}

#[test]
fn a_cancelled_bake_keeps_the_previous_cache() {
    let dir = scratch("keep");
    let path = dir.join("scene.wpc");
    std::fs::write(&path, b"the previous cache").expect("write");
    let (status, _, _) = watched_bake(|s, f| s == "direct light" && f > 0.0, &path);
    assert_eq!(status, WPBGI_CANCELLED);
    assert_eq!(std::fs::read(&path).expect("read"), b"the previous cache");
}

/// Assert `status` is `expected` and the message mentions every word of `words`.
#[track_caller]
fn refused(status: i32, expected: i32, words: &[&str]) {
    let message = last_error();
    assert_eq!(status, expected, "status for: {message}");
    for w in words {
        assert!(message.contains(w), "\"{message}\" should mention \"{w}\"");
    }
}

#[test]
fn invalid_arguments_return_a_code_and_a_message() {
    let dir = scratch("invalid");
    let scene = Scene::load(&scene_path());
    let good = bake_settings(500, 0);
    let cache_path = dir.join("small.wpc");
    assert_eq!(
        bake_to(&scene, &good, &cache_path),
        WPBGI_OK,
        "{}",
        last_error()
    );
    let cache = Cache::open(&scene, &cache_path).expect("open");
    let rs = render_settings(8);
    let mut rgb = vec![0.0f32; 8 * 8 * 3];
    let p = path_c(&cache_path);
    // SAFETY (all calls below): every pointer is NULL, live, or a valid string or buffer; the
    // wrong ones are wrong only in the ways the ABI promises to check.
    unsafe {
        let mut handle = null_mut();
        refused(
            wpbgi_scene_load(null(), &mut handle),
            WPBGI_INVALID_ARGUMENT,
            &["path", "NULL"],
        );
        refused(
            wpbgi_scene_load(c("x.gltf").as_ptr(), null_mut()),
            WPBGI_INVALID_ARGUMENT,
            &["scene_out"],
        );
        refused(
            wpbgi_scene_load(c("").as_ptr(), &mut handle),
            WPBGI_INVALID_ARGUMENT,
            &["path", "empty"],
        );
        let missing = dir.join("missing.gltf");
        refused(
            wpbgi_scene_load(path_c(&missing).as_ptr(), &mut handle),
            WPBGI_FAILED,
            &["missing.gltf"],
        );
        assert!(handle.is_null());
        refused(
            wpbgi_scene_load(path_c(&dir.join("notes.txt")).as_ptr(), &mut handle),
            WPBGI_FAILED,
            &["notes.txt", "unsupported"],
        );

        refused(
            wpbgi_bake(null(), &good, p.as_ptr(), None, null_mut()),
            WPBGI_INVALID_ARGUMENT,
            &["scene"],
        );
        refused(
            wpbgi_bake(scene.0, null(), p.as_ptr(), None, null_mut()),
            WPBGI_INVALID_ARGUMENT,
            &["settings"],
        );
        refused(
            wpbgi_bake(scene.0, &good, null(), None, null_mut()),
            WPBGI_INVALID_ARGUMENT,
            &["cache_path"],
        );
        let mut wrong = good;
        wrong.struct_size -= 8;
        refused(
            wpbgi_bake(scene.0, &wrong, p.as_ptr(), None, null_mut()),
            WPBGI_INVALID_ARGUMENT,
            &["struct_size"],
        );
        let mut wrong = good;
        wrong.quality = 9;
        refused(
            wpbgi_bake(scene.0, &wrong, p.as_ptr(), None, null_mut()),
            WPBGI_INVALID_ARGUMENT,
            &["quality"],
        );
        let mut wrong = good;
        wrong.bounces = -2;
        refused(
            wpbgi_bake(scene.0, &wrong, p.as_ptr(), None, null_mut()),
            WPBGI_INVALID_ARGUMENT,
            &["bounces"],
        );
        let unwritable = dir.join("no-such-folder/x.wpc");
        refused(
            wpbgi_bake(
                scene.0,
                &good,
                path_c(&unwritable).as_ptr(),
                None,
                null_mut(),
            ),
            WPBGI_FAILED,
            &["no-such-folder"],
        );
        refused(
            wpbgi_bake_settings_init(null_mut()),
            WPBGI_INVALID_ARGUMENT,
            &["settings"],
        );
        refused(
            wpbgi_render_settings_init(null_mut()),
            WPBGI_INVALID_ARGUMENT,
            &["settings"],
        );

        let mut out = null_mut();
        refused(
            wpbgi_cache_open(scene.0, null(), &mut out),
            WPBGI_INVALID_ARGUMENT,
            &["path"],
        );
        refused(
            wpbgi_cache_open(scene.0, p.as_ptr(), null_mut()),
            WPBGI_INVALID_ARGUMENT,
            &["cache_out"],
        );
        let garbage = dir.join("garbage.wpc");
        std::fs::write(&garbage, b"not a cache").expect("write");
        refused(
            wpbgi_cache_open(scene.0, path_c(&garbage).as_ptr(), &mut out),
            WPBGI_FAILED,
            &["garbage.wpc"],
        );
        assert!(out.is_null());
        let mut short = [0 as c_char; 32];
        refused(
            wpbgi_cache_hash(cache.0, short.as_mut_ptr(), 32),
            WPBGI_INVALID_ARGUMENT,
            &["33"],
        );
        refused(
            wpbgi_cache_hash(null(), short.as_mut_ptr(), 32),
            WPBGI_INVALID_ARGUMENT,
            &["cache"],
        );
        refused(
            wpbgi_bake_hash(scene.0, &good, null_mut(), 33),
            WPBGI_INVALID_ARGUMENT,
            &["hash_out"],
        );

        let n = rgb.len();
        refused(
            wpbgi_render(null(), cache.0, &rs, rgb.as_mut_ptr(), n),
            WPBGI_INVALID_ARGUMENT,
            &["scene"],
        );
        refused(
            wpbgi_render(scene.0, null(), &rs, rgb.as_mut_ptr(), n),
            WPBGI_INVALID_ARGUMENT,
            &["cache"],
        );
        refused(
            wpbgi_render(scene.0, cache.0, null(), rgb.as_mut_ptr(), n),
            WPBGI_INVALID_ARGUMENT,
            &["settings"],
        );
        refused(
            wpbgi_render(scene.0, cache.0, &rs, null_mut(), n),
            WPBGI_INVALID_ARGUMENT,
            &["rgb_out"],
        );
        refused(
            wpbgi_render(scene.0, cache.0, &rs, rgb.as_mut_ptr(), n - 1),
            WPBGI_INVALID_ARGUMENT,
            &["rgb_out", "191", "192"],
        );
        let misaligned = rgb.as_mut_ptr().cast::<u8>().add(1).cast::<f32>();
        refused(
            wpbgi_render(scene.0, cache.0, &rs, misaligned, n - 1),
            WPBGI_INVALID_ARGUMENT,
            &["aligned"],
        );
        let mut big = rs;
        big.width = 0;
        refused(
            wpbgi_render(scene.0, cache.0, &big, rgb.as_mut_ptr(), n),
            WPBGI_INVALID_ARGUMENT,
            &["width"],
        );
        let mut named = rs;
        let nobody = c("nobody");
        named.camera = nobody.as_ptr();
        refused(
            wpbgi_render(scene.0, cache.0, &named, rgb.as_mut_ptr(), n),
            WPBGI_FAILED,
            &["nobody"],
        );
        let mut dark = rs;
        dark.light_samples = 0;
        refused(
            wpbgi_render(scene.0, cache.0, &dark, rgb.as_mut_ptr(), n),
            WPBGI_INVALID_ARGUMENT,
            &["light_samples"],
        );
        refused(
            wpbgi_render_to_file(scene.0, cache.0, &rs, path_c(&dir.join("x.tiff")).as_ptr()),
            WPBGI_INVALID_ARGUMENT,
            &["x.tiff", ".exr"],
        );
        refused(
            wpbgi_preview(null(), cache.0, &named, rgb.as_mut_ptr(), n),
            WPBGI_INVALID_ARGUMENT,
            &["camera", "scene is NULL"],
        );

        // Nothing above broke the handles: they still render, and a success clears the message.
        assert_eq!(
            wpbgi_render(scene.0, cache.0, &rs, rgb.as_mut_ptr(), n),
            WPBGI_OK
        );
        assert_eq!(last_error(), "");
        wpbgi_scene_free(null_mut());
        wpbgi_cache_free(null_mut());
    }
}

#[test]
fn a_cache_of_another_scene_or_setting_is_refused() {
    let dir = scratch("stale");
    let scene = Scene::load(&scene_path());
    let path = dir.join("glossy.wpc");
    assert_eq!(bake_to(&scene, &bake_settings(500, 0), &path), WPBGI_OK);
    let other = Scene::load(&scene_path().with_file_name("cbox-diffuse.gltf"));
    let (status, message) = Cache::open(&other, &path).err().expect("refused");
    assert_eq!(status, WPBGI_FAILED);
    assert!(message.contains("glossy.wpc"), "{message}");
}

#[test]
fn headless_preview_equals_the_rust_api() {
    use std::sync::Arc;
    use wpbgi::preview::{device::Gpu, Preview, Show, DEFAULT_CUT_PIXELS};
    let dir = scratch("preview");
    let scene = Scene::load(&scene_path());
    let path = dir.join("preview.wpc");
    assert_eq!(bake_to(&scene, &bake_settings(2000, 0), &path), WPBGI_OK);
    let cache = Cache::open(&scene, &path).expect("open");
    let size = 48;
    let mut rgb = vec![f32::NAN; size * size * 3];
    // SAFETY: live handles, initialised settings, a buffer of the stated length.
    let status = unsafe {
        wpbgi_preview(
            scene.0,
            cache.0,
            &render_settings(size as u32),
            rgb.as_mut_ptr(),
            rgb.len(),
        )
    };
    assert_eq!(status, WPBGI_OK, "{}", last_error());

    let lib_scene = wpbgi::scene::Scene::load(&scene_path()).expect("load");
    let lib_cache = wpbgi::cache::store::BakedCache::open_fresh(&lib_scene, &path).expect("open");
    let gpu = Arc::new(Gpu::from_env().expect("Vulkan (lavapipe in CI)"));
    let mut preview = Preview::new(
        gpu,
        &lib_cache,
        Some(&lib_scene),
        (size as u32, size as u32),
    )
    .expect("preview");
    let camera = lib_scene
        .camera(None, size as u32, size as u32)
        .expect("camera");
    let frame = preview
        .frame(&camera, Show::Total, DEFAULT_CUT_PIXELS)
        .expect("frame");
    let expected: Vec<f32> = frame
        .image
        .pixels
        .iter()
        .flat_map(|p| p.to_array())
        .collect();
    assert!(
        same_bits(&rgb, &expected),
        "the ABI's preview differs from the Rust API's"
    );
    assert!(rgb.iter().any(|&v| v > 0.0));
}

/// `wpbgi_scene_load_at`: a USD stage whose mesh moves between time codes 1 and 10 (the
/// repository's tests/data/usd/animated.usda) loads at a frame. The bake's hash, which covers
/// the geometry, is the default load's at the stage's start (1), another at 10, and a time code
/// that is not a number is refused.
#[test]
fn scenes_load_at_a_time_code() {
    let stage =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/usd/animated.usda");
    let hash_at = |time: Option<f64>| {
        let mut s = null_mut();
        // SAFETY: valid string and out pointer.
        let status = unsafe {
            match time {
                Some(t) => wpbgi_scene_load_at(path_c(&stage).as_ptr(), t, &mut s),
                None => wpbgi_scene_load(path_c(&stage).as_ptr(), &mut s),
            }
        };
        assert_eq!(status, WPBGI_OK, "{}", last_error());
        hash_of(&Scene(s), &bake_settings(1000, 0))
    };
    assert_eq!(hash_at(None), hash_at(Some(1.0)));
    assert_ne!(hash_at(Some(1.0)), hash_at(Some(10.0)));
    let mut s = null_mut();
    // SAFETY: valid string and out pointer.
    let status = unsafe { wpbgi_scene_load_at(path_c(&stage).as_ptr(), f64::NAN, &mut s) };
    assert_eq!(status, WPBGI_INVALID_ARGUMENT);
    assert!(s.is_null());
    assert!(last_error().contains("time_code"), "{}", last_error());
}

/// `wpbgi_scene_set_environment`: a scene with no light of its own (the repository's
/// tests/data/usd/cube-unlit.usda) is refused by the bake with a message naming the call;
/// lit by a constant environment it bakes, and the environment enters the bake's hash. A file
/// that is not there and a NULL spec are refused.
#[test]
fn an_environment_lights_an_unlit_scene() {
    let dir = scratch("environment");
    let cube = Scene::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/usd/cube-unlit.usda"),
    );
    let settings = bake_settings(1000, 0);
    let status = bake_to(&cube, &settings, &dir.join("dark.wpc"));
    assert_ne!(status, WPBGI_OK);
    assert!(
        last_error().contains("wpbgi_scene_set_environment"),
        "{}",
        last_error()
    );
    let hash = |scene: &Scene| hash_of(scene, &settings);
    let unlit = hash(&cube);
    // SAFETY: a live handle used by this thread alone, a valid string.
    let status = unsafe { wpbgi_scene_set_environment(cube.0, c("0.5,1,2").as_ptr(), 1.0, 0.0) };
    assert_eq!(status, WPBGI_OK, "{}", last_error());
    assert_ne!(hash(&cube), unlit);
    assert_eq!(
        bake_to(&cube, &settings, &dir.join("lit.wpc")),
        WPBGI_OK,
        "{}",
        last_error()
    );
    // SAFETY: as above.
    let status =
        unsafe { wpbgi_scene_set_environment(cube.0, c("no-such-sky.exr").as_ptr(), 1.0, 0.0) };
    assert_ne!(status, WPBGI_OK);
    assert!(last_error().contains("no-such-sky.exr"), "{}", last_error());
    // SAFETY: NULL is refused.
    let status = unsafe { wpbgi_scene_set_environment(cube.0, null(), 1.0, 0.0) };
    assert_eq!(status, WPBGI_INVALID_ARGUMENT);
}

/// `wpbgi_relight` and `wpbgi_scene_edit`: a brighter light rescales the cache, which opens
/// for a scene given the same edit and is refused for the original; an edit of a reflectance
/// bakes again; edits that name nothing, no edits and a NULL list are refused with a message.
#[test]
fn relight_and_edited_scenes() {
    let dir = scratch("relight");
    let scene = Scene::load(&scene_path());
    let cache_path = dir.join("original.wpc");
    let settings = bake_settings(POINTS, BOUNCES);
    let cache = baked(&scene, &settings, &cache_path);
    let relight = |edits: &[&str], output: &std::path::Path| -> (i32, i32) {
        let texts: Vec<CString> = edits.iter().map(|e| c(e)).collect();
        let pointers: Vec<*const c_char> = texts.iter().map(|t| t.as_ptr()).collect();
        let mut rescaled = -1;
        // SAFETY: live handles, `pointers.len()` valid strings, a valid path, no callback.
        let status = unsafe {
            wpbgi_relight(
                scene.0,
                cache.0,
                pointers.as_ptr(),
                pointers.len(),
                path_c(output).as_ptr(),
                0,
                None,
                null_mut(),
                &mut rescaled,
            )
        };
        (status, rescaled)
    };
    let edited_scene = |edits: &[&str]| {
        let s = Scene::load(&scene_path());
        for e in edits {
            // SAFETY: a live handle used by this thread alone, a valid string.
            let status = unsafe { wpbgi_scene_edit(s.0, c(e).as_ptr()) };
            assert_eq!(status, WPBGI_OK, "{}", last_error());
        }
        s
    };
    for (edits, rescaled) in [
        (&["light.emission*=2"][..], 1),
        (&["white.reflectance=0.5", "light.emission*=2"][..], 0),
    ] {
        let output = dir.join(format!("relit-{rescaled}.wpc"));
        assert_eq!(
            relight(edits, &output),
            (WPBGI_OK, rescaled),
            "{}",
            last_error()
        );
        assert!(
            Cache::open(&edited_scene(edits), &output).is_ok(),
            "{edits:?}"
        );
        let refused = Cache::open(&scene, &output)
            .err()
            .expect("stale for the original");
        assert_eq!(refused.0, WPBGI_FAILED);
    }
    // SAFETY: a live handle, a valid string.
    let status = unsafe { wpbgi_scene_edit(scene.0, c("lamp.emission=1").as_ptr()) };
    assert_eq!(status, WPBGI_INVALID_ARGUMENT);
    assert!(last_error().contains("\"lamp\""), "{}", last_error());
    assert_eq!(
        relight(&[], &dir.join("none.wpc")).0,
        WPBGI_INVALID_ARGUMENT
    );
    assert!(last_error().contains("edit_count"), "{}", last_error());
    // SAFETY: NULL is refused.
    let status = unsafe {
        wpbgi_relight(
            scene.0,
            cache.0,
            null(),
            1,
            path_c(&dir.join("x.wpc")).as_ptr(),
            0,
            None,
            null_mut(),
            null_mut(),
        )
    };
    assert_eq!(status, WPBGI_INVALID_ARGUMENT);
    assert!(last_error().contains("edits"), "{}", last_error());
}
