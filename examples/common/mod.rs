//! What the benchmarks share: the reference scenes, a bake written to and read back from a
//! cache file, and the path tracer given a wall-clock budget.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};
use wpbgi::bake::store::write;
use wpbgi::bake::{bake, BakeSettings, Baked};
use wpbgi::cache::store::{bake_hash, BakedCache};
use wpbgi::reference::{render, RenderOutput, RenderSettings};
use wpbgi::render::{render_final, FinalOutput, FinalSettings};
use wpbgi::scene::camera::Camera;
use wpbgi::scene::Scene;

pub type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

/// Run `command` (named `what` in the error) and return its output, or its stderr as the
/// error when it fails.
pub fn run_ok(what: &str, command: &mut Command) -> Result<std::process::Output> {
    let run = command.output()?;
    if !run.status.success() {
        return Err(format!("{what} failed: {}", String::from_utf8_lossy(&run.stderr)).into());
    }
    Ok(run)
}

/// A file of tests/data/mitsuba.
pub fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/mitsuba")
        .join(name)
}

/// Bake `scene` into a temporary cache named after `tag` and open it, as a user's bake and
/// render would; also the seconds that took.
pub fn bake_cache(
    scene: &Scene,
    settings: &BakeSettings,
    tag: &str,
) -> Result<(Baked, BakedCache, f64)> {
    let start = Instant::now();
    let baked = bake(scene, settings, &|_, _| {})?;
    let path = std::env::temp_dir().join(format!("wpbgi-bench-{tag}.wpc"));
    let hash = bake_hash(scene, &settings.to_json());
    write(&path, hash, &baked, serde_json::json!({}))?;
    let seconds = start.elapsed().as_secs_f64();
    Ok((baked, BakedCache::read(&path, None)?, seconds))
}

/// The final render of `scene` from `cache` through `camera` with `settings`, and its seconds.
#[allow(dead_code)] // not every benchmark renders from a cache
pub fn timed_render(
    scene: &Scene,
    cache: &BakedCache,
    camera: &Camera,
    settings: &FinalSettings,
) -> Result<(FinalOutput, f64)> {
    let t = Instant::now();
    let out = render_final(scene, cache, camera, settings, &|_, _| {})?;
    Ok((out, t.elapsed().as_secs_f64()))
}

/// Our path tracer at `max_depth`, one sample per pixel per pass, for `seconds` of wall time.
pub fn path_tracer_for(
    scene: &Scene,
    camera: &Camera,
    max_depth: i32,
    seconds: f64,
) -> Result<RenderOutput> {
    let settings = RenderSettings {
        spp: 1,
        max_depth,
        time_limit: Some(Duration::from_secs_f64(seconds)),
        ..Default::default()
    };
    Ok(render(scene, camera, &settings, &|_| {})?)
}

/// The sample counts the Mitsuba anchor runs at.
pub const ANCHOR_SPP: [u32; 2] = [16, 256];

/// `scripts/anchor/mitsuba_oidn.py` on one scene: one JSON object per spp of `spps`.
pub fn mitsuba_anchor(
    python: &Path,
    scene: &Path,
    reference: &Path,
    spps: &[u32],
) -> Result<Vec<(u32, Value)>> {
    mitsuba_anchor_with(python, scene, reference, spps, MitsubaMode::DEFAULT)
}

/// How the anchor runs Mitsuba.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MitsubaMode {
    /// Its variant: `llvm_ad_rgb` (the JIT's lanes over paths, the anchor's default) or
    /// `scalar_rgb` (one path at a time, as our path tracer).
    pub variant: &'static str,
    /// Embree's robust intersections (its watertight triangle test, as our accel's;
    /// Mitsuba's default is off).
    pub robust: bool,
}

impl MitsubaMode {
    /// The anchor's Mitsuba: `llvm_ad_rgb`, Embree's default intersections.
    pub const DEFAULT: MitsubaMode = MitsubaMode {
        variant: "llvm_ad_rgb",
        robust: false,
    };
}

/// [`mitsuba_anchor`], with Mitsuba run as `mode` says.
pub fn mitsuba_anchor_with(
    python: &Path,
    scene: &Path,
    reference: &Path,
    spps: &[u32],
    mode: MitsubaMode,
) -> Result<Vec<(u32, Value)>> {
    anchor_lines(run_ok(
        "the Mitsuba anchor",
        Command::new(python)
            .env("EMBREE_ROBUST", if mode.robust { "1" } else { "0" })
            .env("MITSUBA_VARIANT", mode.variant)
            .arg(anchor_script())
            .arg(scene)
            .arg(reference)
            .arg("8")
            .args(spps.iter().map(|s| s.to_string())),
    )?)
}

/// A deep reference: Mitsuba's image at max_depth 64 and its per-sample variance over its
/// sample count (`scripts/anchor/mitsuba_ref.py`).
#[allow(dead_code)] // only the still benchmark holds images to deep references
pub struct DeepReference {
    pub image: PathBuf,
    pub variance: PathBuf,
    pub spp: u32,
}

/// [`mitsuba_anchor`] at max_depth 64 against a deep reference, whose own noise (its
/// variance over its samples) is taken out of every squared error.
#[allow(dead_code)] // only the still benchmark holds images to deep references
pub fn mitsuba_anchor_deep(
    python: &Path,
    scene: &Path,
    reference: &DeepReference,
    spps: &[u32],
) -> Result<Vec<(u32, Value)>> {
    anchor_lines(run_ok(
        "the Mitsuba anchor",
        Command::new(python)
            .env("REF_VAR", &reference.variance)
            .env("REF_SPP", reference.spp.to_string())
            .arg(anchor_script())
            .arg(scene)
            .arg(&reference.image)
            .arg("64")
            .args(spps.iter().map(|s| s.to_string())),
    )?)
}

fn anchor_script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/anchor/mitsuba_oidn.py")
}

/// The anchor's JSON lines, by sample count.
fn anchor_lines(run: std::process::Output) -> Result<Vec<(u32, Value)>> {
    Ok(String::from_utf8_lossy(&run.stdout)
        .lines()
        .filter_map(|l| serde_json::from_str::<Value>(l).ok())
        .filter_map(|v| Some((v["spp"].as_u64()? as u32, v)))
        .collect())
}
