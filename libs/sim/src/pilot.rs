//! The pilot of a flight with the real firmware: from the ground to the scenario's start pose
//! through ArduCopter's own sequence, then hands the vehicle over to the pipeline.
//!
//! A sans-IO state machine, like a ground station's script: the caller feeds it the autopilot's
//! MAVLink messages ([`Pilot::handle`]) and the vehicle's true state on every step
//! ([`Pilot::poll`]), and sends the messages it returns. The sequence is what an operator does:
//!
//! 1. wait for the autopilot's HEARTBEAT;
//! 2. GUIDED (MAV_CMD_DO_SET_MODE), repeated until the HEARTBEAT shows it;
//! 3. arm (MAV_CMD_COMPONENT_ARM_DISARM), repeated while the pre-arm checks refuse (the EKF
//!    needs GPS first: about 40 s after boot);
//! 4. MAV_CMD_NAV_TAKEOFF to the start height, then wait for the climb;
//! 5. hold the start position and turn to the start heading (SET_POSITION_TARGET_LOCAL_NED,
//!    position + yaw) until the vehicle has settled there;
//! 6. [`PilotPhase::Ready`]: send nothing more; control takes over.
//!
//! The autopilot's local frame has its origin where it armed (home), which is the simulator's
//! origin: the ground below the start.

use hubtrack_types::params;
use mavlink::dialects::common::{
    MavCmd, MavFrame, MavMessage, MavModeFlag, MavResult, PositionTargetTypemask,
    COMMAND_LONG_DATA, HEARTBEAT_DATA, SET_POSITION_TARGET_LOCAL_NED_DATA,
};
use mavlink::MavHeader;

use crate::math::wrap_pi;

/// ArduCopter custom_mode of GUIDED.
const GUIDED: u32 = 4;
/// type_mask: position and yaw only (ignore velocity, acceleration and yaw rate).
const TYPE_MASK_POSITION_YAW: u16 = 0b0000_1001_1111_1000;

params! {
    /// `[sim.pilot]`: how the pilot takes a vehicle flown by ArduCopter SITL to the start pose.
    pub struct PilotConfig {
        /// Between two tries of a command the autopilot has not acted on yet, s, (0, 60].
        pub retry_s: f64 = 1.0, open_closed(0.0, 60.0);
        /// Longest time from boot to the start pose before the flight is given up, s (simulated),
        /// (0, 3600].
        pub deadline_s: f64 = 300.0, open_closed(0.0, 3600.0);
        /// At the start pose: largest position error, m, (0, 10] (gusts move a vehicle holding
        /// position by tens of centimetres).
        pub position_tolerance_m: f64 = 1.0, open_closed(0.0, 10.0);
        /// At the start pose: largest heading error, degrees, (0, 30].
        pub yaw_tolerance_deg: f64 = 2.0, open_closed(0.0, 30.0);
        /// At the start pose: largest speed, m/s, (0, 2].
        pub speed_tolerance_m_s: f64 = 0.5, open_closed(0.0, 2.0);
        /// How long the vehicle must stay within those tolerances before the hand-over, s, [0, 60].
        pub settle_s: f64 = 2.0, closed(0.0, 60.0);
    }
}

/// Where the pilot is in the sequence.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PilotPhase {
    /// No autopilot HEARTBEAT yet.
    WaitAutopilot,
    /// Asking for GUIDED.
    Guided,
    /// Asking to arm.
    Arm,
    /// Asking to take off.
    Takeoff,
    /// Climbing.
    Climb,
    /// Moving to the start position and heading.
    Position,
    /// At the start pose: the pipeline has the vehicle.
    Ready,
    /// The sequence did not finish by the deadline.
    Failed,
}

/// The vehicle's true state as the pilot checks it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PilotView {
    /// Position, NED, m.
    pub position_ned: [f64; 3],
    /// Speed, m/s.
    pub speed_m_s: f64,
    /// Heading, rad.
    pub yaw_rad: f64,
}

/// The pilot (see the [module](self) documentation).
#[derive(Debug, Clone)]
pub struct Pilot {
    cfg: PilotConfig,
    target_ned: [f64; 3],
    target_yaw_rad: f64,
    phase: PilotPhase,
    autopilot: Option<(u8, u8)>,
    mode: u32,
    armed: bool,
    takeoff_accepted: bool,
    next_send_s: f64,
    settled_since_s: Option<f64>,
    log: Vec<String>,
}

impl Pilot {
    /// A pilot that will take the vehicle to `target_ned` facing `target_yaw_rad`.
    pub fn new(target_ned: [f64; 3], target_yaw_rad: f64, cfg: &PilotConfig) -> Pilot {
        Pilot {
            cfg: cfg.clone(),
            target_ned,
            target_yaw_rad,
            phase: PilotPhase::WaitAutopilot,
            autopilot: None,
            mode: 0,
            armed: false,
            takeoff_accepted: false,
            next_send_s: 0.0,
            settled_since_s: None,
            log: Vec::new(),
        }
    }

    /// The phase now.
    pub fn phase(&self) -> PilotPhase {
        self.phase
    }

    /// Log lines since the last call (mode changes, refusals, the autopilot's STATUSTEXTs).
    pub fn take_log(&mut self) -> Vec<String> {
        std::mem::take(&mut self.log)
    }

    /// One message from the link.
    pub fn handle(&mut self, header: &MavHeader, msg: &MavMessage) {
        let source = (header.system_id as u8, header.component_id);
        match msg {
            MavMessage::HEARTBEAT(hb) if is_autopilot(hb) => {
                if self.autopilot.is_none() {
                    self.log.push(format!(
                        "autopilot system {} component {}: {:?}",
                        source.0, source.1, hb.mavtype
                    ));
                }
                self.autopilot = Some(source);
                let armed = hb
                    .base_mode
                    .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED);
                if (hb.custom_mode, armed) != (self.mode, self.armed) {
                    self.log.push(format!(
                        "autopilot in mode {}, {}",
                        hb.custom_mode,
                        if armed { "armed" } else { "disarmed" }
                    ));
                }
                self.mode = hb.custom_mode;
                self.armed = armed;
            }
            MavMessage::COMMAND_ACK(ack) if Some(source) == self.autopilot => {
                if ack.command == MavCmd::MAV_CMD_NAV_TAKEOFF
                    && ack.result == MavResult::MAV_RESULT_ACCEPTED
                {
                    self.takeoff_accepted = true;
                }
                if ack.result != MavResult::MAV_RESULT_ACCEPTED {
                    self.log
                        .push(format!("{:?} refused: {:?}", ack.command, ack.result));
                }
            }
            MavMessage::STATUSTEXT(t) if Some(source) == self.autopilot => {
                let text = t.text.to_str().unwrap_or("?").trim_end_matches('\0');
                self.log
                    .push(format!("autopilot says ({:?}): {text}", t.severity));
            }
            _ => {}
        }
    }

    /// A step at simulated time `t_s` with the true state `view`: advances the sequence and
    /// returns what to send.
    pub fn poll(&mut self, t_s: f64, view: &PilotView) -> Vec<MavMessage> {
        if !matches!(self.phase, PilotPhase::Ready | PilotPhase::Failed)
            && t_s > self.cfg.deadline_s
        {
            self.log.push(format!(
                "not at the start pose after {:.0} s (stuck in {:?})",
                self.cfg.deadline_s, self.phase
            ));
            self.phase = PilotPhase::Failed;
        }
        let Some(target) = self.autopilot else {
            return Vec::new();
        };
        let guided = self.mode == GUIDED;
        let next = match self.phase {
            PilotPhase::WaitAutopilot => Some(PilotPhase::Guided),
            PilotPhase::Guided if guided => Some(PilotPhase::Arm),
            // Before the take-off, GUIDED lost (or never kept) means asking for it again.
            PilotPhase::Arm | PilotPhase::Takeoff if !guided => Some(PilotPhase::Guided),
            PilotPhase::Arm if self.armed => Some(PilotPhase::Takeoff),
            PilotPhase::Takeoff if self.takeoff_accepted => Some(PilotPhase::Climb),
            PilotPhase::Climb if -view.position_ned[2] >= -self.target_ned[2] - 1.0 => {
                Some(PilotPhase::Position)
            }
            _ => None,
        };
        if let Some(n) = next {
            self.log
                .push(format!("t={t_s:.1}s: {:?} -> {n:?}", self.phase));
            self.phase = n;
            self.next_send_s = t_s;
        }
        if self.phase == PilotPhase::Position {
            let e = [
                view.position_ned[0] - self.target_ned[0],
                view.position_ned[1] - self.target_ned[1],
                view.position_ned[2] - self.target_ned[2],
            ];
            let settled = e.iter().map(|v| v * v).sum::<f64>().sqrt()
                <= self.cfg.position_tolerance_m
                && wrap_pi(view.yaw_rad - self.target_yaw_rad)
                    .abs()
                    .to_degrees()
                    <= self.cfg.yaw_tolerance_deg
                && view.speed_m_s <= self.cfg.speed_tolerance_m_s;
            if !settled {
                self.settled_since_s = None;
            } else if t_s - *self.settled_since_s.get_or_insert(t_s) >= self.cfg.settle_s {
                self.log
                    .push(format!("t={t_s:.1}s: at the start pose; handing over"));
                self.phase = PilotPhase::Ready;
                return Vec::new();
            }
        }
        if t_s < self.next_send_s {
            return Vec::new();
        }
        self.next_send_s = t_s + self.cfg.retry_s;
        let command = |command: MavCmd, p: [f32; 7]| {
            MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
                param1: p[0],
                param2: p[1],
                param3: p[2],
                param4: p[3],
                param5: p[4],
                param6: p[5],
                param7: p[6],
                command,
                target_system: target.0,
                target_component: target.1,
                confirmation: 0,
            })
        };
        match self.phase {
            PilotPhase::Guided => vec![command(
                MavCmd::MAV_CMD_DO_SET_MODE,
                [
                    MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED.bits() as f32,
                    GUIDED as f32,
                    0.0,
                    0.0,
                    0.0,
                    0.0,
                    0.0,
                ],
            )],
            PilotPhase::Arm => vec![command(
                MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
                [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            )],
            PilotPhase::Takeoff => vec![command(
                MavCmd::MAV_CMD_NAV_TAKEOFF,
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -self.target_ned[2] as f32],
            )],
            PilotPhase::Position => {
                vec![MavMessage::SET_POSITION_TARGET_LOCAL_NED(
                    SET_POSITION_TARGET_LOCAL_NED_DATA {
                        time_boot_ms: (t_s * 1000.0) as u32,
                        x: self.target_ned[0] as f32,
                        y: self.target_ned[1] as f32,
                        z: self.target_ned[2] as f32,
                        yaw: self.target_yaw_rad as f32,
                        type_mask: PositionTargetTypemask::from_bits_retain(TYPE_MASK_POSITION_YAW),
                        target_system: target.0,
                        target_component: target.1,
                        coordinate_frame: MavFrame::MAV_FRAME_LOCAL_NED,
                        ..Default::default()
                    },
                )]
            }
            _ => Vec::new(),
        }
    }
}

fn is_autopilot(hb: &HEARTBEAT_DATA) -> bool {
    hb.autopilot != mavlink::dialects::common::MavAutopilot::MAV_AUTOPILOT_INVALID
        && matches!(
            hb.mavtype,
            mavlink::dialects::common::MavType::MAV_TYPE_QUADROTOR
                | mavlink::dialects::common::MavType::MAV_TYPE_HEXAROTOR
                | mavlink::dialects::common::MavType::MAV_TYPE_OCTOROTOR
        )
}

#[cfg(test)]
mod tests {
    use super::*;
    use mavlink::dialects::common::{MavAutopilot, MavState, MavType, COMMAND_ACK_DATA};

    fn hb(mode: u32, armed: bool) -> MavMessage {
        MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: mode,
            mavtype: MavType::MAV_TYPE_QUADROTOR,
            autopilot: MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA,
            base_mode: if armed {
                MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED
            } else {
                MavModeFlag::empty()
            },
            system_status: MavState::MAV_STATE_STANDBY,
            mavlink_version: 3,
        })
    }

    fn h() -> MavHeader {
        MavHeader {
            system_id: 1,
            component_id: 1,
            sequence: 0,
        }
    }

    fn command_of(msgs: &[MavMessage]) -> Option<MavCmd> {
        match msgs.first() {
            Some(MavMessage::COMMAND_LONG(c)) => Some(c.command),
            _ => None,
        }
    }

    /// The whole sequence with scripted autopilot answers: each command repeated until the
    /// autopilot shows it done, then silence once at the pose.
    #[test]
    fn sequence_from_ground_to_hand_over() {
        let cfg = PilotConfig::default();
        let mut p = Pilot::new([0.0, 0.0, -90.0], 1.0, &cfg);
        let ground = PilotView {
            position_ned: [0.0; 3],
            speed_m_s: 0.0,
            yaw_rad: 0.0,
        };
        assert!(
            p.poll(0.0, &ground).is_empty(),
            "nothing before a heartbeat"
        );
        p.handle(&h(), &hb(0, false));
        let m = p.poll(0.1, &ground);
        assert_eq!(command_of(&m), Some(MavCmd::MAV_CMD_DO_SET_MODE));
        assert!(p.poll(0.5, &ground).is_empty(), "not before retry_s");
        assert_eq!(
            command_of(&p.poll(1.2, &ground)),
            Some(MavCmd::MAV_CMD_DO_SET_MODE),
            "repeated"
        );
        p.handle(&h(), &hb(GUIDED, false));
        assert_eq!(
            command_of(&p.poll(1.3, &ground)),
            Some(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM)
        );
        p.handle(&h(), &hb(GUIDED, true));
        assert_eq!(
            command_of(&p.poll(1.4, &ground)),
            Some(MavCmd::MAV_CMD_NAV_TAKEOFF)
        );
        p.handle(
            &h(),
            &MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
                command: MavCmd::MAV_CMD_NAV_TAKEOFF,
                result: MavResult::MAV_RESULT_ACCEPTED,
            }),
        );
        assert!(p.poll(1.5, &ground).is_empty());
        assert_eq!(p.phase(), PilotPhase::Climb);
        let up = PilotView {
            position_ned: [0.0, 0.0, -89.5],
            speed_m_s: 0.0,
            yaw_rad: 0.0,
        };
        let m = p.poll(30.0, &up);
        let Some(MavMessage::SET_POSITION_TARGET_LOCAL_NED(sp)) = m.first() else {
            panic!("{m:?}")
        };
        assert_eq!(sp.coordinate_frame, MavFrame::MAV_FRAME_LOCAL_NED);
        assert_eq!((sp.z, sp.yaw), (-90.0, 1.0));
        let there = PilotView {
            position_ned: [0.0, 0.0, -90.0],
            speed_m_s: 0.0,
            yaw_rad: 1.0,
        };
        p.poll(40.0, &there);
        assert_eq!(p.phase(), PilotPhase::Position, "settling");
        assert!(p.poll(42.5, &there).is_empty());
        assert_eq!(p.phase(), PilotPhase::Ready);
        assert!(p.poll(50.0, &there).is_empty());
    }

    #[test]
    fn gives_up_at_the_deadline() {
        let cfg = PilotConfig::default();
        let mut p = Pilot::new([0.0, 0.0, -90.0], 0.0, &cfg);
        let ground = PilotView {
            position_ned: [0.0; 3],
            speed_m_s: 0.0,
            yaw_rad: 0.0,
        };
        p.poll(cfg.deadline_s + 1.0, &ground);
        assert_eq!(p.phase(), PilotPhase::Failed);
    }

    /// The type_mask keeps position and yaw and ignores everything else.
    #[test]
    fn type_mask_is_position_and_yaw() {
        use PositionTargetTypemask as M;
        let ignored = M::POSITION_TARGET_TYPEMASK_VX_IGNORE
            | M::POSITION_TARGET_TYPEMASK_VY_IGNORE
            | M::POSITION_TARGET_TYPEMASK_VZ_IGNORE
            | M::POSITION_TARGET_TYPEMASK_AX_IGNORE
            | M::POSITION_TARGET_TYPEMASK_AY_IGNORE
            | M::POSITION_TARGET_TYPEMASK_AZ_IGNORE
            | M::POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE;
        assert_eq!(ignored.bits(), TYPE_MASK_POSITION_YAW);
    }
}
