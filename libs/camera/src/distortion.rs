//! Lens distortion in normalised image coordinates (`x/z`, `y/z`), with OpenCV's formulas.

use serde::{Deserialize, Serialize};

/// Newton steps when inverting a distortion; each converges quadratically within the monotonic
/// range, so this is a guard against oscillation, not an accuracy setting.
const MAX_NEWTON_STEPS: usize = 50;
/// Stop iterating once a step moves the estimate by less than this (normalised units).
const NEWTON_TOLERANCE: f64 = 1e-14;
/// Normalised radius up to which the monotonic range of a radial polynomial is searched: 10 is
/// 84° off axis, beyond any lens the plumb_bob model describes well.
const PLUMB_BOB_SEARCH_RADIUS: f64 = 10.0;
/// Steps of that search (the fold-over point is then refined by bisection).
const MONOTONIC_SEARCH_STEPS: usize = 400;

/// A lens distortion model.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "model", rename_all = "snake_case")]
pub enum Distortion {
    /// An ideal pinhole.
    None,
    /// ROS `plumb_bob` = OpenCV's default model: radial `1 + k1 r² + k2 r⁴ + k3 r⁶` and
    /// tangential `p1`, `p2`.
    PlumbBob {
        /// Radial r².
        k1: f64,
        /// Radial r⁴.
        k2: f64,
        /// Tangential 1.
        p1: f64,
        /// Tangential 2.
        p2: f64,
        /// Radial r⁶.
        k3: f64,
    },
    /// ROS `equidistant` = OpenCV's fisheye model: `θd = θ (1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸)`
    /// with `θ` the angle off the optical axis.
    Equidistant {
        /// θ².
        k1: f64,
        /// θ⁴.
        k2: f64,
        /// θ⁶.
        k3: f64,
        /// θ⁸.
        k4: f64,
    },
}

impl Distortion {
    /// Radial-only plumb_bob (the renderer's historic two-term model).
    pub fn radial(k1: f64, k2: f64) -> Distortion {
        if k1 == 0.0 && k2 == 0.0 {
            Distortion::None
        } else {
            Distortion::PlumbBob {
                k1,
                k2,
                p1: 0.0,
                p2: 0.0,
                k3: 0.0,
            }
        }
    }

    /// The ROS `distortion_model` name.
    pub fn ros_name(&self) -> &'static str {
        match self {
            Distortion::None | Distortion::PlumbBob { .. } => "plumb_bob",
            Distortion::Equidistant { .. } => "equidistant",
        }
    }

    /// The ROS `D` vector.
    pub fn coefficients(&self) -> Vec<f64> {
        match *self {
            Distortion::None => vec![0.0; 5],
            Distortion::PlumbBob { k1, k2, p1, p2, k3 } => vec![k1, k2, p1, p2, k3],
            Distortion::Equidistant { k1, k2, k3, k4 } => vec![k1, k2, k3, k4],
        }
    }

    /// Every coefficient is finite.
    pub fn is_finite(&self) -> bool {
        self.coefficients().iter().all(|c| c.is_finite())
    }

    /// Distorted radius (normalised) of an undistorted radius `r`, radial part only.
    pub fn radial_map(&self, r: f64) -> f64 {
        match *self {
            Distortion::None => r,
            Distortion::PlumbBob { k1, k2, k3, .. } => {
                let r2 = r * r;
                r * (1.0 + r2 * (k1 + r2 * (k2 + r2 * k3)))
            }
            Distortion::Equidistant { k1, k2, k3, k4 } => {
                let t = r.atan();
                let t2 = t * t;
                t * (1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4))))
            }
        }
    }

    /// Sign-relevant slope of [`Distortion::radial_map`]: d r_d / d r for plumb_bob, d θd / d θ
    /// for equidistant (θ increases with r, so the signs agree).
    fn radial_slope(&self, r: f64) -> f64 {
        match *self {
            Distortion::None => 1.0,
            Distortion::PlumbBob { k1, k2, k3, .. } => {
                let s = r * r;
                1.0 + s * (3.0 * k1 + s * (5.0 * k2 + s * 7.0 * k3))
            }
            Distortion::Equidistant { k1, k2, k3, k4 } => {
                let t = r.atan();
                let u = t * t;
                1.0 + u * (3.0 * k1 + u * (5.0 * k2 + u * (7.0 * k3 + u * 9.0 * k4)))
            }
        }
    }

    /// Largest undistorted normalised radius up to which [`Distortion::radial_map`] increases
    /// (beyond it the model folds back and projection is undefined); infinite if it never folds
    /// within the range a lens can have.
    pub fn max_radius(&self) -> f64 {
        let limit = match self {
            Distortion::None => return f64::INFINITY,
            Distortion::PlumbBob { .. } => PLUMB_BOB_SEARCH_RADIUS,
            // θ < 90°: search in θ up to 89.9° (r ≈ 573).
            Distortion::Equidistant { .. } => (89.9f64).to_radians().tan(),
        };
        // Scan evenly in θ = atan(r) for the first non-positive slope, then bisect on it.
        let t_max = limit.atan();
        let step = t_max / MONOTONIC_SEARCH_STEPS as f64;
        for i in 1..=MONOTONIC_SEARCH_STEPS {
            let t = step * i as f64;
            if self.radial_slope(t.tan()) <= 0.0 {
                let (mut lo, mut hi) = ((t - step).tan(), t.tan());
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if mid <= lo || mid >= hi {
                        break;
                    }
                    if self.radial_slope(mid) > 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                return lo;
            }
        }
        match self {
            Distortion::Equidistant { .. } => f64::INFINITY,
            _ => limit,
        }
    }

    /// Undistorted normalised point → distorted normalised point (OpenCV's formulas).
    pub fn distort(&self, p: [f64; 2]) -> [f64; 2] {
        let [x, y] = p;
        match *self {
            Distortion::None => p,
            Distortion::PlumbBob { k1, k2, p1, p2, k3 } => {
                let r2 = x * x + y * y;
                let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
                [
                    x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
                    y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y,
                ]
            }
            Distortion::Equidistant { .. } => {
                let r = (x * x + y * y).sqrt();
                if r < 1e-12 {
                    return p;
                }
                let s = self.radial_map(r) / r;
                [x * s, y * s]
            }
        }
    }

    /// Distorted normalised point → undistorted normalised point: the inverse of
    /// [`Distortion::distort`] within the monotonic range (Newton iteration; exact to ~1e-12).
    /// Points beyond the image circle of the model map to its edge.
    pub fn undistort(&self, pd: [f64; 2]) -> [f64; 2] {
        match *self {
            Distortion::None => pd,
            Distortion::Equidistant { .. } => self.undistort_radial(pd),
            Distortion::PlumbBob { p1, p2, .. } if p1 == 0.0 && p2 == 0.0 => {
                self.undistort_radial(pd)
            }
            Distortion::PlumbBob { .. } => self.undistort_newton_2d(pd),
        }
    }

    /// Radially symmetric models: solve `radial_map(r) = |pd|` for r.
    fn undistort_radial(&self, pd: [f64; 2]) -> [f64; 2] {
        let rd = (pd[0] * pd[0] + pd[1] * pd[1]).sqrt();
        if rd < 1e-15 {
            return pd;
        }
        let r_max = self.max_radius();
        let rd_max = if r_max.is_finite() {
            self.radial_map(r_max)
        } else {
            f64::INFINITY
        };
        if rd >= rd_max {
            let s = r_max / rd;
            return [pd[0] * s, pd[1] * s];
        }
        // Newton on θ = atan(r) keeps the equidistant model well scaled near 90°.
        let f = |t: f64| self.radial_map(t.tan()) - rd;
        let t_hi = if r_max.is_finite() {
            r_max.atan()
        } else {
            std::f64::consts::FRAC_PI_2 - 1e-9
        };
        let mut t = rd.atan().min(t_hi);
        let (mut lo, mut hi) = (0.0, t_hi);
        for _ in 0..MAX_NEWTON_STEPS {
            let v = f(t);
            if v > 0.0 {
                hi = t;
            } else {
                lo = t;
            }
            let h = 1e-7 * (1.0 + t);
            let d = (f(t + h) - f(t - h)) / (2.0 * h);
            let mut next = if d > 0.0 { t - v / d } else { f64::NAN };
            if !(next > lo && next < hi) {
                next = 0.5 * (lo + hi); // Newton left the bracket: bisect.
            }
            let done = (next - t).abs() < NEWTON_TOLERANCE;
            t = next;
            if done {
                break;
            }
        }
        let s = t.tan() / rd;
        [pd[0] * s, pd[1] * s]
    }

    /// plumb_bob with tangential terms: 2-D Newton with the analytic Jacobian.
    fn undistort_newton_2d(&self, pd: [f64; 2]) -> [f64; 2] {
        let Distortion::PlumbBob { k1, k2, p1, p2, k3 } = *self else {
            return pd;
        };
        let mut p = pd;
        for _ in 0..MAX_NEWTON_STEPS {
            let [x, y] = p;
            let d = self.distort(p);
            let (ex, ey) = (d[0] - pd[0], d[1] - pd[1]);
            let r2 = x * x + y * y;
            let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
            let dradial = k1 + 2.0 * k2 * r2 + 3.0 * k3 * r2 * r2; // d radial / d r2
            let j00 = radial + 2.0 * x * x * dradial + 2.0 * p1 * y + 6.0 * p2 * x;
            let j01 = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
            let j10 = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
            let j11 = radial + 2.0 * y * y * dradial + 6.0 * p1 * y + 2.0 * p2 * x;
            let det = j00 * j11 - j01 * j10;
            if det.abs() < 1e-12 || !det.is_finite() {
                break;
            }
            let dx = (j11 * ex - j01 * ey) / det;
            let dy = (-j10 * ex + j00 * ey) / det;
            p = [x - dx, y - dy];
            if dx.abs() + dy.abs() < NEWTON_TOLERANCE {
                break;
            }
        }
        p
    }
}
