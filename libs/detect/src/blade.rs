//! A blade's axis from one edge: its partner edge found in the gradient image.
//!
//! The hub is where the blade *axes* meet. Hough often finds only one edge of a blade (the other
//! has little contrast against the sky or ground behind it, or is too short near the root), and
//! an edge lies half a chord off the axis: at 25–45 m the crossing of such edges sits 3–6 % of
//! the image height below or beside the spinner, which is a miss. A blade is a band of nearly
//! uniform shade, so its other edge has the opposite gradient sign (across the blade) at an
//! offset that changes slowly along it. Sampling that signed response across the edge at a few
//! points along it, on either side, finds the partner; the axis is the midline.

use crate::geometry::{dist, Segment, P2};
use crate::tower::GradPlane;

/// How the partner edge of a blade is searched.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PartnerSearch {
    /// Narrowest band, px: closer responses are the known edge's own spread (Sobel 3×3).
    pub min_width: f64,
    /// Widest band, px.
    pub max_width: f64,
    /// Points sampled along the edge.
    pub samples: usize,
    /// The partner must be found at this fraction of the usable samples.
    pub min_found_frac: f64,
    /// A partner response must reach this fraction of the edge's own response.
    pub min_response_ratio: f64,
    /// Largest RMS deviation of the partner offsets from a straight line, px.
    pub max_rms_px: f64,
    /// Largest change of band width per px along the blade (taper).
    pub max_taper: f64,
}

/// The Sobel gradients of the working image.
pub(crate) struct Gradients<'a> {
    /// Horizontal gradient.
    pub x: GradPlane<'a>,
    /// Vertical gradient.
    pub y: GradPlane<'a>,
}

impl Gradients<'_> {
    /// Gradient at the pixel nearest `q`, projected on the unit vector `n`.
    fn along(&self, q: P2, n: P2) -> f64 {
        let (x, y) = (q[0].round() as i64, q[1].round() as i64);
        self.x.at(x, y) * n[0] + self.y.at(x, y) * n[1]
    }
}

/// Least-squares line `o = alpha + beta·s` through `(s, o)` points with its RMS residual.
fn fit_line(pts: &[(f64, f64)]) -> Option<(f64, f64, f64)> {
    let n = pts.len() as f64;
    if pts.len() < 2 {
        return None;
    }
    let (ms, mo) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sss: f64 = pts.iter().map(|p| (p.0 - ms).powi(2)).sum();
    let sso: f64 = pts.iter().map(|p| (p.0 - ms) * (p.1 - mo)).sum();
    if sss < 1e-9 {
        return None;
    }
    let beta = sso / sss;
    let alpha = mo - beta * ms;
    let rms = (pts
        .iter()
        .map(|p| (p.1 - alpha - beta * p.0).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    Some((alpha, beta, rms))
}

/// The axis of the blade whose one edge is `edge`, oriented from the end nearer the hub
/// candidate `c` outward; `None` when no consistent partner edge is found on either side.
pub(crate) fn partner_axis(
    g: &Gradients<'_>,
    edge: &Segment,
    c: P2,
    ps: &PartnerSearch,
) -> Option<Segment> {
    let (a, b) = if dist(edge.a, c) <= dist(edge.b, c) {
        (edge.a, edge.b)
    } else {
        (edge.b, edge.a)
    };
    let len = dist(a, b);
    if len < 1.0 || ps.samples < 2 {
        return None;
    }
    let d = [(b[0] - a[0]) / len, (b[1] - a[1]) / len];
    let n = [-d[1], d[0]];
    let at = |s: f64, o: f64| [a[0] + s * d[0] + o * n[0], a[1] + s * d[1] + o * n[1]];
    // The edge's own response at each sample (strongest within a pixel of the line), and its
    // sign across the line, taken from all samples together.
    let samples: Vec<(f64, f64)> = (0..ps.samples)
        .map(|k| {
            let s = (k as f64 + 0.5) / ps.samples as f64 * len;
            let e = [-1.0, 0.0, 1.0]
                .iter()
                .map(|&o| g.along(at(s, o), n))
                .max_by(|x, y| x.abs().total_cmp(&y.abs()))
                .unwrap_or(0.0);
            (s, e)
        })
        .collect();
    let sign = samples.iter().map(|x| x.1).sum::<f64>().signum();
    let usable: Vec<(f64, f64)> = samples
        .into_iter()
        .filter(|x| x.1 * sign > 0.0)
        .map(|(s, e)| (s, e.abs()))
        .collect();
    let need = ((ps.min_found_frac * ps.samples as f64).ceil() as usize).max(3);
    if usable.len() < need {
        return None;
    }
    let mut best: Option<(usize, f64, f64, f64, f64)> = None; // found, rms, side, alpha, beta
    for side in [1.0, -1.0] {
        let mut found = Vec::with_capacity(usable.len());
        for &(s, e) in &usable {
            // The nearest local maximum of the opposite-signed response above the threshold.
            let thr = ps.min_response_ratio * e;
            let resp = |o: f64| -sign * g.along(at(s, side * o), n);
            let mut o = ps.min_width.ceil();
            while o <= ps.max_width {
                let v = resp(o);
                if v >= thr {
                    let (mut peak_o, mut peak_v) = (o, v);
                    while peak_o + 1.0 <= ps.max_width && resp(peak_o + 1.0) > peak_v {
                        peak_o += 1.0;
                        peak_v = resp(peak_o);
                    }
                    found.push((s, peak_o));
                    break;
                }
                o += 1.0;
            }
        }
        if found.len() < need {
            log::trace!(
                "partner of {edge:?} on side {side}: found at {} of {} samples",
                found.len(),
                usable.len()
            );
            continue;
        }
        let Some((mut alpha, mut beta, mut rms)) = fit_line(&found) else {
            continue;
        };
        if rms > ps.max_rms_px {
            // One sample may have caught a crossing line: drop the worst and fit again.
            if let Some(worst) = (0..found.len()).max_by(|&i, &j| {
                let r = |k: usize| (found[k].1 - alpha - beta * found[k].0).abs();
                r(i).total_cmp(&r(j))
            }) {
                found.remove(worst);
            }
            if found.len() < need {
                continue;
            }
            let Some(f) = fit_line(&found) else { continue };
            (alpha, beta, rms) = f;
        }
        let (w0, w1) = (alpha, alpha + beta * len);
        if rms > ps.max_rms_px
            || beta.abs() > ps.max_taper
            || w0.min(w1) < ps.min_width - 1.0
            || w0.max(w1) > ps.max_width + 1.0
        {
            log::trace!("partner of {edge:?} on side {side}: widths {w0:.1}..{w1:.1} px, taper {beta:.3}, rms {rms:.2} px at {found:?}: refused");
            continue;
        }
        let better = match best {
            None => true,
            Some((f, r, ..)) => found.len() > f || (found.len() == f && rms < r),
        };
        if better {
            best = Some((found.len(), rms, side, alpha, beta));
        }
    }
    let (_, _, side, alpha, beta) = best?;
    let half = |o: f64| side * o / 2.0;
    Some(Segment::new(
        at(0.0, half(alpha)),
        at(len, half(alpha + beta * len)),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sobel pair over an image drawn by `shade(x, y)`.
    fn gradients(w: usize, h: usize, shade: impl Fn(f64, f64) -> f64) -> (Vec<i16>, Vec<i16>) {
        let img: Vec<f64> = (0..w * h)
            .map(|i| shade((i % w) as f64, (i / w) as f64))
            .collect();
        let px = |x: usize, y: usize| img[y.clamp(0, h - 1) * w + x.clamp(0, w - 1)];
        let (mut gx, mut gy) = (vec![0i16; w * h], vec![0i16; w * h]);
        for y in 1..h - 1 {
            for x in 1..w - 1 {
                let sx = px(x + 1, y - 1) + 2.0 * px(x + 1, y) + px(x + 1, y + 1)
                    - px(x - 1, y - 1)
                    - 2.0 * px(x - 1, y)
                    - px(x - 1, y + 1);
                let sy = px(x - 1, y + 1) + 2.0 * px(x, y + 1) + px(x + 1, y + 1)
                    - px(x - 1, y - 1)
                    - 2.0 * px(x, y - 1)
                    - px(x + 1, y - 1);
                gx[y * w + x] = sx as i16;
                gy[y * w + x] = sy as i16;
            }
        }
        (gx, gy)
    }

    fn search() -> PartnerSearch {
        PartnerSearch {
            min_width: 2.0,
            max_width: 30.0,
            samples: 9,
            min_found_frac: 0.6,
            min_response_ratio: 0.3,
            max_rms_px: 1.5,
            max_taper: 0.15,
        }
    }

    /// A tapering band (blade) from `hub` along `angle` (radians from +x), width `w0` at the hub
    /// and `w1` at length `len`, shade 80 on 200.
    fn band(hub: P2, angle: f64, len: f64, w0: f64, w1: f64) -> impl Fn(f64, f64) -> f64 {
        let d = [angle.cos(), angle.sin()];
        move |x, y| {
            let (rx, ry) = (x - hub[0], y - hub[1]);
            let s = rx * d[0] + ry * d[1];
            let o = -rx * d[1] + ry * d[0];
            let half = (w0 + (w1 - w0) * s / len) / 2.0;
            if s >= 0.0 && s <= len && o.abs() <= half {
                80.0
            } else {
                200.0
            }
        }
    }

    #[test]
    fn one_edge_and_its_partner_give_the_blade_axis() {
        let (w, h) = (200, 160);
        let hub = [40.0, 40.0];
        let angle = 30f64.to_radians();
        let (gx, gy) = gradients(w, h, band(hub, angle, 150.0, 16.0, 8.0));
        let g = Gradients {
            x: GradPlane {
                data: &gx,
                width: w,
                height: h,
            },
            y: GradPlane {
                data: &gy,
                width: w,
                height: h,
            },
        };
        let d = [angle.cos(), angle.sin()];
        let n = [-d[1], d[0]];
        // The edge on the +n side, from 20 to 120 px out, as Hough would give it.
        let edge_at = |s: f64| {
            let half = (16.0 + (8.0 - 16.0) * s / 150.0) / 2.0;
            [
                hub[0] + s * d[0] + half * n[0],
                hub[1] + s * d[1] + half * n[1],
            ]
        };
        let edge = Segment::new(edge_at(120.0), edge_at(20.0));
        let axis = partner_axis(&g, &edge, hub, &search()).expect("partner edge");
        // The axis runs through the hub: both of its ends lie on the band's centre line.
        for p in [axis.a, axis.b] {
            let o = -(p[0] - hub[0]) * d[1] + (p[1] - hub[1]) * d[0];
            assert!(
                o.abs() < 1.0,
                "axis end {p:?} is {o:.2} px off the centre line"
            );
        }
        // Oriented from the hub outward.
        assert!(dist(axis.a, hub) < dist(axis.b, hub));
    }

    #[test]
    fn a_lone_step_edge_has_no_partner() {
        let (w, h) = (200, 160);
        // Dark below the line y = 0.3 x + 50, bright above: an edge with nothing opposite.
        let (gx, gy) = gradients(w, h, |x, y| if y > 0.3 * x + 50.0 { 80.0 } else { 200.0 });
        let g = Gradients {
            x: GradPlane {
                data: &gx,
                width: w,
                height: h,
            },
            y: GradPlane {
                data: &gy,
                width: w,
                height: h,
            },
        };
        let edge = Segment::new([20.0, 56.0], [180.0, 104.0]);
        assert!(partner_axis(&g, &edge, [0.0, 50.0], &search()).is_none());
    }
}
