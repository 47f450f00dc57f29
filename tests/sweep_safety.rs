//! Nothing a study writes may destroy a user's files, and the last bad inputs: one test per problem, through
//! the built binary (the ownership, link, lock, size and row rules of `docs/guarantees.md`).

#![allow(
    clippy::disallowed_methods,
    reason = "tests write their inputs, plant links and corrupt rows directly"
)]

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::{err, oeg, ok, root, s, sweep_plan_error, temp_dir};

fn smoke() -> PathBuf {
    root().join("sweeps/smoke.toml")
}

/// Every file under `dir`, with its bytes.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).expect("dir") {
            let p = e.expect("entry").path();
            if p.is_dir() {
                todo.push(p);
            } else {
                let bytes = std::fs::read(&p).expect("read");
                out.push((p, bytes));
            }
        }
    }
    out.sort();
    out
}

fn sweep_run(out: &Path) -> Output {
    oeg(&["sweep", "run", s(&smoke()), "--out", s(out), "--jobs", "2"])
}

/// A finished smoke sweep in `dir/name`.
fn finished(dir: &Path, name: &str) -> PathBuf {
    let out = dir.join(name);
    ok(&sweep_run(&out));
    out
}

#[test]
fn sweep_run_and_report_refuse_a_folder_that_is_not_a_sweeps() {
    let dir = temp_dir("safety", "ownership");
    let theirs = dir.join("theirs");
    std::fs::create_dir_all(theirs.join("src")).expect("dir");
    for (f, text) in [
        ("runs.csv", "their rows"),
        ("obstacles.csv", "theirs"),
        ("src/a.rs", "fn a() {}"),
    ] {
        std::fs::write(theirs.join(f), text).expect("write");
    }
    let before = snapshot(&theirs);
    let e = err(&sweep_run(&theirs));
    assert!(
        e.contains("theirs") && e.contains("is not a sweep's folder"),
        "{e}"
    );
    let e = err(&oeg(&["sweep", "report", s(&theirs)]));
    assert!(e.contains("is not a sweep's folder"), "{e}");
    assert_eq!(snapshot(&theirs), before, "nothing of theirs was touched");
    // An `oeg run` folder is a job's, not a sweep's: its obstacles.csv stays.
    let run = dir.join("run");
    ok(&oeg(&[
        "preview",
        s(&root().join("tests/scenes/person.toml")),
        "--out",
        s(&run),
    ]));
    let before = snapshot(&run);
    err(&sweep_run(&run));
    err(&oeg(&["sweep", "report", s(&run)]));
    assert_eq!(snapshot(&run), before);
    // The root and the current folder, whatever they hold.
    let e = err(&sweep_run(Path::new("/")));
    assert!(e.contains("root"), "{e}");
    let empty = dir.join("empty_cwd");
    std::fs::create_dir_all(&empty).expect("dir");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_oeg"))
        .args(["sweep", "run", s(&smoke()), "--out", "."])
        .current_dir(&empty)
        .output()
        .expect("runs");
    let e = err(&o);
    assert!(e.contains("current folder"), "{e}");
    assert_eq!(
        std::fs::read_dir(&empty).expect("dir").count(),
        0,
        "nothing written"
    );
}

#[test]
fn an_earlier_versions_file_pair_beside_someone_elses_files_is_never_replaced() {
    let dir = temp_dir("safety", "earlier");
    let experiment = dir.join("experiment");
    std::fs::create_dir_all(experiment.join("src")).expect("dir");
    for f in ["metrics.json", "timing.json", "thesis.tex", "src/train.py"] {
        std::fs::write(experiment.join(f), f).expect("write");
    }
    let before = snapshot(&experiment);
    let e = err(&oeg(&[
        "run",
        s(&root().join("tests/scenes/person.toml")),
        "--out",
        s(&experiment),
    ]));
    assert!(e.contains("no oeg job wrote"), "{e}");
    assert_eq!(snapshot(&experiment), before, "thesis.tex and src/ stay");
}

#[test]
fn a_link_planted_in_a_sweep_folder_is_never_followed() {
    let dir = temp_dir("safety", "links");
    let out = finished(&dir, "study");
    let outside = dir.join("outside");
    std::fs::create_dir_all(&outside).expect("dir");
    std::fs::write(outside.join("precious.csv"), "keep").expect("write");
    let before = snapshot(&outside);
    std::fs::remove_file(out.join("runs.csv")).expect("rm");
    std::os::unix::fs::symlink(outside.join("precious.csv"), out.join("runs.csv")).expect("link");
    let e = err(&sweep_run(&out));
    assert!(
        e.contains("runs.csv") && e.contains("symbolic link inside the sweep folder"),
        "{e}"
    );
    std::fs::remove_file(out.join("runs.csv")).expect("rm");
    ok(&sweep_run(&out));
    std::os::unix::fs::symlink(&outside, out.join("plots")).expect("link");
    let e = err(&oeg(&["sweep", "report", s(&out)]));
    assert!(e.contains("plots") && e.contains("symbolic link"), "{e}");
    // A run's folder replaced by a link to somewhere else.
    let run = std::fs::read_dir(out.join("runs"))
        .expect("runs")
        .next()
        .expect("a run")
        .expect("e")
        .path();
    std::fs::remove_dir_all(&run).expect("rm");
    std::os::unix::fs::symlink(&outside, &run).expect("link");
    err(&sweep_run(&out));
    assert_eq!(snapshot(&outside), before, "nothing outside the folder changed");
}

#[test]
fn a_row_that_is_not_its_runs_is_an_error_before_any_run_never_a_panic() {
    let dir = temp_dir("safety", "rows");
    let out = finished(&dir, "study");
    let mut runs: Vec<PathBuf> = std::fs::read_dir(out.join("runs"))
        .expect("runs")
        .map(|e| e.expect("entry").path())
        .collect();
    runs.sort();
    let (a, b) = (&runs[0], &runs[1]);
    let a_row = std::fs::read(a.join("row.json")).expect("row");
    let b_row = std::fs::read(b.join("row.json")).expect("row");
    for bad in [
        b"[]".to_vec(),
        b"5".to_vec(),
        b"\"x\"".to_vec(),
        b"true".to_vec(),
        b"{\"row\": {}}".to_vec(),
        a_row.clone(),
    ] {
        std::fs::write(b.join("row.json"), &bad).expect("write");
        let e = err(&sweep_run(&out));
        assert!(e.contains("row.json"), "{}: {e}", String::from_utf8_lossy(&bad));
        let e = err(&oeg(&[
            "sweep",
            "merge",
            s(&out),
            "--out",
            s(&dir.join("merged")),
        ]));
        assert!(e.contains("row.json"), "{e}");
    }
    let e = err(&sweep_run(&out));
    assert!(e.contains("a copied row") && e.contains("remove"), "{e}");
    std::fs::write(b.join("row.json"), &b_row).expect("restore");
    ok(&sweep_run(&out));
}

#[test]
fn a_lock_naming_a_live_process_that_holds_no_lock_is_taken_over() {
    let dir = temp_dir("safety", "lock");
    let out = finished(&dir, "study");
    // After a container restart the id names some live process (1 is always alive); after a requeue the
    // record names another host. Nobody holds the operating system's lock, so the folder is free.
    for record in ["1\n", "host=another-node pid=1 boot=x start=1\n"] {
        std::fs::write(out.join(".lock"), record).expect("write");
        ok(&sweep_run(&out));
        assert!(!out.join(".lock").exists(), "released");
    }
}

#[test]
fn a_text_input_of_endless_bytes_is_refused_before_it_is_read() {
    let dir = temp_dir("safety", "sizes");
    let o = dir.join("o");
    for args in [
        vec!["run", "/dev/zero", "--out", s(&o)],
        vec!["validate", "/dev/zero"],
        vec!["sweep", "plan", "/dev/zero"],
    ] {
        let e = err(&oeg(&args));
        assert!(
            e.contains("/dev/zero") && e.contains("over the limit"),
            "{args:?}: {e}"
        );
    }
    // A data input of endless bytes, whatever its name says.
    let zero = dir.join("zero.graph");
    std::os::unix::fs::symlink("/dev/zero", &zero).expect("link");
    let e = err(&oeg(&["map", s(&zero), "--resolution", "0.1", "--out", s(&o)]));
    assert!(
        e.contains("zero.graph") && e.contains("not a regular file"),
        "{e}"
    );
    let sweep = dir.join("zero_base.toml");
    std::fs::write(&sweep, "name = \"z\"\nseed = 1\nscenarios = [\"/dev/zero\"]\n").expect("write");
    let e = err(&oeg(&["sweep", "plan", s(&sweep)]));
    assert!(
        e.contains("zero_base.toml:3:") && e.contains("over the limit"),
        "{e}"
    );
}

#[test]
fn a_report_says_how_much_of_the_plan_it_covers_and_refuses_a_partial_study() {
    let dir = temp_dir("safety", "partial");
    let shard = dir.join("shard");
    ok(&oeg(&[
        "sweep",
        "run",
        s(&smoke()),
        "--out",
        s(&shard),
        "--shard",
        "1/2",
    ]));
    let e = err(&oeg(&["sweep", "report", s(&shard)]));
    assert!(
        e.contains("covers 4 of the plan's 8 runs") && e.contains("--partial"),
        "{e}"
    );
    let out = ok(&oeg(&["sweep", "report", s(&shard), "--partial"]));
    assert!(out.contains("4 of the plan's 8 runs (a partial study)"), "{out}");
    let whole = finished(&dir, "whole");
    let out = ok(&oeg(&["sweep", "report", s(&whole)]));
    assert!(out.contains("8 of the plan's 8 runs\n"), "{out}");
    // From inside the study: the current folder is a sweep's, so the report may write there.
    let inside = std::process::Command::new(env!("CARGO_BIN_EXE_oeg"))
        .args(["sweep", "report", "."])
        .current_dir(&whole)
        .output()
        .expect("runs");
    assert!(ok(&inside).contains("8 of the plan's 8 runs"));
    // Another plan's plan.json over these rows, and a plan with no runs.
    let plan = std::fs::read_to_string(whole.join("plan.json")).expect("plan");
    let other: String = plan.replace("\"id\": \"", "\"id\": \"x");
    std::fs::write(whole.join("plan.json"), other).expect("write");
    let e = err(&oeg(&["sweep", "report", s(&whole)]));
    assert!(e.contains("is not in") && e.contains("plan.json"), "{e}");
    std::fs::write(whole.join("plan.json"), "{\"runs\": []}").expect("write");
    let e = err(&oeg(&["sweep", "report", s(&whole)]));
    assert!(e.contains("lists no runs"), "{e}");
}

#[test]
fn bases_of_one_name_in_two_folders_stay_two_scenarios() {
    let dir = temp_dir("safety", "bases");
    let base = std::fs::read_to_string(root().join("sweeps/bases/field_lasers.toml")).expect("base");
    let urdf = root().join("scenarios/robots/pioneer3at.urdf");
    let base = base.replace("../../scenarios/robots/pioneer3at.urdf", s(&urdf));
    for (folder, seconds) in [("a", "8.0"), ("b", "9.0")] {
        std::fs::create_dir_all(dir.join(folder)).expect("dir");
        let text = base.replacen("duration_s = 10.0", &format!("duration_s = {seconds}"), 1);
        assert_ne!(text, base, "the base has `duration_s = 10.0`");
        std::fs::write(dir.join(folder).join("field.toml"), text).expect("write");
    }
    let sweep = dir.join("two.toml");
    std::fs::write(
        &sweep,
        "name = \"two\"\nseed = 1\nscenarios = [\"a/field.toml\", \"b/field.toml\"]\n",
    )
    .expect("write");
    let out = ok(&oeg(&["sweep", "plan", s(&sweep)]));
    assert!(
        out.contains(" a/field replicate 0") && out.contains(" b/field replicate 0"),
        "{out}"
    );
}

#[test]
fn sweep_errors_point_at_the_sweep_files_own_lines() {
    let dir = temp_dir("safety", "lines");
    let base = root().join("sweeps/bases/smoke.toml");
    for (body, expected) in [
        // Expectations are checked as `oeg validate` checks them.
        (
            "[set]\n\"expectations.coverage\" = { min = 2.0 }\n",
            "e.toml:5:27: `expectations.coverage`",
        ),
        // A fixed-length list with an extra element.
        (
            "[set]\n\"robot.drive.waypoints_xy_m\" = [[0.0, 0.0, 5.0], [1.0, 0.0]]\n",
            "e.toml:5:",
        ),
        (
            "[[axes]]\nkey = \"sensors.*.x\"\nvalues = [0.1]\n[[axes]]\nkey = \"sensors.0.x\"\nvalues = [0.2]\n",
            "e.toml:8:7: axes `sensors.*.x` and `sensors.0.x`",
        ),
    ] {
        let e = sweep_plan_error(&dir, "e", body);
        assert!(e.contains(expected), "{body}: {e}");
        let places_in_base = e
            .match_indices("smoke.toml:")
            .any(|(k, m)| e[k + m.len()..].starts_with(|c: char| c.is_ascii_digit()));
        assert!(!places_in_base, "no place in the rewritten base: {e}");
    }
    // A base scenario's own error points at the base's own line.
    let text = std::fs::read_to_string(root().join("sweeps/bases/field_lasers.toml")).expect("base");
    let urdf = root().join("scenarios/robots/pioneer3at.urdf");
    let broken = text
        .replace("../../scenarios/robots/pioneer3at.urdf", s(&urdf))
        .replacen("duration_s = 10.0", "duration_s = -1.0", 1);
    let line = broken
        .lines()
        .position(|l| l.starts_with("duration_s"))
        .expect("duration_s")
        + 1;
    std::fs::write(dir.join("broken.toml"), broken).expect("write");
    std::fs::write(
        dir.join("uses_broken.toml"),
        "name = \"u\"\nseed = 1\nscenarios = [\"broken.toml\"]\n",
    )
    .expect("write");
    let e = err(&oeg(&["sweep", "plan", s(&dir.join("uses_broken.toml"))]));
    assert!(e.contains(&format!("broken.toml:{line}:")), "{e}");
    let generated = format!(
        "name = \"g\"\nseed = 1\n[generate]\nbase = {:?}\ncurbs = {{ count = [1, 2, 3] }}\n",
        s(&base)
    );
    let path = dir.join("g.toml");
    std::fs::write(&path, generated).expect("write");
    let e = err(&oeg(&["sweep", "plan", s(&path)]));
    assert!(
        e.contains("g.toml:5:") && e.contains("expected a list of 2 values, got 3"),
        "{e}"
    );
}

#[test]
fn settings_on_the_command_line_mean_one_thing() {
    let dir = temp_dir("safety", "settings");
    let graph = dir.join("demo");
    ok(&oeg(&["demo", "--out", s(&graph)]));
    let input = graph.join("demo.graph");
    let m = dir.join("m");
    let map = |extra: &[&str]| {
        let mut args = vec!["map", s(&input), "--resolution", "0.5", "--out", s(&m)];
        args.extend_from_slice(extra);
        oeg(&args)
    };
    let e = err(&map(&["--set", "map.resolution_m=0.1"]));
    assert!(e.contains("`--resolution`"), "{e}");
    let e = err(&map(&["--set", "map.model.p_max=0.7 # note"]));
    assert!(e.contains("is not one value"), "{e}");
    ok(&map(&["--set", "input.log_pose=true"]));
}
