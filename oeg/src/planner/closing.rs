//! Why there is no path: the cells the map could not decide that closed every way from the start to the goal.

use super::{PlannerOptions, UncertainCells, UnknownCells, as_planned, plan};
use crate::error::Result;
use crate::geometry::{CellIndex, GridWindow};
use crate::traversability::Traversability;

/// The cells that closed the way from `start` to `goal` when [`plan`] finds no path: on the path it finds when
/// it takes every uncertain and unknown cell as drivable, the uncertain and unknown cells that `options`
/// forbid (on the path, or within the inflation radius of it where `options` inflate them), in row-major
/// order; not those the planner takes as drivable (under the robot at the start, beyond
/// [`PlannerOptions::optimistic_beyond_m`]). Observing them again, or planning through them, opens that path.
/// `None` when even that path does not exist: the map's blocked cells, with their inflation, close the way.
///
/// ```
/// use oeg::{CellIndex, CellRegion, GridGeometry, GridWindow, PlannerOptions, Traversability, closing_cells};
///
/// // A corridor of 0.1 m cells, one row wide, with one uncertain cell across it.
/// let region = CellRegion::from_corners(CellIndex::new(0, 0), CellIndex::new(9, 0)).expect("region");
/// let window = GridWindow::new(GridGeometry::new(0.1)?, region);
/// let decisions: Vec<Traversability> = region
///     .cells()
///     .map(|c| if c.i == 4 { Traversability::Uncertain } else { Traversability::Free })
///     .collect();
/// let options = PlannerOptions { inflation_radius_m: 0.0, ..PlannerOptions::default() };
/// let closing = closing_cells(&window, &decisions, CellIndex::new(0, 0), CellIndex::new(9, 0), &options)?;
/// assert_eq!(closing, Some(vec![CellIndex::new(4, 0)]));
/// # Ok::<(), oeg::Error>(())
/// ```
///
/// # Errors
/// As [`plan`].
pub fn closing_cells(
    window: &GridWindow,
    decisions: &[Traversability],
    start: CellIndex,
    goal: CellIndex,
    options: &PlannerOptions,
) -> Result<Option<Vec<CellIndex>>> {
    let relaxed = PlannerOptions {
        unknown: UnknownCells::Drivable,
        uncertain: UncertainCells::Drivable,
        ..*options
    };
    let Some(path) = plan(window, decisions, start, goal, &relaxed)? else {
        return Ok(None);
    };
    // What the planner reads: the cells under the robot at the start cleared, those it plans through
    // optimistically drivable.
    let (decisions, _) = as_planned(window, decisions, start, goal, options);
    let (region, resolution_m) = (window.region(), window.resolution_m());
    let reach = (options.inflation_radius_m / resolution_m).ceil() as i32;
    let r2 = (options.inflation_radius_m / resolution_m).powi(2) + 1e-9;
    let mut closing: Vec<usize> = Vec::new();
    for c in &path.cells {
        for dj in -reach..=reach {
            for di in -reach..=reach {
                let Some(k) = region.offset(CellIndex::new(c.i + di, c.j + dj)) else {
                    continue;
                };
                let on_path = di == 0 && dj == 0;
                let within = f64::from(di * di + dj * dj) <= r2;
                let forbids = match decisions[k] {
                    Traversability::Uncertain => options.uncertain == UncertainCells::Blocked && within,
                    Traversability::Unknown => match options.unknown {
                        UnknownCells::Avoid => on_path,
                        UnknownCells::Inflate => within,
                        UnknownCells::Drivable => false,
                    },
                    _ => false,
                };
                if forbids {
                    closing.push(k);
                }
            }
        }
    }
    closing.sort_unstable();
    closing.dedup();
    let nx = region.num_x as usize;
    Ok(Some(
        closing
            .into_iter()
            .map(|k| region.cell_at((k % nx) as u32, (k / nx) as u32))
            .collect(),
    ))
}
