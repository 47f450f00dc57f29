//! Why a closed loop stopped or touched: the cells that closed the map's paths at a stop, and what the map
//! called the cells a contact entered.

use oeg::{CellIndex, Map, Pose2, RobotProfile, Traversability, TraversabilityRule};

use super::{NavigationInputs, clamped_cell, planner_options, truth_plan};
use crate::error::{EvalError, Result};
use crate::judge::plan_check::{closing_words, count_reasons, map_reason};
use crate::judge::verdict::TruthClass;

/// Which cells closed the way ([`oeg::closing_cells`]), by why `map` could not decide them ([`map_reason`]),
/// with what the truth says of them; `blocked` when even the path through every cell the map cannot decide does
/// not exist.
pub(super) fn closed_by(
    map: &Map,
    decisions: &[Traversability],
    inputs: &NavigationInputs<'_>,
    window: &oeg::GridWindow,
    from: Pose2,
    goal: (f64, f64),
) -> Result<String> {
    let (Some(a), Some(b)) = (
        clamped_cell(window, (from.x_m, from.y_m)),
        clamped_cell(window, goal),
    ) else {
        return Ok("outside the map region".into());
    };
    let options = planner_options(inputs);
    let region = *window.region();
    let closing = oeg::closing_cells(window, decisions, a, b, &options).map_err(|e| EvalError::Input {
        path: inputs.scenario.name.clone().into(),
        message: format!("planner: {e}"),
    })?;
    let Some(closing) = closing else {
        // Closed by the map's blocked cells: which of them lie on the truth's own path from here.
        return Ok(match truth_plan(inputs, (from.x_m, from.y_m))? {
            None => "blocked; the truth has no path either".into(),
            Some(truth_path) => {
                let on_truth_path = truth_path
                    .cells
                    .iter()
                    .filter(|c| {
                        region
                            .offset(**c)
                            .is_some_and(|k| decisions[k] == Traversability::Blocked)
                    })
                    .count();
                format!(
                    "blocked; the truth has a path, with {on_truth_path} cells the map calls blocked on it \
                     (the rest closed by the inflation around blocked cells)"
                )
            }
        });
    };
    let mut truly_blocked = 0;
    let (profile, rule) = (&inputs.truth.profile, inputs.scenario.map.traversability);
    let on_map = closing.iter().filter_map(|&c| region.offset(c).map(|k| (c, k)));
    let reasons = count_reasons(on_map.map(|(c, k)| {
        truly_blocked += u64::from(TruthClass::of(inputs.truth, k).is_blocked());
        map_reason(map, c, profile, rule)
    }));
    let total: u64 = reasons.values().sum();
    Ok(match closing_words(&reasons) {
        Some(words) => format!(
            "{words}; the truth: {} drivable, {truly_blocked} blocked",
            total - truly_blocked
        ),
        None => "blocked (the inflation around blocked cells)".into(),
    })
}

/// What `map` calls the truly blocked `cells` a contact entered, now: the most telling of their classes,
/// blocked over uncertain over unknown over traversable over free ([`super::record::Event::mapped_as`]).
/// Blocked: the navigator drove into what its map forbade; uncertain or unknown: the map could not decide;
/// traversable or free: the map called them drivable, a false clearance.
pub(super) fn mapped_as(
    map: &Map,
    cells: &[CellIndex],
    profile: &RobotProfile,
    rule: TraversabilityRule,
) -> String {
    let rank = |t: Traversability| match t {
        Traversability::Blocked => 4,
        Traversability::Uncertain => 3,
        Traversability::Unknown => 2,
        Traversability::Traversable => 1,
        Traversability::Free => 0,
    };
    cells
        .iter()
        .map(|c| map.traversability(*c, profile, rule))
        .max_by_key(|t| rank(*t))
        .map_or_else(String::new, |t| t.name().to_string())
}
