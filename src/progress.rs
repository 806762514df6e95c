//! Progress reporting hooks.
//!
//! The library never prints: long stages report through this trait, and the
//! binary draws progress bars with it. Implementations must be cheap and
//! thread-safe; `advance` is called from worker threads.

/// Receives progress of long-running stages.
pub trait Progress: Sync {
    /// A new stage begins with `total` units of work (0 when unknown).
    fn stage(&self, name: &str, total: u64);
    /// `n` more units of the current stage are done.
    fn advance(&self, n: u64);
    /// The current stage is complete.
    fn finish(&self);
}

/// Reports nothing.
pub struct Silent;

impl Progress for Silent {
    fn stage(&self, _: &str, _: u64) {}
    fn advance(&self, _: u64) {}
    fn finish(&self) {}
}
