//! Borrowed-image wrapping (no copy) and the grey pyramid.

use opencv::core::{Mat, Rect};
use opencv::imgproc;
use opencv::prelude::*;

use crate::{DetectError, ImageView};
use hubtrack_types::PixelFormat;

/// Check that the view describes its buffer consistently; returns bytes per pixel.
pub(crate) fn check_view(image: &ImageView<'_>) -> Result<usize, DetectError> {
    let bpp = image.format.bytes_per_pixel();
    let (w, h) = (image.width as usize, image.height as usize);
    if w == 0 || h == 0 || w > i32::MAX as usize / 4 || h > i32::MAX as usize / 4 {
        return Err(DetectError::BadImage(format!("image size {w}x{h} is empty or too large")));
    }
    if image.stride < w * bpp {
        return Err(DetectError::BadImage(format!(
            "stride {} < width {w} * {bpp} bytes per pixel",
            image.stride
        )));
    }
    let need = image.stride.checked_mul(h).ok_or_else(|| DetectError::BadImage("stride * height overflows".into()))?;
    if image.data.len() < need {
        return Err(DetectError::BadImage(format!(
            "buffer has {} bytes, stride {} * height {h} needs {need}",
            image.data.len(),
            image.stride
        )));
    }
    if image.stride > i32::MAX as usize {
        return Err(DetectError::BadImage(format!("stride {} too large", image.stride)));
    }
    Ok(bpp)
}

/// Reusable buffers: full-resolution grey and the pyramid levels. OpenCV's `create` reuses a
/// Mat's allocation when size and type match, so steady-state frames allocate nothing here.
#[derive(Default)]
pub(crate) struct Pyramid {
    gray: Mat,
    levels: Vec<Mat>,
    /// Number of pyrDown steps of the last build.
    pub count: usize,
}

/// How many pyrDown steps bring `w`×`h` into `[min_side, max_side]` (at least one step; stop
/// early rather than going below `min_side`).
pub fn pyramid_levels(mut w: u32, mut h: u32, min_side: u32, max_side: u32) -> usize {
    let mut n = 0;
    loop {
        if n >= 1 && w <= max_side && h <= max_side {
            break;
        }
        let (nw, nh) = (w.div_ceil(2), h.div_ceil(2));
        if n >= 1 && (nw < min_side || nh < min_side) {
            break;
        }
        w = nw;
        h = nh;
        n += 1;
        if w < 2 || h < 2 {
            break;
        }
    }
    n
}

impl Pyramid {
    /// Wrap `image` without copying, convert to grey and pyrDown `levels` times. Returns the
    /// working (smallest) level.
    pub fn build(&mut self, image: &ImageView<'_>, levels: usize) -> Result<&Mat, DetectError> {
        let bpp = check_view(image)?;
        let (w, h) = (image.width as i32, image.height as i32);
        let need = image.stride * image.height as usize;
        // Borrowed header over the caller's memory: rows of `stride` bytes, then the valid
        // columns, then the channel layout. None of these steps copies pixels.
        let flat = Mat::new_rows_cols_with_data::<u8>(h, image.stride as i32, &image.data[..need])?;
        let roi = flat.roi(Rect::new(0, 0, w * bpp as i32, h))?;
        match image.format {
            PixelFormat::Bgr8 => {
                let bgr = roi.reshape(3, h)?;
                imgproc::cvt_color_def(&bgr, &mut self.gray, imgproc::COLOR_BGR2GRAY)?;
            }
            PixelFormat::Gray8 => {
                // Grey input: pyrDown reads the borrowed header directly.
                if self.levels.is_empty() {
                    self.levels.push(Mat::default());
                }
                imgproc::pyr_down_def(&roi, &mut self.levels[0])?;
                return self.finish(1, levels);
            }
        }
        if self.levels.is_empty() {
            self.levels.push(Mat::default());
        }
        imgproc::pyr_down_def(&self.gray, &mut self.levels[0])?;
        self.finish(1, levels)
    }

    /// The full-resolution grey image of the last [`Pyramid::build`] of `image` (the converted
    /// copy for colour input, the caller's own pixels for grey); `None` if it is not at hand.
    pub fn full_grey<'a>(&'a self, image: &ImageView<'a>) -> Option<crate::spinner::GreyPlane<'a>> {
        let (width, height) = (image.width as usize, image.height as usize);
        match image.format {
            PixelFormat::Gray8 => Some(crate::spinner::GreyPlane { data: image.data, width, height, stride: image.stride }),
            PixelFormat::Bgr8 => {
                let ok = self.gray.cols() as usize == width && self.gray.rows() as usize == height && self.gray.is_continuous();
                let data = self.gray.data_bytes().ok().filter(|_| ok)?;
                Some(crate::spinner::GreyPlane { data, width, height, stride: width })
            }
        }
    }

    fn finish(&mut self, done: usize, levels: usize) -> Result<&Mat, DetectError> {
        while self.levels.len() < levels {
            self.levels.push(Mat::default());
        }
        for i in done..levels {
            let (src, dst) = self.levels.split_at_mut(i);
            imgproc::pyr_down_def(&src[i - 1], &mut dst[0])?;
        }
        self.count = levels;
        Ok(&self.levels[levels - 1])
    }
}

/// Copy a grey Mat's pixels into a row-major `Vec` (tests and debugging only).
#[allow(dead_code)]
pub(crate) fn mat_to_vec(m: &Mat) -> Result<Vec<u8>, DetectError> {
    let mut out = Vec::with_capacity((m.rows() * m.cols()) as usize);
    for r in 0..m.rows() {
        let row = m.at_row::<u8>(r)?;
        out.extend_from_slice(row);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_for_common_sizes() {
        assert_eq!(pyramid_levels(1920, 1080, 200, 500), 2); // 480x270
        assert_eq!(pyramid_levels(640, 480, 200, 500), 1); // 320x240
        assert_eq!(pyramid_levels(400, 300, 200, 500), 1); // at least once, even if already small
        assert_eq!(pyramid_levels(3840, 2160, 200, 500), 3); // 480x270
    }

    #[test]
    fn stride_padding_is_honoured_without_copy() {
        // 8x4 grey image in a buffer with stride 12: left half 0, right half 200; padding 255.
        let (w, h, stride) = (8usize, 4usize, 12usize);
        let mut data = vec![255u8; stride * h];
        for r in 0..h {
            for c in 0..w {
                data[r * stride + c] = if c < w / 2 { 0 } else { 200 };
            }
        }
        let view = ImageView { width: w as u32, height: h as u32, stride, format: PixelFormat::Gray8, data: &data };
        let mut p = Pyramid::default();
        let m = p.build(&view, 1).unwrap();
        assert_eq!((m.cols(), m.rows()), (4, 2));
        let v = mat_to_vec(m).unwrap();
        // If the padding leaked in, the rightmost column would be brighter than 200.
        assert!(v[3] <= 200 && v[0] < 100, "{v:?}");
    }

    #[test]
    fn bad_buffers_are_errors() {
        let data = vec![0u8; 100];
        let mut p = Pyramid::default();
        let short = ImageView { width: 10, height: 10, stride: 30, format: PixelFormat::Bgr8, data: &data };
        assert!(matches!(p.build(&short, 1), Err(DetectError::BadImage(_))));
        let narrow = ImageView { width: 10, height: 2, stride: 20, format: PixelFormat::Bgr8, data: &data };
        assert!(matches!(p.build(&narrow, 1), Err(DetectError::BadImage(_))));
        let empty = ImageView { width: 0, height: 2, stride: 20, format: PixelFormat::Gray8, data: &data };
        assert!(matches!(p.build(&empty, 1), Err(DetectError::BadImage(_))));
    }
}
