//! One API for compressing camera frames, shared by the recorder and anything else that sends
//! frames somewhere (a live view): [`FrameEncoder::encode`] takes a frame as it travels between
//! the stages (header + pixels, BGR or grey, any stride) and returns its compressed bytes.
//!
//! Codecs (chosen in `cargo bench -p hubtrack-record --bench encode`, table in
//! `docs/recording.md`):
//! - [`Codec::Jpeg`]: libjpeg-turbo (one small shared library, SIMD colour conversion and DCT),
//!   4:2:0 chroma: about twice as fast as the pure-Rust encoder;
//! - [`Codec::JpegRust`]: the pure-Rust `jpeg-encoder` (no C library), kept as the reference;
//! - [`Codec::H264`]: OpenH264 (built from source into the binary), constrained baseline: no
//!   B-frames, so every access unit can be shown as soon as it arrives; an IDR keyframe with its
//!   SPS/PPS every `keyframe_interval` frames, so a viewer or replay can start (or resume after
//!   a gap) there. Output is Annex B, one access unit per frame.

use hubtrack_types::{FrameHeader, PixelFormat};
use openh264::encoder::{
    BitRate, Encoder as H264Encoder, EncoderConfig, FrameRate, FrameType, IntraFramePeriod,
    Profile, RateControlMode, UsageType,
};
use openh264::formats::{RGB8Source, RGBSource, YUVBuffer, YUVSlices, YUVSource};
use openh264::{OpenH264API, Timestamp};

/// How frames are compressed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Codec {
    /// JPEG through libjpeg-turbo.
    Jpeg,
    /// JPEG through the pure-Rust `jpeg-encoder`.
    JpegRust,
    /// H.264 (Annex B) through OpenH264.
    H264,
}

/// What an encoder is built with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EncoderSettings {
    /// The codec.
    pub codec: Codec,
    /// JPEG quality, libjpeg's 1..=100 scale.
    pub jpeg_quality: u32,
    /// H.264 target bit rate, kbit/s.
    pub h264_bitrate_kbps: u32,
    /// H.264: an IDR keyframe every this many frames (1: every frame).
    pub keyframe_interval: u32,
    /// H.264: the highest frame rate the rate control plans for, Hz.
    pub max_fps: f32,
}

/// The format names of `foxglove.CompressedImage` / `foxglove.CompressedVideo`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EncodedFormat {
    /// `jpeg` (a `foxglove.CompressedImage`).
    Jpeg,
    /// `h264` (a `foxglove.CompressedVideo`): Annex B.
    H264,
}

impl EncodedFormat {
    /// The `format` field of the Foxglove message.
    pub fn name(self) -> &'static str {
        match self {
            EncodedFormat::Jpeg => "jpeg",
            EncodedFormat::H264 => "h264",
        }
    }
}

/// One compressed frame.
#[derive(Debug, Clone, PartialEq)]
pub struct EncodedFrame {
    /// The compressed bytes (a JPEG file, or one H.264 access unit in Annex B).
    pub data: Vec<u8>,
    /// Their format.
    pub format: EncodedFormat,
    /// True when the frame decodes on its own (every JPEG; an H.264 IDR with SPS/PPS).
    pub keyframe: bool,
}

/// Why a frame could not be encoded (the encoder stays usable for the next frame).
#[derive(Debug, thiserror::Error)]
pub enum EncodeError {
    /// The pixels do not fit the header, or the size is one the codec cannot take.
    #[error("frame {seq}: {len} bytes of pixels for {width}x{height} (stride {stride}): {why}")]
    Size {
        /// Frame seq.
        seq: u64,
        /// Bytes given.
        len: usize,
        /// Width, px.
        width: u32,
        /// Height, px.
        height: u32,
        /// Bytes per row.
        stride: u32,
        /// What does not fit.
        why: &'static str,
    },
    /// The codec library refused the frame.
    #[error("frame {seq}: {codec}: {reason}")]
    Codec {
        /// Frame seq.
        seq: u64,
        /// The codec.
        codec: &'static str,
        /// What it said.
        reason: String,
    },
}

/// Compresses frames with one codec; keeps its buffers (and, for H.264, its reference frames)
/// from frame to frame. Not shared between threads: one per consumer.
pub struct FrameEncoder {
    backend: Backend,
}

enum Backend {
    Turbo {
        compressor: turbojpeg::Compressor,
    },
    Rust(crate::jpeg::JpegEncoder),
    H264 {
        encoder: Box<H264Encoder>,
        yuv: Option<YUVBuffer>,
        grey_chroma: Vec<u8>,
        packed: Vec<u8>,
        settings: EncoderSettings,
        frames: u64,
    },
}

impl FrameEncoder {
    /// An encoder with `settings`; fails only if the codec library cannot start.
    pub fn new(settings: &EncoderSettings) -> Result<FrameEncoder, EncodeError> {
        let fail = |codec, e: String| EncodeError::Codec {
            seq: 0,
            codec,
            reason: e,
        };
        let backend = match settings.codec {
            Codec::Jpeg => {
                let mut compressor = turbojpeg::Compressor::new()
                    .map_err(|e| fail("libjpeg-turbo", e.to_string()))?;
                compressor.set_quality(settings.jpeg_quality.clamp(1, 100) as i32);
                Backend::Turbo { compressor }
            }
            Codec::JpegRust => Backend::Rust(crate::jpeg::JpegEncoder::new(settings.jpeg_quality)),
            Codec::H264 => Backend::H264 {
                encoder: Box::new(new_h264(settings).map_err(|e| fail("OpenH264", e))?),
                yuv: None,
                grey_chroma: Vec::new(),
                packed: Vec::new(),
                settings: *settings,
                frames: 0,
            },
        };
        Ok(FrameEncoder { backend })
    }

    /// What this encoder produces.
    pub fn format(&self) -> EncodedFormat {
        match self.backend {
            Backend::Turbo { .. } | Backend::Rust(_) => EncodedFormat::Jpeg,
            Backend::H264 { .. } => EncodedFormat::H264,
        }
    }

    /// The compressed form of one frame (`header` gives its size, pixel format and stride;
    /// `pixels` holds at least `header.payload_len()` bytes).
    pub fn encode(
        &mut self,
        header: &FrameHeader,
        pixels: &[u8],
    ) -> Result<EncodedFrame, EncodeError> {
        check(header, pixels)?;
        let seq = header.seq;
        let (w, h) = (header.width as usize, header.height as usize);
        let stride = header.stride as usize;
        let pixels = &pixels[..header.payload_len()];
        match &mut self.backend {
            Backend::Turbo { compressor } => {
                let (format, subsamp) = match header.format {
                    PixelFormat::Bgr8 => (turbojpeg::PixelFormat::BGR, turbojpeg::Subsamp::Sub2x2),
                    PixelFormat::Gray8 => (turbojpeg::PixelFormat::GRAY, turbojpeg::Subsamp::Gray),
                };
                compressor.set_subsamp(subsamp);
                let image = turbojpeg::Image {
                    pixels,
                    width: w,
                    pitch: stride,
                    height: h,
                    format,
                };
                let data = compressor
                    .compress_to_vec(image)
                    .map_err(|e| EncodeError::Codec {
                        seq,
                        codec: "libjpeg-turbo",
                        reason: e.to_string(),
                    })?;
                Ok(jpeg_frame(data))
            }
            Backend::Rust(enc) => {
                let data = enc.encode(header, pixels).map_err(|e| EncodeError::Codec {
                    seq,
                    codec: "jpeg-encoder",
                    reason: e.to_string(),
                })?;
                Ok(jpeg_frame(data))
            }
            Backend::H264 {
                encoder,
                yuv,
                grey_chroma,
                packed,
                settings,
                frames,
            } => {
                if w % 2 != 0 || h % 2 != 0 {
                    return Err(size_error(
                        header,
                        pixels,
                        "H.264 needs an even width and height",
                    ));
                }
                if *frames % u64::from(settings.keyframe_interval.max(1)) == 0 {
                    encoder.force_intra_frame();
                }
                *frames += 1;
                let at = Timestamp::from_millis(header.capture_ns / 1_000_000);
                let bitstream = match header.format {
                    PixelFormat::Bgr8 => {
                        let buf = match yuv {
                            Some(b) if b.dimensions() == (w, h) => b,
                            _ => yuv.insert(YUVBuffer::new(w, h)),
                        };
                        // The converter reads rows of whole pixels: repack only odd strides.
                        let (rows, stride) = if stride.is_multiple_of(3) {
                            (pixels, stride)
                        } else {
                            packed.clear();
                            for r in pixels.chunks(stride) {
                                packed.extend_from_slice(&r[..w * 3]);
                            }
                            (&packed[..], w * 3)
                        };
                        buf.read_rgb8(BgrRows {
                            pixels: rows,
                            w,
                            h,
                            stride,
                        });
                        encoder.encode_at(&*buf, at)
                    }
                    PixelFormat::Gray8 => {
                        // Grey is Y alone: chroma stays at its neutral 128.
                        let (cw, ch) = (w / 2, h / 2);
                        grey_chroma.resize(cw * ch, 128);
                        let planes = YUVSlices::new(
                            (pixels, &grey_chroma[..], &grey_chroma[..]),
                            (w, h),
                            (stride, cw, cw),
                        );
                        encoder.encode_at(&planes, at)
                    }
                }
                .map_err(|e| EncodeError::Codec {
                    seq,
                    codec: "OpenH264",
                    reason: e.to_string(),
                })?;
                let keyframe = bitstream.frame_type() == FrameType::IDR;
                let data = bitstream.to_vec();
                if data.is_empty() {
                    return Err(EncodeError::Codec {
                        seq,
                        codec: "OpenH264",
                        reason: "the encoder skipped the frame".into(),
                    });
                }
                Ok(EncodedFrame {
                    data,
                    format: EncodedFormat::H264,
                    keyframe,
                })
            }
        }
    }
}

fn jpeg_frame(data: Vec<u8>) -> EncodedFrame {
    EncodedFrame {
        data,
        format: EncodedFormat::Jpeg,
        keyframe: true,
    }
}

fn size_error(header: &FrameHeader, pixels: &[u8], why: &'static str) -> EncodeError {
    EncodeError::Size {
        seq: header.seq,
        len: pixels.len(),
        width: header.width,
        height: header.height,
        stride: header.stride,
        why,
    }
}

/// The checks every codec needs before it touches the pixels.
fn check(header: &FrameHeader, pixels: &[u8]) -> Result<(), EncodeError> {
    let row = header.width as usize * header.format.bytes_per_pixel();
    if header.width == 0 || header.height == 0 {
        return Err(size_error(header, pixels, "empty frame"));
    }
    if header.width > u32::from(u16::MAX) || header.height > u32::from(u16::MAX) {
        return Err(size_error(header, pixels, "larger than a JPEG can be"));
    }
    if (header.stride as usize) < row {
        return Err(size_error(header, pixels, "stride shorter than a row"));
    }
    if pixels.len() < header.payload_len() {
        return Err(size_error(
            header,
            pixels,
            "fewer bytes than the header says",
        ));
    }
    Ok(())
}

fn new_h264(s: &EncoderSettings) -> Result<H264Encoder, String> {
    // Real-time camera usage with bit-rate control; frame skipping off: every frame is one
    // access unit (a skipped frame would be a hole in the recording).
    let config = EncoderConfig::new()
        .usage_type(UsageType::CameraVideoRealTime)
        .profile(Profile::Baseline)
        .rate_control_mode(RateControlMode::Bitrate)
        .bitrate(BitRate::from_bps(s.h264_bitrate_kbps.saturating_mul(1000)))
        .max_frame_rate(FrameRate::from_hz(s.max_fps))
        .skip_frames(false)
        .intra_frame_period(IntraFramePeriod::from_num_frames(
            s.keyframe_interval.max(1),
        ))
        .num_threads(1);
    H264Encoder::with_api_config(OpenH264API::from_source(), config).map_err(|e| e.to_string())
}

/// BGR rows (any stride that holds whole pixels) for OpenH264's SIMD colour conversion.
struct BgrRows<'a> {
    pixels: &'a [u8],
    w: usize,
    h: usize,
    stride: usize,
}

impl RGBSource for BgrRows<'_> {
    fn dimensions(&self) -> (usize, usize) {
        (self.w, self.h)
    }

    fn pixel_f32(&self, x: usize, y: usize) -> (f32, f32, f32) {
        let i = y * self.stride + x * 3;
        (
            f32::from(self.pixels[i + 2]),
            f32::from(self.pixels[i + 1]),
            f32::from(self.pixels[i]),
        )
    }
}

impl RGB8Source for BgrRows<'_> {
    fn dimensions_padded(&self) -> (usize, usize) {
        (self.stride / 3, self.h)
    }

    fn rgb8_data(&self) -> &[u8] {
        self.pixels
    }

    fn rgb_channel_offsets(&self) -> (usize, usize, usize) {
        (2, 1, 0)
    }
}
