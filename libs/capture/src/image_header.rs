//! An image's size from its file header, before anything is decoded: a 1 MB PNG can declare
//! 20000 × 20000 pixels (1.2 GB decoded), so size is checked first and such files are refused.
//!
//! PNG, JPEG, BMP and WebP headers are read; other formats are left to the decoder.

use std::io::Read;
use std::path::Path;

/// The most pixels an image may declare (width × height): 8K UHD (7680 × 4320) with margin.
/// Decoding takes 3 bytes per pixel (about 150 MB at the limit).
pub const MAX_IMAGE_PIXELS: u64 = 50_000_000;

/// Bytes read to find the size (JPEG may need to skip metadata segments: EXIF, thumbnails).
const HEADER_PROBE_BYTES: u64 = 256 * 1024;

/// Width and height declared by the header of `path`, or `None` for a format not read here or a
/// header that does not say (the decoder then decides).
pub fn declared_size(path: &Path) -> std::io::Result<Option<(u32, u32)>> {
    let mut head = Vec::new();
    std::fs::File::open(path)?
        .take(HEADER_PROBE_BYTES)
        .read_to_end(&mut head)?;
    Ok(size_from_bytes(&head))
}

fn be16(b: &[u8], i: usize) -> Option<u32> {
    Some(u32::from(u16::from_be_bytes(
        b.get(i..i + 2)?.try_into().ok()?,
    )))
}

fn le16(b: &[u8], i: usize) -> Option<u32> {
    Some(u32::from(u16::from_le_bytes(
        b.get(i..i + 2)?.try_into().ok()?,
    )))
}

fn le24(b: &[u8], i: usize) -> Option<u32> {
    let s = b.get(i..i + 3)?;
    Some(u32::from(s[0]) | u32::from(s[1]) << 8 | u32::from(s[2]) << 16)
}

fn le32(b: &[u8], i: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(i..i + 4)?.try_into().ok()?))
}

fn be32(b: &[u8], i: usize) -> Option<u32> {
    Some(u32::from_be_bytes(b.get(i..i + 4)?.try_into().ok()?))
}

/// See [`declared_size`].
pub fn size_from_bytes(b: &[u8]) -> Option<(u32, u32)> {
    if b.starts_with(b"\x89PNG\r\n\x1a\n") && b.get(12..16) == Some(b"IHDR") {
        return Some((be32(b, 16)?, be32(b, 20)?));
    }
    if b.starts_with(b"BM") {
        // BITMAPINFOHEADER: signed 32-bit width and height (negative height: top-down).
        let w = le32(b, 18)? as i32;
        let h = le32(b, 22)? as i32;
        return Some((w.unsigned_abs(), h.unsigned_abs()));
    }
    if b.starts_with(b"RIFF") && b.get(8..12) == Some(b"WEBP") {
        return match b.get(12..16)? {
            b"VP8X" => Some((le24(b, 24)? + 1, le24(b, 27)? + 1)),
            b"VP8L" => {
                let bits = le32(b, 21)?;
                Some(((bits & 0x3FFF) + 1, ((bits >> 14) & 0x3FFF) + 1))
            }
            b"VP8 " => Some((le16(b, 26)? & 0x3FFF, le16(b, 28)? & 0x3FFF)),
            _ => None,
        };
    }
    if b.starts_with(&[0xFF, 0xD8]) {
        // JPEG: walk the segments to the first start-of-frame (SOF0..SOF15 except DHT, JPG, DAC).
        let mut i = 2;
        while i + 4 <= b.len() {
            if b[i] != 0xFF {
                return None;
            }
            let marker = b[i + 1];
            if marker == 0xFF {
                i += 1;
                continue;
            }
            let len = be16(b, i + 2)? as usize;
            if (0xC0..=0xCF).contains(&marker) && ![0xC4, 0xC8, 0xCC].contains(&marker) {
                return Some((be16(b, i + 7)?, be16(b, i + 5)?));
            }
            i += 2 + len;
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_are_read_from_real_encoder_output() {
        use opencv::core::{Mat, Scalar, Vector, CV_8UC3};
        let m = Mat::new_rows_cols_with_default(37, 53, CV_8UC3, Scalar::all(90.0)).unwrap();
        for ext in [".png", ".jpg", ".bmp", ".webp"] {
            let mut buf = Vector::<u8>::new();
            opencv::imgcodecs::imencode(ext, &m, &mut buf, &Vector::new()).unwrap();
            assert_eq!(size_from_bytes(buf.as_slice()), Some((53, 37)), "{ext}");
        }
        assert_eq!(size_from_bytes(b"not an image"), None);
        assert_eq!(size_from_bytes(b"\x89PNG\r\n\x1a\n\0\0\0\x0dIHD"), None);
    }
}
