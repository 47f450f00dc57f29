//! Writes the seed inputs of the fuzz corpus (`fuzz/corpus/<target>/seed_*`) from the project's own writers:
//! `cargo run --example fuzz_seeds -p oeg-eval`. Nothing from `../shared/data` is copied.

#![allow(
    clippy::disallowed_methods,
    reason = "tests and tools write their inputs directly"
)]

use std::path::Path;

use nalgebra::Point3;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let corpus = root.join("fuzz/corpus");
    let dir = |t: &str| {
        let d = corpus.join(t);
        std::fs::create_dir_all(&d).map(|()| d)
    };
    // A small scan: a ring of hits around a sensor.
    let mut scan = oeg::Scan::new(Point3::new(0.0, 0.0, 0.5), oeg::SensorModel::laser());
    for k in 0..12 {
        let a = f64::from(k) * 0.5;
        scan.push_hit(Point3::new(2.0 * a.cos(), 2.0 * a.sin(), 0.1 * f64::from(k % 3)));
    }
    oeg::write_graph(
        &dir("graph")?.join("seed_ring.graph"),
        std::slice::from_ref(&scan),
    )?;
    let points: Vec<Point3<f32>> = scan
        .rays
        .iter()
        .map(|r| Point3::from(r.offset_in_world))
        .collect();
    let cloud = oeg::PcdCloud {
        width: points.len() as u32,
        height: 1,
        viewpoint: nalgebra::Isometry3::identity(),
        points,
    };
    for (name, encoding) in [
        ("ascii", oeg::PcdEncoding::Ascii),
        ("binary", oeg::PcdEncoding::Binary),
        ("compressed", oeg::PcdEncoding::BinaryCompressed),
    ] {
        oeg::write_pcd(&dir("pcd")?.join(format!("seed_{name}.pcd")), &cloud, encoding)?;
    }
    oeg::save_map(
        &oeg::Map::new(oeg::MapConfig::new(0.5))?,
        &dir("map")?.join("seed_empty.oeg"),
    )?;
    let mut map = oeg::Map::new(oeg::MapConfig::new(0.5))?;
    map.integrate(&scan)?;
    oeg::save_map(&map, &dir("map")?.join("seed_ring.oeg"))?;
    // A map with a ceiling layer (version 2): the ground under a board, then the board's top over it.
    let robust = oeg::MapPreset::Robust.model(&oeg::RobotProfile::default());
    let mut map = oeg::Map::new(oeg::MapConfig {
        model: robust,
        ..oeg::MapConfig::new(0.5)
    })?;
    for (z0, z1) in [(0.25, 0.0), (0.45, 0.34)] {
        let mut scan = oeg::Scan::new(Point3::new(0.25, 0.25, z0), oeg::SensorModel::laser());
        scan.push_hit(Point3::new(2.25, 0.25, z1));
        map.integrate(&scan)?;
    }
    assert_eq!(map.num_ceilings(), 1, "the seed must hold a ceiling");
    oeg::save_map(&map, &dir("map")?.join("seed_ceiling.oeg"))?;
    // A short recorded log of the smallest shipped scene.
    let mut loaded = sim::scenario::load(&root.join("scenarios/thin_pole.toml"))?;
    loaded.scenario.duration_s = 0.2;
    loaded.scenario.sensors.truncate(1);
    let mut simulation = sim::Simulation::new(&loaded)?;
    let header = oeg_eval::jobs::record::log_header(&loaded, &simulation);
    let mut writer = sim::log::LogWriter::create(&dir("log")?.join("seed_short.oeglog"), &header)?;
    for _ in 0..2 {
        if let Some(scan) = simulation.next_scan() {
            writer.push(&scan)?;
        }
    }
    writer.finish()?;
    for name in ["thin_pole", "default"] {
        let text = std::fs::read(root.join(format!("scenarios/{name}.toml")))?;
        std::fs::write(dir("scenario")?.join(format!("seed_{name}.toml")), text)?;
    }
    std::fs::write(
        dir("urdf")?.join("seed_pioneer3at.urdf"),
        std::fs::read(root.join("scenarios/robots/pioneer3at.urdf"))?,
    )?;
    let mut png_bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut png_bytes, 4, 3);
        encoder.set_color(png::ColorType::Grayscale);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header()?;
        writer.write_image_data(&[0, 10, 20, 30, 40, 50, 60, 70, 80, 90, 100, 255])?;
    }
    std::fs::write(dir("png")?.join("seed_ramp.png"), png_bytes)?;
    println!("wrote the seeds under {}", corpus.display());
    Ok(())
}
