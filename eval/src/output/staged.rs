//! A job's output folder, all or nothing: staged beside the target and swapped in whole ([`Staged`]), never over
//! a folder the job did not write.

use std::path::{Path, PathBuf};

use super::{create_dir, write_bytes};
use crate::error::{EvalError, Result};
use crate::lock::LockFile;

/// The name of the file that marks a folder as a job's output, which the next job writing there may replace.
pub(crate) const OUTPUT_MARKER: &str = ".oeg-output";

/// The prefix of a job's staging inside a mount point (see [`Staged`]), and of what it sets aside there.
const MOUNT_STAGING: &str = ".oeg-staging.";

/// A job's output folder, written all or nothing.
///
/// The job writes into a staging folder beside its output, `.<name>.staging.<pid>.<n>`; [`Staged::commit`]
/// moves it into place with two renames (the previous output aside, the new one in), then deletes the
/// previous output. So a reader of the output folder sees the complete previous results or the complete new
/// ones, and a job killed at any point leaves the previous results intact and consistent, or (killed between
/// the two renames) no output folder, with the previous one set aside; the next job writing there puts it back
/// before it starts. A job that fails or is dropped removes its staging folder; the staging of killed jobs
/// (whose process no longer runs) is removed by the next job that writes beside them.
///
/// A mount point (a container's volume: another file system than its parent's) cannot be renamed. There the
/// job stages inside it (`.oeg-staging.<pid>.<n>`) and [`Staged::commit`] moves the previous output's entries
/// aside and the new ones in, each with one rename: every file is whole, but a job killed during the commit
/// can leave the folder with part of the old and part of the new entries (the next job writing there replaces
/// them).
///
/// Only folders that a job wrote (they hold [`OUTPUT_MARKER`], or, written by an earlier version, the pair of
/// files their job always wrote and nothing that job does not write) or empty folders are replaced: a folder of
/// someone else's files is an error, before any work is done. Two jobs committing the same folder take turns (a
/// lock file, `lock`), so each leaves it whole and the last one's results stay.
#[derive(Debug)]
pub(crate) struct Staged {
    target: PathBuf,
    staging: PathBuf,
    in_place: bool,
}

impl Staged {
    /// Starts a job that writes the folder `target`: checks that `target` may be replaced, removes stale
    /// staging of killed jobs beside it and creates this job's staging folder (and `target`'s parents). Jobs
    /// call it before their work, so a folder they may not write costs nothing.
    ///
    /// `inputs` are the files and folders the job reads: a target that holds one of them (or is one) is refused,
    /// whoever wrote it, since replacing it would destroy what the job has just read.
    ///
    /// # Errors
    /// [`EvalError::Io`] naming `target` when it is a file or a folder that no job wrote, or when a folder
    /// cannot be created; [`EvalError::Input`] naming the input that `target` holds.
    pub(crate) fn begin(target: &Path, inputs: &[&Path]) -> Result<Self> {
        check_not_an_input(target, inputs)?;
        Self::begin_as(target, is_mount_point(target))
    }

    fn begin_as(target: &Path, in_place: bool) -> Result<Self> {
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
        let staging = if in_place {
            for stale in oeg_files::stale_owners(target, MOUNT_STAGING, "") {
                let _ = std::fs::remove_dir_all(target.join(stale));
            }
            target.join(format!("{MOUNT_STAGING}{}", oeg_files::unique_suffix()))
        } else {
            create_dir(&parent)?;
            // A job killed between the two renames of its swap left no output folder and the previous one
            // aside: put it back, so the previous results stay whatever this job does.
            let mut set_aside = oeg_files::stale_owners(&parent, &format!(".{name}.old."), "");
            set_aside.sort();
            if !target.exists()
                && let Some(previous) = set_aside.pop()
            {
                let _ = restore(&parent.join(previous), target);
            }
            for stale in set_aside.into_iter().chain(oeg_files::stale_owners(
                &parent,
                &format!(".{name}.staging."),
                "",
            )) {
                let _ = std::fs::remove_dir_all(parent.join(stale));
            }
            parent.join(format!(".{name}.staging.{}", oeg_files::unique_suffix()))
        };
        create_dir(&staging)?;
        let marker = format!(
            "written by oeg {}; the next job writing this folder replaces it as a whole\n",
            env!("CARGO_PKG_VERSION")
        );
        write_bytes(&staging.join(OUTPUT_MARKER), marker.as_bytes())?;
        Ok(Self {
            target: target.to_path_buf(),
            staging,
            in_place,
        })
    }

    /// The folder the job writes into until [`Staged::commit`].
    pub(crate) fn dir(&self) -> &Path {
        &self.staging
    }

    /// Where a file written at `staged` (inside [`Staged::dir`]) lies once committed.
    pub(crate) fn final_path(&self, staged: &Path) -> PathBuf {
        staged
            .strip_prefix(&self.staging)
            .map_or_else(|_| staged.to_path_buf(), |rel| self.target.join(rel))
    }

    /// `work` (the job's writes into [`Staged::dir`]) with its error naming a file where it would be in the
    /// output folder: the staging folder is removed when the job fails, so a message must not send the user
    /// there.
    ///
    /// # Errors
    /// `work`'s error.
    pub(crate) fn explained<T>(&self, work: Result<T>) -> Result<T> {
        work.map_err(|e| match e {
            EvalError::Io { path, source } => EvalError::Io {
                path: self.final_path(&path),
                source,
            },
            EvalError::Map(oeg::Error::Io { path, source }) => EvalError::Map(oeg::Error::Io {
                path: self.final_path(&path),
                source,
            }),
            other => other,
        })
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
    pub(crate) fn commit(self) -> Result<PathBuf> {
        if self.in_place {
            return self.commit_in_place();
        }
        let _lock = commit_lock(&self.target.with_file_name(format!(
            ".{}.lock",
            self.target.file_name().unwrap_or_default().to_string_lossy()
        )))?;
        check_replaceable(&self.target)?;
        let aside = self.target.exists().then(|| {
            let name = self.target.file_name().unwrap_or_default().to_string_lossy();
            self.target
                .with_file_name(format!(".{name}.old.{}", oeg_files::unique_suffix()))
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

    /// [`Staged::commit`] inside a mount point: the previous entries aside, the new ones in, one rename each.
    #[expect(
        clippy::disallowed_methods,
        reason = "moving a job's own entries inside its output folder"
    )]
    fn commit_in_place(self) -> Result<PathBuf> {
        let io = |path: &Path| {
            let path = path.to_path_buf();
            move |source| EvalError::Io { path, source }
        };
        let _lock = commit_lock(&self.target.join(format!("{MOUNT_STAGING}lock")))?;
        check_replaceable(&self.target)?;
        let aside = self
            .target
            .join(format!("{MOUNT_STAGING}{}.old", oeg_files::unique_suffix()));
        create_dir(&aside)?;
        for entry in std::fs::read_dir(&self.target).map_err(io(&self.target))? {
            let name = entry.map_err(io(&self.target))?.file_name();
            if !name.to_string_lossy().starts_with(MOUNT_STAGING) {
                let from = self.target.join(&name);
                std::fs::rename(&from, aside.join(&name)).map_err(io(&from))?;
            }
        }
        for entry in std::fs::read_dir(&self.staging).map_err(io(&self.staging))? {
            let name = entry.map_err(io(&self.staging))?.file_name();
            let to = self.target.join(&name);
            std::fs::rename(self.staging.join(&name), &to).map_err(io(&to))?;
        }
        let _ = std::fs::remove_dir_all(&aside);
        Ok(self.target.clone())
    }
}

/// Whether `dir` is a mount point: a folder on another file system than its parent's, which cannot be
/// renamed (`EBUSY`). Told by the device numbers, so only on Unix; elsewhere no folder is one.
#[cfg(not(unix))]
fn is_mount_point(_dir: &Path) -> bool {
    false
}

/// Whether `dir` is a mount point: a folder on another file system than its parent's, which cannot be
/// renamed (`EBUSY`).
#[cfg(unix)]
fn is_mount_point(dir: &Path) -> bool {
    use std::os::unix::fs::MetadataExt as _;
    let Ok(meta) = std::fs::symlink_metadata(dir) else {
        return false;
    };
    let parent = std::fs::canonicalize(dir)
        .ok()
        .and_then(|d| d.parent().map(Path::to_path_buf));
    meta.is_dir()
        && parent
            .and_then(|p| std::fs::metadata(p).ok())
            .is_some_and(|p| p.dev() != meta.dev())
}

/// How long a job waits for another job's swap of the same folder (two renames) before it gives up.
const COMMIT_PATIENCE: std::time::Duration = std::time::Duration::from_secs(60);

/// Takes the lock file `path` (`.<name>.lock` beside the output folder), waiting while another job swaps the
/// same folder, so two jobs never interleave their renames.
fn commit_lock(path: &Path) -> Result<LockFile> {
    let started = std::time::Instant::now();
    loop {
        match LockFile::try_take(path)? {
            Ok(lock) => return Ok(lock),
            Err(busy) if started.elapsed() > COMMIT_PATIENCE => {
                return Err(io_error(
                    path,
                    &format!(
                        "another job has been putting its results in place for a minute: {}",
                        busy.describe(path)
                    ),
                ));
            }
            Err(_) => std::thread::sleep(std::time::Duration::from_millis(10)),
        }
    }
}

impl Drop for Staged {
    /// A job that did not commit leaves nothing behind (after a commit the staging folder is gone already).
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.staging);
    }
}

/// Moves a set-aside output folder back into place.
#[expect(
    clippy::disallowed_methods,
    reason = "putting a job's own previous output back"
)]
fn restore(aside: &Path, target: &Path) -> std::io::Result<()> {
    std::fs::rename(aside, target)
}

fn io_error(path: &Path, message: &str) -> EvalError {
    EvalError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidInput, message.to_string()),
    }
}

/// A job of an earlier version, before [`OUTPUT_MARKER`]: the pair of files it always wrote, every file it
/// could write, and whether its sub-folders are earlier outputs of `oeg run` (the compared model of a run,
/// each scenario of a suite).
struct EarlierJob {
    marks: [&'static str; 2],
    files: &'static [&'static str],
    run_folders: bool,
}

/// The files of `oeg run` (and of its compared model's sub-folder).
const RUN_FILES: &[&str] = &[
    "metrics.json",
    "timing.json",
    "map.oeg",
    "obstacles.csv",
    "wrong_cells.csv",
    "plan.csv",
    "comparison.csv",
    "decisions_comparison.png",
    "decisions.png",
    "elevation.png",
    "elevation_error.png",
    "occupancy.png",
    "traversability.png",
    "truth_elevation.png",
    "variance.png",
];

/// `oeg run`, `map`, `suite`, `plan` and `preview` of earlier versions.
const EARLIER_JOBS: [EarlierJob; 5] = [
    EarlierJob {
        marks: ["metrics.json", "timing.json"],
        files: RUN_FILES,
        run_folders: true,
    },
    EarlierJob {
        marks: ["map.oeg", "summary.json"],
        files: &[
            "map.oeg",
            "summary.json",
            "timing.json",
            "elevation.png",
            "occupancy.png",
            "traversability.png",
            "variance.png",
            "demo.graph",
        ],
        run_folders: false,
    },
    EarlierJob {
        marks: ["suite.csv", "suite.json"],
        files: &["suite.csv", "suite.json"],
        run_folders: true,
    },
    EarlierJob {
        marks: ["plan.json", "path.csv"],
        files: &["plan.json", "path.csv", "plan.png"],
        run_folders: false,
    },
    EarlierJob {
        marks: ["preview_elevation.png", "preview_decisions.png"],
        files: &["preview_elevation.png", "preview_decisions.png"],
        run_folders: false,
    },
];

/// Whether `dir` is the output of a job of an earlier version: it holds the pair of files the job always
/// wrote, and every entry in it is one that job writes (a folder with anything else in it, a `thesis.tex`
/// beside a `metrics.json` and a `timing.json`, is someone's, and is never replaced).
fn is_earlier_output(dir: &Path, jobs: &[EarlierJob]) -> bool {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return false;
    };
    let entries: Vec<(std::ffi::OsString, Option<std::fs::FileType>)> = entries
        .filter_map(|e| e.ok().map(|e| (e.file_name(), e.file_type().ok())))
        .collect();
    jobs.iter().any(|job| {
        job.marks
            .iter()
            .all(|m| std::fs::symlink_metadata(dir.join(m)).is_ok_and(|meta| meta.is_file()))
            && entries.iter().all(|(name, kind)| match kind {
                Some(k) if k.is_file() => job.files.iter().any(|f| name == *f),
                Some(k) if k.is_dir() => {
                    job.run_folders && is_earlier_output(&dir.join(name), &EARLIER_JOBS[..1])
                }
                _ => false,
            })
    })
}

/// Whether a job may replace `target`: absent, an empty folder, or a folder a job wrote.
/// Refuses a `target` that is one of `inputs` or holds one, comparing the paths with links resolved. An input
/// that does not exist (yet) cannot be lost; a `target` that does not exist holds nothing.
fn check_not_an_input(target: &Path, inputs: &[&Path]) -> Result<()> {
    let Ok(target_real) = std::fs::canonicalize(target) else {
        return Ok(());
    };
    for input in inputs {
        if let Ok(real) = std::fs::canonicalize(input)
            && real.starts_with(&target_real)
        {
            return Err(EvalError::Input {
                path: input.to_path_buf(),
                message: format!(
                    "is an input of this job and lies in its output folder {}, which the job replaces as a whole; \
                     write the output to another folder",
                    target.display()
                ),
            });
        }
    }
    Ok(())
}

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
    if std::fs::symlink_metadata(target.join(OUTPUT_MARKER)).is_ok_and(|m| m.is_file())
        || is_earlier_output(target, &EARLIER_JOBS)
    {
        return Ok(());
    }
    let mut entries = std::fs::read_dir(target).map_err(|source| EvalError::Io {
        path: target.to_path_buf(),
        source,
    })?;
    // A mount point's own staging (a job killed there) does not make it someone's.
    let empty = entries.all(|e| {
        e.ok()
            .is_some_and(|e| e.file_name().to_string_lossy().starts_with(MOUNT_STAGING))
    });
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

#[cfg(test)]
#[allow(clippy::disallowed_methods, reason = "tests read back the files they wrote")]
mod tests {
    use super::*;

    /// `dir/name` holding `files` (paths inside it, sub-folders made), each `x`.
    fn make_folder(dir: &Path, name: &str, files: &[&str]) -> PathBuf {
        let d = dir.join(name);
        create_dir(&d).expect("dir");
        for f in files {
            let path = d.join(f);
            create_dir(path.parent().expect("parent")).expect("dir");
            write_bytes(&path, b"x").expect("file");
        }
        d
    }

    #[test]
    fn only_empty_folders_and_folders_a_job_wrote_are_replaced() {
        let dir = crate::test_support::scratch_dir("output", "replaced");
        let folder = |name: &str, files: &[&str]| make_folder(&dir, name, files);
        for ok in [
            folder("empty", &[]),
            folder("marked", &[OUTPUT_MARKER, "notes.txt"]),
            folder("old_run", &["metrics.json", "timing.json", "map.oeg"]),
        ] {
            assert!(check_replaceable(&ok).is_ok(), "{}", ok.display());
        }
        for refused in [
            folder("theirs", &["thesis.tex"]),
            folder("half", &["metrics.json"]),
        ] {
            let err = check_replaceable(&refused)
                .expect_err("someone else's")
                .to_string();
            assert!(err.contains("no oeg job wrote"), "{err}");
        }
        // A killed job's lock (no process has this id) is taken over.
        write_bytes(&dir.join(".old_run.lock"), b"4294967295").expect("lock");
        let staged = Staged::begin(&dir.join("old_run"), &[]).expect("begins");
        write_bytes(&staged.dir().join("metrics.json"), b"new").expect("file");
        let target = staged.commit().expect("committed");
        assert_eq!(std::fs::read(target.join("metrics.json")).expect("read"), b"new");
        assert!(!target.join("map.oeg").exists(), "the folder was replaced whole");
        assert!(!dir.join(".old_run.lock").exists(), "the lock is released");
        // Killed between its two renames: no output folder, the previous one aside. The next job puts it back
        // first, so its own failure leaves the previous results.
        let aside = folder(".killed.old.4294967295.0", &[OUTPUT_MARKER, "metrics.json"]);
        let failed = Staged::begin(&dir.join("killed"), &[]).expect("begins");
        drop(failed);
        assert!(
            dir.join("killed/metrics.json").is_file(),
            "the previous results are back"
        );
        assert!(!aside.exists());
        std::fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn a_folder_is_an_earlier_output_only_if_every_entry_is_one_its_job_writes() {
        let dir = crate::test_support::scratch_dir("output", "earlier");
        let folder = |name: &str, files: &[&str]| make_folder(&dir, name, files);
        for ok in [
            folder(
                "run",
                &[
                    "metrics.json",
                    "timing.json",
                    "decisions.png",
                    "robust/metrics.json",
                    "robust/timing.json",
                ],
            ),
            folder("plan", &["plan.json", "path.csv", "plan.png"]),
            folder(
                "suite",
                &[
                    "suite.csv",
                    "suite.json",
                    "default/metrics.json",
                    "default/timing.json",
                ],
            ),
        ] {
            assert!(check_replaceable(&ok).is_ok(), "{}", ok.display());
        }
        // A machine-learning experiment and a thesis: the job's pair, and files it never writes.
        for refused in [
            folder("experiment", &["metrics.json", "timing.json", "thesis.tex"]),
            folder("with_src", &["metrics.json", "timing.json", "src/main.rs"]),
            folder("plan_and_notes", &["plan.json", "path.csv", "notes.md"]),
            folder("suite_of_theirs", &["suite.csv", "suite.json", "data/raw.csv"]),
        ] {
            let staged = Staged::begin(&refused, &[]);
            let err = staged.expect_err("someone's folder").to_string();
            assert!(err.contains("no oeg job wrote"), "{err}");
        }
        assert!(dir.join("experiment/thesis.tex").is_file());
        assert!(dir.join("with_src/src/main.rs").is_file());
        std::fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn a_mount_point_is_written_in_place() {
        assert!(is_mount_point(Path::new("/proc")), "/proc is a mount point");
        assert!(!is_mount_point(&std::env::temp_dir().join("oeg-no-such-folder")));
        let dir = crate::test_support::scratch_dir("output", "mount");
        let target = make_folder(&dir, "volume", &[]);
        assert!(!is_mount_point(&target));
        for (round, content) in [b"first".as_slice(), b"second"].into_iter().enumerate() {
            let staged = Staged::begin_as(&target, true).expect("begins");
            assert!(staged.dir().starts_with(&target), "staged inside the mount point");
            write_bytes(&staged.dir().join("metrics.json"), content).expect("file");
            if round == 0 {
                write_bytes(&staged.dir().join("only_first.csv"), b"x").expect("file");
            }
            let done = staged.commit().expect("committed");
            assert_eq!(done, target);
            assert_eq!(std::fs::read(target.join("metrics.json")).expect("read"), content);
        }
        let mut names: Vec<String> = std::fs::read_dir(&target)
            .expect("list")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(
            names,
            [OUTPUT_MARKER, "metrics.json"],
            "the previous output went whole"
        );
        std::fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn a_failed_write_names_the_file_in_the_output_folder_not_in_the_staging() {
        let dir = std::env::temp_dir().join(format!("oeg-staged-explained-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let target = dir.join("out");
        let staged = Staged::begin(&target, &[]).expect("begins");
        // A folder where the job writes a file: the write fails inside the staging folder.
        create_dir(&staged.dir().join("metrics.json")).expect("dir");
        let work = write_bytes(&staged.dir().join("metrics.json"), b"{}");
        let e = staged
            .explained(work)
            .expect_err("a folder in the way")
            .to_string();
        assert!(
            e.starts_with(&format!("{}", target.join("metrics.json").display())),
            "{e}"
        );
        assert!(!e.contains(".staging."), "{e}");
        drop(staged);
        std::fs::remove_dir_all(&dir).expect("cleanup");
    }
}
