//! The Python package (`python/`, pyo3 + maturin) as a user gets it: `pip install ./python` in a
//! fresh virtual environment (scripts/test.sh does that and names its interpreter in
//! WPBGI_WHEEL_PYTHON), then `import wpbgi` bakes and renders the bundled scene to a numpy
//! array. The cache is byte for byte the one `wpbgi bake` writes with the same settings, and
//! the array is bit for bit the EXR `wpbgi render` writes from it. The USD pipeline example
//! (python/examples/usd_pipeline.py) runs on the same installed package with Pixar's usd-core.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

const SCRIPT: &str = r#"
import sys, wpbgi, numpy
scene_path, cache_path, out_path = sys.argv[1:4]
scene = wpbgi.Scene(scene_path)
stages = []
report = wpbgi.bake(scene, cache_path, quality="draft", points=3000, bounces=2,
                    progress=lambda stage, f: stages.append(stage))
assert report["surfels"] == 3000 and report["bounces"] == 2, report
assert "surfels" in stages and "bounces" in stages, stages
cache = wpbgi.Cache(scene, cache_path)
assert cache.hash == report["hash"] == wpbgi.bake_hash(scene, quality="draft", points=3000, bounces=2)
image = wpbgi.render(scene, cache, 48, 32, light_samples=8)
assert image.shape == (32, 48, 3) and image.dtype == numpy.float32, (image.shape, image.dtype)
image.astype("<f4").tofile(out_path)
# Relighting: a warmer light rescales the cache, fresh for the edited scene only.
warm = ["light.emission*=1.25,1,0.75"]
relit = wpbgi.relight(scene, cache_path, cache_path + ".warm", warm)
assert relit["how"] == "rescaled" and relit["factor"] == [1.25, 1.0, 0.75], relit
wpbgi.Cache(scene.edited(warm), cache_path + ".warm")
try:
    wpbgi.Cache(scene, cache_path + ".warm")
    raise SystemExit("the relit cache was not refused for the original scene")
except wpbgi.Error as e:
    assert "stale" in str(e), e
# With the transport kept beside the cache, a reflectance edit is re-solved from it.
wpbgi.bake(scene, cache_path + ".kept", quality="draft", points=3000, bounces=2,
           keep_transport=True)
darker = ["white.reflectance*=0.8"]
relit = wpbgi.relight(scene, cache_path + ".kept", cache_path + ".darker", darker)
assert relit["how"] == "resolved", relit
wpbgi.Cache(scene.edited(darker), cache_path + ".darker")
try:
    scene.edited(["lamp.emission=1"])
    raise SystemExit("an edit that names nothing was not refused")
except wpbgi.Error as e:
    assert "lamp" in str(e), e
# A setting out of range is refused, naming it; a callback returning True cancels.
try:
    wpbgi.render(scene, cache, 8, 8, max_depth=0)
    raise SystemExit("max_depth=0 was not refused")
except wpbgi.Error as e:
    assert "max_depth" in str(e), e
try:
    wpbgi.bake(scene, cache_path + ".cancelled", quality="draft", points=3000, progress=lambda s, f: True)
    raise SystemExit("the bake was not cancelled")
except wpbgi.Cancelled:
    pass
print("ok")
"#;

fn wpbgi(args: &[&str]) {
    let out = Command::new(env!("CARGO_BIN_EXE_wpbgi"))
        .args(args)
        .output()
        .expect("runs");
    assert!(
        out.status.success(),
        "wpbgi {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The Python of the fresh virtual environment the package was installed into, if any.
fn wheel_python() -> Option<PathBuf> {
    let python = std::env::var_os("WPBGI_WHEEL_PYTHON").map(PathBuf::from);
    if python.is_none() {
        eprintln!(
            "skipped: WPBGI_WHEEL_PYTHON is not set (scripts/test.sh sets it after pip install \
             ./python in a fresh virtual environment; without network it cannot)"
        );
    }
    python
}

#[test]
fn pip_installed_package_bakes_and_renders_what_the_cli_does() {
    let Some(python) = wheel_python() else {
        return;
    };
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cbox-rough.gltf");
    let dir = common::Scratch::new("python");
    let (py_cache, py_image) = (dir.join("python.wpc"), dir.join("python.f32"));
    let out = Command::new(&python)
        .args(["-c", SCRIPT])
        .arg(&scene)
        .arg(&py_cache)
        .arg(&py_image)
        // Not the source tree's python/wpbgi: the installed package.
        .current_dir(&dir)
        .output()
        .expect("runs python");
    assert!(
        out.status.success() && String::from_utf8_lossy(&out.stdout).trim() == "ok",
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );

    let s = |p: &Path| p.to_str().expect("utf-8 path").to_string();
    let cli_cache = dir.join("cli.wpc");
    let cli_image = dir.join("cli.exr");
    wpbgi(&[
        "bake",
        &s(&scene),
        "-o",
        &s(&cli_cache),
        "--quality",
        "draft",
        "--points",
        "3000",
        "--bounces",
        "2",
    ]);
    assert!(
        std::fs::read(&py_cache).expect("python's cache")
            == std::fs::read(&cli_cache).expect("the CLI's cache"),
        "the caches differ"
    );
    wpbgi(&[
        "render",
        &s(&scene),
        "--cache",
        &s(&cli_cache),
        "-o",
        &s(&cli_image),
        "--size",
        "48x32",
        "--light-samples",
        "8",
    ]);
    let exr = wpbgi::image::read_exr(&cli_image).expect("the CLI's EXR");
    let from_cli: Vec<u8> = exr
        .pixels
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    let from_python = std::fs::read(&py_image).expect("python's array");
    assert_eq!(from_python.len(), 48 * 32 * 3 * 4);
    assert!(from_python == from_cli, "the images differ");
}

/// The example's JSON line for `stage`.
fn pipeline(python: &Path, stage: &Path) -> serde_json::Value {
    let out = Command::new(python)
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("python/examples/usd_pipeline.py"))
        .arg(stage)
        .args(["--quality", "draft", "--points", "1500", "--bounces", "0"])
        .output()
        .expect("run usd_pipeline.py");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "usd_pipeline.py failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(stdout.trim()).unwrap_or_else(|e| panic!("{e}: {stdout}"))
}

fn hash_of(cache: &Path) -> String {
    let c = wpbgi::Cache::read(cache, None).expect("a valid cache");
    wpbgi::cache::hash_hex(c.cache.hash)
}

/// python/examples/usd_pipeline.py records the cache and its hash in the stage's root layer,
/// re-uses it while the stage and settings are unchanged, and bakes again when a material
/// changes or the cache goes missing.
#[test]
fn usd_pipeline_records_the_cache_and_reuses_it_while_it_is_good() {
    let Some(python) = wheel_python() else {
        return;
    };
    let has_usd = Command::new(&python)
        .args(["-c", "import pxr.Sdf"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_usd {
        eprintln!(
            "skipped: usd-core is not installed beside the package (scripts/test.sh installs it)"
        );
        return;
    }
    let dir = common::Scratch::new("usd-pipeline");
    let stage = dir.join("cbox.usda");
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/usd/cbox-diffuse.usda");
    std::fs::copy(&source, &stage).expect("copy the stage");

    // First run: nothing recorded, so it bakes and records the cache next to the stage.
    let first = pipeline(&python, &stage);
    assert_eq!(first["baked"], true, "{first}");
    assert_eq!(first["reason"], "no record");
    let cache = PathBuf::from(first["cache"].as_str().expect("cache path"));
    assert_eq!(cache, dir.join("cbox.wpc"));
    let hash = first["hash"].as_str().expect("hash").to_string();
    assert_eq!(hash_of(&cache), hash, "the recorded hash is the cache's");
    let text = std::fs::read_to_string(&stage).expect("the stage");
    assert!(
        text.contains("customLayerData") && text.contains(&hash) && text.contains("cbox.wpc"),
        "the record is in the root layer:\n{text}"
    );

    // Second run: the stage and settings are unchanged, so the cache is re-used untouched.
    let modified = std::fs::metadata(&cache)
        .and_then(|m| m.modified())
        .expect("mtime");
    let second = pipeline(&python, &stage);
    assert_eq!(second["baked"], false, "{second}");
    assert_eq!(second["hash"], hash.as_str());
    assert_eq!(
        std::fs::metadata(&cache).and_then(|m| m.modified()).ok(),
        Some(modified)
    );

    // A changed material: baked again, under a new hash.
    let text = std::fs::read_to_string(&stage).expect("the stage");
    let changed = text.replacen("0.885809", "0.5", 1);
    assert_ne!(
        changed, text,
        "the fixture has the colour this test changes"
    );
    std::fs::write(&stage, changed).expect("write the stage");
    let third = pipeline(&python, &stage);
    assert_eq!(third["baked"], true, "{third}");
    assert_eq!(third["reason"], "the stage or the settings changed");
    assert_ne!(third["hash"], hash.as_str());
    assert_eq!(hash_of(&cache), third["hash"].as_str().expect("hash"));

    // The recorded cache deleted: baked again, under the same hash.
    std::fs::remove_file(&cache).expect("remove the cache");
    let fourth = pipeline(&python, &stage);
    assert_eq!(fourth["baked"], true, "{fourth}");
    assert_eq!(fourth["reason"], "the recorded cache is missing or stale");
    assert_eq!(fourth["hash"], third["hash"]);
}
