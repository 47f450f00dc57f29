//! The part of one ray the map learns from (eq. 10-12's parameters along it): where its samples start and
//! end, the variance its heights get, and a near-hit sample's probability and height.

use nalgebra::Vector3;

use crate::model::{
    GAUSSIAN_CUTOFF_SIGMAS, HitHeight, ModelOptions, clamp_probability, elevation_observation,
    inverse_sensor_model, vertical_variance,
};
use crate::scan::{Ray, RayKind, Scan};
use crate::sensor::{MIN_RANGE_SIGMA_M, RangeNoiseModel};
use crate::traversal::CellCrossing;

/// The part of one ray the map learns from, in the ray's parameter (metres along it from the sensor).
pub(super) struct RaySpan {
    /// The sensor.
    pub(super) origin: Vector3<f64>,
    /// The unit direction.
    pub(super) dir: Vector3<f64>,
    /// The hit's range and its standard deviation, or `None` for a ray that only clears.
    pub(super) hit: Option<(f64, f64)>,
    /// Where the span starts, after height thresholding.
    pub(super) l_lo: f64,
    /// Where it ends: 3 sigma past the hit, the clearing range, or the height threshold.
    pub(super) l_hi: f64,
    /// The variance a sample's height gets (the range variance, or its vertical projection).
    pub(super) s2: f32,
    /// Samples that end before this are plain free samples (`p = p_min`, no exponential); only the few cells
    /// within 3 sigma of the hit evaluate eq. 10.
    pub(super) free_until: f64,
    /// The sensor's range error model and range.
    pub(super) noise: RangeNoiseModel,
    pub(super) max_range_m: f64,
}

impl RaySpan {
    /// The span of `ray`, or `None` for a ray that teaches nothing (zero length, or wholly above the height
    /// threshold).
    #[inline(always)]
    pub(super) fn of(scan: &Scan, ray: &Ray, opts: &ModelOptions) -> Option<Self> {
        let o = scan.origin_in_world.coords;
        let clear_range_m = f64::from(opts.no_return_clear_range_m.unwrap_or(scan.sensor.max_range_m));
        let max_range_m = opts.max_range_m.map_or(f64::INFINITY, f64::from);
        let v: Vector3<f64> = ray.offset_in_world.cast();
        let length = v.norm();
        if length == 0.0 {
            return None;
        }
        let dir = v / length;
        // The hit range, or None for a ray that only clears; and the end of the traversal.
        let (hit, l_end) = match ray.kind {
            RayKind::Hit if length <= max_range_m => {
                let sigma = ray
                    .range_sigma_m
                    .unwrap_or_else(|| scan.sensor.sigma_m(length as f32));
                let sigma = f64::from(sigma.max(MIN_RANGE_SIGMA_M));
                (
                    Some((length, sigma)),
                    length + f64::from(GAUSSIAN_CUTOFF_SIGMAS) * sigma,
                )
            }
            RayKind::Hit => (None, max_range_m),
            RayKind::NoReturn => (None, clear_range_m.min(max_range_m)),
        };
        let sigma_for_free = hit.map_or_else(
            || {
                f64::from(
                    ray.range_sigma_m
                        .unwrap_or_else(|| scan.sensor.sigma_m(l_end as f32)),
                )
            },
            |(_, s)| s,
        );
        // Height thresholding: keep the part of the ray at or below max_height above the robot's ground.
        let (mut l_lo, mut l_hi): (f64, f64) = (0.0, l_end);
        if let Some(h) = opts.max_height_m {
            let h = f64::from(h) + scan.ground_z_m.unwrap_or(0.0);
            if dir.z > 0.0 {
                l_hi = l_hi.min((h - o.z) / dir.z);
            } else if dir.z < 0.0 {
                l_lo = l_lo.max((h - o.z) / dir.z);
            } else if o.z > h {
                l_hi = -1.0;
            }
        }
        if l_hi < l_lo {
            return None;
        }
        let s2 = if opts.vertical_variance {
            vertical_variance(sigma_for_free, dir.z, hit.map_or(l_end, |(l, _)| l))
        } else {
            (sigma_for_free * sigma_for_free) as f32
        };
        let free_until = hit.map_or(f64::INFINITY, |(l_p, s)| {
            l_p - f64::from(GAUSSIAN_CUTOFF_SIGMAS) * s
        });
        Some(Self {
            origin: o,
            dir,
            hit,
            l_lo,
            l_hi,
            s2,
            free_until,
            noise: scan.sensor.noise,
            max_range_m: f64::from(scan.sensor.max_range_m),
        })
    }

    /// The variance of the hit's height had its beam met a surface at `surface_m`, where a descending beam
    /// crosses that height: the sensor's range error there, in proportion to the hit's own
    /// ([`RangeNoiseModel::sigma_m`]). A sensor reports the error of the range it measured, so a reading
    /// that fell short of the surface reports less error than the beam has there, and one that went long
    /// more: weighted by what they report, the short ones would pull the surface up, and one far short would
    /// look like a structure over it. The hit's own variance for a level or rising beam, or a surface not
    /// below the sensor. `vertical`: the variance projected on the vertical
    /// ([`ModelOptions::vertical_variance`]).
    pub(super) fn s2_meeting(&self, surface_m: f32, vertical: bool) -> f32 {
        let Some((l_p, sigma)) = self.hit else {
            return self.s2;
        };
        let r0 = (f64::from(surface_m) - self.origin.z) / self.dir.z;
        if self.dir.z >= 0.0 || r0.is_nan() || r0 <= 0.0 {
            return self.s2;
        }
        let r0 = r0.min(self.max_range_m);
        let (at_hit, at_surface) = (self.noise.sigma_m(l_p as f32), self.noise.sigma_m(r0 as f32));
        if at_hit.is_nan() || at_hit <= 0.0 || !at_surface.is_finite() {
            return self.s2;
        }
        let sigma0 = (sigma * f64::from(at_surface / at_hit)).max(f64::from(MIN_RANGE_SIGMA_M));
        if vertical {
            vertical_variance(sigma0, self.dir.z, r0)
        } else {
            (sigma0 * sigma0) as f32
        }
    }

    /// The most cells the samples within 3 sigma of the hit can cross, at `resolution_m`: a straight segment
    /// crosses one cell more than the cell boundaries it passes, at most `|dx| / resolution_m + 1` of each
    /// axis (and one more for rounding).
    #[inline]
    pub(super) fn near_hit_cells(&self, resolution_m: f64) -> usize {
        let length = (self.l_hi - self.free_until.max(self.l_lo)).max(0.0);
        let across = (self.dir.x.abs() + self.dir.y.abs()) * length / resolution_m;
        // A finite ray's span is bounded by the grid's index range ([`super::integrate`]'s walk check).
        across as usize + 4
    }

    /// The beam's height at `l` along it.
    #[inline(always)]
    pub(super) fn height_at(&self, l: f64) -> f64 {
        self.origin.z + self.dir.z * l
    }

    /// The beam's highest and lowest heights inside a crossed cell, from its heights where it enters
    /// (`z_enter_m`, [`RaySpan::height_at`] the crossing's `l_enter`) and leaves (`z_exit_m`): the beam is
    /// straight, so they are its heights at the crossing's two ends, the higher first (the enter height when
    /// the two are equal).
    #[inline(always)]
    pub(super) fn top_and_bottom(z_enter_m: f64, z_exit_m: f64) -> (f32, f32) {
        if z_exit_m > z_enter_m {
            (z_exit_m as f32, z_enter_m as f32)
        } else {
            (z_enter_m as f32, z_exit_m as f32)
        }
    }

    /// A sample within 3 sigma of the hit: eq. 10's probability (clamped), and eq. 12's height where the cell
    /// measures one (every such cell, or only the end point's under [`HitHeight::Endpoint`]). Within 3 sigma
    /// of the measured range the surface may lie anywhere: a sample without a height counts for the occupancy,
    /// but its height bounds nothing (a noisy long reading would otherwise "prove" free space under the
    /// ground).
    #[inline(always)]
    pub(super) fn hit_probability_and_height(
        &self,
        opts: &ModelOptions,
        crossing: &CellCrossing,
    ) -> (f32, Option<f32>) {
        let Some((l_p, sigma)) = self.hit else {
            unreachable!("free_until is infinite without a hit")
        };
        let l = l_p.clamp(crossing.l_enter, crossing.l_exit);
        let p = inverse_sensor_model(
            l as f32,
            l_p as f32,
            sigma as f32,
            opts.significance_k_m,
            opts.p_min,
        );
        let p = clamp_probability(p, opts.p_min, opts.p_max);
        // Under `HitHeight::Endpoint` only the cell holding the end point (where the clamp leaves `l_p` as it
        // is) measures a height.
        let measures_height = opts.hit_height == HitHeight::BeamSample || l == l_p;
        let z = elevation_observation(
            p,
            (self.origin.z + self.dir.z * l) as f32,
            opts.elevation_threshold,
        )
        .filter(|_| measures_height);
        (p, z)
    }
}
