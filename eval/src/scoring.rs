//! Any map judged against a scenario, not only the testbed's: the scenario's truth with what its sensors
//! could see ([`ScoringTruth`]), and another mapper's arrays resampled onto the truth's grid and judged by the
//! same code as `oeg run` (`oeg score`, the Python package's `oeg.score`; `docs/scoring.md`).

use sim::observability::Observability;
use sim::scenario::{LoadedScenario, Scenario};
use sim::sensors::ObstacleReturns;
use sim::truth::TruthRaster;

use crate::error::Result;
use crate::judge::estimate::{Estimate, ForeignMap};
use crate::judge::{Evaluation, Sensed, score};
use crate::mapping::Mapping;
use crate::pipeline::truth_of;
use crate::progress::Progress;

/// A scenario's truth, as `oeg run` judges a map against it.
#[derive(Debug, Clone)]
pub struct ScoringTruth {
    /// The scenario (its robot, obstacles, planner ends and expectations).
    pub scenario: Scenario,
    /// The truth raster over the scenario's map region, at its resolution.
    pub raster: TruthRaster,
    /// What the rays of the scenario's scripted drive could have told, cell by cell; `None` when not asked
    /// for, or for a closed-loop scenario (whose rays depend on the map that steered it).
    pub observability: Option<Observability>,
    /// The readings each obstacle gave the sensors over that drive; `None` with no observability.
    pub returns: Option<ObstacleReturns>,
}

impl ScoringTruth {
    /// The truth of `loaded`. With `with_sensors`, the scenario's scripted drive is simulated with its
    /// sensors (the same seed gives the rays `oeg run` and `oeg record` cast), to know what they could see;
    /// the truth is then taken at the end of the drive, as `oeg run` takes it.
    ///
    /// # Errors
    /// A world that cannot be built, a region that does not fit the grid, `progress` cancelled.
    pub fn of(loaded: &LoadedScenario, with_sensors: bool, progress: &Progress) -> Result<Self> {
        let s = &loaded.scenario;
        if with_sensors && s.navigation.is_none() {
            let mut mapping = Mapping::new(loaded, &[])?;
            progress.set_length(mapping.simulation.num_scans_total());
            mapping.feed_until(s.duration_s, progress)?;
            progress.finish();
            mapping.simulation.world_mut().advance_to(s.duration_s);
            return Ok(Self {
                scenario: s.clone(),
                raster: truth_of(loaded, mapping.simulation.world(), progress)?,
                returns: Some(mapping.simulation.obstacle_returns().clone()),
                observability: Some(mapping.observability.finished()),
            });
        }
        // The static world's truth (people and the robot left out) is the same at any time.
        let world = sim::World::new(loaded)?;
        Ok(Self {
            scenario: s.clone(),
            raster: truth_of(loaded, &world, progress)?,
            observability: None,
            returns: None,
        })
    }

    /// Judges `foreign`, resampled onto the truth's grid ([`Estimate::resample`]), as `oeg run` judges its
    /// own map: the verdict counts and metrics, the per-obstacle table and the planner check.
    ///
    /// # Errors
    /// A planner check that cannot run.
    pub fn score(&self, foreign: &ForeignMap) -> Result<Evaluation> {
        let estimate = Estimate::resample(foreign, &self.raster)?;
        let sensed = Sensed {
            returns: self.returns.as_ref(),
            observability: self.observability.as_ref(),
            navigation: None,
            physics: None,
        };
        score(&self.scenario, estimate, &self.raster, &sensed)
    }
}
