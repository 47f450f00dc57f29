//! `oeg run` end to end through the built binary, on the hand-built scenes of `tests/scenes/`: the static
//! decision scene (curbs, a board, a branch) and the person who crosses and leaves.
#![allow(clippy::disallowed_methods, reason = "tests read back the files they wrote")]

mod common;

use common::{oeg_with_threads, temp_dir};
use std::path::{Path, PathBuf};
use std::process::Output;

use oeg::{RobotProfile, Traversability, TraversabilityRule};

fn scene(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("tests/scenes/{name}.toml"))
}

fn run(out: &Path, extra: &[&str], threads: Option<&str>) -> Output {
    run_scene("decisions", out, extra, threads)
}

fn run_scene(name: &str, out: &Path, extra: &[&str], threads: Option<&str>) -> Output {
    let scene = scene(name);
    let mut args = vec![
        "run",
        scene.to_str().expect("utf8"),
        "--out",
        out.to_str().expect("utf8"),
    ];
    args.extend_from_slice(extra);
    oeg_with_threads(&args, threads)
}

fn metrics(out: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(out.join("metrics.json")).expect("metrics.json")).expect("json")
}

/// The fraction of the cells in the rectangle `[x0, x1] x [y0, y1]` (shrunk by one cell on each side) that the
/// map classes as blocked.
fn blocked_fraction(map: &oeg::Map, (x0, y0): (f64, f64), (x1, y1): (f64, f64)) -> f64 {
    let g = *map.geometry();
    let r = g.resolution_m();
    let region = g
        .region_covering((x0 + r, y0 + r), (x1 - r, y1 - r))
        .expect("region");
    let blocked = region
        .cells()
        .filter(|c| {
            map.traversability(*c, &RobotProfile::default(), TraversabilityRule::Absolute)
                == Traversability::Blocked
        })
        .count();
    blocked as f64 / region.num_cells() as f64
}

#[test]
fn the_decision_scene_gets_the_papers_decisions_right() {
    let out = temp_dir("run", "decisions");
    let o = run(&out, &[], None);
    assert!(
        o.status.success(),
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    for name in [
        "metrics.json",
        "timing.json",
        "map.oeg",
        "occupancy.png",
        "elevation.png",
        "variance.png",
        "traversability.png",
        "truth_elevation.png",
        "elevation_error.png",
        "decisions.png",
        "plan.csv",
    ] {
        assert!(out.join(name).is_file(), "{name} missing");
    }
    let m = metrics(&out);
    for key in [
        "scenario",
        "seed",
        "num_cells",
        "num_observed_cells",
        "coverage",
        "elevation_rmse_m",
        "elevation_mae_m",
        "elevation_bias_m",
        "elevation_p95_abs_err_m",
        "elevation_within_2sigma",
        "occupancy_brier",
        "num_scored_cells",
        "right_drivable_cells",
        "right_blocked_cells",
        "unsafe_cells",
        "overcautious_cells",
        "uncertain_cells",
        "uncertain_truly_blocked_cells",
        "unsafe_step_cells",
        "overcautious_step_cells",
        "num_clearance_cells",
        "unsafe_clearance_cells",
        "overcautious_clearance_cells",
        "map_bytes",
        "num_scans",
        "num_rays",
        "plan_found",
        "plan_length_m",
        "plan_unsafe_cells",
        "truth_plan_found",
        "truth_plan_length_m",
        "plan_length_ratio",
        "expectations_passed",
    ] {
        assert!(m.get(key).is_some(), "metrics.json lacks {key}");
    }
    assert_eq!(m["scenario"], "decisions");
    assert!(m["coverage"].as_f64().expect("number") > 0.95);
    assert!(m["elevation_rmse_m"].as_f64().expect("number") < 0.06);
    let timing: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("timing.json")).expect("read")).expect("json");
    assert!(timing["simulation_rays_per_s"].as_f64().expect("number") > 0.0);

    // Every truly blocked cell is mapped blocked (measured over seeds 1 to 5: 0 each time); the over-cautious
    // cells are the halo that range noise spreads around the board and the curbs' front faces.
    assert_eq!(m["unsafe_step_cells"], 0, "unsafe step cells");
    assert_eq!(m["unsafe_clearance_cells"], 0, "unsafe clearance cells");
    assert!(m["num_clearance_cells"].as_u64().expect("count") > 100);
    let wrong = std::fs::read_to_string(out.join("wrong_cells.csv")).expect("wrong_cells.csv");
    assert!(wrong.starts_with("x_m,y_m,error,mapped,"), "{wrong}");
    assert_eq!(
        wrong.lines().count() as u64 - 1,
        m["overcautious_step_cells"].as_u64().expect("count"),
        "one row per wrong cell, all over-cautious"
    );

    // The planner drives from the start to the goal on the map as it would on the truth, near no obstacle.
    assert_eq!(m["plan_found"], true);
    assert_eq!(m["plan_unsafe_cells"], 0);
    assert_eq!(m["plan_length_ratio"], 1.0);
    let plan = std::fs::read_to_string(out.join("plan.csv")).expect("plan.csv");
    assert!(
        plan.starts_with("path,step,x_m,y_m,unsafe_cell,blind_cell\nmap,0,"),
        "{plan}"
    );
    assert!(plan.lines().any(|l| l.starts_with("truth,")), "{plan}");

    let map = oeg::load_map(&out.join("map.oeg")).expect("map");
    let curb_3cm = blocked_fraction(&map, (3.3, -1.4), (3.7, -0.6));
    let curb_5cm = blocked_fraction(&map, (3.3, 0.6), (3.7, 1.4));
    let board = blocked_fraction(&map, (4.3, -1.05), (4.7, -0.45));
    let branch = blocked_fraction(&map, (4.3, 0.45), (4.7, 1.05));
    assert_eq!(curb_3cm, 0.0, "the 3 cm curb is traversable");
    assert_eq!(curb_5cm, 1.0, "the 5 cm curb is blocked");
    assert!(board > 0.9, "the 0.35 m board is blocked: {board}");
    assert_eq!(branch, 0.0, "the robot passes under the 0.6 m branch");
}

#[test]
fn the_person_who_crossed_and_left_is_gone_from_the_map() {
    let out = temp_dir("run", "person");
    let o = run_scene("person", &out, &[], None);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m = metrics(&out);
    assert_eq!(m["unsafe_step_cells"], 0);
    // Measured 0 over seeds 1 to 5: nothing of the person is left.
    assert_eq!(
        m["overcautious_step_cells"], 0,
        "cells still blocked by the person"
    );
    let map = oeg::load_map(&out.join("map.oeg")).expect("map");
    // The person crossed x = 3 from y = -2 to 2 while the robot watched from 2.5 m.
    let crossing = blocked_fraction(&map, (2.7, -1.9), (3.3, 1.9));
    assert_eq!(crossing, 0.0, "the person is gone from the map");
    assert_eq!(
        m["plan_found"], true,
        "the planner reaches the goal where the person walked"
    );
    // And the person was seen: without the clearing the crossing stays blocked.
    let frozen = temp_dir("run", "person_frozen");
    let o = run_scene(
        "person",
        &frozen,
        &["--set", "map.model.free_space_max_depth_m=0.0"],
        None,
    );
    assert!(
        !o.status.success(),
        "the scene's expectations catch the person left behind"
    );
    let map = oeg::load_map(&frozen.join("map.oeg")).expect("map");
    let crossing = blocked_fraction(&map, (2.7, -1.9), (3.3, 1.9));
    assert!(crossing > 0.2, "{crossing}");
    let m = metrics(&frozen);
    assert_eq!(m["plan_found"], false, "the person left behind blocks the goal");
    assert_eq!(m["truth_plan_found"], true);
    // The rays reached the corridor the person left: the map, not the sensors' reach, lacks the path.
    assert_eq!(m["observable_truth_plan_found"], true);
}

#[test]
fn metrics_are_identical_across_runs_and_thread_counts() {
    let dir = temp_dir("run", "determinism");
    let short = ["--set", "duration_s=5.0"];
    let bytes = |name: &str, threads: &str| {
        let out = dir.join(name);
        let o = run(&out, &short, Some(threads));
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (
            std::fs::read(out.join("metrics.json")).expect("metrics"),
            std::fs::read(out.join("decisions.png")).expect("png"),
        )
    };
    let a = bytes("a", "2");
    let b = bytes("b", "2");
    let one = bytes("one", "1");
    assert!(a == b, "two runs differ");
    assert!(a == one, "1 and 2 threads differ");
}

#[test]
fn a_failed_expectation_exits_non_zero_and_names_it() {
    let out = temp_dir("run", "expect");
    let o = run(
        &out,
        &[
            "--set",
            "duration_s=3.0",
            "--set",
            "expectations.num_scans={ max = 1 }",
        ],
        None,
    );
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("expectation failed: num_scans = ") && err.contains("(required <= 1)"),
        "{err}"
    );
    assert_eq!(metrics(&out)["expectations_passed"], false);
}

#[test]
fn bad_overrides_and_unknown_metrics_are_clear_errors() {
    let out = temp_dir("run", "bad");
    for (args, expected) in [
        (vec!["--set", "duration_s"], "expected key=value"),
        (vec!["--set", "robot.wheels=4"], "unknown field `wheels`"),
        (vec!["--set", "sensors.9.rate_hz=1"], "no index 9"),
        (vec!["--set", "map.resolution_m=-1"], "resolution_m"),
        (
            vec!["--set", "expectations.speed={ max = 1 }"],
            "`speed` is not a metric",
        ),
        (vec!["--set", "name.first=1"], "is a value, not a table"),
        (
            vec!["--set", "map.model.free_space_max_depth_m=-1"],
            "invalid setting `free_space_max_depth_m`: must be a depth in metres >= 0, got -1",
        ),
        // The error names the override, not a line of the rewritten scenario.
        (
            vec!["--set", "map.resolution_m=0.05", "--set", "map.model.p_max=2"],
            "decisions.toml: --set map.model.p_max=2: `map.model`: invalid setting `p_max`",
        ),
    ] {
        let o = run(&out, &args, None);
        assert!(!o.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains(expected) && !err.contains("panicked"),
            "{args:?}: {err}"
        );
    }
}
