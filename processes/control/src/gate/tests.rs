//! The gate driven with scripted times; every test compares the exact sequence of actions.

use super::*;
use hubtrack_types::Stamps;

const MS: u64 = 1_000_000;
const AUTOPILOT: (u8, u8) = (1, 1);

/// Heard from, armed, GUIDED.
const FOLLOWS: AutopilotView = AutopilotView {
    target: Some(AUTOPILOT),
    follows_setpoints: true,
};
/// Heard from, but disarmed, not in GUIDED or its link timed out.
const NOT_FOLLOWING: AutopilotView = AutopilotView {
    target: Some(AUTOPILOT),
    follows_setpoints: false,
};
/// Never heard from.
const UNHEARD: AutopilotView = AutopilotView {
    target: None,
    follows_setpoints: false,
};

/// Heartbeat 1 Hz, resend 10 Hz, inputs stale after 500 ms.
fn timing() -> GateTiming {
    GateTiming::from_rates(1.0, 10.0, 500)
}

/// A setpoint of `task` for frame `seq`.
fn setpoint(task: ApproachTask, seq: u64) -> Setpoint {
    Setpoint {
        stamps: Stamps {
            seq,
            capture_ns: seq * 100 * MS,
            recv_ns: seq * 100 * MS + 7,
            publish_ns: 0,
        },
        task,
        sent: false,
        vx_m_s: 1.0,
        vy_m_s: -0.5,
        vz_m_s: 0.25,
        yaw_rate_rad_s: 0.1,
        reason: Text64::new("T3: 12.0 m to hub"),
    }
}

/// What happened at a time (ms), compactly.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Ev {
    Heartbeat,
    /// A setpoint sent: its frame and task.
    Send(u64, ApproachTask),
    /// The stale report: the frame of the quieted setpoint and the silence so far, ms.
    Stale(u64, u64),
}

/// Drives a gate and logs every action as `(ms, Ev)`; sends succeed unless `failing`.
struct Rig {
    gate: CommandGate,
    log: Vec<(u64, Ev)>,
    failing: bool,
}

impl Rig {
    fn new() -> Rig {
        Rig {
            gate: CommandGate::new(timing()),
            log: Vec::new(),
            failing: false,
        }
    }

    fn record(&mut self, ms: u64, action: Action) {
        let ev = match action {
            Action::SendHeartbeat => Ev::Heartbeat,
            Action::SendSetpoint { setpoint, target } => {
                assert_eq!(target, AUTOPILOT);
                if !self.failing {
                    self.gate.on_sent();
                }
                Ev::Send(setpoint.stamps.seq, setpoint.task)
            }
            Action::ReportStale {
                quiet,
                silent_for_ns,
            } => {
                assert_eq!(silent_for_ns % MS, 0, "whole ms in these scripts");
                Ev::Stale(quiet.stamps.seq, silent_for_ns / MS)
            }
        };
        self.log.push((ms, ev));
    }

    /// A track state's setpoint arrives at `ms`.
    fn track(&mut self, ms: u64, task: ApproachTask, seq: u64, view: AutopilotView) {
        if let Some(a) = self.gate.on_track(setpoint(task, seq), ms * MS, view) {
            self.record(ms, a);
        }
    }

    /// Ticks at `from`, `from + step`, ... up to `to` (ms, inclusive).
    fn ticks(&mut self, from: u64, to: u64, step: u64, view: AutopilotView) {
        for ms in (from..=to).step_by(step as usize) {
            self.tick(ms, view);
        }
    }

    fn tick(&mut self, ms: u64, view: AutopilotView) {
        for a in self.gate.on_tick(ms * MS, view) {
            self.record(ms, a);
        }
    }

    fn take(&mut self) -> Vec<(u64, Ev)> {
        std::mem::take(&mut self.log)
    }
}

use ApproachTask::{Abort, Approach, Hold};
use Ev::{Heartbeat, Send, Stale};

#[test]
fn timing_from_the_control_settings() {
    assert_eq!(
        GateTiming::from_rates(1.0, 15.0, 500),
        GateTiming {
            heartbeat_period_ns: 1_000_000_000,
            resend_period_ns: 66_666_666,
            input_timeout_ns: 500_000_000,
        }
    );
    assert_eq!(period_ns(0.2), 5_000_000_000);
}

#[test]
fn abort_is_never_sent_and_nothing_goes_to_a_vehicle_that_does_not_follow() {
    assert!(may_command(ApproachTask::Approach, true));
    assert!(may_command(ApproachTask::Hold, true));
    assert!(!may_command(ApproachTask::Abort, true));
    assert!(!may_command(ApproachTask::Approach, false));
}

#[test]
fn heartbeat_on_the_first_tick_then_once_a_period() {
    let mut rig = Rig::new();
    rig.ticks(0, 3000, 10, UNHEARD);
    assert_eq!(
        rig.take(),
        [
            (0, Heartbeat),
            (1000, Heartbeat),
            (2000, Heartbeat),
            (3000, Heartbeat)
        ]
    );
    // Whatever the autopilot's state: the heartbeat is how it sees the companion at all.
    rig.ticks(3010, 4000, 10, FOLLOWS);
    assert_eq!(rig.take(), [(4000, Heartbeat)]);
}

#[test]
fn the_heartbeat_period_runs_from_the_tick_that_sent_it() {
    let mut rig = Rig::new();
    for ms in [5, 999, 1004, 1005, 1006, 2004, 2005, 3006] {
        rig.tick(ms, UNHEARD);
    }
    assert_eq!(
        rig.take(),
        [
            (5, Heartbeat),
            (1005, Heartbeat),
            (2005, Heartbeat),
            (3006, Heartbeat)
        ]
    );
}

#[test]
fn a_new_setpoint_goes_out_at_once_and_again_every_resend_period_while_fresh() {
    let mut rig = Rig::new();
    rig.tick(0, FOLLOWS);
    rig.track(5, Approach, 1, FOLLOWS);
    rig.ticks(10, 340, 10, FOLLOWS);
    // A new track state: sent at once, and the period counts from it.
    rig.track(345, Approach, 2, FOLLOWS);
    rig.ticks(350, 460, 10, FOLLOWS);
    assert_eq!(
        rig.take(),
        [
            (0, Heartbeat),
            (5, Send(1, Approach)),
            (110, Send(1, Approach)),
            (210, Send(1, Approach)),
            (310, Send(1, Approach)),
            (345, Send(2, Approach)),
            (450, Send(2, Approach)),
        ]
    );
}

#[test]
fn every_track_state_is_sent_even_faster_than_the_resend_rate() {
    let mut rig = Rig::new();
    rig.tick(0, FOLLOWS);
    for (i, ms) in [10, 20, 30, 40].into_iter().enumerate() {
        rig.track(ms, Approach, i as u64 + 1, FOLLOWS);
        rig.tick(ms + 1, FOLLOWS);
    }
    assert_eq!(
        rig.take(),
        [
            (0, Heartbeat),
            (10, Send(1, Approach)),
            (20, Send(2, Approach)),
            (30, Send(3, Approach)),
            (40, Send(4, Approach)),
        ]
    );
}

#[test]
fn stale_inputs_go_silent_just_after_the_timeout_reported_once_until_a_new_track() {
    let mut rig = Rig::new();
    rig.track(0, Approach, 1, FOLLOWS);
    // At exactly the timeout the inputs still count as fresh.
    rig.ticks(0, 500, 100, FOLLOWS);
    rig.tick(501, FOLLOWS);
    rig.ticks(600, 2000, 100, FOLLOWS);
    assert_eq!(
        rig.take(),
        [
            (0, Send(1, Approach)),
            (0, Heartbeat),
            (100, Send(1, Approach)),
            (200, Send(1, Approach)),
            (300, Send(1, Approach)),
            (400, Send(1, Approach)),
            (500, Send(1, Approach)),
            (501, Stale(1, 501)),
            (1000, Heartbeat),
            (2000, Heartbeat),
        ]
    );

    // A new track state resumes sending at once; going stale again is reported again.
    rig.track(2050, Approach, 2, FOLLOWS);
    rig.ticks(2100, 2700, 50, FOLLOWS);
    assert_eq!(
        rig.take(),
        [
            (2050, Send(2, Approach)),
            (2150, Send(2, Approach)),
            (2250, Send(2, Approach)),
            (2350, Send(2, Approach)),
            (2450, Send(2, Approach)),
            (2550, Send(2, Approach)),
            (2600, Stale(2, 550)),
        ]
    );
}

#[test]
fn no_track_yet_means_heartbeats_only_and_no_stale_report() {
    let mut rig = Rig::new();
    rig.ticks(0, 5000, 100, FOLLOWS);
    assert!(rig
        .take()
        .iter()
        .all(|(ms, ev)| *ev == Heartbeat && ms % 1000 == 0));
}

#[test]
fn nothing_goes_to_an_autopilot_that_does_not_follow_setpoints() {
    let mut rig = Rig::new();
    rig.tick(0, UNHEARD);
    rig.track(10, Approach, 1, UNHEARD);
    rig.ticks(20, 200, 10, UNHEARD);
    rig.track(210, Approach, 2, NOT_FOLLOWING);
    rig.ticks(220, 400, 10, NOT_FOLLOWING);
    // No target, however it claims to follow: there is no one to send to.
    rig.ticks(
        410,
        420,
        10,
        AutopilotView {
            target: None,
            follows_setpoints: true,
        },
    );
    assert_eq!(rig.take(), [(0, Heartbeat)]);

    // It follows (armed, GUIDED): the newest fresh setpoint goes out on the next tick.
    rig.ticks(430, 650, 10, FOLLOWS);
    // Disarmed, mode changed or link lost: silence at once.
    rig.ticks(660, 700, 10, NOT_FOLLOWING);
    rig.track(705, Approach, 3, NOT_FOLLOWING);
    rig.ticks(710, 900, 10, NOT_FOLLOWING);
    // Back: sending resumes.
    rig.ticks(910, 920, 10, FOLLOWS);
    assert_eq!(
        rig.take(),
        [
            (430, Send(2, Approach)),
            (530, Send(2, Approach)),
            (630, Send(2, Approach)),
            (910, Send(3, Approach)),
        ]
    );
}

#[test]
fn a_stale_setpoint_is_never_sent() {
    let mut rig = Rig::new();
    rig.tick(0, NOT_FOLLOWING);
    rig.track(100, Approach, 1, NOT_FOLLOWING);
    rig.ticks(110, 600, 10, NOT_FOLLOWING);
    rig.tick(601, NOT_FOLLOWING);
    // Following now, but the only setpoint is stale.
    rig.ticks(610, 3000, 10, FOLLOWS);
    assert_eq!(
        rig.take(),
        [
            (0, Heartbeat),
            (601, Stale(1, 501)),
            (1000, Heartbeat),
            (2000, Heartbeat),
            (3000, Heartbeat),
        ]
    );
}

#[test]
fn a_hold_is_sent_like_any_task_and_an_abort_never() {
    let mut rig = Rig::new();
    rig.tick(0, FOLLOWS);
    rig.track(10, Hold, 1, FOLLOWS);
    rig.ticks(20, 200, 10, FOLLOWS);
    // An abort replaces the hold: neither is sent from now on.
    rig.track(205, Abort, 2, FOLLOWS);
    rig.ticks(210, 700, 10, FOLLOWS);
    rig.tick(706, FOLLOWS);
    // A hold again after the abort.
    rig.track(800, Hold, 3, FOLLOWS);
    assert_eq!(
        rig.take(),
        [
            (0, Heartbeat),
            (10, Send(1, Hold)),
            (110, Send(1, Hold)),
            (706, Stale(2, 501)),
            (800, Send(3, Hold)),
        ]
    );
}

#[test]
fn a_setpoint_that_failed_to_go_out_is_asked_for_again_on_the_next_tick() {
    let mut rig = Rig::new();
    rig.tick(0, FOLLOWS);
    rig.track(10, Approach, 1, FOLLOWS);
    rig.failing = true;
    rig.track(150, Approach, 2, FOLLOWS);
    rig.tick(152, FOLLOWS);
    rig.tick(154, FOLLOWS);
    rig.failing = false;
    rig.ticks(156, 300, 2, FOLLOWS);
    assert_eq!(
        rig.take(),
        [
            (0, Heartbeat),
            (10, Send(1, Approach)),
            (150, Send(2, Approach)),
            (152, Send(2, Approach)),
            (154, Send(2, Approach)),
            (156, Send(2, Approach)),
            (256, Send(2, Approach)),
        ]
    );
}

#[test]
fn on_sent_without_a_pending_send_changes_nothing() {
    let mut gate = CommandGate::new(timing());
    let before = gate.clone();
    gate.on_sent();
    assert_eq!(gate, before);
    // Not commanded: nothing is pending, so a stray on_sent does not restart the period
    // (from 100 ms it would hold the resend back until 200 ms).
    assert_eq!(
        gate.on_track(setpoint(Approach, 1), 100 * MS, NOT_FOLLOWING),
        None
    );
    gate.on_sent();
    let sent = gate.on_tick(150 * MS, FOLLOWS).collect::<Vec<_>>();
    assert_eq!(
        sent,
        [
            Action::SendHeartbeat,
            Action::SendSetpoint {
                setpoint: setpoint(Approach, 1),
                target: AUTOPILOT
            }
        ]
    );

    // Nor after a refusal that followed a send that failed: the refusal ends what was pending.
    let mut gate = CommandGate::new(timing());
    assert!(gate
        .on_track(setpoint(Approach, 1), 100 * MS, FOLLOWS)
        .is_some());
    assert_eq!(
        gate.on_track(setpoint(Approach, 2), 110 * MS, NOT_FOLLOWING),
        None
    );
    gate.on_sent();
    let sent = gate.on_tick(150 * MS, FOLLOWS).collect::<Vec<_>>();
    assert_eq!(
        sent,
        [
            Action::SendHeartbeat,
            Action::SendSetpoint {
                setpoint: setpoint(Approach, 2),
                target: AUTOPILOT
            }
        ]
    );
}

#[test]
fn the_actions_carry_the_setpoint_unchanged_and_the_stale_report_a_quiet_hold() {
    let mut gate = CommandGate::new(timing());
    let sp = setpoint(Approach, 9);
    assert_eq!(
        gate.on_track(sp, 1000 * MS, FOLLOWS),
        Some(Action::SendSetpoint {
            setpoint: sp,
            target: AUTOPILOT
        })
    );
    gate.on_sent();
    let actions = gate
        .on_tick(1000 * MS + 500 * MS + 1, FOLLOWS)
        .collect::<Vec<_>>();
    let quiet = Setpoint {
        task: Hold,
        sent: false,
        vx_m_s: 0.0,
        vy_m_s: 0.0,
        vz_m_s: 0.0,
        yaw_rate_rad_s: 0.0,
        reason: Text64::new("inputs stale: silent"),
        stamps: sp.stamps,
    };
    assert_eq!(
        actions,
        [
            Action::SendHeartbeat,
            Action::ReportStale {
                quiet,
                silent_for_ns: 500 * MS + 1,
            }
        ]
    );
    assert_eq!(gate.on_tick(1000 * MS + 600 * MS, FOLLOWS).next(), None);
}

#[test]
fn time_running_backwards_neither_panics_nor_sends_early() {
    let mut rig = Rig::new();
    rig.tick(1000, FOLLOWS);
    rig.track(1000, Approach, 1, FOLLOWS);
    rig.tick(900, FOLLOWS);
    rig.tick(1099, FOLLOWS);
    rig.tick(1100, FOLLOWS);
    assert_eq!(
        rig.take(),
        [
            (1000, Heartbeat),
            (1000, Send(1, Approach)),
            (1100, Send(1, Approach)),
        ]
    );
}
