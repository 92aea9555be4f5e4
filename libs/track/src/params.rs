//! Configuration of the track stage (`[track]` in `config/hubtrack.toml`).
//!
//! Plain serde data, each section declared once with [`hubtrack_types::params!`] (every field with
//! its doc, default and allowed range): keys left out take the defaults below and a misspelt key
//! is an error. [`TrackConfig::validate`] checks every number against its allowed range (and the
//! few constraints between fields) and names the offending key by its full dotted path
//! (`track.filter.damping`).
//!
//! ## Pixel-valued parameters and the reference resolution
//! The thesis ran its filter on frames downscaled to about 480×270 px. Every parameter given in
//! pixels here (noise, gates, radii) is specified **at the reference width**
//! [`FilterConfig::reference_width_px`] and scaled by `image_width / reference_width_px` to the
//! resolution of the actual frame (variances by the square of that factor), so behaviour does not
//! depend on the resolution the detector reports in.
//!
//! ## Times and the reference step
//! The thesis filter stepped once per video frame (24 fps GoPro clips). Its per-step values (γ, Q)
//! are converted to continuous time with the reference frame rate
//! [`FilterConfig::reference_rate_hz`], and the filter then runs on the real `capture_ns` stamps.

use hubtrack_types::params::Check;
pub use hubtrack_types::params::ParamError;

/// Upper bound for pixel-valued parameters (px at the reference width).
const MAX_PX: f64 = 1e4;
/// Upper bound for times, s.
const MAX_TIME_S: f64 = 3600.0;
/// Upper bound for counts.
const MAX_COUNT: u32 = 1000;
/// Upper bound for chi-square thresholds.
const MAX_CHI2: f64 = 1e6;
/// Upper bound for noise parameters.
const MAX_NOISE: f64 = 1e6;
/// Upper bound for real sizes, m.
const MAX_SIZE_M: f64 = 100.0;

hubtrack_types::params! {
    /// `[track]`: everything the tracker needs.
    pub struct TrackConfig {
        /// The camera model (pinhole).
        pub camera: CameraConfig = CameraConfig::default();
        /// The damped constant-velocity Kalman filter of the hub position (thesis section 6.2).
        pub filter: FilterConfig = FilterConfig::default();
        /// The thesis's own filter noise and damping, used by the [`crate::BaselineTracker`].
        pub thesis_filter: ThesisFilterConfig = ThesisFilterConfig::default();
        /// Outlier gating of hub measurements.
        pub gating: GatingConfig = GatingConfig::default();
        /// Track modes and their time limits.
        pub modes: ModeConfig = ModeConfig::default();
        /// Prediction of the hub's image motion from the vehicle's attitude, rates and velocity.
        pub ego_motion: EgoMotionConfig = EgoMotionConfig::default();
        /// Distance estimation (thesis section 7.3).
        pub distance: DistanceConfig = DistanceConfig::default();
        /// Relative yaw estimation (thesis section 7.4).
        pub yaw: YawConfig = YawConfig::default();
        /// Distance from motion parallax (the hub triangulated from the vehicle's positions).
        pub parallax: ParallaxConfig = ParallaxConfig::default();
        /// Detections whose hub cannot be the turbine's, given the tower they found and the
        /// turbine profile, are kept out of the track.
        pub profile_check: ProfileCheckConfig = ProfileCheckConfig::default();
    }
}

hubtrack_types::params! {
    /// `[track.profile_check]`: a detection whose hub sits where the profile's hub cannot be
    /// relative to the detected tower (below its top, or beside its axis by more than the hub
    /// overhang allows) is not fed to the track (`crate::profile_check`). Metres come from the
    /// tower band's width and the profile's tower-top diameter.
    pub struct ProfileCheckConfig {
        /// Check detections against the profile.
        pub enabled: bool = true;
        /// The hub may lie this many spinner diameters below the detected tower top (a band
        /// measured on the taper, a top the nacelle hides) before it contradicts the profile.
        pub below_top_spinners: f64 = 1.0, closed(0.0, 100.0);
        /// The hub may lie this many times (overhang + spinner radius) beside the tower axis
        /// (a band read too narrow or too wide by a blade across it).
        pub beside_slack: f64 = 1.5, closed(1.0, 100.0);
        /// Frames from a camera rolled more than this are not checked, degrees (image rows are
        /// then not horizontal).
        pub max_roll_deg: f64 = 20.0, closed(0.0, 90.0);
    }
}

/// Centre focal length of the GoPro HERO3+ wide lens divided by the image width (833.9 / 1920).
pub const GOPRO_FOCAL_PER_WIDTH: f64 = hubtrack_types::setup::GOPRO_FOCAL_LENGTH_PER_WIDTH;

hubtrack_types::params! {
    /// `[track.camera]`: the pinhole camera model.
    pub struct CameraConfig {
        /// Horizontal field of view, degrees. The focal length in px is
        /// `f = (image_width / 2) / tan(hfov / 2)` with the width of each frame. Default 118 (GoPro
        /// HERO3+ wide, thesis table C.1).
        /// From the top-level `[camera]` section (`hfov_deg`), not a key of its own: see
        /// [`TrackConfig::with_setup`].
        #[serde(skip)]
        pub hfov_deg: f64 = 118.0, open(0.0, 180.0);
        /// Focal length divided by the image width (dimensionless), overriding `hfov_deg` when > 0.
        /// For a lens with barrel distortion the pinhole focal length at the image centre differs
        /// from the one implied by the edge FOV: the GoPro HERO3+ wide lens (the thesis camera, as
        /// modelled by the renderer) has f = 833.9 px at 1920 px wide (0.4343), while 118° as a
        /// pinhole gives 576.8 px (0.3004) and would make every distance ~31 % short. Default
        /// 0.4343 (the GoPro); 0 = use `hfov_deg`.
        /// From the top-level `[camera]` section (`focal_length_per_width`), not a key of its own: see
        /// [`TrackConfig::with_setup`].
        #[serde(skip)]
        pub focal_length_per_width: f64 = GOPRO_FOCAL_PER_WIDTH, closed(0.0, MAX_PX);
        /// Camera mount pitch relative to the body x axis, degrees, positive up. Default 0 (camera
        /// looks along the body's nose).
        pub mount_pitch_deg: f64 = 0.0, closed(-90.0, 90.0);
        /// The camera of `[camera]` (calibration or pinhole): see [`TrackConfig::with_setup`].
        #[serde(skip)]
        pub lens: hubtrack_types::setup::Lens = hubtrack_types::setup::Lens::default();
    }
}

hubtrack_types::params! {
    /// `[track.filter]`: the thesis's damped constant-velocity filter, state `x, y, ẋ, ẏ`.
    pub struct FilterConfig {
        /// Velocity damping γ per reference step (eq. 6.4), dimensionless in [0, 1]: the velocity
        /// decays to γ of its value every `1 / reference_rate_hz` s without measurements (1 = no
        /// damping). Default 0.95 (velocity time constant ≈ 0.8 s, as the thesis filter). Rendered
        /// flights (`hubtrack eval --sequence`, R 25, Q 1e-2) gave 2.24 % filtered RMS with 0.95,
        /// 2.11 % with 0.9, 2.34 % with 0.8: within run-to-run noise, and the stronger damping
        /// makes the track lag a steadily moving hub (12 px at 65 px/s with 0.9, 6 px with 0.95).
        // Strictly positive for the continuous-time conversion (ln γ); 1 = no damping.
        pub damping: f64 = 0.95, open_closed(0.0, 1.0);
        /// Process noise Q per reference step and state: px² for the positions and
        /// (px / reference step)² for the velocities, at the reference width. Converted to a
        /// continuous white-noise density. Default 1e-2 (the thesis's 1e-4 made the track too stiff
        /// to follow the turns of the rendered flights once R matched the detector).
        pub process_noise: f64 = 1e-2, open_closed(0.0, MAX_NOISE);
        /// Measurement noise R per axis, px² at the reference width: the detector's hub error.
        /// Default 25 (σ = 5 px = 1.9 % of the height; the default detector's median error on
        /// rendered frames is ~0.8 %, with a heavy tail). The thesis's 1e-1 trusts every detection
        /// fully: the velocity then follows the detector's jitter, the prediction overshoots, and
        /// the gate rejects good detections: rendered flights 4.17 % filtered RMS and 90 % valid
        /// frames with it, 2.24 % and 99 % with 25 (with Q 1e-2 and γ 0.95: R 4 → 2.8 %, 10 → 2.5
        /// %, 50 → 3.0 %, 100 → 2.9 %; below the detector's noise the velocity follows its jitter,
        /// above it the track lags the turns).
        pub measurement_noise: f64 = 25.0, open_closed(0.0, MAX_NOISE);
        /// Image width at which all pixel-valued parameters are given, px (thesis: 480).
        pub reference_width_px: f64 = 480.0, open_closed(0.0, MAX_PX);
        /// Frame rate the per-step values (γ, Q) refer to, Hz (thesis: 24 fps GoPro clips).
        pub reference_rate_hz: f64 = 24.0, open_closed(0.0, 1000.0);
        /// Standard deviation of the velocity when a track starts, px/s at the reference width.
        pub initial_velocity_std_px_s: f64 = 50.0, open_closed(0.0, MAX_PX);
        /// Detections with a lower `confidence` (0..1) are treated as missed frames. Default 0.
        pub min_confidence: f64 = 0.0, closed(0.0, 1.0);
    }
}

hubtrack_types::params! {
    /// `[track.thesis_filter]`: the thesis's filter values, used by the [`crate::BaselineTracker`]
    /// (the reference `hubtrack eval --sequence` compares against). Pixel values are at
    /// `filter.reference_width_px`, per-step values at `filter.reference_rate_hz`.
    pub struct ThesisFilterConfig {
        /// Velocity damping γ per reference step (eq. 6.4). The thesis gives no value; default
        /// 0.95.
        pub damping: f64 = 0.95, open_closed(0.0, 1.0);
        /// Process noise Q per reference step and state, thesis value 1e-4 (Q = 1e-4·I, section
        /// 9.2.2).
        pub process_noise: f64 = 1e-4, open_closed(0.0, MAX_NOISE);
        /// Measurement noise R per axis, px², thesis value 1e-1 (R = 1e-1·I).
        pub measurement_noise: f64 = 1e-1, open_closed(0.0, MAX_NOISE);
    }
}

hubtrack_types::params! {
    /// `[track.gating]`: rejection of measurements that do not fit the track.
    pub struct GatingConfig {
        /// Gate hub measurements at all (the [`crate::BaselineTracker`] never gates).
        pub enabled: bool = true;
        /// Chi-square threshold of the squared Mahalanobis distance of the innovation (2 degrees of
        /// freedom); default 13.82 = 99.9 % of true measurements pass.
        pub chi2_threshold: f64 = 13.82, open_closed(0.0, MAX_CHI2);
        /// Innovations shorter than this are always accepted, px at the reference width. The thesis
        /// R is a smoothing weight rather than the detector's true noise; this floor keeps an
        /// over-confident covariance from rejecting ordinary detector jitter.
        pub min_gate_px: f64 = 5.0, closed(0.0, MAX_PX);
        /// Distance and yaw are measured only from accepted detections within this distance of the
        /// predicted hub, px at the reference width. A detection near the hub but on another
        /// feature (a nose-cone circle, a false circle twice the spinner's size, a blade band taken
        /// for the tower) passes the hub gate when the hub noise is wide, and its size and gap
        /// then corrupt the distance and yaw: seed 19 of `hubtrack fly` flew around the turbine on
        /// a distance of 11 m at 30 m and a yaw of the wrong sign. Default 5 (= `min_gate_px`).
        pub estimate_gate_px: f64 = 5.0, closed(0.0, MAX_PX);
        /// A gated-out measurement that persists for this many consecutive consistent detections
        /// (e.g. the true hub after a re-acquisition) restarts the track there.
        pub jump_accept_count: u32 = 3, closed(1, MAX_COUNT);
        /// Two gated-out measurements are consistent when they lie within this distance of each
        /// other (after the ego-motion prediction), px at the reference width.
        pub jump_consistency_px: f64 = 5.0, open_closed(0.0, MAX_PX);
        /// After a jump the track before it is kept, predicted, for this long, s: a detection
        /// inside its gate, while the new track has fewer consistent detections than it had,
        /// brings it back. Three frames of a false feature (the nacelle's underside, a tower-top
        /// junction) otherwise capture the track, and the true hub found again is gated out as an
        /// outlier of the false track (a rendered flight stayed 120 px off for 2 s that way).
        /// 0 disables it. Range [0, 60]; default 3.
        pub jump_fallback_s: f64 = 3.0, closed(0.0, 60.0);
        /// Robust update: an accepted measurement whose squared Mahalanobis distance d² exceeds
        /// this (and whose innovation exceeds `min_gate_px`) is applied with its noise R scaled by
        /// d² / robust_chi2, so it pulls the track by a bounded amount (a Student-t-like weight).
        /// The detector's errors are heavy-tailed: a false feature found every other frame 80 px
        /// below the hub (a tower-top junction at 30 m) passed the gate and dragged the track
        /// half-way to it. 0 disables it; values at or above `chi2_threshold` change nothing.
        /// `hubtrack eval --sequence`, 40 flights (seeds 7, 100, 500, 2026): filtered RMS 4.0 %
        /// with 0, 2.85 % with 2, 2.74 % with 4 (default), 3.36 % with 9.
        pub robust_chi2: f64 = 4.0, closed(0.0, 1000.0);
    }
}

hubtrack_types::params! {
    /// `[track.modes]`: the track mode machine (acquiring, tracking, coasting, lost).
    pub struct ModeConfig {
        /// Consistent detections needed to go from `acquiring` to `tracking`.
        pub confirm_count: u32 = 3, closed(1, MAX_COUNT);
        /// Consecutive frames without an accepted detection after which `tracking` becomes
        /// `coasting`.
        pub coast_after_missed: u32 = 1, closed(1, MAX_COUNT);
        /// Seconds without an accepted detection after which the track is `lost`.
        pub lost_after_s: f64 = 1.0, open_closed(0.0, MAX_TIME_S);
        /// Seconds without an accepted detection (or since the first frame if there never was one)
        /// after which `search_requested` is set. Must be at least `lost_after_s`.
        pub search_after_s: f64 = 5.0;
    }
}

hubtrack_types::params! {
    /// `[track.ego_motion]`: predicting the hub's image motion from the vehicle state.
    pub struct EgoMotionConfig {
        /// Use the vehicle's attitude and body rates to predict the image shift of a rotation
        /// (yaw: horizontal ≈ f·Δψ, pitch: vertical ≈ f·Δθ, roll: rotation about the image centre).
        pub enabled: bool = true;
        /// Also use the vehicle's velocity (with the distance estimate) for the parallax of
        /// translation, the distance change and the relative-yaw change.
        pub use_velocity: bool = true;
        /// A vehicle state older (or newer) than this relative to the frame is not used, s. Within
        /// it, the attitude is extrapolated to the frame time with the body rates.
        pub max_state_age_s: f64 = 0.5, open_closed(0.0, MAX_TIME_S);
        /// Standard deviation of the predicted ego-motion shift as a fraction of the shift (added
        /// to the position process noise), dimensionless.
        pub shift_std_fraction: f64 = 0.1, closed(0.0, 10.0);
        /// A filtered distance under this does not predict the image shift of the vehicle's
        /// translation (the rotation still does), m: nothing the vehicle approaches is that
        /// close, and a distance read far too short (a merged tower band read 1.5 m at 10 m)
        /// had the predicted hub pass through the camera within a second of coasting
        /// (`eval --sequence --seed 500`, flight 6: filtered hub RMS 65 % of the height).
        pub min_range_m: f64 = 2.0, closed(0.0, 100.0);
    }
}

hubtrack_types::params! {
    /// `[track.distance]`: distance from tower width and spinner diameter, fused and filtered.
    pub struct DistanceConfig {
        /// Real tower diameter where the detector measures its width (just under the nacelle), m.
        /// Default 2.2 (tower top of the modelled turbine; the thesis assumed 2 m).
        /// From the top-level `[turbine]` section (`tower_top_diameter_m`), not a key of its own: see
        /// [`TrackConfig::with_setup`].
        #[serde(skip)]
        pub tower_diameter_m: f64 = 2.2, open_closed(0.0, MAX_SIZE_M);
        /// How much wider the tower gets per metre below its top, m/m: a width measured under
        /// the top is taken back to the top (see [`hubtrack_types::setup::tower_top_width_px`]).
        /// From the `[turbine]` section (`tower_base_diameter_m` with the top diameter and the hub
        /// height), not a key of its own. Default: the thesis turbine's (`[turbine]`'s defaults).
        #[serde(skip)]
        pub tower_taper: f64 = hubtrack_types::setup::TurbineSetup::default().tower_taper(),
            closed(0.0, 1.0);
        /// Height of the hub centre above the tower top, m: where the tower's width is measured
        /// relative to the hub (see [`crate::estimate::HubFromTower`]). From the `[turbine]`
        /// section (`hub_above_tower_top_m`), not a key of its own.
        #[serde(skip)]
        pub hub_above_tower_top_m: f64 = hubtrack_types::setup::TurbineSetup::default().hub_above_tower_top_m,
            closed(0.0, MAX_SIZE_M);
        /// Standard deviation of the measured tower width, px at the reference width (the thesis:
        /// one pixel moved the estimate from 35 m to 40 m).
        pub tower_width_std_px: f64 = 1.0, open_closed(0.0, MAX_PX);
        /// Real spinner (nose cone) diameter at the blade roots, m. Default 3.2.
        /// From the top-level `[turbine]` section (`spinner_diameter_m`), not a key of its own: see
        /// [`TrackConfig::with_setup`].
        #[serde(skip)]
        pub spinner_diameter_m: f64 = 3.2, open_closed(0.0, MAX_SIZE_M);
        /// Standard deviation of the detected spinner radius, px at the reference width.
        pub spinner_radius_std_px: f64 = 1.0, open_closed(0.0, MAX_PX);
        /// The spinner seen from below or above: a further radius std of this fraction of the
        /// radius times `sin²β`, β the line of sight's elevation from the (horizontal) rotor
        /// axis, from the attitude (none without one). A spinner is a circle only head-on: seen
        /// from 10–20° below its axis, its nose and the hub cover behind it stick out of the
        /// rim, and a circle fitted to the silhouette is too large (on the GoPro's rendered
        /// flights +3 % at `sin β` 0.2, +11 % at 0.3: about `sin²β`). So large a std lets the
        /// tower carry the distance there, yet still lets the spinner overrule a tower band
        /// 1.3x too wide (see `consistency_chi2`). The yaw is left out: an estimate 20° off
        /// close in would take the distance from the spinner where the tower's bands are least
        /// sure. 0 = trust it the same from any side.
        pub spinner_oblique_std: f64 = 1.0, closed(0.0, 100.0);
        /// Tower widths and spinner diameters smaller than this are not used, px at the reference
        /// width.
        pub min_size_px: f64 = 2.0, closed(0.0, MAX_PX);
        /// Process noise of the distance filter (random walk), m²/s: the variance a static estimate
        /// gains per second (the UAV approaches at ≤ 1–2 m/s; with velocity aiding the motion
        /// itself is predicted).
        pub process_noise_m2_s: f64 = 1.0, open_closed(0.0, MAX_NOISE);
        /// Chi-square threshold (1 degree of freedom) for gating distance measurements; default
        /// 10.83 = 99.9 %.
        pub gate_chi2: f64 = 10.83, open_closed(0.0, MAX_CHI2);
        /// Chi-square threshold (1 degree of freedom) between the tower-width and the spinner
        /// distance of one frame: above it the one farther from the filtered distance (both
        /// without a filtered distance) is dropped, and a dropped tower gives no yaw either.
        pub consistency_chi2: f64 = 16.0, open_closed(0.0, MAX_CHI2);
        /// Consecutive consistent gated-out distance measurements after which the filter restarts
        /// at the new value.
        pub jump_accept_count: u32 = 3, closed(1, MAX_COUNT);
        /// No distance jumps close in, m (0 = jumps everywhere): while the filtered distance is
        /// below this, gated-out measurements never restart the filter, however many agree. Close
        /// in, a tower band merged with the blade pointing down reads the distance 1.5× short for
        /// seconds (`fly` seeds 285 and 518: 150–165 px for 100 px at 5 m, no spinner circle in
        /// those frames), and a restart there made the vehicle back away to 8 m. Up to 15 m a
        /// restart can also be the dangerous way: `fly --random-setup` seed 206 (60° 1280×720)
        /// took a circle half the spinner's size for it at 10.7 m, three readings of ~16 m
        /// restarted the filter at 16.4 m while the truth was 8.3 m, and T3 flew on to 1.62 m
        /// from the rotor plane. At 15 m it ends done at 5.14 m (`fly --random-setup` 1–120 110
        /// of 120 as at 10 m, 121–240 106 against 107, closest to the rotor plane 4.00 m against
        /// 1.62 m). Range [0, 100]; default 15.
        pub jump_min_distance_m: f64 = 15.0, closed(0.0, MAX_SIZE_M);
        /// How long the close-in rule (`jump_min_distance_m`) outlives the filter's last accepted
        /// measurement, s (0 = forever). After that long without one, the old distance is no
        /// evidence against new readings, and a consistent run of them restarts the filter as
        /// anywhere else. Without it a wrong first reading is a trap: `fly` seed 176 started 40 m
        /// out, its first tower band ran from the tower's edge to a field boundary (134 px for
        /// 22), the filter started at 2.7 m, the vehicle backed away 6 m (`max_backoff_m`) and
        /// then hovered for 100 s with every later reading gated out and the distance invalid.
        /// Longer than the merged-band runs the rule is for (seconds). Range [0, 3600]; default 10.
        pub jump_lockout_max_s: f64 = 10.0, closed(0.0, MAX_TIME_S);
        /// The distance is reported valid only while its standard deviation is at most this, m.
        pub max_std_m: f64 = 10.0, open_closed(0.0, 1e4);
        /// The distance is reported valid only within this many seconds of its last accepted
        /// measurement, s.
        pub stale_after_s: f64 = 2.0, open_closed(0.0, MAX_TIME_S);
    }
}

hubtrack_types::params! {
    /// `[track.parallax]`: distance from motion parallax (`crate::parallax`). The detected hub
    /// seen from the vehicle's positions (the autopilot's local position, the attitude and the
    /// camera model give a world ray per frame) is triangulated over a sliding window; the distance
    /// to that point is a measurement of its own, and tower-width or spinner distances that
    /// disagree with it are dropped (a tower band half hidden by a blade and a spinner circle on
    /// part of the spinner read twice the distance together, so they cannot catch each other).
    pub struct ParallaxConfig {
        /// Use it (needs a valid vehicle position and attitude).
        pub enabled: bool = true;
        /// Sightings older than this are forgotten, s (the baseline is what the vehicle flew in
        /// this time; a longer window also spans more of the autopilot's position drift).
        pub window_s: f64 = 10.0, open_closed(0.0, MAX_TIME_S);
        /// Standard deviation of the direction to the detected hub, degrees (hub placement and
        /// attitude error: 0.5° is ~4 px at 960 px wide with the GoPro lens).
        pub bearing_std_deg: f64 = 0.5, open_closed(0.0, 90.0);
        /// Standard deviation of where on the rotor the detector puts the hub, m (the spinner is
        /// 3.2 m across; the crossing of blade lines wanders over it): close in it outweighs
        /// `bearing_std_deg`, and rays from a few metres that cross within it say nothing.
        pub hub_placement_std_m: f64 = 0.5, closed(0.0, MAX_SIZE_M);
        /// Successive frames share their hub-placement error: the covariance of a triangulation
        /// over more sightings than this is inflated by `sightings / independent_sightings`.
        pub independent_sightings: u32 = 10, closed(1, MAX_COUNT);
        /// Fewest sightings triangulated.
        pub min_sightings: u32 = 10, closed(2, MAX_COUNT);
        /// The parallax distance is used only when its standard deviation is at most this fraction
        /// of it (enough baseline across the line of sight: hovering or flying straight at the hub
        /// gives none).
        pub max_relative_std: f64 = 0.2, open_closed(0.0, 10.0);
        /// ... and when the rays pass the triangulated point within this many of their standard
        /// deviations (RMS; from `bearing_std_deg` and `hub_placement_std_m`): more means the
        /// sightings are not of one point (the track moved to another feature).
        pub max_residual_sigmas: f64 = 3.0, open_closed(0.0, 100.0);
        /// ... and when the triangulated hub is at least this many times the spread of the camera
        /// positions across the line of sight away: rays of two different points fan out from
        /// where the cameras were and cross among them.
        pub min_distance_baselines: f64 = 2.0, closed(0.0, 100.0);
        /// Chi-square threshold (1 degree of freedom) between a frame's tower-width or spinner
        /// distance and the parallax distance: above it that measurement is dropped (a dropped
        /// tower band gives no yaw either).
        pub consistency_chi2: f64 = 9.0, open_closed(0.0, MAX_CHI2);
    }
}

hubtrack_types::params! {
    /// `[track.yaw]`: relative yaw from the hub–tower gap and the nacelle, fused and filtered.
    pub struct YawConfig {
        /// L: horizontal offset from the tower axis to the rotor centre along the rotor axis, m
        /// (eq. 7.14). Default 4.2 (modelled turbine; the thesis assumed 5 m hub-to-tower-top).
        /// From the top-level `[turbine]` section (`hub_overhang_m`), not a key of its own: see
        /// [`TrackConfig::with_setup`].
        #[serde(skip)]
        pub hub_tower_offset_m: f64 = 4.2, open_closed(0.0, MAX_SIZE_M);
        /// Standard deviation of the hub–tower gap when the hub comes from the spinner circle, px
        /// at the reference width, (0, 1e4]. Measured in rendered flights (960 px wide): the circle
        /// centre is within a median 1.8 px of the true hub and the two-edge tower axis within 3.4
        /// px, so ~2.5 px here with tails.
        pub gap_std_spinner_px: f64 = 3.0, open_closed(0.0, MAX_PX);
        /// ... when the hub comes from blade lines only: their crossing wanders a median 14 px (960
        /// px wide) from the hub at 15–25 m (~7 px here), heavy-tailed. 5 px, as tuned in flights
        /// before the split; higher values slowed the yaw at long range (all hubs from lines).
        pub gap_std_lines_px: f64 = 5.0, open_closed(0.0, MAX_PX);
        /// Also estimate the yaw from the nacelle's far end beside the spinner (the detector's
        /// `nacelle_end_dx_px`). A hub–tower gap and a nacelle yaw beyond the yaw gate
        /// (`gate_chi2`) from each other are both dropped: with a blade pointing down the tower
        /// hides behind that blade and its gap takes either sign, and on turbines of other
        /// proportions the nacelle's "end" is as often the spinner's rim, a blade root or the
        /// nacelle's near side. Dropping only the gap let one persistent false nacelle reading
        /// own the yaw (`fly --random-setup` seed 36; before that, dropping every gap of the
        /// other sign, `fly` seed 37 came within 2.1 m of the rotor plane on a distance read 1.8×
        /// long that shrank the detector's window onto the spinner's own edge).
        pub use_nacelle: bool = true;
        /// Distance from the hub back to the nacelle's rear face along the rotor axis, m. From
        /// `[turbine]` (`nacelle_front_behind_hub_m` + `nacelle_length_m`), not a key of its own:
        /// see [`TrackConfig::with_setup`]. Default: the thesis turbine's 11.2.
        #[serde(skip)]
        pub nacelle_rear_m: f64 = 11.2, open_closed(0.0, MAX_SIZE_M);
        /// Half the nacelle's width, m. From `[turbine]` (`nacelle_width_m`). Default 1.7.
        #[serde(skip)]
        pub nacelle_half_width_m: f64 = 1.7, closed(0.0, MAX_SIZE_M);
        /// Standard deviation of the nacelle end's image position, px at the reference width (the
        /// detector finds it on its working image, about as wide: the edge column within ±1 px,
        /// the rear corner's rounding and the chamfer a few px more).
        pub nacelle_std_px: f64 = 3.0, open_closed(0.0, MAX_PX);
        /// The nacelle is used only while the filtered distance is at least this, m. Closer, the
        /// rear corner of a small yaw lies inside the band the detector skips beside the spinner
        /// (`detect.default.nacelle_min_offset_m`, 2 m: at 23 m the end of a 6° yaw is 1.9 m out),
        /// so what it finds there is the spinner's own rim (with the circle a few px off its
        /// centre), a blade root or the tower (`fly` seed 20: one such reading at 7 m turned a −1°
        /// approach into −13°; seed 412 at 23 m: −7.7° read for +19°, on the spinner's far rim).
        /// In 14 recorded flights the readings the tracker used at 10–25 m (truth) had the right
        /// sign for 5–34 % of those with |yaw| ≥ 3° (mean error 16–34°); at 25–40 m 63–76 %. With
        /// the parallax distance, 25 against 12: `fly` seeds 161–480 296 against 292 of 320,
        /// |final yaw| p90 4.2° either way.
        pub nacelle_min_distance_m: f64 = 25.0, closed(0.0, MAX_SIZE_M);
        /// Least standard deviation of a nacelle yaw, degrees: the nacelle's shape (rounded rear,
        /// a cooler on the roof) is known roughly only.
        pub nacelle_min_std_deg: f64 = 2.0, closed(0.0, 90.0);
        /// A nacelle yaw smaller than this, degrees, is not used (0 = all are). Near zero yaw both
        /// sides of the nacelle stick out beside the spinner by about its half-width, and which
        /// one the detector takes is a toss-up: in five recorded `fly` flights (seeds 31, 42, 78,
        /// 82, 97; hub within 10 px, 12 m and farther) the sign was right for 71 % of the readings
        /// of 3–6°, 93 % of 6–9° and all of 9° and more (seed 42 at 32 m: +27 px for −3.4°, the
        /// yaw filter read +5.3°).
        pub nacelle_min_abs_deg: f64 = 6.0, closed(0.0, 90.0);
        /// A nacelle end is used only when the detected hub is within this distance of the track's
        /// prediction, px at the reference width (0 = within `gating.estimate_gate_px`, as every
        /// estimate). The end is measured from the detected hub and takes its error whole: in eight
        /// recorded `fly` flights (1,820 readings of 6° and more, 12 m and farther) the sign was
        /// right for 91–94 % of the readings whose hub was within 3 px (at 480 px) of the track and
        /// for 73 % of those 3–5 px off. At 3: `fly` seeds 1–160 152 against 150 of 160 (in: 55,
        /// 61, 94, 154; out: 45, 67), |final yaw| p90 3.39° against 3.70°. Default 3.
        pub nacelle_gate_px: f64 = 3.0, closed(0.0, 1e4);
        /// A nacelle end is used only when the detector placed the hub on a spinner circle: the end
        /// is searched beyond the spinner's width from the detected hub, and a hub from the blade
        /// lines alone (a blade seen by one edge puts it half a chord off) left the spinner's own
        /// rim in the search. Recorded `fly` flights, readings of 6° and more from 25 m: the sign
        /// was right for 94 % of those with a circle and 75 % of those without in six successful
        /// flights, 74 % and 48 % in the 28 that failed. Default true.
        pub nacelle_needs_spinner: bool = true;
        /// A nacelle end is used only when it lies at least this far beyond the spinner's rim,
        /// m at the hub's depth: the rim is a vertical edge at the hub's rows too, and a spinner
        /// wider than the nacelle (`[turbine]` `spinner_diameter_m` over `nacelle_width_m`)
        /// hides the front corners, so an end at the rim is the rim, on either side whatever the
        /// yaw. The rim is placed from the filtered distance and, larger if so, from the
        /// detected spinner circle, so a distance read long does not pull it in. `fly
        /// --random-setup` seeds 2 and 10 (4.27 m spinners, 3.3–3.6 m nacelles) read ends 1–3
        /// px beyond the rim at 30–39 m as +8° for −2°, and T3 flew the approach 6° off; with
        /// 0.3 m (the detector's `detect.default.nacelle_clearance_m`) seed 10 still took an end
        /// 0.2 m beyond the rim for +8°. On the thesis turbine (1.6 m spinner radius, 1.7 m half
        /// width, rear face 11.2 m behind the hub) it leaves the ends of yaws from 6.5° at 30 m
        /// (`nacelle_min_abs_deg` is 6°: at 6° the end reads 2.09 m beside the hub, the rim's
        /// reach 2.1 m). Default 0.5.
        pub nacelle_rim_clearance_m: f64 = 0.5, closed(0.0, MAX_SIZE_M);
        /// Distance from the hub back to the nacelle's front face along the rotor axis, m. From
        /// `[turbine]` (`nacelle_front_behind_hub_m`). Default 1.2.
        #[serde(skip)]
        pub nacelle_front_m: f64 = 1.2, closed(0.0, 50.0);
        /// A nacelle end is used only when it sticks out at least this many standard deviations
        /// beyond the front corners' head-on offset `f·nacelle_half_width_m / (d +
        /// nacelle_front_m)` (the std: `nacelle_std_px` with the hub's `gap_std_spinner_px` or
        /// `gap_std_lines_px`, and the distance's). Head-on, the front corners peek out beside
        /// the spinner farther than the rear-corner model expects, and with the hub a few px off
        /// and the distance 10–15 % long the reading maps to 6–8° of either sign (`fly` seeds 94
        /// and 103 at 30–34 m: +7° and +8° for −1°, T2 flew them to −8°). 0 = off, the default:
        /// at 2 it brought those two and 19, 47, 55, 154 in but lost 4, 11, 59, 77, 78, 110, 140
        /// (`fly` seeds 1–160: 149 against 150, median |final yaw| 1.06° against 1.21°; seeds
        /// 1–20: 18 against 19), and at 1 it lost 4 of the first 48 seeds that pass either way.
        /// With the std scaled to 960 px (σ ≈ 8.5 px) 2σ also drops true readings below ~12° at
        /// 30 m, where the nacelle is the main far-range cue.
        pub nacelle_min_excess_sigma: f64 = 0.0, closed(0.0, 10.0);
        /// Also use the relative yaw the detector's learned yaw network read (`yaw_net_deg`,
        /// `detect.default.hub_yaw`), with its spread as the standard deviation: to veto the gaps
        /// and nacelle yaws that contradict it (`net_vetoes_gap`), and as the yaw where no
        /// geometric cue is left (`net_fallback_after_s`). It is not fused with the cues: its error
        /// is a bias per scene more than noise per frame.
        pub use_net: bool = true;
        /// Least standard deviation of a network yaw, degrees: its errors from frame to frame of
        /// one flight are correlated (the same scene, the same bias), so its own spread overstates
        /// what many frames add up to. Range (0, 90].
        pub net_min_std_deg: f64 = 2.0, open_closed(0.0, 90.0);
        /// A network yaw whose spread exceeds this is not used, degrees (a broad distribution: the
        /// view does not tell). Range (0, 90].
        pub net_max_std_deg: f64 = 8.0, open_closed(0.0, 90.0);
        /// A hub–tower gap or nacelle yaw beyond the yaw gate (`gate_chi2`) from the network's is
        /// dropped: the network still reads where a blade pointing down in front of the tower
        /// makes the gap take either sign.
        pub net_vetoes_gap: bool = true;
        /// Let the network correct a stale yaw, seconds (0 = never, the default): once no hub–tower
        /// gap, nacelle or blade-skew yaw has been fused for this long and the network's filtered
        /// reading stands `net_fallback_min_deg` from the yaw, it restarts the yaw there and every
        /// network reading is fused until a geometric cue returns. Close in the tower hides behind
        /// the spinner and the blade pointing down, the yaw goes stale and the approach flies on
        /// what it remembers: in 14 of the 19 failures of `fly` seeds 161–560 without the fallback
        /// the yaw was invalid for the last metres and `done` came 5–15° off, while the network
        /// read it within 1.3–4.9° (median per flight, 5–10 m). At 1 s it saved 12 of those 19, but
        /// the network's bias (a few degrees per scene) then sets the final yaw where the
        /// remembered one was right: on seeds 161–207 and 261–304, 82 of 91 against 87 of 91 off
        /// (3 in, 7 out, the new failures 5.6–13° off). Fusing every reading once the cues were
        /// gone (no `net_fallback_min_deg`) saved 13 of the 19 and lost 4 of 18 good endings of
        /// 161–180. With the close-range model (`detect.default.hub_yaw_close`) and 3°, 164
        /// against 172 of the first 179 seeds of 161–560 (7 in, 15 out, up to 13° off: that
        /// model's bias at 5 m); with readings only from 8 m out (`net_fallback_min_distance_m`)
        /// and 6°, 207 against 208 of 216 (6 in, 7 out; |final yaw| p90 3.44° against 3.75°).
        /// Even, so off.
        pub net_fallback_after_s: f64 = 0.0, closed(0.0, MAX_TIME_S);
        /// See `net_fallback_after_s`, degrees: a filtered network reading nearer the stale yaw
        /// leaves it alone (its error is a bias per scene, ~4° at 3.5–8 m). Range [0, 90].
        pub net_fallback_min_deg: f64 = 6.0, closed(0.0, 90.0);
        /// See `net_fallback_after_s`, metres: the fallback uses only network readings taken with
        /// the filtered distance at least this (0 = all readings). Held out, the
        /// network's mean error is 4.0° at 3.5–8 m against 3.4° at 8–15 m and 2.3–2.6° beyond
        /// 15 m; readings from farther out are carried in by the ego-motion prediction, their
        /// spread growing with time. Range [0, 100].
        pub net_fallback_min_distance_m: f64 = 8.0, closed(0.0, MAX_SIZE_M);
        /// Largest relative yaw the estimators report, degrees (asin and the blade fit are
        /// clipped).
        pub max_abs_deg: f64 = 85.0, open(0.0, 90.0);
        /// Process noise of the yaw filter (random walk), deg²/s.
        pub process_noise_deg2_s: f64 = 4.0, open_closed(0.0, MAX_NOISE);
        /// Chi-square threshold (1 degree of freedom) for gating yaw measurements.
        pub gate_chi2: f64 = 10.83, open_closed(0.0, MAX_CHI2);
        /// Consecutive consistent gated-out yaw measurements after which the filter restarts.
        pub jump_accept_count: u32 = 3, closed(1, MAX_COUNT);
        /// A tower band dropped for its width (`distance.consistency_chi2` against the spinner)
        /// still gives the hub–tower gap (at the depth of the filtered distance) when its width is
        /// within this factor of the width the tower has at the spinner's distance (1 = a dropped
        /// band gives no yaw). The chi-square test is strict close in, where the width's noise is a
        /// small part of it, but the band's axis stays on the tower's when its width is a little
        /// off: in a rendered flight at 8–10 m (`fly` seed 42) bands 1.1–1.3× the width expected
        /// had gaps within 2 px of the truth, and no yaw was measured from 10 m to the end. A band
        /// ~1.5× or more is the blade pointing down merged with the tower, whose axis is not the
        /// tower's (1.35 let such bands in: seeds 85, 117, 119 ended 2–5° worse). Default 1 = off:
        /// 1.2 brought seed 42 in (−5.9° → −2.4°) and lost 38 and 60 over `fly` seeds 1–120 (106
        /// against 107 of 120, median |final yaw| 1.36° against 1.28°); the final yaws are limited
        /// by the turbine-heading estimate far out more than by these gaps. Range [1, 3].
        pub gap_max_width_ratio: f64 = 1.0, closed(1.0, 3.0);
        /// The yaw filter restarts on a persistent jump only while the filtered distance is at
        /// least this, m (0 = at any distance). The relative yaw cannot jump: the ego-motion
        /// prediction carries it through the vehicle's own motion, so a persistent jump means
        /// either a wrong start (far out, where the first gaps are a few pixels) or a wrong tower.
        /// Close in, the tower is the blade pointing down in front of it often enough (`fly` seed
        /// 31: three gaps of −121 px at 6.7 m restarted the yaw at +43° for −5°, and T2 flew the
        /// vehicle to −16°); there the measurements are only gated, and the gate widens with the
        /// prediction's growing variance until true ones are accepted again. 20 against 10: in the
        /// recorded failures of `fly` seeds 161–560 most restarts at 10–20 m went to a wrong band
        /// (+28° to +47° for −7° to −1°: the blade pointing down beside the tower), while
        /// successful flights restarted only farther out; seeds 161–560 375 against 371 of 400 (in:
        /// 207, 269, 279, 326; none lost). 25 lost 279 again in the first 97 seeds and gained none.
        /// Also tried: restarting close in after 10 consecutive gaps whose band agreed in width
        /// with the frame's spinner circle (seed 344 at 13.5 m measured −25° from such bands while
        /// the filter held +39°); replayed over the recorded failures it made 7 right and 2 wrong
        /// restarts (a band exactly as wide as the tower, 78 px beside it), but flown over 329
        /// seeds it gained none and lost 279. Default 20.
        pub jump_min_distance_m: f64 = 20.0, closed(0.0, MAX_SIZE_M);
        /// The yaw is reported valid only while its standard deviation is at most this, degrees.
        pub max_std_deg: f64 = 10.0, open_closed(0.0, 180.0);
        /// The yaw is reported valid only within this many seconds of its last accepted
        /// measurement.
        pub stale_after_s: f64 = 2.0, open_closed(0.0, MAX_TIME_S);
    }
}

impl TrackConfig {
    /// Checks every value against its allowed range; the error names the first bad key.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.check_ranges("track")?;
        self.camera.check_ranges("track.camera")?;
        self.filter.check_ranges("track.filter")?;
        self.thesis_filter.check_ranges("track.thesis_filter")?;
        self.gating.check_ranges("track.gating")?;
        self.modes.validate("track.modes")?;
        self.ego_motion.check_ranges("track.ego_motion")?;
        self.distance.check_ranges("track.distance")?;
        self.parallax.check_ranges("track.parallax")?;
        self.profile_check.check_ranges("track.profile_check")?;
        self.yaw.validate("track.yaw")
    }
}

impl ModeConfig {
    /// [`ModeConfig::check_ranges`], then `search_after_s` in `[lost_after_s, 3600]`.
    pub fn validate(&self, section: &str) -> Result<(), ParamError> {
        self.check_ranges(section)?;
        Check::new(section).closed(
            "search_after_s",
            self.search_after_s,
            self.lost_after_s,
            MAX_TIME_S,
        )
    }
}

impl TrackConfig {
    /// This configuration with the camera of `[camera]` (see
    /// [`hubtrack_types::setup::Lens::new`]) and the turbine of `[turbine]`.
    pub fn with_setup(
        mut self,
        lens: &hubtrack_types::setup::Lens,
        turbine: &hubtrack_types::setup::TurbineSetup,
    ) -> TrackConfig {
        self.camera.focal_length_per_width = lens.focal_length_per_width();
        self.camera.lens = lens.clone();
        self.distance.tower_diameter_m = turbine.tower_top_diameter_m;
        self.distance.tower_taper = turbine.tower_taper();
        self.distance.hub_above_tower_top_m = turbine.hub_above_tower_top_m;
        self.distance.spinner_diameter_m = turbine.spinner_diameter_m;
        self.yaw.hub_tower_offset_m = turbine.hub_overhang_m;
        self.yaw.nacelle_rear_m = turbine.nacelle_rear_behind_hub_m();
        self.yaw.nacelle_half_width_m = turbine.nacelle_width_m / 2.0;
        self.yaw.nacelle_front_m = turbine.nacelle_front_behind_hub_m;
        self
    }
}

impl YawConfig {
    /// [`YawConfig::check_ranges`].
    pub fn validate(&self, section: &str) -> Result<(), ParamError> {
        self.check_ranges(section)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_thesis_values() {
        let c = TrackConfig::default();
        c.validate().unwrap();
        assert_eq!(c.thesis_filter.process_noise, 1e-4);
        assert_eq!(c.thesis_filter.measurement_noise, 1e-1);
        assert_eq!(c.camera.hfov_deg, 118.0);
    }

    #[test]
    fn bad_values_name_the_full_key() {
        let mut c = TrackConfig::default();
        c.filter.damping = 1.5;
        let e = c.validate().unwrap_err();
        assert_eq!(e.key, "track.filter.damping");
        assert_eq!(e.value, "1.5");
        assert_eq!(e.allowed, "(0, 1]");

        let mut c = TrackConfig::default();
        c.modes.search_after_s = 0.5; // below lost_after_s
        assert_eq!(c.validate().unwrap_err().key, "track.modes.search_after_s");

        let mut c = TrackConfig::default();
        c.camera.hfov_deg = f64::NAN;
        assert_eq!(c.validate().unwrap_err().key, "track.camera.hfov_deg");

        let mut c = TrackConfig::default();
        c.gating.jump_accept_count = 0;
        assert_eq!(
            c.validate().unwrap_err().to_string(),
            "config key `track.gating.jump_accept_count` = 0 is out of range: allowed [1, 1000]"
        );

        let mut c = TrackConfig::default();
        c.yaw.max_abs_deg = 90.0;
        let e = c.validate().unwrap_err();
        assert_eq!(
            (e.key.as_str(), e.allowed.as_str()),
            ("track.yaw.max_abs_deg", "(0, 90)")
        );
    }

    #[test]
    fn serde_is_strict_and_fills_defaults() {
        let c: TrackConfig = serde_json::from_str(r#"{"filter": {"damping": 0.8}}"#).unwrap();
        assert_eq!(c.filter.damping, 0.8);
        assert_eq!(
            c.filter.process_noise,
            FilterConfig::default().process_noise
        );
        assert_eq!(c.gating, GatingConfig::default());
        assert!(serde_json::from_str::<TrackConfig>(r#"{"filter": {"dampnig": 0.9}}"#).is_err());
        assert!(serde_json::from_str::<TrackConfig>(r#"{"filtre": {}}"#).is_err());
        let back: TrackConfig = serde_json::from_str(&serde_json::to_string(&c).unwrap()).unwrap();
        assert_eq!(back, c);
    }
}
