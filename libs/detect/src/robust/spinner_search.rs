//! Step 9, the spinner search: circles in the Canny edges (gradient vote, rim coverage, circle
//! fit; `crate::spinner`) around a candidate or, at close range, anywhere in the image. The
//! search around the tracker's predicted hub runs on a second thread while the lines are found.

use std::thread::ScopedJoinHandle;

use crate::geometry::{self, P2};
use crate::heat::Heatmap;
use crate::params::DefaultParams;
use crate::spinner::{find_circles, CircleSearch, EdgePoint};
use crate::DetectError;

use super::context::FrameCtx;
use super::edges::EdgeImage;

/// A candidate within this fraction of `spinner_max_offset_frac` of a searched one reuses its
/// spinner circles.
const SPINNER_REUSE_OF_OFFSET: f64 = 0.5;

/// Where a spinner circle search looks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum CircleQuery {
    /// Around a hub candidate ([`search_circles`]).
    Around(P2),
    /// Anywhere in the image, for close-range spinners only ([`search_close_circles`]).
    Close,
}

/// A spinner circle search: circles `[x, y, r, rim coverage]` (working px, best covered first).
pub(super) type CircleFinder<'a> =
    dyn FnMut(CircleQuery) -> Result<Vec<[f64; 4]>, DetectError> + 'a;

/// The edge points of the whole working image, collected at most once per frame.
pub(super) struct EdgePointCache<'a> {
    points: &'a mut Vec<EdgePoint>,
    ready: bool,
    /// The searches around candidates select their points from this list (else each collects
    /// its own box).
    share: bool,
}

impl<'a> EdgePointCache<'a> {
    /// An empty cache over `points` for the frame `f`. Without a prediction the close-range
    /// search reads every edge point of the frame anyway (unless the tracker's distance,
    /// `expected` spinner radius, rules close spinners out): then the searches around
    /// candidates take theirs from the same list.
    pub fn new(
        f: &FrameCtx<'_>,
        expected: Option<f64>,
        points: &'a mut Vec<EdgePoint>,
    ) -> EdgePointCache<'a> {
        let FrameCtx { p, hints, .. } = *f;
        let (close_min_r, close_max_r) = close_spinner_radii(f, expected);
        let share =
            hints.predicted_hub_px.is_none() && p.close_spinner_always && close_max_r > close_min_r;
        EdgePointCache {
            points,
            ready: false,
            share,
        }
    }

    /// Every edge point of `img`, in row order.
    fn all(&mut self, img: &EdgeImage<'_>) -> &[EdgePoint] {
        if !self.ready {
            edge_points(
                img,
                [0, 0, img.width as i32, img.height as i32],
                self.points,
            );
            self.ready = true;
        }
        self.points
    }

    /// [`EdgePointCache::all`] when it is to be shared with the searches around candidates.
    fn shared(&mut self, img: &EdgeImage<'_>) -> Option<&[EdgePoint]> {
        if self.share {
            Some(self.all(img))
        } else {
            None
        }
    }
}

/// A candidate this close (working px) to an already searched one takes its circles: the search
/// box of the first covers most of the second's.
pub(super) fn spinner_reuse_px(p: &DefaultParams, h: f64) -> f64 {
    SPINNER_REUSE_OF_OFFSET * p.spinner_max_offset_frac * h
}

/// Spinner candidates around `c`: circles `[x, y, r, rim coverage]` (working px, best covered
/// first) among the Canny edge pixels in a square of half side `spinner_search_frac · h`, see
/// [`crate::spinner`].
/// With an `expected` radius only the radii of the `spinner_hint_radius_*` window around it are
/// searched, and only the edge pixels such circles can reach are collected.
/// `all`: every edge point of the image in row order, to select the box's from (else they are
/// collected from `img` into `pts`).
pub(super) fn search_circles(
    f: &FrameCtx<'_>,
    img: &EdgeImage<'_>,
    c: P2,
    expected: Option<f64>,
    pts: &mut Vec<EdgePoint>,
    all: Option<&[EdgePoint]>,
) -> Vec<[f64; 4]> {
    let FrameCtx { p, h, .. } = *f;
    let (min_r, max_r) = spinner_radii(f, expected);
    let off = p.spinner_max_offset_frac * h;
    // The box holds the rim of a circle of the largest radius centred on the candidate (a
    // larger one than `spinner_search_frac` only close in, with a tracker's distance).
    let half = (p.spinner_search_frac * h)
        .max(max_r + p.spinner_cell_px)
        .min(off + max_r + p.spinner_cell_px);
    let (cols, rows) = (img.width as i32, img.height as i32);
    let x0 = ((c[0] - half).floor() as i32).clamp(0, cols);
    let y0 = ((c[1] - half).floor() as i32).clamp(0, rows);
    let x1 = ((c[0] + half).ceil() as i32).clamp(0, cols);
    let y1 = ((c[1] + half).ceil() as i32).clamp(0, rows);
    if max_r <= min_r || x1 - x0 < 2 || y1 - y0 < 2 {
        return Vec::new();
    }
    match all {
        Some(all) => select_points(all, [x0, y0, x1, y1], pts),
        None => edge_points(img, [x0, y0, x1, y1], pts),
    }
    let cs = CircleSearch {
        roi: [
            (c[0] - off).max(0.0),
            (c[1] - off).max(0.0),
            (c[0] + off).min(cols as f64),
            (c[1] + off).min(rows as f64),
        ],
        min_r,
        max_r,
        cell: p.spinner_cell_px,
        radial_cos: p.spinner_radial_tol_deg.to_radians().cos(),
        // With the size known, the radii searched are few and a weaker rim suffices.
        min_coverage: if expected.is_some() {
            p.spinner_hint_min_coverage
        } else {
            p.spinner_min_coverage
        },
        max_interior_density: p.spinner_max_interior_density,
        max_peaks: p.spinner_peaks as usize,
        vote_every: p.spinner_vote_every as usize,
        visible_in: rims_may_leave(f, expected, max_r).then_some([cols as f64, rows as f64]),
    };
    find_circles(pts, &cs)
}

/// The Canny edge pixels of the box `[x0, y0, x1, y1)` with their unit gradient directions.
pub(super) fn edge_points(
    img: &EdgeImage<'_>,
    [x0, y0, x1, y1]: [i32; 4],
    pts: &mut Vec<EdgePoint>,
) {
    pts.clear();
    for y in y0..y1 {
        let row = y as usize * img.width;
        let (e, gx, gy) = (&img.edges[row..], &img.dx[row..], &img.dy[row..]);
        for x in x0..x1 {
            let xi = x as usize;
            if e[xi] == 0 {
                continue;
            }
            let (vx, vy) = (gx[xi] as f64, gy[xi] as f64);
            // Plain sqrt: i16 components cannot overflow, and libm's hypot is several times slower.
            let m = (vx * vx + vy * vy).sqrt();
            if m > 0.0 {
                pts.push(EdgePoint {
                    p: [x as f64, y as f64],
                    u: [vx / m, vy / m],
                });
            }
        }
    }
}

/// The points of `all` (in row order) inside the box `[x0, y0, x1, y1)`, in the same order:
/// what [`edge_points`] collects for that box.
pub(super) fn select_points(
    all: &[EdgePoint],
    [x0, y0, x1, y1]: [i32; 4],
    pts: &mut Vec<EdgePoint>,
) {
    pts.clear();
    let (x0, y0, x1, y1) = (x0 as f64, y0 as f64, x1 as f64, y1 as f64);
    let a = all.partition_point(|e| e.p[1] < y0);
    let b = all.partition_point(|e| e.p[1] < y1).max(a);
    pts.extend(all[a..b].iter().filter(|e| e.p[0] >= x0 && e.p[0] < x1));
}

/// Close-range spinners anywhere in the image: circles of radius at least
/// `close_spinner_radius_frac · h` (working px, best first). At 5–8 m the blades run out of the
/// frame and no blade crossing may lie near the spinner to search around; this runs only when
/// nothing else was detected and no hub was predicted, and with an `expected` radius only over
/// the radii it allows.
/// With a confident `heat`map (peak at least `close_spinner_heat_min`) only centres within
/// `close_spinner_heat_box_frac · h` of its peak are searched, from the points that can reach
/// them (`pts` holds them).
fn search_close_circles(
    f: &FrameCtx<'_>,
    img: &EdgeImage<'_>,
    expected: Option<f64>,
    heat: Option<&Heatmap>,
    whole: &mut EdgePointCache<'_>,
    pts: &mut Vec<EdgePoint>,
) -> Vec<[f64; 4]> {
    let FrameCtx { p, h, .. } = *f;
    let (min_r, max_r) = close_spinner_radii(f, expected);
    if max_r <= min_r {
        return Vec::new();
    }
    let (w, hh) = (img.width as f64, img.height as f64);
    let focus = heat
        .filter(|_| p.close_spinner_heat_min > 0.0)
        .and_then(|m| m.peak())
        .filter(|(_, prob)| *prob >= p.close_spinner_heat_min)
        .map(|([fx, fy], _)| [fx * w, fy * hh]);
    let (roi, pts): ([f64; 4], &[EdgePoint]) = match focus {
        Some([cx, cy]) => {
            let half = p.close_spinner_heat_box_frac * h;
            let roi = [
                (cx - half).max(0.0),
                (cy - half).max(0.0),
                (cx + half).min(w),
                (cy + half).min(hh),
            ];
            // The rims of circles centred in the box lie within max_r of it.
            let reach = max_r + 2.0;
            let bounds = [
                (roi[0] - reach).floor() as i32,
                (roi[1] - reach).floor() as i32,
                (roi[2] + reach).ceil() as i32,
                (roi[3] + reach).ceil() as i32,
            ];
            select_points(whole.all(img), bounds, pts);
            (roi, pts)
        }
        None => ([0.0, 0.0, w, hh], whole.all(img)),
    };
    let cs = CircleSearch {
        roi,
        min_r,
        max_r,
        // Large circles need no fine centre cells; the rim fit refines the centre.
        cell: 2.0 * p.spinner_cell_px,
        radial_cos: p.spinner_radial_tol_deg.to_radians().cos(),
        min_coverage: p.close_spinner_min_coverage,
        max_interior_density: p.spinner_max_interior_density,
        max_peaks: p.close_spinner_peaks as usize,
        vote_every: p.close_spinner_vote_every as usize,
        visible_in: rims_may_leave(f, expected, max_r)
            .then_some([img.width as f64, img.height as f64]),
    };
    find_circles(pts, &cs)
}

/// Radii `[min, max]` the close-range search looks for (working px): at least
/// `close_spinner_radius_frac · h`, and with a tracker's distance only the radii it allows (none
/// when the hub is far).
fn close_spinner_radii(f: &FrameCtx<'_>, expected: Option<f64>) -> (f64, f64) {
    let (lo, max_r) = spinner_radii(f, expected);
    (lo.max(f.p.close_spinner_radius_frac * f.h), max_r)
}

/// Whether a circle's rim is scored over the part inside the frame only: with a tracker's
/// distance, or when the radii searched reach beyond `spinner_max_radius_frac` (a narrow lens
/// close in, whose spinner is cut by the frame's edges). Otherwise the whole rim must show.
fn rims_may_leave(f: &FrameCtx<'_>, expected: Option<f64>, max_r: f64) -> bool {
    expected.is_some() || max_r > f.p.spinner_max_radius_frac * f.h
}

/// Radii `[min, max]` the spinner step searches (working px): up to the frame's blind limit
/// ([`FrameCtx::spinner_max_r`]), narrowed to the `spinner_hint_radius_*` window around an
/// `expected` radius (whose upper limit is `spinner_hint_max_radius_frac`: close in through a
/// narrow lens the spinner is larger than `spinner_max_radius_frac`). An empty range
/// (min ≥ max) means the expected spinner is too small or too large to search for.
pub(super) fn spinner_radii(f: &FrameCtx<'_>, expected: Option<f64>) -> (f64, f64) {
    let FrameCtx { p, h, .. } = *f;
    let lo = p.spinner_min_radius_px;
    match expected.filter(|r| p.spinner_hint_radius_lo > 0.0 && r.is_finite() && *r > 0.0) {
        Some(r) => (
            lo.max(p.spinner_hint_radius_lo * r),
            (p.spinner_hint_max_radius_frac * h)
                .max(f.spinner_max_r)
                .min(p.spinner_hint_radius_hi * r),
        ),
        None => (lo, f.spinner_max_r),
    }
}

/// The circle searches of one frame, as the spinner step asks for them ([`CircleFinder`]):
/// around a candidate ([`search_circles`]) or anywhere for close spinners
/// ([`search_close_circles`]).
pub(super) struct Spinners<'a, 'scope> {
    /// The frame searched.
    pub frame: FrameCtx<'a>,
    /// Its edges and gradients.
    pub img: &'a EdgeImage<'a>,
    /// The spinner radius a tracker's distance expects, working px.
    pub expected_r: Option<f64>,
    /// The learned heatmap, which focuses the close-range search before acquisition.
    pub heat: Option<&'a Heatmap>,
    /// The search around the tracker's predicted hub, running on a second thread: the first
    /// candidate near the prediction takes its circles, as a candidate near an already
    /// searched one does in the spinner step.
    pub ahead: Option<(P2, ScopedJoinHandle<'scope, Vec<[f64; 4]>>)>,
    /// The edge points of the whole image.
    pub whole: EdgePointCache<'a>,
    /// Scratch space for one search's edge points.
    pub pts: &'a mut Vec<EdgePoint>,
}

impl Spinners<'_, '_> {
    /// Circles `[x, y, r, rim coverage]` (working px, best covered first) where `q` asks.
    pub fn find(&mut self, q: CircleQuery) -> Result<Vec<[f64; 4]>, DetectError> {
        let f = self.frame;
        // Only before acquisition: with a tracker's prediction the search runs when nothing
        // else was found, and the heatmap's peak may then be what misled it.
        let heat = self.heat.filter(|_| f.hints.predicted_hub_px.is_none());
        let CircleQuery::Around(c) = q else {
            return Ok(search_close_circles(
                &f,
                self.img,
                self.expected_r,
                heat,
                &mut self.whole,
                self.pts,
            ));
        };
        let reuse = spinner_reuse_px(f.p, f.h);
        match self.ahead.take_if(|(q, _)| geometry::dist(*q, c) <= reuse) {
            // A panic there is a bug here: carry it on.
            Some((_, job)) => Ok(job.join().unwrap_or_else(|e| std::panic::resume_unwind(e))),
            None => Ok(search_circles(
                &f,
                self.img,
                c,
                self.expected_r,
                self.pts,
                self.whole.shared(self.img),
            )),
        }
    }
}
