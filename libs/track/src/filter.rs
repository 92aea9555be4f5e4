//! The Kalman filters: the damped constant-velocity hub filter and a scalar random-walk filter.
//!
//! ## Continuous-time form of the thesis filter (eq. 6.1–6.4)
//! The thesis steps `x ← x + ẋ`, `ẋ ← γ·ẋ` once per frame with `Q = q·I`. Here the velocity is in
//! px/s and decays continuously, `dẋ/dt = −λ·ẋ` with `λ = −ln γ / T_ref` (`T_ref` = one
//! reference frame), so over any `dt`:
//! `ẋ ← a·ẋ`, `x ← x + b·ẋ` with `a = e^{−λ·dt}` (= γ per `T_ref`) and `b = (1 − a)/λ`.
//! Process noise is white noise on position and velocity with densities
//! `q_pos = q·s²/T_ref` (px²/s) and `q_vel = q·s²/T_ref³` ((px/s)²/s), `s` = resolution scale,
//! which adds `q·s²` px² and `q·s²` (px/frame)² per reference step as in the thesis; `Q(dt)` is
//! its exact integral through the dynamics. Transition and noise therefore compose exactly:
//! predicting over `dt₁` then `dt₂` equals predicting over `dt₁ + dt₂`, so the filter state does
//! not depend on the frame rate, only on the time stamps.

use nalgebra::{Matrix2, Matrix2x4, Matrix4, Vector2, Vector4};

use crate::estimate::Estimate;

/// Below this `λ·dt` the noise integrals use their Taylor series (avoids cancellation).
const SERIES_THRESHOLD: f64 = 1e-3;

/// The damped constant-velocity motion model in continuous time, per axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CvModel {
    /// Velocity decay rate λ, 1/s.
    pub lambda: f64,
    /// Position white-noise density, px²/s.
    pub q_pos: f64,
    /// Velocity white-noise density, (px/s)²/s.
    pub q_vel: f64,
}

impl CvModel {
    /// Model from the thesis's per-step values: damping γ and process noise `q` per reference
    /// step of `1 / reference_rate_hz` s, at resolution scale `scale` (image width / reference
    /// width).
    pub fn from_thesis(
        damping: f64,
        process_noise: f64,
        reference_rate_hz: f64,
        scale: f64,
    ) -> CvModel {
        let t_ref = 1.0 / reference_rate_hz;
        let q = process_noise * scale * scale;
        CvModel {
            lambda: -damping.ln() / t_ref,
            q_pos: q / t_ref,
            q_vel: q / t_ref.powi(3),
        }
    }

    /// `(a, b)`: over `dt`, velocity ← a·velocity, position ← position + b·velocity.
    pub fn transition(&self, dt: f64) -> (f64, f64) {
        let u = self.lambda * dt;
        let a = (-u).exp();
        let b = if u < SERIES_THRESHOLD {
            dt * (1.0 - u / 2.0 + u * u / 6.0)
        } else {
            -(-u).exp_m1() / self.lambda
        };
        (a, b)
    }

    /// Per-axis process noise over `dt`: `(Q_pp, Q_pv, Q_vv)`.
    pub fn noise(&self, dt: f64) -> (f64, f64, f64) {
        let u = self.lambda * dt;
        // ∫a², ∫a·b, ∫b² over [0, dt] with a(s) = e^{−λs}, b(s) = (1 − e^{−λs})/λ.
        let (int_aa, int_ab, int_bb) = if u < SERIES_THRESHOLD {
            (
                dt * (1.0 - u + 2.0 * u * u / 3.0),
                dt * dt * (0.5 - u / 2.0 + 7.0 * u * u / 24.0),
                dt.powi(3) * (1.0 / 3.0 - u / 4.0 + 7.0 * u * u / 60.0),
            )
        } else {
            let e1 = -(-u).exp_m1(); // 1 − e^{−u}
            let e2 = -(-2.0 * u).exp_m1(); // 1 − e^{−2u}
            let l = self.lambda;
            (
                e2 / (2.0 * l),
                (e1 - e2 / 2.0) / (l * l),
                (u - 2.0 * e1 + e2 / 2.0) / l.powi(3),
            )
        };
        (
            self.q_pos * dt + self.q_vel * int_bb,
            self.q_vel * int_ab,
            self.q_vel * int_aa,
        )
    }
}

/// Kalman filter of the hub: state `[x, y, ẋ, ẏ]` (px, px/s), measurement `[x, y]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HubFilter {
    /// State `[x, y, ẋ, ẏ]`.
    pub x: Vector4<f64>,
    /// State covariance.
    pub p: Matrix4<f64>,
}

/// Measurement model H (positions only).
fn h() -> Matrix2x4<f64> {
    Matrix2x4::new(1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0)
}

impl HubFilter {
    /// Starts at measurement `z` with position variance `r` (px²) and velocity variance
    /// `vel_var` ((px/s)²), zero velocity.
    pub fn new(z: [f64; 2], r: f64, vel_var: f64) -> HubFilter {
        HubFilter {
            x: Vector4::new(z[0], z[1], 0.0, 0.0),
            p: Matrix4::from_diagonal(&Vector4::new(r, r, vel_var, vel_var)),
        }
    }

    /// Position `[x, y]`.
    pub fn position(&self) -> [f64; 2] {
        [self.x[0], self.x[1]]
    }

    /// Predicts over `dt` s (eq. 4.20–4.21 with the damped model) and adds a known position shift
    /// (the ego-motion, the control input `B·u`) with per-axis variance `shift_var`.
    pub fn predict(&mut self, model: &CvModel, dt: f64, shift: [f64; 2], shift_var: f64) {
        if dt > 0.0 {
            let (a, b) = model.transition(dt);
            let (qpp, qpv, qvv) = model.noise(dt);
            let f = Matrix4::new(
                1.0, 0.0, b, 0.0, //
                0.0, 1.0, 0.0, b, //
                0.0, 0.0, a, 0.0, //
                0.0, 0.0, 0.0, a,
            );
            let q = Matrix4::new(
                qpp, 0.0, qpv, 0.0, //
                0.0, qpp, 0.0, qpv, //
                qpv, 0.0, qvv, 0.0, //
                0.0, qpv, 0.0, qvv,
            );
            self.x = f * self.x;
            self.p = f * self.p * f.transpose() + q;
        }
        self.x[0] += shift[0];
        self.x[1] += shift[1];
        self.p[(0, 0)] += shift_var;
        self.p[(1, 1)] += shift_var;
    }

    /// Innovation `ν = z − H·x`, its covariance `S = H·P·Hᵀ + r·I` and the squared Mahalanobis
    /// distance `νᵀ·S⁻¹·ν`.
    pub fn innovation(&self, z: [f64; 2], r: f64) -> (Vector2<f64>, Matrix2<f64>, f64) {
        let h = h();
        let nu = Vector2::new(z[0], z[1]) - h * self.x;
        let s = h * self.p * h.transpose() + Matrix2::identity() * r;
        let d2 = s
            .try_inverse()
            .map_or(f64::INFINITY, |si| (nu.transpose() * si * nu)[(0, 0)]);
        (nu, s, d2)
    }

    /// Measurement update (eq. 4.22–4.24, Joseph form for symmetry) with `R = r·I`.
    pub fn update(&mut self, z: [f64; 2], r: f64) {
        let h = h();
        let (nu, s, _) = self.innovation(z, r);
        let Some(si) = s.try_inverse() else { return };
        let k = self.p * h.transpose() * si;
        self.x += k * nu;
        let ikh = Matrix4::identity() - k * h;
        self.p = ikh * self.p * ikh.transpose() + k * (Matrix2::identity() * r) * k.transpose();
    }

    /// Rescales pixel quantities by `(rx, ry)` (the frame size changed).
    pub fn rescale(&mut self, rx: f64, ry: f64) {
        let t = Matrix4::from_diagonal(&Vector4::new(rx, ry, rx, ry));
        self.x = t * self.x;
        self.p = t * self.p * t;
    }
}

/// Scalar random-walk Kalman filter with chi-square gating and acceptance of persistent jumps.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ScalarFilter {
    /// Current estimate (meaningful once `initialised`).
    pub value: f64,
    /// Its variance.
    pub var: f64,
    /// A measurement has been accepted since the start.
    pub initialised: bool,
    /// When the last measurement was accepted, ns.
    pub last_accept_ns: Option<u64>,
    /// Consecutive consistent gated-out measurements.
    rejects: u32,
    /// The last gated-out measurement.
    last_reject: Option<Estimate>,
}

impl ScalarFilter {
    /// Random-walk prediction over `dt` s with density `q` (unit²/s) plus a known change `shift`
    /// with variance `shift_var`.
    pub fn predict(&mut self, dt: f64, q: f64, shift: f64, shift_var: f64) {
        if self.initialised {
            self.value += shift;
            self.var += q * dt.max(0.0) + shift_var;
        }
    }

    /// Current estimate, if initialised.
    pub fn estimate(&self) -> Option<Estimate> {
        self.initialised.then(|| Estimate {
            value: self.value,
            std: self.var.sqrt(),
        })
    }

    /// Fuses measurement `z` at `t_ns` unless its normalised innovation² exceeds `gate_chi2`;
    /// after `jump_count` consecutive mutually consistent rejections the filter restarts at the
    /// new value. Returns whether `z` was used.
    pub fn update(&mut self, z: Estimate, gate_chi2: f64, jump_count: u32, t_ns: u64) -> bool {
        let r = z.var();
        if !(z.value.is_finite() && r.is_finite() && r > 0.0) {
            return false;
        }
        if !self.initialised {
            self.restart(z, t_ns);
            return true;
        }
        let s = self.var + r;
        let nu = z.value - self.value;
        if nu * nu <= gate_chi2 * s {
            let k = self.var / s;
            self.value += k * nu;
            self.var *= 1.0 - k;
            self.last_accept_ns = Some(t_ns);
            self.rejects = 0;
            self.last_reject = None;
            return true;
        }
        let consistent = self
            .last_reject
            .is_some_and(|p| (z.value - p.value).powi(2) <= gate_chi2 * (r + p.var()));
        self.rejects = if consistent {
            self.rejects.saturating_add(1)
        } else {
            1
        };
        self.last_reject = Some(z);
        if self.rejects >= jump_count {
            log::debug!(
                "scalar filter: persistent jump {} → {}, restarting",
                self.value,
                z.value
            );
            self.restart(z, t_ns);
            return true;
        }
        false
    }

    fn restart(&mut self, z: Estimate, t_ns: u64) {
        *self = ScalarFilter {
            value: z.value,
            var: z.var(),
            initialised: true,
            last_accept_ns: Some(t_ns),
            rejects: 0,
            last_reject: None,
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transition_and_noise_compose_over_time() {
        let m = CvModel::from_thesis(0.95, 1e-4, 24.0, 4.0);
        // γ per reference step.
        let (a, _) = m.transition(1.0 / 24.0);
        assert!((a - 0.95).abs() < 1e-12);
        let mut one = HubFilter::new([100.0, 50.0], 1.0, 100.0);
        one.x[2] = 30.0;
        one.x[3] = -10.0;
        let mut many = one;
        one.predict(&m, 0.3, [0.0, 0.0], 0.0);
        for _ in 0..9 {
            many.predict(&m, 0.3 / 9.0, [0.0, 0.0], 0.0);
        }
        assert!((one.x - many.x).norm() < 1e-9, "{} vs {}", one.x, many.x);
        assert!(
            (one.p - many.p).norm() < 1e-9 * one.p.norm(),
            "{} vs {}",
            one.p,
            many.p
        );
    }

    #[test]
    fn noise_series_matches_closed_form_at_the_threshold() {
        let m = CvModel {
            lambda: 1.0,
            q_pos: 0.0,
            q_vel: 1.0,
        };
        let below = m.noise(SERIES_THRESHOLD * 0.999_999);
        let above = m.noise(SERIES_THRESHOLD * 1.000_001);
        for (x, y) in [(below.0, above.0), (below.1, above.1), (below.2, above.2)] {
            assert!((x - y).abs() <= 1e-5 * y.abs(), "{x} vs {y}");
        }
        // Undamped limit: white-noise acceleration integrals dt³/3, dt²/2, dt.
        let m = CvModel {
            lambda: 0.0,
            q_pos: 0.0,
            q_vel: 2.0,
        };
        let (pp, pv, vv) = m.noise(0.5);
        assert!((pp - 2.0 * 0.125 / 3.0).abs() < 1e-12);
        assert!((pv - 2.0 * 0.125).abs() < 1e-12);
        assert!((vv - 1.0).abs() < 1e-12);
    }

    #[test]
    fn scalar_gates_and_accepts_persistent_jumps() {
        let mut f = ScalarFilter::default();
        assert!(f.update(
            Estimate {
                value: 40.0,
                std: 1.0
            },
            10.83,
            3,
            0
        ));
        assert!(f.update(
            Estimate {
                value: 40.5,
                std: 1.0
            },
            10.83,
            3,
            1
        ));
        assert!(!f.update(
            Estimate {
                value: 5.0,
                std: 1.0
            },
            10.83,
            3,
            2
        ));
        assert!((f.value - 40.25).abs() < 0.5);
        assert!(!f.update(
            Estimate {
                value: 20.0,
                std: 1.0
            },
            10.83,
            3,
            3
        ));
        assert!(!f.update(
            Estimate {
                value: 20.2,
                std: 1.0
            },
            10.83,
            3,
            4
        ));
        assert!(f.update(
            Estimate {
                value: 20.1,
                std: 1.0
            },
            10.83,
            3,
            5
        ));
        assert_eq!(f.value, 20.1);
    }
}
