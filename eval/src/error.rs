//! The evaluation crate's error type.

use std::path::PathBuf;

/// A file's problem met by the testbed's own files (outputs, rows, sweeps), as the map crate reports it.
impl From<oeg_files::FileError> for EvalError {
    fn from(e: oeg_files::FileError) -> Self {
        Self::Map(e.into())
    }
}

/// What can go wrong while running an evaluation job.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum EvalError {
    /// From the map crate (reading data, building or saving the map). Its message names the file.
    #[error(transparent)]
    Map(#[from] oeg::Error),
    /// From the simulation crate (scenario files, the robot, the world). Its message names the file and place.
    #[error(transparent)]
    Sim(#[from] sim::SimError),
    /// A setting that cannot be used; its message names where it came from (`--set KEY=VALUE: ...`).
    #[error(transparent)]
    Setting(#[from] crate::settings::SettingError),
    /// The MCAP recording could not be written.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// Arguments on the command line that the job cannot use (no input files, an impossible `--jobs`).
    #[error("the command line: {message}")]
    CommandLine {
        /// What is wrong and what was expected.
        message: String,
    },
    /// An input the job cannot use, with a message that names the file and the place itself (`path.csv:3:
    /// ...`), so the file is not named twice.
    #[error("{message}")]
    Placed {
        /// The file and place, then what is wrong and what was expected.
        message: String,
    },
    /// An input the job cannot use.
    #[error("{}: {message}", path.display())]
    Input {
        /// The input.
        path: PathBuf,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A place in a text file (a sweep file) is wrong. Displayed as `file:line:column: message`.
    #[error("{}{}: {message}", path.display(), position.map(|p| format!(":{p}")).unwrap_or_default())]
    At {
        /// The file.
        path: PathBuf,
        /// Where in it, when known.
        position: Option<sim::TextPosition>,
        /// What is wrong and what was expected.
        message: String,
    },
    /// The caller cancelled the job ([`crate::progress::Progress::cancel`]); nothing was written.
    #[error("cancelled")]
    Cancelled,
    /// A file or folder could not be created or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
}

/// Short for `Result<T, EvalError>`.
pub type Result<T, E = EvalError> = std::result::Result<T, E>;

/// What went wrong writing the MCAP recording (`crate::recording`). Defined here, with the crate's other
/// errors, so that the error module depends on no module that reports through it.
#[derive(Debug, thiserror::Error)]
#[error("writing the MCAP recording: {0}")]
pub struct RecordingError(pub(crate) String);

impl From<mcap::McapError> for RecordingError {
    fn from(e: mcap::McapError) -> Self {
        Self(e.to_string())
    }
}
