//! ROS 2 bags: the shared real scans written as a bag map to the same bytes as the scan graph; transforms are
//! looked up through the tree and interpolated at each cloud's stamp; a hostile bag gets a clear error naming
//! its file, topic, message and field, never a panic.
#![allow(
    clippy::disallowed_methods,
    reason = "the tests write corrupt bags byte by byte and read the committed corpus whole"
)]

#[path = "common/bags.rs"]
mod bags;
mod common;

use std::path::Path;

use bags::{scratch, transform};
use common::shared_file;
use nalgebra::{Isometry3, Point3, Vector3};
use oeg::{BagOptions, BagWriter, CloudPrecision, Map, MapConfig, SensorModel};

fn map_of<'a>(scans: impl Iterator<Item = &'a oeg::Scan>) -> Vec<u8> {
    let mut map = Map::new(MapConfig::new(0.05)).expect("valid");
    for scan in scans {
        map.integrate(scan).expect("integrated");
    }
    oeg::map_to_bytes(&map)
}

#[test]
fn the_shared_real_scans_as_a_bag_map_to_the_graph_s_bytes() {
    let Some(path) = shared_file("3dtk_frames.graph") else {
        return;
    };
    let nodes = oeg::read_graph(&path).expect("readable");
    let folder = scratch("rosbag", "3dtk");
    let mut bag = BagWriter::new(&folder).expect("writer");
    for (k, node) in nodes.iter().enumerate() {
        let stamp = 1_000_000_000 + k as i64 * 100_000_000;
        let tf = transform("map", "scanner", stamp, node.world_from_sensor);
        bag.transforms("/tf", stamp, &[tf]).expect("tf");
        let points: Vec<Vector3<f64>> = node.points_in_sensor.iter().map(|p| p.coords).collect();
        bag.cloud("/scan", "scanner", stamp, &points, CloudPrecision::Float64)
            .expect("cloud");
    }
    bag.finish().expect("written");
    let read = oeg::read_bag(&folder, &BagOptions::default()).expect("readable");
    assert_eq!(read.map_frame, "map");
    assert_eq!(read.scans.len(), nodes.len());
    assert!(read.skipped.is_empty(), "{:?}", read.skipped);
    let graph_scans: Vec<_> = nodes.iter().map(|n| n.to_scan(SensorModel::laser())).collect();
    assert_eq!(
        map_of(read.scans.iter().map(|s| &s.scan)),
        map_of(graph_scans.iter()),
        "the bag's map and the graph's differ"
    );
    let _ = std::fs::remove_dir_all(&folder);
}

/// A bag of one lidar on a robot driving along x: `map` -> `odom` static, `odom` -> `base_link` stamped at 0
/// and 1 s, `base_link` -> `lidar` static, and one cloud at each of `cloud_stamps_ns`.
fn driving_bag(folder: &Path, cloud_stamps_ns: &[i64]) {
    let mut bag = BagWriter::new(folder).expect("writer");
    let up = Isometry3::translation(0.0, 0.0, 0.5);
    bag.transforms(
        "/tf_static",
        0,
        &[
            transform("map", "odom", 0, Isometry3::translation(10.0, 0.0, 0.0)),
            transform("base_link", "lidar", 0, up),
        ],
    )
    .expect("static");
    for (t, x) in [(0, 0.0), (1_000_000_000, 2.0)] {
        let odom = transform("odom", "base_link", t, Isometry3::translation(x, 0.0, 0.0));
        bag.transforms("/tf", t, &[odom]).expect("tf");
    }
    for &t in cloud_stamps_ns {
        let points = [Vector3::new(1.0, 0.0, -0.5), Vector3::new(2.0, 1.0, -0.5)];
        bag.cloud("/points", "lidar", t, &points, CloudPrecision::Float32)
            .expect("cloud");
    }
    bag.finish().expect("written");
}

#[test]
fn a_cloud_is_placed_through_the_tree_at_its_stamp_and_one_without_a_transform_is_counted() {
    let folder = scratch("rosbag", "driving");
    driving_bag(&folder, &[500_000_000, 1_500_000_000]);
    let bag = oeg::read_bag(&folder, &BagOptions::default()).expect("readable");
    assert_eq!(bag.scans.len(), 1);
    let scan = &bag.scans[0].scan;
    // Half way between x = 0 and 2 in odom, odom 10 m along map's x, the lidar 0.5 m up.
    assert!((scan.origin_in_world - Point3::new(11.0, 0.0, 0.5)).norm() < 1e-9);
    assert!((scan.rays[1].offset_in_world - Vector3::new(2.0, 1.0, -0.5)).norm() < 1e-6);
    // The cloud at 1.5 s lies 0.5 s past the last odometry transform: skipped, with the reason.
    assert_eq!(bag.skipped.len(), 1);
    assert_eq!(bag.skipped[0].count, 1);
    assert!(
        bag.skipped[0].reason.contains("0.500 s older"),
        "{}",
        bag.skipped[0].reason
    );
    // Within a tolerance it is mapped at the last transform; in the odom frame the static `map` edge is unused.
    let options = BagOptions {
        tf_tolerance_s: 0.6,
        map_frame: Some("odom".into()),
        ..BagOptions::default()
    };
    let bag = oeg::read_bag(&folder, &options).expect("readable");
    assert_eq!(bag.scans.len(), 2);
    assert!((bag.scans[1].scan.origin_in_world - Point3::new(2.0, 0.0, 0.5)).norm() < 1e-9);
    // A time range and a stride select messages by the bag's log time.
    let late = BagOptions {
        start_s: Some(1.2),
        tf_tolerance_s: 1.0,
        ..BagOptions::default()
    };
    let bag = oeg::read_bag(&folder, &late).expect("readable");
    assert_eq!((bag.scans.len(), bag.num_not_selected), (1, 1));
    let _ = std::fs::remove_dir_all(&folder);
}

/// Writes one file of a split bag into `folder` as `file` (through a bag of its own) and returns its name.
fn split_file(folder: &Path, file: &str, write: impl FnOnce(&mut BagWriter)) -> String {
    let part = scratch("rosbag", &format!("part-{file}"));
    let mut bag = BagWriter::new(&part).expect("writer");
    write(&mut bag);
    let written = bag.finish().expect("written");
    std::fs::create_dir_all(folder).expect("folder");
    std::fs::rename(&written, folder.join(file)).expect("moved");
    let _ = std::fs::remove_dir_all(&part);
    file.to_string()
}

#[test]
fn a_bag_split_over_files_reads_as_one_with_the_transforms_of_every_file() {
    // The whole bag in one file, and the same messages split as rosbag2 splits a long recording: the static
    // transforms in the first file only, each file with its own schema and channel ids (the second file's
    // topics come in another order, so its ids differ), and a cloud in the second file placed by a transform
    // from the first.
    let whole = scratch("rosbag", "whole");
    driving_bag(&whole, &[500_000_000, 900_000_000]);
    let split = scratch("rosbag", "split");
    let up = Isometry3::translation(0.0, 0.0, 0.5);
    let points = [Vector3::new(1.0, 0.0, -0.5), Vector3::new(2.0, 1.0, -0.5)];
    let first = split_file(&split, "split_0.mcap", |bag| {
        let statics = [
            transform("map", "odom", 0, Isometry3::translation(10.0, 0.0, 0.0)),
            transform("base_link", "lidar", 0, up),
        ];
        bag.transforms("/tf_static", 0, &statics).expect("static");
        let odom = transform("odom", "base_link", 0, Isometry3::identity());
        bag.transforms("/tf", 0, &[odom]).expect("tf");
        bag.cloud("/points", "lidar", 500_000_000, &points, CloudPrecision::Float32)
            .expect("cloud");
    });
    let second = split_file(&split, "split_1.mcap", |bag| {
        bag.cloud("/points", "lidar", 900_000_000, &points, CloudPrecision::Float32)
            .expect("cloud");
        let odom = transform(
            "odom",
            "base_link",
            1_000_000_000,
            Isometry3::translation(2.0, 0.0, 0.0),
        );
        bag.transforms("/tf", 1_000_000_000, &[odom]).expect("tf");
    });
    std::fs::write(
        split.join("metadata.yaml"),
        format!(
            "rosbag2_bagfile_information:\n  version: 9\n  storage_identifier: mcap\n  relative_file_paths:\n    \
             - {first}\n    - {second}\n"
        ),
    )
    .expect("metadata");
    let one = oeg::read_bag(&whole, &BagOptions::default()).expect("whole");
    let both = oeg::read_bag(&split, &BagOptions::default()).expect("split");
    assert_eq!(both.scans.len(), 2, "{:?}", both.skipped);
    assert_eq!(
        map_of(both.scans.iter().map(|s| &s.scan)),
        map_of(one.scans.iter().map(|s| &s.scan)),
        "the split bag maps as the whole one"
    );
    // The second file's cloud, at 0.9 s, between the first file's transform at 0 s and the second's at 1 s.
    assert!((both.scans[1].scan.origin_in_world - Point3::new(11.8, 0.0, 0.5)).norm() < 1e-9);
    // A file the metadata names outside the bag's folder is refused, naming the metadata and the entry.
    for outside in ["../elsewhere.mcap", "/etc/hostname"] {
        std::fs::write(
            split.join("metadata.yaml"),
            format!("rosbag2_bagfile_information:\n  relative_file_paths:\n    - {first}\n    - {outside}\n"),
        )
        .expect("metadata");
        let e = oeg::read_bag(&split, &BagOptions::default())
            .expect_err("outside the folder")
            .to_string();
        assert!(e.contains("metadata.yaml") && e.contains(outside), "{e}");
    }
    let _ = std::fs::remove_dir_all(&whole);
    let _ = std::fs::remove_dir_all(&split);
}

#[test]
fn a_grid_map_is_chosen_by_time_counted_from_the_bag_s_first_message() {
    let folder = scratch("rosbag", "grid_map_times");
    let mut bag = BagWriter::new(&folder).expect("writer");
    // The bag starts at 1 s with a transform; maps at 3 s and 5 s, 2 and 4 s after its start.
    let odom = transform("odom", "base_link", 1_000_000_000, Isometry3::identity());
    bag.transforms("/tf", 1_000_000_000, &[odom]).expect("tf");
    for (stamp_ns, level) in [(3_000_000_000, 1.0), (5_000_000_000, 2.0)] {
        let raster = oeg::BagRaster {
            frame: "map".into(),
            stamp_ns,
            origin_xy_m: [0.0, 0.0],
            resolution_m: 0.1,
            rows: 2,
            cols: 2,
        };
        bag.grid_map("/elevation_map", &raster, &[("elevation", &[level; 4])])
            .expect("grid map");
    }
    bag.finish().expect("written");
    let level_at = |at_s: Option<f64>| {
        let read = oeg::read_grid_map(&folder, "/elevation_map", at_s, 1 << 26).expect("a map");
        read.layers[0].1[0]
    };
    assert_eq!(level_at(None), 2.0, "the last map");
    assert_eq!(
        level_at(Some(3.0)),
        1.0,
        "the map at or before 3 s after the start"
    );
    assert_eq!(level_at(Some(4.0)), 2.0);
    assert_eq!(level_at(Some(60.0)), 2.0);
    let e = oeg::read_grid_map(&folder, "/elevation_map", Some(1.5), 1 << 26)
        .expect_err("no map yet")
        .to_string();
    assert!(
        e.contains("no message on /elevation_map at or before 1.5 s"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&folder);
}

#[test]
fn options_that_name_what_the_bag_lacks_are_refused() {
    let folder = scratch("rosbag", "options");
    driving_bag(&folder, &[500_000_000]);
    let e = |options: BagOptions| oeg::read_bag(&folder, &options).expect_err("refused").to_string();
    let missing = e(BagOptions {
        topics: vec!["/velodyne_points".into()],
        ..BagOptions::default()
    });
    assert!(
        missing.contains("/velodyne_points") && missing.contains("/points (sensor_msgs/msg/PointCloud2)"),
        "{missing}"
    );
    let not_range = e(BagOptions {
        topics: vec!["/tf".into()],
        ..BagOptions::default()
    });
    assert!(
        not_range.contains("not a PointCloud2 or LaserScan"),
        "{not_range}"
    );
    let frame = e(BagOptions {
        map_frame: Some("world".into()),
        ..BagOptions::default()
    });
    assert!(frame.contains("`world`") && frame.contains("odom"), "{frame}");
    assert!(
        e(BagOptions {
            stride: 0,
            ..BagOptions::default()
        })
        .contains("stride")
    );
    let _ = std::fs::remove_dir_all(&folder);
}

#[test]
fn a_corrupt_or_truncated_bag_gets_an_error_naming_the_file_never_a_panic() {
    let folder = scratch("rosbag", "corrupt");
    driving_bag(&folder, &[500_000_000]);
    let name = folder.file_name().expect("named").to_string_lossy().to_string();
    let file = folder.join(format!("{name}_0.mcap"));
    let bytes = std::fs::read(&file).expect("written");
    let options = BagOptions::default();
    // Every truncation, and a byte flipped at every position of the first 2 KiB: an error or a map, never a
    // panic; a truncated file is always an error.
    for cut in (0..bytes.len()).step_by(7) {
        std::fs::write(&file, &bytes[..cut]).expect("write");
        let e = oeg::read_bag(&file, &options).expect_err("truncated");
        assert!(e.to_string().contains(&name), "{e}");
    }
    for k in 0..bytes.len().min(2048) {
        let mut flipped = bytes.clone();
        flipped[k] ^= 0x5A;
        std::fs::write(&file, &flipped).expect("write");
        let _ = oeg::read_bag(&file, &options);
    }
    let _ = std::fs::remove_dir_all(&folder);
}

#[test]
fn every_byte_of_a_zstd_and_an_lz4_bag_flipped_gives_an_error_or_a_map_never_a_panic() {
    // Written by the Python `mcap` package in zstd and lz4 chunks (`fuzz/corpus/bag`, from the Python tests'
    // robot bag).
    let corpus = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus/bag");
    let options = BagOptions {
        odometry_topics: vec!["/odom".into()],
        ..BagOptions::default()
    };
    for name in ["robot_zstd.mcap", "robot_lz4.mcap"] {
        let bytes = std::fs::read(corpus.join(name)).expect("committed");
        let whole = oeg::parse_bag(Path::new(name), &bytes, &options, 1 << 26).expect("readable");
        assert_eq!(whole.scans.len(), 2, "{name}");
        for k in 0..bytes.len() {
            let mut flipped = bytes.clone();
            flipped[k] ^= 0xA5;
            let _ = oeg::parse_bag(Path::new(name), &flipped, &options, 1 << 26);
        }
    }
}

#[test]
fn a_written_grid_map_reads_back_and_a_corrupt_one_is_an_error_never_a_panic() {
    let folder = scratch("rosbag", "grid_map");
    let mut bag = BagWriter::new(&folder).expect("writer");
    let raster = oeg::BagRaster {
        frame: "map".into(),
        stamp_ns: 2_000_000_000,
        origin_xy_m: [-1.0, 3.0],
        resolution_m: 0.5,
        rows: 3,
        cols: 4,
    };
    let elevation: Vec<f32> = (0..12).map(|k| k as f32 * 0.1).collect();
    bag.grid_map("/elevation_map", &raster, &[("elevation", &elevation)])
        .expect("grid map");
    bag.finish().expect("written");
    let read = oeg::read_grid_map(&folder, "/elevation_map", None, 1 << 26).expect("readable");
    assert_eq!(
        (read.rows, read.cols, read.origin_xy_m, read.resolution_m),
        (3, 4, [-1.0, 3.0], 0.5)
    );
    assert_eq!(read.layers, vec![("elevation".to_string(), elevation)]);
    let e = oeg::read_grid_map(&folder, "/map", None, 1 << 26).expect_err("no such topic");
    assert!(e.to_string().contains("no topic /map"), "{e}");
    // Written by the Python `rosbags` serializer with a wrapped circular buffer (`fuzz/corpus/bag`).
    let corpus = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus/bag/grid_map_zstd.mcap");
    let bytes = std::fs::read(&corpus).expect("committed");
    let name = Path::new("grid_map_zstd.mcap");
    let whole = oeg::parse_grid_map(name, &bytes, "/elevation_map", None, 1 << 26).expect("readable");
    assert_eq!((whole.rows, whole.cols), (4, 6));
    for k in 0..bytes.len() {
        let mut flipped = bytes.clone();
        flipped[k] ^= 0xA5;
        let _ = oeg::parse_grid_map(name, &flipped, "/elevation_map", None, 1 << 26);
    }
    let _ = std::fs::remove_dir_all(&folder);
}
