//! The map file format (`.oeg`), versions 1 to 3, in the framed container of [`super::container`].
//! Little-endian throughout:
//!
//! ```text
//! offset  size  what
//! 0       8     magic "OEGMAP\r\n" (the CR LF catches text-mode transfers)
//! 8       4     u32 format version (1 without a ceiling layer, 3 with one)
//! 12      4     u32 length H of the header
//! 16      H     header, UTF-8 JSON: see MapFileHeader (resolution, tile size, tile count, model options, ...)
//! 16+H    ...   num_tiles times: i32 tile column, i32 tile row, then 64 x 64 cells row-major from the tile's
//!               min-x, min-y cell, each cell three f32: log-odds, elevation mean (m), elevation variance (m^2)
//! ...     ...   versions 2 and 3, num_ceiling_tiles times: i32 tile column, i32 tile row, then 64 x 64
//!               ceilings in the same order, each three f32: height (m), variance (m^2), log-odds (NaN: none),
//!               then one u8: the side the beams came from, 0 above (a top), 1 below (an underside), 2 both,
//!               then (version 3 only) one f32: the highest point a beam passed under it (m, -inf: none)
//! end-8   8     u64 FNV-1a-64 checksum of every byte before it
//! ```
//!
//! A map without a ceiling layer ([`crate::OverheadHits::Ceiling`]) is written as version 1, byte for byte
//! as before the layer existed; a map with one as version 3, whose header adds `num_ceiling_tiles`. Version 2
//! files (ceilings without the clear height, before it was kept) are read with none (`-inf`): their
//! structures above the robot's height are judged `uncertain` ([`crate::Ceiling::clear_m`]).
//!
//! A never-observed cell has NaN log-odds; a cell without an elevation estimate has an infinite variance (see
//! [`crate::Cell`]). Tile `(ti, tj)` holds cells `(64 ti .. 64 ti + 63, 64 tj .. 64 tj + 63)`.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::{ByteReader, container, read_file, write_atomically};
use crate::error::{Error, Result};
use crate::map::{IntegrationStats, Map, MapConfig};
use crate::storage::{TILE_CELLS, TILE_SIZE, TileIndex};
use crate::{Ceiling, Cell, SeenFrom};

/// The file's first eight bytes.
pub(crate) const MAGIC: &[u8; 8] = b"OEGMAP\r\n";
/// The format version of a map with a ceiling layer; one without is written as [`FORMAT_VERSION_NO_CEILINGS`].
/// This crate reads both, and [`FORMAT_VERSION_CEILINGS_WITHOUT_CLEAR`].
pub(crate) const FORMAT_VERSION: u32 = 3;
/// The format version of a map without a ceiling layer (the format before the layer existed).
pub(crate) const FORMAT_VERSION_NO_CEILINGS: u32 = 1;
/// The format version of a ceiling layer without [`Ceiling::clear_m`]: read, no longer written.
pub(crate) const FORMAT_VERSION_CEILINGS_WITHOUT_CLEAR: u32 = 2;
const TILE_RECORD_BYTES: usize = 8 + TILE_CELLS * 12;
/// A ceiling tile record's bytes in `version`.
const fn ceiling_record_bytes(version: u32) -> usize {
    if version == FORMAT_VERSION_CEILINGS_WITHOUT_CLEAR {
        8 + TILE_CELLS * 13
    } else {
        8 + TILE_CELLS * 17
    }
}

/// The JSON header of a map file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MapFileHeader {
    /// The map's configuration (resolution, model options, memory limit).
    pub config: MapConfig,
    /// Tile edge in cells (64).
    pub tile_size: u32,
    /// Number of tile records that follow.
    pub num_tiles: u64,
    /// Number of ceiling tile records after them (version 2; absent in version 1).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub num_ceiling_tiles: u64,
    /// Scans integrated into the map.
    pub num_scans: u64,
    /// Integration totals.
    pub totals: IntegrationStats,
    /// The program that wrote the file.
    pub written_by: String,
    /// The format version of the file the header was read from (not in the JSON: it is the file's prefix);
    /// [`MapFileHeader::format_version`] for a header about to be written.
    #[serde(skip)]
    pub file_version: u32,
}

impl MapFileHeader {
    /// The format version a file with this header has when this crate writes it: 3 with a ceiling layer, 1
    /// without.
    pub fn format_version(&self) -> u32 {
        if self.num_ceiling_tiles == 0 {
            FORMAT_VERSION_NO_CEILINGS
        } else {
            FORMAT_VERSION
        }
    }
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}

/// Serialises the map into the bytes of a map file.
pub fn map_to_bytes(map: &Map) -> Vec<u8> {
    let tiles: Vec<_> = map.tiles().collect();
    let ceiling_tiles: Vec<_> = map.ceiling_tiles().collect();
    let header = MapFileHeader {
        config: *map.config(),
        tile_size: TILE_SIZE as u32,
        num_tiles: tiles.len() as u64,
        num_ceiling_tiles: ceiling_tiles.len() as u64,
        num_scans: map.num_scans(),
        totals: map.totals(),
        written_by: format!("oeg {}", env!("CARGO_PKG_VERSION")),
        file_version: 0,
    };
    // A plain struct of numbers and strings always serialises.
    let json = serde_json::to_vec(&header).unwrap_or_default();
    let mut out = container::container_prefix_bytes(MAGIC, header.format_version(), &json);
    out.reserve(
        tiles.len() * TILE_RECORD_BYTES + ceiling_tiles.len() * ceiling_record_bytes(FORMAT_VERSION) + 8,
    );
    for (tile, cells) in tiles {
        out.extend_from_slice(&tile.ti.to_le_bytes());
        out.extend_from_slice(&tile.tj.to_le_bytes());
        for c in cells.iter() {
            for v in [c.log_odds, c.mean_m, c.var_m2] {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    for (tile, ceilings) in ceiling_tiles {
        out.extend_from_slice(&tile.ti.to_le_bytes());
        out.extend_from_slice(&tile.tj.to_le_bytes());
        for c in ceilings.iter() {
            for v in [c.z_m, c.var_m2, c.log_odds] {
                out.extend_from_slice(&v.to_le_bytes());
            }
            out.push(c.seen_from as u8);
            out.extend_from_slice(&c.clear_m.to_le_bytes());
        }
    }
    container::seal_container(&mut out);
    out
}

/// Saves the map to `path` atomically.
///
/// # Errors
/// [`Error::Io`] naming the file.
pub fn save_map(map: &Map, path: &Path) -> Result<()> {
    Ok(write_atomically(path, &map_to_bytes(map))?)
}

/// Reads only the header of a map file (and checks magic, version and checksum).
///
/// # Errors
/// As [`load_map`].
pub fn read_map_header(path: &Path) -> Result<MapFileHeader> {
    let data = read_file(path, crate::DEFAULT_MEMORY_LIMIT_BYTES)?;
    parse(path, &data, None).map(|(h, _)| h)
}

/// Loads a map saved by [`save_map`], within the default memory limit ([`crate::DEFAULT_MEMORY_LIMIT_BYTES`]).
///
/// # Errors
/// As [`load_map_within`].
pub fn load_map(path: &Path) -> Result<Map> {
    load_map_within(path, crate::DEFAULT_MEMORY_LIMIT_BYTES)
}

/// Loads a map saved by [`save_map`], refusing it before allocating if it would hold more than `limit_bytes`.
///
/// The limit is the caller's: the `memory_limit_bytes` a file's header records is ignored, so a file cannot
/// raise the bound it is read under. The loaded map's [`MapConfig::memory_limit_bytes`] is `limit_bytes`.
///
/// # Errors
/// [`Error::Io`] if the file cannot be read; [`Error::Parse`] naming the byte offset for a wrong magic number,
/// an unsupported version, a malformed header, a truncated file, a checksum mismatch, a tile outside the
/// representable grid, a cell value no map holds (an infinite log-odds, a NaN or infinite elevation, a
/// negative or NaN variance), or tiles that would exceed `limit_bytes`.
pub fn load_map_within(path: &Path, limit_bytes: u64) -> Result<Map> {
    // A file holds no more than the map it makes (its cells packed, 12 bytes as in memory, its ceilings in 17 of
    // their 20), plus its header and tile records: one larger than the limit and a megabyte is refused before
    // it is read.
    let data = read_file(path, limit_bytes.saturating_add(1 << 20))?;
    map_from_bytes(path, &data, limit_bytes)
}

/// A map from the bytes of a map file (`path` names it in errors), within `limit_bytes`.
///
/// # Errors
/// As [`load_map_within`], but for reading the file.
pub fn map_from_bytes(path: &Path, data: &[u8], limit_bytes: u64) -> Result<Map> {
    parse(path, data, Some(limit_bytes)).map(|(_, m)| m.unwrap_or_else(|| unreachable!("asked for the map")))
}

/// The smallest and largest tile coordinate: cells are `i32`, and a tile holds 64 of them per side.
const TILE_COORD_RANGE: std::ops::RangeInclusive<i32> = (i32::MIN >> 6)..=(i32::MAX >> 6);

fn parse(path: &Path, data: &[u8], build: Option<u64>) -> Result<(MapFileHeader, Option<Map>)> {
    let prefix = container::read_container_prefix(
        path,
        data,
        MAGIC,
        &[
            FORMAT_VERSION_NO_CEILINGS,
            FORMAT_VERSION_CEILINGS_WITHOUT_CLEAR,
            FORMAT_VERSION,
        ],
        "an OEG map file",
    )?;
    let mut r = ByteReader::new(path, data);
    r.take(prefix.body_start, "the header")?;
    let header = MapFileHeader {
        file_version: prefix.version,
        ..serde_json::from_slice(prefix.header)
            .map_err(|e| r.error_at::<Error>(16, format!("malformed header: {e}")))?
    };
    if header.tile_size as usize != TILE_SIZE {
        return Err(r.error_at(
            16,
            format!(
                "tile size {} is not supported (expected {TILE_SIZE})",
                header.tile_size
            ),
        ));
    }
    if prefix.version == FORMAT_VERSION_NO_CEILINGS && header.num_ceiling_tiles != 0 {
        return Err(r.error_at(
            16,
            format!(
                "a version 1 header declares {} ceiling tiles (expected none: the ceiling layer is version 2 or 3)",
                header.num_ceiling_tiles
            ),
        ));
    }
    let expected_len = (prefix.body_start as u64).saturating_add(
        header
            .num_tiles
            .saturating_mul(TILE_RECORD_BYTES as u64)
            .saturating_add(
                header
                    .num_ceiling_tiles
                    .saturating_mul(ceiling_record_bytes(prefix.version) as u64),
            )
            .saturating_add(8),
    );
    if expected_len != data.len() as u64 {
        return Err(r.error(format!(
            "the header declares {} tiles and {} ceiling tiles, so the file should be {expected_len} bytes, but it \
             is {}: truncated or corrupt",
            header.num_tiles,
            header.num_ceiling_tiles,
            data.len()
        )));
    }
    container::check_container_checksum(path, data, data.len() - 8)?;
    let Some(limit_bytes) = build else {
        return Ok((header, None));
    };
    let config = MapConfig {
        memory_limit_bytes: limit_bytes,
        ..header.config
    };
    let mut map =
        Map::new(config).map_err(|e| r.error_at::<Error>(16, format!("invalid map settings: {e}")))?;
    read_tiles(
        &mut r,
        path,
        header.num_tiles,
        "tile",
        Cell::UNOBSERVED,
        read_cell,
        |tile, cells| map.insert_tile(tile, cells),
    )?;
    read_tiles(
        &mut r,
        path,
        header.num_ceiling_tiles,
        "ceiling tile",
        Ceiling::NONE,
        |r, what, k| {
            read_ceiling(
                r,
                what,
                k,
                prefix.version != FORMAT_VERSION_CEILINGS_WITHOUT_CLEAR,
            )
        },
        |tile, ceilings| map.insert_ceiling_tile(tile, ceilings),
    )?;
    map.restore_counters(header.num_scans, header.totals);
    Ok((header, Some(map)))
}

/// Reads a tile record's coordinates, refusing a tile outside the grid.
fn read_tile_index(r: &mut ByteReader<'_>, what: &str) -> Result<TileIndex> {
    let at = r.pos();
    let tile = TileIndex {
        ti: r.i32(what)?,
        tj: r.i32(what)?,
    };
    if !(TILE_COORD_RANGE.contains(&tile.ti) && TILE_COORD_RANGE.contains(&tile.tj)) {
        return Err(r.error_at(
            at,
            format!(
                "{what} has coordinates ({}, {}), outside the grid's tiles {} ..= {}",
                tile.ti,
                tile.tj,
                TILE_COORD_RANGE.start(),
                TILE_COORD_RANGE.end()
            ),
        ));
    }
    Ok(tile)
}

/// Reads `count` tile records of `kind` (`"tile"`, `"ceiling tile"`: the name in errors), each a tile index and
/// 64 x 64 values read by `read` (given the record's name and the cell's position in the tile), and hands each
/// tile to `insert`; a memory-limit error names the record.
fn read_tiles<T: Copy>(
    r: &mut ByteReader<'_>,
    path: &Path,
    count: u64,
    kind: &str,
    fill: T,
    read: impl Fn(&mut ByteReader<'_>, &str, usize) -> Result<T>,
    mut insert: impl FnMut(TileIndex, Box<[T; TILE_CELLS]>) -> Result<()>,
) -> Result<()> {
    for t in 0..count {
        let what = format!("{kind} {t}");
        let tile = read_tile_index(r, &what)?;
        let mut values = Box::new([fill; TILE_CELLS]);
        for (k, v) in values.iter_mut().enumerate() {
            *v = read(r, &what, k)?;
        }
        insert(tile, values).map_err(|e| match e {
            Error::MemoryLimit { .. } => Error::parse(path, format!("loading {what}: {e}")),
            other => other,
        })?;
    }
    Ok(())
}

/// One cell of a tile record (`what`, cell `k`), refused with its place if no map holds it.
fn read_cell(r: &mut ByteReader<'_>, what: &str, k: usize) -> Result<Cell> {
    let at = r.pos();
    let c = Cell {
        log_odds: r.f32(what)?,
        mean_m: r.f32(what)?,
        var_m2: r.f32(what)?,
    };
    match cell_problem(&c) {
        Some(problem) => Err(r.error_at(at, format!("{what}, cell {k}: {problem}"))),
        None => Ok(c),
    }
}

/// One ceiling of a ceiling tile record (`what`, cell `k`), refused with its place if no map holds it; its clear
/// height is read `with_clear` (version 3), and is none in version 2.
fn read_ceiling(r: &mut ByteReader<'_>, what: &str, k: usize, with_clear: bool) -> Result<Ceiling> {
    let at = r.pos();
    let (z_m, var_m2, log_odds) = (r.f32(what)?, r.f32(what)?, r.f32(what)?);
    let side = r.take(1, what)?[0];
    let seen_from = SeenFrom::from_byte(side).ok_or_else(|| {
        r.error_at::<Error>(
            at + 12,
            format!("{what}, cell {k}: side {side} is not 0 (above), 1 (below) or 2 (both)"),
        )
    })?;
    let clear_m = if with_clear {
        r.f32(what)?
    } else {
        f32::NEG_INFINITY
    };
    let c = Ceiling {
        z_m,
        var_m2,
        log_odds,
        seen_from,
        clear_m,
    };
    match ceiling_problem(&c) {
        Some(problem) => Err(r.error_at(at, format!("{what}, cell {k}: {problem}"))),
        None => Ok(c),
    }
}

/// What makes a ceiling's values impossible, if anything: none (NaN log-odds), or a finite log-odds, a finite
/// height and a finite variance of 0 or more.
fn ceiling_problem(c: &Ceiling) -> Option<String> {
    if !c.is_some() {
        return None;
    }
    if c.log_odds.is_infinite() {
        return Some(format!(
            "ceiling log-odds {} is infinite (expected NaN or a finite number)",
            c.log_odds
        ));
    }
    if !c.z_m.is_finite() {
        return Some(format!("ceiling height {} m is not a finite number", c.z_m));
    }
    if !(c.var_m2.is_finite() && c.var_m2 >= 0.0) {
        return Some(format!(
            "ceiling variance {} m^2 is not a finite variance of 0 or more",
            c.var_m2
        ));
    }
    if !(c.clear_m.is_finite() || c.clear_m == f32::NEG_INFINITY) {
        return Some(format!(
            "ceiling clear height {} m is not a finite number or -inf",
            c.clear_m
        ));
    }
    None
}

/// What makes a cell's values impossible for a map to hold, if anything: the log-odds is NaN (never observed)
/// or finite; the elevation is finite; the variance is NaN-free and not negative (infinite: no estimate).
fn cell_problem(c: &Cell) -> Option<String> {
    if c.log_odds.is_infinite() {
        return Some(format!(
            "log-odds {} is infinite (expected NaN or a finite number)",
            c.log_odds
        ));
    }
    if !c.mean_m.is_finite() {
        return Some(format!("elevation {} m is not a finite number", c.mean_m));
    }
    if c.var_m2.is_nan() || c.var_m2 < 0.0 {
        return Some(format!(
            "elevation variance {} m^2 is not a variance (expected 0 or more, or infinite for no estimate)",
            c.var_m2
        ));
    }
    None
}

#[cfg(test)]
mod tests;
