//! Scoring of hub detections, as defined in `../shared/data/README.md`: a detection is a hit when
//! it lies within 3 % of the image height of the visible rotor axis, the segment from the
//! blade-axis point to the spinner (nose); a negative with any detection is a false positive.

use std::collections::BTreeMap;

/// Hit tolerance, fraction of image height.
pub const HIT_TOLERANCE: f64 = 0.03;

/// Distance from `p` to the segment `a`–`b`.
pub fn point_segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (cx, cy) = (a[0] + t * dx, a[1] + t * dy);
    ((p[0] - cx).powi(2) + (p[1] - cy).powi(2)).sqrt()
}

/// Truth of one evaluation image.
#[derive(Debug, Clone)]
pub enum Truth {
    /// A turbine whose hub is visible: the rotor-axis segment.
    Visible { axis: [f64; 2], hub: [f64; 2] },
    /// A turbine whose hub is hidden or cut: counts neither way.
    Hidden,
    /// No turbine.
    Negative,
}

impl Truth {
    /// The truth of a rendered frame with a turbine: visible when the renderer saw the hub and
    /// its nose, else hidden.
    pub fn of_rendered(t: &hubtrack_render::Truth) -> Truth {
        match (t.turbine_in_view, t.hub_px, t.nose_px) {
            (true, Some(hub), Some(nose)) => Truth::Visible {
                axis: hub,
                hub: nose,
            },
            _ => Truth::Hidden,
        }
    }
}

/// Outcome of one image in one mode.
#[derive(Debug, Clone, Copy, Default)]
pub struct Outcome {
    /// The detector reported a hub.
    pub detected: bool,
    /// Error in % of image height (visible-hub images with a detection).
    pub error_pct: Option<f64>,
    /// Hit (visible-hub images).
    pub hit: bool,
}

/// Scores one detection against its truth.
pub fn score(truth: &Truth, detected_hub: Option<[f64; 2]>, image_height: f64) -> Outcome {
    match (truth, detected_hub) {
        (Truth::Visible { axis, hub }, Some(p)) => {
            let e = point_segment_distance(p, *axis, *hub) / image_height;
            Outcome {
                detected: true,
                error_pct: Some(100.0 * e),
                hit: e <= HIT_TOLERANCE,
            }
        }
        (_, d) => Outcome {
            detected: d.is_some(),
            ..Default::default()
        },
    }
}

/// Accumulated results of one category in one mode.
#[derive(Debug, Clone, Default)]
pub struct Tally {
    /// Visible-hub images.
    pub visible: u64,
    /// Of those, detected.
    pub detected: u64,
    /// Of those, hits.
    pub hits: u64,
    /// Errors of detected visible-hub images, % of height.
    pub errors: Vec<f64>,
    /// Negative images.
    pub negatives: u64,
    /// Negatives with a detection.
    pub false_positives: u64,
    /// Hidden-hub images (not scored).
    pub hidden: u64,
}

impl Tally {
    /// Adds one image.
    pub fn add(&mut self, truth: &Truth, o: &Outcome) {
        match truth {
            Truth::Visible { .. } => {
                self.visible += 1;
                self.detected += o.detected as u64;
                self.hits += o.hit as u64;
                self.errors.extend(o.error_pct);
            }
            Truth::Negative => {
                self.negatives += 1;
                self.false_positives += o.detected as u64;
            }
            Truth::Hidden => self.hidden += 1,
        }
    }

    /// Median and 90th percentile of the errors.
    pub fn error_percentiles(&self) -> (f64, f64) {
        let mut e = self.errors.clone();
        if e.is_empty() {
            return (f64::NAN, f64::NAN);
        }
        e.sort_by(|a, b| a.total_cmp(b));
        let at = |q: f64| e[((e.len() - 1) as f64 * q).round() as usize];
        (at(0.5), at(0.9))
    }
}

/// Per-category tallies for each mode: `tallies[category][mode]`.
pub type Table = BTreeMap<String, Vec<Tally>>;

fn pct(n: u64, d: u64) -> String {
    if d == 0 {
        "-".into()
    } else {
        format!("{:.1}", 100.0 * n as f64 / d as f64)
    }
}

/// Prints the table with one column group per mode.
pub fn print_table(title: &str, modes: &[&str], table: &Table) {
    println!("\n{title}");
    let mut head = format!("{:<22}{:>7}", "category", "images");
    for m in modes {
        head += &format!(
            " | {:<8}{:>6}{:>6}{:>7}{:>7}{:>6}",
            m, "det%", "hit%", "med%h", "p90%h", "FP%"
        );
    }
    println!("{head}");
    for (cat, tallies) in table {
        let t0 = &tallies[0];
        let mut row = format!("{:<22}{:>7}", cat, t0.visible + t0.negatives + t0.hidden);
        for t in tallies {
            let (med, p90) = t.error_percentiles();
            let f = |v: f64| {
                if v.is_nan() {
                    "-".to_string()
                } else {
                    format!("{v:.2}")
                }
            };
            row += &format!(
                " | {:<8}{:>6}{:>6}{:>7}{:>7}{:>6}",
                "",
                pct(t.detected, t.visible),
                pct(t.hits, t.visible),
                f(med),
                f(p90),
                pct(t.false_positives, t.negatives)
            );
        }
        println!("{row}");
    }
    println!("det% and hit% over images with a visible hub; med/p90 error in % of image height over detections; FP% over negatives");
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distance_to_segment() {
        assert_eq!(
            point_segment_distance([0.0, 1.0], [-1.0, 0.0], [1.0, 0.0]),
            1.0
        );
        assert_eq!(
            point_segment_distance([3.0, 0.0], [-1.0, 0.0], [1.0, 0.0]),
            2.0
        );
        assert_eq!(
            point_segment_distance([5.0, 5.0], [1.0, 1.0], [1.0, 1.0]),
            (32.0f64).sqrt()
        );
    }

    #[test]
    fn hit_within_three_percent_of_height() {
        let t = Truth::Visible {
            axis: [100.0, 100.0],
            hub: [120.0, 100.0],
        };
        assert!(score(&t, Some([110.0, 132.0]), 1080.0).hit);
        assert!(!score(&t, Some([110.0, 134.0]), 1080.0).hit);
        let o = score(&Truth::Negative, Some([1.0, 1.0]), 1080.0);
        let mut tally = Tally::default();
        tally.add(&Truth::Negative, &o);
        assert_eq!((tally.negatives, tally.false_positives), (1, 1));
    }
}
