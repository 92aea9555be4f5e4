//! Step 7, refinement: the hub moved to the least-squares point of its blades' lines, each blade
//! weighted equally; a blade seen by one edge contributes its axis when the partner edge is
//! found in the gradient image (`blade.rs`); with two or more known axes, the axes alone.

use crate::geometry::{self, Segment, P2};

use super::blades::{is_paired, Blade};
use super::context::SceneCtx;
use super::evaluate::{evaluate, Candidate};
use super::ROTOR_BLADES;

/// The candidate at `c` (steps 6 and 7): evaluated there and, with two blades or more, at the
/// least-squares point of its blades ([`refine`]) if that lies near and scores at least as
/// well (its blades and tower then match the reported hub).
pub(super) fn candidate_at(sc: &SceneCtx<'_>, c: P2) -> Candidate {
    let (p, h) = (sc.p, sc.h);
    let mut cand = evaluate(sc, c, None);
    if cand.blades.len() >= 2 {
        if let Some(r) = refine(sc, &cand.blades, c) {
            if geometry::dist(r, c) <= p.cluster_radius_frac * h * 2.0 {
                // Re-evaluate at the refined point so blades and tower match the output.
                let again = evaluate(sc, r, None);
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
    cand
}

/// Least-squares point closest to all lines, each blade's lines together weighing 1. With at
/// least two blades of known axis, their axes alone (the edges meet at the spinner rim, the
/// axes at its centre). A blade seen by one edge only has its axis from `partner` (the partner
/// edge in the image, see `blade.rs`) when that finds one.
fn refine(sc: &SceneCtx<'_>, blades: &[Blade], centre: P2) -> Option<P2> {
    let segs = sc.segs;
    let axes: Vec<(Segment, f64)> = blades
        .iter()
        .take(ROTOR_BLADES)
        .filter_map(|b| {
            b.axis
                .or_else(|| one_sided_axis(sc, b, centre))
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
        if let Some(axis) = bl.axis.or_else(|| one_sided_axis(sc, bl, centre)) {
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
pub(super) fn one_sided_axis(sc: &SceneCtx<'_>, b: &Blade, centre: P2) -> Option<Segment> {
    let (segs, partner) = (sc.segs, sc.partner);
    if is_paired(segs, b, centre) {
        return None;
    }
    let longest = b
        .lines
        .iter()
        .max_by(|&&i, &&j| segs[i].length().total_cmp(&segs[j].length()))?;
    partner(&segs[*longest], centre)
}
