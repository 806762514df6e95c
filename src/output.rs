//! Writing output files: complete or not at all.

use crate::error::{Error, Result};
use std::io::Write;
use std::path::Path;

/// The directory a file at `path` lives in (`.` for a bare name).
pub fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// A temporary file beside `path` (same directory, so a rename publishes
/// it atomically), named `.NAME.*.partial`; deleted if dropped unpublished.
/// Refuses a `path` that is a directory.
pub fn temp_beside(path: &Path) -> Result<tempfile::NamedTempFile> {
    if path.is_dir() {
        return Err(Error::io(
            path,
            "create",
            std::io::Error::new(std::io::ErrorKind::IsADirectory, "is a directory"),
        ));
    }
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    tempfile::Builder::new()
        .prefix(&format!(".{name}."))
        .suffix(".partial")
        .tempfile_in(parent_dir(path))
        .map_err(|e| Error::io(path, "create", e))
}

/// Write `bytes` to `path` through a temporary file in the same directory,
/// renamed into place only when fully written and synced.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut tmp = temp_beside(path)?;
    tmp.write_all(bytes)
        .map_err(|e| Error::io(path, "write", e))?;
    publish(tmp, path)
}

/// Sync a fully written temporary file from [`temp_beside`], make it
/// readable like a normal output file, and rename it to `path`.
pub fn publish(tmp: tempfile::NamedTempFile, path: &Path) -> Result<()> {
    tmp.as_file()
        .sync_all()
        .map_err(|e| Error::io(path, "write", e))?;
    use std::os::unix::fs::PermissionsExt;
    tmp.as_file()
        .set_permissions(std::fs::Permissions::from_mode(0o644))
        .map_err(|e| Error::io(path, "write", e))?;
    tmp.persist(path)
        .map_err(|e| Error::io(path, "rename into place", e.error))?;
    Ok(())
}
