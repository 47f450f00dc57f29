//! The crate's error type.

use std::path::PathBuf;

/// A file that could not be read, parsed or written, named with what went wrong. Its messages are the map
/// crate's (`oeg::Error::Parse` and `Io`), which it converts into.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
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

impl FileError {
    /// A file that does not parse: `message` says where and what was expected.
    pub fn parse(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Self::Parse {
            path: path.into(),
            message: message.into(),
        }
    }

    /// A file the operating system could not open, read or write.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.into(),
            source,
        }
    }
}

/// Short for `std::result::Result<T, FileError>`.
pub type Result<T, E = FileError> = std::result::Result<T, E>;
