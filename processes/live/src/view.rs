//! What goes out to the clients and when: video frames within the frame-rate and bitrate cap,
//! encoded only while a client watches the video; the overlay of each frame sent; the messages
//! at most `max_message_hz` per channel. Nothing here waits: the server queues per client and
//! drops a stalled client's oldest messages.

use crate::downscale::downscale;
use crate::rate::{ByteBudget, RateGate};
use crate::server::Channels;
use foxglove::RawChannel;
use hubtrack_record::encoder::{Codec, EncodeError, EncoderSettings, FrameEncoder};
use hubtrack_record::writer::{CAMERA_FRAME_ID, JPEG_FORMAT};
use hubtrack_record::{annotations, compressed_image, ChannelKind};
use hubtrack_runtime::config::LiveConfig;
use hubtrack_types::{DetectOverlay, FrameHeader};
use serde::Serialize;
use std::collections::{BTreeMap, VecDeque};

/// Frames sent whose overlay may still come (detect runs a few frames behind at most).
const SENT_MEMORY: usize = 16;

/// What became of one frame offered to the video.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameOutcome {
    /// Encoded and handed to the server.
    Sent,
    /// Nobody watches the video: not encoded.
    NoViewer,
    /// Within the frame-rate or bitrate cap: skipped.
    Capped,
    /// The pixels do not fit the header, or the encoder refused them.
    Bad,
}

/// Counters of the live view.
#[derive(Debug, Clone, Copy, Default)]
pub struct LiveStats {
    /// Video frames sent.
    pub frames_sent: u64,
    /// Frames skipped (no viewer, or the cap).
    pub frames_skipped: u64,
    /// Frames that could not be encoded.
    pub frames_bad: u64,
    /// Messages sent (overlay and JSON channels).
    pub messages_sent: u64,
    /// Bytes handed to the server (per client).
    pub bytes_sent: u64,
}

/// The live view's state between the subscribers and the server.
pub struct LiveView {
    channels: Channels,
    max_width: u32,
    fps: RateGate,
    budget: ByteBudget,
    max_message_hz: f64,
    gates: BTreeMap<(ChannelKind, String), RateGate>,
    jpeg: FrameEncoder,
    sums: Vec<u32>,
    small: Vec<u8>,
    buf: Vec<u8>,
    /// `(seq, capture wall-clock ns, scale)` of the frames sent.
    sent: VecDeque<(u64, u64, f64)>,
    /// The counters.
    pub stats: LiveStats,
}

impl LiveView {
    /// A view serving `channels` with the caps of `cfg`; fails only if libjpeg-turbo cannot
    /// start.
    pub fn new(channels: Channels, cfg: &LiveConfig) -> Result<LiveView, EncodeError> {
        // The recorder's encoder (libjpeg-turbo): H.264 would need every frame for its
        // references, and the view sends only a few per second.
        let jpeg = FrameEncoder::new(&EncoderSettings {
            codec: Codec::Jpeg,
            jpeg_quality: cfg.jpeg_quality,
            h264_bitrate_kbps: 0,
            keyframe_interval: 1,
            max_fps: cfg.max_fps as f32,
        })?;
        Ok(LiveView {
            channels,
            max_width: cfg.max_width,
            fps: RateGate::new(cfg.max_fps),
            budget: ByteBudget::new(cfg.max_kbps),
            max_message_hz: cfg.max_message_hz,
            gates: BTreeMap::new(),
            jpeg,
            sums: Vec::new(),
            small: Vec::new(),
            buf: Vec::new(),
            sent: VecDeque::with_capacity(SENT_MEMORY),
            stats: LiveStats::default(),
        })
    }

    /// Whether a new frame would be sent now: someone watches and the caps allow it. Asked
    /// before the frame is taken from shared memory.
    pub fn wants_frame(&mut self, now_ns: u64) -> bool {
        self.channels.video.has_sinks() && self.fps.due(now_ns) && self.budget.available(now_ns)
    }

    /// Offers the newest frame (read straight from shared memory).
    pub fn offer_frame(
        &mut self,
        header: &FrameHeader,
        pixels: &[u8],
        now_ns: u64,
    ) -> FrameOutcome {
        if !self.channels.video.has_sinks() {
            self.stats.frames_skipped += 1;
            return FrameOutcome::NoViewer;
        }
        if !self.wants_frame(now_ns) {
            self.stats.frames_skipped += 1;
            return FrameOutcome::Capped;
        }
        self.fps.take(now_ns);
        let Some(small) = downscale(
            header,
            pixels,
            self.max_width,
            &mut self.sums,
            &mut self.small,
        ) else {
            self.stats.frames_bad += 1;
            return FrameOutcome::Bad;
        };
        let jpeg = match self.jpeg.encode(&small, &self.small) {
            Ok(j) => j.data,
            Err(e) => {
                log::warn!("live view: frame not encoded: {e}");
                self.stats.frames_bad += 1;
                return FrameOutcome::Bad;
            }
        };
        compressed_image::encode(
            header.capture_realtime_ns,
            CAMERA_FRAME_ID,
            JPEG_FORMAT,
            jpeg,
            &mut self.buf,
        );
        self.channels.video.log(&self.buf);
        self.budget.spend(self.buf.len(), now_ns);
        self.stats.frames_sent += 1;
        self.stats.bytes_sent += self.buf.len() as u64;
        if self.sent.len() == SENT_MEMORY {
            self.sent.pop_front();
        }
        let scale = f64::from(small.width) / f64::from(header.width.max(1));
        self.sent
            .push_back((header.seq, header.capture_realtime_ns, scale));
        FrameOutcome::Sent
    }

    /// Sends the overlay of a frame that went out as video, scaled to it and stamped with its
    /// time (the viewers pair annotations with images by timestamp); other overlays have no
    /// image to go over and are not sent.
    pub fn offer_overlay(&mut self, overlay: &DetectOverlay, now_ns: u64) {
        if !self.channels.overlay.has_sinks() {
            return;
        }
        let seq = overlay.stamps.seq;
        let Some(&(_, image_ns, scale)) = self.sent.iter().rev().find(|(s, _, _)| *s == seq) else {
            return;
        };
        let mut json = annotations::to_json(overlay, image_ns);
        annotations::rescale(&mut json, scale);
        let channel = self.channels.overlay.clone();
        self.log_json(&channel, &json, now_ns);
    }

    /// Sends a message of `kind` unless its channel (per `key`, e.g. the stage of a status) sent
    /// one less than `1 / max_message_hz` ago or nobody subscribes.
    pub fn offer_message<T: Serialize>(
        &mut self,
        kind: ChannelKind,
        key: &str,
        value: &T,
        now_ns: u64,
    ) {
        let Some(channel) = self.channels.messages.get(&kind).cloned() else {
            return;
        };
        if !channel.has_sinks() {
            return;
        }
        let hz = self.max_message_hz;
        let gate = self
            .gates
            .entry((kind, key.to_string()))
            .or_insert_with(|| RateGate::new(hz));
        if !gate.pass(now_ns) {
            return;
        }
        self.log_json(&channel, value, now_ns);
    }

    fn log_json<T: Serialize>(&mut self, channel: &RawChannel, value: &T, now_ns: u64) {
        self.buf.clear();
        if let Err(e) = serde_json::to_writer(&mut self.buf, value) {
            log::warn!("live view: {} not encoded: {e}", channel.topic());
            return;
        }
        channel.log(&self.buf);
        self.budget.spend(self.buf.len(), now_ns);
        self.stats.messages_sent += 1;
        self.stats.bytes_sent += self.buf.len() as u64;
    }
}
