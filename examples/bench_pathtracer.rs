//! Reference path tracer speed: seconds per sample per pixel per megapixel on the Cornell scenes
//! of `tests/data/mitsuba` at 512², max_depth 8 (the setting Mitsuba's figures are quoted for).
//!
//! `cargo run --release --example bench_pathtracer [-- SPP]` (default 16 spp)

use std::path::Path;
use std::time::Instant;
use wpbgi::reference::{render, RenderSettings};
use wpbgi::scene::Scene;

fn main() -> anyhow::Result<()> {
    let spp: u32 = match std::env::args().nth(1) {
        Some(s) => s.parse()?,
        None => 16,
    };
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba");
    println!(
        "512x512, max_depth 8, {spp} spp, {} threads",
        rayon::current_num_threads()
    );
    println!("{:<14} {:>9} {:>14}", "scene", "seconds", "s/spp/MP");
    for name in ["cbox-diffuse", "cbox-rough", "cbox-glossy"] {
        let scene = Scene::load(&dir.join(format!("{name}.gltf")))?;
        let camera = scene.default_camera(512, 512)?;
        let settings = RenderSettings {
            spp,
            max_depth: 8,
            ..Default::default()
        };
        let t = Instant::now();
        let out = render(&scene, &camera, &settings, &|_| {})?;
        let secs = t.elapsed().as_secs_f64();
        let mp = 512.0 * 512.0 / 1e6;
        println!(
            "{name:<14} {secs:>9.2} {:>14.3}",
            secs / out.spp as f64 / mp
        );
    }
    Ok(())
}
