//! A seed's scene placed into a base scenario: obstacles without overlap and out of the robot's lane, people
//! on their walks, the drive, the planner's ends, the map region and the duration, as TOML values.

use rand::RngExt;
use toml::{Table, Value};

use super::{Count, GenerateSpec, Range};

impl GenerateSpec {
    pub(super) fn field_end_m(&self) -> f64 {
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
