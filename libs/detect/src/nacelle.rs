//! The nacelle's far end beside the spinner: on which side of the hub, and how far, the nacelle
//! reaches out in the image.
//!
//! Seen from the front at a relative yaw ψ the nacelle (a box behind the rotor) sticks out beside
//! the spinner on the side of the tower, as far as its rear corner: `Lr·sin ψ + w·cos ψ` metres
//! (rear face `Lr` behind the hub, half width `w`). Its rear edge is vertical, so in a band of rows
//! around the hub it adds up coherently down one image column, while blade edges beside the hub
//! are inclined and the horizon is horizontal. On the other side nothing sticks out beyond the
//! spinner, whatever the yaw. This gives the yaw's sign where the hub–tower gap fails: with a
//! blade pointing down, the tower hides behind that blade and the band measured below the hub
//! is the blade, or the blade and one tower edge merged.

use crate::geometry::P2;
use crate::params::DefaultParams;
use crate::robust::Optics;
use crate::tower::GradPlane;

/// How far beside the hub the nacelle's far end is searched, metres at the hub's depth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct NacelleReach {
    /// Nearest: `nacelle_clearance_m` beyond the wider of the spinner and the nacelle's front
    /// corners, which stick out on both sides whatever the yaw (a 4.3 m spinner's rim lies 2.15
    /// m out, where a fixed 2 m band would take it for the nacelle's end).
    pub near_m: f64,
    /// Farthest: the rear corner at `nacelle_max_yaw_deg`, `Lr·sin ψ + w·cos ψ`.
    pub far_m: f64,
}

impl NacelleReach {
    /// The reach for the turbine of `optics`.
    pub fn of(p: &DefaultParams, optics: &Optics) -> NacelleReach {
        let half_width = optics.nacelle_width_m / 2.0;
        let (sin, cos) = p.nacelle_max_yaw_deg.to_radians().sin_cos();
        NacelleReach {
            near_m: optics.spinner_radius_m.max(half_width) + p.nacelle_clearance_m,
            far_m: optics.nacelle_rear_m * sin + half_width * cos,
        }
    }
}

/// Signed offset, working px, from the hub to the nacelle's far end along the image row
/// (positive: to the right), or `None` when neither side shows a clear vertical edge or both
/// do. `px_per_m`: image scale at the hub's depth (working px per metre).
pub(crate) fn nacelle_end(
    p: &DefaultParams,
    reach: NacelleReach,
    gx: &GradPlane<'_>,
    hub: P2,
    px_per_m: f64,
) -> Option<f64> {
    let half_rows = (p.nacelle_band_half_m * px_per_m).round() as i64;
    if half_rows < 1 || !(hub[0].is_finite() && hub[1].is_finite()) {
        return None;
    }
    let (x0, y0) = (hub[0].round() as i64, hub[1].round() as i64);
    let rows: Vec<i64> = (y0 - half_rows..=y0 + half_rows)
        .filter(|&y| y >= 0 && y < gx.height as i64)
        .collect();
    if rows.len() < 3 {
        return None;
    }
    let near = (reach.near_m * px_per_m).ceil().max(1.0) as i64;
    let far = (reach.far_m * px_per_m).floor() as i64;
    // Median signed horizontal gradient down one column: a vertical edge keeps its sign over
    // all rows; texture cancels and an inclined edge (a blade beside the hub, however strong)
    // crosses a few rows only.
    let mut vals = Vec::with_capacity(rows.len());
    let mut column = |x: i64| {
        vals.clear();
        vals.extend(rows.iter().map(|&y| gx.at(x, y)));
        vals.sort_by(f64::total_cmp);
        vals[vals.len() / 2].abs()
    };
    let mut best = |side: i64| {
        (near..=far)
            .map(|k| x0 + side * k)
            .filter(|&x| x >= 1 && x < gx.width as i64 - 1)
            .map(|x| (column(x), x))
            .max_by(|a, b| a.0.total_cmp(&b.0))
    };
    let (right, left) = (best(1), best(-1));
    let strength = |s: Option<(f64, i64)>| s.map_or(0.0, |s| s.0);
    let (win, other) = if strength(right) >= strength(left) {
        (right?, strength(left))
    } else {
        (left?, strength(right))
    };
    log::trace!(
        "nacelle: best column {} ({:.0}), other side {other:.0}",
        win.1,
        win.0
    );
    (win.0 >= p.nacelle_min_response && win.0 >= p.nacelle_min_ratio * other)
        .then(|| win.1 as f64 - hub[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The thesis turbine's reach: 2 m (its 1.7 m half width + 0.3) to ~10 m.
    const THESIS: NacelleReach = NacelleReach {
        near_m: 2.0,
        far_m: 10.0,
    };

    /// The reach of a turbine with the thesis turbine's nacelle and a spinner of `diameter_m`.
    fn reach_with_spinner(diameter_m: f64) -> NacelleReach {
        NacelleReach::of(
            &DefaultParams::default(),
            &Optics {
                focal_px: 500.0,
                spinner_radius_m: diameter_m / 2.0,
                tower_top_diameter_m: 2.2,
                hub_tower_gap_m: 4.2,
                nacelle_width_m: 3.4,
                nacelle_rear_m: 11.2,
                bending_lens: None,
            },
        )
    }

    #[test]
    fn the_reach_follows_the_turbines_spinner_and_nacelle() {
        let thesis = reach_with_spinner(3.2);
        assert!((thesis.near_m - 2.0).abs() < 1e-9, "{thesis:?}");
        // 11.2·sin 55° + 1.7·cos 55°.
        assert!((thesis.far_m - 10.15).abs() < 0.01, "{thesis:?}");
        // A spinner wider than the nacelle sets the near end.
        assert!((reach_with_spinner(4.3).near_m - 2.45).abs() < 1e-9);
    }

    /// A large spinner (4.3 m, `fly --random-setup` seed 10) lit from one side: its bright rim
    /// lies 2.15 m out, beyond a fixed 2 m band, where it reads as a nacelle end 6–9° of yaw
    /// long; the turbine's own reach starts beyond it.
    #[test]
    fn a_large_spinners_rim_is_not_the_nacelles_end() {
        let p = DefaultParams::default();
        let (w, h) = (200usize, 100usize);
        let hub = [100.0, 50.0];
        let s = 5.0; // px per m: spinner radius 10.75 px
        let data = sobel_x(w, h, |x, y| {
            let (dx, dy) = (x as f64 - hub[0], y as f64 - hub[1]);
            match (dx * dx + dy * dy <= 10.75 * 10.75, dx >= 0.0) {
                (true, true) => 200.0,
                (true, false) => 125.0,
                _ => 120.0,
            }
        });
        let g = GradPlane {
            data: &data,
            width: w,
            height: h,
        };
        assert!(nacelle_end(&p, THESIS, &g, hub, s).is_some());
        assert_eq!(nacelle_end(&p, reach_with_spinner(4.3), &g, hub, s), None);
    }

    /// Sobel-x of a `w × h` image given per pixel.
    fn sobel_x(w: usize, h: usize, img: impl Fn(usize, usize) -> f64) -> Vec<i16> {
        let mut out = vec![0i16; w * h];
        for y in 1..h - 1 {
            for x in 1..w - 1 {
                let g = |dx: usize, dy: usize| img(x + dx - 1, y + dy - 1);
                let v = (g(2, 0) + 2.0 * g(2, 1) + g(2, 2)) - (g(0, 0) + 2.0 * g(0, 1) + g(0, 2));
                out[y * w + x] = v.round() as i16;
            }
        }
        out
    }

    #[test]
    fn the_side_with_a_vertical_edge_beyond_the_spinner_is_the_nacelle_side() {
        let p = DefaultParams::default();
        let (w, h) = (200usize, 100usize);
        let hub = [100.0, 50.0];
        let s = 5.0; // px per m: spinner radius 8 px
                     // Spinner disc, a nacelle reaching 30 px to the right, and an inclined blade edge on
                     // the left (inclined edges do not add up down a column).
        let img = |x: usize, y: usize| {
            let (dx, dy) = (x as f64 - hub[0], y as f64 - hub[1]);
            let spinner = dx * dx + dy * dy <= 64.0;
            let nacelle = (0.0..=30.0).contains(&dx) && dy.abs() <= 8.0;
            let blade = dx < 0.0 && (dy + 0.58 * dx).abs() <= 4.0;
            if spinner || nacelle || blade {
                200.0
            } else {
                120.0
            }
        };
        let data = sobel_x(w, h, img);
        let g = GradPlane {
            data: &data,
            width: w,
            height: h,
        };
        let dx = nacelle_end(&p, THESIS, &g, hub, s).expect("nacelle found");
        assert!((dx - 30.0).abs() <= 1.5, "{dx}");
        // Mirrored: to the left.
        let data = sobel_x(w, h, |x, y| img(w - 1 - x, y));
        let g = GradPlane {
            data: &data,
            width: w,
            height: h,
        };
        let dx = nacelle_end(&p, THESIS, &g, [w as f64 - 1.0 - hub[0], hub[1]], s)
            .expect("nacelle found");
        assert!((dx + 30.0).abs() <= 1.5, "{dx}");
    }

    #[test]
    fn no_side_without_an_edge_beyond_the_spinner_or_with_edges_on_both() {
        let p = DefaultParams::default();
        let (w, h) = (200usize, 100usize);
        let hub = [100.0, 50.0];
        let spinner_only = sobel_x(w, h, |x, y| {
            if (x as f64 - hub[0]).powi(2) + (y as f64 - hub[1]).powi(2) <= 64.0 {
                200.0
            } else {
                120.0
            }
        });
        assert_eq!(
            nacelle_end(
                &p,
                THESIS,
                &GradPlane {
                    data: &spinner_only,
                    width: w,
                    height: h
                },
                hub,
                5.0
            ),
            None
        );
        let both = sobel_x(w, h, |x, _| {
            if (70..=130).contains(&x) {
                200.0
            } else {
                120.0
            }
        });
        assert_eq!(
            nacelle_end(
                &p,
                THESIS,
                &GradPlane {
                    data: &both,
                    width: w,
                    height: h
                },
                hub,
                5.0
            ),
            None
        );
    }
}
