//! Frame sinks: shared memory for the process, memory for tests and benchmarks.

use crate::{CaptureError, Fill, FrameInfo, FrameSink};
use hubtrack_runtime::ipc::FramePublisher;
use hubtrack_types::time::{monotonic_ns, realtime_ns};
use hubtrack_types::{FrameHeader, FrameSourceKind};

/// Publishes frames on the frames service, numbering them `seq = 0, 1, 2, ...`.
pub struct ShmSink {
    publisher: FramePublisher,
    source: FrameSourceKind,
    /// Sequence number of the next frame.
    pub next_seq: u64,
    /// Header of the last published frame.
    pub last: Option<FrameHeader>,
}

impl ShmSink {
    /// Wraps a frame publisher for frames of `source`.
    pub fn new(publisher: FramePublisher, source: FrameSourceKind) -> ShmSink {
        ShmSink {
            publisher,
            source,
            next_seq: 0,
            last: None,
        }
    }
}

/// The header of a tightly packed frame with `seq` described by `info`.
pub fn header_for(info: &FrameInfo, seq: u64, source: FrameSourceKind) -> FrameHeader {
    FrameHeader {
        seq,
        capture_ns: info.capture_ns.unwrap_or(0),
        capture_realtime_ns: realtime_ns(),
        publish_ns: 0,
        width: info.width,
        height: info.height,
        stride: info.stride() as u32,
        format: info.format,
        source,
        truth: info.truth,
        camera_jpeg_len: 0,
    }
}

impl ShmSink {
    fn send(
        &mut self,
        info: FrameInfo,
        camera_jpeg: &[u8],
        fill: &mut Fill<'_>,
    ) -> Result<(), CaptureError> {
        let mut header = header_for(&info, self.next_seq, self.source);
        // A JPEG too large to announce is not kept: the recorder then encodes the pixels.
        let camera_jpeg = match u32::try_from(camera_jpeg.len()) {
            Ok(len) => {
                header.camera_jpeg_len = len;
                camera_jpeg
            }
            Err(_) => &[],
        };
        let stamp_when_ready = info.capture_ns.is_none();
        let pixels_len = header.payload_len();
        let sent = self.publisher.publish_with(header, |buf, header| {
            let (pixels, tail) = buf.split_at_mut(pixels_len);
            tail.copy_from_slice(camera_jpeg);
            if let Some(truth) = fill(pixels)? {
                header.truth = truth;
            }
            if stamp_when_ready {
                header.capture_ns = monotonic_ns();
                header.capture_realtime_ns = realtime_ns();
            }
            Ok::<(), CaptureError>(())
        })?;
        self.next_seq += 1;
        self.last = Some(sent);
        Ok(())
    }
}

impl FrameSink for ShmSink {
    fn publish(&mut self, info: FrameInfo, fill: &mut Fill<'_>) -> Result<(), CaptureError> {
        self.send(info, &[], fill)
    }

    fn publish_with_camera_jpeg(
        &mut self,
        info: FrameInfo,
        jpeg: &[u8],
        fill: &mut Fill<'_>,
    ) -> Result<(), CaptureError> {
        self.send(info, jpeg, fill)
    }
}

/// Keeps the last frame in memory (tests, benchmarks, offline tools).
#[derive(Default)]
pub struct VecSink {
    /// Source kind stamped into headers.
    pub source: FrameSourceKind,
    /// Pixels of the last frame.
    pub pixels: Vec<u8>,
    /// Header of the last frame.
    pub header: FrameHeader,
    /// Frames taken.
    pub count: u64,
    /// The camera's JPEG of the last frame (empty: none).
    pub camera_jpeg: Vec<u8>,
}

impl FrameSink for VecSink {
    fn publish_with_camera_jpeg(
        &mut self,
        info: FrameInfo,
        jpeg: &[u8],
        fill: &mut Fill<'_>,
    ) -> Result<(), CaptureError> {
        self.publish(info, fill)?;
        self.camera_jpeg = jpeg.to_vec();
        self.header.camera_jpeg_len = jpeg.len() as u32;
        Ok(())
    }

    fn publish(&mut self, info: FrameInfo, fill: &mut Fill<'_>) -> Result<(), CaptureError> {
        self.pixels.resize(info.len(), 0);
        self.camera_jpeg.clear();
        self.header = header_for(&info, self.count, self.source);
        if let Some(truth) = fill(&mut self.pixels)? {
            self.header.truth = truth;
        }
        if info.capture_ns.is_none() {
            self.header.capture_ns = monotonic_ns();
        }
        self.count += 1;
        Ok(())
    }
}
