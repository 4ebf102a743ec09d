//! Alpha cut-outs (glTF `alphaMode: MASK`, issue 22): a light, a floor, and between them an
//! occluder whose material is masked. Fully cut away (a constant alpha below the cutoff), the
//! path tracer's image is the image of the scene without the occluder, byte for byte; kept
//! (alpha above the cutoff), it is the opaque occluder's image; half cut by a texture, the
//! floor's light lies between the two, and the bake's surfels keep out of the hole while
//! their areas sum to the half that is there.

mod common;

use std::path::{Path, PathBuf};
use wpbgi::reference::{render, RenderSettings};
use wpbgi::scene::Scene;

fn dir() -> common::Scratch {
    common::Scratch::new("cutout")
}

/// The scene as glTF text: `occluder` is the occluder's material (`None`: no occluder).
fn scene_text(occluder: Option<&str>) -> String {
    let quad = |name: &str, y: f32, half: f32, material: usize, down: bool| {
        // Four vertices at height y, texture coordinates (x / 2h + 1/2, z / 2h + 1/2).
        let idx = if down {
            "[0, 1, 2, 0, 2, 3]"
        } else {
            "[0, 2, 1, 0, 3, 2]"
        };
        (name.to_string(), y, half, material, idx.to_string())
    };
    let mut quads = vec![
        quad("light", 1.5, 0.25, 0, true),
        quad("floor", 0.0, 2.0, 1, false),
    ];
    if occluder.is_some() {
        quads.push(quad("occluder", 0.75, 0.5, 2, false));
    }
    // One buffer per quad, inline as base64.
    let mut buffers = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut meshes = Vec::new();
    let mut nodes = vec![
        r#"{"camera": 0, "translation": [0, 2.6, 0], "rotation": [-0.70710678, 0, 0, 0.70710678]}"#
            .to_string(),
    ];
    for (q, (name, y, h, material, idx)) in quads.iter().enumerate() {
        let mut bytes = Vec::new();
        let corners = [(-h, -h), (*h, -h), (*h, *h), (-h, *h)];
        for (x, z) in corners {
            for v in [x, *y, z] {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
        for (x, z) in corners {
            for v in [x / (2.0 * h) + 0.5, z / (2.0 * h) + 0.5] {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
        let indices: Vec<u16> = serde_json::from_str(idx).expect("indices");
        for i in indices {
            bytes.extend_from_slice(&i.to_le_bytes());
        }
        buffers.push(format!(
            r#"{{"byteLength": {}, "uri": "data:application/octet-stream;base64,{}"}}"#,
            bytes.len(),
            common::b64(&bytes)
        ));
        let a = 3 * q;
        views.push(format!(
            r#"{{"buffer": {q}, "byteOffset": 0, "byteLength": 48}}"#
        ));
        views.push(format!(
            r#"{{"buffer": {q}, "byteOffset": 48, "byteLength": 32}}"#
        ));
        views.push(format!(
            r#"{{"buffer": {q}, "byteOffset": 80, "byteLength": 12}}"#
        ));
        accessors.push(format!(
            r#"{{"bufferView": {a}, "componentType": 5126, "count": 4, "type": "VEC3", "min": [{}, {y}, {}], "max": [{h}, {y}, {h}]}}"#,
            -h, -h
        ));
        accessors.push(format!(
            r#"{{"bufferView": {}, "componentType": 5126, "count": 4, "type": "VEC2"}}"#,
            a + 1
        ));
        accessors.push(format!(
            r#"{{"bufferView": {}, "componentType": 5123, "count": 6, "type": "SCALAR"}}"#,
            a + 2
        ));
        meshes.push(format!(
            r#"{{"name": "{name}", "primitives": [{{"attributes": {{"POSITION": {a}, "TEXCOORD_0": {}}}, "indices": {}, "material": {material}}}]}}"#,
            a + 1,
            a + 2
        ));
        nodes.push(format!(r#"{{"mesh": {q}}}"#));
    }
    let materials = [
        r#"{"name": "light", "emissiveFactor": [1, 1, 1], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 10}}, "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0}}"#.to_string(),
        r#"{"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1], "metallicFactor": 0, "roughnessFactor": 1}}"#.to_string(),
        occluder.unwrap_or("{}").to_string(),
    ];
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "extensionsUsed": ["KHR_materials_emissive_strength"],
"scene": 0, "scenes": [{{"nodes": [{}]}}],
"cameras": [{{"type": "perspective", "perspective": {{"yfov": 1.2, "znear": 0.01}}}}],
"nodes": [{}], "meshes": [{}], "materials": [{}], "buffers": [{}], "bufferViews": [{}], "accessors": [{}],
"images": [{{"uri": "half.png"}}], "textures": [{{"source": 0, "sampler": 0}}],
"samplers": [{{"wrapS": 33071, "wrapT": 33071}}]}}"#,
        (0..nodes.len())
            .map(|i| i.to_string())
            .collect::<Vec<_>>()
            .join(", "),
        nodes.join(", "),
        meshes.join(", "),
        materials.join(", "),
        buffers.join(", "),
        views.join(", "),
        accessors.join(", ")
    )
}

/// Write the scene (and its 8 × 1 alpha texture: opaque left half, clear right half).
fn write_scene(d: &Path, name: &str, occluder: Option<&str>) -> PathBuf {
    let mut png = image::RgbaImage::new(8, 1);
    for (x, _, p) in png.enumerate_pixels_mut() {
        *p = image::Rgba([128, 128, 128, if x < 4 { 255 } else { 0 }]);
    }
    png.save(d.join("half.png")).expect("png");
    let path = d.join(name);
    std::fs::write(&path, scene_text(occluder)).expect("scene");
    path
}

fn masked(alpha: f32, textured: bool) -> String {
    let texture = if textured {
        r#", "baseColorTexture": {"index": 0}"#
    } else {
        ""
    };
    format!(
        r#"{{"name": "cut", "alphaMode": "MASK", "alphaCutoff": 0.5, "doubleSided": true, "pbrMetallicRoughness": {{"baseColorFactor": [0.5, 0.5, 0.5, {alpha}], "metallicFactor": 0, "roughnessFactor": 1{texture}}}}}"#
    )
}

fn image_of(path: &Path) -> wpbgi::image::Image {
    let scene = Scene::load(path).unwrap_or_else(|e| panic!("{e}"));
    let camera = scene.default_camera(48, 48).expect("camera");
    let settings = RenderSettings {
        spp: 16,
        max_depth: 3,
        ..Default::default()
    };
    render(&scene, &camera, &settings, &|_| {})
        .expect("render")
        .mean
}

#[test]
fn masked_occluders_let_light_through_their_holes() {
    let d = dir();
    let without = image_of(&write_scene(&d, "without.gltf", None));
    let cut = write_scene(&d, "cut.gltf", Some(&masked(0.2, false)));
    let cut_scene = Scene::load(&cut).expect("scene");
    assert!(
        cut_scene
            .warnings
            .iter()
            .any(|w| w.0.contains("occluder") && w.0.contains("cutoff")),
        "{:?}",
        cut_scene.warnings
    );
    assert!(image_of(&cut) == without, "a cut-away occluder still shows");
    let kept = image_of(&write_scene(&d, "kept.gltf", Some(&masked(0.9, false))));
    let opaque_material = masked(0.9, false).replace("MASK", "OPAQUE");
    let opaque = image_of(&write_scene(&d, "opaque.gltf", Some(&opaque_material)));
    assert!(kept == opaque, "an alpha above the cutoff is opaque");
    assert!(kept != without);
    let mean = |img: &wpbgi::image::Image| img.mean().x;
    assert!(
        mean(&kept) < 0.95 * mean(&without),
        "the occluder casts no shadow"
    );
    // Half cut by the texture: the light it lets through lies between.
    let half_path = write_scene(&d, "half.gltf", Some(&masked(1.0, true)));
    let half = image_of(&half_path);
    assert!(
        mean(&kept) < mean(&half) && mean(&half) < mean(&without),
        "{} {} {}",
        mean(&kept),
        mean(&half),
        mean(&without)
    );
    // The bake's surfels: none in the hole (texture u > 1/2: x > 0 on the occluder), and the
    // occluder's surfels cover the half that is there (area 0.5 of its 1).
    let scene = Scene::load(&half_path).expect("scene");
    let occluder = scene
        .meshes
        .iter()
        .position(|m| m.name.contains("occluder"))
        .expect("occluder") as u32;
    let surfels = wpbgi::surfels::sample_surfels(&scene, 20_000, 0);
    let on: Vec<_> = surfels.iter().filter(|s| s.mesh == occluder).collect();
    assert!(on.len() > 100);
    assert!(on.iter().all(|s| s.p.x <= 1e-3), "a surfel in the hole");
    let area: f32 = on.iter().map(|s| s.area).sum();
    assert!(
        (area - 0.5).abs() < 0.02,
        "the occluder's surfels cover {area}"
    );
}

/// USD's `opacityThreshold`: a constant opacity below it removes the mesh whole, above it
/// leaves the mesh opaque (no transmission), and without a threshold opacity stays
/// transmission.
#[cfg(feature = "usd")]
#[test]
fn usd_opacity_threshold_cuts_out() {
    let d = dir();
    let stage = |opacity: f32, threshold: f32| {
        format!(
            r#"#usda 1.0
(
    upAxis = "Y"
)
def Material "m"
{{
    token outputs:surface.connect = </m/s.outputs:surface>
    def Shader "s"
    {{
        uniform token info:id = "UsdPreviewSurface"
        float inputs:opacity = {opacity}
        float inputs:opacityThreshold = {threshold}
        token outputs:surface
    }}
}}
def Mesh "leaf" (
    prepend apiSchemas = ["MaterialBindingAPI"]
)
{{
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 1, 2, 3]
    point3f[] points = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
    rel material:binding = </m>
}}
"#
        )
    };
    let load = |name: &str, opacity: f32, threshold: f32| {
        let path = d.join(name);
        std::fs::write(&path, stage(opacity, threshold)).expect("stage");
        Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
    };
    let cut = load("cut.usda", 0.2, 0.5);
    assert!(cut.meshes.is_empty());
    assert!(
        cut.warnings.iter().any(|w| w.0.contains("cutoff")),
        "{:?}",
        cut.warnings
    );
    let kept = load("kept.usda", 0.9, 0.5);
    assert_eq!(kept.meshes.len(), 1);
    let transmission = |s: &Scene| match &s.materials[s.meshes[0].material].scattering {
        wpbgi::scene::Scattering::Pbr(p) => p.transmission,
        _ => panic!("not a UsdPreviewSurface"),
    };
    assert_eq!(transmission(&kept), 0.0);
    let glass = load("glass.usda", 0.2, 0.0);
    assert!((transmission(&glass) - 0.8).abs() < 1e-6);
}
