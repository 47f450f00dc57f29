//! The decisions as a ROS / nav2 `map_server` map: a binary PGM image (`P5`, row 0 the max-y edge, as
//! `map_saver` writes it) and its YAML description (`image`, `mode: trinary`, `resolution`, `origin` of the
//! lower-left pixel's corner, `negate`, `occupied_thresh`, `free_thresh`). nav2, ROS 1's `map_server` and
//! most planners read it as it is.

use crate::map::Raster;
use crate::planner::UncertainCells;
use crate::traversability::Traversability;

/// Grey of a free cell (`map_saver`'s 254).
pub const PGM_FREE: u8 = 254;
/// Grey of an occupied cell (`map_saver`'s 0).
pub const PGM_OCCUPIED: u8 = 0;
/// Grey of an unknown cell (`map_saver`'s 205).
pub const PGM_UNKNOWN: u8 = 205;

/// `free_thresh` of the YAML: 205 reads as unknown (occupancy 0.196 is above it), 254 as free.
const FREE_THRESH: f64 = 0.1;
/// `occupied_thresh` of the YAML: 0 reads as occupied.
const OCCUPIED_THRESH: f64 = 0.65;

/// The grey of one decision: drivable cells free, blocked cells occupied, never-observed cells unknown, and
/// uncertain cells as `uncertain` says (occupied by default, as the built-in planner treats them).
pub fn nav2_grey(t: Traversability, uncertain: UncertainCells) -> u8 {
    match t {
        Traversability::Free | Traversability::Traversable => PGM_FREE,
        Traversability::Blocked => PGM_OCCUPIED,
        Traversability::Unknown => PGM_UNKNOWN,
        Traversability::Uncertain => match uncertain {
            UncertainCells::Blocked => PGM_OCCUPIED,
            UncertainCells::Drivable => PGM_FREE,
        },
    }
}

/// The PGM image and the YAML text of `decisions`; the YAML names the image `image_name` (a path relative to
/// the YAML file, as `map_server` resolves it).
pub fn nav2_map(
    decisions: &Raster<Traversability>,
    uncertain: UncertainCells,
    image_name: &str,
) -> (Vec<u8>, String) {
    let region = decisions.region;
    let (w, h) = (region.num_x as usize, region.num_y as usize);
    let mut pgm = format!("P5\n# CREATOR: oeg {}\n{w} {h}\n255\n", decisions.resolution_m).into_bytes();
    pgm.reserve(w * h);
    for v in (0..h).rev() {
        pgm.extend(
            decisions.values[v * w..(v + 1) * w]
                .iter()
                .map(|t| nav2_grey(*t, uncertain)),
        );
    }
    let res = decisions.resolution_m;
    let (x0, y0) = (f64::from(region.min.i) * res, f64::from(region.min.j) * res);
    let yaml = format!(
        "image: {image_name}\nmode: trinary\nresolution: {res}\norigin: [{x0}, {y0}, 0.0]\nnegate: 0\n\
         occupied_thresh: {OCCUPIED_THRESH}\nfree_thresh: {FREE_THRESH}\n"
    );
    (pgm, yaml)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{CellIndex, CellRegion};

    #[test]
    fn the_image_runs_from_the_max_y_row_and_the_origin_is_the_lower_left_corner() {
        let region = CellRegion::from_corners(CellIndex::new(-2, 4), CellIndex::new(0, 5)).expect("region");
        use Traversability::*;
        let decisions = Raster {
            region,
            resolution_m: 0.5,
            // Row y = 4 (bottom): free, blocked, unknown; row y = 5 (top): traversable, uncertain, free.
            values: vec![Free, Blocked, Unknown, Traversable, Uncertain, Free],
        };
        let (pgm, yaml) = nav2_map(&decisions, UncertainCells::Blocked, "map.pgm");
        let header = "P5\n# CREATOR: oeg 0.5\n3 2\n255\n";
        assert_eq!(&pgm[..header.len()], header.as_bytes());
        assert_eq!(&pgm[header.len()..], &[254, 0, 254, 254, 0, 205]);
        assert!(yaml.contains("origin: [-1, 2, 0.0]\n"), "{yaml}");
        assert!(yaml.contains("resolution: 0.5\n") && yaml.contains("mode: trinary\n"));
        // map_server's trinary reading: occupancy = (255 - grey) / 255.
        let occ = |g: u8| f64::from(255 - g) / 255.0;
        assert!(occ(PGM_FREE) < FREE_THRESH);
        assert!(occ(PGM_UNKNOWN) > FREE_THRESH && occ(PGM_UNKNOWN) < OCCUPIED_THRESH);
        assert!(occ(PGM_OCCUPIED) > OCCUPIED_THRESH);
        let (drivable, _) = nav2_map(&decisions, UncertainCells::Drivable, "map.pgm");
        assert_eq!(drivable[header.len() + 1], PGM_FREE);
    }
}
