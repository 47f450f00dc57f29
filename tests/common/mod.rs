//! Helpers shared by the tests that drive the built `oeg` binary.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
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

/// A path as a command-line argument.
pub fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// The standard output of a command that succeeded; a failure panics with both outputs.
pub fn ok(o: &Output) -> String {
    assert!(
        o.status.success(),
        "oeg failed: {}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The error of a command that failed with an error, not a panic (a panic exits with 101).
pub fn err(o: &Output) -> String {
    let e = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(
        !o.status.success(),
        "expected a failure: {}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert_ne!(o.status.code(), Some(101), "expected an error, not a panic: {e}");
    assert!(!e.contains("panicked"), "{e}");
    e
}

/// The error of `oeg sweep plan` on the sweep file `dir/NAME.toml`: `name = "NAME"`, `seed = 1`, the shipped
/// smoke base as its one scenario (lines 1 to 3), then `body` from line 4.
#[expect(clippy::disallowed_methods, reason = "a test writes its input directly")]
pub fn sweep_plan_error(dir: &Path, name: &str, body: &str) -> String {
    let base = root().join("sweeps/bases/smoke.toml");
    let path = dir.join(format!("{name}.toml"));
    let head = format!("name = \"{name}\"\nseed = 1\nscenarios = [{:?}]\n", s(&base));
    std::fs::write(&path, format!("{head}{body}")).expect("write");
    err(&oeg(&["sweep", "plan", s(&path)]))
}
