//! Step 11, ranking: the best candidate by the learned score of its features, reported at
//! `ranker.min_score`; with `ranker.ranking = "rules"`, by the confidence of steps 6–10, then
//! blade support, reported at `min_confidence` (`crate::ranker`).

use crate::geometry::P2;
use crate::params::{DefaultParams, Ranking};
use crate::Considered;

use super::evaluate::Candidate;

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
pub(super) fn preferred(p: &DefaultParams, a: &Candidate, b: &Candidate) -> bool {
    match p.ranker.ranking {
        Ranking::Rules => better(a, b),
        Ranking::Learned => {
            let (x, y) = (learned_score(p, a), learned_score(p, b));
            x > y + 1e-9 || (x >= y - 1e-9 && a.support > b.support)
        }
    }
}

/// Whether `c` is reported as the hub, and with what confidence (0..1).
pub(super) fn decision(p: &DefaultParams, c: &Candidate) -> (bool, f64) {
    match p.ranker.ranking {
        Ranking::Rules => (c.confidence >= p.min_confidence, c.confidence),
        Ranking::Learned => {
            let s = learned_score(p, c);
            (s >= p.ranker.min_score, crate::ranker::logistic(s))
        }
    }
}

/// Sorts candidates best first by the rules' ordering ([`better`]), stably.
pub(super) fn sort(cands: &mut [Candidate]) {
    cands.sort_by(|a, b| {
        if better(a, b) {
            std::cmp::Ordering::Less
        } else if better(b, a) {
            std::cmp::Ordering::Greater
        } else {
            std::cmp::Ordering::Equal
        }
    });
}

/// The preferred candidate of `cands` ([`preferred`]; the first of equals), each with its
/// heatmap feature from `heat_at` and listed in `considered`.
pub(super) fn pick(
    p: &DefaultParams,
    cands: impl IntoIterator<Item = Candidate>,
    heat_at: &dyn Fn(P2) -> f64,
    considered: &mut Vec<Considered>,
) -> Option<Candidate> {
    let mut best: Option<Candidate> = None;
    for mut cand in cands {
        cand.features[crate::ranker::HUB_HEAT] = heat_at(cand.centre);
        considered.push(cand.considered());
        if cand.square {
            continue;
        }
        if best.as_ref().is_none_or(|b| preferred(p, &cand, b)) {
            best = Some(cand);
        }
    }
    best
}
