//! What the plugin's tests share: the test scene, scratch folders, and the Rust API's own
//! bake and render, which every route through the C ABI must reproduce byte for byte.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use wpbgi::bake::bounce::BounceSettings;
use wpbgi::bake::{bake, BakeSettings};
use wpbgi::render::{render_final, FinalSettings};
use wpbgi::scene::Scene;

/// Mitsuba's glossy Cornell box (rough conductor and dielectric walls): the 4D BSDF
/// operators run in its bounces.
pub fn scene_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/mitsuba/cbox-glossy.gltf")
}

#[path = "../../../tests/common/scratch.rs"]
mod scratch;

/// A fresh, empty folder for one test, removed when it passes.
pub fn scratch(name: &str) -> scratch::Scratch {
    scratch::Scratch::new(&format!("plugin-{name}"))
}

/// The small bake every test uses: the default preset (`wpbgi_bake_settings_init`'s) with
/// `points` surfels and `bounces`.
pub const POINTS: u64 = 3000;
pub const BOUNCES: i32 = 1;
pub const SIZE: u32 = 32;

/// The library's settings for the default preset with these points and bounces.
pub fn library_settings(points: u64, bounces: i32) -> BakeSettings {
    BakeSettings {
        points: points as usize,
        bounces: if bounces < 0 {
            BounceSettings::auto()
        } else {
            BounceSettings::exactly(bounces as u32)
        },
        ..BakeSettings::default()
    }
}

/// The cache bytes and the image (RGB floats, rows top first) that the Rust API gives for
/// the test scene.
pub fn rust_api_result(points: u64, bounces: i32, size: u32) -> (Vec<u8>, Vec<f32>) {
    let scene = Scene::load(&scene_path()).expect("load the test scene");
    let baked = bake(&scene, &library_settings(points, bounces), &|_, _| {}).expect("bake");
    let dir = scratch(&format!("rust-api-{points}-{bounces}-{size}"));
    let path = dir.join("rust.wpc");
    wpbgi::bake::store::save(&path, &scene, &baked).expect("save");
    let cache = wpbgi::cache::store::BakedCache::open_fresh(&scene, &path).expect("open");
    let camera = scene.camera(None, size, size).expect("camera");
    let out = render_final(
        &scene,
        &cache,
        &camera,
        &FinalSettings::default(),
        &|_, _| {},
    )
    .expect("render");
    let rgb = out
        .beauty
        .pixels
        .iter()
        .flat_map(|p| p.to_array())
        .collect();
    let bytes = std::fs::read(&path).expect("read the cache");
    let _ = std::fs::remove_dir_all(dir);
    (bytes, rgb)
}

/// The pixels of a little-endian Portable Float Map, rows top first (as the C and Python
/// examples write them).
pub fn read_pfm(path: &Path) -> (u32, u32, Vec<f32>) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = bytes.splitn(4, |&b| b == b'\n');
    assert_eq!(
        lines.next(),
        Some(&b"PF"[..]),
        "{}: not a colour PFM",
        path.display()
    );
    let size = std::str::from_utf8(lines.next().expect("size line")).expect("size text");
    let (w, h) = size.split_once(' ').expect("width and height");
    let (w, h): (u32, u32) = (w.parse().expect("width"), h.parse().expect("height"));
    assert_eq!(lines.next(), Some(&b"-1.0"[..]), "little-endian scale");
    let data = lines.next().expect("pixels");
    assert_eq!(data.len(), w as usize * h as usize * 12, "pixel bytes");
    let floats: Vec<f32> = data
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    let row = w as usize * 3;
    let rgb = floats.chunks_exact(row).rev().flatten().copied().collect();
    (w, h, rgb)
}

/// Whether two float images are the same bit for bit.
pub fn same_bits(a: &[f32], b: &[f32]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}
