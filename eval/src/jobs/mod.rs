//! One file per command of the `oeg` program (rerun's `commands/` layout): each job takes its options, does its
//! work through the shared wings ([`crate::pipeline`], [`crate::judge`], [`crate::settings`],
//! [`crate::figures`], `output`) and returns what it did. No job calls another; `oeg demo` is
//! `oeg map` on built-in scans, so it lives in the map job's folder ([`map::demo`]).

pub mod check_path;
pub mod inspect;
pub mod map;
pub mod plan;
pub mod preview;
pub mod record;
pub mod run;
pub mod score;
pub mod suite;
pub mod sweep;

/// The default number of scenarios or simulations at once (`oeg suite --jobs`, `oeg sweep run --jobs`): the
/// threads rayon would use (`RAYON_NUM_THREADS`, else one per core).
pub fn default_jobs() -> usize {
    rayon::current_num_threads()
}
