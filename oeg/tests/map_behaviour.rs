//! The map's behaviour through its public API: Algorithm 1 end to end on small hand-made scans.

use nalgebra::{Point3, Vector3};
use oeg::{
    CellIndex, CellRegion, FreeSpaceElevation, Map, MapConfig, ModelOptions, Ray, RobotProfile, Scan,
    ScanHitElevation, SensorModel, Traversability, TraversabilityRule,
};
use proptest::prelude::*;

#[path = "common/scans.rs"]
mod scans;

use scans::{cell, hit_from_above, map_with, scan_of};

#[test]
fn a_hit_marks_its_cell_occupied_at_its_height_and_clears_the_way() {
    let mut map = map_with(0.1, ModelOptions::default());
    let scan = scan_of(Point3::new(0.05, 0.05, 0.5), &[(2.05, 0.05, 0.2)]);
    let stats = map.integrate(&scan).expect("integrated");
    assert_eq!(stats.num_rays, 1);
    // 0.05 .. 2.05 along x: cells 0..=20, plus the cells up to 3 sigma behind the hit (same cell here).
    assert_eq!(stats.num_cells_updated, 21);
    let hit = map.cell(cell(&map, 2.05, 0.05));
    let e = hit.elevation().expect("elevation");
    assert!((e.mean_m - 0.2).abs() < 0.01, "{e:?}");
    // sigma_t = the laser's 12 mm range error.
    assert!((e.var_m2 - 0.012f32 * 0.012).abs() < 1e-6, "{e:?}");
    assert_eq!(map.is_occupied(cell(&map, 2.05, 0.05)), Some(true));
    for x in [0.05, 0.5, 1.0, 1.85] {
        let c = cell(&map, x, 0.05);
        assert_eq!(map.is_occupied(c), Some(false), "x = {x}");
        // Zero mode: free samples are the measurement h = 0.
        assert_eq!(map.cell(c).elevation().map(|e| e.mean_m), Some(0.0));
    }
    assert!(!map.cell(cell(&map, 2.5, 0.05)).is_observed());
    assert!(!map.cell(cell(&map, 1.0, 0.5)).is_observed());
}

#[test]
fn several_rays_of_one_scan_update_a_cell_once_and_occupied_wins() {
    let opts = ModelOptions::default();
    let mut once = map_with(0.2, opts);
    once.integrate(&scan_of(Point3::new(0.1, 0.1, 0.5), &[(2.1, 0.1, 0.1)]))
        .expect("integrated");
    let mut many = map_with(0.2, opts);
    // Three hits in the same cell, and a ray that passes over that cell to hit farther away.
    let targets = [
        (2.1, 0.1, 0.1),
        (2.12, 0.12, 0.15),
        (2.08, 0.15, 0.12),
        (4.1, 0.1, 0.0),
    ];
    many.integrate(&scan_of(Point3::new(0.1, 0.1, 0.5), &targets))
        .expect("integrated");
    let c = cell(&once, 2.1, 0.1);
    assert_eq!(
        once.cell(c).log_odds,
        many.cell(c).log_odds,
        "one update per scan"
    );
    assert_eq!(
        many.is_occupied(c),
        Some(true),
        "occupied wins over the ray that passed"
    );
    // The highest point the scan saw in the cell is its elevation measurement.
    let e = many.cell(c).elevation().expect("elevation");
    assert!((e.mean_m - 0.15).abs() < 1e-3, "{e:?}");
}

#[test]
fn no_return_rays_only_clear() {
    let mut map = map_with(
        0.1,
        ModelOptions {
            no_return_clear_range_m: Some(3.0),
            ..ModelOptions::default()
        },
    );
    let mut scan = Scan::new(Point3::new(0.05, 0.05, 0.3), SensorModel::laser());
    scan.rays.push(Ray::no_return(Vector3::new(1.0, 0.0, 0.0)));
    map.integrate(&scan).expect("integrated");
    let observed: Vec<_> = map.observed_cells().collect();
    assert_eq!(observed.len(), 31, "0.05 m to 3.05 m");
    assert!(observed.iter().all(|(c, _)| map.is_occupied(*c) == Some(false)));
    assert!(!map.cell(cell(&map, 3.2, 0.05)).is_observed());
}

#[test]
fn hits_beyond_the_maximum_range_only_clear_up_to_it() {
    let mut map = map_with(
        0.1,
        ModelOptions {
            max_range_m: Some(1.0),
            ..ModelOptions::default()
        },
    );
    map.integrate(&scan_of(Point3::new(0.05, 0.05, 0.3), &[(5.05, 0.05, 0.3)]))
        .expect("integrated");
    assert_eq!(map.num_observed_cells(), 11);
    assert!(
        map.observed_cells()
            .all(|(c, _)| map.is_occupied(c) == Some(false))
    );
}

/// The paper's Fig. 5 and 6: a person stands 2 m ahead for several scans, then leaves; the laser, 0.4 m up,
/// then sees the floor 4 m ahead through the place the person stood.
fn person_walks_through(mode: FreeSpaceElevation) -> Map {
    let mut map = map_with(
        0.1,
        ModelOptions {
            free_space_elevation: mode,
            ..ModelOptions::default()
        },
    );
    let origin = Point3::new(0.05, 0.05, 0.4);
    let person: Vec<_> = (0..10).map(|k| (2.05, 0.05, 0.1 + 0.04 * f64::from(k))).collect();
    for _ in 0..6 {
        map.integrate(&scan_of(origin, &person)).expect("integrated");
    }
    let c = cell(&map, 2.05, 0.05);
    assert_eq!(
        map.is_occupied(c),
        Some(true),
        "{mode:?}: the person is an obstacle"
    );
    let e = map.cell(c).elevation().expect("elevation");
    assert!(e.mean_m > 0.4, "{mode:?}: the person's height is mapped: {e:?}");
    for _ in 0..12 {
        map.integrate(&scan_of(origin, &[(4.05, 0.05, 0.0)]))
            .expect("integrated");
    }
    map
}

#[test]
fn issue_dynamic_obstacle_is_cleared_in_zero_and_ray_bound_modes() {
    for mode in [FreeSpaceElevation::Zero, FreeSpaceElevation::RayBound] {
        let map = person_walks_through(mode);
        let c = cell(&map, 2.05, 0.05);
        assert_eq!(map.is_occupied(c), Some(false), "{mode:?}: the person is gone");
        let e = map.cell(c).elevation().expect("elevation");
        // The ray to the floor passes the cell at about 0.2 m: zero mode is back on the ground; ray_bound is
        // capped by the beam.
        let limit = if mode == FreeSpaceElevation::Zero {
            0.01
        } else {
            0.25
        };
        assert!(
            e.mean_m < limit,
            "{mode:?}: elevation back near the ground: {e:?}"
        );
        assert_eq!(
            map.traversability(c, &RobotProfile::default(), TraversabilityRule::Absolute),
            Traversability::Free
        );
    }
}

#[test]
fn skip_mode_keeps_the_height_but_frees_the_cell() {
    let map = person_walks_through(FreeSpaceElevation::Skip);
    let c = cell(&map, 2.05, 0.05);
    assert_eq!(map.is_occupied(c), Some(false));
    assert!(map.cell(c).elevation().expect("elevation").mean_m > 0.4);
}

#[test]
fn bad_resolutions_and_scans_are_errors_not_panics() {
    for r in [0.0, -0.05, f64::NAN] {
        let err = Map::new(MapConfig::new(r)).expect_err("bad resolution");
        assert!(err.to_string().contains("resolution_m"), "{err}");
    }
    let mut map = map_with(0.1, ModelOptions::default());
    let mut scan = scan_of(Point3::new(0.0, 0.0, 0.3), &[(1.0, 0.0, 0.0)]);
    scan.rays.push(Ray::hit(Vector3::new(f32::INFINITY, 0.0, 0.0)));
    let err = map.integrate(&scan).expect_err("infinite ray");
    assert!(err.to_string().contains("ray 1"), "{err}");
    assert_eq!(map.num_observed_cells(), 0, "a rejected scan changes nothing");
}

#[test]
fn a_map_over_its_memory_limit_is_an_error() {
    let config = MapConfig {
        memory_limit_bytes: 1 << 20,
        ..MapConfig::new(0.05)
    };
    let mut map = Map::new(config).expect("valid");
    // A 6 m ray at 0.05 m touches 2 tiles of 48 KiB plus their scratch (208 KiB each): fine. A 500 m ray is
    // not.
    map.integrate(&scan_of(Point3::new(0.0, 0.0, 0.3), &[(6.0, 0.0, 0.0)]))
        .expect("fits");
    let err = map
        .integrate(&scan_of(Point3::new(0.0, 0.0, 0.3), &[(500.0, 300.0, 0.0)]))
        .expect_err("too big");
    assert!(matches!(err, oeg::Error::MemoryLimit { .. }), "{err}");
    assert!(map.memory_bytes() <= 1 << 20);
}

#[test]
fn a_raster_counts_against_the_same_budget_as_the_map() {
    let config = MapConfig {
        memory_limit_bytes: 1 << 20,
        ..MapConfig::new(0.05)
    };
    let mut map = Map::new(config).expect("valid");
    map.integrate(&scan_of(Point3::new(0.0, 0.0, 0.3), &[(6.0, 0.0, 0.0)]))
        .expect("fits");
    let held = map.memory_bytes();
    assert!(held > 0 && held < 1 << 20);
    // A square raster of f32 whose own bytes fit the limit but not beside the map: refused.
    let side = (((1u64 << 20) - held / 2) as f64 / 4.0).sqrt() as i32;
    let region =
        CellRegion::from_corners(CellIndex::new(0, 0), CellIndex::new(side - 1, side - 1)).expect("region");
    assert!(region.num_cells() * 4 <= 1 << 20);
    let err = map
        .layer(oeg::LayerKind::ElevationM, region)
        .expect_err("over the budget");
    assert!(matches!(err, oeg::Error::MemoryLimit { .. }), "{err}");
    let small = CellRegion::from_corners(CellIndex::new(0, 0), CellIndex::new(99, 99)).expect("region");
    assert!(map.layer(oeg::LayerKind::ElevationM, small).is_ok());
}

#[test]
fn the_per_scan_scratch_is_counted_apart_sized_by_the_rules_and_can_be_given_back() {
    // The scratch a map keeps for the next scan (every tile a scan touched) is not part of the map's memory,
    // and costs 20 bytes a cell under the paper's rules, 32 (and 48 a cell hit) under rules that judge samples.
    let scan = scan_of(
        Point3::new(0.0, 0.0, 0.3),
        &[(3.0, 0.0, 0.0), (0.0, 3.0, 0.0), (2.0, 2.0, 0.1)],
    );
    let mut map = map_with(0.01, ModelOptions::default());
    map.integrate(&scan).expect("ok");
    assert_eq!(map.scratch_cell_bytes(), 20);
    let (map_bytes, scratch_bytes) = (map.memory_bytes(), map.scratch_bytes());
    assert!(map_bytes > map.cell_bytes() && map_bytes < map.cell_bytes() * 11 / 10);
    // The scratch holds the tiles the scan touched, as the cells do: 20 bytes a cell against 12.
    assert!(
        scratch_bytes > map.cell_bytes() * 20 / 12,
        "{scratch_bytes} bytes of scratch, cells {}",
        map.cell_bytes()
    );
    let cells: Vec<_> = map.observed_cells().collect();
    map.release_scratch();
    assert_eq!(map.memory_bytes(), map_bytes);
    assert!(map.scratch_bytes() < 1024, "{}", map.scratch_bytes());
    assert_eq!(map.observed_cells().collect::<Vec<_>>(), cells);
    map.integrate(&scan_of(Point3::new(0.0, 0.0, 0.3), &[(1.0, 1.0, 0.0)]))
        .expect("integrates again");

    let mut robust = map_with(0.01, oeg::MapPreset::Robust.model(&RobotProfile::default()));
    robust.integrate(&scan).expect("ok");
    assert_eq!(robust.scratch_cell_bytes(), 32);
    assert!(robust.scratch_bytes() > robust.cell_bytes() * 32 / 12 + 3 * 48);
}

#[test]
fn memory_follows_what_was_seen_not_the_extent() {
    // A robot crossing a 300 m x 170 m area at 0.05 m: a dense grid would need 6000 x 3400 x 12 = 245 MB.
    let mut map = map_with(0.05, ModelOptions::default());
    for k in 0..60 {
        let x = -150.0 + 5.0 * f64::from(k);
        let y = -85.0 + 2.8 * f64::from(k);
        map.integrate(&scan_of(
            Point3::new(x, y, 0.5),
            &[(x + 3.0, y, 0.0), (x, y + 3.0, 0.0)],
        ))
        .expect("ok");
    }
    let dense_bytes = 6000u64 * 3400 * 12;
    assert!(
        map.memory_bytes() * 20 < dense_bytes,
        "{} bytes",
        map.memory_bytes()
    );
    // The count is honest: at least 12 bytes per cell of every allocated tile.
    assert!(map.memory_bytes() >= map.cell_bytes() && map.cell_bytes() >= map.num_observed_cells() * 12);
}

#[test]
fn the_terrain_rule_measures_steps_against_the_neighbours() {
    // A plane at 0.5 m height (a plateau) seen from above: absolute says blocked, terrain says traversable.
    let mut map = map_with(0.1, ModelOptions::default());
    let mut scan = Scan::new(Point3::new(0.0, 0.0, 1.5), SensorModel::laser());
    for i in -10..=10 {
        for j in -10..=10 {
            scan.push_hit(Point3::new(
                0.05 + 0.1 * f64::from(i),
                0.05 + 0.1 * f64::from(j),
                0.5,
            ));
        }
    }
    for _ in 0..2 {
        map.integrate(&scan).expect("integrated");
    }
    let c = cell(&map, 0.05, 0.05);
    let p = RobotProfile::default();
    assert_eq!(
        map.traversability(c, &p, TraversabilityRule::Absolute),
        Traversability::Blocked
    );
    assert_eq!(
        map.traversability(c, &p, TraversabilityRule::Terrain),
        Traversability::Traversable
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Whatever scans come in, every observed cell's log-odds stays within the clamping bounds.
    #[test]
    fn log_odds_stay_within_bounds(
        points in prop::collection::vec((-4.0f64..4.0, -4.0f64..4.0, -0.5f64..1.5), 1..60),
        origin in (-1.0f64..1.0, -1.0f64..1.0, 0.0f64..1.0),
        repeats in 1usize..5,
        stereo in any::<bool>(),
    ) {
        let opts = ModelOptions::default();
        let mut map = map_with(0.1, opts);
        let mut scan = scan_of(Point3::new(origin.0, origin.1, origin.2), &points);
        if stereo {
            scan.sensor = SensorModel::stereo();
        }
        for _ in 0..repeats {
            map.integrate(&scan).expect("integrated");
        }
        for (_, c) in map.observed_cells() {
            prop_assert!(c.log_odds >= opts.log_odds_min && c.log_odds <= opts.log_odds_max, "{:?}", c);
            prop_assert!(c.var_m2 > 0.0, "{:?}", c);
        }
    }

    /// Without process noise a Kalman fusion never increases the variance (eq. 9).
    #[test]
    fn fusion_never_increases_variance(mu in -5.0f32..5.0, var in 1e-6f32..10.0, h in -5.0f32..5.0, s2 in 1e-6f32..10.0) {
        let prior = oeg::Elevation { mean_m: mu, var_m2: var };
        let post = oeg::kalman_fuse(Some(prior), h, s2, 0.0);
        prop_assert!(post.var_m2 <= var && post.var_m2 <= s2 * (1.0 + 1e-6));
        prop_assert!(post.mean_m >= mu.min(h) - 1e-4 && post.mean_m <= mu.max(h) + 1e-4);
    }

    /// Eq. 7 keeps any sequence of updates inside the bounds.
    #[test]
    fn clamped_updates_stay_in_bounds(deltas in prop::collection::vec(-5.0f32..5.0, 0..50)) {
        let mut l = 0.0;
        for d in deltas {
            l = oeg::update_log_odds(l, d, -2.0, 3.5);
            prop_assert!((-2.0..=3.5).contains(&l));
        }
    }
}

/// A push-broom laser sees a 5 cm curb, then its beams pass over it on their way to the ground beyond.
fn curb_then_overpass(rule: oeg::FreeSpaceOccupancy) -> Map {
    let mut map = map_with(
        0.05,
        ModelOptions {
            free_space_occupancy: rule,
            ..ModelOptions::default()
        },
    );
    for _ in 0..5 {
        map.integrate(&scan_of(Point3::new(0.0, 0.025, 0.4), &[(2.025, 0.025, 0.05)]))
            .expect("integrated");
    }
    for k in 0..30 {
        let x = 2.5 + 0.02 * f64::from(k);
        map.integrate(&scan_of(Point3::new(0.0, 0.025, 0.4), &[(x, 0.025, 0.0)]))
            .expect("integrated");
    }
    map
}

#[test]
fn issue_beams_passing_over_a_curb_erase_it_under_the_papers_rule_only() {
    let p = RobotProfile::default();
    let paper = curb_then_overpass(oeg::FreeSpaceOccupancy::Always);
    let c = cell(&paper, 2.025, 0.025);
    assert_eq!(
        paper.traversability(c, &p, TraversabilityRule::Absolute),
        Traversability::Free,
        "erased"
    );
    let bounded = curb_then_overpass(oeg::FreeSpaceOccupancy::BelowElevation);
    assert_eq!(
        bounded.traversability(c, &p, TraversabilityRule::Absolute),
        Traversability::Blocked,
        "kept"
    );
}

#[test]
fn below_elevation_still_clears_people() {
    let mut map = map_with(
        0.1,
        ModelOptions {
            free_space_occupancy: oeg::FreeSpaceOccupancy::BelowElevation,
            ..ModelOptions::default()
        },
    );
    let origin = Point3::new(0.05, 0.05, 0.4);
    let person: Vec<_> = (0..10).map(|k| (2.05, 0.05, 0.1 + 0.04 * f64::from(k))).collect();
    for _ in 0..6 {
        map.integrate(&scan_of(origin, &person)).expect("integrated");
    }
    for _ in 0..12 {
        map.integrate(&scan_of(origin, &[(4.05, 0.05, 0.0)]))
            .expect("integrated");
    }
    assert_eq!(map.is_occupied(cell(&map, 2.05, 0.05)), Some(false));
}

/// A board's top at 0.34 m seen from above, then a laser low on the robot whose beams pass under the board to
/// the ground beyond it, under the given depth limit.
fn board_then_underpass(max_depth_m: Option<f32>) -> Map {
    let mut map = map_with(
        0.1,
        ModelOptions {
            free_space_occupancy: oeg::FreeSpaceOccupancy::BelowElevation,
            free_space_max_depth_m: max_depth_m,
            ..ModelOptions::default()
        },
    );
    for _ in 0..5 {
        map.integrate(&scan_of(Point3::new(0.05, 0.05, 0.45), &[(2.05, 0.05, 0.34)]))
            .expect("integrated");
    }
    // From 0.25 m, level: 9 cm under the board's top.
    for _ in 0..30 {
        map.integrate(&scan_of(Point3::new(0.05, 0.05, 0.25), &[(4.05, 0.05, 0.25)]))
            .expect("integrated");
    }
    map
}

#[test]
fn free_samples_far_below_a_surface_leave_it_only_with_a_depth_limit() {
    let p = RobotProfile::default();
    let paper = board_then_underpass(None);
    let c = cell(&paper, 2.05, 0.05);
    assert_eq!(
        paper.traversability(c, &p, TraversabilityRule::Absolute),
        Traversability::Free,
        "the beams under the board cleared it"
    );
    let limited = board_then_underpass(Some(0.05));
    assert_eq!(
        limited.traversability(c, &p, TraversabilityRule::Absolute),
        Traversability::Blocked,
        "9 cm under the top is deeper than 5 cm: kept"
    );
    let deep = board_then_underpass(Some(0.1));
    assert_eq!(
        deep.traversability(c, &p, TraversabilityRule::Absolute),
        Traversability::Free,
        "within 10 cm: the beams count again"
    );
}

#[test]
fn many_noisy_hits_in_a_cell_bias_the_highest_upwards_but_not_the_weighted_mean() {
    // A stereo-like scan: 21 hits on flat ground at z = 0 inside one 0.2 m cell, their heights spread evenly
    // over +-5 cm (zero-mean noise). The paper's highest hit reads 5 cm, a step that blocks the Pioneer; the
    // weighted mean reads the ground.
    let targets: Vec<(f64, f64, f64)> = (0..21)
        .map(|k| (2.1, 0.1, -0.05 + 0.005 * f64::from(k)))
        .collect();
    let scan = scan_of(Point3::new(0.1, 0.1, 0.5), &targets);
    let elevation_with = |rule| {
        let mut map = map_with(
            0.2,
            ModelOptions {
                scan_hit_elevation: rule,
                ..ModelOptions::default()
            },
        );
        map.integrate(&scan).expect("integrated");
        let c = cell(&map, 2.1, 0.1);
        (
            map.cell(c).elevation().expect("elevation"),
            map.traversability(c, &RobotProfile::default(), TraversabilityRule::Absolute),
        )
    };
    let (highest, class) = elevation_with(ScanHitElevation::Highest);
    assert!((highest.mean_m - 0.05).abs() < 1e-4, "{highest:?}");
    assert_eq!(class, Traversability::Blocked);
    let (mean, class) = elevation_with(ScanHitElevation::WeightedMean);
    assert!(mean.mean_m.abs() < 1e-4, "{mean:?}");
    assert!(
        mean.var_m2 < highest.var_m2 / 20.0,
        "21 measurements: {mean:?} against {highest:?}"
    );
    assert_eq!(class, Traversability::Traversable);
}

#[test]
fn under_the_endpoint_rule_only_the_hits_own_cell_gets_a_height() {
    // A laser 0.42 m up looking 25 degrees down at flat ground: its beam passes 1.5 cm over the cells just
    // before its end point, within 3 sigma of the 12 mm range error.
    let target = (0.915, 0.025, 0.0);
    let origin = Point3::new(0.915 - 0.42 / 25f64.to_radians().tan(), 0.025, 0.42);
    let heights = |hit_height| {
        let mut map = map_with(
            0.05,
            ModelOptions {
                hit_height,
                ..ModelOptions::default()
            },
        );
        map.integrate(&scan_of(origin, &[target])).expect("integrated");
        let end = map
            .cell(cell(&map, target.0, target.1))
            .elevation()
            .expect("end point");
        let before = map.cell(cell(&map, target.0 - 0.05, target.1)).elevation();
        (end.mean_m, before.map(|e| e.mean_m))
    };
    let (end, before) = heights(oeg::HitHeight::BeamSample);
    assert!(end.abs() < 1e-3);
    assert!(before.expect("the paper's beam sample") > 0.004, "{before:?}");
    let (end, before) = heights(oeg::HitHeight::Endpoint);
    assert!(end.abs() < 1e-3);
    assert_eq!(before, None, "the cell before the end point measures no height");
}

#[test]
fn the_highest_level_of_a_scan_ignores_the_ground_seen_under_a_table_edge() {
    let origin = Point3::new(0.0, 0.025, 0.45);
    // One scan sees both a table's edge at 0.44 m and the ground under it in the same cell.
    let targets = [
        (2.02, 0.025, 0.44),
        (2.03, 0.025, 0.0),
        (2.04, 0.025, 0.441),
        (2.01, 0.025, 0.001),
    ];
    let measure = |rule| {
        let mut map = map_with(
            0.05,
            ModelOptions {
                scan_hit_elevation: rule,
                hit_height: oeg::HitHeight::Endpoint,
                ..ModelOptions::default()
            },
        );
        map.integrate(&scan_of(origin, &targets)).expect("integrated");
        map.cell(cell(&map, 2.025, 0.025))
            .elevation()
            .expect("elevation")
            .mean_m
    };
    assert!((measure(ScanHitElevation::HighestLevel) - 0.4405).abs() < 0.002);
    let mean = measure(ScanHitElevation::MeanWithSpread);
    assert!(mean > 0.05 && mean < 0.4, "the mean mixes the two levels: {mean}");
}

#[test]
fn the_contact_rule_measures_a_step_from_the_lowest_level_not_the_lowest_cell() {
    // Flat ground with 1 cm noise in a fixed pattern, and a 5 cm curb on its right half.
    let mut map = map_with(0.05, ModelOptions::default());
    let profile = RobotProfile::default();
    let noise = [0.0, 0.01, -0.01, 0.005, -0.005, 0.012, -0.012, 0.0];
    // Three cells of margin all round, so that the cells looked at have their contact windows observed.
    for j in -3..15 {
        for i in -3..27 {
            let (x, y) = (0.025 + 0.05 * f64::from(i), 0.025 + 0.05 * f64::from(j));
            let z = noise[(i * 7 + j * 3_i32).rem_euclid(8) as usize] + if i >= 12 { 0.05 } else { 0.0 };
            hit_from_above(&mut map, x, y, z);
        }
    }
    let rule = TraversabilityRule::Contact {
        kappa: 2.0,
        reach_m: 0.25,
    };
    let at = |x: f64| map.traversability(cell(&map, x, 0.3), &profile, rule);
    // Noisy flat cells 0.3 m from the curb: their lowest neighbour is 1.2 cm low (a 2.4 cm rise for the highest,
    // within 2 sigma of 3.5 cm), the lowest level is not.
    for x in [0.075, 0.175, 0.275, 0.325] {
        assert_eq!(at(x), Traversability::Traversable, "x = {x}");
    }
    // The curb's first cells, and its top more than the contact distance inside: a step, then a plateau.
    assert_eq!(at(0.625), Traversability::Blocked);
    assert_eq!(at(0.925), Traversability::Traversable);
    assert_eq!(at(1.125), Traversability::Traversable);
    let ground = map
        .ground_within(cell(&map, 0.275, 0.3), profile.contact_distance_m(), 2.0)
        .expect("ground");
    assert!(ground.mean_m.abs() < 0.006, "{ground:?}");
}

#[test]
fn grounds_for_several_distances_in_one_walk_are_each_the_ground_alone() {
    // A noisy floor with a 6 cm box: the grounds of two windows, together and alone, to the bit.
    let mut map = map_with(0.05, ModelOptions::default());
    let mut targets = Vec::new();
    for k in 0..400 {
        let (x, y) = (0.5 + f64::from(k % 20) * 0.05, -0.5 + f64::from(k / 20) * 0.05);
        let z = if x > 0.9 && y > 0.0 {
            0.06
        } else {
            0.003 * f64::from((k * 7) % 5)
        };
        targets.push((x, y, z));
    }
    map.integrate(&scan_of(Point3::new(0.0, 0.0, 0.5), &targets))
        .expect("integrated");
    for k in 0..400 {
        let c = cell(
            &map,
            0.5 + f64::from(k % 20) * 0.05,
            -0.5 + f64::from(k / 20) * 0.05,
        );
        let both = map.grounds_within(c, [0.25, 0.1], 2.0);
        assert_eq!(
            both,
            [map.ground_within(c, 0.25, 2.0), map.ground_within(c, 0.1, 2.0)]
        );
    }
}
