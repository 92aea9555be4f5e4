//! Writing a recording.

use crate::compressed_image;
use crate::compressed_video;
use crate::config::FrameEncoding;
use crate::encoder::{EncodedFormat, EncodedFrame};
use crate::raw_image::{self, ImageMeta};
use crate::RecordError;
use hubtrack_types::{FrameHeader, PixelFormat};
use mcap::records::MessageHeader;
use mcap::WriteOptions;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// Topic of the frames (foxglove.CompressedImage or foxglove.RawImage, by
/// [`crate::config::FrameEncoding`]).
pub const FRAMES_TOPIC: &str = "/frames";
/// Topic of the raw copies of some frames when `/frames` is compressed (foxglove.RawImage).
pub const RAW_FRAMES_TOPIC: &str = "/frames/raw";
/// `format` of the JPEG frames.
pub const JPEG_FORMAT: &str = "jpeg";
/// Topic of the frame headers (stamps and truth).
pub const FRAME_HEADERS_TOPIC: &str = "/frames/header";
/// Topic of the detector overlay (foxglove.ImageAnnotations).
pub const OVERLAY_TOPIC: &str = "/frames/overlay";
/// Topic of the recorder's own counters.
pub const RECORDER_TOPIC: &str = "/recorder";
/// The MCAP profile (none of the registered ones fits: mixed protobuf and JSON).
pub const PROFILE: &str = "";
/// Frame id written into images.
pub const CAMERA_FRAME_ID: &str = "camera";

/// The JSON-encoded channels and the Rust type whose schema they carry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum ChannelKind {
    /// `/frames/header`: [`hubtrack_types::FrameHeader`].
    FrameHeader,
    /// `/detections`: [`hubtrack_types::Detection`].
    Detection,
    /// `/track`: [`hubtrack_types::TrackState`].
    Track,
    /// `/setpoints`: [`hubtrack_types::Setpoint`].
    Setpoint,
    /// `/vehicle`: [`hubtrack_types::VehicleState`].
    Vehicle,
    /// `/status`: [`hubtrack_types::StageStatus`].
    Status,
    /// `/recorder`: [`RecorderStats`].
    Recorder,
}

impl ChannelKind {
    /// Every JSON channel.
    pub const ALL: [ChannelKind; 7] = [
        ChannelKind::FrameHeader,
        ChannelKind::Detection,
        ChannelKind::Track,
        ChannelKind::Setpoint,
        ChannelKind::Vehicle,
        ChannelKind::Status,
        ChannelKind::Recorder,
    ];

    /// MCAP topic.
    pub fn topic(self) -> &'static str {
        match self {
            ChannelKind::FrameHeader => FRAME_HEADERS_TOPIC,
            ChannelKind::Detection => "/detections",
            ChannelKind::Track => "/track",
            ChannelKind::Setpoint => "/setpoints",
            ChannelKind::Vehicle => "/vehicle",
            ChannelKind::Status => "/status",
            ChannelKind::Recorder => RECORDER_TOPIC,
        }
    }

    /// Schema name.
    pub fn schema_name(self) -> &'static str {
        match self {
            ChannelKind::FrameHeader => "hubtrack.FrameHeader",
            ChannelKind::Detection => "hubtrack.Detection",
            ChannelKind::Track => "hubtrack.TrackState",
            ChannelKind::Setpoint => "hubtrack.Setpoint",
            ChannelKind::Vehicle => "hubtrack.VehicleState",
            ChannelKind::Status => "hubtrack.StageStatus",
            ChannelKind::Recorder => "hubtrack.RecorderStats",
        }
    }

    /// The JSON schema, generated from the Rust type so it cannot drift, in the subset the
    /// viewers parse ([`crate::viewer_schema`]).
    pub fn json_schema(self) -> Vec<u8> {
        use hubtrack_types as t;
        let schema = match self {
            ChannelKind::FrameHeader => schemars::schema_for!(t::FrameHeader),
            ChannelKind::Detection => schemars::schema_for!(t::Detection),
            ChannelKind::Track => schemars::schema_for!(t::TrackState),
            ChannelKind::Setpoint => schemars::schema_for!(t::Setpoint),
            ChannelKind::Vehicle => schemars::schema_for!(t::VehicleState),
            ChannelKind::Status => schemars::schema_for!(t::StageStatus),
            ChannelKind::Recorder => schemars::schema_for!(RecorderStats),
        };
        let schema = serde_json::to_value(&schema).expect("schemas serialise");
        serde_json::to_vec(&crate::viewer_schema::for_viewers(&schema)).expect("schemas serialise")
    }

    /// The channel of a topic, if it is one of hubtrack's JSON channels.
    pub fn from_topic(topic: &str) -> Option<ChannelKind> {
        ChannelKind::ALL.into_iter().find(|k| k.topic() == topic)
    }
}

/// The recorder's counters, written to `/recorder` periodically and at the end.
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Serialize, serde::Deserialize, schemars::JsonSchema,
)]
pub struct RecorderStats {
    /// Frames received from shared memory.
    pub frames_received: u64,
    /// Frames written to the file.
    pub frames_recorded: u64,
    /// Frames dropped because the disk writer fell behind (queue full).
    pub frames_dropped_queue: u64,
    /// Frames never received (seq gaps: overwritten in shared memory before the recorder read them).
    pub frames_lost: u64,
    /// Frames whose pixels were not written because the disk was nearly full (`min_free_mib`);
    /// their headers were.
    pub frames_dropped_disk: u64,
    /// Frames whose pixels could not be encoded (JPEG); their headers were written.
    pub frames_encode_failed: u64,
    /// Frames recorded as the camera's own JPEG, without encoding (V4L2 MJPG, JPEG files).
    #[serde(default)]
    pub frames_camera_jpeg: u64,
    /// Raw copies written to `/frames/raw` beside the compressed frames (`recorder.raw_every`
    /// and raw windows, `hubtrack raw-window`).
    #[serde(default)]
    pub frames_raw_copies: u64,
    /// Result messages written.
    pub messages_recorded: u64,
    /// Bytes written so far (approximate until the file is finished).
    pub bytes_written: u64,
}

/// Options of a new recording.
#[derive(Debug, Clone)]
pub struct RecordingOptions {
    /// `None`, `Some("lz4")` or `Some("zstd")`.
    pub compression: Option<mcap::Compression>,
    /// Target chunk size, bytes.
    pub chunk_size: u64,
    /// How `/frames` holds the pixels. Beside compressed frames, `/frames/raw` starts with the
    /// first raw copy (`recorder.raw_every`, a raw window).
    pub frame_encoding: FrameEncoding,
}

impl Default for RecordingOptions {
    fn default() -> Self {
        RecordingOptions {
            compression: Some(mcap::Compression::Lz4),
            chunk_size: 4 << 20,
            frame_encoding: FrameEncoding::Raw,
        }
    }
}

/// An MCAP file being written.
pub struct Recording {
    path: PathBuf,
    writer: mcap::Writer<BufWriter<File>>,
    /// `/frames` when it holds compressed frames, and their format.
    compressed_channel: Option<(u16, EncodedFormat)>,
    /// Where raw pixels go: `/frames` (raw encoding) or `/frames/raw` (raw copies beside JPEG).
    raw_channel: Option<u16>,
    overlay_channel: u16,
    log_channel: u16,
    json_channels: BTreeMap<ChannelKind, u16>,
    scratch: Vec<u8>,
    /// Wall-clock minus monotonic ns, to turn monotonic stamps into MCAP publish times.
    realtime_offset_ns: i128,
}

/// The error with its causes: the MCAP library's I/O error only says "I/O error from writing"
/// and keeps the cause (e.g. "No space left on device") as its source.
fn mcap_err(path: &Path, e: impl std::error::Error) -> RecordError {
    let mut message = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        message += &format!(": {s}");
        source = s.source();
    }
    RecordError::Mcap {
        path: path.into(),
        message,
    }
}

/// Foxglove's name for a pixel format.
pub fn foxglove_encoding(f: PixelFormat) -> &'static str {
    match f {
        PixelFormat::Bgr8 => "bgr8",
        PixelFormat::Gray8 => "mono8",
    }
}

/// Registers a protobuf channel on `topic` with the schema `name` (a `FileDescriptorSet`).
fn add_protobuf_channel(
    writer: &mut mcap::Writer<BufWriter<File>>,
    path: &Path,
    topic: &str,
    name: &str,
    descriptor: &[u8],
) -> Result<u16, RecordError> {
    let schema = writer
        .add_schema(name, "protobuf", descriptor)
        .map_err(|e| mcap_err(path, e))?;
    writer
        .add_channel(schema, topic, "protobuf", &BTreeMap::new())
        .map_err(|e| mcap_err(path, e))
}

/// Registers a `foxglove.RawImage` channel on `topic`.
fn add_raw_channel(
    writer: &mut mcap::Writer<BufWriter<File>>,
    path: &Path,
    topic: &str,
) -> Result<u16, RecordError> {
    add_protobuf_channel(
        writer,
        path,
        topic,
        raw_image::SCHEMA_NAME,
        &raw_image::descriptor_set(),
    )
}

impl Recording {
    /// Creates the file (its folder too) and registers every channel with its schema.
    pub fn create(path: &Path, options: &RecordingOptions) -> Result<Recording, RecordError> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|cause| RecordError::Io {
                path: dir.into(),
                cause,
            })?;
        }
        let file = File::create(path).map_err(|cause| RecordError::Io {
            path: path.into(),
            cause,
        })?;
        let mut writer = WriteOptions::new()
            .profile(PROFILE)
            .library(concat!("hubtrack-record ", env!("CARGO_PKG_VERSION")))
            .compression(options.compression)
            .chunk_size(Some(options.chunk_size))
            .create(BufWriter::with_capacity(1 << 20, file))
            .map_err(|e| mcap_err(path, e))?;
        let no_meta = BTreeMap::new();
        let (compressed, raw_topic) = match options.frame_encoding {
            FrameEncoding::Raw => (None, Some(FRAMES_TOPIC)),
            FrameEncoding::Jpeg => (Some(EncodedFormat::Jpeg), None),
            FrameEncoding::H264 => (Some(EncodedFormat::H264), None),
        };
        let compressed_channel = match compressed {
            Some(format) => {
                let (name, descriptor) = match format {
                    EncodedFormat::Jpeg => (
                        compressed_image::SCHEMA_NAME,
                        compressed_image::descriptor_set(),
                    ),
                    EncodedFormat::H264 => (
                        compressed_video::SCHEMA_NAME,
                        compressed_video::descriptor_set(),
                    ),
                };
                let id = add_protobuf_channel(&mut writer, path, FRAMES_TOPIC, name, &descriptor)?;
                Some((id, format))
            }
            None => None,
        };
        let raw_channel = match raw_topic {
            Some(topic) => Some(add_raw_channel(&mut writer, path, topic)?),
            None => None,
        };
        let overlay_schema = writer
            .add_schema(
                crate::annotations::SCHEMA_NAME,
                "jsonschema",
                &crate::annotations::json_schema(),
            )
            .map_err(|e| mcap_err(path, e))?;
        let overlay_channel = writer
            .add_channel(overlay_schema, OVERLAY_TOPIC, "json", &no_meta)
            .map_err(|e| mcap_err(path, e))?;
        let log_channel = add_protobuf_channel(
            &mut writer,
            path,
            crate::log::LOG_TOPIC,
            crate::log::SCHEMA_NAME,
            &crate::log::descriptor_set(),
        )?;
        let mut json_channels = BTreeMap::new();
        for kind in ChannelKind::ALL {
            let schema = writer
                .add_schema(kind.schema_name(), "jsonschema", &kind.json_schema())
                .map_err(|e| mcap_err(path, e))?;
            let id = writer
                .add_channel(schema, kind.topic(), "json", &no_meta)
                .map_err(|e| mcap_err(path, e))?;
            json_channels.insert(kind, id);
        }
        let realtime_offset_ns = hubtrack_types::time::realtime_ns() as i128
            - hubtrack_types::time::monotonic_ns() as i128;
        Ok(Recording {
            path: path.into(),
            writer,
            compressed_channel,
            raw_channel,
            overlay_channel,
            log_channel,
            json_channels,
            scratch: Vec::new(),
            realtime_offset_ns,
        })
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Converts a monotonic stamp to wall-clock ns (for MCAP publish times).
    pub fn to_realtime(&self, monotonic_ns: u64) -> u64 {
        (monotonic_ns as i128 + self.realtime_offset_ns).max(0) as u64
    }

    /// Writes one frame's JPEG to `/frames` (see [`Recording::write_encoded`]).
    pub fn write_jpeg(
        &mut self,
        header: &FrameHeader,
        jpeg: Vec<u8>,
        log_time: u64,
    ) -> Result<(), RecordError> {
        let frame = EncodedFrame {
            data: jpeg,
            format: EncodedFormat::Jpeg,
            keyframe: true,
        };
        self.write_encoded(header, frame, log_time)
    }

    /// Writes one frame's compressed bytes to `/frames`: a `foxglove.CompressedImage` (JPEG) or
    /// a `foxglove.CompressedVideo` (one H.264 access unit). Call before
    /// [`Recording::write_frame`] of the same frame: replay pairs an image with the header that
    /// follows it.
    pub fn write_encoded(
        &mut self,
        header: &FrameHeader,
        frame: EncodedFrame,
        log_time: u64,
    ) -> Result<(), RecordError> {
        let (channel_id, format) = match self.compressed_channel {
            Some((id, format)) if format == frame.format => (id, format),
            _ => {
                return Err(RecordError::Encode {
                    channel: FRAMES_TOPIC.into(),
                    message: format!("this recording's frames are not {}", frame.format.name()),
                })
            }
        };
        let encode = match format {
            EncodedFormat::Jpeg => compressed_image::encode,
            EncodedFormat::H264 => compressed_video::encode,
        };
        encode(
            header.capture_realtime_ns,
            CAMERA_FRAME_ID,
            format.name(),
            frame.data,
            &mut self.scratch,
        );
        let h = MessageHeader {
            channel_id,
            sequence: header.seq as u32,
            log_time,
            publish_time: header.capture_realtime_ns,
        };
        self.writer
            .write_to_known_channel(&h, &self.scratch)
            .map_err(|e| mcap_err(&self.path, e))
    }

    /// Writes one frame's raw pixels (skipped when `pixels` is `None`) to `/frames` (raw
    /// encoding) or `/frames/raw` (raw copies beside JPEG), then its header to `/frames/header`.
    /// `log_time` is the wall-clock receive time.
    pub fn write_frame(
        &mut self,
        header: &FrameHeader,
        pixels: Option<&[u8]>,
        log_time: u64,
    ) -> Result<(), RecordError> {
        let sequence = header.seq as u32;
        let publish_time = header.capture_realtime_ns;
        if let Some(pixels) = pixels {
            let meta = ImageMeta {
                timestamp_ns: header.capture_realtime_ns,
                frame_id: CAMERA_FRAME_ID,
                width: header.width,
                height: header.height,
                encoding: foxglove_encoding(header.format),
                step: header.stride,
            };
            let channel_id = match self.raw_channel {
                Some(id) => id,
                // Raw copies beside compressed frames that were not announced at the start (a
                // raw window, `hubtrack raw-window`): the channel starts with its first frame.
                None => {
                    let id = add_raw_channel(&mut self.writer, &self.path, RAW_FRAMES_TOPIC)?;
                    self.raw_channel = Some(id);
                    id
                }
            };
            raw_image::encode(&meta, pixels, &mut self.scratch);
            let h = MessageHeader {
                channel_id,
                sequence,
                log_time,
                publish_time,
            };
            self.writer
                .write_to_known_channel(&h, &self.scratch)
                .map_err(|e| mcap_err(&self.path, e))?;
        }
        self.write_json(
            ChannelKind::FrameHeader,
            header.seq,
            log_time,
            publish_time,
            header,
        )
    }

    /// Writes the detector overlay of a frame as `foxglove.ImageAnnotations`. `image_time_ns` is
    /// the frame's capture wall-clock time (Foxglove matches annotations to images by it).
    pub fn write_overlay(
        &mut self,
        overlay: &hubtrack_types::DetectOverlay,
        image_time_ns: u64,
        log_time: u64,
    ) -> Result<(), RecordError> {
        self.scratch.clear();
        serde_json::to_writer(
            &mut self.scratch,
            &crate::annotations::to_json(overlay, image_time_ns),
        )
        .map_err(|e| RecordError::Encode {
            channel: OVERLAY_TOPIC.into(),
            message: e.to_string(),
        })?;
        let h = MessageHeader {
            channel_id: self.overlay_channel,
            sequence: overlay.stamps.seq as u32,
            log_time,
            publish_time: self.to_realtime(overlay.stamps.publish_ns),
        };
        self.writer
            .write_to_known_channel(&h, &self.scratch)
            .map_err(|e| mcap_err(&self.path, e))
    }

    /// Writes a stage's log line to `/log` as `foxglove.Log`; its publish time is when it was
    /// logged.
    pub fn write_log(
        &mut self,
        line: &hubtrack_types::LogLine,
        log_time: u64,
    ) -> Result<(), RecordError> {
        use prost::Message;
        self.scratch.clear();
        crate::log::to_message(line)
            .encode(&mut self.scratch)
            .map_err(|e| RecordError::Encode {
                channel: crate::log::LOG_TOPIC.into(),
                message: e.to_string(),
            })?;
        let h = MessageHeader {
            channel_id: self.log_channel,
            sequence: 0,
            log_time,
            publish_time: line.realtime_ns,
        };
        self.writer
            .write_to_known_channel(&h, &self.scratch)
            .map_err(|e| mcap_err(&self.path, e))
    }

    /// Writes a JSON message to a hubtrack channel.
    pub fn write_json<T: Serialize>(
        &mut self,
        kind: ChannelKind,
        seq: u64,
        log_time: u64,
        publish_time: u64,
        value: &T,
    ) -> Result<(), RecordError> {
        self.scratch.clear();
        serde_json::to_writer(&mut self.scratch, value).map_err(|e| RecordError::Encode {
            channel: kind.topic().into(),
            message: e.to_string(),
        })?;
        let h = MessageHeader {
            channel_id: self.json_channels[&kind],
            sequence: seq as u32,
            log_time,
            publish_time,
        };
        self.writer
            .write_to_known_channel(&h, &self.scratch)
            .map_err(|e| mcap_err(&self.path, e))
    }

    /// Closes the current chunk and hands everything to the OS: after a crash, the file is
    /// readable up to here.
    pub fn flush(&mut self) -> Result<(), RecordError> {
        self.writer.flush().map_err(|e| mcap_err(&self.path, e))
    }

    /// Writes the summary, indexes and footer, and closes the file.
    pub fn finish(mut self) -> Result<(), RecordError> {
        self.writer.finish().map_err(|e| mcap_err(&self.path, e))?;
        Ok(())
    }
}
