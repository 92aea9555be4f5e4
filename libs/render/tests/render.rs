//! End-to-end checks of projection, truth, conventions, effects and robustness.

use hubtrack_render::camera::Distortion;
use hubtrack_render::scene::{HUB_OVERHANG_M, SPINNER_NOSE_LENGTH_M};
use hubtrack_render::{
    Camera, CameraPose, Distractor, Ground, NacelleSize, RenderError, Renderer, Scene, Sky, Truth,
};

fn render(cam: Camera, scene: &Scene, pose: &CameraPose) -> (Vec<u8>, Truth) {
    let mut r = Renderer::new(cam);
    let mut buf = vec![0u8; cam.frame_bytes()];
    let truth = r.render(scene, pose, &mut buf).expect("render");
    (buf, truth)
}

fn quiet(scene: Scene) -> Scene {
    Scene {
        noise_sigma: 0.0,
        blur: false,
        jpeg_quality: None,
        propellers_in_view: false,
        ..scene
    }
}

fn px(cam: &Camera, buf: &[u8], x: usize, y: usize) -> [u8; 3] {
    let i = (y * cam.width as usize + x) * 3;
    [buf[i], buf[i + 1], buf[i + 2]]
}

#[test]
fn projection_centre_and_fov_edges_pinhole() {
    let cam = Camera::pinhole(640, 480, 90.0);
    let c = cam.project([0.0, 0.0, 10.0]).expect("in front");
    assert!((c[0] - 319.5).abs() < 1e-12 && (c[1] - 239.5).abs() < 1e-12);
    // 45° to the right = outer edge of the last pixel column.
    let e = cam.project([10.0, 0.0, 10.0]).expect("in front");
    assert!((e[0] - 639.5).abs() < 1e-9, "{e:?}");
    let l = cam.project([-10.0, 0.0, 10.0]).expect("in front");
    assert!((l[0] + 0.5).abs() < 1e-9, "{l:?}");
    assert!(cam.project([0.0, 0.0, -1.0]).is_none());
    assert!(cam.project([1.0, 1.0, 0.0]).is_none());
}

#[test]
fn gopro_fov_edges() {
    use hubtrack_render::camera::{GOPRO_DFOV_DEG, GOPRO_HFOV_DEG, GOPRO_VFOV_DEG};
    let cam = Camera::gopro_hero3();
    let h = (GOPRO_HFOV_DEG / 2.0).to_radians().tan();
    let right = cam.project([h, 0.0, 1.0]).expect("in front");
    assert!(
        (right[0] - 1919.5).abs() < 0.01 && (right[1] - 539.5).abs() < 1e-9,
        "{right:?}"
    );
    let v = (GOPRO_VFOV_DEG / 2.0).to_radians().tan();
    let bottom = cam.project([0.0, v, 1.0]).expect("in front");
    assert!((bottom[1] - 1079.5).abs() < 0.01, "{bottom:?}");
    // Diagonal: the corner direction at half the diagonal FOV lands on the image corner.
    let d = (GOPRO_DFOV_DEG / 2.0).to_radians().tan();
    let (cx, cy) = (960.0f64, 540.0f64);
    let n = (cx * cx + cy * cy).sqrt();
    let corner = cam
        .project([d * cx / n, d * cy / n, 1.0])
        .expect("in front");
    assert!(
        (corner[0] - 1919.5).abs() < 0.02 && (corner[1] - 1079.5).abs() < 0.02,
        "{corner:?}"
    );
    // Barrel distortion: a point at the pinhole edge position lands well inside the frame.
    assert!(matches!(cam.distortion, Distortion::PlumbBob { k1, .. } if k1 < 0.0));
    let pin_edge = cam.project([960.0 / cam.fx, 0.0, 1.0]).expect("in front");
    assert!(pin_edge[0] < 1919.5 - 50.0, "{pin_edge:?}");
}

#[test]
fn usb_camera_diagonal_fov() {
    let cam = Camera::usb_narrow();
    assert_eq!((cam.width, cam.height), (640, 480));
    let d = 30f64.to_radians().tan();
    let corner = cam.project([d * 0.8, d * 0.6, 1.0]).expect("in front");
    assert!(
        (corner[0] - 639.5).abs() < 1e-6 && (corner[1] - 479.5).abs() < 1e-6,
        "{corner:?}"
    );
}

#[test]
fn unproject_inverts_project() {
    let cam = Camera::gopro_hero3();
    for &(x, y) in &[(0.0, 0.0), (0.5, -0.3), (-1.4, 0.55), (1.6, 0.6)] {
        let p = cam.project([x, y, 1.0]).expect("in front");
        let back = cam.unproject(p);
        assert!(
            (back[0] - x).abs() < 1e-9 && (back[1] - y).abs() < 1e-9,
            "{x} {y} -> {back:?}"
        );
    }
}

#[test]
fn hub_at_image_centre_when_looking_at_it() {
    for cam in [
        Camera::gopro_hero3(),
        Camera::usb_narrow(),
        Camera::pinhole(800, 600, 50.0),
    ] {
        for pose in [
            CameraPose::front(100.0),
            CameraPose::looking_at_hub(80.0, 25.0, -15.0),
            CameraPose::looking_at_hub(40.0, -30.0, 12.0),
        ] {
            let (_, t) = render(cam, &quiet(Scene::default_clear()), &pose);
            let hub = t.hub_px.expect("hub projects");
            assert!(
                (hub[0] - cam.cx).abs() < 1e-6 && (hub[1] - cam.cy).abs() < 1e-6,
                "{pose:?} -> {hub:?}"
            );
            assert!(t.turbine_in_view);
            let expected =
                (pose.distance_m.powi(2) + pose.lateral_m.powi(2) + pose.height_m.powi(2)).sqrt();
            assert!((t.distance_m - expected).abs() < 1e-9);
            assert!((t.hub_cam_m[2] - expected).abs() < 1e-6);
        }
    }
}

#[test]
fn relative_yaw_sign_convention() {
    let cam = Camera::pinhole(640, 480, 60.0);
    let scene = quiet(Scene::default_clear());
    // Straight in front: zero.
    let (_, t) = render(cam, &scene, &CameraPose::front(80.0));
    assert!(t.relative_yaw_deg.abs() < 1e-9);
    // Camera moved to the viewer's right (turbine's own left), turned to look at the hub: positive.
    let (_, t) = render(cam, &scene, &CameraPose::looking_at_hub(80.0, 30.0, 0.0));
    assert!(t.relative_yaw_deg > 0.0);
    assert!((t.relative_yaw_deg - 30f64.atan2(80.0).to_degrees()).abs() < 1e-9);
    // Geometry agrees: seen from the viewer's right, the nose (in front of the hub, toward the
    // rotor-face side) appears left of the hub.
    let (hub, nose) = (t.hub_px.expect("hub"), t.nose_px.expect("nose"));
    assert!(nose[0] < hub[0] - 1.0, "hub {hub:?} nose {nose:?}");
    // And the mirror image.
    let (_, t) = render(cam, &scene, &CameraPose::looking_at_hub(80.0, -30.0, 0.0));
    assert!(t.relative_yaw_deg < 0.0);
    assert!(t.nose_px.expect("nose")[0] > t.hub_px.expect("hub")[0] + 1.0);
    // Turning the nacelle clockwise (seen from above) puts a front camera on the turbine's left.
    let yawed = Scene {
        nacelle_yaw_deg: 20.0,
        ..scene.clone()
    };
    let (_, t) = render(cam, &yawed, &CameraPose::front(80.0));
    assert!((t.relative_yaw_deg - 20.0).abs() < 1e-9);
    assert!(t.nose_px.expect("nose")[0] < t.hub_px.expect("hub")[0]);
}

#[test]
fn nose_is_spinner_length_in_front_of_hub() {
    let cam = Camera::pinhole(1000, 800, 40.0);
    let pose = CameraPose::front(100.0);
    let (_, t) = render(cam, &quiet(Scene::default_clear()), &pose);
    // Front view: nose and hub on the optical axis.
    let nose = t.nose_px.expect("nose");
    assert!((nose[0] - cam.cx).abs() < 1e-6 && (nose[1] - cam.cy).abs() < 1e-6);
    // Tower top straight below the hub, at the pinhole position.
    let top = t.tower_top_px.expect("tower top");
    let depth = pose.distance_m + HUB_OVERHANG_M;
    let expected_v = cam.cy + cam.fy * (hubtrack_render::scene::NACELLE_HEIGHT_M / 2.0) / depth;
    assert!(
        (top[0] - cam.cx).abs() < 1e-6 && (top[1] - expected_v).abs() < 1e-6,
        "{top:?}"
    );
    // Pure side view from the viewer's right: the nose sticks out to the left of the hub by
    // exactly f · SPINNER_NOSE_LENGTH_M / distance.
    let side = CameraPose::looking_at_hub(0.0, 50.0, 0.0);
    let (_, t) = render(cam, &quiet(Scene::default_clear()), &side);
    let (hub, nose) = (t.hub_px.expect("hub"), t.nose_px.expect("nose"));
    assert!((hub[0] - cam.cx).abs() < 1e-6);
    let expected = cam.cx - cam.fx * SPINNER_NOSE_LENGTH_M / 50.0;
    assert!(
        (nose[0] - expected).abs() < 1e-6 && (nose[1] - cam.cy).abs() < 1e-6,
        "{nose:?} vs {expected}"
    );
    assert!((t.relative_yaw_deg - 90.0).abs() < 1e-9);
}

#[test]
fn a_turbines_own_spinner_overhang_and_nacelle_reach_the_truth() {
    let cam = Camera::pinhole(1000, 800, 40.0);
    let scene = quiet(Scene {
        spinner_diameter_m: 4.8,
        hub_overhang_m: 6.0,
        nacelle_scale: 1.3,
        ..Scene::default_clear()
    });
    // Front view: the tower top is half the (scaled) nacelle under the hub, one overhang deeper.
    let pose = CameraPose::front(100.0);
    let (_, t) = render(cam, &scene, &pose);
    let top = t.tower_top_px.expect("tower top");
    let expected_v = cam.cy + cam.fy * (1.3 * 3.5 / 2.0) / (100.0 + 6.0);
    assert!(
        (top[1] - expected_v).abs() < 1e-6,
        "{top:?} vs {expected_v}"
    );
    // Side view: a spinner 1.5 times the default's diameter has a 1.5 times longer nose.
    let side = CameraPose::looking_at_hub(0.0, 50.0, 0.0);
    let (_, t) = render(cam, &scene, &side);
    let nose = t.nose_px.expect("nose");
    let expected = cam.cx - cam.fx * 1.5 * SPINNER_NOSE_LENGTH_M / 50.0;
    assert!((nose[0] - expected).abs() < 1e-6, "{nose:?} vs {expected}");
    // A nacelle of its own dimensions (a turbine profile's): the tower top half its height under
    // the hub, and the body drawn that wide.
    let own = NacelleSize {
        length_m: 12.0,
        width_m: 5.0,
        height_m: 4.9,
        front_behind_hub_m: 1.0,
    };
    let sized = quiet(Scene {
        nacelle_size: Some(own),
        ..scene.clone()
    });
    let (img, t) = render(cam, &sized, &pose);
    let top = t.tower_top_px.expect("tower top");
    let expected_v = cam.cy + cam.fy * (4.9 / 2.0) / (100.0 + 6.0);
    assert!(
        (top[1] - expected_v).abs() < 1e-6,
        "{top:?} vs {expected_v}"
    );
    let (plain, _) = render(cam, &scene, &pose);
    assert_ne!(img, plain, "the nacelle's own size is drawn");
    // Out of range: refused, not drawn.
    let mut renderer = Renderer::new(cam);
    let mut out = vec![0u8; cam.frame_bytes()];
    for bad in [
        Scene {
            spinner_diameter_m: f64::NAN,
            ..Scene::default_clear()
        },
        Scene {
            hub_overhang_m: 0.0,
            ..Scene::default_clear()
        },
        Scene {
            nacelle_scale: 9.0,
            ..Scene::default_clear()
        },
        Scene {
            nacelle_size: Some(NacelleSize {
                width_m: f64::NAN,
                ..NacelleSize::default_scaled(1.0)
            }),
            ..Scene::default_clear()
        },
    ] {
        assert!(renderer.render(&bad, &pose, &mut out).is_err());
    }
}

#[test]
fn tower_width_matches_pinhole_prediction() {
    let cam = Camera::pinhole(1280, 960, 40.0);
    for distance in [60.0, 100.0, 180.0, 300.0] {
        let scene = quiet(Scene::default_clear());
        let pose = CameraPose::front(distance);
        let (_, t) = render(cam, &scene, &pose);
        let w = t.tower_width_px.expect("tower width");
        let z = t.tower_width_height_m.expect("height");
        let row = t.tower_width_row.expect("row");
        // The camera looks along -X at hub height: the tower axis is at depth distance + overhang.
        let depth = distance + HUB_OVERHANG_M;
        let predicted = cam.fx * scene.tower_diameter_at(z) / depth;
        assert!(
            (w - predicted).abs() <= 1.0,
            "d={distance}: measured {w} px, predicted {predicted:.2} px"
        );
        // The row is the one through the reference point just below the nacelle.
        let expected_row = cam.cy + cam.fy * (scene.hub_height_m - z) / depth;
        assert!(
            (row - expected_row.round()).abs() < 0.5,
            "row {row} vs {expected_row}"
        );
        assert!(
            (z - (scene.tower_top_height_m() - hubtrack_render::TOWER_WIDTH_REF_BELOW_TOP_M)).abs()
                < 1e-9
        );
    }
}

#[test]
fn tower_width_falls_back_to_lowest_visible_row() {
    // Camera pitched down close to the tower base: the reference row (under the nacelle) is
    // above the image, so the width is measured on the lowest row that shows the tower.
    let cam = Camera::pinhole(800, 600, 50.0);
    let scene = quiet(Scene::default_clear());
    let pose = CameraPose {
        height_m: -45.0,
        pitch_deg: -30.0,
        ..CameraPose::front(60.0)
    };
    let (_, t) = render(cam, &scene, &pose);
    let row = t.tower_width_row.expect("row");
    let z = t.tower_width_height_m.expect("height");
    // Tower top above the image: the width is taken low on the tower, at the base margin.
    assert!(
        (z - hubtrack_render::TOWER_WIDTH_MIN_HEIGHT_M).abs() < 0.05,
        "z {z}"
    );
    assert!(row > 100.0, "row {row}");
    // Looking down 30°, a vertical tower is not slanted at the image centre column: the width
    // is close to f·D/Z with Z the depth of the axis point.
    let w = t.tower_width_px.expect("width");
    let cam_h = scene.hub_height_m + pose.height_m;
    let dx = pose.distance_m + HUB_OVERHANG_M;
    let dz = cam_h - z;
    let p = pose.pitch_deg.to_radians();
    let depth = dx * p.cos() + dz * (-p).sin();
    let predicted = cam.fx * scene.tower_diameter_at(z) / depth;
    assert!(
        (w - predicted).abs() <= 1.5,
        "measured {w}, predicted {predicted:.2}"
    );
}

#[test]
fn hub_pixel_is_turbine_not_sky() {
    let cam = Camera::gopro_hero3();
    let scene = quiet(Scene::default_clear());
    let pose = CameraPose::front(120.0);
    let (buf, t) = render(cam, &scene, &pose);
    let hub = t.hub_px.expect("hub");
    let [b, g, r] = px(&cam, &buf, hub[0].round() as usize, hub[1].round() as usize);
    // Turbine paint is a neutral light grey; clear sky at this elevation is clearly blue.
    assert!(
        (r as i32 - b as i32).abs() < 15 && (g as i32 - b as i32).abs() < 15,
        "bgr {b} {g} {r}"
    );
    let (sky_buf, _) = render(
        cam,
        &Scene {
            turbine_present: false,
            ..scene
        },
        &pose,
    );
    let [sb, _, sr] = px(
        &cam,
        &sky_buf,
        hub[0].round() as usize,
        hub[1].round() as usize,
    );
    assert!(
        sb as i32 - sr as i32 > 25,
        "sky should be blue: b {sb} r {sr}"
    );
}

#[test]
fn scene_without_turbine_reports_nothing_in_view() {
    let cam = Camera::usb_narrow();
    for distractor in [
        Distractor::None,
        Distractor::Mast,
        Distractor::PowerLines,
        Distractor::Chimney,
    ] {
        let scene = Scene {
            turbine_present: false,
            distractor,
            ..Scene::default_clear()
        };
        let (_, t) = render(cam, &scene, &CameraPose::front(100.0));
        assert!(!t.turbine_in_view);
        assert!(t.hub_px.is_none() && t.tower_width_px.is_none());
    }
}

/// A chimney without a turbine stands where the turbine would be: a column of grey concrete
/// across the sky above the image centre, several pixels wide, where the empty scene shows sky.
#[test]
fn a_chimney_stands_where_the_turbine_would_be() {
    let cam = Camera::usb_narrow();
    let empty = Scene {
        turbine_present: false,
        ..Scene::default_clear()
    };
    let pose = CameraPose::front(100.0);
    let (sky, _) = render(cam, &empty, &pose);
    let (chimney, _) = render(
        cam,
        &Scene {
            distractor: Distractor::Chimney,
            ..empty
        },
        &pose,
    );
    // The row a third of the way down: sky in the empty scene.
    let y = cam.height as usize / 3;
    let changed: Vec<usize> = (0..cam.width as usize)
        .filter(|&x| {
            let (a, b) = (px(&cam, &sky, x, y), px(&cam, &chimney, x, y));
            a.iter().zip(&b).any(|(p, q)| p.abs_diff(*q) > 20)
        })
        .collect();
    assert!(changed.len() >= 3, "{changed:?}");
    // One column, not scattered pixels.
    assert!(
        changed.last().unwrap() - changed[0] < changed.len() + 2,
        "{changed:?}"
    );
}

#[test]
fn hub_outside_image_is_not_in_view() {
    let cam = Camera::usb_narrow();
    let pose = CameraPose {
        yaw_deg: 90.0,
        ..CameraPose::front(100.0)
    };
    let (_, t) = render(cam, &Scene::default_clear(), &pose);
    assert!(!t.turbine_in_view);
}

#[test]
fn deterministic_for_same_seed() {
    let cam = Camera::gopro_hero3();
    let scene = Scene {
        sky: Sky::Clouds,
        second_turbine: true,
        propellers_in_view: true,
        jpeg_quality: Some(80),
        ..Scene::random(42)
    };
    let pose = CameraPose::looking_at_hub(70.0, 15.0, -8.0);
    let (a, ta) = render(cam, &scene, &pose);
    // A second render with a reused renderer (scratch state from another scene in between).
    let mut r = Renderer::new(cam);
    let mut b = vec![0u8; cam.frame_bytes()];
    r.render(&Scene::random(7), &CameraPose::front(40.0), &mut b)
        .expect("render");
    let tb = r.render(&scene, &pose, &mut b).expect("render");
    assert!(a == b, "same seed must give identical bytes");
    assert_eq!(ta, tb);
    // A different seed changes the picture; a different frame changes only the noise.
    let (c, _) = render(
        cam,
        &Scene {
            seed: 43,
            ..scene.clone()
        },
        &pose,
    );
    assert!(a != c);
    let (d, _) = render(
        cam,
        &Scene {
            frame: 1,
            ..scene.clone()
        },
        &pose,
    );
    assert!(a != d);
}

#[test]
fn wrong_buffer_size_is_an_error() {
    let cam = Camera::usb_narrow();
    let mut r = Renderer::new(cam);
    let mut small = vec![0u8; cam.frame_bytes() - 1];
    let err = r
        .render(
            &Scene::default_clear(),
            &CameraPose::front(50.0),
            &mut small,
        )
        .unwrap_err();
    assert_eq!(
        err,
        RenderError::BufferSize {
            expected: 640 * 480 * 3,
            got: 640 * 480 * 3 - 1
        }
    );
    let mut big = vec![0u8; cam.frame_bytes() + 3];
    assert!(matches!(
        r.render(&Scene::default_clear(), &CameraPose::front(50.0), &mut big),
        Err(RenderError::BufferSize { .. })
    ));
}

#[test]
fn invalid_inputs_are_errors() {
    let cam = Camera::usb_narrow();
    let mut r = Renderer::new(cam);
    let mut buf = vec![0u8; cam.frame_bytes()];
    let under = CameraPose {
        height_m: -80.0,
        ..CameraPose::front(50.0)
    };
    assert!(matches!(
        r.render(&Scene::default_clear(), &under, &mut buf),
        Err(RenderError::CameraBelowGround { .. })
    ));
    let nan = CameraPose {
        yaw_deg: f64::NAN,
        ..CameraPose::front(50.0)
    };
    assert!(matches!(
        r.render(&Scene::default_clear(), &nan, &mut buf),
        Err(RenderError::InvalidInput(_))
    ));
    let bad = Scene {
        hub_height_m: -3.0,
        ..Scene::default_clear()
    };
    assert!(matches!(
        r.render(&bad, &CameraPose::front(50.0), &mut buf),
        Err(RenderError::InvalidInput(_))
    ));
}

/// Per row, the centre of the main turbine's pixels (those that differ from the same frame
/// without the turbine), keeping only rows where they form one narrow run (tower only, no blade),
/// then dropping the ends (base outline, nacelle).
fn tower_centres(cam: &Camera, with: &[u8], without: &[u8]) -> Vec<(f64, f64)> {
    let w = cam.width as usize;
    let mut pts = Vec::new();
    for y in 0..cam.height as usize {
        let cols: Vec<usize> = (0..w)
            .filter(|&x| {
                let i = (y * w + x) * 3;
                (0..3)
                    .map(|c| (with[i + c] as i32 - without[i + c] as i32).abs())
                    .sum::<i32>()
                    > 30
            })
            .collect();
        if let (Some(&first), Some(&last)) = (cols.first(), cols.last()) {
            let single_run = last - first + 1 == cols.len();
            if single_run && cols.len() < 80 {
                pts.push((y as f64, (first + last) as f64 / 2.0));
            }
        }
    }
    // The tower is the longest block of consecutive rows (blades above give shorter blocks).
    let mut best = (0, 0);
    let mut start = 0;
    for i in 1..=pts.len() {
        if i == pts.len() || pts[i].0 != pts[i - 1].0 + 1.0 {
            if i - start > best.1 - best.0 {
                best = (start, i);
            }
            start = i;
        }
    }
    let block = &pts[best.0..best.1];
    let trim = block.len() / 6;
    block[trim..block.len() - trim].to_vec()
}

/// Largest distance of the centres from the straight line through the first and last.
fn max_bend(pts: &[(f64, f64)]) -> f64 {
    let (a, b) = (pts[0], pts[pts.len() - 1]);
    pts.iter()
        .map(|p| {
            let t = (p.0 - a.0) / (b.0 - a.0);
            (p.1 - (a.1 + t * (b.1 - a.1))).abs()
        })
        .fold(0.0, f64::max)
}

#[test]
fn straight_tower_bends_near_gopro_edge() {
    // Camera turned right and pitched down so the tower runs down near the left image edge.
    let scene = quiet(Scene::default_clear());
    let pose = CameraPose {
        yaw_deg: 48.0,
        pitch_deg: -22.0,
        ..CameraPose::front(70.0)
    };
    let no_turbine = Scene {
        turbine_present: false,
        ..scene.clone()
    };
    let gopro = Camera::gopro_hero3();
    let (with, _) = render(gopro, &scene, &pose);
    let (without, _) = render(gopro, &no_turbine, &pose);
    let pts = tower_centres(&gopro, &with, &without);
    assert!(pts.len() > 150, "tower visible on {} rows", pts.len());
    assert!(
        pts.iter().all(|p| p.1 < 600.0),
        "tower should be near the left edge: {:?}",
        pts[0]
    );
    let bend = max_bend(&pts);
    assert!(
        bend > 4.0,
        "tower should bend through the barrel lens, max deviation {bend:.2} px"
    );

    // The same view through a pinhole lens of the same horizontal field of view stays straight.
    let pin = Camera::pinhole(1920, 1080, 118.0);
    let (with, _) = render(pin, &scene, &pose);
    let (without, _) = render(pin, &no_turbine, &pose);
    let pts = tower_centres(&pin, &with, &without);
    assert!(pts.len() > 150, "tower visible on {} rows", pts.len());
    let bend = max_bend(&pts);
    eprintln!("{:?}", pts.iter().step_by(15).collect::<Vec<_>>());
    assert!(
        bend < 1.0,
        "pinhole tower should be straight, max deviation {bend:.2} px"
    );
}

#[test]
fn random_scenes_and_extreme_poses_render() {
    let cam = Camera::usb_narrow();
    let mut r = Renderer::new(cam);
    let mut buf = vec![0u8; cam.frame_bytes()];
    let poses = [
        CameraPose::front(8.0),
        CameraPose::looking_at_hub(150.0, 80.0, 40.0),
        CameraPose {
            pitch_deg: -89.0,
            ..CameraPose::front(20.0)
        },
        CameraPose {
            pitch_deg: 89.0,
            roll_deg: 90.0,
            ..CameraPose::front(20.0)
        },
        CameraPose {
            yaw_deg: 180.0,
            ..CameraPose::front(30.0)
        },
        CameraPose {
            distance_m: -40.0,
            ..CameraPose::front(0.0)
        },
        CameraPose {
            distance_m: 0.0,
            lateral_m: 0.0,
            height_m: 3.0,
            yaw_deg: 0.0,
            pitch_deg: -90.0,
            roll_deg: 0.0,
        },
        CameraPose::looking_at_hub(5.0, 3.0, -25.0),
    ];
    for seed in 0..24u64 {
        let scene = Scene::random(seed);
        let pose = &poses[seed as usize % poses.len()];
        let t = r.render(&scene, pose, &mut buf).expect("render");
        assert!(t.distance_m.is_finite() && t.relative_yaw_deg.is_finite());
        if let Some(h) = t.hub_px {
            assert!(h[0].is_finite() && h[1].is_finite());
        }
    }
}

#[test]
fn every_sky_and_ground_renders_plausibly() {
    let cam = Camera::pinhole(320, 240, 90.0);
    for sky in [Sky::Clear, Sky::Overcast, Sky::Clouds] {
        for ground in [Ground::Grass, Ground::Sea, Ground::Hills] {
            let scene = quiet(Scene {
                sky,
                ground,
                turbine_present: false,
                ..Scene::default_clear()
            });
            let (buf, _) = render(cam, &scene, &CameraPose::front(100.0));
            // Top row is sky (bright-ish, bluer or grey), bottom row is ground (darker).
            let top: u32 = (0..320)
                .map(|x| px(&cam, &buf, x, 2).iter().map(|&c| c as u32).sum::<u32>())
                .sum();
            let bottom: u32 = (0..320)
                .map(|x| {
                    px(&cam, &buf, x, 237)
                        .iter()
                        .map(|&c| c as u32)
                        .sum::<u32>()
                })
                .sum();
            assert!(
                top > bottom,
                "{sky:?}/{ground:?}: sky {top} vs ground {bottom}"
            );
        }
    }
}

#[test]
fn sensor_noise_has_requested_strength() {
    let cam = Camera::pinhole(320, 240, 60.0);
    let clean = quiet(Scene {
        turbine_present: false,
        ..Scene::default_clear()
    });
    let noisy = Scene {
        noise_sigma: 4.0,
        ..clean.clone()
    };
    let pose = CameraPose::front(100.0);
    let (a, _) = render(cam, &clean, &pose);
    let (b, _) = render(cam, &noisy, &pose);
    let n = a.len() as f64;
    let mean: f64 = a
        .iter()
        .zip(&b)
        .map(|(&x, &y)| y as f64 - x as f64)
        .sum::<f64>()
        / n;
    let var: f64 = a
        .iter()
        .zip(&b)
        .map(|(&x, &y)| (y as f64 - x as f64 - mean).powi(2))
        .sum::<f64>()
        / n;
    assert!(mean.abs() < 0.3, "mean {mean}");
    assert!((var.sqrt() - 4.0).abs() < 0.5, "sigma {}", var.sqrt());
}

#[test]
fn blur_and_jpeg_change_the_image_mildly() {
    let cam = Camera::pinhole(320, 240, 60.0);
    let base = quiet(Scene::default_clear());
    let pose = CameraPose::front(60.0);
    let (a, _) = render(cam, &base, &pose);
    for scene in [
        Scene {
            blur: true,
            ..base.clone()
        },
        Scene {
            jpeg_quality: Some(50),
            ..base.clone()
        },
    ] {
        let (b, _) = render(cam, &scene, &pose);
        let mad: f64 = a
            .iter()
            .zip(&b)
            .map(|(&x, &y)| (x as f64 - y as f64).abs())
            .sum::<f64>()
            / a.len() as f64;
        assert!(mad > 0.05 && mad < 8.0, "mean abs diff {mad}");
    }
}

#[test]
fn tiny_and_odd_sized_cameras_do_not_panic() {
    for (w, h) in [(1u32, 1u32), (2, 3), (17, 9), (33, 1), (1, 40)] {
        for cam in [
            Camera::pinhole(w, h, 70.0),
            Camera {
                distortion: Distortion::radial(-0.2, 0.02),
                ..Camera::pinhole(w, h, 100.0)
            },
        ] {
            let mut r = Renderer::new(cam);
            let mut buf = vec![0u8; cam.frame_bytes()];
            let scene = Scene {
                blur: true,
                jpeg_quality: Some(40),
                propellers_in_view: true,
                ..Scene::random(w as u64 * 7 + h as u64)
            };
            r.render(&scene, &CameraPose::front(60.0), &mut buf)
                .expect("render");
        }
    }
}

#[test]
fn strong_custom_distortion_renders() {
    // k1 alone folds back beyond r = 1/sqrt(3 |k1|): projection must refuse those points.
    let cam = Camera {
        distortion: Distortion::radial(-0.3, 0.0),
        ..Camera::pinhole(640, 480, 120.0)
    };
    let r_max = cam.max_undistorted_radius();
    assert!((r_max - 1.0 / (0.9f64).sqrt()).abs() < 1e-12);
    assert!(cam.project([r_max * 1.01, 0.0, 1.0]).is_none());
    assert!(cam.project([r_max * 0.99, 0.0, 1.0]).is_some());
    let (_, t) = render(cam, &Scene::default_clear(), &CameraPose::front(50.0));
    assert!(t.turbine_in_view);
}

/// Mean absolute difference between horizontally neighbouring pixels (green channel) in the
/// rows `rows` of a frame: how much fine texture the ground shows.
fn fine_texture(cam: &Camera, buf: &[u8], rows: std::ops::Range<usize>) -> f64 {
    let (w, mut sum, mut n) = (cam.width as usize, 0.0, 0usize);
    for y in rows {
        for x in 1..w {
            sum += (px(cam, buf, x, y)[1] as f64 - px(cam, buf, x - 1, y)[1] as f64).abs();
            n += 1;
        }
    }
    sum / n as f64
}

#[test]
fn shrubland_ground_has_more_fine_texture_than_fields() {
    // Looking down from above the hub: the lower half of the frame is ground near the tower.
    let cam = Camera::pinhole(960, 540, 75.0);
    let pose = CameraPose::looking_at_hub(60.0, 0.0, 40.0);
    let fields = quiet(Scene {
        seed: 5,
        ..Scene::default_clear()
    });
    let shrubs = Scene {
        shrubland: true,
        ..fields.clone()
    };
    let (a, ta) = render(cam, &fields, &pose);
    let (b, tb) = render(cam, &shrubs, &pose);
    assert_eq!(ta, tb, "the ground does not change the truth");
    let (fa, fb) = (
        fine_texture(&cam, &a, 400..540),
        fine_texture(&cam, &b, 400..540),
    );
    assert!(
        fb > 2.0 * fa,
        "shrubland {fb:.2} against fields {fa:.2} grey levels per pixel step"
    );
}

#[test]
fn wind_farm_neighbours_stand_behind_the_main_turbine() {
    let cam = Camera::gopro_hero3();
    let pose = CameraPose::looking_at_hub(40.0, 10.0, 15.0);
    let alone = quiet(Scene {
        seed: 9,
        ..Scene::default_clear()
    });
    let farm = Scene {
        neighbour_turbines: 5,
        ..alone.clone()
    };
    let (a, ta) = render(cam, &alone, &pose);
    let (b, tb) = render(cam, &farm, &pose);
    assert_eq!(ta, tb, "the truth is the main turbine's");
    let changed = a
        .chunks_exact(3)
        .zip(b.chunks_exact(3))
        .filter(|(p, q)| p != q)
        .count();
    assert!(
        changed > 500,
        "the neighbours are drawn ({changed} pixels changed)"
    );
    // Nothing in front of the main turbine: its hub pixel and the pixels around it stay.
    let [hx, hy] = ta.hub_px.expect("hub in view");
    for dy in -3i64..=3 {
        for dx in -3i64..=3 {
            let (x, y) = ((hx as i64 + dx) as usize, (hy as i64 + dy) as usize);
            assert_eq!(
                px(&cam, &a, x, y),
                px(&cam, &b, x, y),
                "hub area changed at ({x}, {y})"
            );
        }
    }
}

#[test]
fn photo_like_cases_cover_views_from_above_far_and_oblique() {
    use hubtrack_render::dataset::{photo_case, PHOTO_DISTANCE_M, PHOTO_MAX_REL_YAW_DEG};
    let cases: Vec<_> = (0..400).map(|i| photo_case(7, i, false)).collect();
    let again = photo_case(7, 3, false);
    assert_eq!(
        (again.scene, again.pose.distance_m),
        (cases[3].scene.clone(), cases[3].pose.distance_m),
        "deterministic"
    );
    let (mut above, mut far, mut oblique, mut shrubs, mut farms) = (0, 0, 0, 0, 0);
    for c in &cases {
        let p = &c.pose;
        let ground_range = p.distance_m.hypot(p.lateral_m);
        assert!(
            (PHOTO_DISTANCE_M.0 - 1e-9..PHOTO_DISTANCE_M.1 + 1e-9).contains(&ground_range),
            "{ground_range}"
        );
        let rel = c.scene.nacelle_yaw_deg + p.lateral_m.atan2(p.distance_m).to_degrees();
        assert!(
            rel.abs() <= PHOTO_MAX_REL_YAW_DEG + 1e-9,
            "relative yaw {rel}"
        );
        assert!(
            c.scene.hub_height_m + p.height_m >= 2.9,
            "camera above the ground"
        );
        above += (p.height_m > 0.3 * ground_range) as usize;
        far += (ground_range > 100.0) as usize;
        oblique += (rel.abs() > 40.0) as usize;
        shrubs += c.scene.shrubland as usize;
        farms += (c.scene.neighbour_turbines > 0) as usize;
    }
    for (what, n) in [
        ("from well above", above),
        ("beyond 100 m", far),
        ("beyond 40° yaw", oblique),
        ("shrubland", shrubs),
        ("wind farm", farms),
    ] {
        assert!(n >= 40, "{what}: {n} of 400");
    }
    let negative = photo_case(7, 0, true).scene;
    assert!(
        negative.neighbour_turbines == 0 && !negative.turbine_present,
        "negatives hold no turbine"
    );
}

#[test]
fn close_photo_like_cases_stay_within_their_range_in_a_stream_of_their_own() {
    use hubtrack_render::dataset::{photo_case, photo_case_close, PHOTO_CLOSE_DISTANCE_M};
    let mut from_above = 0;
    for i in 0..200 {
        let c = photo_case_close(7, i, false);
        let ground_range = c.pose.distance_m.hypot(c.pose.lateral_m);
        assert!(
            (PHOTO_CLOSE_DISTANCE_M.0 - 1e-9..PHOTO_CLOSE_DISTANCE_M.1 + 1e-9)
                .contains(&ground_range),
            "{ground_range}"
        );
        assert_eq!(c.categories, ["photo-like", "photo-like:close"]);
        from_above += (c.pose.height_m > 0.3 * ground_range) as usize;
        // Not the far views' scenes brought closer: a stream of its own.
        assert_ne!(c.scene, photo_case(7, i, false).scene);
    }
    assert!(from_above >= 40, "from well above: {from_above} of 200");
    assert_eq!(photo_case_close(7, 0, true).categories, ["negatives"]);
}
