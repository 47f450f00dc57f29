//! Where the map's recent scans were taken from: how much a scan's measurements of a cell share their errors
//! with the estimate before it ([`ModelOptions::measurement_correlation`]).

use nalgebra::Point3;

use crate::model::ModelOptions;
use crate::sensor::RangeNoiseModel;

/// Scans remembered: a sensor's previous scan lies among them while fewer than this many scans of other
/// sensors come between two of its own (a 5 Hz camera beside two 75 Hz lasers needs 31).
pub(crate) const RECENT_VIEWS: usize = 256;

/// One scan's view: its sensor's origin and range error model.
#[derive(Debug, Clone, Copy)]
struct View {
    origin: Point3<f64>,
    noise: RangeNoiseModel,
}

/// The views of the map's last [`RECENT_VIEWS`] scans, kept only under a model whose measurements correlate
/// (none under the paper's, which holds nothing here).
#[derive(Debug, Clone, Default)]
pub(crate) struct RecentViews {
    /// A ring of at most [`RECENT_VIEWS`], allocated whole at the first view.
    views: Vec<View>,
    /// Where the next view goes once the ring is full.
    next: usize,
}

impl RecentViews {
    /// Bytes held: the ring, allocated whole once the first view is kept.
    pub(crate) fn memory_bytes(&self) -> u64 {
        (self.views.capacity() * size_of::<View>()) as u64
    }

    /// Bytes held once the next scan's view is kept under `opts`: what that scan's memory checks leave room
    /// for.
    pub(crate) fn memory_bytes_after_push(&self, opts: &ModelOptions) -> u64 {
        if opts.measurement_correlation > 0.0 {
            (RECENT_VIEWS * size_of::<View>()) as u64
        } else {
            self.memory_bytes()
        }
    }

    /// The correlation of a scan's measurements from `origin` by a sensor of range error model `noise` with
    /// the estimates before it, under `opts`: `rho exp(-d / resolution)`, with `rho` the option and `d` the
    /// distance to the nearest recent view by a sensor of the same model. Measured from the same place, a
    /// scan repeats the errors of the geometry it sees the cell with (which cells a beam's noisy end points
    /// land in, where it crosses the cell); a view a cell's width away sees the cell through other beams.
    /// 0 without such a view.
    pub(crate) fn correlation(
        &self,
        origin: &Point3<f64>,
        noise: &RangeNoiseModel,
        opts: &ModelOptions,
        resolution_m: f64,
    ) -> f32 {
        if opts.measurement_correlation <= 0.0 {
            return 0.0;
        }
        let nearest_m = self
            .views
            .iter()
            .filter(|v| v.noise == *noise)
            .map(|v| (v.origin - origin).norm())
            .reduce(f64::min);
        nearest_m.map_or(0.0, |d| {
            opts.measurement_correlation * (-d / resolution_m).exp() as f32
        })
    }

    /// Keeps a scan's view, under a model whose measurements correlate.
    pub(crate) fn push(&mut self, origin: Point3<f64>, noise: RangeNoiseModel, opts: &ModelOptions) {
        if opts.measurement_correlation <= 0.0 {
            return;
        }
        let view = View { origin, noise };
        if self.views.capacity() == 0 {
            self.views.reserve_exact(RECENT_VIEWS);
        }
        if self.views.len() < RECENT_VIEWS {
            self.views.push(view);
        } else {
            self.views[self.next] = view;
            self.next = (self.next + 1) % RECENT_VIEWS;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opts(rho: f32) -> ModelOptions {
        ModelOptions {
            measurement_correlation: rho,
            ..ModelOptions::default()
        }
    }

    #[test]
    fn a_view_from_the_same_place_correlates_fully_and_one_a_cell_away_by_a_factor_e() {
        let (laser, stereo) = (RangeNoiseModel::laser(), RangeNoiseModel::stereo());
        let mut views = RecentViews::default();
        let o = opts(1.0);
        assert_eq!(views.correlation(&Point3::origin(), &laser, &o, 0.05), 0.0);
        views.push(Point3::origin(), laser, &o);
        assert_eq!(views.correlation(&Point3::origin(), &laser, &o, 0.05), 1.0);
        let c = views.correlation(&Point3::new(0.05, 0.0, 0.0), &laser, &o, 0.05);
        assert!((c - (-1.0_f32).exp()).abs() < 1e-6, "{c}");
        // Another sensor's view says nothing of this one's errors.
        assert_eq!(views.correlation(&Point3::origin(), &stereo, &o, 0.05), 0.0);
        // The option scales it; 0 (the paper) keeps nothing.
        assert_eq!(
            views.correlation(&Point3::origin(), &laser, &opts(0.5), 0.05),
            0.5
        );
        let mut paper = RecentViews::default();
        paper.push(Point3::origin(), laser, &opts(0.0));
        assert_eq!(paper.memory_bytes(), 0);
    }

    #[test]
    fn the_ring_keeps_the_last_views_and_its_size() {
        let laser = RangeNoiseModel::laser();
        let (mut views, o) = (RecentViews::default(), opts(1.0));
        for k in 0..RECENT_VIEWS + 10 {
            views.push(Point3::new(k as f64, 0.0, 0.0), laser, &o);
        }
        let bytes = views.memory_bytes();
        assert_eq!(bytes, (RECENT_VIEWS * size_of::<View>()) as u64);
        assert_eq!(RecentViews::default().memory_bytes_after_push(&o), bytes);
        // The first ten were overwritten: the nearest view to the origin is now 10 m away.
        let c = views.correlation(&Point3::origin(), &laser, &o, 10.0);
        assert!((c - (-1.0_f32).exp()).abs() < 1e-6, "{c}");
        views.push(Point3::origin(), laser, &o);
        assert_eq!(views.memory_bytes(), bytes);
    }
}
