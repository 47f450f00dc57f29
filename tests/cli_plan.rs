//! `oeg plan` through the built binary: a path on a saved map, and why there is none.

#![allow(
    clippy::disallowed_methods,
    reason = "tests and tools write their inputs directly"
)]

mod common;

use common::{oeg, temp_dir};
use std::path::{Path, PathBuf};
use std::process::Output;

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The demo's map in a fresh folder named `name`: the folder and the map file.
fn demo_map(name: &str) -> (PathBuf, PathBuf) {
    let dir = temp_dir("map", name);
    let demo = dir.join("demo");
    let o = oeg(&["demo", "--out", demo.to_str().expect("utf8")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let map = demo.join("map.oeg");
    (dir, map)
}

/// `oeg plan MAP --from 0.5,0 --to TO --out DIR/NAME EXTRA...`: its `plan.json`, its folder and what it said,
/// after checking its exit status (0 with a path, 3 without, as `oeg plan --help` documents).
fn plan_with(
    map: &Path,
    dir: &Path,
    to: &str,
    name: &str,
    extra: &[&str],
) -> (serde_json::Value, PathBuf, String) {
    let out = dir.join(name);
    let mut args = vec![
        "plan",
        map.to_str().expect("utf8"),
        "--from",
        "0.5,0",
        "--to",
        to,
        "--out",
        out.to_str().expect("utf8"),
    ];
    args.extend_from_slice(extra);
    let o = oeg(&args);
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("plan.json")).expect("plan.json")).expect("json");
    let expected = if summary["plan_found"] == true { 0 } else { 3 };
    assert_eq!(o.status.code(), Some(expected), "{}", stderr(&o));
    (summary, out, stderr(&o))
}

#[test]
fn plan_finds_the_way_between_the_demo_curbs_and_none_onto_the_5_cm_curb() {
    let (dir, map) = demo_map("plan");
    let plan = |to: &str, name: &str| plan_with(&map, &dir, to, name, &[]);
    // Along the corridor between the 3 cm and the 5 cm curb (0.8 m apart): the straight 5.5 m, but for the few
    // cells the path steps aside to keep to the corridor's middle, away from the curbs (the inflation cost).
    let (open, out, _) = plan("6,0", "open");
    assert_eq!(open["plan_found"], true);
    let length_m = open["plan_length_m"].as_f64().expect("length");
    assert!((5.5..5.7).contains(&length_m), "{open}");
    let path = std::fs::read_to_string(out.join("path.csv")).expect("path.csv");
    assert!(path.starts_with("step,x_m,y_m\n0,0.525,0.025\n"), "{path}");
    assert_eq!(
        path.lines().count() as u64 - 1,
        open["num_path_cells"].as_u64().expect("cells")
    );
    assert!(out.join("plan.png").is_file());
    assert!(open["no_path_reason"].is_null(), "{open}");
    // Onto the 5 cm curb: no path (and an empty path.csv), and the reason.
    let (blocked, out, said) = plan("3.15,1.2", "blocked");
    assert_eq!(blocked["plan_found"], false);
    // The curb's top is level; its edges are steps, and the goal lies closer to one than the robot's radius.
    let reason = "the goal cell lies within the inflation radius (0.25 m) of a blocked or uncertain cell";
    assert_eq!(blocked["no_path_reason"], reason);
    assert!(said.contains(reason), "{said}");
    assert!(blocked["plan_length_m"].is_null());
    assert_eq!(
        std::fs::read_to_string(out.join("path.csv")).expect("path.csv"),
        "step,x_m,y_m\n"
    );
    // A malformed point is a clear error.
    let o = oeg(&[
        "plan",
        map.to_str().expect("utf8"),
        "--from",
        "0.5",
        "--to",
        "6,0",
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("expected X,Y in metres"), "{}", stderr(&o));
    // Far points: the search's arrays over 100 km x 100 km at 0.05 m would pass the memory limit, so the
    // plan is refused before it allocates them (it used to abort).
    let o = oeg(&[
        "plan",
        map.to_str().expect("utf8"),
        "--from",
        "0.5,0",
        "--to",
        "100000,100000",
        "--out",
        dir.join("far").to_str().expect("utf8"),
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("over the memory limit")
            && stderr(&o).contains("plan between points nearer the map"),
        "{}",
        stderr(&o)
    );
    assert!(!dir.join("far").exists(), "nothing written");
}

#[test]
fn with_no_connection_plan_lists_the_cells_that_closed_the_way() {
    let (dir, map) = demo_map("closing");
    let plan = |to: &str, name: &str| plan_with(&map, &dir, to, name, &[]);
    // A goal the robot may not stand on (beside the 5 cm curb) is closed by the goal itself: nothing to list.
    let (blocked, out, _) = plan("3.15,1.2", "blocked");
    assert_eq!(blocked["closed_by"], serde_json::json!({}));
    assert!(!out.join("closing.csv").exists());
    // Far beyond the room: both ends may be stood on, but the room's walls close every way, whatever the planner
    // made of the cells it cannot decide: nothing to list.
    let (far, out, said) = plan("30,0", "walled");
    assert_eq!(far["plan_found"], false);
    assert!(said.contains("no connection"), "{said}");
    assert_eq!(far["closed_by"], serde_json::json!({}));
    assert!(!out.join("closing.csv").exists());
    // Into the room's corner the sensor never saw: the never-observed cells on the path through every undecided
    // cell closed the way, counted by reason in plan.json and listed in closing.csv.
    let (corner, out, said) = plan("0.5,2.5", "corner");
    assert_eq!(corner["plan_found"], false);
    let closed_by = corner["closed_by"].as_object().expect("closed_by");
    let never_observed = closed_by["never_observed"].as_u64().expect("count");
    assert!(never_observed > 0, "{corner}");
    let total: u64 = closed_by.values().map(|n| n.as_u64().expect("count")).sum();
    assert!(
        said.contains(&format!("closed by {total} cells the map cannot decide")),
        "{said}"
    );
    let closing = std::fs::read_to_string(out.join("closing.csv")).expect("closing.csv");
    assert!(closing.starts_with("x_m,y_m,class,reason\n"), "{closing}");
    assert_eq!(closing.lines().count() as u64 - 1, total);
    let listed = closing
        .lines()
        .filter(|l| l.ends_with(",unknown,never_observed"))
        .count() as u64;
    assert_eq!(listed, never_observed, "{closing}");
    // Judged by the contact rule, observed cells beside the never-observed ones are the frontier: the reason is
    // the decision's doubt.
    let (judged, out, _) = plan_with(
        &map,
        &dir,
        "0.5,2.5",
        "corner_contact",
        &["--set", "map.preset=robust"],
    );
    let frontier = judged["closed_by"]["frontier"].as_u64().expect("frontier cells");
    assert!(frontier > 0, "{judged}");
    let closing = std::fs::read_to_string(out.join("closing.csv")).expect("closing.csv");
    let listed = closing
        .lines()
        .filter(|l| l.ends_with(",unknown,frontier"))
        .count() as u64;
    assert_eq!(listed, frontier, "{closing}");
}

#[test]
fn plan_json_names_the_step_rule_the_cells_were_judged_by() {
    let (dir, map) = demo_map("rule");
    // The paper's absolute rule unless given; a preset's rule with `map.preset`.
    let (paper, _, _) = plan_with(&map, &dir, "6,0", "paper", &[]);
    assert_eq!(paper["traversability"]["kind"], "absolute", "{paper}");
    let (robust, _, _) = plan_with(&map, &dir, "6,0", "robust", &["--set", "map.preset=robust"]);
    assert_eq!(robust["traversability"]["kind"], "contact", "{robust}");
}
