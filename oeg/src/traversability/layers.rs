//! The map's decisions over a region: the layers of classes and doubts, and the counts of each class.

use serde::{Deserialize, Serialize};

use super::rules::{Doubt, RobotProfile, Traversability, TraversabilityRule};
use crate::error::Result;
use crate::geometry::CellRegion;
use crate::map::{Map, Raster};

impl Map {
    /// A dense raster of [`Map::traversability`] over `region`.
    ///
    /// # Errors
    /// [`crate::Error::MemoryLimit`] if the raster would exceed the map's memory limit.
    pub fn traversability_layer(
        &self,
        region: CellRegion,
        profile: &RobotProfile,
        rule: TraversabilityRule,
    ) -> Result<Raster<Traversability>> {
        let n = self.check_raster_size(&region, 1)?;
        let mut values = Vec::with_capacity(n);
        values.extend(region.cells().map(|c| self.traversability(c, profile, rule)));
        Ok(Raster {
            window: crate::GridWindow::new(*self.geometry(), region),
            values,
        })
    }

    /// [`Map::traversability_layer`] and, from the same decision of each cell, why it is undecided
    /// ([`Map::doubt`]): one pass where asking [`Map::doubt`] of each undecided cell after the layer would
    /// decide it twice.
    ///
    /// # Errors
    /// [`crate::Error::MemoryLimit`] if the two rasters would take the map past its memory limit.
    pub fn traversability_and_doubt_layers(
        &self,
        region: CellRegion,
        profile: &RobotProfile,
        rule: TraversabilityRule,
    ) -> Result<(Raster<Traversability>, Raster<Option<Doubt>>)> {
        let n = self.check_raster_size(&region, 1 + size_of::<Option<Doubt>>() as u64)?;
        let (mut classes, mut doubts) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for cell in region.cells() {
            let d = self.decision(cell, profile, rule);
            classes.push(d.class);
            doubts.push(d.doubt);
        }
        let window = crate::GridWindow::new(*self.geometry(), region);
        Ok((
            Raster {
                window,
                values: classes,
            },
            Raster {
                window,
                values: doubts,
            },
        ))
    }

    /// Counts of each traversability class over the observed cells.
    pub fn traversability_counts(
        &self,
        profile: &RobotProfile,
        rule: TraversabilityRule,
    ) -> TraversabilityCounts {
        let mut counts = TraversabilityCounts::default();
        for (c, _) in self.observed_cells() {
            match self.traversability(c, profile, rule) {
                Traversability::Unknown => {}
                Traversability::Free => counts.num_free += 1,
                Traversability::Traversable => counts.num_traversable += 1,
                Traversability::Blocked => counts.num_blocked += 1,
                Traversability::Uncertain => counts.num_uncertain += 1,
            }
        }
        counts
    }
}

/// Number of observed cells in each traversability class.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct TraversabilityCounts {
    /// Observed, not occupied.
    pub num_free: u64,
    /// Occupied, low enough.
    pub num_traversable: u64,
    /// Occupied, too high.
    pub num_blocked: u64,
    /// Occupied, too close to a threshold to tell.
    pub num_uncertain: u64,
}

impl TraversabilityCounts {
    /// Occupied cells: traversable, blocked and uncertain.
    pub fn num_occupied(&self) -> u64 {
        self.num_traversable + self.num_blocked + self.num_uncertain
    }
}
