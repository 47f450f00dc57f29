//! The data sets people compare mappers on: a KITTI odometry sequence (lidar scans placed through the camera
//! poses and the calibration) and the DynamicMap benchmark's frames (world-frame points, the sensor's pose in
//! `VIEWPOINT`), each read into the scans their definition gives.
#![allow(
    clippy::disallowed_methods,
    reason = "the tests write the data sets' files as the data sets ship them"
)]

use std::path::PathBuf;

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use oeg::{PcdCloud, PcdEncoding, PcdOptions, PcdPoints, SensorModel};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("oeg-datasets-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch");
    dir
}

/// A 3 x 4 matrix as a line of KITTI's text files.
fn line(m: &Isometry3<f64>) -> String {
    let h = m.to_homogeneous();
    (0..3)
        .flat_map(|r| (0..4).map(move |c| (r, c)))
        .map(|(r, c)| format!("{:e}", h[(r, c)]))
        .collect::<Vec<_>>()
        .join(" ")
}

#[test]
fn a_kitti_sequence_places_each_scan_through_the_camera_pose_and_the_calibration() {
    let seq = scratch("kitti").join("07");
    std::fs::create_dir_all(seq.join("velodyne")).expect("folders");
    // The lidar in the camera's frame (x forward -> z forward), at the camera (a lever arm would move the lidar
    // along an arc when the camera turns).
    let axes = UnitQuaternion::from_basis_unchecked(&[
        Vector3::new(0.0, 0.0, 1.0),
        Vector3::new(-1.0, 0.0, 0.0),
        Vector3::new(0.0, -1.0, 0.0),
    ]);
    let tr = Isometry3::from_parts(Translation3::identity(), axes);
    std::fs::write(
        seq.join("calib.txt"),
        format!("P0: 1 0 0 0 0 1 0 0 0 0 1 0\nTr: {}\n", line(&tr)),
    )
    .expect("calib");
    // The camera moves 2 m along its z (forward) and turns 90 degrees about its y (down: a left turn).
    let turn = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -std::f64::consts::FRAC_PI_2);
    let cameras = [
        Isometry3::identity(),
        Isometry3::from_parts(Translation3::new(0.0, 0.0, 2.0), turn),
    ];
    let poses: Vec<String> = cameras.iter().map(line).collect();
    std::fs::write(seq.join("poses.txt"), poses.join("\n") + "\n").expect("poses");
    // Each scan: one point 5 m ahead of the lidar, one NaN, one at the origin (both left out).
    for k in 0..2 {
        let mut bytes = Vec::new();
        for p in [
            [5.0_f32, 0.0, 0.0, 0.3],
            [f32::NAN, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 0.0],
        ] {
            for v in p {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
        std::fs::write(seq.join(format!("velodyne/{k:06}.bin")), bytes).expect("scan");
    }
    let scans = oeg::read_kitti(&seq, SensorModel::laser(), 1 << 30).expect("readable");
    assert_eq!(scans.len(), 2);
    // The first scan is the world's frame; the second lidar stands 2 m ahead, turned left, so its point 5 m
    // ahead lies 5 m to the left of the lidar.
    assert!(scans[0].1.origin_in_world.coords.norm() < 1e-9);
    let second = &scans[1].1;
    assert!(
        (second.origin_in_world - Point3::new(2.0, 0.0, 0.0)).norm() < 1e-6,
        "{}",
        second.origin_in_world
    );
    assert_eq!(second.rays.len(), 1);
    let hit = second.origin_in_world + second.rays[0].offset_in_world.cast::<f64>();
    assert!((hit - Point3::new(2.0, 5.0, 0.0)).norm() < 1e-5, "{hit}");
    // A scan whose file is not whole points is named.
    std::fs::write(seq.join("velodyne/000001.bin"), [0u8; 20]).expect("truncated");
    let e = oeg::read_kitti(&seq, SensorModel::laser(), 1 << 30).expect_err("refused");
    assert!(e.to_string().contains("000001.bin"), "{e}");
    // One pose short.
    std::fs::write(seq.join("poses.txt"), &poses[0]).expect("poses");
    let e = oeg::read_kitti(&seq, SensorModel::laser(), 1 << 30).expect_err("refused");
    assert!(e.to_string().contains("1 poses for 2 scans"), "{e}");
}

#[test]
fn a_dynamicmap_frame_is_hits_from_its_viewpoint_to_its_world_points() {
    let dir = scratch("dynamicmap");
    let viewpoint = Isometry3::from_parts(
        Translation3::new(10.0, 5.0, 1.0),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 1.0),
    );
    let cloud = PcdCloud {
        width: 2,
        height: 1,
        viewpoint,
        points: vec![Point3::new(12.0, 5.0, 0.0), Point3::new(10.0, 8.0, 0.5)],
    };
    std::fs::create_dir_all(dir.join("pcd")).expect("frames");
    let path = dir.join("pcd/000000.pcd");
    oeg::write_pcd(&path, &cloud, PcdEncoding::Binary).expect("written");
    let options = PcdOptions {
        points: PcdPoints::World,
        ..PcdOptions::default()
    };
    let scan = oeg::read_pcd_scan(&path, &options).expect("readable");
    assert_eq!(scan.origin_in_world, Point3::new(10.0, 5.0, 1.0));
    // The points stay where they are: not turned nor moved by the viewpoint a second time.
    let first = scan.origin_in_world + scan.rays[0].offset_in_world.cast::<f64>();
    assert!((first - Point3::new(12.0, 5.0, 0.0)).norm() < 1e-6);
    // The sequence's folder reads its frames so.
    let sequence = oeg::read_dynamicmap(&dir, SensorModel::laser(), 1 << 20).expect("readable");
    assert_eq!(sequence.len(), 1);
    assert_eq!(sequence[0].1.rays, scan.rays);
    assert!(oeg::read_dynamicmap(&dir.join("pcd"), SensorModel::laser(), 1 << 20).is_err());
    let placed = oeg::read_pcd_scan(&path, &PcdOptions::default()).expect("readable");
    let moved = placed.origin_in_world + placed.rays[0].offset_in_world.cast::<f64>();
    assert!(
        (moved - first).norm() > 1.0,
        "PCL's convention places the points by the viewpoint"
    );
}
