//! The previewer's frame time at 1280×720 (docs/design.md §8): the bundled Cornell box at draft
//! quality (20 000 surfels) and at about a million surfels, from the scene camera, for several
//! cut bounds; per frame, the cut's size, the CPU time of the cut (with each node's radiance
//! towards the eye) and the GPU time (three passes and, headless, the 14.7 MB readback of the
//! float frame, which the windowed mode does not do). The median of 5 frames after one to warm
//! up. The device is whatever `Gpu` picks: lavapipe on a machine without a GPU.
//!
//! `cargo run --release --example bench_preview [-- POINTS ...]` (default: 20000 1000000).

use std::sync::Arc;
use std::time::Instant;
use wpbgi::bake::{bake, BakeSettings, Quality};
use wpbgi::preview::device::Gpu;
use wpbgi::preview::window::MOVING_COARSENESS;
use wpbgi::preview::{Preview, Show, DEFAULT_CUT_PIXELS};
use wpbgi::scene::Scene;

type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

fn main() -> Result<()> {
    let points: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse())
        .collect::<std::result::Result<_, _>>()?;
    let points = if points.is_empty() {
        vec![20_000, 1_000_000]
    } else {
        points
    };
    let scene = Scene::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cbox-rough.gltf"),
    )?;
    let gpu = Arc::new(Gpu::from_env()?);
    println!("device: {} ({:?})", gpu.name, gpu.kind);
    let (w, h) = (1280, 720);
    let camera = scene.default_camera(w, h)?;
    for n in points {
        let settings = BakeSettings {
            points: n,
            light_samples: 16,
            ..BakeSettings::preset(Quality::Draft).direct_only()
        };
        let t = Instant::now();
        let baked = bake(&scene, &settings, &|_, _| {})?;
        let cache = wpbgi::bake::store::in_memory(std::path::Path::new("bench.wpc"), &baked)?;
        println!(
            "\n{} surfels, {} tree nodes (direct-only bake {:.1} s)",
            baked.surfels.len(),
            cache.nodes.len(),
            t.elapsed().as_secs_f64()
        );
        let t = Instant::now();
        let mut preview = Preview::new(gpu.clone(), &cache, Some(&scene), (w, h))?;
        println!(
            "  loading onto the device: {:.2} s",
            t.elapsed().as_secs_f64()
        );
        let fixed = median(
            (0..5)
                .map(|_| {
                    preview
                        .frame(&camera, Show::Direct, 1.0)
                        .map(|f| 1e3 * f.draw_seconds)
                })
                .collect::<std::result::Result<_, _>>()?,
        );
        println!("  a frame without splats (G-buffer, resolve, readback): {fixed:.1} ms");
        println!("  cut px | nodes   | cut ms | GPU ms | frame ms | fps");
        // Full-size frames at several cut bounds, then the windowed mode's first frame after
        // a move: half the size, the default cut made 8× coarser (8 pixels at that size).
        let (rw, rh) = preview.reduced_size();
        let moving = camera.clone().with_size(rw, rh);
        let runs = [1.0, 2.0, 4.0, 8.0, 16.0, 32.0]
            .map(|p| (&camera, p, ""))
            .into_iter()
            .chain([(
                &moving,
                0.5 * MOVING_COARSENESS * DEFAULT_CUT_PIXELS,
                " (moving, half size)",
            )]);
        for (camera, cut_pixels, label) in runs {
            preview.frame(camera, Show::Total, cut_pixels)?;
            let (mut cut, mut draw, mut nodes) = (vec![], vec![], 0);
            for _ in 0..5 {
                let f = preview.frame(camera, Show::Total, cut_pixels)?;
                cut.push(1e3 * f.cut_seconds);
                draw.push(1e3 * f.draw_seconds);
                nodes = f.cut_size;
            }
            let (c, d) = (median(cut), median(draw));
            println!(
                "  {cut_pixels:>6} | {nodes:>7} | {c:>6.1} | {d:>6.1} | {:>8.1} | {:>4.1}{label}",
                c + d,
                1e3 / (c + d)
            );
        }
    }
    Ok(())
}
