//! Configuration of the approach controller (`[control.approach]` in `config/hubtrack.toml`).
//!
//! Plain serde data, declared once with [`hubtrack_types::params!`] (every field with its doc,
//! default and allowed range): keys left out take the defaults below and a misspelt key is an
//! error. [`ApproachConfig::validate`] checks every number against its allowed range (and the
//! inner/outer pairs against each other) and names the offending key by its full dotted path
//! (`control.approach.max_forward_m_s`).
//!
//! Image errors are in *normalised* image coordinates: `ex = (hub_x - w/2) / (w/2)`,
//! `ey = (hub_y - h/2) / (h/2)`, so -1..1 spans the image from edge to edge on each axis and no
//! focal length is needed. The section is flat (one table) so every key is
//! `control.approach.<key>`.
//!
//! The defaults suit a ~2 kg quadrotor that starts 25-40 m from the hub and should stop 5 m in
//! front of it within about two minutes.

use hubtrack_types::params::Check;
pub use hubtrack_types::params::ParamError;

/// Upper bound for times, s.
const MAX_TIME_S: f64 = 3600.0;
/// Upper bound for the spinner's closest fit, m.
const MAX_FIT_M: f64 = 1e4;
/// Upper bound for the vertical focal length in half image heights (a 0.01° telephoto).
const MAX_FOCAL_HALF_HEIGHTS: f64 = 1e4;

hubtrack_types::params! {
    /// `[control.approach]`: the T1/T2/T3 approach controller (thesis section 7.1, algorithm 2).
    pub struct ApproachConfig {
        // ---- targets and tolerances ----
        /// Distance from the camera to the hub at which the approach stops, m. Range [1, 100];
        /// default 5 (thesis section 7.1).
        pub target_distance_m: f64 = 5.0, closed(1.0, 100.0);
        /// Distance tolerance counted as "at target", m: T3 is satisfied and Done may begin once
        /// the filtered distance is within this of the target. Range (0, 10]; default 0.3.
        pub distance_tolerance_m: f64 = 0.3, open_closed(0.0, 10.0);
        /// Distance error that restarts T3 (and leaves Done), m; larger than `distance_tolerance_m`
        /// so the task does not chatter. Range (0, 20]; default 0.5.
        pub distance_tolerance_outer_m: f64 = 0.5, open_closed(0.0, 20.0);
        /// Closest allowed distance to the hub, m: the forward speed cap falls to zero here, and
        /// closer than `target_distance_m - distance_tolerance_outer_m` the vehicle backs away in
        /// every task. Range (0, target_distance_m); default 3.
        pub min_distance_m: f64 = 3.0;
        /// Backing away from a hub that reads too close stops after this much backward travel
        /// (commanded speed × time) without the distance reaching the target: a distance that does
        /// not grow while the vehicle backs away is no measurement of it. In a simulated flight the
        /// distance restarted at 3 m with the hub 37 m away, the detector kept finding a circle of
        /// the size that expects, and the vehicle backed away to 57 m. The allowance restarts when
        /// the distance reads at the target or a new track starts. Range (0, 1000]; default 6 (a
        /// reading at `min_distance_m` needs 2 m).
        pub max_backoff_m: f64 = 6.0, open_closed(0.0, 1000.0);
        /// Closing in must make the distance shrink (`shrink_check.rs`): a reading more than
        /// `shrink_check_noise_m` plus `shrink_check_frac` of the distance flown above what the
        /// autopilot's position says is left to the hub (from a reading taken within
        /// `shrink_check_range_m`) blocks forward motion until the readings agree with the
        /// position again. The readings are judged against one anchor over this much flight,
        /// m (0 = no check). Range [0, 100]; default 1.
        pub shrink_check_m: f64 = 1.0, closed(0.0, 100.0);
        /// The judging window grows with the distance: this share of the anchor's reading, if
        /// longer than `shrink_check_m`. Readings confirm an anchor (only a confirmed one can
        /// latch) when over whole windows (`shrink_check_confirm_windows` in a row) they shrank by
        /// the distance flown within `shrink_check_frac` of it. Range [0, 1]; default 0.15.
        pub shrink_check_window_frac: f64 = 0.15, closed(0.0, 1.0);
        /// Windows in a row over which the readings must shrink by the distance flown before an
        /// anchor is confirmed; a window that ends on time before its length was flown (a hover)
        /// neither counts nor breaks the row. A reading off by a factor that drifts can shrink as
        /// flown over one window: `fly --random-setup` seed 82 read 0.38–0.47× the truth from 35 m
        /// to 20 m, one window confirmed it, and the right 18.4 m that followed was held for a
        /// contradiction until the time ran out. Range [1, 100]; default 2.
        pub shrink_check_confirm_windows: u32 = 2, closed(1, 100);
        /// How long an anchor lasts in a hover before the next reading that agrees replaces it,
        /// s. Range (0, 600]; default 2.
        pub shrink_check_window_s: f64 = 2.0, open_closed(0.0, 600.0);
        /// Noise a reading may show above the odometry, m. Range [0, 100]; default 0.5.
        pub shrink_check_noise_m: f64 = 0.5, closed(0.0, 100.0);
        /// Share of the distance flown a reading may fail to shrink by: the distance filter's lag
        /// grows while the vehicle speeds up and the detector's bias changes with the distance
        /// (−10 % at 20 m, ~0 at 5 m is 0.17 m per metre). Range [0, 1]; default 0.35.
        pub shrink_check_frac: f64 = 0.35, closed(0.0, 1.0);
        /// Readings farther than this start no anchor, m: the check guards the last metres,
        /// where the view is filled by rotor parts. Range [0, 1000]; default 15.
        pub shrink_check_range_m: f64 = 15.0, closed(0.0, 1000.0);
        /// A latched reading at least this many times what the odometry leaves, and beyond
        /// `shrink_check_range_m`, is judged by backing away at `search_backoff_m_s` (0 = never:
        /// the latch holds the vehicle in a hover until the readings agree again). From
        /// `shrink_check_window_s` after the backing begins (the distance filter settles after
        /// the jump), over a window of flight
        /// (`shrink_check_m`, or `shrink_check_window_frac` of the reading), a reading that grows
        /// by the distance flown (its slope against the odometry's distance within
        /// `shrink_check_frac` of 1) lifts the latch and starts a new anchor; one that does not
        /// ends the backing, and the latch holds. A confirmed anchor can itself be the wrong
        /// one: `fly --random-setup` seeds 219 and 231 read 0.35–0.5× the truth from 34 m in,
        /// confirmed an anchor ~8 m out, then read right (2.6× the odometry) at 21 m and hovered
        /// against the latch until the time ran out. A right reading changes by the distance
        /// flown, one off by a factor by that factor of it, and backing away is safe whichever
        /// is right. A reading only a little beyond the odometry is not judged: a window's
        /// change would be lost in its noise, and backing out of the readings' contradiction
        /// and closing in again would repeat. Nor is one within the range: close in, where a
        /// blade or the spinner is taken for the tower, backing away lost seed 191 its track
        /// 5.3 m out (it ended 22° off axis; held there, it ends done). Range [0, 100];
        /// default 1.5.
        pub shrink_check_probe_ratio: f64 = 1.5, closed(0.0, 100.0);
        /// Relative yaw counted as "in front of the rotor", degrees: T2 is satisfied and Done may
        /// begin below it. Range (0, 45]; default 3.
        pub yaw_tolerance_deg: f64 = 3.0, open_closed(0.0, 45.0);
        /// Relative yaw that restarts T2 (and leaves Done), degrees; larger than
        /// `yaw_tolerance_deg`. Range (0, 90); default 5.
        pub yaw_tolerance_outer_deg: f64 = 5.0, open(0.0, 90.0);
        /// Horizontal half-size of the target box, normalised image units (1 = image edge): T1
        /// starts when the hub is further than this from the centre. Range (0, 1]; default 0.15
        /// (wide enough that the pitch of a vehicle accelerating forward does not trip it).
        pub box_x: f64 = 0.15, open_closed(0.0, 1.0);
        /// Vertical half-size of the target box, normalised image units (1 = image edge): T1 starts
        /// when the hub is further than this above or below the centre. Range (0, 1]; default 0.18.
        pub box_y: f64 = 0.18, open_closed(0.0, 1.0);
        /// Horizontal half-size of the inner box, normalised image units: T1 is satisfied (and Done
        /// may begin) once the hub is back inside it. Range (0, box_x); default 0.07.
        pub box_inner_x: f64 = 0.07;
        /// Vertical half-size of the inner box, normalised image units: T1 is satisfied (and Done
        /// may begin) once the hub is back inside it. Range (0, box_y); default 0.08.
        pub box_inner_y: f64 = 0.08;
        /// Horizontal deadband of the yaw correction, normalised image units: no yaw rate is
        /// commanded for smaller errors (detector jitter). Range [0, box_inner_x); default 0.02.
        pub deadband_x: f64 = 0.02, closed(0.0, 1.0);
        /// Vertical deadband of the climb correction, normalised image units: no vertical speed is
        /// commanded for smaller errors. Range [0, box_inner_y); default 0.03.
        pub deadband_y: f64 = 0.03, closed(0.0, 1.0);
        /// Time all three tasks must be within their inner tolerances before Done, s. Range
        /// [0, 60]; default 1.5.
        pub done_hold_s: f64 = 1.5, closed(0.0, 60.0);
        /// A track lost while the vehicle settles at the target (every task within its inner
        /// tolerance, `done_hold_s` running) or is done does not end that for this long, s, as
        /// long as the odometry keeps the vehicle within `distance_tolerance_m` of the target
        /// distance from the hub fixed by the last confirmed track: settling goes on to Done, and
        /// Done holds, with zero commands. Close in, a narrow lens's view fills with the spinner
        /// right at 5 m and the track drops out there; re-acquired in that view it was often
        /// something else, and T2 flew the vehicle 7 m aside (`fly --random-setup` seed 14, the
        /// 640×480 USB lens). Past it, or out of tolerance, the loss is handled as any other.
        /// Range [0, 60]; default 5 (0 = a loss always restarts the tasks).
        pub settle_through_loss_s: f64 = 5.0, closed(0.0, 60.0);
        /// Once settling at the target has begun (every task within its inner tolerance), it
        /// goes on, and Done holds, while the odometry keeps the vehicle within this of where
        /// settling began, m, and within `distance_tolerance_m` of the target distance from the
        /// hub fixed then, whatever the image errors do; while those are out of their
        /// tolerances, settling and Done hold that station on the odometry. Close in, a spinner wider than the view leaves the hub's image position and
        /// the yaw to a few rim pixels: they jitter across the tolerances while the vehicle
        /// stands still, and settling restarted for a minute without reaching Done (`fly
        /// --random-setup` seeds 8 and 10: a 4.3 m spinner through the USB and a 60° lens).
        /// At 5 m, 0.2 m aside is 2.3° of relative yaw. Range [0, 10]; default 0.2 (0 = the
        /// image errors alone decide).
        pub settle_hold_drift_m: f64 = 0.2, closed(0.0, 10.0);
        /// While settling at the target or done, a distance reading farther than the odometry's
        /// distance to the hub fixed when settling began by more than this, m, is held to that
        /// distance (the careful side): at 5 m a tower band found on a blade's edge reads the
        /// tower narrow and the hub far, and T3 would fly in on it. Seen on a variant of the
        /// approach (`fly --random-setup` seed 35): hovering 5.07 m out, the track's distance
        /// went 6.75 → 7.8 m within 0.5 s and T3 flew the vehicle to 2.6 m from the rotor plane.
        /// A hub fixed short when settling began now holds the vehicle short of the target
        /// instead of letting a later, longer reading bring it in; the vehicle's own drift still
        /// shows, through the odometry. Within `distance_tolerance_outer_m`, so that a reading
        /// growing through the filter is held before it ends settling. Range [0, 100]; default
        /// 0.3 (0 = any longer reading is held).
        pub settle_distance_margin_m: f64 = 0.3, closed(0.0, 100.0);
        /// The settled hub bounds the distance once settling has run this long, s: a filtered
        /// distance only passing through the target on its way from a wrong reading to a right
        /// one must not fix the station. Range [0, 60]; default 0.5.
        pub settle_distance_after_s: f64 = 0.5, closed(0.0, 60.0);

        // ---- the last metres on the odometry ----
        /// Where the camera cannot see the spinner whole at the target, the last metres run on
        /// the autopilot's position: the approach closes in on the image only to this many times
        /// the closest distance at which the spinner still fits the camera's narrower field of
        /// view (control's start-up envelope check, from the calibration and the turbine
        /// profile), fixes the hub there with everything centred and the yaw inside its
        /// tolerance, and flies the rest straight along that line to the target, facing the
        /// fixed hub, whatever the track does. The margin leaves the detector the spinner's rim
        /// with some background around it. Closer in, the hub's image position and the yaw are
        /// read from a few rim pixels: through 36–38° views with 4.2–4.6 m spinners they jumped
        /// and T1/T2 walked the vehicle off the axis (`fly --random-setup` seeds 8, 14, 32, 41,
        /// 44 and 58). Range [1, 3]; default 1.15.
        pub odometry_leg_fit_margin: f64 = 1.15, closed(1.0, 3.0);
        /// Longest odometry leg, m: the hub fixed at its start is off by a few per cent of that
        /// distance, so a leg starts at most this far beyond the target. Range (0, 50]; default 5.
        pub odometry_leg_max_m: f64 = 5.0, open_closed(0.0, 50.0);
        /// Longest time on an odometry leg, s; past it the approach goes back to the image.
        /// Range (0, 600]; default 40.
        pub odometry_leg_max_s: f64 = 40.0, open_closed(0.0, 600.0);
        /// Yaw-rate gain of the odometry leg, per s (rad/s per rad between the heading and the
        /// fixed hub's bearing). Range (0, 10]; default 1.
        pub odometry_leg_yaw_gain_per_s: f64 = 1.0, open_closed(0.0, 10.0);
        /// The closest distance at which the turbine's spinner fits the camera's narrower field
        /// of view, m (0: not known, no odometry leg). Not a key: the control stage sets it from
        /// the camera calibration and the turbine profile ([`ApproachConfig::with_spinner_fit`]).
        #[serde(skip)]
        pub spinner_fits_from_m: f64 = 0.0, closed(0.0, MAX_FIT_M);
        /// The camera's vertical focal length in half image heights (`fy / (height / 2)`; 0: not
        /// known). With it T1 takes the hub's vertical error as a level body would see it: the
        /// camera is fixed to the body (see `track.camera.mount_pitch_deg`), so a vehicle
        /// pitching 4° nose-down to fly forward sees the hub 4° higher, which through a 60°
        /// 640×480 lens is 0.2 of the half-height, past `box_y`: T1 interrupted the approach
        /// to climb toward a hub that was level, and `fly` seeds 43 and 77 ran out of time
        /// hunting between T1 and T3. Not a key: the control stage sets it from the camera
        /// calibration ([`ApproachConfig::with_camera_focal`]).
        #[serde(skip)]
        pub focal_half_heights: f64 = 0.0, closed(0.0, MAX_FOCAL_HALF_HEIGHTS);

        // ---- gains ----
        /// T1 yaw-rate gain, deg/s per normalised unit of horizontal error (beyond the deadband).
        /// Range (0, 1000]; default 40 (hub at the image edge: 40 deg/s before the rate limit).
        pub yaw_gain_deg_s: f64 = 40.0, open_closed(0.0, 1000.0);
        /// T1 vertical-speed gain, m/s per normalised unit of vertical error (beyond the deadband).
        /// It must outpace the apparent vertical drift of an off-centre hub while closing in, which
        /// grows as the distance shrinks. Range (0, 100]; default 2.
        pub climb_gain_m_s: f64 = 2.0, open_closed(0.0, 100.0);
        /// T2 lateral-speed gain, m/s per metre of lateral offset from the rotor axis
        /// (distance x sin(relative yaw)), i.e. 1/s. Range (0, 10]; default 0.15.
        pub lateral_gain_per_s: f64 = 0.15, open_closed(0.0, 10.0);
        /// In Done, the lateral gain that holds the station sideways against drift, m/s per metre
        /// off the rotor axis (the image errors are noisier than the drift and wait for their
        /// outer thresholds). 0 = hover without correction. Range [0, 10]; default 0.8.
        pub done_lateral_gain_per_s: f64 = 0.8, closed(0.0, 10.0);
        /// In Done, the gain that holds the distance against drift, m/s per metre of distance error
        /// (0 = hover, and only the outer threshold `distance_tolerance_outer_m` restarts T3). At
        /// 5 m the filtered distance is good to a few centimetres, and a gust that pushes the
        /// vehicle back is otherwise left until it is 0.5 m out: `fly` seed 492 reported done at
        /// 5.07 m and ended 3 s later at 5.58 m, a failure. Range [0, 10]; default 0.3 (T3's own
        /// gain).
        pub done_distance_gain_per_s: f64 = 0.3, closed(0.0, 10.0);
        /// T3 forward-speed gain, m/s per metre of distance error, i.e. 1/s. Range (0, 10];
        /// default 0.3.
        pub forward_gain_per_s: f64 = 0.3, open_closed(0.0, 10.0);
        /// Forward speed cap per metre of margin to `min_distance_m`, 1/s: the forward speed never
        /// exceeds this x (distance - min_distance_m), so the vehicle slows down as it closes in.
        /// Range (0, 10]; default 0.5.
        pub slowdown_gain_per_s: f64 = 0.5, open_closed(0.0, 10.0);
        /// Fraction of the yaw rate that keeps the hub centred while T2 moves sideways (-vy /
        /// distance) added ahead of the image error, dimensionless: 1 flies a clean arc round the
        /// hub, 0 leaves it to the T1 feedback. Range [0, 1]; default 1.
        pub arc_feedforward: f64 = 1.0, closed(0.0, 1.0);
        /// No valid yaw (T2) or no valid distance (T3, which then cannot move forward) for this
        /// long, s, starts a sideways probe: both come from the tower (hub–tower gap, tower width),
        /// which from one spot can stay hidden, e.g. behind a blade pointing down, and a few metres
        /// aside the view changes. Range [0, 600]; default 8.
        pub yaw_probe_after_s: f64 = 8.0, closed(0.0, 600.0);
        /// Sideways speed of the probe, m/s. Range (0, 10]; default 0.5.
        pub yaw_probe_speed_m_s: f64 = 0.5, open_closed(0.0, 10.0);
        /// The probe sweeps to either side of where it started by this angle seen from the hub,
        /// degrees (0: no probe, hold): distance × tan(angle), 6 m at 35 m, 0.9 m at 5 m.
        /// Range [0, 45]; default 10.
        pub yaw_probe_span_deg: f64 = 10.0, closed(0.0, 45.0);
        /// Distance used for the T2 lateral offset while no valid distance estimate exists, m.
        /// Range (0, 1000]; default 20.
        pub nominal_distance_m: f64 = 20.0, open_closed(0.0, 1000.0);

        // ---- limits ----
        /// Largest forward speed, m/s. Range (0, 10]; default 1.5.
        pub max_forward_m_s: f64 = 1.5, open_closed(0.0, 10.0);
        /// Largest backward speed (backing away from the hub), m/s. Range [0, 10]; default 1.
        pub max_backward_m_s: f64 = 1.0, closed(0.0, 10.0);
        /// Largest sideways speed, m/s. Range (0, 10]; default 1.5.
        pub max_lateral_m_s: f64 = 1.5, open_closed(0.0, 10.0);
        /// Largest climb or descent speed, m/s. Range (0, 5]; default 1.
        pub max_vertical_m_s: f64 = 1.0, open_closed(0.0, 5.0);
        /// Largest yaw rate, deg/s. Range (0, 180]; default 20.
        pub max_yaw_rate_deg_s: f64 = 20.0, open_closed(0.0, 180.0);
        /// Largest change of the forward and sideways speed commands, m/s per second (m/s²), per
        /// axis. A multicopter tilts about atan(a / g) to accelerate, and the fixed camera tilts
        /// with it: 1 m/s² pitches ~6° and moves the hub ~0.16 of the half-height in the image,
        /// out of the default box, so the default keeps the pitch near 3°. Range (0, 20];
        /// default 0.5.
        pub accel_xy_m_s2: f64 = 0.5, open_closed(0.0, 20.0);
        /// Largest decrease of a forward speed command, m/s per second (m/s²): slowing down
        /// toward the rotor may be quicker than speeding up (the pitch-up it costs is brief, and
        /// the hub is nearer than thought when the distance drops at once). At 1.5 m/s the
        /// stopping distance is 2.25 m at 0.5 m/s² and 1.1 m at 1. Range [accel_xy_m_s2, 20];
        /// default 1.
        pub brake_x_m_s2: f64 = 1.0;
        /// Largest change of the vertical speed command, m/s per second (m/s²). Range (0, 20];
        /// default 1.
        pub accel_z_m_s2: f64 = 1.0, open_closed(0.0, 20.0);
        /// Largest change of the yaw-rate command, deg/s per second (deg/s²). Range (0, 1000];
        /// default 40.
        pub yaw_accel_deg_s2: f64 = 40.0, open_closed(0.0, 1000.0);
        /// Longest time step the rate limits and filters accept between two calls, s: a longer gap
        /// (a stall) counts as this long, so commands never jump. Range (0, 5]; default 0.5.
        pub max_dt_s: f64 = 0.5, open_closed(0.0, 5.0);

        // ---- filters ----
        /// Time constant of the first-order low-pass filter on the relative yaw used by T2, s
        /// (0 = unfiltered). Range [0, 60]; default 0.5.
        pub yaw_filter_s: f64 = 0.5, closed(0.0, 60.0);
        /// Time constant of the first-order low-pass filter on the distance used by T3, s
        /// (0 = unfiltered). Range [0, 60]; default 0.5.
        pub distance_filter_s: f64 = 0.5, closed(0.0, 60.0);
        /// Only the part of the relative yaw beyond this many of the tracker's standard deviations
        /// is acted on (the yaw is shrunk toward 0 by `k·yaw_std_deg` before filtering), so T2 does
        /// not chase noise at long range, where the hub–tower gap is a few pixels. Range [0, 5];
        /// default 1.
        pub yaw_significance_sigmas: f64 = 1.0, closed(0.0, 5.0);
        /// Time constant of the estimate of the turbine's facing heading, s; 0 disables it. The
        /// rotor does not turn during an approach, so every yaw measurement plus the autopilot's
        /// heading toward the hub is a measurement of one constant, the heading that faces the
        /// rotor; averaging it over this long (a running mean at first) and subtracting the current
        /// heading toward the hub gives a relative yaw far less noisy than one frame's hub–tower
        /// gap, and it follows the vehicle's own motion at once. Range [0, 600]; default 10.
        pub turbine_heading_filter_s: f64 = 10.0, closed(0.0, 600.0);
        /// A track lost closer than this to the hub is searched for by backing away (at
        /// `search_backoff_m_s`, until this distance) instead of by rotating, m. Range [0, 100];
        /// default 10 (0 = always rotate).
        pub close_range_m: f64 = 10.0, closed(0.0, 100.0);
        /// Backing-away speed of the close-range search, m/s. Range (0, 2]; default 0.3.
        pub search_backoff_m_s: f64 = 0.3, open_closed(0.0, 2.0);
        /// Each yaw measurement moves the turbine-heading estimate by at most this much error,
        /// degrees (outliers have bounded influence). Range (0, 90]; default 10.
        pub turbine_heading_clip_deg: f64 = 10.0, open_closed(0.0, 90.0);
        /// Closer to the hub than this, m, a yaw measurement more than `turbine_heading_clip_deg`
        /// from an established turbine-heading estimate is dropped instead of clipped (0 = always
        /// clip). Close in, the tower often stands behind the blade pointing down and the band
        /// taken for it gives a steady wrong yaw, while the estimate carries every farther
        /// measurement; clipped, such a run still pulls it ~1° a second at 5 m (`fly` seed 78:
        /// +28° measured for +4°, T2 then flew the vehicle to −18°). Range [0, 100]; default 10.
        pub turbine_heading_close_m: f64 = 10.0, closed(0.0, 100.0);
        /// Closer to the hub than this, m, an established turbine-heading estimate takes no more
        /// yaw measurements at all: it holds what the farther views gave (0 = never hold). Close
        /// in the tower stands behind a blade or the spinner, the band taken for it is often a
        /// blade root, and one such frame at 7 m weighs as much as ten at 25 m (`fly` seed 224:
        /// +9.9° measured at 7.8 m for −1.7°, T2 then moved the vehicle to −6°). Range [0, 100];
        /// default 0.
        pub turbine_heading_hold_m: f64 = 0.0, closed(0.0, 100.0);
        /// How long the hub's position, fixed from the last confirmed track (autopilot position
        /// plus distance along the bearing), bounds the distance of a track that follows a loss, s
        /// (0 = no bound). A track re-acquired after a loss can be something else: lost at 3.5 m,
        /// `fly` seed 176 (with `turbine_heading_hold_m` 10) re-acquired a blade tip 200 px aside
        /// that read 22 m, and T3 flew into the rotor. Until the new track's distance agrees with
        /// the remembered hub (within `reacquire_margin_m`) or `reacquire_check_s` has passed, the
        /// controller takes the smaller of the two. Range [0, 3600]; default 60.
        pub reacquire_memory_s: f64 = 60.0, closed(0.0, MAX_TIME_S);
        /// Longest the remembered hub bounds a re-acquired track's distance, s. Range [0, 600];
        /// default 15.
        pub reacquire_check_s: f64 = 15.0, closed(0.0, 600.0);
        /// A re-acquired track's distance within this of the remembered hub's, m, plus
        /// `reacquire_margin_frac` of it, agrees with it. Range [0, 100]; default 2.
        pub reacquire_margin_m: f64 = 2.0, closed(0.0, 100.0);
        /// The part of the margin that grows with the remembered distance (its own error).
        /// Range [0, 1]; default 0.2.
        pub reacquire_margin_frac: f64 = 0.2, closed(0.0, 1.0);
        /// Yaw measurements needed before the turbine-heading estimate replaces the filtered
        /// tracker yaw. Range [1, 10000]; default 15.
        pub turbine_heading_min_samples: u32 = 15, closed(1, 10_000);
        /// Weight of the learned yaw network's turbine heading in the one the approach flies on,
        /// range [0, 1] (0 = the geometric cues' alone, 1 = the network's alone). The network's
        /// trusted readings (the track's `net_yaw_deg`, from
        /// `track.yaw.net_fallback_min_distance_m` out) build a second turbine-heading estimate,
        /// equally weighted and forgotten like the first; once both hold
        /// `turbine_heading_min_samples`, the approach flies on their weighted mean. The two fail
        /// in different places: the geometric estimate when the tower hides behind the blade
        /// pointing down or the spinner for the last 20 m and only far, noisy views set it, the
        /// network by a bias per scene (~3° at 8–15 m). Default 0.7: `fly` seeds 161–560 393 of 400
        /// against 388 at 0.5 and 381 at 0 (the geometric estimate alone); seeds 1–20 20 of 20
        /// against 18 at 0.5; at 0.3, 282 against 284 at 0.5 of the 294 seeds of 261–560 flown both
        /// ways; at 0.85 393 again, but 18 of the 20 blocks of 20 reach 19 (0.7: 19) and |final
        /// yaw| p90 3.09° (0.7: 2.93°).
        pub net_heading_weight: f64 = 0.7, closed(0.0, 1.0);

        // ---- track loss, search and abort ----
        /// Oldest usable track, s: with more time since the last accepted detection (plus the age
        /// of the track state itself) the controller holds instead of moving.
        pub max_track_age_s: f64 = 1.0, open_closed(0.0, 60.0);
        /// Time without a usable track after which the vehicle searches by rotating, s (the
        /// tracker's `search_requested` starts the search at once). Range [0, 3600]; default 5.
        pub search_after_s: f64 = 5.0, closed(0.0, MAX_TIME_S);
        /// Yaw rate of the search rotation, deg/s, towards the side where the hub was last seen.
        /// Range (0, max_yaw_rate_deg_s]; default 10.
        pub search_yaw_rate_deg_s: f64 = 10.0;
        /// Total rotation of one search, degrees; afterwards the vehicle holds until a track
        /// returns (0 = never search). Range [0, 3600]; default 360.
        pub search_max_turn_deg: f64 = 360.0, closed(0.0, 3600.0);
        /// A hub the tracker has seen but not yet confirmed (acquiring) sets the search's side
        /// when it lies at least this far off the image centre, in half image widths: a start
        /// with the hub at the frame's edge, where it is too cut to confirm, turns towards it
        /// instead of the long way round. Range [0, 1]; default 0.1.
        pub search_side_min_offset: f64 = 0.1, closed(0.0, 1.0);
        /// Time the inputs must be good (link up, finite numbers, time running forward) before an
        /// abort clears by itself, s. Range [0, 3600]; default 2.
        pub abort_recover_s: f64 = 2.0, closed(0.0, MAX_TIME_S);
    }
}

/// A measured quantity set from outside the config: itself up to `max`, or 0 ("not known")
/// when it is no number or not positive.
fn known(value: f64, max: f64) -> f64 {
    if value > 0.0 {
        value.min(max)
    } else {
        0.0
    }
}

impl ApproachConfig {
    /// This config for a camera and turbine whose spinner fits the camera's narrower field of
    /// view from `closest_fit_m` out (see `odometry_leg_fit_margin`). A distance that is no
    /// number or not positive means not known (no leg); a telephoto's kilometres are cut to the
    /// field's range (the leg is at most `odometry_leg_max_m` anyway).
    pub fn with_spinner_fit(mut self, closest_fit_m: f64) -> ApproachConfig {
        self.spinner_fits_from_m = known(closest_fit_m, MAX_FIT_M);
        self
    }

    /// This config for a camera whose vertical focal length is `focal_half_heights` half image
    /// heights (see `focal_half_heights`). A value that is no number or not positive means not
    /// known: T1 then takes the vertical error as the image shows it.
    pub fn with_camera_focal(mut self, focal_half_heights: f64) -> ApproachConfig {
        self.focal_half_heights = known(focal_half_heights, MAX_FOCAL_HALF_HEIGHTS);
        self
    }

    /// Where the last metres on the odometry begin, m: `None` when the spinner fits the view
    /// at the target with the margin (or its fit is not known).
    pub fn odometry_leg_from_m(&self) -> Option<f64> {
        let from = (self.spinner_fits_from_m * self.odometry_leg_fit_margin)
            .min(self.target_distance_m + self.odometry_leg_max_m);
        (from > self.target_distance_m + self.distance_tolerance_outer_m).then_some(from)
    }

    /// Checks every value against its allowed range (and the inner/outer pairs against each
    /// other); the error names the first bad key as `control.approach.<key>`.
    pub fn validate(&self) -> Result<(), ParamError> {
        let section = "control.approach";
        self.check_ranges(section)?;
        let c = Check::new(section);
        // The outer threshold must lie outside the inner one, or the hysteresis would chatter.
        c.less(
            "distance_tolerance_m",
            self.distance_tolerance_m,
            "distance_tolerance_outer_m",
            self.distance_tolerance_outer_m,
        )?;
        c.open(
            "min_distance_m",
            self.min_distance_m,
            0.0,
            self.target_distance_m,
        )?;
        c.less(
            "yaw_tolerance_deg",
            self.yaw_tolerance_deg,
            "yaw_tolerance_outer_deg",
            self.yaw_tolerance_outer_deg,
        )?;
        c.open("box_inner_x", self.box_inner_x, 0.0, self.box_x)?;
        c.open("box_inner_y", self.box_inner_y, 0.0, self.box_y)?;
        // A deadband as wide as the inner box would let the hub rest outside it forever.
        c.less(
            "deadband_x",
            self.deadband_x,
            "box_inner_x",
            self.box_inner_x,
        )?;
        c.less(
            "deadband_y",
            self.deadband_y,
            "box_inner_y",
            self.box_inner_y,
        )?;
        c.closed("brake_x_m_s2", self.brake_x_m_s2, self.accel_xy_m_s2, 20.0)?;
        c.open_closed(
            "search_yaw_rate_deg_s",
            self.search_yaw_rate_deg_s,
            0.0,
            self.max_yaw_rate_deg_s,
        )
    }
}
