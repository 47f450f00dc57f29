//! Helpers shared by the tests that drive the built `oeg` binary.

#![allow(dead_code)]

use std::path::PathBuf;
use std::process::{Command, Output};

/// Runs `oeg` with `args`.
pub fn oeg(args: &[&str]) -> Output {
    oeg_with_threads(args, None)
}

/// Runs `oeg` with `args`, with `RAYON_NUM_THREADS` set when `threads` is given.
pub fn oeg_with_threads(args: &[&str], threads: Option<&str>) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_oeg"));
    c.args(args);
    if let Some(t) = threads {
        c.env("RAYON_NUM_THREADS", t);
    }
    c.output().expect("the oeg binary runs")
}

/// A fresh, empty temporary folder for one test (`group` keeps test files apart).
pub fn temp_dir(group: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("oeg-{group}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// The repository root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}
