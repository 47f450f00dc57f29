//! The robot model's tests: the shipped Pioneer 3-AT's height, mounts, footprint, wheels and body.

use super::*;

fn pioneer() -> RobotModel {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/robots/pioneer3at.urdf");
    RobotModel::load(&path, "base_link").expect("the shipped URDF loads")
}

#[test]
fn the_pioneer_is_0_46_m_tall_with_its_mounts_where_the_file_says() {
    let robot = pioneer();
    assert!((robot.height_m() - 0.46).abs() < 1e-9, "{}", robot.height_m());
    let left = robot.base_from_link("laser_left_mount").expect("mount");
    assert!(
        (left.translation.vector - Vector3::new(0.08, 0.1, 0.42)).norm() < 1e-9,
        "{left}"
    );
    let front = robot.base_from_link("laser_front_mount").expect("mount");
    assert!(
        (front.translation.vector - Vector3::new(0.2, 0.0, 0.30)).norm() < 1e-9,
        "{front}"
    );
    let stereo = robot.base_from_link("stereo_mount").expect("mount");
    assert!((stereo.translation.z - 0.452).abs() < 1e-9);
}

#[test]
fn the_pioneers_body_fills_8_cm_to_0_46_m_over_its_wheels_contacts() {
    let body = pioneer().body_span().expect("wheels and a body");
    assert!((body.underside_m - 0.08).abs() < 1e-6, "{body:?}");
    assert!((body.height_m - 0.46).abs() < 1e-6, "{body:?}");
}

#[test]
fn the_footprint_bounds_the_body_and_the_wheels() {
    let f = pioneer().footprint();
    // The body is 0.51 m long; the wheels (radius 0.111 m at x = +-0.135 m, 0.075 m wide at y = +-0.197 m)
    // stand out to y = +-0.2345 m: the datasheet's 0.508 x 0.497 m, within a centimetre.
    assert!(
        (f.max_x_m - 0.255).abs() < 1e-9 && (f.min_x_m + 0.255).abs() < 1e-9,
        "{f:?}"
    );
    assert!(
        (f.max_y_m - 0.2345).abs() < 1e-6 && (f.min_y_m + 0.2345).abs() < 1e-6,
        "{f:?}"
    );
    let wheels = pioneer().wheel_contacts();
    assert!(
        wheels
            .iter()
            .all(|c| c.x < f.max_x_m && c.x > f.min_x_m && c.y.abs() < f.max_y_m)
    );
}

#[test]
fn the_wheels_touch_the_ground_at_the_published_positions() {
    let c = pioneer().wheel_contacts();
    assert_eq!(c.len(), 4);
    assert!((c[0] - Point3::new(0.135, 0.197, 0.0)).norm() < 1e-9, "{}", c[0]);
    assert!(
        (c[3] - Point3::new(-0.134, -0.197, 0.0)).norm() < 1e-9,
        "{}",
        c[3]
    );
}

#[test]
fn broken_descriptions_are_clear_errors() {
    let dir = std::env::temp_dir().join(format!("sim-urdf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let missing = RobotModel::load(&dir.join("nope.urdf"), "base_link").expect_err("missing");
    assert!(
        matches!(missing, SimError::Io { .. }) && missing.to_string().contains("nope.urdf"),
        "{missing}"
    );

    let broken = dir.join("broken.urdf");
    std::fs::write(&broken, "<robot name=\"r\"><link name=\"base_link\">").expect("write");
    let e = RobotModel::load(&broken, "base_link").expect_err("broken xml");
    assert!(
        e.to_string().contains("broken.urdf") && e.to_string().contains("not a valid URDF"),
        "{e}"
    );

    let no_base = dir.join("nobase.urdf");
    std::fs::write(&no_base, "<robot name=\"r\"><link name=\"body\"/></robot>").expect("write");
    let e = RobotModel::load(&no_base, "base_link").expect_err("no base");
    assert!(
        e.to_string().contains("no link named `base_link`") && e.to_string().contains("body"),
        "{e}"
    );

    let mesh = dir.join("mesh.urdf");
    std::fs::write(
        &mesh,
        "<robot name=\"r\"><link name=\"base_link\"><collision><geometry><mesh filename=\"a.stl\"/></geometry></collision></link></robot>",
    )
    .expect("write");
    let e = RobotModel::load(&mesh, "base_link").expect_err("mesh");
    assert!(e.to_string().contains("mesh collision"), "{e}");

    let loose = dir.join("loose.urdf");
    std::fs::write(
        &loose,
        "<robot name=\"r\"><link name=\"base_link\"/><link name=\"floating\"/></robot>",
    )
    .expect("write");
    let e = RobotModel::load(&loose, "base_link").expect_err("not connected");
    assert!(e.to_string().contains("`floating` is not connected"), "{e}");
}
