//! Replayed control (`hubtrack-control --replay`, started by `hubtrack replay`): no autopilot.
//!
//! `hubtrack replay` publishes the recorded vehicle states on the vehicle service, each before
//! the track state that followed it live. For every track state this steps the approach once
//! with the newest vehicle state received, at the track's capture time, and decides `sent` by the
//! live rule ([`may_command`] on [`follows_setpoints`]) judged on that vehicle state as it stands
//! at the track's capture time ([`aged_state`]), not on the wall clock. Nothing is resent and
//! nothing goes stale on wall-clock timers: replay may run slower or faster than the recording.

use crate::setpoint::{Controller, TRACK_BUFFER};
use crate::ControlStage;
use hubtrack_control_stage::may_command;
use hubtrack_mavlink::{aged_state, follows_setpoints};
use hubtrack_runtime::ipc::MsgSubscriber;
use hubtrack_runtime::stage::Stage;
use hubtrack_types::services::{TRACK, VEHICLE};
use hubtrack_types::time::monotonic_ns;
use hubtrack_types::{Setpoint, TrackState, VehicleState};
use std::time::Duration;

/// Longest sleep between checks for shutdown when no track state comes.
const INPUT_WAIT: Duration = Duration::from_millis(50);
/// Vehicle states buffered between track states; only the newest is used, so a full buffer
/// loses nothing that matters.
const VEHICLE_BUFFER: usize = 16;

/// Runs replayed control until SIGINT/SIGTERM.
pub fn run(stage: ControlStage) -> anyhow::Result<()> {
    let mut controller = Controller::new(&stage)?;
    let Stage {
        config,
        shutdown,
        node,
        mut status,
    } = stage;
    let cfg = &config.control;
    let ms_to_ns = |ms: u64| ms * 1_000_000;
    let (link_timeout_ns, state_timeout_ns) = (
        ms_to_ns(cfg.link_timeout_ms),
        ms_to_ns(cfg.vehicle_timeout_ms),
    );
    let tracks = MsgSubscriber::<TrackState>::new(&node, &TRACK, TRACK_BUFFER)?;
    let vehicles = MsgSubscriber::<VehicleState>::polling(&node, &VEHICLE, VEHICLE_BUFFER)?;
    log::info!("replay mode: no MAVLink link; vehicle states from the vehicle service, time from the track states");
    // Before the first vehicle state, what live control sees before the autopilot is heard from.
    let mut vehicle = VehicleState::default();
    let mut vehicles_received = 0u64;

    while !shutdown.requested() {
        status.tick();
        tracks.wait(INPUT_WAIT);
        while let Some(track) = tracks.receive()? {
            let recv_ns = monotonic_ns();
            status.status.inputs += 1;
            // Replay published the vehicle states that preceded this track state before it.
            while let Some(v) = vehicles.receive()? {
                vehicle = v;
                vehicles_received += 1;
            }
            let now_ns = track.stamps.capture_ns;
            let at_track = aged_state(&vehicle, now_ns, link_timeout_ns, state_timeout_ns);
            let setpoint = controller.step(&track, &at_track, recv_ns);
            let sent = may_command(setpoint.task, follows_setpoints(&at_track));
            controller.publish(Setpoint { sent, ..setpoint }, &mut status)?;
        }
    }
    status.publish_now();
    log::info!(
        "stopped: {} setpoints published from {} track states and {} vehicle states",
        status.status.outputs,
        status.status.inputs,
        vehicles_received
    );
    Ok(())
}
