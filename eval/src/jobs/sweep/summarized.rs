//! The metrics `oeg sweep report` summarizes, with their labels: `(column, label with units, is a rate)`.

/// The metrics summarized: `(column, label with units, is a rate)`.
pub const METRICS: [(&str, &str, bool); 10] = [
    ("unsafe_step_cells", "unsafe step cells", false),
    ("unsafe_clearance_cells", "unsafe clearance cells", false),
    ("overcautious_step_cells", "over-cautious step cells", false),
    (
        "overcautious_clearance_cells",
        "over-cautious clearance cells",
        false,
    ),
    ("plan_unsafe_cells", "unsafe cells on the planned path", false),
    ("plan_found", "rate of runs with a path found", true),
    ("elevation_rmse_m", "elevation RMSE [m]", false),
    (
        "elevation_within_2sigma",
        "fraction of cells within 2 sigma",
        false,
    ),
    (
        "obstacle_decision_error_rate",
        "per-obstacle decision error rate",
        false,
    ),
    ("coverage", "coverage of the region", false),
];

/// The metrics summarized when some run has them: closed-loop runs' (`[navigation]`) and what no ray could tell
/// (absent from rows of earlier versions).
pub const OPTIONAL_METRICS: [(&str, &str, bool); 18] = [
    ("blind_cells", "unsafe cells no ray could tell about", false),
    ("plan_blind_cells", "blind cells on the planned path", false),
    (
        "observable_truth_plan_found",
        "rate of runs whose truth has a path through what the rays reached",
        true,
    ),
    (
        "nav_reached",
        "rate of closed-loop runs that reached the goal",
        true,
    ),
    (
        "nav_contacts",
        "contacts with truly blocked cells per closed-loop run",
        false,
    ),
    (
        "nav_contacts_observable",
        "contacts with cells a ray could have told about, per closed-loop run",
        false,
    ),
    (
        "nav_contacts_blind",
        "contacts no ray could have warned of, per closed-loop run",
        false,
    ),
    (
        "nav_contacts_mapped_drivable",
        "contacts the map called drivable, per run",
        false,
    ),
    ("nav_stuck", "rate of closed-loop runs that ended stuck", true),
    ("uncertain_cells", "uncertain cells", false),
    (
        "doubt_imprecise_cells",
        "uncertain cells the sensors measured too coarsely to tell a step",
        false,
    ),
    (
        "dynamic_accuracy",
        "DA: cells people left, mapped drivable (fraction)",
        false,
    ),
    (
        "associated_accuracy",
        "AA: sqrt(SA x DA), ghosts cleared and obstacles kept (fraction)",
        false,
    ),
    (
        "nav_closest_approach_m",
        "closest approach to a truly blocked cell [m]",
        false,
    ),
    (
        "phys_goal_reached",
        "rate of drives on the wheels that reached the goal",
        true,
    ),
    ("phys_stalls", "stalls per drive on the wheels", false),
    (
        "phys_contacts",
        "body contacts with obstacles per drive on the wheels",
        false,
    ),
    ("phys_max_pitch_deg", "largest pitch on the wheels [deg]", false),
];
