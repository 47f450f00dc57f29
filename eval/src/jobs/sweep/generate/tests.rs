//! The generator's tests.
#![allow(clippy::disallowed_methods, reason = "tests read back the files they wrote")]

use std::path::{Path, PathBuf};

use super::*;
use toml::Table;

fn spec() -> GenerateSpec {
    toml::from_str(
        "base = \"x.toml\"\ncurbs = { count = [2, 4] }\nboards = { count = [1, 3] }\nwalls = { count = [1, 2] }\n\
         bushes = { count = [0, 2] }\nramps = { count = [0, 2] }\npeople = { count = [1, 3] }\n",
    )
    .expect("spec")
}

fn base() -> (PathBuf, Table) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../sweeps/bases/smoke.toml");
    let text = std::fs::read_to_string(&path).expect("base");
    (path, toml::from_str(&text).expect("toml"))
}

#[test]
fn generated_scenes_are_valid_deterministic_and_keep_the_drive_clear() {
    let (path, base) = base();
    let g = spec();
    for seed in 0..40u64 {
        let mut a = base.clone();
        g.place(seed, &mut a);
        let mut b = base.clone();
        g.place(seed, &mut b);
        assert_eq!(a, b, "seed {seed}: the same scene twice");
        let text = toml::to_string(&a).expect("text");
        let loaded = sim::scenario::load_str(&path, &text).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        let s = &loaded.scenario;
        assert!(!s.obstacles.is_empty() && !s.actors.is_empty(), "seed {seed}");
        for o in &s.obstacles {
            let [x, y] = o.center_xy_m();
            assert!((g.field_start_m..=g.field_end_m()).contains(&x), "{o:?}");
            assert!(y.abs() <= g.field_half_width_m, "{o:?}");
            // Nothing stands in the lane the robot drives.
            if x < g.drive_length_m {
                assert!(y.abs() > g.lane_half_width_m, "seed {seed}: {o:?} in the lane");
            }
        }
        // People leave before the run ends, and the robot faces the field.
        for sim::scenario::Actor::Person { waypoints, .. } in &s.actors {
            let last = waypoints[waypoints.len() - 1];
            assert!(last[0] < s.duration_s, "seed {seed}");
        }
        assert_eq!(
            s.robot.drive.waypoints_xy_m,
            vec![[0.0, 0.0], [g.drive_length_m, 0.0]]
        );
    }
    let (mut a, mut b) = (base.clone(), base);
    g.place(1, &mut a);
    g.place(2, &mut b);
    assert_ne!(a, b, "another seed, another scene");
}

#[test]
fn a_goal_beyond_the_field_is_navigated_to_in_closed_loop() {
    let (path, base) = base();
    let g = GenerateSpec {
        goal_beyond_m: 2.0,
        navigate: true,
        navigation_time_s: 30.0,
        ..spec()
    };
    let mut doc = base.clone();
    g.place(3, &mut doc);
    let text = toml::to_string(&doc).expect("text");
    let s = sim::scenario::load_str(&path, &text).expect("valid").scenario;
    let n = s.navigation.expect("a closed-loop run");
    assert_eq!(n.goal_xy_m, [g.field_end_m() + 2.0, 0.0]);
    assert_eq!(n.time_limit_s, Some(30.0));
    assert!(
        s.map.max_xy_m[0] >= n.goal_xy_m[0] + 1.0,
        "the region holds the goal"
    );
    assert!(s.duration_s >= g.drive_length_m / g.speed_m_s + 30.0);
    for o in &s.obstacles {
        let [x, y] = o.center_xy_m();
        assert!(
            (x - n.goal_xy_m[0]).hypot(y - n.goal_xy_m[1]) > 0.6,
            "{o:?} at the goal"
        );
    }
    // Without `navigate`, the goal is the planner check's only.
    let mut open = base;
    GenerateSpec {
        goal_beyond_m: 2.0,
        ..spec()
    }
    .place(3, &mut open);
    assert!(!open.contains_key("navigation"));
    assert_eq!(
        open["planner"]["goal_xy_m"][0].as_float(),
        Some(g.field_end_m() + 2.0)
    );
}

#[test]
fn heights_fall_in_their_ranges_and_straddle_the_step() {
    let (_, base) = base();
    let g = spec();
    let mut heights = Vec::new();
    for seed in 0..40u64 {
        let mut doc = base.clone();
        g.place(seed, &mut doc);
        for o in doc["obstacles"].as_array().expect("obstacles") {
            if o["name"].as_str().is_some_and(|n| n.starts_with("curb")) {
                heights.push(o["size_m"][2].as_float().expect("height"));
            }
        }
    }
    assert!(heights.iter().all(|h| (0.02..=0.05).contains(h)));
    assert!(heights.iter().any(|h| *h < 0.035) && heights.iter().any(|h| *h > 0.035));
}
