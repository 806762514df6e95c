//! The map writer's spill thread: it writes the cells the writer hands it
//! to the scratch file while routing goes on (see `writer`).

use super::STAGED;
use crate::error::{Error, Result};
use crate::store::codec::StagedPhoton;
use crate::store::spill::{Frame, Scratch};
use std::path::Path;

/// The state of the spill thread's job.
pub(super) enum Collected {
    /// No job was under way.
    Idle,
    /// Still running.
    Running,
    /// Done, freeing this many bytes of buffers.
    Freed(u64),
    /// The thread stopped (a spill failed).
    Stopped,
}

/// Cells handed to the spill thread: each one's index and its chunks.
pub(super) type SpillJob = Vec<(u32, Vec<Vec<StagedPhoton>>)>;

/// What the spill thread hands back when it stops: the scratch file, each
/// cell's newest frame, and the error of a spill that failed.
type SpillEnd = (Scratch, Vec<Option<Frame>>, Option<Error>);

/// The thread that writes spilled cells to the scratch file while routing
/// goes on. It owns the scratch file and each cell's newest frame (the
/// link the next frame of that cell starts with); one job at a time is
/// under way.
pub(super) struct Spiller {
    jobs: crossbeam_channel::Sender<SpillJob>,
    /// Bytes of buffers each finished job freed.
    done: crossbeam_channel::Receiver<u64>,
    thread: std::thread::JoinHandle<SpillEnd>,
    busy: bool,
}

impl Spiller {
    pub(super) fn start(mut scratch: Scratch, cells: usize) -> Result<Spiller> {
        let (jobs, job_rx) = crossbeam_channel::bounded::<SpillJob>(1);
        let (done_tx, done) = crossbeam_channel::bounded::<u64>(1);
        let thread = std::thread::Builder::new()
            .name("littoral-spill".into())
            .spawn(move || {
                let mut newest: Vec<Option<Frame>> = vec![None; cells];
                for job in job_rx {
                    let mut freed = 0;
                    for (cell, chunks) in job {
                        let cell = cell as usize;
                        match scratch.spill(chunks.iter().flatten(), newest[cell]) {
                            Ok(frame) => newest[cell] = frame,
                            Err(e) => return (scratch, newest, Some(e)),
                        }
                        freed += chunks
                            .iter()
                            .map(|c| (c.capacity() * STAGED) as u64)
                            .sum::<u64>();
                    }
                    if done_tx.send(freed).is_err() {
                        break;
                    }
                }
                (scratch, newest, None)
            })
            .map_err(|e| Error::io(Path::new("spill thread"), "start", e))?;
        Ok(Spiller {
            jobs,
            done,
            thread,
            busy: false,
        })
    }

    /// Hand over the next job (none may be under way); false if the
    /// thread has stopped.
    pub(super) fn send(&mut self, job: SpillJob) -> bool {
        debug_assert!(!self.busy);
        self.busy = self.jobs.send(job).is_ok();
        self.busy
    }

    /// Whether the job under way is done (waiting for it if `wait`).
    pub(super) fn collect(&mut self, wait: bool) -> Collected {
        if !self.busy {
            return Collected::Idle;
        }
        let freed = if wait {
            self.done.recv().ok()
        } else {
            match self.done.try_recv() {
                Ok(freed) => Some(freed),
                Err(crossbeam_channel::TryRecvError::Empty) => return Collected::Running,
                Err(crossbeam_channel::TryRecvError::Disconnected) => None,
            }
        };
        self.busy = false;
        match freed {
            Some(freed) => Collected::Freed(freed),
            None => Collected::Stopped,
        }
    }

    /// Finish the job under way and stop: the scratch file, each cell's
    /// newest frame, and the bytes the last job freed; or the error of a
    /// spill that failed.
    pub(super) fn stop(self, path: &Path) -> Result<(Scratch, Vec<Option<Frame>>, u64)> {
        let freed = if self.busy {
            self.done.recv().unwrap_or(0)
        } else {
            0
        };
        drop(self.jobs);
        let (scratch, newest, error) = self.thread.join().map_err(|_| {
            Error::io(
                path,
                "spill",
                std::io::Error::other("the spill thread panicked"),
            )
        })?;
        match error {
            Some(e) => Err(e),
            None => Ok((scratch, newest, freed)),
        }
    }
}
