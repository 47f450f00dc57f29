//! Long scans: one can be stopped (`Map::integrate_unless` asks its caller every `RAYS_BETWEEN_STOP_CHECKS` rays
//! and leaves the map as it was), and long rays that together need more memory than the map may hold are refused
//! before the memory is taken.

use std::sync::atomic::{AtomicUsize, Ordering};

use nalgebra::{Point3, Vector3};
use oeg::{Error, Map, MapConfig, RAYS_BETWEEN_STOP_CHECKS, Ray, Scan, SensorModel};

/// `n` rays from above the origin to a circle of 10 m.
fn ring(n: usize) -> Scan {
    let mut scan = Scan::new(Point3::new(0.0, 0.0, 0.5), SensorModel::laser());
    scan.rays = (0..n)
        .map(|k| {
            let a = k as f32 / n as f32 * std::f32::consts::TAU;
            Ray::hit(Vector3::new(10.0 * a.cos(), 10.0 * a.sin(), -0.5))
        })
        .collect();
    scan
}

#[test]
fn a_stopped_scan_leaves_the_map_as_it_was_and_the_next_one_integrates() {
    let mut map = Map::new(MapConfig::new(0.05)).expect("map");
    let scan = ring(5 * RAYS_BETWEEN_STOP_CHECKS);
    // A cancellation, once asked for, stays asked for (the threads that gather a long scan's rays each ask).
    let asked = AtomicUsize::new(0);
    let stop_at_the_third_question = || asked.fetch_add(1, Ordering::SeqCst) + 1 >= 3;
    let e = map
        .integrate_unless(&scan, &stop_at_the_third_question)
        .expect_err("stopped");
    assert!(matches!(e, Error::Cancelled), "{e}");
    assert!(asked.load(Ordering::SeqCst) >= 3);
    assert_eq!((map.num_scans(), map.num_observed_cells()), (0, 0));
    // Not stopped: the same as `integrate`.
    let mut plain = Map::new(MapConfig::new(0.05)).expect("map");
    let stats = map.integrate_unless(&scan, &|| false).expect("integrated");
    assert_eq!(stats, plain.integrate(&scan).expect("integrated"));
    assert_eq!(map.num_observed_cells(), plain.num_observed_cells());
    assert!(map.num_observed_cells() > 0);
}

#[test]
fn far_stereo_hits_whose_bands_together_pass_the_limit_are_refused_before_the_second_is_allocated() {
    // Two hits 60 m away: a stereo error band of 3 sigma (about 345 m past the hit at 60 m) makes each ray's
    // scratch (127 tiles of 64 x 64 cells, 20 bytes a cell under the paper's rules: 10.4 MB) more than half the
    // limit; the two together more than it. The second ray is refused before its tiles are allocated, so the
    // scratch keeps only the first ray's.
    let limit = 16 << 20;
    let config = MapConfig {
        memory_limit_bytes: limit,
        ..MapConfig::new(0.05)
    };
    let mut map = Map::new(config).expect("map");
    let mut scan = Scan::new(Point3::origin(), SensorModel::stereo());
    scan.rays = vec![
        Ray::hit(Vector3::new(60.0, 0.0, 0.0)),
        Ray::hit(Vector3::new(0.0, 60.0, 0.0)),
    ];
    let e = map.integrate(&scan).expect_err("over the limit");
    assert!(matches!(e, Error::MemoryLimit { .. }), "{e}");
    let held = map.memory_bytes() + map.scratch_bytes();
    assert!(
        held > limit / 2 && held < limit * 3 / 4,
        "{held} bytes held after the refusal, of a limit of {limit}"
    );
}

#[test]
fn under_every_rule_s_evidence_the_hits_kept_beside_the_grid_count_against_the_limit() {
    // A far stereo hit under the recommended model: its band's cells each keep 32 bytes in the scratch grid
    // and, within 3 sigma of the hit, 48 more in the scan's hit log (thousands of cells here). Whatever the
    // limit, the map either takes the ray and holds no more than the limit, log included, or refuses it with
    // a memory error and holds no more than the limit either. The least limit that takes it is found by
    // bisection.
    let mut scan = Scan::new(Point3::new(0.0, 0.0, 0.3), SensorModel::stereo());
    scan.rays = vec![Ray::hit(Vector3::new(40.0, 0.0, -0.3))];
    let try_under = |limit: u64| {
        let mut map = Map::new(MapConfig {
            memory_limit_bytes: limit,
            model: oeg::MapPreset::Robust.model(&oeg::RobotProfile::default()),
            ..MapConfig::new(0.05)
        })
        .expect("map");
        let done = map.integrate(&scan);
        let held = map.memory_bytes() + map.scratch_bytes();
        assert!(held <= limit, "{held} bytes held under a limit of {limit}");
        match &done {
            Ok(_) => {}
            // A refusal says what the map and its scratch would have held: more than the limit.
            Err(
                e @ Error::MemoryLimit {
                    requested_bytes,
                    limit_bytes,
                },
            ) => assert!(requested_bytes > limit_bytes, "{e}"),
            Err(e) => panic!("{e}"),
        }
        (done.is_ok(), held)
    };
    let (mut refused, mut taken) = (1u64 << 20, 64u64 << 20);
    assert!(!try_under(refused).0 && try_under(taken).0);
    while taken - refused > 1 {
        let mid = refused + (taken - refused) / 2;
        if try_under(mid).0 {
            taken = mid;
        } else {
            refused = mid;
        }
    }
    // Below it, every limit down to past the map's own cells (a few megabytes) is refused within itself: the
    // grid fits some of these without the log.
    for k in 1..=160 {
        assert!(!try_under(taken - k * 32 * 1024).0);
    }
    // Where it is taken, the log is part of what is held: thousands of cells of 48 bytes.
    let (_, held) = try_under(taken);
    let mut paper = Map::new(MapConfig::new(0.05)).expect("map");
    paper.integrate(&scan).expect("fits");
    assert!(
        held > paper.memory_bytes() + 1000 * 48,
        "{held} bytes held at the least limit"
    );
}
