//! The command gate: what live control sends to the autopilot, and when.
//!
//! A plain state machine in the style of a sans-IO protocol reader: the caller feeds it events
//! with their time — a new setpoint ([`CommandGate::on_track`]), a turn of the loop
//! ([`CommandGate::on_tick`]), a setpoint that went out ([`CommandGate::on_sent`]) — and gets
//! back [`Action`]s to perform. It reads no clock, does no I/O and logs nothing, so every rule
//! is testable with scripted times:
//!
//! - our HEARTBEAT on the first tick and then every `heartbeat_period_ns`;
//! - each new setpoint at once, and the newest one again every `resend_period_ns` while its
//!   track is fresh;
//! - silence once no track state has arrived for more than `input_timeout_ns` (the autopilot's
//!   own guided-mode timeout then stops the vehicle), reported once with a quiet Hold setpoint,
//!   until the next track state;
//! - setpoints only to an autopilot that has been heard from and follows them (link up, armed,
//!   GUIDED), and never an Abort ([`may_command`]).
//!
//! All times are one monotonic clock in nanoseconds (live control: the wall clock).

use hubtrack_types::{ApproachTask, Setpoint, Text64};

/// Whether a setpoint of `task` may go to the autopilot: only while the vehicle follows
/// setpoints (link up, armed, GUIDED: `hubtrack_mavlink::follows_setpoints`), and never in
/// Abort (bad data: send nothing, the autopilot's guided timeout stops the vehicle).
pub fn may_command(task: ApproachTask, vehicle_follows: bool) -> bool {
    vehicle_follows && task != ApproachTask::Abort
}

/// One period of `hz`, ns (truncated).
pub fn period_ns(hz: f64) -> u64 {
    (1e9 / hz) as u64
}

/// The gate's three timings, ns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GateTiming {
    /// Between two of our HEARTBEATs.
    pub heartbeat_period_ns: u64,
    /// Between two sendings of the same setpoint.
    pub resend_period_ns: u64,
    /// Longest time without a track state before the inputs are stale.
    pub input_timeout_ns: u64,
}

impl GateTiming {
    /// From the `[control]` settings: `heartbeat_hz`, `setpoint_rate_hz` and `input_timeout_ms`.
    pub fn from_rates(heartbeat_hz: f64, setpoint_rate_hz: f64, input_timeout_ms: u64) -> Self {
        GateTiming {
            heartbeat_period_ns: period_ns(heartbeat_hz),
            resend_period_ns: period_ns(setpoint_rate_hz),
            input_timeout_ns: input_timeout_ms.saturating_mul(1_000_000),
        }
    }
}

/// The autopilot as the gate needs to see it at one moment (from the vehicle monitor).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct AutopilotView {
    /// Its MAVLink system and component id, once it has been heard from.
    pub target: Option<(u8, u8)>,
    /// It follows setpoints now: link up, armed and in GUIDED.
    pub follows_setpoints: bool,
}

/// What the caller is to do.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Action {
    /// Send our HEARTBEAT.
    SendHeartbeat,
    /// Send this setpoint to the autopilot `target` (system, component), then report with
    /// [`CommandGate::on_sent`] whether it went out.
    SendSetpoint {
        /// The setpoint, as given to the gate.
        setpoint: Setpoint,
        /// The autopilot's system and component id.
        target: (u8, u8),
    },
    /// The inputs went stale: nothing more is sent. Publish `quiet` (the newest setpoint as a
    /// Hold with zero velocity, not sent) to say so.
    ReportStale {
        /// What to publish.
        quiet: Setpoint,
        /// Time since the newest track state arrived, ns.
        silent_for_ns: u64,
    },
}

/// The actions of one event, in order (at most two: a heartbeat and a setpoint or a report).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Actions {
    slots: [Option<Action>; 2],
    next: usize,
}

impl Actions {
    fn push(&mut self, action: Action) {
        if let Some(slot) = self.slots.iter_mut().find(|s| s.is_none()) {
            *slot = Some(action);
        }
    }
}

impl Iterator for Actions {
    type Item = Action;

    fn next(&mut self) -> Option<Action> {
        while let Some(slot) = self.slots.get_mut(self.next) {
            self.next += 1;
            if let Some(action) = slot.take() {
                return Some(action);
            }
        }
        None
    }
}

/// The newest setpoint and when its track state arrived.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Newest {
    setpoint: Setpoint,
    arrived_ns: u64,
}

/// The command gate (see the [module](self) documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct CommandGate {
    timing: GateTiming,
    /// When the next HEARTBEAT is due (0: on the first tick).
    next_heartbeat_ns: u64,
    newest: Option<Newest>,
    /// When a setpoint last went out.
    last_sent_ns: u64,
    /// The staleness of `newest` has been reported.
    stale_reported: bool,
    /// The time of the last [`Action::SendSetpoint`], until [`CommandGate::on_sent`].
    pending_ns: Option<u64>,
}

impl CommandGate {
    /// A gate that has sent nothing and has no setpoint yet.
    pub fn new(timing: GateTiming) -> CommandGate {
        CommandGate {
            timing,
            next_heartbeat_ns: 0,
            newest: None,
            last_sent_ns: 0,
            stale_reported: false,
            pending_ns: None,
        }
    }

    /// The timings in use.
    pub fn timing(&self) -> GateTiming {
        self.timing
    }

    /// A new setpoint, from a track state that arrived at `now_ns`: it becomes the newest, the
    /// inputs are fresh again, and it is to be sent at once if `autopilot` may be commanded.
    pub fn on_track(
        &mut self,
        setpoint: Setpoint,
        now_ns: u64,
        autopilot: AutopilotView,
    ) -> Option<Action> {
        self.newest = Some(Newest {
            setpoint,
            arrived_ns: now_ns,
        });
        self.stale_reported = false;
        self.command(setpoint, now_ns, autopilot)
    }

    /// A turn of the loop at `now_ns`: a HEARTBEAT when due; then, for the newest setpoint,
    /// either the report that the inputs went stale (once) or, while they are fresh, sending
    /// it again when `resend_period_ns` has passed since a setpoint last went out.
    pub fn on_tick(&mut self, now_ns: u64, autopilot: AutopilotView) -> Actions {
        let mut actions = Actions::default();
        if now_ns >= self.next_heartbeat_ns {
            actions.push(Action::SendHeartbeat);
            self.next_heartbeat_ns = now_ns.saturating_add(self.timing.heartbeat_period_ns);
        }
        let Some(Newest {
            setpoint,
            arrived_ns,
        }) = self.newest
        else {
            return actions;
        };
        let age_ns = now_ns.saturating_sub(arrived_ns);
        if age_ns > self.timing.input_timeout_ns {
            if !self.stale_reported {
                self.stale_reported = true;
                actions.push(Action::ReportStale {
                    quiet: quiet(setpoint),
                    silent_for_ns: age_ns,
                });
            }
        } else if now_ns.saturating_sub(self.last_sent_ns) >= self.timing.resend_period_ns {
            if let Some(action) = self.command(setpoint, now_ns, autopilot) {
                actions.push(action);
            }
        }
        actions
    }

    /// The last [`Action::SendSetpoint`] went out (call it only then): the resend period
    /// counts from the event that asked for it. A setpoint that failed to go out is asked for
    /// again on the next tick.
    pub fn on_sent(&mut self) {
        if let Some(at_ns) = self.pending_ns.take() {
            self.last_sent_ns = at_ns;
        }
    }

    /// [`Action::SendSetpoint`] if `autopilot` may be commanded with `setpoint` now.
    fn command(
        &mut self,
        setpoint: Setpoint,
        now_ns: u64,
        autopilot: AutopilotView,
    ) -> Option<Action> {
        self.pending_ns = None;
        let target = autopilot.target?;
        if !may_command(setpoint.task, autopilot.follows_setpoints) {
            return None;
        }
        self.pending_ns = Some(now_ns);
        Some(Action::SendSetpoint { setpoint, target })
    }
}

/// `setpoint` as the record of going silent: Hold, zero velocity, not sent.
fn quiet(setpoint: Setpoint) -> Setpoint {
    Setpoint {
        task: ApproachTask::Hold,
        sent: false,
        vx_m_s: 0.0,
        vy_m_s: 0.0,
        vz_m_s: 0.0,
        yaw_rate_rad_s: 0.0,
        reason: Text64::new("inputs stale: silent"),
        ..setpoint
    }
}

#[cfg(test)]
mod tests;
