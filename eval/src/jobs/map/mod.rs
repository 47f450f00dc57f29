//! `oeg map`: build a map from recorded range data (OctoMap scan graphs, PCD files, sensor logs, ROS 2 bags) and
//! write the map, its layer images, `summary.json` and `timing.json`.

pub mod demo;
mod inputs;

pub use inputs::{InputFormat, Inputs, ScanSource, read_inputs};

use std::path::{Path, PathBuf};
use std::time::Instant;

use oeg::{Map, MapConfig, RobotProfile, Scan, SensorModel, TraversabilityRule};
use serde::Serialize;

use crate::error::{EvalError, Result};
use crate::figures::write_layer_images;
use crate::output::{Staged, write_bytes, write_json};
use crate::progress::Progress;

/// Everything `oeg map` needs.
#[derive(Debug, Clone)]
pub struct MapJob {
    /// The input files.
    pub inputs: Vec<PathBuf>,
    /// Where the outputs go (created if needed).
    pub out_dir: PathBuf,
    /// The map's resolution and model.
    pub config: MapConfig,
    /// The sensor model of scan-graph scans.
    pub graph_sensor: SensorModel,
    /// How PCD files become scans (includes their sensor model).
    pub pcd: oeg::PcdOptions,
    /// How ROS 2 bags become scans.
    pub bag: oeg::BagOptions,
    /// Which pose sensor-log scans are placed with.
    pub log_pose: sim::sensors::PoseSource,
    /// The robot for the traversability layer.
    pub profile: RobotProfile,
    /// The traversability rule.
    pub rule: TraversabilityRule,
    /// Copy the input files into the output folder beside the map (the demo keeps its scans there).
    pub keep_inputs: bool,
    /// Write the files a planner reads (`planner/`: a nav2 map and `.npy` layers) over the observed region.
    /// Their size follows the region's extent, not what the map holds.
    pub planner_files: bool,
    /// The files each image is written as (`--svg` adds an SVG beside each PNG).
    pub figures: crate::figures::ImageFormats,
}

/// `summary.json`: one flat object, snake_case keys with units in their names. Deterministic for the same
/// inputs and settings.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MapSummary {
    /// Number of input files.
    pub num_inputs: u64,
    /// Scans integrated.
    pub num_scans: u64,
    /// Rays integrated (hits and no-returns).
    pub num_rays: u64,
    /// Range messages of ROS 2 bags not mapped: no transform to the map frame at their stamp, or no valid
    /// reading (the reasons are printed and in the report).
    pub num_messages_skipped: u64,
    /// Cell visits by rays.
    pub num_cell_visits: u64,
    /// Cell size.
    pub resolution_m: f64,
    /// Eq. 12's free-space rule.
    pub free_space_elevation: oeg::FreeSpaceElevation,
    /// Height threshold, if any.
    pub max_height_m: Option<f32>,
    /// Scans that say where the ground under the robot was (a sensor log that records it, a bag whose
    /// transforms hold `input.bag.ground_frame`): the height threshold measures from it; the others' from z = 0.
    pub num_scans_with_ground: u64,
    /// Cells observed at least once.
    pub num_cells_observed: u64,
    /// Observed cells with `P > occupied_threshold`.
    pub num_cells_occupied: u64,
    /// Observed, not occupied.
    pub num_cells_free: u64,
    /// Occupied and low enough for the robot.
    pub num_cells_traversable: u64,
    /// Occupied and too high (or of unknown height).
    pub num_cells_blocked: u64,
    /// The robot's step limit used for the classes.
    pub max_step_m: f32,
    /// Bytes the map holds ([`Map::memory_bytes`]): its cells, without the per-scan scratch (in `timing.json`).
    pub map_bytes: u64,
    /// Bytes of the saved map file.
    pub map_file_bytes: u64,
    /// Observed extent: min x.
    pub extent_min_x_m: Option<f64>,
    /// Observed extent: min y.
    pub extent_min_y_m: Option<f64>,
    /// Observed extent: max x.
    pub extent_max_x_m: Option<f64>,
    /// Observed extent: max y.
    pub extent_max_y_m: Option<f64>,
}

/// `timing.json`: wall times, kept apart from the summary because they vary from run to run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MapTiming {
    /// Reading and decoding the inputs.
    pub read_wall_time_s: f64,
    /// Integrating every scan (the map-building time).
    pub integrate_wall_time_s: f64,
    /// Rays integrated per second of integration.
    pub integrate_rays_per_s: f64,
    /// Cell visits per second of integration.
    pub integrate_cell_visits_per_s: f64,
    /// Threads integration may use (`RAYON_NUM_THREADS`, or every core): a long scan's rays are gathered in
    /// parallel, and the touched tiles updated in parallel. The map is the same on any number.
    pub integrate_threads: u32,
    /// Bytes of the per-scan scratch the map kept while integrating ([`Map::scratch_bytes`]): with the map's
    /// own `map_bytes` of `summary.json`, the memory integration took. It grows with the threads.
    pub scratch_bytes: u64,
}

/// What a map job produced.
#[derive(Debug, Clone)]
pub struct MapReport {
    /// The summary written to `summary.json`.
    pub summary: MapSummary,
    /// The timing written to `timing.json`.
    pub timing: MapTiming,
    /// Every file written, in order.
    pub files: Vec<PathBuf>,
    /// Range messages of a bag that were not mapped, by bag, topic and reason.
    pub skipped: Vec<(PathBuf, oeg::BagSkip)>,
}

/// Scans given to the map at once ([`Map::integrate_batch`]).
const SCANS_PER_BATCH: usize = 1024;

/// Runs the job: reads, integrates, writes `map.oeg`, the layer images, `summary.json` and `timing.json`.
///
/// # Errors
/// Bad inputs or settings (before any output is written), or a failed write.
pub fn run(job: &MapJob, progress: &Progress) -> Result<MapReport> {
    if job.inputs.is_empty() {
        return Err(EvalError::CommandLine {
            message: "no input files".into(),
        });
    }
    job.profile.validate()?;
    let inputs: Vec<&Path> = job.inputs.iter().map(PathBuf::as_path).collect();
    let staged = Staged::begin(&job.out_dir, &inputs)?;
    let mut map = Map::new(job.config)?;
    let read_start = Instant::now();
    let Inputs {
        scans,
        skipped,
        stances,
    } = read_inputs(job)?;
    let read_wall_time_s = read_start.elapsed().as_secs_f64();
    // The ground the robot of a sensor log stood on, before the first scan, as `oeg run` gives it.
    if job.rule.needs_stance() {
        for (path, stance) in &stances {
            map.integrate_stance(stance).map_err(|e| EvalError::Input {
                path: path.clone(),
                message: format!("the header's stance: {e}"),
            })?;
        }
    }

    let start = Instant::now();
    // In batches, so that a log of many short scans uses every core (`Map::integrate_batch`); a batch is a
    // fraction of a second of work, between two steps of the progress bar.
    for (k, batch) in scans.chunks(SCANS_PER_BATCH).enumerate() {
        let batch: Vec<&Scan> = batch.iter().map(|(_, scan)| scan).collect();
        map.integrate_batch(&batch).map_err(|e| {
            let source = &scans[k * SCANS_PER_BATCH + e.index].0;
            EvalError::Input {
                path: source.file.clone(),
                message: format!("{}: {}", source.place, e.error),
            }
        })?;
        progress.inc(batch.len() as u64);
    }
    let integrate_wall_time_s = start.elapsed().as_secs_f64();
    progress.finish();
    // The per-scan scratch and the scans are given back before the outputs are drawn and written, which need
    // memory of their own (the map file's bytes, a raster of the observed region).
    let map_bytes = map.memory_bytes();
    let scratch_bytes = map.scratch_bytes();
    map.release_scratch();
    let num_scans_with_ground = scans.iter().filter(|(_, s)| s.ground_z_m.is_some()).count() as u64;
    drop(scans);

    // The writes, their errors naming the output folder's files (the staging is gone when the job fails).
    let work = || -> Result<_> {
        let stage = staged.dir();
        let (mut files, map_file_bytes) = write_map_files(job, &map, stage)?;
        let totals = map.totals();
        let mut summary = summarize(job, &map, map_bytes, map_file_bytes);
        summary.num_messages_skipped = skipped.iter().map(|(_, s)| s.count).sum();
        summary.num_scans_with_ground = num_scans_with_ground;
        let per_s = |n: u64| {
            if integrate_wall_time_s > 0.0 {
                n as f64 / integrate_wall_time_s
            } else {
                0.0
            }
        };
        let timing = MapTiming {
            read_wall_time_s,
            integrate_wall_time_s,
            integrate_rays_per_s: per_s(totals.num_rays),
            integrate_cell_visits_per_s: per_s(totals.num_cell_visits),
            integrate_threads: u32::try_from(rayon::current_num_threads()).unwrap_or(u32::MAX),
            scratch_bytes,
        };
        let summary_path = stage.join("summary.json");
        write_json(&summary_path, &summary)?;
        files.push(summary_path);
        let timing_path = stage.join("timing.json");
        write_json(&timing_path, &timing)?;
        files.push(timing_path);
        Ok((files, summary, timing))
    };
    let (files, summary, timing) = staged.explained(work())?;
    let files = files.iter().map(|f| staged.final_path(f)).collect();
    staged.commit()?;
    Ok(MapReport {
        summary,
        timing,
        files,
        skipped,
    })
}

/// Writes the inputs (when kept), `map.oeg` and the layer images into `stage`; returns the files and the map
/// file's size in bytes.
fn write_map_files(job: &MapJob, map: &Map, stage: &Path) -> Result<(Vec<PathBuf>, u64)> {
    let mut files = Vec::new();
    if job.keep_inputs {
        for input in &job.inputs {
            let name = input.file_name().unwrap_or_default();
            let bytes = oeg_files::read_bounded(input, job.config.memory_limit_bytes)?;
            let kept = stage.join(name);
            write_bytes(&kept, &bytes)?;
            files.push(kept);
        }
    }
    let map_path = stage.join("map.oeg");
    let map_file = oeg::map_to_bytes(map);
    write_bytes(&map_path, &map_file)?;
    let map_file_bytes = map_file.len() as u64;
    drop(map_file);
    files.push(map_path);
    let images = write_layer_images(map, stage, &job.profile, job.rule, None, job.figures)?;
    files.extend(images);
    // The decisions and layers as files a planner reads (`docs/planner-protocol.md`), over the observed
    // region: a map built from real data can feed a planner too. Dense files follow the region's extent, so
    // they are written when asked for.
    if let Some(region) = map.observed_region().filter(|_| job.planner_files) {
        let dir = stage.join("planner");
        crate::output::create_dir(&dir)?;
        let planner_files = oeg::planner_files(
            map,
            region,
            &job.profile,
            job.rule,
            oeg::UncertainCells::Blocked,
        )
        .map_err(|e| match e {
            e @ oeg::Error::MemoryLimit { .. } => EvalError::Input {
                path: job.out_dir.clone(),
                message: format!(
                    "writing the planner files ({} x {} cells of the observed region) of the map of {}: {e}",
                    region.num_x,
                    region.num_y,
                    job.inputs
                        .iter()
                        .map(|p| p.display().to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            },
            other => EvalError::Map(other),
        })?;
        for (name, bytes) in planner_files {
            let path = dir.join(name);
            write_bytes(&path, &bytes)?;
            files.push(path);
        }
    }

    Ok((files, map_file_bytes))
}

/// `summary.json`: what the map holds, with its memory (`map_bytes`) and its file's size.
fn summarize(job: &MapJob, map: &Map, map_bytes: u64, map_file_bytes: u64) -> MapSummary {
    let totals = map.totals();
    let counts = map.traversability_counts(&job.profile, job.rule);
    let extent = map.observed_region().map(|r| {
        let (x0, y0) = map.geometry().cell_min_corner(r.min);
        let (x1, y1) = map.geometry().cell_min_corner(r.max());
        let res = map.geometry().resolution_m();
        (x0, y0, x1 + res, y1 + res)
    });
    MapSummary {
        num_inputs: job.inputs.len() as u64,
        num_scans: map.num_scans(),
        num_rays: totals.num_rays,
        num_messages_skipped: 0,
        num_cell_visits: totals.num_cell_visits,
        resolution_m: map.geometry().resolution_m(),
        free_space_elevation: job.config.model.free_space_elevation,
        max_height_m: job.config.model.max_height_m,
        num_scans_with_ground: 0,
        num_cells_observed: map.num_observed_cells(),
        num_cells_occupied: counts.num_occupied(),
        num_cells_free: counts.num_free,
        num_cells_traversable: counts.num_traversable,
        num_cells_blocked: counts.num_blocked,
        max_step_m: job.profile.max_step_m,
        map_bytes,
        map_file_bytes,
        extent_min_x_m: extent.map(|e| e.0),
        extent_min_y_m: extent.map(|e| e.1),
        extent_max_x_m: extent.map(|e| e.2),
        extent_max_y_m: extent.map(|e| e.3),
    }
}
