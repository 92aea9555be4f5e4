//! The world: turbine dimensions, sky, ground, sun, distractors and image effects.

use serde::{Deserialize, Serialize};

use crate::math::{add, deg, scale, Rng, V3};

/// Default hub height (m) of the modelled ~1.5 MW class turbine.
pub const DEFAULT_HUB_HEIGHT_M: f64 = 70.0;
/// Lowest hub height accepted by [`Scene::random`] (m).
pub const MIN_HUB_HEIGHT_M: f64 = 64.0;
/// Highest hub height used by [`Scene::random`] (m).
pub const MAX_HUB_HEIGHT_M: f64 = 85.0;
/// Default tower diameter at the ground (m).
pub const DEFAULT_TOWER_BASE_DIAMETER_M: f64 = 4.3;
/// Default tower diameter at the top flange (m).
pub const DEFAULT_TOWER_TOP_DIAMETER_M: f64 = 2.2;
/// Default blade length from the rotor centre (m).
pub const DEFAULT_BLADE_LENGTH_M: f64 = 33.5;

/// Default horizontal distance from the tower axis to the rotor centre (blade-root plane),
/// metres ([`Scene::hub_overhang_m`]).
pub const HUB_OVERHANG_M: f64 = 4.2;
/// Default nacelle body length (m); [`Scene::nacelle_scale`] scales the whole body.
pub const NACELLE_LENGTH_M: f64 = 10.0;
/// Default nacelle body height (m); the rotor axis runs through its mid-height.
pub const NACELLE_HEIGHT_M: f64 = 3.5;
/// Nacelle sizes the renderer draws, as [`Scene::nacelle_scale`] (smallest, largest).
pub const NACELLE_SCALE_RANGE: (f64, f64) = (0.3, 4.0);
/// Default nacelle body width (m).
pub const NACELLE_WIDTH_M: f64 = 3.4;
/// Default position of the nacelle's front face ahead of the tower axis (m).
pub const NACELLE_FRONT_X_M: f64 = 3.0;
/// Default spinner (nose cone) radius at the blade-root plane (m)
/// ([`Scene::spinner_diameter_m`]).
pub const SPINNER_RADIUS_M: f64 = 1.6;
/// Distance from the blade-root plane to the tip of the default spinner's nose (m); other
/// spinners keep its proportions.
pub const SPINNER_NOSE_LENGTH_M: f64 = 2.0;

/// Nose length of a spinner of radius `radius_m` (the default spinner's proportions), metres.
pub fn spinner_nose_length_m(radius_m: f64) -> f64 {
    SPINNER_NOSE_LENGTH_M * radius_m / SPINNER_RADIUS_M
}

/// A nacelle body's dimensions, metres: a box along the rotor axis, which runs through its
/// mid-height.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct NacelleSize {
    /// Along the rotor axis, front face to rear face.
    pub length_m: f64,
    /// Across the rotor axis.
    pub width_m: f64,
    /// Vertical: the hub sits half of it above the tower top.
    pub height_m: f64,
    /// From the blade-root plane back to the front face.
    pub front_behind_hub_m: f64,
}

impl NacelleSize {
    /// The default body scaled by `k` (length, width, height and the front's setback alike).
    pub fn default_scaled(k: f64) -> NacelleSize {
        NacelleSize {
            length_m: NACELLE_LENGTH_M * k,
            width_m: NACELLE_WIDTH_M * k,
            height_m: NACELLE_HEIGHT_M * k,
            front_behind_hub_m: (HUB_OVERHANG_M - NACELLE_FRONT_X_M) * k,
        }
    }

    /// Every dimension finite and within what the renderer draws: 1–50 m long, 0.3–20 m wide,
    /// 0.3–40 m high, the front 0–20 m behind the blade-root plane.
    pub fn is_drawable(&self) -> bool {
        (1.0..=50.0).contains(&self.length_m)
            && (0.3..=20.0).contains(&self.width_m)
            && (0.3..=40.0).contains(&self.height_m)
            && (0.0..=20.0).contains(&self.front_behind_hub_m)
    }
}

fn default_hub_overhang_m() -> f64 {
    HUB_OVERHANG_M
}

fn default_spinner_diameter_m() -> f64 {
    2.0 * SPINNER_RADIUS_M
}

fn default_nacelle_scale() -> f64 {
    1.0
}

/// Sky appearance.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Sky {
    /// Blue gradient, strong sun.
    Clear,
    /// Uniform grey cloud deck, soft light.
    Overcast,
    /// Blue sky with procedural cumulus-like clouds.
    Clouds,
}

/// Ground appearance.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Ground {
    /// Flat farmland: patchwork of fields with grass texture.
    Grass,
    /// Open sea with waves and sun glint (offshore turbine).
    Sea,
    /// Farmland with a ring of hills on the horizon.
    Hills,
}

/// Objects that look a bit like a turbine tower and should not be detected as one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Distractor {
    /// Nothing extra.
    None,
    /// A guyed meteorological lattice mast near the turbine site.
    Mast,
    /// A line of lattice pylons with sagging conductors behind the turbine.
    PowerLines,
    /// An industrial chimney: a smooth, tapered concrete column as tall as a turbine tower,
    /// without a rotor. Never drawn by [`Scene::random`]: it belongs to the held-out scenes of
    /// the cross-domain evaluation (`dataset::held_out_scene`).
    Chimney,
}

/// Everything about the world except the camera pose.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Scene {
    /// Whether the (main) turbine exists at all.
    pub turbine_present: bool,
    /// Height of the rotor centre above the ground, metres (64..85).
    pub hub_height_m: f64,
    /// Tower diameter at the ground, metres (~4.3).
    pub tower_base_diameter_m: f64,
    /// Tower diameter at the top, metres (~2.2).
    pub tower_top_diameter_m: f64,
    /// Blade length from the rotor centre, metres (~33.5).
    pub blade_length_m: f64,
    /// Horizontal distance from the tower axis to the blade-root plane, metres (4.2).
    #[serde(default = "default_hub_overhang_m")]
    pub hub_overhang_m: f64,
    /// Spinner diameter at the blade-root plane, metres (3.2).
    #[serde(default = "default_spinner_diameter_m")]
    pub spinner_diameter_m: f64,
    /// Nacelle body size over the default 10 × 3.5 × 3.4 m body (1); unused with `nacelle_size`.
    #[serde(default = "default_nacelle_scale")]
    pub nacelle_scale: f64,
    /// The nacelle body's own dimensions (a turbine profile's), instead of the default body
    /// scaled by `nacelle_scale`.
    #[serde(default)]
    pub nacelle_size: Option<NacelleSize>,
    /// Angle of blade 1 from vertical-up, clockwise as seen from the front (from the camera side);
    /// blades 2 and 3 at +120° and +240°.
    pub rotor_angle_deg: f64,
    /// Rotor axis heading relative to the world X axis, positive = clockwise seen from above
    /// (the rotor face turns toward the viewer's left, so the camera ends up on the turbine's
    /// left: relative yaw grows by the same amount).
    pub nacelle_yaw_deg: f64,
    /// Blade pitch (feathering) in degrees: 0 = operating (chord near the rotor plane at the tip),
    /// ~85 = parked/feathered (leading edge facing the wind).
    pub blade_pitch_deg: f64,
    /// Sky type.
    pub sky: Sky,
    /// Ground type.
    pub ground: Ground,
    /// Sun heading, degrees clockwise (seen from above) from world +X (0 = sun behind a camera that
    /// looks at the rotor face).
    pub sun_azimuth_deg: f64,
    /// Sun elevation above the horizon, degrees.
    pub sun_elevation_deg: f64,
    /// Darken the upper tower below the nacelle where the nacelle blocks the sun (computed shadow).
    pub nacelle_shadow: bool,
    /// A smaller turbine far in the distance (not part of the truth).
    pub second_turbine: bool,
    /// Further full-size turbines of a wind farm, 100–700 m behind and beside the main one,
    /// facing the same wind (not part of the truth; 0 = none). [`Scene::random`] draws none: the
    /// photo-like training views of [`crate::dataset::photo_case`] do.
    #[serde(default)]
    pub neighbour_turbines: u8,
    /// Shrubland ground (dense dark bushes on light soil, as on Mediterranean wind farms) instead
    /// of the smooth field texture: many short strong edges behind a turbine seen from above.
    /// [`Scene::random`] draws none: the photo-like training views do.
    #[serde(default)]
    pub shrubland: bool,
    /// The UAV's own propeller blur in a top corner.
    pub propellers_in_view: bool,
    /// Masts / power lines (used esp. in scenes without a turbine).
    pub distractor: Distractor,
    /// Gaussian-ish sensor noise, standard deviation in 8-bit levels (0 = off).
    pub noise_sigma: f32,
    /// Mild 3x3 blur.
    pub blur: bool,
    /// Horizontal motion blur: how far the camera's turn smears each point during the
    /// exposure, as a share of the frame's width (0 = off; one pixel or less is none). Never
    /// set by [`Scene::random`]: the held-out scenes of the cross-domain evaluation use it.
    #[serde(default)]
    pub motion_blur_frac: f32,
    /// JPEG-like 8x8 block DCT quantisation artefacts at this quality 1..100 (None = off).
    pub jpeg_quality: Option<u8>,
    /// All randomness (texture placement, noise, clouds, distractor layout) comes from this.
    pub seed: u64,
    /// Frame counter mixed into the sensor noise only, so consecutive frames of one scene get
    /// fresh noise while texture and clouds stay put. Same `seed` + same `frame` = same bytes.
    pub frame: u64,
}

impl Default for Scene {
    fn default() -> Scene {
        Scene::default_clear()
    }
}

impl Scene {
    /// A clear-sky grass scene with the default turbine, sun behind the camera, mild noise.
    pub fn default_clear() -> Scene {
        Scene {
            turbine_present: true,
            hub_height_m: DEFAULT_HUB_HEIGHT_M,
            tower_base_diameter_m: DEFAULT_TOWER_BASE_DIAMETER_M,
            tower_top_diameter_m: DEFAULT_TOWER_TOP_DIAMETER_M,
            blade_length_m: DEFAULT_BLADE_LENGTH_M,
            hub_overhang_m: HUB_OVERHANG_M,
            spinner_diameter_m: 2.0 * SPINNER_RADIUS_M,
            nacelle_scale: 1.0,
            nacelle_size: None,
            rotor_angle_deg: 0.0,
            nacelle_yaw_deg: 0.0,
            blade_pitch_deg: 2.0,
            sky: Sky::Clear,
            ground: Ground::Grass,
            sun_azimuth_deg: 30.0,
            sun_elevation_deg: 40.0,
            nacelle_shadow: true,
            second_turbine: false,
            neighbour_turbines: 0,
            shrubland: false,
            propellers_in_view: false,
            distractor: Distractor::None,
            noise_sigma: 2.0,
            blur: false,
            motion_blur_frac: 0.0,
            jpeg_quality: None,
            seed: 1,
            frame: 0,
        }
    }

    /// A random but plausible scene (sky, ground, sun, rotor angle, effects) from a seed.
    ///
    /// The nacelle yaw stays 0 so that the camera pose alone sets the viewing geometry.
    pub fn random(seed: u64) -> Scene {
        let mut r = Rng::new(seed, 0x5CE7E);
        let sky = match r.below(10) {
            0..=3 => Sky::Clear,
            4..=6 => Sky::Overcast,
            _ => Sky::Clouds,
        };
        let ground = match r.below(4) {
            0 | 1 => Ground::Grass,
            2 => Ground::Sea,
            _ => Ground::Hills,
        };
        let turbine_present = r.chance(0.9);
        let distractor = match r.below(100) {
            0..=14 => Distractor::Mast,
            15..=29 => Distractor::PowerLines,
            _ if !turbine_present => Distractor::Mast,
            _ => Distractor::None,
        };
        let parked = r.chance(0.15);
        Scene {
            turbine_present,
            hub_height_m: r.range(MIN_HUB_HEIGHT_M, MAX_HUB_HEIGHT_M),
            tower_base_diameter_m: DEFAULT_TOWER_BASE_DIAMETER_M * r.range(0.95, 1.05),
            tower_top_diameter_m: DEFAULT_TOWER_TOP_DIAMETER_M * r.range(0.95, 1.05),
            blade_length_m: DEFAULT_BLADE_LENGTH_M,
            hub_overhang_m: HUB_OVERHANG_M,
            spinner_diameter_m: 2.0 * SPINNER_RADIUS_M,
            nacelle_scale: 1.0,
            nacelle_size: None,
            rotor_angle_deg: r.range(0.0, 120.0),
            nacelle_yaw_deg: 0.0,
            blade_pitch_deg: if parked {
                r.range(70.0, 88.0)
            } else {
                r.range(0.0, 6.0)
            },
            sky,
            ground,
            sun_azimuth_deg: r.range(0.0, 360.0),
            sun_elevation_deg: r.range(12.0, 65.0),
            nacelle_shadow: r.chance(0.8),
            second_turbine: r.chance(0.3),
            neighbour_turbines: 0,
            shrubland: false,
            propellers_in_view: r.chance(0.25),
            distractor,
            noise_sigma: r.range(0.0, 4.0) as f32,
            blur: r.chance(0.3),
            motion_blur_frac: 0.0,
            jpeg_quality: if r.chance(0.4) {
                Some(r.range(55.0, 95.0) as u8)
            } else {
                None
            },
            seed,
            frame: 0,
        }
    }

    /// Unit rotor-axis direction in the world frame (pointing out of the rotor face, upwind).
    pub fn rotor_axis(&self) -> [f64; 3] {
        let y = deg(self.nacelle_yaw_deg);
        [y.cos(), -y.sin(), 0.0]
    }

    /// Unit vector to the turbine's own left (= the viewer's right when facing the rotor).
    pub fn turbine_left(&self) -> [f64; 3] {
        let y = deg(self.nacelle_yaw_deg);
        [y.sin(), y.cos(), 0.0]
    }

    /// Rotor centre (where the blade axes meet) in the world frame.
    pub fn hub_world(&self) -> [f64; 3] {
        add(
            [0.0, 0.0, self.hub_height_m],
            scale(self.rotor_axis(), self.hub_overhang_m),
        )
    }

    /// Tip of the spinner nose cone in the world frame.
    pub fn nose_world(&self) -> [f64; 3] {
        add(
            self.hub_world(),
            scale(
                self.rotor_axis(),
                spinner_nose_length_m(self.spinner_diameter_m / 2.0),
            ),
        )
    }

    /// Height of the tower top (flange under the nacelle) above the ground, metres.
    pub fn tower_top_height_m(&self) -> f64 {
        self.hub_height_m - self.nacelle().height_m / 2.0
    }

    /// The nacelle body drawn: `nacelle_size`, else the default body scaled by `nacelle_scale`.
    pub fn nacelle(&self) -> NacelleSize {
        self.nacelle_size
            .unwrap_or_else(|| NacelleSize::default_scaled(self.nacelle_scale))
    }

    /// Tower axis point at the top of the tower, world frame.
    pub fn tower_top_world(&self) -> [f64; 3] {
        [0.0, 0.0, self.tower_top_height_m()]
    }

    /// Tower diameter (m) at height `z_m` above the ground (linear taper).
    pub fn tower_diameter_at(&self, z_m: f64) -> f64 {
        let t = (z_m / self.tower_top_height_m()).clamp(0.0, 1.0);
        self.tower_base_diameter_m + (self.tower_top_diameter_m - self.tower_base_diameter_m) * t
    }

    /// Unit vector toward the sun, world frame.
    pub fn sun_dir(&self) -> [f64; 3] {
        sun_vector(self.sun_azimuth_deg, self.sun_elevation_deg)
    }
}

/// Unit vector toward the sun for a heading (clockwise from +X seen from above) and elevation.
pub(crate) fn sun_vector(az_deg: f64, el_deg: f64) -> V3 {
    let (a, e) = (deg(az_deg), deg(el_deg));
    [e.cos() * a.cos(), -e.cos() * a.sin(), e.sin()]
}
