//! The walk against a supersampled oracle and against the textbook walk.

use std::collections::BTreeSet;

use proptest::prelude::*;

use super::*;

fn cells(g: &GridGeometry, o: (f64, f64), p: (f64, f64)) -> Vec<CellCrossing> {
    let d = (p.0 - o.0, p.1 - o.1);
    GroundTraversal::new(g, o, d, 0.0, 1.0).expect("finite").collect()
}

/// Every cell that a dense set of samples along the segment falls into.
fn supersampled_oracle(g: &GridGeometry, o: (f64, f64), p: (f64, f64)) -> BTreeSet<CellIndex> {
    let n = 20_000;
    (0..=n)
        .filter_map(|k| {
            let t = f64::from(k) / f64::from(n);
            g.cell_of(o.0 + (p.0 - o.0) * t, o.1 + (p.1 - o.1) * t)
        })
        .collect()
}

#[test]
fn a_single_cell_ray_visits_its_cell() {
    let g = GridGeometry::new(1.0).expect("valid");
    let v = cells(&g, (0.2, 0.3), (0.7, 0.9));
    assert_eq!(v.len(), 1);
    assert_eq!(v[0].cell, CellIndex::new(0, 0));
    assert_eq!((v[0].l_enter, v[0].l_exit), (0.0, 1.0));
}

#[test]
fn a_vertical_ray_visits_one_cell() {
    let g = GridGeometry::new(0.1).expect("valid");
    let v: Vec<_> = GroundTraversal::new(&g, (0.05, 0.05), (0.0, 0.0), 0.0, 3.0)
        .expect("finite")
        .collect();
    assert_eq!(v.len(), 1);
    assert_eq!(v[0].l_exit, 3.0);
}

#[test]
fn an_axis_aligned_ray_includes_the_end_cell_and_its_intervals_tile_the_ray() {
    let g = GridGeometry::new(0.5).expect("valid");
    let v = cells(&g, (0.25, 0.25), (2.25, 0.25));
    let got: Vec<_> = v.iter().map(|c| c.cell.i).collect();
    assert_eq!(got, vec![0, 1, 2, 3, 4]);
    assert!(v.iter().all(|c| c.cell.j == 0));
    // Intervals are contiguous and cover [0, 1].
    assert_eq!(v[0].l_enter, 0.0);
    assert_eq!(v.last().map(|c| c.l_exit), Some(1.0));
    for w in v.windows(2) {
        assert_eq!(w[0].l_exit, w[1].l_enter);
    }
    assert!((v[1].l_enter - 0.125).abs() < 1e-12);
}

#[test]
fn a_ray_through_a_corner_stays_four_connected() {
    let g = GridGeometry::new(1.0).expect("valid");
    let v = cells(&g, (0.5, 0.5), (2.5, 2.5));
    assert_eq!(v.len(), 5);
    for w in v.windows(2) {
        let (a, b) = (w[0].cell, w[1].cell);
        assert_eq!((a.i - b.i).abs() + (a.j - b.j).abs(), 1);
    }
}

#[test]
fn negative_directions_and_negative_cells_work() {
    let g = GridGeometry::new(0.1).expect("valid");
    let v = cells(&g, (0.05, 0.05), (-0.25, -0.05));
    assert_eq!(v.first().map(|c| c.cell), Some(CellIndex::new(0, 0)));
    assert_eq!(v.last().map(|c| c.cell), Some(CellIndex::new(-3, -1)));
}

#[test]
fn non_finite_rays_are_refused() {
    let g = GridGeometry::new(0.1).expect("valid");
    assert!(GroundTraversal::new(&g, (0.0, 0.0), (f64::NAN, 0.0), 0.0, 1.0).is_none());
    assert!(GroundTraversal::new(&g, (0.0, 0.0), (1e12, 0.0), 0.0, 1.0).is_none());
    assert!(GroundTraversal::new(&g, (0.0, 0.0), (1.0, 0.0), 1.0, 0.0).is_none());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// The traversal is a 4-connected run from the start cell to the end cell that holds every cell a dense
    /// sampling of the segment touches, and only a few more (corner cells).
    #[test]
    fn traversal_matches_a_supersampled_oracle(
        ox in -5.0f64..5.0, oy in -5.0f64..5.0, px in -5.0f64..5.0, py in -5.0f64..5.0,
        r in prop::sample::select(vec![0.05, 0.1, 0.2, 0.37]),
    ) {
        let g = GridGeometry::new(r).expect("valid");
        let v = cells(&g, (ox, oy), (px, py));
        let visited: Vec<CellIndex> = v.iter().map(|c| c.cell).collect();
        prop_assert_eq!(visited.first().copied(), g.cell_of(ox, oy));
        prop_assert_eq!(visited.last().copied(), g.cell_of(px, py));
        for w in visited.windows(2) {
            prop_assert_eq!((w[0].i - w[1].i).abs() + (w[0].j - w[1].j).abs(), 1, "not 4-connected: {:?}", w);
        }
        let set: BTreeSet<CellIndex> = visited.iter().copied().collect();
        prop_assert_eq!(set.len(), visited.len(), "a cell was visited twice");
        let oracle = supersampled_oracle(&g, (ox, oy), (px, py));
        for c in &oracle {
            prop_assert!(set.contains(c), "missed cell {:?}", c);
        }
        // A 4-connected walk needs exactly |di| + |dj| + 1 cells; the oracle is 8-connected and may skip
        // the corner cells a 4-connected walk must add, one per diagonal step.
        prop_assert!(visited.len() <= 2 * oracle.len());
        for w in v.windows(2) {
            prop_assert!(w[0].l_exit == w[1].l_enter && w[0].l_enter <= w[0].l_exit);
        }
    }

    /// The walk's crossings are bit for bit those of the textbook walk ([`reference_walk`]), and walking
    /// tile by tile ([`GroundTraversal::walk_tile`]) gives the same crossings as the iterator, each with its
    /// cell's offset, and stops exactly where the walk enters another tile.
    #[test]
    fn the_tile_walk_and_the_iterator_are_the_textbook_walk(
        ox in -20.0f64..20.0, oy in -20.0f64..20.0,
        dx in -1.0f64..1.0, dy in -1.0f64..1.0, dz in -1.0f64..1.0,
        l_start in 0.0f64..5.0, length in 0.0f64..40.0,
        axis in prop::sample::select(vec![None, Some(0), Some(1)]),
        r in prop::sample::select(vec![0.05, 0.1, 0.2, 0.37]),
    ) {
        // Some rays along an axis, where one step is never taken.
        let (dx, dy) = match axis {
            Some(0) => (dx, 0.0),
            Some(_) => (0.0, dy),
            None => (dx, dy),
        };
        let norm = (dx * dx + dy * dy + dz * dz).sqrt().max(1e-9);
        let (dx, dy) = (dx / norm, dy / norm);
        let g = GridGeometry::new(r).expect("valid");
        let l_end = l_start + length;
        let walk = GroundTraversal::new(&g, (ox, oy), (dx, dy), l_start, l_end).expect("finite");
        let expected = reference_walk(&g, (ox, oy), (dx, dy), l_start, l_end);
        let by_iterator: Vec<CellCrossing> = walk.clone().collect();
        prop_assert_eq!(&by_iterator, &expected);
        let mut tiled = walk;
        let mut by_tile = Vec::new();
        while let Some(tile) = tiled.tile() {
            let before = by_tile.len();
            tiled.walk_tile(|offset, crossing| {
                assert_eq!(offset, offset_in_tile(crossing.cell));
                assert_eq!(TileIndex::of(crossing.cell), tile);
                by_tile.push(*crossing);
            });
            prop_assert!(by_tile.len() > before, "a call walked no cell");
            if let Some(next) = tiled.tile() {
                prop_assert_ne!(next, tile);
            }
        }
        prop_assert_eq!(&by_tile, &expected);
    }
}

/// The Amanatides-Woo walk as first written here: each crossing's exit clamped to its entry, and an axis
/// that has reached the end cell's index held by a test of the cell.
fn reference_walk(
    g: &GridGeometry,
    (ox, oy): (f64, f64),
    (dx, dy): (f64, f64),
    l_start: f64,
    l_end: f64,
) -> Vec<CellCrossing> {
    let start = g.cell_of(ox + dx * l_start, oy + dy * l_start).expect("finite");
    let end = g.cell_of(ox + dx * l_end, oy + dy * l_end).expect("finite");
    let r = g.resolution_m();
    let axis = |index: i32, end_index: i32, o: f64, d: f64| -> (i32, f64, f64) {
        let step = match end_index.cmp(&index) {
            std::cmp::Ordering::Greater => 1,
            std::cmp::Ordering::Less => -1,
            std::cmp::Ordering::Equal => {
                if d >= 0.0 {
                    1
                } else {
                    -1
                }
            }
        };
        if d == 0.0 {
            return (step, f64::INFINITY, f64::INFINITY);
        }
        let boundary = if d > 0.0 {
            f64::from(index) + 1.0
        } else {
            f64::from(index)
        } * r;
        (step, (boundary - o) / d, r / d.abs())
    };
    let (step_i, mut t_max_x, t_delta_x) = axis(start.i, end.i, ox, dx);
    let (step_j, mut t_max_y, t_delta_y) = axis(start.j, end.j, oy, dy);
    let (mut cell, mut l) = (start, l_start);
    let mut crossings = Vec::new();
    for _ in 0..start.i.abs_diff(end.i) + start.j.abs_diff(end.j) {
        let step_x = (t_max_x <= t_max_y || cell.j == end.j) && cell.i != end.i;
        let t_next = if step_x { t_max_x } else { t_max_y };
        let l_exit = t_next.clamp(l, l_end);
        crossings.push(CellCrossing {
            cell,
            l_enter: l,
            l_exit,
        });
        if step_x {
            cell.i += step_i;
            t_max_x += t_delta_x;
        } else {
            cell.j += step_j;
            t_max_y += t_delta_y;
        }
        l = l_exit;
    }
    crossings.push(CellCrossing {
        cell,
        l_enter: l,
        l_exit: l_end.max(l),
    });
    crossings
}
