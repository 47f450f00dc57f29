//! `oeg check-path` through the built binary: a path into a wall is a contact at its place, a path round it
//! passes, a broken path or a map of another cell size is refused by name, and a long path is checked within
//! its bound.

#![allow(clippy::disallowed_methods, reason = "tests write their inputs directly")]

mod common;

use std::path::{Path, PathBuf};

use common::{err, oeg, ok, root, s, temp_dir};

fn scene(name: &str) -> PathBuf {
    root().join("tests/scenes").join(format!("{name}.toml"))
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).expect("read")).expect("json")
}

/// A fresh folder for one test, and a writer of its input files.
fn folder(name: &str) -> (PathBuf, impl Fn(&str, &str) -> PathBuf) {
    let dir = temp_dir("check-path", name);
    let at = dir.clone();
    (dir, move |file: &str, text: &str| {
        let p = at.join(file);
        std::fs::write(&p, text).expect("path");
        p
    })
}

#[test]
fn check_path_finds_the_first_contact_and_passes_a_path_round_the_wall() {
    let (dir, write) = folder("wall");
    let straight = write("straight.csv", "x_m,y_m\n0,0\n5.5,0\n");
    let e = err(&oeg(&[
        "check-path",
        s(&scene("nav_wall")),
        s(&straight),
        "--out",
        s(&dir.join("a")),
    ]));
    assert!(e.contains("touches `wall`"), "{e}");
    let check = json(&dir.join("a/path_check.json"));
    let contact = &check["first_contact"];
    // The wall's face is at x = 2.7 m; the footprint reaches 0.255 m ahead of the robot's centre.
    let x = contact["x_m"].as_f64().expect("x");
    assert!((2.4..2.5).contains(&x), "{check:#}");
    assert!(check["cells_by_truth"]["step"].as_u64() > Some(0), "{check:#}");
    let round = write(
        "round.csv",
        "# round the wall's lower end\n0,0\n2.8,-1.6\n5.5,0\n",
    );
    let out = ok(&oeg(&[
        "check-path",
        s(&scene("nav_wall")),
        s(&round),
        "--out",
        s(&dir.join("b")),
    ]));
    assert!(out.contains("closest approach"), "{out}");
    let check = json(&dir.join("b/path_check.json"));
    assert_eq!(check["first_contact"], serde_json::Value::Null);
    assert_eq!(check["contact_poses"], 0);
    let broken = write("broken.csv", "0,0\n1,north\n");
    let e = err(&oeg(&[
        "check-path",
        s(&scene("nav_wall")),
        s(&broken),
        "--out",
        s(&dir.join("c")),
    ]));
    assert!(e.contains("broken.csv:2: y `north` is not a number"), "{e}");
    assert_eq!(e.matches("broken.csv").count(), 1, "the file named once: {e}");
    assert!(!dir.join("c").exists(), "nothing written for a broken path");
    // A map of another cell size is refused by name, not judged cell by cell against unrelated truth cells.
    let coarse = dir.join("coarse.oeg");
    oeg::save_map(&oeg::Map::new(oeg::MapConfig::new(0.1)).expect("map"), &coarse).expect("saved");
    let e = err(&oeg(&[
        "check-path",
        s(&scene("nav_wall")),
        s(&round),
        "--map",
        s(&coarse),
        "--out",
        s(&dir.join("f")),
    ]));
    assert!(
        e.contains("coarse.oeg") && e.contains("a map of 0.1 m cells; the scenario's truth has 0.05 m cells"),
        "{e}"
    );
    assert!(!dir.join("f").exists(), "nothing written for a refused map");
}

#[test]
fn a_long_path_is_checked_within_its_bound_and_a_longer_one_is_refused() {
    let (dir, write) = folder("long");
    // A long path (2,000 points back and forth beside the wall, 4 km) is checked with one flag a cell, not every
    // pose's cells; one over the pose limit (3,000 km) is refused before the work.
    let zigzag = |name: &str, n: usize, far: f64| {
        let mut text = String::from("x_m,y_m\n");
        for k in 0..n {
            text.push_str(&format!(
                "{},{}\n",
                if k % 2 == 0 { 0.0 } else { far },
                -3.0 + 0.002 * (k % 2500) as f64
            ));
        }
        write(name, &text)
    };
    ok(&oeg(&[
        "check-path",
        s(&scene("nav_wall")),
        s(&zigzag("long.csv", 2000, 2.0)),
        "--out",
        s(&dir.join("d")),
    ]));
    let long = json(&dir.join("d/path_check.json"));
    // 1,999 segments of just over 2 m, 81 poses each, and the end.
    assert_eq!(long["num_poses"], 161_920, "{long:#}");
    assert_eq!(long["contact_poses"], 0, "{long:#}");
    let e = err(&oeg(&[
        "check-path",
        s(&scene("nav_wall")),
        s(&zigzag("too_long.csv", 300_000, 6.5)),
        "--out",
        s(&dir.join("e")),
    ]));
    assert!(
        e.contains("too_long.csv") && e.contains("over the limit of 1000000"),
        "{e}"
    );
    assert!(!dir.join("e").exists(), "nothing written for a refused path");
}
