//! Bad input never panics: each broken file gives its own clear error naming the file and the
//! object (or, for degenerate triangles, a warning and a dropped triangle).

use std::path::Path;
use wpbgi::scene::Scene;
use wpbgi::Error;

mod common;
use common::{b64, triangle_gltf};

const TRI: [[f32; 3]; 3] = [[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]];

fn dir() -> common::Scratch {
    common::Scratch::new("import")
}

fn load_str(name: &str, text: &str) -> Result<Scene, Error> {
    let dir = dir();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    Scene::load(&p)
}

fn message(r: Result<Scene, Error>) -> String {
    match r {
        Ok(_) => panic!("the broken file was accepted"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn valid_triangle_loads() {
    let s = load_str("ok.gltf", &triangle_gltf(&TRI, &[0, 1, 2], "")).unwrap();
    assert_eq!(s.triangle_count(), 1);
    assert!(s.has_emitters());
}

fn minimal_glb() -> Vec<u8> {
    let json = br#"{"asset":{"version":"2.0"}}  "#; // padded to a multiple of 4
    let mut glb = Vec::new();
    let total = 12 + 8 + json.len();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&(total as u32).to_le_bytes());
    glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(json);
    glb
}

#[test]
fn truncated_glb() {
    let glb = minimal_glb();
    let dir = dir();
    let p = dir.join("truncated.glb");
    std::fs::write(&p, &glb[..glb.len() - 9]).unwrap();
    let m = message(Scene::load(&p));
    assert!(m.contains("truncated.glb") && m.contains("GLB"), "{m}");
}

#[test]
fn wrong_magic() {
    let mut glb = minimal_glb();
    glb[..4].copy_from_slice(b"gLTF");
    let dir = dir();
    let p = dir.join("magic.glb");
    std::fs::write(&p, &glb).unwrap();
    let m = message(Scene::load(&p));
    assert!(m.contains("magic.glb") && m.contains("magic"), "{m}");
}

#[test]
fn broken_json() {
    let m = message(load_str(
        "broken.gltf",
        r#"{"asset": {"version": "2.0"}, "nodes": [ "#,
    ));
    assert!(m.contains("broken.gltf") && m.contains("JSON"), "{m}");
}

#[test]
fn missing_bin() {
    let text = triangle_gltf(&TRI, &[0, 1, 2], "");
    let start = text.find("data:").unwrap();
    let end = text[start..].find('"').unwrap() + start;
    let text = format!("{}missing.bin{}", &text[..start], &text[end..]);
    let m = message(load_str("nobin.gltf", &text));
    assert!(
        m.contains("nobin.gltf") && m.contains("buffer 0") && m.contains("missing.bin"),
        "{m}"
    );
}

#[test]
fn out_of_range_indices() {
    let m = message(load_str("idx.gltf", &triangle_gltf(&TRI, &[0, 1, 7], "")));
    assert!(
        m.contains("idx.gltf") && m.contains("\"tri\"") && m.contains("index 7 is out of range"),
        "{m}"
    );
}

#[test]
fn accessor_past_buffer_end() {
    let text = triangle_gltf(&TRI, &[0, 1, 2], "")
        .replace(r#""count":3,"type":"VEC3""#, r#""count":30,"type":"VEC3""#);
    let m = message(load_str("acc.gltf", &text));
    assert!(m.contains("acc.gltf") && m.contains("past the end"), "{m}");
}

#[test]
fn nan_and_inf_positions() {
    for (name, bad) in [("nan.gltf", f32::NAN), ("inf.gltf", f32::INFINITY)] {
        let m = message(load_str(
            name,
            &triangle_gltf(&[[0., 0., 0.], [bad, 0., 0.], [0., 1., 0.]], &[0, 1, 2], ""),
        ));
        assert!(
            m.contains(name) && m.contains("vertex 1") && m.contains("NaN or infinite"),
            "{m}"
        );
    }
}

#[test]
fn zero_area_triangles_are_dropped_with_a_warning() {
    let pos = [[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [2., 0., 0.]];
    let s = load_str(
        "degenerate.gltf",
        &triangle_gltf(&pos, &[0, 1, 2, 0, 1, 3], ""),
    )
    .unwrap();
    assert_eq!(s.triangle_count(), 1);
    assert!(
        s.warnings
            .iter()
            .any(|w| w.0.contains("dropped 1 degenerate")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn texture_that_does_not_decode() {
    let mut doc: serde_json::Value =
        serde_json::from_str(&triangle_gltf(&TRI, &[0, 1, 2], "")).unwrap();
    let not_png = b64(b"\x89PNG\r\n\x1a\n this is not really a png");
    doc["materials"][0]["pbrMetallicRoughness"] =
        serde_json::json!({"baseColorTexture": {"index": 0}});
    doc["textures"] = serde_json::json!([{"source": 0}]);
    doc["images"] =
        serde_json::json!([{"name": "albedo", "uri": format!("data:image/png;base64,{not_png}")}]);
    let m = message(load_str("tex.gltf", &doc.to_string()));
    assert!(
        m.contains("tex.gltf") && m.contains("albedo") && m.contains("does not decode"),
        "{m}"
    );
}

#[test]
fn unsupported_extension_and_no_emitter() {
    let m = message(Scene::load(Path::new("scene.obj")));
    assert!(m.contains("scene.obj"), "{m}");
    let s = load_str(
        "dark.gltf",
        &triangle_gltf(&TRI, &[0, 1, 2], "")
            .replace(r#""emissiveFactor":[1,1,1]"#, r#""emissiveFactor":[0,0,0]"#),
    )
    .unwrap();
    let m = s.check_renderable().unwrap_err().to_string();
    assert!(m.contains("dark.gltf") && m.contains("no emitter"), "{m}");
}

#[test]
fn bad_mitsuba_parameters_name_the_material() {
    let m = message(load_str(
        "mi.gltf",
        &triangle_gltf(
            &TRI,
            &[0, 1, 2],
            r#","extras":{"mitsuba":{"type":"roughconductor","distribution":"phong"}}"#,
        ),
    ));
    assert!(
        m.contains("mi.gltf") && m.contains("\"lamp\"") && m.contains("phong"),
        "{m}"
    );
}
