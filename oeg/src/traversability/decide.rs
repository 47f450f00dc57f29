//! The part of the traversability decision that reads the map: a cell's surface, the grounds around it and
//! the structure over it, judged by the pure rules of [`super::rules`].

use super::rules::{
    Doubt, RobotProfile, Traversability, TraversabilityRule, ceiling_decision, contact_decision,
    footprint_decision, more_restrictive, step_decision,
};
use crate::geometry::CellIndex;
use crate::map::Map;
use crate::model::{Elevation, HitHeight, ceiling_confirmed};

/// How far `top` lies above `ground`, metres, with the standard deviation of the difference.
fn rise_over(top: Elevation, ground: Elevation) -> (f32, f32) {
    (top.mean_m - ground.mean_m, (top.var_m2 + ground.var_m2).sqrt())
}

impl Map {
    /// The traversability of one cell for `profile` under `rule`: its surface's decision, or the structure's
    /// over it ([`crate::OverheadHits::Ceiling`], [`ceiling_decision`]) where that is more restrictive.
    pub fn traversability(
        &self,
        cell: CellIndex,
        profile: &RobotProfile,
        rule: TraversabilityRule,
    ) -> Traversability {
        self.decision(cell, profile, rule).class
    }

    /// Why [`Map::traversability`] cannot decide `cell`: the rule that could not tell for an uncertain cell, or
    /// why an observed cell is left unknown ([`Doubt::Frontier`], [`Doubt::NoHeight`]); `None` for a decided or
    /// a never observed cell.
    pub fn doubt(&self, cell: CellIndex, profile: &RobotProfile, rule: TraversabilityRule) -> Option<Doubt> {
        self.decision(cell, profile, rule).doubt
    }

    /// [`Map::traversability`] with the reason when the class leaves the cell undecided ([`Map::doubt`]).
    pub(super) fn decision(
        &self,
        cell: CellIndex,
        profile: &RobotProfile,
        rule: TraversabilityRule,
    ) -> Decision {
        let d = self.cell_decision(cell, profile, rule);
        // The frontier: a wheel on a drivable cell may come from any cell within the contact distance, and one
        // the map never observed may hold a step. The cell is not known to be drivable until its whole contact
        // window is observed: it is unknown, as the cells it borders (the planner neither enters nor inflates
        // them, and plans through them optimistically beyond its stopping distance), not an obstacle.
        if matches!(rule, TraversabilityRule::Contact { .. })
            && d.class.is_drivable()
            && self.unobserved_within(cell, profile.contact_distance_m())
        {
            return Decision {
                class: Traversability::Unknown,
                doubt: Some(Doubt::Frontier),
            };
        }
        d
    }

    /// [`Map::decision`] before the frontier test: the surface's decision or the structure's.
    fn cell_decision(&self, cell: CellIndex, profile: &RobotProfile, rule: TraversabilityRule) -> Decision {
        let surface = self.surface_traversability(cell, profile, rule);
        let Some(ceiling) = self.ceiling(cell) else {
            return surface;
        };
        let confirmed = ceiling_confirmed(ceiling.log_odds, self.config.model.p_max);
        let kappa = match rule {
            TraversabilityRule::Contact { kappa, .. } => kappa,
            _ => 0.0,
        };
        // The clearance is measured from the cell's own surface, the ground the structure was seen over; a cell
        // that has forgotten it measures from the lowest level in the robot's contact distance.
        let ground = self
            .cell(cell)
            .elevation()
            .or_else(|| self.ground_within(cell, profile.contact_distance_m(), kappa));
        let structure = Elevation {
            mean_m: ceiling.z_m,
            var_m2: ceiling.var_m2,
        };
        let over_ceiling = match ground {
            Some(g) => {
                let (clearance, sigma) = rise_over(structure, g);
                let passed_under_m = ceiling.clear_m - g.mean_m;
                ceiling_decision(clearance, passed_under_m, sigma, kappa, profile, confirmed).map(|class| {
                    let doubt = (class == Traversability::Uncertain)
                        .then(|| ceiling_doubt(clearance, sigma * kappa, profile, confirmed));
                    Decision { class, doubt }
                })
            }
            None => Some(Decision::uncertain(Doubt::StructureNoGround)),
        };
        match over_ceiling {
            Some(c) if more_restrictive(surface.class, Some(c.class)) != surface.class => c,
            _ => surface,
        }
    }

    /// The traversability of one cell's surface for `profile` under `rule`.
    fn surface_traversability(
        &self,
        cell: CellIndex,
        profile: &RobotProfile,
        rule: TraversabilityRule,
    ) -> Decision {
        let c = self.cell(cell);
        if !c.is_observed() {
            return Traversability::Unknown.into();
        }
        if c.log_odds <= self.occupied_log_odds() {
            // Beams passed through the cell and none ended in it: no height was measured, and the beams bound it
            // only from above (a low wall's top that the lidar grazes is passed over, never hit). The contact
            // rule judges it by the estimates around it.
            return match (rule, c.elevation()) {
                (TraversabilityRule::Contact { kappa, reach_m }, None) => {
                    self.unmeasured(cell, profile, kappa, reach_m, Doubt::BesideStep)
                }
                _ => Traversability::Free.into(),
            };
        }
        let Some(e) = c.elevation() else {
            // Occupied, height unknown. Under the contact rule the cell lies within a beam's range noise of its end point, which alone measures a height
            // ([`crate::HitHeight::Endpoint`]): the surface it belongs to was measured around it, and it is
            // judged by the estimates within the contact distance as a free cell is. With none there, its
            // height is unknown, as a clearance never observed is: neither drivable nor an obstacle.
            return match rule {
                TraversabilityRule::Contact { kappa, reach_m } => {
                    if self.has_estimate_within(cell, profile.contact_distance_m()) {
                        let d = self.unmeasured(cell, profile, kappa, reach_m, Doubt::BesideStep);
                        match d.class {
                            Traversability::Free => Traversability::Traversable.into(),
                            _ => d,
                        }
                    } else {
                        Decision {
                            class: Traversability::Unknown,
                            doubt: Some(Doubt::NoHeight),
                        }
                    }
                }
                // Under the endpoint height rule only a beam's end cell measures a height, by design: the
                // cells within its range noise are occupied and hold none, and the surface they belong to was
                // measured around them. They are judged as high as the highest estimate next to them. Under
                // the beam-sample rule an occupied cell without a height is weak evidence of something
                // unmeasured, and the rules without an uncertain answer assume the worst, as published.
                _ if self.config.model.hit_height == HitHeight::Endpoint => {
                    match self.highest_neighbour(cell) {
                        Some(h) => self.judge_surface(cell, h, profile, rule),
                        None => Decision {
                            class: Traversability::Unknown,
                            doubt: Some(Doubt::NoHeight),
                        },
                    }
                }
                _ => Traversability::Blocked.into(),
            };
        };
        match rule {
            TraversabilityRule::Contact { kappa, reach_m } => {
                // One walk over the wider of the two windows gives both grounds.
                let [wide, ground] = self
                    .grounds_within(cell, [reach_m, profile.contact_distance_m()], kappa)
                    .map(|g| g.unwrap_or(e));
                let (wide_rise, wide_sigma) = rise_over(e, wide);
                // A cell measured too coarsely to tell level ground from a step is imprecise, whichever band
                // its estimate falls in.
                let band_doubt = |doubt| {
                    if imprecise(e, kappa, profile) {
                        Doubt::Imprecise
                    } else {
                        doubt
                    }
                };
                if let Some(t) = footprint_decision(wide_rise, wide_sigma, reach_m, kappa, profile) {
                    return Decision::or_doubt(t, band_doubt(Doubt::FootprintBand));
                }
                let (step, sigma) = rise_over(e, ground);
                let decision = contact_decision(step, sigma, kappa, profile);
                // A wheel may come from any cell within the contact distance. One with no height that may be
                // part of a step (the shadow behind a curb's far edge: `unmeasured_decision`) may lie a step
                // lower: the cell cannot be called drivable.
                if decision == Traversability::Traversable
                    && self.step_may_hide_within(cell, (e, wide), profile, kappa, reach_m)
                {
                    Decision::uncertain(Doubt::HiddenStep)
                } else if (step - profile.height_m).abs() <= kappa * sigma {
                    Decision::or_doubt(decision, Doubt::HeightBand)
                } else {
                    Decision::or_doubt(decision, band_doubt(Doubt::StepBand))
                }
            }
            _ => self.judge_surface(cell, e, profile, rule),
        }
    }

    /// The decision of the rules that judge a surface alone ([`TraversabilityRule::Terrain`], `Absolute` and
    /// `Conservative`) for `cell` at the height `e`: the terrain rule's step over the lowest estimate of its 3 x 3
    /// neighbourhood, or the absolute height.
    fn judge_surface(
        &self,
        cell: CellIndex,
        e: Elevation,
        profile: &RobotProfile,
        rule: TraversabilityRule,
    ) -> Decision {
        let step_m = match rule {
            TraversabilityRule::Terrain => {
                let ground = self
                    .neighbourhood(cell)
                    .filter_map(|n| self.cell(n).elevation())
                    .fold(e.mean_m, |g, ne| g.min(ne.mean_m));
                e.mean_m - ground
            }
            _ => e.mean_m,
        };
        step_decision(step_m, e.var_m2.sqrt(), rule, profile).into()
    }

    /// [`TraversabilityRule::Contact`]'s decision for a free cell, which holds no height: `Free` where the
    /// cells around it say it is ground, `Uncertain` where it may be part of a step. The cell is judged as if it
    /// were as high as the highest estimate within the contact distance: where that would be drivable, the
    /// cell lies in ground that is level to within a step (a gap between a lidar's rings, ground the robot
    /// drove over out of its sensors' view); where it would not, it lies beside something higher (the top of a
    /// low wall that the lidar grazes and never hits, the shadow behind a curb) and cannot be told from it.
    /// With no estimate within reach it is free, as in the paper.
    pub fn unmeasured_decision(
        &self,
        cell: CellIndex,
        profile: &RobotProfile,
        kappa: f32,
        reach_m: f32,
    ) -> Traversability {
        self.unmeasured(cell, profile, kappa, reach_m, Doubt::BesideStep)
            .class
    }

    /// [`Map::unmeasured_decision`], with `doubt` as the reason for an uncertain cell, or
    /// [`Doubt::Imprecise`] when the higher estimate it is judged by is too coarse to tell a step.
    fn unmeasured(
        &self,
        cell: CellIndex,
        profile: &RobotProfile,
        kappa: f32,
        reach_m: f32,
        doubt: Doubt,
    ) -> Decision {
        // Level ground, the common case, in one pass: where no estimate within reach rises a step over another,
        // the cell is ground. The tests below would say so too: the rises they take are at most `hi - lo`, and
        // their standard deviations at most `sqrt(2 var_max)`.
        // The same pass finds the highest estimate within the contact distance (the last of equal ones).
        let contact = self.reach_cells(profile.contact_distance_m());
        let (mut lo, mut hi, mut var_max) = (f32::INFINITY, f32::NEG_INFINITY, 0.0_f32);
        let mut highest: Option<Elevation> = None;
        for (gap2, c) in self.cells_within(cell, reach_m.max(profile.contact_distance_m())) {
            if let Some(e) = self.cell(c).elevation() {
                (lo, hi, var_max) = (lo.min(e.mean_m), hi.max(e.mean_m), var_max.max(e.var_m2));
                if gap2 <= contact * contact && highest.is_none_or(|h| e.mean_m.total_cmp(&h.mean_m).is_ge())
                {
                    highest = Some(e);
                }
            }
        }
        if lo > hi || hi - lo + kappa * (2.0 * var_max).sqrt() < profile.max_step_m {
            return Traversability::Free.into();
        }
        let [wide, ground] = self.grounds_within(cell, [reach_m, profile.contact_distance_m()], kappa);
        let (Some(highest), Some(wide), Some(ground)) = (highest, wide, ground) else {
            return Traversability::Free.into();
        };
        let top = self.top_level(cell, highest, profile.contact_distance_m(), kappa);
        let (wide_rise, wide_sigma) = rise_over(top, wide);
        let (step, sigma) = rise_over(top, ground);
        let level = footprint_decision(wide_rise, wide_sigma, reach_m, kappa, profile).is_none()
            && contact_decision(step, sigma, kappa, profile) == Traversability::Traversable;
        if level {
            Traversability::Free.into()
        } else if imprecise(highest, kappa, profile) {
            // The level's variance is that of a mean; each estimate in it is as coarse as the highest.
            Decision::uncertain(Doubt::Imprecise)
        } else {
            Decision::uncertain(doubt)
        }
    }

    /// Whether a free cell within the robot's contact distance of `cell` may lie a step below it: `cell`'s
    /// surface lies a step or more above the lowest ground within `reach_m` (`surface` and that ground), and
    /// the free cell may be part of a step ([`Map::unmeasured_decision`] says `Uncertain`). The shadow behind
    /// a curb's far edge is such a cell for the curb's top; for the ground beyond the shadow it is not.
    fn step_may_hide_within(
        &self,
        cell: CellIndex,
        (surface, wide): (Elevation, Elevation),
        profile: &RobotProfile,
        kappa: f32,
        reach_m: f32,
    ) -> bool {
        let (drop, sigma) = rise_over(surface, wide);
        if contact_decision(drop, sigma, kappa, profile) == Traversability::Traversable {
            return false;
        }
        self.cells_within(cell, profile.contact_distance_m())
            .any(|(_, c)| {
                let n = self.cell(c);
                n.is_observed()
                    && n.log_odds <= self.occupied_log_odds()
                    && n.elevation().is_none()
                    && self.unmeasured_decision(c, profile, kappa, reach_m) == Traversability::Uncertain
            })
    }
}

/// A cell's class and, when it is left undecided, why.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Decision {
    pub(super) class: Traversability,
    pub(super) doubt: Option<Doubt>,
}

impl Decision {
    fn uncertain(doubt: Doubt) -> Self {
        Self {
            class: Traversability::Uncertain,
            doubt: Some(doubt),
        }
    }

    /// `class`, with `doubt` as the reason if it is uncertain.
    fn or_doubt(class: Traversability, doubt: Doubt) -> Self {
        Self {
            class,
            doubt: (class == Traversability::Uncertain).then_some(doubt),
        }
    }
}

impl From<Traversability> for Decision {
    fn from(class: Traversability) -> Self {
        Self { class, doubt: None }
    }
}

/// Whether an estimate is too coarse to tell level ground from a step: beside a neighbour measured as well, the
/// difference of two level cells (standard deviation `sqrt(2) sigma`) would reach a step within `kappa` standard
/// deviations, so the uncertain band holds level ground itself. The sensors' resolution at that range, not a
/// surface near a threshold.
fn imprecise(e: Elevation, kappa: f32, profile: &RobotProfile) -> bool {
    kappa * (2.0 * e.var_m2).sqrt() >= profile.max_step_m
}

/// Which of [`ceiling_decision`]'s tests left a structure uncertain, for a `clearance_m` with an uncertain band
/// of `band_m` on either side.
fn ceiling_doubt(clearance_m: f32, band_m: f32, profile: &RobotProfile, confirmed: bool) -> Doubt {
    if clearance_m > profile.height_m + band_m {
        Doubt::UndersideUnseen
    } else if !confirmed
        && clearance_m > profile.max_step_m + band_m
        && clearance_m < profile.height_m - band_m
    {
        Doubt::StructureUnconfirmed
    } else {
        Doubt::StructureBand
    }
}
