//! Seeded approach scenarios, and the vehicle's geometry relative to the turbine: the camera pose
//! for the renderer and the ground truth of distance, relative yaw and offsets.
//!
//! # Frames
//! * **Local NED** (the autopilot's frame): origin on the ground (z = 0) directly below the
//!   vehicle's start position; x north, y east, z down. The ground is flat at z = 0, so the
//!   height above ground is `−z`.
//! * **Render world** (see `hubtrack_render`): origin at the tower base, X the rotor axis out of
//!   the rotor face, Y the viewer's right when facing the rotor, Z up. The scene keeps
//!   `nacelle_yaw_deg = 0` and the turbine is placed in NED by rotating about the vertical so that
//!   world X points along the NED heading `rotor_axis_heading_rad`:
//!   `X = (cos h, sin h, 0)`, `Y = (sin h, −cos h, 0)`, `Z = (0, 0, −1)` in NED.
//! * **Body** (FRD): x nose, y right, z down; ZYX Euler roll/pitch/yaw as MAVLink ATTITUDE.
//! * **Camera**: at the vehicle's position (no lever arm), optical axis along body x tilted up by
//!   `mount_pitch_deg` about body y; image x along body y (right).

use serde::{Deserialize, Serialize};

use hubtrack_render::{Camera, CameraPose, Distractor, NacelleSize, Scene};
use hubtrack_types::setup::TurbineSetup;

use crate::math::{body_to_ned, dot, mat_vec, norm, sub, wrap_deg, wrap_pi};
use crate::params::{CameraConfig, CameraModel, SimConfig, WindConfig};
use crate::rng::Rng;
use crate::vehicle::{Multicopter, VehicleStart};
use crate::wind::Wind;

/// Random stream of the scenario layout within a seed.
const STREAM_LAYOUT: u64 = 0x5CE4_A210;
/// Random stream of the scene options switched on in the config.
const STREAM_SCENE_OPTIONS: u64 = 0x0971_0175;
/// Seed mix of the wind (so the wind is not correlated with the layout).
const WIND_SEED_MIX: u64 = 0xA076_1D64_78BD_642F;

/// One seeded approach: the turbine scene, its placement in the local NED frame, the vehicle's
/// start and the wind.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Scenario {
    /// The seed everything here was drawn from.
    pub seed: u64,
    /// The renderer scene (turbine dimensions, sky, ground, sun, effects; `nacelle_yaw_deg = 0`,
    /// `frame = 0`: use [`Scenario::scene_for_frame`] for per-frame sensor noise).
    pub scene: Scene,
    /// The hub (rotor centre) in the local NED frame, m.
    pub hub_ned: [f64; 3],
    /// NED heading of the rotor axis (world +X, out of the rotor face), rad, [0, 2π).
    pub rotor_axis_heading_rad: f64,
    /// Where the vehicle starts (hovering).
    pub start: VehicleStart,
    /// Start offset along the rotor axis in front of the hub (= render pose `distance_m`), m.
    pub start_distance_m: f64,
    /// Start sideways offset (+ = viewer's right, = render pose `lateral_m`), m.
    pub start_lateral_m: f64,
    /// Start height of the camera minus the hub height, m.
    pub start_height_m: f64,
    /// Start heading minus the heading that faces the rotor (looking along −X), degrees.
    pub start_heading_offset_deg: f64,
    /// Seed of the wind process ([`Scenario::wind`]).
    pub wind_seed: u64,
    /// Mean wind of this scenario (air velocity, NED, m/s), for logs.
    pub wind_mean_ned: [f64; 3],
}

impl Scenario {
    /// The scenario of `seed` under `cfg` (its `seed` field is not used; see
    /// [`Scenario::from_config`]). Pure: the same seed and config give the same scenario.
    pub fn from_seed(seed: u64, cfg: &SimConfig) -> Scenario {
        let sc = &cfg.scenario;
        let mut r = Rng::new(seed, STREAM_LAYOUT);
        let heading = match sc.rotor_axis_heading_deg {
            Some(h) => h.to_radians().rem_euclid(std::f64::consts::TAU),
            None => r.range(0.0, std::f64::consts::TAU),
        };
        let distance = r.within(sc.distance_m);
        let lateral = r.within(sc.lateral_m);
        let height = r.within(sc.height_m);
        let heading_offset = r.within(sc.heading_offset_deg);

        let scene = scene_for(seed, cfg);

        // Origin on the ground below the start; the hub is found from the start offsets.
        let start_ned = [0.0, 0.0, -(scene.hub_height_m + height)];
        let (axis, right) = axes(heading);
        let hub_ned = [
            start_ned[0] - distance * axis[0] - lateral * right[0],
            start_ned[1] - distance * axis[1] - lateral * right[1],
            -scene.hub_height_m,
        ];
        // "Facing the rotor" = looking along −X.
        let yaw = wrap_pi(heading + std::f64::consts::PI + heading_offset.to_radians());
        let wind_seed = seed ^ WIND_SEED_MIX;
        let wind_mean_ned = Wind::new(wind_seed, &cfg.wind).mean_ned();
        Scenario {
            seed,
            scene,
            hub_ned,
            rotor_axis_heading_rad: heading,
            start: VehicleStart {
                position_ned: start_ned,
                velocity_ned: [0.0; 3],
                yaw_rad: yaw,
            },
            start_distance_m: distance,
            start_lateral_m: lateral,
            start_height_m: height,
            start_heading_offset_deg: heading_offset,
            wind_seed,
            wind_mean_ned,
        }
    }

    /// This scenario with the turbine of a profile (`[turbine]`) instead of the seed's own:
    /// tower, rotor, hub height, overhang and spinner as [`show_turbine`] draws them. The start
    /// keeps its offsets from the hub.
    pub fn with_turbine(mut self, turbine: &TurbineSetup) -> Scenario {
        let climb = turbine.hub_height_m - self.scene.hub_height_m;
        show_turbine(&mut self.scene, turbine);
        self.hub_ned[2] -= climb;
        self.start.position_ned[2] -= climb;
        self
    }

    /// The scenario of `cfg.seed`.
    pub fn from_config(cfg: &SimConfig) -> Scenario {
        Scenario::from_seed(cfg.seed, cfg)
    }

    /// A fresh wind process of this scenario (same sequence every time).
    pub fn wind(&self, cfg: &WindConfig) -> Wind {
        Wind::new(self.wind_seed, cfg)
    }

    /// The scene for camera frame `frame` (only the sensor noise and propeller phase change).
    pub fn scene_for_frame(&self, frame: u64) -> Scene {
        let mut s = self.scene.clone();
        s.frame = frame;
        s
    }

    /// Unit rotor axis (world +X, out of the rotor face) in NED.
    pub fn rotor_axis_ned(&self) -> [f64; 3] {
        axes(self.rotor_axis_heading_rad).0
    }

    /// Unit world +Y (the viewer's right when facing the rotor) in NED.
    pub fn viewer_right_ned(&self) -> [f64; 3] {
        axes(self.rotor_axis_heading_rad).1
    }

    /// NED heading that looks straight at the rotor face (along world −X), rad, (−π, π].
    pub fn facing_rotor_heading_rad(&self) -> f64 {
        wrap_pi(self.rotor_axis_heading_rad + std::f64::consts::PI)
    }

    /// A render-world point (m) in the local NED frame.
    pub fn world_to_ned(&self, p: [f64; 3]) -> [f64; 3] {
        let (x, y) = axes(self.rotor_axis_heading_rad);
        let d = sub(p, self.scene.hub_world());
        [
            self.hub_ned[0] + d[0] * x[0] + d[1] * y[0],
            self.hub_ned[1] + d[0] * x[1] + d[1] * y[1],
            self.hub_ned[2] - d[2],
        ]
    }

    /// A local NED point (m) in the render world.
    pub fn ned_to_world(&self, p: [f64; 3]) -> [f64; 3] {
        let (x, y) = axes(self.rotor_axis_heading_rad);
        let d = sub(p, self.hub_ned);
        let h = self.scene.hub_world();
        [h[0] + dot(d, x), h[1] + dot(d, y), h[2] - d[2]]
    }

    /// The tower base (world origin) in the local NED frame.
    pub fn tower_base_ned(&self) -> [f64; 3] {
        self.world_to_ned([0.0; 3])
    }
}

/// World X and Y axes in NED for rotor-axis heading `h`.
fn axes(h: f64) -> ([f64; 3], [f64; 3]) {
    let (s, c) = h.sin_cos();
    ([c, s, 0.0], [s, -c, 0.0])
}

/// Gives a rendered scene the dimensions of a turbine profile: tower diameters, rotor, hub
/// height, overhang, spinner and the nacelle body (its height twice the hub's height above the
/// tower top: the rotor axis runs through its mid-height).
pub fn show_turbine(scene: &mut Scene, t: &TurbineSetup) {
    scene.nacelle_size = Some(NacelleSize {
        length_m: t.nacelle_length_m,
        width_m: t.nacelle_width_m,
        height_m: 2.0 * t.hub_above_tower_top_m,
        front_behind_hub_m: t.nacelle_front_behind_hub_m,
    });
    scene.tower_top_diameter_m = t.tower_top_diameter_m;
    scene.tower_base_diameter_m = t.tower_base_diameter_m;
    scene.blade_length_m = t.rotor_radius_m;
    scene.hub_height_m = t.hub_height_m;
    scene.hub_overhang_m = t.hub_overhang_m;
    scene.spinner_diameter_m = t.spinner_diameter_m;
}

/// The renderer scene of a scenario: [`Scene::random`] of the seed (sky, ground, sun, rotor
/// angle, blade pitch, noise, blur, nacelle shadow), with the turbine always present, the nacelle
/// yaw 0 and the optional content as configured.
fn scene_for(seed: u64, cfg: &SimConfig) -> Scene {
    let sc = &cfg.scenario;
    let mut s = Scene::random(seed);
    let mut r = Rng::new(seed, STREAM_SCENE_OPTIONS);
    s.turbine_present = true;
    s.nacelle_yaw_deg = 0.0;
    s.frame = 0;
    s.distractor = if !sc.distractors {
        Distractor::None
    } else if s.distractor != Distractor::None {
        s.distractor
    } else if r.chance(0.5) {
        Distractor::Mast
    } else {
        Distractor::PowerLines
    };
    s.second_turbine = sc.second_turbine;
    s.propellers_in_view = sc.propellers;
    s.jpeg_quality = if sc.jpeg {
        Some(s.jpeg_quality.unwrap_or(r.range(55.0, 95.0) as u8))
    } else {
        None
    };
    s
}

/// The renderer camera: the calibrated camera when one is given (`[camera] calibration`), else
/// the config's model (GoPro HERO3+ or USB), scaled by `scale` (intrinsics scaled, distortion
/// unchanged).
pub fn render_camera(camera: &CameraConfig, calibration: Option<&Camera>) -> Camera {
    let base = match (calibration, camera.model) {
        (Some(c), _) => *c,
        (None, CameraModel::Gopro) => Camera::gopro_hero3(),
        (None, CameraModel::Usb) => Camera::usb_narrow(),
    };
    let s = camera.scale;
    let width = ((base.width as f64 * s).round() as u32).max(1);
    let height = ((base.height as f64 * s).round() as u32).max(1);
    // Rounding keeps the aspect within the model's tolerance for every allowed scale; should it
    // not, scale by the width alone.
    base.scaled_to(width, height).unwrap_or_else(|_| {
        let f = base.fx * f64::from(width) / f64::from(base.width);
        Camera::centred(width, height, f, base.distortion)
    })
}

/// The renderer's camera pose for the vehicle state: position relative to the hub in world axes,
/// and the camera orientation (body attitude composed with the mount pitch) as yaw relative to
/// the horizontal line of sight to the hub, absolute pitch and clockwise roll.
pub fn camera_pose(
    scenario: &Scenario,
    vehicle: &Multicopter,
    camera: &CameraConfig,
) -> CameraPose {
    let (x_axis, y_axis) = axes(scenario.rotor_axis_heading_rad);
    let d = sub(vehicle.position_ned(), scenario.hub_ned);
    let [roll, pitch, yaw] = vehicle.attitude();
    let r = body_to_ned(roll, pitch, yaw);
    let m = camera.mount_pitch_deg.to_radians();
    let fwd = mat_vec(&r, [m.cos(), 0.0, -m.sin()]);
    let right = mat_vec(&r, [0.0, 1.0, 0.0]);

    let horiz = fwd[0].hypot(fwd[1]);
    // Looking straight up or down has no heading: take the body's.
    let heading = if horiz > 1e-9 {
        fwd[1].atan2(fwd[0])
    } else {
        yaw
    };
    let cam_pitch = (-fwd[2]).clamp(-1.0, 1.0).asin();
    // Decompose the roll about the optical axis against the level camera of the same heading
    // and pitch (the renderer's construction).
    let (sh, ch) = heading.sin_cos();
    let (sp, cp) = cam_pitch.sin_cos();
    let right0 = [-sh, ch, 0.0];
    let up0 = [-sp * ch, -sp * sh, -cp];
    let cam_roll = (-dot(right, up0)).atan2(dot(right, right0));

    CameraPose {
        distance_m: dot(d, x_axis),
        lateral_m: dot(d, y_axis),
        height_m: -d[2],
        yaw_deg: wrap_deg((heading - bearing_to_hub(scenario, d)).to_degrees()),
        pitch_deg: cam_pitch.to_degrees(),
        roll_deg: cam_roll.to_degrees(),
    }
}

/// NED heading of the horizontal line of sight from a point at `d` = point − hub to the hub; the
/// renderer's choice (look along −X) straight above or below the hub.
fn bearing_to_hub(scenario: &Scenario, d: [f64; 3]) -> f64 {
    if d[0].abs() + d[1].abs() > 1e-9 {
        (-d[1]).atan2(-d[0])
    } else {
        scenario.facing_rotor_heading_rad()
    }
}

/// Ground-truth geometry of the vehicle (its camera) relative to the turbine.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Geometry {
    /// 3D camera–hub distance, m.
    pub distance_m: f64,
    /// Relative yaw, degrees, (−180, 180]: `atan2(lateral_m, rotor_plane_m)`, the same definition
    /// and sign as the renderer's `Truth::relative_yaw_deg` (positive on the viewer's right).
    pub relative_yaw_deg: f64,
    /// Signed horizontal offset from the rotor axis, m, + = the viewer's right when facing the rotor.
    pub lateral_m: f64,
    /// Vehicle height minus hub height, m.
    pub height_m: f64,
    /// Signed distance in front of the rotor plane (the vertical plane through the hub
    /// perpendicular to the axis), m; negative = behind it.
    pub rotor_plane_m: f64,
    /// Vehicle heading minus the horizontal bearing to the hub, degrees, (−180, 180]; positive =
    /// the vehicle looks to the right of the hub.
    pub heading_error_deg: f64,
}

/// Ground-truth geometry of the vehicle relative to the turbine.
pub fn geometry(scenario: &Scenario, vehicle: &Multicopter) -> Geometry {
    let (x_axis, y_axis) = axes(scenario.rotor_axis_heading_rad);
    let d = sub(vehicle.position_ned(), scenario.hub_ned);
    let rotor_plane_m = dot(d, x_axis);
    let lateral_m = dot(d, y_axis);
    Geometry {
        distance_m: norm(d),
        relative_yaw_deg: wrap_deg(lateral_m.atan2(rotor_plane_m).to_degrees()),
        lateral_m,
        height_m: -d[2],
        rotor_plane_m,
        heading_error_deg: wrap_deg(
            (vehicle.attitude()[2] - bearing_to_hub(scenario, d)).to_degrees(),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::{ScenarioConfig, VehicleConfig};
    use hubtrack_render::{Renderer, Truth};
    use std::f64::consts::PI;

    fn vehicle_at(sc: &Scenario, pos: [f64; 3], roll: f64, pitch: f64, yaw: f64) -> Multicopter {
        let mut v = Multicopter::new(&sc.start, &VehicleConfig::default());
        v.set_position_ned(pos);
        v.set_attitude(roll, pitch, yaw);
        v
    }

    /// NED point at world offsets (along axis, right, up) from the hub.
    fn at_offsets(sc: &Scenario, along: f64, right: f64, up: f64) -> [f64; 3] {
        let (x, y) = axes(sc.rotor_axis_heading_rad);
        [
            sc.hub_ned[0] + along * x[0] + right * y[0],
            sc.hub_ned[1] + along * x[1] + right * y[1],
            sc.hub_ned[2] - up,
        ]
    }

    fn bearing(sc: &Scenario, p: [f64; 3]) -> f64 {
        (sc.hub_ned[1] - p[1]).atan2(sc.hub_ned[0] - p[0])
    }

    fn small_cam() -> CameraConfig {
        CameraConfig {
            scale: 0.125,
            ..Default::default()
        }
    }

    fn render(sc: &Scenario, pose: &CameraPose, cam: &CameraConfig) -> Truth {
        let camera = render_camera(cam, None);
        let mut r = Renderer::new(camera);
        let mut buf = vec![0u8; camera.frame_bytes()];
        r.render(&sc.scene, pose, &mut buf).unwrap()
    }

    #[test]
    fn same_seed_same_scenario_and_seeds_differ() {
        let cfg = SimConfig::default();
        assert_eq!(Scenario::from_seed(42, &cfg), Scenario::from_seed(42, &cfg));
        let a = Scenario::from_seed(42, &cfg);
        let b = Scenario::from_seed(43, &cfg);
        assert_ne!(a.hub_ned, b.hub_ned);
        assert_ne!(a.rotor_axis_heading_rad, b.rotor_axis_heading_rad);
        assert_ne!(a.scene, b.scene);
        assert_ne!(a.wind_mean_ned, b.wind_mean_ned);
        assert_eq!(
            Scenario::from_config(&SimConfig {
                seed: 42,
                ..cfg.clone()
            }),
            a
        );
    }

    #[test]
    fn ranges_are_respected_and_the_start_matches_its_offsets() {
        let cfg = SimConfig::default();
        let sc_cfg = &cfg.scenario;
        let (mut headings, mut min_h, mut max_h) = (Vec::new(), f64::MAX, f64::MIN);
        for seed in 0..300 {
            let s = Scenario::from_seed(seed, &cfg);
            assert!((sc_cfg.distance_m[0]..=sc_cfg.distance_m[1]).contains(&s.start_distance_m));
            assert!((sc_cfg.lateral_m[0]..=sc_cfg.lateral_m[1]).contains(&s.start_lateral_m));
            assert!((sc_cfg.height_m[0]..=sc_cfg.height_m[1]).contains(&s.start_height_m));
            assert!(
                (sc_cfg.heading_offset_deg[0]..=sc_cfg.heading_offset_deg[1])
                    .contains(&s.start_heading_offset_deg)
            );
            assert!((0.0..std::f64::consts::TAU).contains(&s.rotor_axis_heading_rad));
            headings.push(s.rotor_axis_heading_rad);
            min_h = min_h.min(s.start_heading_offset_deg);
            max_h = max_h.max(s.start_heading_offset_deg);
            let m = s.wind_mean_ned;
            assert!(m[0].hypot(m[1]) <= cfg.wind.mean_speed_m_s[1] + 1e-9);
            // Scene: turbine present, nacelle yaw 0, optional content off by default.
            assert!(s.scene.turbine_present);
            assert_eq!(s.scene.nacelle_yaw_deg, 0.0);
            assert_eq!(s.scene.distractor, Distractor::None);
            assert!(!s.scene.second_turbine && !s.scene.propellers_in_view);
            assert_eq!(s.scene.jpeg_quality, None);
            // The start state reproduces the drawn offsets.
            let v = Multicopter::new(&s.start, &VehicleConfig::default());
            let g = geometry(&s, &v);
            assert!((g.rotor_plane_m - s.start_distance_m).abs() < 1e-9);
            assert!((g.lateral_m - s.start_lateral_m).abs() < 1e-9);
            assert!((g.height_m - s.start_height_m).abs() < 1e-9);
            let off = wrap_pi(s.start.yaw_rad - s.facing_rotor_heading_rad()).to_degrees();
            assert!((off - s.start_heading_offset_deg).abs() < 1e-9);
            // Origin on the ground under the start.
            assert_eq!(s.start.position_ned[0], 0.0);
            assert!(
                (-s.start.position_ned[2] - (s.scene.hub_height_m + s.start_height_m)).abs() < 1e-9
            );
            assert!((s.tower_base_ned()[2]).abs() < 1e-9);
        }
        // Headings cover the circle (yaw wrap is exercised) and the offsets their range.
        assert!(headings.iter().any(|&h| h < 0.5) && headings.iter().any(|&h| h > 5.8));
        assert!(min_h < -25.0 && max_h > 25.0);
    }

    #[test]
    fn optional_scene_content_and_fixed_heading() {
        let cfg = SimConfig {
            scenario: ScenarioConfig {
                distractors: true,
                second_turbine: true,
                jpeg: true,
                propellers: true,
                rotor_axis_heading_deg: Some(123.0),
                distance_m: [30.0, 30.0],
                ..Default::default()
            },
            ..Default::default()
        };
        let s = Scenario::from_seed(7, &cfg);
        assert_ne!(s.scene.distractor, Distractor::None);
        assert!(
            s.scene.second_turbine && s.scene.propellers_in_view && s.scene.jpeg_quality.is_some()
        );
        assert!((s.rotor_axis_heading_rad - 123f64.to_radians()).abs() < 1e-12);
        assert_eq!(s.start_distance_m, 30.0);
        assert_eq!(s.scene_for_frame(9).frame, 9);
    }

    #[test]
    fn world_and_ned_round_trip() {
        let s = Scenario::from_seed(3, &SimConfig::default());
        let p = [12.0, -4.0, 55.0];
        let back = s.ned_to_world(s.world_to_ned(p));
        for i in 0..3 {
            assert!((back[i] - p[i]).abs() < 1e-9);
        }
        let hub = s.world_to_ned(s.scene.hub_world());
        for (a, b) in hub.iter().zip(s.hub_ned) {
            assert!((a - b).abs() < 1e-9);
        }
        // The nose of the spinner is along the rotor axis heading.
        let nose = s.world_to_ned(s.scene.nose_world());
        let h = (nose[1] - hub[1]).atan2(nose[0] - hub[0]);
        assert!(wrap_pi(h - s.rotor_axis_heading_rad).abs() < 1e-9);
        // Viewer's right: facing the rotor (heading h + π), the right is heading h + π + π/2.
        let r = s.viewer_right_ned();
        let right_heading = r[1].atan2(r[0]);
        assert!(wrap_pi(right_heading - (s.rotor_axis_heading_rad + 1.5 * PI)).abs() < 1e-9);
    }

    #[test]
    fn render_cameras_are_scaled_and_centred() {
        let c = render_camera(&CameraConfig::default(), None);
        assert_eq!((c.width, c.height), (960, 540));
        assert!((c.fx - Camera::gopro_hero3().fx / 2.0).abs() < 1e-9);
        assert_eq!((c.cx, c.cy), (479.5, 269.5));
        assert_eq!(c.distortion, Camera::gopro_hero3().distortion);
        let usb = CameraConfig {
            model: CameraModel::Usb,
            scale: 1.0,
            mount_pitch_deg: 0.0,
        };
        assert_eq!(render_camera(&usb, None), Camera::usb_narrow());
        // A calibration replaces the model.
        let fisheye = Camera::centred(
            1280,
            960,
            500.0,
            hubtrack_types::setup::Distortion::Equidistant {
                k1: 0.01,
                k2: 0.0,
                k3: 0.0,
                k4: 0.0,
            },
        );
        let half = render_camera(&CameraConfig::default(), Some(&fisheye));
        assert_eq!((half.width, half.height, half.fx), (640, 480, 250.0));
        assert_eq!(half.distortion, fisheye.distortion);
    }

    #[test]
    fn facing_the_hub_gives_zero_camera_yaw_and_the_hub_at_the_centre() {
        let cfg = SimConfig::default();
        for seed in [1, 2, 3, 10] {
            let s = Scenario::from_seed(seed, &cfg);
            // Level, at hub height, 20 m in front and 4 m to the right, facing the hub.
            let p = at_offsets(&s, 20.0, 4.0, 0.0);
            let v = vehicle_at(&s, p, 0.0, 0.0, bearing(&s, p));
            let pose = camera_pose(&s, &v, &small_cam());
            assert!(pose.yaw_deg.abs() < 1e-9, "{pose:?}");
            assert!(pose.pitch_deg.abs() < 1e-9 && pose.roll_deg.abs() < 1e-9);
            assert!((pose.distance_m - 20.0).abs() < 1e-9 && (pose.lateral_m - 4.0).abs() < 1e-9);
            let g = geometry(&s, &v);
            assert!(g.heading_error_deg.abs() < 1e-9);
            let cam = render_camera(&small_cam(), None);
            let t = render(&s, &pose, &small_cam());
            let hub = t.hub_px.unwrap();
            assert!(
                (hub[0] - cam.cx).abs() < 1e-6 && (hub[1] - cam.cy).abs() < 1e-6,
                "{hub:?}"
            );
            assert!((t.distance_m - g.distance_m).abs() < 1e-9);
            assert!((t.relative_yaw_deg - g.relative_yaw_deg).abs() < 1e-9);
            assert!((g.relative_yaw_deg - 4f64.atan2(20.0).to_degrees()).abs() < 1e-9);
        }
    }

    #[test]
    fn mount_pitch_aims_the_camera_at_a_hub_above() {
        let s = Scenario::from_seed(5, &SimConfig::default());
        // 6 m below the hub, 15 m in front, 3 m to the left.
        let p = at_offsets(&s, 15.0, -3.0, -6.0);
        let v = vehicle_at(&s, p, 0.0, 0.0, bearing(&s, p));
        let elevation = 6f64.atan2(15f64.hypot(3.0)).to_degrees();
        let cam = CameraConfig {
            mount_pitch_deg: elevation,
            ..small_cam()
        };
        let pose = camera_pose(&s, &v, &cam);
        assert!((pose.pitch_deg - elevation).abs() < 1e-9);
        let t = render(&s, &pose, &cam);
        let c = render_camera(&cam, None);
        let hub = t.hub_px.unwrap();
        assert!(
            (hub[0] - c.cx).abs() < 1e-6 && (hub[1] - c.cy).abs() < 1e-6,
            "{hub:?}"
        );
        let g = geometry(&s, &v);
        assert!((t.distance_m - g.distance_m).abs() < 1e-9);
        assert!((t.relative_yaw_deg - g.relative_yaw_deg).abs() < 1e-9);
        assert!(g.relative_yaw_deg < 0.0, "left of the axis is negative");
        assert!((g.height_m + 6.0).abs() < 1e-9);
    }

    #[test]
    fn yaw_pitch_roll_move_the_hub_the_right_way_in_the_image() {
        let s = Scenario::from_seed(8, &SimConfig::default());
        let cam = small_cam();
        let c = render_camera(&cam, None);
        let p = at_offsets(&s, 25.0, 0.0, 0.0);
        let b = bearing(&s, p);
        let hub_px = |roll: f64, pitch: f64, yaw: f64| {
            let v = vehicle_at(&s, p, roll, pitch, yaw);
            render(&s, &camera_pose(&s, &v, &cam), &cam).hub_px.unwrap()
        };
        // Yaw left (heading decreases): the hub moves right.
        let left = hub_px(0.0, 0.0, b - 10f64.to_radians());
        assert!(
            left[0] > c.cx + 5.0 && (left[1] - c.cy).abs() < 1e-6,
            "{left:?}"
        );
        let v = vehicle_at(&s, p, 0.0, 0.0, b - 10f64.to_radians());
        assert!((camera_pose(&s, &v, &cam).yaw_deg + 10.0).abs() < 1e-9);
        assert!((geometry(&s, &v).heading_error_deg + 10.0).abs() < 1e-9);
        // Nose down (as when accelerating forward): the camera looks below the horizon, the hub
        // (at camera height) appears above the centre.
        let v = vehicle_at(&s, p, 0.0, -8f64.to_radians(), b);
        assert!((camera_pose(&s, &v, &cam).pitch_deg + 8.0).abs() < 1e-9);
        let down = hub_px(0.0, -8f64.to_radians(), b);
        assert!(
            down[1] < c.cy - 5.0 && (down[0] - c.cx).abs() < 1e-6,
            "{down:?}"
        );
        // Roll right (right side down): camera roll positive; a hub to the right of the centre
        // (vehicle yawed left) rises in the image.
        let v = vehicle_at(&s, p, 10f64.to_radians(), 0.0, b);
        assert!((camera_pose(&s, &v, &cam).roll_deg - 10.0).abs() < 1e-9);
        let rolled = hub_px(10f64.to_radians(), 0.0, b - 10f64.to_radians());
        assert!(rolled[0] > c.cx && rolled[1] < c.cy - 2.0, "{rolled:?}");
    }

    #[test]
    fn full_attitude_and_mount_match_the_renderer_camera_frame() {
        // The renderer's hub_cam_m (hub in the camera frame: x right, y down, z forward) must equal
        // the hub expressed in our camera axes built directly from the body rotation.
        let cfg = SimConfig::default();
        for (seed, roll, pitch, dyaw, mount) in [
            (1u64, 0.1, -0.15, 0.2, 0.0),
            (2, -0.2, 0.1, -0.3, 12.0),
            (3, 0.25, 0.2, 0.05, -20.0),
            (4, 0.0, 0.0, 3.0, 0.0),
        ] {
            let s = Scenario::from_seed(seed, &cfg);
            let p = at_offsets(&s, 18.0, -5.0, -3.0);
            let v = vehicle_at(&s, p, roll, pitch, bearing(&s, p) + dyaw);
            let cam = CameraConfig {
                mount_pitch_deg: mount,
                ..small_cam()
            };
            let pose = camera_pose(&s, &v, &cam);
            let t = render(&s, &pose, &cam);
            let r = body_to_ned(roll, pitch, v.attitude()[2]);
            let m = f64::to_radians(mount);
            let fwd = mat_vec(&r, [m.cos(), 0.0, -m.sin()]);
            let right = mat_vec(&r, [0.0, 1.0, 0.0]);
            let down = mat_vec(&r, [m.sin(), 0.0, m.cos()]);
            let d = sub(s.hub_ned, p);
            let expected = [dot(d, right), dot(d, down), dot(d, fwd)];
            for i in 0..3 {
                assert!(
                    (t.hub_cam_m[i] - expected[i]).abs() < 1e-6,
                    "seed {seed}: {:?} vs {expected:?}",
                    t.hub_cam_m
                );
            }
        }
    }

    #[test]
    fn geometry_signs() {
        let s = Scenario::from_seed(4, &SimConfig::default());
        // Behind the rotor plane, to the viewer's right and above.
        let p = at_offsets(&s, -2.0, 7.0, 3.0);
        let v = vehicle_at(&s, p, 0.0, 0.0, 0.0);
        let g = geometry(&s, &v);
        assert!((g.rotor_plane_m + 2.0).abs() < 1e-9);
        assert!((g.lateral_m - 7.0).abs() < 1e-9);
        assert!((g.height_m - 3.0).abs() < 1e-9);
        assert!((g.distance_m - (4.0f64 + 49.0 + 9.0).sqrt()).abs() < 1e-9);
        assert!(g.relative_yaw_deg > 90.0);
        // Heading to the right of the hub: positive heading error.
        let p = at_offsets(&s, 20.0, 0.0, 0.0);
        let v = vehicle_at(&s, p, 0.0, 0.0, bearing(&s, p) + 0.3);
        assert!((geometry(&s, &v).heading_error_deg - 0.3f64.to_degrees()).abs() < 1e-9);
    }
}
