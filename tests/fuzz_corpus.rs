//! Replays the fuzz targets' committed inputs (fuzz/seeds, fuzz/corpus and fuzz/regressions,
//! one folder per target) through the same entry points the fuzzers call
//! (`wpbgi::fuzzing`): none may panic. CI runs this; cargo-fuzz itself is not needed here
//! (docs/fuzzing.md says how to fuzz).

use std::path::Path;

/// The inputs of `target` in every committed folder.
fn inputs(target: &str) -> Vec<std::path::PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz");
    let mut files: Vec<_> = ["seeds", "corpus", "regressions"]
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
