#![doc = include_str!("../README.md")]
//!
//! # The API
//!
//! Every module is private; this list is the crate's whole public API, each item under one name.

mod cell;
mod error;
mod footprint;
mod geometry;
mod io;
mod map;
mod model;
mod planner;
mod preset;
mod scan;
mod sensor;
mod storage;
mod traversability;
mod traversal;

// The map: its grid, cells and layers.
pub use cell::Cell;
pub use error::{Error, Result};
pub use geometry::{CellIndex, CellRegion, GridGeometry, GridWindow, MAX_RESOLUTION_M, MIN_RESOLUTION_M};
pub use map::{
    BatchError, BodySpan, DEFAULT_MEMORY_LIMIT_BYTES, DEFAULT_STANCE_SIGMA_M, IntegrationStats, Layer,
    LayerKind, Map, MapConfig, RAYS_BETWEEN_STOP_CHECKS, Raster, Stance,
};

// What goes in: scans of rays from a sensor with a range-noise model.
pub use scan::{Ray, RayKind, Scan};
pub use sensor::{
    DEFAULT_LASER_SIGMA_M, DEFAULT_MAX_RANGE_M, DEFAULT_STEREO_COEFFICIENT_PER_M, MIN_RANGE_SIGMA_M,
    RangeNoiseModel, SensorModel,
};

// The model: the paper's equations, the rules beyond it, the options that choose them, and the named presets.
pub use model::{
    BEAM_SIGMA_RAD, Ceiling, CeilingHit, DEFAULT_ELEVATION_THRESHOLD, DEFAULT_LOG_ODDS_MAX,
    DEFAULT_LOG_ODDS_MIN, DEFAULT_OCCUPIED_THRESHOLD, DEFAULT_P_MAX, DEFAULT_P_MIN, DEFAULT_SIGNIFICANCE_K_M,
    DEFAULT_SURFACE_BAND_SIGMAS, Elevation, ElevationFusion, FreeSpaceElevation, FreeSpaceOccupancy,
    GAUSSIAN_CUTOFF_SIGMAS, HitHeight, Level, ModelOptions, OverheadHits, ScanHitElevation, SeenFrom,
    VERTICAL_SIGMA_FLOOR_M, band_contradicts, beam_footprint_m, ceiling_confirmed, ceiling_contradicts,
    ceiling_passed_under, clamp_probability, correlated_variance, elevation_observation, free_sample_informs,
    fuse_elevation, fuse_top_surface, fuse_with_disagreement, inverse_sensor_model, kalman_fuse, log_odds,
    normal_tail, overhead_significant, p_occ, probability_from_log_odds, ray_bound, spread_variance,
    surface_level, update_ceiling, update_log_odds, vertical_variance,
};
pub use preset::{MapModel, MapPreset, ModelChoice, ModelKeys, ROBUST_HEIGHT_MARGIN_M, STATIC_MAX_DEPTH_M};

// The decision: where the robot can drive, and a planner that uses it.
pub use footprint::{Footprint, Pose2};
pub use planner::{
    DEFAULT_COST_SCALING_FACTOR, DEFAULT_DOUBT_COST, DEFAULT_FOOTPRINT_RADIUS_M,
    DEFAULT_INFLATION_COST_WIDTH_M, DEFAULT_INFLATION_RADIUS_M, INFLATED_CELL_COST, NoPath,
    PLANNER_BYTES_PER_CELL, Plan, PlannerOptions, UncertainCells, UnknownCells, closing_cells,
    forbidden_mask, plan, plan_or_why,
};
pub use traversability::{
    DEFAULT_MAX_GRADE, DEFAULT_MAX_STEP_M, DEFAULT_REACH_M, DEFAULT_ROBOT_HEIGHT_M, DEFAULT_UNCERTAIN_KAPPA,
    Doubt, RobotProfile, Traversability, TraversabilityCounts, TraversabilityRule, ceiling_decision,
    contact_decision, footprint_decision, more_restrictive, step_decision,
};

// Files: real range data in (OctoMap scan graphs, PCL point clouds), maps out and back, and the framing and
// atomic writes the testbed's own files share.
pub use io::dynamicmap::read_dynamicmap;
pub use io::graph::{GraphNode, parse_graph, read_graph, read_graph_scans, write_graph};
pub use io::kitti::{kitti_scan_files, parse_kitti_scan, read_kitti};
pub use io::mapfile::{
    MapFileHeader, load_map, load_map_within, map_from_bytes, map_to_bytes, read_map_header, save_map,
};
pub use io::nav2::{
    Nav2Map, PGM_FREE, PGM_OCCUPIED, PGM_UNKNOWN, nav2_grey, nav2_map, parse_nav2_map, read_nav2_map,
};
pub use io::npy::{NpyArray, NpyData};
pub use io::pcd::{
    InvalidPoints, PcdCloud, PcdEncoding, PcdFrame, PcdOptions, PcdPoints, parse_pcd, parse_pcd_within,
    read_pcd, read_pcd_scan, read_pcd_scan_within, read_pcd_within, write_pcd, write_pcd_with_intensity,
};
pub use io::planner_files::{PLANNER_FLOAT_LAYERS, planner_files};
pub use io::rosbag::{
    Bag, BagOptions, BagRaster, BagScan, BagSkip, BagTransform, BagWriter, CLOUD_CLEAR_FIELDS,
    CLOUD_RANGE_SIGMA_FIELD, CloudPrecision, DEFAULT_GROUND_FRAME, GridMapLayers, MAX_GRID_MAP_CELLS,
    parse_bag, parse_grid_map, read_bag, read_bag_within, read_grid_map,
};
