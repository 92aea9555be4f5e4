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
//!
//! One module per step, in the order [`run`] and [`recognise`] call them: [`edges`] (1),
//! [`lines`] (2), [`horizon`] (3, 4), [`bands`] (8, needed by 5), [`proposals`] (5),
//! [`blades`], [`evaluate`] and [`tower`] (6, 10), [`refine`] (7), [`spinner_search`] and
//! [`spinner`] (9), [`ranking`] (11) and [`report`]; [`context`] holds what they all read.

mod bands;
mod blades;
mod context;
mod edges;
mod evaluate;
mod horizon;
mod lines;
mod proposals;
mod ranking;
mod refine;
mod report;
mod spinner;
mod spinner_search;
#[cfg(test)]
mod tests;
mod tower;

use std::time::Instant;

use opencv::core::Mat;

use crate::blade::{partner_axis, Gradients, PartnerSearch};
use crate::geometry::{Segment, P2};
use crate::params::DefaultParams;
use crate::{us_since, DetectError, Found, Hints, Scratch};

pub(crate) use context::{Expected, Optics};
pub(crate) use evaluate::passes_through;

use context::{FrameCtx, SceneCtx};
use edges::EdgeImage;
use evaluate::Candidate;
use spinner_search::{search_circles, CircleFinder, EdgePointCache, Spinners};

/// Blades of the rotor (the thesis's turbines and practically every utility-scale one): the
/// strongest this many blade groups make a candidate's rotor, more are penalised.
const ROTOR_BLADES: usize = 3;

/// Run the default pipeline on the working image `small`, with the sizes `expected` from the
/// tracker's distance (if any).
pub(crate) fn run(
    p: &DefaultParams,
    small: &Mat,
    s: &mut Scratch,
    hints: &Hints,
    expected: Expected<'_>,
) -> Result<Found, DetectError> {
    let t = Instant::now();
    let (high, edge_count) = edges::canny(p, small, s)?;
    let edges_us = us_since(t);

    let img = EdgeImage::of(&s.edges, &s.dx, &s.dy)?;
    let frame = FrameCtx {
        p,
        w: img.width as f64,
        h: img.height as f64,
        hints,
        spinner_max_r: context::blind_spinner_max_r(
            p,
            img.height as f64,
            expected.optics.as_ref(),
            hints,
        ),
        camera: expected.optics.and_then(|o| o.bending_lens),
    };
    let settings = lines::hough_settings(p, frame.h);
    let (hough, segments) = (&mut s.hough, &mut s.segments);
    let whole = EdgePointCache::new(&frame, expected.spinner_radius, &mut s.all_edge_points);
    let pts = &mut s.edge_points;
    std::thread::scope(|scope| {
        // The spinner around the tracker's predicted hub needs only the edges, so it is searched
        // on a second thread while this one runs Hough and the geometry.
        let img = &img;
        let ahead = hints.predicted_hub_px.map(|c| {
            (
                c,
                scope.spawn(move || {
                    search_circles(
                        &frame,
                        img,
                        c,
                        expected.spinner_radius,
                        &mut Vec::new(),
                        None,
                    )
                }),
            )
        });
        let t = Instant::now();
        hough.run(img, &settings, segments);
        let hough_us = us_since(t);

        let t = Instant::now();
        let line_count = segments.len() as u32;
        let segs = lines::merge_collinear(p, segments, frame.h);
        log::trace!(
            "hough {} merged {} high {high} longest {:?}",
            segments.len(),
            segs.len(),
            segs.iter().take(5).collect::<Vec<_>>()
        );
        let mut spinners = Spinners {
            frame,
            img,
            expected_r: expected.spinner_radius,
            heat: expected.heat,
            ahead,
            whole,
            pts,
        };
        let grad = img.gradients();
        let mut found = recognise(
            &frame,
            &segs,
            &mut |q| spinners.find(q),
            Some(&grad),
            expected,
        )?;
        found.line_count = line_count;
        found.edge_count = edge_count;
        found.edges_us = edges_us;
        found.hough_us = hough_us;
        found.geometry_us = us_since(t);
        Ok(found)
    })
}

/// Steps 3–11 on the merged lines `segs` of `frame`: plain data (working px) except for
/// `search`, which looks for spinner circles in the image, and `grad`, the gradient image, in
/// which the tower is measured from both edges ([`crate::tower`]) and the partner edges of
/// blades seen by one edge are searched ([`crate::blade`]); without it the tower axis is the
/// mean of the tower lines. `expected`: the sizes a tracker's distance lets the detector
/// expect, and the learned heatmap.
fn recognise(
    frame: &FrameCtx<'_>,
    segs: &[Segment],
    search: &mut CircleFinder<'_>,
    grad: Option<&Gradients<'_>>,
    expected: Expected<'_>,
) -> Result<Found, DetectError> {
    let FrameCtx { p, w, h, hints, .. } = *frame;
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
    // Steps 3 and 4: the roll, and the lines that may be blade or tower edges.
    let roll_deg = match hints.roll_rad {
        Some(r) => r.to_degrees(),
        None => horizon::search_roll(p, segs),
    };
    let mut found = Found {
        roll_used_deg: roll_deg,
        line_count: segs.len() as u32,
        ..Found::default()
    };
    let usable = horizon::usable_lines(frame, segs, roll_deg);
    // Step 8, edge pairing: its band axes propose candidates too.
    let axes = bands::pair_edges(frame, segs, &usable);
    let sc = SceneCtx {
        p,
        w,
        h,
        hints,
        spinner_max_r: frame.spinner_max_r,
        camera: frame.camera,
        segs,
        usable: &usable,
        axes: &axes,
        roll_deg,
        partner: &partner,
    };
    // Step 5: the candidates; steps 6, 7 and 10: each evaluated, refined, scored.
    let mut cands: Vec<Candidate> = proposals::centres(&sc, expected.heat)
        .into_iter()
        .map(|c| refine::candidate_at(&sc, c))
        .collect();
    ranking::sort(&mut cands);
    // Step 9: spinner circles around the best candidates.
    let extra = spinner::around_candidates(&sc, &cands, search, expected.spinner_radius)?;
    // Step 11: the preferred candidate; then close-range spinners anywhere, if called for.
    let heat_at = |c: P2| {
        expected
            .heat
            .map_or(0.0, |m| m.near(c[0] / w, c[1] / h, p.hub_heat_radius_cells))
    };
    let mut best = ranking::pick(
        p,
        cands.into_iter().chain(extra),
        &heat_at,
        &mut found.candidates,
    );
    spinner::close_range(&sc, search, &heat_at, &mut best, &mut found.candidates)?;
    report::report(&sc, best, grad, &expected, &mut found);
    Ok(found)
}
