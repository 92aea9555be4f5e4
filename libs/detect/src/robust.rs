//! The default pipeline: blade convergence first, tower as support.
//!
//! The thesis starts from the tower and searches blades around its top; that fails whenever the
//! tower edge is broken (nacelle shadow), hidden (close range, views from above against the
//! ground) or the horizon ends near the hub. Here the hub is found where long segments
//! *converge* (each ending near the point and pointing at it), and the tower only raises the
//! confidence:
//!
//! 1. Sobel gradients → Canny thresholds from a percentile of the gradient magnitude (contrast
//!    adaptive) → Canny on the same gradients (no second Sobel).
//! 2. HoughLinesP with lengths relative to the image height; collinear pieces merged.
//! 3. Roll: the hint, or the roll in ±`roll_search_deg` that makes most line length vertical.
//! 4. Horizon candidates (long, near-horizontal after roll) never count as blades.
//! 5. Proposals: intersections of pairs of long, clearly non-parallel segments lying just beyond
//!    an end of both (blades start at the hub; a line passing through is no blade) → grid vote
//!    → a few peaks.
//! 6. Each peak: supporting lines (near end close, line pointing at it) grouped into blades;
//!    a downward "blade" that is the tower is dropped; tower lines below are looked up;
//!    confidence from blade count, tower, and blade separations vs a (skewed) 120° rotor.
//! 7. Best peak; hub refined by least squares over its blade lines, each blade weighted equally.

use std::time::Instant;

use opencv::core::{self, Mat};
use opencv::imgproc;
use opencv::prelude::*;

use crate::geometry::{self, Segment, P2};
use crate::params::DefaultParams;
use crate::{hough_segments, us_since, DetectError, Found, Hints, LineKind, Scratch};

/// Number of bins of the gradient-magnitude histogram: the Sobel 3×3 L1 magnitude of 8-bit
/// images is at most 4·255·2 = 2040.
const GRAD_BINS: usize = 2048;
/// Roll search step (degrees) when no roll hint is given.
const ROLL_STEP_DEG: f64 = 1.0;
/// Lines within this of vertical (degrees, after a trial roll) count for the roll search.
const ROLL_VERTICAL_TOL_DEG: f64 = 1.5;
/// Number of vote peaks examined in detail.
const MAX_PEAKS: usize = 6;
/// A supporting line may point past the candidate by this angle (degrees) on top of the fixed
/// distance tolerance: the blade edges sit half a chord off the blade axis.
const SUPPORT_ANGLE_DEG: f64 = 12.0;

/// Run the default pipeline on the working image.
pub(crate) fn run(p: &DefaultParams, small: &Mat, s: &mut Scratch, hints: &Hints) -> Result<Found, DetectError> {
    let t = Instant::now();
    imgproc::spatial_gradient(small, &mut s.dx, &mut s.dy, 3, core::BORDER_DEFAULT)?;
    let high = adaptive_high(p, &s.dx, &s.dy, &mut s.hist)?;
    imgproc::canny_derivative(&s.dx, &s.dy, &mut s.edges, p.canny_low_ratio * high, high, false)?;
    let edge_count = core::count_non_zero(&s.edges)? as u32;
    let edges_us = us_since(t);

    let t = Instant::now();
    let h = small.rows() as f64;
    let w = small.cols() as f64;
    hough_segments(
        &s.edges,
        &mut s.lines,
        &mut s.segments,
        p.hough_rho_px,
        p.hough_theta_deg,
        (p.hough_threshold_frac * h).round() as i32,
        p.hough_min_length_frac * h,
        p.hough_max_gap_frac * h,
    )?;
    let hough_us = us_since(t);

    let t = Instant::now();
    let line_count = s.segments.len() as u32;
    let segs = merge_collinear(p, &s.segments, h);
    log::trace!("hough {} merged {} high {high} longest {:?}", s.segments.len(), segs.len(), segs.iter().take(5).collect::<Vec<_>>());
    let mut found = recognise(p, &segs, w, h, hints);
    found.line_count = line_count;
    found.edge_count = edge_count;
    found.edges_us = edges_us;
    found.hough_us = hough_us;
    found.geometry_us = us_since(t);
    Ok(found)
}

/// High Canny threshold: the `canny_high_percentile` of the L1 gradient magnitude, clamped.
fn adaptive_high(p: &DefaultParams, dx: &Mat, dy: &Mat, hist: &mut Vec<u32>) -> Result<f64, DetectError> {
    hist.clear();
    hist.resize(GRAD_BINS, 0);
    let mut n = 0u64;
    for r in 0..dx.rows() {
        let (rx, ry) = (dx.at_row::<i16>(r)?, dy.at_row::<i16>(r)?);
        for (a, b) in rx.iter().zip(ry) {
            let m = (a.unsigned_abs() as usize + b.unsigned_abs() as usize).min(GRAD_BINS - 1);
            hist[m] += 1;
        }
        n += rx.len() as u64;
    }
    let target = (p.canny_high_percentile * n as f64) as u64;
    let mut acc = 0u64;
    let mut level = GRAD_BINS - 1;
    for (i, c) in hist.iter().enumerate() {
        acc += *c as u64;
        if acc >= target {
            level = i;
            break;
        }
    }
    Ok((level as f64).clamp(p.canny_high_min, p.canny_high_max))
}

/// Greedy merge of collinear segments (longest first): a shorter segment that is nearly parallel,
/// on the same line and close along it extends the longer one. Returns at most `max_segments`.
pub(crate) fn merge_collinear(p: &DefaultParams, input: &[Segment], h: f64) -> Vec<Segment> {
    let mut segs: Vec<Segment> = input.to_vec();
    segs.sort_by(|a, b| b.length().total_cmp(&a.length()));
    let max_gap = p.merge_gap_frac * h;
    let mut out: Vec<Segment> = Vec::with_capacity(segs.len());
    'next: for s in segs {
        for m in out.iter_mut() {
            let da = (s.orientation_deg() - m.orientation_deg()).abs();
            let da = da.min(180.0 - da);
            if da > p.merge_angle_deg {
                continue;
            }
            if m.line_distance(s.a) > p.merge_offset_px || m.line_distance(s.b) > p.merge_offset_px {
                continue;
            }
            let len = m.length().max(1e-9);
            let (ta, tb) = (m.project_t(s.a), m.project_t(s.b));
            let (lo, hi) = (ta.min(tb), ta.max(tb));
            // Gap along the line between the two pieces (0 if they overlap).
            let gap = ((lo - 1.0).max(0.0) + (-hi).max(0.0)) * len;
            if gap > max_gap {
                continue;
            }
            let (nlo, nhi) = (lo.min(0.0), hi.max(1.0));
            let (a, b) = (m.a, m.b);
            let at = |t: f64| [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
            *m = Segment::new(at(nlo), at(nhi));
            continue 'next;
        }
        if out.len() < p.max_segments {
            out.push(s);
        }
    }
    out
}

/// The roll (degrees) in ±`roll_search_deg` that makes the most line length vertical.
pub(crate) fn search_roll(p: &DefaultParams, segs: &[Segment]) -> f64 {
    let steps = (p.roll_search_deg / ROLL_STEP_DEG).round() as i32;
    let mut best = (0.0, 0.0);
    for k in -steps..=steps {
        let r = k as f64 * ROLL_STEP_DEG;
        let score: f64 = segs
            .iter()
            .filter(|s| geometry::roll_compensated_tilt_deg(s, r).abs() <= ROLL_VERTICAL_TOL_DEG)
            .map(|s| s.length())
            .sum();
        // Prefer the smaller roll on ties (the vehicle is level most of the time).
        if score > best.1 + 1e-9 || (score == best.1 && r.abs() < f64::abs(best.0)) {
            best = (r, score);
        }
    }
    best.0
}

/// Horizon/ridge candidates: long and near horizontal after roll compensation.
pub(crate) fn is_horizon(p: &DefaultParams, s: &Segment, w: f64, roll_deg: f64) -> bool {
    s.length() >= p.horizon_min_length_frac * w
        && (90.0 - geometry::roll_compensated_tilt_deg(s, roll_deg).abs()) <= p.horizon_max_tilt_deg
}

/// Intersections of pairs of long, non-parallel segments that lie just beyond an end of both,
/// with weight `min(len)`.
pub(crate) fn proposals(p: &DefaultParams, segs: &[Segment], usable: &[bool], w: f64, h: f64) -> Vec<(P2, f64)> {
    let min_len = p.candidate_min_length_frac * h;
    let long: Vec<usize> = (0..segs.len()).filter(|&i| usable[i] && segs[i].length() >= min_len).collect();
    let near_end = |s: &Segment, x: P2| -> bool {
        let t = s.project_t(x);
        let len = s.length();
        let beyond = if t < 0.5 { -t } else { t - 1.0 };
        beyond >= -p.candidate_inside_frac && beyond * len <= p.candidate_end_reach_frac * len
    };
    let mut out = Vec::new();
    for (k, &i) in long.iter().enumerate() {
        for &j in &long[k + 1..] {
            let (a, b) = (&segs[i], &segs[j]);
            let d = (a.orientation_deg() - b.orientation_deg()).abs();
            if d.min(180.0 - d) < p.candidate_min_angle_deg {
                continue;
            }
            let Some(x) = geometry::line_intersection(a, b) else { continue };
            if x[0] < 0.0 || x[1] < 0.0 || x[0] > w - 1.0 || x[1] > h - 1.0 {
                continue;
            }
            if near_end(a, x) && near_end(b, x) {
                out.push((x, a.length().min(b.length())));
            }
        }
    }
    out
}

/// Peaks of the proposal density: grid vote with `cell` size, 3×3 sum, then the weighted mean
/// of the proposals around each local maximum.
pub(crate) fn peaks(props: &[(P2, f64)], w: f64, h: f64, cell: f64, max_peaks: usize) -> Vec<(P2, f64)> {
    if props.is_empty() {
        return Vec::new();
    }
    let (gw, gh) = ((w / cell).ceil() as usize + 1, (h / cell).ceil() as usize + 1);
    let mut grid = vec![0.0f64; gw * gh];
    for (x, wt) in props {
        let (gx, gy) = ((x[0] / cell) as usize, (x[1] / cell) as usize);
        grid[gy.min(gh - 1) * gw + gx.min(gw - 1)] += wt;
    }
    let mut sm = vec![0.0f64; gw * gh];
    for y in 0..gh {
        for x in 0..gw {
            let mut s = 0.0;
            for yy in y.saturating_sub(1)..(y + 2).min(gh) {
                for xx in x.saturating_sub(1)..(x + 2).min(gw) {
                    s += grid[yy * gw + xx];
                }
            }
            sm[y * gw + x] = s;
        }
    }
    let mut cells: Vec<(usize, f64)> = sm.iter().copied().enumerate().filter(|(_, v)| *v > 0.0).collect();
    cells.sort_by(|a, b| b.1.total_cmp(&a.1));
    let mut out: Vec<(P2, f64)> = Vec::new();
    for (c, v) in cells {
        if out.len() >= max_peaks {
            break;
        }
        let centre = [((c % gw) as f64 + 0.5) * cell, ((c / gw) as f64 + 0.5) * cell];
        // Weighted mean of the proposals in the 3x3 neighbourhood.
        let (mut sx, mut sy, mut sw) = (0.0, 0.0, 0.0);
        for (x, wt) in props {
            if (x[0] - centre[0]).abs() <= 1.5 * cell && (x[1] - centre[1]).abs() <= 1.5 * cell {
                sx += x[0] * wt;
                sy += x[1] * wt;
                sw += wt;
            }
        }
        if sw <= 0.0 {
            continue;
        }
        let m = [sx / sw, sy / sw];
        if out.iter().any(|(q, _)| geometry::dist(*q, m) < 2.0 * cell) {
            continue;
        }
        out.push((m, v));
    }
    out
}

/// A blade around a candidate: member lines, mean direction, total length.
#[derive(Debug, Clone)]
pub(crate) struct Blade {
    pub lines: Vec<usize>,
    pub angle_deg: f64,
    pub weight: f64,
}

/// Everything evaluated for one hub candidate.
#[derive(Debug, Clone, Default)]
struct Candidate {
    centre: P2,
    blades: Vec<Blade>,
    rejected: Vec<usize>,
    tower: Vec<usize>,
    confidence: f64,
    support: f64,
}

/// Lines supporting a hub at `c`: near end within reach, line pointing at `c`.
fn support_lines(p: &DefaultParams, segs: &[Segment], usable: &[bool], c: P2, h: f64) -> Vec<usize> {
    let reach = p.support_end_dist_frac * h;
    let tol0 = p.support_line_dist_frac * h;
    let tan = SUPPORT_ANGLE_DEG.to_radians().tan();
    (0..segs.len())
        .filter(|&i| {
            if !usable[i] {
                return false;
            }
            let s = &segs[i];
            let (_, d_end) = s.nearest_end(c);
            if d_end > reach {
                return false;
            }
            // The line must not pass through c: c lies beyond the nearer end.
            let t = s.project_t(c);
            if t > p.candidate_inside_frac && t < 1.0 - p.candidate_inside_frac {
                return false;
            }
            s.line_distance(c) <= tol0 + tan * d_end
        })
        .collect()
}

/// Group support lines by direction away from `c` into blades, merging groups closer than
/// `blade_min_separation_deg` (both edges of a wide blade near the root).
fn group_blades(p: &DefaultParams, segs: &[Segment], lines: &[usize], c: P2) -> Vec<Blade> {
    let angles: Vec<f64> = lines.iter().map(|&i| segs[i].angle_away_from(c)).collect();
    let mut blades: Vec<Blade> = geometry::group_by_angle(&angles, p.blade_group_tol_deg)
        .into_iter()
        .map(|g| {
            let a: Vec<f64> = g.iter().map(|&k| angles[k]).collect();
            let wts: Vec<f64> = g.iter().map(|&k| segs[lines[k]].length()).collect();
            Blade {
                lines: g.iter().map(|&k| lines[k]).collect(),
                angle_deg: geometry::circular_mean_deg(&a, Some(&wts)),
                weight: wts.iter().sum(),
            }
        })
        .collect();
    blades.sort_by(|a, b| b.weight.total_cmp(&a.weight));
    let mut merged: Vec<Blade> = Vec::new();
    for b in blades {
        if let Some(m) = merged.iter_mut().find(|m| geometry::ang_dist(m.angle_deg, b.angle_deg) < p.blade_min_separation_deg) {
            m.lines.extend(b.lines);
            m.weight += b.weight;
        } else {
            merged.push(b);
        }
    }
    merged
}

/// Tower lines for a hub at `c`: near vertical after roll, top end not far below `c`,
/// horizontally close, extending downward.
fn tower_lines(p: &DefaultParams, segs: &[Segment], c: P2, h: f64, roll_deg: f64) -> Vec<usize> {
    let max_below = p.tower_top_max_below_frac * h;
    let max_dx = p.tower_max_dx_frac * h;
    (0..segs.len())
        .filter(|&i| {
            let s = &segs[i];
            if geometry::roll_compensated_tilt_deg(s, roll_deg).abs() > p.tower_max_tilt_deg {
                return false;
            }
            let (top, bot) = if s.a[1] < s.b[1] { (s.a, s.b) } else { (s.b, s.a) };
            let below = top[1] - c[1];
            // The top may reach a little above the hub (the tower edge continues behind the
            // spinner in views from below) but must end near it and go down from there.
            below >= -p.tower_top_max_above_frac * h && below <= max_below && bot[1] > c[1] && (top[0] - c[0]).abs() <= max_dx
        })
        .collect()
}

/// The blade has lines on both sides of its axis ray from `c` (both edges of the band).
fn is_paired(segs: &[Segment], b: &Blade, c: P2) -> bool {
    let d = geometry::dir_from_up_cw(b.angle_deg);
    let (mut left, mut right) = (false, false);
    for &i in &b.lines {
        let m = segs[i].midpoint();
        let cross = d[0] * (m[1] - c[1]) - d[1] * (m[0] - c[0]);
        if cross > 0.0 {
            right = true;
        } else if cross < 0.0 {
            left = true;
        }
    }
    left && right
}

/// Score of how well blade directions fit a rotor: all pairwise separations of the (up to 3)
/// strongest blades within `blade_sep_tol_deg` of 120° (or of 240° for the reflex angle).
fn rotor_geometry_ok(p: &DefaultParams, blades: &[Blade]) -> bool {
    let n = blades.len().min(3);
    if n < 2 {
        return false;
    }
    for i in 0..n {
        for j in i + 1..n {
            let d = geometry::ang_dist(blades[i].angle_deg, blades[j].angle_deg);
            if (d - p.blade_target_deg).abs() > p.blade_sep_tol_deg {
                return false;
            }
        }
    }
    true
}

fn evaluate(p: &DefaultParams, segs: &[Segment], usable: &[bool], c: P2, h: f64, roll_deg: f64, hints: &Hints) -> Candidate {
    let lines = support_lines(p, segs, usable, c, h);
    let mut blades = group_blades(p, segs, &lines, c);
    let tower = tower_lines(p, segs, c, h, roll_deg);
    // A "blade" pointing straight down along the tower is the tower itself.
    let down = 180.0 - roll_deg;
    let mut rejected = Vec::new();
    blades.retain(|b| {
        let is_tower = geometry::ang_dist(b.angle_deg, down) <= p.tower_max_tilt_deg && b.lines.iter().all(|i| tower.contains(i));
        if is_tower {
            rejected.extend(b.lines.iter().copied());
        }
        !is_tower
    });
    // Weak blades (total length below one minimum Hough segment) are noise.
    let min_weight = p.candidate_min_length_frac * h;
    blades.retain(|b| {
        let keep = b.weight >= min_weight;
        if !keep {
            rejected.extend(b.lines.iter().copied());
        }
        keep
    });
    let nb = blades.len();
    let mut conf = match nb {
        0 | 1 => 0.0,
        2 => p.conf_two_blades,
        _ => p.conf_three_blades,
    };
    if nb >= 2 {
        if !tower.is_empty() {
            conf += p.conf_tower;
        }
        if rotor_geometry_ok(p, &blades) {
            conf += p.conf_geometry;
        }
        if blades.iter().filter(|b| is_paired(segs, b, c)).count() >= 2 {
            conf += p.conf_paired;
        }
        conf -= p.conf_extra_blade_penalty * nb.saturating_sub(3) as f64;
        if let Some(pred) = hints.predicted_hub_px {
            if geometry::dist(pred, c) <= p.prediction_radius_frac * h {
                conf += p.prediction_bonus;
            }
        }
    }
    let support = blades.iter().take(3).map(|b| b.weight).sum();
    Candidate { centre: c, blades, rejected, tower, confidence: conf.min(1.0), support }
}

/// Least-squares point closest to all lines, each blade's lines together weighing 1.
fn refine(segs: &[Segment], blades: &[Blade], centre: P2) -> Option<P2> {
    let (mut a11, mut a12, mut a22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for bl in blades.iter().take(3) {
        // Each side of the blade (each edge) weighs half, so a blade seen with both edges pulls
        // toward its axis, not toward its longer edge.
        let d = geometry::dir_from_up_cw(bl.angle_deg);
        let side = |s: &Segment| {
            let m = s.midpoint();
            d[0] * (m[1] - centre[1]) - d[1] * (m[0] - centre[0]) > 0.0
        };
        let tot = |right: bool| bl.lines.iter().filter(|&&i| side(&segs[i]) == right).map(|&i| segs[i].length()).sum::<f64>();
        let (tr, tl) = (tot(true), tot(false));
        let sides = (tr > 0.0) as u32 + (tl > 0.0) as u32;
        for &i in &bl.lines {
            let s = &segs[i];
            let len = s.length().max(1e-9);
            let n = [-(s.b[1] - s.a[1]) / len, (s.b[0] - s.a[0]) / len];
            let w = len / if side(s) { tr } else { tl }.max(1e-9) / sides.max(1) as f64;
            let c = n[0] * s.a[0] + n[1] * s.a[1];
            a11 += w * n[0] * n[0];
            a12 += w * n[0] * n[1];
            a22 += w * n[1] * n[1];
            b1 += w * n[0] * c;
            b2 += w * n[1] * c;
        }
    }
    let det = a11 * a22 - a12 * a12;
    if det.abs() < 1e-9 {
        return None;
    }
    Some([(a22 * b1 - a12 * b2) / det, (a11 * b2 - a12 * b1) / det])
}

/// Steps after the Hough transform, on plain data (working px).
pub(crate) fn recognise(p: &DefaultParams, segs: &[Segment], w: f64, h: f64, hints: &Hints) -> Found {
    let roll_deg = match hints.roll_rad {
        Some(r) => r.to_degrees(),
        None => search_roll(p, segs),
    };
    let mut found = Found { roll_used_deg: roll_deg, line_count: segs.len() as u32, ..Found::default() };
    let mut kinds = vec![LineKind::Other; segs.len()];
    let usable: Vec<bool> = segs.iter().map(|s| !is_horizon(p, s, w, roll_deg)).collect();
    for (i, u) in usable.iter().enumerate() {
        if !u {
            kinds[i] = LineKind::Rejected;
        }
    }
    let props = proposals(p, segs, &usable, w, h);
    let mut best: Option<Candidate> = None;
    let mut centres: Vec<P2> = peaks(&props, w, h, p.cluster_radius_frac * h, MAX_PEAKS).into_iter().map(|(c, _)| c).collect();
    if let Some(pred) = hints.predicted_hub_px {
        centres.push(pred);
    }
    for c in centres {
        let mut cand = evaluate(p, segs, &usable, c, h, roll_deg, hints);
        if cand.blades.len() >= 2 {
            if let Some(r) = refine(segs, &cand.blades, c) {
                if geometry::dist(r, c) <= p.cluster_radius_frac * h * 2.0 {
                    // Re-evaluate at the refined point so blades and tower match the output.
                    let again = evaluate(p, segs, &usable, r, h, roll_deg, hints);
                    if again.confidence >= cand.confidence {
                        cand = again;
                    }
                }
            }
        }
        if log::log_enabled!(log::Level::Trace) {
            log::trace!(
                "candidate {:?} conf {:.2} support {:.0} blades {:?} tower {}",
                cand.centre,
                cand.confidence,
                cand.support,
                cand.blades.iter().map(|b| (b.angle_deg.round(), b.weight.round(), b.lines.len())).collect::<Vec<_>>(),
                cand.tower.len()
            );
        }
        let better = match &best {
            None => true,
            Some(b) => cand.confidence > b.confidence + 1e-9 || (cand.confidence >= b.confidence - 1e-9 && cand.support > b.support),
        };
        if better {
            best = Some(cand);
        }
    }
    if let Some(b) = best {
        for &i in &b.rejected {
            kinds[i] = LineKind::Rejected;
        }
        for &i in &b.tower {
            kinds[i] = LineKind::Tower;
        }
        for bl in &b.blades {
            for &i in &bl.lines {
                kinds[i] = LineKind::Blade;
            }
        }
        found.blade_angles = b.blades.iter().map(|x| x.angle_deg).collect();
        found.confidence = b.confidence;
        found.detected = b.confidence >= p.min_confidence;
        found.hub = b.centre;
        found.search_circle = Some([b.centre[0], b.centre[1], p.support_end_dist_frac * h]);
        if !b.tower.is_empty() {
            let top = b
                .tower
                .iter()
                .flat_map(|&i| [segs[i].a, segs[i].b])
                .min_by(|x, y| x[1].total_cmp(&y[1]))
                .unwrap_or(b.centre);
            let axis = crate::thesis::tower_axis(segs, &b.tower);
            found.tower_top = Some(axis.and_then(|a| a.x_at_y(top[1])).map_or(top, |x| [x, top[1]]));
            found.tower_axis = axis;
            let row = top[1] + p.tower_width_below_top_frac * h;
            found.tower_width = crate::thesis::tower_width_at(segs, &b.tower, row, 1.0).map(|wd| (wd, row));
        }
    }
    found.lines = segs.iter().copied().zip(kinds).collect();
    found
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::dir_from_up_cw;

    fn ray(from: P2, angle: f64, start: f64, len: f64) -> Segment {
        let d = dir_from_up_cw(angle);
        Segment::new(
            [from[0] + d[0] * start, from[1] + d[1] * start],
            [from[0] + d[0] * (start + len), from[1] + d[1] * (start + len)],
        )
    }

    fn rotor(hub: P2, rot: f64) -> Vec<Segment> {
        let mut v = vec![Segment::new([hub[0] - 3.0, 269.0], [hub[0] - 2.0, hub[1] + 8.0]), Segment::new([hub[0] + 3.0, 269.0], [hub[0] + 2.0, hub[1] + 8.0])];
        for a in [rot, rot + 120.0, rot + 240.0] {
            v.push(ray(hub, a - 3.0, 6.0, 70.0));
            v.push(ray(hub, a + 3.0, 6.0, 70.0));
        }
        v
    }

    #[test]
    fn finds_hub_with_horizon_through_it() {
        let p = DefaultParams::default();
        let hub = [200.0, 120.0];
        let mut segs = rotor(hub, 20.0);
        // Horizon split by the tower: two long pieces ending at the tower.
        segs.push(Segment::new([0.0, 125.0], [196.0, 125.0]));
        segs.push(Segment::new([204.0, 125.0], [479.0, 125.0]));
        let f = recognise(&p, &segs, 480.0, 270.0, &Hints { roll_rad: Some(0.0), predicted_hub_px: None });
        assert!(f.detected, "{f:?}");
        assert!(geometry::dist(f.hub, hub) < 3.0, "{:?}", f.hub);
        assert_eq!(f.blade_angles.len(), 3);
    }

    #[test]
    fn roll_search_finds_tilted_tower() {
        let p = DefaultParams::default();
        let d = dir_from_up_cw(-6.0);
        let segs = vec![
            Segment::new([100.0, 260.0], [100.0 + 150.0 * d[0], 260.0 + 150.0 * d[1]]),
            Segment::new([110.0, 260.0], [110.0 + 150.0 * d[0], 260.0 + 150.0 * d[1]]),
            Segment::new([0.0, 50.0], [40.0, 10.0]),
        ];
        assert!((search_roll(&p, &segs) - 6.0).abs() <= 1.0);
    }

    #[test]
    fn collinear_pieces_merge() {
        let p = DefaultParams::default();
        let segs = [Segment::new([100.0, 200.0], [100.0, 150.0]), Segment::new([100.5, 145.0], [101.0, 90.0]), Segment::new([0.0, 0.0], [50.0, 0.0])];
        let m = merge_collinear(&p, &segs, 270.0);
        assert_eq!(m.len(), 2);
        assert!(m[0].length() > 105.0, "{m:?}");
    }

    #[test]
    fn parallel_lines_alone_are_no_turbine() {
        let p = DefaultParams::default();
        // Power-line like: several long near-parallel sagging wires.
        let segs: Vec<Segment> = (0..5).map(|k| Segment::new([0.0, 50.0 + 10.0 * k as f64], [479.0, 60.0 + 12.0 * k as f64])).collect();
        let f = recognise(&p, &segs, 480.0, 270.0, &Hints::default());
        assert!(!f.detected);
    }
}
