//! `oeg validate` and `oeg preview` through the built binary.

#![allow(
    clippy::disallowed_methods,
    reason = "tests and tools write their inputs directly"
)]

mod common;

use common::{oeg, temp_dir};
use std::path::PathBuf;

fn scenarios_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenarios")
}

#[test]
fn validate_prints_one_line_per_valid_file() {
    let files =
        ["default.toml", "curbs_and_boards.toml"].map(|f| scenarios_dir().join(f).display().to_string());
    let o = oeg(&[&files[0], &files[1]].iter().fold(vec!["validate"], |mut v, f| {
        v.push(f);
        v
    }));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(out.lines().count(), 2, "{out}");
    assert!(out.lines().all(|l| l.contains(": ok: ")), "{out}");
    assert!(out.contains("0.46 m tall"), "{out}");
}

#[test]
fn validate_fails_on_a_bad_file_and_names_its_place() {
    let dir = temp_dir("scn", "bad");
    let good = scenarios_dir().join("curbs_and_boards.toml");
    let text = std::fs::read_to_string(&good)
        .expect("read")
        .replace("speed_m_s = 0.5", "speed_m_s = -0.5");
    let bad = dir.join("bad.toml");
    // Keep the URDF reachable from the copy.
    let text = text.replace(
        "robots/pioneer3at.urdf",
        &scenarios_dir()
            .join("robots/pioneer3at.urdf")
            .display()
            .to_string(),
    );
    std::fs::write(&bad, text).expect("write");
    let o = oeg(&[
        "validate",
        good.to_str().expect("utf8"),
        bad.to_str().expect("utf8"),
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bad.toml:21:") && err.contains("robot.drive.speed_m_s"),
        "{err}"
    );
    assert!(!err.contains("error: :"), "{err}");
    assert!(err.contains("1 of 2 scenario files are invalid"), "{err}");
    assert_eq!(
        String::from_utf8_lossy(&o.stdout).lines().count(),
        1,
        "the good file still gets its line"
    );
}

#[test]
fn a_missing_scenario_file_is_named_once_with_its_cause_once() {
    let o = oeg(&["run", "no_such_scenario.toml"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.starts_with("error: no_such_scenario.toml: "), "{err}");
    assert_eq!(err.matches("os error 2").count(), 1, "{err}");
}

#[test]
fn preview_draws_the_truth() {
    let out = temp_dir("scn", "preview");
    let scenario = scenarios_dir().join("curbs_and_boards.toml");
    let o = oeg(&[
        "preview",
        scenario.to_str().expect("utf8"),
        "--out",
        out.to_str().expect("utf8"),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for name in ["preview_elevation.png", "preview_decisions.png"] {
        let bytes = std::fs::read(out.join(name)).expect(name);
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    }
}

#[test]
fn the_documented_example_validates() {
    let doc =
        std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("docs/scenario-format.md"))
            .expect("doc");
    let example = doc.split("## Example").nth(1).expect("an example section");
    let toml = example
        .split("```toml")
        .nth(1)
        .and_then(|s| s.split("```").next())
        .expect("a toml block");
    let dir = temp_dir("scn", "doc");
    std::fs::create_dir_all(dir.join("robots")).expect("dir");
    std::fs::copy(
        scenarios_dir().join("robots/pioneer3at.urdf"),
        dir.join("robots/pioneer3at.urdf"),
    )
    .expect("copy");
    let path = dir.join("curb_check.toml");
    std::fs::write(&path, toml).expect("write");
    let o = oeg(&["validate", path.to_str().expect("utf8")]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn validate_refuses_expectations_that_name_no_metric_or_can_never_be_met() {
    let dir = temp_dir("scn", "expectations");
    let text = std::fs::read_to_string(scenarios_dir().join("thin_pole.toml"))
        .expect("scenario")
        .replace(
            "robots/pioneer3at.urdf",
            scenarios_dir()
                .join("robots/pioneer3at.urdf")
                .to_str()
                .expect("utf8"),
        );
    let cases = [
        (
            "unknown",
            "unsafe_cellz = { max = 0 }",
            "`unsafe_cellz` is not a metric",
        ),
        ("absurd", "occupancy_brier = { min = 1.5 }", "can never be met"),
        ("negative", "num_scans = { max = -1 }", "can never be met"),
    ];
    for (name, line, expected) in cases {
        let path = dir.join(format!("{name}.toml"));
        let edited = text.replace("[expectations]\n", &format!("[expectations]\n{line}\n"));
        assert_ne!(edited, text, "the scenario has expectations");
        std::fs::write(&path, &edited).expect("write");
        let line_no = edited.lines().position(|l| l == line).expect("the line") + 1;
        let (path, out) = (path.to_str().expect("utf8"), dir.join("out"));
        let out = out.to_str().expect("utf8");
        for (command, args) in [
            ("validate", vec!["validate", path]),
            ("run", vec!["run", path, "--out", out]),
        ] {
            let o = oeg(&args);
            let stderr = String::from_utf8_lossy(&o.stderr);
            assert!(!o.status.success(), "{name} {command}: {stderr}");
            assert!(stderr.contains(expected), "{name} {command}: {stderr}");
            let place = format!("{name}.toml:{line_no}:");
            assert!(
                stderr.contains(&place),
                "{name} {command}: expected {place} in {stderr}"
            );
        }
    }
    assert!(!dir.join("out").exists(), "nothing written");
}
