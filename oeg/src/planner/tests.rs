//! The planner's tests.

use super::*;
use proptest::prelude::*;

/// `r` as a window onto a grid of `resolution_m`.
pub(super) fn on(r: &CellRegion, resolution_m: f64) -> GridWindow {
    GridWindow::new(crate::GridGeometry::new(resolution_m).expect("resolution"), *r)
}

pub(super) fn region(nx: i32, ny: i32) -> CellRegion {
    CellRegion::from_corners(CellIndex::new(0, 0), CellIndex::new(nx - 1, ny - 1)).expect("region")
}

/// Every cell of `r` Free, except those `mark` picks, which are `class`.
pub(super) fn marked(
    r: &CellRegion,
    class: Traversability,
    mark: impl Fn(CellIndex) -> bool,
) -> Vec<Traversability> {
    r.cells()
        .map(|c| if mark(c) { class } else { Traversability::Free })
        .collect()
}

pub(super) fn no_inflation(unknown: UnknownCells) -> PlannerOptions {
    PlannerOptions {
        inflation_radius_m: 0.0,
        footprint_radius_m: 0.0,
        unknown,
        uncertain: UncertainCells::Blocked,
        inflation_cost_width_m: 0.0,
        ..PlannerOptions::default()
    }
}

#[test]
fn beyond_the_optimistic_distance_undecided_cells_are_crossed_at_a_cost_and_near_ones_decide() {
    // A 20 x 9 room at 0.1 m, start at the left, goal at the right, and a wall of uncertain cells across
    // it at column `wall`: the planner without optimism finds no path; with it, it crosses the wall when
    // the wall lies beyond the distance, and not when it lies within it.
    let r = region(20, 9);
    let (start, goal) = (CellIndex::new(0, 4), CellIndex::new(19, 4));
    let wall_at = |column: i32, class: Traversability| marked(&r, class, |c| c.i == column);
    let strict = no_inflation(UnknownCells::Avoid);
    let optimistic = PlannerOptions {
        optimistic_beyond_m: Some(0.5),
        ..strict
    };
    for class in [Traversability::Uncertain, Traversability::Unknown] {
        let far = wall_at(10, class);
        assert!(
            plan(&on(&r, 0.1), &far, start, goal, &strict)
                .expect("valid")
                .is_none()
        );
        let crossed = plan(&on(&r, 0.1), &far, start, goal, &optimistic)
            .expect("valid")
            .expect("crossed beyond 0.5 m");
        assert!(crossed.cells.iter().any(|c| c.i == 10));
        // 0.3 m from the start: within the distance, the wall decides for real.
        let near = wall_at(3, class);
        assert!(
            plan(&on(&r, 0.1), &near, start, goal, &optimistic)
                .expect("valid")
                .is_none()
        );
    }
}

#[test]
fn undecided_cells_cost_more_than_sure_ones() {
    // A block of uncertain cells on the straight line with a free way round it: the path goes round while
    // the detour costs less than the block's doubt, and through it when crossing is the cheaper.
    let r = region(30, 11);
    let (start, goal) = (CellIndex::new(0, 5), CellIndex::new(29, 5));
    let block = marked(&r, Traversability::Uncertain, |c| {
        (14..=16).contains(&c.i) && (3..=7).contains(&c.j)
    });
    let options = |doubt_cost| PlannerOptions {
        optimistic_beyond_m: Some(0.5),
        doubt_cost,
        ..no_inflation(UnknownCells::Avoid)
    };
    let crosses = |p: &Plan| {
        p.cells
            .iter()
            .any(|c| block[r.offset(*c).expect("inside")] != Traversability::Free)
    };
    let round = plan(&on(&r, 0.1), &block, start, goal, &options(DEFAULT_DOUBT_COST))
        .expect("valid")
        .expect("a path");
    assert!(!crosses(&round), "went through the block at the default cost");
    let through = plan(&on(&r, 0.1), &block, start, goal, &options(0.0))
        .expect("valid")
        .expect("a path");
    assert!(crosses(&through), "a free doubt should take the straight line");
    assert!(through.length_m < round.length_m);
}

#[test]
fn a_doubt_cost_an_optimistic_distance_or_an_inflation_cost_out_of_range_is_refused() {
    for bad in [
        PlannerOptions {
            doubt_cost: -1.0,
            ..PlannerOptions::default()
        },
        PlannerOptions {
            doubt_cost: f64::NAN,
            ..PlannerOptions::default()
        },
        PlannerOptions {
            optimistic_beyond_m: Some(f64::INFINITY),
            ..PlannerOptions::default()
        },
        PlannerOptions {
            inflation_cost_width_m: -0.1,
            ..PlannerOptions::default()
        },
        PlannerOptions {
            cost_scaling_factor: f64::NAN,
            ..PlannerOptions::default()
        },
        PlannerOptions {
            cost_scaling_factor: -1.0,
            ..PlannerOptions::default()
        },
    ] {
        assert!(bad.validate().is_err(), "{bad:?}");
    }
}

#[test]
fn no_path_says_which_end_is_forbidden_or_that_nothing_joins_them() {
    let r = region(10, 3);
    let why = |d: &[Traversability], goal: CellIndex, options: &PlannerOptions| {
        plan_or_why(&on(&r, 0.1), d, CellIndex::new(0, 1), goal, options)
            .expect("valid")
            .expect_err("no path")
    };
    let avoid = no_inflation(UnknownCells::Avoid);
    // A wall across the region.
    let wall = marked(&r, Traversability::Blocked, |c| c.i == 5);
    assert_eq!(why(&wall, CellIndex::new(9, 1), &avoid), NoPath::NoConnection);
    // The goal on the wall, or uncertain.
    assert_eq!(
        why(&wall, CellIndex::new(5, 1), &avoid),
        NoPath::Goal(Traversability::Blocked)
    );
    let uncertain = marked(&r, Traversability::Uncertain, |c| c.i == 9);
    let reason = why(&uncertain, CellIndex::new(9, 1), &avoid);
    assert_eq!(reason, NoPath::Goal(Traversability::Uncertain));
    assert!(reason.describe(&avoid).contains("uncertain"));
    // A free goal beside a blocked cell, inside the inflation radius.
    let inflated = PlannerOptions {
        inflation_radius_m: 0.15,
        ..avoid
    };
    let post = marked(&r, Traversability::Blocked, |c| c == CellIndex::new(9, 2));
    let reason = why(&post, CellIndex::new(9, 1), &inflated);
    assert_eq!(reason, NoPath::Goal(Traversability::Free));
    assert!(
        reason
            .describe(&inflated)
            .contains("within the inflation radius (0.15 m)")
    );
}

#[test]
fn an_open_grid_gives_the_octile_distance() {
    let r = region(10, 6);
    let d = vec![Traversability::Free; 60];
    let p = plan(
        &on(&r, 0.1),
        &d,
        CellIndex::new(0, 0),
        CellIndex::new(9, 3),
        &no_inflation(UnknownCells::Avoid),
    )
    .expect("valid")
    .expect("a path");
    // 3 diagonals and 6 straight moves.
    assert!(
        (p.length_m - (0.6 + 0.3 * std::f64::consts::SQRT_2)).abs() < 1e-9,
        "{}",
        p.length_m
    );
    assert_eq!(p.cells.first(), Some(&CellIndex::new(0, 0)));
    assert_eq!(p.cells.last(), Some(&CellIndex::new(9, 3)));
    for w in p.cells.windows(2) {
        assert!((w[0].i - w[1].i).abs() <= 1 && (w[0].j - w[1].j).abs() <= 1 && w[0] != w[1]);
    }
}

#[test]
fn a_wall_with_no_gap_leaves_no_path_and_inflation_closes_a_narrow_gap() {
    let r = region(11, 11);
    // A wall at i = 5 with a one-cell gap at j = 5.
    let d = marked(&r, Traversability::Blocked, |c| c.i == 5 && c.j != 5);
    let (s, g) = (CellIndex::new(0, 5), CellIndex::new(10, 5));
    let open = plan(&on(&r, 0.1), &d, s, g, &no_inflation(UnknownCells::Avoid)).expect("valid");
    assert!(open.is_some(), "the gap lets a point robot through");
    let wide = PlannerOptions {
        inflation_radius_m: 0.1,
        footprint_radius_m: 0.1,
        unknown: UnknownCells::Avoid,
        uncertain: UncertainCells::Blocked,
        ..PlannerOptions::default()
    };
    assert_eq!(
        plan(&on(&r, 0.1), &d, s, g, &wide).expect("valid"),
        None,
        "a 0.1 m robot does not fit"
    );
    let closed = marked(&r, Traversability::Blocked, |c| c.i == 5);
    assert_eq!(
        plan(&on(&r, 0.1), &closed, s, g, &no_inflation(UnknownCells::Avoid)).expect("valid"),
        None
    );
}

#[test]
fn diagonals_do_not_cut_corners() {
    let r = region(2, 2);
    // Free (0,0) and (1,1); blocked (1,0) and (0,1): only a corner-cutting diagonal would connect them.
    let d = vec![
        Traversability::Free,
        Traversability::Blocked,
        Traversability::Blocked,
        Traversability::Free,
    ];
    let p = plan(
        &on(&r, 1.0),
        &d,
        CellIndex::new(0, 0),
        CellIndex::new(1, 1),
        &no_inflation(UnknownCells::Avoid),
    );
    assert_eq!(p.expect("valid"), None);
}

#[test]
fn unknown_cells_follow_the_option() {
    let r = region(7, 3);
    // The middle column is unknown; the start cell is unknown too (the robot stands on it).
    let d = marked(&r, Traversability::Unknown, |c| {
        c.i == 3 || c == CellIndex::new(0, 1)
    });
    let (s, g) = (CellIndex::new(0, 1), CellIndex::new(6, 1));
    let go = |unknown| plan(&on(&r, 1.0), &d, s, g, &no_inflation(unknown)).expect("valid");
    assert_eq!(go(UnknownCells::Avoid), None, "the unknown column is not entered");
    assert!(go(UnknownCells::Drivable).is_some());
    assert_eq!(go(UnknownCells::Inflate), None);
    // The start's own unknown cell is exempt: with the column known, a path exists.
    let mut known = d.clone();
    for c in r.cells().filter(|c| c.i == 3) {
        known[r.offset(c).expect("inside")] = Traversability::Traversable;
    }
    assert!(
        plan(&on(&r, 1.0), &known, s, g, &no_inflation(UnknownCells::Avoid))
            .expect("valid")
            .is_some()
    );
    // Inflated unknown cells close a corridor that avoided unknown cells leave open.
    let opts = |unknown| PlannerOptions {
        inflation_radius_m: 2.0,
        footprint_radius_m: 2.0,
        unknown,
        uncertain: UncertainCells::Blocked,
        ..PlannerOptions::default()
    };
    let corridor = marked(&r, Traversability::Unknown, |c| c.j == 2);
    let (s, g) = (CellIndex::new(0, 0), CellIndex::new(6, 0));
    assert!(
        plan(&on(&r, 1.0), &corridor, s, g, &opts(UnknownCells::Avoid))
            .expect("valid")
            .is_some()
    );
    assert_eq!(
        plan(&on(&r, 1.0), &corridor, s, g, &opts(UnknownCells::Inflate)).expect("valid"),
        None
    );
}

#[test]
fn the_robot_stands_on_its_unobserved_footprint() {
    // 0.1 m cells; nothing within 0.2 m of the start was observed (no sensor sees under the robot).
    let r = region(12, 5);
    let s = CellIndex::new(2, 2);
    let d = marked(&r, Traversability::Unknown, |c| {
        (c.i - 2).abs() <= 2 && (c.j - 2).abs() <= 2
    });
    let g = CellIndex::new(11, 2);
    let footprint = PlannerOptions {
        inflation_radius_m: 0.2,
        footprint_radius_m: 0.2,
        unknown: UnknownCells::Avoid,
        uncertain: UncertainCells::Blocked,
        ..PlannerOptions::default()
    };
    assert!(plan(&on(&r, 0.1), &d, s, g, &footprint).expect("valid").is_some());
    let point = no_inflation(UnknownCells::Avoid);
    assert_eq!(
        plan(&on(&r, 0.1), &d, s, g, &point).expect("valid"),
        None,
        "only the start cell is exempt"
    );
}

#[test]
fn blocked_cells_under_the_robot_at_the_start_are_cleared_but_not_at_the_goal() {
    // A false hit 0.1 m beside the start would pin a 0.2 m robot; the same next to the goal blocks it.
    let r = region(12, 5);
    let (s, g) = (CellIndex::new(2, 2), CellIndex::new(9, 2));
    let options = PlannerOptions {
        inflation_radius_m: 0.2,
        footprint_radius_m: 0.2,
        unknown: UnknownCells::Avoid,
        uncertain: UncertainCells::Blocked,
        ..PlannerOptions::default()
    };
    let with_hit_at =
        |hit: CellIndex| -> Vec<Traversability> { marked(&r, Traversability::Blocked, |c| c == hit) };
    let near_start = with_hit_at(CellIndex::new(3, 2));
    assert!(
        plan(&on(&r, 0.1), &near_start, s, g, &options)
            .expect("valid")
            .is_some()
    );
    let near_goal = with_hit_at(CellIndex::new(10, 2));
    assert_eq!(
        plan(&on(&r, 0.1), &near_goal, s, g, &options).expect("valid"),
        None
    );
}

#[test]
fn a_wide_inflation_radius_does_not_clear_the_obstacles_around_the_start() {
    // 0.1 m cells. A wall 1 m ahead of the start with a 0.3 m gap; the robot (0.25 m footprint) plans with a
    // 5 m safety margin. Clearing the start's inflation radius would erase the wall and report a path
    // through it; only the footprint is cleared, so there is no path.
    let r = region(60, 60);
    let (s, g) = (CellIndex::new(30, 20), CellIndex::new(30, 50));
    let wall = marked(&r, Traversability::Blocked, |c| c.j == 30 && (c.i - 30).abs() > 1);
    let options = PlannerOptions {
        inflation_radius_m: 5.0,
        ..PlannerOptions::default()
    };
    assert_eq!(plan(&on(&r, 0.1), &wall, s, g, &options).expect("valid"), None);
    // Without the wall the margin is free to be as wide as it likes around the start.
    let open = marked(&r, Traversability::Blocked, |_| false);
    assert!(
        plan(&on(&r, 0.1), &open, s, g, &options)
            .expect("valid")
            .is_some()
    );
}

#[test]
fn bad_inputs_are_errors() {
    let r = region(3, 3);
    let d = vec![Traversability::Free; 9];
    let o = PlannerOptions::default();
    assert!(
        plan(
            &on(&r, 0.1),
            &d[..8],
            CellIndex::new(0, 0),
            CellIndex::new(2, 2),
            &o
        )
        .is_err()
    );
    assert!(plan(&on(&r, 0.1), &d, CellIndex::new(0, 0), CellIndex::new(3, 2), &o).is_err());
    let bad = PlannerOptions {
        inflation_radius_m: f64::NAN,
        footprint_radius_m: f64::NAN,
        ..o
    };
    let err =
        plan(&on(&r, 0.1), &d, CellIndex::new(0, 0), CellIndex::new(2, 2), &bad).expect_err("NaN radius");
    assert!(err.to_string().contains("inflation_radius_m"), "{err}");
}

/// Brute force: a cell is forbidden when a blocked cell lies within the radius of it.
fn brute_mask(r: &CellRegion, d: &[Traversability], radius_cells: f64) -> Vec<bool> {
    r.cells()
        .map(|c| {
            r.cells().any(|o| {
                let (dx, dy) = (f64::from(o.i - c.i), f64::from(o.j - c.j));
                d[r.offset(o).expect("inside")] == Traversability::Blocked
                    && dx * dx + dy * dy <= radius_cells * radius_cells + 1e-9
            })
        })
        .collect()
}

proptest! {
    #[test]
    fn the_inflated_mask_matches_brute_force(
        cells in proptest::collection::vec(0u8..12, 12 * 9),
        radius_cells in 0.0f64..16.0,
    ) {
        let r = region(12, 9);
        let d: Vec<Traversability> = cells
            .iter()
            .map(|v| if *v == 0 { Traversability::Blocked } else { Traversability::Free })
            .collect();
        let options = PlannerOptions { inflation_radius_m: radius_cells * 0.1, unknown: UnknownCells::Avoid, ..PlannerOptions::default() };
        let mask = forbidden_mask(&on(&r, 0.1), &d, &options).expect("valid");
        prop_assert_eq!(mask, brute_mask(&r, &d, radius_cells));
    }

    #[test]
    fn a_path_is_never_shorter_than_the_straight_line_and_avoids_the_mask(
        cells in proptest::collection::vec(0u8..5, 10 * 10),
    ) {
        let r = region(10, 10);
        let mut d: Vec<Traversability> = cells
            .iter()
            .map(|v| if *v == 0 { Traversability::Blocked } else { Traversability::Free })
            .collect();
        d[0] = Traversability::Free;
        d[99] = Traversability::Free;
        let o = no_inflation(UnknownCells::Avoid);
        if let Some(p) = plan(&on(&r, 1.0), &d, CellIndex::new(0, 0), CellIndex::new(9, 9), &o).expect("valid") {
            prop_assert!(p.length_m >= 9.0 * std::f64::consts::SQRT_2 - 1e-9);
            for c in &p.cells {
                prop_assert!(d[r.offset(*c).expect("inside")] != Traversability::Blocked);
            }
        }
    }
}

#[test]
fn the_undecided_cells_on_the_relaxed_path_closed_the_way_and_none_did_behind_a_blocked_wall() {
    // A 10 x 5 room at 0.1 m with a wall across column 5: uncertain, unknown, or blocked.
    let r = region(10, 5);
    let w = on(&r, 0.1);
    let (start, goal) = (CellIndex::new(0, 2), CellIndex::new(9, 2));
    let closing = |class, options: PlannerOptions| {
        let decisions = marked(&r, class, |c| c.i == 5);
        assert_eq!(plan(&w, &decisions, start, goal, &options).expect("plan"), None);
        closing_cells(&w, &decisions, start, goal, &options).expect("valid")
    };
    let strict = no_inflation(UnknownCells::Avoid);
    for class in [Traversability::Uncertain, Traversability::Unknown] {
        // Without inflation, the one wall cell the relaxed path crosses.
        let cells = closing(class, strict).expect("the relaxed path exists");
        assert_eq!(cells.len(), 1, "{class:?}: {cells:?}");
        assert_eq!(cells[0].i, 5);
    }
    // Inflated, the wall's cells within the radius of the path close it too; unknown cells under `Avoid` are
    // not inflated, so only the one on the path counts.
    let inflated = |unknown| PlannerOptions {
        inflation_radius_m: 0.15,
        ..no_inflation(unknown)
    };
    let count = |class, unknown| {
        closing(class, inflated(unknown))
            .expect("the relaxed path exists")
            .len()
    };
    assert!(count(Traversability::Uncertain, UnknownCells::Avoid) >= 3);
    assert_eq!(count(Traversability::Unknown, UnknownCells::Avoid), 1);
    assert!(count(Traversability::Unknown, UnknownCells::Inflate) >= 3);
    // A blocked wall closes the way whatever the planner makes of undecided cells.
    assert_eq!(closing(Traversability::Blocked, strict), None);
}

#[test]
fn the_cells_under_the_robot_at_the_start_never_close_the_way() {
    // Unknown cells all round the start, within its footprint radius, and an uncertain wall farther on: the
    // planner clears the footprint, so only the wall closes the way.
    let r = region(12, 5);
    let w = on(&r, 0.1);
    let (start, goal) = (CellIndex::new(2, 2), CellIndex::new(11, 2));
    let decisions: Vec<Traversability> = r
        .cells()
        .map(|c| match c {
            c if c.i == 8 => Traversability::Uncertain,
            c if (c.i - start.i).abs() <= 1 && (c.j - start.j).abs() <= 1 => Traversability::Unknown,
            _ => Traversability::Free,
        })
        .collect();
    let options = PlannerOptions {
        footprint_radius_m: 0.15,
        inflation_radius_m: 0.15,
        ..no_inflation(UnknownCells::Avoid)
    };
    assert_eq!(plan(&w, &decisions, start, goal, &options).expect("plan"), None);
    let closing = closing_cells(&w, &decisions, start, goal, &options)
        .expect("valid")
        .expect("the relaxed path exists");
    assert!(!closing.is_empty());
    assert!(closing.iter().all(|c| c.i == 8), "{closing:?}");
}
