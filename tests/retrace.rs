//! The bright pixels' rays through glossy hits (`FinalSettings::retrace_glossy`, issue 75
//! item 2) against Mitsuba 3.9.1 at max_depth 8.
//!
//! A draft cache of exactly 5 bounces (like for like with max_depth 8, as in
//! tests/multibounce.rs), rendered at 128² with the rays going on through glossy hits and
//! with each reading the cache's map at its first hit, both against the 256² reference
//! averaged 2 × 2. The maps blur a narrow lobe: the caustic a glass sphere focuses on the
//! floor, the room in a mirror. The bounds sit between the two measured figures, so each test
//! fails where the rays stop at the maps.

mod common;

use wpbgi::bake::bounce::BounceSettings;
use wpbgi::bake::{BakeSettings, Quality};
use wpbgi::image::{error_against, Image};
use wpbgi::render::{render_final, FinalSettings};
use wpbgi::scene::Scene;
use wpbgi::spectrum::luminance;

/// relMSE against the reference and the luminance of pixel window `[x, y, w, h]` over the
/// reference's, for the render with the retrace and the one without.
struct Both {
    retraced: (f64, f32),
    maps: (f64, f32),
}

fn both(name: &str, window: [u32; 4]) -> Both {
    let scene = Scene::load(&common::mitsuba_data(&format!("{name}.gltf"))).expect("scene");
    let settings = BakeSettings {
        bounces: BounceSettings::exactly(5),
        ..BakeSettings::preset(Quality::Draft).direct_only()
    };
    let dir = common::Scratch::new("retrace");
    let cache = common::bake_to_cache(&scene, &settings, &dir.join(format!("{name}.wpc")));
    let camera = scene.default_camera(128, 128).expect("camera");
    let reference = common::reference_128(name, 8);
    let [x0, y0, w, h] = window;
    let window_sum = |img: &Image| {
        (y0..y0 + h)
            .flat_map(|y| (x0..x0 + w).map(move |x| (x, y)))
            .map(|(x, y)| luminance(img.get(x, y)))
            .sum::<f32>()
    };
    let measure = |retrace_glossy: bool| {
        let settings = FinalSettings {
            retrace_glossy,
            ..FinalSettings::default()
        };
        let out = render_final(&scene, &cache, &camera, &settings, &|_, _| {}).expect("render");
        assert!(out.beauty.pixels.iter().all(|p| p.is_finite()));
        let (_, rel) = error_against(&out.beauty, &reference).expect("same size");
        (rel, window_sum(&out.beauty) / window_sum(&reference))
    };
    let b = Both {
        retraced: measure(true),
        maps: measure(false),
    };
    eprintln!(
        "{name}: retraced relMSE {:.3e}, window {:.3}; maps relMSE {:.3e}, window {:.3}",
        b.retraced.0, b.retraced.1, b.maps.0, b.maps.1
    );
    b
}

/// cbox-mirror (a mirror box and a glass sphere, both α 0.001). Measured: relMSE 8.69e-4
/// retraced (9.8e-4 when `render::bright::GLINT_CAP` was 16), 1.23e-3 from the maps.
#[test]
fn a_mirror_and_clear_glass_are_seen_through_not_in_their_maps() {
    let b = both("cbox-mirror", [0, 0, 128, 128]);
    assert!(b.retraced.0 < 9.6e-4, "relMSE {:.3e}", b.retraced.0);
}

/// cbox-rough's glass sphere (α 0.1) focuses the lamp on the floor in the window. Measured:
/// relMSE 4.50e-4 retraced, 9.1e-4 from the maps; the window 0.982 and 0.710 of the
/// reference's light (the maps spread the lobe the sphere focuses). (When this test was
/// written: 8.0e-4 and 1.21e-3, the bound 1.0e-3; the renders have improved since.)
#[test]
fn the_caustic_under_a_rough_glass_sphere_is_traced_through_it() {
    let b = both("cbox-rough", [83, 114, 7, 4]);
    assert!(b.retraced.0 < 6.0e-4, "relMSE {:.3e}", b.retraced.0);
    assert!(
        b.retraced.1 > 0.85 && b.retraced.1 < 1.15,
        "caustic at {:.3} of the reference",
        b.retraced.1
    );
}

/// Each traced ray's random numbers are keyed by its receiver, buffer pixel and place in the
/// grid: the retraced image is the same, bit for bit, on one thread and on two.
#[test]
fn byte_identical_for_any_thread_count() {
    let scene = Scene::load(&common::mitsuba_data("cbox-glossy.gltf")).expect("scene");
    let settings = BakeSettings {
        bounces: BounceSettings::exactly(2),
        ..BakeSettings::preset(Quality::Draft).direct_only()
    };
    let dir = common::Scratch::new("retrace-threads");
    let cache = common::bake_to_cache(&scene, &settings, &dir.join("cbox-glossy.wpc"));
    assert!(
        cache.bounces() > 0,
        "the retrace needs a multi-bounce cache"
    );
    let camera = scene.default_camera(48, 48).expect("camera");
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| common::final_render(&scene, &cache, &camera))
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.beauty, b.beauty);
    assert_eq!(a.indirect, b.indirect);
}
