//! A PCD file's header: its lines up to `DATA`, checked, with the layout of its records.

use std::path::Path;

use nalgebra::{Isometry3, Translation3};

use super::PcdEncoding;
use crate::error::{Error, Result};
use crate::io::unit_quaternion;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum ScalarType {
    F,
    I,
    U,
}

#[derive(Debug, Clone)]
pub(super) struct Field {
    pub(super) name: String,
    pub(super) size: usize,
    pub(super) kind: ScalarType,
    pub(super) count: usize,
}

pub(super) struct Header {
    pub(super) fields: Vec<Field>,
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) num_points: usize,
    pub(super) viewpoint: Isometry3<f64>,
    pub(super) encoding: PcdEncoding,
    /// Byte offset of the body.
    pub(super) body_start: usize,
    /// Line number (1-based) of the DATA line.
    pub(super) data_line: usize,
}

/// The most bytes a PCD body may expand to (4 GiB): a bound on what a corrupt header can make us allocate.
pub(super) const MAX_BODY_BYTES: usize = 4 << 30;

/// The header's lines as read so far, before `DATA` completes them.
#[derive(Default)]
struct HeaderLines {
    names: Option<Vec<String>>,
    sizes: Option<Vec<usize>>,
    types: Option<Vec<ScalarType>>,
    counts: Option<Vec<usize>>,
    width: Option<usize>,
    height: Option<usize>,
    points: Option<usize>,
    viewpoint: Option<Isometry3<f64>>,
}

/// Reads the header, line by line up to `DATA`; every error names the file and the line.
pub(super) fn parse_header(path: &Path, data: &[u8]) -> Result<Header> {
    let err = |line: usize, message: String| Error::parse(path, format!("line {line}: {message}"));
    let mut lines = HeaderLines::default();
    let mut pos = 0;
    let mut line_no = 0;
    while pos < data.len() {
        line_no += 1;
        let end = data[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(data.len(), |k| pos + k);
        let raw = &data[pos..end];
        pos = (end + 1).min(data.len());
        let line = std::str::from_utf8(raw)
            .map_err(|_| err(line_no, "the header is not text: is this a PCD file?".into()))?
            .trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let mut words = line.split_whitespace();
        let key = words.next().unwrap_or_default();
        let values: Vec<&str> = words.collect();
        if key == "DATA" {
            return lines
                .finish(&values, pos, line_no)
                .map_err(|message| err(line_no, message));
        }
        lines
            .read(key, &values)
            .map_err(|message| err(line_no, message))?;
    }
    Err(Error::parse(
        path,
        format!(
            "at byte {} (line {line_no}): the header has no DATA line: truncated, or not a PCD file",
            data.len()
        ),
    ))
}

/// Whole numbers of a header line (`what` names it in the message).
fn whole_numbers(values: &[&str], what: &str) -> std::result::Result<Vec<usize>, String> {
    values
        .iter()
        .map(|v| {
            v.parse::<usize>()
                .map_err(|_| format!("{what}: expected whole numbers, got `{v}`"))
        })
        .collect()
}

/// The one whole number of a header line.
fn whole_number(values: &[&str], what: &str) -> std::result::Result<usize, String> {
    match whole_numbers(values, what)?.as_slice() {
        [n] => Ok(*n),
        _ => Err(format!(
            "{what}: expected one whole number, got `{}`",
            values.join(" ")
        )),
    }
}

impl HeaderLines {
    /// Takes one line before `DATA`; the message says what is wrong with it.
    fn read(&mut self, key: &str, values: &[&str]) -> std::result::Result<(), String> {
        match key {
            "VERSION" => {}
            "FIELDS" | "COLUMNS" => self.names = Some(values.iter().map(|s| s.to_string()).collect()),
            "SIZE" => self.sizes = Some(whole_numbers(values, "SIZE")?),
            "TYPE" => {
                self.types = Some(
                    values
                        .iter()
                        .map(|t| match *t {
                            "F" => Ok(ScalarType::F),
                            "I" => Ok(ScalarType::I),
                            "U" => Ok(ScalarType::U),
                            other => Err(format!("TYPE: expected F, I or U, got `{other}`")),
                        })
                        .collect::<std::result::Result<_, _>>()?,
                );
            }
            "COUNT" => self.counts = Some(whole_numbers(values, "COUNT")?),
            "WIDTH" => self.width = Some(whole_number(values, "WIDTH")?),
            "HEIGHT" => self.height = Some(whole_number(values, "HEIGHT")?),
            "POINTS" => self.points = Some(whole_number(values, "POINTS")?),
            "VIEWPOINT" => {
                let v: Vec<f64> = values
                    .iter()
                    .map(|s| s.parse::<f64>().ok().filter(|v| v.is_finite()))
                    .collect::<Option<_>>()
                    .filter(|v: &Vec<f64>| v.len() == 7)
                    .ok_or_else(|| "VIEWPOINT: expected 7 finite numbers tx ty tz qw qx qy qz".to_string())?;
                let rotation = unit_quaternion(v[3], v[4], v[5], v[6])
                    .ok_or_else(|| "VIEWPOINT: the rotation quaternion is zero".to_string())?;
                self.viewpoint = Some(Isometry3::from_parts(
                    Translation3::new(v[0], v[1], v[2]),
                    rotation,
                ));
            }
            other => return Err(format!("unknown header key `{other}`")),
        }
        Ok(())
    }

    /// The header, completed by its `DATA` line (`values`), whose body starts at byte `body_start`.
    fn finish(
        self,
        values: &[&str],
        body_start: usize,
        data_line: usize,
    ) -> std::result::Result<Header, String> {
        let encoding = match values {
            ["ascii"] => PcdEncoding::Ascii,
            ["binary"] => PcdEncoding::Binary,
            ["binary_compressed"] => PcdEncoding::BinaryCompressed,
            _ => {
                return Err(format!(
                    "DATA: expected ascii, binary or binary_compressed, got `{}`",
                    values.join(" ")
                ));
            }
        };
        let names = self.names.ok_or("no FIELDS line before DATA")?;
        let sizes = self.sizes.ok_or("no SIZE line before DATA")?;
        let types = self.types.ok_or("no TYPE line before DATA")?;
        let counts = self.counts.unwrap_or_else(|| vec![1; names.len()]);
        if sizes.len() != names.len() || types.len() != names.len() || counts.len() != names.len() {
            return Err(format!(
                "FIELDS, SIZE, TYPE and COUNT must list the same number of entries ({}, {}, {}, {})",
                names.len(),
                sizes.len(),
                types.len(),
                counts.len()
            ));
        }
        let fields: Vec<Field> = names
            .into_iter()
            .zip(sizes)
            .zip(types)
            .zip(counts)
            .map(|(((name, size), kind), count)| Field {
                name,
                size,
                kind,
                count,
            })
            .collect();
        for f in &fields {
            if ![1, 2, 4, 8].contains(&f.size) || f.count == 0 {
                return Err(format!(
                    "field `{}` has SIZE {} and COUNT {}",
                    f.name, f.size, f.count
                ));
            }
        }
        let width = self.width.ok_or("no WIDTH line before DATA")?;
        let height = self.height.unwrap_or(1);
        let num_points = self.points.unwrap_or(width.saturating_mul(height));
        if num_points != width.saturating_mul(height) {
            return Err(format!(
                "POINTS is {num_points} but WIDTH x HEIGHT is {width} x {height}"
            ));
        }
        let as_u32 = |v: usize, what: &str| u32::try_from(v).map_err(|_| format!("{what} {v} is too large"));
        Ok(Header {
            fields,
            width: as_u32(width, "WIDTH")?,
            height: as_u32(height, "HEIGHT")?,
            num_points,
            viewpoint: self.viewpoint.unwrap_or_else(Isometry3::identity),
            encoding,
            body_start,
            data_line,
        })
    }
}
