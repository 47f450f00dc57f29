//! The OEG update rules and the options that parameterise them.
//!
//! * `equations`: the paper's equations (sections 3 and 4), one pure function each;
//! * `rules`: the rules beyond the paper (free space in 2.5D, surface fusion, honest variance), one pure
//!   function each;
//! * `options`: the options that choose and parameterise them, with their documented defaults;
//! * `ceiling`: the structure over a cell ([`Ceiling`]), the state the ceiling rule updates;
//!
//! `Map::integrate` (`map/integrate.rs`) strings them together as the paper's Algorithm 1 does.

mod ceiling;
mod equations;
mod options;
mod rules;

pub use ceiling::{Ceiling, SeenFrom};
pub use equations::*;
pub use options::*;
pub use rules::*;
