//! The thin-walled dielectric (glTF transmission without a volume): its import mapping, its
//! limit against the analytic slab reflectance, reciprocity, and sample/eval/pdf consistency.
//! (Its sampler is also chi-square tested in `bsdf_sampling.rs`.)

mod common;

use common::triangle_gltf;
use glam::{Vec2, Vec3};
use std::path::Path;
use wpbgi::bsdf::fresnel::fresnel_dielectric;
use wpbgi::bsdf::{Bsdf, Distribution, Lobe, Microfacet, ThinDielectric, TransportMode};
use wpbgi::geometry::warp::square_to_uniform_sphere;
use wpbgi::sampler::Sampler;
use wpbgi::scene::Scene;
use wpbgi::spectrum::Rgb;

fn thin(kind: Distribution, au: f32, av: f32, eta: f32) -> Bsdf {
    Bsdf::ThinDielectric(ThinDielectric {
        distr: Microfacet::new(kind, au, av),
        eta,
        specular_reflectance: Rgb::ONE,
        specular_transmittance: Rgb::ONE,
    })
}

/// The BSDF of a glTF material with `extensions`; not metallic (glTF's default metallicFactor
/// is 1, and a metal does not transmit).
fn material_of(extensions: &str) -> Bsdf {
    let tri = [[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]];
    let text = triangle_gltf(
        &tri,
        &[0, 1, 2],
        &format!(
            r#","pbrMetallicRoughness":{{"metallicFactor":0.0,"roughnessFactor":0.5}},"extensions":{{{extensions}}}"#
        ),
    );
    let scene = Scene::from_gltf_bytes(Path::new("thin.gltf"), text.as_bytes()).expect("loads");
    scene.materials[0].bsdf_at(&scene.textures, Vec2::ZERO)
}

#[test]
fn transmission_without_volume_is_thin_walled() {
    let t = r#""KHR_materials_transmission":{"transmissionFactor":1.0}"#;
    assert!(matches!(material_of(t), Bsdf::ThinDielectric(_)));
    let zero = format!(r#"{t},"KHR_materials_volume":{{"thicknessFactor":0.0}}"#);
    assert!(matches!(material_of(&zero), Bsdf::ThinDielectric(_)));
    let solid = format!(r#"{t},"KHR_materials_volume":{{"thicknessFactor":0.3}}"#);
    assert!(matches!(material_of(&solid), Bsdf::Dielectric(_)));
}

/// As α → 0 the slab reflects R' = R + T²R/(1 − R²) of the light (Mitsuba's `thindielectric`);
/// at normal incidence that is 2R/(1 + R) with R = ((η − 1)/(η + 1))².
#[test]
fn smooth_limit_reflects_like_a_slab() {
    let eta = 1.5_f32;
    let r0 = ((eta - 1.0) / (eta + 1.0)).powi(2) as f64;
    for (cos, expected) in [
        (1.0_f32, 2.0 * r0 / (1.0 + r0)),
        (0.5, {
            let r = fresnel_dielectric(0.5, eta).r as f64;
            r + (1.0 - r) * (1.0 - r) * r / (1.0 - r * r)
        }),
    ] {
        let b = thin(Distribution::Ggx, 1e-3, 1e-3, eta);
        for wi in [
            Vec3::new((1.0 - cos * cos).sqrt(), 0.0, cos),
            Vec3::new((1.0 - cos * cos).sqrt(), 0.0, -cos),
        ] {
            let n = 200_000u64;
            let (mut refl, mut trans) = (0.0f64, 0.0f64);
            for i in 0..n {
                let mut s = Sampler::new(3, i, 0);
                let (u0, u) = (s.next_1d(), s.next_2d());
                if let Some(bs) = b.sample(wi, u0, u, TransportMode::Radiance) {
                    let same_side = (bs.wo.z > 0.0) == (wi.z > 0.0);
                    assert_eq!(same_side, bs.lobe == Lobe::Reflection);
                    match bs.lobe {
                        Lobe::Reflection => refl += bs.weight.x as f64,
                        Lobe::Transmission => trans += bs.weight.x as f64,
                    }
                }
            }
            let (refl, trans) = (refl / n as f64, trans / n as f64);
            // Binomial standard error of the reflected fraction; α = 1e-3 moves R' by ~1e-6.
            let se = (expected * (1.0 - expected) / n as f64).sqrt();
            assert!(
                (refl - expected).abs() < 4.0 * se,
                "wi {wi}: reflected {refl}, slab formula {expected} (se {se})"
            );
            assert!(
                (refl + trans - 1.0).abs() < 1e-3,
                "wi {wi}: a smooth slab loses no energy, got {}",
                refl + trans
            );
        }
    }
}

fn random_direction(s: &mut Sampler) -> Vec3 {
    square_to_uniform_sphere(s.next_2d())
}

#[test]
fn reciprocal_and_consistent() {
    let bsdfs = [
        thin(Distribution::Ggx, 0.3, 0.3, 1.5),
        thin(Distribution::Beckmann, 0.1, 0.4, 2.4),
        thin(Distribution::Ggx, 0.05, 0.05, 1.33),
    ];
    let mut s = Sampler::new(9, 0, 0);
    let mut checked = 0;
    for b in &bsdfs {
        for _ in 0..20_000 {
            let wi = random_direction(&mut s);
            let wo = random_direction(&mut s);
            if wi.z.abs() < 0.05 || wo.z.abs() < 0.05 {
                continue;
            }
            // f(wi, wo) = f(wo, wi), where eval carries |cos θo|.
            let f = b.eval(wi, wo, TransportMode::Radiance).x / wo.z.abs();
            let g = b.eval(wo, wi, TransportMode::Radiance).x / wi.z.abs();
            assert!(
                (f - g).abs() <= 1e-4 * f.abs().max(1e-3),
                "{wi} {wo}: {f} vs {g}"
            );
            // Samples: weight = eval/pdf, pdf = pdf(wo). pdf(wo) recomputes the half vector from
            // the rounded wo; at α = 0.05 and |cos| ≥ 0.05 a few ulps of wo move D by up to
            // ~1e-4 relative, so 1e-3 holds every sample while a wrong factor (e.g. a missing
            // lobe probability, ≥ 4 %) cannot pass.
            let (u0, u) = (s.next_1d(), s.next_2d());
            if let Some(bs) = b.sample(wi, u0, u, TransportMode::Radiance) {
                let e = b.eval(wi, bs.wo, TransportMode::Radiance).x;
                let p = b.pdf(wi, bs.wo);
                assert!((p - bs.pdf).abs() <= 1e-3 * p, "pdf {} vs {p}", bs.pdf);
                assert!(
                    (bs.weight.x - e / p).abs() <= 1e-3 * bs.weight.x.max(1e-3),
                    "weight {} vs eval/pdf {}",
                    bs.weight.x,
                    e / p
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 30_000, "{checked} samples checked");
}
