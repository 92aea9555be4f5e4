//! Angle wrapping and the few 3-vector / rotation helpers the crate needs.

use std::f64::consts::{PI, TAU};

/// Standard gravity, m/s².
pub const GRAVITY_M_S2: f64 = 9.80665;

/// Wrap an angle to (−π, π] rad.
pub fn wrap_pi(a: f64) -> f64 {
    let r = a.rem_euclid(TAU);
    if r > PI {
        r - TAU
    } else {
        r
    }
}

/// Wrap an angle to (−180, 180] degrees.
pub fn wrap_deg(a: f64) -> f64 {
    let r = a.rem_euclid(360.0);
    if r > 180.0 {
        r - 360.0
    } else {
        r
    }
}

pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(crate) fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// Body-to-NED rotation of ZYX Euler angles (yaw ψ, then pitch θ, then roll φ), row-major:
/// `v_ned = R · v_body`; the columns are the body x (nose), y (right) and z (down) axes in NED.
pub(crate) fn body_to_ned(roll: f64, pitch: f64, yaw: f64) -> [[f64; 3]; 3] {
    let (sf, cf) = roll.sin_cos();
    let (st, ct) = pitch.sin_cos();
    let (sp, cp) = yaw.sin_cos();
    [
        [cp * ct, cp * st * sf - sp * cf, cp * st * cf + sp * sf],
        [sp * ct, sp * st * sf + cp * cf, sp * st * cf - cp * sf],
        [-st, ct * sf, ct * cf],
    ]
}

pub(crate) fn mat_vec(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_ranges() {
        assert_eq!(wrap_pi(PI), PI);
        assert_eq!(wrap_pi(-PI), PI);
        assert!((wrap_pi(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-12);
        assert_eq!(wrap_deg(180.0), 180.0);
        assert_eq!(wrap_deg(-180.0), 180.0);
        assert_eq!(wrap_deg(-190.0), 170.0);
        assert_eq!(wrap_deg(370.0), 10.0);
    }

    #[test]
    fn rotation_axes() {
        // Yaw 90° (east): the nose points east, the right wing south.
        let r = body_to_ned(0.0, 0.0, PI / 2.0);
        let nose = mat_vec(&r, [1.0, 0.0, 0.0]);
        let right = mat_vec(&r, [0.0, 1.0, 0.0]);
        assert!((nose[1] - 1.0).abs() < 1e-12 && nose[0].abs() < 1e-12);
        assert!((right[0] + 1.0).abs() < 1e-12);
        // Positive roll: right wing down.
        let r = body_to_ned(0.2, 0.0, 0.0);
        assert!(mat_vec(&r, [0.0, 1.0, 0.0])[2] > 0.0);
        // Positive pitch: nose up.
        let r = body_to_ned(0.0, 0.2, 0.0);
        assert!(mat_vec(&r, [1.0, 0.0, 0.0])[2] < 0.0);
    }
}
