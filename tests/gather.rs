//! The gather against an independent result: the irradiance from a uniformly lit square.
//!
//! A diffuse square (2 × 2, albedo 0.5, facing down) is lit from below by a directional light
//! of irradiance π, so every point of it reflects L = ρE/π = 0.5. A receiver facing up at
//! height h below it gathers E = ∫ L cos θ_r cos θ_s / r² dA, which the test integrates
//! numerically (a 2000² midpoint rule in f64, error < 1e-6 relative) from the geometry alone.
//! The gather goes through the whole chain: bake, cache file, senders, cut, microbuffer,
//! convolution with a white diffuse BSDF (L_o = E/π), each receiver with its near leaves split
//! into pieces (the bake's way) and traced (the render's: `render::near_field`); and a receiver
//! that sees the square only through a 1 cm gap under a black plate, where the two part.
//!
//! Tolerance 3 %: a 16² buffer's pixels span 9°, the surfels are 1/2000 of the square each,
//! and the measured errors (0.3–2.7 %, printed per case) come from where the square's edge
//! crosses pixels and from the footprints of the senders; a plain z-test without coverage
//! is +24 % off at the square's edge, a clamp per pixel −6 % (see the microbuffer docs).

mod common;

use common::b64;
use glam::Vec3;
use std::path::Path;
use wpbgi::bake::store::write;
use wpbgi::bake::{bake, BakeSettings, Baked};
use wpbgi::bsdf::{Bsdf, Diffuse};
use wpbgi::cache::store::{bake_hash, BakedCache};
use wpbgi::gather::fpbgi::ClusterGather;
use wpbgi::gather::{splat_cut, Microbuffer, Senders};
use wpbgi::geometry::frame::Frame;
use wpbgi::render::near_field::trace_near_field;
use wpbgi::render::primary::Receiver;
use wpbgi::scene::Scene;
use wpbgi::spectrum::Rgb;

/// A horizontal rectangle `[x0, x1] × [z0, z1]` at height `y`, facing −y.
type Plate = (f32, [f32; 4]);

/// A 2 × 2 square at y = 0 facing −y, lit from below, with black (reflectance 0) `plates`
/// below it: they shade the square above them and hide it from below.
fn lit_square_and(plates: &[Plate]) -> String {
    let rects = std::iter::once((0.0, [-1.0, 1.0, -1.0, 1.0])).chain(plates.iter().copied());
    let (mut bin, mut views, mut accessors, mut meshes, mut nodes) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (m, (y, [x0, x1, z0, z1])) in rects.enumerate() {
        let positions = [[x0, y, z0], [x1, y, z0], [x1, y, z1], [x0, y, z1]];
        // Counter-clockwise seen from below (normal −y).
        let indices: [u32; 6] = [0, 1, 2, 0, 2, 3];
        let start = bin.len();
        positions
            .iter()
            .flatten()
            .for_each(|x: &f32| bin.extend_from_slice(&x.to_le_bytes()));
        indices
            .iter()
            .for_each(|i| bin.extend_from_slice(&i.to_le_bytes()));
        views.push(format!(
            r#"{{"buffer":0,"byteOffset":{start},"byteLength":48}},{{"buffer":0,"byteOffset":{},"byteLength":24}}"#,
            start + 48
        ));
        accessors.push(format!(
            r#"{{"bufferView":{},"componentType":5126,"count":4,"type":"VEC3","min":[{x0},{y},{z0}],"max":[{x1},{y},{z1}]}},{{"bufferView":{},"componentType":5125,"count":6,"type":"SCALAR"}}"#,
            2 * m,
            2 * m + 1
        ));
        let (name, material) = if m == 0 { ("square", 0) } else { ("plate", 1) };
        meshes.push(format!(
            r#"{{"name":"{name}{m}","primitives":[{{"attributes":{{"POSITION":{}}},"indices":{},"material":{material}}}]}}"#,
            2 * m,
            2 * m + 1
        ));
        nodes.push(format!(r#"{{"mesh":{m},"name":"{name}{m}"}}"#));
    }
    let sun = nodes.len();
    format!(
        r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["KHR_lights_punctual"],
"extensions":{{"KHR_lights_punctual":{{"lights":[{{"type":"directional","intensity":3.14159265,"color":[1,1,1]}}]}}}},
"scene":0,"scenes":[{{"nodes":[{}]}}],
"nodes":[{},{{"name":"sun","rotation":[0.70710678,0,0,0.70710678],"extensions":{{"KHR_lights_punctual":{{"light":0}}}}}}],
"meshes":[{}],
"materials":[{{"name":"white","extras":{{"mitsuba":{{"type":"diffuse","reflectance":[0.5,0.5,0.5]}}}}}},{{"name":"black","extras":{{"mitsuba":{{"type":"diffuse","reflectance":[0,0,0]}}}}}}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{}],
"accessors":[{}]}}"#,
        (0..=sun)
            .map(|i| i.to_string())
            .collect::<Vec<_>>()
            .join(","),
        nodes.join(","),
        meshes.join(","),
        bin.len(),
        b64(&bin),
        views.join(","),
        accessors.join(",")
    )
}

/// E at `p` (receiver facing +y) from the square of radiance `l`, by the midpoint rule.
fn irradiance(p: Vec3, n: Vec3, l: f64) -> f64 {
    irradiance_where(p, n, l, |_| true)
}

/// [`irradiance`] from the points `q` of the square for which `seen(q)` holds.
fn irradiance_where(p: Vec3, n: Vec3, l: f64, seen: impl Fn(glam::DVec3) -> bool) -> f64 {
    let count = 2000;
    let h = 2.0 / count as f64;
    let n = n.as_dvec3();
    let mut sum = 0.0;
    for j in 0..count {
        for i in 0..count {
            let (x, z) = (-1.0 + (i as f64 + 0.5) * h, -1.0 + (j as f64 + 0.5) * h);
            let q = glam::DVec3::new(x, 0.0, z);
            if !seen(q) {
                continue;
            }
            let d = q - p.as_dvec3();
            let r2 = d.length_squared();
            // cos at the square (normal −y) is d.y/r; at the receiver, d·n/r where positive.
            sum += d.y * d.dot(n).max(0.0) / (r2 * r2);
        }
    }
    l * sum * h * h
}

fn senders() -> (Scene, Senders) {
    let (scene, baked, senders) = square_senders(&[], "gather");
    // Every surfel reflects exactly ρE/π = 0.5 (a directional light has no noise).
    for r in &baked.radiance {
        match r {
            wpbgi::surfels::radiance::SurfelRadiance::Rgb(c) => {
                assert!((*c - Rgb::splat(0.5)).abs().max_element() < 1e-5, "{c}")
            }
            _ => panic!("diffuse surfels store RGB"),
        }
    }
    (scene, senders)
}

/// The lit square and its `plates` ([`lit_square_and`]) baked with 8 000 surfels, and their
/// senders as a render reads them, in a scratch folder named `name`.
fn square_senders(plates: &[Plate], name: &str) -> (Scene, Baked, Senders) {
    let dir = common::Scratch::new(name);
    let gltf = dir.join("square.gltf");
    std::fs::write(&gltf, lit_square_and(plates)).unwrap();
    let scene = Scene::load(&gltf).unwrap();
    let settings = BakeSettings {
        points: 8000,
        light_samples: 4,
        ..BakeSettings::preset(wpbgi::bake::Quality::Draft).direct_only()
    };
    let baked = bake(&scene, &settings, &|_, _| {}).unwrap();
    let senders = cached_senders(&scene, &settings, &baked, &dir.join("square.wpc"));
    (scene, baked, senders)
}

/// The senders of `baked` (of `scene` with `settings`) as a render reads them: written to a
/// cache at `path` and read back.
fn cached_senders(scene: &Scene, settings: &BakeSettings, baked: &Baked, path: &Path) -> Senders {
    let hash = bake_hash(scene, &settings.to_json());
    write(path, hash, baked, serde_json::json!({})).unwrap();
    Senders::from_cache(&BakedCache::read(path, None).unwrap()).unwrap()
}

/// Each receiver gathers twice: with its near leaves split, as the bake's are, and traced, as
/// the render's are (`render::near_field`). Measured: split −2.2 % to +2.7 %, traced −2.2 % to
/// +0.7 % (printed per case): where a ray-traced and a splatted part of one surface share a
/// pixel, the ray's hit takes the pixel and hides the splats of that surface there (hiding
/// only those behind it left the nearer part of an obliquely seen pixel to count twice: +4.4 %
/// at 0.1 below the square), so neither a ring of pixels darkens where the two meet nor one
/// brightens.
#[test]
fn gather_matches_the_integrated_irradiance() {
    let (scene, senders) = senders();
    let tracer = wpbgi::trace::Tracer::new(&scene);
    let white = Bsdf::Diffuse(Diffuse {
        reflectance: Rgb::ONE,
    });
    let mut stack = Vec::new();
    for (p, normal, n) in [
        (Vec3::new(0.0, -0.1, 0.0), Vec3::Y, 16),
        (Vec3::new(0.0, -0.5, 0.0), Vec3::Y, 16),
        (Vec3::new(0.0, -2.0, 0.0), Vec3::Y, 16),
        (Vec3::new(0.8, -0.3, -0.5), Vec3::Y, 16),
        (Vec3::new(1.5, -0.5, 0.0), Vec3::Y, 16),
        (Vec3::new(0.0, -0.5, 0.0), Vec3::Y, 32),
        (Vec3::new(0.3, -0.05, 0.2), Vec3::Y, 8),
        // Within two surfel radii (0.0126) of the square: every surfel near the receiver is
        // split into pieces.
        (Vec3::new(0.1, -0.02, 0.1), Vec3::Y, 16),
        // Facing along the square, whose plane the receiver's horizon cuts: the split
        // surfels there are clipped by the horizon.
        (Vec3::new(0.5, -0.02, 0.0), Vec3::X, 16),
        (
            Vec3::new(-0.3, -0.05, 0.3),
            Vec3::new(-1.0, 0.0, 1.0).normalize(),
            16,
        ),
    ] {
        let frame = Frame::from_normal(normal);
        let receiver = receiver_at(p, frame);
        let expected = irradiance(p, normal, 0.5);
        for traced in [false, true] {
            let mut mb = Microbuffer::new(n, false, frame);
            if traced {
                let mut trace = |mb: &mut Microbuffer, leaves: &[u32]| {
                    trace_near_field(&tracer, &senders, &receiver, mb, leaves);
                };
                ClusterGather::alone(&senders).fill_tracing_near(
                    p,
                    u32::MAX,
                    &mut mb,
                    &mut stack,
                    &mut trace,
                );
            } else {
                splat_cut(&senders, p, u32::MAX, &mut mb, &[0], &mut stack);
                mb.resolve();
            }
            let lo = mb.convolve(&white, Vec3::Z);
            let gathered = lo.x as f64 * std::f64::consts::PI;
            let err = gathered / expected - 1.0;
            eprintln!(
                "p = {p}, n = {n}, traced {traced}: gathered {gathered:.5}, expected \
                 {expected:.5}, error {:+.2} %",
                100.0 * err
            );
            assert!(
                err.abs() < 0.03,
                "p = {p}, n = {n}, traced {traced}: {gathered} vs {expected}"
            );
            assert!(lo.is_finite());
        }
    }
}

/// A render receiver at `p` with shading frame `frame`, on no mesh, white.
fn receiver_at(p: Vec3, frame: Frame) -> Receiver {
    Receiver {
        pixel: 0,
        weight: Rgb::ONE,
        p,
        err: Vec3::ZERO,
        ng: frame.n,
        mesh: u32::MAX,
        frame,
        bsdf: Bsdf::Diffuse(Diffuse {
            reflectance: Rgb::ONE,
        }),
        view: Vec3::Z,
        chain: 0,
        quarter: None,
    }
}

/// A receiver that sees the lit square only through a gap: a black plate 1 cm above it, its
/// edge 1–2 cm to the receiver's side, within a surfel radius (8 000 surfels over the square
/// and the plate, 1.8 cm in radius). The receiver looks up through a slit and sees the part
/// of the square beyond it, all of it lit (the plate's shadow on the square lies on the
/// plate's side of its edge). Traced, as the render's near field is (`render::near_field`),
/// the gather's irradiance is within 20 % of that part's integral: measured +1.2 %, +13.0 %
/// and +8.1 % with the edge 1, 1.5 and 2 cm away, the slit's edge resolved to the 16² buffer's
/// pixels, and the square's splats in the pixels along it taking more than their share of the
/// pixels the plate hides (finer buffers do not take it below 10 %). Split into pieces, as
/// the bake's near leaves are, the plate's discs let the square through their gaps and past
/// the plate's edge: measured +9.8 %, +220 % and +939 %, which the test requires to stay above
/// +100 % with the edge 1.5 and 2 cm away, so that it keeps telling the two apart.
#[test]
fn a_traced_near_field_sees_a_gap_as_it_is() {
    for (rim, split_above) in [(0.01f32, None), (0.015, Some(1.0)), (0.02, Some(1.0))] {
        let (traced, split) = through_a_gap(0.3, 0.01, rim);
        eprintln!(
            "edge {rim} away: traced {:+.1} %, split {:+.1} %",
            100.0 * traced,
            100.0 * split
        );
        assert!(
            traced.abs() < 0.2,
            "edge {rim} away, traced: {:+.1} %",
            100.0 * traced
        );
        if let Some(above) = split_above {
            assert!(
                split > above,
                "edge {rim} away, split: {:+.1} %",
                100.0 * split
            );
        }
    }
}

/// The relative errors of the irradiance a receiver facing up gathers, at `h` below the lit
/// square, under a black plate `gap` above it whose edge lies `rim` to its −x side, with its
/// near field traced and split.
fn through_a_gap(h: f32, gap: f32, rim: f32) -> (f64, f64) {
    let plate: Plate = (-h + gap, [-rim, 1.5, -1.5, 1.5]);
    let (scene, _, senders) = square_senders(&[plate], "gather-gap");
    let tracer = wpbgi::trace::Tracer::new(&scene);
    let p = Vec3::new(0.0, -h, 0.0);
    let frame = Frame::from_normal(Vec3::Y);
    let white = Bsdf::Diffuse(Diffuse {
        reflectance: Rgb::ONE,
    });
    let receiver = receiver_at(p, frame);
    // Seen through the slit (the segment from the receiver crosses the plate's height beyond
    // its edge) and lit (not in the plate's shadow).
    let (hd, gd, rd) = (f64::from(h), f64::from(gap), f64::from(rim));
    let expected = irradiance_where(p, Vec3::Y, 0.5, |q| q.x * gd / hd < -rd && q.x < -rd);
    let mut stack = Vec::new();
    let mut error = |traced: bool| {
        let mut mb = Microbuffer::new(16, false, frame);
        let mut gather = ClusterGather::alone(&senders);
        let mut rays = 0;
        if traced {
            let mut trace = |mb: &mut Microbuffer, leaves: &[u32]| {
                rays += trace_near_field(&tracer, &senders, &receiver, mb, leaves);
            };
            gather.fill_tracing_near(p, u32::MAX, &mut mb, &mut stack, &mut trace);
            assert_eq!(rays, 256, "one ray through each pixel");
        } else {
            gather.fill(p, u32::MAX, &mut mb, &mut stack);
        }
        let lo = mb.convolve(&white, Vec3::Z);
        assert!(lo.is_finite());
        f64::from(lo.x) * std::f64::consts::PI / expected - 1.0
    };
    (error(true), error(false))
}

/// A receiver on a solid reaches the surfels of its own solid one by one (their inward light
/// is in no node's maps), but not those of another solid: a node wholly on another closed
/// mesh is taken whole, as any receiver takes it. Two glass spheres (the bundled caustic
/// scene's, instanced twice): every node holding surfels of one sphere alone needs leaves for
/// that sphere's receivers and not for the other's, and a node mixing meshes still does.
#[test]
fn a_solid_reaches_only_its_own_solid_as_leaves() {
    let data = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mitsuba/");
    let mut g: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(format!("{data}caustic.gltf")).unwrap())
            .unwrap();
    let sphere = g["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .position(|n| n["name"] == "sphere")
        .expect("the caustic scene's sphere");
    let mesh = g["nodes"][sphere]["mesh"].clone();
    let instance = |name: &str, x: f32| {
        serde_json::json!({"name": name, "mesh": mesh, "scale": [0.5, 0.5, 0.5],
            "translation": [x, -0.5, 0.0]})
    };
    g["nodes"][sphere] = instance("sphere-a", -0.45);
    let nodes = g["nodes"].as_array_mut().unwrap();
    nodes.push(instance("sphere-b", 0.45));
    let b = nodes.len() - 1;
    g["scenes"][0]["nodes"]
        .as_array_mut()
        .unwrap()
        .push(b.into());
    for buffer in g["buffers"].as_array_mut().unwrap() {
        if let Some(uri) = buffer["uri"].as_str().filter(|u| !u.starts_with("data:")) {
            buffer["uri"] = format!("{data}{uri}").into();
        }
    }
    let dir = common::Scratch::new("two-solids");
    let gltf = dir.join("two-spheres.gltf");
    std::fs::write(&gltf, g.to_string()).unwrap();
    let scene = Scene::load(&gltf).unwrap();
    let settings = BakeSettings {
        points: 3000,
        light_samples: 4,
        bounces: wpbgi::bake::bounce::BounceSettings::exactly(0),
        ..BakeSettings::preset(wpbgi::bake::Quality::Draft).direct_only()
    };
    let baked = bake(&scene, &settings, &|_, _| {}).unwrap();
    let senders = cached_senders(&scene, &settings, &baked, &dir.join("two-spheres.wpc"));
    let spheres: Vec<u32> = (0..scene.meshes.len() as u32)
        .filter(|&m| scene.meshes[m as usize].name.contains("sphere"))
        .collect();
    let [a, b] = spheres[..] else {
        panic!("two sphere meshes: {spheres:?}");
    };
    // The meshes under each node, from its surfels.
    let mut below: Vec<Vec<u32>> = vec![Vec::new(); senders.nodes.len()];
    for j in (0..senders.nodes.len()).rev() {
        let node = &senders.nodes[j];
        below[j] = if node.is_leaf() {
            vec![senders.surfels[node.surfel() as usize].mesh]
        } else {
            let mut m: Vec<u32> = node
                .children
                .iter()
                .filter(|&&c| (c as usize) < below.len())
                .flat_map(|&c| below[c as usize].clone())
                .collect();
            m.sort_unstable();
            m.dedup();
            m
        };
    }
    let (mut own, mut other, mut mixed) = (0, 0, 0);
    for (j, meshes) in below.iter().enumerate() {
        let j = j as u32;
        match meshes[..] {
            [m] if m == a || m == b => {
                let other_sphere = if m == a { b } else { a };
                assert!(senders.needs_leaves(j, m), "node {j} on its own solid");
                assert!(
                    !senders.needs_leaves(j, other_sphere),
                    "node {j} on the other"
                );
                own += 1;
                other += 1;
            }
            _ if meshes.contains(&a) || meshes.contains(&b) => {
                assert!(senders.needs_leaves(j, a) && senders.needs_leaves(j, b));
                mixed += 1;
            }
            _ => assert!(!senders.needs_leaves(j, a) && !senders.needs_leaves(j, b)),
        }
    }
    assert!(
        own > 100 && other > 100 && mixed > 0,
        "{own} {other} {mixed}"
    );
}
