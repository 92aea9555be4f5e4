//! The pixels of a recorded frame message, whatever its schema: `foxglove.RawImage` (the pixels
//! as captured), `foxglove.CompressedImage` JPEG or `foxglove.CompressedVideo` H.264 (decoded;
//! close to, not equal to, the captured pixels). Used by replay; a message that does not decode
//! is an error naming why, never a panic.

use crate::compressed_image::{self, CompressedImage};
use crate::compressed_video::{self, CompressedVideo};
use crate::raw_image::{self, RawImage};
use crate::video::VideoDecoder;
use hubtrack_types::FrameHeader;
use prost::Message;

/// How a frame message stores its pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameCoding {
    /// `foxglove.RawImage`: bit-exact.
    Raw,
    /// `foxglove.CompressedImage`: lossy.
    Compressed,
    /// `foxglove.CompressedVideo`: lossy, and each frame needs the ones since its keyframe.
    Video,
}

impl FrameCoding {
    /// The coding of a schema name, if it is an image schema.
    pub fn of_schema(name: &str) -> Option<FrameCoding> {
        match name {
            raw_image::SCHEMA_NAME => Some(FrameCoding::Raw),
            compressed_image::SCHEMA_NAME => Some(FrameCoding::Compressed),
            compressed_video::SCHEMA_NAME => Some(FrameCoding::Video),
            _ => None,
        }
    }
}

/// Decodes a recording's frame messages, in file order (video frames depend on the ones
/// before them: every video message must pass through [`FrameDecoder::pixels`]).
#[derive(Default)]
pub struct FrameDecoder {
    video: VideoDecoder,
}

impl FrameDecoder {
    /// The pixels of one frame message in the layout its `header` describes.
    pub fn pixels(
        &mut self,
        coding: FrameCoding,
        data: &[u8],
        header: &FrameHeader,
    ) -> Result<Vec<u8>, String> {
        match coding {
            FrameCoding::Video => {
                let msg =
                    CompressedVideo::decode(data).map_err(|e| format!("CompressedVideo: {e}"))?;
                if msg.format != "h264" {
                    return Err(format!(
                        "CompressedVideo format {:?} (only h264 is read)",
                        msg.format
                    ));
                }
                self.video.decode(&msg.data, header)
            }
            other => pixels(other, data, header),
        }
    }
}

/// The pixels of one raw or JPEG frame message in the layout its `header` describes (video
/// frames need a [`FrameDecoder`]).
pub fn pixels(coding: FrameCoding, data: &[u8], header: &FrameHeader) -> Result<Vec<u8>, String> {
    match coding {
        FrameCoding::Video => Err("a video frame needs the frames before it (FrameDecoder)".into()),
        FrameCoding::Raw => {
            let img = RawImage::decode(data).map_err(|e| format!("RawImage: {e}"))?;
            if img.data.len() != header.payload_len() {
                return Err(format!(
                    "RawImage of {} bytes, the header says {}",
                    img.data.len(),
                    header.payload_len()
                ));
            }
            Ok(img.data)
        }
        FrameCoding::Compressed => {
            let img = CompressedImage::decode(data).map_err(|e| format!("CompressedImage: {e}"))?;
            if img.format != "jpeg" {
                return Err(format!(
                    "CompressedImage format {:?} (only jpeg is read)",
                    img.format
                ));
            }
            crate::jpeg::decode(&img.data, header).map_err(|e| e.to_string())
        }
    }
}
