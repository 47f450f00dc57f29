//! A later run's hits, when a long scan's rays are gathered in runs in parallel (`map/runs.rs`) under every
//! rule's evidence: kept in their order and replayed into the merged evidence after the earlier runs'.

use super::rule_evidence::{HitLog, ScanEvidence};
use super::scratch::{HitLevels, HitSink, HitStore, SampledHit};
use crate::model::{ModelOptions, SeenFrom};
use crate::storage::{CapacityExceeded, TileGrid, TileIndex};

/// A later run's hits, when a scan's rays are gathered in runs in parallel: how a cell's hits combine
/// ([`crate::ScanHitElevation::HighestLevel`], the spread of the hits) depends on their order, so each is kept
/// here, in its order, and added to the merged evidence after the earlier runs'
/// ([`super::scratch::Evidence::replay`]). Only the probability, a maximum, is raised at once.
#[derive(Debug, Clone, Default)]
pub(crate) struct DeferredHits {
    hits: Vec<DeferredHit>,
}

#[derive(Debug, Clone, Copy)]
struct DeferredHit {
    tile: TileIndex,
    offset: u16,
    /// `Some` for a hit above the cell's surface band: the side its beam came from and its score.
    overhead: Option<(SeenFrom, f32)>,
    hit: SampledHit,
}

impl HitStore for DeferredHits {
    fn reserve(&mut self, entries: usize, limit_bytes: u64) -> Result<(), CapacityExceeded> {
        let (len, capacity) = (self.hits.len(), self.hits.capacity());
        let needed = len.saturating_add(entries);
        if needed <= capacity {
            return Ok(());
        }
        let bytes = |n: usize| (n as u64).saturating_mul(size_of::<DeferredHit>() as u64);
        let target = [needed.max(capacity.saturating_mul(2)), needed]
            .into_iter()
            .find(|n| bytes(*n) <= limit_bytes)
            .ok_or(CapacityExceeded {
                requested_bytes: bytes(needed),
            })?;
        self.hits.reserve_exact(target - len);
        Ok(())
    }

    fn clear(&mut self) {
        self.hits.clear();
    }

    fn memory_bytes(&self) -> u64 {
        (self.hits.capacity() * size_of::<DeferredHit>()) as u64
    }
}

impl HitSink<ScanEvidence> for DeferredHits {
    #[inline(always)]
    fn add_hit(
        &mut self,
        evidence: &mut ScanEvidence,
        (tile, offset): (TileIndex, usize),
        hit: SampledHit,
        _: HitLevels,
    ) {
        evidence.paper.raise_p(hit.p);
        self.hits.push(DeferredHit {
            tile,
            offset: offset as u16,
            overhead: None,
            hit,
        });
    }

    #[inline(always)]
    fn add_overhead(
        &mut self,
        _evidence: &mut ScanEvidence,
        (tile, offset): (TileIndex, usize),
        hit: SampledHit,
        side: SeenFrom,
        score: f32,
    ) {
        self.hits.push(DeferredHit {
            tile,
            offset: offset as u16,
            overhead: Some((side, score)),
            hit,
        });
    }
}

impl DeferredHits {
    /// Adds the hits, in their order, to `grid`'s evidence (the runs' grids merged into it, so every tile
    /// they were gathered in is there) and its `log`, within `limit_bytes`
    /// ([`super::scratch::Evidence::replay`]).
    pub(super) fn replay(
        &self,
        grid: &mut TileGrid<ScanEvidence>,
        log: &mut HitLog,
        opts: &ModelOptions,
        limit_bytes: u64,
    ) -> Result<(), CapacityExceeded> {
        // Each hit adds at most one entry.
        log.reserve(self.hits.len(), limit_bytes)?;
        let levels = HitLevels::of(opts);
        for d in &self.hits {
            // The tile is in the grid: the runs' tiles were placed in it by the merge.
            let slot = grid.slot_or_insert(d.tile, 0)?;
            let at = (d.tile, usize::from(d.offset));
            let evidence = &mut grid.slot_tile_mut(slot)[at.1];
            match d.overhead {
                None => log.add_hit(evidence, at, d.hit, levels),
                Some((side, score)) => log.add_overhead(evidence, at, d.hit, side, score),
            }
        }
        Ok(())
    }
}
