//! A run's files published as one set, and what keeps runs from replacing
//! each other's files or the user's.
//!
//! - [`Staging`]: every file of a run is written, under its final name, in
//!   a hidden staging directory inside the output directory
//!   (`.littoral-stage.HOST_PID.RANDOM`); [`Staging::publish`] then renames
//!   them into place with the JSON report last, so a reader that trusts
//!   the report finds the files it lists. A SIGINT, SIGTERM or SIGHUP during
//!   the renames waits for them (`output::remove_temporaries`), so a run
//!   leaves either none of its files under final names or all of them.
//!   Nothing is built by reading back a final name.
//! - [`RunLock`]: an advisory lock (`flock`) on a hidden lock file beside
//!   what a run writes (`.NAME.littoral-lock`, removed by the last holder):
//!   two runs writing the same render or map at once fail fast instead of
//!   mixing their files; renders reading one map share it, and wait while
//!   it is written.
//! - [`check_target`]: an output name that is a link, a device, a FIFO or a
//!   directory is refused rather than replaced by a rename, and an output
//!   that is one of the run's inputs is refused ([`refuse_input`]).
//! - [`sweep_stale`]: temporaries of processes on this host that died
//!   without cleaning up (SIGKILL, power loss) are removed at the next run
//!   in that directory; their names carry the owner ([`super::owner_tag`]).

use crate::error::{Error, Result};
use std::fs::File;
use std::path::{Path, PathBuf};

/// This host's name for temporary file names: letters, digits and '-'
/// (anything else becomes '-'), at most 40 characters; "host" when the
/// name cannot be read.
pub fn host_name() -> String {
    let mut buf = [0u8; 256];
    // SAFETY: the buffer is valid for its whole length, and gethostname
    // writes at most that many bytes.
    let ok = unsafe { libc::gethostname(buf.as_mut_ptr().cast(), buf.len()) } == 0;
    let end = buf.iter().position(|&b| b == 0).unwrap_or(buf.len());
    let name: String = String::from_utf8_lossy(&buf[..end])
        .chars()
        .take(40)
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .collect();
    if ok && !name.is_empty() {
        name
    } else {
        "host".into()
    }
}

/// The owner of a temporary named by [`super::temp_in`] or [`Staging`]:
/// (host, pid), read from its `HOST_PID` component.
fn owner_of(name: &str) -> Option<(&str, u32)> {
    if !name.starts_with('.') {
        return None;
    }
    let name = name.strip_suffix(".partial").unwrap_or(name);
    let mut parts = name.rsplit('.');
    let _random = parts.next()?;
    let tag = parts.next()?;
    let (host, pid) = tag.rsplit_once('_')?;
    Some((host, pid.parse().ok()?))
}

fn alive(pid: u32) -> bool {
    let Ok(pid) = libc::pid_t::try_from(pid) else {
        return true;
    };
    // SAFETY: signal 0 only checks that the process exists.
    let r = unsafe { libc::kill(pid, 0) };
    r == 0 || std::io::Error::last_os_error().raw_os_error() != Some(libc::ESRCH)
}

/// Remove the temporaries in `dir` left by dead processes of this host
/// (partial cubes and maps, scratch maps, staging directories); returns
/// what it removed. Temporaries of live processes and of other hosts are
/// kept; a directory that cannot be listed is skipped.
pub fn sweep_stale(dir: &Path) -> Vec<PathBuf> {
    let host = host_name();
    let me = std::process::id();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut removed = Vec::new();
    for e in entries.flatten() {
        let name = e.file_name();
        let Some(name) = name.to_str() else { continue };
        let Some((h, pid)) = owner_of(name) else {
            continue;
        };
        let ours = name.starts_with(".littoral") || name.ends_with(".partial");
        if !ours || h != host || pid == me || alive(pid) {
            continue;
        }
        let path = e.path();
        let gone = match e.file_type() {
            Ok(t) if t.is_dir() => std::fs::remove_dir_all(&path).is_ok(),
            Ok(_) => std::fs::remove_file(&path).is_ok(),
            Err(_) => false,
        };
        if gone {
            removed.push(path);
        }
    }
    removed.sort();
    removed
}

/// What [`sweep_stale`] removed, as one warning line, or none.
pub fn sweep_warning(removed: &[PathBuf]) -> Option<String> {
    let first = removed.first()?;
    let dir = super::parent_dir(first);
    Some(format!(
        "removed {} temporary file(s) left in {} by runs that were killed: {}",
        removed.len(),
        dir.display(),
        removed
            .iter()
            .filter_map(|p| p.file_name())
            .map(|n| n.to_string_lossy().into_owned())
            .collect::<Vec<_>>()
            .join(", ")
    ))
}

/// Refuse to write `path` when it exists and is not a regular file: a
/// rename would replace a link, a device or a FIFO with a plain file, and
/// a directory cannot be replaced at all.
pub fn check_target(path: &Path) -> Result<()> {
    let Ok(m) = std::fs::symlink_metadata(path) else {
        return Ok(());
    };
    let t = m.file_type();
    let what = if t.is_file() {
        return Ok(());
    } else if t.is_symlink() {
        "a symbolic link (littoral does not write through links: name its target)"
    } else if t.is_dir() {
        "a directory"
    } else {
        "not a regular file (a device, FIFO or socket)"
    };
    Err(Error::io(
        path,
        "write",
        std::io::Error::new(std::io::ErrorKind::AlreadyExists, what),
    ))
}

/// Whether `a` and `b` name the same file: the same device and inode when
/// both exist, else the same absolute path.
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            return x.dev() == y.dev() && x.ino() == y.ino();
        }
    }
    let abs = |p: &Path| {
        let dir = super::parent_dir(p);
        let dir = dir.canonicalize().unwrap_or_else(|_| dir.to_path_buf());
        p.file_name().map(|n| dir.join(n))
    };
    abs(a).is_some() && abs(a) == abs(b)
}

/// Refuse an output `out` (what `role` names, e.g. "--map") that is the
/// input `input` (what `input_role` names): the run would overwrite what
/// it reads.
pub fn refuse_input(out: &Path, role: &str, input: &Path, input_role: &str) -> Result<()> {
    if input.as_os_str().is_empty() || !same_file(out, input) {
        return Ok(());
    }
    Err(Error::invalid(
        role,
        format!(
            "{} is the {input_role} ({}): refusing to overwrite an input",
            out.display(),
            input.display()
        ),
    ))
}

/// An advisory lock (`flock`) held for a run's lifetime on
/// `DIR/.NAME.littoral-lock`. The last holder removes the lock file when
/// it lets go (and a signal handler with the run's temporaries), so a
/// finished run leaves nothing; a lock taken on a file another run has
/// just removed is noticed (the path no longer names the locked file) and
/// taken again.
#[derive(Debug)]
pub struct RunLock {
    file: File,
    path: PathBuf,
    what: PathBuf,
}

impl RunLock {
    fn take(what: &Path, exclusive: bool) -> Result<RunLock> {
        let name = what
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let path = super::parent_dir(what).join(format!(".{name}.littoral-lock"));
        loop {
            let file = std::fs::OpenOptions::new()
                .create(true)
                .truncate(false)
                .write(true)
                .open(&path)
                .map_err(|e| Error::io(&path, "open lock file", e))?;
            let lock = RunLock {
                file,
                path: path.clone(),
                what: what.to_path_buf(),
            };
            if exclusive {
                lock.upgrade()?;
            } else {
                lock.file
                    .lock_shared()
                    .map_err(|e| Error::io(&path, "lock", e))?;
            }
            if lock.still_named() {
                super::record_temporary(&path);
                return Ok(lock);
            }
            // Removed (and perhaps made again) by the holder we waited for:
            // this lock is on a file nobody else will look at (dropping it
            // leaves the path alone, which names another file now).
            drop(lock);
        }
    }

    /// Whether the lock file's path still names the file this lock is on.
    fn still_named(&self) -> bool {
        #[cfg(unix)]
        {
            use std::os::unix::fs::MetadataExt;
            match (self.file.metadata(), std::fs::metadata(&self.path)) {
                (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
                _ => false,
            }
        }
        #[cfg(not(unix))]
        {
            true
        }
    }

    fn busy(&self) -> Error {
        Error::io(
            &self.what,
            "lock",
            std::io::Error::new(
                std::io::ErrorKind::WouldBlock,
                format!(
                    "another littoral run is writing it or reading it (lock {})",
                    self.path.display()
                ),
            ),
        )
    }

    /// The exclusive lock on writing `what` (a map file, or
    /// `DIR/NAME.render` for a render's set), or an error at once when another run holds it.
    pub fn exclusive(what: &Path) -> Result<RunLock> {
        RunLock::take(what, true)
    }

    /// A shared lock on reading `what`: waits while a run writes it.
    pub fn shared(what: &Path) -> Result<RunLock> {
        RunLock::take(what, false)
    }

    /// Make a shared lock exclusive, or fail at once when another run
    /// holds it too.
    pub fn upgrade(&self) -> Result<()> {
        match self.file.try_lock() {
            Ok(()) => Ok(()),
            Err(std::fs::TryLockError::WouldBlock) => Err(self.busy()),
            Err(std::fs::TryLockError::Error(e)) => Err(Error::io(&self.path, "lock", e)),
        }
    }
}

impl Drop for RunLock {
    /// The last holder (the one that can take the lock exclusively)
    /// removes the lock file before letting go.
    fn drop(&mut self) {
        if self.file.try_lock().is_ok() && self.still_named() {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

/// `LITTORAL_PUBLISH_PAUSE_MS`: a pause before each rename of a
/// publication, so that tests can deliver a signal at every moment of it.
/// Unset (the normal case), there is none.
fn publish_pause() -> Option<std::time::Duration> {
    let ms: u64 = std::env::var("LITTORAL_PUBLISH_PAUSE_MS")
        .ok()?
        .parse()
        .ok()?;
    Some(std::time::Duration::from_millis(ms.min(10_000)))
}

/// The staging directory of a run's files inside its output directory.
#[derive(Debug)]
pub struct Staging {
    dir: Option<tempfile::TempDir>,
    out_dir: PathBuf,
}

impl Staging {
    /// A new, empty staging directory in `out_dir` (which must exist).
    pub fn new(out_dir: &Path) -> Result<Staging> {
        let dir = super::make_temporary(
            || {
                tempfile::Builder::new()
                    .prefix(&format!(".littoral-stage.{}.", super::owner_tag()))
                    .tempdir_in(out_dir)
            },
            |d| d.path(),
        )
        .map_err(|e| Error::io(out_dir, "create staging directory", e))?;
        Ok(Staging {
            dir: Some(dir),
            out_dir: out_dir.to_path_buf(),
        })
    }

    /// Where the files are written before they are published.
    pub fn dir(&self) -> &Path {
        self.dir.as_ref().expect("a staging directory").path()
    }

    /// The output directory the set is published into.
    pub fn out_dir(&self) -> &Path {
        &self.out_dir
    }

    /// The name a staged file `name` will have once published.
    pub fn final_path(&self, name: &str) -> PathBuf {
        self.out_dir.join(name)
    }

    /// Where the file that will be published as `final_path` is now.
    pub fn staged(&self, final_path: &Path) -> PathBuf {
        self.dir().join(final_path.file_name().unwrap_or_default())
    }

    /// Rename every staged file into the output directory, those named in
    /// `last` last and in that order (the report that lists the others),
    /// and remove the staging directory. Refuses, before renaming anything,
    /// when a final name is a link or a special file ([`check_target`]).
    pub fn publish(mut self, last: &[&str]) -> Result<Vec<PathBuf>> {
        let dir = self.dir.take().expect("a staging directory");
        let mut names: Vec<std::ffi::OsString> = std::fs::read_dir(dir.path())
            .map_err(|e| Error::io(dir.path(), "list", e))?
            .map(|e| e.map(|e| e.file_name()))
            .collect::<std::io::Result<_>>()
            .map_err(|e| Error::io(dir.path(), "list", e))?;
        names.sort_by_key(|n| {
            let k = last
                .iter()
                .position(|l| n.as_os_str() == std::ffi::OsStr::new(l));
            (k.is_some(), k, n.clone())
        });
        for n in &names {
            check_target(&self.out_dir.join(n))?;
        }
        let _publishing = super::PUBLISHING.lock().unwrap_or_else(|e| e.into_inner());
        let pause = publish_pause();
        let mut published = Vec::with_capacity(names.len());
        for n in &names {
            if let Some(p) = pause {
                std::thread::sleep(p);
            }
            let to = self.out_dir.join(n);
            std::fs::rename(dir.path().join(n), &to)
                .map_err(|e| Error::io(&to, "rename into place", e))?;
            published.push(to);
        }
        if let Ok(d) = File::open(&self.out_dir) {
            // Best effort: the renames reach the disk with the directory.
            let _ = d.sync_all();
        }
        dir.close()
            .map_err(|e| Error::io(&self.out_dir, "remove staging directory", e))?;
        Ok(published)
    }
}
