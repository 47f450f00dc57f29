//! The run's comparison images: the true elevation, the elevation error, and the decisions.

use std::path::{Path, PathBuf};

use oeg::Map;
use sim::scenario::Scenario;
use sim::truth::TruthRaster;

use crate::error::Result;
use crate::figures::{Colormap, DRIVE, Figure, Fill, Legend, NO_DATA, PLAN, Pattern, Rgb, finite_range};
use crate::figures::{ImageFormats, save};
use crate::judge::Evaluation;
use crate::judge::verdict::Verdict;

/// The verdicts of `decisions.png`, in legend order, with their legend text and fill. The wrong and the
/// uncertain decisions are textured, so that the classes stay apart in grey scale.
pub(crate) const DECISION_CLASSES: [(Verdict, &str, Fill); 6] = [
    (
        Verdict::NotScored,
        "not observed",
        Fill::patterned(NO_DATA, Pattern::Solid),
    ),
    (
        Verdict::RightDrivable,
        "right, drivable",
        Fill::patterned([255, 255, 255], Pattern::Solid),
    ),
    (
        Verdict::RightBlocked,
        "right, blocked",
        Fill::patterned([110, 110, 110], Pattern::Solid),
    ),
    (
        Verdict::Unsafe,
        "UNSAFE (mapped drivable)",
        Fill::patterned([220, 20, 20], Pattern::CrossHatch),
    ),
    (
        Verdict::OverCautious,
        "over-cautious (mapped blocked)",
        Fill::patterned([255, 160, 30], Pattern::Hatch),
    ),
    (
        Verdict::Uncertain,
        "uncertain (the map cannot tell)",
        Fill::patterned([70, 170, 230], Pattern::Dots),
    ),
];

/// The fill of a verdict on `decisions.png`.
pub(crate) fn verdict_fill(v: Verdict) -> Fill {
    DECISION_CLASSES
        .iter()
        .find(|(c, ..)| *c == v)
        .map_or(NO_DATA.into(), |(_, _, fill)| *fill)
}

/// Obstacle footprints and names on `decisions.png`.
const OUTLINE: Rgb = [0, 0, 0];

/// The scenario's drive as a polyline of world points.
pub(crate) fn drive_polyline(s: &Scenario) -> Vec<(f64, f64)> {
    s.robot
        .drive
        .waypoints_xy_m
        .iter()
        .map(|w| (w[0], w[1]))
        .collect()
}

/// The true elevation of every cell, with a colour bar over its range.
pub(crate) fn truth_elevation_figure(truth: &TruthRaster, title: &str) -> Figure {
    let elevations: Vec<f32> = truth.cells.iter().map(|c| c.elevation_m).collect();
    let (lo, hi) = finite_range(&elevations).unwrap_or((0.0, 1.0));
    let legend = Legend::ColorBar {
        colormap: Colormap::Viridis,
        min: lo,
        max: hi,
        label: "elevation [m]".into(),
    };
    Figure::new(
        &truth.window,
        title,
        |c| match truth.get(c) {
            Some(t) if t.elevation_m.is_finite() => Colormap::Viridis.color((t.elevation_m - lo) / (hi - lo)),
            _ => NO_DATA,
        },
        &legend,
    )
}

/// What a closed-loop run adds to its decisions image: the trajectory the robot truly drove and some of the
/// paths it planned on the way.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct Overlay {
    /// The true trajectory, world points.
    pub trajectory: Vec<(f64, f64)>,
    /// Planned paths, world points each.
    pub plans: Vec<Vec<(f64, f64)>>,
}

/// The driven trajectory on the images.
pub(crate) const DRIVEN: Rgb = [0, 150, 60];
/// Paths planned on the way, on the images.
pub(crate) const REPLANNED: Rgb = [190, 120, 230];

impl Overlay {
    /// Draws the plans, then the trajectory over them.
    pub(crate) fn draw(&self, fig: &mut Figure) {
        for p in &self.plans {
            fig.polyline(p, REPLANNED);
        }
        fig.polyline(&self.trajectory, DRIVEN);
    }

    /// The legend entries of what [`Overlay::draw`] draws.
    pub(crate) fn legend(&self) -> Vec<(String, Fill)> {
        vec![
            ("driven (true pose)".into(), DRIVEN.into()),
            (
                format!("{} of the paths planned on the way", self.plans.len()),
                REPLANNED.into(),
            ),
        ]
    }
}

/// Writes `truth_elevation.png`, `elevation_error.png` and `decisions.png` (with a closed-loop run's
/// `overlay`).
///
/// # Errors
/// A failed write.
pub(crate) fn write(
    out_dir: &Path,
    s: &Scenario,
    map: &Map,
    truth: &TruthRaster,
    evaluation: &Evaluation,
    overlay: Option<&Overlay>,
    formats: ImageFormats,
) -> Result<Vec<PathBuf>> {
    let metrics = &evaluation.metrics;
    let drive = drive_polyline(s);
    let with_drive = |mut fig: Figure| {
        fig.polyline(&drive, DRIVE);
        fig
    };
    let mut files = Vec::new();

    let fig = truth_elevation_figure(truth, &format!("{}: true elevation (drive in blue)", s.name));
    files.extend(save(
        &out_dir.join("truth_elevation.png"),
        with_drive(fig).canvas(),
        formats,
    )?);

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
        &truth.window,
        &format!(
            "{}: elevation error (RMSE {:.3} m)",
            s.name, metrics.elevation_rmse_m
        ),
        |c| error_of(c).map_or(NO_DATA, |e| Colormap::Diverging.color((e + span) / (2.0 * span))),
        &legend,
    );
    files.extend(save(
        &out_dir.join("elevation_error.png"),
        with_drive(fig).canvas(),
        formats,
    )?);

    let fig = decisions_figure(s, map.geometry(), evaluation, &s.name, overlay);
    files.extend(save(&out_dir.join("decisions.png"), fig.canvas(), formats)?);
    Ok(files)
}

/// `decisions.png`: every cell's verdict, the drive, the obstacles' footprints and names, and the path planned
/// on the map; titled `title` with the counts.
pub(crate) fn decisions_figure(
    s: &Scenario,
    geometry: &oeg::GridGeometry,
    evaluation: &Evaluation,
    title: &str,
    overlay: Option<&Overlay>,
) -> Figure {
    let (metrics, plan, verdicts) = (&evaluation.metrics, &evaluation.plan, &evaluation.verdicts);
    let mut classes: Vec<(String, Fill)> = DECISION_CLASSES
        .iter()
        .map(|(_, n, c)| ((*n).to_string(), *c))
        .collect();
    classes.push(("drive".into(), DRIVE.into()));
    classes.push(("obstacle footprint".into(), OUTLINE.into()));
    classes.push((
        if plan.map_plan.is_some() {
            "path planned on the map".into()
        } else {
            "no path on the map".into()
        },
        PLAN.into(),
    ));
    if let Some(o) = overlay {
        classes.extend(o.legend());
    }
    let legend = Legend::Classes(classes);
    let fig = Figure::new(
        &verdicts.window,
        &format!(
            "{title}: {} unsafe, {} over-cautious, {} uncertain cells",
            metrics.unsafe_cells, metrics.overcautious_cells, metrics.uncertain_cells
        ),
        |c| {
            verdicts
                .offset(c)
                .map_or(NO_DATA.into(), |k| verdict_fill(verdicts.verdict[k]))
        },
        &legend,
    );
    let mut fig = fig;
    if let Some(o) = overlay {
        o.draw(&mut fig);
    }
    fig.polyline(&drive_polyline(s), DRIVE);
    // The scene under the decisions: every obstacle's footprint, and the names of the named ones.
    for o in &s.obstacles {
        let outline = crate::judge::obstacles::footprint_outline(o);
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
        fig.polyline(&crate::judge::plan_check::polyline(p, geometry), PLAN);
    }
    fig
}

/// The map's decisions at an event of a closed-loop run, judged against the truth, with the trajectory up
/// to the event and a marker where the robot was.
pub(crate) fn event_figure(
    s: &Scenario,
    truth: &TruthRaster,
    decisions: &[oeg::Traversability],
    (trajectory, at): (Vec<(f64, f64)>, (f64, f64)),
    title: &str,
) -> Figure {
    let verdicts = crate::judge::verdict::Verdicts::from_classes(truth, decisions.to_vec());
    let mut classes: Vec<(String, Fill)> = DECISION_CLASSES
        .iter()
        .map(|(_, n, c)| ((*n).to_string(), *c))
        .collect();
    classes.push(("driven so far".into(), DRIVEN.into()));
    classes.push(("obstacle footprint".into(), OUTLINE.into()));
    let mut fig = Figure::new(
        &verdicts.window,
        title,
        |c| {
            verdicts
                .offset(c)
                .map_or(NO_DATA.into(), |k| verdict_fill(verdicts.verdict[k]))
        },
        &Legend::Classes(classes),
    );
    for o in &s.obstacles {
        fig.polyline(&crate::judge::obstacles::footprint_outline(o), OUTLINE);
    }
    fig.polyline(&trajectory, DRIVEN);
    fig.marker(at.0, at.1, DRIVEN);
    fig
}

/// `observability.png`: per cell, what a ray of the sensors could have told (a ray ended on the cell: its
/// step; a ray crossed its band between a step and the robot's height: its clearance), and the truly blocked
/// cells no ray could have told about.
pub(crate) fn observability_figure(
    s: &Scenario,
    observability: &sim::observability::Observability,
    verdicts: &crate::judge::verdict::Verdicts,
) -> Figure {
    const BOTH: Rgb = [255, 255, 255];
    const STEP_ONLY: Rgb = [150, 200, 150];
    const BAND_ONLY: Rgb = [150, 170, 230];
    const NEITHER: Rgb = [200, 200, 200];
    const BLIND: Rgb = [150, 0, 150];
    let classes = vec![
        ("step and clearance observable".to_string(), BOTH.into()),
        ("step only (a ray ended here)".to_string(), STEP_ONLY.into()),
        (
            "clearance only (a ray crossed the band)".to_string(),
            BAND_ONLY.into(),
        ),
        ("no ray told anything".to_string(), NEITHER.into()),
        (
            "truly blocked, no ray could tell (blind)".to_string(),
            BLIND.into(),
        ),
        ("obstacle footprint".to_string(), OUTLINE.into()),
    ];
    let o = observability;
    let mut fig = Figure::new(
        &o.window,
        &format!("{}: what the sensors could see ({} rays)", s.name, o.num_rays),
        |c| {
            let Some(k) = o.window.region().offset(c) else {
                return NO_DATA;
            };
            if verdicts.window == o.window && verdicts.unobservable[k] {
                return BLIND;
            }
            match (o.step[k], o.clearance[k]) {
                (true, true) => BOTH,
                (true, false) => STEP_ONLY,
                (false, true) => BAND_ONLY,
                (false, false) => NEITHER,
            }
        },
        &Legend::Classes(classes),
    );
    for obstacle in &s.obstacles {
        fig.polyline(&crate::judge::obstacles::footprint_outline(obstacle), OUTLINE);
    }
    fig.polyline(&drive_polyline(s), DRIVE);
    fig
}
