//! Step 6, blades: the lines supporting a candidate (near end close, line pointing at it, not
//! continuing behind it), grouped by direction into blades, and the rotor tests on them.

use crate::geometry::{self, Segment, P2};
use crate::params::DefaultParams;

use super::context::SceneCtx;
use super::ROTOR_BLADES;

/// A supporting line may point past the candidate by this angle (degrees) on top of the fixed
/// distance tolerance: the blade edges sit half a chord off the blade axis.
const SUPPORT_ANGLE_DEG: f64 = 12.0;

/// A blade around a candidate: member lines, mean direction, total length.
#[derive(Debug, Clone)]
pub(super) struct Blade {
    /// Indices of its lines among the scene's.
    pub lines: Vec<usize>,
    /// Mean direction away from the candidate, degrees clockwise from up (length-weighted).
    pub angle_deg: f64,
    /// Summed length of its lines, px.
    pub weight: f64,
    /// The longest band axis among the blade's paired edges.
    pub axis: Option<Segment>,
}

/// Lines supporting a hub at `c`: near end within reach, line pointing at `c`.
pub(super) fn support_lines(sc: &SceneCtx<'_>, c: P2, spinner_r: f64) -> Vec<usize> {
    let SceneCtx {
        p, segs, usable, h, ..
    } = *sc;
    // With a spinner of radius r at c, blade edges end at its rim and pass within r of c.
    let reach = (p.support_end_dist_frac * h).max(p.spinner_reach_radii * spinner_r);
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
            s.line_distance(c) <= (tol0 + tan * d_end).max(spinner_r) && !continues_beyond(sc, i, c)
        })
        .collect()
}

/// Usable lines passing within the support reach of `c` that are neither among its supporting
/// `lines` nor its `tower`: texture, wires, field borders around a false candidate.
pub(super) fn clutter_lines(
    sc: &SceneCtx<'_>,
    c: P2,
    spinner_r: f64,
    lines: &[usize],
    tower: &[usize],
) -> usize {
    let SceneCtx {
        p, segs, usable, h, ..
    } = *sc;
    let reach = (p.support_end_dist_frac * h).max(p.spinner_reach_radii * spinner_r);
    (0..segs.len())
        .filter(|i| {
            usable[*i]
                && !lines.contains(i)
                && !tower.contains(i)
                && segs[*i].segment_distance(c) <= reach
        })
        .count()
}

/// Line `i` continues, nearly collinear, on the far side of `c`: it passes behind the hub.
pub(super) fn continues_beyond(sc: &SceneCtx<'_>, i: usize, c: P2) -> bool {
    let SceneCtx {
        p, segs, usable, h, ..
    } = *sc;
    let s = &segs[i];
    let off = p.occluded_offset_frac * h;
    let d = [s.b[0] - s.a[0], s.b[1] - s.a[1]];
    let side = |q: P2| (q[0] - c[0]) * d[0] + (q[1] - c[1]) * d[1];
    let own = side(s.midpoint());
    // A near-horizontal line may be a horizon or field border, which the wide lens bends: its
    // continuation may drift off the straight extension, the more so the farther out.
    let bend = if s.tilt_from_vertical_deg().abs() >= 90.0 - p.occluded_bent_max_tilt_deg {
        p.occluded_bend_deg.to_radians().tan()
    } else {
        0.0
    };
    let tol = |q: P2| off + bend * geometry::dist(q, c);
    segs.iter().enumerate().any(|(j, t)| {
        if j == i || !usable[j] {
            return false;
        }
        // Cheap tests first: this runs for every supporting line against every segment.
        if side(t.a) * own >= 0.0
            || side(t.b) * own >= 0.0
            || s.line_distance(t.a) > tol(t.a)
            || s.line_distance(t.b) > tol(t.b)
        {
            return false;
        }
        let da = (s.orientation_deg() - t.orientation_deg()).abs();
        da.min(180.0 - da) <= p.occluded_angle_deg
    })
}

/// Group support lines by direction away from `c` into blades, merging groups closer than
/// `blade_min_separation_deg` (both edges of a wide blade near the root).
pub(super) fn group_blades(
    p: &DefaultParams,
    segs: &[Segment],
    lines: &[usize],
    c: P2,
) -> Vec<Blade> {
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
                axis: None,
            }
        })
        .collect();
    blades.sort_by(|a, b| b.weight.total_cmp(&a.weight));
    let mut merged: Vec<Blade> = Vec::new();
    for b in blades {
        if let Some(m) = merged
            .iter_mut()
            .find(|m| geometry::ang_dist(m.angle_deg, b.angle_deg) < p.blade_min_separation_deg)
        {
            m.lines.extend(b.lines);
            m.weight += b.weight;
            if m.axis.is_none() {
                m.axis = b.axis;
            }
        } else {
            merged.push(b);
        }
    }
    merged
}

/// The blade has lines on both sides of its axis ray from `c` (both edges of the band).
pub(super) fn is_paired(segs: &[Segment], b: &Blade, c: P2) -> bool {
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
pub(super) fn rotor_geometry_ok(p: &DefaultParams, blades: &[Blade]) -> bool {
    let n = blades.len().min(ROTOR_BLADES);
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

/// The rotor's third blade, not seen, would point straight down (`down`, degrees from up
/// clockwise): opposite the bisector of the two seen blades, which are about 120° apart.
pub(super) fn hidden_blade_down(p: &DefaultParams, blades: &[Blade], down: f64) -> bool {
    p.hidden_blade_tol_deg > 0.0
        && implied_third_blade(p, blades[0].angle_deg, blades[1].angle_deg)
            .is_some_and(|third| geometry::ang_dist(third, down) <= p.hidden_blade_tol_deg)
}

/// The direction of a rotor's third blade (degrees from up, clockwise) that two blades seen at
/// `a` and `b` imply: opposite their bisector, when they are about 120° apart.
pub(super) fn implied_third_blade(p: &DefaultParams, a: f64, b: f64) -> Option<f64> {
    ((geometry::ang_dist(a, b) - p.blade_target_deg).abs() <= p.blade_sep_tol_deg)
        .then(|| geometry::circular_mean_deg(&[a, b], None) + 180.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_blades_about_120_degrees_apart_imply_the_third() {
        let p = DefaultParams::default();
        // AP `fly` seed 19 at 10 m: blades 304° and 64° seen, the third hangs at 184°.
        let third = implied_third_blade(&p, 304.0, 64.0).unwrap();
        assert!(geometry::ang_dist(third, 184.0) < 1e-9, "{third}");
        // Stray lines 172° apart imply nothing.
        assert_eq!(implied_third_blade(&p, 268.0, 96.0), None);
    }
}
