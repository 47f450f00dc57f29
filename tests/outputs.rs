//! Outputs are all or nothing and only ever replace what a job wrote: a FIFO, a device, a file or someone
//! else's folder given as `--out` is refused and left untouched; a run killed at any moment leaves the previous
//! results or none, never a mix; `oeg suite` runs a scenario named twice once, and its failed rows measure
//! nothing.

#![allow(
    clippy::disallowed_methods,
    reason = "tests and tools write their inputs directly"
)]

mod common;

use common::{oeg, root, temp_dir};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

fn scene(name: &str) -> PathBuf {
    root().join(format!("tests/scenes/{name}.toml"))
}

/// A short run of the decision scene (1 s of driving), for tests about files rather than maps. Its scene's
/// expectations are for the whole drive, so the run exits non-zero with its report written.
fn short_run_args<'a>(scenario: &'a str, out: &'a str, seed: &'a str) -> Vec<&'a str> {
    vec![
        "run",
        scenario,
        "--out",
        out,
        "--seed",
        seed,
        "--set",
        "duration_s=1.0",
    ]
}

/// Every file under `dir` but `timing.json` (wall times differ run to run), by relative path.
fn contents(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("readable") {
            let p = e.expect("entry").path();
            if p.is_dir() {
                stack.push(p);
            } else if p.file_name().is_some_and(|n| n != "timing.json") {
                let rel = p.strip_prefix(dir).expect("inside").to_path_buf();
                out.insert(rel, std::fs::read(&p).expect("read"));
            }
        }
    }
    out
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("dir");
    for e in std::fs::read_dir(from).expect("readable") {
        let e = e.expect("entry");
        std::fs::copy(e.path(), to.join(e.file_name())).expect("copy");
    }
}

#[test]
fn record_refuses_a_fifo_a_device_or_a_link_to_one_and_leaves_them_alone() {
    use std::os::unix::fs::FileTypeExt;
    let dir = temp_dir("outputs", "fifo");
    let fifo = dir.join("pipe");
    if !std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success())
    {
        println!("skipped: `mkfifo` is not available here");
        return;
    }
    let link = dir.join("link");
    std::os::unix::fs::symlink(&fifo, &link).expect("symlink");
    // A link to a device: refusing it never touches the device (a rename would only replace the link).
    let device = dir.join("device");
    std::os::unix::fs::symlink("/dev/null", &device).expect("symlink");
    let scenario = scene("decisions");
    for out in [&fifo, &link, &device] {
        let o = oeg(&[
            "record",
            scenario.to_str().expect("utf8"),
            "--out",
            out.to_str().expect("utf8"),
        ]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{stderr}");
        assert!(
            stderr.contains("a device, a FIFO or a socket") && !stderr.contains("wrote"),
            "{stderr}"
        );
        assert!(std::fs::metadata(&fifo).expect("there").file_type().is_fifo());
    }
    assert!(
        std::fs::symlink_metadata(&device)
            .expect("link")
            .file_type()
            .is_symlink()
    );
    assert_eq!(
        std::fs::read_dir(&dir).expect("dir").count(),
        3,
        "nothing else written"
    );
}

#[test]
fn an_out_folder_of_someone_elses_files_or_a_file_is_refused_untouched() {
    let dir = temp_dir("outputs", "foreign");
    let theirs = dir.join("theirs");
    std::fs::create_dir_all(&theirs).expect("dir");
    std::fs::write(theirs.join("thesis.tex"), b"precious").expect("write");
    let file = dir.join("a_file");
    std::fs::write(&file, b"also precious").expect("write");
    let scenario = scene("decisions");
    for (out, expected) in [(&theirs, "no oeg job wrote"), (&file, "is a file, not a folder")] {
        let o = oeg(&short_run_args(
            scenario.to_str().expect("utf8"),
            out.to_str().expect("utf8"),
            "1",
        ));
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && stderr.contains(expected), "{stderr}");
        assert!(
            stderr.contains(out.to_str().expect("utf8")),
            "names the path: {stderr}"
        );
    }
    assert_eq!(
        std::fs::read(theirs.join("thesis.tex")).expect("kept"),
        b"precious"
    );
    assert_eq!(std::fs::read(&file).expect("kept"), b"also precious");
    assert_eq!(std::fs::read_dir(&theirs).expect("dir").count(), 1);
    assert_eq!(
        std::fs::read_dir(&dir).expect("dir").count(),
        2,
        "no staging left"
    );
}

#[test]
fn a_killed_run_leaves_the_previous_results_or_none_never_a_mix() {
    let dir = temp_dir("outputs", "kill");
    let scenario = scene("decisions");
    let scenario = scenario.to_str().expect("utf8");
    // The two complete result sets: the previous run (seed 1) and the one that gets killed (seed 2).
    let (ref_old, ref_new) = (dir.join("ref_old"), dir.join("ref_new"));
    let o = oeg(&short_run_args(scenario, ref_old.to_str().expect("utf8"), "1"));
    assert!(
        ref_old.join("metrics.json").exists(),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let started = Instant::now();
    let o = oeg(&short_run_args(scenario, ref_new.to_str().expect("utf8"), "2"));
    assert!(
        ref_new.join("metrics.json").exists(),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let full = started.elapsed();
    let (old, new) = (contents(&ref_old), contents(&ref_new));
    assert_ne!(old, new, "the two seeds give different results");
    assert!(old.contains_key(Path::new("map.oeg")) && old.contains_key(Path::new("metrics.json")));

    let out = dir.join("out");
    let mut outcomes = Vec::new();
    // Kill points spread over the whole run, the last ones in the final writes and the commit.
    for fraction in [0.05, 0.3, 0.6, 0.85, 0.93, 0.97, 0.99, 1.02] {
        let _ = std::fs::remove_dir_all(&out);
        copy_dir(&ref_old, &out);
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_oeg"))
            .args(short_run_args(scenario, out.to_str().expect("utf8"), "2"))
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .expect("spawned");
        std::thread::sleep(full.mul_f64(fraction));
        let _ = child.kill(); // SIGKILL: no destructor, no clean-up runs
        let _ = child.wait();
        let outcome = if !out.exists() {
            "none"
        } else {
            let now = contents(&out);
            if now == old {
                "previous"
            } else if now == new {
                "new"
            } else {
                let mixed: Vec<_> = now.keys().filter(|k| old.get(*k) != now.get(*k)).collect();
                panic!("killed at {fraction} of the run: a mix of old and new files, {mixed:?} changed");
            }
        };
        outcomes.push((fraction, outcome));
    }
    println!("kill outcomes: {outcomes:?}");
    assert!(outcomes.iter().any(|(_, o)| *o == "previous"), "{outcomes:?}");
    // The next run removes what the killed ones left beside the output and completes.
    let o = oeg(&short_run_args(scenario, out.to_str().expect("utf8"), "2"));
    assert_eq!(contents(&out), new, "{}", String::from_utf8_lossy(&o.stderr));
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .expect("dir")
        .map(|e| e.expect("entry").file_name())
        .filter(|n| n.to_string_lossy().starts_with(".out."))
        .collect();
    assert!(leftovers.is_empty(), "stale staging removed: {leftovers:?}");
}

#[test]
fn a_suite_runs_a_scenario_named_twice_once_and_failed_rows_measure_nothing() {
    let dir = temp_dir("outputs", "suite");
    let broken = dir.join("broken.toml");
    std::fs::write(&broken, "name = \"broken\"\nduration_s = \"soon\"\n").expect("write");
    let good = scene("decisions");
    let good = good.to_str().expect("utf8");
    let out = dir.join("suite");
    let o = oeg(&[
        "suite",
        good,
        good,
        broken.to_str().expect("utf8"),
        "--out",
        out.to_str().expect("utf8"),
        "--set",
        "duration_s=1.0",
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success(),
        "the broken scenario fails the suite: {stderr}"
    );
    let rows: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("suite.json")).expect("suite.json")).expect("json");
    let rows = rows.as_array().expect("rows");
    assert_eq!(rows.len(), 2, "the scenario named twice ran once: {rows:?}");
    let error = rows
        .iter()
        .find(|r| r["status"] == "error")
        .expect("an error row");
    for key in [
        "coverage",
        "unsafe_step_cells",
        "plan_unsafe_cells",
        "elevation_rmse_m",
    ] {
        assert!(error[key].is_null(), "{key}: {error}");
    }
    let csv = std::fs::read_to_string(out.join("suite.csv")).expect("suite.csv");
    let header: Vec<&str> = csv.lines().next().expect("header").split(',').collect();
    let line = csv
        .lines()
        .find(|l| l.starts_with("broken,"))
        .expect("broken row");
    let column = header
        .iter()
        .position(|h| *h == "unsafe_step_cells")
        .expect("column");
    assert_eq!(line.split(',').nth(column), Some(""), "empty, not 0: {line}");
    assert!(stderr.contains("broken") && stderr.contains(" - "), "{stderr}");
}

#[test]
fn two_suites_on_one_folder_take_turns_and_each_leaves_it_whole() {
    let dir = temp_dir("outputs", "race");
    let out = dir.join("suite");
    let good = scene("decisions");
    let args = |seed: &'static str| {
        vec![
            "suite".to_string(),
            good.to_str().expect("utf8").to_string(),
            "--out".to_string(),
            out.to_str().expect("utf8").to_string(),
            "--set".to_string(),
            "duration_s=1.0".to_string(),
            "--set".to_string(),
            format!("seed={seed}"),
        ]
    };
    let spawn = |seed| {
        std::process::Command::new(env!("CARGO_BIN_EXE_oeg"))
            .args(args(seed))
            .output()
    };
    let (a, b) = std::thread::scope(|s| {
        let a = s.spawn(|| spawn("1"));
        let b = s.spawn(|| spawn("2"));
        (a.join().expect("a"), b.join().expect("b"))
    });
    for o in [a.expect("ran"), b.expect("ran")] {
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(
            !stderr.contains("error: ") || stderr.contains("did not pass"),
            "{stderr}"
        );
    }
    // Whichever finished last wins, whole: its table and its run folder agree.
    let rows: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("suite.json")).expect("suite.json")).expect("json");
    let metrics: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("decisions/metrics.json")).expect("metrics"))
            .expect("json");
    assert_eq!(rows[0]["unsafe_step_cells"], metrics["unsafe_step_cells"]);
    assert_eq!(rows[0]["coverage"], metrics["coverage"]);
    assert_eq!(rows[0]["elevation_rmse_m"], metrics["elevation_rmse_m"]);
}

#[test]
fn a_mount_point_as_out_is_written_in_place_twice() {
    // A container's volume is a mount point, which cannot be renamed: the job stages inside it. Mounting needs
    // privileges a test machine may not give; then the test says so and checks nothing.
    let dir = temp_dir("outputs", "mount");
    let volume = dir.join("volume");
    std::fs::create_dir_all(&volume).expect("dir");
    let mounted = std::process::Command::new("mount")
        .args(["-t", "tmpfs", "oeg-test", volume.to_str().expect("utf8")])
        .output();
    if !mounted.as_ref().is_ok_and(|o| o.status.success()) {
        eprintln!(
            "skipped: cannot mount a tmpfs here ({mounted:?}); the in-place commit is tested in oeg_eval::output"
        );
        return;
    }
    let out = volume.to_str().expect("utf8");
    let scenario = scene("decisions");
    let args = short_run_args(scenario.to_str().expect("utf8"), out, "3");
    let results: Vec<BTreeMap<PathBuf, Vec<u8>>> = (0..2)
        .map(|_| {
            let o = oeg(&args);
            let e = String::from_utf8_lossy(&o.stderr).into_owned();
            assert!(
                !e.contains("busy") && volume.join("metrics.json").is_file(),
                "{e}"
            );
            contents(&volume)
        })
        .collect();
    let _ = std::process::Command::new("umount").arg(&volume).status();
    assert_eq!(results[0], results[1], "the second run replaced the first whole");
    assert!(
        results[0]
            .keys()
            .all(|k| !k.to_string_lossy().contains(".oeg-staging")),
        "no staging left: {:?}",
        results[0].keys().collect::<Vec<_>>()
    );
}
