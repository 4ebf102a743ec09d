//! The environment (a USD dome light) against analytic answers.
//!
//! - Uniform radiance L around a convex diffuse object of albedo ρ: every point sees only the
//!   environment, so it reflects exactly ρL, and the background is L. Both the path tracer and
//!   the final render from a baked cache must find that: the cache holds ρL on every surfel,
//!   and a convex object gathers no indirect light from itself.
//! - A map that is white above the horizon and black below, over a floor facing up: the floor
//!   reflects ρ (less 0.1 %: the map's bilinear lookup fades to black within half a texel of
//!   the horizon, where cos θ ≤ sin(π/64)); turned upside down, the floor is black.
//!
//! Fixtures: tests/data/usd/dome*.usda (tests/data/README.md).

mod common;

use glam::Vec3;
use std::path::{Path, PathBuf};
use wpbgi::bake::{BakeSettings, Quality};
use wpbgi::reference::{render, RenderSettings};

use wpbgi::scene::{Camera, Scene};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/usd")
        .join(name)
}

fn load(name: &str) -> Scene {
    Scene::load(&data(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Path-traced image at `spp` samples per pixel.
fn reference(scene: &Scene, camera: &Camera, spp: u32) -> Vec<Vec3> {
    let settings = RenderSettings {
        spp,
        max_depth: -1,
        seed: 11,
        ..Default::default()
    };
    render(scene, camera, &settings, &|_| {})
        .expect("render")
        .mean
        .pixels
}

/// Pixels of a `size`² image well inside the object (their 3 × 3 neighbourhood all hits it, by
/// the final render's depth AOV) and well outside it; the silhouette mixes both and is left out.
fn split(pixels: &[Vec3], depth: &[Vec3], size: usize) -> (Vec<Vec3>, Vec<Vec3>) {
    let (mut object, mut background) = (Vec::new(), Vec::new());
    for y in 1..size - 1 {
        for x in 1..size - 1 {
            let hits = (0..9)
                .filter(|k| depth[(y + k / 3 - 1) * size + x + k % 3 - 1].x > 0.0)
                .count();
            match hits {
                9 => object.push(pixels[y * size + x]),
                0 => background.push(pixels[y * size + x]),
                _ => {}
            }
        }
    }
    (object, background)
}

fn mean(v: &[Vec3]) -> Vec3 {
    v.iter().copied().sum::<Vec3>() / v.len() as f32
}

#[test]
fn dome_light_imports_as_the_environment() {
    let uniform = load("dome.usda");
    let env = uniform.environment.as_ref().expect("environment");
    // colour 0.5 × intensity 2.
    for w in [Vec3::X, Vec3::NEG_Y, Vec3::new(0.3, 0.4, -0.5).normalize()] {
        assert_eq!(env.radiance(w), Vec3::ONE);
    }
    let sky = load("dome-sky.usda");
    let env = sky.environment.as_ref().expect("environment");
    assert_eq!(env.radiance(Vec3::Y), Vec3::ONE, "zenith");
    assert_eq!(env.radiance(Vec3::NEG_Y), Vec3::ZERO, "nadir");
    let flipped = load("dome-sky-flipped.usda");
    let env = flipped.environment.as_ref().expect("environment");
    assert_eq!(env.radiance(Vec3::Y), Vec3::ZERO, "flipped zenith");
    assert_eq!(env.radiance(Vec3::NEG_Y), Vec3::ONE, "flipped nadir");
}

/// Uniform radiance 1 around a diffuse sphere of albedo 0.5: the sphere is 0.5, the background
/// 1, by path tracing and by the final render from a baked cache.
#[test]
fn convex_object_under_a_uniform_environment_reflects_albedo_times_radiance() {
    let scene = load("dome.usda");
    let camera = scene.camera(None, 32, 32).expect("camera");
    let dir = tempdir();
    let cache = common::bake_to_cache(
        &scene,
        &BakeSettings::preset(Quality::Draft).direct_only(),
        &dir.join("dome.wpbgi"),
    );
    let out = common::final_render(&scene, &cache, &camera);
    let (object, background) = split(&out.beauty.pixels, &out.depth.pixels, 32);
    assert!(object.len() > 100 && background.len() > 100);
    assert!(out.beauty.pixels.iter().all(|p| p.is_finite()));
    for p in &background {
        assert_eq!(*p, Vec3::ONE, "background");
    }
    // Per pixel: 16 emitter samples at each of the pixel's samples, with a convex object's
    // indirect light 0 exactly.
    let m = mean(&object);
    eprintln!("final render: sphere {m} over {} pixels", object.len());
    assert!(
        (m - Vec3::splat(0.5)).abs().max_element() < 0.01,
        "final render: sphere mean {m}"
    );
    let indirect = mean(&split(&out.indirect.pixels, &out.depth.pixels, 32).0);
    assert!(
        indirect.max_element() < 0.005,
        "the sphere gathers {indirect} from itself"
    );
    let traced = reference(&scene, &camera, 64);
    let (object, _) = split(&traced, &out.depth.pixels, 32);
    let m = mean(&object);
    eprintln!("path tracer: sphere {m}; final render's indirect {indirect}");
    // 64 samples per pixel over ~450 pixels: the standard error of the mean is below 1e-3.
    assert!(
        (m - Vec3::splat(0.5)).abs().max_element() < 0.005,
        "path tracer: sphere mean {m}"
    );
}

/// The sky map over a floor facing up, and upside down.
#[test]
fn environment_map_lights_the_floor_by_its_orientation() {
    for (name, expected) in [
        ("dome-sky.usda", 0.5 * (1.0 - 1e-3)),
        ("dome-sky-flipped.usda", 0.0),
    ] {
        let scene = load(name);
        let camera = scene.camera(None, 16, 16).expect("camera");
        let traced = reference(&scene, &camera, 64);
        assert!(traced.iter().all(|p| p.is_finite()));
        // The camera looks straight down at the floor, which fills the view.
        let m = mean(&traced);
        eprintln!("{name}: floor {m}");
        assert!(
            (m - Vec3::splat(expected)).abs().max_element() < 0.005,
            "{name}: floor mean {m}, expected {expected}"
        );
    }
}

fn tempdir() -> common::Scratch {
    common::Scratch::new("environment")
}
