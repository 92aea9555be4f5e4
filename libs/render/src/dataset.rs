//! Evaluation sets of synthetic frames with exact truth: scenes and poses drawn deterministically
//! from a seed, by distance class, with the conditions the detector must survive (relative yaw,
//! pointing error, roll, horizon near the hub, shadows, propellers, skies, both lenses, negatives).
//! One generator for `hubtrack eval`, the detector benchmark and the sequence evaluation.

use crate::{Camera, CameraPose, Distractor, Scene};

/// Distance classes of the synthetic set, metres: far ≥ 25, medium 12–25, close < 12.
pub const CLASSES: [(&str, f64, f64); 3] = [
    ("far", 25.0, 45.0),
    ("medium", 12.0, 25.0),
    ("close", 6.0, 12.0),
];
/// Largest relative yaw in the synthetic set, degrees.
pub const MAX_REL_YAW_DEG: f64 = 30.0;
/// Largest camera pointing error (hub away from the image centre), degrees.
pub const MAX_POINTING_DEG: f64 = 12.0;
/// Largest camera roll, degrees.
pub const MAX_ROLL_DEG: f64 = 10.0;
/// Camera height relative to the hub, metres.
pub const HEIGHT_RANGE_M: (f64, f64) = (-12.0, 6.0);
/// Camera heights within this of the hub height put the horizon near the hub, metres.
pub const HORIZON_NEAR_M: f64 = 3.0;
/// Relative yaw beyond which a view counts as oblique, degrees.
pub const OBLIQUE_DEG: f64 = 15.0;

/// A small deterministic generator (SplitMix64) for the synthetic set.
pub struct Rng(pub u64);

impl Rng {
    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// One synthetic evaluation case: scene, pose, lens and the roll the vehicle would report.
pub struct SynthCase {
    /// Scene.
    pub scene: Scene,
    /// Camera pose.
    pub pose: CameraPose,
    /// GoPro (3 of 4) or USB camera.
    pub wide: bool,
    /// Categories the case counts in.
    pub categories: Vec<String>,
}

/// Distances of the far views that only the learned heatmap's training set holds (`hubtrack
/// dataset --beyond`), metres: photos show turbines well beyond the approach's 45 m.
pub const BEYOND_M: (f64, f64) = (45.0, 250.0);

/// Distances of the hover views that only the learned yaw network's training set holds
/// (`hubtrack dataset --close-in`), metres: the approach ends 5 m from the hub.
pub const CLOSE_IN_M: (f64, f64) = (4.0, 8.0);

/// The `index`-th case of a distance class (deterministic in `seed`).
pub fn synth_case(seed: u64, class: usize, index: u64, negative: bool) -> SynthCase {
    let (name, lo, hi) = CLASSES[class];
    synth_case_between(seed, class, index, negative, name, lo, hi)
}

/// As [`synth_case`], at a distance drawn from `[lo, hi)` metres, counted under the distance
/// category `name`.
pub fn synth_case_between(
    seed: u64,
    class: usize,
    index: u64,
    negative: bool,
    name: &str,
    lo: f64,
    hi: f64,
) -> SynthCase {
    let mut r = Rng(seed ^ (class as u64) << 40 ^ index.wrapping_mul(0x9E37));
    let mut scene = Scene::random(r.next_u64());
    scene.turbine_present = !negative;
    if negative && scene.distractor == Distractor::None {
        scene.distractor = Distractor::Mast;
    }
    let distance = r.range(lo, hi);
    let rel_yaw = r.range(-MAX_REL_YAW_DEG, MAX_REL_YAW_DEG);
    let nacelle = r.range(-0.5, 0.5) * rel_yaw;
    let lateral = distance * (rel_yaw - nacelle).to_radians().tan();
    scene.nacelle_yaw_deg = nacelle;
    let height = r.range(HEIGHT_RANGE_M.0, HEIGHT_RANGE_M.1);
    let mut pose = CameraPose::looking_at_hub(distance, lateral, height);
    pose.yaw_deg += r.range(-MAX_POINTING_DEG, MAX_POINTING_DEG);
    pose.pitch_deg += r.range(-0.6, 0.6) * MAX_POINTING_DEG;
    pose.roll_deg = r.range(-MAX_ROLL_DEG, MAX_ROLL_DEG);
    let wide = !r.next_u64().is_multiple_of(4);
    let mut categories = vec!["all".to_string(), format!("distance:{name}")];
    categories.push(format!("sky:{:?}", scene.sky).to_lowercase());
    categories.push(if rel_yaw.abs() > OBLIQUE_DEG {
        "view:oblique".into()
    } else {
        "view:front".into()
    });
    if height.abs() < HORIZON_NEAR_M {
        categories.push("effects:horizon_near_hub".into());
    }
    if scene.propellers_in_view {
        categories.push("effects:propellers".into());
    }
    if scene.nacelle_shadow {
        categories.push("effects:nacelle_shadow".into());
    }
    categories.push(if wide {
        "camera:gopro".into()
    } else {
        "camera:usb".into()
    });
    if negative {
        categories = vec!["negatives".into()];
    }
    SynthCase {
        scene,
        pose,
        wide,
        categories,
    }
}

/// Distances of the photo-like views ([`photo_case`]), metres (drawn log-uniformly).
pub const PHOTO_DISTANCE_M: (f64, f64) = (12.0, 250.0);
/// Distances of the close photo-like views ([`photo_case_close`]), metres (drawn
/// log-uniformly): inspection photos taken next to the hub, the spinner filling a fifth of the
/// frame or more, most blades cut by the border.
pub const PHOTO_CLOSE_DISTANCE_M: (f64, f64) = (5.0, 12.0);
/// Elevation of the photo-like camera above the hub as seen from it, degrees: drone photos look
/// at turbines from above as often as from below.
pub const PHOTO_ELEVATION_DEG: (f64, f64) = (-20.0, 50.0);
/// Largest relative yaw of the photo-like views, degrees (beyond it the hub hides behind the
/// rotor's edge).
pub const PHOTO_MAX_REL_YAW_DEG: f64 = 70.0;
/// Largest pointing error of the photo-like views as a fraction of the lens's half field of view
/// (horizontal, vertical): photographers frame the turbine anywhere, even cut by the border.
pub const PHOTO_POINTING_FRAC: (f64, f64) = (0.75, 0.6);
/// Share of the photo-like land scenes with shrubland ground.
pub const PHOTO_SHRUBLAND_SHARE: f64 = 0.6;
/// Share of the photo-like scenes with wind-farm neighbours, and their largest number.
pub const PHOTO_NEIGHBOURS: (f64, u8) = (0.6, 5);
/// Photo-like views from this far or farther count as `photo-like:beyond` (beyond the approach's
/// far class), the others as `photo-like:approach`, metres.
pub const PHOTO_BEYOND_M: f64 = 45.0;
/// Lowest camera height above the ground in the photo-like views, metres.
pub const PHOTO_MIN_CAMERA_HEIGHT_M: f64 = 3.0;

/// Horizontal field of view of the photo-like views' photo camera (a 1920x1080 pinhole, as a
/// drone's photo camera), degrees.
pub const PHOTO_LENS_HFOV_DEG: f64 = 75.0;

/// The lenses of the photo-like views: `[0]` the GoPro (`SynthCase::wide`, a third of the
/// views), `[1]` a drone's photo camera.
pub fn photo_lenses() -> [Camera; 2] {
    [
        Camera::gopro_hero3(),
        Camera::pinhole(1920, 1080, PHOTO_LENS_HFOV_DEG),
    ]
}

/// Horizontal and vertical half fields of view of a camera, degrees (pinhole approximation).
fn half_fov_deg(cam: &Camera) -> (f64, f64) {
    let half = |pixels: u32, f: f64| (pixels as f64 / 2.0 / f).atan().to_degrees();
    (half(cam.width, cam.fx), half(cam.height, cam.fy))
}

/// The `index`-th photo-like case (deterministic in `seed`): a turbine as drone photos show it
/// and approaches do not (`hubtrack dataset --photo-like`, `hubtrack eval --photo-like`). Views
/// from 12–250 m, from 20° below to 50° above the hub, relative yaw up to ±70°, the hub anywhere
/// in the frame, shrubland ground and wind-farm neighbours, through one of [`photo_lenses`].
pub fn photo_case(seed: u64, index: u64, negative: bool) -> SynthCase {
    photo_case_within(seed, index, negative, PHOTO_DISTANCE_M)
}

/// The `index`-th close photo-like case (deterministic in `seed`, a stream apart from
/// [`photo_case`]'s): the same views from 5–12 m ([`PHOTO_CLOSE_DISTANCE_M`]), category
/// `photo-like:close` (`hubtrack dataset --photo-close`, `hubtrack eval --photo-close`).
pub fn photo_case_close(seed: u64, index: u64, negative: bool) -> SynthCase {
    photo_case_within(
        seed ^ 0xC105_E000_0000_0000,
        index,
        negative,
        PHOTO_CLOSE_DISTANCE_M,
    )
}

/// A photo-like case whose ground range lies within `range` (metres).
fn photo_case_within(seed: u64, index: u64, negative: bool, range: (f64, f64)) -> SynthCase {
    let mut r = Rng(seed ^ 0x9407_0000_0000 ^ index.wrapping_mul(0x9E37_79B9));
    let wide = r.next_u64().is_multiple_of(3);
    let half_fov_deg = half_fov_deg(&photo_lenses()[if wide { 0 } else { 1 }]);
    let mut scene = Scene::random(r.next_u64());
    scene.turbine_present = !negative;
    if negative && scene.distractor == Distractor::None {
        scene.distractor = Distractor::Mast;
    }
    scene.shrubland =
        scene.ground != crate::Ground::Sea && r.range(0.0, 1.0) < PHOTO_SHRUBLAND_SHARE;
    if !negative && r.range(0.0, 1.0) < PHOTO_NEIGHBOURS.0 {
        scene.neighbour_turbines = 1 + (r.next_u64() % PHOTO_NEIGHBOURS.1 as u64) as u8;
    }
    let ground_range = (r.range(range.0.ln(), range.1.ln())).exp();
    // The camera's bearing from the hub (0 = in front of a rotor facing +X) and the nacelle's
    // yaw: the relative yaw is their sum.
    let rel_yaw = r.range(-PHOTO_MAX_REL_YAW_DEG, PHOTO_MAX_REL_YAW_DEG);
    let nacelle = r.range(-0.5, 0.5) * rel_yaw;
    scene.nacelle_yaw_deg = nacelle;
    let bearing = (rel_yaw - nacelle).to_radians();
    let (distance, lateral) = (ground_range * bearing.cos(), ground_range * bearing.sin());
    let elevation = r.range(PHOTO_ELEVATION_DEG.0, PHOTO_ELEVATION_DEG.1);
    let height = (ground_range * elevation.to_radians().tan())
        .max(PHOTO_MIN_CAMERA_HEIGHT_M - scene.hub_height_m);
    let mut pose = CameraPose::looking_at_hub(distance, lateral, height);
    pose.yaw_deg += r.range(-1.0, 1.0) * PHOTO_POINTING_FRAC.0 * half_fov_deg.0;
    pose.pitch_deg += r.range(-1.0, 1.0) * PHOTO_POINTING_FRAC.1 * half_fov_deg.1;
    pose.roll_deg = r.range(-MAX_ROLL_DEG, MAX_ROLL_DEG);
    let class = if ground_range >= PHOTO_BEYOND_M {
        "beyond"
    } else if ground_range < PHOTO_DISTANCE_M.0 {
        "close"
    } else {
        "approach"
    };
    let categories = if negative {
        vec!["negatives".into()]
    } else {
        vec!["photo-like".into(), format!("photo-like:{class}")]
    };
    SynthCase {
        scene,
        pose,
        wide,
        categories,
    }
}

/// Frames per second of the evaluation flights.
pub const FLIGHT_FPS: f64 = 15.0;
/// Approach of an evaluation flight: start and end distance to the hub, metres.
pub const FLIGHT_DISTANCE_M: (f64, f64) = (30.0, 6.0);
/// Largest lateral drift, metres.
pub const FLIGHT_MAX_DRIFT_M: f64 = 5.0;
/// Camera height relative to the hub at the start (climbs to 0), metres.
pub const FLIGHT_START_HEIGHT_M: (f64, f64) = (-10.0, -2.0);
/// Amplitude of a yaw turn of the vehicle (the hub sweeps across the image), degrees.
pub const FLIGHT_TURN_DEG: f64 = 15.0;
/// Roll jitter amplitude, degrees.
pub const FLIGHT_ROLL_DEG: f64 = 5.0;
/// Dropouts per flight (frames whose detection is suppressed, as by an occlusion), and their length range.
pub const FLIGHT_DROPOUTS: usize = 2;
/// Length range of a dropout, frames.
pub const FLIGHT_DROPOUT_FRAMES: (u64, u64) = (5, 15);

/// One frame of an evaluation flight.
#[derive(Debug, Clone)]
pub struct FlightFrame {
    /// Scene (fixed per flight except the noise frame counter).
    pub scene: Scene,
    /// Camera pose.
    pub pose: CameraPose,
    /// Vehicle heading change since the flight start, radians (camera yaw in the world), for the
    /// tracker's ego-motion input.
    pub heading_rad: f64,
    /// The detection of this frame is suppressed (simulated occlusion / dropout).
    pub dropout: bool,
}

/// A deterministic evaluation flight of `frames` frames at [`FLIGHT_FPS`]: approach from 30 to 6 m
/// with lateral drift, a climb to hub height, a yaw turn, roll jitter and dropouts.
pub fn flight(seed: u64, frames: u64) -> Vec<FlightFrame> {
    use std::f64::consts::TAU;
    let mut r = Rng(seed.wrapping_mul(0x2545_F491_4F6C_DD1D) ^ 0xF1_1647);
    let mut scene = Scene::random(r.next_u64());
    scene.turbine_present = true;
    scene.distractor = Distractor::None;
    let nacelle = r.range(-20.0, 20.0);
    scene.nacelle_yaw_deg = nacelle;
    let drift = r.range(-FLIGHT_DRIFT_FACTOR, FLIGHT_DRIFT_FACTOR) * FLIGHT_MAX_DRIFT_M;
    let drift_period = r.range(0.6, 1.4);
    let h0 = r.range(FLIGHT_START_HEIGHT_M.0, FLIGHT_START_HEIGHT_M.1);
    let turn_at = r.range(0.3, 0.6);
    let turn_sign = if r.next_u64().is_multiple_of(2) {
        1.0
    } else {
        -1.0
    };
    let roll_phase = r.range(0.0, TAU);
    let mut drop_ranges = Vec::new();
    for _ in 0..FLIGHT_DROPOUTS {
        let start = (r.range(0.15, 0.9) * frames as f64) as u64;
        let len = FLIGHT_DROPOUT_FRAMES.0
            + r.next_u64() % (FLIGHT_DROPOUT_FRAMES.1 - FLIGHT_DROPOUT_FRAMES.0 + 1);
        drop_ranges.push(start..start + len);
    }
    let n = frames.max(2) as f64;
    (0..frames)
        .map(|i| {
            let u = i as f64 / (n - 1.0);
            let t = i as f64 / FLIGHT_FPS;
            let distance = FLIGHT_DISTANCE_M.0 + (FLIGHT_DISTANCE_M.1 - FLIGHT_DISTANCE_M.0) * u;
            // Drift shrinks with distance so the turbine stays in view when close.
            let lateral = drift * (distance / FLIGHT_DISTANCE_M.0) * (TAU * u / drift_period).sin();
            let height = h0 * (1.0 - u);
            let mut pose = CameraPose::looking_at_hub(distance, lateral, height);
            // A yaw turn: the vehicle turns away and back (raised cosine, 2 s), plus small wander.
            let turn_u = ((t - turn_at * n / FLIGHT_FPS) / 2.0).clamp(0.0, 1.0);
            let turn = turn_sign * FLIGHT_TURN_DEG * 0.5 * (1.0 - (TAU * turn_u).cos());
            pose.yaw_deg += turn + 1.5 * (TAU * t / 3.1).sin();
            pose.pitch_deg += 1.0 * (TAU * t / 2.3).sin();
            pose.roll_deg = FLIGHT_ROLL_DEG * (TAU * t / 1.7 + roll_phase).sin();
            let mut s = scene.clone();
            s.frame = i;
            // The heading that keeps the hub centred changes with the lateral offset: camera to the
            // viewer's right must turn left to see the hub.
            let heading_rad = (-(lateral.atan2(distance)).to_degrees() + pose.yaw_deg).to_radians();
            FlightFrame {
                scene: s,
                pose,
                heading_rad,
                dropout: drop_ranges.iter().any(|r| r.contains(&i)),
            }
        })
        .collect()
}

/// Fraction of [`FLIGHT_MAX_DRIFT_M`] a flight's drift amplitude is drawn from (±).
const FLIGHT_DRIFT_FACTOR: f64 = 1.0;

/// Cameras no model or ranker of the project was trained or tuned on (those saw the GoPro and the
/// narrow USB camera only), for the cross-domain evaluation (`hubtrack eval --cross-domain`):
/// other sizes, fields of view and lens models, each with the calibration detect is given.
pub fn held_out_cameras() -> Vec<(&'static str, Camera)> {
    use crate::camera::Distortion;
    vec![
        ("pinhole 640x480 90deg", Camera::pinhole(640, 480, 90.0)),
        ("pinhole 1280x720 60deg", Camera::pinhole(1280, 720, 60.0)),
        (
            "plumb_bob 2704x1520 100deg",
            Camera::centred(
                2704,
                1520,
                1300.0,
                Distortion::PlumbBob {
                    k1: -0.22,
                    k2: 0.05,
                    p1: 0.0008,
                    p2: -0.0005,
                    k3: -0.004,
                },
            ),
        ),
        (
            "equidistant 1920x1080 fisheye",
            Camera::centred(
                1920,
                1080,
                700.0,
                Distortion::Equidistant {
                    k1: -0.03,
                    k2: 0.008,
                    k3: -0.002,
                    k4: 0.0003,
                },
            ),
        ),
    ]
}

/// Seed mix of the held-out turbine draws (independent of the scene's other draws).
const HELD_OUT_TURBINE_SEED_MIX: u64 = 0x7E1D_0F15_C0DE_0047;
/// Tower top diameters of the held-out turbine family, metres (real fleets: 1.8–3.5).
pub const HELD_OUT_TOWER_TOP_M: (f64, f64) = (1.8, 3.5);
/// Tower base over top diameter of the held-out family (taper).
pub const HELD_OUT_TAPER: (f64, f64) = (1.4, 2.2);
/// Blade lengths of the held-out family, metres (rotors of 25–65 m radius).
pub const HELD_OUT_BLADE_M: (f64, f64) = (23.0, 63.0);
/// Spinner diameters of the held-out family, metres (the training family's is 3.2).
pub const HELD_OUT_SPINNER_M: (f64, f64) = (2.4, 4.6);
/// Hub overhangs of the held-out family, metres (the training family's is 4.2).
pub const HELD_OUT_OVERHANG_M: (f64, f64) = (3.0, 7.0);
/// Nacelle sizes of the held-out family over the training family's one nacelle.
pub const HELD_OUT_NACELLE_SCALE: (f64, f64) = (0.8, 1.5);

const HELD_OUT_SCENE_SEED_MIX: u64 = 0x5CE7_E0FF_C0DE_0047;
/// Share of the held-out scenes with a chimney standing near the turbine (every scene without
/// a turbine has one).
pub const HELD_OUT_CHIMNEY_SHARE: f64 = 0.5;
/// Motion blur of the held-out scenes, share of the frame's width (0.1–0.6 %: 2–12 px at
/// 1920 px, a 90° lens turning at 9–54°/s through a 1/100 s exposure).
pub const HELD_OUT_MOTION_BLUR_FRAC: (f64, f64) = (0.001, 0.006);

/// Gives `scene` what the training scenes never show: an industrial chimney (a smooth tapered
/// column as tall as a tower, in every scene without a turbine and in
/// `HELD_OUT_CHIMNEY_SHARE` of the others, instead of the mast or power line the scene drew)
/// and horizontal motion blur. Detector and rankers never saw either.
pub fn held_out_scene(scene: &mut Scene, seed: u64) {
    let mut r = Rng(seed ^ HELD_OUT_SCENE_SEED_MIX);
    if !scene.turbine_present || r.range(0.0, 1.0) < HELD_OUT_CHIMNEY_SHARE {
        scene.distractor = Distractor::Chimney;
    }
    scene.motion_blur_frac =
        r.range(HELD_OUT_MOTION_BLUR_FRAC.0, HELD_OUT_MOTION_BLUR_FRAC.1) as f32;
}

/// Gives `scene` turbine proportions outside the training family (which varies the tower by
/// ±5 % around 2.2 m and keeps 33.5 m blades, one spinner, overhang and nacelle): tower top,
/// taper, blade length, spinner, overhang and nacelle size drawn over what real fleets have.
/// The hub height grows with the blades so the rotor clears the ground.
pub fn held_out_turbine(scene: &mut Scene, seed: u64) {
    let mut r = Rng(seed ^ HELD_OUT_TURBINE_SEED_MIX);
    let top = r.range(HELD_OUT_TOWER_TOP_M.0, HELD_OUT_TOWER_TOP_M.1);
    scene.tower_top_diameter_m = top;
    scene.tower_base_diameter_m = top * r.range(HELD_OUT_TAPER.0, HELD_OUT_TAPER.1);
    scene.blade_length_m = r.range(HELD_OUT_BLADE_M.0, HELD_OUT_BLADE_M.1);
    scene.hub_height_m = scene.hub_height_m.max(scene.blade_length_m + 25.0);
    scene.spinner_diameter_m = r.range(HELD_OUT_SPINNER_M.0, HELD_OUT_SPINNER_M.1);
    scene.nacelle_scale = r.range(HELD_OUT_NACELLE_SCALE.0, HELD_OUT_NACELLE_SCALE.1);
    // The blade-root plane stays clear of the nacelle's front (its default 1.2 m, scaled).
    scene.hub_overhang_m = r
        .range(HELD_OUT_OVERHANG_M.0, HELD_OUT_OVERHANG_M.1)
        .max(1.2 * scene.nacelle_scale + scene.spinner_diameter_m / 4.0);
}
