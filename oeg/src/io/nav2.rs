//! The decisions as a ROS / nav2 `map_server` map: a binary PGM image (`P5`, row 0 the max-y edge, as
//! `map_saver` writes it) and its YAML description (`image`, `mode: trinary`, `resolution`, `origin` of the
//! lower-left pixel's corner, `negate`, `occupied_thresh`, `free_thresh`). nav2, ROS 1's `map_server` and
//! most planners read it as it is. [`read_nav2_map`] reads such a map back (any `trinary` map with a PGM
//! image, whoever wrote it), so a map made by another tool can be scored (`oeg score --nav2`).

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::map::Raster;
use crate::planner::UncertainCells;
use crate::traversability::Traversability;

/// Grey of a free cell (`map_saver`'s 254).
pub const PGM_FREE: u8 = 254;
/// Grey of an occupied cell (`map_saver`'s 0).
pub const PGM_OCCUPIED: u8 = 0;
/// Grey of an unknown cell (`map_saver`'s 205).
pub const PGM_UNKNOWN: u8 = 205;

/// `free_thresh` of the YAML: 205 reads as unknown (occupancy 0.196 is above it), 254 as free.
const FREE_THRESH: f64 = 0.1;
/// `occupied_thresh` of the YAML: 0 reads as occupied.
const OCCUPIED_THRESH: f64 = 0.65;

/// The grey of one decision: drivable cells free, blocked cells occupied, never-observed cells unknown, and
/// uncertain cells as `uncertain` says (occupied by default, as the built-in planner treats them).
pub fn nav2_grey(t: Traversability, uncertain: UncertainCells) -> u8 {
    match t {
        Traversability::Free | Traversability::Traversable => PGM_FREE,
        Traversability::Blocked => PGM_OCCUPIED,
        Traversability::Unknown => PGM_UNKNOWN,
        Traversability::Uncertain => match uncertain {
            UncertainCells::Blocked => PGM_OCCUPIED,
            UncertainCells::Drivable => PGM_FREE,
        },
    }
}

/// The PGM image and the YAML text of `decisions`; the YAML names the image `image_name` (a path relative to
/// the YAML file, as `map_server` resolves it).
pub fn nav2_map(
    decisions: &Raster<Traversability>,
    uncertain: UncertainCells,
    image_name: &str,
) -> (Vec<u8>, String) {
    let region = *decisions.region();
    let (w, h) = (region.num_x as usize, region.num_y as usize);
    let mut pgm = format!(
        "P5\n# CREATOR: oeg {}\n{w} {h}\n255\n",
        decisions.window.resolution_m()
    )
    .into_bytes();
    pgm.reserve(w * h);
    for v in (0..h).rev() {
        pgm.extend(
            decisions.values[v * w..(v + 1) * w]
                .iter()
                .map(|t| nav2_grey(*t, uncertain)),
        );
    }
    let res = decisions.window.resolution_m();
    let (x0, y0) = (f64::from(region.min.i) * res, f64::from(region.min.j) * res);
    let yaml = format!(
        "image: {image_name}\nmode: trinary\nresolution: {res}\norigin: [{x0}, {y0}, 0.0]\nnegate: 0\n\
         occupied_thresh: {OCCUPIED_THRESH}\nfree_thresh: {FREE_THRESH}\n"
    );
    (pgm, yaml)
}

/// A nav2 map read back: its decisions, row 0 the min-y row (as the testbed's rasters), and where they lie.
#[derive(Debug, Clone, PartialEq)]
pub struct Nav2Map {
    /// Cell size, metres.
    pub resolution_m: f64,
    /// World x and y of the lower-left corner of the min-y, min-x cell, metres.
    pub origin_xy_m: [f64; 2],
    /// Rows (the image's height).
    pub rows: usize,
    /// Columns (the image's width).
    pub cols: usize,
    /// `rows * cols` decisions, row-major from the min-y row: occupied pixels [`Traversability::Blocked`],
    /// free ones [`Traversability::Free`], the rest [`Traversability::Unknown`].
    pub decisions: Vec<Traversability>,
    /// The image file, resolved against the YAML file's folder.
    pub image: PathBuf,
}

/// The YAML description of a nav2 map.
#[derive(Debug, Clone, PartialEq)]
struct Nav2Yaml {
    image: String,
    resolution_m: f64,
    origin: [f64; 3],
    negate: bool,
    occupied_thresh: f64,
    free_thresh: f64,
}

/// The keys of a nav2 map's YAML; `mode` must be `trinary` (the default).
const YAML_KEYS: [&str; 7] = [
    "image",
    "mode",
    "resolution",
    "origin",
    "negate",
    "occupied_thresh",
    "free_thresh",
];

/// A value of the nav2 YAML: a scalar (quotes removed) or a sequence of scalars, written in flow style
/// (`[0, 0, 0]`) or in block style (`- 0` lines under the key).
#[derive(Debug, Clone, PartialEq)]
enum YamlValue {
    Scalar(String),
    Sequence(Vec<String>),
}

/// A scalar without its quotes (`"m.pgm"`, `'0.05'`), as YAML reads it.
fn unquoted(v: &str) -> &str {
    let v = v.trim();
    for q in ['"', '\''] {
        if let Some(inner) = v.strip_prefix(q).and_then(|v| v.strip_suffix(q)) {
            return inner;
        }
    }
    v
}

/// A line without its comment: `#` at the start or after a space, outside quotes.
fn without_comment(line: &str) -> &str {
    let mut quote = None;
    let mut previous = ' ';
    for (k, c) in line.char_indices() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (None, '"' | '\'') => quote = Some(c),
            (None, '#') if previous.is_whitespace() => return &line[..k],
            _ => {}
        }
        previous = c;
    }
    line
}

/// Parses the YAML text of a nav2 map (`path` is named in errors) as `map_server` reads it: a mapping of the
/// keys it knows ([`YAML_KEYS`]; others are ignored, as `map_server` ignores them), scalars plain or quoted,
/// the origin as a flow (`[x, y, yaw]`) or block (`- x` lines) sequence, `#` comments, `---` and `...`.
fn parse_nav2_yaml(path: &Path, text: &str) -> Result<Nav2Yaml> {
    let mut entries: Vec<(&str, YamlValue, usize)> = Vec::new();
    // Whether the last key had no value on its line, so that `- item` lines below it are its sequence.
    let mut open_block = false;
    for (n, raw) in text.lines().enumerate() {
        let fail = |what: String| Error::parse(path, format!("line {}: {what}", n + 1));
        let line = without_comment(raw);
        let trimmed = line.trim();
        if trimmed.is_empty() || trimmed == "---" || trimmed == "..." {
            continue;
        }
        // An item of the block sequence under the last key.
        if let Some(item) = trimmed.strip_prefix("- ").or((trimmed == "-").then_some("")) {
            match entries.last_mut() {
                Some((_, YamlValue::Sequence(items), _)) if open_block && line.starts_with([' ', '-']) => {
                    items.push(unquoted(item).to_string());
                    continue;
                }
                _ => return Err(fail(format!("`{trimmed}` is a list item that belongs to no key"))),
            }
        }
        if line.starts_with([' ', '\t']) {
            return Err(fail(format!(
                "`{trimmed}` is indented: expected `key: value` at the start of the line"
            )));
        }
        let (key, value) = trimmed
            .split_once(':')
            .ok_or_else(|| fail(format!("expected `key: value`, found `{trimmed}`")))?;
        let (key, value) = (unquoted(key), value.trim());
        if entries.iter().any(|(k, ..)| *k == key) {
            return Err(fail(format!("`{key}` is given twice")));
        }
        open_block = value.is_empty();
        let value = if open_block {
            YamlValue::Sequence(Vec::new())
        } else if let Some(inner) = value.strip_prefix('[').and_then(|v| v.strip_suffix(']')) {
            YamlValue::Sequence(inner.split(',').map(|x| unquoted(x).to_string()).collect())
        } else {
            YamlValue::Scalar(unquoted(value).to_string())
        };
        entries.push((key, value, n + 1));
    }
    let mut values: Vec<(&str, &str, usize)> = Vec::new();
    let mut origin_items: Option<(&[String], usize)> = None;
    for (key, value, n) in &entries {
        if !YAML_KEYS.contains(key) {
            continue;
        }
        match (value, *key) {
            (YamlValue::Sequence(items), "origin") => origin_items = Some((items, *n)),
            (YamlValue::Scalar(v), "origin") => {
                return Err(Error::parse(
                    path,
                    format!("line {n}: `origin: {v}`, expected [x, y, yaw] in metres and radians"),
                ));
            }
            (YamlValue::Scalar(v), _) => values.push((key, v.as_str(), *n)),
            (YamlValue::Sequence(items), _) => {
                let what = if items.is_empty() {
                    "has no value"
                } else {
                    "is a list"
                };
                return Err(Error::parse(
                    path,
                    format!("line {n}: `{key}` {what}, expected a single value"),
                ));
            }
        }
    }
    let get = |key: &str| values.iter().find(|(k, ..)| *k == key).map(|(_, v, n)| (*v, *n));
    let number = |key: &str, default: Option<f64>| -> Result<f64> {
        match get(key) {
            None => default.ok_or_else(|| Error::parse(path, format!("the key `{key}` is missing"))),
            Some((v, n)) => v
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| Error::parse(path, format!("line {n}: `{key}: {v}`, expected a number"))),
        }
    };
    if let Some((mode, n)) = get("mode")
        && mode != "trinary"
    {
        return Err(Error::parse(
            path,
            format!("line {n}: `mode: {mode}`: only `trinary` maps hold decisions (free, occupied, unknown)"),
        ));
    }
    let (image, _) = get("image").ok_or_else(|| Error::parse(path, "the key `image` is missing"))?;
    let image = image.to_string();
    let resolution_m = number("resolution", None)?;
    if resolution_m <= 0.0 {
        return Err(Error::parse(
            path,
            format!("`resolution: {resolution_m}`, expected metres above 0"),
        ));
    }
    let (origin_items, n) = origin_items.ok_or_else(|| Error::parse(path, "the key `origin` is missing"))?;
    let origin: Vec<f64> = origin_items
        .iter()
        .map(|x| x.trim().parse::<f64>())
        .collect::<std::result::Result<Vec<f64>, _>>()
        .ok()
        .filter(|v| v.len() == 3 && v.iter().all(|x| x.is_finite()))
        .ok_or_else(|| {
            Error::parse(
                path,
                format!(
                    "line {n}: `origin: [{}]`, expected [x, y, yaw] in metres and radians",
                    origin_items.join(", ")
                ),
            )
        })?;
    if origin[2] != 0.0 {
        return Err(Error::parse(
            path,
            format!(
                "line {n}: the origin's yaw is {}, only maps aligned with the world's axes (yaw 0) can be read",
                origin[2]
            ),
        ));
    }
    let negate = match get("negate") {
        None | Some(("0", _)) => false,
        Some(("1", _)) => true,
        Some((v, n)) => {
            return Err(Error::parse(
                path,
                format!("line {n}: `negate: {v}`, expected 0 or 1"),
            ));
        }
    };
    let occupied_thresh = number("occupied_thresh", Some(0.65))?;
    let free_thresh = number("free_thresh", Some(0.196))?;
    if !(0.0..=1.0).contains(&free_thresh) || !(free_thresh..=1.0).contains(&occupied_thresh) {
        return Err(Error::parse(
            path,
            format!(
                "free_thresh {free_thresh} and occupied_thresh {occupied_thresh}: expected 0 <= free <= occupied <= 1"
            ),
        ));
    }
    Ok(Nav2Yaml {
        image,
        resolution_m,
        origin: [origin[0], origin[1], origin[2]],
        negate,
        occupied_thresh,
        free_thresh,
    })
}

/// A binary PGM image (`P5`, one byte per pixel): its width, height, largest grey and pixels, row 0 the top.
/// Images of more than `max_pixels` pixels are refused before their pixels are read.
fn parse_pgm<'a>(path: &Path, bytes: &'a [u8], max_pixels: u64) -> Result<(usize, usize, u8, &'a [u8])> {
    let fail = |what: String| Error::parse(path, what);
    if !bytes.starts_with(b"P5") {
        return Err(fail(
            "expected a binary PGM image (magic `P5`); convert other images with `convert map.png map.pgm`"
                .into(),
        ));
    }
    // Three numbers after the magic, separated by white space and `#` comments, then one white space byte.
    let mut pos = 2;
    let mut numbers = [0u64; 3];
    for (k, number) in numbers.iter_mut().enumerate() {
        loop {
            match bytes.get(pos) {
                Some(b'#') => {
                    while bytes.get(pos).is_some_and(|b| *b != b'\n') {
                        pos += 1;
                    }
                }
                Some(b) if b.is_ascii_whitespace() => pos += 1,
                _ => break,
            }
        }
        let start = pos;
        while bytes.get(pos).is_some_and(u8::is_ascii_digit) && pos - start < 10 {
            pos += 1;
        }
        *number = std::str::from_utf8(&bytes[start..pos])
            .ok()
            .and_then(|t| t.parse().ok())
            .ok_or_else(|| {
                fail(format!(
                    "byte {start}: expected the image's {} as a number",
                    ["width", "height", "largest grey"][k]
                ))
            })?;
    }
    if !bytes.get(pos).is_some_and(u8::is_ascii_whitespace) {
        return Err(fail(format!(
            "byte {pos}: expected one white space before the pixels"
        )));
    }
    pos += 1;
    let [w, h, maxval] = numbers;
    if !(1..=255).contains(&maxval) {
        return Err(fail(format!(
            "the largest grey is {maxval}: only 8-bit images (1 to 255) are read"
        )));
    }
    let pixels = w
        .checked_mul(h)
        .filter(|n| *n > 0 && *n <= max_pixels)
        .ok_or_else(|| fail(format!("a {w} x {h} image, expected 1 to {max_pixels} pixels")))?;
    let data = &bytes[pos..];
    if data.len() as u64 != pixels {
        return Err(fail(format!(
            "{} bytes of pixels for a {w} x {h} image, expected {pixels}",
            data.len()
        )));
    }
    Ok((w as usize, h as usize, maxval as u8, data))
}

/// The decision of one grey, as `map_server` reads a `trinary` map: occupancy `(maxval - grey) / maxval`
/// (`grey / maxval` when negated), occupied above `occupied_thresh`, free below `free_thresh`, unknown between.
fn decision_of_grey(grey: u8, maxval: u8, yaml: &Nav2Yaml) -> Traversability {
    let g = f64::from(grey.min(maxval)) / f64::from(maxval);
    let occupancy = if yaml.negate { g } else { 1.0 - g };
    if occupancy > yaml.occupied_thresh {
        Traversability::Blocked
    } else if occupancy < yaml.free_thresh {
        Traversability::Free
    } else {
        Traversability::Unknown
    }
}

/// Reads a nav2 / ROS `map_server` map: the YAML file `yaml_path` and the PGM image it names (relative to the
/// YAML's folder). At most `max_cells` cells are read; files are read with bounded reads.
///
/// # Errors
/// [`Error::Parse`] naming the file and the place: a YAML key that is unknown, missing or out of range, a
/// mode other than `trinary`, a rotated origin, an image that is not an 8-bit binary PGM or has more than
/// `max_cells` pixels, or a truncated image; [`Error::Io`] for a file that cannot be read.
pub fn read_nav2_map(yaml_path: &Path, max_cells: u64) -> Result<Nav2Map> {
    let yaml = parse_nav2_yaml(yaml_path, &oeg_files::read_text(yaml_path)?)?;
    let image = yaml_path.parent().unwrap_or(Path::new("")).join(&yaml.image);
    // The header is a few dozen bytes: a file this long holds at most `max_cells` pixels.
    let bytes = oeg_files::read_bounded(&image, max_cells.saturating_add(4096))?;
    decode(&yaml, image, &bytes, max_cells)
}

/// The map of a parsed YAML and its image's bytes.
fn decode(yaml: &Nav2Yaml, image: PathBuf, bytes: &[u8], max_cells: u64) -> Result<Nav2Map> {
    let (cols, rows, maxval, pixels) = parse_pgm(&image, bytes, max_cells)?;
    let decisions = (0..rows)
        .rev()
        .flat_map(|r| pixels[r * cols..(r + 1) * cols].iter())
        .map(|g| decision_of_grey(*g, maxval, yaml))
        .collect();
    Ok(Nav2Map {
        resolution_m: yaml.resolution_m,
        origin_xy_m: [yaml.origin[0], yaml.origin[1]],
        rows,
        cols,
        decisions,
        image,
    })
}

/// Parses a nav2 map held in memory, the YAML's text and the image's bytes (for the fuzzer and tests).
///
/// # Errors
/// As [`read_nav2_map`].
pub fn parse_nav2_map(yaml_text: &str, image: &[u8], max_cells: u64) -> Result<Nav2Map> {
    let yaml = parse_nav2_yaml(Path::new("map.yaml"), yaml_text)?;
    let image_path = PathBuf::from(&yaml.image);
    decode(&yaml, image_path, image, max_cells)
}

#[cfg(test)]
mod tests;
