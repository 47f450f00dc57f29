//! `sensor_msgs/PointCloud2`: its fields by name, the points and the testbed's two extensions (each reading's
//! range error, and the rays that returned nothing), read and written.

use nalgebra::Vector3;

use super::cdr::{CdrError, CdrReader, CdrResult, CdrWriter};
use super::msgs::Header;

/// `sensor_msgs/PointField`'s `FLOAT32` and `FLOAT64`: the coordinates' types this reader takes.
const FLOAT32: u8 = 7;
const FLOAT64: u8 = 8;

/// `sensor_msgs/PointField`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PointField {
    pub(crate) name: String,
    pub(crate) offset: u32,
    pub(crate) datatype: u8,
}

/// The extra PointCloud2 field, FLOAT32, that carries each reading's range error (metres), as `oeg record
/// --format rosbag2` writes it; a reader that does not know it skips it.
pub const CLOUD_RANGE_SIGMA_FIELD: &str = "range_sigma";

/// The extra PointCloud2 fields, FLOAT32, that carry the end of a ray that returned nothing (its direction times
/// the sensor's range, in the cloud's frame) for a point whose `x`, `y` and `z` are NaN, as `oeg record --format
/// rosbag2` writes them; NaN for a hit. A reader that does not know them drops such points as any NaN point.
pub const CLOUD_CLEAR_FIELDS: [&str; 3] = ["clear_x", "clear_y", "clear_z"];

/// One reading of a cloud, in its frame ([`PointCloud2::readings`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct CloudReading {
    /// The hit's end point, or the end of the ray that returned nothing.
    pub(crate) point: Vector3<f64>,
    pub(crate) hit: bool,
    /// Its range error, where the cloud carries one.
    pub(crate) range_sigma_m: Option<f32>,
}

/// `sensor_msgs/PointCloud2`, its `data` borrowed from the message.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PointCloud2<'a> {
    pub(crate) header: Header,
    pub(crate) height: u32,
    pub(crate) width: u32,
    pub(crate) fields: Vec<PointField>,
    pub(crate) is_bigendian: bool,
    pub(crate) point_step: u32,
    pub(crate) row_step: u32,
    pub(crate) data: &'a [u8],
}

impl<'a> PointCloud2<'a> {
    pub(crate) fn decode(data: &'a [u8]) -> CdrResult<Self> {
        let mut r = CdrReader::new(data)?;
        let header = Header::read(&mut r)?;
        let height = r.u32("height")?;
        let width = r.u32("width")?;
        // A field is at least a 4-byte name length, its offset, type and count.
        let n = r.sequence_len("fields", 13)?;
        let fields = (0..n)
            .map(|k| {
                let field = PointField {
                    name: r.string(&format!("fields[{k}].name"))?,
                    offset: r.u32(&format!("fields[{k}].offset"))?,
                    datatype: r.u8(&format!("fields[{k}].datatype"))?,
                };
                r.u32(&format!("fields[{k}].count"))?;
                Ok(field)
            })
            .collect::<CdrResult<Vec<_>>>()?;
        let cloud = Self {
            header,
            height,
            width,
            fields,
            is_bigendian: r.bool("is_bigendian")?,
            point_step: r.u32("point_step")?,
            row_step: r.u32("row_step")?,
            data: r.bytes("data")?,
        };
        r.bool("is_dense")?;
        Ok(cloud)
    }

    /// The offset and type of the coordinate field `axis`, checked to lie within a point.
    fn coordinate(&self, axis: &str) -> CdrResult<(usize, u8)> {
        self.float_field(axis)?.ok_or_else(|| CdrError {
            field: "fields".into(),
            message: format!(
                "no field `{axis}` (the cloud has {})",
                self.fields
                    .iter()
                    .map(|f| f.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        })
    }

    /// The offset and type of the field `name`, if the cloud has it: FLOAT32 or FLOAT64, within a point.
    fn float_field(&self, name: &str) -> CdrResult<Option<(usize, u8)>> {
        let Some(f) = self.fields.iter().find(|f| f.name == name) else {
            return Ok(None);
        };
        let size = match f.datatype {
            FLOAT32 => 4,
            FLOAT64 => 8,
            t => {
                return Err(CdrError {
                    field: format!("fields[{name}].datatype"),
                    message: format!("{t}, where FLOAT32 (7) or FLOAT64 (8) is expected"),
                });
            }
        };
        if f.offset as usize + size > self.point_step as usize {
            return Err(CdrError {
                field: format!("fields[{name}].offset"),
                message: format!(
                    "{} + {size} bytes runs past point_step {}",
                    f.offset, self.point_step
                ),
            });
        }
        Ok(Some((f.offset as usize, f.datatype)))
    }

    /// The points in the cloud's frame, row by row; points with a NaN or infinite coordinate (`is_dense =
    /// false`) left out. The fields `x`, `y` and `z` are found by name (FLOAT32 or FLOAT64); any other field
    /// (intensity, ring, time) and padding are skipped.
    #[cfg(test)]
    pub(crate) fn points(&self) -> CdrResult<Vec<Vector3<f64>>> {
        Ok(self
            .readings()?
            .into_iter()
            .filter(|r| r.hit)
            .map(|r| r.point)
            .collect())
    }

    /// The readings in the cloud's frame, row by row: every point with finite coordinates is a hit; a point
    /// with a NaN coordinate is a ray that returned nothing when the cloud has the fields
    /// [`CLOUD_CLEAR_FIELDS`] and they hold its cleared ray's end (finite, not zero), and is left out otherwise. A finite, positive
    /// [`CLOUD_RANGE_SIGMA_FIELD`] is the reading's range error. Any other field is skipped.
    pub(crate) fn readings(&self) -> CdrResult<Vec<CloudReading>> {
        let axes = [
            self.coordinate("x")?,
            self.coordinate("y")?,
            self.coordinate("z")?,
        ];
        let clear = match CLOUD_CLEAR_FIELDS.map(|f| self.float_field(f)) {
            [Ok(Some(x)), Ok(Some(y)), Ok(Some(z))] => Some([x, y, z]),
            [x, y, z] => {
                x?;
                y?;
                z?;
                None
            }
        };
        let sigma = self.float_field(CLOUD_RANGE_SIGMA_FIELD)?;
        let step = self.point_step as usize;
        let (w, h) = (self.width as usize, self.height as usize);
        if w == 0 || h == 0 {
            return Ok(Vec::new());
        }
        let row_step = self.row_step as usize;
        // The last row needs its points only; the rows before it, `row_step` bytes each.
        let fits = w
            .checked_mul(step)
            .filter(|&row| h == 1 || row <= row_step)
            .and_then(|row| row_step.checked_mul(h - 1)?.checked_add(row))
            .is_some_and(|n| n <= self.data.len());
        if !fits {
            return Err(CdrError {
                field: "data".into(),
                message: format!(
                    "{} bytes cannot hold {h} rows of {w} points of {step} bytes, {row_step} bytes a row",
                    self.data.len()
                ),
            });
        }
        let big = self.is_bigendian;
        let read = |p: &[u8], (offset, datatype): (usize, u8)| -> f64 {
            if datatype == FLOAT32 {
                let mut b = [0u8; 4];
                b.copy_from_slice(&p[offset..offset + 4]);
                f64::from(if big {
                    f32::from_be_bytes(b)
                } else {
                    f32::from_le_bytes(b)
                })
            } else {
                let mut b = [0u8; 8];
                b.copy_from_slice(&p[offset..offset + 8]);
                if big {
                    f64::from_be_bytes(b)
                } else {
                    f64::from_le_bytes(b)
                }
            }
        };
        let vector = |p: &[u8], [x, y, z]: [(usize, u8); 3]| Vector3::new(read(p, x), read(p, y), read(p, z));
        let finite = |v: &Vector3<f64>| v.iter().all(|c| c.is_finite());
        let mut readings = Vec::with_capacity(w * h);
        for row in 0..h {
            let start = row * row_step;
            for k in 0..w {
                let p = &self.data[start + k * step..start + (k + 1) * step];
                let range_sigma_m = sigma
                    .map(|f| read(p, f) as f32)
                    .filter(|s| s.is_finite() && *s > 0.0);
                let v = vector(p, axes);
                if finite(&v) {
                    readings.push(CloudReading {
                        point: v,
                        hit: true,
                        range_sigma_m,
                    });
                } else if let Some(end) = clear
                    .map(|c| vector(p, c))
                    .filter(|v| finite(v) && v.norm() > 0.0)
                {
                    readings.push(CloudReading {
                        point: end,
                        hit: false,
                        range_sigma_m,
                    });
                }
            }
        }
        Ok(readings)
    }

    /// A cloud of `points` (x, y, z, FLOAT64 or FLOAT32, unorganized), little-endian.
    /// A cloud of `points` (x, y, z as FLOAT64 or FLOAT32) with the FLOAT32 fields `extra` after them, each
    /// one value a point.
    pub(crate) fn encode(
        header: &Header,
        points: &[Vector3<f64>],
        float64: bool,
        extra: &[(&str, &[f32])],
    ) -> Vec<u8> {
        let size: u32 = if float64 { 8 } else { 4 };
        let step = 3 * size + 4 * extra.len() as u32;
        let mut w = CdrWriter::new();
        header.write(&mut w);
        w.u32(1);
        w.len(points.len());
        w.len(3 + extra.len());
        for (k, name) in ["x", "y", "z"].into_iter().enumerate() {
            w.string(name);
            w.u32(size * k as u32);
            w.u8(if float64 { FLOAT64 } else { FLOAT32 });
            w.u32(1);
        }
        for (k, (name, _)) in extra.iter().enumerate() {
            w.string(name);
            w.u32(3 * size + 4 * k as u32);
            w.u8(FLOAT32);
            w.u32(1);
        }
        w.bool(false);
        w.u32(step);
        w.len(step as usize * points.len());
        let mut data = Vec::with_capacity(step as usize * points.len());
        for (i, p) in points.iter().enumerate() {
            for c in p.iter() {
                if float64 {
                    data.extend_from_slice(&c.to_le_bytes());
                } else {
                    data.extend_from_slice(&(*c as f32).to_le_bytes());
                }
            }
            for (_, values) in extra {
                data.extend_from_slice(&values[i].to_le_bytes());
            }
        }
        w.bytes(&data);
        w.bool(points.iter().all(|p| p.iter().all(|c| c.is_finite())));
        w.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lidar_header() -> Header {
        Header {
            stamp_ns: 1_500_000_123,
            frame_id: "lidar".into(),
        }
    }

    #[test]
    fn a_cloud_reads_back_as_written() {
        let points = [Vector3::new(1.0, 2.0, 3.0), Vector3::new(-1.0, 0.5, f64::NAN)];
        for float64 in [false, true] {
            let data = PointCloud2::encode(&lidar_header(), &points, float64, &[]);
            let cloud = PointCloud2::decode(&data).expect("decodes");
            assert_eq!(cloud.header, lidar_header());
            assert_eq!(cloud.points().expect("points"), vec![Vector3::new(1.0, 2.0, 3.0)]);
        }
    }

    #[test]
    fn a_cloud_s_rays_that_returned_nothing_and_range_errors_read_back_from_their_fields() {
        let nan = f32::NAN;
        let points = [
            Vector3::new(1.0, 2.0, 3.0),
            Vector3::repeat(f64::NAN),
            Vector3::repeat(f64::NAN),
        ];
        let sigma = [0.02, 0.5, -1.0];
        let clear = [[nan, 10.0, 0.0], [nan, 0.0, 0.0], [nan, 0.0, 0.0]];
        let fields = [
            (CLOUD_RANGE_SIGMA_FIELD, &sigma[..]),
            (CLOUD_CLEAR_FIELDS[0], &clear[0][..]),
            (CLOUD_CLEAR_FIELDS[1], &clear[1][..]),
            (CLOUD_CLEAR_FIELDS[2], &clear[2][..]),
        ];
        let data = PointCloud2::encode(&lidar_header(), &points, false, &fields);
        let cloud = PointCloud2::decode(&data).expect("decodes");
        // The third point has neither coordinates nor a cleared end (a zero one is none): left out. A range
        // error that is not a positive number is none.
        assert_eq!(
            cloud.readings().expect("readings"),
            vec![
                CloudReading {
                    point: Vector3::new(1.0, 2.0, 3.0),
                    hit: true,
                    range_sigma_m: Some(0.02),
                },
                CloudReading {
                    point: Vector3::new(10.0, 0.0, 0.0),
                    hit: false,
                    range_sigma_m: Some(0.5),
                },
            ]
        );
        // A reader that knows only x, y and z sees the hit.
        assert_eq!(cloud.points().expect("points"), vec![Vector3::new(1.0, 2.0, 3.0)]);
        // Two of the three cleared-end fields are not a cleared end: such points are left out, as any NaN.
        let data = PointCloud2::encode(&lidar_header(), &points, false, &fields[..3]);
        let cloud = PointCloud2::decode(&data).expect("decodes");
        assert_eq!(cloud.readings().expect("readings").len(), 1);
    }

    #[test]
    fn a_cloud_whose_sizes_lie_is_refused_by_field() {
        let data = PointCloud2::encode(&lidar_header(), &[Vector3::new(1.0, 2.0, 3.0)], true, &[]);
        let mut cloud = PointCloud2::decode(&data).expect("decodes");
        cloud.width = u32::MAX;
        cloud.height = u32::MAX;
        assert_eq!(cloud.points().expect_err("refused").field, "data");
        cloud.width = 1;
        cloud.height = 1;
        cloud.fields[2].offset = 20;
        assert_eq!(cloud.points().expect_err("refused").field, "fields[z].offset");
        cloud.fields[2].name = "intensity".into();
        assert!(
            cloud
                .points()
                .expect_err("refused")
                .message
                .contains("no field `z`")
        );
    }
}
