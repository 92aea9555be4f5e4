//! End-to-end checks on rendered frames (hubtrack-render).

use hubtrack_detect::params::{DetectConfig, Mode, StillMirror};
use hubtrack_detect::{Detector, Hints, ImageView};
use hubtrack_render::{Camera, CameraPose, Ground, Renderer, Scene};
use hubtrack_types::{Detection, PixelFormat};

/// Sunlit turbine over a dark sea, sun behind the camera: the high-contrast situation the
/// thesis's fixed Canny thresholds (300/400) were tuned for.
fn sunlit_sea() -> Scene {
    Scene {
        ground: Ground::Sea,
        sun_azimuth_deg: 0.0,
        sun_elevation_deg: 20.0,
        ..Scene::default_clear()
    }
}

/// A renderer for the GoPro camera and a frame buffer for it.
fn gopro_renderer() -> (Renderer, Vec<u8>) {
    let cam = Camera::gopro_hero3();
    (Renderer::new(cam), vec![0u8; cam.frame_bytes()])
}

/// A rendered BGR frame of `cam` as the detector's input.
fn bgr_view<'a>(cam: &Camera, buf: &'a [u8]) -> ImageView<'a> {
    ImageView {
        width: cam.width,
        height: cam.height,
        stride: cam.width as usize * 3,
        format: PixelFormat::Bgr8,
        data: buf,
    }
}

/// Renders `scene` from `pose` (GoPro camera) and detects in it with `config` and `hints`.
fn render_and_detect(
    r: &mut Renderer,
    buf: &mut [u8],
    scene: &Scene,
    pose: &CameraPose,
    config: DetectConfig,
    hints: &Hints,
) -> (Detection, hubtrack_render::Truth) {
    let cam = Camera::gopro_hero3();
    let truth = r.render(scene, pose, buf).unwrap();
    let view = bgr_view(&cam, buf);
    (
        Detector::new(config)
            .unwrap()
            .detect(&view, hints)
            .unwrap()
            .detection,
        truth,
    )
}

fn run(mode: Mode, pose: CameraPose) -> (hubtrack_detect::Output, hubtrack_render::Truth) {
    let cam = Camera::gopro_hero3();
    let mut r = Renderer::new(cam);
    let mut buf = vec![0u8; cam.frame_bytes()];
    let truth = r.render(&sunlit_sea(), &pose, &mut buf).unwrap();
    let mut det = Detector::new(DetectConfig {
        mode,
        ..DetectConfig::default()
    })
    .unwrap();
    let view = bgr_view(&cam, &buf);
    (
        det.detect(
            &view,
            &Hints {
                roll_rad: Some(0.0),
                ..Hints::default()
            },
        )
        .unwrap(),
        truth,
    )
}

#[test]
fn front_view_hub_found_by_both_modes() {
    for mode in [Mode::Thesis, Mode::Default] {
        let (out, truth) = run(mode, CameraPose::front(30.0));
        let d = out.detection;
        assert!(d.detected, "{mode:?}: not detected");
        let hub = truth.hub_px.unwrap();
        let err = ((d.hub_px[0] - hub[0]).powi(2) + (d.hub_px[1] - hub[1]).powi(2)).sqrt();
        assert!(
            err <= 0.03 * 1080.0,
            "{mode:?}: hub {:?} truth {hub:?} err {err:.1}px",
            d.hub_px
        );
        assert_eq!((d.image_width, d.image_height), (1920, 1080));
        assert!(d.timings.total_us > 0.0 && d.line_count > 0 && d.edge_count > 0);
    }
}

/// Hints come from other processes and the autopilot: no roll (a vehicle on its side, NaN,
/// infinity), predicted hub or distance may cost more than the hint itself.
#[test]
fn any_hint_is_survived() {
    let (mut r, mut buf) = gopro_renderer();
    let pose = CameraPose::front(20.0);
    for mode in [Mode::Thesis, Mode::Default] {
        for roll_deg in [85.0, 90.0, 179.0, -120.0, f64::NAN, f64::INFINITY] {
            let config = DetectConfig {
                mode,
                ..DetectConfig::default()
            };
            let hints = Hints {
                roll_rad: Some(roll_deg.to_radians()),
                predicted_hub_px: Some([f64::NAN, 1e300]),
                hub_distance_m: Some(-3.0),
            };
            let (d, _) = render_and_detect(&mut r, &mut buf, &sunlit_sea(), &pose, config, &hints);
            assert!(
                d.roll_used_deg.abs() <= 45.0,
                "{mode:?} roll {roll_deg}: used {}",
                d.roll_used_deg
            );
        }
    }
}

#[test]
fn yaw_sign_follows_project_convention() {
    // Camera on the turbine's own left (viewer's right, lateral > 0): positive relative yaw.
    // The hub, 4.2 m in front of the tower, then appears LEFT of the tower axis.
    // The formula and sign are unit-tested in lib.rs; here the rendered geometry must agree
    // whenever a mode reports hub and tower.
    for mode in [Mode::Thesis, Mode::Default] {
        let (out, truth) = run(mode, CameraPose::looking_at_hub(30.0, 12.0, 0.0));
        assert!(truth.relative_yaw_deg > 0.0);
        let d = out.detection;
        let hub = truth.hub_px.unwrap();
        let hit = ((d.hub_px[0] - hub[0]).powi(2) + (d.hub_px[1] - hub[1]).powi(2)).sqrt()
            <= 0.03 * 1080.0;
        // The truth itself: the hub appears left of the tower top.
        assert!(hub[0] < truth.tower_top_px.unwrap()[0]);
        // Only a correct detection with both tower edges (known width) can be held to the sign.
        if d.detected && d.tower_found && hit && d.tower_width_px > 0.0 {
            assert!(d.hub_tower_gap_px < 0.0, "gap {}", d.hub_tower_gap_px);
            if let Some(y) = out.yaw_deg {
                assert!(y > 0.0, "yaw {y}");
            }
        }
    }
}

/// A blade pointing straight down hangs in front of the tower and hides it: with a distance
/// from the tracker inside `tower_blade_down_max_distance_m` no tower is measured (its band
/// would be the blade), while the hub is still found; without a distance, or beyond that one,
/// the band is measured as before.
#[test]
fn no_tower_measured_behind_a_blade_pointing_down() {
    let (mut r, mut buf) = gopro_renderer();
    let hints = Hints {
        roll_rad: Some(0.0),
        hub_distance_m: Some(20.0),
        ..Hints::default()
    };
    let mut detect = |rotor_angle_deg: f64, hints: &Hints, max_distance_m: f64| {
        let mut config = DetectConfig::default();
        config.default.tower_blade_down_max_distance_m = max_distance_m;
        let scene = Scene {
            rotor_angle_deg,
            ..sunlit_sea()
        };
        // 5 m below the hub (at hub height the horizon passed for a blade in this scene). Without
        // the rule the blade-down frame measures a band 110 px wide (the tower: 82 px) with a
        // hub–tower gap of -36 px where it is ~0.
        render_and_detect(
            &mut r,
            &mut buf,
            &scene,
            &CameraPose::looking_at_hub(20.0, 0.0, -5.0),
            config,
            hints,
        )
    };
    let (down, truth) = detect(60.0, &hints, 40.0);
    let no_distance = Hints {
        hub_distance_m: None,
        ..hints
    };
    let (unruled, _) = detect(60.0, &no_distance, 40.0);
    assert!(
        unruled.tower_found,
        "without a distance the rule does not apply: {unruled:?}"
    );
    let hub = truth.hub_px.unwrap();
    assert!(
        down.detected
            && ((down.hub_px[0] - hub[0]).powi(2) + (down.hub_px[1] - hub[1]).powi(2)).sqrt()
                <= 0.03 * 1080.0,
        "truth {hub:?} {down:?}"
    );
    assert!(
        !down.tower_found && down.tower_width_px == 0.0,
        "tower measured behind the blade: {down:?}"
    );
    // Beyond the configured distance the rule does not apply either.
    let (beyond, _) = detect(60.0, &hints, 15.0);
    assert!(
        beyond.tower_found && beyond.tower_width_px > 0.0,
        "{beyond:?}"
    );
}

/// A blade 8–16° from straight down crosses the tower below the hub; a band from one tower
/// edge to that blade's edge, or the blade alone, reads a hub–tower gap tens of pixels off
/// (`fly` seed 279: its sign wrong at 16–24 m, the approach ended 7.7° off). With the ray rule
/// (`tower_blade_ray_tol_deg`) such bands are no tower: no reported gap is misleading, where
/// without the rule some are.
#[test]
fn a_band_along_a_tilted_blade_is_no_tower() {
    let (mut r, mut buf) = gopro_renderer();
    let hints = Hints {
        roll_rad: Some(0.0),
        hub_distance_m: Some(19.0),
        ..Hints::default()
    };
    let mut with_rule = DetectConfig::default();
    assert!(with_rule.default.tower_blade_ray_tol_deg >= 16.0);
    with_rule.default.tower_blade_ray_min_deg = with_rule.default.tower_blade_ray_min_deg.min(8.0);
    let mut without = with_rule.clone();
    without.default.tower_blade_ray_tol_deg = 0.0;
    let (mut misleading_with, mut misleading_without, mut measured_with) =
        (Vec::new(), Vec::new(), 0);
    // Rotor angles whose third blade is 16, 12, 8 degrees left and 8, 12 right of down.
    for rotor_angle_deg in [44.0, 48.0, 52.0, 68.0, 72.0] {
        for lateral_m in [-3.0, -1.7, 0.0, 1.7, 3.0] {
            let scene = Scene {
                rotor_angle_deg,
                ground: Ground::Grass,
                ..sunlit_sea()
            };
            let pose = CameraPose::looking_at_hub(19.0, lateral_m, 0.0);
            for (config, misleading) in [
                (&with_rule, &mut misleading_with),
                (&without, &mut misleading_without),
            ] {
                let (d, truth) =
                    render_and_detect(&mut r, &mut buf, &scene, &pose, config.clone(), &hints);
                let true_gap = truth.hub_px.unwrap()[0] - truth.tower_top_px.unwrap()[0];
                if d.tower_found && d.tower_width_px > 0.0 {
                    if std::ptr::eq(config, &with_rule) {
                        measured_with += 1;
                    }
                    // 20 px: a quarter of the tower's width here, ~4° of yaw.
                    if (d.hub_tower_gap_px - true_gap).abs() > 20.0 {
                        misleading.push((
                            rotor_angle_deg,
                            lateral_m,
                            true_gap.round(),
                            d.hub_tower_gap_px.round(),
                        ));
                    }
                }
            }
        }
    }
    assert!(
        misleading_with.is_empty(),
        "misleading gaps with the ray rule (rotor, lateral, truth, gap): {misleading_with:?}"
    );
    assert!(
        !misleading_without.is_empty(),
        "the scenes no longer test the rule: none misleading without it"
    );
    // The rule removes bands, not every tower (7 of 25 are measured; most frames here show
    // none without it either).
    assert!(
        measured_with >= 5,
        "the rule left only {measured_with} of 25 towers"
    );
}

/// Still photos (`detect_still`): one level finer as well, the more confident detection wins;
/// with `still_finer_level` off it is exactly the frame path (given the stills' first pyramid
/// level, `box_first_level` off), and a detection of the frame path
/// is never lost or made less confident. (Its gain is on cluttered real photos, measured by
/// `hubtrack eval`; on these clean renders both levels see the turbine to ~120 m and neither at
/// 160 m.) The still photos' own heatmap and ranking (`still_models`) are off here; on, they
/// find every hub found without them, the one at 160 m too.
#[test]
fn stills_are_also_detected_one_level_finer() {
    let cam = Camera::gopro_hero3();
    let (mut r, mut buf) = gopro_renderer();
    let hints = Hints {
        roll_rad: Some(0.0),
        ..Hints::default()
    };
    let mut levels_only = DetectConfig::default();
    levels_only.default.still_models = false;
    // Stills' own override of weak choices off too: only the finer level differs here.
    levels_only.default.still_heat_override_max = levels_only.default.heat_override_max;
    // Video frames' own first pyramid level off: stills always take the Gaussian one.
    levels_only.default.box_first_level = false;
    // And the mirror image's detection (`still_mirror`, tested below).
    levels_only.default.still_mirror = StillMirror::Off;
    for d in [30.0, 120.0, 160.0] {
        let truth = r
            .render(&sunlit_sea(), &CameraPose::front(d), &mut buf)
            .unwrap();
        let view = bgr_view(&cam, &buf);
        let mut det = Detector::new(levels_only.clone()).unwrap();
        let frame = det.detect(&view, &hints).unwrap().detection;
        let still = det.detect_still(&view, &hints).unwrap().detection;
        let with_models = Detector::new(DetectConfig::default())
            .unwrap()
            .detect_still(&view, &hints)
            .unwrap()
            .detection;
        let mut off = levels_only.clone();
        off.default.still_finer_level = false;
        let same = Detector::new(off)
            .unwrap()
            .detect_still(&view, &hints)
            .unwrap()
            .detection;
        assert_eq!(
            (same.detected, same.hub_px, same.confidence),
            (frame.detected, frame.hub_px, frame.confidence),
            "{d} m"
        );
        if frame.detected {
            assert!(
                still.detected && still.confidence >= frame.confidence,
                "{d} m: {} < {}",
                still.confidence,
                frame.confidence
            );
        }
        let hub = truth.hub_px.unwrap();
        let on_hub = |x: &Detection| {
            x.detected && (x.hub_px[0] - hub[0]).hypot(x.hub_px[1] - hub[1]) <= 0.03 * 1080.0
        };
        assert_eq!(
            on_hub(&still),
            on_hub(&frame),
            "{d} m: the clean render is seen alike at both levels"
        );
        assert!(
            on_hub(&with_models) || !on_hub(&still),
            "{d} m: the still models lose the hub the levels find"
        );
    }
}

/// Still photos are also detected in their mirror image (`still_mirror`): on close photo-like
/// views of the evaluation seed 2026 (5–12 m, the hub's visible axis up to a third of the
/// frame long; scored as `hubtrack eval` does, within 3 % of the height of the blade-axis
/// point to nose segment) both views together hit more hubs than the photo alone: averaged
/// no fewer, and clearly more with either view's detection standing (`hubtrack eval
/// --photo-close 300` shows the same on 300 views).
#[test]
fn stills_are_also_detected_in_their_mirror_image() {
    use hubtrack_detect::geometry::Segment;
    use hubtrack_render::dataset::{photo_case_close, photo_lenses};
    let mut renderers = photo_lenses().map(Renderer::new);
    let detector = |how: StillMirror| {
        let mut c = DetectConfig::default();
        c.default.still_mirror = how;
        Detector::new(c).unwrap()
    };
    let mut dets = [
        detector(StillMirror::Off),
        detector(StillMirror::Average),
        detector(StillMirror::Either),
    ];
    let mut hits = [0usize; 3];
    let mut seen = 0;
    for i in 0..40u64 {
        let case = photo_case_close(2026, i, false);
        let r = &mut renderers[if case.wide { 0 } else { 1 }];
        let cam = *r.camera();
        let mut buf = vec![0u8; cam.frame_bytes()];
        let truth = r.render(&case.scene, &case.pose, &mut buf).unwrap();
        let (Some(hub), Some(nose), true) = (truth.hub_px, truth.nose_px, truth.turbine_in_view)
        else {
            continue;
        };
        seen += 1;
        let view = bgr_view(&cam, &buf);
        let axis = Segment::new(hub, nose);
        let hit: Vec<bool> = dets
            .iter_mut()
            .map(|det| {
                let d = det
                    .detect_still(&view, &Hints::default())
                    .unwrap()
                    .detection;
                d.detected && axis.segment_distance(d.hub_px) <= 0.03 * cam.height as f64
            })
            .collect();
        for (n, h) in hits.iter_mut().zip(&hit) {
            *n += usize::from(*h);
        }
    }
    assert!(seen >= 30, "only {seen} of 40 close views show the hub");
    let [off, average, either] = hits;
    eprintln!("close photo-like views with the hub: {seen}; hits: photo alone {off}, averaged {average}, either {either}");
    // The current models hit 26, 27 and 33 of the 40 views.
    assert!(
        average >= off && either >= average && either >= off + 4,
        "hits of {seen}: photo alone {off}, averaged {average}, either {either}"
    );
}

/// Frames of the evaluation seed 2026 (not trained on) with the hub in view: `count` cases
/// cycling through the first `classes` distance classes, as (BGR frame, camera, true hub px,
/// truth).
fn unseen_frames(
    count: u64,
    classes: u64,
) -> Vec<(Vec<u8>, Camera, [f64; 2], hubtrack_render::Truth)> {
    use hubtrack_render::dataset::synth_case;
    let mut renderers = [
        Renderer::new(Camera::gopro_hero3()),
        Renderer::new(Camera::usb_narrow()),
    ];
    (0..count)
        .filter_map(|i| {
            let case = synth_case(2026, (i % classes) as usize, i, false);
            let r = &mut renderers[if case.wide { 0 } else { 1 }];
            let cam = *r.camera();
            let mut buf = vec![0u8; cam.frame_bytes()];
            let truth = r.render(&case.scene, &case.pose, &mut buf).unwrap();
            truth
                .hub_px
                .filter(|_| truth.turbine_in_view)
                .map(|hub| (buf, cam, hub, truth))
        })
        .collect()
}

/// The shipped hub heatmap finds the hub on frames of an evaluation seed it was not trained on
/// (the training seeds are 101–104): its most probable cell lies within one cell of the truth
/// in most frames with the hub in view. 97.6 % over 5,700 held-out frames at training, 30 of
/// 30 here; 80 % leaves room for a retrained model.
#[test]
fn the_hub_heatmap_peaks_at_the_hub_on_unseen_frames() {
    use hubtrack_detect::heat::{HubNet, NET_HEIGHT, NET_STRIDE, NET_WIDTH};
    let mut det = Detector::new(DetectConfig::default()).unwrap();
    let mut net = HubNet::new(true).unwrap();
    let (cols, rows) = (
        (NET_WIDTH / NET_STRIDE) as f64,
        (NET_HEIGHT / NET_STRIDE) as f64,
    );
    let (mut frames, mut near) = (0, 0);
    for (buf, cam, hub, _) in unseen_frames(30, 3) {
        let view = bgr_view(&cam, &buf);
        let heat = net.run(&det.network_input(&view).unwrap()).unwrap();
        let (peak, _) = heat.peak().unwrap();
        let (fx, fy) = (hub[0] / cam.width as f64, hub[1] / cam.height as f64);
        frames += 1;
        if ((peak[0] - fx) * cols).abs() <= 1.0 && ((peak[1] - fy) * rows).abs() <= 1.0 {
            near += 1;
        }
    }
    eprintln!("heatmap peak at the hub in {near} of {frames} frames");
    assert!(frames >= 25, "only {frames} frames with the hub in view");
    assert!(
        near * 10 >= frames * 8,
        "heatmap peak at the hub in {near} of {frames} frames"
    );
}

/// The detector's own network kernels (`detect.default.builtin_nets`, where the CPU has AVX2
/// and FMA) and OpenCV's dnn module give the same heatmaps on rendered frames, to float
/// rounding, and the same detections.
#[test]
fn own_kernels_and_the_dnn_module_see_the_same() {
    use hubtrack_detect::heat::HubNet;
    let mut det = Detector::new(DetectConfig::default()).unwrap();
    let mut dnn_config = DetectConfig::default();
    dnn_config.default.builtin_nets = false;
    let mut det_dnn = Detector::new(dnn_config).unwrap();
    let (mut own, mut dnn) = (HubNet::new(true).unwrap(), HubNet::new(false).unwrap());
    let mut frames = 0;
    for (buf, cam, _, _) in unseen_frames(12, 3) {
        let view = bgr_view(&cam, &buf);
        let input = det.network_input(&view).unwrap();
        let (a, b) = (own.run(&input).unwrap(), dnn.run(&input).unwrap());
        let worst =
            a.p.iter()
                .zip(&b.p)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0f32, f32::max);
        assert!(worst < 1e-4, "probabilities differ by {worst}");
        let hints = Hints::default();
        let (d1, d2) = (
            det.detect(&view, &hints).unwrap().detection,
            det_dnn.detect(&view, &hints).unwrap().detection,
        );
        assert_eq!(d1.detected, d2.detected);
        assert!(
            (d1.hub_px[0] - d2.hub_px[0]).abs() < 0.5 && (d1.hub_px[1] - d2.hub_px[1]).abs() < 0.5,
            "{:?} vs {:?}",
            d1.hub_px,
            d2.hub_px
        );
        frames += 1;
    }
    assert!(frames >= 10);
}

/// The shipped hub crop network places the hub from candidates a spinner radius or two off, on
/// frames of an evaluation seed it was not trained on (training seeds 101 and 103, 105 beyond
/// 45 m): started 2–5 % of the image height beside the hub in a random direction, its peak is
/// within 3 % of the height (a hit) in most frames, and nearer the hub than the start in
/// most. Far and medium classes: from 12 m on, where the crop holds the spinner whole.
#[test]
fn the_hub_crop_network_moves_offset_candidates_onto_the_hub() {
    use hubtrack_detect::heat::HubCropNet;
    let mut det = Detector::new(DetectConfig::default()).unwrap();
    let mut net = HubCropNet::new(true).unwrap();
    let (mut frames, mut hits, mut closer) = (0, 0, 0);
    for (i, (buf, cam, hub, _)) in unseen_frames(40, 2).into_iter().enumerate() {
        let i = i as u64;
        let view = bgr_view(&cam, &buf);
        let small = det.working_level(&view).unwrap();
        let scale = cam.height as f64 / opencv::prelude::MatTraitConst::rows(&small) as f64;
        // A start 2–5 % of the height away, in a direction that turns with the frame.
        let (r, a) = (
            (0.02 + 0.03 * ((i * 7 % 10) as f64 / 9.0)) * cam.height as f64,
            i as f64 * 2.4,
        );
        let start = [
            (hub[0] + r * a.cos()) / scale,
            (hub[1] + r * a.sin()) / scale,
        ];
        let peak = net.run(&small, start).unwrap();
        let err = ((peak.hub[0] * scale - hub[0]).hypot(peak.hub[1] * scale - hub[1]))
            / cam.height as f64;
        frames += 1;
        hits += usize::from(err <= 0.03);
        closer += usize::from((err * cam.height as f64) < r);
    }
    eprintln!(
        "hub crop: {hits} of {frames} within 3 % of the height, {closer} nearer than the start"
    );
    assert!(frames >= 30, "only {frames} frames with the hub in view");
    assert!(
        hits * 10 >= frames * 7,
        "hub crop peak within 3 % in {hits} of {frames} frames"
    );
    assert!(
        closer * 10 >= frames * 8,
        "hub crop peak nearer the hub than the start in {closer} of {frames} frames"
    );
}

/// The shipped yaw networks read the relative yaw of views of the thesis turbine from an
/// evaluation seed they were not trained on (training seeds 111 and 113), around the true hub at
/// the true distance: the sign of clearly oblique views (|yaw| ≥ 8°) and a median error of a few
/// degrees. At training, on the held-out seed 112: mean error 2.2–3.9° (the thesis turbine's
/// network) and 2.5–4.9° (the family's) from 3.5 to 46 m.
#[test]
fn the_yaw_network_reads_the_relative_yaw_of_unseen_views() {
    use hubtrack_detect::heat::HubYawNet;
    let mut det = Detector::new(DetectConfig::default()).unwrap();
    // Both shipped models: the one for the thesis turbine (trained on it alone) and the one for
    // every other turbine (trained on it and a family of other proportions).
    for (name, mut net) in [
        ("thesis turbine's", HubYawNet::thesis_turbine(true).unwrap()),
        ("turbine family's", HubYawNet::new(true).unwrap()),
    ] {
        let (mut errors, mut oblique, mut sign_ok) = (Vec::new(), 0, 0);
        // All three classes (6–45 m), within the network's range.
        for (buf, cam, hub, truth) in unseen_frames(90, 3)
            .into_iter()
            .filter(|f| f.3.distance_m <= 45.0)
        {
            let view = bgr_view(&cam, &buf);
            let small = det.working_level(&view).unwrap();
            let scale = cam.height as f64 / opencv::prelude::MatTraitConst::rows(&small) as f64;
            let r = net
                .run(
                    &small,
                    [hub[0] / scale, hub[1] / scale],
                    truth.distance_m,
                    cam.fx / scale,
                )
                .unwrap();
            errors.push((r.yaw_deg - truth.relative_yaw_deg).abs());
            if truth.relative_yaw_deg.abs() >= 8.0 {
                oblique += 1;
                sign_ok += usize::from(r.yaw_deg * truth.relative_yaw_deg > 0.0);
            }
        }
        errors.sort_by(f64::total_cmp);
        let median = errors[errors.len() / 2];
        eprintln!("{name} yaw network: {} views, median error {median:.1} deg, sign right in {sign_ok} of {oblique} oblique", errors.len());
        assert!(
            errors.len() >= 60,
            "only {} views within 45 m",
            errors.len()
        );
        assert!(median <= 5.0, "{name}: median yaw error {median:.1} deg");
        assert!(
            sign_ok * 10 >= oblique * 9,
            "{name}: sign right in {sign_ok} of {oblique} views beyond 8 deg"
        );
    }
}

/// The close-range yaw model (`detect.default.hub_yaw_close`) reads the hover views where the
/// approach ends (4–8 m, evaluation seed 2026, never trained on) within a few degrees, and
/// better than the whole-range model on the same views: the final yaw is judged there
/// (held out at training: mean error 3.3° at 3.5–8 m against 4.0°).
#[test]
fn the_close_range_yaw_network_reads_the_hover_views() {
    use hubtrack_detect::heat::HubYawNet;
    use hubtrack_render::dataset::{synth_case_between, CLASSES, CLOSE_IN_M};
    let mut det = Detector::new(DetectConfig::default()).unwrap();
    let (mut close, mut whole) = (
        HubYawNet::close_range(true).unwrap(),
        HubYawNet::thesis_turbine(true).unwrap(),
    );
    let mut renderers = [
        Renderer::new(Camera::gopro_hero3()),
        Renderer::new(Camera::usb_narrow()),
    ];
    let (mut close_err, mut whole_err) = (Vec::new(), Vec::new());
    for i in 0..80 {
        let case = synth_case_between(
            2026,
            CLASSES.len() + 1,
            i,
            false,
            "close_in",
            CLOSE_IN_M.0,
            CLOSE_IN_M.1,
        );
        let r = &mut renderers[if case.wide { 0 } else { 1 }];
        let cam = *r.camera();
        let mut buf = vec![0u8; cam.frame_bytes()];
        let truth = r.render(&case.scene, &case.pose, &mut buf).unwrap();
        let Some(hub) = truth.hub_px.filter(|_| truth.turbine_in_view) else {
            continue;
        };
        let view = bgr_view(&cam, &buf);
        let small = det.working_level(&view).unwrap();
        let scale = cam.height as f64 / opencv::prelude::MatTraitConst::rows(&small) as f64;
        let at = [hub[0] / scale, hub[1] / scale];
        close_err.push(
            (close
                .run(&small, at, truth.distance_m, cam.fx / scale)
                .unwrap()
                .yaw_deg
                - truth.relative_yaw_deg)
                .abs(),
        );
        whole_err.push(
            (whole
                .run(&small, at, truth.distance_m, cam.fx / scale)
                .unwrap()
                .yaw_deg
                - truth.relative_yaw_deg)
                .abs(),
        );
    }
    let mean = |e: &[f64]| e.iter().sum::<f64>() / e.len() as f64;
    let (c, w) = (mean(&close_err), mean(&whole_err));
    eprintln!("hover views: {}, mean yaw error close-range model {c:.2} deg, whole-range model {w:.2} deg", close_err.len());
    assert!(
        close_err.len() >= 50,
        "only {} hover views with the hub in view",
        close_err.len()
    );
    assert!(c <= 4.5, "close-range model: mean error {c:.2} deg");
    assert!(
        c < w,
        "close-range model {c:.2} deg, no better than the whole-range model's {w:.2} deg"
    );
}

/// The detection carries the yaw network's reading when it has a distance in the network's
/// range (the tracker's hint), not beyond it nor with `hub_yaw` off; its sign is the truth's.
#[test]
fn the_detection_carries_the_yaw_network_reading_within_its_range() {
    let (mut r, mut buf) = gopro_renderer();
    let pose = CameraPose::looking_at_hub(15.0, -4.0, 0.0);
    let hints = |d: f64| Hints {
        roll_rad: Some(0.0),
        hub_distance_m: Some(d),
        ..Hints::default()
    };
    let (d, truth) = render_and_detect(
        &mut r,
        &mut buf,
        &sunlit_sea(),
        &pose,
        DetectConfig::default(),
        &hints(15.5),
    );
    assert!(d.detected && d.yaw_net_valid, "{d:?}");
    assert!(
        truth.relative_yaw_deg < -10.0 && d.yaw_net_deg < 0.0,
        "network {:+.1} for {:+.1}",
        d.yaw_net_deg,
        truth.relative_yaw_deg
    );
    assert!(d.yaw_net_std_deg > 0.0 && d.yaw_net_std_deg < 15.0);
    let (far, _) = render_and_detect(
        &mut r,
        &mut buf,
        &sunlit_sea(),
        &pose,
        DetectConfig::default(),
        &hints(60.0),
    );
    assert!(
        far.detected && !far.yaw_net_valid,
        "read beyond hub_yaw_max_distance_m"
    );
    let mut off = DetectConfig::default();
    off.default.hub_yaw = false;
    let (none, _) = render_and_detect(&mut r, &mut buf, &sunlit_sea(), &pose, off, &hints(15.5));
    assert!(
        none.detected && !none.yaw_net_valid,
        "read with hub_yaw off"
    );
}

/// The close-range spinner search restricted to a confident heatmap peak
/// (`detect.default.close_spinner_heat_min`) still finds the hub in hover views (4–8 m, where
/// the blades run out of the frame and the search matters most), about as often as the search
/// over the whole image.
#[test]
fn the_close_search_near_the_heatmap_peak_finds_hover_views() {
    use hubtrack_render::dataset::{synth_case_between, CLASSES, CLOSE_IN_M};
    let mut whole_config = DetectConfig::default();
    whole_config.default.close_spinner_heat_min = 0.0;
    let mut whole = Detector::new(whole_config).unwrap();
    let mut focused = Detector::new(DetectConfig::default()).unwrap();
    assert!(focused.config().default.close_spinner_heat_min > 0.0);
    let mut r = Renderer::new(Camera::gopro_hero3());
    let cam = *r.camera();
    let mut buf = vec![0u8; cam.frame_bytes()];
    let (mut frames, mut hits_whole, mut hits_focused) = (0, 0, 0);
    for i in 0..30 {
        let case = synth_case_between(
            77,
            CLASSES.len() + 1,
            i,
            false,
            "close_in",
            CLOSE_IN_M.0,
            CLOSE_IN_M.1,
        );
        let truth = r.render(&case.scene, &case.pose, &mut buf).unwrap();
        let Some(hub) = truth.hub_px.filter(|_| truth.turbine_in_view) else {
            continue;
        };
        let view = bgr_view(&cam, &buf);
        let hints = Hints {
            roll_rad: Some(case.pose.roll_deg.to_radians()),
            ..Hints::default()
        };
        let hit = |d: Detection| {
            d.detected
                && (d.hub_px[0] - hub[0]).hypot(d.hub_px[1] - hub[1]) <= 0.03 * cam.height as f64
        };
        frames += 1;
        hits_whole += usize::from(hit(whole.detect(&view, &hints).unwrap().detection));
        hits_focused += usize::from(hit(focused.detect(&view, &hints).unwrap().detection));
    }
    eprintln!("hover views: {frames}, hub found by the whole-image search in {hits_whole}, near the heatmap peak in {hits_focused}");
    assert!(
        frames >= 20,
        "only {frames} hover views with the hub in view"
    );
    assert!(
        hits_whole * 10 >= frames * 6,
        "whole-image search: {hits_whole} of {frames}"
    );
    assert!(
        hits_focused + 2 >= hits_whole,
        "near the heatmap peak: {hits_focused} of {frames}, whole image {hits_whole}"
    );
}
