//! Relighting against baking again (issue 25): for each edit kind on cbox-rough and
//! cbox-glossy, the seconds `bake::relight` takes from a cache of the unedited scene, beside a
//! fresh bake of the edited scene with the same settings (the default preset, automatic
//! bounces), their ratio, from the cache alone and with the transport kept beside it (`wpbgi
//! bake --keep-transport`), how the relight went with it (rescaled, re-solved from the
//! transport, or baked again), and the relMSE
//! between the final renders (256², default settings) of the relit and the fresh caches. The
//! issue asks for a tenth of the bake's time at relMSE 1e-3.
//!
//! `cargo run --release --example bench_relight [-- SCENE_NAME ...]`

use std::sync::atomic::AtomicBool;
use std::time::Instant;
use wpbgi::bake::bounce::kept::beside;
use wpbgi::bake::bounce::TransportHandoff;
use wpbgi::bake::relight::{relight, Relighting};
use wpbgi::bake::{bake_with_transport, BakeSettings};
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
    for name in scenes {
        let original = Scene::load(&data(&format!("{name}.gltf")))?;
        let (path, cache, kept_seconds) = bake_keeping_transport(&original, &settings, name)?;
        let transport = beside(&path);
        let transport_bytes = std::fs::metadata(&transport)?.len();
        println!(
            "{name}: bake with --keep-transport {kept_seconds:.2} s, transport {} MB",
            transport_bytes / 1_000_000
        );
        println!(
            "{:<12} {:<20} {:>9} {:>9} {:>7} {:>9} {:>7} {:>10}  how (with the transport)",
            "scene", "edit", "bake s", "alone s", "ratio", "kept s", "ratio", "relMSE"
        );
        let camera = original.camera(None, 256, 256)?;
        let mut edits: Vec<(&str, String)> =
            EDITS.iter().map(|(k, e)| (*k, e.to_string())).collect();
        edits.extend(glossy_edits(name));
        for (kind, text) in edits {
            let edit: Edit = text.parse()?;
            let output = std::env::temp_dir().join(format!("wpbgi-bench-relit-{name}.wpc"));
            let relit = |keep: bool| -> Result<(Relighting, f64)> {
                // The cache alone (as before the transport was kept), then with it.
                let aside = transport.with_extension("aside");
                if !keep {
                    std::fs::rename(&transport, &aside)?;
                }
                let start = Instant::now();
                let relit = relight(
                    &original,
                    &cache,
                    std::slice::from_ref(&edit),
                    &output,
                    &|_, _| {},
                    &AtomicBool::new(false),
                );
                let seconds = start.elapsed().as_secs_f64();
                if !keep {
                    std::fs::rename(&aside, &transport)?;
                }
                Ok((relit?.how, seconds))
            };
            let (_, alone_seconds) = relit(false)?;
            let (how, kept_seconds) = relit(true)?;
            let edited = original.edited(&[edit])?;
            let (_, fresh, bake_seconds) =
                bake_cache(&edited, &settings, &format!("relight-{name}-fresh"))?;
            let relit_cache = BakedCache::open_fresh(&edited, &output)?;
            let (a, _) = timed_render(&edited, &relit_cache, &camera, &render)?;
            let (b, _) = timed_render(&edited, &fresh, &camera, &render)?;
            let (_, rel) = error_against(&a.beauty, &b.beauty).ok_or("image sizes differ")?;
            let how = match how {
                Relighting::Rescaled { .. } => "rescaled".to_string(),
                Relighting::Resolved { .. } => "re-solved from the kept transport".to_string(),
                Relighting::Rebaked { why } => format!("baked again: {why}"),
            };
            println!(
                "{name:<12} {kind:<20} {bake_seconds:>9.2} {alone_seconds:>9.2} {:>7.3} {kept_seconds:>9.2} {:>7.3} {rel:>10.2e}  {how}",
                alone_seconds / bake_seconds,
                kept_seconds / bake_seconds
            );
        }
    }
    Ok(())
}

/// Bake `scene` and write its cache with the transport beside it (`wpbgi bake
/// --keep-transport`): the cache's path, the cache, and the seconds of the whole.
fn bake_keeping_transport(
    scene: &Scene,
    settings: &BakeSettings,
    name: &str,
) -> Result<(std::path::PathBuf, BakedCache, f64)> {
    let start = Instant::now();
    let mut handoff = TransportHandoff {
        keep: true,
        ..TransportHandoff::default()
    };
    let baked = bake_with_transport(
        scene,
        settings,
        &|_, _| {},
        &AtomicBool::new(false),
        &mut handoff,
    )?;
    let path = std::env::temp_dir().join(format!("wpbgi-bench-relight-{name}.wpc"));
    wpbgi::bake::store::save(&path, scene, &baked)?;
    if let Some(kept) = handoff.kept {
        kept.write(&beside(&path))?;
    }
    let seconds = start.elapsed().as_secs_f64();
    Ok((path.clone(), BakedCache::read(&path, None)?, seconds))
}
