//! The crate's error type.

use std::path::PathBuf;

/// Everything that can go wrong in the map crate.
///
/// Each variant says what was being done and, for files, which file and where. Dependencies' errors are
/// turned into text so they do not leak into this crate's public API.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A map or model setting is out of its valid range.
    #[error("invalid setting `{name}`: {message}")]
    InvalidSetting {
        /// The setting's name as it appears in [`crate::MapConfig`] or [`crate::ModelOptions`].
        name: &'static str,
        /// What was expected.
        message: String,
    },
    /// A scan holds a value the map cannot use (NaN or infinite coordinates, a negative variance, ...).
    #[error("invalid scan: {0}")]
    InvalidScan(String),
    /// Storing the map would exceed the configured memory limit.
    #[error(
        "the map would need at least {requested_bytes} bytes, over its memory limit of {limit_bytes} bytes \
         (is a point or a pose very far away? otherwise use a coarser resolution, or raise the limit: \
         `--memory-limit-mib` of `oeg map`, `MapConfig::memory_limit_bytes` in the library)"
    )]
    MemoryLimit {
        /// Bytes the map would hold after the operation.
        requested_bytes: u64,
        /// The configured limit.
        limit_bytes: u64,
    },
    /// The caller stopped the work ([`crate::Map::integrate_unless`]); the map is as it was before it.
    #[error("cancelled: the map is as it was before this scan")]
    Cancelled,
    /// A file could not be parsed.
    #[error("{}: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// Where in the file and what was expected.
        message: String,
    },
    /// A file could not be opened, read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
}

impl Error {
    pub(crate) fn setting(name: &'static str, message: impl Into<String>) -> Self {
        Self::InvalidSetting {
            name,
            message: message.into(),
        }
    }

    pub(crate) fn parse(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Self::Parse {
            path: path.into(),
            message: message.into(),
        }
    }
}

impl From<oeg_files::FileError> for Error {
    fn from(e: oeg_files::FileError) -> Self {
        match e {
            oeg_files::FileError::Parse { path, message } => Self::Parse { path, message },
            oeg_files::FileError::Io { path, source } => Self::Io { path, source },
        }
    }
}

/// Short for `std::result::Result<T, oeg::Error>`.
pub type Result<T, E = Error> = std::result::Result<T, E>;
