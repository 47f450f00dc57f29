//! `oeg run`: one scenario through the whole pipeline ([`crate::pipeline::run_scenario`]), and the lines
//! that tell the user what it found.

use crate::pipeline::RunReport;

/// What `oeg` with no arguments runs (relative to the repository root).
pub const DEFAULT_SCENARIO: &str = "scenarios/default.toml";

/// The run's summary: what each model's map made the robot do, its wrong cells and its regression bounds
/// (`Outcome::lines`), then the sensor log, the wall times and the report's path.
pub fn summary_lines(report: &RunReport) -> Vec<String> {
    let m = &report.metrics;
    let mut lines: Vec<String> = report.outcomes.iter().flat_map(|o| o.lines()).collect();
    let t = &report.timing;
    lines.push(format!(
        "{}: {} scans, {} rays; coverage {:.1} %, elevation RMSE {:.3} m; simulation {:.2} s, map {:.2} s, \
         truth {:.2} s; report: {}",
        m.scenario,
        m.num_scans,
        m.num_rays,
        100.0 * m.coverage,
        m.elevation_rmse_m,
        t.simulation_wall_time_s,
        t.map_wall_time_s,
        t.truth_wall_time_s,
        report.out_dir.join("report.html").display()
    ));
    lines
}
