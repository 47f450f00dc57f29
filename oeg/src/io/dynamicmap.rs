//! Sequences of the DynamicMap benchmark's unified format (KTH's dynamic-points-removal benchmark): a folder
//! whose `pcd/` holds one PCD file a frame, numbered, each frame's points already in the world frame and the
//! sensor's pose in `VIEWPOINT` ([`PcdPoints::World`]).

use std::path::{Path, PathBuf};

use super::pcd::{PcdOptions, PcdPoints, read_pcd_scan_within};
use super::sorted_files;
use crate::error::Result;
use crate::scan::Scan;
use crate::sensor::SensorModel;

/// A DynamicMap sequence's frames as scans, in name order, each a hit a point from its viewpoint; at most
/// `limit_bytes` of files read in all.
///
/// # Errors
/// [`crate::Error::Io`] for a folder or file that cannot be read; [`crate::Error::Parse`] for a folder with no
/// `.pcd` frame or a malformed frame, named.
pub fn read_dynamicmap(folder: &Path, sensor: SensorModel, limit_bytes: u64) -> Result<Vec<(PathBuf, Scan)>> {
    let options = PcdOptions {
        points: PcdPoints::World,
        sensor,
        ..PcdOptions::default()
    };
    let mut left = limit_bytes;
    let mut out = Vec::new();
    for frame in sorted_files(&folder.join("pcd"), "pcd")? {
        let scan = read_pcd_scan_within(&frame, &options, left)?;
        left = left.saturating_sub(std::fs::metadata(&frame).map_or(0, |m| m.len()));
        out.push((frame, scan));
    }
    Ok(out)
}
