//! `oeg map`, `oeg inspect` and `oeg` (the demo) through the built binary.

#![allow(
    clippy::disallowed_methods,
    reason = "tests and tools write their inputs directly"
)]

mod common;

use common::{map_at, oeg, temp_dir};
use std::path::{Path, PathBuf};
use std::process::Output;

use nalgebra::Point3;
use oeg::write_graph;
use oeg::{Scan, SensorModel};

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Three scans of a floor with a 10 cm box, written as a scan graph.
fn write_scans(path: &Path) {
    let mut scans = Vec::new();
    for k in 0..3 {
        let origin = Point3::new(0.2 * f64::from(k), 0.0, 0.5);
        let mut scan = Scan::new(origin, SensorModel::laser());
        for a in -20..=20 {
            for r in 1..=8 {
                let (x, y) = (0.5 * f64::from(r), 0.1 * f64::from(a));
                let z = if (2.0..2.5).contains(&x) && y.abs() < 0.5 {
                    0.1
                } else {
                    0.0
                };
                scan.push_hit(Point3::new(x, y, z));
            }
        }
        scans.push(scan);
    }
    write_graph(path, &scans).expect("written");
}

#[test]
fn map_writes_every_output_and_inspect_reads_the_map() {
    let dir = temp_dir("map", "ok");
    let input = dir.join("scans.graph");
    write_scans(&input);
    let out = dir.join("out");
    let o = oeg(&[
        "map",
        input.to_str().expect("utf8"),
        "--resolution",
        "0.1",
        "--out",
        out.to_str().expect("utf8"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for name in [
        "map.oeg",
        "occupancy.png",
        "elevation.png",
        "variance.png",
        "traversability.png",
        "summary.json",
        "timing.json",
    ] {
        assert!(out.join(name).is_file(), "{name} missing");
    }
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).expect("read")).expect("json");
    assert_eq!(summary["num_scans"], 3);
    assert_eq!(summary["num_rays"], 3 * 41 * 8);
    let observed = summary["num_cells_observed"].as_u64().expect("count");
    let parts = ["num_cells_free", "num_cells_traversable", "num_cells_blocked"]
        .iter()
        .map(|k| summary[*k].as_u64().expect("count"))
        .sum::<u64>();
    assert_eq!(observed, parts);
    assert!(
        summary["num_cells_blocked"].as_u64().expect("count") > 0,
        "the 10 cm box blocks"
    );
    assert!(summary["map_bytes"].as_u64().expect("bytes") > 0);
    let timing: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("timing.json")).expect("read")).expect("json");
    assert!(timing["integrate_rays_per_s"].as_f64().expect("rate") > 0.0);
    // The PNG has the plot's size plus margins.
    let png = std::fs::read(out.join("elevation.png")).expect("read");
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");

    let o = oeg(&["inspect", out.join("map.oeg").to_str().expect("utf8")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("resolution:           0.1 m"), "{text}");
    assert!(text.contains("scans integrated:     3"), "{text}");
    assert!(
        text.contains(r#""scan_hit_elevation":"highest""#),
        "every model option is printed: {text}"
    );
    assert!(
        text.contains(&format!("observed cells:       {observed}")),
        "{text}"
    );
}

#[test]
fn the_same_inputs_give_the_same_summary_map_and_images() {
    let dir = temp_dir("map", "determinism");
    let input = dir.join("scans.graph");
    write_scans(&input);
    let run = |name: &str| {
        let out = dir.join(name);
        let o = oeg(&[
            "map",
            input.to_str().expect("utf8"),
            "--resolution",
            "0.05",
            "--out",
            out.to_str().expect("utf8"),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        out
    };
    let (a, b) = (run("a"), run("b"));
    for name in ["summary.json", "map.oeg", "elevation.png", "traversability.png"] {
        assert_eq!(
            std::fs::read(a.join(name)).expect("a"),
            std::fs::read(b.join(name)).expect("b"),
            "{name}"
        );
    }
}

#[test]
fn bad_inputs_fail_with_the_file_named_and_write_nothing() {
    let dir = temp_dir("map", "bad");
    let input = dir.join("scans.graph");
    write_scans(&input);
    let bytes = std::fs::read(&input).expect("read");
    let truncated = dir.join("truncated.graph");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).expect("write");
    let corrupt_pcd = dir.join("corrupt.pcd");
    std::fs::write(
        &corrupt_pcd,
        b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 3\nDATA binary\n\x01\x02",
    )
    .expect("write");
    let big = dir.join("big.graph");
    let mut dense = Scan::new(Point3::new(0.0, 0.0, 0.5), SensorModel::laser());
    for k in 0..20_000 {
        dense.push_hit(Point3::new(
            1.0 + f64::from(k % 100) * 0.01,
            f64::from(k / 100) * 0.01,
            0.0,
        ));
    }
    write_graph(&big, &[dense]).expect("graph");
    let unknown = dir.join("scan.xyz");
    std::fs::write(&unknown, b"1 2 3\n").expect("write");
    let input_s = input.to_str().expect("utf8");
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec![
                truncated.display().to_string(),
                "--resolution".into(),
                "0.1".into(),
            ],
            "truncated.graph",
        ),
        (
            vec![
                corrupt_pcd.display().to_string(),
                "--resolution".into(),
                "0.1".into(),
            ],
            "corrupt.pcd",
        ),
        (
            vec![unknown.display().to_string(), "--resolution".into(), "0.1".into()],
            "unknown input format",
        ),
        (
            vec![
                dir.join("missing.graph").display().to_string(),
                "--resolution".into(),
                "0.1".into(),
            ],
            "missing.graph",
        ),
        (
            vec![input_s.into(), "--resolution".into(), "0".into()],
            "resolution_m",
        ),
        (vec![input_s.into(), "--resolution=-0.1".into()], "resolution_m"),
        (
            vec![
                input_s.into(),
                "--resolution".into(),
                "0.01".into(),
                "--memory-limit-mib".into(),
                "1".into(),
            ],
            "memory limit",
        ),
        // 1 MiB for a graph that needs about three times its size in memory.
        (
            vec![
                big.display().to_string(),
                "--resolution".into(),
                "0.1".into(),
                "--memory-limit-mib".into(),
                "1".into(),
            ],
            "would take about",
        ),
    ];
    for (k, (args, expected)) in cases.into_iter().enumerate() {
        let out = dir.join(format!("out{k}"));
        let mut all = vec!["map".to_string()];
        all.extend(args);
        all.extend(["--out".to_string(), out.display().to_string()]);
        let refs: Vec<&str> = all.iter().map(String::as_str).collect();
        let o = oeg(&refs);
        assert!(!o.status.success(), "case {k} should fail");
        let err = stderr(&o);
        assert!(
            err.contains(expected),
            "case {k}: expected `{expected}` in: {err}"
        );
        assert!(!err.contains("panicked"), "case {k}: {err}");
        assert!(!out.exists(), "case {k}: no output folder for a failed job");
    }
}

#[test]
fn a_far_point_or_pose_is_refused_at_once_naming_the_file_and_the_node() {
    let dir = temp_dir("map", "far");
    let mut near = Scan::new(Point3::new(0.0, 0.0, 0.5), SensorModel::laser());
    near.push_hit(Point3::new(1.0, 0.0, 0.0));
    // A point 10,000 km from its pose: the ray would span 3 million tiles.
    let mut far_point = Scan::new(Point3::new(0.0, 0.0, 0.5), SensorModel::laser());
    far_point.push_hit(Point3::new(1.0e7, 0.0, 0.0));
    // A pose 200,000 km away whose point lies 1.15 m from it: beyond the grid's index range.
    let mut far_pose = Scan::new(Point3::new(2.0e8, 0.0, 0.5), SensorModel::laser());
    far_pose.push_hit(Point3::new(2.0e8 + 1.15, 0.0, 0.0));
    for (name, scan, expected) in [
        ("far_point", far_point, "memory limit"),
        ("far_pose", far_pose, "(200000000.000, 0.000) m"),
    ] {
        let input = dir.join(format!("{name}.graph"));
        write_graph(&input, &[near.clone(), scan, near.clone()]).expect("graph");
        let out = dir.join(format!("out_{name}"));
        let started = std::time::Instant::now();
        let o = map_at(&input, &out, &[]);
        let err = stderr(&o);
        assert!(!o.status.success(), "{name}: {err}");
        let file = format!("{name}.graph");
        assert!(
            err.contains(&file) && err.contains("node 1 (id 1)"),
            "{name}: {err}"
        );
        assert!(err.contains(expected), "{name}: {err}");
        assert!(
            started.elapsed().as_secs_f64() < 20.0,
            "{name}: {:?}",
            started.elapsed()
        );
        assert!(!out.exists());
    }
}

#[test]
fn images_follow_what_the_map_holds_and_dense_planner_files_fail_whole_naming_the_inputs() {
    // Two small scans 2.8 km apart: the sparse map is small, its extent is 1.6 billion cells at 0.05 m. The
    // images read only the cells they show, so they are drawn in well under a second of work; the planner's
    // dense files over that extent are over the memory limit, and then nothing is written.
    let dir = temp_dir("map", "images");
    let input = dir.join("apart.graph");
    let scans: Vec<Scan> = [(0.0, 0.0), (2000.0, 2000.0)]
        .iter()
        .map(|&(x, y)| {
            let mut scan = Scan::new(Point3::new(x, y, 0.5), SensorModel::laser());
            scan.push_hit(Point3::new(x + 1.0, y, 0.0));
            scan
        })
        .collect();
    write_graph(&input, &scans).expect("graph");
    let out = dir.join("out");
    let o = map_at(&input, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    for image in [
        "occupancy.png",
        "elevation.png",
        "variance.png",
        "traversability.png",
    ] {
        assert!(out.join(image).is_file(), "{image}");
    }
    assert!(!out.join("planner").exists(), "planner files only when asked for");

    let out = dir.join("out_planner");
    let o = oeg(&[
        "map",
        input.to_str().expect("utf8"),
        "--resolution",
        "0.05",
        "--planner-files",
        "--out",
        out.to_str().expect("utf8"),
    ]);
    let err = stderr(&o);
    assert!(!o.status.success(), "{err}");
    assert!(err.contains("memory limit"), "{err}");
    assert!(
        err.contains("writing the planner files")
            && err.contains("apart.graph")
            && err.contains("out_planner:"),
        "the error names the inputs and the output folder: {err}"
    );
    assert!(!out.exists(), "no map.oeg without its planner files");
    let left: Vec<_> = std::fs::read_dir(&dir)
        .expect("dir")
        .map(|e| e.expect("entry").file_name())
        .collect();
    assert_eq!(left.len(), 2, "no staging left: {left:?}");
}

#[test]
fn inspect_rejects_a_corrupt_map() {
    let dir = temp_dir("map", "inspect");
    let input = dir.join("scans.graph");
    write_scans(&input);
    let out = dir.join("out");
    assert!(
        oeg(&[
            "map",
            input.to_str().expect("utf8"),
            "--resolution",
            "0.2",
            "--out",
            out.to_str().expect("utf8")
        ])
        .status
        .success()
    );
    let map = out.join("map.oeg");
    let mut bytes = std::fs::read(&map).expect("read");
    let k = bytes.len() / 2;
    bytes[k] ^= 0xff;
    let bad = dir.join("bad.oeg");
    std::fs::write(&bad, &bytes).expect("write");
    let o = oeg(&["inspect", bad.to_str().expect("utf8")]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("bad.oeg") && stderr(&o).contains("checksum"),
        "{}",
        stderr(&o)
    );
    std::fs::write(&bad, &bytes[..100]).expect("write");
    let o = oeg(&["inspect", bad.to_str().expect("utf8")]);
    assert!(
        !o.status.success() && stderr(&o).contains("bad.oeg"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn the_demo_runs_with_no_arguments_style_output() {
    let dir = temp_dir("map", "demo");
    let out = dir.join("demo");
    let o = oeg(&["demo", "--out", out.to_str().expect("utf8")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).expect("read")).expect("json");
    assert_eq!(summary["num_scans"], 12);
    assert!(summary["num_cells_blocked"].as_u64().expect("count") > 0);
    assert!(out.join("traversability.png").is_file());
    // The same files a closed-loop run gives an external planner, over the observed region.
    let sidecar: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("planner/layers.json")).expect("layers.json"))
            .expect("json");
    let shape = sidecar["shape"].as_array().expect("shape");
    let decisions = std::fs::read(out.join("planner/decisions.npy")).expect("decisions.npy");
    let array = oeg::NpyArray::from_bytes(&out.join("planner/decisions.npy"), &decisions).expect("npy");
    assert_eq!(
        [array.rows as u64, array.cols as u64],
        [shape[0].as_u64().expect("rows"), shape[1].as_u64().expect("cols")]
    );
    for f in [
        "map.pgm",
        "map.yaml",
        "elevation_m.npy",
        "variance_m2.npy",
        "occupancy_probability.npy",
    ] {
        assert!(out.join("planner").join(f).is_file(), "{f}");
    }
}

#[test]
fn the_shared_real_scans_map_when_present() {
    let dir = std::env::var_os("OEG_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data"));
    let input = dir.join("3dtk_frames.graph");
    if !input.is_file() {
        println!(
            "skipped: {} is absent (the shared data set lives beside the project)",
            input.display()
        );
        return;
    }
    let out = temp_dir("map", "real").join("out");
    let o = oeg(&[
        "map",
        input.to_str().expect("utf8"),
        "--resolution",
        "0.1",
        "--out",
        out.to_str().expect("utf8"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).expect("read")).expect("json");
    assert_eq!(summary["num_rays"], 233_028);
    assert_eq!(summary["num_scans"], 3);
}

#[test]
fn map_and_plan_take_settings_by_their_scenario_keys() {
    let dir = temp_dir("map", "settings");
    let demo = dir.join("demo");
    let o = oeg(&["demo", "--out", demo.to_str().expect("utf8")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let graph = demo.join("demo.graph");
    let map_path = demo.join("map.oeg");
    let map_s = map_path.to_str().expect("utf8");
    let out = dir.join("octomap_hit");
    let o = oeg(&[
        "map",
        graph.to_str().expect("utf8"),
        "--resolution",
        "0.05",
        "--out",
        out.to_str().expect("utf8"),
        "--set",
        "map.model.p_max=0.7",
        "--set",
        "map.model.max_height_m=0.5",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let inspect = oeg(&["inspect", out.join("map.oeg").to_str().expect("utf8")]);
    let text = String::from_utf8_lossy(&inspect.stdout);
    assert!(
        text.contains("\"p_max\":0.7") || text.contains("\"p_max\": 0.7"),
        "{text}"
    );
    // A robot that climbs 6 cm may plan onto the 5 cm curb the default robot may not.
    let plan = |extra: &[&str]| -> serde_json::Value {
        let out = dir.join("plan");
        let mut args = vec![
            "plan",
            map_s,
            "--from",
            "0.5,0",
            "--to",
            "3.15,1.2",
            "--out",
            out.to_str().expect("utf8"),
        ];
        args.extend_from_slice(extra);
        let o = oeg(&args);
        assert!(matches!(o.status.code(), Some(0 | 3)), "{}", stderr(&o));
        serde_json::from_slice(&std::fs::read(out.join("plan.json")).expect("plan.json")).expect("json")
    };
    assert_eq!(plan(&[])["plan_found"], false);
    assert_eq!(plan(&["--set", "robot.max_step_m=0.06"])["plan_found"], true);
    // A bad value names its override.
    let map_with = |set: &'static str| -> Vec<&str> {
        vec![
            "map",
            graph.to_str().expect("utf8"),
            "--resolution",
            "0.05",
            "--out",
            "x",
            "--set",
            set,
        ]
    };
    for (args, expected) in [
        (
            map_with("map.model.p_max=2"),
            "--set map.model.p_max=2: invalid setting `p_max`",
        ),
        (
            map_with("input.pcd_frame=sideways"),
            "--set input.pcd_frame=sideways: unknown variant `sideways`",
        ),
        (
            vec![
                "plan",
                map_s,
                "--from",
                "0,0",
                "--to",
                "1,0",
                "--set",
                "planner.inflation_radius_m=-1",
            ],
            "--set planner.inflation_radius_m=-1: planner.inflation_radius_m",
        ),
    ] {
        let o = oeg(&args);
        assert!(!o.status.success(), "{args:?}");
        assert!(stderr(&o).contains(expected), "{args:?}: {}", stderr(&o));
    }
}
