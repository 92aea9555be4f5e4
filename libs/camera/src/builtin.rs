//! The cameras the project ships calibrations for (`config/cameras/`), as code for the renderer
//! and the tests; `calibration::tests` checks the shipped files describe the same cameras.

use crate::{CameraModel, Distortion};

/// Focal length in pixels of the GoPro HERO3+ Black 1080p "wide" model: with [`GOPRO_K1`] and
/// [`GOPRO_K2`] the exact solution of "image edge at half the horizontal / vertical / diagonal
/// field of view" (118°, 69.5°, 133.6°) for the 1920x1080 frame, the thesis camera.
pub const GOPRO_F_PX: f64 = 833.933_951_036_557_1;
/// Radial distortion k1 of the GoPro model (barrel: negative).
pub const GOPRO_K1: f64 = -0.144_044_163_816_726_08;
/// Radial distortion k2 of the GoPro model.
pub const GOPRO_K2: f64 = 0.011_818_423_162_821_256;
/// Diagonal field of view of the narrow USB camera, degrees.
pub const USB_DFOV_DEG: f64 = 60.0;

impl CameraModel {
    /// GoPro HERO3+ Black wide: 1920x1080, 118° x 69.5°, strong barrel distortion
    /// (`config/cameras/gopro_hero3_wide_1080p.yaml`).
    pub fn gopro_hero3() -> CameraModel {
        CameraModel::centred(
            1920,
            1080,
            GOPRO_F_PX,
            Distortion::radial(GOPRO_K1, GOPRO_K2),
        )
    }

    /// Narrow USB camera: 640x480, 60° diagonal field of view, no distortion
    /// (`config/cameras/usb_narrow_640x480.yaml`).
    pub fn usb_narrow() -> CameraModel {
        let (w, h) = (640u32, 480u32);
        let half_diag_px = 0.5 * f64::from(w * w + h * h).sqrt();
        let f = half_diag_px / (USB_DFOV_DEG / 2.0).to_radians().tan();
        CameraModel::centred(w, h, f, Distortion::None)
    }
}
