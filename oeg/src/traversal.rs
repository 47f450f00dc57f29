//! Ray traversal over the grid (the "3D Bresenham" of the paper's Algorithm 1).
//!
//! A ray `o + d l` is traversed along its projection on the ground plane: every cell the projection crosses is
//! visited exactly once, in order, the end cell included (the trap MoveIt once shipped). The walk is the
//! Amanatides-Woo grid walk parameterised by the ray's own parameter `l`, so each visit comes with the interval
//! of `l` spent inside the cell, from which the caller picks its sample and the sample's height. Consecutive
//! cells share an edge (the run is 4-connected): where the projection passes exactly through a corner, one of
//! the two side cells is visited as well.

use crate::geometry::{CellIndex, GridGeometry};
use crate::storage::{TILE_MASK, TILE_SHIFT, TileIndex, offset_in_tile};

/// One cell crossed by a ray, with the part of the ray inside it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct CellCrossing {
    /// The cell.
    pub cell: CellIndex,
    /// Ray parameter where the projection enters the cell.
    pub l_enter: f64,
    /// Ray parameter where it leaves (or the end of the traversal).
    pub l_exit: f64,
}

/// Iterator over the cells crossed by a ray's ground projection. No allocation.
#[derive(Debug, Clone)]
pub(crate) struct GroundTraversal {
    start: CellIndex,
    cell: CellIndex,
    end: CellIndex,
    step_i: i32,
    step_j: i32,
    t_max_x: f64,
    t_max_y: f64,
    t_delta_x: f64,
    t_delta_y: f64,
    l: f64,
    l_start: f64,
    l_end: f64,
    remaining_steps: u64,
    done: bool,
}

impl GroundTraversal {
    /// The cells crossed by the projection of `origin + direction * l` for `l` in `[l_start, l_end]`.
    ///
    /// `origin_xy_m` and `direction_xy` are the ray's x and y components; `l` is in units of the direction's
    /// length (metres for a unit direction). Returns `None` if either end is not finite or lies outside the
    /// `i32` index range, or if `l_end < l_start`.
    #[inline(always)]
    pub(crate) fn new(
        geometry: &GridGeometry,
        origin_xy_m: (f64, f64),
        direction_xy: (f64, f64),
        l_start: f64,
        l_end: f64,
    ) -> Option<Self> {
        // Written to reject NaN bounds too.
        if l_end
            .partial_cmp(&l_start)
            .is_none_or(|o| o == std::cmp::Ordering::Less)
        {
            return None;
        }
        let (ox, oy) = origin_xy_m;
        let (dx, dy) = direction_xy;
        let start = geometry.cell_of(ox + dx * l_start, oy + dy * l_start)?;
        let end = geometry.cell_of(ox + dx * l_end, oy + dy * l_end)?;
        let r = geometry.resolution_m();
        let axis = |index: i32, end_index: i32, o: f64, d: f64| -> (i32, f64, f64) {
            let step = match end_index.cmp(&index) {
                std::cmp::Ordering::Greater => 1,
                std::cmp::Ordering::Less => -1,
                std::cmp::Ordering::Equal => {
                    if d >= 0.0 {
                        1
                    } else {
                        -1
                    }
                }
            };
            if d == 0.0 {
                return (step, f64::INFINITY, f64::INFINITY);
            }
            let boundary = if d > 0.0 {
                f64::from(index) + 1.0
            } else {
                f64::from(index)
            } * r;
            ((step), (boundary - o) / d, r / d.abs())
        };
        let (step_i, t_max_x, t_delta_x) = axis(start.i, end.i, ox, dx);
        let (step_j, t_max_y, t_delta_y) = axis(start.j, end.j, oy, dy);
        // An axis already at the end cell's index never steps: its next boundary is at infinity.
        let t_max_x = if start.i == end.i { f64::INFINITY } else { t_max_x };
        let t_max_y = if start.j == end.j { f64::INFINITY } else { t_max_y };
        let remaining_steps = (i64::from(end.i) - i64::from(start.i)).unsigned_abs()
            + (i64::from(end.j) - i64::from(start.j)).unsigned_abs();
        Some(Self {
            start,
            cell: start,
            end,
            step_i,
            step_j,
            t_max_x,
            t_max_y,
            t_delta_x,
            t_delta_y,
            l: l_start,
            l_start,
            l_end,
            remaining_steps,
            done: false,
        })
    }
}

impl GroundTraversal {
    /// The cell the walk starts in (before any step).
    pub(crate) fn first_cell(&self) -> CellIndex {
        self.start
    }

    /// The cell the walk ends in.
    pub(crate) fn last_cell(&self) -> CellIndex {
        self.end
    }
}

impl GroundTraversal {
    /// The tile of the cell the walk is in, or `None` once the walk is over.
    #[inline(always)]
    pub(crate) fn tile(&self) -> Option<TileIndex> {
        (!self.done).then(|| TileIndex::of(self.cell))
    }

    /// The [`offset_in_tile`] of the cell the walk is in.
    #[inline(always)]
    pub(crate) fn offset_in_tile(&self) -> usize {
        offset_in_tile(self.cell)
    }

    /// Walks on through the tile of the cell the walk is in, as [`Iterator::next`] would, calling
    /// `visit(offset, crossing)` for each crossed cell of that tile with its [`offset_in_tile`]; stops at the
    /// first cell of another tile (where the next call starts) or at the end. A straight walk crosses a tile
    /// once, in one call.
    ///
    /// The hot loop of integration: the cell's offset is stepped along with it (one add) and the tile's edge
    /// is a count of steps per axis, where the iterator finds each cell's tile and offset afresh.
    #[inline(always)]
    pub(crate) fn walk_tile(&mut self, mut visit: impl FnMut(usize, &CellCrossing)) {
        if self.done {
            return;
        }
        let edge = |index: i32, step: i32| -> u32 {
            let within = (index & TILE_MASK) as u32;
            if step > 0 {
                TILE_MASK as u32 - within
            } else {
                within
            }
        };
        // Steps the walk can take along each axis before it leaves the tile.
        let mut inside_x = edge(self.cell.i, self.step_i);
        let mut inside_y = edge(self.cell.j, self.step_j);
        let mut offset = offset_in_tile(self.cell);
        let (offset_step_x, offset_step_y) = (self.step_i as isize, (self.step_j as isize) << TILE_SHIFT);
        // The state in locals, written back when the walk leaves the tile: kept in registers.
        let (mut cell, end) = (self.cell, self.end);
        let (mut t_max_x, mut t_max_y, mut l) = (self.t_max_x, self.t_max_y, self.l);
        let mut remaining = self.remaining_steps;
        loop {
            let l_enter = l;
            if remaining == 0 {
                let crossing = CellCrossing {
                    cell,
                    l_enter,
                    l_exit: self.l_end.max(l_enter),
                };
                visit(offset, &crossing);
                self.done = true;
                return;
            }
            let step_x = t_max_x <= t_max_y;
            // The nearer boundary (`min`, without NaN handling: none is NaN).
            let t_next = if t_max_y < t_max_x { t_max_y } else { t_max_x };
            let l_exit = t_next.clamp(self.l_start, self.l_end);
            visit(
                offset,
                &CellCrossing {
                    cell,
                    l_enter,
                    l_exit,
                },
            );
            l = l_exit;
            remaining -= 1;
            let leaves = if step_x {
                cell.i += self.step_i;
                t_max_x = if cell.i == end.i {
                    f64::INFINITY
                } else {
                    t_max_x + self.t_delta_x
                };
                let leaves = inside_x == 0;
                inside_x = inside_x.wrapping_sub(1);
                offset = offset.wrapping_add_signed(offset_step_x);
                leaves
            } else {
                cell.j += self.step_j;
                t_max_y = if cell.j == end.j {
                    f64::INFINITY
                } else {
                    t_max_y + self.t_delta_y
                };
                let leaves = inside_y == 0;
                inside_y = inside_y.wrapping_sub(1);
                offset = offset.wrapping_add_signed(offset_step_y);
                leaves
            };
            if leaves {
                (self.cell, self.t_max_x, self.t_max_y) = (cell, t_max_x, t_max_y);
                (self.l, self.remaining_steps) = (l, remaining);
                return;
            }
        }
    }
}

impl ExactSizeIterator for GroundTraversal {}

impl Iterator for GroundTraversal {
    type Item = CellCrossing;

    #[inline]
    fn next(&mut self) -> Option<CellCrossing> {
        if self.done {
            return None;
        }
        let cell = self.cell;
        let l_enter = self.l;
        if self.remaining_steps == 0 {
            self.done = true;
            return Some(CellCrossing {
                cell,
                l_enter,
                l_exit: self.l_end.max(l_enter),
            });
        }
        // Step along the axis whose boundary comes first. An axis that has reached the end cell's index has its
        // next boundary at infinity (`new` and each step set it so), so only the other moves, which keeps the
        // walk on the end cell despite rounding.
        let step_x = self.t_max_x <= self.t_max_y;
        let t_next = if step_x { self.t_max_x } else { self.t_max_y };
        // `t_next` never decreases along the walk (each axis's boundaries increase, and the walk takes the
        // nearer one), so clamping it to the span gives each crossing's exit without the previous one's.
        let l_exit = t_next.clamp(self.l_start, self.l_end);
        if step_x {
            self.cell.i += self.step_i;
            self.t_max_x = if self.cell.i == self.end.i {
                f64::INFINITY
            } else {
                self.t_max_x + self.t_delta_x
            };
        } else {
            self.cell.j += self.step_j;
            self.t_max_y = if self.cell.j == self.end.j {
                f64::INFINITY
            } else {
                self.t_max_y + self.t_delta_y
            };
        }
        self.remaining_steps -= 1;
        self.l = l_exit;
        Some(CellCrossing {
            cell,
            l_enter,
            l_exit,
        })
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        if self.done {
            return (0, Some(0));
        }
        let n = usize::try_from(self.remaining_steps + 1).unwrap_or(usize::MAX);
        (n, Some(n))
    }
}

#[cfg(test)]
mod tests;
