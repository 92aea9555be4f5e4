//! ROS `camera_info` YAML (as written by the ROS camera calibrator and `camera_calibration_parsers`)
//! ↔ [`CameraModel`].

use crate::{CameraModel, Distortion};
use serde::{Deserialize, Serialize};
use std::io::Read;
use std::path::{Path, PathBuf};

/// A calibration file is a few hundred bytes; anything over this is not one (and is not read
/// into memory whole).
const MAX_FILE_BYTES: u64 = 64 * 1024;
/// Largest frame side a calibration may describe, px (8K is 7680).
const MAX_SIDE_PX: u32 = 16_384;
/// `camera_matrix` entries that must be zero (skew, the bottom row) may deviate by this much in a
/// file written with limited precision.
const ZERO_TOLERANCE: f64 = 1e-9;

/// Largest ratio of fx to fy (either way) a calibration may state: camera pixels are square to
/// within a few per cent; a factor of two is a typing error.
const MAX_PIXEL_ASPECT: f64 = 2.0;

/// Narrowest horizontal field of view a calibration may describe, degrees: a lens narrower than
/// this (a 500 mm telephoto on a full-frame sensor sees 4°) does not fly an approach, and
/// absurd coefficients (k1 = 1e20) shrink the undistorted view to nothing.
const MIN_HFOV_DEG: f64 = 1.0;

/// Why a calibration file was refused.
#[derive(Debug, thiserror::Error)]
#[error("camera calibration {path}: {reason}")]
pub struct CalibrationError {
    /// The file.
    pub path: PathBuf,
    /// What is wrong with it.
    pub reason: String,
}

#[derive(Serialize, Deserialize)]
struct Matrix {
    rows: usize,
    cols: usize,
    data: Vec<f64>,
}

#[derive(Serialize, Deserialize)]
struct RosCameraInfo {
    image_width: u32,
    image_height: u32,
    #[serde(default)]
    camera_name: String,
    camera_matrix: Matrix,
    distortion_model: String,
    distortion_coefficients: Matrix,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    rectification_matrix: Option<Matrix>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    projection_matrix: Option<Matrix>,
}

impl Matrix {
    fn check(&self, name: &str, rows: &[usize], cols: &[usize]) -> Result<(), String> {
        if !rows.contains(&self.rows) || !cols.contains(&self.cols) {
            return Err(format!(
                "`{name}` is {}x{}, expected {}x{}",
                self.rows,
                self.cols,
                rows.iter()
                    .map(|r| r.to_string())
                    .collect::<Vec<_>>()
                    .join(" or "),
                cols.iter()
                    .map(|c| c.to_string())
                    .collect::<Vec<_>>()
                    .join(" or "),
            ));
        }
        if self.data.len() != self.rows * self.cols {
            return Err(format!(
                "`{name}` declares {}x{} but has {} values",
                self.rows,
                self.cols,
                self.data.len()
            ));
        }
        if let Some(i) = self.data.iter().position(|v| !v.is_finite()) {
            return Err(format!("`{name}` value {i} is {}", self.data[i]));
        }
        Ok(())
    }
}

impl CameraModel {
    /// Reads a ROS `camera_info` YAML file.
    pub fn load(path: &Path) -> Result<CameraModel, CalibrationError> {
        let err = |reason: String| CalibrationError {
            path: path.to_path_buf(),
            reason,
        };
        let file = std::fs::File::open(path).map_err(|e| err(format!("cannot open: {e}")))?;
        let mut text = String::new();
        file.take(MAX_FILE_BYTES + 1)
            .read_to_string(&mut text)
            .map_err(|e| err(format!("cannot read as UTF-8 text: {e}")))?;
        if text.len() as u64 > MAX_FILE_BYTES {
            return Err(err(format!(
                "larger than {MAX_FILE_BYTES} bytes: not a camera_info YAML"
            )));
        }
        CameraModel::from_ros_yaml(&text).map_err(err)
    }

    /// Parses ROS `camera_info` YAML text; the error says what is missing or wrong.
    pub fn from_ros_yaml(text: &str) -> Result<CameraModel, String> {
        let info: RosCameraInfo = serde_norway::from_str(text).map_err(|e| e.to_string())?;
        let (w, h) = (info.image_width, info.image_height);
        if w == 0 || h == 0 || w > MAX_SIDE_PX || h > MAX_SIDE_PX {
            return Err(format!(
                "image size {w}x{h} is outside 1..={MAX_SIDE_PX} px per side"
            ));
        }
        let k = &info.camera_matrix;
        k.check("camera_matrix", &[3], &[3])?;
        let d = &k.data;
        let zeros = [d[1], d[3], d[6], d[7]];
        if zeros.iter().any(|z| z.abs() > ZERO_TOLERANCE) || (d[8] - 1.0).abs() > ZERO_TOLERANCE {
            return Err(format!(
                "`camera_matrix` must be [fx, 0, cx, 0, fy, cy, 0, 0, 1] (no skew), got {d:?}"
            ));
        }
        let (fx, cx, fy, cy) = (d[0], d[2], d[4], d[5]);
        if !(fx > 0.0 && fy > 0.0) {
            return Err(format!(
                "focal lengths fx = {fx}, fy = {fy} must be positive"
            ));
        }
        if !(1.0 / MAX_PIXEL_ASPECT..=MAX_PIXEL_ASPECT).contains(&(fx / fy)) {
            return Err(format!(
                "focal lengths fx = {fx}, fy = {fy} differ more than {MAX_PIXEL_ASPECT} times: \
                 pixels are near square, a mistyped camera_matrix is not"
            ));
        }
        let inside = |c: f64, side: u32| c >= -0.5 && c <= f64::from(side) - 0.5;
        if !inside(cx, w) || !inside(cy, h) {
            return Err(format!(
                "principal point ({cx}, {cy}) lies outside the {w}x{h} image"
            ));
        }
        let c = &info.distortion_coefficients;
        let distortion = match info.distortion_model.as_str() {
            "plumb_bob" => {
                c.check("distortion_coefficients", &[1], &[4, 5])?;
                let k3 = c.data.get(4).copied().unwrap_or(0.0);
                Distortion::PlumbBob {
                    k1: c.data[0],
                    k2: c.data[1],
                    p1: c.data[2],
                    p2: c.data[3],
                    k3,
                }
            }
            "equidistant" | "fisheye" => {
                c.check("distortion_coefficients", &[1], &[4])?;
                Distortion::Equidistant {
                    k1: c.data[0],
                    k2: c.data[1],
                    k3: c.data[2],
                    k4: c.data[3],
                }
            }
            other => {
                return Err(format!(
                    "distortion_model `{other}` is not supported: use `plumb_bob` (k1 k2 p1 p2 k3) \
                     or `equidistant` (k1 k2 k3 k4)"
                ))
            }
        };
        let distortion = if distortion.coefficients().iter().all(|&v| v == 0.0) {
            Distortion::None
        } else {
            distortion
        };
        let model = CameraModel {
            width: w,
            height: h,
            fx,
            fy,
            cx,
            cy,
            distortion,
        };
        if !model.covers_image() {
            return Err(
                "the distortion folds back inside the image (the coefficients cannot describe \
                 a real lens over this frame)"
                    .to_string(),
            );
        }
        let hfov = model.hfov_deg();
        // NaN (coefficients that overflow) fails too.
        if hfov.is_nan() || hfov < MIN_HFOV_DEG {
            return Err(format!(
                "the lens sees {hfov:.2}° across the image (fx and the distortion together), \
                 less than {MIN_HFOV_DEG}°: the coefficients cannot describe a camera that \
                 films a turbine"
            ));
        }
        Ok(model)
    }

    /// This camera as ROS `camera_info` YAML (unrectified: R = I, P = [K | 0]).
    pub fn to_ros_yaml(&self, camera_name: &str) -> String {
        let coefficients = self.distortion.coefficients();
        let info = RosCameraInfo {
            image_width: self.width,
            image_height: self.height,
            camera_name: camera_name.to_string(),
            camera_matrix: Matrix {
                rows: 3,
                cols: 3,
                data: vec![self.fx, 0.0, self.cx, 0.0, self.fy, self.cy, 0.0, 0.0, 1.0],
            },
            distortion_model: self.distortion.ros_name().to_string(),
            distortion_coefficients: Matrix {
                rows: 1,
                cols: coefficients.len(),
                data: coefficients,
            },
            rectification_matrix: Some(Matrix {
                rows: 3,
                cols: 3,
                data: vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            }),
            projection_matrix: Some(Matrix {
                rows: 3,
                cols: 4,
                data: vec![
                    self.fx, 0.0, self.cx, 0.0, 0.0, self.fy, self.cy, 0.0, 0.0, 0.0, 1.0, 0.0,
                ],
            }),
        };
        serde_norway::to_string(&info).expect("plain data serialises")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ROS_EXAMPLE: &str = "\
image_width: 640
image_height: 480
camera_name: narrow_stereo
camera_matrix:
  rows: 3
  cols: 3
  data: [430.215550, 0.000000, 306.691343, 0.000000, 430.531693, 227.224800, 0.000000, 0.000000, 1.000000]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [-0.337017, 0.116546, -0.002171, 0.001562, 0.000000]
rectification_matrix:
  rows: 3
  cols: 3
  data: [1.000000, 0.000000, 0.000000, 0.000000, 1.000000, 0.000000, 0.000000, 0.000000, 1.000000]
projection_matrix:
  rows: 3
  cols: 4
  data: [337.097351, 0.000000, 304.001556, 0.000000, 0.000000, 378.137482, 229.059950, 0.000000, 0.000000, 0.000000, 1.000000, 0.000000]
";

    #[test]
    fn reads_a_ros_calibrator_file() {
        let cam = CameraModel::from_ros_yaml(ROS_EXAMPLE).unwrap();
        assert_eq!((cam.width, cam.height), (640, 480));
        assert_eq!((cam.fx, cam.cy), (430.215550, 227.224800));
        assert_eq!(
            cam.distortion,
            Distortion::PlumbBob {
                k1: -0.337017,
                k2: 0.116546,
                p1: -0.002171,
                p2: 0.001562,
                k3: 0.0
            }
        );
    }

    #[test]
    fn writes_what_it_reads() {
        for cam in [
            CameraModel::gopro_hero3(),
            CameraModel::usb_narrow(),
            CameraModel::centred(
                1280,
                960,
                400.0,
                Distortion::Equidistant {
                    k1: 0.01,
                    k2: -0.02,
                    k3: 0.003,
                    k4: -0.001,
                },
            ),
        ] {
            let back = CameraModel::from_ros_yaml(&cam.to_ros_yaml("x")).unwrap();
            assert_eq!(back, cam);
        }
    }

    fn refused(text: &str) -> String {
        CameraModel::from_ros_yaml(text).unwrap_err()
    }

    #[test]
    fn refuses_bad_files_saying_why() {
        let missing = ROS_EXAMPLE.replace("image_height: 480\n", "");
        assert!(
            refused(&missing).contains("image_height"),
            "{}",
            refused(&missing)
        );
        let short = ROS_EXAMPLE.replace(
            "[-0.337017, 0.116546, -0.002171, 0.001562, 0.000000]",
            "[-0.3, 0.1]",
        );
        assert!(
            refused(&short).contains("has 2 values"),
            "{}",
            refused(&short)
        );
        let nan = ROS_EXAMPLE.replace("430.215550", ".nan");
        assert!(refused(&nan).contains("NaN"), "{}", refused(&nan));
        let model = ROS_EXAMPLE.replace("plumb_bob", "rational_polynomial");
        assert!(
            refused(&model).contains("not supported"),
            "{}",
            refused(&model)
        );
        let zero = ROS_EXAMPLE.replace("image_width: 640", "image_width: 0");
        assert!(refused(&zero).contains("image size"), "{}", refused(&zero));
        let outside = ROS_EXAMPLE.replace("306.691343", "9000.0");
        assert!(
            refused(&outside).contains("principal point"),
            "{}",
            refused(&outside)
        );
        let negative = ROS_EXAMPLE.replace("430.531693", "-430.5");
        assert!(
            refused(&negative).contains("positive"),
            "{}",
            refused(&negative)
        );
        let anisotropic = ROS_EXAMPLE.replace("430.531693", "0.4305");
        assert!(
            refused(&anisotropic).contains("differ more than"),
            "{}",
            refused(&anisotropic)
        );
        let absurd = ROS_EXAMPLE.replace("0.116546", "1e20");
        assert!(
            refused(&absurd).contains("less than 1°"),
            "{}",
            refused(&absurd)
        );
        let folding = ROS_EXAMPLE.replace("0.116546", "-2.0");
        assert!(
            refused(&folding).contains("folds back"),
            "{}",
            refused(&folding)
        );
        let fisheye_5 = ROS_EXAMPLE.replace("plumb_bob", "equidistant");
        assert!(
            refused(&fisheye_5).contains("expected 1x4"),
            "{}",
            refused(&fisheye_5)
        );
        assert!(!refused("").is_empty());
        assert!(!refused("image_width: [").is_empty());
    }

    #[test]
    fn load_names_the_file_and_refuses_huge_ones() {
        let dir = std::env::temp_dir().join(format!("hubtrack-camera-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let big = dir.join("big.yaml");
        std::fs::write(&big, "a".repeat(MAX_FILE_BYTES as usize + 10)).unwrap();
        let e = CameraModel::load(&big).unwrap_err().to_string();
        assert!(e.contains("big.yaml") && e.contains("larger than"), "{e}");
        let e = CameraModel::load(&dir.join("absent.yaml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("absent.yaml") && e.contains("cannot open"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn the_shipped_calibrations_are_the_builtin_cameras() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config/cameras");
        let gopro = CameraModel::load(&dir.join("gopro_hero3_wide_1080p.yaml")).unwrap();
        assert_eq!(gopro, CameraModel::gopro_hero3());
        let usb = CameraModel::load(&dir.join("usb_narrow_640x480.yaml")).unwrap();
        assert_eq!(usb, CameraModel::usb_narrow());
    }
}
