//! The worker pools every parallel stage runs in.

use crate::error::{Error, Result};

/// Most worker threads a run may ask for per core of the machine (and at
/// least [`MIN_THREAD_CAP`] in all): more only costs memory and time, and
/// thousands exhaust the process's threads.
pub const THREADS_PER_CORE_CAP: usize = 8;
pub const MIN_THREAD_CAP: usize = 64;

/// The largest thread count [`check_threads`] accepts on this machine.
pub fn thread_cap() -> usize {
    (workers(0) * THREADS_PER_CORE_CAP).max(MIN_THREAD_CAP)
}

/// What is wrong with `threads` when it is beyond [`thread_cap`], naming
/// the machine's core count; none when it is within.
pub fn too_many_threads(threads: usize) -> Option<String> {
    (threads > thread_cap()).then(|| {
        format!(
            "{threads} threads: at most {} on this machine ({} cores; 0 = one per core)",
            thread_cap(),
            workers(0)
        )
    })
}

/// Refuse a thread count beyond [`thread_cap`] ([`too_many_threads`]).
pub fn check_threads(threads: usize) -> Result<usize> {
    match too_many_threads(threads) {
        Some(what) => Err(Error::invalid("--threads", what)),
        None => Ok(threads),
    }
}

/// A rayon pool of `threads` workers (0 = one per core). Stages install
/// their work in their own pool, so `--threads` holds for every stage and
/// results never depend on the global pool.
pub fn pool(threads: usize) -> Result<rayon::ThreadPool> {
    check_threads(threads)?;
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error::invalid("threads", e.to_string()))
}

/// Per-thread buffers sized by a band count (see [`with_band_scratch`]).
pub trait BandScratch: Sized {
    fn for_bands(bands: usize) -> Self;
    fn bands(&self) -> usize;
}

/// Run `f` with this thread's buffers in `key`, made (again) for `bands`
/// bands when there are none or they are for another band count.
pub fn with_band_scratch<T: BandScratch + 'static, R>(
    key: &'static std::thread::LocalKey<std::cell::RefCell<Option<T>>>,
    bands: usize,
    f: impl FnOnce(&mut T) -> R,
) -> R {
    key.with(|s| {
        let mut s = s.borrow_mut();
        if s.as_ref().is_none_or(|sc| sc.bands() != bands) {
            *s = Some(T::for_bands(bands));
        }
        f(s.as_mut().expect("just set"))
    })
}

/// The number of workers a pool of `threads` (0 = one per core) has.
pub fn workers(threads: usize) -> usize {
    if threads == 0 {
        std::thread::available_parallelism().map_or(1, |n| n.get())
    } else {
        threads
    }
}
