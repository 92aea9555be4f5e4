//! Distance from motion parallax: the hub seen from several camera positions is triangulated.
//!
//! The autopilot knows where the vehicle is (`LOCAL_POSITION_NED`), the camera model and the
//! attitude turn each detected hub pixel into a ray in the world frame, and the hub does not
//! move. Rays from positions a few metres apart meet at the hub; the distance from the current
//! position to that point needs neither the tower's nor the spinner's size. It is the check the
//! size-based distances lack: a tower band half hidden behind a blade and a spinner circle fitted
//! to part of the spinner agree with each other at twice the true distance (`fly` seed 412, 60
//! against 33 m from the first frame on), and everything that uses the distance — the nacelle
//! yaw, the hub–tower gap — then reads a wrong yaw.
//!
//! Pure functions over plain data; [`ParallaxRanger`] keeps the sightings of one track.

use crate::estimate::Estimate;
use crate::params::ParallaxConfig;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use std::collections::VecDeque;

/// Nanoseconds per second.
const NS_PER_S: f64 = 1e9;
/// Smallest eigenvalue of the normal matrix relative to its largest below which the rays are
/// taken as parallel (no triangulation).
const MIN_CONDITION: f64 = 1e-9;

/// One sighting of the hub: where the camera was and the direction it saw the hub in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sighting {
    /// Capture time, ns.
    pub t_ns: u64,
    /// Camera position, world frame (NED), m.
    pub camera_m: Vector3<f64>,
    /// Unit ray from the camera toward the detected hub, world frame.
    pub ray: Vector3<f64>,
}

/// The hub triangulated from sightings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Triangulation {
    /// The point nearest to all rays (weighted least squares), world frame, m.
    pub hub_m: Vector3<f64>,
    /// Its covariance, m².
    pub covariance: Matrix3<f64>,
    /// Root mean square of each ray's miss distance from `hub_m` in its own standard deviations.
    pub rms_residual_sigmas: f64,
}

impl Triangulation {
    /// Distance from `camera_m` to the hub with its standard deviation (the covariance along the
    /// line of sight).
    pub fn distance_from(&self, camera_m: &Vector3<f64>) -> Option<Estimate> {
        let to_hub = self.hub_m - camera_m;
        let d = to_hub.norm();
        if d <= 0.0 {
            return None;
        }
        let e = to_hub / d;
        let var = (e.transpose() * self.covariance * e)[(0, 0)];
        (var.is_finite() && var > 0.0).then(|| Estimate {
            value: d,
            std: var.sqrt(),
        })
    }
}

/// The point nearest to all rays. Each ray is weighted by the inverse square of its miss
/// distance's standard deviation at the hub, `(range · bearing_std_rad)² + placement_std_m²`
/// (the angular error of the hub pixel and the attitude, and where on the spinner the detector
/// put the hub, which dominates close in): the ranges come from an unweighted first solution. The covariance is the inverse normal matrix, inflated by `n / independent` when
/// more than `independent` sightings are used (successive frames see the same hub-placement
/// error, so they are not independent). `None` with fewer than two sightings, with rays that
/// are (nearly) parallel, or with a point behind any of the cameras.
pub fn triangulate(
    sightings: &[Sighting],
    bearing_std_rad: f64,
    placement_std_m: f64,
    independent: usize,
) -> Option<Triangulation> {
    let valid_std = bearing_std_rad > 0.0 && placement_std_m >= 0.0; // false for NaN
    if sightings.len() < 2 || !valid_std {
        return None;
    }
    let solve = |weights: &dyn Fn(&Sighting) -> f64| -> Option<(Vector3<f64>, Matrix3<f64>)> {
        let (mut a, mut b) = (Matrix3::zeros(), Vector3::zeros());
        for s in sightings {
            // Projector onto the plane perpendicular to the ray: the miss distance of a point.
            let p = Matrix3::identity() - s.ray * s.ray.transpose();
            let w = weights(s);
            a += p * w;
            b += p * s.camera_m * w;
        }
        let eig = SymmetricEigen::new(a);
        let (lo, hi) = eig
            .eigenvalues
            .iter()
            .fold((f64::INFINITY, 0.0_f64), |(lo, hi), &e| {
                (lo.min(e), hi.max(e))
            });
        if hi.is_nan() || hi <= 0.0 || lo < MIN_CONDITION * hi {
            return None;
        }
        let inv = a.try_inverse()?;
        Some((inv * b, inv))
    };
    let (first, _) = solve(&|_| 1.0)?;
    let miss_var = |range: f64| (range * bearing_std_rad).powi(2) + placement_std_m.powi(2);
    let (hub, inv) = solve(&|s| 1.0 / miss_var((first - s.camera_m).norm()))?;
    let mut sum_sq = 0.0;
    for s in sightings {
        let to_hub = hub - s.camera_m;
        let range = to_hub.norm();
        if range <= 0.0 || to_hub.dot(&s.ray) <= 0.0 {
            return None;
        }
        let miss = (to_hub - s.ray * to_hub.dot(&s.ray)).norm();
        sum_sq += miss * miss / miss_var(range);
    }
    let n = sightings.len();
    let inflation = n as f64 / independent.clamp(1, n) as f64;
    Some(Triangulation {
        hub_m: hub,
        covariance: inv * inflation,
        rms_residual_sigmas: (sum_sq / n as f64).sqrt(),
    })
}

/// The sightings of one hub track and the distance they give (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct ParallaxRanger {
    sightings: VecDeque<Sighting>,
}

impl ParallaxRanger {
    /// Forgets every sighting (a new track: the rays would not meet at one point).
    pub fn clear(&mut self) {
        self.sightings.clear();
    }

    /// Number of sightings held.
    pub fn len(&self) -> usize {
        self.sightings.len()
    }

    /// No sightings held.
    pub fn is_empty(&self) -> bool {
        self.sightings.is_empty()
    }

    /// Adds a sighting and drops those older than `window_s` before it. Only its horizontal
    /// part is kept (see [`ParallaxRanger::distance_from`]).
    pub fn push(&mut self, s: Sighting, cfg: &ParallaxConfig) {
        let Some(s) = horizontal(&s) else { return };
        if self.sightings.back().is_some_and(|last| last.t_ns > s.t_ns) {
            // Time went backwards (a replay restarted): the old rays belong to another pass.
            self.sightings.clear();
        }
        self.sightings.push_back(s);
        let window_ns = (cfg.window_s * NS_PER_S) as u64;
        while self
            .sightings
            .front()
            .is_some_and(|f| s.t_ns.saturating_sub(f.t_ns) > window_ns)
        {
            self.sightings.pop_front();
        }
    }

    /// The distance from `camera_m` to the triangulated hub along the current `ray` to it, when
    /// enough sightings with enough baseline agree: at least `min_sightings`, a relative standard
    /// deviation of at most `max_relative_std`, and rays that pass the point within
    /// `max_residual_sigmas` bearing standard deviations (RMS; more means the sightings are not
    /// of one point), and a point at least `min_distance_baselines` times the spread of the
    /// camera positions across the line of sight away (rays of two different points, or noise, fan out from where the
    /// cameras were and "meet" among them).
    ///
    /// The triangulation is horizontal (north, east): the camera's pitch moves with every
    /// acceleration and the attitude lags it by a degree or two, so a climb with the nose
    /// pitching would make rays cross metres from the hub (a rendered flight read 5–9 m at 33 m
    /// in 3-D while climbing 1 m); the azimuths come from the heading alone. The horizontal
    /// distance is turned into the distance along `ray` by its elevation.
    pub fn distance_from(
        &self,
        camera_m: &Vector3<f64>,
        ray: &Vector3<f64>,
        cfg: &ParallaxConfig,
    ) -> Option<Estimate> {
        if !cfg.enabled || self.sightings.len() < cfg.min_sightings as usize {
            return None;
        }
        let std_rad = cfg.bearing_std_deg.to_radians();
        let (front, back) = self.sightings.as_slices();
        let all: Vec<Sighting> = front.iter().chain(back).copied().collect();
        let tri = triangulate(
            &all,
            std_rad,
            cfg.hub_placement_std_m,
            cfg.independent_sightings as usize,
        )?;
        if tri.rms_residual_sigmas > cfg.max_residual_sigmas {
            return None;
        }
        let here = Vector3::new(camera_m.x, camera_m.y, 0.0);
        let d = tri.distance_from(&here)?;
        if d.std > cfg.max_relative_std * d.value
            || d.value < cfg.min_distance_baselines * baseline(&all, ray)
        {
            return None;
        }
        let cos_elevation = ray.x.hypot(ray.y) / ray.norm();
        (cos_elevation > 0.1).then(|| Estimate {
            value: d.value / cos_elevation,
            std: d.std / cos_elevation,
        })
    }
}

/// Spread of the sightings' horizontal camera positions across the line of sight `ray`, m
/// (motion along the line of sight gives no parallax).
fn baseline(sightings: &[Sighting], ray: &Vector3<f64>) -> f64 {
    let across = Vector3::new(-ray.y, ray.x, 0.0);
    let n = across.norm();
    if n <= 0.0 {
        return 0.0;
    }
    let (lo, hi) = sightings
        .iter()
        .map(|s| s.camera_m.dot(&across) / n)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        });
    if hi >= lo {
        hi - lo
    } else {
        0.0
    }
}

/// The horizontal part of a sighting (camera and ray on the north–east plane); `None` for a
/// vertical ray.
fn horizontal(s: &Sighting) -> Option<Sighting> {
    let ray = Vector3::new(s.ray.x, s.ray.y, 0.0);
    let n = ray.norm();
    (n > 1e-6 && n.is_finite()).then(|| Sighting {
        t_ns: s.t_ns,
        camera_m: Vector3::new(s.camera_m.x, s.camera_m.y, 0.0),
        ray: ray / n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const HUB: [f64; 3] = [30.0, 5.0, -60.0];

    fn sighting(t_s: f64, camera: [f64; 3], error_rad: f64) -> Sighting {
        let c = Vector3::from(camera);
        let to_hub = Vector3::from(HUB) - c;
        // Turn the true ray by `error_rad` about the vertical (a hub placed a few px aside).
        let rot = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), error_rad);
        Sighting {
            t_ns: (t_s * NS_PER_S) as u64,
            camera_m: c,
            ray: rot * to_hub.normalize(),
        }
    }

    /// A camera position and its true ray to the hub.
    fn at(camera: [f64; 3]) -> (Vector3<f64>, Vector3<f64>) {
        let c = Vector3::from(camera);
        (c, (Vector3::from(HUB) - c).normalize())
    }

    fn cfg() -> ParallaxConfig {
        ParallaxConfig::default()
    }

    #[test]
    fn rays_from_a_sideways_pass_meet_at_the_hub() {
        // 4 m of sideways flight, 30 m from the hub: the exact rays give the exact point.
        let s: Vec<Sighting> = (0..20)
            .map(|i| sighting(i as f64 * 0.2, [0.0, -2.0 + 0.2 * i as f64, -60.0], 0.0))
            .collect();
        let tri = triangulate(&s, 0.01, 0.0, 10).unwrap();
        assert!(
            (tri.hub_m - Vector3::from(HUB)).norm() < 1e-6,
            "{:?}",
            tri.hub_m
        );
        assert!(tri.rms_residual_sigmas < 1e-6);
        let d = tri.distance_from(&s[19].camera_m).unwrap();
        let truth = (Vector3::from(HUB) - s[19].camera_m).norm();
        assert!((d.value - truth).abs() < 1e-6);
        // σ ≈ d²·σθ / baseline, inflated by √(20/10): tens of centimetres to a few metres.
        assert!(d.std > 0.5 && d.std < 5.0, "{d:?}");
    }

    #[test]
    fn rays_along_the_line_of_sight_give_no_distance() {
        // Flying straight at the hub: every ray is the same line; nothing to triangulate.
        let dir = (Vector3::from(HUB) - Vector3::new(0.0, 0.0, -60.0)).normalize();
        let s: Vec<Sighting> = (0..20)
            .map(|i| {
                let c = Vector3::new(0.0, 0.0, -60.0) + dir * (0.3 * i as f64);
                Sighting {
                    t_ns: i * 100_000_000,
                    camera_m: c,
                    ray: dir,
                }
            })
            .collect();
        assert!(triangulate(&s, 0.01, 0.5, 10).is_none());
    }

    #[test]
    fn the_ranger_needs_baseline_and_agreeing_rays() {
        let c = cfg();
        let mut r = ParallaxRanger::default();
        // Hovering (gusts move it by centimetres): too little baseline for 20 % accuracy.
        for i in 0..30 {
            r.push(
                sighting(i as f64 * 0.1, [0.0, 0.02 * (i % 3) as f64, -60.0], 0.0),
                &c,
            );
        }
        let (cam, ray) = at([0.0, 0.0, -60.0]);
        assert!(r.distance_from(&cam, &ray, &c).is_none());
        // Then 3 m sideways with half-degree bearing noise: a distance within its error.
        for i in 0..30 {
            let err = if i % 2 == 0 { 0.5_f64 } else { -0.5 }.to_radians();
            r.push(
                sighting(3.0 + i as f64 * 0.1, [0.0, 0.1 * i as f64, -60.0], err),
                &c,
            );
        }
        let (here, ray) = at([0.0, 2.9, -60.0]);
        let d = r
            .distance_from(&here, &ray, &c)
            .expect("distance after a sideways pass");
        let truth = (Vector3::from(HUB) - here).norm();
        assert!(
            (d.value - truth).abs() < 2.0 * d.std + 0.5,
            "{d:?} vs {truth}"
        );
        // Rays of two different points (the track moved to a false hub unnoticed): they fan out
        // from where the cameras were, and a point that near is no triangulation.
        let mut bad = r.clone();
        for i in 0..30 {
            let mut s = sighting(
                6.0 + i as f64 * 0.1,
                [0.0, 3.0 + 0.1 * i as f64, -60.0],
                0.0,
            );
            s.ray = (Vector3::new(30.0, -15.0, -60.0) - s.camera_m).normalize();
            bad.push(s, &c);
        }
        let (cam, ray) = at([0.0, 5.9, -60.0]);
        assert!(bad.distance_from(&cam, &ray, &c).is_none());
    }

    #[test]
    fn old_sightings_leave_the_window_and_time_going_back_clears_it() {
        let c = cfg();
        let mut r = ParallaxRanger::default();
        for i in 0..100 {
            r.push(
                sighting(i as f64 * 0.5, [0.0, 0.1 * i as f64, -60.0], 0.0),
                &c,
            );
        }
        let span = c.window_s / 0.5;
        assert!(
            (r.len() as f64 - (span + 1.0)).abs() <= 1.0,
            "{} sightings",
            r.len()
        );
        r.push(sighting(1.0, [0.0, 0.0, -60.0], 0.0), &c);
        assert_eq!(r.len(), 1);
    }
}
