//! Simulated sensors: beam patterns, ray casts into the world, noise. Every beam of a scan is cast in parallel
//! (rayon) with its own random stream derived from (sensor, scan, beam), so results do not depend on the
//! number of threads.
//!
//! What each beam goes through, in order (each step off when its parameter is 0):
//! 1. angular jitter: the beam travels along a perturbed direction but is reported along its nominal one;
//! 2. camera holes and dropouts: no return;
//! 3. the ray cast (robot excluded, people included): nothing within range, or a hit closer than the minimum
//!    range, is a no-return reading, never a hit at maximum range;
//! 4. mixed pixels: at a depth edge (a neighbouring ray, one beam spacing away, differs by more than 0.1 m),
//!    the range is drawn uniformly between the two surfaces;
//! 5. spurious returns: a false hit at a uniformly random range between the minimum range and the true one;
//! 6. range noise: bias (drawn once per sensor) plus Gaussian noise of the kind's model; cameras' depth noise
//!    is along the optical axis (converted to range).
//!
//! Cameras report only their valid pixels (holes, dropouts and pixels without a surface in range are left
//! out, like NaN pixels of a depth image); lasers report their no-return beams.
//!
//! Each hit carries the range error its model gives at the measured range (bias excluded: it is systematic),
//! so the map's elevation variance matches the noise actually applied.

use nalgebra::{Isometry3, Point3, Translation3, Vector3};
use oeg::{Ray, RayKind, Scan};
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, Normal, StandardNormal};
use rayon::prelude::*;

use crate::scenario::sensors::{BeamPattern, RangeNoise, SensorKind, SensorSpec};

use crate::robot::rotation_from_rpy;
use crate::seed::{self, Stream};
use crate::world::{Actors, HitKind, RayStart, World};

/// Range difference beyond which two neighbouring beams see a depth edge, metres.
pub const DEPTH_EDGE_M: f64 = 0.1;

/// One reading of a scan, in the sensor frame.
#[derive(Debug, Clone, Copy)]
pub struct SensorRay {
    /// Hit or no return.
    pub kind: RayKind,
    /// Hit: the measured end point in the sensor frame, metres; no return: the unit direction.
    pub vector_in_sensor: Vector3<f32>,
    /// The range error of the sensor model at the measured range, metres (0 for no returns).
    pub range_sigma_m: f32,
    /// How far the beam truly went along its nominal direction before it hit something, metres, noise-free:
    /// infinite when it hit nothing within range, NaN when it told nothing (a hole, a dropout, a hit outside
    /// the sensor's range) or the scan was read from a log. The observability truth reads it.
    pub true_range_m: f32,
    /// Whether that noise-free hit was on a moving actor (a person) rather than the ground or a static
    /// obstacle: such a ray tells nothing of the scene's own surfaces (the observability truth).
    pub true_hit_actor: bool,
}

impl PartialEq for SensorRay {
    /// Field by field, with the true range compared bit for bit: a ray that told nothing (NaN) equals itself.
    fn eq(&self, other: &Self) -> bool {
        self.kind == other.kind
            && self.vector_in_sensor == other.vector_in_sensor
            && self.range_sigma_m == other.range_sigma_m
            && self.true_range_m.to_bits() == other.true_range_m.to_bits()
            && self.true_hit_actor == other.true_hit_actor
    }
}

/// How many readings each obstacle returned over a run: whether the sensors saw it at all. An obstacle with none
/// is invisible to the sensor set (between a lidar's beams, above or below every beam), and no map of those
/// readings can hold it.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ObstacleReturns {
    counts: Vec<u64>,
}

impl ObstacleReturns {
    /// Counts for `num_obstacles` obstacles, all zero.
    pub fn new(num_obstacles: usize) -> Self {
        Self {
            counts: vec![0; num_obstacles],
        }
    }

    fn add(&mut self, index: usize) {
        if let Some(c) = self.counts.get_mut(index) {
            *c += 1;
        }
    }

    /// Readings returned by obstacle `index` (0 for an index beyond the scenario's obstacles).
    pub fn of(&self, index: usize) -> u64 {
        self.counts.get(index).copied().unwrap_or(0)
    }
}

/// Which pose a scan is placed with in the world: `"estimated"` or `"true"`. The bare `true` of a TOML file or
/// of `--set input.log_pose=true` reads as `"true"` (and `false` as `"estimated"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "snake_case", try_from = "PoseSourceText")]
pub enum PoseSource {
    /// The estimated pose (odometry drift included): what a robot's mapper gets.
    #[default]
    Estimated,
    /// The true pose.
    True,
}

/// How a [`PoseSource`] may be written.
#[derive(serde::Deserialize)]
#[serde(untagged)]
enum PoseSourceText {
    Word(String),
    Flag(bool),
}

impl TryFrom<PoseSourceText> for PoseSource {
    type Error = String;

    fn try_from(text: PoseSourceText) -> Result<Self, String> {
        match text {
            PoseSourceText::Word(w) if w == "estimated" => Ok(Self::Estimated),
            PoseSourceText::Word(w) if w == "true" => Ok(Self::True),
            PoseSourceText::Flag(true) => Ok(Self::True),
            PoseSourceText::Flag(false) => Ok(Self::Estimated),
            PoseSourceText::Word(w) => Err(format!("unknown variant `{w}`, expected `estimated` or `true`")),
        }
    }
}

/// One scan of one sensor.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorScan {
    /// Index of the sensor in the scenario.
    pub sensor_index: usize,
    /// Scans of this sensor before this one.
    pub scan_index: u64,
    /// Simulated time, seconds.
    pub stamp_s: f64,
    /// True `world_from_sensor`.
    pub world_from_sensor: Isometry3<f64>,
    /// Estimated `world_from_sensor`.
    pub estimated_world_from_sensor: Isometry3<f64>,
    /// The ground under the robot in the sensor's frame ([`crate::World::ground_in_link`]), which places
    /// the map's height threshold ([`oeg::Scan::ground_z_m`]); `None` for a robot without wheels.
    pub ground_in_sensor: Option<Point3<f64>>,
    /// The readings.
    pub rays: Vec<SensorRay>,
}

impl SensorScan {
    /// The scan as the map's input, placed with `pose`; rays keep their range errors.
    pub fn to_scan(&self, pose: PoseSource, sensor: oeg::SensorModel) -> Scan {
        let world_from_sensor = match pose {
            PoseSource::Estimated => self.estimated_world_from_sensor,
            PoseSource::True => self.world_from_sensor,
        };
        let rotation = world_from_sensor.rotation;
        let mut scan = Scan::new(Point3::from(world_from_sensor.translation.vector), sensor);
        scan.stamp_s = self.stamp_s;
        scan.ground_z_m = self.ground_in_sensor.map(|g| (world_from_sensor * g).z);
        // Rotated in float64 and stored in float32, as a bag's reader places a cloud's float32 points; a ray
        // that returned nothing reaches the sensor's range ([`SensorScan::cleared_in_sensor`]).
        scan.rays.extend(self.rays.iter().map(|r| Ray {
            kind: r.kind,
            offset_in_world: (rotation * Self::cleared_in_sensor(r, &sensor).cast::<f64>()).cast::<f32>(),
            range_sigma_m: (r.kind == RayKind::Hit).then_some(r.range_sigma_m),
        }));
        scan
    }

    /// A reading's vector in the sensor's frame: a hit's, or for a ray that returned nothing, its direction
    /// times the range of `sensor` (the map's model of the sensor), the segment it clears.
    pub fn cleared_in_sensor(ray: &SensorRay, sensor: &oeg::SensorModel) -> Vector3<f32> {
        if ray.kind == RayKind::Hit {
            ray.vector_in_sensor
        } else {
            ray.vector_in_sensor * sensor.max_range_m
        }
    }

    /// Number of hits.
    pub fn num_hits(&self) -> usize {
        self.rays.iter().filter(|r| r.kind == RayKind::Hit).count()
    }
}

/// A sensor in the simulation.
#[derive(Debug, Clone)]
pub struct SimSensor {
    /// Its resolved settings.
    pub spec: SensorSpec,
    /// `link_from_sensor`.
    pub link_from_sensor: Isometry3<f64>,
    /// Beam directions in the sensor frame (unit).
    directions: Vec<Vector3<f64>>,
    /// Two unit vectors perpendicular to each direction, for jitter and mixed-pixel neighbours.
    perpendiculars: Vec<(Vector3<f64>, Vector3<f64>)>,
    /// Angle to the neighbouring beam, radians.
    spacing_rad: f64,
    bias_m: f64,
    stream_seed: u64,
    num_scans: u64,
}

impl SimSensor {
    /// A sensor from its spec; `seed` is the scenario's.
    pub fn new(spec: SensorSpec, seed: u64) -> Self {
        let directions = beam_directions(&spec.beams);
        let perpendiculars = directions
            .iter()
            .map(|d| {
                let helper = if d.z.abs() < 0.9 {
                    Vector3::z()
                } else {
                    Vector3::x()
                };
                let e1 = d.cross(&helper).normalize();
                (e1, d.cross(&e1))
            })
            .collect();
        let spacing_rad = match &spec.beams {
            BeamPattern::Fan { step_rad, .. } | BeamPattern::Sweep { step_rad, .. } => *step_rad,
            BeamPattern::Pinhole { focal_px, stride, .. } => f64::from(*stride) / focal_px,
        };
        let mut stream = seed::stream(seed, &format!("sensor/{}", spec.name));
        let bias_m = if spec.noise.bias_sigma_m > 0.0 {
            Normal::new(0.0, spec.noise.bias_sigma_m).map_or(0.0, |n| n.sample(&mut stream))
        } else {
            0.0
        };
        let stream_seed: u64 = stream.random();
        let link_from_sensor = Isometry3::from_parts(
            Translation3::new(spec.xyz_m[0], spec.xyz_m[1], spec.xyz_m[2]),
            rotation_from_rpy(spec.rpy_rad),
        );
        Self {
            spec,
            link_from_sensor,
            directions,
            perpendiculars,
            spacing_rad,
            bias_m,
            stream_seed,
            num_scans: 0,
        }
    }

    /// Beam directions in the sensor frame.
    pub fn directions(&self) -> &[Vector3<f64>] {
        &self.directions
    }

    /// The range bias drawn for this sensor, metres.
    pub fn bias_m(&self) -> f64 {
        self.bias_m
    }

    /// The ground under the robot in this sensor's frame ([`crate::World::ground_in_link`]).
    pub fn ground_in_sensor(&self, world: &World) -> Option<Point3<f64>> {
        world
            .ground_in_link(&self.spec.mount_link)
            .map(|g| self.link_from_sensor.inverse_transform_point(&g))
    }

    /// What the map should assume about this sensor when a ray carries no error of its own.
    pub fn map_model(&self) -> oeg::SensorModel {
        let noise = match self.spec.noise.range {
            RangeNoise::Linear { sigma_m, per_m } => oeg::RangeNoiseModel::Laser {
                sigma_m: sigma_m as f32,
                sigma_per_m: per_m as f32,
            },
            RangeNoise::Disparity { coefficient_per_m } => oeg::RangeNoiseModel::Stereo {
                coefficient_per_m: coefficient_per_m as f32,
            },
            // The axial model is close to 0.0019 z^2 beyond a metre.
            RangeNoise::Axial { scale } => oeg::RangeNoiseModel::Stereo {
                coefficient_per_m: (0.0019 * scale) as f32,
            },
        };
        oeg::SensorModel {
            noise,
            max_range_m: self.spec.max_range_m as f32,
        }
    }

    /// Takes one scan of the world at its current time into `rays` (reused between scans). `returns` gets one
    /// more for each reading that is an obstacle's own return (index in the scenario's `obstacles`, not a
    /// spurious one), `sources` is scratch reused between scans.
    pub fn capture(
        &mut self,
        world: &World,
        sensor_index: usize,
        rays: &mut Vec<SensorRay>,
        sources: &mut Vec<ReturnSource>,
        returns: &mut ObstacleReturns,
    ) -> Option<SensorScan> {
        let world_from_link = world.world_from_link(&self.spec.mount_link)?;
        let estimated = world.estimated_world_from_link(&self.spec.mount_link)?;
        let world_from_sensor = world_from_link * self.link_from_sensor;
        let scan_index = self.num_scans;
        self.num_scans += 1;
        let this = &*self;
        let origin = Point3::from(world_from_sensor.translation.vector);
        let rotation = world_from_sensor.rotation;
        (0..this.directions.len())
            .into_par_iter()
            .map(|k| this.beam(world, &origin, &rotation, scan_index, k))
            .unzip_into_vecs(rays, sources);
        for source in sources.iter() {
            if let ReturnSource::Obstacle(index) = source {
                returns.add(*index as usize);
            }
        }
        if matches!(self.spec.kind, SensorKind::Stereo | SensorKind::DepthCamera) {
            // A camera pixel without depth is an invalid measurement, not a ray that saw nothing up to its
            // range (a laser's no return): it is left out, as depth images mark it NaN. Its source goes with it.
            let mut kept = rays.iter().map(|r| r.kind == RayKind::Hit);
            sources.retain(|_| kept.next().unwrap_or(false));
            rays.retain(|r| r.kind == RayKind::Hit);
        }
        Some(SensorScan {
            sensor_index,
            scan_index,
            stamp_s: world.time_s(),
            world_from_sensor,
            estimated_world_from_sensor: estimated * self.link_from_sensor,
            ground_in_sensor: self.ground_in_sensor(world),
            rays: rays.clone(),
        })
    }

    /// One beam's reading, and the obstacle whose return it is (`None`: terrain, a person, no return or a
    /// spurious return).
    fn beam(
        &self,
        world: &World,
        origin: &Point3<f64>,
        rotation: &nalgebra::UnitQuaternion<f64>,
        scan_index: u64,
        k: usize,
    ) -> (SensorRay, ReturnSource) {
        let noise = &self.spec.noise;
        let nominal = self.directions[k];
        let no_return = SensorRay {
            kind: RayKind::NoReturn,
            vector_in_sensor: nominal.cast(),
            range_sigma_m: 0.0,
            true_range_m: f32::NAN,
            true_hit_actor: false,
        };
        // A stream per beam: the same numbers whatever thread casts it.
        let mut rng = Stream::seed_from_u64(
            self.stream_seed
                ^ scan_index.wrapping_mul(0x9e37_79b9_7f4a_7c15)
                ^ (k as u64).wrapping_mul(0xc2b2_ae3d_27d4_eb4f),
        );
        let (e1, e2) = self.perpendiculars[k];
        let mut travelled = nominal;
        if noise.angular_jitter_rad > 0.0 {
            let (a, b): (f64, f64) = (rng.sample(StandardNormal), rng.sample(StandardNormal));
            travelled = (nominal + (e1 * a + e2 * b) * noise.angular_jitter_rad).normalize();
        }
        if noise.hole_probability > 0.0 && rng.random::<f64>() < noise.hole_probability {
            return (no_return, ReturnSource::None);
        }
        if noise.dropout_probability > 0.0 && rng.random::<f64>() < noise.dropout_probability {
            return (no_return, ReturnSource::None);
        }
        let cast = |d: &Vector3<f64>| {
            world.cast_ray(
                origin,
                &(rotation * d),
                self.spec.max_range_m,
                Actors::Included,
                RayStart::InsideExits,
            )
        };
        let Some(hit) = cast(&travelled) else {
            let nothing = SensorRay {
                true_range_m: f32::INFINITY,
                ..no_return
            };
            return (nothing, ReturnSource::None);
        };
        let mut range = hit.distance_m;
        if range < self.spec.min_range_m {
            return (no_return, ReturnSource::None);
        }
        if noise.mixed_pixel_probability > 0.0 && rng.random::<f64>() < noise.mixed_pixel_probability {
            let neighbour = (travelled + e1 * self.spacing_rad).normalize();
            let other = cast(&neighbour).map_or(self.spec.max_range_m, |h| h.distance_m);
            if (other - range).abs() > DEPTH_EDGE_M {
                range = rng.random_range(range.min(other)..range.max(other));
            }
        }
        let mut source = match hit.kind {
            HitKind::Obstacle { index } => {
                u32::try_from(index).map_or(ReturnSource::None, ReturnSource::Obstacle)
            }
            HitKind::Actor { .. } => ReturnSource::Actor,
            HitKind::Terrain => ReturnSource::Terrain,
        };
        if noise.spurious_probability > 0.0 && rng.random::<f64>() < noise.spurious_probability {
            range = rng.random_range(self.spec.min_range_m..range.max(self.spec.min_range_m + 1e-6));
            source = ReturnSource::None;
        }
        let forward = nominal.x.max(1e-6);
        let sigma = noise.range_sigma_m(range, forward);
        let mut measured = range + self.bias_m;
        if sigma > 0.0 {
            let z: f64 = rng.sample(StandardNormal);
            measured += sigma * z;
        }
        if measured <= self.spec.min_range_m || measured > self.spec.max_range_m {
            return (no_return, ReturnSource::None);
        }
        let sigma_at_measured = noise.range_sigma_m(measured, forward);
        (
            SensorRay {
                kind: RayKind::Hit,
                vector_in_sensor: (nominal * measured).cast(),
                range_sigma_m: sigma_at_measured as f32,
                true_range_m: hit.distance_m as f32,
                true_hit_actor: matches!(hit.kind, HitKind::Actor { .. }),
            },
            source,
        )
    }
}

/// What a scan's reading returned from: the scene's own surfaces, a moving actor, or nothing (a no-return, a
/// hole, a dropout, a reading out of range, a spurious return).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReturnSource {
    /// No surface: the reading is not a return of the scene.
    None,
    /// The ground.
    Terrain,
    /// Static obstacle number `index` of the scenario.
    Obstacle(u32),
    /// A moving actor (a person).
    Actor,
}

/// The unit beam directions of a pattern, in the sensor frame (x forward, y left, z up).
pub fn beam_directions(pattern: &BeamPattern) -> Vec<Vector3<f64>> {
    match pattern {
        BeamPattern::Fan { fov_rad, step_rad } => {
            let n = pattern.num_azimuths();
            (0..n)
                .map(|k| {
                    let a = -fov_rad / 2.0 + k as f64 * step_rad;
                    Vector3::new(a.cos(), a.sin(), 0.0)
                })
                .collect()
        }
        BeamPattern::Sweep {
            elevations_rad,
            fov_rad,
            step_rad,
        } => {
            let n = pattern.num_azimuths();
            let start = if pattern.is_full_circle() {
                0.0
            } else {
                -fov_rad / 2.0
            };
            let mut out = Vec::with_capacity(n * elevations_rad.len());
            for k in 0..n {
                let a = start + k as f64 * step_rad;
                for e in elevations_rad {
                    out.push(Vector3::new(e.cos() * a.cos(), e.cos() * a.sin(), e.sin()));
                }
            }
            out
        }
        BeamPattern::Pinhole {
            width_px,
            height_px,
            focal_px,
            stride,
        } => {
            // Through pixel centres: pixel (u, v) spans [u, u + 1), its centre u + 0.5; the principal point is
            // the image centre. Optical (right, down, forward) -> sensor (forward, left, up).
            let (w, h) = (f64::from(*width_px), f64::from(*height_px));
            let mut out = Vec::new();
            for v in (0..*height_px).step_by(*stride as usize) {
                for u in (0..*width_px).step_by(*stride as usize) {
                    let x = (f64::from(u) + 0.5 - w / 2.0) / focal_px;
                    let y = (f64::from(v) + 0.5 - h / 2.0) / focal_px;
                    out.push(Vector3::new(1.0, -x, -y).normalize());
                }
            }
            out
        }
    }
}
