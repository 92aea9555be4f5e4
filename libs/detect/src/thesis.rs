//! The thesis pipeline (section 6.1.5), step by step, on the working-size grey image.
//!
//! Canny (fixed 300/400) → HoughLinesP (table 9.1) → tower lines (near vertical after roll
//! compensation, an end point in the lowest 20 %) → tower top = highest tower-line point →
//! blade lines (an END point within 0.3·height of the tower top) → group by angle → drop a blade
//! pointing down over the tower → 120° ± 20° voting (≥ 3 votes removes) → hub = mean of the
//! intersections between lines of different blades that pass the tower-axis / tower-top filter.

use std::time::Instant;

use opencv::core::{self, Mat, Vec4i, Vector};
use opencv::imgproc;
use opencv::prelude::*;

use crate::geometry::{self, Segment, P2};
use crate::params::ThesisParams;
use crate::{us_since, DetectError, Found, Hints, LineKind, Scratch};

/// Run the thesis pipeline on the working image.
pub(crate) fn run(
    p: &ThesisParams,
    small: &Mat,
    s: &mut Scratch,
    hints: &Hints,
) -> Result<Found, DetectError> {
    let t = Instant::now();
    imgproc::canny(small, &mut s.edges, p.canny_low, p.canny_high, 3, false)?;
    let edge_count = core::count_non_zero(&s.edges)? as u32;
    let edges_us = us_since(t);
    let t = Instant::now();
    hough_segments(p, &s.edges, &mut s.lines, &mut s.segments)?;
    let hough_us = us_since(t);
    let t = Instant::now();
    let roll_deg = hints.roll_rad.unwrap_or(0.0).to_degrees();
    let mut found = recognise(
        p,
        &s.segments,
        small.cols() as f64,
        small.rows() as f64,
        roll_deg,
    );
    found.edge_count = edge_count;
    found.edges_us = edges_us;
    found.hough_us = hough_us;
    found.geometry_us = us_since(t);
    Ok(found)
}

/// Indices of the tower lines: within `tower_max_tilt_deg` of vertical after roll compensation
/// and with an end point in the lowest `tower_bottom_frac` of the image.
pub(crate) fn tower_lines(
    p: &ThesisParams,
    segs: &[Segment],
    height: f64,
    roll_deg: f64,
) -> Vec<usize> {
    let bottom = height * (1.0 - p.tower_bottom_frac);
    segs.iter()
        .enumerate()
        .filter(|(_, s)| {
            geometry::roll_compensated_tilt_deg(s, roll_deg).abs() <= p.tower_max_tilt_deg
                && s.a[1].max(s.b[1]) >= bottom
        })
        .map(|(i, _)| i)
        .collect()
}

/// A tower axis line: the mean of the tower lines' x at the top and the bottom of their span.
pub(crate) fn tower_axis(segs: &[Segment], idx: &[usize]) -> Option<Segment> {
    if idx.is_empty() {
        return None;
    }
    let top = idx
        .iter()
        .map(|&i| segs[i].a[1].min(segs[i].b[1]))
        .fold(f64::INFINITY, f64::min);
    let bot = idx
        .iter()
        .map(|&i| segs[i].a[1].max(segs[i].b[1]))
        .fold(f64::NEG_INFINITY, f64::max);
    let (mut xt, mut xb, mut n) = (0.0, 0.0, 0.0);
    for &i in idx {
        if let (Some(a), Some(b)) = (segs[i].x_at_y(top), segs[i].x_at_y(bot)) {
            xt += a;
            xb += b;
            n += 1.0;
        }
    }
    if n == 0.0 || (bot - top).abs() < 1e-9 {
        return None;
    }
    Some(Segment::new([xt / n, top], [xb / n, bot]))
}

/// Tower width at `row`: horizontal distance between the outermost tower lines there (their
/// infinite extensions). `None` with fewer than two distinct lines.
pub(crate) fn tower_width_at(
    segs: &[Segment],
    idx: &[usize],
    row: f64,
    min_width: f64,
) -> Option<f64> {
    let xs: Vec<f64> = idx.iter().filter_map(|&i| segs[i].x_at_y(row)).collect();
    if xs.len() < 2 {
        return None;
    }
    let lo = xs.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (hi - lo >= min_width).then_some(hi - lo)
}

/// A blade: the lines of one angle group and their mean direction.
#[derive(Debug, Clone)]
pub(crate) struct Blade {
    pub lines: Vec<usize>,
    pub angle_deg: f64,
}

/// Blade lines (non-tower lines with an end point within `radius` of `centre`, i.e. starting or
/// ending there; lines only passing through are ignored), grouped by angle.
pub(crate) fn blades_around(
    p: &ThesisParams,
    segs: &[Segment],
    tower: &[usize],
    centre: P2,
    radius: f64,
) -> Vec<Blade> {
    let cand: Vec<usize> = (0..segs.len())
        .filter(|i| !tower.contains(i) && segs[*i].nearest_end(centre).1 <= radius)
        .collect();
    let angles: Vec<f64> = cand
        .iter()
        .map(|&i| segs[i].angle_away_from(centre))
        .collect();
    geometry::group_by_angle(&angles, p.blade_group_tol_deg)
        .into_iter()
        .map(|g| {
            let a: Vec<f64> = g.iter().map(|&k| angles[k]).collect();
            Blade {
                lines: g.iter().map(|&k| cand[k]).collect(),
                angle_deg: geometry::circular_mean_deg(&a, None),
            }
        })
        .collect()
}

/// The thesis's false-blade elimination: remove a blade pointing down over the tower, then
/// vote. Returns (kept, rejected).
pub(crate) fn eliminate(
    p: &ThesisParams,
    blades: Vec<Blade>,
    roll_deg: f64,
) -> (Vec<Blade>, Vec<Blade>) {
    let (mut kept, mut rejected): (Vec<Blade>, Vec<Blade>) = (Vec::new(), Vec::new());
    // "Down" in the image of a rolled camera is 180° minus the roll (content rotated CCW).
    let down = 180.0 - roll_deg;
    for b in blades {
        if geometry::ang_dist(b.angle_deg, down) <= p.blade_over_tower_tol_deg {
            rejected.push(b);
        } else {
            kept.push(b);
        }
    }
    let angles: Vec<f64> = kept.iter().map(|b| b.angle_deg).collect();
    let keep = geometry::vote_keep(&angles, p.vote_target_deg, p.vote_tol_deg, p.vote_limit);
    let mut out = Vec::new();
    for (b, k) in kept.into_iter().zip(keep) {
        if k {
            out.push(b);
        } else {
            rejected.push(b);
        }
    }
    (out, rejected)
}

/// All pairwise intersections between lines of different blades.
pub(crate) fn blade_intersections(segs: &[Segment], blades: &[Blade]) -> Vec<P2> {
    let mut pts = Vec::new();
    for i in 0..blades.len() {
        for j in i + 1..blades.len() {
            for &a in &blades[i].lines {
                for &b in &blades[j].lines {
                    if let Some(x) = geometry::line_intersection(&segs[a], &segs[b]) {
                        pts.push(x);
                    }
                }
            }
        }
    }
    pts
}

/// Steps after the Hough transform, on plain data.
pub(crate) fn recognise(
    p: &ThesisParams,
    segs: &[Segment],
    width: f64,
    height: f64,
    roll_deg: f64,
) -> Found {
    let _ = width;
    let mut found = Found {
        roll_used_deg: roll_deg,
        line_count: segs.len() as u32,
        ..Found::default()
    };
    let mut kinds = vec![LineKind::Other; segs.len()];
    let tower = tower_lines(p, segs, height, roll_deg);
    for &i in &tower {
        kinds[i] = LineKind::Tower;
    }
    let finish = |found: &mut Found, kinds: &[LineKind]| {
        found.lines = segs.iter().copied().zip(kinds.iter().copied()).collect();
    };
    if tower.is_empty() {
        finish(&mut found, &kinds);
        return found;
    }
    // Tower top = highest point among the tower lines.
    let top = tower
        .iter()
        .flat_map(|&i| [segs[i].a, segs[i].b])
        .min_by(|a, b| a[1].total_cmp(&b[1]))
        .unwrap_or([0.0, 0.0]);
    let axis = tower_axis(segs, &tower);
    found.tower_top = Some(
        axis.and_then(|a| a.x_at_y(top[1]))
            .map_or(top, |x| [x, top[1]]),
    );
    found.tower_axis = axis;
    let row = top[1] + p.tower_width_below_top_frac * height;
    // Two edges closer than 1 px are the same edge seen twice, not a tower.
    found.tower_width = tower_width_at(segs, &tower, row, 1.0).map(|w| (w, row));

    let radius = p.search_radius_frac * height;
    found.search_circle = Some([top[0], top[1], radius]);
    let blades = blades_around(p, segs, &tower, top, radius);
    let (blades, rejected) = eliminate(p, blades, roll_deg);
    for b in &rejected {
        for &i in &b.lines {
            kinds[i] = LineKind::Rejected;
        }
    }
    for b in &blades {
        for &i in &b.lines {
            kinds[i] = LineKind::Blade;
        }
    }
    found.blade_angles = blades.iter().map(|b| b.angle_deg).collect();
    finish(&mut found, &kinds);
    if blades.len() < p.min_blades as usize {
        return found;
    }
    let pts = blade_intersections(segs, &blades);
    let axis_line = axis.unwrap_or(Segment::new(top, [top[0], top[1] + 1.0]));
    let kept = geometry::filter_intersections(
        &pts,
        &axis_line,
        top,
        p.hub_max_dx_frac * radius,
        p.hub_max_dy_frac * radius,
    );
    if let Some(hub) = geometry::mean_point(&kept) {
        found.detected = true;
        found.hub = hub;
        found.confidence = 1.0;
    }
    found
}

/// Run HoughLinesP with the thesis's settings on `edges` into `out` (working px), through the
/// OpenCV buffer `lines`.
fn hough_segments(
    p: &ThesisParams,
    edges: &Mat,
    lines: &mut Vector<Vec4i>,
    out: &mut Vec<Segment>,
) -> Result<(), DetectError> {
    lines.clear();
    imgproc::hough_lines_p(
        edges,
        lines,
        p.hough_rho_px,
        p.hough_theta_deg.to_radians(),
        p.hough_threshold.max(1),
        p.hough_min_length_px,
        p.hough_max_gap_px,
    )?;
    out.clear();
    out.extend(
        lines
            .iter()
            .map(|l| Segment::new([l[0] as f64, l[1] as f64], [l[2] as f64, l[3] as f64])),
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::dir_from_up_cw;

    fn ray(from: P2, angle: f64, start: f64, len: f64) -> Segment {
        let d = dir_from_up_cw(angle);
        Segment::new(
            [from[0] + d[0] * start, from[1] + d[1] * start],
            [
                from[0] + d[0] * (start + len),
                from[1] + d[1] * (start + len),
            ],
        )
    }

    /// A synthetic front view on a 480x270 working image: tower from the bottom up to (240, 120),
    /// hub 6 px above, three blades at 10/130/250°, and a horizon line.
    fn scene(roll: f64) -> Vec<Segment> {
        let hub = [240.0, 114.0];
        let rot = |s: Segment| {
            // Rotate the whole picture counter-clockwise by `roll` around the hub, as a
            // clockwise-rolled camera would see it.
            let r = (-roll).to_radians();
            let f = |p: P2| {
                let (x, y) = (p[0] - hub[0], p[1] - hub[1]);
                [
                    hub[0] + x * r.cos() - y * r.sin(),
                    hub[1] + x * r.sin() + y * r.cos(),
                ]
            };
            Segment::new(f(s.a), f(s.b))
        };
        let mut v = vec![
            Segment::new([236.0, 269.0], [237.0, 120.0]),
            Segment::new([244.0, 269.0], [243.0, 122.0]),
        ];
        for a in [10.0, 130.0, 250.0] {
            v.push(ray(hub, a - 3.0, 8.0, 70.0));
            v.push(ray(hub, a + 3.0, 8.0, 70.0));
        }
        v.into_iter().map(rot).collect()
    }

    #[test]
    fn tower_selection_with_roll() {
        let p = ThesisParams::default();
        let segs = scene(8.0);
        // Without compensation the rolled tower (8° > 5°) is missed; with it, it is found.
        assert!(tower_lines(&p, &segs, 270.0, 0.0).is_empty());
        assert_eq!(tower_lines(&p, &segs, 270.0, 8.0), vec![0, 1]);
        // A vertical line that does not reach the lowest 20 % is not a tower line.
        let high = [Segment::new([10.0, 10.0], [10.0, 150.0])];
        assert!(tower_lines(&p, &high, 270.0, 0.0).is_empty());
    }

    #[test]
    fn blades_grouped_and_hub_found() {
        let p = ThesisParams::default();
        let segs = scene(0.0);
        let f = recognise(&p, &segs, 480.0, 270.0, 0.0);
        assert!(f.detected);
        assert_eq!(f.blade_angles.len(), 3);
        assert!(
            (f.hub[0] - 240.0).abs() < 2.0 && (f.hub[1] - 114.0).abs() < 2.0,
            "{:?}",
            f.hub
        );
        let w = f.tower_width.unwrap().0;
        assert!((w - 6.0).abs() < 1.5, "{w}");
    }

    #[test]
    fn line_passing_through_is_not_a_blade() {
        let p = ThesisParams::default();
        let mut segs = scene(0.0);
        // A long horizontal line crossing right through the search circle.
        segs.push(Segment::new([100.0, 110.0], [400.0, 110.0]));
        let tower = tower_lines(&p, &segs, 270.0, 0.0);
        let blades = blades_around(&p, &segs, &tower, [240.0, 120.0], 81.0);
        assert!(blades.iter().all(|b| !b.lines.contains(&(segs.len() - 1))));
    }

    #[test]
    fn false_blade_removed_by_votes() {
        let p = ThesisParams::default();
        let mut segs = scene(0.0);
        // Horizon piece ending near the hub, pointing left (270°): a fourth, false blade.
        segs.push(ray([240.0, 118.0], 290.0, 20.0, 90.0));
        let f = recognise(&p, &segs, 480.0, 270.0, 0.0);
        assert!(f.detected);
        assert_eq!(f.blade_angles.len(), 3, "{:?}", f.blade_angles);
        assert!(f.lines.iter().any(|(_, k)| *k == LineKind::Rejected));
        assert!(
            (f.hub[0] - 240.0).abs() < 2.0 && (f.hub[1] - 114.0).abs() < 2.0,
            "{:?}",
            f.hub
        );
    }

    #[test]
    fn downward_blade_over_tower_removed() {
        let p = ThesisParams::default();
        let blades = vec![
            Blade {
                lines: vec![],
                angle_deg: 0.0,
            },
            Blade {
                lines: vec![],
                angle_deg: 120.0,
            },
            Blade {
                lines: vec![],
                angle_deg: 178.0,
            },
        ];
        let (kept, rej) = eliminate(&p, blades, 0.0);
        assert_eq!(kept.len(), 2);
        assert_eq!(rej[0].angle_deg, 178.0);
    }
}
