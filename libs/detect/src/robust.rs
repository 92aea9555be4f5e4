//! The default pipeline: blade convergence first, tower as support.
//!
//! The thesis starts from the tower and searches blades around its top; that fails whenever the
//! tower edge is broken (nacelle shadow), hidden (close range, views from above against the
//! ground) or the horizon ends near the hub. Here the hub is found where long segments
//! *converge* (each ending near the point and pointing at it), and the tower only raises the
//! confidence:
//!
//! 1. Sobel gradients → Canny thresholds from a percentile of the gradient magnitude (contrast
//!    adaptive) → Canny on the same gradients (no second Sobel).
//! 2. Probabilistic Hough with lengths relative to the image height, each edge pixel voting only
//!    for line directions its gradient allows (`hough.rs`); collinear pieces merged.
//! 3. Roll: the hint, or the roll in ±`roll_search_deg` that makes most line length vertical.
//! 4. Horizon candidates (long, near-horizontal after roll) never count as blades.
//! 5. Proposals: intersections of pairs of long, clearly non-parallel segments lying just beyond
//!    an end of both (blades start at the hub; a line passing through is no blade) → grid vote
//!    → a few peaks.
//! 6. Each peak: supporting lines (near end close, line pointing at it) grouped into blades;
//!    a downward "blade" that is the tower is dropped; tower lines below are looked up;
//!    confidence from blade count, tower, and blade separations vs a (skewed) 120° rotor.
//! 7. Hub refined by least squares over its blade lines, each blade weighted equally; a blade
//!    seen by one edge contributes its axis instead when its partner edge is found in the
//!    gradient image (`blade.rs`); with two or more known axes, over the axes alone.
//! 8. Edge pairing (`pair_edges`): the two edges of a blade (nearly parallel, overlapping, a
//!    slender band) give its axis, the internal bisector; axis–axis crossings are extra
//!    proposals and axes may end further from the hub (blades start at the spinner rim).
//! 9. Spinner step: around the best few candidates, circles in the Canny edges (gradient vote,
//!    rim coverage, circle fit; `spinner.rs`); a circle with two blades starting at its rim
//!    becomes a candidate centred on it, with a confidence bonus. Around the tracker's predicted
//!    hub the search runs on a second thread from step 2 on. Without a tracker's prediction,
//!    large (close-range) circles are searched over the whole image (every frame, or only when
//!    nothing is detected: `close_spinner_always`); a circle whose inside is full of edges is
//!    clutter, not a spinner.
//! 10. Penalties: a long line passing through a candidate (tower, mast) lowers its confidence;
//!     a supporting line that continues collinearly beyond the candidate (horizon or field border
//!     hidden by the turbine) is no blade.
//! 11. Ranking (`ranker.rs`): the best candidate by the learned score of its features, reported
//!     at `ranker.min_score`; with `ranker.ranking = "rules"`, by the confidence of steps 6–10,
//!     then support, reported at `min_confidence`.

use std::time::Instant;

use opencv::core::{self, Mat};
use opencv::imgproc;
use opencv::prelude::*;

use crate::blade::{partner_axis, Gradients, PartnerSearch};
use crate::geometry::{self, Segment, P2};
use crate::hough::HoughSettings;
use crate::params::{DefaultParams, Ranking};
use crate::spinner::{find_circles, CircleSearch, EdgePoint};
use crate::tower::{fit_tower, fit_tower_one_edge, scan_tower_edges, GradPlane};
use crate::{us_since, Considered, DetectError, Found, Hints, LineKind, Scratch};

/// Number of bins of the gradient-magnitude histogram: the Sobel 3×3 L1 magnitude of 8-bit
/// images is at most 4·255·2 = 2040.
const GRAD_BINS: usize = 2048;
/// Roll search step (degrees) when no roll hint is given.
const ROLL_STEP_DEG: f64 = 1.0;
/// Lines within this of vertical (degrees, after a trial roll) count for the roll search.
const ROLL_VERTICAL_TOL_DEG: f64 = 1.5;
/// A candidate within this fraction of `spinner_max_offset_frac` of a searched one reuses its
/// spinner circles.
const SPINNER_REUSE_OF_OFFSET: f64 = 0.5;
/// A circle lies inside another when it reaches at most this far (working px) beyond its rim.
const SPINNER_NEST_TOL_PX: f64 = 1.0;
/// Tower edges tried as seeds of the two-edge tower fit, longest first.
const TOWER_SEEDS: usize = 4;
/// Number of vote peaks examined in detail.
const MAX_PEAKS: usize = 6;
/// Blades of the rotor (the thesis's turbines and practically every utility-scale one): the
/// strongest this many blade groups make a candidate's rotor, more are penalised.
const ROTOR_BLADES: usize = 3;
/// A supporting line may point past the candidate by this angle (degrees) on top of the fixed
/// distance tolerance: the blade edges sit half a chord off the blade axis.
const SUPPORT_ANGLE_DEG: f64 = 12.0;

/// Sizes a tracker's distance lets the detector expect, working px.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Expected<'a> {
    /// Tower width just under the nacelle.
    pub tower_width: Option<f64>,
    /// Spinner radius.
    pub spinner_radius: Option<f64>,
    /// Image scale at the hub's depth, px per metre.
    pub px_per_m: Option<f64>,
    /// The camera and turbine sizes that turn a spinner's radius into a tower width.
    pub optics: Option<Optics>,
    /// The learned hub heatmap of the frame (`hub_heat`).
    pub heat: Option<&'a crate::heat::Heatmap>,
}

/// Focal length (working px) and the turbine's known sizes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Optics {
    /// Focal length, working px.
    pub focal_px: f64,
    /// Spinner radius, m.
    pub spinner_radius_m: f64,
    /// Tower diameter just under the nacelle, m.
    pub tower_top_diameter_m: f64,
    /// Horizontal distance from the hub back to the tower axis, m.
    pub hub_tower_gap_m: f64,
}

impl Optics {
    /// The tower width (working px) a spinner of radius `r` px implies: the spinner gives the
    /// hub's distance `f·R/r`, the tower stands `hub_tower_gap_m` farther. `None` for r ≤ 0.
    pub fn tower_width_for_spinner(&self, r: f64) -> Option<f64> {
        (r > 0.0).then(|| {
            self.focal_px * self.tower_top_diameter_m
                / (self.focal_px * self.spinner_radius_m / r + self.hub_tower_gap_m)
        })
    }
}

/// Run the default pipeline on the working image, with the sizes `expected` from the tracker's
/// distance (if any).
pub(crate) fn run(
    p: &DefaultParams,
    small: &Mat,
    s: &mut Scratch,
    hints: &Hints,
    expected: Expected<'_>,
) -> Result<Found, DetectError> {
    let t = Instant::now();
    imgproc::spatial_gradient(small, &mut s.dx, &mut s.dy, 3, core::BORDER_DEFAULT)?;
    let high = adaptive_high(p, &s.dx, &s.dy, &mut s.hist)?;
    imgproc::canny_derivative(
        &s.dx,
        &s.dy,
        &mut s.edges,
        p.canny_low_ratio * high,
        high,
        false,
    )?;
    let edge_count = core::count_non_zero(&s.edges)? as u32;
    let edges_us = us_since(t);

    let (ew, eh) = (s.edges.cols() as usize, s.edges.rows() as usize);
    let img = EdgeImage {
        edges: s.edges.data_typed::<u8>()?,
        dx: s.dx.data_typed::<i16>()?,
        dy: s.dy.data_typed::<i16>()?,
        width: ew,
        height: eh,
    };
    let h = eh as f64;
    let w = ew as f64;
    let settings = HoughSettings {
        rho: p.hough_rho_px,
        theta_deg: p.hough_theta_deg,
        threshold: (p.hough_threshold_frac * h).round().max(1.0) as u32,
        min_length: p.hough_min_length_frac * h,
        max_gap: p.hough_max_gap_frac * h,
        orientation_tol_deg: p.hough_orientation_tol_deg,
    };
    let (hough, segments, pts) = (&mut s.hough, &mut s.segments, &mut s.edge_points);
    // Without a prediction the close-range search reads every edge point of the frame anyway
    // (unless the tracker's distance rules close spinners out): then the searches around
    // candidates take theirs from the same list.
    let (close_min_r, close_max_r) = close_spinner_radii(p, h, expected.spinner_radius);
    let share =
        hints.predicted_hub_px.is_none() && p.close_spinner_always && close_max_r > close_min_r;
    let mut whole = EdgePointCache {
        points: &mut s.all_edge_points,
        ready: false,
        share,
    };
    std::thread::scope(|scope| {
        // The spinner around the tracker's predicted hub needs only the edges, so it is searched
        // on a second thread while this one runs Hough and the geometry; the first candidate
        // near the prediction takes its circles, as a candidate near an already searched one
        // does in `recognise`.
        let img = &img;
        let mut ahead = hints.predicted_hub_px.map(|c| {
            (
                c,
                scope.spawn(move || {
                    search_circles(p, img, c, h, expected.spinner_radius, &mut Vec::new(), None)
                }),
            )
        });
        let t = Instant::now();
        hough.run(img.edges, img.dx, img.dy, ew, eh, &settings, segments);
        let hough_us = us_since(t);

        let t = Instant::now();
        let line_count = segments.len() as u32;
        let segs = merge_collinear(p, segments, h);
        log::trace!(
            "hough {} merged {} high {high} longest {:?}",
            segments.len(),
            segs.len(),
            segs.iter().take(5).collect::<Vec<_>>()
        );
        let reuse = spinner_reuse_px(p, h);
        let mut search = |q: CircleQuery| -> Result<Vec<[f64; 4]>, DetectError> {
            // Only before acquisition: with a tracker's prediction the search runs when nothing
            // else was found, and the heatmap's peak may then be what misled it.
            let heat = expected.heat.filter(|_| hints.predicted_hub_px.is_none());
            let CircleQuery::Around(c) = q else {
                return Ok(search_close_circles(
                    p,
                    img,
                    h,
                    expected.spinner_radius,
                    heat,
                    &mut whole,
                    pts,
                ));
            };
            match ahead.take_if(|(q, _)| geometry::dist(*q, c) <= reuse) {
                // A panic there is a bug here: carry it on.
                Some((_, job)) => Ok(job.join().unwrap_or_else(|e| std::panic::resume_unwind(e))),
                None => Ok(search_circles(
                    p,
                    img,
                    c,
                    h,
                    expected.spinner_radius,
                    pts,
                    whole.shared(img),
                )),
            }
        };
        let grad = Gradients {
            x: GradPlane {
                data: img.dx,
                width: ew,
                height: eh,
            },
            y: GradPlane {
                data: img.dy,
                width: ew,
                height: eh,
            },
        };
        let mut found = recognise(p, &segs, w, h, hints, &mut search, Some(&grad), expected)?;
        found.line_count = line_count;
        found.edge_count = edge_count;
        found.edges_us = edges_us;
        found.hough_us = hough_us;
        found.geometry_us = us_since(t);
        Ok(found)
    })
}

/// The edge points of the whole working image, collected at most once per frame.
struct EdgePointCache<'a> {
    points: &'a mut Vec<EdgePoint>,
    ready: bool,
    /// The searches around candidates select their points from this list (else each collects
    /// its own box).
    share: bool,
}

impl EdgePointCache<'_> {
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

/// The Canny edge image and its Sobel gradients, row-major (working px).
struct EdgeImage<'a> {
    edges: &'a [u8],
    dx: &'a [i16],
    dy: &'a [i16],
    width: usize,
    height: usize,
}

/// A candidate this close (working px) to an already searched one takes its circles: the search
/// box of the first covers most of the second's.
fn spinner_reuse_px(p: &DefaultParams, h: f64) -> f64 {
    SPINNER_REUSE_OF_OFFSET * p.spinner_max_offset_frac * h
}

/// Spinner candidates around `c`: circles `[x, y, r, rim coverage]` (working px, best covered
/// first) among the Canny edge pixels in a square of half side `spinner_search_frac · h`, see
/// [`crate::spinner`].
/// With an `expected` radius only the radii of the `spinner_hint_radius_*` window around it are
/// searched, and only the edge pixels such circles can reach are collected.
/// `all`: every edge point of the image in row order, to select the box's from (else they are
/// collected from `img` into `pts`).
fn search_circles(
    p: &DefaultParams,
    img: &EdgeImage<'_>,
    c: P2,
    h: f64,
    expected: Option<f64>,
    pts: &mut Vec<EdgePoint>,
    all: Option<&[EdgePoint]>,
) -> Vec<[f64; 4]> {
    let (min_r, max_r) = spinner_radii(p, h, expected);
    let off = p.spinner_max_offset_frac * h;
    let half = (p.spinner_search_frac * h).min(off + max_r + p.spinner_cell_px);
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
    };
    find_circles(pts, &cs)
}

/// The Canny edge pixels of the box `[x0, y0, x1, y1)` with their unit gradient directions.
fn edge_points(img: &EdgeImage<'_>, [x0, y0, x1, y1]: [i32; 4], pts: &mut Vec<EdgePoint>) {
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
fn select_points(all: &[EdgePoint], [x0, y0, x1, y1]: [i32; 4], pts: &mut Vec<EdgePoint>) {
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
    p: &DefaultParams,
    img: &EdgeImage<'_>,
    h: f64,
    expected: Option<f64>,
    heat: Option<&crate::heat::Heatmap>,
    whole: &mut EdgePointCache<'_>,
    pts: &mut Vec<EdgePoint>,
) -> Vec<[f64; 4]> {
    let (min_r, max_r) = close_spinner_radii(p, h, expected);
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
    };
    find_circles(pts, &cs)
}

/// Radii `[min, max]` the close-range search looks for (working px): at least
/// `close_spinner_radius_frac · h`, and with a tracker's distance only the radii it allows (none
/// when the hub is far).
fn close_spinner_radii(p: &DefaultParams, h: f64, expected: Option<f64>) -> (f64, f64) {
    let (lo, max_r) = spinner_radii(p, h, expected);
    (lo.max(p.close_spinner_radius_frac * h), max_r)
}

/// Radii `[min, max]` the spinner step searches (working px): the configured limits, narrowed
/// to the `spinner_hint_radius_*` window around an `expected` radius. An empty range (min ≥ max)
/// means the expected spinner is too small or too large to search for.
fn spinner_radii(p: &DefaultParams, h: f64, expected: Option<f64>) -> (f64, f64) {
    let (lo, hi) = (p.spinner_min_radius_px, p.spinner_max_radius_frac * h);
    match expected.filter(|r| p.spinner_hint_radius_lo > 0.0 && r.is_finite() && *r > 0.0) {
        Some(r) => (
            lo.max(p.spinner_hint_radius_lo * r),
            hi.min(p.spinner_hint_radius_hi * r),
        ),
        None => (lo, hi),
    }
}

/// High Canny threshold: the `canny_high_percentile` of the L1 gradient magnitude, clamped.
/// Every other pixel of every other row is counted: 30 000 samples at 480×270 pin a percentile
/// as well as all 130 000 do, at a quarter of the cost.
fn adaptive_high(
    p: &DefaultParams,
    dx: &Mat,
    dy: &Mat,
    hist: &mut Vec<u32>,
) -> Result<f64, DetectError> {
    hist.clear();
    hist.resize(GRAD_BINS, 0);
    let mut n = 0u64;
    for r in (0..dx.rows()).step_by(2) {
        let (rx, ry) = (dx.at_row::<i16>(r)?, dy.at_row::<i16>(r)?);
        for (a, b) in rx.iter().zip(ry).step_by(2) {
            let m = (a.unsigned_abs() as usize + b.unsigned_abs() as usize).min(GRAD_BINS - 1);
            hist[m] += 1;
            n += 1;
        }
    }
    let target = (p.canny_high_percentile * n as f64) as u64;
    let mut acc = 0u64;
    let mut level = GRAD_BINS - 1;
    for (i, c) in hist.iter().enumerate() {
        acc += *c as u64;
        if acc >= target {
            level = i;
            break;
        }
    }
    Ok((level as f64).clamp(p.canny_high_min, p.canny_high_max))
}

/// Passes of [`merge_collinear_once`] at most: each pass can only join pieces that the previous
/// one grew toward each other, and two passes settle practically every image.
const MERGE_PASSES: usize = 4;

/// Merge collinear segments until no two merge any more (at most [`MERGE_PASSES`] passes).
/// One greedy pass leaves pieces of one line apart when a piece grew toward another only
/// after that one was placed: a horizon cut by the tower stayed in pieces too short to be
/// seen as a horizon, and one of them passed for a blade at hub height.
pub(crate) fn merge_collinear(p: &DefaultParams, input: &[Segment], h: f64) -> Vec<Segment> {
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
fn merge_collinear_once(p: &DefaultParams, input: &[Segment], h: f64) -> Vec<Segment> {
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

/// The roll (degrees) in ±`roll_search_deg` that makes the most line length vertical.
pub(crate) fn search_roll(p: &DefaultParams, segs: &[Segment]) -> f64 {
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

/// Horizon/ridge candidates: long and near horizontal after roll compensation.
pub(crate) fn is_horizon(p: &DefaultParams, s: &Segment, w: f64, roll_deg: f64) -> bool {
    s.length() >= p.horizon_min_length_frac * w
        && (90.0 - geometry::roll_compensated_tilt_deg(s, roll_deg).abs()) <= p.horizon_max_tilt_deg
}

/// Lines that may be blade or tower edges: all but horizon candidates ([`is_horizon`]), except
/// that a horizon candidate pairing into a slender band narrowing by `horizon_band_min_taper`
/// is a blade lying level. A blade lying level is as long and flat as a horizon, but its two
/// edges pair; a horizon is one line, a road or field strip a band of even width (rendered
/// flights at 30 m lost the level blade as "horizon", and two blade roots at the tower top
/// then outscored the hub).
pub(crate) fn usable_lines(
    p: &DefaultParams,
    segs: &[Segment],
    w: f64,
    h: f64,
    roll_deg: f64,
) -> Vec<bool> {
    let mut usable: Vec<bool> = segs
        .iter()
        .map(|s| !is_horizon(p, s, w, roll_deg))
        .collect();
    if p.horizon_band_min_taper > 0.0 && usable.iter().any(|u| !u) {
        for b in pair_edges(p, segs, &vec![true; segs.len()], h) {
            let taper = b.width[0].max(b.width[1]) / b.width[0].min(b.width[1]).max(1e-9);
            if (!usable[b.edges[0]] || !usable[b.edges[1]]) && taper >= p.horizon_band_min_taper {
                usable[b.edges[0]] = true;
                usable[b.edges[1]] = true;
            }
        }
    }
    usable
}

/// Intersections of pairs of long, non-parallel segments that lie just beyond an end of both,
/// with weight `min(len)`.
pub(crate) fn proposals(
    p: &DefaultParams,
    segs: &[Segment],
    usable: &[bool],
    w: f64,
    h: f64,
) -> Vec<(P2, f64)> {
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

/// A band found from two paired edges: a blade (or the tower) with its axis.
#[derive(Debug, Clone, Copy)]
pub(crate) struct BandAxis {
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
pub(crate) fn pair_edges(
    p: &DefaultParams,
    segs: &[Segment],
    usable: &[bool],
    h: f64,
) -> Vec<BandAxis> {
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

/// Intersections of pairs of band axes that lie beyond the nearer end of both within their
/// reach, weighted `axis_proposal_weight · min(axis length)`.
pub(crate) fn axis_proposals(
    p: &DefaultParams,
    axes: &[BandAxis],
    w: f64,
    h: f64,
) -> Vec<(P2, f64)> {
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

/// The axis ends short of `c` (not passing through it), within reach, and its line passes near `c`.
fn axis_points_at(p: &DefaultParams, a: &BandAxis, c: P2, h: f64, spinner_r: f64) -> bool {
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

/// Peaks of the proposal density: grid vote with `cell` size, 3×3 sum, then the weighted mean
/// of the proposals around each local maximum.
pub(crate) fn peaks(
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

/// A blade around a candidate: member lines, mean direction, total length.
#[derive(Debug, Clone)]
pub(crate) struct Blade {
    pub lines: Vec<usize>,
    pub angle_deg: f64,
    pub weight: f64,
    /// The longest band axis among the blade's paired edges.
    pub axis: Option<Segment>,
}

/// Everything evaluated for one hub candidate.
#[derive(Debug, Clone, Default)]
struct Candidate {
    centre: P2,
    blades: Vec<Blade>,
    rejected: Vec<usize>,
    tower: Vec<usize>,
    /// Reported confidence, at most 1.
    confidence: f64,
    /// The confidence before capping, for ranking: a candidate with every cue and a spinner
    /// beats one with every cue but the spinner.
    score: f64,
    support: f64,
    spinner: Option<[f64; 3]>,
    /// What the learned ranker sees ([`crate::ranker`]).
    features: crate::ranker::Features,
}

/// Lines supporting a hub at `c`: near end within reach, line pointing at `c`.
fn support_lines(
    p: &DefaultParams,
    segs: &[Segment],
    usable: &[bool],
    c: P2,
    h: f64,
    spinner_r: f64,
) -> Vec<usize> {
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
            s.line_distance(c) <= (tol0 + tan * d_end).max(spinner_r)
                && !continues_beyond(p, segs, usable, i, c, h)
        })
        .collect()
}

/// Usable lines passing within the support reach of `c` that are neither among its supporting
/// `lines` nor its `tower`: texture, wires, field borders around a false candidate.
#[allow(clippy::too_many_arguments)]
fn clutter_lines(
    p: &DefaultParams,
    segs: &[Segment],
    usable: &[bool],
    c: P2,
    h: f64,
    spinner_r: f64,
    lines: &[usize],
    tower: &[usize],
) -> usize {
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
fn continues_beyond(
    p: &DefaultParams,
    segs: &[Segment],
    usable: &[bool],
    i: usize,
    c: P2,
    h: f64,
) -> bool {
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
fn group_blades(p: &DefaultParams, segs: &[Segment], lines: &[usize], c: P2) -> Vec<Blade> {
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

/// Tower lines for a hub at `c`: near vertical after roll, top end not far below `c`,
/// horizontally close, extending downward. "Not far" scales with the spinner radius
/// `spinner_r` (0: none) at close range, where the nacelle and tower grow past the fixed limits.
fn tower_lines(
    p: &DefaultParams,
    segs: &[Segment],
    c: P2,
    h: f64,
    roll_deg: f64,
    spinner_r: f64,
) -> Vec<usize> {
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

/// The blade has lines on both sides of its axis ray from `c` (both edges of the band).
fn is_paired(segs: &[Segment], b: &Blade, c: P2) -> bool {
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
fn rotor_geometry_ok(p: &DefaultParams, blades: &[Blade]) -> bool {
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

/// Evaluate a hub candidate at `c`; `spinner`: a spinner circle `[x, y, r]` centred at `c`.
#[allow(clippy::too_many_arguments)]
fn evaluate(
    p: &DefaultParams,
    segs: &[Segment],
    usable: &[bool],
    axes: &[BandAxis],
    c: P2,
    h: f64,
    roll_deg: f64,
    hints: &Hints,
    spinner: Option<[f64; 3]>,
    partner: &dyn Fn(&Segment, P2) -> Option<Segment>,
) -> Candidate {
    let spinner_r = spinner.map_or(0.0, |k| k[2]);
    let mut lines = support_lines(p, segs, usable, c, h, spinner_r);

    let supporting: Vec<&BandAxis> = axes
        .iter()
        .filter(|a| axis_points_at(p, a, c, h, spinner_r))
        .collect();
    for a in &supporting {
        for e in a.edges {
            if !lines.contains(&e) {
                lines.push(e);
            }
        }
    }
    let mut blades = group_blades(p, segs, &lines, c);
    for a in &supporting {
        if let Some(b) = blades
            .iter_mut()
            .find(|b| b.lines.contains(&a.edges[0]) && b.lines.contains(&a.edges[1]))
        {
            if b.axis.is_none_or(|x| x.length() < a.axis.length()) {
                b.axis = Some(a.axis);
            }
        }
    }
    // The fixed window here: a window grown with the spinner takes the edges of a blade
    // pointing down for tower lines, and the blade is then dropped as "the tower itself".
    let tower = tower_lines(p, segs, c, h, roll_deg, 0.0);
    // A "blade" pointing straight down along the tower is the tower itself.
    let down = 180.0 - roll_deg;
    let mut rejected = Vec::new();
    blades.retain(|b| {
        let is_tower = geometry::ang_dist(b.angle_deg, down) <= p.tower_max_tilt_deg
            && b.lines.iter().all(|i| tower.contains(i));
        if is_tower {
            rejected.extend(b.lines.iter().copied());
        }
        !is_tower
    });
    // A rotor has three blades: with four or more, one pointing straight down along which a
    // tower line runs is the tower, even when some of its lines are not tower lines (a short
    // piece of a tower edge, the nacelle's underside, the shadow edge). Without this the true
    // hub loses to a point lower on the tower, where ground lines behind it pass for blades.
    if blades.len() > ROTOR_BLADES {
        let down_blade = blades
            .iter()
            .enumerate()
            .filter(|(_, b)| {
                geometry::ang_dist(b.angle_deg, down) <= p.tower_max_tilt_deg
                    && b.lines.iter().any(|i| tower.contains(i))
            })
            .min_by(|(_, a), (_, b)| {
                geometry::ang_dist(a.angle_deg, down)
                    .total_cmp(&geometry::ang_dist(b.angle_deg, down))
            })
            .map(|(k, _)| k);
        if let Some(k) = down_blade {
            rejected.extend(blades.remove(k).lines);
        }
    }
    // Two blades nearly opposite are one straight line through the candidate; when one of them
    // points down the tower, that one is the tower (a blade pointing up stands above it).
    let points_down = |b: &Blade| geometry::ang_dist(b.angle_deg, down) <= p.tower_max_tilt_deg;
    let opposite: Vec<usize> = (0..blades.len())
        .filter(|&i| {
            (0..blades.len()).any(|j| {
                j != i
                    && geometry::ang_dist(blades[i].angle_deg, blades[j].angle_deg)
                        >= p.blade_max_separation_deg
                    && (points_down(&blades[i]) || !points_down(&blades[j]))
            })
        })
        .collect();
    for &k in opposite.iter().rev() {
        rejected.extend(blades.remove(k).lines);
    }
    // Weak blades (total length below one minimum Hough segment) are noise.
    let min_weight = p.candidate_min_length_frac * h;
    blades.retain(|b| {
        let keep = b.weight >= min_weight;
        if !keep {
            rejected.extend(b.lines.iter().copied());
        }
        keep
    });
    let nb = blades.len();
    let through = nb >= 2 && passes_through(p, segs, usable, c, h);
    let mut conf = match nb {
        0 | 1 => 0.0,
        2 if !tower.is_empty() && hidden_blade_down(p, &blades, down) => p.conf_three_blades,
        2 => p.conf_two_blades,
        _ => p.conf_three_blades,
    };
    if nb >= 2 {
        if !tower.is_empty() {
            conf += p.conf_tower;
        }
        if rotor_geometry_ok(p, &blades) {
            conf += p.conf_geometry;
        }
        let band = |b: &Blade| {
            b.axis.is_some()
                || is_paired(segs, b, c)
                || (p.paired_by_partner && one_sided_axis(segs, b, c, partner).is_some())
        };
        if blades.iter().filter(|b| band(b)).count() >= 2 {
            conf += p.conf_paired;
        }
        conf -= p.conf_extra_blade_penalty * nb.saturating_sub(ROTOR_BLADES) as f64;
        if spinner.is_some() {
            conf += p.conf_spinner;
        }
        if through {
            conf -= p.conf_through_penalty;
        }
        if let Some(pred) = hints.predicted_hub_px {
            if geometry::dist(pred, c) <= p.prediction_radius_frac * h {
                conf += p.prediction_bonus;
            }
        }
    }
    if spinner_r > 0.0 && spinner_r >= p.close_spinner_radius_frac * h {
        conf = conf.max(p.conf_close_spinner);
    }
    let support = blades.iter().take(ROTOR_BLADES).map(|b| b.weight).sum();
    let cues = crate::ranker::Cues {
        blades: nb,
        tower_lines: tower.len(),
        hidden_blade_down: nb == 2 && !tower.is_empty() && hidden_blade_down(p, &blades, down),
        geometry_ok: nb >= 2 && rotor_geometry_ok(p, &blades),
        paired: blades
            .iter()
            .filter(|b| b.axis.is_some() || is_paired(segs, b, c))
            .count(),
        spinner_radius: spinner_r,
        passes_through: through,
        near_prediction: hints
            .predicted_hub_px
            .is_some_and(|q| geometry::dist(q, c) <= p.prediction_radius_frac * h),
        blade_weights: blades.iter().take(ROTOR_BLADES).map(|b| b.weight).collect(),
        blade_angles: blades
            .iter()
            .take(ROTOR_BLADES)
            .map(|b| b.angle_deg)
            .collect(),
        rejected_lines: rejected.len(),
        rule_score: conf,
        clutter_lines: clutter_lines(p, segs, usable, c, h, spinner_r, &lines, &tower),
        banded_blades: blades.iter().filter(|b| b.axis.is_some()).count(),
        tower_top_below: tower
            .iter()
            .flat_map(|&i| [segs[i].a[1], segs[i].b[1]])
            .min_by(f64::total_cmp)
            .map(|top| top - c[1]),
        image_lines: usable.iter().filter(|&&u| u).count(),
        image_height: h,
    };
    let features = crate::ranker::features(&cues);
    Candidate {
        centre: c,
        blades,
        rejected,
        tower,
        confidence: conf.min(1.0),
        score: conf,
        support,
        spinner,
        features,
    }
}

/// The rotor's third blade, not seen, would point straight down (`down`, degrees from up
/// clockwise): opposite the bisector of the two seen blades, which are about 120° apart.
fn hidden_blade_down(p: &DefaultParams, blades: &[Blade], down: f64) -> bool {
    let [a, b] = [blades[0].angle_deg, blades[1].angle_deg];
    if p.hidden_blade_tol_deg <= 0.0
        || (geometry::ang_dist(a, b) - p.blade_target_deg).abs() > p.blade_sep_tol_deg
    {
        return false;
    }
    let third = geometry::circular_mean_deg(&[a, b], None) + 180.0;
    geometry::ang_dist(third, down) <= p.hidden_blade_tol_deg
}

/// A long usable line passes through `c` (not ending near it): `c` lies on a tower, mast or wire.
pub(crate) fn passes_through(
    p: &DefaultParams,
    segs: &[Segment],
    usable: &[bool],
    c: P2,
    h: f64,
) -> bool {
    let min_len = p.candidate_min_length_frac * h;
    let margin = p.through_margin_frac * h;
    segs.iter().zip(usable).any(|(s, &u)| {
        if !u || s.length() < min_len || s.line_distance(c) > p.through_dist_frac * h {
            return false;
        }
        let t = s.project_t(c) * s.length();
        t >= margin && s.length() - t >= margin
    })
}

/// Least-squares point closest to all lines, each blade's lines together weighing 1. With at
/// least two blades of known axis, their axes alone (the edges meet at the spinner rim, the
/// axes at its centre). A blade seen by one edge only has its axis from `partner` (the partner
/// edge in the image, see `blade.rs`) when that finds one.
fn refine(
    segs: &[Segment],
    blades: &[Blade],
    centre: P2,
    partner: &dyn Fn(&Segment, P2) -> Option<Segment>,
) -> Option<P2> {
    let axes: Vec<(Segment, f64)> = blades
        .iter()
        .take(ROTOR_BLADES)
        .filter_map(|b| {
            b.axis
                .or_else(|| one_sided_axis(segs, b, centre, partner))
                .map(|a| (a, 1.0))
        })
        .collect();
    if axes.len() >= 2 {
        if let Some(x) = geometry::lines_nearest_point(&axes) {
            return Some(x);
        }
    }
    let mut lines: Vec<(Segment, f64)> = Vec::new();
    for bl in blades.iter().take(ROTOR_BLADES) {
        if let Some(axis) = bl
            .axis
            .or_else(|| one_sided_axis(segs, bl, centre, partner))
        {
            lines.push((axis, 1.0));
            continue;
        }
        // Each side of the blade (each edge) weighs half, so a blade seen with both edges pulls
        // toward its axis, not toward its longer edge.
        let d = geometry::dir_from_up_cw(bl.angle_deg);
        let side = |s: &Segment| {
            let m = s.midpoint();
            d[0] * (m[1] - centre[1]) - d[1] * (m[0] - centre[0]) > 0.0
        };
        let tot = |right: bool| {
            bl.lines
                .iter()
                .filter(|&&i| side(&segs[i]) == right)
                .map(|&i| segs[i].length())
                .sum::<f64>()
        };
        let (tr, tl) = (tot(true), tot(false));
        let sides = (tr > 0.0) as u32 + (tl > 0.0) as u32;
        for &i in &bl.lines {
            let s = &segs[i];
            let w = s.length() / if side(s) { tr } else { tl }.max(1e-9) / sides.max(1) as f64;
            lines.push((*s, w));
        }
    }
    geometry::lines_nearest_point(&lines)
}

/// The axis of a blade whose lines all lie on one side of it (one edge seen), from the partner
/// of its longest line.
fn one_sided_axis(
    segs: &[Segment],
    b: &Blade,
    centre: P2,
    partner: &dyn Fn(&Segment, P2) -> Option<Segment>,
) -> Option<Segment> {
    if is_paired(segs, b, centre) {
        return None;
    }
    let longest = b
        .lines
        .iter()
        .max_by(|&&i, &&j| segs[i].length().total_cmp(&segs[j].length()))?;
    partner(&segs[*longest], centre)
}

/// Whether a band's `axis` (from its top down) lies, halfway down, within `tol` px of one of
/// the `rays` (blade angles, degrees clockwise from up) from `hub`: that band is a blade (or a
/// blade merged with a tower edge), not the tower.
fn axis_along_a_ray(axis: &Segment, hub: P2, rays: &[f64], tol: f64) -> bool {
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
/// for a detected hub only) the gradient is scanned for edges below the hub. `tower_width`:
/// the width expected from a tracker's distance; with it one edge alone places the tower.
#[allow(clippy::too_many_arguments)]
fn measure_tower(
    p: &DefaultParams,
    segs: &[Segment],
    b: &Candidate,
    g: &GradPlane<'_>,
    tower_width: Option<f64>,
    optics: Option<&Optics>,
    hub_distance_m: Option<f64>,
    roll_deg: f64,
    h: f64,
    detected: bool,
) -> Option<(crate::tower::TowerFit, f64)> {
    // With a blade pointing down, the tower hides behind it and the band seen below the hub
    // is that blade: its axis runs through the hub.
    let down = 180.0 - roll_deg;
    let near_down = |a: f64| geometry::ang_dist(a, down) <= p.tower_blade_down_tol_deg;
    let blade_down = b.blades.iter().any(|bl| near_down(bl.angle_deg))
        || b.blades
            .first()
            .is_some_and(|bl| (0..3).any(|k| near_down(bl.angle_deg + 120.0 * k as f64)));
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
    // Only one edge in sight (the other behind a blade pointing down): with the width expected
    // from the tracker's distance, that edge places the axis on the hub's side of it (the
    // blade hangs from the hub; without one a lone edge may be the tower's near or far one).
    // Tried last, only at close range (farther out the lone edge was as often the blade's:
    // rendered flights, 15–25 m), and only with edges more upright than a blade's beside the
    // tower, most upright first.
    let one = |seeds: &[Segment]| {
        let e = tower_width.filter(|_| {
            blade_down && hub_distance_m.is_some_and(|d| d <= p.tower_one_edge_max_distance_m)
        })?;
        let tilt = |s: &Segment| geometry::roll_compensated_tilt_deg(s, roll_deg).abs();
        let mut upright: Vec<&Segment> = seeds
            .iter()
            .take(TOWER_SEEDS)
            .filter(|s| tilt(s) <= p.tower_one_edge_max_tilt_deg)
            .collect();
        upright.sort_by(|x, y| tilt(x).total_cmp(&tilt(y)));
        upright
            .into_iter()
            .filter_map(|s| fit_tower_one_edge(g, s, e, b.centre[0]))
            .find(|f| !is_blade(f))
    };
    // Seeds: the tower lines in a window grown with the spinner (at close range the tower
    // top and edges lie beyond the fixed one).
    let mut hough: Vec<Segment> = tower_lines(p, segs, b.centre, h, roll_deg, spinner_r)
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
    both(&scanned)
        .map(|fit| (fit, top))
        .or_else(|| one(&hough).map(|fit| (fit, hough_top)))
        .or_else(|| one(&scanned).map(|fit| (fit, top)))
}

/// How near a candidate must lie to the heatmap's peak to stand for it, working px: the
/// `hub_heat_radius_cells` neighbourhood in the larger of the cell's two sides.
fn heat_reach_px(p: &DefaultParams, heat: Option<&crate::heat::Heatmap>, w: f64, h: f64) -> f64 {
    heat.filter(|m| m.cols > 0 && m.rows > 0).map_or(0.0, |m| {
        p.hub_heat_radius_cells * (w / m.cols as f64).max(h / m.rows as f64)
    })
}

/// Steps after the Hough transform, on plain data (working px).
/// Ordering of candidates: higher uncapped confidence, then more blade support.
fn better(a: &Candidate, b: &Candidate) -> bool {
    a.score > b.score + 1e-9 || (a.score >= b.score - 1e-9 && a.support > b.support)
}

/// The learned ranker's score of `c`: log-odds that it is the hub rather than no hub at all.
fn learned_score(p: &DefaultParams, c: &Candidate) -> f64 {
    crate::ranker::score(&p.ranker.weights.to_array(), &c.features)
}

/// Final ordering of candidates by the configured ranking (`ranker.ranking`); ties go to more
/// blade support.
fn preferred(p: &DefaultParams, a: &Candidate, b: &Candidate) -> bool {
    match p.ranker.ranking {
        Ranking::Rules => better(a, b),
        Ranking::Learned => {
            let (x, y) = (learned_score(p, a), learned_score(p, b));
            x > y + 1e-9 || (x >= y - 1e-9 && a.support > b.support)
        }
    }
}

/// Whether `c` is reported as the hub, and with what confidence (0..1).
fn decision(p: &DefaultParams, c: &Candidate) -> (bool, f64) {
    match p.ranker.ranking {
        Ranking::Rules => (c.confidence >= p.min_confidence, c.confidence),
        Ranking::Learned => {
            let s = learned_score(p, c);
            (s >= p.ranker.min_score, crate::ranker::logistic(s))
        }
    }
}

/// Where a spinner circle search looks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum CircleQuery {
    /// Around a hub candidate ([`search_circles`]).
    Around(P2),
    /// Anywhere in the image, for close-range spinners only ([`search_close_circles`]).
    Close,
}

/// A spinner circle search: circles `[x, y, r, rim coverage]` (working px, best covered first).
pub(crate) type CircleFinder<'a> =
    dyn FnMut(CircleQuery) -> Result<Vec<[f64; 4]>, DetectError> + 'a;

/// The first circle near `cand` (within `spinner_max_offset_frac · h`) that at least two blades
/// start from, evaluated as a spinner-centred candidate. A larger such circle around it wins:
/// the shading of the nose cone draws circles inside the spinner's outline, and the blades
/// start at the outline (a nose-cone circle put the hub 2 % of the height high and its size
/// put the hub 50 % too far: rendered flights at 30 m).
#[allow(clippy::too_many_arguments)]
fn spinner_candidate(
    p: &DefaultParams,
    segs: &[Segment],
    usable: &[bool],
    axes: &[BandAxis],
    cand: &Candidate,
    others: &[Candidate],
    circles: &[[f64; 4]],
    h: f64,
    roll_deg: f64,
    hints: &Hints,
    expected_r: Option<f64>,
    partner: &dyn Fn(&Segment, P2) -> Option<Segment>,
) -> Option<Candidate> {
    let with_blades = circles
        .iter()
        .filter(|k| geometry::dist([k[0], k[1]], cand.centre) <= p.spinner_max_offset_frac * h)
        .map(|k| (evaluate(p, segs, usable, axes, [k[0], k[1]], h, roll_deg, hints, Some([k[0], k[1], k[2]]), partner), k[3]))
        .inspect(|(c, cov)| log::trace!("circle {:?} (rim {cov:.2}): conf {:.2} blades {:?}", c.spinner, c.confidence, c.blades.iter().map(|b| (b.angle_deg.round(), b.weight.round())).collect::<Vec<_>>()))
        .filter(|(c, _)| c.blades.len() >= 2)
        .filter(|(c, _)| {
            // Measured against the strongest blade candidate near the circle (not only the one
            // searched around: a weaker candidate between the blades finds the same circle).
            let Some(k) = c.spinner.filter(|k| k[2] <= p.spinner_kept_support_max_radius_px) else { return true };
            let centre = [k[0], k[1]];
            let strongest = others
                .iter()
                .chain(std::iter::once(cand))
                .filter(|o| o.blades.len() >= 2 && geometry::dist(o.centre, centre) <= p.spinner_max_offset_frac * h)
                .max_by(|a, b| a.support.total_cmp(&b.support))
                .unwrap_or(cand);
            let kept = kept_support(p, strongest, c);
            if kept < p.spinner_min_kept_support {
                log::trace!("circle {:?} keeps {:.0} % of the blade support: not this rotor's spinner", c.spinner, 100.0 * kept);
            }
            kept >= p.spinner_min_kept_support
        })
        .filter(|(c, _)| {
            // Small circles have the kept-support test above; their blade axes, a pixel or two
            // off each, do not place the meeting point to a fraction of their radius.
            let Some(k) = c.spinner.filter(|k| p.spinner_max_convergence_radii > 0.0 && k[2] > p.spinner_kept_support_max_radius_px) else { return true };
            let Some(off) = axes_meet_offset(segs, axes, c, partner) else { return true };
            let ok = off <= p.spinner_max_convergence_radii * k[2] + p.spinner_convergence_tol_px;
            if !ok {
                log::trace!("circle {k:?}: its blades meet {off:.1} px from its centre ({:.2} radii): not a spinner", off / k[2]);
            }
            ok
        });
    let mut with_blades: Vec<(Candidate, f64)> = with_blades.collect();
    // What the learned ranker sees of each circle: its rim, and where its blades' axes meet.
    for (c, cov) in with_blades.iter_mut() {
        c.features[crate::ranker::SPINNER_COVERAGE] = *cov;
        if let Some(k) = c
            .spinner
            .filter(|k| k[2] > p.spinner_kept_support_max_radius_px)
        {
            c.features[crate::ranker::SPINNER_AXES_OFFSET] =
                axes_meet_offset(segs, axes, c, partner).map_or(0.0, |off| (off / k[2]).min(2.0));
        }
    }
    // Circles are best covered first. A near tie goes to the size the tracker's distance
    // expects, or without one to the predicted hub: the rim alone does not tell them apart.
    let tie = p.spinner_tie_ratio * with_blades.first()?.1;
    let off = |c: &Candidate| match (expected_r, hints.predicted_hub_px, c.spinner) {
        (Some(e), _, Some(k)) if e > 0.0 => (k[2] / e).ln().abs(),
        (_, Some(q), _) => geometry::dist(c.centre, q),
        _ => 0.0,
    };
    let pick = (0..with_blades.len())
        .filter(|&i| p.spinner_tie_ratio < 1.0 && with_blades[i].1 >= tie)
        .min_by(|&i, &j| {
            off(&with_blades[i].0)
                .total_cmp(&off(&with_blades[j].0))
                .then(i.cmp(&j))
        })
        .unwrap_or(0);
    let (first, first_cov) = with_blades.remove(pick);
    let inner = first.spinner?;
    // A circle round the best-covered one is the spinner's silhouette round a ring on its
    // face, if its rim is about as well covered; a less covered one is drawn by blade edges
    // crossing near the spinner (a rendered flight at 12 m: rim 0.45 round 0.7, 1.26x the
    // radius, the hub 5 % of the image height off).
    let encloses = |(c, cov): &(Candidate, f64)| {
        *cov >= p.spinner_nest_min_coverage_ratio * first_cov
            && c.spinner.is_some_and(|k| {
                k[2] > inner[2]
                    && geometry::dist([k[0], k[1]], [inner[0], inner[1]]) + inner[2]
                        <= k[2] + SPINNER_NEST_TOL_PX
            })
    };
    Some(
        with_blades
            .into_iter()
            .filter(encloses)
            .map(|(c, _)| c)
            .max_by(|a, b| {
                a.spinner
                    .map_or(0.0, |k| k[2])
                    .total_cmp(&b.spinner.map_or(0.0, |k| k[2]))
            })
            .unwrap_or(first),
    )
}

/// How far from the centre of `c`'s spinner circle the axes of its (up to three) strongest
/// blades meet, px; `None` without a circle or with fewer than two known axes. Axes only: a
/// blade seen by one edge is half a chord off its axis, about a spinner radius at the root,
/// which is no test of a circle of that size; a blade's axis is its band's (one of whose edges
/// it holds, whether or not the band points at this circle: that is the test) or its partner
/// edge's.
fn axes_meet_offset(
    segs: &[Segment],
    axes: &[BandAxis],
    c: &Candidate,
    partner: &dyn Fn(&Segment, P2) -> Option<Segment>,
) -> Option<f64> {
    let k = c.spinner?;
    let centre = [k[0], k[1]];
    let band_axis = |b: &Blade| {
        axes.iter()
            .find(|a| a.edges.iter().any(|e| b.lines.contains(e)))
            .map(|a| a.axis)
    };
    let known: Vec<(Segment, f64)> = c
        .blades
        .iter()
        .take(ROTOR_BLADES)
        .filter_map(|b| {
            b.axis
                .or_else(|| band_axis(b))
                .or_else(|| one_sided_axis(segs, b, centre, partner))
                .map(|a| (a, 1.0))
        })
        .collect();
    let meet = (known.len() >= 2)
        .then(|| geometry::lines_nearest_point(&known))
        .flatten()?;
    Some(geometry::dist(meet, centre))
}

/// The fraction of `cand`'s blade support (its blades' weights) that `circle`, evaluated at its
/// own centre, keeps in the same directions (within `blade_group_tol_deg`); 1 for a candidate
/// with fewer than two blades.
fn kept_support(p: &DefaultParams, cand: &Candidate, circle: &Candidate) -> f64 {
    let own: Vec<&Blade> = cand.blades.iter().take(ROTOR_BLADES).collect();
    let total: f64 = own.iter().map(|b| b.weight).sum();
    if own.len() < 2 || total <= 0.0 {
        return 1.0;
    }
    let kept: f64 = own
        .iter()
        .map(|b| {
            let seen: f64 = circle
                .blades
                .iter()
                .filter(|c| geometry::ang_dist(c.angle_deg, b.angle_deg) <= p.blade_group_tol_deg)
                .map(|c| c.weight)
                .sum();
            seen.min(b.weight)
        })
        .sum();
    kept / total
}

/// Steps after the Hough transform, on plain data (working px) except for `search`, which
/// looks for spinner circles in the image.
/// `grad` (the horizontal gradient) measures the tower from both edges ([`crate::tower`]);
/// without it the tower axis is the mean of the tower lines. `tower_width` (working px), the
/// width expected from a tracker's distance, narrows the widths a tower band may have.
#[allow(clippy::too_many_arguments)]
pub(crate) fn recognise(
    p: &DefaultParams,
    segs: &[Segment],
    w: f64,
    h: f64,
    hints: &Hints,
    search: &mut CircleFinder<'_>,
    grad: Option<&Gradients<'_>>,
    expected: Expected<'_>,
) -> Result<Found, DetectError> {
    let tower_width = expected.tower_width;
    let partner_search = PartnerSearch {
        min_width: p.blade_partner_min_width_px,
        max_width: p.blade_partner_max_width_frac * h,
        samples: p.blade_partner_samples as usize,
        min_found_frac: p.blade_partner_min_found_frac,
        min_response_ratio: p.blade_partner_response_ratio,
        max_rms_px: p.blade_partner_max_rms_px,
        max_taper: p.blade_partner_max_taper,
    };
    let partner = |s: &Segment, c: P2| grad.and_then(|g| partner_axis(g, s, c, &partner_search));
    let roll_deg = match hints.roll_rad {
        Some(r) => r.to_degrees(),
        None => search_roll(p, segs),
    };
    let mut found = Found {
        roll_used_deg: roll_deg,
        line_count: segs.len() as u32,
        ..Found::default()
    };
    let mut kinds = vec![LineKind::Other; segs.len()];
    let usable = usable_lines(p, segs, w, h, roll_deg);
    for (i, u) in usable.iter().enumerate() {
        if !u {
            kinds[i] = LineKind::Rejected;
        }
    }
    let axes = pair_edges(p, segs, &usable, h);
    let mut props = proposals(p, segs, &usable, w, h);
    let axis_props = axis_proposals(p, &axes, w, h);
    log::trace!(
        "axes {:?} axis proposals {:?}",
        axes.iter().map(|a| (a.axis, a.width)).collect::<Vec<_>>(),
        axis_props
    );
    props.extend(axis_props);
    let mut cands: Vec<Candidate> = Vec::new();
    let mut centres: Vec<P2> = peaks(&props, w, h, p.cluster_radius_frac * h, MAX_PEAKS)
        .into_iter()
        .map(|(c, _)| c)
        .collect();
    if let Some(pred) = hints.predicted_hub_px {
        centres.push(pred);
    }
    // The heatmap's peak, where no line crossing or band axis proposed anything near it.
    let heat_reach = heat_reach_px(p, expected.heat, w, h);
    if let Some((peak, prob)) = expected.heat.and_then(|m| m.peak()) {
        let c = [peak[0] * w, peak[1] * h];
        if prob >= p.hub_heat_candidate_min
            && !centres.iter().any(|q| geometry::dist(*q, c) <= heat_reach)
        {
            log::trace!("heatmap peak {c:?} ({prob:.2}) is a candidate");
            centres.push(c);
        }
    }
    let heat_at = |c: P2| {
        expected
            .heat
            .map_or(0.0, |m| m.near(c[0] / w, c[1] / h, p.hub_heat_radius_cells))
    };
    for c in centres {
        let mut cand = evaluate(
            p, segs, &usable, &axes, c, h, roll_deg, hints, None, &partner,
        );
        if cand.blades.len() >= 2 {
            if let Some(r) = refine(segs, &cand.blades, c, &partner) {
                if geometry::dist(r, c) <= p.cluster_radius_frac * h * 2.0 {
                    // Re-evaluate at the refined point so blades and tower match the output.
                    let again = evaluate(
                        p, segs, &usable, &axes, r, h, roll_deg, hints, None, &partner,
                    );
                    log::trace!(
                        "candidate {c:?} refined to {r:?}: conf {:.2} -> {:.2}",
                        cand.confidence,
                        again.confidence
                    );
                    if again.score >= cand.score {
                        cand = again;
                    }
                }
            }
        }
        if log::log_enabled!(log::Level::Trace) {
            log::trace!(
                "candidate {:?} conf {:.2} support {:.0} blades {:?} tower {}",
                cand.centre,
                cand.confidence,
                cand.support,
                cand.blades
                    .iter()
                    .map(|b| (b.angle_deg.round(), b.weight.round(), b.lines.len()))
                    .collect::<Vec<_>>(),
                cand.tower.len()
            );
        }
        cands.push(cand);
    }
    cands.sort_by(|a, b| {
        if better(a, b) {
            std::cmp::Ordering::Less
        } else if better(b, a) {
            std::cmp::Ordering::Greater
        } else {
            std::cmp::Ordering::Equal
        }
    });
    // Spinner step on the best few distinct candidates with at least two blades.
    // A candidate near an already searched one reuses its circles (the search box of the
    // first covers most of the second's).
    let mut searched: Vec<(P2, Vec<[f64; 4]>)> = Vec::new();
    let mut extra: Vec<Candidate> = Vec::new();
    let reuse = spinner_reuse_px(p, h);
    // The tracker's predicted hub is searched too, with or without blades: at close range the
    // blades leave the frame and only the spinner is left to see.
    let predicted = |c: &Candidate| {
        hints
            .predicted_hub_px
            .is_some_and(|q| geometry::dist(q, c.centre) < 1e-9)
    };
    for (k, cand) in cands
        .iter()
        .filter(|c| c.blades.len() >= 2 || predicted(c))
        .enumerate()
    {
        if k >= p.spinner_candidates && !predicted(cand) {
            continue;
        }
        let circles = match searched
            .iter()
            .find(|(q, _)| geometry::dist(*q, cand.centre) <= reuse)
        {
            Some((_, c)) => c.clone(),
            None => {
                let c = search(CircleQuery::Around(cand.centre))?;
                searched.push((cand.centre, c.clone()));
                c
            }
        };
        log::trace!("spinner search at {:?}: {:?}", cand.centre, circles);
        if let Some(mut sc) = spinner_candidate(
            p,
            segs,
            &usable,
            &axes,
            cand,
            &cands,
            &circles,
            h,
            roll_deg,
            hints,
            expected.spinner_radius,
            &partner,
        ) {
            // A circle of the size the tracker's distance expects is the spinner with more
            // certainty than blade lines meeting somewhere near it: at close range under an
            // overcast sky the lines of two blades met at the tower top, 0.15 h below the
            // hub, scored 0.9 with the tower, and the spinner, found at the expected size,
            // 0.8.
            if let (Some(e), Some(k)) = (expected.spinner_radius, sc.spinner) {
                if k[2] >= e / p.spinner_size_match_tol && k[2] <= e * p.spinner_size_match_tol {
                    sc.score += p.spinner_size_match_bonus;
                    sc.features[crate::ranker::SPINNER_SIZE_MATCH] = 1.0;
                    sc.confidence = (sc.confidence + p.spinner_size_match_bonus).min(1.0);
                }
            }
            log::trace!(
                "spinner candidate {:?} conf {:.2} blades {}",
                sc.spinner,
                sc.confidence,
                sc.blades.len()
            );
            extra.push(sc);
        }
    }
    let mut best: Option<Candidate> = None;
    for mut cand in cands.into_iter().chain(extra) {
        cand.features[crate::ranker::HUB_HEAT] = heat_at(cand.centre);
        found.candidates.push(Considered {
            hub: cand.centre,
            confidence: cand.confidence,
            features: cand.features,
        });
        if best.as_ref().is_none_or(|b| preferred(p, &cand, b)) {
            best = Some(cand);
        }
    }
    // A close spinner anywhere in the image with two blades at its rim: when nothing is
    // detected, or always (`close_spinner_always`), then every such circle being a candidate.
    // Not with a tracker's prediction: its neighbourhood was searched already, and a frame
    // missed while tracking would pay for the whole-image search.
    let always = p.close_spinner_always;
    if hints.predicted_hub_px.is_none()
        && (always || best.as_ref().is_none_or(|b| !decision(p, b).0))
    {
        let min_r = p.close_spinner_radius_frac * h;
        for k in search(CircleQuery::Close)?
            .into_iter()
            .filter(|k| k[2] >= min_r)
        {
            let mut cand = evaluate(
                p,
                segs,
                &usable,
                &axes,
                [k[0], k[1]],
                h,
                roll_deg,
                hints,
                Some([k[0], k[1], k[2]]),
                &partner,
            );
            cand.features[crate::ranker::SPINNER_COVERAGE] = k[3];
            cand.features[crate::ranker::SPINNER_AXES_OFFSET] =
                axes_meet_offset(segs, &axes, &cand, &partner)
                    .map_or(0.0, |off| (off / k[2]).min(2.0));
            cand.features[crate::ranker::HUB_HEAT] = heat_at(cand.centre);
            log::trace!(
                "close spinner {k:?}: conf {:.2} blades {}",
                cand.confidence,
                cand.blades.len()
            );
            found.candidates.push(Considered {
                hub: cand.centre,
                confidence: cand.confidence,
                features: cand.features,
            });
            if cand.blades.len() >= 2 && best.as_ref().is_none_or(|b| preferred(p, &cand, b)) {
                best = Some(cand);
                if !always {
                    break;
                }
            }
        }
    }
    if let Some(b) = best {
        found.circle = b.spinner;
        for &i in &b.rejected {
            kinds[i] = LineKind::Rejected;
        }
        for &i in &b.tower {
            kinds[i] = LineKind::Tower;
        }
        for bl in &b.blades {
            for &i in &bl.lines {
                kinds[i] = LineKind::Blade;
            }
        }
        found.blade_angles = b.blades.iter().map(|x| x.angle_deg).collect();
        (found.detected, found.confidence) = decision(p, &b);
        found.hub = b.centre;
        found.search_circle = Some([b.centre[0], b.centre[1], p.support_end_dist_frac * h]);
        match grad {
            Some(g) => {
                if let Some((fit, top_y)) = measure_tower(
                    p,
                    segs,
                    &b,
                    &g.x,
                    tower_width,
                    expected.optics.as_ref(),
                    hints.hub_distance_m,
                    roll_deg,
                    h,
                    found.detected,
                ) {
                    let row = top_y + p.tower_width_below_top_frac * h;
                    found.tower_top = fit.axis.x_at_y(top_y).map(|x| [x, top_y]);
                    found.tower_axis = Some(fit.axis);
                    // A width that was assumed is no measurement of the distance.
                    found.tower_width = if fit.one_edge {
                        None
                    } else {
                        fit.width_at(row).map(|wd| (wd, row))
                    };
                }
                if found.detected {
                    found.nacelle_end_dx = expected
                        .px_per_m
                        .and_then(|s| crate::nacelle::nacelle_end(p, &g.x, b.centre, s));
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
    found.lines = segs.iter().copied().zip(kinds).collect();
    Ok(found)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::dir_from_up_cw;

    /// The default parameters with the rules' ranking: for tests of a rule's effect on the
    /// rules' confidence (the learned ranking weighs the same cues differently).
    fn rules() -> DefaultParams {
        let mut p = DefaultParams::default();
        p.ranker.ranking = Ranking::Rules;
        p
    }

    fn no_circles(_: CircleQuery) -> Result<Vec<[f64; 4]>, DetectError> {
        Ok(Vec::new())
    }

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

    fn rotor(hub: P2, rot: f64) -> Vec<Segment> {
        let mut v = vec![
            Segment::new([hub[0] - 3.0, 269.0], [hub[0] - 2.0, hub[1] + 8.0]),
            Segment::new([hub[0] + 3.0, 269.0], [hub[0] + 2.0, hub[1] + 8.0]),
        ];
        for a in [rot, rot + 120.0, rot + 240.0] {
            v.push(ray(hub, a - 3.0, 6.0, 70.0));
            v.push(ray(hub, a + 3.0, 6.0, 70.0));
        }
        v
    }

    #[test]
    fn a_circle_keeps_the_blade_support_only_where_the_blades_radiate_from_it() {
        let p = DefaultParams::default();
        let blade = |angle_deg: f64, weight: f64| Blade {
            lines: Vec::new(),
            angle_deg,
            weight,
            axis: None,
        };
        let cand = |blades: Vec<Blade>| Candidate {
            support: blades.iter().map(|b| b.weight).sum(),
            blades,
            ..Candidate::default()
        };
        // The rotor's line candidate (seed-4 frame at 40 m, working px): blades at 309° and 67°.
        let rotor = cand(vec![blade(309.0, 325.0), blade(67.0, 198.0)]);
        // The spinner keeps both; the nacelle's rear beside it sees the same blades pass by,
        // half as long; a circle on the horizon gains a "blade" along it.
        let spinner = cand(vec![blade(309.0, 325.0), blade(67.0, 198.0)]);
        let nacelle = cand(vec![blade(312.0, 145.0), blade(64.0, 112.0)]);
        let horizon = cand(vec![blade(88.0, 424.0), blade(312.0, 145.0)]);
        assert!((kept_support(&p, &rotor, &spinner) - 1.0).abs() < 1e-9);
        let k = kept_support(&p, &rotor, &nacelle);
        assert!((k - 257.0 / 523.0).abs() < 1e-9, "{k}");
        assert!(kept_support(&p, &rotor, &horizon) < 0.3);
        // Longer blades from the circle count no more than the candidate's own.
        assert!(
            (kept_support(
                &p,
                &rotor,
                &cand(vec![blade(309.0, 900.0), blade(67.0, 198.0)])
            ) - 1.0)
                .abs()
                < 1e-9
        );
        // A candidate with one blade (the tracker's prediction at close range) checks nothing.
        assert_eq!(
            kept_support(&p, &cand(vec![blade(0.0, 100.0)]), &horizon),
            1.0
        );
    }

    #[test]
    fn finds_hub_with_horizon_through_it() {
        let p = DefaultParams::default();
        let hub = [200.0, 120.0];
        let mut segs = rotor(hub, 20.0);
        // Horizon split by the tower: two long pieces ending at the tower.
        segs.push(Segment::new([0.0, 125.0], [196.0, 125.0]));
        segs.push(Segment::new([204.0, 125.0], [479.0, 125.0]));
        let f = recognise(
            &p,
            &segs,
            480.0,
            270.0,
            &Hints {
                roll_rad: Some(0.0),
                ..Hints::default()
            },
            &mut no_circles,
            None,
            Expected::default(),
        )
        .unwrap();
        assert!(f.detected, "{f:?}");
        assert!(geometry::dist(f.hub, hub) < 3.0, "{:?}", f.hub);
        assert_eq!(f.blade_angles.len(), 3);
    }

    #[test]
    fn fourth_blade_pointing_down_the_tower_is_the_tower() {
        let p = DefaultParams::default();
        let hub = [200.0, 100.0];
        let mut segs = rotor(hub, 0.0);
        // Edges of the nacelle's shadow on the tower, 7.5° and 8.5° off vertical: they join the
        // tower lines' "blade" pointing down, and the second leans more than a tower line may.
        segs.push(ray(hub, 187.5, 8.0, 60.0));
        segs.push(ray(hub, 188.5, 8.0, 60.0));
        let f = recognise(
            &p,
            &segs,
            480.0,
            270.0,
            &Hints {
                roll_rad: Some(0.0),
                ..Hints::default()
            },
            &mut no_circles,
            None,
            Expected::default(),
        )
        .unwrap();
        assert!(f.detected, "{f:?}");
        assert!(geometry::dist(f.hub, hub) < 3.0, "{:?}", f.hub);
        let mut angles: Vec<f64> = f.blade_angles.iter().map(|a| a.round()).collect();
        angles.sort_by(f64::total_cmp);
        assert_eq!(
            angles.len(),
            3,
            "three blades, the tower is no blade: {angles:?}"
        );
        assert!(
            angles.iter().all(|a| geometry::ang_dist(*a, 180.0) > 30.0),
            "{angles:?}"
        );
    }

    #[test]
    fn a_band_along_a_blade_ray_is_that_blade_not_the_tower() {
        // `fly` seed 279 at 19 m (working px): hub (244, 126.5), a blade at 167.6°; the band
        // the partner search found runs from (254.8, 148) to (269.3, 269), along the blade.
        let hub = [244.0, 126.5];
        let band = Segment::new([254.8, 148.0], [269.3, 269.0]);
        let tol = 0.025 * 270.0;
        assert!(axis_along_a_ray(&band, hub, &[167.6], tol));
        // The tower itself, upright 3.5 px left of the hub, is no blade ...
        let tower = Segment::new([240.5, 139.0], [240.5, 269.0]);
        assert!(!axis_along_a_ray(&tower, hub, &[167.6], tol));
        // ... nor is the band without a ray, or with rays pointing elsewhere.
        assert!(!axis_along_a_ray(&band, hub, &[], tol));
        assert!(!axis_along_a_ray(&band, hub, &[192.4, 48.0], tol));
        // A ray pointing up never reaches a band below the hub.
        assert!(!axis_along_a_ray(&band, hub, &[347.6], tol));
    }

    #[test]
    // 0.4343 is the GoPro's focal length per width, not log10(e).
    #[allow(clippy::approx_constant)]
    fn a_spinner_implies_the_tower_width_from_its_own_distance() {
        // GoPro at 960 px wide (f = 417 px), the renderer's turbine.
        let o = Optics {
            focal_px: 0.4343 * 960.0,
            spinner_radius_m: 1.6,
            tower_top_diameter_m: 2.2,
            hub_tower_gap_m: 4.2,
        };
        let r_at = |d: f64| o.focal_px * 1.6 / d;
        // 38 m: the tower top, 42.2 m away, is 1.24 spinner radii wide; 5 m: 0.75.
        let far = o.tower_width_for_spinner(r_at(38.0)).unwrap() / r_at(38.0);
        let close = o.tower_width_for_spinner(r_at(5.0)).unwrap() / r_at(5.0);
        assert!((far - 2.2 / 1.6 * 38.0 / 42.2).abs() < 1e-9, "{far}");
        assert!((close - 2.2 / 1.6 * 5.0 / 9.2).abs() < 1e-9, "{close}");
        // Seed 335 of `hubtrack fly` at 38 m: a band 0.6 r wide (the shading ramp) is outside
        // the default tolerance, the true 1.25 r inside.
        let tol = DefaultParams::default().tower_width_spinner_tol;
        assert!(
            0.6 < far / tol && far / tol < 1.25 && 1.25 < far * tol,
            "{far} {tol}"
        );
        assert!(o.tower_width_for_spinner(0.0).is_none());
    }

    #[test]
    fn roll_search_finds_tilted_tower() {
        let p = DefaultParams::default();
        let d = dir_from_up_cw(-6.0);
        let segs = vec![
            Segment::new([100.0, 260.0], [100.0 + 150.0 * d[0], 260.0 + 150.0 * d[1]]),
            Segment::new([110.0, 260.0], [110.0 + 150.0 * d[0], 260.0 + 150.0 * d[1]]),
            Segment::new([0.0, 50.0], [40.0, 10.0]),
        ];
        assert!((search_roll(&p, &segs) - 6.0).abs() <= 1.0);
    }

    #[test]
    fn collinear_pieces_merge() {
        let p = DefaultParams::default();
        let segs = [
            Segment::new([100.0, 200.0], [100.0, 150.0]),
            Segment::new([100.5, 145.0], [101.0, 90.0]),
            Segment::new([0.0, 0.0], [50.0, 0.0]),
        ];
        let m = merge_collinear(&p, &segs, 270.0);
        assert_eq!(m.len(), 2);
        assert!(m[0].length() > 105.0, "{m:?}");
    }

    #[test]
    fn pieces_bridged_by_a_shorter_one_merge_into_one_line() {
        let p = DefaultParams::default();
        // Longest first: B is placed, A is too far from it, then C bridges A and B but only
        // extends B. A second pass joins A to the grown B.
        let a = Segment::new([0.0, 100.0], [60.0, 100.0]);
        let b = Segment::new([100.0, 100.0], [170.0, 100.0]);
        let c = Segment::new([55.0, 100.0], [105.0, 100.0]);
        assert_eq!(merge_collinear_once(&p, &[a, b, c], 270.0).len(), 2);
        let m = merge_collinear(&p, &[a, b, c], 270.0);
        assert_eq!(m.len(), 1, "{m:?}");
        assert!((m[0].length() - 170.0).abs() < 1e-6, "{m:?}");
    }

    #[test]
    fn two_blades_up_with_the_third_hidden_by_the_tower_count_as_a_rotor() {
        let mut p = DefaultParams::default();
        let hub = [200.0, 100.0];
        // Blades at 60° and 300°: the third would point straight down, over the tower.
        let mut segs = rotor(hub, 60.0);
        segs.retain(|s| {
            geometry::ang_dist(s.angle_away_from(hub), 180.0) > 10.0
                || s.tilt_from_vertical_deg().abs() < 1.0
        });
        assert_eq!(segs.len(), 6, "tower edges and two blades");
        let hints = Hints {
            roll_rad: Some(0.0),
            ..Hints::default()
        };
        let f = recognise(
            &p,
            &segs,
            480.0,
            270.0,
            &hints,
            &mut no_circles,
            None,
            Expected::default(),
        )
        .unwrap();
        assert!(f.detected && geometry::dist(f.hub, hub) < 3.0, "{f:?}");
        let with_rule = f.confidence;
        p.hidden_blade_tol_deg = 0.0;
        let f = recognise(
            &p,
            &segs,
            480.0,
            270.0,
            &hints,
            &mut no_circles,
            None,
            Expected::default(),
        )
        .unwrap();
        assert!(f.confidence < with_rule, "{} vs {with_rule}", f.confidence);
    }

    #[test]
    fn the_learned_ranking_takes_the_rotor_over_longer_single_lines_meeting_elsewhere() {
        let hub = [150.0, 100.0];
        let mut segs = rotor(hub, 10.0);
        // Three field borders, each longer than a blade, ending at one point 120° apart.
        let clutter = [360.0, 160.0];
        for a in [30.0, 150.0, 270.0] {
            segs.push(ray(clutter, a, 6.0, 100.0));
        }
        let hints = Hints {
            roll_rad: Some(0.0),
            ..Hints::default()
        };
        let p = DefaultParams::default();
        assert_eq!(p.ranker.ranking, Ranking::Learned);
        let f = recognise(
            &p,
            &segs,
            480.0,
            270.0,
            &hints,
            &mut no_circles,
            None,
            Expected::default(),
        )
        .unwrap();
        assert!(f.detected && geometry::dist(f.hub, hub) < 3.0, "{f:?}");
        assert!(
            f.candidates
                .iter()
                .any(|c| geometry::dist(c.hub, clutter) < 5.0),
            "the crossing was a candidate: {:?}",
            f.candidates
        );
        // Reported as a probability, above the one the threshold stands for.
        assert!(
            f.confidence > crate::ranker::logistic(p.ranker.min_score) && f.confidence < 1.0,
            "{}",
            f.confidence
        );
    }

    #[test]
    fn two_blades_nearly_opposite_are_one_line_through_the_candidate() {
        let c = [200.0, 120.0];
        // A mast: its top above the candidate, two tower-like edges below, and a field border
        // crossing behind it in two pieces 175° apart (not collinear enough to be caught as a
        // line continuing behind the candidate).
        let mut segs = vec![
            Segment::new([197.0, 269.0], [198.0, 128.0]),
            Segment::new([203.0, 269.0], [202.0, 128.0]),
            ray(c, 0.0, 6.0, 80.0),
        ];
        segs.push(ray(c, 70.0, 6.0, 150.0));
        segs.push(ray(c, 245.0, 6.0, 150.0));
        let hints = Hints {
            roll_rad: Some(0.0),
            ..Hints::default()
        };
        let off = DefaultParams {
            blade_max_separation_deg: 180.0,
            ..rules()
        };
        let f = recognise(
            &off,
            &segs,
            480.0,
            270.0,
            &hints,
            &mut no_circles,
            None,
            Expected::default(),
        )
        .unwrap();
        assert!(
            f.detected,
            "without the rule the three lines pass for a rotor: {f:?}"
        );
        // The learned ranking refuses them without the rule: single edges far from 120° apart.
        let learned = DefaultParams {
            blade_max_separation_deg: 180.0,
            ..DefaultParams::default()
        };
        let f = recognise(
            &learned,
            &segs,
            480.0,
            270.0,
            &hints,
            &mut no_circles,
            None,
            Expected::default(),
        )
        .unwrap();
        assert!(!f.detected, "{f:?}");
        let on = DefaultParams {
            blade_max_separation_deg: 170.0,
            ..off.clone()
        };
        let f = recognise(
            &on,
            &segs,
            480.0,
            270.0,
            &hints,
            &mut no_circles,
            None,
            Expected::default(),
        )
        .unwrap();
        assert!(!f.detected, "{f:?}");
        // A rotor seen at 60° yaw (blades 0°, 120°, 240° on the rotor plane, horizontal
        // components halved): 139° apart at most, all kept.
        let seen = |a: f64| {
            let d = dir_from_up_cw(a);
            (d[0] * 0.5).atan2(-d[1]).to_degrees().rem_euclid(360.0)
        };
        let mut segs = rotor(c, 0.0);
        segs.truncate(2);
        for a in [0.0, 120.0, 240.0] {
            segs.push(ray(c, seen(a) - 3.0, 6.0, 70.0));
            segs.push(ray(c, seen(a) + 3.0, 6.0, 70.0));
        }
        let f = recognise(
            &on,
            &segs,
            480.0,
            270.0,
            &hints,
            &mut no_circles,
            None,
            Expected::default(),
        )
        .unwrap();
        assert!(
            f.detected && geometry::dist(f.hub, c) < 3.0 && f.blade_angles.len() == 3,
            "{f:?}"
        );
    }

    #[test]
    fn parallel_lines_alone_are_no_turbine() {
        let p = DefaultParams::default();
        // Power-line like: several long near-parallel sagging wires.
        let segs: Vec<Segment> = (0..5)
            .map(|k| {
                Segment::new(
                    [0.0, 50.0 + 10.0 * k as f64],
                    [479.0, 60.0 + 12.0 * k as f64],
                )
            })
            .collect();
        let f = recognise(
            &p,
            &segs,
            480.0,
            270.0,
            &Hints::default(),
            &mut no_circles,
            None,
            Expected::default(),
        )
        .unwrap();
        assert!(!f.detected);
    }

    /// A wide blade as its two edges: root half-width `w0` at `start` from the hub, tip
    /// half-width `w1` at `start + len`.
    fn blade_edges(hub: P2, angle: f64, start: f64, len: f64, w0: f64, w1: f64) -> [Segment; 2] {
        let d = dir_from_up_cw(angle);
        let n = [-d[1], d[0]];
        let at = |t: f64, off: f64| {
            [
                hub[0] + d[0] * t + n[0] * off,
                hub[1] + d[1] * t + n[1] * off,
            ]
        };
        [
            Segment::new(at(start, w0), at(start + len, w1)),
            Segment::new(at(start, -w0), at(start + len, -w1)),
        ]
    }

    #[test]
    fn a_level_blade_is_no_horizon_but_a_road_is() {
        let p = DefaultParams::default();
        let (w, h) = (480.0, 270.0);
        // Both edges of a blade lying level, 220 px long, narrowing from 20 to 6 px across.
        let blade = blade_edges([400.0, 120.0], 270.0, 10.0, 220.0, 10.0, 3.0);
        // A road of even width and the horizon itself.
        let road = [
            Segment::new([10.0, 200.0], [300.0, 205.0]),
            Segment::new([10.0, 214.0], [300.0, 219.0]),
        ];
        let horizon = Segment::new([0.0, 160.0], [479.0, 162.0]);
        let segs = vec![blade[0], blade[1], road[0], road[1], horizon];
        assert!(
            segs.iter().all(|s| is_horizon(&p, s, w, 0.0)),
            "all are horizon candidates"
        );
        assert_eq!(
            usable_lines(&p, &segs, w, h, 0.0),
            vec![true, true, false, false, false]
        );
        let off = DefaultParams {
            horizon_band_min_taper: 0.0,
            ..p
        };
        assert_eq!(usable_lines(&off, &segs, w, h, 0.0), vec![false; 5]);
    }

    #[test]
    fn blade_edges_pair_into_axes_through_the_hub() {
        let p = DefaultParams::default();
        let hub = [240.0, 130.0];
        let mut segs: Vec<Segment> = Vec::new();
        for a in [15.0, 135.0, 255.0] {
            segs.extend(blade_edges(hub, a, 30.0, 100.0, 8.0, 3.0));
        }
        // A lone field border and a power line pair (too far apart to be a blade).
        segs.push(Segment::new([10.0, 250.0], [200.0, 230.0]));
        segs.push(Segment::new([300.0, 20.0], [470.0, 20.0]));
        segs.push(Segment::new([300.0, 90.0], [470.0, 90.0]));
        let usable = vec![true; segs.len()];
        let axes = pair_edges(&p, &segs, &usable, 270.0);
        assert_eq!(axes.len(), 3, "{axes:?}");
        for a in &axes {
            assert_eq!(
                a.edges[0] / 2,
                a.edges[1] / 2,
                "edges of different blades paired: {a:?}"
            );
            assert!(a.axis.line_distance(hub) < 1e-6, "{a:?}");
            assert!(
                (a.width[0] - 16.0).abs() < 0.5 || (a.width[1] - 16.0).abs() < 0.5,
                "{a:?}"
            );
        }
        let props = axis_proposals(&p, &axes, 480.0, 270.0);
        assert!(
            !props.is_empty() && props.iter().all(|(x, _)| geometry::dist(*x, hub) < 1e-6),
            "{props:?}"
        );
    }

    #[test]
    fn close_range_hub_from_blade_axes_not_edge_crossings() {
        let p = DefaultParams::default();
        let hub = [240.0, 120.0];
        // Close range: blades start 55 px from the hub (beyond support_end_dist_frac * h = 40
        // px), root chord 36 px; their edges cross each other well off the hub.
        let mut segs: Vec<Segment> = Vec::new();
        for a in [40.0, 160.0, 280.0] {
            segs.extend(blade_edges(hub, a, 55.0, 120.0, 18.0, 9.0));
        }
        let f = recognise(
            &p,
            &segs,
            480.0,
            270.0,
            &Hints {
                roll_rad: Some(0.0),
                ..Hints::default()
            },
            &mut no_circles,
            None,
            Expected::default(),
        )
        .unwrap();
        assert!(f.detected, "{f:?}");
        assert!(geometry::dist(f.hub, hub) < 2.0, "{:?}", f.hub);
    }

    #[test]
    fn tracker_distance_narrows_the_spinner_radii() {
        let p = DefaultParams::default();
        let all = spinner_radii(&p, 270.0, None);
        assert_eq!(
            all,
            (p.spinner_min_radius_px, p.spinner_max_radius_frac * 270.0)
        );
        // Expected 20 px: 10..40 px, inside the configured limits.
        assert_eq!(spinner_radii(&p, 270.0, Some(20.0)), (10.0, 40.0));
        // Far away (expected 3 px): clipped to the limits, and empty: nothing to search.
        let (lo, hi) = spinner_radii(&p, 270.0, Some(1.5));
        assert!(lo >= hi, "{lo} {hi}");
        // Nonsense distances and a disabled window fall back to all radii.
        assert_eq!(spinner_radii(&p, 270.0, Some(f64::NAN)), all);
        assert_eq!(
            spinner_radii(
                &DefaultParams {
                    spinner_hint_radius_lo: 0.0,
                    ..p.clone()
                },
                270.0,
                Some(20.0)
            ),
            all
        );
    }

    #[test]
    fn a_spinner_rim_partly_seen_is_enough_at_the_expected_size() {
        // 30 % of a spinner's rim in the edges (the rest grey on grey blades): below
        // `spinner_min_coverage`, above `spinner_hint_min_coverage`.
        let p = DefaultParams::default();
        let (w, h, c, r) = (480usize, 270usize, [240.0, 135.0], 40.0);
        let (mut edges, mut dx, mut dy) = (vec![0u8; w * h], vec![0i16; w * h], vec![0i16; w * h]);
        let mut a = 200.0f64;
        while a < 200.0 + 0.3 * 360.0 {
            let (s, co) = a.to_radians().sin_cos();
            let (x, y) = (
                (c[0] + r * co).round() as usize,
                (c[1] + r * s).round() as usize,
            );
            edges[y * w + x] = 255;
            dx[y * w + x] = (200.0 * co).round() as i16;
            dy[y * w + x] = (200.0 * s).round() as i16;
            a += 0.25;
        }
        let img = EdgeImage {
            edges: &edges,
            dx: &dx,
            dy: &dy,
            width: w,
            height: h,
        };
        assert!(p.spinner_hint_min_coverage < 0.3 && 0.3 < p.spinner_min_coverage);
        let blind = search_circles(&p, &img, c, h as f64, None, &mut Vec::new(), None);
        assert!(blind.is_empty(), "{blind:?}");
        let hinted = search_circles(&p, &img, c, h as f64, Some(r), &mut Vec::new(), None);
        let k = hinted.first().expect("found with the expected radius");
        assert!(
            geometry::dist([k[0], k[1]], c) < 2.0 && (k[2] - r).abs() < 2.0,
            "{k:?}"
        );
        // The box's points selected from the whole image's are the box's own, in the same
        // order, and find the same circles.
        let mut all = Vec::new();
        edge_points(&img, [0, 0, w as i32, h as i32], &mut all);
        let (mut boxed, mut selected) = (Vec::new(), Vec::new());
        edge_points(&img, [200, 100, 260, 180], &mut boxed);
        select_points(&all, [200, 100, 260, 180], &mut selected);
        assert!(!boxed.is_empty() && boxed.len() < all.len());
        assert_eq!(boxed, selected);
        assert_eq!(
            search_circles(&p, &img, c, h as f64, Some(r), &mut Vec::new(), Some(&all)),
            hinted
        );
    }

    #[test]
    fn spinner_circle_accepted_only_near_the_candidate_with_blades_at_its_rim() {
        let p = rules();
        let hub = [240.0, 120.0];
        // Single-edge blades that stop at a spinner rim of radius 30 (one edge each, so the
        // edge lines pass 6 px off the centre).
        let mut segs: Vec<Segment> = Vec::new();
        for a in [20.0, 140.0, 260.0] {
            segs.push(blade_edges(hub, a, 30.0, 100.0, 6.0, 2.0)[0]);
        }
        let hints = Hints {
            roll_rad: Some(0.0),
            ..Hints::default()
        };
        let mut at_hub = |_: CircleQuery| -> Result<Vec<[f64; 4]>, DetectError> {
            Ok(vec![[hub[0] + 0.5, hub[1] - 0.5, 30.0, 1.0]])
        };
        let f = recognise(
            &p,
            &segs,
            480.0,
            270.0,
            &hints,
            &mut at_hub,
            None,
            Expected::default(),
        )
        .unwrap();
        assert!(f.detected && f.circle.is_some(), "{f:?}");
        assert!(
            geometry::dist(f.hub, [hub[0] + 0.5, hub[1] - 0.5]) < 1e-9,
            "{:?}",
            f.hub
        );
        // A circle far from every candidate is ignored.
        let mut far_away = |_: CircleQuery| -> Result<Vec<[f64; 4]>, DetectError> {
            Ok(vec![[400.0, 240.0, 30.0, 1.0]])
        };
        let g = recognise(
            &p,
            &segs,
            480.0,
            270.0,
            &hints,
            &mut far_away,
            None,
            Expected::default(),
        )
        .unwrap();
        assert!(g.circle.is_none(), "{g:?}");
        // The circle at the size the tracker's distance expects counts for more; at another
        // size it counts as before.
        let conf = |r_expected: f64| {
            let mut at_hub = |_: CircleQuery| -> Result<Vec<[f64; 4]>, DetectError> {
                Ok(vec![[hub[0] + 0.5, hub[1] - 0.5, 30.0, 1.0]])
            };
            let expected = Expected {
                spinner_radius: Some(r_expected),
                ..Expected::default()
            };
            let f =
                recognise(&p, &segs, 480.0, 270.0, &hints, &mut at_hub, None, expected).unwrap();
            assert!(f.circle.is_some(), "{f:?}");
            f.confidence
        };
        let (base, matched, other) = (f.confidence, conf(32.0), conf(60.0));
        assert!(
            base + p.spinner_size_match_bonus <= 1.0 + 1e-9,
            "room for the bonus: {base}"
        );
        assert!(
            (matched - base - p.spinner_size_match_bonus).abs() < 1e-9,
            "{matched} vs {base}"
        );
        assert!((other - base).abs() < 1e-9, "{other} vs {base}");
    }

    #[test]
    fn a_circle_beside_the_point_where_the_blade_axes_meet_is_no_spinner() {
        let hub = [240.0, 120.0];
        let r = 20.0;
        // Three blades seen by both edges (their axes meet at the hub), starting at the rim.
        let mut segs: Vec<Segment> = Vec::new();
        for a in [0.0, 120.0, 240.0] {
            segs.extend(blade_edges(hub, a, r, 100.0, 7.0, 3.0));
        }
        let hints = Hints {
            roll_rad: Some(0.0),
            ..Hints::default()
        };
        // A round patch 1.2 radii beside the hub with a better covered rim than the spinner's
        // (the nacelle's front corner between two blade roots in a rendered flight).
        let beside = [hub[0] + 1.2 * r * 0.6, hub[1] + 1.2 * r * 0.8, r, 0.9];
        let spinner = [hub[0], hub[1], r, 0.6];
        let run = |p: &DefaultParams| {
            let mut circles = |_: CircleQuery| -> Result<Vec<[f64; 4]>, DetectError> {
                Ok(vec![beside, spinner])
            };
            recognise(
                p,
                &segs,
                480.0,
                270.0,
                &hints,
                &mut circles,
                None,
                Expected::default(),
            )
            .unwrap()
        };
        let off = DefaultParams {
            spinner_max_convergence_radii: 0.0,
            ..rules()
        };
        let f = run(&off);
        assert!(
            f.circle
                .is_some_and(|k| geometry::dist([k[0], k[1]], [beside[0], beside[1]]) < 1e-9),
            "without the rule the better rim wins: {f:?}"
        );
        let on = DefaultParams {
            spinner_max_convergence_radii: 1.0,
            ..off.clone()
        };
        let f = run(&on);
        assert!(f.detected && geometry::dist(f.hub, hub) < 1.0, "{f:?}");
        assert!(
            f.circle
                .is_some_and(|k| geometry::dist([k[0], k[1]], hub) < 1e-9),
            "{f:?}"
        );
    }

    #[test]
    fn an_enclosing_circle_replaces_the_best_covered_one_only_with_a_rim_as_well_covered() {
        let p = DefaultParams::default();
        let hub = [240.0, 120.0];
        let mut segs: Vec<Segment> = Vec::new();
        for a in [20.0, 140.0, 260.0] {
            segs.push(blade_edges(hub, a, 30.0, 100.0, 6.0, 2.0)[0]);
        }
        let hints = Hints {
            roll_rad: Some(0.0),
            ..Hints::default()
        };
        // The spinner (best covered) and a larger circle round it, 6 px off centre, as blade
        // edges crossing near the spinner draw one.
        let inner = [hub[0], hub[1], 30.0];
        let outer = [hub[0] + 4.0, hub[1] + 4.5, 36.5];
        assert!(
            geometry::dist([outer[0], outer[1]], [inner[0], inner[1]]) + inner[2]
                <= outer[2] + SPINNER_NEST_TOL_PX,
            "nested"
        );
        let circle = |outer_cov: f64| {
            let mut circles = |_: CircleQuery| -> Result<Vec<[f64; 4]>, DetectError> {
                Ok(vec![
                    [inner[0], inner[1], inner[2], 0.6],
                    [outer[0], outer[1], outer[2], outer_cov],
                ])
            };
            recognise(
                &p,
                &segs,
                480.0,
                270.0,
                &hints,
                &mut circles,
                None,
                Expected::default(),
            )
            .unwrap()
            .circle
        };
        let ratio = p.spinner_nest_min_coverage_ratio;
        assert!(ratio > 0.0 && ratio < 1.0);
        assert_eq!(
            circle(0.6 * ratio - 0.05),
            Some(inner),
            "a weakly covered outer circle is no silhouette"
        );
        assert_eq!(
            circle(0.6 * ratio + 0.05),
            Some(outer),
            "the silhouette round a ring on the spinner's face"
        );
    }

    #[test]
    fn a_near_tie_between_spinner_circles_goes_to_the_expected_size_else_to_the_prediction() {
        // Off by default (see the parameter); the value it was measured with.
        let p = DefaultParams {
            spinner_tie_ratio: 0.8,
            ..DefaultParams::default()
        };
        let hub = [240.0, 120.0];
        let mut segs: Vec<Segment> = Vec::new();
        for a in [20.0, 140.0, 260.0] {
            segs.extend(blade_edges(hub, a, 30.0, 100.0, 6.0, 2.0));
        }
        // The spinner and a slightly better covered circle beside it (the nacelle's corner
        // between two blade roots), both with blades at their rim.
        let spinner = [hub[0], hub[1], 28.0];
        let beside = [hub[0] + 10.0, hub[1] + 4.0, 20.0];
        let circle_with =
            |p: &DefaultParams, beside_cov: f64, predicted: Option<P2>, expected_r: Option<f64>| {
                let hints = Hints {
                    roll_rad: Some(0.0),
                    predicted_hub_px: predicted,
                    ..Hints::default()
                };
                let mut circles = |_: CircleQuery| -> Result<Vec<[f64; 4]>, DetectError> {
                    let mut v = vec![
                        [spinner[0], spinner[1], spinner[2], 0.30],
                        [beside[0], beside[1], beside[2], beside_cov],
                    ];
                    v.sort_by(|a, b| b[3].total_cmp(&a[3]));
                    Ok(v)
                };
                let expected = Expected {
                    spinner_radius: expected_r,
                    ..Expected::default()
                };
                recognise(p, &segs, 480.0, 270.0, &hints, &mut circles, None, expected)
                    .unwrap()
                    .circle
            };
        let circle = |beside_cov: f64, predicted: Option<P2>, expected_r: Option<f64>| {
            circle_with(&p, beside_cov, predicted, expected_r)
        };
        let tie = p.spinner_tie_ratio;
        let (close_call, clear_win) = (0.30 / tie - 0.02, 0.30 / tie + 0.02);
        let (at_spinner, at_beside) = ([hub[0] + 2.0, hub[1] - 3.0], [beside[0] - 1.0, beside[1]]);
        assert_eq!(
            circle(close_call, None, None),
            Some(beside),
            "with no tracker the best covered circle"
        );
        assert_eq!(
            circle(close_call, Some(at_spinner), None),
            Some(spinner),
            "a near tie goes to the prediction"
        );
        assert_eq!(
            circle(close_call, Some(at_beside), Some(27.0)),
            Some(spinner),
            "... or to the expected size"
        );
        assert_eq!(
            circle(close_call, Some(at_spinner), Some(21.0)),
            Some(beside),
            "the size before the prediction"
        );
        assert_eq!(
            circle(clear_win, Some(at_spinner), Some(27.0)),
            Some(beside),
            "a clearly better rim wins anyway"
        );
        let off = DefaultParams {
            spinner_tie_ratio: 1.0,
            ..p.clone()
        };
        assert_eq!(
            circle_with(&off, close_call, Some(at_spinner), Some(27.0)),
            Some(beside),
            "the rule off: the best covered"
        );
    }

    #[test]
    fn close_spinner_is_searched_anywhere_when_nothing_else_is_found() {
        let p = DefaultParams::default();
        let (hub, r) = ([300.0, 150.0], 40.0);
        // Two blades seen by one edge each, starting at the rim of a close spinner: no
        // candidate from them alone.
        let segs: Vec<Segment> = [30.0, 150.0]
            .iter()
            .map(|&a| blade_edges(hub, a, r, 200.0, 12.0, 6.0)[0])
            .collect();
        let hints = Hints {
            roll_rad: Some(0.0),
            ..Hints::default()
        };
        let f = recognise(
            &p,
            &segs,
            480.0,
            270.0,
            &hints,
            &mut no_circles,
            None,
            Expected::default(),
        )
        .unwrap();
        assert!(!f.detected, "{f:?}");
        let mut close = |q: CircleQuery| -> Result<Vec<[f64; 4]>, DetectError> {
            Ok(if q == CircleQuery::Close {
                vec![[hub[0], hub[1], r, 1.0]]
            } else {
                vec![]
            })
        };
        let g = recognise(
            &p,
            &segs,
            480.0,
            270.0,
            &hints,
            &mut close,
            None,
            Expected::default(),
        )
        .unwrap();
        assert!(
            g.detected && g.circle.is_some() && geometry::dist(g.hub, hub) < 1e-9,
            "{g:?}"
        );
    }

    #[test]
    fn close_spinners_are_candidates_in_every_frame_without_a_tracker_when_always() {
        let (spinner_hub, r) = ([360.0, 150.0], 40.0);
        // A rotor detected from its lines, and a close spinner with two one-edge blades elsewhere.
        let mut segs = rotor([120.0, 100.0], 10.0);
        segs.extend(
            [30.0, 150.0]
                .iter()
                .map(|&a| blade_edges(spinner_hub, a, r, 100.0, 12.0, 6.0)[0]),
        );
        let hints = Hints {
            roll_rad: Some(0.0),
            ..Hints::default()
        };
        let run = |p: &DefaultParams, hints: &Hints| {
            let asked = std::cell::Cell::new(0);
            let mut close = |q: CircleQuery| -> Result<Vec<[f64; 4]>, DetectError> {
                if q == CircleQuery::Close {
                    asked.set(asked.get() + 1);
                    return Ok(vec![[spinner_hub[0], spinner_hub[1], r, 1.0]]);
                }
                Ok(vec![])
            };
            let f = recognise(
                p,
                &segs,
                480.0,
                270.0,
                hints,
                &mut close,
                None,
                Expected::default(),
            )
            .unwrap();
            (f, asked.get())
        };
        let always = DefaultParams::default();
        assert!(always.close_spinner_always);
        let (f, asked) = run(&always, &hints);
        assert!(f.detected && asked == 1, "{asked} {f:?}");
        assert!(
            f.candidates
                .iter()
                .any(|c| geometry::dist(c.hub, spinner_hub) < 1e-9),
            "{:?}",
            f.candidates
        );
        // Only as a fallback: something was detected, so no whole-image search.
        let fallback = DefaultParams {
            close_spinner_always: false,
            ..always.clone()
        };
        let (f, asked) = run(&fallback, &hints);
        assert!(f.detected && asked == 0, "{asked} {f:?}");
        // With a tracker's prediction never (its neighbourhood is searched instead).
        let tracked = Hints {
            predicted_hub_px: Some([120.0, 100.0]),
            ..hints
        };
        assert_eq!(run(&always, &tracked).1, 0);
    }

    #[test]
    fn line_continuing_behind_the_candidate_is_no_blade() {
        let p = DefaultParams::default();
        let c = [200.0, 120.0];
        // A field border interrupted by the turbine: two collinear pieces either side of c.
        let segs = vec![
            Segment::new([60.0, 100.0], [190.0, 118.6]),
            Segment::new([212.0, 121.7], [400.0, 148.6]),
        ];
        let usable = vec![true; segs.len()];
        assert!(continues_beyond(&p, &segs, &usable, 0, c, 270.0));
        assert!(support_lines(&p, &segs, &usable, c, 270.0, 0.0).is_empty());
    }

    #[test]
    fn horizon_bent_by_the_lens_still_continues_behind_the_candidate() {
        let p = DefaultParams::default();
        let c = [200.0, 120.0];
        // A horizon seen through a wide lens, interrupted by the tower: the right piece bends
        // 2° away from the left piece's extension (7 px off it at its far end).
        let right_dir = (8.0_f64 - 2.0).to_radians();
        let segs = vec![
            Segment::new(
                [60.0, 120.0 - 140.0 * 8f64.to_radians().tan()],
                [190.0, 120.0 - 10.0 * 8f64.to_radians().tan()],
            ),
            Segment::new(
                [212.0, 120.0 + 12.0 * 8f64.to_radians().tan()],
                [
                    212.0 + 190.0 * right_dir.cos(),
                    120.0 + 12.0 * 8f64.to_radians().tan() + 190.0 * right_dir.sin(),
                ],
            ),
        ];
        let usable = vec![true; segs.len()];
        assert!(continues_beyond(&p, &segs, &usable, 0, c, 270.0));
        // Straight lines only (no bend allowed): the far end is too far off.
        let straight = DefaultParams {
            occluded_bend_deg: 0.0,
            ..p.clone()
        };
        assert!(!continues_beyond(&straight, &segs, &usable, 0, c, 270.0));
        // A blade pointing up, nearly in line with a tower edge below: no bend allowance.
        let up = vec![
            Segment::new([200.0, 20.0], [201.0, 110.0]),
            Segment::new([203.0, 135.0], [210.0, 265.0]),
        ];
        assert!(!continues_beyond(&p, &up, &[true, true], 0, c, 270.0));
    }
}
