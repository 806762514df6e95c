//! Progress reporting hooks.
//!
//! The library never prints: long stages report through this trait, and the
//! binary draws progress bars with it. Implementations must be cheap and
//! thread-safe; `advance` is called from worker threads.
//!
//! A caller may also stop a run (`cancelled`): the long loops (tracing,
//! tile encoding, rendering) ask between units of work and return
//! [`crate::Error::Cancelled`], leaving nothing under a final name.

/// Receives progress of long-running stages.
pub trait Progress: Sync {
    /// A new stage begins with `total` units of work (0 when unknown).
    fn stage(&self, name: &str, total: u64);
    /// `n` more units of the current stage are done.
    fn advance(&self, n: u64);
    /// The current stage is complete.
    fn finish(&self);
    /// True once the caller wants the run stopped (e.g. Ctrl-C in Python);
    /// asked between units of work, from worker threads.
    fn cancelled(&self) -> bool {
        false
    }
}

/// [`crate::Error::Cancelled`] when `progress` asks the run to stop.
pub fn check(progress: &dyn Progress) -> crate::Result<()> {
    if progress.cancelled() {
        Err(crate::Error::Cancelled)
    } else {
        Ok(())
    }
}

/// Reports nothing.
pub struct Silent;

impl Progress for Silent {
    fn stage(&self, _: &str, _: u64) {}
    fn advance(&self, _: u64) {}
    fn finish(&self) {}
}
