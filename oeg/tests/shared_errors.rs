//! Measurements that share their errors, under the recommended model: views of a cell from one place repeat
//! its errors, views a cell's width apart each add part of an independent one's information
//! (`ModelOptions::measurement_correlation`); and a hit is a structure over a surface only if the surface's
//! own noise, where the beam would meet it, cannot explain it.

use nalgebra::Point3;
use oeg::{CellIndex, Map, MapConfig, MapPreset, ModelOptions, Ray, RobotProfile, Scan, SensorModel};

fn robust() -> ModelOptions {
    MapPreset::Robust.model(&RobotProfile::default())
}

fn map_with(model: ModelOptions) -> Map {
    Map::new(MapConfig {
        model,
        ..MapConfig::new(0.05)
    })
    .expect("valid config")
}

fn cell(map: &Map, x: f64, y: f64) -> CellIndex {
    map.geometry().cell_of(x, y).expect("finite")
}

/// The variance of the ground cell at (1.025, 0.025) after one laser hit on it from each of `origins`.
fn variance_after(model: ModelOptions, origins: &[Point3<f64>]) -> f32 {
    let mut map = map_with(model);
    for origin in origins {
        let mut scan = Scan::new(*origin, SensorModel::laser());
        scan.push_hit(Point3::new(1.025, 0.025, 0.0));
        map.integrate(&scan).expect("integrated");
    }
    let c = cell(&map, 1.025, 0.025);
    map.cell(c).elevation().expect("measured").var_m2
}

#[test]
fn views_from_one_place_repeat_their_errors_and_views_a_cell_apart_add_information() {
    let standing: Vec<_> = (0..10).map(|_| Point3::new(0.0, 0.025, 0.5)).collect();
    // Backing away a cell's width (5 cm) between scans: each view correlates exp(-1) with the last.
    let moving: Vec<_> = (0..10)
        .map(|k| Point3::new(-0.05 * k as f64, 0.025, 0.5))
        .collect();
    let one = variance_after(robust(), &standing[..1]);
    assert_eq!(
        variance_after(robust(), &standing),
        one,
        "ten views from one place are one view"
    );
    let moved = variance_after(robust(), &moving);
    let independent = variance_after(
        ModelOptions {
            measurement_correlation: 0.0,
            ..robust()
        },
        &moving,
    );
    // Each of the nine later views carries (1 - 1/e) / (1 + 1/e) = 0.46 of an independent view's information:
    // about 1 + 9 x 0.46 = 5.2 views, against 10 independent ones.
    assert!(moved < one / 4.0, "{moved} against one view's {one}");
    assert!(
        moved > independent * 1.5,
        "{moved} against independent views' {independent}"
    );
}

#[test]
fn a_far_stereo_pixel_measured_short_over_known_ground_is_not_a_structure() {
    let origin = Point3::new(0.0, 0.025, 0.5);
    // Ground 2.975 m away, as a camera measures it there: 4.9 cm of height error.
    let ground = Point3::new(2.975, 0.025, 0.0);
    // A pixel looking at the ground 5 m away reads 2.99 m: its end point lies in the same cell, 20 cm over
    // the ground. At the range it read, the camera's error is 0.29 m, and the end point lies 3.5 standard
    // deviations of the difference over the ground; at the 5 m where its beam meets the ground, 0.81 m (2.1
    // standard deviations): the ground's own noise.
    let far = Point3::new(5.0, 0.025, 0.0);
    let dir = (far - origin).normalize();
    let short = origin + dir * (ground.x / dir.x);
    let over_ground = |sensor: SensorModel| {
        let mut map = map_with(robust());
        let mut camera = Scan::new(origin, SensorModel::stereo());
        camera.push_hit(ground);
        map.integrate(&camera).expect("integrated");
        let mut scan = Scan::new(origin, sensor);
        scan.rays.push(Ray::hit((short - origin).cast::<f32>()));
        map.integrate(&scan).expect("integrated");
        map.ceiling(cell(&map, ground.x, ground.y))
    };
    let ceiling = over_ground(SensorModel::stereo());
    assert!(ceiling.is_none(), "{ceiling:?}");
    // A laser's reading of the same point, with its 1.2 cm of error, is something over the ground.
    let ceiling = over_ground(SensorModel::laser()).expect("a structure");
    assert!((ceiling.z_m - short.z as f32).abs() < 1e-3, "{ceiling:?}");
}
