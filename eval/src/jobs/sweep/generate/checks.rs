//! The `[generate]` table's values checked for sense, each error at its key.

use sim::scenario::KeySeg;

use super::{Count, GenerateSpec, Range};
use crate::error::EvalError;

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
pub(super) const MAX_PER_KIND: u32 = 100;

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
}
