//! One camera model for every stage that turns pixels into rays or rays into pixels: detect and
//! track (pixel → ray, sizes → distance), the renderer and the simulator (ray → pixel).
//!
//! A [`CameraModel`] is a calibrated pinhole (`fx`, `fy`, `cx`, `cy`) with one of the lens
//! [`Distortion`] models of OpenCV and ROS: none, `plumb_bob` (radial k1 k2 k3, tangential p1
//! p2) or `equidistant` (OpenCV's fisheye, k1..k4). Calibrations are read from the ROS
//! `camera_info` YAML the ROS camera calibrator writes ([`CameraModel::load`]); frames of another
//! size with the same aspect use the calibration scaled ([`CameraModel::scaled_to`]).
//!
//! Pixel convention (OpenCV): the centre of pixel `(col, row)` is at `(col, row)`. Camera frame:
//! x right, y down, z forward.

#![warn(missing_docs)]

mod builtin;
mod calibration;
mod distortion;
mod model;

pub use builtin::{GOPRO_F_PX, GOPRO_K1, GOPRO_K2, USB_DFOV_DEG};
pub use calibration::CalibrationError;
pub use distortion::Distortion;
pub use model::{CameraModel, SizeMismatch, MIN_PROJECT_DEPTH_M};
