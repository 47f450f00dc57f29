//! `oeg record` and the replay of its logs through `oeg map`.

#![allow(
    clippy::disallowed_methods,
    reason = "tests and tools write their inputs directly"
)]

mod common;

use common::{oeg_with_threads, temp_dir};
use std::path::PathBuf;

use oeg::{Map, MapConfig};
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
    let out = dir.join("map");
    let o = oeg_with_threads(
        &[
            "map",
            log.to_str().expect("utf8"),
            "--resolution",
            "0.05",
            "--out",
            out.to_str().expect("utf8"),
        ],
        None,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let replayed = oeg::load_map(&out.join("map.oeg")).expect("map");

    // The live run: the same simulation, integrated as it goes.
    let loaded = sim::scenario::load(&scenario).expect("valid");
    let mut simulation = sim::Simulation::new(&loaded).expect("simulation");
    let mut live = Map::new(MapConfig::new(0.05)).expect("map");
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
    assert!(text.contains("no-return rays left out of the graph"), "{text}");
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
