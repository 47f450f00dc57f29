//! The simulation crate's error type.

use std::fmt;
use std::path::PathBuf;

/// A place in a text file: 1-based line and column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TextPosition {
    /// Line, from 1.
    pub line: usize,
    /// Column (characters), from 1.
    pub column: usize,
}

impl TextPosition {
    /// The position of byte `offset` in `text`.
    pub fn of_offset(text: &str, offset: usize) -> Self {
        let offset = offset.min(text.len());
        let before = text.get(..offset).unwrap_or(text);
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |k| k + 1);
        Self {
            line,
            column: before[line_start..].chars().count() + 1,
        }
    }
}

impl fmt::Display for TextPosition {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.line, self.column)
    }
}

/// Everything that can go wrong in the simulation crate.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// A scenario (or a file it refers to) is malformed or makes no sense. Displayed as
    /// `file:line:column: message`, the way compilers report errors, so editors can jump to it.
    #[error("{}{}: {message}", path.display(), position.map(|p| format!(":{p}")).unwrap_or_default())]
    Scenario {
        /// The scenario file.
        path: PathBuf,
        /// Where in it, when known.
        position: Option<TextPosition>,
        /// What is wrong and what was expected.
        message: String,
    },
    /// The robot description cannot be used.
    #[error("{}: {message}", path.display())]
    Urdf {
        /// The URDF file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A recorded sensor log is malformed.
    #[error("{}: {message}", path.display())]
    Log {
        /// The log file.
        path: PathBuf,
        /// Where (byte offset) and what is wrong.
        message: String,
    },
    /// A file could not be read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// From the map crate (grid geometry).
    #[error(transparent)]
    Map(#[from] oeg::Error),
}

/// A file's problem met by the simulator's own files (the sensor log), as the map crate reports it.
impl From<oeg_files::FileError> for SimError {
    fn from(e: oeg_files::FileError) -> Self {
        Self::Map(e.into())
    }
}

/// Short for `Result<T, SimError>`.
pub type Result<T, E = SimError> = std::result::Result<T, E>;

/// Reads a text input (a scenario, a URDF) within `oeg_files::MAX_TEXT_INPUT_BYTES`; an unreadable or oversized
/// file is a [`SimError::Io`] naming it.
pub(crate) fn read_text(path: &std::path::Path) -> Result<String> {
    oeg_files::read_text(path).map_err(|e| match e {
        oeg_files::FileError::Io { path, source } => SimError::Io { path, source },
        other => other.into(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positions_count_lines_and_characters() {
        let text = "a = 1\nbé = 2\n";
        assert_eq!(
            TextPosition::of_offset(text, 0),
            TextPosition { line: 1, column: 1 }
        );
        assert_eq!(
            TextPosition::of_offset(text, 6),
            TextPosition { line: 2, column: 1 }
        );
        // "bé" is three bytes, two characters.
        assert_eq!(
            TextPosition::of_offset(text, 9),
            TextPosition { line: 2, column: 3 }
        );
    }
}
