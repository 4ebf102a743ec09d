//! The same render with 1 and 2 threads is byte-identical: every random number is keyed by
//! (pixel, sample, dimension), never by a thread's stream.

use std::path::PathBuf;
use wpbgi::reference::{render, RenderSettings};
use wpbgi::scene::Scene;

#[test]
fn one_and_two_threads_give_identical_images() {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba/cbox-glossy.gltf");
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let scene = Scene::load(&path).unwrap();
            let cam = scene.default_camera(64, 64).unwrap();
            render(
                &scene,
                &cam,
                &RenderSettings {
                    spp: 8,
                    max_depth: 8,
                    ..Default::default()
                },
                &|_| {},
            )
            .unwrap()
        })
    };
    let (a, b) = (run(1), run(2));
    let bits = |img: &wpbgi::image::Image| {
        img.pixels
            .iter()
            .flat_map(|p| p.to_array().map(f32::to_bits))
            .collect::<Vec<u32>>()
    };
    assert_eq!(bits(&a.mean), bits(&b.mean));
    assert_eq!(bits(&a.variance), bits(&b.variance));
    assert!(a.mean.mean().x > 0.0);
}
