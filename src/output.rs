//! Writing output files: complete or not at all.

use crate::error::{Error, Result};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Every temporary file this process created, for [`remove_temporaries`].
/// Published ones were renamed away and dropped ones deleted, so the list
/// only grows; removing a path that is gone does nothing.
static TEMPORARIES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// A temporary file in `dir` named `PREFIX` + random + `SUFFIX`, deleted if
/// dropped, and recorded so that [`remove_temporaries`] finds it when a
/// signal ends the process before it is dropped or published.
pub fn temp_in(dir: &Path, prefix: &str, suffix: &str) -> std::io::Result<tempfile::NamedTempFile> {
    let tmp = tempfile::Builder::new()
        .prefix(prefix)
        .suffix(suffix)
        .tempfile_in(dir)?;
    TEMPORARIES
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .push(tmp.path().to_path_buf());
    Ok(tmp)
}

/// Remove the temporary files of [`temp_in`] that still exist: what a
/// SIGINT or SIGTERM handler calls before the process exits without
/// running destructors. Returns how many it removed.
pub fn remove_temporaries() -> usize {
    let list = TEMPORARIES.lock().unwrap_or_else(|e| e.into_inner());
    list.iter()
        .filter(|p| std::fs::remove_file(p).is_ok())
        .count()
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

/// Sync a fully written temporary file from [`temp_beside`], make it
/// readable like a normal output file, and rename it to `path`.
pub fn publish(tmp: tempfile::NamedTempFile, path: &Path) -> Result<()> {
    finalize(&tmp, path)?;
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

/// Bytes a direct write's buffer, offset and length are multiples of.
const DIRECT_ALIGN: usize = 4096;

/// How much [`StreamOut`] gathers before a write (1 MiB).
const STREAM_CHUNK: usize = 1 << 20;

/// A sequential writer of a new temporary file that goes around the page
/// cache where it can (Linux `O_DIRECT`), for large outputs written once
/// and not read back by this process: the photon map. Through the page
/// cache every written page is a freshly allocated page, which on a
/// virtual machine whose free memory is handed back to the host costs
/// microseconds a page (about 100–180 MB/s on the 2-core test machine,
/// against 2 GB/s direct; `benches/README.md`), and a map of tens of
/// gigabytes would also push everything else out of the cache.
///
/// Whole 4 KiB blocks of 1 MiB chunks are written directly; the last
/// partial block goes through the page cache at [`StreamOut::finish`].
/// Where direct I/O is refused (other systems, tmpfs, a filesystem
/// rejecting a write with `EINVAL`) it writes through the page cache
/// instead: the bytes in the file are the same either way.
pub struct StreamOut {
    tmp: tempfile::NamedTempFile,
    mem: Vec<u8>,
    start: usize,
    filled: usize,
    written: u64,
    direct: bool,
}

impl StreamOut {
    /// Write `tmp` from its start (it must be empty).
    pub fn new(tmp: tempfile::NamedTempFile) -> StreamOut {
        let mem = vec![0u8; STREAM_CHUNK + DIRECT_ALIGN];
        let start = mem.as_ptr().align_offset(DIRECT_ALIGN).min(DIRECT_ALIGN);
        let direct = set_direct(tmp.as_file(), true);
        StreamOut {
            tmp,
            mem,
            start,
            filled: 0,
            written: 0,
            direct,
        }
    }

    /// Write what is gathered: whole blocks only while direct, everything
    /// otherwise; the rest moves to the front of the buffer.
    fn drain(&mut self) -> std::io::Result<()> {
        let whole = if self.direct {
            self.filled / DIRECT_ALIGN * DIRECT_ALIGN
        } else {
            self.filled
        };
        if whole == 0 {
            return Ok(());
        }
        let chunk = &self.mem[self.start..self.start + whole];
        match write_all_at(self.tmp.as_file(), chunk, self.written) {
            Err(e) if self.direct && e.kind() == std::io::ErrorKind::InvalidInput => {
                // A filesystem that accepted the flag but not the write:
                // the same bytes through the page cache.
                self.direct = false;
                set_direct(self.tmp.as_file(), false);
                return self.drain();
            }
            r => r?,
        }
        self.written += whole as u64;
        self.mem
            .copy_within(self.start + whole..self.start + self.filled, self.start);
        self.filled -= whole;
        Ok(())
    }

    /// Write everything still gathered and hand back the file, positioned
    /// at its end, with direct I/O off (so a header can be patched in).
    pub fn finish(mut self) -> std::io::Result<tempfile::NamedTempFile> {
        if self.direct {
            self.direct = false;
            set_direct(self.tmp.as_file(), false);
        }
        self.drain()?;
        use std::io::Seek;
        self.tmp.seek(std::io::SeekFrom::Start(self.written))?;
        Ok(self.tmp)
    }
}

impl Write for StreamOut {
    fn write(&mut self, data: &[u8]) -> std::io::Result<usize> {
        let n = data.len().min(STREAM_CHUNK - self.filled);
        let at = self.start + self.filled;
        self.mem[at..at + n].copy_from_slice(&data[..n]);
        self.filled += n;
        if self.filled == STREAM_CHUNK {
            self.drain()?;
        }
        Ok(n)
    }

    /// Gathered bytes are written by [`StreamOut::finish`] (a partial
    /// block cannot be written directly).
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// Turn direct I/O on `file` on or off; whether it is now on.
fn set_direct(file: &std::fs::File, on: bool) -> bool {
    #[cfg(target_os = "linux")]
    {
        use std::os::fd::AsRawFd;
        let fd = file.as_raw_fd();
        // SAFETY: fcntl on a descriptor this process owns, reading and
        // setting status flags only.
        unsafe {
            let flags = libc::fcntl(fd, libc::F_GETFL);
            if flags < 0 {
                return false;
            }
            let want = if on {
                flags | libc::O_DIRECT
            } else {
                flags & !libc::O_DIRECT
            };
            libc::fcntl(fd, libc::F_SETFL, want) == 0 && on
        }
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = (file, on);
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{Read, Seek, SeekFrom};

    /// Pieces of every size, across chunk and block edges, direct or not:
    /// the file holds exactly the bytes written, and a header patched in
    /// after `finish` lands at the start.
    #[test]
    fn stream_out_writes_exactly_what_it_is_given() {
        let dir = tempfile::tempdir().unwrap();
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for total in [
            0usize,
            1,
            4095,
            4096,
            4097,
            STREAM_CHUNK,
            3 * STREAM_CHUNK + 12_345,
        ] {
            let bytes: Vec<u8> = (0..total).map(|_| next() as u8).collect();
            let mut out = StreamOut::new(temp_in(dir.path(), "s", ".partial").unwrap());
            let mut at = 0;
            while at < total {
                let n = ((next() % 70_000) as usize).min(total - at);
                out.write_all(&bytes[at..at + n]).unwrap();
                at += n;
            }
            let mut tmp = out.finish().unwrap();
            assert_eq!(tmp.stream_position().unwrap(), total as u64);
            let header = [0xA5u8; 3];
            if total >= header.len() {
                tmp.seek(SeekFrom::Start(0)).unwrap();
                tmp.write_all(&header).unwrap();
            }
            let mut back = Vec::new();
            std::fs::File::open(tmp.path())
                .unwrap()
                .read_to_end(&mut back)
                .unwrap();
            let mut want = bytes.clone();
            if total >= header.len() {
                want[..3].copy_from_slice(&header);
            }
            assert_eq!(back, want, "{total} bytes");
        }
    }

    /// With direct I/O turned off the bytes are the same.
    #[test]
    fn stream_out_without_direct_io_matches() {
        let dir = tempfile::tempdir().unwrap();
        let bytes: Vec<u8> = (0..2 * STREAM_CHUNK + 777)
            .map(|i| (i * 31 % 251) as u8)
            .collect();
        let mut out = StreamOut::new(temp_in(dir.path(), "s", ".partial").unwrap());
        if out.direct {
            set_direct(out.tmp.as_file(), false);
            out.direct = false;
        }
        out.write_all(&bytes).unwrap();
        let tmp = out.finish().unwrap();
        assert_eq!(std::fs::read(tmp.path()).unwrap(), bytes);
    }
}
