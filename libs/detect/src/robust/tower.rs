//! The tower: its Hough lines below a candidate (a cue of step 6), and for the chosen hub its
//! measurement from both edges in the gradient image (`crate::tower`), which gives the distance
//! and, with the hub, the relative yaw.

use crate::blade::Gradients;
use crate::geometry::{self, Segment, P2};
use crate::tower::{fit_tower, scan_tower_edges, GradPlane};
use crate::Found;

use super::context::{Expected, SceneCtx};
use super::evaluate::Candidate;

/// Tower edges tried as seeds of the two-edge tower fit, longest first.
const TOWER_SEEDS: usize = 4;

/// Tower lines for a hub at `c`: near vertical after roll, top end not far below `c`,
/// horizontally close, extending downward. "Not far" scales with the spinner radius
/// `spinner_r` (0: none) at close range, where the nacelle and tower grow past the fixed limits.
pub(super) fn tower_lines(sc: &SceneCtx<'_>, c: P2, spinner_r: f64) -> Vec<usize> {
    let SceneCtx {
        p,
        segs,
        h,
        roll_deg,
        ..
    } = *sc;
    let max_below = (p.tower_top_max_below_frac * h).max(p.tower_top_max_below_radii * spinner_r);
    let max_dx = (p.tower_max_dx_frac * h).max(p.tower_max_dx_radii * spinner_r);
    (0..segs.len())
        .filter(|&i| {
            let s = &segs[i];
            if geometry::roll_compensated_tilt_deg(s, roll_deg).abs() > p.tower_max_tilt_deg {
                return false;
            }
            let (top, bot) = if s.a[1] < s.b[1] {
                (s.a, s.b)
            } else {
                (s.b, s.a)
            };
            let below = top[1] - c[1];
            // The top may reach a little above the hub (the tower edge continues behind the
            // spinner in views from below) but must end near it and go down from there.
            below >= -p.tower_top_max_above_frac * h
                && below <= max_below
                && bot[1] > c[1]
                && (top[0] - c[0]).abs() <= max_dx
        })
        .collect()
}

/// Whether a band's `axis` (from its top down) lies, halfway down, within `tol` px of one of
/// the `rays` (blade angles, degrees clockwise from up) from `hub`: that band is a blade (or a
/// blade merged with a tower edge), not the tower.
pub(super) fn axis_along_a_ray(axis: &Segment, hub: P2, rays: &[f64], tol: f64) -> bool {
    let mid = (axis.a[1] + axis.b[1]) / 2.0;
    let Some(x) = axis.x_at_y(mid) else {
        return false;
    };
    mid > hub[1]
        && rays.iter().any(|&a| {
            let d = geometry::dir_from_up_cw(a);
            d[1] > 0.0 && (x - (hub[0] + (mid - hub[1]) * d[0] / d[1])).abs() <= tol
        })
}

/// The tower of candidate `b` from both edges (see `tower.rs`), and the row of its top
/// (working px). Seeds are the Hough tower lines, longest first; without a fit from them (and
/// for a detected hub only) the gradient is scanned for edges below the hub. `expected`: the
/// width a tracker's distance and the spinner's size allow the tower band.
fn measure_tower(
    sc: &SceneCtx<'_>,
    b: &Candidate,
    g: &GradPlane<'_>,
    expected: &Expected<'_>,
    detected: bool,
) -> Option<(crate::tower::TowerFit, f64)> {
    let SceneCtx {
        p,
        segs,
        h,
        roll_deg,
        hints,
        ..
    } = *sc;
    let (tower_width, optics) = (expected.tower_width, expected.optics.as_ref());
    let hub_distance_m = hints.hub_distance_m;
    // With a blade pointing down, the tower hides behind it and the band seen below the hub
    // is that blade: its axis runs through the hub.
    let down = 180.0 - roll_deg;
    let near_down = |a: f64| geometry::ang_dist(a, down) <= p.tower_blade_down_tol_deg;
    // A blade is down when one is detected there, when the strongest one's 120° steps put one
    // there, or when two detected blades about 120° apart imply the third there (the strongest
    // may be a stray line: AP `fly` seed 19 at 10 m, blades 268°, 304°, 64°, 96° for a rotor at
    // 304°, 64° and 184°, the band below the hub 1.3x the tower's width); the last only close
    // in (`tower_blade_implied_max_distance_m`).
    let close_in = hub_distance_m.is_some_and(|d| d <= p.tower_blade_implied_max_distance_m);
    let implied_down = || {
        close_in
            && b.blades.iter().enumerate().any(|(i, x)| {
                b.blades[i + 1..].iter().any(|y| {
                    super::blades::implied_third_blade(p, x.angle_deg, y.angle_deg)
                        .is_some_and(near_down)
                })
            })
    };
    let blade_down = b.blades.iter().any(|bl| near_down(bl.angle_deg))
        || b.blades
            .first()
            .is_some_and(|bl| (0..3).any(|k| near_down(bl.angle_deg + 120.0 * k as f64)))
        || implied_down();
    // Rays of blades `tower_blade_ray_min_deg`..`tower_blade_ray_tol_deg` from down: detected, or placed at 120°
    // steps from any detected blade (the first may be a stray line: `fly` seed 279 at 19 m,
    // blades 268°, 48°, 90° for a rotor at 288°, 48°, 168°).
    let down_rays: Vec<f64> = b
        .blades
        .iter()
        .flat_map(|bl| (0..3).map(move |k| bl.angle_deg + 120.0 * k as f64))
        .filter(|&a| {
            (p.tower_blade_ray_min_deg..=p.tower_blade_ray_tol_deg)
                .contains(&geometry::ang_dist(a, down))
        })
        .collect();
    // Until its tip is in view, that blade hides the tower wholly or but for one edge: a band
    // below the hub is the blade, or the blade and one tower edge merged, and its width and gap
    // mislead (see `tower_blade_down_max_distance_m`).
    if let Some(d) =
        hub_distance_m.filter(|d| blade_down && *d <= p.tower_blade_down_max_distance_m)
    {
        log::trace!("a blade points down at {d:.1} m: no tower measured");
        return None;
    }
    // A band is that blade when its axis passes the hub, or (for a blade a few degrees off
    // vertical, whose band the edge fit straightens, or which merged with one tower edge) runs
    // along a blade's ray halfway down (see `tower_blade_ray_tol_deg`).
    let tol = p.tower_blade_axis_tol_frac * h;
    let is_blade = |f: &crate::tower::TowerFit| {
        let through_hub = f
            .axis
            .x_at_y(b.centre[1])
            .is_some_and(|x| (x - b.centre[0]).abs() <= tol);
        (blade_down && through_hub) || axis_along_a_ray(&f.axis, b.centre, &down_rays, tol)
    };
    // Widths a tower band may have: about the expected one, and about the spinner's radius
    // (the tower top is 2.2 m wide, the spinner 3.2 m).
    let mut window = (0.0, f64::INFINITY);
    if let Some(e) = tower_width {
        window = (e / p.tower_width_hint_tol, e * p.tower_width_hint_tol);
    }
    let spinner_r = b.spinner.map_or(0.0, |k| k[2]);
    if spinner_r > 0.0 {
        window = (
            window.0.max(p.tower_width_min_radii * spinner_r),
            window.1.min(p.tower_width_max_radii * spinner_r),
        );
        // ... and about the width the spinner's own distance implies (see
        // `tower_width_spinner_tol`).
        if let Some(e) = optics
            .and_then(|o| o.tower_width_for_spinner(spinner_r))
            .filter(|_| p.tower_width_spinner_tol > 0.0)
        {
            window = (
                window.0.max(e / p.tower_width_spinner_tol),
                window.1.min(e * p.tower_width_spinner_tol),
            );
        }
    }
    let both = |seeds: &[Segment]| {
        seeds
            .iter()
            .take(TOWER_SEEDS)
            .filter_map(|s| fit_tower(p, g, s, window))
            .find(|f| !is_blade(f))
    };
    // Seeds: the tower lines in a window grown with the spinner (at close range the tower
    // top and edges lie beyond the fixed one).
    let mut hough: Vec<Segment> = tower_lines(sc, b.centre, spinner_r)
        .into_iter()
        .map(|i| segs[i])
        .collect();
    hough.sort_by(|x, y| y.length().total_cmp(&x.length()));
    let hough_top = hough
        .iter()
        .flat_map(|s| [s.a[1], s.b[1]])
        .fold(f64::INFINITY, f64::min);
    if let Some(fit) = both(&hough) {
        return Some((fit, hough_top));
    }
    if !detected {
        return None;
    }
    // The tower top (under the nacelle) is ~1.1 spinner radii below the hub centre.
    let top = b.centre[1] + (p.tower_scan_start_frac * h).max(p.tower_scan_start_radii * spinner_r);
    let max_dx = (p.tower_max_dx_frac * h).max(p.tower_max_dx_radii * spinner_r);
    let scanned = scan_tower_edges(
        g,
        b.centre[0],
        top,
        max_dx,
        p.tower_max_tilt_deg + roll_deg.abs(),
        p.tower_scan_min_salience,
        TOWER_SEEDS,
    )
    .into_iter()
    .filter(|s| geometry::roll_compensated_tilt_deg(s, roll_deg).abs() <= p.tower_max_tilt_deg)
    .collect::<Vec<_>>();
    log::trace!("tower scan from row {top:.0}: seeds {scanned:?}");
    both(&scanned).map(|fit| (fit, top))
}

/// The chosen hub `b`'s tower into `found`. With the gradient `grad`, measured from both edges
/// ([`measure_tower`]), and for a detected hub the nacelle's end looked up (`crate::nacelle`);
/// without it, from the candidate's tower lines as the thesis does.
pub(super) fn report_tower(
    sc: &SceneCtx<'_>,
    b: &Candidate,
    grad: Option<&Gradients<'_>>,
    expected: &Expected<'_>,
    found: &mut Found,
) {
    let SceneCtx { p, segs, h, .. } = *sc;
    match grad {
        Some(g) => {
            if let Some((fit, top_y)) = measure_tower(sc, b, &g.x, expected, found.detected) {
                let row = top_y + p.tower_width_below_top_frac * h;
                found.tower_top = fit.axis.x_at_y(top_y).map(|x| [x, top_y]);
                found.tower_axis = Some(fit.axis);
                found.tower_width = fit.width_at(row).map(|wd| (wd, row));
            }
            if found.detected {
                found.nacelle_end_dx = expected.px_per_m.zip(expected.optics).and_then(|(s, o)| {
                    let reach = crate::nacelle::NacelleReach::of(p, &o);
                    crate::nacelle::nacelle_end(p, reach, &g.x, b.centre, s)
                });
            }
        }
        None if !b.tower.is_empty() => {
            let top = b
                .tower
                .iter()
                .flat_map(|&i| [segs[i].a, segs[i].b])
                .min_by(|x, y| x[1].total_cmp(&y[1]))
                .unwrap_or(b.centre);
            let row = top[1] + p.tower_width_below_top_frac * h;
            let axis = crate::thesis::tower_axis(segs, &b.tower);
            found.tower_top = Some(
                axis.and_then(|a| a.x_at_y(top[1]))
                    .map_or(top, |x| [x, top[1]]),
            );
            found.tower_axis = axis;
            found.tower_width =
                crate::thesis::tower_width_at(segs, &b.tower, row, 1.0).map(|wd| (wd, row));
        }
        None => {}
    }
}
