//! The scenario's place in its file: the ground, the static obstacles and the moving actors. Frames and
//! units as in [`super::Scenario`]; `docs/scenario-format.md` documents every key.

use std::path::PathBuf;

use serde::Deserialize;

/// The ground.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Terrain {
    /// A horizontal plane.
    Flat {
        /// Height of the plane, metres.
        #[serde(default)]
        height_m: f64,
    },
    /// A plane `z = height_m + slope_x * x + slope_y * y`.
    Slope {
        /// Height at the origin, metres.
        #[serde(default)]
        height_m: f64,
        /// Rise per metre along x.
        #[serde(default)]
        slope_x: f64,
        /// Rise per metre along y.
        #[serde(default)]
        slope_y: f64,
    },
    /// Irregular ground: a sum of seeded sine waves (seed sub-stream `terrain`).
    Noise {
        /// Peak-to-mean amplitude, metres.
        amplitude_m: f64,
        /// Typical wavelength of the bumps, metres.
        wavelength_m: f64,
        /// Heightfield cell size, metres.
        #[serde(default = "default_terrain_cell")]
        cell_m: f64,
    },
    /// A greyscale PNG: black is 0, white is `height_scale_m`; row 0 of the image is the max-y edge (north up),
    /// column 0 the min-x edge; the image's min-x, min-y corner is at `origin_xy_m`.
    Image {
        /// The PNG, relative to the scenario file (8- or 16-bit greyscale).
        path: PathBuf,
        /// Height of a white pixel, metres.
        height_scale_m: f64,
        /// Pixel size, metres.
        cell_m: f64,
        /// Where the image's min-x, min-y corner lies; default: the map's min corner.
        #[serde(default)]
        #[serde(deserialize_with = "crate::scenario::exact::option")]
        origin_xy_m: Option<[f64; 2]>,
    },
}

impl Default for Terrain {
    fn default() -> Self {
        Self::Flat { height_m: 0.0 }
    }
}

fn default_terrain_cell() -> f64 {
    0.1
}

fn default_bush_parts() -> u32 {
    12
}

/// A static obstacle. Heights are above the terrain at the obstacle's centre.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Obstacle {
    /// A box (wall, curb, step, table top): `size_m` = length (local x), width (local y), height.
    Box {
        /// Optional label, shown in reports.
        #[serde(default)]
        name: Option<String>,
        /// Centre of the footprint, metres.
        #[serde(deserialize_with = "crate::scenario::exact::array")]
        center_xy_m: [f64; 2],
        /// Length, width, height, metres.
        #[serde(deserialize_with = "crate::scenario::exact::array")]
        size_m: [f64; 3],
        /// Rotation about z, degrees.
        #[serde(default)]
        yaw_deg: f64,
        /// Height of the box's bottom above the ground, metres (0: standing on it).
        #[serde(default)]
        base_m: f64,
    },
    /// A vertical cylinder (pole, trunk).
    Cylinder {
        /// Optional label.
        #[serde(default)]
        name: Option<String>,
        /// Centre, metres.
        #[serde(deserialize_with = "crate::scenario::exact::array")]
        center_xy_m: [f64; 2],
        /// Radius, metres.
        radius_m: f64,
        /// Height, metres.
        height_m: f64,
        /// Height of the bottom above the ground, metres.
        #[serde(default)]
        base_m: f64,
    },
    /// A wedge rising from 0 at its local -x end to `height_m` at its +x end.
    Ramp {
        /// Optional label.
        #[serde(default)]
        name: Option<String>,
        /// Centre of the footprint, metres.
        #[serde(deserialize_with = "crate::scenario::exact::array")]
        center_xy_m: [f64; 2],
        /// Length along local x, metres.
        length_m: f64,
        /// Width along local y, metres.
        width_m: f64,
        /// Height at the high end, metres.
        height_m: f64,
        /// Rotation about z, degrees.
        #[serde(default)]
        yaw_deg: f64,
    },
    /// An irregular cluster of small boxes (a bush), placed from the seed sub-stream `bush/<index>`.
    Bush {
        /// Optional label.
        #[serde(default)]
        name: Option<String>,
        /// Centre, metres.
        #[serde(deserialize_with = "crate::scenario::exact::array")]
        center_xy_m: [f64; 2],
        /// Radius of the cluster, metres.
        radius_m: f64,
        /// Height of the cluster, metres.
        height_m: f64,
        /// Number of parts.
        #[serde(default = "default_bush_parts")]
        num_parts: u32,
    },
    /// A board or branch at a height, with nothing under it: `size_m` = length, width, thickness;
    /// `clearance_m` is the free gap between the ground and its underside.
    Overhang {
        /// Optional label.
        #[serde(default)]
        name: Option<String>,
        /// Centre of the footprint, metres.
        #[serde(deserialize_with = "crate::scenario::exact::array")]
        center_xy_m: [f64; 2],
        /// Length, width, thickness, metres.
        #[serde(deserialize_with = "crate::scenario::exact::array")]
        size_m: [f64; 3],
        /// Gap under it, metres.
        clearance_m: f64,
        /// Rotation about z, degrees.
        #[serde(default)]
        yaw_deg: f64,
    },
}

impl Obstacle {
    /// The obstacle's kind as written in files.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Box { .. } => "box",
            Self::Cylinder { .. } => "cylinder",
            Self::Ramp { .. } => "ramp",
            Self::Bush { .. } => "bush",
            Self::Overhang { .. } => "overhang",
        }
    }

    /// The obstacle's name, if the file gives one.
    pub fn name(&self) -> Option<&str> {
        match self {
            Self::Box { name, .. }
            | Self::Cylinder { name, .. }
            | Self::Ramp { name, .. }
            | Self::Bush { name, .. }
            | Self::Overhang { name, .. } => name.as_deref(),
        }
    }

    /// The obstacle's label: its name, or `<kind> <index>`.
    pub fn label(&self, index: usize) -> String {
        self.name()
            .map_or_else(|| format!("{} {index}", self.kind()), str::to_string)
    }

    /// The footprint's centre.
    pub fn center_xy_m(&self) -> [f64; 2] {
        match self {
            Self::Box { center_xy_m, .. }
            | Self::Cylinder { center_xy_m, .. }
            | Self::Ramp { center_xy_m, .. }
            | Self::Bush { center_xy_m, .. }
            | Self::Overhang { center_xy_m, .. } => *center_xy_m,
        }
    }
}

/// A moving actor.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Actor {
    /// A person: an upright capsule walking between timed waypoints; absent before the first waypoint's time
    /// and after the last one's (entering and leaving the scene).
    Person {
        /// Label.
        #[serde(default)]
        name: Option<String>,
        /// `[t_s, x_m, y_m]`, times strictly increasing.
        #[serde(deserialize_with = "crate::scenario::exact::each")]
        waypoints: Vec<[f64; 3]>,
        /// Capsule radius, metres.
        #[serde(default = "default_person_radius")]
        radius_m: f64,
        /// Height, metres.
        #[serde(default = "default_person_height")]
        height_m: f64,
    },
}

impl Actor {
    /// Where the actor stands at `t_s`, or `None` when it is not in the scene.
    pub fn position_at(&self, t_s: f64) -> Option<(f64, f64)> {
        match self {
            Self::Person { waypoints, .. } => position_on(waypoints, t_s),
        }
    }

    /// The radius of the actor's footprint, metres.
    pub fn radius_m(&self) -> f64 {
        match self {
            Self::Person { radius_m, .. } => *radius_m,
        }
    }

    /// The times `[first, last]` between which the actor is in the scene, seconds.
    pub fn time_span_s(&self) -> Option<[f64; 2]> {
        match self {
            Self::Person { waypoints, .. } => Some([waypoints.first()?[0], waypoints.last()?[0]]),
        }
    }
}

/// The position at `t_s` along timed waypoints `[t_s, x_m, y_m]` (times increasing), linear between them;
/// `None` before the first or after the last.
pub fn position_on(waypoints: &[[f64; 3]], t_s: f64) -> Option<(f64, f64)> {
    let first = waypoints.first()?;
    let last = waypoints.last()?;
    if t_s < first[0] || t_s > last[0] {
        return None;
    }
    for w in waypoints.windows(2) {
        if t_s <= w[1][0] {
            let f = (t_s - w[0][0]) / (w[1][0] - w[0][0]);
            return Some((
                w[0][1] + f * (w[1][1] - w[0][1]),
                w[0][2] + f * (w[1][2] - w[0][2]),
            ));
        }
    }
    Some((last[1], last[2]))
}

fn default_person_radius() -> f64 {
    0.25
}

fn default_person_height() -> f64 {
    1.7
}
