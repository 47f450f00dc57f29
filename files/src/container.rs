//! The framed binary container of the map file (`.oeg`) and the sensor log (`.oeglog`). Little-endian:
//!
//! ```text
//! offset  size  what
//! 0       8     magic (the format's; ends in "\r\n", which catches text-mode transfers)
//! 8       4     u32 format version
//! 12      4     u32 length H of the header
//! 16      H     header, UTF-8 JSON (the format's own)
//! 16+H    ...   body (the format's own records)
//! end-8   8     u64 FNV-1a-64 checksum of every byte before it ([`crate::fnv1a64`])
//! ```
//!
//! Both formats were version 1 with exactly this framing before it was shared, so their bytes are unchanged.
//! A change to either format's header or body is a new version, never a silent change: readers refuse a
//! version they do not know, naming it.

use std::path::Path;

use crate::error::Result;
use crate::{AtomicFile, ByteReader, Fnv1a64};

/// A container's prefix as read: the header's JSON and where the body starts.
#[derive(Debug)]
pub struct ContainerPrefix<'a> {
    /// The header's bytes (JSON).
    pub header: &'a [u8],
    /// Byte offset of the body.
    pub body_start: usize,
    /// The format version the file declares (one of those asked for).
    pub version: u32,
}

/// Reads the prefix of a container of `format` (its name for messages) with `magic` and one of the `versions`.
///
/// # Errors
/// [`crate::FileError::Parse`] naming the file and byte: a wrong magic number, another version, or a header
/// that runs past the end of the file.
pub fn read_container_prefix<'a>(
    path: &'a Path,
    data: &'a [u8],
    magic: &[u8; 8],
    versions: &[u32],
    format: &str,
) -> Result<ContainerPrefix<'a>> {
    let mut r = ByteReader::new(path, data);
    if r.take(8, "the magic number")? != magic {
        return Err(r.error_at(0, format!("not {format} (wrong magic number)")));
    }
    let found = r.u32("the format version")?;
    if !versions.contains(&found) {
        let known: Vec<String> = versions.iter().map(u32::to_string).collect();
        return Err(r.error_at(
            8,
            format!(
                "format version {found} is not supported (this build reads {})",
                known.join(" and ")
            ),
        ));
    }
    let header_len = r.u32("the header length")? as usize;
    let header = r.take(header_len, "the header")?;
    Ok(ContainerPrefix {
        header,
        body_start: r.pos(),
        version: found,
    })
}

/// Checks that `data` ends, right after `body_end`, in the checksum of every byte before it.
///
/// # Errors
/// [`crate::FileError::Parse`] naming the file and byte: a missing or short checksum, bytes after it, or a
/// mismatch.
pub fn check_container_checksum(path: &Path, data: &[u8], body_end: usize) -> Result<()> {
    let mut r = ByteReader::new(path, data);
    r.take(body_end, "the body")?;
    let stored = u64::from_le_bytes(r.array("the checksum")?);
    if r.remaining() != 0 {
        return Err(r.error("unexpected bytes after the checksum"));
    }
    if crate::fnv1a64(&data[..body_end]) != stored {
        return Err(r.error_at(body_end, "checksum mismatch: the file is corrupt"));
    }
    Ok(())
}

/// The prefix of a container: magic, version, header length and header.
pub fn container_prefix_bytes(magic: &[u8; 8], version: u32, header_json: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(16 + header_json.len());
    out.extend_from_slice(magic);
    out.extend_from_slice(&version.to_le_bytes());
    out.extend_from_slice(&(header_json.len() as u32).to_le_bytes());
    out.extend_from_slice(header_json);
    out
}

/// Appends the checksum of everything in `bytes` to it: the container is complete.
pub fn seal_container(bytes: &mut Vec<u8>) {
    let checksum = crate::fnv1a64(bytes);
    bytes.extend_from_slice(&checksum.to_le_bytes());
}

/// A container written as a stream, atomically ([`AtomicFile`]): the prefix at creation, the body piece by
/// piece, the checksum at [`FramedWriter::finish`].
#[derive(Debug)]
pub struct FramedWriter {
    file: AtomicFile,
    hash: Fnv1a64,
}

impl FramedWriter {
    /// Starts a container at `path`.
    ///
    /// # Errors
    /// As [`AtomicFile::create`].
    pub fn create(path: &Path, magic: &[u8; 8], version: u32, header_json: &[u8]) -> Result<Self> {
        let mut w = Self {
            file: AtomicFile::create(path)?,
            hash: Fnv1a64::new(),
        };
        w.write(&container_prefix_bytes(magic, version, header_json))?;
        Ok(w)
    }

    /// Appends body bytes.
    ///
    /// # Errors
    /// [`crate::FileError::Io`] naming the file.
    pub fn write(&mut self, bytes: &[u8]) -> Result<()> {
        self.hash.update(bytes);
        self.file.write_all(bytes)
    }

    /// Writes the checksum and moves the file into place.
    ///
    /// # Errors
    /// [`crate::FileError::Io`] naming the file.
    pub fn finish(mut self) -> Result<()> {
        let checksum = self.hash.value().to_le_bytes();
        self.file.write_all(&checksum)?;
        self.file.commit()
    }
}
