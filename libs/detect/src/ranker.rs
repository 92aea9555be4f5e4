//! The learned candidate ranker: a logistic model over what the default pipeline measured at a
//! hub candidate.
//!
//! The rule confidence (`conf_*` parameters) adds fixed bonuses per cue; which cue matters how
//! much, and how cues interact with the blades' lengths and the rotor's shape, is learned here
//! from the project's own renderer instead (`hubtrack train-ranker`, never from `../shared/data`).
//! The model is a weight per feature; the probability that a candidate is the hub is
//! `1 / (1 + exp(-w·f))`. All features are scale-free (lengths over the working image height),
//! so one model serves every camera and pyramid level.

use crate::geometry;

/// Names of the features, in order; the keys of `detect.default.ranker_weights`.
pub const FEATURE_NAMES: [&str; FEATURES] = [
    "bias",
    "two_blades",
    "three_blades",
    "extra_blades",
    "tower",
    "tower_lines",
    "hidden_blade_down",
    "geometry_ok",
    "paired",
    "spinner",
    "spinner_radius",
    "spinner_size_match",
    "passes_through",
    "near_prediction",
    "support",
    "weakest_blade",
    "strongest_blade",
    "separation_error",
    "rejected_lines",
    "rule_score",
    "clutter",
    "banded_blades",
    "tower_top_below",
    "image_lines",
    "spinner_coverage",
    "spinner_axes_offset",
    "hub_heat",
];

/// Number of features.
pub const FEATURES: usize = 27;

/// Index of the feature set after evaluation, when the spinner's size matches the tracker's
/// distance.
pub(crate) const SPINNER_SIZE_MATCH: usize = 11;
/// Index of the spinner circle's rim coverage, set by the spinner step.
pub(crate) const SPINNER_COVERAGE: usize = 24;
/// Index of the distance (in radii, at most 2) from the spinner circle's centre to where its
/// blades' axes meet, set by the spinner step for circles above
/// `spinner_kept_support_max_radius_px` (0 otherwise).
pub(crate) const SPINNER_AXES_OFFSET: usize = 25;
/// Index of the learned heatmap's probability at the candidate, set by `recognise`.
pub(crate) const HUB_HEAT: usize = 26;

/// One candidate's feature vector.
pub type Features = [f64; FEATURES];

/// What the pipeline measured at one candidate (working px).
#[derive(Debug, Clone, Default)]
pub(crate) struct Cues {
    /// Blade groups kept.
    pub blades: usize,
    /// Tower lines below the candidate.
    pub tower_lines: usize,
    /// Two blades about 120° apart whose missing third would point down the tower.
    pub hidden_blade_down: bool,
    /// The strongest blades' separations fit a rotor.
    pub geometry_ok: bool,
    /// Blades seen by both edges (or with a band axis).
    pub paired: usize,
    /// Radius of the spinner circle centred at the candidate (0: none).
    pub spinner_radius: f64,
    /// A long line passes through the candidate.
    pub passes_through: bool,
    /// The candidate lies near the tracker's prediction.
    pub near_prediction: bool,
    /// Summed line length of the strongest (up to 3) blades, strongest first.
    pub blade_weights: Vec<f64>,
    /// Their directions, degrees.
    pub blade_angles: Vec<f64>,
    /// Lines dropped as tower, opposite or weak blades.
    pub rejected_lines: usize,
    /// The rule confidence before capping.
    pub rule_score: f64,
    /// Usable lines passing near the candidate that neither support it nor belong to its tower.
    pub clutter_lines: usize,
    /// Blades whose two edges pair into a band with an axis.
    pub banded_blades: usize,
    /// How far the tower's top lies below the candidate, px (`None`: no tower).
    pub tower_top_below: Option<f64>,
    /// Usable lines in the whole image.
    pub image_lines: usize,
    /// Working image height, px.
    pub image_height: f64,
}

/// The feature vector of `c`.
pub(crate) fn features(c: &Cues) -> Features {
    let h = c.image_height.max(1.0);
    let flag = |b: bool| if b { 1.0 } else { 0.0 };
    let weights = &c.blade_weights;
    let mut f = [0.0; FEATURES];
    f[0] = 1.0;
    f[1] = flag(c.blades == 2);
    f[2] = flag(c.blades == 3);
    f[3] = c.blades.saturating_sub(3).min(3) as f64;
    f[4] = flag(c.tower_lines > 0);
    f[5] = c.tower_lines.min(4) as f64 / 4.0;
    f[6] = flag(c.hidden_blade_down);
    f[7] = flag(c.geometry_ok);
    f[8] = c.paired.min(3) as f64 / 3.0;
    f[9] = flag(c.spinner_radius > 0.0);
    f[10] = c.spinner_radius / h;
    f[SPINNER_SIZE_MATCH] = 0.0;
    f[12] = flag(c.passes_through);
    f[13] = flag(c.near_prediction);
    f[14] = weights.iter().sum::<f64>() / h;
    f[15] = if weights.len() >= 2 {
        weights.iter().copied().fold(f64::INFINITY, f64::min) / h
    } else {
        0.0
    };
    f[16] = weights.first().map_or(0.0, |w| w / h);
    f[17] = separation_error(&c.blade_angles);
    f[18] = c.rejected_lines.min(10) as f64 / 10.0;
    f[19] = c.rule_score;
    f[20] = c.clutter_lines.min(10) as f64 / 10.0;
    f[21] = c.banded_blades.min(3) as f64 / 3.0;
    f[22] = c.tower_top_below.map_or(0.0, |d| (d / h).clamp(-0.5, 0.5));
    f[23] = c.image_lines.min(200) as f64 / 200.0;
    f
}

/// How far the blades' pairwise separations lie from a three-bladed rotor's, in units of 60°:
/// each pair's distance to the nearer of 120° (neighbours) and 240° (the reflex angle of two
/// with the third between), mean over pairs; 1 with fewer than two blades.
fn separation_error(angles: &[f64]) -> f64 {
    let mut sum = 0.0;
    let mut n = 0;
    for (i, a) in angles.iter().enumerate() {
        for b in &angles[i + 1..] {
            let d = geometry::ang_dist(*a, *b);
            sum += (d - 120.0).abs().min((d - 240.0).abs()) / 60.0;
            n += 1;
        }
    }
    if n == 0 {
        1.0
    } else {
        sum / n as f64
    }
}

/// The model's score of the candidate with `f`: log-odds that it is the hub rather than no hub.
pub fn score(weights: &[f64; FEATURES], f: &Features) -> f64 {
    weights.iter().zip(f).map(|(w, x)| w * x).sum()
}

/// `1 / (1 + e^-s)`: a score as a probability.
pub fn logistic(s: f64) -> f64 {
    1.0 / (1.0 + (-s).exp())
}

/// One frame of training data: every candidate the pipeline evaluated, and which lie on the
/// hub (within the evaluation's hit tolerance of the rotor axis).
#[derive(Debug, Clone, Default)]
pub struct TrainingFrame {
    /// Features of each candidate.
    pub features: Vec<Features>,
    /// Whether each candidate lies on the hub.
    pub on_hub: Vec<bool>,
}

/// Settings of [`fit`].
#[derive(Debug, Clone, Copy)]
pub struct FitSettings {
    /// Weight of the squared-weight penalty, against the summed log-loss of all frames.
    pub l2: f64,
    /// Gradient steps.
    pub iterations: usize,
    /// Step size on the per-frame mean gradient.
    pub step: f64,
}

/// Fits the ranker's weights: a conditional logit over each frame's candidates plus a "no hub"
/// option of score 0, so a frame is a choice among its candidates or none. The chosen one is
/// the best-scored candidate on the hub, or none when no candidate lies on it (a negative frame,
/// or a hub no candidate found). Full-batch gradient descent from zero: deterministic.
pub fn fit(frames: &[TrainingFrame], settings: &FitSettings) -> [f64; FEATURES] {
    let mut w = [0.0; FEATURES];
    let n = frames.len().max(1) as f64;
    let mut probs = Vec::new();
    for _ in 0..settings.iterations {
        let mut grad = w.map(|x| settings.l2 * x);
        for fr in frames {
            if fr.features.is_empty() {
                continue;
            }
            let scores: Vec<f64> = fr.features.iter().map(|f| score(&w, f)).collect();
            let target = (0..scores.len())
                .filter(|&k| fr.on_hub[k])
                .max_by(|&a, &b| scores[a].total_cmp(&scores[b]));
            // Softmax with the "no hub" option at score 0, shifted for stability.
            let m = scores.iter().copied().fold(0.0, f64::max);
            probs.clear();
            probs.extend(scores.iter().map(|s| (s - m).exp()));
            let z: f64 = probs.iter().sum::<f64>() + (-m).exp();
            for (k, f) in fr.features.iter().enumerate() {
                let t = if target == Some(k) { 1.0 } else { 0.0 };
                let d = probs[k] / z - t;
                for (g, x) in grad.iter_mut().zip(f) {
                    *g += d * x;
                }
            }
        }
        for (x, g) in w.iter_mut().zip(grad) {
            *x -= settings.step * g / n;
        }
    }
    w
}

/// How a ranker does on frames: the best candidate by score is reported when its score reaches
/// `min_score`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RankingOutcome {
    /// Frames with a hub.
    pub frames_with_hub: usize,
    /// ... whose reported candidate lies on it.
    pub hits: usize,
    /// ... with some candidate on it (the most any ranking could hit).
    pub reachable: usize,
    /// Frames without a turbine.
    pub negatives: usize,
    /// ... where a candidate was reported.
    pub false_positives: usize,
}

/// Scores a ranking (`weights`, `min_score`) on `frames`; `negative[i]` marks frame `i` as
/// showing no turbine.
pub fn assess(
    frames: &[TrainingFrame],
    negative: &[bool],
    weights: &[f64; FEATURES],
    min_score: f64,
) -> RankingOutcome {
    let mut o = RankingOutcome::default();
    for (fr, &neg) in frames.iter().zip(negative) {
        let best = (0..fr.features.len())
            .map(|k| (k, score(weights, &fr.features[k])))
            .max_by(|a, b| a.1.total_cmp(&b.1));
        let reported = best.filter(|(_, s)| *s >= min_score).map(|(k, _)| k);
        if neg {
            o.negatives += 1;
            o.false_positives += usize::from(reported.is_some());
        } else {
            o.frames_with_hub += 1;
            o.hits += usize::from(reported.is_some_and(|k| fr.on_hub[k]));
            o.reachable += usize::from(fr.on_hub.iter().any(|&b| b));
        }
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rotor_at_120_degrees_has_no_separation_error() {
        assert!(separation_error(&[0.0, 120.0, 240.0]) < 1e-9);
        assert!(separation_error(&[10.0, 130.0]) < 1e-9);
        assert!((separation_error(&[0.0, 60.0]) - 1.0).abs() < 1e-9);
        assert_eq!(separation_error(&[0.0]), 1.0);
    }

    #[test]
    fn features_are_scale_free() {
        let cues = |h: f64| Cues {
            blades: 3,
            blade_weights: vec![0.5 * h, 0.3 * h, 0.2 * h],
            blade_angles: vec![0.0, 120.0, 240.0],
            spinner_radius: 0.05 * h,
            image_height: h,
            ..Cues::default()
        };
        assert_eq!(features(&cues(270.0)), features(&cues(540.0)));
    }

    #[test]
    fn the_score_is_the_weighted_feature_sum() {
        let mut w = [0.0; FEATURES];
        assert_eq!(score(&w, &[1.0; FEATURES]), 0.0);
        assert!((logistic(0.0) - 0.5).abs() < 1e-12);
        w[0] = 2.0;
        w[17] = -1.0;
        // No blades: bias 2 and separation error 1.
        assert!(
            (score(
                &w,
                &features(&Cues {
                    image_height: 100.0,
                    ..Cues::default()
                })
            ) - 1.0)
                .abs()
                < 1e-12
        );
    }

    /// Frames where the hub is the candidate with a spinner and more paired blades, among
    /// decoys with more support, and negatives with decoys only: the fit learns to prefer the
    /// spinner and to report nothing on the negatives.
    #[test]
    fn the_fit_prefers_the_cue_that_marks_the_hub() {
        let cand = |spinner: bool, support: f64| {
            let mut f = [0.0; FEATURES];
            f[0] = 1.0;
            f[9] = if spinner { 1.0 } else { 0.0 };
            f[14] = support;
            f
        };
        let mut frames = Vec::new();
        let mut negative = Vec::new();
        for i in 0..40 {
            let s = 1.0 + (i % 5) as f64 * 0.1;
            frames.push(TrainingFrame {
                features: vec![cand(false, s + 0.5), cand(true, s), cand(false, s + 0.2)],
                on_hub: vec![false, true, false],
            });
            negative.push(false);
            frames.push(TrainingFrame {
                features: vec![cand(false, s + 0.5), cand(false, s)],
                on_hub: vec![false, false],
            });
            negative.push(true);
        }
        let w = fit(
            &frames,
            &FitSettings {
                l2: 1.0,
                iterations: 500,
                step: 1.0,
            },
        );
        assert!(w[9] > 1.0, "spinner weight {}", w[9]);
        let o = assess(&frames, &negative, &w, 0.0);
        assert_eq!((o.hits, o.frames_with_hub, o.reachable), (40, 40, 40));
        assert_eq!(o.false_positives, 0);
        // Zero weights report every frame's first-best candidate: decoys and false positives.
        let o = assess(&frames, &negative, &[0.0; FEATURES], 0.0);
        assert_eq!(o.false_positives, 40);
    }
}
