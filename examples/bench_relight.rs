//! Relighting against baking again (issue 25): for each edit kind on cbox-rough and
//! cbox-glossy, the seconds `bake::relight` takes from a cache of the unedited scene, beside a
//! fresh bake of the edited scene with the same settings (the default preset, automatic
//! bounces), their ratio, how the relight went (rescaled or baked again), and the relMSE
//! between the final renders (256², default settings) of the relit and the fresh caches. The
//! issue asks for a tenth of the bake's time at relMSE 1e-3.
//!
//! `cargo run --release --example bench_relight [-- SCENE_NAME ...]`

use std::sync::atomic::AtomicBool;
use std::time::Instant;
use wpbgi::bake::relight::{relight, Relighting};
use wpbgi::bake::BakeSettings;
use wpbgi::cache::store::BakedCache;
use wpbgi::image::error_against;
use wpbgi::render::FinalSettings;
use wpbgi::scene::edit::Edit;
use wpbgi::scene::Scene;

#[allow(dead_code)] // the benchmarks' shared helpers, of which this one uses three
mod common;

use common::{bake_cache, data, timed_render, Result};

/// The edits measured: each kind the issue names that the Cornell boxes have (they have no
/// punctual light, so `intensity` is measured on none).
const EDITS: &[(&str, &str)] = &[
    ("emission (grey)", "light.emission*=1.5"),
    ("emission (colour)", "light.emission*=1.25,1,0.75"),
    ("diffuse reflectance", "white.reflectance*=0.8"),
];

/// The glossy material's edits, by scene (its name differs).
fn glossy_edits(scene: &str) -> Vec<(&'static str, String)> {
    let metal = if scene == "cbox-glossy" {
        "gold-a0.05"
    } else {
        "gold-a0.2"
    };
    vec![
        (
            "conductor tint",
            format!("{metal}.specular_reflectance=0.9,0.6,0.3"),
        ),
        ("roughness", format!("{metal}.alpha*=1.5")),
    ]
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scenes: Vec<&str> = if args.is_empty() {
        vec!["cbox-rough", "cbox-glossy"]
    } else {
        args.iter().map(String::as_str).collect()
    };
    let settings = BakeSettings::default();
    let render = FinalSettings::default();
    println!(
        "{:<12} {:<20} {:>9} {:>9} {:>7} {:>10}  how",
        "scene", "edit", "bake s", "relight s", "ratio", "relMSE"
    );
    for name in scenes {
        let original = Scene::load(&data(&format!("{name}.gltf")))?;
        let (_, cache, _) = bake_cache(&original, &settings, &format!("relight-{name}"))?;
        let camera = original.camera(None, 256, 256)?;
        let mut edits: Vec<(&str, String)> =
            EDITS.iter().map(|(k, e)| (*k, e.to_string())).collect();
        edits.extend(glossy_edits(name));
        for (kind, text) in edits {
            let edit: Edit = text.parse()?;
            let output = std::env::temp_dir().join(format!("wpbgi-bench-relit-{name}.wpc"));
            let start = Instant::now();
            let relit = relight(
                &original,
                &cache,
                std::slice::from_ref(&edit),
                &output,
                &|_, _| {},
                &AtomicBool::new(false),
            )?;
            let relight_seconds = start.elapsed().as_secs_f64();
            let edited = original.edited(&[edit])?;
            let (_, fresh, bake_seconds) =
                bake_cache(&edited, &settings, &format!("relight-{name}-fresh"))?;
            let relit_cache = BakedCache::open_fresh(&edited, &output)?;
            let (a, _) = timed_render(&edited, &relit_cache, &camera, &render)?;
            let (b, _) = timed_render(&edited, &fresh, &camera, &render)?;
            let (_, rel) = error_against(&a.beauty, &b.beauty).ok_or("image sizes differ")?;
            let how = match relit.how {
                Relighting::Rescaled { .. } => "rescaled".to_string(),
                Relighting::Rebaked { why } => format!("baked again: {why}"),
            };
            println!(
                "{name:<12} {kind:<20} {bake_seconds:>9.2} {relight_seconds:>9.2} {:>7.3} {rel:>10.2e}  {how}",
                relight_seconds / bake_seconds
            );
        }
    }
    Ok(())
}
