use super::*;
use crate::judge::expectations::check_expectations;
use crate::test_support::{truth_cell, truth_raster};
use nalgebra::Point3;
use oeg::{CellIndex, CellRegion, Map, MapConfig, Scan, SensorModel, TraversabilityRule};

/// Four 1 m cells: ground seen at 0 (truly flat), a 0.2 m block seen at 0.2, a 0.1 m block seen at 0.01
/// (unsafe), and one cell never observed; the third lies under a 0.3 m structure.
fn tiny() -> (Map, TruthRaster) {
    let mut map = Map::new(MapConfig::new(1.0)).expect("valid");
    for (x, z) in [(0.5, 0.0), (1.5, 0.2), (2.5, 0.01)] {
        for _ in 0..2 {
            let mut scan = Scan::new(Point3::new(x, 0.5, 2.0), SensorModel::laser());
            scan.push_hit(Point3::new(x, 0.5, z));
            map.integrate(&scan).expect("integrated");
        }
    }
    let region = CellRegion::from_corners(CellIndex::new(0, 0), CellIndex::new(3, 0)).expect("region");
    let truth = truth_raster(
        region,
        vec![
            truth_cell(0.0, false, f32::NAN),
            truth_cell(0.2, true, f32::NAN),
            truth_cell(0.1, true, 0.3),
            truth_cell(0.0, false, f32::NAN),
        ],
    );
    (map, truth)
}

#[test]
fn metrics_match_hand_computed_values() {
    let (map, truth) = tiny();
    let verdicts = Verdicts::new(&map, &truth, TraversabilityRule::Absolute).expect("verdicts");
    let estimate = Estimate::of_map(&map, &truth, TraversabilityRule::Absolute).expect("estimate");
    let m = compute("tiny", 3, &estimate, &truth, &verdicts);
    assert_eq!((m.num_cells, m.num_observed_cells), (4, 3));
    assert!((m.coverage - 0.75).abs() < 1e-12);
    // Errors 0, 0, -0.09 (to f32 precision).
    assert_eq!(m.num_elevation_cells, 3);
    assert!(
        (m.elevation_rmse_m - (0.0081f64 / 3.0).sqrt()).abs() < 1e-5,
        "{}",
        m.elevation_rmse_m
    );
    assert!((m.elevation_mae_m - 0.03).abs() < 1e-5);
    assert!((m.elevation_bias_m + 0.03).abs() < 1e-5);
    assert!((m.elevation_p95_abs_err_m - 0.09).abs() < 1e-5);
    assert!(
        (m.elevation_within_2sigma - 2.0 / 3.0).abs() < 1e-12,
        "the 9 cm miss is far outside 2 sigma"
    );
    // The ground right and drivable, the 0.2 m block right and blocked, the 0.1 m block under a 0.3 m
    // structure mapped drivable: unsafe, counted as clearance (the classes partition the cells).
    assert_eq!(m.num_scored_cells, 3);
    assert_eq!((m.right_drivable_cells, m.right_blocked_cells), (1, 1));
    assert_eq!((m.unsafe_step_cells, m.overcautious_step_cells), (0, 0));
    assert_eq!(
        (m.unsafe_cells, m.overcautious_cells, m.uncertain_cells),
        (1, 0, 0)
    );
    assert_eq!(
        (
            m.num_clearance_cells,
            m.unsafe_clearance_cells,
            m.overcautious_clearance_cells
        ),
        (1, 1, 0)
    );
    // Brier: every observed cell occupied with P = 0.9707 (two confident hits reach L_max = 3.5);
    // outcomes 0, 1, 1: ((P - 0)^2 + 2 (1 - P)^2) / 3.
    let p = f64::from(oeg::probability_from_log_odds(3.5));
    assert!(
        (m.occupancy_brier - (p * p + 2.0 * (1.0 - p) * (1.0 - p)) / 3.0).abs() < 1e-6,
        "{}",
        m.occupancy_brier
    );
    assert_eq!((m.num_scans, m.num_rays), (6, 6));
}

#[test]
fn expectations_pass_and_fail_with_the_measured_and_required_values() {
    let (map, truth) = tiny();
    let verdicts = Verdicts::new(&map, &truth, TraversabilityRule::Absolute).expect("verdicts");
    let estimate = Estimate::of_map(&map, &truth, TraversabilityRule::Absolute).expect("estimate");
    let mut m = compute("tiny", 3, &estimate, &truth, &verdicts);
    let mut e = BTreeMap::new();
    e.insert(
        "coverage".to_string(),
        sim::scenario::Expectation {
            min: Some(0.5),
            max: None,
        },
    );
    assert!(check_expectations(&mut m, &e).is_empty());
    assert!(m.expectations_passed);
    e.insert(
        "unsafe_cells".to_string(),
        sim::scenario::Expectation {
            min: None,
            max: Some(0.0),
        },
    );
    let failed = check_expectations(&mut m, &e);
    assert_eq!(failed.len(), 1);
    assert_eq!(failed[0].to_string(), "unsafe_cells = 1 (required <= 0)");
    assert!(!m.expectations_passed && m.num_expectations_failed == 1);
    assert!(metric_names().contains(&"elevation_rmse_m".to_string()));
}

#[test]
fn percentiles_use_the_nearest_rank() {
    assert_eq!(percentile(&[1.0, 2.0, 3.0, 4.0], 0.5), 2.0);
    assert_eq!(percentile(&[1.0, 2.0, 3.0, 4.0], 0.95), 4.0);
    assert!(percentile(&[], 0.5).is_nan());
}
