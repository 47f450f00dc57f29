//! `[robot] limits_from`: the truth's and the map's step and clearance thresholds from a physics study's
//! measured limits, and every way that file can be wrong.

#![allow(clippy::disallowed_methods, reason = "tests write their inputs directly")]

mod common;

use std::path::Path;

/// The study's file as `bash scripts/physics-limits.sh` writes it.
const STUDY: &str = r#"{
  "generated_by": "bash scripts/physics-limits.sh",
  "commit": "abc1234",
  "climb_limit_m": [
    { "wheel_friction": 0.5, "limit_m": 0.015 },
    { "wheel_friction": 0.8, "limit_m": 0.025 },
    { "wheel_friction": 1.1, "limit_m": null }
  ],
  "clearance_m": 0.47,
  "note": "..."
}
"#;

/// Loads a scenario whose `[robot]` reads `limits.json` (holding `limits`) beside it, with `robot_keys` added
/// to `[robot]` and `extra` appended.
fn load_with(name: &str, limits: &str, robot_keys: &str, extra: &str) -> Result<sim::LoadedScenario, String> {
    let dir = common::temp_dir(name);
    std::fs::write(dir.join("limits.json"), limits).expect("write");
    let text = common::scenario_text(extra).replacen(
        "[robot]\n",
        &format!("[robot]\nlimits_from = \"limits.json\"\n{robot_keys}"),
        1,
    );
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).expect("write");
    sim::scenario::load(&path).map_err(|e| e.to_string())
}

#[test]
fn the_thresholds_are_the_limits_measured_at_the_scenarios_wheel_friction() {
    let loaded = load_with("limits-default", STUDY, "", "").expect("valid");
    let profile = loaded.scenario.robot.profile();
    assert_eq!((profile.max_step_m, profile.height_m), (0.025, 0.47));
    // The map's decisions read the same profile: its step threshold follows.
    assert!(
        loaded
            .files()
            .iter()
            .any(|f| f.ends_with(Path::new("limits.json")))
    );

    let slippery = load_with(
        "limits-slippery",
        STUDY,
        "",
        "[robot.physics]\nwheel_friction = 0.5\n",
    )
    .expect("valid");
    assert_eq!(slippery.scenario.robot.max_step_m, 0.015);
}

#[test]
fn a_limit_set_twice_or_not_measured_is_an_error_that_names_the_file_and_the_key() {
    for (case, limits, robot_keys, extra, expected) in [
        (
            "both",
            STUDY,
            "max_step_m = 0.03\n",
            "",
            "`robot.max_step_m` is set too",
        ),
        (
            "height",
            STUDY,
            "height_m = 0.5\n",
            "",
            "`robot.height_m` is set too",
        ),
        (
            "friction",
            STUDY,
            "",
            "[robot.physics]\nwheel_friction = 0.9\n",
            "no climb limit measured at the scenario's wheel friction 0.9",
        ),
        (
            "null",
            STUDY,
            "",
            "[robot.physics]\nwheel_friction = 1.1\n",
            "the study measured no limit there",
        ),
        (
            "old",
            r#"{"climb_limit_m": {"friction_0_8": 0.025}, "clearance_m": 0.47}"#,
            "",
            "",
            "expected a sequence",
        ),
        ("truncated", &STUDY[..60], "", "", "line"),
        (
            "absurd",
            r#"{"climb_limit_m": [{"wheel_friction": 0.8, "limit_m": -0.02}], "clearance_m": 0.47}"#,
            "",
            "",
            "above 0",
        ),
        (
            "no-clearance",
            r#"{"climb_limit_m": [{"wheel_friction": 0.8, "limit_m": 0.02}], "clearance_m": null}"#,
            "",
            "",
            "`clearance_m` is null",
        ),
    ] {
        let e = load_with(&format!("limits-{case}"), limits, robot_keys, extra).expect_err(case);
        assert!(
            e.contains("robot.limits_from") && e.contains(expected),
            "{case}: {e}"
        );
        if !matches!(case, "both" | "height") {
            assert!(e.contains("limits.json"), "{case}: {e}");
        }
    }
}

#[test]
fn a_missing_study_file_is_an_error_that_names_it() {
    let text =
        common::scenario_text("").replacen("[robot]\n", "[robot]\nlimits_from = \"nowhere.json\"\n", 1);
    let e = common::load_text("limits-missing", &text)
        .expect_err("missing")
        .to_string();
    assert!(
        e.contains("robot.limits_from") && e.contains("nowhere.json"),
        "{e}"
    );
}
