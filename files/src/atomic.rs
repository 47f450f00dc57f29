//! Outputs written atomically: a temporary file beside the output, renamed over it once complete, and the
//! temporaries of killed writers recognised by their process id and removed.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{FileError, Result};

/// Writes `bytes` to `path` atomically (an [`AtomicFile`] written at once), so a reader never sees half a
/// file and a failed write leaves no partial output.
///
/// # Errors
/// As [`AtomicFile::create`] and [`AtomicFile::commit`].
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut file = AtomicFile::create(path)?;
    file.write_all(bytes)?;
    file.commit()
}

/// A file written atomically: into a temporary file beside it, renamed over it by [`AtomicFile::commit`].
/// Dropped without a commit (an error, a panic), it removes its temporary file and leaves `path` as it was.
///
/// Only regular files are ever replaced (see [`output_target`]): a device, a FIFO, a socket, a folder or a
/// symbolic link to one of them is an error and is left untouched. A symbolic link to a regular file is
/// followed, so the link stays and its target is replaced. Temporary files that killed writers left beside
/// `path` are removed first (by the process id in their names).
#[derive(Debug)]
pub struct AtomicFile {
    path: PathBuf,
    target: PathBuf,
    tmp: PathBuf,
    out: Option<std::io::BufWriter<std::fs::File>>,
}

impl AtomicFile {
    /// Starts writing `path`.
    ///
    /// # Errors
    /// [`FileError::Io`] naming `path` when it is not a regular file (or absent), or the temporary file cannot be
    /// created.
    pub fn create(path: &Path) -> Result<Self> {
        let target = output_target(path)?;
        remove_stale_temporaries(&target);
        let tmp = temporary_path(&target);
        let file = std::fs::File::options()
            .write(true)
            .create_new(true)
            .open(&tmp)
            .map_err(|e| FileError::io(path, e))?;
        Ok(Self {
            path: path.to_path_buf(),
            target,
            tmp,
            out: Some(std::io::BufWriter::new(file)),
        })
    }

    /// Appends `bytes`.
    ///
    /// # Errors
    /// [`FileError::Io`] naming the file.
    pub fn write_all(&mut self, bytes: &[u8]) -> Result<()> {
        match self.out.as_mut() {
            Some(out) => out.write_all(bytes).map_err(|e| FileError::io(&self.path, e)),
            None => Err(FileError::io(
                &self.path,
                std::io::Error::other("the file was already committed"),
            )),
        }
    }

    /// Flushes the file to disk and renames it over `path`.
    ///
    /// # Errors
    /// [`FileError::Io`] naming the file; the temporary file is removed and `path` is left as it was.
    #[expect(
        clippy::disallowed_methods,
        reason = "this is the one place a finished file is renamed into place"
    )]
    pub fn commit(mut self) -> Result<()> {
        let out = self.out.take().ok_or_else(|| {
            FileError::io(
                &self.path,
                std::io::Error::other("the file was already committed"),
            )
        })?;
        let result = out
            .into_inner()
            .map_err(std::io::IntoInnerError::into_error)
            .and_then(|f| f.sync_all())
            .and_then(|()| std::fs::rename(&self.tmp, &self.target));
        result.map_err(|e| {
            let _ = std::fs::remove_file(&self.tmp);
            FileError::io(&self.path, e)
        })
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if self.out.take().is_some() {
            // Abandoned before commit: the temporary file is ours and useless now.
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// The file an output at `path` replaces: `path` itself when nothing or a regular file is there, or the
/// regular file a symbolic link at `path` points to.
///
/// # Errors
/// [`FileError::Io`] naming `path` when it is a folder, a device, a FIFO, a socket, a symbolic link to one of them
/// or a dangling symbolic link: outputs are only ever written to regular files.
pub fn output_target(path: &Path) -> Result<PathBuf> {
    let refuse = |what: &str| {
        FileError::io(
            path,
            std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!("{what}; outputs are only written to regular files, so it was left untouched"),
            ),
        )
    };
    let link = std::fs::symlink_metadata(path);
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() => match link {
            Ok(l) if l.file_type().is_symlink() => {
                std::fs::canonicalize(path).map_err(|e| FileError::io(path, e))
            }
            _ => Ok(path.to_path_buf()),
        },
        Ok(m) if m.is_dir() => Err(refuse("is a folder, not a file")),
        Ok(_) => Err(refuse("is a device, a FIFO or a socket, not a regular file")),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => match link {
            Ok(_) => Err(refuse("is a dangling symbolic link")),
            Err(_) => Ok(path.to_path_buf()),
        },
        Err(e) => Err(FileError::io(path, e)),
    }
}

/// Temporary names: `<name>.<pid>.<n>.tmp` ([`unique_suffix`]), so two writers of one path, in one process or
/// in two, never share a temporary file.
fn temporary_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().map(|n| n.to_os_string()).unwrap_or_default();
    name.push(format!(".{}.tmp", unique_suffix()));
    path.with_file_name(name)
}

/// `<pid>.<n>`, `n` counting up within the process: unique among the calls of every running process. The
/// suffix of temporary files and staging folders, which [`stale_owners`] recognises.
pub fn unique_suffix() -> String {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    format!("{}.{n}", std::process::id())
}

/// Whether the process `pid` is known to have ended: Linux lists running processes under `/proc`; where it
/// does not, no process is known to have ended.
fn process_is_gone(pid: u32) -> bool {
    Path::new("/proc/self").exists() && !Path::new(&format!("/proc/{pid}")).exists()
}

/// Removes the temporary files (`<name>.<pid>.<n>.tmp`) that writers of `path` left behind when they were
/// killed: those whose process no longer runs. Best effort, and only where the operating system lists its
/// processes under `/proc` (Linux); elsewhere nothing is removed.
fn remove_stale_temporaries(path: &Path) {
    let (Some(dir), Some(name)) = (path.parent(), path.file_name().and_then(|n| n.to_str())) else {
        return;
    };
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    for pid in stale_owners(dir, &format!("{name}."), ".tmp") {
        let _ = std::fs::remove_file(dir.join(pid));
    }
}

/// Entries of `dir` named `<prefix><pid>.<n><suffix>` (see [`unique_suffix`]) whose process `pid` is gone
/// (Linux lists running processes under `/proc`; elsewhere none is known to have ended).
pub fn stale_owners(dir: &Path, prefix: &str, suffix: &str) -> Vec<std::ffi::OsString> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    entries
        .filter_map(|e| e.ok().map(|e| e.file_name()))
        .filter(|file| {
            let Some(rest) = file
                .to_str()
                .and_then(|f| f.strip_prefix(prefix))
                .and_then(|f| f.strip_suffix(suffix))
            else {
                return false;
            };
            let mut parts = rest.split('.');
            match (parts.next(), parts.next(), parts.next()) {
                (Some(pid), Some(n), None) if n.bytes().all(|b| b.is_ascii_digit()) && !n.is_empty() => pid
                    .parse::<u32>()
                    .is_ok_and(|pid| pid != std::process::id() && process_is_gone(pid)),
                _ => false,
            }
        })
        .collect()
}
