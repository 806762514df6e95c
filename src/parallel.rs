//! The worker pools every parallel stage runs in.

use crate::error::{Error, Result};

/// A rayon pool of `threads` workers (0 = one per core). Stages install
/// their work in their own pool, so `--threads` holds for every stage and
/// results never depend on the global pool.
pub fn pool(threads: usize) -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error::invalid("threads", e.to_string()))
}

/// The number of workers a pool of `threads` (0 = one per core) has.
pub fn workers(threads: usize) -> usize {
    if threads == 0 {
        std::thread::available_parallelism().map_or(1, |n| n.get())
    } else {
        threads
    }
}
