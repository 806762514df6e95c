//! Writing output files: complete or not at all.

use crate::error::{Error, Result};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

pub mod direct;

pub mod set;

/// Every temporary file and directory this process created, for
/// [`remove_temporaries`]. Published ones were renamed away and dropped
/// ones deleted, so the list only grows; removing a path that is gone does
/// nothing.
static TEMPORARIES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Held while a run's files are renamed into place ([`set::Staging::publish`]):
/// [`remove_temporaries`] waits for it, so a signal never leaves half a set
/// under final names.
pub(crate) static PUBLISHING: Mutex<()> = Mutex::new(());

/// What names this process's temporaries, `HOST_PID`: the host (letters,
/// digits and '-' only, at most 40 characters) and the process id, so that
/// [`set::sweep_stale`] removes only the leftovers of dead processes on this
/// machine (a directory shared by a cluster's nodes holds other hosts' live
/// ones).
pub fn owner_tag() -> &'static str {
    static TAG: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    TAG.get_or_init(|| format!("{}_{}", set::host_name(), std::process::id()))
}

fn record_temporary(path: &Path) {
    temporaries().push(path.to_path_buf());
}

fn temporaries() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    TEMPORARIES.lock().unwrap_or_else(|e| e.into_inner())
}

/// Make a temporary with `make` and record the path `path_of` gives, both
/// under the list's lock: a signal handler ([`remove_temporaries`]) sees
/// the temporary recorded or not yet made, never made and unrecorded.
pub(crate) fn make_temporary<T>(
    make: impl FnOnce() -> std::io::Result<T>,
    path_of: impl FnOnce(&T) -> &Path,
) -> std::io::Result<T> {
    let mut list = temporaries();
    let made = make()?;
    list.push(path_of(&made).to_path_buf());
    Ok(made)
}

/// A temporary file in `dir` named `PREFIX`, [`owner_tag`], `.`, random
/// characters and `SUFFIX`, deleted if dropped, and recorded so that
/// [`remove_temporaries`] finds it when a signal ends the process before
/// it is dropped or published.
pub fn temp_in(dir: &Path, prefix: &str, suffix: &str) -> std::io::Result<tempfile::NamedTempFile> {
    make_temporary(
        || {
            tempfile::Builder::new()
                .prefix(&format!("{prefix}{}.", owner_tag()))
                .suffix(suffix)
                .tempfile_in(dir)
        },
        |t| t.path(),
    )
}

/// Remove the temporary files and directories of [`temp_in`] and
/// [`set::Staging`] that still exist: what a SIGINT or SIGTERM handler
/// calls before the process exits without running destructors. Waits for
/// a publication in progress to finish. Returns how many it removed.
///
/// The process must exit after it: it keeps the locks of the temporaries'
/// list and of publication ([`PUBLISHING`], which [`publish`] takes too),
/// so that the threads still running can neither make a temporary nor
/// rename one into place (over a scratch file already removed, say)
/// before the exit.
pub fn remove_temporaries() -> usize {
    let publishing = PUBLISHING.lock().unwrap_or_else(|e| e.into_inner());
    let list = temporaries();
    let removed = list
        .iter()
        .filter(|p| match std::fs::symlink_metadata(p) {
            Ok(m) if m.is_dir() => std::fs::remove_dir_all(p).is_ok(),
            Ok(_) => std::fs::remove_file(p).is_ok(),
            Err(_) => false,
        })
        .count();
    std::mem::forget(list);
    std::mem::forget(publishing);
    removed
}

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
    temp_in(parent_dir(path), &format!(".{name}."), ".partial")
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

/// A file written whole after a run's work but made before it, so that an
/// unwritable path fails before the work rather than after (a run's JSON
/// report); with no path, nothing.
pub struct LateFile {
    tmp: Option<(tempfile::NamedTempFile, PathBuf)>,
}

impl LateFile {
    /// The temporary file beside `path`, when there is one.
    pub fn create(path: Option<&Path>) -> Result<LateFile> {
        let tmp = match path {
            Some(p) => Some((temp_beside(p)?, p.to_path_buf())),
            None => None,
        };
        Ok(LateFile { tmp })
    }

    /// Write `text` and publish it under its name.
    pub fn write(self, text: &str) -> Result<()> {
        let Some((mut tmp, path)) = self.tmp else {
            return Ok(());
        };
        tmp.write_all(text.as_bytes())
            .map_err(|e| Error::io(&path, "write", e))?;
        publish(tmp, &path)
    }
}

/// Sync a fully written temporary file from [`temp_beside`], make it
/// readable like a normal output file, and rename it to `path`.
pub fn publish(tmp: tempfile::NamedTempFile, path: &Path) -> Result<()> {
    finalize(&tmp, path)?;
    rename_into_place(tmp, path)
}

/// Rename a finalized temporary file to `path`, unless a signal handler
/// has begun removing the temporaries ([`remove_temporaries`]), in which
/// case this waits for the process's exit.
pub fn rename_into_place(tmp: tempfile::NamedTempFile, path: &Path) -> Result<()> {
    let _publishing = PUBLISHING.lock().unwrap_or_else(|e| e.into_inner());
    tmp.persist(path)
        .map_err(|e| Error::io(path, "rename into place", e.error))?;
    Ok(())
}

/// Sync a fully written temporary file that will become `path`, and make it
/// readable like an ordinary output file (temporary files are created
/// private, 0600 on Unix; elsewhere permissions are left as they are).
pub fn finalize(tmp: &tempfile::NamedTempFile, path: &Path) -> Result<()> {
    let file = tmp.as_file();
    file.sync_all().map_err(|e| Error::io(path, "sync", e))?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        file.set_permissions(std::fs::Permissions::from_mode(0o644))
            .map_err(|e| Error::io(path, "set permissions", e))?;
    }
    Ok(())
}

/// Write all of `buf` at byte `offset` of `file` without moving a shared
/// cursor, so threads can write disjoint parts of one file at once.
pub fn write_all_at(file: &std::fs::File, buf: &[u8], offset: u64) -> std::io::Result<()> {
    #[cfg(unix)]
    {
        std::os::unix::fs::FileExt::write_all_at(file, buf, offset)
    }
    #[cfg(windows)]
    {
        let (mut buf, mut offset) = (buf, offset);
        while !buf.is_empty() {
            match std::os::windows::fs::FileExt::seek_write(file, buf, offset) {
                Ok(0) => return Err(std::io::ErrorKind::WriteZero.into()),
                Ok(n) => {
                    buf = &buf[n..];
                    offset += n as u64;
                }
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
        Ok(())
    }
}

/// Fill `buf` from byte `offset` of `file` without moving a shared cursor.
pub fn read_exact_at(file: &std::fs::File, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
    #[cfg(unix)]
    {
        std::os::unix::fs::FileExt::read_exact_at(file, buf, offset)
    }
    #[cfg(windows)]
    {
        let (mut buf, mut offset) = (buf, offset);
        while !buf.is_empty() {
            match std::os::windows::fs::FileExt::seek_read(file, buf, offset) {
                Ok(0) => return Err(std::io::ErrorKind::UnexpectedEof.into()),
                Ok(n) => {
                    buf = &mut buf[n..];
                    offset += n as u64;
                }
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
        Ok(())
    }
}

/// How much [`StreamOut`] gathers before a write (1 MiB).
const STREAM_CHUNK: usize = 1 << 20;

/// A sequential writer of a new temporary file that goes around the page
/// cache where it can ([`direct`]), for large outputs written once and not
/// read back by this process: the photon map. Whole 4 KiB blocks of 1 MiB
/// chunks are written directly; the last partial block goes through the
/// page cache at [`StreamOut::finish`]. The bytes in the file are the same
/// either way.
pub struct StreamOut {
    tmp: tempfile::NamedTempFile,
    blocks: direct::Blocks,
}

impl StreamOut {
    /// Write `tmp` from its start (it must be empty).
    pub fn new(tmp: tempfile::NamedTempFile) -> StreamOut {
        let blocks = direct::Blocks::new(tmp.as_file(), STREAM_CHUNK);
        StreamOut { tmp, blocks }
    }

    /// Write everything still gathered and hand back the file, positioned
    /// at its end, with direct I/O off (so a header can be patched in).
    pub fn finish(mut self) -> std::io::Result<tempfile::NamedTempFile> {
        self.blocks.buffered(self.tmp.as_file());
        self.blocks.drain(self.tmp.as_file())?;
        use std::io::Seek;
        self.tmp
            .seek(std::io::SeekFrom::Start(self.blocks.written()))?;
        Ok(self.tmp)
    }
}

impl Write for StreamOut {
    fn write(&mut self, data: &[u8]) -> std::io::Result<usize> {
        self.blocks.push(self.tmp.as_file(), data)?;
        Ok(data.len())
    }

    /// Gathered bytes are written by [`StreamOut::finish`] (a partial
    /// block cannot be written directly).
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[cfg(test)]
mod tests;
