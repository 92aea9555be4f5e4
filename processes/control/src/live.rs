//! Live control: the MAVLink link to the autopilot, the vehicle state derived from it, and the
//! setpoints sent over it on every track state and repeated on wall-clock timers.
//!
//! When to send what is the [`CommandGate`]'s decision; this loop only feeds it the events with
//! their wall-clock time and performs its actions.

use crate::config::ClockSource;
use crate::setpoint::{Controller, TRACK_BUFFER};
use crate::ControlStage;
use anyhow::Context;
use hubtrack_control_stage::gate::{Action, AutopilotView, CommandGate, GateTiming};
use hubtrack_mavlink::mavlink::MessageData;
use hubtrack_mavlink::{
    companion_heartbeat, follows_setpoints, velocity_setpoint, Endpoint, Link, MavHeader,
    MavMessage, SetpointFrame, Signing, SigningKey, StreamRequests, VehicleMonitor, WantedStream,
};
use hubtrack_runtime::ipc::{MsgPublisher, MsgSubscriber};
use hubtrack_runtime::stage::Stage;
use hubtrack_runtime::status::StatusReporter;
use hubtrack_types::services::{CLOCK, TRACK, VEHICLE};
use hubtrack_types::time::monotonic_ns;
use hubtrack_types::{Setpoint, SimClock, TrackState};
use std::time::Duration;

/// Longest the loop sleeps waiting for a track state before polling the MAVLink link again: a
/// track state wakes it at once (the setpoint path has no polling delay), autopilot messages are
/// handled within this bound.
const LINK_POLL: Duration = Duration::from_millis(2);
/// How often link counters are logged when they changed.
const STATS_LOG_INTERVAL_NS: u64 = 10_000_000_000;

/// The sending side of the link: numbers every message and stamps setpoints.
struct Sender {
    link: Link,
    header: MavHeader,
    frame: SetpointFrame,
}

impl Sender {
    /// Sends one message, numbering it; a failure is logged and counted, never fatal.
    fn send(&mut self, msg: &MavMessage, status: &mut StatusReporter) -> bool {
        self.header.sequence = self.header.sequence.wrapping_add(1);
        match self.link.send(self.header, msg) {
            Ok(()) => true,
            Err(e) => {
                log::warn!("send: {e}");
                status.error(&e.to_string());
                false
            }
        }
    }

    /// Sends `setpoint` to `target` stamped `uptime_ms`; returns whether it went out.
    fn send_setpoint(
        &mut self,
        setpoint: &Setpoint,
        target: (u8, u8),
        uptime_ms: u32,
        status: &mut StatusReporter,
    ) -> bool {
        let v = [
            setpoint.vx_m_s as f32,
            setpoint.vy_m_s as f32,
            setpoint.vz_m_s as f32,
        ];
        let msg = velocity_setpoint(
            target,
            uptime_ms,
            self.frame,
            v,
            setpoint.yaw_rate_rad_s as f32,
        );
        self.send(&msg, status)
    }

    /// Performs one action of the gate and tells it whether a setpoint went out; returns that.
    fn perform(
        &mut self,
        action: Action,
        gate: &mut CommandGate,
        controller: &Controller,
        uptime_ms: u32,
        status: &mut StatusReporter,
    ) -> anyhow::Result<bool> {
        match action {
            Action::SendHeartbeat => {
                self.send(&companion_heartbeat(), status);
                Ok(false)
            }
            Action::SendSetpoint { setpoint, target } => {
                let sent = self.send_setpoint(&setpoint, target, uptime_ms, status);
                if sent {
                    gate.on_sent();
                }
                Ok(sent)
            }
            Action::ReportStale {
                quiet,
                silent_for_ns,
            } => {
                log::warn!(
                    "inputs stale: no track state for {} ms; sending nothing, the autopilot's guided timeout will stop the vehicle",
                    silent_for_ns / 1_000_000
                );
                controller.publish(quiet, status)?;
                Ok(false)
            }
        }
    }
}

/// MAVLink message id of ATTITUDE (30).
const ATTITUDE_ID: u32 = <hubtrack_mavlink::common::ATTITUDE_DATA as MessageData>::ID;
/// MAVLink message id of LOCAL_POSITION_NED (32).
const LOCAL_POSITION_NED_ID: u32 =
    <hubtrack_mavlink::common::LOCAL_POSITION_NED_DATA as MessageData>::ID;

/// Logs what the autopilot says that an operator must see: its STATUSTEXTs (pre-arm failures,
/// EKF and GPS state, failsafes; warnings and worse at warn level) and refused commands.
fn report_autopilot_text(msg: &MavMessage) {
    use hubtrack_mavlink::common::{MavResult, MavSeverity};
    match msg {
        MavMessage::STATUSTEXT(t) => {
            let text = t.text.to_str().unwrap_or("?").trim_end_matches('\0');
            if (t.severity as u32) <= MavSeverity::MAV_SEVERITY_WARNING as u32 {
                log::warn!("autopilot says: {text}");
            } else {
                log::info!("autopilot says: {text}");
            }
        }
        MavMessage::COMMAND_ACK(a) if a.result != MavResult::MAV_RESULT_ACCEPTED => {
            log::warn!("autopilot refused {:?}: {:?}", a.command, a.result);
        }
        _ => {}
    }
}

/// The signing refusals for the link log lines.
fn signing_counts(s: &hubtrack_mavlink::LinkStats) -> String {
    format!(
        "refused by signing: {} unsigned, {} bad signatures, {} replayed",
        s.unsigned_refused, s.bad_signatures, s.old_timestamps
    )
}

/// Runs live control until SIGINT/SIGTERM.
pub fn run(stage: ControlStage) -> anyhow::Result<()> {
    let mut controller = Controller::new(&stage)?;
    let Stage {
        config,
        shutdown,
        node,
        mut status,
    } = stage;
    let cfg = &config.control;
    let endpoint: Endpoint = cfg.link.parse().context("control.link")?;
    let mut link = Link::open(&endpoint)
        .with_context(|| format!("cannot open the autopilot link {endpoint}"))?;
    // The autopilot shares the vehicle's system id; nobody else steers the link.
    let autopilot_id = hubtrack_mavlink::AutopilotId {
        system_id: cfg.system_id,
        component_id: cfg.autopilot_component_id,
    };
    link.expect_autopilot(autopilot_id);
    if !cfg.signing_key_file.is_empty() {
        let key = SigningKey::load(std::path::Path::new(&cfg.signing_key_file))
            .context("control.signing_key_file")?;
        link.enable_signing(Signing::new(key, cfg.signing_link_id));
        log::info!(
            "MAVLink 2 signing on: key {}, link id {}; unsigned and wrongly signed frames are refused",
            cfg.signing_key_file,
            cfg.signing_link_id
        );
    }
    match link.local_addr() {
        Some(local) => log::info!(
            "MAVLink link {endpoint} (local {local}) as system {} component {}",
            cfg.system_id,
            cfg.component_id
        ),
        None => log::info!(
            "MAVLink link {endpoint} as system {} component {}",
            cfg.system_id,
            cfg.component_id
        ),
    }
    let mut sender = Sender {
        link,
        header: MavHeader {
            system_id: cfg.system_id.into(),
            component_id: cfg.component_id,
            sequence: 0,
        },
        frame: cfg.setpoint_frame,
    };

    let tracks = MsgSubscriber::<TrackState>::new(&node, &TRACK, TRACK_BUFFER)?;
    let clock = match cfg.clock {
        ClockSource::Sim => Some(MsgSubscriber::<SimClock>::polling(&node, &CLOCK, 4)?),
        ClockSource::Monotonic => None,
    };
    let vehicle_out = MsgPublisher::new(&node, &VEHICLE)?;

    let ms_to_ns = |ms: u64| ms * 1_000_000;
    let mut monitor = VehicleMonitor::new(
        ms_to_ns(cfg.link_timeout_ms),
        ms_to_ns(cfg.vehicle_timeout_ms),
    )
    .expect_autopilot(autopilot_id);
    let started_ns = monotonic_ns();
    // Heartbeat, resending and staleness run on the wall clock, whatever `control.clock` says.
    let mut gate = CommandGate::new(GateTiming::from_rates(
        cfg.heartbeat_hz,
        cfg.setpoint_rate_hz,
        cfg.input_timeout_ms,
    ));
    // ArduPilot sends a link only the messages asked for; asked again whenever one stops.
    let mut streams = StreamRequests::new(
        &[
            WantedStream {
                message_id: ATTITUDE_ID,
                rate_hz: cfg.attitude_rate_hz,
            },
            WantedStream {
                message_id: LOCAL_POSITION_NED_ID,
                rate_hz: cfg.position_rate_hz,
            },
        ],
        ms_to_ns(cfg.stream_retry_ms),
        ms_to_ns(cfg.stream_retry_ms),
    );
    // Not heard from yet.
    let mut autopilot = AutopilotView::default();
    let mut sim_now_ns = 0u64;
    let mut last_stats_log_ns = started_ns;
    let mut last_stats = sender.link.stats();

    while !shutdown.requested() {
        status.tick();
        let wall_ns = monotonic_ns();
        let uptime_ms = ((wall_ns - started_ns) / 1_000_000) as u32;

        // Our heartbeat when due, so ArduPilot (and a GCS) sees the companion; between track
        // states the newest command repeated while it is fresh, silence once it is stale
        // (judged on the autopilot as the previous turn left it).
        for action in gate.on_tick(wall_ns, autopilot) {
            sender.perform(action, &mut gate, &controller, uptime_ms, &mut status)?;
        }

        // Autopilot → vehicle state (without blocking: the wait is on the track service below).
        let received = match sender.link.recv(Duration::ZERO) {
            Ok(msgs) => msgs,
            Err(e) => {
                log::error!("link {endpoint}: {e}");
                status.error(&e.to_string());
                std::thread::sleep(LINK_POLL);
                Vec::new()
            }
        };
        if let Some(c) = clock
            .as_ref()
            .map(|c| c.receive_newest())
            .transpose()?
            .flatten()
        {
            sim_now_ns = c.now_ns;
        }
        let now_ns = match cfg.clock {
            ClockSource::Monotonic => monotonic_ns(),
            ClockSource::Sim => sim_now_ns,
        };
        let mut vehicle_changed = false;
        for (h, msg) in &received {
            for event in monitor.handle(now_ns, h, msg) {
                log::info!("autopilot: {event}");
            }
            let from_autopilot = monitor.target() == Some((h.system_id as u8, h.component_id));
            if from_autopilot {
                streams.seen(wall_ns, msg);
                report_autopilot_text(msg);
            }
            vehicle_changed = true;
        }
        for request in streams.poll(wall_ns, monitor.target()) {
            sender.send(&request, &mut status);
        }
        for event in monitor.poll(now_ns) {
            log::warn!("autopilot: {event}");
            vehicle_changed = true;
        }
        let vehicle = monitor.state(now_ns);
        if vehicle_changed {
            let mut v = vehicle;
            v.publish_ns = monotonic_ns();
            vehicle_out.publish(v)?;
        }
        autopilot = AutopilotView {
            target: monitor.target(),
            follows_setpoints: follows_setpoints(&vehicle),
        };

        // Track → approach → setpoint, sent at once if the gate allows.
        tracks.wait(LINK_POLL);
        while let Some(track) = tracks.receive()? {
            let recv_ns = monotonic_ns();
            status.status.inputs += 1;
            let setpoint = controller.step(&track, &vehicle, recv_ns);
            let sent = match gate.on_track(setpoint, recv_ns, autopilot) {
                Some(action) => {
                    sender.perform(action, &mut gate, &controller, uptime_ms, &mut status)?
                }
                None => false,
            };
            controller.publish(Setpoint { sent, ..setpoint }, &mut status)?;
        }

        let stats = sender.link.stats();
        if stats != last_stats && wall_ns.saturating_sub(last_stats_log_ns) >= STATS_LOG_INTERVAL_NS
        {
            log::info!(
                "link: {} frames in, {} out; skipped {} garbage bytes, {} CRC errors, {} unknown messages; {}",
                stats.frames_in, stats.frames_out, stats.garbage_bytes, stats.crc_errors, stats.unknown_ids,
                signing_counts(&stats)
            );
            status.status.dropped = stats.garbage_bytes
                + stats.crc_errors
                + stats.parse_errors
                + stats.unsigned_refused
                + stats.bad_signatures
                + stats.old_timestamps;
            last_stats = stats;
            last_stats_log_ns = wall_ns;
        }
    }
    status.publish_now();
    let s = sender.link.stats();
    log::info!(
        "stopped: {} setpoints published; link {} frames in, {} out, {} garbage bytes, {} CRC errors, {} unknown; {}",
        status.status.outputs, s.frames_in, s.frames_out, s.garbage_bytes, s.crc_errors, s.unknown_ids,
        signing_counts(&s)
    );
    Ok(())
}
