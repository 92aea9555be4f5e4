//! Flight metrics and the success decision.
//!
//! A flight succeeds when, at its end, the vehicle hovers at the target: the camera–hub distance
//! is within `distance_tolerance_m` of `target_distance_m`, |relative yaw| ≤ `yaw_tolerance_deg`,
//! the final speed is below `hover_speed_m_s`, the end time is within the time limit, and the
//! vehicle never came closer to the rotor plane than `min_rotor_plane_m` (checked over the whole
//! flight, including the end).
//!
//! The final speed is the RMS speed over the last [`HOVER_WINDOW_S`] of recorded steps (and the
//! final state): one instant can be caught in a gust peak or a zero crossing, a second cannot
//! hide a vehicle that is still moving.

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};

use crate::math::norm;
use crate::params::{SimConfig, SuccessConfig};
use crate::scenario::Geometry;
use crate::vehicle::Multicopter;

/// Window of the final-speed measurement, s.
pub const HOVER_WINDOW_S: f64 = 1.0;

/// The result of one simulated flight.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Outcome {
    /// Scenario seed.
    pub seed: u64,
    /// All success conditions hold.
    pub success: bool,
    /// Final 3D camera–hub distance, m.
    pub final_distance_m: f64,
    /// Final relative yaw, degrees.
    pub final_yaw_deg: f64,
    /// Final sideways offset from the rotor axis, m (+ = viewer's right).
    pub final_lateral_m: f64,
    /// Final height minus hub height, m.
    pub final_height_m: f64,
    /// RMS speed over the last [`HOVER_WINDOW_S`], m/s.
    pub final_speed_m_s: f64,
    /// Simulated time at the end, s.
    pub time_s: f64,
    /// Distance flown, m.
    pub path_length_m: f64,
    /// Smallest distance in front of the rotor plane over the flight, m.
    pub min_rotor_plane_m: f64,
    /// Smallest 3D camera–hub distance over the flight, m.
    pub min_distance_m: f64,
    /// Why the flight ended (given by the simulator, e.g. "arrived", "max_time", "control exited").
    pub end_reason: String,
    /// Why it is not a success, in words (`None` on success).
    pub failure: Option<String>,
    /// Lockstep waits that timed out (`sim.lockstep_timeout_ms`): the simulator went on without
    /// the pipeline's vehicle state or setpoint of that frame. Only a flight without misses is
    /// reproducible from its seed; misses mean the machine was too loaded for lockstep.
    #[serde(default)]
    pub lockstep_misses: u64,
}

/// Accumulates a flight: path length, closest approaches, recent speeds, time at the target.
#[derive(Debug, Clone)]
pub struct FlightRecorder {
    seed: u64,
    cfg: SuccessConfig,
    max_time_s: f64,
    last_pos: Option<[f64; 3]>,
    path_length_m: f64,
    min_rotor_plane_m: f64,
    min_distance_m: f64,
    recent: VecDeque<(f64, f64)>,
    at_target_since: Option<f64>,
    last_t: f64,
}

impl FlightRecorder {
    /// A recorder for the flight of `seed`, without a time limit (see
    /// [`FlightRecorder::with_max_time`] and [`FlightRecorder::from_config`]).
    pub fn new(seed: u64, cfg: &SuccessConfig) -> Self {
        FlightRecorder {
            seed,
            cfg: cfg.clone(),
            max_time_s: f64::INFINITY,
            last_pos: None,
            path_length_m: 0.0,
            min_rotor_plane_m: f64::INFINITY,
            min_distance_m: f64::INFINITY,
            recent: VecDeque::new(),
            at_target_since: None,
            last_t: 0.0,
        }
    }

    /// The same with a time limit: flights ending after `max_time_s` fail.
    pub fn with_max_time(mut self, max_time_s: f64) -> Self {
        self.max_time_s = max_time_s;
        self
    }

    /// A recorder with the success rules and time limit of `cfg`.
    pub fn from_config(seed: u64, cfg: &SimConfig) -> Self {
        FlightRecorder::new(seed, &cfg.success).with_max_time(cfg.max_time_s)
    }

    /// Record the state at `t_s` (call after every physics step, or at least every frame).
    pub fn step(&mut self, t_s: f64, vehicle: &Multicopter, geo: &Geometry) {
        let p = vehicle.position_ned();
        if let Some(q) = self.last_pos {
            self.path_length_m += norm([p[0] - q[0], p[1] - q[1], p[2] - q[2]]);
        }
        self.last_pos = Some(p);
        self.min_rotor_plane_m = self.min_rotor_plane_m.min(geo.rotor_plane_m);
        self.min_distance_m = self.min_distance_m.min(geo.distance_m);
        let speed = norm(vehicle.velocity_ned());
        self.recent.push_back((t_s, speed));
        while self
            .recent
            .front()
            .is_some_and(|&(t, _)| t < t_s - HOVER_WINDOW_S)
        {
            self.recent.pop_front();
        }
        if self.at_target_now(geo, speed) {
            self.at_target_since.get_or_insert(t_s);
        } else {
            self.at_target_since = None;
        }
        self.last_t = t_s;
    }

    fn at_target_now(&self, geo: &Geometry, speed: f64) -> bool {
        let c = &self.cfg;
        (geo.distance_m - c.target_distance_m).abs() <= c.distance_tolerance_m
            && geo.relative_yaw_deg.abs() <= c.yaw_tolerance_deg
            && speed < c.hover_speed_m_s
    }

    /// How long (s) the vehicle has been continuously at the target (distance, yaw and
    /// instantaneous speed within their tolerances) up to the last [`FlightRecorder::step`]; 0 if
    /// not there now. A simulator can end a flight once this exceeds a settling time.
    pub fn time_at_target_s(&self) -> f64 {
        self.at_target_since.map_or(0.0, |t0| self.last_t - t0)
    }

    /// Path length so far, m.
    pub fn path_length_m(&self) -> f64 {
        self.path_length_m
    }

    /// Decide the outcome with the final state at `t_s` (also recorded, if not already).
    pub fn finish(
        &self,
        t_s: f64,
        vehicle: &Multicopter,
        geo: &Geometry,
        end_reason: &str,
    ) -> Outcome {
        let mut rec = self.clone();
        if rec.last_pos.is_none() || t_s > rec.last_t {
            rec.step(t_s, vehicle, geo);
        } else {
            // Same instant as the last step: the minima must still include the final state.
            rec.min_rotor_plane_m = rec.min_rotor_plane_m.min(geo.rotor_plane_m);
            rec.min_distance_m = rec.min_distance_m.min(geo.distance_m);
        }
        let n = rec.recent.len().max(1) as f64;
        let final_speed = (rec.recent.iter().map(|&(_, s)| s * s).sum::<f64>() / n).sqrt();

        let c = &self.cfg;
        let mut why = Vec::new();
        let derr = geo.distance_m - c.target_distance_m;
        if !at_most(derr.abs(), c.distance_tolerance_m) {
            why.push(format!(
                "final distance {:.2} m is not within {} ± {} m",
                geo.distance_m, c.target_distance_m, c.distance_tolerance_m
            ));
        }
        if !at_most(geo.relative_yaw_deg.abs(), c.yaw_tolerance_deg) {
            why.push(format!(
                "final relative yaw {:.1}° exceeds ±{}°",
                geo.relative_yaw_deg, c.yaw_tolerance_deg
            ));
        }
        if !below(final_speed, c.hover_speed_m_s) {
            why.push(format!(
                "not hovering: speed {final_speed:.2} m/s (limit {} m/s)",
                c.hover_speed_m_s
            ));
        }
        if !at_most(t_s, self.max_time_s) {
            why.push(format!("took {t_s:.1} s (limit {} s)", self.max_time_s));
        }
        if !at_most(c.min_rotor_plane_m, rec.min_rotor_plane_m) {
            why.push(format!(
                "came within {:.2} m of the rotor plane (minimum {} m)",
                rec.min_rotor_plane_m, c.min_rotor_plane_m
            ));
        }
        Outcome {
            seed: self.seed,
            success: why.is_empty(),
            final_distance_m: geo.distance_m,
            final_yaw_deg: geo.relative_yaw_deg,
            final_lateral_m: geo.lateral_m,
            final_height_m: geo.height_m,
            final_speed_m_s: final_speed,
            time_s: t_s,
            path_length_m: rec.path_length_m,
            min_rotor_plane_m: rec.min_rotor_plane_m,
            min_distance_m: rec.min_distance_m,
            end_reason: end_reason.to_string(),
            failure: if why.is_empty() {
                None
            } else {
                Some(why.join("; "))
            },
            lockstep_misses: 0,
        }
    }
}

/// `a <= b`; false when either is NaN, so a NaN measure fails the check it is in.
fn at_most(a: f64, b: f64) -> bool {
    a <= b
}

/// `a < b`; false when either is NaN, so a NaN measure fails the check it is in.
fn below(a: f64, b: f64) -> bool {
    a < b
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::{VehicleConfig, WindConfig};
    use crate::scenario::{geometry, Scenario};
    use crate::vehicle::VelocityCommand;
    use crate::wind::Wind;

    #[test]
    fn a_nan_measure_fails_every_check() {
        assert!(at_most(1.0, 1.0) && below(0.5, 1.0));
        assert!(!below(1.0, 1.0));
        for (a, b) in [(f64::NAN, 1.0), (1.0, f64::NAN)] {
            assert!(!at_most(a, b) && !below(a, b));
        }
    }

    fn calm() -> Wind {
        Wind::new(
            1,
            &WindConfig {
                mean_speed_m_s: [0.0, 0.0],
                gust_sigma_m_s: 0.0,
                gust_tau_s: 1.0,
            },
        )
    }

    /// Fly straight along −axis from the start to `target` in front of the hub (perfect control).
    fn fly_to(
        s: &Scenario,
        cfg: &SimConfig,
        plane_target: f64,
        lateral_fix: bool,
    ) -> (Multicopter, FlightRecorder, f64) {
        let mut v = Multicopter::new(&s.start, &VehicleConfig::default());
        let mut w = calm();
        let mut rec = FlightRecorder::from_config(s.seed, cfg);
        let dt = 0.005;
        let mut t = 0.0;
        // Face the hub once, then fly with a proportional controller on position.
        v.set_attitude(0.0, 0.0, s.facing_rotor_heading_rad());
        let axis = s.rotor_axis_ned();
        let right = s.viewer_right_ned();
        let goal = [
            s.hub_ned[0] + plane_target * axis[0],
            s.hub_ned[1] + plane_target * axis[1],
            s.hub_ned[2],
        ];
        while t < 60.0 {
            let p = v.position_ned();
            let mut e = [goal[0] - p[0], goal[1] - p[1], goal[2] - p[2]];
            if !lateral_fix {
                // Keep the lateral offset: only fly along the axis and vertically.
                let lat = e[0] * right[0] + e[1] * right[1];
                e[0] -= lat * right[0];
                e[1] -= lat * right[1];
            }
            let cmd = VelocityCommand {
                velocity_ned: [0.5 * e[0], 0.5 * e[1], 0.5 * e[2]],
                yaw_rate: 0.0,
            };
            v.step(dt, &cmd, &mut w);
            t += dt;
            rec.step(t, &v, &geometry(s, &v));
        }
        (v, rec, t)
    }

    #[test]
    fn a_good_approach_succeeds() {
        let cfg = SimConfig::default();
        let s = Scenario::from_seed(2, &cfg);
        let (v, rec, t) = fly_to(&s, &cfg, 5.0, true);
        let g = geometry(&s, &v);
        let o = rec.finish(t, &v, &g, "arrived");
        assert!(o.success, "{o:?}");
        assert_eq!(o.failure, None);
        assert!((o.final_distance_m - 5.0).abs() < 0.01);
        assert!(o.final_yaw_deg.abs() < 0.5);
        assert!(o.final_speed_m_s < 0.01);
        assert!(o.min_rotor_plane_m > 4.9 && o.min_rotor_plane_m <= 5.0 + 1e-9);
        assert!(o.min_distance_m <= o.final_distance_m + 1e-9);
        // Path length at least the straight-line distance from the start.
        let start_to_goal = ((s.start_distance_m - 5.0).powi(2)
            + s.start_lateral_m.powi(2)
            + s.start_height_m.powi(2))
        .sqrt();
        assert!(
            o.path_length_m >= start_to_goal - 0.05 && o.path_length_m < start_to_goal * 1.2,
            "{o:?}"
        );
        assert_eq!(o.end_reason, "arrived");
        assert!(rec.time_at_target_s() > 10.0);
        // Serialises for the result files.
        let json = to_toml(&o);
        assert!(json.contains("final_distance_m"));
    }

    fn to_toml(o: &Outcome) -> String {
        toml::to_string(o).unwrap()
    }

    #[test]
    fn each_rule_can_fail_and_is_explained() {
        let cfg = SimConfig::default();
        let s = Scenario::from_seed(2, &cfg);

        // Stopping at 7 m: distance fails.
        let (v, rec, t) = fly_to(&s, &cfg, 7.0, true);
        let o = rec.finish(t, &v, &geometry(&s, &v), "max_time");
        assert!(!o.success);
        assert!(
            o.failure.as_deref().unwrap().contains("final distance"),
            "{o:?}"
        );

        // Keeping the lateral offset: relative yaw fails (when the offset is large enough).
        let s2 = (0..50)
            .map(|k| Scenario::from_seed(k, &cfg))
            .find(|s| s.start_lateral_m.abs() > 3.0)
            .unwrap();
        let (v, rec, t) = fly_to(&s2, &cfg, 5.0, false);
        let o = rec.finish(t, &v, &geometry(&s2, &v), "max_time");
        assert!(!o.success);
        assert!(
            o.failure.as_deref().unwrap().contains("relative yaw"),
            "{o:?}"
        );

        // Too late.
        let (v, rec, t) = fly_to(&s, &cfg, 5.0, true);
        let o = rec
            .clone()
            .with_max_time(30.0)
            .finish(t, &v, &geometry(&s, &v), "arrived");
        assert!(!o.success);
        assert!(o.failure.as_deref().unwrap().contains("took"), "{o:?}");

        // Too close to the rotor plane on the way (dips to 2 m, then back to 5 m).
        let (mut v, mut rec, mut t) = fly_to(&s, &cfg, 2.0, true);
        let mut w = calm();
        let axis = s.rotor_axis_ned();
        for _ in 0..(40.0 / 0.005) as usize {
            let g = geometry(&s, &v);
            let e = 5.0 - g.rotor_plane_m;
            let cmd = VelocityCommand {
                velocity_ned: [0.5 * e * axis[0], 0.5 * e * axis[1], 0.0],
                yaw_rate: 0.0,
            };
            v.step(0.005, &cmd, &mut w);
            t += 0.005;
            rec.step(t, &v, &geometry(&s, &v));
        }
        let o = rec.finish(t, &v, &geometry(&s, &v), "arrived");
        assert!(!o.success);
        assert!(o.min_rotor_plane_m < 2.1);
        let f = o.failure.unwrap();
        assert!(
            f.contains("rotor plane") && !f.contains("final distance"),
            "{f}"
        );

        // Still moving at the end.
        let mut v = Multicopter::new(&s.start, &VehicleConfig::default());
        let mut rec = FlightRecorder::from_config(s.seed, &cfg);
        let mut w = calm();
        let mut t = 0.0;
        for _ in 0..400 {
            v.step(
                0.005,
                &VelocityCommand {
                    velocity_ned: [0.0, 0.0, 1.0],
                    yaw_rate: 0.0,
                },
                &mut w,
            );
            t += 0.005;
            rec.step(t, &v, &geometry(&s, &v));
        }
        let o = rec.finish(t, &v, &geometry(&s, &v), "control exited");
        assert!(o.failure.unwrap().contains("not hovering"));
        assert!(o.final_speed_m_s > 0.5);
    }

    #[test]
    fn finish_without_steps_uses_the_final_state() {
        let cfg = SimConfig::default();
        let s = Scenario::from_seed(1, &cfg);
        let v = Multicopter::new(&s.start, &VehicleConfig::default());
        let g = geometry(&s, &v);
        let o = FlightRecorder::new(1, &cfg.success).finish(0.0, &v, &g, "aborted");
        assert!(!o.success);
        assert_eq!(o.min_rotor_plane_m, g.rotor_plane_m);
        assert_eq!(o.min_distance_m, g.distance_m);
        assert_eq!(o.path_length_m, 0.0);
        assert_eq!(o.final_speed_m_s, 0.0);
        assert_eq!(o.seed, 1);
    }
}
