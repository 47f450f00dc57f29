//! Maps a scan graph once and prints the integration totals: `cargo run -p oeg --release --example map_graph --
//! FILE.graph RESOLUTION_M`. A profiling aid; the `oeg map` command is the user-facing tool.

use std::time::Instant;

use oeg::{Map, MapConfig, SensorModel};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().ok_or("usage: map_graph FILE.graph RESOLUTION_M")?;
    let resolution_m: f64 = args
        .next()
        .ok_or("usage: map_graph FILE.graph RESOLUTION_M")?
        .parse()?;
    let scans = oeg::read_graph_scans(path.as_ref(), SensorModel::laser())?;
    let mut map = Map::new(MapConfig::new(resolution_m))?;
    let start = Instant::now();
    for scan in &scans {
        map.integrate(scan)?;
    }
    let seconds = start.elapsed().as_secs_f64();
    let t = map.totals();
    println!(
        "{} rays, {} cell visits, {} cell updates, {} observed cells, {} bytes, {seconds:.4} s, {:.2} M rays/s",
        t.num_rays,
        t.num_cell_visits,
        t.num_cells_updated,
        map.num_observed_cells(),
        map.memory_bytes(),
        t.num_rays as f64 / seconds / 1e6
    );
    Ok(())
}
