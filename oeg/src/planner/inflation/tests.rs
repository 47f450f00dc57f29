//! The inflation's tests.

use super::super::tests::{marked, no_inflation, on, region};
use super::Inflation;
use crate::geometry::CellIndex;
use crate::planner::{
    INFLATED_CELL_COST, PlannerOptions, UncertainCells, UnknownCells, forbidden_mask, plan,
};
use crate::traversability::Traversability;

#[test]
fn a_robot_inside_the_inflation_keeps_the_clearance_it_has_and_no_less() {
    // 0.1 m cells; a wall along x = 5; the robot's centre 0.3 m from it, inside a 0.5 m inflation, with
    // a start exemption too small to reach the wall.
    let r = region(12, 9);
    let d = marked(&r, Traversability::Blocked, |c| c.i == 5 && c.j <= 5);
    let options = PlannerOptions {
        inflation_radius_m: 0.5,
        footprint_radius_m: 0.1,
        unknown: UnknownCells::Drivable,
        uncertain: UncertainCells::Blocked,
        ..PlannerOptions::default()
    };
    let (s, g) = (CellIndex::new(2, 2), CellIndex::new(10, 2));
    let p = plan(&on(&r, 0.1), &d, s, g, &options)
        .expect("valid")
        .expect("a way out and round");
    // Every cell of the path keeps at least the start's clearance less half a cell (0.25 m) from the wall.
    for c in &p.cells {
        for k in 0..=5 {
            let d = f64::from(c.i - 5).hypot(f64::from(c.j - k)) * 0.1;
            assert!(d > 0.25, "{c:?} is {d} m from the wall");
        }
    }
    // Without the clearance rule the start would be pinned: every cell round it lies in the inflation.
    let forbidden = forbidden_mask(&on(&r, 0.1), &d, &options).expect("valid");
    assert!(forbidden[r.offset(s).expect("inside")]);
}

#[test]
fn a_robot_inside_the_inflation_leaves_it_before_driving_along_it() {
    // 0.1 m cells; a wall along y = 0 under a 30 x 12 room; the robot 0.2 m above it, inside a 0.5 m
    // inflation; the goal far along the wall, outside the inflation. Running along the wall at the start's
    // clearance is the shortest path, but every step of it inside the inflation costs more: the path climbs
    // out of the inflation within its first few cells and stays out.
    let r = region(30, 12);
    let d = marked(&r, Traversability::Blocked, |c| c.j == 0);
    let options = PlannerOptions {
        inflation_radius_m: 0.5,
        footprint_radius_m: 0.1,
        ..no_inflation(UnknownCells::Avoid)
    };
    let (s, g) = (CellIndex::new(1, 2), CellIndex::new(28, 6));
    let p = plan(&on(&r, 0.1), &d, s, g, &options)
        .expect("valid")
        .expect("a way out and along");
    let inside = p.cells.iter().filter(|c| c.j <= 5).count();
    assert!(
        inside <= 5,
        "{inside} cells of the path lie inside the inflation: {:?}",
        p.cells
    );
    let first_out = p.cells.iter().position(|c| c.j > 5).expect("leaves");
    assert!(p.cells[first_out..].iter().all(|c| c.j > 5), "{:?}", p.cells);
}

#[test]
fn beyond_the_inflation_a_path_keeps_the_margin_the_room_allows() {
    // 0.05 m cells; a wall along y = 0 under a 120 x 20 room; start and goal 0.30 m above it, just outside a
    // 0.25 m inflation. Without the inflation cost the shortest path runs straight along the wall at 0.30 m;
    // with it, the path moves out to where entering a cell costs almost nothing and comes back at the end.
    let r = region(120, 20);
    let d = marked(&r, Traversability::Blocked, |c| c.j == 0);
    let (s, g) = (CellIndex::new(2, 6), CellIndex::new(117, 6));
    let costed = PlannerOptions {
        inflation_radius_m: 0.25,
        footprint_radius_m: 0.25,
        ..PlannerOptions::default()
    };
    let flat = PlannerOptions {
        inflation_cost_width_m: 0.0,
        ..costed
    };
    let straight = plan(&on(&r, 0.05), &d, s, g, &flat)
        .expect("valid")
        .expect("a path");
    assert!(straight.cells.iter().all(|c| c.j == 6), "{:?}", straight.cells);
    let kept = plan(&on(&r, 0.05), &d, s, g, &costed)
        .expect("valid")
        .expect("a path");
    let middle = &kept.cells[kept.cells.len() / 3..2 * kept.cells.len() / 3];
    // Out past most of the 0.30 m band: the cost 0.20 m beyond the radius is 0.5 cell lengths a cell.
    assert!(middle.iter().map(|c| c.j).min() >= Some(10), "{:?}", kept.cells);
    assert!(kept.length_m > straight.length_m);
    // The cost never forbids: in a corridor with no room, the path is the straight one.
    let corridor = marked(&r, Traversability::Blocked, |c| c.j == 0 || c.j == 12);
    let through = plan(&on(&r, 0.05), &corridor, s, g, &costed)
        .expect("valid")
        .expect("a path");
    assert!(through.cells.iter().all(|c| c.j == 6), "{:?}", through.cells);
}

#[test]
fn the_inflation_cost_decays_from_the_radius_to_nothing_at_the_band_s_edge() {
    // One blocked cell at the origin of a 40 x 1 row of 0.05 m cells: each cell's cost is a function of its
    // distance alone, 4 cell lengths just beyond the radius, halving about every 7 cm, none beyond the band.
    let r = region(40, 1);
    let d = marked(&r, Traversability::Blocked, |c| c.i == 0);
    let options = PlannerOptions::default();
    let inflation = Inflation::of(&on(&r, 0.05), &d, &options);
    let mut extra = vec![0; 40];
    inflation.add_costs(&mut extra, &options);
    for (i, e) in extra.iter().enumerate() {
        let distance_m = i as f64 * 0.05;
        let expected = if distance_m <= 0.25 + 1e-9 || distance_m > 0.55 + 1e-9 {
            0.0
        } else {
            INFLATED_CELL_COST * (-10.0 * (distance_m - 0.25)).exp()
        };
        assert_eq!(*e, (expected * 1000.0).round() as u32, "cell {i}");
    }
    assert!((2000..4000).contains(&extra[6]), "{extra:?}");
    assert!(extra[6..=11].windows(2).all(|w| w[0] > w[1]), "{extra:?}");
    assert!(extra[12..].iter().all(|e| *e == 0), "{extra:?}");
}
