//! The distance from the spinner's looming, read back from a recording: a check on the tracked
//! distance that needs neither the spinner's size nor the truth.
//!
//! The turbine does not move. The spinner circle's radius grows as 1/distance, so over a stretch
//! Δ flown toward the hub (the autopilot's position, projected on the line of sight) the distance
//! now is Δ·r₁/(r₂ − r₁), r₁ and r₂ the radii at either end, whatever the spinner's true size.
//! A distance read 1.5× long or short close in (a tower band merged with a blade, a spinner
//! circle fitted to a part of the spinner) shows as a disagreement with it. The triangulating
//! parallax of the tracker has no baseline on a straight approach; this is the motion cue that
//! has one. The stretch must show the same circle at both ends: one spanning a switch from the
//! spinner to a smaller circle reads the distance as wrongly as the switch does.
//!
//! Pure: the caller gives each frame's vehicle position, line of sight and circle radius.

/// Radii are the median over this many frames either side of each end (the circle fit jitters;
/// fewer at the recording's ends).
pub const SMOOTH_FRAMES: usize = 3;
/// Least stretch flown toward the hub, m ...
pub const MIN_FLOWN_M: f64 = 2.0;
/// ... and at least this share of the tracked distance (a shorter one amplifies the radii's
/// jitter: at 12–20 m over 20 % the looming distance is good to 7 % median, 34 % p90).
pub const MIN_FLOWN_FRAC: f64 = 0.2;
/// The stretch's start is looked for this many frames back at most.
pub const MAX_LOOKBACK_FRAMES: usize = 300;
/// A looming distance and a tracked one disagree when one is more than this factor of the other.
pub const DISAGREE_FACTOR: f64 = 1.5;

/// One frame as the check reads it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sight {
    /// The vehicle's position, north and east, m (`None`: no valid position).
    pub position_ne_m: Option<[f64; 2]>,
    /// Direction of the hub from the vehicle, radians from north (heading plus the hub's
    /// bearing in the image).
    pub line_of_sight_rad: f64,
    /// The spinner circle's radius, px (`None`: no circle in this frame).
    pub radius_px: Option<f64>,
    /// The tracked distance, m (`None`: not valid).
    pub tracked_m: Option<f64>,
}

/// The looming distance of each frame (see the module docs), m; `None` where the vehicle has
/// not flown far enough toward the hub within [`MAX_LOOKBACK_FRAMES`], a circle is missing at
/// either end, or the circle did not grow.
pub fn distances(sights: &[Sight]) -> Vec<Option<f64>> {
    let radii: Vec<Option<f64>> = (0..sights.len())
        .map(|i| smoothed_radius(sights, i))
        .collect();
    (0..sights.len())
        .map(|i| distance_at(sights, &radii, i))
        .collect()
}

/// Frame `i`'s looming distance, `radii` each frame's smoothed radius.
fn distance_at(sights: &[Sight], radii: &[Option<f64>], i: usize) -> Option<f64> {
    let now = &sights[i];
    let tracked = now.tracked_m?;
    let [n2, e2] = now.position_ne_m?;
    let (sin, cos) = now.line_of_sight_rad.sin_cos();
    let stretch = MIN_FLOWN_M.max(MIN_FLOWN_FRAC * tracked);
    for j in (i.saturating_sub(MAX_LOOKBACK_FRAMES)..i).rev() {
        let Some([n1, e1]) = sights[j].position_ne_m else {
            continue;
        };
        let flown = (n2 - n1) * cos + (e2 - e1) * sin;
        if flown >= stretch {
            let (r1, r2) = (radii[j]?, radii[i]?);
            return (r2 > r1).then(|| flown * r1 / (r2 - r1));
        }
    }
    None
}

/// The median radius over a window centred on frame `i`, as wide either side as the recording
/// allows (a one-sided window at its ends would bias the radius toward the neighbours').
fn smoothed_radius(sights: &[Sight], i: usize) -> Option<f64> {
    let half = SMOOTH_FRAMES.min(i).min(sights.len() - 1 - i);
    let (lo, hi) = (i - half, i + half + 1);
    let mut radii: Vec<f64> = sights[lo..hi].iter().filter_map(|s| s.radius_px).collect();
    if radii.is_empty() {
        return None;
    }
    radii.sort_by(f64::total_cmp);
    Some(radii[radii.len() / 2])
}

/// Whether a looming distance and a tracked one disagree (see [`DISAGREE_FACTOR`]).
pub fn disagree(looming_m: f64, tracked_m: f64) -> bool {
    let ratio = looming_m / tracked_m;
    !(1.0 / DISAGREE_FACTOR..=DISAGREE_FACTOR).contains(&ratio)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A straight approach north from 30 m to 5 m at 0.1 m a frame toward a hub whose spinner
    /// is 200 px in radius at 1 m; the tracked distance is `read(true distance)`.
    fn approach(read: impl Fn(f64) -> f64) -> (Vec<Sight>, Vec<f64>) {
        let hub_north = 30.0;
        let mut sights = Vec::new();
        let mut truth = Vec::new();
        let mut north = 0.0;
        while hub_north - north >= 5.0 {
            let d = hub_north - north;
            sights.push(Sight {
                position_ne_m: Some([north, 0.0]),
                line_of_sight_rad: 0.0,
                radius_px: Some(200.0 / d),
                tracked_m: Some(read(d)),
            });
            truth.push(d);
            north += 0.1;
        }
        (sights, truth)
    }

    #[test]
    fn the_looming_distance_is_the_truth_whatever_the_tracked_one_reads() {
        for factor in [1.0, 0.5, 2.0] {
            let (sights, truth) = approach(|d| factor * d);
            let looming = distances(&sights);
            let found: Vec<(f64, f64)> = looming
                .iter()
                .zip(&truth)
                .filter_map(|(l, t)| Some(((*l)?, *t)))
                .collect();
            assert!(
                found.len() > sights.len() / 2,
                "{} of {}",
                found.len(),
                sights.len()
            );
            for (l, t) in &found {
                // The radii are smoothed over ±3 frames of a 1/d curve: a few per cent.
                assert!(
                    (l / t - 1.0).abs() < 0.05,
                    "factor {factor}: looming {l} at {t}"
                );
            }
            let disagreeing = found
                .iter()
                .filter(|(l, t)| disagree(*l, factor * t))
                .count();
            if factor == 1.0 {
                assert_eq!(disagreeing, 0);
            } else {
                assert_eq!(disagreeing, found.len(), "factor {factor}");
            }
        }
    }

    #[test]
    fn no_looming_distance_without_flight_circle_or_growth() {
        // A hover: never flown far enough.
        let hover = vec![
            Sight {
                position_ne_m: Some([0.0, 0.0]),
                line_of_sight_rad: 0.0,
                radius_px: Some(10.0),
                tracked_m: Some(20.0),
            };
            400
        ];
        assert!(distances(&hover).iter().all(Option::is_none));
        // Flying away from the hub (the circle shrinks): no distance either.
        let (mut away, _) = approach(|d| d);
        away.reverse();
        assert!(distances(&away).iter().all(Option::is_none));
        // No circle at all.
        let (mut blind, _) = approach(|d| d);
        blind.iter_mut().for_each(|s| s.radius_px = None);
        assert!(distances(&blind).iter().all(Option::is_none));
    }
}
