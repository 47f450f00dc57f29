//! The rules beyond the paper's equations, one pure function each: how a scan's hits in a cell combine, how a
//! hit is fused with a cell's estimate, and whether a free sample says anything about a cell. The options
//! that select them are in [`super::options`]; `docs/design/robust-model.md` gives each rule's source.

use super::equations::{Elevation, kalman_fuse, log_odds, update_log_odds};
use super::options::{ElevationFusion, FreeSpaceOccupancy, ModelOptions, ScanHitElevation};
use super::{Ceiling, SeenFrom};

/// Fuses the elevation measurement `h` (variance `s2`) into `prior` under `rule` (see [`ElevationFusion`]);
/// `band_sigmas` is the surface band's half width for [`ElevationFusion::TopSurface`].
pub fn fuse_elevation(
    rule: ElevationFusion,
    prior: Option<Elevation>,
    h_m: f32,
    s2_m2: f32,
    process_noise_var_m2: f32,
    band_sigmas: f32,
) -> Elevation {
    match (rule, prior) {
        (
            ElevationFusion::HighestSurface {
                mahalanobis_threshold,
                lower_threshold,
                multi_height_noise_m2,
            },
            Some(e),
        ) => {
            let grown = Elevation {
                var_m2: e.var_m2 + process_noise_var_m2,
                ..e
            };
            let lower = lower_threshold.unwrap_or(mahalanobis_threshold);
            if surface_level(grown, h_m, s2_m2, mahalanobis_threshold) == Level::Above {
                Elevation {
                    mean_m: h_m,
                    var_m2: s2_m2,
                }
            } else if surface_level(grown, h_m, s2_m2, lower) == Level::Below {
                Elevation {
                    mean_m: e.mean_m,
                    var_m2: e.var_m2 + multi_height_noise_m2,
                }
            } else {
                kalman_fuse(prior, h_m, s2_m2, process_noise_var_m2)
            }
        }
        (ElevationFusion::Disagreement, prior) => {
            fuse_with_disagreement(prior, h_m, s2_m2, process_noise_var_m2)
        }
        (ElevationFusion::TopSurface, prior) => {
            fuse_top_surface(prior, h_m, s2_m2, process_noise_var_m2, band_sigmas)
        }
        _ => kalman_fuse(prior, h_m, s2_m2, process_noise_var_m2),
    }
}

impl ScanHitElevation {
    /// Adds the hit `(z_m, var_m2)` to the scan's measurement `(z, var)` of a cell (`z = -inf`,
    /// `var = +inf` before the first hit).
    #[inline(always)]
    pub fn combine(self, (z, var): (f32, f32), z_m: f32, var_m2: f32) -> (f32, f32) {
        match self {
            Self::Highest => {
                if z_m > z {
                    (z_m, var_m2)
                } else {
                    (z, var)
                }
            }
            Self::WeightedMean | Self::MeanWithSpread | Self::HighestLevel => {
                if z == f32::NEG_INFINITY {
                    (z_m, var_m2)
                } else {
                    // One Kalman step with gain var / (var + var_m2).
                    let k = var / (var + var_m2);
                    (z + k * (z_m - z), var * var_m2 / (var + var_m2))
                }
            }
        }
    }
}

/// Whether a free sample passing at `beam_top_m` (its highest point in the cell) may update a cell whose
/// elevation estimate is `prior` under `rule`. (Samples deeper than `free_space_max_depth_m` below the
/// estimate were dropped before this: see [`ModelOptions::free_space_max_depth_m`](crate::ModelOptions::free_space_max_depth_m).)
pub fn free_sample_informs(rule: FreeSpaceOccupancy, prior: Option<Elevation>, beam_top_m: f32) -> bool {
    match (rule, prior) {
        (FreeSpaceOccupancy::Always, _) | (FreeSpaceOccupancy::BelowElevation, None) => true,
        (FreeSpaceOccupancy::BelowElevation, Some(e)) => beam_top_m <= e.mean_m,
        // Decided beam by beam while gathering (`band_contradicts`): only contradicting samples get here.
        (FreeSpaceOccupancy::SurfaceBand, _) => true,
    }
}

/// Where a measurement `h_m` (variance `s2_m2`) lies against a surface estimate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    /// More than the band above the surface: a higher surface.
    Above,
    /// Within the band: the same surface.
    Same,
    /// More than the band below the surface: a lower level (the ground under a table or a board).
    Below,
}

/// Whether `h_m` (variance `s2_m2`) lies above, within or below the band of `surface`: `band_sigmas` standard
/// deviations of the difference, `sqrt(sigma^2 + s^2)`. The one test behind [`ScanHitElevation::HighestLevel`]
/// (within a scan), [`ElevationFusion::TopSurface`] (across scans) and, with its own threshold above and
/// below, [`ElevationFusion::HighestSurface`].
pub fn surface_level(surface: Elevation, h_m: f32, s2_m2: f32, band_sigmas: f32) -> Level {
    let half = band_sigmas * (surface.var_m2 + s2_m2).sqrt();
    if h_m - surface.mean_m > half {
        Level::Above
    } else if surface.mean_m - h_m > half {
        Level::Below
    } else {
        Level::Same
    }
}

/// The upper tail of the standard normal distribution, `P(Z > z)`: `erfc(z / sqrt 2) / 2` by the Chebyshev
/// fit of Numerical Recipes' `erfcc` (fractional error below 1.2e-7 everywhere).
pub fn normal_tail(z: f64) -> f64 {
    let x = z / std::f64::consts::SQRT_2;
    let a = x.abs();
    let t = 1.0 / (1.0 + 0.5 * a);
    let poly = -a * a - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let erfc = t * poly.exp();
    0.5 * if x >= 0.0 { erfc } else { 2.0 - erfc }
}

/// [`crate::OverheadHits::Ceiling`]: whether a scan's hits above a cell's surface band are a structure over it
/// and not the tail of the surface's own noise. `score` is the largest of them in standard deviations of the
/// difference from the surface, among `n` hits of the scan in the cell. One hit beyond `band_sigmas` is a
/// false alarm with the tail probability `Q(band_sigmas)` (0.13 % at 3); the most extreme of `n` is one with
/// `n` times that, so a camera that puts a hundred pixels in a cell each frame would raise a structure out
/// of flat ground every few frames. The test keeps the scan's false-alarm rate at that of one hit
/// (Bonferroni): `n Q(score) <= Q(band_sigmas)`. One hit is judged by the band alone; among 100 the largest
/// must lie 4.2 sigma out, among 1,000 4.6.
pub fn overhead_significant(score: f32, n: f32, band_sigmas: f32) -> bool {
    f64::from(n.max(1.0)) * normal_tail(f64::from(score)) <= normal_tail(f64::from(band_sigmas))
}

/// [`ElevationFusion::TopSurface`]: a measurement within the band of `prior` is fused by eq. 8-9 (it is the same
/// surface, and its disagreement is noise); one above it pulls the estimate up by [`fuse_with_disagreement`], the
/// disagreement kept as variance (a higher surface, or a spurious return that the next measurements outvote);
/// one below it is a lower level and leaves `prior` unchanged. The band is `band_sigmas` standard deviations of
/// the difference, the prior's variance grown by the process noise.
pub fn fuse_top_surface(
    prior: Option<Elevation>,
    h_m: f32,
    s2_m2: f32,
    process_noise_var_m2: f32,
    band_sigmas: f32,
) -> Elevation {
    let Some(e) = prior else {
        return fuse_with_disagreement(None, h_m, s2_m2, process_noise_var_m2);
    };
    let grown = Elevation {
        var_m2: e.var_m2 + process_noise_var_m2,
        ..e
    };
    match surface_level(grown, h_m, s2_m2, band_sigmas) {
        Level::Above => fuse_with_disagreement(prior, h_m, s2_m2, process_noise_var_m2),
        Level::Same => kalman_fuse(prior, h_m, s2_m2, process_noise_var_m2),
        Level::Below => e,
    }
}

/// [`ElevationFusion::Disagreement`]: eq. 8's mean and eq. 9's variance, plus the part of the measurement's
/// disagreement with the prior that their variances do not explain: `w (1 - w) max(0, d^2 - (sigma^2 + s^2))`
/// with `d = h - mu` and `w = sigma^2 / (sigma^2 + s^2)` (the measurement's weight in eq. 8). `w (1 - w) d^2`
/// is the spread term of the variance of the two-component mixture weighted as eq. 8 weights them; the
/// expected innovation `sigma^2 + s^2` is taken off so that measurements that agree within their noise shrink
/// the variance exactly as eq. 9, while a surface that moved, a spurious return or an edge leaves the
/// estimate as uncertain as the disagreement says.
pub fn fuse_with_disagreement(
    prior: Option<Elevation>,
    h_m: f32,
    s2_m2: f32,
    process_noise_var_m2: f32,
) -> Elevation {
    let fused = kalman_fuse(prior, h_m, s2_m2, process_noise_var_m2);
    let Some(e) = prior else { return fused };
    let var = e.var_m2 + process_noise_var_m2;
    let sum = var + s2_m2;
    if sum <= 0.0 {
        return fused;
    }
    let w = var / sum;
    let d = h_m - e.mean_m;
    Elevation {
        mean_m: fused.mean_m,
        var_m2: fused.var_m2 + w * (1.0 - w) * (d * d - sum).max(0.0),
    }
}

/// [`FreeSpaceOccupancy::SurfaceBand`]: whether a beam whose path through a cell spans the heights
/// `[z_lo_m, z_hi_m]` passes through the band where the cell's surface is believed to be, and so contradicts
/// it. A cell's surface is the top of what fills its column, so the band is its lower half, `[mu - k sigma,
/// mu]` with `k = band_sigmas`: a beam there went through where the top is believed to be. A beam below the
/// band passed under the surface (a board, a table, a branch); one above `mu` passed over it (a curb, a low
/// wall), where the surface leaves room. Neither says anything about it.
///
/// The upper half is left out for the same reason as a top's in [`ceiling_contradicts`]: a beam that lands on
/// the ground or on a curb's top a little further on skims the cells before it within millimetres of their
/// surface. With the whole band, every such beam contradicted a surface it agrees with: the cells just short
/// of each lidar ring lost their ground, and a low wall's or a curb's top lost the cells over which the beams
/// that land on its far part pass.
///
/// The anchors' visibility clean-up (elevation_mapping, elevation_mapping_cupy) removes a cell whenever a
/// ray passes below its height, which also removes every overhang a ray passes under; the band keeps them.
pub fn band_contradicts(prior: Elevation, z_lo_m: f32, z_hi_m: f32, band_sigmas: f32) -> bool {
    // The square root only for a beam that reaches down to the mean: most pass over the surface.
    z_lo_m <= prior.mean_m && z_hi_m >= prior.mean_m - band_sigmas * prior.var_m2.sqrt()
}

/// One scan's measurement of the structure over a cell ([`crate::OverheadHits::Ceiling`]): the lowest level of
/// its hits above the cell's surface band.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CeilingHit {
    /// Height, world z, metres.
    pub z_m: f32,
    /// Variance, m^2.
    pub var_m2: f32,
    /// The largest inverse-sensor-model probability among the hits (eq. 10).
    pub p: f32,
    /// From which side the beams came.
    pub seen_from: SeenFrom,
}

/// [`crate::OverheadHits::Ceiling`]: a cell's ceiling after one scan, from the scan's `hit` (if any) and
/// whether a beam passed through the structure's side of its band (`contradicted`, [`ceiling_contradicts`]).
///
/// * A hit within the band of the ceiling is the same structure: its height is fused by eq. 8-9 (with
///   [`correlated_variance`] for the scan's `correlation` with the estimate) and its evidence raised by the
///   hit's log-odds (eq. 5-7).
/// * A hit below the band is a lower structure, and the robot's clearance is set by the lowest: it replaces the
///   ceiling. So does a hit above the band in a scan whose beams contradicted the ceiling (the structure's lower
///   part has gone).
/// * A hit above the band alone is a higher part of the structure and leaves the ceiling as it is.
/// * A scan that only contradicts it lowers its evidence by as much as the surest hit raises it, eq. 6 of
///   `1 - p_max`: the band is the thin slab where the structure was measured, and a beam through it says
///   there is nothing there as surely as a beam ending in it says there is (the symmetric inverse sensor
///   model of a voxel, Thrun et al.'s `l_occ = -l_free`). A 2.5D cell's `p_min` is weak because a beam
///   passing a cell's column says little of its surface; a beam through this slab says all. A ceiling whose
///   evidence falls to `occupied_log_odds` is gone: at the defaults (`p_max` 0.9, clamp 3.5) after 2 such scans,
///   after 1 when a single hit made it.
///
/// Hits win over contradictions in the same scan, as occupied samples win over free ones in a cell (OctoMap).
///
/// `clear_m` is the highest point at which one of the scan's beams passed freely under the prior ceiling's band
/// ([`ceiling_passed_under`]; `-inf`: none). The ceiling keeps the highest such point over the scans
/// (`Ceiling::clear_m`); a structure seen afresh starts with none.
pub fn update_ceiling(
    prior: Ceiling,
    hit: Option<CeilingHit>,
    contradicted: bool,
    clear_m: f32,
    opts: &ModelOptions,
    correlation: f32,
    occupied_log_odds: f32,
) -> Ceiling {
    let evidence = |l: f32, p: f32| update_log_odds(l, log_odds(p), opts.log_odds_min, opts.log_odds_max);
    let fresh = |h: CeilingHit| Ceiling {
        z_m: h.z_m,
        var_m2: h.var_m2,
        log_odds: evidence(0.0, h.p),
        seen_from: h.seen_from,
        clear_m: f32::NEG_INFINITY,
    };
    let clear_m = prior.clear_m.max(clear_m);
    match (prior.height(), hit) {
        (None, Some(h)) => fresh(h),
        (Some(c), Some(h)) => match surface_level(c, h.z_m, h.var_m2, opts.surface_band_sigmas) {
            Level::Same => {
                let q = opts.process_noise_var_m2;
                let fused = kalman_fuse(Some(c), h.z_m, h.var_m2, q);
                Ceiling {
                    z_m: fused.mean_m,
                    var_m2: correlated_variance(fused.var_m2, c.var_m2 + q, h.var_m2, correlation),
                    log_odds: evidence(prior.log_odds, h.p),
                    seen_from: prior.seen_from.and(h.seen_from),
                    clear_m,
                }
            }
            Level::Below => fresh(h),
            Level::Above if contradicted => fresh(h),
            Level::Above => Ceiling { clear_m, ..prior },
        },
        (Some(_), None) if contradicted => {
            let l = evidence(prior.log_odds, 1.0 - opts.p_max);
            if l <= occupied_log_odds {
                Ceiling::NONE
            } else {
                Ceiling {
                    log_odds: l,
                    clear_m,
                    ..prior
                }
            }
        }
        (Some(_), None) => Ceiling { clear_m, ..prior },
        (None, None) => prior,
    }
}

/// [`crate::OverheadHits::Ceiling`]: whether a ceiling's evidence `log_odds_value` makes it sure enough to block
/// the robot: at least what the surest single hit gives, `logit(p_max)`. One hit of a precise sensor confirms
/// a structure; a noisy sensor's (eq. 10 gives a far stereo pixel about 0.55) needs several at that height.
/// A single weak hit above the surface band may be noise's tail (among the hundred pixels a camera puts in a
/// cell each frame, one lies beyond 3 sigma every few frames): the cell is then uncertain, not blocked
/// ([`crate::traversability::ceiling_decision`]).
pub fn ceiling_confirmed(log_odds_value: f32, p_max: f32) -> bool {
    // Less a float's rounding: one sure hit confirms.
    log_odds_value >= log_odds(p_max) - 1e-5
}

/// [`crate::OverheadHits::Ceiling`]: whether a beam whose path through a cell spans the heights `[z_lo_m, z_hi_m]`
/// contradicts the structure over it: it passes through the structure's side of its band, `[z - k sigma, z]`
/// for a top seen from above, `[z, z + k sigma]` for an underside seen from below, the whole band for one seen
/// from both sides. A beam skimming just over a top (one that lands on it a little further on, or on the
/// ground behind) or just under an underside passes where the structure leaves room: a symmetric band would
/// have such grazing beams clear the structures they keep measuring. The band is
/// as wide as the structure's hits spread ([`spread_variance`]): a person's front, hit from the ankles up,
/// is contradicted by any beam through where they stood.
///
/// Where the beam passed is known to its footprint, `footprint_m` (one standard deviation across its direction,
/// on the vertical: [`beam_footprint_m`]). The band is narrowed by it on the side away from the measured
/// height, never past that height: a beam through the height where the structure was hit contradicts it
/// (a person's front, hit at one height, is cleared by the beam that passes where they stood), but one within
/// its footprint of the band's far edge may have passed beside the structure, not through it. Hits on a board's
/// face from a descending ring read as a top, fused into a band a few millimetres deep, and the beams grazing
/// under the board within their footprint of it cleared the board from the cells of its edge, where a real
/// beam's footprint would have met it.
pub fn ceiling_contradicts(
    ceiling: &Ceiling,
    z_lo_m: f32,
    z_hi_m: f32,
    band_sigmas: f32,
    footprint_m: f32,
) -> bool {
    let (lo, hi) = ceiling_band(ceiling, band_sigmas);
    let (lo, hi) = (
        (lo + footprint_m).min(ceiling.z_m),
        (hi - footprint_m).max(ceiling.z_m),
    );
    z_lo_m <= hi && z_hi_m >= lo
}

/// [`crate::OverheadHits::Ceiling`]: whether a beam whose highest point in a cell is `z_top_m` passed wholly under
/// the structure's side of its band ([`ceiling_contradicts`]): the space it crossed, up to `z_top_m`, is clear
/// under the structure (`Ceiling::clear_m`).
pub fn ceiling_passed_under(ceiling: &Ceiling, z_top_m: f32, band_sigmas: f32) -> bool {
    z_top_m < ceiling_band(ceiling, band_sigmas).0
}

/// The structure's side of a ceiling's band, `(lo, hi)`: `[z - k sigma, z]` for a top seen from above,
/// `[z, z + k sigma]` for an underside seen from below, the whole band for one seen from both sides.
fn ceiling_band(ceiling: &Ceiling, band_sigmas: f32) -> (f32, f32) {
    let half = band_sigmas * ceiling.var_m2.sqrt();
    match ceiling.seen_from {
        SeenFrom::Above => (ceiling.z_m - half, ceiling.z_m),
        SeenFrom::Below => (ceiling.z_m, ceiling.z_m + half),
        SeenFrom::Both => (ceiling.z_m - half, ceiling.z_m + half),
    }
}

/// [`ScanHitElevation::MeanWithSpread`]: the variance of a scan's measurement of a cell, the inverse-variance
/// weighted mean of its hits (variance `mean_var_m2`), when the hits' heights have sample variance
/// `sample_var_m2` while their own noise has mean variance `noise_var_m2`: the excess of the sample variance over
/// the noise is the spread of the surface itself within the cell (an edge, a slope, a person's front), and
/// it is added, `mean_var + max(0, sample_var - noise_var)`. Noise alone adds nothing: a cell seen by many
/// noisy pixels is not taken for a rough one.
pub fn spread_variance(mean_var_m2: f32, sample_var_m2: f32, noise_var_m2: f32) -> f32 {
    mean_var_m2 + (sample_var_m2 - noise_var_m2).max(0.0)
}

/// [`crate::ModelOptions::measurement_correlation`]: the variance of a fused estimate when a measurement of
/// variance `s^2` shares its errors with the estimate before it (variance `prior_var_m2`) with correlation
/// `rho`. A series of measurements each correlated `rho` with the one before (a first-order autoregression)
/// carries the information of `(1 - rho) / (1 + rho)` independent ones each: eq. 9 with the measurement's
/// information scaled so. At `rho = 1` a measurement adds nothing, and the estimate is as certain as its best
/// measurement; at 0 this is eq. 9's `fused_var_m2` itself. Never above the prior's variance (a worse
/// measurement does not spoil a good estimate), nor above the measurement's (a better one improves it).
pub fn correlated_variance(fused_var_m2: f32, prior_var_m2: f32, measurement_var_m2: f32, rho: f32) -> f32 {
    if rho <= 0.0 {
        return fused_var_m2;
    }
    let information = (1.0 - rho) / (1.0 + rho);
    let scaled = if information > 0.0 {
        prior_var_m2 * measurement_var_m2 / (measurement_var_m2 + information * prior_var_m2)
    } else {
        prior_var_m2
    };
    fused_var_m2.max(prior_var_m2.min(measurement_var_m2).min(scaled))
}

/// [`crate::ModelOptions::vertical_variance`]: the variance of a hit's height when its range has standard
/// deviation `range_sigma_m` along a beam of unit direction with vertical component `dir_z`, `range_m` from
/// the sensor. Two errors add up: the range error projected onto z, `(sigma_r dir_z)^2`, and the beam's
/// footprint across its direction, `range * BEAM_SIGMA_RAD`, projected onto z (`1 - dir_z^2` of its
/// variance). A floor of 1 mm remains. The paper uses the range variance itself, which overstates the height
/// error of a beam that looks down at the ground 10 times at 18 degrees below the horizon, and understates it
/// for a far, level beam.
pub fn vertical_variance(range_sigma_m: f64, dir_z: f64, range_m: f64) -> f32 {
    let along = range_sigma_m * dir_z;
    let across = range_m * BEAM_SIGMA_RAD;
    let var = along * along + across * across * (1.0 - dir_z * dir_z).max(0.0);
    var.max(VERTICAL_SIGMA_FLOOR_M * VERTICAL_SIGMA_FLOOR_M) as f32
}

/// The standard deviation of where a beam passes on the vertical, `horizontal_m` from the sensor across the
/// ground: its footprint across its direction, `range * BEAM_SIGMA_RAD`, projected onto z, the term
/// [`vertical_variance`] adds to a hit's. The range times `sqrt(1 - dir_z^2)` is the horizontal distance,
/// whatever the beam's elevation.
pub fn beam_footprint_m(horizontal_m: f64) -> f64 {
    horizontal_m * BEAM_SIGMA_RAD
}

/// The standard deviation of where a beam hits across its direction, radians: half the 0.25 degree beam
/// divergence of the SICK LMS 291 class of scanner the paper used (4.4 mrad full angle).
pub const BEAM_SIGMA_RAD: f64 = 0.0022;

/// The floor of [`vertical_variance`]'s standard deviation, metres.
pub const VERTICAL_SIGMA_FLOOR_M: f64 = 0.001;

#[cfg(test)]
mod tests;
