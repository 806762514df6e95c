//! Writing around the page cache: whole aligned blocks with Linux
//! `O_DIRECT`, for large files written once in order (the photon map, the
//! writer's scratch file).
//!
//! Through the page cache every written page is a freshly allocated page,
//! which on a virtual machine whose free memory is handed back to the host
//! costs microseconds a page (about 100–180 MB/s on the 2-core test
//! machine, against 2 GB/s direct; `benches/README.md`), and tens of
//! gigabytes written would also push everything else out of the cache.
//! Where direct I/O is refused (other systems, tmpfs, a filesystem
//! rejecting a write with `EINVAL`) the same bytes go through the page
//! cache instead.

use std::fs::File;
use std::io;

/// Bytes a direct transfer's buffer, offset and length are multiples of.
pub const DIRECT_ALIGN: usize = 4096;

/// An aligned buffer gathering a file's next bytes, written out in whole
/// blocks while direct I/O is on (everything, otherwise). It holds the
/// bytes from file offset `written` on.
pub struct Blocks {
    mem: Vec<u8>,
    start: usize,
    capacity: usize,
    filled: usize,
    written: u64,
    direct: bool,
}

impl Blocks {
    /// Gather up to `capacity` bytes (a multiple of [`DIRECT_ALIGN`])
    /// before writing, for `file` from its start; turns direct I/O on for
    /// `file` where it can.
    pub fn new(file: &File, capacity: usize) -> Blocks {
        debug_assert!(capacity > 0 && capacity.is_multiple_of(DIRECT_ALIGN));
        let mem = vec![0u8; capacity + DIRECT_ALIGN];
        let start = mem.as_ptr().align_offset(DIRECT_ALIGN).min(DIRECT_ALIGN);
        Blocks {
            mem,
            start,
            capacity,
            filled: 0,
            written: 0,
            direct: set_direct(file, true),
        }
    }

    /// Bytes written to the file so far.
    pub fn written(&self) -> u64 {
        self.written
    }

    /// Bytes gathered, not yet written (they follow [`Blocks::written`]).
    pub fn gathered(&self) -> &[u8] {
        &self.mem[self.start..self.start + self.filled]
    }

    /// Append `data`, writing to `file` whenever the buffer fills.
    pub fn push(&mut self, file: &File, mut data: &[u8]) -> io::Result<()> {
        while !data.is_empty() {
            let n = data.len().min(self.capacity - self.filled);
            let at = self.start + self.filled;
            self.mem[at..at + n].copy_from_slice(&data[..n]);
            self.filled += n;
            data = &data[n..];
            if self.filled == self.capacity {
                self.drain(file)?;
            }
        }
        Ok(())
    }

    /// Write what is gathered: whole blocks only while direct, everything
    /// otherwise; the rest moves to the front of the buffer.
    pub fn drain(&mut self, file: &File) -> io::Result<()> {
        let whole = if self.direct {
            self.filled / DIRECT_ALIGN * DIRECT_ALIGN
        } else {
            self.filled
        };
        if whole == 0 {
            return Ok(());
        }
        let chunk = &self.mem[self.start..self.start + whole];
        match super::write_all_at(file, chunk, self.written) {
            Err(e) if self.direct && e.kind() == io::ErrorKind::InvalidInput => {
                // A filesystem that accepted the flag but not the write:
                // the same bytes through the page cache.
                self.buffered(file);
                return self.drain(file);
            }
            r => r?,
        }
        self.written += whole as u64;
        self.mem
            .copy_within(self.start + whole..self.start + self.filled, self.start);
        self.filled -= whole;
        Ok(())
    }

    /// Write everything gathered, zero-padded to a whole block while
    /// direct, so that all of it can be read back from the file.
    pub fn pad_and_drain(&mut self, file: &File) -> io::Result<()> {
        if self.direct {
            let end = self.filled.next_multiple_of(DIRECT_ALIGN);
            self.mem[self.start + self.filled..self.start + end].fill(0);
            self.filled = end;
        }
        self.drain(file)
    }

    /// Go on through the page cache.
    pub fn buffered(&mut self, file: &File) {
        if self.direct {
            self.direct = false;
            set_direct(file, false);
        }
    }
}

/// `len` bytes of `file` from `offset`, read through the reusable buffer
/// `buf` in whole aligned blocks, as a direct read needs (a plain read
/// works the same way). Fails with `UnexpectedEof` if the file ends first.
pub fn read_blocks<'b>(
    file: &File,
    offset: u64,
    len: usize,
    buf: &'b mut Vec<u8>,
) -> io::Result<&'b [u8]> {
    let first = offset / DIRECT_ALIGN as u64 * DIRECT_ALIGN as u64;
    let skip = (offset - first) as usize;
    let span = (skip + len).next_multiple_of(DIRECT_ALIGN);
    if buf.len() < span + DIRECT_ALIGN {
        // Exactly what is asked for: callers charge their buffers at a
        // bound, and doubling would pass it.
        buf.reserve_exact(span + DIRECT_ALIGN - buf.len());
        buf.resize(span + DIRECT_ALIGN, 0);
    }
    let at = buf.as_ptr().align_offset(DIRECT_ALIGN).min(DIRECT_ALIGN);
    let mut got = 0;
    while got < skip + len {
        match read_at(file, &mut buf[at + got..at + span], first + got as u64) {
            Ok(0) => return Err(io::ErrorKind::UnexpectedEof.into()),
            Ok(n) => got += n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(&buf[at + skip..at + skip + len])
}

fn read_at(file: &File, buf: &mut [u8], offset: u64) -> io::Result<usize> {
    #[cfg(unix)]
    {
        std::os::unix::fs::FileExt::read_at(file, buf, offset)
    }
    #[cfg(windows)]
    {
        std::os::windows::fs::FileExt::seek_read(file, buf, offset)
    }
}

/// Turn direct I/O on `file` on or off; whether it is now on. The flag
/// belongs to the open file, so handles made by `try_clone` share it.
pub fn set_direct(file: &File, on: bool) -> bool {
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
mod tests;
