//! What `oeg map` reads: each input's format, its size against the memory limit, and its scans with where each
//! came from.

use std::path::{Path, PathBuf};

use oeg::Scan;

use super::MapJob;
use crate::error::{EvalError, Result};

/// The kinds of input `oeg map` reads, by file extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputFormat {
    /// `.graph`: OctoMap scan graph, one scan per node.
    Graph,
    /// `.pcd`: one point cloud, one scan.
    Pcd,
    /// `.oeglog`: a recorded sensor log (`oeg record`), one scan per record.
    Log,
    /// A ROS 2 bag: its `.mcap` file (recognised by its first bytes) or its folder with `metadata.yaml`; one
    /// scan per `PointCloud2` or `LaserScan` message ([`oeg::read_bag`]).
    Bag,
    /// A KITTI odometry sequence's folder (`velodyne/*.bin`, its poses, `calib.txt`): one scan per `.bin`
    /// ([`oeg::read_kitti`]).
    Kitti,
    /// A sequence of the DynamicMap benchmark's unified format: a folder with `pcd/*.pcd`, each frame's points
    /// in the world frame and the sensor's pose in `VIEWPOINT`; one scan per frame, in name order.
    DynamicMap,
}

/// The first bytes of an MCAP file.
const MCAP_MAGIC: &[u8] = b"\x89MCAP0\r\n";

impl InputFormat {
    /// How many times its size a file of this format takes in memory while it is mapped, at most: its bytes,
    /// its records as read and the scans made of them (24 bytes a ray). A graph's point is 24 bytes in the file,
    /// a log's ray 17, a binary PCD point 12 (ascii more), a bag's point 12 or more, and a compressed chunk
    /// is held decompressed while it is read.
    pub fn memory_factor(self) -> u64 {
        match self {
            Self::Graph => 3,
            Self::Log => 4,
            Self::Pcd => 5,
            Self::Bag => 6,
            // 16 bytes a point in the file, a 24-byte ray in memory.
            Self::Kitti => 3,
            Self::DynamicMap => 5,
        }
    }

    /// The format of `path`: a sensor log or an MCAP file by its magic bytes whatever its name; a folder with a
    /// `metadata.yaml` as a ROS 2 bag, with `velodyne/` as a KITTI sequence, with `pcd/` as a DynamicMap
    /// sequence; anything else by its extension.
    ///
    /// # Errors
    /// [`EvalError::Input`] for a file that is not a sensor log and has another extension.
    pub fn of(path: &Path) -> Result<Self> {
        if starts_with(path, sim::log::MAGIC) {
            return Ok(Self::Log);
        }
        if starts_with(path, MCAP_MAGIC) || path.join("metadata.yaml").is_file() {
            return Ok(Self::Bag);
        }
        if path.join("velodyne").is_dir() {
            return Ok(Self::Kitti);
        }
        if path.join("pcd").is_dir() {
            return Ok(Self::DynamicMap);
        }
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("graph") => Ok(Self::Graph),
            Some("pcd") => Ok(Self::Pcd),
            Some("oeglog") => Ok(Self::Log),
            _ => Err(EvalError::Input {
                path: path.to_path_buf(),
                message:
                    "unknown input format: expected an OctoMap scan graph (.graph), a point cloud (.pcd), \
                          a sensor log (`oeg record`'s, recognised by its first bytes), a ROS 2 bag (its \
                          .mcap file, or its folder with metadata.yaml), a KITTI sequence's folder (with \
                          velodyne/) or a DynamicMap sequence's folder (with pcd/)"
                        .into(),
            }),
        }
    }
}

/// Whether the file at `path` begins with `magic` (false for a file that cannot be read: its reader says why).
fn starts_with(path: &Path, magic: &[u8]) -> bool {
    use std::io::Read;
    let mut head = vec![0u8; magic.len()];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut head))
        .is_ok_and(|()| head == magic)
}

/// Where a scan came from: its file and its place in it, for errors while it is integrated.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanSource {
    /// The input file.
    pub file: PathBuf,
    /// The scan's place in the file: `node 3 (id 17)`, `the cloud`, `scan 5 of sensor lidar at 1.20 s`.
    pub place: String,
}

/// The inputs as scans, each with its [`ScanSource`], and the bags' messages that were not mapped.
#[derive(Debug, Clone, Default)]
pub struct Inputs {
    /// The scans, in the inputs' order.
    pub scans: Vec<(ScanSource, Scan)>,
    /// Range messages of a bag skipped for a missing transform or no valid reading, with their bag.
    pub skipped: Vec<(PathBuf, oeg::BagSkip)>,
    /// Where the robot stood at the start of each sensor log that records it, at the job's pose, with its log.
    pub stances: Vec<(PathBuf, oeg::Stance)>,
}

/// The bytes `path` holds: a file's size, or the regular files of a folder input's data folder together (a bag's
/// own folder, a KITTI sequence's `velodyne/`, a DynamicMap sequence's `pcd/`).
fn input_bytes(path: &Path, format: InputFormat) -> Result<u64> {
    let io = |source| EvalError::Io {
        path: path.to_path_buf(),
        source,
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    if meta.is_dir() {
        let data = match format {
            InputFormat::Kitti => path.join("velodyne"),
            InputFormat::DynamicMap => path.join("pcd"),
            _ => path.to_path_buf(),
        };
        let mut total = 0_u64;
        for entry in std::fs::read_dir(&data).map_err(io)? {
            let meta = entry.map_err(io)?.metadata().map_err(io)?;
            if meta.is_file() {
                total = total.saturating_add(meta.len());
            }
        }
        return Ok(total);
    }
    // A device or a pipe has no size to check (`/dev/zero` would be read until memory runs out).
    if !meta.is_file() {
        return Err(EvalError::Input {
            path: path.to_path_buf(),
            message:
                "is not a regular file (a device or a pipe); `oeg map` checks each input's size against the \
                      memory limit before reading it, so save the data to a file first"
                    .into(),
        });
    }
    Ok(meta.len())
}

/// Reads every input into scans, each with its [`ScanSource`], before anything is written, so a bad input
/// leaves no partial output.
///
/// # Errors
/// The first unreadable or malformed input, named, and inputs that would not fit the memory limit.
pub fn read_inputs(job: &MapJob) -> Result<Inputs> {
    let mut inputs = Inputs::default();
    let source = |path: &Path, place: String| ScanSource {
        file: path.to_path_buf(),
        place,
    };
    // Every scan is held until the map is built: a few times the inputs' bytes (`InputFormat::memory_factor`).
    // Refused before anything is read when that is over the memory limit.
    let limit = job.config.memory_limit_bytes;
    let formats = job
        .inputs
        .iter()
        .map(|path| InputFormat::of(path))
        .collect::<Result<Vec<_>>>()?;
    let mut held = 0_u64;
    for (path, format) in job.inputs.iter().zip(&formats) {
        let bytes = input_bytes(path, *format)?;
        let factor = format.memory_factor();
        held = held.saturating_add(bytes.saturating_mul(factor));
        if held > limit {
            return Err(EvalError::Input {
                path: path.clone(),
                message: format!(
                    "the inputs up to this one would take about {held} bytes in memory (this one {factor} times \
                     its size), over the memory limit of {limit} bytes; map fewer files at once or raise \
                     --memory-limit-mib"
                ),
            });
        }
    }
    let scans = &mut inputs.scans;
    for (path, format) in job.inputs.iter().zip(formats) {
        match format {
            InputFormat::Graph => scans.extend(oeg::read_graph(path)?.iter().enumerate().map(|(k, n)| {
                (
                    source(path, format!("node {k} (id {})", n.id)),
                    n.to_scan(job.graph_sensor),
                )
            })),
            InputFormat::Pcd => scans.push((
                source(path, "the cloud".into()),
                oeg::read_pcd_scan_within(path, &job.pcd, limit)?,
            )),
            InputFormat::Log => {
                let log = sim::log::read_log(path)?;
                if let Some(record) = &log.header.stance {
                    let fail = |message: String| EvalError::Input {
                        path: path.clone(),
                        message: format!("the header's stance: {message}"),
                    };
                    let stance = record.stance(job.log_pose).map_err(|m| fail(m.to_string()))?;
                    if let Some(s) = &stance {
                        s.validate().map_err(|e| fail(e.to_string()))?;
                    }
                    inputs.stances.extend(stance.map(|s| (path.clone(), s)));
                }
                scans.extend(log.scans.iter().map(|s| {
                    let sensor = &log.header.sensors[s.sensor_index];
                    (
                        source(
                            path,
                            format!(
                                "scan {} of sensor {} at {:.3} s",
                                s.scan_index, sensor.name, s.stamp_s
                            ),
                        ),
                        s.to_scan(job.log_pose, sensor.map_model),
                    )
                }));
            }
            InputFormat::Bag => {
                let bag = oeg::read_bag_within(path, &job.bag, limit)?;
                scans.extend(bag.scans.into_iter().map(|s| {
                    let place = format!("message {} of {} at {:.3} s", s.index, s.topic, s.scan.stamp_s);
                    (source(path, place), s.scan)
                }));
                inputs
                    .skipped
                    .extend(bag.skipped.into_iter().map(|s| (path.clone(), s)));
            }
            InputFormat::DynamicMap | InputFormat::Kitti => {
                let read = if format == InputFormat::Kitti {
                    oeg::read_kitti(path, job.graph_sensor, limit)?
                } else {
                    oeg::read_dynamicmap(path, job.graph_sensor, limit)?
                };
                scans.extend(read.into_iter().map(|(file, scan)| {
                    let name = file.file_name().unwrap_or_default().to_string_lossy().to_string();
                    (source(path, format!("frame {name}")), scan)
                }));
            }
        }
    }
    Ok(inputs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::write_bytes;

    #[test]
    fn formats_come_from_the_extension() {
        assert_eq!(
            InputFormat::of(Path::new("a/b.graph")).expect("graph"),
            InputFormat::Graph
        );
        assert_eq!(
            InputFormat::of(Path::new("B.PCD")).expect("pcd"),
            InputFormat::Pcd
        );
        let err = InputFormat::of(Path::new("scan.bt"))
            .expect_err("unknown")
            .to_string();
        assert!(err.contains("scan.bt") && err.contains(".graph"), "{err}");
    }

    #[test]
    fn a_sensor_log_is_recognised_by_its_magic_bytes_whatever_its_name() {
        let dir = crate::test_support::scratch_dir("map", "magic");
        let (no_extension, named_graph) = (dir.join("recorded"), dir.join("log.graph"));
        for path in [&no_extension, &named_graph] {
            write_bytes(path, &[&sim::log::MAGIC[..], b"rest of a log"].concat()).expect("write");
            assert_eq!(InputFormat::of(path).expect("log"), InputFormat::Log);
        }
        // Seven bytes of the magic are not a log.
        write_bytes(&no_extension, &sim::log::MAGIC[..7]).expect("write");
        assert!(InputFormat::of(&no_extension).is_err());
    }
}
