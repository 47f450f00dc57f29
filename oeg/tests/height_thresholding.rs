//! Height thresholding (the paper's section 6.2, Fig. 12): beam parts above `max_height_m` never enter the map,
//! measured from the ground under the robot where the scan says where that is.

use nalgebra::Point3;
use oeg::{ModelOptions, RobotProfile, Traversability, TraversabilityRule};

#[path = "common/scans.rs"]
#[allow(
    dead_code,
    reason = "the shared scans serve several test files; this one needs three"
)]
mod scans;

use scans::{cell, map_with, scan_of};

#[test]
fn height_thresholding_keeps_overhangs_out_of_the_map() {
    // A sensor at 0.3 m sees a branch at 0.8 m, 2 m ahead, and the ground 4 m ahead.
    let targets = [(2.05, 0.05, 0.8), (4.05, 0.05, 0.0)];
    let origin = Point3::new(0.05, 0.05, 0.3);
    let mut plain = map_with(0.1, ModelOptions::default());
    let mut thresholded = map_with(
        0.1,
        ModelOptions {
            max_height_m: Some(0.5),
            ..ModelOptions::default()
        },
    );
    for _ in 0..3 {
        plain.integrate(&scan_of(origin, &targets)).expect("integrated");
        thresholded
            .integrate(&scan_of(origin, &targets))
            .expect("integrated");
    }
    let under_branch = cell(&plain, 2.05, 0.05);
    let profile = RobotProfile::default();
    let rule = TraversabilityRule::Absolute;
    // Without thresholding the branch blocks the path (the paper's Fig. 12 (b)) ...
    assert_eq!(
        plain.traversability(under_branch, &profile, rule),
        Traversability::Blocked
    );
    // ... with it the path is open (Fig. 12 (c)): the cell under the branch is only seen free by the ground ray.
    assert_eq!(
        thresholded.traversability(under_branch, &profile, rule),
        Traversability::Free
    );
    // The part of the branch ray above 0.5 m was ignored: nothing beyond 1.05 m along it but the ground ray.
    assert_eq!(
        thresholded.traversability(cell(&plain, 4.05, 0.05), &profile, rule),
        Traversability::Traversable
    );
}

#[test]
fn height_thresholding_measures_from_the_ground_under_the_robot() {
    // The branch scene of the test above, 2 m higher: a robot on a plateau (or up a slope).
    let lift = 2.0;
    let targets = [(2.05, 0.05, 0.8 + lift), (4.05, 0.05, lift)];
    let origin = Point3::new(0.05, 0.05, 0.3 + lift);
    let thresholded = || {
        map_with(
            0.1,
            ModelOptions {
                max_height_m: Some(0.5),
                ..ModelOptions::default()
            },
        )
    };
    let (mut on_plateau, mut world_z) = (thresholded(), thresholded());
    for _ in 0..3 {
        let mut scan = scan_of(origin, &targets);
        world_z.integrate(&scan).expect("integrated");
        scan.ground_z_m = Some(lift);
        on_plateau.integrate(&scan).expect("integrated");
    }
    let profile = RobotProfile::default();
    // Measured from the robot's ground, the threshold keeps the plateau's ground and drops the branch, as on
    // flat ground at z = 0: the cell under the branch is only seen free, the ground beyond is mapped.
    let rule = TraversabilityRule::Absolute;
    assert_eq!(
        on_plateau.traversability(cell(&on_plateau, 2.05, 0.05), &profile, rule),
        Traversability::Free
    );
    let ground = on_plateau
        .cell(cell(&on_plateau, 4.05, 0.05))
        .elevation()
        .expect("the plateau's ground is mapped");
    assert!((ground.mean_m - lift as f32).abs() < 0.05, "{ground:?}");
    // Measured in world z (a scan that does not say where its ground is), the whole scene is above 0.5 m.
    assert_eq!(world_z.num_observed_cells(), 0);
}
