//! A sweep's output folder: whose it is, one invocation at a time, and writes that never leave it.
//!
//! A sweep folder is not replaced whole like a job's (`output::Staged`): it is resumed, run by run.
//! So it has its own marker, [`SWEEP_MARKER`], and its own rule, checked before any work:
//! * `oeg sweep run --out DIR` creates `DIR`, adopts an empty folder, or resumes a folder that holds the marker
//!   (or, written by an earlier version, only entries a sweep writes, `plan.json` among them). Any other folder
//!   (someone's files, an `oeg run` folder), the file system's root, the current folder and a symbolic link are
//!   refused, naming the folder and what was expected.
//! * `oeg sweep report DIR` writes only into such a folder (a merged one too: `oeg sweep merge` marks it).
//! * One invocation works in a folder at a time: its `.lock` (`lock`).
//! * Every write inside the folder refuses a symbolic link on its way ([`SweepFolder::check`]): a link planted
//!   as `runs.csv`, `plots/` or `runs/<id>` never makes the owner's next run or report write outside the folder.

use std::path::{Path, PathBuf};

use crate::error::{EvalError, Result};
use crate::lock::LockFile;

/// The name of the file that marks a folder as a sweep's.
pub(crate) const SWEEP_MARKER: &str = ".oeg-sweep";

/// Every entry a sweep folder of an earlier version (before [`SWEEP_MARKER`]) may hold: what `oeg sweep run`,
/// `merge` and `report` write.
const SWEEP_ENTRIES: [&str; 9] = [
    "plan.json",
    "runs",
    "runs.csv",
    "runs.jsonl",
    "obstacles.csv",
    "summary.csv",
    "plots",
    ".lock",
    crate::output::OUTPUT_MARKER,
];

/// A sweep folder held by this invocation.
#[derive(Debug)]
pub struct SweepFolder {
    root: PathBuf,
    _lock: Option<LockFile>,
}

impl SweepFolder {
    /// Claims `dir` for `oeg sweep run`: creates it, or adopts an empty folder, or resumes a sweep folder; marks
    /// it and takes its lock.
    ///
    /// # Errors
    /// [`EvalError::Input`] naming the folder: not a sweep's (see the module), the root or the current folder,
    /// a link, a file; another invocation working in it.
    pub fn claim(dir: &Path) -> Result<Self> {
        refuse_special(dir)?;
        match std::fs::symlink_metadata(dir) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => crate::output::create_dir(dir)?,
            Err(source) => {
                return Err(EvalError::Io {
                    path: dir.to_path_buf(),
                    source,
                });
            }
            Ok(_) => check_owned(dir, true)?,
        }
        let folder = Self::locked(dir)?;
        if !dir.join(SWEEP_MARKER).is_file() {
            folder.write_bytes(&dir.join(SWEEP_MARKER), marker_text().as_bytes())?;
        }
        Ok(folder)
    }

    /// Opens an existing sweep folder for `oeg sweep report` and takes its lock.
    ///
    /// # Errors
    /// As [`SweepFolder::claim`], and a folder that does not exist or is empty.
    pub fn open(dir: &Path) -> Result<Self> {
        // The current folder is fine here when it is a sweep's (`oeg sweep report .` from inside the study).
        if !(dir.join(SWEEP_MARKER).is_file() && is_current_folder(dir)) {
            refuse_special(dir)?;
        }
        if !dir.is_dir() {
            return Err(input(
                dir,
                "is not a folder; expected the output folder of `oeg sweep run` or `oeg sweep merge`",
            ));
        }
        check_owned(dir, false)?;
        Self::locked(dir)
    }

    /// A folder this process just created as a whole (the staging of `oeg sweep merge`): marked, no lock.
    ///
    /// # Errors
    /// A failed write.
    pub fn fresh(dir: &Path) -> Result<Self> {
        let folder = Self {
            root: dir.to_path_buf(),
            _lock: None,
        };
        folder.write_bytes(&dir.join(SWEEP_MARKER), marker_text().as_bytes())?;
        Ok(folder)
    }

    fn locked(dir: &Path) -> Result<Self> {
        let folder = Self {
            root: dir.to_path_buf(),
            _lock: None,
        };
        let path = dir.join(".lock");
        folder.check(&path)?;
        match LockFile::try_take(&path)? {
            Ok(lock) => Ok(Self {
                _lock: Some(lock),
                ..folder
            }),
            Err(busy) => Err(input(
                dir,
                &format!(
                    "another `oeg sweep` works in this folder: {}. Give each shard its own --out (and merge \
                     them with `oeg sweep merge`)",
                    busy.describe(&path)
                ),
            )),
        }
    }

    /// The folder.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// Checks that `path`, inside the folder, has no symbolic link on its way from the folder (itself
    /// included): a write there stays inside the folder.
    ///
    /// # Errors
    /// [`EvalError::Input`] naming the link, or a path outside the folder.
    pub fn check(&self, path: &Path) -> Result<()> {
        let rel = path.strip_prefix(&self.root).map_err(|_| {
            input(
                path,
                &format!("lies outside the sweep folder {}", self.root.display()),
            )
        })?;
        let mut here = self.root.clone();
        for part in rel.components() {
            here.push(part);
            if std::fs::symlink_metadata(&here).is_ok_and(|m| m.file_type().is_symlink()) {
                return Err(input(
                    &here,
                    &format!(
                        "is a symbolic link inside the sweep folder {}; a sweep never writes through a link \
                         (it could lead out of the folder): remove it and run again",
                        self.root.display()
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Creates a folder inside, after [`SweepFolder::check`].
    ///
    /// # Errors
    /// As [`SweepFolder::check`], and a failed creation.
    pub fn create_dir(&self, dir: &Path) -> Result<()> {
        self.check(dir)?;
        crate::output::create_dir(dir)?;
        self.check(dir)
    }

    /// Writes a file inside, atomically, after [`SweepFolder::check`].
    ///
    /// # Errors
    /// As [`SweepFolder::check`], and a failed write.
    pub fn write_bytes(&self, path: &Path, bytes: &[u8]) -> Result<()> {
        self.check(path)?;
        crate::output::write_bytes(path, bytes)
    }

    /// `output::write_json` inside.
    ///
    /// # Errors
    /// As [`SweepFolder::write_bytes`].
    pub fn write_json(&self, path: &Path, value: &impl serde::Serialize) -> Result<()> {
        self.check(path)?;
        crate::output::write_json(path, value)
    }

    /// `output::write_csv` inside.
    ///
    /// # Errors
    /// As [`SweepFolder::write_bytes`].
    pub fn write_csv<T: serde::Serialize>(
        &self,
        path: &Path,
        columns: &[&str],
        rows: impl IntoIterator<Item = T>,
    ) -> Result<()> {
        self.check(path)?;
        crate::output::write_csv(path, columns, rows)
    }

    /// `output::write_table` inside.
    ///
    /// # Errors
    /// As [`SweepFolder::write_bytes`].
    pub fn write_table<'a, T: crate::output::CsvRow + 'a>(
        &self,
        path: &Path,
        rows: impl IntoIterator<Item = &'a T>,
    ) -> Result<()> {
        self.check(path)?;
        crate::output::write_table(path, rows)
    }

    /// Removes a folder inside (a killed run's leftovers); a link there is removed, never followed.
    ///
    /// # Errors
    /// As [`SweepFolder::check`] for the folders above it, and a failed removal.
    pub fn remove_dir(&self, dir: &Path) -> Result<()> {
        if let Some(parent) = dir.parent() {
            self.check(parent)?;
        }
        let result = match std::fs::symlink_metadata(dir) {
            Ok(m) if m.is_dir() => std::fs::remove_dir_all(dir),
            Ok(_) => std::fs::remove_file(dir),
            Err(_) => Ok(()),
        };
        result.map_err(|source| EvalError::Io {
            path: dir.to_path_buf(),
            source,
        })
    }
}

fn marker_text() -> String {
    format!(
        "a sweep folder of oeg {}: `oeg sweep run` resumes it and `oeg sweep report` writes into it\n",
        env!("CARGO_PKG_VERSION")
    )
}

fn input(path: &Path, message: &str) -> EvalError {
    EvalError::Input {
        path: path.to_path_buf(),
        message: message.to_string(),
    }
}

/// Whether `dir` is the current folder.
fn is_current_folder(dir: &Path) -> bool {
    match (
        std::fs::canonicalize(dir),
        std::env::current_dir().and_then(std::fs::canonicalize),
    ) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

/// Refuses the file system's root, the current folder (or one above it) and a symbolic link, whatever they
/// hold.
fn refuse_special(dir: &Path) -> Result<()> {
    if std::fs::symlink_metadata(dir).is_ok_and(|m| m.file_type().is_symlink()) {
        return Err(input(
            dir,
            "is a symbolic link; give the sweep folder's own path (a sweep never writes through a link)",
        ));
    }
    if dir.as_os_str().is_empty() {
        return Err(input(dir, "expected a folder name"));
    }
    if let Ok(real) = std::fs::canonicalize(dir) {
        if real.parent().is_none() {
            return Err(input(
                dir,
                "is the file system's root; give a folder of the sweep's own, such as out/<study>",
            ));
        }
        if std::env::current_dir()
            .and_then(std::fs::canonicalize)
            .is_ok_and(|cwd| cwd.starts_with(&real))
        {
            return Err(input(
                dir,
                "is the current folder (or holds it); give a folder of the sweep's own, such as out/<study>",
            ));
        }
    }
    Ok(())
}

/// Whether `dir` is a sweep's folder: it holds [`SWEEP_MARKER`], or (written by an earlier version)
/// `plan.json` and only entries a sweep writes; with `empty_ok`, an empty folder too.
fn check_owned(dir: &Path, empty_ok: bool) -> Result<()> {
    let meta = std::fs::symlink_metadata(dir).map_err(|source| EvalError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    if !meta.is_dir() {
        return Err(input(
            dir,
            "is a file, not a folder; give a new or empty folder, or a sweep's folder",
        ));
    }
    let marker = dir.join(SWEEP_MARKER);
    if std::fs::symlink_metadata(&marker).is_ok_and(|m| m.is_file()) {
        return Ok(());
    }
    let entries: Vec<std::ffi::OsString> = std::fs::read_dir(dir)
        .map_err(|source| EvalError::Io {
            path: dir.to_path_buf(),
            source,
        })?
        .filter_map(|e| e.ok().map(|e| e.file_name()))
        .collect();
    if entries.is_empty() && empty_ok {
        return Ok(());
    }
    let earlier_sweep = entries.iter().any(|e| e == "plan.json")
        && entries
            .iter()
            .all(|e| SWEEP_ENTRIES.iter().any(|known| e == *known));
    if earlier_sweep {
        return Ok(());
    }
    // Name what makes it someone's: entries a sweep never writes, or else (its names without a plan) any.
    let mut named: Vec<&std::ffi::OsString> = entries
        .iter()
        .filter(|e| !SWEEP_ENTRIES.iter().any(|known| *e == *known))
        .collect();
    if named.is_empty() {
        named = entries.iter().collect();
    }
    named.sort();
    let foreign: Vec<String> = named
        .iter()
        .take(3)
        .map(|e| e.to_string_lossy().into_owned())
        .collect();
    Err(input(
        dir,
        &format!(
            "is not a sweep's folder (no {SWEEP_MARKER} in it{}); a sweep writes only into a new or empty folder \
             or one it wrote, so give another --out",
            if foreign.is_empty() {
                String::new()
            } else {
                format!(", and it holds {}", foreign.join(", "))
            }
        ),
    ))
}

#[cfg(test)]
#[allow(clippy::disallowed_methods, reason = "tests read back the files they wrote")]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        crate::test_support::scratch_dir("sweep-folder", name)
    }

    #[test]
    fn a_sweep_claims_only_new_empty_or_its_own_folders() {
        let dir = scratch("claim");
        let new = dir.join("new");
        drop(SweepFolder::claim(&new).expect("a new folder"));
        assert!(new.join(SWEEP_MARKER).is_file(), "marked");
        drop(SweepFolder::claim(&new).expect("its own folder again"));
        let theirs = dir.join("theirs");
        std::fs::create_dir_all(&theirs).expect("dir");
        crate::output::write_bytes(&theirs.join("runs.csv"), b"their data").expect("write");
        let e = SweepFolder::claim(&theirs)
            .expect_err("someone's folder")
            .to_string();
        assert!(
            e.contains("not a sweep's folder") && e.contains("runs.csv"),
            "{e}"
        );
        let run = dir.join("run_output");
        std::fs::create_dir_all(&run).expect("dir");
        for f in [crate::output::OUTPUT_MARKER, "metrics.json", "obstacles.csv"] {
            crate::output::write_bytes(&run.join(f), b"x").expect("write");
        }
        assert!(SweepFolder::claim(&run).is_err(), "an `oeg run` folder");
        assert!(SweepFolder::open(&run).is_err(), "report refuses it too");
        let old = dir.join("earlier_version");
        std::fs::create_dir_all(old.join("runs")).expect("dir");
        crate::output::write_bytes(&old.join("plan.json"), b"{}").expect("write");
        drop(SweepFolder::claim(&old).expect("an earlier version's sweep folder"));
        assert_eq!(
            std::fs::read(theirs.join("runs.csv")).expect("read"),
            b"their data"
        );
        std::fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn the_root_and_the_current_folder_are_refused() {
        for dir in ["/", ".", ".."] {
            let e = SweepFolder::claim(Path::new(dir)).expect_err(dir).to_string();
            assert!(e.contains("root") || e.contains("current folder"), "{dir}: {e}");
        }
    }

    #[test]
    fn writes_never_follow_a_link_inside_the_folder() {
        let dir = scratch("links");
        let outside = dir.join("outside");
        std::fs::create_dir_all(&outside).expect("dir");
        crate::output::write_bytes(&outside.join("precious.csv"), b"keep").expect("write");
        let sweep = dir.join("sweep");
        let folder = SweepFolder::claim(&sweep).expect("claimed");
        std::os::unix::fs::symlink(outside.join("precious.csv"), sweep.join("runs.csv")).expect("link");
        std::os::unix::fs::symlink(&outside, sweep.join("plots")).expect("link");
        let e = folder
            .write_bytes(&sweep.join("runs.csv"), b"rows")
            .expect_err("a link")
            .to_string();
        assert!(e.contains("symbolic link inside the sweep folder"), "{e}");
        assert!(folder.create_dir(&sweep.join("plots")).is_err());
        assert!(
            folder
                .write_bytes(&sweep.join("plots/precious.csv"), b"plot")
                .is_err()
        );
        folder.remove_dir(&sweep.join("plots")).expect("the link goes");
        assert_eq!(
            std::fs::read(outside.join("precious.csv")).expect("read"),
            b"keep"
        );
        assert!(outside.is_dir(), "the link's target stays");
        drop(folder);
        std::fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn two_invocations_never_share_a_folder() {
        let dir = scratch("lock");
        let first = SweepFolder::claim(&dir.join("s")).expect("claimed");
        let e = SweepFolder::claim(&dir.join("s")).expect_err("held").to_string();
        assert!(e.contains("another `oeg sweep` works in this folder"), "{e}");
        drop(first);
        drop(SweepFolder::open(&dir.join("s")).expect("free again"));
        std::fs::remove_dir_all(&dir).expect("cleanup");
    }
}
