//! Following the autopilot: who it is, whether its link is alive, and its state.

use std::fmt;

use hubtrack_types::VehicleState;
use mavlink::dialects::common::{
    MavAutopilot, MavMessage, MavModeFlag, MavType, ATTITUDE_DATA, GLOBAL_POSITION_INT_DATA,
    HEARTBEAT_DATA, LOCAL_POSITION_NED_DATA,
};
use mavlink::MavHeader;

use crate::messages::{copter_mode_name, COPTER_MODE_GUIDED};

/// How far time_boot_ms may step back before it counts as a reboot. Messages are stamped at
/// send time and arrive in order on one link, so any real step back is a restart; the margin
/// only absorbs reordering by a router with several paths. A reboot within this much of the
/// previous uptime is missed (and a restart that takes longer than the previous uptime is only
/// seen as link lost / regained).
pub const REBOOT_BACKSTEP_MS: u32 = 500;

/// GLOBAL_POSITION_INT velocity unit: cm/s.
const CM_PER_M: f64 = 100.0;
/// GLOBAL_POSITION_INT relative_alt unit: mm.
const MM_PER_M: f64 = 1000.0;
/// Nanoseconds per second, for log lines.
const NS_PER_S: f64 = 1e9;

/// Something worth a log line about the autopilot.
#[derive(Debug, Clone, PartialEq)]
pub enum VehicleEvent {
    /// The first autopilot HEARTBEAT (or a new autopilot after the old one's link was lost).
    AutopilotFound {
        /// Its system id.
        system_id: u8,
        /// Its component id.
        component_id: u8,
        /// Vehicle type it reports.
        mav_type: MavType,
        /// Autopilot firmware family.
        autopilot: MavAutopilot,
        /// Armed in that HEARTBEAT.
        armed: bool,
        /// custom_mode in that HEARTBEAT.
        custom_mode: u32,
    },
    /// No autopilot HEARTBEAT for longer than the link timeout.
    LinkLost {
        /// Time since the last HEARTBEAT.
        silent_ns: u64,
    },
    /// HEARTBEATs came back after a loss.
    LinkRegained {
        /// How long they were missing.
        silent_ns: u64,
    },
    /// time_boot_ms went backwards: the autopilot restarted. Attitude and position from before are
    /// dropped.
    Rebooted {
        /// Newest time_boot_ms before.
        previous_time_boot_ms: u32,
        /// The time_boot_ms that stepped back.
        time_boot_ms: u32,
    },
    /// custom_mode changed.
    ModeChanged {
        /// Old custom_mode.
        from: u32,
        /// New custom_mode.
        to: u32,
    },
    /// The motors were armed.
    Armed,
    /// The motors were disarmed.
    Disarmed,
}

/// `GUIDED (4)`, or `mode 42` for a number ArduCopter does not name.
struct Mode(u32);

impl fmt::Display for Mode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match copter_mode_name(self.0) {
            Some(name) => write!(f, "{name} ({})", self.0),
            None => write!(f, "mode {}", self.0),
        }
    }
}

fn armed_word(armed: bool) -> &'static str {
    if armed {
        "armed"
    } else {
        "disarmed"
    }
}

impl fmt::Display for VehicleEvent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            VehicleEvent::AutopilotFound {
                system_id,
                component_id,
                mav_type,
                autopilot,
                armed,
                custom_mode,
            } => write!(
                f,
                "autopilot found: system {system_id} component {component_id}, {mav_type:?}, \
                 {autopilot:?}, {}, {}",
                Mode(*custom_mode),
                armed_word(*armed)
            ),
            VehicleEvent::LinkLost { silent_ns } => write!(
                f,
                "autopilot link lost: no HEARTBEAT for {:.1} s",
                *silent_ns as f64 / NS_PER_S
            ),
            VehicleEvent::LinkRegained { silent_ns } => write!(
                f,
                "autopilot link regained after {:.1} s without HEARTBEAT",
                *silent_ns as f64 / NS_PER_S
            ),
            VehicleEvent::Rebooted {
                previous_time_boot_ms,
                time_boot_ms,
            } => write!(
                f,
                "autopilot rebooted: time_boot_ms went back from {previous_time_boot_ms} to \
                 {time_boot_ms}"
            ),
            VehicleEvent::ModeChanged { from, to } => {
                write!(f, "mode changed: {} -> {}", Mode(*from), Mode(*to))
            }
            VehicleEvent::Armed => f.write_str("armed"),
            VehicleEvent::Disarmed => f.write_str("disarmed"),
        }
    }
}

/// MAV_TYPEs that are components or ground equipment, not a vehicle's flight controller.
fn is_vehicle_type(t: MavType) -> bool {
    !matches!(
        t,
        MavType::MAV_TYPE_GCS
            | MavType::MAV_TYPE_ONBOARD_CONTROLLER
            | MavType::MAV_TYPE_ANTENNA_TRACKER
            | MavType::MAV_TYPE_GIMBAL
            | MavType::MAV_TYPE_ADSB
            | MavType::MAV_TYPE_CAMERA
            | MavType::MAV_TYPE_CHARGING_STATION
            | MavType::MAV_TYPE_FLARM
            | MavType::MAV_TYPE_SERVO
            | MavType::MAV_TYPE_ODID
            | MavType::MAV_TYPE_BATTERY
            | MavType::MAV_TYPE_PARACHUTE
            | MavType::MAV_TYPE_LOG
            | MavType::MAV_TYPE_OSD
            | MavType::MAV_TYPE_IMU
            | MavType::MAV_TYPE_GPS
            | MavType::MAV_TYPE_WINCH
            | MavType::MAV_TYPE_ILLUMINATOR
            | MavType::MAV_TYPE_GRIPPER
            | MavType::MAV_TYPE_RADIO
    )
}

/// An ATTITUDE whose angles are finite and within ±π (MAVLink's range) and whose rates are
/// finite; anything else is a corrupt or hostile frame and is not used.
fn attitude_is_plausible(a: &ATTITUDE_DATA) -> bool {
    let angles = [a.roll, a.pitch, a.yaw];
    let rates = [a.rollspeed, a.pitchspeed, a.yawspeed];
    angles
        .iter()
        .all(|v| v.is_finite() && v.abs() <= std::f32::consts::PI + 1e-3)
        && rates.iter().all(|v| v.is_finite())
}

/// A HEARTBEAT from a vehicle's autopilot (not a GCS, companion or peripheral).
fn is_autopilot(hb: &HEARTBEAT_DATA) -> bool {
    hb.autopilot != MavAutopilot::MAV_AUTOPILOT_INVALID && is_vehicle_type(hb.mavtype)
}

fn is_armed(hb: &HEARTBEAT_DATA) -> bool {
    hb.base_mode
        .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED)
}

/// Follows the autopilot: which system/component it is, link liveness, reboots, and the
/// [`VehicleState`].
///
/// The autopilot is the sender of the first HEARTBEAT whose autopilot is not
/// MAV_AUTOPILOT_INVALID and whose type is a vehicle (not a GCS, companion, gimbal, camera, ...).
/// Once known, messages from every other system/component are ignored (counted in
/// [`VehicleMonitor::ignored_messages`]); that includes our own echo, as the companion's
/// HEARTBEAT never qualifies. A different autopilot is adopted only while the known one's link
/// is lost (e.g. after SYSID_THISMAV was changed and the vehicle rebooted).
///
/// All times are on the caller's clock (ns); nothing here reads a clock.
#[derive(Debug, Clone)]
pub struct VehicleMonitor {
    link_timeout_ns: u64,
    state_timeout_ns: u64,
    target: Option<(u8, u8)>,
    last_heartbeat_ns: Option<u64>,
    /// The link was up at the last check (for loss/regain events).
    link_up: bool,
    armed: bool,
    custom_mode: u32,
    last_recv_ns: u64,
    attitude: Option<(u64, ATTITUDE_DATA)>,
    local_position: Option<(u64, LOCAL_POSITION_NED_DATA)>,
    global_position: Option<(u64, GLOBAL_POSITION_INT_DATA)>,
    time_boot_ms: Option<u32>,
    ignored: u64,
    /// Only this system/component is taken as the autopilot (see [`VehicleMonitor::expect_autopilot`]).
    expected: Option<crate::AutopilotId>,
}

impl VehicleMonitor {
    /// A monitor that calls the link lost after `link_timeout_ns` without an autopilot HEARTBEAT
    /// and attitude/position stale after `state_timeout_ns` without an update.
    pub fn new(link_timeout_ns: u64, state_timeout_ns: u64) -> Self {
        VehicleMonitor {
            link_timeout_ns,
            state_timeout_ns,
            target: None,
            last_heartbeat_ns: None,
            link_up: false,
            armed: false,
            custom_mode: 0,
            last_recv_ns: 0,
            attitude: None,
            local_position: None,
            global_position: None,
            time_boot_ms: None,
            ignored: 0,
            expected: None,
        }
    }

    /// Takes only `id` as the autopilot: heartbeats and telemetry of any other system or
    /// component are ignored (counted), also when the autopilot has fallen silent.
    pub fn expect_autopilot(mut self, id: crate::AutopilotId) -> Self {
        self.expected = Some(id);
        self
    }

    /// Feeds one received message; `now_ns` is its receive time on the pipeline clock.
    ///
    /// Returns events worth logging: autopilot found, link lost (checked first, as in
    /// [`VehicleMonitor::poll`]) or regained, rebooted, mode changed, armed/disarmed.
    pub fn handle(
        &mut self,
        now_ns: u64,
        header: &MavHeader,
        msg: &MavMessage,
    ) -> Vec<VehicleEvent> {
        let mut events = self.poll(now_ns);
        // System ids above 255 only exist in the mavlink crate's non-standard extension.
        let source = u8::try_from(header.system_id)
            .ok()
            .map(|sys| (sys, header.component_id));
        if source.is_none() || source != self.target {
            match (source, msg) {
                (Some(source), MavMessage::HEARTBEAT(hb))
                    if is_autopilot(hb)
                        && !self.link_ok(now_ns)
                        && self.expected.is_none_or(|id| id.sent(header)) =>
                {
                    self.adopt(now_ns, source, hb, &mut events);
                }
                _ => self.ignored += 1,
            }
            return events;
        }

        self.last_recv_ns = now_ns;
        match msg {
            MavMessage::HEARTBEAT(hb) => self.heartbeat(now_ns, hb, &mut events),
            MavMessage::ATTITUDE(a) => {
                self.observe_time(a.time_boot_ms, &mut events);
                if attitude_is_plausible(a) {
                    self.attitude = Some((now_ns, a.clone()));
                } else {
                    // Validated where it enters: detect and track act on these angles.
                    self.ignored += 1;
                }
            }
            MavMessage::LOCAL_POSITION_NED(p) => {
                self.observe_time(p.time_boot_ms, &mut events);
                self.local_position = Some((now_ns, p.clone()));
            }
            MavMessage::GLOBAL_POSITION_INT(p) => {
                self.observe_time(p.time_boot_ms, &mut events);
                self.global_position = Some((now_ns, p.clone()));
            }
            MavMessage::SYSTEM_TIME(t) => self.observe_time(t.time_boot_ms, &mut events),
            _ => {}
        }
        events
    }

    /// Takes `source` as the autopilot, forgetting everything about a previous one.
    fn adopt(
        &mut self,
        now_ns: u64,
        source: (u8, u8),
        hb: &HEARTBEAT_DATA,
        events: &mut Vec<VehicleEvent>,
    ) {
        *self = VehicleMonitor {
            target: Some(source),
            last_heartbeat_ns: Some(now_ns),
            link_up: true,
            armed: is_armed(hb),
            custom_mode: hb.custom_mode,
            last_recv_ns: now_ns,
            ignored: self.ignored,
            expected: self.expected,
            ..VehicleMonitor::new(self.link_timeout_ns, self.state_timeout_ns)
        };
        events.push(VehicleEvent::AutopilotFound {
            system_id: source.0,
            component_id: source.1,
            mav_type: hb.mavtype,
            autopilot: hb.autopilot,
            armed: self.armed,
            custom_mode: self.custom_mode,
        });
    }

    fn heartbeat(&mut self, now_ns: u64, hb: &HEARTBEAT_DATA, events: &mut Vec<VehicleEvent>) {
        if !self.link_up {
            let silent_ns = now_ns.saturating_sub(self.last_heartbeat_ns.unwrap_or(now_ns));
            events.push(VehicleEvent::LinkRegained { silent_ns });
            self.link_up = true;
        }
        self.last_heartbeat_ns = Some(now_ns);
        let armed = is_armed(hb);
        if armed != self.armed {
            events.push(if armed {
                VehicleEvent::Armed
            } else {
                VehicleEvent::Disarmed
            });
            self.armed = armed;
        }
        if hb.custom_mode != self.custom_mode {
            events.push(VehicleEvent::ModeChanged {
                from: self.custom_mode,
                to: hb.custom_mode,
            });
            self.custom_mode = hb.custom_mode;
        }
    }

    /// Tracks the autopilot's boot clock; a step back means it restarted.
    fn observe_time(&mut self, time_boot_ms: u32, events: &mut Vec<VehicleEvent>) {
        match self.time_boot_ms {
            Some(prev)
                if u64::from(time_boot_ms) + u64::from(REBOOT_BACKSTEP_MS) < u64::from(prev) =>
            {
                events.push(VehicleEvent::Rebooted {
                    previous_time_boot_ms: prev,
                    time_boot_ms,
                });
                // The old attitude and position describe the vehicle before the restart (the EKF
                // origin may differ now).
                self.attitude = None;
                self.local_position = None;
                self.global_position = None;
                self.time_boot_ms = Some(time_boot_ms);
            }
            Some(prev) => self.time_boot_ms = Some(prev.max(time_boot_ms)),
            None => self.time_boot_ms = Some(time_boot_ms),
        }
    }

    /// Call periodically: detects link loss (no autopilot HEARTBEAT for the link timeout).
    pub fn poll(&mut self, now_ns: u64) -> Vec<VehicleEvent> {
        let mut events = Vec::new();
        if let (true, Some(last)) = (self.link_up, self.last_heartbeat_ns) {
            let silent_ns = now_ns.saturating_sub(last);
            if silent_ns > self.link_timeout_ns {
                self.link_up = false;
                events.push(VehicleEvent::LinkLost { silent_ns });
            }
        }
        events
    }

    fn link_ok(&self, now_ns: u64) -> bool {
        self.last_heartbeat_ns
            .is_some_and(|last| now_ns.saturating_sub(last) <= self.link_timeout_ns)
    }

    fn fresh(&self, received_ns: u64, now_ns: u64) -> bool {
        now_ns.saturating_sub(received_ns) <= self.state_timeout_ns
    }

    /// The vehicle state at `now_ns`.
    ///
    /// - `link_ok`: an autopilot HEARTBEAT within the link timeout.
    /// - `armed` (base_mode has MAV_MODE_FLAG_SAFETY_ARMED) and `custom_mode`: from the last
    ///   HEARTBEAT, kept when the link is lost (check `link_ok`).
    /// - attitude from ATTITUDE, valid while younger than the state timeout; zero when not.
    /// - position and velocity from LOCAL_POSITION_NED while fresh; otherwise from a fresh
    ///   GLOBAL_POSITION_INT: velocity (vx, vy, vz) and down = −relative_alt, with north and
    ///   east 0 (`position_valid` is true: the height above home and the velocity are real);
    ///   zero and not valid when neither is fresh.
    /// - `recv_ns`: receive time of the newest autopilot message; `publish_ns` 0 (the caller
    ///   sets it).
    pub fn state(&self, now_ns: u64) -> VehicleState {
        let mut s = VehicleState {
            recv_ns: self.last_recv_ns,
            publish_ns: 0,
            link_ok: self.link_ok(now_ns),
            armed: self.armed,
            custom_mode: self.custom_mode,
            ..VehicleState::default()
        };
        if let Some((t, a)) = &self.attitude {
            if self.fresh(*t, now_ns) {
                s.attitude_valid = true;
                s.roll_rad = f64::from(a.roll);
                s.pitch_rad = f64::from(a.pitch);
                s.yaw_rad = f64::from(a.yaw);
                s.body_rates_rad_s = [
                    f64::from(a.rollspeed),
                    f64::from(a.pitchspeed),
                    f64::from(a.yawspeed),
                ];
            }
        }
        let local = self
            .local_position
            .as_ref()
            .filter(|(t, _)| self.fresh(*t, now_ns));
        let global = self
            .global_position
            .as_ref()
            .filter(|(t, _)| self.fresh(*t, now_ns));
        if let Some((_, p)) = local {
            s.position_valid = true;
            s.position_ned_m = [f64::from(p.x), f64::from(p.y), f64::from(p.z)];
            s.velocity_ned_m_s = [f64::from(p.vx), f64::from(p.vy), f64::from(p.vz)];
        } else if let Some((_, p)) = global {
            s.position_valid = true;
            s.position_ned_m = [0.0, 0.0, -f64::from(p.relative_alt) / MM_PER_M];
            s.velocity_ned_m_s = [
                f64::from(p.vx) / CM_PER_M,
                f64::from(p.vy) / CM_PER_M,
                f64::from(p.vz) / CM_PER_M,
            ];
        }
        s
    }

    /// The autopilot's (system id, component id), once found.
    pub fn target(&self) -> Option<(u8, u8)> {
        self.target
    }

    /// Link ok, armed, and in GUIDED: setpoints will be followed (the rule of
    /// [`follows_setpoints`] on [`VehicleMonitor::state`]).
    pub fn guided_and_armed(&self, now_ns: u64) -> bool {
        follows_setpoints(&self.state(now_ns))
    }

    /// Newest time_boot_ms seen from the autopilot (ATTITUDE, LOCAL_POSITION_NED,
    /// GLOBAL_POSITION_INT, SYSTEM_TIME); reset by a reboot.
    pub fn autopilot_time_boot_ms(&self) -> Option<u32> {
        self.time_boot_ms
    }

    /// Messages ignored because they did not come from the autopilot (or came before it was
    /// found).
    pub fn ignored_messages(&self) -> u64 {
        self.ignored
    }
}

/// Whether a vehicle in state `s` follows setpoints: autopilot link ok, armed, and in GUIDED.
///
/// The one rule for live control (on [`VehicleMonitor::state`]) and for replay (on a recorded
/// state aged with [`aged_state`]).
pub fn follows_setpoints(s: &VehicleState) -> bool {
    s.link_ok && s.armed && s.custom_mode == COPTER_MODE_GUIDED
}

/// A published [`VehicleState`] as it stands at `now_ns` (pipeline clock), for a consumer that
/// has only the published states and no link (replay).
///
/// A live monitor publishes a state on every autopilot message and on link loss, so the newest
/// published state is current until its autopilot messages stop. When they have stopped — the
/// newest message (`recv_ns`) is older than a timeout — this applies the monitor's rules: no
/// link after `link_timeout_ns`, no attitude and no position after `state_timeout_ns` (zeroed,
/// as [`VehicleMonitor::state`] leaves them). Judged on the newest message of any kind, so a
/// stale part is declared no earlier than the monitor would.
pub fn aged_state(
    s: &VehicleState,
    now_ns: u64,
    link_timeout_ns: u64,
    state_timeout_ns: u64,
) -> VehicleState {
    let silent_ns = now_ns.saturating_sub(s.recv_ns);
    let mut aged = *s;
    if silent_ns > link_timeout_ns {
        aged.link_ok = false;
    }
    if silent_ns > state_timeout_ns {
        aged.attitude_valid = false;
        aged.roll_rad = 0.0;
        aged.pitch_rad = 0.0;
        aged.yaw_rad = 0.0;
        aged.body_rates_rad_s = [0.0; 3];
        aged.position_valid = false;
        aged.position_ned_m = [0.0; 3];
        aged.velocity_ned_m_s = [0.0; 3];
    }
    aged
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::*;
    use crate::{companion_heartbeat, COPTER_MODE_GUIDED};

    const MS: u64 = 1_000_000;
    const LINK_TIMEOUT: u64 = 3_000 * MS;
    const STATE_TIMEOUT: u64 = 500 * MS;
    const LOITER: u32 = 5;

    fn monitor() -> VehicleMonitor {
        VehicleMonitor::new(LINK_TIMEOUT, STATE_TIMEOUT)
    }

    fn ap() -> MavHeader {
        header(1, 1, 0)
    }

    #[test]
    fn heartbeat_finds_the_autopilot_and_sets_armed_and_mode() {
        let mut m = monitor();
        assert!(!m.state(0).link_ok);
        let ev = m.handle(
            10 * MS,
            &ap(),
            &autopilot_heartbeat(true, COPTER_MODE_GUIDED),
        );
        assert!(
            matches!(
                ev[..],
                [VehicleEvent::AutopilotFound {
                    system_id: 1,
                    component_id: 1,
                    armed: true,
                    custom_mode: 4,
                    ..
                }]
            ),
            "{ev:?}"
        );
        assert_eq!(
            ev[0].to_string(),
            "autopilot found: system 1 component 1, MAV_TYPE_QUADROTOR, MAV_AUTOPILOT_ARDUPILOTMEGA, \
             GUIDED (4), armed"
        );
        assert_eq!(m.target(), Some((1, 1)));
        let s = m.state(20 * MS);
        assert!(s.link_ok && s.armed);
        assert_eq!(
            (s.custom_mode, s.recv_ns, s.publish_ns),
            (COPTER_MODE_GUIDED, 10 * MS, 0)
        );
        assert!(!s.attitude_valid && !s.position_valid);
        assert!(m.guided_and_armed(20 * MS));

        assert_eq!(
            m.handle(1_000 * MS, &ap(), &autopilot_heartbeat(true, LOITER)),
            vec![VehicleEvent::ModeChanged {
                from: COPTER_MODE_GUIDED,
                to: LOITER
            }]
        );
        assert!(!m.guided_and_armed(1_000 * MS));
        assert_eq!(
            VehicleEvent::ModeChanged {
                from: COPTER_MODE_GUIDED,
                to: LOITER
            }
            .to_string(),
            "mode changed: GUIDED (4) -> LOITER (5)"
        );
        assert_eq!(
            m.handle(2_000 * MS, &ap(), &autopilot_heartbeat(false, LOITER)),
            vec![VehicleEvent::Disarmed]
        );
        assert!(!m.state(2_000 * MS).armed);
        assert_eq!(
            m.handle(
                3_000 * MS,
                &ap(),
                &autopilot_heartbeat(true, COPTER_MODE_GUIDED)
            ),
            vec![
                VehicleEvent::Armed,
                VehicleEvent::ModeChanged {
                    from: LOITER,
                    to: COPTER_MODE_GUIDED
                }
            ]
        );
        assert!(m.guided_and_armed(3_000 * MS));
    }

    #[test]
    fn gcs_and_companion_heartbeats_are_not_the_autopilot() {
        let mut m = monitor();
        assert!(m
            .handle(0, &header(255, 190, 0), &gcs_heartbeat())
            .is_empty());
        assert!(m
            .handle(0, &header(1, 191, 0), &companion_heartbeat())
            .is_empty());
        // A GCS type with a real autopilot field is still not a vehicle.
        let MavMessage::HEARTBEAT(mut hb) = autopilot_heartbeat(true, 4) else {
            unreachable!()
        };
        hb.mavtype = MavType::MAV_TYPE_GCS;
        assert!(m
            .handle(0, &header(255, 190, 0), &MavMessage::HEARTBEAT(hb))
            .is_empty());
        // Messages before the autopilot is known are ignored too.
        assert!(m
            .handle(0, &ap(), &attitude(1_000, 0.1, 0.2, 0.3))
            .is_empty());
        assert_eq!(m.target(), None);
        assert_eq!(m.ignored_messages(), 4);
        assert!(!m.state(0).link_ok && !m.state(0).attitude_valid);
        assert_eq!(m.handle(0, &ap(), &autopilot_heartbeat(false, 0)).len(), 1);
        assert_eq!(m.target(), Some((1, 1)));
    }

    #[test]
    fn others_and_our_echo_are_ignored_once_the_autopilot_is_known() {
        let mut m = monitor();
        m.handle(0, &ap(), &autopilot_heartbeat(true, COPTER_MODE_GUIDED));
        // Same system, other component (e.g. a gimbal), and our own echo.
        assert!(m
            .handle(MS, &header(1, 154, 0), &attitude(1_000, 1.0, 1.0, 1.0))
            .is_empty());
        assert!(m
            .handle(MS, &header(1, 191, 0), &companion_heartbeat())
            .is_empty());
        // Another vehicle's heartbeat while ours is alive.
        assert!(m
            .handle(MS, &header(2, 1, 0), &autopilot_heartbeat(false, 0))
            .is_empty());
        assert_eq!(m.ignored_messages(), 3);
        assert_eq!(m.target(), Some((1, 1)));
        assert!(!m.state(MS).attitude_valid);
    }

    #[test]
    fn link_loss_and_regain() {
        let mut m = monitor();
        m.handle(0, &ap(), &autopilot_heartbeat(true, COPTER_MODE_GUIDED));
        assert!(m.poll(LINK_TIMEOUT).is_empty());
        assert!(m.state(LINK_TIMEOUT).link_ok);
        let ev = m.poll(LINK_TIMEOUT + 1);
        assert_eq!(
            ev,
            vec![VehicleEvent::LinkLost {
                silent_ns: LINK_TIMEOUT + 1
            }]
        );
        assert_eq!(
            ev[0].to_string(),
            "autopilot link lost: no HEARTBEAT for 3.0 s"
        );
        assert!(m.poll(LINK_TIMEOUT + 2).is_empty(), "reported once");
        let s = m.state(LINK_TIMEOUT + 1);
        assert!(!s.link_ok && s.armed, "last known armed state is kept");
        assert!(!m.guided_and_armed(LINK_TIMEOUT + 1));
        let ev = m.handle(
            5_000 * MS,
            &ap(),
            &autopilot_heartbeat(true, COPTER_MODE_GUIDED),
        );
        assert_eq!(
            ev,
            vec![VehicleEvent::LinkRegained {
                silent_ns: 5_000 * MS
            }]
        );
        assert!(m.guided_and_armed(5_000 * MS));
    }

    #[test]
    fn late_heartbeat_without_poll_reports_loss_then_regain() {
        let mut m = monitor();
        m.handle(0, &ap(), &autopilot_heartbeat(false, 0));
        let ev = m.handle(10_000 * MS, &ap(), &autopilot_heartbeat(false, 0));
        assert_eq!(
            ev,
            vec![
                VehicleEvent::LinkLost {
                    silent_ns: 10_000 * MS
                },
                VehicleEvent::LinkRegained {
                    silent_ns: 10_000 * MS
                }
            ]
        );
    }

    #[test]
    fn new_autopilot_is_adopted_only_after_loss() {
        let mut m = monitor();
        m.handle(0, &ap(), &autopilot_heartbeat(false, 0));
        m.poll(LINK_TIMEOUT + 1);
        let ev = m.handle(
            LINK_TIMEOUT + 2,
            &header(7, 1, 0),
            &autopilot_heartbeat(false, LOITER),
        );
        assert!(
            matches!(ev[..], [VehicleEvent::AutopilotFound { system_id: 7, .. }]),
            "{ev:?}"
        );
        assert_eq!(m.target(), Some((7, 1)));
        assert!(m.state(LINK_TIMEOUT + 2).link_ok);
    }

    #[test]
    fn attitude_is_copied_and_expires() {
        let mut m = monitor();
        m.handle(0, &ap(), &autopilot_heartbeat(true, COPTER_MODE_GUIDED));
        assert!(m
            .handle(100 * MS, &ap(), &attitude(5_000, 0.1, -0.2, 1.5))
            .is_empty());
        let s = m.state(100 * MS + STATE_TIMEOUT);
        assert!(s.attitude_valid);
        assert_eq!(
            [s.roll_rad, s.pitch_rad, s.yaw_rad],
            [0.1f32, -0.2, 1.5].map(f64::from)
        );
        assert_eq!(s.body_rates_rad_s, [0.01f32, -0.02, 0.03].map(f64::from));
        assert_eq!(s.recv_ns, 100 * MS);
        assert_eq!(m.autopilot_time_boot_ms(), Some(5_000));
        let stale = m.state(100 * MS + STATE_TIMEOUT + 1);
        assert!(!stale.attitude_valid);
        assert_eq!(stale.roll_rad, 0.0);
    }

    #[test]
    fn local_position_preferred_global_as_fallback() {
        let mut m = monitor();
        m.handle(0, &ap(), &autopilot_heartbeat(true, COPTER_MODE_GUIDED));
        m.handle(10 * MS, &ap(), &global_position(1_000));
        let s = m.state(10 * MS);
        assert!(s.position_valid);
        assert_eq!(s.position_ned_m, [0.0, 0.0, -20.5]);
        assert_eq!(s.velocity_ned_m_s, [1.5, -0.5, 0.25]);
        m.handle(20 * MS, &ap(), &local_position(1_010));
        let s = m.state(20 * MS);
        assert_eq!(s.position_ned_m, [12.5, -3.25, -20.0]);
        assert_eq!(s.velocity_ned_m_s, [1.5, -0.5, 0.25]);
        // Local goes stale while global keeps coming.
        m.handle(20 * MS + STATE_TIMEOUT, &ap(), &global_position(1_600));
        let s = m.state(20 * MS + STATE_TIMEOUT + 1);
        assert!(s.position_valid);
        assert_eq!(s.position_ned_m, [0.0, 0.0, -20.5]);
        assert!(!m.state(20 * MS + 2 * STATE_TIMEOUT + 1).position_valid);
    }

    #[test]
    fn reboot_is_detected_from_time_boot_ms() {
        let mut m = monitor();
        m.handle(0, &ap(), &autopilot_heartbeat(true, COPTER_MODE_GUIDED));
        m.handle(MS, &ap(), &attitude(100_000, 0.1, 0.1, 0.1));
        m.handle(MS, &ap(), &local_position(100_010));
        // Small reordering is not a reboot.
        assert!(m
            .handle(
                2 * MS,
                &ap(),
                &attitude(
                    100_010 - u64::from(REBOOT_BACKSTEP_MS) as u32,
                    0.1,
                    0.1,
                    0.1
                )
            )
            .is_empty());
        assert_eq!(m.autopilot_time_boot_ms(), Some(100_010));
        let ev = m.handle(3 * MS, &ap(), &attitude(2_500, 0.3, 0.2, 0.1));
        assert_eq!(
            ev,
            vec![VehicleEvent::Rebooted {
                previous_time_boot_ms: 100_010,
                time_boot_ms: 2_500
            }]
        );
        assert_eq!(
            ev[0].to_string(),
            "autopilot rebooted: time_boot_ms went back from 100010 to 2500"
        );
        assert_eq!(m.autopilot_time_boot_ms(), Some(2_500));
        let s = m.state(3 * MS);
        assert!(
            s.attitude_valid && !s.position_valid,
            "pre-reboot position dropped"
        );
        assert_eq!(s.roll_rad, f64::from(0.3f32));
    }

    #[test]
    fn an_implausible_attitude_is_not_used() {
        let mut m = monitor();
        m.handle(0, &ap(), &autopilot_heartbeat(true, COPTER_MODE_GUIDED));
        m.handle(MS, &ap(), &attitude(1_000, 0.1, 0.0, 0.0));
        for (roll, pitch, yaw) in [
            (f32::NAN, 0.0, 0.0),
            (0.0, f32::INFINITY, 0.0),
            (4.0, 0.0, 0.0),
            (0.0, 0.0, -1e30),
        ] {
            let before = m.ignored_messages();
            m.handle(2 * MS, &ap(), &attitude(1_010, roll, pitch, yaw));
            assert_eq!(m.ignored_messages(), before + 1, "{roll} {pitch} {yaw}");
            assert_eq!(
                m.state(2 * MS).roll_rad,
                f64::from(0.1f32),
                "the last good attitude stays"
            );
        }
        // A real roll of 86° is an attitude, if not one to approach in.
        m.handle(3 * MS, &ap(), &attitude(1_020, 1.5, 0.0, 0.0));
        assert_eq!(m.state(3 * MS).roll_rad, f64::from(1.5f32));
    }

    #[test]
    fn reboot_across_a_link_loss() {
        let mut m = monitor();
        m.handle(0, &ap(), &autopilot_heartbeat(true, COPTER_MODE_GUIDED));
        m.handle(MS, &ap(), &attitude(600_000, 0.0, 0.0, 0.0));
        m.poll(LINK_TIMEOUT + MS + 1);
        let t = 20_000 * MS;
        let ev = m.handle(t, &ap(), &autopilot_heartbeat(false, 0));
        assert_eq!(
            ev,
            vec![
                VehicleEvent::LinkRegained { silent_ns: t },
                VehicleEvent::Disarmed,
                VehicleEvent::ModeChanged {
                    from: COPTER_MODE_GUIDED,
                    to: 0
                }
            ]
        );
        let ev = m.handle(t, &ap(), &attitude(4_000, 0.0, 0.0, 0.0));
        assert!(matches!(ev[..], [VehicleEvent::Rebooted { .. }]), "{ev:?}");
    }

    #[test]
    fn a_published_state_aged_like_the_monitor_ages_it() {
        let mut m = monitor();
        m.handle(0, &ap(), &autopilot_heartbeat(true, COPTER_MODE_GUIDED));
        m.handle(100 * MS, &ap(), &attitude(5_000, 0.1, -0.2, 1.5));
        m.handle(100 * MS, &ap(), &local_position(5_000));
        let published = m.state(100 * MS);
        assert!(follows_setpoints(&published));
        // While messages are recent the published state stands as it is.
        let t = 100 * MS + STATE_TIMEOUT;
        assert_eq!(
            aged_state(&published, t, LINK_TIMEOUT, STATE_TIMEOUT),
            published
        );
        // Silent past the state timeout: attitude and position go, as in the monitor.
        let t = 100 * MS + STATE_TIMEOUT + 1;
        let (aged, live) = (
            aged_state(&published, t, LINK_TIMEOUT, STATE_TIMEOUT),
            m.state(t),
        );
        assert!(!aged.attitude_valid && !aged.position_valid && aged.link_ok);
        assert_eq!(aged, live);
        // Silent past the link timeout: the vehicle no longer follows setpoints.
        let t = 100 * MS + LINK_TIMEOUT + 1;
        let aged = aged_state(&published, t, LINK_TIMEOUT, STATE_TIMEOUT);
        assert!(!aged.link_ok && !follows_setpoints(&aged));
        assert!(!m.guided_and_armed(t));
        // Disarmed or not in GUIDED: not followed.
        assert!(!follows_setpoints(&VehicleState {
            armed: false,
            ..published
        }));
        assert!(!follows_setpoints(&VehicleState {
            custom_mode: LOITER,
            ..published
        }));
    }

    #[test]
    fn only_the_expected_autopilot_is_adopted_even_after_silence() {
        use crate::test_support::{autopilot_heartbeat, header};
        let mut m =
            VehicleMonitor::new(LINK_TIMEOUT, STATE_TIMEOUT).expect_autopilot(crate::AutopilotId {
                system_id: 1,
                component_id: 1,
            });
        let hb = autopilot_heartbeat(false, 4);
        assert!(m.handle(1, &header(99, 1, 0), &hb).is_empty());
        assert!(m.handle(2, &header(1, 2, 0), &hb).is_empty());
        let ev = m.handle(3, &header(1, 1, 0), &hb);
        assert!(matches!(
            ev[..],
            [VehicleEvent::AutopilotFound { system_id: 1, .. }]
        ));
        // The autopilot falls silent: a stranger claiming to be one is still not adopted.
        let later = 3 + LINK_TIMEOUT * 2;
        let ev = m.handle(later, &header(99, 1, 0), &hb);
        assert!(
            !ev.iter()
                .any(|e| matches!(e, VehicleEvent::AutopilotFound { .. })),
            "{ev:?}"
        );
        assert_eq!(m.target, Some((1, 1)));
    }
}
