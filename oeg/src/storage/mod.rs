//! Sparse tiled storage: the map pays only for the areas that were observed.
//!
//! Cells live in square tiles of [`TILE_SIZE`] x [`TILE_SIZE`], allocated on first write. A dense index of tile
//! pointers covers the bounding box of the allocated tiles and grows on demand, so a cell lookup is two
//! shifts, a bounds check and two indexings: no hashing in the hot loop. The index costs 8 bytes per tile
//! slot (512 bytes per 409.6 m^2 at 0.05 m), which is counted in [`TileGrid::memory_bytes`].

mod marked;
mod marks;

pub(crate) use marked::marked_by_tile;
#[cfg(test)]
use marks::for_each_row;
pub(crate) use marks::{CellMarks, Marked};

use crate::geometry::CellIndex;
#[cfg(test)]
use crate::geometry::CellRegion;

/// log2 of the tile edge in cells.
pub(crate) const TILE_SHIFT: u32 = 6;
/// Tile edge, cells.
pub(crate) const TILE_SIZE: usize = 1 << TILE_SHIFT;
/// Cells per tile.
pub(crate) const TILE_CELLS: usize = TILE_SIZE * TILE_SIZE;
pub(crate) const TILE_MASK: i32 = (TILE_SIZE as i32) - 1;

/// Tiles a thread takes at a time in a pass over tiles in parallel (`with_max_len`): one. A pass's tiles hold
/// very different numbers of cells to visit (a laser line's near tiles most of its cells), and rayon's adaptive
/// split otherwise stops at runs of several tiles, so a thread that finished its share waits for the other's
/// run; with one tile a job, it takes the next tile instead. Measured on 2 threads, alternating 21 runs of each
/// build on the default scenario's laser lines and on its stereo frames (`oeg map` of logs recorded from the
/// scenario with only those sensors, `integrate_wall_time_s`): 0.92 and 0.93 of the time with the default split.
pub(crate) const TILES_PER_JOB: usize = 1;

/// A tile's coordinates: cell `(i, j)` is in tile `(i >> TILE_SHIFT, j >> TILE_SHIFT)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct TileIndex {
    /// Tile column.
    pub ti: i32,
    /// Tile row.
    pub tj: i32,
}

impl TileIndex {
    /// The tile holding `cell`.
    #[inline]
    pub(crate) fn of(cell: CellIndex) -> Self {
        Self {
            ti: cell.i >> TILE_SHIFT,
            tj: cell.j >> TILE_SHIFT,
        }
    }

    /// Whether the tile's cells are representable ([`CellIndex`] is `i32`): tiles from `i32::MIN >> 6` to
    /// `i32::MAX >> 6` on each axis. Every [`TileIndex::of`] a cell is.
    pub(crate) fn is_representable(self) -> bool {
        let range = (i32::MIN >> TILE_SHIFT)..=(i32::MAX >> TILE_SHIFT);
        range.contains(&self.ti) && range.contains(&self.tj)
    }

    /// The tile's first cell (min-x, min-y).
    pub(crate) fn first_cell(self) -> CellIndex {
        CellIndex::new(self.ti << TILE_SHIFT, self.tj << TILE_SHIFT)
    }

    /// The tile's cell at `offset` ([`offset_in_tile`]; the bits above a tile's are ignored).
    #[inline]
    pub(crate) fn cell(self, offset: usize) -> CellIndex {
        let (first, k) = (self.first_cell(), offset & (TILE_CELLS - 1));
        CellIndex::new(
            first.i + (k % TILE_SIZE) as i32,
            first.j + (k >> TILE_SHIFT) as i32,
        )
    }
}

/// Offset of a cell inside its tile, row-major.
#[inline]
pub(crate) fn offset_in_tile(cell: CellIndex) -> usize {
    (((cell.j & TILE_MASK) as usize) << TILE_SHIFT) | (cell.i & TILE_MASK) as usize
}

/// One tile's cells.
pub(crate) type Tile<T> = Box<[T; TILE_CELLS]>;

/// A sparse grid of `T`, allocated tile by tile. Cells never written read as the `fill` value.
#[derive(Debug, Clone)]
pub(crate) struct TileGrid<T> {
    fill: T,
    /// Tile rectangle covered by `slots`.
    tile_min: TileIndex,
    tiles_x: usize,
    tiles_y: usize,
    slots: Vec<Option<Tile<T>>>,
    /// What was written in each slot's tile since it was placed, marked by rows ([`TileGrid::mark_rows`], bit
    /// `r` for row `r`) or by cells ([`TileGrid::slot_tile_and_marks_mut`]); each empty for a grid that never
    /// marks that way (the map's layers never do), as long as `slots` for one that does (the scan scratch).
    rows: Vec<u64>,
    marks: Vec<Option<Box<CellMarks>>>,
    /// Lists in `marks` (each has room for a whole tile, for good: marking never reallocates).
    num_mark_lists: usize,
    num_tiles: usize,
    /// Tiles released by [`TileGrid::recycle_marked`], reset to `fill`, reused before allocating.
    pool: Vec<Tile<T>>,
}

/// Why a tile could not be allocated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct CapacityExceeded {
    /// Bytes the grid would have held; `u64::MAX` for a tile that is not representable
    /// ([`TileIndex::is_representable`]), which no amount of memory could hold.
    pub requested_bytes: u64,
}

impl<T: Copy> TileGrid<T> {
    /// An empty grid whose unwritten cells read as `fill`.
    pub(crate) fn new(fill: T) -> Self {
        Self {
            fill,
            tile_min: TileIndex { ti: 0, tj: 0 },
            tiles_x: 0,
            tiles_y: 0,
            slots: Vec::new(),
            rows: Vec::new(),
            marks: Vec::new(),
            num_mark_lists: 0,
            num_tiles: 0,
            pool: Vec::new(),
        }
    }

    /// Bytes held by one tile.
    pub(crate) const fn tile_bytes() -> usize {
        size_of::<[T; TILE_CELLS]>()
    }

    /// Number of allocated tiles.
    pub(crate) fn num_tiles(&self) -> usize {
        self.num_tiles
    }

    /// Number of tiles kept for reuse: that many tiles can be placed without new memory.
    pub(crate) fn num_pooled(&self) -> usize {
        self.pool.len()
    }

    /// Whether `tile` is allocated.
    pub(crate) fn has_tile(&self, tile: TileIndex) -> bool {
        self.slot(tile).is_some_and(|slot| self.slots[slot].is_some())
    }

    /// Bytes allocated: tiles (in use and pooled), the tile index, the marks, and the grid itself.
    pub(crate) fn memory_bytes(&self) -> u64 {
        ((self.num_tiles + self.pool.len()) * Self::tile_bytes()
            + self.slots.capacity() * size_of::<Option<Tile<T>>>()
            + self.rows.capacity() * size_of::<u64>()
            + self.marks.capacity() * size_of::<Option<Box<CellMarks>>>()
            + self.num_mark_lists * size_of::<CellMarks>()
            + size_of::<Self>()) as u64
    }

    #[inline]
    fn slot(&self, tile: TileIndex) -> Option<usize> {
        let u = tile.ti.wrapping_sub(self.tile_min.ti) as u32 as usize;
        let v = tile.tj.wrapping_sub(self.tile_min.tj) as u32 as usize;
        (u < self.tiles_x && v < self.tiles_y).then(|| v * self.tiles_x + u)
    }

    /// The cell's value, or `None` if its tile was never allocated.
    #[inline]
    pub(crate) fn get(&self, cell: CellIndex) -> Option<&T> {
        let slot = self.slot(TileIndex::of(cell))?;
        self.slots[slot].as_ref().map(|t| &t[offset_in_tile(cell)])
    }

    /// The cell's value, allocating its tile (filled with `fill`) if needed. Fails if the grid would then hold
    /// more than `limit_bytes`.
    #[inline]
    #[cfg(test)]
    pub(crate) fn get_or_insert(
        &mut self,
        cell: CellIndex,
        limit_bytes: u64,
    ) -> Result<&mut T, CapacityExceeded> {
        let tile = TileIndex::of(cell);
        let slot = match self.slot(tile) {
            Some(slot) if self.slots[slot].is_some() => slot,
            _ => self.allocate(tile, limit_bytes, None)?,
        };
        match self.slots[slot].as_mut() {
            Some(t) => Ok(&mut t[offset_in_tile(cell)]),
            None => unreachable!("the slot was just allocated"),
        }
    }

    /// The index slot of `tile`, allocating the tile (filled with `fill`) if needed, for repeated access with
    /// [`TileGrid::slot_tile_mut`] while a walk stays inside one tile. Fails past `limit_bytes`.
    #[inline]
    pub(crate) fn slot_or_insert(
        &mut self,
        tile: TileIndex,
        limit_bytes: u64,
    ) -> Result<usize, CapacityExceeded> {
        match self.slot(tile) {
            Some(slot) if self.slots[slot].is_some() => Ok(slot),
            _ => self.allocate(tile, limit_bytes, None),
        }
    }

    /// The tile in `slot`, from [`TileGrid::slot_or_insert`] with no allocation or re-indexing in between.
    #[inline]
    pub(crate) fn slot_tile_mut(&mut self, slot: usize) -> &mut [T; TILE_CELLS] {
        match self.slots[slot].as_deref_mut() {
            Some(t) => t,
            None => unreachable!("slots come from slot_or_insert"),
        }
    }

    /// The whole tile at `tile`, allocating it (filled with `fill`) if needed. Fails past `limit_bytes`.
    pub(crate) fn tile_or_insert(
        &mut self,
        tile: TileIndex,
        limit_bytes: u64,
    ) -> Result<&mut [T; TILE_CELLS], CapacityExceeded> {
        let slot = match self.slot(tile) {
            Some(slot) if self.slots[slot].is_some() => slot,
            _ => self.allocate(tile, limit_bytes, None)?,
        };
        match self.slots[slot].as_deref_mut() {
            Some(t) => Ok(t),
            None => unreachable!("the slot was just allocated"),
        }
    }

    /// Puts `recycled` (or a new tile) at `tile`, growing the index if needed; returns the slot.
    #[cold]
    fn allocate(
        &mut self,
        tile: TileIndex,
        limit_bytes: u64,
        recycled: Option<Tile<T>>,
    ) -> Result<usize, CapacityExceeded> {
        if self.slot(tile).is_none() {
            self.grow_to_cover(tile, limit_bytes)?;
        }
        let recycled = recycled.or_else(|| self.pool.pop());
        // A grid that marks cells gives the slot its list on its first mark: counted here, before.
        let marks_bytes = match self.marks.get(self.slot(tile).unwrap_or(usize::MAX)) {
            Some(None) => size_of::<CellMarks>(),
            _ => 0,
        };
        let requested_bytes = self.memory_bytes() + (Self::tile_bytes() + marks_bytes) as u64;
        if recycled.is_none() && requested_bytes > limit_bytes {
            return Err(CapacityExceeded { requested_bytes });
        }
        let slot = self
            .slot(tile)
            .unwrap_or_else(|| unreachable!("the index covers the tile"));
        let fill = self.fill;
        self.slots[slot] = Some(recycled.unwrap_or_else(|| Box::new([fill; TILE_CELLS])));
        self.num_tiles += 1;
        Ok(slot)
    }

    fn grow_to_cover(&mut self, tile: TileIndex, limit_bytes: u64) -> Result<(), CapacityExceeded> {
        if !tile.is_representable() {
            return Err(CapacityExceeded {
                requested_bytes: u64::MAX,
            });
        }
        // Grow with slack (a quarter of the current size, at least 4 tiles per side) so a robot driving in one
        // direction re-indexes O(log n) times.
        let (lo_i, lo_j, hi_i, hi_j) = if self.tiles_x == 0 {
            (
                i64::from(tile.ti) - 4,
                i64::from(tile.tj) - 4,
                i64::from(tile.ti) + 4,
                i64::from(tile.tj) + 4,
            )
        } else {
            let (cur_lo_i, cur_lo_j) = (i64::from(self.tile_min.ti), i64::from(self.tile_min.tj));
            let (cur_hi_i, cur_hi_j) = (
                cur_lo_i + self.tiles_x as i64 - 1,
                cur_lo_j + self.tiles_y as i64 - 1,
            );
            let slack_i = (self.tiles_x as i64 / 4).max(4);
            let slack_j = (self.tiles_y as i64 / 4).max(4);
            let t_i = i64::from(tile.ti);
            let t_j = i64::from(tile.tj);
            (
                if t_i < cur_lo_i { t_i - slack_i } else { cur_lo_i },
                if t_j < cur_lo_j { t_j - slack_j } else { cur_lo_j },
                if t_i > cur_hi_i { t_i + slack_i } else { cur_hi_i },
                if t_j > cur_hi_j { t_j + slack_j } else { cur_hi_j },
            )
        };
        let clamp = |v: i64| {
            v.clamp(
                i64::from(i32::MIN >> TILE_SHIFT),
                i64::from(i32::MAX >> TILE_SHIFT),
            )
        };
        let (lo_i, lo_j, hi_i, hi_j) = (clamp(lo_i), clamp(lo_j), clamp(hi_i), clamp(hi_j));
        let new_x = (hi_i - lo_i + 1) as u64;
        let new_y = (hi_j - lo_j + 1) as u64;
        // Each slot of the index: the tile's pointer, and a grid that marks has a row mask and a list's pointer
        // too. The old index is still held while the new one is filled.
        let (by_rows, by_cells) = (!self.rows.is_empty(), !self.marks.is_empty());
        let slot_bytes = (size_of::<Option<Tile<T>>>()
            + if by_rows { size_of::<u64>() } else { 0 }
            + if by_cells {
                size_of::<Option<Box<CellMarks>>>()
            } else {
                0
            }) as u64;
        let old_slots = (self.tiles_x * self.tiles_y) as u64;
        let requested_bytes = ((self.num_tiles + self.pool.len()) * Self::tile_bytes()) as u64
            + (new_x.saturating_mul(new_y).saturating_add(old_slots)).saturating_mul(slot_bytes);
        if requested_bytes > limit_bytes {
            return Err(CapacityExceeded { requested_bytes });
        }
        let (new_x, new_y) = (new_x as usize, new_y as usize);
        let mut slots: Vec<Option<Tile<T>>> = Vec::new();
        slots.resize_with(new_x * new_y, || None);
        let mut rows = vec![0u64; if by_rows { new_x * new_y } else { 0 }];
        let mut marks: Vec<Option<Box<CellMarks>>> = Vec::new();
        marks.resize_with(if by_cells { new_x * new_y } else { 0 }, || None);
        let new_min = TileIndex {
            ti: lo_i as i32,
            tj: lo_j as i32,
        };
        for v in 0..self.tiles_y {
            for u in 0..self.tiles_x {
                let (nu, nv) = (
                    (i64::from(self.tile_min.ti) + u as i64 - lo_i) as usize,
                    (i64::from(self.tile_min.tj) + v as i64 - lo_j) as usize,
                );
                let (from, to) = (v * self.tiles_x + u, nv * new_x + nu);
                slots[to] = self.slots[from].take();
                if by_rows {
                    rows[to] = self.rows[from];
                }
                if by_cells {
                    marks[to] = self.marks[from].take();
                }
            }
        }
        self.slots = slots;
        self.rows = rows;
        self.marks = marks;
        self.tile_min = new_min;
        self.tiles_x = new_x;
        self.tiles_y = new_y;
        Ok(())
    }

    /// Allocated tiles in a deterministic order (row by row over the tile index), with their coordinates.
    pub(crate) fn tiles(&self) -> impl Iterator<Item = (TileIndex, &[T; TILE_CELLS])> + '_ {
        self.slots.iter().enumerate().filter_map(move |(slot, t)| {
            let tile = TileIndex {
                ti: self.tile_min.ti + (slot % self.tiles_x.max(1)) as i32,
                tj: self.tile_min.tj + (slot / self.tiles_x.max(1)) as i32,
            };
            t.as_deref().map(|t| (tile, t))
        })
    }

    /// The allocated tiles among `tiles`, mutable, for tiles given in the order of [`TileGrid::tiles`] (row by
    /// row over the tile index, as another grid's [`TileGrid::marked_tiles`] yields them): the cost is that of
    /// the tiles asked for, not of the grid. A tile out of that order, or not allocated, is left out.
    pub(crate) fn tiles_mut_in_order(
        &mut self,
        tiles: impl IntoIterator<Item = TileIndex>,
    ) -> Vec<(TileIndex, &mut [T; TILE_CELLS])> {
        let (min, tiles_x, tiles_y) = (self.tile_min, self.tiles_x, self.tiles_y);
        let slot_of = |tile: TileIndex| {
            let u = tile.ti.wrapping_sub(min.ti) as u32 as usize;
            let v = tile.tj.wrapping_sub(min.tj) as u32 as usize;
            (u < tiles_x && v < tiles_y).then(|| v * tiles_x + u)
        };
        let mut found = Vec::new();
        let (mut rest, mut base): (&mut [Option<Tile<T>>], usize) = (&mut self.slots, 0);
        for tile in tiles {
            let Some(slot) = slot_of(tile).filter(|s| *s >= base) else {
                continue;
            };
            let (_, from) = std::mem::take(&mut rest).split_at_mut(slot - base);
            let Some((at, after)) = from.split_first_mut() else {
                break;
            };
            if let Some(t) = at.as_deref_mut() {
                found.push((tile, t));
            }
            (rest, base) = (after, slot + 1);
        }
        found
    }

    /// The tile at `tile`, if allocated.
    pub(crate) fn tile_mut(&mut self, tile: TileIndex) -> Option<&mut [T; TILE_CELLS]> {
        let slot = self.slot(tile)?;
        self.slots[slot].as_deref_mut()
    }

    /// Inserts a whole tile (used by the map reader). Fails past `limit_bytes`.
    pub(crate) fn insert_tile(
        &mut self,
        tile: TileIndex,
        cells: Tile<T>,
        limit_bytes: u64,
    ) -> Result<(), CapacityExceeded> {
        if let Some(slot) = self.slot(tile)
            && let Some(existing) = self.slots[slot].as_mut()
        {
            *existing = cells;
            return Ok(());
        }
        let requested_bytes = self.memory_bytes() + Self::tile_bytes() as u64;
        if requested_bytes > limit_bytes {
            return Err(CapacityExceeded { requested_bytes });
        }
        self.allocate(tile, limit_bytes, Some(cells)).map(|_| ())
    }

    /// The tile at `tile`, if allocated.
    #[inline]
    pub(crate) fn tile(&self, tile: TileIndex) -> Option<&[T; TILE_CELLS]> {
        let slot = self.slot(tile)?;
        self.slots[slot].as_deref()
    }

    /// The cell region spanned by the allocated tiles, or `None` if there are none.
    #[cfg(test)]
    pub(crate) fn tile_region(&self) -> Option<CellRegion> {
        let mut it = self.tiles().map(|(t, _)| t);
        let first = it.next()?;
        let (mut lo, mut hi) = (first, first);
        for t in it {
            lo = TileIndex {
                ti: lo.ti.min(t.ti),
                tj: lo.tj.min(t.tj),
            };
            hi = TileIndex {
                ti: hi.ti.max(t.ti),
                tj: hi.tj.max(t.tj),
            };
        }
        let max_cell = CellIndex::new(
            hi.first_cell().i + (TILE_SIZE as i32 - 1),
            hi.first_cell().j + (TILE_SIZE as i32 - 1),
        );
        CellRegion::from_corners(lo.first_cell(), max_cell)
    }
}

#[cfg(test)]
mod tests;
