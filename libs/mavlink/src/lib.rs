//! MAVLink 2 link between hubtrack and an ArduPilot (ArduCopter) autopilot.
//!
//! The control process uses it as an onboard companion computer; the simulator uses it to play
//! the autopilot. Pieces:
//!
//! - [`FrameParser`]: incremental framing over arbitrary byte chunks, counting noise, bad
//!   checksums and foreign message ids in [`LinkStats`] instead of failing; [`encode_v2`].
//! - [`Link`]: UDP (`udpin`/`udpout`) or serial transport chosen by an [`Endpoint`] string.
//! - [`companion_heartbeat`], [`velocity_setpoint`]: what the companion sends.
//! - [`Signing`], [`SigningKey`]: MAVLink 2 message signing of a link.
//! - [`VehicleMonitor`]: finds the autopilot, watches its link and boot clock, and turns its
//!   messages into a [`hubtrack_types::VehicleState`].
//!
//! Only the common dialect is compiled in: ArduPilot's own messages (ids outside common) are
//! counted as unknown and skipped.

#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod interval;
mod link;
mod messages;
mod monitor;
mod parser;
mod peer;
mod signing;
mod signing_key;

/// The `mavlink` crate, with the common dialect also at `mavlink::common` (mavlink 0.21 puts it
/// at `mavlink::dialects::common`), so users write `hubtrack_mavlink::mavlink::common::MavType`.
pub mod mavlink {
    pub use ::mavlink::dialects::common;
    pub use ::mavlink::*;
}
/// The common dialect (`mavlink::dialects::common`).
pub use ::mavlink::dialects::common;
pub use ::mavlink::dialects::common::MavMessage;
pub use ::mavlink::MavHeader;

pub use interval::{set_message_interval, StreamRequests, WantedStream};
pub use link::{Endpoint, Link, LinkError};
pub use messages::{
    companion_heartbeat, copter_mode_name, velocity_setpoint, Identity, SetpointFrame,
    COMPONENT_ID_ONBOARD_COMPUTER, COPTER_MODE_GUIDED, TYPE_MASK_VELOCITY_YAW_RATE,
};
pub use monitor::{
    aged_state, follows_setpoints, VehicleEvent, VehicleMonitor, REBOOT_BACKSTEP_MS,
};
pub use parser::{encode_v2, FrameParser, LinkStats};
pub use peer::{AutopilotId, PeerLock};
pub use signing::{signing_timestamp, Refusal, Signing};
pub use signing_key::{KeyError, SigningKey, SIGNING_KEY_LEN};

#[cfg(test)]
mod test_support;

#[cfg(test)]
mod tests {
    /// Users name types as `hubtrack_mavlink::mavlink::common::...` and reach the rest of the
    /// mavlink crate through the same path.
    #[test]
    fn mavlink_facade_paths() {
        let t: crate::mavlink::common::MavType = crate::common::MavType::MAV_TYPE_GCS;
        assert_eq!(t, crate::mavlink::dialects::common::MavType::MAV_TYPE_GCS);
        assert_eq!(crate::mavlink::MAV_STX_V2, 0xFD);
        let _: fn(&[u8], u8) -> u16 = crate::mavlink::calculate_crc;
    }
}
