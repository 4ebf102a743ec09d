//! `wpbgi compare`: error against run time, the cache at several presets against the path
//! tracer given the same time.

use crate::bake_cmd::QualityArg;
use crate::{CameraArgs, StagedBar};
use anyhow::{anyhow, bail, Result};
use clap::Args;
use std::path::PathBuf;
use wpbgi::compare::{check_size, compare, CompareSettings, Reference};
use wpbgi::image::{read_exr, write_exr};

#[derive(Args)]
pub struct CompareArgs {
    /// The scene (.gltf, .glb, .usd, .usda, .usdc or .usdz).
    pub scene: PathBuf,
    /// Report folder: report.json, error_vs_time.svg and .png, summary.md (and reference.exr
    /// when the reference is rendered here).
    #[arg(short, long)]
    pub output: PathBuf,
    /// The ground truth (OpenEXR, at the render size). Without it, the path tracer renders one
    /// at --reference-spp and says how long it took.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Samples per pixel of a reference rendered here.
    #[arg(long, default_value_t = 1024)]
    pub reference_spp: u32,
    /// Bake presets to compare (comma-separated); each is baked and rendered, and the path
    /// tracer is given the same wall time.
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "draft,preview,final"
    )]
    pub presets: Vec<QualityArg>,
    /// Indirect bounces of each bake, as for `wpbgi bake` (a number, or `auto`).
    #[arg(long, default_value = "auto", value_parser = crate::bake_cmd::parse_bounces)]
    pub bounces: wpbgi::bounce::BounceSettings,
    /// Seed of the random streams.
    #[arg(long, default_value_t = 0)]
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
    let settings = CompareSettings {
        presets: a.presets.iter().map(|q| q.quality()).collect(),
        reference_spp: a.reference_spp,
        bounces: a.bounces,
        seed: a.seed,
        ..Default::default()
    };
    let bar = StagedBar::new("comparing");
    let report = compare(&scene, &camera, reference, &settings, &|stage, f| {
        bar.update(stage, f)
    })?;
    bar.finish();
    report.write(&a.output)?;
    if a.json {
        println!("{}", report.to_json());
    }
    say!("{}", report.summary_markdown().trim_end());
    say!("wrote {}", a.output.display());
    Ok(())
}
