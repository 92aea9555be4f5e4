//! Shrinking a frame for the link: a box average over whole `k × k` blocks, straight from the
//! shared-memory sample into a small packed buffer (1920 → 640 wide reads the frame once).

use hubtrack_types::FrameHeader;

/// The whole factor that brings `width` to at most `max_width`.
pub fn factor(width: u32, max_width: u32) -> u32 {
    width.div_ceil(max_width.max(1)).max(1)
}

/// Shrinks `pixels` (laid out as `header` says) by `factor(width, max_width)` into `out` and
/// returns the header of the result (packed rows). `None` when the pixels do not fit the header
/// or the frame is smaller than one block.
pub fn downscale(
    header: &FrameHeader,
    pixels: &[u8],
    max_width: u32,
    sums: &mut Vec<u32>,
    out: &mut Vec<u8>,
) -> Option<FrameHeader> {
    let bpp = header.format.bytes_per_pixel();
    let (w, h, stride) = (
        header.width as usize,
        header.height as usize,
        header.stride as usize,
    );
    if stride < w * bpp || pixels.len() < header.payload_len() || w == 0 || h == 0 {
        return None;
    }
    let k = factor(header.width, max_width) as usize;
    let (ow, oh) = (w / k, h / k);
    if ow == 0 || oh == 0 {
        return None;
    }
    let orow = ow * bpp;
    out.clear();
    out.resize(orow * oh, 0);
    if k == 1 {
        for (dst, src) in out.chunks_exact_mut(orow).zip(pixels.chunks(stride)) {
            dst.copy_from_slice(&src[..orow]);
        }
    } else {
        let area = (k * k) as u32;
        sums.clear();
        sums.resize(orow, 0);
        for (oy, dst) in out.chunks_exact_mut(orow).enumerate() {
            sums.fill(0);
            for y in oy * k..oy * k + k {
                let row = &pixels[y * stride..y * stride + ow * k * bpp];
                for (ox, block) in row.chunks_exact(k * bpp).enumerate() {
                    let acc = &mut sums[ox * bpp..ox * bpp + bpp];
                    for px in block.chunks_exact(bpp) {
                        for (a, &v) in acc.iter_mut().zip(px) {
                            *a += u32::from(v);
                        }
                    }
                }
            }
            for (d, s) in dst.iter_mut().zip(sums.iter()) {
                *d = ((s + area / 2) / area) as u8;
            }
        }
    }
    Some(FrameHeader {
        width: ow as u32,
        height: oh as u32,
        stride: orow as u32,
        camera_jpeg_len: 0, // the camera's JPEG is of the full frame
        ..*header
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use hubtrack_types::PixelFormat;

    fn frame(w: u32, h: u32, stride: u32, format: PixelFormat) -> (FrameHeader, Vec<u8>) {
        let header = FrameHeader {
            width: w,
            height: h,
            stride,
            format,
            ..Default::default()
        };
        let bpp = format.bytes_per_pixel();
        let mut px = vec![0u8; (stride * h) as usize];
        for y in 0..h as usize {
            for x in 0..w as usize * bpp {
                px[y * stride as usize + x] = ((x / bpp) % 7 * 30 + y % 3) as u8;
            }
        }
        (header, px)
    }

    #[test]
    fn full_hd_becomes_640_wide_with_block_means() {
        let (h, px) = frame(1920, 1080, 1920 * 3 + 64, PixelFormat::Bgr8);
        let (mut sums, mut out) = (Vec::new(), Vec::new());
        let small = downscale(&h, &px, 640, &mut sums, &mut out).unwrap();
        assert_eq!((small.width, small.height, small.stride), (640, 360, 1920));
        assert_eq!(out.len(), 1920 * 360);
        // Block (0, 0): columns 0..3 (values 0, 30, 60) over rows 0..3 (+0, +1, +2): mean 31.
        assert_eq!(&out[..3], &[31, 31, 31]);
    }

    #[test]
    fn small_frames_are_copied_and_bad_ones_refused() {
        let (h, px) = frame(320, 240, 400, PixelFormat::Gray8);
        let (mut sums, mut out) = (Vec::new(), Vec::new());
        let same = downscale(&h, &px, 640, &mut sums, &mut out).unwrap();
        assert_eq!((same.width, same.height, same.stride), (320, 240, 320));
        assert_eq!(&out[..320], &px[..320]);
        assert!(downscale(&h, &px[..1000], 640, &mut sums, &mut out).is_none());
        let (tiny, tpx) = frame(3, 1, 3, PixelFormat::Gray8);
        assert!(downscale(&tiny, &tpx, 1, &mut sums, &mut out).is_none());
        assert_eq!(factor(1000, 640), 2);
        assert_eq!(factor(640, 640), 1);
    }
}
