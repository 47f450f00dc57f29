//! The update rules, one behaviour a test.

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
    let higher = fuse_elevation(rule, curb, 0.05, 1e-6, 0.0, 3.0);
    assert_eq!((higher.mean_m, higher.var_m2), (0.05, 1e-6));
    // Much lower: ignored, but the variance grows (multi-height noise).
    let prior = Some(Elevation {
        mean_m: 0.05,
        var_m2: 1e-6,
    });
    let kept = fuse_elevation(rule, prior, 0.0, 1e-4, 0.0, 3.0);
    assert_eq!(kept.mean_m, 0.05);
    assert!((kept.var_m2 - (1e-6 + 1e-4)).abs() < 1e-9, "{kept:?}");
    // Close: fused as eq. 8-9.
    let near = fuse_elevation(rule, curb, 0.031, 1e-4, 0.0, 3.0);
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
        fuse_elevation(rule, top, 0.03, 1e-4, 0.0, 3.0).mean_m,
        kalman_fuse(top, 0.03, 1e-4, 0.0).mean_m
    );
    assert_eq!(fuse_elevation(strict, top, 0.03, 1e-4, 0.0, 3.0).mean_m, 0.05);
    assert_eq!(
        fuse_elevation(strict, top, 0.045, 1e-4, 0.0, 3.0),
        kalman_fuse(top, 0.045, 1e-4, 0.0)
    );
    // The paper's rule always fuses.
    assert_eq!(
        fuse_elevation(ElevationFusion::Kalman, curb, 0.05, 1e-4, 0.0, 3.0),
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

#[test]
fn a_beam_through_the_surface_band_contradicts_it_and_one_under_or_over_does_not() {
    // A board whose top is at 0.46 m, known to 1 cm: its band is [0.43, 0.46].
    let board = Elevation {
        mean_m: 0.46,
        var_m2: 1e-4,
    };
    assert!(band_contradicts(board, 0.44, 0.445, 3.0), "through the board");
    assert!(
        band_contradicts(board, 0.455, 0.465, 3.0),
        "where its top is believed to be"
    );
    assert!(
        !band_contradicts(board, 0.465, 0.48, 3.0),
        "skimming over its top, within the band's upper half"
    );
    assert!(!band_contradicts(board, 0.30, 0.42, 3.0), "under the board");
    assert!(!band_contradicts(board, 0.50, 0.60, 3.0), "over it");
    assert!(
        band_contradicts(board, 0.10, 0.70, 3.0),
        "a steep beam crossing the band"
    );
    // A person's front hit from 0.05 to 0.5 m: the spread makes the band deep, so the beams that hit the
    // body at mid height contradict it once the person has gone.
    // Hits spread evenly from 0.05 to 0.5 m: a sample variance of 0.45^2 / 12.
    let person = Elevation {
        mean_m: 0.3,
        var_m2: spread_variance(1e-5, 0.45 * 0.45 / 12.0, 1e-4),
    };
    assert!(band_contradicts(person, 0.20, 0.21, 3.0));
    // A curb's top at 4 cm known to 3 mm: a beam passing 1 cm over it says nothing.
    let curb = Elevation {
        mean_m: 0.04,
        var_m2: 9e-6,
    };
    assert!(!band_contradicts(curb, 0.05, 0.06, 3.0));
}

#[test]
fn the_spread_of_a_scans_hits_widens_the_measurement_but_their_noise_does_not() {
    // Noise alone: the sample variance is the noise's.
    assert_eq!(spread_variance(1e-6, 1e-4, 1e-4), 1e-6);
    assert_eq!(spread_variance(1e-6, 0.8e-4, 1e-4), 1e-6);
    // Hits at 0 and 4 cm, 1 mm noise: the excess, about (2 cm)^2 x 2, is the edge's.
    let sample = 2.0 * 0.02 * 0.02; // two hits at +-2 cm: sum of squares / (n - 1)
    assert!((spread_variance(0.5e-6, sample, 1e-6) - (0.5e-6 + sample - 1e-6)).abs() < 1e-9);
}

#[test]
fn correlated_measurements_shrink_the_variance_by_their_independent_part() {
    // Independent (the paper): eq. 9 as is.
    assert_eq!(correlated_variance(0.5e-4, 1e-4, 1e-4, 0.0), 0.5e-4);
    // Fully correlated: two equal measurements are as certain as one.
    assert_eq!(correlated_variance(0.5e-4, 1e-4, 1e-4, 1.0), 1e-4);
    // A better measurement still improves the estimate; a worse one does not spoil it.
    assert_eq!(correlated_variance(0.2e-4, 1e-4, 0.25e-4, 1.0), 0.25e-4);
    assert_eq!(correlated_variance(0.9e-4, 1e-4, 9e-4, 1.0), 1e-4);
    // n measurements each correlated `rho` with the last carry the information of
    // 1 + (n - 1) (1 - rho) / (1 + rho) independent ones.
    let (s2, rho, n) = (1e-4_f32, 1.0 / 3.0_f32, 101);
    let mut var = s2;
    for _ in 1..n {
        let fused = var * s2 / (var + s2);
        var = correlated_variance(fused, var, s2, rho);
    }
    let expected = s2 / (1.0 + (n - 1) as f32 * 0.5);
    assert!(
        (var - expected).abs() < 1e-4 * expected,
        "{var} against {expected}"
    );
}

#[test]
fn the_normal_tail_matches_its_table() {
    // Abramowitz and Stegun, table 26.1, to 10 digits.
    for (z, q) in [
        (0.0, 0.5),
        (1.0, 0.158_655_253_9),
        (2.0, 0.022_750_131_95),
        (3.0, 0.001_349_898_032),
        (5.0, 2.866_515_719e-7),
    ] {
        let got = normal_tail(z);
        assert!((got - q).abs() <= 2e-7 * q, "Q({z}) = {got}, not {q}");
    }
    assert!((normal_tail(-1.0) - (1.0 - 0.158_655_253_9)).abs() < 2e-7);
}

#[test]
fn an_overhead_hit_among_many_must_stand_out_further() {
    // One hit: the band itself.
    assert!(overhead_significant(3.01, 1.0, 3.0));
    assert!(!overhead_significant(2.99, 1.0, 3.0));
    // The tail of a hundred pixels: 3.1 sigma is noise, 4.3 a structure.
    assert!(!overhead_significant(3.1, 100.0, 3.0));
    assert!(overhead_significant(4.3, 100.0, 3.0));
    assert!(!overhead_significant(4.3, 1000.0, 3.0));
    // A board's face 30 sigma over the ground stands out among any number.
    assert!(overhead_significant(30.0, 1e6, 3.0));
}

#[test]
fn a_range_error_is_projected_onto_the_vertical() {
    assert!(
        (vertical_variance(0.03, -1.0, 0.0) - 9e-4).abs() < 1e-9,
        "straight down: all of it"
    );
    assert!((vertical_variance(0.03, -0.5, 0.0) - 2.25e-4).abs() < 1e-9);
    assert!(
        (vertical_variance(0.03, 0.0, 0.0) - 1e-6).abs() < 1e-12,
        "level and near: the floor"
    );
    // Level at 10 m: the footprint, 2.2 cm.
    assert!((vertical_variance(0.03, 0.0, 10.0) - 0.022f32 * 0.022).abs() < 1e-7);
}

#[test]
fn disagreement_is_kept_as_variance() {
    let prior = Some(Elevation {
        mean_m: 0.0,
        var_m2: 1e-4,
    });
    // Agreement, exact or within the noise (a 1 cm difference with 1.4 cm expected): eq. 8-9.
    assert_eq!(
        fuse_with_disagreement(prior, 0.0, 1e-4, 0.0),
        kalman_fuse(prior, 0.0, 1e-4, 0.0)
    );
    assert_eq!(
        fuse_with_disagreement(prior, 0.01, 1e-4, 0.0),
        kalman_fuse(prior, 0.01, 1e-4, 0.0)
    );
    // A return 0.3 m up with equal weight: the mean halfway, the variance grows by 0.25 (0.09 - 2e-4).
    let odd = fuse_with_disagreement(prior, 0.3, 1e-4, 0.0);
    assert!((odd.mean_m - 0.15).abs() < 1e-6);
    assert!(
        (odd.var_m2 - (0.5e-4 + 0.25 * (0.09 - 2e-4))).abs() < 1e-6,
        "{odd:?}"
    );
    // Then ground again: the mean comes back, and the variance with it.
    let mut e = odd;
    for _ in 0..20 {
        e = fuse_with_disagreement(Some(e), 0.0, 1e-4, 0.0);
    }
    assert!(e.mean_m.abs() < 0.01 && e.var_m2 < 1e-3, "{e:?}");
    assert_eq!(
        fuse_with_disagreement(None, 0.2, 1e-4, 0.0),
        kalman_fuse(None, 0.2, 1e-4, 0.0)
    );
}

#[test]
fn a_ceiling_is_confirmed_lowered_and_cleared_as_its_evidence_says() {
    let opts = ModelOptions::default();
    let occupied = log_odds(opts.occupied_threshold);
    let hit = |z_m: f32| CeilingHit {
        z_m,
        var_m2: 1e-4,
        p: 0.9,
        seen_from: SeenFrom::Above,
    };
    let update = |c: Ceiling, h: Option<CeilingHit>, contradicted: bool, clear_m: f32| {
        update_ceiling(c, h, contradicted, clear_m, &opts, 0.0, occupied)
    };
    // A first hit makes a ceiling with one hit's evidence (log-odds of 0.9 = 2.2).
    let board = update(Ceiling::NONE, Some(hit(0.34)), false, f32::NEG_INFINITY);
    assert_eq!((board.z_m, board.var_m2), (0.34, 1e-4));
    assert!((board.log_odds - log_odds(0.9)).abs() < 1e-6);
    // The same structure again: fused, and its evidence grows to the clamp.
    let again = update(board, Some(hit(0.35)), false, f32::NEG_INFINITY);
    assert_eq!(
        Elevation {
            mean_m: again.z_m,
            var_m2: again.var_m2
        },
        kalman_fuse(board.height(), 0.35, 1e-4, 0.0)
    );
    assert_eq!(again.log_odds, opts.log_odds_max);
    // A lower structure sets the clearance: it replaces the ceiling.
    let lower = update(again, Some(hit(0.20)), false, f32::NEG_INFINITY);
    assert_eq!(lower.z_m, 0.20);
    // A higher hit alone is a higher part of the structure; with a contradiction, the lower part has gone.
    assert_eq!(update(lower, Some(hit(0.40)), false, f32::NEG_INFINITY), lower);
    assert_eq!(update(lower, Some(hit(0.40)), true, f32::NEG_INFINITY).z_m, 0.40);
    // A hit wins over a contradiction in the same scan.
    assert_eq!(
        update(board, Some(hit(0.345)), true, f32::NEG_INFINITY).log_odds,
        opts.log_odds_max
    );
    // One sure hit confirms a structure, one weak hit (a far stereo pixel) does not.
    assert!(ceiling_confirmed(board.log_odds, opts.p_max));
    let weak = update(
        Ceiling::NONE,
        Some(CeilingHit { p: 0.6, ..hit(0.34) }),
        false,
        f32::NEG_INFINITY,
    );
    assert!(weak.is_some() && !ceiling_confirmed(weak.log_odds, opts.p_max));
    // Nothing said: unchanged.
    assert_eq!(update(board, None, false, f32::NEG_INFINITY), board);
    assert!(!update(Ceiling::NONE, None, true, f32::NEG_INFINITY).is_some());
    // Contradictions alone, each as strong as the surest hit (logit of 1 - p_max = -2.2): from the clamp's
    // top (3.5), gone after exactly 2 scans; from one hit, after 1.
    let once = update(again, None, true, f32::NEG_INFINITY);
    assert!((once.log_odds - (3.5 - log_odds(0.9))).abs() < 1e-5, "{once:?}");
    assert!(!update(once, None, true, f32::NEG_INFINITY).is_some());
    assert!(!update(board, None, true, f32::NEG_INFINITY).is_some());
    // The highest beam under it is kept across scans, whatever else the scans say; a structure seen afresh
    // (a lower hit) starts with none.
    let passed = update(board, None, false, 0.25);
    assert_eq!(passed.clear_m, 0.25);
    assert_eq!(update(passed, Some(hit(0.345)), false, 0.20).clear_m, 0.25);
    assert_eq!(update(passed, Some(hit(0.345)), false, 0.30).clear_m, 0.30);
    assert_eq!(
        update(passed, Some(hit(0.20)), false, 0.30).clear_m,
        f32::NEG_INFINITY
    );
}

#[test]
fn a_beam_contradicts_a_ceiling_only_on_the_structures_side_of_it() {
    // A board's top at 0.34 m known to 1 cm, seen from above: the board lies under it.
    let top = Ceiling {
        z_m: 0.34,
        var_m2: 1e-4,
        log_odds: 2.0,
        seen_from: SeenFrom::Above,
        clear_m: f32::NEG_INFINITY,
    };
    assert!(
        ceiling_contradicts(&top, 0.33, 0.335, 3.0, 0.0),
        "through the board"
    );
    assert!(ceiling_passed_under(&top, 0.30, 3.0), "under the board: clear");
    assert!(!ceiling_passed_under(&top, 0.33, 3.0), "in the board's band");
    assert!(
        ceiling_contradicts(&top, 0.30, 0.40, 3.0, 0.0),
        "a steep beam across it"
    );
    assert!(
        !ceiling_contradicts(&top, 0.341, 0.345, 3.0, 0.0),
        "skimming over the top"
    );
    assert!(
        !ceiling_contradicts(&top, 0.20, 0.30, 3.0, 0.0),
        "under the board"
    );
    // Its underside at 0.30 m seen from below: the board lies over it.
    let underside = Ceiling {
        z_m: 0.30,
        seen_from: SeenFrom::Below,
        ..top
    };
    assert!(
        ceiling_contradicts(&underside, 0.305, 0.31, 3.0, 0.0),
        "through the board"
    );
    assert!(
        !ceiling_contradicts(&underside, 0.29, 0.299, 3.0, 0.0),
        "skimming under it"
    );
    assert!(
        !ceiling_contradicts(&underside, 0.40, 0.45, 3.0, 0.0),
        "over the board"
    );
    assert!(ceiling_passed_under(&underside, 0.299, 3.0));
    assert!(!ceiling_passed_under(&underside, 0.40, 3.0), "over it");
    // Seen from both sides: either side of it.
    let front = Ceiling {
        seen_from: SeenFrom::Both,
        ..top
    };
    assert!(ceiling_contradicts(&front, 0.341, 0.345, 3.0, 0.0));
    assert!(ceiling_contradicts(&front, 0.33, 0.335, 3.0, 0.0));
    assert!(!ceiling_contradicts(&front, 0.20, 0.30, 3.0, 0.0));
    assert_eq!(SeenFrom::Above.and(SeenFrom::Below), SeenFrom::Both);
    assert_eq!(SeenFrom::Below.and(SeenFrom::Below), SeenFrom::Below);
    for side in [SeenFrom::Above, SeenFrom::Below, SeenFrom::Both] {
        assert_eq!(SeenFrom::from_byte(side as u8), Some(side));
    }
    assert_eq!(SeenFrom::from_byte(3), None);
}

#[test]
fn a_measurement_is_above_within_or_below_a_surfaces_band() {
    let ground = Elevation {
        mean_m: 0.0,
        var_m2: 1e-4,
    };
    // The band is 3 sigma of the difference: sqrt(1e-4 + 1e-4) = 1.41 cm, so +-4.24 cm.
    assert_eq!(surface_level(ground, 0.04, 1e-4, 3.0), Level::Same);
    assert_eq!(surface_level(ground, 0.05, 1e-4, 3.0), Level::Above);
    assert_eq!(surface_level(ground, -0.05, 1e-4, 3.0), Level::Below);
    // A noisier measurement widens the band.
    assert_eq!(surface_level(ground, 0.05, 1e-3, 3.0), Level::Same);
}

#[test]
fn the_top_surface_is_kept_against_lower_hits_and_follows_higher_ones() {
    let top = Elevation {
        mean_m: 0.44,
        var_m2: 1e-5,
    };
    let table = Some(top);
    // The ground seen under a table top: a lower level, the estimate is left as it is.
    assert_eq!(fuse_top_surface(table, 0.0, 1e-4, 0.0, 3.0), top);
    // Within the band: eq. 8-9.
    assert_eq!(
        fuse_top_surface(table, 0.445, 1e-5, 0.0, 3.0),
        kalman_fuse(table, 0.445, 1e-5, 0.0)
    );
    // Above: pulled up with the disagreement kept as variance, so one spurious return does not become the
    // surface, and a surface seen again and again does.
    let ground = Some(Elevation {
        mean_m: 0.0,
        var_m2: 1e-4,
    });
    assert_eq!(
        fuse_top_surface(ground, 0.3, 1e-4, 0.0, 3.0),
        fuse_with_disagreement(ground, 0.3, 1e-4, 0.0)
    );
    let mut e = ground;
    for _ in 0..10 {
        e = Some(fuse_top_surface(e, 0.3, 1e-4, 0.0, 3.0));
    }
    assert!((e.expect("some").mean_m - 0.3).abs() < 0.01, "{e:?}");
    assert_eq!(
        fuse_top_surface(None, 0.2, 1e-4, 0.0, 3.0),
        kalman_fuse(None, 0.2, 1e-4, 0.0)
    );
    assert_eq!(
        fuse_elevation(ElevationFusion::TopSurface, table, 0.0, 1e-4, 0.0, 3.0),
        top
    );
}

#[test]
fn a_beam_within_its_footprint_of_a_structure_s_far_edge_does_not_contradict_it_but_one_through_its_height_does()
 {
    // A board's face hit by a descending ring: the hits read as a top and fuse into a band 3 mm deep under
    // 0.424 m, while the underside is at 0.4216 m.
    let face = Ceiling {
        z_m: 0.424,
        var_m2: 1e-6,
        log_odds: 3.5,
        seen_from: SeenFrom::Above,
        clear_m: f32::NEG_INFINITY,
    };
    // 2 m out, a beam's footprint is 4.4 mm (`BEAM_SIGMA_RAD`), as `vertical_variance` has it.
    let footprint = beam_footprint_m(2.0) as f32;
    for dir_z in [0.0_f64, -0.3] {
        let range = 2.0 / (1.0 - dir_z * dir_z).sqrt();
        let hit = vertical_variance(0.0, dir_z, range).sqrt();
        assert!((hit - footprint).abs() < 1e-6, "{hit} {footprint}");
    }
    assert!((footprint - 0.0044).abs() < 1e-6, "{footprint}");
    // A beam under the board, through the band's lower edge: a line through the band, but within its
    // footprint of the space under the board.
    let (lo, hi) = (0.4209, 0.4212);
    assert!(ceiling_contradicts(&face, lo, hi, 3.0, 0.0), "a line");
    assert!(
        !ceiling_contradicts(&face, lo, hi, 3.0, footprint),
        "a beam may have passed under the board"
    );
    // Nor did it pass under: it says neither.
    assert!(!ceiling_passed_under(&face, hi, 3.0));
    // A beam through the height where the board was hit contradicts it, however wide its footprint: the beam
    // that passes where a person stood clears them.
    assert!(ceiling_contradicts(&face, 0.4235, 0.4245, 3.0, footprint));
    assert!(
        !ceiling_contradicts(&face, 0.4241, 0.4245, 3.0, footprint),
        "over the top"
    );
    // A deep band, a person's front hit from the ankles up: narrowed by the footprint at its far edge only.
    let front = Ceiling {
        z_m: 1.0,
        var_m2: 0.01,
        seen_from: SeenFrom::Both,
        ..face
    };
    assert!(ceiling_contradicts(&front, 0.70, 0.75, 3.0, footprint));
    assert!(ceiling_contradicts(&front, 1.25, 1.29, 3.0, footprint));
    assert!(
        !ceiling_contradicts(&front, 0.69, 0.699, 3.0, footprint),
        "within the footprint below"
    );
    assert!(
        !ceiling_contradicts(&front, 1.297, 1.31, 3.0, footprint),
        "within the footprint above"
    );
    // An underside seen from below: narrowed over it, never under its height.
    let underside = Ceiling {
        z_m: 0.50,
        seen_from: SeenFrom::Below,
        ..face
    };
    assert!(ceiling_contradicts(&underside, 0.499, 0.501, 3.0, footprint));
    assert!(!ceiling_contradicts(&underside, 0.5025, 0.503, 3.0, footprint));
    assert!(
        ceiling_passed_under(&underside, 0.499, 3.0),
        "passing under is as before"
    );
}
