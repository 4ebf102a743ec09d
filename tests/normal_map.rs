//! Normal maps (issue 22) against the analytic answer: a diffuse floor of albedo ρ under a
//! distant light of irradiance E from straight above sends ρ E cos θ / π, where θ is the angle
//! between the light and the shading normal (Mitsuba's `diffuse` takes its cosine in the
//! shading frame). With a constant normal map tilting the normal by θ the floor darkens by
//! cos θ in the path tracer, in the bake's surfels (the light they send on) and in the final
//! render from the cache; the flat map (0.5, 0.5, 1) changes nothing; and the tilt follows the image's axes (+X right, along +s;
//! +Y up, along +t), checked by a light from the side the map leans to and from the other.
//!
//! The scene is USD written here: a 2 × 2 floor facing +Y with texture coordinates
//! ((1 + x) / 2, (1 − z) / 2), a 1 × 1 normal map read raw with scale 2 and bias −1 (as
//! UsdPreviewSurface asks of an 8-bit map), a `DistantLight` (normalize: its intensity is the
//! irradiance) and a camera looking straight down.

use glam::Vec3;
mod common;

use std::path::{Path, PathBuf};
use wpbgi::bake::{bake, BakeSettings, Quality};
use wpbgi::reference::{render, RenderSettings};
use wpbgi::surfels::radiance::SurfelRadiance;

use wpbgi::scene::Scene;

const ALBEDO: f32 = 0.5;
const IRRADIANCE: f32 = 3.0;

fn dir() -> common::Scratch {
    common::Scratch::new("normal-map")
}

/// The stage with the normal map `texel` (8-bit RGB) and the light travelling along
/// `light_direction`; also the shading normal the texel encodes (8-bit values as stored).
fn write_scene(d: &Path, name: &str, texel: [u8; 3], light_direction: Vec3) -> (PathBuf, Vec3) {
    let png = d.join(format!("{name}.png"));
    image::RgbImage::from_pixel(1, 1, image::Rgb(texel))
        .save(&png)
        .expect("png");
    // The light's -Z axis is its direction: a rotation taking -Z to `light_direction`.
    let d_l = light_direction.normalize();
    let q = glam::Quat::from_rotation_arc(Vec3::NEG_Z, d_l);
    let usda = format!(
        r#"#usda 1.0
(
    metersPerUnit = 1
    upAxis = "Y"
)

def Mesh "floor" (
    prepend apiSchemas = ["MaterialBindingAPI"]
)
{{
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 1, 2, 3]
    rel material:binding = </look>
    point3f[] points = [(-1, 0, 1), (1, 0, 1), (1, 0, -1), (-1, 0, -1)]
    texCoord2f[] primvars:st = [(0, 0), (1, 0), (1, 1), (0, 1)] (
        interpolation = "vertex"
    )
}}

def Material "look"
{{
    token outputs:surface.connect = </look/surface.outputs:surface>

    def Shader "surface"
    {{
        uniform token info:id = "UsdPreviewSurface"
        color3f inputs:diffuseColor = ({ALBEDO}, {ALBEDO}, {ALBEDO})
        normal3f inputs:normal.connect = </look/normals.outputs:rgb>
        token outputs:surface
    }}

    def Shader "reader"
    {{
        uniform token info:id = "UsdPrimvarReader_float2"
        token inputs:varname = "st"
        float2 outputs:result
    }}

    def Shader "normals"
    {{
        uniform token info:id = "UsdUVTexture"
        float4 inputs:bias = (-1, -1, -1, 0)
        asset inputs:file = @{name}.png@
        float4 inputs:scale = (2, 2, 2, 1)
        token inputs:sourceColorSpace = "raw"
        float2 inputs:st.connect = </look/reader.outputs:result>
        float3 outputs:rgb
    }}
}}

def DistantLight "sun"
{{
    float inputs:angle = 0
    float inputs:intensity = {IRRADIANCE}
    bool inputs:normalize = true
    quatf xformOp:orient = ({}, {}, {}, {})
    uniform token[] xformOpOrder = ["xformOp:orient"]
}}

def Camera "camera"
{{
    float focalLength = 50
    float horizontalAperture = 20
    float verticalAperture = 20
    double3 xformOp:translate = (0, 3, 0)
    float xformOp:rotateX = -90
    uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateX"]
}}
"#,
        q.w, q.x, q.y, q.z
    );
    let path = d.join(format!("{name}.usda"));
    std::fs::write(&path, usda).expect("usda");
    // Tangent space: x along +s (world +x), y along +t (world −z: t = (1 − z) / 2), z the
    // floor's normal (world +y).
    let m = Vec3::from(texel.map(|v| 2.0 * f32::from(v) / 255.0 - 1.0));
    let normal = Vec3::new(m.x, m.z, -m.y).normalize();
    (path, normal)
}

fn mean(pixels: &[Vec3]) -> Vec3 {
    pixels.iter().copied().sum::<Vec3>() / pixels.len() as f32
}

#[test]
fn a_normal_map_tilts_the_cosine_as_analytic() {
    let d = dir();
    let down = Vec3::NEG_Y;
    let slanted = Vec3::new(-1.0, -1.0, 0.0);
    for (name, texel, light) in [
        ("flat", [128, 128, 255], down),
        ("tilted", [218, 128, 218], down),
        ("tilted-up", [128, 218, 218], down),
        // The light comes from +x, above: the map leaning to +x faces it more than the floor.
        ("towards", [218, 128, 218], slanted),
        ("away", [38, 128, 218], slanted),
        // From −z, above: the map leaning up the image (+t, world −z) faces it.
        ("up-towards", [128, 218, 218], Vec3::new(0.0, -1.0, 1.0)),
        ("up-away", [128, 38, 218], Vec3::new(0.0, -1.0, 1.0)),
    ] {
        let (path, normal) = write_scene(&d, name, texel, light);
        let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        let camera = scene.camera(None, 16, 16).expect("camera");
        let expected =
            ALBEDO * IRRADIANCE * normal.dot(-light.normalize()).max(0.0) / std::f32::consts::PI;
        let traced = render(
            &scene,
            &camera,
            &RenderSettings {
                spp: 4,
                max_depth: -1,
                seed: 1,
                ..Default::default()
            },
            &|_| {},
        )
        .expect("path tracer");
        let m = mean(&traced.mean.pixels);
        eprintln!("{name}: normal {normal}, path tracer {m}, expected {expected}");
        // A delta light on a plane that fills the view: no noise, only rounding.
        assert!(
            (m - Vec3::splat(expected)).abs().max_element() <= 1e-4 * expected.max(1e-3),
            "{name}: path tracer {m}, expected {expected}"
        );
        let baked = bake(
            &scene,
            &BakeSettings {
                points: 2000,
                ..BakeSettings::preset(Quality::Draft).direct_only()
            },
            &|_, _| {},
        )
        .expect("bakes");
        // Every surfel of the floor holds the mapped cosine's light too (a delta light: exact
        // to rounding), which is what it sends to other surfaces.
        for (i, r) in baked.radiance.iter().enumerate() {
            let SurfelRadiance::Rgb(v) = r else {
                panic!("{name}: a diffuse surfel with a map");
            };
            assert!(
                (*v - Vec3::splat(expected)).abs().max_element() <= 1e-4 * expected.max(1e-3),
                "{name}: surfel {i} holds {v}, expected {expected}"
            );
        }
        let cache = wpbgi::bake::store::in_memory(&path, &baked).expect("cache");
        let out = common::final_render(&scene, &cache, &camera);
        let m = mean(&out.beauty.pixels);
        eprintln!("{name}: final render {m}");
        assert!(
            (m - Vec3::splat(expected)).abs().max_element() <= 1e-4 * expected.max(1e-3),
            "{name}: final render {m}, expected {expected}"
        );
    }
}
