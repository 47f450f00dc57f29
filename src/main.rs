//! `oeg`: the Occupancy-Elevation Grid testbed's command-line program. Thin: it parses arguments and calls
//! the `eval` crate.

use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

/// `println!` that ignores a closed standard output (`oeg run ... | head -1`) instead of panicking.
macro_rules! say {
    ($($arg:tt)*) => {{
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

use clap::{Parser, Subcommand, ValueEnum};
use eval::mapping::{MapJob, MapReport};
use eval::progress::Progress;
use oeg::MapConfig;
use oeg::io::pcd::PcdOptions;

#[derive(Parser, Debug)]
#[command(
    name = "oeg",
    version,
    about = "Occupancy-Elevation Grid mapping and evaluation"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Build a map from OctoMap scan graphs (.graph) and point clouds (.pcd); write map.oeg, layer images,
    /// summary.json and timing.json.
    Map(MapArgs),
    /// Plan a path on a saved map (map.oeg) from one point to another: write plan.json, path.csv and
    /// plan.png.
    Plan(PlanArgs),
    /// Print a saved map's header and statistics.
    Inspect {
        /// A map file written by `oeg map` (map.oeg).
        map: PathBuf,
    },
    /// Run a scenario end to end: simulate, map, compare with the truth, write the report; exit non-zero when
    /// the scenario's expectations are not met.
    Run(RunArgs),
    /// Run many scenarios (files, or folders of .toml files): print a table, write suite.csv and suite.json,
    /// exit non-zero if any fails its expectations.
    Suite {
        /// Scenario files or folders.
        #[arg(required = true)]
        paths: Vec<PathBuf>,
        /// Output folder: one sub-folder per scenario, plus suite.csv and suite.json.
        #[arg(long, default_value = "out/suite")]
        out: PathBuf,
        /// Override a value in every scenario (repeatable), as for `oeg run`.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        overrides: Vec<String>,
        /// Scenarios run at once, on as many threads [default: RAYON_NUM_THREADS, else one per core]. Results
        /// do not depend on it.
        #[arg(long, value_parser = clap::value_parser!(u16).range(1..=256))]
        jobs: Option<u16>,
    },
    /// Check scenario files: print one line per file, exit non-zero if any is invalid.
    Validate {
        /// Scenario files (.toml).
        #[arg(required = true)]
        scenarios: Vec<PathBuf>,
    },
    /// Draw a scenario's true elevation and decisions, its drive and sensor mounts, before running it.
    Preview {
        /// A scenario file (.toml).
        scenario: PathBuf,
        /// Output folder.
        #[arg(long, default_value = "out/preview")]
        out: PathBuf,
    },
    /// Run a scenario's drive and sensors and record every scan (a sensor log, or an OctoMap scan graph).
    Record {
        /// A scenario file (.toml).
        scenario: PathBuf,
        /// The file to write (.oeglog, or .graph with --format graph).
        #[arg(long)]
        out: PathBuf,
        /// log: the testbed's sensor log (both poses, no-returns, range errors); graph: OctoMap's scan graph
        /// (estimated pose, hits only) for other mappers.
        #[arg(long, value_enum, default_value_t = FormatArg::Log)]
        format: FormatArg,
        /// Replace the scenario's seed.
        #[arg(long)]
        seed: Option<u64>,
    },
    /// Studies of many runs: axes of settings, seeds and randomized scenes, with confidence intervals
    /// (docs/sweep-format.md).
    #[command(subcommand)]
    Sweep(SweepCommand),
    /// Map the built-in demonstration scans (what `oeg` with no arguments does).
    Demo {
        /// Output folder.
        #[arg(long, default_value = "out/demo")]
        out: PathBuf,
    },
}

#[derive(Subcommand, Debug)]
enum SweepCommand {
    /// Print the plan: every run's id, axis values and seed, and how many simulations they share.
    Plan {
        /// A sweep file (.toml).
        file: PathBuf,
        /// Override a value in every run (repeatable), as for `oeg run`; the axes still set their keys.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        overrides: Vec<String>,
    },
    /// Run the plan (or one shard of it) in parallel; killed and started again, it resumes.
    Run {
        /// A sweep file (.toml).
        file: PathBuf,
        /// Override a value in every run (repeatable), as for `oeg run`; give the same on a resumed run.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        overrides: Vec<String>,
        /// Output folder: plan.json, runs/<id>/, runs.csv, runs.jsonl, obstacles.csv.
        #[arg(long)]
        out: PathBuf,
        /// Simulations at once [default: RAYON_NUM_THREADS, else one per core]. Results do not depend on it.
        #[arg(long, value_parser = clap::value_parser!(u16).range(1..=256))]
        jobs: Option<u16>,
        /// Run only shard I of N (1-based; runs are dealt by id). Without it: SLURM_ARRAY_TASK_ID within
        /// SLURM_ARRAY_TASK_MIN..MAX, or JOB_COMPLETION_INDEX with --shards, or the whole plan.
        #[arg(long, value_name = "I/N", value_parser = eval::sweep::execute::parse_shard)]
        shard: Option<(usize, usize)>,
        /// The number of shards of a Kubernetes Indexed Job (its completions), with JOB_COMPLETION_INDEX.
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100_000))]
        shards: Option<u32>,
        /// Simulate every run on its own, even runs that could share a simulation (to measure sharing).
        #[arg(long)]
        simulate_each: bool,
    },
    /// Combine the outputs of a sweep's shards into one set of rows; fails naming any missing or duplicated
    /// run.
    Merge {
        /// The shards' output folders.
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
    },
    /// Measure a study: run the whole plan into temporary folders, with shared simulations and with one per run,
    /// in turn, and print wall times, runs per hour and the speed-up of sharing.
    Bench {
        /// A sweep file (.toml).
        file: PathBuf,
        /// Override a value in every run (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        overrides: Vec<String>,
        /// Simulations at once [default: RAYON_NUM_THREADS, else one per core].
        #[arg(long, value_parser = clap::value_parser!(u16).range(1..=256))]
        jobs: Option<u16>,
        /// Repetitions of each way.
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u16).range(1..=100))]
        repeat: u16,
        /// Only the shared way (runs per hour), without the one-simulation-per-run comparison.
        #[arg(long)]
        no_compare: bool,
    },
    /// Write summary.csv (means and 95 % intervals) and plots of a sweep's output folder; refuses a folder
    /// that does not cover the whole plan (a shard, an unfinished run) unless --partial.
    Report {
        /// A folder written by `oeg sweep run` or `oeg sweep merge`.
        dir: PathBuf,
        /// Summarise the finished runs of an incomplete study; every plot's title says "partial: N of M runs".
        #[arg(long)]
        partial: bool,
    },
}

fn run_sweep(command: SweepCommand) -> anyhow::Result<()> {
    use eval::sweep::{Plan, Sweep, execute};
    match command {
        SweepCommand::Plan { file, overrides } => {
            let plan = Plan::new(Sweep::load(&file)?.with_overrides(&overrides)?)?;
            say!(
                "{}: {} runs, {} simulations",
                plan.sweep.spec.name,
                plan.runs.len(),
                plan.num_groups()
            );
            for r in &plan.runs {
                say!(
                    "{} {} replicate {} seed {}: {}",
                    r.id,
                    r.scenario,
                    r.replicate,
                    r.seed,
                    eval::sweep::plan::describe(&r.axis_values)
                );
            }
        }
        SweepCommand::Run {
            file,
            overrides,
            out,
            jobs,
            shard,
            shards,
            simulate_each,
        } => {
            let plan = Plan::new(Sweep::load(&file)?.with_overrides(&overrides)?)?;
            let shard = match shard {
                Some(s) => Some(s),
                None => execute::shard_from_env(|k| std::env::var(k).ok(), shards.map(|n| n as usize))
                    .map_err(|e| anyhow::anyhow!("the shard: {e}"))?,
            };
            let options = execute::RunOptions {
                out_dir: out,
                shard,
                jobs: jobs.map_or_else(eval::suite::default_jobs, usize::from),
                simulate_each,
            };
            let progress = Progress::new(0, "runs");
            let start = std::time::Instant::now();
            let summary = execute::run(&plan, &options, &progress)?;
            say!(
                "{}{}: {} runs, {} finished before, {} run now in {} simulations ({} errors) in {:.1} s",
                plan.sweep.spec.name,
                shard.map(|(i, n)| format!(" shard {i}/{n}")).unwrap_or_default(),
                summary.num_selected,
                summary.num_already_done,
                summary.num_run,
                summary.num_simulations,
                summary.num_errors,
                start.elapsed().as_secs_f64()
            );
            for f in summary.files {
                say!("wrote {}", f.display());
            }
        }
        SweepCommand::Merge { dirs, out } => {
            let summary = eval::sweep::merge::merge(&dirs, &out)?;
            say!("merged {} runs from {} folders", summary.num_runs, dirs.len());
            for f in summary.files {
                say!("wrote {}", f.display());
            }
        }
        SweepCommand::Bench {
            file,
            overrides,
            jobs,
            repeat,
            no_compare,
        } => {
            let plan = Plan::new(Sweep::load(&file)?.with_overrides(&overrides)?)?;
            let jobs = jobs.map_or_else(eval::suite::default_jobs, usize::from);
            let f = eval::sweep::bench::bench(&plan, jobs, usize::from(repeat), !no_compare)?;
            say!(
                "{}: {} runs, {jobs} jobs, {repeat} repetitions",
                plan.sweep.spec.name,
                f.num_runs
            );
            for line in f.lines() {
                say!("{line}");
            }
        }
        SweepCommand::Report { dir, partial } => {
            let report = eval::sweep::report::report(&dir, partial)?;
            say!(
                "{}: {} of the plan's {} runs{}",
                dir.display(),
                report.num_covered,
                report.num_planned,
                if report.num_covered < report.num_planned {
                    " (a partial study)"
                } else {
                    ""
                }
            );
            for f in report.files {
                say!("wrote {}", f.display());
            }
        }
    }
    Ok(())
}

#[derive(clap::Args, Debug)]
struct RunArgs {
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
    /// Also map the same sensor log with this model preset (`paper` or `robust`) and write its report into
    /// OUT/PRESET/ with comparison.csv and decisions_comparison.png side by side.
    #[arg(long, value_name = "PRESET")]
    compare: Option<oeg::MapPreset>,
}

#[derive(clap::Args, Debug)]
struct PlanArgs {
    /// A map file (map.oeg, from `oeg map` or `oeg run`).
    map: PathBuf,
    /// Start, world frame, metres: X,Y.
    #[arg(long, value_parser = parse_xy, allow_hyphen_values = true)]
    from: (f64, f64),
    /// Goal, world frame, metres: X,Y.
    #[arg(long, value_parser = parse_xy, allow_hyphen_values = true)]
    to: (f64, f64),
    /// Output folder (created if needed).
    #[arg(long, default_value = "out/plan")]
    out: PathBuf,
    /// A setting by its scenario key (repeatable): planner.inflation_radius_m (0.25, the Pioneer 3-AT's
    /// inscribed radius), planner.unknown (avoid, inflate or drivable), robot.max_step_m (0.035),
    /// robot.height_m (0.46), map.traversability.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    overrides: Vec<String>,
}

/// `X,Y` in metres, as `--from` and `--to` take them.
fn parse_xy(text: &str) -> Result<(f64, f64), String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let number = |s: &str| {
        s.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("expected X,Y in metres (two finite numbers), got `{text}`"))
    };
    match parts.as_slice() {
        [x, y] => Ok((number(x)?, number(y)?)),
        _ => Err(format!(
            "expected X,Y in metres (two numbers separated by a comma), got `{text}`"
        )),
    }
}

fn run_plan(args: &PlanArgs) -> anyhow::Result<()> {
    let settings = eval::settings::plan_settings(&args.overrides).map_err(anyhow::Error::msg)?;
    let job = eval::plan::PlanJob {
        map: args.map.clone(),
        from_xy_m: args.from,
        to_xy_m: args.to,
        out_dir: args.out.clone(),
        options: settings.planner,
        profile: settings.robot,
        rule: settings.map.traversability,
    };
    let (summary, files) = eval::plan::run_job(&job)?;
    if summary.plan_found {
        say!(
            "path found: {:.2} m, {} cells",
            summary.plan_length_m,
            summary.num_path_cells
        );
    } else {
        say!(
            "no path from ({}, {}) to ({}, {}) m",
            args.from.0,
            args.from.1,
            args.to.0,
            args.to.1
        );
    }
    for f in files {
        say!("wrote {}", f.display());
    }
    Ok(())
}

#[derive(clap::Args, Debug)]
struct MapArgs {
    /// Input files: .graph (OctoMap scan graph), .pcd (ascii, binary or binary_compressed), .oeglog (a
    /// sensor log of `oeg record`).
    #[arg(required = true)]
    inputs: Vec<PathBuf>,
    /// Cell size in metres (the setting map.resolution_m).
    #[arg(long)]
    resolution: f64,
    /// Output folder (created if needed).
    #[arg(long)]
    out: PathBuf,
    /// A setting by its scenario key (repeatable), e.g. --set map.model.max_height_m=0.5 or
    /// --set input.pcd_frame=optical: map.model.* (every model option), map.traversability, robot.max_step_m,
    /// robot.height_m, input.graph_sensor (laser|stereo), input.pcd_sensor (laser|stereo), input.pcd_frame
    /// (as_is|optical), input.pcd_invalid (drop|no_return), input.log_pose (estimated|true). README, "Settings".
    #[arg(long = "set", value_name = "KEY=VALUE")]
    overrides: Vec<String>,
    /// Memory limit of the map in MiB.
    #[arg(long, default_value_t = oeg::DEFAULT_MEMORY_LIMIT_BYTES >> 20)]
    memory_limit_mib: u64,
}

#[derive(ValueEnum, Clone, Copy, Debug)]
#[value(rename_all = "snake_case")]
enum FormatArg {
    Log,
    Graph,
}

impl MapArgs {
    fn job(&self) -> anyhow::Result<MapJob> {
        let settings =
            eval::settings::map_settings(self.resolution, &self.overrides).map_err(anyhow::Error::msg)?;
        Ok(MapJob {
            inputs: self.inputs.clone(),
            out_dir: self.out.clone(),
            config: MapConfig {
                resolution_m: settings.map.resolution_m,
                model: settings.map.model,
                memory_limit_bytes: self.memory_limit_mib.saturating_mul(1 << 20),
            },
            graph_sensor: settings.input.graph_sensor.model(),
            pcd: PcdOptions {
                frame: settings.input.pcd_frame,
                invalid_points: settings.input.pcd_invalid,
                sensor: settings.input.pcd_sensor.model(),
            },
            log_pose: settings.input.log_pose,
            profile: settings.robot,
            rule: settings.map.traversability,
            keep_inputs: false,
        })
    }
}

fn print_report(report: &MapReport) {
    let s = &report.summary;
    say!(
        "mapped {} scans, {} rays at {} m: {} cells observed ({} free, {} traversable, {} blocked), {} bytes; \
         integration {:.3} s ({:.2} M rays/s)",
        s.num_scans,
        s.num_rays,
        s.resolution_m,
        s.num_cells_observed,
        s.num_cells_free,
        s.num_cells_traversable,
        s.num_cells_blocked,
        s.map_bytes,
        report.timing.integrate_wall_time_s,
        report.timing.integrate_rays_per_s / 1e6
    );
    for f in &report.files {
        say!("wrote {}", f.display());
    }
}

fn run_map(args: &MapArgs) -> anyhow::Result<()> {
    let report = eval::mapping::run(&args.job()?, &Progress::new(0, "scans"))?;
    print_report(&report);
    Ok(())
}

fn run_demo(out: PathBuf) -> anyhow::Result<()> {
    let args = MapArgs {
        inputs: Vec::new(),
        resolution: 0.05,
        out: out.clone(),
        overrides: vec!["map.model.max_height_m=0.5".into()],
        memory_limit_mib: oeg::DEFAULT_MEMORY_LIMIT_BYTES >> 20,
    };
    let report = eval::demo::run(args.job()?, &Progress::new(0, "scans"))?;
    print_report(&report);
    say!(
        "kept the scans as {} (synthetic scans of a scene with a 3 cm and a 5 cm curb and a board at 0.35 m)",
        out.join("demo.graph").display()
    );
    Ok(())
}

/// What `oeg` with no arguments runs (relative to the repository root).
const DEFAULT_SCENARIO: &str = "scenarios/default.toml";

fn run_scenario(args: &RunArgs) -> anyhow::Result<()> {
    if !args.scenario.exists() && args.scenario == std::path::Path::new(DEFAULT_SCENARIO) {
        anyhow::bail!(
            "{DEFAULT_SCENARIO} not found: run `oeg` from the repository root, or give a scenario: oeg run FILE"
        );
    }
    let options = eval::run::RunOptions {
        scenario: args.scenario.clone(),
        out_dir: args.out.clone(),
        seed: args.seed,
        overrides: args.overrides.clone(),
        compare: args.compare,
    };
    let progress = Progress::new(0, "scans");
    let report = eval::run::run(&options, &progress)?;
    let m = &report.metrics;
    say!(
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
    );
    if let Some((preset, c)) = &report.compared {
        say!(
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
        );
    }
    say!(
        "simulation {:.2} s ({:.2} M rays/s), map {:.2} s ({:.2} M rays/s), truth {:.2} s; report in {}",
        report.timing.simulation_wall_time_s,
        report.timing.simulation_rays_per_s / 1e6,
        report.timing.map_wall_time_s,
        report.timing.map_rays_per_s / 1e6,
        report.timing.truth_wall_time_s,
        report.out_dir.display()
    );
    if !report.failed.is_empty() {
        for f in &report.failed {
            eprintln!("expectation failed: {f}");
        }
        anyhow::bail!("{} of the scenario's expectations failed", report.failed.len());
    }
    Ok(())
}

fn run_suite(
    paths: &[PathBuf],
    out: &std::path::Path,
    overrides: &[String],
    jobs: usize,
) -> anyhow::Result<()> {
    eprintln!("{}", eval::suite::table_header());
    let rows = eval::suite::suite(paths, out, overrides, jobs)?;
    say!("{}", eval::suite::table_header());
    for r in &rows {
        say!("{}", eval::suite::table_line(r));
    }
    for r in rows.iter().filter(|r| r.status != "pass") {
        eprintln!("{} {}: {}", r.scenario, r.status, r.problems);
    }
    say!(
        "wrote {} and {}",
        out.join("suite.csv").display(),
        out.join("suite.json").display()
    );
    let num_bad = rows.iter().filter(|r| r.status != "pass").count();
    if num_bad > 0 {
        anyhow::bail!("{num_bad} of {} scenarios did not pass", rows.len());
    }
    Ok(())
}

fn run_validate(paths: &[PathBuf]) -> anyhow::Result<()> {
    let mut num_bad = 0;
    for path in paths {
        match eval::preview::validate(path) {
            Ok(loaded) => say!("{}", eval::preview::describe(&loaded)),
            Err(e) => {
                num_bad += 1;
                eprintln!("error: {e}");
            }
        }
    }
    if num_bad > 0 {
        anyhow::bail!("{num_bad} of {} scenario files are invalid", paths.len());
    }
    Ok(())
}

fn run_record(
    path: &std::path::Path,
    out: &std::path::Path,
    format: FormatArg,
    seed: Option<u64>,
) -> anyhow::Result<()> {
    let format = match format {
        FormatArg::Log => eval::record::RecordFormat::Log,
        FormatArg::Graph => eval::record::RecordFormat::Graph,
    };
    let progress = Progress::new(0, "scans");
    let r = eval::record::record(path, out, format, seed, &progress)?;
    say!(
        "recorded {} scans, {} rays in {:.2} s ({:.2} M simulated rays/s){}; wrote {}",
        r.num_scans,
        r.num_rays,
        r.wall_time_s,
        r.rays_per_s / 1e6,
        if r.num_rays_left_out > 0 {
            format!(", {} no-return rays left out of the graph", r.num_rays_left_out)
        } else {
            String::new()
        },
        r.path.display()
    );
    Ok(())
}

fn run_preview(path: &std::path::Path, out: &std::path::Path) -> anyhow::Result<()> {
    for f in eval::preview::preview(path, out)? {
        say!("wrote {}", f.display());
    }
    Ok(())
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
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::Map(args)) => run_map(&args),
        Some(Command::Run(args)) => run_scenario(&args),
        Some(Command::Plan(args)) => run_plan(&args),
        Some(Command::Inspect { map }) => eval::inspect::inspect(&map)
            .map(|text| {
                let _ = write!(std::io::stdout(), "{text}");
            })
            .map_err(Into::into),
        Some(Command::Demo { out }) => run_demo(out),
        Some(Command::Validate { scenarios }) => run_validate(&scenarios),
        Some(Command::Suite {
            paths,
            out,
            overrides,
            jobs,
        }) => run_suite(
            &paths,
            &out,
            &overrides,
            jobs.map_or_else(eval::suite::default_jobs, usize::from),
        ),
        Some(Command::Record {
            scenario,
            out,
            format,
            seed,
        }) => run_record(&scenario, &out, format, seed),
        Some(Command::Preview { scenario, out }) => run_preview(&scenario, &out),
        Some(Command::Sweep(command)) => run_sweep(command),
        // The default run shows the paper's model and the recommended one side by side.
        None => run_scenario(&RunArgs {
            scenario: PathBuf::from(DEFAULT_SCENARIO),
            out: None,
            seed: None,
            overrides: Vec::new(),
            compare: Some(oeg::MapPreset::Robust),
        }),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", error_text(&e));
            ExitCode::FAILURE
        }
    }
}
