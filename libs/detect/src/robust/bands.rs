//! Step 8, edge pairing: the two edges of a blade (nearly parallel, overlapping, a slender band)
//! give its axis, the internal bisector. Axes point at the hub from farther out than single
//! edges (blades start at the spinner rim), so they propose and support candidates too.

use crate::geometry::{self, Segment, P2};
use crate::params::DefaultParams;

use super::context::FrameCtx;

/// A band found from two paired edges: a blade (or the tower) with its axis.
#[derive(Debug, Clone, Copy)]
pub(super) struct BandAxis {
    /// The axis (internal bisector of the edges), spanning both edges.
    pub axis: Segment,
    /// Indices of the two edges.
    pub edges: [usize; 2],
    /// Band width at `axis.a` and at `axis.b`, px.
    pub width: [f64; 2],
}

impl BandAxis {
    /// Band width at the axis end nearer to `c`, and that end's distance to `c`.
    fn near_end(&self, c: P2) -> (f64, f64) {
        let (da, db) = (
            geometry::dist(self.axis.a, c),
            geometry::dist(self.axis.b, c),
        );
        if da <= db {
            (self.width[0], da)
        } else {
            (self.width[1], db)
        }
    }

    /// How far short of `c` the axis may end: the blade starts at the spinner rim (radius
    /// `spinner_r` when a spinner was found, else judged from the band width).
    fn reach(&self, p: &DefaultParams, c: P2, h: f64, spinner_r: f64) -> f64 {
        let (w, _) = self.near_end(c);
        (p.support_end_dist_frac * h)
            .max(p.axis_reach_widths * w)
            .max(p.spinner_reach_radii * spinner_r)
    }
}

/// Pair the two edges of each blade (and of the tower): nearly parallel, overlapping along their
/// direction, a slender band between them. Greedy by overlap, each edge in at most one pair.
pub(super) fn pair_edges(f: &FrameCtx<'_>, segs: &[Segment], usable: &[bool]) -> Vec<BandAxis> {
    let FrameCtx { p, h, .. } = *f;
    let min_len = p.pair_min_length_frac * h;
    let max_w = p.pair_max_width_frac * h;
    let idx: Vec<usize> = (0..segs.len())
        .filter(|&i| usable[i] && segs[i].length() >= min_len)
        .collect();
    let mut cands: Vec<(f64, BandAxis)> = Vec::new();
    for (k, &i) in idx.iter().enumerate() {
        for &j in &idx[k + 1..] {
            let (s, t) = (&segs[i], &segs[j]);
            let d = (s.orientation_deg() - t.orientation_deg()).abs();
            if d.min(180.0 - d) > p.pair_max_angle_deg {
                continue;
            }
            let overlap = geometry::projected_overlap(s, t).min(geometry::projected_overlap(t, s));
            if overlap < p.pair_min_overlap_frac * s.length().min(t.length()) {
                continue;
            }
            let Some(axis) = geometry::band_axis(s, t) else {
                continue;
            };
            let width = [
                geometry::band_width_at(s, t, axis.a),
                geometry::band_width_at(s, t, axis.b),
            ];
            if width.iter().any(|&w| w < p.pair_min_width_px || w > max_w) {
                continue;
            }
            if 0.5 * (width[0] + width[1]) > p.pair_max_width_to_length * axis.length() {
                continue;
            }
            cands.push((
                overlap,
                BandAxis {
                    axis,
                    edges: [i, j],
                    width,
                },
            ));
        }
    }
    cands.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut used = vec![false; segs.len()];
    let mut out = Vec::new();
    for (_, b) in cands {
        if used[b.edges[0]] || used[b.edges[1]] {
            continue;
        }
        used[b.edges[0]] = true;
        used[b.edges[1]] = true;
        out.push(b);
    }
    out
}

/// The axis ends short of `c` (not passing through it), within reach, and its line passes near `c`.
pub(super) fn axis_points_at(
    p: &DefaultParams,
    a: &BandAxis,
    c: P2,
    h: f64,
    spinner_r: f64,
) -> bool {
    let t = a.axis.project_t(c);
    if t > p.candidate_inside_frac && t < 1.0 - p.candidate_inside_frac {
        return false;
    }
    let (_, d_end) = a.near_end(c);
    if d_end > a.reach(p, c, h, spinner_r) {
        return false;
    }
    a.axis.line_distance(c)
        <= p.axis_line_dist_frac * h + p.axis_angle_tol_deg.to_radians().tan() * d_end
}
