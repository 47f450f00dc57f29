//! LZF, the compression of PCD's `binary_compressed` (Marc Lehmann's liblzf format).
//!
//! A control byte `c` either starts a literal run (`c < 32`: copy the next `c + 1` bytes) or a back-reference
//! of length `(c >> 5) + 2` (7 means "add the next byte") at distance `((c & 31) << 8) + next byte + 1`.

/// The most bytes one input byte can expand to: a three-byte back-reference copies at most 264 bytes.
pub(crate) const MAX_EXPANSION: usize = 88;

/// Decompresses `input`, which must expand to exactly `expected_len` bytes. A length that no input of this size
/// can expand to ([`MAX_EXPANSION`] times) is refused before anything is allocated.
pub(crate) fn decompress(input: &[u8], expected_len: usize) -> Result<Vec<u8>, String> {
    if expected_len > input.len().saturating_mul(MAX_EXPANSION) {
        return Err(format!(
            "{} compressed bytes cannot expand to the declared {expected_len} (at most {MAX_EXPANSION} times \
             as many)",
            input.len()
        ));
    }
    let mut out = Vec::with_capacity(expected_len);
    let mut i = 0;
    while i < input.len() {
        let ctrl = usize::from(input[i]);
        i += 1;
        if ctrl < 32 {
            let n = ctrl + 1;
            let run = input
                .get(i..i + n)
                .ok_or_else(|| format!("literal run at byte {} runs past the end", i - 1))?;
            if out.len() + n > expected_len {
                return Err(format!("data expands beyond the declared {expected_len} bytes"));
            }
            out.extend_from_slice(run);
            i += n;
        } else {
            let mut len = ctrl >> 5;
            if len == 7 {
                len += usize::from(*input.get(i).ok_or("back-reference length runs past the end")?);
                i += 1;
            }
            len += 2;
            let low = usize::from(*input.get(i).ok_or("back-reference offset runs past the end")?);
            i += 1;
            let distance = ((ctrl & 0x1f) << 8) + low + 1;
            if distance > out.len() {
                return Err(format!(
                    "back-reference at byte {} points before the start",
                    i - 2
                ));
            }
            if out.len() + len > expected_len {
                return Err(format!("data expands beyond the declared {expected_len} bytes"));
            }
            let start = out.len() - distance;
            // Byte by byte: the source may overlap what is being written (run-length encoding).
            for k in 0..len {
                let b = out[start + k];
                out.push(b);
            }
        }
    }
    if out.len() != expected_len {
        return Err(format!(
            "data expands to {} bytes, the header declares {expected_len}",
            out.len()
        ));
    }
    Ok(out)
}

/// Compresses `input` with a small hash-table matcher. Valid LZF for any decoder.
pub(crate) fn compress(input: &[u8]) -> Vec<u8> {
    const HASH_BITS: u32 = 14;
    const MAX_DISTANCE: usize = 1 << 13;
    const MAX_LEN: usize = 264;
    let mut out = Vec::with_capacity(input.len() + input.len() / 16 + 8);
    let mut table = vec![usize::MAX; 1 << HASH_BITS];
    let mut literals: Vec<u8> = Vec::with_capacity(32);
    let flush = |out: &mut Vec<u8>, literals: &mut Vec<u8>| {
        for chunk in literals.chunks(32) {
            out.push((chunk.len() - 1) as u8);
            out.extend_from_slice(chunk);
        }
        literals.clear();
    };
    let mut i = 0;
    while i < input.len() {
        if i + 3 <= input.len() {
            let key = u32::from(input[i]) << 16 | u32::from(input[i + 1]) << 8 | u32::from(input[i + 2]);
            let h = (key.wrapping_mul(2_654_435_761) >> (32 - HASH_BITS)) as usize;
            let candidate = table[h];
            table[h] = i;
            if candidate != usize::MAX
                && i - candidate <= MAX_DISTANCE
                && input[candidate..candidate + 3] == input[i..i + 3]
            {
                let mut len = 3;
                while len < MAX_LEN && i + len < input.len() && input[candidate + len] == input[i + len] {
                    len += 1;
                }
                flush(&mut out, &mut literals);
                let distance = i - candidate - 1;
                let l = len - 2;
                if l < 7 {
                    out.push(((l << 5) | (distance >> 8)) as u8);
                } else {
                    out.push(((7 << 5) | (distance >> 8)) as u8);
                    out.push((l - 7) as u8);
                }
                out.push((distance & 0xff) as u8);
                i += len;
                continue;
            }
        }
        literals.push(input[i]);
        i += 1;
    }
    flush(&mut out, &mut literals);
    out
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    #[test]
    fn a_declared_size_no_input_can_expand_to_is_refused_before_allocating() {
        // The 4 GiB of a 268 M-point cloud from 300 bytes.
        let err = decompress(&[0u8; 300], 4 << 30).expect_err("impossible expansion");
        assert!(err.contains("cannot expand"), "{err}");
        // The most compressible input there is: one literal, then maximal back-references of 264 bytes.
        let mut input = vec![0u8, 7];
        for _ in 0..100 {
            input.extend_from_slice(&[0xe0, 255, 0]);
        }
        let out = decompress(&input, 1 + 100 * 264).expect("exactly the maximal expansion");
        assert!(out.iter().all(|&b| b == 7));
        assert!(out.len() <= input.len() * MAX_EXPANSION);
    }

    #[test]
    fn a_hand_made_stream_with_a_back_reference_decodes() {
        // "abc" as a literal run, then a back-reference of length 6 at distance 3: "abcabcabc".
        let stream = [2, b'a', b'b', b'c', (4 << 5), 2];
        assert_eq!(decompress(&stream, 9).expect("valid"), b"abcabcabc");
    }

    #[test]
    fn corrupt_streams_are_errors() {
        assert!(decompress(&[5, b'a'], 6).is_err());
        assert!(decompress(&[(1 << 5), 0], 3).is_err());
        assert!(decompress(&[0, b'a'], 2).is_err());
    }

    proptest! {
        #[test]
        fn compress_then_decompress_is_the_identity(data in prop::collection::vec(0u8..4, 0..3000)) {
            let packed = compress(&data);
            prop_assert_eq!(decompress(&packed, data.len()).expect("valid"), data);
        }
    }
}
