//! `[recorder]`: how the recorder stage writes the MCAP file.

use hubtrack_types::params;
use serde::{Deserialize, Serialize};

/// MCAP chunk compression.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Compression {
    /// No compression (fastest, largest).
    None,
    /// LZ4 (fast; the default).
    Lz4,
    /// Zstandard (smaller, slower).
    Zstd,
}

/// The largest `recorder.chunk_size_kib`: a chunk plus the largest frame stays well within what
/// every reader accepts ([`crate::reader::MAX_RECORD_BYTES`]).
pub const MAX_CHUNK_SIZE_KIB: u64 = 64 << 10;

/// How frame pixels are recorded on `/frames`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FrameEncoding {
    /// `foxglove.CompressedImage`, JPEG: about 40 times smaller than raw.
    Jpeg,
    /// `foxglove.CompressedVideo`, H.264: about 10 times smaller than JPEG, more CPU.
    H264,
    /// `foxglove.RawImage`: the captured pixels, bit-exact (for replay that reproduces a run).
    Raw,
}

/// Which library encodes JPEG frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum JpegLibrary {
    /// libjpeg-turbo (SIMD; about 2.4 times faster: the flight default).
    Turbojpeg,
    /// The pure-Rust `jpeg-encoder` (no C library).
    JpegEncoder,
}

params! {
    /// `[recorder]`.
    pub struct RecorderConfig {
        /// Chunk compression.
        pub compression: Compression = Compression::Lz4;
        /// Target chunk size, KiB. A chunk is also closed at every flush.
        pub chunk_size_kib: u64 = 4096, closed(16, MAX_CHUNK_SIZE_KIB);
        /// Frames buffered between the shared-memory reader and the disk writer; when full,
        /// further frames are dropped and counted (the camera never waits for the disk).
        pub queue_frames: usize = 16, closed(1, 1024);
        /// Close the current chunk and flush to the OS at least this often, ms: after a
        /// `kill -9` everything older than this is readable.
        pub flush_interval_ms: u64 = 200, closed(10, 60_000);
        /// Record the pixels of every frame (false: only the frame headers).
        pub record_frames: bool = true;
        /// How `/frames` holds the pixels: `jpeg` (`foxglove.CompressedImage`), `h264`
        /// (`foxglove.CompressedVideo`) or `raw` (`foxglove.RawImage`, bit-exact).
        pub frame_encoding: FrameEncoding = FrameEncoding::Jpeg;
        /// With `jpeg` or `h264`: also record every N-th frame raw on `/frames/raw` (1: every frame,
        /// 0: none), for bit-exact replay of those frames.
        pub raw_every: u64 = 0, closed(0, 1_000_000);
        /// With `jpeg` or `h264`: length of a raw window, seconds of capture time — every frame
        /// also raw on `/frames/raw` from the next frame on, when `hubtrack raw-window` asks
        /// without a length.
        pub raw_window_s: f64 = 10.0, open_closed(0.0, 3600.0);
        /// The longest raw window a request may open, s (0: requests are refused). At
        /// 1920x1080 30 fps a raw second is 187 MB.
        pub raw_window_max_s: f64 = 60.0, closed(0.0, 3600.0);
        /// JPEG quality (libjpeg's 1..100 scale). 65 keeps 1920x1080 with the synthetic camera's
        /// sensor noise under 300 MB per minute at 30 fps, at a PSNR above 32 dB.
        pub jpeg_quality: u32 = 65, closed(1, 100);
        /// The JPEG library: `turbojpeg` (libjpeg-turbo) or `jpeg-encoder` (pure Rust).
        pub jpeg_library: JpegLibrary = JpegLibrary::Turbojpeg;
        /// H.264 target bit rate, kbit/s. 4000 is 30 MB per minute (any size, any rate); at
        /// 1920x1080 30 fps with the synthetic camera's noise a PSNR of about 35 dB.
        pub h264_bitrate_kbps: u32 = 4000, closed(100, 100_000);
        /// H.264: an IDR keyframe every this many frames; replay resumes at the next keyframe
        /// after a damaged frame, and a viewer can start there.
        pub keyframe_interval: u32 = 30, closed(1, 10_000);
        /// H.264: the frame rate the bit rate is planned for, Hz (the camera's rate).
        pub h264_frame_rate: f64 = 30.0, closed(1.0, 1000.0);
        /// Free space the recorder leaves on the recording's file system, MiB (0: no limit).
        /// Below it, frame pixels are no longer written (headers and results still are) so that
        /// the file can always be finished; above twice the limit, pixels are written again.
        pub min_free_mib: u64 = 512, closed(0, 1 << 24);
    }
}

impl RecorderConfig {
    /// The frame encoder's settings, `None` with raw frames.
    pub fn encoder_settings(&self) -> Option<crate::encoder::EncoderSettings> {
        use crate::encoder::Codec;
        let codec = match (self.frame_encoding, self.jpeg_library) {
            (FrameEncoding::Raw, _) => return None,
            (FrameEncoding::Jpeg, JpegLibrary::Turbojpeg) => Codec::Jpeg,
            (FrameEncoding::Jpeg, JpegLibrary::JpegEncoder) => Codec::JpegRust,
            (FrameEncoding::H264, _) => Codec::H264,
        };
        Some(crate::encoder::EncoderSettings {
            codec,
            jpeg_quality: self.jpeg_quality,
            h264_bitrate_kbps: self.h264_bitrate_kbps,
            keyframe_interval: self.keyframe_interval,
            max_fps: self.h264_frame_rate as f32,
        })
    }

    /// Checks every value; errors name the key under `recorder`.
    pub fn validate(&self) -> Result<(), hubtrack_types::params::ParamError> {
        self.check_ranges("recorder")
    }
}
