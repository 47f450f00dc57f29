//! Can the robot drive over a cell? The paper's step decision (section 1 and 3: a Pioneer 3-AT climbs 3.5 cm).

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Default largest step the robot climbs, metres: the paper's Pioneer 3-AT, 3.5 cm "tested in practice".
pub const DEFAULT_MAX_STEP_M: f32 = 0.035;
/// Default robot height, metres: the paper's Pioneer 3-AT with its sensors, 0.46 m.
pub const DEFAULT_ROBOT_HEIGHT_M: f32 = 0.46;

/// The robot as the decisions see it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RobotProfile {
    /// Largest step the robot drives over, metres.
    pub max_step_m: f32,
    /// Height of the robot, metres: it passes under structures higher than this. Set the map's
    /// [`crate::ModelOptions::max_height_m`] a little above it so such structures never enter the map.
    pub height_m: f32,
}

impl Default for RobotProfile {
    fn default() -> Self {
        Self {
            max_step_m: DEFAULT_MAX_STEP_M,
            height_m: DEFAULT_ROBOT_HEIGHT_M,
        }
    }
}

impl RobotProfile {
    /// Checks the profile for sense.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] for a non-finite or non-positive value.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [("max_step_m", self.max_step_m), ("height_m", self.height_m)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::setting(
                    name,
                    format!("must be a positive number of metres, got {v}"),
                ));
            }
        }
        Ok(())
    }
}

/// The class of a cell for the robot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[repr(u8)]
pub enum Traversability {
    /// Never observed.
    Unknown = 0,
    /// Observed and not occupied.
    Free = 1,
    /// Occupied, but low enough to drive over.
    Traversable = 2,
    /// Occupied and too high (or occupied with no elevation estimate).
    Blocked = 3,
}

impl Traversability {
    /// Whether the robot may enter the cell.
    pub fn is_drivable(self) -> bool {
        matches!(self, Self::Free | Self::Traversable)
    }
}

/// How the step of an occupied cell is measured.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum TraversabilityRule {
    /// The paper: blocked when `mu > max_step`, the step measured from z = 0.
    #[default]
    Absolute,
    /// Blocked when `mu + kappa * sigma > max_step`: an uncertain estimate counts as higher.
    Conservative {
        /// Number of standard deviations added to the mean.
        kappa: f32,
    },
    /// The step is measured against the neighbouring ground: blocked when `mu` minus the lowest elevation among
    /// the cell and its eight neighbours exceeds `max_step`. Slopes and raised terrain stay drivable; a curb is
    /// blocked by its height above the road beside it.
    Terrain,
}

/// The step decision for one occupied cell: `step_m` is the measured step (for [`TraversabilityRule::Terrain`],
/// already relative to the neighbours' ground), `sigma_m` the elevation standard deviation.
pub fn step_decision(
    step_m: f32,
    sigma_m: f32,
    rule: TraversabilityRule,
    profile: &RobotProfile,
) -> Traversability {
    let effective = match rule {
        TraversabilityRule::Conservative { kappa } => step_m + kappa * sigma_m,
        TraversabilityRule::Absolute | TraversabilityRule::Terrain => step_m,
    };
    if effective > profile.max_step_m {
        Traversability::Blocked
    } else {
        Traversability::Traversable
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_papers_threshold_is_3_5_cm() {
        let p = RobotProfile::default();
        assert_eq!(
            step_decision(0.030, 0.0, TraversabilityRule::Absolute, &p),
            Traversability::Traversable
        );
        assert_eq!(
            step_decision(0.035, 0.0, TraversabilityRule::Absolute, &p),
            Traversability::Traversable
        );
        assert_eq!(
            step_decision(0.036, 0.0, TraversabilityRule::Absolute, &p),
            Traversability::Blocked
        );
    }

    #[test]
    fn the_conservative_rule_adds_kappa_sigma() {
        let p = RobotProfile::default();
        let rule = TraversabilityRule::Conservative { kappa: 2.0 };
        assert_eq!(step_decision(0.02, 0.005, rule, &p), Traversability::Traversable);
        assert_eq!(step_decision(0.02, 0.01, rule, &p), Traversability::Blocked);
    }

    #[test]
    fn profiles_are_validated() {
        assert!(RobotProfile::default().validate().is_ok());
        assert!(
            RobotProfile {
                height_m: -1.0,
                ..RobotProfile::default()
            }
            .validate()
            .is_err()
        );
        assert!(
            RobotProfile {
                max_step_m: f32::NAN,
                ..RobotProfile::default()
            }
            .validate()
            .is_err()
        );
    }
}
