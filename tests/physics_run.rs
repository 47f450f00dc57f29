//! `oeg run` with the robot on its wheels: the physics files, the metrics, the recording and the page, the same
//! bytes on one and two threads.

#![allow(
    clippy::disallowed_methods,
    reason = "tests and tools write their inputs directly"
)]

mod common;

use common::{oeg_with_threads, root, s, temp_dir};

#[test]
fn a_drive_on_the_wheels_reports_what_happened_the_same_on_one_and_two_threads() {
    let scenario = root().join("scenarios/physics_curbs.toml");
    let run = |threads: &str| {
        let out = temp_dir("physics-run", threads);
        let o = oeg_with_threads(&["run", s(&scenario), "--mcap", "--out", s(&out)], Some(threads));
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        out
    };
    let (one, two) = (run("1"), run("2"));
    for file in ["physics.json", "physics.csv", "metrics.json", "map.oeg"] {
        let a = std::fs::read(one.join(file)).expect(file);
        assert_eq!(a, std::fs::read(two.join(file)).expect(file), "{file} differs");
    }

    // What happened, by name: the stall against the 8 cm curb, the body's contact with its edge.
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(one.join("physics.json")).expect("json")).expect("json");
    let kinds: Vec<&str> = summary["events"]
        .as_array()
        .expect("events")
        .iter()
        .filter_map(|e| e["kind"].as_str())
        .collect();
    assert!(
        kinds.contains(&"stall") && kinds.contains(&"contact"),
        "{kinds:?}"
    );
    assert!(summary["robot"]["wheel_torque_nm"].as_f64().expect("torque") > 0.0);
    let metrics: serde_json::Value =
        serde_json::from_slice(&std::fs::read(one.join("metrics.json")).expect("json")).expect("json");
    assert_eq!(metrics["phys_stalls"], 1);
    assert_eq!(metrics["phys_goal_reached"], false);

    // The sampled state, one row every 0.05 s of the 22 s run, climbing: the pitch passes 3 degrees.
    let csv = std::fs::read_to_string(one.join("physics.csv")).expect("csv");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let pitch = header
        .iter()
        .position(|c| *c == "pitch_deg")
        .expect("pitch column");
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap_or(f64::NAN)).collect())
        .collect();
    assert!(rows.len() >= 400, "{} rows", rows.len());
    assert!(rows.iter().any(|r| r[pitch].abs() > 3.0));

    // The recording carries the state and the events; the page shows them.
    let mcap = std::fs::read(one.join("recording.mcap")).expect("mcap");
    let has = |needle: &[u8]| mcap.windows(needle.len()).any(|w| w == needle);
    assert!(has(b"/physics") && has(b"oeg.PhysicsState") && has(b"stall: no progress"));
    let page = std::fs::read_to_string(one.join("report.html")).expect("page");
    assert!(page.contains("On its wheels") && page.contains("curb 8 cm"));
}

#[test]
fn a_kinematic_run_has_no_physics_files_or_keys() {
    let out = temp_dir("physics-run", "kinematic");
    let o = oeg_with_threads(
        &[
            "run",
            s(&root().join("scenarios/corridor_lasers.toml")),
            "--out",
            s(&out),
        ],
        None,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!out.join("physics.json").exists() && !out.join("physics.csv").exists());
    let metrics = std::fs::read_to_string(out.join("metrics.json")).expect("metrics");
    assert!(!metrics.contains("phys_"));
}
