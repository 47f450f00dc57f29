//! Scenario files: schema, loading and validation.

mod check;
pub mod exact;
pub mod heightmap;
mod limits;
mod load;
mod navigation;
mod physics;
mod scene;
mod schema;
pub mod sensors;

pub use load::{
    KeySeg, LoadedScenario, MAX_CELL_VISITS_PER_RUN, MAX_DURATION_S, MAX_LENGTH_M, MAX_MAP_CELLS,
    MAX_OBJECTS, MAX_PARTS, MAX_RAYS_PER_RUN, MAX_TRUTH_BYTES, MAX_TRUTH_FILTER_STEPS, MAX_TRUTH_SAMPLES,
    load, load_doc, load_str, position_of,
};
pub use navigation::*;
pub use physics::*;
pub use scene::*;
pub use schema::*;
pub use sensors::{NoiseSettings, SensorKind, SensorMount};
