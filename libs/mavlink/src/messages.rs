//! The messages the companion sends: its HEARTBEAT and velocity setpoints, plus ArduCopter
//! numbers.

use mavlink::dialects::common::{
    MavAutopilot, MavFrame, MavMessage, MavModeFlag, MavState, MavType, PositionTargetTypemask,
    HEARTBEAT_DATA, SET_POSITION_TARGET_LOCAL_NED_DATA,
};
use mavlink::MavHeader;

/// Who we are on the link.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Identity {
    /// MAVLink system id; a companion computer normally shares the autopilot's (1).
    pub system_id: u8,
    /// MAVLink component id; [`COMPONENT_ID_ONBOARD_COMPUTER`] for the companion.
    pub component_id: u8,
}

impl Identity {
    /// The header for one outgoing frame with this identity and sequence number.
    pub fn header(&self, sequence: u8) -> MavHeader {
        MavHeader {
            system_id: u32::from(self.system_id),
            component_id: self.component_id,
            sequence,
        }
    }
}

/// MAV_COMP_ID_ONBOARD_COMPUTER, the component id of a companion computer.
pub const COMPONENT_ID_ONBOARD_COMPUTER: u8 = 191;

/// ArduCopter custom_mode number of GUIDED.
pub const COPTER_MODE_GUIDED: u32 = 4;

/// type_mask for "velocity + yaw rate only" (ignore position, acceleration, yaw) = 1479.
pub const TYPE_MASK_VELOCITY_YAW_RATE: u16 = 1479;

// The number above is the named bits; checked at compile time.
const _: () = assert!(
    PositionTargetTypemask::POSITION_TARGET_TYPEMASK_X_IGNORE.bits()
        | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_Y_IGNORE.bits()
        | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_Z_IGNORE.bits()
        | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_AX_IGNORE.bits()
        | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_AY_IGNORE.bits()
        | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_AZ_IGNORE.bits()
        | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_YAW_IGNORE.bits()
        == TYPE_MASK_VELOCITY_YAW_RATE
);

/// Names of ArduCopter's custom_mode numbers (ArduCopter `Mode::Number`).
const COPTER_MODE_NAMES: &[(u32, &str)] = &[
    (0, "STABILIZE"),
    (1, "ACRO"),
    (2, "ALT_HOLD"),
    (3, "AUTO"),
    (COPTER_MODE_GUIDED, "GUIDED"),
    (5, "LOITER"),
    (6, "RTL"),
    (7, "CIRCLE"),
    (9, "LAND"),
    (11, "DRIFT"),
    (13, "SPORT"),
    (14, "FLIP"),
    (15, "AUTOTUNE"),
    (16, "POSHOLD"),
    (17, "BRAKE"),
    (18, "THROW"),
    (19, "AVOID_ADSB"),
    (20, "GUIDED_NOGPS"),
    (21, "SMART_RTL"),
    (22, "FLOWHOLD"),
    (23, "FOLLOW"),
    (24, "ZIGZAG"),
    (25, "SYSTEMID"),
    (26, "AUTOROTATE"),
    (27, "AUTO_RTL"),
    (28, "TURTLE"),
];

/// The ArduCopter name of a custom_mode number (`GUIDED` for 4), `None` if unknown.
pub fn copter_mode_name(custom_mode: u32) -> Option<&'static str> {
    COPTER_MODE_NAMES
        .iter()
        .find(|(n, _)| *n == custom_mode)
        .map(|(_, name)| *name)
}

/// The companion's HEARTBEAT: MAV_TYPE_ONBOARD_CONTROLLER, MAV_AUTOPILOT_INVALID,
/// MAV_STATE_ACTIVE, no mode flags.
///
/// ArduPilot only forwards messages to a link after it has seen a heartbeat there, and GCSs list
/// the companion by it; send it at 1 Hz.
pub fn companion_heartbeat() -> MavMessage {
    MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: 0,
        mavtype: MavType::MAV_TYPE_ONBOARD_CONTROLLER,
        autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
        base_mode: MavModeFlag::empty(),
        system_status: MavState::MAV_STATE_ACTIVE,
        mavlink_version: mavlink::dialects::common::MINOR_MAVLINK_VERSION,
    })
}

/// Which body frame velocity setpoints use.
///
/// For velocities ArduCopter treats both the same: x forward and y right along the vehicle's
/// heading, z down, not tilted with roll and pitch (it rotates the vector by yaw only).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SetpointFrame {
    /// MAV_FRAME_BODY_NED (8).
    BodyNed,
    /// MAV_FRAME_BODY_OFFSET_NED (9).
    BodyOffsetNed,
}

impl SetpointFrame {
    /// The MAV_FRAME value.
    // The two body frames are deprecated in the MAVLink spec in favour of MAV_FRAME_BODY_FRD,
    // which ArduCopter does not accept for SET_POSITION_TARGET_LOCAL_NED.
    #[allow(deprecated)]
    pub fn mav_frame(self) -> MavFrame {
        match self {
            SetpointFrame::BodyNed => MavFrame::MAV_FRAME_BODY_NED,
            SetpointFrame::BodyOffsetNed => MavFrame::MAV_FRAME_BODY_OFFSET_NED,
        }
    }
}

/// SET_POSITION_TARGET_LOCAL_NED with velocity `v` (m/s, body x forward, y right, z down) and
/// yaw rate (rad/s, positive clockwise seen from above), type_mask
/// [`TYPE_MASK_VELOCITY_YAW_RATE`], for `target` = (system, component), stamped `time_boot_ms`.
///
/// ArduCopter acts on it only in GUIDED and stops the vehicle if no new setpoint arrives within
/// about 3 s, so send it continuously.
pub fn velocity_setpoint(
    target: (u8, u8),
    time_boot_ms: u32,
    frame: SetpointFrame,
    v: [f32; 3],
    yaw_rate: f32,
) -> MavMessage {
    MavMessage::SET_POSITION_TARGET_LOCAL_NED(SET_POSITION_TARGET_LOCAL_NED_DATA {
        time_boot_ms,
        x: 0.0,
        y: 0.0,
        z: 0.0,
        vx: v[0],
        vy: v[1],
        vz: v[2],
        afx: 0.0,
        afy: 0.0,
        afz: 0.0,
        yaw: 0.0,
        yaw_rate,
        type_mask: PositionTargetTypemask::from_bits_retain(TYPE_MASK_VELOCITY_YAW_RATE),
        target_system: target.0,
        target_component: target.1,
        coordinate_frame: frame.mav_frame(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{encode_v2, FrameParser};

    #[test]
    fn velocity_setpoint_fields() {
        for (frame, number) in [
            (SetpointFrame::BodyNed, 8),
            (SetpointFrame::BodyOffsetNed, 9),
        ] {
            let msg = velocity_setpoint((1, 1), 4242, frame, [1.5, -0.5, 0.25], -0.3);
            let MavMessage::SET_POSITION_TARGET_LOCAL_NED(d) = &msg else {
                panic!("wrong message {msg:?}")
            };
            assert_eq!(d.type_mask.bits(), 1479);
            assert_eq!(d.type_mask.bits(), TYPE_MASK_VELOCITY_YAW_RATE);
            assert_eq!(d.coordinate_frame as u32, number);
            assert_eq!(
                (d.target_system, d.target_component, d.time_boot_ms),
                (1, 1, 4242)
            );
            assert_eq!([d.vx, d.vy, d.vz, d.yaw_rate], [1.5, -0.5, 0.25, -0.3]);
            assert_eq!([d.x, d.y, d.z, d.afx, d.afy, d.afz, d.yaw], [0.0; 7]);
            // And it survives the wire.
            let h = Identity {
                system_id: 1,
                component_id: COMPONENT_ID_ONBOARD_COMPUTER,
            }
            .header(3);
            assert_eq!(
                FrameParser::new().push(&encode_v2(h, &msg)),
                vec![(h, msg.clone())]
            );
        }
    }

    #[test]
    fn companion_heartbeat_fields() {
        let MavMessage::HEARTBEAT(hb) = companion_heartbeat() else {
            panic!("not a heartbeat")
        };
        assert_eq!(hb.mavtype, MavType::MAV_TYPE_ONBOARD_CONTROLLER);
        assert_eq!(hb.autopilot, MavAutopilot::MAV_AUTOPILOT_INVALID);
        assert_eq!(hb.system_status, MavState::MAV_STATE_ACTIVE);
        assert_eq!(hb.mavlink_version, 3);
    }

    #[test]
    fn mode_names_and_serde() {
        assert_eq!(copter_mode_name(COPTER_MODE_GUIDED), Some("GUIDED"));
        assert_eq!(copter_mode_name(5), Some("LOITER"));
        assert_eq!(copter_mode_name(8), None);
        assert_eq!(
            serde_json::to_string(&SetpointFrame::BodyOffsetNed).unwrap(),
            "\"body_offset_ned\""
        );
        let f: SetpointFrame = serde_json::from_str("\"body_ned\"").unwrap();
        assert_eq!(f, SetpointFrame::BodyNed);
    }
}
