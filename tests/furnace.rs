//! White furnaces (issue 5): a closed box with inward normals and uniform emission Le
//! everywhere.
//!
//! - Diffuse albedo ρ: every point sees Le + ρ·(everything it sees), so the radiance is
//!   Le/(1 − ρ) everywhere; the cache must hold that after its bounces.
//! - A `roughconductor` with `material: none` (Fresnel 1) and specular_reflectance ρ: Mitsuba's
//!   microfacet model scatters once, and the light its masking stops is lost (about 3 % per
//!   bounce at α = 0.1 in this box), so the answer is not Le/(1 − ρ) but what our path tracer
//!   (checked against Mitsuba's images in tests/reference_vs_mitsuba.rs) finds for the same
//!   scene.
//! - Inside a closed room of uniform radiance, a bounce's microbuffers gather exactly π.

mod common;

use glam::Vec3;
use wpbgi::bake::bounce::BounceSettings;
use wpbgi::bake::{bake, BakeSettings, Baked};
use wpbgi::bsdf::{Bsdf, Diffuse, Distribution, Microfacet, RoughConductor};
use wpbgi::haar::direction_to_square;
use wpbgi::scene::{Emission, Material, Mesh, Scattering, Scene};
use wpbgi::spectrum::Rgb;
use wpbgi::surfels::radiance::SurfelRadiance;

/// The unit cube's six faces as one mesh, wound so that the geometric normals point inwards.
fn inward_box() -> Mesh {
    let c = |i: u32| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32);
    let positions: Vec<Vec3> = (0..8).map(c).collect();
    // Each face as a quad (a, b, c, d) in order round it, seen from inside.
    let quads = [
        [0, 4, 5, 1], // y = 0, normal +y
        [2, 3, 7, 6], // y = 1, normal −y
        [0, 2, 6, 4], // x = 0, normal +x
        [1, 5, 7, 3], // x = 1, normal −x
        [0, 1, 3, 2], // z = 0, normal +z
        [4, 6, 7, 5], // z = 1, normal −z
    ];
    let mut triangles = Vec::new();
    for [a, b, cc, d] in quads {
        triangles.push([a, b, cc]);
        triangles.push([a, cc, d]);
    }
    Mesh {
        name: "box".into(),
        positions,
        normals: None,
        uvs: None,
        triangles,
        material: 0,
    }
}

fn furnace(rho: f32, le: f32) -> Scene {
    Scene {
        meshes: vec![inward_box()],
        materials: vec![Material {
            name: "furnace".into(),
            scattering: Scattering::Explicit(Bsdf::Diffuse(Diffuse {
                reflectance: Rgb::splat(rho),
            })),
            cutout: None,
            normal_map: None,
            emission: Some(Emission {
                radiance: Rgb::splat(le),
                texture: None,
                two_sided: false,
            }),
        }],
        ..Default::default()
    }
}

/// The furnace with a `roughconductor` of roughness `alpha`, `material: none` (η = 0, k = 1).
fn conductor_furnace(rho: f32, le: f32, alpha: f32) -> Scene {
    let mut scene = furnace(rho, le);
    scene.materials[0].scattering = Scattering::Explicit(Bsdf::Conductor(RoughConductor {
        distr: Microfacet::new(Distribution::Ggx, alpha, alpha),
        eta: Rgb::ZERO,
        k: Rgb::ONE,
        specular_reflectance: Rgb::splat(rho),
    }));
    scene
}

const CENTRE: Vec3 = Vec3::splat(0.5);

/// The furnace baked with 3 000 surfels and automatic bounces on `threads` threads.
fn bake_furnace(scene: &Scene, threads: usize) -> Baked {
    let settings = BakeSettings {
        points: 3000,
        light_samples: 64,
        bounces: BounceSettings::auto(),
        ..BakeSettings::preset(wpbgi::bake::Quality::Draft).direct_only()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    pool.install(|| bake(scene, &settings, &|_, _| {}).expect("bake"))
}

/// Surfel `i`'s cached radiance towards the centre of the box.
fn radiance_towards_centre(baked: &Baked, i: usize) -> Rgb {
    let s = &baked.surfels[i];
    match &baked.radiance[i] {
        SurfelRadiance::Rgb(c) => *c,
        SurfelRadiance::Map(m) => {
            let p = direction_to_square((CENTRE - s.p).normalize());
            m.eval(p.x, p.y)
        }
    }
}

/// Surfel `i`'s cached radiance (red) towards the centre of the box.
fn towards_centre(baked: &Baked, i: usize) -> f64 {
    f64::from(radiance_towards_centre(baked, i).x)
}

/// The area-weighted mean of [`radiance_towards_centre`], red, green and blue.
fn mean_radiance_rgb(baked: &Baked) -> [f64; 3] {
    let (mut sum, mut area) = ([0.0f64; 3], 0.0f64);
    for (i, s) in baked.surfels.iter().enumerate() {
        let l = radiance_towards_centre(baked, i).to_array();
        for c in 0..3 {
            sum[c] += f64::from(l[c]) * f64::from(s.area);
        }
        area += f64::from(s.area);
    }
    sum.map(|x| x / area)
}

/// The area-weighted mean of [`towards_centre`].
fn mean_radiance(baked: &Baked) -> f64 {
    mean_radiance_rgb(baked)[0]
}

/// Diffuse furnaces at ρ = 0.5, 0.9 and 0.99: within 1 %, 1 % and 2 % of Le/(1 − ρ) with at
/// most 30 explicit bounces, the stiff one by its extrapolated tail, whose ratio is ρ. At
/// ρ = 0.5, the same cache for 1 and 2 threads.
///
/// Measured (3 000 surfels): +0.14 %, +0.29 %, +0.45 %, each after 4 bounces (the ratios
/// settle at once), the last bounce ratio at 0.99 0.98999 (+0.13 %, +0.23 %, +0.18 % before
/// mixed pixels were traced and the rendering's bright pixels were; the diffuse receivers'
/// traced pixels read the nearest surfel's light, not the cut's). Before the gather was made exact
/// (this commit's history: straddling nodes, horizon texels, solid-angle light sampling) the
/// same furnaces measured −1.7 %, −8.9 % and −49 %.
#[test]
fn diffuse_furnace_holds_le_over_one_minus_rho() {
    for (rho, tolerance) in [(0.5f32, 0.01), (0.9, 0.01), (0.99, 0.01)] {
        let expected = 1.0 / (1.0 - f64::from(rho));
        let baked = bake_furnace(&furnace(rho, 1.0), 2);
        let report = baked.bounces.clone().unwrap_or_default();
        let err = mean_radiance(&baked) / expected - 1.0;
        eprintln!("diffuse ρ = {rho}: {:+.2} %; {report:?}", 100.0 * err);
        assert!(err.abs() <= tolerance, "ρ = {rho}: {:+.2} %", 100.0 * err);
        assert!(report.bounces >= 3 && report.bounces <= 30);
        if rho == 0.99 {
            let [tail, ..] = report.extrapolated.expect("an extrapolated tail");
            let e = &report.energies;
            let r = e[e.len() - 1] / e[e.len() - 2];
            assert!((tail - r / (1.0 - r)).abs() < 1e-9 * tail);
            assert!((r / 0.99 - 1.0).abs() < 1e-3, "bounce ratio {r}");
        }
        if rho == 0.5 {
            let one = bake_furnace(&furnace(rho, 1.0), 1);
            assert!(
                one.radiance == baked.radiance,
                "the bounces depend on the thread count"
            );
        }
    }
}

/// A coloured diffuse furnace, ρ = (0.95, 0.6, 0.3): each channel within 1 % of its own
/// Le/(1 − ρ) (20, 2.5, 1.43). Its channels shrink at their own rates, ρ each, so the tail of
/// the bounces left is each channel's own: one tail from the luminance's ratio (0.945 where
/// the bounces settled) left red 4.1 % dark.
///
/// Measured: +0.30 %, +0.17 %, +0.08 % after 12 bounces, the tails' ratios 0.9500, 0.6000,
/// 0.3000.
#[test]
fn coloured_furnace_holds_each_channels_le_over_one_minus_rho() {
    let rho = [0.95f32, 0.6, 0.3];
    let mut scene = furnace(0.5, 1.0);
    scene.materials[0].scattering = Scattering::Explicit(Bsdf::Diffuse(Diffuse {
        reflectance: Rgb::from(rho),
    }));
    let baked = bake_furnace(&scene, 2);
    let report = baked.bounces.clone().unwrap_or_default();
    let mean = mean_radiance_rgb(&baked);
    let tail = report.extrapolated.expect("an extrapolated tail");
    for c in 0..3 {
        let expected = 1.0 / (1.0 - f64::from(rho[c]));
        let err = mean[c] / expected - 1.0;
        let ratio = tail[c] / (1.0 + tail[c]);
        eprintln!(
            "channel {c}: {:+.2} % of {expected:.3}, tail ratio {ratio:.4}",
            100.0 * err
        );
        assert!(err.abs() <= 0.01, "channel {c}: {:+.2} %", 100.0 * err);
        assert!(
            (ratio / f64::from(rho[c]) - 1.0).abs() < 1e-2,
            "channel {c}'s tail ratio {ratio}"
        );
    }
    eprintln!("{report:?}");
}

/// Conductor furnaces (α = 0.1, `material: none`) at ρ = 0.5, 0.9 and 0.99 against the path
/// tracer: the mean cached radiance of every surfel towards the box's centre against
/// [`PATHS`] paths from the centre through each, within 1 % each. The path tracer's own
/// standard error is under a quarter of the tolerance (asserted).
///
/// Measured: +0.16 %, −0.15 %, +0.40 % (the path tracer's standard error 0.05 %, 0.19 %,
/// 0.22 %); the furnace holds 1.96, 8.0 and 26 where Le/(1 − ρ) is 2, 10 and 100. Before the
/// receivers' light was summed over the bounces and turned into outgoing radiance once,
/// +0.17 %, +0.03 % and +1.14 % (ρ = 0.99's bound was 2 % then); with the light sent between
/// bounces thresholded at 5× the cache's threshold but its flux not kept, ρ = 0.9 fell to
/// −3.3 %. Before the operator's output was scaled to its albedo's flux, and before the
/// gather was exact, the same furnaces measured +1.3 %, +8.8 % and +35 %.
#[test]
fn conductor_furnace_matches_the_path_tracer() {
    const PATHS: u32 = 64;
    for (rho, tolerance) in [(0.5f32, 0.01), (0.9, 0.01), (0.99, 0.01)] {
        let scene = conductor_furnace(rho, 1.0, 0.1);
        let baked = bake_furnace(&scene, 2);
        let settings = wpbgi::reference::RenderSettings {
            max_depth: -1,
            ..Default::default()
        };
        let ctx = settings.context(&scene);
        let (mut ours, mut sum, mut sum2, mut count) = (0.0f64, 0.0f64, 0.0f64, 0u32);
        for (i, s) in baked.surfels.iter().enumerate() {
            ours += towards_centre(&baked, i);
            let d = (s.p - CENTRE).normalize();
            let mut sampler = wpbgi::sampler::Sampler::new(7, i as u64, 0);
            for _ in 0..PATHS {
                let l = f64::from(wpbgi::reference::radiance(&ctx, CENTRE, d, &mut sampler).x);
                sum += l;
                sum2 += l * l;
                count += 1;
            }
        }
        let n = f64::from(count);
        let reference = sum / n;
        let standard_error = ((sum2 / n - reference * reference) / n).sqrt() / reference;
        let ours = ours / f64::from(count / PATHS);
        let err = ours / reference - 1.0;
        eprintln!(
            "conductor ρ = {rho}: cache {ours:.4}, path tracer {reference:.4} (± {:.2} %): \
             {:+.2} %; {:?}",
            100.0 * standard_error,
            100.0 * err,
            baked.bounces
        );
        assert!(standard_error < tolerance / 4.0);
        assert!(err.abs() <= tolerance, "ρ = {rho}: {:+.2} %", 100.0 * err);
        // Not Le/(1 − ρ): the BSDF loses light.
        assert!(reference < 0.99 / (1.0 - f64::from(rho)));
    }
}

/// Inside a closed room whose every surfel sends radiance 1 (towards its front), the
/// surfels' microbuffers, as a bounce builds them, gather irradiance π: for diffuse surfels
/// (RGB) and for conductor surfels (16² sphere maps). Measured with 3 000 surfels: 1.0000 π
/// for both, also on surfels near an edge. Before, 0.991 π (diffuse) and 0.992 π (maps):
/// nodes straddling the receiver's plane were seen from behind, maps' texels straddling the
/// horizon read black, and a node's I and P came from texels of different sizes.
#[test]
fn closed_room_gathers_pi() {
    for scene in [furnace(0.5, 1.0), conductor_furnace(0.5, 1.0, 0.1)] {
        let settings = BakeSettings {
            points: 3000,
            ..BakeSettings::preset(wpbgi::bake::Quality::Draft).direct_only()
        };
        let (baked, gathered) = uniform_gather(&scene, &settings, 1);
        let (mut all, mut edges) = ((0.0f64, 0u32), (0.0f64, 0u32));
        for (s, e) in baked.surfels.iter().zip(&gathered) {
            // The distance to the nearest other face of the room.
            let edge = (0..3)
                .filter(|&a| s.n[a].abs() < 0.5)
                .map(|a| s.p[a].min(1.0 - s.p[a]))
                .fold(f32::INFINITY, f32::min);
            all = (all.0 + e, all.1 + 1);
            if edge < 0.15 {
                edges = (edges.0 + e, edges.1 + 1);
            }
        }
        let (mean, near_edges) = (all.0 / f64::from(all.1), edges.0 / f64::from(edges.1));
        eprintln!("irradiance / π: mean {mean:.5}, within 0.15 of an edge {near_edges:.5}");
        assert!((mean - 1.0).abs() < 2e-3, "{mean}");
        assert!((near_edges - 1.0).abs() < 2e-3, "{near_edges}");
    }
}

/// In the open Cornell box (cbox-diffuse) with every surfel sending radiance 1 towards its
/// front, a surfel gathers π times the cosine-weighted fraction of its hemisphere whose rays
/// hit a front face (1 024 rays each, for every tenth surfel not under a closed box, where it
/// is dark anyway). Per mesh, the ratio is within 2 % of 1. Measured: 1.005–1.013 (0.994–1.017
/// before mixed pixels were traced). Before the back faces of the closed boxes were hidden
/// from receivers outside them, the floor and the walls gathered 0.88–0.95: the back faces'
/// black splats filled the gaps between the front faces'. (Rays that hit a back face, the
/// lamp's top seen from the ceiling, bring nothing: counting them, the ceiling read 0.979.)
#[test]
fn open_room_gathers_what_its_rays_hit() {
    let scene = Scene::load(&common::mitsuba_data("cbox-diffuse.gltf")).expect("scene");
    let settings = BakeSettings::preset(wpbgi::bake::Quality::Draft).direct_only();
    let (baked, gathered) = uniform_gather(&scene, &settings, 10);
    let boxes: Vec<Option<(Vec3, Vec3)>> = scene
        .meshes
        .iter()
        .map(|m| {
            m.is_closed().then(|| {
                m.positions
                    .iter()
                    .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
                        (lo.min(p), hi.max(p))
                    })
            })
        })
        .collect();
    // Within the bounds of another closed mesh.
    let inside = |p: Vec3, mesh: u32| {
        boxes.iter().enumerate().any(|(m, b)| {
            b.is_some_and(|(lo, hi)| {
                m != mesh as usize && p.cmpge(lo - 1e-3).all() && p.cmple(hi + 1e-3).all()
            })
        })
    };
    let ctx = wpbgi::trace::Tracer::new(&scene);
    let mut per_mesh = vec![(0.0f64, 0.0f64); scene.meshes.len()];
    for (i, (s, e)) in baked.surfels.iter().zip(&gathered).enumerate().step_by(10) {
        if inside(s.p, s.mesh) {
            continue;
        }
        let frame = wpbgi::geometry::frame::Frame::from_normal(s.n);
        let mut sampler = wpbgi::sampler::Sampler::new(3, i as u64, 0);
        let hits = (0..1024)
            .filter(|_| {
                let u = sampler.next_2d();
                let w = frame.to_world(wpbgi::geometry::warp::square_to_cosine_hemisphere(u));
                wpbgi::trace::intersect(&ctx, s.p + s.n * 1e-4, w)
                    .is_some_and(|h| h.ng.dot(w) < 0.0)
            })
            .count();
        let m = &mut per_mesh[s.mesh as usize];
        *m = (m.0 + e, m.1 + hits as f64 / 1024.0);
    }
    for (mesh, (ours, rays)) in scene.meshes.iter().zip(per_mesh) {
        if rays == 0.0 {
            continue;
        }
        eprintln!("{}: gathered / hit {:.4}", mesh.name, ours / rays);
        assert!(
            (ours / rays - 1.0).abs() < 0.02,
            "{}: {}",
            mesh.name,
            ours / rays
        );
    }
}

/// Bake `scene` with `settings`, set every surfel's radiance to 1 towards its front, and
/// gather, for every `step`-th surfel (0 for the others), the irradiance / π that its
/// microbuffer collects as a bounce builds it.
fn uniform_gather(scene: &Scene, settings: &BakeSettings, step: usize) -> (Baked, Vec<f64>) {
    use wpbgi::bake::bounce::iterate::close_buffer;
    use wpbgi::gather::cut::splat_cut;
    use wpbgi::gather::microbuffer::Microbuffer;
    use wpbgi::gather::senders::Senders;
    use wpbgi::geometry::frame::Frame;
    use wpbgi::haar::{texel_directions, Haar2d, SparseHaar};
    use wpbgi::surfels::radiance::intensity_map;
    let settings = BakeSettings {
        light_samples: 4,
        bounces: BounceSettings::exactly(0),
        ..settings.clone()
    };
    let mut baked = bake(scene, &settings, &|_, _| {}).expect("bake");
    let levels = baked.plan.map_levels;
    for (r, s) in baked.radiance.iter_mut().zip(&baked.surfels) {
        *r = match r {
            SurfelRadiance::Rgb(_) => SurfelRadiance::Rgb(Rgb::ONE),
            SurfelRadiance::Map(m) => {
                let l = m.levels();
                let texels: Vec<Rgb> = texel_directions(l)
                    .iter()
                    .map(|w| Rgb::splat(if w.dot(s.n) > 0.0 { 1.0 } else { 0.0 }))
                    .collect();
                SurfelRadiance::Map(SparseHaar::compress(&Haar2d::forward(&texels, 1 << l), 0.0))
            }
        };
    }
    baked.emitted.fill(Rgb::ZERO);
    let leaf = |i: u32| {
        let s = &baked.surfels[i as usize];
        intensity_map(s.n, s.area, &baked.radiance[i as usize], true)
    };
    baked.coded = wpbgi::surfels::coding::encode(
        &baked.tree,
        &leaf,
        levels,
        baked.coded.split_level,
        settings.tau,
    );
    let cache = wpbgi::bake::store::in_memory("furnace".as_ref(), &baked).expect("cache");
    let senders = Senders::from_cache(&cache).expect("senders");
    let accel = wpbgi::accel::Accel::build(scene);
    let mut stack = Vec::new();
    let n = if levels > 3 { 1 << levels } else { 16 };
    let gathered = baked
        .surfels
        .iter()
        .enumerate()
        .map(|(i, s)| {
            if i % step != 0 {
                return 0.0;
            }
            let mut mb = Microbuffer::new(n, false, Frame::from_normal(s.n));
            mb.record_links();
            splat_cut(&senders, s.p, s.mesh, &mut mb, &[0], &mut stack);
            mb.resolve();
            let diffuse = matches!(baked.radiance[i], SurfelRadiance::Rgb(_));
            close_buffer(&senders, (&accel, scene), (s, diffuse), &mut mb);
            mb.cos_radiance
                .iter()
                .zip(&mb.pixels)
                .map(|(l, p)| f64::from(l.x * p.solid_angle))
                .sum::<f64>()
                / std::f64::consts::PI
        })
        .collect();
    (baked, gathered)
}
