//! `oeg sweep` end to end: plan, run, resume after SIGKILL, shards and merge, report, generated scenes that
//! `oeg run` reproduces, and bad input.

#![allow(
    clippy::disallowed_methods,
    reason = "tests and tools write their inputs directly"
)]

mod common;

use std::path::{Path, PathBuf};

use common::{check_page, check_svg, err, oeg, ok, root, s, sweep_plan_error, temp_dir};

fn smoke() -> PathBuf {
    root().join("sweeps/smoke.toml")
}

/// The rows of a runs.csv without the wall-time column (the only one that varies between runs).
fn rows_without_wall_time(dir: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("runs.csv")).expect("runs.csv");
    let mut r = csv::Reader::from_reader(text.as_bytes());
    let headers = r.headers().expect("header").clone();
    let wall = headers
        .iter()
        .position(|h| h == "wall_time_s")
        .expect("wall_time_s column");
    assert_eq!(wall, headers.len() - 1, "wall_time_s is the last column");
    r.records()
        .map(|rec| {
            let rec = rec.expect("row");
            rec.iter().take(wall).collect::<Vec<_>>().join(",")
        })
        .collect()
}

/// A copy of the smoke sweep with more seeds, so that a run lasts long enough to be killed half-way.
fn longer_sweep(dir: &Path, seeds: u32) -> PathBuf {
    let text = std::fs::read_to_string(smoke())
        .expect("smoke.toml")
        .replace("seeds = 2", &format!("seeds = {seeds}"));
    let text = text.replace(
        "base = \"bases/smoke.toml\"",
        &format!("base = {:?}", s(&root().join("sweeps/bases/smoke.toml"))),
    );
    let path = dir.join("longer.toml");
    std::fs::write(&path, text).expect("write");
    path
}

#[test]
fn plan_lists_every_run_and_the_shared_simulations() {
    let out = ok(&oeg(&["sweep", "plan", s(&smoke())]));
    assert!(out.starts_with("smoke: 8 runs, 4 simulations"), "{out}");
    assert_eq!(out.lines().count(), 9, "{out}");
}

#[test]
fn set_holds_for_every_run_under_every_preset() {
    let dir = temp_dir("sweep", "set");
    let plain = ok(&oeg(&["sweep", "plan", s(&smoke())]));
    let set = ok(&oeg(&[
        "sweep",
        "plan",
        s(&smoke()),
        "--set",
        "map.model.p_max=0.7",
    ]));
    let ids = |out: &str| -> Vec<String> { out.lines().skip(1).map(|l| l[..16].to_string()).collect() };
    assert!(
        ids(&plain).iter().all(|id| !ids(&set).contains(id)),
        "--set changes every run"
    );
    ok(&oeg(&[
        "sweep",
        "run",
        s(&smoke()),
        "--out",
        s(&dir),
        "--set",
        "map.model.p_max=0.7",
    ]));
    for run in std::fs::read_dir(dir.join("runs"))
        .expect("runs")
        .filter_map(Result::ok)
    {
        let text = std::fs::read_to_string(run.path().join("scenario.toml")).expect("scenario");
        let doc: toml::Table = toml::from_str(&text).expect("toml");
        assert_eq!(
            doc["map"]["model"]["p_max"].as_float(),
            Some(0.7),
            "{}",
            run.path().display()
        );
    }
}

#[test]
fn a_killed_sweep_resumes_to_the_rows_of_an_uninterrupted_one() {
    use std::process::{Command, Stdio};
    let dir = temp_dir("sweep", "resume");
    let file = longer_sweep(&dir, 16);
    let whole = dir.join("whole");
    ok(&oeg(&[
        "sweep",
        "run",
        s(&file),
        "--out",
        s(&whole),
        "--jobs",
        "1",
    ]));
    let total = rows_without_wall_time(&whole).len();
    assert_eq!(total, 64);

    let killed = dir.join("killed");
    let mut child = Command::new(env!("CARGO_BIN_EXE_oeg"))
        .args(["sweep", "run", s(&file), "--out", s(&killed), "--jobs", "1"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn");
    let finished = |d: &Path| -> usize {
        std::fs::read_dir(d.join("runs"))
            .map(|it| {
                it.filter_map(Result::ok)
                    .filter(|e| e.path().join("row.json").is_file())
                    .count()
            })
            .unwrap_or(0)
    };
    let start = std::time::Instant::now();
    while finished(&killed) == 0 && start.elapsed().as_secs() < 120 {
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    child.kill().expect("SIGKILL");
    child.wait().expect("reaped");
    let done = finished(&killed);
    assert!(
        done >= 1 && done < total,
        "killed after {done} of {total} runs: the kill must land half-way"
    );

    let again = ok(&oeg(&[
        "sweep",
        "run",
        s(&file),
        "--out",
        s(&killed),
        "--jobs",
        "1",
    ]));
    assert!(again.contains(&format!("{done} finished before")), "{again}");
    assert_eq!(rows_without_wall_time(&killed), rows_without_wall_time(&whole));
    for name in ["runs.jsonl", "obstacles.csv"] {
        let a = std::fs::read_to_string(whole.join(name)).expect("file");
        let b = std::fs::read_to_string(killed.join(name)).expect("file");
        let strip = |t: &str| -> Vec<String> {
            t.lines()
                .map(|l| l.split("\"wall_time_s\"").next().unwrap_or(l).to_string())
                .collect()
        };
        assert_eq!(strip(&a), strip(&b), "{name}");
    }
    // A third start finds nothing to do.
    let third = ok(&oeg(&["sweep", "run", s(&file), "--out", s(&killed)]));
    assert!(
        third.contains(&format!("{total} finished before, 0 run now")),
        "{third}"
    );
}

#[test]
fn shards_merge_into_the_rows_of_a_whole_run_and_gaps_are_named() {
    let dir = temp_dir("sweep", "shards");
    // The whole plan on one thread; the shards below on every core: the same rows.
    let whole = dir.join("whole");
    ok(&common::oeg_with_threads(
        &["sweep", "run", s(&smoke()), "--out", s(&whole), "--jobs", "1"],
        Some("1"),
    ));
    let shards: Vec<PathBuf> = (1..=3).map(|i| dir.join(format!("shard{i}"))).collect();
    for (i, d) in shards.iter().enumerate() {
        ok(&oeg(&[
            "sweep",
            "run",
            s(&smoke()),
            "--out",
            s(d),
            "--shard",
            &format!("{}/3", i + 1),
        ]));
    }
    let merged = dir.join("merged");
    let mut args = vec!["sweep", "merge"];
    args.extend(shards.iter().map(|p| s(p)));
    args.extend(["--out", s(&merged)]);
    ok(&oeg(&args));
    assert_eq!(rows_without_wall_time(&merged), rows_without_wall_time(&whole));

    // Shard 3 missing: its runs are named. Shard 1 twice: its runs are duplicated.
    let e = err(&oeg(&[
        "sweep",
        "merge",
        s(&shards[0]),
        s(&shards[1]),
        "--out",
        s(&dir.join("m2")),
    ]));
    assert!(e.contains("missing run(s)"), "{e}");
    let missing: Vec<String> = std::fs::read_dir(shards[2].join("runs"))
        .expect("runs")
        .filter_map(Result::ok)
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        !missing.is_empty() && missing.iter().all(|id| e.contains(id.as_str())),
        "{e}"
    );
    let e = err(&oeg(&[
        "sweep",
        "merge",
        s(&shards[0]),
        s(&shards[0]),
        s(&shards[1]),
        s(&shards[2]),
        "--out",
        s(&dir.join("m3")),
    ]));
    assert!(e.contains("duplicated run(s)") && !e.contains("missing"), "{e}");

    // Slurm's array variables choose the shard when --shard is absent.
    let env_shard = dir.join("slurm2");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_oeg"))
        .args(["sweep", "run", s(&smoke()), "--out", s(&env_shard)])
        .env("SLURM_ARRAY_TASK_ID", "11")
        .env("SLURM_ARRAY_TASK_MIN", "10")
        .env("SLURM_ARRAY_TASK_MAX", "12")
        .output()
        .expect("runs");
    assert!(ok(&o).contains("shard 2/3"));
    assert_eq!(
        rows_without_wall_time(&env_shard),
        rows_without_wall_time(&shards[1])
    );
}

#[test]
fn the_report_writes_intervals_and_plots() {
    let dir = temp_dir("sweep", "report");
    ok(&oeg(&["sweep", "run", s(&smoke()), "--out", s(&dir)]));
    let out = ok(&oeg(&["sweep", "report", s(&dir), "--svg"]));
    assert!(out.contains("summary.csv"), "{out}");
    let summary = std::fs::read_to_string(dir.join("summary.csv")).expect("summary");
    let mut r = csv::Reader::from_reader(summary.as_bytes());
    let headers = r.headers().expect("header").clone();
    for h in [
        "axis",
        "value",
        "line",
        "metric",
        "interval",
        "n",
        "mean",
        "std",
        "ci95_low",
        "ci95_high",
    ] {
        assert!(headers.iter().any(|x| x == h), "{h} in {headers:?}");
    }
    let rows: Vec<csv::StringRecord> = r.records().map(|x| x.expect("row")).collect();
    // Every noise level and preset has each metric over its 2 seeds.
    let rmse: Vec<&csv::StringRecord> = rows
        .iter()
        .filter(|x| &x[0] == "sensors.*.noise.range_sigma_m" && &x[3] == "elevation_rmse_m")
        .collect();
    assert_eq!(rmse.len(), 4, "2 noise levels x 2 presets");
    assert!(rmse.iter().all(|x| &x[5] == "2" && &x[4] == "student_t"));
    for name in [
        "unsafe_step_cells_vs_sensors_all_noise_range_sigma_m.png",
        "plan_found_vs_sensors_all_noise_range_sigma_m.png",
        "psychometric_step.png",
    ] {
        let bytes = std::fs::read(dir.join("plots").join(name)).expect(name);
        assert!(bytes.starts_with(b"\x89PNG"), "{name}");
        // With --svg, the plot as SVG beside it: title, axis labels, ticks and legend as vector text.
        let svg = dir.join("plots").join(name.replace(".png", ".svg"));
        assert!(check_svg(&svg) >= 5, "{}", svg.display());
    }
    // The study's page shows every plot and the summary table.
    let page = check_page(&dir.join("report.html"));
    for name in [
        "plots/psychometric_step.png",
        "summary.csv",
        "<td>elevation_rmse_m</td>",
    ] {
        assert!(page.contains(name), "{name} missing from the page");
    }
}

#[test]
fn a_generated_scene_is_a_plain_scenario_that_oeg_run_reproduces() {
    let dir = temp_dir("sweep", "reproduce");
    ok(&oeg(&["sweep", "run", s(&smoke()), "--out", s(&dir)]));
    let plan: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("plan.json")).expect("plan")).expect("json");
    let runs = plan["runs"].as_array().expect("runs");
    for run in [&runs[0], &runs[runs.len() - 1]] {
        let id = run["id"].as_str().expect("id");
        let run_dir = dir.join("runs").join(id);
        let again = dir.join(format!("again-{id}"));
        ok(&oeg(&[
            "run",
            s(&run_dir.join("scenario.toml")),
            "--out",
            s(&again),
        ]));
        for name in ["metrics.json", "obstacles.csv"] {
            assert_eq!(
                std::fs::read(run_dir.join(name)).expect("sweep's"),
                std::fs::read(again.join(name)).expect("run's"),
                "{id} {name}"
            );
        }
    }
}

#[test]
fn bad_sweeps_and_flags_are_clear_errors() {
    let dir = temp_dir("sweep", "bad");
    let base = root().join("sweeps/bases/smoke.toml");
    for (body, expected) in [
        (
            "[[axes]]\nkey = \"map.model.p_maxx\"\nvalues = [0.7]\n",
            "b.toml:5:7: axis `map.model.p_maxx`",
        ),
        (
            "[[axes]]\nkey = \"map.model.p_max\"\nvalues = []\n",
            "b.toml:6:10: axis `map.model.p_max` has no values",
        ),
        (
            "[[axes]]\nkey = \"map.model.p_max\"\nrange = { start = 0.6, stop = 0.9, step = 0.0 }\n",
            "b.toml:6:9: axis `map.model.p_max`: `step = 0`",
        ),
        (
            "[[axes]]\nkey = \"map.model.p_max\"\nvalues = [2.0]\n",
            "b.toml:5:7: axis `map.model.p_max` = 2.0",
        ),
    ] {
        let e = sweep_plan_error(&dir, "b", body);
        assert!(e.contains(expected), "{body}: {e}");
    }
    let generated = format!(
        "name = \"g\"\nseed = 1\n[generate]\nbase = {:?}\ncurbs = {{ count = [1, 2], height_m = [0.05, 0.02] }}\n",
        s(&base)
    );
    let path = dir.join("g.toml");
    std::fs::write(&path, generated).expect("write");
    let e = err(&oeg(&["sweep", "plan", s(&path)]));
    assert!(
        e.contains("g.toml:5:") && e.contains("min 0.05 is above max 0.02"),
        "{e}"
    );
    let e = err(&oeg(&[
        "sweep",
        "plan",
        s(&smoke()),
        "--set",
        "map.model.p_max=2",
    ]));
    assert!(
        e.contains("--set map.model.p_max=2: `map.model`: invalid setting `p_max`"),
        "{e}"
    );
    for shard in ["0/3", "4/3"] {
        let e = err(&oeg(&[
            "sweep",
            "run",
            s(&smoke()),
            "--out",
            s(&dir.join("o")),
            "--shard",
            shard,
        ]));
        assert!(e.contains("--shard") && e.contains("1 <= i <= n"), "{shard}: {e}");
    }
}

#[test]
fn every_shipped_study_plans_and_its_base_validates() {
    let dir = root().join("sweeps");
    let mut studies: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("sweeps/")
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    studies.sort();
    assert!(studies.len() >= 5, "{studies:?}");
    for study in &studies {
        let out = ok(&oeg(&["sweep", "plan", s(study)]));
        // "name: N runs, M simulations", then one line per run.
        let runs: usize = out
            .split_once(": ")
            .and_then(|(_, rest)| rest.split(' ').next())
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("{}: {out}", study.display()));
        assert!(
            runs >= 6 && out.lines().count() == runs + 1,
            "{}: {out}",
            study.display()
        );
    }
    let bases: Vec<PathBuf> = std::fs::read_dir(dir.join("bases"))
        .expect("sweeps/bases/")
        .filter_map(Result::ok)
        .map(|e| e.path())
        .collect();
    let mut args = vec!["validate"];
    args.extend(bases.iter().map(|p| s(p)));
    ok(&oeg(&args));
}
