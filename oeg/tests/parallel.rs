//! The map is the same, bit for bit, on any number of threads: a long scan's rays are gathered in parallel and
//! the touched tiles updated in parallel (`Map::integrate`), under every preset, on synthetic scans long enough
//! to be split and on the shared real scans when present.

mod common;

use common::shared_file;
use nalgebra::{Point3, Vector3};
use oeg::{Map, MapConfig, MapPreset, Ray, RobotProfile, Scan, SensorModel, map_to_bytes};

/// Integrates `scans` into a fresh map of `preset` at `resolution_m` on a pool of `threads` threads and
/// returns the saved map's bytes.
fn map_bytes_on(threads: usize, preset: MapPreset, resolution_m: f64, scans: &[Scan]) -> Vec<u8> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool");
    pool.install(|| {
        let mut config = MapConfig::new(resolution_m);
        config.model = preset.model(&RobotProfile::default());
        let mut map = Map::new(config).expect("valid");
        for scan in scans {
            map.integrate(scan).expect("integrated");
        }
        assert!(map.num_observed_cells() > 100);
        map_to_bytes(&map)
    })
}

fn assert_same_on_any_thread_count(resolution_m: f64, scans: &[Scan]) {
    for preset in MapPreset::ALL {
        let one = map_bytes_on(1, preset, resolution_m, scans);
        for threads in [2, 3, 5] {
            assert!(
                map_bytes_on(threads, preset, resolution_m, scans) == one,
                "{preset:?} at {resolution_m} m: the map on {threads} threads differs from the map on one"
            );
        }
    }
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
fn the_shared_real_scans_map_the_same_on_any_thread_count() {
    let Some(path) = shared_file("3dtk_frames.graph") else {
        return;
    };
    let scans = oeg::read_graph_scans(&path, SensorModel::laser()).expect("readable");
    assert_same_on_any_thread_count(0.05, &scans);
}
