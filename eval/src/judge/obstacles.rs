//! Per-obstacle decisions (`obstacles.csv`): for each obstacle of the scenario, what the truth and the map say
//! about the cells of its footprint, so a user sees where the decision boundary fell (which curb heights were
//! mapped blocked, which boards the robot was allowed under).

use nalgebra::{Isometry2, Point2, Vector2};
use oeg::Traversability;
use serde::Serialize;
use sim::scenario::{Obstacle, Scenario};
use sim::sensors::ObstacleReturns;
use sim::truth::TruthRaster;

use crate::judge::estimate::Estimate;
use crate::judge::verdict::{Verdict, Verdicts};

/// One row of `obstacles.csv`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ObstacleDecision {
    /// Index in the scenario's `obstacles`.
    pub index: usize,
    /// Label.
    pub name: String,
    /// Kind (`box`, `cylinder`, `ramp`, `bush`, `overhang`).
    pub kind: String,
    /// The height that decides: a box's or cylinder's height, a ramp's or bush's top, an overhang's clearance
    /// (the free gap under it), metres.
    pub height_m: f64,
    /// Readings the sensors got from the obstacle over the run (its own returns, spurious ones left out). 0: no
    /// beam ever reached it (between a lidar's beams, over or under every beam), so no map of these readings
    /// can hold it, whatever its model. Empty when the readings are not known (a map scored without the
    /// scenario's sensors, `oeg score --no-observability`).
    pub sensor_returns: Option<u64>,
    /// Cells whose centre lies in the footprint, plus the cell of the obstacle's centre.
    pub num_cells: u64,
    /// Of those, observed by the map.
    pub num_observed_cells: u64,
    /// Observed cells the truth blocks (step, or a structure lower than the robot).
    pub true_blocked_cells: u64,
    /// Observed cells the map blocks.
    pub mapped_blocked_cells: u64,
    /// Observed cells the map cannot judge.
    pub uncertain_cells: u64,
    /// Truly blocked, mapped drivable.
    pub unsafe_cells: u64,
    /// Of the unsafe cells, those no ray could have told about (blind).
    pub blind_cells: u64,
    /// Truly drivable, mapped blocked.
    pub overcautious_cells: u64,
    /// Mean true elevation (highest surface below the robot's height) over the observed cells, metres.
    pub true_elevation_mean_m: Option<f64>,
    /// Mean mapped elevation over the observed cells with an estimate, metres: how high the map thinks the
    /// obstacle is (a curb mapped at 3.6 cm is blocked even if it is 3.4 cm high).
    pub mapped_elevation_mean_m: Option<f64>,
    /// `blocked` when any observed cell is truly blocked, else `passable` (see [`decisions`]).
    pub true_decision: &'static str,
    /// `blocked`, `uncertain` or `passable` by most of the deciding cells, `unseen` when none was observed
    /// (see [`decisions`]).
    pub mapped_decision: &'static str,
    /// `right`, `unsafe` (truly blocked, mapped passable), `overcautious` (truly passable, mapped blocked),
    /// `uncertain` or `unseen`.
    pub decision: &'static str,
    /// Whether the two decisions agree.
    pub decision_right: bool,
}

/// An obstacle's footprint on the ground plane.
enum Footprint {
    /// A rectangle: its centre and heading, and half its length (local x) and width (local y), metres.
    Rect {
        pose: Isometry2<f64>,
        half_length_m: f64,
        half_width_m: f64,
    },
    /// A disc.
    Disc { center: Point2<f64>, radius_m: f64 },
}

fn footprint(o: &Obstacle) -> Footprint {
    let [cx, cy] = o.center_xy_m();
    let rect = |length: f64, width: f64, yaw_deg: f64| Footprint::Rect {
        pose: Isometry2::new(Vector2::new(cx, cy), yaw_deg.to_radians()),
        half_length_m: length / 2.0,
        half_width_m: width / 2.0,
    };
    match o {
        Obstacle::Box { size_m, yaw_deg, .. } | Obstacle::Overhang { size_m, yaw_deg, .. } => {
            rect(size_m[0], size_m[1], *yaw_deg)
        }
        Obstacle::Ramp {
            length_m,
            width_m,
            yaw_deg,
            ..
        } => rect(*length_m, *width_m, *yaw_deg),
        Obstacle::Cylinder { radius_m, .. } | Obstacle::Bush { radius_m, .. } => Footprint::Disc {
            center: Point2::new(cx, cy),
            radius_m: *radius_m,
        },
    }
}

/// Whether the world point `p` lies in the obstacle's footprint.
pub(crate) fn footprint_contains(o: &Obstacle, p: Point2<f64>) -> bool {
    match footprint(o) {
        Footprint::Rect {
            pose,
            half_length_m,
            half_width_m,
        } => {
            let local = pose.inverse() * p;
            local.x.abs() <= half_length_m && local.y.abs() <= half_width_m
        }
        Footprint::Disc { center, radius_m } => (p - center).norm() <= radius_m,
    }
}

/// The obstacle's footprint as a closed polygon of world points (a circle as 32 sides), for the images.
pub(crate) fn footprint_outline(o: &Obstacle) -> Vec<(f64, f64)> {
    match footprint(o) {
        Footprint::Rect {
            pose,
            half_length_m: hl,
            half_width_m: hw,
        } => [(-hl, -hw), (hl, -hw), (hl, hw), (-hl, hw), (-hl, -hw)]
            .iter()
            .map(|(x, y)| {
                let p = pose * Point2::new(*x, *y);
                (p.x, p.y)
            })
            .collect(),
        Footprint::Disc { center, radius_m } => (0..=32)
            .map(|k| {
                let a = std::f64::consts::TAU * f64::from(k) / 32.0;
                (center.x + radius_m * a.cos(), center.y + radius_m * a.sin())
            })
            .collect(),
    }
}

fn deciding_height(o: &Obstacle) -> f64 {
    match o {
        Obstacle::Box { size_m, base_m, .. } => base_m + size_m[2],
        Obstacle::Cylinder { height_m, base_m, .. } => base_m + height_m,
        Obstacle::Ramp { height_m, .. } | Obstacle::Bush { height_m, .. } => *height_m,
        Obstacle::Overhang { clearance_m, .. } => *clearance_m,
    }
}

/// The decision table of every obstacle, read from the run's verdict raster.
///
/// An obstacle is truly `blocked` when any observed cell of its footprint is truly blocked (a wheel meets its
/// step, or the robot its underside, somewhere), `passable` otherwise. The map's decision is taken over the
/// cells that decide: the truly blocked ones for a blocked obstacle, every observed one for a passable one.
/// It is `blocked` when most of them are mapped blocked, `uncertain` when most are mapped blocked or
/// uncertain, `passable` otherwise, and `unseen` when none was observed.
pub(crate) fn decisions(
    s: &Scenario,
    estimate: &Estimate,
    truth: &TruthRaster,
    verdicts: &Verdicts,
    returns: Option<&ObstacleReturns>,
) -> Vec<ObstacleDecision> {
    s.obstacles
        .iter()
        .enumerate()
        .map(|(index, o)| {
            let mut row = ObstacleDecision {
                index,
                name: o.label(index),
                kind: o.kind().to_string(),
                // Rounded to the micrometre: 0.036, not 0.036000000000000004.
                height_m: (deciding_height(o) * 1e6).round() / 1e6,
                sensor_returns: returns.map(|r| r.of(index)),
                num_cells: 0,
                num_observed_cells: 0,
                true_blocked_cells: 0,
                mapped_blocked_cells: 0,
                uncertain_cells: 0,
                unsafe_cells: 0,
                blind_cells: 0,
                overcautious_cells: 0,
                true_elevation_mean_m: None,
                mapped_elevation_mean_m: None,
                true_decision: "passable",
                mapped_decision: "unseen",
                decision: "unseen",
                decision_right: false,
            };
            let tally = tally_footprint(o, estimate, truth, verdicts, &mut row);
            conclude(&mut row, &tally);
            row
        })
        .collect()
}

/// What the footprint's cells add up to, beyond the row's counts.
struct Tally {
    /// Sum of the true elevations of the observed cells, metres.
    true_sum: f64,
    /// Sum of the mapped elevations of the cells with one, metres.
    mapped_sum: f64,
    /// Cells with a mapped elevation.
    num_mapped: u64,
    /// Over the truly blocked cells: (cells, mapped blocked, mapped uncertain).
    over_blocked: [u64; 3],
    /// Over every observed cell: (cells, mapped blocked, mapped uncertain).
    over_all: [u64; 3],
}

/// Counts the cells of `o`'s footprint into `row`: the cells whose centre lies in the footprint, and the cell
/// of the obstacle's centre (a 2 cm pole covers no cell centre).
fn tally_footprint(
    o: &Obstacle,
    estimate: &Estimate,
    truth: &TruthRaster,
    verdicts: &Verdicts,
    row: &mut ObstacleDecision,
) -> Tally {
    let geometry = *estimate.window.geometry();
    let [cx, cy] = o.center_xy_m();
    let center_cell = geometry.cell_of(cx, cy);
    let mut t = Tally {
        true_sum: 0.0,
        mapped_sum: 0.0,
        num_mapped: 0,
        over_blocked: [0; 3],
        over_all: [0; 3],
    };
    for (k, cell) in truth.window.region().cells().enumerate() {
        let (x, y) = geometry.cell_center(cell);
        if !footprint_contains(o, Point2::new(x, y)) && center_cell != Some(cell) {
            continue;
        }
        row.num_cells += 1;
        let verdict = verdicts.verdict[k];
        if verdict == Verdict::NotScored {
            continue;
        }
        row.num_observed_cells += 1;
        let truly = verdicts.truth[k].is_blocked();
        let mapped = verdicts.mapped[k];
        let tally = [
            1,
            u64::from(mapped == Traversability::Blocked),
            u64::from(mapped == Traversability::Uncertain),
        ];
        for (a, n) in t.over_all.iter_mut().zip(tally) {
            *a += n;
        }
        if truly {
            for (a, n) in t.over_blocked.iter_mut().zip(tally) {
                *a += n;
            }
        }
        row.true_blocked_cells += u64::from(truly);
        row.mapped_blocked_cells += tally[1];
        row.uncertain_cells += tally[2];
        row.unsafe_cells += u64::from(verdict == Verdict::Unsafe);
        row.blind_cells += u64::from(verdict == Verdict::Unsafe && verdicts.unobservable[k]);
        row.overcautious_cells += u64::from(verdict == Verdict::OverCautious);
        t.true_sum += f64::from(truth.cells[k].elevation_m);
        if let Some((e, _)) = estimate.elevation(k) {
            t.mapped_sum += e;
            t.num_mapped += 1;
        }
    }
    t
}

/// The row's mean elevations and its decisions, from the counts (see [`decisions`]).
fn conclude(row: &mut ObstacleDecision, t: &Tally) {
    // Rounded to the tenth of a millimetre, so the CSV reads 0.0361, not 0.036112...
    let round = |v: f64| (v * 1e4).round() / 1e4;
    if row.num_observed_cells > 0 {
        row.true_elevation_mean_m = Some(round(t.true_sum / row.num_observed_cells as f64));
    }
    if t.num_mapped > 0 {
        row.mapped_elevation_mean_m = Some(round(t.mapped_sum / t.num_mapped as f64));
    }
    if row.num_observed_cells > 0 {
        let truly_blocked = row.true_blocked_cells > 0;
        row.true_decision = if truly_blocked { "blocked" } else { "passable" };
        let [n, blocked, uncertain] = if truly_blocked { t.over_blocked } else { t.over_all };
        row.mapped_decision = if 2 * blocked > n {
            "blocked"
        } else if 2 * (blocked + uncertain) > n {
            "uncertain"
        } else {
            "passable"
        };
        row.decision_right = row.true_decision == row.mapped_decision;
        row.decision = match (row.true_decision, row.mapped_decision) {
            (_, "uncertain") => "uncertain",
            (t, m) if t == m => "right",
            ("blocked", _) => "unsafe",
            _ => "overcautious",
        };
    }
}

impl crate::output::CsvRow for ObstacleDecision {
    const COLUMNS: &'static [&'static str] = &[
        "index",
        "name",
        "kind",
        "height_m",
        "sensor_returns",
        "num_cells",
        "num_observed_cells",
        "true_blocked_cells",
        "mapped_blocked_cells",
        "uncertain_cells",
        "unsafe_cells",
        "blind_cells",
        "overcautious_cells",
        "true_elevation_mean_m",
        "mapped_elevation_mean_m",
        "true_decision",
        "mapped_decision",
        "decision",
        "decision_right",
    ];
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn footprints_follow_position_yaw_and_radius() {
        let board = Obstacle::Overhang {
            name: None,
            center_xy_m: [2.0, 0.0],
            size_m: [0.4, 2.0, 0.02],
            clearance_m: 0.35,
            yaw_deg: 90.0,
        };
        // Turned 90 degrees: 2 m along x, 0.4 m along y.
        assert!(footprint_contains(&board, Point2::new(2.9, 0.1)));
        assert!(!footprint_contains(&board, Point2::new(2.0, 0.5)));
        let pole = Obstacle::Cylinder {
            name: None,
            center_xy_m: [0.0, 0.0],
            radius_m: 0.1,
            height_m: 2.0,
            base_m: 0.0,
        };
        assert!(footprint_contains(&pole, Point2::new(0.07, 0.07)));
        assert!(!footprint_contains(&pole, Point2::new(0.08, 0.08)));

        // The outlines agree: closed, every vertex on the footprint's edge (just inside when moved 0.1 % towards
        // the centre, just outside when moved 0.1 % away).
        for o in [&board, &pole] {
            let outline = footprint_outline(o);
            let (a, b) = (outline[0], outline[outline.len() - 1]);
            assert!(
                (a.0 - b.0).abs() < 1e-12 && (a.1 - b.1).abs() < 1e-12,
                "closed: {a:?} {b:?}"
            );
            let [cx, cy] = o.center_xy_m();
            let scaled = |(x, y): (f64, f64), f: f64| Point2::new(cx + f * (x - cx), cy + f * (y - cy));
            for p in &outline {
                assert!(footprint_contains(o, scaled(*p, 0.999)), "{p:?}");
                assert!(!footprint_contains(o, scaled(*p, 1.001)), "{p:?}");
            }
        }
        let board_outline = footprint_outline(&board);
        let max_x = board_outline
            .iter()
            .map(|p| p.0)
            .fold(f64::NEG_INFINITY, f64::max);
        assert!((max_x - 3.0).abs() < 1e-9, "{board_outline:?}");
    }
}
