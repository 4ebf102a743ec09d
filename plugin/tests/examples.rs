//! The examples, run as a user runs them: the C example compiled with the system's C compiler
//! against `wpbgi.h` and the shared library, and the Python example through ctypes. Their
//! caches and images must equal the Rust API's byte for byte. (The USD pipeline example uses
//! the Python package: tests/python_package.rs.)

mod common;

use common::*;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The folder holding the shared library this test run built (`target/<profile>`, or its
/// `deps`).
fn library_dir() -> PathBuf {
    let name = format!(
        "{}wpbgi_plugin{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    );
    let exe = std::env::current_exe().expect("the test's path");
    let deps = exe.parent().expect("deps folder");
    let found = [deps, deps.parent().expect("profile folder")]
        .into_iter()
        .find(|d| d.join(&name).is_file())
        .unwrap_or_else(|| panic!("{name} was not built next to {}", exe.display()))
        .to_path_buf();
    found
}

fn library_path() -> PathBuf {
    library_dir().join(format!(
        "{}wpbgi_plugin{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    ))
}

fn plugin_dir() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

#[track_caller]
fn run(cmd: &mut Command) -> String {
    let out = cmd
        .output()
        .unwrap_or_else(|e| panic!("cannot run {cmd:?}: {e}"));
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{cmd:?} failed:\n{stderr}");
    String::from_utf8_lossy(&out.stdout).into_owned() + &stderr
}

/// The example's arguments: the scene, its outputs, and the shared small bake.
fn example_args(dir: &Path, name: &str) -> Vec<String> {
    vec![
        scene_path().display().to_string(),
        dir.join(format!("{name}.wpc")).display().to_string(),
        dir.join(format!("{name}.pfm")).display().to_string(),
        POINTS.to_string(),
        BOUNCES.to_string(),
        SIZE.to_string(),
    ]
}

/// Assert that `name`'s cache and image in `dir` are the Rust API's.
#[track_caller]
fn assert_same_as_rust(dir: &Path, name: &str, rust: &(Vec<u8>, Vec<f32>)) {
    let cache = std::fs::read(dir.join(format!("{name}.wpc"))).expect("the example's cache");
    assert!(
        cache == rust.0,
        "{name}: its cache differs from the Rust API's"
    );
    let (w, h, rgb) = read_pfm(&dir.join(format!("{name}.pfm")));
    assert_eq!((w, h), (SIZE, SIZE));
    assert!(
        same_bits(&rgb, &rust.1),
        "{name}: its image differs from the Rust API's"
    );
}

#[test]
fn c_and_python_examples_reproduce_the_rust_api() {
    let dir = scratch("examples");
    let rust = rust_api_result(POINTS, BOUNCES, SIZE);

    // C: compiled with warnings as errors against the checked-in header.
    let exe = dir.join("bake_and_render");
    let lib_dir = library_dir();
    run(
        Command::new(std::env::var("CC").unwrap_or_else(|_| "cc".into()))
            .args(["-std=c99", "-Wall", "-Wextra", "-Werror", "-I"])
            .arg(plugin_dir().join("include"))
            .arg(plugin_dir().join("examples/bake_and_render.c"))
            .arg("-L")
            .arg(&lib_dir)
            .arg("-lwpbgi_plugin")
            .arg(format!("-Wl,-rpath,{}", lib_dir.display()))
            .arg("-o")
            .arg(&exe),
    );
    // The library found above, not another copy on cargo's LD_LIBRARY_PATH (a `cargo build`
    // leaves an older one in the profile folder, which comes first there).
    let log = run(Command::new(&exe)
        .args(example_args(&dir, "c"))
        .env("LD_LIBRARY_PATH", &lib_dir));
    assert!(log.contains("progress reports"), "{log}");
    assert_same_as_rust(&dir, "c", &rust);
    // Its EXR, written by wpbgi_render_to_file, holds the same floats.
    let exr = wpbgi::image::read_exr(&dir.join("c.exr")).expect("the example's EXR");
    let floats: Vec<f32> = exr.pixels.iter().flat_map(|p| p.to_array()).collect();
    assert!(same_bits(&floats, &rust.1));

    // Python, through ctypes.
    let python = std::env::var("WPBGI_PYTHON").unwrap_or_else(|_| "python3".into());
    run(Command::new(&python)
        .arg(plugin_dir().join("python/example.py"))
        .args(example_args(&dir, "python"))
        .env("WPBGI_LIBRARY", library_path()));
    assert_same_as_rust(&dir, "python", &rust);

    // Python's errors: the status and the library's sentence; a callback that returns True
    // cancels, one that raises cancels and re-raises, and neither leaves a cache; a closed
    // handle is passed as NULL and refused.
    let check = r#"
import os, sys, wpbgi
scene_path, out = sys.argv[1], sys.argv[2]
try:
    wpbgi.Scene(out + "/missing.gltf")
    raise SystemExit("a missing scene loaded")
except wpbgi.Error as e:
    assert e.status == wpbgi.FAILED and "missing.gltf" in str(e), (e.status, str(e))
scene = wpbgi.Scene(scene_path)
try:
    wpbgi.bake(scene, out + "/cancelled.wpc", points=3000, progress=lambda stage, f: stage == "direct light")
    raise SystemExit("the bake was not cancelled")
except wpbgi.Cancelled as e:
    assert e.status == wpbgi.CANCELLED and str(e) == "the bake was cancelled", str(e)
class Stop(Exception):
    pass
def fail(stage, f):
    raise Stop(stage)
try:
    wpbgi.bake(scene, out + "/raised.wpc", points=3000, progress=fail)
    raise SystemExit("the exception was lost")
except Stop as e:
    assert str(e) == "surfels", str(e)
assert not os.path.exists(out + "/cancelled.wpc") and not os.path.exists(out + "/raised.wpc")
cache = wpbgi.Cache(out + "/python.wpc", scene)
cache.close()
try:
    wpbgi.render(scene, cache, 8, 8)
    raise SystemExit("a closed cache rendered")
except wpbgi.Error as e:
    assert e.status == wpbgi.INVALID_ARGUMENT and "cache is NULL" in str(e), str(e)
# A USD stage at a time code: its moving mesh changes the bake's hash between frames.
stage = os.path.join(os.path.dirname(scene_path), "..", "usd", "animated.usda")
first, last = wpbgi.Scene(stage, time_code=1), wpbgi.Scene(stage, time_code=10)
assert wpbgi.bake_hash(wpbgi.Scene(stage)) == wpbgi.bake_hash(first)
assert wpbgi.bake_hash(first) != wpbgi.bake_hash(last)
# An environment lights a scene without a light of its own, and enters the bake's hash.
cube = wpbgi.Scene(os.path.join(os.path.dirname(scene_path), "..", "usd", "cube-unlit.usda"))
cube.set_environment("0.5,1,2")
grey = wpbgi.bake_hash(cube)
cube.set_environment("1")
assert wpbgi.bake_hash(cube) != grey
# A brighter light rescales the cache; it opens for a scene given the same edit only.
original = wpbgi.Cache(out + "/python.wpc", scene)
assert wpbgi.relight(scene, original, ["light.emission*=2"], out + "/bright.wpc")
bright = wpbgi.Scene(scene_path)
bright.edit("light.emission*=2")
wpbgi.Cache(out + "/bright.wpc", bright).close()
try:
    wpbgi.Cache(out + "/bright.wpc", scene)
    raise SystemExit("the relit cache opened for the original scene")
except wpbgi.Error as e:
    assert "stale" in str(e), str(e)
try:
    bright.edit("lamp.emission=1")
    raise SystemExit("an edit that names nothing was accepted")
except wpbgi.Error as e:
    assert e.status == wpbgi.INVALID_ARGUMENT and "lamp" in str(e), str(e)
print("python errors ok")
"#;
    let log = run(Command::new(&python)
        .args(["-c", check])
        .arg(scene_path())
        .arg(&*dir)
        .env("PYTHONPATH", plugin_dir().join("python"))
        .env("WPBGI_LIBRARY", library_path()));
    assert!(log.contains("python errors ok"), "{log}");
}
