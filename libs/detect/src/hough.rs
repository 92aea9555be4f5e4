//! Progressive probabilistic Hough transform (Matas, Galambos & Kittler 2000, the algorithm of
//! OpenCV's `HoughLinesP`) in which every edge pixel votes only for the line directions its own
//! gradient allows (O'Gorman & Clowes 1976).
//!
//! A straight edge's pixels all have their gradient along the line's normal, so a pixel votes
//! for the normal angles within `orientation_tol_deg` of its gradient direction instead of all
//! 180: on the default settings (±10° of 1° bins) that is 21 votes instead of 180, the main
//! cost of the transform. Texture pixels, whose gradients point every way, no longer pile up
//! in the bins of lines they do not lie on, so the accumulator is also cleaner. With a
//! tolerance of 90° every pixel votes for every angle, which is `HoughLinesP` itself.
//!
//! Like `HoughLinesP`: pixels are visited in a fixed pseudo-random order (deterministic from
//! frame to frame); when a bin reaches the threshold, the line through the pixel is walked both
//! ways on the edge mask, bridging gaps up to `max_gap`; a walk spanning `min_length` (in x or
//! y) is a segment whose pixels withdraw their votes; walked pixels leave the mask either way.
//! Unlike it, only pixels that voted withdraw votes (`HoughLinesP` also subtracts votes never
//! cast, driving bins below zero).

use crate::geometry::Segment;

/// A Canny edge image and its Sobel gradients, row-major, `width`·`height` each (working px).
#[derive(Debug, Clone, Copy)]
pub(crate) struct EdgeImage<'a> {
    /// Non-zero on edge pixels.
    pub edges: &'a [u8],
    /// Horizontal gradient.
    pub dx: &'a [i16],
    /// Vertical gradient.
    pub dy: &'a [i16],
    /// Width, px.
    pub width: usize,
    /// Height, px.
    pub height: usize,
}

/// Fixed-point fraction bits of the line walk.
const SHIFT: u32 = 16;
/// Fixed-point fraction bits of a vote's rho: enough that integer votes fall in the same bins
/// as exact arithmetic would (the error, |x|·2⁻³², is far below any bin boundary distance
/// that occurs), and few enough that i64 cannot overflow for sides up to u16.
const VOTE_SHIFT: u32 = 32;
/// Seed of the visiting order (any fixed value: the order must only be the same every frame).
const ORDER_SEED: u64 = 0x9E37_79B9_7F4A_7C15;

/// Settings of [`OrientedHough::run`], in working px.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct HoughSettings {
    /// Distance resolution, px.
    pub rho: f64,
    /// Angle resolution, degrees.
    pub theta_deg: f64,
    /// Votes a bin needs before its line is walked.
    pub threshold: u32,
    /// A segment must span this many px in x or y.
    pub min_length: f64,
    /// Largest gap bridged inside a segment, px.
    pub max_gap: f64,
    /// A pixel votes for normal angles within this of its gradient direction, degrees (≥ 90: all).
    pub orientation_tol_deg: f64,
}

/// Reusable buffers of the transform (no allocation per frame once sized).
#[derive(Default)]
pub(crate) struct OrientedHough {
    /// Votes, `[rho][angle]`: a pixel's neighbouring angles share cache lines. A bin holds the
    /// pixels of one strip `rho` wide across the image (< width + height at 1 px), so u16
    /// (saturating, for absurd settings) halves the memory cleared per frame.
    acc: Vec<u16>,
    /// 0: no edge (or already on a segment); 1: edge pixel not yet visited; 2: visited and voted.
    mask: Vec<u8>,
    /// First angle bin each pixel votes for (per pixel, for withdrawing its votes).
    first: Vec<u16>,
    /// Edge pixels `(x, y)`, shuffled.
    points: Vec<(u16, u16)>,
    cos: Vec<f64>,
    sin: Vec<f64>,
    /// `cos / rho` and `sin / rho` in fixed point (`VOTE_SHIFT - 1` fraction bits, for coordinates
    /// doubled so that a half-pixel image centre stays an integer): votes in integer arithmetic.
    cos_q: Vec<i64>,
    sin_q: Vec<i64>,
}

impl OrientedHough {
    /// Segments among the non-zero pixels of `img.edges`, whose gradients are `img.dx`,
    /// `img.dy`, written to `out` (cleared first) in the order found. Buffers shorter than
    /// `width`·`height`, or sides beyond u16 (working images are at most a few hundred px), give
    /// no segments.
    pub fn run(&mut self, img: &EdgeImage<'_>, s: &HoughSettings, out: &mut Vec<Segment>) {
        let EdgeImage {
            edges,
            dx,
            dy,
            width,
            height,
        } = *img;
        out.clear();
        let n = width * height;
        if width == 0
            || height == 0
            || edges.len() < n
            || dx.len() < n
            || dy.len() < n
            || width > u16::MAX as usize
            || height > u16::MAX as usize
        {
            return;
        }
        let theta = s.theta_deg.to_radians();
        let num_angle = ((std::f64::consts::PI / theta).round() as usize).max(1);
        let irho = 1.0 / s.rho;
        // Distances from the image centre (not a corner, as HoughLinesP): |rho| is at most half
        // the diagonal, so the accumulator is ~3x smaller and stays in cache.
        let (xc, yc) = (width as f64 / 2.0, height as f64 / 2.0);
        let half_rho = (xc.hypot(yc) / s.rho).ceil() as usize + 1;
        let num_rho = 2 * half_rho + 1;
        // rho_off + ½ makes the value positive, so truncation rounds (half up).
        let rho_round = to_fixed(half_rho as f64 + 0.5, VOTE_SHIFT);
        self.cos.clear();
        self.sin.clear();
        self.cos_q.clear();
        self.sin_q.clear();
        for k in 0..num_angle {
            let a = k as f64 * theta;
            self.cos.push(a.cos() * irho);
            self.sin.push(a.sin() * irho);
            self.cos_q.push(to_fixed(a.cos() * irho, VOTE_SHIFT - 1));
            self.sin_q.push(to_fixed(a.sin() * irho, VOTE_SHIFT - 1));
        }
        let (cos_q, sin_q) = (&self.cos_q, &self.sin_q);
        let bin = move |x2: i64, y2: i64, t: usize| rho_bin(x2, y2, cos_q[t], sin_q[t], rho_round);
        // Bins each pixel votes for: 2·half + 1 around its gradient angle (all when ≥ 90°).
        let half = if s.orientation_tol_deg >= 90.0 {
            num_angle
        } else {
            (s.orientation_tol_deg / s.theta_deg).round().max(0.0) as usize
        };
        let (span, all) = if 2 * half + 1 >= num_angle {
            (num_angle, true)
        } else {
            (2 * half + 1, false)
        };
        self.acc.clear();
        self.acc.resize(num_angle * num_rho, 0);
        self.mask.clear();
        self.mask.resize(n, 0);
        self.first.clear();
        self.first.resize(n, 0);
        self.points.clear();
        for y in 0..height {
            for x in 0..width {
                let i = y * width + x;
                if edges[i] == 0 {
                    continue;
                }
                self.mask[i] = 1;
                let first = if all {
                    0
                } else {
                    // The normal angle in [0, π): the gradient direction modulo π.
                    let a = normal_angle(dx[i], dy[i]);
                    let centre = (a / theta).round() as usize % num_angle;
                    (centre + num_angle - half) % num_angle
                };
                self.first[i] = first as u16;
                self.points.push((x as u16, y as u16));
            }
        }
        // Fisher–Yates with a fixed xorshift sequence: the same order every frame.
        let mut state = ORDER_SEED;
        for i in (1..self.points.len()).rev() {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let j = (state % (i as u64 + 1)) as usize;
            self.points.swap(i, j);
        }
        let max_gap = s.max_gap.max(0.0) as i64;
        let min_length = s.min_length;
        for pi in 0..self.points.len() {
            let (x, y) = self.points[pi];
            let i = y as usize * width + x as usize;
            if self.mask[i] != 1 {
                continue;
            }
            self.mask[i] = 2;
            let first = self.first[i];
            // Vote, keeping the strongest bin.
            let (mut best, mut best_n) = (0u16, 0usize);
            let (x2, y2) = (2 * x as i64 - width as i64, 2 * y as i64 - height as i64);
            let mut t = first as usize;
            for _ in 0..span {
                let r = bin(x2, y2, t);
                let v = &mut self.acc[r * num_angle + t];
                *v = v.saturating_add(1);
                if *v > best {
                    best = *v;
                    best_n = t;
                }
                t += 1;
                if t == num_angle {
                    t = 0;
                }
            }
            if (best as u32) < s.threshold {
                continue;
            }
            // Walk the line of bin best_n through (x, y) both ways in fixed point, one px per
            // step along the dominant axis.
            let (a, b) = (-self.sin[best_n], self.cos[best_n]);
            let x_major = a.abs() > b.abs();
            let (step_x, step_y, x0, y0) = if x_major {
                (
                    a.signum() as i64,
                    ((b * (1i64 << SHIFT) as f64) / a.abs()).round() as i64,
                    x as i64,
                    ((y as i64) << SHIFT) + (1 << (SHIFT - 1)),
                )
            } else {
                (
                    ((a * (1i64 << SHIFT) as f64) / b.abs()).round() as i64,
                    b.signum() as i64,
                    ((x as i64) << SHIFT) + (1 << (SHIFT - 1)),
                    y as i64,
                )
            };
            let pixel = |px: i64, py: i64| {
                if x_major {
                    (px, py >> SHIFT)
                } else {
                    (px >> SHIFT, py)
                }
            };
            let inside = |(c, r): (i64, i64)| {
                c >= 0 && r >= 0 && (c as usize) < width && (r as usize) < height
            };
            let mut ends = [(x as i64, y as i64); 2];
            for (k, end) in ends.iter_mut().enumerate() {
                let (sx, sy) = if k == 0 {
                    (step_x, step_y)
                } else {
                    (-step_x, -step_y)
                };
                let (mut px, mut py, mut gap) = (x0, y0, 0);
                loop {
                    let (c, r) = pixel(px, py);
                    if !inside((c, r)) {
                        break;
                    }
                    if self.mask[r as usize * width + c as usize] != 0 {
                        gap = 0;
                        *end = (c, r);
                    } else {
                        gap += 1;
                        if gap > max_gap {
                            break;
                        }
                    }
                    px += sx;
                    py += sy;
                }
            }
            let good = ((ends[1].0 - ends[0].0).abs() as f64) >= min_length
                || ((ends[1].1 - ends[0].1).abs() as f64) >= min_length;
            // Take the walked pixels off the mask; on a segment, withdraw the votes they cast.
            for (k, end) in ends.iter().enumerate() {
                let (sx, sy) = if k == 0 {
                    (step_x, step_y)
                } else {
                    (-step_x, -step_y)
                };
                let (mut px, mut py) = (x0, y0);
                loop {
                    let (c, r) = pixel(px, py);
                    if !inside((c, r)) {
                        break;
                    }
                    let i = r as usize * width + c as usize;
                    if self.mask[i] == 2 && good {
                        let (c2, r2) = (2 * c - width as i64, 2 * r - height as i64);
                        let mut t = self.first[i] as usize;
                        for _ in 0..span {
                            let rr = bin(c2, r2, t);
                            let v = &mut self.acc[rr * num_angle + t];
                            *v = v.saturating_sub(1);
                            t += 1;
                            if t == num_angle {
                                t = 0;
                            }
                        }
                    }
                    // As in HoughLinesP, a walk that made no segment also takes its pixels off.
                    self.mask[i] = 0;
                    if (c, r) == *end {
                        break;
                    }
                    px += sx;
                    py += sy;
                }
            }
            if good {
                out.push(Segment::new(
                    [ends[0].0 as f64, ends[0].1 as f64],
                    [ends[1].0 as f64, ends[1].1 as f64],
                ));
            }
        }
    }
}

/// `v` in fixed point with `bits` fraction bits.
fn to_fixed(v: f64, bits: u32) -> i64 {
    (v * (1i64 << bits) as f64).round() as i64
}

/// Rho bin of a pixel given as doubled centred coordinates (`2x - width`, `2y - height`: a
/// half-pixel image centre stays an integer), with `cos_q`, `sin_q` (cos/rho, sin/rho) at
/// `VOTE_SHIFT - 1` and the offset `rho_round` at `VOTE_SHIFT` fraction bits. Integer
/// arithmetic: the vote loop's cost, and no float-to-int conversion per vote.
#[inline]
fn rho_bin(x2: i64, y2: i64, cos_q: i64, sin_q: i64, rho_round: i64) -> usize {
    ((x2 * cos_q + y2 * sin_q + rho_round) >> VOTE_SHIFT) as usize
}

/// The gradient direction `(gx, gy)` modulo π, in [0, π]: the normal of the edge through the
/// pixel. A polynomial arctangent (max error 0.06°, far below the 1° bins) instead of libm's
/// `atan2`, which cost as much as the voting.
fn normal_angle(gx: i16, gy: i16) -> f64 {
    use std::f64::consts::{FRAC_PI_2, PI};
    let (x, y) = (gx as f64, gy as f64);
    let (ax, ay) = (x.abs(), y.abs());
    if ax == 0.0 && ay == 0.0 {
        return 0.0;
    }
    // atan of the smaller over the larger ratio, in [0, π/4].
    let (t, swapped) = if ay <= ax {
        (ay / ax, false)
    } else {
        (ax / ay, true)
    };
    let t2 = t * t;
    let mut a = t
        * (0.999_866
            + t2 * (-0.330_299_5 + t2 * (0.180_141 + t2 * (-0.085_133 + t2 * 0.020_835_1))));
    if swapped {
        a = FRAC_PI_2 - a;
    }
    // Into the gradient's quadrant, then modulo π.
    let full = match (x >= 0.0, y >= 0.0) {
        (true, true) => a,
        (false, true) => PI - a,
        (false, false) => a - PI,
        (true, false) => -a,
    };
    if full < 0.0 {
        full + PI
    } else {
        full
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view<'a>(e: &'a [u8], gx: &'a [i16], gy: &'a [i16], w: usize, h: usize) -> EdgeImage<'a> {
        EdgeImage {
            edges: e,
            dx: gx,
            dy: gy,
            width: w,
            height: h,
        }
    }

    #[test]
    fn integer_votes_fall_in_the_bins_of_exact_arithmetic() {
        // Every pixel of a 480x270 working image (and of an odd-sized one, whose centre is a
        // half pixel), every 1° angle, 1 px rho: the fixed-point bin equals the f64 bin, except
        // on exact bin boundaries (cos 60° = 0.5 puts some pixels there), where f64's own
        // rounding of cos decides and either bin is right.
        for (w, h) in [(480usize, 270usize), (321, 241)] {
            let (xc, yc) = (w as f64 / 2.0, h as f64 / 2.0);
            let half_rho = xc.hypot(yc).ceil() as usize + 1;
            let rho_round = to_fixed(half_rho as f64 + 0.5, VOTE_SHIFT);
            for k in 0..180 {
                let a = (k as f64).to_radians();
                let (c, s) = (a.cos(), a.sin());
                let (cq, sq) = (to_fixed(c, VOTE_SHIFT - 1), to_fixed(s, VOTE_SHIFT - 1));
                for y in 0..h {
                    for x in 0..w {
                        let v = (x as f64 - xc) * c + (y as f64 - yc) * s + half_rho as f64 + 0.5;
                        if (v - v.round()).abs() < 1e-9 {
                            continue;
                        }
                        let exact = v as usize;
                        let fixed = rho_bin(
                            2 * x as i64 - w as i64,
                            2 * y as i64 - h as i64,
                            cq,
                            sq,
                            rho_round,
                        );
                        assert_eq!(fixed, exact, "pixel ({x}, {y}) angle {k} in {w}x{h}");
                    }
                }
            }
        }
    }

    #[test]
    fn fast_normal_angle_matches_atan2() {
        for gx in (-300..=300).step_by(7) {
            for gy in (-300..=300).step_by(11) {
                if gx == 0 && gy == 0 {
                    continue;
                }
                let exact = (gy as f64)
                    .atan2(gx as f64)
                    .rem_euclid(std::f64::consts::PI);
                let fast = normal_angle(gx as i16, gy as i16);
                // Equal modulo π (0 and π are the same normal).
                let d = (fast - exact).abs();
                let d = d.min((d - std::f64::consts::PI).abs());
                assert!(d < 0.06f64.to_radians(), "({gx}, {gy}): {fast} vs {exact}");
            }
        }
    }

    /// An image with the given lines drawn (1 px, gradients along their normals) and noise.
    fn scene(
        w: usize,
        h: usize,
        lines: &[([f64; 2], [f64; 2])],
        noise: usize,
    ) -> (Vec<u8>, Vec<i16>, Vec<i16>) {
        let (mut e, mut gx, mut gy) = (vec![0u8; w * h], vec![0i16; w * h], vec![0i16; w * h]);
        for &(a, b) in lines {
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let len = dx.hypot(dy);
            let (nx, ny) = (-dy / len, dx / len);
            for k in 0..=(len.ceil() as usize) {
                let t = k as f64 / len;
                let (x, y) = (
                    (a[0] + t * dx).round() as usize,
                    (a[1] + t * dy).round() as usize,
                );
                if x < w && y < h {
                    e[y * w + x] = 255;
                    gx[y * w + x] = (nx * 200.0) as i16;
                    gy[y * w + x] = (ny * 200.0) as i16;
                }
            }
        }
        // Scattered texture pixels with random gradients.
        let mut state = 12345u64;
        for _ in 0..noise {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let i = (state >> 33) as usize % (w * h);
            e[i] = 255;
            gx[i] = ((state >> 8) & 0xff) as i16 - 128;
            gy[i] = ((state >> 16) & 0xff) as i16 - 128;
        }
        (e, gx, gy)
    }

    fn settings(tol: f64) -> HoughSettings {
        HoughSettings {
            rho: 1.0,
            theta_deg: 1.0,
            threshold: 20,
            min_length: 20.0,
            max_gap: 4.0,
            orientation_tol_deg: tol,
        }
    }

    #[test]
    fn finds_every_line_among_texture_with_and_without_orientation() {
        let lines = [
            ([20.0, 30.0], [180.0, 90.0]),
            ([100.0, 10.0], [104.0, 140.0]),
            ([10.0, 140.0], [120.0, 145.0]),
        ];
        let (e, gx, gy) = scene(200, 150, &lines, 600);
        for tol in [10.0, 90.0] {
            let mut hough = OrientedHough::default();
            let mut out = Vec::new();
            hough.run(&view(&e, &gx, &gy, 200, 150), &settings(tol), &mut out);
            for (a, b) in lines {
                // Covered by segments on it (the walk may split a digital line in pieces, as
                // HoughLinesP does; the geometry merges collinear pieces).
                let truth = Segment::new(a, b);
                let on: f64 = out
                    .iter()
                    .filter(|s| [s.a, s.b].iter().all(|p| truth.line_distance(*p) <= 1.5))
                    .map(|s| s.length())
                    .sum();
                assert!(
                    on >= 0.7 * truth.length(),
                    "tol {tol}: {truth:?} covered {on:.0} px by {out:?}"
                );
            }
        }
    }

    #[test]
    fn gradients_across_the_line_cast_no_votes_for_it() {
        // The same pixels, but every gradient along the line instead of across it: with the
        // orientation rule no bin of that line gets their votes; without it the line is found.
        let (e, gx, gy) = scene(200, 150, &[([20.0, 75.0], [180.0, 75.0])], 0);
        let (gx, gy) = (gy, gx);
        let mut out = Vec::new();
        OrientedHough::default().run(&view(&e, &gx, &gy, 200, 150), &settings(10.0), &mut out);
        assert!(out.is_empty(), "{out:?}");
        OrientedHough::default().run(&view(&e, &gx, &gy, 200, 150), &settings(90.0), &mut out);
        assert_eq!(out.len(), 1, "{out:?}");
    }

    #[test]
    fn same_input_same_segments() {
        let (e, gx, gy) = scene(
            160,
            120,
            &[([10.0, 10.0], [150.0, 100.0]), ([80.0, 5.0], [60.0, 115.0])],
            300,
        );
        let (mut a, mut b) = (Vec::new(), Vec::new());
        let mut hough = OrientedHough::default();
        hough.run(&view(&e, &gx, &gy, 160, 120), &settings(10.0), &mut a);
        hough.run(&view(&e, &gx, &gy, 160, 120), &settings(10.0), &mut b);
        assert_eq!(a, b);
    }
}
