//! The bake's stages on the five Cornell-class scenes (issue 19): seconds of direct light, of
//! the first bounce (which records the light transport) and of each later one (which replays
//! it), the transport's bytes per surfel, the peak memory, the cache's bytes per surfel, and
//! the relMSE at 256² of a default render from the cache against Mitsuba 3's max_depth 8
//! reference.
//!
//! Beside each run, our path tracer (max_depth 8) given the same wall time as bake + render,
//! and its relMSE. Beside each scene, from the same run, the bounces as they ran before the transport was
//! recorded: every bounce gathering again (`--transport-memory 0`, which the cache does not
//! notice: the bench checks that both caches are byte-identical), exactly 3 bounces each.
//!
//! `cargo run --release --example bench_bounces [-- SCENE[,SCENE…] [POINTS[,POINTS…]]]`
//! (default: all five scenes at 20 000 and 100 000 surfels, `--bounces auto`).

use std::time::Instant;
use wpbgi::bake::{bake, BakeSettings, Quality};
use wpbgi::bounce::BounceSettings;
use wpbgi::compare::memory;
use wpbgi::image::{error_against, read_exr};
use wpbgi::render::{render_final, FinalSettings};
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

fn main() -> common::Result<()> {
    let mut args = std::env::args().skip(1);
    let names: Vec<String> = args.next().map_or(SCENES.map(String::from).to_vec(), |a| {
        a.split(',').map(String::from).collect()
    });
    let points: Vec<usize> = match args.next() {
        Some(a) => a.split(',').map(|p| p.parse()).collect::<Result<_, _>>()?,
        None => vec![20_000, 100_000],
    };
    println!("threads: {}", rayon::current_num_threads());
    println!(
        "| scene | surfels | direct s | bounce 1 s | later bounces s (mean, max) | bounces | \
         later / first | stage / first | transport B/surfel | peak MB | cache B/surfel | \
         render s | relMSE | path tracer, same time: relMSE |"
    );
    println!("|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let mut before_after = Vec::new();
    for name in &names {
        let scene = Scene::load(&data(&format!("{name}.gltf")))?;
        let reference = read_exr(&data(&format!("{name}_d8_ref.exr"))).ok();
        let camera = scene.default_camera(256, 256)?;
        for &n in &points {
            let settings = BakeSettings {
                points: n,
                bounces: BounceSettings::auto(),
                ..BakeSettings::from_quality(Quality::Preview)
            };
            memory::reset_peak();
            let (baked, cache, bake_s) =
                common::bake_cache(&scene, &settings, &format!("{name}-{n}"))?;
            let peak = memory::peak().map_or("-".into(), |b| (b / 1_000_000).to_string());
            let stage = |s: &str| {
                baked
                    .timings
                    .iter()
                    .find(|(k, _)| *k == s)
                    .map_or(0.0, |(_, v)| *v)
            };
            let report = baked.bounces.clone().unwrap_or_default();
            let first = report.seconds.first().copied().unwrap_or(0.0);
            let later = &report.seconds[1.min(report.seconds.len())..];
            let mean_later = later.iter().sum::<f64>() / later.len().max(1) as f64;
            let max_later = later.iter().copied().fold(0.0, f64::max);
            let bounce_stage = report.seconds.iter().sum::<f64>();
            let cache_bytes = std::fs::metadata(&cache.cache.path)?.len();
            let t = Instant::now();
            let out = render_final(
                &scene,
                &cache,
                &camera,
                &FinalSettings::default(),
                &|_, _| {},
            )?;
            let render_s = t.elapsed().as_secs_f64();
            let rel_of = |image: &wpbgi::image::Image| {
                reference
                    .as_ref()
                    .and_then(|r| error_against(image, r))
                    .map_or("no reference".into(), |(_, rel)| format!("{rel:.3e}"))
            };
            let rel = rel_of(&out.beauty);
            let pt = common::path_tracer_for(&scene, &camera, 8, bake_s + render_s)?;
            let pt_rel = rel_of(&pt.mean);
            let surfels = baked.surfels.len() as f64;
            println!(
                "| {name} | {n} | {:.2} | {first:.2} | {mean_later:.3}, {max_later:.3} | {} | \
                 {:.3} | {:.2} | {:.0} | {peak} | {:.0} | {render_s:.1} | {rel} | {pt_rel} ({} spp) |",
                stage("direct light"),
                report.bounces,
                max_later / first.max(1e-9),
                bounce_stage / first.max(1e-9),
                report.transport.bytes as f64 / surfels,
                cache_bytes as f64 / surfels,
                pt.spp,
            );
            if n == points[0] {
                before_after.push((name.clone(), n, regather_ratio(&scene, &settings)?));
            }
        }
    }
    println!();
    println!("Every bounce gathering again (as before the transport) against recorded, 3 bounces:");
    println!(
        "| scene | surfels | bounces regathered s | bounces recorded s | speed-up | same cache |"
    );
    println!("|---|---:|---:|---:|---:|---|");
    for (name, n, (again, recorded, same)) in before_after {
        println!(
            "| {name} | {n} | {again:.1} | {recorded:.1} | {:.1}× | {same} |",
            again / recorded.max(1e-9)
        );
    }
    Ok(())
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
        let baked = bake(scene, &s, &|_, _| {})?;
        let path = std::env::temp_dir().join("wpbgi-bench-regather.wpc");
        let hash = wpbgi::bake::store::bake_hash(scene, &s.to_json());
        wpbgi::bake::store::write(&path, hash, &baked, serde_json::json!({}))?;
        let seconds = baked.bounces.map_or(0.0, |r| r.seconds.iter().sum());
        Ok((seconds, std::fs::read(&path)?))
    };
    let (again, a) = run(Some(0))?;
    let (recorded, b) = run(None)?;
    Ok((again, recorded, a == b))
}
