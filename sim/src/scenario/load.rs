//! Reading a scenario file: TOML syntax, the schema (unknown keys are errors), then a check of every value for
//! sense. Every error names the file, the line and column, and what was expected.

use std::path::Path;

use toml::de::{DeTable, DeValue};

use super::schema::{Actor, Obstacle, Scenario, ScenarioSource, Terrain};
use crate::error::{Result, SimError, TextPosition};
use crate::robot::RobotModel;

/// The largest map region a scenario may ask for, in cells: the truth raster and images are dense over it
/// (25 million cells is 250 m x 250 m at 0.05 m).
pub const MAX_MAP_CELLS: u64 = 25_000_000;
/// The longest simulated duration, seconds (one day).
pub const MAX_DURATION_S: f64 = 86_400.0;
/// The longest length of an obstacle, an actor or the terrain, metres (100 km): more than any scene, and a
/// typed `1e9` is caught.
pub const MAX_LENGTH_M: f64 = 100_000.0;
/// The most obstacles and actors a scenario may list, each.
pub const MAX_OBJECTS: usize = 10_000;
/// The most solid parts the world may hold: an obstacle is one, a bush `num_parts` (Rapier holds each as a
/// collider, about a kilobyte).
pub const MAX_PARTS: usize = 100_000;
/// The most rays a run may cast, all sensors together (rate x duration x rays per scan): 2 billion. The
/// simulation casts a few million rays a second and the map integrates about a million on the reference
/// machine, so the worst valid scenario finishes, in hours rather than never (`docs/guarantees.md`).
pub const MAX_RAYS_PER_RUN: f64 = 2e9;
/// The most cells a run's rays may cross, all sensors together (rays x their longest range / the cell size):
/// 10^12. The map walks 65-84 million cells a second on one core of the reference machine (README, "Bad
/// input, bounds and outputs"), so this too keeps the worst valid scenario to hours.
pub const MAX_CELL_VISITS_PER_RUN: f64 = 1e12;

/// One step of a path to a value in the file: a key or an array index.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KeySeg<'a> {
    /// A table key.
    Key(&'a str),
    /// An array element.
    Index(usize),
}

/// A scenario with everything it refers to loaded and checked.
#[derive(Debug, Clone)]
pub struct LoadedScenario {
    /// The scenario.
    pub scenario: Scenario,
    /// Its file and text.
    pub source: ScenarioSource,
    /// The robot, from its URDF.
    pub robot: RobotModel,
}

/// Reads, parses and validates a scenario file, and loads its robot.
///
/// # Errors
/// [`SimError::Scenario`] with file, line and column for a syntax error, an unknown key, a value of the wrong
/// type or a value that makes no sense; [`SimError::Io`] for an unreadable file; [`SimError::Urdf`] for a bad
/// robot description.
pub fn load(path: &Path) -> Result<LoadedScenario> {
    let text = crate::error::read_text(path)?;
    load_str(path, &text)
}

/// As [`load`], from text already read (`path` names it in errors and anchors relative paths).
///
/// # Errors
/// As [`load`].
pub fn load_str(path: &Path, text: &str) -> Result<LoadedScenario> {
    let source = ScenarioSource {
        path: path.to_path_buf(),
        text: text.to_string(),
    };
    let scenario: Scenario = toml::from_str(text).map_err(|e| SimError::Scenario {
        path: path.to_path_buf(),
        position: e.span().map(|s| TextPosition::of_offset(text, s.start)),
        message: e.message().trim().to_string(),
    })?;
    let checker = Checker {
        source: &source,
        document: DeTable::parse(text).ok().map(|d| d.into_inner()),
    };
    let mut scenario = scenario;
    apply_preset(&mut scenario, text).map_err(|message| checker.error(&[KeySeg::Key("map")], message))?;
    checker.validate(&scenario)?;
    let urdf_path = source.resolve(&scenario.robot.urdf);
    let robot = RobotModel::load(&urdf_path, &scenario.robot.base_link)
        .map_err(|e| checker.error(&[KeySeg::Key("robot"), KeySeg::Key("urdf")], e.to_string()))?;
    for (k, s) in scenario.sensors.iter().enumerate() {
        if robot.link(&s.mount_link).is_none() {
            return Err(checker.error(
                &[
                    KeySeg::Key("sensors"),
                    KeySeg::Index(k),
                    KeySeg::Key("mount_link"),
                ],
                format!(
                    "sensor `{}` is mounted on link `{}`, which {} does not have (links: {})",
                    s.name,
                    s.mount_link,
                    urdf_path.display(),
                    robot.link_names().join(", ")
                ),
            ));
        }
    }
    Ok(LoadedScenario {
        scenario,
        source,
        robot,
    })
}

/// Applies the scenario's `[map] preset` to its model and step rule: the keys the file gives in `[map.model]`
/// and `[map] traversability` over the preset's.
fn apply_preset(scenario: &mut Scenario, text: &str) -> std::result::Result<(), String> {
    if scenario.map.preset == oeg::MapPreset::Paper {
        return Ok(());
    }
    let mut doc: toml::Table = toml::from_str(text).map_err(|e| e.message().to_string())?;
    expand_map_preset(&mut doc)?;
    let map = doc
        .get("map")
        .cloned()
        .unwrap_or_else(|| toml::Value::Table(toml::Table::new()));
    let map: super::MapSettings = map
        .try_into()
        .map_err(|e: toml::de::Error| e.message().to_string())?;
    scenario.map.model = map.model;
    scenario.map.traversability = map.traversability;
    Ok(())
}

/// Expands `[map] preset` in a settings document (a scenario, or the settings of `oeg map` and `oeg plan`):
/// `[map.model]` becomes the preset's options (for the robot of `[robot]`) with the document's own
/// `[map.model]` keys over them, and `[map] traversability` the preset's rule unless the document gives one.
/// `paper`, or no preset, changes nothing.
///
/// # Errors
/// A preset name or a `[robot]` that does not read.
pub fn expand_map_preset(doc: &mut toml::Table) -> std::result::Result<(), String> {
    let Some(map) = doc.get("map").and_then(toml::Value::as_table) else {
        return Ok(());
    };
    let preset: oeg::MapPreset = match map.get("preset") {
        None => return Ok(()),
        Some(v) => v
            .clone()
            .try_into()
            .map_err(|e: toml::de::Error| format!("map.preset: {}", e.message()))?,
    };
    if preset == oeg::MapPreset::Paper {
        return Ok(());
    }
    let robot = doc.get("robot").and_then(toml::Value::as_table);
    let number = |key: &str, default: f32| -> std::result::Result<f32, String> {
        match robot.and_then(|r| r.get(key)) {
            None => Ok(default),
            Some(v) => v
                .as_float()
                .or_else(|| v.as_integer().map(|i| i as f64))
                .map(|x| x as f32)
                .ok_or_else(|| format!("robot.{key}: expected a number")),
        }
    };
    let profile = oeg::RobotProfile {
        max_step_m: number("max_step_m", oeg::DEFAULT_MAX_STEP_M)?,
        height_m: number("height_m", oeg::DEFAULT_ROBOT_HEIGHT_M)?,
        max_grade: number("max_grade", oeg::DEFAULT_MAX_GRADE)?,
    };
    let mut model = toml::Table::try_from(preset.model(&profile)).map_err(|e| e.to_string())?;
    if let Some(given) = map.get("model").and_then(toml::Value::as_table) {
        for (k, v) in given {
            model.insert(k.clone(), v.clone());
        }
    }
    let mut map = map.clone();
    map.insert("model".into(), toml::Value::Table(model));
    if !map.contains_key("traversability") {
        let rule = toml::Value::try_from(preset.traversability()).map_err(|e| e.to_string())?;
        map.insert("traversability".into(), rule);
    }
    doc.insert("map".into(), toml::Value::Table(map));
    Ok(())
}

/// The byte offset of the value at `path` in a parsed TOML document, or of its nearest existing parent.
pub fn value_offset(doc: &DeTable<'_>, path: &[KeySeg<'_>]) -> Option<usize> {
    let mut best = None;
    let mut table = Some(doc);
    let mut array: Option<&[toml::Spanned<DeValue<'_>>]> = None;
    for seg in path {
        let value = match (*seg, table, array) {
            (KeySeg::Key(k), Some(t), _) => t.iter().find(|(key, _)| key.get_ref() == k).map(|(_, v)| v),
            (KeySeg::Index(i), _, Some(a)) => a.get(i),
            _ => None,
        };
        let Some(value) = value else { break };
        best = Some(value.span().start);
        table = None;
        array = None;
        match value.get_ref() {
            DeValue::Table(t) => table = Some(t),
            DeValue::Array(a) => array = Some(a),
            _ => {}
        }
    }
    best
}

/// Where the value at `path` lies in TOML `text` (or its nearest existing parent), as line and column; `None`
/// when the text does not parse or holds none of the path.
pub fn position_of(text: &str, path: &[KeySeg<'_>]) -> Option<TextPosition> {
    let doc = DeTable::parse(text).ok()?;
    value_offset(doc.get_ref(), path).map(|o| TextPosition::of_offset(text, o))
}

struct Checker<'a> {
    source: &'a ScenarioSource,
    document: Option<DeTable<'a>>,
}

impl Checker<'_> {
    /// The byte offset of the value at `path`, or of its nearest existing parent.
    fn offset(&self, path: &[KeySeg<'_>]) -> Option<usize> {
        value_offset(self.document.as_ref()?, path)
    }

    fn error(&self, path: &[KeySeg<'_>], message: impl Into<String>) -> SimError {
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

    fn positive(&self, v: f64, path: &[KeySeg<'_>], what: &str) -> Result<()> {
        self.check(v.is_finite() && v > 0.0, path, || {
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

    fn validate(&self, s: &Scenario) -> Result<()> {
        use KeySeg::{Index as I, Key as K};
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
                    "`{}` is used as a folder name: expected letters, digits, '-', '_' or '.'",
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
        if let Err(e) = oeg::GridGeometry::new(m.resolution_m) {
            return Err(self.error(&[K("map"), K("resolution_m")], e.to_string()));
        }
        let cells = ((m.max_xy_m[0] - m.min_xy_m[0]) / m.resolution_m).ceil()
            * ((m.max_xy_m[1] - m.min_xy_m[1]) / m.resolution_m).ceil();
        self.check(cells <= MAX_MAP_CELLS as f64, &[K("map"), K("resolution_m")], || {
            format!("the region holds {cells:.0} cells at this resolution, over the limit of {MAX_MAP_CELLS}; use a coarser resolution or a smaller region")
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

        self.validate_terrain(s)?;
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
        let mut names = std::collections::BTreeSet::new();
        let (mut total_rays, mut total_cells) = (0.0_f64, 0.0_f64);
        for (k, sensor) in s.sensors.iter().enumerate() {
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

    fn validate_terrain(&self, s: &Scenario) -> Result<()> {
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
                crate::terrain::read_greyscale_png(&file)
                    .map(|_| ())
                    .map_err(|e| self.error(&at("path"), e))
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
