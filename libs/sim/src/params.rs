//! Configuration of the simulator (`[sim]` in the config file).
//!
//! Plain serde data, each section declared once with [`hubtrack_types::params!`] (every field with
//! its doc, default and allowed range): keys left out take the defaults below and a misspelt key
//! is an error. [`SimConfig::validate`] checks every number against its allowed range (and the
//! scenario ranges and the physics rate against the frame rate) and names the offending key by
//! its full dotted path (`sim.vehicle.max_tilt_deg`).
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

hubtrack_types::params! {
    /// `[sim]`: the flight simulator (scenario, vehicle, autopilot, wind, camera, success rules).
    pub struct SimConfig {
        /// Scenario seed, any u64: the same seed gives the same turbine, start, wind and images.
        pub seed: u64 = 1;
        /// Camera frame rate, Hz, (0, 240].
        pub fps: f64 = 15.0, open_closed(0.0, 240.0);
        /// Physics integration rate, Hz, [fps, 10000]; the autopilot's messages are timed on it.
        pub physics_hz: f64 = 200.0;
        /// A flight ends after this much simulated time, s, (0, 86400].
        pub max_time_s: f64 = 120.0, open_closed(0.0, MAX_TIME_S);
        /// "realtime": simulated time follows the wall clock (the demo); "lockstep": each camera
        /// frame waits for control's setpoint for it, so time advances as fast as the stages answer
        /// and a seed gives the same flight every time (`hubtrack fly`).
        pub pace: SimPace = SimPace::Realtime;
        /// Lockstep: longest wait for the pipeline's answer to one frame before going on without
        /// it, ms, [10, 60000].
        pub lockstep_timeout_ms: u64 = 2000, closed(10, 60_000);
        /// The flight ends once control has reported `done` this long, s, [0, 60] (the final hold).
        pub end_after_done_s: f64 = 3.0, closed(0.0, 60.0);
        /// MAVLink link to control, as `control.link` ("udpout:HOST:PORT", "udpin:HOST:PORT" or
        /// "serial:DEVICE:BAUD"); default "udpout:127.0.0.1:14550", where control listens by
        /// default.
        pub link: String = "udpout:127.0.0.1:14550".into();
        /// The camera on the vehicle.
        pub camera: CameraConfig = CameraConfig::default();
        /// The multicopter model.
        pub vehicle: VehicleConfig = VehicleConfig::default();
        /// The simulated ArduCopter autopilot, as seen over MAVLink.
        pub autopilot: AutopilotConfig = AutopilotConfig::default();
        /// Mean wind and gusts.
        pub wind: WindConfig = WindConfig::default();
        /// How the seeded approach scenarios are drawn.
        pub scenario: ScenarioConfig = ScenarioConfig::default();
        /// When a flight counts as a success.
        pub success: SuccessConfig = SuccessConfig::default();
        /// Who flies the vehicle: "model" (our model of ArduCopter: `[sim.autopilot]` and
        /// `[sim.vehicle]`) or "ardupilot" (ArduCopter SITL coupled through its JSON physics
        /// interface: `[sim.rotorcraft]` and `[sim.pilot]`; `hubtrack fly --autopilot ardupilot`).
        pub flight_controller: FlightController = FlightController::Model;
        /// UDP port on which the simulator serves ArduPilot SITL's JSON physics (SITL's
        /// `--sim-port-out`; 9002 is SITL's default), [1, 65535].
        pub sitl_json_port: u16 = 9002, closed(1, 65535);
        /// The quadcopter ArduCopter SITL flies.
        pub rotorcraft: crate::rotorcraft::RotorcraftConfig = Default::default();
        /// The pilot that takes ArduCopter SITL to the start pose.
        pub pilot: crate::pilot::PilotConfig = Default::default();
    }
}

/// Who flies the simulated vehicle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FlightController {
    /// Our model of ArduCopter in GUIDED (`libs/sim` autopilot and vehicle).
    Model,
    /// The real ArduCopter firmware as SITL, flying our rotorcraft physics.
    Ardupilot,
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

hubtrack_types::params! {
    /// `[sim.camera]`: the camera rigidly mounted on the vehicle.
    pub struct CameraConfig {
        /// Camera model, "gopro" (1920x1080, 118 deg, barrel lens) or "usb" (640x480, 60 deg
        /// diagonal).
        pub model: CameraModel = CameraModel::Gopro;
        /// Image size factor, [0.05, 1]: width, height and focal lengths are scaled by it (0.5 =
        /// 960x540 GoPro).
        pub scale: f64 = 0.5, closed(0.05, 1.0);
        /// Camera mount pitch relative to the body x axis, degrees, [-90, 90], positive up.
        pub mount_pitch_deg: f64 = 0.0, closed(-90.0, 90.0);
    }
}

hubtrack_types::params! {
    /// `[sim.vehicle]`: the multicopter under ArduCopter's position/velocity controller.
    ///
    /// Defaults follow ArduCopter's stock parameters where one exists (WPNAV_ACCEL 2.5 m/s²,
    /// WPNAV_SPEED 5 m/s, WPNAV_SPEED_UP 2.5 m/s, WPNAV_SPEED_DN 1.5 m/s, ANGLE_MAX 30°).
    pub struct VehicleConfig {
        /// Velocity response time constant, s, (0, 10]: the velocity follows a step command like a
        /// first-order lag.
        pub velocity_tc_s: f64 = 0.6, open_closed(0.0, 10.0);
        /// Largest acceleration the velocity controller demands, m/s², (0, 9] (horizontal norm, and
        /// vertical).
        // Below g so that the thrust never has to pull downward.
        pub max_accel_m_s2: f64 = 2.5, open_closed(0.0, 9.0);
        /// Largest horizontal speed, m/s, (0, 30]; faster commands are scaled down to it.
        pub max_speed_m_s: f64 = 5.0, open_closed(0.0, 30.0);
        /// Largest climb rate, m/s, (0, 10].
        pub max_climb_m_s: f64 = 2.5, open_closed(0.0, 10.0);
        /// Largest descent rate, m/s, (0, 10].
        pub max_descent_m_s: f64 = 1.5, open_closed(0.0, 10.0);
        /// Yaw-rate limit, deg/s, (0, 360]; commanded yaw rates are clamped to it.
        pub max_yaw_rate_deg_s: f64 = 90.0, open_closed(0.0, 360.0);
        /// Yaw-rate response time constant, s, (0, 10].
        pub yaw_tc_s: f64 = 0.25, open_closed(0.0, 10.0);
        /// Largest tilt (lean) angle, degrees, (0, 60]; the horizontal thrust is limited to g·tan
        /// of it.
        pub max_tilt_deg: f64 = 30.0, open_closed(0.0, 60.0);
        /// Attitude response time constant, s, (0, 2]: roll and pitch follow the demanded tilt with
        /// this lag.
        pub attitude_tc_s: f64 = 0.15, open_closed(0.0, 2.0);
        /// Linear rotor-drag coefficient, 1/s, [0, 5]: air moving at v relative to the vehicle
        /// pushes it with c·v (m/s²). Sets the tilt into the wind (tan θ = c·v/g) and how hard
        /// gusts push.
        pub drag_per_s: f64 = 0.3, closed(0.0, 5.0);
        /// Time constant with which the velocity controller's integrator learns a wind disturbance,
        /// s, (0, 60]. Gusts faster than this are only partly rejected and show up as velocity
        /// errors.
        pub disturbance_tc_s: f64 = 1.0, open_closed(0.0, 60.0);
    }
}

hubtrack_types::params! {
    /// `[sim.autopilot]`: the simulated ArduCopter (GUIDED mode) as the companion sees it over
    /// MAVLink.
    pub struct AutopilotConfig {
        /// MAVLink system id of the autopilot, [1, 255].
        pub system_id: u8 = 1, closed(1, 255);
        /// MAVLink component id of the autopilot, [1, 255] (1 = MAV_COMP_ID_AUTOPILOT1).
        pub component_id: u8 = 1, closed(1, 255);
        /// HEARTBEAT rate, Hz, (0, 50].
        pub heartbeat_hz: f64 = 1.0, open_closed(0.0, 50.0);
        /// ATTITUDE rate, Hz, (0, 400].
        pub attitude_hz: f64 = 25.0, open_closed(0.0, 400.0);
        /// LOCAL_POSITION_NED rate, Hz, (0, 400].
        pub position_hz: f64 = 10.0, open_closed(0.0, 400.0);
        /// Velocity command timeout, s, (0, 60]: without a new setpoint for this long the vehicle
        /// stops (ArduCopter: 3 s).
        pub command_timeout_s: f64 = 3.0, open_closed(0.0, 60.0);
        /// Start with the motors armed (true/false).
        pub start_armed: bool = true;
        /// Enter GUIDED at `guided_after_s` (true/false); false stays in LOITER until set by a
        /// script.
        pub start_guided: bool = true;
        /// Simulated time at which the pilot switches from LOITER to GUIDED, s, [0, 86400]; 0 =
        /// GUIDED from the start.
        pub guided_after_s: f64 = 0.0, closed(0.0, MAX_TIME_S);
    }
}

hubtrack_types::params! {
    /// `[sim.wind]`: a steady mean wind plus Ornstein–Uhlenbeck gusts (horizontal only).
    pub struct WindConfig {
        /// Mean wind speed range `[lo, hi]`, m/s, within [0, 30]; the speed is uniform in it, the
        /// direction uniform.
        pub mean_speed_m_s: [f64; 2] = [0.0, 4.0];
        /// Gust standard deviation per horizontal axis, m/s, [0, 10].
        pub gust_sigma_m_s: f64 = 1.0, closed(0.0, 10.0);
        /// Gust correlation time, s, (0, 600].
        pub gust_tau_s: f64 = 2.0, open_closed(0.0, 600.0);
    }
}

hubtrack_types::params! {
    /// `[sim.scenario]`: where the vehicle starts relative to the turbine and what the scene looks
    /// like.
    ///
    /// Offsets are those of the renderer's camera pose: along the rotor axis (in front of the
    /// rotor), sideways (+ = the viewer's right when facing the rotor) and up, relative to the hub.
    pub struct ScenarioConfig {
        /// Start distance in front of the hub along the rotor axis, range `[lo, hi]`, m, within [3,
        /// 1000].
        pub distance_m: [f64; 2] = [25.0, 40.0];
        /// Start sideways offset from the rotor axis, range `[lo, hi]`, m, within [-1000, 1000]; +
        /// = viewer's right.
        pub lateral_m: [f64; 2] = [-10.0, 10.0];
        /// Start camera height minus hub height, range `[lo, hi]`, m, within [-60, 60].
        pub height_m: [f64; 2] = [-8.0, 4.0];
        /// Start heading minus the heading that faces the rotor (looking along the axis), range
        /// `[lo, hi]`, degrees, within [-180, 180].
        pub heading_offset_deg: [f64; 2] = [-30.0, 30.0];
        /// NED heading of the rotor axis (out of the rotor face), degrees, [0, 360); unset =
        /// uniform random per seed.
        pub rotor_axis_heading_deg: Option<f64> = None;
        /// Allow a met mast or power line in the scene (true/false); false = none.
        pub distractors: bool = false;
        /// Add a second, distant turbine (true/false).
        pub second_turbine: bool = false;
        /// Apply JPEG-like compression artefacts (true/false); quality drawn from the seed.
        pub jpeg: bool = false;
        /// Show the vehicle's own propeller blur in a corner (true/false).
        pub propellers: bool = false;
    }
}

hubtrack_types::params! {
    /// `[sim.success]`: the target hover and what counts as reaching it.
    pub struct SuccessConfig {
        /// Target camera–hub distance, m, (0, 100].
        pub target_distance_m: f64 = 5.0, open_closed(0.0, 100.0);
        /// Allowed final distance error, m, (0, 100].
        pub distance_tolerance_m: f64 = 0.5, open_closed(0.0, 100.0);
        /// Allowed final |relative yaw|, degrees, (0, 90].
        pub yaw_tolerance_deg: f64 = 5.0, open_closed(0.0, 90.0);
        /// Smallest allowed distance in front of the rotor plane over the whole flight, m, [0,
        /// 100].
        pub min_rotor_plane_m: f64 = 3.0, closed(0.0, 100.0);
        /// Final speed must be below this to count as hovering, m/s, (0, 10].
        pub hover_speed_m_s: f64 = 0.3, open_closed(0.0, 10.0);
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
            problem: None,
        });
    }
    Ok(())
}

impl SimConfig {
    /// Check every value against its allowed range; the error names the key (`sim.<sub>.<key>`).
    pub fn validate(&self) -> Result<(), ParamError> {
        self.check_ranges("sim")?;
        Check::new("sim").closed("physics_hz", self.physics_hz, self.fps, 10_000.0)?;
        self.camera.check_ranges("sim.camera")?;
        self.vehicle.check_ranges("sim.vehicle")?;
        self.autopilot.check_ranges("sim.autopilot")?;
        self.wind.validate("sim.wind")?;
        self.scenario.validate("sim.scenario")?;
        self.success.check_ranges("sim.success")?;
        self.rotorcraft.validate("sim.rotorcraft")?;
        self.pilot.check_ranges("sim.pilot")
    }
}

impl WindConfig {
    /// [`WindConfig::check_ranges`], then the mean speed range within [0, 30].
    pub fn validate(&self, section: &str) -> Result<(), ParamError> {
        self.check_ranges(section)?;
        let c = Check::new(section);
        range(
            &c,
            section,
            "mean_speed_m_s",
            self.mean_speed_m_s,
            0.0,
            30.0,
        )
    }
}

impl ScenarioConfig {
    /// [`ScenarioConfig::check_ranges`], then every start range and the rotor axis heading.
    pub fn validate(&self, section: &str) -> Result<(), ParamError> {
        self.check_ranges(section)?;
        let c = Check::new(section);
        range(
            &c,
            section,
            "distance_m",
            self.distance_m,
            3.0,
            MAX_DISTANCE_M,
        )?;
        range(
            &c,
            section,
            "lateral_m",
            self.lateral_m,
            -MAX_DISTANCE_M,
            MAX_DISTANCE_M,
        )?;
        range(&c, section, "height_m", self.height_m, -60.0, 60.0)?;
        range(
            &c,
            section,
            "heading_offset_deg",
            self.heading_offset_deg,
            -180.0,
            180.0,
        )?;
        if let Some(h) = self.rotor_axis_heading_deg {
            if !(h.is_finite() && (0.0..360.0).contains(&h)) {
                return Err(ParamError {
                    key: format!("{section}.rotor_axis_heading_deg"),
                    value: h.to_string(),
                    allowed: "[0, 360) or unset (random)".into(),
                    problem: None,
                });
            }
        }
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
