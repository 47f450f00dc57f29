//! `oeg validate` and `oeg preview`: check scenario files, and draw a scenario's truth before running it.

use std::path::{Path, PathBuf};

use sim::scenario::{self, LoadedScenario};
use sim::world::World;

use crate::error::Result;
use crate::figures::{Figure, ImageFormats, Legend, NO_DATA, Rgb, save};
use crate::judge::verdict::TruthClass;
use crate::output::Staged;

/// Sample points per cell side for the preview's truth (the evaluation uses more).
pub const PREVIEW_SAMPLES_PER_SIDE: u32 = 2;

/// One line describing a valid scenario.
pub fn describe(loaded: &LoadedScenario) -> String {
    let s = &loaded.scenario;
    let size = [
        s.map.max_xy_m[0] - s.map.min_xy_m[0],
        s.map.max_xy_m[1] - s.map.min_xy_m[1],
    ];
    format!(
        "{}: ok: `{}`, {:.0} s, map {:.1} x {:.1} m at {} m, {} obstacles, {} actors, {} sensors, robot `{}` {:.2} m tall",
        loaded.source.path.display(),
        s.name,
        s.duration_s,
        size[0],
        size[1],
        s.map.resolution_m,
        s.obstacles.len(),
        s.actors.len(),
        s.sensors.len(),
        loaded.robot.name,
        loaded.robot.height_m()
    )
}

/// Loads a scenario and builds its world, as `oeg validate` does.
///
/// # Errors
/// The scenario's error (file, line, column, what was expected).
pub fn validate(path: &Path) -> Result<LoadedScenario> {
    let loaded = scenario::load(path)?;
    crate::pipeline::check_expectations(&loaded, &loaded.source.text)?;
    World::new(&loaded)?;
    Ok(loaded)
}

/// The truth's classes (`oeg_eval::verdict::TruthClass`) with their legend text and colour.
pub const TRUTH_CLASSES: [(TruthClass, &str, Rgb); 5] = [
    (TruthClass::OffTerrain, "off the terrain", NO_DATA),
    (TruthClass::Drivable, "drivable", [255, 255, 255]),
    (TruthClass::Step, "step blocked", [200, 40, 40]),
    (
        TruthClass::PassableUnder,
        "under structure: passable",
        [90, 140, 230],
    ),
    (TruthClass::TooLow, "under structure: too low", [120, 30, 120]),
];

/// Writes `preview_elevation.png` and `preview_decisions.png` for a scenario (as `formats` asks): the truth
/// at time 0 with the people left out, the drive and the sensor mounts. Returns the files written.
///
/// # Errors
/// A bad scenario, or a failed write.
pub fn preview(path: &Path, out_dir: &Path, formats: ImageFormats) -> Result<Vec<PathBuf>> {
    let loaded = validate(path)?;
    let s = &loaded.scenario;
    let inputs = loaded.files();
    let inputs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
    let staged = Staged::begin(out_dir, &inputs)?;
    let world = World::new(&loaded)?;
    let truth = crate::pipeline::truth_sampled(
        &loaded,
        &world,
        PREVIEW_SAMPLES_PER_SIDE,
        &crate::progress::Progress::hidden(),
    )?;

    let drive = crate::figures::comparison::drive_polyline(s);
    let mounts: Vec<(f64, f64)> = s
        .sensors
        .iter()
        .filter_map(|m| world.world_from_link(&m.mount_link))
        .map(|p| (p.translation.x, p.translation.y))
        .collect();
    let overlay = |fig: &mut Figure| {
        fig.polyline(&drive, [230, 30, 30]);
        if let Some(&(x, y)) = drive.first() {
            fig.marker(x, y, [230, 30, 30]);
        }
        for &(x, y) in &mounts {
            fig.marker(x, y, [255, 200, 0]);
        }
    };

    let title = format!("{}: true elevation (drive red, sensors yellow)", s.name);
    let mut fig = crate::figures::comparison::truth_elevation_figure(&truth, &title);
    overlay(&mut fig);
    let work = || -> Result<_> {
        let mut files = save(&staged.dir().join("preview_elevation.png"), fig.canvas(), formats)?;

        let legend = Legend::Classes(
            TRUTH_CLASSES
                .iter()
                .map(|(_, n, c)| ((*n).to_string(), (*c).into()))
                .collect(),
        );
        let title = format!(
            "{}: true decisions (step {} m, height {} m)",
            s.name, truth.profile.max_step_m, truth.profile.height_m
        );
        let mut fig = Figure::new(
            &truth.window,
            &title,
            |c| {
                let Some(k) = truth.window.region().offset(c) else {
                    return NO_DATA;
                };
                let class = TruthClass::of(&truth, k);
                TRUTH_CLASSES
                    .iter()
                    .find(|(t, ..)| *t == class)
                    .map_or(NO_DATA, |(_, _, rgb)| *rgb)
            },
            &legend,
        );
        overlay(&mut fig);
        files.extend(save(
            &staged.dir().join("preview_decisions.png"),
            fig.canvas(),
            formats,
        )?);
        Ok(files)
    };
    let files = staged.explained(work())?;
    let files = files.iter().map(|f| staged.final_path(f)).collect();
    staged.commit()?;
    Ok(files)
}
