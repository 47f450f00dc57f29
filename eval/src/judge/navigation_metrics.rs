//! The closed loop's keys of `metrics.json` (`nav_*`): one type, filled from a run's figures in one place.

use serde::Serialize;

use crate::judge::NavigationFigures;

/// The closed loop's figures in `metrics.json`, each null for a run without `[navigation]`. Flattened into
/// [`crate::judge::Metrics`], so the keys keep their `nav_` names and places.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct NavMetrics {
    /// Whether the robot reached the goal.
    #[serde(rename = "nav_reached")]
    pub reached: Option<bool>,
    /// Seconds the robot navigated.
    #[serde(rename = "nav_time_s")]
    pub time_s: Option<f64>,
    /// Length truly driven over the truth's shortest path (null unless reached).
    #[serde(rename = "nav_length_ratio")]
    pub length_ratio: Option<f64>,
    /// Plans asked for.
    #[serde(rename = "nav_replans")]
    pub replans: Option<u64>,
    /// Times the collision guard stopped the robot short of a cell its map calls blocked.
    #[serde(rename = "nav_guard_stops")]
    pub guard_stops: Option<u64>,
    /// Replanning times with no path on the map.
    #[serde(rename = "nav_no_path_replans")]
    pub no_path_replans: Option<u64>,
    /// Planner calls that failed (an external planner's crash, time-out or bad path).
    #[serde(rename = "nav_planner_failures")]
    pub planner_failures: Option<u64>,
    /// Times the robot's footprint entered truly blocked cells. The number that must be zero.
    #[serde(rename = "nav_contacts")]
    pub contacts: Option<u64>,
    /// Of the contacts, those with a cell a ray could have told about before the contact: the map's or the
    /// navigator's to avoid.
    #[serde(rename = "nav_contacts_observable")]
    pub contacts_observable: Option<u64>,
    /// Of the contacts, the blind ones: no ray could have told about any cell the footprint entered.
    #[serde(rename = "nav_contacts_blind")]
    pub contacts_blind: Option<u64>,
    /// Of the contacts, those with a cell the robot's map called blocked at that moment: the navigator's to
    /// avoid.
    #[serde(rename = "nav_contacts_mapped_blocked")]
    pub contacts_mapped_blocked: Option<u64>,
    /// Of the contacts, those with no cell called blocked and one the map could not decide.
    #[serde(rename = "nav_contacts_mapped_undecided")]
    pub contacts_mapped_undecided: Option<u64>,
    /// Of the contacts, those whose cells the map called drivable: the map's false clearance.
    #[serde(rename = "nav_contacts_mapped_drivable")]
    pub contacts_mapped_drivable: Option<u64>,
    /// The smallest distance from the footprint to a truly blocked cell, metres.
    #[serde(rename = "nav_closest_approach_m")]
    pub closest_approach_m: Option<f64>,
    /// Whether the robot ended stuck.
    #[serde(rename = "nav_stuck")]
    pub stuck: Option<bool>,
}

impl NavMetrics {
    /// Every figure present and zero (`false`): the shape of a closed-loop run's keys.
    pub const ZERO: Self = Self {
        reached: Some(false),
        time_s: Some(0.0),
        length_ratio: Some(0.0),
        replans: Some(0),
        guard_stops: Some(0),
        no_path_replans: Some(0),
        planner_failures: Some(0),
        contacts: Some(0),
        contacts_observable: Some(0),
        contacts_blind: Some(0),
        contacts_mapped_blocked: Some(0),
        contacts_mapped_undecided: Some(0),
        contacts_mapped_drivable: Some(0),
        closest_approach_m: Some(0.0),
        stuck: Some(false),
    };

    /// A closed-loop run's figures.
    pub fn of(n: &NavigationFigures) -> Self {
        let [blocked, undecided, drivable] = n.contacts_mapped;
        Self {
            reached: Some(n.reached),
            time_s: Some(n.time_s),
            length_ratio: n.length_ratio,
            replans: Some(n.replans),
            guard_stops: Some(n.guard_stops),
            no_path_replans: Some(n.no_path_replans),
            planner_failures: Some(n.planner_failures),
            contacts: Some(n.contacts),
            contacts_observable: Some(n.contacts_observable),
            contacts_blind: Some(n.contacts - n.contacts_observable),
            contacts_mapped_blocked: Some(blocked),
            contacts_mapped_undecided: Some(undecided),
            contacts_mapped_drivable: Some(drivable),
            closest_approach_m: n.closest_approach_m,
            stuck: Some(n.stuck),
        }
    }
}
