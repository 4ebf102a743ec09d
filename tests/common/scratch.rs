//! Scratch folders for tests that write files: one per test, removed with everything in it
//! when the test passes, kept (and named on standard error) when it fails. A suite run wrote
//! about a gigabyte of caches and images into the temporary folder and left it there; twelve
//! runs had left 12 GB. Shared by the crate's tests and the plugin's (`#[path]`).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// A fresh, empty folder `<temp>/wpbgi-<name>-<process id>-<n>`, which derefs to its path.
/// `n` counts the process's scratch folders, so tests running in parallel never share one.
pub struct Scratch(PathBuf);

impl Scratch {
    /// Create the folder (emptied first, should a run with the same process id have left it).
    pub fn new(name: &str) -> Scratch {
        static MADE: AtomicUsize = AtomicUsize::new(0);
        let n = MADE.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("wpbgi-{name}-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("create a scratch folder");
        Scratch(dir)
    }
}

impl std::ops::Deref for Scratch {
    type Target = Path;

    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if std::thread::panicking() {
            eprintln!("kept for a look: {}", self.0.display());
        } else {
            // A file still open elsewhere (a mapped cache) goes with its last handle.
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}
