//! Simulated sensors: geometry, noise statistics, determinism.

#![allow(
    clippy::disallowed_methods,
    reason = "tests and tools write their inputs directly"
)]

mod common;

use nalgebra::Vector3;
use oeg::RayKind;
use sim::Simulation;
use sim::scenario::sensors::BeamPattern;
use sim::sensors::{PoseSource, SensorScan, beam_directions};

/// A scenario with one sensor entry (`sensor` is the body of a `[[sensors]]` table) facing a wall 5 m ahead
/// (the robot at the origin looking along +x).
fn scan_with(name: &str, sensor: &str, extra: &str) -> (SensorScan, Simulation) {
    let text = common::scenario_text(&format!(
        "[[obstacles]]\nkind = \"box\"\nname = \"wall\"\ncenter_xy_m = [5.1, 0.0]\nsize_m = [0.2, 7.0, 3.0]\n\n[[sensors]]\n{sensor}\n{extra}"
    ))
    .replace("[[0.0, 0.0], [4.0, 0.0]]", "[[0.0, 0.0], [0.5, 0.0]]");
    let loaded = common::load_text(name, &text).expect("valid");
    let mut sim = Simulation::new(&loaded).expect("simulation");
    let scan = sim.next_scan().expect("a scan at t = 0");
    (scan, sim)
}

const LASER: &str = "name = \"laser\"\nkind = \"laser2d\"\nmount_link = \"laser_front_mount\"\nfov_deg = 90.0\nstep_deg = 1.0\n";

#[test]
fn laser_beams_fan_at_the_configured_angles() {
    let dirs = beam_directions(&BeamPattern::Fan {
        fov_rad: 90f64.to_radians(),
        step_rad: 1f64.to_radians(),
    });
    assert_eq!(dirs.len(), 91);
    let angle = |d: &Vector3<f64>| d.y.atan2(d.x).to_degrees();
    assert!((angle(&dirs[0]) + 45.0).abs() < 1e-9);
    assert!((angle(&dirs[45])).abs() < 1e-9);
    assert!((angle(&dirs[90]) - 45.0).abs() < 1e-9);
    assert!(dirs.iter().all(|d| d.z == 0.0 && (d.norm() - 1.0).abs() < 1e-12));
}

#[test]
fn lidar_channels_sit_at_their_elevations() {
    let elevations: Vec<f64> = [-15.0f64, 1.0, 15.0].iter().map(|a| a.to_radians()).collect();
    let dirs = beam_directions(&BeamPattern::Sweep {
        elevations_rad: elevations,
        fov_rad: std::f64::consts::TAU,
        step_rad: 90f64.to_radians(),
    });
    assert_eq!(
        dirs.len(),
        12,
        "4 azimuths x 3 channels, the full circle not repeated"
    );
    assert!((dirs[2].z.asin().to_degrees() - 15.0).abs() < 1e-9);
    assert!(
        (dirs[3].y - (-15f64).to_radians().cos()).abs() < 1e-9,
        "second azimuth is +90 degrees: {}",
        dirs[3]
    );
}

#[test]
fn the_counted_rays_per_scan_are_the_rays_cast() {
    let patterns = [
        BeamPattern::Fan {
            fov_rad: 90f64.to_radians(),
            step_rad: 1f64.to_radians(),
        },
        BeamPattern::Fan {
            fov_rad: std::f64::consts::TAU,
            step_rad: 0.5f64.to_radians(),
        },
        BeamPattern::Sweep {
            elevations_rad: vec![-0.2, 0.0, 0.2],
            fov_rad: std::f64::consts::TAU,
            step_rad: 0.2f64.to_radians(),
        },
        BeamPattern::Sweep {
            elevations_rad: vec![0.1],
            fov_rad: 100f64.to_radians(),
            step_rad: 3f64.to_radians(),
        },
        BeamPattern::Pinhole {
            width_px: 641,
            height_px: 479,
            focal_px: 500.0,
            stride: 4,
        },
    ];
    for p in &patterns {
        assert_eq!(p.rays_per_scan(), beam_directions(p).len() as u64, "{p:?}");
    }
}

#[test]
fn stereo_rays_pass_through_pixel_centres() {
    let (w, h, f) = (4u32, 2u32, 2.0);
    let dirs = beam_directions(&BeamPattern::Pinhole {
        width_px: w,
        height_px: h,
        focal_px: f,
        stride: 1,
    });
    assert_eq!(dirs.len(), 8);
    // Pixel (u, v) = (0, 0): centre (0.5, 0.5), optical (x, y) = ((0.5 - 2) / 2, (0.5 - 1) / 2) = (-0.75, -0.25):
    // left of and above the axis, so +y (left) and +z (up) in the sensor frame.
    let d = dirs[0] / dirs[0].x;
    assert!((d.y - 0.75).abs() < 1e-12 && (d.z - 0.25).abs() < 1e-12, "{d}");
    // Pixel (3, 1): optical (0.75, 0.25).
    let d = dirs[7] / dirs[7].x;
    assert!((d.y + 0.75).abs() < 1e-12 && (d.z + 0.25).abs() < 1e-12, "{d}");
}

#[test]
fn a_noiseless_laser_facing_a_wall_returns_its_distance() {
    let (scan, sim) = scan_with(
        "wall",
        &format!("{LASER}\n[sensors.noise]\nrange_sigma_m = 0.0\n"),
        "",
    );
    let origin = scan.world_from_sensor.translation.vector;
    assert!(
        (origin.x - 0.2).abs() < 1e-9 && (origin.z - 0.3).abs() < 1e-6,
        "{origin}"
    );
    let middle = scan.rays[45];
    assert_eq!(middle.kind, RayKind::Hit);
    assert!(
        (f64::from(middle.vector_in_sensor.x) - 4.8).abs() < 1e-4,
        "{:?}",
        middle
    );
    // A beam at angle a reaches the wall plane at 4.8 / cos(a).
    let beam = scan.rays[15];
    let a = (-30f64).to_radians();
    assert!(
        (f64::from(beam.vector_in_sensor.norm()) - 4.8 / a.cos()).abs() < 1e-3,
        "{beam:?}"
    );
    assert_eq!(sim.sensors()[0].directions().len(), 91);
}

/// Range errors of the beams within 30 degrees of the axis (those that see the wall), over 30 scans.
fn range_errors(noise: &str, seed_name: &str) -> (Vec<f64>, Vec<f32>, usize) {
    let (_, mut sim) = scan_with(
        seed_name,
        &format!("{LASER}\nrate_hz = 10.0\n[sensors.noise]\n{noise}"),
        "",
    );
    let (mut errors, mut sigmas, mut no_returns) = (Vec::new(), Vec::new(), 0);
    for _ in 0..30 {
        let Some(scan) = sim.next_scan() else { break };
        // The wall's face is at x = 5.0; the robot drives towards it.
        let to_wall = 5.0 - scan.world_from_sensor.translation.x;
        for (k, r) in scan.rays.iter().enumerate().take(76).skip(15) {
            let a = (-45.0 + k as f64).to_radians();
            let truth = to_wall / a.cos();
            match r.kind {
                RayKind::Hit => {
                    errors.push(f64::from(r.vector_in_sensor.norm()) - truth);
                    sigmas.push(r.range_sigma_m);
                }
                RayKind::NoReturn => no_returns += 1,
            }
        }
    }
    (errors, sigmas, no_returns)
}

fn mean_std(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    (
        mean,
        (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt(),
    )
}

#[test]
fn gaussian_range_noise_has_the_configured_spread_and_the_rays_say_so() {
    let (errors, sigmas, _) = range_errors("range_sigma_m = 0.02\n", "gauss");
    assert!(errors.len() > 1500, "{}", errors.len());
    let (mean, std) = mean_std(&errors);
    assert!(mean.abs() < 0.002, "mean {mean}");
    assert!((std - 0.02).abs() < 0.001, "std {std}");
    assert!(
        sigmas.iter().all(|s| (s - 0.02).abs() < 1e-6),
        "each ray carries the model's error"
    );
}

#[test]
fn a_bias_is_drawn_once_per_sensor() {
    let (errors, _, _) = range_errors("range_sigma_m = 0.0\nbias_sigma_m = 0.05\n", "bias");
    let first = errors[0];
    assert!(first.abs() > 1e-4, "a bias was drawn: {first}");
    assert!(
        errors.iter().all(|e| (e - first).abs() < 1e-3),
        "the same bias on every beam"
    );
}

#[test]
fn dropouts_are_no_returns_at_the_configured_rate() {
    let (errors, _, no_returns) = range_errors("range_sigma_m = 0.0\ndropout_probability = 0.2\n", "dropout");
    let rate = no_returns as f64 / (no_returns + errors.len()) as f64;
    assert!((rate - 0.2).abs() < 0.02, "dropout rate {rate}");
    assert!(
        errors.iter().all(|e| e.abs() < 1e-3),
        "a dropout is never a hit at some range"
    );
}

#[test]
fn spurious_returns_land_before_the_true_surface_at_the_configured_rate() {
    let (errors, _, _) = range_errors("range_sigma_m = 0.0\nspurious_probability = 0.1\n", "spurious");
    let spurious = errors.iter().filter(|e| **e < -1e-3).count();
    let rate = spurious as f64 / errors.len() as f64;
    assert!((rate - 0.1).abs() < 0.015, "spurious rate {rate}");
    assert!(errors.iter().all(|e| *e < 1e-3), "never behind the wall");
}

#[test]
fn stereo_depth_error_grows_with_the_square_of_depth() {
    // A wall in front of a noisy stereo camera looking straight ahead; only pixels at most 5 degrees below the
    // axis, which see the wall, not the floor.
    let stats = |x: f64, name: &str| {
        let sensor = "name = \"cam\"\nkind = \"stereo\"\nmount_link = \"stereo_mount\"\npreset = \"paper_stereo\"\nrate_hz = 10.0\n[sensors.noise]\nhole_probability = 0.0\n";
        let text = common::scenario_text(&format!(
            "[[obstacles]]\nkind = \"box\"\ncenter_xy_m = [{x}, 0.0]\nsize_m = [0.2, 7.0, 3.0]\n\n[[sensors]]\n{sensor}"
        ))
        // The robot stands still.
        .replace("[[0.0, 0.0], [4.0, 0.0]]", "[[0.0, 0.0]]");
        let loaded = common::load_text(name, &text).expect("valid");
        let mut sim = Simulation::new(&loaded).expect("simulation");
        let directions = sim.sensors()[0].directions().to_vec();
        let (mut errors, mut depth) = (Vec::new(), 0.0);
        for _ in 0..5 {
            let scan = sim.next_scan().expect("scan");
            depth = x - 0.1 - scan.world_from_sensor.translation.x;
            for (r, d) in scan.rays.iter().zip(&directions) {
                if r.kind == RayKind::Hit && d.z / d.x > -(5f64.to_radians().tan()) {
                    // Depth is the sensor-frame x (the optical axis).
                    errors.push(f64::from(r.vector_in_sensor.x) - depth);
                }
            }
        }
        (mean_std(&errors).1, errors.len(), depth)
    };
    let (s2, n2, z2) = stats(2.321, "stereo2");
    let (s4, n4, z4) = stats(4.321, "stereo4");
    assert!(n2 > 1000 && n4 > 1000, "{n2} {n4}");
    // The paper's 0.032 z^2.
    assert!((s2 / (0.032 * z2 * z2) - 1.0).abs() < 0.06, "{s2} at {z2} m");
    assert!((s4 / (0.032 * z4 * z4) - 1.0).abs() < 0.06, "{s4} at {z4} m");
}

#[test]
fn the_same_seed_gives_the_same_scans_on_one_and_two_threads() {
    let noise = "range_sigma_m = 0.02\ndropout_probability = 0.1\nspurious_probability = 0.05\nangular_jitter_deg = 0.2\nmixed_pixel_probability = 0.3\n";
    let run = |threads: usize, name: &str, seed: u64| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| {
            let extra = format!("{LASER}\nrate_hz = 10.0\n[sensors.noise]\n{noise}");
            let text = common::scenario_text(&format!(
                "[[obstacles]]\nkind = \"box\"\ncenter_xy_m = [5.1, 0.0]\nsize_m = [0.2, 7.0, 3.0]\n\n[[sensors]]\n{extra}"
            ))
            .replace("seed = 7", &format!("seed = {seed}"));
            let loaded = common::load_text(name, &text).expect("valid");
            let mut sim = Simulation::new(&loaded).expect("simulation");
            (0..20).filter_map(|_| sim.next_scan()).collect::<Vec<_>>()
        })
    };
    let one = run(1, "det1", 7);
    let two = run(2, "det2", 7);
    assert_eq!(one, two);
    let other = run(2, "det3", 8);
    assert_ne!(one, other, "a different seed changes the noise");
}

/// The log header's entry for the scene's one laser (`LASER`), its ground given.
fn laser_log_sensor(sim: &Simulation, ground_in_sensor_m: Option<[f64; 3]>) -> sim::log::LogSensor {
    sim::log::LogSensor {
        name: "laser".into(),
        kind: "laser2d".into(),
        preset: "sick_lms291".into(),
        rate_hz: 75.0,
        map_model: sim.sensors()[0].map_model(),
        ground_in_sensor_m,
    }
}

#[test]
fn logs_read_back_exactly_and_reject_damage() {
    let (_, mut sim) = scan_with(
        "log",
        &format!("{LASER}\n[sensors.noise]\ndropout_probability = 0.1\n"),
        "",
    );
    let scans: Vec<_> = (0..5).filter_map(|_| sim.next_scan()).collect();
    let ground = sim.sensors()[0]
        .ground_in_sensor(sim.world())
        .map(|g| [g.x, g.y, g.z]);
    let header = sim::log::LogHeader {
        scenario: "log".into(),
        seed: 7,
        duration_s: 4.0,
        sensors: vec![laser_log_sensor(&sim, ground)],
        stance: Some(sim::log::LogStance::new(
            &sim.world().robot().wheel_contacts(),
            sim.world().robot().footprint(),
            &sim.world().world_from_base(),
            &sim.world().estimated_world_from_base(),
        )),
    };
    let dir = common::temp_dir("logfile");
    let path = dir.join("run.oeglog");
    let mut w = sim::log::LogWriter::create(&path, &header).expect("create");
    for s in &scans {
        w.push(s).expect("push");
    }
    assert_eq!(w.finish().expect("finish"), 5);
    let back = sim::log::read_log(&path).expect("read");
    assert_eq!(back.header, header);
    // The stance reads back as the world's own (the poses' rotations renormalised, the same to rounding).
    let stance = back.header.stance.as_ref().expect("stance");
    let (read, world) = (
        stance
            .stance(PoseSource::Estimated)
            .expect("pose")
            .expect("wheels"),
        sim.world().estimated_stance().expect("wheels"),
    );
    assert_eq!(read.contacts.len(), world.contacts.len());
    for (a, b) in read.contacts.iter().zip(&world.contacts) {
        assert!((a - b).norm() < 1e-12, "{a} {b}");
    }
    // A log holds what the sensors measured; the noise-free range is the simulation's own and reads back NaN.
    let measured: Vec<_> = scans
        .iter()
        .map(|s| {
            let mut s = s.clone();
            s.rays.iter_mut().for_each(|r| r.true_range_m = f32::NAN);
            s
        })
        .collect();
    // The ground under the robot reads back with every scan, from the header.
    assert!(measured.iter().all(|s| s.ground_in_sensor.is_some()));
    assert_eq!(back.scans, measured);
    let bytes = std::fs::read(&path).expect("bytes");
    for cut in [0, 10, 40, bytes.len() / 2, bytes.len() - 1] {
        std::fs::write(dir.join("cut.oeglog"), &bytes[..cut]).expect("write");
        let err = sim::log::read_log(&dir.join("cut.oeglog"))
            .expect_err("truncated")
            .to_string();
        assert!(err.contains("cut.oeglog: at byte"), "{cut}: {err}");
    }
    let mut flipped = bytes.clone();
    let k = bytes.len() - 30;
    flipped[k] ^= 0x10;
    std::fs::write(dir.join("flip.oeglog"), &flipped).expect("write");
    let err = sim::log::read_log(&dir.join("flip.oeglog"))
        .expect_err("corrupt")
        .to_string();
    assert!(
        err.contains("checksum") || err.contains("non-finite") || err.contains("kind"),
        "{err}"
    );
    // An abandoned writer leaves no file.
    let abandoned = dir.join("abandoned.oeglog");
    drop(sim::log::LogWriter::create(&abandoned, &header).expect("create"));
    assert!(!abandoned.exists());
    assert_eq!(
        std::fs::read_dir(&dir).expect("dir").count(),
        3,
        "no temporary files left"
    );
}

#[test]
fn mixed_pixels_fall_between_the_surfaces_at_a_depth_edge() {
    // A wall ending at y = 1: beams near its edge mix the wall (4.8 m) with the floor behind.
    let sensor = "name = \"laser\"\nkind = \"laser2d\"\nmount_link = \"laser_front_mount\"\nfov_deg = 90.0\nstep_deg = 0.5\nrpy_deg = [0.0, 2.0, 0.0]\n[sensors.noise]\nrange_sigma_m = 0.0\nmixed_pixel_probability = 1.0\n";
    let text = common::scenario_text(&format!(
        "[[obstacles]]\nkind = \"box\"\ncenter_xy_m = [5.1, -1.5]\nsize_m = [0.2, 5.0, 3.0]\n\n[[sensors]]\n{sensor}"
    ))
    .replace("[[0.0, 0.0], [4.0, 0.0]]", "[[0.0, 0.0]]");
    let loaded = common::load_text("mixed", &text).expect("valid");
    let mut sim = Simulation::new(&loaded).expect("simulation");
    let scan = sim.next_scan().expect("scan");
    // Per beam at azimuth a (pitched 2 degrees down): the wall at 4.8 / (cos a cos 2deg) while its edge at
    // y = 1 is not passed, else the floor at 0.3 / (cos a sin 2deg).
    let pitch = 2f64.to_radians();
    let mut mixed = Vec::new();
    for (k, r) in scan.rays.iter().enumerate() {
        let a = (-45.0 + 0.5 * k as f64).to_radians();
        let wall = 4.8 / (a.cos() * pitch.cos());
        let floor = 0.3 / (a.cos() * pitch.sin());
        let range = f64::from(r.vector_in_sensor.norm());
        // On the grazing floor neighbouring beams differ by about 0.1 m and mix harmlessly; count what lies
        // clearly off both surfaces.
        if r.kind == RayKind::Hit && (range - wall).abs() > 0.15 && (range - floor).abs() > 0.15 {
            assert!(
                range > wall.min(floor) && range < wall.max(floor),
                "beam {k}: {range} outside both surfaces"
            );
            mixed.push(a.to_degrees());
        }
    }
    // The wall's two ends, at y = 1 and y = -4.
    let edges = [
        (1.0f64 / 4.8).atan().to_degrees(),
        (-4.0f64 / 4.8).atan().to_degrees(),
    ];
    assert!(!mixed.is_empty(), "no mixed pixel at the edges");
    assert!(
        mixed.iter().all(|a| edges.iter().any(|e| (a - e).abs() < 1.5)),
        "mixed pixels only at the edges {edges:?}: {mixed:?}"
    );
}

#[test]
fn each_obstacle_counts_the_readings_it_returned_and_one_no_beam_reaches_counts_none() {
    // The wall ahead (obstacle 0); a board 1 m up, above the laser's plane (1); a box behind the robot, outside
    // the laser's 90 degree fan (2).
    let others = "[[obstacles]]\nkind = \"overhang\"\nname = \"high board\"\ncenter_xy_m = [2.0, 0.0]\n\
                  size_m = [0.5, 0.5, 0.05]\nclearance_m = 1.0\n\n[[obstacles]]\nkind = \"box\"\nname = \"behind\"\n\
                  center_xy_m = [-1.5, 0.0]\nsize_m = [0.2, 0.2, 0.5]\n";
    let (scan, sim) = scan_with(
        "returns",
        &format!("{LASER}\n[sensors.noise]\nrange_sigma_m = 0.0\n"),
        others,
    );
    let hits = scan.rays.iter().filter(|r| r.kind == RayKind::Hit).count() as u64;
    assert!(hits > 0);
    let returns = sim.obstacle_returns();
    assert_eq!(returns.of(0), hits, "every hit of this scan is the wall's");
    assert_eq!(returns.of(1), 0, "no beam reaches a board over the laser's plane");
    assert_eq!(returns.of(2), 0, "nor a box behind the fan");
    assert_eq!(returns.of(99), 0);
    // Spurious returns are not the wall's, though they are hits.
    let (scan, sim) = scan_with(
        "spurious_returns",
        &format!("{LASER}\n[sensors.noise]\nrange_sigma_m = 0.0\nspurious_probability = 0.5\n"),
        "",
    );
    let hits = scan.rays.iter().filter(|r| r.kind == RayKind::Hit).count() as u64;
    let returned = sim.obstacle_returns().of(0);
    assert!(returned > 0 && returned < hits, "{returned} of {hits}");
}

#[test]
fn a_scan_says_how_high_the_ground_under_the_robot_is() {
    // The robot stands 3 m up a 10 % slope: the ground under it is 0.3 m high, whichever sensor looks.
    let text = common::scenario_driving(
        1.0,
        "waypoints_xy_m = [[3.0, 0.0], [3.5, 0.0]]\nspeed_m_s = 0.5",
        &format!("[terrain]\nkind = \"slope\"\nslope_x = 0.1\n\n[[sensors]]\n{LASER}"),
    );
    let loaded = common::load_text("ground", &text).expect("valid");
    let mut sim = Simulation::new(&loaded).expect("simulation");
    let scan = sim.next_scan().expect("a scan at t = 0");
    let model = sim.sensors()[0].map_model();
    for pose in [PoseSource::True, PoseSource::Estimated] {
        let ground = scan.to_scan(pose, model).ground_z_m.expect("a robot on wheels");
        assert!((ground - 0.3).abs() < 0.01, "{ground}");
    }
    // The sensor sits above it: the map's threshold measures from the ground, not from the sensor.
    assert!(scan.world_from_sensor.translation.z > 0.3 + 0.1);
}

#[test]
fn a_log_whose_ground_lies_far_from_its_sensor_is_refused() {
    let (scan, sim) = scan_with("farground", LASER, "");
    let header = sim::log::LogHeader {
        scenario: "farground".into(),
        seed: 7,
        duration_s: 4.0,
        sensors: vec![laser_log_sensor(&sim, Some([0.0, 0.0, -1e300]))],
        stance: None,
    };
    let dir = common::temp_dir("farground");
    let path = dir.join("far.oeglog");
    let mut w = sim::log::LogWriter::create(&path, &header).expect("create");
    w.push(&scan).expect("push");
    w.finish().expect("finish");
    let err = sim::log::read_log(&path).expect_err("absurd ground").to_string();
    assert!(
        err.contains("far.oeglog") && err.contains("sensor laser: ground_in_sensor_m"),
        "{err}"
    );
}
