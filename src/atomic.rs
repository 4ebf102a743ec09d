//! Atomic file output: write to a temporary file next to the target, sync it, rename it into
//! place. A crash or a kill at any moment leaves either the previous file or the new one under
//! the target name, never a partial one (rename is atomic within a file system).

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// The temporary file this process writes `path` through: hidden, next to it, named after
/// the process (two processes writing one path do not share it), with the extension last
/// (some writers pick the format from it). `None` for a path without a file name.
pub fn temporary_path(path: &Path) -> Option<PathBuf> {
    let name = path.file_name()?.to_string_lossy().into_owned();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default();
    Some(path.with_file_name(format!(".{name}.{}.tmp.{ext}", std::process::id())))
}

/// Write through a temporary file next to `path` ([`temporary_path`]), then rename it into
/// place. `write` receives the temporary path; on its failure the temporary file is removed.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> std::result::Result<(), String>,
) -> Result<()> {
    replace(path, write, true)
}

/// [`write_atomically`] without syncing the file before the rename, for a file that can be
/// made again and is checked when read (a kept transport): after a power cut it may be
/// empty or short under its name, never a mixture of two versions while the system runs.
pub fn write_atomically_unsynced(
    path: &Path,
    write: impl FnOnce(&Path) -> std::result::Result<(), String>,
) -> Result<()> {
    replace(path, write, false)
}

fn replace(
    path: &Path,
    write: impl FnOnce(&Path) -> std::result::Result<(), String>,
    sync: bool,
) -> Result<()> {
    let tmp = temporary_path(path).ok_or_else(|| Error::Output {
        path: path.to_path_buf(),
        reason: "not a file name".into(),
    })?;
    let output_error = |reason: String| Error::Output {
        path: path.to_path_buf(),
        reason,
    };
    if let Err(e) = write(&tmp) {
        let _ = std::fs::remove_file(&tmp);
        return Err(output_error(e));
    }
    if sync {
        std::fs::File::open(&tmp)
            .and_then(|f| f.sync_all())
            .map_err(|e| output_error(e.to_string()))?;
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        output_error(e.to_string())
    })
}
