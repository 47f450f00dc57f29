//! What the sensors could see, on the geometry alone and in a simulated world: a board that fits between two
//! lidar rings is blind at 3 m and observable at 1 m; a person is neither ground nor structure.

#![allow(
    clippy::disallowed_methods,
    reason = "tests and tools write their inputs directly"
)]

mod common;

use oeg::{GridGeometry, RobotProfile};
use sim::Simulation;
use sim::observability::{Observer, blind_band, ray_heights_at};

/// A 16-ring lidar (rings 2 degrees apart, none level) 0.452 m up, looking level; the robot stands still.
const LIDAR: &str = r#"
[[sensors]]
name = "lidar"
kind = "lidar3d"
mount_link = "stereo_mount"
preset = "vlp16"
"#;

/// A board 4 cm thick whose underside is 0.33 m above the ground, 1.2 m wide, its centre `x` metres ahead.
fn board(x: f64) -> String {
    format!(
        "[[obstacles]]\nkind = \"overhang\"\nname = \"board\"\ncenter_xy_m = [{x}, 0.0]\nsize_m = [0.3, 1.2, \
         0.04]\nclearance_m = 0.33\n"
    )
}

fn standing(extra: &str) -> String {
    common::scenario_text(extra).replace("[[0.0, 0.0], [4.0, 0.0]]", "[[0.0, 0.0]]")
}

#[test]
fn a_board_between_two_rings_is_blind_at_3_m_and_observable_at_1_m_on_the_geometry_alone() {
    let loaded = common::load_text("rings", &standing(LIDAR)).expect("valid");
    let sim = Simulation::new(&loaded).expect("simulation");
    let inside = |range: f64| {
        ray_heights_at(sim.sensors(), sim.world(), range)
            .into_iter()
            .filter(|h| (0.33..=0.37).contains(h))
            .count()
    };
    // At 1 m the rings at -5 degrees pass at 0.365 m: through the board.
    assert!(inside(1.0) > 0, "a ring crosses the board at 1 m");
    // At 3 m the -1 and -3 degree rings pass at 0.40 and 0.29 m: the board hides between them.
    assert_eq!(inside(3.0), 0, "no ring crosses the board at 3 m");
    let band = blind_band(sim.sensors(), sim.world(), &RobotProfile::default(), 0.5, 5.0);
    let at = |r: f64| band.iter().find(|b| (b.range_m - r).abs() < 1e-9).expect("row");
    assert!(at(3.0).largest_gap_m > 0.04, "{:?}", at(3.0));
    assert!(
        at(3.0).gap_from_m < 0.33 && at(3.0).gap_to_m > 0.37,
        "{:?}",
        at(3.0)
    );
    // Near the robot the lowest ring has not come down yet: below 0.15 m nothing is seen at 1 m.
    assert!(
        at(1.0).gap_from_m < 0.04 && at(1.0).gap_to_m > 0.15,
        "{:?}",
        at(1.0)
    );
}

/// The board's cells after one second of scans: whether a ray ended in their band.
fn board_band_hits(x: f64) -> (usize, usize) {
    let text = standing(&format!("{LIDAR}{}", board(x)));
    let loaded = common::load_text(&format!("board-{x}"), &text).expect("valid");
    let mut sim = Simulation::new(&loaded).expect("simulation");
    let geometry = GridGeometry::new(0.05).expect("geometry");
    let region = geometry
        .region_covering((x - 0.1, -0.5), (x + 0.1, 0.5))
        .expect("region");
    let window = oeg::GridWindow::new(geometry, region);
    let mut o = Observer::new(sim.world(), &window, RobotProfile::default());
    while let Some(scan) = sim.next_scan() {
        if scan.stamp_s > 1.0 {
            break;
        }
        o.observe(&scan, 100.0);
    }
    let o = o.finished();
    (o.band_hit.iter().filter(|h| **h).count(), o.band_hit.len())
}

#[test]
fn in_the_world_the_far_board_is_never_hit_and_the_near_one_is() {
    let (far, n) = board_band_hits(3.0);
    assert_eq!(far, 0, "no ray ended on the board at 3 m ({n} cells)");
    let (near, _) = board_band_hits(1.0);
    assert!(near > 0, "rays ended on the board at 1 m");
}

/// Over the cells a person standing 3 m ahead of a standing lidar covers: whether every height at which a ray
/// met the person was seen again after they left, for a person who leaves at `leave_s` of a 2 s run.
fn seen_again_after_leaving(leave_s: f64) -> Vec<bool> {
    let person = format!(
        "[[actors]]\nkind = \"person\"\nwaypoints = [[0.0, 3.0, 0.0], [{leave_s:?}, 3.0, 0.0], [{:?}, 3.0, 3.9]]\n",
        leave_s + 0.5
    );
    let text = standing(&format!("{LIDAR}{person}")).replace("duration_s = 4.0", "duration_s = 2.0");
    let loaded = common::load_text(&format!("person-{leave_s}"), &text).expect("valid");
    let mut sim = Simulation::new(&loaded).expect("simulation");
    let geometry = GridGeometry::new(0.05).expect("geometry");
    let region = geometry.region_covering((2.6, -0.4), (3.4, 0.4)).expect("region");
    let window = oeg::GridWindow::new(geometry, region);
    // The cells of the person's disk, covered until they leave (and a little longer, as they walk off).
    let covered_until_s: Vec<f64> = region
        .cells()
        .map(|c| {
            let (x, y) = geometry.cell_center(c);
            if (x - 3.0).hypot(y) <= 0.25 {
                leave_s + 0.1
            } else {
                f64::NEG_INFINITY
            }
        })
        .collect();
    let mut o = Observer::new(sim.world(), &window, RobotProfile::default()).tracking_actors(covered_until_s);
    while let Some(scan) = sim.next_scan() {
        o.observe(&scan, 100.0);
    }
    o.finished().seen_again().expect("tracked")
}

#[test]
fn a_person_who_left_is_seen_again_where_the_rings_met_them_and_one_who_stayed_is_not() {
    // Left after half a second: the rings that met the person cross the same cells at the same heights in the
    // scans after, so every height met is seen again.
    let left = seen_again_after_leaving(0.5);
    // Stayed to the end: the heights the rings met are never seen again.
    let stayed = seen_again_after_leaving(1.95);
    let unseen = stayed.iter().filter(|s| !**s).count();
    assert!(unseen > 0, "the rings met the person who stayed");
    assert!(
        left.iter().all(|s| *s),
        "{} cells not seen again",
        left.iter().filter(|s| !**s).count()
    );
}

#[test]
fn a_ray_that_ends_on_a_person_tells_nothing_of_the_cell_under_them() {
    // A person stands 1 m ahead of a standing lidar, where the rings end inside the robot's height band: on the
    // person, not on any structure. No cell's band was hit, and the ray is marked as the person's.
    let person = "[[actors]]\nkind = \"person\"\nwaypoints = [[0.0, 1.0, 0.0], [10.0, 1.0, 0.0]]\n";
    let text = standing(&format!("{LIDAR}{person}"));
    let loaded = common::load_text("person-band", &text).expect("valid");
    let mut sim = Simulation::new(&loaded).expect("simulation");
    let geometry = GridGeometry::new(0.05).expect("geometry");
    let region = geometry.region_covering((0.6, -0.4), (1.4, 0.4)).expect("region");
    let window = oeg::GridWindow::new(geometry, region);
    let mut o = Observer::new(sim.world(), &window, RobotProfile::default());
    // Rays that truly ended on the person inside the band: 3.5 cm to 0.46 m over the ground.
    let mut on_person_in_band = 0;
    while let Some(scan) = sim.next_scan() {
        if scan.stamp_s > 1.0 {
            break;
        }
        let (origin, rotation) = (
            scan.world_from_sensor.translation.vector,
            scan.world_from_sensor.rotation,
        );
        on_person_in_band += scan
            .rays
            .iter()
            .filter(|r| r.true_hit_actor)
            .map(|r| {
                origin.z
                    + (rotation * r.vector_in_sensor.cast::<f64>().normalize()).z * f64::from(r.true_range_m)
            })
            .filter(|z| (0.035..=0.46).contains(z))
            .count();
        o.observe(&scan, 100.0);
    }
    assert!(
        on_person_in_band > 100,
        "the rings met the person in the band: {on_person_in_band} rays"
    );
    let o = o.finished();
    assert!(
        o.band_hit.iter().all(|h| !h),
        "{} cells hit in their band",
        o.band_hit.iter().filter(|h| **h).count()
    );
}
