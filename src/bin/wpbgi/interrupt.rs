//! Ctrl-C for the command line (issue 22).
//!
//! The first SIGINT or SIGTERM sets a flag that the bake and the render look at between
//! surfels, receiver groups and tiles: the command stops, leaves its outputs as they were
//! (every output is written to a temporary file and renamed into place, `wpbgi::atomic`),
//! says so in one line and exits with status 130, as shells report a process stopped by
//! Ctrl-C. A command that has not stopped within [`GRACE`] (a stage that does not look at the
//! flag, such as loading a scene) and a second Ctrl-C exit at once with 130, after removing
//! the temporary files of the command's outputs.
//!
//! Signals are caught on Unix only; elsewhere Ctrl-C keeps the system's default (the process
//! ends, the outputs are still whole: they are renamed into place only once written).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::Duration;

/// The exit status of an interrupted command (128 + SIGINT).
pub const EXIT_INTERRUPTED: i32 = 130;

/// How long an interrupted command may take to stop by itself.
pub const GRACE: Duration = Duration::from_millis(500);

/// Set by the first Ctrl-C.
static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// The outputs whose temporary files an exit past the grace removes.
static OUTPUTS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// The flag the library's cancellable calls look at.
pub fn flag() -> &'static AtomicBool {
    &INTERRUPTED
}

/// Whether Ctrl-C was pressed.
pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::Relaxed)
}

/// Name the files the command writes: an exit past the grace removes their temporary files.
pub fn guard_outputs(paths: impl IntoIterator<Item = PathBuf>) {
    if let Ok(mut outputs) = OUTPUTS.lock() {
        outputs.extend(paths);
    }
}

/// Exit with [`EXIT_INTERRUPTED`], the command's outputs untouched.
pub fn exit_interrupted() -> ! {
    if let Ok(outputs) = OUTPUTS.lock() {
        for path in outputs.iter() {
            if let Some(tmp) = wpbgi::atomic::temporary_path(path) {
                let _ = std::fs::remove_file(tmp);
            }
        }
    }
    eprintln!("interrupted: the outputs were left as they were");
    std::process::exit(EXIT_INTERRUPTED)
}

/// Catch SIGINT and SIGTERM (see the module docs) and start the thread that ends a command
/// that does not stop within the grace.
pub fn install() {
    #[cfg(unix)]
    unix::install();
    std::thread::Builder::new()
        .name("interrupt".into())
        .spawn(|| {
            while !interrupted() {
                std::thread::sleep(Duration::from_millis(20));
            }
            std::thread::sleep(GRACE);
            exit_interrupted()
        })
        .ok();
}

#[cfg(unix)]
mod unix {
    use super::{EXIT_INTERRUPTED, INTERRUPTED};
    use std::sync::atomic::Ordering;

    extern "C" fn on_signal(_: libc::c_int) {
        // A second signal ends the process at once (only async-signal-safe calls here).
        if INTERRUPTED.swap(true, Ordering::SeqCst) {
            unsafe { libc::_exit(EXIT_INTERRUPTED) };
        }
    }

    pub fn install() {
        for signal in [libc::SIGINT, libc::SIGTERM] {
            // SAFETY: a zeroed sigaction is valid; the handler only stores to an atomic or
            // calls _exit, both async-signal-safe.
            unsafe {
                let mut action: libc::sigaction = std::mem::zeroed();
                action.sa_sigaction = on_signal as extern "C" fn(libc::c_int) as usize;
                action.sa_flags = libc::SA_RESTART;
                libc::sigemptyset(&mut action.sa_mask);
                libc::sigaction(signal, &action, std::ptr::null_mut());
            }
        }
    }
}
