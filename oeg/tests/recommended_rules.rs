//! The recommended preset's rules beyond the paper's, on small hand-made scans: structures over a surface (the
//! ceiling layer: boards, tables and people, contradicted and passed under) and free cells beside a step.

use nalgebra::{Point3, Vector3};
use oeg::{
    CellIndex, Map, ModelOptions, Ray, RobotProfile, Scan, SensorModel, Traversability, TraversabilityRule,
};

#[path = "common/scans.rs"]
mod scans;

use scans::{cell, hit_from_above, map_with, scan_of};

/// Ground seen under a board every scan by a low laser, the board's top hit only every tenth scan by a higher
/// one: the robust preset with overhead hits as given.
fn board_seen_now_and_then(overhead_hits: oeg::OverheadHits) -> Map {
    let profile = RobotProfile::default();
    let mut map = map_with(
        0.05,
        ModelOptions {
            overhead_hits,
            ..oeg::MapPreset::Robust.model(&profile)
        },
    );
    for k in 0..60 {
        // Beams from 0.25 m down to the ground beyond and under the board (its top at 0.34 m).
        let ground: Vec<_> = (0..16)
            .map(|i| (1.625 + 0.05 * f64::from(i), 0.025, 0.0))
            .collect();
        map.integrate(&scan_of(Point3::new(0.025, 0.025, 0.25), &ground))
            .expect("integrated");
        if k % 10 == 0 {
            map.integrate(&scan_of(Point3::new(0.025, 0.025, 0.45), &[(2.025, 0.025, 0.34)]))
                .expect("integrated");
        }
    }
    map
}

#[test]
fn a_board_hit_now_and_then_over_ground_hit_every_scan_is_kept_as_a_ceiling() {
    let p = RobotProfile::default();
    let rule = oeg::MapPreset::Robust.traversability();
    let mut kept = board_seen_now_and_then(oeg::OverheadHits::Ceiling);
    ground_around(&mut kept, 2.025, 0.025);
    let c = cell(&kept, 2.025, 0.025);
    let ceiling = kept.ceiling(c).expect("a ceiling over the ground");
    assert!((ceiling.z_m - 0.34).abs() < 0.01, "{ceiling:?}");
    let ground = kept.cell(c).elevation().expect("ground");
    assert!(
        ground.mean_m.abs() < 0.01,
        "the ground stays the surface: {ground:?}"
    );
    assert_eq!(kept.traversability(c, &p, rule), Traversability::Blocked);
    // Beams under the board never pass through its band, so they leave it alone.
    assert_eq!(kept.num_ceilings(), 1);
    // One height per cell: the ground under it outvotes the board's rare hits.
    let mut lost = board_seen_now_and_then(oeg::OverheadHits::Surface);
    ground_around(&mut lost, 2.025, 0.025);
    assert!(lost.ceiling(c).is_none());
    assert_eq!(lost.traversability(c, &p, rule), Traversability::Traversable);
}

#[test]
fn a_person_over_the_ground_is_a_ceiling_that_beams_through_it_clear() {
    let p = RobotProfile::default();
    let rule = oeg::MapPreset::Robust.traversability();
    let mut map = map_with(0.05, oeg::MapPreset::Robust.model(&p));
    let origin = Point3::new(0.025, 0.025, 0.45);
    let ground_behind: Vec<_> = (0..10).map(|i| (2.0 + 0.05 * f64::from(i), 0.025, 0.0)).collect();
    for _ in 0..5 {
        map.integrate(&scan_of(origin, &ground_behind))
            .expect("integrated");
    }
    // A person stands at x = 2.0-2.5 m: the beams stop on their front at 0.10-0.45 m.
    let front: Vec<_> = (0..10)
        .map(|i| (2.025 + 0.05 * f64::from(i), 0.025, 0.10 + 0.035 * f64::from(i)))
        .collect();
    for _ in 0..20 {
        map.integrate(&scan_of(origin, &front)).expect("integrated");
    }
    let c = cell(&map, 2.025, 0.025);
    assert!(map.ceiling(c).is_some());
    assert_eq!(map.traversability(c, &p, rule), Traversability::Blocked);
    // The person leaves: the beams reach the ground again and pass through the heights where they stood.
    let far: Vec<_> = (0..10).map(|i| (2.6 + 0.1 * f64::from(i), 0.025, 0.0)).collect();
    let mut scans = 0;
    while map.ceiling(c).is_some() {
        map.integrate(&scan_of(origin, &far)).expect("integrated");
        scans += 1;
        assert!(
            scans <= 2,
            "a ceiling at the clamp is gone within 2 contradicting scans"
        );
    }
    assert_ne!(map.traversability(c, &p, rule), Traversability::Blocked);
}

/// A scan of laser beams from `origin` onto each of `targets`, each range known to 5 mm.
fn beams(map: &mut Map, origin: Point3<f64>, targets: &[(f64, f64, f64)]) {
    let mut scan = Scan::new(origin, SensorModel::laser());
    for &(x, y, z) in targets {
        let v = Point3::new(x, y, z) - origin;
        scan.rays.push(Ray::hit(v.cast()).with_range_sigma_m(0.005));
    }
    map.integrate(&scan).expect("integrated");
}

#[test]
fn a_structure_hit_over_the_robot_is_passed_under_only_where_a_beam_passed_under_it_as_high() {
    let profile = RobotProfile::default();
    let rule = oeg::MapPreset::Robust.traversability();
    let lidar = Point3::new(0.025, 0.025, 0.45);
    let ground = |map: &mut Map| {
        ground_around(map, 2.025, 0.025);
        for _ in 0..3 {
            beams(map, lidar, &[(2.025, 0.025, 0.0), (2.125, 0.025, 0.0)]);
        }
    };
    let c = CellIndex::new(40, 0);
    // A board's face met by a ring rising onto it at 0.48 m, while the beams under it pass at 0.42 m at most (a
    // lower ring, on to the ground 30 m away): its underside may hang anywhere from 0.42 to 0.48 m.
    let mut face = map_with(0.05, oeg::MapPreset::Robust.model(&profile));
    ground(&mut face);
    for _ in 0..5 {
        beams(&mut face, lidar, &[(2.03, 0.025, 0.48), (30.4, 0.025, 0.0)]);
    }
    let ceiling = face.ceiling(c).expect("the face");
    assert!(ceiling.clear_m < 0.43, "{ceiling:?}");
    assert_eq!(face.traversability(c, &profile, rule), Traversability::Uncertain);
    // A flat underside 0.50 m up: the ring meets it in this cell, then, a little nearer, passes just under it on
    // its way to the underside further on.
    let mut underside = map_with(0.05, oeg::MapPreset::Robust.model(&profile));
    ground(&mut underside);
    beams(&mut underside, lidar, &[(2.03, 0.025, 0.50)]);
    for _ in 0..3 {
        beams(&mut underside, lidar, &[(2.125, 0.025, 0.50)]);
    }
    let ceiling = underside.ceiling(c).expect("the underside");
    assert!(ceiling.clear_m > 0.49, "{ceiling:?}");
    assert_eq!(
        underside.traversability(c, &profile, rule),
        Traversability::Traversable
    );
}

/// One frame of a camera that puts a ray on `(x, y, z)` for each `z` of `heights`, straight down from 1 m above
/// the ground, each range known to 5 mm.
fn frame_from_above(map: &mut Map, x: f64, y: f64, heights: &[f64]) {
    let mut scan = Scan::new(Point3::new(x, y, 1.0), SensorModel::laser());
    for z in heights {
        scan.rays
            .push(Ray::hit(Vector3::new(0.0, 0.0, (z - 1.0) as f32)).with_range_sigma_m(0.005));
    }
    map.integrate(&scan).expect("integrated");
}

#[test]
fn a_hit_in_the_tail_of_many_raises_no_ceiling_but_a_structure_among_many_does() {
    let profile = RobotProfile::default();
    let rule = oeg::MapPreset::Robust.traversability();
    let ground = || {
        let mut map = map_with(0.05, oeg::MapPreset::Robust.model(&profile));
        ground_around(&mut map, 0.025, 0.025);
        for _ in 0..10 {
            frame_from_above(&mut map, 0.025, 0.025, &[0.0; 200]);
        }
        map
    };
    let c = CellIndex::new(0, 0);
    let sigma = ground().cell(c).elevation().expect("ground").var_m2.sqrt();
    // The difference of a hit and the surface has a standard deviation of about sqrt(2) sigma.
    let diff = f64::from(sigma) * 2.0_f64.sqrt();
    // A hundred and ninety-nine pixels on the ground and one 3.3 sigma over it: among 200, that is the noise's
    // tail (Bonferroni asks 4.4 sigma), and the flat ground stays drivable.
    let mut map = ground();
    let mut tail = vec![0.0; 199];
    tail.push(3.3 * diff);
    frame_from_above(&mut map, 0.025, 0.025, &tail);
    assert!(map.ceiling(c).is_none(), "{:?}", map.ceiling(c));
    assert_eq!(map.traversability(c, &profile, rule), Traversability::Traversable);
    // The same hit alone in its scan is judged by the band itself: a structure.
    let mut map = ground();
    frame_from_above(&mut map, 0.025, 0.025, &[3.3 * diff]);
    assert!(map.ceiling(c).is_some());
    // A structure 10 sigma over the ground stands out among 200.
    let mut map = ground();
    let mut board = vec![0.0; 199];
    board.push(10.0 * diff);
    frame_from_above(&mut map, 0.025, 0.025, &board);
    let ceiling = map.ceiling(c).expect("a structure");
    assert!((f64::from(ceiling.z_m) - 10.0 * diff).abs() < 1e-3, "{ceiling:?}");
}

/// Level ground at z = 0 hit from above in every cell within 3 cells of `(x, y)` but its own: the cell's
/// contact window is observed, so the frontier ([`oeg::Doubt::Frontier`]) leaves its decision alone.
fn ground_around(map: &mut Map, x: f64, y: f64) {
    for dj in -3..=3 {
        for di in -3..=3 {
            if (di, dj) != (0, 0) {
                hit_from_above(map, x + 0.05 * f64::from(di), y + 0.05 * f64::from(dj), 0.0);
            }
        }
    }
}

#[test]
fn a_free_cell_beside_a_step_is_uncertain_and_one_in_level_ground_is_free() {
    let profile = RobotProfile::default();
    let rule = oeg::MapPreset::Robust.traversability();
    let mut map = map_with(0.05, oeg::MapPreset::Robust.model(&profile));
    let at = |i: i32| 0.025 + 0.05 * f64::from(i);
    // Ground, a 5 cm curb top on cells 10 to 13, its shadow (cells 14 to 16) never hit, ground beyond; one cell
    // of the ground, (4, 6), is never hit either.
    let never_hit = |i: i32, j: i32| (14..17).contains(&i) || (i, j) == (4, 6);
    for j in 0..12 {
        for i in (0..24).filter(|&i| !never_hit(i, j)) {
            let z = if (10..14).contains(&i) { 0.05 } else { 0.0 };
            hit_from_above(&mut map, at(i), at(j), z);
        }
        // A beam over the shadow, landing on the ground beyond it.
        map.integrate(&scan_of(Point3::new(at(14), at(j), 0.3), &[(at(18), at(j), 0.0)]))
            .expect("integrated");
    }
    // And one over the unhit ground cell.
    map.integrate(&scan_of(Point3::new(at(4), at(6), 0.3), &[(at(6), at(6), 0.0)]))
        .expect("integrated");
    let decision = |i: i32| map.traversability(CellIndex::new(i, 6), &profile, rule);
    for i in [4, 14, 15, 16] {
        let c = map.cell(CellIndex::new(i, 6));
        assert!(c.is_observed() && c.elevation().is_none(), "cell {i} is free");
    }
    // In level ground a free cell is ground as its neighbours are.
    assert_eq!(decision(4), Traversability::Free);
    // Beside the curb's top it may be part of the curb, or ground a step below it.
    assert_eq!(decision(14), Traversability::Uncertain);
    // The curb's near edge is a step; its far edge may drop into the shadow; the ground beyond cannot.
    assert_eq!(decision(10), Traversability::Blocked);
    assert_eq!(decision(13), Traversability::Uncertain);
    assert_eq!(decision(18), Traversability::Traversable);
    assert_eq!(decision(20), Traversability::Traversable);
    // The paper's rules call every free cell free.
    assert_eq!(
        map.traversability(CellIndex::new(14, 6), &profile, TraversabilityRule::Absolute),
        Traversability::Free
    );
}

#[test]
fn a_board_s_face_hit_from_above_stays_under_beams_that_graze_under_it_within_their_footprint() {
    let profile = RobotProfile::default();
    let rule = oeg::MapPreset::Robust.traversability();
    let mut map = map_with(0.05, oeg::MapPreset::Robust.model(&profile));
    let c = CellIndex::new(10, 0);
    ground_around(&mut map, 0.525, 0.025);
    let high = Point3::new(0.025, 0.025, 0.45);
    for _ in 0..3 {
        beams(&mut map, high, &[(0.525, 0.025, 0.0), (0.625, 0.025, 0.0)]);
    }
    // A descending ring meets the face of a board whose underside hangs at 0.4216 m, at 0.424 m: the hits read
    // as a top, and the ring's beams across the cell fuse into a band a few millimetres deep.
    let face_hits: Vec<_> = (0..20)
        .map(|i| (0.53, 0.006 + 0.002 * f64::from(i), 0.424))
        .collect();
    for _ in 0..10 {
        beams(&mut map, high, &face_hits);
    }
    let face = map.ceiling(c).expect("the face");
    let band_lo = face.z_m - 3.0 * face.var_m2.sqrt();
    // A lower ring passes just under the underside, inside that band by less than its 1.1 mm footprint (half a metre out), on its
    // way to a wall 30 m away (in a simulation, a ray without a footprint; a real beam would meet the board).
    let low = Point3::new(0.025, 0.025, 0.43);
    let under_m = f64::from(band_lo) + 0.0005;
    let wall_z = 0.43 + (under_m - 0.43) * (30.0 - 0.025) / (0.525 - 0.025);
    for _ in 0..5 {
        beams(&mut map, low, &[(30.0, 0.025, wall_z)]);
    }
    let ceiling = map.ceiling(c).expect("the board stays");
    assert!(ceiling.log_odds >= face.log_odds, "{ceiling:?}");
    assert_ne!(map.traversability(c, &profile, rule), Traversability::Traversable);
}
