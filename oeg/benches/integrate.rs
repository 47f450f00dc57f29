//! Map-building speed: `cargo bench -p oeg --bench integrate`.
//!
//! * `real/3dtk_frames/<res>`: the 233,028 real rays of `../shared/data/3dtk_frames.graph` (or
//!   `$OEG_SHARED_DATA`) into a fresh map, single thread; skipped with a printed reason when absent. Compare
//!   with OctoMap's `graph2tree -i 3dtk_frames.graph -res <res>` run in the same session (README).
//! * `synthetic/fan/<res>`: a 100,000-ray scan of a room with a floor and walls, always available.
//! * `options/<settings>`: the room scan integrated 5 times at 0.05 m under the paper's model and under the
//!   static settings of the README (`below_elevation`, `highest_surface`, `free_space_max_depth_m`) and with
//!   `scan_hit_elevation = weighted_mean`, in the same run, so their ratios are the cost of those options.
//! * `decisions/<rule>`: the traversability of every cell of the 12 m x 12 m room (57,600 cells at 0.05 m) from
//!   the `robust` map of those 5 scans, under the paper's absolute step rule and under `robust`'s contact rule
//!   (the ground within the contact distance and the robot's half width, and the free cells' own rule).

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use nalgebra::Point3;
use oeg::{Map, MapConfig, Scan, SensorModel};

const RESOLUTIONS_M: [f64; 3] = [0.05, 0.1, 0.2];

fn shared_graph() -> Option<PathBuf> {
    let dir = std::env::var_os("OEG_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data"));
    let path = dir.join("3dtk_frames.graph");
    path.is_file().then_some(path)
}

fn build(scans: &[Scan], resolution_m: f64) -> Map {
    build_with(scans, MapConfig::new(resolution_m))
}

fn build_with(scans: &[Scan], config: MapConfig) -> Map {
    let mut map = Map::new(config).expect("valid config");
    for scan in scans {
        map.integrate(scan).expect("integrated");
    }
    map
}

fn real(c: &mut Criterion) {
    let Some(path) = shared_graph() else {
        println!("skipped real/3dtk_frames: 3dtk_frames.graph is absent (set OEG_SHARED_DATA)");
        return;
    };
    let scans = oeg::read_graph_scans(&path, SensorModel::laser()).expect("readable");
    let num_rays: usize = scans.iter().map(|s| s.rays.len()).sum();
    let mut group = c.benchmark_group("real/3dtk_frames");
    group.throughput(Throughput::Elements(num_rays as u64));
    group.sample_size(20);
    for r in RESOLUTIONS_M {
        group.bench_with_input(BenchmarkId::from_parameter(r), &r, |b, &r| {
            b.iter(|| black_box(build(&scans, r)))
        });
    }
    group.finish();
}

/// A sensor 1 m up in a 12 m x 12 m room: 100,000 rays to the floor and the walls.
fn room_scan() -> Scan {
    let mut scan = Scan::new(Point3::new(0.3, -0.2, 1.0), SensorModel::laser());
    let n = 100_000;
    for k in 0..n {
        let azimuth = f64::from(k) * 2.0 * std::f64::consts::PI / f64::from(n) * 37.0;
        let elevation = -0.6 + 0.7 * f64::from(k) / f64::from(n);
        let d = nalgebra::Vector3::new(
            azimuth.cos() * elevation.cos(),
            azimuth.sin() * elevation.sin().abs().max(0.3),
            elevation.sin(),
        );
        let d = d.normalize();
        // Distance to the floor (z = 0) or the walls at |x|, |y| = 6.
        let mut t = f64::INFINITY;
        if d.z < 0.0 {
            t = t.min(-1.0 / d.z);
        }
        for (o, v) in [(0.3, d.x), (-0.2, d.y)] {
            if v != 0.0 {
                t = t.min(((6.0f64.copysign(v)) - o) / v);
            }
        }
        scan.push_hit(scan.origin_in_world + d * t);
    }
    scan
}

fn synthetic(c: &mut Criterion) {
    let scans = [room_scan()];
    let mut group = c.benchmark_group("synthetic/fan");
    group.throughput(Throughput::Elements(scans[0].rays.len() as u64));
    group.sample_size(20);
    for r in RESOLUTIONS_M {
        group.bench_with_input(BenchmarkId::from_parameter(r), &r, |b, &r| {
            b.iter(|| black_box(build(&scans, r)))
        });
    }
    group.finish();
}

fn options(c: &mut Criterion) {
    let scan = room_scan();
    let scans = vec![scan; 5];
    let mut group = c.benchmark_group("options");
    group.throughput(Throughput::Elements(5 * scans[0].rays.len() as u64));
    group.sample_size(20);
    let paper = MapConfig::new(0.05);
    let static_settings = MapConfig {
        model: oeg::ModelOptions {
            free_space_occupancy: oeg::FreeSpaceOccupancy::BelowElevation,
            free_space_max_depth_m: Some(0.01),
            elevation_fusion: oeg::ElevationFusion::HighestSurface {
                mahalanobis_threshold: 3.0,
                lower_threshold: Some(1.0),
                multi_height_noise_m2: 1e-4,
            },
            ..oeg::ModelOptions::default()
        },
        ..MapConfig::new(0.05)
    };
    let weighted_mean = MapConfig {
        model: oeg::ModelOptions {
            scan_hit_elevation: oeg::ScanHitElevation::WeightedMean,
            ..oeg::ModelOptions::default()
        },
        ..MapConfig::new(0.05)
    };
    // The paper's rules with robust's height threshold: robust's cost without the rays it cuts.
    let paper_cut = MapConfig {
        model: oeg::ModelOptions {
            max_height_m: Some(oeg::RobotProfile::default().height_m + oeg::ROBUST_HEIGHT_MARGIN_M),
            ..oeg::ModelOptions::default()
        },
        ..MapConfig::new(0.05)
    };
    let robust = MapConfig {
        model: oeg::MapPreset::Robust.model(&oeg::RobotProfile::default()),
        ..MapConfig::new(0.05)
    };
    for (name, config) in [
        ("paper", paper),
        ("static_settings", static_settings),
        ("weighted_mean", weighted_mean),
        ("paper_height_threshold", paper_cut),
        ("robust", robust),
    ] {
        group.bench_function(name, |b| b.iter(|| black_box(build_with(&scans, config))));
    }
    group.finish();
}

fn decisions(c: &mut Criterion) {
    let profile = oeg::RobotProfile::default();
    let scans = vec![room_scan(); 5];
    let map = build_with(
        &scans,
        MapConfig {
            model: oeg::MapPreset::Robust.model(&profile),
            ..MapConfig::new(0.05)
        },
    );
    let region = map
        .geometry()
        .region_covering((-6.0, -6.0), (6.0, 6.0))
        .expect("region");
    let mut group = c.benchmark_group("decisions");
    group.throughput(Throughput::Elements(region.num_cells()));
    group.sample_size(20);
    for (name, rule) in [
        ("absolute", oeg::TraversabilityRule::Absolute),
        ("contact", oeg::MapPreset::Robust.traversability()),
    ] {
        group.bench_function(name, |b| {
            b.iter(|| {
                black_box(
                    map.traversability_layer(region, &profile, rule)
                        .expect("within the limit"),
                )
            })
        });
    }
    group.finish();
}

criterion_group!(benches, real, synthetic, options, decisions);
criterion_main!(benches);
