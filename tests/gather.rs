//! The gather against an independent result: the irradiance from a uniformly lit square.
//!
//! A diffuse square (2 × 2, albedo 0.5, facing down) is lit from below by a directional light
//! of irradiance π, so every point of it reflects L = ρE/π = 0.5. A receiver facing up at
//! height h below it gathers E = ∫ L cos θ_r cos θ_s / r² dA, which the test integrates
//! numerically (a 2000² midpoint rule in f64, error < 1e-6 relative) from the geometry alone.
//! The gather goes through the whole chain: bake, cache file, senders, cut, microbuffer,
//! convolution with a white diffuse BSDF (L_o = E/π).
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
use wpbgi::gather::{splat_cut, Microbuffer, Senders};
use wpbgi::geometry::frame::Frame;
use wpbgi::scene::Scene;
use wpbgi::spectrum::Rgb;

/// A 2 × 2 square at y = 0 facing −y, lit from below.
fn lit_square() -> String {
    let positions: [[f32; 3]; 4] = [[-1., 0., -1.], [1., 0., -1.], [1., 0., 1.], [-1., 0., 1.]];
    // Counter-clockwise seen from below (normal −y).
    let indices: [u32; 6] = [0, 1, 2, 0, 2, 3];
    let mut bin = Vec::new();
    for p in positions {
        for x in p {
            bin.extend_from_slice(&x.to_le_bytes());
        }
    }
    for i in indices {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    format!(
        r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["KHR_lights_punctual"],
"extensions":{{"KHR_lights_punctual":{{"lights":[{{"type":"directional","intensity":3.14159265,"color":[1,1,1]}}]}}}},
"scene":0,"scenes":[{{"nodes":[0,1]}}],
"nodes":[{{"mesh":0,"name":"square"}},{{"name":"sun","rotation":[0.70710678,0,0,0.70710678],"extensions":{{"KHR_lights_punctual":{{"light":0}}}}}}],
"meshes":[{{"name":"square","primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"material":0}}]}}],
"materials":[{{"name":"white","extras":{{"mitsuba":{{"type":"diffuse","reflectance":[0.5,0.5,0.5]}}}}}}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":24}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[-1,0,-1],"max":[1,0,1]}},
{{"bufferView":1,"componentType":5125,"count":6,"type":"SCALAR"}}]}}"#,
        bin.len(),
        b64(&bin)
    )
}

/// E at `p` (receiver facing +y) from the square of radiance `l`, by the midpoint rule.
fn irradiance(p: Vec3, n: Vec3, l: f64) -> f64 {
    let count = 2000;
    let h = 2.0 / count as f64;
    let n = n.as_dvec3();
    let mut sum = 0.0;
    for j in 0..count {
        for i in 0..count {
            let (x, z) = (-1.0 + (i as f64 + 0.5) * h, -1.0 + (j as f64 + 0.5) * h);
            let d = glam::DVec3::new(x, 0.0, z) - p.as_dvec3();
            let r2 = d.length_squared();
            // cos at the square (normal −y) is d.y/r; at the receiver, d·n/r where positive.
            sum += d.y * d.dot(n).max(0.0) / (r2 * r2);
        }
    }
    l * sum * h * h
}

fn senders() -> Senders {
    let dir = common::Scratch::new("gather");
    let gltf = dir.join("square.gltf");
    std::fs::write(&gltf, lit_square()).unwrap();
    let scene = Scene::load(&gltf).unwrap();
    let settings = BakeSettings {
        points: 8000,
        light_samples: 4,
        ..BakeSettings::preset(wpbgi::bake::Quality::Draft).direct_only()
    };
    let baked = bake(&scene, &settings, &|_, _| {}).unwrap();
    // Every surfel reflects exactly ρE/π = 0.5 (a directional light has no noise).
    for r in &baked.radiance {
        match r {
            wpbgi::surfels::radiance::SurfelRadiance::Rgb(c) => {
                assert!((*c - Rgb::splat(0.5)).abs().max_element() < 1e-5, "{c}")
            }
            _ => panic!("diffuse surfels store RGB"),
        }
    }
    cached_senders(&scene, &settings, &baked, &dir.join("square.wpc"))
}

/// The senders of `baked` (of `scene` with `settings`) as a render reads them: written to a
/// cache at `path` and read back.
fn cached_senders(scene: &Scene, settings: &BakeSettings, baked: &Baked, path: &Path) -> Senders {
    let hash = bake_hash(scene, &settings.to_json());
    write(path, hash, baked, serde_json::json!({})).unwrap();
    Senders::from_cache(&BakedCache::read(path, None).unwrap()).unwrap()
}

#[test]
fn gather_matches_the_integrated_irradiance() {
    let senders = senders();
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
        let mut mb = Microbuffer::new(n, false, frame);
        splat_cut(&senders, p, u32::MAX, &mut mb, &[0], &mut stack);
        mb.resolve();
        let lo = mb.convolve(&white, Vec3::Z);
        let gathered = lo.x as f64 * std::f64::consts::PI;
        let expected = irradiance(p, normal, 0.5);
        let err = gathered / expected - 1.0;
        eprintln!(
            "p = {p}, n = {n}: gathered {gathered:.5}, expected {expected:.5}, error {:+.2} %",
            100.0 * err
        );
        assert!(
            err.abs() < 0.03,
            "p = {p}, n = {n}: {gathered} vs {expected}"
        );
        assert!(lo.is_finite());
    }
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
            vec![senders.surfels[node.surfel as usize].mesh]
        } else {
            let mut m: Vec<u32> = node
                .node
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
