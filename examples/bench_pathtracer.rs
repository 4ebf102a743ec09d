//! The reference path tracer's speed beside Mitsuba 3's (issue 21): the Cornell scenes of
//! `tests/data/mitsuba` at 256², max_depth 8, the same samples per pixel, from the same run.
//! Ours: wall seconds of `reference::render` and samples per second (camera paths, all
//! threads). Mitsuba's: `llvm_ad_rgb`'s `path` integrator through
//! `scripts/anchor/mitsuba_oidn.py` (wall seconds after an untimed JIT warm-up of the same
//! count) when `WPBGI_ANCHOR_PYTHON` names a Python with mitsuba, numpy and pyoidn (see
//! `bench_bounces`); then the ratio of our samples per second to Mitsuba's, and the same for
//! Mitsuba with Embree's robust intersections (`embree_use_robust_intersections`, off by
//! default: Embree's watertight triangle test and rounding-safe box test, the kind of query
//! ours always is, so the like-for-like figure), and for Mitsuba's `scalar_rgb` variant (one
//! path at a time, as ours, with Embree's default intersections): beside `llvm_ad_rgb` it
//! says how much of the gap is the width of Mitsuba's shading and how much the code of one
//! path. Last, what a user of Mitsuba pays for the same count denoised: `llvm_ad_rgb`'s
//! render, the albedo and normal guides (16 spp) and Intel Open Image Denoise together (the
//! anchor script's `oidn_total_s`), and our time over it (ours undenoised: the error each
//! reaches is `compare`'s and `bench_render`'s business, not this table's). With `WPBGI_PREVIOUS=/path/to/an/older/wpbgi`, that version's `wpbgi reference` at
//! the same settings (its own seconds, from its `--json`), and our time over its.
//!
//! `cargo run --release --example bench_pathtracer [-- SPP [ROUNDS]]` (default 256 spp, one
//! round). Mitsuba renders only that count (the anchor script's AOVs and denoiser run too,
//! outside its render's timing, and are the Mitsuba + OIDN column's). With several rounds, each runs ours, the previous version and
//! Mitsuba one after the other (odd rounds in the reverse order), and each keeps its fastest:
//! on a shared machine a single run of either can be 10 % slow, and one in a fixed place 6 %.
//!
//! Then the ray queries alone, on each scene's triangles: [`RAYS`] rays from uniform points of
//! the scene's bounds (2 % in from each side) in uniform directions, closest hits, and
//! occlusion segments from the same points to other uniform points; our `Accel` on all threads
//! beside Mitsuba's (Embree's) `ray_intersect_preliminary` and `ray_test` on the same rays
//! (`scripts/anchor/mitsuba_rays.py`, its arrays made before the timing), by default and with
//! robust intersections, fastest of `ROUNDS` (at least three), with every side's hit counts as
//! a check that they answer the same queries.
//! A path's time is mostly these queries and its shading: the two tables together say which
//! of them holds the gap.

use glam::Vec3;
use rayon::prelude::*;
use std::path::Path;
use std::process::Command;
use std::time::Instant;
use wpbgi::accel::Accel;
use wpbgi::geometry::warp::square_to_uniform_sphere;
use wpbgi::reference::{render, RenderSettings};
use wpbgi::sampler::Sampler;
use wpbgi::scene::Scene;

#[allow(dead_code)] // the benchmarks' shared helpers, of which this one uses a few
mod common;

use common::MitsubaMode;

const SIZE: u32 = 256;

/// Rays per scene in the ray-query table.
const RAYS: usize = 1 << 22;

/// The scenes, in the order both tables list them.
const SCENES: [&str; 4] = ["cbox-diffuse", "cbox-rough", "cbox-glossy", "cbox-mirror"];

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
         Mitsuba Msamples/s | ours / Mitsuba: samples/s | Mitsuba robust Msamples/s | \
         ours / Mitsuba robust | Mitsuba scalar Msamples/s | ours / Mitsuba scalar | \
         Mitsuba + OIDN s | ours / Mitsuba + OIDN: time |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let samples = f64::from(SIZE * SIZE) * f64::from(spp);
    for name in SCENES {
        let scene_path = dir.join(format!("{name}.gltf"));
        let scene = Scene::load(&scene_path)?;
        let camera = scene.default_camera(SIZE, SIZE)?;
        let settings = RenderSettings {
            spp,
            max_depth: 8,
            ..Default::default()
        };
        // Each round runs the five one after the other, so that the machine's drift falls on
        // all of them; each keeps its fastest round. Odd rounds run them in the reverse order:
        // here the same binary timed twice in a fixed order read 6 % apart by its place.
        let (mut ours, mut before) = (f64::INFINITY, f64::INFINITY);
        // Mitsuba's fastest seconds in each mode of `MITSUBA_MODES`, and its default mode's
        // image denoised by OIDN (render, guide AOVs and denoiser together).
        let mut mitsuba = [f64::INFINITY; MITSUBA_MODES.len()];
        let mut denoised = f64::INFINITY;
        for round in 0..rounds {
            let mut order = [
                Run::Ours,
                Run::Previous,
                Run::Mitsuba(0),
                Run::Mitsuba(1),
                Run::Mitsuba(2),
            ];
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
                    Run::Mitsuba(mode) => {
                        if let Some(py) = &python {
                            let line = common::mitsuba_anchor_with(
                                Path::new(py),
                                &scene_path,
                                &dir.join(format!("{name}_d8_ref.exr")),
                                &[spp],
                                MITSUBA_MODES[mode],
                            )?
                            .into_iter()
                            .find(|(s, _)| *s == spp)
                            .map(|(_, v)| v)
                            .ok_or("the Mitsuba anchor printed no line")?;
                            let seconds = |key: &str| {
                                line[key]
                                    .as_f64()
                                    .ok_or(format!("the Mitsuba anchor printed no {key}"))
                            };
                            mitsuba[mode] = mitsuba[mode].min(seconds("pt_s")?);
                            if mode == 0 {
                                denoised = denoised.min(seconds("oidn_total_s")?);
                            }
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
            Some(_) => {
                // Per mode: its samples per second, and ours over them.
                let [llvm, robust, scalar] =
                    mitsuba.map(|m| format!("{:.2} | {:.2}", rate(m), m / ours));
                println!(
                    "| {name} | {ours:.2} | {:.2} | {before} | {:.2} | {llvm} | {robust} | \
                     {scalar} | {denoised:.2} | {:.2} |",
                    rate(ours),
                    mitsuba[0],
                    ours / denoised,
                )
            }
            None => println!(
                "| {name} | {ours:.2} | {:.2} | {before} | not run (`WPBGI_ANCHOR_PYTHON`) \
                 | | | | | | | | |",
                rate(ours)
            ),
        }
    }
    ray_queries(&dir, python.as_deref().map(Path::new), rounds.max(3))
}

/// The ray-query table (see the module docs).
fn ray_queries(dir: &Path, python: Option<&Path>, rounds: u32) -> common::Result<()> {
    println!();
    println!(
        "ray queries alone: {RAYS} rays a scene, {} threads, fastest of {rounds} rounds",
        rayon::current_num_threads()
    );
    println!(
        "| scene | ours closest Mrays/s | Mitsuba (Embree) closest Mrays/s | ours / Embree | \
         Embree robust closest Mrays/s | ours / robust | ours occlusion Mrays/s | Embree \
         occlusion Mrays/s | ours / Embree | Embree robust occlusion Mrays/s | ours / robust | \
         hits ours / Embree / robust | occluded ours / Embree / robust |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for name in SCENES {
        let scene_path = dir.join(format!("{name}.gltf"));
        let scene = Scene::load(&scene_path)?;
        let accel = Accel::build(&scene);
        let rays = random_rays(&scene);
        let fastest = |query: &(dyn Fn(&Ray) -> bool + Sync)| {
            let mut best = f64::INFINITY;
            let mut count = 0;
            for _ in 0..rounds {
                let t = Instant::now();
                count = rays
                    .par_iter()
                    .with_min_len(4096)
                    .filter(|r| query(r))
                    .count();
                best = best.min(t.elapsed().as_secs_f64());
            }
            (RAYS as f64 / best / 1e6, count)
        };
        let (closest, hits) = fastest(&|r| {
            accel
                .closest_hit(r.origin, r.dir, 0.0, f32::INFINITY)
                .is_some()
        });
        let (occlusion, occluded) =
            fastest(&|r| accel.occluded(r.origin, r.to_other, 0.0, r.length * 0.999));
        let Some(python) = python else {
            println!(
                "| {name} | {closest:.2} | not run (`WPBGI_ANCHOR_PYTHON`) | | | | {occlusion:.2} | \
                 | | | | {hits} | {occluded} |"
            );
            continue;
        };
        let m = mitsuba_rays(python, &scene_path, &rays, rounds)?;
        let field = |k: &str| {
            m[k].as_f64()
                .ok_or(format!("mitsuba_rays.py printed no {k}"))
        };
        let rate = |k: &str| Ok::<_, String>(RAYS as f64 / field(k)? / 1e6);
        let (m_closest, m_occlusion) = (rate("closest_s")?, rate("occluded_s")?);
        let (r_closest, r_occlusion) = (rate("closest_robust_s")?, rate("occluded_robust_s")?);
        println!(
            "| {name} | {closest:.2} | {m_closest:.2} | {:.2} | {r_closest:.2} | {:.2} | \
             {occlusion:.2} | {m_occlusion:.2} | {:.2} | {r_occlusion:.2} | {:.2} | \
             {hits} / {} / {} | {occluded} / {} / {} |",
            closest / m_closest,
            closest / r_closest,
            occlusion / m_occlusion,
            occlusion / r_occlusion,
            field("hits")?,
            field("hits_robust")?,
            field("occluded")?,
            field("occluded_robust")?
        );
    }
    Ok(())
}

/// One query of the ray table: a closest-hit ray along `dir`, and an occlusion segment from
/// the same origin along the unit `to_other`, `length` long.
struct Ray {
    origin: Vec3,
    dir: Vec3,
    to_other: Vec3,
    length: f32,
}

/// [`RAYS`] rays of `scene` (see the module docs), the same every run.
fn random_rays(scene: &Scene) -> Vec<Ray> {
    let (lo, hi) = scene.bounds();
    let inside = |u: Vec3| lo + (hi - lo) * (Vec3::splat(0.02) + 0.96 * u);
    (0..RAYS)
        .map(|i| {
            let mut s = Sampler::new(7, i as u64, 0);
            let origin = inside(Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()));
            let other = inside(Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()));
            let dir = square_to_uniform_sphere(s.next_2d());
            let length = (other - origin).length();
            Ray {
                origin,
                dir,
                to_other: (other - origin) / length,
                length,
            }
        })
        .collect()
}

/// Mitsuba's times and counts for `rays` (`scripts/anchor/mitsuba_rays.py`'s JSON line).
fn mitsuba_rays(
    python: &Path,
    scene: &Path,
    rays: &[Ray],
    rounds: u32,
) -> common::Result<serde_json::Value> {
    let file = std::env::temp_dir().join("wpbgi-bench-rays.f32");
    let mut bytes = Vec::with_capacity(rays.len() * 40);
    for r in rays {
        for v in [r.origin, r.dir, r.to_other] {
            for c in v.to_array() {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        bytes.extend_from_slice(&r.length.to_le_bytes());
    }
    std::fs::write(&file, bytes)?;
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/anchor/mitsuba_rays.py");
    let run = common::run_ok(
        "the Mitsuba ray anchor",
        Command::new(python)
            .arg(script)
            .arg(scene)
            .arg(&file)
            .arg(rounds.to_string()),
    );
    std::fs::remove_file(&file)?;
    let json = String::from_utf8_lossy(&run?.stdout)
        .lines()
        .find_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .ok_or("mitsuba_rays.py printed no JSON line")?;
    Ok(json)
}

/// The three timed in a round.
#[derive(Clone, Copy)]
enum Run {
    Ours,
    Previous,
    /// Mitsuba in the mode `MITSUBA_MODES[k]`.
    Mitsuba(usize),
}

/// The Mitsuba columns, in the table's order: the anchor's `llvm_ad_rgb`, the same with
/// Embree's robust intersections, and `scalar_rgb`.
const MITSUBA_MODES: [MitsubaMode; 3] = [
    MitsubaMode::DEFAULT,
    MitsubaMode {
        robust: true,
        ..MitsubaMode::DEFAULT
    },
    MitsubaMode {
        variant: "scalar_rgb",
        robust: false,
    },
];

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
