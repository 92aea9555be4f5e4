//! `hubtrack-track`: one `TrackState` per `Detection` (a prediction when the frame had no hub),
//! using the newest vehicle state to predict the hub's motion through turns.

use clap::Parser;
use hubtrack_runtime::ipc::{MsgPublisher, MsgSubscriber};
use hubtrack_runtime::stage::{Stage, StageArgs};
use hubtrack_track::Tracker;
use hubtrack_types::services::{DETECTIONS, TRACK, VEHICLE};
use hubtrack_types::time::monotonic_ns;
use hubtrack_types::{Detection, Stamps, TrackState, VehicleState};
use std::time::Duration;

/// Longest sleep between checks for shutdown when no detection comes.
const INPUT_WAIT: Duration = Duration::from_millis(50);
/// Detections buffered between wake-ups (every detection is used, in order).
const DETECTION_BUFFER: usize = 16;

#[derive(Parser)]
#[command(
    name = "hubtrack-track",
    about = "Track the hub through the detections"
)]
struct Args {
    #[command(flatten)]
    stage: StageArgs,
}

hubtrack_runtime::sections! {
    /// What the track stage reads.
    struct TrackSections {
        camera: hubtrack_types::setup::CameraSetup,
        turbine: hubtrack_types::setup::TurbineSetup,
        track: hubtrack_track::params::TrackConfig,
    }
}

fn main() {
    hubtrack_runtime::exit_with(run());
}

fn run() -> anyhow::Result<()> {
    let args = Args::parse();
    let Some(Stage {
        config,
        shutdown,
        node,
        mut status,
    }) = Stage::<TrackSections>::start("track", &args.stage)?
    else {
        return Ok(());
    };
    let lens = hubtrack_types::setup::Lens::new(&config.camera)?;
    let track = config.track.with_setup(&lens, &config.turbine);
    let mut tracker = Tracker::new(track).map_err(|e| anyhow::anyhow!("{e}"))?;

    let detections = MsgSubscriber::<Detection>::new(&node, &DETECTIONS, DETECTION_BUFFER)?;
    let vehicle = MsgSubscriber::<VehicleState>::polling(&node, &VEHICLE, 4)?;
    let track = MsgPublisher::<TrackState>::new(&node, &TRACK)?;
    let mut last_vehicle: Option<VehicleState> = None;
    let mut last_seq: Option<u64> = None;

    while !shutdown.requested() {
        status.tick();
        detections.wait(INPUT_WAIT);
        while let Some(det) = detections.receive()? {
            let recv_ns = monotonic_ns();
            // The newest vehicle state for every detection, also for one already queued behind
            // the previous: a replay publishes the next detection right after our output, with
            // the vehicle states that preceded it live.
            if let Some(v) = vehicle.receive_newest()? {
                last_vehicle = Some(v);
            }
            status.status.inputs += 1;
            if let Some(last) = last_seq {
                status.status.skipped += det.stamps.seq.saturating_sub(last + 1);
            }
            last_seq = Some(det.stamps.seq);
            let mut state = tracker.update(&det, last_vehicle.as_ref());
            state.stamps = Stamps {
                seq: det.stamps.seq,
                capture_ns: det.stamps.capture_ns,
                recv_ns,
                publish_ns: monotonic_ns(),
            };
            track.publish(state)?;
            status.status.outputs += 1;
        }
    }
    status.publish_now();
    log::info!("published {} track states", status.status.outputs);
    Ok(())
}
