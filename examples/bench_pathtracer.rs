//! The reference path tracer's speed beside Mitsuba 3's (issue 21): the Cornell scenes of
//! `tests/data/mitsuba` at 256², max_depth 8, the same samples per pixel, from the same run.
//! Ours: wall seconds of `reference::render` and samples per second (camera paths, all
//! threads). Mitsuba's: `llvm_ad_rgb`'s `path` integrator through
//! `scripts/anchor/mitsuba_oidn.py` (wall seconds after an untimed JIT warm-up of the same
//! count) when `WPBGI_ANCHOR_PYTHON` names a Python with mitsuba, numpy and pyoidn (see
//! `bench_bounces`); then the ratio of our samples per second to Mitsuba's. With
//! `WPBGI_PREVIOUS=/path/to/an/older/wpbgi`, that version's `wpbgi reference` at the same
//! settings (its own seconds, from its `--json`), and our time over its.
//!
//! `cargo run --release --example bench_pathtracer [-- SPP [ROUNDS]]` (default 256 spp, one
//! round). Mitsuba renders only that count (the anchor script's AOVs and denoiser run too,
//! outside the timing). With several rounds, each runs ours, the previous version and
//! Mitsuba one after the other (odd rounds in the reverse order), and each keeps its fastest:
//! on a shared machine a single run of either can be 10 % slow, and one in a fixed place 6 %.

use std::path::Path;
use std::process::Command;
use std::time::Instant;
use wpbgi::reference::{render, RenderSettings};
use wpbgi::scene::Scene;

#[allow(dead_code)] // the benchmarks' shared helpers, of which this one uses three
mod common;

const SIZE: u32 = 256;

fn main() -> common::Result<()> {
    let mut args = std::env::args().skip(1);
    let spp: u32 = match args.next() {
        Some(s) => s.parse()?,
        None => 256,
    };
    let rounds: u32 = match args.next() {
        Some(s) => s.parse::<u32>()?.max(1),
        None => 1,
    };
    let python = std::env::var_os("WPBGI_ANCHOR_PYTHON");
    let previous = std::env::var_os("WPBGI_PREVIOUS");
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba");
    println!(
        "{SIZE}², max_depth 8, {spp} spp, {} threads, best of {rounds} round(s) each",
        rayon::current_num_threads()
    );
    println!(
        "| scene | ours s | ours Msamples/s | previous s | ours / previous: time | Mitsuba s | \
         Mitsuba Msamples/s | ours / Mitsuba: samples/s |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|");
    let samples = f64::from(SIZE * SIZE) * f64::from(spp);
    for name in ["cbox-diffuse", "cbox-rough", "cbox-glossy", "cbox-mirror"] {
        let scene_path = dir.join(format!("{name}.gltf"));
        let scene = Scene::load(&scene_path)?;
        let camera = scene.default_camera(SIZE, SIZE)?;
        let settings = RenderSettings {
            spp,
            max_depth: 8,
            ..Default::default()
        };
        // Each round runs the three one after the other, so that the machine's drift falls on
        // all of them; each keeps its fastest round. Odd rounds run them in the reverse order:
        // here the same binary timed twice in a fixed order read 6 % apart by its place.
        let (mut ours, mut before, mut mitsuba) = (f64::INFINITY, f64::INFINITY, f64::INFINITY);
        for round in 0..rounds {
            let mut order = [Run::Ours, Run::Previous, Run::Mitsuba];
            if round % 2 == 1 {
                order.reverse();
            }
            for run in order {
                match run {
                    Run::Ours => {
                        let t = Instant::now();
                        render(&scene, &camera, &settings, &|_| {})?;
                        ours = ours.min(t.elapsed().as_secs_f64());
                    }
                    Run::Previous => {
                        if let Some(bin) = &previous {
                            let b = previous_seconds(Path::new(bin), &scene_path, name, spp)?;
                            before = before.min(b);
                        }
                    }
                    Run::Mitsuba => {
                        if let Some(py) = &python {
                            let m = common::mitsuba_anchor(
                                Path::new(py),
                                &scene_path,
                                &dir.join(format!("{name}_d8_ref.exr")),
                                &[spp],
                            )?
                            .into_iter()
                            .find(|(s, _)| *s == spp)
                            .and_then(|(_, v)| v["pt_s"].as_f64())
                            .ok_or("the Mitsuba anchor printed no time")?;
                            mitsuba = mitsuba.min(m);
                        }
                    }
                }
            }
        }
        let before = match previous {
            Some(_) => format!("{before:.2} | {:.2}", ours / before),
            None => "not run (`WPBGI_PREVIOUS`) |".to_string(),
        };
        let rate = |s: f64| samples / s / 1e6;
        match python {
            Some(_) => println!(
                "| {name} | {ours:.2} | {:.2} | {before} | {mitsuba:.2} | {:.2} | {:.2} |",
                rate(ours),
                rate(mitsuba),
                mitsuba / ours
            ),
            None => println!(
                "| {name} | {ours:.2} | {:.2} | {before} | not run (`WPBGI_ANCHOR_PYTHON`) | | |",
                rate(ours)
            ),
        }
    }
    Ok(())
}

/// The three timed in a round.
#[derive(Clone, Copy)]
enum Run {
    Ours,
    Previous,
    Mitsuba,
}

/// The previous version's own seconds for the same render (`wpbgi reference --json`).
fn previous_seconds(bin: &Path, scene: &Path, name: &str, spp: u32) -> common::Result<f64> {
    let out = std::env::temp_dir().join(format!("wpbgi-bench-pt-{name}.exr"));
    let run = common::run_ok(
        "the previous version's reference",
        Command::new(bin)
            .arg("-q")
            .arg("reference")
            .arg(scene)
            .arg("-o")
            .arg(&out)
            .args(["--size", &format!("{SIZE}x{SIZE}")])
            .args(["--spp", &spp.to_string(), "--max-depth", "8", "--json"]),
    )?;
    let json: serde_json::Value = serde_json::from_slice(&run.stdout)?;
    Ok(json["frames"][0]["seconds"]
        .as_f64()
        .ok_or("the previous version's --json has no frames[0].seconds")?)
}
