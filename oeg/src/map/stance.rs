//! The ground a robot stands on, as a measurement: elevation_mapping_cupy's initializer at start (its
//! `use_initializer_at_start`, which lays a plane through the robot's footprint frames into the map before the
//! first point cloud). The sensors of a robot rarely see under it, so without it the cells under its start are
//! never observed, and every cell within a wheel's contact distance of them is a frontier cell
//! ([`crate::Doubt::Frontier`]): the robot is sealed in by the ground it stands on.

use nalgebra::Point3;

use super::Map;
use crate::cell::Cell;
use crate::error::{Error, Result};
use crate::footprint::{Footprint, Pose2};
use crate::geometry::{CellIndex, CellRegion, GridWindow};
use crate::model::{Ceiling, log_odds, update_log_odds};
use crate::storage::{TileIndex, offset_in_tile};
use crate::traversability::TraversabilityRule;

/// Default standard deviation of a wheel's contact height, metres: a tyre's deflection under the robot's
/// weight, and the pose's height error at the start (5 mm).
pub const DEFAULT_STANCE_SIGMA_M: f32 = 0.005;

/// How far outside its footprint's circumscribed circle a contact point may lie, metres: a wheel's contact is
/// under the robot.
const CONTACT_TOLERANCE_M: f64 = 0.1;

/// Where a robot stands: the world points where its wheels (or feet) touch the ground, and its footprint at
/// its planar pose. [`Map::integrate_stance`] takes it as a measurement of the ground under the footprint.
#[derive(Debug, Clone, PartialEq)]
pub struct Stance {
    /// The contact points, world metres: at least one. Three or more not on one line give the ground's plane
    /// (least squares); fewer give a level plane at their mean height.
    pub contacts: Vec<Point3<f64>>,
    /// The robot's footprint in its base frame.
    pub footprint: Footprint,
    /// The robot's planar pose: where the footprint lies.
    pub pose: Pose2,
    /// Standard deviation of a contact's height, metres ([`DEFAULT_STANCE_SIGMA_M`]).
    pub sigma_m: f32,
}

/// The ground's plane through the contacts: `z = z0 + gx (x - x0) + gy (y - y0)`, and the root mean square of
/// the contacts' distances from it (a twist of the ground between the wheels).
#[derive(Debug, Clone, Copy, PartialEq)]
struct GroundPlane {
    centre: Point3<f64>,
    gradient: (f64, f64),
    residual_m: f64,
}

impl GroundPlane {
    fn fit(contacts: &[Point3<f64>]) -> Self {
        let n = contacts.len() as f64;
        let centre = Point3::from(contacts.iter().map(|p| p.coords).sum::<nalgebra::Vector3<f64>>() / n);
        let (mut sxx, mut sxy, mut syy, mut sxz, mut syz) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for p in contacts {
            let d = p - centre;
            (sxx, sxy, syy) = (sxx + d.x * d.x, sxy + d.x * d.y, syy + d.y * d.y);
            (sxz, syz) = (sxz + d.x * d.z, syz + d.y * d.z);
        }
        // Contacts on one line (or fewer than three) leave the slope across it unknown: level.
        let det = sxx * syy - sxy * sxy;
        let gradient = if contacts.len() >= 3 && det > 1e-12 * (sxx + syy).powi(2).max(f64::MIN_POSITIVE) {
            ((syy * sxz - sxy * syz) / det, (sxx * syz - sxy * sxz) / det)
        } else {
            (0.0, 0.0)
        };
        let mut plane = Self {
            centre,
            gradient,
            residual_m: 0.0,
        };
        let squares: f64 = contacts
            .iter()
            .map(|p| (p.z - plane.z_at(p.x, p.y)).powi(2))
            .sum();
        plane.residual_m = (squares / n).sqrt();
        plane
    }

    fn z_at(&self, x: f64, y: f64) -> f64 {
        self.centre.z + self.gradient.0 * (x - self.centre.x) + self.gradient.1 * (y - self.centre.y)
    }
}

impl Stance {
    /// Checks the stance for sense ([`Map::integrate_stance`] does too).
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] for a stance with no contact point, or with a value that is not finite, a
    /// footprint that is no rectangle, a standard deviation that is not positive, a contact point farther from
    /// the robot than its footprint reaches (plus 0.1 m), or contact points that give no finite plane.
    pub fn validate(&self) -> Result<()> {
        self.ground().map(|_| ())
    }

    /// The ground's plane and the variance of a height on it, after the checks [`Stance::validate`] names, all
    /// made here: validating and integrating fit the plane once each.
    fn ground(&self) -> Result<(GroundPlane, f32)> {
        let bad = |message: String| Error::setting("stance", message);
        if self.contacts.is_empty() {
            return Err(bad("needs at least one contact point".into()));
        }
        if let Some(p) = self
            .contacts
            .iter()
            .find(|p| !p.coords.iter().all(|v| v.is_finite()))
        {
            return Err(bad(format!("contact point {p:?} is not finite")));
        }
        let f = &self.footprint;
        if ![f.min_x_m, f.max_x_m, f.min_y_m, f.max_y_m]
            .iter()
            .all(|v| v.is_finite())
            || f.length_m() <= 0.0
            || f.width_m() <= 0.0
        {
            return Err(bad(format!("footprint {f:?} is not a finite rectangle")));
        }
        if ![self.pose.x_m, self.pose.y_m, self.pose.yaw_rad]
            .iter()
            .all(|v| v.is_finite())
        {
            return Err(bad(format!("pose {:?} is not finite", self.pose)));
        }
        if !(self.sigma_m.is_finite() && self.sigma_m > 0.0) {
            return Err(bad(format!(
                "sigma_m must be a positive number of metres, got {}",
                self.sigma_m
            )));
        }
        // The contacts lie under the robot: within its footprint's reach of its position.
        let reach = self.footprint.circumscribed_radius_m() + CONTACT_TOLERANCE_M;
        if let Some(p) = self
            .contacts
            .iter()
            .find(|p| (p.x - self.pose.x_m).hypot(p.y - self.pose.y_m) > reach)
        {
            return Err(bad(format!(
                "contact point {p:?} lies more than {reach} m from the robot at ({}, {})",
                self.pose.x_m, self.pose.y_m
            )));
        }
        let plane = GroundPlane::fit(&self.contacts);
        let sigma = f64::from(self.sigma_m);
        let var_m2 = (sigma * sigma + plane.residual_m * plane.residual_m) as f32;
        let finite = [plane.gradient.0, plane.gradient.1, plane.centre.z]
            .iter()
            .all(|v| (*v as f32).is_finite());
        if !(finite && var_m2.is_finite()) {
            return Err(bad(format!(
                "the contact points {:?} give no finite plane",
                self.contacts
            )));
        }
        Ok((plane, var_m2))
    }
}

/// The space a robot's body fills over its footprint, metres above the ground its wheels stand on: from the
/// underside of its chassis (its ground clearance; the wheels alone reach lower) up to its height. What lies
/// in it where the robot stands is gone ([`Map::integrate_footprint`]); what lies under the chassis between
/// the wheels, lower than `underside_m`, the robot may straddle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodySpan {
    /// The chassis' lowest point above the wheels' contacts, metres.
    pub underside_m: f32,
    /// The robot's highest point above them, metres.
    pub height_m: f32,
}

impl TraversabilityRule {
    /// Whether the rule's frontier test ([`crate::Doubt::Frontier`]) needs the ground a robot stands on as a
    /// measurement ([`Map::integrate_stance`]): the contact rule's does, or the cells around a robot whose
    /// sensors never see under it stay frontier cells. The other rules judge each cell by its own estimate.
    pub fn needs_stance(&self) -> bool {
        matches!(self, Self::Contact { .. })
    }
}

impl Map {
    /// Takes the ground under a standing robot as one measurement of the cells its footprint covers that no
    /// scan has observed: each gets one hit's occupancy (`p_max`) and the height of the plane through the
    /// contact points at its centre, with the contacts' variance plus the square of the plane's residual. A
    /// cell a scan observed keeps what the scan measured. Returns the cells it set.
    ///
    /// The contact rule's frontier ([`crate::Doubt::Frontier`]) needs it: without it the cells under a robot
    /// whose sensors look ahead are never observed, and those around them are frontier cells. `oeg run` gives
    /// it at the start to maps judged by [`crate::TraversabilityRule::Contact`]; the paper's model, and a map
    /// built from inputs that record no robot (scan graphs, point clouds, bags), never take one.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] for a stance [`Stance::validate`] refuses, or one whose footprint lies beyond the
    /// grid; [`Error::MemoryLimit`] if the footprint's tiles would exceed the map's limit (nothing is set then).
    pub fn integrate_stance(&mut self, stance: &Stance) -> Result<u64> {
        self.lay_ground(stance, None)
    }

    /// Takes a driving robot's stance as what it is, proof of what its body occupies (nav2's footprint
    /// clearing, the obstacle layer's `footprint_clearing_enabled`, on by default, kept to the space the body
    /// fills): as [`Map::integrate_stance`] for the cells under the footprint that no scan measured, and
    /// besides:
    /// * an estimate above the plane by more than the chassis' clearance (`body.underside_m`) plus the surface
    ///   band ([`crate::ModelOptions::surface_band_sigmas`] standard deviations of the difference) lies where
    ///   the body is: a spurious return that no later beam passed through (the space between a push-broom
    ///   lidar and the ground its line sweeps is never crossed again), a person who left. It takes the plane
    ///   too. Lower ones (a curb under the chassis' overhang) are kept, and so are cells seen only free: a
    ///   wheel's contact, inferred from the pose, set into free cells would stand out of them, and the rules
    ///   that judge a free cell by the estimates beside it would read a step there;
    /// * a structure over a cell ([`Map::ceiling`]) whose lowest hits lie within the body's span is removed.
    ///
    /// Returns the cells it set.
    ///
    /// The robot has to be where the stance says: `oeg run` gives it the stance at the estimated pose after
    /// every batch of scans, for the maps judged by [`crate::TraversabilityRule::Contact`].
    ///
    /// # Errors
    /// As [`Map::integrate_stance`].
    pub fn integrate_footprint(&mut self, stance: &Stance, body: BodySpan) -> Result<u64> {
        self.lay_ground(stance, Some(body))
    }

    /// The plane under `stance` into the cells under its footprint that no scan measured, and, given the
    /// robot's `body`, into those whose estimate it contradicts ([`Map::integrate_footprint`]).
    fn lay_ground(&mut self, stance: &Stance, body: Option<BodySpan>) -> Result<u64> {
        let (plane, var_m2) = stance.ground()?;
        let cells = self.cells_under_footprint(&stance.footprint, stance.pose)?;
        let tiles: Vec<TileIndex> = {
            let mut t: Vec<TileIndex> = cells.iter().map(|c| TileIndex::of(*c)).collect();
            t.sort_unstable();
            t.dedup();
            t
        };
        let limit = self
            .config
            .memory_limit_bytes
            .saturating_sub(self.ceilings.memory_bytes() + self.own_bytes());
        let new_tiles = tiles.iter().filter(|t| !self.cells.has_tile(**t)).count() as u64;
        let requested =
            self.cells.memory_bytes() + new_tiles * crate::storage::TileGrid::<Cell>::tile_bytes() as u64;
        if requested > limit {
            return Err(Error::MemoryLimit {
                requested_bytes: requested + self.ceilings.memory_bytes() + self.own_bytes(),
                limit_bytes: self.config.memory_limit_bytes,
            });
        }
        let opts = &self.config.model;
        let hit = update_log_odds(0.0, log_odds(opts.p_max), opts.log_odds_min, opts.log_odds_max);
        let band_sigmas = opts.surface_band_sigmas;
        let mut set = 0;
        for cell in cells {
            let tile = self
                .cells
                .tile_or_insert(TileIndex::of(cell), u64::MAX)
                .map_err(|e| Error::MemoryLimit {
                    requested_bytes: e.requested_bytes,
                    limit_bytes: self.config.memory_limit_bytes,
                })?;
            let c = &mut tile[offset_in_tile(cell)];
            let (x, y) = self.geometry.cell_center(cell);
            let ground_m = plane.z_at(x, y) as f32;
            if let (Some(body), Some(ceilings)) = (body, self.ceilings.tile_mut(TileIndex::of(cell))) {
                let ceiling = &mut ceilings[offset_in_tile(cell)];
                let over_m = ceiling.z_m - ground_m;
                if ceiling.is_some() && over_m < body.height_m && over_m > body.underside_m {
                    *ceiling = Ceiling::NONE;
                }
            }
            // An estimate the body's span contradicts; a cell seen only free has none.
            let contradicted = body.is_some_and(|b| {
                c.elevation().is_some_and(|e| {
                    e.mean_m - ground_m - band_sigmas * (e.var_m2 + var_m2).sqrt() > b.underside_m
                })
            });
            if c.is_observed() && !contradicted {
                continue;
            }
            *c = Cell {
                log_odds: hit.max(c.log_odds),
                mean_m: ground_m,
                var_m2,
            };
            set += 1;
        }
        Ok(set)
    }

    /// The cells the footprint at `pose` overlaps ([`Footprint::cells_under`]).
    fn cells_under_footprint(&self, footprint: &Footprint, pose: Pose2) -> Result<Vec<CellIndex>> {
        let (lo, hi) = footprint.bounds(pose);
        let region: CellRegion = self.geometry.region_covering(lo, hi)?;
        Ok(footprint.cells_under(&GridWindow::new(self.geometry, region), pose))
    }
}

#[cfg(test)]
mod tests;
