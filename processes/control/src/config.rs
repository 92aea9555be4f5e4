//! `[control]`: the MAVLink link to the autopilot, the command timing and the approach.

use hubtrack_runtime::config::ParamError;
use hubtrack_types::params;
use serde::{Deserialize, Serialize};

/// Which clock control stamps MAVLink input with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ClockSource {
    /// `CLOCK_MONOTONIC`, the clock of real cameras (flight).
    Monotonic,
    /// The simulator's clock (service `clock`), so a lockstep simulation has one time base.
    Sim,
}

params! {
    /// `[control]`: the approach controller and the MAVLink link to the autopilot.
    pub struct ControlConfig {
        /// MAVLink link to the autopilot: "udpin:HOST:PORT" (listen; replies go to the sender),
        /// "udpout:HOST:PORT" (send there), or "serial:DEVICE:BAUD" (e.g.
        /// "serial:/dev/ttyAMA0:921600"). The simulator sends to the default.
        pub link: String = "udpin:127.0.0.1:14550".into();
        /// Our MAVLink system id: the vehicle's own (ArduPilot SYSID_THISMAV, default 1).
        pub system_id: u8 = 1, closed(1, 255);
        /// Our MAVLink component id: 191 = MAV_COMP_ID_ONBOARD_COMPUTER.
        pub component_id: u8 = 191, closed(1, 255);
        /// The autopilot's component id (1 = MAV_COMP_ID_AUTOPILOT1; 0: any component of
        /// `system_id`). Heartbeats and telemetry from any other system or component are
        /// ignored, and on "udpin" replies go only to the address the autopilot speaks from.
        pub autopilot_component_id: u8 = 1, closed(0, 255);
        /// MAVLink 2 signing key file ("": signing off): 64 hex digits, the 32-byte key shared
        /// with the autopilot (make it with `hubtrack signing-key FILE`), readable by its owner
        /// only. With a key, every frame sent is signed, and frames received unsigned, with
        /// another key or with a replayed timestamp are refused and counted. Relative to the
        /// config file.
        pub signing_key_file: String = String::new();
        /// Link id in the signature of our frames (one stream per link, spec: the channel).
        pub signing_link_id: u8 = 0;
        /// Frame of the velocity setpoints: "body_offset_ned" (MAV_FRAME_BODY_OFFSET_NED = 9,
        /// velocities along the vehicle's heading, what ArduCopter documents for body
        /// velocities) or "body_ned" (8).
        pub setpoint_frame: hubtrack_mavlink::SetpointFrame =
            hubtrack_mavlink::SetpointFrame::BodyOffsetNed;
        /// Setpoints are sent on every new track state and at least this often while inputs
        /// are fresh, Hz.
        pub setpoint_rate_hz: f64 = 15.0, closed(10.0, 50.0);
        /// Our HEARTBEAT to the autopilot, Hz (ArduPilot expects 1 Hz).
        pub heartbeat_hz: f64 = 1.0, closed(0.2, 10.0);
        /// No autopilot HEARTBEAT for this long means the link is lost: stop commanding, ms.
        pub link_timeout_ms: u64 = 3000, closed(500, 30_000);
        /// Attitude and position older than this are not used, ms.
        pub vehicle_timeout_ms: u64 = 500, closed(50, 5000);
        /// No track state for this long (wall clock) means our inputs are stale: send nothing at
        /// all, so ArduPilot's guided-mode timeout stops the vehicle, ms.
        pub input_timeout_ms: u64 = 500, closed(50, 5000);
        /// ATTITUDE asked of the autopilot (MAV_CMD_SET_MESSAGE_INTERVAL), Hz: detect levels the
        /// image with it and track compensates the vehicle's rotation.
        pub attitude_rate_hz: f64 = 50.0, closed(1.0, 200.0);
        /// LOCAL_POSITION_NED asked of the autopilot, Hz.
        pub position_rate_hz: f64 = 25.0, closed(1.0, 200.0);
        /// A requested message not heard for this long (wall clock) is asked for again, ms: after
        /// an autopilot reboot, a lost request, or before the autopilot was there.
        pub stream_retry_ms: u64 = 1000, closed(100, 60_000);
        /// Clock used to stamp autopilot messages: "monotonic" (flight) or "sim" (simulated
        /// flights, where the simulator's clock drives the pipeline).
        pub clock: ClockSource = ClockSource::Monotonic;
        /// The T1/T2/T3 approach.
        pub approach: hubtrack_approach::ApproachConfig = Default::default();
    }
}

impl ControlConfig {
    /// Checks every value; errors name the key under `control`.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.check_ranges("control")?;
        hubtrack_mavlink::Endpoint::of_config("control.link", &self.link)?;
        self.approach.validate()
    }
}

hubtrack_runtime::sections! {
    /// What the control stage reads.
    pub struct ControlSections {
        camera: hubtrack_types::setup::CameraSetup,
        turbine: hubtrack_types::setup::TurbineSetup,
        control: ControlConfig,
    }
}
