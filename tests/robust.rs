//! The recommended `robust` preset against the paper's model on scenes nobody tuned for (`tests/scenes/`), each
//! seen only by the default scenario's sensors: a person who stood in front of a robot that did not move (and of
//! a wall, so that beams cross where the person's top was once they have left), curbs
//! at 15, 30 and 45 degrees to the grid either side of the 3.5 cm threshold, and a table 2 cm lower than the
//! robot.
#![allow(clippy::disallowed_methods, reason = "tests read back the files they wrote")]

mod common;

use common::{oeg, root, temp_dir};
use std::path::Path;

/// Runs `tests/scenes/<scene>.toml` with `map.preset = <preset>` into a fresh folder and returns it.
fn run(scene: &str, preset: &str) -> std::path::PathBuf {
    let out = temp_dir("robust", &format!("{scene}-{preset}"));
    let file = root().join(format!("tests/scenes/{scene}.toml"));
    let set = format!("map.preset={preset}");
    let o = oeg(&[
        "run",
        file.to_str().expect("utf8"),
        "--out",
        out.to_str().expect("utf8"),
        "--set",
        &set,
    ]);
    assert!(
        o.status.success(),
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    out
}

/// Rows of a CSV file the project writes, as header name -> value maps.
fn rows(path: &Path) -> Vec<std::collections::BTreeMap<String, String>> {
    let mut r = csv::Reader::from_path(path).expect("csv");
    let header: Vec<String> = r.headers().expect("header").iter().map(str::to_string).collect();
    r.records()
        .map(|rec| {
            let rec = rec.expect("record");
            header
                .iter()
                .cloned()
                .zip(rec.iter().map(str::to_string))
                .collect()
        })
        .collect()
}

/// The `wrong_cells.csv` rows of a kind within `radius_m` of `(x, y)`.
fn cells_near(out: &Path, error: &str, (x, y): (f64, f64), radius_m: f64) -> usize {
    rows(&out.join("wrong_cells.csv"))
        .iter()
        .filter(|r| r["error"] == error)
        .filter(|r| {
            let (cx, cy): (f64, f64) = (r["x_m"].parse().expect("x"), r["y_m"].parse().expect("y"));
            (cx - x).hypot(cy - y) <= radius_m
        })
        .count()
}

#[test]
fn a_standing_robot_forgets_a_person_who_stood_in_front_of_it() {
    // The person stood at (1.6, 0) from 0.5 to 3.5 s and was gone by 4.5 s; the run ends at 6 s, 1.5 s (37
    // scans of each laser, 7 of the camera) later: more than the documented bounds, 2 scans through the
    // structure's side of a ceiling's band and 9 through a surface's band.
    let robust = run("person_standing", "robust");
    assert_eq!(
        cells_near(&robust, "over_cautious", (1.6, 0.0), 0.4),
        0,
        "robust keeps no ghost where the person stood"
    );
    assert_eq!(cells_near(&robust, "unsafe", (1.6, 0.0), 0.4), 0);
    // Forgotten, not flagged: the cells there that are not right (uncertain ones: the camera's ground is noisy
    // at 1.6 m) hold the ground's height, not the person's.
    let ghost = rows(&robust.join("wrong_cells.csv"))
        .iter()
        .filter(|r| {
            let (x, y): (f64, f64) = (r["x_m"].parse().expect("x"), r["y_m"].parse().expect("y"));
            (x - 1.6).hypot(y) <= 0.4 && r["elevation_m"].parse::<f64>().is_ok_and(|z| z > 0.1)
        })
        .count();
    assert_eq!(
        ghost, 0,
        "cells near where the person stood still hold their height"
    );
    // The paper's model keeps one: eq. 8-9 average the person's height with the later ground hits.
    let paper = run("person_standing", "paper");
    assert!(
        cells_near(&paper, "over_cautious", (1.6, 0.0), 0.4) > 20,
        "the paper's ghost is gone: the scene no longer shows what it is for"
    );
}

#[test]
fn curbs_at_15_30_and_45_degrees_get_no_unsafe_decision_from_robust() {
    let robust = run("angled_curbs", "robust");
    let decisions = rows(&robust.join("obstacles.csv"));
    assert_eq!(decisions.len(), 6);
    for d in &decisions {
        let name = &d["name"];
        assert_ne!(d["decision"], "unsafe", "{name}: {d:?}");
        // A 4 cm curb is blocked or flagged; a 3 cm one passable or flagged, never blocked outright.
        let allowed: &[&str] = if name.starts_with("4.0") {
            &["blocked", "uncertain"]
        } else {
            &["passable", "uncertain"]
        };
        assert!(allowed.contains(&d["mapped_decision"].as_str()), "{name}: {d:?}");
    }
    // The paper's model erases the 4 cm curbs: push-broom beams passing over them count as free space.
    let paper = run("angled_curbs", "paper");
    let unsafe_curbs = rows(&paper.join("obstacles.csv"))
        .iter()
        .filter(|d| d["decision"] == "unsafe")
        .count();
    assert_eq!(unsafe_curbs, 3, "the paper's model lost every 4 cm curb");
}

#[test]
fn a_table_2_cm_lower_than_the_robot_is_never_driven_under() {
    let robust = run("low_table", "robust");
    let decisions = rows(&robust.join("obstacles.csv"));
    assert_eq!(decisions[0]["true_decision"], "blocked");
    assert_ne!(decisions[0]["decision"], "unsafe", "{:?}", decisions[0]);
    let metrics: serde_json::Value =
        serde_json::from_slice(&std::fs::read(robust.join("metrics.json")).expect("metrics.json"))
            .expect("json");
    assert_eq!(metrics["plan_unsafe_cells"], 0, "no planned cell near the table");
    // The paper's model maps the ground seen under it: the table is gone.
    let paper = run("low_table", "paper");
    assert_eq!(rows(&paper.join("obstacles.csv"))[0]["decision"], "unsafe");
    // Under both, cells under the table's middle are blind (no ray ended under it within the robot's height)
    // and, under the paper's, its edges are not: `wrong_cells.csv` tells them apart as the metrics count them.
    for out in [&robust, &paper] {
        let m: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("metrics.json")).expect("metrics.json"))
                .expect("json");
        let unsafe_rows = rows(&out.join("wrong_cells.csv"))
            .into_iter()
            .filter(|r| r["error"] == "unsafe")
            .collect::<Vec<_>>();
        let blind = unsafe_rows.iter().filter(|r| r["blind"] == "true").count() as u64;
        assert!(blind > 0, "{}: a blind unsafe cell", out.display());
        assert_eq!(Some(blind), m["blind_cells"].as_u64(), "{}", out.display());
        assert_eq!(
            Some(unsafe_rows.len() as u64 - blind),
            m["unsafe_observable_cells"].as_u64(),
            "{}",
            out.display()
        );
    }
}

/// The shipped scenes under `robust`: regression bounds measured on 2026-12-06 (`oeg suite scenarios --set
/// map.preset=robust`), once a scan's measurements decorrelated with the distance between views and a hit was
/// weighted by the noise its beam has where it meets the surface, and the navigator kept its path while it
/// stayed valid (`[navigation] replan = "when_invalid"`). They pin what the preset does today, not what it
/// should do: the scenarios' own `[expectations]` (set for their own settings) fail under it. The planner
/// finds no path on the final map in 4 of the 24 scenes: `large_outdoor` (far stereo ground, `imprecise`),
/// `nav_curbs` (the 3 cm curb across the way is uncertain, and the robot turns back and forth before it until
/// its time runs out: the finding of issue 40), `physics_nav_slope` (two tilted lasers see a strip of ground
/// little wider than the robot, and the frontier leaves it undecided) and `spurious_returns` (spurious
/// returns leave blocked specks across the way). Against the bounds before: fewer unsafe step cells on
/// `default` (26 to 1) and `physics_nav_curbs` (100 to 65), more on `curb_staircase` (9 to 13),
/// `ramp_and_slope` (31 to 43) and `nav_curbs` (106 to 120), and more unsafe clearance cells where the robot
/// drives past a board (`physics_nav_board` 69 to 142, `nav_blind_spot` 188 to 236): with variances that
/// shrink again as the robot moves, fewer cells are uncertain and more are decided, some wrongly.
const ROBUST_BOUNDS: [(&str, u64, u64, f64); 24] = [
    // (scenario, unsafe step cells, unsafe clearance cells: measured + about 10 % + 2; elevation within 2 sigma:
    // measured - 0.02).
    ("boards_and_branches", 2, 5, 0.96),
    ("corridor_lasers", 4, 2, 0.96),
    ("curb_staircase", 17, 2, 0.96),
    ("curbs_and_boards", 2, 41, 0.94),
    ("default", 4, 175, 0.92),
    ("large_outdoor", 2, 380, 0.97),
    ("long_range_stereo", 2, 2, 0.90),
    ("nav_around_wall", 4, 2, 0.96),
    ("nav_blind_spot", 2, 262, 0.95),
    ("nav_board_and_branch", 2, 61, 0.94),
    ("nav_curbs", 134, 2, 0.96),
    ("nav_person_crossing", 4, 2, 0.95),
    ("outdoor_stereo", 2, 2, 0.90),
    ("people_walking", 2, 2, 0.86),
    // The robot on its wheels.
    ("physics_curbs", 88, 2, 0.90),
    // Physics in the closed loop.
    ("physics_nav_board", 2, 159, 0.91),
    ("physics_nav_curbs", 74, 2, 0.93),
    ("physics_nav_slope", 7, 2, 0.90),
    ("pose_drift", 10, 2, 0.96),
    ("ramp_and_slope", 50, 2, 0.96),
    ("spurious_returns", 2, 2, 0.96),
    ("thin_pole", 2, 2, 0.97),
    ("trees_no_threshold", 7, 2, 0.94),
    ("trees_threshold", 7, 2, 0.94),
];

#[test]
fn the_shipped_scenes_under_robust_stay_within_their_measured_bounds() {
    let out = temp_dir("robust", "suite");
    let o = oeg(&[
        "suite",
        root().join("scenarios").to_str().expect("utf8"),
        "--out",
        out.to_str().expect("utf8"),
        "--set",
        "map.preset=robust",
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    let rows: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("suite.json")).expect("suite.json")).expect("json");
    let rows = rows.as_array().expect("rows");
    assert_eq!(rows.len(), ROBUST_BOUNDS.len(), "{stderr}");
    for (scenario, step, clearance, within_2sigma) in ROBUST_BOUNDS {
        let row = rows.iter().find(|r| r["scenario"] == scenario).expect(scenario);
        assert_ne!(row["status"], "error", "{scenario}: {row}");
        // Wherever a path is planned on the robust map, no cell of it is near a true obstacle.
        assert_eq!(row["plan_unsafe_cells"], 0, "{scenario}: {row}");
        let count = |key: &str| row[key].as_u64().expect(key);
        assert!(count("unsafe_step_cells") <= step, "{scenario}: {row}");
        assert!(count("unsafe_clearance_cells") <= clearance, "{scenario}: {row}");
        let metrics: serde_json::Value = serde_json::from_slice(
            &std::fs::read(out.join(scenario).join("metrics.json")).expect("metrics.json"),
        )
        .expect("json");
        let calibration = metrics["elevation_within_2sigma"]
            .as_f64()
            .expect("within 2 sigma");
        assert!(
            calibration >= within_2sigma,
            "{scenario}: within 2 sigma {calibration}"
        );
    }
}
