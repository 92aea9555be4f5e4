//! What the operator knows about the camera and the turbine, in one place: every stage that turns
//! pixels into metres or degrees (detect, track, the simulator) reads these two sections, so they
//! cannot disagree.
//!
//! The camera is a calibration file (`camera.calibration`, ROS `camera_info` YAML, see
//! `config/cameras/`) or, without one, a distortion-free lens of the given focal length. The
//! turbine is a profile file (`turbine.profile`, see `config/turbines/`) whose keys fill this
//! section; keys set explicitly (`--set turbine.hub_overhang_m=…`) win over the profile's.

use crate::params;
use crate::params::{Check, ParamError};
pub use hubtrack_camera::{CalibrationError, CameraModel, Distortion, SizeMismatch};

/// The GoPro HERO3+ wide lens's centre focal length per image width (833.9 px at 1920), the
/// thesis camera.
#[allow(clippy::approx_constant)] // 0.4343 is the lens, not log10(e)
pub const GOPRO_FOCAL_LENGTH_PER_WIDTH: f64 = 0.4343;

/// The centre focal lengths per image width the estimators are built for, `[min, max]`: from a
/// 180°-class fisheye to a 5.7° telephoto. A calibration outside it is refused where it is read.
pub const FOCAL_LENGTH_PER_WIDTH_RANGE: [f64; 2] = [0.05, 10.0];

params! {
    /// `[camera]`: the camera that takes the frames.
    pub struct CameraSetup {
        /// Calibration file of the camera, ROS `camera_info` YAML (`plumb_bob` or `equidistant`
        /// distortion): used for every pixel ↔ ray conversion, and frames of another size with
        /// the same aspect use it scaled. Empty = a distortion-free lens from
        /// `focal_length_per_width` / `hfov_deg`. Also `--camera FILE`.
        pub calibration: String = String::new();
        /// Without a calibration: horizontal field of view, degrees; the focal length is
        /// `(width / 2) / tan(hfov / 2)` unless `focal_length_per_width` is set.
        pub hfov_deg: f64 = 118.0, closed(1.0, 179.0);
        /// Without a calibration: centre focal length divided by the image width, overriding
        /// `hfov_deg` when > 0. A lens with strong barrel distortion has a much longer centre
        /// focal length than the pinhole value from its edge field of view: the GoPro HERO3+
        /// wide has 833.9 px at 1920 wide (0.4343) against 577 px (0.3004) from 118°. 0 = use
        /// `hfov_deg`.
        pub focal_length_per_width: f64 = GOPRO_FOCAL_LENGTH_PER_WIDTH,
            zero_or_closed(FOCAL_LENGTH_PER_WIDTH_RANGE[0], FOCAL_LENGTH_PER_WIDTH_RANGE[1]);
    }
}

params! {
    /// `[turbine]`: the dimensions of the turbine type being approached (a profile from
    /// `config/turbines/`, or the keys themselves). The defaults are the thesis turbine, an
    /// Enercon E-70 (`config/turbines/enercon_e70.toml`).
    pub struct TurbineSetup {
        /// Turbine profile file (TOML with the keys of this section): its values replace the
        /// section's, except keys given with `--set`. Empty = the keys of this section. Also
        /// `--turbine FILE`.
        pub profile: String = String::new();
        /// Name of the turbine type, for logs and reports.
        pub name: String = "Enercon E-70 (thesis turbine)".to_string();
        /// Height of the rotor centre above the tower base, m.
        pub hub_height_m: f64 = 64.0, closed(10.0, 250.0);
        /// Blade tip radius, m: the rotor's extent in the image.
        pub rotor_radius_m: f64 = 35.5, closed(5.0, 150.0);
        /// Tower diameter just under the nacelle, where the detector measures its width, m; the
        /// distance estimate divides it by the measured width.
        pub tower_top_diameter_m: f64 = 2.2, closed(0.1, 30.0);
        /// Tower diameter at the ground, m: with the top diameter, the taper that says how much
        /// wider the tower is below the point the detector measures.
        pub tower_base_diameter_m: f64 = 4.3, closed(0.1, 30.0);
        /// Horizontal distance from the tower axis to the hub centre along the rotor axis, m; the
        /// yaw estimate (thesis eq. 7.14) divides the hub–tower gap in the image by it.
        pub hub_overhang_m: f64 = 4.2, closed(0.1, 50.0);
        /// Height of the hub centre above the tower top (the flange under the nacelle), m: with
        /// the camera below or above the hub, where the tower's width is measured lies this much
        /// (and the rows down to the measured one) off the hub's height. Default: half the
        /// thesis turbine's 3.5 m nacelle. A metre off moves the distance by about 1 % at
        /// 12–30 m from 5–10 m below the hub, nothing when level with it.
        pub hub_above_tower_top_m: f64 = 1.75, closed(0.0, 20.0);
        /// Spinner (nose cone) diameter at the blade roots, m: a second distance cue close in,
        /// and the size of circle the detector searches for.
        pub spinner_diameter_m: f64 = 3.2, closed(0.1, 30.0);
        /// Nacelle width, m: the nacelle yaw cue reads how far the nacelle's far rear corner
        /// sticks out beside the spinner, and the detector looks for that corner beyond the wider
        /// of the spinner and the nacelle's front corners. Default: the thesis turbine's 3.4 m.
        pub nacelle_width_m: f64 = 3.4, closed(0.3, 20.0);
        /// Nacelle length along the rotor axis, front face to rear face, m. Default 10.
        pub nacelle_length_m: f64 = 10.0, closed(1.0, 50.0);
        /// Distance from the hub centre (the blade-root plane) back to the nacelle's front face
        /// along the rotor axis, m; less than `hub_overhang_m`, as the nacelle sits on the tower.
        /// Default 1.2.
        pub nacelle_front_behind_hub_m: f64 = 1.2, closed(0.0, 20.0);
    }
}

impl TurbineSetup {
    /// The keys a turbine profile file must state: the dimensions the distance and the yaw are
    /// computed from. A profile that leaves one out would fly on the thesis turbine's value.
    pub const PROFILE_REQUIRED: [&'static str; 6] = [
        "hub_height_m",
        "rotor_radius_m",
        "tower_top_diameter_m",
        "tower_base_diameter_m",
        "spinner_diameter_m",
        "hub_overhang_m",
    ];
}

impl CameraSetup {
    /// Checks every value and that the calibration file (if any) reads; errors name the key
    /// under `camera`.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.check_ranges("camera")?;
        let calibrated = self.calibrated().map_err(|e| ParamError {
            key: "camera.calibration".into(),
            value: format!("{:?}", self.calibration),
            allowed: "a ROS camera_info YAML file".into(),
            problem: Some(e.reason),
        })?;
        if let Some(model) = calibrated {
            let [lo, hi] = FOCAL_LENGTH_PER_WIDTH_RANGE;
            let f = model.focal_length_per_width();
            if !(lo..=hi).contains(&f) {
                return Err(ParamError {
                    key: "camera.calibration".into(),
                    value: format!("{:?}", self.calibration),
                    allowed: format!(
                        "a lens whose fx / image_width lies in [{lo}, {hi}] (this one: {f:.4})"
                    ),
                    problem: None,
                });
            }
        }
        Ok(())
    }

    /// For logs: the calibration file, or the pinhole it falls back to.
    pub fn describe(&self) -> String {
        if !self.calibration.is_empty() {
            format!("calibration {}", self.calibration)
        } else if self.focal_length_per_width > 0.0 {
            format!(
                "uncalibrated pinhole, focal length {} x width",
                self.focal_length_per_width
            )
        } else {
            format!("uncalibrated pinhole, {} deg wide", self.hfov_deg)
        }
    }

    /// The calibration file's camera, `None` without one.
    pub fn calibrated(&self) -> Result<Option<CameraModel>, CalibrationError> {
        if self.calibration.is_empty() {
            return Ok(None);
        }
        CameraModel::load(std::path::Path::new(&self.calibration)).map(Some)
    }

    /// The uncalibrated lens for `width` × `height` frames: a centred pinhole of the configured
    /// focal length.
    pub fn pinhole(&self, width: u32, height: u32) -> CameraModel {
        let f = if self.focal_length_per_width > 0.0 {
            self.focal_length_per_width * f64::from(width)
        } else {
            (f64::from(width) / 2.0) / (self.hfov_deg.to_radians() / 2.0).tan()
        };
        CameraModel::centred(width, height, f, hubtrack_camera::Distortion::None)
    }
}

/// The camera for frames of one size: the calibration scaled to it, or the configured pinhole.
/// Built once from [`CameraSetup`] so that the file is read once.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Lens {
    calibrated: Option<CameraModel>,
    setup: CameraSetup,
}

impl Lens {
    /// Reads the calibration file of `setup` (if any).
    pub fn new(setup: &CameraSetup) -> Result<Lens, CalibrationError> {
        Ok(Lens {
            calibrated: setup.calibrated()?,
            setup: setup.clone(),
        })
    }

    /// A lens from a camera model (tests, the simulator).
    pub fn from_model(model: CameraModel) -> Lens {
        Lens {
            calibrated: Some(model),
            setup: CameraSetup::default(),
        }
    }

    /// The calibrated camera, if a calibration was given.
    pub fn calibration(&self) -> Option<&CameraModel> {
        self.calibrated.as_ref()
    }

    /// The camera for `width` × `height` frames; refused when a calibration of another aspect
    /// ratio cannot describe them.
    pub fn for_frame(&self, width: u32, height: u32) -> Result<CameraModel, SizeMismatch> {
        match &self.calibrated {
            Some(c) => c.scaled_to(width, height),
            None => Ok(self.setup.pinhole(width, height)),
        }
    }

    /// Centre focal length per image width (for size priors that need one number).
    pub fn focal_length_per_width(&self) -> f64 {
        match &self.calibrated {
            Some(c) => c.focal_length_per_width(),
            None => self.setup.pinhole(1000, 1000).focal_length_per_width(),
        }
    }
}

impl TurbineSetup {
    /// Checks every value; errors name the key under `turbine`.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.check_ranges("turbine")?;
        let check = Check::new("turbine");
        check.less_eq(
            "tower_top_diameter_m",
            self.tower_top_diameter_m,
            "tower_base_diameter_m",
            self.tower_base_diameter_m,
        )?;
        check.less(
            "spinner_diameter_m",
            self.spinner_diameter_m,
            "rotor_radius_m",
            self.rotor_radius_m,
        )?;
        check.less(
            "rotor_radius_m",
            self.rotor_radius_m,
            "hub_height_m",
            self.hub_height_m,
        )?;
        // The nacelle sits on the tower: its front ahead of the tower axis, its rear behind it.
        check.less(
            "nacelle_front_behind_hub_m",
            self.nacelle_front_behind_hub_m,
            "hub_overhang_m",
            self.hub_overhang_m,
        )?;
        check.less(
            "hub_overhang_m",
            self.hub_overhang_m,
            "nacelle_front_behind_hub_m + nacelle_length_m",
            self.nacelle_rear_behind_hub_m(),
        )
    }

    /// Distance from the hub centre back to the nacelle's rear face along the rotor axis, m.
    pub fn nacelle_rear_behind_hub_m(&self) -> f64 {
        self.nacelle_front_behind_hub_m + self.nacelle_length_m
    }

    /// How much wider the tower gets per metre below its top, m/m: the linear taper from
    /// `tower_top_diameter_m` to `tower_base_diameter_m` over the hub height (the tower top lies a
    /// metre or two under the hub, which makes this a few per cent low).
    pub fn tower_taper(&self) -> f64 {
        ((self.tower_base_diameter_m - self.tower_top_diameter_m) / self.hub_height_m).max(0.0)
    }
}

/// The tower's width at its top, px, from its width `width_px` measured `rows_below_top_px` image
/// rows under the top of a tower widening `taper` m per metre down.
///
/// At depth `d` a height `Δz` below the top appears `Δrow = f·Δz/d` rows lower, where the tower is
/// `taper·Δz` wider, which is `f·taper·Δz/d = taper·Δrow` px: the correction is independent of the
/// focal length and the distance. Without it a width measured a few metres down reads the
/// distance several per cent short.
pub fn tower_top_width_px(width_px: f64, rows_below_top_px: f64, taper: f64) -> f64 {
    width_px - taper * rows_below_top_px.max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tower_width_is_taken_back_to_the_top() {
        // Thesis turbine: 2.2 m at the top, 4.3 m at the base, 64 m hub: 2.1/64 m per metre.
        let t = TurbineSetup::default();
        assert!((t.tower_taper() - 2.1 / 64.0).abs() < 1e-12);
        // f = 1000 px, 30 m: 3 m under the top is 100 rows down, where the tower is
        // 2.2 + 3·2.1/64 m wide = 1000·that/30 px; back at the top it is 1000·2.2/30 px.
        let measured = 1000.0 * (2.2 + 3.0 * t.tower_taper()) / 30.0;
        let top = tower_top_width_px(measured, 100.0, t.tower_taper());
        assert!((top - 1000.0 * 2.2 / 30.0).abs() < 1e-9, "{top}");
        // A row above the top (noise) takes nothing off; a cylinder has no taper.
        assert_eq!(tower_top_width_px(50.0, -4.0, t.tower_taper()), 50.0);
        let cylinder = TurbineSetup {
            tower_base_diameter_m: 2.2,
            ..TurbineSetup::default()
        };
        assert_eq!(cylinder.tower_taper(), 0.0);
    }

    #[test]
    fn the_defaults_are_the_shipped_thesis_profile() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../config/turbines/enercon_e70.toml"
        );
        let text = std::fs::read_to_string(path).unwrap();
        let profile: TurbineSetup = toml_like(&text);
        assert_eq!(profile, TurbineSetup::default());
    }

    /// The profile files are flat `key = value` TOML; shared-types has no TOML parser, so read
    /// them line by line here (the config loader's own test reads them with the real one).
    fn toml_like(text: &str) -> TurbineSetup {
        let mut t = TurbineSetup::default();
        for line in text.lines().map(str::trim) {
            let Some((k, v)) = line.split_once('=') else {
                continue;
            };
            if line.starts_with('#') {
                continue;
            }
            let (k, v) = (k.trim(), v.trim());
            let f = || v.parse::<f64>().unwrap();
            match k {
                "name" => t.name = v.trim_matches('"').to_string(),
                "hub_height_m" => t.hub_height_m = f(),
                "rotor_radius_m" => t.rotor_radius_m = f(),
                "tower_top_diameter_m" => t.tower_top_diameter_m = f(),
                "tower_base_diameter_m" => t.tower_base_diameter_m = f(),
                "hub_overhang_m" => t.hub_overhang_m = f(),
                "hub_above_tower_top_m" => t.hub_above_tower_top_m = f(),
                "spinner_diameter_m" => t.spinner_diameter_m = f(),
                "nacelle_width_m" => t.nacelle_width_m = f(),
                "nacelle_length_m" => t.nacelle_length_m = f(),
                "nacelle_front_behind_hub_m" => t.nacelle_front_behind_hub_m = f(),
                other => panic!("unknown key {other}"),
            }
        }
        t
    }

    #[test]
    fn a_lens_without_calibration_is_the_configured_pinhole() {
        let lens = Lens::new(&CameraSetup::default()).unwrap();
        let cam = lens.for_frame(1920, 1080).unwrap();
        assert!((cam.fx - GOPRO_FOCAL_LENGTH_PER_WIDTH * 1920.0).abs() < 1e-9);
        // Any frame size works without a calibration.
        assert!(lens.for_frame(640, 480).is_ok());
        let gopro = Lens::from_model(CameraModel::gopro_hero3());
        assert!(gopro.for_frame(960, 540).is_ok());
        assert!(gopro.for_frame(640, 480).is_err());
    }

    #[test]
    fn turbine_constraints_between_keys() {
        let t = TurbineSetup {
            tower_top_diameter_m: 5.0,
            ..TurbineSetup::default()
        };
        assert_eq!(
            t.validate().unwrap_err().key,
            "turbine.tower_top_diameter_m"
        );
        let t = TurbineSetup {
            rotor_radius_m: 70.0,
            ..TurbineSetup::default()
        };
        assert_eq!(t.validate().unwrap_err().key, "turbine.rotor_radius_m");
    }
}
