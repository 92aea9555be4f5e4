//! Configuration of the simulator (`[sim]` in the config file).
//!
//! Plain serde data: every struct is `#[serde(deny_unknown_fields, default)]`, so keys left out
//! take the defaults below and a misspelt key is an error. [`SimConfig::validate`] checks every
//! number against its allowed range and names the offending key by its full dotted path
//! (`sim.vehicle.max_tilt_deg`).
//!
//! Ranges drawn per scenario are two-element arrays `[lo, hi]` (`lo <= hi`; equal values fix the
//! quantity).

use serde::{Deserialize, Serialize};

use hubtrack_types::params::Check;
pub use hubtrack_types::params::ParamError;

/// Longest simulated time, frame interval or time constant accepted anywhere, s.
const MAX_TIME_S: f64 = 86_400.0;
/// Largest distance accepted in a scenario range, m.
const MAX_DISTANCE_M: f64 = 1000.0;

/// `[sim]`: the flight simulator (scenario, vehicle, autopilot, wind, camera, success rules).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SimConfig {
    /// Scenario seed, any u64: the same seed gives the same turbine, start, wind and images.
    pub seed: u64,
    /// Camera frame rate, Hz, (0, 240].
    pub fps: f64,
    /// Physics integration rate, Hz, [fps, 10000]; the autopilot's messages are timed on it.
    pub physics_hz: f64,
    /// A flight ends after this much simulated time, s, (0, 86400].
    pub max_time_s: f64,
    /// "realtime": simulated time follows the wall clock (the demo); "lockstep": each camera frame
    /// waits for control's setpoint for it, so time advances as fast as the stages answer and a
    /// seed gives the same flight every time (`hubtrack fly`).
    pub pace: SimPace,
    /// Lockstep: longest wait for the pipeline's answer to one frame before going on without it, ms, [10, 60000].
    pub lockstep_timeout_ms: u64,
    /// The flight ends once control has reported `done` this long, s, [0, 60] (the final hold).
    pub end_after_done_s: f64,
    /// MAVLink link to control, as `control.link` ("udpout:HOST:PORT", "udpin:HOST:PORT" or
    /// "serial:DEVICE:BAUD"); default "udpout:127.0.0.1:14550", where control listens by default.
    pub link: String,
    /// The camera on the vehicle.
    pub camera: CameraConfig,
    /// The multicopter model.
    pub vehicle: VehicleConfig,
    /// The simulated ArduCopter autopilot, as seen over MAVLink.
    pub autopilot: AutopilotConfig,
    /// Mean wind and gusts.
    pub wind: WindConfig,
    /// How the seeded approach scenarios are drawn.
    pub scenario: ScenarioConfig,
    /// When a flight counts as a success.
    pub success: SuccessConfig,
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            seed: 1,
            fps: 15.0,
            physics_hz: 200.0,
            max_time_s: 120.0,
            pace: SimPace::Realtime,
            lockstep_timeout_ms: 2000,
            end_after_done_s: 3.0,
            link: "udpout:127.0.0.1:14550".into(),
            camera: CameraConfig::default(),
            vehicle: VehicleConfig::default(),
            autopilot: AutopilotConfig::default(),
            wind: WindConfig::default(),
            scenario: ScenarioConfig::default(),
            success: SuccessConfig::default(),
        }
    }
}

/// How simulated time advances.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SimPace {
    /// Simulated time follows the wall clock.
    Realtime,
    /// Simulated time advances frame by frame as the pipeline answers.
    Lockstep,
}

/// The renderer camera model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CameraModel {
    /// GoPro HERO3+ Black 1080p wide: 1920x1080, 118 x 69.5 deg, barrel distortion.
    Gopro,
    /// Narrow USB camera: 640x480, 60 deg diagonal, no distortion.
    Usb,
}

/// `[sim.camera]`: the camera rigidly mounted on the vehicle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CameraConfig {
    /// Camera model, "gopro" (1920x1080, 118 deg, barrel lens) or "usb" (640x480, 60 deg diagonal).
    pub model: CameraModel,
    /// Image size factor, [0.05, 1]: width, height and focal lengths are scaled by it (0.5 = 960x540 GoPro).
    pub scale: f64,
    /// Camera mount pitch relative to the body x axis, degrees, [-90, 90], positive up.
    pub mount_pitch_deg: f64,
}

impl Default for CameraConfig {
    fn default() -> Self {
        CameraConfig {
            model: CameraModel::Gopro,
            scale: 0.5,
            mount_pitch_deg: 0.0,
        }
    }
}

/// `[sim.vehicle]`: the multicopter under ArduCopter's position/velocity controller.
///
/// Defaults follow ArduCopter's stock parameters where one exists (WPNAV_ACCEL 2.5 m/s²,
/// WPNAV_SPEED 5 m/s, WPNAV_SPEED_UP 2.5 m/s, WPNAV_SPEED_DN 1.5 m/s, ANGLE_MAX 30°).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct VehicleConfig {
    /// Velocity response time constant, s, (0, 10]: the velocity follows a step command like a first-order lag.
    pub velocity_tc_s: f64,
    /// Largest acceleration the velocity controller demands, m/s², (0, 9] (horizontal norm, and vertical).
    pub max_accel_m_s2: f64,
    /// Largest horizontal speed, m/s, (0, 30]; faster commands are scaled down to it.
    pub max_speed_m_s: f64,
    /// Largest climb rate, m/s, (0, 10].
    pub max_climb_m_s: f64,
    /// Largest descent rate, m/s, (0, 10].
    pub max_descent_m_s: f64,
    /// Yaw-rate limit, deg/s, (0, 360]; commanded yaw rates are clamped to it.
    pub max_yaw_rate_deg_s: f64,
    /// Yaw-rate response time constant, s, (0, 10].
    pub yaw_tc_s: f64,
    /// Largest tilt (lean) angle, degrees, (0, 60]; the horizontal thrust is limited to g·tan of it.
    pub max_tilt_deg: f64,
    /// Attitude response time constant, s, (0, 2]: roll and pitch follow the demanded tilt with this lag.
    pub attitude_tc_s: f64,
    /// Linear rotor-drag coefficient, 1/s, [0, 5]: air moving at v relative to the vehicle pushes it with c·v (m/s²).
    /// Sets the tilt into the wind (tan θ = c·v/g) and how hard gusts push.
    pub drag_per_s: f64,
    /// Time constant with which the velocity controller's integrator learns a wind disturbance, s, (0, 60].
    /// Gusts faster than this are only partly rejected and show up as velocity errors.
    pub disturbance_tc_s: f64,
}

impl Default for VehicleConfig {
    fn default() -> Self {
        VehicleConfig {
            velocity_tc_s: 0.6,
            max_accel_m_s2: 2.5,
            max_speed_m_s: 5.0,
            max_climb_m_s: 2.5,
            max_descent_m_s: 1.5,
            max_yaw_rate_deg_s: 90.0,
            yaw_tc_s: 0.25,
            max_tilt_deg: 30.0,
            attitude_tc_s: 0.15,
            drag_per_s: 0.3,
            disturbance_tc_s: 1.0,
        }
    }
}

/// `[sim.autopilot]`: the simulated ArduCopter (GUIDED mode) as the companion sees it over MAVLink.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AutopilotConfig {
    /// MAVLink system id of the autopilot, [1, 255].
    pub system_id: u8,
    /// MAVLink component id of the autopilot, [1, 255] (1 = MAV_COMP_ID_AUTOPILOT1).
    pub component_id: u8,
    /// HEARTBEAT rate, Hz, (0, 50].
    pub heartbeat_hz: f64,
    /// ATTITUDE rate, Hz, (0, 400].
    pub attitude_hz: f64,
    /// LOCAL_POSITION_NED rate, Hz, (0, 400].
    pub position_hz: f64,
    /// Velocity command timeout, s, (0, 60]: without a new setpoint for this long the vehicle stops (ArduCopter: 3 s).
    pub command_timeout_s: f64,
    /// Start with the motors armed (true/false).
    pub start_armed: bool,
    /// Enter GUIDED at `guided_after_s` (true/false); false stays in LOITER until set by a script.
    pub start_guided: bool,
    /// Simulated time at which the pilot switches from LOITER to GUIDED, s, [0, 86400]; 0 = GUIDED from the start.
    pub guided_after_s: f64,
}

impl Default for AutopilotConfig {
    fn default() -> Self {
        AutopilotConfig {
            system_id: 1,
            component_id: 1,
            heartbeat_hz: 1.0,
            attitude_hz: 25.0,
            position_hz: 10.0,
            command_timeout_s: 3.0,
            start_armed: true,
            start_guided: true,
            guided_after_s: 0.0,
        }
    }
}

/// `[sim.wind]`: a steady mean wind plus Ornstein–Uhlenbeck gusts (horizontal only).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WindConfig {
    /// Mean wind speed range `[lo, hi]`, m/s, within [0, 30]; the speed is uniform in it, the direction uniform.
    pub mean_speed_m_s: [f64; 2],
    /// Gust standard deviation per horizontal axis, m/s, [0, 10].
    pub gust_sigma_m_s: f64,
    /// Gust correlation time, s, (0, 600].
    pub gust_tau_s: f64,
}

impl Default for WindConfig {
    fn default() -> Self {
        WindConfig {
            mean_speed_m_s: [0.0, 4.0],
            gust_sigma_m_s: 1.0,
            gust_tau_s: 2.0,
        }
    }
}

/// `[sim.scenario]`: where the vehicle starts relative to the turbine and what the scene looks like.
///
/// Offsets are those of the renderer's camera pose: along the rotor axis (in front of the rotor),
/// sideways (+ = the viewer's right when facing the rotor) and up, relative to the hub.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ScenarioConfig {
    /// Start distance in front of the hub along the rotor axis, range `[lo, hi]`, m, within [3, 1000].
    pub distance_m: [f64; 2],
    /// Start sideways offset from the rotor axis, range `[lo, hi]`, m, within [-1000, 1000]; + = viewer's right.
    pub lateral_m: [f64; 2],
    /// Start camera height minus hub height, range `[lo, hi]`, m, within [-60, 60].
    pub height_m: [f64; 2],
    /// Start heading minus the heading that faces the rotor (looking along the axis), range `[lo, hi]`, degrees, within [-180, 180].
    pub heading_offset_deg: [f64; 2],
    /// NED heading of the rotor axis (out of the rotor face), degrees, [0, 360); unset = uniform random per seed.
    pub rotor_axis_heading_deg: Option<f64>,
    /// Allow a met mast or power line in the scene (true/false); false = none.
    pub distractors: bool,
    /// Add a second, distant turbine (true/false).
    pub second_turbine: bool,
    /// Apply JPEG-like compression artefacts (true/false); quality drawn from the seed.
    pub jpeg: bool,
    /// Show the vehicle's own propeller blur in a corner (true/false).
    pub propellers: bool,
}

impl Default for ScenarioConfig {
    fn default() -> Self {
        ScenarioConfig {
            distance_m: [25.0, 40.0],
            lateral_m: [-10.0, 10.0],
            height_m: [-8.0, 4.0],
            heading_offset_deg: [-30.0, 30.0],
            rotor_axis_heading_deg: None,
            distractors: false,
            second_turbine: false,
            jpeg: false,
            propellers: false,
        }
    }
}

/// `[sim.success]`: the target hover and what counts as reaching it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SuccessConfig {
    /// Target camera–hub distance, m, (0, 100].
    pub target_distance_m: f64,
    /// Allowed final distance error, m, (0, 100].
    pub distance_tolerance_m: f64,
    /// Allowed final |relative yaw|, degrees, (0, 90].
    pub yaw_tolerance_deg: f64,
    /// Smallest allowed distance in front of the rotor plane over the whole flight, m, [0, 100].
    pub min_rotor_plane_m: f64,
    /// Final speed must be below this to count as hovering, m/s, (0, 10].
    pub hover_speed_m_s: f64,
}

impl Default for SuccessConfig {
    fn default() -> Self {
        SuccessConfig {
            target_distance_m: 5.0,
            distance_tolerance_m: 0.5,
            yaw_tolerance_deg: 5.0,
            min_rotor_plane_m: 3.0,
            hover_speed_m_s: 0.3,
        }
    }
}

/// `[lo, hi]` with `lo <= hi`, both within `[min, max]`.
fn range(
    c: &Check,
    prefix: &str,
    key: &str,
    r: [f64; 2],
    min: f64,
    max: f64,
) -> Result<(), ParamError> {
    c.closed(key, r[0], min, max)?;
    c.closed(key, r[1], min, max)?;
    if r[0] > r[1] {
        return Err(ParamError {
            key: format!("{prefix}.{key}"),
            value: format!("[{}, {}]", r[0], r[1]),
            allowed: format!("[lo, hi] with lo <= hi within [{min}, {max}]"),
        });
    }
    Ok(())
}

impl SimConfig {
    /// Check every value against its allowed range; the error names the key (`sim.<sub>.<key>`).
    pub fn validate(&self) -> Result<(), ParamError> {
        let c = Check::new("sim");
        c.open_closed("fps", self.fps, 0.0, 240.0)?;
        c.closed("physics_hz", self.physics_hz, self.fps, 10_000.0)?;
        c.open_closed("max_time_s", self.max_time_s, 0.0, MAX_TIME_S)?;
        c.closed(
            "lockstep_timeout_ms",
            self.lockstep_timeout_ms as f64,
            10.0,
            60_000.0,
        )?;
        c.closed("end_after_done_s", self.end_after_done_s, 0.0, 60.0)?;

        let c = Check::new("sim.camera");
        c.closed("scale", self.camera.scale, 0.05, 1.0)?;
        c.closed("mount_pitch_deg", self.camera.mount_pitch_deg, -90.0, 90.0)?;

        let c = Check::new("sim.vehicle");
        let v = &self.vehicle;
        c.open_closed("velocity_tc_s", v.velocity_tc_s, 0.0, 10.0)?;
        // Below g so that the thrust never has to pull downward.
        c.open_closed("max_accel_m_s2", v.max_accel_m_s2, 0.0, 9.0)?;
        c.open_closed("max_speed_m_s", v.max_speed_m_s, 0.0, 30.0)?;
        c.open_closed("max_climb_m_s", v.max_climb_m_s, 0.0, 10.0)?;
        c.open_closed("max_descent_m_s", v.max_descent_m_s, 0.0, 10.0)?;
        c.open_closed("max_yaw_rate_deg_s", v.max_yaw_rate_deg_s, 0.0, 360.0)?;
        c.open_closed("yaw_tc_s", v.yaw_tc_s, 0.0, 10.0)?;
        c.open_closed("max_tilt_deg", v.max_tilt_deg, 0.0, 60.0)?;
        c.open_closed("attitude_tc_s", v.attitude_tc_s, 0.0, 2.0)?;
        c.closed("drag_per_s", v.drag_per_s, 0.0, 5.0)?;
        c.open_closed("disturbance_tc_s", v.disturbance_tc_s, 0.0, 60.0)?;

        let c = Check::new("sim.autopilot");
        let a = &self.autopilot;
        c.count("system_id", a.system_id as u32, 1, 255)?;
        c.count("component_id", a.component_id as u32, 1, 255)?;
        c.open_closed("heartbeat_hz", a.heartbeat_hz, 0.0, 50.0)?;
        c.open_closed("attitude_hz", a.attitude_hz, 0.0, 400.0)?;
        c.open_closed("position_hz", a.position_hz, 0.0, 400.0)?;
        c.open_closed("command_timeout_s", a.command_timeout_s, 0.0, 60.0)?;
        c.closed("guided_after_s", a.guided_after_s, 0.0, MAX_TIME_S)?;

        let c = Check::new("sim.wind");
        let w = &self.wind;
        range(
            &c,
            "sim.wind",
            "mean_speed_m_s",
            w.mean_speed_m_s,
            0.0,
            30.0,
        )?;
        c.closed("gust_sigma_m_s", w.gust_sigma_m_s, 0.0, 10.0)?;
        c.open_closed("gust_tau_s", w.gust_tau_s, 0.0, 600.0)?;

        let p = "sim.scenario";
        let c = Check::new(p);
        let s = &self.scenario;
        range(&c, p, "distance_m", s.distance_m, 3.0, MAX_DISTANCE_M)?;
        range(
            &c,
            p,
            "lateral_m",
            s.lateral_m,
            -MAX_DISTANCE_M,
            MAX_DISTANCE_M,
        )?;
        range(&c, p, "height_m", s.height_m, -60.0, 60.0)?;
        range(
            &c,
            p,
            "heading_offset_deg",
            s.heading_offset_deg,
            -180.0,
            180.0,
        )?;
        if let Some(h) = s.rotor_axis_heading_deg {
            if !(h.is_finite() && (0.0..360.0).contains(&h)) {
                return Err(ParamError {
                    key: format!("{p}.rotor_axis_heading_deg"),
                    value: h.to_string(),
                    allowed: "[0, 360) or unset (random)".into(),
                });
            }
        }

        let c = Check::new("sim.success");
        let s = &self.success;
        c.open_closed("target_distance_m", s.target_distance_m, 0.0, 100.0)?;
        c.open_closed("distance_tolerance_m", s.distance_tolerance_m, 0.0, 100.0)?;
        c.open_closed("yaw_tolerance_deg", s.yaw_tolerance_deg, 0.0, 90.0)?;
        c.closed("min_rotor_plane_m", s.min_rotor_plane_m, 0.0, 100.0)?;
        c.open_closed("hover_speed_m_s", s.hover_speed_m_s, 0.0, 10.0)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_documented_values() {
        let c = SimConfig::default();
        c.validate().unwrap();
        assert_eq!(c.seed, 1);
        assert_eq!(c.fps, 15.0);
        assert_eq!(c.physics_hz, 200.0);
        assert_eq!(c.max_time_s, 120.0);
        assert_eq!(c.autopilot.command_timeout_s, 3.0);
        assert_eq!(c.success.target_distance_m, 5.0);
    }

    #[test]
    fn toml_round_trip_and_partial_sections() {
        let c = SimConfig::default();
        let text = toml::to_string(&c).unwrap();
        let back: SimConfig = toml::from_str(&text).unwrap();
        assert_eq!(back, c);

        let part: SimConfig = toml::from_str(
            "seed = 7\n[camera]\nmodel = \"usb\"\n[scenario]\nrotor_axis_heading_deg = 90.0\ndistance_m = [30.0, 30.0]\n",
        )
        .unwrap();
        assert_eq!(part.seed, 7);
        assert_eq!(part.camera.model, CameraModel::Usb);
        assert_eq!(part.camera.scale, 0.5);
        assert_eq!(part.scenario.rotor_axis_heading_deg, Some(90.0));
        part.validate().unwrap();
    }

    #[test]
    fn unknown_keys_are_errors() {
        assert!(toml::from_str::<SimConfig>("[vehicle]\nmax_tilt = 3.0\n").is_err());
        assert!(toml::from_str::<SimConfig>("[camera]\nmodel = \"webcam\"\n").is_err());
    }

    #[test]
    fn errors_name_the_full_key() {
        let mut c = SimConfig::default();
        c.vehicle.max_tilt_deg = 80.0;
        assert_eq!(c.validate().unwrap_err().key, "sim.vehicle.max_tilt_deg");

        let mut c = SimConfig::default();
        c.scenario.distance_m = [40.0, 25.0];
        let e = c.validate().unwrap_err();
        assert_eq!(e.key, "sim.scenario.distance_m");
        assert!(e.allowed.contains("lo <= hi"));

        let c = SimConfig {
            physics_hz: 10.0,
            ..Default::default()
        };
        assert_eq!(c.validate().unwrap_err().key, "sim.physics_hz");

        let mut c = SimConfig::default();
        c.autopilot.system_id = 0;
        assert_eq!(c.validate().unwrap_err().key, "sim.autopilot.system_id");

        let mut c = SimConfig::default();
        c.scenario.rotor_axis_heading_deg = Some(360.0);
        assert_eq!(
            c.validate().unwrap_err().key,
            "sim.scenario.rotor_axis_heading_deg"
        );

        let mut c = SimConfig::default();
        c.wind.gust_tau_s = 0.0;
        assert_eq!(c.validate().unwrap_err().key, "sim.wind.gust_tau_s");
    }
}
