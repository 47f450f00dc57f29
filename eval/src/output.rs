//! Writing a job's outputs: every file atomically (temporary file, then rename).

use std::path::Path;

use serde::Serialize;

use crate::error::{EvalError, Result};

/// Creates the output folder (and its parents).
///
/// # Errors
/// [`EvalError::Io`] naming the folder.
pub fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|source| EvalError::Io {
        path: dir.to_path_buf(),
        source,
    })
}

/// Writes `value` as pretty JSON with a final newline.
///
/// # Errors
/// [`EvalError::Map`] wrapping the I/O error, naming the file.
pub fn write_json(path: &Path, value: &impl Serialize) -> Result<()> {
    let mut bytes = serde_json::to_vec_pretty(value).map_err(|e| EvalError::Input {
        path: path.to_path_buf(),
        message: format!("cannot serialise: {e}"),
    })?;
    bytes.push(b'\n');
    Ok(oeg::io::write_atomically(path, &bytes)?)
}

/// Writes bytes (an image, a map).
///
/// # Errors
/// As [`write_json`].
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    Ok(oeg::io::write_atomically(path, bytes)?)
}

/// A coordinate rounded to the micrometre for CSV files: cell centres such as `1180.5 * 0.1` print as
/// `118.05`, not `118.05000000000001`.
pub fn round_m(v_m: f64) -> f64 {
    (v_m * 1e6).round() / 1e6
}
