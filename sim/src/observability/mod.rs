//! What the sensors could see: an observability truth, from the rays the simulated sensors cast and from
//! nothing the map computes. Per cell of the map region:
//!
//! * the **step** decision was observable when a ray truly ended on the cell (on its surface: the ground or a
//!   static obstacle, not a person standing there);
//! * the **clearance** decision: a ray crossed, or ended inside, the band over the cell between a step above
//!   the ground (`max_step_m`) and the robot's height, the band where a structure the robot cannot pass under
//!   would have to be ([`Observability::clearance`]). Over a cell that truly holds such a structure, only a
//!   ray that *ended* inside the band, on the structure ([`Observability::band_hit`]; a ray that met a person
//!   who walked under it tells nothing of the structure), can have told: a ray that crossed the band
//!   there without ending passed above or below the structure (between two lidar rings, say), and saw
//!   nothing of it.
//!
//! A truly blocked cell that the map calls drivable is then *unsafe* when a ray could have told, and *blind*
//! when none could: no map of these readings could have known (`oeg_eval::judge::verdict`).
//!
//! In scenes with people, over the cells they cover, it also keeps the heights at which rays met them and those
//! observed again after they left ([`SeenAgain`]): which ghosts a map of these readings could have cleared.
//!
//! [`blind_band`] answers the same question on the geometry alone: for each range from the robot, the largest
//! vertical gap between the sensors' rays within the robot's height band, on flat ground. A board thinner than
//! the gap at a range can hide in it.

use nalgebra::{Point3, Vector3};
use oeg::{CellIndex, GridWindow, RobotProfile};
use rayon::prelude::*;

use crate::sensors::SensorScan;
use crate::world::World;

mod blind_band;
mod seen_again;

pub use blind_band::{BlindBandRow, blind_band, ray_heights_at};

pub use seen_again::SeenAgain;
use seen_again::Sight;

/// The observability of every cell of a region: what the sensors' rays could have told, once a run's scans are
/// observed ([`Observer::finished`]), or so far ([`Observer::observed`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Observability {
    /// The cells, on the map's grid.
    pub window: GridWindow,
    /// Per cell: a ray truly ended on it, on the ground or a static obstacle (not a person).
    pub step: Vec<bool>,
    /// Per cell: a ray crossed or ended inside its band between a step and the robot's height.
    pub clearance: Vec<bool>,
    /// Per cell: a ray ended inside that band on the scene's own surfaces (a structure's underside or side;
    /// not a person).
    pub band_hit: Vec<bool>,
    /// Rays that told something (cast, and not a hole or a dropout).
    pub num_rays: u64,
    /// Per cell an actor covers, once asked for ([`Observer::tracking_actors`]): the heights at which rays met
    /// the actor over it, and those the sensors observed again after it left.
    seen_again: Option<SeenAgain>,
    profile: RobotProfile,
}

/// Observes a run's scans into an [`Observability`], reading the ground under every cell of its region.
#[derive(Debug, Clone)]
pub struct Observer {
    observed: Observability,
    /// Ground height at each cell's centre, metres (NaN off the terrain): 8 bytes a cell, which only
    /// observing needs.
    ground_m: Vec<f64>,
    ground_lo_m: f64,
    ground_hi_m: f64,
}

impl Observability {
    /// Per cell, whether the sensors observed again, after the last actor left it, every height at which a
    /// ray had met an actor over it (true for a cell no ray met an actor over); `None` unless asked for with
    /// [`Observer::tracking_actors`].
    pub fn seen_again(&self) -> Option<Vec<bool>> {
        self.seen_again.as_ref().map(SeenAgain::cells)
    }
}

impl Observer {
    /// Nothing observed yet over `window`; the ground is read from `world` under every cell's centre.
    pub fn new(world: &World, window: &GridWindow, profile: RobotProfile) -> Self {
        let geometry = window.geometry();
        let cells: Vec<CellIndex> = window.region().cells().collect();
        let ground_m: Vec<f64> = cells
            .par_iter()
            .map(|c| {
                let (x, y) = geometry.cell_center(*c);
                world.ground_z(x, y).unwrap_or(f64::NAN)
            })
            .collect();
        let finite = ground_m.iter().copied().filter(|g| g.is_finite());
        let (ground_lo_m, ground_hi_m) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), g| {
            (lo.min(g), hi.max(g))
        });
        Self {
            observed: Observability {
                window: *window,
                step: vec![false; cells.len()],
                clearance: vec![false; cells.len()],
                band_hit: vec![false; cells.len()],
                num_rays: 0,
                seen_again: None,
                profile,
            },
            ground_m,
            ground_lo_m,
            ground_hi_m,
        }
    }

    /// Also keeps, over the cells actors cover (`covered_until_s`: per cell of the window, the last time an
    /// actor covered it, -inf: never), the heights at which rays met an actor there and those observed again
    /// after it left ([`SeenAgain`]; 16 bytes a cell): what tells a ghost a map should have cleared from one
    /// no map of these readings could.
    ///
    /// # Panics
    /// If `covered_until_s` does not hold one time per cell of the window.
    #[must_use]
    pub fn tracking_actors(mut self, covered_until_s: Vec<f64>) -> Self {
        let o = &mut self.observed;
        assert_eq!(covered_until_s.len(), o.step.len(), "one time per cell");
        o.seen_again = Some(SeenAgain::new(covered_until_s, o.profile.height_m, &o.window));
        self
    }

    /// What the scans observed so far told.
    pub fn observed(&self) -> &Observability {
        &self.observed
    }

    /// What the scans observed told, without what only observing needs (the ground under every cell, 8 bytes a
    /// cell): for what reads it after the run (the judge, the figures).
    #[must_use]
    pub fn finished(self) -> Observability {
        self.observed
    }

    /// Records the rays of one scan of a sensor whose range ends at `max_range_m`.
    pub fn observe(&mut self, scan: &SensorScan, max_range_m: f64) {
        let origin = Point3::from(scan.world_from_sensor.translation.vector);
        let rotation = scan.world_from_sensor.rotation;
        let this = &*self;
        let (ground_m, observed) = (&self.ground_m, &self.observed);
        let (step, height) = (
            f64::from(observed.profile.max_step_m),
            f64::from(observed.profile.height_m),
        );
        let stamp_s = scan.stamp_s;
        let ((x0, y0), (w, h)) = (observed.window.min_corner_m(), observed.window.size_m());
        let region_m = ((x0, y0), (x0 + w, y0 + h));
        // The cells people covered are walked again from the ground up, once one of them has been left.
        let tracked_m = (observed.seen_again.as_ref())
            .filter(|s| s.may_see_again(stamp_s))
            .and_then(SeenAgain::rect_m);
        // Each ray lists the cells it makes observable; the lists are merged by OR, so the order of the
        // threads does not matter.
        let (steps, bands, sights) = scan
            .rays
            .par_iter()
            .filter(|r| !r.true_range_m.is_nan())
            .fold(
                || (Vec::new(), Vec::new(), Vec::new()),
                |(mut steps, mut bands, mut sights), r| {
                    let dir = rotation * r.vector_in_sensor.cast::<f64>().normalize();
                    let hit = r.true_range_m.is_finite();
                    let length = if hit {
                        f64::from(r.true_range_m)
                    } else {
                        max_range_m
                    };
                    let end = origin + dir * length;
                    if hit && let Some(k) = this.offset_at(&end) {
                        // On the cell, and whether inside its band: on the ground or a structure. A ray that
                        // ended on a person tells nothing of either (the board a person walks under, the
                        // curb a person stands on).
                        if !r.true_hit_actor {
                            steps.push((k, (step..=height).contains(&(end.z - ground_m[k]))));
                        }
                        if let Some(seen) = &observed.seen_again {
                            seen.ended(k, end.z - ground_m[k], stamp_s, &mut sights);
                        }
                    }
                    let ray = (&origin, &dir, length);
                    this.walk_band(ray, region_m, &mut bands);
                    if let Some((seen, rect_m)) = observed.seen_again.as_ref().zip(tracked_m) {
                        this.walk_tracked(seen, ray, rect_m, stamp_s, &mut sights);
                    }
                    (steps, bands, sights)
                },
            )
            .reduce(
                || (Vec::new(), Vec::new(), Vec::new()),
                |(mut a, mut b, mut c), (d, e, f)| {
                    a.extend(d);
                    b.extend(e);
                    c.extend(f);
                    (a, b, c)
                },
            );
        let observed = &mut self.observed;
        observed.num_rays += scan.rays.iter().filter(|r| !r.true_range_m.is_nan()).count() as u64;
        for (k, in_band) in steps {
            observed.step[k] = true;
            observed.band_hit[k] |= in_band;
        }
        for k in bands {
            observed.clearance[k] = true;
        }
        if let Some(seen) = &mut observed.seen_again {
            seen.record(sights);
        }
    }

    fn offset_at(&self, p: &Point3<f64>) -> Option<usize> {
        self.observed.window.offset_of(p.x, p.y)
    }

    /// The cells whose band the ray crosses within the rectangle `rect_m` (the region's).
    #[inline(never)]
    fn walk_band(&self, ray: Ray<'_>, rect_m: Rect, out: &mut Vec<usize>) {
        let profile = &self.observed.profile;
        let (step, height) = (f64::from(profile.max_step_m), f64::from(profile.height_m));
        self.walk_heights(ray, (step, height), rect_m, |k, za, zb| {
            let g = self.ground_m[k];
            if g.is_finite() && za.max(zb) >= g + step && za.min(zb) <= g + height {
                out.push(k);
            }
        });
    }

    /// What the ray says of the cells actors cover ([`SeenAgain::crossed`]), from their ground to the robot's
    /// height, within the rectangle `rect_m` that holds them all.
    #[inline(never)]
    fn walk_tracked(&self, seen: &SeenAgain, ray: Ray<'_>, rect_m: Rect, t_s: f64, out: &mut Vec<Sight>) {
        self.walk_heights(
            ray,
            (0.0, f64::from(self.observed.profile.height_m)),
            rect_m,
            |k, za, zb| {
                let g = self.ground_m[k];
                if g.is_finite() {
                    seen.crossed(k, (za - g, zb - g), t_s, out);
                }
            },
        );
    }

    /// Calls `f(k, z_enter, z_leave)` for each cell `k` of the region the ray from `origin` along the unit
    /// `dir` crosses within `length`, with the ray's heights where it enters and leaves the cell, over the part
    /// of the ray that can lie between `lo_m` and `hi_m` over some cell's ground and within the rectangle
    /// `rect_m` (its min and max corners, metres; the region's or a part of it).
    #[inline(always)]
    fn walk_heights(
        &self,
        (origin, dir, length): Ray<'_>,
        (lo_m, hi_m): (f64, f64),
        rect_m: Rect,
        mut f: impl FnMut(usize, f64, f64),
    ) {
        // The part of the ray within those heights over any cell's ground.
        let (z_lo, z_hi) = (self.ground_lo_m + lo_m, self.ground_hi_m + hi_m);
        let Some((mut t0, mut t1)) = slab(origin.z, dir.z, z_lo, z_hi, length) else {
            return;
        };
        // ... and within the rectangle.
        let ((x0, y0), (x1, y1)) = rect_m;
        for (o, d, a, b) in [(origin.x, dir.x, x0, x1), (origin.y, dir.y, y0, y1)] {
            match slab(o, d, a, b, length) {
                Some((s0, s1)) => (t0, t1) = (t0.max(s0), t1.min(s1)),
                None => return,
            }
        }
        if t0 >= t1 {
            return;
        }
        let window = &self.observed.window;
        let res = window.resolution_m();
        // Amanatides and Woo's traversal of the cells the segment's x-y shadow crosses.
        let at = |t: f64| (origin.x + dir.x * t, origin.y + dir.y * t);
        let (sx, sy) = at(t0);
        let Some(mut cell) = window.geometry().cell_of(sx, sy) else {
            return;
        };
        let axis = |d: f64, p: f64, index: i32| -> (i32, f64, f64) {
            if d.abs() < 1e-12 {
                return (0, f64::INFINITY, f64::INFINITY);
            }
            let boundary = if d > 0.0 {
                f64::from(index + 1) * res
            } else {
                f64::from(index) * res
            };
            (
                if d > 0.0 { 1 } else { -1 },
                t0 + (boundary - p) / d,
                res / d.abs(),
            )
        };
        let (step_i, mut next_x, dx) = axis(dir.x, sx, cell.i);
        let (step_j, mut next_y, dy) = axis(dir.y, sy, cell.j);
        let mut enter = t0;
        let max_cells = window.region().num_x as usize + window.region().num_y as usize + 2;
        for _ in 0..max_cells {
            let leave = next_x.min(next_y).min(t1);
            if let Some(k) = window.region().offset(cell) {
                f(k, origin.z + dir.z * enter, origin.z + dir.z * leave);
            }
            if leave >= t1 {
                break;
            }
            if next_x < next_y {
                cell.i += step_i;
                next_x += dx;
            } else {
                cell.j += step_j;
                next_y += dy;
            }
            enter = leave;
        }
    }
}

/// A ray: its origin, unit direction and length, metres.
type Ray<'a> = (&'a Point3<f64>, &'a Vector3<f64>, f64);

/// A rectangle of the ground plane: its min and max corners, metres.
type Rect = ((f64, f64), (f64, f64));

/// The interval of `t` in `[0, length]` over which `o + d t` lies within `[a, b]`.
fn slab(o: f64, d: f64, a: f64, b: f64, length: f64) -> Option<(f64, f64)> {
    if d.abs() < 1e-12 {
        return (a..=b).contains(&o).then_some((0.0, length));
    }
    let (ta, tb) = ((a - o) / d, (b - o) / d);
    let (lo, hi) = (ta.min(tb).max(0.0), ta.max(tb).min(length));
    (lo < hi).then_some((lo, hi))
}
