//! The tower from both of its edges.
//!
//! The relative yaw comes from the hub–tower gap (hub x − tower-axis x), a few pixels per degree,
//! so the tower axis must be right to a pixel. Hough often finds one tower edge only: the lower
//! blade hides the other near the top, or the sea behind it has little contrast. One edge is
//! half a tower width off the axis (10–25 px at 10–25 m with the GoPro), which alone is a
//! 10–20° yaw error. So from the edge Hough found (the *seed*), the partner edge is looked for
//! in the horizontal gradient: the tower is a band of uniform shade, so its other edge has the
//! opposite gradient sign at a near-constant offset on every row from the tower top down
//! (unless it is lit from one side against ground of a middle shade: then both edges share a
//! sign and the opposite one is the shading inside, see [`fit_tower`]). Accumulating that
//! signed response over all rows (blades crossing the tower hide only some of them) gives the
//! width; both edges are then fitted to sub-pixel edge points and the axis is their midline.
//! Without a partner the axis is unknown and no tower is reported. A blade pointing down is also
//! a band of two edges, but it narrows toward its tip, while the tower widens downward by its
//! taper only (its rows are at about the same depth from a level camera): bands narrowing
//! downward are no tower, nor are bands widening faster than the taper allows (from a tower
//! edge to the edge of a blade crossing it).

use crate::geometry::{Segment, P2};
use crate::params::DefaultParams;

/// An edge point must reach this fraction of the edge's typical (75th percentile) response.
const EDGE_POINT_MIN_OF_TYPICAL: f64 = 0.4;
/// Edge points are searched this far (px) on either side of the predicted edge position.
const EDGE_SEARCH_PX: i64 = 2;
/// Edge points farther than this (px) from the first line fit are dropped before the second.
const EDGE_OUTLIER_PX: f64 = 1.5;
/// An edge fit needs at least this many points.
const EDGE_MIN_POINTS: usize = 6;

/// One Sobel gradient plane (x or y) of the working image, row-major.
pub(crate) struct GradPlane<'a> {
    /// `width · height` values.
    pub data: &'a [i16],
    /// Image width, px.
    pub width: usize,
    /// Image height, px.
    pub height: usize,
}

impl GradPlane<'_> {
    /// The value at `(x, y)`; 0 outside the image.
    pub fn at(&self, x: i64, y: i64) -> f64 {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
            return 0.0;
        }
        self.data[y as usize * self.width + x as usize] as f64
    }

    /// Row `y` (in range).
    fn row(&self, y: i64) -> &[i16] {
        &self.data[y as usize * self.width..][..self.width]
    }
}

/// The tower measured from its two edges (working px).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct TowerFit {
    /// The two edge lines, left first (x at their common top row).
    pub edges: [Segment; 2],
    /// The midline, from the top row of the fit down.
    pub axis: Segment,
}

impl TowerFit {
    /// Distance between the edge lines at row `y`.
    pub fn width_at(&self, y: f64) -> Option<f64> {
        Some((self.edges[1].x_at_y(y)? - self.edges[0].x_at_y(y)?).abs())
    }
}

/// Finds the tower's second edge from `seed` (one tower edge, from its top down) and fits both;
/// `None` when no edge of the opposite gradient sign runs beside it at a tower-like width.
/// `window` (working px, min and max) narrows the tower-like widths further.
pub(crate) fn fit_tower(
    p: &DefaultParams,
    g: &GradPlane<'_>,
    seed: &Segment,
    window: (f64, f64),
) -> Option<TowerFit> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { fit_tower_avx2(p, g, seed, window) };
    }
    fit_tower_here(p, g, seed, window)
}

/// [`fit_tower`] compiled for AVX2 (the partner search's sums over all offsets vectorise to
/// twice the width; integer sums, the same results).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn fit_tower_avx2(
    p: &DefaultParams,
    g: &GradPlane<'_>,
    seed: &Segment,
    window: (f64, f64),
) -> Option<TowerFit> {
    fit_tower_here(p, g, seed, window)
}

#[inline(always)]
fn fit_tower_here(
    p: &DefaultParams,
    g: &GradPlane<'_>,
    seed: &Segment,
    window: (f64, f64),
) -> Option<TowerFit> {
    let h = g.height as f64;
    let top = seed.a[1].min(seed.b[1]).max(0.0);
    let seed_bottom = seed.a[1].max(seed.b[1]);
    let rows: Vec<i64> = (top.ceil() as i64..g.height as i64 - 1).collect();
    let x0 = |y: i64| seed.x_at_y(y as f64);

    // The seed's gradient sign (over its own extent) and mean strength over all rows (its line
    // extended down), the same rows the partner is measured on.
    let best_near = |x: f64, y: i64| {
        let xi = x.round() as i64;
        (-1..=1)
            .map(|d| g.at(xi + d, y))
            .max_by(|a, b| a.abs().total_cmp(&b.abs()))
            .unwrap_or(0.0)
    };
    let sum: f64 = rows
        .iter()
        .filter(|&&y| (y as f64) <= seed_bottom)
        .filter_map(|&y| Some(best_near(x0(y)?, y)))
        .sum();
    if sum == 0.0 {
        return None;
    }
    let sign = sum.signum();
    let strength = rows
        .iter()
        .filter_map(|&y| Some((best_near(x0(y)?, y) * sign).max(0.0)))
        .sum::<f64>()
        / rows.len().max(1) as f64;
    if strength <= 0.0 {
        return None;
    }

    // Partner: on either side, at an offset that may drift linearly from the top row to the
    // bottom one (the two edges of a tapered tower seen in perspective are not parallel),
    // accumulated over all rows. Normally of the opposite gradient sign (a band of uniform
    // shade). But a tower lit from one side against ground of a middle shade is darker than the
    // ground at one limb and brighter at the other: both edges have the seed's sign, and the
    // only opposite-sign response is the shading inside, a ramp or a sharp terminator (widths
    // read ~0.6x). So when a same-sign edge lies beyond the opposite-sign partner, that edge is
    // the silhouette.
    let wmin = (p.tower_min_width_frac * h).max(window.0).ceil().max(1.0) as i64;
    let wmax = (p.tower_max_width_frac * h).min(window.1).floor() as i64;
    if wmax < wmin || rows.is_empty() {
        return None;
    }
    let search = PartnerSearch {
        g,
        rows: &rows,
        x0: &x0,
        wmin,
        wmax,
    };
    let opposite = search.best(-sign)?;
    // Behind the opposite-sign edge, ramp or not: a tower in direct sun shows a sharp shading
    // terminator too, lit half on one side and dark limb on the other, and that terminator is
    // then the strongest opposite-sign response (the dark limb on brighter ground has the
    // seed's sign). Measured: the slim turbine's 1.8 m tower through the 90° 640×480 lens read
    // 0.65× its width at 20–30 m (`eval --sequence`), a search cost lost in the frame time.
    let same = search.best(sign);
    let beyond = |s: &Partner| {
        opposite.off_top.signum() == s.off_top.signum()
            && s.off_top.abs() > opposite.off_top.abs()
            && s.response >= p.tower_same_sign_partner_min_ratio * opposite.response
    };
    let (partner_sign, found) = match same {
        Some(s) if beyond(&s) => (sign, s),
        _ => (-sign, opposite),
    };
    let Partner {
        response,
        off_top,
        off_bot,
        background,
        ..
    } = found;
    log::trace!(
        "tower partner of {seed:?} (sign {sign}, partner {partner_sign}; opposite {:.0}, same {:.0}): offsets {off_top}..{off_bot} px, response {response:.0}, seed {strength:.0}, background {background:.1}",
        opposite.response,
        same.map_or(0.0, |s| s.response),
    );
    if response < p.tower_partner_min_ratio * strength
        || response < p.tower_partner_min_salience * background
    {
        return None;
    }
    let (y_top, y_bot) = (rows[0] as f64, *rows.last()? as f64);
    let frac = |y: i64| {
        if y_bot > y_top {
            (y as f64 - y_top) / (y_bot - y_top)
        } else {
            0.0
        }
    };
    let offset = |y: i64| off_top as f64 + (off_bot - off_top) as f64 * frac(y);

    let seed_fit = fit_edge(g, &rows, x0, sign)?;
    let partner_fit = fit_edge(g, &rows, |y| x0(y).map(|x| x + offset(y)), partner_sign)?;
    // Each edge moves outward to the end of its shading ramp, if it is one.
    let out = off_top.signum() as f64; // from the seed toward the partner
                                       // Within the width window: half the room left to its upper end for each edge.
    let room = (window.1 - off_top.abs().max(off_bot.abs()) as f64) / 2.0;
    let max_ramp = (off_top.abs() as f64 * p.tower_ramp_max_frac)
        .min(room)
        .floor()
        .max(0.0) as i64;
    let seed_fit = to_ramp_end(
        g,
        &rows,
        seed_fit,
        sign,
        -out,
        p.tower_ramp_min_frac,
        max_ramp,
    );
    let partner_fit = to_ramp_end(
        g,
        &rows,
        partner_fit,
        partner_sign,
        out,
        p.tower_ramp_min_frac,
        max_ramp,
    );
    let (left, right) = if off_top > 0 {
        (seed_fit, partner_fit)
    } else {
        (partner_fit, seed_fit)
    };
    let bottom = h - 1.0;
    let mid = |y: f64| Some((left.x_at_y(y)? + right.x_at_y(y)?) / 2.0);
    let axis = Segment::new([mid(top)?, top], [mid(bottom)?, bottom]);
    let fit = TowerFit {
        edges: [left, right],
        axis,
    };
    // A blade pointing down is a band too, but narrows toward its tip; the tower does not.
    // It widens downward by its own taper only (its rows are at about the same depth).
    let top_width = fit.width_at(top)?.max(1e-9);
    let taper = fit.width_at(bottom)? / top_width;
    let max_taper = p.tower_max_width_ratio * (1.0 + p.tower_taper * (bottom - top) / top_width);
    log::trace!(
        "tower band {:?}: width ratio bottom/top {taper:.2} (max {max_taper:.2})",
        fit.axis
    );
    (taper >= p.tower_min_width_ratio && taper <= max_taper).then_some(fit)
}

/// Largest tilt from the image vertical the tower scan searches, degrees.
const MAX_SCAN_TILT_DEG: f64 = 60.0;

/// Tower edges straight from the gradient, for when the Hough transform has none: near a
/// jagged, slightly tilted edge its walk along the accumulator direction leaves the edge
/// within a few tens of pixels, the short piece is dropped with its votes, and a tower edge
/// 80 px long in plain view goes missing. Here every near-vertical line from row `top` to the
/// bottom whose top is within `max_dx` of `hub_x` is scored by its mean signed horizontal
/// gradient (a tower edge keeps its sign all the way down); the `max_seeds` strongest local
/// maxima, each at least `min_salience` times the mean score, are returned as segments (top
/// first). `max_tilt_deg` bounds the tilt from the image vertical (roll included).
pub(crate) fn scan_tower_edges(
    g: &GradPlane<'_>,
    hub_x: f64,
    top: f64,
    max_dx: f64,
    max_tilt_deg: f64,
    min_salience: f64,
    max_seeds: usize,
) -> Vec<Segment> {
    let y0 = top.max(0.0).ceil() as i64;
    let y1 = g.height as i64 - 1;
    if y1 - y0 < EDGE_MIN_POINTS as i64 || max_dx <= 0.0 {
        return Vec::new();
    }
    let n = (y1 - y0) as f64;
    // The drift range grows with tan(tilt): bounded, so that no tilt (a roll hint added to it)
    // can ask for an unbounded accumulator.
    let max_drift = (max_tilt_deg
        .clamp(0.0, MAX_SCAN_TILT_DEG)
        .to_radians()
        .tan()
        * n)
        .round() as i64;
    let x_lo = (hub_x - max_dx).floor().max(0.0) as i64;
    let x_hi = (hub_x + max_dx).ceil().min(g.width as f64 - 1.0) as i64;
    let (nx, nd) = (
        (x_hi - x_lo + 1).max(0) as usize,
        (2 * max_drift + 1) as usize,
    );
    let mut score = vec![0.0f64; nx * nd];
    // For each drift, every start column is summed at once along the row (contiguous,
    // vectorised); integer sums are exact, so equal to summing the f64 values.
    let mut acc = vec![0i32; nx];
    for (j, d) in (-max_drift..=max_drift).enumerate() {
        acc.iter_mut().for_each(|a| *a = 0);
        for (y, st) in (y0..y1).zip(round_steps(d, y1 - y0)) {
            // Columns x_lo + i + st inside the image; outside counts as 0.
            let first = x_lo + st;
            let i_lo = (-first).max(0) as usize;
            let i_hi = ((g.width as i64 - first).max(0) as usize).min(nx);
            if i_lo >= i_hi {
                continue;
            }
            let row = &g.row(y)[(first + i_lo as i64) as usize..];
            acc[i_lo..i_hi]
                .iter_mut()
                .zip(row)
                .for_each(|(a, &v)| *a += v as i32);
        }
        for (i, a) in acc.iter().enumerate() {
            score[i * nd + j] = (*a as f64 / n).abs();
        }
    }
    let mean = score.iter().sum::<f64>() / score.len().max(1) as f64;
    let mut peaks: Vec<(f64, usize, usize)> = Vec::new();
    for i in 0..nx {
        for j in 0..nd {
            let v = score[i * nd + j];
            if v < min_salience * mean || v <= 0.0 {
                continue;
            }
            // A local maximum over neighbouring positions and drifts.
            let is_max = (i.saturating_sub(2)..(i + 3).min(nx))
                .all(|a| (j.saturating_sub(2)..(j + 3).min(nd)).all(|b| score[a * nd + b] <= v));
            if is_max {
                peaks.push((v, i, j));
            }
        }
    }
    peaks.sort_by(|a, b| b.0.total_cmp(&a.0));
    peaks
        .into_iter()
        .take(max_seeds)
        .map(|(_, i, j)| {
            let x = (x_lo + i as i64) as f64;
            let d = j as f64 - max_drift as f64;
            Segment::new([x, y0 as f64], [x + d, y1 as f64])
        })
        .collect()
}

/// The best partner edge of one gradient sign: mean response along its path, signed offsets
/// from the seed at the top and bottom rows, and the mean response over all offsets searched.
#[derive(Debug, Clone, Copy)]
struct Partner {
    response: f64,
    off_top: i64,
    off_bot: i64,
    background: f64,
}

/// The partner-edge search of [`fit_tower`]: the rows from the tower top down, the seed's x on
/// each row, and the offsets (px) a partner may lie at.
struct PartnerSearch<'a, F: Fn(i64) -> Option<f64>> {
    g: &'a GradPlane<'a>,
    rows: &'a [i64],
    x0: &'a F,
    wmin: i64,
    wmax: i64,
}

impl<F: Fn(i64) -> Option<f64>> PartnerSearch<'_, F> {
    /// The best path of gradient sign `sign` (±1) on either side of the seed; `None` without rows.
    #[inline(always)]
    fn best(&self, sign: f64) -> Option<Partner> {
        let (g, rows, wmin, wmax) = (self.g, self.rows, self.wmin, self.wmax);
        let reach = wmax + wmax / 4 + 2;
        // Per row, the response at every offset −reach..=reach from the seed. Gradients are
        // integers, so the sums below are exact in i32 (≤ rows · 2¹⁵) and equal to f64 sums.
        let span = (2 * reach + 1) as usize;
        let mut resp = vec![0i32; rows.len() * span];
        let isign = sign as i32;
        for (k, &y) in rows.iter().enumerate() {
            if let Some(x) = (self.x0)(y) {
                // Columns xi − reach ..= xi + reach, clipped to the image (outside stays 0).
                let first = x.round() as i64 - reach;
                let o_lo = (-first).max(0) as usize;
                let o_hi = ((g.width as i64 - first).max(0) as usize).min(span);
                if o_lo < o_hi {
                    let src = &g.row(y)[(first + o_lo as i64) as usize..];
                    resp[k * span + o_lo..k * span + o_hi]
                        .iter_mut()
                        .zip(src)
                        .for_each(|(r, &v)| *r = (isign * v as i32).max(0));
                }
            }
        }
        // Rows are consecutive: row k is at fraction k / last of the way down, and the offset
        // there is o_top + round(drift · k / last). Those steps are tabulated once per drift; for
        // one drift, every top offset is summed at once along the row (contiguous, vectorised).
        let last = rows.len() as i64 - 1;
        let max_drift = 2 + wmax / 4;
        let n_top = (wmax - wmin + 1) as usize;
        let n_drift = (2 * max_drift + 1) as usize;
        // sums[(side, drift, o_top)]: the summed response along that path.
        let mut sums = vec![0i32; 2 * n_drift * n_top];
        for (si, side) in [-1i64, 1].into_iter().enumerate() {
            for (di, d) in (-max_drift..=max_drift).enumerate() {
                let acc = &mut sums[(si * n_drift + di) * n_top..][..n_top];
                for (k, st) in round_steps(d, last).into_iter().enumerate() {
                    let row = &resp[k * span..(k + 1) * span];
                    if side > 0 {
                        // Index reach + o_top + st for o_top = wmin.. : ascending.
                        let lo = (reach + wmin + st) as usize;
                        acc.iter_mut()
                            .zip(&row[lo..lo + n_top])
                            .for_each(|(a, v)| *a += v);
                    } else {
                        // Index reach − o_top − st: descending with o_top.
                        let hi = (reach - wmin - st) as usize;
                        acc.iter_mut()
                            .zip(row[hi + 1 - n_top..=hi].iter().rev())
                            .for_each(|(a, v)| *a += v);
                    }
                }
            }
        }
        let mean = |si: usize, o_top: i64, o_bot: i64| {
            let di = (o_bot - o_top + max_drift) as usize;
            sums[(si * n_drift + di) * n_top + (o_top - wmin) as usize] as f64 / rows.len() as f64
        };
        let mut best: Option<(f64, usize, i64, i64)> = None;
        for si in 0..2 {
            for o_top in wmin..=wmax {
                let drift = 2 + o_top / 4;
                for o_bot in (o_top - drift).max(wmin)..=(o_top + drift).min(reach) {
                    let m = mean(si, o_top, o_bot);
                    if best.is_none_or(|(b, ..)| m > b) {
                        best = Some((m, si, o_top, o_bot));
                    }
                }
            }
        }
        let (response, si, o_top, o_bot) = best?;
        let side = if si == 0 { -1 } else { 1 };
        // The background: the mean response over all offsets (texture, other edges).
        let background = resp.iter().map(|&v| v as f64).sum::<f64>() / resp.len() as f64;
        Some(Partner {
            response,
            off_top: side * o_top,
            off_bot: side * o_bot,
            background,
        })
    }
}

/// Sub-pixel points of an edge of gradient sign `sign` within ±`EDGE_SEARCH_PX` of `predict(y)`
/// on each row, and the line `x = a + b·y` through them (least squares, outliers dropped once).
/// Rows where the edge is hidden (response below `EDGE_POINT_MIN_OF_TYPICAL` of its typical
/// response) give no point.
fn fit_edge(
    g: &GradPlane<'_>,
    rows: &[i64],
    predict: impl Fn(i64) -> Option<f64>,
    sign: f64,
) -> Option<Segment> {
    let mut peaks: Vec<(f64, P2)> = Vec::new();
    for &y in rows {
        let Some(x) = predict(y) else { continue };
        let xi = x.round() as i64;
        let (mut bx, mut bv) = (xi, f64::NEG_INFINITY);
        for d in -EDGE_SEARCH_PX..=EDGE_SEARCH_PX {
            let v = sign * g.at(xi + d, y);
            if v > bv {
                (bx, bv) = (xi + d, v);
            }
        }
        if bv <= 0.0 {
            continue;
        }
        // Parabola through the peak and its neighbours.
        let (l, r) = (sign * g.at(bx - 1, y), sign * g.at(bx + 1, y));
        let den = l - 2.0 * bv + r;
        let sub = if den < 0.0 {
            (0.5 * (l - r) / den).clamp(-0.5, 0.5)
        } else {
            0.0
        };
        peaks.push((bv, [bx as f64 + sub, y as f64]));
    }
    let mut vs: Vec<f64> = peaks.iter().map(|(v, _)| *v).collect();
    vs.sort_by(|a, b| a.total_cmp(b));
    let typical = *vs.get(vs.len() * 3 / 4)?;
    let pts: Vec<P2> = peaks
        .iter()
        .filter(|(v, _)| *v >= EDGE_POINT_MIN_OF_TYPICAL * typical)
        .map(|(_, q)| *q)
        .collect();
    let line = fit_x_of_y(&pts)?;
    let kept: Vec<P2> = pts
        .iter()
        .copied()
        .filter(|q| (line.0 + line.1 * q[1] - q[0]).abs() <= EDGE_OUTLIER_PX)
        .collect();
    let (a, b) = fit_x_of_y(&kept)?;
    let (y0, y1) = (kept.first()?[1], kept.last()?[1]);
    Some(Segment::new([a + b * y0, y0], [a + b * y1, y1]))
}

/// The edge `line` (gradient sign `sign`) moved `k` px toward `outward` (±1), `k` the largest
/// shift up to `max_k` at which the summed response along the shifted line, and at every smaller
/// shift, still reaches `min_frac` of the response along `line`. A tower lit from one side is a
/// shading ramp toward its dark limb; where the limb is as dark as the ground behind it there is
/// no edge at the silhouette, only the ramp's end, and the steepest part of the ramp (where the
/// edge fit lands) lies inside the tower: widths read 0.7× the truth in such renders. A sharp
/// edge's response halves within a pixel, so it stays in place. `min_frac` ≥ 1 or `max_k` 0:
/// `line` unchanged.
fn to_ramp_end(
    g: &GradPlane<'_>,
    rows: &[i64],
    line: Segment,
    sign: f64,
    outward: f64,
    min_frac: f64,
    max_k: i64,
) -> Segment {
    let along = |dx: f64| -> f64 {
        rows.iter()
            .filter_map(|&y| Some(sign * g.at((line.x_at_y(y as f64)? + dx).round() as i64, y)))
            .sum()
    };
    let base = along(0.0);
    if base <= 0.0 || min_frac >= 1.0 {
        return line;
    }
    let k = (1..=max_k)
        .take_while(|&k| along(outward * k as f64) >= min_frac * base)
        .last()
        .unwrap_or(0);
    let dx = outward * k as f64;
    Segment::new([line.a[0] + dx, line.a[1]], [line.b[0] + dx, line.b[1]])
}

/// `floor(delta · k / last + 0.5)` for k = 0 ..= last (all 0 when `last` is 0): the rounded
/// shift of row k along a line drifting by `delta` over `last` rows. Added to a positive start,
/// it rounds as `f64::round` does.
fn round_steps(delta: i64, last: i64) -> Vec<i64> {
    if last <= 0 {
        return vec![0; (last + 1).max(1) as usize];
    }
    (0..=last)
        .map(|k| (2 * delta * k + last).div_euclid(2 * last))
        .collect()
}

/// Least-squares `x = a + b·y`; `None` with fewer than `EDGE_MIN_POINTS` points or no spread in y.
fn fit_x_of_y(pts: &[P2]) -> Option<(f64, f64)> {
    if pts.len() < EDGE_MIN_POINTS {
        return None;
    }
    let n = pts.len() as f64;
    let my = pts.iter().map(|q| q[1]).sum::<f64>() / n;
    let mx = pts.iter().map(|q| q[0]).sum::<f64>() / n;
    let syy: f64 = pts.iter().map(|q| (q[1] - my).powi(2)).sum();
    if syy < 1e-9 {
        return None;
    }
    let sxy: f64 = pts.iter().map(|q| (q[1] - my) * (q[0] - mx)).sum();
    let b = sxy / syy;
    Some((mx - b * my, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// No limit on the band width beyond the parameters'.
    const ANY_WIDTH: (f64, f64) = (0.0, f64::INFINITY);

    /// A bright vertical band (the tower) on a dark background, slightly tilted, with one
    /// blade-like bright stripe crossing its right edge on some rows.
    fn image(w: usize, h: usize, left: f64, width: f64, tilt: f64) -> Vec<u8> {
        let mut img = vec![40u8; w * h];
        for y in 0..h {
            let l = left + tilt * y as f64;
            for x in 0..w {
                let xf = x as f64 + 0.5;
                let inside = xf > l && xf < l + width;
                let blade = (y > 60 && y < 90) && xf > l + width - 4.0 && xf < l + width + 30.0;
                if inside || blade {
                    img[y * w + x] = 200;
                }
            }
        }
        img
    }

    fn sobel_x(img: &[u8], w: usize, h: usize) -> Vec<i16> {
        let mut out = vec![0i16; w * h];
        for y in 1..h - 1 {
            for x in 1..w - 1 {
                let p = |dx: i64, dy: i64| {
                    img[(y as i64 + dy) as usize * w + (x as i64 + dx) as usize] as i32
                };
                let v = (p(1, -1) + 2 * p(1, 0) + p(1, 1)) - (p(-1, -1) + 2 * p(-1, 0) + p(-1, 1));
                out[y * w + x] = v as i16;
            }
        }
        out
    }

    /// The gradient plane over `gx`, `w`×`h`.
    fn plane(gx: &[i16], w: usize, h: usize) -> GradPlane<'_> {
        GradPlane {
            data: gx,
            width: w,
            height: h,
        }
    }

    #[test]
    fn finds_the_hidden_partner_edge_and_the_axis() {
        let (w, h) = (200, 160);
        let (left, width, tilt) = (80.3, 24.0, 0.02);
        let img = image(w, h, left, width, tilt);
        let gx = sobel_x(&img, w, h);
        let g = GradPlane {
            data: &gx,
            width: w,
            height: h,
        };
        // Hough found only the left edge, from row 40 to 100.
        let seed = Segment::new([left + tilt * 40.0, 40.0], [left + tilt * 100.0, 100.0]);
        let fit =
            fit_tower(&DefaultParams::default(), &g, &seed, ANY_WIDTH).expect("partner found");
        for y in [40.0, 100.0, 150.0] {
            let axis = fit.axis.x_at_y(y).unwrap();
            let truth = left + tilt * y + width / 2.0;
            // Pixel-centre sampling of the rendered band quantises each edge by up to 0.5 px.
            assert!(
                (axis - truth).abs() < 1.0,
                "axis at row {y}: {axis} vs {truth}"
            );
            assert!((fit.width_at(y).unwrap() - width).abs() < 1.0);
        }
        // The same from the right edge.
        let seed = Segment::new(
            [left + width + tilt * 100.0, 100.0],
            [left + width + tilt * 150.0, 150.0],
        );
        let fit2 = fit_tower(&DefaultParams::default(), &g, &seed, ANY_WIDTH)
            .expect("partner found from the right");
        assert!((fit2.axis.x_at_y(120.0).unwrap() - fit.axis.x_at_y(120.0).unwrap()).abs() < 0.6);
    }

    /// A vertical tower `width` px wide from `left` on uniform `ground`, its shade across the
    /// tower given by `shade(t)` for t = 0 (left limb) .. 1 (right limb).
    fn shaded_tower_image(
        w: usize,
        h: usize,
        left: f64,
        width: f64,
        ground: u8,
        shade: impl Fn(f64) -> f64,
    ) -> Vec<u8> {
        let mut img = vec![ground; w * h];
        for y in 0..h {
            for x in 0..w {
                let t = (x as f64 + 0.5 - left) / width;
                if (0.0..1.0).contains(&t) {
                    img[y * w + x] = shade(t).round() as u8;
                }
            }
        }
        img
    }

    /// A tower lit from the left on ground as dark as its shaded limb: a sharp lit edge, a
    /// bright face, then a steady brightness ramp (as in the renderer's side-lit towers) that
    /// meets the ground level at the silhouette, and no edge there.
    fn side_lit_image(w: usize, h: usize, left: f64, width: f64) -> Vec<u8> {
        let (ground, lit) = (60.0, 215.0);
        // Flat for the first 40 %, then linearly down to the ground level.
        shaded_tower_image(w, h, left, width, ground as u8, |t| {
            lit - (lit - ground) * ((t - 0.4) / 0.6).max(0.0)
        })
    }

    #[test]
    fn a_side_lit_tower_is_measured_to_the_end_of_its_shading_ramp() {
        let (w, h) = (200, 160);
        let (left, width) = (80.0, 14.0);
        let img = side_lit_image(w, h, left, width);
        let gx = sobel_x(&img, w, h);
        let g = plane(&gx, w, h);
        let seed = Segment::new([left, 40.0], [left, 150.0]);
        let ramp = fit_tower(&DefaultParams::default(), &g, &seed, ANY_WIDTH)
            .expect("tower with the ramp");
        let steepest = DefaultParams {
            tower_ramp_min_frac: 1.0,
            ..DefaultParams::default()
        };
        let fixed = fit_tower(&steepest, &g, &seed, ANY_WIDTH).expect("tower without");
        let (with, without) = (
            ramp.width_at(100.0).unwrap(),
            fixed.width_at(100.0).unwrap(),
        );
        assert!(
            without < width - 2.0,
            "the steepest point lies inside the tower: {without}"
        );
        assert!(
            with > without + 1.5 && (with - width).abs() < (without - width).abs(),
            "ramp end {with} vs steepest {without}, truth {width}"
        );
        assert!(with <= width + 1.0, "never beyond the silhouette: {with}");
    }

    /// Ground of a middle shade; a tower `width` px wide from `left`, dark at its left limb
    /// (darker than the ground) and shaded linearly up to a lit right limb brighter than the
    /// ground: both silhouette edges fall from left to right, only the ramp inside rises.
    fn limbs_around_ground_image(w: usize, h: usize, left: f64, width: f64) -> Vec<u8> {
        let (ground, dark, lit) = (120, 60.0, 170.0);
        // Dark for the first 30 %, then a ramp up to the lit limb.
        shaded_tower_image(w, h, left, width, ground, |t| {
            dark + (lit - dark) * ((t - 0.3) / 0.7).max(0.0)
        })
    }

    #[test]
    fn a_tower_darker_and_brighter_than_the_ground_is_measured_between_its_silhouette_edges() {
        let (w, h) = (200, 160);
        let (left, width) = (80.0, 24.0);
        let img = limbs_around_ground_image(w, h, left, width);
        let gx = sobel_x(&img, w, h);
        let g = GradPlane {
            data: &gx,
            width: w,
            height: h,
        };
        // From either limb the opposite-sign response is the ramp inside; the partner is the
        // other limb's edge of the same sign beyond it.
        for seed_x in [left, left + width] {
            let seed = Segment::new([seed_x, 40.0], [seed_x, 150.0]);
            let fit = fit_tower(&DefaultParams::default(), &g, &seed, ANY_WIDTH).expect("tower");
            let got = fit.width_at(100.0).unwrap();
            assert!(
                (got - width).abs() <= 1.5,
                "seed at {seed_x}: width {got}, truth {width}"
            );
            assert!((fit.axis.x_at_y(100.0).unwrap() - (left + width / 2.0)).abs() <= 1.0);
        }
        // Opposite signs only, from the lit limb: the band ends at the dark end of the ramp,
        // inside the tower.
        let opposite_only = DefaultParams {
            tower_same_sign_partner_min_ratio: 1000.0,
            ..DefaultParams::default()
        };
        let seed = Segment::new([left + width, 40.0], [left + width, 150.0]);
        let inside = fit_tower(&opposite_only, &g, &seed, ANY_WIDTH)
            .map_or(0.0, |f| f.width_at(100.0).unwrap());
        assert!(inside < width - 4.0, "opposite-sign band {inside}");
    }

    /// A tower in direct sun on ground of a middle shade: its lit half brighter than the ground,
    /// a sharp terminator, its dark half darker than the ground. Both silhouette edges rise from
    /// left to right; the terminator, no ramp, is the only falling edge.
    #[test]
    fn a_sunlit_towers_sharp_terminator_is_not_its_edge() {
        let (w, h) = (200, 160);
        let (left, width) = (80.0, 20.0);
        // The lit half a little brighter than the ground, the dark half much darker.
        let shade = |t: f64| if t < 0.55 { 170.0 } else { 40.0 };
        let img = shaded_tower_image(w, h, left, width, 120, shade);
        let gx = sobel_x(&img, w, h);
        let g = plane(&gx, w, h);
        let seed = Segment::new([left, 40.0], [left, 150.0]);
        let fit = fit_tower(&DefaultParams::default(), &g, &seed, ANY_WIDTH).expect("tower");
        let got = fit.width_at(100.0).unwrap();
        assert!((got - width).abs() <= 1.5, "width {got}, truth {width}");
        assert!((fit.axis.x_at_y(100.0).unwrap() - (left + width / 2.0)).abs() <= 1.0);
        // Opposite signs only: the lit half.
        let opposite_only = DefaultParams {
            tower_same_sign_partner_min_ratio: 1000.0,
            ..DefaultParams::default()
        };
        let half = fit_tower(&opposite_only, &g, &seed, ANY_WIDTH)
            .map_or(0.0, |f| f.width_at(100.0).unwrap());
        assert!(half < 0.65 * width, "opposite-sign band {half}");
    }

    #[test]
    fn a_tower_widening_by_its_taper_over_many_rows_is_a_tower() {
        // 12 px wide at the top row, 150 rows down (12.5 top widths: ~27 m of a 2.2 m tower),
        // widening by 0.03 m/m of taper to 12 · (1 + 0.03 · 150 / 12) = 16.5 px (ratio 1.38).
        let (w, h) = (200, 160);
        let (top, rows) = (9.0, 150.0);
        let half = |y: f64| (12.0 + 4.5 * ((y - top) / rows).max(0.0)) / 2.0;
        let img: Vec<u8> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f64 + 0.5, (i / w) as f64);
                if (x - 100.0).abs() < half(y) {
                    200
                } else {
                    40
                }
            })
            .collect();
        let gx = sobel_x(&img, w, h);
        let g = GradPlane {
            data: &gx,
            width: w,
            height: h,
        };
        let seed = Segment::new([100.0 - half(20.0), 20.0], [100.0 - half(150.0), 150.0]);
        let p = DefaultParams::default();
        let fit = fit_tower(&p, &g, &seed, ANY_WIDTH).expect("tapered tower");
        assert!((fit.width_at(100.0).unwrap() - 2.0 * half(100.0)).abs() < 1.0);
        // Without the taper model the same band widens too much for a tower.
        assert!(fit_tower(
            &DefaultParams {
                tower_taper: 0.0,
                ..p
            },
            &g,
            &seed,
            ANY_WIDTH
        )
        .is_none());
    }

    #[test]
    fn bands_changing_width_fast_are_no_tower() {
        // Left edge vertical at x = 80, right edge from x = 116 at the top to x = 96 at the bottom.
        let (w, h) = (200, 160);
        let img: Vec<u8> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f64 + 0.5, (i / w) as f64);
                if x > 80.0 && x < 116.0 - 20.0 * y / h as f64 {
                    200
                } else {
                    40
                }
            })
            .collect();
        let gx = sobel_x(&img, w, h);
        let g = GradPlane {
            data: &gx,
            width: w,
            height: h,
        };
        let seed = Segment::new([80.0, 20.0], [80.0, 120.0]);
        assert!(fit_tower(&DefaultParams::default(), &g, &seed, ANY_WIDTH).is_none());
        // The same band widening downward that fast is a tower edge beside a blade's edge.
        let flipped: Vec<u8> = (0..w * h)
            .map(|i| img[(h - 1 - i / w) * w + i % w])
            .collect();
        let gx = sobel_x(&flipped, w, h);
        let g = GradPlane {
            data: &gx,
            width: w,
            height: h,
        };
        assert!(fit_tower(&DefaultParams::default(), &g, &seed, ANY_WIDTH).is_none());
        // A band widening as a tapered tower does (30 → 33 px) is accepted.
        let tower: Vec<u8> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f64 + 0.5, (i / w) as f64);
                if x > 80.0 && x < 110.0 + 3.0 * y / h as f64 {
                    200
                } else {
                    40
                }
            })
            .collect();
        let gx = sobel_x(&tower, w, h);
        let g = GradPlane {
            data: &gx,
            width: w,
            height: h,
        };
        assert!(fit_tower(&DefaultParams::default(), &g, &seed, ANY_WIDTH).is_some());
    }

    #[test]
    fn a_lone_edge_is_no_tower() {
        // A step: bright right half, no opposite edge anywhere.
        let (w, h) = (200, 160);
        let img: Vec<u8> = (0..w * h)
            .map(|i| if i % w >= 90 { 200 } else { 40 })
            .collect();
        let gx = sobel_x(&img, w, h);
        let g = GradPlane {
            data: &gx,
            width: w,
            height: h,
        };
        let seed = Segment::new([90.0, 40.0], [90.0, 120.0]);
        assert!(fit_tower(&DefaultParams::default(), &g, &seed, ANY_WIDTH).is_none());
    }

    #[test]
    fn a_width_window_keeps_a_blade_beside_the_tower_out_of_the_band() {
        // Tower x 80..100 on a dark background; a blade pointing down in front of it covers
        // x 96..130 on every row. The blade's outer edge is the strongest edge around.
        let (w, h) = (200, 240); // widths up to 0.25 h = 60 px
        let scene = |tower: u8, blade: u8| -> Vec<u8> {
            (0..w * h)
                .map(|i| {
                    let x = (i % w) as f64 + 0.5;
                    if x > 96.0 && x < 130.0 {
                        blade
                    } else if x > 80.0 && x < 100.0 {
                        tower
                    } else {
                        0
                    }
                })
                .collect()
        };
        let seed = Segment::new([80.0, 20.0], [80.0, 120.0]);
        let p = DefaultParams::default();
        // A blade darker than the tower: the tower's visible right boundary (x 96) is an edge
        // of the opposite sign, but weaker than the blade's outer one.
        let gx = sobel_x(&scene(220, 150), w, h);
        let g = GradPlane {
            data: &gx,
            width: w,
            height: h,
        };
        let wide = fit_tower(&p, &g, &seed, ANY_WIDTH).expect("some band");
        assert!(
            (wide.width_at(60.0).unwrap() - 50.0).abs() < 1.5,
            "{:?}",
            wide.width_at(60.0)
        );
        // Expecting ~18 px (from a tracker's distance), the partner is the boundary at 96.
        let fit = fit_tower(&p, &g, &seed, (12.0, 27.0)).expect("tower band");
        assert!(
            (fit.width_at(60.0).unwrap() - 16.0).abs() < 1.5,
            "{:?}",
            fit.width_at(60.0)
        );
        // A blade brighter than the tower leaves no opposite edge at a tower-like width: no
        // tower rather than the wrong band.
        let gx = sobel_x(&scene(120, 200), w, h);
        let g = GradPlane {
            data: &gx,
            width: w,
            height: h,
        };
        assert!(fit_tower(&p, &g, &seed, ANY_WIDTH).is_some());
        assert!(fit_tower(&p, &g, &seed, (12.0, 27.0)).is_none());
    }

    #[test]
    fn scan_finds_a_jagged_tilted_edge_hough_would_miss() {
        // A bright tower from x = 100 at row 60 drifting to x = 104 at the bottom (3°), in
        // whole-pixel steps as a rasterised edge is, beside a dim uniform background.
        let (w, h) = (200, 160);
        let img: Vec<u8> = (0..w * h)
            .map(|i| {
                let (x, y): (usize, usize) = (i % w, i / w);
                let edge = 100 + (y.saturating_sub(60)) * 4 / 100;
                if x >= edge && x < edge + 20 {
                    180
                } else {
                    50
                }
            })
            .collect();
        let gx = sobel_x(&img, w, h);
        let g = GradPlane {
            data: &gx,
            width: w,
            height: h,
        };
        let seeds = scan_tower_edges(&g, 110.0, 60.0, 40.0, 8.0, 3.0, 4);
        assert!(seeds.len() >= 2, "{seeds:?}");
        // Both tower edges are found, with their drift.
        let near = |x_top: f64| {
            seeds
                .iter()
                .any(|s| (s.a[0] - x_top).abs() <= 1.0 && ((s.b[0] - s.a[0]) - 4.0).abs() <= 1.5)
        };
        assert!(near(100.0) && near(120.0), "{seeds:?}");
        // Nothing but texture: no seeds.
        let flat = vec![0i16; w * h];
        let g = GradPlane {
            data: &flat,
            width: w,
            height: h,
        };
        assert!(scan_tower_edges(&g, 110.0, 60.0, 40.0, 8.0, 3.0, 4).is_empty());
    }

    #[test]
    fn tabulated_steps_round_as_f64_round_from_a_positive_start() {
        for last in 0..40i64 {
            for delta in -20..=20i64 {
                let steps = round_steps(delta, last);
                assert_eq!(steps.len() as i64, last + 1);
                for (k, st) in steps.iter().enumerate() {
                    let exact = if last > 0 {
                        30.0 + delta as f64 * k as f64 / last as f64
                    } else {
                        30.0
                    };
                    assert_eq!(
                        30 + st,
                        exact.round() as i64,
                        "delta {delta} k {k} last {last}"
                    );
                }
            }
        }
    }
}
