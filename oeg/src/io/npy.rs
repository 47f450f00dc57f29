//! NumPy's `.npy` format, version 1.0 (numpy's `format.py`, NEP 1): a magic string, a header that is a
//! Python dict literal (`descr`, `fortran_order`, `shape`) padded with spaces to a multiple of 64 bytes and
//! ending in a newline, then the data in C order. `numpy.load` reads what this writes; the reader takes back
//! the two element types written here, so the testbed's own tests and tools need no Python.

use std::path::Path;

use crate::error::{Error, Result};

const MAGIC: &[u8] = b"\x93NUMPY";

/// The elements of an array.
#[derive(Debug, Clone, PartialEq)]
pub enum NpyData {
    /// Little-endian 32-bit floats (`<f4`).
    F32(Vec<f32>),
    /// Unsigned bytes (`|u1`).
    U8(Vec<u8>),
}

impl NpyData {
    fn descr(&self) -> &'static str {
        match self {
            Self::F32(_) => "<f4",
            Self::U8(_) => "|u1",
        }
    }

    fn len(&self) -> usize {
        match self {
            Self::F32(v) => v.len(),
            Self::U8(v) => v.len(),
        }
    }
}

/// A 2D array: `rows` x `cols`, row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct NpyArray {
    /// Number of rows.
    pub rows: usize,
    /// Number of columns.
    pub cols: usize,
    /// `rows * cols` elements, row-major.
    pub data: NpyData,
}

impl NpyArray {
    /// The `.npy` bytes of the array.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] when the data does not hold `rows * cols` elements.
    pub fn to_bytes(&self) -> Result<Vec<u8>> {
        if self.rows.checked_mul(self.cols) != Some(self.data.len()) {
            return Err(Error::setting(
                "npy",
                format!(
                    "{} elements for a {} x {} array",
                    self.data.len(),
                    self.rows,
                    self.cols
                ),
            ));
        }
        let dict = format!(
            "{{'descr': '{}', 'fortran_order': False, 'shape': ({}, {}), }}",
            self.data.descr(),
            self.rows,
            self.cols
        );
        // Magic (6) + version (2) + header length (2) + dict + padding + newline: a multiple of 64.
        let unpadded = MAGIC.len() + 4 + dict.len() + 1;
        let padding = (64 - unpadded % 64) % 64;
        let header_len = dict.len() + padding + 1;
        let mut out = Vec::with_capacity(unpadded + padding + self.data.len() * 4);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&[1, 0]);
        out.extend_from_slice(&(header_len as u16).to_le_bytes());
        out.extend_from_slice(dict.as_bytes());
        out.extend(std::iter::repeat_n(b' ', padding));
        out.push(b'\n');
        match &self.data {
            NpyData::F32(v) => v.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
            NpyData::U8(v) => out.extend_from_slice(v),
        }
        Ok(out)
    }

    /// Reads a 2D `<f4` or `|u1` array in C order from the bytes of `path` (named in errors).
    ///
    /// # Errors
    /// [`Error::Parse`] naming the file and what was expected: a wrong magic or version, a header that is
    /// not the dict written here, another element type, Fortran order, or a data size that does not match.
    pub fn from_bytes(path: &Path, bytes: &[u8]) -> Result<Self> {
        let fail = |what: String| Error::parse(path, what);
        if bytes.len() < 10 || &bytes[..6] != MAGIC {
            return Err(fail(
                "not a .npy file: expected the magic \\x93NUMPY at byte 0".into(),
            ));
        }
        if bytes[6] != 1 {
            return Err(fail(format!(
                "npy version {}.{}, expected 1.0",
                bytes[6], bytes[7]
            )));
        }
        let header_len = usize::from(u16::from_le_bytes([bytes[8], bytes[9]]));
        let header = bytes
            .get(10..10 + header_len)
            .and_then(|h| std::str::from_utf8(h).ok())
            .ok_or_else(|| {
                fail(format!(
                    "the header of {header_len} bytes is truncated or not text"
                ))
            })?;
        let field = |key: &str| -> Option<&str> {
            let start = header.find(&format!("'{key}':"))? + key.len() + 3;
            Some(header[start..].trim_start())
        };
        let descr = field("descr")
            .and_then(|v| v.strip_prefix('\''))
            .and_then(|v| v.split('\'').next())
            .ok_or_else(|| fail("the header has no 'descr'".into()))?;
        if !field("fortran_order").is_some_and(|v| v.starts_with("False")) {
            return Err(fail("expected 'fortran_order': False".into()));
        }
        let shape: Vec<usize> = field("shape")
            .and_then(|v| v.strip_prefix('('))
            .and_then(|v| v.split(')').next())
            .map(|v| {
                v.split(',')
                    .map(str::trim)
                    .filter(|s| !s.is_empty())
                    .map(str::parse)
                    .collect()
            })
            .transpose()
            .ok()
            .flatten()
            .ok_or_else(|| fail("the header's 'shape' is not a tuple of sizes".into()))?;
        let [rows, cols] = shape[..] else {
            return Err(fail(format!("expected a 2D array, the shape is {shape:?}")));
        };
        let body = &bytes[10 + header_len..];
        let n = rows
            .checked_mul(cols)
            .ok_or_else(|| fail(format!("a shape of ({rows}, {cols}) is too large")))?;
        let size = |elem: usize| {
            (n.checked_mul(elem) == Some(body.len()))
                .then_some(())
                .ok_or_else(|| {
                    fail(format!(
                        "{} bytes of data for a ({rows}, {cols}) array of {elem}-byte elements",
                        body.len()
                    ))
                })
        };
        let data = match descr {
            "<f4" => {
                size(4)?;
                NpyData::F32(
                    body.chunks_exact(4)
                        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                        .collect(),
                )
            }
            "|u1" => {
                size(1)?;
                NpyData::U8(body.to_vec())
            }
            other => return Err(fail(format!("element type '{other}', expected '<f4' or '|u1'"))),
        };
        Ok(Self { rows, cols, data })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arrays_round_trip_with_an_aligned_header() {
        for array in [
            NpyArray {
                rows: 2,
                cols: 3,
                data: NpyData::F32(vec![0.0, 1.5, f32::NAN, -2.0, 3.0, 4.0]),
            },
            NpyArray {
                rows: 1,
                cols: 2,
                data: NpyData::U8(vec![7, 255]),
            },
        ] {
            let bytes = array.to_bytes().expect("bytes");
            let header_len = usize::from(u16::from_le_bytes([bytes[8], bytes[9]]));
            assert_eq!((10 + header_len) % 64, 0);
            assert_eq!(bytes[9 + header_len], b'\n');
            let back = NpyArray::from_bytes(Path::new("a.npy"), &bytes).expect("reads");
            assert_eq!((back.rows, back.cols), (array.rows, array.cols));
            match (&back.data, &array.data) {
                (NpyData::F32(a), NpyData::F32(b)) => {
                    assert!(a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()));
                }
                (a, b) => assert_eq!(a, b),
            }
        }
    }

    #[test]
    fn broken_files_name_what_is_wrong() {
        let good = NpyArray {
            rows: 2,
            cols: 2,
            data: NpyData::F32(vec![1.0; 4]),
        }
        .to_bytes()
        .expect("bytes");
        let p = Path::new("layer.npy");
        let truncated = NpyArray::from_bytes(p, &good[..good.len() - 1]).expect_err("short");
        assert!(truncated.to_string().contains("layer.npy") && truncated.to_string().contains("15 bytes"));
        let e = NpyArray::from_bytes(p, b"PK\x03\x04 not numpy").expect_err("magic");
        assert!(e.to_string().contains("magic"), "{e}");
        let mismatched = NpyArray {
            rows: 3,
            cols: 3,
            data: NpyData::U8(vec![0; 4]),
        };
        assert!(mismatched.to_bytes().is_err());
    }
}
