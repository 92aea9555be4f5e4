//! Live control: the MAVLink link to the autopilot, the vehicle state derived from it, and the
//! setpoints sent over it on every track state and repeated on wall-clock timers.

use crate::config::{ClockSource, ControlConfig};
use crate::setpoint::{may_command, Controller, TRACK_BUFFER};
use crate::ControlStage;
use anyhow::Context;
use hubtrack_mavlink::{
    companion_heartbeat, velocity_setpoint, Endpoint, Link, MavHeader, VehicleMonitor,
};
use hubtrack_runtime::ipc::{MsgPublisher, MsgSubscriber};
use hubtrack_runtime::stage::Stage;
use hubtrack_runtime::status::StatusReporter;
use hubtrack_types::services::{CLOCK, TRACK, VEHICLE};
use hubtrack_types::time::monotonic_ns;
use hubtrack_types::{ApproachTask, Setpoint, SimClock, Text64, TrackState};
use std::time::Duration;

/// Longest the loop sleeps waiting for a track state before polling the MAVLink link again: a
/// track state wakes it at once (the setpoint path has no polling delay), autopilot messages are
/// handled within this bound.
const LINK_POLL: Duration = Duration::from_millis(2);
/// How often link counters are logged when they changed.
const STATS_LOG_INTERVAL_NS: u64 = 10_000_000_000;

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
    );
    let started_ns = monotonic_ns();
    let mut header = MavHeader {
        system_id: cfg.system_id.into(),
        component_id: cfg.component_id,
        sequence: 0,
    };
    let heartbeat_period_ns = (1e9 / cfg.heartbeat_hz) as u64;
    let resend_period_ns = (1e9 / cfg.setpoint_rate_hz) as u64;
    let input_timeout_ns = ms_to_ns(cfg.input_timeout_ms);
    let mut next_heartbeat_ns = 0;
    let mut sim_now_ns = 0u64;
    // The newest command and when (wall clock) its track arrived and it was last sent.
    let mut last: Option<(Setpoint, u64)> = None;
    let mut last_sent_ns = 0u64;
    let mut stale_reported = false;
    let mut last_stats_log_ns = started_ns;
    let mut last_stats = link.stats();

    while !shutdown.requested() {
        status.tick();
        let wall_ns = monotonic_ns();
        let uptime_ms = ((wall_ns - started_ns) / 1_000_000) as u32;

        // Our heartbeat, so ArduPilot (and a GCS) sees the companion.
        if wall_ns >= next_heartbeat_ns {
            send(&mut link, &mut header, &companion_heartbeat(), &mut status);
            next_heartbeat_ns = wall_ns + heartbeat_period_ns;
        }

        // Autopilot → vehicle state (without blocking: the wait is on the track service below).
        let received = match link.recv(Duration::ZERO) {
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
            vehicle_changed = true;
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

        // Track → approach → setpoint.
        tracks.wait(LINK_POLL);
        while let Some(track) = tracks.receive()? {
            let recv_ns = monotonic_ns();
            status.status.inputs += 1;
            let setpoint = controller.step(&track, &vehicle, recv_ns);
            last = Some((setpoint, recv_ns));
            stale_reported = false;
            let sent = command(
                &mut link,
                &mut header,
                &monitor,
                now_ns,
                cfg,
                uptime_ms,
                &setpoint,
                &mut status,
            );
            if sent {
                last_sent_ns = recv_ns;
            }
            controller.publish(Setpoint { sent, ..setpoint }, &mut status)?;
        }

        // Between track states: repeat the newest command at the configured rate while it is
        // fresh; once stale, go silent (and say so once).
        if let Some((setpoint, track_wall_ns)) = last {
            let now_wall = monotonic_ns();
            if now_wall.saturating_sub(track_wall_ns) > input_timeout_ns {
                if !stale_reported {
                    log::warn!(
                        "inputs stale: no track state for {} ms; sending nothing, the autopilot's guided timeout will stop the vehicle",
                        (now_wall - track_wall_ns) / 1_000_000
                    );
                    let quiet = Setpoint {
                        task: ApproachTask::Hold,
                        sent: false,
                        vx_m_s: 0.0,
                        vy_m_s: 0.0,
                        vz_m_s: 0.0,
                        yaw_rate_rad_s: 0.0,
                        reason: Text64::new("inputs stale: silent"),
                        ..setpoint
                    };
                    controller.publish(quiet, &mut status)?;
                    stale_reported = true;
                }
            } else if now_wall.saturating_sub(last_sent_ns) >= resend_period_ns
                && command(
                    &mut link,
                    &mut header,
                    &monitor,
                    now_ns,
                    cfg,
                    uptime_ms,
                    &setpoint,
                    &mut status,
                )
            {
                last_sent_ns = now_wall;
            }
        }

        let stats = link.stats();
        if stats != last_stats && wall_ns.saturating_sub(last_stats_log_ns) >= STATS_LOG_INTERVAL_NS
        {
            log::info!(
                "link: {} frames in, {} out; skipped {} garbage bytes, {} CRC errors, {} unknown messages",
                stats.frames_in, stats.frames_out, stats.garbage_bytes, stats.crc_errors, stats.unknown_ids
            );
            status.status.dropped = stats.garbage_bytes + stats.crc_errors + stats.parse_errors;
            last_stats = stats;
            last_stats_log_ns = wall_ns;
        }
    }
    status.publish_now();
    let s = link.stats();
    log::info!(
        "stopped: {} setpoints published; link {} frames in, {} out, {} garbage bytes, {} CRC errors, {} unknown",
        status.status.outputs, s.frames_in, s.frames_out, s.garbage_bytes, s.crc_errors, s.unknown_ids
    );
    Ok(())
}

/// Sends `setpoint` to the autopilot if it may be commanded ([`may_command`] with the
/// monitor's view at `now_ns`); returns whether it was sent.
#[allow(clippy::too_many_arguments)]
fn command(
    link: &mut Link,
    header: &mut MavHeader,
    monitor: &VehicleMonitor,
    now_ns: u64,
    cfg: &ControlConfig,
    uptime_ms: u32,
    setpoint: &Setpoint,
    status: &mut StatusReporter,
) -> bool {
    let Some(target) = monitor.target() else {
        return false;
    };
    if !may_command(setpoint.task, monitor.guided_and_armed(now_ns)) {
        return false;
    }
    let v = [
        setpoint.vx_m_s as f32,
        setpoint.vy_m_s as f32,
        setpoint.vz_m_s as f32,
    ];
    let msg = velocity_setpoint(
        target,
        uptime_ms,
        cfg.setpoint_frame,
        v,
        setpoint.yaw_rate_rad_s as f32,
    );
    send(link, header, &msg, status)
}

/// Sends one message, numbering it; a failure is logged and counted, never fatal.
fn send(
    link: &mut Link,
    header: &mut MavHeader,
    msg: &hubtrack_mavlink::MavMessage,
    status: &mut StatusReporter,
) -> bool {
    header.sequence = header.sequence.wrapping_add(1);
    match link.send(*header, msg) {
        Ok(()) => true,
        Err(e) => {
            log::warn!("send: {e}");
            status.error(&e.to_string());
            false
        }
    }
}
