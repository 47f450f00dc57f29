//! When the navigator takes a new path (`[navigation] replan`): every mode drives the robot round the wall of
//! `tests/scenes/nav_wall.toml` to its goal, and each plans as often as it promises.

#![allow(clippy::disallowed_methods, reason = "tests read back the files they wrote")]

mod common;

use common::{oeg, ok, root, s, temp_dir};

/// `navigation.json` of `nav_wall` run under replanning mode `mode`.
fn run(mode: &str) -> serde_json::Value {
    let out = temp_dir("nav-replan", mode);
    let scene = root().join("tests/scenes/nav_wall.toml");
    let set = format!("navigation.replan={mode}");
    ok(&oeg(&["run", s(&scene), "--out", s(&out), "--set", &set]));
    serde_json::from_slice(&std::fs::read(out.join("navigation.json")).expect("navigation.json"))
        .expect("json")
}

#[test]
fn each_replanning_mode_reaches_the_goal_and_plans_as_often_as_it_promises() {
    let [periodic, shorter, invalid] = ["periodic", "when_shorter", "when_invalid"].map(run);
    for nav in [&periodic, &shorter, &invalid] {
        assert_eq!(nav["outcome"], "reached", "{nav:#}");
        assert_eq!(nav["contacts"], 0, "{nav:#}");
    }
    let replans = |nav: &serde_json::Value| nav["replans"].as_u64().expect("replans");
    // `periodic` and `when_shorter` plan at every replanning time (the second may keep its path); `when_invalid`,
    // the default, plans once, and again only when the wall closes the straight path.
    assert!(replans(&periodic) > 3, "{periodic:#}");
    assert!(replans(&shorter) > 3, "{shorter:#}");
    assert!((2..replans(&shorter)).contains(&replans(&invalid)), "{invalid:#}");
}
