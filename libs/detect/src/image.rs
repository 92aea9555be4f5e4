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
        return Err(DetectError::BadImage(format!(
            "image size {w}x{h} is empty or too large"
        )));
    }
    if image.stride < w * bpp {
        return Err(DetectError::BadImage(format!(
            "stride {} < width {w} * {bpp} bytes per pixel",
            image.stride
        )));
    }
    let need = image
        .stride
        .checked_mul(h)
        .ok_or_else(|| DetectError::BadImage("stride * height overflows".into()))?;
    if image.data.len() < need {
        return Err(DetectError::BadImage(format!(
            "buffer has {} bytes, stride {} * height {h} needs {need}",
            image.data.len(),
            image.stride
        )));
    }
    if image.stride > i32::MAX as usize {
        return Err(DetectError::BadImage(format!(
            "stride {} too large",
            image.stride
        )));
    }
    Ok(bpp)
}

/// The mirror image (left and right swapped) of `image`, a view checked by [`check_view`],
/// written into `buf` (rows packed).
pub(crate) fn mirror_into<'b>(image: &ImageView<'_>, buf: &'b mut Vec<u8>) -> ImageView<'b> {
    let bpp = image.format.bytes_per_pixel();
    let (w, h) = (image.width as usize, image.height as usize);
    let row = w * bpp;
    buf.clear();
    buf.resize(row * h, 0);
    for (y, dst) in buf.chunks_exact_mut(row).enumerate() {
        let src = &image.data[y * image.stride..y * image.stride + row];
        for (d, s) in dst.chunks_exact_mut(bpp).zip(src.chunks_exact(bpp).rev()) {
            d.copy_from_slice(s);
        }
    }
    ImageView {
        width: image.width,
        height: image.height,
        stride: row,
        format: image.format,
        data: buf,
    }
}

/// Reusable buffers: full-resolution grey (Gaussian first step) and the pyramid levels. OpenCV's `create` reuses a
/// Mat's allocation when size and type match, so steady-state frames allocate nothing here.
#[derive(Default)]
pub(crate) struct Pyramid {
    /// The full-size grey of a [`FirstStep::Gaussian`] build of a colour frame.
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
    pub fn build(
        &mut self,
        image: &ImageView<'_>,
        levels: usize,
        first: FirstStep,
    ) -> Result<&Mat, DetectError> {
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
            // block, and the "exact" variant rounds the same on every CPU (the area resize's
            // integer fast path gives the same pixels, and was no faster on cold frames).
            let (ew, eh) = (w / 2 * 2, h / 2 * 2);
            let half = Size::new(w / 2, h / 2);
            let even = roi.roi(Rect::new(0, 0, ew * bpp as i32, eh))?;
            match image.format {
                PixelFormat::Bgr8 => {
                    let need = image.stride * (eh as usize - 1) + 3 * ew as usize;
                    half_grey_bgr(
                        &image.data[..need],
                        image.stride,
                        ew as usize,
                        eh as usize,
                        &mut self.levels[0],
                    )?;
                }
                PixelFormat::Gray8 => {
                    imgproc::resize(
                        &even,
                        &mut self.levels[0],
                        half,
                        0.0,
                        0.0,
                        imgproc::INTER_LINEAR_EXACT,
                    )?;
                }
            }
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

/// The grey of the 2×2 block means of the `w`×`h` (even) BGR frame in `src` (rows of `stride`
/// bytes) into `dst` (`w/2`×`h/2`): bit for bit OpenCV's `resize(INTER_LINEAR_EXACT)` to half
/// size (each channel's rounded 2×2 mean) followed by `cvtColor(BGR2GRAY)`, in one pass over the
/// frame without the half-size colour image in between.
fn half_grey_bgr(
    src: &[u8],
    stride: usize,
    w: usize,
    h: usize,
    dst: &mut Mat,
) -> Result<(), DetectError> {
    // SAFETY: every pixel is written below; `create` reuses the allocation when size and type match.
    unsafe { dst.create_rows_cols((h / 2) as i32, (w / 2) as i32, opencv::core::CV_8UC1)? };
    let (ow, oh) = (w / 2, h / 2);
    let out = dst.data_bytes_mut()?;
    let rows = |first: usize, out: &mut [u8]| {
        for (k, o) in out.chunks_exact_mut(ow).enumerate() {
            let y = first + k;
            let (top, bottom) = (
                &src[2 * y * stride..][..3 * w],
                &src[(2 * y + 1) * stride..][..3 * w],
            );
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU has AVX2 (checked just above).
                unsafe { half_grey_row_avx2(top, bottom, o) };
                continue;
            }
            half_grey_row(top, bottom, o);
        }
    };
    // With OpenCV allowed more than one thread (as its own resize would use), the lower half
    // of the frame goes to a second thread: the pass is bound by memory reads, which two cores
    // make faster (a thread costs some 30 µs; the pass ~0.8 ms on one core).
    if opencv::core::get_num_threads()? > 1 && oh >= 64 {
        let (upper, lower) = out.split_at_mut(oh / 2 * ow);
        std::thread::scope(|scope| {
            scope.spawn(|| rows(oh / 2, lower));
            rows(0, upper);
        });
    } else {
        rows(0, out);
    }
    Ok(())
}

/// [`half_grey_row`] in AVX2 instructions, 16 output pixels from 32 input pixels of each row at
/// a time (each 128-bit lane does 8 of them): the channels are separated with byte shuffles,
/// each horizontal pair summed with `vpmaddubsw`, and the grey weighted with `vpmaddwd`, in the
/// same integer arithmetic as the scalar row (so the same pixels).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn half_grey_row_avx2(top: &[u8], bottom: &[u8], out: &mut [u8]) {
    use std::arch::x86_64::*;
    // Shuffle masks taking channel `c` of 16 BGR pixels (48 bytes, in three 16-byte vectors)
    // into one vector: mask k of channel c picks, from vector k, the bytes of the pixels whose
    // channel-c byte lies there, at the pixel's lane (-1 zeroes the lane).
    const fn mask(c: usize, k: usize) -> [i8; 16] {
        let mut m = [-1i8; 16];
        let mut p = 0;
        while p < 16 {
            let byte = 3 * p + c;
            if byte / 16 == k {
                m[p] = (byte % 16) as i8;
            }
            p += 1;
        }
        m
    }
    const MASKS: [[[i8; 16]; 3]; 3] = [
        [mask(0, 0), mask(0, 1), mask(0, 2)],
        [mask(1, 0), mask(1, 1), mask(1, 2)],
        [mask(2, 0), mask(2, 1), mask(2, 2)],
    ];
    let m: [[__m256i; 3]; 3] =
        MASKS.map(|ch| ch.map(|k| _mm256_broadcastsi128_si256(_mm_loadu_si128(k.as_ptr().cast()))));
    let ones8 = _mm256_set1_epi8(1);
    let two = _mm256_set1_epi16(2);
    // (B, G) pairs weighted 3735, 19235; (R, 1) pairs weighted 9798, 2^14 (the rounding).
    let w_bg = _mm256_set1_epi32((19235 << 16) | 3735);
    let w_r1 = _mm256_set1_epi32((1 << 14 << 16) | 9798);
    let one16 = _mm256_set1_epi16(1);
    let blocks = out.len().min(top.len() / 6).min(bottom.len() / 6) / 16;
    for i in 0..blocks {
        // 2×2 sums of each channel, u16: lane 0 the first 8 output pixels, lane 1 the next 8.
        let sums = |row: &[u8]| -> [__m256i; 3] {
            let p = row[96 * i..][..96].as_ptr();
            let load =
                |k: usize| _mm256_loadu2_m128i(p.add(48 + 16 * k).cast(), p.add(16 * k).cast());
            let v = [load(0), load(1), load(2)];
            [0, 1, 2].map(|c| {
                let shuffled = |k: usize| _mm256_shuffle_epi8(v[k], m[c][k]);
                _mm256_maddubs_epi16(
                    _mm256_or_si256(_mm256_or_si256(shuffled(0), shuffled(1)), shuffled(2)),
                    ones8,
                )
            })
        };
        let (a, b) = (sums(top), sums(bottom));
        let mean =
            |c: usize| _mm256_srli_epi16::<2>(_mm256_add_epi16(_mm256_add_epi16(a[c], b[c]), two));
        let (bl, gr, rd) = (mean(0), mean(1), mean(2));
        let grey = |bg: __m256i, r1: __m256i| {
            _mm256_srli_epi32::<15>(_mm256_add_epi32(
                _mm256_madd_epi16(bg, w_bg),
                _mm256_madd_epi16(r1, w_r1),
            ))
        };
        let lo = grey(
            _mm256_unpacklo_epi16(bl, gr),
            _mm256_unpacklo_epi16(rd, one16),
        );
        let hi = grey(
            _mm256_unpackhi_epi16(bl, gr),
            _mm256_unpackhi_epi16(rd, one16),
        );
        // Per lane: 8 pixels in order in the low 8 bytes; gather both lanes' into 16 bytes.
        let px = _mm256_packus_epi16(_mm256_packs_epi32(lo, hi), _mm256_setzero_si256());
        let px = _mm256_permute4x64_epi64::<0b1000>(px);
        _mm_storeu_si128(
            out[16 * i..][..16].as_mut_ptr().cast(),
            _mm256_castsi256_si128(px),
        );
    }
    let done = 16 * blocks;
    half_grey_row(&top[6 * done..], &bottom[6 * done..], &mut out[done..]);
}

/// One output row of [`half_grey_bgr`] from two BGR rows.
#[inline(always)]
fn half_grey_row(top: &[u8], bottom: &[u8], out: &mut [u8]) {
    for ((o, a), b) in out
        .iter_mut()
        .zip(top.chunks_exact(6))
        .zip(bottom.chunks_exact(6))
    {
        let mean = |c: usize| {
            (u32::from(a[c]) + u32::from(a[c + 3]) + u32::from(b[c]) + u32::from(b[c + 3]) + 2) >> 2
        };
        *o = bgr_grey(mean(0) as u8, mean(1) as u8, mean(2) as u8);
    }
}

/// The grey of one BGR pixel exactly as OpenCV's `cvtColor(BGR2GRAY)` makes it for 8-bit
/// images (OpenCV 4's `RGB2Gray<uchar>`): 0.114 B + 0.587 G + 0.299 R in 15-bit fixed point,
/// rounded.
#[inline]
pub(crate) fn bgr_grey(b: u8, g: u8, r: u8) -> u8 {
    ((3735 * u32::from(b) + 19235 * u32::from(g) + 9798 * u32::from(r) + (1 << 14)) >> 15) as u8
}

/// One source pixel's share of a destination pixel in an area resize.
#[derive(Debug, Clone, Copy)]
struct AreaTap {
    /// Destination index.
    dst: usize,
    /// Source index.
    src: usize,
    /// Weight.
    alpha: f32,
}

/// The taps of an area resize of `src_len` pixels to `dst_len` (fewer), in OpenCV's order and
/// with its weights (`computeResizeAreaTab` in OpenCV 4's `resize.cpp`).
fn area_taps(src_len: usize, dst_len: usize) -> Vec<AreaTap> {
    let scale = 1.0 / (dst_len as f64 / src_len as f64);
    let mut taps = Vec::with_capacity(src_len * 2);
    for d in 0..dst_len {
        let f1 = d as f64 * scale;
        let f2 = f1 + scale;
        let cell = scale.min(src_len as f64 - f1);
        let s2 = (f2.floor() as usize).min(src_len - 1);
        let s1 = (f1.ceil() as usize).min(s2);
        if s1 as f64 - f1 > 1e-3 {
            taps.push(AreaTap {
                dst: d,
                src: s1 - 1,
                alpha: ((s1 as f64 - f1) / cell) as f32,
            });
        }
        for s in s1..s2 {
            taps.push(AreaTap {
                dst: d,
                src: s,
                alpha: (1.0 / cell) as f32,
            });
        }
        if f2 - s2 as f64 > 1e-3 {
            taps.push(AreaTap {
                dst: d,
                src: s2,
                alpha: ((f2 - s2 as f64).min(1.0).min(cell) / cell) as f32,
            });
        }
    }
    taps
}

/// Shrink a grey image to `width`×`height` by area averaging: the same pixels as OpenCV's
/// `resize(INTER_AREA)` (its general, non-integer-ratio path, in the same float arithmetic),
/// without its per-call table set-up and generic loops (0.27 ms for 480×270 → 192×128). Larger
/// targets, integer ratios and other pixel types go to OpenCV.
pub(crate) fn resize_area_grey(
    src: &Mat,
    dst: &mut Mat,
    width: i32,
    height: i32,
) -> Result<(), DetectError> {
    let (sw, sh) = (src.cols(), src.rows());
    let integer_ratio = sw % width == 0 && sh % height == 0;
    if src.typ() != opencv::core::CV_8UC1
        || width <= 0
        || height <= 0
        || width > sw
        || height > sh
        || integer_ratio
    {
        imgproc::resize(
            src,
            dst,
            Size::new(width, height),
            0.0,
            0.0,
            imgproc::INTER_AREA,
        )?;
        return Ok(());
    }
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { resize_area_grey_avx2(src, dst, width, height) };
    }
    resize_area_grey_here(src, dst, width, height)
}

/// [`resize_area_grey_here`] compiled for AVX2 (the row conversions and roundings in vectors;
/// the same float operations, nothing fused).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn resize_area_grey_avx2(
    src: &Mat,
    dst: &mut Mat,
    width: i32,
    height: i32,
) -> Result<(), DetectError> {
    resize_area_grey_here(src, dst, width, height)
}

/// [`resize_area_grey`] of a grey `src` to a smaller, non-integer-ratio size.
#[inline(always)]
fn resize_area_grey_here(
    src: &Mat,
    dst: &mut Mat,
    width: i32,
    height: i32,
) -> Result<(), DetectError> {
    let (sw, sh) = (src.cols(), src.rows());
    let (w, h) = (width as usize, height as usize);
    let xtaps = area_taps(sw as usize, w);
    let ytaps = area_taps(sh as usize, h);
    // SAFETY: every pixel is written below; `create` reuses the allocation when size and type match.
    unsafe { dst.create_rows_cols(height, width, opencv::core::CV_8UC1)? };
    // Each destination column's taps are consecutive; laid out as `depth` planes of one tap per
    // column (short columns padded with zero weights), so that the sum over a row runs across
    // columns, not down a chain of dependent additions. Per column the sum is the same as
    // OpenCV's: from 0.0, taps left to right (then + 0.0, which changes nothing).
    let mut spans = vec![(0usize, 0usize); w];
    for (k, t) in xtaps.iter().enumerate() {
        if spans[t.dst].1 == 0 {
            spans[t.dst].0 = k;
        }
        spans[t.dst].1 = k + 1;
    }
    let depth = spans.iter().map(|(a, b)| b - a).max().unwrap_or(0);
    let (mut index, mut weight) = (vec![0u32; depth * w], vec![0f32; depth * w]);
    for (d, &(a, b)) in spans.iter().enumerate() {
        for j in 0..depth {
            let t = xtaps[(a + j).min(b - 1)];
            assert!(t.src < sw as usize, "area tap outside the row");
            index[j * w + d] = t.src as u32;
            weight[j * w + d] = if a + j < b { t.alpha } else { 0.0 };
        }
    }
    let mut pixels = vec![0f32; sw as usize];
    let mut row = vec![0f32; w];
    let mut sum = vec![0f32; w];
    let mut current = ytaps[0].dst;
    let mut row_of = usize::MAX;
    for yt in &ytaps {
        // A source row on the border of two destination rows is summed once.
        if yt.src != row_of {
            for (f, &b) in pixels.iter_mut().zip(src.at_row::<u8>(yt.src as i32)?) {
                *f = f32::from(b);
            }
            row.fill(0.0);
            // SAFETY: every index is below `sw` = `pixels.len()` (asserted as they were made).
            unsafe { weigh_row(&pixels, &index, &weight, &mut row) };
            row_of = yt.src;
        }
        if yt.dst != current {
            write_row(dst.at_row_mut::<u8>(current as i32)?, &sum);
            for (a, r) in sum.iter_mut().zip(&row) {
                *a = yt.alpha * r;
            }
            current = yt.dst;
        } else {
            for (a, r) in sum.iter_mut().zip(&row) {
                *a += yt.alpha * r;
            }
        }
    }
    write_row(dst.at_row_mut::<u8>(current as i32)?, &sum);
    Ok(())
}

/// `row[d] += pixels[index[j·w + d]] · weight[j·w + d]` for the tap planes `j` in order (`w` =
/// `row.len()`).
///
/// # Safety
/// Every index must be below `pixels.len()` (the caller checks once, not per row).
unsafe fn weigh_row(pixels: &[f32], index: &[u32], weight: &[f32], row: &mut [f32]) {
    debug_assert!(
        index.iter().all(|&i| (i as usize) < pixels.len()) && index.len() == weight.len()
    );
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above); the indices are the caller's promise.
        return weigh_row_avx2(pixels, index, weight, row);
    }
    weigh_row_here(pixels, index, weight, row)
}

/// [`weigh_row_here`] with AVX2 gathers, 8 destination pixels at a time: the same float
/// operations in the same order per pixel (nothing fused), so the same sums.
///
/// # Safety
/// The CPU must have AVX2; every index must be below `pixels.len()`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn weigh_row_avx2(pixels: &[f32], index: &[u32], weight: &[f32], row: &mut [f32]) {
    use std::arch::x86_64::*;
    let w = row.len();
    let planes = index.len() / w.max(1);
    let blocks = w / 8;
    for b in 0..blocks {
        let mut r = _mm256_loadu_ps(row[8 * b..][..8].as_ptr());
        for j in 0..planes {
            let idx = _mm256_loadu_si256(index[j * w + 8 * b..][..8].as_ptr().cast());
            let wt = _mm256_loadu_ps(weight[j * w + 8 * b..][..8].as_ptr());
            r = _mm256_add_ps(
                r,
                _mm256_mul_ps(_mm256_i32gather_ps::<4>(pixels.as_ptr(), idx), wt),
            );
        }
        _mm256_storeu_ps(row[8 * b..][..8].as_mut_ptr(), r);
    }
    let done = 8 * blocks;
    for j in 0..planes {
        for d in done..w {
            row[d] += *pixels.get_unchecked(index[j * w + d] as usize) * weight[j * w + d];
        }
    }
}

/// # Safety
/// Every index must be below `pixels.len()`.
#[inline(always)]
unsafe fn weigh_row_here(pixels: &[f32], index: &[u32], weight: &[f32], row: &mut [f32]) {
    let w = row.len();
    for (idx, wt) in index.chunks_exact(w).zip(weight.chunks_exact(w)) {
        for ((r, &i), &a) in row.iter_mut().zip(idx).zip(wt) {
            *r += *pixels.get_unchecked(i as usize) * a;
        }
    }
}

/// A row of float sums as 8-bit pixels, rounded half to even and saturated (OpenCV's
/// `saturate_cast<uchar>(float)`).
#[inline(always)]
fn write_row(out: &mut [u8], sum: &[f32]) {
    // Adding and taking away 1.5·2²³ rounds a float below 2²² to an integer, half to even
    // (the FPU's default rounding), without a library call on CPUs lacking `roundss`.
    const ROUND: f32 = 12_582_912.0;
    for (o, v) in out.iter_mut().zip(sum) {
        *o = ((v.clamp(-1.0, 256.0) + ROUND) - ROUND).clamp(0.0, 255.0) as u8;
    }
}

/// Copy a grey Mat's pixels into a row-major `Vec` (tests only).
#[cfg(test)]
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
    fn padded(
        w: usize,
        h: usize,
        stride: usize,
        pixel: impl Fn(usize, usize) -> Vec<u8>,
    ) -> Vec<u8> {
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
        let view = ImageView {
            width: w as u32,
            height: h as u32,
            stride,
            format: PixelFormat::Gray8,
            data: &data,
        };
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
        let data = padded(w, h, stride, |x, y| {
            vec![(10 * x) as u8, (20 * y) as u8, 40]
        });
        let view = ImageView {
            width: w as u32,
            height: h as u32,
            stride,
            format: PixelFormat::Bgr8,
            data: &data,
        };
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
        let grey_data: Vec<u8> = (0..h)
            .flat_map(|y| {
                (0..w).map(move |x| grey(10.0 * x as f64, 20.0 * y as f64, 40.0).round() as u8)
            })
            .collect();
        let gview = ImageView {
            width: w as u32,
            height: h as u32,
            stride: w,
            format: PixelFormat::Gray8,
            data: &grey_data,
        };
        let g = mat_to_vec(p.build(&gview, 1, FirstStep::Box).unwrap()).unwrap();
        assert!(
            g.iter().zip(&got).all(|(a, b)| a.abs_diff(*b) <= 1),
            "{g:?} vs {got:?}"
        );
    }

    /// A `w`×`h` BGR image of pseudo-random colours (every rounding case of a conversion
    /// occurs), rows of `stride` bytes.
    fn random_colours(w: usize, h: usize, stride: usize) -> Vec<u8> {
        padded(w, h, stride, |x, y| {
            let k = ((y * w + x) as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
            vec![(k >> 40) as u8, (k >> 48) as u8, (k >> 56) as u8]
        })
    }

    #[test]
    fn box_halving_is_the_rounded_2x2_mean() {
        let (w, h, stride) = (64usize, 48usize, 64 * 3 + 7);
        let data = random_colours(w, h, stride);
        let flat = Mat::new_rows_cols_with_data::<u8>(h as i32, stride as i32, &data).unwrap();
        let roi = flat.roi(Rect::new(0, 0, 3 * w as i32, h as i32)).unwrap();
        let bgr = roi.reshape(3, h as i32).unwrap();
        let mut half = Mat::default();
        imgproc::resize(
            &bgr,
            &mut half,
            Size::new(w as i32 / 2, h as i32 / 2),
            0.0,
            0.0,
            imgproc::INTER_LINEAR_EXACT,
        )
        .unwrap();
        let got = mat_to_vec(&half.reshape(1, h as i32 / 2).unwrap().try_clone().unwrap()).unwrap();
        for y in 0..h / 2 {
            for x in 0..w / 2 {
                for c in 0..3 {
                    let at = |dx: usize, dy: usize| {
                        u32::from(data[(2 * y + dy) * stride + 3 * (2 * x + dx) + c])
                    };
                    let want = (at(0, 0) + at(1, 0) + at(0, 1) + at(1, 1) + 2) / 4;
                    assert_eq!(
                        u32::from(got[(y * w / 2 + x) * 3 + c]),
                        want,
                        "pixel {x},{y} channel {c}"
                    );
                }
            }
        }
    }

    #[test]
    fn box_first_level_of_colour_frames_is_opencvs_resize_then_grey() {
        // Odd and even sizes, padded strides, every rounding case of both steps.
        for (w, h, stride) in [
            (64usize, 48usize, 64 * 3 + 7),
            (251, 161, 251 * 3 + 5),
            (1920, 16, 1920 * 3),
            (640, 201, 640 * 3 + 1),
        ] {
            let data = random_colours(w, h, stride);
            let flat = Mat::new_rows_cols_with_data::<u8>(h as i32, stride as i32, &data).unwrap();
            let (ew, eh) = (w / 2 * 2, h / 2 * 2);
            let even = flat.roi(Rect::new(0, 0, 3 * ew as i32, eh as i32)).unwrap();
            let bgr = even.reshape(3, eh as i32).unwrap();
            let (mut half, mut want) = (Mat::default(), Mat::default());
            imgproc::resize(
                &bgr,
                &mut half,
                Size::new(w as i32 / 2, h as i32 / 2),
                0.0,
                0.0,
                imgproc::INTER_LINEAR_EXACT,
            )
            .unwrap();
            imgproc::cvt_color_def(&half, &mut want, imgproc::COLOR_BGR2GRAY).unwrap();
            let view = ImageView {
                width: w as u32,
                height: h as u32,
                stride,
                format: PixelFormat::Bgr8,
                data: &data,
            };
            let mut p = Pyramid::default();
            let got = mat_to_vec(p.build(&view, 1, FirstStep::Box).unwrap()).unwrap();
            let want = mat_to_vec(&want).unwrap();
            let differ = got.iter().zip(&want).filter(|(a, b)| a != b).count();
            assert_eq!(
                (got.len(), differ),
                (want.len(), 0),
                "{w}x{h}: {differ} pixels differ"
            );
        }
    }

    #[test]
    fn colour_pixels_convert_to_grey_as_opencv_does() {
        // 40,000 colours.
        let (w, h, stride) = (251usize, 160usize, 251 * 3 + 5);
        let data = random_colours(w, h, stride);
        let flat = Mat::new_rows_cols_with_data::<u8>(h as i32, stride as i32, &data).unwrap();
        let roi = flat.roi(Rect::new(0, 0, 3 * w as i32, h as i32)).unwrap();
        let bgr = roi.reshape(3, h as i32).unwrap();
        let mut grey = Mat::default();
        imgproc::cvt_color_def(&bgr, &mut grey, imgproc::COLOR_BGR2GRAY).unwrap();
        let want = mat_to_vec(&grey).unwrap();
        let got: Vec<u8> = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| {
                let p = &data[y * stride + 3 * x..][..3];
                bgr_grey(p[0], p[1], p[2])
            })
            .collect();
        let bad: Vec<_> = (0..got.len())
            .filter(|&i| got[i] != want[i])
            .map(|i| {
                let (x, y) = (i % w, i / w);
                (x, y, &data[y * stride + 3 * x..][..3], got[i], want[i])
            })
            .take(12)
            .collect();
        assert!(
            bad.is_empty(),
            "{} differ: {bad:?}",
            (0..got.len()).filter(|&i| got[i] != want[i]).count()
        );
    }

    #[test]
    fn area_resize_matches_opencv() {
        // The detector's case (480×270 → 192×128), the 640×480 camera's (320×240) and odd sizes.
        for (sw, sh, w, h) in [
            (480, 270, 192, 128),
            (320, 240, 192, 128),
            (500, 281, 192, 128),
            (333, 201, 97, 64),
            (400, 256, 192, 128),
        ] {
            let data: Vec<u8> = (0..sw * sh)
                .map(|i| ((i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 56) as u8)
                .collect();
            let src = Mat::new_rows_cols_with_data::<u8>(sh, sw, &data)
                .unwrap()
                .try_clone()
                .unwrap();
            let mut want = Mat::default();
            imgproc::resize(
                &src,
                &mut want,
                Size::new(w, h),
                0.0,
                0.0,
                imgproc::INTER_AREA,
            )
            .unwrap();
            let mut got = Mat::default();
            resize_area_grey(&src, &mut got, w, h).unwrap();
            let (g, o) = (mat_to_vec(&got).unwrap(), mat_to_vec(&want).unwrap());
            let differ = g.iter().zip(&o).filter(|(a, b)| a != b).count();
            assert_eq!(
                differ,
                0,
                "{sw}x{sh} -> {w}x{h}: {differ} of {} pixels differ",
                o.len()
            );
        }
        // Halves round to even, as `saturate_cast<uchar>(float)`; out of range saturates.
        let mut out = [0u8; 8];
        write_row(&mut out, &[0.5, 1.5, 2.5, 3.49, 254.5, 255.5, -0.7, 300.0]);
        assert_eq!(out, [0, 2, 2, 3, 254, 255, 0, 255]);
    }

    #[test]
    fn bad_buffers_are_errors() {
        let data = vec![0u8; 100];
        let mut p = Pyramid::default();
        let short = ImageView {
            width: 10,
            height: 10,
            stride: 30,
            format: PixelFormat::Bgr8,
            data: &data,
        };
        assert!(matches!(
            p.build(&short, 1, FirstStep::Box),
            Err(DetectError::BadImage(_))
        ));
        let narrow = ImageView {
            width: 10,
            height: 2,
            stride: 20,
            format: PixelFormat::Bgr8,
            data: &data,
        };
        assert!(matches!(
            p.build(&narrow, 1, FirstStep::Box),
            Err(DetectError::BadImage(_))
        ));
        let empty = ImageView {
            width: 0,
            height: 2,
            stride: 20,
            format: PixelFormat::Gray8,
            data: &data,
        };
        assert!(matches!(
            p.build(&empty, 1, FirstStep::Box),
            Err(DetectError::BadImage(_))
        ));
    }
}
