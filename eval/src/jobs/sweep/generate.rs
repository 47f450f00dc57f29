//! Randomized scenes: a sweep's `[generate]` table places obstacles and people from distributions with each
//! run's scenario seed (sub-streams `generate/<kind>`), so a replicate is a new scene and the same seed is the
//! same scene. `docs/sweep-format.md` documents every key.
//!
//! The layout keeps the question meaningful: the robot drives along +x from the origin to `drive_length_m` and
//! stops facing the obstacle field. The field spans `field_start_m .. field_start_m + field_length_m` along x
//! and `±field_half_width_m` across; a lane `±lane_half_width_m` wide stays free as far as the robot drives
//! (obstacles do not lift the simulated robot), and beyond the stop obstacles may stand in the lane, in front
//! of the robot. The planner plans from the start to a free goal past the field's far end, so it must cross
//! or go round what was placed. Generated obstacles are appended to the base scenario's; the drive, planner,
//! map region and duration are the generator's.

use std::path::PathBuf;

use rand::RngExt;
use serde::Deserialize;
use sim::scenario::KeySeg;
use toml::{Table, Value};

use crate::error::EvalError;

/// Uniform `[min, max]`.
pub type Range = [f64; 2];
/// Uniform integer `[min, max]`.
pub type Count = [u32; 2];

/// The `[generate]` table.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GenerateSpec {
    /// The scenario that gives the robot, its sensors, the map model and resolution, the terrain (relative to
    /// the sweep file).
    pub base: PathBuf,
    /// Where the robot stops, metres along x from the start.
    #[serde(default = "d_drive")]
    pub drive_length_m: f64,
    /// Driving speed, m/s.
    #[serde(default = "d_speed")]
    pub speed_m_s: f64,
    /// Where the obstacle field begins, metres along x.
    #[serde(default = "d_field_start")]
    pub field_start_m: f64,
    /// Length of the field along x, metres.
    #[serde(default = "d_field_length")]
    pub field_length_m: f64,
    /// Half the field's width, metres.
    #[serde(default = "d_half_width")]
    pub field_half_width_m: f64,
    /// Half the width of the lane kept free where the robot drives, metres.
    #[serde(default = "d_lane")]
    pub lane_half_width_m: f64,
    /// Seconds the sensors keep scanning after the robot stops and the last person left.
    #[serde(default = "d_settle")]
    pub settle_s: f64,
    /// How far past the field's far end the goal lies, metres (kept free of obstacles; the map region reaches
    /// a metre beyond it).
    #[serde(default = "d_goal_beyond")]
    pub goal_beyond_m: f64,
    /// Closed loop: after its drive the robot navigates to the goal (`[navigation]`), for at most
    /// `navigation_time_s`.
    #[serde(default)]
    pub navigate: bool,
    /// A closed-loop run's time limit after the drive, seconds.
    #[serde(default = "d_navigation_time")]
    pub navigation_time_s: f64,
    /// Curbs: boxes across the drive at a random yaw and offset to the cell grid.
    pub curbs: Option<Curbs>,
    /// Boards and table tops at a clearance near the robot's height.
    pub boards: Option<Boards>,
    /// Walls of random height, some lower than the sensors.
    pub walls: Option<Walls>,
    /// Bushes.
    pub bushes: Option<Bushes>,
    /// Ramps.
    pub ramps: Option<Ramps>,
    /// People who walk through, or who stand in front of the robot for a while and leave.
    pub people: Option<People>,
}

fn d_drive() -> f64 {
    3.0
}
fn d_speed() -> f64 {
    0.4
}
fn d_field_start() -> f64 {
    1.5
}
fn d_field_length() -> f64 {
    5.0
}
fn d_half_width() -> f64 {
    2.5
}
fn d_lane() -> f64 {
    0.6
}
fn d_goal_beyond() -> f64 {
    0.5
}
fn d_navigation_time() -> f64 {
    60.0
}
fn d_settle() -> f64 {
    2.0
}

/// `[generate.curbs]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Curbs {
    /// How many.
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub count: Count,
    /// Height, metres (default 2 to 5 cm, around the 3.5 cm step).
    #[serde(default = "d_curb_h")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub height_m: Range,
    /// Length across the drive, metres.
    #[serde(default = "d_curb_len")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub length_m: Range,
    /// Depth along the drive, metres.
    #[serde(default = "d_curb_depth")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub depth_m: Range,
    /// Yaw to the drive, degrees (0: the face square to the drive).
    #[serde(default = "d_curb_yaw")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub yaw_deg: Range,
}
fn d_curb_h() -> Range {
    [0.02, 0.05]
}
fn d_curb_len() -> Range {
    [0.8, 1.6]
}
fn d_curb_depth() -> Range {
    [0.25, 0.45]
}
fn d_curb_yaw() -> Range {
    [-45.0, 45.0]
}

/// `[generate.boards]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Boards {
    /// How many.
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub count: Count,
    /// Free gap under the board, metres (default 0.38 to 0.54: around the robot's 0.46 m).
    #[serde(default = "d_board_clear")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub clearance_m: Range,
    /// Length, metres.
    #[serde(default = "d_board_len")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub length_m: Range,
    /// Width, metres.
    #[serde(default = "d_board_width")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub width_m: Range,
    /// Thickness, metres.
    #[serde(default = "d_board_thick")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub thickness_m: Range,
    /// Yaw, degrees.
    #[serde(default = "d_any_yaw")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub yaw_deg: Range,
}
fn d_board_clear() -> Range {
    [0.38, 0.54]
}
fn d_board_len() -> Range {
    [0.5, 1.0]
}
fn d_board_width() -> Range {
    [0.6, 1.2]
}
fn d_board_thick() -> Range {
    [0.02, 0.05]
}
fn d_any_yaw() -> Range {
    [-90.0, 90.0]
}

/// `[generate.walls]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Walls {
    /// How many.
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub count: Count,
    /// Height, metres (default 0.1 to 1.2: some below the sensors).
    #[serde(default = "d_wall_h")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub height_m: Range,
    /// Length, metres.
    #[serde(default = "d_wall_len")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub length_m: Range,
    /// Thickness, metres.
    #[serde(default = "d_wall_thick")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub thickness_m: Range,
    /// Yaw, degrees.
    #[serde(default = "d_any_yaw")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub yaw_deg: Range,
}
fn d_wall_h() -> Range {
    [0.1, 1.2]
}
fn d_wall_len() -> Range {
    [1.0, 2.0]
}
fn d_wall_thick() -> Range {
    [0.1, 0.2]
}

/// `[generate.bushes]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bushes {
    /// How many.
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub count: Count,
    /// Radius, metres.
    #[serde(default = "d_bush_r")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub radius_m: Range,
    /// Height, metres.
    #[serde(default = "d_bush_h")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub height_m: Range,
}
fn d_bush_r() -> Range {
    [0.3, 0.7]
}
fn d_bush_h() -> Range {
    [0.4, 1.2]
}

/// `[generate.ramps]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ramps {
    /// How many.
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub count: Count,
    /// Height at the high end, metres.
    #[serde(default = "d_ramp_h")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub height_m: Range,
    /// Length, metres.
    #[serde(default = "d_ramp_len")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub length_m: Range,
    /// Width, metres.
    #[serde(default = "d_ramp_width")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub width_m: Range,
    /// Yaw, degrees.
    #[serde(default = "d_ramp_yaw")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub yaw_deg: Range,
}
fn d_ramp_h() -> Range {
    [0.05, 0.2]
}
fn d_ramp_len() -> Range {
    [0.8, 1.5]
}
fn d_ramp_width() -> Range {
    [0.6, 1.2]
}
fn d_ramp_yaw() -> Range {
    [-180.0, 180.0]
}

/// `[generate.people]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct People {
    /// How many.
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub count: Count,
    /// Probability that a person stands still in front of the robot (else walks through the field).
    #[serde(default = "d_half")]
    pub stand_probability: f64,
    /// How long a standing person stands, seconds.
    #[serde(default = "d_stand")]
    #[serde(deserialize_with = "sim::scenario::exact::array")]
    pub stand_s: Range,
    /// Probability that the robot is standing (stopped at the end of its drive) when a person stands in front
    /// of it; otherwise it is still driving towards them.
    #[serde(default = "d_half")]
    pub robot_standing_probability: f64,
    /// Walking speed, m/s.
    #[serde(default = "d_walk")]
    pub walk_speed_m_s: f64,
}
fn d_half() -> f64 {
    0.5
}
fn d_stand() -> Range {
    [2.0, 6.0]
}
fn d_walk() -> f64 {
    1.0
}

type Fail<'f> = &'f dyn Fn(&[KeySeg<'_>], String) -> EvalError;

fn check_range(r: Range, at: &[KeySeg<'_>], positive: bool, fail: Fail<'_>) -> Result<(), EvalError> {
    if !(r[0].is_finite() && r[1].is_finite()) {
        return Err(fail(at, format!("expected finite [min, max], got {r:?}")));
    }
    if r[0] > r[1] {
        return Err(fail(
            at,
            format!("min {} is above max {}; expected [min, max]", r[0], r[1]),
        ));
    }
    if positive && r[0] <= 0.0 {
        return Err(fail(at, format!("expected positive sizes, got min {}", r[0])));
    }
    Ok(())
}

fn check_count(c: Count, at: &[KeySeg<'_>], fail: Fail<'_>) -> Result<(), EvalError> {
    if c[0] > c[1] {
        return Err(fail(
            at,
            format!("min {} is above max {}; expected [min, max]", c[0], c[1]),
        ));
    }
    if c[1] > MAX_PER_KIND {
        return Err(fail(
            at,
            format!("at most {MAX_PER_KIND} of a kind, got {}", c[1]),
        ));
    }
    Ok(())
}

/// The most obstacles or people of one kind.
pub const MAX_PER_KIND: u32 = 100;

impl GenerateSpec {
    /// Checks every value; `fail` builds an error at a key path inside `[generate]`.
    ///
    /// # Errors
    /// The first bad value: a range with min above max, a negative size, a probability outside [0, 1].
    pub fn check(&self, fail: impl Fn(&[KeySeg<'_>], String) -> EvalError) -> Result<(), EvalError> {
        use KeySeg::Key as K;
        let fail: Fail<'_> = &fail;
        for (name, v) in [
            ("drive_length_m", self.drive_length_m),
            ("speed_m_s", self.speed_m_s),
            ("field_length_m", self.field_length_m),
            ("field_half_width_m", self.field_half_width_m),
            ("lane_half_width_m", self.lane_half_width_m),
            ("navigation_time_s", self.navigation_time_s),
        ] {
            if !(v.is_finite() && v > 0.0 && v <= 1000.0) {
                return Err(fail(
                    &[K(name)],
                    format!("expected a positive length or speed up to 1000, got {v}"),
                ));
            }
        }
        for (name, v) in [
            ("field_start_m", self.field_start_m),
            ("settle_s", self.settle_s),
            ("goal_beyond_m", self.goal_beyond_m),
        ] {
            if !(v.is_finite() && (0.0..=1000.0).contains(&v)) {
                return Err(fail(
                    &[K(name)],
                    format!("expected a value in [0, 1000], got {v}"),
                ));
            }
        }
        if self.lane_half_width_m >= self.field_half_width_m {
            return Err(fail(
                &[K("lane_half_width_m")],
                "expected a lane narrower than the field (lane_half_width_m < field_half_width_m)".into(),
            ));
        }
        if let Some(c) = &self.curbs {
            check_count(c.count, &[K("curbs"), K("count")], fail)?;
            check_range(c.height_m, &[K("curbs"), K("height_m")], true, fail)?;
            check_range(c.length_m, &[K("curbs"), K("length_m")], true, fail)?;
            check_range(c.depth_m, &[K("curbs"), K("depth_m")], true, fail)?;
            check_range(c.yaw_deg, &[K("curbs"), K("yaw_deg")], false, fail)?;
        }
        if let Some(b) = &self.boards {
            check_count(b.count, &[K("boards"), K("count")], fail)?;
            check_range(b.clearance_m, &[K("boards"), K("clearance_m")], true, fail)?;
            check_range(b.length_m, &[K("boards"), K("length_m")], true, fail)?;
            check_range(b.width_m, &[K("boards"), K("width_m")], true, fail)?;
            check_range(b.thickness_m, &[K("boards"), K("thickness_m")], true, fail)?;
            check_range(b.yaw_deg, &[K("boards"), K("yaw_deg")], false, fail)?;
        }
        if let Some(w) = &self.walls {
            check_count(w.count, &[K("walls"), K("count")], fail)?;
            check_range(w.height_m, &[K("walls"), K("height_m")], true, fail)?;
            check_range(w.length_m, &[K("walls"), K("length_m")], true, fail)?;
            check_range(w.thickness_m, &[K("walls"), K("thickness_m")], true, fail)?;
            check_range(w.yaw_deg, &[K("walls"), K("yaw_deg")], false, fail)?;
        }
        if let Some(b) = &self.bushes {
            check_count(b.count, &[K("bushes"), K("count")], fail)?;
            check_range(b.radius_m, &[K("bushes"), K("radius_m")], true, fail)?;
            check_range(b.height_m, &[K("bushes"), K("height_m")], true, fail)?;
        }
        if let Some(r) = &self.ramps {
            check_count(r.count, &[K("ramps"), K("count")], fail)?;
            check_range(r.height_m, &[K("ramps"), K("height_m")], true, fail)?;
            check_range(r.length_m, &[K("ramps"), K("length_m")], true, fail)?;
            check_range(r.width_m, &[K("ramps"), K("width_m")], true, fail)?;
            check_range(r.yaw_deg, &[K("ramps"), K("yaw_deg")], false, fail)?;
        }
        if let Some(p) = &self.people {
            check_count(p.count, &[K("people"), K("count")], fail)?;
            check_range(p.stand_s, &[K("people"), K("stand_s")], true, fail)?;
            for (name, v) in [
                ("stand_probability", p.stand_probability),
                ("robot_standing_probability", p.robot_standing_probability),
            ] {
                if !(0.0..=1.0).contains(&v) {
                    return Err(fail(
                        &[K("people"), K(name)],
                        format!("expected a probability in [0, 1], got {v}"),
                    ));
                }
            }
            if !(p.walk_speed_m_s.is_finite() && p.walk_speed_m_s > 0.0 && p.walk_speed_m_s <= 10.0) {
                return Err(fail(
                    &[K("people"), K("walk_speed_m_s")],
                    format!("expected a speed in (0, 10] m/s, got {}", p.walk_speed_m_s),
                ));
            }
        }
        Ok(())
    }

    fn field_end_m(&self) -> f64 {
        self.field_start_m + self.field_length_m
    }

    fn goal(&self) -> [f64; 2] {
        [self.field_end_m() + self.goal_beyond_m, 0.0]
    }

    /// Places this seed's scene into `doc` (a base scenario): obstacles and people appended, the drive, the
    /// planner's start and goal, the map region and the duration set.
    pub fn place(&self, seed: u64, doc: &mut Table) {
        let mut placer = Placer {
            spec: self,
            taken: Vec::new(),
            obstacles: Vec::new(),
        };
        self.place_obstacles(seed, &mut placer);
        let (actors, last_s) = self.people(seed);
        append(doc, "obstacles", placer.obstacles);
        append(doc, "actors", actors);
        self.set_frame(doc, last_s);
    }

    /// Curbs, boards, walls, bushes and ramps, each kind from its own random stream (`generate/<kind>`).
    fn place_obstacles(&self, seed: u64, placer: &mut Placer<'_>) {
        if let Some(c) = &self.curbs {
            let mut rng = sim::seed::stream(seed, "generate/curbs");
            for k in 0..count(&mut rng, c.count) {
                let h = uniform(&mut rng, c.height_m);
                let (len, depth) = (uniform(&mut rng, c.length_m), uniform(&mut rng, c.depth_m));
                let yaw = uniform(&mut rng, c.yaw_deg);
                placer.place(&mut rng, 0.5 * len.hypot(depth), true, |[x, y]| {
                    obstacle(&[
                        ("kind", s("box")),
                        ("name", s(&format!("curb {k}: {:.1} cm", h * 100.0))),
                        ("center_xy_m", xy(x, y)),
                        ("size_m", floats(&[depth, len, h])),
                        ("yaw_deg", f(yaw)),
                    ])
                });
            }
        }
        if let Some(b) = &self.boards {
            let mut rng = sim::seed::stream(seed, "generate/boards");
            for k in 0..count(&mut rng, b.count) {
                let clearance = uniform(&mut rng, b.clearance_m);
                let (len, width) = (uniform(&mut rng, b.length_m), uniform(&mut rng, b.width_m));
                let thick = uniform(&mut rng, b.thickness_m);
                let yaw = uniform(&mut rng, b.yaw_deg);
                placer.place(&mut rng, 0.5 * len.hypot(width), true, |[x, y]| {
                    obstacle(&[
                        ("kind", s("overhang")),
                        ("name", s(&format!("board {k}: {clearance:.3} m"))),
                        ("center_xy_m", xy(x, y)),
                        ("size_m", floats(&[len, width, thick])),
                        ("clearance_m", f(clearance)),
                        ("yaw_deg", f(yaw)),
                    ])
                });
            }
        }
        if let Some(w) = &self.walls {
            let mut rng = sim::seed::stream(seed, "generate/walls");
            for k in 0..count(&mut rng, w.count) {
                let h = uniform(&mut rng, w.height_m);
                let (len, thick) = (uniform(&mut rng, w.length_m), uniform(&mut rng, w.thickness_m));
                let yaw = uniform(&mut rng, w.yaw_deg);
                placer.place(&mut rng, 0.5 * len.hypot(thick), true, |[x, y]| {
                    obstacle(&[
                        ("kind", s("box")),
                        ("name", s(&format!("wall {k}: {h:.2} m"))),
                        ("center_xy_m", xy(x, y)),
                        ("size_m", floats(&[thick, len, h])),
                        ("yaw_deg", f(yaw)),
                    ])
                });
            }
        }
        if let Some(b) = &self.bushes {
            let mut rng = sim::seed::stream(seed, "generate/bushes");
            for k in 0..count(&mut rng, b.count) {
                let (r, h) = (uniform(&mut rng, b.radius_m), uniform(&mut rng, b.height_m));
                placer.place(&mut rng, r, false, |[x, y]| {
                    obstacle(&[
                        ("kind", s("bush")),
                        ("name", s(&format!("bush {k}: {h:.2} m"))),
                        ("center_xy_m", xy(x, y)),
                        ("radius_m", f(r)),
                        ("height_m", f(h)),
                    ])
                });
            }
        }
        if let Some(ramps) = &self.ramps {
            let mut rng = sim::seed::stream(seed, "generate/ramps");
            for k in 0..count(&mut rng, ramps.count) {
                let h = uniform(&mut rng, ramps.height_m);
                let (len, width) = (
                    uniform(&mut rng, ramps.length_m),
                    uniform(&mut rng, ramps.width_m),
                );
                let yaw = uniform(&mut rng, ramps.yaw_deg);
                placer.place(&mut rng, 0.5 * len.hypot(width), true, |[x, y]| {
                    obstacle(&[
                        ("kind", s("ramp")),
                        ("name", s(&format!("ramp {k}: {h:.2} m"))),
                        ("center_xy_m", xy(x, y)),
                        ("length_m", f(len)),
                        ("width_m", f(width)),
                        ("height_m", f(h)),
                        ("yaw_deg", f(yaw)),
                    ])
                });
            }
        }
    }

    /// The people, from the stream `generate/people`, and the time the last of them has left (at least the
    /// end of the drive).
    fn people(&self, seed: u64) -> (Vec<Value>, f64) {
        let drive_time_s = self.drive_length_m / self.speed_m_s;
        let mut last_s = drive_time_s;
        let mut actors = Vec::new();
        if let Some(p) = &self.people {
            let mut rng = sim::seed::stream(seed, "generate/people");
            let side = self.field_half_width_m + 0.4;
            for k in 0..count(&mut rng, p.count) {
                let from = if rng.random_bool(0.5) { side } else { -side };
                let (waypoints, name) = if rng.random_bool(p.stand_probability) {
                    // Walks in from the side, stands on the lane in front of the robot, walks out the other side.
                    let robot_standing = rng.random_bool(p.robot_standing_probability);
                    let stand = uniform(&mut rng, p.stand_s);
                    let x = self.drive_length_m + uniform(&mut rng, [1.2, 2.0]);
                    let walk = side / p.walk_speed_m_s;
                    let arrive = if robot_standing {
                        drive_time_s + uniform(&mut rng, [0.5, 2.0])
                    } else {
                        uniform(&mut rng, [0.0, 0.5 * drive_time_s]) + walk
                    };
                    let leave = arrive + stand;
                    (
                        vec![
                            [arrive - walk, x, from],
                            [arrive, x, 0.0],
                            [leave, x, 0.0],
                            [leave + walk, x, -from],
                        ],
                        format!(
                            "person {k}: stands {stand:.1} s before a {} robot",
                            if robot_standing { "standing" } else { "moving" }
                        ),
                    )
                } else {
                    let x = uniform(&mut rng, [self.field_start_m, self.field_end_m()]);
                    let start = uniform(&mut rng, [0.0, drive_time_s]);
                    let cross = 2.0 * side / p.walk_speed_m_s;
                    (
                        vec![[start, x, from], [start + cross, x, -from]],
                        format!("person {k}: walks through"),
                    )
                };
                last_s = last_s.max(waypoints[waypoints.len() - 1][0]);
                let mut t = Table::new();
                t.insert("kind".into(), s("person"));
                t.insert("name".into(), s(&name));
                t.insert(
                    "waypoints".into(),
                    Value::Array(waypoints.iter().map(|w| floats(w)).collect()),
                );
                actors.push(Value::Table(t));
            }
        }
        (actors, last_s)
    }

    /// The map region around the field, the drive along the lane, the planner's start and goal, and the
    /// duration: until the last person has left, and `settle_s` more.
    fn set_frame(&self, doc: &mut Table, last_s: f64) {
        let end = self.field_end_m();
        let half = self.field_half_width_m;
        set(doc, &["map", "min_xy_m"], xy(-1.0, -half - 1.0));
        set(
            doc,
            &["map", "max_xy_m"],
            xy(end.max(self.goal()[0]) + 1.0, half + 1.0),
        );
        set(
            doc,
            &["robot", "drive", "waypoints_xy_m"],
            Value::Array(vec![xy(0.0, 0.0), xy(self.drive_length_m, 0.0)]),
        );
        set(doc, &["robot", "drive", "speed_m_s"], f(self.speed_m_s));
        set(doc, &["planner", "start_xy_m"], xy(0.0, 0.0));
        let [gx, gy] = self.goal();
        set(doc, &["planner", "goal_xy_m"], xy(gx, gy));
        let mut duration = last_s + self.settle_s;
        if self.navigate {
            let drive_s = self.drive_length_m / self.speed_m_s;
            duration = duration.max(drive_s + self.navigation_time_s);
            let mut navigation = Table::new();
            navigation.insert("goal_xy_m".into(), xy(gx, gy));
            navigation.insert("speed_m_s".into(), f(self.speed_m_s));
            navigation.insert("time_limit_s".into(), f(self.navigation_time_s));
            doc.insert("navigation".into(), Value::Table(navigation));
        }
        set(doc, &["duration_s"], f((duration * 10.0).ceil() / 10.0));
    }
}

/// Places obstacles without overlap, out of the lane the robot drives and away from the goal.
struct Placer<'a> {
    spec: &'a GenerateSpec,
    /// Centres and radii placed so far.
    taken: Vec<([f64; 2], f64)>,
    obstacles: Vec<Value>,
}

/// Tries per obstacle before the field counts as full and the obstacle is left out.
const PLACEMENT_TRIES: u32 = 200;

impl Placer<'_> {
    /// Draws a centre for an obstacle of bounding radius `r`; `may_block_lane`: it may stand in the lane
    /// beyond the robot's stop (it is what the robot faces).
    fn place(
        &mut self,
        rng: &mut sim::seed::Stream,
        r: f64,
        may_block_lane: bool,
        make: impl FnOnce([f64; 2]) -> Value,
    ) {
        let g = self.spec;
        let stop = g.drive_length_m + 0.6;
        for _ in 0..PLACEMENT_TRIES {
            let c = [
                uniform(rng, [g.field_start_m, g.field_end_m()]),
                uniform(rng, [-g.field_half_width_m, g.field_half_width_m]),
            ];
            let in_lane_of_drive = c[0] - r < stop && c[1].abs() - r < g.lane_half_width_m;
            let [gx, gy] = g.goal();
            let near_goal = (c[0] - gx).hypot(c[1] - gy) < r + 0.6;
            let blocks_lane = !may_block_lane && c[1].abs() - r < g.lane_half_width_m;
            let overlaps = self
                .taken
                .iter()
                .any(|(o, ro)| (c[0] - o[0]).hypot(c[1] - o[1]) < r + ro + 0.2);
            if !(in_lane_of_drive || near_goal || overlaps || blocks_lane) {
                self.taken.push((c, r));
                self.obstacles.push(make([round(c[0]), round(c[1])]));
                return;
            }
        }
    }
}

fn count(rng: &mut sim::seed::Stream, c: Count) -> u32 {
    rng.random_range(c[0]..=c[1])
}

fn uniform(rng: &mut sim::seed::Stream, r: Range) -> f64 {
    if r[0] >= r[1] {
        return r[0];
    }
    round(rng.random_range(r[0]..r[1]))
}

/// Generated values to the tenth of a millimetre (or degree): the scenario file reads as written by hand.
fn round(v: f64) -> f64 {
    (v * 1e4).round() / 1e4
}

fn s(text: &str) -> Value {
    Value::String(text.into())
}

fn f(v: f64) -> Value {
    Value::Float(v)
}

fn floats(v: &[f64]) -> Value {
    Value::Array(v.iter().map(|x| f(*x)).collect())
}

fn xy(x: f64, y: f64) -> Value {
    floats(&[x, y])
}

fn obstacle(fields: &[(&str, Value)]) -> Value {
    Value::Table(
        fields
            .iter()
            .map(|(k, v)| ((*k).to_string(), v.clone()))
            .collect(),
    )
}

fn append(doc: &mut Table, key: &str, items: Vec<Value>) {
    if items.is_empty() {
        return;
    }
    match doc.get_mut(key) {
        Some(Value::Array(a)) => a.extend(items),
        _ => {
            doc.insert(key.into(), Value::Array(items));
        }
    }
}

fn set(doc: &mut Table, path: &[&str], value: Value) {
    let Some((last, parents)) = path.split_last() else {
        return;
    };
    let mut here = doc;
    for p in parents {
        let entry = here
            .entry((*p).to_string())
            .or_insert_with(|| Value::Table(Table::new()));
        if !entry.is_table() {
            *entry = Value::Table(Table::new());
        }
        let Value::Table(t) = entry else { return };
        here = t;
    }
    here.insert((*last).to_string(), value);
}

#[cfg(test)]
#[allow(clippy::disallowed_methods, reason = "tests read back the files they wrote")]
mod tests {
    use std::path::{Path, PathBuf};

    use super::*;

    fn spec() -> GenerateSpec {
        toml::from_str(
            "base = \"x.toml\"\ncurbs = { count = [2, 4] }\nboards = { count = [1, 3] }\nwalls = { count = [1, 2] }\n\
             bushes = { count = [0, 2] }\nramps = { count = [0, 2] }\npeople = { count = [1, 3] }\n",
        )
        .expect("spec")
    }

    fn base() -> (PathBuf, Table) {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../sweeps/bases/smoke.toml");
        let text = std::fs::read_to_string(&path).expect("base");
        (path, toml::from_str(&text).expect("toml"))
    }

    #[test]
    fn generated_scenes_are_valid_deterministic_and_keep_the_drive_clear() {
        let (path, base) = base();
        let g = spec();
        for seed in 0..40u64 {
            let mut a = base.clone();
            g.place(seed, &mut a);
            let mut b = base.clone();
            g.place(seed, &mut b);
            assert_eq!(a, b, "seed {seed}: the same scene twice");
            let text = toml::to_string(&a).expect("text");
            let loaded = sim::scenario::load_str(&path, &text).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
            let s = &loaded.scenario;
            assert!(!s.obstacles.is_empty() && !s.actors.is_empty(), "seed {seed}");
            for o in &s.obstacles {
                let [x, y] = o.center_xy_m();
                assert!((g.field_start_m..=g.field_end_m()).contains(&x), "{o:?}");
                assert!(y.abs() <= g.field_half_width_m, "{o:?}");
                // Nothing stands in the lane the robot drives.
                if x < g.drive_length_m {
                    assert!(y.abs() > g.lane_half_width_m, "seed {seed}: {o:?} in the lane");
                }
            }
            // People leave before the run ends, and the robot faces the field.
            for sim::scenario::Actor::Person { waypoints, .. } in &s.actors {
                let last = waypoints[waypoints.len() - 1];
                assert!(last[0] < s.duration_s, "seed {seed}");
            }
            assert_eq!(
                s.robot.drive.waypoints_xy_m,
                vec![[0.0, 0.0], [g.drive_length_m, 0.0]]
            );
        }
        let (mut a, mut b) = (base.clone(), base);
        g.place(1, &mut a);
        g.place(2, &mut b);
        assert_ne!(a, b, "another seed, another scene");
    }

    #[test]
    fn a_goal_beyond_the_field_is_navigated_to_in_closed_loop() {
        let (path, base) = base();
        let g = GenerateSpec {
            goal_beyond_m: 2.0,
            navigate: true,
            navigation_time_s: 30.0,
            ..spec()
        };
        let mut doc = base.clone();
        g.place(3, &mut doc);
        let text = toml::to_string(&doc).expect("text");
        let s = sim::scenario::load_str(&path, &text).expect("valid").scenario;
        let n = s.navigation.expect("a closed-loop run");
        assert_eq!(n.goal_xy_m, [g.field_end_m() + 2.0, 0.0]);
        assert_eq!(n.time_limit_s, Some(30.0));
        assert!(
            s.map.max_xy_m[0] >= n.goal_xy_m[0] + 1.0,
            "the region holds the goal"
        );
        assert!(s.duration_s >= g.drive_length_m / g.speed_m_s + 30.0);
        for o in &s.obstacles {
            let [x, y] = o.center_xy_m();
            assert!(
                (x - n.goal_xy_m[0]).hypot(y - n.goal_xy_m[1]) > 0.6,
                "{o:?} at the goal"
            );
        }
        // Without `navigate`, the goal is the planner check's only.
        let mut open = base;
        GenerateSpec {
            goal_beyond_m: 2.0,
            ..spec()
        }
        .place(3, &mut open);
        assert!(!open.contains_key("navigation"));
        assert_eq!(
            open["planner"]["goal_xy_m"][0].as_float(),
            Some(g.field_end_m() + 2.0)
        );
    }

    #[test]
    fn heights_fall_in_their_ranges_and_straddle_the_step() {
        let (_, base) = base();
        let g = spec();
        let mut heights = Vec::new();
        for seed in 0..40u64 {
            let mut doc = base.clone();
            g.place(seed, &mut doc);
            for o in doc["obstacles"].as_array().expect("obstacles") {
                if o["name"].as_str().is_some_and(|n| n.starts_with("curb")) {
                    heights.push(o["size_m"][2].as_float().expect("height"));
                }
            }
        }
        assert!(heights.iter().all(|h| (0.02..=0.05).contains(h)));
        assert!(heights.iter().any(|h| *h < 0.035) && heights.iter().any(|h| *h > 0.035));
    }
}
