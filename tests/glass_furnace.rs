//! A rough glass sphere alone under a white sky, rendered from its cache against our path
//! tracer (checked against Mitsuba's images in tests/reference_vs_mitsuba.rs).
//!
//! Everything the camera sees of the sphere is the sky, reflected once (direct light, traced
//! exactly) or seen through the sphere: through the render's gather of the sphere's inside,
//! the transmitted half of its receivers' buffers, which holds about 95 % of the light. A
//! transmitted lobe (α 0.1) is narrower than the buffer's pixels, and the inside of a solid
//! is what its splatted far side covers only in part; this scene holds that part of the
//! render to the path tracer with nothing else in the image.

mod common;

use glam::{Mat3, Vec2, Vec3};
use wpbgi::bake::{BakeSettings, Quality};
use wpbgi::bsdf::{Bsdf, Distribution, Microfacet, RoughDielectric};
use wpbgi::reference::RenderSettings;
use wpbgi::scene::{Camera, Environment, Material, Scattering, Scene};
use wpbgi::spectrum::{luminance, Rgb};

/// The unit sphere in rough glass (α 0.1, η 1.5) under a sky of radiance 1.
fn glass_under_a_white_sky() -> Scene {
    Scene {
        meshes: vec![common::closed_sphere(5)],
        materials: vec![Material {
            name: "glass".into(),
            scattering: Scattering::Explicit(Bsdf::Dielectric(RoughDielectric {
                distr: Microfacet::new(Distribution::Ggx, 0.1, 0.1),
                eta: 1.5,
                specular_reflectance: Rgb::ONE,
                specular_transmittance: Rgb::ONE,
            })),
            cutout: None,
            normal_map: None,
            emission: None,
        }],
        environment: Some(Environment {
            name: "sky".into(),
            map: None,
            scale: Rgb::ONE,
            to_local: Mat3::IDENTITY,
        }),
        ..Default::default()
    }
}

/// The sphere's mean luminance in the render against the path tracer's (2 048 samples over
/// the disc's pixels: its noise is below 0.2 %), over the pixels within 95 % of the disc's
/// radius. Measured: 0.982 (before the convolution integrated the BSDF over a lobe's pixels
/// and the transmitted pixels were traced, 0.893; with only the first, 0.937). The bound
/// admits 3 % below, where the remaining loss (1.8 %) and some margin lie, and 2 % above.
#[test]
fn a_rough_glass_sphere_under_a_white_sky_matches_the_path_tracer() {
    let scene = glass_under_a_white_sky();
    let settings = BakeSettings {
        points: 6000,
        ..BakeSettings::preset(Quality::Preview)
    };
    let dir = common::Scratch::new("glass-furnace");
    let cache = common::bake_to_cache(&scene, &settings, &dir.join("glass.wpc"));
    let n = 64;
    let yfov = 0.6f32;
    let camera = Camera::look_at("camera", Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, yfov, n, n)
        .expect("camera");
    let ours = common::final_render(&scene, &cache, &camera);
    let truth = wpbgi::reference::render(
        &scene,
        &camera,
        &RenderSettings {
            spp: 2048,
            ..Default::default()
        },
        &|_| {},
    )
    .expect("path tracer");
    // The disc's radius in pixels: the unit sphere seen from 4 away subtends asin(1/4), and
    // the image plane's half height is tan(yfov/2).
    let radius = (0.25f32).asin().tan() / (0.5 * yfov).tan() * (n as f32 / 2.0);
    let (mut sum_ours, mut sum_truth) = (0.0f64, 0.0f64);
    for y in 0..n {
        for x in 0..n {
            let offset = Vec2::new(x as f32 + 0.5, y as f32 + 0.5) - Vec2::splat(n as f32 / 2.0);
            if offset.length() < 0.95 * radius {
                sum_ours += f64::from(luminance(ours.beauty.get(x, y)));
                sum_truth += f64::from(luminance(truth.mean.get(x, y)));
            }
        }
    }
    let ratio = sum_ours / sum_truth;
    eprintln!("the sphere against the path tracer: {ratio:.4}");
    assert!(ours.beauty.pixels.iter().all(|p| p.is_finite()));
    assert!((0.97..1.02).contains(&ratio), "ratio {ratio:.4}");
}
