//! The memory bound is real: under an address-space limit (`ulimit -v`) 10 % above the default map bound
//! (plus what the program needs before it maps anything), `oeg map` on an input that needs more than the bound
//! fails with the memory-limit error and never aborts.

mod common;

use common::temp_dir;
use std::process::Command;

use nalgebra::Point3;
use oeg::{Scan, SensorModel};

/// The address space the program takes before it maps anything (the binary, thread stacks, allocator
/// arenas), measured as the smallest `ulimit -v` under which it maps a tiny input, in KiB.
/// `None` when even 4 GiB is not enough (a shell without `ulimit -v`).
fn baseline_kib(input: &std::path::Path, out: &std::path::Path) -> Option<u64> {
    let ok = |kib: u64| {
        let _ = std::fs::remove_dir_all(out);
        map_under_ulimit(kib, input, out).status.success()
    };
    let (mut lo, mut hi) = (16 * 1024, 4 * 1024 * 1024);
    if !ok(hi) {
        return None;
    }
    while hi - lo > 8 * 1024 {
        let mid = (lo + hi) / 2;
        if ok(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Some(hi)
}

/// `oeg map INPUT --resolution 0.05 --out OUT` under `ulimit -v LIMIT_KIB`.
fn map_under_ulimit(limit_kib: u64, input: &std::path::Path, out: &std::path::Path) -> std::process::Output {
    Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v {limit_kib} && exec \"$0\" map \"$1\" --resolution 0.05 --out \"$2\""
        ))
        .args([
            env!("CARGO_BIN_EXE_oeg"),
            input.to_str().expect("utf8"),
            out.to_str().expect("utf8"),
        ])
        .output()
        .expect("sh runs")
}

#[test]
fn the_default_memory_bound_holds_under_ulimit_and_the_program_never_aborts() {
    let dir = temp_dir("memory", "ulimit");
    // A tiny input, for the baseline.
    let tiny = dir.join("tiny.graph");
    let mut scan = Scan::new(Point3::new(0.0, 0.0, 0.5), SensorModel::laser());
    scan.push_hit(Point3::new(2.0, 0.0, 0.0));
    oeg::write_graph(&tiny, &[scan]).expect("graph");
    let Some(base) = baseline_kib(&tiny, &dir.join("tiny_out")) else {
        println!("skipped: `oeg map` does not run under `sh -c 'ulimit -v 4194304'` here");
        return;
    };
    // 60 rays of 12 km in a fan: together they need more than the 4 GiB bound, each alone far less.
    let spread = dir.join("spread.graph");
    let scans: Vec<Scan> = (0..60)
        .map(|k| {
            let mut scan = Scan::new(Point3::new(0.0, 0.0, 0.5), SensorModel::laser());
            let a = f64::from(k) * 0.1;
            scan.push_hit(Point3::new(12_000.0 * a.cos(), 12_000.0 * a.sin(), 0.0));
            scan
        })
        .collect();
    oeg::write_graph(&spread, &scans).expect("graph");
    let bound_kib = oeg::DEFAULT_MEMORY_LIMIT_BYTES / 1024;
    let limit_kib = base + bound_kib + bound_kib / 10;
    let out = dir.join("out");
    let o = map_under_ulimit(limit_kib, &spread, &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    println!("baseline {base} KiB, limit {limit_kib} KiB: {stderr}");
    assert_eq!(o.status.code(), Some(1), "an error, not an abort: {stderr}");
    assert!(
        stderr.contains("memory limit") && stderr.contains("spread.graph"),
        "{stderr}"
    );
    assert!(
        !stderr.contains("memory allocation") && !stderr.contains("panicked"),
        "{stderr}"
    );
    assert!(!out.exists());

    // One corrupt far point: refused before anything is allocated, in well under a second of work. 400 km at
    // 0.05 m crosses 125,000 tiles: 10 GB of scratch at 20 bytes a cell, over the 4 GiB bound.
    let far = dir.join("far.graph");
    let mut scan = Scan::new(Point3::new(0.0, 0.0, 0.5), SensorModel::laser());
    scan.push_hit(Point3::new(400_000.0, 0.0, 0.0));
    oeg::write_graph(&far, &[scan]).expect("graph");
    let started = std::time::Instant::now();
    let o = map_under_ulimit(limit_kib, &far, &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("far.graph: node 0 (id 0)") && stderr.contains("memory limit"),
        "{stderr}"
    );
    assert!(started.elapsed().as_secs_f64() < 5.0, "{:?}", started.elapsed());
}
