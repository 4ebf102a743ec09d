//! Relighting against baking again (issue 25): for each edit kind on cbox-rough and
//! cbox-glossy, the seconds `bake::relight` takes from a cache of the unedited scene, beside a
//! fresh bake of the edited scene with the same settings (the default preset, automatic
//! bounces), their ratio, from the cache alone and with the transport kept beside it (`wpbgi
//! bake --keep-transport`), how the relight went with it (rescaled, re-solved from the
//! transport, or baked again), and the relMSE
//! between the final renders (256², default settings) of the relit and the fresh caches. The
//! issue asks for a tenth of the bake's time at relMSE 1e-3.
//!
//! Beside them, from the same run: with `WPBGI_PREVIOUS=/path/to/an/older/wpbgi`, that
//! version's `wpbgi relight` of the same cache and transport, timed as a process beside this
//! version's `target/release/wpbgi relight` (both the command a user runs: the scene's load
//! included; the fastest of two runs each, alternated; the previous version relights a cache
//! and transport it baked itself, as its transport file may be of an older format), with the ratio; and with `WPBGI_ANCHOR_PYTHON` (see `bench_bounces`) what a user
//! would do instead of relighting: render the scene again with Mitsuba 3, raw and + OIDN
//! (`scripts/anchor/mitsuba_oidn.py` at 16, 64 and 256 spp: seconds and relMSE against
//! Mitsuba's reference), beside a re-solving relight plus the final render from its cache, and
//! that render's relMSE against the same reference, with ours over each as ratios. Mitsuba has references of the unedited
//! scenes only, so the anchor is taken on them: an edit changes neither Mitsuba's time a
//! sample nor, measurably, ours (the relit caches are the fresh bakes', byte for byte).
//!
//! `cargo run --release --example bench_relight [-- SCENE_NAME ...]`

use std::path::Path;
use std::process::Command;
use std::sync::atomic::AtomicBool;
use std::time::Instant;
use wpbgi::bake::bounce::kept::beside;
use wpbgi::bake::bounce::TransportHandoff;
use wpbgi::bake::relight::{relight, Relighting};
use wpbgi::bake::{bake_with_transport, BakeSettings};
use wpbgi::cache::store::BakedCache;
use wpbgi::image::{error_against, read_exr};
use wpbgi::render::FinalSettings;
use wpbgi::scene::edit::Edit;
use wpbgi::scene::Scene;

#[allow(dead_code)] // the benchmarks' shared helpers, of which this one uses five
mod common;

use common::{bake_cache, data, mitsuba_anchor, run_ok, timed_render, Result};

/// Runs of each version's `wpbgi relight` per edit, of which the fastest counts.
const CLI_ROUNDS: usize = 2;

/// The sample counts Mitsuba + OIDN renders each scene at, for the anchor line.
const ANCHOR_SPP: [u32; 3] = [16, 64, 256];

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
    let previous = std::env::var_os("WPBGI_PREVIOUS");
    let python = std::env::var_os("WPBGI_ANCHOR_PYTHON");
    let this_bin = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/release/wpbgi");
    for name in scenes {
        let original = Scene::load(&data(&format!("{name}.gltf")))?;
        let (path, cache, kept_seconds) = bake_keeping_transport(&original, &settings, name)?;
        // The previous version relights a cache and transport of its own baking: its
        // transport file may be of another format (the caches are the same bytes).
        let previous_path = match &previous {
            Some(bin) => Some(previous_bake(Path::new(bin), name)?),
            None => None,
        };
        let transport = beside(&path);
        let transport_bytes = std::fs::metadata(&transport)?.len();
        println!(
            "{name}: bake with --keep-transport {kept_seconds:.2} s, transport {} MB",
            transport_bytes / 1_000_000
        );
        println!(
            "{:<12} {:<20} {:>9} {:>9} {:>7} {:>9} {:>7} {:>10} {:>9} {:>10} {:>7}  how (with the transport)",
            "scene",
            "edit",
            "bake s",
            "alone s",
            "ratio",
            "kept s",
            "ratio",
            "relMSE",
            "CLI s",
            "prev. s",
            "ratio"
        );
        // The re-solving relights' seconds, for the anchor line.
        let mut resolved_seconds = Vec::new();
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
                Relighting::Resolved { .. } => {
                    resolved_seconds.push(kept_seconds);
                    "re-solved from the kept transport".to_string()
                }
                Relighting::Rebaked { why } => format!("baked again: {why}"),
            };
            // The command a user runs, this version's and the previous one's, the fastest of
            // [`CLI_ROUNDS`] each, alternated (the first of a pair reads the transport less
            // warm from the page cache).
            let (this_cli, previous_cli) = match &previous {
                Some(bin) => {
                    let (mut this, mut before) = (f64::INFINITY, Some(f64::INFINITY));
                    for round in 0..CLI_ROUNDS {
                        for which in [round % 2, 1 - round % 2] {
                            if which == 0 {
                                this = this.min(cli_relight(&this_bin, name, &path, &text)?);
                            } else if let (Some(b), Some(p)) = (before, &previous_path) {
                                before = match cli_relight(Path::new(bin), name, p, &text) {
                                    Ok(s) => Some(b.min(s)),
                                    Err(e) => {
                                        eprintln!("the previous version's relight failed: {e}");
                                        None
                                    }
                                };
                            }
                        }
                    }
                    (format!("{this:.2}"), before)
                }
                None => ("-".to_string(), None),
            };
            let (previous_shown, ratio) = match (previous_cli, this_cli.parse::<f64>()) {
                (Some(p), Ok(t)) => (format!("{p:.2}"), format!("{:.3}", t / p)),
                _ if previous.is_some() => ("failed".to_string(), "-".to_string()),
                _ => ("not run".to_string(), "-".to_string()),
            };
            println!(
                "{name:<12} {kind:<20} {bake_seconds:>9.2} {alone_seconds:>9.2} {:>7.3} {kept_seconds:>9.2} {:>7.3} {rel:>10.2e} {this_cli:>9} {previous_shown:>10} {ratio:>7}  {how}",
                alone_seconds / bake_seconds,
                kept_seconds / bake_seconds
            );
        }
        anchor_line(
            name,
            &original,
            &cache,
            &camera,
            &render,
            &resolved_seconds,
            &python,
        )?;
    }
    Ok(())
}

/// The anchor on the unedited scene `name`: the median re-solving relight (`resolved`
/// seconds) plus the final render from `cache`, and that render's relMSE against Mitsuba's
/// reference, beside Mitsuba + OIDN's seconds and relMSE at [`ANCHOR_SPP`] (when `python`
/// names an anchor Python).
fn anchor_line(
    name: &str,
    scene: &Scene,
    cache: &BakedCache,
    camera: &wpbgi::scene::camera::Camera,
    render: &FinalSettings,
    resolved: &[f64],
    python: &Option<std::ffi::OsString>,
) -> Result<()> {
    let reference_path = data(&format!("{name}_d8_ref.exr"));
    let reference = read_exr(&reference_path)?;
    let (ours, render_seconds) = timed_render(scene, cache, camera, render)?;
    let (_, rel) = error_against(&ours.beauty, &reference).ok_or("image sizes differ")?;
    let mut sorted = resolved.to_vec();
    sorted.sort_by(f64::total_cmp);
    let relight = sorted.get(sorted.len() / 2).copied();
    print!(
        "{name} against Mitsuba's reference (max_depth 8): ours relight {} + render {render_seconds:.2} s = {}, relMSE {rel:.2e}",
        relight.map_or("-".to_string(), |s| format!("{s:.2}")),
        relight.map_or("-".to_string(), |s| format!("{:.2} s", s + render_seconds)),
    );
    match python {
        Some(py) => {
            let runs = mitsuba_anchor(
                Path::new(py),
                &data(&format!("{name}.gltf")),
                &reference_path,
                &ANCHOR_SPP,
            )?;
            // Each Mitsuba figure with ours over it: time (relight + render) and relMSE.
            let ours = relight.map(|s| s + render_seconds);
            let against = |s: f64, r: f64| match ours {
                Some(t) => format!(
                    " (ours / it: {:.2}× the time, {:.2}× the relMSE)",
                    t / s,
                    rel / r
                ),
                None => String::new(),
            };
            for (spp, v) in runs {
                let field = |k: &str, i: Option<usize>| match i {
                    Some(i) => v[k][i].as_f64(),
                    None => v[k].as_f64(),
                };
                if let (Some(s), Some(r)) = (field("pt_s", None), field("pt", Some(1))) {
                    print!(
                        "; Mitsuba {spp} spp {s:.2} s, relMSE {r:.2e}{}",
                        against(s, r)
                    );
                }
                if let (Some(s), Some(r)) = (field("oidn_total_s", None), field("oidn", Some(1))) {
                    print!(
                        "; Mitsuba + OIDN {spp} spp {s:.2} s, relMSE {r:.2e}{}",
                        against(s, r)
                    );
                }
            }
            println!();
        }
        None => println!("; Mitsuba + OIDN not run (`WPBGI_ANCHOR_PYTHON`)"),
    }
    Ok(())
}

/// `wpbgi relight` of binary `bin` on cache `cache` of scene `name` with the edit `edit`, as
/// a user runs it: the seconds the process took.
fn cli_relight(bin: &Path, name: &str, cache: &Path, edit: &str) -> Result<f64> {
    let out = std::env::temp_dir().join(format!("wpbgi-bench-cli-relit-{name}.wpc"));
    let start = Instant::now();
    run_ok(
        &bin.display().to_string(),
        Command::new(bin)
            .arg("relight")
            .arg(cache)
            .arg("--scene")
            .arg(data(&format!("{name}.gltf")))
            .arg("-o")
            .arg(&out)
            .arg("--set")
            .arg(edit),
    )?;
    Ok(start.elapsed().as_secs_f64())
}

/// The previous version's `wpbgi bake --keep-transport` of scene `name`: its cache's path.
fn previous_bake(bin: &Path, name: &str) -> Result<std::path::PathBuf> {
    let out = std::env::temp_dir().join(format!("wpbgi-bench-relight-{name}-previous.wpc"));
    run_ok(
        &bin.display().to_string(),
        Command::new(bin)
            .arg("bake")
            .arg(data(&format!("{name}.gltf")))
            .arg("-o")
            .arg(&out)
            .arg("--keep-transport")
            .arg("-q"),
    )?;
    Ok(out)
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
