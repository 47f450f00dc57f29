//! `--set key=value`: override any scenario value by its dotted key (`map.resolution_m=0.1`,
//! `sensors.0.noise.dropout_probability=0.05`, `map.model.free_space_elevation=ray_bound`). A `*` segment
//! stands for every element of a list or every key of a table (`sensors.*.noise.range_sigma_m=0.02`).
//!
//! The value is read as a TOML value (`0.1`, `true`, `[1.0, 2.0]`, `"text"`); a bare word that is not one is
//! taken as a string. The scenario is rewritten with the overrides and then checked like any scenario file, so
//! an override that makes no sense is reported as such. Sweep files (`crate::jobs::sweep`) set their axes through
//! the same [`Override`], so a key works the same way on the command line and in a study.

use toml::{Table, Value};

use super::SettingError;

/// One `key=value` override.
#[derive(Debug, Clone, PartialEq)]
pub struct Override {
    /// The dotted key, `*` for every element.
    pub key: String,
    /// The value.
    pub value: Value,
    /// How the user wrote it, for error messages (`map.model.p_max=2`).
    pub source: String,
}

impl Override {
    /// Parses `key=value` as the command line gives it.
    ///
    /// # Errors
    /// A message naming the override: no `=`, or an empty key or key segment.
    pub fn parse(text: &str) -> Result<Self, SettingError> {
        let blame = |message: String| SettingError::Override {
            text: text.to_string(),
            message,
        };
        let (key, raw) = text
            .split_once('=')
            .ok_or_else(|| blame("expected key=value".into()))?;
        let key = key.trim();
        check_key(key).map_err(|e| blame(e.to_string()))?;
        Ok(Self {
            key: key.to_string(),
            value: parse_value(raw.trim()).map_err(blame)?,
            source: text.to_string(),
        })
    }

    /// An override from a key and a value (a sweep's axis); it is spelt `key=value` in TOML syntax.
    pub fn new(key: &str, value: Value) -> Self {
        Self {
            source: format!("{key}={}", inline_value(&value)),
            key: key.to_string(),
            value,
        }
    }

    /// Applies the override to a document.
    ///
    /// # Errors
    /// A key whose parent does not exist, an index past a list's end, a key into a value, a `*` that matches
    /// nothing; the message names the override.
    pub fn apply_to(&self, doc: &mut Table) -> Result<(), SettingError> {
        let segments: Vec<&str> = self.key.split('.').collect();
        let mut root = Value::Table(std::mem::take(doc));
        let result = set_in(&mut root, &segments, 0, &self.value);
        if let Value::Table(t) = root {
            *doc = t;
        }
        result.map_err(|message| SettingError::Override {
            text: self.source.clone(),
            message,
        })
    }
}

/// Checks a dotted key: no empty segment.
///
/// # Errors
/// What is wrong with it.
pub(crate) fn check_key(key: &str) -> Result<(), SettingError> {
    if key.is_empty() || key.split('.').any(str::is_empty) {
        return Err(SettingError::Invalid {
            message: "expected a dotted key such as map.resolution_m".into(),
        });
    }
    Ok(())
}

/// Whether setting `key` (with `*` segments) can set the value at the dotted `target`: it names it, a table
/// above it, or matches it through `*`.
pub(crate) fn key_covers(key: &str, target: &str) -> bool {
    let (k, t): (Vec<&str>, Vec<&str>) = (key.split('.').collect(), target.split('.').collect());
    k.len() <= t.len() && k.iter().zip(&t).all(|(a, b)| a == b || *a == "*")
}

/// A TOML value on one line (`0.1`, `"static"`, `{ kind = "kalman" }`).
pub(crate) fn inline_value(v: &Value) -> String {
    v.to_string()
}

/// Removes the value at a dotted key, if there is one (the key falls back to its default).
pub(crate) fn remove(doc: &mut Table, key: &str) {
    let segments: Vec<&str> = key.split('.').collect();
    let Some((last, parents)) = segments.split_last() else {
        return;
    };
    let mut here = doc;
    for seg in parents {
        match here.get_mut(*seg) {
            Some(Value::Table(t)) => here = t,
            _ => return,
        }
    }
    here.remove(*last);
}

/// A value as the command line gives it: one TOML value and nothing after it (`0.1`, `true`, `[1.0, 2.0]`,
/// `"text"`, `{ min = 0.9 }`), or a bare word taken as a string (`optical`, `paper`, `robots/p3at.urdf`).
///
/// # Errors
/// Anything else, such as `0.1 # note`, `[1.0, 2.0] x` or `1\nb = 2`: what follows a value is never dropped.
fn parse_value(raw: &str) -> Result<Value, String> {
    match raw.parse::<Value>() {
        Ok(v) => Ok(v),
        Err(_) if is_bare_word(raw) => Ok(Value::String(raw.to_string())),
        Err(e) => Err(format!(
            "`{raw}` is not one value: expected a number, true or false, a \"quoted string\", a [list], an \
             {{ inline = table }} or a bare word of letters, digits and `_-.+/:` ({})",
            e.message().trim()
        )),
    }
}

/// A word that is no TOML value but plainly a string: no spaces, quotes, brackets, `#`, `=` or `,`.
fn is_bare_word(raw: &str) -> bool {
    !raw.is_empty()
        && raw
            .chars()
            .all(|c| c.is_alphanumeric() || "_-.+/:@%~".contains(c))
}

/// Sets `path[depth..]` inside `here`, which is reached by `path[..depth]`.
fn set_in(here: &mut Value, path: &[&str], depth: usize, value: &Value) -> Result<(), String> {
    let at = if depth == 0 {
        "the scenario".to_string()
    } else {
        format!("`{}`", path[..depth].join("."))
    };
    let seg = path[depth];
    let last = depth + 1 == path.len();
    if seg == "*" {
        let children: Vec<&mut Value> = match here {
            Value::Table(t) => t.iter_mut().map(|(_, v)| v).collect(),
            Value::Array(a) => a.iter_mut().collect(),
            _ => return Err(format!("{at} is a value, not a table or a list")),
        };
        if children.is_empty() {
            return Err(format!("{at} is empty: `*` matches nothing"));
        }
        for child in children {
            if last {
                *child = value.clone();
            } else {
                set_in(child, path, depth + 1, value)?;
            }
        }
        return Ok(());
    }
    let child = match here {
        Value::Table(t) => {
            if last {
                t.insert(seg.to_string(), value.clone());
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
                .map_err(|_| format!("{at} is a list: expected an index or `*`, got `{seg}`"))?;
            let n = a.len();
            let slot = a
                .get_mut(i)
                .ok_or_else(|| format!("{at} has {n} entries, no index {i}"))?;
            if last {
                *slot = value.clone();
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

    /// Applies `overrides` (`key=value` each) to a scenario text, as `oeg run` does through
    /// `settings::resolve_with`.
    ///
    /// # Errors
    /// A message naming the override: no `=`, an empty key, a key whose parent does not exist, an index past an
    /// array's end, a key into something that is not a table or an array.
    fn apply(text: &str, overrides: &[String]) -> Result<String, String> {
        if overrides.is_empty() {
            return Ok(text.to_string());
        }
        let mut doc: Table =
            toml::from_str(text).map_err(|e| format!("the scenario is not valid TOML: {}", e.message()))?;
        for o in overrides {
            Override::parse(o)
                .and_then(|o| o.apply_to(&mut doc))
                .map_err(|e| e.to_string())?;
        }
        toml::to_string(&doc).map_err(|e| format!("cannot write the overridden scenario: {e}"))
    }

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
    fn a_star_sets_every_element() {
        let text = format!("{TEXT}[[sensors]]\nname = \"b\"\n");
        let out = apply(&text, &["sensors.*.noise.range_sigma_m=0.03".into()]).expect("applied");
        let t: Table = toml::from_str(&out).expect("toml");
        for k in 0..2 {
            assert_eq!(t["sensors"][k]["noise"]["range_sigma_m"].as_float(), Some(0.03));
        }
        let err = apply("a = []\n", &["a.*.b=1".into()]).expect_err("empty list");
        assert!(err.contains("matches nothing"), "{err}");
    }

    #[test]
    fn missing_tables_are_created() {
        let out = apply(TEXT, &["expectations.coverage={ min = 0.9 }".into()]).expect("applied");
        let t: Table = toml::from_str(&out).expect("toml");
        assert_eq!(t["expectations"]["coverage"]["min"].as_float(), Some(0.9));
    }

    #[test]
    fn removed_keys_fall_back_to_their_default() {
        let mut doc: Table = toml::from_str(TEXT).expect("toml");
        remove(&mut doc, "map.resolution_m");
        remove(&mut doc, "map.nothing.here");
        assert!(doc["map"].as_table().is_some_and(Table::is_empty));
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

    #[test]
    fn junk_after_a_value_is_an_error_naming_the_override() {
        for (text, value) in [
            ("map.resolution_m=0.1", Value::Float(0.1)),
            ("input.pcd_frame=optical", Value::String("optical".into())),
            (
                "robot.urdf=robots/p3at.urdf",
                Value::String("robots/p3at.urdf".into()),
            ),
            ("map.preset=\"robust\"", Value::String("robust".into())),
            (
                "a=[1.0, 2.0]",
                Value::Array(vec![Value::Float(1.0), Value::Float(2.0)]),
            ),
        ] {
            assert_eq!(Override::parse(text).expect(text).value, value, "{text}");
        }
        for text in [
            "map.resolution_m=0.1 # coarse",
            "map.resolution_m=0.1#x",
            "map.resolution_m=[1.0, 2.0] x",
            "map.resolution_m=0.1 junk",
            "name=1\nseed = 2",
            "a=\"open",
        ] {
            let e = Override::parse(text).expect_err(text).to_string();
            assert!(e.starts_with(&format!("--set {text}: ")), "{e}");
            assert!(e.contains("is not one value"), "{e}");
        }
    }
}
