//! Runs OEG experiments end to end: scenario runs and suites (`oeg run`, `oeg suite`), studies over many runs
//! (`oeg sweep`), maps from recorded data (`oeg map`), plans on saved maps (`oeg plan`), inspection of saved
//! maps (`oeg inspect`), scenario checks and previews (`oeg validate`, `oeg preview`), reports and images. It
//! ties the map crate (`oeg`) to the simulation (`sim`); the command-line program is a thin layer over it.
//!
//! The crate is built in wings, each depending only on the ones listed before it:
//!
//! | Wing | What it holds |
//! |---|---|
//! | [`error`], `output`, `lock`, [`progress`] | errors, atomic outputs and staged folders, locks, progress |
//! | [`settings`] | `--set key=value` overrides and every job's settings table |
//! | [`judge`] | the verdict raster and what reads it: metrics, obstacles, wrong cells, the plan check |
//! | [`figures`] | the rasteriser and every figure |
//! | `mapping` | a simulation feeding its scans into one map per model |
//! | [`navigation`] | closed-loop runs: replanning, the controller, external planners, contacts |
//! | [`pipeline`], `report` | simulate, map, truth, judge; the run's report files |
//! | [`jobs`] | one module per command; no job calls another |
//!
//! The wings in plain type (`output`, `lock`, `mapping`, `report`, and `recording`, the MCAP writer) are the
//! crate's own, as are the parts of the public wings that nothing outside reads (the figures' canvas and
//! charts, the judge's ghosts, obstacles and wrong cells, the closed loop's controller, contacts and records,
//! the sweep's folder, generator, presets and statistics): the program, the Python package, the fuzz targets
//! and the tests reach them only through the jobs and the types they return.

pub mod error;
pub mod figures;
pub mod jobs;
pub mod judge;
pub(crate) mod lock;
pub(crate) mod mapping;
pub mod navigation;
pub(crate) mod output;
pub mod pipeline;
pub mod progress;
pub(crate) mod recording;
pub(crate) mod report;
pub mod scoring;
pub mod settings;
#[cfg(test)]
mod test_support;

pub use error::{EvalError, Result};
