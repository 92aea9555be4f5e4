//! The camera pose relative to the turbine, and the rasteriser's projection. The camera itself
//! (intrinsics and lens distortion) is [`hubtrack_camera::CameraModel`], the model every stage
//! shares.
//!
//! Pixel convention (same as OpenCV): the centre of pixel `(col, row)` is at pixel coordinate
//! `(col, row)`; the image spans `[-0.5, width - 0.5] x [-0.5, height - 0.5]`. A centred principal
//! point is therefore `((width - 1) / 2, (height - 1) / 2)`.

use serde::{Deserialize, Serialize};

use crate::math::{add, cross, deg, normalize, scale, WorldToCam, V3};

pub use hubtrack_camera::CameraModel as Camera;
pub use hubtrack_camera::Distortion;
pub use hubtrack_camera::{GOPRO_F_PX, GOPRO_K1, GOPRO_K2, MIN_PROJECT_DEPTH_M, USB_DFOV_DEG};

/// GoPro HERO3+ Black, 1080p "wide": horizontal FOV (degrees).
pub const GOPRO_HFOV_DEG: f64 = 118.0;
/// GoPro HERO3+ Black, 1080p "wide": vertical FOV (degrees).
pub const GOPRO_VFOV_DEG: f64 = 69.5;
/// GoPro HERO3+ Black, 1080p "wide": diagonal FOV (degrees), the third constraint of the fit of
/// [`GOPRO_F_PX`], [`GOPRO_K1`], [`GOPRO_K2`].
pub const GOPRO_DFOV_DEG: f64 = 133.6;

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
/// front of the camera. Beyond the valid range of the lens model it continues radially and
/// linearly, so triangles that leave the valid range stay well formed (they are off-screen).
#[derive(Clone, Copy, Debug)]
pub(crate) struct RasterProjector {
    cam: Camera,
    r_lim: f64,
}

/// Fraction of the lens model's valid radius up to which the rasteriser uses it exactly.
const RASTER_VALID_FRACTION: f64 = 0.98;
/// Normalised radius beyond which nothing is on screen for any real camera (89.9° off axis).
const RASTER_MAX_RADIUS: f64 = 1e3;

impl RasterProjector {
    pub fn new(cam: &Camera) -> RasterProjector {
        let r_lim = (cam.max_undistorted_radius() * RASTER_VALID_FRACTION).min(RASTER_MAX_RADIUS);
        RasterProjector { cam: *cam, r_lim }
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
        let n = [p[0] * iz, p[1] * iz];
        let r2 = n[0] * n[0] + n[1] * n[1];
        let d = if r2 <= self.r_lim * self.r_lim {
            self.cam.distortion.distort(n)
        } else {
            // Continue with the distorted radius growing like r: keeps the map monotonic.
            let k = self.r_lim / r2.sqrt();
            let at_limit = self.cam.distortion.distort([n[0] * k, n[1] * k]);
            [at_limit[0] / k, at_limit[1] / k]
        };
        self.cam.to_pixel(d)
    }
}
