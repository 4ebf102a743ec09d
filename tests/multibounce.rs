//! Multi-bounce caches (issue 5) against Mitsuba 3.9.1 at max_depth 8.
//!
//! A draft cache with `--bounces auto` rendered at 128² with the defaults, against the 256²
//! reference averaged 2 × 2. A direct-only cache gives relMSE 2.7e-2 (at 256²), so the
//! bounds below (about 1.5× the measured values, in each test) fail long before the bounces
//! are lost. The remaining error is the light each bounce loses in the
//! gather (about 2.5 %: darker walls), which issue 5 still has to remove.

mod common;

use wpbgi::bake::store::{bake_hash, write, BakedCache};
use wpbgi::bake::{bake, BakeSettings, Quality};
use wpbgi::bounce::BounceSettings;
use wpbgi::image::error_against;
use wpbgi::render::{render_final, FinalSettings};
use wpbgi::scene::Scene;

/// relMSE and the relative error of the image mean (largest channel) against max_depth 8.
fn against_depth_8(name: &str, bounces: BounceSettings) -> (f64, f32) {
    let scene = Scene::load(&common::mitsuba_data(&format!("{name}.gltf"))).expect("scene");
    let settings = BakeSettings {
        bounces,
        ..BakeSettings::from_quality(Quality::Draft)
    };
    let baked = bake(&scene, &settings, &|_, _| {}).expect("bake");
    let dir = std::env::temp_dir().join(format!("wpbgi-multibounce-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join(format!("{name}.wpc"));
    write(
        &path,
        bake_hash(&scene, &settings.to_json()),
        &baked,
        serde_json::json!({}),
    )
    .expect("write");
    let cache = BakedCache::read(&path, None).expect("read");
    let camera = scene.default_camera(128, 128).expect("camera");
    let out = render_final(
        &scene,
        &cache,
        &camera,
        &FinalSettings::default(),
        &|_, _| {},
    )
    .expect("render");
    assert!(out.beauty.pixels.iter().all(|p| p.is_finite()));
    let reference = common::reference_128(name, 8);
    let (_, rel) = error_against(&out.beauty, &reference).expect("same size");
    let (mean, ref_mean) = (out.beauty.mean(), reference.mean());
    let mean_err = ((mean - ref_mean) / ref_mean).abs().max_element();
    eprintln!(
        "{name}: {:?} bounces, relMSE {rel:.3e}, mean {mean} vs {ref_mean}",
        baked.bounces.map(|b| b.bounces)
    );
    (rel, mean_err)
}

/// Measured at 128²: 10 bounces, relMSE 1.1e-3, image mean 3.1 % dark in red (the channel
/// with the most bounces). A direct-only cache, at 256²: relMSE 2.7e-2, red 18 % dark.
#[test]
fn cbox_diffuse_with_bounces_matches_mitsuba_at_depth_8() {
    let (rel, mean_err) = against_depth_8("cbox-diffuse", BounceSettings::auto());
    assert!(rel < 1.7e-3, "relMSE {rel:.3e}");
    assert!(mean_err < 0.045, "mean off by {mean_err}");
}
