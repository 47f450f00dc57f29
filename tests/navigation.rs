//! Closed-loop runs through the built binary: the robot reaches a goal round a wall, a curb no sensor sees is
//! a contact with its time and place, runs are the same bytes on any thread count, every way an external
//! planner can fail is an event with its message, the example planners drive the robot, the planner's files
//! read back, and a scenario's command never runs unless allowed. The hand-made scenes where a navigator must
//! stay live are in `navigation_liveness.rs`.

#![allow(clippy::disallowed_methods, reason = "tests write their inputs directly")]

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use common::{check_page, err, oeg, oeg_with_threads, ok, root, s, temp_dir};

fn scene(name: &str) -> PathBuf {
    root().join("tests/scenes").join(format!("{name}.toml"))
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).expect("read")).expect("json")
}

fn events(out: &Path) -> Vec<serde_json::Value> {
    json(&out.join("navigation.json"))["events"]
        .as_array()
        .expect("events")
        .clone()
}

/// Every file under `dir` but the wall times, by relative path.
fn contents(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("dir").flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.file_name().is_some_and(|n| n != "timing.json") {
                out.insert(
                    p.strip_prefix(dir).expect("inside").to_path_buf(),
                    std::fs::read(&p).expect("read"),
                );
            }
        }
    }
    out
}

#[test]
fn a_closed_loop_run_reaches_a_goal_round_a_wall_without_touching_it() {
    let out = temp_dir("nav", "wall");
    let stdout = ok(&oeg(&["run", s(&scene("nav_wall")), "--out", s(&out)]));
    assert!(stdout.contains("nav_wall"), "{stdout}");
    let nav = json(&out.join("navigation.json"));
    assert_eq!(nav["outcome"], "reached", "{nav:#}");
    assert_eq!(nav["contacts"], 0);
    // It planned again when the wall closed the straight path (`[navigation] replan = "when_invalid"`).
    assert!(nav["replans"].as_u64() >= Some(2), "{nav:#}");
    // It went round: the straight line is 5.5 m, the way round the wall's end longer.
    assert!(nav["driven_length_m"].as_f64().expect("length") > 6.0, "{nav:#}");
    let approach = nav["closest_approach_m"]
        .as_f64()
        .expect("an approach within 2 m");
    assert!(approach > 0.0 && approach < 1.0, "{approach}");
    let m = json(&out.join("metrics.json"));
    assert_eq!(m["nav_reached"], true);
    assert_eq!(m["nav_contacts"], 0);
    // The trajectory: one row per tick, in time order, the robot never passing through the wall's cells.
    let trajectory = std::fs::read_to_string(out.join("trajectory.csv")).expect("trajectory");
    let mut lines = trajectory.lines();
    assert_eq!(
        lines.next(),
        Some(
            "time_s,true_x_m,true_y_m,true_yaw_deg,estimated_x_m,estimated_y_m,estimated_yaw_deg,speed_m_s,\
             turn_rate_deg_s,planner_state,plan"
        )
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert!(
        rows.windows(2)
            .all(|w| w[0][0].parse::<f64>().ok() < w[1][0].parse::<f64>().ok())
    );
    assert_eq!(rows.last().expect("rows")[9], "reached");
    for f in ["events.csv", "plans.csv", "decisions.png", "metrics.json"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    assert!(
        !out.join("planner").exists(),
        "the built-in planner exchanges no files"
    );
}

#[test]
fn a_curb_the_sensors_cannot_see_is_a_contact_with_its_time_and_place() {
    let out = temp_dir("nav", "blind");
    ok(&oeg(&["run", s(&scene("nav_blind")), "--out", s(&out)]));
    let contact = events(&out)
        .into_iter()
        .find(|e| e["kind"] == "contact")
        .expect("a contact");
    assert_eq!(contact["obstacle"], "curb 6 cm");
    // The curb spans x 2.35 .. 2.65 m; the footprint reaches 0.255 m ahead of the robot's centre.
    let (x, t) = (
        contact["x_m"].as_f64().expect("x"),
        contact["time_s"].as_f64().expect("t"),
    );
    assert!((2.0..2.4).contains(&x), "{contact:#}");
    assert!(t > 4.0 && t < 7.0, "{contact:#}");
    let nav = json(&out.join("navigation.json"));
    assert!(nav["contacts"].as_u64() >= Some(1));
    assert_eq!(nav["closest_approach_m"], 0.0);
    let csv = std::fs::read_to_string(out.join("events.csv")).expect("events");
    assert!(csv.starts_with(
        "time_s,kind,x_m,y_m,yaw_deg,obstacle,distance_m,observable,mapped_as,closed_by,message\n"
    ));
    assert!(csv.contains(",contact,") && csv.contains("curb 6 cm"), "{csv}");
    // The curb is below every beam the tilted lasers cast before the robot reached it: a blind contact.
    assert_eq!(contact["observable"], false, "{contact:#}");
    assert_eq!(nav["contacts_blind"], nav["contacts"]);
    assert_eq!(nav["contacts_observable"], 0);
    let metrics = json(&out.join("metrics.json"));
    assert_eq!(metrics["nav_contacts_blind"], nav["contacts"]);
    assert_eq!(metrics["nav_contacts_observable"], 0);
    // What the map called the curb when the robot entered it: never blocked, since no beam saw it. Every
    // contact has one cause, and the metrics say the same as the summary.
    assert_ne!(contact["mapped_as"], "blocked", "{contact:#}");
    let by_cause = ["blocked", "undecided", "drivable"].map(|c| {
        let n = &nav[format!("contacts_mapped_{c}")];
        assert_eq!(metrics[format!("nav_contacts_mapped_{c}")], *n, "{c}");
        n.as_u64().expect("a count")
    });
    assert_eq!(Some(by_cause.iter().sum::<u64>()), nav["contacts"].as_u64());
    let images: Vec<_> = std::fs::read_dir(out.join("events"))
        .expect("event images")
        .flatten()
        .collect();
    assert!(
        images
            .iter()
            .any(|e| e.file_name().to_string_lossy().ends_with("_contact.png"))
    );
    assert_eq!(json(&out.join("metrics.json"))["nav_contacts"], nav["contacts"]);
    // The run's page shows the closed loop: its outcome, the events and the maps at the events.
    let page = check_page(&out.join("report.html"));
    assert!(page.contains("id=\"navigation\"") && page.contains("<td>contact</td>"));
    assert!(
        page.contains("_contact.png\""),
        "the contact's image is on the page"
    );
}

#[test]
fn a_curb_the_lasers_saw_is_an_observable_contact() {
    // The paper's model maps the 3 cm curb of `nav_curbs` low and, planning at every replanning time, drives
    // into its 5 cm neighbour, which the lasers had seen: the contact is the map's, not the sensors'.
    let (out, curbs) = (temp_dir("nav", "curbs"), root().join("scenarios/nav_curbs.toml"));
    let run = ["run", s(&curbs), "--out", s(&out)];
    ok(&oeg(
        &[&run[..], &["--set", "navigation.replan=periodic"]].concat()
    ));
    let nav = json(&out.join("navigation.json"));
    assert!(nav["contacts"].as_u64() >= Some(1), "{nav:#}");
    assert_eq!(nav["contacts_observable"], nav["contacts"]);
    assert!(
        events(&out)
            .iter()
            .filter(|e| e["kind"] == "contact")
            .all(|e| e["observable"] == true)
    );
}

#[test]
fn closed_loop_runs_are_the_same_bytes_on_one_and_two_threads() {
    let (a, b) = (temp_dir("nav", "threads1"), temp_dir("nav", "threads2"));
    ok(&oeg_with_threads(
        &["run", s(&scene("nav_blind")), "--out", s(&a)],
        Some("1"),
    ));
    ok(&oeg_with_threads(
        &["run", s(&scene("nav_blind")), "--out", s(&b)],
        Some("2"),
    ));
    let (ca, cb) = (contents(&a), contents(&b));
    assert!(ca.contains_key(Path::new("trajectory.csv")));
    assert_eq!(ca.keys().collect::<Vec<_>>(), cb.keys().collect::<Vec<_>>());
    for (name, bytes) in &ca {
        assert!(
            cb[name] == *bytes,
            "{} differs between 1 and 2 threads",
            name.display()
        );
    }
}

/// A planner script in `dir` running `body` (a POSIX shell script; the path file is `$7`).
fn planner_script(dir: &Path, name: &str, body: &str) -> String {
    let path = dir.join(format!("{name}.sh"));
    std::fs::write(&path, format!("#!/bin/sh\n{body}\n")).expect("script");
    format!("sh {}", s(&path))
}

#[test]
fn every_way_a_planner_fails_is_an_event_with_its_message() {
    let dir = temp_dir("nav", "failing-planners");
    let cases = [
        (
            "letters",
            "printf 'x,y\\n0,0\\nzero,1\\n' > \"$7\"",
            "path.csv:3: x `zero` is not a number",
        ),
        (
            "nan",
            "printf '0,0\\nNaN,1\\n' > \"$7\"",
            "path.csv:2: (NaN, 1) is not a finite point",
        ),
        (
            "off_the_map",
            "printf '0,0\\n500,0\\n' > \"$7\"",
            "path.csv:2: (500, 0) m lies off the map",
        ),
        ("empty", ": > \"$7\"", "path.csv: the path is empty"),
        ("no_file", "exit 0", "path.csv: no readable path"),
        (
            "exit",
            "echo boom >&2; exit 1",
            "exited with exit status: 1; its stderr ends: boom",
        ),
        ("timeout", "sleep 20", "ran over its time-out of 0.3 s"),
    ];
    for (name, body, expected) in cases {
        let out = dir.join(name);
        let command = planner_script(&dir, name, body);
        ok(&oeg(&[
            "run",
            s(&scene("nav_blind")),
            "--out",
            s(&out),
            "--planner-command",
            &command,
            "--set",
            "navigation.planner_timeout_s=0.3",
            "--set",
            "navigation.stuck_time_s=1.5",
        ]));
        let failure = events(&out)
            .into_iter()
            .find(|e| e["kind"] == "planner_failed")
            .unwrap_or_else(|| panic!("{name}: no planner_failed event"));
        let message = failure["message"].as_str().expect("message");
        assert!(message.contains(expected), "{name}: {message}");
        // A file is named where it is after the run, never in the staging folder that is gone by then.
        assert!(!message.contains(".staging."), "{name}: {message}");
        if message.contains("path.csv") {
            let shown = out.join("planner").join("path.csv");
            assert!(message.starts_with(s(&shown)), "{name}: {message}");
        }
        let nav = json(&out.join("navigation.json"));
        assert_eq!(
            nav["outcome"], "stuck",
            "{name}: the robot waits for a path it never gets"
        );
        assert!(nav["planner_failures"].as_u64() >= Some(1));
        assert_eq!(nav["wall_time_dependent"], name == "timeout", "{name}");
    }
}

#[test]
fn the_example_planners_drive_the_robot_to_its_goal() {
    let dir = temp_dir("nav", "examples");
    let shell = root().join("examples/planners/oeg_plan.sh");
    let python = root().join("examples/planners/npy_planner.py");
    let mut planners = vec![("shell", format!("sh {}", s(&shell)))];
    if std::process::Command::new("python3")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
    {
        planners.push(("python", format!("python3 {}", s(&python))));
    } else {
        println!("skipped the Python example planner: python3 is not on the PATH");
    }
    for (name, command) in planners {
        let out = dir.join(name);
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_oeg"))
            .args([
                "run",
                s(&scene("nav_wall")),
                "--out",
                s(&out),
                "--planner-command",
                &command,
            ])
            .env("OEG", env!("CARGO_BIN_EXE_oeg"))
            .output()
            .expect("runs");
        ok(&o);
        let nav = json(&out.join("navigation.json"));
        assert_eq!(nav["planner"], "external", "{name}");
        assert_eq!(nav["outcome"], "reached", "{name}: {nav:#}");
        assert_eq!(nav["planner_failures"], 0, "{name}: {nav:#}");
        assert_eq!(nav["contacts"], 0, "{name}");
    }
}

#[test]
fn the_planner_files_read_back_with_their_origin_resolution_and_values() {
    let out = temp_dir("nav", "files");
    let dir = temp_dir("nav", "files-planner");
    // A planner that keeps a copy of what it was given, then fails (the run goes on).
    let copy = planner_script(
        &dir,
        "copy",
        &format!("cp \"$(dirname \"$5\")\"/* {} ; exit 1", s(&dir)),
    );
    ok(&oeg(&[
        "run",
        s(&scene("nav_wall")),
        "--out",
        s(&out),
        "--planner-command",
        &copy,
        "--set",
        "navigation.stuck_time_s=1",
    ]));
    let sidecar = json(&dir.join("layers.json"));
    assert_eq!(sidecar["resolution_m"], 0.05);
    let origin: Vec<f64> = sidecar["origin_xy_m"]
        .as_array()
        .expect("origin")
        .iter()
        .filter_map(serde_json::Value::as_f64)
        .collect();
    assert_eq!(origin, [-1.0, -3.0]);
    assert_eq!(sidecar["shape"], serde_json::json!([120, 160]));
    assert_eq!(sidecar["layers"]["decisions"]["values"]["3"], "blocked");
    let yaml = std::fs::read_to_string(dir.join("map.yaml")).expect("yaml");
    assert!(
        yaml.contains("resolution: 0.05\n") && yaml.contains("origin: [-1, -3, 0.0]\n"),
        "{yaml}"
    );
    assert!(yaml.contains("image: map.pgm\n") && yaml.contains("mode: trinary\n"));
    let pgm = std::fs::read(dir.join("map.pgm")).expect("pgm");
    let header = b"P5\n# CREATOR: oeg 0.05\n160 120\n255\n";
    assert_eq!(&pgm[..header.len()], header);
    assert_eq!(pgm.len(), header.len() + 160 * 120);
    // The decisions and the layers against the map file given beside them.
    let map = oeg::load_map(&dir.join("map.oeg")).expect("map");
    let region = oeg::CellRegion::from_corners(oeg::CellIndex::new(-20, -60), oeg::CellIndex::new(139, 59))
        .expect("region");
    let profile = oeg::RobotProfile::default();
    let decisions = map
        .traversability_layer(region, &profile, oeg::TraversabilityRule::default())
        .expect("layer");
    let npy = |name: &str| {
        let path = dir.join(name);
        oeg::NpyArray::from_bytes(&path, &std::fs::read(&path).expect("npy")).expect("reads")
    };
    let d = npy("decisions.npy");
    assert_eq!((d.rows, d.cols), (120, 160));
    let oeg::NpyData::U8(codes) = d.data else {
        panic!("uint8 decisions")
    };
    assert_eq!(
        codes,
        decisions.values.iter().map(|t| *t as u8).collect::<Vec<_>>()
    );
    // PGM rows run from the max-y edge: its last row is the npy's first.
    let pixels = &pgm[header.len()..];
    for (k, t) in decisions.values[..160].iter().enumerate() {
        assert_eq!(
            pixels[119 * 160 + k],
            oeg::nav2_grey(*t, oeg::UncertainCells::Blocked)
        );
    }
    let e = npy("elevation_m.npy");
    let oeg::NpyData::F32(elevation) = e.data else {
        panic!("float32 elevation")
    };
    let expected = map
        .layer(oeg::LayerKind::ElevationM, region)
        .expect("layer")
        .values;
    assert!(
        elevation
            .iter()
            .zip(&expected)
            .all(|(a, b)| a.to_bits() == b.to_bits())
    );
    // And with numpy, where it is installed.
    let script = format!(
        "import numpy, json\nd = numpy.load({:?})\nassert d.shape == (120, 160) and d.dtype == numpy.uint8\n\
         e = numpy.load({:?})\nassert e.dtype == numpy.float32\nprint('numpy read', d.shape)\n",
        s(&dir.join("decisions.npy")),
        s(&dir.join("elevation_m.npy"))
    );
    match std::process::Command::new("python3")
        .args(["-c", &script])
        .output()
    {
        Ok(o) if o.status.success() => println!("{}", String::from_utf8_lossy(&o.stdout)),
        Ok(o) if String::from_utf8_lossy(&o.stderr).contains("No module named 'numpy'") => {
            println!("skipped the numpy check: numpy is not installed");
        }
        Ok(o) => panic!(
            "numpy could not read the files: {}",
            String::from_utf8_lossy(&o.stderr)
        ),
        Err(_) => println!("skipped the numpy check: python3 is not on the PATH"),
    }
}

#[test]
fn a_scenario_command_never_runs_unless_allowed() {
    let dir = temp_dir("nav", "command");
    let marker = dir.join("it ran");
    let text = std::fs::read_to_string(scene("nav_blind"))
        .expect("scene")
        .replace("../../scenarios/robots", s(&root().join("scenarios/robots")))
        .replace(
            "goal_xy_m = [5.0, 0.0]",
            &format!(
                "goal_xy_m = [5.0, 0.0]\nplanner = \"external\"\ncommand = [\"sh\", \"-c\", \"touch '{}'\"]",
                s(&marker)
            ),
        );
    let scenario = dir.join("sent.toml");
    std::fs::write(&scenario, text).expect("scenario");
    let e = err(&oeg(&["run", s(&scenario), "--out", s(&dir.join("refused"))]));
    assert!(
        e.contains("--allow-scenario-command") && e.contains("[\"sh\", \"-c\", \"touch '"),
        "the exact argument vector: {e}"
    );
    assert!(!marker.exists(), "the command ran without being allowed");
    // Control characters in the file cannot hide the command behind another: they show escaped.
    let hiding = dir.join("hiding.toml");
    std::fs::write(
        &hiding,
        std::fs::read_to_string(&scenario)
            .expect("scenario")
            .replace("\"-c\", ", "\"-c\", \"\\u001b[2K\\rsafe-looking\", "),
    )
    .expect("scenario");
    let e = err(&oeg(&["run", s(&hiding), "--out", s(&dir.join("refused"))]));
    assert!(
        e.contains(r#"["sh", "-c", "\u{1b}[2K\rsafe-looking", "touch"#)
            && !e.contains('\u{1b}')
            && !e.contains('\r'),
        "{e:?}"
    );
    assert!(!dir.join("refused").exists(), "refused before any work");
    ok(&oeg(&[
        "run",
        s(&scenario),
        "--out",
        s(&dir.join("allowed")),
        "--allow-scenario-command",
        "--set",
        "navigation.stuck_time_s=1",
    ]));
    assert!(marker.exists(), "allowed, the command ran");
}
