//! The result of the default pipeline: the chosen candidate's hub, blades, spinner circle and
//! tower written into [`Found`], with every line's role for the overlay.

use crate::blade::Gradients;
use crate::{Found, LineKind};

use super::context::{Expected, SceneCtx};
use super::evaluate::Candidate;
use super::ranking::decision;
use super::tower::report_tower;

/// Writes the chosen candidate `best` (if any) into `found`, decided as the ranking says, with
/// its tower ([`report_tower`]), and the role of every line of the scene.
pub(super) fn report(
    sc: &SceneCtx<'_>,
    best: Option<Candidate>,
    grad: Option<&Gradients<'_>>,
    expected: &Expected<'_>,
    found: &mut Found,
) {
    let SceneCtx {
        p, segs, usable, h, ..
    } = *sc;
    let mut kinds: Vec<LineKind> = usable
        .iter()
        .map(|&u| {
            if u {
                LineKind::Other
            } else {
                LineKind::Rejected
            }
        })
        .collect();
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
        report_tower(sc, &b, grad, expected, found);
    }
    found.lines = segs.iter().copied().zip(kinds).collect();
}
