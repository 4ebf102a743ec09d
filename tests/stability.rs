//! The stability matrix of docs/design.md §10: stiff and extreme inputs, each case checked for
//! finite output and against an answer that does not come from the code under test.
//!
//! | case | checked against |
//! |---|---|
//! | roughness 1e-4 … 1, Beckmann and GGX, conductor and dielectric | energy ≤ 1; smooth limit reflects all (conductor) or R + T = 1 (dielectric); sample weight = f cos / pdf |
//! | IOR 1.0001, 1.33, 1.5, 2.4, 4.0, from both sides | Fresnel's equations (written out here) and Snell's law |
//! | total internal reflection | every sample reflects beyond the critical angle |
//! | IOR 1.0 | the glass vanishes: the image equals the scene without it |
//! | grazing angles, cos θ = 1e-6 | finite BSDF values and images |
//! | radiance 2^±20 and 10^±6 | outputs scale exactly (bit for bit by powers of two) |
//! | scene scale 1e-3 … 1e4 | the image of the unscaled scene |
//! | degenerate and coincident triangles | the image of the clean scene |
//! | closed box of albedo 0.99 | Le / (1 − ρ) = 100 Le |
//!
//! Images are small (24² to 32²) and bakes use 3 000 surfels, to stay within CI's budget.

mod common;

use glam::{Vec2, Vec3};
use std::path::{Path, PathBuf};
use wpbgi::bake::bounce::BounceSettings;
use wpbgi::bake::{bake, BakeSettings, Quality};
use wpbgi::bsdf::{
    Bsdf, Diffuse, Distribution, Lobe, Microfacet, RoughConductor, RoughDielectric, ThinDielectric,
    TransportMode,
};
use wpbgi::image::{error_against, Image};
use wpbgi::reference::{render, RenderSettings};

use wpbgi::scene::{Camera, Emission, Material, Mesh, Scattering, Scene};
use wpbgi::spectrum::Rgb;

fn mitsuba(name: &str) -> PathBuf {
    common::mitsuba_data(name)
}

fn load(name: &str) -> Scene {
    Scene::load(&mitsuba(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// A low-discrepancy point in [0, 1)² for sample `k` of `n` (stratified x, golden-ratio y).
fn point(k: u32, n: u32) -> (f32, Vec2) {
    let u0 = (k as f32 + 0.5) / n as f32;
    let a = (k as f64 * 0.618_033_988_749_895).fract() as f32;
    let b = (k as f64 * 0.754_877_666_246_693).fract() as f32;
    (u0, Vec2::new(a, b))
}

/// A unit direction with cos θ = `cos` (and a fixed azimuth), on the side of `side`.
fn direction(cos: f32, side: f32) -> Vec3 {
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    Vec3::new(0.8 * sin, 0.6 * sin, cos * side.signum())
}

fn conductor(kind: Distribution, alpha: f32) -> Bsdf {
    // Mitsuba's `material: none`: Fresnel 1.
    Bsdf::Conductor(RoughConductor {
        distr: Microfacet::new(kind, alpha, alpha),
        eta: Rgb::ZERO,
        k: Rgb::ONE,
        specular_reflectance: Rgb::ONE,
    })
}

fn dielectric(kind: Distribution, alpha: f32, eta: f32) -> Bsdf {
    Bsdf::Dielectric(RoughDielectric {
        distr: Microfacet::new(kind, alpha, alpha),
        eta,
        specular_reflectance: Rgb::ONE,
        specular_transmittance: Rgb::ONE,
    })
}

/// Sampling statistics of `bsdf` from `wi`: (mean importance-mode weight (the albedo), share
/// of reflection samples, transmitted directions), after checking every value is finite and
/// that each sample's weight is f |cos| / pdf where the lobe is not a near-delta.
fn sample_stats(bsdf: &Bsdf, wi: Vec3, n: u32, check_weights: bool) -> (f64, f64, Vec<Vec3>) {
    let (mut albedo, mut reflected, mut through) = (0.0f64, 0u32, Vec::new());
    for k in 0..n {
        let (u0, u) = point(k, n);
        let Some(s) = bsdf.sample(wi, u0, u, TransportMode::Importance) else {
            continue;
        };
        assert!(
            s.weight.is_finite() && s.weight.min_element() >= 0.0 && s.pdf.is_finite(),
            "{bsdf:?} from {wi}: sample {s:?}"
        );
        assert!(s.wo.is_finite() && (s.wo.length() - 1.0).abs() < 1e-4);
        albedo += f64::from(s.weight.x);
        match s.lobe {
            Lobe::Reflection => reflected += 1,
            Lobe::Transmission => through.push(s.wo),
        }
        let f = bsdf.eval(wi, s.wo, TransportMode::Importance);
        let pdf = bsdf.pdf(wi, s.wo);
        assert!(
            f.is_finite() && pdf.is_finite() && pdf >= 0.0,
            "{bsdf:?}: {f} {pdf}"
        );
        if check_weights && pdf > 0.0 {
            // `eval` includes the cosine (Mitsuba's convention).
            let expected = f.x / pdf;
            assert!(
                (expected - s.weight.x).abs() <= 2e-3 * s.weight.x.max(1e-3),
                "{bsdf:?} from {wi}: weight {} but f cos / pdf = {expected}",
                s.weight.x
            );
        }
    }
    (albedo / n as f64, f64::from(reflected) / n as f64, through)
}

/// Fresnel reflectance of unpolarised light going from index `n1` into `n2` at cos θᵢ = `cos`
/// (the textbook formulas, independent of `wpbgi::bsdf::fresnel`): 1 under total internal
/// reflection.
fn fresnel(cos: f64, n1: f64, n2: f64) -> f64 {
    let sin_t = n1 / n2 * (1.0 - cos * cos).max(0.0).sqrt();
    if sin_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    let rs = ((n1 * cos - n2 * cos_t) / (n1 * cos + n2 * cos_t)).powi(2);
    let rp = ((n1 * cos_t - n2 * cos) / (n1 * cos_t + n2 * cos)).powi(2);
    0.5 * (rs + rp)
}

#[test]
fn roughness_from_1e_4_to_1() {
    const N: u32 = 8192;
    for kind in [Distribution::Beckmann, Distribution::Ggx] {
        for alpha in [1e-4, 1e-3, 1e-2, 0.1, 0.5, 1.0] {
            for cos in [1.0, 0.5, 1e-6] {
                let wi = direction(cos, 1.0);
                let what = format!("{kind:?} α = {alpha}, cos θ = {cos}");
                // Weight = f cos / pdf is checked where float precision allows: not for
                // near-delta lobes (f and pdf of a 1e-4 lobe exceed it together), nor at grazing
                // incidence (the half vector recomputed from a grazing pair loses digits).
                let check = alpha >= 1e-2 && cos >= 0.5;
                let (albedo, _, _) = sample_stats(&conductor(kind, alpha), wi, N, check);
                // Weights are at most 1 for a Fresnel-1 conductor (G1 ≤ 1): the mean is ≤ 1.
                assert!(albedo <= 1.0 + 1e-6, "{what}: conductor albedo {albedo}");
                if alpha <= 1e-2 && cos >= 0.5 {
                    // The smooth limit reflects everything.
                    assert!(albedo > 0.99, "{what}: conductor albedo {albedo}");
                }
                let (albedo, _, _) = sample_stats(&dielectric(kind, alpha, 1.5), wi, N, check);
                // Importance transport: reflected plus transmitted energy ≤ 1.
                assert!(albedo <= 1.0 + 1e-3, "{what}: dielectric albedo {albedo}");
                if alpha <= 1e-2 && cos >= 0.5 {
                    assert!(albedo > 0.99, "{what}: dielectric R + T = {albedo}");
                }
            }
        }
    }
}

/// The smooth limit (Beckmann, α = 1e-4) of each index from both sides: the share of reflected samples
/// is Fresnel's R (lobe choice is stratified, so within 1e-3), transmitted directions obey
/// Snell's law, and beyond the critical angle nothing is transmitted. Rough interfaces
/// (α = 0.3) keep R + T ≤ 1.
#[test]
fn indices_of_refraction_from_both_sides() {
    const N: u32 = 4096;
    for eta in [1.0001f32, 1.33, 1.5, 2.4, 4.0] {
        for side in [1.0f32, -1.0] {
            for cos in [1.0f32, 0.7, 0.3, 1e-6] {
                let wi = direction(cos, side);
                let (n1, n2) = if side > 0.0 {
                    (1.0, f64::from(eta))
                } else {
                    (f64::from(eta), 1.0)
                };
                let what = format!(
                    "η = {eta} from {}, cos θ = {cos}",
                    if side > 0.0 { "outside" } else { "inside" }
                );
                // Beckmann: GGX's heavy tail puts a few of 4096 microfacets 60 α off the
                // normal, which near the critical angle turns a refracted ray by 0.3 %.
                let smooth = dielectric(Distribution::Beckmann, 1e-4, eta);
                let (energy, reflected, through) = sample_stats(&smooth, wi, N, false);
                let r = fresnel(f64::from(cos), n1, n2);
                // At grazing incidence even a 1e-4 roughness tilts the visible microfacets by
                // far more than cos θ, so smooth Fresnel applies only away from grazing.
                if cos >= 0.3 {
                    assert!(
                        (reflected - r).abs() < 1e-3 + 2.0 / f64::from(N),
                        "{what}: {reflected} of the samples reflect, Fresnel says {r}"
                    );
                }
                if r >= 1.0 {
                    assert!(through.is_empty(), "{what}: transmission under TIR");
                }
                if cos >= 0.3 {
                    assert!((energy - 1.0).abs() < 1e-2, "{what}: R + T = {energy}");
                }
                let sin_i = f64::from(wi.truncate().length());
                for wo in through.iter().filter(|_| cos >= 0.3) {
                    assert!(wo.z * wi.z < 0.0, "{what}: transmitted to the same side");
                    let sin_t = f64::from(wo.truncate().length());
                    assert!(
                        (n2 * sin_t - n1 * sin_i).abs() < 2e-3 * n2,
                        "{what}: Snell: {n1} sin θi = {} but {n2} sin θt = {}",
                        n1 * sin_i,
                        n2 * sin_t
                    );
                }
                let rough = dielectric(Distribution::Ggx, 0.3, eta);
                let (energy, _, _) = sample_stats(&rough, wi, N, cos >= 0.3);
                assert!(energy <= 1.0 + 1e-3, "{what}, α = 0.3: R + T = {energy}");
            }
        }
    }
}

/// Every BSDF, smooth to rough, from grazing incidence (cos θ = 1e-6) and towards grazing
/// directions: finite values everywhere.
#[test]
fn grazing_angles_stay_finite() {
    let grazing = [direction(1e-6, 1.0), direction(1e-6, -1.0)];
    for alpha in [1e-4, 0.1, 1.0] {
        let bsdfs = [
            Bsdf::Diffuse(Diffuse {
                reflectance: Rgb::splat(0.5),
            }),
            conductor(Distribution::Ggx, alpha),
            conductor(Distribution::Beckmann, alpha),
            dielectric(Distribution::Ggx, alpha, 1.5),
            dielectric(Distribution::Beckmann, alpha, 2.4),
            Bsdf::ThinDielectric(ThinDielectric {
                distr: Microfacet::new(Distribution::Ggx, alpha, alpha),
                eta: 1.5,
                specular_reflectance: Rgb::ONE,
                specular_transmittance: Rgb::ONE,
            }),
        ];
        for b in &bsdfs {
            for wi in grazing {
                sample_stats(b, wi, 512, false);
                for wo in grazing
                    .iter()
                    .chain(&[Vec3::Z, -Vec3::Z, direction(0.5, 1.0)])
                {
                    for mode in [TransportMode::Radiance, TransportMode::Importance] {
                        assert!(b.eval(wi, *wo, mode).is_finite(), "{b:?} {wi} {wo}");
                    }
                    assert!(b.pdf(wi, *wo).is_finite(), "{b:?} {wi} {wo}");
                }
            }
        }
    }
    // A camera skimming a lit floor at 0.001° renders finite pixels.
    let scene = load("cbox-diffuse.gltf");
    let (lo, hi) = scene.bounds();
    let eye = Vec3::new(0.5 * (lo.x + hi.x), lo.y + 1e-5 * (hi.y - lo.y), hi.z);
    let target = Vec3::new(eye.x, lo.y, lo.z);
    let camera = Camera::look_at("grazing", eye, target, 0.5, 24, 24).expect("camera");
    assert!(path_traced(&scene, &camera, 4)
        .pixels
        .iter()
        .all(|p| p.is_finite()));
}

/// Clear glass of index 1 is left out at import (with a warning), so the image is the one of
/// the scene without it; the BSDF itself stays finite at η = 1.
#[test]
fn index_matched_glass_vanishes() {
    let path = mitsuba("cbox-glossy.gltf");
    let text = std::fs::read_to_string(&path).expect("gltf");
    let mut json: serde_json::Value = serde_json::from_str(&text).expect("json");
    let glass = json["materials"]
        .as_array_mut()
        .expect("materials")
        .iter_mut()
        .find(|m| m["name"] == "glass-a0.02")
        .expect("glass");
    glass["extras"]["mitsuba"]["int_ior"] = 1.0.into();
    glass["extensions"]["KHR_materials_ior"]["ior"] = 1.0.into();
    let matched = Scene::from_gltf_bytes(&path, json.to_string().as_bytes()).expect("loads");
    assert!(
        matched.warnings.iter().any(|w| w.0.contains("index 1")),
        "{:?}",
        matched.warnings
    );
    let mut without = load("cbox-glossy.gltf");
    let before = without.meshes.len();
    without.meshes.retain(|m| m.name != "sphere");
    assert_eq!(
        without.meshes.len(),
        before - 1,
        "the glass sphere is a mesh of its own"
    );
    assert_eq!(matched.meshes.len(), without.meshes.len());
    let camera = without.default_camera(24, 24).expect("camera");
    assert_eq!(
        path_traced(&matched, &camera, 4).pixels,
        path_traced(&without, &camera, 4).pixels
    );
    for alpha in [1e-4, 0.3] {
        let b = dielectric(Distribution::Ggx, alpha, 1.0);
        for cos in [1.0, 0.5, 1e-6] {
            for side in [1.0, -1.0] {
                sample_stats(&b, direction(cos, side), 256, false);
            }
        }
    }
}

fn path_traced(scene: &Scene, camera: &Camera, spp: u32) -> Image {
    let settings = RenderSettings {
        spp,
        seed: 3,
        ..Default::default()
    };
    render(scene, camera, &settings, &|_| {})
        .expect("render")
        .mean
}

/// 3 000 surfels and the CLI's default of automatic bounces.
fn bake_settings() -> BakeSettings {
    BakeSettings {
        points: 3000,
        light_samples: 16,
        bounces: BounceSettings::auto(),
        ..BakeSettings::preset(Quality::Draft).direct_only()
    }
}

/// Bake in memory and render the final image.
fn final_render(scene: &Scene, camera: &Camera) -> Image {
    let baked = bake(scene, &bake_settings(), &|_, _| {}).expect("bake");
    let cache = wpbgi::bake::store::in_memory(Path::new("memory"), &baked).expect("cache");
    let out = common::final_render(scene, &cache, camera);
    assert!(out.beauty.pixels.iter().all(|p| p.is_finite()));
    out.beauty
}

fn scale_emission(scene: &mut Scene, s: f32) {
    for m in &mut scene.materials {
        if let Some(e) = &mut m.emission {
            e.radiance *= s;
        }
    }
}

/// Emission scaled by 2^±20 (about 1e∓6) scales the path tracer's and the cache's images bit
/// for bit (relative thresholds everywhere, automatic bounces included); by 10^±6, the path
/// tracer's to float rounding (1e-5).
#[test]
fn radiance_scales_exactly() {
    let base = load("cbox-diffuse.gltf");
    let camera = base.default_camera(24, 24).expect("camera");
    let traced = path_traced(&base, &camera, 4);
    let cached = final_render(&base, &camera);
    for (s, exact) in [
        (2f32.powi(-20), true),
        (2f32.powi(20), true),
        (1e-6, false),
        (1e6, false),
    ] {
        let mut scene = base.clone();
        scale_emission(&mut scene, s);
        let mut images = vec![("path tracer", path_traced(&scene, &camera, 4), &traced)];
        // The cache at the binary scales only (each bake costs seconds in CI).
        if exact {
            images.push(("final render", final_render(&scene, &camera), &cached));
        }
        for (what, img, base_img) in images {
            for (a, b) in img.pixels.iter().zip(&base_img.pixels) {
                let expected = *b * s;
                if exact {
                    assert_eq!(*a, expected, "{what} at scale {s}");
                } else {
                    assert!(
                        (*a - expected).abs().max_element() <= 1e-5 * expected.max_element(),
                        "{what} at scale {s}: {a} against {expected}"
                    );
                }
            }
        }
    }
}

/// The scene and its camera scaled by `s` about the origin.
fn scaled(scene: &Scene, s: f32) -> Scene {
    let mut out = scene.clone();
    for m in &mut out.meshes {
        for p in &mut m.positions {
            *p *= s;
        }
    }
    for c in &mut out.cameras {
        c.position *= s;
    }
    out
}

/// Radiance does not depend on units: the scene at 1e-3 and 1e4 of its size renders the image
/// of the unscaled scene, by the path tracer (the same random numbers, so to rounding, except
/// where rounding turns a path) and from the cache.
#[test]
fn scene_scale_from_1e_3_to_1e4() {
    let base = load("cbox-diffuse.gltf");
    let camera = base.default_camera(24, 24).expect("camera");
    let traced = path_traced(&base, &camera, 8);
    let cached = final_render(&base, &camera);
    for s in [1e-3f32, 1e4] {
        let scene = scaled(&base, s);
        let camera = scene.default_camera(24, 24).expect("camera");
        for (what, img, reference) in [
            ("path tracer", path_traced(&scene, &camera, 8), &traced),
            ("final render", final_render(&scene, &camera), &cached),
        ] {
            assert!(img.pixels.iter().all(|p| p.is_finite()));
            let (_, rel) = error_against(&img, reference).expect("same size");
            let (m, r) = (img.mean(), reference.mean());
            eprintln!("scale {s}: {what} relMSE {rel:.2e}, mean {m} against {r}");
            assert!(
                rel < 2e-3,
                "{what} at scale {s}: relMSE {rel} against scale 1"
            );
            assert!(
                ((m - r).abs() / r).max_element() < 0.01,
                "{what} at scale {s}: mean {m} against {r}"
            );
        }
    }
}

/// Zero-area triangles (a repeated vertex, three collinear points) added to every mesh, the
/// light's included, and a coincident copy of the back wall: the path tracer's image is the
/// clean scene's, bit for bit; the cache's is within its own noise.
#[test]
fn degenerate_and_coincident_triangles() {
    let clean = load("cbox-diffuse.gltf");
    let mut dirty = clean.clone();
    for m in &mut dirty.meshes {
        let (a, b) = (m.positions[0], m.positions[1]);
        let n = m.positions.len() as u32;
        m.positions.extend([a, 0.5 * (a + b), b]);
        m.triangles.push([0, 0, 1]);
        m.triangles.push([n, n + 1, n + 2]);
    }
    let back = dirty
        .meshes
        .iter()
        .find(|m| m.name.contains("back"))
        .expect("back wall")
        .clone();
    dirty.meshes.push(Mesh {
        name: "back (copy)".into(),
        ..back
    });
    let camera = clean.default_camera(24, 24).expect("camera");
    assert_eq!(
        path_traced(&dirty, &camera, 4).pixels,
        path_traced(&clean, &camera, 4).pixels
    );
    let (a, b) = (final_render(&dirty, &camera), final_render(&clean, &camera));
    let (_, rel) = error_against(&a, &b).expect("same size");
    eprintln!("degenerate and coincident: final render relMSE {rel:.2e} against the clean scene");
    assert!(rel < 5e-3, "relMSE {rel}");
}

/// Inside a closed box whose walls emit Le and reflect ρ = 0.99 diffusely, the radiance is
/// Le / (1 − ρ) = 100 Le everywhere. The path tracer (Russian roulette, unlimited depth) and
/// the final render from the cache (whose bounces extrapolate the geometric tail) both find
/// it within 3 %.
#[test]
fn albedo_0_99_closed_box() {
    let quads = [
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 5, 7, 3],
        [0, 1, 3, 2],
        [4, 6, 7, 5],
    ];
    let corner = |i: u32| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32);
    let scene = Scene {
        meshes: vec![Mesh {
            name: "box".into(),
            positions: (0..8).map(corner).collect(),
            normals: None,
            uvs: None,
            triangles: quads
                .iter()
                .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
                .collect(),
            material: 0,
        }],
        materials: vec![Material {
            name: "furnace".into(),
            scattering: Scattering::Explicit(Bsdf::Diffuse(Diffuse {
                reflectance: Rgb::splat(0.99),
            })),
            cutout: None,
            normal_map: None,
            emission: Some(Emission {
                radiance: Rgb::ONE,
                texture: None,
                two_sided: false,
            }),
        }],
        ..Default::default()
    };
    let camera = Camera::look_at(
        "inside",
        Vec3::new(0.5, 0.5, 0.9),
        Vec3::new(0.5, 0.5, 0.0),
        1.0,
        16,
        16,
    )
    .expect("camera");
    for (what, img) in [
        ("path tracer", path_traced(&scene, &camera, 64)),
        ("final render", final_render(&scene, &camera)),
    ] {
        assert!(img.pixels.iter().all(|p| p.is_finite()));
        let m = img.mean().x;
        eprintln!("albedo 0.99 box: {what} mean {m}");
        assert!((m - 100.0).abs() < 3.0, "{what}: {m}, expected 100");
    }
}
