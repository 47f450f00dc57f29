//! Can the robot drive over a cell? The paper's step decision (section 1 and 3: a Pioneer 3-AT climbs 3.5 cm).

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Default largest step the robot climbs, metres: the paper's Pioneer 3-AT, 3.5 cm "tested in practice".
pub const DEFAULT_MAX_STEP_M: f32 = 0.035;
/// Default robot height, metres: the paper's Pioneer 3-AT with its sensors, 0.46 m.
pub const DEFAULT_ROBOT_HEIGHT_M: f32 = 0.46;
/// Default steepest grade the robot climbs (rise over run): the Pioneer 3-AT's data sheet, 35 %.
pub const DEFAULT_MAX_GRADE: f32 = 0.35;
/// Default `kappa` of [`TraversabilityRule::Contact`]: a step or clearance within 2 standard deviations of its
/// threshold is uncertain (a 95 % two-sided band).
pub const DEFAULT_UNCERTAIN_KAPPA: f32 = 2.0;

/// The robot as the decisions see it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RobotProfile {
    /// Largest step the robot drives over, metres.
    pub max_step_m: f32,
    /// Height of the robot, metres: it passes under structures higher than this. Set the map's
    /// [`crate::ModelOptions::max_height_m`] a little above it so such structures never enter the map.
    pub height_m: f32,
    /// Steepest grade the robot climbs, rise over run (0.35 = 35 %, 19.3 degrees).
    pub max_grade: f32,
}

impl Default for RobotProfile {
    fn default() -> Self {
        Self {
            max_step_m: DEFAULT_MAX_STEP_M,
            height_m: DEFAULT_ROBOT_HEIGHT_M,
            max_grade: DEFAULT_MAX_GRADE,
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
        if !(self.max_grade.is_finite() && self.max_grade > 0.0 && self.max_grade <= 10.0) {
            return Err(Error::setting(
                "max_grade",
                format!(
                    "must be a grade (rise over run) in (0, 10], got {}",
                    self.max_grade
                ),
            ));
        }
        Ok(())
    }

    /// The contact distance, metres: `max_step_m / max_grade` (0.10 m for the Pioneer 3-AT, the scale of its
    /// wheels' contact). A rise of more than `max_step_m` between two points closer than this is a step: it is
    /// higher than the robot steps over and steeper on average than it climbs. A slope the robot climbs never
    /// rises that much over this distance, so slopes are not steps and a slope too steep is one.
    pub fn contact_distance_m(&self) -> f32 {
        self.max_step_m / self.max_grade
    }
}

/// The class of a cell for the robot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[repr(u8)]
pub enum Traversability {
    /// Never observed; under [`TraversabilityRule::Contact`] or [`crate::HitHeight::Endpoint`], also an observed
    /// cell whose height nothing around it measured ([`Doubt::NoHeight`]); under the contact rule, one that
    /// would be drivable beside a cell never observed ([`Doubt::Frontier`]).
    Unknown = 0,
    /// Observed and not occupied.
    Free = 1,
    /// Occupied, but low enough to drive over.
    Traversable = 2,
    /// Occupied and too high (or occupied with no elevation estimate).
    Blocked = 3,
    /// Observed, but its step or clearance lies within `kappa` standard deviations of the threshold: the map
    /// cannot tell ([`TraversabilityRule::Contact`]).
    Uncertain = 4,
}

impl Traversability {
    /// Whether the robot may enter the cell (uncertain cells are not: the planner decides about them, see
    /// [`crate::planner::UncertainCells`]).
    pub fn is_drivable(self) -> bool {
        matches!(self, Self::Free | Self::Traversable)
    }

    /// The snake_case name used in files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Unknown => "unknown",
            Self::Free => "free",
            Self::Traversable => "traversable",
            Self::Blocked => "blocked",
            Self::Uncertain => "uncertain",
        }
    }
}

/// Why [`TraversabilityRule::Contact`] cannot decide an observed cell ([`crate::Map::doubt`]): the test that
/// could not tell for a [`Traversability::Uncertain`] cell, or why an observed cell is left
/// [`Traversability::Unknown`] (no height, the frontier). Each names what the map would have to measure better
/// to decide.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Doubt {
    /// The cell's step over the ground within the contact distance lies within `kappa` standard deviations of
    /// `max_step_m` ([`contact_decision`]).
    StepBand,
    /// The cell's height over that ground lies within `kappa` standard deviations of the robot's height: an
    /// overhang it might just pass under ([`contact_decision`]).
    HeightBand,
    /// The cell's rise over the robot's half width lies within `kappa` standard deviations of what it climbs
    /// ([`footprint_decision`]).
    FootprintBand,
    /// The cell's estimate is too coarse to tell level ground from a step: `kappa * sqrt(2) * sigma >=
    /// max_step_m`, so two level cells measured so would differ by a step within the band. The sensors'
    /// resolution at that range (a stereo camera's depth error grows with the square of the range): driving
    /// closer and looking again decides it.
    Imprecise,
    /// Occupied with no height estimate (it lies within a beam's range noise of its end point, which alone
    /// measures a height), and no estimate to judge it by within the contact distance (the 3 x 3 neighbourhood
    /// for the other rules). It is [`Traversability::Unknown`], as a clearance never observed is.
    NoHeight,
    /// A cell with no height (free: beams passed over it; or occupied within a beam's range noise of its end
    /// point) beside an estimate a step higher: it may be part of the step (the top of a low wall the lidar
    /// grazes, the shadow behind a curb).
    BesideStep,
    /// A cell that would be traversable, with such a free cell within the contact distance and ground a step
    /// below it: a curb's far edge may drop into its own shadow.
    HiddenStep,
    /// The frontier: the cell would be drivable, but a cell within the robot's contact distance was never
    /// observed, and a wheel may come from it. The cell is [`Traversability::Unknown`], not uncertain: it is
    /// not known to be drivable, and it is no obstacle either. Observing the rest of the window decides it.
    Frontier,
    /// A structure's clearance lies within `kappa` standard deviations of a step or of the robot's height
    /// ([`ceiling_decision`]).
    StructureBand,
    /// A structure lower than the robot, seen less surely than one sure hit: it may not be there.
    StructureUnconfirmed,
    /// A structure measured higher than the robot, under which no beam passed higher than the robot: its
    /// underside may hang lower than its hits.
    UndersideUnseen,
    /// A structure over a cell with no ground within the contact distance to measure its clearance from.
    StructureNoGround,
}

impl Doubt {
    /// Every doubt, in file order.
    pub const ALL: [Self; 12] = [
        Self::StepBand,
        Self::HeightBand,
        Self::FootprintBand,
        Self::Imprecise,
        Self::NoHeight,
        Self::BesideStep,
        Self::HiddenStep,
        Self::Frontier,
        Self::StructureBand,
        Self::StructureUnconfirmed,
        Self::UndersideUnseen,
        Self::StructureNoGround,
    ];

    /// The snake_case name used in files.
    pub fn name(self) -> &'static str {
        match self {
            Self::StepBand => "step_band",
            Self::HeightBand => "height_band",
            Self::FootprintBand => "footprint_band",
            Self::Imprecise => "imprecise",
            Self::NoHeight => "no_height",
            Self::BesideStep => "beside_step",
            Self::HiddenStep => "hidden_step",
            Self::Frontier => "frontier",
            Self::StructureBand => "structure_band",
            Self::StructureUnconfirmed => "structure_unconfirmed",
            Self::UndersideUnseen => "underside_unseen",
            Self::StructureNoGround => "structure_no_ground",
        }
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
    /// The robot's physical rule, the testbed's truth applied to the map: the step of a cell is its elevation
    /// above the lowest estimate within the robot's contact distance ([`RobotProfile::contact_distance_m`]),
    /// so slopes it climbs stay drivable and edges at any angle to the grid are steps. A cell is uncertain when
    /// its step lies within `kappa` standard deviations of `max_step_m`, or its height above that ground within
    /// `kappa` standard deviations of the robot's height (an overhang the robot might just pass under); the
    /// standard deviation is that of the difference, `sqrt(sigma^2 + sigma_ground^2)`.
    ///
    /// A free cell (beams passed through it and none ended there) holds no measured ground, and the beams bound
    /// it only from above: it is judged as if it were as high as the highest estimate within the contact
    /// distance, free where that would be drivable and uncertain where not (a low wall's top that a lidar
    /// grazes and never hits, the shadow behind a curb). A cell that would be traversable is uncertain when
    /// such a cell within the contact distance lies beside ground a step below it: a curb's far edge may drop
    /// into its own shadow.
    ///
    /// Over the robot's half width `reach_m` the same holds with the rise a slope allows:
    /// [`footprint_decision`]. A top that rises more over the robot's own extent than it can climb is a
    /// structure it cannot pass under (a board, a table top) or a plateau it cannot have climbed; from one height
    /// per cell the two cannot be told apart, and both are blocked.
    Contact {
        /// Width of the uncertain band, in standard deviations; default [`DEFAULT_UNCERTAIN_KAPPA`].
        #[serde(default = "default_kappa")]
        kappa: f32,
        /// The robot's half width, metres; default [`DEFAULT_REACH_M`].
        #[serde(default = "default_reach")]
        reach_m: f32,
    },
}

/// [`TraversabilityRule::Contact`]'s default `reach_m`: half the Pioneer 3-AT's 0.50 m width (its data sheet),
/// the planner's default clearance too.
pub const DEFAULT_REACH_M: f32 = 0.25;

fn default_reach() -> f32 {
    DEFAULT_REACH_M
}

fn default_kappa() -> f32 {
    DEFAULT_UNCERTAIN_KAPPA
}

impl TraversabilityRule {
    /// Checks the rule's parameters.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] for a negative or non-finite `kappa`.
    pub fn validate(&self) -> Result<()> {
        match *self {
            Self::Contact { reach_m, .. } if !(reach_m.is_finite() && reach_m >= 0.0) => Err(Error::setting(
                "traversability",
                format!("reach_m must be a distance in metres >= 0, got {reach_m}"),
            )),
            Self::Conservative { kappa } | Self::Contact { kappa, .. }
                if !(kappa.is_finite() && kappa >= 0.0) =>
            {
                Err(Error::setting(
                    "traversability",
                    format!("kappa must be a number of standard deviations >= 0, got {kappa}"),
                ))
            }
            _ => Ok(()),
        }
    }
}

/// [`TraversabilityRule::Contact`]'s decision for an occupied cell whose elevation lies `rise_m` above the
/// lowest estimate within the contact distance, with standard deviation `sigma_m` (of the difference).
pub fn contact_decision(rise_m: f32, sigma_m: f32, kappa: f32, profile: &RobotProfile) -> Traversability {
    let band = kappa * sigma_m;
    if (rise_m - profile.height_m).abs() <= band {
        // Could be a structure the robot just passes under, or one it hits.
        Traversability::Uncertain
    } else if rise_m > profile.max_step_m + band {
        Traversability::Blocked
    } else if rise_m >= profile.max_step_m - band {
        Traversability::Uncertain
    } else {
        Traversability::Traversable
    }
}

/// [`TraversabilityRule::Contact`]'s second test: a cell whose elevation lies `rise_m` above the lowest level
/// within `reach_m` (the robot's half width), with standard deviation `sigma_m`. Drivable ground rises at most
/// `max_step_m + max_grade * reach_m` over that distance (a step, then the steepest grade); more is `Blocked`,
/// within `kappa` sigma of it `Uncertain`, and less leaves the decision to [`contact_decision`] (`None`).
pub fn footprint_decision(
    rise_m: f32,
    sigma_m: f32,
    reach_m: f32,
    kappa: f32,
    profile: &RobotProfile,
) -> Option<Traversability> {
    let allowance = profile.max_step_m + profile.max_grade * reach_m;
    let band = kappa * sigma_m;
    if rise_m > allowance + band {
        Some(Traversability::Blocked)
    } else if rise_m >= allowance - band {
        Some(Traversability::Uncertain)
    } else {
        None
    }
}

/// The decision for a structure `clearance_m` over a cell's ground, with standard deviation `sigma_m` (of the
/// difference): the robot drives over it when it is no higher than a step, under it when it is higher than the
/// robot, and hits it in between, whatever it is (a board, a table top, a person): `Blocked`, or `Uncertain`
/// within `kappa` sigma of either threshold. A structure that is not `confirmed` (seen less surely than one
/// sure hit: [`crate::model::ceiling_confirmed`]) may not be there at all, and blocks nothing for sure: it is
/// `Uncertain` where a confirmed one would be `Blocked`. `None` leaves the decision to the cell's surface.
///
/// A structure measured higher than the robot is passed under only where a beam passed under it higher than
/// the robot too: `passed_under_m`, the highest point over the ground at which a beam crossed the cell under
/// it ([`crate::Ceiling::clear_m`]; `-inf`: none). The hits say where beams met the structure, not where its
/// lowest part is: a lidar ring rising onto a board's face meets it above the board's underside, and the
/// underside may lie anywhere between the highest beam that passed under it and the hits. Where that span
/// reaches down to the robot's height, `Uncertain`. A flat underside seen from a robot that moves is crossed
/// just under its height in the scans before each part of it is hit, so it is passed under.
pub fn ceiling_decision(
    clearance_m: f32,
    passed_under_m: f32,
    sigma_m: f32,
    kappa: f32,
    profile: &RobotProfile,
    confirmed: bool,
) -> Option<Traversability> {
    let band = kappa * sigma_m;
    if clearance_m < profile.max_step_m - band {
        None
    } else if clearance_m > profile.height_m + band {
        (passed_under_m <= profile.height_m + band).then_some(Traversability::Uncertain)
    } else if confirmed && clearance_m > profile.max_step_m + band && clearance_m < profile.height_m - band {
        Some(Traversability::Blocked)
    } else {
        Some(Traversability::Uncertain)
    }
}

/// The more restrictive of two decisions about one cell: blocked over uncertain over the rest (`a` when
/// neither restricts more).
pub fn more_restrictive(a: Traversability, b: Option<Traversability>) -> Traversability {
    let rank = |t: Traversability| match t {
        Traversability::Blocked => 2,
        Traversability::Uncertain => 1,
        _ => 0,
    };
    match b {
        Some(b) if rank(b) > rank(a) => b,
        _ => a,
    }
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
        TraversabilityRule::Contact { kappa, .. } => {
            return contact_decision(step_m, sigma_m, kappa, profile);
        }
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
    fn a_top_higher_than_the_robot_climbs_over_its_half_width_is_blocked() {
        let p = RobotProfile::default();
        // Over 0.25 m the Pioneer 3-AT climbs 3.5 cm + 35 % of 0.25 m = 12.25 cm.
        assert_eq!(
            footprint_decision(0.40, 0.005, 0.25, 2.0, &p),
            Some(Traversability::Blocked)
        );
        assert_eq!(
            footprint_decision(0.12, 0.005, 0.25, 2.0, &p),
            Some(Traversability::Uncertain)
        );
        // A 30 % ramp rises 7.5 cm over 0.25 m, a 5 cm curb's top 5 cm: left to the contact rule.
        assert_eq!(footprint_decision(0.075, 0.005, 0.25, 2.0, &p), None);
        assert_eq!(footprint_decision(0.05, 0.005, 0.25, 2.0, &p), None);
        assert!(
            TraversabilityRule::Contact {
                kappa: 2.0,
                reach_m: f32::NAN
            }
            .validate()
            .is_err()
        );
    }

    #[test]
    fn a_structure_between_a_step_and_the_robots_height_over_the_ground_blocks_it() {
        let p = RobotProfile::default();
        // A board 0.30 m over the ground, known to 1 cm: blocked; 0.44 m: within 2 sigma of 0.46 m, uncertain.
        assert_eq!(
            ceiling_decision(0.30, 0.30, 0.01, 2.0, &p, true),
            Some(Traversability::Blocked)
        );
        assert_eq!(
            ceiling_decision(0.44, 0.44, 0.01, 2.0, &p, true),
            Some(Traversability::Uncertain)
        );
        // 0.50 m: the robot passes under it; 2 cm: it drives over it. Both leave the decision to the surface.
        assert_eq!(ceiling_decision(0.50, 0.50, 0.01, 2.0, &p, true), None);
        assert_eq!(ceiling_decision(0.02, 0.02, 0.005, 2.0, &p, true), None);
        // 3.5 cm known to 5 mm: cannot tell whether it is a step.
        assert_eq!(
            ceiling_decision(0.035, 0.035, 0.005, 2.0, &p, true),
            Some(Traversability::Uncertain)
        );
        // Without an uncertain band (kappa 0) the thresholds are sharp.
        assert_eq!(
            ceiling_decision(0.459, 0.459, 0.01, 0.0, &p, true),
            Some(Traversability::Blocked)
        );
        assert_eq!(ceiling_decision(0.461, 0.461, 0.01, 0.0, &p, true), None);
        // Seen less surely than one sure hit (a far stereo pixel), it may not be there: uncertain, not blocked.
        assert_eq!(
            ceiling_decision(0.30, 0.30, 0.01, 2.0, &p, false),
            Some(Traversability::Uncertain)
        );
        assert_eq!(ceiling_decision(0.50, 0.50, 0.01, 2.0, &p, false), None);
        // Hits 0.48 m up where no beam passed under it higher than 0.42 m (a board's face met by a rising
        // ring): its underside may hang anywhere from 0.42 to 0.48 m, the robot's 0.46 m among them.
        assert_eq!(
            ceiling_decision(0.48, 0.42, 0.005, 2.0, &p, true),
            Some(Traversability::Uncertain)
        );
        assert_eq!(
            ceiling_decision(0.48, f32::NEG_INFINITY, 0.005, 2.0, &p, true),
            Some(Traversability::Uncertain)
        );
        // A beam passed under it at 0.475 m: the robot passes under it.
        assert_eq!(ceiling_decision(0.48, 0.475, 0.005, 2.0, &p, true), None);
        // The more restrictive decision wins.
        let (b, u, t) = (
            Traversability::Blocked,
            Traversability::Uncertain,
            Traversability::Traversable,
        );
        assert_eq!(more_restrictive(t, Some(b)), b);
        assert_eq!(more_restrictive(b, Some(u)), b);
        assert_eq!(more_restrictive(Traversability::Free, Some(u)), u);
        assert_eq!(more_restrictive(u, None), u);
        assert_eq!(more_restrictive(t, Some(Traversability::Free)), t);
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

    #[test]
    fn the_contact_distance_folds_the_slope_limit_into_the_step() {
        let p = RobotProfile::default();
        assert!((p.contact_distance_m() - 0.1).abs() < 1e-6);
        // A 35 % grade rises exactly one step over the contact distance.
        assert!((p.max_grade * p.contact_distance_m() - p.max_step_m).abs() < 1e-6);
        assert!(RobotProfile { max_grade: 0.0, ..p }.validate().is_err());
    }

    #[test]
    fn the_contact_rule_is_uncertain_within_kappa_sigma_of_either_threshold() {
        let p = RobotProfile::default();
        let rule = TraversabilityRule::Contact {
            kappa: 2.0,
            reach_m: DEFAULT_REACH_M,
        };
        // 1 cm known to 5 mm: drivable; 3.9 cm known to 1 mm: blocked.
        assert_eq!(step_decision(0.010, 0.005, rule, &p), Traversability::Traversable);
        assert_eq!(step_decision(0.039, 0.001, rule, &p), Traversability::Blocked);
        // 3.9 cm known to 1 cm (4 mm over the threshold under 1 cm noise): cannot tell.
        assert_eq!(step_decision(0.039, 0.01, rule, &p), Traversability::Uncertain);
        assert_eq!(step_decision(0.031, 0.01, rule, &p), Traversability::Uncertain);
        // A structure 1 cm above the robot's height, known to 1 cm: it may or may not pass under it.
        assert_eq!(step_decision(0.47, 0.01, rule, &p), Traversability::Uncertain);
        assert_eq!(step_decision(0.30, 0.01, rule, &p), Traversability::Blocked);
        assert!(
            TraversabilityRule::Contact {
                kappa: -1.0,
                reach_m: DEFAULT_REACH_M
            }
            .validate()
            .is_err()
        );
    }
}
