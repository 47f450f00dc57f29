//! The sensor presets, each with its source: the values an entry leaves out.

use super::SensorKind;

/// A preset's values: the same fields as a file entry, all given.
pub(super) struct Preset {
    pub(super) name: &'static str,
    pub(super) kind: SensorKind,
    pub(super) rate_hz: f64,
    pub(super) min_range_m: f64,
    pub(super) max_range_m: f64,
    pub(super) fov_deg: f64,
    pub(super) step_deg: f64,
    pub(super) vertical_angles_deg: &'static [f64],
    pub(super) image_size_px: [u32; 2],
    pub(super) hfov_deg: f64,
    pub(super) pixel_stride: u32,
    pub(super) baseline_m: f64,
    pub(super) range_sigma_m: f64,
    pub(super) disparity_sigma_px: f64,
    pub(super) hole_probability: f64,
}

const VLP16_ANGLES: [f64; 16] = [
    -15.0, -13.0, -11.0, -9.0, -7.0, -5.0, -3.0, -1.0, 1.0, 3.0, 5.0, 7.0, 9.0, 11.0, 13.0, 15.0,
];

const BASE: Preset = Preset {
    name: "",
    kind: SensorKind::Laser2d,
    rate_hz: 10.0,
    min_range_m: 0.1,
    max_range_m: 80.0,
    fov_deg: 180.0,
    step_deg: 0.5,
    vertical_angles_deg: &[],
    image_size_px: [0, 0],
    hfov_deg: 60.0,
    pixel_stride: 1,
    baseline_m: 0.12,
    range_sigma_m: 0.0,
    disparity_sigma_px: 0.0,
    hole_probability: 0.0,
};

/// Every preset, the kind's default first. Sources: SICK LMS 291 and LMS1xx datasheets (180 degrees, 0.25/0.5/1
/// degree steps, up to 75 Hz, 80 m, statistical error 12 mm), Velodyne VLP-16 (16 channels, 2 degrees apart
/// over +-15 degrees, 0.2 degree azimuth step at 10 Hz, 100 m, +-3 cm), the paper's simple stereo rig (Fig. 4:
/// depth error 0.032 m at 1 m), Kinect v1 (640 x 480, 57 degrees, 0.5 to 4.5 m).
pub(super) const PRESETS: &[Preset] = &[
    Preset {
        name: "sick_lms291",
        kind: SensorKind::Laser2d,
        rate_hz: 75.0,
        range_sigma_m: 0.012,
        ..BASE
    },
    // The paper's data set (section 6.2): LMS 291-S14 scanners sweeping 90 degrees.
    Preset {
        name: "sick_lms291_90",
        kind: SensorKind::Laser2d,
        rate_hz: 75.0,
        fov_deg: 90.0,
        range_sigma_m: 0.012,
        ..BASE
    },
    Preset {
        name: "vlp16",
        kind: SensorKind::Lidar3d,
        rate_hz: 10.0,
        min_range_m: 0.5,
        max_range_m: 100.0,
        fov_deg: 360.0,
        step_deg: 0.2,
        vertical_angles_deg: &VLP16_ANGLES,
        range_sigma_m: 0.03,
        ..BASE
    },
    // A cheap rig: 320 x 240, 12 cm baseline, focal 240 px; a 0.92 px disparity error gives the paper's
    // 0.032 z^2 m depth error.
    Preset {
        name: "paper_stereo",
        kind: SensorKind::Stereo,
        rate_hz: 5.0,
        min_range_m: 0.3,
        max_range_m: 8.0,
        image_size_px: [320, 240],
        hfov_deg: 67.38,
        pixel_stride: 2,
        baseline_m: 0.12,
        disparity_sigma_px: 0.9216,
        hole_probability: 0.05,
        ..BASE
    },
    // A good matcher: 0.1 px.
    Preset {
        name: "stereo_vga",
        kind: SensorKind::Stereo,
        rate_hz: 10.0,
        min_range_m: 0.3,
        max_range_m: 15.0,
        image_size_px: [640, 480],
        hfov_deg: 66.0,
        pixel_stride: 4,
        baseline_m: 0.12,
        disparity_sigma_px: 0.1,
        hole_probability: 0.02,
        ..BASE
    },
    Preset {
        name: "kinect_like",
        kind: SensorKind::DepthCamera,
        rate_hz: 10.0,
        min_range_m: 0.5,
        max_range_m: 4.5,
        image_size_px: [640, 480],
        hfov_deg: 57.0,
        pixel_stride: 4,
        hole_probability: 0.02,
        ..BASE
    },
];

/// The names of the presets of `kind`, default first.
pub fn preset_names(kind: SensorKind) -> Vec<&'static str> {
    PRESETS
        .iter()
        .filter(|p| p.kind == kind)
        .map(|p| p.name)
        .collect()
}
