//! A sweep's plan: every run with its fully resolved scenario, its id and the simulation it shares.
//!
//! A run's scenario is resolved in one order, whatever the order of the axes in the file: the base scenario,
//! the generated scene (from the replicate's seed), the preset, the file's `set`, the command line's `--set`,
//! then the other axes (by key). Its id
//! is a hash of that resolved scenario (and of the base file's name as the sweep file writes it), so
//! reordering axes or the values of an axis changes no id, and two runs with the same id are the same run.

use std::path::{Path, PathBuf};

use rand::RngExt;
use serde::Serialize;
use toml::{Table, Value};

use super::spec::{Combine, MAX_RUNS, Sweep};
use crate::error::{EvalError, Result};
use crate::settings::SettingError;
use crate::settings::overrides::Override;

/// One run of the plan.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// Hash of the resolved scenario, 16 hex digits.
    pub id: String,
    /// Hash of the part of the scenario the simulation depends on: runs with the same group share it.
    pub group: String,
    /// The base scenario file (as the sweep file names it, resolved against its folder).
    pub base: PathBuf,
    /// Label of the base scenario: its file stem.
    pub scenario: String,
    /// Replicate number, from 0.
    pub replicate: u32,
    /// The scenario seed of this replicate.
    pub seed: u64,
    /// Value of each axis, in the file's order.
    pub axis_values: Vec<(String, Value)>,
    /// The resolved scenario.
    pub doc: Table,
}

/// The plan of a sweep.
#[derive(Debug, Clone)]
pub struct SweepPlan {
    /// The sweep.
    pub sweep: Sweep,
    /// Every run, in the order of the file: base scenarios, then axis combinations, then replicates.
    pub runs: Vec<Run>,
}

/// A run as `plan.json` lists it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlannedRun<'a> {
    /// The id.
    pub id: &'a str,
    /// The shared-simulation group.
    pub group: &'a str,
    /// The base scenario's label.
    pub scenario: &'a str,
    /// The replicate.
    pub replicate: u32,
    /// The seed.
    pub seed: u64,
    /// Axis values.
    pub axes: serde_json::Map<String, serde_json::Value>,
}

/// Keys that do not change the simulation: runs differing only in these share one.
const MAP_ONLY_KEYS: [&str; 8] = [
    "map.preset",
    "map.model",
    "map.traversability",
    "map.resolution_m",
    "planner",
    "expectations",
    "name",
    "description",
];

/// The scenario seed of replicate `r` of a sweep seeded with `seed` (63 bits: TOML integers are signed).
pub fn replicate_seed(seed: u64, r: u32) -> u64 {
    sim::seed::stream(seed, &format!("replicate/{r}")).random::<u64>() >> 1
}

/// A TOML value as JSON, for rows and `plan.json`.
pub fn to_json(v: &Value) -> serde_json::Value {
    serde_json::to_value(v).unwrap_or(serde_json::Value::Null)
}

/// A hash of a document, 16 hex digits.
fn digest(prefix: &str, doc: &Table) -> String {
    let text = format!("{prefix}\n{}", toml::to_string(doc).unwrap_or_default());
    format!("{:016x}", oeg_files::fnv1a64(text.as_bytes()))
}

impl SweepPlan {
    /// Resolves every run of a sweep and checks each scenario (as `oeg validate` does).
    ///
    /// # Errors
    /// A base scenario that cannot be read, a plan larger than [`MAX_RUNS`], or a run whose scenario is
    /// invalid: the error names the axis values and the sweep file's place.
    pub fn new(sweep: Sweep) -> Result<Self> {
        use sim::scenario::KeySeg::{Index as I, Key as K};
        let spec = &sweep.spec;
        let bases: Vec<(PathBuf, PathBuf)> = match &spec.generate {
            Some(g) => vec![(g.base.clone(), sweep.resolve(&g.base))],
            None => spec
                .scenarios
                .iter()
                .map(|p| (p.clone(), sweep.resolve(p)))
                .collect(),
        };
        // The size is counted before anything is built: five axes of 10,000 values must be an error, not an
        // exhausted machine.
        let total = sweep.num_planned_runs();
        if total > MAX_RUNS as u128 {
            return Err(sweep.error(
                &[K("axes")],
                format!("the plan has {total} runs, over the limit of {MAX_RUNS}; use fewer values or seeds"),
            ));
        }
        let total = total as usize;
        let labels = scenario_labels(&bases);
        let combos = combinations(&sweep);
        let mut runs = Vec::with_capacity(total);
        for (k, (written, base)) in bases.iter().enumerate() {
            let at_base: Vec<sim::scenario::KeySeg<'_>> = if spec.generate.is_some() {
                vec![K("generate"), K("base")]
            } else {
                vec![K("scenarios"), I(k)]
            };
            let text = oeg_files::read_text(base)
                .map_err(|e| sweep.error(&at_base, format!("cannot read the base scenario: {e}")))?;
            let base_doc: Table = toml::from_str(&text).map_err(|e| EvalError::At {
                path: base.clone(),
                position: e.span().map(|s| sim::TextPosition::of_offset(&text, s.start)),
                message: e.message().trim().to_string(),
            })?;
            let label = labels[k].clone();
            check_set_against(&sweep, &base_doc, base)
                .and_then(|()| check_overrides(&sweep, &base_doc, base))
                .and_then(|()| check_axes_against(&sweep, &base_doc, base))
                .map_err(|e| base_error(&sweep, base, &text).unwrap_or(e))?;
            for combo in &combos {
                for r in 0..spec.seeds {
                    let seed = replicate_seed(spec.seed, r);
                    let doc = resolve(&sweep, &base_doc, combo, seed).map_err(|message| {
                        sweep.error(&[K("axes")], format!("{}: {message}", describe(combo)))
                    })?;
                    let prefix = format!("scenario={}", written.display());
                    let mut sim_doc = doc.clone();
                    for key in MAP_ONLY_KEYS {
                        crate::settings::overrides::remove(&mut sim_doc, key);
                    }
                    let id = digest(&prefix, &doc);
                    // A closed-loop run's map decides where the robot drives: it shares its simulation
                    // with no other run.
                    let group = if doc.contains_key("navigation") {
                        id.clone()
                    } else {
                        digest(&prefix, &sim_doc)
                    };
                    runs.push(Run {
                        id,
                        group,
                        base: base.clone(),
                        scenario: label.clone(),
                        replicate: r,
                        seed,
                        axis_values: combo.clone(),
                        doc,
                    });
                }
            }
        }
        let plan = Self { sweep, runs };
        plan.check_runs()?;
        Ok(plan)
    }

    /// Loads every resolved scenario as `oeg run` would.
    fn check_runs(&self) -> Result<()> {
        for run in &self.runs {
            run.load().map_err(|e| {
                if let Some(own) = oeg_files::read_text(&run.base)
                    .ok()
                    .and_then(|text| base_error(&self.sweep, &run.base, &text))
                {
                    return own;
                }
                // The resolved scenario is a rewritten text: its lines are nobody's, so the error points at
                // the sweep file's axes and names the base.
                self.sweep.error(
                    &[sim::scenario::KeySeg::Key("axes")],
                    format!(
                        "run {} ({}, seed {}) on {}: {}",
                        run.id,
                        describe(&run.axis_values),
                        run.seed,
                        run.base.display(),
                        message_of(&e)
                    ),
                )
            })?;
        }
        let mut ids: Vec<&str> = self.runs.iter().map(|r| r.id.as_str()).collect();
        ids.sort_unstable();
        if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
            return Err(self.sweep.error(
                &[sim::scenario::KeySeg::Key("axes")],
                format!(
                    "two runs resolve to the same scenario (id {}): an axis value changes nothing",
                    w[0]
                ),
            ));
        }
        Ok(())
    }

    /// Runs of shard `i` of `n` (1-based): the ids in sorted order, dealt round-robin. Deterministic by id.
    pub fn shard(&self, i: usize, n: usize) -> Vec<&Run> {
        let mut ids: Vec<&str> = self.runs.iter().map(|r| r.id.as_str()).collect();
        ids.sort_unstable();
        let mine: std::collections::BTreeSet<&str> = ids
            .iter()
            .enumerate()
            .filter(|(k, _)| k % n == i - 1)
            .map(|(_, id)| *id)
            .collect();
        self.runs
            .iter()
            .filter(|r| mine.contains(r.id.as_str()))
            .collect()
    }

    /// The plan as `plan.json` lists it.
    pub fn listing(&self) -> serde_json::Value {
        let runs: Vec<PlannedRun<'_>> = self
            .runs
            .iter()
            .map(|r| PlannedRun {
                id: &r.id,
                group: &r.group,
                scenario: &r.scenario,
                replicate: r.replicate,
                seed: r.seed,
                axes: r
                    .axis_values
                    .iter()
                    .map(|(k, v)| (k.clone(), to_json(v)))
                    .collect(),
            })
            .collect();
        let axes: Vec<serde_json::Value> = self
            .sweep
            .axes
            .iter()
            .map(|a| {
                serde_json::json!({
                    "key": a.key,
                    "numeric": a.is_numeric(),
                    "values": a.values.iter().map(to_json).collect::<Vec<_>>(),
                })
            })
            .collect();
        serde_json::json!({
            "sweep": self.sweep.spec.name,
            "file": self.sweep.path.display().to_string(),
            "num_runs": self.runs.len(),
            "num_simulations": self.num_groups(),
            "axes": axes,
            "runs": runs,
        })
    }

    /// Distinct simulations.
    pub fn num_groups(&self) -> usize {
        let groups: std::collections::BTreeSet<&str> = self.runs.iter().map(|r| r.group.as_str()).collect();
        groups.len()
    }
}

impl Run {
    /// The resolved scenario as a TOML file's text, paths made absolute so it runs from anywhere.
    pub fn scenario_text(&self) -> String {
        let mut doc = self.doc.clone();
        let dir = self.base.parent().unwrap_or(Path::new("."));
        let absolute = |p: &str| {
            let joined = dir.join(p);
            std::path::absolute(&joined)
                .unwrap_or(joined)
                .display()
                .to_string()
        };
        if let Some(Value::Table(robot)) = doc.get_mut("robot")
            && let Some(Value::String(urdf)) = robot.get_mut("urdf")
        {
            *urdf = absolute(urdf);
        }
        if let Some(Value::Table(terrain)) = doc.get_mut("terrain")
            && let Some(Value::String(path)) = terrain.get_mut("path")
        {
            *path = absolute(path);
        }
        let header = format!(
            "# Run {} of a sweep ({}, seed {}): a plain scenario, `oeg run` reproduces it.\n",
            self.id,
            describe(&self.axis_values),
            self.seed
        );
        header + &toml::to_string(&doc).unwrap_or_default()
    }

    /// Loads the resolved scenario (named after the base file, so relative paths resolve as there).
    ///
    /// # Errors
    /// An invalid scenario.
    pub fn load(&self) -> Result<sim::LoadedScenario> {
        let text = toml::to_string(&self.doc).map_err(|e| EvalError::Input {
            path: self.base.clone(),
            message: format!("cannot write the resolved scenario: {e}"),
        })?;
        load_resolved(&self.base, &text)
    }
}

/// `key=value, key=value` of a combination.
pub fn describe(combo: &[(String, Value)]) -> String {
    if combo.is_empty() {
        return "no axes".into();
    }
    combo
        .iter()
        .map(|(k, v)| format!("{k}={v}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The axis value combinations, in the file's order (the last axis varies fastest).
fn combinations(sweep: &Sweep) -> Vec<Vec<(String, Value)>> {
    let axes = &sweep.axes;
    if axes.is_empty() {
        return vec![Vec::new()];
    }
    match sweep.spec.combine {
        Combine::Zip => (0..axes[0].values.len())
            .map(|k| {
                axes.iter()
                    .map(|a| (a.key.clone(), a.values[k].clone()))
                    .collect()
            })
            .collect(),
        Combine::Product => {
            let mut out: Vec<Vec<(String, Value)>> = vec![Vec::new()];
            for a in axes {
                out = out
                    .into_iter()
                    .flat_map(|prefix| {
                        a.values.iter().map(move |v| {
                            let mut c = prefix.clone();
                            c.push((a.key.clone(), v.clone()));
                            c
                        })
                    })
                    .collect();
            }
            out
        }
    }
}

/// One run's scenario: base, generated scene, preset, `set`, `--set`, axes (sorted by key), seed.
fn resolve(
    sweep: &Sweep,
    base: &Table,
    combo: &[(String, Value)],
    seed: u64,
) -> std::result::Result<Table, SettingError> {
    let mut doc = base.clone();
    doc.insert("seed".into(), Value::Integer(seed as i64));
    if let Some(g) = &sweep.spec.generate {
        g.place(seed, &mut doc);
    }
    let preset_key = super::presets::PRESET_KEY;
    if let Some((_, Value::String(name))) = combo.iter().find(|(k, _)| k == preset_key) {
        for (key, value) in sweep.preset(name).unwrap_or_default() {
            match value {
                Some(v) => Override::new(&key, v).apply_to(&mut doc)?,
                None => crate::settings::overrides::remove(&mut doc, &key),
            }
        }
    }
    // The file's `set` and the command line's `--set` hold for every preset; an axis on the same key wins.
    for (key, value) in &sweep.spec.set {
        Override::new(key, value.clone()).apply_to(&mut doc)?;
    }
    for o in &sweep.overrides {
        o.apply_to(&mut doc)?;
    }
    let mut sorted: Vec<&(String, Value)> = combo.iter().filter(|(k, _)| k != preset_key).collect();
    sorted.sort_by(|a, b| a.0.cmp(&b.0));
    for (key, value) in sorted {
        Override::new(key, value.clone()).apply_to(&mut doc)?;
    }
    // The seed is the replicate's, whatever an axis said: `seeds` is how a sweep varies it.
    doc.insert("seed".into(), Value::Integer(seed as i64));
    Ok(doc)
}

/// Loads a scenario text as `oeg run` and `oeg validate` do: the file's checks, then its expectations (so a
/// run's `scenario.toml` reproduces it).
fn load_resolved(base: &Path, text: &str) -> Result<sim::LoadedScenario> {
    let loaded = sim::scenario::load_str(base, text)?;
    crate::pipeline::check_expectations(&loaded, text)?;
    Ok(loaded)
}

/// [`load_resolved`] of a resolved document: the message of what is wrong, without a place in the rewritten
/// text.
fn check_resolved(base: &Path, doc: &Table) -> std::result::Result<(), SettingError> {
    let text = toml::to_string(doc).map_err(|e| SettingError::invalid(e.to_string()))?;
    load_resolved(base, &text)
        .map(|_| ())
        .map_err(|e| SettingError::invalid(message_of(&e)))
}

/// When a resolved run fails, the base scenario's own error, if the base alone (as its file says, with its
/// own lines) fails too. A generator's base is not judged alone: its drive, planner, region and duration are
/// replaced.
fn base_error(sweep: &Sweep, base: &Path, text: &str) -> Option<EvalError> {
    if sweep.spec.generate.is_some() {
        return None;
    }
    load_resolved(base, text).err()
}

/// An error's message without a place in a rewritten text.
fn message_of(e: &EvalError) -> String {
    match e {
        EvalError::Sim(e) => crate::pipeline::scenario_message(e),
        EvalError::At { message, .. } => message.clone(),
        other => other.to_string(),
    }
}

/// The `scenario` column of each base: its file name without `.toml`, or, where two bases share a name (in
/// different folders), the path the sweep file gives, so two scenarios are never pooled into one.
fn scenario_labels(bases: &[(PathBuf, PathBuf)]) -> Vec<String> {
    let stem = |p: &Path| {
        p.file_stem()
            .map_or_else(|| "scenario".into(), |s| s.to_string_lossy().into_owned())
    };
    let stems: Vec<String> = bases.iter().map(|(_, base)| stem(base)).collect();
    let mut uses: std::collections::BTreeMap<&str, usize> = std::collections::BTreeMap::new();
    for s in &stems {
        *uses.entry(s).or_default() += 1;
    }
    bases
        .iter()
        .zip(&stems)
        .map(|((written, _), s)| {
            if uses[s.as_str()] > 1 {
                written.with_extension("").to_string_lossy().into_owned()
            } else {
                s.clone()
            }
        })
        .collect()
}

/// The file's `set` entries on a base: when together they make the scenario invalid, the first after which it
/// no longer reads is reported at its own line (keys that only make sense together, a region's two corners,
/// are fine together).
fn check_set_against(sweep: &Sweep, base_doc: &Table, base: &Path) -> Result<()> {
    use sim::scenario::KeySeg::Key as K;
    let seed = replicate_seed(sweep.spec.seed, 0);
    let mut start = base_doc.clone();
    start.insert("seed".into(), Value::Integer(seed as i64));
    if let Some(g) = &sweep.spec.generate {
        g.place(seed, &mut start);
    }
    let check = |doc: &Table| check_resolved(base, doc);
    let apply =
        |doc: &mut Table, key: &String, value: &Value| Override::new(key, value.clone()).apply_to(doc);
    let mut all = start.clone();
    let together = sweep
        .spec
        .set
        .iter()
        .try_for_each(|(key, value)| apply(&mut all, key, value))
        .and_then(|()| check(&all));
    if together.is_ok() {
        return Ok(());
    }
    let mut doc = start;
    for (key, value) in &sweep.spec.set {
        if let Err(message) = apply(&mut doc, key, value).and_then(|()| check(&doc)) {
            return Err(sweep.error(
                &[K("set"), K(key)],
                format!("`{key}` = {value} on {}: {message}", base.display()),
            ));
        }
    }
    Ok(())
}

/// The command line's `--set` overrides on a base (with its first replicate's scene): one that makes the
/// scenario invalid is named.
fn check_overrides(sweep: &Sweep, base_doc: &Table, base: &Path) -> Result<()> {
    if sweep.overrides.is_empty() {
        return Ok(());
    }
    let mut bare = sweep.clone();
    bare.overrides.clear();
    let doc = resolve(&bare, base_doc, &[], replicate_seed(sweep.spec.seed, 0))?;
    let texts: Vec<String> = sweep.overrides.iter().map(|o| o.source.clone()).collect();
    crate::settings::resolve_with(&doc, &texts, |d| check_resolved(base, d)).map_err(|e| {
        EvalError::CommandLine {
            message: format!("{e} (on {})", base.display()),
        }
    })
}

/// Each axis alone (its first and last value) on a base: an unknown key or a value the scenario rejects is
/// reported at the axis, not at some run.
fn check_axes_against(sweep: &Sweep, base_doc: &Table, base: &Path) -> Result<()> {
    use sim::scenario::KeySeg::{Index as I, Key as K};
    for (k, axis) in sweep.axes.iter().enumerate() {
        if axis.key == super::presets::PRESET_KEY {
            continue;
        }
        let Some(last) = axis.values.last() else { continue };
        for v in [&axis.values[0], last] {
            let combo = vec![(axis.key.clone(), v.clone())];
            let seed = replicate_seed(sweep.spec.seed, 0);
            let checked = resolve(sweep, base_doc, &combo, seed).and_then(|doc| check_resolved(base, &doc));
            if let Err(message) = checked {
                return Err(sweep.error(
                    &[K("axes"), I(k), K("key")],
                    format!("axis `{}` = {v} on {}: {message}", axis.key, base.display()),
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(axes: &str) -> SweepPlan {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/scenes");
        let text = format!("name = \"t\"\nseed = 3\nseeds = 2\nscenarios = [\"person.toml\"]\n{axes}");
        let sweep = Sweep::from_str(&dir.join("t.toml"), &text).expect("sweep");
        SweepPlan::new(sweep).expect("plan")
    }

    const A: &str = "[[axes]]\nkey = \"map.resolution_m\"\nvalues = [0.05, 0.1]\n";
    const B: &str = "[[axes]]\nkey = \"sensors.*.noise.dropout_probability\"\nvalues = [0.0, 0.1, 0.2]\n";

    #[test]
    fn ids_do_not_depend_on_the_order_of_axes() {
        let ab = plan(&format!("{A}{B}"));
        let ba = plan(&format!("{B}{A}"));
        assert_eq!(ab.runs.len(), 12);
        let ids = |p: &SweepPlan| {
            let mut v: Vec<String> = p.runs.iter().map(|r| r.id.clone()).collect();
            v.sort();
            v
        };
        assert_eq!(ids(&ab), ids(&ba));
        // Runs differing only in map.resolution_m share a simulation.
        assert_eq!(ab.num_groups(), 6);
    }

    #[test]
    fn shards_cover_every_run_exactly_once() {
        let p = plan(&format!("{A}{B}"));
        for n in 1..=7 {
            let mut seen: Vec<&str> = (1..=n)
                .flat_map(|i| p.shard(i, n))
                .map(|r| r.id.as_str())
                .collect();
            seen.sort_unstable();
            let mut all: Vec<&str> = p.runs.iter().map(|r| r.id.as_str()).collect();
            all.sort_unstable();
            assert_eq!(seen, all, "n = {n}");
        }
    }

    #[test]
    fn a_huge_plan_is_refused_before_it_is_built() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/scenes");
        let mut text = "name = \"t\"\nseed = 3\nscenarios = [\"person.toml\"]\n".to_string();
        for k in 0..5 {
            text.push_str(&format!(
                "[[axes]]\nkey = \"a{k}\"\nlinspace = {{ start = 0.0, stop = 1.0, num = 10000 }}\n"
            ));
        }
        let sweep = Sweep::from_str(&dir.join("t.toml"), &text).expect("sweep");
        let err = SweepPlan::new(sweep).expect_err("too many").to_string();
        assert!(
            err.contains("100000000000000000000 runs, over the limit of 100000"),
            "{err}"
        );
    }

    #[test]
    fn an_axis_on_an_unknown_key_names_the_axis() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/scenes");
        let text = "name = \"t\"\nseed = 3\nscenarios = [\"person.toml\"]\n[[axes]]\nkey = \"map.model.p_maxx\"\nvalues = [0.7]\n";
        let sweep = Sweep::from_str(&dir.join("t.toml"), text).expect("sweep");
        let err = SweepPlan::new(sweep).expect_err("unknown key").to_string();
        assert!(err.contains("t.toml:5:7: axis `map.model.p_maxx`"), "{err}");
        assert!(err.contains("unknown field `p_maxx`"), "{err}");
    }
}
