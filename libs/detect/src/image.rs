//! Borrowed-image wrapping (no copy) and the grey pyramid.

use opencv::core::{Mat, Rect, Size};
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
    /// The half-size colour frame of a [`FirstStep::Box`] build.
    half_bgr: Mat,
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

/// How the first pyramid level is made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum FirstStep {
    /// Grey at full size, then the Gaussian `pyrDown` (the thesis's pyramid).
    Gaussian,
    /// The mean of each 2×2 block of the (colour) frame, then grey: one read of the frame and a
    /// quarter of the conversions (`detect.default.box_first_level`).
    Box,
}

impl Pyramid {
    /// Wrap `image` without copying, convert to grey and halve it `levels` times, the first
    /// time as `first` says, then with `pyrDown`. Returns the working (smallest) level.
    pub fn build(&mut self, image: &ImageView<'_>, levels: usize, first: FirstStep) -> Result<&Mat, DetectError> {
        let bpp = check_view(image)?;
        let (w, h) = (image.width as i32, image.height as i32);
        let need = image.stride * image.height as usize;
        // Borrowed header over the caller's memory: rows of `stride` bytes, then the valid
        // columns, then the channel layout. None of these steps copies pixels.
        let flat = Mat::new_rows_cols_with_data::<u8>(h, image.stride as i32, &image.data[..need])?;
        let roi = flat.roi(Rect::new(0, 0, w * bpp as i32, h))?;
        if self.levels.is_empty() {
            self.levels.push(Mat::default());
        }
        if first == FirstStep::Box && levels >= 1 && w >= 2 && h >= 2 {
            // An even-sized view, so that the halving is exactly 2×2 blocks (an odd last row
            // or column is dropped); bilinear resizing to exactly half size averages each 2×2
            // block, and the "exact" variant rounds the same on every CPU.
            let (ew, eh) = (w / 2 * 2, h / 2 * 2);
            let half = Size::new(w / 2, h / 2);
            let even = roi.roi(Rect::new(0, 0, ew * bpp as i32, eh))?;
            match image.format {
                PixelFormat::Bgr8 => {
                    let bgr = even.reshape(3, eh)?;
                    imgproc::resize(&bgr, &mut self.half_bgr, half, 0.0, 0.0, imgproc::INTER_LINEAR_EXACT)?;
                    imgproc::cvt_color_def(&self.half_bgr, &mut self.levels[0], imgproc::COLOR_BGR2GRAY)?;
                }
                PixelFormat::Gray8 => {
                    imgproc::resize(&even, &mut self.levels[0], half, 0.0, 0.0, imgproc::INTER_LINEAR_EXACT)?;
                }
            }
            // The full-size grey of an earlier build is stale now.
            self.gray = Mat::default();
            return self.finish(1, levels);
        }
        match image.format {
            PixelFormat::Bgr8 => {
                let bgr = roi.reshape(3, h)?;
                imgproc::cvt_color_def(&bgr, &mut self.gray, imgproc::COLOR_BGR2GRAY)?;
            }
            PixelFormat::Gray8 => {
                // Grey input: pyrDown reads the borrowed header directly.
                imgproc::pyr_down_def(&roi, &mut self.levels[0])?;
                return self.finish(1, levels);
            }
        }
        imgproc::pyr_down_def(&self.gray, &mut self.levels[0])?;
        self.finish(1, levels)
    }

    /// Make sure [`Pyramid::full_grey`] has the full-size grey of `image` (the frame of the
    /// last build): a [`FirstStep::Box`] build of a colour frame skips that conversion.
    pub fn convert_full_grey(&mut self, image: &ImageView<'_>) -> Result<(), DetectError> {
        let ok = self.gray.cols() as u32 == image.width && self.gray.rows() as u32 == image.height;
        if image.format == PixelFormat::Gray8 || ok {
            return Ok(());
        }
        let bpp = check_view(image)?;
        let (w, h) = (image.width as i32, image.height as i32);
        let need = image.stride * image.height as usize;
        let flat = Mat::new_rows_cols_with_data::<u8>(h, image.stride as i32, &image.data[..need])?;
        let roi = flat.roi(Rect::new(0, 0, w * bpp as i32, h))?;
        let bgr = roi.reshape(3, h)?;
        imgproc::cvt_color_def(&bgr, &mut self.gray, imgproc::COLOR_BGR2GRAY)?;
        Ok(())
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

    /// A `w`×`h` image of `pixel(x, y)` (its bytes) in a buffer of `stride` bytes a row, the
    /// padding 255.
    fn padded(w: usize, h: usize, stride: usize, pixel: impl Fn(usize, usize) -> Vec<u8>) -> Vec<u8> {
        let mut data = vec![255u8; stride * h];
        for y in 0..h {
            for x in 0..w {
                let px = pixel(x, y);
                data[y * stride + px.len() * x..][..px.len()].copy_from_slice(&px);
            }
        }
        data
    }

    #[test]
    fn stride_padding_is_honoured_without_copy() {
        // 8x4 grey image in a buffer with stride 12: left half 0, right half 200; padding 255.
        let (w, h, stride) = (8usize, 4usize, 12usize);
        let data = padded(w, h, stride, |x, _| vec![if x < w / 2 { 0 } else { 200 }]);
        let view = ImageView { width: w as u32, height: h as u32, stride, format: PixelFormat::Gray8, data: &data };
        let mut p = Pyramid::default();
        for first in [FirstStep::Gaussian, FirstStep::Box] {
            let m = p.build(&view, 1, first).unwrap();
            assert_eq!((m.cols(), m.rows()), (4, 2));
            let v = mat_to_vec(m).unwrap();
            // If the padding leaked in, the rightmost column would be brighter than 200.
            assert!(v[3] <= 200 && v[0] < 100, "{first:?}: {v:?}");
        }
    }

    #[test]
    fn box_first_level_is_the_grey_of_2x2_means() {
        // 5x3 BGR (odd sizes: the last column and row are dropped), stride padded to 16 bytes.
        // Pixel (x, y) has B = 10x, G = 20y, R = 40: each 2x2 block's mean is that of its corners.
        let (w, h, stride) = (5usize, 3usize, 16usize);
        let data = padded(w, h, stride, |x, y| vec![(10 * x) as u8, (20 * y) as u8, 40]);
        let view = ImageView { width: w as u32, height: h as u32, stride, format: PixelFormat::Bgr8, data: &data };
        let mut p = Pyramid::default();
        let m = p.build(&view, 1, FirstStep::Box).unwrap();
        assert_eq!((m.cols(), m.rows()), (2, 1));
        let got = mat_to_vec(m).unwrap();
        // OpenCV's grey: 0.114 B + 0.587 G + 0.299 R of the block means (B 5 or 25, G 10, R 40).
        let grey = |b: f64, g: f64, r: f64| 0.114 * b + 0.587 * g + 0.299 * r;
        for (x, b) in [(0usize, 5.0), (1, 25.0)] {
            let want = grey(b, 10.0, 40.0);
            assert!((got[x] as f64 - want).abs() <= 1.0, "{got:?} vs {want}");
        }
        // The same frame in grey takes the same first level (to rounding).
        let grey_data: Vec<u8> = (0..h).flat_map(|y| (0..w).map(move |x| grey(10.0 * x as f64, 20.0 * y as f64, 40.0).round() as u8)).collect();
        let gview = ImageView { width: w as u32, height: h as u32, stride: w, format: PixelFormat::Gray8, data: &grey_data };
        let g = mat_to_vec(p.build(&gview, 1, FirstStep::Box).unwrap()).unwrap();
        assert!(g.iter().zip(&got).all(|(a, b)| a.abs_diff(*b) <= 1), "{g:?} vs {got:?}");
        // The full-size grey is made on request.
        assert!(p.full_grey(&view).is_none());
        let _ = p.build(&view, 1, FirstStep::Box).unwrap();
        p.convert_full_grey(&view).unwrap();
        let full = p.full_grey(&view).unwrap();
        assert_eq!((full.width, full.height), (w, h));
        assert!((full.data[3] as f64 - grey(30.0, 0.0, 40.0)).abs() <= 1.0);
    }

    #[test]
    fn bad_buffers_are_errors() {
        let data = vec![0u8; 100];
        let mut p = Pyramid::default();
        let short = ImageView { width: 10, height: 10, stride: 30, format: PixelFormat::Bgr8, data: &data };
        assert!(matches!(p.build(&short, 1, FirstStep::Box), Err(DetectError::BadImage(_))));
        let narrow = ImageView { width: 10, height: 2, stride: 20, format: PixelFormat::Bgr8, data: &data };
        assert!(matches!(p.build(&narrow, 1, FirstStep::Box), Err(DetectError::BadImage(_))));
        let empty = ImageView { width: 0, height: 2, stride: 20, format: PixelFormat::Gray8, data: &data };
        assert!(matches!(p.build(&empty, 1, FirstStep::Box), Err(DetectError::BadImage(_))));
    }
}
