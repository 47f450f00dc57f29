//! Scenario files: one test per error class, and every shipped scenario validates.

mod common;

use sim::SimError;

fn error_of(name: &str, text: &str) -> (String, Option<sim::TextPosition>) {
    match common::load_text(name, text) {
        Ok(_) => panic!("{name}: expected an error"),
        Err(SimError::Scenario {
            position, message, ..
        }) => (message, position),
        Err(other) => panic!("{name}: expected a scenario error, got {other}"),
    }
}

#[test]
fn a_valid_scenario_loads() {
    let loaded = common::load_text("valid", &common::scenario_text("")).expect("valid");
    assert_eq!(loaded.scenario.name, "test");
    assert_eq!(loaded.scenario.tick_s, 0.1);
    assert!((loaded.robot.height_m() - 0.46).abs() < 1e-9);
}

#[test]
fn a_syntax_error_names_line_and_column() {
    let text = common::scenario_text("[[obstacles]]\nkind = \"box\"\ncenter_xy_m = [1.0, 2.0\n");
    let (message, position) = error_of("syntax", &text);
    let p = position.expect("position");
    assert_eq!(p.line, 19, "{message}");
    assert!(p.column > 1, "{p}");
    let shown = common::load_text("syntax", &text).expect_err("error").to_string();
    assert!(shown.contains("syntax.toml:19:"), "{shown}");
}

#[test]
fn an_unknown_key_is_an_error_at_its_place() {
    let text = common::scenario_text("").replace("speed_m_s = 1.0", "speed_m_s = 1.0\nspeed_kmh = 3.6");
    let (message, position) = error_of("unknown", &text);
    assert!(message.contains("unknown field `speed_kmh`"), "{message}");
    assert_eq!(position.expect("position").line, 16);
}

#[test]
fn bad_values_are_errors_at_their_place() {
    let cases = [
        (
            "resolution",
            common::scenario_text("").replace("resolution_m = 0.05", "resolution_m = -0.05"),
            "map.resolution_m",
            8,
        ),
        (
            "huge",
            common::scenario_text("").replace("resolution_m = 0.05", "resolution_m = 0.001"),
            "over the limit",
            8,
        ),
        (
            "name_with_control_characters",
            common::scenario_text("").replace("name = \"test\"", "name = \"te\\u0000st\\u001b[2K\""),
            "\"te\\0st\\u{1b}[2K\" is used as a folder name",
            1,
        ),
        (
            "sensor_name_with_control_characters",
            common::scenario_text(
                "[[sensors]]\nname = \"lidar\\r\\u001b[2Kok\"\nkind = \"laser2d\"\nmount_link = \"base_link\"\n",
            ),
            "the sensor name \"lidar\\r\\u{1b}[2Kok\" is shown in messages",
            18,
        ),
        (
            "truth_too_fine",
            common::scenario_text("").replace("resolution_m = 0.05", "resolution_m = 0.003"),
            "steps of its running minimum, over the limit",
            8,
        ),
        (
            "truth_contact_too_long",
            common::scenario_text("").replace("[robot]\n", "[robot]\nmax_grade = 0.0005\n"),
            "max_step_m / max_grade = 70.000 m",
            8,
        ),
        (
            "waypoint",
            common::scenario_text("").replace("[4.0, 0.0]]", "[40.0, 0.0]]"),
            "outside the map region",
            14,
        ),
        (
            "noise",
            common::scenario_text("[robot.odometry]\nxy_sigma_m_per_sqrt_m = -0.1\n"),
            "xy_sigma_m_per_sqrt_m",
            18,
        ),
        (
            "duration",
            common::scenario_text("").replace("duration_s = 4.0", "duration_s = 0.0"),
            "duration_s",
            3,
        ),
        (
            "mount",
            common::scenario_text("[[sensors]]\nname = \"l\"\nkind = \"laser2d\"\nmount_link = \"roof\"\n"),
            "`roof`, which",
            20,
        ),
        (
            "box",
            common::scenario_text(
                "[[obstacles]]\nkind = \"box\"\ncenter_xy_m = [1.0, 1.0]\nsize_m = [1.0, 0.0, 1.0]\n",
            ),
            "obstacles[0].size_m",
            20,
        ),
        (
            "times",
            common::scenario_text(
                "[[actors]]\nkind = \"person\"\nwaypoints = [[2.0, 1.0, 1.0], [1.0, 2.0, 2.0]]\n",
            ),
            "times must increase",
            19,
        ),
        (
            "reach",
            common::scenario_text("[map.traversability]\nkind = \"contact\"\nreach_m = -0.1\n"),
            "map.traversability.reach_m",
            19,
        ),
        (
            "expect",
            common::scenario_text("[expectations]\ncoverage = { min = 0.9, max = 0.5 }\n"),
            "min 0.9 exceeds max 0.5",
            18,
        ),
    ];
    for (name, text, expected, line) in cases {
        let (message, position) = error_of(name, &text);
        assert!(message.contains(expected), "{name}: {message}");
        assert_eq!(position.map(|p| p.line), Some(line), "{name}: {message}");
    }
}

#[test]
fn a_wrong_type_is_an_error() {
    let text = common::scenario_text("").replace("seed = 7", "seed = \"seven\"");
    let (message, position) = error_of("type", &text);
    assert!(message.contains("invalid type"), "{message}");
    assert_eq!(position.expect("position").line, 2);
}

#[test]
fn missing_files_are_errors_naming_them() {
    let err = sim::scenario::load(std::path::Path::new("/nonexistent/scenario.toml")).expect_err("missing");
    assert!(
        matches!(err, SimError::Io { .. }) && err.to_string().contains("/nonexistent/scenario.toml"),
        "{err}"
    );
    let text =
        common::scenario_text("").replace(&common::urdf_path().display().to_string(), "robots/none.urdf");
    let (message, position) = error_of("nourdf", &text);
    assert!(
        message.contains("robot.urdf") && message.contains("none.urdf"),
        "{message}"
    );
    assert_eq!(position.expect("position").line, 11);
    let text = common::scenario_text(
        "[terrain]\nkind = \"image\"\npath = \"missing.png\"\nheight_scale_m = 1.0\ncell_m = 0.1\n",
    );
    let (message, _) = error_of("noimage", &text);
    assert!(message.contains("missing.png"), "{message}");
}

#[test]
fn every_shipped_scenario_validates() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios");
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .expect("scenarios folder")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    names.sort();
    assert!(!names.is_empty());
    for path in names {
        let loaded = sim::scenario::load(&path).unwrap_or_else(|e| panic!("{e}"));
        sim::World::new(&loaded).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    }
}

#[test]
fn bad_sensor_settings_are_errors_at_their_place() {
    let sensor = |body: &str| {
        common::scenario_text(&format!(
            "[[sensors]]\nname = \"s\"\nkind = \"laser2d\"\nmount_link = \"laser_front_mount\"\n{body}"
        ))
    };
    let cases = [
        ("fov", sensor("fov_deg = -90.0\n"), "sensors[0].fov_deg", 21),
        ("step", sensor("step_deg = 0.0\n"), "sensors[0].step_deg", 21),
        (
            "nan",
            sensor("[sensors.noise]\nrange_sigma_m = nan\n"),
            "sensors[0].noise.range_sigma_m",
            22,
        ),
        (
            "foreign",
            sensor("baseline_m = 0.1\n"),
            "does not apply to a laser2d",
            21,
        ),
        (
            "preset",
            sensor("preset = \"kinect\"\n"),
            "presets for laser2d: sick_lms291, sick_lms291_90",
            21,
        ),
        (
            "prob",
            sensor("[sensors.noise]\ndropout_probability = 2.0\n"),
            "expected a probability",
            22,
        ),
    ];
    for (name, text, expected, line) in cases {
        let (message, position) = error_of(name, &text);
        assert!(message.contains(expected), "{name}: {message}");
        assert_eq!(position.map(|p| p.line), Some(line), "{name}: {message}");
    }
}

#[test]
fn every_size_and_rate_is_bounded_so_a_valid_scenario_always_finishes() {
    let sensor = |kind: &str, body: &str| {
        common::scenario_text(&format!(
            "[[sensors]]\nname = \"s\"\nkind = \"{kind}\"\nmount_link = \"laser_front_mount\"\n{body}"
        ))
    };
    let cases = [
        (
            "rate",
            sensor("laser2d", "rate_hz = 1e9\n"),
            "sensors[0].rate_hz",
            21,
        ),
        (
            "camera",
            sensor("stereo", "image_size_px = [20000, 20000]\npixel_stride = 1\n"),
            "rays per frame",
            22,
        ),
        (
            "rays",
            sensor("lidar3d", "rate_hz = 1000.0\nazimuth_step_deg = 0.01\n")
                .replace("duration_s = 4.0", "duration_s = 86400.0"),
            "rays per run",
            17,
        ),
        (
            "cells",
            sensor("laser2d", "rate_hz = 1000.0\nmax_range_m = 100000.0\n"),
            "cells of 0.05 m",
            17,
        ),
        (
            "box",
            common::scenario_text(
                "[[obstacles]]\nkind = \"box\"\ncenter_xy_m = [3.0, 0.0]\nsize_m = [1e9, 1.0, 0.1]\n",
            ),
            "obstacles[0].size_m",
            20,
        ),
        (
            "parts",
            common::scenario_text(&(0..101).fold(String::new(), |t, _| {
                t + "[[obstacles]]\nkind = \"bush\"\ncenter_xy_m = [3.0, 0.0]\nradius_m = 0.5\nheight_m = 0.5\nnum_parts = 1000\n"
            })),
            "solid parts",
            17,
        ),
        (
            "person",
            common::scenario_text(
                "[[actors]]\nkind = \"person\"\nradius_m = 1e12\nheight_m = 1.7\nwaypoints = [[0.0, 1.0, 1.0]]\n",
            ),
            "actors[0].radius_m",
            19,
        ),
    ];
    for (name, text, expected, line) in cases {
        let (message, position) = error_of(name, &text);
        assert!(message.contains(expected), "{name}: {message}");
        assert_eq!(position.map(|p| p.line), Some(line), "{name}: {message}");
    }
}

#[test]
fn fixed_length_lists_with_extra_elements_are_errors_at_their_place() {
    let base = common::scenario_text("");
    for (name, from, to) in [
        (
            "corner",
            "min_xy_m = [-2.0, -4.0]",
            "min_xy_m = [-2.0, -4.0, 5.0]",
        ),
        ("waypoint", "[4.0, 0.0]]", "[4.0, 0.0, 1.0]]"),
    ] {
        assert!(base.contains(from), "{name}: the test scenario has `{from}`");
        let (message, position) = error_of(name, &base.replacen(from, to, 1));
        assert!(
            message.contains("expected a list of 2 values, got 3"),
            "{name}: {message}"
        );
        assert!(position.is_some(), "{name}: {message}");
    }
}

#[test]
fn bad_navigation_settings_are_errors_at_their_place() {
    for (name, navigation, expected) in [
        (
            "nav-goal",
            "goal_xy_m = [50.0, 0.0]",
            "`navigation.goal_xy_m`: point [50.0, 0.0] m lies outside",
        ),
        (
            "nav-replan",
            "goal_xy_m = [5.0, 0.0]\nreplan_period_s = 0.01",
            "`navigation.replan_period_s`",
        ),
        (
            "nav-speed",
            "goal_xy_m = [5.0, 0.0]\nspeed_m_s = 2.0",
            "at most the robot's max_speed_m_s",
        ),
        (
            "nav-lookahead",
            "goal_xy_m = [5.0, 0.0]\nlookahead_m = -1.0",
            "`navigation.lookahead_m`",
        ),
        (
            "nav-timeout",
            "goal_xy_m = [5.0, 0.0]\nplanner_timeout_s = 0.0",
            "`navigation.planner_timeout_s`",
        ),
        (
            "nav-command",
            "goal_xy_m = [5.0, 0.0]\ncommand = [\" \"]",
            "expected a command line",
        ),
        (
            "nav-unknown-key",
            "goal_xy_m = [5.0, 0.0]\ngoal_tol = 1.0",
            "unknown field `goal_tol`",
        ),
        (
            "nav-planner",
            "goal_xy_m = [5.0, 0.0]\nplanner = \"dijkstra\"",
            "unknown variant `dijkstra`",
        ),
    ] {
        let text = common::scenario_text(&format!("[navigation]\n{navigation}\n"));
        let (message, position) = error_of(name, &text);
        assert!(message.contains(expected), "{name}: {message}");
        let line = position.expect("a place in the file").line;
        let navigation_line = text.lines().position(|l| l == "[navigation]").expect("table") + 1;
        assert!(line >= navigation_line, "{name}: line {line}");
    }
    let loaded = common::load_text(
        "nav-ok",
        &common::scenario_text("[navigation]\ngoal_xy_m = [5.0, 0.0]\n"),
    )
    .expect("valid");
    let n = loaded.scenario.navigation.expect("navigation");
    assert_eq!(
        (n.replan_period_s, n.goal_tolerance_m, n.lookahead_m),
        (1.0, 0.25, 0.6)
    );
    assert_eq!(n.unknown, oeg::UnknownCells::Drivable);
}
