//! The truth raster against hand-built scenes.

#![allow(
    clippy::disallowed_methods,
    reason = "tests and tools write their inputs directly"
)]

mod common;

use oeg::{CellRegion, GridGeometry, GridWindow, RobotProfile};
use sim::truth::TruthRaster;
use sim::world::{Actors, World};

/// The paper's Pioneer 3-AT: 3.5 cm steps, 0.46 m tall, 35 % grades (a contact distance of 0.10 m).
const PROFILE: RobotProfile = RobotProfile {
    max_step_m: 0.035,
    height_m: 0.46,
    max_grade: 0.35,
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
        TruthRaster::compute(
            &world,
            &GridWindow::new(geometry, region),
            PROFILE,
            Actors::Excluded,
            4,
            &|| true,
        )
        .expect("never cancelled"),
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
    // The curbs span x = 2.85 to 3.15 m; cells at their edges.
    let low = at(2.87, -1.02);
    assert!(
        (low.elevation_m - 0.03).abs() < 1e-3 && !low.step_blocked && (low.step_m - 0.03).abs() < 1e-3,
        "{low:?}"
    );
    let high = at(2.87, 1.02);
    assert!(
        (high.elevation_m - 0.05).abs() < 1e-3 && high.step_blocked,
        "{high:?}"
    );
    assert!(at(3.13, 1.02).step_blocked, "the far edge too");
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
        (low.elevation_m - 0.37).abs() < 2e-3,
        "the board's top is the surface: {low:?}"
    );
    assert!(
        truth.truly_blocked(
            truth
                .window
                .region()
                .offset(g.cell_of(3.02, -1.02).expect("cell"))
                .expect("inside")
        )
    );
    assert!(at(2.82, -1.02).step_blocked, "its edge is a step as well");
    let high = at(3.02, 1.02);
    assert_eq!(high.clearance_passable(&PROFILE), Some(true), "{high:?}");
    assert!(
        !high.step_blocked && high.elevation_m.abs() < 1e-3,
        "the board above the robot is not seen: {high:?}"
    );
}

#[test]
fn a_slope_the_robot_climbs_never_blocks_and_a_steeper_one_does() {
    let (truth, _, _) = truth_over(
        "slope",
        "[terrain]\nkind = \"slope\"\nslope_x = 0.3\n",
        (0.0, 0.0),
        (3.0, 1.0),
    );
    assert!(
        truth.cells.iter().all(|c| !c.step_blocked),
        "a 30 % grade rises 3 cm over the 0.10 m contact distance"
    );
    let top = truth.cells.iter().map(|c| c.elevation_m).fold(f32::MIN, f32::max);
    assert!((top - 0.9).abs() < 0.02, "elevation is absolute: {top}");
    let (steep, _, _) = truth_over(
        "steep",
        "[terrain]\nkind = \"slope\"\nslope_x = 0.45\n",
        (0.0, 0.0),
        (3.0, 1.0),
    );
    assert!(
        steep.cells.iter().all(|c| c.step_blocked),
        "a 45 % grade is steeper than the robot climbs"
    );
}

#[test]
fn a_ramp_is_drivable_and_its_open_sides_are_steps() {
    // 0.15 m over 1 m (15 %), 1 m wide: the robot drives up it, but not onto it from the side.
    let extra = "[[obstacles]]\nkind = \"ramp\"\ncenter_xy_m = [3.0, 0.0]\nlength_m = 1.0\nwidth_m = 1.0\nheight_m = 0.15\n";
    let (truth, g, _) = truth_over("ramp", extra, (2.0, -1.0), (4.0, 1.0));
    let at = |x, y| *truth.get(g.cell_of(x, y).expect("cell")).expect("inside");
    for x in [2.6, 3.0, 3.3] {
        let on = at(x, 0.02);
        assert!(!on.step_blocked && on.elevation_m > 0.01, "{x}: {on:?}");
    }
    let side = at(3.3, 0.48);
    assert!(side.step_blocked, "the side of the ramp 11 cm up: {side:?}");
}

/// Writes an 8-bit greyscale PNG of `w x h` pixels, `f(column, row)` giving each value.
fn write_png(path: &std::path::Path, w: u32, h: u32, f: impl Fn(u32, u32) -> u8) {
    let file = std::fs::File::create(path).expect("png file");
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().expect("header");
    let data: Vec<u8> = (0..h)
        .flat_map(|r| (0..w).map(move |c| (c, r)))
        .map(|(c, r)| f(c, r))
        .collect();
    writer.write_image_data(&data).expect("pixels");
}

#[test]
fn steps_drawn_into_a_heightmap_are_steps() {
    // 1 cm pixels, 1 mm per grey level: a 3 cm and a 5 cm bar, 0.3 m wide, drawn into the terrain itself, on a
    // 10 % slope (0.1 mm per pixel is below the image's resolution, so the slope is built in 1 mm terraces of
    // 1 cm: 10 % on average, each terrace a 1 mm rise).
    let dir = common::temp_dir("heightmap_steps");
    let png_path = dir.join("steps.png");
    write_png(&png_path, 400, 100, |c, _| {
        let slope = (c / 10) as u8;
        let bar = match c {
            100..=129 => 30,
            250..=279 => 50,
            _ => 0,
        };
        slope + bar
    });
    let extra = format!(
        "[terrain]\nkind = \"image\"\npath = \"{}\"\nheight_scale_m = 0.255\ncell_m = 0.01\norigin_xy_m = [0.0, -0.5]\n",
        png_path.display()
    );
    let (truth, g, _) = truth_over("heightmap", &extra, (0.05, -0.4), (3.9, 0.4));
    let at = |x, y| *truth.get(g.cell_of(x, y).expect("cell")).expect("inside");
    let low = at(1.12, 0.0);
    assert!(!low.step_blocked, "a 3 cm bar is climbed: {low:?}");
    let edge = at(2.52, 0.0);
    assert!(
        edge.step_blocked && (edge.step_m - 0.05).abs() < 0.006,
        "a 5 cm bar's edge is a step: {edge:?}"
    );
    let far_edge = at(2.77, 0.0);
    assert!(far_edge.step_blocked, "and so is its far edge: {far_edge:?}");
    let middle = at(2.65, 0.0);
    assert!(
        !middle.step_blocked,
        "the middle of its top, 15 cm from either edge, is flat ground to a wheel: {middle:?}"
    );
    let slope = at(2.0, 0.0);
    assert!(
        !slope.step_blocked && slope.step_m < 0.02,
        "the slope between: {slope:?}"
    );
}

#[test]
fn people_are_in_the_truth_only_when_asked() {
    let extra = "[[actors]]\nkind = \"person\"\nwaypoints = [[0.0, 3.0, 0.0], [10.0, 3.0, 0.0]]\n";
    let loaded = common::load_text("people", &common::scenario_text(extra)).expect("valid");
    let world = World::new(&loaded).expect("world");
    let g = GridGeometry::new(0.05).expect("resolution");
    let region = g.region_covering((2.9, -0.1), (3.1, 0.1)).expect("region");
    let with = TruthRaster::compute(
        &world,
        &GridWindow::new(g, region),
        PROFILE,
        Actors::Included,
        2,
        &|| true,
    )
    .expect("never cancelled");
    let without = TruthRaster::compute(
        &world,
        &GridWindow::new(g, region),
        PROFILE,
        Actors::Excluded,
        2,
        &|| true,
    )
    .expect("never cancelled");
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
    assert_eq!(a.window, b.window);
    assert!(bits(&a) == bits(&b), "the same seed gave a different truth");
    assert!(a.cells.iter().any(|c| c.step_blocked), "the bush blocks");
}

#[test]
fn a_cell_s_truth_does_not_depend_on_how_the_region_is_cut_into_bands() {
    // The truth goes in bands of cell rows that hold about a million samples: a narrow region is one band, a
    // region 30 m wide at 0.01 m is a band per cell row. Every cell the two share must be the same, bit for bit.
    let extra = "[[obstacles]]\nkind = \"box\"\ncenter_xy_m = [3.0, -1.0]\nsize_m = [0.3, 1.0, 0.05]\n";
    let loaded = common::load_text("bands", &common::scenario_text(extra)).expect("valid");
    let world = World::new(&loaded).expect("world");
    let g = GridGeometry::new(0.01).expect("resolution");
    let compute = |min, max| {
        let region = g.region_covering(min, max).expect("region");
        TruthRaster::compute(
            &world,
            &GridWindow::new(g, region),
            PROFILE,
            Actors::Excluded,
            4,
            &|| true,
        )
        .expect("never cancelled")
    };
    let narrow = compute((2.5, -1.2), (3.5, -0.8));
    let wide = compute((-10.0, -1.2), (20.0, -0.8));
    let mut blocked = 0;
    for cell in narrow.window.region().cells() {
        let (a, b) = (narrow.get(cell).expect("inside"), wide.get(cell).expect("inside"));
        assert_eq!(format!("{a:?}"), format!("{b:?}"), "cell {cell:?}");
        blocked += usize::from(a.step_blocked);
    }
    assert!(blocked > 0, "the curb's edges are steps");
}

#[test]
fn the_truth_stops_when_asked() {
    let (_, g, world) = truth_over("cancelled", "", (0.0, -1.0), (1.0, 1.0));
    let region = g.region_covering((0.0, -1.0), (1.0, 1.0)).expect("region");
    let asked = std::cell::Cell::new(0);
    let keep_going = || {
        asked.set(asked.get() + 1);
        false
    };
    let result = TruthRaster::compute(
        &world,
        &GridWindow::new(g, region),
        PROFILE,
        Actors::Excluded,
        4,
        &keep_going,
    );
    assert_eq!(result, Err(sim::truth::TruthCancelled));
    assert_eq!(asked.get(), 1, "asked before the first band");
}
