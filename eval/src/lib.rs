//! Runs OEG experiments end to end: scenario runs and suites (`oeg run`, `oeg suite`), studies over many runs
//! (`oeg sweep`), maps from recorded data (`oeg map`), plans on saved maps (`oeg plan`), inspection of saved
//! maps (`oeg inspect`), scenario checks and previews (`oeg validate`, `oeg preview`), reports and images.
//! Every job's settings go through one resolver ([`settings`]). It ties the map crate (`oeg`) to the outside
//! world; the command-line program is a thin layer over it.

pub mod demo;
pub mod error;
pub mod evaluation;
pub mod inspect;
pub mod lock;
pub mod mapping;
pub mod metrics;
pub mod obstacles;
pub mod output;
pub mod overrides;
pub mod plan;
pub mod preview;
pub mod progress;
pub mod record;
pub mod render;
pub mod report_images;
pub mod run;
pub mod settings;
pub mod suite;
pub mod sweep;
#[cfg(test)]
mod test_support;
pub mod verdict;
pub mod wrong_cells;

pub use error::{EvalError, Result};
