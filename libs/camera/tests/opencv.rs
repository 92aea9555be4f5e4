//! Projection checked against OpenCV's own `projectPoints` (plumb_bob) and
//! `fisheye::projectPoints` (equidistant), the definitions the ROS calibration formats follow.

use hubtrack_camera::{CameraModel, Distortion};
use opencv::core::{Mat, Point2d, Point3d, Vector};

fn points() -> Vec<[f64; 3]> {
    let mut v = Vec::new();
    for i in -4..=4 {
        for j in -3..=3 {
            let (x, y) = (f64::from(i) * 0.22, f64::from(j) * 0.17);
            v.push([x * 10.0, y * 10.0, 10.0 + 0.3 * f64::from(i + j)]);
        }
    }
    v
}

fn intrinsics(cam: &CameraModel) -> Mat {
    Mat::from_slice_2d(&[
        [cam.fx, 0.0, cam.cx],
        [0.0, cam.fy, cam.cy],
        [0.0, 0.0, 1.0],
    ])
    .unwrap()
}

fn opencv_project(cam: &CameraModel, pts: &[[f64; 3]]) -> Vec<[f64; 2]> {
    let object: Vector<Point3d> = pts.iter().map(|p| Point3d::new(p[0], p[1], p[2])).collect();
    let zero = Mat::from_slice(&[0.0f64, 0.0, 0.0]).unwrap();
    let k = intrinsics(cam);
    let coefficients = cam.distortion.coefficients();
    let d = Mat::from_slice(&coefficients).unwrap();
    let mut image: Vector<Point2d> = Vector::new();
    match cam.distortion {
        Distortion::Equidistant { .. } => opencv::calib3d::fisheye_project_points_vec_def(
            &object, &mut image, &zero, &zero, &k, &d,
        )
        .unwrap(),
        _ => {
            opencv::calib3d::project_points_def(&object, &zero, &zero, &k, &d, &mut image).unwrap()
        }
    }
    image.iter().map(|p| [p.x, p.y]).collect()
}

fn agrees_with_opencv(cam: CameraModel) {
    let pts = points();
    let theirs = opencv_project(&cam, &pts);
    for (p, t) in pts.iter().zip(theirs) {
        let ours = cam.project(*p).unwrap();
        assert!(
            (ours[0] - t[0]).abs() < 1e-6 && (ours[1] - t[1]).abs() < 1e-6,
            "{cam:?}: {p:?} → ours {ours:?}, OpenCV {t:?}"
        );
        // And back: the ray through OpenCV's pixel is the point's direction.
        let r = cam.ray(t);
        assert!(
            (r[0] - p[0] / p[2]).abs() < 1e-9 && (r[1] - p[1] / p[2]).abs() < 1e-9,
            "{cam:?}: ray of {t:?} = {r:?}, expected {:?}",
            [p[0] / p[2], p[1] / p[2]]
        );
    }
}

#[test]
fn pinhole_matches_opencv() {
    agrees_with_opencv(CameraModel::pinhole(1280, 720, 75.0));
}

#[test]
fn plumb_bob_matches_opencv() {
    agrees_with_opencv(CameraModel::gopro_hero3());
    agrees_with_opencv(CameraModel {
        width: 1920,
        height: 1080,
        fx: 1100.0,
        fy: 1090.0,
        cx: 970.0,
        cy: 530.0,
        distortion: Distortion::PlumbBob {
            k1: -0.28,
            k2: 0.09,
            p1: 0.0015,
            p2: -0.0008,
            k3: -0.012,
        },
    });
}

#[test]
fn equidistant_matches_opencv_fisheye() {
    agrees_with_opencv(CameraModel {
        width: 1920,
        height: 1080,
        fx: 700.0,
        fy: 700.0,
        cx: 955.0,
        cy: 545.0,
        distortion: Distortion::Equidistant {
            k1: -0.04,
            k2: 0.012,
            k3: -0.004,
            k4: 0.0006,
        },
    });
}
