//! The recommended preset's rules are fixed at compile time in the map's hot loop (`map/rule_set.rs`); the
//! same rules read from the options at run time give the same map, bit for bit. The options are made to take
//! the run-time path by a depth bound no surface reaches (`free_space_max_depth_m` of a kilometre), which
//! drops no sample.

mod common;

use common::shared_file;
use nalgebra::{Point3, Vector3};
use oeg::{Map, MapConfig, MapPreset, ModelOptions, Ray, RobotProfile, Scan, SensorModel};

/// A depth under a surface that no free sample of these scans lies at.
const UNREACHED_DEPTH_M: f32 = 1000.0;

fn map_of(model: ModelOptions, scans: &[Scan]) -> Map {
    let mut config = MapConfig::new(0.05);
    config.model = model;
    let mut map = Map::new(config).expect("valid");
    for scan in scans {
        map.integrate(scan).expect("integrated");
    }
    map
}

/// Every cell and every ceiling of `a` and `b`, compared bit for bit.
fn assert_same_cells(a: &Map, b: &Map) {
    assert_eq!(a.num_observed_cells(), b.num_observed_cells());
    assert_eq!(a.num_ceilings(), b.num_ceilings());
    for (index, cell) in a.observed_cells() {
        let other = b.cell(index);
        assert_eq!(
            [cell.log_odds, cell.mean_m, cell.var_m2].map(f32::to_bits),
            [other.log_odds, other.mean_m, other.var_m2].map(f32::to_bits),
            "cell {index:?}"
        );
        let bits = |m: &Map| {
            m.ceiling(index)
                .map(|c| [c.z_m, c.var_m2, c.log_odds, c.clear_m].map(f32::to_bits))
        };
        assert_eq!(bits(a), bits(b), "ceiling over {index:?}");
        assert_eq!(
            a.ceiling(index).map(|c| c.seen_from),
            b.ceiling(index).map(|c| c.seen_from)
        );
    }
}

/// The recommended preset's map of `scans`, with its rules fixed and read from the options.
fn assert_fixed_rules_map_as_read_ones(scans: &[Scan]) -> Map {
    let robust = MapPreset::Robust.model(&RobotProfile::default());
    let read = ModelOptions {
        free_space_max_depth_m: Some(UNREACHED_DEPTH_M),
        ..robust
    };
    let fixed = map_of(robust, scans);
    assert_same_cells(&fixed, &map_of(read, scans));
    fixed
}

/// A sensor 0.3 m over level ground, under a board whose underside is 0.42 m high over x in [2, 3] m: rising
/// beams hit its underside, level and falling ones pass under it onto the ground or into a wall, some return
/// nothing; the sensor moves between scans, so the second scan's samples read what the first left.
fn board_scans() -> Vec<Scan> {
    (0..4)
        .map(|k| {
            let origin = Point3::new(0.4 * f64::from(k), 0.1 * f64::from(k), 0.3);
            let mut scan = Scan::new(origin, SensorModel::laser());
            scan.rays = (0..6_000)
                .map(|i| {
                    let azimuth = (i % 600) as f32 / 600.0 * 1.2 - 0.6;
                    let elevation = (i / 600) as f32 / 10.0 * 0.3 - 0.2;
                    let dir = Vector3::new(
                        elevation.cos() * azimuth.cos(),
                        elevation.cos() * azimuth.sin(),
                        elevation.sin(),
                    );
                    let x0 = origin.x as f32;
                    let to_ground = if dir.z < 0.0 { -0.3 / dir.z } else { f32::INFINITY };
                    let to_board = if dir.z > 0.0 { 0.12 / dir.z } else { f32::INFINITY };
                    let board_x = x0 + to_board * dir.x;
                    let to_wall = (8.0 - x0) / dir.x;
                    if i % 17 == 0 {
                        Ray::no_return(dir * 5.0)
                    } else if (2.0..3.0).contains(&board_x) && to_board < to_wall {
                        Ray::hit(dir * to_board)
                    } else if to_ground < to_wall {
                        Ray::hit(dir * to_ground)
                    } else {
                        Ray::hit(dir * to_wall)
                    }
                })
                .collect();
            scan
        })
        .collect()
}

#[test]
fn the_fixed_rules_map_a_board_over_level_ground_as_the_options_do() {
    let map = assert_fixed_rules_map_as_read_ones(&board_scans());
    assert!(map.num_observed_cells() > 1000);
    assert!(map.num_ceilings() > 20, "{} ceilings", map.num_ceilings());
}

#[test]
fn the_fixed_rules_map_the_shared_real_scans_as_the_options_do() {
    let Some(path) = shared_file("3dtk_frames.graph") else {
        return;
    };
    let scans = oeg::read_graph_scans(&path, SensorModel::laser()).expect("readable");
    let map = assert_fixed_rules_map_as_read_ones(&scans);
    assert!(map.num_ceilings() > 0);
}
