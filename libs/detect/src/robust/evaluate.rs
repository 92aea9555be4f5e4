//! Steps 6 and 10, scoring a candidate: its blades (the tower and lines through it dropped), its
//! tower lines, the rules' confidence and the features the learned ranker sees.

use crate::geometry::{self, Segment, P2};
use crate::params::DefaultParams;
use crate::Considered;

use super::bands::{axis_points_at, BandAxis};
use super::blades::{
    clutter_lines, group_blades, hidden_blade_down, is_paired, rotor_geometry_ok, support_lines,
    Blade,
};
use super::context::SceneCtx;
use super::tower::tower_lines;
use super::ROTOR_BLADES;

/// Everything evaluated for one hub candidate.
#[derive(Debug, Clone, Default)]
pub(super) struct Candidate {
    /// The candidate hub, working px.
    pub centre: P2,
    /// Its blades, strongest first.
    pub blades: Vec<Blade>,
    /// Lines dropped as the tower, opposite or weak blades.
    pub rejected: Vec<usize>,
    /// Its tower lines.
    pub tower: Vec<usize>,
    /// Reported confidence, at most 1.
    pub confidence: f64,
    /// The confidence before capping, for ranking: a candidate with every cue and a spinner
    /// beats one with every cue but the spinner.
    pub score: f64,
    /// Summed weight (line length) of its (up to three) strongest blades.
    pub support: f64,
    /// The spinner circle `[x, y, r]` centred on it, if any.
    pub spinner: Option<[f64; 3]>,
    /// What the learned ranker sees ([`crate::ranker`]).
    pub features: crate::ranker::Features,
    /// Its blades all run along the world's vertical and horizontal (`square_blades_max_deg`):
    /// built edges, no rotor.
    pub square: bool,
}

impl Candidate {
    /// The candidate as the detector reports it among those considered.
    pub fn considered(&self) -> Considered {
        Considered {
            hub: self.centre,
            confidence: self.confidence,
            features: self.features,
        }
    }
}

/// Evaluate a hub candidate at `c`; `spinner`: a spinner circle `[x, y, r]` centred at `c`.
pub(super) fn evaluate(sc: &SceneCtx<'_>, c: P2, spinner: Option<[f64; 3]>) -> Candidate {
    let SceneCtx {
        p,
        segs,
        usable,
        axes,
        h,
        roll_deg,
        hints,
        ..
    } = *sc;
    let spinner_r = spinner.map_or(0.0, |k| k[2]);
    let mut lines = support_lines(sc, c, spinner_r);

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
    let tower = tower_lines(sc, c, 0.0);
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
        let band = |b: &Blade| b.axis.is_some() || is_paired(segs, b, c);
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
        clutter_lines: clutter_lines(sc, c, spinner_r, &lines, &tower),
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
    let square = square_blades(sc, c, &blades);
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
        square,
    }
}

/// How far from the hub a blade's direction is undistorted, fraction of the working height:
/// near the hub, where the blade's lines met, and far enough for a sub-degree direction.
const BLADE_DIRECTION_STEP_FRAC: f64 = 0.1;

/// Whether, without a tracker's prediction, two or more blades are seen at `c` and every one
/// of them lies within `square_blades_max_deg` of the world's vertical or horizontal (the
/// blades' image angles taken through the lens's undistortion when it bends straight lines,
/// and the camera's roll removed). Three blades 120° apart always have one at least 30° from
/// both (still 20° at 45° of relative yaw or of pitch), while a roof, a chimney's rim, a mast
/// with its stays or field borders at the horizon meet at right angles.
pub(super) fn square_blades(sc: &SceneCtx<'_>, c: P2, blades: &[Blade]) -> bool {
    let p = sc.p;
    if p.square_blades_max_deg <= 0.0 || sc.hints.predicted_hub_px.is_some() || blades.len() < 2 {
        return false;
    }
    let undistorted_c = sc.camera.map(|cam| cam.undistort_pixel(c));
    let undistorted_angle = |a: f64| match (&sc.camera, undistorted_c) {
        (Some(cam), Some(q0)) => {
            let d = geometry::dir_from_up_cw(a);
            let step = BLADE_DIRECTION_STEP_FRAC * sc.h;
            let q1 = cam.undistort_pixel([c[0] + step * d[0], c[1] + step * d[1]]);
            geometry::up_cw_deg([q1[0] - q0[0], q1[1] - q0[1]])
        }
        _ => a,
    };
    blades.iter().take(ROTOR_BLADES).all(|b| {
        geometry::off_axes_deg(undistorted_angle(b.angle_deg) + sc.roll_deg)
            <= p.square_blades_max_deg
    })
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
