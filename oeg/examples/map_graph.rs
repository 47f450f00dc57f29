//! Maps a scan graph once and prints the integration totals: `cargo run -p oeg --release --example map_graph --
//! FILE.graph RESOLUTION_M [PRESET]` (PRESET: `paper`, the default, `static` or `robust`, for the default
//! robot). Integration uses `RAYON_NUM_THREADS` threads (all cores when unset). A profiling aid and the timed program of `scripts/bench-regression.sh`, whose output line it keeps
//! as the first version printed it; the `oeg map` command is the user-facing tool.

use std::time::Instant;

use oeg::{Map, MapConfig, SensorModel};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().ok_or("usage: map_graph FILE.graph RESOLUTION_M")?;
    let resolution_m: f64 = args
        .next()
        .ok_or("usage: map_graph FILE.graph RESOLUTION_M")?
        .parse()?;
    let preset: oeg::MapPreset = args.next().as_deref().unwrap_or("paper").parse()?;
    let scans = oeg::read_graph_scans(path.as_ref(), SensorModel::laser())?;
    let mut config = MapConfig::new(resolution_m);
    config.model = preset.model(&oeg::RobotProfile::default());
    let mut map = Map::new(config)?;
    let start = Instant::now();
    for scan in &scans {
        map.integrate(scan)?;
    }
    let seconds = start.elapsed().as_secs_f64();
    let t = map.totals();
    // "N bytes" is the map with its scratch, as the first version counted it (its `memory_bytes()`).
    println!(
        "{} rays, {} cell visits, {} cell updates, {} observed cells, {} bytes, {seconds:.4} s, {:.2} M rays/s; \
         map {} bytes, scratch {} bytes ({} bytes a cell), {} threads",
        t.num_rays,
        t.num_cell_visits,
        t.num_cells_updated,
        map.num_observed_cells(),
        map.memory_bytes() + map.scratch_bytes(),
        t.num_rays as f64 / seconds / 1e6,
        map.memory_bytes(),
        map.scratch_bytes(),
        map.scratch_cell_bytes(),
        rayon::current_num_threads(),
    );
    Ok(())
}
