//! One entry point per reader, for the fuzzer and for the corpus test: each takes any bytes, and must return
//! (an error is fine) without panicking, hanging or allocating past its bound.
//!
//! The targets read from memory through the same code as the files: the scan graph, the PCD cloud (ascii,
//! binary and binary_compressed), the sensor log, the map file, the scenario TOML, the terrain PNG, the
//! robot's URDF, the sweep file (read, checked and planned against the shipped base scenarios), a sweep
//! run's `row.json`, the maps `oeg score` reads from other tools: a `.npy` array and a nav2 map (its YAML,
//! a NUL byte, then its PGM image), and the new doors of a run: the truth of a scenario (its settings fuzzed:
//! the region, the resolution, the robot's step and grade), a planner's path file, `oeg check-path` on a
//! fixed scene, a ROS 2 bag's MCAP file, and a KITTI scan with its poses and calibration.

use std::path::{Path, PathBuf};

/// A reader under test.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    /// OctoMap scan graphs (`.graph`).
    Graph,
    /// PCL point clouds (`.pcd`), every encoding.
    Pcd,
    /// The testbed's sensor logs (`.oeglog`).
    Log,
    /// Map files (`.oeg`), then the map's layers.
    Map,
    /// Scenario files (`.toml`).
    Scenario,
    /// Terrain heightmaps (`.png`).
    Png,
    /// Robot descriptions (`.urdf`).
    Urdf,
    /// Sweep files (`.toml`), then their plan.
    Sweep,
    /// A sweep run's `row.json`.
    Row,
    /// A `.npy` array, then its values as decisions or floats.
    Npy,
    /// A nav2 map: its YAML text, a NUL byte, its PGM image.
    Nav2,
    /// A scenario file, then its truth when the validated cost is small ([`TRUTH_MAX_SAMPLES`]).
    Truth,
    /// A planner's path file (`path.csv`).
    Path,
    /// A path file checked by `oeg check-path` against `tests/scenes/nav_wall.toml`.
    CheckPath,
    /// A ROS 2 bag's MCAP file (chunks, CDR messages, the transform tree) as scans, and its grid map.
    Bag,
    /// A KITTI scan: its poses' text, a NUL byte, the calibration's text, a NUL byte, the scan's `.bin` bytes.
    Kitti,
}

/// Every target, in the order of the corpus folders.
pub const TARGETS: [Target; 16] = [
    Target::Graph,
    Target::Pcd,
    Target::Log,
    Target::Map,
    Target::Scenario,
    Target::Png,
    Target::Urdf,
    Target::Sweep,
    Target::Row,
    Target::Npy,
    Target::Nav2,
    Target::Truth,
    Target::Path,
    Target::CheckPath,
    Target::Bag,
    Target::Kitti,
];

/// The most sample points the truth target computes (a larger valid truth is bounded by validation,
/// `sim::scenario::MAX_TRUTH_SAMPLES`, and takes longer than the fuzzer's time limit: not a hang).
pub const TRUTH_MAX_SAMPLES: u64 = 1 << 18;

/// The most poses the check-path target checks (`oeg check-path` allows
/// `oeg_eval::jobs::check_path::MAX_CHECKED_POSES`, which take longer than the fuzzer's time limit).
pub const CHECK_PATH_MAX_POSES: u64 = 20_000;

/// The extent the path target reads points in: min x, max x, min y, max y, metres.
pub const PATH_EXTENT: [f64; 4] = [-1.0, 10.0, -5.0, 5.0];

/// The most runs the sweep target plans: a larger plan loads every run's scenario, which takes longer than
/// the fuzzer's time limit (it is bounded by `oeg_eval::jobs::sweep::spec::MAX_RUNS`, not a hang).
pub const SWEEP_MAX_PLANNED_RUNS: usize = 64;

/// The most cells the nav2 target reads: small, so the fuzzer finds reads that ignore it.
pub const NAV2_MAX_CELLS: u64 = 1 << 20;

/// The memory bound the map target loads under: small, so the fuzzer finds allocations that ignore it.
pub const MAP_LIMIT_BYTES: u64 = 256 << 20;

impl Target {
    /// The target's name: its corpus folder and its argument to the fuzz binary.
    pub fn name(self) -> &'static str {
        match self {
            Self::Graph => "graph",
            Self::Pcd => "pcd",
            Self::Log => "log",
            Self::Map => "map",
            Self::Scenario => "scenario",
            Self::Png => "png",
            Self::Urdf => "urdf",
            Self::Sweep => "sweep",
            Self::Row => "row",
            Self::Npy => "npy",
            Self::Nav2 => "nav2",
            Self::Truth => "truth",
            Self::Path => "path",
            Self::CheckPath => "check_path",
            Self::Bag => "bag",
            Self::Kitti => "kitti",
        }
    }

    /// The target named `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        TARGETS.into_iter().find(|t| t.name() == name)
    }
}

/// The folder of the committed corpus.
pub fn corpus_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("corpus")
}

/// Feeds `data` to `target`'s reader. Returns whether the reader accepted it (for the corpus statistics).
pub fn run(target: Target, data: &[u8]) -> bool {
    let path = Path::new("fuzz-input");
    match target {
        Target::Graph => oeg::parse_graph(path, data).is_ok(),
        Target::Pcd => oeg::parse_pcd(path, data).is_ok(),
        Target::Log => sim::log::parse_log(path, data).is_ok(),
        Target::Map => match oeg::map_from_bytes(path, data, MAP_LIMIT_BYTES) {
            Ok(map) => {
                // A loaded map must be usable: its layers and decisions over what it observed.
                if let Some(region) = map.observed_region() {
                    let _ = map.layer(oeg::LayerKind::ElevationM, region);
                    let _ = map.traversability_layer(
                        region,
                        &oeg::RobotProfile::default(),
                        oeg::TraversabilityRule::default(),
                    );
                }
                true
            }
            Err(_) => false,
        },
        Target::Scenario => std::str::from_utf8(data).is_ok_and(|text| {
            // Beside the shipped scenarios, so `robots/pioneer3at.urdf` resolves as it does for them.
            let at = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/fuzz-input.toml");
            sim::scenario::load_str(&at, text).is_ok()
        }),
        Target::Png => sim::scenario::heightmap::decode_greyscale_png(path, data).is_ok(),
        Target::Urdf => std::str::from_utf8(data)
            .is_ok_and(|text| sim::robot::RobotModel::from_urdf_text(path, text, "base_link").is_ok()),
        Target::Sweep => std::str::from_utf8(data).is_ok_and(|text| {
            // Beside the shipped sweeps, so `bases/smoke.toml` resolves as it does for them.
            let at = Path::new(env!("CARGO_MANIFEST_DIR")).join("../sweeps/fuzz-input.toml");
            match oeg_eval::jobs::sweep::Sweep::from_str(&at, text) {
                Ok(sweep) if sweep.num_planned_runs() <= SWEEP_MAX_PLANNED_RUNS as u128 => {
                    oeg_eval::jobs::sweep::SweepPlan::new(sweep).is_ok()
                }
                Ok(_) => true,
                Err(_) => false,
            }
        }),
        Target::Row => serde_json::from_slice(data)
            .is_ok_and(|json| oeg_eval::jobs::sweep::rows::parse_record(&json, "0123456789abcdef").is_ok()),
        Target::Npy => match oeg::NpyArray::from_bytes(path, data) {
            Ok(a) => {
                // As `oeg score` reads it: integer codes as decisions, anything as floats.
                if let Some(codes) = a.data.to_i64() {
                    let _ = oeg_eval::judge::estimate::decisions_from_codes(&codes);
                }
                a.data.to_f64().len() == a.rows * a.cols
            }
            Err(_) => false,
        },
        Target::Nav2 => {
            let (yaml, image) = data.split_at(data.iter().position(|b| *b == 0).unwrap_or(data.len()));
            let image = image.get(1..).unwrap_or_default();
            std::str::from_utf8(yaml)
                .is_ok_and(|yaml| oeg::parse_nav2_map(yaml, image, NAV2_MAX_CELLS).is_ok())
        }
        Target::Truth => std::str::from_utf8(data).is_ok_and(truth_of_text),
        Target::Path => oeg_eval::navigation::external::parse_path(path, data, PATH_EXTENT).is_ok(),
        Target::CheckPath => check_path(path, data),
        Target::Kitti => {
            let mut parts = data.splitn(3, |b| *b == 0);
            let (poses, calib, bin) = (parts.next(), parts.next(), parts.next());
            let text = |p: Option<&[u8]>| String::from_utf8_lossy(p.unwrap_or_default()).into_owned();
            let sensor = oeg::SensorModel::laser();
            (0..2).any(|index| {
                oeg::parse_kitti_scan(
                    path,
                    &text(poses),
                    &text(calib),
                    index,
                    bin.unwrap_or_default(),
                    sensor,
                )
                .is_ok()
            })
        }
        // As `oeg map` reads it, and with `/odom`'s odometry in the transform tree (refused without that topic);
        // and its grid map as `oeg score --grid-map` reads it.
        Target::Bag => {
            oeg::parse_grid_map(path, data, "/elevation_map", None, MAP_LIMIT_BYTES).is_ok()
                | [Vec::new(), vec!["/odom".to_string()]]
                    .into_iter()
                    .map(|odometry_topics| {
                        let options = oeg::BagOptions {
                            odometry_topics,
                            tf_tolerance_s: 0.5,
                            ..oeg::BagOptions::default()
                        };
                        oeg::parse_bag(path, data, &options, MAP_LIMIT_BYTES).is_ok()
                    })
                    .fold(false, |a, b| a | b)
        }
    }
}

/// Loads a scenario's text as the scenario target does; when it validates and its truth is small, builds its
/// world and computes the truth, which must cover the map's region.
fn truth_of_text(text: &str) -> bool {
    let at = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/fuzz-input.toml");
    let Ok(loaded) = sim::scenario::load_str(&at, text) else {
        return false;
    };
    let s = &loaded.scenario;
    let region = *loaded.window.region();
    let cost = sim::truth::TruthCost::estimate(
        u64::from(region.num_x),
        u64::from(region.num_y),
        loaded.window.resolution_m(),
        sim::truth::DEFAULT_SAMPLES_PER_SIDE,
        f64::from(s.robot.profile().contact_distance_m()),
    );
    if cost.samples > TRUTH_MAX_SAMPLES || s.obstacles.len() > 64 {
        return true;
    }
    let Ok(world) = sim::World::new(&loaded) else {
        return true;
    };
    let progress = oeg_eval::progress::Progress::hidden();
    let truth = oeg_eval::pipeline::truth_of(&loaded, &world, &progress).expect("never cancelled");
    assert_eq!(
        truth.cells.len() as u64,
        region.num_cells(),
        "the truth covers the region"
    );
    true
}

/// The scene, its truth and robot the check-path target checks paths against, built once.
struct CheckPathScene {
    loaded: sim::scenario::LoadedScenario,
    truth: sim::truth::TruthRaster,
}

fn check_path(path: &Path, data: &[u8]) -> bool {
    static SCENE: std::sync::OnceLock<CheckPathScene> = std::sync::OnceLock::new();
    let scene = SCENE.get_or_init(|| {
        let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/scenes/nav_wall.toml");
        let loaded = sim::scenario::load(&file).expect("the shipped scene");
        let world = sim::World::new(&loaded).expect("its world");
        let progress = oeg_eval::progress::Progress::hidden();
        let truth = oeg_eval::pipeline::truth_of(&loaded, &world, &progress).expect("its truth");
        CheckPathScene { loaded, truth }
    });
    let res = scene.truth.window.resolution_m();
    let extent = oeg_eval::navigation::external::extent_of(&scene.truth.window);
    let Ok(points) = oeg_eval::navigation::external::parse_path(path, data, extent) else {
        return false;
    };
    if oeg_eval::jobs::check_path::count_poses(&points, res / 2.0) > CHECK_PATH_MAX_POSES {
        return true;
    }
    let judge = oeg_eval::jobs::check_path::PathJudge {
        scenario: &scene.loaded.scenario,
        truth: &scene.truth,
        footprint: scene.loaded.robot.footprint(),
    };
    let check = judge.check(path, &points, None).expect("within the pose bound");
    assert_eq!(check.num_points, points.len() as u64);
    true
}
