//! A frame's pixels on their way from shared memory to the file.
//!
//! The reader compresses each frame straight from its shared-memory sample ([`FramePacker`]):
//! a 1080p BGR frame is 6 MB, and copying 180 MB/s into private buffers first would take the
//! memory bandwidth the detector on the other core needs. Only pixels that are written raw
//! (`frame_encoding = "raw"`, or a raw copy for `/frames/raw`) are copied, into a fixed pool of
//! buffers. Every recorded frame holds one pool buffer until the writer is done with it
//! ([`write_frame`] gives it back), so the pool also bounds the frames in flight: when the disk
//! falls behind and the pool is empty, frames are dropped and counted, and the camera never
//! waits.
//!
//! The reader holds each frame until detect has published its result for it ([`HeldFrame`]):
//! encoding a 1080p frame reads 6 MB, and doing it while detect works on the same frame on the
//! other core slows detect down; a frame period later the memory bus is free.

use anyhow::Context;
use hubtrack_record::config::RecorderConfig;
use hubtrack_record::encoder::{EncodedFormat, EncodedFrame, FrameEncoder};
use hubtrack_record::writer::RecorderStats;
use hubtrack_record::{RecordError, Recording};
use hubtrack_runtime::ipc::FrameSample;
use hubtrack_types::FrameHeader;
use std::sync::mpsc::{Receiver, SyncSender};
use std::time::{Duration, Instant};

/// A frame received from shared memory and not yet compressed.
pub struct HeldFrame {
    /// The sample (still in shared memory).
    pub sample: FrameSample,
    /// Its pixels go to `/frames/raw` as well.
    pub raw_copy: bool,
    /// Wall-clock time it was received, ns (its MCAP log time).
    pub log_time: u64,
    received: Instant,
}

impl HeldFrame {
    /// A frame received now.
    pub fn new(sample: FrameSample, raw_copy: bool, log_time: u64) -> HeldFrame {
        HeldFrame {
            sample,
            raw_copy,
            log_time,
            received: Instant::now(),
        }
    }

    /// True once detect is done with the frame (a detection of this frame or a later one has
    /// arrived: `detected_seq`) or the frame has waited `wait` (detect is not running, or it
    /// skipped this frame).
    pub fn due(&self, detected_seq: Option<u64>, wait: Duration) -> bool {
        ready(
            self.sample.user_header().seq,
            detected_seq,
            self.received.elapsed(),
            wait,
        )
    }
}

fn ready(seq: u64, detected_seq: Option<u64>, waited: Duration, wait: Duration) -> bool {
    detected_seq.is_some_and(|d| d >= seq) || waited >= wait
}

/// What of a frame's pixels is to be written.
pub enum Pixels {
    /// None: frames are not recorded (`record_frames = false`); the header still is.
    None,
    /// Raw on `/frames`: the pixels, copied into a pool buffer.
    Raw(Vec<u8>),
    /// Compressed on `/frames` (JPEG or H.264).
    Encoded {
        /// The compressed frame, or why it could not be compressed.
        frame: Result<EncodedFrame, String>,
        /// The bytes are the camera's own JPEG, not encoded here.
        from_camera: bool,
        /// The frame's pool buffer; holds the raw pixels when `raw_copy`.
        buffer: Vec<u8>,
        /// The raw pixels go to `/frames/raw` as well (`raw_every`, a raw window).
        raw_copy: bool,
    },
}

/// The reader's side: compresses from the sample, copies what is written raw.
pub struct FramePacker {
    encoder: Option<FrameEncoder>,
    record_frames: bool,
    free: Receiver<Vec<u8>>,
}

impl FramePacker {
    /// A packer drawing buffers from `free` (the writer gives them back).
    pub fn new(cfg: &RecorderConfig, free: Receiver<Vec<u8>>) -> anyhow::Result<FramePacker> {
        let encoder = cfg
            .encoder_settings()
            .map(|s| FrameEncoder::new(&s))
            .transpose()
            .context("starting the frame encoder")?;
        Ok(FramePacker {
            encoder,
            record_frames: cfg.record_frames,
            free,
        })
    }

    /// The pixels of the frame in `payload` (a sample: pixels, then the camera's JPEG if the
    /// header announces one) as they are to be written; `None` when no pool buffer is free (the
    /// writer is behind): the frame is dropped.
    pub fn pack(&mut self, header: &FrameHeader, payload: &[u8], raw_copy: bool) -> Option<Pixels> {
        if !self.record_frames {
            return Some(Pixels::None);
        }
        let mut buffer = self.free.try_recv().ok()?;
        buffer.clear();
        let pixels = &payload[..header.payload_len().min(payload.len())];
        let Some(encoder) = self.encoder.as_mut() else {
            buffer.extend_from_slice(pixels);
            return Some(Pixels::Raw(buffer));
        };
        let camera_jpeg = header
            .camera_jpeg(payload)
            .filter(|_| encoder.format() == EncodedFormat::Jpeg);
        let (frame, from_camera) = match camera_jpeg {
            Some(jpeg) => (
                Ok(EncodedFrame {
                    data: jpeg.to_vec(),
                    format: EncodedFormat::Jpeg,
                    keyframe: true,
                }),
                true,
            ),
            None => (
                encoder.encode(header, pixels).map_err(|e| e.to_string()),
                false,
            ),
        };
        if raw_copy {
            buffer.extend_from_slice(pixels);
        }
        Some(Pixels::Encoded {
            frame,
            from_camera,
            buffer,
            raw_copy,
        })
    }
}

/// The writer's side: writes the frame (only its header when `disk_low`), counts it, and gives
/// its pool buffer back.
pub fn write_frame(
    rec: &mut Recording,
    header: &FrameHeader,
    pixels: Pixels,
    disk_low: bool,
    log_time: u64,
    stats: &mut RecorderStats,
    free: &SyncSender<Vec<u8>>,
) -> Result<(), RecordError> {
    let give_back = |buffer: Vec<u8>| {
        let _ = free.try_send(buffer);
    };
    match pixels {
        Pixels::None => rec.write_frame(header, None, log_time),
        Pixels::Raw(buffer) | Pixels::Encoded { buffer, .. } if disk_low => {
            stats.frames_dropped_disk += 1;
            give_back(buffer);
            rec.write_frame(header, None, log_time)
        }
        Pixels::Raw(buffer) => {
            stats.bytes_written += buffer.len() as u64;
            let r = rec.write_frame(header, Some(&buffer), log_time);
            give_back(buffer);
            r
        }
        Pixels::Encoded {
            frame,
            from_camera,
            buffer,
            raw_copy,
        } => {
            match frame {
                Ok(frame) => {
                    stats.frames_camera_jpeg += u64::from(from_camera);
                    stats.bytes_written += frame.data.len() as u64;
                    rec.write_encoded(header, frame, log_time)?;
                }
                Err(e) => {
                    stats.frames_encode_failed += 1;
                    log::warn!("frame not encoded, header kept: {e}");
                }
            }
            if raw_copy {
                stats.bytes_written += buffer.len() as u64;
                stats.frames_raw_copies += 1;
            }
            let r = rec.write_frame(header, raw_copy.then_some(&buffer[..]), log_time);
            give_back(buffer);
            r
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_is_due_once_detected_or_after_the_wait() {
        let wait = Duration::from_millis(25);
        let early = Duration::from_millis(3);
        assert!(!ready(7, None, early, wait), "no detection yet");
        assert!(
            !ready(7, Some(6), early, wait),
            "detect still on an older frame"
        );
        assert!(ready(7, Some(7), early, wait), "its own detection");
        assert!(ready(7, Some(9), early, wait), "detect skipped it");
        assert!(ready(7, None, wait, wait), "detect not running");
    }
}
