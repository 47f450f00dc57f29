//! Hand-made closed-loop scenes where a navigator must stay live, under both presets: a gap between two walls
//! the robot sees from one side is driven through, and a person who blocks a corridor and leaves is waited for.

#![allow(clippy::disallowed_methods, reason = "tests read back the files they wrote")]

mod common;

use common::{oeg, ok, root, s, temp_dir};

/// `oeg run` of `tests/scenes/<scene>.toml` under `preset`, which must reach the goal touching nothing: its
/// `navigation.json`.
fn reached_untouched(scene: &str, preset: &str) -> serde_json::Value {
    let out = temp_dir("nav-live", &format!("{scene}_{preset}"));
    let file = root().join("tests/scenes").join(format!("{scene}.toml"));
    let set = format!("map.preset={preset}");
    ok(&oeg(&["run", s(&file), "--set", &set, "--out", s(&out)]));
    let nav: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("navigation.json")).expect("navigation.json"))
            .expect("json");
    assert_eq!(nav["outcome"], "reached", "{scene}, {preset}: {nav:#}");
    assert_eq!(nav["contacts"], 0, "{scene}, {preset}: {nav:#}");
    nav
}

#[test]
fn a_gap_between_two_walls_seen_from_one_side_is_driven_through() {
    // The walls' tops, far sides and the ground behind them are never observed before the robot is in the gap:
    // the frontier rule must not close it. Under both presets the robot drives through (the straight line is
    // 5.5 m; the way round a wall's end is longer than 6 m), touching nothing.
    for preset in ["paper", "robust"] {
        let nav = reached_untouched("nav_gap", preset);
        let driven = nav["driven_length_m"].as_f64().expect("length");
        assert!(driven < 6.0, "{preset}: went round, {driven} m: {nav:#}");
    }
}

#[test]
fn a_person_who_blocks_the_corridor_and_leaves_is_waited_for() {
    // A person stands across a corridor for 8 s, then leaves through a side door. The robot, facing away
    // after its last plan, finds no path and makes no progress; the recovery sequence turns it to face the
    // goal and waits, mapping: the lasers see the corridor clear, the next plan goes through, and the robot
    // reaches the goal under both presets.
    for preset in ["paper", "robust"] {
        let nav = reached_untouched("nav_person_blocks", preset);
        let events = nav["events"].as_array().expect("events");
        let kinds: Vec<&str> = events
            .iter()
            .map(|e| e["kind"].as_str().unwrap_or_default())
            .collect();
        let recovery = kinds.iter().position(|k| *k == "recovery").expect("a recovery");
        let no_path = kinds.iter().position(|k| *k == "no_path").expect("a stall");
        assert!(no_path < recovery, "{preset}: {kinds:?}");
        assert!(!kinds.contains(&"stuck"), "{preset}: {kinds:?}");
        // The stall says what closed the way, and what the truth makes of it.
        let closed_by = events[no_path]["closed_by"].as_str().unwrap_or_default();
        assert!(closed_by.contains("the truth has a path"), "{closed_by}");
    }
}
