//! Every tunable number of the detector, as plain serde data (no OpenCV here).
//!
//! The configuration lives under the `detect` key of the project configuration, so error keys are
//! full dotted paths such as `detect.thesis.canny_high`. Every struct denies unknown fields and
//! fills missing ones from [`Default`], which holds the documented defaults.
//!
//! Pixel quantities are in the pixels of the *working* (downsampled) image unless the name says
//! `_frac` (fraction of the working-image height, so they survive a change of working size).

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

use hubtrack_types::params::Check;
pub use hubtrack_types::params::ParamError;

/// Whole detector configuration (`detect` section).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct DetectConfig {
    /// Pipeline to run.
    pub mode: Mode,
    /// Camera and turbine dimensions for distance and yaw.
    pub camera: CameraParams,
    /// Parameters of the thesis pipeline.
    pub thesis: ThesisParams,
    /// Parameters of the default pipeline.
    pub default: DefaultParams,
}

/// Camera optics and known turbine dimensions used for distance and yaw estimates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CameraParams {
    /// Horizontal field of view, degrees. 118 = GoPro HERO3+ Black 1080p wide (the thesis camera).
    /// The pinhole focal length is `f = (width / 2) / tan(hfov / 2)` at full resolution.
    pub hfov_deg: f64,
    /// Centre focal length divided by the image width, overriding `hfov_deg` when > 0. A lens
    /// with strong barrel distortion has a much longer centre focal length than the pinhole value
    /// from its edge FOV: the GoPro HERO3+ wide (the thesis camera, as the renderer models it)
    /// has 833.9 px at 1920 wide (0.4343) vs 577 px (0.3004) from 118°, which would make every
    /// distance ~31 % short. Default 0.4343; 0 = use `hfov_deg`. Must equal
    /// `track.camera.focal_length_per_width` (checked at load).
    pub focal_length_per_width: f64,
    /// Tower diameter at the top, metres (2.2 m on the thesis's ~1.5 MW turbines); the distance
    /// estimate divides it by the measured tower width.
    pub tower_top_diameter_m: f64,
    /// Distance from the hub centre to the tower axis along the rotor axis, metres (~4 m); the
    /// yaw estimate (thesis eq. 7.14) divides the image gap by it.
    pub hub_tower_gap_m: f64,
    /// Spinner (nose cone) diameter at the blade roots, metres (3.2 m on the modelled turbine):
    /// with the tracker's distance it gives the spinner radius to search for. Must equal
    /// `track.distance.spinner_diameter_m` (checked at load).
    pub spinner_diameter_m: f64,
}

impl Default for CameraParams {
    #[allow(clippy::approx_constant)] // 0.4343 is the GoPro lens (833.9 / 1920), not log10(e)
    fn default() -> Self {
        CameraParams {
            hfov_deg: 118.0,
            focal_length_per_width: 0.4343,
            tower_top_diameter_m: 2.2,
            hub_tower_gap_m: 4.2,
            spinner_diameter_m: 3.2,
        }
    }
}

/// Parameters of the thesis pipeline (section 6.1.5, 8.1 and table 9.1). Defaults are the
/// thesis's values; where the thesis gives no number the choice is documented.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ThesisParams {
    /// Downsample with pyrDown (at least once) until both sides are at most this, px (thesis 8.1: 200–500).
    pub pyramid_max_side_px: u32,
    /// Stop downsampling before any side would drop below this, px (thesis 8.1).
    pub pyramid_min_side_px: u32,
    /// Canny low hysteresis threshold (thesis: 300).
    pub canny_low: f64,
    /// Canny high hysteresis threshold (thesis: 400).
    pub canny_high: f64,
    /// Hough accumulator distance resolution, px (thesis: 1).
    pub hough_rho_px: f64,
    /// Hough accumulator angle resolution, degrees (thesis: 1).
    pub hough_theta_deg: f64,
    /// Hough accumulator threshold, votes (thesis table 9.1: 43).
    pub hough_threshold: i32,
    /// Minimum Hough segment length, px at the working size (thesis table 9.1: 50 at 270 px height).
    pub hough_min_length_px: f64,
    /// Maximum gap bridged inside one Hough segment, px (thesis table 9.1: 13).
    pub hough_max_gap_px: f64,
    /// A tower line may deviate this much from vertical after roll compensation, degrees
    /// ("a few degrees" in the thesis).
    pub tower_max_tilt_deg: f64,
    /// A tower line must have an end point in this lowest fraction of the image (thesis: 20 %).
    pub tower_bottom_frac: f64,
    /// Blade search radius around the tower top, fraction of image height (thesis: 0.3).
    pub search_radius_frac: f64,
    /// Blade lines whose directions differ by at most this are one blade, degrees (thesis: "adjacent angles"; 10° separates 120°-spaced blades safely while merging both edges of a tapered blade).
    pub blade_group_tol_deg: f64,
    /// A blade pointing down within this of the tower direction is removed, degrees.
    pub blade_over_tower_tol_deg: f64,
    /// Expected angle between blades, degrees (thesis: 120).
    pub vote_target_deg: f64,
    /// Tolerance on the blade separation, degrees (thesis: 20).
    pub vote_tol_deg: f64,
    /// A blade with this many votes is removed (thesis: 3).
    pub vote_limit: u32,
    /// Intersections farther than this from the tower axis line horizontally are discarded,
    /// fraction of the search radius (thesis gives no number; 0.35 R ≈ 0.1 image height covers
    /// the hub–tower gap up to ~45° yaw at 30 m).
    pub hub_max_dx_frac: f64,
    /// Intersections farther than this vertically from the tower top are discarded, fraction of
    /// the search radius ("less strict" than the horizontal limit).
    pub hub_max_dy_frac: f64,
    /// Minimum number of blades for a detection (thesis: 2).
    pub min_blades: u32,
    /// The tower width is measured this far below the tower top, fraction of image height (just
    /// under the nacelle, where the tower diameter is the known top diameter).
    pub tower_width_below_top_frac: f64,
}

impl Default for ThesisParams {
    fn default() -> Self {
        ThesisParams {
            pyramid_max_side_px: 500,
            pyramid_min_side_px: 200,
            canny_low: 300.0,
            canny_high: 400.0,
            hough_rho_px: 1.0,
            hough_theta_deg: 1.0,
            hough_threshold: 43,
            hough_min_length_px: 50.0,
            hough_max_gap_px: 13.0,
            tower_max_tilt_deg: 5.0,
            tower_bottom_frac: 0.2,
            search_radius_frac: 0.3,
            blade_group_tol_deg: 10.0,
            blade_over_tower_tol_deg: 15.0,
            vote_target_deg: 120.0,
            vote_tol_deg: 20.0,
            vote_limit: 3,
            hub_max_dx_frac: 0.35,
            hub_max_dy_frac: 0.7,
            min_blades: 2,
            tower_width_below_top_frac: 0.05,
        }
    }
}

/// Parameters of the default (robust) pipeline; see `robust/mod.rs` for the steps.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DefaultParams {
    /// Downsample (at least once) until both sides are at most this, px. 500 keeps the
    /// 1920×1080 → 480×270 working size of the thesis, which fits the 5 ms budget.
    pub pyramid_max_side_px: u32,
    /// Stop downsampling before any side would drop below this, px.
    pub pyramid_min_side_px: u32,
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
    pub box_first_level: bool,
    /// Canny high threshold = this percentile (0..1) of the Sobel L1 gradient magnitude, so the
    /// edge density follows the image contrast instead of a fixed level.
    pub canny_high_percentile: f64,
    /// Lower clamp of the adaptive high threshold (Sobel L1 units, max 2040): below this a
    /// "gradient" is sensor noise even in a flat sky.
    pub canny_high_min: f64,
    /// Upper clamp of the adaptive high threshold: the thesis's 400 already keeps every turbine
    /// edge, more would drop low-contrast blades against textured ground.
    pub canny_high_max: f64,
    /// Canny low threshold as a fraction of the high one (the classic 1:2 – 1:3 ratio).
    pub canny_low_ratio: f64,
    /// Hough accumulator distance resolution, px.
    pub hough_rho_px: f64,
    /// Hough accumulator angle resolution, degrees.
    pub hough_theta_deg: f64,
    /// Hough accumulator threshold, as a fraction of image height (votes).
    pub hough_threshold_frac: f64,
    /// Minimum Hough segment length, fraction of image height.
    pub hough_min_length_frac: f64,
    /// Maximum gap inside one Hough segment, fraction of image height.
    pub hough_max_gap_frac: f64,
    /// Each edge pixel votes only for line normals within this angle of its own gradient
    /// direction, degrees (`hough.rs`): a straight edge's gradients are its normal, so its
    /// votes are kept while the cost drops from 180 to 2·tol + 1 bins per pixel and texture
    /// stops voting for lines it is not on. Sobel directions on a clean 1-px edge scatter by
    /// a few degrees, on a jagged or blurred one by up to ~8°. 90 = every angle, as OpenCV's
    /// `HoughLinesP`.
    pub hough_orientation_tol_deg: f64,
    /// At most this many segments (the longest) enter the geometry, bounding its O(n²) steps.
    pub max_segments: usize,
    /// Collinear merge: maximum angle between two segments, degrees.
    pub merge_angle_deg: f64,
    /// Collinear merge: maximum perpendicular offset, px.
    pub merge_offset_px: f64,
    /// Collinear merge: maximum gap between the segments along the line, fraction of image height.
    pub merge_gap_frac: f64,
    /// Lines longer than this fraction of the image width and within `horizon_max_tilt_deg` of
    /// horizontal (after roll) are horizon/ridge candidates and never blades.
    pub horizon_min_length_frac: f64,
    /// See `horizon_min_length_frac`, degrees from horizontal.
    pub horizon_max_tilt_deg: f64,
    /// A horizon candidate whose edge pairs with another into a slender band (`pair_*`) that
    /// narrows by at least this ratio from one end to the other is a blade lying level, not a
    /// horizon, and stays usable. A horizon is a single line; a road or a field strip is a
    /// band of even width (ratio ~1; a road beside a real turbine paired so, untapered). 0
    /// disables the exception.
    pub horizon_band_min_taper: f64,
    /// Convergence: only segments at least this long (fraction of image height) propose hub candidates.
    pub candidate_min_length_frac: f64,
    /// Convergence: two proposing segments must differ in direction by at least this, degrees.
    pub candidate_min_angle_deg: f64,
    /// Convergence: a proposal must lie within this fraction of a segment's length beyond its
    /// nearer end (blades start at the hub, they do not pass through it).
    pub candidate_end_reach_frac: f64,
    /// Convergence: a proposal may lie at most this fraction of a segment's length inside it.
    pub candidate_inside_frac: f64,
    /// Clustering radius of the candidate proposals, fraction of image height.
    pub cluster_radius_frac: f64,
    /// A supporting blade line must pass within this of the hub candidate, fraction of image height
    /// (blade edges are offset from the blade axis by half the root chord).
    pub support_line_dist_frac: f64,
    /// A supporting blade line's nearer end must lie within this of the candidate, fraction of
    /// image height.
    pub support_end_dist_frac: f64,
    /// Lines within this angle are one blade, degrees.
    pub blade_group_tol_deg: f64,
    /// Two blades closer than this in angle are merged / not counted apart, degrees.
    pub blade_min_separation_deg: f64,
    /// Two "blades" at least this far apart (degrees) are the two halves of one straight line
    /// through the candidate (a horizon, field border or mast hidden behind it), not blades:
    /// both are dropped. Two of a rotor's blades, 120° apart on the rotor plane, are seen this
    /// close to opposite only from nearly edge-on (at 60° yaw at most ~140° apart, at 78° ~160°).
    /// 180 = off (the default). At 170 `hubtrack eval` synthetic false positives 6.2 → 2.1 %
    /// (seed 77: 18.8 → 14.6 %: masts whose top passes for a blade, field borders on both
    /// sides), real photos 37.7 → 41.5 % (with `close_spinner_min_coverage` 0.3: synthetic hits
    /// 69.5 → 69.8 %); at 165 the photos drop to 34 %. Off because the live pipeline's distance
    /// got worse: `tests/test_pipeline.py::test_track_follows_truth` median distance error
    /// 0.08–0.13 (session 17's build, 6 runs) against 0.10–0.17 (6 runs; 3 of 12 above the
    /// test's 0.15), and `hubtrack fly` seeds 161–240 gave 73 of 80 with it and the close-spinner
    /// rule against 75 for session 17's build; why the distance suffers is not understood yet.
    pub blade_max_separation_deg: f64,
    /// Expected angle between blades, degrees.
    pub blade_target_deg: f64,
    /// Tolerance on the blade separation (larger than the thesis's to allow oblique views), degrees.
    pub blade_sep_tol_deg: f64,
    /// Tower lines: maximum tilt from vertical after roll, degrees (larger than the thesis's
    /// because the wide lens bends lines and unknown roll is searched).
    pub tower_max_tilt_deg: f64,
    /// Tower lines must reach above this far below the candidate hub, fraction of image height.
    pub tower_top_max_below_frac: f64,
    /// Tower lines may start at most this far above the candidate hub, fraction of image height
    /// (the tower top hides behind the nacelle; a line passing the hub is no tower top).
    pub tower_top_max_above_frac: f64,
    /// Tower lines may be this far horizontally from the hub candidate, fraction of image height.
    pub tower_max_dx_frac: f64,
    /// Tower seeds (not the blade/tower classification): with a spinner circle of radius r,
    /// tower lines may reach this many r below the hub when that is more than
    /// `tower_top_max_below_frac`; at close range the tower top, under the nacelle, is ~1.1 r
    /// below the hub centre. Range [0, 10].
    pub tower_top_max_below_radii: f64,
    /// ... and may be this many r from the hub horizontally when that is more than
    /// `tower_max_dx_frac`: a tower edge lies (overhang·sin ψ + tower radius)·f/depth from the
    /// hub, ≤ 2 r up to ψ = 30°. Range [0, 10]. (Not for the classification: there a grown
    /// window takes the edges of a blade pointing down for tower lines and drops the blade.)
    pub tower_max_dx_radii: f64,
    /// A blade pointing down in front of the tower, shifted by the yaw, makes a band about twice
    /// as wide. With a tracker's distance d (the detect stage has one; photos do not) a band may
    /// be at most this factor narrower or wider than f·tower_top_diameter_m / (d +
    /// hub_tower_gap_m). Range [1, 10].
    pub tower_width_hint_tol: f64,
    /// With a spinner circle of radius r, a tower band is at least this many r wide: the tower
    /// top (2.2 m), farther than the spinner (3.2 m), is 0.67–1.25 r from 4 m to 40 m.
    /// Range [0, 10].
    pub tower_width_min_radii: f64,
    /// ... and at most this many r wide. Range [0, 10].
    pub tower_width_max_radii: f64,
    /// ... and at most this factor narrower or wider than the width the spinner's radius
    /// implies: the spinner gives the hub's distance f·R/r, the tower top is
    /// `tower_top_diameter_m` wide `hub_tower_gap_m` farther (1.24 r at 38 m, 0.75 r at 5 m).
    /// Without it the shading ramp of a side-lit tower passed for its far edge at 38 m (0.6 r):
    /// the distance read 64–71 m and the tracker's width window then kept the true band out
    /// (`fly` seed 335). 0 = off. Range 0 or [1, 10].
    pub tower_width_spinner_tol: f64,
    /// When the Hough lines give no tower (HoughLinesP's walk along a jagged, slightly tilted
    /// edge drops the short piece with its votes, so an edge in plain view can go missing), the
    /// horizontal gradient below a detected hub is scanned for near-vertical edges: from this
    /// far below the hub, fraction of image height, range [0, 1] ...
    pub tower_scan_start_frac: f64,
    /// ... or this many spinner radii when that is more (the nacelle bottom is ~1.1 r down),
    /// range [0, 10].
    pub tower_scan_start_radii: f64,
    /// A scanned edge's mean gradient must be this many times the mean over all positions.
    /// Range [1, 100].
    pub tower_scan_min_salience: f64,
    /// Without a roll hint, the roll is searched in ±this range, degrees.
    pub roll_search_deg: f64,
    /// Search radius around `hints.predicted_hub_px`, fraction of image height: candidates
    /// inside it get `prediction_bonus` added to their score.
    pub prediction_radius_frac: f64,
    /// Score bonus (confidence units) for candidates near the predicted hub.
    pub prediction_bonus: f64,
    /// A spinner candidate whose circle is within this factor of the radius the tracker's
    /// distance expects ...
    pub spinner_size_match_tol: f64,
    /// ... gets this added to its score and confidence (the spinner at the predicted size is the
    /// strongest single cue at close range; blade lines meeting near it can still outscore it).
    pub spinner_size_match_bonus: f64,
    /// Confidence weight of having 2 blades.
    pub conf_two_blades: f64,
    /// Confidence weight of having 3 blades.
    pub conf_three_blades: f64,
    /// Two blades whose missing third would point straight down (within this, degrees) count
    /// as three when a tower supports the candidate: a blade pointing down lies over the tower
    /// and its edges are the tower's (or hidden by it). The third direction of a rotor is taken
    /// opposite the bisector of the two seen blades; 0 turns the rule off.
    pub hidden_blade_tol_deg: f64,
    /// Confidence added when a tower supports the candidate.
    pub conf_tower: f64,
    /// Confidence added when the blade separations fit a (possibly skewed) 120° rotor.
    pub conf_geometry: f64,
    /// Confidence added when at least two blades show both edges (a blade is a band with two
    /// edges on either side of its axis; field borders, wires and horizons give single lines).
    pub conf_paired: f64,
    /// Confidence removed per blade beyond three (clutter: textured ground, lattice masts).
    pub conf_extra_blade_penalty: f64,
    /// With `ranker.ranking = "rules"`: `detected` requires at least this confidence.
    pub min_confidence: f64,
    /// The tower width is measured this far below the tower top, fraction of image height.
    pub tower_width_below_top_frac: f64,
    /// Tower partner edge: the tower is at least this wide, fraction of image height (a 2.2 m
    /// tower top at 60 m with the GoPro lens is ~3 %).
    pub tower_min_width_frac: f64,
    /// Tower partner edge: the tower is at most this wide, fraction of image height (~17 % at 10 m).
    pub tower_max_width_frac: f64,
    /// Tower partner edge: its mean gradient response (opposite sign to the found edge, over
    /// all rows from the tower top down) must reach this fraction of the found edge's own
    /// (a tower lit from one side has one strong and one weak edge); else the axis is unknown
    /// and no tower is reported (one edge is half a width off the axis).
    pub tower_partner_min_ratio: f64,
    /// Tower partner edge: its response must also be this many times the mean response over
    /// all offsets searched (it must stand out of the background texture).
    pub tower_partner_min_salience: f64,
    /// Tower partner edge of the seed's own gradient sign: taken instead of the best
    /// opposite-sign one when that one is a shading ramp (the response 2 px nearer or farther
    /// stays `tower_ramp_min_frac` of its own), the same-sign edge lies beyond it, and its
    /// response is at least this fraction of the ramp's. A tower lit from one side against ground
    /// of a middle shade is darker than the ground at one limb and brighter at the other: both
    /// edges have one sign, the ramp inside is the only opposite-sign response (widths read
    /// ~0.6x), and the lit limb may be barely brighter than the ground. A large value (1000)
    /// disables it.
    pub tower_same_sign_partner_min_ratio: f64,
    /// A tower edge moves outward to the end of its shading ramp: as far as the summed gradient
    /// response along the shifted edge stays at least this fraction of the response at the
    /// fitted (steepest) position. A side-lit tower's dark limb on dark ground has no edge, only
    /// the end of a ramp; a sharp edge's response halves within a pixel and stays put. ≥ 1
    /// disables it.
    pub tower_ramp_min_frac: f64,
    /// ... by at most this fraction of the tower width.
    pub tower_ramp_max_frac: f64,
    /// The tower band's width at the image bottom over its width at its top must be at least
    /// this: a blade pointing down narrows toward its tip (~0.65 over the visible part), the
    /// tower keeps its image width within ~10 %. A blade pointing down in front of the tower
    /// merges with it into one band that narrows by ~13 % (rendered approaches at ~40 m),
    /// whose width and hub–tower gap are both wrong: 0.9 rejects it (0.85 let it through).
    pub tower_min_width_ratio: f64,
    /// ... and at most this times the widening the tower's taper gives over the visible rows
    /// (`1 + tower_taper · rows / top width`, see `tower_taper`), while a band from a tower edge
    /// to the edge of a blade crossing it widens fast.
    pub tower_max_width_ratio: f64,
    /// Tower taper: growth of its diameter per metre down, m/m (steel towers ~0.02–0.035; the
    /// renderer's 2.2 m top and 4.3 m base over ~70 m: 0.03). Its rows are at about the same
    /// depth, so over `rows` px below a top `w` px wide (`rows·D/w` metres) the band widens by
    /// `tower_taper · rows / w`: ~30 % at 30 m with the wide-angle camera, up to ~2x when the
    /// whole tower is in view. 0 = the tower keeps its width.
    pub tower_taper: f64,
    /// When a detected blade, or the strongest blade at 120° steps, is within this of straight
    /// down, degrees, that blade hides the tower ...
    pub tower_blade_down_tol_deg: f64,
    /// A tower band whose axis, halfway down, lies on the ray of a blade (detected, or placed
    /// 120° or 240° from a detected one) within this of straight down, degrees, is that blade,
    /// or that blade merged with one tower edge (within `tower_blade_axis_tol_frac` of the
    /// ray). `fly` seed 279: a blade at 168° (detected blades 268°, 48°, 90°) read as the tower
    /// at 16–24 m with the gap's sign wrong. 0 = only the check at the hub's row. Range [0, 60].
    pub tower_blade_ray_tol_deg: f64,
    /// ... but not rays within this of straight down, degrees. Such a blade's band misleads
    /// too (rendered at 19 m: gaps 40–60 px off), but it covers the tower, so without it no
    /// tower and no distance is measured while that blade hangs in front (`fly` seed 340: no
    /// distance at 37 m for 120 s). Fresh `fly` seeds 241–400: 145 of 160 with 5, 143 with 0,
    /// 136 without the ray rule. Range [0, 60].
    pub tower_blade_ray_min_deg: f64,
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
    pub tower_blade_down_max_distance_m: f64,
    /// Nacelle search (`nacelle.rs`; needs a tracker's distance): rows scanned either side of
    /// the hub's row, metres at the hub's depth. The nacelle is 3.5 m high and its rear, 11 m
    /// behind the hub, looks smaller: ±1 m stays on its side face at 10–40 m.
    pub nacelle_band_half_m: f64,
    /// ... columns from this far beside the hub, m at the hub's depth: past the spinner
    /// (radius 1.6 m) and the nacelle's front corners (half width 1.7 m), which show on both
    /// sides whatever the yaw.
    pub nacelle_min_offset_m: f64,
    /// ... to this far, m at the hub's depth (the rear corner of an 11 m nacelle at 60° yaw).
    pub nacelle_max_offset_m: f64,
    /// ... the best column's median signed horizontal Sobel response must be at least this
    /// (8-bit 3×3 Sobel: a step of `c` grey levels gives `4c`; 40 = a 10-level step) ...
    pub nacelle_min_response: f64,
    /// ... and this many times the other side's best (one side only sticks out).
    pub nacelle_min_ratio: f64,
    /// ... and a tower band whose axis passes within this of the hub, fraction of image
    /// height, is that blade, not the tower.
    pub tower_blade_axis_tol_frac: f64,
    /// Edge pairing: both edges of a blade (or the tower) must be at least this long, fraction
    /// of image height.
    pub pair_min_length_frac: f64,
    /// Edge pairing: the two edges differ in direction by at most this, degrees (blades taper,
    /// so their edges converge slightly toward the tip).
    pub pair_max_angle_deg: f64,
    /// Edge pairing: the edges must overlap along their direction by at least this fraction of
    /// the shorter one.
    pub pair_min_overlap_frac: f64,
    /// Edge pairing: the band must be at least this wide at both ends, working px (closer
    /// edges are one edge seen twice).
    pub pair_min_width_px: f64,
    /// Edge pairing: the band may be at most this wide at either end, fraction of image height
    /// (a blade root seen from a few metres).
    pub pair_max_width_frac: f64,
    /// Edge pairing: mean band width over axis length at most this (blades are slender).
    pub pair_max_width_to_length: f64,
    /// A blade axis may end at most this many band widths (at its nearer end) short of the hub:
    /// blades start at the spinner rim, whose radius grows with the root chord as the camera
    /// approaches.
    pub axis_reach_widths: f64,
    /// A supporting blade axis passes within this of the hub, fraction of image height, ...
    pub axis_line_dist_frac: f64,
    /// ... plus this angle (degrees) times the distance from its nearer end.
    pub axis_angle_tol_deg: f64,
    /// Vote weight of an axis–axis intersection relative to an edge–edge one.
    pub axis_proposal_weight: f64,
    /// Spinner step: the best this many candidates (with at least two blades) are searched for a
    /// spinner circle; 0 disables the step.
    pub spinner_candidates: usize,
    /// Spinner step: half side of the square searched around a candidate, fraction of image height.
    pub spinner_search_frac: f64,
    /// Spinner step: a circle's centre may be at most this far from the candidate, fraction of
    /// image height (blade-edge convergence is biased toward the spinner rim).
    pub spinner_max_offset_frac: f64,
    /// Spinner step: smallest circle radius searched, working px (below this the spinner is a
    /// few pixels and edge convergence is accurate enough).
    pub spinner_min_radius_px: f64,
    /// Spinner step: largest circle radius searched, fraction of image height.
    pub spinner_max_radius_frac: f64,
    /// Spinner step with the tracker's distance: only radii from this times the radius expected
    /// at that distance (`detect.camera.spinner_diameter_m`) are searched, within the two limits
    /// above. The window allows the distance to be off by a factor of two either way (the
    /// tracker's distance is good to ~30 %); the narrower search is faster and finds fewer
    /// circles of the wrong size. 0 = search all radii always.
    pub spinner_hint_radius_lo: f64,
    /// ... up to this times the expected radius.
    pub spinner_hint_radius_hi: f64,
    /// Spinner step: centre accumulator cell and radius step of the gradient circle vote, working px.
    pub spinner_cell_px: f64,
    /// Spinner step: an edge pixel is on a rim when its gradient is within this of the radial
    /// direction, degrees.
    pub spinner_radial_tol_deg: f64,
    /// Spinner step: smallest fraction of the rim covered by edge pixels (blade roots, the
    /// nacelle and shading hide parts of it).
    pub spinner_min_coverage: f64,
    /// Spinner step: the searches around hub candidates vote for centres with every
    /// this-many-th edge point (in row order), and measure rim coverage with all of them
    /// (`close_spinner_vote_every` for the whole-image search). 1: every point. Session 34, 2
    /// against 1: synthetic hits seeds 2026 / 77 / 500 93.8 / 93.5 / 92.0 → 93.3 / 92.8 /
    /// 92.3 %, photos 64.2 → 62.3 % (small spinners have few rim points to spare).
    pub spinner_vote_every: u32,
    /// Spinner step: centre peaks of the vote whose rims are measured, per search. Small
    /// circles (corners, blade–nacelle junctions) take the strongest accumulator peaks, and a
    /// close spinner was often only the 4th to 12th: 3 → 12 took synthetic hits 57.5 → 60.2 %
    /// (session 9). More peaks find more false circles in textured ground too (real photos
    /// 35.8 → 28.3 % alone); `spinner_max_interior_density` removes those. Session 34, 8
    /// against 12 (a third of the rims' ~0.5 ms a frame): synthetic hits seeds 2026 / 77 /
    /// 500 93.8 / 93.5 / 92.0 → 93.5 / 93.2 / 92.3 %, close 89.0 / 88.5 / 84.0 → 88.5 /
    /// 88.0 / 84.0 %, photos the same.
    pub spinner_peaks: u32,
    /// ... when the tracker's distance gives the expected radius (the radii searched are then
    /// 0.5–2× that one, around the predicted hub): at 5 m under an overcast sky the grey
    /// spinner on grey blades shows 25–40 % of its rim, and the track was lost at the target.
    pub spinner_hint_min_coverage: f64,
    /// A circle enclosing the best-covered spinner circle replaces it (the silhouette round a
    /// ring on the spinner's face) only when its rim coverage is at least this fraction of the
    /// inner one's; a circle drawn by blade edges crossing near the spinner is covered less.
    /// 0 = always the outer one.
    pub spinner_nest_min_coverage_ratio: f64,
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
    pub spinner_min_kept_support: f64,
    /// ... nor circles larger than this, working px (8 px: the modelled spinner from ~30 m
    /// with the wide-angle lens): a spinner a few pixels across is any round blob, a larger
    /// one shows its own outline.
    pub spinner_kept_support_max_radius_px: f64,
    /// Spinner step: a circle whose inner 70 % holds more Canny edge pixels than this per px² is
    /// clutter (textured ground, a tower with blades and horizon), not the smooth spinner.
    pub spinner_max_interior_density: f64,
    /// Still photos only (`hubtrack detect`, `hubtrack eval` on photos; never the detect
    /// stage, which keeps its frame budget): detect also one pyramid level finer and keep the
    /// more confident detection. Real development photos: 39.6 → 49.1 % hits (far 0 → 1 of
    /// 9, the rest medium and close turbines whose blades are thin at the working size), no
    /// false positive more; ~4× the time per photo. Default true.
    pub still_finer_level: bool,
    /// Still photos only (`hubtrack detect`, the photos of `hubtrack eval`; never the detect
    /// stage): detect also in the photo's mirror image and combine the two, as test-time
    /// augmentation does — the rules and networks are not exactly mirror-symmetric, so the
    /// two views err apart. `"off"`; `"average"`: hubs found in both within
    /// `still_mirror_agree_frac` are averaged, nothing else changes; `"either"`: as average,
    /// and otherwise the more confident of the two detections stands (a hub found in one view
    /// only counts); `"both"`: only hubs both views find count (averaged). Doubles the time
    /// per photo. Session 36, hits off / average / either / both: photo-like views seed 2026
    /// 81.3 / 84.0 / 89.0 / 78.3 % (negatives detected 1 / 1 / 2 / 0 of 25), seed 500 81.2 /
    /// 82.8 / 85.2 / 78.0 % (7 / 7 / 9 / 4 of 50); close photo-like views seed 2026 62.0 /
    /// 66.0 / 72.0 / 53.0 % (1 / 1 / 2 / 0 of 25); approach frames as stills seed 2026 93.8 /
    /// 95.5 / 96.8 / 93.8 % (5 / 5 / 5 / 1 of 48); the development photos 35 / 38 / 43 / 36 of
    /// 53 (0 of 8 negatives each). Default `"either"`: the most hits everywhere, 18 instead of
    /// 14 of the 148 rendered negatives detected; `"both"` 5, for 0–9 points of hits.
    pub still_mirror: StillMirror,
    /// Hubs of the two views at most this far apart are one hub (averaged), fraction of the
    /// image height. Range [0, 0.5].
    pub still_mirror_agree_frac: f64,
    /// Spinner step: with a circle of radius r, blade lines and axes may end up to this many r
    /// from its centre (blades start at the spinner rim).
    pub spinner_reach_radii: f64,
    /// Confidence added when a spinner circle is found with at least two blades starting at its rim.
    pub conf_spinner: f64,
    /// Close range (thesis future work: Hough circles on the hub): a spinner circle at least
    /// this large, fraction of image height, with two blades starting at its rim, is a hub by
    /// itself — at 5–8 m the blades run out of the frame and their edge pairs are too far apart
    /// to be grouped, so blade counting alone fails exactly where the approach ends.
    pub close_spinner_radius_frac: f64,
    /// Lowest confidence of a close-range spinner (see `close_spinner_radius_frac`).
    pub conf_close_spinner: f64,
    /// Least rim coverage of a close-range spinner found by the whole-image search (see
    /// `close_spinner_radius_frac`); `spinner_min_coverage` applies near blade candidates. At
    /// 5–8 m the spinner's rim runs partly against blade roots and the nacelle of about its
    /// own shade, where Canny marks no edge. 0.4 → 0.3: synthetic close hits 61 → 71 % (seed
    /// 2026; seed 77 54.5 → 62 %) at one or two more false positives in 48 negatives (a
    /// cloud's edge); 0.25 detects 10 of 48 negatives.
    pub close_spinner_min_coverage: f64,
    /// The whole-image close-range search votes for centres with every this-many-th edge
    /// point (in row order), and measures rim coverage with all of them. Its circles are at
    /// least `close_spinner_radius_frac` of the height in radius, a hundred or more rim points
    /// at the working size, and neighbouring points cast nearly the same vote: 2 halves the
    /// vote, the costliest part of the search (about 0.6 of 0.9 ms per frame). 1: every point.
    /// Session 33, 2 against 1: synthetic close hits seeds 2026 / 77 / 500 89.5 / 88.5 / 84.5
    /// → 89.0 / 88.5 / 84.0 % (one frame each way), false positives and photo hits the same.
    pub close_spinner_vote_every: u32,
    /// Centre peaks of the whole-image close-range search whose rims are measured
    /// (`spinner_peaks` for the searches around candidates). Session 34, 6 against 12:
    /// synthetic hits seeds 2026 / 77 / 500 / 11–14 93.8 / 93.5 / 92.0 / 91.2 / 93.3 / 91.7 /
    /// 93.0 → 93.8 / 93.7 / 92.0 / 91.3 / 93.2 / 91.7 / 93.0 %, close 2 frames fewer of 1,400,
    /// false positives and photos the same, and no time gained that the bench could see (two
    /// A/B rounds in one sitting: the geometry step 3.13 against 3.12 ms); 3: close hits seed
    /// 2026 89.0 → 86.0 %.
    pub close_spinner_peaks: u32,
    /// Before acquisition (no tracker's prediction), when the learned heatmap's peak is at
    /// least this probable, the close-range search looks for centres only near it
    /// (`close_spinner_heat_box_frac`), from the edge points that can reach them; below it, with
    /// a prediction, or at 0 (off) over the whole image. The whole-image search ran on every
    /// frame without a tracker, ~0.6 ms. Session 34, 0.5 with a box of ±0.2 h against off:
    /// bench default 5.50–5.65 → 4.99–5.25 ms (three A/B rounds), synthetic hits seeds 2026 /
    /// 77 / 500 / 11–14 93.8 / 93.5 / 92.0 / 91.2 / 93.3 / 91.7 / 93.0 → 92.8 / 93.7 / 92.3 /
    /// 92.0 / 92.0 / 92.0 / 92.5 % (close 607.5 → 606 summed points; seed 500 close 84.0 →
    /// 85.5 %, seed 12 87.5 → 84.5 %), photos and false positives the same; 0.3 about the
    /// same; `hubtrack fly` seeds 161–240 79 of 80 either way, every outcome the same (flights
    /// acquire at 30 m, where no close spinner is searched for).
    pub close_spinner_heat_min: f64,
    /// ... within this of the peak, fraction of the image height (half the box's side).
    pub close_spinner_heat_box_frac: f64,
    /// Without a tracker's prediction, search the whole image for close spinners in every
    /// frame and let each be a candidate, instead of only when nothing else is detected. With
    /// the learned ranking: synthetic hits seeds 2026 / 77 / 500 76.7 / 73.7 / 71.2 → 78.0 /
    /// 74.2 / 72.0 % (close 74.5 → 79.5 % at seed 2026), false positives and photos unchanged;
    /// detect median 2.65 → 3.33 ms single-threaded at 1920×1080 on frames without a tracker.
    pub close_spinner_always: bool,
    /// A long line passing within this of a candidate, fraction of image height, and extending
    /// at least `through_margin_frac` beyond it on both sides, puts the candidate on a tower,
    /// mast or wire rather than at a hub (blades and the tower end at the hub).
    pub through_dist_frac: f64,
    /// See `through_dist_frac`, fraction of image height (more than `tower_top_max_above_frac`:
    /// the tower edge may show a little above the hub).
    pub through_margin_frac: f64,
    /// Confidence removed from a candidate that a long line passes through.
    pub conf_through_penalty: f64,
    /// A supporting line with a nearly collinear continuation on the far side of the candidate
    /// (within this angle, degrees, ...) is a horizon, field border or wire that the turbine
    /// hides, not a blade.
    pub occluded_angle_deg: f64,
    /// ... and within this offset from its line, fraction of image height.
    pub occluded_offset_frac: f64,
    /// ... plus, for lines within `occluded_bent_max_tilt_deg` of horizontal (horizons and
    /// field borders, which a wide lens bends), this angle (degrees) times the distance from
    /// the candidate: the continuation drifts off the straight extension farther out.
    pub occluded_bend_deg: f64,
    /// See `occluded_bend_deg`, degrees from horizontal. Only such lines: a blade pointing up
    /// is nearly collinear with the tower below the hub.
    pub occluded_bent_max_tilt_deg: f64,
    /// Blade seen by one edge (`blade.rs`): its partner edge is searched at least this far
    /// from it, working px (closer is the edge's own Sobel spread).
    pub blade_partner_min_width_px: f64,
    /// ... and at most this far, fraction of image height (blade chords reach ~0.1 h at 8 m
    /// with the GoPro).
    pub blade_partner_max_width_frac: f64,
    /// ... at this many points along the edge.
    pub blade_partner_samples: u32,
    /// ... and must be found at this fraction of them.
    pub blade_partner_min_found_frac: f64,
    /// ... with a response of opposite sign of at least this fraction of the edge's own.
    pub blade_partner_response_ratio: f64,
    /// ... at offsets within this RMS of a straight line, working px.
    pub blade_partner_max_rms_px: f64,
    /// ... whose slope (band width change per px along the blade) is at most this.
    pub blade_partner_max_taper: f64,
    /// Run the learned hub heatmap (`libs/detect/src/heat.rs`, trained on the project's
    /// renderer by `scripts/train-hubnet.sh`) on every frame: it feeds the ranker's `hub_heat`
    /// feature and proposes candidates of its own (`hub_heat_candidate_min`). About 0.8 ms per
    /// frame single-threaded here.
    pub hub_heat: bool,
    /// Run the learned networks (heatmap, hub crop, yaw) with the detector's own kernels
    /// (`libs/detect/src/convnet.rs`) on CPUs with AVX2 and FMA, instead of OpenCV's dnn module
    /// (used anyway on other CPUs). Same networks, outputs equal to float rounding; on this
    /// machine the heatmap takes 0.40 instead of 0.93 ms a frame (session 34).
    pub builtin_nets: bool,
    /// The `hub_heat` feature of a candidate is the heatmap's largest probability within this
    /// many cells (8 network px, ~1/24 of the width) of it. Range [0, 4]; default 1.
    pub hub_heat_radius_cells: f64,
    /// A heatmap peak at least this probable with no candidate within
    /// `hub_heat_radius_cells` of it becomes a candidate itself (refined to its blades'
    /// crossing like any other). Range [0, 1]; default 0.5 (1 = never).
    pub hub_heat_candidate_min: f64,
    /// Place the detected hub with the learned hub crop network (`heat::HubCropNet`, trained on
    /// the renderer by `scripts/train-hubnet.sh`): a crop of the working level around the
    /// chosen candidate, 0.3 of the frame height on a side, gives a probability per 1/16 of the
    /// crop, and the hub moves to its peak. Blade-edge crossings sit up to a spinner radius or
    /// two beside the hub seen obliquely (the edges are half a chord off the blade axes), more
    /// than the 3 % of the image height a hit allows from 12 m on. About 0.2 ms per frame.
    /// Still photos with `still_models` use their own crop model (`models/hubcrop-still.onnx`,
    /// trained with photo-like views too: `scripts/train-hubnet.sh crop-still`), which places the
    /// hub where the video model takes a nacelle seen from above for it (photos 32 → 33 of 53,
    /// photo-like views of seed 2026 64.3 → 67.0 %, session 29).
    pub hub_crop: bool,
    /// ... when the crop's peak probability is at least this. Range [0, 1]; default 0.5.
    pub hub_crop_min: f64,
    /// ... and lies at most this far from the candidate, fraction of the image height.
    /// Range [0, 0.15]; default 0.1.
    pub hub_crop_max_shift_frac: f64,
    /// ... and at least this far: nearer, the blades' crossing stands (within a cell of the
    /// network's peak, geometry places the hub better on real photos). Fraction of the image
    /// height, range [0, 0.15]; default 0.02. 0.03 until session 29, when with the still crop
    /// model and `hub_crop_spinner_escape_radii` 0.02 took synthetic hits seeds 2026 / 77 / 500
    /// from 89.0 / 88.0 / 86.8 to 89.7 / 88.5 / 87.7 % (far 92.0 / 93.5 / 93.0 → 94.0 / 95.0 /
    /// 94.5 %: far hubs 3.2–3.8 % off that the network placed), photo-like views seeds 2026 /
    /// 500 68.7 / 72.3 → 69.3 / 74.0 %, photos 33 of 53 either way (median error 0.84 → 1.16 %
    /// of the height), `hubtrack fly` seeds 161–560 382 of 400 either way (8 in, 8 out).
    pub hub_crop_min_shift_frac: f64,
    /// ... and not when the hub is a spinner circle's centre (the circle places it better) ...
    pub hub_crop_keep_spinner: bool,
    /// ... unless the network's peak lies beyond the circle's rim by this many radii: the
    /// circle was drawn by a blade root or the nacelle's end beside the spinner (most of the
    /// rendered medium-range misses that were detected, session 29), and the network sees the
    /// hub next to it. At 0 (the peak outside the circle) synthetic hits seeds 2026 / 77 / 500
    /// 87.8 / 86.8 / 86.2 → 89.0 / 88.0 / 86.8 % (seed 2026 far 90.5 → 92.0, medium 88.0 →
    /// 89.5, close 85.0 → 85.5 %), photo-like views 67.0 → 68.7 %, photos unchanged; at 0.5
    /// 88.8 / 87.3 %; never keeping the circle (`hub_crop_keep_spinner` false) 88.5 / 87.7 %.
    /// Range [0, 10]; 10 = never (the rule off).
    pub hub_crop_spinner_escape_radii: f64,
    /// Networks' verdict when the lines found nothing: without a tracker's prediction, a frame
    /// with no detection whose heatmap (`hub_heat`) peaks at least this probably, and whose
    /// crop network (`hub_crop`) then places a hub at least `heat_verify_crop_min` probably
    /// within `hub_crop_max_shift_frac` of that peak, is detected there, with the product of
    /// the two probabilities as its confidence (and no tower, blades or circle). Close in the
    /// spinner fills the frame, its rim and the blade roots are of one shade and the lines
    /// give nothing to rank, while both networks still see the hub. Session 30, synthetic
    /// hits far / medium / close, seeds 2026, 77, 500 and the held-out 1234, 4242: 94.0 /
    /// 89.5 / 85.5 → 97.5 / 92.0 / 91.5 %, 95.0 / 92.0 / 78.5 → 97.0 / 95.5 / 85.0 %, 94.5 /
    /// 91.0 / 77.5 → 96.5 / 94.5 / 86.0 %, 96.0 / 90.5 / 80.5 → 99.0 / 94.0 / 87.5 %, 95.5 /
    /// 90.0 / 80.0 → 97.0 / 93.5 / 87.0 %, false positives on their negatives unchanged (0, 1,
    /// 0, 3, 1 of 48; without the line rules below 11 more of 144 on the first three, mast
    /// tops); photo-like views (seeds 2026 / 500) 69.3 / 74.0 → 80.7 / 82.3 % (negatives 1 → 2
    /// / 1 → 1 of 25); real photos unchanged. Range [0, 1]; 1 = off.
    pub heat_verify_min: f64,
    /// See `heat_verify_min`. Range [0, 1].
    pub heat_verify_crop_min: f64,
    /// ... and lines that end within this of that hub, fraction of the image height, must
    /// include one more than `heat_verify_oblique_deg` from both the vertical and the
    /// horizontal: the networks also take a mast's top for a hub; and no long line may pass
    /// through it (`through_dist_frac`, `through_margin_frac`). Range [0, 0.5].
    pub heat_verify_end_frac: f64,
    /// See `heat_verify_end_frac`, degrees. Range [0, 45].
    pub heat_verify_oblique_deg: f64,
    /// ... and at least one such oblique line must pass within this of it, fraction of the
    /// image height (a blade's edge; from 5 m the spinner's rim is within ~0.3 of the height).
    /// Range [0, 2].
    pub heat_verify_blade_frac: f64,
    /// The verdict also replaces a detection whose hub the heatmap rates below this (within
    /// `hub_heat_radius_cells`): the ranking's choice where both networks and the lines
    /// around agree on a hub elsewhere, or the crop network's place for it where they agree on
    /// the same. Synthetic hits (all classes) seeds 2026 / 77 / 500 / 1234 / 4242 at 0 → 0.3 →
    /// 0.5 → 0.7 → 1: 93.7 / 92.5 / 92.3 / 93.5 / 92.5 → 93.8 / 93.5 / 93.0 / 93.7 / 93.2 →
    /// 94.7 / 93.8 / 93.0 / 94.2 / 93.5 → 94.7 / 93.8 / 93.3 / 94.3 / 94.0 → 94.7 / 93.7 /
    /// 93.3 / 94.5 / 94.0 % (at 1 close range loses where a spinner circle placed the hub),
    /// false positives unchanged; photo-like views (2026 / 500) 80.7 / 82.3 → 81.0 / 83.3 %
    /// at 0.7 (session 30). But flights start from such frames (acquisition, search), and
    /// `hubtrack fly` seeds 161–560 at 0.7 gave 376 of 400 against 381 with 0 (2 in, 8 out,
    /// 161 flights changed; the failures the usual yaw close in), so video frames keep 0 and
    /// stills use `still_heat_override_max`. Range [0, 1]; 0 = never.
    pub heat_override_max: f64,
    /// `heat_override_max` for still photos (`Detector::detect_still`): photo-like views
    /// (seeds 2026 / 500) 80.7 / 82.3 → 81.0 / 83.3 % at 0.7. Range [0, 1]; 0 = never.
    pub still_heat_override_max: f64,
    /// Read the relative yaw with the learned yaw network (`heat::HubYawNet`) around a
    /// detected hub, from the tracker's distance or else the spinner circle's (the detection's
    /// `yaw_net_*`; the tracker weighs it in, see `track.yaw.use_net`).
    pub hub_yaw: bool,
    /// ... only from this distance, metres (trained from 3.5 m), range [0, 100] ...
    pub hub_yaw_min_distance_m: f64,
    /// ... up to this one, metres (trained to 46 m: the whole approach from 40 m), range
    /// [0, 100]. At 30 m (the first model, trained to 32 m) `fly` seeds 161–360 gave 190 of
    /// 200; at 45 with the model trained to 46 m, 191.
    pub hub_yaw_max_distance_m: f64,
    /// Close in, read the yaw with a second model trained on views from 3.5–14 m only
    /// (`models/hubyaw-close.onnx`, `scripts/train-hubnet.sh yaw-close`): where the approach
    /// ends, the whole-range model's error was largest (held out, mean 4.0° at 3.5–8 m against
    /// 2.3–2.6° beyond 15 m; the close model 3.3°). Off by default (session 28): as a veto only
    /// it changed no outcome of 57 `fly` seeds, and as the yaw's fallback close in
    /// (`track.yaw.net_fallback_after_s` 1 s, `net_fallback_min_deg` 3°) it saved 13 of session
    /// 26's 19 failures but ended 15 good flights 5–10° off (seeds 161–560, stopped at 179: 164
    /// against 172): its error is still a bias per scene, up to 13° at 5 m (seed 363) ...
    pub hub_yaw_close: bool,
    /// ... up to this distance, metres, range [0, 14] (its training range).
    pub hub_yaw_close_max_distance_m: f64,
    /// How the hub is picked among the candidates.
    pub ranker: RankerParams,
    /// Still photos (`hubtrack detect`, the photos of `hubtrack eval`) use their own learned
    /// heatmap (`models/hubnet-still.onnx`), hub crop (`models/hubcrop-still.onnx`, session 29)
    /// and `still_ranker`, all trained with photo-like rendered views too (drone photos'
    /// viewpoints: from above, among wind farms, the hub anywhere; see the README, "Photo-like
    /// views"); video frames keep `models/hubnet.onnx`, `models/hubcrop.onnx` and `ranker`.
    /// Used everywhere, the photo-trained heatmap and ranking took the development photos from
    /// 56.6 to 60.4 % hits and rendered frames (seed 2026) from 87.8 to 90.5 %, but `fly`
    /// seeds 161–560 from 212 to 202 of the 221 flown (4 in, 14 out); the photo-trained crop
    /// places rendered approach frames' hubs slightly worse (87.8 → 87.2 %).
    pub still_models: bool,
    /// Video frames use the still photos' heatmap and `still_ranker` too (off): how session 27
    /// measured them in flight, and how `scripts/train-ranker.sh still` fits `still_ranker`.
    pub still_models_for_frames: bool,
    /// The candidate ranking of still photos with `still_models` (see `ranker`).
    pub still_ranker: RankerParams,
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

/// The learned candidate ranker (`ranker.rs`, trained by `scripts/train-ranker.sh` on the
/// project's renderer, never on `../shared/data`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RankerParams {
    /// `"learned"`: the candidate with the highest score `weights · features` wins and is the
    /// hub when the score reaches `min_score`; the reported confidence is `1 / (1 + e^-score)`.
    /// `"rules"`: the highest `conf_*` sum wins, detected at `min_confidence` (the rules'
    /// confidence is also one of the learned features, `rule_score`). Session 19, `hubtrack
    /// eval` learned / rules: real photos 39.6 / 37.7 % hits, synthetic 78.0 / 69.5 % with
    /// 4.2 / 6.2 % false positives (seed 77: 74.2 / 66.0 % with 2.1 / 22.9 %).
    pub ranking: Ranking,
    /// With `"learned"`: the best candidate is the hub when its score (log-odds against "no
    /// hub in this frame") reaches this. Chosen on the training seeds (11–18, 600 negatives)
    /// with the `hub_heat` model of session 24: −1 (a probability of 0.27) 77.8 % hits with
    /// 6.8 % false positives, −0.5 76.3 % with 4.0 %, −0.25 75.8 % with 2.5 %, 0 75.2 % with
    /// 1.5 %. Held out (`hubtrack eval`, seeds 2026 / 77 / 500): −1 83.7 / 78.8 / 78.5 % hits
    /// with 4.2 / 12.5 / 2.1 % false positives; −0.5 81.0 / 77.7 / 76.5 % with 0 / 2.1 / 0.
    /// Before the heatmap (session 19) the default was −1. For `still_ranker` (session 27):
    /// −0.1, chosen the same way (training frames of seeds 11–18 and photo-like views 11–14:
    /// −0.5 76.5 % hits with 6.3 % false positives, −0.25 75.6 % with 4.1 %, −0.1 75.0 % with
    /// 3.3 %, 0 74.5 % with 2.9 %; the first under 4 %).
    pub min_score: f64,
    /// Log-odds per unit of each feature (`hubtrack train-ranker` prints a fitted section).
    pub weights: FeatureWeights,
}

/// Weight of each candidate feature in the learned score (log-odds per unit of the feature).
/// Lengths are fractions of the working image height. Fitted by `scripts/train-ranker.sh`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FeatureWeights {
    /// Constant term.
    pub bias: f64,
    /// 1 when exactly two blade groups remain.
    pub two_blades: f64,
    /// 1 when exactly three remain.
    pub three_blades: f64,
    /// Blade groups beyond three (0..3).
    pub extra_blades: f64,
    /// 1 when tower lines run down from below the candidate.
    pub tower: f64,
    /// Number of such tower lines / 4 (at most 1).
    pub tower_lines: f64,
    /// 1 when two blades ~120° apart leave the third hidden straight down the tower.
    pub hidden_blade_down: f64,
    /// 1 when the strongest blades' separations fit a three-bladed rotor (`blade_sep_tol_deg`).
    pub geometry_ok: f64,
    /// Blades seen by both edges (or with a band axis) / 3 (at most 1).
    pub paired: f64,
    /// 1 when a spinner circle is centred on the candidate.
    pub spinner: f64,
    /// The spinner's radius.
    pub spinner_radius: f64,
    /// 1 when that radius is the one the tracker's distance expects (`spinner_size_match_tol`).
    pub spinner_size_match: f64,
    /// 1 when a long line passes through the candidate (tower, mast, wire).
    pub passes_through: f64,
    /// 1 when the candidate lies within `prediction_radius_frac` of the tracker's prediction.
    pub near_prediction: f64,
    /// Summed length of the (up to three) strongest blades.
    pub support: f64,
    /// Length of the weakest of them (0 with fewer than two).
    pub weakest_blade: f64,
    /// Length of the strongest.
    pub strongest_blade: f64,
    /// Mean distance of the blades' pairwise separations from 120° (or 240°), in units of 60°
    /// (1 with fewer than two blades).
    pub separation_error: f64,
    /// Lines dropped as tower, opposite or weak blades / 10 (at most 1).
    pub rejected_lines: f64,
    /// The rules' confidence before capping (`conf_*` sums).
    pub rule_score: f64,
    /// Usable lines passing within the support reach that neither support the candidate nor
    /// belong to its tower / 10 (at most 1): texture around a false candidate.
    pub clutter: f64,
    /// Blades whose two edges pair into a band with an axis / 3 (at most 1).
    pub banded_blades: f64,
    /// How far the tower's top lies below the candidate (±0.5; 0 without a tower).
    pub tower_top_below: f64,
    /// Usable lines in the whole image / 200 (at most 1): how textured the frame is.
    pub image_lines: f64,
    /// Rim coverage of the spinner circle (0..1; 0 without one).
    pub spinner_coverage: f64,
    /// Distance from the spinner circle's centre to where its blades' axes meet, in radii (at
    /// most 2; 0 without a circle above `spinner_kept_support_max_radius_px` or without two
    /// known axes): a round patch beside the hub has a rim drawn by blade edges but is centred
    /// beside the point the blades radiate from.
    pub spinner_axes_offset: f64,
    /// The learned hub heatmap's probability at the candidate (0..1; 0 with `hub_heat` off):
    /// whether the frame around it looks like a hub to a network that saw the whole image.
    pub hub_heat: f64,
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

impl Default for RankerParams {
    fn default() -> Self {
        RankerParams {
            ranking: Ranking::Learned,
            min_score: -0.5,
            weights: FeatureWeights::default(),
        }
    }
}

impl Default for FeatureWeights {
    /// Fitted by `scripts/train-ranker.sh -- --also-without hub_heat` (see the README,
    /// "Learned ranking" and "Learned hub heatmap") in session 24, with the shipped
    /// `models/hubnet.onnx`: every training frame also counts once with `hub_heat` zeroed, so
    /// the ranker does not depend on a network that has seen renders only.
    fn default() -> Self {
        FeatureWeights {
            bias: -0.501,
            two_blades: -1.966,
            three_blades: -0.480,
            extra_blades: -0.113,
            tower: 0.062,
            tower_lines: 0.361,
            hidden_blade_down: 0.640,
            geometry_ok: 0.447,
            paired: 2.998,
            spinner: 0.741,
            spinner_radius: 0.322,
            spinner_size_match: 1.614,
            passes_through: -0.446,
            near_prediction: 0.345,
            support: 0.434,
            weakest_blade: 0.916,
            strongest_blade: -0.298,
            separation_error: -1.734,
            rejected_lines: 1.020,
            rule_score: -0.347,
            clutter: -2.942,
            banded_blades: -1.906,
            tower_top_below: 0.397,
            image_lines: -0.173,
            spinner_coverage: 4.675,
            spinner_axes_offset: -1.136,
            hub_heat: 2.110,
        }
    }
}

impl FeatureWeights {
    /// The still photos' weights (`still_ranker`): fitted by `scripts/train-ranker.sh` in
    /// session 27 with the still heatmap (`models/hubnet-still.onnx`) and photo-like views
    /// among the training frames (see the README, "Photo-like views"); every training frame
    /// also counts once with `hub_heat` zeroed.
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

impl RankerParams {
    /// Checks the values; errors name the keys under `section` (e.g. `detect.default.ranker`).
    fn validate(&self, section: &str) -> Result<(), ParamError> {
        let c = Check::new(section);
        c.closed("min_score", self.min_score, -50.0, 50.0)?;
        let weights = format!("{section}.weights");
        let w = Check::new(&weights);
        for (name, v) in crate::ranker::FEATURE_NAMES
            .iter()
            .zip(self.weights.to_array())
        {
            w.closed(name, v, -100.0, 100.0)?;
        }
        Ok(())
    }
}

impl Default for DefaultParams {
    fn default() -> Self {
        DefaultParams {
            pyramid_max_side_px: 500,
            pyramid_min_side_px: 200,
            box_first_level: true,
            canny_high_percentile: 0.95,
            canny_high_min: 100.0,
            canny_high_max: 200.0,
            canny_low_ratio: 0.5,
            hough_rho_px: 1.0,
            hough_theta_deg: 1.0,
            hough_threshold_frac: 0.1,
            hough_min_length_frac: 0.08,
            hough_max_gap_frac: 0.02,
            hough_orientation_tol_deg: 10.0,
            max_segments: 200,
            merge_angle_deg: 3.0,
            merge_offset_px: 2.0,
            merge_gap_frac: 0.05,
            horizon_min_length_frac: 0.4,
            horizon_max_tilt_deg: 8.0,
            horizon_band_min_taper: 1.25,
            candidate_min_length_frac: 0.1,
            candidate_min_angle_deg: 25.0,
            candidate_end_reach_frac: 0.6,
            candidate_inside_frac: 0.1,
            cluster_radius_frac: 0.04,
            support_line_dist_frac: 0.03,
            support_end_dist_frac: 0.15,
            blade_group_tol_deg: 8.0,
            blade_min_separation_deg: 30.0,
            blade_max_separation_deg: 180.0,
            blade_target_deg: 120.0,
            blade_sep_tol_deg: 45.0,
            tower_max_tilt_deg: 8.0,
            tower_top_max_below_frac: 0.15,
            tower_top_max_above_frac: 0.03,
            tower_max_dx_frac: 0.12,
            tower_top_max_below_radii: 1.5,
            tower_max_dx_radii: 2.0,
            tower_width_hint_tol: 1.5,
            tower_width_min_radii: 0.5,
            tower_width_max_radii: 1.6,
            tower_width_spinner_tol: 1.5,
            tower_scan_start_frac: 0.06,
            tower_scan_start_radii: 1.2,
            tower_scan_min_salience: 3.0,
            roll_search_deg: 10.0,
            prediction_radius_frac: 0.15,
            prediction_bonus: 0.1,
            spinner_size_match_tol: 1.25,
            spinner_size_match_bonus: 0.15,
            conf_two_blades: 0.3,
            conf_three_blades: 0.5,
            hidden_blade_tol_deg: 15.0,
            conf_tower: 0.25,
            conf_geometry: 0.15,
            conf_paired: 0.1,
            conf_extra_blade_penalty: 0.1,
            min_confidence: 0.75,
            tower_width_below_top_frac: 0.05,
            tower_min_width_frac: 0.02,
            tower_max_width_frac: 0.25,
            tower_partner_min_ratio: 0.15,
            tower_partner_min_salience: 4.0,
            tower_same_sign_partner_min_ratio: 0.5,
            tower_ramp_min_frac: 0.8,
            tower_ramp_max_frac: 0.3,
            tower_min_width_ratio: 0.9,
            tower_max_width_ratio: 1.15,
            tower_taper: 0.03,
            tower_blade_down_tol_deg: 12.0,
            tower_blade_ray_tol_deg: 25.0,
            tower_blade_ray_min_deg: 5.0,
            tower_blade_down_max_distance_m: 0.0,
            tower_blade_axis_tol_frac: 0.025,
            nacelle_band_half_m: 1.0,
            nacelle_min_offset_m: 2.0,
            nacelle_max_offset_m: 10.0,
            nacelle_min_response: 40.0,
            nacelle_min_ratio: 2.0,
            pair_min_length_frac: 0.06,
            pair_max_angle_deg: 10.0,
            pair_min_overlap_frac: 0.5,
            pair_min_width_px: 2.5,
            pair_max_width_frac: 0.15,
            pair_max_width_to_length: 0.5,
            axis_reach_widths: 3.0,
            axis_line_dist_frac: 0.015,
            axis_angle_tol_deg: 3.0,
            axis_proposal_weight: 2.0,
            spinner_candidates: 3,
            spinner_search_frac: 0.4,
            spinner_max_offset_frac: 0.15,
            spinner_min_radius_px: 4.0,
            spinner_max_radius_frac: 0.32,
            spinner_hint_radius_lo: 0.5,
            spinner_hint_radius_hi: 2.0,
            blade_partner_min_width_px: 2.0,
            blade_partner_max_width_frac: 0.1,
            blade_partner_samples: 9,
            blade_partner_min_found_frac: 0.6,
            blade_partner_response_ratio: 0.3,
            blade_partner_max_rms_px: 1.5,
            blade_partner_max_taper: 0.15,
            spinner_cell_px: 2.0,
            spinner_radial_tol_deg: 25.0,
            spinner_min_coverage: 0.4,
            spinner_vote_every: 1,
            spinner_peaks: 12,
            spinner_hint_min_coverage: 0.25,
            spinner_nest_min_coverage_ratio: 0.8,
            spinner_min_kept_support: 0.7,
            spinner_kept_support_max_radius_px: 8.0,
            spinner_max_interior_density: 0.1,
            still_finer_level: true,
            still_mirror: StillMirror::Either,
            still_mirror_agree_frac: 0.06,
            spinner_reach_radii: 2.0,
            conf_spinner: 0.2,
            close_spinner_radius_frac: 0.12,
            conf_close_spinner: 0.8,
            close_spinner_min_coverage: 0.3,
            close_spinner_vote_every: 2,
            close_spinner_peaks: 12,
            close_spinner_heat_min: 0.5,
            close_spinner_heat_box_frac: 0.2,
            close_spinner_always: true,
            through_dist_frac: 0.01,
            through_margin_frac: 0.05,
            conf_through_penalty: 0.3,
            occluded_angle_deg: 3.0,
            occluded_offset_frac: 0.008,
            occluded_bend_deg: 3.0,
            occluded_bent_max_tilt_deg: 20.0,
            hub_heat: true,
            builtin_nets: true,
            hub_heat_radius_cells: 1.0,
            hub_heat_candidate_min: 0.5,
            hub_crop: true,
            hub_crop_min: 0.5,
            hub_crop_max_shift_frac: 0.1,
            hub_crop_min_shift_frac: 0.02,
            hub_crop_keep_spinner: true,
            hub_crop_spinner_escape_radii: 0.0,
            heat_verify_min: 0.5,
            heat_verify_crop_min: 0.5,
            heat_verify_end_frac: 0.06,
            heat_verify_oblique_deg: 15.0,
            heat_verify_blade_frac: 0.3,
            heat_override_max: 0.0,
            still_heat_override_max: 0.7,
            hub_yaw: true,
            hub_yaw_min_distance_m: 3.5,
            hub_yaw_max_distance_m: 45.0,
            hub_yaw_close: false,
            hub_yaw_close_max_distance_m: 12.0,
            ranker: RankerParams::default(),
            still_models: true,
            still_models_for_frames: false,
            still_ranker: RankerParams {
                ranking: Ranking::Learned,
                min_score: -0.1,
                weights: FeatureWeights::still(),
            },
        }
    }
}

impl DetectConfig {
    /// Check every parameter's range; the error names the first offending key.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.camera.validate()?;
        self.thesis.validate()?;
        self.default.validate()
    }
}

impl CameraParams {
    fn validate(&self) -> Result<(), ParamError> {
        let c = Check::new("detect.camera");
        c.closed("hfov_deg", self.hfov_deg, 1.0, 179.0)?;
        if self.focal_length_per_width != 0.0 {
            c.closed(
                "focal_length_per_width",
                self.focal_length_per_width,
                0.05,
                10.0,
            )?;
        }
        c.closed("tower_top_diameter_m", self.tower_top_diameter_m, 0.1, 30.0)?;
        c.closed("hub_tower_gap_m", self.hub_tower_gap_m, 0.1, 50.0)?;
        c.closed("spinner_diameter_m", self.spinner_diameter_m, 0.1, 30.0)
    }
}

impl ThesisParams {
    fn validate(&self) -> Result<(), ParamError> {
        let c = Check::new("detect.thesis");
        c.closed(
            "pyramid_min_side_px",
            self.pyramid_min_side_px as f64,
            16.0,
            4096.0,
        )?;
        c.closed(
            "pyramid_max_side_px",
            self.pyramid_max_side_px as f64,
            16.0,
            4096.0,
        )?;
        c.less(
            "pyramid_min_side_px",
            self.pyramid_min_side_px as f64,
            "pyramid_max_side_px",
            self.pyramid_max_side_px as f64,
        )?;
        c.closed("canny_low", self.canny_low, 0.0, 4096.0)?;
        c.closed("canny_high", self.canny_high, 0.0, 4096.0)?;
        c.less(
            "canny_low",
            self.canny_low,
            "canny_high",
            self.canny_high + f64::EPSILON,
        )?;
        c.closed("hough_rho_px", self.hough_rho_px, 0.1, 10.0)?;
        c.closed("hough_theta_deg", self.hough_theta_deg, 0.05, 10.0)?;
        c.closed(
            "hough_threshold",
            self.hough_threshold as f64,
            1.0,
            10_000.0,
        )?;
        c.closed("hough_min_length_px", self.hough_min_length_px, 1.0, 4096.0)?;
        c.closed("hough_max_gap_px", self.hough_max_gap_px, 0.0, 4096.0)?;
        c.closed("tower_max_tilt_deg", self.tower_max_tilt_deg, 0.0, 45.0)?;
        c.closed("tower_bottom_frac", self.tower_bottom_frac, 0.0, 1.0)?;
        c.closed("search_radius_frac", self.search_radius_frac, 0.01, 2.0)?;
        c.closed("blade_group_tol_deg", self.blade_group_tol_deg, 0.0, 60.0)?;
        c.closed(
            "blade_over_tower_tol_deg",
            self.blade_over_tower_tol_deg,
            0.0,
            90.0,
        )?;
        c.closed("vote_target_deg", self.vote_target_deg, 0.0, 180.0)?;
        c.closed("vote_tol_deg", self.vote_tol_deg, 0.0, 180.0)?;
        c.closed("vote_limit", self.vote_limit as f64, 1.0, 100.0)?;
        c.closed("hub_max_dx_frac", self.hub_max_dx_frac, 0.0, 10.0)?;
        c.closed("hub_max_dy_frac", self.hub_max_dy_frac, 0.0, 10.0)?;
        c.closed(
            "min_blades",
            self.min_blades as f64,
            2.0,
            crate::MAX_BLADES_F,
        )?;
        c.closed(
            "tower_width_below_top_frac",
            self.tower_width_below_top_frac,
            0.0,
            1.0,
        )
    }
}

impl DefaultParams {
    fn validate(&self) -> Result<(), ParamError> {
        let c = Check::new("detect.default");
        c.closed(
            "pyramid_min_side_px",
            self.pyramid_min_side_px as f64,
            16.0,
            4096.0,
        )?;
        c.closed(
            "pyramid_max_side_px",
            self.pyramid_max_side_px as f64,
            16.0,
            4096.0,
        )?;
        c.less(
            "pyramid_min_side_px",
            self.pyramid_min_side_px as f64,
            "pyramid_max_side_px",
            self.pyramid_max_side_px as f64,
        )?;
        c.closed(
            "canny_high_percentile",
            self.canny_high_percentile,
            0.0,
            1.0,
        )?;
        c.closed("canny_high_min", self.canny_high_min, 1.0, 4096.0)?;
        c.closed("canny_high_max", self.canny_high_max, 1.0, 4096.0)?;
        c.less(
            "canny_high_min",
            self.canny_high_min,
            "canny_high_max",
            self.canny_high_max + f64::EPSILON,
        )?;
        c.closed("canny_low_ratio", self.canny_low_ratio, 0.05, 1.0)?;
        c.closed("hough_rho_px", self.hough_rho_px, 0.1, 10.0)?;
        c.closed("hough_theta_deg", self.hough_theta_deg, 0.05, 10.0)?;
        c.closed(
            "hough_threshold_frac",
            self.hough_threshold_frac,
            0.001,
            1.0,
        )?;
        c.closed(
            "hough_min_length_frac",
            self.hough_min_length_frac,
            0.001,
            1.0,
        )?;
        c.closed("hough_max_gap_frac", self.hough_max_gap_frac, 0.0, 1.0)?;
        c.closed(
            "hough_orientation_tol_deg",
            self.hough_orientation_tol_deg,
            0.0,
            90.0,
        )?;
        c.closed("max_segments", self.max_segments as f64, 2.0, 10_000.0)?;
        c.closed("merge_angle_deg", self.merge_angle_deg, 0.0, 30.0)?;
        c.closed("merge_offset_px", self.merge_offset_px, 0.0, 50.0)?;
        c.closed("merge_gap_frac", self.merge_gap_frac, 0.0, 1.0)?;
        c.closed(
            "horizon_min_length_frac",
            self.horizon_min_length_frac,
            0.0,
            2.0,
        )?;
        c.closed("horizon_max_tilt_deg", self.horizon_max_tilt_deg, 0.0, 45.0)?;
        c.closed(
            "horizon_band_min_taper",
            self.horizon_band_min_taper,
            0.0,
            100.0,
        )?;
        c.closed(
            "candidate_min_length_frac",
            self.candidate_min_length_frac,
            0.0,
            2.0,
        )?;
        c.closed(
            "candidate_min_angle_deg",
            self.candidate_min_angle_deg,
            0.0,
            90.0,
        )?;
        c.closed(
            "candidate_end_reach_frac",
            self.candidate_end_reach_frac,
            0.0,
            10.0,
        )?;
        c.closed(
            "candidate_inside_frac",
            self.candidate_inside_frac,
            0.0,
            0.5,
        )?;
        c.closed("cluster_radius_frac", self.cluster_radius_frac, 0.001, 1.0)?;
        c.closed(
            "support_line_dist_frac",
            self.support_line_dist_frac,
            0.0,
            1.0,
        )?;
        c.closed(
            "support_end_dist_frac",
            self.support_end_dist_frac,
            0.0,
            2.0,
        )?;
        c.closed("blade_group_tol_deg", self.blade_group_tol_deg, 0.0, 60.0)?;
        c.closed(
            "blade_min_separation_deg",
            self.blade_min_separation_deg,
            0.0,
            120.0,
        )?;
        c.closed(
            "blade_max_separation_deg",
            self.blade_max_separation_deg,
            120.0,
            180.0,
        )?;
        c.closed("blade_target_deg", self.blade_target_deg, 0.0, 180.0)?;
        c.closed("blade_sep_tol_deg", self.blade_sep_tol_deg, 0.0, 180.0)?;
        c.closed("tower_max_tilt_deg", self.tower_max_tilt_deg, 0.0, 45.0)?;
        c.closed(
            "tower_top_max_below_frac",
            self.tower_top_max_below_frac,
            0.0,
            2.0,
        )?;
        c.closed(
            "tower_top_max_above_frac",
            self.tower_top_max_above_frac,
            0.0,
            2.0,
        )?;
        c.closed("tower_max_dx_frac", self.tower_max_dx_frac, 0.0, 2.0)?;
        c.closed(
            "tower_top_max_below_radii",
            self.tower_top_max_below_radii,
            0.0,
            10.0,
        )?;
        c.closed("tower_max_dx_radii", self.tower_max_dx_radii, 0.0, 10.0)?;
        c.closed("tower_width_hint_tol", self.tower_width_hint_tol, 1.0, 10.0)?;
        c.closed(
            "tower_width_min_radii",
            self.tower_width_min_radii,
            0.0,
            10.0,
        )?;
        c.closed(
            "tower_width_max_radii",
            self.tower_width_max_radii,
            0.0,
            10.0,
        )?;
        c.zero_or_closed(
            "tower_width_spinner_tol",
            self.tower_width_spinner_tol,
            1.0,
            10.0,
        )?;
        c.closed(
            "tower_scan_start_frac",
            self.tower_scan_start_frac,
            0.0,
            1.0,
        )?;
        c.closed(
            "tower_scan_start_radii",
            self.tower_scan_start_radii,
            0.0,
            10.0,
        )?;
        c.closed(
            "tower_scan_min_salience",
            self.tower_scan_min_salience,
            1.0,
            100.0,
        )?;
        c.less(
            "tower_width_min_radii",
            self.tower_width_min_radii,
            "tower_width_max_radii",
            self.tower_width_max_radii,
        )?;
        c.closed("roll_search_deg", self.roll_search_deg, 0.0, 45.0)?;
        c.closed(
            "prediction_radius_frac",
            self.prediction_radius_frac,
            0.0,
            2.0,
        )?;
        c.closed("prediction_bonus", self.prediction_bonus, 0.0, 1.0)?;
        c.closed(
            "spinner_size_match_tol",
            self.spinner_size_match_tol,
            1.0,
            10.0,
        )?;
        c.closed(
            "spinner_size_match_bonus",
            self.spinner_size_match_bonus,
            0.0,
            1.0,
        )?;
        c.closed("conf_two_blades", self.conf_two_blades, 0.0, 1.0)?;
        c.closed("conf_three_blades", self.conf_three_blades, 0.0, 1.0)?;
        c.closed("hidden_blade_tol_deg", self.hidden_blade_tol_deg, 0.0, 60.0)?;
        c.closed("conf_tower", self.conf_tower, 0.0, 1.0)?;
        c.closed("conf_geometry", self.conf_geometry, 0.0, 1.0)?;
        c.closed("conf_paired", self.conf_paired, 0.0, 1.0)?;
        c.closed(
            "conf_extra_blade_penalty",
            self.conf_extra_blade_penalty,
            0.0,
            1.0,
        )?;
        c.closed("min_confidence", self.min_confidence, 0.0, 1.0)?;
        c.closed(
            "tower_width_below_top_frac",
            self.tower_width_below_top_frac,
            0.0,
            1.0,
        )?;
        c.closed("tower_min_width_frac", self.tower_min_width_frac, 0.0, 1.0)?;
        c.closed("tower_max_width_frac", self.tower_max_width_frac, 0.0, 1.0)?;
        c.closed(
            "tower_partner_min_ratio",
            self.tower_partner_min_ratio,
            0.0,
            1.0,
        )?;
        c.closed(
            "tower_partner_min_salience",
            self.tower_partner_min_salience,
            0.0,
            1000.0,
        )?;
        c.closed(
            "tower_same_sign_partner_min_ratio",
            self.tower_same_sign_partner_min_ratio,
            0.0,
            1000.0,
        )?;
        c.closed("tower_ramp_min_frac", self.tower_ramp_min_frac, 0.0, 1.0)?;
        c.closed("tower_ramp_max_frac", self.tower_ramp_max_frac, 0.0, 1.0)?;
        c.closed(
            "tower_min_width_ratio",
            self.tower_min_width_ratio,
            0.0,
            10.0,
        )?;
        c.closed(
            "tower_max_width_ratio",
            self.tower_max_width_ratio,
            0.0,
            10.0,
        )?;
        c.closed("tower_taper", self.tower_taper, 0.0, 1.0)?;
        c.less(
            "tower_min_width_ratio",
            self.tower_min_width_ratio,
            "tower_max_width_ratio",
            self.tower_max_width_ratio,
        )?;
        c.closed(
            "tower_blade_down_tol_deg",
            self.tower_blade_down_tol_deg,
            0.0,
            60.0,
        )?;
        c.closed(
            "tower_blade_ray_tol_deg",
            self.tower_blade_ray_tol_deg,
            0.0,
            60.0,
        )?;
        c.closed(
            "tower_blade_ray_min_deg",
            self.tower_blade_ray_min_deg,
            0.0,
            60.0,
        )?;
        c.closed(
            "tower_blade_down_max_distance_m",
            self.tower_blade_down_max_distance_m,
            0.0,
            1000.0,
        )?;
        c.closed(
            "tower_blade_axis_tol_frac",
            self.tower_blade_axis_tol_frac,
            0.0,
            1.0,
        )?;
        c.closed("nacelle_band_half_m", self.nacelle_band_half_m, 0.0, 20.0)?;
        c.less(
            "nacelle_min_offset_m",
            self.nacelle_min_offset_m,
            "nacelle_max_offset_m",
            self.nacelle_max_offset_m,
        )?;
        c.closed(
            "nacelle_min_offset_m",
            self.nacelle_min_offset_m,
            0.0,
            100.0,
        )?;
        c.closed(
            "nacelle_max_offset_m",
            self.nacelle_max_offset_m,
            0.0,
            100.0,
        )?;
        c.closed(
            "nacelle_min_response",
            self.nacelle_min_response,
            0.0,
            4080.0,
        )?;
        c.closed("nacelle_min_ratio", self.nacelle_min_ratio, 1.0, 1000.0)?;
        c.less(
            "tower_min_width_frac",
            self.tower_min_width_frac,
            "tower_max_width_frac",
            self.tower_max_width_frac,
        )?;
        c.closed("pair_min_length_frac", self.pair_min_length_frac, 0.0, 2.0)?;
        c.closed("pair_max_angle_deg", self.pair_max_angle_deg, 0.0, 45.0)?;
        c.closed(
            "pair_min_overlap_frac",
            self.pair_min_overlap_frac,
            0.0,
            1.0,
        )?;
        c.closed("pair_min_width_px", self.pair_min_width_px, 0.0, 100.0)?;
        c.closed("pair_max_width_frac", self.pair_max_width_frac, 0.0, 1.0)?;
        c.closed(
            "pair_max_width_to_length",
            self.pair_max_width_to_length,
            0.0,
            10.0,
        )?;
        c.closed("axis_reach_widths", self.axis_reach_widths, 0.0, 20.0)?;
        c.closed("axis_line_dist_frac", self.axis_line_dist_frac, 0.0, 1.0)?;
        c.closed("axis_angle_tol_deg", self.axis_angle_tol_deg, 0.0, 45.0)?;
        c.closed(
            "axis_proposal_weight",
            self.axis_proposal_weight,
            0.0,
            100.0,
        )?;
        c.closed(
            "spinner_candidates",
            self.spinner_candidates as f64,
            0.0,
            10.0,
        )?;
        c.closed("spinner_search_frac", self.spinner_search_frac, 0.01, 1.0)?;
        c.closed(
            "spinner_max_offset_frac",
            self.spinner_max_offset_frac,
            0.0,
            1.0,
        )?;
        c.closed(
            "spinner_min_radius_px",
            self.spinner_min_radius_px,
            1.0,
            1000.0,
        )?;
        c.closed(
            "spinner_max_radius_frac",
            self.spinner_max_radius_frac,
            0.01,
            1.0,
        )?;
        c.closed(
            "spinner_hint_radius_lo",
            self.spinner_hint_radius_lo,
            0.0,
            1.0,
        )?;
        c.closed(
            "spinner_hint_radius_hi",
            self.spinner_hint_radius_hi,
            1.0,
            100.0,
        )?;
        c.closed(
            "blade_partner_min_width_px",
            self.blade_partner_min_width_px,
            1.0,
            100.0,
        )?;
        c.closed(
            "blade_partner_max_width_frac",
            self.blade_partner_max_width_frac,
            0.0,
            1.0,
        )?;
        c.closed(
            "blade_partner_samples",
            self.blade_partner_samples as f64,
            2.0,
            100.0,
        )?;
        c.closed(
            "blade_partner_min_found_frac",
            self.blade_partner_min_found_frac,
            0.0,
            1.0,
        )?;
        c.closed(
            "blade_partner_response_ratio",
            self.blade_partner_response_ratio,
            0.0,
            10.0,
        )?;
        c.closed(
            "blade_partner_max_rms_px",
            self.blade_partner_max_rms_px,
            0.0,
            100.0,
        )?;
        c.closed(
            "blade_partner_max_taper",
            self.blade_partner_max_taper,
            0.0,
            1.0,
        )?;
        c.closed("spinner_cell_px", self.spinner_cell_px, 0.5, 20.0)?;
        c.closed(
            "spinner_radial_tol_deg",
            self.spinner_radial_tol_deg,
            0.0,
            90.0,
        )?;
        c.closed("spinner_min_coverage", self.spinner_min_coverage, 0.0, 1.0)?;
        c.closed(
            "spinner_hint_min_coverage",
            self.spinner_hint_min_coverage,
            0.0,
            1.0,
        )?;
        c.closed(
            "spinner_nest_min_coverage_ratio",
            self.spinner_nest_min_coverage_ratio,
            0.0,
            10.0,
        )?;
        c.closed(
            "close_spinner_min_coverage",
            self.close_spinner_min_coverage,
            0.0,
            1.0,
        )?;
        c.closed(
            "close_spinner_vote_every",
            self.close_spinner_vote_every as f64,
            1.0,
            16.0,
        )?;
        c.closed(
            "spinner_vote_every",
            self.spinner_vote_every as f64,
            1.0,
            16.0,
        )?;
        c.closed("spinner_peaks", self.spinner_peaks as f64, 1.0, 64.0)?;
        c.closed(
            "close_spinner_peaks",
            self.close_spinner_peaks as f64,
            1.0,
            64.0,
        )?;
        c.closed(
            "close_spinner_heat_min",
            self.close_spinner_heat_min,
            0.0,
            1.0,
        )?;
        c.closed(
            "close_spinner_heat_box_frac",
            self.close_spinner_heat_box_frac,
            0.01,
            1.0,
        )?;
        c.closed(
            "hub_heat_radius_cells",
            self.hub_heat_radius_cells,
            0.0,
            4.0,
        )?;
        c.closed(
            "hub_heat_candidate_min",
            self.hub_heat_candidate_min,
            0.0,
            1.0,
        )?;
        c.closed("hub_crop_min", self.hub_crop_min, 0.0, 1.0)?;
        c.closed("heat_verify_min", self.heat_verify_min, 0.0, 1.0)?;
        c.closed("heat_verify_crop_min", self.heat_verify_crop_min, 0.0, 1.0)?;
        c.closed("heat_verify_end_frac", self.heat_verify_end_frac, 0.0, 0.5)?;
        c.closed(
            "heat_verify_oblique_deg",
            self.heat_verify_oblique_deg,
            0.0,
            45.0,
        )?;
        c.closed(
            "heat_verify_blade_frac",
            self.heat_verify_blade_frac,
            0.0,
            2.0,
        )?;
        c.closed("heat_override_max", self.heat_override_max, 0.0, 1.0)?;
        c.closed(
            "still_heat_override_max",
            self.still_heat_override_max,
            0.0,
            1.0,
        )?;
        c.closed(
            "still_mirror_agree_frac",
            self.still_mirror_agree_frac,
            0.0,
            0.5,
        )?;
        c.closed(
            "hub_crop_max_shift_frac",
            self.hub_crop_max_shift_frac,
            0.0,
            0.15,
        )?;
        c.closed(
            "hub_crop_min_shift_frac",
            self.hub_crop_min_shift_frac,
            0.0,
            0.15,
        )?;
        c.closed(
            "hub_crop_spinner_escape_radii",
            self.hub_crop_spinner_escape_radii,
            0.0,
            10.0,
        )?;
        c.closed(
            "hub_yaw_min_distance_m",
            self.hub_yaw_min_distance_m,
            0.0,
            100.0,
        )?;
        c.closed(
            "hub_yaw_max_distance_m",
            self.hub_yaw_max_distance_m,
            0.0,
            100.0,
        )?;
        c.closed(
            "hub_yaw_close_max_distance_m",
            self.hub_yaw_close_max_distance_m,
            0.0,
            14.0,
        )?;
        c.closed(
            "spinner_min_kept_support",
            self.spinner_min_kept_support,
            0.0,
            1.0,
        )?;
        c.closed(
            "spinner_kept_support_max_radius_px",
            self.spinner_kept_support_max_radius_px,
            0.0,
            1000.0,
        )?;
        c.closed(
            "spinner_max_interior_density",
            self.spinner_max_interior_density,
            0.0,
            1.0,
        )?;
        c.closed("spinner_reach_radii", self.spinner_reach_radii, 0.0, 10.0)?;
        c.closed("conf_spinner", self.conf_spinner, 0.0, 1.0)?;
        c.closed(
            "close_spinner_radius_frac",
            self.close_spinner_radius_frac,
            0.0,
            1.0,
        )?;
        c.closed("conf_close_spinner", self.conf_close_spinner, 0.0, 1.0)?;
        c.closed("through_dist_frac", self.through_dist_frac, 0.0, 1.0)?;
        c.closed("through_margin_frac", self.through_margin_frac, 0.0, 2.0)?;
        c.closed("conf_through_penalty", self.conf_through_penalty, 0.0, 1.0)?;
        c.closed("occluded_angle_deg", self.occluded_angle_deg, 0.0, 45.0)?;
        c.closed("occluded_offset_frac", self.occluded_offset_frac, 0.0, 1.0)?;
        c.closed("occluded_bend_deg", self.occluded_bend_deg, 0.0, 45.0)?;
        c.closed(
            "occluded_bent_max_tilt_deg",
            self.occluded_bent_max_tilt_deg,
            0.0,
            90.0,
        )?;
        self.ranker.validate("detect.default.ranker")?;
        self.still_ranker.validate("detect.default.still_ranker")
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
