//! `oeg sweep`: studies of many runs (plan, run, merge, bench, report).

use std::path::{Path, PathBuf};

use clap::Subcommand;
use oeg_eval::jobs::default_jobs;
use oeg_eval::jobs::sweep::execute::{self, ExecuteOptions};
use oeg_eval::jobs::sweep::plan::describe;
use oeg_eval::jobs::sweep::{Sweep, SweepPlan, bench, merge, report};
use oeg_eval::progress::Progress;

/// `oeg sweep`'s sub-commands.
#[derive(Subcommand, Debug)]
pub(crate) enum SweepCommand {
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
        #[arg(long, value_name = "I/N", value_parser = oeg_eval::jobs::sweep::execute::parse_shard)]
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
        /// Also write each plot as SVG beside its PNG, for papers.
        #[arg(long)]
        svg: bool,
    },
}

/// Runs one sub-command and says what it did.
pub(crate) fn run(command: SweepCommand) -> anyhow::Result<()> {
    match command {
        SweepCommand::Plan { file, overrides } => print_plan(&load(&file, &overrides)?),
        SweepCommand::Run {
            file,
            overrides,
            out,
            jobs,
            shard,
            shards,
            simulate_each,
        } => {
            let shard = match shard {
                Some(s) => Some(s),
                None => execute::shard_from_env(|k| std::env::var(k).ok(), shards.map(|n| n as usize))
                    .map_err(|e| anyhow::anyhow!("the shard: {e}"))?,
            };
            let options = ExecuteOptions {
                out_dir: out,
                shard,
                jobs: jobs.map_or_else(default_jobs, usize::from),
                simulate_each,
            };
            run_plan(&load(&file, &overrides)?, &options)
        }
        SweepCommand::Merge { dirs, out } => {
            let summary = merge::merge(&dirs, &out)?;
            say!("merged {} runs from {} folders", summary.num_runs, dirs.len());
            for f in summary.files {
                say!("wrote {}", f.display());
            }
            Ok(())
        }
        SweepCommand::Bench {
            file,
            overrides,
            jobs,
            repeat,
            no_compare,
        } => {
            let plan = load(&file, &overrides)?;
            let jobs = jobs.map_or_else(default_jobs, usize::from);
            let f = bench::bench(&plan, jobs, usize::from(repeat), !no_compare)?;
            say!(
                "{}: {} runs, {jobs} jobs, {repeat} repetitions",
                plan.sweep.spec.name,
                f.num_runs
            );
            for line in f.lines() {
                say!("{line}");
            }
            Ok(())
        }
        SweepCommand::Report { dir, partial, svg } => {
            write_report(&dir, partial, oeg_eval::figures::ImageFormats { svg })
        }
    }
}

/// The sweep file with `--set` overrides, planned.
fn load(file: &Path, overrides: &[String]) -> anyhow::Result<SweepPlan> {
    Ok(SweepPlan::new(Sweep::load(file)?.with_overrides(overrides)?)?)
}

/// `oeg sweep plan`: one line for the plan, one per run.
fn print_plan(plan: &SweepPlan) -> anyhow::Result<()> {
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
            describe(&r.axis_values)
        );
    }
    Ok(())
}

/// `oeg sweep run`: the plan's runs (or one shard's), then what they did.
fn run_plan(plan: &SweepPlan, options: &ExecuteOptions) -> anyhow::Result<()> {
    let progress = Progress::new(0, "runs");
    let start = std::time::Instant::now();
    let summary = execute::run(plan, options, &progress)?;
    say!(
        "{}{}: {} runs, {} finished before, {} run now in {} simulations ({} errors) in {:.1} s",
        plan.sweep.spec.name,
        options
            .shard
            .map(|(i, n)| format!(" shard {i}/{n}"))
            .unwrap_or_default(),
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
    Ok(())
}

/// `oeg sweep report`: the summary and plots, and how much of the plan they cover.
fn write_report(dir: &Path, partial: bool, formats: oeg_eval::figures::ImageFormats) -> anyhow::Result<()> {
    let report = report::report(dir, partial, formats)?;
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
    Ok(())
}
