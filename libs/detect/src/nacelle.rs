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
use crate::tower::GradPlane;

/// Signed offset, working px, from the hub to the nacelle's far end along the image row
/// (positive: to the right), or `None` when neither side shows a clear vertical edge or both
/// do. `px_per_m`: image scale at the hub's depth (working px per metre).
pub(crate) fn nacelle_end(
    p: &DefaultParams,
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
    let near = (p.nacelle_min_offset_m * px_per_m).ceil().max(1.0) as i64;
    let far = (p.nacelle_max_offset_m * px_per_m).floor() as i64;
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
        let dx = nacelle_end(&p, &g, hub, s).expect("nacelle found");
        assert!((dx - 30.0).abs() <= 1.5, "{dx}");
        // Mirrored: to the left.
        let data = sobel_x(w, h, |x, y| img(w - 1 - x, y));
        let g = GradPlane {
            data: &data,
            width: w,
            height: h,
        };
        let dx = nacelle_end(&p, &g, [w as f64 - 1.0 - hub[0], hub[1]], s).expect("nacelle found");
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
