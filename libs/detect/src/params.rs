//! Every tunable number of the detector, as plain serde data (no OpenCV here).
//!
//! The configuration lives under the `detect` key of the project configuration, so error keys are
//! full dotted paths such as `detect.thesis.canny_high`. Every section is declared once with
//! [`hubtrack_types::params!`]: each field with its doc, default and allowed range; the struct
//! denies unknown fields and fills missing ones from [`Default`].
//!
//! Pixel quantities are in the pixels of the *working* (downsampled) image unless the name says
//! `_frac` (fraction of the working-image height, so they survive a change of working size).

use hubtrack_types::params::Check;
pub use hubtrack_types::params::ParamError;
use serde::{Deserialize, Serialize};

/// Which pipeline [`crate::Detector::detect`] runs.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Faithful reimplementation of the thesis (section 6.1.5): the reference.
    Thesis,
    /// The project's robust pipeline (adaptive edges, convergence voting, confidence).
    #[default]
    Default,
}

hubtrack_types::params! {
    /// Whole detector configuration (`detect` section).
    pub struct DetectConfig {
        /// Pipeline to run.
        pub mode: Mode = Mode::Default;
        /// Camera and turbine dimensions for distance and yaw: not keys of `[detect]` but the
        /// top-level `[camera]` and `[turbine]` sections, which track reads too
        /// ([`DetectConfig::with_setup`]).
        #[serde(skip)]
        pub camera: CameraParams = CameraParams::default();
        /// Parameters of the thesis pipeline.
        pub thesis: ThesisParams = ThesisParams::default();
        /// Parameters of the default pipeline.
        pub default: DefaultParams = DefaultParams::default();
    }
}

impl CameraParams {
    /// Whether every turbine dimension here lies within the fraction `tolerance` of the thesis
    /// turbine's (`tolerance` 0: never).
    pub fn is_thesis_turbine(&self, tolerance: f64) -> bool {
        let thesis = CameraParams::default();
        let near = |a: f64, b: f64| (a - b).abs() <= tolerance * b.abs();
        tolerance > 0.0
            && near(self.tower_top_diameter_m, thesis.tower_top_diameter_m)
            && near(self.tower_taper, thesis.tower_taper)
            && near(self.hub_tower_gap_m, thesis.hub_tower_gap_m)
            && near(self.spinner_diameter_m, thesis.spinner_diameter_m)
            && near(self.nacelle_width_m, thesis.nacelle_width_m)
            && near(self.nacelle_rear_m, thesis.nacelle_rear_m)
    }
}

impl DetectConfig {
    /// This configuration with the lens of `[camera]` (see [`Lens::new`]) and the turbine of
    /// `[turbine]`.
    pub fn with_setup(self, lens: &Lens, turbine: &TurbineSetup) -> DetectConfig {
        DetectConfig {
            camera: CameraParams {
                hfov_deg: self.camera.hfov_deg,
                focal_length_per_width: lens.focal_length_per_width(),
                lens: lens.clone(),
                tower_top_diameter_m: turbine.tower_top_diameter_m,
                tower_taper: turbine.tower_taper(),
                hub_tower_gap_m: turbine.hub_overhang_m,
                spinner_diameter_m: turbine.spinner_diameter_m,
                nacelle_width_m: turbine.nacelle_width_m,
                nacelle_rear_m: turbine.nacelle_rear_behind_hub_m(),
            },
            ..self
        }
    }

    /// Check every parameter's range; the error names the first offending key.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.camera.check_ranges("detect.camera")?;
        self.thesis.validate()?;
        self.default.validate()
    }
}

use hubtrack_types::setup::{
    Lens, TurbineSetup, FOCAL_LENGTH_PER_WIDTH_RANGE, GOPRO_FOCAL_LENGTH_PER_WIDTH,
};

hubtrack_types::params! {
    /// Camera optics and known turbine dimensions used for distance and yaw estimates.
    pub struct CameraParams {
        /// Horizontal field of view, degrees. 118 = GoPro HERO3+ Black 1080p wide (the thesis
        /// camera). The pinhole focal length is `f = (width / 2) / tan(hfov / 2)` at full
        /// resolution.
        pub hfov_deg: f64 = 118.0, closed(1.0, 179.0);
        /// Centre focal length divided by the image width, overriding `hfov_deg` when > 0. A lens
        /// with strong barrel distortion has a much longer centre focal length than the pinhole
        /// value from its edge FOV: the GoPro HERO3+ wide (the thesis camera, as the renderer
        /// models it) has 833.9 px at 1920 wide (0.4343) vs 577 px (0.3004) from 118°, which would
        /// make every distance ~31 % short. Default 0.4343; 0 = use `hfov_deg`.
        pub focal_length_per_width: f64 = GOPRO_FOCAL_LENGTH_PER_WIDTH,
            zero_or_closed(FOCAL_LENGTH_PER_WIDTH_RANGE[0], FOCAL_LENGTH_PER_WIDTH_RANGE[1]);
        /// Tower diameter at the top, metres (2.2 m on the thesis's ~1.5 MW turbines); the distance
        /// estimate divides it by the measured tower width.
        pub tower_top_diameter_m: f64 = 2.2, closed(0.1, 30.0);
        /// How much wider the tower gets per metre below its top, m/m: the width, measured a
        /// little under the top, is taken back to the top before it gives a distance. From
        /// `[turbine]` (see [`TurbineSetup::tower_taper`]); default: the thesis turbine's.
        #[serde(skip)]
        pub tower_taper: f64 = TurbineSetup::default().tower_taper(), closed(0.0, 1.0);
        /// Distance from the hub centre to the tower axis along the rotor axis, metres (~4 m); the
        /// yaw estimate (thesis eq. 7.14) divides the image gap by it.
        pub hub_tower_gap_m: f64 = 4.2, closed(0.1, 50.0);
        /// Spinner (nose cone) diameter at the blade roots, metres (3.2 m on the modelled turbine):
        /// with the tracker's distance it gives the spinner radius to search for.
        pub spinner_diameter_m: f64 = 3.2, closed(0.1, 30.0);
        /// Nacelle width, metres: its front corners stick out beside the spinner whatever the
        /// yaw, so the nacelle's far end is searched beyond them. From `[turbine]`
        /// (`nacelle_width_m`); default: the thesis turbine's.
        #[serde(skip)]
        pub nacelle_width_m: f64 = TurbineSetup::default().nacelle_width_m, closed(0.3, 20.0);
        /// Distance from the hub back to the nacelle's rear face, metres: how far out its rear
        /// corner can appear. From `[turbine]` (see [`TurbineSetup::nacelle_rear_behind_hub_m`]).
        #[serde(skip)]
        pub nacelle_rear_m: f64 = TurbineSetup::default().nacelle_rear_behind_hub_m(), closed(1.0, 70.0);
        /// The camera (from `[camera]`): frames of a size its calibration cannot describe are
        /// refused.
        #[serde(skip)]
        pub lens: Lens = Lens::default();
    }
}

hubtrack_types::params! {
    /// Parameters of the thesis pipeline (section 6.1.5, 8.1 and table 9.1). Defaults are the
    /// thesis's values; where the thesis gives no number the choice is documented.
    pub struct ThesisParams {
        /// Downsample with pyrDown (at least once) until both sides are at most this, px (thesis
        /// 8.1: 200–500).
        pub pyramid_max_side_px: u32 = 500, closed(16.0, 4096.0);
        /// Stop downsampling before any side would drop below this, px (thesis 8.1).
        pub pyramid_min_side_px: u32 = 200, closed(16.0, 4096.0);
        /// Canny low hysteresis threshold (thesis: 300).
        pub canny_low: f64 = 300.0, closed(0.0, 4096.0);
        /// Canny high hysteresis threshold (thesis: 400).
        pub canny_high: f64 = 400.0, closed(0.0, 4096.0);
        /// Hough accumulator distance resolution, px (thesis: 1).
        pub hough_rho_px: f64 = 1.0, closed(0.1, 10.0);
        /// Hough accumulator angle resolution, degrees (thesis: 1).
        pub hough_theta_deg: f64 = 1.0, closed(0.05, 10.0);
        /// Hough accumulator threshold, votes (thesis table 9.1: 43).
        pub hough_threshold: i32 = 43, closed(1.0, 10_000.0);
        /// Minimum Hough segment length, px at the working size (thesis table 9.1: 50 at 270 px
        /// height).
        pub hough_min_length_px: f64 = 50.0, closed(1.0, 4096.0);
        /// Maximum gap bridged inside one Hough segment, px (thesis table 9.1: 13).
        pub hough_max_gap_px: f64 = 13.0, closed(0.0, 4096.0);
        /// A tower line may deviate this much from vertical after roll compensation, degrees
        /// ("a few degrees" in the thesis).
        pub tower_max_tilt_deg: f64 = 5.0, closed(0.0, 45.0);
        /// A tower line must have an end point in this lowest fraction of the image (thesis: 20 %).
        pub tower_bottom_frac: f64 = 0.2, closed(0.0, 1.0);
        /// Blade search radius around the tower top, fraction of image height (thesis: 0.3).
        pub search_radius_frac: f64 = 0.3, closed(0.01, 2.0);
        /// Blade lines whose directions differ by at most this are one blade, degrees (thesis:
        /// "adjacent angles"; 10° separates 120°-spaced blades safely while merging both edges of a
        /// tapered blade).
        pub blade_group_tol_deg: f64 = 10.0, closed(0.0, 60.0);
        /// A blade pointing down within this of the tower direction is removed, degrees.
        pub blade_over_tower_tol_deg: f64 = 15.0, closed(0.0, 90.0);
        /// Expected angle between blades, degrees (thesis: 120).
        pub vote_target_deg: f64 = 120.0, closed(0.0, 180.0);
        /// Tolerance on the blade separation, degrees (thesis: 20).
        pub vote_tol_deg: f64 = 20.0, closed(0.0, 180.0);
        /// A blade with this many votes is removed (thesis: 3).
        pub vote_limit: u32 = 3, closed(1.0, 100.0);
        /// Intersections farther than this from the tower axis line horizontally are discarded,
        /// fraction of the search radius (thesis gives no number; 0.35 R ≈ 0.1 image height covers
        /// the hub–tower gap up to ~45° yaw at 30 m).
        pub hub_max_dx_frac: f64 = 0.35, closed(0.0, 10.0);
        /// Intersections farther than this vertically from the tower top are discarded, fraction of
        /// the search radius ("less strict" than the horizontal limit).
        pub hub_max_dy_frac: f64 = 0.7, closed(0.0, 10.0);
        /// Minimum number of blades for a detection (thesis: 2).
        pub min_blades: u32 = 2, closed(2.0, crate::MAX_BLADES_F);
        /// The tower width is measured this far below the tower top, fraction of image height (just
        /// under the nacelle, where the tower diameter is the known top diameter).
        pub tower_width_below_top_frac: f64 = 0.05, closed(0.0, 1.0);
    }
}

impl ThesisParams {
    /// Checks the ranges and that each lower threshold lies below its upper one.
    fn validate(&self) -> Result<(), ParamError> {
        let section = "detect.thesis";
        self.check_ranges(section)?;
        let c = Check::new(section);
        c.less(
            "pyramid_min_side_px",
            self.pyramid_min_side_px as f64,
            "pyramid_max_side_px",
            self.pyramid_max_side_px as f64,
        )?;
        c.less(
            "canny_low",
            self.canny_low,
            "canny_high",
            self.canny_high + f64::EPSILON,
        )
    }
}

hubtrack_types::params! {
    /// Parameters of the default (robust) pipeline; see `robust/mod.rs` for the steps.
    pub struct DefaultParams {
        /// Downsample (at least once) until both sides are at most this, px. 500 keeps the
        /// 1920×1080 → 480×270 working size of the thesis, which fits the 5 ms budget.
        pub pyramid_max_side_px: u32 = 500, closed(16.0, 4096.0);
        /// Stop downsampling before any side would drop below this, px.
        pub pyramid_min_side_px: u32 = 200, closed(16.0, 4096.0);
        /// Video frames: the first halving averages 2×2 pixels of the colour frame (then grey)
        /// instead of converting the full frame to grey and applying the Gaussian `pyrDown`; the
        /// further levels are `pyrDown`s either way. The full-size grey conversion was the
        /// costliest step of the default mode: with the box step the pyramid of a 1920×1080 BGR
        /// frame takes 1.25 instead of 1.75 ms (single-threaded, frames not in the cache).
        /// Synthetic hits over seeds 2026, 77, 500, 11–14 (200 per class): 93.7 / 92.5 / 92.3 /
        /// 91.8 / 92.8 / 92.3 / 94.0 % → 94.0 / 93.7 / 92.2 / 91.7 / 92.8 / 92.2 / 93.2 %; false
        /// positives 7 → 12 of 336 negatives (mast tops against the horizon). Still photos
        /// (`hubtrack detect`, no time budget) keep `pyrDown`, as their models were trained; the
        /// thesis mode always uses it.
        pub box_first_level: bool = true;
        /// Canny high threshold = this percentile (0..1) of the Sobel L1 gradient magnitude, so the
        /// edge density follows the image contrast instead of a fixed level.
        pub canny_high_percentile: f64 = 0.95, closed(0.0, 1.0);
        /// Lower clamp of the adaptive high threshold (Sobel L1 units, max 2040): below this a
        /// "gradient" is sensor noise even in a flat sky.
        pub canny_high_min: f64 = 100.0, closed(1.0, 4096.0);
        /// Upper clamp of the adaptive high threshold: the thesis's 400 already keeps every turbine
        /// edge, more would drop low-contrast blades against textured ground.
        pub canny_high_max: f64 = 200.0, closed(1.0, 4096.0);
        /// Canny low threshold as a fraction of the high one (the classic 1:2 – 1:3 ratio).
        pub canny_low_ratio: f64 = 0.5, closed(0.05, 1.0);
        /// Hough accumulator distance resolution, px.
        pub hough_rho_px: f64 = 1.0, closed(0.1, 10.0);
        /// Hough accumulator angle resolution, degrees.
        pub hough_theta_deg: f64 = 1.0, closed(0.05, 10.0);
        /// Hough accumulator threshold, as a fraction of image height (votes).
        pub hough_threshold_frac: f64 = 0.1, closed(0.001, 1.0);
        /// Minimum Hough segment length, fraction of image height.
        pub hough_min_length_frac: f64 = 0.08, closed(0.001, 1.0);
        /// Maximum gap inside one Hough segment, fraction of image height.
        pub hough_max_gap_frac: f64 = 0.02, closed(0.0, 1.0);
        /// Each edge pixel votes only for line normals within this angle of its own gradient
        /// direction, degrees (`hough.rs`): a straight edge's gradients are its normal, so its
        /// votes are kept while the cost drops from 180 to 2·tol + 1 bins per pixel and texture
        /// stops voting for lines it is not on. Sobel directions on a clean 1-px edge scatter by
        /// a few degrees, on a jagged or blurred one by up to ~8°. 90 = every angle, as OpenCV's
        /// `HoughLinesP`.
        pub hough_orientation_tol_deg: f64 = 10.0, closed(0.0, 90.0);
        /// At most this many segments (the longest) enter the geometry, bounding its O(n²) steps.
        pub max_segments: usize = 200, closed(2.0, 10_000.0);
        /// Collinear merge: maximum angle between two segments, degrees.
        pub merge_angle_deg: f64 = 3.0, closed(0.0, 30.0);
        /// Collinear merge: maximum perpendicular offset, px.
        pub merge_offset_px: f64 = 2.0, closed(0.0, 50.0);
        /// Collinear merge: maximum gap between the segments along the line, fraction of image
        /// height.
        pub merge_gap_frac: f64 = 0.05, closed(0.0, 1.0);
        /// Lines longer than this fraction of the image width and within `horizon_max_tilt_deg` of
        /// horizontal (after roll) are horizon/ridge candidates and never blades.
        pub horizon_min_length_frac: f64 = 0.4, closed(0.0, 2.0);
        /// See `horizon_min_length_frac`, degrees from horizontal.
        pub horizon_max_tilt_deg: f64 = 8.0, closed(0.0, 45.0);
        /// Through a calibrated lens that bends lines (fisheye, plumb_bob), the Hough lines are
        /// judged undistorted, and level pieces within this of one straight line (fraction of
        /// the image height) count together toward `horizon_min_length_frac`: the lens bends
        /// the horizon into an arc that the Hough transform cuts into pieces, each too short to
        /// be a horizon, and the pieces beside a mast passed for blades (fisheye negatives:
        /// 5.5 % false positives). 0: each line on its own, as through a pinhole.
        pub horizon_piece_tol_frac: f64 = 0.01, closed(0.0, 0.2);
        /// A horizon candidate whose edge pairs with another into a slender band (`pair_*`) that
        /// narrows by at least this ratio from one end to the other is a blade lying level, not a
        /// horizon, and stays usable. A horizon is a single line; a road or a field strip is a
        /// band of even width (ratio ~1; a road beside a real turbine paired so, untapered). 0
        /// disables the exception.
        pub horizon_band_min_taper: f64 = 1.25, closed(0.0, 100.0);
        /// Convergence: only segments at least this long (fraction of image height) propose hub
        /// candidates.
        pub candidate_min_length_frac: f64 = 0.1, closed(0.0, 2.0);
        /// Convergence: two proposing segments must differ in direction by at least this, degrees.
        pub candidate_min_angle_deg: f64 = 25.0, closed(0.0, 90.0);
        /// Convergence: a proposal must lie within this fraction of a segment's length beyond its
        /// nearer end (blades start at the hub, they do not pass through it).
        pub candidate_end_reach_frac: f64 = 0.6, closed(0.0, 10.0);
        /// Convergence: a proposal may lie at most this fraction of a segment's length inside it.
        pub candidate_inside_frac: f64 = 0.1, closed(0.0, 0.5);
        /// Clustering radius of the candidate proposals, fraction of image height.
        pub cluster_radius_frac: f64 = 0.04, closed(0.001, 1.0);
        /// A supporting blade line must pass within this of the hub candidate, fraction of image
        /// height (blade edges are offset from the blade axis by half the root chord).
        pub support_line_dist_frac: f64 = 0.03, closed(0.0, 1.0);
        /// A supporting blade line's nearer end must lie within this of the candidate, fraction of
        /// image height.
        pub support_end_dist_frac: f64 = 0.15, closed(0.0, 2.0);
        /// Lines within this angle are one blade, degrees.
        pub blade_group_tol_deg: f64 = 8.0, closed(0.0, 60.0);
        /// Two blades closer than this in angle are merged / not counted apart, degrees.
        pub blade_min_separation_deg: f64 = 30.0, closed(0.0, 120.0);
        /// Two "blades" at least this far apart (degrees) are the two halves of one straight line
        /// through the candidate (a horizon, field border or mast hidden behind it), not blades:
        /// both are dropped. Two of a rotor's blades, 120° apart on the rotor plane, are seen this
        /// close to opposite only from nearly edge-on (at 60° yaw at most ~140° apart, at 78°
        /// ~160°). 180 = off, the default: at 170 the rule removes false positives (masts whose
        /// top passes for a blade, field borders on both sides, a chimney the horizon crosses:
        /// held-out scenes 7.0 → 3.5 %, the fisheye 6.0 → 5.0 %) with hits within 2 points and
        /// the photos unchanged, but flown the track is lost more often close in, and `fly
        /// --random-setup` seed 98 came 1.21 m from the rotor plane on a distance read long after
        /// such a loss (CHANGELOG 2026-11-30).
        pub blade_max_separation_deg: f64 = 180.0, closed(120.0, 180.0);
        /// Expected angle between blades, degrees.
        pub blade_target_deg: f64 = 120.0, closed(0.0, 180.0);
        /// Tolerance on the blade separation (larger than the thesis's to allow oblique views),
        /// degrees.
        pub blade_sep_tol_deg: f64 = 45.0, closed(0.0, 180.0);
        /// Without a tracker's prediction (acquisition, still photos), a candidate whose seen
        /// blades (two or more) all lie within this of the world's vertical or horizontal is no
        /// hub: three blades 120° apart always have one 30° from both (20° at 45° of yaw or
        /// pitch), while roofs, chimney rims, a mast with its stays and field borders at the
        /// horizon meet at right angles. On the cross-domain sets' frames without a turbine it
        /// takes false positives from 7.5 to 4.0 % in the held-out scenes (chimneys), 3.0 to
        /// 1.5 % through the 60° lens, 7.0 to 5.0 % through the fisheye, hits unchanged (one of
        /// 1 260 lost, one gained). Not while tracking: there it dropped close-in detections of
        /// the hub, and two of 240 `fly --random-setup` flights came within 3 m of the rotor.
        /// Degrees, range [0, 20]; 0 = off.
        pub square_blades_max_deg: f64 = 10.0, closed(0.0, 20.0);
        /// Tower lines: maximum tilt from vertical after roll, degrees (larger than the thesis's
        /// because the wide lens bends lines and unknown roll is searched).
        pub tower_max_tilt_deg: f64 = 8.0, closed(0.0, 45.0);
        /// Tower lines must reach above this far below the candidate hub, fraction of image height.
        pub tower_top_max_below_frac: f64 = 0.15, closed(0.0, 2.0);
        /// Tower lines may start at most this far above the candidate hub, fraction of image height
        /// (the tower top hides behind the nacelle; a line passing the hub is no tower top).
        pub tower_top_max_above_frac: f64 = 0.03, closed(0.0, 2.0);
        /// Tower lines may be this far horizontally from the hub candidate, fraction of image
        /// height.
        pub tower_max_dx_frac: f64 = 0.12, closed(0.0, 2.0);
        /// Tower seeds (not the blade/tower classification): with a spinner circle of radius r,
        /// tower lines may reach this many r below the hub when that is more than
        /// `tower_top_max_below_frac`; at close range the tower top, under the nacelle, is ~1.1 r
        /// below the hub centre. Range [0, 10].
        pub tower_top_max_below_radii: f64 = 1.5, closed(0.0, 10.0);
        /// ... and may be this many r from the hub horizontally when that is more than
        /// `tower_max_dx_frac`: a tower edge lies (overhang·sin ψ + tower radius)·f/depth from the
        /// hub, ≤ 2 r up to ψ = 30°. Range [0, 10]. (Not for the classification: there a grown
        /// window takes the edges of a blade pointing down for tower lines and drops the blade.)
        pub tower_max_dx_radii: f64 = 2.0, closed(0.0, 10.0);
        /// A blade pointing down in front of the tower, shifted by the yaw, makes a band about
        /// twice as wide. With a tracker's distance d (the detect stage has one; photos do not) a
        /// band may be at most this factor narrower or wider than f·tower_top_diameter_m / (d +
        /// hub_tower_gap_m). Range [1, 10].
        pub tower_width_hint_tol: f64 = 1.5, closed(1.0, 10.0);
        /// With a spinner circle of radius r, a tower band is at least this many r wide: the tower
        /// top (2.2 m), farther than the spinner (3.2 m), is 0.67–1.25 r from 4 m to 40 m.
        /// Range [0, 10].
        pub tower_width_min_radii: f64 = 0.5, closed(0.0, 10.0);
        /// ... and at most this many r wide. Range [0, 10].
        pub tower_width_max_radii: f64 = 1.6, closed(0.0, 10.0);
        /// ... and at most this factor narrower or wider than the width the spinner's radius
        /// implies: the spinner gives the hub's distance f·R/r, the tower top is
        /// `tower_top_diameter_m` wide `hub_tower_gap_m` farther (1.24 r at 38 m, 0.75 r at 5 m).
        /// Without it the shading ramp of a side-lit tower passed for its far edge at 38 m (0.6 r):
        /// the distance read 64–71 m and the tracker's width window then kept the true band out
        /// (`fly` seed 335). 0 = off. Range 0 or [1, 10].
        pub tower_width_spinner_tol: f64 = 1.5, zero_or_closed(1.0, 10.0);
        /// When the Hough lines give no tower (HoughLinesP's walk along a jagged, slightly tilted
        /// edge drops the short piece with its votes, so an edge in plain view can go missing), the
        /// horizontal gradient below a detected hub is scanned for near-vertical edges: from this
        /// far below the hub, fraction of image height, range [0, 1] ...
        pub tower_scan_start_frac: f64 = 0.06, closed(0.0, 1.0);
        /// ... or this many spinner radii when that is more (the nacelle bottom is ~1.1 r down),
        /// range [0, 10].
        pub tower_scan_start_radii: f64 = 1.2, closed(0.0, 10.0);
        /// A scanned edge's mean gradient must be this many times the mean over all positions.
        /// Range [1, 100].
        pub tower_scan_min_salience: f64 = 3.0, closed(1.0, 100.0);
        /// Without a roll hint, the roll is searched in ±this range, degrees.
        pub roll_search_deg: f64 = 10.0, closed(0.0, 45.0);
        /// Search radius around `hints.predicted_hub_px`, fraction of image height: candidates
        /// inside it get `prediction_bonus` added to their score.
        pub prediction_radius_frac: f64 = 0.15, closed(0.0, 2.0);
        /// Score bonus (confidence units) for candidates near the predicted hub.
        pub prediction_bonus: f64 = 0.1, closed(0.0, 1.0);
        /// A spinner candidate whose circle is within this factor of the radius the tracker's
        /// distance expects ...
        pub spinner_size_match_tol: f64 = 1.25, closed(1.0, 10.0);
        /// ... gets this added to its score and confidence (the spinner at the predicted size is
        /// the strongest single cue at close range; blade lines meeting near it can still outscore
        /// it).
        pub spinner_size_match_bonus: f64 = 0.15, closed(0.0, 1.0);
        /// Confidence weight of having 2 blades.
        pub conf_two_blades: f64 = 0.3, closed(0.0, 1.0);
        /// Confidence weight of having 3 blades.
        pub conf_three_blades: f64 = 0.5, closed(0.0, 1.0);
        /// Two blades whose missing third would point straight down (within this, degrees) count
        /// as three when a tower supports the candidate: a blade pointing down lies over the tower
        /// and its edges are the tower's (or hidden by it). The third direction of a rotor is taken
        /// opposite the bisector of the two seen blades; 0 turns the rule off.
        pub hidden_blade_tol_deg: f64 = 15.0, closed(0.0, 60.0);
        /// Confidence added when a tower supports the candidate.
        pub conf_tower: f64 = 0.25, closed(0.0, 1.0);
        /// Confidence added when the blade separations fit a (possibly skewed) 120° rotor.
        pub conf_geometry: f64 = 0.15, closed(0.0, 1.0);
        /// Confidence added when at least two blades show both edges (a blade is a band with two
        /// edges on either side of its axis; field borders, wires and horizons give single lines).
        pub conf_paired: f64 = 0.1, closed(0.0, 1.0);
        /// Confidence removed per blade beyond three (clutter: textured ground, lattice masts).
        pub conf_extra_blade_penalty: f64 = 0.1, closed(0.0, 1.0);
        /// With `ranker.ranking = "rules"`: `detected` requires at least this confidence.
        pub min_confidence: f64 = 0.75, closed(0.0, 1.0);
        /// The tower width is measured this far below the tower top, fraction of image height.
        pub tower_width_below_top_frac: f64 = 0.05, closed(0.0, 1.0);
        /// Tower partner edge: the tower is at least this wide, fraction of image height (a 2.2 m
        /// tower top at 60 m with the GoPro lens is ~3 %).
        pub tower_min_width_frac: f64 = 0.02, closed(0.0, 1.0);
        /// Tower partner edge: the tower is at most this wide, fraction of image height (~17 % at
        /// 10 m).
        pub tower_max_width_frac: f64 = 0.25, closed(0.0, 1.0);
        /// Tower partner edge: its mean gradient response (opposite sign to the found edge, over
        /// all rows from the tower top down) must reach this fraction of the found edge's own
        /// (a tower lit from one side has one strong and one weak edge); else the axis is unknown
        /// and no tower is reported (one edge is half a width off the axis).
        pub tower_partner_min_ratio: f64 = 0.15, closed(0.0, 1.0);
        /// Tower partner edge: its response must also be this many times the mean response over
        /// all offsets searched (it must stand out of the background texture).
        pub tower_partner_min_salience: f64 = 4.0, closed(0.0, 1000.0);
        /// Tower partner edge of the seed's own gradient sign: taken instead of the best
        /// opposite-sign one when it lies beyond that one and its response is at least this
        /// fraction of it. A tower lit from one side against ground of a middle shade is darker
        /// than the ground at one limb and brighter at the other: both edges have one sign, and
        /// the only opposite-sign response is the shading inside, a ramp or, in direct sun, a
        /// sharp terminator (widths read ~0.6x; the slim turbine's tower through the 90°
        /// 640×480 lens 0.65× at 20–30 m), and the lit limb may be barely brighter than the
        /// ground. A large value (1000) disables it.
        pub tower_same_sign_partner_min_ratio: f64 = 0.5, closed(0.0, 1000.0);
        /// A tower edge moves outward to the end of its shading ramp: as far as the summed gradient
        /// response along the shifted edge stays at least this fraction of the response at the
        /// fitted (steepest) position. A side-lit tower's dark limb on dark ground has no edge,
        /// only the end of a ramp; a sharp edge's response halves within a pixel and stays put. ≥ 1
        /// disables it.
        pub tower_ramp_min_frac: f64 = 0.8, closed(0.0, 1.0);
        /// ... by at most this fraction of the tower width.
        pub tower_ramp_max_frac: f64 = 0.3, closed(0.0, 1.0);
        /// The tower band's width at the image bottom over its width at its top must be at least
        /// this: a blade pointing down narrows toward its tip (~0.65 over the visible part), the
        /// tower keeps its image width within ~10 %. A blade pointing down in front of the tower
        /// merges with it into one band that narrows by ~13 % (rendered approaches at ~40 m),
        /// whose width and hub–tower gap are both wrong: 0.9 rejects it (0.85 let it through).
        pub tower_min_width_ratio: f64 = 0.9, closed(0.0, 10.0);
        /// ... and at most this times the widening the tower's taper gives over the visible rows
        /// (`1 + tower_taper · rows / top width`, see `tower_taper`), while a band from a tower
        /// edge to the edge of a blade crossing it widens fast.
        pub tower_max_width_ratio: f64 = 1.15, closed(0.0, 10.0);
        /// Tower taper: growth of its diameter per metre down, m/m (steel towers ~0.02–0.035; the
        /// renderer's 2.2 m top and 4.3 m base over ~70 m: 0.03). Its rows are at about the same
        /// depth, so over `rows` px below a top `w` px wide (`rows·D/w` metres) the band widens by
        /// `tower_taper · rows / w`: ~30 % at 30 m with the wide-angle camera, up to ~2x when the
        /// whole tower is in view. 0 = the tower keeps its width.
        pub tower_taper: f64 = 0.03, closed(0.0, 1.0);
        /// When a detected blade, the strongest blade at 120° steps, or the third blade two
        /// detected ones about 120° apart imply is within this of straight down, degrees, that
        /// blade hides the tower ...
        pub tower_blade_down_tol_deg: f64 = 12.0, closed(0.0, 60.0);
        /// The third blade two detected ones imply counts only with the tracker's hub distance
        /// at most this, m: close in, that blade hides the tower (AP `fly` seed 19 at 10 m: a
        /// band 1.3x the tower's width read 5 m at 8.9 m); farther out a band through the hub is
        /// often the tower below the blade's tip, and rejecting it costs the yaw (AP `fly` seed
        /// 11 at 36 m: no yaw for 90 s with the rule at every distance). 0 = never.
        pub tower_blade_implied_max_distance_m: f64 = 20.0, closed(0.0, 1000.0);
        /// A tower band whose axis, halfway down, lies on the ray of a blade (detected, or placed
        /// 120° or 240° from a detected one) within this of straight down, degrees, is that blade,
        /// or that blade merged with one tower edge (within `tower_blade_axis_tol_frac` of the
        /// ray). `fly` seed 279: a blade at 168° (detected blades 268°, 48°, 90°) read as the tower
        /// at 16–24 m with the gap's sign wrong. 0 = only the check at the hub's row. Range [0,
        /// 60].
        pub tower_blade_ray_tol_deg: f64 = 25.0, closed(0.0, 60.0);
        /// ... but not rays within this of straight down, degrees. Such a blade's band misleads
        /// too (rendered at 19 m: gaps 40–60 px off), but it covers the tower, so without it no
        /// tower and no distance is measured while that blade hangs in front (`fly` seed 340: no
        /// distance at 37 m for 120 s). Fresh `fly` seeds 241–400: 145 of 160 with 5, 143 with 0,
        /// 136 without the ray rule. Range [0, 60].
        pub tower_blade_ray_min_deg: f64 = 5.0, closed(0.0, 60.0);
        /// With a blade pointing down (see `tower_blade_down_tol_deg`) and the tracker's hub
        /// distance at most this, m, no tower is measured. The blade hangs in front of the tower
        /// (the hub overhang, ~4 m) and is about as wide near the hub: from the front, for yaws the
        /// approach leaves (|ψ| ≲ 20°), it hides the tower over the whole image height, or all
        /// but one edge, and the band seen is the blade or the blade and one tower edge merged
        /// (rendered flights: 1.4–1.9× or 0.55× the tower's width, the hub–tower gap of the wrong
        /// sign). Distance then comes from the spinner and yaw from the blade skew and the
        /// turbine-heading memory. Farther out the tower shows below the blade's tip: from about
        /// the blade length over the tangent of half the vertical field of view (33.5 m /
        /// tan 31° ≈ 56 m for the modelled turbine and the GoPro), so 60 is the value to use.
        /// Default 0 = always measure: with 60 the rendered sequences' yaw and distance tails
        /// shrink (`eval --sequence --seed 7`: yaw p90 27 → 7°, distance p90 52 → 20 %), but the
        /// flights lose, as no other cue gives the yaw's sign (`fly` seeds 1–39: 29 of 39
        /// against 32, the failures still on the final yaw).
        pub tower_blade_down_max_distance_m: f64 = 0.0, closed(0.0, 1000.0);
        /// Nacelle search (`nacelle.rs`; needs a tracker's distance): rows scanned either side of
        /// the hub's row, metres at the hub's depth. The nacelle is 3.5 m high and its rear, 11 m
        /// behind the hub, looks smaller: ±1 m stays on its side face at 10–40 m.
        pub nacelle_band_half_m: f64 = 1.0, closed(0.0, 20.0);
        /// ... columns from this far beyond the wider of the spinner and the nacelle's front
        /// corners (the turbine's `spinner_diameter_m` and `nacelle_width_m`), m at the hub's
        /// depth: those show on both sides whatever the yaw. 0.3: 2 m beside the hub for the
        /// thesis turbine (1.6 m spinner radius, 1.7 m half width).
        pub nacelle_clearance_m: f64 = 0.3, closed(0.0, 20.0);
        /// ... to where the nacelle's rear corner appears at this relative yaw, degrees (55: 10.2
        /// m beside the hub for the thesis turbine's 11.2 m from hub to rear face).
        pub nacelle_max_yaw_deg: f64 = 55.0, closed(1.0, 90.0);
        /// ... the best column's median signed horizontal Sobel response must be at least this
        /// (8-bit 3×3 Sobel: a step of `c` grey levels gives `4c`; 40 = a 10-level step) ...
        pub nacelle_min_response: f64 = 40.0, closed(0.0, 4080.0);
        /// ... and this many times the other side's best (one side only sticks out).
        pub nacelle_min_ratio: f64 = 2.0, closed(1.0, 1000.0);
        /// ... and a tower band whose axis passes within this of the hub, fraction of image
        /// height, is that blade, not the tower.
        pub tower_blade_axis_tol_frac: f64 = 0.025, closed(0.0, 1.0);
        /// Edge pairing: both edges of a blade (or the tower) must be at least this long, fraction
        /// of image height.
        pub pair_min_length_frac: f64 = 0.06, closed(0.0, 2.0);
        /// Edge pairing: the two edges differ in direction by at most this, degrees (blades taper,
        /// so their edges converge slightly toward the tip).
        pub pair_max_angle_deg: f64 = 10.0, closed(0.0, 45.0);
        /// Edge pairing: the edges must overlap along their direction by at least this fraction of
        /// the shorter one.
        pub pair_min_overlap_frac: f64 = 0.5, closed(0.0, 1.0);
        /// Edge pairing: the band must be at least this wide at both ends, working px (closer
        /// edges are one edge seen twice).
        pub pair_min_width_px: f64 = 2.5, closed(0.0, 100.0);
        /// Edge pairing: the band may be at most this wide at either end, fraction of image height
        /// (a blade root seen from a few metres).
        pub pair_max_width_frac: f64 = 0.15, closed(0.0, 1.0);
        /// Edge pairing: mean band width over axis length at most this (blades are slender).
        pub pair_max_width_to_length: f64 = 0.5, closed(0.0, 10.0);
        /// A blade axis may end at most this many band widths (at its nearer end) short of the hub:
        /// blades start at the spinner rim, whose radius grows with the root chord as the camera
        /// approaches.
        pub axis_reach_widths: f64 = 3.0, closed(0.0, 20.0);
        /// A supporting blade axis passes within this of the hub, fraction of image height, ...
        pub axis_line_dist_frac: f64 = 0.015, closed(0.0, 1.0);
        /// ... plus this angle (degrees) times the distance from its nearer end.
        pub axis_angle_tol_deg: f64 = 3.0, closed(0.0, 45.0);
        /// Vote weight of an axis–axis intersection relative to an edge–edge one.
        pub axis_proposal_weight: f64 = 2.0, closed(0.0, 100.0);
        /// Spinner step: the best this many candidates (with at least two blades) are searched for
        /// a spinner circle; 0 disables the step.
        pub spinner_candidates: usize = 3, closed(0.0, 10.0);
        /// Spinner step: half side of the square searched around a candidate, fraction of image
        /// height.
        pub spinner_search_frac: f64 = 0.4, closed(0.01, 1.0);
        /// Spinner step: a circle's centre may be at most this far from the candidate, fraction of
        /// image height (blade-edge convergence is biased toward the spinner rim).
        pub spinner_max_offset_frac: f64 = 0.15, closed(0.0, 1.0);
        /// Spinner step: smallest circle radius searched, working px (below this the spinner is a
        /// few pixels and edge convergence is accurate enough).
        pub spinner_min_radius_px: f64 = 4.0, closed(1.0, 1000.0);
        /// Spinner step: largest circle radius searched, fraction of image height (without a
        /// tracker's distance, at least; see `spinner_closest_m`).
        pub spinner_max_radius_frac: f64 = 0.32, closed(0.01, 1.0);
        /// Spinner step without a tracker's distance: circles are searched up to the radius the
        /// spinner has this close through the camera's lens (`detect.camera`), when that is more
        /// than `spinner_max_radius_frac` (up to `spinner_hint_max_radius_frac`): a still photo or
        /// the first frame through a narrow lens at the end of an approach shows the spinner half
        /// the height or more across, its rim cut by the frame. Metres; the approach's target is
        /// 5 m, and 4 m leaves room for its tolerance.
        pub spinner_closest_m: f64 = 4.0, closed(0.5, 100.0);
        /// ... and with the tracker's distance, when the radius it expects asks for more: a
        /// narrow lens at the approach's end sees the spinner larger than that (a 3.6 m spinner
        /// at 5 m is 0.33 of the height through a 100° lens at 16:9, 0.5–0.7 through a 60° one),
        /// its rim then partly outside the frame.
        pub spinner_hint_max_radius_frac: f64 = 0.75, closed(0.01, 2.0);
        /// Spinner step with the tracker's distance: only radii from this times the radius expected
        /// at that distance (`detect.camera.spinner_diameter_m`) are searched, within the two
        /// limits above. The window allows the distance to be off by a factor of two either way
        /// (the tracker's distance is good to ~30 %); the narrower search is faster and finds fewer
        /// circles of the wrong size. 0 = search all radii always.
        pub spinner_hint_radius_lo: f64 = 0.5, closed(0.0, 1.0);
        /// ... up to this times the expected radius.
        pub spinner_hint_radius_hi: f64 = 2.0, closed(1.0, 100.0);
        /// Spinner step: centre accumulator cell and radius step of the gradient circle vote,
        /// working px.
        pub spinner_cell_px: f64 = 2.0, closed(0.5, 20.0);
        /// Spinner step: an edge pixel is on a rim when its gradient is within this of the radial
        /// direction, degrees.
        pub spinner_radial_tol_deg: f64 = 25.0, closed(0.0, 90.0);
        /// Spinner step: smallest fraction of the rim covered by edge pixels (blade roots, the
        /// nacelle and shading hide parts of it).
        pub spinner_min_coverage: f64 = 0.4, closed(0.0, 1.0);
        /// Spinner step: the searches around hub candidates vote for centres with every
        /// this-many-th edge point (in row order), and measure rim coverage with all of them
        /// (`close_spinner_vote_every` for the whole-image search). 1 (the default): every point;
        /// small spinners have few rim points to spare, and 2 loses photo hits.
        pub spinner_vote_every: u32 = 1, closed(1.0, 16.0);
        /// Spinner step: centre peaks of the vote whose rims are measured, per search. Small
        /// circles (corners, blade–nacelle junctions) take the strongest accumulator peaks, and a
        /// close spinner is often only the 4th to 12th peak, hence 12. More peaks also find more
        /// false circles in textured ground; `spinner_max_interior_density` removes those. The rims
        /// cost ~0.5 ms a frame; 8 peaks save a third of that for slightly fewer close hits.
        pub spinner_peaks: u32 = 12, closed(1.0, 64.0);
        /// ... when the tracker's distance gives the expected radius (the radii searched are then
        /// 0.5–2× that one, around the predicted hub): at 5 m under an overcast sky the grey
        /// spinner on grey blades shows 25–40 % of its rim, and the track was lost at the target.
        pub spinner_hint_min_coverage: f64 = 0.25, closed(0.0, 1.0);
        /// A circle enclosing the best-covered spinner circle replaces it (the silhouette round a
        /// ring on the spinner's face) only when its rim coverage is at least this fraction of the
        /// inner one's; a circle drawn by blade edges crossing near the spinner is covered less.
        /// 0 = always the outer one.
        pub spinner_nest_min_coverage_ratio: f64 = 0.8, closed(0.0, 10.0);
        /// A small circle is a spinner only if, measured from its centre, the strongest blade-line
        /// candidate within `spinner_max_offset_frac` keeps at least this fraction of its blade
        /// support (blade length) in the same directions: the blades radiate from the spinner,
        /// while a round patch beside it sees them pass by. Seen obliquely from 30–40 m, a backlit
        /// nacelle's rear is such a patch (rim 0.73 against the spinner's 0.45, 0.49 of the
        /// support kept): in two recorded `fly` flights 40 % of the detections sat on it, > 3 % of
        /// the image height off toward the nacelle, and the hub–tower gap and the nacelle step
        /// read the yaw's sign wrong from there. 0 = off. `hubtrack eval` synthetic hits 64.7 →
        /// 65.5 % (far 67.5 → 70 %); applied to all radii 59.5 %. Candidates with fewer than two
        /// blades (the tracker's predicted hub at close range) are not checked ...
        pub spinner_min_kept_support: f64 = 0.7, closed(0.0, 1.0);
        /// ... nor circles larger than this, working px (8 px: the modelled spinner from ~30 m
        /// with the wide-angle lens): a spinner a few pixels across is any round blob, a larger
        /// one shows its own outline.
        pub spinner_kept_support_max_radius_px: f64 = 8.0, closed(0.0, 1000.0);
        /// Spinner step: a circle whose inner 70 % holds more Canny edge pixels than this per px²
        /// is clutter (textured ground, a tower with blades and horizon), not the smooth spinner.
        pub spinner_max_interior_density: f64 = 0.1, closed(0.0, 1.0);
        /// Still photos only (`hubtrack detect`, `hubtrack eval` on photos; never the detect
        /// stage, which keeps its frame budget): detect also one pyramid level finer and keep the
        /// more confident detection. Real development photos: 39.6 → 49.1 % hits (far 0 → 1 of
        /// 9, the rest medium and close turbines whose blades are thin at the working size), no
        /// false positive more; ~4× the time per photo. Default true.
        pub still_finer_level: bool = true;
        /// Still photos only (`hubtrack detect`, the photos of `hubtrack eval`; never the detect
        /// stage): detect also in the photo's mirror image and combine the two, as test-time
        /// augmentation does — the rules and networks are not exactly mirror-symmetric, so the two
        /// views err apart. `"off"`; `"average"`: hubs found in both within
        /// `still_mirror_agree_frac` are averaged, nothing else changes; `"either"`: as average,
        /// and otherwise the more confident of the two detections stands (a hub found in one view
        /// only counts); `"both"`: only hubs both views find count (averaged). Doubles the time per
        /// photo. Default `"either"`: the most hits on photos and photo-like rendered views, at a
        /// few more rendered negatives detected; `"both"` detects the fewest negatives and loses up
        /// to 9 points of hits.
        pub still_mirror: StillMirror = StillMirror::Either;
        /// Hubs of the two views at most this far apart are one hub (averaged), fraction of the
        /// image height. Range [0, 0.5].
        pub still_mirror_agree_frac: f64 = 0.06, closed(0.0, 0.5);
        /// Spinner step: with a circle of radius r, blade lines and axes may end up to this many r
        /// from its centre (blades start at the spinner rim).
        pub spinner_reach_radii: f64 = 2.0, closed(0.0, 10.0);
        /// Confidence added when a spinner circle is found with at least two blades starting at its
        /// rim.
        pub conf_spinner: f64 = 0.2, closed(0.0, 1.0);
        /// Close range (thesis future work: Hough circles on the hub): a spinner circle at least
        /// this large, fraction of image height, with two blades starting at its rim, is a hub by
        /// itself — at 5–8 m the blades run out of the frame and their edge pairs are too far apart
        /// to be grouped, so blade counting alone fails exactly where the approach ends.
        pub close_spinner_radius_frac: f64 = 0.12, closed(0.0, 1.0);
        /// Lowest confidence of a close-range spinner (see `close_spinner_radius_frac`).
        pub conf_close_spinner: f64 = 0.8, closed(0.0, 1.0);
        /// Least rim coverage of a close-range spinner found by the whole-image search (see
        /// `close_spinner_radius_frac`); `spinner_min_coverage` applies near blade candidates. At
        /// 5–8 m the spinner's rim runs partly against blade roots and the nacelle of about its
        /// own shade, where Canny marks no edge. 0.4 → 0.3: synthetic close hits 61 → 71 % (seed
        /// 2026; seed 77 54.5 → 62 %) at one or two more false positives in 48 negatives (a
        /// cloud's edge); 0.25 detects 10 of 48 negatives.
        pub close_spinner_min_coverage: f64 = 0.3, closed(0.0, 1.0);
        /// The whole-image close-range search votes for centres with every this-many-th edge point
        /// (in row order), and measures rim coverage with all of them. Its circles are at least
        /// `close_spinner_radius_frac` of the height in radius, a hundred or more rim points at the
        /// working size, and neighbouring points cast nearly the same vote: 2 (the default) halves
        /// the vote, the costliest part of the search (about 0.6 of 0.9 ms per frame), for about
        /// one close frame in two hundred. 1: every point.
        pub close_spinner_vote_every: u32 = 2, closed(1.0, 16.0);
        /// Centre peaks of the whole-image close-range search whose rims are measured
        /// (`spinner_peaks` for the searches around candidates). 12 as there: fewer peaks save no
        /// measurable time, and 3 lose close hits.
        pub close_spinner_peaks: u32 = 12, closed(1.0, 64.0);
        /// Before acquisition (no tracker's prediction), when the learned heatmap's peak is at
        /// least this probable, the close-range search looks for centres only near it
        /// (`close_spinner_heat_box_frac`), from the edge points that can reach them; below it,
        /// with a prediction, or at 0 (off) over the whole image. The whole-image search costs ~0.6
        /// ms on every frame without a tracker; 0.5 with a box of ±0.2 h saves about half a
        /// millisecond a frame with hits, false positives and flights practically the same.
        pub close_spinner_heat_min: f64 = 0.5, closed(0.0, 1.0);
        /// ... within this of the peak, fraction of the image height (half the box's side).
        pub close_spinner_heat_box_frac: f64 = 0.2, closed(0.01, 1.0);
        /// Without a tracker's prediction, search the whole image for close spinners in every
        /// frame and let each be a candidate, instead of only when nothing else is detected. With
        /// the learned ranking: synthetic hits seeds 2026 / 77 / 500 76.7 / 73.7 / 71.2 → 78.0 /
        /// 74.2 / 72.0 % (close 74.5 → 79.5 % at seed 2026), false positives and photos unchanged;
        /// detect median 2.65 → 3.33 ms single-threaded at 1920×1080 on frames without a tracker.
        pub close_spinner_always: bool = true;
        /// A long line passing within this of a candidate, fraction of image height, and extending
        /// at least `through_margin_frac` beyond it on both sides, puts the candidate on a tower,
        /// mast or wire rather than at a hub (blades and the tower end at the hub).
        pub through_dist_frac: f64 = 0.01, closed(0.0, 1.0);
        /// See `through_dist_frac`, fraction of image height (more than `tower_top_max_above_frac`:
        /// the tower edge may show a little above the hub).
        pub through_margin_frac: f64 = 0.05, closed(0.0, 2.0);
        /// Confidence removed from a candidate that a long line passes through.
        pub conf_through_penalty: f64 = 0.3, closed(0.0, 1.0);
        /// A supporting line with a nearly collinear continuation on the far side of the candidate
        /// (within this angle, degrees, ...) is a horizon, field border or wire that the turbine
        /// hides, not a blade.
        pub occluded_angle_deg: f64 = 3.0, closed(0.0, 45.0);
        /// ... and within this offset from its line, fraction of image height.
        pub occluded_offset_frac: f64 = 0.008, closed(0.0, 1.0);
        /// ... plus, for lines within `occluded_bent_max_tilt_deg` of horizontal (horizons and
        /// field borders, which a wide lens bends), this angle (degrees) times the distance from
        /// the candidate: the continuation drifts off the straight extension farther out.
        pub occluded_bend_deg: f64 = 3.0, closed(0.0, 45.0);
        /// See `occluded_bend_deg`, degrees from horizontal. Only such lines: a blade pointing up
        /// is nearly collinear with the tower below the hub.
        pub occluded_bent_max_tilt_deg: f64 = 20.0, closed(0.0, 90.0);
        /// Blade seen by one edge (`blade.rs`): its partner edge is searched at least this far
        /// from it, working px (closer is the edge's own Sobel spread).
        pub blade_partner_min_width_px: f64 = 2.0, closed(1.0, 100.0);
        /// ... and at most this far, fraction of image height (blade chords reach ~0.1 h at 8 m
        /// with the GoPro).
        pub blade_partner_max_width_frac: f64 = 0.1, closed(0.0, 1.0);
        /// ... at this many points along the edge.
        pub blade_partner_samples: u32 = 9, closed(2.0, 100.0);
        /// ... and must be found at this fraction of them.
        pub blade_partner_min_found_frac: f64 = 0.6, closed(0.0, 1.0);
        /// ... with a response of opposite sign of at least this fraction of the edge's own.
        pub blade_partner_response_ratio: f64 = 0.3, closed(0.0, 10.0);
        /// ... at offsets within this RMS of a straight line, working px.
        pub blade_partner_max_rms_px: f64 = 1.5, closed(0.0, 100.0);
        /// ... whose slope (band width change per px along the blade) is at most this.
        pub blade_partner_max_taper: f64 = 0.15, closed(0.0, 1.0);
        /// Run the learned hub heatmap (`libs/detect/src/heat.rs`, trained on the project's
        /// renderer by `scripts/train-hubnet.sh`) on every frame: it feeds the ranker's `hub_heat`
        /// feature and proposes candidates of its own (`hub_heat_candidate_min`). About 0.8 ms per
        /// frame single-threaded here.
        pub hub_heat: bool = true;
        /// Run the learned networks (heatmap, hub crop, yaw) with the detector's own kernels
        /// (`libs/detect/src/convnet.rs`) on CPUs with AVX2 and FMA, instead of OpenCV's dnn module
        /// (used anyway on other CPUs). Same networks, outputs equal to float rounding, and about
        /// twice as fast (the heatmap ~0.4 instead of ~0.9 ms a frame).
        pub builtin_nets: bool = true;
        /// The `hub_heat` feature of a candidate is the heatmap's largest probability within this
        /// many cells (8 network px, ~1/24 of the width) of it. Range [0, 4]; default 1.
        pub hub_heat_radius_cells: f64 = 1.0, closed(0.0, 4.0);
        /// A heatmap peak at least this probable with no candidate within
        /// `hub_heat_radius_cells` of it becomes a candidate itself (refined to its blades'
        /// crossing like any other). Range [0, 1]; default 0.5 (1 = never).
        pub hub_heat_candidate_min: f64 = 0.5, closed(0.0, 1.0);
        /// Place the detected hub with the learned hub crop network (`heat::HubCropNet`, trained on
        /// the renderer by `scripts/train-hubnet.sh`): a crop of the working level around the
        /// chosen candidate, 0.3 of the frame height on a side, gives a probability per 1/16 of the
        /// crop, and the hub moves to its peak. Blade-edge crossings sit up to a spinner radius or
        /// two beside the hub seen obliquely (the edges are half a chord off the blade axes), more
        /// than the 3 % of the image height a hit allows from 12 m on. About 0.2 ms per frame. Not
        /// while tracking (a tracker's prediction is given): the hub–tower gap and nacelle cues and
        /// the approach's centring work from the blades' crossing. Still photos with `still_models`
        /// use their own crop model (`models/hubcrop-still.onnx`, trained with photo-like views
        /// too: `scripts/train-hubnet.sh crop-still`), which places the hub where the video model
        /// takes a nacelle seen from above for it.
        pub hub_crop: bool = true;
        /// ... when the crop's peak probability is at least this. Range [0, 1]; default 0.5.
        pub hub_crop_min: f64 = 0.5, closed(0.0, 1.0);
        /// ... and lies at most this far from the candidate, fraction of the image height.
        /// Range [0, 0.15]; default 0.1.
        pub hub_crop_max_shift_frac: f64 = 0.1, closed(0.0, 0.15);
        /// ... and at least this far: nearer, the blades' crossing stands (within a cell of the
        /// network's peak, geometry places the hub better on real photos). Fraction of the image
        /// height, range [0, 0.15]; default 0.02, which keeps the network's placement of far hubs
        /// 3–4 % of the height off the crossing.
        pub hub_crop_min_shift_frac: f64 = 0.02, closed(0.0, 0.15);
        /// ... and not when the hub is a spinner circle's centre (the circle places it better) ...
        pub hub_crop_keep_spinner: bool = true;
        /// ... unless the network's peak lies beyond the circle's rim by this many radii: the
        /// circle was drawn by a blade root or the nacelle's end beside the spinner (most rendered
        /// medium-range misses that are detected), and the network sees the hub next to it. Default
        /// 0: the peak outside the circle suffices (more hits than 0.5, or than never keeping the
        /// circle). Range [0, 10]; 10 = never (the rule off).
        pub hub_crop_spinner_escape_radii: f64 = 0.0, closed(0.0, 10.0);
        /// Networks' verdict when the lines found nothing: without a tracker's prediction, a frame
        /// with no detection whose heatmap (`hub_heat`) peaks at least this probably, and whose
        /// crop network (`hub_crop`) then places a hub at least `heat_verify_crop_min` probably
        /// within `hub_crop_max_shift_frac` of that peak, is detected there, with the product of
        /// the two probabilities as its confidence (and no tower, blades or circle). Close in the
        /// spinner fills the frame, its rim and the blade roots are of one shade and the lines give
        /// nothing to rank, while both networks still see the hub: the verdict adds several points
        /// of close and medium hits on rendered frames and photo-like views, without more false
        /// positives thanks to the line rules below (without them the networks take mast tops for
        /// hubs). Range [0, 1]; 1 = off.
        pub heat_verify_min: f64 = 0.5, closed(0.0, 1.0);
        /// See `heat_verify_min`. Range [0, 1].
        pub heat_verify_crop_min: f64 = 0.5, closed(0.0, 1.0);
        /// When the crop network is not that sure of its crop (`CROP_FRAC` of the height, the
        /// size it was trained on), it looks again at the heatmap's peak through crops
        /// `heat_verify_crop_zoom` times wider in turn, up to this many times, and takes the first
        /// look it is sure of (its allowed shift, `hub_crop_max_shift_frac`, wider by as much).
        /// Through a narrow lens or close in, the spinner fills the trained crop and the network
        /// sees no hub in it: 1, 1.5, 2.25 and 3.4 times the crop take the close hits of the
        /// held-out 60° camera from 63 to 78 % and of held-out turbines from 73 to 80 % (`eval
        /// --cross-domain`). Video frames only: on photos the still crop network's wider looks
        /// lose 5 of 43 hits. Range [0, 8]; 0 = the trained crop only.
        pub heat_verify_crop_zooms: u32 = 3, closed(0.0, 8.0);
        /// See `heat_verify_crop_zooms`: each look's crop is this many times wider than the last.
        /// Range [1, 4].
        pub heat_verify_crop_zoom: f64 = 1.5, closed(1.0, 4.0);
        /// ... and lines that end within this of that hub, fraction of the image height, must
        /// include one more than `heat_verify_oblique_deg` from both the vertical and the
        /// horizontal: the networks also take a mast's top for a hub; and no long line may pass
        /// through it (`through_dist_frac`, `through_margin_frac`). Range [0, 0.5].
        pub heat_verify_end_frac: f64 = 0.06, closed(0.0, 0.5);
        /// See `heat_verify_end_frac`, degrees. Range [0, 45].
        pub heat_verify_oblique_deg: f64 = 15.0, closed(0.0, 45.0);
        /// ... and at least one such oblique line must pass within this of it, fraction of the
        /// image height (a blade's edge; from 5 m the spinner's rim is within ~0.3 of the height).
        /// Range [0, 2].
        pub heat_verify_blade_frac: f64 = 0.3, closed(0.0, 2.0);
        /// ... and some line within that reach must rise above it, its far end at least this
        /// far above the horizontal through the hub, degrees: one of three blades 120° apart
        /// always points within 60° of straight up, while a mast's top (its stays, crossbars and
        /// shaft all hang from it or run level) has nothing above it. 20° leaves 10° to the camera's
        /// roll. Range [0, 90]; 0 = off.
        pub heat_verify_rise_deg: f64 = 20.0, closed(0.0, 90.0);
        /// The verdict also replaces a detection whose hub the heatmap rates below this (within
        /// `hub_heat_radius_cells`): the ranking's choice where both networks and the lines around
        /// agree on a hub elsewhere, or the crop network's place for it where they agree on the
        /// same. Higher values gain up to a point of rendered hits, but flights start from such
        /// frames (acquisition, search) and succeed less often with it, so video frames keep 0 and
        /// stills use `still_heat_override_max`. Range [0, 1]; 0 = never.
        pub heat_override_max: f64 = 0.0, closed(0.0, 1.0);
        /// `heat_override_max` for still photos (`Detector::detect_still`): photo-like views
        /// (seeds 2026 / 500) 80.7 / 82.3 → 81.0 / 83.3 % at 0.7. Range [0, 1]; 0 = never.
        pub still_heat_override_max: f64 = 0.7, closed(0.0, 1.0);
        /// Read the relative yaw with the learned yaw network (`heat::HubYawNet`) around a
        /// detected hub, from the tracker's distance or else the spinner circle's (the detection's
        /// `yaw_net_*`; the tracker weighs it in, see `track.yaw.use_net`).
        pub hub_yaw: bool = true;
        /// ... only from this distance, metres (trained from 3.5 m), range [0, 100] ...
        pub hub_yaw_min_distance_m: f64 = 3.5, closed(0.0, 100.0);
        /// ... up to this one, metres (trained to 46 m: the whole approach from 40 m), range
        /// [0, 100]. At 30 m (the first model, trained to 32 m) `fly` seeds 161–360 gave 190 of
        /// 200; at 45 with the model trained to 46 m, 191.
        pub hub_yaw_max_distance_m: f64 = 45.0, closed(0.0, 100.0);
        /// The yaw network trained on the thesis turbine alone (`models/hubyaw-thesis.onnx`)
        /// reads the yaw instead of the one trained on a family of turbines
        /// (`models/hubyaw.onnx`) when every dimension of the turbine the detector is given
        /// (tower top diameter and taper, overhang, spinner, nacelle width and rear) lies within
        /// this fraction of the thesis turbine's (its training scenes vary the tower by 5 %): a
        /// network trained on the operator's own turbine type reads it better than one trained on
        /// many (held out, mean error 2.2–3.9° against 2.5–4.9°; `fly --first-seed 161 --seeds
        /// 120` 119 of 120 against 112). Range [0, 1]; 0 = the family's network always.
        pub hub_yaw_thesis_tolerance: f64 = 0.05, closed(0.0, 1.0);
        /// Close in, read the yaw with a second model trained on views from 3.5–14 m only
        /// (`models/hubyaw-close.onnx`, `scripts/train-hubnet.sh yaw-close`): where the approach
        /// ends, the whole-range model's error is largest (held out, mean 4.0° at 3.5–8 m against
        /// 2.3–2.6° beyond 15 m; the close model 3.3°). Off by default: its error is still a bias
        /// per scene, up to 13° at 5 m, and as the yaw's fallback close in
        /// (`track.yaw.net_fallback_after_s`, `net_fallback_min_deg`) it ends good flights 5–10°
        /// off as often as it saves failing ones ...
        pub hub_yaw_close: bool = false;
        /// ... up to this distance, metres, range [0, 14] (its training range).
        pub hub_yaw_close_max_distance_m: f64 = 12.0, closed(0.0, 14.0);
        /// How the hub is picked among the candidates.
        pub ranker: RankerParams = RankerParams::default();
        /// Still photos (`hubtrack detect`, the photos of `hubtrack eval`) use their own learned
        /// heatmap (`models/hubnet-still.onnx`), hub crop (`models/hubcrop-still.onnx`) and
        /// `still_ranker`, all trained with photo-like rendered views too (drone photos'
        /// viewpoints: from above, among wind farms, the hub anywhere; see the README, "Photo-like
        /// views"); video frames keep `models/hubnet.onnx`, `models/hubcrop.onnx` and `ranker`. The
        /// photo-trained models find more hubs in photos and rendered stills, but fewer flights
        /// succeed with them on video frames, and the photo-trained crop places rendered approach
        /// frames' hubs slightly worse.
        pub still_models: bool = true;
        /// Video frames use the still photos' heatmap and `still_ranker` too (off): for measuring
        /// them in flight, and how `scripts/train-ranker.sh still` fits `still_ranker`.
        pub still_models_for_frames: bool = false;
        /// The candidate ranking of still photos with `still_models` (see `ranker`).
        pub still_ranker: RankerParams = RankerParams {
            ranking: Ranking::Learned,
            min_score: -0.1,
            weights: FeatureWeights::still(),
        };
    }
}

impl DefaultParams {
    /// Checks the ranges, that each lower limit lies below its upper one, and both rankings.
    fn validate(&self) -> Result<(), ParamError> {
        let section = "detect.default";
        self.check_ranges(section)?;
        let c = Check::new(section);
        c.less(
            "pyramid_min_side_px",
            self.pyramid_min_side_px as f64,
            "pyramid_max_side_px",
            self.pyramid_max_side_px as f64,
        )?;
        c.less(
            "canny_high_min",
            self.canny_high_min,
            "canny_high_max",
            self.canny_high_max + f64::EPSILON,
        )?;
        c.less(
            "tower_width_min_radii",
            self.tower_width_min_radii,
            "tower_width_max_radii",
            self.tower_width_max_radii,
        )?;
        c.less(
            "tower_min_width_ratio",
            self.tower_min_width_ratio,
            "tower_max_width_ratio",
            self.tower_max_width_ratio,
        )?;
        c.less(
            "tower_min_width_frac",
            self.tower_min_width_frac,
            "tower_max_width_frac",
            self.tower_max_width_frac,
        )?;
        self.ranker.validate("detect.default.ranker")?;
        self.still_ranker.validate("detect.default.still_ranker")
    }
}

/// How a still photo's detection combines with its mirror image's (`still_mirror`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum StillMirror {
    /// The photo alone.
    Off,
    /// Hubs found in both views, close together, are averaged.
    Average,
    /// As `Average`, and otherwise the more confident detection of the two.
    #[default]
    Either,
    /// Only hubs both views find (close together, averaged).
    Both,
}

/// How the default pipeline picks the hub among its candidates.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Ranking {
    /// The hand-set confidence sums (`conf_*`, `prediction_bonus`, ...): the best candidate by
    /// confidence, detected at `min_confidence`.
    Rules,
    /// The learned model (`ranker.rs`): the best candidate by `weights · features`, detected at
    /// `min_score`; the reported confidence is the logistic of the score.
    #[default]
    Learned,
}

hubtrack_types::params! {
    /// The learned candidate ranker (`ranker.rs`, trained by `scripts/train-ranker.sh` on the
    /// project's renderer, never on `../shared/data`).
    pub struct RankerParams {
        /// `"learned"`: the candidate with the highest score `weights · features` wins and is the
        /// hub when the score reaches `min_score`; the reported confidence is `1 / (1 + e^-score)`.
        /// `"rules"`: the highest `conf_*` sum wins, detected at `min_confidence` (the rules'
        /// confidence is also one of the learned features, `rule_score`). The learned ranking finds
        /// more hubs in photos and rendered frames with fewer false positives.
        pub ranking: Ranking = Ranking::Learned;
        /// With `"learned"`: the best candidate is the hub when its score (log-odds against "no hub
        /// in this frame") reaches this. Chosen on the training seeds (11–18, 600 negatives) as the
        /// trade-off between hits and false positives: −1 (a probability of 0.27) gives about 2
        /// points more hits at 3–4 times the false positives of −0.5; 0 about 1 point fewer at a
        /// third of them. `still_ranker` uses −0.1, chosen the same way on training frames and
        /// photo-like views: the first value under 4 % false positives.
        pub min_score: f64 = -0.5, closed(-50.0, 50.0);
        /// Log-odds per unit of each feature (`hubtrack train-ranker` prints a fitted section).
        pub weights: FeatureWeights = FeatureWeights::default();
    }
}

impl RankerParams {
    /// Checks the values; errors name the keys under `section` (e.g. `detect.default.ranker`).
    fn validate(&self, section: &str) -> Result<(), ParamError> {
        self.check_ranges(section)?;
        self.weights.check_ranges(&format!("{section}.weights"))
    }
}

hubtrack_types::params! {
    /// Weight of each candidate feature in the learned score (log-odds per unit of the feature).
    /// Lengths are fractions of the working image height. The defaults are fitted by
    /// `scripts/train-ranker.sh -- --also-without hub_heat` (see the README, "Learned ranking"
    /// and "Learned hub heatmap") with the shipped `models/hubnet.onnx`: every training frame
    /// also counts once with `hub_heat` zeroed, so the ranker does not depend on a network that
    /// has seen renders only.
    pub struct FeatureWeights {
        /// Constant term.
        pub bias: f64 = -0.501, closed(-100.0, 100.0);
        /// 1 when exactly two blade groups remain.
        pub two_blades: f64 = -1.966, closed(-100.0, 100.0);
        /// 1 when exactly three remain.
        pub three_blades: f64 = -0.480, closed(-100.0, 100.0);
        /// Blade groups beyond three (0..3).
        pub extra_blades: f64 = -0.113, closed(-100.0, 100.0);
        /// 1 when tower lines run down from below the candidate.
        pub tower: f64 = 0.062, closed(-100.0, 100.0);
        /// Number of such tower lines / 4 (at most 1).
        pub tower_lines: f64 = 0.361, closed(-100.0, 100.0);
        /// 1 when two blades ~120° apart leave the third hidden straight down the tower.
        pub hidden_blade_down: f64 = 0.640, closed(-100.0, 100.0);
        /// 1 when the strongest blades' separations fit a three-bladed rotor (`blade_sep_tol_deg`).
        pub geometry_ok: f64 = 0.447, closed(-100.0, 100.0);
        /// Blades seen by both edges (or with a band axis) / 3 (at most 1).
        pub paired: f64 = 2.998, closed(-100.0, 100.0);
        /// 1 when a spinner circle is centred on the candidate.
        pub spinner: f64 = 0.741, closed(-100.0, 100.0);
        /// The spinner's radius.
        pub spinner_radius: f64 = 0.322, closed(-100.0, 100.0);
        /// 1 when that radius is the one the tracker's distance expects (`spinner_size_match_tol`).
        pub spinner_size_match: f64 = 1.614, closed(-100.0, 100.0);
        /// 1 when a long line passes through the candidate (tower, mast, wire).
        pub passes_through: f64 = -0.446, closed(-100.0, 100.0);
        /// 1 when the candidate lies within `prediction_radius_frac` of the tracker's prediction.
        pub near_prediction: f64 = 0.345, closed(-100.0, 100.0);
        /// Summed length of the (up to three) strongest blades.
        pub support: f64 = 0.434, closed(-100.0, 100.0);
        /// Length of the weakest of them (0 with fewer than two).
        pub weakest_blade: f64 = 0.916, closed(-100.0, 100.0);
        /// Length of the strongest.
        pub strongest_blade: f64 = -0.298, closed(-100.0, 100.0);
        /// Mean distance of the blades' pairwise separations from 120° (or 240°), in units of 60°
        /// (1 with fewer than two blades).
        pub separation_error: f64 = -1.734, closed(-100.0, 100.0);
        /// Lines dropped as tower, opposite or weak blades / 10 (at most 1).
        pub rejected_lines: f64 = 1.020, closed(-100.0, 100.0);
        /// The rules' confidence before capping (`conf_*` sums).
        pub rule_score: f64 = -0.347, closed(-100.0, 100.0);
        /// Usable lines passing within the support reach that neither support the candidate nor
        /// belong to its tower / 10 (at most 1): texture around a false candidate.
        pub clutter: f64 = -2.942, closed(-100.0, 100.0);
        /// Blades whose two edges pair into a band with an axis / 3 (at most 1).
        pub banded_blades: f64 = -1.906, closed(-100.0, 100.0);
        /// How far the tower's top lies below the candidate (±0.5; 0 without a tower).
        pub tower_top_below: f64 = 0.397, closed(-100.0, 100.0);
        /// Usable lines in the whole image / 200 (at most 1): how textured the frame is.
        pub image_lines: f64 = -0.173, closed(-100.0, 100.0);
        /// Rim coverage of the spinner circle (0..1; 0 without one).
        pub spinner_coverage: f64 = 4.675, closed(-100.0, 100.0);
        /// Distance from the spinner circle's centre to where its blades' axes meet, in radii (at
        /// most 2; 0 without a circle above `spinner_kept_support_max_radius_px` or without two
        /// known axes): a round patch beside the hub has a rim drawn by blade edges but is centred
        /// beside the point the blades radiate from.
        pub spinner_axes_offset: f64 = -1.136, closed(-100.0, 100.0);
        /// The learned hub heatmap's probability at the candidate (0..1; 0 with `hub_heat` off):
        /// whether the frame around it looks like a hub to a network that saw the whole image.
        pub hub_heat: f64 = 2.110, closed(-100.0, 100.0);
    }
}

impl FeatureWeights {
    /// The weights in the order of [`crate::ranker::FEATURE_NAMES`].
    pub fn to_array(&self) -> [f64; crate::ranker::FEATURES] {
        [
            self.bias,
            self.two_blades,
            self.three_blades,
            self.extra_blades,
            self.tower,
            self.tower_lines,
            self.hidden_blade_down,
            self.geometry_ok,
            self.paired,
            self.spinner,
            self.spinner_radius,
            self.spinner_size_match,
            self.passes_through,
            self.near_prediction,
            self.support,
            self.weakest_blade,
            self.strongest_blade,
            self.separation_error,
            self.rejected_lines,
            self.rule_score,
            self.clutter,
            self.banded_blades,
            self.tower_top_below,
            self.image_lines,
            self.spinner_coverage,
            self.spinner_axes_offset,
            self.hub_heat,
        ]
    }
}

impl FeatureWeights {
    /// The still photos' weights (`still_ranker`): fitted by `scripts/train-ranker.sh` with the
    /// still heatmap (`models/hubnet-still.onnx`) and photo-like views among the training frames
    /// (see the README, "Photo-like views"); every training frame also counts once with `hub_heat`
    /// zeroed.
    pub fn still() -> Self {
        FeatureWeights {
            bias: -0.200,
            two_blades: -2.126,
            three_blades: -0.518,
            extra_blades: -0.008,
            tower: 0.119,
            tower_lines: 0.587,
            hidden_blade_down: 0.773,
            geometry_ok: 0.612,
            paired: 3.120,
            spinner: 0.760,
            spinner_radius: 0.344,
            spinner_size_match: 1.674,
            passes_through: -0.501,
            near_prediction: 0.082,
            support: 0.220,
            weakest_blade: 0.963,
            strongest_blade: -0.407,
            separation_error: -1.515,
            rejected_lines: 1.038,
            rule_score: -0.371,
            clutter: -2.785,
            banded_blades: -1.932,
            tower_top_below: 0.217,
            image_lines: 0.302,
            spinner_coverage: 4.284,
            spinner_axes_offset: -1.122,
            hub_heat: 2.474,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_validate_and_roundtrip() {
        let c = DetectConfig::default();
        c.validate().unwrap();
        let s = serde_json::to_string(&c).unwrap();
        let back: DetectConfig = serde_json::from_str(&s).unwrap();
        assert_eq!(back, c);
        let m: DetectConfig = serde_json::from_str(r#"{"mode":"thesis"}"#).unwrap();
        assert_eq!(m.mode, Mode::Thesis);
    }

    #[test]
    fn the_thesis_turbines_own_yaw_network_serves_that_turbine_only() {
        let with = |t: &TurbineSetup| {
            DetectConfig::default()
                .with_setup(&Lens::default(), t)
                .camera
        };
        let tol = DefaultParams::default().hub_yaw_thesis_tolerance;
        let thesis = TurbineSetup::default();
        assert!(with(&thesis).is_thesis_turbine(tol));
        assert!(!with(&thesis).is_thesis_turbine(0.0));
        // The Vestas V90's profile (config/turbines/vestas_v90.toml): its tower and nacelle are
        // within a few per cent of the thesis turbine's, its spinner and overhang are not.
        let v90 = TurbineSetup {
            hub_height_m: 80.0,
            rotor_radius_m: 45.0,
            tower_top_diameter_m: 2.3,
            tower_base_diameter_m: 4.15,
            hub_overhang_m: 3.9,
            spinner_diameter_m: 3.4,
            ..TurbineSetup::default()
        };
        assert!(!with(&v90).is_thesis_turbine(tol));
        // Any one dimension off by more than the tolerance is another turbine.
        for t in [
            TurbineSetup {
                hub_overhang_m: thesis.hub_overhang_m * 1.1,
                ..TurbineSetup::default()
            },
            TurbineSetup {
                spinner_diameter_m: thesis.spinner_diameter_m * 0.9,
                ..TurbineSetup::default()
            },
            TurbineSetup {
                nacelle_width_m: thesis.nacelle_width_m * 1.1,
                ..TurbineSetup::default()
            },
        ] {
            assert!(!with(&t).is_thesis_turbine(tol));
        }
    }

    #[test]
    fn bad_values_name_their_key() {
        let mut c = DetectConfig::default();
        c.thesis.canny_high = 100.0;
        let e = c.validate().unwrap_err();
        assert_eq!(e.key, "detect.thesis.canny_low");
        let mut c = DetectConfig::default();
        c.default.min_confidence = 2.0;
        assert_eq!(
            c.validate().unwrap_err().key,
            "detect.default.min_confidence"
        );
        assert!(serde_json::from_str::<DetectConfig>(r#"{"thesis":{"nope":1}}"#).is_err());
        let mut c = DetectConfig::default();
        c.default.ranker.weights.paired = f64::NAN;
        assert_eq!(
            c.validate().unwrap_err().key,
            "detect.default.ranker.weights.paired"
        );
    }

    #[test]
    fn ranker_weights_are_named_like_the_features() {
        let v = serde_json::to_value(FeatureWeights::default()).unwrap();
        let keys: Vec<&str> = v.as_object().unwrap().keys().map(|k| k.as_str()).collect();
        let mut names = crate::ranker::FEATURE_NAMES.to_vec();
        names.sort_unstable();
        let mut keys = keys;
        keys.sort_unstable();
        assert_eq!(keys, names);
        let w = FeatureWeights::default();
        for (name, x) in crate::ranker::FEATURE_NAMES.iter().zip(w.to_array()) {
            assert_eq!(v[*name].as_f64().unwrap(), x, "{name}");
        }
    }
}
