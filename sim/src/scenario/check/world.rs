//! The check of the scenario's place: the ground, the obstacles and the actors.

use super::super::load::{KeySeg, MAX_MAP_CELLS, MAX_OBJECTS, MAX_PARTS};
use super::super::scene::{Actor, Obstacle, Terrain};
use super::super::schema::Scenario;
use super::Checker;
use crate::error::Result;

impl Checker<'_> {
    /// The obstacles and the actors: their number, their parts and each one's values.
    pub(super) fn validate_objects(&self, s: &Scenario) -> Result<()> {
        use KeySeg::{Index as I, Key as K};
        for (key, n) in [("obstacles", s.obstacles.len()), ("actors", s.actors.len())] {
            self.check(n <= MAX_OBJECTS, &[K(key)], || {
                format!("{n} {key}, over the limit of {MAX_OBJECTS}")
            })?;
        }
        for (k, o) in s.obstacles.iter().enumerate() {
            self.validate_obstacle(s, k, o)?;
        }
        let parts: usize = s
            .obstacles
            .iter()
            .map(|o| match o {
                Obstacle::Bush { num_parts, .. } => *num_parts as usize,
                _ => 1,
            })
            .sum();
        self.check(parts <= MAX_PARTS, &[K("obstacles")], || {
            format!("the obstacles hold {parts} solid parts (a bush counts its num_parts), over the limit of {MAX_PARTS}")
        })?;
        for (k, a) in s.actors.iter().enumerate() {
            let Actor::Person {
                waypoints,
                radius_m,
                height_m,
                ..
            } = a;
            let at = |key| [K("actors"), I(k), K(key)];
            self.length(*radius_m, &at("radius_m"), "radius in metres")?;
            self.length(*height_m, &at("height_m"), "height in metres")?;
            self.check(!waypoints.is_empty(), &at("waypoints"), || {
                "expected at least one [t_s, x_m, y_m]".into()
            })?;
            for (n, w) in waypoints.iter().enumerate() {
                let path = [K("actors"), I(k), K("waypoints"), I(n)];
                self.check(w[0].is_finite(), &path, || {
                    format!("time {} is not a number", w[0])
                })?;
                self.inside(s, [w[1], w[2]], &path)?;
                if n > 0 {
                    self.check(w[0] > waypoints[n - 1][0], &path, || {
                        format!(
                            "times must increase: {} s follows {} s",
                            w[0],
                            waypoints[n - 1][0]
                        )
                    })?;
                }
            }
        }
        Ok(())
    }

    pub(super) fn validate_terrain(&self, s: &Scenario) -> Result<()> {
        use KeySeg::Key as K;
        let at = |key| [K("terrain"), K(key)];
        match &s.terrain {
            Terrain::Flat { height_m } => self.check(height_m.is_finite(), &at("height_m"), || {
                "expected a finite height".into()
            }),
            Terrain::Slope {
                height_m,
                slope_x,
                slope_y,
            } => {
                let ok = [height_m, slope_x, slope_y]
                    .iter()
                    .all(|v| v.is_finite() && v.abs() < 100.0);
                self.check(ok, &at("slope_x"), || {
                    "expected finite height and slopes (rise per metre under 100)".into()
                })
            }
            Terrain::Noise {
                amplitude_m,
                wavelength_m,
                cell_m,
            } => {
                self.non_negative(*amplitude_m, &at("amplitude_m"), "amplitude in metres")?;
                self.positive(*wavelength_m, &at("wavelength_m"), "wavelength in metres")?;
                self.positive(*cell_m, &at("cell_m"), "cell size in metres")?;
                self.heightfield_size(s, *cell_m, &at("cell_m"))
            }
            Terrain::Image {
                path,
                height_scale_m,
                cell_m,
                origin_xy_m,
            } => {
                self.positive(*cell_m, &at("cell_m"), "pixel size in metres")?;
                self.check(height_scale_m.is_finite(), &at("height_scale_m"), || {
                    "expected a finite height".into()
                })?;
                if let Some(o) = origin_xy_m {
                    self.check(o.iter().all(|v| v.is_finite()), &at("origin_xy_m"), || {
                        "expected finite numbers".into()
                    })?;
                }
                let file = self.source.resolve(path);
                super::super::heightmap::read_greyscale_png(&file)
                    .map(|_| ())
                    .map_err(|e| self.error(&at("path"), e.to_string()))
            }
        }
    }

    fn heightfield_size(&self, s: &Scenario, cell_m: f64, path: &[KeySeg<'_>]) -> Result<()> {
        let n = ((s.map.max_xy_m[0] - s.map.min_xy_m[0]) / cell_m + 3.0)
            * ((s.map.max_xy_m[1] - s.map.min_xy_m[1]) / cell_m + 3.0);
        self.check(n <= MAX_MAP_CELLS as f64, path, || {
            format!(
                "the terrain would need {n:.0} heights, over the limit of {MAX_MAP_CELLS}; use a larger cell"
            )
        })
    }

    fn validate_obstacle(&self, s: &Scenario, k: usize, o: &Obstacle) -> Result<()> {
        use KeySeg::{Index as I, Key as K};
        let at = |key| [K("obstacles"), I(k), K(key)];
        self.inside(s, o.center_xy_m(), &at("center_xy_m"))?;
        match o {
            Obstacle::Box {
                size_m,
                yaw_deg,
                base_m,
                ..
            } => {
                for v in size_m {
                    self.length(*v, &at("size_m"), "size in metres")?;
                }
                self.check(yaw_deg.is_finite(), &at("yaw_deg"), || {
                    "expected a finite angle".into()
                })?;
                self.non_negative(*base_m, &at("base_m"), "height above the ground in metres")
            }
            Obstacle::Cylinder {
                radius_m,
                height_m,
                base_m,
                ..
            } => {
                self.length(*radius_m, &at("radius_m"), "radius in metres")?;
                self.length(*height_m, &at("height_m"), "height in metres")?;
                self.non_negative(*base_m, &at("base_m"), "height above the ground in metres")
            }
            Obstacle::Ramp {
                length_m,
                width_m,
                height_m,
                yaw_deg,
                ..
            } => {
                self.length(*length_m, &at("length_m"), "length in metres")?;
                self.length(*width_m, &at("width_m"), "width in metres")?;
                self.length(*height_m, &at("height_m"), "height in metres")?;
                self.check(yaw_deg.is_finite(), &at("yaw_deg"), || {
                    "expected a finite angle".into()
                })
            }
            Obstacle::Bush {
                radius_m,
                height_m,
                num_parts,
                ..
            } => {
                self.length(*radius_m, &at("radius_m"), "radius in metres")?;
                self.length(*height_m, &at("height_m"), "height in metres")?;
                self.check((1..=1000).contains(num_parts), &at("num_parts"), || {
                    format!("expected 1 to 1000 parts, got {num_parts}")
                })
            }
            Obstacle::Overhang {
                size_m,
                clearance_m,
                yaw_deg,
                ..
            } => {
                for v in size_m {
                    self.length(*v, &at("size_m"), "size in metres")?;
                }
                self.length(
                    *clearance_m,
                    &at("clearance_m"),
                    "gap under the overhang in metres",
                )?;
                self.check(yaw_deg.is_finite(), &at("yaw_deg"), || {
                    "expected a finite angle".into()
                })
            }
        }
    }
}
