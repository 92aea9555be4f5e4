//! Image-space effects: sun disc, propeller blur, 3x3 blur, motion blur, sensor noise, JPEG-like
//! artefacts.
//!
//! All passes work in place on the caller's BGR8 buffer and use scratch owned by [`Effects`].

use crate::math::Rng;

/// Length of the noise table; rows read it at random offsets.
const NOISE_TABLE_LEN: usize = 1 << 16;
/// Apparent sun radius (radians) including the overexposed core.
const SUN_CORE_RAD: f64 = 0.0085;
/// Outer radius of the sun's bloom as a multiple of the core.
const SUN_BLOOM_FACTOR: f64 = 5.0;

/// Reusable buffers for the effect passes.
pub(crate) struct Effects {
    w: usize,
    h: usize,
    noise_sigma: f32,
    noise_pos: Vec<u8>,
    noise_neg: Vec<u8>,
    blur_rows: [Vec<u16>; 3],
    y_plane: Vec<f32>,
    cb_plane: Vec<f32>,
    cr_plane: Vec<f32>,
    prop: Option<PropellerShape>,
}

/// Propeller disc geometry for one seed: the covered pixels with their polar coordinates in the
/// disc (cached, so per frame only the cheap shading runs).
struct PropellerShape {
    seed: u64,
    /// (pixel index, normalised radius 0..1, angle rad)
    pixels: Vec<(u32, f32, f32)>,
    phase: f64,
    bend: f32,
    tone: f32,
}

impl PropellerShape {
    fn new(seed: u64, w: usize, h: usize) -> PropellerShape {
        let (wf, hf) = (w as f64, h as f64);
        let mut rng = Rng::new(seed, 0x9409);
        let left = rng.chance(0.5);
        // Disc seen obliquely from below: an ellipse whose centre lies just outside the corner.
        let rx = wf * rng.range(0.22, 0.30);
        let ry = rx * rng.range(0.35, 0.5);
        let cx = if left {
            wf * rng.range(-0.02, 0.06)
        } else {
            wf * rng.range(0.94, 1.02)
        };
        let cy = -ry * rng.range(0.15, 0.45);
        let phase = rng.range(0.0, std::f64::consts::TAU);
        // Rolling shutter bends each blade image into an arc: angle grows with radius.
        let bend = (rng.range(0.6, 1.6) * if rng.chance(0.5) { 1.0 } else { -1.0 }) as f32;
        let tone = rng.range(20.0, 45.0) as f32;
        let x0 = (cx - rx).floor().max(0.0) as usize;
        let x1 = ((cx + rx).ceil().min(wf - 1.0)).max(0.0) as usize;
        let y1 = ((cy + ry).ceil().min(hf - 1.0)).max(0.0) as usize;
        let mut pixels = Vec::new();
        for y in 0..=y1.min(h.saturating_sub(1)) {
            for x in x0..=x1.min(w.saturating_sub(1)) {
                let (ex, ey) = ((x as f64 - cx) / rx, (y as f64 - cy) / ry);
                let r = (ex * ex + ey * ey).sqrt();
                if r <= 1.0 {
                    pixels.push(((y * w + x) as u32, r as f32, ey.atan2(ex) as f32));
                }
            }
        }
        PropellerShape {
            seed,
            pixels,
            phase,
            bend,
            tone,
        }
    }
}

impl Effects {
    pub fn new(w: usize, h: usize) -> Effects {
        Effects {
            w,
            h,
            noise_sigma: -1.0,
            noise_pos: Vec::new(),
            noise_neg: Vec::new(),
            blur_rows: [vec![0; w * 3], vec![0; w * 3], vec![0; w * 3]],
            y_plane: Vec::new(),
            cb_plane: Vec::new(),
            cr_plane: Vec::new(),
            prop: None,
        }
    }

    /// Add zero-mean, approximately Gaussian noise of standard deviation `sigma` (8-bit levels)
    /// independently to every byte. Each row reads a precomputed table at a random offset:
    /// a saturating add/sub of two byte arrays, which the compiler vectorises.
    pub fn noise(&mut self, out: &mut [u8], sigma: f32, seed: u64, frame: u64) {
        if !(sigma > 0.0) {
            return;
        }
        let row_len = self.w * 3;
        if self.noise_sigma != sigma {
            // Irwin–Hall(4) rescaled to unit variance: cheap and close to Gaussian.
            let mut rng = Rng::new(0x0153, 0x0153);
            let n = NOISE_TABLE_LEN + row_len;
            self.noise_pos.clear();
            self.noise_neg.clear();
            for _ in 0..n {
                let s: f64 = (0..4).map(|_| rng.uniform()).sum::<f64>() - 2.0;
                let v = (s * 3f64.sqrt() * sigma as f64)
                    .round()
                    .clamp(-255.0, 255.0) as i32;
                self.noise_pos.push(v.max(0) as u8);
                self.noise_neg.push((-v).max(0) as u8);
            }
            self.noise_sigma = sigma;
        }
        let mut rng = Rng::new(seed ^ frame.wrapping_mul(0xA24B_AED4_963E_E407), 0x0153);
        for row in out.chunks_exact_mut(row_len) {
            let off = rng.below(NOISE_TABLE_LEN as u64) as usize;
            let pos = &self.noise_pos[off..off + row_len];
            let neg = &self.noise_neg[off..off + row_len];
            for ((p, &a), &s) in row.iter_mut().zip(pos).zip(neg) {
                *p = p.saturating_add(a).saturating_sub(s);
            }
        }
    }

    /// Horizontal motion blur, in place: each pixel becomes the mean of the `len_px` pixels
    /// of its row centred on it (rounded to a whole number; borders replicated) — the smear of
    /// a camera turning about its vertical axis during the exposure.
    pub fn motion_blur(&mut self, out: &mut [u8], len_px: f32) {
        let len = (len_px.round() as usize).clamp(1, self.w.max(1));
        if len <= 1 {
            return;
        }
        let (w, rl) = (self.w, self.w * 3);
        let (before, after) = ((len - 1) / 2, len / 2);
        // Prefix sums of one row, per channel, over the row extended by replicated borders.
        let mut prefix = vec![0u32; (w + len) * 3 + 3];
        for row in out.chunks_exact_mut(rl).take(self.h) {
            let px = |i: isize| -> usize { i.clamp(0, w as isize - 1) as usize };
            for k in 0..w + len {
                let src = px(k as isize - before as isize) * 3;
                for c in 0..3 {
                    prefix[(k + 1) * 3 + c] = prefix[k * 3 + c] + u32::from(row[src + c]);
                }
            }
            for x in 0..w {
                // Pixels x − before ..= x + after sit at extended indices x ..= x + len − 1.
                let (lo, hi) = (x, x + before + after + 1);
                for c in 0..3 {
                    let sum = prefix[hi * 3 + c] - prefix[lo * 3 + c];
                    row[x * 3 + c] = ((sum + len as u32 / 2) / len as u32) as u8;
                }
            }
        }
    }

    /// Separable [1 2 1]/4 x [1 2 1]/4 blur, in place, with replicated borders.
    pub fn blur(&mut self, out: &mut [u8]) {
        let (w, h) = (self.w, self.h);
        if w < 2 || h < 2 {
            return;
        }
        let rl = w * 3;
        // Zipped slices (no indexing) so both passes vectorise.
        let hblur = |src: &[u8], dst: &mut [u16]| {
            for c in 0..3 {
                dst[c] = 3 * src[c] as u16 + src[3 + c] as u16;
                dst[rl - 3 + c] = 3 * src[rl - 3 + c] as u16 + src[rl - 6 + c] as u16;
            }
            let mid = dst[3..rl - 3]
                .iter_mut()
                .zip(src[..rl - 6].iter().zip(&src[3..rl - 3]).zip(&src[6..]));
            for (d, ((&l, &m), &r)) in mid {
                *d = l as u16 + 2 * m as u16 + r as u16;
            }
        };
        let [r0, r1, r2] = &mut self.blur_rows;
        let (mut prev, mut cur, mut next) = (r0, r1, r2);
        hblur(&out[0..rl], cur);
        prev.copy_from_slice(cur);
        for y in 0..h {
            let ny = (y + 1).min(h - 1);
            hblur(&out[ny * rl..(ny + 1) * rl], next);
            let dst = &mut out[y * rl..(y + 1) * rl];
            for (d, ((&p, &c), &n)) in dst
                .iter_mut()
                .zip(prev.iter().zip(cur.iter()).zip(next.iter()))
            {
                *d = ((p + 2 * c + n + 8) >> 4) as u8;
            }
            std::mem::swap(&mut prev, &mut cur);
            std::mem::swap(&mut cur, &mut next);
        }
    }

    /// JPEG-like compression artefacts: YCbCr 4:2:0, 8x8 DCT, quantisation with the standard
    /// (IJG) tables scaled for `quality`, inverse DCT. Blocking, ringing and chroma bleeding.
    pub fn jpeg(&mut self, out: &mut [u8], quality: u8) {
        let (w, h) = (self.w, self.h);
        let (cw, ch) = (w.div_ceil(2), h.div_ceil(2));
        self.y_plane.resize(w * h, 0.0);
        self.cb_plane.resize(cw * ch, 0.0);
        self.cr_plane.resize(cw * ch, 0.0);
        // Forward colour transform, one 2x2 chroma cell at a time (edge cells replicate).
        for cy in 0..ch {
            let (y0, y1) = (2 * cy, (2 * cy + 1).min(h - 1));
            for cx in 0..cw {
                let (x0, x1) = (2 * cx, (2 * cx + 1).min(w - 1));
                let (mut sr, mut sg, mut sb) = (0.0f32, 0.0f32, 0.0f32);
                for (yy, xx) in [(y0, x0), (y0, x1), (y1, x0), (y1, x1)] {
                    let i = yy * w + xx;
                    let p = &out[i * 3..i * 3 + 3];
                    let (b, g, r) = (p[0] as f32, p[1] as f32, p[2] as f32);
                    self.y_plane[i] = 0.299 * r + 0.587 * g + 0.114 * b - 128.0;
                    sr += r;
                    sg += g;
                    sb += b;
                }
                let (r, g, b) = (sr * 0.25, sg * 0.25, sb * 0.25);
                self.cb_plane[cy * cw + cx] = -0.168_736 * r - 0.331_264 * g + 0.5 * b;
                self.cr_plane[cy * cw + cx] = 0.5 * r - 0.418_688 * g - 0.081_312 * b;
            }
        }
        let (ql, qc) = quant_tables(quality);
        dct_plane(&mut self.y_plane, w, h, &ql);
        dct_plane(&mut self.cb_plane, cw, ch, &qc);
        dct_plane(&mut self.cr_plane, cw, ch, &qc);
        for cy in 0..ch {
            for cx in 0..cw {
                let (cb, cr) = (self.cb_plane[cy * cw + cx], self.cr_plane[cy * cw + cx]);
                let (dr, dg, db) = (
                    1.402 * cr + 128.5,
                    -0.344_136 * cb - 0.714_136 * cr + 128.5,
                    1.772 * cb + 128.5,
                );
                for yy in 2 * cy..(2 * cy + 2).min(h) {
                    for xx in 2 * cx..(2 * cx + 2).min(w) {
                        let i = yy * w + xx;
                        let yv = self.y_plane[i];
                        let p = &mut out[i * 3..i * 3 + 3];
                        p[2] = (yv + dr) as u8;
                        p[1] = (yv + dg) as u8;
                        p[0] = (yv + db) as u8;
                    }
                }
            }
        }
    }

    /// The UAV's own propeller: a motion-blurred, semi-transparent dark disc entering the frame
    /// from a top corner (side, size and shape from the seed). Two curved blade images (rolling
    /// shutter) rotate from frame to frame.
    pub fn propeller(&mut self, out: &mut [u8], seed: u64, frame: u64) {
        if self.prop.as_ref().map(|p| p.seed) != Some(seed) {
            self.prop = Some(PropellerShape::new(seed, self.w, self.h));
        }
        let Some(shape) = self.prop.as_ref() else {
            return;
        };
        // Blade images advance by an irrational fraction of a turn per frame.
        let phase = shape.phase + frame as f64 * 2.399_963;
        const HUB_R: f32 = 0.08;
        const INV_BLADE_HALF_WIDTH: f32 = 1.0 / 0.16;
        let tau = std::f32::consts::TAU;
        let pi = std::f32::consts::PI;
        let phase = phase.rem_euclid(std::f64::consts::TAU) as f32;
        for &(idx, r, ang) in &shape.pixels {
            // Motion-blurred disc: the blades cover a larger fraction of the circle near the hub.
            let disc = (0.05 / r.max(0.05)).min(0.5) + 0.12;
            let mut blade = 0.0f32;
            for k in 0..2 {
                let centre = phase + pi * k as f32 + shape.bend * r;
                let d = (ang - centre).rem_euclid(tau);
                let x = d.min(tau - d) * INV_BLADE_HALF_WIDTH;
                // ≈ exp(-x²) without a libm call.
                let x2 = x * x;
                blade = blade.max(1.0 / (1.0 + x2 + 0.5 * x2 * x2 + x2 * x2 * x2 / 6.0));
            }
            let rim = ((1.0 - r) / 0.05).clamp(0.0, 1.0);
            let a = if r < HUB_R {
                0.95
            } else {
                ((disc + 0.55 * blade) * rim).min(0.9)
            };
            let p = &mut out[idx as usize * 3..idx as usize * 3 + 3];
            for c in p.iter_mut() {
                *c = (*c as f32 * (1.0 - a) + shape.tone * a) as u8;
            }
        }
    }

    /// Overexposed sun disc with bloom at pixel `centre` for a camera of focal `f_px`.
    pub fn sun_disc(&mut self, out: &mut [u8], centre: [f64; 2], f_px: f64, strength: f32) {
        let r_core = (SUN_CORE_RAD * f_px).max(1.5);
        let r_out = r_core * SUN_BLOOM_FACTOR;
        let (w, h) = (self.w as f64, self.h as f64);
        if centre[0] < -r_out
            || centre[1] < -r_out
            || centre[0] > w + r_out
            || centre[1] > h + r_out
        {
            return;
        }
        let (x0, x1) = (
            (centre[0] - r_out).floor().max(0.0) as usize,
            (centre[0] + r_out).ceil().min(w - 1.0) as usize,
        );
        let (y0, y1) = (
            (centre[1] - r_out).floor().max(0.0) as usize,
            (centre[1] + r_out).ceil().min(h - 1.0) as usize,
        );
        for y in y0..=y1 {
            for x in x0..=x1 {
                let d = ((x as f64 - centre[0]).powi(2) + (y as f64 - centre[1]).powi(2)).sqrt();
                let a = if d <= r_core {
                    1.0
                } else {
                    let t = (d - r_core) / (r_out - r_core);
                    if t >= 1.0 {
                        continue;
                    }
                    0.85 * (1.0 - t).powi(3)
                } as f32
                    * strength;
                let p = &mut out[(y * self.w + x) * 3..(y * self.w + x) * 3 + 3];
                let tgt = [250.0f32, 254.0, 255.0];
                for c in 0..3 {
                    p[c] = (p[c] as f32 + (tgt[c] - p[c] as f32) * a) as u8;
                }
            }
        }
    }
}

/// Standard JPEG luminance / chrominance quantisation tables scaled to `quality` (IJG formula).
fn quant_tables(quality: u8) -> ([f32; 64], [f32; 64]) {
    const LUMA: [u16; 64] = [
        16, 11, 10, 16, 24, 40, 51, 61, 12, 12, 14, 19, 26, 58, 60, 55, 14, 13, 16, 24, 40, 57, 69,
        56, 14, 17, 22, 29, 51, 87, 80, 62, 18, 22, 37, 56, 68, 109, 103, 77, 24, 35, 55, 64, 81,
        104, 113, 92, 49, 64, 78, 87, 103, 121, 120, 101, 72, 92, 95, 98, 112, 100, 103, 99,
    ];
    const CHROMA: [u16; 64] = [
        17, 18, 24, 47, 99, 99, 99, 99, 18, 21, 26, 66, 99, 99, 99, 99, 24, 26, 56, 99, 99, 99, 99,
        99, 47, 66, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99,
        99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99,
    ];
    let q = quality.clamp(1, 100) as u32;
    let s = if q < 50 { 5000 / q } else { 200 - 2 * q };
    let scale = |t: &[u16; 64]| {
        let mut o = [0f32; 64];
        for i in 0..64 {
            o[i] = ((t[i] as u32 * s + 50) / 100).clamp(1, 255) as f32;
        }
        o
    };
    (scale(&LUMA), scale(&CHROMA))
}

/// Orthonormal 8-point DCT-II matrix: `C[k][n]`.
fn dct_matrix() -> [[f32; 8]; 8] {
    let mut m = [[0f32; 8]; 8];
    for (k, row) in m.iter_mut().enumerate() {
        let a = if k == 0 {
            (1.0f64 / 8.0).sqrt()
        } else {
            (2.0f64 / 8.0).sqrt()
        };
        for (n, v) in row.iter_mut().enumerate() {
            *v = (a * (std::f64::consts::PI * (2 * n + 1) as f64 * k as f64 / 16.0).cos()) as f32;
        }
    }
    m
}

/// Round to nearest (ties to even) for |x| < 2^22 without a libm call.
#[inline(always)]
fn round_fast(x: f32) -> f32 {
    const MAGIC: f32 = 12_582_912.0; // 1.5 * 2^23
    (x + MAGIC) - MAGIC
}

/// Quantise every 8x8 block of a plane in the DCT domain (edge blocks replicate the border).
/// The loops run over contiguous rows of 8 so they vectorise.
fn dct_plane(p: &mut [f32], w: usize, h: usize, q: &[f32; 64]) {
    let c = dct_matrix();
    let mut ct = [[0f32; 8]; 8];
    for k in 0..8 {
        for n in 0..8 {
            ct[n][k] = c[k][n];
        }
    }
    let inv_q: [f32; 64] = q.map(|v| 1.0 / v);
    let mut blk = [[0f32; 8]; 8];
    let mut tmp = [[0f32; 8]; 8];
    for by in (0..h).step_by(8) {
        for bx in (0..w).step_by(8) {
            for (y, row) in blk.iter_mut().enumerate() {
                let sy = (by + y).min(h - 1);
                if bx + 8 <= w {
                    // Element-wise copy: `copy_from_slice` here becomes a memmove call per row.
                    for (d, s) in row.iter_mut().zip(&p[sy * w + bx..sy * w + bx + 8]) {
                        *d = *s;
                    }
                } else {
                    for (x, v) in row.iter_mut().enumerate() {
                        *v = p[sy * w + (bx + x).min(w - 1)];
                    }
                }
            }
            // Forward: tmp = C · blk, then blk = tmp · Cᵀ, quantised.
            for k in 0..8 {
                let mut acc = [0f32; 8];
                for n in 0..8 {
                    let s = c[k][n];
                    for x in 0..8 {
                        acc[x] += s * blk[n][x];
                    }
                }
                tmp[k] = acc;
            }
            for k in 0..8 {
                let mut acc = [0f32; 8];
                for n in 0..8 {
                    let s = tmp[k][n];
                    for l in 0..8 {
                        acc[l] += s * ct[n][l];
                    }
                }
                // The JPEG tables refer to the (1/4)-scaled 2D DCT, which equals the orthonormal
                // transform used here, so the table values apply as they are.
                for l in 0..8 {
                    let qq = q[k * 8 + l];
                    blk[k][l] = round_fast(acc[l] * inv_q[k * 8 + l]) * qq;
                }
            }
            // Inverse: tmp = Cᵀ · blk, then out = tmp · C.
            for n in 0..8 {
                let mut acc = [0f32; 8];
                for k in 0..8 {
                    let s = ct[n][k];
                    for l in 0..8 {
                        acc[l] += s * blk[k][l];
                    }
                }
                tmp[n] = acc;
            }
            for y in 0..8 {
                if by + y >= h {
                    break;
                }
                let mut acc = [0f32; 8];
                for l in 0..8 {
                    let s = tmp[y][l];
                    for x in 0..8 {
                        acc[x] += s * c[l][x];
                    }
                }
                let n = (w - bx).min(8);
                for (d, s) in p[(by + y) * w + bx..(by + y) * w + bx + n]
                    .iter_mut()
                    .zip(&acc)
                {
                    *d = *s;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn motion_blur_smears_a_vertical_edge_over_its_length_only_along_rows() {
        let (w, h) = (40, 3);
        // Dark left half, bright right half, every row alike.
        let img: Vec<u8> = (0..w * h * 3)
            .map(|i| if (i / 3) % w < w / 2 { 20 } else { 220 })
            .collect();
        let mut out = img.clone();
        Effects::new(w, h).motion_blur(&mut out, 8.0);
        let row = |r: usize| &out[r * w * 3..(r + 1) * w * 3];
        // Far from the edge, and at the replicated borders, nothing changes.
        assert_eq!(row(1)[0], 20);
        assert_eq!(row(1)[(w - 1) * 3], 220);
        assert_eq!(row(1)[(w / 2 - 5) * 3], 20);
        assert_eq!(row(1)[(w / 2 + 4) * 3], 220);
        // Across the edge the level ramps in eighths: 8 pixels in between, rising.
        let ramp: Vec<u8> = (w / 2 - 4..w / 2 + 4).map(|x| row(1)[x * 3]).collect();
        assert!(ramp.windows(2).all(|p| p[0] < p[1]), "{ramp:?}");
        // One bright pixel of eight: 20 + 200/8.
        assert_eq!(ramp[0], 20 + 25);
        // Rows stay rows: the blur does not mix them, all three are equal.
        assert_eq!(row(0), row(2));
        // Length 1 (or less) is no blur.
        let mut same = img.clone();
        Effects::new(w, h).motion_blur(&mut same, 0.6);
        assert_eq!(same, img);
    }

    #[test]
    fn dct_quantisation_with_unit_table_is_nearly_identity() {
        let (w, h) = (19, 11);
        let mut rng = Rng::new(3, 4);
        let orig: Vec<f32> = (0..w * h)
            .map(|_| rng.range(-128.0, 127.0) as f32)
            .collect();
        let mut p = orig.clone();
        dct_plane(&mut p, w, h, &[1.0; 64]);
        // Rounding each coefficient to an integer moves each pixel by well under a level.
        let worst = p
            .iter()
            .zip(&orig)
            .map(|(a, b)| (a - b).abs())
            .fold(0f32, f32::max);
        assert!(worst < 1.5, "worst {worst}");
        assert!(worst > 0.0);
    }

    #[test]
    fn jpeg_quality_100_is_nearly_lossless_and_low_quality_is_not() {
        let (w, h) = (37, 21);
        let mut rng = Rng::new(5, 6);
        let img: Vec<u8> = (0..w * h * 3)
            .map(|i| ((i % 97) as f64 * 2.0 + rng.range(0.0, 20.0)) as u8)
            .collect();
        let mut fx = Effects::new(w, h);
        let mut hi = img.clone();
        fx.jpeg(&mut hi, 100);
        let mut lo = img.clone();
        fx.jpeg(&mut lo, 10);
        let mad = |a: &[u8]| {
            a.iter()
                .zip(&img)
                .map(|(&x, &y)| (x as f64 - y as f64).abs())
                .sum::<f64>()
                / img.len() as f64
        };
        // Chroma subsampling alone costs a few levels on this busy pattern.
        assert!(mad(&hi) < mad(&lo), "q100 {} vs q10 {}", mad(&hi), mad(&lo));
        assert!(mad(&lo) > 3.0);
    }
}
