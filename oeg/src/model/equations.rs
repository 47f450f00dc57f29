//! The paper's equations (sections 3 and 4) as small pure functions: occupancy in log-odds (eq. 3-7), the
//! Gaussian inverse sensor model (eq. 10-11), the elevation measurement (eq. 12) and its Kalman fusion
//! (eq. 8-9). Each function names the equation it implements.

/// Eq. 3: the occupancy probability of log-odds `l`, `1 - 1 / (1 + e^l)`.
pub fn probability_from_log_odds(l: f32) -> f32 {
    1.0 - 1.0 / (1.0 + l.exp())
}

/// Eq. 6: the log-odds `log(p / (1 - p))` of one measurement's probability `p` (prior 0.5, so eq. 4's prior
/// term vanishes).
pub fn log_odds(p: f32) -> f32 {
    (p / (1.0 - p)).ln()
}

/// Eq. 5 with Yguel's clamping, eq. 7: `max(min(l + delta, l_max), l_min)`.
pub fn update_log_odds(l: f32, delta: f32, l_min: f32, l_max: f32) -> f32 {
    (l + delta).clamp(l_min, l_max)
}

/// Eq. 11: the occupancy probability of a sample at range `l` without the Gaussian bump: `p_min` up to the
/// measured range `l_p`, 0.5 (unknown) behind it.
pub fn p_occ(l: f32, l_p: f32, p_min: f32) -> f32 {
    if l <= l_p { p_min } else { 0.5 }
}

/// Eq. 10: the Gaussian inverse sensor model, the occupancy probability of a sample at range `l` on a beam that
/// measured `l_p` with range error `dl`:
/// `p_occ(l) + (k / (dl sqrt(2 pi)) + 0.5 - p_occ(l)) exp(-((l - l_p) / dl)^2 / 2)`.
///
/// The result can exceed 1 for small `dl`; [`clamp_probability`] bounds it before it becomes log-odds.
pub fn inverse_sensor_model(l: f32, l_p: f32, dl: f32, k: f32, p_min: f32) -> f32 {
    let base = p_occ(l, l_p, p_min);
    let z = (l - l_p) / dl;
    let peak = k / (dl * (2.0 * std::f32::consts::PI).sqrt());
    base + (peak + 0.5 - base) * (-0.5 * z * z).exp()
}

/// Bounds an inverse-sensor-model probability into `[p_min, p_max]`, inside the open interval (0, 1), so its
/// log-odds is finite.
pub fn clamp_probability(p: f32, p_min: f32, p_max: f32) -> f32 {
    p.clamp(p_min, p_max)
}

/// Eq. 12: the elevation measurement of a sample at height `z_m` with occupancy probability `p`: `z` when
/// `p > l_occ`, otherwise the paper's `0` (returned as `None` here; what a free sample does is
/// [`FreeSpaceElevation`](crate::FreeSpaceElevation)'s choice).
pub fn elevation_observation(p: f32, z_m: f32, l_occ: f32) -> Option<f32> {
    (p > l_occ).then_some(z_m)
}

/// An elevation estimate: the Gaussian `N(mean_m, var_m2)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Elevation {
    /// Mean `mu`, metres (world z).
    pub mean_m: f32,
    /// Variance `sigma^2`, m^2.
    pub var_m2: f32,
}

/// Eq. 8 and 9, the one-dimensional Kalman update of Pfaff et al.: fuses the measurement `h` with variance
/// `s2` into the prior `(mu, sigma^2)`:
/// `mu' = (s2 mu + sigma^2 h) / (sigma^2 + s2)`, `sigma'^2 = sigma^2 s2 / (sigma^2 + s2)`.
///
/// `process_noise_var_m2` is added to the prior variance first (0 in the paper). With no prior (`None`) the
/// measurement becomes the estimate.
pub fn kalman_fuse(prior: Option<Elevation>, h_m: f32, s2_m2: f32, process_noise_var_m2: f32) -> Elevation {
    match prior {
        None => Elevation {
            mean_m: h_m,
            var_m2: s2_m2,
        },
        Some(Elevation {
            mean_m: mu,
            var_m2: var,
        }) => {
            let var = var + process_noise_var_m2;
            let sum = var + s2_m2;
            if sum <= 0.0 {
                // Two exact estimates: keep the prior rather than divide by zero.
                return Elevation {
                    mean_m: mu,
                    var_m2: var,
                };
            }
            Elevation {
                mean_m: (s2_m2 * mu + var * h_m) / sum,
                var_m2: var * s2_m2 / sum,
            }
        }
    }
}

/// The ray-bound rule of [`FreeSpaceElevation::RayBound`](crate::FreeSpaceElevation::RayBound): a beam that passed through the cell at height
/// `beam_z_m` caps the elevation mean there.
pub fn ray_bound(prior: Elevation, beam_z_m: f32) -> Elevation {
    Elevation {
        mean_m: prior.mean_m.min(beam_z_m),
        var_m2: prior.var_m2,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f32, b: f32, tol: f32) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn eq3_and_eq6_are_inverse() {
        assert!(close(probability_from_log_odds(0.0), 0.5, 1e-7));
        // OctoMap's clamping bounds: -2 -> 0.1192, 3.5 -> 0.9707.
        assert!(close(probability_from_log_odds(-2.0), 0.119_203, 1e-5));
        assert!(close(probability_from_log_odds(3.5), 0.970_688, 1e-5));
        assert!(close(log_odds(0.7), 0.847_298, 1e-5));
        assert!(close(log_odds(0.4), -0.405_465, 1e-5));
        for p in [0.1_f32, 0.3, 0.5, 0.8, 0.95] {
            assert!(close(probability_from_log_odds(log_odds(p)), p, 1e-5));
        }
    }

    #[test]
    fn eq7_clamps_to_the_bounds() {
        assert_eq!(update_log_odds(3.0, 0.847, -2.0, 3.5), 3.5);
        assert_eq!(update_log_odds(-1.8, -0.405, -2.0, 3.5), -2.0);
        assert!(close(update_log_odds(0.0, 0.847, -2.0, 3.5), 0.847, 1e-6));
    }

    #[test]
    fn eq10_matches_hand_computed_values() {
        // At the hit: p_occ = p_min = 0.4, bump = k / (dl sqrt(2 pi)) = 0.03 / (0.03 * 2.506628) = 0.398942.
        let p = inverse_sensor_model(5.0, 5.0, 0.03, 0.03, 0.4);
        assert!(close(p, 0.4 + (0.398_942 + 0.5 - 0.4), 1e-5), "{p}");
        // One dl before the hit: 0.4 + 0.498942 * exp(-0.5) = 0.702627.
        let p = inverse_sensor_model(4.97, 5.0, 0.03, 0.03, 0.4);
        assert!(close(p, 0.702_627, 1e-4), "{p}");
        // One dl behind the hit, p_occ is 0.5: 0.5 + 0.398942 * exp(-0.5) = 0.741971.
        let p = inverse_sensor_model(5.03, 5.0, 0.03, 0.03, 0.4);
        assert!(close(p, 0.741_971, 1e-4), "{p}");
        // Far before the hit the Gaussian vanishes and p = p_min.
        assert!(close(inverse_sensor_model(1.0, 5.0, 0.03, 0.03, 0.4), 0.4, 1e-6));
        // The paper's Fig. 3: a larger range error lowers the peak.
        assert!(
            inverse_sensor_model(15.0, 15.0, 0.3, 0.03, 0.4)
                < inverse_sensor_model(10.0, 10.0, 0.2, 0.03, 0.4)
        );
    }

    #[test]
    fn eq11_switches_at_the_measured_range() {
        assert_eq!(p_occ(2.0, 2.0, 0.4), 0.4);
        assert_eq!(p_occ(2.01, 2.0, 0.4), 0.5);
    }

    #[test]
    fn eq12_gives_the_height_only_near_the_hit() {
        assert_eq!(elevation_observation(0.8, 0.31, 0.5), Some(0.31));
        assert_eq!(elevation_observation(0.4, 0.31, 0.5), None);
    }

    #[test]
    fn eq8_eq9_match_hand_computed_values() {
        // Prior N(1, 0.04), measurement 2 with 0.01: mu = (0.01 * 1 + 0.04 * 2) / 0.05 = 1.8, var = 0.008.
        let e = kalman_fuse(
            Some(Elevation {
                mean_m: 1.0,
                var_m2: 0.04,
            }),
            2.0,
            0.01,
            0.0,
        );
        assert!(
            close(e.mean_m, 1.8, 1e-6) && close(e.var_m2, 0.008, 1e-7),
            "{e:?}"
        );
        // Process noise inflates the prior first: var 0.03 + 0.01 = 0.04 -> same result.
        let e2 = kalman_fuse(
            Some(Elevation {
                mean_m: 1.0,
                var_m2: 0.03,
            }),
            2.0,
            0.01,
            0.01,
        );
        assert!(
            close(e2.mean_m, 1.8, 1e-6) && close(e2.var_m2, 0.008, 1e-7),
            "{e2:?}"
        );
        // No prior: the measurement is the estimate.
        let e3 = kalman_fuse(None, 0.2, 0.5, 0.0);
        assert_eq!(
            e3,
            Elevation {
                mean_m: 0.2,
                var_m2: 0.5
            }
        );
    }

    #[test]
    fn ray_bound_only_lowers() {
        let e = Elevation {
            mean_m: 1.2,
            var_m2: 0.01,
        };
        assert_eq!(ray_bound(e, 0.3).mean_m, 0.3);
        assert_eq!(ray_bound(e, 2.0).mean_m, 1.2);
        assert_eq!(ray_bound(e, 0.3).var_m2, 0.01);
    }
}
