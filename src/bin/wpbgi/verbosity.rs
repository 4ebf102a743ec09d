//! How much the command line says on standard error: `-q` (errors and warnings only), the
//! default (what each command did, with its figures), or `-v` (also the scene as loaded and
//! the final render's gather statistics). Set once from the global flags; progress bars are
//! hidden when quiet. `--json` output on standard output does not depend on it.

use std::sync::atomic::{AtomicU8, Ordering};

const QUIET: u8 = 0;
const NORMAL: u8 = 1;
const VERBOSE: u8 = 2;

static LEVEL: AtomicU8 = AtomicU8::new(NORMAL);

/// Set the level from the global `-q` and `-v` flags (clap keeps them exclusive).
pub fn set(quiet: bool, verbose: bool) {
    let level = match (quiet, verbose) {
        (true, _) => QUIET,
        (_, true) => VERBOSE,
        _ => NORMAL,
    };
    LEVEL.store(level, Ordering::Relaxed);
}

pub fn quiet() -> bool {
    LEVEL.load(Ordering::Relaxed) == QUIET
}

pub fn verbose() -> bool {
    LEVEL.load(Ordering::Relaxed) == VERBOSE
}
