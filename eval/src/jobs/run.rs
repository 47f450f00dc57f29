//! `oeg run`: one scenario through the whole pipeline ([`crate::pipeline::run_scenario`]), and the lines
//! that tell the user what it found.

use crate::pipeline::RunReport;

/// What `oeg` with no arguments runs (relative to the repository root).
pub const DEFAULT_SCENARIO: &str = "scenarios/default.toml";

/// The run's summary: one line for the scenario's model, one for the compared model if there is one, and one
/// for the wall times and the output folder.
pub fn summary_lines(report: &RunReport) -> Vec<String> {
    let m = &report.metrics;
    let mut lines = vec![format!(
        "{}: {} scans, {} rays; coverage {:.1} %, elevation RMSE {:.3} m; step cells: {} unsafe, {} over-cautious; \
         clearance cells: {} unsafe, {} over-cautious",
        m.scenario,
        m.num_scans,
        m.num_rays,
        100.0 * m.coverage,
        m.elevation_rmse_m,
        m.unsafe_step_cells,
        m.overcautious_step_cells,
        m.unsafe_clearance_cells,
        m.overcautious_clearance_cells
    )];
    if let Some((preset, c)) = &report.compared {
        lines.push(format!(
            "{} model on the same sensor log: step cells {} unsafe, {} over-cautious; clearance cells {} unsafe, \
             {} over-cautious; {} uncertain cells; plan {} ({} unsafe path cells)",
            preset.name(),
            c.unsafe_step_cells,
            c.overcautious_step_cells,
            c.unsafe_clearance_cells,
            c.overcautious_clearance_cells,
            c.uncertain_cells,
            if c.plan_found { "found" } else { "not found" },
            c.plan_unsafe_cells
        ));
    }
    let t = &report.timing;
    lines.push(format!(
        "simulation {:.2} s ({:.2} M rays/s), map {:.2} s ({:.2} M rays/s), truth {:.2} s; report: {}",
        t.simulation_wall_time_s,
        t.simulation_rays_per_s / 1e6,
        t.map_wall_time_s,
        t.map_rays_per_s / 1e6,
        t.truth_wall_time_s,
        report.out_dir.join("report.html").display()
    ));
    lines
}
