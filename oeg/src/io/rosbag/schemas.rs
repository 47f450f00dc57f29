//! The message definitions a written bag's schemas carry (`ros2msg`), as `ros2 bag record` writes them, so that
//! Foxglove and the Python `rosbags` package decode its messages by their schema.

use super::msgs::{GRID_MAP, OCCUPANCY_GRID, POINT_CLOUD2};

/// The definitions a bag's schema records carry (`ros2msg`): the message's own, then each message it uses,
/// after a line of 80 `=` and `MSG: package/Name`, as `ros2 bag record` writes them.
pub(crate) fn schema_text(name: &str) -> String {
    let pose: (&str, &str) = ("geometry_msgs/Pose", "Point position\nQuaternion orientation\n");
    let point: (&str, &str) = ("geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z\n");
    let quaternion: (&str, &str) = (
        "geometry_msgs/Quaternion",
        "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
    );
    let grid_map_deps = [
        ("std_msgs/Header", HEADER),
        ("builtin_interfaces/Time", TIME),
        (
            "grid_map_msgs/GridMapInfo",
            "float64 resolution\nfloat64 length_x\nfloat64 length_y\ngeometry_msgs/Pose pose\n",
        ),
        pose,
        point,
        quaternion,
        (
            "std_msgs/Float32MultiArray",
            "MultiArrayLayout layout\nfloat32[] data\n",
        ),
        (
            "std_msgs/MultiArrayLayout",
            "MultiArrayDimension[] dim\nuint32 data_offset\n",
        ),
        (
            "std_msgs/MultiArrayDimension",
            "string label\nuint32 size\nuint32 stride\n",
        ),
    ];
    let occupancy_deps = [
        ("std_msgs/Header", HEADER),
        ("builtin_interfaces/Time", TIME),
        (
            "nav_msgs/MapMetaData",
            "builtin_interfaces/Time map_load_time\nfloat32 resolution\nuint32 width\nuint32 height\n\
             geometry_msgs/Pose origin\n",
        ),
        pose,
        point,
        quaternion,
    ];
    let (own, deps): (&str, &[(&str, &str)]) = if name == GRID_MAP {
        (
            "std_msgs/Header header\ngrid_map_msgs/GridMapInfo info\nstring[] layers\nstring[] basic_layers\n\
             std_msgs/Float32MultiArray[] data\nuint16 outer_start_index\nuint16 inner_start_index\n",
            &grid_map_deps,
        )
    } else if name == OCCUPANCY_GRID {
        (
            "std_msgs/Header header\nnav_msgs/MapMetaData info\nint8[] data\n",
            &occupancy_deps,
        )
    } else if name == POINT_CLOUD2 {
        (
            "std_msgs/Header header\nuint32 height\nuint32 width\nsensor_msgs/PointField[] fields\nbool is_bigendian\n\
             uint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n",
            &[
                ("std_msgs/Header", HEADER),
                ("builtin_interfaces/Time", TIME),
                (
                    "sensor_msgs/PointField",
                    "uint8 INT8=1\nuint8 UINT8=2\nuint8 INT16=3\nuint8 UINT16=4\nuint8 INT32=5\nuint8 UINT32=6\n\
                     uint8 FLOAT32=7\nuint8 FLOAT64=8\nstring name\nuint32 offset\nuint8 datatype\nuint32 count\n",
                ),
            ],
        )
    } else {
        (
            "geometry_msgs/TransformStamped[] transforms\n",
            &[
                (
                    "geometry_msgs/TransformStamped",
                    "std_msgs/Header header\nstring child_frame_id\nTransform transform\n",
                ),
                ("std_msgs/Header", HEADER),
                ("builtin_interfaces/Time", TIME),
                (
                    "geometry_msgs/Transform",
                    "Vector3 translation\nQuaternion rotation\n",
                ),
                ("geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n"),
                (
                    "geometry_msgs/Quaternion",
                    "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
                ),
            ],
        )
    };
    let mut text = own.to_string();
    for (dep, body) in deps {
        text.push_str(&format!("{}\nMSG: {dep}\n{body}", "=".repeat(80)));
    }
    text
}

const HEADER: &str = "builtin_interfaces/Time stamp\nstring frame_id\n";
const TIME: &str = "int32 sec\nuint32 nanosec\n";
