//! Writing a job's outputs: every file atomically (temporary file, then rename), and every job's folder all
//! or nothing ([`Staged`]).

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::error::{EvalError, Result};

/// The name of the file that marks a folder as a job's output, which the next job writing there may replace.
pub const OUTPUT_MARKER: &str = ".oeg-output";

/// A job's output folder, written all or nothing.
///
/// The job writes into a staging folder beside its output, `.<name>.staging.<pid>.<n>`; [`Staged::commit`]
/// moves it into place with two renames (the previous output aside, the new one in), then deletes the
/// previous output. So a reader of the output folder sees the complete previous results or the complete new
/// ones, and a job killed at any point leaves the previous results intact and consistent, or (killed between
/// the two renames) no output folder at all. A job that fails or is dropped removes its staging folder; the
/// staging and set-aside folders of killed jobs (whose process no longer runs) are removed by the next job
/// that writes beside them.
///
/// Only folders that a job wrote (they hold [`OUTPUT_MARKER`]) or empty folders are replaced: a folder of
/// someone else's files is an error, before any work is done.
#[derive(Debug)]
pub struct Staged {
    target: PathBuf,
    staging: PathBuf,
}

impl Staged {
    /// Starts a job that writes the folder `target`: checks that `target` may be replaced, removes stale
    /// staging of killed jobs beside it and creates this job's staging folder (and `target`'s parents).
    ///
    /// # Errors
    /// [`EvalError::Io`] naming `target` when it is a file or a folder that no job wrote, or when a folder
    /// cannot be created.
    pub fn begin(target: &Path) -> Result<Self> {
        check_replaceable(target)?;
        let name = target
            .file_name()
            .and_then(|n| n.to_str())
            .filter(|n| !n.is_empty() && *n != "..")
            .ok_or_else(|| io_error(target, "is not a folder name this job can write"))?;
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        create_dir(&parent)?;
        for kind in ["staging", "old"] {
            for stale in oeg::io::stale_owners(&parent, &format!(".{name}.{kind}."), "") {
                let _ = std::fs::remove_dir_all(parent.join(stale));
            }
        }
        let staging = parent.join(format!(".{name}.staging.{}", unique_suffix()));
        create_dir(&staging)?;
        let marker = format!(
            "written by oeg {}; the next job writing this folder replaces it as a whole\n",
            env!("CARGO_PKG_VERSION")
        );
        write_bytes(&staging.join(OUTPUT_MARKER), marker.as_bytes())?;
        Ok(Self {
            target: target.to_path_buf(),
            staging,
        })
    }

    /// The folder the job writes into until [`Staged::commit`].
    pub fn dir(&self) -> &Path {
        &self.staging
    }

    /// The output folder the job's files end up in.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Where a file written at `staged` (inside [`Staged::dir`]) lies once committed.
    pub fn final_path(&self, staged: &Path) -> PathBuf {
        staged
            .strip_prefix(&self.staging)
            .map_or_else(|_| staged.to_path_buf(), |rel| self.target.join(rel))
    }

    /// Puts the staging folder in place of the output folder: the previous output aside, the new one in, the
    /// previous one deleted.
    ///
    /// # Errors
    /// [`EvalError::Io`] naming the folder when the output folder changed into something that may not be
    /// replaced while the job ran, or a rename fails (the staging folder is then removed).
    #[expect(
        clippy::disallowed_methods,
        reason = "this is the one place a finished folder is moved into place"
    )]
    pub fn commit(self) -> Result<PathBuf> {
        check_replaceable(&self.target)?;
        let aside = self.target.exists().then(|| {
            let name = self.target.file_name().unwrap_or_default().to_string_lossy();
            self.target
                .with_file_name(format!(".{name}.old.{}", unique_suffix()))
        });
        if let Some(aside) = &aside {
            std::fs::rename(&self.target, aside).map_err(|source| EvalError::Io {
                path: self.target.clone(),
                source,
            })?;
        }
        std::fs::rename(&self.staging, &self.target).map_err(|source| EvalError::Io {
            path: self.target.clone(),
            source,
        })?;
        if let Some(aside) = &aside {
            let _ = std::fs::remove_dir_all(aside);
        }
        Ok(self.target.clone())
    }
}

impl Drop for Staged {
    /// A job that did not commit leaves nothing behind (after a commit the staging folder is gone already).
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.staging);
    }
}

/// `<pid>.<n>`, `n` counting up within the process: unique among the jobs of every running process.
fn unique_suffix() -> String {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    format!("{}.{n}", std::process::id())
}

fn io_error(path: &Path, message: &str) -> EvalError {
    EvalError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidInput, message.to_string()),
    }
}

/// Whether a job may replace `target`: absent, an empty folder, or a folder a job wrote.
fn check_replaceable(target: &Path) -> Result<()> {
    let Ok(meta) = std::fs::symlink_metadata(target) else {
        return Ok(());
    };
    if meta.file_type().is_symlink() {
        return Err(io_error(
            target,
            "is a symbolic link; give the output folder's own path (outputs never replace a link)",
        ));
    }
    if !meta.is_dir() {
        return Err(io_error(
            target,
            "is a file, not a folder; the output must be a folder (give a new or empty one)",
        ));
    }
    if target.join(OUTPUT_MARKER).is_file() {
        return Ok(());
    }
    let empty = std::fs::read_dir(target)
        .map_err(|source| EvalError::Io {
            path: target.to_path_buf(),
            source,
        })?
        .next()
        .is_none();
    if empty {
        Ok(())
    } else {
        Err(io_error(
            target,
            "holds files that no oeg job wrote (no .oeg-output in it); the job replaces its output folder as a \
             whole, so give a new or empty folder",
        ))
    }
}

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
