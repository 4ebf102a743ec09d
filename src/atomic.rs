//! Atomic file output: write to a temporary file next to the target, sync it, rename it into
//! place. A crash or a kill at any moment leaves either the previous file or the new one under
//! the target name, never a partial one (rename is atomic within a file system).

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// Write through a temporary file next to `path`, then rename it into place. `write` receives
/// the temporary path; on its failure the temporary file is removed.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> std::result::Result<(), String>,
) -> Result<()> {
    let output_error = |reason: String| Error::Output {
        path: path.to_path_buf(),
        reason,
    };
    let name = path
        .file_name()
        .ok_or_else(|| output_error("not a file name".into()))?
        .to_string_lossy()
        .into_owned();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default();
    // The extension stays last: some writers pick the format from it.
    let tmp: PathBuf = path.with_file_name(format!(".{name}.{}.tmp.{ext}", std::process::id()));
    if let Err(e) = write(&tmp) {
        let _ = std::fs::remove_file(&tmp);
        return Err(output_error(e));
    }
    std::fs::File::open(&tmp)
        .and_then(|f| f.sync_all())
        .map_err(|e| output_error(e.to_string()))?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        output_error(e.to_string())
    })
}
