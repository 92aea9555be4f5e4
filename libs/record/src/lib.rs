//! hubtrack's recording format, in one place for the recorder, replay, latency and recovery.
//!
//! One MCAP file per run: chunked, indexed, lz4/zstd compressed, schemas embedded.
//! - `/frames`: the video as `foxglove.CompressedImage` (JPEG, the default),
//!   `foxglove.CompressedVideo` (H.264) or `foxglove.RawImage` (protobuf), so Foxglove and
//!   Lichtblick show it; `/frames/raw`: raw copies of some frames beside compressed ones
//!   (`recorder.raw_every`, raw windows: [`raw_window`]);
//! - `/frames/overlay`: what the detector saw (`foxglove.ImageAnnotations`, JSON), drawn over the video;
//! - `/frames/header`: the [`hubtrack_types::FrameHeader`] of each frame (stamps and truth), JSON;
//! - `/detections`, `/track`, `/setpoints`, `/vehicle`, `/status`: the stage messages, JSON with
//!   an embedded JSON schema generated from the Rust types;
//! - `/recorder`: the recorder's own counters, JSON;
//! - `/log`: every line the stages and the supervisor logged (`foxglove.Log`, protobuf: [`log`]).
//!
//! Every message's MCAP `sequence` is the frame `seq` it belongs to (truncated to 32 bits), so a
//! gap is visible to any MCAP tool; `log_time` is the wall-clock receive time (epoch ns) and
//! `publish_time` the wall-clock time the publishing stage sent it.

#![warn(missing_docs)]

pub mod annotations;
pub mod channels;
pub mod compressed_image;
pub mod compressed_video;
pub mod config;
pub mod encoder;
pub mod flight;
pub mod frame_payload;
pub mod jpeg;
pub mod latency;
pub mod log;
pub mod looming;
pub mod raw_image;
pub mod raw_window;
pub mod reader;
pub mod video;
pub mod viewer_schema;
pub mod writer;

pub use reader::{inspect, recover, FileInfo, RecoverReport};
pub use writer::{ChannelKind, Recording, RecordingOptions};

/// Why a recording could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// File system error.
    #[error("{path}: {cause}")]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// The OS error (not a `source`: the message already says it, and error chains would
        /// print it twice).
        cause: std::io::Error,
    },
    /// The MCAP library refused the data.
    #[error("MCAP {path}: {message}")]
    Mcap {
        /// The file.
        path: std::path::PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A message could not be serialised.
    #[error("cannot encode {channel}: {message}")]
    Encode {
        /// Channel.
        channel: String,
        /// Why.
        message: String,
    },
}
