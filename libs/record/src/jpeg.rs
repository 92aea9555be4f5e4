//! JPEG frames: encoding for the recorder, decoding for replay. Through OpenCV's imgcodecs, which
//! on Debian links libjpeg-turbo (SIMD; measured in `cargo bench -p hubtrack-record`).

use hubtrack_types::{FrameHeader, PixelFormat};
use opencv::core::{Mat, Rect, Vector};
use opencv::imgcodecs;
use opencv::prelude::*;

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
    /// The bytes are not a JPEG of the header's size.
    #[error("frame {seq}: {reason}")]
    Bad {
        /// Frame seq.
        seq: u64,
        /// What is wrong.
        reason: String,
    },
    /// OpenCV failed.
    #[error("frame {seq}: OpenCV: {0}", seq = .1)]
    OpenCv(opencv::Error, u64),
}

/// Encodes frames to JPEG at a fixed quality, reusing its buffers.
pub struct JpegEncoder {
    params: Vector<i32>,
    out: Vector<u8>,
}

impl JpegEncoder {
    /// An encoder at `quality` (1..=100, libjpeg's scale).
    pub fn new(quality: u32) -> JpegEncoder {
        JpegEncoder {
            params: Vector::from_slice(&[imgcodecs::IMWRITE_JPEG_QUALITY, quality as i32]),
            out: Vector::new(),
        }
    }

    /// The JPEG of one frame (the header says its size, layout and stride).
    pub fn encode(&mut self, header: &FrameHeader, pixels: &[u8]) -> Result<Vec<u8>, JpegError> {
        let seq = header.seq;
        let cv = |e| JpegError::OpenCv(e, seq);
        let bpp = header.format.bytes_per_pixel();
        let need = header.payload_len();
        let row = header.width as usize * bpp;
        if pixels.len() < need || (header.stride as usize) < row || need == 0 {
            return Err(JpegError::Size {
                seq,
                len: pixels.len(),
                need,
                width: header.width,
                height: header.height,
                stride: header.stride,
            });
        }
        let h = header.height as i32;
        // Borrowed: rows of `stride` bytes, the valid columns, then the channel layout.
        let flat = Mat::new_rows_cols_with_data::<u8>(h, header.stride as i32, &pixels[..need])
            .map_err(cv)?;
        let roi = flat.roi(Rect::new(0, 0, row as i32, h)).map_err(cv)?;
        let image = roi.reshape(bpp as i32, h).map_err(cv)?;
        imgcodecs::imencode(".jpg", &image, &mut self.out, &self.params).map_err(cv)?;
        Ok(self.out.to_vec())
    }
}

/// The pixels of a JPEG frame in the layout `header` describes (format and stride), for replay.
pub fn decode(jpeg: &[u8], header: &FrameHeader) -> Result<Vec<u8>, JpegError> {
    let seq = header.seq;
    let cv = |e| JpegError::OpenCv(e, seq);
    let flags = match header.format {
        PixelFormat::Bgr8 => imgcodecs::IMREAD_COLOR,
        PixelFormat::Gray8 => imgcodecs::IMREAD_GRAYSCALE,
    };
    let bad = |reason: String| JpegError::Bad { seq, reason };
    if jpeg.len() < 4 || jpeg[..2] != [0xff, 0xd8] {
        return Err(bad(format!("not a JPEG ({} bytes)", jpeg.len())));
    }
    let image = imgcodecs::imdecode(&Vector::<u8>::from_slice(jpeg), flags).map_err(cv)?;
    if image.empty() {
        return Err(bad("JPEG does not decode (corrupt or truncated)".into()));
    }
    if (image.cols() as u32, image.rows() as u32) != (header.width, header.height) {
        return Err(bad(format!(
            "JPEG is {}x{}, the header says {}x{}",
            image.cols(),
            image.rows(),
            header.width,
            header.height
        )));
    }
    let row = header.width as usize * header.format.bytes_per_pixel();
    let stride = header.stride as usize;
    if stride < row {
        return Err(bad(format!("stride {stride} below a row of {row} bytes")));
    }
    // imdecode returns a continuous image: rows of exactly `row` bytes.
    let src = image.data_bytes().map_err(cv)?;
    if src.len() != row * header.height as usize {
        return Err(bad(format!(
            "decoded {} bytes, expected {}",
            src.len(),
            row * header.height as usize
        )));
    }
    let mut out = vec![0u8; header.payload_len()];
    for (dst, src) in out.chunks_mut(stride).zip(src.chunks(row)) {
        dst[..row].copy_from_slice(src);
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
        // A cut JPEG: libjpeg may fill the missing rows or refuse; either way no panic.
        let _ = decode(&jpeg[..jpeg.len() / 3], &h);
        assert!(decode(&[0xff, 0xd8, 0, 0, 1, 2, 3], &h).is_err());
        assert!(decode(b"not a jpeg", &h).is_err());
        let mut other = h;
        other.width = 16;
        other.stride = 48;
        assert!(decode(&jpeg, &other).is_err(), "size mismatch");
    }
}
