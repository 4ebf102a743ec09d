//! Replays the fuzz targets' committed inputs (fuzz/seeds and fuzz/regressions, one folder per
//! target) through the same entry points the fuzzers call
//! (`wpbgi::fuzzing`): none may panic. CI runs this; cargo-fuzz itself is not needed here
//! (docs/fuzzing.md says how to fuzz).

use std::path::Path;

/// The inputs of `target` in every committed folder.
fn inputs(target: &str) -> Vec<std::path::PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz");
    let mut files: Vec<_> = ["seeds", "regressions"]
        .iter()
        .filter_map(|set| std::fs::read_dir(root.join(set).join(target)).ok())
        .flatten()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    files
}

fn replay(target: &str, run: impl Fn(&[u8]) + std::panic::RefUnwindSafe) {
    let files = inputs(target);
    assert!(!files.is_empty(), "no committed inputs for {target}");
    for f in &files {
        let data = std::fs::read(f).expect("readable input");
        if std::panic::catch_unwind(|| run(&data)).is_err() {
            panic!("{target}: {} panics", f.display());
        }
    }
    eprintln!("{target}: {} inputs replayed", files.len());
}

#[test]
fn gltf_inputs_never_panic() {
    replay("gltf", wpbgi::fuzzing::gltf);
}

#[test]
fn usd_inputs_never_panic() {
    for ext in ["usda", "usdc", "usdz"] {
        replay(ext, |data| wpbgi::fuzzing::usd(data, ext));
    }
}

#[test]
fn cache_inputs_never_panic() {
    replay("cache", wpbgi::fuzzing::cache);
}

/// Each input that crashed or hung a fuzzer (fuzz/regressions) now gives a clear error, within
/// 30 seconds. Before: openusd 0.6 looped or recursed without end on names and paths that are
/// not identifiers (an xformOp name, a prim name, a binding, a connection, a reference), its
/// crate reader panicked on malformed usdc, and the gltf crate panicked on an index accessor
/// of VEC3 floats, on a POSITION naming an accessor that does not exist, and on an image in a
/// buffer view without a MIME type. openusd's crate reader allocated sizes read from the file
/// before reading the bytes (an abort: 8 EB for a 1.5 KB file) and traversed children named
/// by punctuation without end; vendor/openusd/PATCHES.md has the reader's patch.
/// `usdc/token-array-claims-more-than-the-file.usdc` aborted the same way in an attribute's
/// value; now that value is refused and the rest of the file loads, so it is only replayed.
#[test]
fn fuzzer_findings_give_clear_errors() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/regressions");
    for (file, expected) in [
        (
            "usda/xform-op-order-with-newlines.usda",
            "xformOpOrder names \"xputs:exposure = 1\\n}\\nformOp:rotateX\", which is not an xformOp",
        ),
        (
            "usda/prim-name-with-brace.usda",
            "/look lists a child named \"colo}r\", which is not an identifier",
        ),
        ("usda/binding-to-garbled-path.usda", "its material binding names"),
        ("usda/surface-output-to-garbled-path.usda", "outputs:surface connects to"),
        ("usda/reference-to-garbled-path.usda", "has references to"),
        (
            "usdc/capacity-overflow.usdc",
            "Unable to read PATHS section: Failed to decompress data",
        ),
        ("usdc/lz4-chunked.usdc", "lz4 chunked decompression"),
        ("usdc/path-table-index-past-end.usdc", "openusd failed reading it (\"index out of bounds"),
        (
            "usdc/tokens-claim-more-than-the-file.usdc",
            "Compressed block claims 8155847897241313652 bytes but the file ends after 1469",
        ),
        ("usdc/child-named-by-punctuation.usdc", "/ lists a child named \";-)\""),
        (
            "gltf/index-accessor-of-vec3.gltf",
            "index accessor 0 holds Vec3 of F32, where glTF allows Scalar of U8 or U16 or U32",
        ),
        (
            "gltf/position-accessor-out-of-range.gltf",
            "POSITION names accessor 0, but the file has 0 accessors",
        ),
        (
            "gltf/image-without-mime-type.gltf",
            "image 0 needs a bufferView with a mimeType, or a uri",
        ),
    ] {
        let path = root.join(file);
        let (send, receive) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let _ = send.send(wpbgi::scene::Scene::load(&path).map(|_| ()));
        });
        match receive.recv_timeout(std::time::Duration::from_secs(30)) {
            Ok(Err(e)) => assert!(e.to_string().contains(expected), "{file}: {e}"),
            Ok(Ok(())) => panic!("{file} loads"),
            Err(_) => panic!("{file} hangs or panics"),
        }
    }
}
