//! Helpers shared by the integration tests (and the ray benchmark). Each test binary uses a
//! subset, hence the `dead_code` allowance.
#![allow(dead_code)]

mod scratch;

#[allow(unused_imports)] // not every test binary writes files
pub use scratch::Scratch;

use glam::Vec3;
use wpbgi::scene::Mesh;

/// The command line's arguments for a small bake that still runs the bounces (2 000 surfels,
/// 16 light samples, two bounces): what the CLI tests bake with.
pub const SMALL_BAKE: [&str; 6] = [
    "--points",
    "2000",
    "--light-samples",
    "16",
    "--bounces",
    "2",
];

/// Standard base64 (for data URIs).
pub fn b64(data: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in data.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for i in 0..4 {
            if i <= c.len() {
                out.push(A[(n >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// A one-triangle glTF with the given positions and indices, embedded as a data URI.
pub fn triangle_gltf(positions: &[[f32; 3]], indices: &[u32], extra_material: &str) -> String {
    let mut bin = Vec::new();
    for p in positions {
        for x in p {
            bin.extend_from_slice(&x.to_le_bytes());
        }
    }
    let pos_len = bin.len();
    for i in indices {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0,"name":"tri"}}],
"meshes":[{{"name":"tri","primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"material":0}}]}}],
"materials":[{{"name":"lamp","emissiveFactor":[1,1,1]{extra_material}}}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{pos_len}}},{{"buffer":0,"byteOffset":{pos_len},"byteLength":{}}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":{},"type":"VEC3","min":[0,0,0],"max":[1,1,1]}},
{{"bufferView":1,"componentType":5125,"count":{},"type":"SCALAR"}}]}}"#,
        bin.len(),
        b64(&bin),
        indices.len() * 4,
        positions.len(),
        indices.len()
    )
}

/// A closed, consistently outward-wound icosphere-like mesh: a subdivided octahedron with
/// shared vertices.
pub fn closed_sphere(levels: u32) -> Mesh {
    let mut pos = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    for _ in 0..levels {
        let mut cache = std::collections::HashMap::new();
        let mut mid = |a: u32, b: u32, pos: &mut Vec<Vec3>| {
            *cache.entry((a.min(b), a.max(b))).or_insert_with(|| {
                pos.push(((pos[a as usize] + pos[b as usize]) * 0.5).normalize());
                pos.len() as u32 - 1
            })
        };
        let mut next = Vec::new();
        for [a, b, c] in tris {
            let (ab, bc, ca) = (
                mid(a, b, &mut pos),
                mid(b, c, &mut pos),
                mid(c, a, &mut pos),
            );
            next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        tris = next;
    }
    Mesh {
        name: "sphere".into(),
        positions: pos,
        normals: None,
        uvs: None,
        triangles: tris,
        material: 0,
    }
}

/// Bake `scene` with `settings` into a cache file at `path` and open it.
pub fn bake_to_cache(
    scene: &wpbgi::scene::Scene,
    settings: &wpbgi::bake::BakeSettings,
    path: &std::path::Path,
) -> wpbgi::cache::store::BakedCache {
    let baked = wpbgi::bake::bake(scene, settings, &|_, _| {}).expect("bake");
    let hash = wpbgi::cache::store::bake_hash(scene, &settings.to_json());
    wpbgi::bake::store::write(path, hash, &baked, serde_json::json!({})).expect("write");
    wpbgi::cache::store::BakedCache::read(path, None).expect("read")
}

/// The final render of `scene` from `cache` through `camera` with the default settings.
#[allow(dead_code)] // not every test file renders
pub fn final_render(
    scene: &wpbgi::scene::Scene,
    cache: &wpbgi::cache::store::BakedCache,
    camera: &wpbgi::scene::Camera,
) -> wpbgi::render::FinalOutput {
    let settings = wpbgi::render::FinalSettings::default();
    wpbgi::render::render_final(scene, cache, camera, &settings, &|_, _| {}).expect("final render")
}

/// A scene of `meshes`, all of one grey (albedo 0.5) diffuse material.
pub fn grey_scene(meshes: Vec<Mesh>) -> wpbgi::scene::Scene {
    use wpbgi::bsdf::{Bsdf, Diffuse};
    use wpbgi::scene::{Material, Scattering, Scene};
    Scene {
        meshes,
        materials: vec![Material {
            name: "grey".into(),
            scattering: Scattering::Explicit(Bsdf::Diffuse(Diffuse {
                reflectance: wpbgi::spectrum::Rgb::splat(0.5),
            })),
            cutout: None,
            normal_map: None,
            emission: None,
        }],
        ..Default::default()
    }
}

/// A file of tests/data/mitsuba (Mitsuba 3's reference scenes and renders).
pub fn mitsuba_data(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/mitsuba")
        .join(name)
}

/// Mitsuba's 256² reference of `name` at max_depth `depth`, averaged 2 × 2: the box filter over
/// a 128² pixel is exactly the mean of its four 256² box-filtered quarters.
pub fn reference_128(name: &str, depth: u32) -> wpbgi::image::Image {
    let r = wpbgi::image::read_exr(&mitsuba_data(&format!("{name}_d{depth}_ref.exr")))
        .expect("reference");
    let mut out = wpbgi::image::Image::new(r.width / 2, r.height / 2);
    for y in 0..out.height {
        for x in 0..out.width {
            out.pixels[(y * out.width + x) as usize] = (r.get(2 * x, 2 * y)
                + r.get(2 * x + 1, 2 * y)
                + r.get(2 * x, 2 * y + 1)
                + r.get(2 * x + 1, 2 * y + 1))
                * 0.25;
        }
    }
    out
}
