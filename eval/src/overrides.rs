//! `--set key=value`: override any scenario value by its dotted key (`map.resolution_m=0.1`,
//! `sensors.0.noise.dropout_probability=0.05`, `map.model.free_space_elevation=ray_bound`).
//!
//! The value is read as a TOML value (`0.1`, `true`, `[1.0, 2.0]`, `"text"`); a bare word that is not one is
//! taken as a string. The scenario is rewritten with the overrides and then checked like any scenario file, so
//! an override that makes no sense is reported as such.

use toml::{Table, Value};

/// Applies `overrides` (`key=value` each) to the scenario text.
///
/// # Errors
/// A message naming the override: no `=`, an empty key, a key whose parent does not exist, an index past an
/// array's end, a key into something that is not a table or an array.
pub fn apply(text: &str, overrides: &[String]) -> Result<String, String> {
    if overrides.is_empty() {
        return Ok(text.to_string());
    }
    let mut doc: Table =
        toml::from_str(text).map_err(|e| format!("the scenario is not valid TOML: {}", e.message()))?;
    for o in overrides {
        let (key, raw) = o
            .split_once('=')
            .ok_or_else(|| format!("--set {o}: expected key=value"))?;
        let key = key.trim();
        if key.is_empty() || key.split('.').any(str::is_empty) {
            return Err(format!(
                "--set {o}: expected a dotted key such as map.resolution_m"
            ));
        }
        let value = parse_value(raw.trim());
        set(&mut doc, key, value).map_err(|e| format!("--set {o}: {e}"))?;
    }
    toml::to_string(&doc).map_err(|e| format!("cannot write the overridden scenario: {e}"))
}

fn parse_value(raw: &str) -> Value {
    match toml::from_str::<Table>(&format!("v = {raw}")) {
        Ok(mut t) => t.remove("v").unwrap_or_else(|| Value::String(raw.to_string())),
        Err(_) => Value::String(raw.to_string()),
    }
}

fn set(doc: &mut Table, key: &str, value: Value) -> Result<(), String> {
    let segments: Vec<&str> = key.split('.').collect();
    let mut root = Value::Table(std::mem::take(doc));
    let result = set_in(&mut root, &segments, 0, value);
    if let Value::Table(t) = root {
        *doc = t;
    }
    result
}

/// Sets `path[depth..]` inside `here`, which is reached by `path[..depth]`.
fn set_in(here: &mut Value, path: &[&str], depth: usize, value: Value) -> Result<(), String> {
    let at = if depth == 0 {
        "the scenario".to_string()
    } else {
        format!("`{}`", path[..depth].join("."))
    };
    let seg = path[depth];
    let last = depth + 1 == path.len();
    let child = match here {
        Value::Table(t) => {
            if last {
                t.insert(seg.to_string(), value);
                return Ok(());
            }
            // A missing table on the way is created: `expectations.coverage={ min = 0.9 }` works in a file
            // without [expectations]. Whether the key is allowed there is the scenario check's business.
            t.entry(seg.to_string())
                .or_insert_with(|| Value::Table(Table::new()))
        }
        Value::Array(a) => {
            let i: usize = seg
                .parse()
                .map_err(|_| format!("{at} is a list: expected an index, got `{seg}`"))?;
            let n = a.len();
            let slot = a
                .get_mut(i)
                .ok_or_else(|| format!("{at} has {n} entries, no index {i}"))?;
            if last {
                *slot = value;
                return Ok(());
            }
            slot
        }
        _ => return Err(format!("{at} is a value, not a table")),
    };
    set_in(child, path, depth + 1, value)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "name = \"x\"\n[map]\nresolution_m = 0.05\n[[sensors]]\nname = \"a\"\n[sensors.noise]\nrange_sigma_m = 0.01\n";

    #[test]
    fn values_are_replaced_and_added() {
        let out = apply(
            TEXT,
            &[
                "map.resolution_m=0.1".into(),
                "sensors.0.noise.dropout_probability=0.2".into(),
                "name=other".into(),
            ],
        )
        .expect("applied");
        let t: Table = toml::from_str(&out).expect("toml");
        assert_eq!(t["map"]["resolution_m"].as_float(), Some(0.1));
        assert_eq!(
            t["sensors"][0]["noise"]["dropout_probability"].as_float(),
            Some(0.2)
        );
        assert_eq!(t["sensors"][0]["noise"]["range_sigma_m"].as_float(), Some(0.01));
        assert_eq!(t["name"].as_str(), Some("other"));
    }

    #[test]
    fn missing_tables_are_created() {
        let out = apply(TEXT, &["expectations.coverage={ min = 0.9 }".into()]).expect("applied");
        let t: Table = toml::from_str(&out).expect("toml");
        assert_eq!(t["expectations"]["coverage"]["min"].as_float(), Some(0.9));
    }

    #[test]
    fn malformed_overrides_are_clear_errors() {
        for (o, expected) in [
            ("map.resolution_m", "expected key=value"),
            ("=3", "dotted key"),
            ("map..x=1", "dotted key"),
            ("sensors.4.name=b", "has 1 entries, no index 4"),
            ("sensors.first.name=b", "expected an index"),
            ("name.first=1", "is a value, not a table"),
        ] {
            let err = apply(TEXT, &[o.to_string()]).expect_err(o);
            assert!(err.contains(expected) && err.contains(o), "{o}: {err}");
        }
    }
}
