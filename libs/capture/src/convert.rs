//! Pixel conversions and OpenCV `Mat` copies used by the sources.

use crate::{check_len, CaptureError};
use opencv::core::{Mat, MatTraitConst, MatTraitConstManual};
use opencv::imgproc;

/// ITU-R BT.601 limited-range YUV to RGB, in 16.16 fixed point.
const Y_OFFSET: i32 = 16;
const UV_OFFSET: i32 = 128;
const Y_GAIN: i32 = 76_309; // 1.164 * 65536
const V_TO_R: i32 = 104_597; // 1.596
const U_TO_G: i32 = 25_675; // 0.392
const V_TO_G: i32 = 53_279; // 0.813
const U_TO_B: i32 = 132_201; // 2.017

#[inline]
fn clamp_u8(v: i32) -> u8 {
    (v >> 16).clamp(0, 255) as u8
}

/// Converts a packed YUYV 4:2:2 image (`stride` bytes per row) to tightly packed BGR8.
pub fn yuyv_to_bgr(
    src: &[u8],
    width: usize,
    height: usize,
    stride: usize,
    dst: &mut [u8],
) -> Result<(), CaptureError> {
    check_len(dst, width * height * 3)?;
    if !width.is_multiple_of(2)
        || stride < width * 2
        || src.len() < stride * (height.max(1) - 1) + width * 2
    {
        return Err(CaptureError::BadFrame {
            seq: 0,
            reason: format!(
                "YUYV buffer of {} bytes does not hold {width}x{height} (stride {stride})",
                src.len()
            ),
        });
    }
    for row in 0..height {
        let s = &src[row * stride..row * stride + width * 2];
        let d = &mut dst[row * width * 3..(row + 1) * width * 3];
        for (quad, out) in s.chunks_exact(4).zip(d.chunks_exact_mut(6)) {
            let (y0, u, y1, v) = (
                quad[0] as i32,
                quad[1] as i32 - UV_OFFSET,
                quad[2] as i32,
                quad[3] as i32 - UV_OFFSET,
            );
            let r = V_TO_R * v;
            let g = -U_TO_G * u - V_TO_G * v;
            let b = U_TO_B * u;
            for (k, y) in [y0, y1].into_iter().enumerate() {
                let yy = Y_GAIN * (y - Y_OFFSET);
                out[k * 3] = clamp_u8(yy + b);
                out[k * 3 + 1] = clamp_u8(yy + g);
                out[k * 3 + 2] = clamp_u8(yy + r);
            }
        }
    }
    Ok(())
}

/// Copies an 8-bit OpenCV image (gray, BGR or BGRA) into tightly packed BGR8.
pub fn mat_to_bgr(mat: &Mat, dst: &mut [u8]) -> Result<(), CaptureError> {
    let (w, h) = (mat.cols() as usize, mat.rows() as usize);
    check_len(dst, w * h * 3)?;
    let converted;
    let bgr = match mat.channels() {
        3 => mat,
        1 => {
            let mut m = Mat::default();
            imgproc::cvt_color_def(mat, &mut m, imgproc::COLOR_GRAY2BGR)?;
            converted = m;
            &converted
        }
        4 => {
            let mut m = Mat::default();
            imgproc::cvt_color_def(mat, &mut m, imgproc::COLOR_BGRA2BGR)?;
            converted = m;
            &converted
        }
        n => {
            return Err(CaptureError::BadFrame {
                seq: 0,
                reason: format!("{n}-channel image"),
            })
        }
    };
    if bgr.is_continuous() {
        dst.copy_from_slice(bgr.data_bytes()?);
    } else {
        for row in 0..h {
            let r = bgr.row(row as i32)?;
            dst[row * w * 3..(row + 1) * w * 3].copy_from_slice(&r.data_bytes()?[..w * 3]);
        }
    }
    Ok(())
}

/// Writes tightly packed BGR8 pixels to an image file (format from the extension: .png, .jpg, ...).
pub fn write_bgr_image(
    path: &std::path::Path,
    width: u32,
    height: u32,
    bgr: &[u8],
) -> Result<(), CaptureError> {
    use opencv::prelude::*;
    check_len(bgr, width as usize * height as usize * 3)?;
    let flat = Mat::new_rows_cols_with_data(height as i32, (width * 3) as i32, bgr)?;
    let mat = flat.reshape(3, height as i32)?;
    let refused = |reason: &str| CaptureError::ImageWrite {
        path: path.to_path_buf(),
        reason: reason.into(),
    };
    let name = path
        .to_str()
        .ok_or_else(|| refused("the path is not UTF-8"))?;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        if !dir.is_dir() {
            return Err(refused(&format!("no folder {}", dir.display())));
        }
    }
    if !opencv::imgcodecs::imwrite_def(name, &mat)? {
        return Err(refused(
            "the image writer refused it (an extension it cannot write, or no permission)",
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn yuyv_grey_and_primaries() {
        // Two pixels per quad: black (Y=16), white (Y=235), neutral chroma.
        let src = [16u8, 128, 235, 128];
        let mut dst = [0u8; 6];
        yuyv_to_bgr(&src, 2, 1, 4, &mut dst).unwrap();
        assert_eq!(&dst[..3], &[0, 0, 0]);
        assert!(dst[3..].iter().all(|&c| c >= 254), "{dst:?}");
        // Pure red in BT.601: Y=81, U=90, V=240.
        let src = [81u8, 90, 81, 240];
        yuyv_to_bgr(&src, 2, 1, 4, &mut dst).unwrap();
        let (b, g, r) = (dst[0], dst[1], dst[2]);
        assert!(r >= 250 && g <= 5 && b <= 5, "bgr = {b} {g} {r}");
    }

    #[test]
    fn yuyv_honours_stride_padding() {
        // 2x2 image, stride 8 (4 bytes padding per row), second row white.
        let src = [
            16u8, 128, 16, 128, 9, 9, 9, 9, 235, 128, 235, 128, 9, 9, 9, 9,
        ];
        let mut dst = [0u8; 12];
        yuyv_to_bgr(&src, 2, 2, 8, &mut dst).unwrap();
        assert!(dst[..6].iter().all(|&c| c == 0));
        assert!(dst[6..].iter().all(|&c| c >= 254));
    }

    #[test]
    fn yuyv_rejects_short_buffers() {
        let mut dst = [0u8; 12];
        assert!(yuyv_to_bgr(&[0u8; 6], 2, 2, 4, &mut dst).is_err());
        let mut small = [0u8; 5];
        assert!(matches!(
            yuyv_to_bgr(&[0u8; 8], 2, 2, 4, &mut small),
            Err(CaptureError::BufferSize { .. })
        ));
    }
}
