//! The process's own memory use, for reports and budget checks.
//!
//! `--mem-budget` bounds anonymous memory: the heap (buffers, the tile
//! cache, the boundary grid) and thread stacks. Pages of the memory-mapped
//! photon map are file pages: the kernel drops them under pressure and
//! reads them again, so they are reported apart ([`MemoryPeaks`]) and are
//! not charged to the budget. VmHWM, the kernel's peak resident set, adds
//! the two (and the binary's own pages), so on its own it overstates what
//! the budget governs by the size of the map's resident pages.

/// Peak resident set size of this process (VmHWM, bytes): anonymous memory
/// plus resident file pages (binary text, libraries, mapped files). `None`
/// where /proc is unavailable.
pub fn peak_rss_bytes() -> Option<u64> {
    status_kib("VmHWM:").map(|k| k * 1024)
}

/// Resident anonymous memory of this process now (RssAnon, bytes).
pub fn rss_anon_bytes() -> Option<u64> {
    status_kib("RssAnon:").map(|k| k * 1024)
}

/// Hand memory freed by a finished stage back to the system. glibc keeps
/// freed memory in the arena of the thread that freed it, so a later stage
/// allocating from other threads' arenas would otherwise stack its memory
/// on top of the earlier stage's (measured: emission then render with a
/// boundary grid peaked at 261 MiB instead of 166 MiB). A no-op elsewhere.
pub fn release_free_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only walks the allocator's own free lists.
    unsafe {
        libc::malloc_trim(0);
    }
}

/// Allocations at least this large get their own mapping (see
/// [`tune_allocator`]).
pub const MMAP_THRESHOLD: usize = 256 << 10;

/// Set glibc's allocator for a stage that must stay inside its budget. A
/// no-op elsewhere.
///
/// - The mmap threshold is fixed at [`MMAP_THRESHOLD`]. By default glibc
///   raises it (up to 32 MiB) each time a mapped block is freed, after
///   which tile-sized buffers (decoded photons and their search trees,
///   1-2 MiB each) come from the heap arenas, where a cache that keeps
///   evicting and decoding tiles fragments them: rendering a 47 M-photon
///   map under a 256 MiB budget peaked at 333 MiB of anonymous memory with
///   245 MiB of cache. With a fixed threshold every such buffer is its own
///   mapping and goes back to the system when freed.
/// - One arena for all threads. With an arena per thread, each worker's
///   arena kept its own high-water mark of small buffers (neighbour lists,
///   query scratch): rendering 1.2 × 10^9 photons at 64 x 64 pixels under
///   256 MiB peaked at 324.1 MiB with two workers, against 267.1 MiB with
///   one arena (and 203 s instead of 309 s: fewer page faults). Small
///   allocations are rare enough in every stage that the shared lock does
///   not show.
pub fn tune_allocator() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets allocator parameters; safe to call at any
    // time. Arenas made before the call stay, and threads started later
    // may share them, so the programs call it first thing in `main`.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD as libc::c_int);
        libc::mallopt(libc::M_ARENA_MAX, 1);
    }
}

fn status_kib(key: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    status_field(&status, key)
}

fn status_field(status: &str, key: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with(key))?;
    line[key.len()..]
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()
}

/// Peak memory of a stage, as users read it against `--mem-budget`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct MemoryPeaks {
    /// Most anonymous resident memory seen (RssAnon, bytes): what
    /// `--mem-budget` bounds.
    pub anon_bytes: u64,
    /// Most resident file pages seen (RssFile, bytes): the mapped photon
    /// map, the binary and its libraries; not charged to the budget.
    pub file_bytes: u64,
    /// The kernel's peak resident set (VmHWM, bytes): both together.
    pub rss_bytes: u64,
}

impl MemoryPeaks {
    /// The larger of each peak, this one's or `other`'s (processes that
    /// ran apart: the peak any one of them reached).
    pub fn max_with(&mut self, other: &MemoryPeaks) {
        self.anon_bytes = self.anon_bytes.max(other.anon_bytes);
        self.file_bytes = self.file_bytes.max(other.file_bytes);
        self.rss_bytes = self.rss_bytes.max(other.rss_bytes);
    }
}

/// Samples this process's RssAnon and RssFile every [`SAMPLE_PERIOD`] on a
/// thread of its own until [`PeakSampler::finish`], keeping the largest
/// values. A sample costs a read of `/proc/self/status` (tens of
/// microseconds), well under 1 % of a core at this period; a spike that
/// comes and goes between two samples is missed, so the anonymous peak is
/// a lower bound, and VmHWM (exact, but with file pages) the upper bound.
pub struct PeakSampler {
    stop: std::sync::mpsc::Sender<()>,
    thread: std::thread::JoinHandle<MemoryPeaks>,
}

/// How often [`PeakSampler`] reads the process status.
pub const SAMPLE_PERIOD: std::time::Duration = std::time::Duration::from_millis(5);

impl PeakSampler {
    /// Start sampling (where /proc is unavailable the peaks stay 0).
    pub fn start() -> PeakSampler {
        let (stop, stopped) = std::sync::mpsc::channel::<()>();
        let thread = std::thread::spawn(move || {
            let mut peaks = MemoryPeaks::default();
            loop {
                if let Ok(status) = std::fs::read_to_string("/proc/self/status") {
                    let kib = |k| status_field(&status, k).unwrap_or(0) * 1024;
                    peaks.anon_bytes = peaks.anon_bytes.max(kib("RssAnon:"));
                    peaks.file_bytes = peaks.file_bytes.max(kib("RssFile:"));
                }
                match stopped.recv_timeout(SAMPLE_PERIOD) {
                    Err(std::sync::mpsc::RecvTimeoutError::Timeout) => continue,
                    _ => break,
                }
            }
            peaks
        });
        PeakSampler { stop, thread }
    }

    /// Stop sampling; the peaks seen, with VmHWM.
    pub fn finish(self) -> MemoryPeaks {
        let _ = self.stop.send(());
        let mut peaks = self.thread.join().unwrap_or_default();
        peaks.rss_bytes = peak_rss_bytes().unwrap_or(0);
        peaks
    }
}

#[cfg(test)]
mod tests;
