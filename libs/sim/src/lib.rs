//! Simulated multicopter and ArduCopter GUIDED-mode autopilot, seeded approach scenarios and
//! flight outcome metrics.
//!
//! This is the pure, deterministic part of the flight simulator: no IO, no threads, no wall
//! clock. All randomness comes from a seed (the crate's own SplitMix64), all time is passed in.
//! A simulator process built on it runs a loop like
//!
//! ```no_run
//! # use hubtrack_sim::*;
//! let cfg = SimConfig::default();
//! let scenario = Scenario::from_config(&cfg);
//! let mut vehicle = Multicopter::new(&scenario.start, &cfg.vehicle);
//! let mut wind = scenario.wind(&cfg.wind);
//! let mut autopilot = Autopilot::new(&cfg.autopilot);
//! let mut recorder = FlightRecorder::from_config(scenario.seed, &cfg);
//! let dt = 1.0 / cfg.physics_hz;
//! let mut t = 0.0;
//! while t < cfg.max_time_s {
//!     // for each MAVLink message received: autopilot.handle(t, &header, &msg, &vehicle);
//!     let cmd = autopilot.command(t);
//!     vehicle.step(dt, &cmd, &mut wind);
//!     t += dt;
//!     let _to_send = autopilot.outgoing(t, &vehicle);
//!     recorder.step(t, &vehicle, &geometry(&scenario, &vehicle));
//!     // every 1/fps: render camera_pose(&scenario, &vehicle, &cfg.camera) with render_camera(&cfg.camera)
//! }
//! let outcome = recorder.finish(t, &vehicle, &geometry(&scenario, &vehicle), "max_time");
//! ```
//!
//! # Conventions
//! * **Local NED** (autopilot frame): origin on the flat ground (z = 0) below the vehicle's
//!   start; x north, y east, z down. Height above ground = −z.
//! * **Attitude**: ZYX Euler angles as in MAVLink ATTITUDE: roll right side down positive, pitch
//!   nose up positive, yaw clockwise from north in (−π, π]. Body rates `[p, q, r]` in FRD body axes.
//!   Yaw rates are positive clockwise (turning right).
//! * **Render world** (`hubtrack_render`): X rotor axis out of the rotor face, Y viewer's right
//!   when facing the rotor, Z up, origin at the tower base; the scene keeps `nacelle_yaw_deg = 0`
//!   and world X points along the NED heading [`Scenario::rotor_axis_heading_rad`]. See
//!   [`scenario`] for the exact mapping.
//! * **Camera**: at the vehicle's position, along the body nose tilted up by
//!   `mount_pitch_deg`. [`camera_pose`] returns the renderer pose: a vehicle facing the hub gives
//!   `yaw_deg = 0`; nose down gives a negative `pitch_deg`; roll right gives a positive
//!   `roll_deg`.
//! * **Relative yaw** ([`Geometry::relative_yaw_deg`]): the renderer's `Truth::relative_yaw_deg`,
//!   `atan2(lateral, along-axis)`, positive on the viewer's right.
//! * **Wind**: air velocity (where the air goes), NED, m/s.

#![warn(missing_docs)]

pub mod autopilot;
pub mod math;
pub mod outcome;
pub mod params;
pub mod pilot;
pub mod rotorcraft;
pub mod scenario;
pub mod sitl_json;
pub mod vehicle;
pub mod wind;

mod rng;

pub use autopilot::{
    AcceptedSetpoint, Autopilot, AutopilotStats, CommandResult, IgnoreReason, RejectReason,
};
pub use math::{wrap_deg, wrap_pi, GRAVITY_M_S2};
pub use outcome::{FlightRecorder, Outcome};
pub use params::{
    AutopilotConfig, CameraConfig, CameraModel, FlightController, ParamError, ScenarioConfig,
    SimConfig, SimPace, SuccessConfig, VehicleConfig, WindConfig,
};
pub use pilot::{Pilot, PilotConfig, PilotPhase, PilotView};
pub use rotorcraft::{FrameLayout, Rotorcraft, RotorcraftConfig};
pub use scenario::{camera_pose, geometry, render_camera, show_turbine, Geometry, Scenario};
pub use vehicle::{Multicopter, VehicleStart, VelocityCommand};
pub use wind::Wind;
