//! The built-in demonstration data: what `oeg` with no arguments maps until the simulated scenarios arrive.
//!
//! A scanner 0.45 m above the ground drives 6 m along +x through a small analytic scene (a floor, a 3 cm and a
//! 5 cm curb, a board at 0.33-0.35 m on the right, walls) and sweeps a 120 x 35 degree field of rays from
//! 12 poses. Rays are intersected with the scene's boxes exactly (slab test), without noise; rays that hit
//! nothing within 12 m are left out (the scan-graph format has no no-return rays). The result is written as an
//! OctoMap scan graph, so the demo exercises the same reader as real data.

use std::path::Path;

use nalgebra::{Point3, Vector3};
use oeg::{Scan, SensorModel};

use crate::error::Result;

/// An axis-aligned box, min and max corners.
#[derive(Debug, Clone, Copy)]
struct Aabb {
    min: [f64; 3],
    max: [f64; 3],
}

/// The demo scene: name and box.
fn scene() -> Vec<(&'static str, Aabb)> {
    vec![
        (
            "floor",
            Aabb {
                min: [-2.0, -4.0, -0.1],
                max: [14.0, 4.0, 0.0],
            },
        ),
        (
            "curb 3 cm",
            Aabb {
                min: [3.0, -2.0, 0.0],
                max: [3.3, -0.4, 0.03],
            },
        ),
        (
            "curb 5 cm",
            Aabb {
                min: [3.0, 0.4, 0.0],
                max: [3.3, 2.0, 0.05],
            },
        ),
        (
            "board at 0.35 m",
            Aabb {
                min: [5.0, -2.0, 0.33],
                max: [5.6, -0.6, 0.35],
            },
        ),
        (
            "left wall",
            Aabb {
                min: [-2.0, 3.0, 0.0],
                max: [14.0, 3.2, 1.0],
            },
        ),
        (
            "right wall",
            Aabb {
                min: [-2.0, -3.2, 0.0],
                max: [14.0, -3.0, 1.0],
            },
        ),
        (
            "end wall",
            Aabb {
                min: [12.0, -3.2, 0.0],
                max: [12.2, 3.2, 1.0],
            },
        ),
    ]
}

/// Distance along the unit ray `o + d t` to the box, if it is hit within `max_t` (slab method).
fn hit(o: &Point3<f64>, d: &Vector3<f64>, b: &Aabb, max_t: f64) -> Option<f64> {
    let (mut t0, mut t1) = (0.0f64, max_t);
    for a in 0..3 {
        if d[a].abs() < 1e-12 {
            if o[a] < b.min[a] || o[a] > b.max[a] {
                return None;
            }
            continue;
        }
        let (ta, tb) = ((b.min[a] - o[a]) / d[a], (b.max[a] - o[a]) / d[a]);
        t0 = t0.max(ta.min(tb));
        t1 = t1.min(ta.max(tb));
        if t0 > t1 {
            return None;
        }
    }
    Some(t0)
}

/// The demo's scans.
pub fn demo_scans() -> Vec<Scan> {
    let boxes = scene();
    let mut scans = Vec::new();
    for k in 0..12 {
        let origin = Point3::new(0.5 * f64::from(k), 0.0, 0.45);
        let mut scan = Scan::new(origin, SensorModel::laser());
        for el in -30..=5 {
            for az in -60..=60 {
                let (el, az) = (f64::from(el).to_radians(), f64::from(az).to_radians());
                let d = Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin());
                let nearest = boxes
                    .iter()
                    .filter_map(|(_, b)| hit(&origin, &d, b, 12.0))
                    .reduce(f64::min);
                if let Some(t) = nearest {
                    scan.push_hit(origin + d * t);
                }
            }
        }
        scans.push(scan);
    }
    scans
}

/// Writes the demo's scans as an OctoMap scan graph.
///
/// # Errors
/// The file cannot be written.
pub fn write_demo_graph(path: &Path) -> Result<()> {
    oeg::write_graph(path, &demo_scans())?;
    Ok(())
}

/// Maps the demo's scans with `job`'s settings into `job.out_dir`, keeping the scans there as `demo.graph`
/// (`job.inputs` and `job.keep_inputs` are set here). The scans go through a scratch folder, removed after.
///
/// # Errors
/// As [`super::run`], and a scratch folder that cannot be written.
pub fn run(job: super::MapJob, progress: &crate::progress::Progress) -> Result<super::MapReport> {
    let scratch = std::env::temp_dir().join(format!("oeg-demo-{}", std::process::id()));
    crate::output::create_dir(&scratch)?;
    let input = scratch.join("demo.graph");
    let result = write_demo_graph(&input).and_then(|()| {
        super::run(
            &super::MapJob {
                inputs: vec![input.clone()],
                keep_inputs: true,
                ..job
            },
            progress,
        )
    });
    let _ = std::fs::remove_dir_all(&scratch);
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_slab_test_finds_the_near_face() {
        let b = Aabb {
            min: [1.0, -1.0, -1.0],
            max: [2.0, 1.0, 1.0],
        };
        let o = Point3::new(0.0, 0.0, 0.0);
        assert_eq!(hit(&o, &Vector3::x(), &b, 10.0), Some(1.0));
        assert_eq!(hit(&o, &-Vector3::x(), &b, 10.0), None);
        assert_eq!(hit(&o, &Vector3::x(), &b, 0.5), None);
    }

    #[test]
    fn demo_rays_end_on_the_scene() {
        let scans = demo_scans();
        assert_eq!(scans.len(), 12);
        // Downward rays from 0.45 m hit the floor at z = 0 or an obstacle top.
        for ray in scans[0].rays.iter().take(50) {
            let end = scans[0].origin_in_world + ray.offset_in_world.cast::<f64>();
            assert!(end.z >= -1e-6 && end.z <= 1.0 + 1e-6, "{end}");
        }
    }
}
