//! The Rapier world against analytic answers.

#![allow(
    clippy::disallowed_methods,
    reason = "tests and tools write their inputs directly"
)]

mod common;

use nalgebra::{Point3, Vector3};
use sim::world::{Actors, HitKind, RayStart, World};

fn world(name: &str, extra: &str) -> World {
    let loaded = common::load_text(name, &common::scenario_text(extra)).expect("valid scenario");
    World::new(&loaded).expect("world")
}

fn cast(w: &World, from: [f64; 3], dir: [f64; 3]) -> Option<sim::RayHit> {
    w.cast_ray(
        &Point3::from(from),
        &Vector3::from(dir),
        50.0,
        Actors::Included,
        RayStart::InsideExits,
    )
}

#[test]
fn a_ray_hits_a_yawed_box_where_geometry_says() {
    // A 1 x 2 x 0.5 box at (5, 0) turned 90 degrees: its faces normal to x are 1 m apart (width 2 along x).
    let w = world(
        "box",
        "[[obstacles]]\nkind = \"box\"\ncenter_xy_m = [5.0, 0.0]\nsize_m = [1.0, 2.0, 0.5]\nyaw_deg = 90.0\n",
    );
    let hit = cast(&w, [0.0, 0.0, 0.2], [1.0, 0.0, 0.0]).expect("hit");
    assert!((hit.distance_m - 4.0).abs() < 1e-4, "{hit:?}");
    assert_eq!(hit.kind, HitKind::Obstacle { index: 0 });
    // Over the box (0.5 m high) the ray reaches the ground beyond.
    let over = cast(&w, [0.0, 0.0, 1.0], [1.0, 0.0, -0.08]).expect("hit");
    assert_eq!(over.kind, HitKind::Terrain);
    // Straight down onto its top.
    let top = cast(&w, [5.9, 0.4, 2.0], [0.0, 0.0, -1.0]).expect("hit");
    assert!((top.point_in_world.z - 0.5).abs() < 1e-4, "{top:?}");
}

#[test]
fn a_ray_hits_a_cylinder_at_its_radius() {
    let w = world(
        "cyl",
        "[[obstacles]]\nkind = \"cylinder\"\ncenter_xy_m = [3.0, 1.0]\nradius_m = 0.1\nheight_m = 2.0\n",
    );
    let hit = cast(&w, [0.0, 1.0, 1.0], [1.0, 0.0, 0.0]).expect("hit");
    assert!((hit.distance_m - 2.9).abs() < 1e-4, "{hit:?}");
    // Above its top: nothing but the ground far away.
    assert!(cast(&w, [0.0, 1.0, 2.5], [1.0, 0.0, 0.0]).is_none());
}

#[test]
fn a_slope_is_where_its_equation_says() {
    let w = world(
        "slope",
        "[terrain]\nkind = \"slope\"\nheight_m = 0.2\nslope_x = 0.1\n",
    );
    for (x, y) in [(0.0, 0.0), (5.0, 2.0), (-1.5, -3.0)] {
        let g = w.ground_z(x, y).expect("on the terrain");
        assert!((g - (0.2 + 0.1 * x)).abs() < 1e-4, "({x}, {y}): {g}");
    }
    // The robot on the slope pitches nose up: pitch is negative about +y.
    let (_, pitch, _) = w.world_from_base().rotation.euler_angles();
    assert!((pitch + 0.1f64.atan()).abs() < 1e-3, "{pitch}");
}

#[test]
fn issue_heightfield_orientation_follows_the_image() {
    // A 3 x 2 image: top row (max y) 0, 128, 255; bottom row (min y) 255, 255, 0, with 1 m pixels from (0, 0).
    let dir = common::temp_dir("image_png");
    let png_path = dir.join("terrain.png");
    {
        let file = std::fs::File::create(&png_path).expect("create");
        let mut enc = png::Encoder::new(file, 3, 2);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().expect("header");
        w.write_image_data(&[0, 128, 255, 255, 255, 0]).expect("data");
    }
    let extra = format!(
        "[terrain]\nkind = \"image\"\npath = \"{}\"\nheight_scale_m = 1.0\ncell_m = 1.0\norigin_xy_m = [0.0, 0.0]\n",
        png_path.display()
    );
    let loaded = common::load_text("image", &common::scenario_text(&extra)).expect("valid");
    let w = World::new(&loaded).expect("world");
    // Grid points: (x, y) = (0, 1) -> 0, (1, 1) -> 0.502, (2, 1) -> 1, (0, 0) -> 1, (1, 0) -> 1, (2, 0) -> 0.
    for (x, y, z) in [
        (0.0, 1.0, 0.0),
        (1.0, 1.0, 128.0 / 255.0),
        (2.0, 1.0, 1.0),
        (0.0, 0.0, 1.0),
        (2.0, 0.0, 0.0),
    ] {
        let g = w
            .ground_z(
                x + if x > 1.0 { -1e-4 } else { 1e-4 },
                y + if y > 0.5 { -1e-4 } else { 1e-4 },
            )
            .expect("on it");
        assert!((g - z).abs() < 2e-3, "({x}, {y}): expected {z}, got {g}");
    }
}

#[test]
fn an_overhang_floats_at_its_clearance() {
    let w = world(
        "overhang",
        "[[obstacles]]\nkind = \"overhang\"\ncenter_xy_m = [3.0, 0.0]\nsize_m = [0.4, 2.0, 0.05]\nclearance_m = 0.6\n",
    );
    let under = cast(&w, [3.0, 0.0, 0.01], [0.0, 0.0, 1.0]).expect("hit");
    assert!((under.distance_m - 0.59).abs() < 1e-4, "{under:?}");
    let down = cast(&w, [3.0, 0.0, 2.0], [0.0, 0.0, -1.0]).expect("hit");
    assert!((down.point_in_world.z - 0.65).abs() < 1e-4, "{down:?}");
    // A low horizontal ray passes under it.
    let low = cast(&w, [0.0, 0.0, 0.3], [1.0, 0.0, 0.0]);
    assert!(low.is_none(), "{low:?}");
}

#[test]
fn a_sensor_inside_the_robot_still_sees_the_wall_ahead() {
    let w = world(
        "inside",
        "[[obstacles]]\nkind = \"box\"\ncenter_xy_m = [3.0, 0.0]\nsize_m = [0.2, 4.0, 1.0]\n",
    );
    // From the chassis centre, inside the robot's own collider.
    let from = w.world_from_link("chassis").expect("link").translation.vector;
    let hit = cast(&w, [from.x, from.y, from.z], [1.0, 0.0, 0.0]).expect("the wall");
    assert_eq!(hit.kind, HitKind::Obstacle { index: 0 });
    assert!((hit.distance_m - 2.9).abs() < 1e-3, "{hit:?}");
    // The robot's colliders are really there: they follow the base.
    assert!(!w.robot_collider_poses().is_empty());
}

#[test]
fn people_enter_and_leave() {
    let mut w = world(
        "person",
        "[[actors]]\nkind = \"person\"\nwaypoints = [[1.0, 3.0, -2.0], [3.0, 3.0, 2.0]]\n",
    );
    let probe = |w: &World, actors| {
        w.cast_ray(
            &Point3::new(0.0, 0.0, 1.0),
            &Vector3::x(),
            10.0,
            actors,
            RayStart::InsideExits,
        )
    };
    assert!(probe(&w, Actors::Included).is_none(), "not there yet at t = 0");
    w.advance_to(2.0);
    assert_eq!(w.actor_positions(), vec![Some((3.0, 0.0))]);
    let hit = probe(&w, Actors::Included).expect("the person");
    assert_eq!(hit.kind, HitKind::Actor { index: 0 });
    assert!((hit.distance_m - 2.75).abs() < 1e-3, "{hit:?}");
    assert!(probe(&w, Actors::Excluded).is_none(), "excluded for the truth");
    w.advance_to(3.5);
    assert_eq!(w.actor_positions(), vec![None]);
    assert!(probe(&w, Actors::Included).is_none(), "gone");
}

#[test]
fn the_robot_follows_its_drive() {
    let mut w = world("drive", "");
    w.advance_to(2.5);
    let p = w.world_from_base().translation.vector;
    assert!(
        (p.x - 2.5).abs() < 1e-9 && p.y.abs() < 1e-9 && p.z.abs() < 1e-4,
        "{p}"
    );
    // Perfect odometry by default.
    assert_eq!(w.estimated_world_from_base(), w.world_from_base());
    let mast = w
        .world_from_link("laser_left_mount")
        .expect("mount")
        .translation
        .vector;
    assert!((mast - Vector3::new(2.58, 0.1, 0.42)).norm() < 1e-4, "{mast}");
}

#[test]
fn the_same_seed_gives_the_same_world_and_drift() {
    let extra = "[robot.odometry]\nxy_sigma_m_per_sqrt_m = 0.05\nyaw_sigma_deg_per_sqrt_m = 1.0\n\n[terrain]\nkind = \"noise\"\namplitude_m = 0.05\nwavelength_m = 2.0\n\n[[obstacles]]\nkind = \"bush\"\ncenter_xy_m = [5.0, 1.0]\nradius_m = 0.6\nheight_m = 0.8\n";
    let run = || {
        let mut w = world("seeded", extra);
        w.advance_to(3.0);
        let hits: Vec<_> = (0..50)
            .map(|k| {
                cast(&w, [0.0, -1.0 + 0.05 * f64::from(k), 0.5], [1.0, 0.0, -0.02]).map(|h| h.distance_m)
            })
            .collect();
        (w.estimated_world_from_base(), hits)
    };
    let (a, b) = (run(), run());
    assert_eq!(a, b);
    assert_ne!(a.0, {
        let w = world("seeded", extra);
        w.estimated_world_from_base()
    });
}
