//! `oeg`: the Occupancy-Elevation Grid testbed's command-line program. Thin: it parses arguments (one file per
//! command in `cli/`) and calls the jobs of the `oeg_eval` crate.

use std::process::ExitCode;

/// `println!` that ignores a closed standard output (`oeg run ... | head -1`) instead of panicking.
macro_rules! say {
    ($($arg:tt)*) => {{
        let _ = std::io::Write::write_fmt(&mut std::io::stdout(), format_args!("{}\n", format_args!($($arg)*)));
    }};
}

mod cli;

use clap::{Parser, Subcommand};

#[derive(Parser, Debug)]
#[command(
    name = "oeg",
    version,
    about = "Occupancy-Elevation Grid mapping and evaluation",
    after_help = "With no command, `oeg` runs scenarios/default.toml with the paper's model and the robust \
                  preset side by side (`oeg run scenarios/default.toml --compare robust`) and writes \
                  out/default/report.html. The guide: docs/guide.md."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Build a map from recorded range data (scan graphs, point clouds, sensor logs, ROS 2 bags, KITTI and
    /// DynamicMap sequences); write map.oeg, layer images, summary.json and timing.json.
    Map(cli::map::MapArgs),
    /// Plan a path on a saved map (map.oeg) from one point to another: write plan.json, path.csv and
    /// plan.png. Exit status 0 with a path, 3 with none (the reason is printed and in plan.json), 1 on an
    /// error.
    Plan(cli::plan::PlanArgs),
    /// Check a path (x,y lines in metres, e.g. one a planner logged in the field) against a scenario's truth
    /// with the robot's footprint: the first contact, the closest approach, the cells crossed; exit non-zero
    /// on a contact.
    CheckPath(cli::check_path::CheckPathArgs),
    /// Score a map made by another tool (.npy layers, a nav2 map, or a grid_map in a ROS 2 bag) against a
    /// scenario's truth, as `oeg run` scores its own: verdict counts, per-obstacle table, planner check
    /// (docs/scoring.md).
    Score(Box<cli::score::ScoreArgs>),
    /// Print a saved map's header and statistics.
    Inspect(cli::inspect::InspectArgs),
    /// Run a scenario end to end: simulate, map, compare with the truth, write the report; exit non-zero when
    /// the scenario's expectations are not met.
    Run(cli::run::RunArgs),
    /// Run many scenarios (files, or folders of .toml files): print a table, write suite.csv and suite.json,
    /// exit non-zero if any fails its expectations.
    Suite(cli::suite::SuiteArgs),
    /// Check scenario files: print one line per file, exit non-zero if any is invalid.
    Validate(cli::validate::ValidateArgs),
    /// Draw a scenario's true elevation and decisions, its drive and sensor mounts, before running it.
    Preview(cli::preview::PreviewArgs),
    /// Run a scenario's drive and sensors and record every scan (a sensor log, or an OctoMap scan graph).
    Record(cli::record::RecordArgs),
    /// Studies of many runs: axes of settings, seeds and randomized scenes, with confidence intervals
    /// (docs/sweep-format.md).
    #[command(subcommand)]
    Sweep(cli::sweep::SweepCommand),
    /// Map the built-in demonstration scans: the map on its own, with no simulation.
    Demo(cli::demo::DemoArgs),
}

/// The error and its causes on one line, each cause once: the library errors already name their source in
/// their message (`file: No such file or directory`), so a cause whose text is already there is not repeated.
fn error_text(e: &anyhow::Error) -> String {
    let mut text = e.to_string();
    for cause in e.chain().skip(1) {
        let cause = cause.to_string();
        if !text.contains(&cause) {
            text.push_str(": ");
            text.push_str(&cause);
        }
    }
    text
}

fn main() -> ExitCode {
    let result = match Cli::parse().command {
        Some(Command::Map(args)) => cli::map::run(&args),
        Some(Command::Plan(args)) => cli::plan::run(&args),
        Some(Command::Inspect(args)) => cli::inspect::run(&args),
        Some(Command::CheckPath(args)) => cli::check_path::run(&args),
        Some(Command::Score(args)) => cli::score::run(&args),
        Some(Command::Run(args)) => cli::run::run(&args),
        Some(Command::Suite(args)) => cli::suite::run(&args),
        Some(Command::Validate(args)) => cli::validate::run(&args),
        Some(Command::Preview(args)) => cli::preview::run(&args),
        Some(Command::Record(args)) => cli::record::run(&args),
        Some(Command::Sweep(command)) => cli::sweep::run(command),
        Some(Command::Demo(args)) => cli::demo::run(&args),
        None => cli::run::run(&cli::run::RunArgs::default_run()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => match e.downcast_ref::<cli::Status>() {
            Some(status) => {
                eprintln!("{status}");
                ExitCode::from(status.code)
            }
            None => {
                eprintln!("error: {}", error_text(&e));
                ExitCode::FAILURE
            }
        },
    }
}
