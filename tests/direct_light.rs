//! Direct light at surfels against closed forms (issue 3 acceptance): a diffuse surfel under a
//! rectangle and under a disk light, against Lambert's exact polygon irradiance; a rough
//! conductor surfel under a small light, against the BSDF integrated over the light.

use glam::{Vec2, Vec3};
use wpbgi::accel::Accel;
use wpbgi::bake::DirectLight;
use wpbgi::bsdf::{Bsdf, Diffuse, Distribution, Microfacet, RoughConductor, TransportMode};
use wpbgi::emitters::{ClosedFormLight, EmitterSampler, CLOSED_FORM_TRIANGLES};
use wpbgi::geometry::frame::Frame;
use wpbgi::haar::{
    direction_to_square, square_to_direction, texel_centre, texel_of, Haar2d, SparseHaar,
};
use wpbgi::scene::{Emission, LightKind, Material, Mesh, PunctualLight, Scattering, Scene};
use wpbgi::spectrum::Rgb;
use wpbgi::surfels::Surfel;

const LE: f32 = 3.0;

/// A receiver triangle whose centroid is the origin, facing +z, and an emitting polygon (a fan
/// around its first vertex) facing the receiver.
fn scene(polygon: &[Vec3], receiver: Bsdf) -> Scene {
    let receiver_mesh = Mesh {
        name: "receiver".into(),
        positions: vec![
            Vec3::new(-0.01, -0.01, 0.0),
            Vec3::new(0.02, -0.01, 0.0),
            Vec3::new(-0.01, 0.02, 0.0),
        ],
        normals: None,
        uvs: None,
        triangles: vec![[0, 1, 2]],
        material: 0,
    };
    let n = polygon.len() as u32;
    let light = Mesh {
        name: "light".into(),
        positions: polygon.to_vec(),
        normals: None,
        uvs: None,
        triangles: (1..n - 1).map(|i| [0, i, i + 1]).collect(),
        material: 1,
    };
    Scene {
        meshes: vec![receiver_mesh, light],
        materials: vec![
            Material {
                name: "receiver".into(),
                scattering: Scattering::Explicit(receiver),
                cutout: None,
                normal_map: None,
                emission: None,
            },
            Material {
                name: "light".into(),
                scattering: Scattering::Explicit(Bsdf::Diffuse(Diffuse {
                    reflectance: Rgb::ZERO,
                })),
                cutout: None,
                normal_map: None,
                emission: Some(Emission {
                    radiance: Rgb::splat(LE),
                    texture: None,
                    two_sided: false,
                }),
            },
        ],
        ..Default::default()
    }
}

fn surfel() -> Surfel {
    Surfel {
        p: Vec3::ZERO,
        n: Vec3::Z,
        area: 1e-4,
        mesh: 0,
        triangle: 0,
        b: Vec2::splat(1.0 / 3.0),
    }
}

/// Lambert's formula: the irradiance at the origin (normal +z) from a polygon of radiance L
/// entirely above the horizon, E = L/2 Σ Θᵢ n·(vᵢ × vᵢ₊₁)/|vᵢ × vᵢ₊₁|.
fn polygon_irradiance(poly: &[Vec3], l: f64) -> f64 {
    let v: Vec<_> = poly.iter().map(|p| p.as_dvec3().normalize()).collect();
    let mut sum = 0.0;
    for i in 0..v.len() {
        let (a, b) = (v[i], v[(i + 1) % v.len()]);
        let c = a.cross(b);
        sum += a.dot(b).clamp(-1.0, 1.0).acos() * c.z / c.length();
    }
    0.5 * l * sum.abs()
}

/// Wind `poly` so its front face (counter-clockwise) looks at the origin.
fn facing_origin(mut poly: Vec<Vec3>) -> Vec<Vec3> {
    let n = (poly[1] - poly[0]).cross(poly[2] - poly[0]);
    if n.dot(-poly[0]) < 0.0 {
        poly.reverse();
    }
    poly
}

/// Run `f` with direct lighting of `sc` (no light tree) at `samples` samples per surfel.
fn with_direct<R>(sc: &Scene, samples: u32, seed: u64, f: impl FnOnce(&DirectLight) -> R) -> R {
    let accel = Accel::build(sc);
    let emitters = EmitterSampler::new(sc);
    f(&DirectLight {
        scene: sc,
        accel: &accel,
        emitters: &emitters,
        samples,
        seed,
        light_tree: None,
        max_cut: 1000,
    })
}

fn irradiance(poly: &[Vec3], samples: u32) -> f32 {
    let sc = scene(
        poly,
        Bsdf::Diffuse(Diffuse {
            reflectance: Rgb::splat(0.5),
        }),
    );
    with_direct(&sc, samples, 7, |d| {
        d.irradiance(&surfel(), surfel().n, 0).x
    })
}

/// A 1 × 0.6 rectangle light, off-axis and tilted by 25° about x, facing the origin.
fn tilted_rectangle() -> Vec<Vec3> {
    let (c, s) = (25f32.to_radians().cos(), 25f32.to_radians().sin());
    let corner = |x: f32, y: f32| Vec3::new(0.3 + x, -0.2 + y * c, 1.0 + y * s);
    facing_origin(vec![
        corner(-0.5, -0.3),
        corner(0.5, -0.3),
        corner(0.5, 0.3),
        corner(-0.5, 0.3),
    ])
}

#[test]
fn diffuse_surfel_under_a_rectangle_light() {
    let rect = tilted_rectangle();
    let exact = polygon_irradiance(&rect, LE as f64);
    let ours = irradiance(&rect, 1024) as f64;
    eprintln!(
        "rectangle: {ours} vs {exact} ({:+.3} %)",
        100.0 * (ours / exact - 1.0)
    );
    assert!((ours / exact - 1.0).abs() < 0.005);
}

/// A surfel's point and directional lights come in once each and exactly, beside an area
/// light drawn by its samples: under a rectangle that faces away (it sends the surfel nothing
/// but takes its share of the samples), the irradiance is I cos θ / d² + E cos θ for every
/// count of samples and every seed. Drawn among the samples by power, the point light took a
/// whole number of them near its share, one more or fewer from surfel to surfel.
#[test]
fn delta_lights_beside_an_area_light_are_exact_at_a_surfel() {
    let mut away = tilted_rectangle();
    away.reverse();
    let mut sc = scene(
        &away,
        Bsdf::Diffuse(Diffuse {
            reflectance: Rgb::splat(0.5),
        }),
    );
    let bulb = Vec3::new(0.4, -0.3, 0.8);
    let sun = Vec3::new(0.2, 0.1, -1.0).normalize();
    sc.lights = vec![
        PunctualLight {
            name: "bulb".into(),
            kind: LightKind::Point,
            position: bulb,
            direction: -Vec3::Z,
            intensity: Rgb::splat(0.5),
        },
        PunctualLight {
            name: "sun".into(),
            kind: LightKind::Directional,
            position: Vec3::ZERO,
            direction: sun,
            intensity: Rgb::splat(0.7),
        },
    ];
    let exact = 0.5 * bulb.z / bulb.length().powi(3) + 0.7 * -sun.z;
    for samples in [4, 8, 32] {
        for seed in 0..8 {
            let ours = with_direct(&sc, samples, seed, |d| {
                d.irradiance(&surfel(), surfel().n, 0).x
            });
            assert!(
                (ours / exact - 1.0).abs() < 1e-5,
                "{samples} samples, seed {seed}: {ours} vs {exact}"
            );
        }
    }
}

#[test]
fn diffuse_surfel_under_a_disk_light() {
    // A 96-gon of radius 0.5 (Lambert's formula is exact for the polygon itself).
    let disk: Vec<Vec3> = (0..96)
        .map(|i| {
            let a = i as f32 / 96.0 * std::f32::consts::TAU;
            Vec3::new(-0.2 + 0.5 * a.cos(), 0.1 + 0.5 * a.sin(), 0.8)
        })
        .collect();
    let disk = facing_origin(disk);
    let exact = polygon_irradiance(&disk, LE as f64);
    let ours = irradiance(&disk, 1024) as f64;
    eprintln!(
        "disk: {ours} vs {exact} ({:+.3} %)",
        100.0 * (ours / exact - 1.0)
    );
    assert!((ours / exact - 1.0).abs() < 0.005);
}

/// The render's closed form of a few constant emitting triangles (its diffuse hits' unshadowed
/// direct light) is Lambert's formula: the tilted rectangle and a 12-gon, against this file's
/// own evaluation in double precision; seen from behind, a one-sided light gives nothing. A
/// textured emission, an environment or more than [`CLOSED_FORM_TRIANGLES`] triangles have
/// none.
#[test]
fn closed_form_light_is_lamberts_formula() {
    let rect = tilted_rectangle();
    let gon = |n: usize| -> Vec<Vec3> {
        let ring = (0..n).map(|i| {
            let a = i as f32 / n as f32 * std::f32::consts::TAU;
            Vec3::new(-0.2 + 0.5 * a.cos(), 0.1 + 0.5 * a.sin(), 0.8)
        });
        facing_origin(ring.collect())
    };
    let diffuse = || {
        Bsdf::Diffuse(Diffuse {
            reflectance: Rgb::splat(0.5),
        })
    };
    for poly in [rect.clone(), gon(12)] {
        let light = ClosedFormLight::of(&scene(&poly, diffuse())).expect("a closed form");
        let ours = light.irradiance(Vec3::ZERO, Vec3::Z).x as f64;
        let exact = polygon_irradiance(&poly, LE as f64);
        assert!((ours / exact - 1.0).abs() < 1e-6, "{ours} vs {exact}");
        // The same light from above it: its back.
        assert_eq!(
            light.irradiance(Vec3::new(0.0, 0.0, 3.0), -Vec3::Z),
            Rgb::ZERO
        );
    }
    // On the light's own plane, inside one of its triangles and beside it (a light flush
    // with a ceiling), facing its way or the other: nothing, as the emitter samples find, not
    // Lambert's π (undefined there). A hair off the plane is still on it.
    let light = ClosedFormLight::of(&scene(&rect, diffuse())).expect("a closed form");
    let (u, v) = (rect[1] - rect[0], rect[3] - rect[0]);
    let normal = u.cross(v).normalize();
    for (a, b) in [(0.3, 0.4), (1.5, 0.5), (-0.5, -0.5)] {
        let on = rect[0] + a * u + b * v;
        for p in [on, on + normal * 1e-7, on - normal * 1e-7] {
            for n in [normal, -normal] {
                assert_eq!(light.irradiance(p, n), Rgb::ZERO, "at {p}, facing {n}");
            }
        }
    }
    let mut textured = scene(&rect, diffuse());
    if let Some(e) = &mut textured.materials[1].emission {
        e.texture = Some(wpbgi::scene::TexRef {
            texture: 0,
            wrap_s: wpbgi::scene::Wrap::Repeat,
            wrap_t: wpbgi::scene::Wrap::Repeat,
            transform: glam::Affine2::IDENTITY,
            srgb: true,
            scale: glam::Vec4::ONE,
            bias: glam::Vec4::ZERO,
        });
    }
    assert!(ClosedFormLight::of(&textured).is_none());
    let mut lit = scene(&rect, diffuse());
    lit.environment = Some(wpbgi::scene::Environment::constant(Rgb::ONE));
    assert!(ClosedFormLight::of(&lit).is_none());
    assert!(ClosedFormLight::of(&scene(&gon(CLOSED_FORM_TRIANGLES + 3), diffuse())).is_none());
}

/// A rough conductor under a small square light: the radiance map's value towards the mirror
/// direction, after wavelet compression, equals the BSDF integrated over the light (by a 64 × 64
/// midpoint rule, independent of the sampler) within 0.5 % plus the compression bound.
#[test]
fn rough_conductor_surfel_under_a_small_light() {
    let bsdf = Bsdf::Conductor(RoughConductor {
        distr: Microfacet::new(Distribution::Ggx, 0.2, 0.2),
        eta: Rgb::ZERO,
        k: Rgb::ONE,
        specular_reflectance: Rgb::ONE,
    });
    let dir = Vec3::new(0.5, 0.0, 0.866).normalize();
    let frame = Frame::from_normal(dir);
    let half = 0.01;
    let square: Vec<Vec3> = [(-1., -1.), (1., -1.), (1., 1.), (-1., 1.)]
        .iter()
        .map(|(a, b)| dir + (frame.s * *a + frame.t * *b) * half)
        .collect();
    let square = facing_origin(square);
    let sc = scene(&square, bsdf);
    let n = 64u32;
    let map = with_direct(&sc, 1024, 3, |d| {
        d.radiance_map((&surfel(), surfel().n), 0, &bsdf, n.trailing_zeros())
    });
    let mirror = Vec3::new(-dir.x, -dir.y, dir.z);
    let (tx, ty) = texel_of(mirror, n);
    let centre = square_to_direction(texel_centre(ty * n + tx, n));
    // The expected value: f(centre, ω) |cos| Lₑ integrated over the light's area.
    let m = 64;
    let mut expected = 0.0f64;
    for i in 0..m {
        for j in 0..m {
            let (a, b) = (
                (i as f32 + 0.5) / m as f32 * 2.0 - 1.0,
                (j as f32 + 0.5) / m as f32 * 2.0 - 1.0,
            );
            let q = dir + (frame.s * a + frame.t * b) * half;
            let w = q.normalize();
            let d2 = q.length_squared();
            let da = (2.0 * half / m as f32).powi(2);
            let solid = da * w.dot(dir).abs() / d2;
            let f = bsdf.eval(centre, w, TransportMode::Radiance).x;
            expected += (f * LE * solid) as f64;
        }
    }
    let h = Haar2d::forward(&map, n as usize);
    let tau = 1e-3;
    let sparse = SparseHaar::compress(&h, tau);
    let p = direction_to_square(centre);
    let ours = sparse.eval(p.x, p.y).x as f64;
    // Point error bound from the threshold: every dropped coefficient has magnitude below
    // τ‖f‖₂, and at a point at most 3 basis functions per level are non-zero, each of size 2^l,
    // so |Δf(x)| ≤ 3 (2^J − 1) τ ‖f‖₂ (J = log2 N).
    let norm: f64 = std::iter::once(h.scale)
        .chain(h.details.iter().flat_map(|d| d.iter().copied()))
        .map(|c| (c.abs().max_element() as f64).powi(2))
        .sum::<f64>()
        .sqrt();
    let bound = 3.0 * (n as f64 - 1.0) * tau as f64 * norm;
    eprintln!(
        "mirror radiance: {ours} vs {expected} ({:+.3} %), compression bound {bound:.3e}, {} of {} coefficients kept",
        100.0 * (ours / expected - 1.0),
        sparse.coefficient_count(),
        1 + 3 * h.details.len()
    );
    assert!((ours - expected).abs() <= 0.005 * expected + bound);
    // The bound must leave the test its teeth.
    assert!(bound < 0.05 * expected, "bound {bound} vs value {expected}");
}
