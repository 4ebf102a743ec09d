//! White furnace (issue 5): a closed box with inward normals, diffuse albedo ρ and uniform
//! emission Le everywhere. Every point sees Le + ρ·(everything it sees), so the radiance is
//! Le/(1 − ρ) everywhere: the cache must hold that after its bounces.

use glam::Vec3;
use wpbgi::bake::{bake, BakeSettings, SurfelRadiance};
use wpbgi::bounce::{BounceReport, BounceSettings};
use wpbgi::bsdf::{Bsdf, Diffuse};
use wpbgi::scene::{Emission, Material, Mesh, Scattering, Scene};
use wpbgi::spectrum::Rgb;

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
            emission: Some(Emission {
                radiance: Rgb::splat(le),
                texture: None,
                two_sided: false,
            }),
        }],
        ..Default::default()
    }
}

/// The area-weighted mean cached radiance, and the bounce report.
fn cached_radiance(
    scene: &Scene,
    bounces: BounceSettings,
    threads: usize,
) -> (f64, BounceReport, Vec<f32>) {
    let settings = BakeSettings {
        points: 3000,
        light_samples: 64,
        bounces,
        ..BakeSettings::from_quality(wpbgi::bake::Quality::Draft)
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    let baked = pool.install(|| bake(scene, &settings, &|_, _| {}).expect("bake"));
    let (mut sum, mut area) = (0.0f64, 0.0f64);
    let mut values = Vec::new();
    for (s, r) in baked.surfels.iter().zip(&baked.radiance) {
        let SurfelRadiance::Rgb(c) = r else {
            panic!("diffuse surfels hold RGB");
        };
        sum += f64::from(c.x * s.area);
        area += f64::from(s.area);
        values.push(c.x);
    }
    (sum / area, baked.bounces.unwrap_or_default(), values)
}

/// ρ = 0.5: within 2.5 % of Le/(1 − ρ) with 3 000 surfels, the same cache for 1 and 2 threads.
///
/// The issue asks for 1 % at ρ = 0.5 and 0.9 and 2 % at 0.99; measured now (`furnace_table`):
/// −1.7 %, −8.9 %, −49 %. Each bounce loses about 1 % (the gather of a closed room, below) and
/// the direct light near the edges 1 %; a stiff scene multiplies the first. That target is
/// open, and this bound guards what is reached.
#[test]
fn diffuse_furnace_at_half_albedo() {
    let (rho, le) = (0.5f32, 1.0f32);
    let expected = f64::from(le / (1.0 - rho));
    let (mean, report, one) = cached_radiance(&furnace(rho, le), BounceSettings::auto(), 1);
    let err = mean / expected - 1.0;
    eprintln!(
        "ρ = {rho}: mean {mean:.4}, expected {expected:.4} ({:+.2} %); {report:?}",
        100.0 * err
    );
    assert!(err.abs() <= 0.025, "{:+.2} %", 100.0 * err);
    assert!(report.bounces >= 3 && report.bounces <= 30);
    let (_, _, two) = cached_radiance(&furnace(rho, le), BounceSettings::auto(), 2);
    assert!(one == two, "the bounces depend on the thread count");
}

/// A stiff furnace (ρ = 0.99) stops within 30 explicit bounces with the geometric tail
/// extrapolated, and its bounce energies fall at a steady ratio near ρ.
#[test]
fn stiff_furnace_extrapolates_its_tail() {
    let (_, report, _) = cached_radiance(&furnace(0.99, 1.0), BounceSettings::auto(), 2);
    eprintln!("{report:?}");
    assert!(report.bounces <= 30);
    let tail = report.extrapolated.expect("an extrapolated tail");
    let e = &report.energies;
    let r = e[e.len() - 1] / e[e.len() - 2];
    assert!((tail - r / (1.0 - r)).abs() < 1e-9 * tail);
    // Every bounce keeps 0.99 of the light less what the gather loses (1 %, see above).
    assert!(r > 0.97 && r < 0.99, "ratio {r}");
}

/// Inside a closed room whose every surfel sends radiance 1, the surfels' microbuffers (as a
/// bounce builds them) gather irradiance π. Measured with 3 000 surfels: a mean of 0.991 π,
/// 0.989 π on surfels more than 0.15 from another face. Before the holes between a nearby
/// wall's discs were filled from ray hits, surfels within 0.02 of an edge saw 0.91 π.
#[test]
fn closed_room_gathers_pi() {
    use wpbgi::bake::pipeline::intensity_map;
    use wpbgi::bake::store::BakedCache;
    use wpbgi::bounce::iterate::close_buffer;
    use wpbgi::gather::cut::splat_cut;
    use wpbgi::gather::microbuffer::Microbuffer;
    use wpbgi::gather::senders::Senders;
    use wpbgi::geometry::frame::Frame;
    let scene = furnace(0.5, 1.0);
    let settings = BakeSettings {
        points: 3000,
        light_samples: 4,
        ..BakeSettings::from_quality(wpbgi::bake::Quality::Draft)
    };
    let mut baked = bake(&scene, &settings, &|_, _| {}).expect("bake");
    for r in baked.radiance.iter_mut() {
        *r = SurfelRadiance::Rgb(Rgb::ONE);
    }
    baked.emitted.fill(Rgb::ZERO);
    let levels = baked.plan.map_levels;
    let leaf = |i: u32| {
        intensity_map(
            &baked.surfels[i as usize],
            &baked.radiance[i as usize],
            levels,
            true,
        )
    };
    baked.coded = wpbgi::bake::encode(&baked.tree, &leaf, baked.coded.split_level, settings.tau);
    let cache = BakedCache::in_memory("furnace".as_ref(), &baked).expect("cache");
    let senders = Senders::from_cache(&cache).expect("senders");
    let accel = wpbgi::accel::Accel::build(&scene);
    let mut stack = Vec::new();
    let (mut all, mut inner) = ((0.0f64, 0u32), (0.0f64, 0u32));
    for s in &baked.surfels {
        let mut mb = Microbuffer::new(16, false, Frame::from_normal(s.n));
        splat_cut(&senders, s.p, s.mesh, &mut mb, &[0], &mut stack);
        mb.resolve();
        close_buffer(&senders, (&accel, &scene), s, &mut mb);
        let e = mb
            .cos_radiance
            .iter()
            .zip(&mb.pixels)
            .map(|(l, p)| f64::from(l.x * p.solid_angle))
            .sum::<f64>()
            / std::f64::consts::PI;
        // The distance to the nearest other face of the room.
        let edge = (0..3)
            .filter(|&a| s.n[a].abs() < 0.5)
            .map(|a| s.p[a].min(1.0 - s.p[a]))
            .fold(f32::INFINITY, f32::min);
        all = (all.0 + e, all.1 + 1);
        if edge > 0.15 {
            inner = (inner.0 + e, inner.1 + 1);
        }
    }
    let (mean, inner_mean) = (all.0 / f64::from(all.1), inner.0 / f64::from(inner.1));
    eprintln!("irradiance / π: mean {mean:.4}, away from the edges {inner_mean:.4}");
    assert!(inner_mean > 0.983 && inner_mean < 1.01, "{inner_mean}");
    assert!(mean > 0.985 && mean < 1.01, "{mean}");
}

/// The figures of docs/bounces.md: `cargo test --release --test furnace -- --ignored`.
#[test]
#[ignore = "a measurement, not a check"]
fn furnace_table() {
    for rho in [0.5f32, 0.9, 0.99] {
        let expected = f64::from(1.0 / (1.0 - rho));
        let (mean, report, _) = cached_radiance(&furnace(rho, 1.0), BounceSettings::auto(), 2);
        eprintln!(
            "ρ = {rho}: {:+.2} % after {} bounces (tail × {:?})",
            100.0 * (mean / expected - 1.0),
            report.bounces,
            report.extrapolated
        );
    }
}
