//! `wpbgi relight`: a cache for a scene whose materials and lights were edited after the bake
//! (the run's global `--set` edits, which every other command applies to the scene it loads).

use anyhow::Result;
use clap::Args;
use serde_json::json;
use std::path::PathBuf;
use wpbgi::bake::relight::{relight, Relighting};
use wpbgi::cache::store::BakedCache;

#[derive(Args)]
pub struct RelightArgs {
    /// The cache, a fresh bake of --scene.
    cache: PathBuf,
    /// The scene the cache was baked from, before the edits.
    #[arg(long)]
    scene: PathBuf,
    /// The relit cache to write (.wpc), atomically.
    #[arg(short, long)]
    output: PathBuf,
    /// Print the result as one JSON document on standard output (a failure as
    /// {"error": ..., "exit": ...}).
    #[arg(long)]
    pub(crate) json: bool,
}

pub fn relight_command(a: RelightArgs) -> Result<()> {
    let edits = crate::edits();
    if edits.is_empty() {
        anyhow::bail!("relight needs at least one --set EDIT (e.g. --set 'light.emission*=2')");
    }
    let scene = crate::load_unedited(&a.scene)?;
    crate::warn(&scene);
    let cache = BakedCache::read(&a.cache, None)?;
    let bar = (!a.json).then(|| crate::StagedBar::new("re-baking"));
    let progress = |stage: &str, f: f32| {
        if let Some(b) = &bar {
            b.update(stage, f);
        }
    };
    crate::interrupt::guard_outputs([
        a.output.clone(),
        wpbgi::bake::bounce::kept::beside(&a.output),
    ]);
    let relit = relight(
        &scene,
        &cache,
        edits,
        &a.output,
        &progress,
        crate::interrupt::flag(),
    )?;
    bar.as_ref().map(crate::StagedBar::finish);
    let (how, detail) = match &relit.how {
        Relighting::Rescaled { factor } => ("rescaled", json!({"factor": factor.to_array()})),
        Relighting::Resolved {
            why,
            kept_direct,
            kept_irradiance,
            kept_operators,
        } => (
            "resolved",
            json!({
                "why": why,
                "kept_direct_surfels": kept_direct.0,
                "kept_irradiance_surfels": kept_irradiance,
                "surfels": kept_direct.1,
                "kept_operators": kept_operators.0,
                "operators": kept_operators.1,
            }),
        ),
        Relighting::Rebaked { why } => ("rebaked", json!({"why": why})),
    };
    if a.json {
        println!(
            "{}",
            json!({
                "output": a.output,
                "how": how,
                "detail": detail,
                "seconds": relit.seconds,
                "stage_seconds": crate::stage_seconds_json(&relit.timings),
                "bounces": relit.bounces.as_ref().map(crate::bounces_json),
            })
        );
    } else {
        say!(
            "relit {} in {:.2} s: {}",
            a.output.display(),
            relit.seconds,
            relit.how
        );
        crate::say_stages(&relit.timings);
        if let Some(r) = &relit.bounces {
            crate::say_bounces(r);
        }
    }
    Ok(())
}
