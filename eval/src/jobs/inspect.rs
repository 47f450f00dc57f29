//! `oeg inspect`: a saved map's header and statistics, as text.

use std::fmt::Write as _;
use std::path::Path;

use oeg::{RobotProfile, TraversabilityRule};

use crate::error::Result;

/// The report `oeg inspect` prints.
///
/// # Errors
/// The map file cannot be read or is malformed (named, with the byte offset).
pub fn inspect(path: &Path) -> Result<String> {
    let header = oeg::read_map_header(path)?;
    let map = oeg::load_map(path)?;
    let profile = RobotProfile::default();
    let counts = map.traversability_counts(&profile, TraversabilityRule::Absolute);
    let mut out = String::new();
    let m = &header.config.model;
    // Writing into a String cannot fail.
    let _ = writeln!(out, "file:                 {}", path.display());
    let _ = writeln!(out, "format version:       {}", header.file_version);
    let _ = writeln!(out, "written by:           {}", header.written_by);
    let _ = writeln!(out, "resolution:           {} m", header.config.resolution_m);
    let _ = writeln!(
        out,
        "tiles:                {} of {}x{} cells",
        header.num_tiles, header.tile_size, header.tile_size
    );
    if header.num_ceiling_tiles > 0 {
        let _ = writeln!(
            out,
            "ceiling layer:        {} tiles, {} cells with a structure over their surface",
            header.num_ceiling_tiles,
            map.num_ceilings()
        );
    }
    let _ = writeln!(out, "scans integrated:     {}", header.num_scans);
    let _ = writeln!(out, "rays integrated:      {}", header.totals.num_rays);
    let _ = writeln!(
        out,
        "cell visits:          {} ({} cell updates)",
        header.totals.num_cell_visits, header.totals.num_cells_updated
    );
    let _ = writeln!(
        out,
        "log-odds bounds:      [{}, {}]",
        m.log_odds_min, m.log_odds_max
    );
    let _ = writeln!(out, "occupied threshold:   {}", m.occupied_threshold);
    let _ = writeln!(
        out,
        "p_min / p_max / k:    {} / {} / {} m",
        m.p_min, m.p_max, m.significance_k_m
    );
    let _ = writeln!(out, "free-space elevation: {:?}", m.free_space_elevation);
    // Every model option, as the scenario files and the map file's header spell them.
    let _ = writeln!(
        out,
        "model options:        {}",
        serde_json::to_string(m).unwrap_or_default()
    );
    let _ = writeln!(
        out,
        "max height:           {}",
        m.max_height_m.map_or("none".to_string(), |h| format!("{h} m"))
    );
    let _ = writeln!(out, "observed cells:       {}", map.num_observed_cells());
    let _ = writeln!(out, "  free:               {}", counts.num_free);
    let _ = writeln!(
        out,
        "  traversable:        {} (occupied, step <= {} m)",
        counts.num_traversable, profile.max_step_m
    );
    let _ = writeln!(out, "  blocked:            {}", counts.num_blocked);
    if let Some(r) = map.observed_region() {
        let (x0, y0) = map.geometry().cell_min_corner(r.min);
        let res = map.geometry().resolution_m();
        let _ = writeln!(
            out,
            "extent:               x {:.2} .. {:.2} m, y {:.2} .. {:.2} m ({} x {} cells)",
            x0,
            x0 + f64::from(r.num_x) * res,
            y0,
            y0 + f64::from(r.num_y) * res,
            r.num_x,
            r.num_y
        );
    }
    let elevations: Vec<f32> = map
        .observed_cells()
        .filter_map(|(_, c)| c.elevation().map(|e| e.mean_m))
        .collect();
    if let (Some(lo), Some(hi)) = (
        elevations.iter().copied().reduce(f32::min),
        elevations.iter().copied().reduce(f32::max),
    ) {
        let _ = writeln!(
            out,
            "elevation range:      {lo:.3} .. {hi:.3} m ({} cells with an estimate)",
            elevations.len()
        );
    }
    let _ = writeln!(out, "memory:               {} bytes", map.memory_bytes());
    Ok(out)
}
