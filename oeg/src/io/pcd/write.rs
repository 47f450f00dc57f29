//! Writing PCD files: `x y z` (float32), with an `intensity` field when given, in any of the three encodings.

use std::path::Path;

use super::super::{lzf, write_atomically};
use super::{PcdCloud, PcdEncoding};
use crate::error::{Error, Result};

/// Writes a cloud with the fields `x y z` (F4) in `encoding`.
///
/// # Errors
/// [`Error::Io`] naming the file; [`Error::InvalidSetting`] if `width * height` differs from the number of points.
pub fn write_pcd(path: &Path, cloud: &PcdCloud, encoding: PcdEncoding) -> Result<()> {
    write_pcd_with_intensity(path, cloud, None, encoding)
}

/// [`write_pcd`], with a field `intensity` (float32) of one value a point when given: the DynamicMap
/// benchmark's frames and ground truth carry each point's label there (0 static, 1 dynamic).
///
/// # Errors
/// As [`write_pcd`], and [`Error::InvalidSetting`] when `intensity` has not one value a point.
pub fn write_pcd_with_intensity(
    path: &Path,
    cloud: &PcdCloud,
    intensity: Option<&[f32]>,
    encoding: PcdEncoding,
) -> Result<()> {
    if cloud.width as usize * cloud.height as usize != cloud.points.len() {
        return Err(Error::setting(
            "cloud",
            "width x height must equal the number of points",
        ));
    }
    if intensity.is_some_and(|i| i.len() != cloud.points.len()) {
        return Err(Error::setting("intensity", "one value a point"));
    }
    let t = cloud.viewpoint.translation.vector;
    let q = cloud.viewpoint.rotation.quaternion();
    let data = match encoding {
        PcdEncoding::Ascii => "ascii",
        PcdEncoding::Binary => "binary",
        PcdEncoding::BinaryCompressed => "binary_compressed",
    };
    let (fields, sizes, types, counts) = if intensity.is_some() {
        ("x y z intensity", "4 4 4 4", "F F F F", "1 1 1 1")
    } else {
        ("x y z", "4 4 4", "F F F", "1 1 1")
    };
    let mut out = format!(
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS {fields}\nSIZE {sizes}\nTYPE {types}\n\
         COUNT {counts}\nWIDTH {}\nHEIGHT {}\nVIEWPOINT {} {} {} {} {} {} {}\nPOINTS {}\nDATA {data}\n",
        cloud.width,
        cloud.height,
        t.x,
        t.y,
        t.z,
        q.w,
        q.i,
        q.j,
        q.k,
        cloud.points.len()
    )
    .into_bytes();
    let num_fields = 3 + usize::from(intensity.is_some());
    let values = |k: usize| -> [f32; 4] {
        let p = cloud.points[k];
        [p.x, p.y, p.z, intensity.map_or(0.0, |i| i[k])]
    };
    match encoding {
        PcdEncoding::Ascii => {
            for k in 0..cloud.points.len() {
                let line: Vec<String> = values(k)[..num_fields].iter().map(f32::to_string).collect();
                out.extend_from_slice(format!("{}\n", line.join(" ")).as_bytes());
            }
        }
        PcdEncoding::Binary => {
            for k in 0..cloud.points.len() {
                for v in &values(k)[..num_fields] {
                    out.extend_from_slice(&v.to_le_bytes());
                }
            }
        }
        PcdEncoding::BinaryCompressed => {
            let mut field_major = Vec::with_capacity(cloud.points.len() * 4 * num_fields);
            for field in 0..num_fields {
                for k in 0..cloud.points.len() {
                    field_major.extend_from_slice(&values(k)[field].to_le_bytes());
                }
            }
            let packed = lzf::compress(&field_major);
            out.extend_from_slice(&(packed.len() as u32).to_le_bytes());
            out.extend_from_slice(&(field_major.len() as u32).to_le_bytes());
            out.extend_from_slice(&packed);
        }
    }
    Ok(write_atomically(path, &out)?)
}
