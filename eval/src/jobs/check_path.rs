//! `oeg check-path`: any path (one logged by a planner in the field, one from another tool) checked against a
//! scenario's truth with the robot's real footprint: the rectangle bounding its URDF's collision shapes, turned
//! along the path. It reports the first contact, the closest approach and the cells the footprint crossed by
//! the truth's class, and with a map file the map's verdict on them too.

use std::collections::BTreeMap;
use std::path::PathBuf;

use oeg::Pose2;
use serde::Serialize;

use crate::error::{EvalError, Result};
use crate::judge::verdict::Verdicts;
use crate::navigation::contact::ContactWatch;
use crate::output::{Staged, write_json};
use sim::truth::TruthRaster;

/// `oeg check-path`.
#[derive(Debug, Clone)]
pub struct CheckPathJob {
    /// The scenario whose world is the truth.
    pub scenario: PathBuf,
    /// `--set` overrides of the scenario.
    pub overrides: Vec<String>,
    /// The path: lines of `x,y` in metres, world frame (the planner protocol's format).
    pub path: PathBuf,
    /// A map to judge along the path too (`map.oeg`).
    pub map: Option<PathBuf>,
    /// Output folder.
    pub out_dir: PathBuf,
}

/// Where the footprint first entered a truly blocked cell.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Contact {
    /// Distance along the path, metres.
    pub along_m: f64,
    /// The robot's centre, metres.
    pub x_m: f64,
    /// The robot's centre, metres.
    pub y_m: f64,
    /// Heading, degrees.
    pub yaw_deg: f64,
    /// The obstacle holding the cell (`terrain` for a step of the ground).
    pub obstacle: String,
}

/// `path_check.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PathCheck {
    /// The scenario's name.
    pub scenario: String,
    /// Points of the path.
    pub num_points: u64,
    /// Its length, metres.
    pub length_m: f64,
    /// Poses checked: every half cell along the path, heading along it.
    pub num_poses: u64,
    /// The first contact, null when there is none.
    pub first_contact: Option<Contact>,
    /// Poses whose footprint touched a truly blocked cell.
    pub contact_poses: u64,
    /// The smallest distance from the footprint to a truly blocked cell, metres (null: none within 2 m).
    pub closest_approach_m: Option<f64>,
    /// Where along the path, metres.
    pub closest_approach_along_m: Option<f64>,
    /// The cells the footprint crossed, by the truth's class.
    pub cells_by_truth: BTreeMap<String, u64>,
    /// With a map: the same cells by the map's verdict (`unsafe`, `right_drivable`, ...).
    pub cells_by_verdict: Option<BTreeMap<String, u64>>,
    /// The footprint used, base frame, metres: `[min_x, max_x, min_y, max_y]`.
    pub footprint_m: [f64; 4],
}

/// Checks the path and writes `path_check.json` into the output folder.
///
/// # Errors
/// A bad scenario or override, an unreadable or malformed path file (named with its line), an unreadable map,
/// a failed write.
pub fn run_job(job: &CheckPathJob) -> Result<(PathCheck, Vec<PathBuf>)> {
    let loaded = crate::pipeline::load(&crate::pipeline::RunOptions {
        scenario: job.scenario.clone(),
        overrides: job.overrides.clone(),
        ..Default::default()
    })?;
    let s = &loaded.scenario;
    let mut inputs = loaded.files();
    inputs.push(job.path.clone());
    inputs.extend(job.map.clone());
    let inputs: Vec<&std::path::Path> = inputs.iter().map(PathBuf::as_path).collect();
    let staged = Staged::begin(&job.out_dir, &inputs)?;
    let world = sim::World::new(&loaded)?;
    let truth = crate::pipeline::truth_of(&loaded, &world, &crate::progress::Progress::hidden())?;
    let extent = crate::navigation::external::extent_of(&truth.window);
    // Every message of `read_path` names the file and the line.
    let points = crate::navigation::external::read_path(&job.path, extent)
        .map_err(|f| EvalError::Placed { message: f.message })?;
    let verdicts = match &job.map {
        Some(path) => {
            let map = oeg::load_map(path)?;
            // The map's cells are judged against the truth's, one to one: another cell size would compare
            // unrelated cells.
            let (mine, truths) = (map.geometry().resolution_m(), truth.window.resolution_m());
            if mine != truths {
                return Err(EvalError::Input {
                    path: path.clone(),
                    message: format!(
                        "a map of {mine} m cells; the scenario's truth has {truths} m cells: judge a map made at \
                         the scenario's resolution, or give the scenario that one (--set map.resolution_m={mine})"
                    ),
                });
            }
            Some(Verdicts::new(&map, &truth, s.map.traversability)?)
        }
        None => None,
    };
    let judge = PathJudge {
        scenario: s,
        truth: &truth,
        footprint: loaded.robot.footprint(),
    };
    let check = judge.check(&job.path, &points, verdicts.as_ref())?;
    let json = staged.dir().join("path_check.json");
    staged.explained(write_json(&json, &check))?;
    let files = vec![staged.final_path(&json)];
    staged.commit()?;
    Ok((check, files))
}

/// What a path is checked against: the scenario, its truth and the robot's footprint.
#[derive(Debug, Clone, Copy)]
pub struct PathJudge<'a> {
    /// The scenario (its obstacles name the contacts).
    pub scenario: &'a sim::scenario::Scenario,
    /// Its truth, on the map's window.
    pub truth: &'a TruthRaster,
    /// The robot's footprint, base frame.
    pub footprint: oeg::Footprint,
}

impl PathJudge<'_> {
    /// Checks `points` (read from `path`, which errors name): a pose every half cell along them, each against
    /// the truth, and with `verdicts` the map's verdicts on the cells crossed. The number of poses is bounded
    /// ([`MAX_CHECKED_POSES`]) before the work.
    ///
    /// # Errors
    /// A path that needs more poses than the bound.
    pub fn check(
        &self,
        path: &std::path::Path,
        points: &[(f64, f64)],
        verdicts: Option<&Verdicts>,
    ) -> Result<PathCheck> {
        let (s, truth, footprint) = (self.scenario, self.truth, self.footprint);
        let region = *truth.window.region();
        let res = truth.window.resolution_m();
        // Each pose looks at the blocked cells within a few metres: the number of poses is bounded before the work.
        let planned_poses = count_poses(points, res / 2.0);
        if planned_poses > MAX_CHECKED_POSES {
            return Err(EvalError::Input {
                path: path.to_path_buf(),
                message: format!(
                    "the path needs {planned_poses} poses (one every {} m along it), over the limit of \
                     {MAX_CHECKED_POSES}; check a shorter path, or its parts one by one",
                    res / 2.0
                ),
            });
        }
        let mut watch = ContactWatch::new(s, truth, footprint);
        let (mut first_contact, mut contact_poses) = (None, 0u64);
        // The cells the footprint crossed, one flag a cell of the region (not a list of every pose's cells).
        let mut crossed = vec![false; truth.cells.len()];
        let num_poses = for_each_pose(points, res / 2.0, |along, pose| {
            let began = watch.check(along, pose);
            let mut touching = false;
            for c in footprint.cells_under(&truth.window, pose) {
                if let Some(k) = region.offset(c) {
                    touching |= truth.truly_blocked(k);
                    crossed[k] = true;
                }
            }
            contact_poses += u64::from(touching);
            if let (None, Some(c)) = (&first_contact, began) {
                first_contact = Some(Contact {
                    along_m: round(along),
                    x_m: round(pose.x_m),
                    y_m: round(pose.y_m),
                    yaw_deg: round(pose.yaw_rad.to_degrees()),
                    obstacle: c.obstacle,
                });
            }
        });
        let classes = Verdicts::from_classes(truth, vec![oeg::Traversability::Unknown; truth.cells.len()]);
        let mut cells_by_truth = BTreeMap::new();
        let mut cells_by_verdict = verdicts.map(|_| BTreeMap::new());
        for k in (0..crossed.len()).filter(|&k| crossed[k]) {
            *cells_by_truth
                .entry(classes.truth[k].name().to_string())
                .or_insert(0) += 1;
            if let (Some(v), Some(by)) = (verdicts, cells_by_verdict.as_mut()) {
                *by.entry(v.verdict[k].name().to_string()).or_insert(0) += 1;
            }
        }
        let length_m = points
            .windows(2)
            .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
            .sum::<f64>();
        Ok(PathCheck {
            scenario: s.name.clone(),
            num_points: points.len() as u64,
            length_m: round(length_m),
            num_poses,
            first_contact,
            contact_poses,
            closest_approach_m: watch.closest.map(|c| round(c.0)),
            closest_approach_along_m: watch.closest.map(|c| round(c.1)),
            cells_by_truth,
            cells_by_verdict,
            footprint_m: [
                footprint.min_x_m,
                footprint.max_x_m,
                footprint.min_y_m,
                footprint.max_y_m,
            ]
            .map(round),
        })
    }
}

/// The most poses `oeg check-path` checks: a path of 25 km at 0.05 m (a pose every half cell). Each pose looks at
/// the truly blocked cells within [`crate::navigation::APPROACH_WINDOW_M`] of the footprint.
pub const MAX_CHECKED_POSES: u64 = 1_000_000;

/// The poses of a segment `length_m` long, one every `step_m` (its last point is the next segment's first).
fn segment_poses(length_m: f64, step_m: f64) -> u64 {
    if length_m > 0.0 {
        (length_m / step_m).ceil() as u64
    } else {
        0
    }
}

/// The number of poses a check of `points` visits, one every `step_m` (half a cell), without visiting them.
pub fn count_poses(points: &[(f64, f64)], step_m: f64) -> u64 {
    let along: u64 = points
        .windows(2)
        .map(|w| segment_poses((w[1].0 - w[0].0).hypot(w[1].1 - w[0].1), step_m))
        .fold(0, u64::saturating_add);
    along.saturating_add(u64::from(!points.is_empty()))
}

/// Visits the poses every `step_m` along the polyline, heading along each segment, with the distance along
/// the path (the watch's clock), one at a time: a long path's poses are never held together. A one-point path
/// is one pose, heading +x. Returns the number of poses.
fn for_each_pose(points: &[(f64, f64)], step_m: f64, mut visit: impl FnMut(f64, Pose2)) -> u64 {
    let (mut along, mut yaw_rad, mut count) = (0.0, 0.0, 0u64);
    for w in points.windows(2) {
        let (a, b) = (w[0], w[1]);
        let length = (b.0 - a.0).hypot(b.1 - a.1);
        if length <= 0.0 {
            continue;
        }
        yaw_rad = (b.1 - a.1).atan2(b.0 - a.0);
        let n = segment_poses(length, step_m);
        for k in 0..n {
            let f = k as f64 / n as f64;
            visit(
                along + f * length,
                Pose2 {
                    x_m: a.0 + f * (b.0 - a.0),
                    y_m: a.1 + f * (b.1 - a.1),
                    yaw_rad,
                },
            );
            count += 1;
        }
        along += length;
    }
    if let Some(&(x_m, y_m)) = points.last() {
        visit(along, Pose2 { x_m, y_m, yaw_rad });
        count += 1;
    }
    count
}

fn round(v: f64) -> f64 {
    crate::output::round_m(v)
}
