//! Why the contact rule cannot decide a cell ([`oeg::Doubt`]): one test per rule, on small hand-made scans
//! under the recommended preset.

use nalgebra::{Point3, Vector3};
use oeg::{
    CellIndex, Doubt, Map, MapConfig, MapPreset, Ray, RobotProfile, Scan, SensorModel, Traversability,
    TraversabilityRule,
};

fn robust_map() -> Map {
    Map::new(MapConfig {
        model: MapPreset::Robust.model(&RobotProfile::default()),
        ..MapConfig::new(0.05)
    })
    .expect("valid config")
}

fn rule() -> TraversabilityRule {
    MapPreset::Robust.traversability()
}

/// Level ground hit straight down from 1 m above the centre of each cell `(i, j)` of `cells`, each range
/// known to `sigma_m`, `times` over.
fn level_ground(map: &mut Map, cells: impl Iterator<Item = (i32, i32)> + Clone, sigma_m: f32, times: usize) {
    for _ in 0..times {
        for (i, j) in cells.clone() {
            let (x, y) = (0.025 + 0.05 * f64::from(i), 0.025 + 0.05 * f64::from(j));
            let mut scan = Scan::new(Point3::new(x, y, 1.0), SensorModel::laser());
            scan.rays
                .push(Ray::hit(Vector3::new(0.0, 0.0, -1.0)).with_range_sigma_m(sigma_m));
            map.integrate(&scan).expect("integrated");
        }
    }
}

/// The cells of a square patch, `0..n` each way.
fn patch(n: i32) -> impl Iterator<Item = (i32, i32)> + Clone {
    (0..n).flat_map(move |j| (0..n).map(move |i| (i, j)))
}

fn decide(map: &Map, i: i32, j: i32) -> (Traversability, Option<Doubt>) {
    let (p, c) = (RobotProfile::default(), CellIndex::new(i, j));
    (map.traversability(c, &p, rule()), map.doubt(c, &p, rule()))
}

#[test]
fn level_ground_measured_finely_is_drivable_and_coarsely_is_imprecise() {
    // Ranges known to 5 mm: the difference of two cells is known to 7 mm, a step 5 standard deviations away.
    let mut fine = robust_map();
    level_ground(&mut fine, patch(20), 0.005, 3);
    assert_eq!(decide(&fine, 10, 10), (Traversability::Traversable, None));
    // Known to 3 cm (a stereo camera's depth error at 1 m): two level cells may differ by a step within 2
    // standard deviations, so level ground is uncertain, and the doubt is the sensor's resolution, not a step.
    let mut coarse = robust_map();
    level_ground(&mut coarse, patch(20), 0.03, 3);
    assert_eq!(
        decide(&coarse, 10, 10),
        (Traversability::Uncertain, Some(Doubt::Imprecise))
    );
    // 1 cm: 2 sqrt(2) x 1 cm = 2.8 cm, under the 3.5 cm step: precise enough to decide.
    let mut cm = robust_map();
    level_ground(&mut cm, patch(20), 0.01, 3);
    assert_eq!(decide(&cm, 10, 10), (Traversability::Traversable, None));
}

#[test]
fn a_step_within_two_sigma_of_the_threshold_is_a_step_band_doubt() {
    // Level ground at 0 and a 3.5 cm plateau on columns 10 and up, ranges known to 5 mm: the plateau's edge
    // rises 3.5 cm over the ground beside it, on the threshold.
    let mut map = robust_map();
    level_ground(&mut map, patch(20).filter(|(i, _)| *i < 10), 0.005, 3);
    for _ in 0..3 {
        for (i, j) in patch(20).filter(|(i, _)| *i >= 10) {
            let (x, y) = (0.025 + 0.05 * f64::from(i), 0.025 + 0.05 * f64::from(j));
            let mut scan = Scan::new(Point3::new(x, y, 1.035), SensorModel::laser());
            scan.rays
                .push(Ray::hit(Vector3::new(0.0, 0.0, -1.0)).with_range_sigma_m(0.005));
            map.integrate(&scan).expect("integrated");
        }
    }
    assert_eq!(
        decide(&map, 10, 10),
        (Traversability::Uncertain, Some(Doubt::StepBand))
    );
}

#[test]
fn a_drivable_cell_whose_contact_window_reaches_unobserved_space_is_the_frontier() {
    let mut map = robust_map();
    level_ground(&mut map, patch(20), 0.005, 3);
    // The contact distance is 0.10 m: a point of a cell three cells on lies within it of a point of this one,
    // so the outer three rings of the patch see past its edge.
    for (i, j) in [(0, 10), (2, 10), (17, 5), (10, 19)] {
        assert_eq!(
            decide(&map, i, j),
            (Traversability::Unknown, Some(Doubt::Frontier)),
            "({i}, {j})"
        );
    }
    for (i, j) in [(3, 10), (16, 5), (10, 16)] {
        assert_eq!(
            decide(&map, i, j),
            (Traversability::Traversable, None),
            "({i}, {j})"
        );
    }
    // A cell never observed has no doubt: it is simply unknown.
    assert_eq!(decide(&map, -5, -5), (Traversability::Unknown, None));
}

/// Long readings along row 20 from 1 m up, ending on the ground at x = 2.025 m, each known to `sigma_m`: the
/// cells within 3 sigma before each end point count for the occupancy, and only the end point's cell measures
/// a height ([`oeg::HitHeight::Endpoint`]).
fn long_readings(map: &mut Map, sigma_m: f32) {
    for _ in 0..5 {
        let mut scan = Scan::new(Point3::new(0.025, 1.025, 1.0), SensorModel::laser());
        scan.rays
            .push(Ray::hit(Vector3::new(2.0, 0.0, -1.0)).with_range_sigma_m(sigma_m));
        map.integrate(&scan).expect("integrated");
    }
}

/// The cells of row 20 the long readings left occupied with no height.
fn without_height(map: &Map) -> Vec<CellIndex> {
    (0..40)
        .map(|i| CellIndex::new(i, 20))
        .filter(|c| {
            let cell = map.cell(*c);
            cell.log_odds > map.occupied_log_odds() && cell.elevation().is_none()
        })
        .collect()
}

#[test]
fn an_occupied_cell_with_no_height_is_judged_by_the_level_around_it_and_unknown_alone_under_every_rule() {
    let p = RobotProfile::default();
    // Level ground all round but on row 20 from x = 0.5 m on, which only the long readings reach: each cell
    // they leave without a height has level estimates beside it, and is ground.
    let mut beside = robust_map();
    level_ground(
        &mut beside,
        patch(48).filter(|(i, j)| *j != 20 || *i < 10),
        0.005,
        3,
    );
    long_readings(&mut beside, 0.2);
    let cells = without_height(&beside);
    assert!(
        !cells.is_empty(),
        "the long readings leave cells without a height"
    );
    for c in &cells {
        assert_eq!(
            decide(&beside, c.i, c.j),
            (Traversability::Traversable, None),
            "{c:?}"
        );
    }
    // The rules that judge a surface alone judge it as high as the highest estimate next to it: level ground,
    // not the worst case (the end-point rule leaves such cells without a height by design).
    for rule in [TraversabilityRule::Terrain, TraversabilityRule::Absolute] {
        for c in &cells {
            assert_eq!(
                beside.traversability(*c, &p, rule),
                Traversability::Traversable,
                "{rule:?} {c:?}"
            );
        }
    }
    // No ground measured within 0.15 m of row 20 from x = 0.5 m on, and readings known to 0.5 m: the cells they
    // leave without a height far from their end points have nothing to be judged by.
    let mut alone = robust_map();
    level_ground(
        &mut alone,
        patch(48).filter(|(i, j)| !(17..=23).contains(j) || *i < 10),
        0.005,
        3,
    );
    long_readings(&mut alone, 0.5);
    // The end points fall in cell 40, whose estimate lies within the contact distance of cells 37 to 43.
    let far: Vec<CellIndex> = without_height(&alone)
        .into_iter()
        .filter(|c| (c.i - 40).abs() >= 4)
        .collect();
    assert!(!far.is_empty(), "cells without a height far from the end points");
    for c in &far {
        assert_eq!(
            decide(&alone, c.i, c.j),
            (Traversability::Unknown, Some(Doubt::NoHeight)),
            "{c:?}"
        );
        // Nor has the terrain rule: no estimate in its 3 x 3 neighbourhood.
        let terrain = TraversabilityRule::Terrain;
        assert_eq!(
            (
                alone.traversability(*c, &p, terrain),
                alone.doubt(*c, &p, terrain)
            ),
            (Traversability::Unknown, Some(Doubt::NoHeight)),
            "{c:?}"
        );
    }
}

#[test]
fn every_doubt_has_its_own_name() {
    let names: std::collections::BTreeSet<_> = Doubt::ALL.iter().map(|d| d.name()).collect();
    assert_eq!(names.len(), Doubt::ALL.len());
    for d in Doubt::ALL {
        assert_eq!(
            serde_json::to_value(d).expect("serialises"),
            serde_json::Value::from(d.name())
        );
    }
}

/// The layers of classes and doubts, made in one pass, say of every cell what `traversability` and `doubt`
/// say of it one at a time: drivable, imprecise, frontier and never observed cells alike.
#[test]
fn the_one_pass_layers_agree_with_each_cell_s_decision() {
    let mut map = robust_map();
    level_ground(&mut map, patch(12), 0.005, 3);
    level_ground(&mut map, (14..20).map(|i| (i, 5)), 0.03, 3);
    let region = oeg::CellRegion {
        min: CellIndex::new(-3, -3),
        num_x: 27,
        num_y: 19,
    };
    let (classes, doubts) = map
        .traversability_and_doubt_layers(region, &RobotProfile::default(), rule())
        .expect("small layers");
    let cells: Vec<_> = region.cells().collect();
    assert_eq!(
        (classes.values.len(), doubts.values.len()),
        (cells.len(), cells.len())
    );
    let mut seen = std::collections::BTreeSet::new();
    for (k, cell) in cells.into_iter().enumerate() {
        let expected = decide(&map, cell.i, cell.j);
        assert_eq!((classes.values[k], doubts.values[k]), expected, "cell {cell:?}");
        seen.insert(format!("{expected:?}"));
    }
    // The region holds decided, undecided and never observed cells.
    assert!(seen.len() >= 3, "{seen:?}");
}
