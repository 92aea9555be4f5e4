//! H.264 frames back to pixels, for replay: one access unit per recorded frame, decoded in file
//! order by OpenH264. A P-frame needs the frames before it, so after an access unit that does
//! not decode (corrupt, truncated, or missing) the decoder skips every frame up to the next IDR
//! keyframe and resumes there; each skipped frame is an error naming why, never a panic.

use hubtrack_types::{FrameHeader, PixelFormat};
use openh264::decoder::Decoder;
use openh264::formats::YUVSource;
use openh264::OpenH264API;

/// NAL unit type of an IDR slice (ITU-T H.264, Table 7-1).
const NAL_IDR: u8 = 5;

/// True when the Annex B access unit holds an IDR slice (a frame that decodes on its own).
pub fn is_keyframe(access_unit: &[u8]) -> bool {
    openh264::nal_units(access_unit).any(|nal| {
        // A NAL unit starts with its 3- or 4-byte start code; the header byte follows.
        let body = nal.iter().position(|&b| b == 1).map(|i| &nal[i + 1..]);
        body.and_then(|b| b.first())
            .is_some_and(|h| h & 0x1f == NAL_IDR)
    })
}

/// Decodes a recording's H.264 access units in order.
pub struct VideoDecoder {
    decoder: Option<Decoder>,
    /// True until a keyframe decodes (at the start and after any failure).
    waiting_for_keyframe: bool,
    rgb: Vec<u8>,
}

impl Default for VideoDecoder {
    fn default() -> Self {
        VideoDecoder::new()
    }
}

impl VideoDecoder {
    /// A decoder waiting for the first keyframe.
    pub fn new() -> VideoDecoder {
        VideoDecoder {
            decoder: None,
            waiting_for_keyframe: true,
            rgb: Vec::new(),
        }
    }

    /// The pixels of one access unit in the layout `header` describes (format and stride).
    pub fn decode(&mut self, access_unit: &[u8], header: &FrameHeader) -> Result<Vec<u8>, String> {
        let key = is_keyframe(access_unit);
        if self.waiting_for_keyframe && !key {
            return Err("H.264 P-frame before a keyframe (skipped up to the next keyframe)".into());
        }
        let r = self.decode_unit(access_unit, header);
        self.waiting_for_keyframe = r.is_err();
        if r.is_err() {
            // The reference chain is broken: start afresh at the next keyframe.
            self.decoder = None;
        }
        r
    }

    fn decode_unit(&mut self, access_unit: &[u8], header: &FrameHeader) -> Result<Vec<u8>, String> {
        if self.decoder.is_none() {
            let d = Decoder::with_api_config(OpenH264API::from_source(), Default::default())
                .map_err(|e| format!("OpenH264 decoder: {e}"))?;
            self.decoder = Some(d);
        }
        let decoder = self.decoder.as_mut().expect("set above");
        let yuv = decoder
            .decode(access_unit)
            .map_err(|e| format!("H.264 access unit does not decode: {e}"))?
            .ok_or("H.264 access unit without a picture")?;
        let (w, h) = yuv.dimensions();
        if (w as u32, h as u32) != (header.width, header.height) {
            return Err(format!(
                "H.264 picture is {w}x{h}, the header says {}x{}",
                header.width, header.height
            ));
        }
        let stride = header.stride as usize;
        let bpp = header.format.bytes_per_pixel();
        if stride < w * bpp {
            return Err(format!("stride {stride} below a row of {} bytes", w * bpp));
        }
        let mut out = vec![0u8; header.payload_len()];
        match header.format {
            PixelFormat::Bgr8 => {
                self.rgb.resize(w * h * 3, 0);
                yuv.write_rgb8(&mut self.rgb);
                for (dst, src) in out.chunks_mut(stride).zip(self.rgb.chunks(w * 3)) {
                    for (d, s) in dst[..w * 3].chunks_mut(3).zip(src.chunks(3)) {
                        d.copy_from_slice(&[s[2], s[1], s[0]]);
                    }
                }
            }
            PixelFormat::Gray8 => {
                let y_stride = yuv.strides().0;
                for (dst, src) in out.chunks_mut(stride).zip(yuv.y().chunks(y_stride)) {
                    dst[..w].copy_from_slice(&src[..w]);
                }
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::encoder::{Codec, EncoderSettings, FrameEncoder};

    fn settings() -> EncoderSettings {
        EncoderSettings {
            codec: Codec::H264,
            jpeg_quality: 80,
            h264_bitrate_kbps: 2000,
            keyframe_interval: 5,
            max_fps: 30.0,
        }
    }

    fn frame(seq: u64, format: PixelFormat, stride_pad: u32) -> (FrameHeader, Vec<u8>) {
        let (w, h) = (96u32, 64u32);
        let bpp = format.bytes_per_pixel() as u32;
        let stride = w * bpp + stride_pad;
        let header = FrameHeader {
            seq,
            width: w,
            height: h,
            stride,
            format,
            capture_ns: seq * 33_000_000,
            ..Default::default()
        };
        let mut px = vec![0u8; (stride * h) as usize];
        for y in 0..h as usize {
            for x in 0..(w * bpp) as usize {
                px[y * stride as usize + x] =
                    ((x / bpp as usize + y + seq as usize) % 160) as u8 + 40;
            }
        }
        (header, px)
    }

    fn mean_abs(a: &[u8], b: &[u8], h: &FrameHeader) -> f64 {
        let row = (h.width as usize) * h.format.bytes_per_pixel();
        let mut sum = 0.0;
        for y in 0..h.height as usize {
            let o = y * h.stride as usize;
            for x in 0..row {
                sum += (a[o + x] as f64 - b[o + x] as f64).abs();
            }
        }
        sum / (row * h.height as usize) as f64
    }

    #[test]
    fn keyframes_at_the_interval_and_round_trip() {
        for (format, pad) in [
            (PixelFormat::Bgr8, 0),
            (PixelFormat::Bgr8, 4),
            (PixelFormat::Gray8, 8),
        ] {
            let mut enc = FrameEncoder::new(&settings()).unwrap();
            let mut dec = VideoDecoder::new();
            for seq in 0..12 {
                let (h, px) = frame(seq, format, pad);
                let e = enc.encode(&h, &px).unwrap();
                assert_eq!(e.keyframe, seq % 5 == 0, "seq {seq}");
                assert_eq!(is_keyframe(&e.data), e.keyframe);
                assert!(e.data.starts_with(&[0, 0, 0, 1]), "Annex B start code");
                let back = dec.decode(&e.data, &h).unwrap();
                assert_eq!(back.len(), px.len());
                let err = mean_abs(&back, &px, &h);
                assert!(err < 6.0, "{format:?} seq {seq}: mean abs error {err}");
            }
        }
    }

    #[test]
    fn corrupt_units_are_skipped_until_the_next_keyframe() {
        let mut enc = FrameEncoder::new(&settings()).unwrap();
        let units: Vec<_> = (0..12)
            .map(|seq| {
                let (h, px) = frame(seq, PixelFormat::Bgr8, 0);
                (h, enc.encode(&h, &px).unwrap().data)
            })
            .collect();
        let mut dec = VideoDecoder::new();
        // Starting mid-stream: P-frames are refused until the keyframe at seq 5.
        let results: Vec<bool> = units[2..]
            .iter()
            .enumerate()
            .map(|(i, (h, au))| {
                // Frame 7 is truncated to a third, frame 8 is garbage.
                let au: Vec<u8> = match i + 2 {
                    7 => au[..au.len() / 3].to_vec(),
                    8 => vec![0, 0, 0, 1, 0x41, 0xff, 0x13, 0x37],
                    _ => au.clone(),
                };
                dec.decode(&au, h).is_ok()
            })
            .collect();
        // seq:            2      3      4      5     6     7(cut)  8      9      10    11
        assert_eq!(&results[..4], &[false, false, false, true]);
        assert!(results[4], "seq 6 follows its keyframe");
        assert!(!results[6], "garbage does not decode");
        assert_eq!(
            &results[7..],
            &[false, true, true],
            "resumes at the keyframe of seq 10"
        );
        assert!(dec.decode(b"", &units[0].0).is_err());
    }

    #[test]
    fn a_missing_unit_breaks_the_chain_until_the_next_keyframe() {
        let mut enc = FrameEncoder::new(&settings()).unwrap();
        let mut dec = VideoDecoder::new();
        let mut ok = Vec::new();
        for seq in 0..12 {
            let (h, px) = frame(seq, PixelFormat::Bgr8, 0);
            let au = enc.encode(&h, &px).unwrap().data;
            if seq != 2 {
                ok.push((seq, dec.decode(&au, &h).is_ok()));
            }
        }
        // OpenH264 sees the gap in frame_num: 3 and 4 are refused, 5 (a keyframe) resumes.
        let refused: Vec<u64> = ok.iter().filter(|(_, d)| !d).map(|(s, _)| *s).collect();
        assert_eq!(refused, vec![3, 4]);
    }
}
