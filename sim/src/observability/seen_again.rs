//! Ghosts the sensors could have cleared. Over each cell an actor (a person) covers: the heights at which rays
//! met it there, and those the sensors observed again after the last actor left (a ray crossed that height
//! over the cell, or ended there on what stands). A map of these readings can clear what a person left in it
//! only at the heights the sensors observed again: a lidar ring that met a person at 0.41 m leaves a ghost that
//! only a later ray at about 0.41 m over the same cell can clear, and rings passing at 0.43 m and higher say
//! nothing of it. DA (`oeg_eval::judge::ghosts`) counts only the cells whose every such height was observed
//! again.

use oeg::GridWindow;

/// Height slices over a cell's ground, from the ground to the robot's height: 1.4 cm each for the Pioneer's
/// 0.46 m.
const SLICES: u32 = 32;

/// Per cell: the last time an actor covered it, and two masks of 32 height slices over its ground
/// (16 bytes a cell, and a bit).
#[derive(Debug, Clone, PartialEq)]
pub struct SeenAgain {
    /// The last time an actor covered the cell, seconds; -inf: never (the cell is not tracked).
    covered_until_s: Vec<f64>,
    /// A bit per cell: tracked. Every ray's walk asks it of every cell it crosses, and the bits of a large
    /// region stay in a core's cache where the times do not.
    tracked: Vec<u64>,
    /// The slices where a ray ended over the cell while an actor could be there (above the lowest slice: the
    /// actor, not the ground under it).
    met: Vec<u32>,
    /// The slices a ray crossed, or ended in, over the cell after the last actor left it.
    again: Vec<u32>,
    slice_m: f64,
    height_m: f64,
    /// The earliest of the tracked cells' times: no scan before it observes one again.
    first_left_s: f64,
    /// [`SeenAgain::rect_m`].
    rect_m: Option<((f64, f64), (f64, f64))>,
}

/// What one ray says of one tracked cell: its slices, and whether they observe the cell again (after the
/// actor left) or met the actor.
#[derive(Debug, Clone, Copy)]
pub(super) struct Sight {
    k: usize,
    slices: u32,
    again: bool,
}

impl SeenAgain {
    pub(super) fn new(covered_until_s: Vec<f64>, height_m: f32, window: &GridWindow) -> Self {
        let n = covered_until_s.len();
        let height_m = f64::from(height_m);
        let mut tracked = vec![0u64; n.div_ceil(64)];
        for (k, until) in covered_until_s.iter().enumerate() {
            if *until > f64::NEG_INFINITY {
                tracked[k / 64] |= 1 << (k % 64);
            }
        }
        let first_left_s = covered_until_s
            .iter()
            .copied()
            .filter(|t| *t > f64::NEG_INFINITY)
            .fold(f64::INFINITY, f64::min);
        Self {
            first_left_s,
            rect_m: Self::compute_rect_m(&tracked, window),
            covered_until_s,
            tracked,
            met: vec![0; n],
            again: vec![0; n],
            slice_m: height_m / f64::from(SLICES),
            height_m,
        }
    }

    /// A ray that ended `h_m` over the ground of cell `k` at time `t_s`.
    pub(super) fn ended(&self, k: usize, h_m: f64, t_s: f64, out: &mut Vec<Sight>) {
        let until = self.covered_until_s[k];
        if until == f64::NEG_INFINITY || !(0.0..=self.height_m).contains(&h_m) {
            return;
        }
        let slices = self.slices(h_m, h_m);
        if t_s > until {
            self.push_again(k, slices, out);
        } else if h_m >= self.slice_m {
            out.push(Sight {
                k,
                slices,
                again: false,
            });
        }
    }

    /// A ray that crossed cell `k` between `a_m` and `b_m` over its ground at time `t_s`.
    #[inline(always)]
    pub(super) fn crossed(&self, k: usize, (a_m, b_m): (f64, f64), t_s: f64, out: &mut Vec<Sight>) {
        if self.tracked[k / 64] & (1 << (k % 64)) == 0 {
            return;
        }
        let until = self.covered_until_s[k];
        let (lo, hi) = (a_m.min(b_m), a_m.max(b_m));
        if until == f64::NEG_INFINITY || t_s <= until || hi < 0.0 || lo > self.height_m {
            return;
        }
        self.push_again(k, self.slices(lo, hi), out);
    }

    /// Slices observed again over cell `k`, kept only where they observe a height met on an actor that no ray
    /// observed again yet. After the last actor left a cell, no ray meets one there: what was met is final.
    fn push_again(&self, k: usize, slices: u32, out: &mut Vec<Sight>) {
        if self.met[k] & !self.again[k] & slices != 0 {
            out.push(Sight {
                k,
                slices,
                again: true,
            });
        }
    }

    /// The smallest rectangle of the window (min and max corners, metres) that holds every tracked cell, or
    /// `None` without one: rays elsewhere say nothing of them.
    pub(super) fn rect_m(&self) -> Option<((f64, f64), (f64, f64))> {
        self.rect_m
    }

    /// Whether a scan at `t_s` can observe a tracked cell again: no actor had left one before the first left.
    pub(super) fn may_see_again(&self, t_s: f64) -> bool {
        t_s > self.first_left_s
    }

    fn compute_rect_m(tracked: &[u64], window: &GridWindow) -> Option<((f64, f64), (f64, f64))> {
        let num_x = window.region().num_x as usize;
        let (mut lo, mut hi) = ((usize::MAX, usize::MAX), (0, 0));
        for (w, bits) in tracked.iter().enumerate() {
            let mut bits = *bits;
            while bits != 0 {
                let k = w * 64 + bits.trailing_zeros() as usize;
                bits &= bits - 1;
                let (i, j) = (k % num_x, k / num_x);
                lo = (lo.0.min(i), lo.1.min(j));
                hi = (hi.0.max(i), hi.1.max(j));
            }
        }
        if lo.0 == usize::MAX {
            return None;
        }
        let ((x0, y0), r) = (window.min_corner_m(), window.resolution_m());
        let corner = |i: usize, j: usize| (x0 + i as f64 * r, y0 + j as f64 * r);
        Some((corner(lo.0, lo.1), corner(hi.0 + 1, hi.1 + 1)))
    }

    /// Adds one scan's sights (merged by OR, so their order does not matter).
    pub(super) fn record(&mut self, sights: Vec<Sight>) {
        for s in sights {
            if s.again {
                self.again[s.k] |= s.slices;
            } else {
                self.met[s.k] |= s.slices;
            }
        }
    }

    /// Per cell: every slice where a ray met an actor was observed again (true where none met one).
    pub(super) fn cells(&self) -> Vec<bool> {
        self.met
            .iter()
            .zip(&self.again)
            .map(|(met, again)| met & !again == 0)
            .collect()
    }

    /// The slices from height `lo_m` to `hi_m` over the ground (`lo_m <= hi_m`), clamped to the band.
    fn slices(&self, lo_m: f64, hi_m: f64) -> u32 {
        let index = |h: f64| ((h.max(0.0) / self.slice_m) as u32).min(SLICES - 1);
        let (a, b) = (index(lo_m), index(hi_m));
        (u32::MAX >> (SLICES - 1 - b)) & (u32::MAX << a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One tracked cell (0), covered until 5 s, and one never covered (1); the band 0.32 m, slices of 1 cm.
    fn seen() -> SeenAgain {
        SeenAgain::new(vec![5.0, f64::NEG_INFINITY], 0.32, &window())
    }

    /// Two cells of 0.1 m along x from the origin.
    fn window() -> GridWindow {
        let g = oeg::GridGeometry::new(0.1).expect("grid");
        let region = oeg::CellRegion::from_corners(oeg::CellIndex::new(0, 0), oeg::CellIndex::new(1, 0))
            .expect("region");
        GridWindow::new(g, region)
    }

    #[test]
    fn the_rectangle_holds_the_tracked_cells_and_rays_before_the_first_leaving_say_nothing() {
        let s = seen();
        assert_eq!(s.rect_m(), Some(((0.0, 0.0), (0.1, 0.1))));
        assert!(!s.may_see_again(5.0) && s.may_see_again(5.1));
        let none = SeenAgain::new(vec![f64::NEG_INFINITY; 2], 0.32, &window());
        assert_eq!(none.rect_m(), None);
        assert!(!none.may_see_again(1e9));
    }

    #[test]
    fn a_height_met_on_the_actor_must_be_crossed_again_after_it_left() {
        let mut s = seen();
        let mut out = Vec::new();
        // A ring meets the person at 0.205 m at 2 s.
        s.ended(0, 0.205, 2.0, &mut out);
        // After the person left: rings pass over the cell at 0.25 to 0.26 m and under it at 0.10 to 0.12 m.
        s.crossed(0, (0.26, 0.25), 6.0, &mut out);
        s.crossed(0, (0.10, 0.12), 7.0, &mut out);
        // A ray crossing 0.20 to 0.21 m while the person still stood there says nothing of the ghost.
        s.crossed(0, (0.20, 0.21), 4.0, &mut out);
        s.record(out);
        assert_eq!(s.cells(), vec![false, true]);
        // A ray through 0.20 to 0.21 m after the person left observes it again.
        let mut out = Vec::new();
        s.crossed(0, (0.21, 0.20), 8.0, &mut out);
        s.record(out);
        assert_eq!(s.cells(), vec![true, true]);
    }

    #[test]
    fn the_ground_under_the_actor_and_heights_beyond_the_band_ask_for_nothing() {
        let mut s = seen();
        let mut out = Vec::new();
        // The ground under the person's feet (the lowest slice), and the person's head above the robot.
        s.ended(0, 0.004, 2.0, &mut out);
        s.ended(0, 1.5, 2.0, &mut out);
        // The untracked cell keeps nothing.
        s.ended(1, 0.2, 2.0, &mut out);
        assert!(out.is_empty());
        s.record(out);
        assert_eq!(s.cells(), vec![true, true]);
    }

    #[test]
    fn slices_cover_a_crossing_from_its_lowest_to_its_highest_height() {
        let s = seen();
        assert_eq!(s.slices(0.0, 0.0), 1);
        assert_eq!(s.slices(0.015, 0.035), 0b1110);
        assert_eq!(s.slices(-1.0, 9.0), u32::MAX);
        assert_eq!(s.slices(0.3199, 0.32), 1 << 31);
    }
}
