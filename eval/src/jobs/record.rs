//! `oeg record`: run a scenario's drive and sensors and write every scan to a log, an OctoMap scan graph, an
//! MCAP recording for Foxglove or a ROS 2 bag.

use std::path::{Path, PathBuf};
use std::time::Instant;

use nalgebra::{Isometry3, Vector3};
use sim::log::{LogHeader, LogSensor, LogStance, LogWriter};
use sim::sensors::{PoseSource, ReturnSource};
use sim::{Simulation, scenario};

use crate::error::{EvalError, Result};
use crate::progress::Progress;
use crate::recording::{DEFAULT_GRID_PERIOD_S, Recording};

/// The output format of `oeg record`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RecordFormat {
    /// The testbed's sensor log (`.oeglog`): both poses, hits and no-returns, range errors.
    Log,
    /// An OctoMap scan graph (`.graph`): one node per scan at the estimated pose, hits only.
    Graph,
    /// An MCAP recording (`.mcap`, `docs/mcap.md`): the true and estimated poses, each sensor's scans and
    /// the truth's grid; no map (`oeg run --mcap` adds the map's layers, the plans and the events).
    Mcap,
    /// A ROS 2 bag (a folder with an MCAP file and `metadata.yaml`): each sensor's scans as
    /// `sensor_msgs/PointCloud2` on `/<sensor>/points` in the sensor's frame, and the poses as `/tf`
    /// (`map` -> `odom`: the true pose's correction of the estimated one; `odom` -> `base_link`: the estimated
    /// pose) and `/tf_static` (`base_link` -> each sensor); at the end, the truth as `/truth/grid_map` and
    /// `/truth/occupancy`. Every ray is written: a hit as its end point, a ray that returned nothing as NaN
    /// coordinates (which other readers drop) with its cleared end in [`oeg::CLOUD_CLEAR_FIELDS`], and each
    /// reading's range error in [`oeg::CLOUD_RANGE_SIGMA_FIELD`].
    Rosbag2,
    /// The DynamicMap benchmark's unified format (a folder): `pcd/NNNNNN.pcd` a scan, its hits in the world
    /// frame at the estimated pose, `VIEWPOINT` the sensor's pose, and each point's label in `intensity` (1: the
    /// reading returned from a moving actor, 0: from the static scene); `gt_cloud.pcd`, every frame's points
    /// and labels in order, as the benchmark's evaluation reads them.
    DynamicMap,
}

/// What a recording produced.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordReport {
    /// The file written.
    pub path: PathBuf,
    /// Scans written.
    pub num_scans: u64,
    /// Rays simulated.
    pub num_rays: u64,
    /// No-return rays left out (the graph and DynamicMap formats, which hold hits only).
    pub num_rays_left_out: u64,
    /// Wall time of the simulation, seconds.
    pub wall_time_s: f64,
    /// Simulated rays per second of wall time.
    pub rays_per_s: f64,
}

/// The log header of a simulation.
pub fn log_header(loaded: &scenario::LoadedScenario, sim: &Simulation) -> LogHeader {
    LogHeader {
        scenario: loaded.scenario.name.clone(),
        seed: loaded.scenario.seed,
        duration_s: loaded.scenario.duration_s,
        sensors: sim
            .sensors()
            .iter()
            .map(|s| LogSensor {
                name: s.spec.name.clone(),
                kind: s.spec.kind.name().to_string(),
                preset: s.spec.preset.to_string(),
                rate_hz: s.spec.rate_hz,
                map_model: s.map_model(),
                ground_in_sensor_m: s.ground_in_sensor(sim.world()).map(|g| [g.x, g.y, g.z]),
            })
            .collect(),
        stance: log_stance(sim.world()),
    }
}

/// Where the robot stands at the start of the run, as the log records it.
fn log_stance(world: &sim::World) -> Option<LogStance> {
    let robot = world.robot();
    let contacts = robot.wheel_contacts();
    let footprint = robot.footprint();
    (!contacts.is_empty()).then(|| {
        LogStance::new(
            &contacts,
            footprint,
            &world.world_from_base(),
            &world.estimated_world_from_base(),
        )
    })
}

/// Records every scan of `sim` into an MCAP file at `out`, then the truth's grid over the scenario's map
/// region; returns the scans written.
fn record_mcap(
    loaded: &scenario::LoadedScenario,
    sim: &mut Simulation,
    header: &LogHeader,
    out: &Path,
    progress: &Progress,
) -> Result<u64> {
    let s = &loaded.scenario;
    let mut recording = Recording::new(loaded.window, DEFAULT_GRID_PERIOD_S)?;
    let mut num_scans = 0;
    while let Some(scan) = sim.next_scan() {
        let sensor = &header.sensors[scan.sensor_index];
        let placed = scan.to_scan(PoseSource::Estimated, sensor.map_model);
        recording.sensor_scan(sim.world(), &sensor.name, &placed, s.tick_s)?;
        num_scans += 1;
        progress.inc(1);
    }
    // The static world's truth, people left out, as a run's recording has it.
    recording.truth(&crate::pipeline::truth_of(loaded, sim.world(), progress)?)?;
    oeg_files::write_atomically(out, &recording.finish()?)?;
    Ok(num_scans)
}

/// Records every scan of `sim` into a ROS 2 bag folder at `out` ([`RecordFormat::Rosbag2`]); returns the scans
/// written.
fn record_rosbag2(
    loaded: &scenario::LoadedScenario,
    sim: &mut Simulation,
    header: &LogHeader,
    out: &Path,
    progress: &Progress,
) -> Result<u64> {
    let mut bag = oeg::BagWriter::new(out)?;
    // base_link -> each sensor, fixed on the robot (the URDF's fixed joints and the mount).
    let mounts: Vec<Isometry3<f64>> = sim
        .sensors()
        .iter()
        .map(|s| {
            let base_from_link = sim.world().robot().base_from_link(&s.spec.mount_link);
            base_from_link.unwrap_or_else(Isometry3::identity) * s.link_from_sensor
        })
        .collect();
    let transform = |parent: &str, child: &str, stamp_ns, transform| oeg::BagTransform {
        parent: parent.into(),
        child: child.into(),
        stamp_ns,
        transform,
    };
    let statics: Vec<oeg::BagTransform> = header
        .sensors
        .iter()
        .zip(&mounts)
        .map(|(s, m)| transform(BASE_FRAME, &s.name, 0, *m))
        .collect();
    bag.transforms("/tf_static", 0, &statics)?;
    let mut num_scans = 0;
    while let Some(scan) = sim.next_scan() {
        let sensor = &header.sensors[scan.sensor_index];
        let stamp_ns = (scan.stamp_s * 1e9).round() as i64;
        let base_from_sensor = mounts[scan.sensor_index].inverse();
        let estimated = scan.estimated_world_from_sensor * base_from_sensor;
        let truth = scan.world_from_sensor * base_from_sensor;
        let mut transforms = vec![
            transform("map", "odom", stamp_ns, truth * estimated.inverse()),
            transform("odom", BASE_FRAME, stamp_ns, estimated),
        ];
        // REP 120's frame on the ground under the robot: its origin the mean of the wheels' contacts, which the
        // run measures its height threshold from (`oeg::BagOptions::ground_frame` reads it back).
        if let Some(ground) = scan.ground_in_sensor {
            let ground_in_base = mounts[scan.sensor_index] * ground;
            transforms.push(transform(
                BASE_FRAME,
                oeg::DEFAULT_GROUND_FRAME,
                stamp_ns,
                Isometry3::translation(ground_in_base.x, ground_in_base.y, ground_in_base.z),
            ));
        }
        bag.transforms("/tf", stamp_ns, &transforms)?;
        let cloud = BagCloud::of(&scan, &sensor.map_model, &loaded.scenario.map.model);
        let topic = format!("/{}/points", sensor.name);
        bag.cloud_with_fields(
            &topic,
            &sensor.name,
            stamp_ns,
            (&cloud.points, oeg::CloudPrecision::Float32),
            &cloud.fields(),
        )?;
        num_scans += 1;
        progress.inc(1);
    }
    write_truth(
        &mut bag,
        &crate::pipeline::truth_of(loaded, sim.world(), progress)?,
        sim.world().time_s(),
    )?;
    bag.finish()?;
    Ok(num_scans)
}

/// One scan as a PointCloud2's columns, in the sensor's frame: each hit's end point and range error, and for a
/// ray that returned nothing, NaN coordinates and its cleared ray's end ([`oeg::CLOUD_CLEAR_FIELDS`]: its
/// direction times the sensor's range) with the range error the map gives it there under the scenario's model
/// ([`oeg::CLOUD_RANGE_SIGMA_FIELD`]), so that the bag maps as the run does.
struct BagCloud {
    points: Vec<Vector3<f64>>,
    range_sigma_m: Vec<f32>,
    clear: [Vec<f32>; 3],
}

impl BagCloud {
    fn of(scan: &sim::sensors::SensorScan, sensor: &oeg::SensorModel, model: &oeg::ModelOptions) -> Self {
        // Where the map ends a ray that returned nothing ([`oeg::ModelOptions::no_return_clear_range_m`]).
        let cleared_m = model
            .no_return_clear_range_m
            .unwrap_or(sensor.max_range_m)
            .min(model.max_range_m.unwrap_or(f32::INFINITY));
        let n = scan.rays.len();
        let mut cloud = Self {
            points: Vec::with_capacity(n),
            range_sigma_m: Vec::with_capacity(n),
            clear: std::array::from_fn(|_| Vec::with_capacity(n)),
        };
        for r in &scan.rays {
            let (point, sigma, clear) = if r.kind == oeg::RayKind::Hit {
                (
                    r.vector_in_sensor.cast(),
                    r.range_sigma_m,
                    Vector3::repeat(f32::NAN),
                )
            } else {
                let end = sim::sensors::SensorScan::cleared_in_sensor(r, sensor);
                (Vector3::repeat(f64::NAN), sensor.sigma_m(cleared_m), end)
            };
            cloud.points.push(point);
            cloud.range_sigma_m.push(sigma);
            for (axis, column) in cloud.clear.iter_mut().enumerate() {
                column.push(clear[axis]);
            }
        }
        cloud
    }

    /// The extra fields: the range errors, and the cleared rays' ends where the scan has any.
    fn fields(&self) -> Vec<(&'static str, &[f32])> {
        let mut fields = vec![(oeg::CLOUD_RANGE_SIGMA_FIELD, self.range_sigma_m.as_slice())];
        if self.points.iter().any(|p| p.x.is_nan()) {
            fields.extend(
                oeg::CLOUD_CLEAR_FIELDS
                    .into_iter()
                    .zip(self.clear.iter().map(Vec::as_slice)),
            );
        }
        fields
    }
}

/// The static world's truth (people left out, as a run's recording has it) at the end of a bag, in the `map`
/// frame: `/truth/grid_map` (a `grid_map_msgs/GridMap` of the layers `elevation`, NaN off the terrain, and
/// `traversability`, 1 drivable and 0 truly blocked) and `/truth/occupancy` (a `nav_msgs/OccupancyGrid`: 100
/// truly blocked, 0 drivable, -1 off the terrain). `oeg score --grid-map` scores the first as a perfect map.
fn write_truth(bag: &mut oeg::BagWriter, truth: &sim::truth::TruthRaster, time_s: f64) -> Result<()> {
    let region = truth.window.region();
    let (x, y) = truth.window.min_corner_m();
    let raster = oeg::BagRaster {
        frame: "map".into(),
        stamp_ns: (time_s * 1e9).round() as i64,
        origin_xy_m: [x, y],
        resolution_m: truth.window.resolution_m(),
        rows: region.num_y as usize,
        cols: region.num_x as usize,
    };
    let elevation: Vec<f32> = truth.cells.iter().map(|c| c.elevation_m).collect();
    let traversability: Vec<f32> = (0..truth.cells.len())
        .map(|k| if truth.truly_blocked(k) { 0.0 } else { 1.0 })
        .collect();
    bag.grid_map(
        "/truth/grid_map",
        &raster,
        &[("elevation", &elevation), ("traversability", &traversability)],
    )?;
    let occupancy: Vec<i8> = (0..truth.cells.len())
        .map(|k| match (elevation[k].is_nan(), truth.truly_blocked(k)) {
            (true, _) => -1,
            (false, true) => 100,
            (false, false) => 0,
        })
        .collect();
    bag.occupancy_grid("/truth/occupancy", &raster, &occupancy)?;
    Ok(())
}

/// Records every scan of `sim` into a DynamicMap sequence folder at `out` ([`RecordFormat::DynamicMap`]);
/// returns the scans written and the no-return rays left out.
fn record_dynamicmap(
    sim: &mut Simulation,
    header: &LogHeader,
    out: &Path,
    progress: &Progress,
) -> Result<(u64, u64)> {
    let frames = out.join("pcd");
    crate::output::create_dir(&frames)?;
    let (mut all_points, mut all_labels) = (Vec::new(), Vec::new());
    let (mut num_scans, mut left_out) = (0_u64, 0_u64);
    while let Some(scan) = sim.next_scan() {
        let placed = scan.to_scan(PoseSource::Estimated, header.sensors[scan.sensor_index].map_model);
        let origin = placed.origin_in_world;
        let (mut points, mut labels) = (Vec::new(), Vec::new());
        for (ray, source) in placed.rays.iter().zip(sim.last_scan_sources()) {
            if ray.kind == oeg::RayKind::Hit {
                points.push((origin + ray.offset_in_world.cast::<f64>()).cast::<f32>());
                labels.push(if *source == ReturnSource::Actor { 1.0 } else { 0.0 });
            }
        }
        left_out += (placed.rays.len() - points.len()) as u64;
        let cloud = oeg::PcdCloud {
            width: points.len() as u32,
            height: 1,
            viewpoint: scan.estimated_world_from_sensor,
            points,
        };
        let path = frames.join(format!("{num_scans:06}.pcd"));
        oeg::write_pcd_with_intensity(&path, &cloud, Some(&labels), oeg::PcdEncoding::Binary)?;
        all_points.extend(cloud.points);
        all_labels.extend(labels);
        num_scans += 1;
        progress.inc(1);
    }
    let gt = oeg::PcdCloud {
        width: all_points.len() as u32,
        height: 1,
        viewpoint: Isometry3::identity(),
        points: all_points,
    };
    oeg::write_pcd_with_intensity(
        &out.join("gt_cloud.pcd"),
        &gt,
        Some(&all_labels),
        oeg::PcdEncoding::Binary,
    )?;
    Ok((num_scans, left_out))
}

/// The robot's frame in a written bag (REP 105).
const BASE_FRAME: &str = "base_link";

/// Runs the scenario (its seed replaced by `seed` when given) and records every scan to `out`.
///
/// # Errors
/// A bad scenario, or a failed write (no partial file is left).
pub fn record(
    path: &Path,
    out: &Path,
    format: RecordFormat,
    seed: Option<u64>,
    progress: &Progress,
) -> Result<RecordReport> {
    // Refuse an output that is not a regular file (a bag: a folder) before simulating anything.
    if matches!(format, RecordFormat::Rosbag2 | RecordFormat::DynamicMap) {
        if out.exists() && !out.is_dir() {
            return Err(EvalError::Input {
                path: out.to_path_buf(),
                message: "a ROS 2 bag or a DynamicMap sequence is a folder, and this is a file".into(),
            });
        }
    } else {
        oeg_files::output_target(out)?;
    }
    let mut loaded = scenario::load(path)?;
    if let Some(seed) = seed {
        loaded.scenario.seed = seed;
    }
    if loaded.scenario.sensors.is_empty() {
        return Err(EvalError::Input {
            path: path.to_path_buf(),
            message: "the scenario has no sensors to record".into(),
        });
    }
    let mut sim = Simulation::new(&loaded)?;
    let header = log_header(&loaded, &sim);
    progress.set_length(sim.num_scans_total());
    let start = Instant::now();
    let (num_scans, num_rays_left_out) = match format {
        RecordFormat::Log => {
            let mut writer = LogWriter::create(out, &header)?;
            while let Some(scan) = sim.next_scan() {
                writer.push(&scan)?;
                progress.inc(1);
            }
            (writer.finish()?, 0)
        }
        RecordFormat::Graph => {
            let mut scans = Vec::new();
            while let Some(scan) = sim.next_scan() {
                scans.push(scan.to_scan(PoseSource::Estimated, header.sensors[scan.sensor_index].map_model));
                progress.inc(1);
            }
            let left_out = oeg::write_graph(out, &scans)?;
            (scans.len() as u64, left_out)
        }
        RecordFormat::Mcap => (record_mcap(&loaded, &mut sim, &header, out, progress)?, 0),
        RecordFormat::Rosbag2 => (record_rosbag2(&loaded, &mut sim, &header, out, progress)?, 0),
        RecordFormat::DynamicMap => record_dynamicmap(&mut sim, &header, out, progress)?,
    };
    progress.finish();
    let wall_time_s = start.elapsed().as_secs_f64();
    let num_rays = sim.num_rays();
    Ok(RecordReport {
        path: out.to_path_buf(),
        num_scans,
        num_rays,
        num_rays_left_out,
        wall_time_s,
        rays_per_s: if wall_time_s > 0.0 {
            num_rays as f64 / wall_time_s
        } else {
            0.0
        },
    })
}
