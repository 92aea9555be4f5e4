//! Step 5, proposals and voting: where pairs of long, clearly non-parallel lines (and of band
//! axes) cross just beyond an end of both, a grid vote, and its few peaks as hub candidates,
//! joined by the tracker's prediction and the learned heatmap's peak.

use crate::geometry::{self, Segment, P2};
use crate::heat::Heatmap;

use super::bands::{axis_points_at, BandAxis};
use super::context::{FrameCtx, SceneCtx};

/// Number of vote peaks examined in detail.
const MAX_PEAKS: usize = 6;

/// The hub candidates of a scene (step 5): the peaks of the vote over the line and band-axis
/// crossings, the tracker's predicted hub, and the learned `heat`map's peak where nothing was
/// proposed near it.
pub(super) fn centres(sc: &SceneCtx<'_>, heat: Option<&Heatmap>) -> Vec<P2> {
    let f = sc.frame();
    let FrameCtx { p, w, h, hints, .. } = f;
    let mut props = proposals(&f, sc.segs, sc.usable);
    let axis_props = axis_proposals(&f, sc.axes);
    log::trace!(
        "axes {:?} axis proposals {:?}",
        sc.axes
            .iter()
            .map(|a| (a.axis, a.width))
            .collect::<Vec<_>>(),
        axis_props
    );
    props.extend(axis_props);
    let mut centres: Vec<P2> = peaks(&props, w, h, p.cluster_radius_frac * h, MAX_PEAKS)
        .into_iter()
        .map(|(c, _)| c)
        .collect();
    if let Some(pred) = hints.predicted_hub_px {
        centres.push(pred);
    }
    // The heatmap's peak, where no line crossing or band axis proposed anything near it.
    let heat_reach = heat_reach_px(&f, heat);
    if let Some((peak, prob)) = heat.and_then(|m| m.peak()) {
        let c = [peak[0] * w, peak[1] * h];
        if prob >= p.hub_heat_candidate_min
            && !centres.iter().any(|q| geometry::dist(*q, c) <= heat_reach)
        {
            log::trace!("heatmap peak {c:?} ({prob:.2}) is a candidate");
            centres.push(c);
        }
    }
    centres
}

/// Intersections of pairs of long, non-parallel segments that lie just beyond an end of both,
/// with weight `min(len)`.
pub(super) fn proposals(f: &FrameCtx<'_>, segs: &[Segment], usable: &[bool]) -> Vec<(P2, f64)> {
    let FrameCtx { p, w, h, .. } = *f;
    let min_len = p.candidate_min_length_frac * h;
    let long: Vec<usize> = (0..segs.len())
        .filter(|&i| usable[i] && segs[i].length() >= min_len)
        .collect();
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
            let Some(x) = geometry::line_intersection(a, b) else {
                continue;
            };
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

/// Intersections of pairs of band axes that lie beyond the nearer end of both within their
/// reach, weighted `axis_proposal_weight · min(axis length)`.
pub(super) fn axis_proposals(f: &FrameCtx<'_>, axes: &[BandAxis]) -> Vec<(P2, f64)> {
    let FrameCtx { p, w, h, .. } = *f;
    let mut out = Vec::new();
    for (k, a) in axes.iter().enumerate() {
        for b in &axes[k + 1..] {
            let d = (a.axis.orientation_deg() - b.axis.orientation_deg()).abs();
            if d.min(180.0 - d) < p.candidate_min_angle_deg {
                continue;
            }
            let Some(x) = geometry::line_intersection(&a.axis, &b.axis) else {
                continue;
            };
            if x[0] < 0.0 || x[1] < 0.0 || x[0] > w - 1.0 || x[1] > h - 1.0 {
                continue;
            }
            if axis_points_at(p, a, x, h, 0.0) && axis_points_at(p, b, x, h, 0.0) {
                out.push((
                    x,
                    p.axis_proposal_weight * a.axis.length().min(b.axis.length()),
                ));
            }
        }
    }
    out
}

/// Peaks of the proposal density: grid vote with `cell` size, 3×3 sum, then the weighted mean
/// of the proposals around each local maximum.
pub(super) fn peaks(
    props: &[(P2, f64)],
    w: f64,
    h: f64,
    cell: f64,
    max_peaks: usize,
) -> Vec<(P2, f64)> {
    if props.is_empty() {
        return Vec::new();
    }
    let (gw, gh) = (
        (w / cell).ceil() as usize + 1,
        (h / cell).ceil() as usize + 1,
    );
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
    let mut cells: Vec<(usize, f64)> = sm
        .iter()
        .copied()
        .enumerate()
        .filter(|(_, v)| *v > 0.0)
        .collect();
    cells.sort_by(|a, b| b.1.total_cmp(&a.1));
    let mut out: Vec<(P2, f64)> = Vec::new();
    for (c, v) in cells {
        if out.len() >= max_peaks {
            break;
        }
        let centre = [
            ((c % gw) as f64 + 0.5) * cell,
            ((c / gw) as f64 + 0.5) * cell,
        ];
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

/// How near a candidate must lie to the heatmap's peak to stand for it, working px: the
/// `hub_heat_radius_cells` neighbourhood in the larger of the cell's two sides.
fn heat_reach_px(f: &FrameCtx<'_>, heat: Option<&Heatmap>) -> f64 {
    let FrameCtx { p, w, h, .. } = *f;
    heat.filter(|m| m.cols > 0 && m.rows > 0).map_or(0.0, |m| {
        p.hub_heat_radius_cells * (w / m.cols as f64).max(h / m.rows as f64)
    })
}
