//! `oeg run`: one scenario end to end.

use std::path::{Path, PathBuf};

use oeg_eval::jobs::run::{DEFAULT_SCENARIO, summary_lines};
use oeg_eval::pipeline::{RunOptions, run_scenario};
use oeg_eval::progress::Progress;

/// `oeg run`'s arguments.
#[derive(clap::Args, Debug)]
pub(crate) struct RunArgs {
    /// A scenario file (.toml).
    scenario: PathBuf,
    /// Output folder [default: out/<scenario name>].
    #[arg(long)]
    out: Option<PathBuf>,
    /// Replace the scenario's seed.
    #[arg(long)]
    seed: Option<u64>,
    /// Override a scenario value by its dotted key, e.g. --set map.resolution_m=0.1 or
    /// --set sensors.0.noise.dropout_probability=0.05 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    overrides: Vec<String>,
    /// Also map the same sensor log with this model preset (`paper`, `static` or `robust`) and write its report
    /// into OUT/PRESET/ with comparison.csv and decisions_comparison.png side by side.
    #[arg(long, value_name = "PRESET")]
    compare: Option<oeg::MapPreset>,
    /// A closed-loop run's planner: this program plans at every replanning time instead of the scenario's
    /// planner (docs/planner-protocol.md). One string, split into words like a shell does (quotes keep
    /// spaces), with no variables or globs.
    #[arg(long, value_name = "COMMAND")]
    planner_command: Option<String>,
    /// Let the scenario's own `[navigation] command` run: a scenario file never runs a program without it.
    #[arg(long)]
    allow_scenario_command: bool,
    /// Also write recording.mcap, for Foxglove: the robot's true and estimated pose, each sensor's scans, the
    /// map's layers every second of simulated time, the truth, the planned paths and the events
    /// (docs/mcap.md).
    #[arg(long)]
    mcap: bool,
    /// Also write each figure as SVG beside its PNG, for papers: lines and text as vectors, the map's cells
    /// as an image inside it.
    #[arg(long)]
    svg: bool,
}

impl RunArgs {
    /// What `oeg` with no arguments runs: the default scenario, with the paper's model and the recommended one
    /// side by side.
    pub(crate) fn default_run() -> Self {
        Self {
            scenario: PathBuf::from(DEFAULT_SCENARIO),
            out: None,
            seed: None,
            overrides: Vec::new(),
            compare: Some(oeg::MapPreset::Robust),
            planner_command: None,
            allow_scenario_command: false,
            mcap: false,
            svg: false,
        }
    }
}

/// Runs the scenario, prints its summary, fails when an expectation is not met.
pub(crate) fn run(args: &RunArgs) -> anyhow::Result<()> {
    if !args.scenario.exists() && args.scenario == Path::new(DEFAULT_SCENARIO) {
        anyhow::bail!(
            "{DEFAULT_SCENARIO} not found: run `oeg` from the repository root, or give a scenario: oeg run FILE"
        );
    }
    let options = RunOptions {
        scenario: args.scenario.clone(),
        out_dir: args.out.clone(),
        seed: args.seed,
        overrides: args.overrides.clone(),
        compare: args.compare,
        planner_command: args
            .planner_command
            .as_deref()
            .map(oeg_eval::navigation::external::split_command)
            .transpose()
            .map_err(|e| anyhow::anyhow!("--planner-command: {e}"))?,
        allow_scenario_command: args.allow_scenario_command,
        mcap: args.mcap,
        figures: oeg_eval::figures::ImageFormats { svg: args.svg },
        planner_callback: None,
    };
    let report = run_scenario(&options, &Progress::new(0, "scans"))?;
    for line in summary_lines(&report) {
        say!("{line}");
    }
    super::fail_on_expectations(&report.failed)
}
