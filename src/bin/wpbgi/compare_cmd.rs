//! `wpbgi compare`: error against run time, the cache at several presets against the path
//! tracer's curve, raw and denoised; with `--frames`, the same over a shot.

use crate::bake_cmd::QualityArg;
use std::sync::LazyLock;

/// `--presets`' default, `CompareSettings::default()`'s, as the flag takes it (comma-separated).
static DEFAULT_PRESETS: LazyLock<String> = LazyLock::new(|| {
    let names: Vec<&str> = CompareSettings::default()
        .presets
        .iter()
        .map(|q| q.name())
        .collect();
    names.join(",")
});
use crate::{CameraArgs, StagedBar};
use anyhow::{anyhow, bail, Result};
use clap::Args;
use std::path::PathBuf;
use wpbgi::compare::shot;
use wpbgi::compare::{check_size, compare, CompareSettings, Reference};
use wpbgi::image::{read_exr, write_exr};
use wpbgi::scene::{Camera, Scene};

#[derive(Args)]
pub struct CompareArgs {
    /// The scene (.gltf, .glb, .usd, .usda, .usdc or .usdz).
    pub scene: PathBuf,
    /// Report folder: report.json, error_vs_time.svg and .png, summary.md (and reference.exr
    /// when the reference is rendered here); for a shot (--frames), report.json and
    /// summary.md.
    #[arg(short, long)]
    pub output: PathBuf,
    /// The ground truth (OpenEXR, at the render size). Without it, the path tracer renders one
    /// at --reference-spp and says how long it took.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Samples per pixel of a reference rendered here.
    #[arg(long, default_value_t = CompareSettings::default().reference_spp)]
    pub reference_spp: u32,
    /// Bake presets to compare (comma-separated); each is baked and rendered, and the path
    /// tracer runs as long as the longest of them.
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = DEFAULT_PRESETS.as_str()
    )]
    pub presets: Vec<QualityArg>,
    /// Indirect bounces of each bake, as for `wpbgi bake` (a number, or `auto`).
    #[arg(long, default_value_t = CompareSettings::default().bounces,
          value_parser = crate::bake_cmd::parse_bounces)]
    pub bounces: wpbgi::bake::bounce::BounceSettings,
    /// A shot instead of one frame: bake each preset once and render N frames (at least 2)
    /// along an orbit of the camera (--orbit), the path tracer, raw and denoised, rendering
    /// each frame in the cache's seconds per frame (bake included). The report gives every
    /// frame's error and each method's flicker (temporal MSE: the mean squared change of the
    /// error from frame to frame). Each frame's reference is path-traced at --reference-spp
    /// (written as reference.0001.exr, …) or read from --reference, whose name then needs
    /// $F4, $F or #### where the frame number (1 to N) goes.
    #[arg(long, value_name = "N")]
    pub frames: Option<u32>,
    /// With --frames: degrees the camera turns about its up axis over the shot, around the
    /// point of its view axis level with the scene's centre (0: a still camera).
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 30.0,
        allow_negative_numbers = true
    )]
    pub orbit: f32,
    /// Seed of the random streams.
    #[arg(long, default_value_t = CompareSettings::default().seed)]
    pub seed: u64,
    /// Also write the report (report.json's document) to standard output; a failure as
    /// {"error": ..., "exit": ...}.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub camera: CameraArgs,
}

pub fn compare_command(a: CompareArgs) -> Result<()> {
    let scene = crate::load_scene(&a.scene)?;
    crate::warn(&scene);
    scene.check_renderable()?;
    let camera = crate::pick_camera(&scene, &a.camera)?;
    if a.reference_spp == 0 {
        bail!("--reference-spp must be at least 1");
    }
    let settings = CompareSettings {
        presets: a.presets.iter().map(|q| q.quality()).collect(),
        reference_spp: a.reference_spp,
        bounces: a.bounces,
        seed: a.seed,
        ..Default::default()
    };
    if let Some(frames) = a.frames {
        return shot_command(&a, &scene, &camera, frames, &settings);
    }
    let reference = match &a.reference {
        Some(path) => {
            let image = read_exr(path)?;
            check_size(&image, camera.width, camera.height)
                .map_err(|m| anyhow!("{}: {m} (set --size)", path.display()))?;
            Reference {
                image,
                path: Some(path.clone()),
                spp: None,
                seconds: None,
            }
        }
        None => {
            let bar = crate::progress_bar("path tracing the reference");
            let r = Reference::render(&scene, &camera, a.reference_spp, a.seed, &|f| {
                bar.set_position((f * 1000.0) as u64)
            })?;
            bar.finish_and_clear();
            say!(
                "rendered the reference: {} spp in {:.1} s",
                r.spp.unwrap_or(0),
                r.seconds.unwrap_or(0.0)
            );
            std::fs::create_dir_all(&a.output)?;
            write_exr(&a.output.join("reference.exr"), &r.image)?;
            r
        }
    };
    let bar = StagedBar::new("comparing");
    let report = compare(&scene, &camera, reference, &settings, &|stage, f| {
        bar.update(stage, f)
    })?;
    bar.finish();
    report.write(&a.output)?;
    announce(&a, report.to_json(), report.summary_markdown());
    Ok(())
}

/// `compare --frames N`: the shot's references (read or rendered), then the shot.
fn shot_command(
    a: &CompareArgs,
    scene: &Scene,
    camera: &Camera,
    frames: u32,
    settings: &CompareSettings,
) -> Result<()> {
    let cameras = shot::cameras(scene, camera, frames, a.orbit)?;
    let references = match &a.reference {
        Some(pattern) => {
            let mut references = Vec::with_capacity(cameras.len());
            for frame in 1..=i64::from(frames) {
                let path = crate::frames::named(pattern, frame)?;
                let image = read_exr(&path)?;
                check_size(&image, camera.width, camera.height)
                    .map_err(|m| anyhow!("{}: {m} (set --size)", path.display()))?;
                references.push(Reference {
                    image,
                    path: Some(path),
                    spp: None,
                    seconds: None,
                });
            }
            references
        }
        None => {
            let bar = crate::progress_bar("path tracing the references");
            let n = cameras.len() as f32;
            let mut references = Vec::with_capacity(cameras.len());
            for (i, cam) in cameras.iter().enumerate() {
                // The same seed every frame, so that a still camera's references are identical.
                references.push(Reference::render(
                    scene,
                    cam,
                    a.reference_spp,
                    a.seed,
                    &|f| bar.set_position(((i as f32 + f) / n * 1000.0) as u64),
                )?);
            }
            bar.finish_and_clear();
            say!(
                "rendered {frames} references: {} spp in {:.1} s",
                a.reference_spp,
                references.iter().filter_map(|r| r.seconds).sum::<f64>()
            );
            std::fs::create_dir_all(&a.output)?;
            for (i, r) in references.iter().enumerate() {
                let name = format!("reference.{:04}.exr", i + 1);
                write_exr(&a.output.join(name), &r.image)?;
            }
            references
        }
    };
    let bar = StagedBar::new("comparing a shot");
    let report = shot::shot(
        scene,
        &cameras,
        &references,
        settings,
        a.orbit,
        &|stage, f| bar.update(stage, f),
    )?;
    bar.finish();
    report.write(&a.output)?;
    announce(a, report.to_json(), report.summary_markdown());
    Ok(())
}

/// Say what `compare` wrote: the report's JSON on standard output with --json, the summary
/// and the folder on standard error.
fn announce(a: &CompareArgs, json: serde_json::Value, summary: String) {
    if a.json {
        println!("{json}");
    }
    say!("{}", summary.trim_end());
    say!("wrote {}", a.output.display());
}
