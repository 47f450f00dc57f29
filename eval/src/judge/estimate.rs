//! What a map says about every cell of the truth's region, whoever made it. The judge reads only this, so the
//! testbed's own map ([`Estimate::of_map`]) and the arrays of another mapper resampled onto the truth's grid
//! ([`Estimate::resample`]) are scored by the same code (`docs/scoring.md`).
//!
//! The resampling rule, for a truth cell (a square of the truth's resolution):
//! 1. its **sources** are the user's cells whose centres lie inside it; when none does (the user's grid is
//!    coarser, or shifted), the user's cell that contains the truth cell's centre; none outside the arrays;
//! 2. its **decision** is the most restrictive known decision of its sources (blocked, then uncertain, then
//!    drivable), as a costmap keeps the highest cost when it is downsampled; unknown when every source is;
//! 3. its **elevation** is the mean of its sources' elevations, and its **variance** that of the mixture of
//!    their Gaussians: the mean of their variances plus the variance of their elevations;
//! 4. its **occupancy** probability is the mean of its sources'.
//!
//! When the user's grid is the truth's (same resolution, origin on a cell corner), every truth cell has
//! exactly one source, and the arrays are taken as they are.

use oeg::{Doubt, GridWindow, LayerKind, Map, Traversability, TraversabilityRule};
use sim::truth::TruthRaster;

use crate::error::{EvalError, Result};

/// The most cells a user's arrays may hold (a 10,000 x 10,000 grid, 1 km a side at 0.1 m): larger ones are
/// refused before they are resampled.
pub const MAX_FOREIGN_CELLS: u64 = 100_000_000;
/// The largest elevation another mapper's map may hold, metres either side of zero (1000 km): beyond any terrain,
/// and small enough that its error squared stays finite, so an elevation metric is never infinite (which JSON
/// could only write as `null`, the same as "no elevation").
pub const MAX_ABS_ELEVATION_M: f64 = 1e6;

/// What a map says about each cell of a region: row-major over the truth's region, as the truth raster.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// The truth's cells, on the truth's grid.
    pub window: GridWindow,
    /// The map's decision on every cell; [`Traversability::Unknown`] where the map cannot decide.
    pub decisions: Vec<Traversability>,
    /// Why the map could not decide each uncertain cell, or each observed cell it left unknown ([`Map::doubt`]),
    /// `None` on the others; empty when the map does not say (another mapper's arrays).
    pub doubts: Vec<Option<Doubt>>,
    /// Whether the map observed the cell: for the testbed's map, a ray reached it; for another mapper's
    /// arrays, the cell has a decision, an elevation or an occupancy probability.
    pub observed: Vec<bool>,
    /// Elevation, world z, metres; NaN where there is no estimate. The three layers are kept in single
    /// precision, as the testbed's map stores them (another mapper's values are rounded to it: 6e-8 of their
    /// size, a tenth of a micrometre at 1 m), which halves the judge's largest rasters.
    pub elevation_m: Vec<f32>,
    /// The elevation's variance, m^2; NaN where there is none.
    pub variance_m2: Vec<f32>,
    /// Occupancy probability; NaN where there is none.
    pub occupancy: Vec<f32>,
    /// The testbed's own map's bookkeeping (zero for another mapper's arrays).
    pub totals: MapTotals,
}

/// A map's bookkeeping, reported beside its metrics.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MapTotals {
    /// Bytes the map holds.
    pub map_bytes: u64,
    /// Scans integrated.
    pub num_scans: u64,
    /// Rays integrated.
    pub num_rays: u64,
}

/// Another mapper's map as arrays: `rows` x `cols`, row 0 the min-y row and column 0 the min-x column (as
/// `oeg map --planner-files` writes them, and `matplotlib.pyplot.imshow(a, origin="lower")` shows them).
#[derive(Debug, Clone, PartialEq)]
pub struct ForeignMap {
    /// World x and y of the lower-left corner of cell `[0, 0]`, metres.
    pub origin_xy_m: [f64; 2],
    /// Cell size, metres.
    pub resolution_m: f64,
    /// Rows.
    pub rows: usize,
    /// Columns.
    pub cols: usize,
    /// The decisions.
    pub decisions: Vec<Traversability>,
    /// Elevations, metres (NaN: none).
    pub elevation_m: Option<Vec<f64>>,
    /// Elevation variances, m^2 (NaN: none).
    pub variance_m2: Option<Vec<f64>>,
    /// Occupancy probabilities (NaN: none).
    pub occupancy: Option<Vec<f64>>,
}

/// The decisions of integer codes, the testbed's own (`0` unknown, `1` free, `2` traversable, `3` blocked,
/// `4` uncertain: [`Traversability`] as `u8`, `docs/planner-protocol.md`).
///
/// # Errors
/// The first other code, with its row-major position.
pub fn decisions_from_codes(codes: &[i64]) -> std::result::Result<Vec<Traversability>, String> {
    const CODES: [Traversability; 5] = [
        Traversability::Unknown,
        Traversability::Free,
        Traversability::Traversable,
        Traversability::Blocked,
        Traversability::Uncertain,
    ];
    codes
        .iter()
        .enumerate()
        .map(|(k, c)| {
            usize::try_from(*c)
                .ok()
                .and_then(|c| CODES.get(c).copied())
                .ok_or_else(|| {
                    format!(
                        "decision code {c} at element {k}: expected 0 (unknown), 1 (free), 2 (traversable), \
                         3 (blocked) or 4 (uncertain)"
                    )
                })
        })
        .collect()
}

impl ForeignMap {
    /// Checks the arrays against each other: every array `rows * cols` long, a resolution above zero, a finite
    /// origin, no more than [`MAX_FOREIGN_CELLS`] cells, no negative variance or occupancy outside `[0, 1]`.
    /// `source` names where the arrays came from in the error, and `layer_files` the files of the elevation,
    /// variance and occupancy layers where they came from files of their own.
    ///
    /// # Errors
    /// [`EvalError::Input`] naming `source` (or the layer's file) and what is wrong.
    pub fn check(&self, source: &std::path::Path, layer_files: [Option<&std::path::Path>; 3]) -> Result<()> {
        let fail = |message: String| EvalError::Input {
            path: source.to_path_buf(),
            message,
        };
        let n = (self.rows as u64).saturating_mul(self.cols as u64);
        if n == 0 || n > MAX_FOREIGN_CELLS {
            return Err(fail(format!(
                "a {} x {} grid, expected 1 to {MAX_FOREIGN_CELLS} cells",
                self.rows, self.cols
            )));
        }
        if !(self.resolution_m.is_finite() && self.resolution_m > 0.0) {
            return Err(fail(format!(
                "resolution {} m, expected a cell size above 0",
                self.resolution_m
            )));
        }
        if !self.origin_xy_m.iter().all(|v| v.is_finite()) {
            return Err(fail(format!(
                "origin {:?}, expected finite metres",
                self.origin_xy_m
            )));
        }
        let len = |name: &str, got: usize| {
            (got as u64 == n).then_some(()).ok_or_else(|| {
                fail(format!(
                    "the {name} hold {got} cells, the decisions' grid {} x {} = {n}",
                    self.rows, self.cols
                ))
            })
        };
        len("decisions", self.decisions.len())?;
        for ((name, layer, valid), file) in [
            (
                "elevations",
                &self.elevation_m,
                (-MAX_ABS_ELEVATION_M, MAX_ABS_ELEVATION_M),
            ),
            ("variances", &self.variance_m2, (0.0, f64::INFINITY)),
            ("occupancy probabilities", &self.occupancy, (0.0, 1.0)),
        ]
        .into_iter()
        .zip(layer_files)
        {
            let Some(v) = layer else { continue };
            let fail = |message: String| EvalError::Input {
                path: file.unwrap_or(source).to_path_buf(),
                message,
            };
            len(name, v.len())?;
            if let Some((k, x)) = v
                .iter()
                .enumerate()
                .find(|(_, x)| !(x.is_nan() || (x.is_finite() && (valid.0..=valid.1).contains(*x))))
            {
                // Huge values in scientific notation, not three hundred digits.
                let x = if x.abs() < 1e15 {
                    format!("{x}")
                } else {
                    format!("{x:e}")
                };
                return Err(fail(format!(
                    "{name}: {x} at row {}, column {}, expected a finite value in [{}, {}] or NaN for none",
                    k / self.cols,
                    k % self.cols,
                    valid.0,
                    valid.1
                )));
            }
        }
        Ok(())
    }
}

impl Estimate {
    /// The testbed's own map over the truth's region: its decisions for the truth's robot under `rule`, its
    /// elevation, variance and occupancy layers, and its bookkeeping.
    ///
    /// # Errors
    /// Rasters too large for the map's memory limit.
    pub fn of_map(map: &Map, truth: &TruthRaster, rule: TraversabilityRule) -> Result<Self> {
        let region = *truth.window.region();
        let layer = |kind: LayerKind| -> Result<Vec<f32>> { Ok(map.layer(kind, region)?.values) };
        // The occupancy is NaN exactly where no ray reached the cell.
        let occupancy = layer(LayerKind::OccupancyProbability)?;
        let (decisions, doubts) = map.traversability_and_doubt_layers(region, &truth.profile, rule)?;
        let decisions = decisions.values;
        // Only the contact rule leaves cells undecided for a reason; the others' doubts are all `None`.
        let says_why = matches!(rule, TraversabilityRule::Contact { .. });
        let doubts = doubts
            .values
            .into_iter()
            .zip(&decisions)
            .map(|(doubt, d)| {
                doubt.filter(|_| says_why && matches!(d, Traversability::Uncertain | Traversability::Unknown))
            })
            .collect();
        Ok(Self {
            window: truth.window,
            decisions,
            doubts,
            observed: occupancy.iter().map(|o| !o.is_nan()).collect(),
            elevation_m: layer(LayerKind::ElevationM)?,
            variance_m2: layer(LayerKind::VarianceM2)?,
            occupancy,
            totals: MapTotals {
                map_bytes: map.memory_bytes(),
                num_scans: map.num_scans(),
                num_rays: map.totals().num_rays,
            },
        })
    }

    /// `foreign`, resampled onto the truth's grid by the rule of this module's documentation.
    ///
    /// # Errors
    /// A truth whose resolution is not a valid cell size.
    pub fn resample(foreign: &ForeignMap, truth: &TruthRaster) -> Result<Self> {
        let (geometry, region) = (truth.window.geometry(), *truth.window.region());
        let n = truth.cells.len();
        let mut acc = vec![Sources::default(); n];
        let (ox, oy, res) = (
            foreign.origin_xy_m[0],
            foreign.origin_xy_m[1],
            foreign.resolution_m,
        );
        // 1. Every user cell into the truth cell that holds its centre.
        for r in 0..foreign.rows {
            let y = oy + (r as f64 + 0.5) * res;
            for c in 0..foreign.cols {
                let x = ox + (c as f64 + 0.5) * res;
                let Some(k) = geometry.cell_of(x, y).and_then(|cell| region.offset(cell)) else {
                    continue;
                };
                acc[k].add(foreign, r * foreign.cols + c);
            }
        }
        // 2. A truth cell that holds no user cell's centre takes the user cell under its own centre.
        for (k, cell) in region.cells().enumerate() {
            if acc[k].count > 0 {
                continue;
            }
            let (x, y) = geometry.cell_center(cell);
            let (c, r) = (((x - ox) / res).floor(), ((y - oy) / res).floor());
            if c >= 0.0 && r >= 0.0 && (c as usize) < foreign.cols && (r as usize) < foreign.rows {
                acc[k].add(foreign, r as usize * foreign.cols + c as usize);
            }
        }
        let mut e = Self {
            window: truth.window,
            decisions: Vec::with_capacity(n),
            doubts: Vec::new(),
            observed: Vec::with_capacity(n),
            elevation_m: Vec::with_capacity(n),
            variance_m2: Vec::with_capacity(n),
            occupancy: Vec::with_capacity(n),
            totals: MapTotals::default(),
        };
        for s in &acc {
            let decision = s.decision.unwrap_or(Traversability::Unknown);
            let (elevation, variance) = s.elevation();
            let occupancy = mean(s.occupancy_sum, s.num_occupancy);
            e.decisions.push(decision);
            e.observed
                .push(decision != Traversability::Unknown || !elevation.is_nan() || !occupancy.is_nan());
            e.elevation_m.push(elevation as f32);
            e.variance_m2.push(variance as f32);
            e.occupancy.push(occupancy as f32);
        }
        Ok(e)
    }

    /// The elevation and its variance at raster offset `k`, when the map has one.
    pub fn elevation(&self, k: usize) -> Option<(f64, f64)> {
        let e = self.elevation_m[k];
        (!e.is_nan()).then(|| (f64::from(e), f64::from(self.variance_m2[k])))
    }

    /// The occupancy probability at raster offset `k` (NaN where there is none).
    pub fn occupancy(&self, k: usize) -> f64 {
        f64::from(self.occupancy[k])
    }
}

/// What a truth cell's sources add up to.
#[derive(Debug, Clone, Copy, Default)]
struct Sources {
    count: u32,
    decision: Option<Traversability>,
    elevation_sum: f64,
    elevation_sq_sum: f64,
    num_elevation: u32,
    variance_sum: f64,
    num_variance: u32,
    occupancy_sum: f64,
    num_occupancy: u32,
}

impl Sources {
    fn add(&mut self, f: &ForeignMap, k: usize) {
        self.count += 1;
        let d = f.decisions[k];
        if d != Traversability::Unknown {
            self.decision = Some(match self.decision {
                None => d,
                Some(a) => oeg::more_restrictive(a, Some(d)),
            });
        }
        let value = |layer: &Option<Vec<f64>>| layer.as_ref().map_or(f64::NAN, |v| v[k]);
        let e = value(&f.elevation_m);
        if !e.is_nan() {
            self.elevation_sum += e;
            self.elevation_sq_sum += e * e;
            self.num_elevation += 1;
            let v = value(&f.variance_m2);
            if !v.is_nan() {
                self.variance_sum += v;
                self.num_variance += 1;
            }
        }
        let o = value(&f.occupancy);
        if !o.is_nan() {
            self.occupancy_sum += o;
            self.num_occupancy += 1;
        }
    }

    /// The mean elevation and the mixture's variance (NaN when no source has a variance).
    fn elevation(&self) -> (f64, f64) {
        let mean_e = mean(self.elevation_sum, self.num_elevation);
        if self.num_elevation <= 1 {
            return (mean_e, mean(self.variance_sum, self.num_variance));
        }
        let spread = (mean(self.elevation_sq_sum, self.num_elevation) - mean_e * mean_e).max(0.0);
        (mean_e, mean(self.variance_sum, self.num_variance) + spread)
    }
}

fn mean(sum: f64, n: u32) -> f64 {
    if n == 0 { f64::NAN } else { sum / f64::from(n) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{truth_cell, truth_raster};
    use oeg::{CellIndex, CellRegion, GridGeometry};

    /// A truth of 2 x 2 cells of 0.5 m from (0, 0).
    fn truth() -> TruthRaster {
        let region = CellRegion::from_corners(CellIndex::new(0, 0), CellIndex::new(1, 1)).expect("region");
        let mut t = truth_raster(region, vec![truth_cell(0.0, false, f32::NAN); 4]);
        t.window = GridWindow::new(GridGeometry::new(0.5).expect("resolution"), region);
        t
    }

    fn foreign(res: f64, rows: usize, cols: usize, decisions: Vec<Traversability>) -> ForeignMap {
        ForeignMap {
            origin_xy_m: [0.0, 0.0],
            resolution_m: res,
            rows,
            cols,
            elevation_m: Some((0..rows * cols).map(|k| k as f64).collect()),
            variance_m2: Some(vec![0.01; rows * cols]),
            occupancy: None,
            decisions,
        }
    }

    #[test]
    fn the_same_grid_is_taken_as_it_is() {
        use Traversability::*;
        let f = foreign(0.5, 2, 2, vec![Free, Blocked, Unknown, Uncertain]);
        let e = Estimate::resample(&f, &truth()).expect("resampled");
        assert_eq!(e.decisions, f.decisions);
        assert_eq!(e.elevation_m, vec![0.0, 1.0, 2.0, 3.0]);
        assert_eq!(e.variance_m2, vec![0.01; 4]);
        assert!(e.occupancy.iter().all(|o| o.is_nan()));
    }

    #[test]
    fn a_finer_grid_keeps_the_most_restrictive_decision_and_the_mixture() {
        use Traversability::*;
        // 4 x 4 cells of 0.25 m: each truth cell holds 4 user cells' centres.
        let mut d = vec![Free; 16];
        d[0] = Blocked; // truth cell (0, 0)
        d[2] = Uncertain; // truth cell (1, 0)
        d[3] = Unknown;
        for k in [8, 9, 12, 13] {
            d[k] = Unknown; // truth cell (0, 1): all unknown
        }
        let f = foreign(0.25, 4, 4, d);
        let e = Estimate::resample(&f, &truth()).expect("resampled");
        assert_eq!(e.decisions, vec![Blocked, Uncertain, Unknown, Free]);
        // Truth cell (0, 0) holds user cells 0, 1, 4, 5: elevations 0, 1, 4, 5.
        assert!((e.elevation_m[0] - 2.5).abs() < 1e-12);
        // Mixture: mean variance 0.01 plus the elevations' variance 4.25.
        assert!((e.variance_m2[0] - 4.26).abs() < 1e-9, "{}", e.variance_m2[0]);
    }

    #[test]
    fn a_coarser_or_shifted_grid_is_sampled_under_each_cell_centre() {
        use Traversability::*;
        // One 2 m cell from (-0.5, -0.5) covers the whole truth.
        let mut f = foreign(2.0, 1, 1, vec![Blocked]);
        f.origin_xy_m = [-0.5, -0.5];
        let e = Estimate::resample(&f, &truth()).expect("resampled");
        assert_eq!(e.decisions, vec![Blocked; 4]);
        assert_eq!(e.variance_m2, vec![0.01; 4]);
        // Off the truth: nothing is known.
        f.origin_xy_m = [10.0, 10.0];
        let e = Estimate::resample(&f, &truth()).expect("resampled");
        assert_eq!(e.decisions, vec![Unknown; 4]);
        assert!(e.elevation_m.iter().all(|x| x.is_nan()));
    }

    #[test]
    fn bad_arrays_are_refused_with_what_is_wrong() {
        use Traversability::*;
        let p = std::path::Path::new("mine.npy");
        let mut f = foreign(0.5, 2, 2, vec![Free; 3]);
        assert!(
            f.check(p, [None; 3])
                .expect_err("short")
                .to_string()
                .contains("3 cells")
        );
        f.decisions.push(Free);
        f.check(p, [None; 3]).expect("good");
        f.variance_m2 = Some(vec![0.01, -1.0, 0.01, 0.01]);
        let e = f.check(p, [None; 3]).expect_err("negative").to_string();
        assert!(e.contains("mine.npy") && e.contains("row 0, column 1"), "{e}");
        f.variance_m2 = None;
        f.resolution_m = 0.0;
        assert!(f.check(p, [None; 3]).is_err());
        assert_eq!(
            decisions_from_codes(&[0, 3, 4]),
            Ok(vec![Unknown, Blocked, Uncertain])
        );
        let e = decisions_from_codes(&[1, 7]).expect_err("code 7");
        assert!(e.contains("code 7 at element 1"), "{e}");
    }
}
