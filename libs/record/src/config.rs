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
    /// `foxglove.RawImage`: the captured pixels, bit-exact (for replay that reproduces a run).
    Raw,
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
        /// How `/frames` holds the pixels: `jpeg` (compressed) or `raw` (bit-exact).
        pub frame_encoding: FrameEncoding = FrameEncoding::Jpeg;
        /// With `jpeg`: also record every N-th frame raw on `/frames/raw` (1: every frame,
        /// 0: none), for bit-exact replay of those frames.
        pub raw_every: u64 = 0, closed(0, 1_000_000);
        /// JPEG quality (libjpeg's 1..100 scale). 65 keeps 1920x1080 with the synthetic camera's
        /// sensor noise under 300 MB per minute at 30 fps, at a PSNR above 32 dB.
        pub jpeg_quality: u32 = 65, closed(1, 100);
        /// Free space the recorder leaves on the recording's file system, MiB (0: no limit).
        /// Below it, frame pixels are no longer written (headers and results still are) so that
        /// the file can always be finished; above twice the limit, pixels are written again.
        pub min_free_mib: u64 = 512, closed(0, 1 << 24);
    }
}

impl RecorderConfig {
    /// Checks every value; errors name the key under `recorder`.
    pub fn validate(&self) -> Result<(), hubtrack_types::params::ParamError> {
        self.check_ranges("recorder")
    }
}
