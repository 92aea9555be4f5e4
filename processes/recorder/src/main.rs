//! `hubtrack-recorder`: subscribes to every service and writes one MCAP file.
//!
//! Two threads: the reader takes samples from shared memory as soon as they arrive and, once
//! detect is done with a frame, compresses it straight from shared memory (JPEG through libjpeg-turbo by default, or H.264:
//! `recorder.frame_encoding`; see `frames`); the writer writes. Each frame in flight holds one
//! buffer of a fixed pool: when the disk falls behind and the pool is empty, frames are dropped
//! and counted: the recorder never slows the camera (the camera never waits for anyone anyway:
//! safe overflow). The supervisor starts this process at a lower priority than the camera and
//! detect, so encoding can fall behind only into counted losses, never into the camera's or
//! detect's time. A frame that does not encode keeps its header and is counted
//! (`frames_encode_failed`). On SIGINT/SIGTERM the writer drains the queue and finishes the
//! file; after `kill -9` the file is readable up to its last flushed chunk (see
//! `hubtrack recover`).

mod frames;

use anyhow::Context;
use clap::Parser;
use frames::{FramePacker, HeldFrame, Pixels};
use hubtrack_record::config::{Compression, FrameEncoding, RecorderConfig};
use hubtrack_record::raw_window::RawWindow;
use hubtrack_record::writer::{ChannelKind, RecorderStats};
use hubtrack_record::{Recording, RecordingOptions};
use hubtrack_runtime::ipc::{FrameSubscriber, MsgSubscriber};
use hubtrack_runtime::stage::{Stage, StageArgs};
use hubtrack_runtime::status::StatusReporter;
use hubtrack_types::services::{
    DETECTIONS, FRAMES, LOG, OVERLAY, RAW_WINDOW, SETPOINTS, STATUS, TRACK, VEHICLE,
};
use hubtrack_types::time::{monotonic_ns, realtime_ns};
use hubtrack_types::{
    DetectOverlay, Detection, FrameHeader, LogLine, RawWindowRequest, Setpoint, StageStatus,
    TrackState, VehicleState,
};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, Receiver, SyncSender, TrySendError};
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

/// Sleep of the reader between checks for frames, shutdown and the other services.
const READER_WAIT: Duration = Duration::from_millis(5);
/// Longest a frame waits for detect to be done with it before it is compressed anyway (detect
/// not running, or skipping frames); a frame is never held past the next one's arrival either.
const DETECT_WAIT: Duration = Duration::from_millis(25);
/// Result-service receive buffer (messages are small; a generous buffer loses none).
const RESULT_BUFFER: usize = 64;
/// How often the recorder writes its counters to `/recorder`.
const STATS_INTERVAL: Duration = Duration::from_secs(1);

#[derive(Parser)]
#[command(
    name = "hubtrack-recorder",
    about = "Record every hubtrack service to an MCAP file"
)]
struct Args {
    #[command(flatten)]
    stage: StageArgs,
    /// Output MCAP file (required unless only checking or printing the config).
    #[arg(long, short = 'o', value_name = "PATH.mcap", required_unless_present_any = ["check_config", "print_config"])]
    output: Option<PathBuf>,
}

/// What the reader hands the writer.
enum Item {
    Frame {
        header: FrameHeader,
        pixels: Pixels,
        log_time: u64,
    },
    Json {
        kind: ChannelKind,
        seq: u64,
        publish_ns: u64,
        log_time: u64,
        json: JsonMsg,
    },
    Overlay {
        overlay: Box<DetectOverlay>,
        log_time: u64,
    },
    Log {
        line: Box<LogLine>,
        log_time: u64,
    },
}

/// Frames whose wall-clock capture time the writer remembers, to stamp overlays exactly like
/// their image (Foxglove pairs annotations with images by timestamp).
const IMAGE_TIME_MEMORY: usize = 256;

enum JsonMsg {
    Detection(Detection),
    Track(TrackState),
    Setpoint(Setpoint),
    Vehicle(VehicleState),
    Status(StageStatus),
    /// The reader's counters; the writer adds its own and writes `/recorder`.
    Recorder(RecorderStats),
}

hubtrack_runtime::sections! {
    /// What the recorder stage reads.
    struct RecorderSections { recorder: RecorderConfig }
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
    }) = Stage::<RecorderSections>::start("recorder", &args.stage)?
    else {
        return Ok(());
    };
    let output = args.output.context("--output is required")?;
    let cfg = config.recorder.clone();

    let recording = Recording::create(&output, &options(&cfg))?;
    log::info!("recording to {}", output.display());

    // Polled, not woken by each frame: the camera's notification goes to detect alone (see
    // `FrameSubscriber::polling`); the buffer holds many sleeps' worth of frames.
    let mut frames = FrameSubscriber::polling(&node, usize::MAX)?;
    let detections = MsgSubscriber::<Detection>::polling(&node, &DETECTIONS, RESULT_BUFFER)?;
    let track = MsgSubscriber::<TrackState>::polling(&node, &TRACK, RESULT_BUFFER)?;
    let setpoints = MsgSubscriber::<Setpoint>::polling(&node, &SETPOINTS, RESULT_BUFFER)?;
    let vehicle = MsgSubscriber::<VehicleState>::polling(&node, &VEHICLE, RESULT_BUFFER)?;
    let status_in = MsgSubscriber::<StageStatus>::polling(&node, &STATUS, RESULT_BUFFER)?;
    let raw_requests = MsgSubscriber::<RawWindowRequest>::polling(
        &node,
        &RAW_WINDOW,
        RAW_WINDOW.qos.subscriber_max_buffer_size,
    )?;
    let logs = MsgSubscriber::<LogLine>::polling(&node, &LOG, LOG.qos.subscriber_max_buffer_size)?;
    let mut raw_window = RawWindow::new(cfg.raw_window_s, cfg.raw_window_max_s);
    let compressed = cfg.frame_encoding != FrameEncoding::Raw;
    let raw_every = cfg.raw_every;
    let overlays = MsgSubscriber::<DetectOverlay>::polling(
        &node,
        &OVERLAY,
        OVERLAY.qos.subscriber_max_buffer_size,
    )?;

    // Fixed pool of frame buffers: `free` holds empty ones, `queue` carries filled ones.
    let (free_tx, free_rx) = mpsc::sync_channel::<Vec<u8>>(cfg.queue_frames);
    for _ in 0..cfg.queue_frames {
        free_tx.send(Vec::new()).expect("pool fits its channel");
    }
    let mut packer = FramePacker::new(&cfg, free_rx)?;
    let (queue_tx, queue_rx) = mpsc::sync_channel::<Item>(
        cfg.queue_frames + RESULT_BUFFER * 5 + LOG.qos.subscriber_max_buffer_size,
    );
    let (stats_tx, stats_rx) = mpsc::channel::<RecorderStats>();
    // Set once by the writer when the file can no longer be written (e.g. the disk is full).
    let writer_failed = Arc::new(OnceLock::<String>::new());
    let failed = writer_failed.clone();
    let writer = std::thread::Builder::new()
        .name("mcap-writer".into())
        .spawn(move || {
            let r = write_loop(recording, queue_rx, free_tx, stats_tx, &cfg);
            if let Err(e) = &r {
                let _ = failed.set(format!("{e:#}"));
            }
            r
        })?;

    let mut stats = RecorderStats::default();
    let mut stats_at = Instant::now();
    let (mut lost_unlogged, mut lost_logged_at) = (0u64, None::<Instant>);
    // The newest frame, until detect is done with it; the newest frame seq detect has reported.
    let mut held: Option<HeldFrame> = None;
    let mut detected_seq: Option<u64> = None;
    while !shutdown.requested() {
        if let Some(why) = writer_failed.get() {
            // Nothing more can be recorded: say why, count it, and end (the supervisor restarts
            // the recorder into a new segment, which works again once space is freed).
            // The status text is short: the innermost cause (e.g. "No space left on device").
            let cause = why.rsplit(": ").next().unwrap_or(why);
            status.error(&format!("write failed: {cause}"));
            status.publish_now();
            break;
        }
        frames.wait(READER_WAIT);
        while let Some(r) = raw_requests.receive()? {
            match raw_window.request(r.seconds) {
                Ok(s) if compressed => log::info!(
                    "raw window: every frame of the next {s:.1} s also raw on /frames/raw"
                ),
                Ok(_) => log::info!("raw window: /frames is raw already"),
                Err(why) => {
                    log::warn!("raw window refused: {why}");
                    status.error(&format!("raw window refused: {why}"));
                }
            }
        }
        while let Some(sample) = frames.receive()? {
            stats.frames_received += 1;
            let header = *sample.user_header();
            let raw_copy = compressed
                && (raw_window.take(header.capture_ns)
                    || (raw_every > 0 && header.seq.is_multiple_of(raw_every)));
            if let Some(older) = held.replace(HeldFrame::new(sample, raw_copy, realtime_ns())) {
                pack(older, &mut packer, &queue_tx, &mut stats, &mut status);
            }
        }
        if frames.lost > stats.frames_lost {
            lost_unlogged += frames.lost - stats.frames_lost;
        }
        // Each loss is logged (at most once per STATS_INTERVAL under sustained overload): the
        // camera never waits, so a reader that falls more than the frames service's buffer
        // behind loses the oldest frames.
        if lost_unlogged > 0 && lost_logged_at.is_none_or(|t| t.elapsed() >= STATS_INTERVAL) {
            log::warn!(
                "{lost_unlogged} frame(s) overwritten in shared memory before the recorder read them ({} lost in this file): the recorder fell more than {} frames behind the camera",
                frames.lost,
                FRAMES.qos.subscriber_max_buffer_size
            );
            lost_unlogged = 0;
            lost_logged_at = Some(Instant::now());
        }
        stats.frames_lost = frames.lost;
        let now = realtime_ns();
        // Queues every message of one service for the writer; evaluates to the highest seq
        // among them.
        macro_rules! drain {
            ($sub:expr, $kind:expr, $variant:ident, $seq:expr, $pub_ns:expr) => {{
                let mut newest: Option<u64> = None;
                while let Some(m) = $sub.receive()? {
                    let seq = $seq(&m);
                    newest = newest.max(Some(seq));
                    let item = Item::Json {
                        kind: $kind,
                        seq,
                        publish_ns: $pub_ns(&m),
                        log_time: now,
                        json: JsonMsg::$variant(m),
                    };
                    enqueue(&queue_tx, item, &mut stats, &mut status);
                }
                newest
            }};
        }
        let newest_detection = drain!(
            detections,
            ChannelKind::Detection,
            Detection,
            |m: &Detection| m.stamps.seq,
            |m: &Detection| m.stamps.publish_ns
        );
        detected_seq = detected_seq.max(newest_detection);
        if let Some(due) = held.take_if(|h| h.due(detected_seq, DETECT_WAIT)) {
            pack(due, &mut packer, &queue_tx, &mut stats, &mut status);
        }
        drain!(
            track,
            ChannelKind::Track,
            Track,
            |m: &TrackState| m.stamps.seq,
            |m: &TrackState| m.stamps.publish_ns
        );
        drain!(
            setpoints,
            ChannelKind::Setpoint,
            Setpoint,
            |m: &Setpoint| m.stamps.seq,
            |m: &Setpoint| m.stamps.publish_ns
        );
        drain!(
            vehicle,
            ChannelKind::Vehicle,
            Vehicle,
            |_: &VehicleState| 0,
            |m: &VehicleState| m.publish_ns
        );
        drain!(
            status_in,
            ChannelKind::Status,
            Status,
            |_: &StageStatus| 0,
            |m: &StageStatus| m.publish_ns
        );
        while let Some(o) = overlays.receive()? {
            enqueue(
                &queue_tx,
                Item::Overlay {
                    overlay: Box::new(o),
                    log_time: now,
                },
                &mut stats,
                &mut status,
            );
        }

        while let Some(line) = logs.receive()? {
            enqueue(
                &queue_tx,
                Item::Log {
                    line: Box::new(line),
                    log_time: now,
                },
                &mut stats,
                &mut status,
            );
        }

        while let Ok(s) = stats_rx.try_recv() {
            stats.frames_recorded = s.frames_recorded;
            stats.frames_dropped_disk = s.frames_dropped_disk;
            stats.frames_encode_failed = s.frames_encode_failed;
            stats.frames_camera_jpeg = s.frames_camera_jpeg;
            stats.frames_raw_copies = s.frames_raw_copies;
            stats.messages_recorded = s.messages_recorded;
            stats.bytes_written = s.bytes_written;
        }
        status.status.inputs = stats.frames_received;
        status.status.outputs = stats.frames_recorded;
        status.status.dropped = stats.frames_dropped_queue + stats.frames_lost;
        status.tick();
        if stats_at.elapsed() >= STATS_INTERVAL {
            stats_at = Instant::now();
            let _ = queue_tx.try_send(Item::Json {
                kind: ChannelKind::Recorder,
                seq: 0,
                publish_ns: monotonic_ns(),
                log_time: realtime_ns(),
                json: JsonMsg::Recorder(stats),
            });
        }
    }

    log::info!("stopping: finishing {}", output.display());
    if let Some(last) = held.take() {
        pack(last, &mut packer, &queue_tx, &mut stats, &mut status);
    }
    // Final reader counts go into the file's last `/recorder` message.
    let _ = queue_tx.send(Item::Json {
        kind: ChannelKind::Recorder,
        seq: 0,
        publish_ns: monotonic_ns(),
        log_time: realtime_ns(),
        json: JsonMsg::Recorder(stats),
    });
    drop(queue_tx);
    let final_stats = writer
        .join()
        .map_err(|_| anyhow::anyhow!("writer thread panicked"))?
        .with_context(|| {
            format!(
                "recording to {} failed after {} frames received ({} dropped)",
                output.display(),
                stats.frames_received,
                stats.frames_dropped_queue
            )
        })?;
    stats.frames_recorded = final_stats.frames_recorded;
    stats.frames_dropped_disk = final_stats.frames_dropped_disk;
    stats.frames_encode_failed = final_stats.frames_encode_failed;
    stats.frames_camera_jpeg = final_stats.frames_camera_jpeg;
    stats.frames_raw_copies = final_stats.frames_raw_copies;
    stats.messages_recorded = final_stats.messages_recorded;
    stats.bytes_written = final_stats.bytes_written;
    status.status.outputs = stats.frames_recorded;
    status.publish_now();
    log::info!(
        "recorded {} frames ({} received, {} dropped: disk behind, {} lost: overwritten before read, {} without pixels: disk nearly full, {} without pixels: not encodable, {} as the camera's own JPEG, {} raw copies), {} messages, {} bytes",
        stats.frames_recorded,
        stats.frames_received,
        stats.frames_dropped_queue,
        stats.frames_lost,
        stats.frames_dropped_disk,
        stats.frames_encode_failed,
        stats.frames_camera_jpeg,
        stats.frames_raw_copies,
        stats.messages_recorded,
        stats.bytes_written
    );
    Ok(())
}

fn options(cfg: &RecorderConfig) -> RecordingOptions {
    RecordingOptions {
        compression: match cfg.compression {
            Compression::None => None,
            Compression::Lz4 => Some(mcap::Compression::Lz4),
            Compression::Zstd => Some(mcap::Compression::Zstd),
        },
        chunk_size: cfg.chunk_size_kib * 1024,
        frame_encoding: cfg.frame_encoding,
    }
}

/// Compresses a held frame from shared memory (or copies what is written raw), releases the
/// sample and hands the frame to the writer; without a free pool buffer it drops the frame.
fn pack(
    frame: HeldFrame,
    packer: &mut FramePacker,
    queue: &SyncSender<Item>,
    stats: &mut RecorderStats,
    status: &mut StatusReporter,
) {
    let header = *frame.sample.user_header();
    let Some(pixels) = packer.pack(&header, frame.sample.payload(), frame.raw_copy) else {
        stats.frames_dropped_queue += 1;
        status.status.dropped += 1;
        return;
    };
    drop(frame.sample); // release shared memory before the (possibly slow) hand-off
    let item = Item::Frame {
        header,
        pixels,
        log_time: frame.log_time,
    };
    enqueue(queue, item, stats, status);
}

/// Hands an item to the writer without ever blocking the reader; a full queue drops it.
fn enqueue(
    queue: &SyncSender<Item>,
    item: Item,
    stats: &mut RecorderStats,
    status: &mut StatusReporter,
) {
    match queue.try_send(item) {
        Ok(()) => {}
        Err(TrySendError::Full(Item::Frame { .. })) => {
            stats.frames_dropped_queue += 1;
            status.status.dropped += 1;
        }
        Err(TrySendError::Full(_)) => status.error("writer queue full: result message dropped"),
        Err(TrySendError::Disconnected(_)) => status.error("writer thread gone"),
    }
}

/// Keeps `min_free_mib` free on the recording's file system: below it, frame pixels are skipped
/// so that the file can still be finished (a full disk would leave it without its summary);
/// above twice the limit they are written again.
struct DiskGuard {
    dir: std::ffi::CString,
    shown: PathBuf,
    min_free: u64,
    low: bool,
}

impl DiskGuard {
    fn new(file: &Path, min_free_mib: u64) -> DiskGuard {
        let dir = match file.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let c = std::ffi::CString::new(dir.as_os_str().as_encoded_bytes()).unwrap_or_default();
        let mut guard = DiskGuard {
            dir: c,
            shown: dir,
            min_free: min_free_mib << 20,
            low: false,
        };
        guard.check();
        guard
    }

    /// Free bytes for an unprivileged writer, or `None` when the file system cannot be asked.
    fn free_bytes(&self) -> Option<u64> {
        let mut st = std::mem::MaybeUninit::<libc::statvfs>::uninit();
        // SAFETY: statvfs(3) fills `st` on success; the path is a valid C string.
        let rc = unsafe { libc::statvfs(self.dir.as_ptr(), st.as_mut_ptr()) };
        if rc != 0 {
            return None;
        }
        // SAFETY: rc == 0, so `st` is initialised.
        let st = unsafe { st.assume_init() };
        Some(st.f_bavail.saturating_mul(st.f_frsize))
    }

    fn check(&mut self) {
        if self.min_free == 0 {
            return;
        }
        let Some(free) = self.free_bytes() else {
            return;
        };
        if !self.low && free < self.min_free {
            self.low = true;
            log::error!(
                "disk nearly full: {} MiB free on {} (recorder.min_free_mib = {}): no longer recording frame pixels, \
                 headers and results still recorded",
                free >> 20,
                self.shown.display(),
                self.min_free >> 20
            );
        } else if self.low && free > 2 * self.min_free {
            self.low = false;
            log::warn!(
                "disk space back ({} MiB free on {}): recording frame pixels again",
                free >> 20,
                self.shown.display()
            );
        }
    }
}

/// Reader-side counts (received, dropped, lost) with writer-side counts (recorded, bytes).
fn merged(reader: &RecorderStats, writer: &RecorderStats) -> RecorderStats {
    RecorderStats {
        frames_dropped_disk: writer.frames_dropped_disk,
        frames_encode_failed: writer.frames_encode_failed,
        frames_camera_jpeg: writer.frames_camera_jpeg,
        frames_raw_copies: writer.frames_raw_copies,
        frames_recorded: writer.frames_recorded,
        messages_recorded: writer.messages_recorded,
        bytes_written: writer.bytes_written,
        ..*reader
    }
}

/// Writes until the queue closes, then finishes the file. When a write fails (a full disk, an I/O
/// error), the error is logged with its cause, the file is finished if the file system still
/// allows it (otherwise `hubtrack recover` reads it up to its last intact chunk), and the error
/// is returned: the reader then stops and the recorder exits with it.
fn write_loop(
    mut rec: Recording,
    queue: Receiver<Item>,
    free: SyncSender<Vec<u8>>,
    stats_out: mpsc::Sender<RecorderStats>,
    cfg: &RecorderConfig,
) -> anyhow::Result<RecorderStats> {
    let mut stats = RecorderStats::default();
    let result = write_items(&mut rec, &queue, &free, &stats_out, &mut stats, cfg);
    match result {
        Ok(()) => {
            rec.finish().context("finishing the file")?;
            Ok(stats)
        }
        Err(e) => {
            let path = rec.path().display().to_string();
            log::error!(
                "writing {path} failed: {e:#}; {} frames recorded until then",
                stats.frames_recorded
            );
            let _ = stats_out.send(stats);
            match rec.finish() {
                Ok(()) => log::warn!("{path} finished despite the error"),
                Err(f) => log::error!(
                    "{path} could not be finished ({f}): `hubtrack recover {path}` copies what it holds"
                ),
            }
            Err(e)
        }
    }
}

fn write_items(
    rec: &mut Recording,
    queue: &Receiver<Item>,
    free: &SyncSender<Vec<u8>>,
    stats_out: &mpsc::Sender<RecorderStats>,
    stats: &mut RecorderStats,
    cfg: &RecorderConfig,
) -> anyhow::Result<()> {
    let flush_interval = Duration::from_millis(cfg.flush_interval_ms);
    let mut disk = DiskGuard::new(rec.path(), cfg.min_free_mib);
    let mut flushed_at = Instant::now();
    let mut reported = RecorderStats::default();
    let mut last_frame = FrameHeader::default();
    let mut reader_stats = RecorderStats::default();
    let mut image_times =
        std::collections::VecDeque::<(u64, u64)>::with_capacity(IMAGE_TIME_MEMORY);
    loop {
        let item = match queue.recv_timeout(flush_interval) {
            Ok(item) => Some(item),
            Err(mpsc::RecvTimeoutError::Timeout) => None,
            Err(mpsc::RecvTimeoutError::Disconnected) => break,
        };
        match item {
            Some(Item::Frame {
                header,
                pixels,
                log_time,
            }) => {
                frames::write_frame(rec, &header, pixels, disk.low, log_time, stats, free)
                    .context("writing a frame")?;
                stats.frames_recorded += 1;
                last_frame = header;
                if image_times.len() == IMAGE_TIME_MEMORY {
                    image_times.pop_front();
                }
                image_times.push_back((header.seq, header.capture_realtime_ns));
            }
            Some(Item::Json {
                kind,
                seq,
                publish_ns,
                log_time,
                json,
            }) => {
                let publish_time = rec.to_realtime(publish_ns);
                let r = match &json {
                    JsonMsg::Detection(m) => rec.write_json(kind, seq, log_time, publish_time, m),
                    JsonMsg::Track(m) => rec.write_json(kind, seq, log_time, publish_time, m),
                    JsonMsg::Setpoint(m) => rec.write_json(kind, seq, log_time, publish_time, m),
                    JsonMsg::Vehicle(m) => rec.write_json(kind, seq, log_time, publish_time, m),
                    JsonMsg::Status(m) => rec.write_json(kind, seq, log_time, publish_time, m),
                    JsonMsg::Recorder(reader) => {
                        reader_stats = *reader;
                        rec.write_json(
                            kind,
                            last_frame.seq,
                            log_time,
                            publish_time,
                            &merged(&reader_stats, stats),
                        )
                    }
                };
                r.context("writing a message")?;
                stats.messages_recorded += 1;
            }
            Some(Item::Overlay { overlay, log_time }) => {
                let seq = overlay.stamps.seq;
                let image_time = image_times
                    .iter()
                    .rev()
                    .find(|(s, _)| *s == seq)
                    .map_or_else(|| rec.to_realtime(overlay.stamps.capture_ns), |(_, t)| *t);
                rec.write_overlay(&overlay, image_time, log_time)
                    .context("writing an overlay")?;
                stats.messages_recorded += 1;
            }
            Some(Item::Log { line, log_time }) => {
                rec.write_log(&line, log_time)
                    .context("writing a log line")?;
                stats.messages_recorded += 1;
            }
            None => {}
        }
        if flushed_at.elapsed() >= flush_interval {
            rec.flush().context("flushing")?;
            flushed_at = Instant::now();
            disk.check();
            if *stats != reported {
                let _ = stats_out.send(*stats);
                reported = *stats;
            }
        }
    }
    let now = realtime_ns();
    rec.write_json(
        ChannelKind::Recorder,
        last_frame.seq,
        now,
        now,
        &merged(&reader_stats, stats),
    )?;
    Ok(())
}
