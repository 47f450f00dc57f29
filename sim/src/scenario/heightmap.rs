//! Height-map images a scenario's `[terrain]` refers to: 8- or 16-bit greyscale PNGs, checked from their
//! header before a pixel is decoded.

use std::path::{Path, PathBuf};

/// A height-map image that cannot be used: the file, and what is wrong with it.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}: {message}", path.display())]
pub struct HeightmapError {
    /// The image.
    pub path: PathBuf,
    /// What is wrong and what was expected.
    pub message: String,
}

fn error(path: &Path, message: String) -> HeightmapError {
    HeightmapError {
        path: path.to_path_buf(),
        message,
    }
}

/// Reads an 8- or 16-bit greyscale PNG as values in [0, 1], row 0 first. Returns (width, height, values).
///
/// # Errors
/// As [`decode_greyscale_png`], and a file that cannot be read.
pub fn read_greyscale_png(path: &Path) -> Result<(usize, usize, Vec<f64>), HeightmapError> {
    let bytes = oeg_files::read_bounded(path, MAX_TERRAIN_FILE_BYTES)
        .map_err(|e| error(path, format!("cannot open the terrain image: {e}")))?;
    decode_greyscale_png(path, &bytes)
}

/// The most pixels a terrain image may hold: the scenario's cell limit
/// ([`super::MAX_MAP_CELLS`]), checked from the PNG header before any pixel is decoded.
pub const MAX_TERRAIN_PIXELS: u64 = super::MAX_MAP_CELLS;

/// The largest terrain image file read: [`MAX_TERRAIN_PIXELS`] of 16 bits, uncompressed, and a mebibyte of
/// headers (a PNG that deflates nothing is a little larger than its pixels).
pub const MAX_TERRAIN_FILE_BYTES: u64 = 2 * MAX_TERRAIN_PIXELS + (1 << 20);

/// Decodes the bytes of an 8- or 16-bit greyscale PNG (`path` names it in messages) as values in [0, 1].
///
/// # Errors
/// A message naming the file: not a PNG, not greyscale, smaller than 2 x 2, or larger than
/// [`MAX_TERRAIN_PIXELS`] (refused before decoding).
pub fn decode_greyscale_png(path: &Path, bytes: &[u8]) -> Result<(usize, usize, Vec<f64>), HeightmapError> {
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder
        .read_info()
        .map_err(|e| error(path, format!("not a readable PNG: {e}")))?;
    let (w, h) = (reader.info().width, reader.info().height);
    if u64::from(w) * u64::from(h) > MAX_TERRAIN_PIXELS {
        return Err(error(
            path,
            format!("the header declares {w} x {h} pixels, over the limit of {MAX_TERRAIN_PIXELS}"),
        ));
    }
    let (color, depth) = reader.output_color_type();
    if color != png::ColorType::Grayscale {
        return Err(error(path, format!("expected a greyscale PNG, found {color:?}")));
    }
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| error(path, "image too large".into()))?;
    let mut buf = vec![0; size];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| error(path, format!("corrupt image data: {e}")))?;
    let (w, h) = (info.width as usize, info.height as usize);
    if w < 2 || h < 2 {
        return Err(error(
            path,
            format!("expected at least 2 x 2 pixels, found {w} x {h}"),
        ));
    }
    let values = match depth {
        png::BitDepth::Eight => buf[..w * h].iter().map(|&v| f64::from(v) / 255.0).collect(),
        png::BitDepth::Sixteen => buf[..w * h * 2]
            .chunks_exact(2)
            .map(|c| f64::from(u16::from_be_bytes([c[0], c[1]])) / 65535.0)
            .collect(),
        other => {
            return Err(error(
                path,
                format!("expected 8- or 16-bit samples, found {other:?}"),
            ));
        }
    };
    Ok((w, h, values))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn crc32(bytes: &[u8]) -> u32 {
        let mut c = !0u32;
        for &b in bytes {
            c ^= u32::from(b);
            for _ in 0..8 {
                c = if c & 1 == 1 {
                    0xedb8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
            }
        }
        !c
    }

    /// The bytes of a greyscale PNG that declares `w` x `h` pixels and holds a few bytes of image data.
    fn header_only_png(w: u32, h: u32) -> Vec<u8> {
        let mut bytes = b"\x89PNG\r\n\x1a\n".to_vec();
        let mut chunk = |kind: &[u8; 4], data: &[u8]| {
            bytes.extend_from_slice(&(data.len() as u32).to_be_bytes());
            let mut body = kind.to_vec();
            body.extend_from_slice(data);
            bytes.extend_from_slice(&body);
            bytes.extend_from_slice(&crc32(&body).to_be_bytes());
        };
        let mut ihdr = Vec::new();
        ihdr.extend_from_slice(&w.to_be_bytes());
        ihdr.extend_from_slice(&h.to_be_bytes());
        ihdr.extend_from_slice(&[8, 0, 0, 0, 0]); // 8-bit greyscale, deflate, no filter, no interlace
        chunk(b"IHDR", &ihdr);
        chunk(b"IDAT", &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01]);
        chunk(b"IEND", &[]);
        bytes
    }

    #[test]
    fn a_png_declaring_too_many_pixels_is_refused_from_its_header() {
        let bytes = header_only_png(60_000, 60_000);
        assert!(bytes.len() < 200, "{} bytes", bytes.len());
        let err = decode_greyscale_png(Path::new("huge.png"), &bytes).expect_err("too large");
        let err = err.to_string();
        assert!(err.contains("huge.png") && err.contains("60000 x 60000"), "{err}");
    }
}
