//! Named model presets: sets of `--set` overrides a sweep's `preset` axis applies (`docs/sweep-format.md`).
//!
//! * `paper`: the update rules as published (every rule option back to its default). The height threshold,
//!   the range limit and the no-return clearing range stay as the scenario sets them: they describe the
//!   robot and its sensors, not the rules.
//! * `static`: the README's static settings (a beam passing above or far below a cell's surface says nothing
//!   about it; a much higher hit replaces the estimate), for scenes without moving people.
//! * `robust`: the map crate's recommended preset (`[map] preset = "robust"`, `oeg::MapPreset::Robust`): every
//!   rule option and the step rule from it, the scenario's height threshold and ranges over it.

use toml::Value;

/// The axis key that selects presets.
pub const PRESET_KEY: &str = "preset";

/// The built-in presets and what they are.
pub const BUILT_IN: [(&str, &str); 3] = [
    ("paper", "the paper's update rules as published"),
    ("robust", "oeg's recommended preset (map.preset = robust)"),
    (
        "static",
        "the static settings: free_space_occupancy = below_elevation, free_space_max_depth_m = 0.01, highest_surface fusion",
    ),
];

/// The model options that are update rules; `paper` returns each to its default.
const RULE_KEYS: [&str; 19] = [
    "map.preset",
    "map.model.log_odds_min",
    "map.model.log_odds_max",
    "map.model.occupied_threshold",
    "map.model.significance_k_m",
    "map.model.p_min",
    "map.model.p_max",
    "map.model.elevation_threshold",
    "map.model.free_space_elevation",
    "map.model.free_space_occupancy",
    "map.model.free_space_max_depth_m",
    "map.model.hit_height",
    "map.model.scan_hit_elevation",
    "map.model.overhead_hits",
    "map.model.elevation_fusion",
    "map.model.process_noise_var_m2",
    "map.model.surface_band_sigmas",
    "map.model.measurement_correlation",
    "map.model.vertical_variance",
];

/// A built-in preset's overrides in order: `(key, Some(value))` sets, `(key, None)` removes (the default).
pub fn built_in(name: &str) -> Option<Vec<(String, Option<Value>)>> {
    let paper = || {
        RULE_KEYS
            .iter()
            .map(|k| ((*k).to_string(), None))
            .collect::<Vec<_>>()
    };
    match name {
        "paper" => Some(paper()),
        "robust" => {
            let mut o = paper();
            o.push(("map.traversability".into(), None));
            o.push(("map.preset".into(), Some(Value::String("robust".into()))));
            Some(o)
        }
        "static" => {
            let mut o = paper();
            let fusion: toml::Table = toml::from_str(
                "kind = \"highest_surface\"\nmahalanobis_threshold = 3.0\nlower_threshold = 1.0\n\
                 multi_height_noise_m2 = 0.0001\n",
            )
            .ok()?;
            o.push((
                "map.model.free_space_occupancy".into(),
                Some(Value::String("below_elevation".into())),
            ));
            o.push((
                "map.model.free_space_max_depth_m".into(),
                Some(Value::Float(0.01)),
            ));
            o.push(("map.model.elevation_fusion".into(), Some(Value::Table(fusion))));
            Some(o)
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The model options that describe the robot and its sensors, which `paper` leaves as the scenario sets them.
    const SCENE_KEYS: [&str; 3] = ["max_height_m", "max_range_m", "no_return_clear_range_m"];

    #[test]
    fn every_model_option_is_a_rule_or_a_scene_setting() {
        // Every option serialized, the optional ones and those left out at the paper's value included.
        let all = oeg::ModelOptions {
            free_space_max_depth_m: Some(0.01),
            max_height_m: Some(0.5),
            max_range_m: Some(10.0),
            no_return_clear_range_m: Some(5.0),
            ..oeg::MapPreset::Robust.model(&oeg::RobotProfile::default())
        };
        let json = serde_json::to_value(all).expect("serializes");
        let fields = json.as_object().expect("an object");
        for key in fields.keys() {
            let in_rules = RULE_KEYS.contains(&format!("map.model.{key}").as_str());
            assert!(
                in_rules != SCENE_KEYS.contains(&key.as_str()),
                "`{key}` must be in exactly one of RULE_KEYS and SCENE_KEYS"
            );
        }
        assert_eq!(
            fields.len() + 1,
            RULE_KEYS.len() + SCENE_KEYS.len(),
            "RULE_KEYS lists a removed option"
        );
    }
}
