//! Inputs read within a bound, and a reader of binary files that names the file and the byte.

use std::path::Path;

use crate::error::{FileError, Result};

/// The largest text input the programs read: a scenario, a sweep file, a sweep's base scenario, a robot's
/// URDF. The largest shipped one is a few kilobytes; 16 MiB holds hundreds of thousands of waypoints.
pub const MAX_TEXT_INPUT_BYTES: u64 = 16 << 20;

/// Reads a whole file of at most `limit` bytes. A larger regular file is refused from its size before a
/// byte is read; a device or a pipe (`/dev/zero`), whose size is unknown, as soon as it passes `limit`.
///
/// # Errors
/// [`FileError::Io`] naming the file: it cannot be read, or it is larger than `limit` (kind
/// [`std::io::ErrorKind::FileTooLarge`]).
pub fn read_bounded(path: &Path, limit: u64) -> Result<Vec<u8>> {
    use std::io::Read as _;
    let too_large = |size: String| {
        FileError::io(
            path,
            std::io::Error::new(
                std::io::ErrorKind::FileTooLarge,
                format!("is {size}, over the limit of {limit} bytes for this input; is it the right file?"),
            ),
        )
    };
    let file = std::fs::File::open(path).map_err(|e| FileError::io(path, e))?;
    let meta = file.metadata().map_err(|e| FileError::io(path, e))?;
    if meta.is_dir() {
        return Err(FileError::io(
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
        .map_err(|e| FileError::io(path, e))?;
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
        FileError::parse(
            path,
            format!(
                "byte {}: not UTF-8 text; expected a text file",
                e.utf8_error().valid_up_to()
            ),
        )
    })
}

/// A little-endian reader over a file's bytes that names the file and byte offset in its errors.
pub struct ByteReader<'a> {
    path: &'a Path,
    data: &'a [u8],
    pos: usize,
}

impl<'a> ByteReader<'a> {
    /// A reader of `data`, the bytes of the file at `path`, from its first byte.
    #[inline]
    pub fn new(path: &'a Path, data: &'a [u8]) -> Self {
        Self { path, data, pos: 0 }
    }

    /// The offset of the next byte.
    #[inline]
    pub fn pos(&self) -> usize {
        self.pos
    }

    /// The bytes left.
    #[inline]
    pub fn remaining(&self) -> usize {
        self.data.len() - self.pos
    }

    /// A parse error at the reader's position: the file, the byte and `message`, as the caller's error.
    pub fn error<E: From<FileError>>(&self, message: impl std::fmt::Display) -> E {
        self.error_at(self.pos, message)
    }

    /// A parse error at byte `at`.
    pub fn error_at<E: From<FileError>>(&self, at: usize, message: impl std::fmt::Display) -> E {
        FileError::parse(self.path, format!("at byte {at}: {message}")).into()
    }

    /// The next `n` bytes, or an error naming `what` they were to hold when the file ends first.
    pub fn take(&mut self, n: usize, what: impl std::fmt::Display) -> Result<&'a [u8]> {
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

    /// The next `N` bytes, as [`ByteReader::take`].
    pub fn array<const N: usize>(&mut self, what: impl std::fmt::Display) -> Result<[u8; N]> {
        let s = self.take(N, what)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }

    /// A little-endian `u32`.
    pub fn u32(&mut self, what: impl std::fmt::Display) -> Result<u32> {
        self.array(what).map(u32::from_le_bytes)
    }

    /// A little-endian `i32`.
    pub fn i32(&mut self, what: impl std::fmt::Display) -> Result<i32> {
        self.array(what).map(i32::from_le_bytes)
    }

    /// A little-endian `f64`.
    pub fn f64(&mut self, what: impl std::fmt::Display) -> Result<f64> {
        self.array(what).map(f64::from_le_bytes)
    }

    /// A little-endian `f32`.
    pub fn f32(&mut self, what: impl std::fmt::Display) -> Result<f32> {
        self.array(what).map(f32::from_le_bytes)
    }
}
