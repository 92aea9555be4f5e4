//! Shared helpers for the unit tests.

use mavlink::dialects::common::*;
use mavlink::MavHeader;

use crate::{velocity_setpoint, SetpointFrame, COPTER_MODE_GUIDED};

/// The project's deterministic PRNG (SplitMix64), so tests are reproducible.
pub use hubtrack_types::mutate::Rng;

/// Bytes from [`Rng`] for the parser's tests.
pub trait RngBytes {
    /// A random byte.
    fn byte(&mut self) -> u8;
    /// A random byte that is not a frame start.
    fn non_stx_byte(&mut self) -> u8;
}

impl RngBytes for Rng {
    fn byte(&mut self) -> u8 {
        self.next_u64() as u8
    }

    fn non_stx_byte(&mut self) -> u8 {
        loop {
            let b = self.byte();
            if b != mavlink::MAV_STX && b != mavlink::MAV_STX_V2 {
                return b;
            }
        }
    }
}

pub fn header(system_id: u8, component_id: u8, sequence: u8) -> MavHeader {
    MavHeader {
        system_id: u32::from(system_id),
        component_id,
        sequence,
    }
}

pub fn autopilot_heartbeat(armed: bool, custom_mode: u32) -> MavMessage {
    let mut base_mode = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
        | MavModeFlag::MAV_MODE_FLAG_STABILIZE_ENABLED;
    if armed {
        base_mode |= MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED;
    }
    MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode,
        mavtype: MavType::MAV_TYPE_QUADROTOR,
        autopilot: MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA,
        base_mode,
        system_status: MavState::MAV_STATE_ACTIVE,
        mavlink_version: 3,
    })
}

pub fn gcs_heartbeat() -> MavMessage {
    MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: 0,
        mavtype: MavType::MAV_TYPE_GCS,
        autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
        base_mode: MavModeFlag::empty(),
        system_status: MavState::MAV_STATE_ACTIVE,
        mavlink_version: 3,
    })
}

pub fn attitude(time_boot_ms: u32, roll: f32, pitch: f32, yaw: f32) -> MavMessage {
    MavMessage::ATTITUDE(ATTITUDE_DATA {
        time_boot_ms,
        roll,
        pitch,
        yaw,
        rollspeed: 0.01,
        pitchspeed: -0.02,
        yawspeed: 0.03,
    })
}

pub fn local_position(time_boot_ms: u32) -> MavMessage {
    MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
        time_boot_ms,
        x: 12.5,
        y: -3.25,
        z: -20.0,
        vx: 1.5,
        vy: -0.5,
        vz: 0.25,
    })
}

pub fn global_position(time_boot_ms: u32) -> MavMessage {
    MavMessage::GLOBAL_POSITION_INT(GLOBAL_POSITION_INT_DATA {
        time_boot_ms,
        lat: 593_000_000,
        lon: 105_000_000,
        alt: 150_000,
        relative_alt: 20_500,
        vx: 150,
        vy: -50,
        vz: 25,
        hdg: 9000,
    })
}

/// One of each message the link carries, with distinct headers.
pub fn sample_messages() -> Vec<(MavHeader, MavMessage)> {
    vec![
        (
            header(1, 1, 0),
            autopilot_heartbeat(true, COPTER_MODE_GUIDED),
        ),
        (header(1, 1, 1), attitude(123_456, 0.1, -0.2, 1.5)),
        (header(1, 1, 2), local_position(123_470)),
        (header(1, 1, 3), global_position(123_480)),
        (
            header(1, 191, 7),
            velocity_setpoint((1, 1), 5000, SetpointFrame::BodyNed, [1.0, -0.5, 0.25], 0.1),
        ),
    ]
}
