//! NumPy's `.npy` format, version 1.0 (numpy's `format.py`, NEP 1): a magic string, a header that is a
//! Python dict literal (`descr`, `fortran_order`, `shape`) padded with spaces to a multiple of 64 bytes and
//! ending in a newline, then the data in C order. `numpy.load` reads what this writes. The reader takes what
//! `numpy.save` writes for a 2D array of floats, integers or booleans, in C or Fortran order and either byte
//! order, so a map made by another tool can be scored (`oeg score`) without Python.

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
    /// 64-bit floats (`<f8`; read from `f8` of either byte order).
    F64(Vec<f64>),
    /// Integers (`<i8`; read from every other integer type, and from booleans as 0 and 1).
    I64(Vec<i64>),
}

impl NpyData {
    /// The type as numpy names it: `float32`, `uint8`, `float64` or `int64`.
    pub fn dtype(&self) -> &'static str {
        match self {
            Self::F32(_) => "float32",
            Self::U8(_) => "uint8",
            Self::F64(_) => "float64",
            Self::I64(_) => "int64",
        }
    }

    fn descr(&self) -> &'static str {
        match self {
            Self::F32(_) => "<f4",
            Self::U8(_) => "|u1",
            Self::F64(_) => "<f8",
            Self::I64(_) => "<i8",
        }
    }

    fn len(&self) -> usize {
        match self {
            Self::F32(v) => v.len(),
            Self::U8(v) => v.len(),
            Self::F64(v) => v.len(),
            Self::I64(v) => v.len(),
        }
    }

    /// The elements as `f64` (integers exactly up to 2^53).
    pub fn to_f64(&self) -> Vec<f64> {
        match self {
            Self::F32(v) => v.iter().map(|x| f64::from(*x)).collect(),
            Self::U8(v) => v.iter().map(|x| f64::from(*x)).collect(),
            Self::F64(v) => v.clone(),
            Self::I64(v) => v.iter().map(|x| *x as f64).collect(),
        }
    }

    /// The elements as integers, or `None` for a float array.
    pub fn to_i64(&self) -> Option<Vec<i64>> {
        match self {
            Self::U8(v) => Some(v.iter().map(|x| i64::from(*x)).collect()),
            Self::I64(v) => Some(v.clone()),
            Self::F32(_) | Self::F64(_) => None,
        }
    }
}

/// An element type of a `.npy` header (`descr`): its kind, size and byte order.
#[derive(Debug, Clone, Copy)]
struct Element {
    kind: u8,
    size: usize,
    big_endian: bool,
}

impl Element {
    /// Parses `<f4`, `|u1`, `>i8`, `|b1` and the like; `None` for anything else (strings, objects,
    /// complex numbers, structured types).
    fn parse(descr: &str) -> Option<Self> {
        let b = descr.as_bytes();
        let [order, kind, ..] = *b else { return None };
        let size: usize = descr.get(2..)?.parse().ok()?;
        let big_endian = match order {
            b'<' | b'=' | b'|' => false,
            b'>' => true,
            _ => return None,
        };
        let known = matches!(
            (kind, size),
            (b'f', 4 | 8) | (b'i' | b'u', 1 | 2 | 4 | 8) | (b'b', 1)
        );
        known.then_some(Self {
            kind,
            size,
            big_endian,
        })
    }

    /// The elements of `body`, whose length is a multiple of the size.
    fn decode(self, body: &[u8]) -> std::result::Result<NpyData, String> {
        let word = |c: &[u8]| {
            let mut w = [0u8; 8];
            if self.big_endian {
                w[8 - c.len()..].copy_from_slice(c);
                u64::from_be_bytes(w)
            } else {
                w[..c.len()].copy_from_slice(c);
                u64::from_le_bytes(w)
            }
        };
        let words = body.chunks_exact(self.size).map(word);
        let bits = (self.size * 8) as u32;
        Ok(match (self.kind, self.size) {
            (b'u', 1) => NpyData::U8(body.to_vec()),
            (b'f', 4) => NpyData::F32(words.map(|w| f32::from_bits(w as u32)).collect()),
            (b'f', _) => NpyData::F64(words.map(f64::from_bits).collect()),
            (b'b', _) => NpyData::I64(words.map(|w| i64::from(w != 0)).collect()),
            (b'i', _) => NpyData::I64(
                // Sign-extend from the element's width.
                words
                    .map(|w| ((w << (64 - bits)) as i64) >> (64 - bits))
                    .collect(),
            ),
            _ => NpyData::I64(
                words
                    .map(|w| i64::try_from(w).map_err(|_| format!("the unsigned value {w} is too large")))
                    .collect::<std::result::Result<_, _>>()?,
            ),
        })
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
        let mut out = Vec::with_capacity(unpadded + padding + self.data.len() * 8);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&[1, 0]);
        out.extend_from_slice(&(header_len as u16).to_le_bytes());
        out.extend_from_slice(dict.as_bytes());
        out.extend(std::iter::repeat_n(b' ', padding));
        out.push(b'\n');
        match &self.data {
            NpyData::F32(v) => v.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
            NpyData::U8(v) => out.extend_from_slice(v),
            NpyData::F64(v) => v.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
            NpyData::I64(v) => v.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        }
        Ok(out)
    }

    /// Reads a 2D array from the bytes of `path` (named in errors): floats (`f4`, `f8`), integers (`i1` to
    /// `i8`, `u1` to `u8`) or booleans (`b1`), little- or big-endian, in C or Fortran order, in `.npy` version
    /// 1.0, 2.0 or 3.0. Fortran order is turned into C order. `|u1` stays bytes, `f4` stays `f32`, other
    /// floats are `f64` and other integers `i64` ([`NpyData`]).
    ///
    /// # Errors
    /// [`Error::Parse`] naming the file and what was expected: a wrong magic or version, a header that is
    /// not a `.npy` dict, another element type, a shape that is not 2D, or a data size that does not match.
    pub fn from_bytes(path: &Path, bytes: &[u8]) -> Result<Self> {
        let fail = |what: String| Error::parse(path, what);
        if bytes.len() < 10 || &bytes[..6] != MAGIC {
            return Err(fail(
                "not a .npy file: expected the magic \\x93NUMPY at byte 0".into(),
            ));
        }
        let (header_len, start): (usize, usize) = match bytes[6] {
            1 => (usize::from(u16::from_le_bytes([bytes[8], bytes[9]])), 10),
            2 | 3 if bytes.len() >= 12 => (
                u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
                12,
            ),
            major => {
                return Err(fail(format!(
                    "npy version {major}.{}, expected 1.0, 2.0 or 3.0",
                    bytes[7]
                )));
            }
        };
        let header = start
            .checked_add(header_len)
            .and_then(|end| bytes.get(start..end))
            .and_then(|h| std::str::from_utf8(h).ok())
            .ok_or_else(|| {
                fail(format!(
                    "the header of {header_len} bytes is truncated or not text"
                ))
            })?;
        let dict = HeaderDict::parse(header).map_err(|e| fail(format!("the header {e}")))?;
        let descr = dict.descr.as_str();
        let element = Element::parse(descr).ok_or_else(|| {
            fail(format!(
                "element type '{descr}', expected floats ('<f4', '<f8'), integers ('|u1', '<i8', ...) or \
                 booleans ('|b1')"
            ))
        })?;
        let (fortran, shape) = (dict.fortran_order, dict.shape);
        let [rows, cols] = shape[..] else {
            return Err(fail(format!(
                "expected a 2D array (rows, columns), the shape is {shape:?}"
            )));
        };
        let body = &bytes[start + header_len..];
        let n = rows
            .checked_mul(cols)
            .ok_or_else(|| fail(format!("a shape of ({rows}, {cols}) is too large")))?;
        if n.checked_mul(element.size) != Some(body.len()) {
            return Err(fail(format!(
                "{} bytes of data for a ({rows}, {cols}) array of {}-byte elements",
                body.len(),
                element.size
            )));
        }
        let data = element.decode(body).map_err(fail)?;
        let data = if fortran && rows > 1 && cols > 1 {
            transpose(data, rows, cols)
        } else {
            data
        };
        Ok(Self { rows, cols, data })
    }
}

/// The header's dict literal, as numpy reads it (`ast.literal_eval`, then exactly the keys `descr`,
/// `fortran_order` and `shape`): `{'descr': '<f4', 'fortran_order': False, 'shape': (3, 4), }`.
struct HeaderDict {
    descr: String,
    fortran_order: bool,
    shape: Vec<usize>,
}

/// A value of the header's dict.
enum HeaderValue {
    Str(String),
    Bool(bool),
    Tuple(Vec<usize>),
}

impl HeaderDict {
    /// Parses `text` as a Python dict literal of strings, booleans and tuples of sizes, with exactly the three
    /// keys; the error says what was expected and where (a character offset).
    fn parse(text: &str) -> std::result::Result<Self, String> {
        let mut p = Literal {
            text: text.as_bytes(),
            at: 0,
        };
        p.expect(b'{')?;
        let (mut descr, mut fortran_order, mut shape) = (None, None, None);
        loop {
            p.skip_space();
            if p.eat(b'}') {
                break;
            }
            let key = p.string()?;
            p.skip_space();
            p.expect(b':')?;
            p.skip_space();
            let at = p.at;
            let value = p.value()?;
            let slot_taken = match (key.as_str(), value) {
                ("descr", HeaderValue::Str(v)) => descr.replace(v).is_some(),
                ("fortran_order", HeaderValue::Bool(v)) => fortran_order.replace(v).is_some(),
                ("shape", HeaderValue::Tuple(v)) => shape.replace(v).is_some(),
                ("descr" | "fortran_order" | "shape", _) => {
                    return Err(format!(
                        "has a '{key}' of the wrong kind at character {at}: expected a string for 'descr', \
                         True or False for 'fortran_order', a tuple of sizes for 'shape'"
                    ));
                }
                _ => {
                    return Err(format!(
                        "has the key {key:?}: expected exactly 'descr', 'fortran_order' and 'shape'"
                    ));
                }
            };
            if slot_taken {
                return Err(format!("has the key '{key}' twice"));
            }
            p.skip_space();
            if !p.eat(b',') {
                p.skip_space();
                p.expect(b'}')?;
                break;
            }
        }
        p.skip_space();
        if p.at != p.text.len() {
            return Err(format!("has text after its dict at character {}", p.at));
        }
        match (descr, fortran_order, shape) {
            (Some(descr), Some(fortran_order), Some(shape)) => Ok(Self {
                descr,
                fortran_order,
                shape,
            }),
            _ => Err("lacks a key: expected exactly 'descr', 'fortran_order' and 'shape'".into()),
        }
    }
}

/// A cursor over a Python literal's bytes.
struct Literal<'a> {
    text: &'a [u8],
    at: usize,
}

impl Literal<'_> {
    fn skip_space(&mut self) {
        while self
            .text
            .get(self.at)
            .is_some_and(|c| matches!(c, b' ' | b'\t' | b'\n' | b'\r'))
        {
            self.at += 1;
        }
    }

    fn eat(&mut self, c: u8) -> bool {
        let found = self.text.get(self.at) == Some(&c);
        self.at += usize::from(found);
        found
    }

    fn expect(&mut self, c: u8) -> std::result::Result<(), String> {
        self.skip_space();
        if self.eat(c) {
            Ok(())
        } else {
            Err(format!(
                "is not a .npy dict: expected '{}' at character {}",
                char::from(c),
                self.at
            ))
        }
    }

    /// A quoted string without escapes (numpy's keys and type codes have none).
    fn string(&mut self) -> std::result::Result<String, String> {
        let start = self.at;
        let quote = match self.text.get(self.at) {
            Some(&q @ (b'\'' | b'"')) => q,
            _ => {
                return Err(format!(
                    "is not a .npy dict: expected a quoted key at character {start}"
                ));
            }
        };
        self.at += 1;
        let end = self.text[self.at..]
            .iter()
            .position(|&c| c == quote || c == b'\\' || c == b'\n')
            .map(|k| self.at + k)
            .filter(|&k| self.text[k] == quote)
            .ok_or_else(|| format!("has an unclosed or escaped string at character {start}"))?;
        let s = String::from_utf8_lossy(&self.text[self.at..end]).into_owned();
        self.at = end + 1;
        Ok(s)
    }

    fn value(&mut self) -> std::result::Result<HeaderValue, String> {
        let rest = &self.text[self.at..];
        if rest.starts_with(b"True") {
            self.at += 4;
            return Ok(HeaderValue::Bool(true));
        }
        if rest.starts_with(b"False") {
            self.at += 5;
            return Ok(HeaderValue::Bool(false));
        }
        match rest.first() {
            Some(b'\'' | b'"') => self.string().map(HeaderValue::Str),
            Some(b'(') => {
                self.at += 1;
                let mut sizes = Vec::new();
                let mut trailing_comma = false;
                loop {
                    self.skip_space();
                    if self.eat(b')') {
                        break;
                    }
                    sizes.push(self.size()?);
                    self.skip_space();
                    trailing_comma = self.eat(b',');
                    if !trailing_comma {
                        self.expect(b')')?;
                        break;
                    }
                }
                // `(5)` is the number 5 in Python, not a tuple.
                if sizes.len() == 1 && !trailing_comma {
                    return Err("has a 'shape' that is a number in parentheses, not a tuple".into());
                }
                Ok(HeaderValue::Tuple(sizes))
            }
            _ => Err(format!(
                "has a value at character {} that is not a string, True, False or a tuple",
                self.at
            )),
        }
    }

    /// A size: decimal digits, no leading zero (as Python writes an `int`).
    fn size(&mut self) -> std::result::Result<usize, String> {
        let start = self.at;
        while self.text.get(self.at).is_some_and(u8::is_ascii_digit) {
            self.at += 1;
        }
        let digits = std::str::from_utf8(&self.text[start..self.at]).unwrap_or("");
        if digits.is_empty() || (digits.len() > 1 && digits.starts_with('0')) {
            return Err(format!(
                "has a 'shape' entry at character {start} that is not a size"
            ));
        }
        digits
            .parse()
            .map_err(|_| format!("has a 'shape' entry at character {start} too large for this machine"))
    }
}

/// The C-order elements of a `rows` x `cols` array given in Fortran (column-major) order.
fn transpose(data: NpyData, rows: usize, cols: usize) -> NpyData {
    fn t<T: Copy>(v: &[T], rows: usize, cols: usize) -> Vec<T> {
        (0..rows)
            .flat_map(|r| (0..cols).map(move |c| v[c * rows + r]))
            .collect()
    }
    match data {
        NpyData::F32(v) => NpyData::F32(t(&v, rows, cols)),
        NpyData::U8(v) => NpyData::U8(t(&v, rows, cols)),
        NpyData::F64(v) => NpyData::F64(t(&v, rows, cols)),
        NpyData::I64(v) => NpyData::I64(t(&v, rows, cols)),
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

    /// A `.npy` file with the given header fields and body, as `numpy.save` lays it out.
    fn npy(version: u8, descr: &str, fortran: bool, shape: &str, body: &[u8]) -> Vec<u8> {
        let dict = format!(
            "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}\n",
            if fortran { "True" } else { "False" }
        );
        let mut out = MAGIC.to_vec();
        out.extend_from_slice(&[version, 0]);
        if version == 1 {
            out.extend_from_slice(&(dict.len() as u16).to_le_bytes());
        } else {
            out.extend_from_slice(&(dict.len() as u32).to_le_bytes());
        }
        out.extend_from_slice(dict.as_bytes());
        out.extend_from_slice(body);
        out
    }

    #[test]
    fn what_numpy_save_writes_is_read_in_c_order() {
        let p = Path::new("user.npy");
        // float64, Fortran order: the array [[1, 2, 3], [4, 5, 6]] is stored by columns.
        let body: Vec<u8> = [1.0f64, 4.0, 2.0, 5.0, 3.0, 6.0]
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let a = NpyArray::from_bytes(p, &npy(1, "<f8", true, "(2, 3)", &body)).expect("f8");
        assert_eq!((a.rows, a.cols), (2, 3));
        assert_eq!(a.data, NpyData::F64(vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]));
        // Big-endian int16 with negative values, version 2.0.
        let body: Vec<u8> = [-3i16, 0, 4, 32767]
            .iter()
            .flat_map(|x| x.to_be_bytes())
            .collect();
        let a = NpyArray::from_bytes(p, &npy(2, ">i2", false, "(2, 2)", &body)).expect("i2");
        assert_eq!(a.data, NpyData::I64(vec![-3, 0, 4, 32767]));
        assert_eq!(a.data.to_f64(), vec![-3.0, 0.0, 4.0, 32767.0]);
        // Booleans, and int64 (numpy's default for a list of ints).
        let a = NpyArray::from_bytes(p, &npy(1, "|b1", false, "(1, 3)", &[1, 0, 1])).expect("b1");
        assert_eq!(a.data.to_i64(), Some(vec![1, 0, 1]));
        let body: Vec<u8> = [3i64, 1].iter().flat_map(|x| x.to_le_bytes()).collect();
        let a = NpyArray::from_bytes(p, &npy(1, "<i8", false, "(2, 1)", &body)).expect("i8");
        assert_eq!(a.data, NpyData::I64(vec![3, 1]));
        // What is refused, by name.
        let e = NpyArray::from_bytes(p, &npy(1, "<U4", false, "(1, 1)", &[0; 16])).expect_err("text");
        assert!(
            e.to_string().contains("'<U4'") && e.to_string().contains("user.npy"),
            "{e}"
        );
        let e = NpyArray::from_bytes(p, &npy(1, "<f4", false, "(4,)", &[0; 16])).expect_err("1D");
        assert!(e.to_string().contains("2D"), "{e}");
        let big = u64::MAX.to_le_bytes();
        let e = NpyArray::from_bytes(p, &npy(1, "<u8", false, "(1, 1)", &big)).expect_err("u8");
        assert!(e.to_string().contains("too large"), "{e}");
        let e = NpyArray::from_bytes(p, &npy(9, "<f4", false, "(1, 1)", &[0; 4])).expect_err("version");
        assert!(e.to_string().contains("version 9.0"), "{e}");
        let e =
            NpyArray::from_bytes(p, &npy(1, "<f4", false, "(1000000, 1000000)", &[0; 4])).expect_err("size");
        assert!(e.to_string().contains("4 bytes of data"), "{e}");
        // What is written reads back, for the new types too.
        for data in [NpyData::F64(vec![0.5, -1.0]), NpyData::I64(vec![-7, 9])] {
            let array = NpyArray {
                rows: 1,
                cols: 2,
                data,
            };
            let back = NpyArray::from_bytes(p, &array.to_bytes().expect("bytes")).expect("reads");
            assert_eq!(back, array);
        }
    }

    /// A version 1.0 file of four float32 ones with `dict` as its header.
    fn with_header(dict: &str) -> Vec<u8> {
        let mut out = MAGIC.to_vec();
        out.extend_from_slice(&[1, 0]);
        out.extend_from_slice(&(dict.len() as u16).to_le_bytes());
        out.extend_from_slice(dict.as_bytes());
        out.extend(std::iter::repeat_n(1.0f32.to_le_bytes(), 4).flatten());
        out
    }

    #[test]
    fn the_header_is_parsed_as_the_dict_literal_numpy_reads() {
        let p = Path::new("h.npy");
        // What numpy writes, and the same dict spelled otherwise, are read.
        for dict in [
            "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 2), }      \n",
            "{\"shape\": (2,2), \"fortran_order\": False, \"descr\": \"<f4\"}",
            "{ 'descr' : '<f4' ,\n 'fortran_order' : False , 'shape' : ( 2 , 2 , ) }",
        ] {
            let a = NpyArray::from_bytes(p, &with_header(dict)).unwrap_or_else(|e| panic!("{dict}: {e}"));
            assert_eq!((a.rows, a.cols), (2, 2), "{dict}");
        }
        // Headers numpy refuses are refused, each saying why (the first `'key':` text anywhere no longer counts).
        for (dict, why) in [
            (
                "{'note': \"'descr': '<f8', 'shape': (1, 2)\", 'descr': '<f4', 'fortran_order': False, 'shape': (2, 2)}",
                "has the key \"note\"",
            ),
            (
                "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 2), 'extra': True}",
                "has the key \"extra\"",
            ),
            ("{'descr': '<f4', 'fortran_order': False}", "lacks a key"),
            (
                "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 2), 'shape': (4, 1)}",
                "has the key 'shape' twice",
            ),
            (
                "{'descr': '<f4', 'fortran_order': 0, 'shape': (2, 2)}",
                "not a string, True, False",
            ),
            (
                "{'descr': '<f4', 'fortran_order': 'False', 'shape': (2, 2)}",
                "of the wrong kind",
            ),
            (
                "{'descr': '<f4', 'fortran_order': False, 'shape': (4)}",
                "not a tuple",
            ),
            (
                "{'descr': '<f4', 'fortran_order': False, 'shape': (02, 2)}",
                "not a size",
            ),
            (
                "{'descr': '<f4', 'fortran_order': False, 'shape': (-2, -2)}",
                "not a size",
            ),
            (
                "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 2)} # (1, 4)",
                "text after its dict",
            ),
            (
                "'descr': '<f4', 'fortran_order': False, 'shape': (2, 2)",
                "expected '{'",
            ),
            (
                "{'descr': '<f\\4', 'fortran_order': False, 'shape': (2, 2)}",
                "escaped string",
            ),
            (
                "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 2)",
                "expected '}'",
            ),
        ] {
            let e = NpyArray::from_bytes(p, &with_header(dict))
                .expect_err(dict)
                .to_string();
            assert!(e.contains("h.npy") && e.contains(why), "{dict}: {e}");
        }
    }
}
