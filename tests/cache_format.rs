//! The `.wpc` container: round trip, and every kind of damage refused with its own error.

mod common;

use std::path::{Path, PathBuf};
use wpbgi::cache::{content_hash, write, Cache, CacheError, ALIGNMENT, FORMAT_VERSION};
use xxhash_rust::xxh3::xxh3_64;

/// A folder of its own per test (tests run in parallel, and one checks for leftover files).
fn dir(test: &str) -> common::Scratch {
    common::Scratch::new(&format!("cache-{test}"))
}

fn sections() -> Vec<(&'static str, Vec<u8>)> {
    vec![
        ("plan", br#"{"bounces":0}"#.to_vec()),
        (
            "surfels",
            (0..1000u32).flat_map(|i| i.to_le_bytes()).collect(),
        ),
        ("empty", Vec::new()),
        ("nodes", (0..333u32).map(|i| (i * 7) as u8).collect()),
    ]
}

/// A sample cache `name` in a scratch folder of its own (kept while the first value lives),
/// its bytes and its hash.
fn sample_file(name: &str) -> (common::Scratch, PathBuf, Vec<u8>, [u8; 16]) {
    let dir = dir(name);
    let path = dir.join(name);
    let hash = content_hash(&[b"scene bytes", b"settings"]);
    let s = sections();
    let refs: Vec<(&str, &[u8])> = s.iter().map(|(n, b)| (*n, b.as_slice())).collect();
    write(&path, hash, &refs).expect("writes");
    let bytes = std::fs::read(&path).expect("reads");
    (dir, path, bytes, hash)
}

#[test]
fn round_trip() {
    let (_dir, path, bytes, hash) = sample_file("round.wpc");
    let c = Cache::read(&path, Some(hash)).expect("valid");
    assert_eq!(c.version, FORMAT_VERSION);
    assert_eq!(c.len(), bytes.len());
    for (name, data) in sections() {
        assert_eq!(c.section(name).expect("present"), data.as_slice());
    }
    // Coarse to fine: the order written is kept, and every section is aligned for mmap.
    let names: Vec<&str> = c.sections.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["plan", "surfels", "empty", "nodes"]);
    assert!(c
        .sections
        .iter()
        .all(|s| (s.offset as usize).is_multiple_of(ALIGNMENT)));
    assert!(matches!(
        c.section("missing"),
        Err(CacheError::MissingSection { .. })
    ));
    // No temporary file is left next to it.
    let leftovers = std::fs::read_dir(path.parent().expect("dir"))
        .expect("list")
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp."))
        .count();
    assert_eq!(leftovers, 0);
}

/// A cache is mapped, not copied, and a new cache written over its path (as a bake writes:
/// to a temporary file, then renamed) leaves a reader of the old one reading the old bytes
/// to its end: the rule farm renders rely on (docs/farm.md).
#[test]
fn a_mapped_cache_survives_a_new_one_renamed_over_it() {
    let (_dir, path, _, hash) = sample_file("replaced.wpc");
    let old = Cache::read(&path, Some(hash)).expect("valid");
    let new_hash = content_hash(&[b"another scene"]);
    write(&path, new_hash, &[("plan", b"{}".as_slice())]).expect("writes");
    for (name, data) in sections() {
        assert_eq!(old.section(name).expect("still there"), data.as_slice());
    }
    let new = Cache::read(&path, Some(new_hash)).expect("the new one");
    assert_eq!(new.section("plan").expect("plan"), b"{}");
}

#[test]
fn every_truncation_is_reported_as_truncated() {
    let (_dir, path, bytes, _) = sample_file("trunc.wpc");
    for len in 0..bytes.len() {
        match Cache::parse(&path, bytes[..len].to_vec(), None) {
            Err(CacheError::Truncated { .. }) => {}
            other => panic!("truncated to {len} bytes: {other:?}"),
        }
    }
}

#[test]
fn every_flipped_byte_is_refused() {
    let (_dir, path, bytes, _) = sample_file("flip.wpc");
    let c = Cache::parse(&path, bytes.clone(), None).expect("valid");
    for at in 0..bytes.len() {
        let mut b = bytes.clone();
        b[at] ^= 0x10;
        let r = Cache::parse(&path, b, None);
        assert!(r.is_err(), "byte {at} flipped and still accepted");
        // A flip inside a section's data names that section.
        if let Some(s) = c
            .sections
            .iter()
            .find(|s| (s.offset..s.offset + s.length).contains(&(at as u64)))
        {
            match r {
                Err(CacheError::Corrupted { what, .. }) => {
                    assert!(what.contains(&s.name), "byte {at}: {what}")
                }
                other => panic!("byte {at} in section {}: {other:?}", s.name),
            }
        }
    }
}

/// Rewrite header field bytes and re-seal the header checksum, as a newer or foreign writer
/// would have produced them.
fn reseal(mut b: Vec<u8>, at: usize, value: &[u8]) -> Vec<u8> {
    b[at..at + value.len()].copy_from_slice(value);
    let sum = xxh3_64(&b[..56]);
    b[56..64].copy_from_slice(&sum.to_le_bytes());
    b
}

#[test]
fn foreign_newer_byte_order_and_stale_files_have_their_own_errors() {
    let (_dir, path, bytes, hash) = sample_file("kinds.wpc");
    let p = Path::new(&path);
    let mut foreign = bytes.clone();
    foreign[1] = b'X';
    assert!(matches!(
        Cache::parse(p, foreign, None),
        Err(CacheError::Foreign { .. })
    ));
    assert!(matches!(
        Cache::parse(p, b"glTF binary, not a cache at all".to_vec(), None),
        Err(CacheError::Foreign { .. })
    ));
    let newer = reseal(bytes.clone(), 8, &(FORMAT_VERSION + 1).to_le_bytes());
    match Cache::parse(p, newer, None) {
        Err(e @ CacheError::NewerVersion { .. }) => assert!(e.to_string().contains("newer")),
        other => panic!("{other:?}"),
    }
    let swapped = reseal(bytes.clone(), 12, &0x0102_0304u32.to_be_bytes());
    assert!(matches!(
        Cache::parse(p, swapped, None),
        Err(CacheError::ByteOrder { .. })
    ));
    let other_scene = content_hash(&[b"another scene", b"settings"]);
    assert_ne!(other_scene, hash);
    match Cache::read(p, Some(other_scene)) {
        Err(e @ CacheError::Stale { .. }) => assert!(e.to_string().contains("rebake")),
        other => panic!("{other:?}"),
    }
    assert!(Cache::read(p, Some(hash)).is_ok());
}

#[test]
fn content_hash_separates_its_parts() {
    assert_ne!(content_hash(&[b"ab", b"c"]), content_hash(&[b"a", b"bc"]));
    assert_eq!(content_hash(&[b"ab", b"c"]), content_hash(&[b"ab", b"c"]));
}
