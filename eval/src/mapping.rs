//! A simulation feeding its scans into the maps: one map per model, every scan at the estimated pose. The
//! scripted drive takes all the scans at once ([`crate::pipeline::simulate_and_map`]), a closed loop one
//! control step at a time ([`crate::navigation`]).

use std::time::Instant;

use oeg::{Map, MapConfig};
use sim::Simulation;
use sim::scenario;
use sim::sensors::PoseSource;

use sim::observability::{BlindBandRow, Observer, blind_band};

use crate::error::Result;
use crate::progress::Progress;

/// Wall times of a simulation shared by several maps.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SimulatedTiming {
    /// Simulating the drive and the sensors, seconds.
    pub simulation_wall_time_s: f64,
    /// Integrating the scans, seconds, summed over the maps.
    pub map_wall_time_s: f64,
    /// Rays simulated.
    pub num_rays: u64,
}

/// A simulation feeding its scans, at the estimated pose, into one map per model.
#[derive(Debug)]
pub struct Mapping {
    /// The simulation, at the time of its last scan.
    pub simulation: Simulation,
    /// One map per model, the first the run's own.
    pub maps: Vec<Map>,
    /// Which maps take the robot's stance as the ground under it ([`oeg::TraversabilityRule::needs_stance`]):
    /// at the start, and after every batch of scans ([`Map::integrate_footprint`]).
    take_stance: Vec<bool>,
    /// The space the robot's body fills over its footprint (`None`: a robot without wheels or body).
    body: Option<oeg::BodySpan>,
    models: Vec<oeg::SensorModel>,
    simulation_s: f64,
    map_s: Vec<f64>,
    last_tick: i64,
    /// Whether progress counts simulated seconds rather than scans (a closed loop, whose end is its goal).
    pub count_simulated_time: bool,
    tick_s: f64,
    duration_s: f64,
    /// What the rays could have told, over the map region on the first map's grid.
    pub observability: Observer,
    /// The sensors' blind band at the start, on flat ground (`blind_band.csv`).
    pub blind_band: Vec<BlindBandRow>,
    max_range_m: Vec<f64>,
    /// The recording the scans, poses and the first map's layers go into, when the run records one.
    recording: Option<Recorded>,
}

/// A recording with what it needs to draw the first map's decisions.
#[derive(Debug)]
struct Recorded {
    recording: crate::recording::Recording,
    sensors: Vec<String>,
    profile: oeg::RobotProfile,
    rule: oeg::TraversabilityRule,
}

/// Ranges of the blind band, metres: every half metre.
pub(crate) const BLIND_BAND_STEP_M: f64 = 0.5;
/// The farthest range of the blind band, metres (or the sensors' longest range, if shorter).
pub(crate) const BLIND_BAND_MAX_M: f64 = 20.0;

impl Mapping {
    /// A simulation at time 0 and empty maps, one per entry of `maps` (the map settings of runs that share
    /// this simulation: they differ only in the map's model, resolution or rule).
    ///
    /// # Errors
    /// A world or map that cannot be built.
    pub fn new(loaded: &scenario::LoadedScenario, maps: &[&scenario::MapSettings]) -> Result<Self> {
        let simulation = Simulation::new(loaded)?;
        // The ground the robot stands on at the start, for the rules whose frontier needs it.
        let stance = simulation.world().estimated_stance();
        let take_stance: Vec<bool> = maps.iter().map(|m| m.traversability.needs_stance()).collect();
        let body = simulation.world().robot().body_span();
        let maps = maps
            .iter()
            .map(|m| {
                let mut map = Map::new(MapConfig {
                    resolution_m: m.resolution_m,
                    model: m.model,
                    memory_limit_bytes: oeg::DEFAULT_MEMORY_LIMIT_BYTES,
                })?;
                if let Some(s) = stance.as_ref().filter(|_| m.traversability.needs_stance()) {
                    map.integrate_stance(s)?;
                }
                Ok(map)
            })
            .collect::<std::result::Result<Vec<_>, oeg::Error>>()?;
        let models = simulation.sensors().iter().map(|x| x.map_model()).collect();
        let s = &loaded.scenario;
        // What the sensors could see, on the scenario's own window (the first map's: the others share the
        // simulation and differ in their model, or in a sweep's resolution, where the judge leaves it out).
        let mut observability = Observer::new(simulation.world(), &loaded.window, s.robot.profile());
        if !s.actors.is_empty() {
            // DA counts only the cells whose ghosts the sensors could have cleared (`judge::ghosts`).
            let (covered_until_s, _) =
                crate::judge::ghosts::actor_cells(&s.actors, s.duration_s, &loaded.window);
            observability = observability.tracking_actors(covered_until_s);
        }
        let max_range_m: Vec<f64> = simulation.sensors().iter().map(|x| x.spec.max_range_m).collect();
        let blind_band = blind_band(
            simulation.sensors(),
            simulation.world(),
            &s.robot.profile(),
            BLIND_BAND_STEP_M,
            max_range_m
                .iter()
                .copied()
                .fold(0.0, f64::max)
                .min(BLIND_BAND_MAX_M),
        );
        Ok(Self {
            observability,
            blind_band,
            max_range_m,
            map_s: vec![0.0; maps.len()],
            simulation,
            maps,
            take_stance,
            body,
            models,
            simulation_s: 0.0,
            last_tick: -1,
            count_simulated_time: false,
            tick_s: loaded.scenario.tick_s,
            duration_s: loaded.scenario.duration_s,
            recording: None,
        })
    }

    /// Records every scan from now on into `recording`: the robot's poses once a tick, each scan's returns
    /// where the map places them, and the first map's layers (its decisions for `profile` under `rule`) at
    /// the recording's rate.
    pub fn record(
        &mut self,
        recording: crate::recording::Recording,
        profile: oeg::RobotProfile,
        rule: oeg::TraversabilityRule,
    ) {
        let sensors = self
            .simulation
            .sensors()
            .iter()
            .map(|x| x.spec.name.clone())
            .collect();
        self.recording = Some(Recorded {
            recording,
            sensors,
            profile,
            rule,
        });
    }

    /// The recording, with the first map's layers at the end of what was fed; `None` when not recording.
    ///
    /// # Errors
    /// A layer that cannot be written.
    pub fn take_recording(&mut self) -> Result<Option<crate::recording::Recording>> {
        let Some(mut r) = self.recording.take() else {
            return Ok(None);
        };
        if let Some(map) = self.maps.first() {
            let t = self.simulation.world().time_s();
            r.recording.map_layers(t, map, &r.profile, r.rule, true)?;
        }
        Ok(Some(r.recording))
    }

    /// Takes every scan up to `until_s` (and the end of the run) and integrates it into every map.
    ///
    /// # Errors
    /// A scan a map rejects, or `progress` cancelled.
    pub fn feed_until(&mut self, until_s: f64, progress: &Progress) -> Result<()> {
        if self.recording.is_some() {
            return self.feed_recording_until(until_s, progress);
        }
        // The next batch of scans is simulated while the last is mapped: within a feed, the maps do not steer
        // the simulation, and each side keeps its own order, so the results do not depend on it. Batches let
        // the maps gather short scans side by side (`Map::integrate_batch`) and the threads meet seldom.
        let mut batch = self.simulate_batch(until_s);
        while !batch.0.is_empty() {
            progress.check_cancelled()?;
            let last_stamp_s = batch.0.last().map_or(0.0, |scan| scan.stamp_s);
            let num_scans = batch.0.len() as u64;
            let Self {
                observability,
                maps,
                take_stance,
                body,
                map_s,
                models,
                max_range_m,
                simulation,
                simulation_s,
                ..
            } = self;
            let (scans, stance) = batch;
            let (simulated, mapped) = rayon::join(
                || simulate_batch(simulation, simulation_s, until_s),
                || {
                    map_batch(observability, maps, map_s, models, max_range_m, scans)?;
                    let stance = stance.as_ref().zip(*body);
                    lay_footprints(maps, take_stance, map_s, stance)
                },
            );
            mapped?;
            batch = simulated;
            self.report_progress(last_stamp_s, num_scans, progress);
        }
        Ok(())
    }

    /// [`Mapping::feed_until`] while recording: simulating and mapping take turns, scan by scan, since a
    /// recording reads the world as it was at the scan.
    /// The robot's stance is taken where [`Mapping::feed_until`] takes it, after every [`SCANS_PER_BATCH`] scans
    /// and after the last, so that a recorded run maps as an unrecorded one.
    fn feed_recording_until(&mut self, until_s: f64, progress: &Progress) -> Result<()> {
        let mut since_stance = 0;
        while let Some(scan) = self.simulate_next(until_s) {
            progress.check_cancelled()?;
            let (stamp_s, sensor_index) = (scan.stamp_s, scan.sensor_index);
            let scan = self.map_scan(scan)?;
            since_stance += 1;
            if since_stance == SCANS_PER_BATCH {
                self.lay_footprint()?;
                since_stance = 0;
            }
            if let Some(r) = &mut self.recording {
                let name = r.sensors.get(sensor_index).map_or("sensor", String::as_str);
                r.recording
                    .sensor_scan(self.simulation.world(), name, &scan, self.tick_s)?;
                if let Some(map) = self.maps.first() {
                    r.recording.map_layers(stamp_s, map, &r.profile, r.rule, false)?;
                }
            }
            self.report_progress(stamp_s, 1, progress);
        }
        if since_stance > 0 {
            self.lay_footprint()?;
        }
        Ok(())
    }

    /// The robot's stance now into the maps that take it ([`lay_footprints`]).
    fn lay_footprint(&mut self) -> Result<()> {
        let stance = self.simulation.world().estimated_stance();
        let stance = stance.as_ref().zip(self.body);
        lay_footprints(&mut self.maps, &self.take_stance, &mut self.map_s, stance)
    }

    /// Moves the progress bar past `num_scans` scans, the last at `stamp_s`: its line is refreshed once per
    /// simulation tick (`tick_s`).
    fn report_progress(&mut self, stamp_s: f64, num_scans: u64, progress: &Progress) {
        if self.count_simulated_time {
            progress.set_position(stamp_s.max(0.0) as u64);
        } else {
            progress.inc(num_scans);
        }
        let tick = (stamp_s / self.tick_s).floor() as i64;
        if tick != self.last_tick {
            self.last_tick = tick;
            progress.message(format!(
                "t = {:.1} / {:.0} s, {:.2} M rays/s",
                stamp_s,
                self.duration_s,
                self.simulation.num_rays() as f64 / self.simulation_s.max(1e-9) / 1e6
            ));
        }
    }

    /// The simulation's next batch of scans up to `until_s`, timed, and where the robot stands after it.
    fn simulate_batch(&mut self, until_s: f64) -> (Vec<sim::sensors::SensorScan>, Option<oeg::Stance>) {
        simulate_batch(&mut self.simulation, &mut self.simulation_s, until_s)
    }

    /// [`map_scan`] of this mapping's maps and observability.
    fn map_scan(&mut self, scan: sim::sensors::SensorScan) -> Result<oeg::Scan> {
        map_scan(
            &mut self.observability,
            &mut self.maps,
            &mut self.map_s,
            &self.models,
            &self.max_range_m,
            scan,
        )
    }

    /// The simulation's next scan up to `until_s`, timed.
    fn simulate_next(&mut self, until_s: f64) -> Option<sim::sensors::SensorScan> {
        let t0 = Instant::now();
        let scan = self.simulation.next_scan_until(until_s);
        self.simulation_s += t0.elapsed().as_secs_f64();
        scan
    }

    /// The wall times so far.
    pub fn timing(&self) -> SimulatedTiming {
        SimulatedTiming {
            simulation_wall_time_s: self.simulation_s,
            map_wall_time_s: self.map_s.iter().sum(),
            num_rays: self.simulation.num_rays(),
        }
    }
}

/// Scans simulated, then mapped, together ([`Mapping::feed_until`]): a fraction of a second of the drive.
const SCANS_PER_BATCH: usize = 32;

/// The simulation's next scans up to `until_s`, at most [`SCANS_PER_BATCH`], the time added to `simulation_s`,
/// and where the robot stands (as odometry believes) at the last of them.
fn simulate_batch(
    simulation: &mut Simulation,
    simulation_s: &mut f64,
    until_s: f64,
) -> (Vec<sim::sensors::SensorScan>, Option<oeg::Stance>) {
    let t0 = Instant::now();
    let batch = std::iter::from_fn(|| simulation.next_scan_until(until_s))
        .take(SCANS_PER_BATCH)
        .collect();
    let stance = simulation.world().estimated_stance();
    *simulation_s += t0.elapsed().as_secs_f64();
    (batch, stance)
}

/// The robot's stance, with the space its body fills ([`Map::integrate_footprint`]), into the maps that take
/// it, each map's time added to its `map_s`.
fn lay_footprints(
    maps: &mut [Map],
    take_stance: &[bool],
    map_s: &mut [f64],
    stance: Option<(&oeg::Stance, oeg::BodySpan)>,
) -> Result<()> {
    let Some((stance, body)) = stance else {
        return Ok(());
    };
    for ((map, take), seconds) in maps.iter_mut().zip(take_stance).zip(map_s) {
        if *take {
            let t0 = Instant::now();
            map.integrate_footprint(stance, body)?;
            *seconds += t0.elapsed().as_secs_f64();
        }
    }
    Ok(())
}

/// Simulated scans into the observability and, at the estimated pose, into every map: each map takes the batch
/// at once (`Map::integrate_batch`), the maps at the same time (they are independent), each map's time added
/// to its `map_s`. Returns the scans as the maps took them.
fn map_batch(
    observability: &mut Observer,
    maps: &mut [Map],
    map_s: &mut [f64],
    models: &[oeg::SensorModel],
    max_range_m: &[f64],
    batch: Vec<sim::sensors::SensorScan>,
) -> Result<Vec<oeg::Scan>> {
    let scans: Vec<oeg::Scan> = batch
        .into_iter()
        .map(|scan| {
            observability.observe(&scan, max_range_m[scan.sensor_index]);
            scan.to_scan(PoseSource::Estimated, models[scan.sensor_index])
        })
        .collect();
    let integrate = |(map, seconds): (&mut Map, &mut f64)| {
        let t1 = Instant::now();
        let r = map.integrate_batch(&scans).map(|_| ()).map_err(|e| e.error);
        *seconds += t1.elapsed().as_secs_f64();
        r
    };
    if maps.len() > 1 {
        use rayon::prelude::*;
        maps.par_iter_mut()
            .zip(map_s.par_iter_mut())
            .map(integrate)
            .collect::<std::result::Result<Vec<()>, _>>()?;
    } else {
        maps.iter_mut().zip(map_s.iter_mut()).try_for_each(integrate)?;
    }
    Ok(scans)
}

/// One simulated scan into the observability and, at the estimated pose, into every map ([`map_batch`] of
/// one scan). Returns the scan as the maps took it.
fn map_scan(
    observability: &mut Observer,
    maps: &mut [Map],
    map_s: &mut [f64],
    models: &[oeg::SensorModel],
    max_range_m: &[f64],
    scan: sim::sensors::SensorScan,
) -> Result<oeg::Scan> {
    let mut taken = map_batch(observability, maps, map_s, models, max_range_m, vec![scan])?;
    Ok(taken.remove(0))
}
