//! False doubts on flat, empty ground (issue: "a map a robot can drive on"): under the recommended preset, the
//! uncertain cells that are not `imprecise`, the over-cautious and the unsafe cells, as a fraction of the scored
//! cells, for each kind of sensor, standing and moving. `imprecise` doubts are the sensors' resolution (a
//! stereo camera at a few metres cannot tell a 3.5 cm step) and are reported, not bounded.

#![allow(clippy::disallowed_methods, reason = "tests write their inputs directly")]

mod common;

use common::{oeg, root, s, temp_dir};

/// Each kind of sensor, on the Pioneer's mounts as the shipped scenarios place it.
const SENSORS: [(&str, &str); 4] = [
    (
        "laser2d",
        "[[sensors]]\nname = \"laser_left\"\nkind = \"laser2d\"\nmount_link = \"laser_left_mount\"\n\
         rpy_deg = [0.0, 25.0, 15.0]\n\n[[sensors]]\nname = \"laser_right\"\nkind = \"laser2d\"\n\
         mount_link = \"laser_right_mount\"\nrpy_deg = [0.0, 25.0, -15.0]\n",
    ),
    (
        "lidar3d",
        "[[sensors]]\nname = \"lidar\"\nkind = \"lidar3d\"\nmount_link = \"stereo_mount\"\npreset = \"vlp16\"\n",
    ),
    (
        "stereo",
        "[[sensors]]\nname = \"stereo\"\nkind = \"stereo\"\nmount_link = \"stereo_mount\"\n\
         rpy_deg = [0.0, 15.0, 0.0]\n",
    ),
    (
        "depth_camera",
        "[[sensors]]\nname = \"depth\"\nkind = \"depth_camera\"\nmount_link = \"stereo_mount\"\n\
         rpy_deg = [0.0, 15.0, 0.0]\n",
    ),
];

/// The largest fraction of false doubts, over-cautious and unsafe cells: the target, 0.5 %, but for a
/// standing 3D lidar. Its end points are binned by where they land, and a cell on a ring's inner edge holds only
/// the short readings, which end above the ground (a range error `e` moves a beam `e * dir_z` up): about one
/// standard deviation of bias, and 2.5 % of the cells uncertain. That one is a regression bound, not the target;
/// moving, the rings sweep over every cell and it is 0.04 %.
fn bound(kind: &str, moving: bool) -> f64 {
    match (kind, moving) {
        ("lidar3d", false) => 0.03,
        _ => 0.005,
    }
}

#[test]
fn flat_empty_ground_has_few_false_doubts_for_every_sensor_standing_or_moving() {
    let template = std::fs::read_to_string(root().join("tests/scenes/flat_ground.toml")).expect("scene");
    let (head, _) = template.split_once("# Sensors").expect("the sensors marker");
    let urdf = root().join("scenarios/robots/pioneer3at.urdf");
    let dir = temp_dir("flat_ground", "scenes");
    let mut report = Vec::new();
    for (kind, sensors) in SENSORS {
        for moving in [false, true] {
            let mut scene = head
                .replace("../../scenarios/robots/pioneer3at.urdf", s(&urdf))
                .replace("name = \"flat_ground\"", &format!("name = \"flat_{kind}\""));
            if moving {
                scene = scene
                    .replace("duration_s = 4.0", "duration_s = 12.0")
                    .replace("[[0.0, 0.0]]", "[[0.0, 0.0], [4.0, 0.0]]");
            }
            scene.push_str(sensors);
            let name = format!("{kind}-{}", if moving { "moving" } else { "standing" });
            let file = dir.join(format!("{name}.toml"));
            std::fs::write(&file, scene).expect("scene written");
            let out = dir.join(&name);
            let o = oeg(&["run", s(&file), "--out", s(&out), "--set", "map.preset=robust"]);
            assert!(
                o.status.success(),
                "{name}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
            let m: serde_json::Value =
                serde_json::from_slice(&std::fs::read(out.join("metrics.json")).expect("metrics"))
                    .expect("json");
            let n = |key: &str| m[key].as_u64().unwrap_or_else(|| panic!("{name}: {key}"));
            let scored = n("num_scored_cells");
            let false_doubts = n("uncertain_cells") - n("doubt_imprecise_cells");
            let wrong = false_doubts + n("overcautious_cells") + n("unsafe_cells");
            let rate = wrong as f64 / scored as f64;
            report.push(format!(
                "{name}: {wrong} of {scored} ({:.2} %; imprecise {})",
                100.0 * rate,
                n("doubt_imprecise_cells")
            ));
            assert!(scored > 1000, "{name}: {scored} scored cells");
            assert!(rate <= bound(kind, moving), "{}", report.join("\n"));
        }
    }
    println!("{}", report.join("\n"));
}
