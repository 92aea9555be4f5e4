//! The pixels of a recorded frame message, whatever its schema: `foxglove.RawImage` (the pixels
//! as captured) or `foxglove.CompressedImage` JPEG (decoded; close to, not equal to, the
//! captured pixels). Used by replay; a message that does not decode is an error naming why,
//! never a panic.

use crate::compressed_image::{self, CompressedImage};
use crate::raw_image::{self, RawImage};
use hubtrack_types::FrameHeader;
use prost::Message;

/// How a frame message stores its pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameCoding {
    /// `foxglove.RawImage`: bit-exact.
    Raw,
    /// `foxglove.CompressedImage`: lossy.
    Compressed,
}

impl FrameCoding {
    /// The coding of a schema name, if it is an image schema.
    pub fn of_schema(name: &str) -> Option<FrameCoding> {
        match name {
            raw_image::SCHEMA_NAME => Some(FrameCoding::Raw),
            compressed_image::SCHEMA_NAME => Some(FrameCoding::Compressed),
            _ => None,
        }
    }
}

/// The pixels of one frame message in the layout its `header` describes.
pub fn pixels(coding: FrameCoding, data: &[u8], header: &FrameHeader) -> Result<Vec<u8>, String> {
    match coding {
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
