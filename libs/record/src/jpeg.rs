//! JPEG frames in pure Rust: the `jpeg-encoder` backend of [`crate::encoder::FrameEncoder`]
//! (`recorder.jpeg_library = "jpeg-encoder"`; libjpeg-turbo is the default) and decoding for
//! replay (`jpeg-decoder`). OpenCV's imgcodecs would pull about 120 shared libraries into the
//! recorder and the `hubtrack` command. Measured in `cargo bench -p hubtrack-record --bench encode`.

use hubtrack_types::{FrameHeader, PixelFormat};
use jpeg_encoder::{ColorType, Encoder};

/// Why a frame could not be encoded or decoded.
#[derive(Debug, thiserror::Error)]
pub enum JpegError {
    /// The pixels do not fit the header.
    #[error("frame {seq}: {len} bytes of pixels, the header says {need} ({width}x{height}, stride {stride})")]
    Size {
        /// Frame seq.
        seq: u64,
        /// Bytes given.
        len: usize,
        /// Bytes the header implies.
        need: usize,
        /// Width, px.
        width: u32,
        /// Height, px.
        height: u32,
        /// Bytes per row.
        stride: u32,
    },
    /// The bytes are not a JPEG of the header's size, or the encoder refused the frame.
    #[error("frame {seq}: {reason}")]
    Bad {
        /// Frame seq.
        seq: u64,
        /// What is wrong.
        reason: String,
    },
}

/// Encodes frames to JPEG at a fixed quality (4:2:0 chroma), reusing its row buffer.
pub struct JpegEncoder {
    quality: u8,
    packed: Vec<u8>,
}

impl JpegEncoder {
    /// An encoder at `quality` (1..=100, libjpeg's scale).
    pub fn new(quality: u32) -> JpegEncoder {
        JpegEncoder {
            quality: quality.clamp(1, 100) as u8,
            packed: Vec::new(),
        }
    }

    /// The JPEG of one frame (the header says its size, layout and stride).
    pub fn encode(&mut self, header: &FrameHeader, pixels: &[u8]) -> Result<Vec<u8>, JpegError> {
        let seq = header.seq;
        let bpp = header.format.bytes_per_pixel();
        let need = header.payload_len();
        let row = header.width as usize * bpp;
        let too_big = header.width > u32::from(u16::MAX) || header.height > u32::from(u16::MAX);
        if pixels.len() < need || (header.stride as usize) < row || need == 0 || too_big {
            return Err(JpegError::Size {
                seq,
                len: pixels.len(),
                need,
                width: header.width,
                height: header.height,
                stride: header.stride,
            });
        }
        // The encoder reads packed rows: copy only when the rows are padded.
        let data = if header.stride as usize == row {
            &pixels[..need]
        } else {
            self.packed.clear();
            for r in pixels[..need].chunks(header.stride as usize) {
                self.packed.extend_from_slice(&r[..row]);
            }
            &self.packed[..]
        };
        let color = match header.format {
            PixelFormat::Bgr8 => ColorType::Bgr,
            PixelFormat::Gray8 => ColorType::Luma,
        };
        let mut out = Vec::with_capacity(need / 16);
        Encoder::new(&mut out, self.quality)
            .encode(data, header.width as u16, header.height as u16, color)
            .map_err(|e| JpegError::Bad {
                seq,
                reason: format!("JPEG encoder: {e}"),
            })?;
        Ok(out)
    }
}

/// The pixels of a JPEG frame in the layout `header` describes (format and stride), for replay.
pub fn decode(jpeg: &[u8], header: &FrameHeader) -> Result<Vec<u8>, JpegError> {
    let seq = header.seq;
    let bad = |reason: String| JpegError::Bad { seq, reason };
    if jpeg.len() < 4 || jpeg[..2] != [0xff, 0xd8] {
        return Err(bad(format!("not a JPEG ({} bytes)", jpeg.len())));
    }
    let mut decoder = jpeg_decoder::Decoder::new(jpeg);
    let decoded = decoder
        .decode()
        .map_err(|e| bad(format!("JPEG does not decode: {e}")))?;
    let info = decoder
        .info()
        .ok_or_else(|| bad("JPEG without a frame header".into()))?;
    if (u32::from(info.width), u32::from(info.height)) != (header.width, header.height) {
        return Err(bad(format!(
            "JPEG is {}x{}, the header says {}x{}",
            info.width, info.height, header.width, header.height
        )));
    }
    let src_bpp = match info.pixel_format {
        jpeg_decoder::PixelFormat::L8 => 1,
        jpeg_decoder::PixelFormat::RGB24 => 3,
        other => return Err(bad(format!("JPEG pixel format {other:?} not read"))),
    };
    let (w, h) = (header.width as usize, header.height as usize);
    if decoded.len() != w * h * src_bpp {
        return Err(bad(format!(
            "decoded {} bytes, expected {}",
            decoded.len(),
            w * h * src_bpp
        )));
    }
    let bpp = header.format.bytes_per_pixel();
    let stride = header.stride as usize;
    if stride < w * bpp {
        return Err(bad(format!(
            "stride {stride} below a row of {} bytes",
            w * bpp
        )));
    }
    let mut out = vec![0u8; header.payload_len()];
    for (dst, src) in out.chunks_mut(stride).zip(decoded.chunks(w * src_bpp)) {
        match (header.format, src_bpp) {
            (PixelFormat::Bgr8, 3) => {
                for (d, s) in dst[..w * 3].chunks_mut(3).zip(src.chunks(3)) {
                    d.copy_from_slice(&[s[2], s[1], s[0]]);
                }
            }
            (PixelFormat::Bgr8, _) => {
                for (d, &l) in dst[..w * 3].chunks_mut(3).zip(src) {
                    d.fill(l);
                }
            }
            (PixelFormat::Gray8, 1) => dst[..w].copy_from_slice(src),
            (PixelFormat::Gray8, _) => {
                return Err(bad("a colour JPEG for a grey frame".into()));
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(w: u32, h: u32, stride: u32) -> (FrameHeader, Vec<u8>) {
        let header = FrameHeader {
            seq: 7,
            width: w,
            height: h,
            stride,
            format: PixelFormat::Bgr8,
            ..Default::default()
        };
        let mut px = vec![0u8; (stride * h) as usize];
        for y in 0..h as usize {
            for x in 0..(w * 3) as usize {
                px[y * stride as usize + x] = ((x / 3 + y) % 200) as u8 + 20;
            }
        }
        (header, px)
    }

    #[test]
    fn round_trip_keeps_size_stride_and_content() {
        let (h, px) = frame(64, 48, 64 * 3 + 8);
        let jpeg = JpegEncoder::new(95).encode(&h, &px).unwrap();
        assert_eq!(&jpeg[..2], &[0xff, 0xd8]);
        let back = decode(&jpeg, &h).unwrap();
        assert_eq!(back.len(), px.len());
        let row = 64 * 3;
        let err: f64 = (0..48)
            .flat_map(|y| (0..row).map(move |x| y * (row + 8) + x))
            .map(|i| (back[i] as f64 - px[i] as f64).abs())
            .sum::<f64>()
            / (48 * row) as f64;
        assert!(err < 3.0, "mean abs error {err}");
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let (h, px) = frame(32, 32, 96);
        assert!(JpegEncoder::new(90).encode(&h, &px[..100]).is_err());
        let jpeg = JpegEncoder::new(90).encode(&h, &px).unwrap();
        // A cut JPEG: the decoder may fill the missing rows or refuse; either way no panic.
        let _ = decode(&jpeg[..jpeg.len() / 3], &h);
        assert!(decode(&[0xff, 0xd8, 0, 0, 1, 2, 3], &h).is_err());
        assert!(decode(b"not a jpeg", &h).is_err());
        let mut other = h;
        other.width = 16;
        other.stride = 48;
        assert!(decode(&jpeg, &other).is_err(), "size mismatch");
    }
}
