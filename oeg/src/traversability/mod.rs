//! The traversability decision, in one place: the robot ([`RobotProfile`]), the classes ([`Traversability`]),
//! the step rules ([`TraversabilityRule`]) and the pure decision functions in `rules`, and the part that reads
//! the map ([`crate::Map::traversability`]) in `decide`, the windows of cells it reads around a cell in
//! `window`, and its layers over a region ([`crate::Map::traversability_layer`]) in `layers`.

mod decide;
mod layers;
mod rules;
mod window;

pub use layers::TraversabilityCounts;
pub use rules::*;
