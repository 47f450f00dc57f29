//! The tiled storage's tests.

use super::*;

#[test]
fn a_tile_outside_the_grid_is_refused_not_a_panic() {
    let mut g = TileGrid::new(0u32);
    for tile in [
        TileIndex { ti: 1 << 25, tj: 0 },
        TileIndex { ti: 0, tj: i32::MIN },
    ] {
        assert!(!tile.is_representable());
        let boxed = Box::new([0u32; TILE_CELLS]);
        assert_eq!(
            g.insert_tile(tile, boxed, u64::MAX),
            Err(CapacityExceeded {
                requested_bytes: u64::MAX
            })
        );
        assert!(g.tile_or_insert(tile, u64::MAX).is_err());
    }
    assert_eq!(g.num_tiles(), 0);
}

#[test]
fn cells_read_back_and_unwritten_cells_are_absent() {
    let mut g = TileGrid::new(0u32);
    *g.get_or_insert(CellIndex::new(3, 4), u64::MAX).expect("room") = 7;
    *g.get_or_insert(CellIndex::new(-300, 900), u64::MAX)
        .expect("room") = 9;
    *g.get_or_insert(CellIndex::new(5000, -5000), u64::MAX)
        .expect("room") = 11;
    assert_eq!(g.get(CellIndex::new(3, 4)), Some(&7));
    assert_eq!(g.get(CellIndex::new(-300, 900)), Some(&9));
    assert_eq!(g.get(CellIndex::new(5000, -5000)), Some(&11));
    assert_eq!(g.get(CellIndex::new(4, 4)), Some(&0));
    assert_eq!(g.get(CellIndex::new(100_000, 4)), None);
    assert_eq!(g.num_tiles(), 3);
}

#[test]
fn memory_is_proportional_to_tiles_and_capped() {
    let mut g = TileGrid::new(0.0f32);
    let before = g.memory_bytes();
    *g.get_or_insert(CellIndex::new(0, 0), u64::MAX).expect("room") = 1.0;
    assert!(g.memory_bytes() >= before + TileGrid::<f32>::tile_bytes() as u64);
    let limit = g.memory_bytes() + 10;
    let err = g
        .get_or_insert(CellIndex::new(1000, 0), limit)
        .expect_err("over the limit");
    assert!(err.requested_bytes > limit);
    // A far-away cell would need a huge tile index: refused, not allocated.
    let err = g
        .get_or_insert(CellIndex::new(i32::MAX, i32::MIN), 1 << 30)
        .expect_err("index too large");
    assert!(err.requested_bytes > 1 << 30);
}

#[test]
fn recycled_tiles_read_as_new_and_keep_their_memory() {
    let mut g = TileGrid::new(0u16);
    let slot = g
        .slot_or_insert(TileIndex::of(CellIndex::new(1, 1)), u64::MAX)
        .expect("room");
    let (t, marks) = g.slot_tile_and_marks_mut(slot);
    t[offset_in_tile(CellIndex::new(1, 1))] = 5;
    marks.mark_if(offset_in_tile(CellIndex::new(1, 1)), true);
    let bytes = g.memory_bytes();
    g.recycle_marked();
    assert_eq!(g.num_tiles(), 0);
    assert_eq!(g.get(CellIndex::new(1, 1)), None);
    assert_eq!(g.memory_bytes(), bytes);
    // Reuse from the pool needs no room beyond what is held.
    assert_eq!(*g.get_or_insert(CellIndex::new(1, 1), bytes).expect("pooled"), 0);
}

#[test]
fn marked_cells_are_the_cells_recycled_and_survive_growth() {
    let mut g = TileGrid::new(0u8);
    let tile = TileIndex::of(CellIndex::new(3, 5));
    let at = offset_in_tile(CellIndex::new(3, 5));
    let slot = g.slot_or_insert(tile, u64::MAX).expect("room");
    let (t, marks) = g.slot_tile_and_marks_mut(slot);
    t[at] = 1;
    marks.mark_if(at, true);
    // A write that is not the cell's first is not marked again.
    marks.mark_if(at, false);
    let room = g.memory_bytes();
    // Growing the index far away moves the tile and its marks together.
    let far = g
        .slot_or_insert(TileIndex { ti: -40, tj: 30 }, u64::MAX)
        .expect("room");
    let (t, marks) = g.slot_tile_and_marks_mut(far);
    t[0] = 2;
    marks.mark_if(0, true);
    assert!(
        g.memory_bytes() >= room + (TILE_CELLS * size_of::<u16>()) as u64,
        "marks are counted"
    );
    let marked: Vec<_> = g.marked_tiles().map(|(t, _, m)| (t, visited(m))).collect();
    assert_eq!(
        marked,
        vec![(tile, vec![at]), (TileIndex { ti: -40, tj: 30 }, vec![0])]
    );
    g.recycle_marked();
    assert_eq!(g.marked_tiles().count(), 0);
    // The pooled tiles read as new.
    let slot = g.slot_or_insert(tile, u64::MAX).expect("pooled");
    assert_eq!(g.slot_tile_mut(slot)[offset_in_tile(CellIndex::new(3, 5))], 0);
    let other = g
        .slot_or_insert(TileIndex { ti: 9, tj: 9 }, u64::MAX)
        .expect("pooled");
    assert!(g.slot_tile_mut(other).iter().all(|&v| v == 0));
}

fn visited(marked: Marked<'_>) -> Vec<usize> {
    let mut cells = Vec::new();
    marked.for_each(|k| cells.push(k));
    cells
}

#[test]
fn marked_rows_and_cells_are_visited_once_and_recycled() {
    let mut g = TileGrid::new(0u8);
    let tile = TileIndex { ti: 0, tj: 0 };
    let slot = g.slot_or_insert(tile, u64::MAX).expect("room");
    let (t, marks) = g.slot_tile_and_marks_mut(slot);
    // A cell in row 1 (also marked as a row below) and one in row 3.
    for k in [TILE_SIZE + 5, 3 * TILE_SIZE + 2] {
        t[k] = 1;
        marks.mark_if(k, true);
    }
    g.slot_tile_mut(slot)[TILE_SIZE + 9] = 2;
    g.mark_rows(slot, 1 << 1);
    let (_, _, marked) = g.marked_tiles().next().expect("marked");
    assert_eq!(marked.num_cells(), TILE_SIZE + 2);
    let cells = visited(marked);
    let expected: Vec<usize> = (TILE_SIZE..2 * TILE_SIZE).chain([3 * TILE_SIZE + 2]).collect();
    assert_eq!(
        cells, expected,
        "the row's cells, then the marked cell outside it"
    );
    g.recycle_marked();
    let slot = g.slot_or_insert(tile, u64::MAX).expect("pooled");
    assert!(g.slot_tile_mut(slot).iter().all(|&v| v == 0));
}

#[test]
fn evidence_reset_where_it_is_read_leaves_the_grid_as_recycling_does() {
    let mut g = TileGrid::new(0u8);
    let tiles = [TileIndex { ti: 0, tj: 0 }, TileIndex { ti: 2, tj: -1 }];
    for (n, tile) in tiles.into_iter().enumerate() {
        let slot = g.slot_or_insert(tile, u64::MAX).expect("room");
        let (t, marks) = g.slot_tile_and_marks_mut(slot);
        t[7 + n] = 3;
        marks.mark_if(7 + n, true);
        g.slot_tile_mut(slot)[5 * TILE_SIZE + 1] = 4;
        g.mark_rows(slot, 1 << 5);
    }
    // Read and reset on the caller's side, in the order of the grid's tiles, then taken back.
    let fill = g.fill();
    let mut seen = Vec::new();
    for (tile, t, marked) in g.marked_tiles_mut() {
        let mut values = Vec::new();
        marked.for_each(|k| values.push(t[k]));
        seen.push((tile, values.iter().map(|&v| u32::from(v)).sum::<u32>()));
        marked.reset(t, fill);
    }
    assert_eq!(
        seen,
        vec![(tiles[1], 7), (tiles[0], 7)],
        "row by row over the tile index"
    );
    g.release_reset();
    assert_eq!(g.num_tiles(), 0);
    assert_eq!(g.marked_tiles().count(), 0);
    assert_eq!(g.num_pooled(), 2);
    for tile in tiles {
        let slot = g.slot_or_insert(tile, u64::MAX).expect("pooled");
        assert!(
            g.slot_tile_mut(slot).iter().all(|&v| v == 0),
            "a pooled tile reads as new"
        );
    }
}

#[test]
fn growing_a_marking_grid_s_index_counts_its_marks_and_the_old_index_held_meanwhile() {
    let mut g = TileGrid::new(0u8);
    let slot = g
        .slot_or_insert(TileIndex { ti: 0, tj: 0 }, u64::MAX)
        .expect("room");
    g.mark_rows(slot, 1);
    // The index is 9 x 9 tiles; a tile 1,000 tiles away grows it to 1,009 x 9 (with 4 tiles of slack). Each
    // slot holds a tile pointer and a row mask (8 + 8 bytes), and the old 81 slots are held while the new ones
    // are filled: one 4 KiB tile plus (9,081 + 81) x 16 bytes.
    let far = TileIndex { ti: 1000, tj: 0 };
    let needed = 4096 + (1009 * 9 + 81) * 16;
    assert_eq!(
        g.slot_or_insert(far, needed - 1),
        Err(CapacityExceeded {
            requested_bytes: needed
        })
    );
    assert!(g.slot_or_insert(far, u64::MAX).is_ok());
    assert!(
        g.memory_bytes() >= 2 * 4096 + 1009 * 9 * 16,
        "the grown index is counted"
    );
}

#[test]
fn rows_are_listed_in_order() {
    let mut seen = Vec::new();
    for_each_row((1 << 63) | (1 << 7) | 1, |r| seen.push(r));
    assert_eq!(seen, vec![0, 7, 63]);
}

#[test]
fn tiles_asked_for_in_order_are_lent_together_and_others_left_out() {
    let mut g = TileGrid::new(0u8);
    let at = |ti, tj| TileIndex { ti, tj };
    for t in [at(0, 0), at(3, 0), at(1, 2), at(-2, 5)] {
        g.tile_or_insert(t, u64::MAX).expect("room")[0] = 1;
    }
    let asked = [at(3, 0), at(2, 1), at(1, 2), at(0, 0), at(-2, 5), at(99, 99)];
    // (0, 0) comes after (1, 2) in the grid's order: out of order, so left out, as are the unallocated.
    let lent = g.tiles_mut_in_order(asked);
    let got: Vec<TileIndex> = lent.iter().map(|(t, _)| *t).collect();
    assert_eq!(got, vec![at(3, 0), at(1, 2), at(-2, 5)]);
    for (_, t) in lent {
        t[1] = 7;
    }
    assert_eq!(g.get(CellIndex::new(3 * 64 + 1, 0)), Some(&7));
    assert_eq!(g.get(CellIndex::new(1, 0)), Some(&0));
}

#[test]
fn tiles_iterate_in_a_fixed_order() {
    let mut g = TileGrid::new(0u8);
    for c in [
        CellIndex::new(200, 0),
        CellIndex::new(0, 0),
        CellIndex::new(0, 200),
    ] {
        *g.get_or_insert(c, u64::MAX).expect("room") = 1;
    }
    let order: Vec<_> = g.tiles().map(|(t, _)| (t.tj, t.ti)).collect();
    let mut sorted = order.clone();
    sorted.sort();
    assert_eq!(order, sorted);
    let region = g.tile_region().expect("tiles");
    assert_eq!(region.min, CellIndex::new(0, 0));
    assert_eq!(region.max(), CellIndex::new(255, 255));
}

#[test]
fn offsets_inside_a_tile_are_row_major() {
    assert_eq!(offset_in_tile(CellIndex::new(0, 0)), 0);
    assert_eq!(offset_in_tile(CellIndex::new(1, 0)), 1);
    assert_eq!(offset_in_tile(CellIndex::new(0, 1)), TILE_SIZE);
    assert_eq!(offset_in_tile(CellIndex::new(-1, -1)), TILE_CELLS - 1);
}
