//! Simulated rays per second: `cargo bench -p sim --bench raycast`.
//!
//! A 40 m x 40 m scene with irregular terrain (a 0.1 m heightfield) and 48 obstacles (boxes, poles, bushes,
//! boards), seen by a VLP-16-class lidar (28,800 beams a scan) and a VGA stereo camera (stride 4: 19,200 rays),
//! with noise on. Each iteration takes one scan of each sensor. Run it twice to get the per-core figure:
//! `RAYON_NUM_THREADS=1 cargo bench -p sim --bench raycast` and with 2.

#![allow(
    clippy::disallowed_methods,
    reason = "tests and tools write their inputs directly"
)]

use std::fmt::Write as _;
use std::hint::black_box;
use std::path::PathBuf;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};

fn scenario_text() -> String {
    let urdf = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenarios/robots/pioneer3at.urdf");
    let mut s = format!(
        "name = \"bench\"\nseed = 1\nduration_s = 1000.0\n\n[map]\nmin_xy_m = [-20.0, -20.0]\nmax_xy_m = [20.0, 20.0]\n\
         resolution_m = 0.1\n\n[robot]\nurdf = \"{}\"\n\n[robot.drive]\nwaypoints_xy_m = [[0.0, 0.0], [10.0, 0.0]]\n\
         speed_m_s = 0.01\n\n[terrain]\nkind = \"noise\"\namplitude_m = 0.05\nwavelength_m = 4.0\n\n",
        urdf.display()
    );
    for k in 0..48 {
        let angle = f64::from(k) * 0.37;
        let r = 3.0 + f64::from(k % 12) * 1.3;
        let (x, y) = (r * angle.cos(), r * angle.sin());
        let body = match k % 4 {
            0 => format!(
                "kind = \"box\"\ncenter_xy_m = [{x}, {y}]\nsize_m = [0.8, 0.4, 0.6]\nyaw_deg = {}\n",
                k * 17
            ),
            1 => format!("kind = \"cylinder\"\ncenter_xy_m = [{x}, {y}]\nradius_m = 0.1\nheight_m = 2.0\n"),
            2 => format!("kind = \"bush\"\ncenter_xy_m = [{x}, {y}]\nradius_m = 0.6\nheight_m = 0.9\n"),
            _ => format!(
                "kind = \"overhang\"\ncenter_xy_m = [{x}, {y}]\nsize_m = [0.5, 1.5, 0.05]\nclearance_m = 0.4\n"
            ),
        };
        let _ = write!(s, "[[obstacles]]\n{body}\n");
    }
    s.push_str(
        "[[sensors]]\nname = \"lidar\"\nkind = \"lidar3d\"\nmount_link = \"stereo_mount\"\npreset = \"vlp16\"\nrate_hz = 10.0\n\
         [sensors.noise]\ndropout_probability = 0.02\n\n\
         [[sensors]]\nname = \"stereo\"\nkind = \"stereo\"\nmount_link = \"stereo_mount\"\npreset = \"stereo_vga\"\nrate_hz = 10.0\n",
    );
    s
}

fn simulated_rays(c: &mut Criterion) {
    let dir = std::env::temp_dir().join(format!("sim-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("bench.toml");
    std::fs::write(&path, scenario_text()).expect("write");
    let loaded = sim::scenario::load(&path).expect("valid bench scenario");
    let mut sim = sim::Simulation::new(&loaded).expect("simulation");
    let rays_per_iteration = sim
        .sensors()
        .iter()
        .map(|s| s.directions().len() as u64)
        .sum::<u64>();
    let mut group = c.benchmark_group("simulated_rays");
    group.throughput(Throughput::Elements(rays_per_iteration));
    group.sample_size(20);
    group.bench_function(
        format!("lidar_and_stereo/threads={}", rayon::current_num_threads()),
        |b| {
            b.iter(|| {
                for _ in 0..sim.sensors().len() {
                    black_box(sim.next_scan());
                }
            });
        },
    );
    group.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, simulated_rays);
criterion_main!(benches);
