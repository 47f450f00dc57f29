//! `oeg check-path`: a path checked against a scenario's truth with the robot's footprint.

use std::path::PathBuf;

use oeg_eval::jobs::check_path::{CheckPathJob, run_job};

/// `oeg check-path`'s arguments.
#[derive(clap::Args, Debug)]
pub(crate) struct CheckPathArgs {
    /// The scenario whose world is the truth (.toml).
    scenario: PathBuf,
    /// The path: lines of x,y in metres, world frame, an optional header (x_m,y_m) and # comments.
    path: PathBuf,
    /// A map file (map.oeg) to judge along the path too: the crossed cells by the map's verdict.
    #[arg(long)]
    map: Option<PathBuf>,
    /// Override a scenario value by its dotted key (repeatable), as `oeg run --set`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    overrides: Vec<String>,
    /// Output folder for path_check.json.
    #[arg(long, default_value = "out/check_path")]
    out: PathBuf,
}

/// Checks the path, prints what it found, fails when the footprint touches a truly blocked cell.
pub(crate) fn run(args: &CheckPathArgs) -> anyhow::Result<()> {
    let job = CheckPathJob {
        scenario: args.scenario.clone(),
        overrides: args.overrides.clone(),
        path: args.path.clone(),
        map: args.map.clone(),
        out_dir: args.out.clone(),
    };
    let (check, files) = run_job(&job)?;
    say!(
        "{}: a path of {} points, {:.2} m, checked at {} poses with the footprint {:?} m",
        check.scenario,
        check.num_points,
        check.length_m,
        check.num_poses,
        check.footprint_m
    );
    if check.first_contact.is_none() {
        say!("no contact: the footprint never touches a truly blocked cell along the path");
    }
    match &check.closest_approach_m {
        Some(d) => say!(
            "closest approach to a truly blocked cell: {d:.3} m, {:.2} m along the path",
            check.closest_approach_along_m.unwrap_or(f64::NAN)
        ),
        None => say!("no truly blocked cell within 2 m of the footprint"),
    }
    let cells: Vec<String> = check
        .cells_by_truth
        .iter()
        .map(|(k, n)| format!("{n} {k}"))
        .collect();
    say!("cells crossed, by the truth: {}", cells.join(", "));
    if let Some(by) = &check.cells_by_verdict {
        let cells: Vec<String> = by.iter().map(|(k, n)| format!("{n} {k}")).collect();
        say!("cells crossed, by the map's verdict: {}", cells.join(", "));
    }
    for f in &files {
        say!("wrote {}", f.display());
    }
    if let Some(c) = &check.first_contact {
        anyhow::bail!(
            "the footprint touches `{}` {:.2} m along the path, at ({:.3}, {:.3}) m heading {:.1} degrees",
            c.obstacle,
            c.along_m,
            c.x_m,
            c.y_m,
            c.yaw_deg
        );
    }
    Ok(())
}
