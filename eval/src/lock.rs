//! Lock files: one job at a time in a folder (a sweep folder's `.lock`) or on a folder's swap (the
//! `.<name>.lock` beside a job's output).
//!
//! The lock is the operating system's advisory lock on the file (`flock`), which the kernel releases when its
//! holder ends, however it ends: a killed job, a container restart or a requeue on another node leaves a file
//! that nobody holds, and the next job takes it. A process id alone cannot tell this, because ids are reused
//! (after a container restart the id of a killed job often names a live process).
//!
//! The file also records who holds it: the host, the process id, the boot and the process's start time
//! ([`Holder`]). That record is what the messages print, and what decides on a file system that has no locks
//! (some network file systems refuse `flock`): there a lock is stale when its holder is on this host and its
//! process has ended or is another process with the same id (its start time or the boot differs). A holder on
//! another host cannot be checked from here; the message then says so and names the file to remove.

use std::io::{Read as _, Seek as _, Write as _};
use std::path::{Path, PathBuf};

use crate::error::{EvalError, Result};

/// What identifies a lock's holder beyond its process id.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Holder {
    /// The host name.
    pub host: String,
    /// The process id.
    pub pid: u32,
    /// The kernel's boot id (`/proc/sys/kernel/random/boot_id`): a restarted machine has another.
    pub boot: String,
    /// The process's start time, in clock ticks since boot (`/proc/<pid>/stat`, field 22).
    pub start: u64,
}

impl Holder {
    /// This process.
    pub(crate) fn this_process() -> Self {
        let pid = std::process::id();
        Self {
            host: host_name(),
            pid,
            boot: boot_id(),
            start: process_start(pid).unwrap_or(0),
        }
    }

    /// Reads a lock file's record (`host=... pid=... boot=... start=...`); `None` for anything else (a file
    /// being written, or written by an earlier version: a bare process id).
    pub(crate) fn parse(text: &str) -> Option<Self> {
        let mut holder = Self {
            host: String::new(),
            pid: 0,
            boot: String::new(),
            start: 0,
        };
        let mut seen = 0;
        for field in text.split_whitespace() {
            let (key, value) = field.split_once('=')?;
            match key {
                "host" => holder.host = value.to_string(),
                "pid" => holder.pid = value.parse().ok()?,
                "boot" => holder.boot = value.to_string(),
                "start" => holder.start = value.parse().ok()?,
                _ => return None,
            }
            seen += 1;
        }
        (seen == 4).then_some(holder)
    }

    fn record(&self) -> String {
        format!(
            "host={} pid={} boot={} start={}\n",
            self.host, self.pid, self.boot, self.start
        )
    }

    /// Whether the holder is known to have ended: on this host, its process is gone or the id now names
    /// another process (started at another time, or the machine rebooted). A holder on another host is never
    /// known to have ended.
    pub(crate) fn is_gone(&self) -> bool {
        let here = Self::this_process();
        if self.host != here.host {
            return false;
        }
        if !here.boot.is_empty() && self.boot != here.boot {
            return true;
        }
        match process_start(self.pid) {
            Some(start) => start != self.start,
            // No record of its start: gone if Linux lists processes under `/proc` and not this one.
            None => Path::new("/proc/self").exists() && !Path::new(&format!("/proc/{}", self.pid)).exists(),
        }
    }
}

impl std::fmt::Display for Holder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "process {} on host {}", self.pid, self.host)
    }
}

/// Why a lock could not be taken.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Busy {
    /// A live process holds the operating system's lock on the file (its record, if it could be read).
    Locked(Option<Holder>),
    /// The file system has no locks, and the record names a holder that is not known to have ended.
    Recorded(Holder),
}

impl Busy {
    /// Who holds it, for messages, with what to do if that is wrong.
    pub(crate) fn describe(&self, lock: &Path) -> String {
        match self {
            Self::Locked(Some(h)) => format!(
                "{h} holds the lock {} (the operating system's lock on it is held, so a process holds it; if no \
                 job of yours runs there, a network file system may have kept the lock of a crashed node: it \
                 may be stale, and removing {} frees the folder)",
                lock.display(),
                lock.display()
            ),
            Self::Locked(None) => format!(
                "another process holds the lock {} (if no job of yours runs, it may be stale: remove {})",
                lock.display(),
                lock.display()
            ),
            Self::Recorded(h) => format!(
                "{h} holds the lock {} according to the file (this file system has no locks to check it); \
                 the lock may be stale: if no job of that process runs any more, remove {}",
                lock.display(),
                lock.display()
            ),
        }
    }
}

/// A held lock file; dropped, it removes the file and releases the lock.
#[derive(Debug)]
pub(crate) struct LockFile {
    path: PathBuf,
    _file: std::fs::File,
}

impl LockFile {
    /// Tries once to take the lock at `path` (creating the file).
    ///
    /// # Errors
    /// [`EvalError::Io`] naming the file when it cannot be opened or written (a folder, a link, a read-only
    /// folder).
    pub(crate) fn try_take(path: &Path) -> Result<std::result::Result<Self, Busy>> {
        let io = |source| EvalError::Io {
            path: path.to_path_buf(),
            source,
        };
        // A holder removes its file when it ends; one opened just before that is not the lock any more, so the
        // file is opened again (a few times at most: it changes only when a holder ends).
        for _ in 0..8 {
            refuse_link(path)?;
            let mut file = std::fs::File::options()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(path)
                .map_err(io)?;
            let locked = match file.try_lock() {
                Ok(()) => true,
                Err(std::fs::TryLockError::WouldBlock) => {
                    return Ok(Err(Busy::Locked(read_holder(&mut file))));
                }
                // No locks on this file system: the record decides.
                Err(std::fs::TryLockError::Error(_)) => false,
            };
            if !same_file(path, &file) {
                continue;
            }
            if !locked
                && let Some(holder) = read_holder(&mut file)
                && holder != Holder::this_process()
                && !holder.is_gone()
            {
                return Ok(Err(Busy::Recorded(holder)));
            }
            file.set_len(0).map_err(io)?;
            file.rewind().map_err(io)?;
            file.write_all(Holder::this_process().record().as_bytes())
                .map_err(io)?;
            file.flush().map_err(io)?;
            return Ok(Ok(Self {
                path: path.to_path_buf(),
                _file: file,
            }));
        }
        Ok(Err(Busy::Locked(None)))
    }
}

impl Drop for LockFile {
    /// Removes the file while still holding the lock (a process that opened it meanwhile sees that the path no
    /// longer names its file and opens it again), then releases the lock by closing it.
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

fn refuse_link(path: &Path) -> Result<()> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if !m.is_file() => Err(EvalError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "is not a regular file (a link, a folder or a device); a lock file is never followed or \
                 replaced: remove it",
            ),
        }),
        _ => Ok(()),
    }
}

fn read_holder(file: &mut std::fs::File) -> Option<Holder> {
    let mut text = String::new();
    file.rewind().ok()?;
    file.take(4096).read_to_string(&mut text).ok()?;
    Holder::parse(&text)
}

/// Whether `path` still names the open `file` (its holder may have removed it since it was opened).
#[cfg(unix)]
fn same_file(path: &Path, file: &std::fs::File) -> bool {
    use std::os::unix::fs::MetadataExt as _;
    match (std::fs::symlink_metadata(path), file.metadata()) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

/// Elsewhere an open file cannot be removed, so the path names it.
#[cfg(not(unix))]
fn same_file(_path: &Path, _file: &std::fs::File) -> bool {
    true
}

fn first_line(path: &str) -> String {
    oeg_files::read_text(Path::new(path))
        .ok()
        .and_then(|t| t.lines().next().map(|l| l.trim().to_string()))
        .unwrap_or_default()
}

fn host_name() -> String {
    let name = first_line("/proc/sys/kernel/hostname");
    let name = if name.is_empty() {
        std::env::var("HOSTNAME").unwrap_or_default()
    } else {
        name
    };
    let name: String = name.chars().filter(|c| !c.is_whitespace() && *c != '=').collect();
    if name.is_empty() { "unknown".into() } else { name }
}

fn boot_id() -> String {
    first_line("/proc/sys/kernel/random/boot_id")
}

/// A process's start time in clock ticks since boot, from `/proc/<pid>/stat`; `None` where it is not listed.
fn process_start(pid: u32) -> Option<u64> {
    let stat = oeg_files::read_text(Path::new(&format!("/proc/{pid}/stat"))).ok()?;
    // The command name (field 2) is in parentheses and may hold spaces: fields are counted after its end.
    let rest = &stat[stat.rfind(')')? + 1..];
    rest.split_whitespace().nth(19)?.parse().ok()
}

#[cfg(test)]
#[allow(clippy::disallowed_methods, reason = "tests read back the files they wrote")]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        crate::test_support::scratch_dir("lock", name)
    }

    #[test]
    fn a_lock_is_held_until_dropped_and_its_record_names_the_holder() {
        let dir = scratch("held");
        let path = dir.join(".lock");
        let lock = LockFile::try_take(&path).expect("io").expect("taken");
        let record = Holder::parse(&std::fs::read_to_string(&path).expect("read")).expect("record");
        assert_eq!(record, Holder::this_process());
        assert!(record.start > 0, "the start time is recorded");
        match LockFile::try_take(&path).expect("io") {
            Err(Busy::Locked(Some(h))) => assert_eq!(h.pid, std::process::id()),
            other => panic!("expected the lock held, got {other:?}"),
        }
        drop(lock);
        assert!(!path.exists(), "the file goes with the lock");
        let _again = LockFile::try_take(&path).expect("io").expect("taken again");
        std::fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn a_lock_file_naming_a_live_process_that_holds_no_lock_is_taken_over() {
        // After a container restart the recorded id names some live process (here: this test's own parent
        // or process 1); the OS lock is free, so the file is stale whatever it says.
        let dir = scratch("stale");
        let path = dir.join(".lock");
        for record in [
            "1\n".to_string(),
            format!("{}\n", std::process::id()),
            "host=elsewhere pid=1 boot=x start=5\n".to_string(),
        ] {
            crate::output::write_bytes(&path, record.as_bytes()).expect("write");
            let lock = LockFile::try_take(&path).expect("io");
            assert!(lock.is_ok(), "{record:?}: {lock:?}");
        }
        std::fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn a_recorded_holder_is_gone_when_its_id_names_another_process() {
        let me = Holder::this_process();
        assert!(!me.is_gone());
        assert!(
            Holder {
                start: me.start + 1,
                ..me.clone()
            }
            .is_gone(),
            "id reused"
        );
        assert!(
            Holder {
                boot: "another-boot".into(),
                ..me.clone()
            }
            .is_gone(),
            "rebooted"
        );
        assert!(
            !Holder {
                host: "elsewhere".into(),
                pid: u32::MAX,
                ..me
            }
            .is_gone(),
            "cannot tell"
        );
        assert_eq!(Holder::parse("4242\n"), None);
        assert_eq!(Holder::parse("host=a pid=x boot=b start=1"), None);
    }

    #[test]
    fn the_stale_message_names_the_file_to_remove() {
        let path = Path::new("/shared/study/.lock");
        let busy = Busy::Recorded(Holder {
            host: "node7".into(),
            pid: 12,
            boot: "b".into(),
            start: 3,
        });
        let m = busy.describe(path);
        assert!(m.contains("process 12 on host node7"), "{m}");
        assert!(
            m.contains("may be stale") && m.contains("remove /shared/study/.lock"),
            "{m}"
        );
    }
}
