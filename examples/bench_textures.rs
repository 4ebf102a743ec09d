//! Textured materials at the cost of untextured ones (issue 22): the default bake of a metal
//! plate whose roughness a texture varies (tests/data/usd/rough-plate.usda: roughness 0.25 to
//! 0.75) beside the same plate at the texture's mean roughness, 0.5
//! (rough-plate-constant.usda). Per scene: bake seconds, BSDF operators built, peak memory,
//! and the image's relative MSE at 128² against our path tracer (max depth 8, `SPP` samples
//! per pixel, default 1024), so that what the operators' roughness levels cost in error is a
//! figure beside what they save in time.
//!
//! `cargo run --release --example bench_textures [-- SPP]`

#[allow(dead_code)] // the benchmarks' shared helpers, of which this one uses one
mod common;

use std::path::Path;
use std::time::Instant;
use wpbgi::bake::bounce::BounceSettings;
use wpbgi::bake::{bake, BakeSettings, Quality};
use wpbgi::compare::errors;
use wpbgi::compare::memory::{peak, reset_peak};
use wpbgi::reference::{render, RenderSettings};
use wpbgi::render::FinalSettings;
use wpbgi::scene::Scene;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let spp: u32 = match std::env::args().nth(1) {
        Some(s) => s.parse()?,
        None => 1024,
    };
    println!(
        "{} threads, 128² images, path tracer at {spp} spp",
        rayon::current_num_threads()
    );
    println!("scene                      bake s  operators  peak MB  render s  relMSE");
    let mut seconds = Vec::new();
    for name in ["rough-plate-constant.usda", "rough-plate.usda"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/usd")
            .join(name);
        let scene = Scene::load(&path)?;
        let camera = scene.camera(None, 128, 128)?;
        reset_peak();
        // What `wpbgi bake` does by default: the preview preset, bounces until they converge.
        let settings = BakeSettings {
            bounces: BounceSettings::auto(),
            ..BakeSettings::preset(Quality::Preview).direct_only()
        };
        let t = Instant::now();
        let baked = bake(&scene, &settings, &|_, _| {})?;
        let bake_s = t.elapsed().as_secs_f64();
        let peak_mb = peak().map_or(0, |b| b / 1_000_000);
        let cache = wpbgi::bake::store::in_memory(&path, &baked)?;
        let (image, render_s) =
            common::timed_render(&scene, &cache, &camera, &FinalSettings::default())?;
        let reference = render(
            &scene,
            &camera,
            &RenderSettings {
                spp,
                max_depth: 8,
                ..Default::default()
            },
            &|_| {},
        )?;
        let (_, rel, _) = errors(&image.beauty, &reference.mean)?;
        println!(
            "{name:26} {bake_s:6.2}  {:9}  {peak_mb:7}  {render_s:8.2}  {rel:.2e}",
            baked.operators.len()
        );
        seconds.push(bake_s);
    }
    println!(
        "textured / constant bake time: {:.2}× (issue 22's target: at most 2×)",
        seconds[1] / seconds[0]
    );
    Ok(())
}
