//! `oeg sweep`: studies of many runs over axes of settings, seeds and randomized scenes, on one machine or a
//! cluster (`docs/sweep-format.md`).
//!
//! * [`spec`]: the sweep file and its checks;
//! * `presets`: named model presets;
//! * `generate`: randomized scenes;
//! * [`plan`]: every run resolved, with its id, its shard and the simulation it shares;
//! * `folder`: whose output folder it is, its lock, writes that never leave it;
//! * [`execute`]: running, resuming, sharding; [`rows`]: the rows and tables it writes;
//! * [`merge`]: shards back into one set of rows;
//! * `stats` and [`report`]: means with confidence intervals, `summary.csv` and plots;
//! * [`bench`](mod@bench): what a study costs, and what sharing simulations saves.

pub mod bench;
pub mod execute;
pub(crate) mod folder;
pub(crate) mod generate;
pub mod merge;
pub mod plan;
pub(crate) mod presets;
pub mod report;
pub mod rows;
pub mod spec;
pub(crate) mod stats;
pub(crate) mod summarized;

pub use plan::SweepPlan;
pub use spec::Sweep;
