//! Whether a JPEG the camera delivered can be recorded as it is, instead of encoding the decoded
//! pixels again: it must show exactly those pixels in any viewer.
//!
//! Refused (the recorder then encodes the pixels):
//! - no Huffman tables before the scan: many UVC cameras send "motion JPEG" without them and
//!   rely on the decoder's defaults, which not every viewer has;
//! - an EXIF block: it may carry an orientation our decoder applied and a viewer would apply
//!   differently (or not at all);
//! - anything that is not a JPEG marker stream up to its scan.

/// JPEG markers read here (ITU T.81, table B.1).
const SOI: u8 = 0xD8;
const SOS: u8 = 0xDA;
const DHT: u8 = 0xC4;
const APP1: u8 = 0xE1;

/// True when `bytes` is a JPEG that decodes the same everywhere (see the module docs).
pub fn recordable_as_is(bytes: &[u8]) -> bool {
    if bytes.len() < 4 || bytes[0] != 0xFF || bytes[1] != SOI {
        return false;
    }
    let mut i = 2;
    let mut huffman_tables = false;
    while i + 4 <= bytes.len() {
        if bytes[i] != 0xFF {
            return false;
        }
        let marker = bytes[i + 1];
        if marker == 0xFF {
            i += 1; // fill byte
            continue;
        }
        let len = usize::from(u16::from_be_bytes([bytes[i + 2], bytes[i + 3]]));
        if len < 2 {
            return false;
        }
        match marker {
            SOS => return huffman_tables,
            DHT => huffman_tables = true,
            APP1 if bytes.get(i + 4..i + 10) == Some(b"Exif\0\0".as_slice()) => return false,
            _ => {}
        }
        i += 2 + len;
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    fn segment(marker: u8, body: &[u8]) -> Vec<u8> {
        let mut s = vec![0xFF, marker];
        s.extend_from_slice(&((body.len() + 2) as u16).to_be_bytes());
        s.extend_from_slice(body);
        s
    }

    fn jpeg(segments: &[Vec<u8>]) -> Vec<u8> {
        let mut j = vec![0xFF, SOI];
        for s in segments {
            j.extend_from_slice(s);
        }
        j.extend_from_slice(&segment(SOS, &[1, 1, 0, 0, 63, 0]));
        j.extend_from_slice(&[0x12, 0x34, 0xFF, 0xD9]);
        j
    }

    #[test]
    fn a_complete_jpeg_is_kept() {
        let j = jpeg(&[segment(0xE0, b"JFIF\0\x01\x01"), segment(DHT, &[0; 17])]);
        assert!(recordable_as_is(&j));
    }

    #[test]
    fn a_jpeg_a_real_encoder_wrote_is_kept() {
        let m = opencv::core::Mat::new_rows_cols_with_default(
            48,
            64,
            opencv::core::CV_8UC3,
            opencv::core::Scalar::all(90.0),
        )
        .unwrap();
        let mut buf = opencv::core::Vector::<u8>::new();
        opencv::imgcodecs::imencode_def(".jpg", &m, &mut buf).unwrap();
        assert!(recordable_as_is(buf.as_slice()));
    }

    #[test]
    fn motion_jpeg_without_huffman_tables_is_encoded_again() {
        let j = jpeg(&[segment(0xE0, b"AVI1\0\0\0")]);
        assert!(!recordable_as_is(&j));
    }

    #[test]
    fn a_jpeg_with_exif_is_encoded_again() {
        let j = jpeg(&[segment(APP1, b"Exif\0\0MM\0*"), segment(DHT, &[0; 17])]);
        assert!(!recordable_as_is(&j));
    }

    #[test]
    fn garbage_and_cut_jpegs_are_encoded_again() {
        let j = jpeg(&[segment(DHT, &[0; 17])]);
        for bad in [
            &[][..],
            &[0xFF, SOI],
            &j[..9],
            b"not a jpeg at all",
            &[0xFF, SOI, 0xFF, 0xC4, 0, 0],
        ] {
            assert!(!recordable_as_is(bad), "{bad:?}");
        }
    }
}
