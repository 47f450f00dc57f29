//! The simulation loop: sensors fire at their own rates; the world is moved to each firing time and the
//! sensor scans it.

use crate::error::Result;
use crate::scenario::LoadedScenario;
use crate::sensors::{ObstacleReturns, ReturnSource, SensorRay, SensorScan, SimSensor};
use crate::world::World;

/// A running simulation of one scenario.
#[derive(Debug)]
pub struct Simulation {
    world: World,
    sensors: Vec<SimSensor>,
    /// Index of each sensor's next firing: it fires at `next[k] / rate_hz`.
    next: Vec<u64>,
    duration_s: f64,
    buffer: Vec<SensorRay>,
    sources: Vec<ReturnSource>,
    returns: ObstacleReturns,
    num_rays: u64,
}

impl Simulation {
    /// A simulation at time 0.
    ///
    /// # Errors
    /// As [`World::new`]; sensor settings were checked when the scenario was loaded.
    pub fn new(loaded: &LoadedScenario) -> Result<Self> {
        let world = World::new(loaded)?;
        let mut sensors = Vec::with_capacity(loaded.scenario.sensors.len());
        for mount in &loaded.scenario.sensors {
            let spec = mount.resolve().map_err(|e| crate::SimError::Scenario {
                path: loaded.source.path.clone(),
                position: None,
                message: format!("sensor `{}`: `{}`: {}", mount.name, e.key.join("."), e.message),
            })?;
            sensors.push(SimSensor::new(spec, loaded.scenario.seed));
        }
        Ok(Self {
            next: vec![0; sensors.len()],
            world,
            sensors,
            duration_s: loaded.scenario.duration_s,
            buffer: Vec::new(),
            sources: Vec::new(),
            returns: ObstacleReturns::new(loaded.scenario.obstacles.len()),
            num_rays: 0,
        })
    }

    /// The world (at the time of the last scan).
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The world, to move it to the end of the run for the truth.
    pub fn world_mut(&mut self) -> &mut World {
        &mut self.world
    }

    /// What each reading of the last scan returned from, in the order of its rays.
    pub fn last_scan_sources(&self) -> &[ReturnSource] {
        &self.sources
    }

    /// The sensors.
    pub fn sensors(&self) -> &[SimSensor] {
        &self.sensors
    }

    /// The scenario's duration, seconds.
    pub fn duration_s(&self) -> f64 {
        self.duration_s
    }

    /// The readings each obstacle returned so far.
    pub fn obstacle_returns(&self) -> &ObstacleReturns {
        &self.returns
    }

    /// Rays cast so far.
    pub fn num_rays(&self) -> u64 {
        self.num_rays
    }

    /// Total scans the run will produce.
    pub fn num_scans_total(&self) -> u64 {
        self.sensors
            .iter()
            .map(|s| s.spec.num_scans(self.duration_s))
            .sum()
    }

    /// The next scan in time order (ties: the sensor listed first), or `None` at the end of the run.
    pub fn next_scan(&mut self) -> Option<SensorScan> {
        self.next_scan_until(self.duration_s)
    }

    /// The next scan in time order taken at or before `until_s` (and the end of the run), or `None`: a
    /// closed loop takes the scans of one control step at a time.
    pub fn next_scan_until(&mut self, until_s: f64) -> Option<SensorScan> {
        let end = until_s.min(self.duration_s) + 1e-9;
        let (index, t) = self
            .sensors
            .iter()
            .enumerate()
            .map(|(k, s)| (k, self.next[k] as f64 / s.spec.rate_hz))
            .filter(|(_, t)| *t <= end)
            .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))?;
        self.next[index] += 1;
        self.world.advance_to(t);
        let scan = self.sensors[index].capture(
            &self.world,
            index,
            &mut self.buffer,
            &mut self.sources,
            &mut self.returns,
        )?;
        self.num_rays += scan.rays.len() as u64;
        Some(scan)
    }
}
