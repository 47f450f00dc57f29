//! `oeg plan`: a path on a saved map.

use std::path::PathBuf;

use oeg_eval::jobs::plan::{PlanJob, run_job};

/// `oeg plan`'s arguments.
#[derive(clap::Args, Debug)]
pub(crate) struct PlanArgs {
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
    /// inscribed radius), planner.inflation_cost_width_m (0.30) and planner.cost_scaling_factor (10, per
    /// metre: the cost of cells near the inflation), planner.unknown (avoid, inflate or drivable),
    /// planner.uncertain (blocked or drivable), robot.max_step_m (0.035), robot.height_m (0.46),
    /// map.traversability (the paper's absolute step rule unless given), map.preset (its step rule: `robust`
    /// judges a map as `oeg run --set map.preset=robust` does).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    overrides: Vec<String>,
    /// Also write each figure as SVG beside its PNG, for papers.
    #[arg(long)]
    svg: bool,
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

/// Plans, says whether a path was found and names the files written.
pub(crate) fn run(args: &PlanArgs) -> anyhow::Result<()> {
    let settings = oeg_eval::settings::plan_settings(&args.overrides)?;
    let job = PlanJob {
        map: args.map.clone(),
        from_xy_m: args.from,
        to_xy_m: args.to,
        out_dir: args.out.clone(),
        options: settings.planner,
        profile: settings.robot,
        rule: settings.map.traversability,
        figures: oeg_eval::figures::ImageFormats { svg: args.svg },
    };
    let (summary, files) = run_job(&job)?;
    if summary.plan_found {
        say!(
            "path found: {:.2} m, {} cells",
            summary.plan_length_m,
            summary.num_path_cells
        );
    }
    for f in files {
        say!("wrote {}", f.display());
    }
    if summary.plan_found {
        return Ok(());
    }
    Err(super::Status {
        code: NO_PATH_EXIT_CODE,
        message: format!(
            "no path from ({}, {}) to ({}, {}) m: {}",
            args.from.0,
            args.from.1,
            args.to.0,
            args.to.1,
            summary.no_path_reason.unwrap_or_default()
        ),
    }
    .into())
}

/// `oeg plan`'s exit status when there is no path (its files are written): 1 is an error, 2 bad arguments.
pub(crate) const NO_PATH_EXIT_CODE: u8 = 3;
