//! `grid_map_msgs/GridMap`, the message of ETH's grid_map and of elevation_mapping(_cupy): its geometry, its
//! named layers (`std_msgs/Float32MultiArray`, column- or row-major) and its circular buffer's start indices,
//! read as arrays laid out by the world's axes.
//!
//! grid_map's index `(i, j)` runs against the world's axes from the map's `+x, +y` corner: cell `(i, j)` is
//! centred at `x = px + lx / 2 - (i + 0.5) r`, `y = py + ly / 2 - (j + 0.5) r`, and is stored at
//! `((i + outer_start_index) mod rows, (j + inner_start_index) mod cols)` (`GridMapRosConverter::toMessage`).

use std::path::{Path, PathBuf};

use super::cdr::{CdrError, CdrReader, CdrResult};
use super::container::{Channels, first_log_time, for_each_message, read_bag_files};
use super::msgs::{GRID_MAP, is_type};
use crate::error::{Error, Result};

/// A grid_map's layers as arrays of `rows` x `cols`, row 0 the min-y row and column 0 the min-x column.
#[derive(Debug, Clone, PartialEq)]
pub struct GridMapLayers {
    /// The message's frame.
    pub frame_id: String,
    /// The message's stamp, seconds since the epoch.
    pub stamp_s: f64,
    /// World x and y of the lower-left corner of cell `[0, 0]`, metres.
    pub origin_xy_m: [f64; 2],
    /// Cell size, metres.
    pub resolution_m: f64,
    /// Rows (along y).
    pub rows: usize,
    /// Columns (along x).
    pub cols: usize,
    /// Each layer by name, row-major, NaN where grid_map holds none.
    pub layers: Vec<(String, Vec<f32>)>,
}

/// The cells a grid map message may hold: 2^26 (a 400 m square at 5 cm), checked before any is allocated.
pub const MAX_GRID_MAP_CELLS: u64 = 1 << 26;

/// Reads the `grid_map_msgs/GridMap` on `topic` of a bag (its `.mcap` file or its folder): the last one, or the
/// last one at most `at_s` seconds after the bag's first message.
///
/// # Errors
/// [`Error::Parse`] naming the file, the topic and the field: no such topic or no message in time, a topic of
/// another type, a malformed message, a layer whose size is not the geometry's, a rotated map (grid_map has
/// no orientation).
pub fn read_grid_map(path: &Path, topic: &str, at_s: Option<f64>, limit_bytes: u64) -> Result<GridMapLayers> {
    from_files(
        path,
        &read_bag_files(path, limit_bytes)?,
        topic,
        at_s,
        limit_bytes,
    )
}

/// [`read_grid_map`] for one MCAP file's bytes, `data`, named `path` in errors.
///
/// # Errors
/// As [`read_grid_map`].
pub fn parse_grid_map(
    path: &Path,
    data: &[u8],
    topic: &str,
    at_s: Option<f64>,
    limit_bytes: u64,
) -> Result<GridMapLayers> {
    from_files(
        path,
        &[(path.to_path_buf(), data.to_vec())],
        topic,
        at_s,
        limit_bytes,
    )
}

/// The grid map of a bag from its files' bytes, in order.
fn from_files(
    path: &Path,
    data: &[(PathBuf, Vec<u8>)],
    topic: &str,
    at_s: Option<f64>,
    limit_bytes: u64,
) -> Result<GridMapLayers> {
    let mut chosen: Option<(u64, Vec<u8>, PathBuf)> = None;
    let mut kinds = Vec::new();
    // A time counts from the bag's first message: read only when one is given.
    let until_ns = match at_s {
        Some(s) => Some(first_log_time(data, limit_bytes)?.saturating_add((s.max(0.0) * 1e9) as u64)),
        None => None,
    };
    for_each_message(
        data,
        limit_bytes,
        &mut Channels::default(),
        &mut |file, c, h, message| {
            if c.topic != topic {
                return Ok(());
            }
            if !kinds.contains(&c.kind) {
                kinds.push(c.kind.clone());
            }
            if until_ns.is_none_or(|u| h.log_time <= u)
                && chosen.as_ref().is_none_or(|(t, _, _)| h.log_time >= *t)
            {
                chosen = Some((h.log_time, message.to_vec(), file.to_path_buf()));
            }
            Ok(())
        },
    )?;
    if let Some(kind) = kinds.iter().find(|k| !is_type(k, GRID_MAP)) {
        return Err(Error::parse(
            path,
            format!("topic {topic} is a {kind}, not a grid_map_msgs/GridMap"),
        ));
    }
    let Some((_, message, file)) = chosen else {
        return Err(Error::parse(
            path,
            match (kinds.is_empty(), at_s) {
                (true, _) => format!("no topic {topic} in the bag"),
                (false, Some(s)) => format!("no message on {topic} at or before {s} s"),
                (false, None) => format!("no message on {topic}"),
            },
        ));
    };
    decode(&message)
        .map_err(|e| Error::parse(&file, format!("topic {topic} (grid_map_msgs/msg/GridMap): {e}")))
}

/// One multi-array: its storage order (column-major: grid_map's default) and its values from `data_offset`.
struct Layer {
    column_major: bool,
    sizes: (usize, usize),
    values: Vec<f32>,
}

fn read_layer(r: &mut CdrReader, k: usize) -> CdrResult<Layer> {
    let field = format!("data[{k}].layout.dim");
    let n = r.sequence_len(&field, 12)?;
    let mut dims = Vec::with_capacity(n);
    for d in 0..n {
        let label = r.string(&format!("{field}[{d}].label"))?;
        let size = r.u32(&format!("{field}[{d}].size"))? as usize;
        r.u32(&format!("{field}[{d}].stride"))?;
        dims.push((label, size));
    }
    let offset = r.u32(&format!("data[{k}].layout.data_offset"))? as usize;
    let values = r.f32s_within(&format!("data[{k}].data"), MAX_GRID_MAP_CELLS)?;
    let [(first, outer), (_, inner)] = &dims[..] else {
        return Err(CdrError {
            field,
            message: format!("{n} dimensions, where a grid map layer has 2"),
        });
    };
    let column_major = match first.as_str() {
        "column_index" => true,
        "row_index" => false,
        other => {
            return Err(CdrError {
                field: format!("{field}[0].label"),
                message: format!("`{other}`, where grid_map writes `column_index` or `row_index`"),
            });
        }
    };
    let (outer, inner) = (*outer, *inner);
    let needed = outer.checked_mul(inner).and_then(|c| c.checked_add(offset));
    if needed.is_none_or(|n| n > values.len()) {
        return Err(CdrError {
            field: format!("data[{k}].data"),
            message: format!(
                "{} values for {outer} x {inner} cells after offset {offset}",
                values.len()
            ),
        });
    }
    let values = values[offset..offset + outer * inner].to_vec();
    // Column-major: the outer dimension is the columns.
    let sizes = if column_major {
        (inner, outer)
    } else {
        (outer, inner)
    };
    Ok(Layer {
        column_major,
        sizes,
        values,
    })
}

/// A layer stored from `start` in grid_map's circular buffer of `rows_g x cols_g`, as an array on the world's
/// axes: output row `row` (y up) and column `col` (x up) are grid_map's unwrapped `(i, j)` counted back.
fn unwrap(a: &Layer, (rows_g, cols_g): (usize, usize), start: (usize, usize)) -> Vec<f32> {
    let mut out = vec![f32::NAN; rows_g * cols_g];
    for row in 0..cols_g {
        let sj = (cols_g - 1 - row + start.1) % cols_g;
        for col in 0..rows_g {
            let si = (rows_g - 1 - col + start.0) % rows_g;
            out[row * rows_g + col] = if a.column_major {
                a.values[sj * rows_g + si]
            } else {
                a.values[si * cols_g + sj]
            };
        }
    }
    out
}

fn decode(message: &[u8]) -> CdrResult<GridMapLayers> {
    let mut r = CdrReader::new(message)?;
    let sec = r.i32("header.stamp.sec")?;
    let nanosec = r.u32("header.stamp.nanosec")?;
    let frame_id = r.string("header.frame_id")?;
    let resolution = r.f64("info.resolution")?;
    let (length_x, length_y) = (r.f64("info.length_x")?, r.f64("info.length_y")?);
    let mut pose = [0.0; 7];
    for (k, v) in pose.iter_mut().enumerate() {
        *v = r.f64(&format!("info.pose[{k}]"))?;
    }
    let names = r.sequence_len("layers", 4)?;
    let names = (0..names)
        .map(|k| r.string(&format!("layers[{k}]")))
        .collect::<CdrResult<Vec<_>>>()?;
    let basic = r.sequence_len("basic_layers", 4)?;
    for k in 0..basic {
        r.string(&format!("basic_layers[{k}]"))?;
    }
    let n = r.sequence_len("data", 8)?;
    let arrays = (0..n)
        .map(|k| read_layer(&mut r, k))
        .collect::<CdrResult<Vec<_>>>()?;
    let start = (
        r.u16("outer_start_index")? as usize,
        r.u16("inner_start_index")? as usize,
    );
    let bad = |field: &str, message: String| CdrError {
        field: field.into(),
        message,
    };
    if !(resolution.is_finite() && resolution > 0.0) {
        return Err(bad(
            "info.resolution",
            format!("{resolution}, where a positive cell size is expected"),
        ));
    }
    if !pose.iter().all(|v| v.is_finite()) {
        return Err(bad("info.pose", "a non-finite number".into()));
    }
    // grid_map has no orientation: the pose's rotation is the identity (or all zeros, as some writers leave it).
    let q = &pose[3..];
    if !(q == [0.0, 0.0, 0.0, 1.0] || q == [0.0; 4]) {
        return Err(bad(
            "info.pose.orientation",
            format!("{q:?}: grid maps are not rotated"),
        ));
    }
    let rows_g = (length_x / resolution).round();
    let cols_g = (length_y / resolution).round();
    if !(rows_g >= 1.0 && cols_g >= 1.0 && rows_g * cols_g <= MAX_GRID_MAP_CELLS as f64) {
        return Err(bad(
            "info.length_x",
            format!("{length_x} x {length_y} m at {resolution} m: {rows_g} x {cols_g} cells"),
        ));
    }
    let (rows_g, cols_g) = (rows_g as usize, cols_g as usize);
    if names.len() != arrays.len() {
        return Err(bad(
            "data",
            format!("{} arrays for {} layers", arrays.len(), names.len()),
        ));
    }
    if start.0 >= rows_g.max(1) || start.1 >= cols_g.max(1) {
        return Err(bad(
            "outer_start_index",
            format!("{start:?} outside {rows_g} x {cols_g} cells"),
        ));
    }
    let mut layers = Vec::with_capacity(names.len());
    for (k, (name, a)) in names.into_iter().zip(arrays).enumerate() {
        if a.sizes != (rows_g, cols_g) {
            return Err(bad(
                &format!("data[{k}].layout"),
                format!(
                    "{} x {} cells, where the geometry gives {rows_g} x {cols_g}",
                    a.sizes.0, a.sizes.1
                ),
            ));
        }
        layers.push((name, unwrap(&a, (rows_g, cols_g), start)));
    }
    Ok(GridMapLayers {
        frame_id: super::msgs::frame_name(&frame_id),
        stamp_s: f64::from(sec) + f64::from(nanosec) * 1e-9,
        origin_xy_m: [pose[0] - length_x / 2.0, pose[1] - length_y / 2.0],
        resolution_m: resolution,
        rows: cols_g,
        cols: rows_g,
        layers,
    })
}
