//! `oeg score`: a map made by another tool judged against a scenario's truth.

use std::path::PathBuf;

use oeg_eval::jobs::score::{GridSource, ScoreJob, run_job};
use oeg_eval::progress::Progress;

/// `oeg score`'s arguments.
#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("grid").required(true).args(["layers", "nav2", "decisions", "grid_map"])))]
pub(crate) struct ScoreArgs {
    /// The scenario whose truth judges the map (.toml).
    scenario: PathBuf,
    /// A layers.json sidecar (as `oeg map --planner-files` writes it): the grid, and the .npy files of the
    /// layers it names (decisions, elevation_m, variance_m2, occupancy_probability).
    #[arg(long, value_name = "LAYERS_JSON", conflicts_with = "nav2")]
    layers: Option<PathBuf>,
    /// A nav2 / ROS map_server map (its YAML file, mode trinary, a PGM image): the grid and the decisions
    /// (occupied: blocked, free: free, the rest unknown).
    #[arg(long, value_name = "MAP_YAML")]
    nav2: Option<PathBuf>,
    /// A ROS 2 bag (its .mcap file or its folder) holding grid_map_msgs/GridMap messages on --topic: the last
    /// map (or the last at --time) is scored, its `elevation` and `variance` layers, and its `traversability`
    /// layer (>= 0.5 drivable) or, without one, the terrain step rule (docs/scoring.md).
    #[arg(long, value_name = "BAG", conflicts_with_all = ["layers", "nav2", "decisions", "elevation", "variance", "occupancy"])]
    grid_map: Option<PathBuf>,
    /// The GridMap topic of --grid-map.
    #[arg(
        long,
        value_name = "TOPIC",
        default_value = "/elevation_map",
        requires = "grid_map"
    )]
    topic: String,
    /// Seconds after the bag's first message: score the last GridMap at or before it (default: the last one).
    #[arg(long, value_name = "SECONDS", requires = "grid_map")]
    time: Option<f64>,
    /// The decisions as a 2D .npy of integer codes: 0 unknown, 1 free, 2 traversable, 3 blocked, 4 uncertain;
    /// row 0 the min-y row. Needs --origin and --resolution.
    #[arg(long, value_name = "NPY", conflicts_with_all = ["layers", "nav2"], requires_all = ["origin", "resolution"])]
    decisions: Option<PathBuf>,
    /// World x,y of the lower-left corner of the arrays' cell [0, 0], metres (with --decisions).
    #[arg(
        long,
        value_name = "X,Y",
        value_delimiter = ',',
        allow_negative_numbers = true
    )]
    origin: Option<Vec<f64>>,
    /// The arrays' cell size, metres (with --decisions).
    #[arg(long, value_name = "METRES")]
    resolution: Option<f64>,
    /// Elevations as a 2D .npy in metres, NaN for none (over the sidecar's).
    #[arg(long, value_name = "NPY")]
    elevation: Option<PathBuf>,
    /// Elevation variances as a 2D .npy in m^2, NaN for none (over the sidecar's).
    #[arg(long, value_name = "NPY")]
    variance: Option<PathBuf>,
    /// Occupancy probabilities as a 2D .npy, NaN for none (over the sidecar's).
    #[arg(long, value_name = "NPY")]
    occupancy: Option<PathBuf>,
    /// Do not simulate the scenario's sensors: faster, but no blind counts and no sensor returns per obstacle.
    #[arg(long)]
    no_observability: bool,
    /// Override a scenario value by its dotted key (repeatable), as `oeg run --set`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    overrides: Vec<String>,
    /// Replace the scenario's seed (the sensors' noise, for the observability).
    #[arg(long)]
    seed: Option<u64>,
    /// Output folder for score.json, obstacles.csv, plan.csv and wrong_cells.csv.
    #[arg(long, default_value = "out/score")]
    out: PathBuf,
}

/// Scores the map and prints its verdict counts.
pub(crate) fn run(args: &ScoreArgs) -> anyhow::Result<()> {
    let grid = match (&args.layers, &args.nav2, &args.decisions) {
        _ if let Some(bag) = &args.grid_map => GridSource::GridMap {
            bag: bag.clone(),
            topic: args.topic.clone(),
            at_s: args.time,
        },
        (Some(l), _, _) => GridSource::Layers(l.clone()),
        (_, Some(n), _) => GridSource::Nav2(n.clone()),
        (_, _, Some(d)) => {
            let (Some(&[x, y]), Some(resolution_m)) = (args.origin.as_deref(), args.resolution) else {
                anyhow::bail!("--decisions needs --origin X,Y (two numbers, metres) and --resolution METRES");
            };
            GridSource::Grid {
                decisions: d.clone(),
                origin_xy_m: [x, y],
                resolution_m,
            }
        }
        _ => anyhow::bail!("give the map: --layers, --nav2, --decisions or --grid-map"),
    };
    let job = ScoreJob {
        scenario: args.scenario.clone(),
        overrides: args.overrides.clone(),
        seed: args.seed,
        grid,
        elevation: args.elevation.clone(),
        variance: args.variance.clone(),
        occupancy: args.occupancy.clone(),
        observability: !args.no_observability,
        out_dir: args.out.clone(),
    };
    let report = run_job(&job, &Progress::new(0, "scans"))?;
    let m = &report.evaluation.metrics;
    say!(
        "{}: {} of {} cells observed; {} scored: {} right drivable, {} right blocked, {} unsafe ({} blind), \
         {} over-cautious, {} uncertain",
        m.scenario,
        m.num_observed_cells,
        m.num_cells,
        m.num_scored_cells,
        m.right_drivable_cells,
        m.right_blocked_cells,
        m.unsafe_cells,
        m.blind_cells,
        m.overcautious_cells,
        m.uncertain_cells
    );
    say!(
        "plan: {} ({} unsafe path cells), truth's plan {}; elevation RMSE {:.3} m over {} cells",
        if m.plan_found { "found" } else { "not found" },
        m.plan_unsafe_cells,
        if m.truth_plan_found { "found" } else { "not found" },
        m.elevation_rmse_m,
        m.num_elevation_cells
    );
    if !report.observability {
        say!(
            "blind cells not counted: {}",
            if args.no_observability {
                "--no-observability"
            } else {
                "a closed-loop scenario's rays depend on the map that steered it"
            }
        );
    }
    for f in &report.files {
        say!("wrote {}", f.display());
    }
    super::fail_on_expectations(&report.evaluation.failed)
}
