//! The map file's tests.

use nalgebra::Point3;

use super::*;
use crate::geometry::CellIndex;
use crate::scan::Scan;
use crate::sensor::SensorModel;

fn small_map() -> Map {
    let mut map = Map::new(MapConfig::new(0.1)).expect("valid");
    let mut scan = Scan::new(Point3::new(0.0, 0.0, 0.5), SensorModel::laser());
    for k in 0..50 {
        let a = f64::from(k) * 0.1;
        scan.push_hit(Point3::new(3.0 * a.cos(), 3.0 * a.sin(), 0.2));
    }
    map.integrate(&scan).expect("integrated");
    map
}

fn temp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("oeg-mapfile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir.join(name)
}

#[test]
fn saved_maps_load_back_identically() {
    let map = small_map();
    let path = temp("m.oeg");
    save_map(&map, &path).expect("saved");
    let back = load_map(&path).expect("loaded");
    assert_eq!(back.config(), map.config());
    assert_eq!(back.num_scans(), 1);
    assert_eq!(back.totals(), map.totals());
    assert_eq!(back.num_observed_cells(), map.num_observed_cells());
    for (c, cell) in map.observed_cells() {
        let b = back.cell(c);
        assert_eq!(b.log_odds.to_bits(), cell.log_odds.to_bits());
        assert_eq!(b.mean_m.to_bits(), cell.mean_m.to_bits());
        assert_eq!(b.var_m2.to_bits(), cell.var_m2.to_bits());
    }
    assert!(!back.cell(CellIndex::new(1000, 1000)).is_observed());
    // Same map, same bytes.
    assert_eq!(map_to_bytes(&back), map_to_bytes(&map));
    assert_eq!(
        read_map_header(&path).expect("header").num_tiles,
        map.tiles().count() as u64
    );
}

#[test]
fn truncated_and_corrupt_files_are_errors() {
    let bytes = map_to_bytes(&small_map());
    let p = Path::new("m.oeg");
    for cut in [0, 7, 12, 20, 100, bytes.len() / 2, bytes.len() - 1] {
        let err = parse(p, &bytes[..cut], Some(1 << 30))
            .expect_err("truncated")
            .to_string();
        assert!(err.starts_with("m.oeg: at byte"), "cut {cut}: {err}");
    }
    let mut flipped = bytes.clone();
    let k = flipped.len() - 100;
    flipped[k] ^= 0x40;
    let err = parse(p, &flipped, Some(1 << 30))
        .expect_err("corrupt")
        .to_string();
    assert!(err.contains("checksum mismatch"), "{err}");
    let mut wrong = bytes.clone();
    wrong[0] = b'X';
    assert!(
        parse(p, &wrong, Some(1 << 30))
            .expect_err("magic")
            .to_string()
            .contains("magic")
    );
    let mut future = bytes;
    future[8] = 9;
    assert!(
        parse(p, &future, Some(1 << 30))
            .expect_err("version")
            .to_string()
            .contains("version 9")
    );
}

/// A map file whose header and tile records are `tiles`, each `(ti, tj, cell)`, with a valid checksum.
fn forged(config: MapConfig, tiles: &[(i32, i32, Cell)]) -> Vec<u8> {
    let header = MapFileHeader {
        config,
        tile_size: TILE_SIZE as u32,
        num_tiles: tiles.len() as u64,
        num_ceiling_tiles: 0,
        num_scans: 1,
        totals: IntegrationStats::default(),
        written_by: "a test".into(),
        file_version: 0,
    };
    let json = serde_json::to_vec(&header).expect("json");
    let mut out = container::container_prefix_bytes(MAGIC, FORMAT_VERSION, &json);
    for (ti, tj, cell) in tiles {
        out.extend_from_slice(&ti.to_le_bytes());
        out.extend_from_slice(&tj.to_le_bytes());
        for _ in 0..TILE_CELLS {
            for v in [cell.log_odds, cell.mean_m, cell.var_m2] {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    container::seal_container(&mut out);
    out
}

const GROUND: Cell = Cell {
    log_odds: -1.0,
    mean_m: 0.0,
    var_m2: 1e-4,
};

#[test]
fn a_tile_index_beyond_the_grid_is_an_error_not_a_panic() {
    let p = Path::new("far.oeg");
    for (ti, tj) in [(1 << 25, 0), (0, -(1 << 25) - 1), (i32::MAX, i32::MIN)] {
        let bytes = forged(MapConfig::new(0.1), &[(ti, tj, GROUND)]);
        let err = parse(p, &bytes, Some(1 << 30))
            .expect_err("out of the grid")
            .to_string();
        assert!(
            err.starts_with("far.oeg: at byte") && err.contains("outside the grid"),
            "{err}"
        );
    }
    let edge = forged(MapConfig::new(0.1), &[((1 << 25) - 1, -(1 << 25), GROUND)]);
    assert!(
        parse(p, &edge, Some(1 << 30)).is_ok(),
        "the outermost tiles are fine"
    );
}

#[test]
fn a_map_file_cannot_raise_the_memory_limit_it_is_read_under() {
    // Two tiles 2^24 tiles apart: an index of 2^48 slots. The header asks for an unlimited budget.
    let config = MapConfig {
        memory_limit_bytes: u64::MAX,
        ..MapConfig::new(0.1)
    };
    let bytes = forged(config, &[(0, 0, GROUND), (1 << 24, 1 << 24, GROUND)]);
    let p = Path::new("wide.oeg");
    let started = std::time::Instant::now();
    let err = parse(p, &bytes, Some(crate::DEFAULT_MEMORY_LIMIT_BYTES)).expect_err("over the limit");
    assert!(err.to_string().contains("memory limit"), "{err}");
    assert!(started.elapsed().as_secs_f64() < 5.0, "refused before allocating");
    let (_, map) = parse(p, &forged(config, &[(0, 0, GROUND)]), Some(1 << 30)).expect("small map");
    let map = map.expect("built");
    assert_eq!(
        map.config().memory_limit_bytes,
        1 << 30,
        "the caller's limit, not the file's"
    );
}

#[test]
fn non_finite_cell_values_are_refused_with_their_place() {
    let p = Path::new("bad.oeg");
    let bad = [
        Cell {
            mean_m: f32::INFINITY,
            ..GROUND
        },
        Cell {
            mean_m: f32::NAN,
            ..GROUND
        },
        Cell {
            var_m2: f32::NAN,
            ..GROUND
        },
        Cell {
            var_m2: -1.0,
            ..GROUND
        },
        Cell {
            log_odds: f32::INFINITY,
            ..GROUND
        },
    ];
    for cell in bad {
        let bytes = forged(MapConfig::new(0.1), &[(0, 0, GROUND), (1, 0, cell)]);
        let err = parse(p, &bytes, Some(1 << 30)).expect_err("bad cell").to_string();
        assert!(err.contains("tile 1, cell 0"), "{cell:?}: {err}");
    }
    for fine in [
        Cell::UNOBSERVED,
        Cell {
            var_m2: f32::INFINITY,
            ..GROUND
        },
    ] {
        let bytes = forged(MapConfig::new(0.1), &[(0, 0, fine)]);
        assert!(parse(p, &bytes, Some(1 << 30)).is_ok(), "{fine:?}");
    }
}

/// A map with ground under a board whose top was hit once: one ceiling ([`crate::OverheadHits::Ceiling`]).
fn map_with_a_ceiling() -> Map {
    let model = crate::MapPreset::Robust.model(&crate::RobotProfile::default());
    let mut map = Map::new(MapConfig {
        model,
        ..MapConfig::new(0.05)
    })
    .expect("valid");
    let mut ground = Scan::new(Point3::new(0.025, 0.025, 0.25), SensorModel::laser());
    ground.push_hit(Point3::new(2.025, 0.025, 0.0));
    let mut top = Scan::new(Point3::new(0.025, 0.025, 0.45), SensorModel::laser());
    top.push_hit(Point3::new(2.025, 0.025, 0.34));
    map.integrate(&ground).expect("integrated");
    map.integrate(&top).expect("integrated");
    assert_eq!(map.num_ceilings(), 1);
    map
}

#[test]
fn a_map_with_a_ceiling_layer_is_version_3_and_loads_back_identically() {
    let map = map_with_a_ceiling();
    let bytes = map_to_bytes(&map);
    assert_eq!(bytes[8..12], 3u32.to_le_bytes());
    let p = Path::new("ceiling.oeg");
    let back = map_from_bytes(p, &bytes, crate::DEFAULT_MEMORY_LIMIT_BYTES).expect("loaded");
    let c = map.geometry().cell_of(2.025, 0.025).expect("cell");
    assert_eq!(back.ceiling(c), map.ceiling(c));
    assert!(back.ceiling(c).is_some_and(|c| c.seen_from == SeenFrom::Above));
    assert!(map_to_bytes(&back) == bytes, "same map, same bytes");
    // Without a ceiling the file is version 1, as before the layer existed.
    assert_eq!(map_to_bytes(&small_map())[8..12], 1u32.to_le_bytes());

    // Where the one ceiling's record starts.
    let prefix = container::read_container_prefix(p, &bytes, MAGIC, &[3], "a map").expect("prefix");
    let k = crate::storage::offset_in_tile(c);
    let ceilings_start = prefix.body_start + map.tiles().count() * TILE_RECORD_BYTES;
    let at = ceilings_start + 8 + k * 17;
    let forge = |offset: usize, value: &[u8]| {
        let mut b = bytes[..bytes.len() - 8].to_vec();
        b[offset..offset + value.len()].copy_from_slice(value);
        container::seal_container(&mut b);
        b
    };
    for (offset, value, expected) in [
        (at + 12, vec![7u8], "side 7 is not 0 (above)"),
        (at, f32::INFINITY.to_le_bytes().to_vec(), "ceiling height inf m"),
        (at + 4, (-1.0f32).to_le_bytes().to_vec(), "ceiling variance -1"),
        (
            at + 8,
            f32::INFINITY.to_le_bytes().to_vec(),
            "ceiling log-odds inf",
        ),
        (
            at + 13,
            f32::NAN.to_le_bytes().to_vec(),
            "ceiling clear height NaN",
        ),
    ] {
        let err = map_from_bytes(p, &forge(offset, &value), 1 << 30)
            .expect_err("bad ceiling")
            .to_string();
        assert!(
            err.contains(&format!("ceiling tile 0, cell {k}")) && err.contains(expected),
            "{err}"
        );
    }
    // A version 1 file cannot declare a ceiling layer; a truncated one names the sizes.
    let v1 = forge(8, &1u32.to_le_bytes());
    let err = map_from_bytes(p, &v1, 1 << 30)
        .expect_err("v1 with ceilings")
        .to_string();
    assert!(err.contains("version 1 header declares 1 ceiling tiles"), "{err}");
    let err = map_from_bytes(p, &bytes[..bytes.len() - 100], 1 << 30)
        .expect_err("truncated")
        .to_string();
    assert!(err.contains("1 ceiling tiles"), "{err}");

    // The same map as version 2 wrote it (no clear height): read, with none.
    let mut v2 = bytes[..ceilings_start].to_vec();
    v2[8..12].copy_from_slice(&2u32.to_le_bytes());
    v2.extend_from_slice(&bytes[ceilings_start..ceilings_start + 8]);
    for record in bytes[ceilings_start + 8..bytes.len() - 8].chunks(17) {
        v2.extend_from_slice(&record[..13]);
    }
    container::seal_container(&mut v2);
    let old = map_from_bytes(p, &v2, 1 << 30).expect("version 2 loads");
    assert_eq!(parse(p, &v2, None).expect("header").0.file_version, 2);
    assert_eq!(parse(p, &bytes, None).expect("header").0.file_version, 3);
    let expected = map.ceiling(c).map(|c| Ceiling {
        clear_m: f32::NEG_INFINITY,
        ..c
    });
    assert_eq!(old.ceiling(c), expected);
}
