//! A quadcopter as a rigid body driven by its four motors: the physics that ArduPilot's own
//! controllers fly when ArduCopter SITL is coupled to the simulator (`--model JSON`).
//!
//! Unlike [`crate::Multicopter`] (a model of the vehicle *under* ArduCopter's velocity
//! controller), nothing here knows about setpoints: the motor PWM that the firmware writes is
//! the only input, and attitude, rates and position follow from thrust, torque, gravity and the
//! wind. What is modelled:
//!
//! * **Motors.** PWM 1000..2000 µs maps to a throttle `u` in 0..1; ArduCopter outputs between
//!   `MOT_SPIN_MIN` and `MOT_SPIN_MAX` and linearises thrust with `MOT_THST_EXPO`, so the thrust
//!   of one motor is `T_max · ((1 − e)·x + e·x²)` with `x` the throttle rescaled to that band —
//!   exactly the curve the firmware inverts, so its hover throttle `MOT_THST_HOVER` is
//!   `m·g / (4·T_max)`. Each motor follows its demand with a first-order lag.
//! * **Frame.** "+" (ArduCopter FRAME_TYPE 0: motors 1 right, 2 left, 3 front, 4 back) or "x"
//!   (FRAME_TYPE 1: 1 front-right, 2 back-left, 3 front-left, 4 back-right); motors 1 and 2 turn
//!   counter-clockwise, 3 and 4 clockwise, and the yaw torque is the rotors' reaction torque,
//!   proportional to thrust.
//! * **Air.** Linear rotor drag in the airspeed, `drag_per_s · (w − v)` per unit mass, as in
//!   [`crate::Multicopter`], and a small rotational damping.
//! * **Ground.** Flat ground at z = 0: the vehicle rests on it level until the thrust lifts it.
//!
//! Integration: semi-implicit Euler on velocity/position and body rates, the attitude kept as a
//! unit quaternion; stable at ArduPilot's physics rates (400 Hz and above).

use crate::math::{wrap_pi, GRAVITY_M_S2};
use hubtrack_types::params;
use serde::{Deserialize, Serialize};

/// Motor layout, as ArduCopter's FRAME_TYPE.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FrameLayout {
    /// "+": FRAME_TYPE 0.
    Plus,
    /// "x": FRAME_TYPE 1.
    X,
}

params! {
    /// `[sim.rotorcraft]`: the quadcopter flown by ArduCopter SITL (`hubtrack fly --autopilot
    /// ardupilot`). The defaults are a 1.5 kg quad that hovers at the stock MOT_THST_HOVER 0.39,
    /// with stock ArduCopter gains.
    pub struct RotorcraftConfig {
        /// Motor layout: "plus" or "x"; must match FRAME_TYPE in the ArduPilot parameter file.
        pub frame: FrameLayout = FrameLayout::Plus;
        /// Take-off mass, kg, (0, 50].
        pub mass_kg: f64 = 1.5, open_closed(0.0, 50.0);
        /// Motor distance from the centre, m, (0, 2].
        pub arm_m: f64 = 0.25, open_closed(0.0, 2.0);
        /// Moments of inertia about body x, y, z, kg·m², each (0, 10].
        pub inertia_kg_m2: [f64; 3] = [0.015, 0.015, 0.03];
        /// Throttle (0..1) that hovers the vehicle, in the firmware's linearised thrust: sets the
        /// motors' full thrust (ArduCopter MOT_THST_HOVER: 0.39 in the stock SITL parameters).
        pub hover_throttle: f64 = 0.39, open_closed(0.05, 0.9);
        /// Thrust curve expo, [0, 1] (ArduCopter MOT_THST_EXPO; 0.65 in the stock SITL parameters).
        pub thrust_expo: f64 = 0.65, closed(0.0, 1.0);
        /// Throttle below which the motors give no thrust, [0, 0.5] (ArduCopter MOT_SPIN_MIN).
        pub spin_min: f64 = 0.15, closed(0.0, 0.5);
        /// Throttle of full thrust, [0.5, 1] (ArduCopter MOT_SPIN_MAX).
        pub spin_max: f64 = 0.95, closed(0.5, 1.0);
        /// Motor response time constant, s, (0, 1].
        pub motor_tc_s: f64 = 0.02, open_closed(0.0, 1.0);
        /// Rotor reaction torque per newton of thrust, m, (0, 0.5]: the yaw authority.
        pub yaw_torque_per_thrust_m: f64 = 0.05, open_closed(0.0, 0.5);
        /// Rotational damping, N·m per rad/s, [0, 1].
        pub rate_damping: f64 = 0.002, closed(0.0, 1.0);
    }
}

impl RotorcraftConfig {
    /// [`RotorcraftConfig::check_ranges`], then the inertias.
    pub fn validate(&self, section: &str) -> Result<(), hubtrack_types::params::ParamError> {
        self.check_ranges(section)?;
        let c = hubtrack_types::params::Check::new(section);
        for i in self.inertia_kg_m2 {
            c.open_closed("inertia_kg_m2", i, 0.0, 10.0)?;
        }
        Ok(())
    }
}

/// ArduCopter's motor positions (degrees clockwise from the nose) and yaw factors (+1 turns the
/// frame clockwise when the motor speeds up: a counter-clockwise propeller), motors 1..4.
fn layout(frame: FrameLayout) -> [(f64, f64); 4] {
    match frame {
        FrameLayout::Plus => [(90.0, 1.0), (-90.0, 1.0), (0.0, -1.0), (180.0, -1.0)],
        FrameLayout::X => [(45.0, 1.0), (-135.0, 1.0), (-45.0, -1.0), (135.0, -1.0)],
    }
}

/// Unit quaternion `[w, x, y, z]`, body to NED.
type Quat = [f64; 4];

fn quat_mul(a: Quat, b: Quat) -> Quat {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

fn quat_from_euler(roll: f64, pitch: f64, yaw: f64) -> Quat {
    let (sr, cr) = (roll / 2.0).sin_cos();
    let (sp, cp) = (pitch / 2.0).sin_cos();
    let (sy, cy) = (yaw / 2.0).sin_cos();
    [
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ]
}

/// Rotation matrix (row-major, `v_ned = R · v_body`) of a unit quaternion.
fn quat_matrix(q: Quat) -> [[f64; 3]; 3] {
    let [w, x, y, z] = q;
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

/// The quadcopter (see the [module](self) documentation).
#[derive(Debug, Clone)]
pub struct Rotorcraft {
    cfg: RotorcraftConfig,
    /// Full thrust of one motor, N.
    max_thrust_n: f64,
    /// Per motor: body x, body y of the motor (m) and its yaw factor.
    motors: [(f64, f64, f64); 4],
    thrust_n: [f64; 4],
    pos: [f64; 3],
    vel: [f64; 3],
    q: Quat,
    rates: [f64; 3],
    /// Specific force in body axes (what an accelerometer reads), m/s².
    specific_force: [f64; 3],
    on_ground: bool,
}

impl Rotorcraft {
    /// At rest on the ground at `position_ned` (its z is the ground; normally 0), level, facing
    /// `yaw_rad`.
    pub fn on_ground(position_ned: [f64; 3], yaw_rad: f64, cfg: &RotorcraftConfig) -> Self {
        let max_thrust_n = cfg.mass_kg * GRAVITY_M_S2 / (4.0 * cfg.hover_throttle);
        let motors = layout(cfg.frame).map(|(deg, yaw_factor)| {
            let a = f64::to_radians(deg);
            (cfg.arm_m * a.cos(), cfg.arm_m * a.sin(), yaw_factor)
        });
        Rotorcraft {
            cfg: cfg.clone(),
            max_thrust_n,
            motors,
            thrust_n: [0.0; 4],
            pos: position_ned,
            vel: [0.0; 3],
            q: quat_from_euler(0.0, 0.0, yaw_rad),
            rates: [0.0; 3],
            specific_force: [0.0, 0.0, -GRAVITY_M_S2],
            on_ground: true,
        }
    }

    /// Advance by `dt` s with the motor PWM of channels 1..4 (`pwm_us[0..4]`; missing channels
    /// count as stopped) under the air velocity `wind_ned` (m/s). `dt <= 0` or non-finite does
    /// nothing.
    pub fn step(&mut self, dt: f64, pwm_us: &[u16], wind_ned: [f64; 3], drag_per_s: f64) {
        if !(dt > 0.0 && dt.is_finite()) {
            return;
        }
        let c = &self.cfg;
        let k = 1.0 - (-dt / c.motor_tc_s).exp();
        for (i, t) in self.thrust_n.iter_mut().enumerate() {
            let demand = pwm_us.get(i).map_or(0.0, |&p| {
                Rotorcraft::thrust_for_cfg(c, self.max_thrust_n, p)
            });
            *t += (demand - *t) * k;
        }
        let total: f64 = self.thrust_n.iter().sum();
        let mut torque = [0.0; 3];
        for (&(x, y, yaw_factor), &t) in self.motors.iter().zip(&self.thrust_n) {
            // Thrust along body −z at (x, y): r × F.
            torque[0] -= y * t;
            torque[1] += x * t;
            torque[2] += yaw_factor * c.yaw_torque_per_thrust_m * t;
        }
        let r = quat_matrix(self.q);
        let thrust_ned = [-r[0][2] * total, -r[1][2] * total, -r[2][2] * total];
        let m = c.mass_kg;
        let mut accel = [0.0; 3];
        for i in 0..3 {
            accel[i] = thrust_ned[i] / m + drag_per_s * (wind_ned[i] - self.vel[i]);
        }
        accel[2] += GRAVITY_M_S2;

        // Rigid body rotation: I·ω̇ = τ − ω × Iω − damping·ω.
        let inertia = c.inertia_kg_m2;
        let w = self.rates;
        let iw = [inertia[0] * w[0], inertia[1] * w[1], inertia[2] * w[2]];
        let gyro = [
            w[1] * iw[2] - w[2] * iw[1],
            w[2] * iw[0] - w[0] * iw[2],
            w[0] * iw[1] - w[1] * iw[0],
        ];
        for i in 0..3 {
            let wdot = (torque[i] - gyro[i] - c.rate_damping * w[i]) / inertia[i];
            self.rates[i] += wdot * dt;
        }

        // Resting on the ground: only a net upward force lifts it.
        let grounded = self.pos[2] >= 0.0 && accel[2] >= 0.0;
        if grounded {
            self.on_ground = true;
            self.vel = [0.0; 3];
            self.rates = [0.0; 3];
            self.pos[2] = 0.0;
            let [_, _, yaw] = self.euler();
            self.q = quat_from_euler(0.0, 0.0, yaw);
            accel = [0.0; 3];
        } else {
            self.on_ground = false;
            for ((v, p), a) in self.vel.iter_mut().zip(&mut self.pos).zip(accel) {
                *v += a * dt;
                *p += *v * dt;
            }
            if self.pos[2] > 0.0 {
                // Touched down.
                self.pos[2] = 0.0;
                self.vel = [0.0; 3];
            }
            let [p, q, rr] = self.rates;
            let half = 0.5 * dt;
            let dq = quat_mul(self.q, [0.0, p * half, q * half, rr * half]);
            for (qi, d) in self.q.iter_mut().zip(dq) {
                *qi += d;
            }
            let n = self.q.iter().map(|v| v * v).sum::<f64>().sqrt();
            self.q = self.q.map(|v| v / n);
        }
        // Accelerometer: (a − g) in body axes.
        let r = quat_matrix(self.q);
        let f = [accel[0], accel[1], accel[2] - GRAVITY_M_S2];
        self.specific_force = [
            r[0][0] * f[0] + r[1][0] * f[1] + r[2][0] * f[2],
            r[0][1] * f[0] + r[1][1] * f[1] + r[2][1] * f[2],
            r[0][2] * f[0] + r[1][2] * f[1] + r[2][2] * f[2],
        ];
    }

    /// Thrust demand (N) of one motor for a PWM pulse, µs.
    fn thrust_for_cfg(c: &RotorcraftConfig, max_thrust_n: f64, pwm_us: u16) -> f64 {
        let u = ((f64::from(pwm_us) - 1000.0) / 1000.0).clamp(0.0, 1.0);
        let x = ((u - c.spin_min) / (c.spin_max - c.spin_min)).clamp(0.0, 1.0);
        let e = c.thrust_expo;
        max_thrust_n * ((1.0 - e) * x + e * x * x)
    }

    /// Position, NED, m.
    pub fn position_ned(&self) -> [f64; 3] {
        self.pos
    }

    /// Velocity, NED, m/s.
    pub fn velocity_ned(&self) -> [f64; 3] {
        self.vel
    }

    /// Attitude as a unit quaternion `[w, x, y, z]`, body to NED (ArduPilot's q1..q4).
    pub fn quaternion(&self) -> [f64; 4] {
        self.q
    }

    /// Roll, pitch, yaw (ZYX Euler, MAVLink ATTITUDE conventions), rad.
    pub fn euler(&self) -> [f64; 3] {
        let [w, x, y, z] = self.q;
        let roll = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
        let pitch = (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin();
        let yaw = wrap_pi((2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z)));
        [roll, pitch, yaw]
    }

    /// Body rates `[p, q, r]`, rad/s (what a gyro reads).
    pub fn body_rates(&self) -> [f64; 3] {
        self.rates
    }

    /// Specific force in body axes, m/s² (what an accelerometer reads; `[0, 0, −g]` at rest).
    pub fn specific_force(&self) -> [f64; 3] {
        self.specific_force
    }

    /// Resting on the ground.
    pub fn is_on_ground(&self) -> bool {
        self.on_ground
    }

    /// Thrust of each motor now, N.
    pub fn motor_thrust_n(&self) -> [f64; 4] {
        self.thrust_n
    }

    /// Full thrust of one motor, N.
    pub fn max_motor_thrust_n(&self) -> f64 {
        self.max_thrust_n
    }

    #[cfg(test)]
    fn pwm_for_thrust(&self, thrust_n: f64) -> u16 {
        let c = &self.cfg;
        let e = c.thrust_expo;
        let f = (thrust_n / self.max_thrust_n).clamp(0.0, 1.0);
        let x = if e > 0.0 {
            ((e - 1.0) + ((1.0 - e).powi(2) + 4.0 * e * f).sqrt()) / (2.0 * e)
        } else {
            f
        };
        let u = c.spin_min + x * (c.spin_max - c.spin_min);
        (1000.0 + 1000.0 * u).round() as u16
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(frame: FrameLayout) -> Rotorcraft {
        Rotorcraft::on_ground(
            [0.0; 3],
            0.3,
            &RotorcraftConfig {
                frame,
                ..Default::default()
            },
        )
    }

    /// Idle motors keep it on the ground, level, with the accelerometer reading −g on z.
    #[test]
    fn rests_on_the_ground() {
        let mut v = quad(FrameLayout::Plus);
        for _ in 0..400 {
            v.step(0.0025, &[1000; 4], [0.0; 3], 0.3);
        }
        assert!(v.is_on_ground());
        assert_eq!(v.position_ned(), [0.0; 3]);
        let f = v.specific_force();
        assert!((f[2] + GRAVITY_M_S2).abs() < 1e-9 && f[0].abs() < 1e-9);
        assert!((v.euler()[2] - 0.3).abs() < 1e-12);
    }

    /// The hover throttle holds it up; more throttle climbs.
    #[test]
    fn hover_throttle_hovers_and_more_climbs() {
        let mut v = quad(FrameLayout::X);
        let hover = v.pwm_for_thrust(v.max_motor_thrust_n() * 0.39);
        let climb = hover + 60;
        for _ in 0..800 {
            v.step(0.0025, &[climb; 4], [0.0; 3], 0.3);
        }
        assert!(v.position_ned()[2] < -1.0, "{:?}", v.position_ned());
        let z = v.position_ned()[2];
        let h = v.pwm_for_thrust(v.max_motor_thrust_n() * 0.39);
        // Stop the climb (damped by drag), then hover: the height barely changes.
        for _ in 0..4000 {
            v.step(0.0025, &[h; 4], [0.0; 3], 0.3);
        }
        let vz = v.velocity_ned()[2];
        assert!(vz.abs() < 0.2, "vz {vz}");
        assert!(v.position_ned()[2] < z);
        let [roll, pitch, _] = v.euler();
        assert!(roll.abs() < 1e-9 && pitch.abs() < 1e-9);
    }

    /// Speeding up the right motor of "+" rolls left; the front motor pitches up; the
    /// counter-clockwise pair yaws right — ArduCopter's motor order and factors.
    #[test]
    fn motor_order_matches_arducopter() {
        let base = {
            let v = quad(FrameLayout::Plus);
            v.pwm_for_thrust(v.max_motor_thrust_n() * 0.5)
        };
        let run = |pwm: [u16; 4]| {
            let mut v = quad(FrameLayout::Plus);
            for _ in 0..40 {
                v.step(0.0025, &pwm, [0.0; 3], 0.3);
            }
            v.body_rates()
        };
        assert!(
            run([base + 50, base, base, base])[0] < 0.0,
            "right motor rolls left"
        );
        assert!(
            run([base, base + 50, base, base])[0] > 0.0,
            "left motor rolls right"
        );
        assert!(
            run([base, base, base + 50, base])[1] > 0.0,
            "front motor pitches up"
        );
        assert!(
            run([base + 50, base + 50, base, base])[2] > 0.0,
            "CCW pair yaws right"
        );
    }

    /// Wind pushes a hovering vehicle downwind.
    #[test]
    fn wind_pushes() {
        let mut v = quad(FrameLayout::Plus);
        let h = v.pwm_for_thrust(v.max_motor_thrust_n() * 0.39);
        for _ in 0..200 {
            v.step(0.0025, &[h + 80; 4], [0.0; 3], 0.3);
        }
        for _ in 0..400 {
            v.step(0.0025, &[h; 4], [3.0, 0.0, 0.0], 0.3);
        }
        assert!(v.velocity_ned()[0] > 0.5);
    }
}
