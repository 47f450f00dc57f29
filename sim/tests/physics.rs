//! The robot on its wheels: it follows its path, climbs what its wheels can climb, stalls against what they
//! cannot, stops against a board it does not fit under, and does all of it the same way every time.

#![allow(
    clippy::disallowed_methods,
    reason = "tests and tools write their inputs directly"
)]

mod common;

use sim::physics::{PhysicsEvent, PhysicsEventKind};
use sim::world::World;

/// A physics drive over flat ground from (0, 0) through `waypoints` at 0.5 m/s, with `extra` TOML.
fn scenario(waypoints: &str, extra: &str) -> String {
    common::scenario_driving(
        20.0,
        &format!("mode = \"physics\"\nwaypoints_xy_m = {waypoints}\nspeed_m_s = 0.5"),
        extra,
    )
}

/// Runs the drive for `seconds` and returns the world at the end.
fn drive(name: &str, text: &str, seconds: f64) -> World {
    let loaded = common::load_text(name, text).expect("valid scenario");
    let mut w = World::new(&loaded).expect("world");
    let mut t = 0.0;
    while t < seconds {
        t += 0.1;
        w.advance_to(t);
    }
    w
}

fn events(w: &World) -> Vec<PhysicsEvent> {
    w.physics_events().expect("a physics drive").to_vec()
}

fn reached(w: &World) -> bool {
    events(w).iter().any(|e| e.kind == PhysicsEventKind::GoalReached)
}

fn stalled(w: &World) -> bool {
    events(w)
        .iter()
        .any(|e| matches!(e.kind, PhysicsEventKind::Stall { .. }))
}

fn contacts(w: &World) -> Vec<String> {
    events(w)
        .into_iter()
        .filter_map(|e| match e.kind {
            PhysicsEventKind::Contact { with, .. } if with != "ground" => Some(with),
            _ => None,
        })
        .collect()
}

/// The largest distance of the base from the scripted path over the drive, metres.
fn worst_path_error(w: &World) -> f64 {
    w.physics_samples()
        .expect("samples")
        .iter()
        .filter_map(|s| s.path_error_m)
        .fold(0.0, f64::max)
}

/// A curb across the path: a box from x = 2.5 to 3.5 m, `height_m` high.
fn curb(height_m: f64) -> String {
    format!(
        "[[obstacles]]\nkind = \"box\"\nname = \"curb\"\ncenter_xy_m = [3.0, 0.0]\nsize_m = [1.0, 3.0, {height_m}]\n"
    )
}

/// A board across the path whose underside is `clearance_m` above the ground.
fn board(clearance_m: f64) -> String {
    format!(
        "[[obstacles]]\nkind = \"overhang\"\nname = \"board\"\ncenter_xy_m = [3.0, 0.0]\nsize_m = [0.3, 3.0, 0.05]\nclearance_m = {clearance_m}\n"
    )
}

#[test]
fn on_flat_ground_it_follows_a_straight_line_and_a_turn() {
    let w = drive("straight", &scenario("[[0.0, 0.0], [5.0, 0.0]]", ""), 14.0);
    assert!(reached(&w), "{:?}", events(&w));
    let p = w.planar_pose();
    assert!((p.x_m - 5.0).hypot(p.y_m) < 0.15, "ends at {p:?}");
    // Tolerance: 2 cm off a straight line.
    assert!(
        worst_path_error(&w) < 0.02,
        "{} m off the line",
        worst_path_error(&w)
    );
    assert!(!stalled(&w) && contacts(&w).is_empty(), "{:?}", events(&w));

    let w = drive(
        "turn",
        &scenario("[[0.0, 0.0], [3.0, 0.0], [3.0, 2.5]]", ""),
        18.0,
    );
    assert!(reached(&w), "{:?}", events(&w));
    // Tolerance: 15 cm off a path with a right-angle corner. The robot stops at the corner and turns on the
    // spot at up to its top turn rate, and a skid-steer robot's centre slides while it turns so (10.7 cm
    // measured at the default settings).
    assert!(
        worst_path_error(&w) < 0.15,
        "{} m off the path",
        worst_path_error(&w)
    );
}

#[test]
fn it_climbs_a_2_cm_curb_and_stalls_at_an_8_cm_one() {
    let path = "[[0.0, 0.0], [5.0, 0.0]]";
    let low = drive("curb2", &scenario(path, &curb(0.02)), 16.0);
    assert!(reached(&low) && !stalled(&low), "{:?}", events(&low));

    let high = drive("curb8", &scenario(path, &curb(0.08)), 16.0);
    assert!(stalled(&high), "{:?}", events(&high));
    assert!(!reached(&high));
    let p = high.planar_pose();
    // Stopped with its front wheels against the curb's face (x = 2.5 m): the front axle is 0.135 m ahead
    // of the base, the wheel's radius 0.111 m.
    assert!(p.x_m < 2.5 - 0.135 && p.x_m > 2.0, "stopped at {p:?}");
}

#[test]
fn it_stops_against_a_board_at_0_40_m_and_passes_under_one_at_0_52_m() {
    let path = "[[0.0, 0.0], [5.0, 0.0]]";
    let low = drive("board40", &scenario(path, &board(0.40)), 16.0);
    assert!(
        contacts(&low).contains(&"board".to_string()),
        "{:?}",
        events(&low)
    );
    assert!(!reached(&low));

    let high = drive("board52", &scenario(path, &board(0.52)), 16.0);
    assert!(contacts(&high).is_empty(), "{:?}", events(&high));
    assert!(reached(&high), "{:?}", events(&high));
}

#[test]
fn a_physics_drive_is_the_same_on_one_and_two_threads_and_over_two_runs() {
    let text = scenario("[[0.0, 0.0], [3.0, 0.0], [3.0, 2.0]]", &curb(0.03));
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| {
            let w = drive(&format!("same{threads}"), &text, 8.0);
            format!("{:?}{:?}", w.physics_samples(), w.physics_events())
        })
    };
    let one = run(1);
    assert_eq!(one, run(2));
    assert_eq!(one, run(1));
}

#[test]
fn a_urdf_the_drive_cannot_use_is_an_error_that_names_the_file_and_the_element() {
    let urdf = std::fs::read_to_string(common::urdf_path()).expect("urdf");
    // The shipped robot with `from` replaced by `to` in its URDF, written as `name.urdf`: the load's error.
    let error_with = |name: &str, from: &str, to: &str| {
        let path = common::temp_dir("bad-urdf").join(format!("{name}.urdf"));
        std::fs::write(&path, urdf.replace(from, to)).expect("write");
        let text = scenario("[[0.0, 0.0], [5.0, 0.0]]", "").replace(
            &common::urdf_path().display().to_string(),
            &path.display().to_string(),
        );
        common::load_text(name, &text).expect_err(name).to_string()
    };
    // The wheels without their masses.
    let e = error_with("massless", "<mass value=\"0.6\"/>", "<mass value=\"0\"/>");
    assert!(
        e.contains("massless.urdf") && e.contains("wheel_front_left") && e.contains("mass"),
        "{e}"
    );
    // A body of negative mass.
    let e = error_with("negative", "<mass value=\"10.5\"/>", "<mass value=\"-10.5\"/>");
    assert!(
        e.contains("negative.urdf") && e.contains("chassis") && e.contains("-10.5"),
        "{e}"
    );

    // A wheel joint that does not turn.
    let text = scenario(
        "[[0.0, 0.0], [5.0, 0.0]]",
        "[robot.physics]\nwheel_joints = [\"base_to_chassis\", \"front_left_wheel_joint\"]\n",
    );
    let e = common::load_text("fixed", &text)
        .expect_err("a fixed wheel")
        .to_string();
    assert!(e.contains("base_to_chassis") && e.contains("continuous"), "{e}");

    // Wheels on one side only.
    let text = scenario(
        "[[0.0, 0.0], [5.0, 0.0]]",
        "[robot.physics]\nwheel_joints = [\"front_left_wheel_joint\", \"rear_left_wheel_joint\"]\n",
    );
    let e = common::load_text("one-side", &text)
        .expect_err("one side")
        .to_string();
    assert!(e.contains("both sides"), "{e}");
}

#[test]
fn absurd_physics_settings_are_refused_at_their_place() {
    for (key, value, expected) in [
        ("wheel_friction", "-1.0", "friction coefficient"),
        ("wheel_friction", "nan", "friction coefficient"),
        ("wheel_torque_nm", "1e9", "torque"),
        ("time_step_s", "1.0", "time step"),
        ("time_step_s", "0.0", "time step"),
        ("solver_iterations", "0", "solver iterations"),
    ] {
        let text = scenario(
            "[[0.0, 0.0], [5.0, 0.0]]",
            &format!("[robot.physics]\n{key} = {value}\n"),
        );
        let e = common::load_text("absurd", &text).expect_err(key).to_string();
        assert!(
            e.contains(&format!("robot.physics.{key}")) && e.contains(expected),
            "{key} = {value}: {e}"
        );
    }
}

#[test]
fn the_default_torque_is_the_larger_of_the_grade_and_the_turn_on_the_spot() {
    let loaded = common::load_text("torque", &scenario("[[0.0, 0.0], [5.0, 0.0]]", "")).expect("valid");
    let model = loaded.wheeled.expect("a physics drive");
    // docs/physics.md: 12.9 kg on four 0.111 m wheels; the turn on the spot against friction 0.8 takes
    // 3.40 N m a wheel, times 1.5; the 35 % grade, 1.16 N m.
    assert!((model.mass_kg() - 12.9).abs() < 1e-9);
    assert!(
        (model.wheel_torque_nm() - 5.10).abs() < 0.01,
        "{}",
        model.wheel_torque_nm()
    );
    let (roll, pitch) = model.tip_limits_deg();
    assert!(
        roll > 45.0 && roll < 55.0 && pitch > 30.0 && pitch < 45.0,
        "{roll} {pitch}"
    );
    // A URDF `effort` limit, or the scenario's key, replaces the derived torque.
    let text = scenario(
        "[[0.0, 0.0], [5.0, 0.0]]",
        "[robot.physics]\nwheel_torque_nm = 2.5\n",
    );
    let model = common::load_text("torque-set", &text)
        .expect("valid")
        .wheeled
        .expect("physics");
    assert_eq!(model.wheel_torque_nm(), 2.5);
}

#[test]
fn a_person_who_walks_into_the_standing_robot_pushes_it_at_a_walking_pace() {
    // The robot stands at the origin; a person walks across it at 1 m/s from y = -2 to y = 2. Before the
    // person enters the scene (t = 1 s), nothing stands where the robot settles.
    let text = scenario(
        "[[0.0, 0.0]]",
        "[[actors]]\nkind = \"person\"\nname = \"walker\"\nwaypoints = [[1.0, 0.0, -2.0], [5.0, 0.0, 2.0]]\n",
    );
    let w = drive("person", &text, 6.0);
    let samples = w.physics_samples().expect("a physics drive");
    let at = |t: f64| {
        samples
            .iter()
            .find(|s| s.time_s >= t)
            .map(|s| (s.x_m, s.y_m))
            .expect("sampled")
    };
    let (x0, y0) = at(0.9);
    assert!(x0.hypot(y0) < 0.01, "the robot settled at ({x0}, {y0})");
    // The person moves to where it is at the end of every physics step, with the velocity that takes it
    // there: it pushes the robot along its way at its own pace, never throws it.
    let (_, y_end) = at(5.0);
    assert!(y_end > 1.0, "pushed to y = {y_end}");
    let fastest = samples
        .windows(2)
        .map(|p| (p[1].x_m - p[0].x_m).hypot(p[1].y_m - p[0].y_m) / (p[1].time_s - p[0].time_s))
        .fold(0.0, f64::max);
    assert!(
        fastest < 1.5,
        "pushed at up to {fastest} m/s by a person walking at 1 m/s"
    );
    assert!(
        !events(&w)
            .iter()
            .any(|e| matches!(e.kind, PhysicsEventKind::TipOver { .. })),
        "{:?}",
        events(&w)
    );
}
