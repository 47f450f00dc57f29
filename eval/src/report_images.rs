//! The run's comparison images: the true elevation, the elevation error, and the decisions.

use std::path::{Path, PathBuf};

use oeg::{Map, RobotProfile};
use sim::scenario::Scenario;
use sim::truth::TruthRaster;

use crate::error::Result;
use crate::metrics::Metrics;
use crate::output::write_bytes;
use crate::render::{Colormap, Figure, Legend, NO_DATA, Rgb, finite_range};

/// Decision classes of `decisions.png`, in legend order.
pub const DECISION_CLASSES: [(&str, Rgb); 5] = [
    ("not observed", NO_DATA),
    ("right, drivable", [255, 255, 255]),
    ("right, blocked", [110, 110, 110]),
    ("UNSAFE (mapped drivable)", [220, 20, 20]),
    ("over-cautious (mapped blocked)", [255, 160, 30]),
];

/// The drive on the run's images.
pub const DRIVE: Rgb = [30, 80, 230];
/// The path planned on the map, on `decisions.png`.
pub const PLAN: Rgb = [200, 0, 200];
/// Obstacle footprints and names on `decisions.png`.
const OUTLINE: Rgb = [0, 0, 0];

/// The scenario's drive as a polyline of world points.
pub fn drive_polyline(s: &Scenario) -> Vec<(f64, f64)> {
    s.robot
        .drive
        .waypoints_xy_m
        .iter()
        .map(|w| (w[0], w[1]))
        .collect()
}

/// The true elevation of every cell, with a colour bar over its range.
pub fn truth_elevation_figure(truth: &TruthRaster, title: &str) -> Figure {
    let elevations: Vec<f32> = truth.cells.iter().map(|c| c.elevation_m).collect();
    let (lo, hi) = finite_range(&elevations).unwrap_or((0.0, 1.0));
    let legend = Legend::ColorBar {
        colormap: Colormap::Viridis,
        min: lo,
        max: hi,
        label: "elevation [m]".into(),
    };
    Figure::new(
        truth.region,
        truth.resolution_m,
        title,
        |c| match truth.get(c) {
            Some(t) if t.elevation_m.is_finite() => Colormap::Viridis.color((t.elevation_m - lo) / (hi - lo)),
            _ => NO_DATA,
        },
        &legend,
    )
}

/// Writes `truth_elevation.png`, `elevation_error.png` and `decisions.png`.
///
/// # Errors
/// A failed write.
pub fn write(
    out_dir: &Path,
    s: &Scenario,
    map: &Map,
    truth: &TruthRaster,
    profile: &RobotProfile,
    metrics: &Metrics,
    plan: &crate::plan::PlanCheck,
) -> Result<Vec<PathBuf>> {
    let region = truth.region;
    let res = truth.resolution_m;
    let drive = drive_polyline(s);
    let with_drive = |mut fig: Figure| {
        fig.polyline(&drive, DRIVE);
        fig
    };
    let mut files = Vec::new();

    let fig = truth_elevation_figure(truth, &format!("{}: true elevation (drive in blue)", s.name));
    let path = out_dir.join("truth_elevation.png");
    write_bytes(&path, &with_drive(fig).to_png())?;
    files.push(path);

    let error_of = |c: oeg::CellIndex| -> Option<f32> {
        let t = truth.get(c)?;
        let e = map.cell(c).elevation()?;
        t.elevation_m.is_finite().then_some(e.mean_m - t.elevation_m)
    };
    let span = if metrics.elevation_p95_abs_err_m.is_finite() {
        (metrics.elevation_p95_abs_err_m as f32 * 1.5).max(0.02)
    } else {
        0.1
    };
    let legend = Legend::ColorBar {
        colormap: Colormap::Diverging,
        min: -span,
        max: span,
        label: "map - truth [m]".into(),
    };
    let fig = Figure::new(
        region,
        res,
        &format!(
            "{}: elevation error (RMSE {:.3} m)",
            s.name, metrics.elevation_rmse_m
        ),
        |c| error_of(c).map_or(NO_DATA, |e| Colormap::Diverging.color((e + span) / (2.0 * span))),
        &legend,
    );
    let path = out_dir.join("elevation_error.png");
    write_bytes(&path, &with_drive(fig).to_png())?;
    files.push(path);

    let reference = crate::metrics::step_reference(s.map.traversability);
    let mut classes: Vec<(String, Rgb)> = DECISION_CLASSES
        .iter()
        .map(|(n, c)| ((*n).to_string(), *c))
        .collect();
    classes.push(("drive".into(), DRIVE));
    classes.push(("obstacle footprint".into(), OUTLINE));
    classes.push((
        if plan.map_plan.is_some() {
            "path planned on the map".into()
        } else {
            "no path on the map".into()
        },
        PLAN,
    ));
    let legend = Legend::Classes(classes);
    let fig = Figure::new(
        region,
        res,
        &format!(
            "{}: decisions ({} unsafe, {} over-cautious)",
            s.name, metrics.unsafe_step_cells, metrics.overcautious_step_cells
        ),
        |c| {
            let (Some(t), Some(k)) = (truth.get(c), truth.region.offset(c)) else {
                return NO_DATA;
            };
            let mapped = map.traversability(c, profile, s.map.traversability);
            if mapped == oeg::Traversability::Unknown || t.elevation_m.is_nan() {
                return DECISION_CLASSES[0].1;
            }
            let blocked = mapped == oeg::Traversability::Blocked;
            match (truth.step_blocked(k, reference), blocked) {
                (false, false) => DECISION_CLASSES[1].1,
                (true, true) => DECISION_CLASSES[2].1,
                (true, false) => DECISION_CLASSES[3].1,
                (false, true) => DECISION_CLASSES[4].1,
            }
        },
        &legend,
    );
    let mut fig = with_drive(fig);
    // The scene under the decisions: every obstacle's footprint, and the names of the named ones.
    for o in &s.obstacles {
        let outline = crate::obstacles::footprint_outline(o);
        fig.polyline(&outline, OUTLINE);
        if let Some(name) = o.name() {
            let (x, y) = outline
                .iter()
                .fold((f64::NEG_INFINITY, f64::NEG_INFINITY), |(x, y), p| {
                    (x.max(p.0), y.max(p.1))
                });
            fig.label(x, y, name, OUTLINE);
        }
    }
    if let Some(p) = &plan.map_plan {
        fig.polyline(&crate::plan::polyline(p, map.geometry()), PLAN);
    }
    let path = out_dir.join("decisions.png");
    write_bytes(&path, &fig.to_png())?;
    files.push(path);
    Ok(files)
}
