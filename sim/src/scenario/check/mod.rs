//! The check of a scenario's values for sense, after the schema has read them: every error names the file, the
//! line and the column of the value, and what was expected.

mod physics;
mod world;

use toml::de::DeTable;

use super::load::{
    KeySeg, MAX_CELL_VISITS_PER_RUN, MAX_DURATION_S, MAX_LENGTH_M, MAX_MAP_CELLS, MAX_RAYS_PER_RUN,
    MAX_TRUTH_BYTES, MAX_TRUTH_FILTER_STEPS, MAX_TRUTH_SAMPLES, value_offset,
};
use super::schema::{Scenario, ScenarioSource};
use crate::error::{Result, SimError, TextPosition};

pub(super) struct Checker<'a> {
    pub(super) source: &'a ScenarioSource,
    pub(super) document: Option<DeTable<'a>>,
}

impl Checker<'_> {
    /// The byte offset of the value at `path`, or of its nearest existing parent.
    fn offset(&self, path: &[KeySeg<'_>]) -> Option<usize> {
        value_offset(self.document.as_ref()?, path)
    }

    pub(super) fn error(&self, path: &[KeySeg<'_>], message: impl Into<String>) -> SimError {
        let dotted: Vec<String> = path
            .iter()
            .map(|s| match s {
                KeySeg::Key(k) => (*k).to_string(),
                KeySeg::Index(i) => format!("[{i}]"),
            })
            .collect();
        SimError::Scenario {
            path: self.source.path.clone(),
            position: self
                .offset(path)
                .map(|o| TextPosition::of_offset(&self.source.text, o)),
            message: format!("`{}`: {}", dotted.join(".").replace(".[", "["), message.into()),
        }
    }

    fn check(&self, ok: bool, path: &[KeySeg<'_>], message: impl FnOnce() -> String) -> Result<()> {
        if ok {
            Ok(())
        } else {
            Err(self.error(path, message()))
        }
    }

    fn positive<V: Into<f64> + Copy + std::fmt::Display>(
        &self,
        v: V,
        path: &[KeySeg<'_>],
        what: &str,
    ) -> Result<()> {
        let x: f64 = v.into();
        self.check(x.is_finite() && x > 0.0, path, || {
            format!("expected a positive {what}, got {v}")
        })
    }

    /// A positive length of at most [`MAX_LENGTH_M`].
    fn length(&self, v: f64, path: &[KeySeg<'_>], what: &str) -> Result<()> {
        self.check(v.is_finite() && v > 0.0 && v <= MAX_LENGTH_M, path, || {
            format!("expected a {what} in (0, {MAX_LENGTH_M}], got {v}")
        })
    }

    fn non_negative(&self, v: f64, path: &[KeySeg<'_>], what: &str) -> Result<()> {
        self.check(v.is_finite() && v >= 0.0, path, || {
            format!("expected a {what} >= 0, got {v}")
        })
    }

    fn inside(&self, s: &Scenario, xy: [f64; 2], path: &[KeySeg<'_>]) -> Result<()> {
        let (lo, hi) = (s.map.min_xy_m, s.map.max_xy_m);
        let ok = xy.iter().all(|v| v.is_finite())
            && (lo[0]..=hi[0]).contains(&xy[0])
            && (lo[1]..=hi[1]).contains(&xy[1]);
        self.check(ok, path, || {
            format!(
                "point {xy:?} m lies outside the map region {lo:?} .. {hi:?} m; expected a point inside it"
            )
        })
    }

    /// Checks every value of the scenario for sense, section by section; the first bad one is an error at its
    /// place in the file.
    /// Returns the map's window onto the grid, built from `[map]` once it is known to make sense.
    pub(super) fn validate(&self, s: &Scenario) -> Result<oeg::GridWindow> {
        self.validate_run(s)?;
        let window = self.validate_map(s)?;
        self.validate_robot(s, &window)?;
        self.validate_navigation(s)?;
        self.validate_terrain(s)?;
        self.validate_objects(s)?;
        self.validate_sensors(s)?;
        self.validate_expectations(s)?;
        Ok(window)
    }

    /// The name, the clock and the duration.
    fn validate_run(&self, s: &Scenario) -> Result<()> {
        use KeySeg::Key as K;
        self.check(!s.name.trim().is_empty(), &[K("name")], || {
            "expected a non-empty name".into()
        })?;
        self.check(
            s.name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c)),
            &[K("name")],
            || {
                format!(
                    "{:?} is used as a folder name: expected letters, digits, '-', '_' or '.'",
                    s.name
                )
            },
        )?;
        self.check(
            s.duration_s.is_finite() && s.duration_s > 0.0 && s.duration_s <= MAX_DURATION_S,
            &[K("duration_s")],
            || {
                format!(
                    "expected a duration in (0, {MAX_DURATION_S}] s, got {}",
                    s.duration_s
                )
            },
        )?;
        self.check(
            s.tick_s.is_finite() && s.tick_s > 0.0 && s.tick_s <= s.duration_s,
            &[K("tick_s")],
            || format!("expected a tick in (0, duration_s] s, got {}", s.tick_s),
        )?;
        Ok(())
    }

    /// `[map]` and `[planner]`: the region, the resolution, the model and the rules. Returns the map's window
    /// ([`super::MapSettings::window_on`]).
    fn validate_map(&self, s: &Scenario) -> Result<oeg::GridWindow> {
        use KeySeg::Key as K;
        // The map.
        let m = &s.map;
        let finite = m.min_xy_m.iter().chain(&m.max_xy_m).all(|v| v.is_finite());
        self.check(
            finite && m.min_xy_m[0] < m.max_xy_m[0] && m.min_xy_m[1] < m.max_xy_m[1],
            &[K("map"), K("max_xy_m")],
            || {
                format!(
                    "expected max_xy_m {:?} to exceed min_xy_m {:?} on both axes",
                    m.max_xy_m, m.min_xy_m
                )
            },
        )?;
        let geometry = oeg::GridGeometry::new(m.resolution_m)
            .map_err(|e| self.error(&[K("map"), K("resolution_m")], e.to_string()))?;
        let window = s
            .map
            .window_on(geometry)
            .map_err(|e| self.error(&[K("map"), K("max_xy_m")], e.to_string()))?;
        let cells = window.num_cells();
        self.check(cells <= MAX_MAP_CELLS, &[K("map"), K("resolution_m")], || {
            format!("the region holds {cells} cells at this resolution, over the limit of {MAX_MAP_CELLS}; use a coarser resolution or a smaller region")
        })?;
        if let Err(e) = m.model.validate() {
            return Err(self.error(&[K("map"), K("model")], e.to_string()));
        }
        if let oeg::TraversabilityRule::Conservative { kappa }
        | oeg::TraversabilityRule::Contact { kappa, .. } = m.traversability
        {
            self.non_negative(
                f64::from(kappa),
                &[K("map"), K("traversability"), K("kappa")],
                "number of standard deviations",
            )?;
        }
        if let oeg::TraversabilityRule::Contact { reach_m, .. } = m.traversability {
            self.non_negative(
                f64::from(reach_m),
                &[K("map"), K("traversability"), K("reach_m")],
                "distance in metres",
            )?;
        }

        if let Err(e) = s.planner.options().validate() {
            let key = match e {
                oeg::Error::InvalidSetting { name, .. } => name,
                _ => "inflation_radius_m",
            };
            return Err(self.error(&[K("planner"), K(key)], e.to_string()));
        }
        if let Some(xy) = s.planner.start_xy_m {
            self.inside(s, xy, &[K("planner"), K("start_xy_m")])?;
        }
        if let Some(xy) = s.planner.goal_xy_m {
            self.inside(s, xy, &[K("planner"), K("goal_xy_m")])?;
        }
        Ok(window)
    }

    /// `[navigation]`: the goal, the clocks, the controller and the planner.
    fn validate_navigation(&self, s: &Scenario) -> Result<()> {
        use KeySeg::Key as K;
        let Some(n) = &s.navigation else {
            return Ok(());
        };
        let at = |key| [K("navigation"), K(key)];
        self.inside(s, n.goal_xy_m, &at("goal_xy_m"))?;
        if let Some(limit) = n.time_limit_s {
            self.check(
                limit.is_finite() && limit > 0.0 && limit <= MAX_DURATION_S,
                &at("time_limit_s"),
                || format!("expected a time limit in (0, {MAX_DURATION_S}] s, got {limit}"),
            )?;
        }
        self.check(
            n.replan_period_s.is_finite()
                && n.replan_period_s >= s.tick_s
                && n.replan_period_s <= MAX_DURATION_S,
            &at("replan_period_s"),
            || {
                format!(
                    "expected a period of at least one tick ({} s) and at most {MAX_DURATION_S} s, got {}",
                    s.tick_s, n.replan_period_s
                )
            },
        )?;
        self.length(
            n.goal_tolerance_m,
            &at("goal_tolerance_m"),
            "goal tolerance in metres",
        )?;
        self.length(n.lookahead_m, &at("lookahead_m"), "lookahead in metres")?;
        self.positive(n.speed_m_s, &at("speed_m_s"), "speed in m/s")?;
        self.check(n.speed_m_s <= s.robot.max_speed_m_s, &at("speed_m_s"), || {
            format!(
                "expected at most the robot's max_speed_m_s ({} m/s), got {} m/s",
                s.robot.max_speed_m_s, n.speed_m_s
            )
        })?;
        self.positive(n.stuck_time_s, &at("stuck_time_s"), "time in seconds")?;
        self.length(n.stuck_radius_m, &at("stuck_radius_m"), "radius in metres")?;
        if let Some(d) = n.decide_within_m {
            self.non_negative(d, &at("decide_within_m"), "distance in metres")?;
            self.check(d <= MAX_LENGTH_M, &at("decide_within_m"), || {
                format!("expected a distance in metres of at most {MAX_LENGTH_M}, got {d}")
            })?;
        }
        self.check(
            n.recovery_wait_s.is_finite() && (0.0..=MAX_DURATION_S).contains(&n.recovery_wait_s),
            &at("recovery_wait_s"),
            || {
                format!(
                    "expected a wait in [0, {MAX_DURATION_S}] s, got {}",
                    n.recovery_wait_s
                )
            },
        )?;
        self.non_negative(
            n.backup_distance_m,
            &at("backup_distance_m"),
            "distance in metres",
        )?;
        self.check(n.backup_distance_m <= 10.0, &at("backup_distance_m"), || {
            format!(
                "expected a back-up of at most 10 m, got {} m",
                n.backup_distance_m
            )
        })?;
        self.positive(n.backup_speed_m_s, &at("backup_speed_m_s"), "speed in m/s")?;
        self.check(
            n.backup_speed_m_s <= s.robot.max_speed_m_s,
            &at("backup_speed_m_s"),
            || {
                format!(
                    "expected at most the robot's max_speed_m_s ({} m/s), got {} m/s",
                    s.robot.max_speed_m_s, n.backup_speed_m_s
                )
            },
        )?;
        self.check(
            n.guard_time_s.is_finite() && (0.0..=60.0).contains(&n.guard_time_s),
            &at("guard_time_s"),
            || format!("expected a look-ahead in [0, 60] s, got {}", n.guard_time_s),
        )?;
        self.check(
            n.planner_timeout_s.is_finite() && n.planner_timeout_s > 0.0 && n.planner_timeout_s <= 3600.0,
            &at("planner_timeout_s"),
            || format!("expected a time-out in (0, 3600] s, got {}", n.planner_timeout_s),
        )?;
        if let Some(command) = &n.command {
            self.check(
                command.first().is_some_and(|p| !p.trim().is_empty()),
                &at("command"),
                || "expected a command line: a program, then its arguments".into(),
            )?;
        }
        Ok(())
    }

    /// The truth's cost over the map's region (after `[map]` and the robot's profile are known to make sense):
    /// its sample points, the steps of its running minimum and its memory, each within its limit.
    fn validate_truth_cost(&self, s: &Scenario, window: &oeg::GridWindow) -> Result<()> {
        use KeySeg::Key as K;
        let contact_m = f64::from(s.robot.profile().contact_distance_m());
        let cost = crate::truth::TruthCost::estimate(
            u64::from(window.region().num_x),
            u64::from(window.region().num_y),
            window.resolution_m(),
            crate::truth::DEFAULT_SAMPLES_PER_SIDE,
            contact_m,
        );
        let why = |what: String| {
            format!(
                "the ground truth over the map's region would need {what}; use a coarser [map] resolution_m, a \
                 smaller region or (for the running minimum) a shorter contact distance, [robot] max_step_m / max_grade \
                 = {contact_m:.3} m"
            )
        };
        self.check(
            cost.samples <= MAX_TRUTH_SAMPLES,
            &[K("map"), K("resolution_m")],
            || {
                why(format!(
                    "{} sample points, over the limit of {MAX_TRUTH_SAMPLES}",
                    cost.samples
                ))
            },
        )?;
        self.check(
            cost.filter_steps <= MAX_TRUTH_FILTER_STEPS,
            &[K("map"), K("resolution_m")],
            || {
                why(format!(
                    "{} steps of its running minimum, over the limit of {MAX_TRUTH_FILTER_STEPS}",
                    cost.filter_steps
                ))
            },
        )?;
        self.check(
            cost.peak_bytes <= MAX_TRUTH_BYTES,
            &[K("map"), K("resolution_m")],
            || {
                why(format!(
                    "{} bytes of memory, over the limit of {MAX_TRUTH_BYTES}",
                    cost.peak_bytes
                ))
            },
        )
    }

    /// `[robot]`: its decision limits, its drive and its odometry.
    fn validate_robot(&self, s: &Scenario, window: &oeg::GridWindow) -> Result<()> {
        use KeySeg::{Index as I, Key as K};
        // The robot.
        let r = &s.robot;
        self.positive(
            r.max_step_m,
            &[K("robot"), K("max_step_m")],
            "step height in metres",
        )?;
        self.positive(r.height_m, &[K("robot"), K("height_m")], "robot height in metres")?;
        if let Err(e) = r.profile().validate() {
            return Err(self.error(&[K("robot"), K("max_grade")], e.to_string()));
        }
        self.validate_truth_cost(s, window)?;
        self.positive(r.max_speed_m_s, &[K("robot"), K("max_speed_m_s")], "speed in m/s")?;
        self.positive(
            r.max_turn_rate_deg_s,
            &[K("robot"), K("max_turn_rate_deg_s")],
            "turn rate in degrees per second",
        )?;
        self.positive(
            r.drive.speed_m_s,
            &[K("robot"), K("drive"), K("speed_m_s")],
            "speed in m/s",
        )?;
        self.check(
            !r.drive.waypoints_xy_m.is_empty(),
            &[K("robot"), K("drive"), K("waypoints_xy_m")],
            || "expected at least one waypoint [x, y]".into(),
        )?;
        for (k, w) in r.drive.waypoints_xy_m.iter().enumerate() {
            self.inside(s, *w, &[K("robot"), K("drive"), K("waypoints_xy_m"), I(k)])?;
        }
        if let Some(yaw) = r.drive.start_yaw_deg {
            self.check(
                yaw.is_finite(),
                &[K("robot"), K("drive"), K("start_yaw_deg")],
                || "expected a finite angle".into(),
            )?;
        }
        self.non_negative(
            r.odometry.xy_sigma_m_per_sqrt_m,
            &[K("robot"), K("odometry"), K("xy_sigma_m_per_sqrt_m")],
            "noise",
        )?;
        self.non_negative(
            r.odometry.yaw_sigma_deg_per_sqrt_m,
            &[K("robot"), K("odometry"), K("yaw_sigma_deg_per_sqrt_m")],
            "noise",
        )?;
        self.validate_physics(&r.physics)
    }

    /// `[[sensors]]`: each entry resolved against its preset, unique names, and the run's total work.
    fn validate_sensors(&self, s: &Scenario) -> Result<()> {
        use KeySeg::{Index as I, Key as K};
        let mut names = std::collections::BTreeSet::new();
        let (mut total_rays, mut total_cells) = (0.0_f64, 0.0_f64);
        for (k, sensor) in s.sensors.iter().enumerate() {
            self.check(
                !sensor.name.is_empty() && !sensor.name.chars().any(is_hidden),
                &[K("sensors"), I(k), K("name")],
                || {
                    format!(
                        "the sensor name {:?} is shown in messages, tables and recordings: expected a non-empty \
                         name without control or other non-printing characters",
                        sensor.name
                    )
                },
            )?;
            self.check(
                names.insert(sensor.name.as_str()),
                &[K("sensors"), I(k), K("name")],
                || {
                    format!(
                        "a sensor named `{}` already exists; names must be unique",
                        sensor.name
                    )
                },
            )?;
            let finite = sensor.xyz_m.iter().chain(&sensor.rpy_deg).all(|v| v.is_finite());
            self.check(finite, &[K("sensors"), I(k), K("xyz_m")], || {
                "expected finite offsets".into()
            })?;
            match sensor.resolve() {
                Err(e) => {
                    let mut path = vec![K("sensors"), I(k)];
                    path.extend(e.key.iter().map(|key| K(key)));
                    return Err(self.error(&path, e.message));
                }
                Ok(spec) => {
                    let rays = spec.num_scans(s.duration_s) as f64 * spec.beams.rays_per_scan() as f64;
                    total_rays += rays;
                    total_cells += rays * (spec.max_range_m / s.map.resolution_m).ceil();
                }
            }
        }
        self.check(total_rays <= MAX_RAYS_PER_RUN, &[K("sensors")], || {
            format!(
                "the sensors would cast {total_rays:.3e} rays in {} s, over the limit of {MAX_RAYS_PER_RUN:.0e} \
                 rays per run; lower a rate, a resolution or the duration",
                s.duration_s
            )
        })?;
        self.check(total_cells <= MAX_CELL_VISITS_PER_RUN, &[K("sensors")], || {
            format!(
                "the sensors' rays would cross up to {total_cells:.3e} cells of {} m in {} s, over the limit of \
                 {MAX_CELL_VISITS_PER_RUN:.0e} per run; lower a rate, a range, the duration, or use larger cells",
                s.map.resolution_m, s.duration_s
            )
        })?;
        Ok(())
    }

    /// `[expectations]`: each with a finite `min`, `max` or both.
    fn validate_expectations(&self, s: &Scenario) -> Result<()> {
        use KeySeg::Key as K;
        for (name, e) in &s.expectations {
            let path = [K("expectations"), K(name.as_str())];
            self.check(e.min.is_some() || e.max.is_some(), &path, || {
                "expected `min`, `max` or both".into()
            })?;
            for v in [e.min, e.max].into_iter().flatten() {
                self.check(v.is_finite(), &path, || {
                    format!("threshold {v} is not a finite number")
                })?;
            }
            if let (Some(lo), Some(hi)) = (e.min, e.max) {
                self.check(lo <= hi, &path, || format!("min {lo} exceeds max {hi}"))?;
            }
        }
        Ok(())
    }
}

/// Whether `c` would not show as itself in a terminal: a control character (NUL, escape, carriage return, ...)
/// or one that changes how the text around it shows (bidirectional overrides, zero-width characters). Names
/// that are printed refuse them, so a message shows what the file holds.
pub(crate) fn is_hidden(c: char) -> bool {
    c.is_control()
        || matches!(c, '\u{200b}'..='\u{200f}' | '\u{202a}'..='\u{202e}' | '\u{2060}'..='\u{206f}' | '\u{feff}')
}
