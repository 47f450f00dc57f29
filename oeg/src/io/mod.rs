//! Reading real data into [`crate::Scan`]s, and saving and loading maps.
//!
//! * [`graph`]: OctoMap scan graphs (`.graph`), the format of OctoMap's published data sets;
//! * [`pcd`]: PCL point clouds (`.pcd`: ascii, binary, binary_compressed);
//! * [`dynamicmap`]: the DynamicMap benchmark's sequences (`pcd/` frames, world-frame points);
//! * [`kitti`]: KITTI odometry sequences (`velodyne/*.bin`, the poses, `calib.txt`'s `Tr`);
//! * [`rosbag`]: ROS 2 bags (MCAP storage): `PointCloud2` and `LaserScan` in, placed by `/tf`; clouds and
//!   transforms out;
//! * [`mapfile`]: this crate's own map format (`.oeg`).
//!
//! Every reader checks sizes against the file before allocating, rejects non-finite numbers, and names the
//! file and the byte or line of the problem.

pub(crate) mod dynamicmap;
pub(crate) mod graph;
pub(crate) mod kitti;
mod lzf;
pub(crate) mod mapfile;
pub(crate) mod nav2;
pub(crate) mod npy;
pub(crate) mod pcd;
pub(crate) mod planner_files;
pub(crate) mod rosbag;

use std::path::{Path, PathBuf};

use crate::error::Result;

pub(crate) use oeg_files::{ByteReader, container, unit_quaternion, write_atomically};

/// Reads a whole file of at most `limit` bytes ([`oeg_files::read_bounded`]), naming it on failure: a binary input (a map,
/// a scan graph, a PCD) is never read past the memory its caller allows, whatever the file (a device) says.
pub(crate) fn read_file(path: &Path, limit: u64) -> Result<Vec<u8>> {
    Ok(oeg_files::read_bounded(path, limit)?)
}

/// The files of `dir` whose extension is `extension`, sorted by name (a data set's frames, numbered).
///
/// # Errors
/// [`crate::Error::Io`] for a folder that cannot be listed, [`crate::Error::Parse`] when it holds no such file.
pub(crate) fn sorted_files(dir: &Path, extension: &str) -> Result<Vec<PathBuf>> {
    let io = |source| crate::Error::Io {
        path: dir.to_path_buf(),
        source,
    };
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(io)? {
        let path = entry.map_err(io)?.path();
        if path.extension().is_some_and(|e| e == extension) {
            files.push(path);
        }
    }
    files.sort();
    if files.is_empty() {
        return Err(crate::Error::parse(
            dir,
            format!("no .{extension} file in the folder"),
        ));
    }
    Ok(files)
}
