//! `hubtrack-capture`: opens the configured frame source and publishes every frame zero-copy on
//! the frames service. Never blocks on readers; keeps running whatever happens to them.

use anyhow::Context;
use clap::Parser;
use hubtrack_capture::config::{CaptureSections, Pace};
use hubtrack_capture::pacing::Pacer;
use hubtrack_capture::sink::ShmSink;
use hubtrack_capture::synthetic::Filming;
use hubtrack_capture::{open_source, Step};
use hubtrack_runtime::ipc::{cleanup_dead_nodes, FramePublisher};
use hubtrack_runtime::stage::{Stage, StageArgs};
use std::time::{Duration, Instant};

/// How often capture removes resources of dead subscribers, so a restarted stage finds its port.
const DEAD_NODE_CLEANUP_INTERVAL: Duration = Duration::from_secs(1);

#[derive(Parser)]
#[command(
    name = "hubtrack-capture",
    about = "Publish camera frames on the hubtrack frames service"
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
    }) = Stage::<CaptureSections>::start("capture", &args.stage)?
    else {
        return Ok(());
    };
    let cfg = &config.capture;
    let filming = Filming::of(&config.camera, &config.turbine)?;
    let mut source = open_source(cfg, &filming)?;
    log::info!("source: {}", source.describe());
    let publisher = FramePublisher::new(&node, source.max_frame_len())?;
    let mut sink = ShmSink::new(publisher, source.kind());

    let fps = match (source.self_paced(), cfg.pace) {
        (true, _) | (false, Pace::Fast) => None,
        (false, Pace::Realtime) if cfg.fps > 0.0 => Some(cfg.fps),
        (false, Pace::Realtime) => source.native_fps(),
    };
    let mut pacer = Pacer::new(fps);
    let mut last_cleanup = Instant::now();
    log::info!(
        "publishing at {}",
        fps.map_or("source rate".into(), |f| format!("{f} fps"))
    );

    while !shutdown.requested() {
        if cfg.max_frames > 0 && sink.next_seq >= cfg.max_frames {
            log::info!("max_frames = {} reached", cfg.max_frames);
            break;
        }
        pacer.wait();
        match source.next_frame(&mut sink) {
            Ok(Step::Frame) => status.status.outputs = sink.next_seq,
            Ok(Step::End) => {
                log::info!("end of source after {} frames", sink.next_seq);
                break;
            }
            Err(e) if e.is_per_frame() => {
                log::error!("{e}; skipping this frame");
                status.error(&e.to_string());
            }
            Err(e) => {
                status.error(&e.to_string());
                status.publish_now();
                return Err(e).context("capture stopped");
            }
        }
        status.tick();
        if last_cleanup.elapsed() >= DEAD_NODE_CLEANUP_INTERVAL {
            let n = cleanup_dead_nodes(&node);
            if n > 0 {
                log::info!("removed resources of {n} dead node(s)");
            }
            last_cleanup = Instant::now();
        }
    }
    status.publish_now();
    log::info!("published {} frames", sink.next_seq);
    Ok(())
}
