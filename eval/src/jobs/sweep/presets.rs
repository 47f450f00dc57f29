//! A sweep's `preset` axis: each value is a named model of the map crate ([`oeg::MapPreset`], the one list of
//! presets), applied as `--set` overrides (`docs/sweep-format.md`).
//!
//! Every value first returns every update-rule option to its default (the model options except
//! [`oeg::ModelOptions::SCENE_OPTIONS`], which describe the robot and its sensors and stay as the scenario sets
//! them). Then:
//! * `paper`: nothing more: the update rules as published.
//! * `static`: the options where the preset differs from the paper, written out as keys (its model does not
//!   depend on the robot, so the resolved scenario, and with it every run's id, holds the options themselves).
//! * `robust`: `map.preset = "robust"` with the scenario's step rule removed: the preset's model follows the
//!   robot's height, so the loader expands it for the scenario's robot.

use oeg::{MapPreset, ModelOptions};
use toml::Value;

/// The axis key that selects presets.
pub(crate) const PRESET_KEY: &str = "preset";

/// Every model option that is an update rule, by its `--set` key, with `map.preset`: the keys a preset sets.
fn rule_keys() -> Vec<String> {
    // Every option serialized: the optional ones set, and the ones left out at the paper's value given.
    let all = ModelOptions {
        free_space_max_depth_m: Some(0.01),
        max_height_m: Some(0.5),
        max_range_m: Some(10.0),
        no_return_clear_range_m: Some(5.0),
        ..MapPreset::Robust.model(&oeg::RobotProfile::default())
    };
    let mut keys = vec!["map.preset".to_string()];
    if let Ok(Value::Table(table)) = Value::try_from(all) {
        keys.extend(
            table
                .keys()
                .filter(|k| !ModelOptions::SCENE_OPTIONS.contains(&k.as_str()))
                .map(|k| format!("map.model.{k}")),
        );
    }
    keys
}

/// A model value as a file writes it: the options are `f32`, and a float is given by its shortest `f32`
/// decimal (`0.0001`, not the `f64` `0.00009999999747378752` the same number widens to).
fn as_written(value: Value) -> Value {
    match value {
        Value::Float(f) => Value::Float(format!("{}", f as f32).parse().unwrap_or(f)),
        Value::Table(t) => Value::Table(t.into_iter().map(|(k, v)| (k, as_written(v))).collect()),
        Value::Array(a) => Value::Array(a.into_iter().map(as_written).collect()),
        other => other,
    }
}

/// A built-in preset's overrides in order: `(key, Some(value))` sets, `(key, None)` removes (the default).
/// `None` for a name that is no preset.
pub(crate) fn built_in(name: &str) -> Option<Vec<(String, Option<Value>)>> {
    let preset: MapPreset = name.parse().ok()?;
    let mut o: Vec<(String, Option<Value>)> = rule_keys().into_iter().map(|k| (k, None)).collect();
    match preset {
        MapPreset::Paper => {}
        MapPreset::Static => {
            let paper = Value::try_from(MapPreset::Paper.model(&oeg::RobotProfile::default())).ok()?;
            let Value::Table(model) =
                Value::try_from(MapPreset::Static.model(&oeg::RobotProfile::default())).ok()?
            else {
                return None;
            };
            for (key, value) in model {
                if paper.get(&key) != Some(&value) {
                    o.push((format!("map.model.{key}"), Some(as_written(value))));
                }
            }
        }
        MapPreset::Robust => {
            o.push(("map.traversability".into(), None));
            o.push(("map.preset".into(), Some(Value::String("robust".into()))));
        }
    }
    Some(o)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_model_option_is_a_rule_or_a_scene_setting() {
        let keys = rule_keys();
        let json = serde_json::to_value(ModelOptions {
            free_space_max_depth_m: Some(0.01),
            max_height_m: Some(0.5),
            max_range_m: Some(10.0),
            no_return_clear_range_m: Some(5.0),
            ..MapPreset::Robust.model(&oeg::RobotProfile::default())
        })
        .expect("serializes");
        let fields = json.as_object().expect("an object");
        for key in fields.keys() {
            let in_rules = keys.contains(&format!("map.model.{key}"));
            assert!(
                in_rules != ModelOptions::SCENE_OPTIONS.contains(&key.as_str()),
                "`{key}` must be a rule or a scene option, not both"
            );
        }
        assert_eq!(fields.len() + 1, keys.len() + ModelOptions::SCENE_OPTIONS.len());
    }

    #[test]
    fn static_sets_the_options_where_it_differs_from_the_paper() {
        let o = built_in("static").expect("a preset");
        let set: Vec<&str> = o
            .iter()
            .filter(|(_, v)| v.is_some())
            .map(|(k, _)| k.as_str())
            .collect();
        assert_eq!(
            set,
            [
                "map.model.elevation_fusion",
                "map.model.free_space_max_depth_m",
                "map.model.free_space_occupancy"
            ]
        );
        let value = |key: &str| {
            o.iter()
                .find(|(k, v)| k == key && v.is_some())
                .and_then(|(_, v)| v.clone())
        };
        assert_eq!(
            value("map.model.free_space_occupancy"),
            Some(Value::String("below_elevation".into()))
        );
        assert!(built_in("fast").is_none());
        for preset in MapPreset::ALL {
            assert!(built_in(preset.name()).is_some(), "{}", preset.name());
        }
    }
}
