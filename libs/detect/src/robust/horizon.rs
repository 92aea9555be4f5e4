//! Steps 3 and 4, roll and horizon: the roll that makes most line length vertical (when no hint
//! gives it), and the long near-horizontal lines (horizon, ridges) that never count as blades.

use hubtrack_types::setup::CameraModel;

use crate::geometry::{self, Segment};
use crate::params::DefaultParams;

use super::bands::pair_edges;
use super::context::FrameCtx;

/// Roll search step (degrees) when no roll hint is given.
const ROLL_STEP_DEG: f64 = 1.0;

/// Lines within this of vertical (degrees, after a trial roll) count for the roll search.
const ROLL_VERTICAL_TOL_DEG: f64 = 1.5;

/// The roll (degrees) in ±`roll_search_deg` that makes the most line length vertical.
pub(super) fn search_roll(p: &DefaultParams, segs: &[Segment]) -> f64 {
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

/// Horizon/ridge candidates: long and near horizontal after roll compensation (through a lens
/// that bends lines, see [`horizon_in_pieces`]).
pub(super) fn is_horizon(p: &DefaultParams, s: &Segment, w: f64, roll_deg: f64) -> bool {
    s.length() >= p.horizon_min_length_frac * w && is_level(p, s, roll_deg)
}

/// Within `horizon_max_tilt_deg` of horizontal after roll compensation.
fn is_level(p: &DefaultParams, s: &Segment, roll_deg: f64) -> bool {
    (90.0 - geometry::roll_compensated_tilt_deg(s, roll_deg).abs()) <= p.horizon_max_tilt_deg
}

/// Per line: a horizon candidate seen through a lens that bends lines (see
/// `horizon_piece_tol_frac`). Each line is judged where a pinhole at the same principal point
/// and focal length would have imaged it, and the level lines within the tolerance of its
/// straight line count with it toward the length.
fn horizon_in_pieces(
    f: &FrameCtx<'_>,
    camera: &CameraModel,
    segs: &[Segment],
    roll_deg: f64,
) -> Vec<bool> {
    let FrameCtx { p, w, h, .. } = *f;
    let straight: Vec<Segment> = segs
        .iter()
        .map(|s| Segment::new(camera.undistort_pixel(s.a), camera.undistort_pixel(s.b)))
        .collect();
    let level: Vec<bool> = straight.iter().map(|s| is_level(p, s, roll_deg)).collect();
    let tol = p.horizon_piece_tol_frac * h;
    (0..straight.len())
        .map(|i| {
            let s = &straight[i];
            level[i]
                && straight
                    .iter()
                    .zip(&level)
                    .filter(|(t, l)| {
                        **l && s.line_distance(t.a) <= tol && s.line_distance(t.b) <= tol
                    })
                    .map(|(t, _)| t.length())
                    .sum::<f64>()
                    >= p.horizon_min_length_frac * w
        })
        .collect()
}

/// Lines that may be blade or tower edges: all but horizon candidates ([`is_horizon`]), except
/// that a horizon candidate pairing into a slender band narrowing by `horizon_band_min_taper`
/// is a blade lying level. A blade lying level is as long and flat as a horizon, but its two
/// edges pair; a horizon is one line, a road or field strip a band of even width (rendered
/// flights at 30 m lost the level blade as "horizon", and two blade roots at the tower top
/// then outscored the hub).
pub(super) fn usable_lines(f: &FrameCtx<'_>, segs: &[Segment], roll_deg: f64) -> Vec<bool> {
    let FrameCtx { p, w, .. } = *f;
    let mut usable: Vec<bool> = match f.camera {
        Some(camera) if p.horizon_piece_tol_frac > 0.0 => {
            horizon_in_pieces(f, &camera, segs, roll_deg)
                .into_iter()
                .map(|h| !h)
                .collect()
        }
        _ => segs
            .iter()
            .map(|s| !is_horizon(p, s, w, roll_deg))
            .collect(),
    };
    if p.horizon_band_min_taper > 0.0 && usable.iter().any(|u| !u) {
        for b in pair_edges(f, segs, &vec![true; segs.len()]) {
            let taper = b.width[0].max(b.width[1]) / b.width[0].min(b.width[1]).max(1e-9);
            if (!usable[b.edges[0]] || !usable[b.edges[1]]) && taper >= p.horizon_band_min_taper {
                usable[b.edges[0]] = true;
                usable[b.edges[1]] = true;
            }
        }
    }
    usable
}
