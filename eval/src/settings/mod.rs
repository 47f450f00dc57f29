//! One door for settings: every job that takes settings (`oeg run`, `oeg suite`, `oeg map`, `oeg plan`,
//! `oeg sweep`) takes them as `--set key=value` (`settings::overrides`), resolved here against one table of
//! keys. The keys are the scenario file's (`docs/scenario-format.md`): `map.model.p_max` means the same
//! thing in a scenario, on `oeg run --set`, on `oeg map --set` and in a sweep's axis. Jobs without a scenario
//! take the part of the table they use:
//!
//! | key | `run`, `suite`, `sweep` | `map` | `plan` |
//! |---|---|---|---|
//! | `map.resolution_m`, `map.model.*` | yes | yes | no (the map file has them) |
//! | `map.traversability` | yes | yes | yes |
//! | `robot.max_step_m`, `robot.height_m` | yes | yes | yes |
//! | `planner.inflation_radius_m`, `planner.footprint_radius_m`, `planner.unknown`, `planner.uncertain`, `planner.inflation_cost_width_m`, `planner.cost_scaling_factor` | yes | no | yes |
//! | `input.graph_sensor`, `input.pcd_sensor`, `input.pcd_frame`, `input.pcd_invalid`, `input.log_pose`, `input.bag.*` | no | yes | no |
//! | every other scenario key | yes | no | no |
//!
//! An override that makes the settings invalid is named in the error (`--set map.model.p_max=2: ...`), by
//! [`resolve_with`], which `oeg run` and `oeg suite` use too, with the scenario check as the reader.

mod input;
pub(crate) mod overrides;

pub use input::{BagInput, InputSettings, RangeModel};

use serde::Deserialize;
use serde::de::DeserializeOwned;
use toml::Table;

use crate::settings::overrides::Override;

/// A setting that cannot be used, named by where it came from: a `--set` on the command line (or a sweep's
/// key, which goes through the same door), another option such as `--resolution`, or the defaults.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum SettingError {
    /// A `key=value` override that does not parse or apply, or after which the settings no longer make sense.
    #[error("--set {text}: {message}")]
    Override {
        /// The override as given.
        text: String,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A setting given by an option of its own (`--resolution`).
    #[error("{option}: {message}")]
    Option {
        /// The option, as typed (`--resolution`).
        option: &'static str,
        /// What is wrong and what was expected.
        message: String,
    },
    /// The settings without any override make no sense.
    #[error("the defaults: {message}")]
    Defaults {
        /// What is wrong.
        message: String,
    },
    /// The settings make no sense, and no one source is to blame (or the source is given around it).
    #[error("{message}")]
    Invalid {
        /// What is wrong and what was expected.
        message: String,
    },
}

impl SettingError {
    /// What is wrong, without where it came from.
    pub fn message(&self) -> &str {
        match self {
            Self::Override { message, .. }
            | Self::Option { message, .. }
            | Self::Defaults { message }
            | Self::Invalid { message } => message,
        }
    }

    /// A problem with no source of its own yet.
    pub fn invalid(message: impl Into<String>) -> Self {
        Self::Invalid {
            message: message.into(),
        }
    }
}

/// `[map]` of `oeg map`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MapPart {
    /// Cell size, metres.
    pub resolution_m: f64,
    /// The named model the options start from.
    #[serde(default)]
    pub preset: oeg::MapPreset,
    /// The `[map.model]` keys given over the preset's options.
    #[serde(default, rename = "model")]
    pub model_keys: oeg::ModelKeys,
    /// The step rule of the traversability image, unless the preset's.
    #[serde(default, rename = "traversability")]
    pub traversability_key: Option<oeg::TraversabilityRule>,
    /// The model, resolved for `[robot]` once the settings are read ([`oeg::ModelChoice::resolve`]).
    #[serde(skip)]
    pub model: oeg::ModelOptions,
    /// The step rule, resolved with the model.
    #[serde(skip)]
    pub traversability: oeg::TraversabilityRule,
}

/// Everything `oeg map` can be told.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MapJobSettings {
    /// Resolution and model.
    pub map: MapPart,
    /// Decision limits.
    #[serde(default)]
    pub robot: oeg::RobotProfile,
    /// How files become scans.
    #[serde(default)]
    pub input: InputSettings,
}

/// `[map]` of `oeg plan`: only the rule (the map file holds its model).
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlanMapPart {
    /// The named model whose step rule applies unless `traversability` is given.
    pub preset: oeg::MapPreset,
    /// The step rule, unless the preset's.
    #[serde(rename = "traversability")]
    pub traversability_key: Option<oeg::TraversabilityRule>,
    /// The step rule, resolved once the settings are read.
    #[serde(skip)]
    pub traversability: oeg::TraversabilityRule,
}

/// Everything `oeg plan` can be told.
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlanJobSettings {
    /// The step rule.
    pub map: PlanMapPart,
    /// Decision limits.
    pub robot: oeg::RobotProfile,
    /// The planner, with the scenario's `[planner]` keys.
    pub planner: oeg::PlannerOptions,
}

/// Settings that can check themselves for sense.
pub trait Checked: DeserializeOwned {
    /// Resolves what is derived from what was read: the model from its preset and keys
    /// ([`oeg::ModelChoice::resolve`], the one rule a scenario's loader uses too).
    fn resolve(&mut self);

    /// What makes no sense, if anything.
    ///
    /// # Errors
    /// The first value that makes no sense.
    fn check(&self) -> Result<(), SettingError>;
}

/// An error of the map crate as a setting's problem.
fn invalid(e: oeg::Error) -> SettingError {
    SettingError::invalid(e.to_string())
}

impl Checked for MapJobSettings {
    fn resolve(&mut self) {
        let model = oeg::ModelChoice {
            preset: self.map.preset,
            keys: self.map.model_keys,
            traversability: self.map.traversability_key,
        }
        .resolve(&self.robot);
        self.map.model = model.options;
        self.map.traversability = model.rule;
    }

    fn check(&self) -> Result<(), SettingError> {
        // The one rule for a cell size: the grid's.
        oeg::GridGeometry::new(self.map.resolution_m).map_err(|e| match e {
            oeg::Error::InvalidSetting { name, message } => {
                SettingError::invalid(format!("map.{name}: {message}"))
            }
            other => invalid(other),
        })?;
        self.map.model.validate().map_err(invalid)?;
        self.map.traversability.validate().map_err(invalid)?;
        self.robot.validate().map_err(invalid)
    }
}

impl Checked for PlanJobSettings {
    fn resolve(&mut self) {
        let choice = oeg::ModelChoice {
            preset: self.map.preset,
            traversability: self.map.traversability_key,
            ..oeg::ModelChoice::default()
        };
        self.map.traversability = choice.resolve(&self.robot).rule;
    }

    fn check(&self) -> Result<(), SettingError> {
        self.planner.validate().map_err(|e| match e {
            oeg::Error::InvalidSetting { name, message } => {
                SettingError::invalid(format!("planner.{name}: {message}"))
            }
            other => invalid(other),
        })?;
        self.map.traversability.validate().map_err(invalid)?;
        self.robot.validate().map_err(invalid)
    }
}

/// Reads settings of type `T` from a document: the schema, what is derived from it ([`Checked::resolve`]),
/// then `T`'s own check.
fn read<T: Checked>(doc: &Table) -> Result<T, SettingError> {
    // Read from the document itself: no trip through TOML text.
    let mut value: T = toml::Value::Table(doc.clone())
        .try_into()
        .map_err(|e: toml::de::Error| SettingError::invalid(e.message().trim()))?;
    value.resolve();
    value.check()?;
    Ok(value)
}

/// Resolves `overrides` (`key=value` each) over `base`, in order, and reads the result with `read`. When the
/// result does not read, the error names the first override after which it no longer does.
///
/// # Errors
/// A malformed override, or one that makes the settings invalid: `--set KEY=VALUE: what is wrong`.
pub fn resolve_with<T>(
    base: &Table,
    overrides: &[String],
    read: impl Fn(&Table) -> Result<T, SettingError>,
) -> Result<T, SettingError> {
    let parsed = overrides
        .iter()
        .map(|t| Override::parse(t))
        .collect::<Result<Vec<_>, _>>()?;
    let mut doc = base.clone();
    for o in &parsed {
        o.apply_to(&mut doc)?;
    }
    let full = match read(&doc) {
        Ok(v) => return Ok(v),
        Err(e) => e,
    };
    // Keys that only make sense together (a region's two corners) are applied together above; the blame goes
    // to the first override after which the settings no longer read.
    let mut doc = base.clone();
    for o in &parsed {
        o.apply_to(&mut doc)?;
        if let Err(e) = read(&doc) {
            return Err(SettingError::Override {
                text: o.source.clone(),
                message: e.message().to_string(),
            });
        }
    }
    Err(full)
}

/// [`resolve_with`] for settings that check themselves; the defaults are checked first.
///
/// # Errors
/// As [`resolve_with`], and bad defaults (`the defaults: ...`).
pub fn resolve<T: Checked>(base: &Table, overrides: &[String]) -> Result<T, SettingError> {
    read::<T>(base).map_err(|e| SettingError::Defaults {
        message: e.message().to_string(),
    })?;
    resolve_with(base, overrides, read::<T>)
}

/// `oeg map`'s settings: `--resolution` and the overrides.
///
/// # Errors
/// A bad resolution (named as `--resolution`) or override.
pub fn map_settings(resolution_m: f64, overrides: &[String]) -> Result<MapJobSettings, SettingError> {
    // The cell size has one spelling on `oeg map`: two would leave the reader guessing which one won.
    for text in overrides {
        let o = Override::parse(text)?;
        if overrides::key_covers(&o.key, "map.resolution_m") {
            return Err(SettingError::Override {
                text: text.clone(),
                message: "the cell size is `--resolution` on `oeg map`; give it there only".into(),
            });
        }
    }
    let mut map = Table::new();
    map.insert("resolution_m".into(), toml::Value::Float(resolution_m));
    let mut base = Table::new();
    base.insert("map".into(), toml::Value::Table(map));
    resolve(&base, overrides).map_err(|e| match e {
        SettingError::Defaults { message } => SettingError::Option {
            option: "--resolution",
            message,
        },
        other => other,
    })
}

/// `oeg plan`'s settings from the overrides.
///
/// # Errors
/// A bad override.
pub fn plan_settings(overrides: &[String]) -> Result<PlanJobSettings, SettingError> {
    resolve(&Table::new(), overrides)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map_base() -> Table {
        toml::from_str("[map]\nresolution_m = 0.05\n").expect("toml")
    }

    #[test]
    fn map_settings_take_the_scenario_keys() {
        let s: MapJobSettings = resolve(
            &map_base(),
            &[
                "map.model.p_max=0.7".into(),
                "map.model.max_height_m=0.5".into(),
                "input.pcd_frame=optical".into(),
                "robot.max_step_m=0.05".into(),
            ],
        )
        .expect("valid");
        assert!((s.map.model.p_max - 0.7).abs() < 1e-6);
        assert_eq!(s.map.model.max_height_m, Some(0.5));
        assert_eq!(s.input.pcd_frame, oeg::PcdFrame::Optical);
        assert!((s.robot.max_step_m - 0.05).abs() < 1e-12);
    }

    /// `oeg map` and `oeg plan` resolve a preset by the rule a scenario's loader uses: the preset's options
    /// for the given robot, the given keys over them, and the preset's step rule unless one is given.
    #[test]
    fn a_preset_resolves_for_the_robot_with_the_given_keys_over_it() {
        let robot = oeg::RobotProfile {
            height_m: 0.8,
            ..oeg::RobotProfile::default()
        };
        let s: MapJobSettings = resolve(
            &map_base(),
            &[
                "map.preset=robust".into(),
                "map.model.p_max=0.9".into(),
                "robot.height_m=0.8".into(),
            ],
        )
        .expect("valid");
        let expected = oeg::ModelOptions {
            p_max: 0.9,
            ..oeg::MapPreset::Robust.model(&robot)
        };
        assert_eq!(s.map.model, expected);
        assert_eq!(s.map.traversability, oeg::MapPreset::Robust.traversability());
        let plan: PlanJobSettings = plan_settings(&["map.preset=robust".into()]).expect("valid");
        assert_eq!(plan.map.traversability, oeg::MapPreset::Robust.traversability());
        let plan: PlanJobSettings = plan_settings(&[
            "map.preset=robust".into(),
            "map.traversability={ kind = \"absolute\" }".into(),
        ])
        .expect("valid");
        assert_eq!(plan.map.traversability, oeg::TraversabilityRule::Absolute);
    }

    #[test]
    fn a_bad_override_is_named() {
        for (o, expected) in [
            ("map.model.p_max=2", "--set map.model.p_max=2: "),
            (
                "map.model.p_maxx=0.7",
                "--set map.model.p_maxx=0.7: unknown field `p_maxx`",
            ),
            (
                "input.log_pose=maybe",
                "--set input.log_pose=maybe: unknown variant `maybe`",
            ),
            ("map.resolution_m=0", "--set map.resolution_m=0: map.resolution_m"),
        ] {
            let e = resolve::<MapJobSettings>(&map_base(), &[o.into()])
                .expect_err(o)
                .to_string();
            assert!(e.starts_with(expected), "{o}: {e}");
        }
        let e = resolve::<PlanJobSettings>(&Table::new(), &["planner.unknown=sometimes".into()])
            .expect_err("plan")
            .to_string();
        assert!(
            e.starts_with("--set planner.unknown=sometimes: unknown variant"),
            "{e}"
        );
        let e = resolve::<PlanJobSettings>(&Table::new(), &["map.model.p_max=0.7".into()])
            .expect_err("plan")
            .to_string();
        assert!(e.contains("unknown field `model`"), "{e}");
    }

    #[test]
    fn the_documented_log_pose_spellings_read() {
        for (o, pose) in [
            ("input.log_pose=true", sim::sensors::PoseSource::True),
            ("input.log_pose=\"true\"", sim::sensors::PoseSource::True),
            ("input.log_pose=estimated", sim::sensors::PoseSource::Estimated),
        ] {
            let s: MapJobSettings = resolve(&map_base(), &[o.into()]).expect(o);
            assert_eq!(s.input.log_pose, pose, "{o}");
        }
    }

    #[test]
    fn every_preset_of_the_map_crate_is_a_setting() {
        for preset in oeg::MapPreset::ALL {
            let name = preset.name();
            let s = map_settings(0.05, &[format!("map.preset={name}")]).expect(name);
            assert_eq!(
                s.map.model,
                preset.model(&oeg::RobotProfile::default()),
                "{}",
                preset.name()
            );
            assert_eq!(s.map.traversability, preset.traversability(), "{}", preset.name());
        }
    }

    #[test]
    fn the_cell_size_is_given_once_on_oeg_map() {
        for o in ["map.resolution_m=0.1", "map.*=0.1", "map={ resolution_m = 0.1 }"] {
            let e = map_settings(0.5, &[o.into()]).expect_err(o).to_string();
            assert!(e.contains("`--resolution`"), "{o}: {e}");
        }
        let s = map_settings(0.5, &["map.model.p_max=0.7".into()]).expect("other keys");
        assert!((s.map.resolution_m - 0.5).abs() < 1e-12);
    }
}
