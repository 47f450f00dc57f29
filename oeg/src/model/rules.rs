//! The rules beyond the paper's equations, one pure function each: how a scan's hits in a cell combine, how a
//! hit is fused with a cell's estimate, and whether a free sample says anything about a cell. The options
//! that select them are in [`super::options`]; `oeg/README.md` gives each rule's source.

use super::equations::{Elevation, kalman_fuse};
use super::options::{ElevationFusion, FreeSpaceOccupancy, ScanHitElevation};

/// Fuses the elevation measurement `h` (variance `s2`) into `prior` under `rule` (see [`ElevationFusion`]).
pub fn fuse_elevation(
    rule: ElevationFusion,
    prior: Option<Elevation>,
    h_m: f32,
    s2_m2: f32,
    process_noise_var_m2: f32,
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
            let spread = (e.var_m2 + process_noise_var_m2 + s2_m2).sqrt();
            if h_m - e.mean_m > mahalanobis_threshold * spread {
                Elevation {
                    mean_m: h_m,
                    var_m2: s2_m2,
                }
            } else if e.mean_m - h_m > lower_threshold.unwrap_or(mahalanobis_threshold) * spread {
                Elevation {
                    mean_m: e.mean_m,
                    var_m2: e.var_m2 + multi_height_noise_m2,
                }
            } else {
                kalman_fuse(prior, h_m, s2_m2, process_noise_var_m2)
            }
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
            Self::WeightedMean => {
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
/// estimate were dropped before this: see [`ModelOptions::free_space_max_depth_m`].)
pub fn free_sample_informs(rule: FreeSpaceOccupancy, prior: Option<Elevation>, beam_top_m: f32) -> bool {
    match (rule, prior) {
        (FreeSpaceOccupancy::Always, _) | (FreeSpaceOccupancy::BelowElevation, None) => true,
        (FreeSpaceOccupancy::BelowElevation, Some(e)) => beam_top_m <= e.mean_m,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f32, b: f32, tol: f32) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn a_scans_hits_combine_as_the_highest_or_the_weighted_mean() {
        let none = (f32::NEG_INFINITY, f32::INFINITY);
        let highest = ScanHitElevation::Highest;
        let first = highest.combine(none, 0.1, 0.01);
        assert_eq!(first, (0.1, 0.01));
        assert_eq!(highest.combine(first, 0.3, 0.04), (0.3, 0.04));
        assert_eq!(highest.combine((0.3, 0.04), 0.1, 0.01), (0.3, 0.04));
        // Weighted mean: weights 1 / 0.01 and 1 / 0.03 -> (0.1 * 100 + 0.3 * 33.3) / 133.3 = 0.15, variance
        // 1 / 133.3 = 0.0075.
        let mean = ScanHitElevation::WeightedMean;
        let first = mean.combine(none, 0.1, 0.01);
        assert_eq!(first, (0.1, 0.01));
        let (z, var) = mean.combine(first, 0.3, 0.03);
        assert!(close(z, 0.15, 1e-6) && close(var, 0.0075, 1e-7), "{z} {var}");
    }

    #[test]
    fn the_highest_surface_wins_across_scans() {
        let rule = ElevationFusion::HighestSurface {
            mahalanobis_threshold: 3.0,
            lower_threshold: None,
            multi_height_noise_m2: 1e-4,
        };
        let curb = Some(Elevation {
            mean_m: 0.03,
            var_m2: 1e-6,
        });
        // Much higher: replaces.
        let higher = fuse_elevation(rule, curb, 0.05, 1e-6, 0.0);
        assert_eq!((higher.mean_m, higher.var_m2), (0.05, 1e-6));
        // Much lower: ignored, but the variance grows (multi-height noise).
        let prior = Some(Elevation {
            mean_m: 0.05,
            var_m2: 1e-6,
        });
        let kept = fuse_elevation(rule, prior, 0.0, 1e-4, 0.0);
        assert_eq!(kept.mean_m, 0.05);
        assert!((kept.var_m2 - (1e-6 + 1e-4)).abs() < 1e-9, "{kept:?}");
        // Close: fused as eq. 8-9.
        let near = fuse_elevation(rule, curb, 0.031, 1e-4, 0.0);
        assert_eq!(near, kalman_fuse(curb, 0.031, 1e-4, 0.0));
        // A lower threshold of 1 sigma: a face hit 2 sigma under a curb's top no longer pulls it down.
        let strict = ElevationFusion::HighestSurface {
            mahalanobis_threshold: 3.0,
            lower_threshold: Some(1.0),
            multi_height_noise_m2: 1e-4,
        };
        let top = Some(Elevation {
            mean_m: 0.05,
            var_m2: 0.0,
        });
        assert_eq!(
            fuse_elevation(rule, top, 0.03, 1e-4, 0.0).mean_m,
            kalman_fuse(top, 0.03, 1e-4, 0.0).mean_m
        );
        assert_eq!(fuse_elevation(strict, top, 0.03, 1e-4, 0.0).mean_m, 0.05);
        assert_eq!(
            fuse_elevation(strict, top, 0.045, 1e-4, 0.0),
            kalman_fuse(top, 0.045, 1e-4, 0.0)
        );
        // The paper's rule always fuses.
        assert_eq!(
            fuse_elevation(ElevationFusion::Kalman, curb, 0.05, 1e-4, 0.0),
            kalman_fuse(curb, 0.05, 1e-4, 0.0)
        );
    }

    #[test]
    fn free_samples_above_an_obstacle_say_nothing_about_it() {
        let curb = Some(Elevation {
            mean_m: 0.05,
            var_m2: 1e-4,
        });
        assert!(free_sample_informs(FreeSpaceOccupancy::Always, curb, 0.4));
        assert!(!free_sample_informs(
            FreeSpaceOccupancy::BelowElevation,
            curb,
            0.4
        ));
        assert!(free_sample_informs(
            FreeSpaceOccupancy::BelowElevation,
            curb,
            0.03
        ));
        assert!(free_sample_informs(FreeSpaceOccupancy::BelowElevation, None, 0.4));
    }
}
