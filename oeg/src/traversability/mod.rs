//! The traversability decision, in one place: the robot ([`RobotProfile`]), the classes ([`Traversability`]),
//! the step rules ([`TraversabilityRule`]) and the pure decision functions in `rules`, and the part that reads
//! the map ([`crate::Map::traversability`], [`crate::Map::traversability_layer`]) in `decide`.

mod decide;
mod rules;

pub use decide::TraversabilityCounts;
pub use rules::*;
