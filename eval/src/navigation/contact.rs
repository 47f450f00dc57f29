//! The judge's watch over a closed-loop run: the robot's real footprint, turned with its true heading,
//! against the truly blocked cells of the truth raster. Nothing here reads the map.

use oeg::{CellIndex, Footprint, GridWindow, Pose2};
use sim::scenario::Scenario;
use sim::truth::TruthRaster;

/// How far around the footprint blocked cells are looked for, metres: nearer ones set the closest approach.
pub const APPROACH_WINDOW_M: f64 = 2.0;

/// The contacts and the closest approach over a run.
#[derive(Debug, Clone)]
pub(crate) struct ContactWatch<'a> {
    scenario: &'a Scenario,
    truth: &'a TruthRaster,
    footprint: Footprint,
    blocked: Vec<bool>,
    /// The columns (`i`) of the truly blocked cells of each row of the region, ascending: a pose looks only at
    /// the blocked cells of its window, not at every cell of it.
    blocked_columns: Vec<Vec<i32>>,
    /// The largest distance from the robot's centre to its footprint's corners, metres.
    radius_m: f64,
    in_contact: bool,
    /// The closest approach so far: distance, time, pose, the cell.
    pub closest: Option<(f64, f64, Pose2, CellIndex)>,
}

/// A contact that began at this step.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct NewContact {
    /// The truly blocked cell the footprint entered nearest the robot's centre.
    pub cell: CellIndex,
    /// Every truly blocked cell under the footprint.
    pub cells: Vec<CellIndex>,
    /// The obstacle it belongs to (`terrain` for a step of the ground).
    pub obstacle: String,
}

impl<'a> ContactWatch<'a> {
    /// A watch with no contact yet, on the truth's cells.
    pub(crate) fn new(scenario: &'a Scenario, truth: &'a TruthRaster, footprint: Footprint) -> Self {
        let blocked: Vec<bool> = (0..truth.cells.len()).map(|k| truth.truly_blocked(k)).collect();
        let region = *truth.window.region();
        let blocked_columns = (0..region.num_y)
            .map(|v| {
                (0..region.num_x)
                    .filter(|&u| blocked[v as usize * region.num_x as usize + u as usize])
                    .map(|u| region.cell_at(u, v).i)
                    .collect()
            })
            .collect();
        Self {
            scenario,
            truth,
            footprint,
            blocked,
            blocked_columns,
            radius_m: [
                (footprint.min_x_m, footprint.min_y_m),
                (footprint.min_x_m, footprint.max_y_m),
                (footprint.max_x_m, footprint.min_y_m),
                (footprint.max_x_m, footprint.max_y_m),
            ]
            .iter()
            .fold(0.0_f64, |r, (x, y)| r.max(x.hypot(*y))),
            in_contact: false,
            closest: None,
        }
    }

    /// The step rule of the map the robot navigates by (the scenario's).
    pub(crate) fn rule(&self) -> oeg::TraversabilityRule {
        self.scenario.map.traversability
    }

    /// The truth the watch judges by.
    pub(crate) fn truth(&self) -> &TruthRaster {
        self.truth
    }

    /// The truth's window.
    pub(crate) fn window(&self) -> &GridWindow {
        &self.truth.window
    }

    /// Checks the robot at its true `pose` at `time_s`: a contact that begins here, if one does, and the
    /// closest approach updated.
    pub(crate) fn check(&mut self, time_s: f64, pose: Pose2) -> Option<NewContact> {
        let truth = self.truth;
        let (geometry, region) = (truth.window.geometry(), *truth.window.region());
        let reach = self.footprint.length_m().hypot(self.footprint.width_m()) + APPROACH_WINDOW_M;
        let window = geometry.region_covering(
            (pose.x_m - reach, pose.y_m - reach),
            (pose.x_m + reach, pose.y_m + reach),
        );
        let mut nearest: Option<(f64, CellIndex)> = None;
        if let Some(shared) = window.ok().and_then(|w| w.intersection(&region)) {
            let (lo, hi, rlo) = (shared.min, shared.max(), region.min);
            // The footprint lies within `radius` of the pose, so a cell's distance from the pose less `radius`
            // is a lower bound of the footprint's: a cell whose bound exceeds the nearest so far is skipped
            // without the exact distance (the result is the same).
            let radius = self.radius_m;
            let half = geometry.resolution_m() / 2.0;
            for j in lo.j..=hi.j {
                let row = &self.blocked_columns[(j - rlo.j) as usize];
                let first = row.partition_point(|&i| i < lo.i);
                for &i in row[first..].iter().take_while(|&&i| i <= hi.i) {
                    let cell = CellIndex::new(i, j);
                    let (cx, cy) = geometry.cell_center(cell);
                    let (dx, dy) = (
                        ((cx - pose.x_m).abs() - half).max(0.0),
                        ((cy - pose.y_m).abs() - half).max(0.0),
                    );
                    let bound = nearest.map_or(APPROACH_WINDOW_M, |(best, _)| best);
                    if (dx * dx + dy * dy).sqrt() - radius > bound + 1e-9 {
                        continue;
                    }
                    let d = self.footprint.distance_to_cell(geometry, cell, pose);
                    if d <= APPROACH_WINDOW_M && nearest.is_none_or(|(best, _)| d < best) {
                        nearest = Some((d, cell));
                    }
                }
            }
        }
        if let Some((d, cell)) = nearest
            && self.closest.is_none_or(|(best, ..)| d < best)
        {
            self.closest = Some((d, time_s, pose, cell));
        }
        let touching = nearest.filter(|(d, _)| *d == 0.0);
        let began = touching.is_some() && !self.in_contact;
        self.in_contact = touching.is_some();
        if !began {
            return None;
        }
        // The touched cell nearest the robot's centre names the obstacle.
        let cells: Vec<CellIndex> = self
            .footprint
            .cells_under(&truth.window, pose)
            .into_iter()
            .filter(|c| region.offset(*c).is_some_and(|k| self.blocked[k]))
            .collect();
        let cell = cells
            .iter()
            .copied()
            .min_by(|a, b| {
                let d = |c: &CellIndex| {
                    let (x, y) = self.truth.window.geometry().cell_center(*c);
                    (x - pose.x_m).hypot(y - pose.y_m)
                };
                d(a).total_cmp(&d(b))
            })
            .or(touching.map(|(_, c)| c))?;
        Some(NewContact {
            cell,
            cells: if cells.is_empty() { vec![cell] } else { cells },
            obstacle: self.obstacle_of(cell),
        })
    }

    /// The obstacle a blocked cell belongs to: the one whose footprint holds the cell's centre, else the one
    /// holding a corner of the cell, else `terrain`.
    pub(crate) fn obstacle_of(&self, cell: CellIndex) -> String {
        let (x, y) = self.truth.window.geometry().cell_center(cell);
        let h = self.truth.window.resolution_m() / 2.0;
        let points = [
            (x, y),
            (x - h, y - h),
            (x + h, y - h),
            (x + h, y + h),
            (x - h, y + h),
        ];
        points
            .iter()
            .find_map(|(px, py)| {
                self.scenario.obstacles.iter().enumerate().find(|(_, o)| {
                    crate::judge::obstacles::footprint_contains(o, nalgebra::Point2::new(*px, *py))
                })
            })
            .map_or_else(|| "terrain".to_string(), |(k, o)| o.label(k))
    }
}
