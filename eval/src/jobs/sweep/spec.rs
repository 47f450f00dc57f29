//! Sweep files (`docs/sweep-format.md`): the schema and its checks. Every error names the file, the line and
//! the column, as scenario errors do.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use sim::scenario::KeySeg;
use toml::Value;

use super::generate::GenerateSpec;
use crate::error::{EvalError, Result};

/// The most runs a sweep may plan (a study of 100,000 runs is a cluster's week).
pub const MAX_RUNS: usize = 100_000;
/// The most values one axis may hold.
pub const MAX_AXIS_VALUES: usize = 10_000;
/// The most replicates.
pub const MAX_SEEDS: u32 = 10_000;
/// The most axes (every axis multiplies the plan; a study of more than a few is read by nobody).
pub const MAX_AXES: usize = 64;

/// A sweep file as written.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepSpec {
    /// Short name of the study.
    pub name: String,
    /// What the study asks.
    #[serde(default)]
    pub description: String,
    /// The sweep seed: each replicate's scenario seed is derived from it.
    pub seed: u64,
    /// Replicates of every combination of axis values (seeds derived from `seed`).
    #[serde(default = "one")]
    pub seeds: u32,
    /// How the axes combine.
    #[serde(default)]
    pub combine: Combine,
    /// Base scenario files, relative to the sweep file; several form the categorical axis `scenario`.
    #[serde(default)]
    pub scenarios: Vec<PathBuf>,
    /// Randomized scenes, instead of `scenarios`.
    #[serde(default)]
    pub generate: Option<GenerateSpec>,
    /// Overrides applied to every run, `--set` keys (`"map.resolution_m" = 0.1`).
    #[serde(default)]
    pub set: BTreeMap<String, Value>,
    /// Named model presets of the file, beside the built-in `paper` and `static`: `--set` keys and values.
    #[serde(default)]
    pub presets: BTreeMap<String, BTreeMap<String, Value>>,
    /// The axes.
    #[serde(default)]
    pub axes: Vec<AxisSpec>,
}

fn one() -> u32 {
    1
}

/// How the axes combine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Combine {
    /// Every combination of the axes' values.
    #[default]
    Product,
    /// The k-th values of every axis together (axes of equal length).
    Zip,
}

/// One axis as written: a `--set` key (or `preset`) and its values, given one way.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxisSpec {
    /// A key `--set` accepts, or `preset` for named model presets.
    pub key: String,
    /// Explicit values (numbers, strings, tables).
    #[serde(default)]
    pub values: Option<Vec<Value>>,
    /// `num` values evenly spaced from `start` to `stop`, both included.
    #[serde(default)]
    pub linspace: Option<Spaced>,
    /// `num` values evenly spaced on a log scale from `start` to `stop` (the values, not their exponents, as
    /// numpy's `geomspace`), both included.
    #[serde(default)]
    pub logspace: Option<Spaced>,
    /// `start`, `start + step`, ... up to `stop` (included when a whole number of steps away).
    #[serde(default)]
    pub range: Option<Stepped>,
}

/// `{ start, stop, num }`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spaced {
    /// First value.
    pub start: f64,
    /// Last value.
    pub stop: f64,
    /// Number of values.
    pub num: u32,
}

/// `{ start, stop, step }`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Stepped {
    /// First value.
    pub start: f64,
    /// Last value (bound).
    pub stop: f64,
    /// Step, of the sign of `stop - start`.
    pub step: f64,
}

/// An axis with its values.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// The `--set` key, or `preset`.
    pub key: String,
    /// Its values.
    pub values: Vec<Value>,
}

impl Axis {
    /// Whether every value is a number (plotted along x); otherwise the axis is categorical.
    pub fn is_numeric(&self) -> bool {
        self.values
            .iter()
            .all(|v| matches!(v, Value::Float(_) | Value::Integer(_)))
    }
}

/// A sweep file, read and checked.
#[derive(Debug, Clone)]
pub struct Sweep {
    /// The file.
    pub path: PathBuf,
    /// Its text.
    pub text: String,
    /// What it says.
    pub spec: SweepSpec,
    /// Its axes with their values.
    pub axes: Vec<Axis>,
    /// `--set` overrides from the command line, applied to every run after the file's `set`.
    pub overrides: Vec<crate::settings::overrides::Override>,
}

impl Sweep {
    /// Reads and checks a sweep file.
    ///
    /// # Errors
    /// [`EvalError::At`] with file, line and column: syntax, an unknown key, a value of the wrong type, an
    /// empty axis, a range with step 0, a generator range with min above max, an unknown preset.
    pub fn load(path: &Path) -> Result<Self> {
        let text = oeg_files::read_text(path)?;
        Self::from_str(path, &text)
    }

    /// As [`Sweep::load`], from text already read.
    ///
    /// # Errors
    /// As [`Sweep::load`].
    pub fn from_str(path: &Path, text: &str) -> Result<Self> {
        let spec: SweepSpec = toml::from_str(text).map_err(|e| EvalError::At {
            path: path.to_path_buf(),
            position: e.span().map(|s| sim::TextPosition::of_offset(text, s.start)),
            message: e.message().trim().to_string(),
        })?;
        let mut sweep = Self {
            path: path.to_path_buf(),
            text: text.to_string(),
            spec,
            axes: Vec::new(),
            overrides: Vec::new(),
        };
        sweep.axes = sweep.check()?;
        Ok(sweep)
    }

    /// The sweep with `--set` overrides from the command line (`key=value` each), applied to every run after
    /// the preset and the file's `set` and before the other axes, so an axis still sets its key.
    ///
    /// # Errors
    /// A malformed override, named.
    pub fn with_overrides(mut self, overrides: &[String]) -> Result<Self> {
        self.overrides = overrides
            .iter()
            .map(|o| crate::settings::overrides::Override::parse(o))
            .collect::<std::result::Result<_, _>>()
            .map_err(EvalError::Setting)?;
        Ok(self)
    }

    /// An error at the value of `at` in the file.
    pub fn error(&self, at: &[KeySeg<'_>], message: impl Into<String>) -> EvalError {
        EvalError::At {
            path: self.path.clone(),
            position: sim::scenario::position_of(&self.text, at),
            message: message.into(),
        }
    }

    /// A path the file mentions, relative to the file's folder.
    pub fn resolve(&self, relative: &Path) -> PathBuf {
        self.path
            .parent()
            .map_or_else(|| relative.to_path_buf(), |dir| dir.join(relative))
    }

    /// Checks the file's values for sense, part by part, and expands its axes' values.
    fn check(&self) -> Result<Vec<Axis>> {
        self.check_header()?;
        self.check_set_and_presets()?;
        let axes = self.check_axes()?;
        self.check_zip(&axes)?;
        Ok(axes)
    }

    /// The name, the replicates, and where the scenarios come from.
    fn check_header(&self) -> Result<()> {
        use KeySeg::Key as K;
        let s = &self.spec;
        if s.name.trim().is_empty()
            || !s
                .name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
        {
            return Err(self.error(
                &[K("name")],
                format!(
                    "`{}`: expected a name of letters, digits, '-', '_' or '.'",
                    s.name
                ),
            ));
        }
        if s.seeds == 0 || s.seeds > MAX_SEEDS {
            return Err(self.error(
                &[K("seeds")],
                format!("expected 1 to {MAX_SEEDS} replicates, got {}", s.seeds),
            ));
        }
        match (s.scenarios.is_empty(), &s.generate) {
            (true, None) => {
                return Err(self.error(
                    &[],
                    "expected `scenarios = [...]` (base scenario files) or a `[generate]` table",
                ));
            }
            (false, Some(_)) => {
                return Err(self.error(
                    &[K("generate")],
                    "give either `scenarios` or `[generate]`, not both (the generator has its own `base`)",
                ));
            }
            _ => {}
        }
        if let Some(g) = &s.generate {
            g.check(|at, message| {
                let mut path = vec![K("generate")];
                path.extend_from_slice(at);
                self.error(&path, message)
            })?;
        }
        Ok(())
    }

    /// `set` and the file's own presets: keys that parse, names that are not built in.
    fn check_set_and_presets(&self) -> Result<()> {
        use KeySeg::Key as K;
        let s = &self.spec;
        for key in s.set.keys() {
            crate::settings::overrides::check_key(key)
                .map_err(|e| self.error(&[K("set")], format!("`{key}`: {e}")))?;
        }
        for (name, preset) in &s.presets {
            if oeg::MapPreset::ALL.iter().any(|p| p.name() == name) {
                return Err(self.error(
                    &[K("presets"), K(name)],
                    format!("`{name}` is a built-in preset; give yours another name"),
                ));
            }
            for key in preset.keys() {
                crate::settings::overrides::check_key(key)
                    .map_err(|e| self.error(&[K("presets"), K(name)], format!("`{key}`: {e}")))?;
            }
        }
        Ok(())
    }

    /// Every axis in turn ([`Sweep::check_axis`]), within [`MAX_AXES`].
    fn check_axes(&self) -> Result<Vec<Axis>> {
        use KeySeg::{Index as I, Key as K};
        let s = &self.spec;
        if s.axes.len() > MAX_AXES {
            return Err(self.error(
                &[K("axes"), I(MAX_AXES)],
                format!(
                    "{} axes; at most {MAX_AXES} (each axis multiplies the runs: put fixed values in `set`)",
                    s.axes.len()
                ),
            ));
        }
        let mut axes = Vec::new();
        for (k, a) in s.axes.iter().enumerate() {
            let values = self.check_axis(k, a, &axes)?;
            axes.push(Axis {
                key: a.key.clone(),
                values,
            });
        }
        Ok(axes)
    }

    /// Axis `k`: its key (not the key of an earlier axis, nor overlapping one), exactly one way of giving its
    /// values, and the values themselves (known presets on the preset axis).
    fn check_axis(&self, k: usize, a: &AxisSpec, axes: &[Axis]) -> Result<Vec<Value>> {
        use KeySeg::{Index as I, Key as K};
        let s = &self.spec;
        let at = |field: &'static str| [K("axes"), I(k), K(field)];
        crate::settings::overrides::check_key(&a.key).map_err(|e| self.error(&at("key"), e.to_string()))?;
        if a.key == "scenario" && s.scenarios.len() > 1 {
            return Err(self.error(
                &at("key"),
                "several `scenarios` are the axis `scenario` already; remove this axis",
            ));
        }
        if let Some(b) = axes.iter().find(|b: &&Axis| keys_overlap(&b.key, &a.key)) {
            return Err(self.error(
                &at("key"),
                if b.key == a.key {
                    format!("a second axis on `{}`", a.key)
                } else {
                    format!(
                        "axes `{}` and `{}` set some of the same values, so one would silently replace \
                         the other; give each value one axis",
                        b.key, a.key
                    )
                },
            ));
        }
        let given = [
            a.values.is_some(),
            a.linspace.is_some(),
            a.logspace.is_some(),
            a.range.is_some(),
        ];
        if given.iter().filter(|g| **g).count() != 1 {
            return Err(self.error(
                &[K("axes"), I(k)],
                format!(
                    "axis `{}`: expected exactly one of `values`, `linspace`, `logspace` or `range`",
                    a.key
                ),
            ));
        }
        let values = if let Some(v) = &a.values {
            v.clone()
        } else if let Some(l) = a.linspace {
            spaced(l, false).map_err(|e| self.error(&at("linspace"), format!("axis `{}`: {e}", a.key)))?
        } else if let Some(l) = a.logspace {
            spaced(l, true).map_err(|e| self.error(&at("logspace"), format!("axis `{}`: {e}", a.key)))?
        } else if let Some(r) = a.range {
            stepped(r).map_err(|e| self.error(&at("range"), format!("axis `{}`: {e}", a.key)))?
        } else {
            Vec::new()
        };
        let field = if a.values.is_some() {
            "values"
        } else if a.linspace.is_some() {
            "linspace"
        } else if a.logspace.is_some() {
            "logspace"
        } else {
            "range"
        };
        if values.is_empty() {
            return Err(self.error(&at(field), format!("axis `{}` has no values", a.key)));
        }
        if values.len() > MAX_AXIS_VALUES {
            return Err(self.error(
                &at(field),
                format!(
                    "axis `{}` has {} values; at most {MAX_AXIS_VALUES}",
                    a.key,
                    values.len()
                ),
            ));
        }
        if a.key == super::presets::PRESET_KEY {
            for (j, v) in values.iter().enumerate() {
                let known = v.as_str().is_some_and(|name| self.preset(name).is_some());
                if !known {
                    let at: Vec<KeySeg<'_>> = vec![K("axes"), I(k), K("values"), I(j)];
                    return Err(self.error(
                        &at,
                        format!("unknown preset {v}; presets: {}", self.preset_names().join(", ")),
                    ));
                }
            }
        }
        Ok(values)
    }

    /// `combine = "zip"` needs axes of equal length.
    fn check_zip(&self, axes: &[Axis]) -> Result<()> {
        use KeySeg::{Index as I, Key as K};
        let s = &self.spec;
        if s.combine == Combine::Zip
            && let Some(first) = axes.first()
            && let Some((k, other)) = axes
                .iter()
                .enumerate()
                .find(|(_, a)| a.values.len() != first.values.len())
        {
            return Err(self.error(
                &[K("axes"), I(k)],
                format!(
                    "`combine = \"zip\"` needs axes of equal length: `{}` has {} values, `{}` has {}",
                    first.key,
                    first.values.len(),
                    other.key,
                    other.values.len()
                ),
            ));
        }
        Ok(())
    }

    /// How many runs the plan will have: base scenarios x combinations of axis values x replicates (saturating,
    /// so an absurd file is counted without overflow).
    pub fn num_planned_runs(&self) -> u128 {
        let s = &self.spec;
        let num_combos = match s.combine {
            Combine::Zip => self.axes.first().map_or(1, |a| a.values.len() as u128),
            Combine::Product => self
                .axes
                .iter()
                .fold(1u128, |n, a| n.saturating_mul(a.values.len() as u128)),
        };
        let num_bases = if s.generate.is_some() {
            1
        } else {
            s.scenarios.len()
        };
        (num_bases as u128)
            .saturating_mul(num_combos)
            .saturating_mul(u128::from(s.seeds))
    }

    /// The overrides of a preset by name: the file's own, or a built-in one.
    pub fn preset(&self, name: &str) -> Option<Vec<(String, Option<Value>)>> {
        if let Some(p) = self.spec.presets.get(name) {
            return Some(p.iter().map(|(k, v)| (k.clone(), Some(v.clone()))).collect());
        }
        super::presets::built_in(name)
    }

    /// Every preset name the file may use.
    pub fn preset_names(&self) -> Vec<String> {
        oeg::MapPreset::ALL
            .iter()
            .map(|p| p.name().to_string())
            .chain(self.spec.presets.keys().cloned())
            .collect()
    }
}

/// Whether two `--set` keys can name the same value: segment by segment equal or `*`, up to the shorter key
/// (`sensors.*.x` and `sensors.0.x`; `map.model` and `map.model.p_max`). The preset axis sets keys of its own
/// by design, before the other axes.
fn keys_overlap(a: &str, b: &str) -> bool {
    let preset = super::presets::PRESET_KEY;
    a != preset
        && b != preset
        && a.split('.')
            .zip(b.split('.'))
            .all(|(x, y)| x == y || x == "*" || y == "*")
}

fn spaced(l: Spaced, log: bool) -> std::result::Result<Vec<Value>, String> {
    if !(l.start.is_finite() && l.stop.is_finite()) {
        return Err(format!(
            "expected finite start and stop, got {} and {}",
            l.start, l.stop
        ));
    }
    if l.num == 0 {
        return Err("`num = 0` gives an empty axis; expected at least 1 value".into());
    }
    if l.num as usize > MAX_AXIS_VALUES {
        return Err(format!("`num = {}`: at most {MAX_AXIS_VALUES} values", l.num));
    }
    if log && (l.start <= 0.0 || l.stop <= 0.0) {
        return Err(format!(
            "a log scale needs positive start and stop, got {} and {}",
            l.start, l.stop
        ));
    }
    let n = l.num;
    Ok((0..n)
        .map(|k| {
            let t = if n == 1 {
                0.0
            } else {
                f64::from(k) / f64::from(n - 1)
            };
            let v = if log {
                (l.start.ln() + t * (l.stop.ln() - l.start.ln())).exp()
            } else {
                l.start + t * (l.stop - l.start)
            };
            Value::Float(tidy(v))
        })
        .collect())
}

fn stepped(r: Stepped) -> std::result::Result<Vec<Value>, String> {
    if !(r.start.is_finite() && r.stop.is_finite() && r.step.is_finite()) {
        return Err("expected finite start, stop and step".into());
    }
    if r.step == 0.0 {
        return Err("`step = 0` never reaches `stop`; expected a non-zero step".into());
    }
    let span = r.stop - r.start;
    if span != 0.0 && span.signum() != r.step.signum() {
        return Err(format!(
            "step {} leads away from stop {} (start {}); expected a step of the sign of stop - start",
            r.step, r.stop, r.start
        ));
    }
    // A whole number of steps, with a tolerance for decimal steps (0.1 is not exact in binary).
    let count = (span / r.step + 1e-9).floor() + 1.0;
    if count > MAX_AXIS_VALUES as f64 {
        return Err(format!("{count} values; at most {MAX_AXIS_VALUES}"));
    }
    Ok((0..count as u32)
        .map(|k| Value::Float(tidy(r.start + f64::from(k) * r.step)))
        .collect())
}

/// A computed axis value rounded to 12 significant digits: `0.1 * 3` is written `0.3`, not
/// `0.30000000000000004`, so ids and columns read as the user meant.
fn tidy(v: f64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let digits = 12 - v.abs().log10().ceil() as i32;
    let scale = 10f64.powi(digits.clamp(-300, 300));
    (v * scale).round() / scale
}

#[cfg(test)]
mod tests {
    use super::*;

    fn load(text: &str) -> Result<Sweep> {
        Sweep::from_str(Path::new("study.toml"), text)
    }

    const HEAD: &str = "name = \"s\"\nseed = 1\nscenarios = [\"a.toml\"]\n";

    #[test]
    fn ranges_give_the_documented_values() {
        let s = load(&format!(
            "{HEAD}[[axes]]\nkey = \"a\"\nlinspace = {{ start = 0.0, stop = 0.05, num = 6 }}\n\
             [[axes]]\nkey = \"b\"\nlogspace = {{ start = 0.001, stop = 0.1, num = 3 }}\n\
             [[axes]]\nkey = \"c\"\nrange = {{ start = 0.0, stop = 0.3, step = 0.1 }}\n"
        ))
        .expect("valid");
        let floats = |k: usize| -> Vec<f64> { s.axes[k].values.iter().filter_map(Value::as_float).collect() };
        assert_eq!(floats(0), vec![0.0, 0.01, 0.02, 0.03, 0.04, 0.05]);
        assert_eq!(floats(1), vec![0.001, 0.01, 0.1]);
        assert_eq!(floats(2), vec![0.0, 0.1, 0.2, 0.3]);
        assert!(s.axes.iter().all(Axis::is_numeric));
    }

    #[test]
    fn bad_axes_are_errors_at_their_place() {
        for (axis, line_col, expected) in [
            ("key = \"a\"\nvalues = []", "6:10", "has no values"),
            (
                "key = \"a\"\nlinspace = { start = 0.0, stop = 1.0, num = 0 }",
                "6:12",
                "empty axis",
            ),
            (
                "key = \"a\"\nrange = { start = 0.0, stop = 1.0, step = 0.0 }",
                "6:9",
                "step = 0",
            ),
            (
                "key = \"a\"\nrange = { start = 0.0, stop = 1.0, step = -0.1 }",
                "6:9",
                "leads away",
            ),
            (
                "key = \"a\"\nlogspace = { start = 0.0, stop = 1.0, num = 3 }",
                "6:12",
                "positive",
            ),
            ("key = \"a\"", "4:1", "exactly one of"),
            (
                "key = \"preset\"\nvalues = [\"paper\", \"fast\"]",
                "6:20",
                "unknown preset \"fast\"",
            ),
            (
                "key = \"a\"\nvalues = [1]\nstep = 2",
                "7:1",
                "unknown field `step`",
            ),
        ] {
            let err = load(&format!("{HEAD}[[axes]]\n{axis}\n"))
                .expect_err(axis)
                .to_string();
            assert!(
                err.starts_with(&format!("study.toml:{line_col}: ")),
                "{axis}: {err}"
            );
            assert!(err.contains(expected), "{axis}: {err}");
        }
    }

    #[test]
    fn zip_needs_equal_lengths() {
        let err = load(&format!(
            "{HEAD}combine = \"zip\"\n[[axes]]\nkey = \"a\"\nvalues = [1, 2]\n[[axes]]\nkey = \"b\"\nvalues = [1]\n"
        ))
        .expect_err("unequal")
        .to_string();
        assert!(err.contains("equal length"), "{err}");
    }

    #[test]
    fn overlapping_axes_are_refused_at_the_second() {
        for (a, b) in [
            ("sensors.*.x", "sensors.0.x"),
            ("sensors.0.x", "sensors.*.x"),
            ("map.model", "map.model.p_max"),
            ("map.resolution_m", "map.resolution_m"),
        ] {
            let err = load(&format!(
                "{HEAD}[[axes]]\nkey = \"{a}\"\nvalues = [1]\n[[axes]]\nkey = \"{b}\"\nvalues = [2]\n"
            ))
            .expect_err(b)
            .to_string();
            assert!(err.starts_with("study.toml:8:7: "), "{a} {b}: {err}");
            assert!(err.contains(&format!("`{b}`")), "{err}");
        }
        load(&format!(
            "{HEAD}[[axes]]\nkey = \"sensors.0.x\"\nvalues = [1]\n[[axes]]\nkey = \"sensors.1.x\"\nvalues = [2]\n\
             [[axes]]\nkey = \"preset\"\nvalues = [\"paper\"]\n"
        ))
        .expect("different sensors, and the preset axis");
    }

    #[test]
    fn the_number_of_axes_is_bounded_before_any_is_checked() {
        let axes: String = (0..100_000)
            .map(|k| format!("[[axes]]\nkey = \"k{k}\"\nvalues = [1]\n"))
            .collect();
        let err = load(&format!("{HEAD}{axes}")).expect_err("too many").to_string();
        assert!(err.contains(&format!("100000 axes; at most {MAX_AXES}")), "{err}");
        assert!(err.starts_with("study.toml:"), "{err}");
    }
}
