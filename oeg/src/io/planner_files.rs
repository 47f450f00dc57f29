//! The map as files a planner reads: the decisions as a nav2 map (`map.pgm`, `map.yaml`), every layer as a
//! `.npy` array, and `layers.json`, the sidecar that says where the arrays lie and what their values mean.
//! `oeg map` writes them, and a closed-loop run writes them for an external planner at every replanning time
//! (`docs/planner-protocol.md`).

use crate::error::Result;
use crate::geometry::CellRegion;
use crate::io::nav2::nav2_map;
use crate::io::npy::{NpyArray, NpyData};
use crate::map::{LayerKind, Map};
use crate::planner::UncertainCells;
use crate::traversability::{RobotProfile, Traversability, TraversabilityRule};

/// The float layers a planner gets (as `.npy` files, or as arrays in the Python package's planner callback),
/// with their units and the meaning of NaN.
pub const PLANNER_FLOAT_LAYERS: [(LayerKind, &str, &str); 3] = [
    (LayerKind::ElevationM, "m", "no elevation estimate"),
    (LayerKind::VarianceM2, "m^2", "no elevation estimate"),
    (LayerKind::OccupancyProbability, "1", "never observed"),
];

/// The files, by name, for the map's `region`: `map.pgm`, `map.yaml`, `decisions.npy`, one `.npy` per float
/// layer and `layers.json`. Arrays are `region.num_y` rows by `region.num_x` columns, row 0 the min-y row
/// (`matplotlib.pyplot.imshow(a, origin="lower")`); the PGM image runs from the max-y row, as `map_server`
/// expects.
///
/// # Errors
/// [`crate::Error::MemoryLimit`] if the rasters would exceed the map's memory limit.
pub fn planner_files(
    map: &Map,
    region: CellRegion,
    profile: &RobotProfile,
    rule: TraversabilityRule,
    uncertain: UncertainCells,
) -> Result<Vec<(String, Vec<u8>)>> {
    let (rows, cols) = (region.num_y as usize, region.num_x as usize);
    let decisions = map.traversability_layer(region, profile, rule)?;
    let (pgm, yaml) = nav2_map(&decisions, uncertain, "map.pgm");
    let mut files = vec![
        ("map.pgm".to_string(), pgm),
        ("map.yaml".to_string(), yaml.into_bytes()),
    ];
    let codes = decisions.values.iter().map(|t| *t as u8).collect();
    files.push((
        "decisions.npy".into(),
        NpyArray {
            rows,
            cols,
            data: NpyData::U8(codes),
        }
        .to_bytes()?,
    ));
    let mut entries = vec![format!(
        "    \"decisions\": {{\"file\": \"decisions.npy\", \"dtype\": \"uint8\", \"values\": {{{}}}}}",
        [
            Traversability::Unknown,
            Traversability::Free,
            Traversability::Traversable,
            Traversability::Blocked,
            Traversability::Uncertain,
        ]
        .iter()
        .map(|t| format!("\"{}\": \"{}\"", *t as u8, t.name()))
        .collect::<Vec<_>>()
        .join(", ")
    )];
    for (kind, unit, nan) in PLANNER_FLOAT_LAYERS {
        let layer = map.layer(kind, region)?;
        let file = format!("{}.npy", kind.name());
        files.push((
            file.clone(),
            NpyArray {
                rows,
                cols,
                data: NpyData::F32(layer.values),
            }
            .to_bytes()?,
        ));
        entries.push(format!(
            "    \"{}\": {{\"file\": \"{file}\", \"dtype\": \"float32\", \"unit\": \"{unit}\", \"nan\": \"{nan}\"}}",
            kind.name()
        ));
    }
    let res = map.geometry().resolution_m();
    let (x0, y0) = (f64::from(region.min.i) * res, f64::from(region.min.j) * res);
    let sidecar = format!(
        "{{\n  \"frame\": \"world\",\n  \"resolution_m\": {res},\n  \"origin_xy_m\": [{x0}, {y0}],\n  \
         \"shape\": [{rows}, {cols}],\n  \"row_order\": \"row 0 is the min-y row, column 0 the min-x column; \
         cell [r, c] covers x from origin_x + c * resolution_m and y from origin_y + r * resolution_m\",\n  \
         \"extent_m\": [{x0}, {}, {y0}, {}],\n  \"robot\": {{\"max_step_m\": {}, \"height_m\": {}, \"max_grade\": {}}},\n  \
         \"layers\": {{\n{}\n  }}\n}}\n",
        x0 + cols as f64 * res,
        y0 + rows as f64 * res,
        profile.max_step_m,
        profile.height_m,
        profile.max_grade,
        entries.join(",\n")
    );
    files.push(("layers.json".into(), sidecar.into_bytes()));
    Ok(files)
}
