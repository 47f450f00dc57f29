//! A ROS 2 bag's ground under the robot: where its transforms hold REP 120's `base_footprint`, each scan's
//! height threshold is measured from that frame's origin at the scan's stamp, as `oeg run` measures it from the
//! wheels' contacts; a bag without the frame thresholds in the map frame's z; a scan the frame's transforms do
//! not reach is skipped and counted.
#![allow(
    clippy::disallowed_methods,
    reason = "the tests write their bags into a scratch folder"
)]

use std::path::Path;

#[path = "common/bags.rs"]
mod bags;

use bags::{scratch, transform};
use nalgebra::{Isometry3, Vector3};
use oeg::{BagOptions, BagWriter, CloudPrecision, Map, MapConfig, ModelOptions};

/// A robot standing on a plateau 2 m up (`odom` -> `base_link` at z = 2.1, its base 10 cm over the ground), a
/// lidar 0.3 m over its base, and a cloud at 1 s and at 3 s of the ground 2 to 3 m ahead. With `footprint`,
/// `base_link` -> `base_footprint` (10 cm down) is stamped at 0 and 2 s only.
fn plateau_bag(folder: &Path, footprint: bool) {
    let mut bag = BagWriter::new(folder).expect("writer");
    bag.transforms(
        "/tf_static",
        0,
        &[transform(
            "base_link",
            "lidar",
            0,
            Isometry3::translation(0.0, 0.0, 0.3),
        )],
    )
    .expect("static");
    for t in [0, 2_000_000_000, 4_000_000_000] {
        let mut tf = vec![transform(
            "odom",
            "base_link",
            t,
            Isometry3::translation(0.0, 0.0, 2.1),
        )];
        if footprint && t < 4_000_000_000 {
            tf.push(transform(
                "base_link",
                oeg::DEFAULT_GROUND_FRAME,
                t,
                Isometry3::translation(0.0, 0.0, -0.1),
            ));
        }
        bag.transforms("/tf", t, &tf).expect("tf");
    }
    // The plateau's ground, 0.4 m under the lidar, 2 to 3 m ahead.
    let points: Vec<Vector3<f64>> = (0..=20)
        .map(|k| Vector3::new(2.0 + 0.05 * f64::from(k), 0.0, -0.4))
        .collect();
    for t in [1_000_000_000, 3_000_000_000] {
        bag.cloud("/points", "lidar", t, &points, CloudPrecision::Float32)
            .expect("cloud");
    }
    bag.finish().expect("written");
}

fn cells_with_height(scans: &[oeg::BagScan]) -> usize {
    let model = ModelOptions {
        max_height_m: Some(0.5),
        ..ModelOptions::default()
    };
    let mut map = Map::new(MapConfig {
        model,
        ..MapConfig::new(0.05)
    })
    .expect("valid");
    for s in scans {
        map.integrate(&s.scan).expect("integrated");
    }
    map.observed_cells()
        .filter(|(_, c)| c.elevation().is_some())
        .count()
}

#[test]
fn a_bag_s_base_footprint_is_the_ground_its_height_threshold_measures_from() {
    let folder = scratch("rosbag-ground", "footprint");
    plateau_bag(&folder, true);
    let bag = oeg::read_bag(&folder, &BagOptions::default()).expect("readable");
    assert_eq!(bag.ground_frame.as_deref(), Some("base_footprint"));
    // The cloud at 1 s is mapped with the ground 2 m up; the one at 3 s lies past the footprint's last
    // transform (2 s): skipped, with the reason.
    assert_eq!(bag.scans.len(), 1);
    let ground = bag.scans[0].scan.ground_z_m.expect("a ground");
    assert!((ground - 2.0).abs() < 1e-9, "{ground}");
    assert_eq!(bag.skipped.len(), 1);
    assert!(
        bag.skipped[0]
            .reason
            .contains("`base_footprint` (the ground under the robot)"),
        "{}",
        bag.skipped[0].reason
    );
    // Measured from the plateau, its ground lies under the 0.5 m threshold and is mapped.
    assert!(
        cells_with_height(&bag.scans) >= 15,
        "{}",
        cells_with_height(&bag.scans)
    );
    // Another frame named as the ground, one the bag lacks: the map frame's z, where the plateau lies 2 m
    // over the threshold and nothing of it is mapped.
    let other = BagOptions {
        ground_frame: "base_link_ground".into(),
        ..BagOptions::default()
    };
    let bag = oeg::read_bag(&folder, &other).expect("readable");
    assert_eq!(bag.ground_frame, None);
    assert_eq!(bag.scans.len(), 2);
    assert!(bag.scans.iter().all(|s| s.scan.ground_z_m.is_none()));
    assert_eq!(cells_with_height(&bag.scans), 0);
    let _ = std::fs::remove_dir_all(&folder);
}

#[test]
fn a_bag_without_a_ground_frame_thresholds_in_the_map_frame_s_z() {
    let folder = scratch("rosbag-ground", "no-footprint");
    plateau_bag(&folder, false);
    let bag = oeg::read_bag(&folder, &BagOptions::default()).expect("readable");
    assert_eq!(bag.ground_frame, None);
    assert_eq!(bag.scans.len(), 2);
    assert!(bag.scans.iter().all(|s| s.scan.ground_z_m.is_none()));
    let _ = std::fs::remove_dir_all(&folder);
}
