//! Helpers shared by the simulation tests: scenarios written to a temporary folder.

#![allow(
    clippy::disallowed_methods,
    reason = "tests and tools write their inputs directly"
)]
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use sim::scenario::{self, LoadedScenario};

/// The shipped robot description.
pub(crate) fn urdf_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenarios/robots/pioneer3at.urdf")
        .canonicalize()
        .expect("urdf")
}

/// A fresh temporary folder for one test.
pub(crate) fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("sim-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// A minimal valid scenario over x in [-2, 10], y in [-4, 4] with `extra` TOML appended.
pub(crate) fn scenario_text(extra: &str) -> String {
    scenario_driving(
        4.0,
        "waypoints_xy_m = [[0.0, 0.0], [4.0, 0.0]]\nspeed_m_s = 1.0",
        extra,
    )
}

/// As [`scenario_text`], `duration_s` long, with `drive` as the `[robot.drive]` table's keys.
pub(crate) fn scenario_driving(duration_s: f64, drive: &str, extra: &str) -> String {
    format!(
        r#"name = "test"
seed = 7
duration_s = {duration_s:?}

[map]
min_xy_m = [-2.0, -4.0]
max_xy_m = [10.0, 4.0]
resolution_m = 0.05

[robot]
urdf = "{}"

[robot.drive]
{drive}

{extra}
"#,
        urdf_path().display()
    )
}

/// Writes `text` as `name.toml` in a fresh folder and loads it.
pub(crate) fn load_text(name: &str, text: &str) -> Result<LoadedScenario, sim::SimError> {
    let dir = temp_dir(name);
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).expect("write");
    scenario::load(&path)
}
