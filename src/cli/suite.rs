//! `oeg suite`: many scenarios, one table.

use std::path::PathBuf;

use oeg_eval::jobs::suite;

/// `oeg suite`'s arguments.
#[derive(clap::Args, Debug)]
pub(crate) struct SuiteArgs {
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
    /// Also write each figure as SVG beside its PNG, for papers: lines and text as vectors, the map's cells
    /// as an image inside it.
    #[arg(long)]
    svg: bool,
}

/// Runs the suite, prints its table, fails if any scenario did not pass.
pub(crate) fn run(args: &SuiteArgs) -> anyhow::Result<()> {
    let jobs = args.jobs.map_or_else(oeg_eval::jobs::default_jobs, usize::from);
    eprintln!("{}", suite::table_header());
    let rows = suite::suite(
        &args.paths,
        &args.out,
        &args.overrides,
        jobs,
        oeg_eval::figures::ImageFormats { svg: args.svg },
    )?;
    say!("{}", suite::table_header());
    for r in &rows {
        say!("{}", suite::table_line(r));
    }
    let count = |word: &str| rows.iter().filter(|r| r.safety == word).count();
    say!(
        "drive: {} safe, {} unsafe, {} with no path; regression bounds: {} of {} scenarios within them",
        count("safe"),
        count("unsafe"),
        count("no path"),
        rows.iter().filter(|r| r.status == "pass").count(),
        rows.len()
    );
    for r in rows.iter().filter(|r| r.status != "pass") {
        eprintln!("{} {}: {}", r.scenario, r.status, r.problems);
    }
    say!(
        "wrote {} and {}",
        args.out.join("suite.csv").display(),
        args.out.join("suite.json").display()
    );
    let num_bad = rows.iter().filter(|r| r.status != "pass").count();
    if num_bad > 0 {
        anyhow::bail!("{num_bad} of {} scenarios did not pass", rows.len());
    }
    Ok(())
}
