//! Reading real data into [`crate::Scan`]s, and saving and loading maps.
//!
//! * [`graph`]: OctoMap scan graphs (`.graph`), the format of OctoMap's published data sets;
//! * [`pcd`]: PCL point clouds (`.pcd`: ascii, binary, binary_compressed);
//! * [`mapfile`]: this crate's own map format (`.oeg`).
//!
//! Every reader checks sizes against the file before allocating, rejects non-finite numbers, and names the
//! file and the byte or line of the problem.

pub mod graph;
mod lzf;
pub mod mapfile;
pub mod pcd;

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Writes `bytes` to `path` atomically: to a temporary file beside it, then renamed over it, so a reader never
/// sees half a file and a failed write leaves no partial output.
///
/// # Errors
/// [`Error::Io`] naming the file.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = temporary_path(path);
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    result.map_err(|e| {
        // Best effort: the temporary file is ours and useless now.
        let _ = std::fs::remove_file(&tmp);
        Error::io(path, e)
    })
}

fn temporary_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().map(|n| n.to_os_string()).unwrap_or_default();
    name.push(format!(".{}.tmp", std::process::id()));
    path.with_file_name(name)
}

/// Reads a whole file, naming it on failure.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|e| Error::io(path, e))
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

    fn array<const N: usize>(&mut self, what: impl std::fmt::Display) -> Result<[u8; N]> {
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

/// FNV-1a, 64 bit: the map file's checksum. Not cryptographic; it catches truncation and bit rot.
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

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
