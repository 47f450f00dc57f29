//! Reading real data into [`crate::Scan`]s, and saving and loading maps.
//!
//! * [`graph`]: OctoMap scan graphs (`.graph`), the format of OctoMap's published data sets;
//! * [`pcd`]: PCL point clouds (`.pcd`: ascii, binary, binary_compressed);
//! * [`mapfile`]: this crate's own map format (`.oeg`).
//!
//! Every reader checks sizes against the file before allocating, rejects non-finite numbers, and names the
//! file and the byte or line of the problem.

mod atomic;
pub mod container;
pub mod graph;
mod lzf;
pub mod mapfile;
pub mod nav2;
pub mod npy;
pub mod pcd;
pub mod planner_files;

use std::path::Path;

use crate::error::{Error, Result};

pub use atomic::{AtomicFile, output_target, stale_owners, unique_suffix, write_atomically};

/// The rotation of a quaternion `(w, x, y, z)` read from a file, or `None` when it is zero or not finite.
///
/// The components are scaled by the largest of them before normalising, so a finite quaternion of any
/// magnitude (1e200 as well as 1e-200) keeps its rotation: a plain norm overflows to infinity there and the
/// rotation is silently lost.
pub fn unit_quaternion(w: f64, x: f64, y: f64, z: f64) -> Option<nalgebra::UnitQuaternion<f64>> {
    if ![w, x, y, z].iter().all(|v| v.is_finite()) {
        return None;
    }
    let scale = [w, x, y, z].iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if scale == 0.0 {
        return None;
    }
    let q = nalgebra::Quaternion::new(w / scale, x / scale, y / scale, z / scale);
    Some(nalgebra::UnitQuaternion::from_quaternion(q))
}

/// Reads a whole file of at most `limit` bytes ([`read_bounded`]), naming it on failure: a binary input (a map,
/// a scan graph, a PCD) is never read past the memory its caller allows, whatever the file (a device) says.
pub(crate) fn read_file(path: &Path, limit: u64) -> Result<Vec<u8>> {
    read_bounded(path, limit)
}

/// The largest text input the programs read: a scenario, a sweep file, a sweep's base scenario, a robot's
/// URDF. The largest shipped one is a few kilobytes; 16 MiB holds hundreds of thousands of waypoints.
pub const MAX_TEXT_INPUT_BYTES: u64 = 16 << 20;

/// Reads a whole file of at most `limit` bytes. A larger regular file is refused from its size before a
/// byte is read; a device or a pipe (`/dev/zero`), whose size is unknown, as soon as it passes `limit`.
///
/// # Errors
/// [`Error::Io`] naming the file: it cannot be read, or it is larger than `limit` (kind
/// [`std::io::ErrorKind::FileTooLarge`]).
pub fn read_bounded(path: &Path, limit: u64) -> Result<Vec<u8>> {
    use std::io::Read as _;
    let too_large = |size: String| {
        Error::io(
            path,
            std::io::Error::new(
                std::io::ErrorKind::FileTooLarge,
                format!("is {size}, over the limit of {limit} bytes for this input; is it the right file?"),
            ),
        )
    };
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let meta = file.metadata().map_err(|e| Error::io(path, e))?;
    if meta.is_dir() {
        return Err(Error::io(
            path,
            std::io::Error::new(std::io::ErrorKind::IsADirectory, "is a folder, not a file"),
        ));
    }
    if meta.is_file() && meta.len() > limit {
        return Err(too_large(format!("{} bytes", meta.len())));
    }
    let mut bytes = Vec::new();
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > limit {
        return Err(too_large("longer than that (a device or a pipe)".into()));
    }
    Ok(bytes)
}

/// [`read_bounded`] of a UTF-8 text of at most [`MAX_TEXT_INPUT_BYTES`].
///
/// # Errors
/// As [`read_bounded`], and a file that is not UTF-8 text (naming the byte).
pub fn read_text(path: &Path) -> Result<String> {
    let bytes = read_bounded(path, MAX_TEXT_INPUT_BYTES)?;
    String::from_utf8(bytes).map_err(|e| {
        Error::parse(
            path,
            format!(
                "byte {}: not UTF-8 text; expected a text file",
                e.utf8_error().valid_up_to()
            ),
        )
    })
}

/// A little-endian reader over a file's bytes that names the file and byte offset in its errors.
pub(crate) struct ByteReader<'a> {
    path: &'a Path,
    data: &'a [u8],
    pos: usize,
}

impl<'a> ByteReader<'a> {
    pub(crate) fn new(path: &'a Path, data: &'a [u8]) -> Self {
        Self { path, data, pos: 0 }
    }

    pub(crate) fn pos(&self) -> usize {
        self.pos
    }

    pub(crate) fn remaining(&self) -> usize {
        self.data.len() - self.pos
    }

    pub(crate) fn error(&self, message: impl std::fmt::Display) -> Error {
        self.error_at(self.pos, message)
    }

    pub(crate) fn error_at(&self, at: usize, message: impl std::fmt::Display) -> Error {
        Error::parse(self.path, format!("at byte {at}: {message}"))
    }

    pub(crate) fn take(&mut self, n: usize, what: impl std::fmt::Display) -> Result<&'a [u8]> {
        if self.remaining() < n {
            return Err(self.error(format!(
                "file is truncated: expected {n} more bytes for {what}, found {}",
                self.remaining()
            )));
        }
        let s = &self.data[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    pub(crate) fn array<const N: usize>(&mut self, what: impl std::fmt::Display) -> Result<[u8; N]> {
        let s = self.take(N, what)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }

    pub(crate) fn u32(&mut self, what: impl std::fmt::Display) -> Result<u32> {
        self.array(what).map(u32::from_le_bytes)
    }

    pub(crate) fn i32(&mut self, what: impl std::fmt::Display) -> Result<i32> {
        self.array(what).map(i32::from_le_bytes)
    }

    pub(crate) fn f64(&mut self, what: impl std::fmt::Display) -> Result<f64> {
        self.array(what).map(f64::from_le_bytes)
    }

    pub(crate) fn f32(&mut self, what: impl std::fmt::Display) -> Result<f32> {
        self.array(what).map(f32::from_le_bytes)
    }
}

/// FNV-1a, 64 bit, of `bytes`: the checksum of the map file and the sensor log, and the project's one hash of
/// bytes. Not cryptographic; it catches truncation and bit rot.
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h = Fnv1a64::new();
    h.update(bytes);
    h.value()
}

/// [`fnv1a64`] computed piece by piece, for a file written as a stream.
#[derive(Debug, Clone, Copy)]
pub struct Fnv1a64(u64);

impl Fnv1a64 {
    /// The hash of no bytes.
    pub const fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }

    /// Adds `bytes`.
    pub fn update(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }

    /// The hash of every byte added so far.
    pub const fn value(self) -> u64 {
        self.0
    }
}

impl Default for Fnv1a64 {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
#[allow(clippy::disallowed_methods, reason = "tests write their inputs directly")]
mod tests {
    use super::*;
    use std::path::PathBuf;

    #[test]
    fn text_inputs_over_the_limit_are_refused_before_they_are_read() {
        let dir = scratch_dir("bounded");
        let path = dir.join("big.toml");
        std::fs::write(&path, vec![b'#'; 100]).expect("write");
        assert_eq!(read_bounded(&path, 100).expect("fits").len(), 100);
        let e = read_bounded(&path, 99).expect_err("over").to_string();
        assert!(
            e.contains("big.toml") && e.contains("100 bytes, over the limit of 99"),
            "{e}"
        );
        // A device of endless bytes stops at the limit, not at the end of memory.
        let e = read_bounded(Path::new("/dev/zero"), 1 << 20)
            .expect_err("endless")
            .to_string();
        assert!(e.contains("/dev/zero") && e.contains("over the limit"), "{e}");
        std::fs::write(&path, b"name = \"\xff\"").expect("write");
        let e = read_text(&path).expect_err("not UTF-8").to_string();
        assert!(e.contains("byte 8: not UTF-8"), "{e}");
        assert!(
            read_text(&dir)
                .expect_err("a folder")
                .to_string()
                .contains("folder")
        );
        std::fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn fnv1a64_matches_the_reference_values() {
        assert_eq!(fnv1a64(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a64(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a64(b"foobar"), 0x8594_4171_f739_67e8);
    }

    #[test]
    fn atomic_writes_leave_no_temporary_file() {
        let dir = std::env::temp_dir().join(format!("oeg-io-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join("x.bin");
        write_atomically(&path, b"hello").expect("written");
        assert_eq!(std::fs::read(&path).expect("read"), b"hello");
        let names: Vec<_> = std::fs::read_dir(&dir)
            .expect("dir")
            .map(|e| e.expect("entry").file_name())
            .collect();
        assert_eq!(names.len(), 1, "{names:?}");
        let err = write_atomically(&dir.join("missing/x.bin"), b"x").expect_err("no such folder");
        assert!(err.to_string().contains("missing"), "{err}");
        std::fs::remove_dir_all(&dir).expect("cleanup");
    }

    fn scratch_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("oeg-io-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        dir
    }

    #[test]
    fn writing_over_a_fifo_or_a_link_to_one_is_refused_and_leaves_it_a_fifo() {
        use std::os::unix::fs::FileTypeExt;
        let dir = scratch_dir("fifo");
        let fifo = dir.join("pipe");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if !made.is_ok_and(|s| s.success()) {
            println!("skipped: `mkfifo` is not available here");
            return;
        }
        let link = dir.join("link");
        std::os::unix::fs::symlink(&fifo, &link).expect("symlink");
        for path in [&fifo, &link] {
            let err = write_atomically(path, b"x").expect_err("a FIFO is not a regular file");
            assert!(err.to_string().contains("FIFO"), "{err}");
            assert!(
                std::fs::metadata(&fifo)
                    .expect("still there")
                    .file_type()
                    .is_fifo()
            );
        }
        assert!(
            std::fs::symlink_metadata(&link)
                .expect("link")
                .file_type()
                .is_symlink()
        );
        let err = write_atomically(&dir, b"x").expect_err("a folder");
        assert!(err.to_string().contains("folder"), "{err}");
        assert_eq!(
            std::fs::read_dir(&dir).expect("dir").count(),
            2,
            "no temporary left"
        );
        std::fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn a_link_to_a_regular_file_is_followed_and_kept() {
        let dir = scratch_dir("link");
        let target = dir.join("real.txt");
        std::fs::write(&target, b"old").expect("write");
        let link = dir.join("link.txt");
        std::os::unix::fs::symlink(&target, &link).expect("symlink");
        write_atomically(&link, b"new").expect("written through the link");
        assert_eq!(std::fs::read(&target).expect("read"), b"new");
        assert!(
            std::fs::symlink_metadata(&link)
                .expect("link")
                .file_type()
                .is_symlink()
        );
        let dangling = dir.join("dangling");
        std::os::unix::fs::symlink(dir.join("nowhere"), &dangling).expect("symlink");
        assert!(write_atomically(&dangling, b"x").is_err());
        std::fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn temporary_files_of_killed_writers_are_removed_and_live_ones_kept() {
        let dir = scratch_dir("stale");
        let path = dir.join("map.oeg");
        // No process has pid 4294967295; this process is alive.
        let stale = dir.join("map.oeg.4294967295.0.tmp");
        let live = dir.join(format!("map.oeg.{}.99.tmp", std::process::id()));
        let other = dir.join("notes.4294967295.0.tmp");
        for p in [&stale, &live, &other] {
            std::fs::write(p, b"partial").expect("write");
        }
        write_atomically(&path, b"map").expect("written");
        if Path::new("/proc/self").exists() {
            assert!(!stale.exists(), "a dead writer's temporary file is removed");
        }
        assert!(
            live.exists() && other.exists(),
            "only this path's dead temporaries go"
        );
        std::fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn huge_and_tiny_quaternions_keep_their_rotation() {
        let expected =
            nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(0.5, 0.5, 0.5, 0.5));
        for scale in [1e200, 1e-200, 1.0, f64::MAX / 2.0] {
            let q = unit_quaternion(0.5 * scale, 0.5 * scale, 0.5 * scale, 0.5 * scale).expect("a rotation");
            assert!(q.angle_to(&expected) < 1e-12, "scale {scale}: {q:?}");
        }
        assert!(unit_quaternion(0.0, 0.0, 0.0, 0.0).is_none());
        assert!(unit_quaternion(f64::INFINITY, 0.0, 0.0, 0.0).is_none());
        assert!(unit_quaternion(f64::NAN, 1.0, 0.0, 0.0).is_none());
    }

    #[test]
    fn truncation_errors_name_the_file_and_offset() {
        let path = Path::new("some/file.bin");
        let mut r = ByteReader::new(path, &[1, 0, 0]);
        let err = r.u32("the node count").expect_err("truncated");
        let text = err.to_string();
        assert!(
            text.contains("some/file.bin") && text.contains("byte 0") && text.contains("node count"),
            "{text}"
        );
    }
}
