//! Pinhole camera model, the vehicle's camera pose and the image motion it causes (ego-motion).
//!
//! ## Frames
//! - Image: pixel centres at integer coordinates (OpenCV convention), origin top-left, x right,
//!   y down; the principal point is the image centre `((W − 1) / 2, (H − 1) / 2)`.
//! - Camera: x right, y down, z forward (optical axis).
//! - Body: FRD (x forward/nose, y right, z down). The camera looks along the body x axis, tilted
//!   up by [`crate::params::CameraConfig::mount_pitch_deg`].
//! - World: NED. The body attitude is the aerospace Z-Y-X Euler sequence of
//!   [`hubtrack_types::VehicleState`]: yaw clockwise from north, pitch nose up, roll right wing
//!   down.
//!
//! ## Image motion of a camera rotation
//! A yaw to the right by Δψ moves a scene point near the image centre **left** by ≈ f·Δψ px; a
//! pitch up by Δθ moves it **down** by ≈ f·Δθ px; a roll (right wing down) rotates the image
//! content counter-clockwise about the principal point. [`ego_motion`] does this exactly (ray
//! rotation and re-projection), and with a velocity and a range also the parallax of translation.

use hubtrack_types::setup::{CameraModel, Distortion};
use hubtrack_types::VehicleState;
use nalgebra::{Rotation3, Vector3};

/// Points with a smaller forward component (relative to their range) do not project.
const MIN_FORWARD_FRACTION: f64 = 1e-6;

/// Nanoseconds per second.
pub(crate) const NS_PER_S: f64 = 1e9;

/// Focal length in px of a pinhole camera `image_width_px` wide with horizontal field of view
/// `hfov_deg`: `f = (W / 2) / tan(hfov / 2)`.
pub fn focal_length_px(image_width_px: f64, hfov_deg: f64) -> f64 {
    (image_width_px / 2.0) / (hfov_deg.to_radians() / 2.0).tan()
}

/// The camera of one frame size: the calibrated model (intrinsics and lens distortion, see
/// [`hubtrack_types::setup::Lens`]) with its centre focal length and principal point at hand.
/// Without a calibration it is a distortion-free pinhole.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pinhole {
    /// Centre focal length, px.
    pub f_px: f64,
    /// Principal point x, px.
    pub cx: f64,
    /// Principal point y, px.
    pub cy: f64,
    /// The full model (distortion included).
    pub model: CameraModel,
}

impl Pinhole {
    /// Camera for a `width` × `height` frame with horizontal field of view `hfov_deg`.
    pub fn new(width: u32, height: u32, hfov_deg: f64) -> Pinhole {
        Pinhole::with_focal(width, height, focal_length_px(f64::from(width), hfov_deg))
    }

    /// Camera for a `width` × `height` frame with focal length `f_px`.
    pub fn with_focal(width: u32, height: u32, f_px: f64) -> Pinhole {
        Pinhole::from_model(CameraModel::centred(width, height, f_px, Distortion::None))
    }

    /// The camera of a calibrated model.
    pub fn from_model(model: CameraModel) -> Pinhole {
        Pinhole {
            f_px: model.fx,
            cx: model.cx,
            cy: model.cy,
            model,
        }
    }

    /// Viewing ray of a pixel in the camera frame, `z = 1` (lens distortion removed).
    pub fn ray(&self, px: [f64; 2]) -> Vector3<f64> {
        let [x, y, z] = self.model.ray(px);
        Vector3::new(x, y, z)
    }

    /// Focal length at pixel `px`, px per radian of small horizontal extent: `f_px` for a
    /// distortion-free lens, less towards the edge of a barrel lens. Sizes measured at `px` (a
    /// tower's width, a spinner's radius, a gap) convert to angles with it.
    pub fn focal_at(&self, px: [f64; 2]) -> f64 {
        self.model.local_focal_px(px)
    }

    /// Pixel of a camera-frame point; `None` behind (or beside) the camera.
    pub fn project(&self, p: &Vector3<f64>) -> Option<[f64; 2]> {
        if p.z <= MIN_FORWARD_FRACTION * p.norm() {
            return None;
        }
        self.model.project([p.x, p.y, p.z])
    }
}

/// Camera orientation (and velocity) at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraPose {
    /// Rotation camera frame → world (NED) frame.
    pub r_wc: Rotation3<f64>,
    /// Camera velocity in the world frame, m/s, if known.
    pub v_w: Option<Vector3<f64>>,
}

/// Rotation camera → body for a camera on the body x axis tilted up by `mount_pitch_rad`.
pub fn camera_to_body(mount_pitch_rad: f64) -> Rotation3<f64> {
    let (s, c) = mount_pitch_rad.sin_cos();
    // Columns: camera x (right), y (down), z (forward) expressed in body FRD.
    let m = nalgebra::Matrix3::new(
        0.0, s, c, //
        1.0, 0.0, 0.0, //
        0.0, c, -s,
    );
    Rotation3::from_matrix_unchecked(m)
}

/// Time of a vehicle sample, ns: `recv_ns`, else `publish_ns`, else `None` (unknown: taken as
/// the frame time).
fn sample_time_ns(v: &VehicleState) -> Option<u64> {
    [v.recv_ns, v.publish_ns].into_iter().find(|&t| t != 0)
}

/// Signed `a − b` in seconds.
pub(crate) fn dt_s(a_ns: u64, b_ns: u64) -> f64 {
    if a_ns >= b_ns {
        (a_ns - b_ns) as f64 / NS_PER_S
    } else {
        -((b_ns - a_ns) as f64 / NS_PER_S)
    }
}

/// Camera pose at `t_ns` from a vehicle sample: the attitude extrapolated with the body rates
/// over `t − sample time`. `None` if the attitude is invalid or the sample is further than
/// `max_age_s` from `t`. The velocity is included when `use_velocity` and the position fields
/// are valid.
pub fn camera_pose_at(
    v: &VehicleState,
    t_ns: u64,
    max_age_s: f64,
    r_bc: &Rotation3<f64>,
    use_velocity: bool,
) -> Option<CameraPose> {
    if !v.attitude_valid {
        return None;
    }
    let age = sample_time_ns(v).map_or(0.0, |ts| dt_s(t_ns, ts));
    if !age.is_finite() || age.abs() > max_age_s {
        return None;
    }
    let r_wb0 = Rotation3::from_euler_angles(v.roll_rad, v.pitch_rad, v.yaw_rad);
    let w = Vector3::from(v.body_rates_rad_s);
    let r_wb = r_wb0 * Rotation3::new(w * age);
    let v_w = (use_velocity && v.position_valid).then(|| Vector3::from(v.velocity_ned_m_s));
    Some(CameraPose {
        r_wc: r_wb * r_bc,
        v_w,
    })
}

/// Camera position at `t_ns`, world frame (NED), m: the vehicle's local position carried on
/// with its velocity from the sample time (the camera's offset from the vehicle's centre is a
/// few centimetres and ignored). `None` without a valid position or when the sample is further
/// than `max_age_s` from `t`.
pub fn camera_position_at(v: &VehicleState, t_ns: u64, max_age_s: f64) -> Option<Vector3<f64>> {
    if !v.position_valid {
        return None;
    }
    let age = sample_time_ns(v).map_or(0.0, |ts| dt_s(t_ns, ts));
    if !age.is_finite() || age.abs() > max_age_s {
        return None;
    }
    let p = Vector3::from(v.position_ned_m) + Vector3::from(v.velocity_ned_m_s) * age;
    p.iter().all(|x| x.is_finite()).then_some(p)
}

/// Result of moving an image point with the camera's motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EgoMotion {
    /// Where the point appears after the motion, px.
    pub px: [f64; 2],
    /// New range to the point, m (only with a range and a velocity).
    pub range_m: Option<f64>,
    /// Change of the relative yaw (camera position around the point, project sign), rad (only
    /// with a range and a velocity).
    pub relative_yaw_change_rad: Option<f64>,
}

/// Moves image point `px` from camera pose `p0` to pose `p1` over `dt` seconds.
///
/// Rotation is exact. With `range_m` and a velocity in `p0`/`p1` (the mean is used) the point is
/// placed at that range and the camera translated by `v·dt`, which adds the parallax, the new
/// range and the change of the relative yaw (positive when the camera moves to the viewer's right
/// while facing the point; see the crate docs). Without them the point is at infinity (pure
/// rotation). `None` if the point ends behind the camera.
pub fn ego_motion(
    cam: &Pinhole,
    px: [f64; 2],
    p0: &CameraPose,
    p1: &CameraPose,
    dt: f64,
    range_m: Option<f64>,
) -> Option<EgoMotion> {
    let u_w = p0.r_wc * cam.ray(px).normalize();
    let vel = match (p0.v_w, p1.v_w) {
        (Some(a), Some(b)) => Some((a + b) * 0.5),
        (a, b) => a.or(b),
    };
    let (h_w, range, dyaw) = match (range_m, vel) {
        (Some(d), Some(v)) if d > 0.0 => {
            let h0 = u_w * d; // point relative to the camera before
            let h1 = h0 - v * dt; // and after the camera moved
                                  // Bearing (clockwise from north) of the camera seen from the point; the relative
                                  // yaw grows when that bearing turns anticlockwise (camera moves to its right).
            let bearing = |h: &Vector3<f64>| (-h.y).atan2(-h.x);
            let horizontal = |h: &Vector3<f64>| h.x.hypot(h.y);
            let dyaw = if horizontal(&h0) > 0.0 && horizontal(&h1) > 0.0 {
                Some(-wrap_pi(bearing(&h1) - bearing(&h0)))
            } else {
                None
            };
            (h1, Some(h1.norm()), dyaw)
        }
        _ => (u_w, None, None),
    };
    let p_c1 = p1.r_wc.inverse() * h_w;
    let px1 = cam.project(&p_c1)?;
    Some(EgoMotion {
        px: px1,
        range_m: range,
        relative_yaw_change_rad: dyaw,
    })
}

/// Wraps an angle to (−π, π].
pub fn wrap_pi(a: f64) -> f64 {
    let two_pi = std::f64::consts::TAU;
    let mut r = a.rem_euclid(two_pi);
    if r > std::f64::consts::PI {
        r -= two_pi;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(roll: f64, pitch: f64, yaw: f64) -> CameraPose {
        let r_bc = camera_to_body(0.0);
        CameraPose {
            r_wc: Rotation3::from_euler_angles(roll, pitch, yaw) * r_bc,
            v_w: None,
        }
    }

    #[test]
    fn focal_length_of_the_gopro_pinhole() {
        let f = focal_length_px(1920.0, 118.0);
        assert!((f - 960.0 / 59f64.to_radians().tan()).abs() < 1e-9);
        assert!((f - 576.8).abs() < 0.1, "{f}");
    }

    #[test]
    fn camera_axes_in_body() {
        let r = camera_to_body(0.0);
        // Camera forward = body forward, camera right = body right, camera down = body down.
        assert!((r * Vector3::z() - Vector3::x()).norm() < 1e-12);
        assert!((r * Vector3::x() - Vector3::y()).norm() < 1e-12);
        assert!((r * Vector3::y() - Vector3::z()).norm() < 1e-12);
        // Tilted up by 10°: the optical axis points up (negative body z).
        let r = camera_to_body(10f64.to_radians());
        assert!((r * Vector3::z()).z < 0.0);
        assert!((r.matrix().determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn yaw_right_moves_the_scene_left_pitch_up_moves_it_down() {
        let cam = Pinhole::new(1920, 1080, 118.0);
        let c = [cam.cx, cam.cy];
        let d = 0.05;
        let m = ego_motion(&cam, c, &pose(0.0, 0.0, 0.0), &pose(0.0, 0.0, d), 0.1, None).unwrap();
        assert!(
            (m.px[0] - (cam.cx - cam.f_px * d.tan())).abs() < 1e-9,
            "{:?}",
            m.px
        );
        assert!((m.px[1] - cam.cy).abs() < 1e-9);
        let m = ego_motion(&cam, c, &pose(0.0, 0.0, 0.0), &pose(0.0, d, 0.0), 0.1, None).unwrap();
        assert!(
            (m.px[1] - (cam.cy + cam.f_px * d.tan())).abs() < 1e-9,
            "{:?}",
            m.px
        );
        assert!((m.px[0] - cam.cx).abs() < 1e-9);
        // Roll right wing down: a point on the right of the image moves up.
        let right = [cam.cx + 300.0, cam.cy];
        let m = ego_motion(
            &cam,
            right,
            &pose(0.0, 0.0, 0.0),
            &pose(d, 0.0, 0.0),
            0.1,
            None,
        )
        .unwrap();
        assert!(m.px[1] < cam.cy - 10.0, "{:?}", m.px);
    }

    #[test]
    fn rates_extrapolate_the_attitude() {
        let r_bc = camera_to_body(0.0);
        let mut v = VehicleState {
            attitude_valid: true,
            recv_ns: 1_000_000_000,
            ..Default::default()
        };
        v.body_rates_rad_s = [0.0, 0.0, 0.5];
        let p = camera_pose_at(&v, 1_200_000_000, 0.5, &r_bc, true).unwrap();
        let (_, _, yaw) = (p.r_wc * r_bc.inverse()).euler_angles();
        assert!((yaw - 0.1).abs() < 1e-9, "{yaw}");
        assert!(camera_pose_at(&v, 2_000_000_000, 0.5, &r_bc, true).is_none());
        v.attitude_valid = false;
        assert!(camera_pose_at(&v, 1_000_000_000, 0.5, &r_bc, true).is_none());
    }

    #[test]
    fn moving_right_increases_relative_yaw_and_parallax() {
        // Camera south of the point, looking north (yaw 0), moving east (its right) at 1 m/s.
        let cam = Pinhole::new(1920, 1080, 118.0);
        let mut p0 = pose(0.0, 0.0, 0.0);
        p0.v_w = Some(Vector3::new(0.0, 1.0, 0.0));
        let p1 = p0;
        let m = ego_motion(&cam, [cam.cx, cam.cy], &p0, &p1, 1.0, Some(20.0)).unwrap();
        let dyaw = m.relative_yaw_change_rad.unwrap();
        assert!((dyaw - (1.0f64 / 20.0).atan()).abs() < 1e-9, "{dyaw}");
        // The point stays put in the world, the camera moved right: it appears left of centre.
        assert!(
            (m.px[0] - (cam.cx - cam.f_px / 20.0)).abs() < 1e-6,
            "{:?}",
            m.px
        );
        assert!((m.range_m.unwrap() - 401f64.sqrt()).abs() < 1e-9);
    }
}
