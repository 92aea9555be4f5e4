//! The calibrated camera: intrinsics plus distortion, pixel ↔ ray.

use crate::distortion::Distortion;
use serde::{Deserialize, Serialize};

/// Points closer than this in front of the camera (metres, along the optical axis) do not project.
pub const MIN_PROJECT_DEPTH_M: f64 = 1e-3;
/// Two frame sizes have "the same aspect" when their width/height ratios differ by less than
/// this fraction: 1080 vs 1088 rows (a common encoder padding) is 0.7 %, 4:3 vs 16:9 is 25 %.
const ASPECT_TOLERANCE: f64 = 0.01;
/// Step of the numerical derivative in [`CameraModel::local_focal_px`], px.
const LOCAL_FOCAL_STEP_PX: f64 = 0.5;

/// A camera: pinhole intrinsics at a given frame size and a lens distortion.
///
/// Projection (OpenCV): a camera-frame point `(x, y, z)` maps to normalised `(x/z, y/z)`, is
/// distorted by [`Distortion::distort`], then mapped to pixels `u = fx·xd + cx`, `v = fy·yd + cy`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CameraModel {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point x, pixels (pixel-centre convention).
    pub cx: f64,
    /// Principal point y, pixels.
    pub cy: f64,
    /// Lens distortion.
    pub distortion: Distortion,
}

/// A frame whose size the calibration cannot describe.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "frame size {frame_width}x{frame_height} does not match the camera calibration \
     ({calib_width}x{calib_height}): the aspect ratios differ, so the calibration cannot be \
     scaled to it; pass the calibration of the camera that took these frames (--camera)"
)]
pub struct SizeMismatch {
    /// Frame width, px.
    pub frame_width: u32,
    /// Frame height, px.
    pub frame_height: u32,
    /// Calibrated width, px.
    pub calib_width: u32,
    /// Calibrated height, px.
    pub calib_height: u32,
}

impl CameraModel {
    /// An ideal pinhole `width` × `height` with horizontal field of view `hfov_deg` and the
    /// principal point at the image centre.
    pub fn pinhole(width: u32, height: u32, hfov_deg: f64) -> CameraModel {
        let f = (f64::from(width) / 2.0) / (hfov_deg.to_radians() / 2.0).tan();
        CameraModel::centred(width, height, f, Distortion::None)
    }

    /// A camera with square pixels of focal length `f_px`, the principal point at the image
    /// centre `((W − 1) / 2, (H − 1) / 2)`.
    pub fn centred(width: u32, height: u32, f_px: f64, distortion: Distortion) -> CameraModel {
        CameraModel {
            width,
            height,
            fx: f_px,
            fy: f_px,
            cx: (f64::from(width) - 1.0) / 2.0,
            cy: (f64::from(height) - 1.0) / 2.0,
            distortion,
        }
    }

    /// Number of bytes of one BGR8 frame (`width * height * 3`).
    pub fn frame_bytes(&self) -> usize {
        self.width as usize * self.height as usize * 3
    }

    /// Centre focal length divided by the image width.
    pub fn focal_length_per_width(&self) -> f64 {
        self.fx / f64::from(self.width)
    }

    /// Vertical focal length in half image heights (`fy / (height / 2)`): the normalised image
    /// offset, per unit of tangent, of a ray near the centre (half the height = 1).
    pub fn focal_half_heights(&self) -> f64 {
        self.fy / (f64::from(self.height) / 2.0)
    }

    /// Largest undistorted normalised radius the lens model is valid for (see
    /// [`Distortion::max_radius`]).
    pub fn max_undistorted_radius(&self) -> f64 {
        self.distortion.max_radius()
    }

    /// Pixel of a camera-frame point (x right, y down, z forward, metres); `None` behind the
    /// camera or beyond the valid range of the lens model.
    pub fn project(&self, p_cam: [f64; 3]) -> Option<[f64; 2]> {
        if p_cam[2].is_nan() || p_cam[2] <= MIN_PROJECT_DEPTH_M {
            return None;
        }
        let n = [p_cam[0] / p_cam[2], p_cam[1] / p_cam[2]];
        let r_max = self.max_undistorted_radius();
        if n[0] * n[0] + n[1] * n[1] > r_max * r_max {
            return None;
        }
        Some(self.to_pixel(self.distortion.distort(n)))
    }

    /// Distorted normalised point → pixel.
    pub fn to_pixel(&self, pd: [f64; 2]) -> [f64; 2] {
        [self.fx * pd[0] + self.cx, self.fy * pd[1] + self.cy]
    }

    /// Pixel → the undistorted normalised ray `(x/z, y/z)`.
    pub fn unproject(&self, px: [f64; 2]) -> [f64; 2] {
        let pd = [(px[0] - self.cx) / self.fx, (px[1] - self.cy) / self.fy];
        self.distortion.undistort(pd)
    }

    /// Field of view across the image's narrower direction through the principal point,
    /// radians: the angle between the rays through the outer edges of the two border pixels.
    pub fn narrow_fov_rad(&self) -> f64 {
        let (a, b) = if self.height <= self.width {
            ([self.cx, -0.5], [self.cx, f64::from(self.height) - 0.5])
        } else {
            ([-0.5, self.cy], [f64::from(self.width) - 0.5, self.cy])
        };
        let (a, b) = (self.ray(a), self.ray(b));
        let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        let cos = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (norm(a) * norm(b));
        cos.clamp(-1.0, 1.0).acos()
    }

    /// Pixel → viewing ray in the camera frame with `z = 1`.
    pub fn ray(&self, px: [f64; 2]) -> [f64; 3] {
        let [x, y] = self.unproject(px);
        [x, y, 1.0]
    }

    /// Pixel → where an ideal pinhole with focal length `fx` (and `fy`) at the same principal
    /// point would have imaged the same ray: the undistorted pixel. Image measurements taken
    /// there (widths, offsets) follow pinhole geometry.
    pub fn undistort_pixel(&self, px: [f64; 2]) -> [f64; 2] {
        let [x, y] = self.unproject(px);
        [self.fx * x + self.cx, self.fy * y + self.cy]
    }

    /// Horizontal magnification at pixel `px`: pixels per unit of normalised undistorted x,
    /// `fx` for a pinhole. Small horizontal image extents at `px` (a tower's width) convert to
    /// angles by dividing by it.
    pub fn local_focal_px(&self, px: [f64; 2]) -> f64 {
        let h = LOCAL_FOCAL_STEP_PX;
        let a = self.unproject([px[0] - h, px[1]]);
        let b = self.unproject([px[0] + h, px[1]]);
        let dx = b[0] - a[0];
        if dx > 0.0 && dx.is_finite() {
            2.0 * h / dx
        } else {
            self.fx
        }
    }

    /// Horizontal field of view through the principal point, degrees.
    pub fn hfov_deg(&self) -> f64 {
        let l = self.unproject([-0.5, self.cy]);
        let r = self.unproject([f64::from(self.width) - 0.5, self.cy]);
        (r[0].atan() - l[0].atan()).to_degrees()
    }

    /// The same camera for frames `width` × `height`: intrinsics scaled by the width ratio (pixel
    /// centres stay pixel centres), distortion unchanged. Refused when the aspect ratio differs,
    /// which would mean a crop, not a scale.
    pub fn scaled_to(&self, width: u32, height: u32) -> Result<CameraModel, SizeMismatch> {
        if (width, height) == (self.width, self.height) {
            return Ok(*self);
        }
        let mismatch = SizeMismatch {
            frame_width: width,
            frame_height: height,
            calib_width: self.width,
            calib_height: self.height,
        };
        if width == 0 || height == 0 {
            return Err(mismatch);
        }
        let aspect = |w: u32, h: u32| f64::from(w) / f64::from(h);
        let a = aspect(width, height);
        let b = aspect(self.width, self.height);
        if ((a - b) / b).abs() > ASPECT_TOLERANCE {
            return Err(mismatch);
        }
        let sx = f64::from(width) / f64::from(self.width);
        let sy = f64::from(height) / f64::from(self.height);
        Ok(CameraModel {
            width,
            height,
            fx: self.fx * sx,
            fy: self.fy * sy,
            cx: (self.cx + 0.5) * sx - 0.5,
            cy: (self.cy + 0.5) * sy - 0.5,
            distortion: self.distortion,
        })
    }

    /// Image corners in normalised distorted coordinates lie inside the lens model's valid range
    /// (the distortion does not fold back within the image).
    pub fn covers_image(&self) -> bool {
        let r_max = self.max_undistorted_radius();
        if !r_max.is_finite() {
            return true;
        }
        let rd_max = self.distortion.radial_map(r_max);
        let (w, h) = (f64::from(self.width) - 0.5, f64::from(self.height) - 0.5);
        [[-0.5, -0.5], [w, -0.5], [-0.5, h], [w, h]]
            .iter()
            .all(|&[u, v]| {
                let x = (u - self.cx) / self.fx;
                let y = (v - self.cy) / self.fy;
                (x * x + y * y).sqrt() < rd_max
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip(cam: &CameraModel) {
        for &(u, v) in &[
            (0.0, 0.0),
            (100.0, 900.0),
            (960.0, 540.0),
            (1919.0, 1079.0),
            (1500.0, 20.0),
        ] {
            let u = u * f64::from(cam.width) / 1920.0;
            let v = v * f64::from(cam.height) / 1080.0;
            let [x, y, z] = cam.ray([u, v]);
            let p = cam.project([3.0 * x, 3.0 * y, 3.0 * z]).unwrap();
            assert!(
                (p[0] - u).abs() < 1e-6 && (p[1] - v).abs() < 1e-6,
                "{cam:?} {u},{v} -> {p:?}"
            );
        }
    }

    #[test]
    fn every_model_round_trips_pixel_ray_pixel() {
        round_trip(&CameraModel::pinhole(1280, 720, 70.0));
        round_trip(&CameraModel::gopro_hero3());
        round_trip(&CameraModel::centred(
            1920,
            1080,
            900.0,
            Distortion::PlumbBob {
                k1: -0.2,
                k2: 0.05,
                p1: 0.001,
                p2: -0.002,
                k3: -0.004,
            },
        ));
        round_trip(&CameraModel::centred(
            1920,
            1080,
            800.0,
            Distortion::Equidistant {
                k1: 0.02,
                k2: -0.01,
                k3: 0.003,
                k4: -0.0005,
            },
        ));
    }

    #[test]
    fn scaling_keeps_rays_and_refuses_other_aspects() {
        let cam = CameraModel::gopro_hero3();
        let half = cam.scaled_to(960, 540).unwrap();
        // The same ray lands on the same relative position.
        let p = cam.project([1.0, -0.5, 4.0]).unwrap();
        let q = half.project([1.0, -0.5, 4.0]).unwrap();
        assert!(((p[0] + 0.5) / 2.0 - 0.5 - q[0]).abs() < 1e-9);
        assert!(((p[1] + 0.5) / 2.0 - 0.5 - q[1]).abs() < 1e-9);
        let e = cam.scaled_to(640, 480).unwrap_err();
        assert!(e.to_string().contains("640x480"), "{e}");
        assert!(cam.scaled_to(0, 0).is_err());
        // Encoder padding (1080 → 1088) is within the tolerance.
        assert!(cam.scaled_to(1920, 1088).is_ok());
    }

    #[test]
    fn local_focal_is_fx_for_a_pinhole_and_shrinks_off_axis_with_barrel_distortion() {
        let pin = CameraModel::pinhole(1920, 1080, 90.0);
        assert!((pin.local_focal_px([300.0, 200.0]) - pin.fx).abs() < 1e-6);
        let gopro = CameraModel::gopro_hero3();
        let centre = gopro.local_focal_px([gopro.cx, gopro.cy]);
        assert!((centre - gopro.fx).abs() < 1e-3 * gopro.fx);
        assert!(gopro.local_focal_px([1800.0, gopro.cy]) < 0.8 * centre);
    }

    #[test]
    fn the_narrow_field_of_view_is_across_the_shorter_side() {
        // A 90° × 73.7° pinhole (640 × 480): 2·atan(240 / 320).
        let pin = CameraModel::pinhole(640, 480, 90.0);
        let expected = 2.0 * (240.0f64 / 320.0).atan();
        assert!((pin.narrow_fov_rad() - expected).abs() < 1e-9);
        // Portrait: across the width, 90°.
        let portrait = CameraModel::centred(480, 640, 240.0, Distortion::None);
        assert!((portrait.narrow_fov_rad() - 90f64.to_radians()).abs() < 1e-9);
        // An equidistant fisheye sees θ = r / f: 540 px at f = 700 is 0.771 rad each side.
        let fish = CameraModel::centred(
            1920,
            1080,
            700.0,
            Distortion::Equidistant {
                k1: 0.0,
                k2: 0.0,
                k3: 0.0,
                k4: 0.0,
            },
        );
        assert!((fish.narrow_fov_rad() - 2.0 * 540.0 / 700.0).abs() < 1e-6);
    }

    #[test]
    fn the_focal_length_in_half_heights_is_the_offset_of_a_ray_and_survives_scaling() {
        // A pinhole: a ray at tan = 0.1 below the axis lands 0.1·k half-heights below the centre.
        let pin = CameraModel::pinhole(640, 480, 90.0);
        let k = pin.focal_half_heights();
        let p = pin.project([0.0, 0.1, 1.0]).unwrap();
        assert!(
            ((p[1] - pin.cy) / 240.0 - 0.1 * k).abs() < 1e-9,
            "{k} {p:?}"
        );
        assert!((k - 320.0 / 240.0).abs() < 1e-9);
        // Scaled to another size of the same aspect, the same number.
        let gopro = CameraModel::gopro_hero3();
        let half = gopro.scaled_to(960, 540).unwrap();
        assert!((gopro.focal_half_heights() - half.focal_half_heights()).abs() < 1e-9);
    }

    #[test]
    fn field_of_view_of_the_builtin_cameras() {
        assert!((CameraModel::gopro_hero3().hfov_deg() - 118.0).abs() < 0.1);
        assert!((CameraModel::pinhole(640, 480, 62.0).hfov_deg() - 62.0).abs() < 1e-9);
    }
}
