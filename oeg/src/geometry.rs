//! Grid geometry: cells, regions and the conversions between world coordinates and cell indices.
//!
//! # Convention
//!
//! The map's cells tile the world's x-y plane. Cell `(i, j)` covers
//! `x in [i * r, (i + 1) * r)` and `y in [j * r, (j + 1) * r)` where `r` is the resolution in metres: +i runs
//! along +x, +j along +y, and the map's cell `(0, 0)` has its min-x, min-y corner at the world origin. Indices may
//! be negative, since the map grows wherever the robot looks.
//!
//! A [`CellRegion`] is a rectangular window of cells; its local cell `(0, 0)` is its min-x, min-y corner, and a
//! dense raster over it (a [`crate::Layer`]) is stored row by row: the value of local cell `(u, v)` is at
//! `v * num_x + u`. Row 0 is therefore the *southern* (min-y) row; image writers flip it so north is up.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Index of one map cell: cell `(i, j)` covers `[i r, (i + 1) r) x [j r, (j + 1) r)` for the resolution `r`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct CellIndex {
    /// Column, along +x.
    pub i: i32,
    /// Row, along +y.
    pub j: i32,
}

impl CellIndex {
    /// The cell `(i, j)`.
    pub const fn new(i: i32, j: i32) -> Self {
        Self { i, j }
    }
}

/// The smallest resolution a map accepts, in metres. Below it f32 elevations and f64 indices stop being exact
/// enough to be worth the memory.
pub const MIN_RESOLUTION_M: f64 = 0.001;
/// The largest resolution a map accepts, in metres.
pub const MAX_RESOLUTION_M: f64 = 100.0;

/// The grid's spacing and the world <-> cell conversions.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GridGeometry {
    resolution_m: f64,
}

impl GridGeometry {
    /// A grid with square cells `resolution_m` wide.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] unless `resolution_m` is finite and within
    /// [`MIN_RESOLUTION_M`]..=[`MAX_RESOLUTION_M`].
    pub fn new(resolution_m: f64) -> Result<Self> {
        if !resolution_m.is_finite() || !(MIN_RESOLUTION_M..=MAX_RESOLUTION_M).contains(&resolution_m) {
            return Err(Error::setting(
                "resolution_m",
                format!(
                    "must be a number of metres between {MIN_RESOLUTION_M} and {MAX_RESOLUTION_M}, \
                     got {resolution_m}"
                ),
            ));
        }
        Ok(Self { resolution_m })
    }

    /// The cell size in metres.
    pub fn resolution_m(&self) -> f64 {
        self.resolution_m
    }

    /// The cell holding the world point `(x, y)`, or `None` if the point is not finite or lies beyond the
    /// range of `i32` indices.
    #[inline]
    pub fn cell_of(&self, x_m: f64, y_m: f64) -> Option<CellIndex> {
        Some(CellIndex::new(self.axis_index(x_m)?, self.axis_index(y_m)?))
    }

    /// The index along one axis of the cell holding coordinate `v_m`.
    #[inline]
    pub fn axis_index(&self, v_m: f64) -> Option<i32> {
        let f = v_m / self.resolution_m;
        // The bounds also reject NaN, since every comparison with NaN is false.
        if f >= f64::from(i32::MIN) && f < f64::from(i32::MAX) {
            // floor() without the libm call it costs on baseline x86-64: truncate, then step down for negative
            // non-integers.
            let t = f as i64;
            Some((t - i64::from((t as f64) > f)) as i32)
        } else {
            None
        }
    }

    /// The world coordinates of a cell's centre.
    pub fn cell_center(&self, cell: CellIndex) -> (f64, f64) {
        (
            (f64::from(cell.i) + 0.5) * self.resolution_m,
            (f64::from(cell.j) + 0.5) * self.resolution_m,
        )
    }

    /// The world coordinates of a cell's min-x, min-y corner.
    pub fn cell_min_corner(&self, cell: CellIndex) -> (f64, f64) {
        (
            f64::from(cell.i) * self.resolution_m,
            f64::from(cell.j) * self.resolution_m,
        )
    }

    /// The region of cells that covers the world rectangle `[min, max]` (both corners included).
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] if a corner is not finite, beyond the index range, or `max < min`.
    pub fn region_covering(&self, min_xy_m: (f64, f64), max_xy_m: (f64, f64)) -> Result<CellRegion> {
        let bad = || {
            Error::setting(
                "region",
                format!("cannot cover the rectangle from {min_xy_m:?} to {max_xy_m:?} m"),
            )
        };
        let lo = self.cell_of(min_xy_m.0, min_xy_m.1).ok_or_else(bad)?;
        let hi = self.cell_of(max_xy_m.0, max_xy_m.1).ok_or_else(bad)?;
        if hi.i < lo.i || hi.j < lo.j {
            return Err(bad());
        }
        CellRegion::from_corners(lo, hi).ok_or_else(bad)
    }
}

/// A rectangle of cells from `min` to `min + (num_x - 1, num_y - 1)`, both corners included.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct CellRegion {
    /// The min-x, min-y cell: local cell `(0, 0)`.
    pub min: CellIndex,
    /// Number of cells along x.
    pub num_x: u32,
    /// Number of cells along y.
    pub num_y: u32,
}

impl CellRegion {
    /// The region spanning `lo` to `hi`, both included; `None` if `hi` is below `lo` on an axis.
    pub fn from_corners(lo: CellIndex, hi: CellIndex) -> Option<Self> {
        let num_x = u32::try_from(i64::from(hi.i) - i64::from(lo.i) + 1).ok()?;
        let num_y = u32::try_from(i64::from(hi.j) - i64::from(lo.j) + 1).ok()?;
        (num_x > 0 && num_y > 0).then_some(Self {
            min: lo,
            num_x,
            num_y,
        })
    }

    /// Number of cells in the region.
    pub fn num_cells(&self) -> u64 {
        u64::from(self.num_x) * u64::from(self.num_y)
    }

    /// The max-x, max-y cell.
    pub fn max(&self) -> CellIndex {
        CellIndex::new(
            (i64::from(self.min.i) + i64::from(self.num_x) - 1) as i32,
            (i64::from(self.min.j) + i64::from(self.num_y) - 1) as i32,
        )
    }

    /// Whether `cell` lies inside the region.
    pub fn contains(&self, cell: CellIndex) -> bool {
        self.local(cell).is_some()
    }

    /// The local coordinates `(u, v)` of `cell`, or `None` outside the region.
    pub fn local(&self, cell: CellIndex) -> Option<(u32, u32)> {
        let u = u32::try_from(i64::from(cell.i) - i64::from(self.min.i)).ok()?;
        let v = u32::try_from(i64::from(cell.j) - i64::from(self.min.j)).ok()?;
        (u < self.num_x && v < self.num_y).then_some((u, v))
    }

    /// The row-major offset of `cell` in a raster over this region, or `None` outside it.
    pub fn offset(&self, cell: CellIndex) -> Option<usize> {
        let (u, v) = self.local(cell)?;
        Some(v as usize * self.num_x as usize + u as usize)
    }

    /// The cell at local coordinates `(u, v)`.
    pub fn cell_at(&self, u: u32, v: u32) -> CellIndex {
        CellIndex::new(
            (i64::from(self.min.i) + i64::from(u)) as i32,
            (i64::from(self.min.j) + i64::from(v)) as i32,
        )
    }

    /// The smallest region holding both `self` and `other`.
    pub fn union(&self, other: &CellRegion) -> CellRegion {
        let (a, b) = (self.max(), other.max());
        let lo = CellIndex::new(self.min.i.min(other.min.i), self.min.j.min(other.min.j));
        let hi = CellIndex::new(a.i.max(b.i), a.j.max(b.j));
        // Both inputs are valid, so their union is too.
        Self::from_corners(lo, hi).unwrap_or(*self)
    }

    /// The cells `self` and `other` share, or `None` when they share none.
    pub fn intersection(&self, other: &CellRegion) -> Option<CellRegion> {
        let (a, b) = (self.max(), other.max());
        Self::from_corners(
            CellIndex::new(self.min.i.max(other.min.i), self.min.j.max(other.min.j)),
            CellIndex::new(a.i.min(b.i), a.j.min(b.j)),
        )
    }

    /// Every cell of the region, row by row (the raster order).
    pub fn cells(&self) -> impl Iterator<Item = CellIndex> + '_ {
        (0..self.num_y).flat_map(move |v| (0..self.num_x).map(move |u| self.cell_at(u, v)))
    }
}

/// A window onto the grid: its geometry and a rectangle of its cells, the one value every dense raster over a
/// part of the map (a layer, the truth, a figure, a planner's files) is laid out by. grid_map's
/// `SubmapGeometry` is the model: the map's geometry is set once, and a window onto it is one value, not a
/// resolution and a region carried side by side.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GridWindow {
    geometry: GridGeometry,
    region: CellRegion,
}

impl GridWindow {
    /// The window onto `geometry`'s grid over `region`.
    pub const fn new(geometry: GridGeometry, region: CellRegion) -> Self {
        Self { geometry, region }
    }

    /// The window over the world rectangle from `min_xy_m` (included) to `max_xy_m` (excluded): the cells
    /// whose min-x, min-y corner lies in it, and the cell holding `min_xy_m`. A region given in metres, such
    /// as a scenario's `[map]` region, is read by this one rule, so a rectangle whose sides are whole cells
    /// covers exactly those cells and no row beyond them.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] if a corner is not finite, lies beyond the grid's index range, or
    /// `max_xy_m` is not above `min_xy_m` on both axes.
    pub fn covering(geometry: GridGeometry, min_xy_m: (f64, f64), max_xy_m: (f64, f64)) -> Result<Self> {
        if !(max_xy_m.0 > min_xy_m.0 && max_xy_m.1 > min_xy_m.1) {
            return Err(Error::setting(
                "region",
                format!(
                    "the rectangle from {min_xy_m:?} to {max_xy_m:?} m is empty; expected its max corner above \
                     its min corner on both axes"
                ),
            ));
        }
        // The max corner is excluded: a point a millionth of a cell inside it picks the last cell covered.
        let eps = geometry.resolution_m() * 1e-6;
        let region = geometry.region_covering(min_xy_m, (max_xy_m.0 - eps, max_xy_m.1 - eps))?;
        Ok(Self { geometry, region })
    }

    /// The grid's geometry.
    pub const fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    /// The cells of the window.
    pub const fn region(&self) -> &CellRegion {
        &self.region
    }

    /// The cell size, metres.
    pub fn resolution_m(&self) -> f64 {
        self.geometry.resolution_m()
    }

    /// The number of cells in the window.
    pub fn num_cells(&self) -> u64 {
        self.region.num_cells()
    }

    /// The world coordinates of the window's min-x, min-y corner, metres.
    pub fn min_corner_m(&self) -> (f64, f64) {
        self.geometry.cell_min_corner(self.region.min)
    }

    /// The window's width and height, metres.
    pub fn size_m(&self) -> (f64, f64) {
        let r = self.resolution_m();
        (f64::from(self.region.num_x) * r, f64::from(self.region.num_y) * r)
    }

    /// The row-major offset of the cell holding the world point `(x, y)`, or `None` outside the window.
    pub fn offset_of(&self, x_m: f64, y_m: f64) -> Option<usize> {
        self.region.offset(self.geometry.cell_of(x_m, y_m)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cell_zero_starts_at_the_world_origin() {
        let g = GridGeometry::new(0.1).expect("valid resolution");
        assert_eq!(g.cell_of(0.0, 0.0), Some(CellIndex::new(0, 0)));
        assert_eq!(g.cell_of(0.0999, 0.0999), Some(CellIndex::new(0, 0)));
        assert_eq!(g.cell_of(0.1, 0.25), Some(CellIndex::new(1, 2)));
        assert_eq!(g.cell_of(-0.0001, -0.1), Some(CellIndex::new(-1, -1)));
        let (cx, cy) = g.cell_center(CellIndex::new(1, -3));
        assert!((cx - 0.15).abs() < 1e-12 && (cy + 0.25).abs() < 1e-12);
    }

    #[test]
    fn non_finite_and_far_points_have_no_cell() {
        let g = GridGeometry::new(0.05).expect("valid resolution");
        assert_eq!(g.cell_of(f64::NAN, 0.0), None);
        assert_eq!(g.cell_of(0.0, f64::INFINITY), None);
        assert_eq!(g.cell_of(1e12, 0.0), None);
    }

    #[test]
    fn bad_resolutions_are_rejected() {
        for r in [0.0, -0.1, f64::NAN, f64::INFINITY, 1e-6, 1e6] {
            let err = GridGeometry::new(r).expect_err("must be rejected");
            assert!(err.to_string().contains("resolution_m"), "{err}");
        }
    }

    #[test]
    fn regions_intersect_in_the_cells_they_share_and_in_none_apart() {
        let region = |lo: (i32, i32), hi: (i32, i32)| {
            CellRegion::from_corners(CellIndex::new(lo.0, lo.1), CellIndex::new(hi.0, hi.1)).expect("valid")
        };
        let a = region((-2, 5), (1, 7));
        assert_eq!(
            a.intersection(&region((0, 6), (9, 9))),
            Some(region((0, 6), (1, 7)))
        );
        assert_eq!(a.intersection(&a), Some(a));
        // Touching corners share one cell; apart on one axis, none.
        assert_eq!(
            a.intersection(&region((1, 7), (3, 8))),
            Some(region((1, 7), (1, 7)))
        );
        assert_eq!(a.intersection(&region((2, 5), (3, 7))), None);
        assert_eq!(a.intersection(&region((-2, 8), (1, 9))), None);
    }

    #[test]
    fn region_offsets_are_row_major_from_the_min_corner() {
        let r = CellRegion::from_corners(CellIndex::new(-2, 5), CellIndex::new(1, 7)).expect("valid");
        assert_eq!((r.num_x, r.num_y), (4, 3));
        assert_eq!(r.offset(CellIndex::new(-2, 5)), Some(0));
        assert_eq!(r.offset(CellIndex::new(1, 5)), Some(3));
        assert_eq!(r.offset(CellIndex::new(-2, 6)), Some(4));
        assert_eq!(r.offset(CellIndex::new(2, 6)), None);
        assert_eq!(r.max(), CellIndex::new(1, 7));
        let all: Vec<_> = r.cells().collect();
        assert_eq!(all.len(), 12);
        assert_eq!(all[5], CellIndex::new(-1, 6));
        assert!(CellRegion::from_corners(CellIndex::new(1, 1), CellIndex::new(0, 1)).is_none());
    }

    #[test]
    fn region_covering_includes_both_corners() {
        let g = GridGeometry::new(0.5).expect("valid resolution");
        let r = g.region_covering((-1.0, 0.0), (1.0, 0.49)).expect("valid");
        assert_eq!(r.min, CellIndex::new(-2, 0));
        assert_eq!((r.num_x, r.num_y), (5, 1));
    }

    #[test]
    fn a_window_covers_whole_cells_of_its_rectangle_and_no_row_beyond() {
        let g = GridGeometry::new(0.05).expect("valid");
        // Sides of whole cells: 20 x 10 cells, the max corner excluded.
        let w = GridWindow::covering(g, (0.0, -0.25), (1.0, 0.25)).expect("valid");
        assert_eq!(
            (w.region().min, w.region().num_x, w.region().num_y),
            (CellIndex::new(0, -5), 20, 10)
        );
        assert_eq!(w.size_m(), (1.0, 0.5));
        assert_eq!(w.offset_of(0.999, 0.249), Some(w.num_cells() as usize - 1));
        assert_eq!(w.offset_of(1.0, 0.0), None);
        // A corner inside a cell takes that cell whole.
        let w = GridWindow::covering(g, (0.03, 0.0), (0.08, 0.05)).expect("valid");
        assert_eq!((w.region().num_x, w.region().num_y), (2, 1));
        assert_eq!(w.min_corner_m(), (0.0, 0.0));
    }

    #[test]
    fn an_empty_or_non_finite_rectangle_has_no_window() {
        let g = GridGeometry::new(0.1).expect("valid");
        for (lo, hi) in [
            ((0.0, 0.0), (0.0, 1.0)),
            ((1.0, 0.0), (0.0, 1.0)),
            ((0.0, 0.0), (f64::NAN, 1.0)),
        ] {
            let err = GridWindow::covering(g, lo, hi).expect_err("must be refused");
            assert!(err.to_string().contains("region"), "{err}");
        }
    }
}
