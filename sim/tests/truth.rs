//! The truth raster against hand-built scenes.

mod common;

use oeg::{CellRegion, GridGeometry};
use sim::truth::{TruthProfile, TruthRaster};
use sim::world::{Actors, World};

const PROFILE: TruthProfile = TruthProfile {
    max_step_m: 0.035,
    height_m: 0.46,
};

fn truth_over(
    name: &str,
    extra: &str,
    min: (f64, f64),
    max: (f64, f64),
) -> (TruthRaster, GridGeometry, World) {
    let loaded = common::load_text(name, &common::scenario_text(extra)).expect("valid");
    let world = World::new(&loaded).expect("world");
    let geometry = GridGeometry::new(0.05).expect("resolution");
    let region: CellRegion = geometry.region_covering(min, max).expect("region");
    (
        TruthRaster::compute(&world, &geometry, region, PROFILE, Actors::Excluded, 4),
        geometry,
        world,
    )
}

#[test]
fn a_3_cm_curb_is_traversable_and_a_5_cm_curb_is_blocked() {
    let extra = "[[obstacles]]\nkind = \"box\"\ncenter_xy_m = [3.0, -1.0]\nsize_m = [0.3, 1.0, 0.03]\n\n\
                 [[obstacles]]\nkind = \"box\"\ncenter_xy_m = [3.0, 1.0]\nsize_m = [0.3, 1.0, 0.05]\n";
    let (truth, g, _) = truth_over("curbs", extra, (2.0, -2.0), (4.0, 2.0));
    let at = |x, y| *truth.get(g.cell_of(x, y).expect("cell")).expect("inside");
    let low = at(3.02, -1.02);
    assert!(
        (low.elevation_m - 0.03).abs() < 1e-3 && !low.step_blocked,
        "{low:?}"
    );
    let high = at(3.02, 1.02);
    assert!(
        (high.elevation_m - 0.05).abs() < 1e-3 && high.step_blocked,
        "{high:?}"
    );
    let road = at(2.5, 0.0);
    assert!(
        road.elevation_m.abs() < 1e-3 && !road.step_blocked && road.structure_gap_m.is_nan(),
        "{road:?}"
    );
    assert!(
        low.clearance_passable(&PROFILE).is_none(),
        "a curb is not a structure overhead"
    );
}

#[test]
fn a_board_at_0_35_m_blocks_and_one_at_0_60_m_lets_the_robot_pass() {
    let extra = "[[obstacles]]\nkind = \"overhang\"\ncenter_xy_m = [3.0, -1.0]\nsize_m = [0.4, 1.0, 0.02]\nclearance_m = 0.35\n\n\
                 [[obstacles]]\nkind = \"overhang\"\ncenter_xy_m = [3.0, 1.0]\nsize_m = [0.4, 1.0, 0.02]\nclearance_m = 0.60\n";
    let (truth, g, _) = truth_over("boards", extra, (2.0, -2.0), (4.0, 2.0));
    let at = |x, y| *truth.get(g.cell_of(x, y).expect("cell")).expect("inside");
    let low = at(3.02, -1.02);
    assert_eq!(low.clearance_passable(&PROFILE), Some(false), "{low:?}");
    assert!((low.structure_gap_m - 0.35).abs() < 2e-3, "{low:?}");
    assert!(
        low.step_blocked && (low.elevation_m - 0.37).abs() < 2e-3,
        "the board's top is the surface: {low:?}"
    );
    let high = at(3.02, 1.02);
    assert_eq!(high.clearance_passable(&PROFILE), Some(true), "{high:?}");
    assert!(
        !high.step_blocked && high.elevation_m.abs() < 1e-3,
        "the board above the robot is not seen: {high:?}"
    );
}

#[test]
fn a_slope_alone_never_blocks() {
    let (truth, _, _) = truth_over(
        "slope",
        "[terrain]\nkind = \"slope\"\nslope_x = 0.2\n",
        (0.0, 0.0),
        (3.0, 1.0),
    );
    assert!(
        truth.cells.iter().all(|c| !c.step_blocked),
        "steps measured against the ground beside them"
    );
    let top = truth.cells.iter().map(|c| c.elevation_m).fold(f32::MIN, f32::max);
    assert!((top - 0.6).abs() < 0.02, "elevation is absolute: {top}");
}

#[test]
fn people_are_in_the_truth_only_when_asked() {
    let extra = "[[actors]]\nkind = \"person\"\nwaypoints = [[0.0, 3.0, 0.0], [10.0, 3.0, 0.0]]\n";
    let loaded = common::load_text("people", &common::scenario_text(extra)).expect("valid");
    let world = World::new(&loaded).expect("world");
    let g = GridGeometry::new(0.05).expect("resolution");
    let region = g.region_covering((2.9, -0.1), (3.1, 0.1)).expect("region");
    let with = TruthRaster::compute(&world, &g, region, PROFILE, Actors::Included, 2);
    let without = TruthRaster::compute(&world, &g, region, PROFILE, Actors::Excluded, 2);
    assert!(with.cells.iter().any(|c| c.step_blocked));
    assert!(without.cells.iter().all(|c| !c.step_blocked));
}

#[test]
fn the_truth_is_reproducible() {
    let extra = "[terrain]\nkind = \"noise\"\namplitude_m = 0.04\nwavelength_m = 1.5\n\n\
                 [[obstacles]]\nkind = \"bush\"\ncenter_xy_m = [3.0, 0.0]\nradius_m = 0.5\nheight_m = 0.7\n";
    let a = truth_over("repro_a", extra, (2.0, -1.0), (4.0, 1.0)).0;
    let b = truth_over("repro_b", extra, (2.0, -1.0), (4.0, 1.0)).0;
    // Compare bit patterns: the truth holds NaN (no structure), which is never equal to itself.
    let bits = |t: &TruthRaster| -> Vec<[u32; 4]> {
        t.cells
            .iter()
            .map(|c| [c.elevation_m, c.ground_m, c.step_m, c.structure_gap_m].map(f32::to_bits))
            .collect()
    };
    assert_eq!(a.region, b.region);
    assert!(bits(&a) == bits(&b), "the same seed gave a different truth");
    assert!(a.cells.iter().any(|c| c.step_blocked), "the bush blocks");
}
