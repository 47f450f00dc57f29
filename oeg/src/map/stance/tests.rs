//! The stance's tests: the plane under the footprint, its residual, refused stances, and footprint clearing.

use super::*;
use crate::map::MapConfig;
use crate::model::SeenFrom;
use crate::preset::MapPreset;
use crate::traversability::{RobotProfile, Traversability};

fn pioneer() -> Footprint {
    Footprint {
        min_x_m: -0.3,
        max_x_m: 0.3,
        min_y_m: -0.25,
        max_y_m: 0.25,
    }
}

fn stance(contacts: Vec<Point3<f64>>) -> Stance {
    Stance {
        contacts,
        footprint: pioneer(),
        pose: Pose2 {
            x_m: 1.0,
            y_m: 2.0,
            yaw_rad: 0.3,
        },
        sigma_m: DEFAULT_STANCE_SIGMA_M,
    }
}

/// Four wheels at `(+-0.2, +-0.2)` about `(1, 2)` on the plane `z = 0.1 + 0.05 x`.
fn wheels_on_a_slope() -> Vec<Point3<f64>> {
    [(-0.2, -0.2), (-0.2, 0.2), (0.2, -0.2), (0.2, 0.2)]
        .map(|(dx, dy)| Point3::new(1.0 + dx, 2.0 + dy, 0.1 + 0.05 * (1.0 + dx)))
        .to_vec()
}

#[test]
fn the_footprint_cells_take_the_plane_through_the_wheels_with_the_contacts_variance() {
    let mut map = Map::new(MapConfig::new(0.05)).expect("map");
    let set = map
        .integrate_stance(&stance(wheels_on_a_slope()))
        .expect("stance");
    // A 0.6 x 0.5 m rectangle, turned: about 120 cells of 25 cm^2, and a ring of partly covered ones.
    assert!((120..=200).contains(&set), "{set}");
    assert_eq!(map.num_observed_cells(), set);
    assert_eq!(map.num_scans(), 0);
    for (cell, c) in map.observed_cells() {
        let (x, _) = map.geometry().cell_center(cell);
        assert!((f64::from(c.mean_m) - (0.1 + 0.05 * x)).abs() < 1e-5, "{cell:?}");
        assert!((c.var_m2 - DEFAULT_STANCE_SIGMA_M * DEFAULT_STANCE_SIGMA_M).abs() < 1e-9);
        assert_eq!(map.is_occupied(cell), Some(true));
    }
}

#[test]
fn a_twisted_stance_adds_its_residual_and_one_wheel_gives_a_level_plane() {
    let mut twisted = wheels_on_a_slope();
    twisted[0].z += 0.02;
    let mut map = Map::new(MapConfig::new(0.05)).expect("map");
    map.integrate_stance(&stance(twisted)).expect("stance");
    let (_, c) = map.observed_cells().next().expect("a cell");
    // The plane misses each wheel by 5 mm: the residual's square adds to the contacts' variance.
    let expected = DEFAULT_STANCE_SIGMA_M.powi(2) + 0.005_f32.powi(2);
    assert!((c.var_m2 - expected).abs() < 1e-8, "{} {expected}", c.var_m2);

    let mut level = Map::new(MapConfig::new(0.05)).expect("map");
    level
        .integrate_stance(&stance(vec![Point3::new(1.0, 2.0, 0.3)]))
        .expect("stance");
    assert!(level.observed_cells().all(|(_, c)| c.mean_m == 0.3));
}

#[test]
fn a_cell_a_scan_observed_keeps_its_measurement() {
    let mut map = Map::new(MapConfig::new(0.05)).expect("map");
    let seen = map.geometry().cell_of(1.0, 2.0).expect("cell");
    let measured = Cell {
        log_odds: -1.0,
        mean_m: 0.5,
        var_m2: 1e-4,
    };
    map.cells
        .tile_or_insert(TileIndex::of(seen), u64::MAX)
        .expect("tile")[offset_in_tile(seen)] = measured;
    let set = map
        .integrate_stance(&stance(wheels_on_a_slope()))
        .expect("stance");
    assert_eq!(map.cell(seen), measured);
    assert_eq!(map.num_observed_cells(), set + 1);
}

#[test]
fn under_the_contact_rule_the_ground_it_stands_on_is_drivable_and_no_frontier() {
    let robot = RobotProfile::default();
    let model = MapPreset::Robust.model(&robot);
    let mut map = Map::new(MapConfig {
        model,
        ..MapConfig::new(0.05)
    })
    .expect("map");
    map.integrate_stance(&stance(wheels_on_a_slope()))
        .expect("stance");
    let rule = MapPreset::Robust.traversability();
    let centre = map.geometry().cell_of(1.0, 2.0).expect("cell");
    assert_eq!(
        map.traversability(centre, &robot, rule),
        Traversability::Traversable
    );
}

#[test]
fn a_stance_that_is_not_finite_or_has_no_contact_is_refused_and_sets_nothing() {
    let mut map = Map::new(MapConfig::new(0.05)).expect("map");
    for (s, words) in [
        (stance(Vec::new()), "at least one contact"),
        (stance(vec![Point3::new(f64::NAN, 0.0, 0.0)]), "not finite"),
        (stance(vec![Point3::new(9.0, 2.0, 0.0)]), "more than"),
        (stance(vec![Point3::new(1.0, 2.0, f64::MAX)]), "no finite plane"),
        (
            Stance {
                sigma_m: 0.0,
                ..stance(wheels_on_a_slope())
            },
            "sigma_m",
        ),
        (
            Stance {
                pose: Pose2 {
                    x_m: f64::INFINITY,
                    y_m: 0.0,
                    yaw_rad: 0.0,
                },
                ..stance(wheels_on_a_slope())
            },
            "pose",
        ),
    ] {
        let e = map.integrate_stance(&s).expect_err("refused").to_string();
        assert!(e.contains(words), "{e}");
    }
    assert_eq!(map.num_observed_cells(), 0);
}

#[test]
fn a_stance_beyond_the_memory_limit_is_refused_whole() {
    let mut map = Map::new(MapConfig {
        memory_limit_bytes: 1000,
        ..MapConfig::new(0.05)
    })
    .expect("map");
    let e = map
        .integrate_stance(&stance(wheels_on_a_slope()))
        .expect_err("too big");
    assert!(matches!(e, Error::MemoryLimit { .. }), "{e}");
    assert_eq!(map.num_observed_cells(), 0);
}

/// The Pioneer 3-AT's body: 8 cm to 0.46 m over its wheels' contacts.
const PIONEER_BODY: BodySpan = BodySpan {
    underside_m: 0.08,
    height_m: 0.46,
};

/// A robust map with `cell` set to `c` and a structure at `ceiling_m` (if any) over it.
fn with_cell(cell_xy: (f64, f64), c: Cell, ceiling_m: Option<f32>) -> (Map, CellIndex) {
    let robot = RobotProfile::default();
    let mut map = Map::new(MapConfig {
        model: MapPreset::Robust.model(&robot),
        ..MapConfig::new(0.05)
    })
    .expect("map");
    let cell = map.geometry().cell_of(cell_xy.0, cell_xy.1).expect("cell");
    map.cells
        .tile_or_insert(TileIndex::of(cell), u64::MAX)
        .expect("tile")[offset_in_tile(cell)] = c;
    if let Some(z_m) = ceiling_m {
        map.ceilings
            .tile_or_insert(TileIndex::of(cell), u64::MAX)
            .expect("tile")[offset_in_tile(cell)] = Ceiling {
            z_m,
            var_m2: 1e-4,
            log_odds: 2.0,
            seen_from: SeenFrom::Below,
            clear_m: f32::NEG_INFINITY,
        };
    }
    (map, cell)
}

#[test]
fn a_driving_robot_clears_what_its_body_occupies_and_keeps_the_ground_it_agrees_with() {
    // The plane under the wheels is z = 0.1 + 0.05 x: 0.15 m at the footprint's centre (1, 2).
    let ground = 0.1 + 0.05 * 1.025;
    let ghost = Cell {
        log_odds: 2.0,
        mean_m: ground as f32 + 0.25,
        var_m2: 1e-4,
    };
    // A spurious return 0.25 m above the ground, and a structure 0.3 m up over it: the robot's body is there.
    let (mut map, cell) = with_cell((1.0, 2.0), ghost, Some(ground as f32 + 0.3));
    let mut start = map.clone();
    map.integrate_footprint(&stance(wheels_on_a_slope()), PIONEER_BODY)
        .expect("footprint");
    let cleared = map.cell(cell);
    assert!((f64::from(cleared.mean_m) - ground).abs() < 0.01, "{cleared:?}");
    assert!(
        cleared.log_odds >= 2.0,
        "the ground under a wheel is occupied, as a hit: {cleared:?}"
    );
    assert!(map.ceiling(cell).is_none());
    // At the start a stance only fills what no scan measured: the ghost and its structure stay.
    start
        .integrate_stance(&stance(wheels_on_a_slope()))
        .expect("stance");
    assert_eq!(start.cell(cell), ghost);
    assert!(start.ceiling(cell).is_some());

    // Ground measured within its band of the plane keeps its own estimate; a structure higher than the robot
    // (a table it drives under) stays.
    let measured = Cell {
        log_odds: 1.0,
        mean_m: ground as f32 + 0.004,
        var_m2: 4e-6,
    };
    let (mut map, cell) = with_cell((1.0, 2.0), measured, Some(ground as f32 + 0.6));
    map.integrate_footprint(&stance(wheels_on_a_slope()), PIONEER_BODY)
        .expect("footprint");
    assert_eq!(map.cell(cell), measured);
    assert!(map.ceiling(cell).is_some());

    // A cell seen only free (no height) keeps what it is, under a wheel or between them, and so does a curb
    // lower than the chassis: the robot straddles it, and a contact inferred from the pose is not a
    // measurement of a free cell.
    let free = Cell {
        log_odds: -1.0,
        mean_m: 0.0,
        var_m2: f32::INFINITY,
    };
    for at in [(0.8, 1.8), (1.0, 2.0)] {
        let (mut map, cell) = with_cell(at, free, None);
        map.integrate_footprint(&stance(wheels_on_a_slope()), PIONEER_BODY)
            .expect("footprint");
        assert_eq!(map.cell(cell), free);
    }
    let curb = Cell {
        log_odds: 2.0,
        mean_m: ground as f32 + 0.05,
        var_m2: 1e-5,
    };
    let (mut map, cell) = with_cell((1.0, 2.0), curb, None);
    map.integrate_footprint(&stance(wheels_on_a_slope()), PIONEER_BODY)
        .expect("footprint");
    assert_eq!(map.cell(cell), curb);
}
