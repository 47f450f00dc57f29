//! What a grid written a few cells at a time (the scan scratch) marks, so that visiting and clearing what was
//! written costs what was written: whole rows ([`TileGrid::mark_rows`], free in a walk that crosses many cells)
//! or single cells ([`CellMarks`], for a scan that touches a few cells of many rows).

#[cfg(doc)]
use super::TileGrid;
use super::{TILE_CELLS, TILE_SHIFT, TILE_SIZE};

/// Calls `f` with the index of every row whose bit is set in `rows`, in increasing order.
#[inline]
pub(crate) fn for_each_row(mut rows: u64, mut f: impl FnMut(usize)) {
    while rows != 0 {
        f(rows.trailing_zeros() as usize);
        rows &= rows - 1;
    }
}

/// The cells of a tile written since it was placed, as offsets ([`super::offset_in_tile`]) in the order they were first
/// written: what a grid written a few cells at a time (the scan scratch) visits and clears. Marking is
/// branch-free, for the hottest loop: every call writes, and only a first write counts.
#[derive(Debug, Clone)]
pub(crate) struct CellMarks {
    len: usize,
    /// One more than a tile's cells: the slot past the last mark takes the writes that do not count.
    offsets: [u16; TILE_CELLS + 1],
}

/// What was marked written in a tile: rows ([`TileGrid::mark_rows`]) and cells
/// ([`TileGrid::slot_tile_and_marks_mut`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Marked<'a> {
    pub(super) rows: u64,
    pub(super) cells: &'a [u16],
}

impl Marked<'_> {
    /// Whether nothing was marked.
    pub(crate) fn is_empty(self) -> bool {
        self.rows == 0 && self.cells.is_empty()
    }

    /// The cells to visit: every cell of a marked row, and each marked cell outside them.
    pub(crate) fn num_cells(self) -> usize {
        self.rows.count_ones() as usize * TILE_SIZE + self.cells.len()
    }

    /// Calls `f` with the offset of every cell that may have been written, once each: every cell of the marked
    /// rows, then the marked cells outside them. Cells of a marked row may be unwritten (still `fill`).
    #[inline]
    pub(crate) fn for_each(self, mut f: impl FnMut(usize)) {
        for_each_row(self.rows, |r| {
            (r * TILE_SIZE..(r + 1) * TILE_SIZE).for_each(&mut f)
        });
        for &offset in self.cells {
            let k = usize::from(offset) & (TILE_CELLS - 1);
            if self.rows & (1 << (k >> TILE_SHIFT)) == 0 {
                f(k);
            }
        }
    }
}

impl Marked<'_> {
    /// The rows that hold a marked cell or are marked whole, as a row mask ([`super::TileGrid::mark_rows`]).
    pub(crate) fn rows_covered(self) -> u64 {
        self.cells.iter().fold(self.rows, |rows, &offset| {
            rows | 1 << ((usize::from(offset) & (TILE_CELLS - 1)) >> TILE_SHIFT)
        })
    }

    /// Resets every cell that may have been written in `tile` to `fill`: the cells of the marked rows, and the
    /// marked cells.
    #[inline]
    pub(crate) fn reset<T: Copy>(self, tile: &mut [T; TILE_CELLS], fill: T) {
        for_each_row(self.rows, |r| tile[r * TILE_SIZE..(r + 1) * TILE_SIZE].fill(fill));
        for &offset in self.cells {
            tile[usize::from(offset) & (TILE_CELLS - 1)] = fill;
        }
    }
}

impl CellMarks {
    pub(super) const EMPTY: Self = Self {
        len: 0,
        offsets: [0; TILE_CELLS + 1],
    };

    /// Marks the cell at `offset` if `first` (its first write since the tile was placed).
    #[cfg(test)]
    pub(crate) fn mark_if(&mut self, offset: usize, first: bool) {
        self.len = self.mark_after(self.len, offset, first);
    }

    /// Marks the cell at `offset` after the first `len` marks if `first` (its first write since the tile was
    /// placed), and returns the new count, for a caller that keeps the count itself, in a register across a
    /// loop, and stores it with [`CellMarks::set_len`] when the loop ends.
    #[inline(always)]
    pub(crate) fn mark_after(&mut self, len: usize, offset: usize, first: bool) -> usize {
        let n = len.min(TILE_CELLS);
        self.offsets[n] = offset as u16;
        n + usize::from(first)
    }

    /// The number of marks.
    #[inline(always)]
    pub(crate) fn count(&self) -> usize {
        self.len
    }

    /// Stores the count of a caller of [`CellMarks::mark_after`].
    #[inline(always)]
    pub(crate) fn set_len(&mut self, len: usize) {
        self.len = len.min(TILE_CELLS);
    }

    /// The marked cells' offsets.
    pub(crate) fn as_slice(&self) -> &[u16] {
        &self.offsets[..self.len.min(TILE_CELLS)]
    }

    pub(super) fn clear(&mut self) {
        self.len = 0;
    }
}
