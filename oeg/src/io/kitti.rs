//! KITTI odometry sequences: `velodyne/NNNNNN.bin` (float32 `x y z reflectance` a point, in the lidar's frame),
//! one pose a scan (12 numbers a line: the left camera's 3 x 4 pose `[R | t]` in the first camera's frame, row
//! by row) and `calib.txt`'s `Tr:` (the lidar in the camera's frame). The lidar's pose of scan `k` is
//! `Tr^-1 P_k Tr`: the world is the first scan's lidar frame (x forward, y left, z up), as KISS-ICP and
//! SemanticKITTI's tools read it.
//!
//! The poses are `poses.txt` in the sequence's folder (SemanticKITTI's layout), or `poses/NN.txt` beside the
//! `sequences` folder (the odometry benchmark's).

use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};

use super::{read_file, sorted_files};
use crate::error::{Error, Result};
use crate::scan::Scan;
use crate::sensor::SensorModel;

/// Bytes of one point of a `.bin` scan.
const POINT_BYTES: usize = 16;

/// A KITTI sequence's scans, in the order of their files, each named by its file.
///
/// # Errors
/// [`Error::Io`] for a file that cannot be read; [`Error::Parse`] naming the file and line of a malformed pose
/// or calibration, a scan file whose size is not a whole number of points, fewer poses than scans, or scans
/// that together exceed `limit_bytes`.
pub fn read_kitti(folder: &Path, sensor: SensorModel, limit_bytes: u64) -> Result<Vec<(PathBuf, Scan)>> {
    let scans = kitti_scan_files(folder)?;
    let poses_path = poses_file(folder)?;
    let poses = parse_poses(
        &poses_path,
        &String::from_utf8_lossy(&read_file(&poses_path, 64 << 20)?),
    )?;
    if poses.len() < scans.len() {
        return Err(Error::parse(
            &poses_path,
            format!(
                "{} poses for {} scans in {}",
                poses.len(),
                scans.len(),
                folder.join("velodyne").display()
            ),
        ));
    }
    let calib_path = folder.join("calib.txt");
    let tr = parse_tr(
        &calib_path,
        &String::from_utf8_lossy(&read_file(&calib_path, 1 << 20)?),
    )?;
    let mut left = limit_bytes;
    let mut out = Vec::with_capacity(scans.len());
    for (file, camera_pose) in scans.into_iter().zip(poses) {
        let bytes = read_file(&file, left)?;
        left = left.saturating_sub(bytes.len() as u64);
        let pose = tr.inverse() * camera_pose * tr;
        let scan = parse_bin(&file, &bytes, pose, sensor)?;
        out.push((file, scan));
    }
    Ok(out)
}

/// Scan `index` of a sequence from its files' contents: the poses' and the calibration's text and the scan's
/// bytes, each named by `path` in errors (what [`read_kitti`] does for every scan, from memory).
///
/// # Errors
/// [`Error::Parse`] for a malformed pose or calibration, no pose `index`, or bytes that are not whole points.
pub fn parse_kitti_scan(
    path: &Path,
    poses: &str,
    calib: &str,
    index: usize,
    bin: &[u8],
    sensor: SensorModel,
) -> Result<Scan> {
    let poses = parse_poses(path, poses)?;
    let tr = parse_tr(path, calib)?;
    let camera = poses
        .get(index)
        .ok_or_else(|| Error::parse(path, format!("no pose {index}: the file has {}", poses.len())))?;
    parse_bin(path, bin, tr.inverse() * camera * tr, sensor)
}

/// The `.bin` files of `folder/velodyne`, sorted by name.
///
/// # Errors
/// [`Error::Io`] for a folder that cannot be listed, [`Error::Parse`] when it holds no `.bin` file.
pub fn kitti_scan_files(folder: &Path) -> Result<Vec<PathBuf>> {
    sorted_files(&folder.join("velodyne"), "bin")
}

/// `poses.txt` in the sequence's folder, else `poses/<sequence>.txt` two folders up.
fn poses_file(folder: &Path) -> Result<PathBuf> {
    let own = folder.join("poses.txt");
    if own.is_file() {
        return Ok(own);
    }
    let name = folder
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    let beside = folder.join("../../poses").join(format!("{name}.txt"));
    if beside.is_file() {
        return Ok(beside);
    }
    Err(Error::parse(
        folder,
        format!("no poses: neither {} nor {}", own.display(), beside.display()),
    ))
}

/// Twelve numbers as a 3 x 4 `[R | t]`, row by row; the rotation made orthonormal (the files round it).
/// `None` when the rotation part is no rotation (far from orthonormal, or too large to make one of).
fn pose_of(v: &[f64]) -> Option<Isometry3<f64>> {
    let r = Matrix3::new(v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10]);
    // A rotation rounded to the file's digits (KITTI writes six or more) is orthonormal to 1e-5 or better. The
    // iterations are bounded: nalgebra's default loops until it converges, which a garbage matrix never does.
    let rotation = Rotation3::from_matrix_eps(&r, 1e-12, 100, Rotation3::identity());
    let orthonormal = (r - rotation.matrix()).norm() < 1e-2;
    (orthonormal && rotation.matrix().iter().all(|x| x.is_finite())).then(|| {
        Isometry3::from_parts(
            Translation3::new(v[3], v[7], v[11]),
            UnitQuaternion::from_rotation_matrix(&rotation),
        )
    })
}

const NOT_A_ROTATION: &str = "the 3 x 3 part is not a rotation (its rows are not orthonormal)";

/// Twelve finite numbers from `text`, or what is wrong with them.
fn twelve(text: &str) -> std::result::Result<Vec<f64>, String> {
    let v: Vec<f64> = text
        .split_whitespace()
        .map(|t| t.parse::<f64>().map_err(|_| format!("`{t}` is not a number")))
        .collect::<std::result::Result<_, _>>()?;
    if v.len() != 12 {
        return Err(format!("{} numbers, where a 3 x 4 matrix has 12", v.len()));
    }
    if let Some(x) = v.iter().find(|x| !x.is_finite()) {
        return Err(format!("{x}, where a finite number is expected"));
    }
    Ok(v)
}

fn parse_poses(path: &Path, text: &str) -> Result<Vec<Isometry3<f64>>> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(k, l)| {
            twelve(l)
                .and_then(|v| pose_of(&v).ok_or_else(|| NOT_A_ROTATION.to_string()))
                .map_err(|e| Error::parse(path, format!("line {}: {e}", k + 1)))
        })
        .collect()
}

/// `Tr:` of a calibration file: the lidar in the camera's frame.
fn parse_tr(path: &Path, text: &str) -> Result<Isometry3<f64>> {
    let (k, line) = text
        .lines()
        .enumerate()
        .find(|(_, l)| l.trim_start().starts_with("Tr:"))
        .ok_or_else(|| Error::parse(path, "no `Tr:` line (the lidar's pose in the camera's frame)"))?;
    let rest = line.trim_start().trim_start_matches("Tr:");
    twelve(rest)
        .and_then(|v| pose_of(&v).ok_or_else(|| NOT_A_ROTATION.to_string()))
        .map_err(|e| Error::parse(path, format!("line {}: {e}", k + 1)))
}

/// One `.bin` scan placed at `world_from_lidar`: a hit a point, points with a non-finite coordinate or at the
/// sensor left out.
fn parse_bin(
    path: &Path,
    bytes: &[u8],
    world_from_lidar: Isometry3<f64>,
    sensor: SensorModel,
) -> Result<Scan> {
    if !bytes.len().is_multiple_of(POINT_BYTES) {
        return Err(Error::parse(
            path,
            format!(
                "{} bytes, not a whole number of 16-byte points (x y z reflectance, float32): truncated?",
                bytes.len()
            ),
        ));
    }
    let mut scan = Scan::new(Point3::from(world_from_lidar.translation.vector), sensor);
    scan.rays.reserve(bytes.len() / POINT_BYTES);
    for point in bytes.chunks_exact(POINT_BYTES) {
        let c = |k: usize| {
            let mut b = [0u8; 4];
            b.copy_from_slice(&point[4 * k..4 * k + 4]);
            f64::from(f32::from_le_bytes(b))
        };
        let p = Vector3::new(c(0), c(1), c(2));
        if p.iter().all(|v| v.is_finite()) && p != Vector3::zeros() {
            scan.push_hit(world_from_lidar * Point3::from(p));
        }
    }
    Ok(scan)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pose_line_reads_and_a_bad_one_names_its_line() {
        let text = "1 0 0 1 0 1 0 2 0 0 1 3\n\n1 0 0 0 0 1 0 0 0 0 1 x\n";
        let e = parse_poses(Path::new("poses.txt"), text)
            .expect_err("refused")
            .to_string();
        assert!(e.contains("line 3") && e.contains("`x`"), "{e}");
        let poses = parse_poses(Path::new("poses.txt"), "1 0 0 1 0 1 0 2 0 0 1 3\n").expect("reads");
        assert_eq!(poses[0].translation.vector, Vector3::new(1.0, 2.0, 3.0));
        assert!(parse_tr(Path::new("calib.txt"), "P0: 1 2 3\n").is_err());
    }

    #[test]
    fn a_lidar_pose_is_the_camera_pose_seen_through_the_calibration() {
        // KITTI's calibration turns the camera (z forward, x right, y down) into the lidar (x forward, y
        // left, z up); a camera moving 1 m along its z moves the lidar 1 m along its x.
        let tr =
            pose_of(&[0.0, -1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0]).expect("a rotation");
        let camera = Isometry3::translation(0.0, 0.0, 1.0);
        let lidar = tr.inverse() * camera * tr;
        assert!((lidar.translation.vector - Vector3::new(1.0, 0.0, 0.0)).norm() < 1e-12);
        let truncated = parse_bin(Path::new("000000.bin"), &[0; 17], lidar, SensorModel::laser());
        assert!(truncated.expect_err("refused").to_string().contains("16-byte"));
    }
}
