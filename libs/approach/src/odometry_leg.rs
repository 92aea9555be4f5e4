//! The last metres on the odometry (see `odometry_leg_fit_margin`): where the camera cannot see
//! the spinner whole at the target, the approach fixes the hub from the image a little farther
//! out and flies the rest on the autopilot's position, straight along the line it stood on,
//! facing the fixed hub, then settles at the goal and holds it.
//!
//! A plain state machine over the vehicle states the caller feeds it; it says what to command
//! and leaves the rate limits to the caller.

use crate::{limit, limit_abs, secs, wrap_pi, ApproachConfig, HubFix};
use hubtrack_types::VehicleState;

/// One odometry leg: the hub fixed at its start and the goal `target_distance_m` short of it on
/// the line from where the vehicle stood.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct OdometryLeg {
    /// The fixed hub, north and east, m.
    hub: [f64; 2],
    /// Where the leg ends, north and east, m.
    goal: [f64; 2],
    /// The odometry's distance to the hub at the start, m.
    start_distance_m: f64,
    started_ns: u64,
    /// Since when the vehicle has stood within `distance_tolerance_m` of the goal.
    at_goal_since_ns: Option<u64>,
    /// Settled at the goal for `done_hold_s`; left beyond `distance_tolerance_outer_m`.
    done: bool,
}

/// What one step of the leg asks for (body frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct LegStep {
    /// Forward velocity target, m/s.
    pub vx: f64,
    /// Right velocity target, m/s.
    pub vy: f64,
    /// Yaw-rate target, rad/s, clockwise (0 once settling).
    pub yaw_rate: f64,
    /// The odometry's distance to the fixed hub, m.
    pub distance_m: f64,
    /// How far the vehicle stands from the goal, m.
    pub off_goal_m: f64,
    /// Settling at the goal for this long, s.
    pub settling_s: Option<f64>,
    /// Settled: the leg's Done.
    pub done: bool,
}

impl OdometryLeg {
    /// A leg towards `hub` from where `v` stands; `None` without a valid position and attitude
    /// or with the hub no farther than the target.
    pub(crate) fn start(
        hub: HubFix,
        v: &VehicleState,
        c: &ApproachConfig,
        now: u64,
    ) -> Option<OdometryLeg> {
        let v = Some(v).filter(|v| v.position_valid && v.attitude_valid)?;
        let [n, e, _] = v.position_ned_m;
        let (dn, de) = (hub.north_east[0] - n, hub.north_east[1] - e);
        let from_m = dn.hypot(de);
        if !(from_m.is_finite() && from_m > c.target_distance_m) {
            return None;
        }
        let k = c.target_distance_m / from_m;
        Some(OdometryLeg {
            hub: hub.north_east,
            goal: [hub.north_east[0] - k * dn, hub.north_east[1] - k * de],
            start_distance_m: from_m,
            started_ns: now,
            at_goal_since_ns: None,
            done: false,
        })
    }

    /// The odometry's distance to the hub when the leg started, m.
    pub(crate) fn start_distance_m(&self) -> f64 {
        self.start_distance_m
    }

    /// Seconds since the leg started.
    pub(crate) fn age_s(&self, now: u64) -> f64 {
        secs(self.started_ns, now)
    }

    /// Not done after `odometry_leg_max_s`; once done, the leg holds the goal for good.
    pub(crate) fn overdue(&self, c: &ApproachConfig, now: u64) -> bool {
        !self.done && self.age_s(now) > c.odometry_leg_max_s
    }

    /// One step from the vehicle state `v` (position and attitude valid, checked by the caller).
    pub(crate) fn step(&mut self, c: &ApproachConfig, now: u64, v: &VehicleState) -> LegStep {
        let [n, e, _] = v.position_ned_m;
        let (gn, ge) = (self.goal[0] - n, self.goal[1] - e);
        let (hn, he) = (self.hub[0] - n, self.hub[1] - e);
        let distance_m = hn.hypot(he);
        let off_goal_m = gn.hypot(ge);
        // The goal in the body frame.
        let (sin, cos) = v.yaw_rad.sin_cos();
        let ahead = cos * gn + sin * ge;
        let right = -sin * gn + cos * ge;

        if off_goal_m <= c.distance_tolerance_m {
            self.at_goal_since_ns.get_or_insert(now);
        } else if !self.done || off_goal_m > c.distance_tolerance_outer_m {
            self.at_goal_since_ns = None;
            self.done = false;
        }
        let settling_s = self.at_goal_since_ns.map(|s| secs(s, now));
        if settling_s.is_some_and(|s| s >= c.done_hold_s) {
            self.done = true;
        }
        if settling_s.is_some() {
            // At the goal: hover there at the station-keeping gains, heading held.
            return LegStep {
                vx: c.done_distance_gain_per_s * ahead,
                vy: c.done_lateral_gain_per_s * right,
                yaw_rate: 0.0,
                distance_m,
                off_goal_m,
                settling_s,
                done: self.done,
            };
        }
        // Towards the goal at the approach's gains, slower near the hub as T3 is.
        let cap = (c.slowdown_gain_per_s * (distance_m - c.min_distance_m)).max(0.0);
        let vx = limit(
            c.forward_gain_per_s * ahead,
            -c.max_backward_m_s,
            c.max_forward_m_s.min(cap),
        );
        let vy = limit_abs(c.done_lateral_gain_per_s * right, c.max_lateral_m_s);
        let yaw_rate = limit_abs(
            c.odometry_leg_yaw_gain_per_s * wrap_pi(he.atan2(hn) - v.yaw_rad),
            c.max_yaw_rate_deg_s.to_radians(),
        );
        LegStep {
            vx,
            vy,
            yaw_rate,
            distance_m,
            off_goal_m,
            settling_s,
            done: false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(north: f64, east: f64, yaw_deg: f64) -> VehicleState {
        VehicleState {
            position_valid: true,
            attitude_valid: true,
            position_ned_m: [north, east, -80.0],
            yaw_rad: yaw_deg.to_radians(),
            ..VehicleState::default()
        }
    }

    fn hub(north: f64, east: f64) -> HubFix {
        HubFix {
            north_east: [north, east],
            at_ns: 0,
        }
    }

    #[test]
    fn the_goal_lies_on_the_line_target_short_of_the_hub() {
        let c = ApproachConfig::default();
        // The hub 6.7 m away, 10° right of where the vehicle faces.
        let mut leg = OdometryLeg::start(hub(6.0, 3.0), &at(0.0, 0.0, 16.6), &c, 0).unwrap();
        assert!((leg.start_distance_m() - 45f64.sqrt()).abs() < 1e-9);
        let s = leg.step(&c, 0, &at(0.0, 0.0, 16.6));
        // 1.71 m to go along the line: forward at the T3 gain; the hub 10° right: turn right.
        assert!((s.off_goal_m - (45f64.sqrt() - 5.0)).abs() < 1e-9, "{s:?}");
        assert!((s.distance_m - 45f64.sqrt()).abs() < 1e-9);
        assert!(
            s.vx > 0.0 && s.yaw_rate > 0.0 && s.settling_s.is_none(),
            "{s:?}"
        );
        // At the goal: settling, Done after done_hold_s, left beyond the outer tolerance.
        let goal = [
            6.0 - 6.0 * 5.0 / 45f64.sqrt(),
            3.0 - 3.0 * 5.0 / 45f64.sqrt(),
        ];
        let s = leg.step(&c, 1, &at(goal[0], goal[1], 26.6));
        assert_eq!(s.settling_s, Some(0.0));
        assert!((s.distance_m - 5.0).abs() < 1e-9 && s.yaw_rate == 0.0 && !s.done);
        let hold_ns = (c.done_hold_s * 1e9) as u64 + 2;
        assert!(leg.step(&c, hold_ns, &at(goal[0], goal[1], 26.6)).done);
        let pushed = leg.step(&c, hold_ns + 1, &at(goal[0] - 0.4, goal[1], 26.6));
        assert!(pushed.done, "inside the outer tolerance Done holds");
        assert!(pushed.vx > 0.0, "and steers back: {pushed:?}");
        let out = leg.step(&c, hold_ns + 2, &at(goal[0] - 0.6, goal[1], 26.6));
        assert!(!out.done && out.settling_s.is_none(), "{out:?}");
    }

    #[test]
    fn no_leg_without_a_position_or_inside_the_target() {
        let c = ApproachConfig::default();
        let mut blind = at(0.0, 0.0, 0.0);
        blind.position_valid = false;
        assert!(OdometryLeg::start(hub(7.0, 0.0), &blind, &c, 0).is_none());
        assert!(OdometryLeg::start(hub(4.0, 0.0), &at(0.0, 0.0, 0.0), &c, 0).is_none());
        let far = OdometryLeg::start(hub(7.0, 0.0), &at(0.0, 0.0, 0.0), &c, 0);
        assert!(far.is_some());
    }
}
