//! Synthetic wind-turbine renderer with exact per-frame ground truth.
//!
//! A pure-Rust software rasteriser (no GPU, no OpenCV) that draws a 3D wind turbine — conical
//! tower, nacelle, spinner and three tapered, twisted blades — over a procedural sky and ground,
//! through a real lens model (including the GoPro HERO3+ barrel distortion), and reports where the
//! hub, nose, tower top and tower width are in the rendered image.
//!
//! Used by the camera capture process as a "synthetic" camera, by the flight simulator, and by
//! evaluation tools that need images with exact truth.
//!
//! # World frame
//! Right-handed, metres:
//! * origin on the (flat) ground at the tower axis;
//! * **Z** up;
//! * **X** the reference rotor-axis direction: horizontal, pointing out of the rotor face
//!   (upwind, toward a camera in front of the turbine) when `nacelle_yaw_deg == 0`;
//! * **Y = Z × X**: the turbine's own left, which is the viewer's right when facing the rotor.
//!
//! The nacelle yaw turns the turbine about Z: rotor axis `a = (cos ψ, −sin ψ, 0)`, i.e. positive
//! yaw is clockwise seen from above. The rotor centre ("hub": where the blade axes meet, in the
//! blade-root plane) is at `(0, 0, hub_height) + HUB_OVERHANG_M · a`; the spinner nose is
//! `SPINNER_NOSE_LENGTH_M` further along `a`; the tower top is on the axis at
//! `hub_height − NACELLE_HEIGHT_M / 2`. The rotor has no tilt and no coning. Blade 1 is at
//! `rotor_angle_deg` from vertical-up, measured clockwise as seen from the front.
//!
//! The sun heading uses the same convention as the nacelle yaw (clockwise from +X).
//!
//! # Camera pose and camera frame
//! Camera centre = `hub + (distance_m, lateral_m, height_m)` in world axes. The camera first
//! looks horizontally at the hub, turns right by `yaw_deg`, tilts to `pitch_deg` above the
//! horizon (absolute, not relative to the hub; see [`CameraPose::looking_at_hub`]) and rolls
//! clockwise by `roll_deg`. The camera frame is x right, y down, z forward.
//!
//! # Relative yaw (project contract)
//! `relative_yaw_deg = atan2(lateral_m, distance_m) + nacelle_yaw_deg` (wrapped to (−180, 180]):
//! the horizontal angle at the hub between the rotor axis and the direction to the camera,
//! positive when the camera stands on the turbine's own left (= the viewer's right when facing
//! the rotor), zero straight in front of the rotor face. It depends on where the camera is, not on
//! where it points.
//!
//! # Pixels and truth
//! Pixel centres are at integer coordinates (OpenCV convention), origin top-left; see
//! [`camera`]. Truth points go through the same [`Camera::project`] as the mesh vertices.
//! The tower width is measured on the rasterised tower silhouette (ignoring occlusion by the
//! rotor): the row through the tower axis [`TOWER_WIDTH_REF_BELOW_TOP_M`] below the tower top
//! (just under the nacelle) if that row is in the image, otherwise the lowest image row that
//! shows the tower (not below the axis point [`TOWER_WIDTH_MIN_HEIGHT_M`] above the ground);
//! see [`Truth`].
//!
//! # What a frame contains, in drawing order
//! 1. Sky (clear gradient with sun glow, overcast deck, or procedural clouds on a plane 1.5 km
//!    up) and ground (fields with crop-row stripes, sea with waves, Fresnel sky reflection and
//!    sun glitter), both with distance haze; the horizon is wherever the pose puts it.
//! 2. Sun disc with bloom (not on overcast days).
//! 3. Hills (for [`Ground::Hills`]): two rings of shaded hills 2.5–8 km away.
//! 4. The main turbine, a smaller one far behind it ([`Scene::second_turbine`]), a met mast or
//!    a power line ([`Distractor`]), z-buffered, Lambert + sky/ground ambient shading, the
//!    nacelle's shadow on the tower computed by ray casting toward the sun.
//! 5. Image effects: propeller blur, 3x3 blur, sensor noise, JPEG-like artefacts (that order:
//!    optics, sensor, compression).
//!
//! Geometry is projected vertex by vertex through the lens and rasterised in distorted pixel
//! space; long parts (tower, blades, nacelle faces) are subdivided every few metres so straight
//! edges bend like in the real lens. Sky and ground directions come from a grid every 16 pixels
//! whose rays are undistorted exactly once per camera (bilinear interpolation error ≤ 0.25 px at
//! the GoPro corners).
//!
//! # Randomness
//! Everything random derives from [`Scene::seed`] (texture placement, field palette, clouds,
//! hills, distractor layout, propeller shape); [`Scene::frame`] only changes the sensor noise
//! and the propeller's blade phase. Same scene + pose = same bytes.
//!
//! # Speed
//! Rendering never allocates a frame-sized buffer: the [`Renderer`] owns the depth buffer, the
//! sky/ground direction grid, the textures (built once in [`Renderer::new`], ~0.1 s) and all
//! scratch; small caches (noise table, hills mesh, propeller shape) are rebuilt only when the
//! noise level or seed changes. A 1920x1080 frame of the default scene takes ~10 ms on one core;
//! see `benches/render.rs`.

#![warn(missing_docs)]
// `!(x > y)` is used on purpose: it is also true for NaN, which must take the safe branch.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// Per-channel loops over small fixed arrays read clearer with indices.
#![allow(clippy::needless_range_loop)]

pub mod camera;
pub mod dataset;
pub mod scene;

mod background;
mod effects;
mod math;
mod mesh;
mod raster;
mod texture;

pub use camera::{Camera, CameraPose};
pub use scene::{Distractor, Ground, NacelleSize, Scene, Sky};

use background::Background;
use effects::Effects;
use math::{norm, wrap_deg, Rng};
use mesh::{
    build_chimney, build_hills, build_mast, build_power_lines, build_turbine, Detail, Mesh,
    TurbineSpec,
};
use raster::{DepthMode, Lighting, Raster};

/// The tower width truth is measured on the row through the tower axis this far below the
/// tower top (m), i.e. just below the nacelle.
pub const TOWER_WIDTH_REF_BELOW_TOP_M: f64 = 4.0;
/// The fallback tower-width row is never below the tower-axis point this high above the ground (m).
pub const TOWER_WIDTH_MIN_HEIGHT_M: f64 = 3.0;
/// Lighting (direct sun factor, sky ambient, ground-bounce ambient) under a clear sky.
const LIGHT_CLEAR: (f32, f32, f32) = (0.72, 0.42, 0.22);
/// Lighting under a partly cloudy sky (sun slightly dimmed, more sky light).
const LIGHT_CLOUDS: (f32, f32, f32) = (0.60, 0.46, 0.22);
/// Lighting under an overcast deck: almost no direct sun, strong diffuse sky light.
const LIGHT_OVERCAST: (f32, f32, f32) = (0.12, 0.74, 0.30);
/// Sun disc brightness behind scattered clouds relative to a clear sky.
const SUN_DISC_STRENGTH_CLOUDS: f32 = 0.8;
/// Second turbine: distance behind the main tower along -X (m, range).
const SECOND_TURBINE_BEHIND_M: (f64, f64) = (450.0, 1100.0);
/// Second turbine: sideways offset along ±Y (m, range).
const SECOND_TURBINE_SIDEWAYS_M: (f64, f64) = (120.0, 420.0);
/// Second turbine: size relative to the main one (range).
const SECOND_TURBINE_SCALE: (f64, f64) = (0.8, 1.0);
/// Wind-farm neighbours ([`Scene::neighbour_turbines`]): distance behind the main tower along -X
/// (m, range).
const NEIGHBOUR_BEHIND_M: (f64, f64) = (-100.0, 800.0);
/// Wind-farm neighbours: sideways offset along ±Y (m, range).
const NEIGHBOUR_SIDEWAYS_M: (f64, f64) = (40.0, 450.0);
/// Wind-farm neighbours: size relative to the main one (range).
const NEIGHBOUR_SCALE: (f64, f64) = (0.9, 1.1);
/// Wind-farm neighbours: nacelle yaw spread around the main one's (degrees, ±): one wind.
const NEIGHBOUR_YAW_SPREAD_DEG: f64 = 8.0;
/// A neighbour must be at least this much farther from the camera than the main tower, and
/// [`NEIGHBOUR_MIN_DISTANCE_RATIO`] times as far, so the main turbine stays the nearest and
/// largest (the one the truth is about) and is never hidden (m).
const NEIGHBOUR_MIN_EXTRA_DISTANCE_M: f64 = 60.0;
/// See [`NEIGHBOUR_MIN_EXTRA_DISTANCE_M`].
const NEIGHBOUR_MIN_DISTANCE_RATIO: f64 = 1.3;
/// Neighbours farther than this from the camera are built with low detail (m).
const NEIGHBOUR_LOW_DETAIL_M: f64 = 250.0;
/// The camera must be at least this high above the ground (m).
pub const MIN_CAMERA_HEIGHT_M: f64 = 0.5;

/// Exact truth for one rendered frame, in the frame's own pixel coordinates (origin top-left).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Truth {
    /// Turbine present and its hub projects inside the image.
    pub turbine_in_view: bool,
    /// Where the blade axes meet (rotor centre in the blade-root plane). `Some` whenever the
    /// turbine is present and the hub is in front of the camera, even if outside the image.
    pub hub_px: Option<[f64; 2]>,
    /// Tip of the spinner nose cone (same rules as `hub_px`).
    pub nose_px: Option<[f64; 2]>,
    /// Tower axis at the top of the tower (same rules as `hub_px`).
    pub tower_top_px: Option<[f64; 2]>,
    /// Tower pixel width measured at row `tower_width_row`: number of pixels in that row covered
    /// by the rasterised tower silhouette (a horizontal run, so a tower that appears slanted
    /// measures wider than its perpendicular width). `None` if the tower is not visible or is cut by the
    /// left/right image border in that row.
    pub tower_width_px: Option<f64>,
    /// Row of the width measurement: the row through the tower axis point
    /// [`TOWER_WIDTH_REF_BELOW_TOP_M`] below the tower top if it is in the image, else the lowest
    /// image row showing the tower, but not below the axis point [`TOWER_WIDTH_MIN_HEIGHT_M`]
    /// above the ground (where the base outline curves).
    pub tower_width_row: Option<f64>,
    /// Height above the ground (m) of the tower axis point on `tower_width_row` (the tower
    /// diameter there is [`Scene::tower_diameter_at`] of it).
    pub tower_width_height_m: Option<f64>,
    /// Camera to hub, 3D (m).
    pub distance_m: f64,
    /// Relative yaw (degrees), see the crate docs for the sign convention.
    pub relative_yaw_deg: f64,
    /// Hub position in the camera frame (x right, y down, z forward; m).
    pub hub_cam_m: [f64; 3],
}

/// Errors from [`Renderer::render`].
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum RenderError {
    /// The output buffer does not hold exactly one BGR8 frame of the renderer's camera.
    #[error("output buffer has {got} bytes, expected {expected} (width * height * 3)")]
    BufferSize {
        /// Required length in bytes.
        expected: usize,
        /// Length passed in.
        got: usize,
    },
    /// The pose puts the camera below (or within [`MIN_CAMERA_HEIGHT_M`] of) the ground.
    #[error(
        "camera is {height_m:.2} m above the ground; must be at least {MIN_CAMERA_HEIGHT_M} m"
    )]
    CameraBelowGround {
        /// Camera height above the ground (m).
        height_m: f64,
    },
    /// A scene or pose value is out of range or not finite.
    #[error("invalid input: {0}")]
    InvalidInput(&'static str),
}

/// Renders frames for one camera; owns all reusable scratch (depth buffer, direction grid,
/// textures, meshes, effect buffers) so [`Renderer::render`] does not allocate per frame.
pub struct Renderer {
    camera: Camera,
    raster: Raster,
    background: Background,
    effects: Effects,
    mesh: Mesh,
    hills: Mesh,
    hills_seed: Option<u64>,
}

impl Renderer {
    /// Build a renderer (precomputes textures and the lens direction grid, ~0.1 s).
    pub fn new(camera: Camera) -> Renderer {
        let (w, h) = (camera.width as usize, camera.height as usize);
        Renderer {
            camera,
            raster: Raster::new(&camera),
            background: Background::new(&camera),
            effects: Effects::new(w, h),
            mesh: Mesh::default(),
            hills: Mesh::default(),
            hills_seed: None,
        }
    }

    /// The camera this renderer draws for.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Render BGR8 pixels (stride = width*3, row-major, top row first) into `out`, which the
    /// caller owns, and return the frame's truth.
    pub fn render(
        &mut self,
        scene: &Scene,
        pose: &CameraPose,
        out: &mut [u8],
    ) -> Result<Truth, RenderError> {
        let expected = self.camera.frame_bytes();
        if out.len() != expected {
            return Err(RenderError::BufferSize {
                expected,
                got: out.len(),
            });
        }
        validate(scene, pose)?;
        let cam_height = scene.hub_height_m + pose.height_m;
        if cam_height < MIN_CAMERA_HEIGHT_M {
            return Err(RenderError::CameraBelowGround {
                height_m: cam_height,
            });
        }
        let hub = scene.hub_world();
        let w2c = pose.world_to_cam(hub);

        self.background.render(out, scene, &w2c);

        let sun = scene.sun_dir();
        if scene.sky != Sky::Overcast && sun[2] > 0.0 {
            let sc = w2c.point(math::add(w2c.origin, sun));
            if let Some(px) = self.camera.project(sc) {
                let strength = if scene.sky == Sky::Clouds {
                    SUN_DISC_STRENGTH_CLOUDS
                } else {
                    1.0
                };
                self.effects.sun_disc(out, px, self.camera.fx, strength);
            }
        }

        let (haze, visibility_m) = Background::haze_and_visibility(scene);
        let (sun_k, amb_sky, amb_ground) = match scene.sky {
            Sky::Clear => LIGHT_CLEAR,
            Sky::Clouds => LIGHT_CLOUDS,
            Sky::Overcast => LIGHT_OVERCAST,
        };
        let light = Lighting {
            sun,
            sun_k: if sun[2] > 0.0 { sun_k } else { 0.0 },
            amb_sky,
            amb_ground,
            haze,
            visibility_m,
            eye: w2c.origin,
        };

        self.raster.begin_frame();
        let mut layout = Rng::new(scene.seed, 0x1A70);
        if scene.ground == Ground::Hills {
            // The hills depend on the seed only: rebuild when it changes.
            if self.hills_seed != Some(scene.seed) {
                self.hills.clear();
                build_hills(&mut self.hills, scene.seed);
                self.hills_seed = Some(scene.seed);
            }
            self.raster
                .draw_mesh(out, &self.hills, &w2c, &light, DepthMode::Backdrop);
        }
        // The main tower is drawn first in its own mesh so its spans are recorded unoccluded.
        if scene.turbine_present {
            self.mesh.clear();
            build_turbine(&mut self.mesh, &TurbineSpec::main(scene));
            self.raster
                .draw_mesh(out, &self.mesh, &w2c, &light, DepthMode::TestWrite);
        }
        self.mesh.clear();
        if scene.second_turbine {
            let side = if layout.chance(0.5) { 1.0 } else { -1.0 };
            let mut spec = TurbineSpec::main(scene);
            // Behind the main turbine as seen from the usual camera positions (which are at +X).
            let (bx, by) = (SECOND_TURBINE_BEHIND_M, SECOND_TURBINE_SIDEWAYS_M);
            spec.base = [
                -layout.range(bx.0, bx.1),
                side * layout.range(by.0, by.1),
                0.0,
            ];
            spec.hub_height_m =
                scene.hub_height_m * layout.range(SECOND_TURBINE_SCALE.0, SECOND_TURBINE_SCALE.1);
            spec.blade_length_m =
                scene.blade_length_m * layout.range(SECOND_TURBINE_SCALE.0, SECOND_TURBINE_SCALE.1);
            spec.rotor_angle_deg = layout.range(0.0, 120.0);
            spec.detail = Detail::Low;
            spec.shadow_sun = None;
            build_turbine(&mut self.mesh, &spec);
        }
        self.build_neighbours(scene, w2c.origin);
        match scene.distractor {
            Distractor::None => {}
            Distractor::Mast => build_mast(&mut self.mesh, scene, &mut layout),
            Distractor::PowerLines => build_power_lines(&mut self.mesh, &mut layout),
            Distractor::Chimney => build_chimney(&mut self.mesh, scene, &mut layout),
        }
        if !self.mesh.tris.is_empty() || !self.mesh.wires.is_empty() {
            self.raster
                .draw_mesh(out, &self.mesh, &w2c, &light, DepthMode::TestWrite);
        }

        let truth = self.truth(scene, pose, &w2c);

        if scene.propellers_in_view {
            self.effects.propeller(out, scene.seed, scene.frame);
        }
        let motion_blur_px = scene.motion_blur_frac * self.camera.width as f32;
        if motion_blur_px > 1.0 {
            self.effects.motion_blur(out, motion_blur_px);
        }
        if scene.blur {
            self.effects.blur(out);
        }
        self.effects
            .noise(out, scene.noise_sigma, scene.seed, scene.frame);
        if let Some(q) = scene.jpeg_quality {
            self.effects.jpeg(out, q);
        }
        Ok(truth)
    }

    /// Adds the wind farm's other turbines ([`Scene::neighbour_turbines`]) to the mesh: full size,
    /// facing the same wind, each farther from the camera at `eye` than the main tower.
    fn build_neighbours(&mut self, scene: &Scene, eye: math::V3) {
        let mut r = Rng::new(scene.seed, 0x4E16);
        let horizontal = |p: math::V3| (p[0] - eye[0]).hypot(p[1] - eye[1]);
        let main_distance = horizontal([0.0, 0.0, 0.0]);
        for _ in 0..scene.neighbour_turbines {
            // A few draws to find a place behind the main turbine as seen from the camera.
            for _ in 0..8 {
                let side = if r.chance(0.5) { 1.0 } else { -1.0 };
                let base = [
                    -r.range(NEIGHBOUR_BEHIND_M.0, NEIGHBOUR_BEHIND_M.1),
                    side * r.range(NEIGHBOUR_SIDEWAYS_M.0, NEIGHBOUR_SIDEWAYS_M.1),
                    0.0,
                ];
                let size = r.range(NEIGHBOUR_SCALE.0, NEIGHBOUR_SCALE.1);
                let (yaw, rotor) = (
                    r.range(-NEIGHBOUR_YAW_SPREAD_DEG, NEIGHBOUR_YAW_SPREAD_DEG),
                    r.range(0.0, 120.0),
                );
                let distance = horizontal(base);
                if distance
                    < (main_distance + NEIGHBOUR_MIN_EXTRA_DISTANCE_M)
                        .max(main_distance * NEIGHBOUR_MIN_DISTANCE_RATIO)
                {
                    continue;
                }
                let mut spec = TurbineSpec::main(scene);
                spec.base = base;
                spec.hub_height_m *= size;
                spec.blade_length_m *= size;
                spec.nacelle_yaw_deg += yaw;
                spec.rotor_angle_deg = rotor;
                spec.detail = if distance > NEIGHBOUR_LOW_DETAIL_M {
                    Detail::Low
                } else {
                    Detail::High
                };
                spec.shadow_sun = None;
                build_turbine(&mut self.mesh, &spec);
                break;
            }
        }
    }

    fn truth(&self, scene: &Scene, pose: &CameraPose, w2c: &math::WorldToCam) -> Truth {
        let cam = &self.camera;
        let (w, h) = (cam.width as f64, cam.height as f64);
        let hub_cam = w2c.point(scene.hub_world());
        let proj = |p: [f64; 3]| {
            if scene.turbine_present {
                cam.project(w2c.point(p))
            } else {
                None
            }
        };
        let hub_px = proj(scene.hub_world());
        let inside =
            |p: &[f64; 2]| p[0] >= -0.5 && p[0] <= w - 0.5 && p[1] >= -0.5 && p[1] <= h - 0.5;
        let turbine_in_view = hub_px.as_ref().is_some_and(inside);
        let (mut tower_width_px, mut tower_width_row, mut tower_width_height_m) =
            (None, None, None);
        if scene.turbine_present {
            if let Some((row, z)) = self.tower_width_row(scene, w2c) {
                let (l, r) = self.raster.tower_spans[row];
                if l > 0 && (r as f64) < w - 1.0 {
                    tower_width_px = Some((r - l + 1) as f64);
                }
                tower_width_row = Some(row as f64);
                tower_width_height_m = z;
            }
        }
        Truth {
            turbine_in_view,
            hub_px,
            nose_px: proj(scene.nose_world()),
            tower_top_px: proj(scene.tower_top_world()),
            tower_width_px,
            tower_width_row,
            tower_width_height_m,
            distance_m: norm(pose.offset_from_hub()),
            relative_yaw_deg: wrap_deg(
                pose.lateral_m.atan2(pose.distance_m).to_degrees() + scene.nacelle_yaw_deg,
            ),
            hub_cam_m: hub_cam,
        }
    }

    /// Row for the tower-width truth and the tower height (m) on it.
    fn tower_width_row(
        &self,
        scene: &Scene,
        w2c: &math::WorldToCam,
    ) -> Option<(usize, Option<f64>)> {
        let h = self.camera.height as usize;
        let spans = &self.raster.tower_spans;
        let valid = |r: usize| spans[r].0 <= spans[r].1;
        let axis_v = |z: f64| self.camera.project(w2c.point([0.0, 0.0, z])).map(|p| p[1]);
        let z_ref = scene.tower_top_height_m() - TOWER_WIDTH_REF_BELOW_TOP_M;
        if let Some(v) = axis_v(z_ref) {
            let row = v.round();
            if row >= 0.0 && row < h as f64 && valid(row as usize) {
                return Some((row as usize, Some(z_ref)));
            }
        }
        // Reference row not usable: the lowest image row showing the tower, but not below the
        // axis point TOWER_WIDTH_MIN_HEIGHT_M above the ground (the base outline is curved).
        let start = match axis_v(TOWER_WIDTH_MIN_HEIGHT_M) {
            Some(v) if v.is_finite() => v.round().clamp(0.0, (h - 1) as f64) as usize,
            _ => h - 1,
        };
        let row = (0..=start).rev().find(|&r| valid(r))?;
        // Height of the axis point on that row: bisection along the axis (v is monotonic in z
        // over the visible part of the tower for any sane pose).
        let target = row as f64;
        let (mut lo, mut hi) = (0.0, scene.tower_top_height_m());
        let (vlo, vhi) = (axis_v(lo), axis_v(hi));
        let z = match (vlo, vhi) {
            (Some(a), Some(b)) if (a - target) * (b - target) <= 0.0 => {
                let increasing = b > a;
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    match axis_v(mid) {
                        Some(v) if (v < target) == increasing => lo = mid,
                        Some(_) => hi = mid,
                        None => break,
                    }
                }
                Some(0.5 * (lo + hi))
            }
            _ => None,
        };
        Some((row, z))
    }
}

fn validate(scene: &Scene, pose: &CameraPose) -> Result<(), RenderError> {
    let finite = [
        pose.distance_m,
        pose.lateral_m,
        pose.height_m,
        pose.yaw_deg,
        pose.pitch_deg,
        pose.roll_deg,
        scene.hub_height_m,
        scene.tower_base_diameter_m,
        scene.tower_top_diameter_m,
        scene.blade_length_m,
        scene.hub_overhang_m,
        scene.spinner_diameter_m,
        scene.nacelle_scale,
        scene.rotor_angle_deg,
        scene.nacelle_yaw_deg,
        scene.blade_pitch_deg,
        scene.sun_azimuth_deg,
        scene.sun_elevation_deg,
        scene.noise_sigma as f64,
    ];
    if finite.iter().any(|v| !v.is_finite()) {
        return Err(RenderError::InvalidInput("non-finite scene or pose value"));
    }
    if !(10.0..=500.0).contains(&scene.hub_height_m) {
        return Err(RenderError::InvalidInput(
            "hub_height_m must be within 10..500",
        ));
    }
    if !(0.1..=30.0).contains(&scene.tower_base_diameter_m)
        || !(0.1..=30.0).contains(&scene.tower_top_diameter_m)
    {
        return Err(RenderError::InvalidInput(
            "tower diameters must be within 0.1..30 m",
        ));
    }
    if !(2.0..=200.0).contains(&scene.blade_length_m) {
        return Err(RenderError::InvalidInput(
            "blade_length_m must be within 2..200",
        ));
    }
    if !(0.5..=20.0).contains(&scene.hub_overhang_m)
        || !(0.5..=15.0).contains(&scene.spinner_diameter_m)
        || !(scene::NACELLE_SCALE_RANGE.0..=scene::NACELLE_SCALE_RANGE.1)
            .contains(&scene.nacelle_scale)
    {
        return Err(RenderError::InvalidInput(
            "hub_overhang_m must be within 0.5..20 m, spinner_diameter_m within 0.5..15 m, nacelle_scale within 0.3..4",
        ));
    }
    if scene.nacelle_size.is_some_and(|n| !n.is_drawable()) {
        return Err(RenderError::InvalidInput(
            "nacelle_size must be 1..50 m long, 0.3..20 m wide, 0.3..40 m high (twice a profile's hub_above_tower_top_m), its front 0..20 m behind the blade roots",
        ));
    }
    if scene.noise_sigma < 0.0 || scene.noise_sigma > 100.0 {
        return Err(RenderError::InvalidInput(
            "noise_sigma must be within 0..100",
        ));
    }
    Ok(())
}
