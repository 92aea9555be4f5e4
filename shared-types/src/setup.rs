//! What the operator knows about the camera and the turbine, in one place: every stage that turns
//! pixels into metres or degrees (detect, track) reads these two sections, so they cannot
//! disagree.

use crate::params;
use crate::params::ParamError;

/// The GoPro HERO3+ wide lens's centre focal length per image width (833.9 px at 1920), the
/// thesis camera.
#[allow(clippy::approx_constant)] // 0.4343 is the lens, not log10(e)
pub const GOPRO_FOCAL_LENGTH_PER_WIDTH: f64 = 0.4343;

params! {
    /// `[camera]`: the lens as detect and track model it (a pinhole at the image centre).
    pub struct CameraSetup {
        /// Horizontal field of view, degrees; the pinhole focal length is
        /// `(width / 2) / tan(hfov / 2)` at full resolution unless `focal_length_per_width` is
        /// set. 118 = GoPro HERO3+ Black 1080p wide (the thesis camera).
        pub hfov_deg: f64 = 118.0, closed(1.0, 179.0);
        /// Centre focal length divided by the image width, overriding `hfov_deg` when > 0. A lens
        /// with strong barrel distortion has a much longer centre focal length than the pinhole
        /// value from its edge field of view: the GoPro HERO3+ wide has 833.9 px at 1920 wide
        /// (0.4343) against 577 px (0.3004) from 118°, which would make every distance ~31 %
        /// short. 0 = use `hfov_deg`.
        pub focal_length_per_width: f64 = GOPRO_FOCAL_LENGTH_PER_WIDTH, zero_or_closed(0.05, 10.0);
    }
}

params! {
    /// `[turbine]`: the dimensions of the turbine type being approached.
    pub struct TurbineSetup {
        /// Tower diameter just under the nacelle, where the detector measures its width, m; the
        /// distance estimate divides it by the measured width.
        pub tower_top_diameter_m: f64 = 2.2, closed(0.1, 30.0);
        /// Horizontal distance from the tower axis to the hub centre along the rotor axis, m; the
        /// yaw estimate (thesis eq. 7.14) divides the hub–tower gap in the image by it.
        pub hub_overhang_m: f64 = 4.2, closed(0.1, 50.0);
        /// Spinner (nose cone) diameter at the blade roots, m: a second distance cue close in,
        /// and the size of circle the detector searches for.
        pub spinner_diameter_m: f64 = 3.2, closed(0.1, 30.0);
    }
}

impl CameraSetup {
    /// Checks every value; errors name the key under `camera`.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.check_ranges("camera")
    }
}

impl TurbineSetup {
    /// Checks every value; errors name the key under `turbine`.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.check_ranges("turbine")
    }
}
