//! Small hand-made scans for the map's behaviour tests (`map_behaviour.rs`, `recommended_rules.rs`).

use nalgebra::{Point3, Vector3};
use oeg::{CellIndex, Map, MapConfig, ModelOptions, Ray, Scan, SensorModel};

/// A map of `resolution_m` cells under `model`.
pub(crate) fn map_with(resolution_m: f64, model: ModelOptions) -> Map {
    Map::new(MapConfig {
        model,
        ..MapConfig::new(resolution_m)
    })
    .expect("valid config")
}

/// The cell under `(x, y)`.
pub(crate) fn cell(map: &Map, x: f64, y: f64) -> CellIndex {
    map.geometry().cell_of(x, y).expect("finite")
}

/// A fan of laser rays from `origin` hitting the points `(x, y, z)` of `targets`.
pub(crate) fn scan_of(origin: Point3<f64>, targets: &[(f64, f64, f64)]) -> Scan {
    let mut scan = Scan::new(origin, SensorModel::laser());
    for &(x, y, z) in targets {
        scan.push_hit(Point3::new(x, y, z));
    }
    scan
}

/// A straight-down ray onto `(x, y, z)`, its range (and so its height) known to 5 mm.
pub(crate) fn hit_from_above(map: &mut Map, x: f64, y: f64, z: f64) {
    let mut scan = Scan::new(Point3::new(x, y, z + 1.0), SensorModel::laser());
    scan.rays
        .push(Ray::hit(Vector3::new(0.0, 0.0, -1.0)).with_range_sigma_m(0.005));
    map.integrate(&scan).expect("integrated");
}
