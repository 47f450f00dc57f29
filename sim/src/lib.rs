//! The OEG testbed's simulated world: scenario files ([`scenario`]), the robot from its URDF ([`robot`]), a
//! Rapier world with terrain, obstacles, moving people and the robot on its drive ([`world`]), and the ground
//! truth computed from that world ([`truth`]).
//!
//! Rapier and glam types stay inside this crate; its public API speaks nalgebra (conversions live in one
//! private module). Randomness comes only from the scenario's seed, split into named sub-streams ([`seed`]).

mod convert;
pub mod drive;
pub mod error;
pub mod log;
pub mod observability;
pub mod physics;
pub mod robot;
pub mod scenario;
pub mod seed;
pub mod sensors;
pub mod simulate;
pub mod terrain;
pub mod truth;
pub mod world;

pub use error::{Result, SimError, TextPosition};
pub use robot::RobotModel;
pub use scenario::{LoadedScenario, Scenario, load};
pub use simulate::Simulation;
pub use world::{Actors, HitKind, RayHit, RayStart, World};
