//! The bake's stages on the five Cornell-class scenes (issue 19): seconds of the whole bake (at
//! 100 000 surfels, what `wpbgi bake` does by default), of direct light, of the first bounce
//! (which records the light transport) and of each later one (which replays it), the
//! transport's bytes per surfel, the peak memory (the process's high-water mark reset before
//! each bake, so it includes the heap earlier rows left behind), the cache's bytes per surfel,
//! and
//! the relMSE at 256² of a default render from the cache against Mitsuba 3's max_depth 8
//! reference; beside it, our path tracer (max_depth 8) given the same wall time.
//!
//! At the first surfel count, from the same run, the anchors:
//! - the bounces before the transport was recorded, 3 of them: every bounce gathering again
//!   (`--transport-memory 0`; the bench checks that the cache is byte-identical), and, with
//!   `WPBGI_PREVIOUS=/path/to/an/older/wpbgi`, that binary's own `bake --bounces 3`;
//! - with `WPBGI_ANCHOR_PYTHON` naming a Python with mitsuba, numpy and pyoidn
//!   (`scripts/anchor/README.md`): Mitsuba 3 at 16 and 256 spp, raw and denoised by OIDN,
//!   and the ratios of wpbgi's bake + render time and relMSE to Mitsuba + OIDN's.
//!
//! `cargo run --release --example bench_bounces [-- SCENE[,SCENE…] [POINTS[,POINTS…]]]`
//! (default: all five scenes at 20 000 and 100 000 surfels, `--bounces auto`).

use serde_json::Value;
use std::path::Path;
use std::process::Command;
use wpbgi::bake::bounce::BounceSettings;
use wpbgi::bake::{BakeSettings, Quality};
use wpbgi::compare::memory;
use wpbgi::image::{error_against, read_exr};
use wpbgi::render::FinalSettings;
use wpbgi::scene::Scene;

mod common;

use common::data;

const SCENES: [&str; 5] = [
    "cbox-diffuse",
    "cbox-rough",
    "cbox-glossy",
    "cbox-mirror",
    "caustic",
];

/// One scene's anchors, at the first surfel count.
struct Anchors {
    name: String,
    points: usize,
    /// wpbgi's default bake + render seconds and relMSE.
    ours: (f64, f64),
    /// Bounce seconds (3 bounces): gathering again, recorded, the previous binary's.
    regathered: f64,
    recorded: f64,
    previous: Option<f64>,
    same_cache: bool,
    /// Per spp of [`common::ANCHOR_SPP`]: Mitsuba's seconds and relMSE, raw and with OIDN.
    mitsuba: Vec<(u32, Value)>,
}

fn main() -> common::Result<()> {
    let mut args = std::env::args().skip(1);
    let names: Vec<String> = args.next().map_or(SCENES.map(String::from).to_vec(), |a| {
        a.split(',').map(String::from).collect()
    });
    let points: Vec<usize> = match args.next() {
        Some(a) => a.split(',').map(|p| p.parse()).collect::<Result<_, _>>()?,
        None => vec![20_000, 100_000],
    };
    let previous = std::env::var_os("WPBGI_PREVIOUS");
    let python = std::env::var_os("WPBGI_ANCHOR_PYTHON");
    println!("threads: {}", rayon::current_num_threads());
    println!(
        "| scene | surfels | bake s | direct s | bounce 1 s | later bounces s (mean, max) | bounces | \
         later / first | stage / first | transport B/surfel | peak MB | cache B/surfel | \
         render s | relMSE | path tracer, same time: relMSE |"
    );
    println!("|---|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let mut anchors = Vec::new();
    for name in &names {
        let scene_path = data(&format!("{name}.gltf"));
        let reference_path = data(&format!("{name}_d8_ref.exr"));
        let scene = Scene::load(&scene_path)?;
        let reference = read_exr(&reference_path).ok();
        let camera = scene.default_camera(256, 256)?;
        let rel_of = |image: &wpbgi::image::Image| {
            reference
                .as_ref()
                .and_then(|r| error_against(image, r))
                .map_or(f64::NAN, |(_, rel)| rel)
        };
        for &n in &points {
            let settings = BakeSettings {
                points: n,
                bounces: BounceSettings::auto(),
                ..BakeSettings::preset(Quality::Preview).direct_only()
            };
            memory::reset_peak();
            let (baked, cache, bake_s) =
                common::bake_cache(&scene, &settings, &format!("{name}-{n}"))?;
            let peak = memory::peak().map_or("-".into(), |b| (b / 1_000_000).to_string());
            let direct = baked
                .timings
                .iter()
                .find(|(k, _)| *k == "direct light")
                .map_or(0.0, |(_, v)| *v);
            let report = baked.bounces.clone().unwrap_or_default();
            let first = report.seconds.first().copied().unwrap_or(0.0);
            let later = &report.seconds[1.min(report.seconds.len())..];
            let mean_later = later.iter().sum::<f64>() / later.len().max(1) as f64;
            let max_later = later.iter().copied().fold(0.0, f64::max);
            let bounce_stage = report.seconds.iter().sum::<f64>() + report.final_seconds;
            let cache_bytes = std::fs::metadata(&cache.cache.path)?.len();
            let (out, render_s) =
                common::timed_render(&scene, &cache, &camera, &FinalSettings::default())?;
            let rel = rel_of(&out.beauty);
            let pt = common::path_tracer_for(&scene, &camera, 8, bake_s + render_s)?;
            let surfels = baked.surfels.len() as f64;
            println!(
                "| {name} | {n} | {bake_s:.1} | {direct:.2} | {first:.2} | {mean_later:.3}, {max_later:.3} | {} | \
                 {:.3} | {:.2} | {:.0} | {peak} | {:.0} | {render_s:.1} | {rel:.3e} | {:.3e} ({} spp) |",
                report.bounces,
                max_later / first.max(1e-9),
                bounce_stage / first.max(1e-9),
                report.transport.bytes as f64 / surfels,
                cache_bytes as f64 / surfels,
                rel_of(&pt.mean),
                pt.spp,
            );
            if n != points[0] {
                continue;
            }
            let (regathered, recorded, same_cache) = regather_ratio(&scene, &settings)?;
            let previous = previous
                .as_ref()
                .map(|bin| previous_bounces(Path::new(bin), &scene_path, n))
                .transpose()?;
            let mitsuba = python
                .as_ref()
                .map(|py| {
                    common::mitsuba_anchor(
                        Path::new(py),
                        &scene_path,
                        &reference_path,
                        &common::ANCHOR_SPP,
                    )
                })
                .transpose()?
                .unwrap_or_default();
            anchors.push(Anchors {
                name: name.clone(),
                points: n,
                ours: (bake_s + render_s, rel),
                regathered,
                recorded,
                previous,
                same_cache,
                mitsuba,
            });
        }
    }
    print_anchors(&anchors, previous.is_some(), python.is_some());
    Ok(())
}

fn print_anchors(anchors: &[Anchors], previous: bool, python: bool) {
    println!();
    println!("The bounces before and after the transport, 3 bounces, same run:");
    println!(
        "| scene | surfels | previous version s | gathering again s | recorded s | \
         previous / recorded | again / recorded | same cache |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---|");
    for a in anchors {
        let prev = a.previous.map_or("-".into(), |p| format!("{p:.1}"));
        let ratio = a
            .previous
            .map_or("-".into(), |p| format!("{:.1}×", p / a.recorded.max(1e-9)));
        println!(
            "| {} | {} | {prev} | {:.1} | {:.1} | {ratio} | {:.1}× | {} |",
            a.name,
            a.points,
            a.regathered,
            a.recorded,
            a.regathered / a.recorded.max(1e-9),
            a.same_cache
        );
    }
    if !previous {
        println!("(previous version not run: set WPBGI_PREVIOUS to an older wpbgi binary)");
    }
    println!();
    println!("Against Mitsuba 3 and Mitsuba + OIDN (max_depth 8, 256²), same run:");
    if !python {
        println!("(not run: set WPBGI_ANCHOR_PYTHON, see scripts/anchor/README.md)");
        return;
    }
    println!(
        "| scene | wpbgi bake + render s, relMSE | Mitsuba spp: s, relMSE | + OIDN: s, relMSE | \
         wpbgi time / OIDN's | wpbgi relMSE / OIDN's |"
    );
    println!("|---|---|---|---|---:|---:|");
    for a in anchors {
        for (spp, m) in &a.mitsuba {
            let f = |k: &str| m[k].as_f64().unwrap_or(f64::NAN);
            let rel = |k: &str| m[k][1].as_f64().unwrap_or(f64::NAN);
            println!(
                "| {} | {:.1}, {:.2e} | {spp}: {:.2}, {:.2e} | {:.2}, {:.2e} | {:.1} | {:.2} |",
                a.name,
                a.ours.0,
                a.ours.1,
                f("pt_s"),
                rel("pt"),
                f("oidn_total_s"),
                rel("oidn"),
                a.ours.0 / f("oidn_total_s"),
                a.ours.1 / rel("oidn"),
            );
        }
    }
}

/// The bounce stage's seconds with every bounce gathering again (a transport budget of 0)
/// and with the transport recorded, 3 bounces each, and whether their caches are equal.
fn regather_ratio(scene: &Scene, settings: &BakeSettings) -> common::Result<(f64, f64, bool)> {
    let run = |budget: Option<u64>| -> common::Result<(f64, Vec<u8>)> {
        let s = BakeSettings {
            bounces: BounceSettings {
                transport_budget: budget,
                ..BounceSettings::exactly(3)
            },
            ..settings.clone()
        };
        let (baked, cache, _) = common::bake_cache(scene, &s, "regather")?;
        let seconds = baked
            .bounces
            .map_or(0.0, |r| r.seconds.iter().sum::<f64>() + r.final_seconds);
        Ok((seconds, std::fs::read(&cache.cache.path)?))
    };
    let (again, a) = run(Some(0))?;
    let (recorded, b) = run(None)?;
    Ok((again, recorded, a == b))
}

/// The bounce seconds of an older wpbgi binary's `bake --bounces 3` at `points` surfels (from
/// its `--json` summary).
fn previous_bounces(bin: &Path, scene: &Path, points: usize) -> common::Result<f64> {
    let out = std::env::temp_dir().join("wpbgi-bench-previous.wpc");
    let run = common::run_ok(
        &bin.display().to_string(),
        Command::new(bin)
            .arg("bake")
            .arg(scene)
            .arg("-o")
            .arg(&out)
            .args(["--points", &points.to_string(), "--bounces", "3", "--json"]),
    )?;
    // The JSON lines are on stdout since `--json` covered every command, on stderr before.
    let (stdout, stderr) = (
        String::from_utf8_lossy(&run.stdout),
        String::from_utf8_lossy(&run.stderr),
    );
    let done = stdout
        .lines()
        .chain(stderr.lines())
        .filter_map(|l| serde_json::from_str::<Value>(l).ok())
        .find(|v| v["event"] == "done")
        .ok_or("no summary from the previous binary")?;
    let bounces = &done["stats"]["bounces"];
    let seconds = bounces["seconds"]
        .as_array()
        .ok_or("the previous binary reported no bounce times")?;
    // Older binaries added each bounce to the total within it, and report no final step.
    let last = bounces["final_seconds"].as_f64().unwrap_or(0.0);
    Ok(seconds.iter().filter_map(Value::as_f64).sum::<f64>() + last)
}
