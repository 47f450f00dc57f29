//! Scenario files: schema, loading and validation.

mod load;
mod schema;

pub use load::{
    KeySeg, LoadedScenario, MAX_DURATION_S, MAX_MAP_CELLS, expand_map_preset, load, load_str, position_of,
};
pub use schema::*;
