//! Camera intrinsics with radial lens distortion, and the camera pose relative to the turbine.
//!
//! Pixel convention (same as OpenCV): the centre of pixel `(col, row)` is at pixel coordinate
//! `(col, row)`; the image spans `[-0.5, width - 0.5] x [-0.5, height - 0.5]`. A centred principal
//! point is therefore `((width - 1) / 2, (height - 1) / 2)`.

use serde::{Deserialize, Serialize};

use crate::math::{add, cross, deg, normalize, scale, WorldToCam, V3};

/// Points closer than this in front of the camera (metres, along the optical axis) do not project.
pub const MIN_PROJECT_DEPTH_M: f64 = 1e-3;

/// GoPro HERO3+ Black, 1080p "wide": horizontal FOV (degrees).
pub const GOPRO_HFOV_DEG: f64 = 118.0;
/// GoPro HERO3+ Black, 1080p "wide": vertical FOV (degrees).
pub const GOPRO_VFOV_DEG: f64 = 69.5;
/// GoPro HERO3+ Black, 1080p "wide": diagonal FOV (degrees) used as the third fit constraint.
pub const GOPRO_DFOV_DEG: f64 = 133.6;
/// Focal length in pixels of the GoPro model. Together with [`GOPRO_K1`] and [`GOPRO_K2`] this is the
/// exact solution of the three conditions "image edge at half the horizontal / vertical / diagonal
/// FOV" (118°, 69.5°, 133.6°) for the 1920x1080 frame (see the `gopro_fov_edges` test).
pub const GOPRO_F_PX: f64 = 833.933_951_036_557_1;
/// Radial distortion k1 of the GoPro model (barrel: negative).
pub const GOPRO_K1: f64 = -0.144_044_163_816_726_08;
/// Radial distortion k2 of the GoPro model.
pub const GOPRO_K2: f64 = 0.011_818_423_162_821_256;
/// Diagonal FOV of the narrow USB camera (degrees).
pub const USB_DFOV_DEG: f64 = 60.0;

/// Camera intrinsics + lens distortion.
///
/// Model (OpenCV radial, two terms): a camera-frame point `(x, y, z)` (x right, y down, z forward)
/// maps to normalised `(x/z, y/z)`, with `r² = (x/z)² + (y/z)²` scaled by `1 + k1 r² + k2 r⁴`, then
/// to pixels `u = fx·x_d + cx`, `v = fy·y_d + cy`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point x, pixels (pixel-centre convention, see module docs).
    pub cx: f64,
    /// Principal point y, pixels.
    pub cy: f64,
    /// First radial distortion coefficient (negative = barrel).
    pub k1: f64,
    /// Second radial distortion coefficient.
    pub k2: f64,
}

impl Camera {
    /// GoPro HERO3+ Black wide: 1920x1080, 118° x 69.5° field of view, visible barrel distortion (k1<0).
    pub fn gopro_hero3() -> Camera {
        Camera {
            width: 1920,
            height: 1080,
            fx: GOPRO_F_PX,
            fy: GOPRO_F_PX,
            cx: 959.5,
            cy: 539.5,
            k1: GOPRO_K1,
            k2: GOPRO_K2,
        }
    }

    /// Narrow USB camera: 640x480, 60° diagonal field of view, negligible distortion.
    pub fn usb_narrow() -> Camera {
        let (w, h) = (640u32, 480u32);
        let half_diag_px = 0.5 * ((w * w + h * h) as f64).sqrt();
        let f = half_diag_px / deg(USB_DFOV_DEG / 2.0).tan();
        Camera {
            width: w,
            height: h,
            fx: f,
            fy: f,
            cx: (w as f64 - 1.0) / 2.0,
            cy: (h as f64 - 1.0) / 2.0,
            k1: 0.0,
            k2: 0.0,
        }
    }

    /// Any size with a given horizontal FOV (pinhole, no distortion), handy for tests.
    pub fn pinhole(width: u32, height: u32, hfov_deg: f64) -> Camera {
        let f = (width as f64 / 2.0) / deg(hfov_deg / 2.0).tan();
        Camera {
            width,
            height,
            fx: f,
            fy: f,
            cx: (width as f64 - 1.0) / 2.0,
            cy: (height as f64 - 1.0) / 2.0,
            k1: 0.0,
            k2: 0.0,
        }
    }

    /// Number of bytes of one BGR8 frame (`width * height * 3`).
    pub fn frame_bytes(&self) -> usize {
        self.width as usize * self.height as usize * 3
    }

    /// Largest undistorted radius `r = |(x/z, y/z)|` for which the distortion polynomial is still
    /// monotonic (beyond it the model folds back and projection is undefined). `f64::INFINITY` if
    /// it is monotonic everywhere (the case for all cameras built in here).
    pub fn max_undistorted_radius(&self) -> f64 {
        // d/dr [r (1 + k1 r² + k2 r⁴)] = 1 + 3 k1 s + 5 k2 s², s = r². Smallest positive root.
        let (a, b, c) = (5.0 * self.k2, 3.0 * self.k1, 1.0);
        let mut s_min = f64::INFINITY;
        if a.abs() < 1e-15 {
            if b < 0.0 {
                s_min = -c / b;
            }
        } else {
            let disc = b * b - 4.0 * a * c;
            if disc >= 0.0 {
                let sq = disc.sqrt();
                for s in [(-b - sq) / (2.0 * a), (-b + sq) / (2.0 * a)] {
                    if s > 0.0 && s < s_min {
                        s_min = s;
                    }
                }
            }
        }
        s_min.sqrt()
    }

    /// Radial distortion factor `1 + k1 r² + k2 r⁴` for `r2 = r²`.
    #[inline]
    pub fn distortion_factor(&self, r2: f64) -> f64 {
        1.0 + r2 * (self.k1 + r2 * self.k2)
    }

    /// Project a point in the camera frame (x right, y down, z forward, metres) to distorted pixels; None if behind.
    ///
    /// Also `None` if the point lies beyond the monotonic range of the distortion polynomial
    /// (never the case for the built-in cameras).
    pub fn project(&self, p_cam: [f64; 3]) -> Option<[f64; 2]> {
        if !(p_cam[2] > MIN_PROJECT_DEPTH_M) {
            return None;
        }
        let x = p_cam[0] / p_cam[2];
        let y = p_cam[1] / p_cam[2];
        let r2 = x * x + y * y;
        let rmax = self.max_undistorted_radius();
        if r2 > rmax * rmax {
            return None;
        }
        let f = self.distortion_factor(r2);
        Some([self.fx * x * f + self.cx, self.fy * y * f + self.cy])
    }

    /// Inverse of the distortion: pixel to the normalised undistorted ray `(x/z, y/z)`.
    /// Newton iteration on the radius; exact to ~1e-12 within the monotonic range.
    pub fn unproject(&self, px: [f64; 2]) -> [f64; 2] {
        let xd = (px[0] - self.cx) / self.fx;
        let yd = (px[1] - self.cy) / self.fy;
        let rd = (xd * xd + yd * yd).sqrt();
        if rd < 1e-15 || (self.k1 == 0.0 && self.k2 == 0.0) {
            return [xd, yd];
        }
        let rmax = self.max_undistorted_radius();
        let mut r = rd;
        for _ in 0..50 {
            let r2 = r * r;
            let g = r * self.distortion_factor(r2) - rd;
            let dg = 1.0 + r2 * (3.0 * self.k1 + 5.0 * self.k2 * r2);
            if dg <= 1e-9 {
                break;
            }
            let step = g / dg;
            r = (r - step).clamp(0.0, rmax.min(1e6));
            if step.abs() < 1e-14 {
                break;
            }
        }
        let s = r / rd;
        [xd * s, yd * s]
    }
}

/// Where the camera is, relative to the turbine.
///
/// The camera centre is `hub + distance_m·X + lateral_m·Y + height_m·Z` in the world frame
/// (see the crate docs: X is the reference rotor-axis direction, Y the viewer's right when facing
/// the rotor, Z up). The camera first looks horizontally at the hub, then turns by `yaw_deg`
/// (right positive), tilts to the absolute `pitch_deg` above the horizon, and rolls by `roll_deg`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CameraPose {
    /// Horizontal distance from the hub (rotor centre) along the rotor axis direction, before lateral offset.
    pub distance_m: f64,
    /// Sideways offset, positive = to the camera's right when facing the rotor.
    pub lateral_m: f64,
    /// Camera height minus hub height (negative = below the hub).
    pub height_m: f64,
    /// Camera heading relative to "looking straight at the hub" horizontally (positive = camera turned right).
    pub yaw_deg: f64,
    /// Absolute tilt of the optical axis above the horizon (positive = camera tilted up). Not
    /// relative to the hub: use [`CameraPose::looking_at_hub`] to aim at it.
    pub pitch_deg: f64,
    /// Positive = clockwise roll of the camera (image appears rotated counter-clockwise).
    pub roll_deg: f64,
}

impl CameraPose {
    /// Straight in front of the rotor at hub height, looking at the hub.
    pub fn front(distance_m: f64) -> CameraPose {
        CameraPose {
            distance_m,
            lateral_m: 0.0,
            height_m: 0.0,
            yaw_deg: 0.0,
            pitch_deg: 0.0,
            roll_deg: 0.0,
        }
    }

    /// Camera at the given offsets with yaw, pitch and roll chosen so that the optical axis passes
    /// exactly through the hub (the hub projects to the principal point).
    pub fn looking_at_hub(distance_m: f64, lateral_m: f64, height_m: f64) -> CameraPose {
        let horiz = (distance_m * distance_m + lateral_m * lateral_m).sqrt();
        CameraPose {
            distance_m,
            lateral_m,
            height_m,
            yaw_deg: 0.0,
            pitch_deg: (-height_m).atan2(horiz).to_degrees(),
            roll_deg: 0.0,
        }
    }

    /// Camera centre relative to the hub, world frame, metres.
    pub fn offset_from_hub(&self) -> [f64; 3] {
        [self.distance_m, self.lateral_m, self.height_m]
    }

    /// World-to-camera transform for a hub at world position `hub`.
    pub(crate) fn world_to_cam(&self, hub: V3) -> WorldToCam {
        let origin = add(hub, self.offset_from_hub());
        // Heading (counter-clockwise from +X seen from above) of the horizontal line of sight to
        // the hub; straight above/below the hub there is none, so look along -X (at the rotor face).
        let (dx, dy) = (-self.distance_m, -self.lateral_m);
        let base = if dx.abs() + dy.abs() > 1e-9 {
            dy.atan2(dx)
        } else {
            std::f64::consts::PI
        };
        // Turning right is clockwise seen from above, i.e. decreasing the CCW heading.
        let heading = base - deg(self.yaw_deg);
        let pitch = deg(self.pitch_deg);
        let fwd = [
            pitch.cos() * heading.cos(),
            pitch.cos() * heading.sin(),
            pitch.sin(),
        ];
        let right0 = [heading.sin(), -heading.cos(), 0.0];
        let down0 = normalize(cross(fwd, right0));
        let up0 = scale(down0, -1.0);
        // Clockwise roll (seen from behind the camera) moves the camera's up vector toward its right.
        let roll = deg(self.roll_deg);
        let up = add(scale(up0, roll.cos()), scale(right0, roll.sin()));
        let right = add(scale(right0, roll.cos()), scale(up0, -roll.sin()));
        let down = scale(up, -1.0);
        WorldToCam {
            rot: [right, down, fwd],
            origin,
        }
    }
}

/// Projection used by the rasteriser: like [`Camera::project`] but never fails for points in
/// front of the camera. Beyond the monotonic range of the polynomial it continues radially and
/// linearly, so triangles that leave the valid range stay well formed (they are off-screen).
#[derive(Clone, Copy, Debug)]
pub(crate) struct RasterProjector {
    cam: Camera,
    r_lim: f64,
    rd_lim: f64,
}

impl RasterProjector {
    pub fn new(cam: &Camera) -> RasterProjector {
        let r_lim = (cam.max_undistorted_radius() * 0.98).min(1e3);
        let rd_lim = r_lim * cam.distortion_factor(r_lim * r_lim);
        RasterProjector {
            cam: *cam,
            r_lim,
            rd_lim,
        }
    }

    /// Focal length along x (pixels).
    #[inline]
    pub fn fx(&self) -> f64 {
        self.cam.fx
    }

    /// Camera-frame point (z > 0) to pixels.
    #[inline]
    pub fn project(&self, p: V3) -> [f64; 2] {
        let iz = 1.0 / p[2];
        let x = p[0] * iz;
        let y = p[1] * iz;
        let r2 = x * x + y * y;
        let f = if r2 <= self.r_lim * self.r_lim {
            self.cam.distortion_factor(r2)
        } else {
            // Continue with the distorted radius growing like r: keeps the map monotonic.
            self.rd_lim / self.r_lim
        };
        [
            self.cam.fx * x * f + self.cam.cx,
            self.cam.fy * y * f + self.cam.cy,
        ]
    }
}
