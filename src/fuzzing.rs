//! Entry points for the fuzz targets in `fuzz/` (cargo-fuzz), shared with the test that replays
//! their committed corpora (`tests/fuzz_corpus.rs`), so that CI runs exactly what was fuzzed.
//! Each takes arbitrary bytes, runs the real reader on them, and must return (with or without
//! an error) rather than panic, hang or exhaust memory.

use crate::cache::store::NO_MAP;
use std::path::{Path, PathBuf};

/// glTF JSON or GLB bytes through the importer.
pub fn gltf(data: &[u8]) {
    let _ = crate::scene::Scene::from_gltf_bytes(Path::new("fuzz.gltf"), data);
}

/// USD bytes, written to a file with extension `ext` (`usda`, `usdc` or `usdz`: openusd reads
/// stages from files), through the importer.
pub fn usd(data: &[u8], ext: &str) {
    let path = scratch(ext);
    if std::fs::write(&path, data).is_ok() {
        let _ = crate::scene::Scene::load(&path);
    }
    let _ = std::fs::remove_file(&path);
}

/// Cache file bytes through the reader, then every map the cache holds through the decoder.
pub fn cache(data: &[u8]) {
    let Ok(cache) =
        crate::cache::store::BakedCache::from_bytes(Path::new("fuzz.wpc"), data.to_vec())
    else {
        return;
    };
    for s in &cache.surfels {
        if s.map != NO_MAP {
            let _ = cache.map::<glam::Vec3>(s.map);
        }
    }
    for n in &cache.nodes {
        for m in [n.g, n.h].into_iter().filter(|&m| m != NO_MAP) {
            let _ = cache.map::<glam::Vec3>(m);
        }
        for m in [n.area_g, n.area_h].into_iter().filter(|&m| m != NO_MAP) {
            let _ = cache.map::<f32>(m);
        }
    }
}

/// A file name of this process and thread (fuzzers and tests run several threads), in memory
/// where Linux has /dev/shm.
fn scratch(ext: &str) -> PathBuf {
    let dir = Path::new("/dev/shm");
    let dir = if dir.is_dir() {
        dir.to_path_buf()
    } else {
        std::env::temp_dir()
    };
    // Thread ids print as `ThreadId(N)`; keep the digits.
    let thread: String = format!("{:?}", std::thread::current().id())
        .chars()
        .filter(char::is_ascii_digit)
        .collect();
    dir.join(format!("wpbgi-fuzz-{}-{thread}.{ext}", std::process::id()))
}
