//! ArduCopter in GUIDED mode, as the companion computer sees it over MAVLink.
//!
//! Modelled after ArduCopter 4.x (`GCS_MAVLINK_Copter::handle_message_set_position_target_local_ned`
//! and `ModeGuided`):
//!
//! * **Modes.** GUIDED (custom_mode 4) or LOITER (5). With `start_guided` the autopilot enters
//!   GUIDED at `guided_after_s` (0 = from the start), like a pilot flipping the mode switch;
//!   before that, and in LOITER, the vehicle holds position. Any mode change, and disarming,
//!   discards the velocity target (GUIDED is entered holding position, as ArduCopter does).
//! * **Setpoints.** Only SET_POSITION_TARGET_LOCAL_NED addressed to this vehicle (target system
//!   and component equal to its ids or 0) is handled. It is rejected unless armed and in GUIDED.
//!   Frames: MAV_FRAME_LOCAL_NED (1) and MAV_FRAME_LOCAL_OFFSET_NED (7) take the velocity in NED;
//!   MAV_FRAME_BODY_NED (8) and MAV_FRAME_BODY_OFFSET_NED (9) rotate it by the current heading
//!   only (ArduCopter ignores roll and pitch here); others are rejected. The type_mask must ignore
//!   position (bits 1|2|4) and acceleration (64|128|256) and use all three velocities; bit 512
//!   (force) is irrelevant then. Yaw angle is used when bit 1024 is clear (absolute in the NED
//!   frames, relative to the current heading in the body frames), otherwise the yaw rate when
//!   bit 2048 is clear, otherwise the heading is held. A yaw angle is flown as a yaw rate
//!   proportional to the heading error ([`YAW_ANGLE_GAIN_PER_S`]).
//! * **Timeout.** Without a new accepted setpoint for `command_timeout_s` (ArduCopter:
//!   3 s) the velocity and yaw rate drop to zero (hover); a yaw *angle* target is kept.
//! * **Telemetry.** HEARTBEAT, ATTITUDE and LOCAL_POSITION_NED at their configured rates (as if
//!   the SRn_* stream parameters were set), stamped with `time_boot_ms` = simulated time since
//!   boot. MAV_CMD_SET_MESSAGE_INTERVAL (COMMAND_LONG) changes the rate of ATTITUDE or
//!   LOCAL_POSITION_NED (interval −1 stops it, 0 restores the configured rate) and is answered
//!   with COMMAND_ACK, as the firmware does; other commands are answered
//!   MAV_RESULT_UNSUPPORTED. The real firmware sends a link nothing but HEARTBEAT and STATUSTEXT
//!   until asked, which is why control asks.
//!
//! The autopilot knows the vehicle's heading from the last [`Autopilot::handle`] or
//! [`Autopilot::outgoing`] call (the simulator calls `outgoing` after every physics step), like
//! the real one knows its own attitude.

use mavlink::dialects::common::{
    MavAutopilot, MavCmd, MavMessage, MavModeFlag, MavResult, MavState, MavType, ATTITUDE_DATA,
    COMMAND_ACK_DATA, HEARTBEAT_DATA, LOCAL_POSITION_NED_DATA, MINOR_MAVLINK_VERSION,
    SET_POSITION_TARGET_LOCAL_NED_DATA,
};
use mavlink::MessageData;
use serde::{Deserialize, Serialize};

use crate::math::wrap_pi;
use crate::params::AutopilotConfig;
use crate::vehicle::{Multicopter, VelocityCommand};

/// ArduCopter custom_mode of GUIDED.
pub const COPTER_MODE_GUIDED: u32 = 4;
/// ArduCopter custom_mode of LOITER.
pub const COPTER_MODE_LOITER: u32 = 5;
/// MAV_FRAME_LOCAL_NED.
pub const FRAME_LOCAL_NED: u32 = 1;
/// MAV_FRAME_LOCAL_OFFSET_NED.
pub const FRAME_LOCAL_OFFSET_NED: u32 = 7;
/// MAV_FRAME_BODY_NED.
pub const FRAME_BODY_NED: u32 = 8;
/// MAV_FRAME_BODY_OFFSET_NED.
pub const FRAME_BODY_OFFSET_NED: u32 = 9;
/// type_mask bits ignoring x, y, z position.
pub const MASK_POSITION_IGNORE: u16 = 1 | 2 | 4;
/// type_mask bits ignoring vx, vy, vz.
pub const MASK_VELOCITY_IGNORE: u16 = 8 | 16 | 32;
/// type_mask bits ignoring the acceleration.
pub const MASK_ACCEL_IGNORE: u16 = 64 | 128 | 256;
/// type_mask bit ignoring the yaw angle.
pub const MASK_YAW_IGNORE: u16 = 1024;
/// type_mask bit ignoring the yaw rate.
pub const MASK_YAW_RATE_IGNORE: u16 = 2048;
/// type_mask of "velocity + yaw rate" (position, acceleration and yaw angle ignored).
pub const MASK_VELOCITY_YAW_RATE: u16 = MASK_POSITION_IGNORE | MASK_ACCEL_IGNORE | MASK_YAW_IGNORE;
/// Yaw-angle targets are flown with a yaw rate of this gain times the heading error, 1/s
/// (limited by the vehicle's yaw-rate limit).
pub const YAW_ANGLE_GAIN_PER_S: f64 = 2.0;

/// Counters of what the autopilot did with the companion's messages.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct AutopilotStats {
    /// Setpoints accepted.
    pub accepted: u64,
    /// Setpoints addressed to this vehicle but rejected (mode, arming, frame, type_mask, values).
    pub rejected: u64,
    /// Times a velocity target lapsed after `command_timeout_s` without a new setpoint.
    pub timeouts: u64,
    /// Messages not handled (other message types, or addressed to another vehicle).
    pub ignored: u64,
}

/// A setpoint the autopilot took over.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AcceptedSetpoint {
    /// Velocity target in NED (after the body-frame rotation), m/s.
    pub velocity_ned: [f64; 3],
    /// Yaw-rate target, rad/s, clockwise positive (when the yaw rate is used).
    pub yaw_rate: Option<f64>,
    /// Absolute heading target, rad, clockwise from north (when the yaw angle is used).
    pub yaw_rad: Option<f64>,
    /// MAV_FRAME number of the message.
    pub frame: u32,
    /// type_mask of the message.
    pub type_mask: u16,
}

/// Why a setpoint addressed to this vehicle was rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum RejectReason {
    /// Not in GUIDED (the mode it is in).
    NotGuided {
        /// Current custom_mode.
        custom_mode: u32,
    },
    /// Motors not armed.
    NotArmed,
    /// Coordinate frame other than LOCAL_NED, LOCAL_OFFSET_NED, BODY_NED, BODY_OFFSET_NED.
    UnsupportedFrame(u32),
    /// type_mask other than velocity-only (e.g. a position or acceleration target).
    UnsupportedTypeMask(u16),
    /// A used value is NaN or infinite.
    NotFinite,
}

/// Why a message was not handled at all.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum IgnoreReason {
    /// Not a SET_POSITION_TARGET_LOCAL_NED.
    NotASetpoint,
    /// Addressed to another system or component.
    OtherTarget {
        /// target_system of the message.
        target_system: u8,
        /// target_component of the message.
        target_component: u8,
    },
}

/// What [`Autopilot::handle`] did with a message.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum CommandResult {
    /// The setpoint is now in force.
    Accepted(AcceptedSetpoint),
    /// Addressed to this vehicle but refused.
    Rejected(RejectReason),
    /// Not for this vehicle's GUIDED controller.
    Ignored(IgnoreReason),
}

impl CommandResult {
    /// The setpoint was accepted.
    pub fn is_accepted(&self) -> bool {
        matches!(self, CommandResult::Accepted(_))
    }
}

impl std::fmt::Display for RejectReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RejectReason::NotGuided { custom_mode } => {
                write!(f, "not in GUIDED (custom_mode {custom_mode})")
            }
            RejectReason::NotArmed => write!(f, "not armed"),
            RejectReason::UnsupportedFrame(fr) => write!(f, "unsupported coordinate frame {fr}"),
            RejectReason::UnsupportedTypeMask(m) => {
                write!(f, "unsupported type_mask {m} (only velocity targets)")
            }
            RejectReason::NotFinite => write!(f, "non-finite value"),
        }
    }
}

impl std::fmt::Display for CommandResult {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CommandResult::Accepted(s) => write!(
                f,
                "accepted: v_ned [{:.2}, {:.2}, {:.2}] m/s, yaw_rate {:?}, yaw {:?} (frame {}, mask {})",
                s.velocity_ned[0], s.velocity_ned[1], s.velocity_ned[2], s.yaw_rate, s.yaw_rad, s.frame, s.type_mask
            ),
            CommandResult::Rejected(r) => write!(f, "rejected: {r}"),
            CommandResult::Ignored(IgnoreReason::NotASetpoint) => write!(f, "ignored: not a setpoint"),
            CommandResult::Ignored(IgnoreReason::OtherTarget { target_system, target_component }) => {
                write!(f, "ignored: addressed to {target_system}/{target_component}")
            }
        }
    }
}

#[derive(Debug, Clone, Copy)]
struct Active {
    velocity_ned: [f64; 3],
    yaw_rate: Option<f64>,
    received_s: f64,
    lapsed: bool,
}

/// The simulated ArduCopter.
#[derive(Debug, Clone)]
pub struct Autopilot {
    cfg: AutopilotConfig,
    armed: bool,
    guided: bool,
    /// Pilot's switch to GUIDED still to come at this time.
    guided_at: Option<f64>,
    active: Option<Active>,
    /// Heading target from a yaw-angle setpoint (kept after a velocity timeout).
    yaw_target: Option<f64>,
    /// The vehicle's heading as last seen.
    vehicle_yaw: Option<f64>,
    next_heartbeat: f64,
    next_attitude: f64,
    next_position: f64,
    /// ATTITUDE and LOCAL_POSITION_NED rates now, Hz (0 = stopped).
    attitude_hz: f64,
    position_hz: f64,
    /// Answers to commands, sent with the next [`Autopilot::outgoing`].
    acks: Vec<MavMessage>,
    stats: AutopilotStats,
}

impl Autopilot {
    /// An autopilot in the configured start state (armed, LOITER/GUIDED).
    pub fn new(cfg: &AutopilotConfig) -> Autopilot {
        let immediate = cfg.start_guided && cfg.guided_after_s <= 0.0;
        Autopilot {
            cfg: cfg.clone(),
            armed: cfg.start_armed,
            guided: immediate,
            guided_at: if cfg.start_guided && !immediate {
                Some(cfg.guided_after_s)
            } else {
                None
            },
            active: None,
            yaw_target: None,
            vehicle_yaw: None,
            next_heartbeat: 0.0,
            next_attitude: 0.0,
            next_position: 0.0,
            attitude_hz: cfg.attitude_hz,
            position_hz: cfg.position_hz,
            acks: Vec::new(),
            stats: AutopilotStats::default(),
        }
    }

    fn update_mode(&mut self, now_s: f64) {
        if let Some(t) = self.guided_at {
            if now_s >= t {
                log::info!("autopilot: pilot switched to GUIDED at {now_s:.2} s");
                self.guided_at = None;
                self.enter_mode(true);
            }
        }
    }

    fn enter_mode(&mut self, guided: bool) {
        if guided != self.guided {
            self.active = None;
            self.yaw_target = None;
        }
        self.guided = guided;
    }

    /// Handle a message from the companion received at `now_s` (simulated time since boot);
    /// `vehicle` gives the current heading for body-frame setpoints.
    pub fn handle(
        &mut self,
        now_s: f64,
        header: &mavlink::MavHeader,
        msg: &MavMessage,
        vehicle: &Multicopter,
    ) -> CommandResult {
        self.update_mode(now_s);
        let yaw_now = vehicle.attitude()[2];
        self.vehicle_yaw = Some(yaw_now);
        let result = self.handle_inner(now_s, msg, yaw_now);
        match &result {
            CommandResult::Accepted(_) => self.stats.accepted += 1,
            CommandResult::Rejected(r) => {
                self.stats.rejected += 1;
                log::debug!(
                    "autopilot: setpoint from {}/{} rejected: {r}",
                    header.system_id,
                    header.component_id
                );
            }
            CommandResult::Ignored(_) => self.stats.ignored += 1,
        }
        result
    }

    /// A COMMAND_LONG for this vehicle: MAV_CMD_SET_MESSAGE_INTERVAL for ATTITUDE or
    /// LOCAL_POSITION_NED is applied; every command is answered with COMMAND_ACK.
    fn command_long(&mut self, c: &mavlink::dialects::common::COMMAND_LONG_DATA) {
        let (sys, comp) = self.identity();
        let for_us = |target: u8, own: u8| target == 0 || target == own;
        if !(for_us(c.target_system, sys) && for_us(c.target_component, comp)) {
            return;
        }
        let result = if c.command == MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL {
            let rate = |configured: f64| match c.param2 {
                i if i < 0.0 => Some(0.0),
                0.0 => Some(configured),
                i if i.is_finite() => Some(1e6 / f64::from(i)),
                _ => None,
            };
            let id = c.param1;
            if id == ATTITUDE_DATA::ID as f32 {
                rate(self.cfg.attitude_hz).map(|r| self.attitude_hz = r)
            } else if id == LOCAL_POSITION_NED_DATA::ID as f32 {
                rate(self.cfg.position_hz).map(|r| self.position_hz = r)
            } else {
                None
            }
            .map_or(MavResult::MAV_RESULT_FAILED, |()| {
                MavResult::MAV_RESULT_ACCEPTED
            })
        } else {
            MavResult::MAV_RESULT_UNSUPPORTED
        };
        self.acks.push(MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
            command: c.command,
            result,
        }));
    }

    fn handle_inner(&mut self, now_s: f64, msg: &MavMessage, yaw_now: f64) -> CommandResult {
        if let MavMessage::COMMAND_LONG(c) = msg {
            self.command_long(c);
            return CommandResult::Ignored(IgnoreReason::NotASetpoint);
        }
        let MavMessage::SET_POSITION_TARGET_LOCAL_NED(d) = msg else {
            return CommandResult::Ignored(IgnoreReason::NotASetpoint);
        };
        let SET_POSITION_TARGET_LOCAL_NED_DATA {
            target_system,
            target_component,
            ..
        } = *d;
        let for_us = (target_system == 0 || target_system == self.cfg.system_id)
            && (target_component == 0 || target_component == self.cfg.component_id);
        if !for_us {
            return CommandResult::Ignored(IgnoreReason::OtherTarget {
                target_system,
                target_component,
            });
        }
        if !self.guided {
            return CommandResult::Rejected(RejectReason::NotGuided {
                custom_mode: self.custom_mode(),
            });
        }
        if !self.armed {
            return CommandResult::Rejected(RejectReason::NotArmed);
        }
        let frame = d.coordinate_frame as u32;
        let body = match frame {
            FRAME_LOCAL_NED | FRAME_LOCAL_OFFSET_NED => false,
            FRAME_BODY_NED | FRAME_BODY_OFFSET_NED => true,
            _ => return CommandResult::Rejected(RejectReason::UnsupportedFrame(frame)),
        };
        let mask = d.type_mask.bits();
        let velocity_only = mask & MASK_POSITION_IGNORE == MASK_POSITION_IGNORE
            && mask & MASK_VELOCITY_IGNORE == 0
            && mask & MASK_ACCEL_IGNORE == MASK_ACCEL_IGNORE;
        if !velocity_only {
            return CommandResult::Rejected(RejectReason::UnsupportedTypeMask(mask));
        }
        let use_yaw = mask & MASK_YAW_IGNORE == 0;
        let use_yaw_rate = !use_yaw && mask & MASK_YAW_RATE_IGNORE == 0;
        let v = [d.vx as f64, d.vy as f64, d.vz as f64];
        if v.iter().any(|x| !x.is_finite())
            || (use_yaw && !d.yaw.is_finite())
            || (use_yaw_rate && !d.yaw_rate.is_finite())
        {
            return CommandResult::Rejected(RejectReason::NotFinite);
        }
        let velocity_ned = if body {
            // Heading only: x forward along the heading, y to the right, z down.
            let (s, c) = yaw_now.sin_cos();
            [c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]]
        } else {
            v
        };
        let yaw_rad = use_yaw.then(|| wrap_pi(d.yaw as f64 + if body { yaw_now } else { 0.0 }));
        let yaw_rate = use_yaw_rate.then_some(d.yaw_rate as f64);
        // A new setpoint without a yaw angle releases a previous heading target.
        self.yaw_target = yaw_rad;
        self.active = Some(Active {
            velocity_ned,
            yaw_rate,
            received_s: now_s,
            lapsed: false,
        });
        CommandResult::Accepted(AcceptedSetpoint {
            velocity_ned,
            yaw_rate,
            yaw_rad,
            frame,
            type_mask: mask,
        })
    }

    /// The velocity command in force at `now_s`: the last accepted setpoint, hover after
    /// `command_timeout_s` without a new one, or hover when not GUIDED and armed.
    pub fn command(&mut self, now_s: f64) -> VelocityCommand {
        self.update_mode(now_s);
        if !(self.guided && self.armed) {
            self.active = None;
            self.yaw_target = None;
            return VelocityCommand::HOVER;
        }
        let mut cmd = VelocityCommand::HOVER;
        if let Some(a) = self.active.as_mut() {
            if now_s - a.received_s > self.cfg.command_timeout_s {
                if !a.lapsed {
                    a.lapsed = true;
                    self.stats.timeouts += 1;
                    log::info!(
                        "autopilot: no setpoint for {:.1} s, stopping (timeout {:.1} s)",
                        now_s - a.received_s,
                        self.cfg.command_timeout_s
                    );
                }
            } else {
                cmd.velocity_ned = a.velocity_ned;
                cmd.yaw_rate = a.yaw_rate.unwrap_or(0.0);
            }
        }
        if let (Some(target), Some(yaw)) = (self.yaw_target, self.vehicle_yaw) {
            cmd.yaw_rate = YAW_ANGLE_GAIN_PER_S * wrap_pi(target - yaw);
        }
        cmd
    }

    /// Messages due at `now_s`: HEARTBEAT, ATTITUDE and LOCAL_POSITION_NED at their rates
    /// (`time_boot_ms` = `now_s`·1000). Call after every physics step. All three are due at 0;
    /// a stream whose slot was missed (long gap between calls) sends once and resynchronises.
    pub fn outgoing(&mut self, now_s: f64, vehicle: &Multicopter) -> Vec<MavMessage> {
        self.update_mode(now_s);
        let [roll, pitch, yaw] = vehicle.attitude();
        self.vehicle_yaw = Some(yaw);
        let time_boot_ms = (now_s.max(0.0) * 1000.0).round() as u32;
        let mut out = std::mem::take(&mut self.acks);
        if due(&mut self.next_heartbeat, now_s, self.cfg.heartbeat_hz) {
            out.push(self.heartbeat());
        }
        if self.attitude_hz > 0.0 && due(&mut self.next_attitude, now_s, self.attitude_hz) {
            let [p, q, r] = vehicle.body_rates();
            out.push(MavMessage::ATTITUDE(ATTITUDE_DATA {
                time_boot_ms,
                roll: roll as f32,
                pitch: pitch as f32,
                yaw: yaw as f32,
                rollspeed: p as f32,
                pitchspeed: q as f32,
                yawspeed: r as f32,
            }));
        }
        if self.position_hz > 0.0 && due(&mut self.next_position, now_s, self.position_hz) {
            let p = vehicle.position_ned();
            let v = vehicle.velocity_ned();
            out.push(MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
                time_boot_ms,
                x: p[0] as f32,
                y: p[1] as f32,
                z: p[2] as f32,
                vx: v[0] as f32,
                vy: v[1] as f32,
                vz: v[2] as f32,
            }));
        }
        out
    }

    /// The HEARTBEAT of the current state.
    pub fn heartbeat(&self) -> MavMessage {
        let mut base_mode = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED;
        if self.armed {
            base_mode |= MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED;
        }
        MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: self.custom_mode(),
            mavtype: MavType::MAV_TYPE_QUADROTOR,
            autopilot: MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA,
            base_mode,
            // ArduCopter reports STANDBY while disarmed.
            system_status: if self.armed {
                MavState::MAV_STATE_ACTIVE
            } else {
                MavState::MAV_STATE_STANDBY
            },
            mavlink_version: MINOR_MAVLINK_VERSION,
        })
    }

    /// Current ArduCopter custom_mode (4 = GUIDED, 5 = LOITER).
    pub fn custom_mode(&self) -> u32 {
        if self.guided {
            COPTER_MODE_GUIDED
        } else {
            COPTER_MODE_LOITER
        }
    }

    /// Counters of accepted / rejected / ignored setpoints and timeouts.
    pub fn stats(&self) -> AutopilotStats {
        self.stats
    }

    /// (system id, component id) the autopilot sends with and answers to.
    pub fn identity(&self) -> (u8, u8) {
        (self.cfg.system_id, self.cfg.component_id)
    }

    /// Switch GUIDED on (or back to LOITER); cancels a pending pilot switch and discards the
    /// velocity target.
    pub fn set_guided(&mut self, on: bool) {
        self.guided_at = None;
        self.enter_mode(on);
    }

    /// Arm or disarm (disarming discards the velocity target; the simulated vehicle keeps hovering).
    pub fn set_armed(&mut self, on: bool) {
        if !on {
            self.active = None;
            self.yaw_target = None;
        }
        self.armed = on;
    }

    /// In GUIDED now.
    pub fn is_guided(&self) -> bool {
        self.guided
    }

    /// Armed now.
    pub fn is_armed(&self) -> bool {
        self.armed
    }
}

/// Whether a stream at `hz` is due at `now_s`; advances `next` to the following slot on the
/// grid `k / hz`, so there is no drift and a missed slot is not sent twice.
fn due(next: &mut f64, now_s: f64, hz: f64) -> bool {
    // Tolerance for simulated times accumulated from many small steps.
    const EPS: f64 = 1e-9;
    if now_s + EPS < *next {
        return false;
    }
    let period = 1.0 / hz;
    *next = ((now_s + EPS) / period).floor().max(0.0) * period + period;
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::{VehicleConfig, WindConfig};
    use crate::vehicle::VehicleStart;
    use crate::wind::Wind;
    use mavlink::dialects::common::{MavFrame, PositionTargetTypemask};
    use std::f64::consts::FRAC_PI_2;

    fn header() -> mavlink::MavHeader {
        mavlink::MavHeader {
            system_id: 255,
            component_id: 190,
            sequence: 0,
        }
    }

    fn vehicle(yaw: f64) -> Multicopter {
        Multicopter::new(
            &VehicleStart {
                position_ned: [0.0, 0.0, -70.0],
                velocity_ned: [0.0; 3],
                yaw_rad: yaw,
            },
            &VehicleConfig::default(),
        )
    }

    fn setpoint(frame: MavFrame, mask: u16, v: [f32; 3], yaw: f32, yaw_rate: f32) -> MavMessage {
        MavMessage::SET_POSITION_TARGET_LOCAL_NED(SET_POSITION_TARGET_LOCAL_NED_DATA {
            time_boot_ms: 0,
            x: 0.0,
            y: 0.0,
            z: 0.0,
            vx: v[0],
            vy: v[1],
            vz: v[2],
            afx: 0.0,
            afy: 0.0,
            afz: 0.0,
            yaw,
            yaw_rate,
            type_mask: PositionTargetTypemask::from_bits_retain(mask),
            target_system: 1,
            target_component: 1,
            coordinate_frame: frame,
        })
    }

    #[allow(deprecated)]
    const BODY_NED: MavFrame = MavFrame::MAV_FRAME_BODY_NED;

    #[test]
    fn heartbeat_content_and_stream_rates() {
        let mut ap = Autopilot::new(&AutopilotConfig::default());
        let v = vehicle(0.0);
        let (mut hb, mut att, mut pos) = (Vec::new(), 0, 0);
        let dt = 0.005;
        for k in 0..2000 {
            let t = k as f64 * dt;
            for m in ap.outgoing(t, &v) {
                match m {
                    MavMessage::HEARTBEAT(h) => hb.push((t, h)),
                    MavMessage::ATTITUDE(a) => {
                        att += 1;
                        assert_eq!(a.time_boot_ms, (t * 1000.0).round() as u32);
                    }
                    MavMessage::LOCAL_POSITION_NED(p) => {
                        pos += 1;
                        assert_eq!(p.z, -70.0);
                    }
                    other => panic!("unexpected {other:?}"),
                }
            }
        }
        // 10 s: heartbeats at 0..9 s, 25 Hz attitude, 10 Hz position.
        assert_eq!(hb.len(), 10);
        assert_eq!(att, 250);
        assert_eq!(pos, 100);
        for (i, (t, _)) in hb.iter().enumerate() {
            assert!((t - i as f64).abs() < 1e-6);
        }
        let h = &hb[0].1;
        assert_eq!(h.custom_mode, COPTER_MODE_GUIDED);
        assert_eq!(h.mavtype, MavType::MAV_TYPE_QUADROTOR);
        assert_eq!(h.autopilot, MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA);
        assert_eq!(
            h.base_mode,
            MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
                | MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED
        );
        assert_eq!(h.system_status, MavState::MAV_STATE_ACTIVE);
        assert_eq!(h.mavlink_version, 3);

        ap.set_armed(false);
        ap.set_guided(false);
        let MavMessage::HEARTBEAT(h) = ap.heartbeat() else {
            unreachable!()
        };
        assert_eq!(h.custom_mode, COPTER_MODE_LOITER);
        assert_eq!(h.base_mode, MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED);
    }

    #[test]
    fn attitude_message_carries_the_vehicle_state() {
        let mut ap = Autopilot::new(&AutopilotConfig::default());
        let mut v = vehicle(0.0);
        v.set_attitude(0.1, -0.2, 3.0);
        let msgs = ap.outgoing(1.5, &v);
        let att = msgs
            .iter()
            .find_map(|m| {
                if let MavMessage::ATTITUDE(a) = m {
                    Some(a.clone())
                } else {
                    None
                }
            })
            .unwrap();
        assert_eq!((att.roll, att.pitch, att.yaw), (0.1, -0.2, 3.0));
        assert_eq!(att.time_boot_ms, 1500);
    }

    #[test]
    fn setpoints_need_guided_and_armed() {
        let v = vehicle(0.0);
        let sp = setpoint(
            MavFrame::MAV_FRAME_LOCAL_NED,
            MASK_VELOCITY_YAW_RATE,
            [1.0, 0.0, 0.0],
            0.0,
            0.0,
        );
        let mut ap = Autopilot::new(&AutopilotConfig {
            start_guided: false,
            ..Default::default()
        });
        assert_eq!(
            ap.handle(0.0, &header(), &sp, &v),
            CommandResult::Rejected(RejectReason::NotGuided {
                custom_mode: COPTER_MODE_LOITER
            })
        );
        assert_eq!(ap.command(0.1), VelocityCommand::HOVER);

        let mut ap = Autopilot::new(&AutopilotConfig {
            start_armed: false,
            ..Default::default()
        });
        assert_eq!(
            ap.handle(0.0, &header(), &sp, &v),
            CommandResult::Rejected(RejectReason::NotArmed)
        );
        assert_eq!(ap.command(0.1), VelocityCommand::HOVER);
        ap.set_armed(true);
        assert!(ap.handle(0.2, &header(), &sp, &v).is_accepted());
        assert_eq!(ap.command(0.3).velocity_ned, [1.0, 0.0, 0.0]);
        // Leaving GUIDED discards the target; coming back holds position.
        ap.set_guided(false);
        assert_eq!(ap.command(0.4), VelocityCommand::HOVER);
        ap.set_guided(true);
        assert_eq!(ap.command(0.5), VelocityCommand::HOVER);
        assert_eq!(
            ap.stats(),
            AutopilotStats {
                accepted: 1,
                rejected: 1,
                timeouts: 0,
                ignored: 0
            }
        );
    }

    #[test]
    fn messages_for_others_are_ignored() {
        let v = vehicle(0.0);
        let mut ap = Autopilot::new(&AutopilotConfig::default());
        let MavMessage::SET_POSITION_TARGET_LOCAL_NED(mut d) = setpoint(
            MavFrame::MAV_FRAME_LOCAL_NED,
            MASK_VELOCITY_YAW_RATE,
            [1.0, 0.0, 0.0],
            0.0,
            0.0,
        ) else {
            unreachable!()
        };
        d.target_system = 2;
        let r = ap.handle(
            0.0,
            &header(),
            &MavMessage::SET_POSITION_TARGET_LOCAL_NED(d.clone()),
            &v,
        );
        assert_eq!(
            r,
            CommandResult::Ignored(IgnoreReason::OtherTarget {
                target_system: 2,
                target_component: 1
            })
        );
        // Broadcast is for us.
        d.target_system = 0;
        d.target_component = 0;
        assert!(ap
            .handle(
                0.0,
                &header(),
                &MavMessage::SET_POSITION_TARGET_LOCAL_NED(d),
                &v
            )
            .is_accepted());
        let hb = ap.heartbeat();
        assert_eq!(
            ap.handle(0.0, &header(), &hb, &v),
            CommandResult::Ignored(IgnoreReason::NotASetpoint)
        );
        assert_eq!(ap.stats().ignored, 2);
    }

    #[test]
    fn mask_1479_is_velocity_and_yaw_rate() {
        assert_eq!(MASK_VELOCITY_YAW_RATE, 1479);
        let v = vehicle(0.0);
        let mut ap = Autopilot::new(&AutopilotConfig::default());
        let r = ap.handle(
            0.0,
            &header(),
            &setpoint(
                MavFrame::MAV_FRAME_LOCAL_NED,
                1479,
                [0.5, -1.0, 0.2],
                0.7,
                0.3,
            ),
            &v,
        );
        let CommandResult::Accepted(a) = r else {
            panic!("{r:?}")
        };
        assert_eq!(a.yaw_rate, Some(0.3f32 as f64));
        assert_eq!(a.yaw_rad, None);
        let c = ap.command(0.05);
        assert_eq!(c.velocity_ned, [0.5, -1.0, 0.2f32 as f64]);
        assert_eq!(c.yaw_rate, 0.3f32 as f64);
        // Force bit set as well: still a velocity target.
        assert!(ap
            .handle(
                0.1,
                &header(),
                &setpoint(
                    MavFrame::MAV_FRAME_LOCAL_OFFSET_NED,
                    1479 | 512,
                    [0.0; 3],
                    0.0,
                    0.0
                ),
                &v
            )
            .is_accepted());
    }

    #[test]
    fn position_and_other_masks_and_frames_are_rejected() {
        let v = vehicle(0.0);
        let mut ap = Autopilot::new(&AutopilotConfig::default());
        // Position only (velocity, acceleration, yaw rate ignored): 0b1101_1111_1000 = 3576.
        let pos_mask =
            MASK_VELOCITY_IGNORE | MASK_ACCEL_IGNORE | MASK_YAW_RATE_IGNORE | MASK_YAW_IGNORE;
        let r = ap.handle(
            0.0,
            &header(),
            &setpoint(MavFrame::MAV_FRAME_LOCAL_NED, pos_mask, [0.0; 3], 0.0, 0.0),
            &v,
        );
        assert_eq!(
            r,
            CommandResult::Rejected(RejectReason::UnsupportedTypeMask(pos_mask))
        );
        // Velocity with acceleration.
        let r = ap.handle(
            0.0,
            &header(),
            &setpoint(
                MavFrame::MAV_FRAME_LOCAL_NED,
                MASK_POSITION_IGNORE | MASK_YAW_IGNORE,
                [0.0; 3],
                0.0,
                0.0,
            ),
            &v,
        );
        assert!(matches!(
            r,
            CommandResult::Rejected(RejectReason::UnsupportedTypeMask(_))
        ));
        // Velocity with vz ignored.
        let r = ap.handle(
            0.0,
            &header(),
            &setpoint(MavFrame::MAV_FRAME_LOCAL_NED, 1479 | 32, [0.0; 3], 0.0, 0.0),
            &v,
        );
        assert!(matches!(
            r,
            CommandResult::Rejected(RejectReason::UnsupportedTypeMask(_))
        ));
        // Global frame.
        let r = ap.handle(
            0.0,
            &header(),
            &setpoint(
                MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT,
                1479,
                [0.0; 3],
                0.0,
                0.0,
            ),
            &v,
        );
        assert_eq!(
            r,
            CommandResult::Rejected(RejectReason::UnsupportedFrame(3))
        );
        // NaN.
        let r = ap.handle(
            0.0,
            &header(),
            &setpoint(
                MavFrame::MAV_FRAME_LOCAL_NED,
                1479,
                [f32::NAN, 0.0, 0.0],
                0.0,
                0.0,
            ),
            &v,
        );
        assert_eq!(r, CommandResult::Rejected(RejectReason::NotFinite));
        assert_eq!(ap.stats().rejected, 5);
        assert_eq!(ap.stats().accepted, 0);
        assert_eq!(ap.command(0.1), VelocityCommand::HOVER);
    }

    #[test]
    fn body_frame_is_rotated_by_the_heading() {
        // Heading east: body forward is NED east, body right is NED south.
        let v = vehicle(FRAC_PI_2);
        let mut ap = Autopilot::new(&AutopilotConfig::default());
        assert!(ap
            .handle(
                0.0,
                &header(),
                &setpoint(BODY_NED, 1479, [2.0, 0.0, 0.5], 0.0, 0.0),
                &v
            )
            .is_accepted());
        let c = ap.command(0.01).velocity_ned;
        assert!(
            c[0].abs() < 1e-6 && (c[1] - 2.0).abs() < 1e-6 && (c[2] - 0.5).abs() < 1e-9,
            "{c:?}"
        );
        #[allow(deprecated)]
        let body_offset = MavFrame::MAV_FRAME_BODY_OFFSET_NED;
        assert!(ap
            .handle(
                0.1,
                &header(),
                &setpoint(body_offset, 1479, [0.0, 1.0, 0.0], 0.0, 0.0),
                &v
            )
            .is_accepted());
        let c = ap.command(0.11).velocity_ned;
        assert!((c[0] + 1.0).abs() < 1e-6 && c[1].abs() < 1e-6, "{c:?}");
        // The NED frame is not rotated.
        assert!(ap
            .handle(
                0.2,
                &header(),
                &setpoint(
                    MavFrame::MAV_FRAME_LOCAL_NED,
                    1479,
                    [2.0, 0.0, 0.0],
                    0.0,
                    0.0
                ),
                &v
            )
            .is_accepted());
        assert_eq!(ap.command(0.21).velocity_ned, [2.0, 0.0, 0.0]);
    }

    #[test]
    fn body_frame_command_flies_east_when_heading_east() {
        let mut v = vehicle(FRAC_PI_2);
        let mut w = Wind::new(
            1,
            &WindConfig {
                mean_speed_m_s: [0.0, 0.0],
                gust_sigma_m_s: 0.0,
                gust_tau_s: 1.0,
            },
        );
        let mut ap = Autopilot::new(&AutopilotConfig::default());
        let dt = 0.005;
        for k in 0..1000 {
            let t = k as f64 * dt;
            if k % 20 == 0 {
                ap.handle(
                    t,
                    &header(),
                    &setpoint(BODY_NED, 1479, [1.0, 0.0, 0.0], 0.0, 0.0),
                    &v,
                );
            }
            let c = ap.command(t);
            v.step(dt, &c, &mut w);
            ap.outgoing(t + dt, &v);
        }
        let vel = v.velocity_ned();
        assert!(
            (vel[1] - 1.0).abs() < 0.01 && vel[0].abs() < 1e-6,
            "{vel:?}"
        );
    }

    #[test]
    fn yaw_angle_target_is_flown_and_relative_in_body_frames() {
        let mut v = vehicle(0.0);
        let mut w = Wind::new(
            1,
            &WindConfig {
                mean_speed_m_s: [0.0, 0.0],
                gust_sigma_m_s: 0.0,
                gust_tau_s: 1.0,
            },
        );
        let mut ap = Autopilot::new(&AutopilotConfig::default());
        // Yaw used (bit 1024 clear), yaw rate ignored: 1479 - 1024 + 2048.
        let mask = MASK_POSITION_IGNORE | MASK_ACCEL_IGNORE | MASK_YAW_RATE_IGNORE;
        let r = ap.handle(
            0.0,
            &header(),
            &setpoint(MavFrame::MAV_FRAME_LOCAL_NED, mask, [0.0; 3], -2.5, 0.0),
            &v,
        );
        let CommandResult::Accepted(a) = r else {
            panic!()
        };
        assert_eq!(a.yaw_rad, Some(-2.5f32 as f64));
        let dt = 0.005;
        // The target persists after the velocity timeout.
        for k in 0..2000 {
            let t = k as f64 * dt;
            let c = ap.command(t);
            v.step(dt, &c, &mut w);
            ap.outgoing(t + dt, &v);
        }
        assert!((v.attitude()[2] + 2.5).abs() < 0.01, "{:?}", v.attitude());
        assert_eq!(ap.stats().timeouts, 1);
        // Relative in the body frame: +0.5 rad from the current heading.
        let r = ap.handle(
            10.0,
            &header(),
            &setpoint(BODY_NED, mask, [0.0; 3], 0.5, 0.0),
            &v,
        );
        let CommandResult::Accepted(a) = r else {
            panic!()
        };
        assert!((a.yaw_rad.unwrap() - wrap_pi(v.attitude()[2] + 0.5)).abs() < 1e-6);
    }

    #[test]
    fn timeout_returns_to_hover() {
        let v = vehicle(0.0);
        let mut ap = Autopilot::new(&AutopilotConfig::default());
        assert!(ap
            .handle(
                1.0,
                &header(),
                &setpoint(
                    MavFrame::MAV_FRAME_LOCAL_NED,
                    1479,
                    [1.0, 0.0, 0.0],
                    0.0,
                    0.2
                ),
                &v
            )
            .is_accepted());
        assert_eq!(ap.command(3.9).velocity_ned, [1.0, 0.0, 0.0]);
        assert_eq!(ap.command(4.0).yaw_rate, 0.2f32 as f64);
        assert_eq!(ap.command(4.01), VelocityCommand::HOVER);
        assert_eq!(ap.command(5.0), VelocityCommand::HOVER);
        assert_eq!(ap.stats().timeouts, 1);
        // A new setpoint revives it.
        assert!(ap
            .handle(
                5.0,
                &header(),
                &setpoint(
                    MavFrame::MAV_FRAME_LOCAL_NED,
                    1479,
                    [0.0, 1.0, 0.0],
                    0.0,
                    0.0
                ),
                &v
            )
            .is_accepted());
        assert_eq!(ap.command(5.1).velocity_ned, [0.0, 1.0, 0.0]);
        assert_eq!(ap.command(9.0), VelocityCommand::HOVER);
        assert_eq!(ap.stats().timeouts, 2);
    }

    #[test]
    fn set_message_interval_is_acknowledged_and_applied() {
        use mavlink::dialects::common::COMMAND_LONG_DATA;
        let mut ap = Autopilot::new(&AutopilotConfig::default());
        let v = vehicle(0.0);
        let request = |id: u32, interval_us: f32, command| {
            MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
                param1: id as f32,
                param2: interval_us,
                command,
                target_system: 1,
                target_component: 1,
                ..Default::default()
            })
        };
        let count = |ap: &mut Autopilot, from: f64| {
            let mut n = 0;
            let mut acks = Vec::new();
            for i in 0..1000 {
                for m in ap.outgoing(from + i as f64 * 0.001, &v) {
                    match m {
                        MavMessage::ATTITUDE(_) => n += 1,
                        MavMessage::COMMAND_ACK(a) => acks.push((a.command, a.result)),
                        _ => {}
                    }
                }
            }
            (n, acks)
        };
        // ATTITUDE (id 30) at 50 Hz: 20 000 µs.
        ap.handle(
            0.0,
            &header(),
            &request(30, 20_000.0, MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL),
            &v,
        );
        let (n, acks) = count(&mut ap, 0.0);
        assert_eq!(n, 50);
        assert_eq!(
            acks,
            vec![(
                MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
                MavResult::MAV_RESULT_ACCEPTED
            )]
        );
        // −1 stops it; an id it cannot stream fails; another command is unsupported.
        ap.handle(
            1.0,
            &header(),
            &request(30, -1.0, MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL),
            &v,
        );
        ap.handle(
            1.0,
            &header(),
            &request(999, 1000.0, MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL),
            &v,
        );
        ap.handle(
            1.0,
            &header(),
            &request(0, 0.0, MavCmd::MAV_CMD_NAV_TAKEOFF),
            &v,
        );
        let (n, acks) = count(&mut ap, 1.0);
        assert_eq!(n, 0);
        assert_eq!(
            acks.iter().map(|a| a.1).collect::<Vec<_>>(),
            vec![
                MavResult::MAV_RESULT_ACCEPTED,
                MavResult::MAV_RESULT_FAILED,
                MavResult::MAV_RESULT_UNSUPPORTED
            ]
        );
    }

    #[test]
    fn pilot_switches_to_guided_after_the_configured_time() {
        let v = vehicle(0.0);
        let mut ap = Autopilot::new(&AutopilotConfig {
            guided_after_s: 5.0,
            ..Default::default()
        });
        assert!(!ap.is_guided());
        assert!(ap.is_armed());
        let hb = |msgs: Vec<MavMessage>| {
            msgs.into_iter().find_map(|m| {
                if let MavMessage::HEARTBEAT(h) = m {
                    Some(h.custom_mode)
                } else {
                    None
                }
            })
        };
        assert_eq!(hb(ap.outgoing(0.0, &v)), Some(COPTER_MODE_LOITER));
        let sp = setpoint(
            MavFrame::MAV_FRAME_LOCAL_NED,
            1479,
            [1.0, 0.0, 0.0],
            0.0,
            0.0,
        );
        assert!(!ap.handle(4.9, &header(), &sp, &v).is_accepted());
        assert!(ap.handle(5.0, &header(), &sp, &v).is_accepted());
        assert!(ap.is_guided());
        assert_eq!(hb(ap.outgoing(5.0, &v)), Some(COPTER_MODE_GUIDED));
        assert_eq!(ap.command(5.1).velocity_ned, [1.0, 0.0, 0.0]);
        // A script's set_guided cancels the pending switch.
        let mut ap = Autopilot::new(&AutopilotConfig {
            guided_after_s: 5.0,
            ..Default::default()
        });
        ap.set_guided(false);
        ap.command(6.0);
        assert!(!ap.is_guided());
        // start_guided = false never switches by itself.
        let mut ap = Autopilot::new(&AutopilotConfig {
            start_guided: false,
            ..Default::default()
        });
        ap.command(100.0);
        assert!(!ap.is_guided());
        assert_eq!(ap.identity(), (1, 1));
    }
}
