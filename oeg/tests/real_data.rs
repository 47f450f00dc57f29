//! The shared real files (`../shared/data` beside the project, or `$OEG_SHARED_DATA`), read when present.
//! A user's clone does not have them: each test then prints why it skipped and passes.

mod common;

use common::shared_file;
use oeg::{Map, MapConfig, SensorModel};

#[test]
fn the_3dtk_scan_graph_reads_and_maps() {
    let Some(path) = shared_file("3dtk_frames.graph") else {
        return;
    };
    let nodes = oeg::read_graph(&path).expect("readable");
    assert_eq!(nodes.len(), 3);
    let num_points: usize = nodes.iter().map(|n| n.points_in_sensor.len()).sum();
    assert_eq!(num_points, 233_028);
    let scans: Vec<_> = nodes.iter().map(|n| n.to_scan(SensorModel::laser())).collect();
    let mut map = Map::new(MapConfig::new(0.1)).expect("valid");
    for scan in &scans {
        map.integrate(scan).expect("integrated");
    }
    assert_eq!(map.totals().num_rays, 233_028);
    assert!(map.num_observed_cells() > 1000);
    // The floor is about 0.58 m below the first scan's origin: the most common elevation among occupied cells
    // is near it.
    let floor_z = scans[0].origin_in_world.z - 0.58;
    let near_floor = map
        .observed_cells()
        .filter(|(c, _)| map.is_occupied(*c) == Some(true))
        .filter_map(|(_, c)| c.elevation())
        .filter(|e| (f64::from(e.mean_m) - floor_z).abs() < 0.1)
        .count();
    assert!(near_floor > 100, "{near_floor} floor cells");
}

#[test]
fn octomaps_spherical_scan_reads() {
    let Some(path) = shared_file("spherical_scan.graph") else {
        return;
    };
    let scans = oeg::read_graph_scans(&path, SensorModel::laser()).expect("readable");
    assert_eq!(scans.len(), 1);
    assert_eq!(scans[0].rays.len(), 10_201);
}

#[test]
fn the_kinect_frame_reads_in_the_optical_frame() {
    let Some(path) = shared_file("office1.pcd") else {
        return;
    };
    let cloud = oeg::read_pcd(&path).expect("readable");
    assert_eq!((cloud.width, cloud.height), (640, 480));
    assert_eq!(cloud.num_valid(), 254_456);
    let options = oeg::PcdOptions {
        frame: oeg::PcdFrame::Optical,
        invalid_points: oeg::InvalidPoints::NoReturn,
        ..oeg::PcdOptions::default()
    };
    let scan = cloud.to_scan(&options).expect("pinhole fit");
    assert_eq!(scan.rays.len(), 307_200);
    assert_eq!(scan.num_hits(), 254_456);
    // In the robot frame the camera looks along +x: the points are in front of it.
    let ahead = scan.rays.iter().filter(|r| r.offset_in_world.x > 0.0).count();
    assert_eq!(ahead, scan.rays.len());
    let mut map = Map::new(MapConfig::new(0.05)).expect("valid");
    map.integrate(&scan).expect("integrated");
    assert!(map.num_observed_cells() > 1000);
}
