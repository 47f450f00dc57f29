//! OctoMap scan graphs (`.graph`): the format of OctoMap's `graph2tree` and of the FR-079, Freiburg campus and
//! New College data sets.
//!
//! Binary, little-endian, no header:
//!
//! ```text
//! u32 num_nodes
//! num_nodes times:
//!   u32 num_points
//!   num_points times: i32 (= 3), f64 x, f64 y, f64 z             point in the node (sensor) frame
//!   i32 (= 3), f64 tx, ty, tz, i32 (= 4), f64 qw, qx, qy, qz       world_from_sensor pose
//!   u32 node_id
//! u32 num_edges
//! num_edges times: u32 from, u32 to, pose (as above), f64 weight
//! ```
//!
//! Each node becomes one [`Scan`] whose origin is the pose's translation and whose rays end at
//! `world_from_sensor * p`. The format has no no-return rays.

use std::path::Path;

use nalgebra::{Isometry3, Point3, Translation3, Vector3};

use super::{ByteReader, read_file, unit_quaternion, write_atomically};
use crate::error::Result;
use crate::scan::{Ray, RayKind, Scan};
use crate::sensor::SensorModel;

/// Bytes of one point record.
const POINT_BYTES: usize = 4 + 3 * 8;
/// Bytes of one pose record.
const POSE_BYTES: usize = 4 + 3 * 8 + 4 + 4 * 8;

/// One node of a scan graph: a pose and its points in the sensor frame.
#[derive(Debug, Clone, PartialEq)]
pub struct GraphNode {
    /// The node's id.
    pub id: u32,
    /// `world_from_sensor`.
    pub world_from_sensor: Isometry3<f64>,
    /// Points in the sensor frame, metres.
    pub points_in_sensor: Vec<Point3<f64>>,
}

impl GraphNode {
    /// The node as a scan: origin at the pose, one hit per point.
    pub fn to_scan(&self, sensor: SensorModel) -> Scan {
        let mut scan = Scan::new(Point3::from(self.world_from_sensor.translation.vector), sensor);
        scan.rays.reserve(self.points_in_sensor.len());
        for p in &self.points_in_sensor {
            scan.push_hit(self.world_from_sensor * p);
        }
        scan
    }
}

/// Reads every node of a scan graph. Edges are checked for truncation and otherwise ignored.
///
/// # Errors
/// [`Error::Io`](crate::Error::Io) if the file cannot be read; [`Error::Parse`](crate::Error::Parse) naming the byte offset, node and point for a
/// truncated file, a wrong record tag, a count larger than the file, a non-finite number or a zero quaternion.
pub fn read_graph(path: &Path) -> Result<Vec<GraphNode>> {
    let data = read_file(path, crate::DEFAULT_MEMORY_LIMIT_BYTES)?;
    parse_graph(path, &data)
}

/// Reads a scan graph and converts each node with [`GraphNode::to_scan`].
///
/// # Errors
/// As [`read_graph`].
pub fn read_graph_scans(path: &Path, sensor: SensorModel) -> Result<Vec<Scan>> {
    Ok(read_graph(path)?.iter().map(|n| n.to_scan(sensor)).collect())
}

/// Reads a scan graph from its bytes (`path` names it in errors).
///
/// # Errors
/// As [`read_graph`], but for reading the file.
pub fn parse_graph(path: &Path, data: &[u8]) -> Result<Vec<GraphNode>> {
    let mut r = ByteReader::new(path, data);
    let num_nodes = r.u32("the node count")? as usize;
    // Each node holds at least its point count, pose and id.
    if num_nodes.saturating_mul(4 + POSE_BYTES + 4) > r.remaining() {
        return Err(r.error(format!(
            "the file declares {num_nodes} nodes but holds only {} more bytes: not a scan graph, or truncated",
            r.remaining()
        )));
    }
    let mut nodes = Vec::with_capacity(num_nodes);
    for node in 0..num_nodes {
        let num_points = r.u32(format_args!("the point count of node {node}"))? as usize;
        if num_points.saturating_mul(POINT_BYTES) > r.remaining() {
            return Err(r.error(format!(
                "node {node} declares {num_points} points ({} bytes) but only {} bytes remain: truncated",
                num_points.saturating_mul(POINT_BYTES),
                r.remaining()
            )));
        }
        let mut points = Vec::with_capacity(num_points);
        for k in 0..num_points {
            let v = read_vector3(&mut r, &PointName { node, point: k })?;
            points.push(Point3::from(v));
        }
        let pose = read_pose(&mut r, &format_args!("the pose of node {node}"))?;
        let id = r.u32(format_args!("the id of node {node}"))?;
        nodes.push(GraphNode {
            id,
            world_from_sensor: pose,
            points_in_sensor: points,
        });
    }
    // The edges carry no rays; read them only to catch truncation.
    if r.remaining() > 0 {
        let num_edges = r.u32("the edge count")? as usize;
        for e in 0..num_edges {
            let what = format_args!("edge {e}");
            r.take(8, what)?;
            read_pose(&mut r, &what)?;
            r.f64(what)?;
        }
    }
    Ok(nodes)
}

/// Names a point in errors, formatted only when an error is reported.
struct PointName {
    node: usize,
    point: usize,
}

impl std::fmt::Display for PointName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "point {} of node {}", self.point, self.node)
    }
}

type What<'a> = &'a dyn std::fmt::Display;

fn expect_tag(r: &mut ByteReader<'_>, expected: i32, what: What<'_>) -> Result<()> {
    let at = r.pos();
    let tag = r.i32(what)?;
    if tag != expected {
        return Err(r.error_at(
            at,
            format!("expected the vector length {expected} before {what}, found {tag}"),
        ));
    }
    Ok(())
}

fn finite(r: &ByteReader<'_>, v: f64, what: What<'_>) -> Result<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(r.error(format!("{what} holds the non-finite number {v}")))
    }
}

fn read_vector3(r: &mut ByteReader<'_>, what: What<'_>) -> Result<Vector3<f64>> {
    expect_tag(r, 3, what)?;
    let x = r.f64(what)?;
    let y = r.f64(what)?;
    let z = r.f64(what)?;
    Ok(Vector3::new(
        finite(r, x, what)?,
        finite(r, y, what)?,
        finite(r, z, what)?,
    ))
}

fn read_pose(r: &mut ByteReader<'_>, what: What<'_>) -> Result<Isometry3<f64>> {
    let t = read_vector3(r, what)?;
    expect_tag(r, 4, what)?;
    let mut q = [0.0; 4];
    for v in &mut q {
        *v = r.f64(what)?;
        finite(r, *v, what)?;
    }
    let rotation = unit_quaternion(q[0], q[1], q[2], q[3])
        .ok_or_else(|| r.error::<crate::Error>(format!("{what} has a zero rotation quaternion")))?;
    Ok(Isometry3::from_parts(Translation3::from(t), rotation))
}

/// Writes scans as a scan graph: one node per scan, the identity rotation, the origin as translation and each
/// hit as a point. No-return rays cannot be expressed and are left out; the count of left-out rays is
/// returned. No edges are written.
///
/// # Errors
/// [`Error::Io`](crate::Error::Io) naming the file.
pub fn write_graph(path: &Path, scans: &[Scan]) -> Result<u64> {
    let mut out = Vec::new();
    let mut num_left_out = 0u64;
    out.extend_from_slice(&(scans.len() as u32).to_le_bytes());
    for (id, scan) in scans.iter().enumerate() {
        let hits: Vec<&Ray> = scan.rays.iter().filter(|r| r.kind == RayKind::Hit).collect();
        num_left_out += (scan.rays.len() - hits.len()) as u64;
        out.extend_from_slice(&(hits.len() as u32).to_le_bytes());
        for ray in hits {
            put_vector3(&mut out, &ray.offset_in_world.cast());
        }
        put_vector3(&mut out, &scan.origin_in_world.coords);
        out.extend_from_slice(&4i32.to_le_bytes());
        for v in [1.0f64, 0.0, 0.0, 0.0] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.extend_from_slice(&(id as u32).to_le_bytes());
    }
    out.extend_from_slice(&0u32.to_le_bytes());
    write_atomically(path, &out)?;
    Ok(num_left_out)
}

fn put_vector3(out: &mut Vec<u8>, v: &Vector3<f64>) {
    out.extend_from_slice(&3i32.to_le_bytes());
    for c in v.iter() {
        out.extend_from_slice(&c.to_le_bytes());
    }
}

#[cfg(test)]
#[allow(clippy::disallowed_methods, reason = "tests read back the files they wrote")]
mod tests {
    use super::*;

    fn temp(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("oeg-graph-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        dir.join("scans.graph")
    }

    fn two_scans() -> Vec<Scan> {
        let mut a = Scan::new(Point3::new(1.0, 2.0, 0.5), SensorModel::laser());
        a.push_hit(Point3::new(3.0, 2.0, 0.0));
        a.push_hit(Point3::new(1.0, 5.0, 1.0));
        a.rays.push(Ray::no_return(Vector3::new(0.0, 0.0, 1.0)));
        let mut b = Scan::new(Point3::new(-1.0, 0.0, 0.3), SensorModel::laser());
        b.push_hit(Point3::new(-2.0, -1.0, 0.0));
        vec![a, b]
    }

    #[test]
    fn written_graphs_read_back() {
        let path = temp("roundtrip");
        let scans = two_scans();
        assert_eq!(write_graph(&path, &scans).expect("written"), 1);
        let back = read_graph_scans(&path, SensorModel::laser()).expect("read");
        assert_eq!(back.len(), 2);
        assert_eq!(back[0].origin_in_world, scans[0].origin_in_world);
        assert_eq!(back[0].rays.len(), 2);
        for (a, b) in back[0].rays.iter().zip(&scans[0].rays) {
            assert!((a.offset_in_world - b.offset_in_world).norm() < 1e-6);
        }
        assert_eq!(back[1].rays.len(), 1);
    }

    #[test]
    fn poses_are_applied() {
        // One point 1 m ahead of a sensor at (10, 0, 1) turned 90 degrees left lands at (10, 1, 1).
        let mut data = Vec::new();
        data.extend_from_slice(&1u32.to_le_bytes());
        data.extend_from_slice(&1u32.to_le_bytes());
        put_vector3(&mut data, &Vector3::new(1.0, 0.0, 0.0));
        put_vector3(&mut data, &Vector3::new(10.0, 0.0, 1.0));
        data.extend_from_slice(&4i32.to_le_bytes());
        let h = std::f64::consts::FRAC_PI_4;
        for v in [h.cos(), 0.0, 0.0, h.sin()] {
            data.extend_from_slice(&v.to_le_bytes());
        }
        data.extend_from_slice(&7u32.to_le_bytes());
        let nodes = parse_graph(Path::new("mem.graph"), &data).expect("valid");
        assert_eq!(nodes[0].id, 7);
        let scan = nodes[0].to_scan(SensorModel::laser());
        let end = scan.origin_in_world + scan.rays[0].offset_in_world.cast::<f64>();
        assert!((end - Point3::new(10.0, 1.0, 1.0)).norm() < 1e-6, "{end}");
    }

    #[test]
    fn truncated_graphs_are_errors_at_every_cut() {
        let path = temp("truncated");
        write_graph(&path, &two_scans()).expect("written");
        let data = std::fs::read(&path).expect("read");
        // Every strict prefix (except the one that drops only the optional edge count) is an error.
        for cut in 0..data.len() - 4 {
            let err = parse_graph(Path::new("cut.graph"), &data[..cut]).expect_err("truncated");
            assert!(
                err.to_string().starts_with("cut.graph: at byte"),
                "cut {cut}: {err}"
            );
        }
    }

    #[test]
    fn absurd_counts_are_rejected_before_allocating() {
        let mut data = Vec::new();
        data.extend_from_slice(&u32::MAX.to_le_bytes());
        let err = parse_graph(Path::new("big.graph"), &data).expect_err("absurd");
        assert!(err.to_string().contains("declares 4294967295 nodes"), "{err}");
        let mut data = vec![];
        data.extend_from_slice(&1u32.to_le_bytes());
        data.extend_from_slice(&(1u32 << 30).to_le_bytes());
        data.extend_from_slice(&[0u8; 80]);
        let err = parse_graph(Path::new("big.graph"), &data).expect_err("absurd");
        assert!(
            err.to_string().contains("node 0 declares 1073741824 points"),
            "{err}"
        );
    }

    #[test]
    fn non_finite_points_and_bad_tags_are_errors() {
        let path = temp("nan");
        let mut scans = two_scans();
        scans[1].rays[0].offset_in_world.x = f32::NAN;
        write_graph(&path, &scans).expect("written");
        let err = read_graph(&path).expect_err("NaN point");
        assert!(
            err.to_string().contains("point 0 of node 1") && err.to_string().contains("non-finite"),
            "{err}"
        );

        let mut data = std::fs::read(&path).expect("read");
        data[8] = 9; // the first point's tag
        let err = parse_graph(Path::new("tag.graph"), &data).expect_err("bad tag");
        assert!(err.to_string().contains("expected the vector length 3"), "{err}");
    }
}
