//! Safe output: write to a temporary file in the destination folder, then rename it into place,
//! so a failed or interrupted write never leaves a partial file or destroys an existing one.

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// A fresh temporary path beside `dest`, keeping its extension (encoders choose by it).
pub fn temp_path_for(dest: &Path) -> Result<PathBuf> {
    let dir = match dest.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        return Err(Error::invalid(format!(
            "{}: the output folder {} does not exist",
            dest.display(),
            dir.display()
        )));
    }
    let name = dest
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    let ext = dest
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let nonce = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos())
        .unwrap_or(0);
    Ok(dir.join(format!(".{name}.{}-{nonce}.tmp{ext}", std::process::id())))
}

/// Renames `tmp` to `dest` (atomic on one filesystem); removes `tmp` if that fails.
pub fn rename_into_place(tmp: &Path, dest: &Path) -> Result<()> {
    std::fs::rename(tmp, dest).map_err(|source| {
        let _ = std::fs::remove_file(tmp);
        Error::Io {
            path: dest.to_path_buf(),
            source,
        }
    })
}

/// Writes `bytes` to `dest` through a temporary file.
pub fn write_atomic(dest: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = temp_path_for(dest)?;
    std::fs::write(&tmp, bytes).map_err(|source| {
        let _ = std::fs::remove_file(&tmp);
        Error::Io {
            path: dest.to_path_buf(),
            source,
        }
    })?;
    rename_into_place(&tmp, dest)
}
