//! Typed errors for every stage.
//!
//! Each variant names the file at fault and, where there is one, the tile or
//! field. The library never prints or exits on bad input: it returns one of
//! these, and only `main` turns it into a message and an exit code.

use std::path::{Path, PathBuf};

/// Result alias used across littoral.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong reading, writing or querying a photon map.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// An operating-system I/O failure on a named file.
    #[error("{path}: {action}: {source}")]
    Io {
        path: PathBuf,
        action: &'static str,
        #[source]
        source: std::io::Error,
    },
    /// The map file is structurally wrong (bad magic, short, inconsistent index, ...).
    #[error("{path}: not a valid littoral map: {what}")]
    Format { path: PathBuf, what: String },
    /// The map was written by a newer littoral.
    #[error("{path}: map format version {found} is newer than the newest this build reads ({supported})")]
    Version {
        path: PathBuf,
        found: u32,
        supported: u32,
    },
    /// A tile blob failed its checksum or could not be decoded.
    #[error("{path}: tile {tile}: {what}")]
    Tile {
        path: PathBuf,
        tile: u32,
        what: String,
    },
    /// An argument or configuration value is out of range.
    #[error("{field}: {what}")]
    Invalid { field: String, what: String },
    /// A scene file is malformed or holds an impossible value.
    #[error("{path}:{line}: {key}: {what}")]
    Scene {
        path: PathBuf,
        line: usize,
        key: String,
        what: String,
    },
    /// A tabulated data file (a spectrum CSV) is malformed; `line` is 1-based,
    /// absent when the fault is the file as a whole (e.g. too few rows).
    #[error("{path}: {}{field}: {what}", line_prefix(.line))]
    Data {
        path: PathBuf,
        line: Option<usize>,
        field: String,
        what: String,
    },
    /// The memory budget cannot hold what the operation needs.
    #[error("memory budget of {budget} bytes is too small: {what}")]
    Budget { budget: u64, what: String },
    /// The caller stopped the run (`Progress::cancelled`).
    #[error("cancelled")]
    Cancelled,
}

impl Error {
    /// An I/O error on `path` while doing `action` (e.g. "write", "open").
    pub fn io(path: impl AsRef<Path>, action: &'static str, source: std::io::Error) -> Self {
        Error::Io {
            path: path.as_ref().to_path_buf(),
            action,
            source,
        }
    }

    /// A structural problem with the map file at `path`.
    pub fn format(path: impl AsRef<Path>, what: impl Into<String>) -> Self {
        Error::Format {
            path: path.as_ref().to_path_buf(),
            what: what.into(),
        }
    }

    /// A problem with tile `tile` of the map file at `path`.
    pub fn tile(path: impl AsRef<Path>, tile: u32, what: impl Into<String>) -> Self {
        Error::Tile {
            path: path.as_ref().to_path_buf(),
            tile,
            what: what.into(),
        }
    }

    /// A malformed data file at `path`, read for `field`, at `line` (1-based) if known.
    pub fn data(
        path: impl AsRef<Path>,
        line: Option<usize>,
        field: impl Into<String>,
        what: impl Into<String>,
    ) -> Self {
        Error::Data {
            path: path.as_ref().to_path_buf(),
            line,
            field: field.into(),
            what: what.into(),
        }
    }

    /// An invalid value for `field`.
    pub fn invalid(field: impl Into<String>, what: impl Into<String>) -> Self {
        Error::Invalid {
            field: field.into(),
            what: what.into(),
        }
    }
}

fn line_prefix(line: &Option<usize>) -> String {
    line.map(|n| format!("line {n}: ")).unwrap_or_default()
}
