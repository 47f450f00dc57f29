//! Randomized scenes: a sweep's `[generate]` table places obstacles and people from distributions with each
//! run's scenario seed (sub-streams `generate/<kind>`), so a replicate is a new scene and the same seed is the
//! same scene. `docs/sweep-format.md` documents every key.
//!
//! The layout keeps the question meaningful: the robot drives along +x from the origin to `drive_length_m` and
//! stops facing the obstacle field. The field spans `field_start_m .. field_start_m + field_length_m` along x
//! and `±field_half_width_m` across; a lane `±lane_half_width_m` wide stays free as far as the robot drives
//! (obstacles do not lift the simulated robot), and beyond the stop obstacles may stand in the lane, in front
//! of the robot. The planner plans from the start to a free goal past the field's far end, so it must cross
//! or go round what was placed. Generated obstacles are appended to the base scenario's; the drive, planner,
//! map region and duration are the generator's.

mod checks;
mod placement;
mod spec;
#[cfg(test)]
mod tests;

pub(crate) use spec::*;
