//! Reading a scenario file: TOML syntax, the schema (unknown keys are errors), then a check of every value for
//! sense. Every error names the file, the line and column, and what was expected.

use std::path::Path;

use serde::Deserialize;
use toml::de::{DeTable, DeValue};

use super::check::Checker;
use super::physics::DriveMode;
use super::schema::{Scenario, ScenarioSource};
use crate::error::{Result, SimError, TextPosition};
use crate::physics::WheeledModel;
use crate::robot::RobotModel;

/// The largest map region a scenario may ask for, in cells: the truth raster and images are dense over it
/// (25 million cells is 250 m x 250 m at 0.05 m).
pub const MAX_MAP_CELLS: u64 = 25_000_000;
/// The most sample points the truth may cast rays from (three rays each): the largest region at 4 x 4 samples a
/// cell. The truth samples a few million points a second on the reference machine, so the worst valid truth
/// takes minutes ([`crate::truth::TruthCost`], `docs/guarantees.md`).
pub const MAX_TRUTH_SAMPLES: u64 = MAX_MAP_CELLS * 16;
/// The most steps the truth's running minimum may take: the largest region at 0.05 m with the Pioneer 3-AT's
/// 0.10 m contact distance (51 steps a sample). A long contact distance at a fine resolution (a small
/// `max_grade`) is caught here.
pub const MAX_TRUTH_FILTER_STEPS: u64 = MAX_TRUTH_SAMPLES * 51;
/// The most memory the truth may hold, bytes (4 GiB): its result and one band of samples.
pub const MAX_TRUTH_BYTES: u64 = 4 << 30;
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
/// 10^12. The map walks 65-84 million cells a second on one core of the reference machine
/// (docs/guarantees.md), so this too keeps the worst valid scenario to hours.
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
    /// The robot as bodies and joints, for a drive on its wheels (`[robot.drive] mode = "physics"` only).
    pub wheeled: Option<WheeledModel>,
    /// The map's window onto the grid: `[map]`'s resolution and region, built once when the scenario is
    /// checked ([`super::MapSettings::window_on`]). The truth, what the sensors could see, the recording, the
    /// figures and the planner's files are laid out on it.
    pub window: oeg::GridWindow,
}

impl LoadedScenario {
    /// The same scenario under the named model `preset`: its `[map.model]` keys and `[map] traversability`
    /// still apply over the preset's ([`super::MapSettings::resolve`], as if the file said `preset = "<name>"`).
    /// Nothing else is read or built again: the world, the robot and the window are the scenario's.
    ///
    /// # Errors
    /// [`SimError::Scenario`] when the model under `preset` makes no sense.
    pub fn with_preset(&self, preset: oeg::MapPreset) -> Result<LoadedScenario> {
        let error = |message: String| SimError::Scenario {
            path: self.source.path.clone(),
            position: None,
            message: format!("map (with preset = \"{}\"): {message}", preset.name()),
        };
        let mut scenario = self.scenario.clone();
        scenario.map.preset = preset;
        scenario.map.resolve(&scenario.robot.profile());
        scenario.map.model.validate().map_err(|e| error(e.to_string()))?;
        scenario
            .map
            .traversability
            .validate()
            .map_err(|e| error(e.to_string()))?;
        Ok(LoadedScenario {
            scenario,
            ..self.clone()
        })
    }

    /// The files the scenario was read from: the scenario, its robot's URDF, and its terrain image and measured
    /// limits, if any.
    pub fn files(&self) -> Vec<std::path::PathBuf> {
        let mut files = vec![
            self.source.path.clone(),
            self.source.resolve(&self.scenario.robot.urdf),
        ];
        if let super::scene::Terrain::Image { path, .. } = &self.scenario.terrain {
            files.push(self.source.resolve(path));
        }
        if let Some(limits) = &self.scenario.robot.limits_from {
            files.push(self.source.resolve(limits));
        }
        files
    }
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
    let at_its_place = |e: toml::de::Error| SimError::Scenario {
        path: path.to_path_buf(),
        position: e.span().map(|s| TextPosition::of_offset(text, s.start)),
        message: e.message().trim().to_string(),
    };
    // The text is parsed once, with the place of every value: the schema reads the scenario from it, the
    // checks find their places in it, and a preset's expansion reads its tables.
    let parsed = DeTable::parse(text).map_err(at_its_place)?;
    let mut scenario =
        Scenario::deserialize(toml::de::Deserializer::from(parsed.clone())).map_err(at_its_place)?;
    let checker = Checker {
        source: &source,
        document: Some(parsed.get_ref().clone()),
    };
    super::limits::apply(&checker, &mut scenario, |key| {
        super::limits::stated_in_parsed(parsed.get_ref(), key)
    })?;
    scenario.map.resolve(&scenario.robot.profile());
    let window = checker.validate(&scenario)?;
    let (robot, wheeled) = load_robot(&checker, &scenario)?;
    Ok(LoadedScenario {
        scenario,
        source,
        robot,
        wheeled,
        window,
    })
}

/// The scenario's robot from its URDF, with every sensor's mount link checked against it, and for a drive on
/// its wheels the robot as bodies and joints.
fn load_robot(checker: &Checker<'_>, scenario: &Scenario) -> Result<(RobotModel, Option<WheeledModel>)> {
    let urdf_path = checker.source.resolve(&scenario.robot.urdf);
    let at_urdf = |e: SimError| checker.error(&[KeySeg::Key("robot"), KeySeg::Key("urdf")], e.to_string());
    let text = crate::error::read_text(&urdf_path).map_err(at_urdf)?;
    let robot = RobotModel::from_urdf_text(&urdf_path, &text, &scenario.robot.base_link).map_err(at_urdf)?;
    let wheeled = match scenario.robot.drive.mode {
        DriveMode::Kinematic => None,
        DriveMode::Physics => {
            Some(WheeledModel::from_urdf(&urdf_path, &text, &scenario.robot, &robot).map_err(at_urdf)?)
        }
    };
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
    Ok((robot, wheeled))
}

/// As [`load_str`], for a document already read and changed (a scenario file with `--set` overrides applied):
/// the same schema and checks, without a trip through TOML text. `text` is the file's own text; errors carry
/// no place in it, since the value at fault may come from the command line.
///
/// # Errors
/// As [`load`], without positions.
pub fn load_doc(path: &Path, text: &str, doc: &toml::Table) -> Result<LoadedScenario> {
    let source = ScenarioSource {
        path: path.to_path_buf(),
        text: text.to_string(),
    };
    let mut scenario: Scenario =
        toml::Value::Table(doc.clone())
            .try_into()
            .map_err(|e: toml::de::Error| SimError::Scenario {
                path: path.to_path_buf(),
                position: None,
                message: e.message().trim().to_string(),
            })?;
    let checker = Checker {
        source: &source,
        document: None,
    };
    super::limits::apply(&checker, &mut scenario, |key| super::limits::stated_in(doc, key))?;
    scenario.map.resolve(&scenario.robot.profile());
    let window = checker.validate(&scenario)?;
    let (robot, wheeled) = load_robot(&checker, &scenario)?;
    Ok(LoadedScenario {
        scenario,
        source,
        robot,
        wheeled,
        window,
    })
}

/// The byte offset of the value at `path` in a parsed TOML document, or of its nearest existing parent.
pub(super) fn value_offset(doc: &DeTable<'_>, path: &[KeySeg<'_>]) -> Option<usize> {
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
