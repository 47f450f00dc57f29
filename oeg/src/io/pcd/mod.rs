//! PCL point clouds (`.pcd`), versions 0.6 and 0.7, with `DATA ascii`, `binary` or `binary_compressed`.
//!
//! The fields `x`, `y` and `z` (TYPE F, SIZE 4 or 8) are read; other fields are skipped. `VIEWPOINT` is the
//! sensor's pose in the world (`tx ty tz qw qx qy qz`; identity when absent): the scan's origin is its
//! translation and each point `p` becomes the world point `viewpoint * p`.
//!
//! * Invalid points (NaN, as PCL writes for pixels without depth) are dropped by default. For an organized
//!   cloud (`HEIGHT > 1`, a depth image) they can instead become no-return rays ([`InvalidPoints::NoReturn`]):
//!   the pixel's viewing direction comes from a pinhole model fitted by least squares to the valid pixels
//!   (`x / z = a u + b`, `y / z = c v + d` in the camera frame), so a pixel that saw nothing clears space.
//! * Infinite coordinates are an error.
//! * The DynamicMap benchmark's frames hold points already in the world frame, `VIEWPOINT` the sensor's pose
//!   ([`PcdPoints::World`]): each point is then a hit from the viewpoint's position.
//! * Depth cameras write points in the optical frame (x right, y down, z forward); [`PcdFrame::Optical`] turns
//!   them into the robot convention (x forward, y left, z up: `X = z, Y = -x, Z = -y`) before `VIEWPOINT` is
//!   applied.

use std::path::Path;

use nalgebra::{Isometry3, Point3, Vector3};
use serde::{Deserialize, Serialize};

mod header;
mod write;

pub use self::write::{write_pcd, write_pcd_with_intensity};

use self::header::{Header, MAX_BODY_BYTES, ScalarType, parse_header};
use super::{ByteReader, lzf, read_file};
use crate::error::{Error, Result};
use crate::scan::{Ray, Scan};
use crate::sensor::SensorModel;

/// How the body of a PCD file is stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PcdEncoding {
    /// One point per text line.
    Ascii,
    /// Packed little-endian records, one per point.
    Binary,
    /// LZF-compressed, field by field.
    BinaryCompressed,
}

/// The frame the cloud's points are written in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PcdFrame {
    /// Already x forward, y left, z up (or whatever the world uses).
    #[default]
    AsIs,
    /// Camera optical frame: x right, y down, z forward.
    Optical,
}

/// What to do with NaN points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InvalidPoints {
    /// Leave them out.
    #[default]
    Drop,
    /// Make them no-return rays along the pixel's direction (organized clouds only; unorganized clouds drop
    /// them, since their pixels have no direction).
    NoReturn,
}

/// Where a cloud's points are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PcdPoints {
    /// In the sensor's frame, placed in the world by `VIEWPOINT` (PCL's convention).
    #[default]
    Sensor,
    /// Already in the world frame, `VIEWPOINT` the sensor's pose only (the DynamicMap benchmark's unified
    /// format): each point is a hit from the viewpoint's position.
    World,
}

/// How to turn a cloud into a scan.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PcdOptions {
    /// The points' frame.
    pub frame: PcdFrame,
    /// Whether the points are in the sensor's frame or the world's.
    pub points: PcdPoints,
    /// NaN points.
    pub invalid_points: InvalidPoints,
    /// The sensor model attached to the scan.
    pub sensor: SensorModel,
}

impl Default for PcdOptions {
    fn default() -> Self {
        Self {
            frame: PcdFrame::AsIs,
            points: PcdPoints::Sensor,
            invalid_points: InvalidPoints::Drop,
            sensor: SensorModel::stereo(),
        }
    }
}

/// A point cloud as stored in a PCD file.
#[derive(Debug, Clone, PartialEq)]
pub struct PcdCloud {
    /// Points per row (the image width of an organized cloud).
    pub width: u32,
    /// Rows (1 for an unorganized cloud).
    pub height: u32,
    /// `world_from_sensor`.
    pub viewpoint: Isometry3<f64>,
    /// The points, row-major; NaN marks an invalid point.
    pub points: Vec<Point3<f32>>,
}

impl PcdCloud {
    /// Number of points that are not NaN.
    pub fn num_valid(&self) -> usize {
        self.points.iter().filter(|p| !p.x.is_nan()).count()
    }

    /// The cloud as a scan from the viewpoint.
    ///
    /// # Errors
    /// [`Error::InvalidScan`] if no-return rays were asked for and no pinhole model fits the valid pixels.
    pub fn to_scan(&self, options: &PcdOptions) -> Result<Scan> {
        let origin = Point3::from(self.viewpoint.translation.vector);
        let mut scan = Scan::new(origin, options.sensor);
        let rotation = self.viewpoint.rotation;
        let to_world = |v: Vector3<f64>| -> Vector3<f32> {
            let v = match options.frame {
                PcdFrame::AsIs => v,
                PcdFrame::Optical => Vector3::new(v.z, -v.x, -v.y),
            };
            (rotation * v).cast()
        };
        let pinhole = if options.invalid_points == InvalidPoints::NoReturn && self.height > 1 {
            Some(self.fit_pinhole()?)
        } else {
            None
        };
        scan.rays.reserve(self.points.len());
        if options.points == PcdPoints::World {
            for p in self.points.iter().filter(|p| p.iter().all(|c| c.is_finite())) {
                scan.push_hit(Point3::from(p.coords.cast::<f64>()));
            }
            return Ok(scan);
        }
        for (k, p) in self.points.iter().enumerate() {
            if p.x.is_nan() || p.y.is_nan() || p.z.is_nan() {
                if let Some(pin) = &pinhole {
                    let u = (k % self.width as usize) as f64;
                    let v = (k / self.width as usize) as f64;
                    let direction = Vector3::new(pin.0 * u + pin.1, pin.2 * v + pin.3, 1.0);
                    scan.rays.push(Ray::no_return(to_world(direction)));
                }
                continue;
            }
            scan.rays.push(Ray::hit(to_world(p.coords.cast())));
        }
        Ok(scan)
    }

    /// Least-squares pinhole fit `x / z = a u + b`, `y / z = c v + d` over the valid pixels.
    fn fit_pinhole(&self) -> Result<(f64, f64, f64, f64)> {
        let mut fx = LineFit::default();
        let mut fy = LineFit::default();
        for (k, p) in self.points.iter().enumerate() {
            if p.z.is_nan() || p.z <= 0.0 {
                continue;
            }
            let (x, y, z) = (f64::from(p.x), f64::from(p.y), f64::from(p.z));
            fx.add((k % self.width as usize) as f64, x / z);
            fy.add((k / self.width as usize) as f64, y / z);
        }
        match (fx.solve(), fy.solve()) {
            (Some((a, b)), Some((c, d))) => Ok((a, b, c, d)),
            _ => Err(Error::InvalidScan(
                "cannot infer the pixels' viewing directions: too few valid pixels in front of the camera \
                 (use invalid points = drop)"
                    .into(),
            )),
        }
    }
}

#[derive(Default)]
struct LineFit {
    n: f64,
    sx: f64,
    sy: f64,
    sxx: f64,
    sxy: f64,
}

impl LineFit {
    fn add(&mut self, x: f64, y: f64) {
        self.n += 1.0;
        self.sx += x;
        self.sy += y;
        self.sxx += x * x;
        self.sxy += x * y;
    }

    fn solve(&self) -> Option<(f64, f64)> {
        let det = self.n * self.sxx - self.sx * self.sx;
        if self.n < 2.0 || det.abs() < 1e-9 {
            return None;
        }
        let a = (self.n * self.sxy - self.sx * self.sy) / det;
        Some((a, (self.sy - a * self.sx) / self.n))
    }
}

/// Reads a PCD file.
///
/// # Errors
/// [`Error::Io`] if it cannot be read; [`Error::Parse`] naming the line (header, ascii body) or byte (binary
/// body) for a malformed header, missing x/y/z fields, a count larger than the data, a corrupt compressed
/// block or an infinite coordinate.
pub fn read_pcd(path: &Path) -> Result<PcdCloud> {
    read_pcd_within(path, crate::DEFAULT_MEMORY_LIMIT_BYTES)
}

/// Reads a PCD file, refusing it before decoding if the cloud would take more than `limit_bytes` (its body,
/// decompressed and reordered, and its points).
///
/// # Errors
/// As [`read_pcd`], and [`Error::Parse`] naming the header's DATA line for a cloud over the limit.
pub fn read_pcd_within(path: &Path, limit_bytes: u64) -> Result<PcdCloud> {
    // The body, as stored, is never larger than decoded.
    let data = read_file(path, limit_bytes)?;
    parse_pcd_within(path, &data, limit_bytes)
}

/// Reads a PCD file and converts it with [`PcdCloud::to_scan`].
///
/// # Errors
/// As [`read_pcd`] and [`PcdCloud::to_scan`]; the latter's error is given the file's name.
pub fn read_pcd_scan(path: &Path, options: &PcdOptions) -> Result<Scan> {
    read_pcd_scan_within(path, options, crate::DEFAULT_MEMORY_LIMIT_BYTES)
}

/// As [`read_pcd_scan`], within `limit_bytes` (see [`read_pcd_within`]).
///
/// # Errors
/// As [`read_pcd_within`] and [`PcdCloud::to_scan`].
pub fn read_pcd_scan_within(path: &Path, options: &PcdOptions, limit_bytes: u64) -> Result<Scan> {
    read_pcd_within(path, limit_bytes)?
        .to_scan(options)
        .map_err(|e| Error::parse(path, e.to_string()))
}

/// Reads a point cloud from its bytes (`path` names it in errors).
///
/// # Errors
/// As [`read_pcd`], but for reading the file.
pub fn parse_pcd(path: &Path, data: &[u8]) -> Result<PcdCloud> {
    parse_pcd_within(path, data, crate::DEFAULT_MEMORY_LIMIT_BYTES)
}

/// As [`parse_pcd`], within `limit_bytes` (see [`read_pcd_within`]).
///
/// # Errors
/// As [`read_pcd_within`].
pub fn parse_pcd_within(path: &Path, data: &[u8], limit_bytes: u64) -> Result<PcdCloud> {
    let header = parse_header(path, data)?;
    let (xyz, record_bytes, body_bytes) = check_layout(path, &header, limit_bytes)?;
    let body = &data[header.body_start..];
    let raw = match header.encoding {
        PcdEncoding::Ascii => return parse_ascii(path, &header, body, &xyz),
        PcdEncoding::Binary => {
            let mut r = ByteReader::new(path, data);
            r.take(header.body_start, "the header")?;
            r.take(
                body_bytes,
                format_args!("{} points of {record_bytes} bytes", header.num_points),
            )?;
            body[..body_bytes].to_vec()
        }
        PcdEncoding::BinaryCompressed => decompress_body(path, data, &header, record_bytes, body_bytes)?,
    };
    let points = binary_points(path, &header, &raw, &xyz, record_bytes)?;
    finish(header, points)
}

/// The fields `x`, `y` and `z` (floats), the bytes of a record and of the body, checked against the body
/// limit and `limit_bytes` before anything is allocated.
fn check_layout(path: &Path, header: &Header, limit_bytes: u64) -> Result<(Vec<usize>, usize, usize)> {
    let xyz: Vec<usize> = ["x", "y", "z"]
        .iter()
        .map(|name| {
            header.fields.iter().position(|f| f.name == *name).ok_or_else(|| {
                Error::parse(
                    path,
                    format!("line {}: the cloud has no `{name}` field", header.data_line),
                )
            })
        })
        .collect::<Result<_>>()?;
    for &k in &xyz {
        let f = &header.fields[k];
        if f.kind != ScalarType::F || !(f.size == 4 || f.size == 8) || f.count != 1 {
            return Err(Error::parse(
                path,
                format!(
                    "line {} (the header's DATA line): field `{}` must be TYPE F, SIZE 4 or 8, COUNT 1",
                    header.data_line, f.name
                ),
            ));
        }
    }
    let record_bytes: usize = header.fields.iter().map(|f| f.size * f.count).sum();
    let body_bytes = record_bytes
        .checked_mul(header.num_points)
        .filter(|&b| b <= MAX_BODY_BYTES)
        .ok_or_else(|| {
            Error::parse(
                path,
                format!(
                    "line {} (the header's DATA line): {} points of {record_bytes} bytes exceed the \
                     {MAX_BODY_BYTES}-byte limit",
                    header.data_line, header.num_points
                ),
            )
        })?;
    // The decompressed body, its reordered copy and the points (12 bytes each) live at once.
    let needed = (body_bytes as u64)
        .saturating_mul(2)
        .saturating_add((header.num_points as u64).saturating_mul(12));
    if needed > limit_bytes {
        return Err(Error::parse(
            path,
            format!(
                "line {} (the header's DATA line): {} points would need {needed} bytes, over the memory limit \
                 of {limit_bytes} bytes",
                header.data_line, header.num_points
            ),
        ));
    }
    Ok((xyz, record_bytes, body_bytes))
}

/// A `binary_compressed` body: LZF-decompressed, then from field-major order (all x, then all y, ...) back to
/// records.
fn decompress_body(
    path: &Path,
    data: &[u8],
    header: &Header,
    record_bytes: usize,
    body_bytes: usize,
) -> Result<Vec<u8>> {
    let mut r = ByteReader::new(path, data);
    r.take(header.body_start, "the header")?;
    let compressed = r.u32("the compressed size")? as usize;
    let uncompressed = r.u32("the uncompressed size")? as usize;
    if uncompressed != body_bytes {
        return Err(r.error(format!(
                "the uncompressed size is {uncompressed} bytes, but {} points of {record_bytes} bytes need {body_bytes}",
                header.num_points
            )));
    }
    let start = r.pos();
    let block = r.take(compressed, "the compressed block")?;
    let field_major = lzf::decompress(block, uncompressed)
        .map_err(|m| r.error_at::<Error>(start, format!("corrupt compressed block: {m}")))?;
    // Field-major (all x, then all y, ...) back to records.
    let mut records = vec![0u8; body_bytes];
    let mut offset_in_block = 0;
    let mut offset_in_record = 0;
    for f in &header.fields {
        let w = f.size * f.count;
        for k in 0..header.num_points {
            let src = offset_in_block + k * w;
            let dst = k * record_bytes + offset_in_record;
            records[dst..dst + w].copy_from_slice(&field_major[src..src + w]);
        }
        offset_in_block += w * header.num_points;
        offset_in_record += w;
    }
    Ok(records)
}

/// The points of a binary body's records, each checked.
fn binary_points(
    path: &Path,
    header: &Header,
    raw: &[u8],
    xyz: &[usize],
    record_bytes: usize,
) -> Result<Vec<Point3<f32>>> {
    let offsets: Vec<usize> = header
        .fields
        .iter()
        .scan(0, |acc, f| {
            let o = *acc;
            *acc += f.size * f.count;
            Some(o)
        })
        .collect();
    let read = |rec: &[u8], k: usize| -> f64 {
        let f = &header.fields[k];
        let o = offsets[k];
        if f.size == 4 {
            f64::from(f32::from_le_bytes([rec[o], rec[o + 1], rec[o + 2], rec[o + 3]]))
        } else {
            let mut b = [0u8; 8];
            b.copy_from_slice(&rec[o..o + 8]);
            f64::from_le_bytes(b)
        }
    };
    let mut points = Vec::with_capacity(header.num_points);
    for (k, rec) in raw.chunks_exact(record_bytes).enumerate() {
        let p = [read(rec, xyz[0]), read(rec, xyz[1]), read(rec, xyz[2])];
        points.push(checked_point(path, p, || match header.encoding {
            // Binary records lie in the file as they are; compressed ones only after decompression.
            PcdEncoding::Binary => format!("at byte {}: point {k}", header.body_start + k * record_bytes),
            _ => format!(
                "in the compressed block at byte {}: point {k}",
                header.body_start + 8
            ),
        })?);
    }
    Ok(points)
}

fn checked_point(path: &Path, p: [f64; 3], which: impl Fn() -> String) -> Result<Point3<f32>> {
    if p.iter().any(|v| v.is_infinite()) {
        return Err(Error::parse(
            path,
            format!("{} has an infinite coordinate {p:?}", which()),
        ));
    }
    if p.iter().any(|v| v.is_nan()) {
        return Ok(Point3::new(f32::NAN, f32::NAN, f32::NAN));
    }
    Ok(Point3::new(p[0] as f32, p[1] as f32, p[2] as f32))
}

fn parse_ascii(path: &Path, header: &Header, body: &[u8], xyz: &[usize]) -> Result<PcdCloud> {
    let text = std::str::from_utf8(body).map_err(|e| {
        Error::parse(
            path,
            format!(
                "at byte {}: the ascii body is not text",
                header.body_start + e.valid_up_to()
            ),
        )
    })?;
    // Column of each field's first value.
    let columns: Vec<usize> = header
        .fields
        .iter()
        .scan(0, |acc, f| {
            let c = *acc;
            *acc += f.count;
            Some(c)
        })
        .collect();
    let num_columns: usize = header.fields.iter().map(|f| f.count).sum();
    let mut points = Vec::with_capacity(header.num_points.min(body.len() / 2 + 1));
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty());
    for k in 0..header.num_points {
        let Some((n, line)) = lines.next() else {
            return Err(Error::parse(
                path,
                format!(
                    "at byte {} (the end): the file is truncated: POINTS declares {} points, found {k}",
                    header.body_start + body.len(),
                    header.num_points
                ),
            ));
        };
        let line_no = header.data_line + 1 + n;
        let words: Vec<&str> = line.split_whitespace().collect();
        if words.len() != num_columns {
            return Err(Error::parse(
                path,
                format!(
                    "line {line_no}: expected {num_columns} values, found {}",
                    words.len()
                ),
            ));
        }
        let mut p = [0.0; 3];
        for (axis, &field) in xyz.iter().enumerate() {
            let w = words[columns[field]];
            p[axis] = w.parse::<f64>().map_err(|_| {
                Error::parse(
                    path,
                    format!(
                        "line {line_no}: `{w}` is not a number ({})",
                        header.fields[field].name
                    ),
                )
            })?;
        }
        points.push(checked_point(path, p, || format!("line {line_no}"))?);
    }
    finish_ref(header, points)
}

fn finish(header: Header, points: Vec<Point3<f32>>) -> Result<PcdCloud> {
    finish_ref(&header, points)
}

fn finish_ref(header: &Header, points: Vec<Point3<f32>>) -> Result<PcdCloud> {
    Ok(PcdCloud {
        width: header.width,
        height: header.height,
        viewpoint: header.viewpoint,
        points,
    })
}

#[cfg(test)]
#[allow(clippy::disallowed_methods, reason = "tests write their inputs directly")]
mod tests {
    use super::*;
    use crate::scan::RayKind;
    use nalgebra::Translation3;

    fn temp(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("oeg-pcd-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        dir.join(name)
    }

    #[test]
    fn a_cloud_over_the_callers_memory_limit_is_refused_before_decoding() {
        let path = temp("limit.pcd");
        write_pcd(&path, &depth_image(), PcdEncoding::Binary).expect("written");
        // 12 points of 12 bytes: 12 * 12 * 2 + 12 * 12 = 432 bytes at once.
        assert!(read_pcd_within(&path, 432).is_ok());
        let err = read_pcd_within(&path, 431).expect_err("over").to_string();
        assert!(
            err.contains("memory limit of 431 bytes") && err.contains("line "),
            "{err}"
        );
    }

    #[test]
    fn every_error_of_a_mutated_cloud_names_a_line_or_a_byte() {
        // 3,000 deterministic mutations (byte flips, overwrites, truncations) of the three encodings.
        let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let (mut errors, mut unplaced) = (0, Vec::new());
        for encoding in [
            PcdEncoding::Ascii,
            PcdEncoding::Binary,
            PcdEncoding::BinaryCompressed,
        ] {
            let path = temp(&format!("mutate_{encoding:?}.pcd"));
            write_pcd(&path, &depth_image(), encoding).expect("written");
            let seed = std::fs::read(&path).expect("read");
            for _ in 0..1000 {
                let mut data = seed.clone();
                for _ in 0..1 + next() % 4 {
                    let k = (next() as usize) % data.len();
                    match next() % 3 {
                        0 => data[k] ^= 1 << (next() % 8),
                        1 => data[k] = b"0123456789 .-\nFe"[(next() % 16) as usize],
                        _ => data.truncate(k.max(1)),
                    }
                }
                if let Err(e) = parse_pcd(Path::new("m.pcd"), &data) {
                    errors += 1;
                    let text = e.to_string();
                    if !(text.contains("line ") || text.contains("byte ")) {
                        unplaced.push(text);
                    }
                }
            }
        }
        assert!(errors > 500, "{errors} errors");
        assert!(
            unplaced.is_empty(),
            "{} of {errors} errors name no place: {:?}",
            unplaced.len(),
            &unplaced[..unplaced.len().min(5)]
        );
    }

    /// A 4 x 3 organized cloud from a pinhole camera looking at a wall 2 m away, with two invalid pixels.
    fn depth_image() -> PcdCloud {
        let (fx, cx, cy) = (2.0, 1.5, 1.0);
        let mut points = Vec::new();
        for v in 0..3 {
            for u in 0..4 {
                let z = 2.0f32;
                points.push(Point3::new((u as f32 - cx) / fx * z, (v as f32 - cy) / fx * z, z));
            }
        }
        points[5] = Point3::new(f32::NAN, f32::NAN, f32::NAN);
        points[11] = Point3::new(f32::NAN, f32::NAN, f32::NAN);
        PcdCloud {
            width: 4,
            height: 3,
            viewpoint: Isometry3::from_parts(
                Translation3::new(1.0, 2.0, 0.5),
                nalgebra::UnitQuaternion::identity(),
            ),
            points,
        }
    }

    #[test]
    fn every_encoding_round_trips() {
        let cloud = depth_image();
        for (encoding, name) in [
            (PcdEncoding::Ascii, "a.pcd"),
            (PcdEncoding::Binary, "b.pcd"),
            (PcdEncoding::BinaryCompressed, "c.pcd"),
        ] {
            let path = temp(name);
            write_pcd(&path, &cloud, encoding).expect("written");
            let back = read_pcd(&path).expect("read");
            assert_eq!((back.width, back.height), (4, 3));
            assert_eq!(back.num_valid(), 10, "{encoding:?}");
            assert!((back.viewpoint.translation.vector - cloud.viewpoint.translation.vector).norm() < 1e-9);
            for (a, b) in back.points.iter().zip(&cloud.points) {
                assert!(a.x.is_nan() == b.x.is_nan());
                if !a.x.is_nan() {
                    assert!((a - b).norm() < 1e-6, "{encoding:?}: {a} vs {b}");
                }
            }
        }
    }

    #[test]
    fn invalid_pixels_are_dropped_or_become_no_returns_along_their_pixel() {
        let cloud = depth_image();
        let drop = cloud.to_scan(&PcdOptions::default()).expect("scan");
        assert_eq!(drop.rays.len(), 10);
        assert_eq!(drop.origin_in_world, Point3::new(1.0, 2.0, 0.5));
        let opts = PcdOptions {
            invalid_points: InvalidPoints::NoReturn,
            frame: PcdFrame::Optical,
            ..PcdOptions::default()
        };
        let scan = cloud.to_scan(&opts).expect("scan");
        assert_eq!(scan.rays.len(), 12);
        let misses: Vec<_> = scan.rays.iter().filter(|r| r.kind == RayKind::NoReturn).collect();
        assert_eq!(misses.len(), 2);
        // Pixel (1, 1): optical direction ((1 - 1.5) / 2, 0, 1) -> robot frame (1, 0.25, 0).
        let d = misses[0].offset_in_world;
        assert!((d - Vector3::new(1.0, 0.25, 0.0)).norm() < 1e-5, "{d}");
        // A valid pixel in the optical frame: (x, y, z) -> (z, -x, -y).
        let h = scan.rays[0].offset_in_world;
        assert!((h - Vector3::new(2.0, 1.5, 1.0)).norm() < 1e-5, "{h}");
    }

    fn write_raw(name: &str, bytes: &[u8]) -> std::path::PathBuf {
        let path = temp(name);
        std::fs::write(&path, bytes).expect("write");
        path
    }

    #[test]
    fn bad_files_give_errors_naming_the_place() {
        let cases: [(&str, &[u8], &str); 8] = [
            ("nodata.pcd", b"VERSION 0.7\nFIELDS x y z\n", "no DATA line"),
            (
                "nofield.pcd",
                b"FIELDS x y\nSIZE 4 4\nTYPE F F\nWIDTH 1\nDATA ascii\n1 2\n",
                "no `z` field",
            ),
            (
                "badkey.pcd",
                b"FIELDS x y z\nCOLOUR 3\n",
                "line 2: unknown header key `COLOUR`",
            ),
            (
                "badnum.pcd",
                b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nDATA ascii\n1 two 3\n",
                "line 6: `two`",
            ),
            (
                "short.pcd",
                b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nDATA ascii\n1 2 3\n",
                "truncated",
            ),
            (
                "inf.pcd",
                b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nDATA ascii\n1 inf 3\n",
                "infinite",
            ),
            (
                "trunc.pcd",
                b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nDATA binary\n\0\0\0\0",
                "truncated",
            ),
            (
                "count.pcd",
                b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nPOINTS 3\nDATA binary\n",
                "POINTS is 3",
            ),
        ];
        for (name, bytes, expected) in cases {
            let path = write_raw(name, bytes);
            let err = read_pcd(&path).expect_err(name).to_string();
            assert!(err.contains(name) && err.contains(expected), "{name}: {err}");
        }
    }

    #[test]
    fn corrupt_compressed_blocks_are_errors() {
        let path = temp("corrupt.pcd");
        write_pcd(&path, &depth_image(), PcdEncoding::BinaryCompressed).expect("written");
        let mut bytes = std::fs::read(&path).expect("read");
        let n = bytes.len();
        // Cut the block short.
        let err = parse_pcd(Path::new("cut.pcd"), &bytes[..n - 5])
            .expect_err("truncated")
            .to_string();
        assert!(err.contains("cut.pcd") && err.contains("truncated"), "{err}");
        // A back-reference before the start of the data.
        let start = bytes
            .windows(18)
            .position(|w| w == b"binary_compressed\n")
            .expect("DATA")
            + 18
            + 8;
        bytes[start] = 0xe0;
        bytes[start + 1] = 0xff;
        bytes[start + 2] = 0xff;
        let err = parse_pcd(Path::new("bad.pcd"), &bytes)
            .expect_err("corrupt")
            .to_string();
        assert!(err.contains("corrupt compressed block"), "{err}");
    }
}
