"""ROS 2 bags against independent tools: the `rosbags` package reads what `oeg record --format rosbag2` writes,
and writes the bags (LaserScan, PointCloud2 with extra fields, Odometry, /tf_static) that `oeg map` reads; the
`mcap` package writes the same messages in zstd and lz4 chunks, which map to the same bytes.

Both packages are pure Python (`pip install rosbags mcap`); without them these tests skip with the reason.
"""

from __future__ import annotations

import json
import math
import struct
from pathlib import Path
from typing import Any, List, Tuple

import numpy as np
import pytest

from _cli import ROOT, oeg_binary, run_cli

rosbag2 = pytest.importorskip("rosbags.rosbag2", reason="the rosbags package is not installed (pip install rosbags)")
typesys = pytest.importorskip("rosbags.typesys", reason="the rosbags package is not installed (pip install rosbags)")

TS = typesys.get_typestore(typesys.Stores.ROS2_HUMBLE)
TS_ANY: Any = None


def _fails(*args: str) -> str:
    """Runs `oeg` expecting it to fail; returns what it printed to stderr."""
    import subprocess

    done = subprocess.run([str(oeg_binary()), *args], capture_output=True, text=True, cwd=ROOT)
    assert done.returncode != 0, done.stdout
    assert "panicked" not in done.stderr, done.stderr
    return done.stderr


def _summary(folder: Path) -> Any:
    return json.loads((folder / "summary.json").read_text())


def test_a_recorded_bag_reads_in_rosbags_with_its_clouds_and_transforms(tmp_path: Path) -> None:
    bag = tmp_path / "corridor"
    out = run_cli("record", "scenarios/corridor_lasers.toml", "--format", "rosbag2", "--out", str(bag))
    num_rays = int(out.split(" scans, ")[1].split(" rays")[0])
    points = 0
    frames = set()
    with rosbag2.Reader(bag) as reader:
        topics = {c.topic: c.msgtype for c in reader.connections}
        assert topics["/laser_left/points"] == "sensor_msgs/msg/PointCloud2"
        assert topics["/tf"] == topics["/tf_static"] == "tf2_msgs/msg/TFMessage"
        # The offered QoS, as rosbags parses rosbag2's metadata: the static transforms transient local (what
        # tf2's static listener asks for when the bag is played back), the rest reliable and volatile.
        qos = {c.topic: c.ext.offered_qos_profiles[0] for c in reader.connections}
        assert qos["/tf_static"].durability.name == "TRANSIENT_LOCAL"
        assert {q.durability.name for t, q in qos.items() if t != "/tf_static"} == {"VOLATILE"}
        assert {q.reliability.name for q in qos.values()} == {"RELIABLE"}
        for conn, _, raw in reader.messages(connections=[c for c in reader.connections if not c.topic.startswith("/truth")]):
            msg = TS.deserialize_cdr(raw, conn.msgtype)
            if conn.msgtype.endswith("PointCloud2"):
                # x, y, z and each reading's range error; corridor_lasers' lasers return every beam, so no
                # cleared-end fields.
                assert msg.point_step == 16 and [f.name for f in msg.fields] == ["x", "y", "z", "range_sigma"]
                sigma = np.frombuffer(bytes(msg.data), dtype="<f4").reshape(-1, 4)[:, 3]
                assert np.all(np.isfinite(sigma)) and np.all(sigma > 0.0)
                points += msg.width * msg.height
            else:
                frames |= {(t.header.frame_id, t.child_frame_id) for t in msg.transforms}
    # corridor_lasers' lasers return every beam: each ray is a point.
    assert points == num_rays
    # The truth at the end, as a GridMap (its type read from the bag's own schema) and an OccupancyGrid that
    # agree: a truly blocked cell is 0 in `traversability` and 100 in the occupancy grid.
    with rosbag2.Reader(bag) as reader:
        ts = typesys.get_typestore(typesys.Stores.ROS2_HUMBLE)
        grid_conn = next(c for c in reader.connections if c.topic == "/truth/grid_map")
        ts.register(typesys.get_types_from_msg(grid_conn.msgdef.data, grid_conn.msgtype))
        truth = {c.topic: TS_ANY for c in reader.connections if c.topic.startswith("/truth")}
        for conn, _, raw in reader.messages(connections=[c for c in reader.connections if c.topic in truth]):
            truth[conn.topic] = ts.deserialize_cdr(raw, conn.msgtype)
    grid, occupancy = truth["/truth/grid_map"], truth["/truth/occupancy"]
    assert grid.layers == ["elevation", "traversability"]
    blocked_in_grid = int(np.count_nonzero(grid.data[1].data == 0.0))
    assert blocked_in_grid == int(np.count_nonzero(occupancy.data == 100)) > 0
    assert occupancy.info.width * occupancy.info.height == grid.data[0].data.size
    expected = {("map", "odom"), ("odom", "base_link"), ("base_link", "base_footprint"), ("base_link", "laser_left")}
    assert expected <= frames
    # Mapped in the odom frame (the estimated pose) with the scenario's model, the bag gives the map of the
    # testbed's own log of the same scans (the run's map), byte for byte.
    log = tmp_path / "corridor.oeglog"
    run_cli("record", "scenarios/corridor_lasers.toml", "--out", str(log))
    model = ["--set", "map.model.max_height_m=0.5", "--set", "map.model.no_return_clear_range_m=8.0"]
    run_cli("map", str(bag), "--resolution", "0.05", "--out", str(tmp_path / "from_bag"), "--set", 'input.bag.map_frame="odom"', *model)
    run_cli("map", str(log), "--resolution", "0.05", "--out", str(tmp_path / "from_log"), *model)
    assert _summary(tmp_path / "from_bag")["num_rays"] == num_rays
    assert (tmp_path / "from_bag" / "map.oeg").read_bytes() == (tmp_path / "from_log" / "map.oeg").read_bytes()


def _header(stamp_ns: int, frame: str) -> Any:
    msgs = TS.types
    time = msgs["builtin_interfaces/msg/Time"](sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9)
    return msgs["std_msgs/msg/Header"](stamp=time, frame_id=frame)


def _robot_messages() -> List[Tuple[str, str, int, bytes]]:
    """A robot driving 2 m along x in 1 s (Odometry), a lidar 0.5 m over its base (/tf_static), a LaserScan at
    0.5 s (two hits, an infinite reading, a NaN and one under range_min) and a PointCloud2 at 0.5 s with an
    intensity field, padding and a NaN point (is_dense false)."""
    m = TS.types
    vec = m["geometry_msgs/msg/Vector3"]
    quat = m["geometry_msgs/msg/Quaternion"]
    out: List[Tuple[str, str, int, bytes]] = []

    def add(topic: str, msg: Any, stamp_ns: int) -> None:
        out.append((topic, msg.__msgtype__, stamp_ns, bytes(TS.serialize_cdr(msg, msg.__msgtype__))))

    mount = m["geometry_msgs/msg/TransformStamped"](
        header=_header(0, "base_link"),
        child_frame_id="lidar",
        transform=m["geometry_msgs/msg/Transform"](translation=vec(x=0.0, y=0.0, z=0.5), rotation=quat(x=0.0, y=0.0, z=0.0, w=1.0)),
    )
    add("/tf_static", m["tf2_msgs/msg/TFMessage"](transforms=[mount]), 0)
    for t_ns, x in ((0, 0.0), (10**9, 2.0)):
        pose = m["geometry_msgs/msg/Pose"](
            position=m["geometry_msgs/msg/Point"](x=x, y=0.0, z=0.0), orientation=quat(x=0.0, y=0.0, z=0.0, w=1.0)
        )
        odom = m["nav_msgs/msg/Odometry"](
            header=_header(t_ns, "odom"),
            child_frame_id="base_link",
            pose=m["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=np.zeros(36)),
            twist=m["geometry_msgs/msg/TwistWithCovariance"](
                twist=m["geometry_msgs/msg/Twist"](linear=vec(x=2.0, y=0.0, z=0.0), angular=vec(x=0.0, y=0.0, z=0.0)),
                covariance=np.zeros(36),
            ),
        )
        add("/odom", odom, t_ns)
    ranges = np.array([1.0, 2.0, math.inf, math.nan, 0.01], dtype=np.float32)
    scan = m["sensor_msgs/msg/LaserScan"](
        header=_header(5 * 10**8, "lidar"),
        angle_min=-0.2,
        angle_max=0.2,
        angle_increment=0.1,
        time_increment=0.0,
        scan_time=0.1,
        range_min=0.05,
        range_max=8.0,
        ranges=ranges,
        intensities=np.zeros(5, dtype=np.float32),
    )
    add("/scan", scan, 5 * 10**8)
    field = m["sensor_msgs/msg/PointField"]
    fields = [
        field(name="x", offset=0, datatype=7, count=1),
        field(name="y", offset=4, datatype=7, count=1),
        field(name="z", offset=8, datatype=7, count=1),
        field(name="intensity", offset=16, datatype=7, count=1),
    ]
    pts = [(1.0, 0.0, -0.5, 7.0), (math.nan, 0.0, 0.0, 1.0), (2.0, 1.0, -0.5, 3.0)]
    data = b"".join(struct.pack("<fff4xf", *p) for p in pts)
    cloud = m["sensor_msgs/msg/PointCloud2"](
        header=_header(5 * 10**8, "lidar"),
        height=1,
        width=3,
        fields=fields,
        is_bigendian=False,
        point_step=20,
        row_step=60,
        data=np.frombuffer(data, dtype=np.uint8),
        is_dense=False,
    )
    add("/points", cloud, 5 * 10**8)
    return out


def _write_rosbags(folder: Path) -> None:
    messages = _robot_messages()
    with rosbag2.Writer(folder, version=8, storage_plugin=rosbag2.StoragePlugin.MCAP) as writer:
        connections = {}
        for topic, msgtype, _, _ in messages:
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, msgtype, typestore=TS)
        for topic, _, stamp, raw in messages:
            writer.write(connections[topic], stamp, raw)


def test_a_bag_written_by_rosbags_maps_laser_scans_clouds_and_odometry(tmp_path: Path) -> None:
    bag = tmp_path / "robot"
    _write_rosbags(bag)
    out = tmp_path / "map"
    printed = run_cli(
        "map", str(bag), "--resolution", "0.05", "--out", str(out), "--set", 'input.bag.odometry=["/odom"]', "--set", 'input.bag.map_frame="odom"'
    )
    s = _summary(out)
    # The scan: two hits and one no-return (the NaN and the reading under range_min left out); the cloud: two
    # points (the NaN one left out).
    assert (s["num_scans"], s["num_rays"], s["num_messages_skipped"]) == (2, 5, 0), printed
    # The robot was half way, at x = 1 m: the infinite reading, straight ahead, clears to range_max (8 m), so
    # the map ends 9 m along x; without the interpolated odometry it would end at 8 or 10 m.
    assert 8.95 < s["extent_max_x_m"] < 9.1, s
    # Without the odometry topic no transform names `map` or `odom`: the map frame must be chosen.
    err = _fails("map", str(bag), "--resolution", "0.05", "--out", str(tmp_path / "no_odom"))
    assert "neither `map` nor `odom`" in err and "robot" in err, err
    assert not (tmp_path / "no_odom").exists()


mcap_writer = pytest.importorskip("mcap.writer", reason="the mcap package is not installed (pip install mcap)")


@pytest.mark.parametrize("compression", ["ZSTD", "LZ4"])
def test_zstd_and_lz4_chunks_map_to_the_bytes_of_an_uncompressed_bag(compression: str, tmp_path: Path) -> None:
    messages = _robot_messages()
    maps = []
    for kind in ("NONE", compression):
        path = tmp_path / f"robot_{kind}.mcap"
        with open(path, "wb") as f:
            w = mcap_writer.Writer(f, compression=getattr(mcap_writer.CompressionType, kind))
            w.start(profile="ros2", library="test")
            channels = {}
            for topic, msgtype, stamp, raw in messages:
                if topic not in channels:
                    schema = w.register_schema(name=msgtype, encoding="ros2msg", data=b"")
                    channels[topic] = w.register_channel(topic=topic, message_encoding="cdr", schema_id=schema)
                w.add_message(channel_id=channels[topic], log_time=stamp, publish_time=stamp, data=raw)
            w.finish()
        out = tmp_path / f"map_{kind}"
        run_cli("map", str(path), "--resolution", "0.05", "--out", str(out), "--set", 'input.bag.odometry=["/odom"]')
        maps.append((out / "map.oeg").read_bytes())
    assert maps[0] == maps[1]
    # A corrupt chunk is an error naming the file, never a crash: a byte flipped in the middle of the first
    # chunk's compressed records.
    data = bytearray((tmp_path / f"robot_{compression}.mcap").read_bytes())
    pos = 8 + 9 + struct.unpack_from("<Q", data, 9)[0]
    assert data[pos] == 0x06, "the record after the header is a chunk"
    body = pos + 9
    name_len = struct.unpack_from("<I", data, body + 28)[0]
    records = body + 32 + name_len + 8
    records_len = struct.unpack_from("<Q", data, records - 8)[0]
    data[records + records_len // 2] ^= 0xFF
    bad = tmp_path / "corrupt.mcap"
    bad.write_bytes(bytes(data))
    err = _fails("map", str(bad), "--resolution", "0.05", "--out", str(tmp_path / "bad"), "--set", 'input.bag.odometry=["/odom"]')
    assert "corrupt.mcap" in err and "chunk" in err, err
    assert not (tmp_path / "bad").exists()


GRID_MAP_INFO = "float64 resolution\nfloat64 length_x\nfloat64 length_y\ngeometry_msgs/Pose pose\n"
GRID_MAP = (
    "std_msgs/Header header\ngrid_map_msgs/GridMapInfo info\nstring[] layers\nstring[] basic_layers\n"
    "std_msgs/Float32MultiArray[] data\nuint16 outer_start_index\nuint16 inner_start_index\n"
)


def test_a_grid_map_in_a_bag_scores_as_its_layers_given_as_npy(tmp_path: Path) -> None:
    """A GridMap written by rosbags' serializer (column-major layers, a wrapped circular buffer) scores as the
    same elevation, variance and decisions written as .npy files with their sidecar."""
    ts = typesys.get_typestore(typesys.Stores.ROS2_HUMBLE)
    ts.register(typesys.get_types_from_msg(GRID_MAP_INFO, "grid_map_msgs/msg/GridMapInfo"))
    ts.register(typesys.get_types_from_msg(GRID_MAP, "grid_map_msgs/msg/GridMap"))
    m = ts.types
    res, n_x, n_y, centre = 0.1, 40, 30, (4.0, 0.5)
    # grid_map's unwrapped index (i, j): i against x, j against y, from the map's +x, +y corner.
    i, j = np.meshgrid(np.arange(n_x), np.arange(n_y), indexing="ij")
    x = centre[0] + n_x * res / 2 - (i + 0.5) * res
    y = centre[1] + n_y * res / 2 - (j + 0.5) * res
    elevation = np.where((x > 5.0) & (x < 5.5), 0.3, 0.0).astype(np.float32)
    elevation[(x < 2.2) & (y > 1.5)] = np.nan
    variance = np.full_like(elevation, 1e-4)
    traversability = np.where(elevation > 0.1, 0.0, 1.0).astype(np.float32)
    start = (7, 11)

    def array(u: np.ndarray) -> Any:
        stored = np.roll(u, shift=start, axis=(0, 1))
        dim = m["std_msgs/msg/MultiArrayDimension"]
        layout = m["std_msgs/msg/MultiArrayLayout"](
            dim=[dim(label="column_index", size=n_y, stride=n_x * n_y), dim(label="row_index", size=n_x, stride=n_x)],
            data_offset=0,
        )
        return m["std_msgs/msg/Float32MultiArray"](layout=layout, data=stored.flatten(order="F").astype(np.float32))

    pose = m["geometry_msgs/msg/Pose"](
        position=m["geometry_msgs/msg/Point"](x=centre[0], y=centre[1], z=0.0),
        orientation=m["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
    )
    msg = m["grid_map_msgs/msg/GridMap"](
        header=_header(10**9, "map"),
        info=m["grid_map_msgs/msg/GridMapInfo"](resolution=res, length_x=n_x * res, length_y=n_y * res, pose=pose),
        layers=["elevation", "variance", "traversability"],
        basic_layers=["elevation"],
        data=[array(elevation), array(variance), array(traversability)],
        outer_start_index=start[0],
        inner_start_index=start[1],
    )
    bag = tmp_path / "elevation_bag"
    with rosbag2.Writer(bag, version=8, storage_plugin=rosbag2.StoragePlugin.MCAP) as writer:
        conn = writer.add_connection("/elevation_map", "grid_map_msgs/msg/GridMap", typestore=ts)
        writer.write(conn, 10**9, bytes(ts.serialize_cdr(msg, "grid_map_msgs/msg/GridMap")))
    # The same layers as the arrays oeg score reads: row 0 the min-y row, column 0 the min-x column.
    def lower_left(u: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(u[::-1, ::-1].T)

    decisions = np.where(np.isnan(elevation), 0, np.where(traversability >= 0.5, 2, 3)).astype(np.int64)
    for name, values in (("decisions", decisions), ("elevation_m", elevation), ("variance_m2", variance)):
        np.save(tmp_path / f"{name}.npy", lower_left(values) if name == "decisions" else lower_left(values).astype(np.float64))
    sidecar = {
        "origin_xy_m": [centre[0] - n_x * res / 2, centre[1] - n_y * res / 2],
        "resolution_m": res,
        "layers": {name: {"file": f"{name}.npy"} for name in ("decisions", "elevation_m", "variance_m2")},
    }
    (tmp_path / "layers.json").write_text(json.dumps(sidecar))
    scenario = "scenarios/corridor_lasers.toml"
    common = ("--no-observability",)
    # The scenario's regression bounds are its own map's: this small map fails them, and the scores are written.
    run_cli("score", scenario, "--grid-map", str(bag), "--out", str(tmp_path / "from_bag"), *common, check=False)
    run_cli("score", scenario, "--layers", str(tmp_path / "layers.json"), "--out", str(tmp_path / "from_npy"), *common, check=False)
    a = json.loads((tmp_path / "from_bag" / "score.json").read_text())
    b = json.loads((tmp_path / "from_npy" / "score.json").read_text())
    assert a == b
    assert a["num_observed_cells"] > 0
    # The wall the grid map holds is blocked, where the truth has level floor: over-cautious cells, counted
    # the same both ways.
    assert a["overcautious_cells"] > 0
    # A topic that is not there is named.
    err = _fails("score", scenario, "--grid-map", str(bag), "--topic", "/grid", "--out", str(tmp_path / "x"), *common)
    assert "no topic /grid" in err, err


def _rotation(q: Any) -> Any:
    """A geometry_msgs/Quaternion as a rotation matrix."""
    x, y, z, w = q.x, q.y, q.z, q.w
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def _pcd_points(path: Path) -> Any:
    """The x, y, z of a binary PCD of four float32 fields, as `oeg record --format dynamicmap` writes it."""
    data = path.read_bytes()
    body = data.index(b"DATA binary\n") + len(b"DATA binary\n")
    return np.frombuffer(data[body:], dtype="<f4").reshape(-1, 4)[:, :3].astype(np.float64)


def test_rosbags_reads_the_points_of_the_recorded_scans(tmp_path: Path) -> None:
    # The same scans written as a bag and as DynamicMap frames (world-frame hits at the estimated pose, a
    # frame a scan, in order): rosbags' clouds, placed by the bag's odom -> base_link -> sensor transforms in
    # numpy, are the frames' points, to float32's rounding.
    bag, frames = tmp_path / "bag", tmp_path / "frames"
    run_cli("record", "scenarios/corridor_lasers.toml", "--format", "rosbag2", "--out", str(bag))
    run_cli("record", "scenarios/corridor_lasers.toml", "--format", "dynamicmap", "--out", str(frames))
    mounts, odom, clouds = {}, {}, []
    with rosbag2.Reader(bag) as reader:
        wanted = [c for c in reader.connections if not c.topic.startswith("/truth")]
        for conn, _, raw in reader.messages(connections=wanted):
            msg = TS.deserialize_cdr(raw, conn.msgtype)
            if conn.msgtype.endswith("TFMessage"):
                for t in msg.transforms:
                    v = t.transform.translation
                    pose = (_rotation(t.transform.rotation), np.array([v.x, v.y, v.z]))
                    stamp = t.header.stamp.sec * 10**9 + t.header.stamp.nanosec
                    if conn.topic == "/tf_static":
                        mounts[t.child_frame_id] = pose
                    elif t.header.frame_id == "odom":
                        odom[stamp] = pose
            else:
                names = [f.name for f in msg.fields]
                columns = np.frombuffer(bytes(msg.data), dtype="<f4").reshape(-1, len(names))
                xyz = columns[:, :3].astype(np.float64)
                stamp = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
                clouds.append((stamp, msg.header.frame_id, xyz[np.all(np.isfinite(xyz), axis=1)]))
    pcds = sorted((frames / "pcd").glob("*.pcd"))
    assert len(pcds) == len(clouds) > 100
    for (stamp, frame, points), pcd in zip(clouds, pcds):
        (r_base, t_base), (r_mount, t_mount) = odom[stamp], mounts[frame]
        world = (points @ r_mount.T + t_mount) @ r_base.T + t_base
        expected = _pcd_points(pcd)
        assert world.shape == expected.shape, pcd.name
        assert np.max(np.abs(world - expected), initial=0.0) < 1e-4, pcd.name
