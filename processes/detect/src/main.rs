//! `hubtrack-detect`: takes the newest frame from shared memory (counting the ones it skipped),
//! wraps its pixels without copying, runs the configured detector with the latest vehicle roll, and
//! publishes a `Detection` (with the frame's seq and capture time, and its own receive and publish
//! stamps) and the overlay of what it saw.

use clap::Parser;
use hubtrack_detect::{Detector, Hints, ImageView};
use hubtrack_runtime::ipc::{FrameSubscriber, MsgPublisher, MsgSubscriber};
use hubtrack_runtime::stage::{Stage, StageArgs};
use hubtrack_types::services::{DETECTIONS, OVERLAY, TRACK, VEHICLE};
use hubtrack_types::setup::Lens;
use hubtrack_types::time::monotonic_ns;
use hubtrack_types::{
    DetectOverlay, Detection, OverlayKind, OverlaySegment, Stamps, TrackState, VehicleState,
    MAX_OVERLAY_LINES,
};
use std::time::Duration;

/// Longest sleep between checks for shutdown when no frame comes.
const FRAME_WAIT: Duration = Duration::from_millis(50);
/// A vehicle attitude further than this from the frame's capture time is not used for roll
/// compensation (both on the pipeline clock, which is the simulator's clock in a simulation).
const MAX_ATTITUDE_AGE_NS: u64 = 200_000_000;

#[derive(Parser)]
#[command(
    name = "hubtrack-detect",
    about = "Detect the turbine hub in the newest frame"
)]
struct Args {
    #[command(flatten)]
    stage: StageArgs,
}

hubtrack_runtime::sections! {
    /// What the detect stage reads.
    struct DetectSections {
        camera: hubtrack_types::setup::CameraSetup,
        turbine: hubtrack_types::setup::TurbineSetup,
        detect: hubtrack_detect::params::DetectConfig,
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
    }) = Stage::<DetectSections>::start("detect", &args.stage)?
    else {
        return Ok(());
    };
    log::info!("mode {:?}", config.detect.mode);
    let lens = Lens::new(&config.camera)?;
    log::info!(
        "camera {}, turbine {}",
        config.camera.describe(),
        config.turbine.name
    );
    let detect = config.detect.with_setup(&lens, &config.turbine);
    let mut detector = Detector::new(detect)?;

    let mut frames = FrameSubscriber::new(&node, 1)?;
    let vehicle = MsgSubscriber::<VehicleState>::polling(&node, &VEHICLE, 4)?;
    // The tracker's prediction focuses the search (and finds the spinner at close range).
    let tracks = MsgSubscriber::<TrackState>::polling(&node, &TRACK, 4)?;
    let mut last_track: Option<TrackState> = None;
    let detections = MsgPublisher::<Detection>::new(&node, &DETECTIONS)?;
    let overlays = MsgPublisher::<DetectOverlay>::new(&node, &OVERLAY)?;
    let mut last_vehicle: Option<VehicleState> = None;

    while !shutdown.requested() {
        status.tick();
        frames.wait(FRAME_WAIT);
        if let Some(v) = vehicle.receive_newest()? {
            last_vehicle = Some(v);
        }
        if let Some(t) = tracks.receive_newest()? {
            last_track = Some(t);
        }
        let Some(sample) = frames.receive_newest()? else {
            continue;
        };
        let recv_ns = monotonic_ns();
        status.status.inputs += 1;
        let header = *sample.user_header();
        let image = ImageView {
            width: header.width,
            height: header.height,
            stride: header.stride as usize,
            format: header.format,
            data: sample.payload(),
        };
        let roll_rad = last_vehicle
            .filter(|v| {
                v.attitude_valid && header.capture_ns.abs_diff(v.recv_ns) < MAX_ATTITUDE_AGE_NS
            })
            .map(|v| v.roll_rad);
        let hints = Hints::for_frame(
            last_track.as_ref(),
            header.width,
            header.height,
            header.capture_ns,
            roll_rad,
        );
        let output = match detector.detect(&image, &hints) {
            Ok(o) => o,
            Err(e) => {
                log::error!("frame {}: {e}", header.seq);
                status.error(&e.to_string());
                continue;
            }
        };
        drop(sample); // the frame goes back to capture's pool before we publish
        let mut detection = output.detection;
        detection.frames_skipped = frames.skipped;
        detection.stamps = Stamps {
            seq: header.seq,
            capture_ns: header.capture_ns,
            recv_ns,
            publish_ns: 0,
        };
        let mut overlay = DetectOverlay {
            detection,
            ..Default::default()
        };
        for (slot, line) in overlay
            .segments
            .iter_mut()
            .zip(output.overlay.lines.iter().take(MAX_OVERLAY_LINES))
        {
            *slot = OverlaySegment {
                a: [line.a[0] as f32, line.a[1] as f32],
                b: [line.b[0] as f32, line.b[1] as f32],
                kind: match line.kind {
                    hubtrack_detect::LineKind::Tower => OverlayKind::Tower,
                    hubtrack_detect::LineKind::Blade => OverlayKind::Blade,
                    hubtrack_detect::LineKind::Rejected => OverlayKind::Rejected,
                    hubtrack_detect::LineKind::Other => OverlayKind::Other,
                },
            };
        }
        overlay.segment_count = output.overlay.lines.len().min(MAX_OVERLAY_LINES) as u32;
        if let Some([x, y, r]) = output.overlay.search_circle {
            overlay.search_circle = [x as f32, y as f32, r as f32];
        }
        detection.stamps.publish_ns = monotonic_ns();
        detections.publish(detection)?;
        overlay.detection = detection;
        overlay.stamps = detection.stamps;
        overlays.publish(overlay)?;
        status.status.outputs += 1;
        status.status.skipped = frames.skipped;
        status.status.dropped = frames.lost;
    }
    status.publish_now();
    log::info!(
        "processed {} frames, skipped {}",
        status.status.outputs,
        frames.skipped
    );
    Ok(())
}
