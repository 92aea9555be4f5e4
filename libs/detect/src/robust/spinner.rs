//! Step 9, the spinner step: a circle found near a candidate with two blades starting at its rim
//! becomes a candidate centred on it (with a confidence bonus), once it passes the tests that
//! tell a spinner from a round patch beside the hub.

use crate::geometry::{self, Segment, P2};
use crate::params::DefaultParams;
use crate::{Considered, DetectError};

use super::blades::Blade;
use super::context::SceneCtx;
use super::evaluate::{evaluate, Candidate};
use super::ranking::{decision, preferred};
use super::refine::one_sided_axis;
use super::spinner_search::{spinner_reuse_px, CircleFinder, CircleQuery};
use super::ROTOR_BLADES;

/// A circle lies inside another when it reaches at most this far (working px) beyond its rim.
pub(super) const SPINNER_NEST_TOL_PX: f64 = 1.0;

/// The spinner step around the candidates (sorted best first): the best `spinner_candidates`
/// distinct ones with at least two blades, and the tracker's predicted hub with or without
/// blades (at close range the blades leave the frame and only the spinner is left to see), are
/// searched for circles with `search`; each that passes [`spinner_candidate`] is a new
/// candidate. `expected_r`: the spinner radius a tracker's distance expects, working px.
pub(super) fn around_candidates(
    sc: &SceneCtx<'_>,
    cands: &[Candidate],
    search: &mut CircleFinder<'_>,
    expected_r: Option<f64>,
) -> Result<Vec<Candidate>, DetectError> {
    let SceneCtx { p, h, hints, .. } = *sc;
    // A candidate near an already searched one reuses its circles (the search box of the
    // first covers most of the second's).
    let mut searched: Vec<(P2, Vec<[f64; 4]>)> = Vec::new();
    let mut extra: Vec<Candidate> = Vec::new();
    let reuse = spinner_reuse_px(p, h);
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
        if let Some(mut spun) = spinner_candidate(sc, cand, cands, &circles) {
            // A circle of the size the tracker's distance expects is the spinner with more
            // certainty than blade lines meeting somewhere near it: at close range under an
            // overcast sky the lines of two blades met at the tower top, 0.15 h below the
            // hub, scored 0.9 with the tower, and the spinner, found at the expected size,
            // 0.8.
            if let (Some(e), Some(k)) = (expected_r, spun.spinner) {
                if k[2] >= e / p.spinner_size_match_tol && k[2] <= e * p.spinner_size_match_tol {
                    spun.score += p.spinner_size_match_bonus;
                    spun.features[crate::ranker::SPINNER_SIZE_MATCH] = 1.0;
                    spun.confidence = (spun.confidence + p.spinner_size_match_bonus).min(1.0);
                }
            }
            log::trace!(
                "spinner candidate {:?} conf {:.2} blades {}",
                spun.spinner,
                spun.confidence,
                spun.blades.len()
            );
            extra.push(spun);
        }
    }
    Ok(extra)
}

/// The close-range spinner step: a close spinner anywhere in the image with two blades at its
/// rim, when nothing is detected (`best` is not reported), or always
/// (`close_spinner_always`), then every such circle being a candidate. Not with a tracker's
/// prediction: its neighbourhood was searched already, and a frame missed while tracking
/// would pay for the whole-image search. Every circle evaluated joins `considered`, with its
/// heatmap feature from `heat_at`.
pub(super) fn close_range(
    sc: &SceneCtx<'_>,
    search: &mut CircleFinder<'_>,
    heat_at: &dyn Fn(P2) -> f64,
    best: &mut Option<Candidate>,
    considered: &mut Vec<Considered>,
) -> Result<(), DetectError> {
    let SceneCtx { p, h, hints, .. } = *sc;
    let always = p.close_spinner_always;
    if hints.predicted_hub_px.is_some()
        || !(always || best.as_ref().is_none_or(|b| !decision(p, b).0))
    {
        return Ok(());
    }
    let min_r = p.close_spinner_radius_frac * h;
    for k in search(CircleQuery::Close)?
        .into_iter()
        .filter(|k| k[2] >= min_r)
    {
        let mut cand = evaluate(sc, [k[0], k[1]], Some([k[0], k[1], k[2]]));
        cand.features[crate::ranker::SPINNER_COVERAGE] = k[3];
        cand.features[crate::ranker::SPINNER_AXES_OFFSET] =
            axes_meet_offset(sc, &cand).map_or(0.0, |off| (off / k[2]).min(2.0));
        cand.features[crate::ranker::HUB_HEAT] = heat_at(cand.centre);
        log::trace!(
            "close spinner {k:?}: conf {:.2} blades {}",
            cand.confidence,
            cand.blades.len()
        );
        considered.push(cand.considered());
        if cand.blades.len() >= 2 && best.as_ref().is_none_or(|b| preferred(p, &cand, b)) {
            *best = Some(cand);
            if !always {
                break;
            }
        }
    }
    Ok(())
}

/// The first circle near `cand` (within `spinner_max_offset_frac · h`) that at least two blades
/// start from, evaluated as a spinner-centred candidate. A larger such circle around it wins:
/// the shading of the nose cone draws circles inside the spinner's outline, and the blades
/// start at the outline (a nose-cone circle put the hub 2 % of the height high and its size
/// put the hub 50 % too far: rendered flights at 30 m).
fn spinner_candidate(
    sc: &SceneCtx<'_>,
    cand: &Candidate,
    others: &[Candidate],
    circles: &[[f64; 4]],
) -> Option<Candidate> {
    let SceneCtx { p, h, .. } = *sc;
    let with_blades = circles
        .iter()
        .filter(|k| geometry::dist([k[0], k[1]], cand.centre) <= p.spinner_max_offset_frac * h)
        .map(|k| (evaluate(sc, [k[0], k[1]], Some([k[0], k[1], k[2]])), k[3]))
        .inspect(|(c, cov)| {
            log::trace!(
                "circle {:?} (rim {cov:.2}): conf {:.2} blades {:?}",
                c.spinner,
                c.confidence,
                c.blades
                    .iter()
                    .map(|b| (b.angle_deg.round(), b.weight.round()))
                    .collect::<Vec<_>>()
            )
        })
        .filter(|(c, _)| c.blades.len() >= 2)
        .filter(|(c, _)| {
            // Measured against the strongest blade candidate near the circle (not only the one
            // searched around: a weaker candidate between the blades finds the same circle).
            let Some(k) = c
                .spinner
                .filter(|k| k[2] <= p.spinner_kept_support_max_radius_px)
            else {
                return true;
            };
            let centre = [k[0], k[1]];
            let strongest = others
                .iter()
                .chain(std::iter::once(cand))
                .filter(|o| {
                    o.blades.len() >= 2
                        && geometry::dist(o.centre, centre) <= p.spinner_max_offset_frac * h
                })
                .max_by(|a, b| a.support.total_cmp(&b.support))
                .unwrap_or(cand);
            let kept = kept_support(p, strongest, c);
            if kept < p.spinner_min_kept_support {
                log::trace!(
                    "circle {:?} keeps {:.0} % of the blade support: not this rotor's spinner",
                    c.spinner,
                    100.0 * kept
                );
            }
            kept >= p.spinner_min_kept_support
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
                axes_meet_offset(sc, c).map_or(0.0, |off| (off / k[2]).min(2.0));
        }
    }
    // Circles are best covered first.
    if with_blades.is_empty() {
        return None;
    }
    let (first, first_cov) = with_blades.remove(0);
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
fn axes_meet_offset(sc: &SceneCtx<'_>, c: &Candidate) -> Option<f64> {
    let axes = sc.axes;
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
                .or_else(|| one_sided_axis(sc, b, centre))
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
pub(super) fn kept_support(p: &DefaultParams, cand: &Candidate, circle: &Candidate) -> f64 {
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
