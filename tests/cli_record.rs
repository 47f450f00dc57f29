//! `oeg record` and the replay of its logs through `oeg map`.

#![allow(
    clippy::disallowed_methods,
    reason = "tests and tools write their inputs directly"
)]

mod common;

use common::{map_at, oeg_with_threads, temp_dir};
use std::path::PathBuf;

use oeg::{Map, MapConfig, MapPreset, RobotProfile};
use sim::sensors::PoseSource;

/// A short run of the curbs scenario with a noisy laser and drift, written beside a copy of the robot.
fn short_scenario(dir: &std::path::Path) -> PathBuf {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    std::fs::create_dir_all(dir.join("robots")).expect("dir");
    std::fs::copy(
        root.join("robots/pioneer3at.urdf"),
        dir.join("robots/pioneer3at.urdf"),
    )
    .expect("copy");
    let text = std::fs::read_to_string(root.join("curbs_and_boards.toml"))
        .expect("read")
        .replace("duration_s = 20.0", "duration_s = 3.0")
        .replace(
            "rpy_deg = [0.0, 30.0, 10.0]",
            "rpy_deg = [0.0, 30.0, 10.0]\nrate_hz = 20.0\n[sensors.noise]\nrange_sigma_m = 0.01\ndropout_probability = 0.05\nangular_jitter_deg = 0.1",
        )
        .replace("[robot.drive]", "[robot.odometry]\nxy_sigma_m_per_sqrt_m = 0.01\n\n[robot.drive]");
    let path = dir.join("short.toml");
    std::fs::write(&path, text).expect("write");
    path
}

#[test]
fn logs_are_identical_on_one_and_two_threads_and_differ_with_the_seed() {
    let dir = temp_dir("rec", "threads");
    let scenario = short_scenario(&dir);
    let s = scenario.to_str().expect("utf8");
    let record = |name: &str, threads: &str, seed: Option<&str>| {
        let out = dir.join(name);
        let mut args = vec!["record", s, "--out", out.to_str().expect("utf8")];
        if let Some(seed) = seed {
            args.extend(["--seed", seed]);
        }
        let o = oeg_with_threads(&args, Some(threads));
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        std::fs::read(out).expect("log")
    };
    let one = record("one.oeglog", "1", None);
    let two = record("two.oeglog", "2", None);
    assert!(one == two, "the same seed gave different logs on 1 and 2 threads");
    let other = record("other.oeglog", "2", Some("99"));
    assert!(one != other, "a different seed changes the noise");
}

#[test]
fn a_replayed_log_gives_the_same_map_as_the_live_simulation() {
    let dir = temp_dir("rec", "replay");
    let scenario = short_scenario(&dir);
    let log = dir.join("run.oeglog");
    let o = oeg_with_threads(
        &[
            "record",
            scenario.to_str().expect("utf8"),
            "--out",
            log.to_str().expect("utf8"),
        ],
        None,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("M simulated rays/s"));
    // The paper's model, and `robust`, whose contact rule takes the ground under the robot's start from the
    // log's header as `oeg run` takes it from the simulation.
    for preset in [MapPreset::Paper, MapPreset::Robust] {
        let out = dir.join(format!("map-{}", preset.name()));
        let set = format!("map.preset={}", preset.name());
        let o = map_at(&log, &out, &["--set", &set]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let replayed = oeg::load_map(&out.join("map.oeg")).expect("map");

        // The live run: the same simulation, integrated as it goes.
        let loaded = sim::scenario::load(&scenario).expect("valid");
        let mut simulation = sim::Simulation::new(&loaded).expect("simulation");
        let robot = RobotProfile::default();
        let mut live = Map::new(MapConfig {
            model: preset.model(&robot),
            ..MapConfig::new(0.05)
        })
        .expect("map");
        let stance = simulation.world().estimated_stance().expect("a robot on wheels");
        let start = live
            .geometry()
            .cell_of(stance.pose.x_m, stance.pose.y_m)
            .expect("cell");
        if preset.traversability().needs_stance() {
            live.integrate_stance(&stance).expect("stance");
        }
        while let Some(scan) = simulation.next_scan() {
            let model = simulation.sensors()[scan.sensor_index].map_model();
            live.integrate(&scan.to_scan(PoseSource::Estimated, model))
                .expect("integrated");
        }
        assert_eq!(live.num_scans(), replayed.num_scans());
        assert_eq!(live.num_observed_cells(), replayed.num_observed_cells());
        for (c, cell) in live.observed_cells() {
            let r = replayed.cell(c);
            assert_eq!(
                [cell.log_odds, cell.mean_m, cell.var_m2].map(f32::to_bits),
                [r.log_odds, r.mean_m, r.var_m2].map(f32::to_bits),
                "{c:?}"
            );
        }
        // The lasers look ahead: only the stance observes the ground under the start, at the wheels' height.
        let under = replayed.cell(start);
        match preset {
            MapPreset::Robust => {
                let z = stance.contacts.iter().map(|p| p.z).sum::<f64>() / stance.contacts.len() as f64;
                assert!((f64::from(under.mean_m) - z).abs() < 0.01, "{under:?} {z}");
            }
            _ => assert!(!under.is_observed(), "{under:?}"),
        }
    }
}

#[test]
fn graph_export_keeps_the_hits() {
    let dir = temp_dir("rec", "graph");
    let scenario = short_scenario(&dir);
    let graph = dir.join("run.graph");
    let o = oeg_with_threads(
        &[
            "record",
            scenario.to_str().expect("utf8"),
            "--out",
            graph.to_str().expect("utf8"),
            "--format",
            "graph",
        ],
        None,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("no-return rays left out (a graph or a DynamicMap frame holds hits only)"),
        "{text}"
    );
    let scans = oeg::read_graph_scans(&graph, oeg::SensorModel::laser()).expect("a valid graph");
    assert_eq!(scans.len(), 61 + 226, "3 s of a laser at 20 Hz and one at 75 Hz");
    assert!(scans.iter().all(|s| s.num_hits() == s.rays.len()));
}

#[test]
fn recording_a_bad_scenario_fails_cleanly() {
    let dir = temp_dir("rec", "bad");
    let scenario = short_scenario(&dir);
    let text = std::fs::read_to_string(&scenario)
        .expect("read")
        .replace("dropout_probability = 0.05", "dropout_probability = -1.0");
    std::fs::write(&scenario, text).expect("write");
    let out = dir.join("never.oeglog");
    let o = oeg_with_threads(
        &[
            "record",
            scenario.to_str().expect("utf8"),
            "--out",
            out.to_str().expect("utf8"),
        ],
        None,
    );
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("short.toml:") && err.contains("dropout_probability"),
        "{err}"
    );
    assert!(!out.exists());
}

/// The values of a binary PCD's four float32 fields (`x y z intensity`), point by point.
fn pcd_xyzi(path: &std::path::Path) -> Vec<[f32; 4]> {
    let data = std::fs::read(path).expect("pcd");
    let marker = b"DATA binary\n";
    let start = data
        .windows(marker.len())
        .position(|w| w == marker)
        .expect("a binary PCD")
        + marker.len();
    data[start..]
        .chunks_exact(16)
        .map(|p| {
            std::array::from_fn(|k| f32::from_le_bytes(p[4 * k..4 * k + 4].try_into().expect("4 bytes")))
        })
        .collect()
}

#[test]
fn a_dynamicmap_sequence_labels_the_points_people_returned_and_maps_back() {
    let dir = temp_dir("rec", "dynamicmap");
    let out = dir.join("people");
    let scenario = common::root().join("scenarios/people_walking.toml");
    let o = common::oeg(&[
        "record",
        common::s(&scenario),
        "--format",
        "dynamicmap",
        "--out",
        common::s(&out),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut frames: Vec<_> = std::fs::read_dir(out.join("pcd"))
        .expect("frames")
        .map(|e| e.expect("entry").path())
        .collect();
    frames.sort();
    let printed = String::from_utf8_lossy(&o.stdout);
    assert!(
        printed.contains(&format!("recorded {} scans", frames.len())),
        "{printed}"
    );
    // The ground truth is every frame's points and labels in order, as the benchmark's evaluation reads it.
    let gt = pcd_xyzi(&out.join("gt_cloud.pcd"));
    let concatenated: Vec<[f32; 4]> = frames.iter().flat_map(|f| pcd_xyzi(f)).collect();
    assert!(gt == concatenated, "gt_cloud.pcd is not the frames in order");
    assert!(gt.iter().all(|p| p[3] == 0.0 || p[3] == 1.0), "labels are 0 or 1");
    let dynamic: Vec<_> = gt.iter().filter(|p| p[3] == 1.0).collect();
    // People walk through the scene: some returns are theirs, standing up from the ground (flat, z = 0).
    assert!(dynamic.len() > 1000, "{} dynamic points", dynamic.len());
    let mut heights: Vec<f32> = dynamic.iter().map(|p| p[2]).collect();
    heights.sort_by(f32::total_cmp);
    let median = heights[heights.len() / 2];
    assert!(
        median > 0.3 && heights[heights.len() - 1] < 2.5,
        "people's returns at {median} m"
    );
    // The folder maps back: one ray a point, from each frame's VIEWPOINT.
    let map = dir.join("map");
    let o = common::oeg(&[
        "map",
        common::s(&out),
        "--resolution",
        "0.1",
        "--out",
        common::s(&map),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(map.join("summary.json")).expect("summary"))
            .expect("json");
    assert_eq!(summary["num_rays"].as_u64(), Some(gt.len() as u64));
    assert_eq!(summary["num_scans"].as_u64(), Some(frames.len() as u64));
}

#[test]
fn a_recorded_ros2_bag_maps_as_the_run_maps_the_same_scans() {
    // `oeg record --format rosbag2` writes every ray (a ray that returned nothing as NaN coordinates and its
    // cleared end) with its range error, so `oeg map` of the bag in the `odom` frame (the estimated pose), with
    // the scenario's model, integrates what `oeg run` integrates: the same float32 vectors in the sensor's
    // frame, rotated in float64 by the same pose (the bag's `odom -> base_link -> sensor` composes back to the
    // run's pose within the last bits of a float64), stored in float32. The same map, byte for byte.
    let dir = temp_dir("rec", "rosbag2_round_trip");
    let scenario = short_scenario(&dir);
    let (bag, run, mapped, in_map) = (
        dir.join("bag"),
        dir.join("run"),
        dir.join("mapped"),
        dir.join("in_map"),
    );
    // The bag mapped with the scenario's model (curbs_and_boards' `[map.model]`).
    fn map_bag<'a>(bag: &'a std::path::Path, out: &'a std::path::Path, extra: &[&'a str]) -> Vec<&'a str> {
        let mut args = vec![
            "map",
            common::s(bag),
            "--resolution",
            "0.05",
            "--set",
            "map.model.max_height_m=0.5",
            "--out",
            common::s(out),
        ];
        args.extend(extra);
        args
    }
    for args in [
        vec![
            "record",
            common::s(&scenario),
            "--format",
            "rosbag2",
            "--out",
            common::s(&bag),
        ],
        vec!["run", common::s(&scenario), "--out", common::s(&run)],
        map_bag(&bag, &mapped, &["--set", "input.bag.map_frame=odom"]),
        map_bag(&bag, &in_map, &[]),
    ] {
        let o = common::oeg(&args);
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        if args[0] == "map" {
            let said = String::from_utf8_lossy(&o.stdout);
            assert!(
                said.contains("height threshold 0.5 m over the ground under the robot at every scan"),
                "{said}"
            );
        }
    }
    let bytes = |d: &std::path::Path| std::fs::read(d.join("map.oeg")).expect("map");
    assert!(
        bytes(&run) == bytes(&mapped),
        "the bag's map differs from the run's"
    );
    // Every scan's height threshold measured from the ground under the robot, the bag's `base_footprint`.
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(mapped.join("summary.json")).expect("summary")).expect("json");
    assert!(summary["num_scans"].as_u64().is_some_and(|n| n > 0));
    assert_eq!(summary["num_scans_with_ground"], summary["num_scans"]);
    // In the `map` frame (the true pose), the same scans land elsewhere: the drift is in the bag's transforms.
    assert!(
        bytes(&in_map) != bytes(&mapped),
        "the true and the estimated pose gave the same map"
    );
}

#[test]
fn a_log_whose_stance_is_not_finite_is_refused_naming_the_file() {
    let dir = temp_dir("rec", "bad_stance");
    let robot = sim::log::LogStance {
        wheel_contacts_m: vec![[0.1, 0.2, -0.19], [0.1, -0.2, -0.19], [-0.1, 0.2, -0.19]],
        footprint_m: [-0.25, 0.25, -0.25, 0.25],
        true_world_from_base: [0.0, 0.0, 0.19, 1.0, 0.0, 0.0, 0.0],
        estimated_world_from_base: [0.0, 0.0, 0.19, 1.0, 0.0, 0.0, 0.0],
    };
    let zero_rotation = sim::log::LogStance {
        estimated_world_from_base: [0.0; 7],
        ..robot.clone()
    };
    let huge_contact = sim::log::LogStance {
        wheel_contacts_m: vec![[0.1, 0.2, f64::MAX], [0.1, -0.2, f64::MAX]],
        ..robot
    };
    for (name, stance, words) in [
        ("zero_rotation", zero_rotation, "zero rotation"),
        ("huge_contact", huge_contact, "no finite plane"),
    ] {
        let log = dir.join(format!("{name}.oeglog"));
        let header = sim::log::LogHeader {
            scenario: name.into(),
            seed: 1,
            duration_s: 1.0,
            sensors: Vec::new(),
            stance: Some(stance),
        };
        let writer = sim::log::LogWriter::create(&log, &header).expect("log");
        writer.finish().expect("finished");
        let out = dir.join(name);
        let o = map_at(&log, &out, &[]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{name}: mapped");
        assert!(
            stderr.contains(&format!("{name}.oeglog")) && stderr.contains("stance") && stderr.contains(words),
            "{name}: {stderr}"
        );
        assert!(!out.exists(), "{name}: an output folder was left");
    }
}
