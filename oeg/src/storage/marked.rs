//! What a grid written a few cells at a time (the scan scratch) marks of what it wrote, read back and
//! recycled: rows or cells ([`super::marks`]), visited by the update and reset to the fill, the tiles kept in
//! the grid's pool for the next scan.

use super::marks::{CellMarks, Marked};
use super::{TILE_CELLS, TileGrid, TileIndex};

impl<T: Copy> TileGrid<T> {
    /// The tile in `slot` (from [`TileGrid::slot_or_insert`], with no allocation or re-indexing in between)
    /// and the list of its cells written since it was placed, to which the caller adds the offset
    /// ([`super::offset_in_tile`]) of each cell it writes for the first time: [`TileGrid::marked_tiles`] and
    /// [`TileGrid::recycle_marked`] then visit those cells alone. The list has room for the whole tile.
    #[inline]
    pub(crate) fn slot_tile_and_marks_mut(&mut self, slot: usize) -> (&mut [T; TILE_CELLS], &mut CellMarks) {
        if self.marks.len() != self.slots.len() {
            self.marks.resize_with(self.slots.len(), || None);
        }
        let marks = self.marks[slot].get_or_insert_with(|| {
            self.num_mark_lists += 1;
            Box::new(CellMarks::EMPTY)
        });
        match self.slots[slot].as_deref_mut() {
            Some(t) => (t, marks),
            None => unreachable!("slots come from slot_or_insert"),
        }
    }

    /// Records that rows `rows` (bit `r` for row `r`, [`super::offset_in_tile`] `>> TILE_SHIFT`) of the tile in `slot`
    /// were written, for [`TileGrid::marked_tiles`] and [`TileGrid::recycle_marked`]: a walk marks the rows
    /// it crossed once per tile, at no cost per cell, where its cells are many.
    #[inline]
    pub(crate) fn mark_rows(&mut self, slot: usize, rows: u64) {
        if self.rows.len() != self.slots.len() {
            self.rows.resize(self.slots.len(), 0);
        }
        self.rows[slot] |= rows;
    }

    /// What was marked written in the tile in `slot`.
    fn marked_in(&self, slot: usize) -> Marked<'_> {
        Marked {
            rows: self.rows.get(slot).copied().unwrap_or(0),
            cells: self
                .marks
                .get(slot)
                .and_then(Option::as_deref)
                .map_or(&[][..], CellMarks::as_slice),
        }
    }

    /// Allocated tiles with something marked written ([`TileGrid::mark_rows`],
    /// [`TileGrid::slot_tile_and_marks_mut`]), in the order of [`TileGrid::tiles`], with what was marked.
    pub(crate) fn marked_tiles(
        &self,
    ) -> impl Iterator<Item = (TileIndex, &[T; TILE_CELLS], Marked<'_>)> + '_ {
        self.tiles().filter_map(move |(tile, t)| {
            let marked = self.slot(tile).map(|s| self.marked_in(s))?;
            (!marked.is_empty()).then_some((tile, t, marked))
        })
    }

    /// The tile at `tile` with what was marked written in it, if allocated.
    pub(crate) fn marked_tile(&self, tile: TileIndex) -> Option<(&[T; TILE_CELLS], Marked<'_>)> {
        let slot = self.slot(tile)?;
        let t = self.slots[slot].as_deref()?;
        Some((t, self.marked_in(slot)))
    }

    /// Releases every tile into the grid's pool, its marked rows and cells reset to `fill`: the grid reads as
    /// empty again but keeps its memory for the next use (the per-scan scratch of [`crate::Map::integrate`]).
    /// For a grid written only where it marked ([`TileGrid::mark_rows`], [`TileGrid::slot_tile_and_marks_mut`]),
    /// so the cost is that of what was written, not of the tiles' size.
    pub(crate) fn recycle_marked(&mut self) {
        let fill = self.fill;
        for (_, tile, marked) in self.marked_tiles_mut() {
            marked.reset(tile, fill);
        }
        self.release_reset();
    }

    /// The allocated tiles with something marked written, mutable, in the order of [`TileGrid::tiles`], with
    /// what was marked, and the grid's fill: for a caller that reads what was written where it is (on any
    /// thread) and resets it there ([`Marked::reset`]) before [`TileGrid::release_reset`] takes the tiles back.
    pub(crate) fn marked_tiles_mut(&mut self) -> Vec<(TileIndex, &mut [T; TILE_CELLS], Marked<'_>)> {
        let (min, tiles_x) = (self.tile_min, self.tiles_x.max(1));
        let (rows, marks) = (&self.rows, &self.marks);
        self.slots
            .iter_mut()
            .enumerate()
            .filter_map(|(slot, t)| {
                let marked = Marked {
                    rows: rows.get(slot).copied().unwrap_or(0),
                    cells: marks
                        .get(slot)
                        .and_then(Option::as_deref)
                        .map_or(&[][..], CellMarks::as_slice),
                };
                let tile = TileIndex {
                    ti: min.ti + (slot % tiles_x) as i32,
                    tj: min.tj + (slot / tiles_x) as i32,
                };
                t.as_deref_mut()
                    .filter(|_| !marked.is_empty())
                    .map(|t| (tile, t, marked))
            })
            .collect()
    }

    /// The grid's fill value: what a cell never written reads as.
    pub(crate) fn fill(&self) -> T {
        self.fill
    }

    /// Releases every tile into the grid's pool, for a grid whose marked cells were reset to `fill` already
    /// ([`TileGrid::marked_tiles_mut`], [`Marked::reset`]): the marks are cleared, the tiles are not read.
    pub(crate) fn release_reset(&mut self) {
        for (slot, t) in self.slots.iter_mut().enumerate() {
            let Some(t) = t.take() else {
                continue;
            };
            if let Some(rows) = self.rows.get_mut(slot) {
                *rows = 0;
            }
            if let Some(Some(marks)) = self.marks.get_mut(slot) {
                marks.clear();
            }
            self.pool.push(t);
        }
        self.num_tiles = 0;
    }
}

/// One tile of a pass over what some grids marked ([`marked_by_tile`]): the target grid's tile there, if it has
/// one, and each grid's marked tile with its marks, in the grids' order.
pub(crate) type MarkedTileWork<'a, T, E> = (
    Option<&'a mut [T; TILE_CELLS]>,
    Vec<(&'a mut [E; TILE_CELLS], Marked<'a>)>,
);

/// Every tile that any of `grids` marked, row by row over the tile index, with `target`'s tile there and each
/// grid's marked tile, lent mutably so that the pass resets what it reads ([`Marked::reset`]) on the thread that
/// read it; each tile's work is independent of the others', for a parallel pass. The grids then take their
/// tiles back ([`TileGrid::release_reset`]).
pub(crate) fn marked_by_tile<'a, T: Copy, E: Copy + 'a>(
    target: &'a mut TileGrid<T>,
    grids: impl IntoIterator<Item = &'a mut TileGrid<E>>,
) -> Vec<MarkedTileWork<'a, T, E>> {
    let mut by_tile: std::collections::BTreeMap<(i32, i32), (TileIndex, Vec<_>)> = Default::default();
    for grid in grids {
        for (tile, evidence, marked) in grid.marked_tiles_mut() {
            by_tile
                .entry((tile.tj, tile.ti))
                .or_insert_with(|| (tile, Vec::new()))
                .1
                .push((evidence, marked));
        }
    }
    let mut lent = target
        .tiles_mut_in_order(by_tile.values().map(|(tile, _)| *tile))
        .into_iter()
        .peekable();
    by_tile
        .into_values()
        .map(|(tile, marked)| (lent.next_if(|(t, _)| *t == tile).map(|(_, t)| t), marked))
        .collect()
}
