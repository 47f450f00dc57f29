//! The map is the same, bit for bit, on any number of threads: a long scan's rays are gathered in parallel and
//! the touched tiles updated in parallel (`Map::integrate`), and short scans are gathered side by side
//! (`Map::integrate_batch`), under every preset, on synthetic scans long enough to be split, on the same rays
//! cut into short scans, and on the shared real scans when present.

mod common;

use common::shared_file;
use nalgebra::{Point3, Vector3};
use oeg::{Map, MapConfig, MapPreset, Ray, RobotProfile, Scan, SensorModel, map_to_bytes};

/// How the scans are given to the map.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Feed {
    /// `Map::integrate`, scan by scan.
    OneByOne,
    /// `Map::integrate_batch`, all at once.
    Batch,
}

/// `f` on a pool of `threads` threads.
fn on_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
        .install(f)
}

fn map_of(preset: MapPreset, resolution_m: f64) -> Map {
    let mut config = MapConfig::new(resolution_m);
    config.model = preset.model(&RobotProfile::default());
    Map::new(config).expect("valid")
}

/// Integrates `scans` into a fresh map of `preset` at `resolution_m` on a pool of `threads` threads and
/// returns the saved map's bytes.
fn map_bytes_on(threads: usize, feed: Feed, preset: MapPreset, resolution_m: f64, scans: &[Scan]) -> Vec<u8> {
    on_threads(threads, || {
        let mut map = map_of(preset, resolution_m);
        match feed {
            Feed::OneByOne => {
                for scan in scans {
                    map.integrate(scan).expect("integrated");
                }
            }
            Feed::Batch => {
                map.integrate_batch(scans).expect("integrated");
            }
        }
        assert!(map.num_observed_cells() > 100);
        assert_eq!(map.num_scans(), scans.len() as u64);
        map_to_bytes(&map)
    })
}

/// The map of `scans` one by one on one thread, against the map on 2, 3 and 5 threads, one by one and in a
/// batch (and in a batch on one thread).
fn assert_same_on_any_thread_count(resolution_m: f64, scans: &[Scan]) {
    for preset in MapPreset::ALL {
        let one = map_bytes_on(1, Feed::OneByOne, preset, resolution_m, scans);
        for (threads, feed) in [
            (1, Feed::Batch),
            (2, Feed::OneByOne),
            (2, Feed::Batch),
            (3, Feed::Batch),
            (5, Feed::OneByOne),
            (5, Feed::Batch),
        ] {
            assert!(
                map_bytes_on(threads, feed, preset, resolution_m, scans) == one,
                "{preset:?} at {resolution_m} m: the map on {threads} threads ({feed:?}) differs from the \
                 map on one"
            );
        }
    }
}

/// `scans` cut into scans of `rays` rays each, from the same sensor pose: a robot's log of short scans.
fn cut(scans: &[Scan], rays: usize) -> Vec<Scan> {
    scans
        .iter()
        .flat_map(|scan| {
            scan.rays.chunks(rays).map(|chunk| {
                let mut short = scan.clone();
                short.rays = chunk.to_vec();
                short
            })
        })
        .collect()
}

/// A sensor 0.4 m over a floor with a box and a step, sweeping 24,000 rays (long enough to be split among 5
/// threads): most hit the ground, some the box, some return nothing, and some run level into a wall. The level
/// rays all measure the sensor's height exactly, at ranges (and so variances) that differ: the highest hit of
/// a wall cell is a tie between rays of different runs, which the merge must resolve as one thread does.
fn synthetic_scans() -> Vec<Scan> {
    (0..3)
        .map(|k| {
            let origin = Point3::new(f64::from(k) * 0.7, 0.2 * f64::from(k), 0.4);
            let mut scan = Scan::new(origin, SensorModel::laser());
            scan.rays = (0..24_000)
                .map(|i| {
                    let azimuth = i as f32 / 24_000.0 * std::f32::consts::TAU * 7.0;
                    let range = 1.0 + (i % 997) as f32 / 997.0 * 9.0;
                    let (x, y) = (range * azimuth.cos(), range * azimuth.sin());
                    let ground = if (2.0..3.0).contains(&x) && y.abs() < 1.0 {
                        0.4
                    } else if x < -4.0 {
                        0.05
                    } else {
                        0.0
                    };
                    let z = ground - origin.z as f32;
                    if i % 13 == 0 {
                        Ray::no_return(Vector3::new(x, y, 0.0))
                    } else if i % 7 == 0 {
                        // Level, into a wall 11 to 12 m away.
                        let wall = 11.0 + (i % 11) as f32 / 11.0;
                        Ray::hit(Vector3::new(wall * azimuth.cos(), wall * azimuth.sin(), 0.0))
                    } else {
                        Ray::hit(Vector3::new(x, y, z))
                    }
                })
                .collect();
            scan
        })
        .collect()
}

#[test]
fn a_synthetic_map_is_the_same_on_one_two_three_and_five_threads() {
    assert_same_on_any_thread_count(0.05, &synthetic_scans());
}

#[test]
fn short_scans_and_long_ones_between_them_map_the_same_on_any_thread_count() {
    let long = synthetic_scans();
    // 700-ray scans, with a long scan after every 25 of them (a stereo frame between laser lines).
    let mut scans = Vec::new();
    for (k, short) in cut(&long, 700).into_iter().enumerate() {
        if k % 25 == 24 {
            scans.push(long[k / 25 % long.len()].clone());
        }
        scans.push(short);
    }
    assert!(scans.len() > 100);
    assert_same_on_any_thread_count(0.05, &scans);
}

#[test]
fn a_batch_stops_at_the_scan_the_map_refuses_with_the_scans_before_it_in_the_map() {
    let scans = cut(&synthetic_scans(), 600);
    let mut bad = scans[..12].to_vec();
    bad[9].rays[3] = Ray::hit(Vector3::new(f32::NAN, 0.0, 0.0));
    for threads in [1, 2] {
        on_threads(threads, || {
            let mut map = map_of(MapPreset::Paper, 0.05);
            let err = map.integrate_batch(&bad).expect_err("scan 9 holds a NaN");
            assert_eq!(err.index, 9, "{err}");
            assert!(err.to_string().contains("scan 9"), "{err}");
            let mut before = map_of(MapPreset::Paper, 0.05);
            for scan in &scans[..9] {
                before.integrate(scan).expect("valid");
            }
            assert!(
                map_to_bytes(&map) == map_to_bytes(&before),
                "on {threads} threads"
            );
        });
    }
}

#[test]
fn the_shared_real_scans_map_the_same_on_any_thread_count() {
    let Some(path) = shared_file("3dtk_frames.graph") else {
        return;
    };
    let scans = oeg::read_graph_scans(&path, SensorModel::laser()).expect("readable");
    assert_same_on_any_thread_count(0.05, &scans);
}

#[test]
fn the_shared_real_scans_cut_into_short_scans_map_the_same_on_any_thread_count() {
    let Some(path) = shared_file("3dtk_frames.graph") else {
        return;
    };
    let scans = oeg::read_graph_scans(&path, SensorModel::laser()).expect("readable");
    assert_same_on_any_thread_count(0.1, &cut(&scans, 900));
}

#[test]
fn a_batch_near_its_memory_limit_maps_and_stops_where_one_thread_does() {
    let scans = cut(&synthetic_scans(), 600);
    // What the map of every scan holds, and the most its scratch held for one scan, on one thread.
    let mut full = map_of(MapPreset::Paper, 0.05);
    let mut scratch_bytes = 0;
    for scan in &scans {
        full.integrate(scan).expect("integrated");
        scratch_bytes = scratch_bytes.max(full.scratch_bytes());
    }
    let full_bytes = full.memory_bytes() + scratch_bytes;
    // From a limit the first scans already exceed to one whose half (the windows' budget) leaves each thread's
    // share of it (a sixteenth) too small for some scans' lists, to one that leaves room.
    for limit in [
        full_bytes / 4,
        full_bytes,
        2 * full_bytes,
        8 * full_bytes,
        64 * full_bytes,
    ] {
        let run = |threads: usize| {
            on_threads(threads, || {
                let mut config = MapConfig::new(0.05);
                config.memory_limit_bytes = limit;
                let mut map = Map::new(config).expect("valid");
                let stopped = map.integrate_batch(&scans).err().map(|e| e.index);
                (stopped, map_to_bytes(&map))
            })
        };
        let (stopped, one) = run(1);
        for threads in [2, 3] {
            let (stopped_here, bytes) = run(threads);
            assert_eq!(stopped_here, stopped, "limit {limit} B on {threads} threads");
            assert!(
                bytes == one,
                "limit {limit} B: the map on {threads} threads differs"
            );
        }
        if limit == full_bytes / 4 {
            assert!(stopped.is_some(), "a quarter of the map's bytes stops the batch");
        }
        if limit == 64 * full_bytes {
            assert_eq!(stopped, None, "64 times the map's bytes maps every scan");
        }
    }
}

#[test]
fn long_scans_of_the_recommended_model_near_its_memory_limit_map_and_stop_where_one_thread_does() {
    // Under `robust` a long scan's later runs defer their hits and replay them into the first run's log after
    // the grids merge; the log must stay within the limit as one thread's does, and a refused scan leaves the
    // map as one thread leaves it.
    let scans = &synthetic_scans()[..2];
    let run = |threads: usize, limit: u64| {
        on_threads(threads, || {
            let mut config = MapConfig::new(0.1);
            config.model = MapPreset::Robust.model(&RobotProfile::default());
            config.memory_limit_bytes = limit;
            let mut map = Map::new(config).expect("valid");
            let taken = scans.iter().take_while(|s| map.integrate(s).is_ok()).count();
            let held = map.memory_bytes() + map.scratch_bytes();
            assert!(
                held <= limit,
                "{held} B held under {limit} B on {threads} threads"
            );
            (taken, map_to_bytes(&map))
        })
    };
    // The least limit under which one thread maps every scan, by bisection.
    let (mut refused, mut taken) = (1u64 << 16, 1u64 << 30);
    assert!(run(1, refused).0 < scans.len(), "{:?}", run(1, refused).0);
    assert!(run(1, taken).0 == scans.len(), "{:?}", run(1, taken).0);
    while taken - refused > 64 * 1024 {
        let mid = refused + (taken - refused) / 2;
        if run(1, mid).0 == scans.len() {
            taken = mid;
        } else {
            refused = mid;
        }
    }
    for limit in [refused / 2, refused, taken, taken + 64 * 1024, 2 * taken] {
        let (scans_taken, one) = run(1, limit);
        for threads in [2, 3] {
            let (taken_here, bytes) = run(threads, limit);
            assert_eq!(taken_here, scans_taken, "limit {limit} B on {threads} threads");
            assert!(
                bytes == one,
                "limit {limit} B: the map on {threads} threads differs"
            );
        }
    }
}
