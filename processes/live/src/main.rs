//! `hubtrack-live`: subscribes to the frames and the result services and serves them live to
//! Foxglove or Lichtblick through the Foxglove WebSocket protocol (`[live]` in the config).
//!
//! One thread reads shared memory and decides what goes out (newest frame only, within the
//! frame-rate and bitrate caps, encoded only while someone watches); the SDK's server threads
//! write to the sockets from bounded per-client queues. The supervisor runs it at a lower
//! priority than the camera and detect.

use clap::Parser;
use hubtrack_live::server::LiveServer;
use hubtrack_live::view::{FrameOutcome, LiveView};
use hubtrack_record::ChannelKind;
use hubtrack_runtime::config::LiveSections;
use hubtrack_runtime::ipc::{FrameSubscriber, MsgSubscriber};
use hubtrack_runtime::stage::{Stage, StageArgs};
use hubtrack_types::services::{DETECTIONS, OVERLAY, SETPOINTS, STATUS, TRACK, VEHICLE};
use hubtrack_types::time::monotonic_ns;
use hubtrack_types::{DetectOverlay, Detection, Setpoint, StageStatus, TrackState, VehicleState};
use std::time::{Duration, Instant};

/// Sleep between checks for frames, messages and shutdown.
const READER_WAIT: Duration = Duration::from_millis(5);
/// Result-service receive buffer (a few sleeps' worth of every stage's messages).
const RESULT_BUFFER: usize = 64;
/// Frames kept in the receive buffer: only the newest is ever sent.
const FRAME_BUFFER: usize = 2;
/// How often the stage logs what it sent.
const REPORT_INTERVAL: Duration = Duration::from_secs(10);

#[derive(Parser)]
#[command(
    name = "hubtrack-live",
    about = "Serve the running pipeline live through the Foxglove WebSocket protocol"
)]
struct Args {
    #[command(flatten)]
    stage: StageArgs,
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
    }) = Stage::<LiveSections>::start("live", &args.stage)?
    else {
        return Ok(());
    };
    let cfg = config.live;
    let mut server = LiveServer::start(&cfg)?;

    let mut frames = FrameSubscriber::polling(&node, FRAME_BUFFER)?;
    let detections = MsgSubscriber::<Detection>::polling(&node, &DETECTIONS, RESULT_BUFFER)?;
    let track = MsgSubscriber::<TrackState>::polling(&node, &TRACK, RESULT_BUFFER)?;
    let setpoints = MsgSubscriber::<Setpoint>::polling(&node, &SETPOINTS, RESULT_BUFFER)?;
    let vehicle = MsgSubscriber::<VehicleState>::polling(&node, &VEHICLE, RESULT_BUFFER)?;
    let status_in = MsgSubscriber::<StageStatus>::polling(&node, &STATUS, RESULT_BUFFER)?;
    let overlays = MsgSubscriber::<DetectOverlay>::polling(
        &node,
        &OVERLAY,
        OVERLAY.qos.subscriber_max_buffer_size,
    )?;

    let mut view = LiveView::new(server.channels.clone(), &cfg)?;
    let mut received = 0u64;
    let mut report_at = Instant::now();
    let mut reported = view.stats;
    while !shutdown.requested() {
        frames.wait(READER_WAIT);
        let now = monotonic_ns();
        if let Some(sample) = frames.receive_newest()? {
            received += 1;
            let header = *sample.user_header();
            if view.offer_frame(&header, sample.payload(), now) == FrameOutcome::Bad {
                status.error(&format!("frame {} not encoded", header.seq));
            }
            drop(sample);
            view.offer_message(ChannelKind::FrameHeader, "", &header, now);
        }
        while let Some(m) = detections.receive()? {
            view.offer_message(ChannelKind::Detection, "", &m, now);
        }
        while let Some(m) = track.receive()? {
            view.offer_message(ChannelKind::Track, "", &m, now);
        }
        while let Some(m) = setpoints.receive()? {
            view.offer_message(ChannelKind::Setpoint, "", &m, now);
        }
        while let Some(m) = vehicle.receive()? {
            view.offer_message(ChannelKind::Vehicle, "", &m, now);
        }
        while let Some(m) = status_in.receive()? {
            view.offer_message(ChannelKind::Status, m.stage.as_str(), &m, now);
        }
        while let Some(o) = overlays.receive()? {
            view.offer_overlay(&o, now);
        }
        let s = view.stats;
        status.status.inputs = received + frames.skipped;
        status.status.outputs = s.frames_sent;
        status.status.skipped = frames.skipped + s.frames_skipped;
        status.status.dropped = frames.lost;
        status.tick();
        if report_at.elapsed() >= REPORT_INTERVAL {
            let dt = report_at.elapsed().as_secs_f64();
            report_at = Instant::now();
            log::info!(
                "live view: {} client(s); {:.1} frames/s, {:.0} kbit/s, {:.1} messages/s sent",
                server.clients(),
                (s.frames_sent - reported.frames_sent) as f64 / dt,
                (s.bytes_sent - reported.bytes_sent) as f64 * 8.0 / 1000.0 / dt,
                (s.messages_sent - reported.messages_sent) as f64 / dt,
            );
            reported = s;
        }
    }
    server.stop();
    let s = view.stats;
    log::info!(
        "live view stopped: {} frames sent, {} skipped, {} not encodable, {} messages, {} bytes",
        s.frames_sent,
        s.frames_skipped + frames.skipped,
        s.frames_bad,
        s.messages_sent,
        s.bytes_sent
    );
    Ok(())
}
