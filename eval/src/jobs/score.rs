//! `oeg score`: a map made by another tool (elevation_mapping, grid_map, a network) judged against a
//! scenario's truth as `oeg run` judges its own: its arrays as `.npy` files, or its decisions as a nav2 map,
//! resampled onto the truth's grid ([`crate::judge::estimate`]), then the verdict counts, the per-obstacle
//! table and the planner check ([`crate::scoring`], `docs/scoring.md`).

use std::path::{Path, PathBuf};

use oeg::NpyArray;

use crate::error::{EvalError, Result};
use crate::judge::Evaluation;
use crate::judge::estimate::{ForeignMap, MAX_FOREIGN_CELLS, decisions_from_codes};
use crate::output::{Staged, write_json};
use crate::progress::Progress;
use crate::scoring::ScoringTruth;

/// Where the map's grid and decisions come from.
#[derive(Debug, Clone, PartialEq)]
pub enum GridSource {
    /// A `layers.json` sidecar (as `oeg map --planner-files` writes it): the origin, the resolution and the
    /// files of the layers it names.
    Layers(PathBuf),
    /// A nav2 map's YAML file: the origin, the resolution and the decisions of its image.
    Nav2(PathBuf),
    /// A `grid_map_msgs/GridMap` in a ROS 2 bag (elevation_mapping's, grid_map's): its geometry, its
    /// `elevation` and `variance` layers, and the decisions of its `traversability` layer or, without one, of
    /// the terrain step rule ([`grid_map_foreign`]).
    GridMap {
        /// The bag (its `.mcap` file or its folder).
        bag: PathBuf,
        /// The topic.
        topic: String,
        /// Seconds after the bag's first message: the last map at or before it (none: the last map).
        at_s: Option<f64>,
    },
    /// The decisions as a `.npy` file, on a grid given by hand.
    Grid {
        /// The decision codes (`docs/planner-protocol.md`).
        decisions: PathBuf,
        /// World x and y of the lower-left corner of cell `[0, 0]`, metres.
        origin_xy_m: [f64; 2],
        /// Cell size, metres.
        resolution_m: f64,
    },
}

/// `oeg score`.
#[derive(Debug, Clone)]
pub struct ScoreJob {
    /// The scenario whose truth judges the map.
    pub scenario: PathBuf,
    /// `--set` overrides of the scenario.
    pub overrides: Vec<String>,
    /// Replaces the scenario's seed.
    pub seed: Option<u64>,
    /// The grid and the decisions.
    pub grid: GridSource,
    /// Elevation `.npy` (metres), over or instead of the sidecar's.
    pub elevation: Option<PathBuf>,
    /// Variance `.npy` (m^2), over or instead of the sidecar's.
    pub variance: Option<PathBuf>,
    /// Occupancy probability `.npy`, over or instead of the sidecar's.
    pub occupancy: Option<PathBuf>,
    /// Simulate the scenario's sensors to know what they could see (the blind counts).
    pub observability: bool,
    /// Output folder.
    pub out_dir: PathBuf,
}

/// The bytes a `.npy` of [`MAX_FOREIGN_CELLS`] 8-byte elements may take, with its header.
const MAX_NPY_BYTES: u64 = MAX_FOREIGN_CELLS * 8 + (1 << 16);

/// Reads a 2D `.npy` file.
fn read_npy(path: &Path) -> Result<NpyArray> {
    let bytes = oeg_files::read_bounded(path, MAX_NPY_BYTES)?;
    Ok(NpyArray::from_bytes(path, &bytes)?)
}

/// A float layer of `rows` x `cols` from a `.npy` file.
fn read_layer(path: &Path, rows: usize, cols: usize) -> Result<Vec<f64>> {
    let a = read_npy(path)?;
    if (a.rows, a.cols) != (rows, cols) {
        return Err(EvalError::Input {
            path: path.to_path_buf(),
            message: format!(
                "a ({}, {}) array, expected the decisions' shape ({rows}, {cols})",
                a.rows, a.cols
            ),
        });
    }
    Ok(a.data.to_f64())
}

/// The decisions of a `.npy` of integer codes, with its shape.
fn read_decisions(path: &Path) -> Result<(usize, usize, Vec<oeg::Traversability>)> {
    let a = read_npy(path)?;
    let fail = |message: String| EvalError::Input {
        path: path.to_path_buf(),
        message,
    };
    let codes = a.data.to_i64().ok_or_else(|| {
        fail("the decisions are floats, expected integer codes (0 unknown, 1 free, 2 traversable, 3 blocked, 4 uncertain)".into())
    })?;
    let decisions = decisions_from_codes(&codes).map_err(fail)?;
    Ok((a.rows, a.cols, decisions))
}

/// What a `layers.json` sidecar says: the grid, and the files of the layers it names (relative to it).
struct Sidecar {
    origin_xy_m: [f64; 2],
    resolution_m: f64,
    files: Vec<(String, PathBuf)>,
}

/// The layers a sidecar may name, with the type `oeg map --planner-files` writes them in.
const SIDECAR_LAYERS: [(&str, &str); 4] = [
    ("decisions", "uint8"),
    ("elevation_m", "float32"),
    ("variance_m2", "float32"),
    ("occupancy_probability", "float32"),
];

/// Reads a `layers.json` sidecar, strictly: only the layers [`SIDECAR_LAYERS`] names, each file of the shape
/// and type the sidecar declares (where it declares them).
fn read_sidecar(path: &Path) -> Result<Sidecar> {
    let fail = |message: String| EvalError::Input {
        path: path.to_path_buf(),
        message,
    };
    let json: serde_json::Value = serde_json::from_str(&oeg_files::read_text(path)?)
        .map_err(|e| fail(format!("line {}: {e}", e.line())))?;
    let number = |v: &serde_json::Value, what: &str| {
        v.as_f64()
            .filter(|x| x.is_finite())
            .ok_or_else(|| fail(format!("`{what}` is {v}, expected a number")))
    };
    let origin = json["origin_xy_m"]
        .as_array()
        .filter(|a| a.len() == 2)
        .ok_or_else(|| fail("expected `origin_xy_m`: [x, y] in metres".into()))?;
    let origin_xy_m = [
        number(&origin[0], "origin_xy_m[0]")?,
        number(&origin[1], "origin_xy_m[1]")?,
    ];
    let resolution_m = number(&json["resolution_m"], "resolution_m")?;
    let shape = match &json["shape"] {
        serde_json::Value::Null => None,
        v => Some(
            v.as_array()
                .and_then(|a| match a[..] {
                    [ref r, ref c] => Some((r.as_u64()? as usize, c.as_u64()? as usize)),
                    _ => None,
                })
                .ok_or_else(|| fail(format!("`shape` is {v}, expected [rows, columns]")))?,
        ),
    };
    let layers = json["layers"]
        .as_object()
        .ok_or_else(|| fail("expected `layers`: an object of {\"file\": ...} by layer name".into()))?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut files = Vec::new();
    for (name, entry) in layers {
        let Some((_, dtype)) = SIDECAR_LAYERS.iter().find(|(n, _)| n == name) else {
            let known: Vec<&str> = SIDECAR_LAYERS.iter().map(|(n, _)| *n).collect();
            return Err(fail(format!(
                "`layers` names {name:?}, which is not a layer oeg score reads; expected {}",
                known.join(", ")
            )));
        };
        let file = entry["file"]
            .as_str()
            .ok_or_else(|| fail(format!("layer `{name}` has no \"file\"")))?;
        let file = dir.join(file);
        let declared = entry["dtype"].as_str();
        if let Some(declared) = declared
            && declared != *dtype
        {
            return Err(fail(format!(
                "layer `{name}` is declared {declared:?}, expected {dtype:?}"
            )));
        }
        if shape.is_some() || declared.is_some() {
            let a = read_npy(&file)?;
            if let Some((rows, cols)) = shape
                && (a.rows, a.cols) != (rows, cols)
            {
                return Err(fail(format!(
                    "layer `{name}`: {} holds a ({}, {}) array, the sidecar's `shape` is [{rows}, {cols}]",
                    file.display(),
                    a.rows,
                    a.cols
                )));
            }
            if declared.is_some() && a.data.dtype() != *dtype {
                return Err(fail(format!(
                    "layer `{name}`: {} holds {}, the sidecar declares {dtype}",
                    file.display(),
                    a.data.dtype()
                )));
            }
        }
        files.push((name.clone(), file));
    }
    Ok(Sidecar {
        origin_xy_m,
        resolution_m,
        files,
    })
}

/// A map read for scoring, and every file it was read from.
pub struct ForeignRead {
    /// The arrays, checked.
    pub map: ForeignMap,
    /// The files read: the sidecar, nav2 YAML or decisions, and each layer's file.
    pub files: Vec<PathBuf>,
}

/// Reads the map the job names, as arrays, checked ([`ForeignMap::check`]).
///
/// # Errors
/// A file that cannot be read or is malformed, arrays of different shapes, bad values; each names its file.
pub fn read_foreign(job: &ScoreJob, profile: &oeg::RobotProfile) -> Result<ForeignRead> {
    if let GridSource::GridMap { bag, topic, at_s } = &job.grid {
        let grid = oeg::read_grid_map(bag, topic, *at_s, MAX_NPY_BYTES.saturating_mul(8))?;
        let map = grid_map_foreign(&grid, profile).map_err(|message| EvalError::Input {
            path: bag.clone(),
            message: format!("topic {topic}: {message}"),
        })?;
        map.check(bag, [None; 3])?;
        return Ok(ForeignRead {
            map,
            files: vec![bag.clone()],
        });
    }
    let mut layers: Vec<(String, PathBuf)> = Vec::new();
    let mut inputs = Vec::new();
    let (source, origin_xy_m, resolution_m, (rows, cols, decisions)) = match &job.grid {
        GridSource::Layers(path) => {
            let sidecar = read_sidecar(path)?;
            let decisions = sidecar
                .files
                .iter()
                .find(|(n, _)| n == "decisions")
                .map(|(_, f)| f.clone())
                .ok_or_else(|| EvalError::Input {
                    path: path.clone(),
                    message: "the sidecar names no `decisions` layer".into(),
                })?;
            layers = sidecar.files.clone();
            inputs.extend(layers.iter().map(|(_, f)| f.clone()));
            (
                path.clone(),
                sidecar.origin_xy_m,
                sidecar.resolution_m,
                read_decisions(&decisions)?,
            )
        }
        GridSource::Nav2(path) => {
            let m = oeg::read_nav2_map(path, MAX_FOREIGN_CELLS)?;
            inputs.push(m.image.clone());
            (
                path.clone(),
                m.origin_xy_m,
                m.resolution_m,
                (m.rows, m.cols, m.decisions),
            )
        }
        GridSource::Grid {
            decisions,
            origin_xy_m,
            resolution_m,
        } => (
            decisions.clone(),
            *origin_xy_m,
            *resolution_m,
            read_decisions(decisions)?,
        ),
        GridSource::GridMap { .. } => unreachable!("read above"),
    };
    inputs.insert(0, source.clone());
    let file = |name: &str, flag: &Option<PathBuf>| {
        flag.clone()
            .or_else(|| layers.iter().find(|(n, _)| n == name).map(|(_, f)| f.clone()))
    };
    let files = [
        file("elevation_m", &job.elevation),
        file("variance_m2", &job.variance),
        file("occupancy_probability", &job.occupancy),
    ];
    let layer = |f: &Option<PathBuf>| -> Result<Option<Vec<f64>>> {
        f.as_ref().map(|f| read_layer(f, rows, cols)).transpose()
    };
    let map = ForeignMap {
        origin_xy_m,
        resolution_m,
        rows,
        cols,
        decisions,
        elevation_m: layer(&files[0])?,
        variance_m2: layer(&files[1])?,
        occupancy: layer(&files[2])?,
    };
    map.check(&source, [0, 1, 2].map(|k| files[k].as_deref()))?;
    inputs.extend(files.into_iter().flatten());
    Ok(ForeignRead { map, files: inputs })
}

/// What `oeg score` did.
#[derive(Debug)]
pub struct ScoreReport {
    /// The judgement, as `oeg run`'s.
    pub evaluation: Evaluation,
    /// The files written.
    pub files: Vec<PathBuf>,
    /// Whether the blind counts are known (the scenario's sensors were simulated).
    pub observability: bool,
}

/// Scores the map and writes `score.json` (the keys of `metrics.json`), `obstacles.csv`, `plan.csv` and
/// `wrong_cells.csv` into the output folder.
///
/// # Errors
/// A bad scenario or override, a map file that cannot be read or is malformed, a failed write.
pub fn run_job(job: &ScoreJob, progress: &Progress) -> Result<ScoreReport> {
    let loaded = crate::pipeline::load(&crate::pipeline::RunOptions {
        scenario: job.scenario.clone(),
        overrides: job.overrides.clone(),
        seed: job.seed,
        ..Default::default()
    })?;
    // The inputs are read, and the output folder claimed, before the simulation.
    let ForeignRead {
        map: foreign,
        files: mut inputs,
    } = read_foreign(job, &loaded.scenario.robot.profile())?;
    inputs.extend(loaded.files());
    let inputs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
    let staged = Staged::begin(&job.out_dir, &inputs)?;
    let truth = ScoringTruth::of(&loaded, job.observability, progress)?;
    let evaluation = truth.score(&foreign)?;
    let dir = staged.dir();
    let work = || -> Result<_> {
        let mut files = crate::report::write_tables(dir, &truth.raster, &evaluation)?;
        let json = dir.join("score.json");
        write_json(&json, &evaluation.metrics)?;
        files.push(json);
        Ok(files)
    };
    let files = staged.explained(work())?;
    let files = files.iter().map(|f| staged.final_path(f)).collect();
    staged.commit()?;
    Ok(ScoreReport {
        evaluation,
        files,
        observability: truth.observability.is_some(),
    })
}

/// The value of a grid_map's `traversability` layer (elevation_mapping's convention: 1 fully traversable, 0
/// not) at and above which a cell is drivable.
pub const GRID_MAP_TRAVERSABLE_AT: f32 = 0.5;

/// A grid_map's layers as another mapper's arrays: `elevation` (metres) and `variance` (m^2) as they are, and
/// each cell's decision: unknown without an elevation; else, where a `traversability` layer has a value,
/// traversable at [`GRID_MAP_TRAVERSABLE_AT`] or above and blocked below; else by the terrain step rule (the
/// paper's: the cell's rise over the lowest elevation of its 3 x 3 neighbourhood against the robot's step,
/// [`oeg::step_decision`]). A grid map has no occupancy.
///
/// # Errors
/// No `elevation` layer, in words.
pub fn grid_map_foreign(
    grid: &oeg::GridMapLayers,
    profile: &oeg::RobotProfile,
) -> std::result::Result<ForeignMap, String> {
    let layer = |name: &str| grid.layers.iter().find(|(n, _)| n == name).map(|(_, v)| v);
    let Some(elevation) = layer("elevation") else {
        let names: Vec<&str> = grid.layers.iter().map(|(n, _)| n.as_str()).collect();
        return Err(format!("no `elevation` layer (it has {})", names.join(", ")));
    };
    let traversability = layer("traversability");
    let (rows, cols) = (grid.rows, grid.cols);
    let at = |r: usize, c: usize| elevation[r * cols + c];
    let decisions = (0..rows * cols)
        .map(|k| {
            let (r, c) = (k / cols, k % cols);
            let e = at(r, c);
            if !e.is_finite() {
                return oeg::Traversability::Unknown;
            }
            if let Some(t) = traversability.map(|t| t[k]).filter(|t| t.is_finite()) {
                return if t >= GRID_MAP_TRAVERSABLE_AT {
                    oeg::Traversability::Traversable
                } else {
                    oeg::Traversability::Blocked
                };
            }
            let mut ground = e;
            for nr in r.saturating_sub(1)..(r + 2).min(rows) {
                for nc in c.saturating_sub(1)..(c + 2).min(cols) {
                    let n = at(nr, nc);
                    if n.is_finite() {
                        ground = ground.min(n);
                    }
                }
            }
            oeg::step_decision(e - ground, 0.0, oeg::TraversabilityRule::Terrain, profile)
        })
        .collect();
    let widen = |v: &Vec<f32>| v.iter().map(|&x| f64::from(x)).collect::<Vec<f64>>();
    Ok(ForeignMap {
        origin_xy_m: grid.origin_xy_m,
        resolution_m: grid.resolution_m,
        rows,
        cols,
        decisions,
        elevation_m: Some(widen(elevation)),
        variance_m2: layer("variance").map(widen),
        occupancy: None,
    })
}
