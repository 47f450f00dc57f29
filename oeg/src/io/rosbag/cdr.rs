//! OMG CDR (XCDR1), the serialization of ROS 2 messages: a 4-byte encapsulation header (`00 01`: little-endian,
//! `00 00`: big-endian), then each primitive aligned to its own size counted from the end of the header, strings
//! as a `u32` length that counts their closing NUL, sequences as a `u32` count and their elements.
//!
//! The reader never allocates what a length in the message asks for before checking that the message holds
//! that many bytes, and names the field of every problem.

/// Where decoding stopped, and why: `field` is the message's field path (`data`, `fields[2].name`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct CdrError {
    pub(crate) field: String,
    pub(crate) message: String,
}

impl std::fmt::Display for CdrError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "field `{}`: {}", self.field, self.message)
    }
}

pub(crate) type CdrResult<T> = Result<T, CdrError>;

fn error(field: &str, message: impl Into<String>) -> CdrError {
    CdrError {
        field: field.to_string(),
        message: message.into(),
    }
}

/// A cursor over one serialized message.
pub(crate) struct CdrReader<'a> {
    body: &'a [u8],
    pos: usize,
    little_endian: bool,
}

impl<'a> CdrReader<'a> {
    /// The message `data`, its encapsulation header checked.
    pub(crate) fn new(data: &'a [u8]) -> CdrResult<Self> {
        let Some((header, body)) = data.split_first_chunk::<4>() else {
            return Err(error(
                "encapsulation header",
                format!(
                    "the message is {} bytes, shorter than CDR's 4-byte header",
                    data.len()
                ),
            ));
        };
        let little_endian = match header[..2] {
            [0, 1] => true,
            [0, 0] => false,
            _ => {
                return Err(error(
                    "encapsulation header",
                    format!(
                        "{:02x} {:02x} is not plain CDR (00 00: big-endian, 00 01: little-endian)",
                        header[0], header[1]
                    ),
                ));
            }
        };
        Ok(Self {
            body,
            pos: 0,
            little_endian,
        })
    }

    /// Bytes left after the cursor.
    pub(crate) fn remaining(&self) -> usize {
        self.body.len() - self.pos
    }

    fn take(&mut self, n: usize, align: usize, field: &str) -> CdrResult<&'a [u8]> {
        let start = self.pos.next_multiple_of(align);
        let end = start
            .checked_add(n)
            .filter(|&e| e <= self.body.len())
            .ok_or_else(|| {
                error(
                    field,
                    format!(
                        "needs {n} bytes at byte {} of the message body, which is {} bytes long (truncated?)",
                        start,
                        self.body.len()
                    ),
                )
            })?;
        self.pos = end;
        Ok(&self.body[start..end])
    }

    fn array<const N: usize>(&mut self, field: &str) -> CdrResult<[u8; N]> {
        let bytes = self.take(N, N, field)?;
        let mut out = [0u8; N];
        out.copy_from_slice(bytes);
        if !self.little_endian {
            out.reverse();
        }
        Ok(out)
    }

    pub(crate) fn u8(&mut self, field: &str) -> CdrResult<u8> {
        Ok(self.take(1, 1, field)?[0])
    }

    pub(crate) fn bool(&mut self, field: &str) -> CdrResult<bool> {
        match self.u8(field)? {
            0 => Ok(false),
            1 => Ok(true),
            b => Err(error(field, format!("a bool is 0 or 1, got {b}"))),
        }
    }

    pub(crate) fn u16(&mut self, field: &str) -> CdrResult<u16> {
        Ok(u16::from_le_bytes(self.array(field)?))
    }

    pub(crate) fn u32(&mut self, field: &str) -> CdrResult<u32> {
        Ok(u32::from_le_bytes(self.array(field)?))
    }

    pub(crate) fn i32(&mut self, field: &str) -> CdrResult<i32> {
        Ok(i32::from_le_bytes(self.array(field)?))
    }

    pub(crate) fn f32(&mut self, field: &str) -> CdrResult<f32> {
        Ok(f32::from_le_bytes(self.array(field)?))
    }

    pub(crate) fn f64(&mut self, field: &str) -> CdrResult<f64> {
        Ok(f64::from_le_bytes(self.array(field)?))
    }

    /// A sequence's element count, checked against the bytes left: each element takes at least
    /// `min_element_bytes`, so a lying count is refused before anything is allocated for it.
    pub(crate) fn sequence_len(&mut self, field: &str, min_element_bytes: usize) -> CdrResult<usize> {
        let n = self.u32(field)? as usize;
        if n.saturating_mul(min_element_bytes) > self.remaining() {
            return Err(error(
                field,
                format!(
                    "a count of {n} elements of at least {min_element_bytes} bytes, but only {} bytes are left",
                    self.remaining()
                ),
            ));
        }
        Ok(n)
    }

    /// A `float32[]` of at most `max` elements.
    pub(crate) fn f32s_within(&mut self, field: &str, max: u64) -> CdrResult<Vec<f32>> {
        let n = self.sequence_len(field, 4)?;
        if n as u64 > max {
            return Err(error(
                field,
                format!("{n} values, over the {max} this reader takes"),
            ));
        }
        (0..n).map(|_| self.f32(field)).collect()
    }

    pub(crate) fn string(&mut self, field: &str) -> CdrResult<String> {
        let n = self.sequence_len(field, 1)?;
        let bytes = self.take(n, 1, field)?;
        let text = match bytes.split_last() {
            Some((0, text)) => text,
            Some(_) => return Err(error(field, "a string that does not end in NUL")),
            // Some writers give an empty string a length of 0.
            None => &[],
        };
        String::from_utf8(text.to_vec()).map_err(|_| error(field, "a string that is not UTF-8"))
    }

    /// A `uint8[]` without copying it.
    pub(crate) fn bytes(&mut self, field: &str) -> CdrResult<&'a [u8]> {
        let n = self.sequence_len(field, 1)?;
        self.take(n, 1, field)
    }

    /// A `float32[]`.
    pub(crate) fn f32s(&mut self, field: &str) -> CdrResult<Vec<f32>> {
        self.f32s_within(field, u64::MAX)
    }
}

/// Writes one message, little-endian, its encapsulation header first.
pub(crate) struct CdrWriter {
    out: Vec<u8>,
}

impl CdrWriter {
    pub(crate) fn new() -> Self {
        Self {
            out: vec![0, 1, 0, 0],
        }
    }

    fn align(&mut self, n: usize) {
        let body = self.out.len() - 4;
        self.out.resize(4 + body.next_multiple_of(n), 0);
    }

    pub(crate) fn u8(&mut self, v: u8) {
        self.out.push(v);
    }

    pub(crate) fn bool(&mut self, v: bool) {
        self.out.push(u8::from(v));
    }

    pub(crate) fn u32(&mut self, v: u32) {
        self.align(4);
        self.out.extend_from_slice(&v.to_le_bytes());
    }

    pub(crate) fn i32(&mut self, v: i32) {
        self.align(4);
        self.out.extend_from_slice(&v.to_le_bytes());
    }

    pub(crate) fn f64(&mut self, v: f64) {
        self.align(8);
        self.out.extend_from_slice(&v.to_le_bytes());
    }

    /// A sequence's count (the caller writes the elements). Counts beyond `u32` do not fit CDR.
    pub(crate) fn len(&mut self, n: usize) {
        self.u32(u32::try_from(n).unwrap_or(u32::MAX));
    }

    pub(crate) fn u16(&mut self, v: u16) {
        self.align(2);
        self.out.extend_from_slice(&v.to_le_bytes());
    }

    pub(crate) fn f32(&mut self, v: f32) {
        self.align(4);
        self.out.extend_from_slice(&v.to_le_bytes());
    }

    /// A `float32[]`.
    pub(crate) fn f32s(&mut self, v: &[f32]) {
        self.len(v.len());
        for x in v {
            self.out.extend_from_slice(&x.to_le_bytes());
        }
    }

    pub(crate) fn string(&mut self, s: &str) {
        self.len(s.len() + 1);
        self.out.extend_from_slice(s.as_bytes());
        self.out.push(0);
    }

    pub(crate) fn bytes(&mut self, b: &[u8]) {
        self.len(b.len());
        self.out.extend_from_slice(b);
    }

    pub(crate) fn finish(self) -> Vec<u8> {
        self.out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primitives_are_aligned_from_the_end_of_the_header_and_read_back() {
        let mut w = CdrWriter::new();
        w.u8(7);
        w.f64(1.5);
        w.string("map");
        w.u32(9);
        let data = w.finish();
        // 4 header bytes, the u8, 7 bytes of padding, the f64.
        assert_eq!(data.len(), 4 + 8 + 8 + 4 + 4 + 4);
        let mut r = CdrReader::new(&data).expect("header");
        assert_eq!(r.u8("a"), Ok(7));
        assert_eq!(r.f64("b"), Ok(1.5));
        assert_eq!(r.string("c").as_deref(), Ok("map"));
        assert_eq!(r.u32("d"), Ok(9));
        assert_eq!(r.remaining(), 0);
    }

    #[test]
    fn big_endian_messages_read_too() {
        let data = [0, 0, 0, 0, 0, 0, 0, 5];
        let mut r = CdrReader::new(&data).expect("header");
        assert_eq!(r.u32("n"), Ok(5));
    }

    #[test]
    fn a_lying_count_or_a_truncated_message_names_its_field() {
        let mut w = CdrWriter::new();
        w.u32(1_000_000);
        let data = w.finish();
        let e = CdrReader::new(&data)
            .expect("header")
            .bytes("data")
            .expect_err("refused");
        assert_eq!(e.field, "data");
        assert!(e.message.contains("1000000"), "{e}");
        assert!(CdrReader::new(&[0, 1]).is_err());
        assert!(CdrReader::new(&[7, 7, 0, 0]).is_err());
        let e = CdrReader::new(&[0, 1, 0, 0, 2])
            .expect("header")
            .f64("x")
            .expect_err("refused");
        assert!(e.message.contains("truncated"), "{e}");
    }
}
