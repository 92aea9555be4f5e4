//! Step 2, lines: the probabilistic Hough transform's settings (lengths relative to the image
//! height, each edge pixel voting only for the directions its gradient allows, `hough.rs`) and
//! the merging of collinear pieces into whole lines.

use crate::geometry::Segment;
use crate::hough::HoughSettings;
use crate::params::DefaultParams;

/// The Hough transform's settings for a working image `h` px high.
pub(super) fn hough_settings(p: &DefaultParams, h: f64) -> HoughSettings {
    HoughSettings {
        rho: p.hough_rho_px,
        theta_deg: p.hough_theta_deg,
        threshold: (p.hough_threshold_frac * h).round().max(1.0) as u32,
        min_length: p.hough_min_length_frac * h,
        max_gap: p.hough_max_gap_frac * h,
        orientation_tol_deg: p.hough_orientation_tol_deg,
    }
}

/// Passes of [`merge_collinear_once`] at most: each pass can only join pieces that the previous
/// one grew toward each other, and two passes settle practically every image.
const MERGE_PASSES: usize = 4;

/// Merge collinear segments until no two merge any more (at most [`MERGE_PASSES`] passes).
/// One greedy pass leaves pieces of one line apart when a piece grew toward another only
/// after that one was placed: a horizon cut by the tower stayed in pieces too short to be
/// seen as a horizon, and one of them passed for a blade at hub height.
pub(super) fn merge_collinear(p: &DefaultParams, input: &[Segment], h: f64) -> Vec<Segment> {
    let mut segs = merge_collinear_once(p, input, h);
    for _ in 1..MERGE_PASSES {
        let n = segs.len();
        segs = merge_collinear_once(p, &segs, h);
        if segs.len() == n {
            break;
        }
    }
    segs.truncate(p.max_segments);
    segs
}

/// One greedy pass (longest first): a shorter segment that is nearly parallel, on the same line
/// and close along it extends the longer one. Longest first.
pub(super) fn merge_collinear_once(p: &DefaultParams, input: &[Segment], h: f64) -> Vec<Segment> {
    let mut segs: Vec<Segment> = input.to_vec();
    segs.sort_by(|a, b| b.length().total_cmp(&a.length()));
    let max_gap = p.merge_gap_frac * h;
    let mut out: Vec<Segment> = Vec::with_capacity(segs.len());
    // Orientations of `out`, kept beside it: the pairs are O(n²) and an atan2 each was a
    // tenth of a millisecond per frame.
    let mut out_deg: Vec<f64> = Vec::with_capacity(segs.len());
    'next: for s in segs {
        let s_deg = s.orientation_deg();
        for (m, m_deg) in out.iter_mut().zip(out_deg.iter_mut()) {
            let da = (s_deg - *m_deg).abs();
            let da = da.min(180.0 - da);
            if da > p.merge_angle_deg {
                continue;
            }
            if m.line_distance(s.a) > p.merge_offset_px || m.line_distance(s.b) > p.merge_offset_px
            {
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
            *m_deg = m.orientation_deg();
            continue 'next;
        }
        out.push(s);
        out_deg.push(s_deg);
    }
    out.sort_by(|a, b| b.length().total_cmp(&a.length()));
    out
}
