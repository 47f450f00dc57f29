//! One file per command: its arguments (clap's derive) and the few lines that call the job in `oeg_eval` and
//! print what it did.

pub mod check_path;
pub mod demo;
pub mod inspect;
pub mod map;
pub mod plan;
pub mod preview;
pub mod record;
pub mod run;
pub mod score;
pub mod suite;
pub mod sweep;
pub mod validate;
