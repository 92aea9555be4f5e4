//! The multicopter under ArduCopter's velocity controller, as a small point-mass model.
//!
//! What is modelled, and why it is enough for the vision pipeline:
//!
//! * **Velocity loop.** The controller demands `a = (v_cmd − v) / velocity_tc_s`, limited to
//!   `max_accel_m_s2`, so a velocity step is followed like a first-order lag (plus the short
//!   attitude lag below). Commands are limited to the speed, climb and descent limits first.
//! * **Thrust and attitude.** The horizontal acceleration is produced by tilting the thrust. The
//!   demanded tilt follows from the demanded acceleration (`pitch = atan2(−a_fwd, g − a_z)`,
//!   `roll = atan(a_right·cos pitch / (g − a_z))`, limited to `max_tilt_deg`); roll and pitch
//!   follow it with the lag `attitude_tc_s`, and the acceleration actually produced is computed
//!   back from the *actual* attitude. So accelerating forward pitches the nose (and the camera)
//!   down, sideways acceleration rolls toward it, and the camera sees what the vehicle does.
//! * **Wind.** Rotor drag is linear in the airspeed (blade flapping and induced drag dominate for
//!   small multicopters): the air pushes with `drag_per_s · (w − v)`. The `−c·v` part is the
//!   vehicle's own damping, which the tuned controller compensates by design; the `c·w` part is a
//!   disturbance the controller's integrator learns with the time constant `disturbance_tc_s`.
//!   A steady wind is therefore rejected fully and the vehicle hovers tilted into it
//!   (`tan θ = c·|w|/g`); gusts faster than the integrator leave velocity errors of a few dm/s.
//!   On the first step the vehicle is trimmed for the wind it meets (it was hovering in it before
//!   the simulation started), so there is no start-up transient.
//! * **Altitude.** The collective follows the vertical demand exactly (no vertical wind).
//! * **Yaw.** The yaw rate follows the (limited) commanded rate with the lag `yaw_tc_s`.
//!
//! Body rates `[p, q, r]` are the Euler-angle rates mapped to the body frame. Integration is
//! semi-implicit Euler with exact exponential filters, stable for any step up to ~0.05 s.

use serde::{Deserialize, Serialize};

use crate::math::{wrap_pi, GRAVITY_M_S2};
use crate::params::VehicleConfig;
use crate::wind::Wind;

/// Where and how the vehicle starts: hovering (or moving) at a position with a heading.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct VehicleStart {
    /// Position in the local NED frame, m.
    pub position_ned: [f64; 3],
    /// Velocity in NED, m/s (zero for a hover).
    pub velocity_ned: [f64; 3],
    /// Heading, rad, clockwise from north.
    pub yaw_rad: f64,
}

/// What the velocity controller is asked to do: NED velocity and yaw rate. Zero = hover.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct VelocityCommand {
    /// Velocity, NED, m/s.
    pub velocity_ned: [f64; 3],
    /// Yaw rate, rad/s, positive clockwise seen from above (turning right).
    pub yaw_rate: f64,
}

impl VelocityCommand {
    /// Hold position and heading.
    pub const HOVER: VelocityCommand = VelocityCommand {
        velocity_ned: [0.0; 3],
        yaw_rate: 0.0,
    };
}

/// The simulated multicopter.
#[derive(Debug, Clone)]
pub struct Multicopter {
    cfg: VehicleConfig,
    pos: [f64; 3],
    vel: [f64; 3],
    roll: f64,
    pitch: f64,
    yaw: f64,
    yaw_rate: f64,
    rates: [f64; 3],
    /// The controller's integrator: its estimate of the wind force per unit mass (N, E), m/s².
    disturbance_est: [f64; 2],
    /// Trimmed for the wind yet (done on the first step).
    trimmed: bool,
    wind: [f64; 3],
    accel: [f64; 3],
}

impl Multicopter {
    /// A vehicle at `start`, level, not rotating.
    pub fn new(start: &VehicleStart, cfg: &VehicleConfig) -> Multicopter {
        Multicopter {
            cfg: cfg.clone(),
            pos: start.position_ned,
            vel: start.velocity_ned,
            roll: 0.0,
            pitch: 0.0,
            yaw: wrap_pi(start.yaw_rad),
            yaw_rate: 0.0,
            rates: [0.0; 3],
            disturbance_est: [0.0; 2],
            trimmed: false,
            wind: [0.0; 3],
            accel: [0.0; 3],
        }
    }

    /// Advance by `dt` seconds with a velocity command in NED and a yaw-rate command, under the
    /// wind (which is stepped by `dt` here). Non-finite command values count as zero; `dt <= 0`
    /// or non-finite does nothing.
    pub fn step(&mut self, dt: f64, cmd: &VelocityCommand, wind: &mut Wind) {
        if !(dt > 0.0 && dt.is_finite()) {
            return;
        }
        let c = &self.cfg;
        let g = GRAVITY_M_S2;
        let w = wind.step(dt);
        self.wind = w;
        let drag = c.drag_per_s;
        let disturbance = [drag * w[0], drag * w[1]];

        let vc = self.limit_command(cmd);

        // Velocity controller demand.
        let mut a_des = [0.0; 3];
        for i in 0..3 {
            a_des[i] = (vc[i] - self.vel[i]) / c.velocity_tc_s;
        }
        let ah = a_des[0].hypot(a_des[1]);
        if ah > c.max_accel_m_s2 {
            let k = c.max_accel_m_s2 / ah;
            a_des[0] *= k;
            a_des[1] *= k;
        }
        a_des[2] = a_des[2].clamp(-c.max_accel_m_s2, c.max_accel_m_s2);
        // Thrust must also carry the weight plus the vertical acceleration.
        let lift = g - a_des[2];

        if !self.trimmed {
            // The vehicle was already hovering in this wind before the simulation started.
            self.disturbance_est = disturbance;
            let a_th = [
                self.vel[0] * drag - disturbance[0],
                self.vel[1] * drag - disturbance[1],
            ];
            let (r, p) = tilt_for(a_th, lift, self.yaw);
            self.roll = r;
            self.pitch = p;
            self.trimmed = true;
        }

        // The integrator learns the wind force with a lag: gusts are only partly rejected.
        let k_d = 1.0 - (-dt / c.disturbance_tc_s).exp();
        for (est, d) in self.disturbance_est.iter_mut().zip(disturbance) {
            *est += (d - *est) * k_d;
        }

        // Horizontal thrust acceleration demand: the controller's acceleration, plus the
        // compensation of the vehicle's own drag, minus the learnt wind force; tilt-limited.
        let mut a_th = [
            a_des[0] + drag * self.vel[0] - self.disturbance_est[0],
            a_des[1] + drag * self.vel[1] - self.disturbance_est[1],
        ];
        let a_max = lift * c.max_tilt_deg.to_radians().tan();
        let n = a_th[0].hypot(a_th[1]);
        if n > a_max {
            a_th = [a_th[0] * a_max / n, a_th[1] * a_max / n];
        }
        let (roll_t, pitch_t) = tilt_for(a_th, lift, self.yaw);

        // Yaw.
        let max_rate = c.max_yaw_rate_deg_s.to_radians();
        let r_cmd = if cmd.yaw_rate.is_finite() {
            cmd.yaw_rate.clamp(-max_rate, max_rate)
        } else {
            0.0
        };
        self.yaw_rate += (r_cmd - self.yaw_rate) * (1.0 - (-dt / c.yaw_tc_s).exp());
        self.yaw = wrap_pi(self.yaw + self.yaw_rate * dt);

        // Attitude follows the demanded tilt.
        let k_a = 1.0 - (-dt / c.attitude_tc_s).exp();
        let (roll0, pitch0) = (self.roll, self.pitch);
        self.roll += (roll_t - self.roll) * k_a;
        self.pitch += (pitch_t - self.pitch) * k_a;

        // Acceleration the actual attitude produces (thrust scaled to hold the vertical demand).
        let a_fwd = -lift * self.pitch.tan();
        let a_right = lift * self.roll.tan() / self.pitch.cos();
        let (sy, cy) = self.yaw.sin_cos();
        let thrust_h = [cy * a_fwd - sy * a_right, sy * a_fwd + cy * a_right];
        self.accel = [
            thrust_h[0] + drag * (w[0] - self.vel[0]),
            thrust_h[1] + drag * (w[1] - self.vel[1]),
            a_des[2],
        ];
        for i in 0..3 {
            self.vel[i] += self.accel[i] * dt;
            self.pos[i] += self.vel[i] * dt;
        }

        // Euler rates to body rates.
        let roll_dot = (self.roll - roll0) / dt;
        let pitch_dot = (self.pitch - pitch0) / dt;
        let yaw_dot = self.yaw_rate;
        let (sf, cf) = self.roll.sin_cos();
        let (st, ct) = self.pitch.sin_cos();
        self.rates = [
            roll_dot - yaw_dot * st,
            pitch_dot * cf + yaw_dot * sf * ct,
            -pitch_dot * sf + yaw_dot * cf * ct,
        ];
    }

    /// The commanded velocity after the speed limits (horizontal norm scaled, vertical clamped).
    fn limit_command(&self, cmd: &VelocityCommand) -> [f64; 3] {
        let c = &self.cfg;
        let mut v = cmd.velocity_ned;
        if v.iter().any(|x| !x.is_finite()) {
            return [0.0; 3];
        }
        let h = v[0].hypot(v[1]);
        if h > c.max_speed_m_s {
            v[0] *= c.max_speed_m_s / h;
            v[1] *= c.max_speed_m_s / h;
        }
        // NED: negative z velocity is a climb.
        v[2] = v[2].clamp(-c.max_climb_m_s, c.max_descent_m_s);
        v
    }

    /// Position in the local NED frame, m.
    pub fn position_ned(&self) -> [f64; 3] {
        self.pos
    }

    /// Velocity in NED, m/s.
    pub fn velocity_ned(&self) -> [f64; 3] {
        self.vel
    }

    /// Acceleration of the last step in NED, m/s² (kinematic, without gravity).
    pub fn acceleration_ned(&self) -> [f64; 3] {
        self.accel
    }

    /// Roll (right side down positive), pitch (nose up positive), yaw (clockwise from north, in
    /// (−π, π]), rad; ZYX Euler angles as in MAVLink ATTITUDE.
    pub fn attitude(&self) -> [f64; 3] {
        [self.roll, self.pitch, self.yaw]
    }

    /// Body rates `[p, q, r]` (about body x forward, y right, z down), rad/s.
    pub fn body_rates(&self) -> [f64; 3] {
        self.rates
    }

    /// The wind (air velocity, NED, m/s) of the last step.
    pub fn wind_ned(&self) -> [f64; 3] {
        self.wind
    }

    /// Set the attitude directly (rates reset to zero), for tests and scripted poses. The next
    /// [`Multicopter::step`] moves roll and pitch back toward what the controller demands.
    pub fn set_attitude(&mut self, roll: f64, pitch: f64, yaw: f64) {
        self.roll = roll;
        self.pitch = pitch;
        self.yaw = wrap_pi(yaw);
        self.yaw_rate = 0.0;
        self.rates = [0.0; 3];
        // Keep the set tilt: do not re-trim on the next step.
        self.trimmed = true;
    }

    /// Move the vehicle to a position (velocity unchanged), for tests and scripted poses.
    pub fn set_position_ned(&mut self, position_ned: [f64; 3]) {
        self.pos = position_ned;
    }

    /// Set the velocity, NED, m/s: with [`Multicopter::set_position_ned`] and
    /// [`Multicopter::set_attitude`], this mirrors a vehicle whose physics runs elsewhere (the
    /// rotorcraft flown by ArduPilot SITL) for the geometry, camera and outcome.
    pub fn set_velocity_ned(&mut self, velocity_ned: [f64; 3]) {
        self.vel = velocity_ned;
    }
}

/// Roll and pitch that point the thrust so that it produces the horizontal acceleration `a_h`
/// (NED) while carrying `lift` = g − a_z vertically, for heading `yaw`.
fn tilt_for(a_h: [f64; 2], lift: f64, yaw: f64) -> (f64, f64) {
    let (sy, cy) = yaw.sin_cos();
    let a_fwd = cy * a_h[0] + sy * a_h[1];
    let a_right = -sy * a_h[0] + cy * a_h[1];
    let pitch = (-a_fwd).atan2(lift);
    let roll = (a_right * pitch.cos()).atan2(lift);
    (roll, pitch)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::WindConfig;

    fn calm() -> Wind {
        Wind::new(
            1,
            &WindConfig {
                mean_speed_m_s: [0.0, 0.0],
                gust_sigma_m_s: 0.0,
                gust_tau_s: 2.0,
            },
        )
    }

    fn start(yaw: f64) -> VehicleStart {
        VehicleStart {
            position_ned: [0.0, 0.0, -70.0],
            velocity_ned: [0.0; 3],
            yaw_rad: yaw,
        }
    }

    const DT: f64 = 0.005;

    fn run(v: &mut Multicopter, w: &mut Wind, cmd: VelocityCommand, seconds: f64) {
        for _ in 0..(seconds / DT).round() as usize {
            v.step(DT, &cmd, w);
        }
    }

    #[test]
    fn hover_in_calm_air_stays_put() {
        let mut v = Multicopter::new(&start(0.3), &VehicleConfig::default());
        let mut w = calm();
        run(&mut v, &mut w, VelocityCommand::HOVER, 10.0);
        assert_eq!(v.position_ned(), [0.0, 0.0, -70.0]);
        assert_eq!(v.attitude(), [0.0, 0.0, 0.3]);
    }

    #[test]
    fn velocity_step_follows_the_configured_lag() {
        let cfg = VehicleConfig::default();
        let mut v = Multicopter::new(&start(0.0), &cfg);
        let mut w = calm();
        // 1 m/s north: the initial demand 1/0.6 = 1.7 m/s² is below the acceleration limit.
        let cmd = VelocityCommand {
            velocity_ned: [1.0, 0.0, 0.0],
            yaw_rate: 0.0,
        };
        run(&mut v, &mut w, cmd, cfg.velocity_tc_s);
        // First-order lag would give 63 %; the attitude lag (0.15 s) delays it a little.
        let at_tau = v.velocity_ned()[0];
        assert!((0.45..0.63).contains(&at_tau), "{at_tau}");
        run(&mut v, &mut w, cmd, 4.0 * cfg.velocity_tc_s);
        let v5 = v.velocity_ned()[0];
        assert!((0.97..1.02).contains(&v5), "{v5}");
        run(&mut v, &mut w, cmd, 5.0);
        assert!((v.velocity_ned()[0] - 1.0).abs() < 1e-3);
        assert!(v.velocity_ned()[1].abs() < 1e-9);
        // At constant speed in calm air the thrust only balances the rotor drag: nose down by
        // atan(c·v/g).
        let expected = -(cfg.drag_per_s * 1.0 / GRAVITY_M_S2).atan();
        assert!(
            (v.attitude()[1] - expected).abs() < 1e-4,
            "{:?}",
            v.attitude()
        );
    }

    #[test]
    fn acceleration_tilts_the_nose_down_and_the_wing_toward_it() {
        let cfg = VehicleConfig::default();
        // Heading east; command east (forward) then south (to the right).
        let mut v = Multicopter::new(&start(std::f64::consts::FRAC_PI_2), &cfg);
        let mut w = calm();
        run(
            &mut v,
            &mut w,
            VelocityCommand {
                velocity_ned: [0.0, 2.0, 0.0],
                yaw_rate: 0.0,
            },
            0.5,
        );
        let [roll, pitch, _] = v.attitude();
        assert!(
            pitch < -5f64.to_radians(),
            "forward acceleration pitches the nose down: {pitch}"
        );
        assert!(roll.abs() < 1e-9);
        assert!(v.body_rates()[1].abs() < 1.0);

        let mut v = Multicopter::new(&start(std::f64::consts::FRAC_PI_2), &cfg);
        run(
            &mut v,
            &mut w,
            VelocityCommand {
                velocity_ned: [-2.0, 0.0, 0.0],
                yaw_rate: 0.0,
            },
            0.5,
        );
        let [roll, pitch, _] = v.attitude();
        assert!(
            roll > 5f64.to_radians(),
            "accelerating right rolls right side down: {roll}"
        );
        assert!(pitch.abs() < 1e-9);
        // Decelerating: nose up.
        run(
            &mut v,
            &mut w,
            VelocityCommand {
                velocity_ned: [-2.0, 0.0, 0.0],
                yaw_rate: 0.0,
            },
            5.0,
        );
        run(&mut v, &mut w, VelocityCommand::HOVER, 0.4);
        assert!(
            v.attitude()[0] < -2f64.to_radians(),
            "braking a rightward motion rolls left"
        );
    }

    #[test]
    fn acceleration_and_tilt_are_limited() {
        let cfg = VehicleConfig::default();
        let mut v = Multicopter::new(&start(0.0), &cfg);
        let mut w = calm();
        let cmd = VelocityCommand {
            velocity_ned: [20.0, 0.0, 0.0],
            yaw_rate: 0.0,
        };
        let mut max_a: f64 = 0.0;
        for _ in 0..2000 {
            v.step(DT, &cmd, &mut w);
            max_a = max_a.max(v.acceleration_ned()[0]);
            assert!(v.attitude()[1].abs() <= cfg.max_tilt_deg.to_radians() + 1e-9);
        }
        assert!(max_a <= cfg.max_accel_m_s2 * 1.01, "{max_a}");
        // Speed limit.
        assert!((v.velocity_ned()[0] - cfg.max_speed_m_s).abs() < 1e-3);
        // Climb limit.
        run(
            &mut v,
            &mut w,
            VelocityCommand {
                velocity_ned: [0.0, 0.0, -9.0],
                yaw_rate: 0.0,
            },
            6.0,
        );
        assert!((v.velocity_ned()[2] + cfg.max_climb_m_s).abs() < 1e-3);
    }

    #[test]
    fn yaw_rate_is_limited_and_wraps() {
        let cfg = VehicleConfig::default();
        let mut v = Multicopter::new(&start(3.0), &cfg);
        let mut w = calm();
        // Ask for 5 rad/s: limited to 90 °/s.
        run(
            &mut v,
            &mut w,
            VelocityCommand {
                velocity_ned: [0.0; 3],
                yaw_rate: 5.0,
            },
            2.0,
        );
        let r = v.body_rates()[2];
        assert!(
            (r - cfg.max_yaw_rate_deg_s.to_radians()).abs() < 1e-3,
            "{r}"
        );
        assert!(r <= cfg.max_yaw_rate_deg_s.to_radians());
        let yaw = v.attitude()[2];
        assert!(yaw > -std::f64::consts::PI && yaw <= std::f64::consts::PI);
        // 3 rad + ~(2 s − 0.25 s lag)·π/2 ≈ 5.75 rad → wrapped to ≈ −0.53 rad.
        let expected = wrap_pi(3.0 + (2.0 - cfg.yaw_tc_s) * cfg.max_yaw_rate_deg_s.to_radians());
        assert!((yaw - expected).abs() < 0.01, "{yaw} vs {expected}");
        // The yaw rate response has the configured lag.
        let mut v = Multicopter::new(&start(0.0), &cfg);
        run(
            &mut v,
            &mut w,
            VelocityCommand {
                velocity_ned: [0.0; 3],
                yaw_rate: 0.5,
            },
            cfg.yaw_tc_s,
        );
        let frac = v.body_rates()[2] / 0.5;
        assert!((frac - 0.632).abs() < 0.01, "{frac}");
    }

    #[test]
    fn steady_wind_is_rejected_with_a_tilt_into_it() {
        let cfg = VehicleConfig::default();
        let mut v = Multicopter::new(&start(0.0), &cfg);
        // 5 m/s air moving east (wind from the west), no gusts.
        let mut w = Wind::new(
            1,
            &WindConfig {
                mean_speed_m_s: [5.0, 5.0],
                gust_sigma_m_s: 0.0,
                gust_tau_s: 2.0,
            },
        );
        let m = w.mean_ned();
        run(&mut v, &mut w, VelocityCommand::HOVER, 20.0);
        let p = v.position_ned();
        assert!(
            p[0].abs() < 1e-6 && p[1].abs() < 1e-6,
            "trimmed at the start, so no drift: {p:?}"
        );
        // Tilted into the wind: the thrust's horizontal part points upwind.
        let [roll, pitch, _] = v.attitude();
        let a_fwd = -GRAVITY_M_S2 * pitch.tan();
        let a_right = GRAVITY_M_S2 * roll.tan() / pitch.cos();
        // Heading north: forward = north, right = east.
        let dot = a_fwd * m[0] + a_right * m[1];
        assert!(dot < 0.0);
        let tilt = (a_fwd.hypot(a_right) / GRAVITY_M_S2).atan();
        let expected = (cfg.drag_per_s * 5.0 / GRAVITY_M_S2).atan();
        assert!((tilt - expected).abs() < 1e-3, "{tilt} vs {expected}");
    }

    #[test]
    fn gusts_cause_velocity_errors_of_a_few_decimetres_per_second() {
        let cfg = VehicleConfig::default();
        let mut v = Multicopter::new(&start(0.0), &cfg);
        let mut w = Wind::new(
            5,
            &WindConfig {
                mean_speed_m_s: [4.0, 4.0],
                gust_sigma_m_s: 1.0,
                gust_tau_s: 2.0,
            },
        );
        let mut sum2 = 0.0;
        let mut max: f64 = 0.0;
        let n = (120.0 / DT) as usize;
        for _ in 0..n {
            v.step(DT, &VelocityCommand::HOVER, &mut w);
            let s = v.velocity_ned()[0].hypot(v.velocity_ned()[1]);
            sum2 += s * s;
            max = max.max(s);
        }
        let rms = (sum2 / n as f64).sqrt();
        assert!((0.03..0.3).contains(&rms), "rms {rms}");
        assert!((0.1..1.0).contains(&max), "max {max}");
        // Position hold is not part of a velocity controller; the drift stays bounded anyway.
        let p = v.position_ned();
        assert!(p[0].hypot(p[1]) < 10.0, "{p:?}");
    }

    #[test]
    fn same_inputs_same_trajectory() {
        let cfg = VehicleConfig::default();
        let fly = || {
            let mut v = Multicopter::new(&start(0.5), &cfg);
            let mut w = Wind::new(9, &WindConfig::default());
            let cmd = VelocityCommand {
                velocity_ned: [1.0, -0.5, 0.2],
                yaw_rate: 0.1,
            };
            run(&mut v, &mut w, cmd, 5.0);
            (v.position_ned(), v.attitude(), v.body_rates())
        };
        assert_eq!(fly(), fly());
    }
}
