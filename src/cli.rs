//! What the command-line programs (`littoral`, `littoral-cube`) share:
//! progress bars on stderr, writing to stdout without panicking when the
//! reader has gone, and the one place an error becomes a message and an
//! exit status.
//!
//! Not for: any pipeline decision (see `job`).

use crate::progress::Progress;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::Write;
use std::process::ExitCode;
use std::sync::Mutex;

/// The result type of a command: any error, reported by [`exit`].
pub type AnyResult<T> = Result<T, Box<dyn std::error::Error>>;

/// On SIGINT, SIGTERM or SIGHUP, remove the run's temporary files
/// (`output::remove_temporaries`: partial maps, cubes and scratch maps) and
/// exit with status 130, so that an interrupted run leaves nothing behind
/// but what it had finished; a publication in progress is waited for
/// (`output::set::Staging::publish`). (SIGKILL cannot be caught: its
/// temporaries stay until the next run in that directory sweeps them,
/// `output::set::sweep_stale`.)
pub fn remove_temporaries_on_signals(program: &'static str) {
    let installed = ctrlc::set_handler(move || {
        let removed = crate::output::remove_temporaries();
        eprintln!("{program}: interrupted; {removed} temporary files removed");
        if let Some(pause) = exit_pause() {
            std::thread::sleep(pause);
        }
        std::process::exit(130);
    });
    if let Err(e) = installed {
        eprintln!("{program}: warning: no signal handler ({e}): an interrupted run may leave temporary files");
    }
}

/// `LITTORAL_EXIT_PAUSE_MS`: a pause between removing the temporaries and
/// exiting on a signal, so that tests can give the threads still running
/// time to make or publish a file (which they must not). Unset (the normal
/// case), there is none.
fn exit_pause() -> Option<std::time::Duration> {
    let ms: u64 = std::env::var("LITTORAL_EXIT_PAUSE_MS").ok()?.parse().ok()?;
    Some(std::time::Duration::from_millis(ms.min(10_000)))
}

/// The exit status of `program` after `result`: success, or one line
/// `PROGRAM: error: ...` on stderr and status 1. (Usage errors exit with 2
/// from the argument parser before a command runs.)
pub fn exit(program: &str, result: AnyResult<()>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{program}: error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// `--threads`: a count up to the machine's cap
/// (`parallel::check_threads`), as a command-line value parser.
pub fn threads_arg(text: &str) -> Result<usize, String> {
    let n: usize = text
        .parse()
        .map_err(|e| format!("{text}: not a thread count ({e})"))?;
    match crate::parallel::too_many_threads(n) {
        Some(what) => Err(what),
        None => Ok(n),
    }
}

/// Write `text` to stdout; a closed pipe (`| head`) ends quietly, other
/// failures are errors rather than the panic `print!` gives.
pub fn print(text: &str) -> AnyResult<()> {
    print_with(|out| out.write_all(text.as_bytes()))
}

/// Stream to stdout through a buffer: a closed pipe ends quietly; an error
/// the writer carries (a bad tile while dumping a map) is returned as it
/// is; other write failures are errors on stdout.
pub fn print_with(write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>) -> AnyResult<()> {
    let mut out = std::io::BufWriter::with_capacity(1 << 16, std::io::stdout().lock());
    match write(&mut out).and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        Err(e) if e.get_ref().is_some_and(|inner| inner.is::<crate::Error>()) => {
            Err(e.into_inner().expect("checked above"))
        }
        Err(e) => Err(crate::Error::io("stdout", "write", e).into()),
    }
}

/// A point `X,Y,Z` (m) given for the flag `field`.
pub fn parse_point(field: &str, text: &str) -> crate::Result<glam::Vec3> {
    let bad = || crate::Error::invalid(field, format!("'{text}' is not X,Y,Z"));
    let v: Vec<f32> = text
        .split(',')
        .map(|s| s.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(glam::Vec3::new(x, y, z)),
        _ => Err(bad()),
    }
}

/// Pretty JSON of `value` on stdout, with a final newline.
pub fn print_json<T: serde::Serialize>(value: &T) -> AnyResult<()> {
    print(&(serde_json::to_string_pretty(value)? + "\n"))
}

/// Progress bars on stderr, one per stage; nothing when quiet.
pub struct Bars {
    quiet: bool,
    bar: Mutex<Option<ProgressBar>>,
}

impl Bars {
    pub fn new(quiet: bool) -> Self {
        Bars {
            quiet,
            bar: Mutex::new(None),
        }
    }

    fn current(&self) -> Option<ProgressBar> {
        self.bar.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }
}

impl Progress for Bars {
    fn stage(&self, name: &str, total: u64) {
        if self.quiet {
            return;
        }
        let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
        bar.set_style(
            ProgressStyle::with_template(
                "{msg:>14} [{bar:32}] {human_pos}/{human_len} {rate} eta {eta}",
            )
            .expect("valid template")
            // Whole units per second with thousands marks ("456,107/s"),
            // where indicatif's `per_sec` prints four decimals.
            .with_key(
                "rate",
                |s: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
                    let _ = write!(w, "{}/s", indicatif::HumanCount(s.per_sec() as u64));
                },
            )
            .progress_chars("=> "),
        );
        bar.set_message(name.to_string());
        *self.bar.lock().unwrap_or_else(|e| e.into_inner()) = Some(bar);
    }

    fn advance(&self, n: u64) {
        if let Some(b) = self.current() {
            b.inc(n);
        }
    }

    fn finish(&self) {
        if let Some(b) = self.bar.lock().unwrap_or_else(|e| e.into_inner()).take() {
            b.finish_and_clear();
        }
    }
}
