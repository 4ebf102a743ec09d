//! Multi-bounce caches against Mitsuba 3's max_depth 8 references (256²), and our path tracer
//! at equal time: bake (draft, exactly 5 bounces: with the render's emission, direct light and
//! gather, the paths of max_depth 8) + render with the defaults, then the path tracer at
//! max_depth 8 for the same wall time; the relMSE and MSE of both, the bounces and the time of
//! each; and the bounces' time without the view tree (every surfel traversing the whole tree).
//!
//! `cargo run --release --example bench_bounces [-- SCENE_NAME]` (cbox-diffuse, cbox-rough or
//! cbox-glossy from tests/data/mitsuba; default: cbox-diffuse and cbox-rough).

use std::time::Instant;
use wpbgi::bake::{BakeSettings, Quality};
use wpbgi::bounce::BounceSettings;
use wpbgi::image::{error_against, read_exr};
use wpbgi::render::{render_final, FinalSettings};
use wpbgi::scene::Scene;

mod common;

use common::data;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let names: Vec<String> = match std::env::args().nth(1) {
        Some(n) => vec![n],
        None => vec!["cbox-diffuse".into(), "cbox-rough".into()],
    };
    println!("threads: {}", rayon::current_num_threads());
    for name in &names {
        let scene = Scene::load(&data(&format!("{name}.gltf")))?;
        let reference = read_exr(&data(&format!("{name}_d8_ref.exr")))?;
        let camera = scene.default_camera(256, 256)?;
        let settings = BakeSettings {
            bounces: BounceSettings::exactly(5),
            ..BakeSettings::from_quality(Quality::Draft)
        };
        let (baked, cache, bake_s) =
            common::bake_cache(&scene, &settings, &format!("bounces-{name}"))?;
        let t = Instant::now();
        let out = render_final(
            &scene,
            &cache,
            &camera,
            &FinalSettings::default(),
            &|_, _| {},
        )?;
        let render_s = t.elapsed().as_secs_f64();
        let (mse, rel) = error_against(&out.beauty, &reference).ok_or("size")?;
        let pt = common::path_tracer_for(&scene, &camera, 8, bake_s + render_s)?;
        let (pt_mse, pt_rel) = error_against(&pt.mean, &reference).ok_or("size")?;
        let report = baked.bounces.unwrap_or_default();
        // The same bounces with every surfel traversing the whole tree (no view tree).
        let alone = BakeSettings {
            bounces: BounceSettings {
                view_tree: false,
                ..settings.bounces
            },
            ..settings.clone()
        };
        let (alone, _, _) = common::bake_cache(&scene, &alone, &format!("alone-{name}"))?;
        let bounce_time = |r: &wpbgi::bounce::BounceReport| r.seconds.iter().sum::<f64>();
        let alone_s = bounce_time(&alone.bounces.unwrap_or_default());
        println!(
            "{name}: bake {bake_s:.1} s ({} bounces, {:.1} s each on average) + render {render_s:.1} s: \
             relMSE {rel:.3e}, MSE {mse:.3e}; path tracer in {:.1} s ({} spp): relMSE {pt_rel:.3e}, \
             MSE {pt_mse:.3e} ({:.2}× our relMSE, {:.2}× our MSE); bounces per surfel without the \
             view tree: {alone_s:.1} s ({:.2}× the view tree's)",
            report.bounces,
            report.seconds.iter().sum::<f64>() / report.seconds.len().max(1) as f64,
            pt.seconds,
            pt.spp,
            pt_rel / rel,
            pt_mse / mse,
            alone_s / bounce_time(&report)
        );
    }
    Ok(())
}
