//! A path planner on the map's decisions: the check a navigation stack makes with a 2.5D map.
//!
//! 8-connected A* over a [`GridWindow`] from a start cell to a goal cell. The robot's centre may enter a cell
//! when the cell is drivable and no blocked cell lies within [`PlannerOptions::inflation_radius_m`] of it (ROS
//! costmap_2d's lethal inscribed radius); unknown cells follow [`UnknownCells`]. Beyond that radius a cell
//! costs more to enter the nearer it lies to a blocked cell, decaying to nothing over
//! [`PlannerOptions::inflation_cost_width_m`] (costmap_2d's inflation cost), so a path keeps a margin where
//! there is room. Diagonal moves may not cut a corner (both cells beside the diagonal must be enterable).
//! Costs are integers (1000 a side, 1414 a diagonal) and ties are broken by cell offset, so the same decisions
//! always give the same path.
//!
//! ```
//! use oeg::{PlannerOptions, plan};
//! use oeg::{CellIndex, CellRegion, GridGeometry, GridWindow, Traversability};
//!
//! // A 10 x 5 window of 0.1 m cells with a wall across x = 0.5 m except at its top row.
//! let region = CellRegion::from_corners(CellIndex::new(0, 0), CellIndex::new(9, 4)).expect("region");
//! let window = GridWindow::new(GridGeometry::new(0.1)?, region);
//! let decisions: Vec<Traversability> = region
//!     .cells()
//!     .map(|c| if c.i == 5 && c.j < 4 { Traversability::Blocked } else { Traversability::Free })
//!     .collect();
//! let options = PlannerOptions {
//!     inflation_radius_m: 0.0,
//!     inflation_cost_width_m: 0.0,
//!     ..PlannerOptions::default()
//! };
//! let path = plan(&window, &decisions, CellIndex::new(0, 0), CellIndex::new(9, 0), &options)?
//!     .expect("through the gap");
//! assert!(path.cells.contains(&CellIndex::new(5, 4)));
//! # Ok::<(), oeg::Error>(())
//! ```

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::geometry::{CellIndex, CellRegion, GridWindow};
use crate::traversability::Traversability;

mod closing;
mod distance;
mod inflation;
mod read;

pub use closing::closing_cells;

use inflation::{Inflation, start_clearance};
use read::as_planned;

/// Default inflation radius, metres: half the Pioneer 3-AT's 0.50 m width (its inscribed radius).
pub const DEFAULT_INFLATION_RADIUS_M: f64 = 0.25;

/// Default footprint radius, metres: the Pioneer 3-AT's inscribed radius, as [`DEFAULT_INFLATION_RADIUS_M`].
pub const DEFAULT_FOOTPRINT_RADIUS_M: f64 = 0.25;

/// Cost of a move to a side neighbour; a diagonal costs [`DIAGONAL_COST`] (1000 sqrt 2, rounded).
const SIDE_COST: u64 = 1000;
const DIAGONAL_COST: u64 = 1414;

/// What the planner makes of cells the map never observed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum UnknownCells {
    /// The robot's centre never enters an unknown cell, but unknown cells are not inflated: costmap_2d with
    /// `track_unknown_space` and a planner that does not allow unknown space. See [`plan`] for the cells
    /// around the start and the goal.
    #[default]
    Avoid,
    /// Unknown cells are obstacles, inflated like blocked ones: the most cautious reading.
    Inflate,
    /// Unknown cells are drivable: optimistic planning, as when exploring.
    Drivable,
}

/// What the planner makes of cells the map cannot judge ([`Traversability::Uncertain`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum UncertainCells {
    /// Uncertain cells are obstacles, inflated like blocked ones: the robot never relies on a decision the
    /// map cannot make.
    #[default]
    Blocked,
    /// Uncertain cells are drivable: the robot takes the risk (to measure what it costs).
    Drivable,
}

/// How the planner reads the map. Every field has a documented default.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlannerOptions {
    /// The robot's centre keeps at least this far from every blocked cell (centre to centre), metres. Default
    /// [`DEFAULT_INFLATION_RADIUS_M`].
    pub inflation_radius_m: f64,
    /// The robot's own radius, metres: at the start, cells this close to the robot's centre lie under it and
    /// count as drivable (see [`plan`]). Default [`DEFAULT_FOOTPRINT_RADIUS_M`]. It is not the inflation
    /// radius: a wide safety margin must not clear the obstacles around the start.
    pub footprint_radius_m: f64,
    /// Unknown cells: default [`UnknownCells::Avoid`].
    pub unknown: UnknownCells,
    /// Uncertain cells: default [`UncertainCells::Blocked`].
    pub uncertain: UncertainCells,
    /// Beyond this distance from the start (centre to centre), metres, the cells the map cannot decide
    /// (uncertain or never observed) are planned through at [`PlannerOptions::doubt_cost`] each, whatever
    /// `unknown` and `uncertain` say: nav2's `allow_unknown`, for uncertain cells too. A robot that replans
    /// as it drives then goes closer and looks again; cells nearer than this decide for real. Default `None`:
    /// never.
    pub optimistic_beyond_m: Option<f64>,
    /// The extra cost of entering a cell the map cannot decide beyond [`PlannerOptions::optimistic_beyond_m`],
    /// in cell lengths: a path crosses `n` such cells only when going round them is more than
    /// `n * doubt_cost` cells longer. Default [`DEFAULT_DOUBT_COST`].
    pub doubt_cost: f64,
    /// Beyond the inflation radius, over this distance, metres, a cell costs more to enter the nearer it lies
    /// to a blocked cell (costmap_2d's inflation cost, which decays from the lethal radius out to nav2's
    /// `inflation_radius`): a cell `d` metres beyond the inflation radius costs [`INFLATED_CELL_COST`] x
    /// exp(-[`PlannerOptions::cost_scaling_factor`] x `d`) cell lengths more. A path then keeps a margin
    /// where there is room, instead of running along the inflation's edge, where any tracking error puts
    /// the footprint onto what the inflation grew from. Default [`DEFAULT_INFLATION_COST_WIDTH_M`]; 0: no
    /// cost.
    pub inflation_cost_width_m: f64,
    /// How fast that cost decays, per metre (nav2's `cost_scaling_factor`). Default
    /// [`DEFAULT_COST_SCALING_FACTOR`].
    pub cost_scaling_factor: f64,
}

/// The default [`PlannerOptions::inflation_cost_width_m`], metres: nav2's default `inflation_radius` (0.55 m)
/// less the inscribed radius its lethal cost stands for ([`DEFAULT_INFLATION_RADIUS_M`], 0.25 m), so that a
/// planner whose inflation radius is larger (a footprint's circumscribed radius) keeps the same band beyond it.
pub const DEFAULT_INFLATION_COST_WIDTH_M: f64 = 0.30;

/// The default [`PlannerOptions::cost_scaling_factor`], per metre: nav2's inflation layer's (10). The cost
/// halves every 7 cm: 4 cell lengths at the inflation's edge, 1.5 at 10 cm beyond it, 0.2 at 30 cm.
pub const DEFAULT_COST_SCALING_FACTOR: f64 = 10.0;

/// The default [`PlannerOptions::doubt_cost`]: a cell the map cannot decide costs 5 cell lengths to enter, its
/// own and 4 more, so the planner goes round a few such cells but crosses a band of them rather than make a
/// long detour.
pub const DEFAULT_DOUBT_COST: f64 = 4.0;

/// The extra cost of entering a cell inside the inflation, in cell lengths, for a robot that stands inside it
/// (see [`plan`]): costmap_2d marks such a cell 253 and nav2's NavFn adds 0.8 of that to its neutral 50 for a
/// free cell, about 5 times; so the cell costs 5 cell lengths, its own and 4 more.
pub const INFLATED_CELL_COST: f64 = 4.0;

impl Default for PlannerOptions {
    fn default() -> Self {
        Self {
            inflation_radius_m: DEFAULT_INFLATION_RADIUS_M,
            footprint_radius_m: DEFAULT_FOOTPRINT_RADIUS_M,
            unknown: UnknownCells::default(),
            uncertain: UncertainCells::default(),
            optimistic_beyond_m: None,
            doubt_cost: DEFAULT_DOUBT_COST,
            inflation_cost_width_m: DEFAULT_INFLATION_COST_WIDTH_M,
            cost_scaling_factor: DEFAULT_COST_SCALING_FACTOR,
        }
    }
}

impl PlannerOptions {
    /// Checks the options for sense.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] for a negative, non-finite or absurd (over 100 m) inflation or footprint
    /// radius, optimistic distance or inflation cost width, a doubt cost that is not a number from 0 to 1000,
    /// or a cost scaling factor that is not a number from 0 to 1000 per metre.
    pub fn validate(&self) -> Result<()> {
        if !(self.doubt_cost.is_finite() && (0.0..=1000.0).contains(&self.doubt_cost)) {
            return Err(Error::setting(
                "doubt_cost",
                format!(
                    "must be a number of cell lengths from 0 to 1000, got {}",
                    self.doubt_cost
                ),
            ));
        }
        let k = self.cost_scaling_factor;
        if !(k.is_finite() && (0.0..=1000.0).contains(&k)) {
            return Err(Error::setting(
                "cost_scaling_factor",
                format!("must be a number per metre from 0 to 1000, got {k}"),
            ));
        }
        for (name, r) in [
            ("inflation_radius_m", self.inflation_radius_m),
            ("footprint_radius_m", self.footprint_radius_m),
            ("optimistic_beyond_m", self.optimistic_beyond_m.unwrap_or(0.0)),
            ("inflation_cost_width_m", self.inflation_cost_width_m),
        ] {
            if !(r.is_finite() && (0.0..=100.0).contains(&r)) {
                return Err(Error::setting(
                    name,
                    format!("must be a distance in metres from 0 to 100, got {r}"),
                ));
            }
        }
        Ok(())
    }
}

/// A planned path.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// The cells the robot's centre passes, start first, goal last, each an 8-neighbour of the one before.
    pub cells: Vec<CellIndex>,
    /// Length of the path through the cell centres, metres.
    pub length_m: f64,
}

/// Where the robot's centre may not be, row-major over `window`: blocked cells inflated by the radius, and
/// unknown cells as `options.unknown` says. Start and goal exemptions are [`plan`]'s, not this mask's.
///
/// # Errors
/// [`Error::InvalidSetting`] for bad options, or a `decisions` slice whose length is not the window's cell
/// count.
pub fn forbidden_mask(
    window: &GridWindow,
    decisions: &[Traversability],
    options: &PlannerOptions,
) -> Result<Vec<bool>> {
    validate_inputs(window.region(), decisions, options)?;
    Ok(Inflation::of(window, decisions, options).forbidden(options.inflation_radius_m))
}

/// The checks every entry point makes: sane options and one decision per cell (the window's resolution was
/// checked when its geometry was made).
fn validate_inputs(
    region: &CellRegion,
    decisions: &[Traversability],
    options: &PlannerOptions,
) -> Result<()> {
    options.validate()?;
    if decisions.len() as u64 != region.num_cells() {
        return Err(Error::setting(
            "decisions",
            format!(
                "one decision per region cell: {} cells, {} decisions",
                region.num_cells(),
                decisions.len()
            ),
        ));
    }
    Ok(())
}

/// The shortest path from `start` to `goal` through `window` on `decisions` (one per cell, row-major),
/// or `None` if there is none.
///
/// The robot stands at the start, so every cell under it counts as drivable, blocked or unknown (costmap_2d's
/// footprint clearing: no sensor sees under the robot, and nothing stands where the robot is; a spurious hit
/// there would otherwise pin it). "Under it" is within the smaller of [`PlannerOptions::footprint_radius_m`]
/// and the inflation radius of the start. Unknown cells within that radius of the goal count as drivable too,
/// whatever [`UnknownCells`] says (the ground under the robot's final footprint need not have been seen), but
/// blocked cells near the goal still count.
///
/// A robot whose centre stands inside the inflation (it turned close to an obstacle, or saw it late) keeps
/// the clearance it has, never less: the path then keeps its centre as far from every obstacle as the start
/// is, less half a cell, instead of there being no path out (costmap_2d's inflation is a cost the planner may
/// cross on its way out of it). Each cell inside the full inflation then costs [`INFLATED_CELL_COST`] more
/// to enter, so the path leaves the inflation the shortest way instead of running along it.
///
/// # Errors
/// As [`forbidden_mask`], and [`Error::InvalidSetting`] for a start or goal outside the window.
pub fn plan(
    window: &GridWindow,
    decisions: &[Traversability],
    start: CellIndex,
    goal: CellIndex,
    options: &PlannerOptions,
) -> Result<Option<Plan>> {
    Ok(plan_or_why(window, decisions, start, goal, options)?.ok())
}

/// Why [`plan`] found no path.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NoPath {
    /// The robot's centre may not stand at the start: the start cell's decision on the map (a drivable
    /// class means a blocked or uncertain cell lies within the inflation radius).
    Start(Traversability),
    /// The robot's centre may not stand at the goal: the goal cell's decision, as for [`NoPath::Start`].
    Goal(Traversability),
    /// The robot may stand at both, but every route between them crosses cells it may not enter.
    NoConnection,
}

impl NoPath {
    /// The reason in words, for a message: `the start cell is blocked on the map`.
    pub fn describe(&self, options: &PlannerOptions) -> String {
        let end = |name: &str, class: &Traversability| match class {
            Traversability::Blocked => format!("the {name} cell is blocked on the map"),
            Traversability::Uncertain => format!(
                "the {name} cell is uncertain on the map (the planner treats uncertain cells as blocked; \
                 planner.uncertain=drivable takes the risk)"
            ),
            Traversability::Unknown => format!(
                "the {name} cell was never observed (planner.unknown=drivable plans through unknown cells)"
            ),
            Traversability::Free | Traversability::Traversable => format!(
                "the {name} cell lies within the inflation radius ({} m) of a blocked or uncertain cell",
                options.inflation_radius_m
            ),
        };
        match self {
            Self::Start(class) => end("start", class),
            Self::Goal(class) => end("goal", class),
            Self::NoConnection => "no connection: every route from the start to the goal crosses blocked, \
                 uncertain or unobserved cells, or passes within the inflation radius of a blocked one"
                .to_string(),
        }
    }
}

/// As [`plan`], with the reason when there is no path.
///
/// # Errors
/// As [`plan`].
pub fn plan_or_why(
    window: &GridWindow,
    decisions: &[Traversability],
    start: CellIndex,
    goal: CellIndex,
    options: &PlannerOptions,
) -> Result<std::result::Result<Plan, NoPath>> {
    let (region, resolution_m) = (window.region(), window.resolution_m());
    let offset_of = |name: &'static str, c: CellIndex| {
        region.offset(c).ok_or_else(|| {
            Error::setting(
                name,
                format!("cell ({}, {}) lies outside the planning region", c.i, c.j),
            )
        })
    };
    let (s, g) = (offset_of("start", start)?, offset_of("goal", goal)?);
    validate_inputs(region, decisions, options)?;
    let original = decisions;
    let (decisions, mut extra) = as_planned(window, decisions, start, goal, options);
    let inflation = Inflation::of(window, &decisions, options);
    let mut forbidden = inflation.forbidden(options.inflation_radius_m);
    if forbidden[s]
        && let Some(clearance) = start_clearance(region, resolution_m, &decisions, start, options)
    {
        let inflated = std::mem::replace(&mut forbidden, inflation.forbidden(clearance));
        // The way out of the inflation is a cost, as costmap_2d's: a path leaves it the shortest way rather
        // than run along it at the start's clearance, where the footprint's corners meet what it inflates.
        let cost = (INFLATED_CELL_COST * SIDE_COST as f64).round() as u32;
        for ((e, inflated), allowed) in extra.iter_mut().zip(&inflated).zip(&forbidden) {
            if *inflated && !*allowed {
                *e = e.saturating_add(cost);
            }
        }
    }
    inflation.add_costs(&mut extra, options);
    drop(inflation);
    if forbidden[s] {
        return Ok(Err(NoPath::Start(original[s])));
    }
    if forbidden[g] {
        return Ok(Err(NoPath::Goal(original[g])));
    }
    let found = astar(region, &forbidden, &extra, s, g).ok_or(NoPath::NoConnection);
    Ok(found.map(|offsets| {
        let nx = region.num_x as usize;
        let cells: Vec<CellIndex> = offsets
            .iter()
            .map(|k| region.cell_at((*k % nx) as u32, (*k / nx) as u32))
            .collect();
        let num_diagonal = cells
            .windows(2)
            .filter(|w| w[0].i != w[1].i && w[0].j != w[1].j)
            .count();
        let num_side = cells.len().saturating_sub(1) - num_diagonal;
        let length_m = (num_side as f64 + num_diagonal as f64 * std::f64::consts::SQRT_2) * resolution_m;
        Plan { cells, length_m }
    }))
}

/// The memory [`plan`] takes per cell of its region, bytes, at most in practice: the decisions' copy and the
/// forbidden mask (1 each), the cost of entering each cell (4), A*'s cost (8), parent (4) and closed flag
/// (1), and its open list (24 a cell pushed once); 43 in all, rounded up. The inflation's distances (8) and
/// masks are freed before A* starts. A caller bounds a plan's region with it before planning.
pub const PLANNER_BYTES_PER_CELL: u64 = 44;

/// Octile distance in cost units: exact for 8-connected moves on an empty grid, so A* stays optimal.
fn heuristic(nx: usize, a: usize, b: usize) -> u64 {
    let (ax, ay) = ((a % nx) as i64, (a / nx) as i64);
    let (bx, by) = ((b % nx) as i64, (b / nx) as i64);
    let (dx, dy) = ((ax - bx).unsigned_abs(), (ay - by).unsigned_abs());
    let (lo, hi) = (dx.min(dy), dx.max(dy));
    SIDE_COST * hi + (DIAGONAL_COST - SIDE_COST) * lo
}

/// A* over the offsets of a `region`-shaped mask; the path's offsets, start first.
/// `extra`: a cost added for entering each cell.
fn astar(
    region: &CellRegion,
    forbidden: &[bool],
    extra: &[u32],
    start: usize,
    goal: usize,
) -> Option<Vec<usize>> {
    const UNSEEN: u64 = u64::MAX;
    const NO_PARENT: u32 = u32::MAX;
    let (nx, ny) = (region.num_x as usize, region.num_y as usize);
    let mut cost = vec![UNSEEN; forbidden.len()];
    let mut parent = vec![NO_PARENT; forbidden.len()];
    let mut closed = vec![false; forbidden.len()];
    // (f, g, offset), smallest first; the offset breaks ties deterministically.
    let mut open = BinaryHeap::new();
    cost[start] = 0;
    open.push(Reverse((heuristic(nx, start, goal), 0u64, start)));
    while let Some(Reverse((_, g, k))) = open.pop() {
        if closed[k] {
            continue;
        }
        closed[k] = true;
        if k == goal {
            let mut path = vec![goal];
            let mut at = goal;
            while at != start {
                at = parent[at] as usize;
                path.push(at);
            }
            path.reverse();
            return Some(path);
        }
        let (x, y) = (k % nx, k / nx);
        for (dx, dy) in [
            (-1i64, 0i64),
            (1, 0),
            (0, -1),
            (0, 1),
            (-1, -1),
            (1, -1),
            (-1, 1),
            (1, 1),
        ] {
            let (u, v) = (x as i64 + dx, y as i64 + dy);
            if u < 0 || v < 0 || u >= nx as i64 || v >= ny as i64 {
                continue;
            }
            let n = v as usize * nx + u as usize;
            if forbidden[n] || closed[n] {
                continue;
            }
            let diagonal = dx != 0 && dy != 0;
            if diagonal && (forbidden[y * nx + u as usize] || forbidden[v as usize * nx + x]) {
                continue; // no corner cutting
            }
            let step = if diagonal { DIAGONAL_COST } else { SIDE_COST };
            let g_n = g + step + u64::from(extra[n]);
            if g_n < cost[n] {
                cost[n] = g_n;
                parent[n] = k as u32;
                open.push(Reverse((g_n + heuristic(nx, n, goal), g_n, n)));
            }
        }
    }
    None
}

#[cfg(test)]
mod tests;
