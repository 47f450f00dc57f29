//! `oeg score` through the built binary: the testbed's own map, written out as another tool would write it
//! (`.npy` layers with their sidecar, and a nav2 map), scores to what `oeg run` reported for it; bad inputs
//! are refused with the file and what was expected.

#![allow(clippy::disallowed_methods, reason = "tests write their inputs directly")]

mod common;

use common::{err, oeg, s, temp_dir};
use std::path::{Path, PathBuf};

use oeg::{NpyArray, NpyData, UncertainCells};

/// The decision scene's first 4 s (the curbs and the board in sight): its expectations may fail, its report is
/// written all the same.
const SHORT: [&str; 2] = ["--set", "duration_s=4.0"];

fn scene() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/scenes/decisions.toml")
}

fn json(path: &Path) -> serde_json::Map<String, serde_json::Value> {
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(path).expect("read")).expect("json");
    v.as_object().expect("object").clone()
}

fn count(m: &serde_json::Map<String, serde_json::Value>, key: &str) -> u64 {
    m[key].as_u64().unwrap_or_else(|| panic!("{key}: {}", m[key]))
}

/// The standard output of `oeg score`, which exits non-zero exactly when the scenario's expectations fail
/// (its files written all the same).
fn stdout_judged(o: &std::process::Output) -> String {
    let said = String::from_utf8_lossy(&o.stdout).into_owned();
    if !o.status.success() {
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains("of the scenario's expectations failed"), "{said}\n{e}");
    }
    said
}

/// Runs the decision scene, then writes its map's layers over the scenario's region as another mapper would
/// (`oeg::planner_files`: `.npy` layers, `layers.json`, a nav2 map).
fn run_and_export(dir: &Path) -> (PathBuf, PathBuf) {
    let run = dir.join("run");
    let o = oeg(&["run", s(&scene()), "--out", s(&run), SHORT[0], SHORT[1]]);
    assert!(
        run.join("metrics.json").is_file(),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let loaded = oeg_eval::pipeline::load(&oeg_eval::pipeline::RunOptions {
        scenario: scene(),
        overrides: vec![SHORT[1].to_string()],
        ..Default::default()
    })
    .expect("scenario");
    let sc = &loaded.scenario;
    let map = oeg::load_map(&run.join("map.oeg")).expect("map");
    let region = *loaded.window.region();
    let files = oeg::planner_files(
        &map,
        region,
        &sc.robot.profile(),
        sc.map.traversability,
        UncertainCells::Blocked,
    )
    .expect("files");
    let layers = dir.join("layers");
    std::fs::create_dir_all(&layers).expect("dir");
    for (name, bytes) in files {
        std::fs::write(layers.join(name), bytes).expect("write");
    }
    (run, layers)
}

#[test]
fn the_testbeds_own_map_scores_to_the_counts_of_oeg_run() {
    let dir = temp_dir("cli_score", "own_map");
    let (run, layers) = run_and_export(&dir);
    let reported = json(&run.join("metrics.json"));

    // The .npy layers on the truth's own grid: every figure is the run's, bit for bit.
    let scored = dir.join("score");
    let out = stdout_judged(&oeg(&[
        "score",
        s(&scene()),
        "--layers",
        s(&layers.join("layers.json")),
        "--out",
        s(&scored),
        SHORT[0],
        SHORT[1],
    ]));
    assert!(out.contains("scored") && out.contains("unsafe"), "{out}");
    let score = json(&scored.join("score.json"));
    for (key, value) in &reported {
        if ["map_bytes", "num_scans", "num_rays"].contains(&key.as_str()) {
            assert_eq!(score[key], 0, "{key}");
        } else if key.starts_with("doubt_") {
            // Arrays say what the map decided, not why.
            assert!(score[key].is_null(), "{key}");
        } else {
            assert_eq!(&score[key], value, "{key}");
        }
    }
    assert!(count(&reported, "num_scored_cells") > 1000);
    for table in ["obstacles.csv", "plan.csv", "wrong_cells.csv"] {
        assert_eq!(
            std::fs::read_to_string(scored.join(table)).expect("scored"),
            std::fs::read_to_string(run.join(table)).expect("run"),
            "{table}"
        );
    }

    // The same decisions as a nav2 map: uncertain cells were written occupied, drivable ones free, and nothing
    // was simulated, so there are no blind counts.
    let nav2 = dir.join("nav2");
    let said = stdout_judged(&oeg(&[
        "score",
        s(&scene()),
        "--nav2",
        s(&layers.join("map.yaml")),
        "--no-observability",
        "--out",
        s(&nav2),
        SHORT[0],
        SHORT[1],
    ]));
    assert!(
        said.contains("blind cells not counted: --no-observability"),
        "{said}"
    );
    let n = json(&nav2.join("score.json"));
    let r = |k: &str| count(&reported, k);
    let uncertain_drivable = r("uncertain_cells") - r("uncertain_truly_blocked_cells");
    assert_eq!(count(&n, "num_scored_cells"), r("num_scored_cells"));
    assert_eq!(count(&n, "right_drivable_cells"), r("right_drivable_cells"));
    assert_eq!(count(&n, "unsafe_cells"), r("unsafe_cells"));
    assert_eq!(
        count(&n, "right_blocked_cells"),
        r("right_blocked_cells") + r("uncertain_truly_blocked_cells")
    );
    assert_eq!(
        count(&n, "overcautious_cells"),
        r("overcautious_cells") + uncertain_drivable
    );
    assert_eq!((count(&n, "uncertain_cells"), count(&n, "blind_cells")), (0, 0));
    assert!(
        n["elevation_rmse_m"].is_null(),
        "no elevation given: {}",
        n["elevation_rmse_m"]
    );
    let obstacles = std::fs::read_to_string(nav2.join("obstacles.csv")).expect("obstacles");
    let returns: Vec<&str> = obstacles
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(4).expect("sensor_returns"))
        .collect();
    assert!(returns.iter().all(|r| r.is_empty()), "{returns:?}");
}

#[test]
fn a_coarser_map_is_resampled_onto_the_truths_grid() {
    // One 1 m cell, blocked, over the robot's start: every truth cell whose centre it covers is blocked.
    let dir = temp_dir("cli_score", "coarse");
    let d = dir.join("d.npy");
    let array = NpyArray {
        rows: 1,
        cols: 1,
        data: NpyData::I64(vec![3]),
    };
    std::fs::write(&d, array.to_bytes().expect("bytes")).expect("write");
    let out = dir.join("out");
    // One cell covers 400 of the scene's 9600: its coverage expectation fails, so the command exits non-zero
    // after writing its files, as `oeg run` does.
    let e = err(&oeg(&[
        "score",
        s(&scene()),
        "--decisions",
        s(&d),
        "--origin=-0.5,-0.5",
        "--resolution",
        "1.0",
        "--no-observability",
        "--out",
        s(&out),
    ]));
    assert!(
        e.contains("expectation failed: coverage") && e.contains("of the scenario's expectations failed"),
        "{e}"
    );
    let m = json(&out.join("score.json"));
    assert!(count(&m, "num_expectations_failed") >= 1);
    // 1 m / 0.05 m = 20 cells a side.
    assert_eq!(count(&m, "num_observed_cells"), 400);
    assert_eq!(count(&m, "num_scored_cells"), 400);
    assert_eq!(
        count(&m, "right_blocked_cells") + count(&m, "overcautious_cells"),
        400
    );
}

#[test]
fn bad_maps_are_refused_with_the_file_and_what_was_expected() {
    let dir = temp_dir("cli_score", "bad");
    let write = |name: &str, bytes: &[u8]| {
        let p = dir.join(name);
        std::fs::write(&p, bytes).expect("write");
        p
    };
    let npy = |rows, cols, data| NpyArray { rows, cols, data }.to_bytes().expect("bytes");
    let codes = write("codes.npy", &npy(2, 2, NpyData::U8(vec![1, 1, 3, 0])));
    let floats = write("floats.npy", &npy(2, 2, NpyData::F32(vec![1.0; 4])));
    let wrong_shape = write("wide.npy", &npy(1, 4, NpyData::F32(vec![0.0; 4])));
    let bad_code = write("code9.npy", &npy(1, 1, NpyData::U8(vec![9])));
    let whole = npy(2, 2, NpyData::U8(vec![1; 4]));
    let truncated = write("short.npy", &whole[..whole.len() - 1]);
    let far = write("far.npy", &npy(2, 2, NpyData::F64(vec![0.0, 0.0, 1e300, 0.0])));
    let negative = write(
        "negative.npy",
        &npy(2, 2, NpyData::F32(vec![0.0, -1.0, 0.0, 0.0])),
    );
    let sidecar = |name: &str, layers: &[&str], extra: &str| {
        write(
            name,
            format!(
                "{{\"origin_xy_m\": [0, 0], \"resolution_m\": 0.05, {extra} \"layers\": {{{}}}}}",
                layers.join(", ")
            )
            .as_bytes(),
        )
    };
    let unknown_layer = sidecar(
        "unknown.json",
        &[
            "\"decisions\": {\"file\": \"codes.npy\"}",
            "\"elevation\": {\"file\": \"floats.npy\"}",
        ],
        "",
    );
    let wrong_shape_sidecar = sidecar(
        "shape.json",
        &["\"decisions\": {\"file\": \"codes.npy\", \"dtype\": \"uint8\"}"],
        "\"shape\": [4, 1],",
    );
    let wrong_type_sidecar = sidecar(
        "dtype.json",
        &[
            "\"decisions\": {\"file\": \"codes.npy\"}",
            "\"elevation_m\": {\"file\": \"codes.npy\", \"dtype\": \"float32\"}",
        ],
        "",
    );
    let (out, scenario, missing) = (dir.join("out"), scene(), dir.join("missing.yaml"));
    let score = |extra: &[&str]| {
        let mut args = vec!["score", s(&scenario), "--no-observability", "--out", s(&out)];
        args.extend_from_slice(extra);
        err(&oeg(&args))
    };
    let grid = ["--origin", "0,0", "--resolution", "0.05"];
    let cases: Vec<(Vec<&str>, Vec<&str>)> = vec![
        (
            [&["--decisions", s(&floats)][..], &grid].concat(),
            vec!["floats.npy", "integer codes"],
        ),
        (
            [&["--decisions", s(&bad_code)][..], &grid].concat(),
            vec!["code9.npy", "decision code 9"],
        ),
        (
            [&["--decisions", s(&truncated)][..], &grid].concat(),
            vec!["short.npy", "bytes of data"],
        ),
        (
            [
                &["--decisions", s(&codes), "--elevation", s(&wrong_shape)][..],
                &grid,
            ]
            .concat(),
            vec!["wide.npy", "(1, 4)", "(2, 2)"],
        ),
        (
            vec!["--decisions", s(&codes), "--origin", "0,0", "--resolution=-1"],
            vec!["codes.npy", "resolution -1"],
        ),
        (vec!["--decisions", s(&codes)], vec!["--origin"]),
        (vec![], vec!["--layers"]),
        (vec!["--layers", s(&codes)], vec!["codes.npy"]),
        (vec!["--nav2", s(&missing)], vec!["missing.yaml"]),
        (
            [&["--decisions", s(&codes), "--variance", s(&negative)][..], &grid].concat(),
            vec!["negative.npy", "variances: -1 at row 0, column 1"],
        ),
        (
            [&["--decisions", s(&codes), "--elevation", s(&far)][..], &grid].concat(),
            vec!["far.npy", "elevations: 1e300 at row 1, column 0", "1000000"],
        ),
        (
            vec!["--layers", s(&unknown_layer)],
            vec![
                "unknown.json",
                "\"elevation\", which is not a layer oeg score reads",
                "elevation_m",
            ],
        ),
        (
            vec!["--layers", s(&wrong_shape_sidecar)],
            vec![
                "shape.json",
                "codes.npy holds a (2, 2) array, the sidecar's `shape` is [4, 1]",
            ],
        ),
        (
            vec!["--layers", s(&wrong_type_sidecar)],
            vec![
                "dtype.json",
                "layer `elevation_m`",
                "holds uint8, the sidecar declares float32",
            ],
        ),
    ];
    for (args, wants) in cases {
        let e = score(&args);
        for want in &wants {
            assert!(e.contains(want), "{args:?}: `{e}` lacks `{want}`");
        }
        assert!(!e.contains("panicked"), "{e}");
    }
    assert!(!out.exists(), "a refused score wrote its folder");
}

#[test]
fn score_refuses_an_output_folder_that_holds_its_own_inputs() {
    // A folder a job wrote (it holds the marker), with a map's layers in it: scoring it into itself would
    // replace the files it has just read.
    let dir = temp_dir("cli_score", "inputs");
    let m = dir.join("m");
    std::fs::create_dir_all(&m).expect("dir");
    std::fs::write(m.join(".oeg-output"), "written by oeg\n").expect("marker");
    let codes = NpyArray {
        rows: 2,
        cols: 2,
        data: NpyData::U8(vec![1, 1, 3, 0]),
    };
    std::fs::write(m.join("codes.npy"), codes.to_bytes().expect("bytes")).expect("npy");
    std::fs::write(
        m.join("layers.json"),
        "{\"origin_xy_m\": [0, 0], \"resolution_m\": 0.05, \"layers\": {\"decisions\": {\"file\": \"codes.npy\"}}}",
    )
    .expect("sidecar");
    for out in [m.clone(), dir.join("m/../m")] {
        let e = err(&oeg(&[
            "score",
            s(&scene()),
            "--no-observability",
            "--layers",
            s(&m.join("layers.json")),
            "--out",
            s(&out),
        ]));
        assert!(
            e.contains("layers.json") && e.contains("is an input of this job and lies in its output folder"),
            "{e}"
        );
        assert!(
            m.join("codes.npy").is_file() && m.join("layers.json").is_file(),
            "the inputs are kept"
        );
    }
}
