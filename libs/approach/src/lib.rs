//! The approach controller: turns the hub track into body-frame velocity and yaw-rate setpoints
//! that bring a multicopter to a point in front of a wind-turbine hub.
//!
//! It implements the navigation method of the thesis (Stokkeland 2014, section 7.1,
//! algorithm 2), made safe and smooth for a real vehicle:
//!
//! - **T1 [`ApproachTask::CentreHub`]**: the hub is outside the target box. Yaw towards it
//!   (horizontal error) and climb/descend (vertical error). Its corrections stay on during T2 and
//!   T3 so the hub stays centred while the vehicle moves.
//! - **T2 [`ApproachTask::ReduceYaw`]**: the relative yaw is too large. Move sideways in
//!   proportion to the lateral offset from the rotor axis (distance × sin(yaw)). With T1 yawing
//!   to keep the hub centred (plus a feed-forward of the arc's yaw rate) the vehicle flies an arc
//!   round the hub. Its correction stays on during T3.
//! - **T3 [`ApproachTask::Approach`]**: move forward (or back) to the target distance, slower as
//!   the vehicle closes in.
//!
//! The reported task is the highest-priority task whose condition is unmet, with hysteresis
//! (enter at an outer threshold, satisfied at an inner one). When a higher task takes over,
//! the lower tasks' velocity components ramp to zero through the rate limits. When all three are
//! within their inner tolerances for `done_hold_s` the controller reports
//! [`ApproachTask::Done`] and hovers; it leaves Done only when an error exceeds an outer
//! threshold.
//!
//! Safety: without a usable track (none, acquiring, lost, or older than `max_track_age_s`) it
//! commands [`ApproachTask::Hold`] (all zero at once), then after `search_after_s` (or when the
//! tracker asks) a bounded [`ApproachTask::Search`] rotation towards the side where the hub was
//! last seen. Forward motion needs a valid distance estimate (or, on the odometry leg, the
//! autopilot's position). Bad data (lost autopilot link,
//! non-finite numbers, a zero image size, time running backwards) gives a sticky
//! [`ApproachTask::Abort`] with all zero, cleared by [`Approach::reset`] or after
//! `abort_recover_s` of good inputs.
//!
//! Conventions: image px origin top-left, x right, y down. Body frame x forward, y right, z down
//! (climbing is `vz < 0`); yaw rate positive clockwise seen from above (turning right). Relative
//! yaw positive when the camera stands on the turbine's own left; reducing it means moving to
//! the vehicle's left (`vy < 0`).

#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod odometry_leg;
mod params;
mod shrink_check;

pub use hubtrack_types::params::ParamError;
pub use params::ApproachConfig;

use hubtrack_types::{ApproachTask, TrackMode, TrackState, VehicleState};
use odometry_leg::OdometryLeg;
use shrink_check::{Contradiction, ShrinkCheck};

/// Longest reason text, bytes (it travels as a [`hubtrack_types::Text64`]).
pub const MAX_REASON_BYTES: usize = 64;
/// Largest elevation, seen or level, the pitch correction of T1's vertical error takes, radians
/// (the tangents stay finite).
const MAX_LEVEL_RAD: f64 = 1.4;

/// The inputs of one controller step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ApproachInput<'a> {
    /// Time of this step on the pipeline clock (monotonic ns); normally the newest track's
    /// `stamps.capture_ns`. It must not run backwards (that is bad data and aborts).
    pub now_ns: u64,
    /// The newest track state, `None` if there has been none yet.
    pub track: Option<&'a TrackState>,
    /// The newest vehicle state, `None` if there has been none. Its absence is not an abort:
    /// the calling process decides whether to send setpoints at all.
    pub vehicle: Option<&'a VehicleState>,
}

/// A change of the active task.
#[derive(Debug, Clone, PartialEq)]
pub struct Transition {
    /// The task before this step.
    pub from: ApproachTask,
    /// The task from this step on.
    pub to: ApproachTask,
    /// Why (the new task's reason).
    pub reason: String,
    /// Entering Done with the two turbine-heading estimates further apart than
    /// `yaw_tolerance_outer_deg`: the station is only as square to the rotor as the estimate
    /// that is right, and the crew should know.
    pub heading_doubt: Option<HeadingDoubt>,
}

/// The relative yaw each turbine-heading estimate gives, degrees (see
/// [`Transition::heading_doubt`]); the approach flies on their `net_heading_weight` mean.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeadingDoubt {
    /// From the track's geometric yaw cues (hub–tower gap, nacelle).
    pub geometric_deg: f64,
    /// From the learned yaw network's readings.
    pub network_deg: f64,
}

/// The setpoint of one controller step (body frame).
#[derive(Debug, Clone, PartialEq)]
pub struct ApproachOutput {
    /// The active task.
    pub task: ApproachTask,
    /// Forward velocity, m/s.
    pub vx_m_s: f64,
    /// Right velocity, m/s.
    pub vy_m_s: f64,
    /// Down velocity, m/s (climbing is negative).
    pub vz_m_s: f64,
    /// Yaw rate, rad/s, positive clockwise seen from above (turning right).
    pub yaw_rate_rad_s: f64,
    /// Why this task is active, with numbers; at most 64 bytes.
    pub reason: String,
    /// `Some` when the task changed in this step.
    pub transition: Option<Transition>,
}

/// The velocity command carried from one step to the next (for the rate limits).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Command {
    vx: f64,
    vy: f64,
    vz: f64,
    /// rad/s
    yaw_rate: f64,
}

/// What a usable track state says about the three tasks (see `Approach::cues`).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Cues {
    /// Normalised image error of the hub, + right of centre (T1).
    ex: f64,
    /// Normalised image error of the hub, + below centre (T1).
    ey: f64,
    /// The relative yaw to act on, degrees (T2).
    yaw: Option<f64>,
    /// The distance to act on, m (T3).
    dist: Option<f64>,
    /// The track's own distance while the remembered hub bounds it (see `bounded_distance`).
    remembered: Option<f64>,
    /// Distance minus the target, m.
    derr: Option<f64>,
    /// A valid distance in this very track state that the odometry does not contradict:
    /// forward motion is allowed.
    forward_ok: bool,
    /// The distance did not shrink as the vehicle closed in (see `shrink_check_m`).
    not_shrinking: Option<Contradiction>,
    /// All three errors within their inner tolerances.
    at_target: bool,
}

/// The sideways target of one step: T2 steering or the probe.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Lateral {
    /// Sideways speed target, m/s.
    vy_t: f64,
    /// The probe sweeps.
    probing: bool,
    /// How long the yaw or the distance has been missing, s.
    missing_s: f64,
    /// How far to either side the probe sweeps, m.
    probe_span_m: f64,
}

/// Sticky abort state.
#[derive(Debug, Clone, PartialEq)]
struct AbortState {
    /// What went wrong first.
    why: String,
    /// Start of the current run of good inputs.
    good_since_ns: Option<u64>,
}

/// The T1/T2/T3 approach controller. Pure: no I/O, no clock; time comes in with each input.
#[derive(Debug, Clone, PartialEq)]
pub struct Approach {
    config: ApproachConfig,
    /// The task reported by the last step.
    task: ApproachTask,
    /// The last command (rate-limit state).
    cmd: Command,
    /// `now_ns` of the last step.
    prev_now_ns: Option<u64>,
    /// `capture_ns` of the newest track seen (to detect time running backwards).
    last_capture_ns: Option<u64>,
    abort: Option<AbortState>,
    /// Filtered relative yaw, degrees (None: no valid yaw since the last reset).
    yaw_f: Option<f64>,
    /// Estimate of the heading that faces the rotor (world frame), kept across track losses.
    turbine_heading: Option<TurbineHeading>,
    /// The same from the learned yaw network's readings (see `net_heading_weight`).
    net_heading: Option<TurbineHeading>,
    /// The relative yaws the two estimates gave when the relative yaw was last worked out
    /// (`heading_yaw`), if both were established then; read on entering Done.
    heading_split: Option<HeadingDoubt>,
    /// Filtered distance, m.
    dist_f: Option<f64>,
    /// `capture_ns` of the track last fed to the filters (a repeated track is not re-filtered).
    filter_capture_ns: Option<u64>,
    /// Hysteresis state: the task's condition is unmet.
    t1_active: bool,
    t2_active: bool,
    t3_active: bool,
    /// Done latched.
    done: bool,
    /// Since when all inner tolerances have held (for `done_hold_s`).
    at_target_since_ns: Option<u64>,
    /// Where the vehicle and the hub were when settling began (see `settle_hold_drift_m`).
    settle_anchor: Option<SettleAnchor>,
    /// Since when the track has been lost while settling or done (see `settle_through_loss_s`).
    settle_lost_since_ns: Option<u64>,
    /// Since when there has been no usable track (None while tracking).
    unusable_since_ns: Option<u64>,
    /// Search rotation so far, degrees.
    search_turned_deg: f64,
    /// The search has used up `search_max_turn_deg`.
    search_exhausted: bool,
    /// Distance backed off in the current close-range search, m.
    backoff_m: f64,
    /// Distance backed off in T3 since the distance last read at the target, m.
    t3_backoff_m: f64,
    /// The newest filtered distance, kept through track losses (where the loss happened).
    last_distance_m: Option<f64>,
    /// The hub was last seen right of centre (search direction); `None` if never seen.
    last_seen_right: Option<bool>,
    /// Since when the yaw or the distance has been missing (None: both are there).
    cue_missing_since_ns: Option<u64>,
    /// Sideways displacement commanded by the current yaw probe, m (+ = right).
    probe_offset_m: f64,
    /// Direction of the probe's sweep (+1 right, −1 left).
    probe_dir: f64,
    /// Where the last confirmed track put the hub (see `reacquire_memory_s`).
    hub_fix: Option<HubFix>,
    /// When the current track was re-acquired after a loss, while the remembered hub still
    /// bounds its distance.
    reacquired_ns: Option<u64>,
    /// Closing in must make the distance shrink (see `shrink_check_m`); kept through losses.
    shrink: ShrinkCheck,
    /// The last metres on the odometry, while they run (see `odometry_leg_fit_margin`).
    leg: Option<OdometryLeg>,
}

/// The hub's horizontal position in the autopilot's local frame, from one track state.
#[derive(Debug, Clone, Copy, PartialEq)]
struct HubFix {
    /// North and east, m.
    north_east: [f64; 2],
    /// When it was fixed.
    at_ns: u64,
}

impl HubFix {
    /// The hub `distance_m` along the bearing `t.hub_bearing_deg[0]` from the vehicle; `None`
    /// without a valid position and attitude.
    fn from(t: &TrackState, v: &VehicleState, distance_m: f64, now: u64) -> Option<HubFix> {
        let v = Some(v).filter(|v| v.position_valid && v.attitude_valid)?;
        let heading = v.yaw_rad + t.hub_bearing_deg[0].to_radians();
        let [n, e, _] = v.position_ned_m;
        let fix = HubFix {
            north_east: [
                n + distance_m * heading.cos(),
                e + distance_m * heading.sin(),
            ],
            at_ns: now,
        };
        fix.north_east.iter().all(|x| x.is_finite()).then_some(fix)
    }

    /// Horizontal distance from the vehicle, m; `None` without a valid position.
    fn distance_from(&self, v: &VehicleState) -> Option<f64> {
        let [n, e, _] = v.position_ned_m;
        let d = (self.north_east[0] - n).hypot(self.north_east[1] - e);
        (v.position_valid && d.is_finite()).then_some(d)
    }
}

/// Where settling at the target began: the vehicle's horizontal position and the hub fixed then.
#[derive(Debug, Clone, Copy, PartialEq)]
struct SettleAnchor {
    /// The vehicle's north and east, m.
    north_east: [f64; 2],
    /// The hub, as the track fixed it then.
    hub: HubFix,
}

impl SettleAnchor {
    /// `None` without a valid position or a hub fix.
    fn new(v: Option<&VehicleState>, hub: Option<HubFix>) -> Option<SettleAnchor> {
        let v = v.filter(|v| v.position_valid)?;
        let [n, e, _] = v.position_ned_m;
        Some(SettleAnchor {
            north_east: [n, e],
            hub: hub?,
        })
    }

    /// The odometry says the vehicle still stands where settling began (within
    /// `settle_hold_drift_m`) and at the target distance (within `distance_tolerance_m`) from
    /// the hub fixed then.
    fn holds(&self, v: &VehicleState, c: &ApproachConfig) -> bool {
        let [n, e, _] = v.position_ned_m;
        let drift = (n - self.north_east[0]).hypot(e - self.north_east[1]);
        let at_distance = self
            .hub
            .distance_from(v)
            .is_some_and(|d| (d - c.target_distance_m).abs() <= c.distance_tolerance_m);
        c.settle_hold_drift_m > 0.0
            && v.position_valid
            && drift <= c.settle_hold_drift_m
            && at_distance
    }
}

/// A reason's note of the track's own distance where a remembered or settled hub bounds it.
fn track_reads(cues: &Cues) -> String {
    cues.remembered
        .map_or(String::new(), |d| format!(" (track reads {d:.1} m)"))
}

/// Cuts a reason to [`MAX_REASON_BYTES`] at a char boundary.
fn truncate_reason(mut s: String) -> String {
    if s.len() > MAX_REASON_BYTES {
        let mut end = MAX_REASON_BYTES;
        while !s.is_char_boundary(end) {
            end -= 1;
        }
        s.truncate(end);
    }
    s
}

/// `v` limited to `[lo, hi]`; never panics (unlike `f64::clamp` with odd bounds) and maps NaN to
/// `lo`.
fn limit(v: f64, lo: f64, hi: f64) -> f64 {
    let v = if v.is_nan() { lo } else { v };
    v.max(lo).min(hi)
}

/// Symmetric limit `[-m, m]`.
fn limit_abs(v: f64, m: f64) -> f64 {
    limit(v, -m, m)
}

/// Error beyond the deadband, continuous at its edge (no step when the hub crosses it).
fn deadband(e: f64, db: f64) -> f64 {
    if e > db {
        e - db
    } else if e < -db {
        e + db
    } else {
        0.0
    }
}

/// Moves `cur` towards `target` by at most `rate * dt`.
fn slew(cur: f64, target: f64, rate: f64, dt: f64) -> f64 {
    let step = rate * dt;
    cur + limit(target - cur, -step, step)
}

/// The forward speed command from `cur` toward `target`: speeding up (or backing away) at
/// `accel` at most, slowing down forward motion at `brake` (≥ `accel`) down to a standstill.
fn slew_forward(cur: f64, target: f64, accel: f64, brake: f64, dt: f64) -> f64 {
    if cur > 0.0 && target < cur {
        (cur - brake * dt).max(target.max(0.0))
    } else {
        slew(cur, target, accel, dt)
    }
}

/// First-order low-pass update with time constant `tau` over `dt`.
fn low_pass(prev: Option<f64>, x: f64, tau: f64, dt: f64) -> f64 {
    match prev {
        None => x,
        Some(_) if tau <= 0.0 => x,
        Some(p) => p + (1.0 - (-dt / tau).exp()) * (x - p),
    }
}

/// Seconds between two monotonic stamps (`b` after `a`, else 0).
fn secs(a: u64, b: u64) -> f64 {
    b.saturating_sub(a) as f64 * 1e-9
}

/// What an unusable track looks like, for the Hold/Search reasons.
fn unusable_reason(track: Option<&TrackState>, age_s: f64, max_age_s: f64) -> Option<String> {
    let Some(t) = track else {
        return Some("no track yet".into());
    };
    match t.mode {
        TrackMode::Acquiring => Some("track acquiring".into()),
        TrackMode::Lost => Some("track lost".into()),
        TrackMode::Tracking | TrackMode::Coasting if age_s > max_age_s => {
            Some(format!("track stale {age_s:.2} s > {max_age_s:.2}"))
        }
        TrackMode::Tracking | TrackMode::Coasting => None,
    }
}

impl Approach {
    /// A controller with a validated config, in [`ApproachTask::Hold`].
    pub fn new(config: ApproachConfig) -> Result<Approach, ParamError> {
        config.validate()?;
        Ok(Approach {
            config,
            task: ApproachTask::Hold,
            cmd: Command::default(),
            prev_now_ns: None,
            last_capture_ns: None,
            abort: None,
            yaw_f: None,
            turbine_heading: None,
            net_heading: None,
            heading_split: None,
            dist_f: None,
            filter_capture_ns: None,
            t1_active: true,
            t2_active: true,
            t3_active: true,
            done: false,
            at_target_since_ns: None,
            settle_anchor: None,
            settle_lost_since_ns: None,
            unusable_since_ns: None,
            search_turned_deg: 0.0,
            search_exhausted: false,
            backoff_m: 0.0,
            t3_backoff_m: 0.0,
            last_distance_m: None,
            last_seen_right: None,
            cue_missing_since_ns: None,
            probe_offset_m: 0.0,
            probe_dir: 1.0,
            hub_fix: None,
            reacquired_ns: None,
            shrink: ShrinkCheck::default(),
            leg: None,
        })
    }

    /// The task reported by the last step ([`ApproachTask::Hold`] before the first).
    pub fn task(&self) -> ApproachTask {
        self.task
    }

    /// The config in use.
    pub fn config(&self) -> &ApproachConfig {
        &self.config
    }

    /// Back to the state of [`Approach::new`]: clears an abort, the filters, the timers and the
    /// rate-limit state (the next step starts from zero velocity).
    pub fn reset(&mut self) {
        let config = self.config.clone();
        // The config was validated by `new`, so this cannot fail; keep the old state if it did.
        if let Ok(fresh) = Approach::new(config) {
            *self = fresh;
        }
    }

    /// Forgets everything learnt from the current track (filters, hysteresis, Done), so the
    /// next usable track starts the tasks afresh from T1.
    fn reset_tasks(&mut self) {
        self.yaw_f = None;
        self.dist_f = None;
        self.filter_capture_ns = None;
        // Unmet until shown otherwise: a fresh track must bring each error inside its inner
        // tolerance before the controller moves on (as at start-up).
        self.t1_active = true;
        self.t2_active = true;
        self.t3_active = true;
        self.done = false;
        self.at_target_since_ns = None;
        self.settle_anchor = None;
        self.t3_backoff_m = 0.0;
        self.leg = None;
    }

    /// One controller step. Never panics; every output is finite and within the configured
    /// limits.
    pub fn step(&mut self, input: &ApproachInput) -> ApproachOutput {
        let now = input.now_ns;
        let (dt, clock_backwards) = match self.prev_now_ns {
            None => (0.0, false),
            Some(p) if now < p => (0.0, true),
            Some(p) => (secs(p, now).min(self.config.max_dt_s), false),
        };
        self.prev_now_ns = Some(now);

        let bad = self.check_inputs(input, clock_backwards);
        let (task, cmd, reason) = match bad {
            Some(why) => {
                // Start (or restart) the good-input timer from scratch: only an unbroken run
                // of good inputs clears an abort.
                let why = match self.abort.take() {
                    Some(a) => a.why,
                    None => why,
                };
                self.abort = Some(AbortState {
                    why: why.clone(),
                    good_since_ns: None,
                });
                self.abort_output(format!("abort: {why}"))
            }
            None => match self.abort.as_mut() {
                None => self.control(now, dt, input),
                Some(a) => {
                    let since = *a.good_since_ns.get_or_insert(now);
                    let good_s = secs(since, now);
                    let why = a.why.clone();
                    if good_s >= self.config.abort_recover_s {
                        // Recovered: start over as after `reset` (from zero velocity), but keep
                        // the clocks so time running backwards is still detected, and the task
                        // so the way out of Abort is reported as a transition.
                        let keep = (self.task, self.prev_now_ns, self.last_capture_ns);
                        self.reset();
                        (self.task, self.prev_now_ns, self.last_capture_ns) = keep;
                        self.control(now, 0.0, input)
                    } else {
                        let recover = self.config.abort_recover_s;
                        self.abort_output(format!("abort: {why} (ok {good_s:.1}/{recover:.1} s)"))
                    }
                }
            },
        };

        let cmd = self.sanitise(cmd);
        self.cmd = cmd;
        let reason = truncate_reason(reason);
        let transition = (task != self.task).then(|| Transition {
            from: self.task,
            to: task,
            reason: reason.clone(),
            heading_doubt: self.heading_split.filter(|s| {
                task == ApproachTask::Done
                    && (s.geometric_deg - s.network_deg).abs() > self.config.yaw_tolerance_outer_deg
            }),
        });
        if let Some(t) = &transition {
            log::debug!("approach: {:?} -> {:?}: {}", t.from, t.to, t.reason);
        }
        self.task = task;
        ApproachOutput {
            task,
            vx_m_s: cmd.vx,
            vy_m_s: cmd.vy,
            vz_m_s: cmd.vz,
            yaw_rate_rad_s: cmd.yaw_rate,
            reason,
            transition,
        }
    }

    /// Why the inputs are bad data (abort), or `None`. Also records the newest capture time.
    fn check_inputs(&mut self, input: &ApproachInput, clock_backwards: bool) -> Option<String> {
        let mut why = None;
        if let Some(v) = input.vehicle {
            if !v.link_ok {
                why = Some("vehicle link lost".to_string());
            }
        }
        if clock_backwards && why.is_none() {
            why = Some("step time went backwards".into());
        }
        if let Some(t) = input.track {
            let capture = t.stamps.capture_ns;
            if why.is_none() && self.last_capture_ns.is_some_and(|last| capture < last) {
                why = Some("track time went backwards".into());
            }
            // Remember it even when bad, so a restarted clock is judged from its new origin.
            self.last_capture_ns = Some(capture);
            if why.is_none() {
                why = track_data_error(t);
            }
        }
        why
    }

    /// Everything zero, at once: aborting is not the moment for a gentle ramp.
    fn abort_output(&self, reason: String) -> (ApproachTask, Command, String) {
        (ApproachTask::Abort, Command::default(), reason)
    }

    /// Last line of defence: a non-finite or out-of-limit command becomes a limited one.
    fn sanitise(&self, cmd: Command) -> Command {
        let c = &self.config;
        let fin = |v: f64| if v.is_finite() { v } else { 0.0 };
        Command {
            vx: limit(fin(cmd.vx), -c.max_backward_m_s, c.max_forward_m_s),
            vy: limit_abs(fin(cmd.vy), c.max_lateral_m_s),
            vz: limit_abs(fin(cmd.vz), c.max_vertical_m_s),
            yaw_rate: limit_abs(fin(cmd.yaw_rate), c.max_yaw_rate_deg_s.to_radians()),
        }
    }

    /// Normal operation (no abort): Hold/Search without a usable track, else the tasks.
    fn control(
        &mut self,
        now: u64,
        dt: f64,
        input: &ApproachInput,
    ) -> (ApproachTask, Command, String) {
        // On the odometry leg the track no longer decides (see `odometry_leg_fit_margin`).
        if let Some(out) = self.odometry_leg(now, dt, input.vehicle) {
            return out;
        }
        // Age of the track = time since its last detection + how old the state itself is.
        let age_s = input.track.map_or(0.0, |t| {
            t.time_since_detection_s + secs(t.stamps.capture_ns, now)
        });
        match (
            unusable_reason(input.track, age_s, self.config.max_track_age_s),
            input.track,
        ) {
            (None, Some(t)) => self.tasks(now, dt, t, input.vehicle),
            (why, _) => {
                let why = why.unwrap_or_default();
                match self.settle_through_loss(now, input.vehicle, &why) {
                    Some(out) => out,
                    None => self.no_track(now, dt, input.track, why),
                }
            }
        }
    }

    /// A track lost while settling at the target or done (see `settle_through_loss_s`): the
    /// settling goes on, to Done, and Done holds, on the odometry's distance from the hub the
    /// last confirmed track fixed, with zero commands. `None` when that does not apply (the
    /// loss is handled by [`Approach::no_track`] from then on).
    fn settle_through_loss(
        &mut self,
        now: u64,
        vehicle: Option<&VehicleState>,
        why: &str,
    ) -> Option<(ApproachTask, Command, String)> {
        let c = &self.config;
        let since = self.at_target_since_ns?;
        let lost_at = *self.settle_lost_since_ns.get_or_insert(now);
        let lost_s = secs(lost_at, now);
        let d = self
            .hub_fix
            .zip(vehicle)
            .and_then(|(f, v)| f.distance_from(v));
        let within = d.is_some_and(|d| (d - c.target_distance_m).abs() <= c.distance_tolerance_m);
        if !(c.settle_through_loss_s > 0.0 && lost_s <= c.settle_through_loss_s && within) {
            return None;
        }
        let d = d.unwrap_or(f64::NAN);
        if !self.done && secs(since, now) >= c.done_hold_s {
            self.done = true;
        }
        Some(if self.done {
            (
                ApproachTask::Done,
                Command::default(),
                format!("done: {d:.2} m by odometry, {why} {lost_s:.1} s"),
            )
        } else {
            (
                ApproachTask::Approach,
                Command::default(),
                format!(
                    "T3: at {d:.2} m by odometry, settling {:.1}/{:.1} s, {why} {lost_s:.1} s",
                    secs(since, now),
                    c.done_hold_s
                ),
            )
        })
    }

    /// Hold, or a bounded search rotation, while there is no usable track.
    fn no_track(
        &mut self,
        now: u64,
        dt: f64,
        track: Option<&TrackState>,
        why: String,
    ) -> (ApproachTask, Command, String) {
        if self.unusable_since_ns.is_none() {
            self.unusable_since_ns = Some(now);
            // The filtered yaw and distance describe a scene we no longer see: start afresh.
            self.reset_tasks();
        }
        let c = &self.config;
        // A tentative hub (not yet confirmed) says which way to turn: `track` is checked
        // (finite, non-zero size) by check_inputs.
        if let Some(t) = track.filter(|t| t.mode == TrackMode::Acquiring) {
            let half = f64::from(t.image_width) / 2.0;
            let ex = (t.hub_px[0] - half) / half;
            if ex.abs() >= c.search_side_min_offset {
                self.last_seen_right = Some(ex > 0.0);
            }
        }
        let lost_s = self.unusable_since_ns.map_or(0.0, |s| secs(s, now));
        let requested = track.is_some_and(|t| t.search_requested);
        let want_search = (requested || lost_s >= c.search_after_s) && c.search_max_turn_deg > 0.0;
        // Lost close to the rotor: turning away would lose it for good (and swing the camera
        // away from the blades we are next to); back away slowly instead, until the whole
        // rotor is back in view.
        if let (true, false, Some(d)) = (
            want_search,
            self.search_exhausted,
            self.last_distance_m.filter(|d| *d < c.close_range_m),
        ) {
            let speed = slew_forward(
                self.cmd.vx,
                -c.search_backoff_m_s,
                c.accel_xy_m_s2,
                c.brake_x_m_s2,
                dt,
            );
            self.backoff_m += speed.abs() * dt;
            if self.backoff_m < c.close_range_m - d {
                let reason = format!(
                    "search: back off, {:.1}/{:.1} m, lost at {d:.1} m",
                    self.backoff_m,
                    c.close_range_m - d
                );
                return (
                    ApproachTask::Search,
                    Command {
                        vx: speed,
                        ..Command::default()
                    },
                    reason,
                );
            }
            self.search_exhausted = true;
        }
        if want_search && !self.search_exhausted {
            let right = self.last_seen_right.unwrap_or(true);
            let sign = if right { 1.0 } else { -1.0 };
            let target = sign * c.search_yaw_rate_deg_s.to_radians();
            let rate = slew(
                self.cmd.yaw_rate,
                target,
                c.yaw_accel_deg_s2.to_radians(),
                dt,
            );
            self.search_turned_deg += rate.abs().to_degrees() * dt;
            if self.search_turned_deg < c.search_max_turn_deg {
                let side = if right { "right" } else { "left" };
                let reason = format!(
                    "search {side} {:.0} deg/s, {:.0}/{:.0} deg, {why}",
                    c.search_yaw_rate_deg_s, self.search_turned_deg, c.search_max_turn_deg
                );
                // Translation stops at once; only the rotation ramps.
                return (
                    ApproachTask::Search,
                    Command {
                        yaw_rate: rate,
                        ..Command::default()
                    },
                    reason,
                );
            }
            self.search_exhausted = true;
        }
        let reason = if self.search_exhausted {
            format!("hold: searched {:.0} deg, {why}", self.search_turned_deg)
        } else {
            format!("hold: {why} ({lost_s:.1} s)")
        };
        // Without a track every motion stops at once: the vehicle must not keep flying
        // blind towards the turbine while a ramp runs down.
        (ApproachTask::Hold, Command::default(), reason)
    }

    /// T1/T2/T3 and Done with a usable track.
    fn tasks(
        &mut self,
        now: u64,
        dt: f64,
        t: &TrackState,
        vehicle: Option<&VehicleState>,
    ) -> (ApproachTask, Command, String) {
        // Back after a loss, also one settled through: a re-acquisition like any other, unless
        // the loss was settled through and the odometry still vouches for the station where
        // settling began (see `update_done`): then the settling, or Done, goes on.
        let was_unusable = self.unusable_since_ns.take().is_some();
        let was_lost_settling = self.settle_lost_since_ns.take().is_some();
        let station_held = was_lost_settling && !was_unusable && self.anchor_holds(vehicle);
        if (was_unusable || was_lost_settling) && !station_held {
            self.restart_after_loss(now);
        }
        let cues = self.cues(now, t, vehicle);
        self.update_hysteresis(&cues);
        if let Some(out) = self.start_odometry_leg(now, dt, &cues, vehicle) {
            return out;
        }
        self.update_done(now, &cues, vehicle);
        // Settling or done while the image errors are out (see `update_done`): hold the
        // station where settling began, on the odometry. With the image errors inside their
        // tolerances, the image keeps the station: its lateral law on the yaw goes on reducing
        // the yaw the estimate still refines (on the odometry alone, `fly` seed 19 ended done at
        // 5.3°; with the image, inside 5°).
        let image_out = self.t1_active || self.t2_active;
        if let Some(v) = vehicle.filter(|_| image_out) {
            if self.at_target_since_ns.is_some() && self.anchor_holds(Some(v)) {
                return self.hold_anchor(now, dt, &cues, v);
            }
        }
        if self.done {
            return self.hold_station(dt, &cues);
        }

        // --- targets of each axis ---
        let vz_t = self.t1_climb_target(&cues);
        let lateral = self.lateral_target(now, &cues);
        let (vx_t, backoff_spent) = self.forward_target(&cues);
        // --- rate limits ---
        let cmd = self.rate_limited(dt, &cues, [vx_t, lateral.vy_t, vz_t], lateral.probing);

        let (task, reason) = if self.t1_active {
            (
                ApproachTask::CentreHub,
                t1_reason(cues.ex, cues.ey, &self.config),
            )
        } else if self.t2_active {
            (ApproachTask::ReduceYaw, self.t2_reason(&cues, &lateral))
        } else {
            let reason = self.t3_reason(now, t, &cues, &lateral, backoff_spent);
            (ApproachTask::Approach, reason)
        };
        (task, cmd, reason)
    }

    /// A usable track again after a loss: a fresh track, a fresh search budget; and the
    /// remembered hub bounds its distance, since it may be something else.
    fn restart_after_loss(&mut self, now: u64) {
        self.reset_tasks();
        self.search_turned_deg = 0.0;
        self.search_exhausted = false;
        self.backoff_m = 0.0;
        if self
            .hub_fix
            .is_some_and(|f| secs(f.at_ns, now) <= self.config.reacquire_memory_s)
        {
            self.reacquired_ns = Some(now);
        }
    }

    /// What a usable track state says about the three tasks: the image errors, the yaw and
    /// distance to act on (feeding the filters and the turbine-heading estimate with it).
    fn cues(&mut self, now: u64, t: &TrackState, vehicle: Option<&VehicleState>) -> Cues {
        // Normalised image errors (checked non-zero size and finite position in check_inputs).
        let (hw, hh) = (
            f64::from(t.image_width) / 2.0,
            f64::from(t.image_height) / 2.0,
        );
        let ex = (t.hub_px[0] - hw) / hw;
        let ey = self.level_ey((t.hub_px[1] - hh) / hh, t, vehicle);
        self.last_seen_right = Some(ex >= 0.0);

        let new_track_state = self.filter_capture_ns != Some(t.stamps.capture_ns);
        self.update_filters(t);
        let yaw = self.heading_yaw(t, vehicle, new_track_state).or(self.yaw_f);
        // This step's reading and where it puts the hub, for the remembered hub and the
        // odometry check.
        let reading = self.dist_f.filter(|_| t.distance_valid);
        // A reading that jumped away from the settled hub fixes no hub.
        let settled_m = self.settled_bound(now, reading, vehicle);
        let fix = reading
            .filter(|_| settled_m.is_none())
            .zip(vehicle)
            .and_then(|(d, v)| HubFix::from(t, v, d, now));
        let (dist, remembered) = self.bounded_distance(now, fix, vehicle);
        let not_shrinking = self.shrink.update(&self.config, now, reading, fix, vehicle);
        // Contradicted, the odometry's distance bounds the reading (backing away stays allowed).
        let dist = match (dist, not_shrinking) {
            (Some(d), Some(n)) => Some(d.min(n.odometry_m)),
            (d, _) => d,
        };
        let (dist, remembered) = match (dist, settled_m) {
            (Some(_), Some(s)) => (Some(s), reading),
            _ => (dist, remembered),
        };
        let c = &self.config;
        // The distance reads at the target again: a fresh backing-off allowance.
        if dist.is_some_and(|d| d >= c.target_distance_m - c.distance_tolerance_outer_m) {
            self.t3_backoff_m = 0.0;
        }
        let derr = dist.map(|d| d - c.target_distance_m);
        let at_target = ex.abs() <= c.box_inner_x
            && ey.abs() <= c.box_inner_y
            && yaw.is_some_and(|y| y.abs() <= c.yaw_tolerance_deg)
            && derr.is_some_and(|e| e.abs() <= c.distance_tolerance_m)
            && not_shrinking.is_none();
        Cues {
            ex,
            ey,
            yaw,
            dist,
            remembered,
            derr,
            forward_ok: t.distance_valid && dist.is_some() && not_shrinking.is_none(),
            not_shrinking,
            at_target,
        }
    }

    /// The vertical image error `ey` of the hub as the camera would see it with the body level
    /// in pitch (see `focal_half_heights`): the hub's elevation on the track's calibrated
    /// bearing plus the body's pitch, back through the focal length near the image centre.
    /// `ey` itself without the focal length, the attitude or the bearing.
    fn level_ey(&self, ey: f64, t: &TrackState, vehicle: Option<&VehicleState>) -> f64 {
        let k = self.config.focal_half_heights;
        let elevation = t.hub_bearing_deg[1]
            .to_radians()
            .clamp(-MAX_LEVEL_RAD, MAX_LEVEL_RAD);
        match vehicle.filter(|v| v.attitude_valid && v.pitch_rad.is_finite()) {
            Some(v) if k > 0.0 && elevation.is_finite() => {
                // Image y grows downward: a hub `e` above the axis sits at −k·tan e.
                let level = (elevation + v.pitch_rad).clamp(-MAX_LEVEL_RAD, MAX_LEVEL_RAD);
                ey - k * (level.tan() - elevation.tan())
            }
            _ => ey,
        }
    }

    /// Settling for `settle_distance_after_s` or done, the odometry's distance to the hub fixed
    /// when settling began, when `reading` lies more than `settle_distance_margin_m` beyond it:
    /// the distance to act on instead (see `settle_distance_margin_m`). `None` otherwise.
    fn settled_bound(
        &self,
        now: u64,
        reading: Option<f64>,
        vehicle: Option<&VehicleState>,
    ) -> Option<f64> {
        let c = &self.config;
        let settled_for_s = self.at_target_since_ns.map_or(0.0, |s| secs(s, now));
        let settled_m = self
            .settle_anchor
            .filter(|_| self.done || settled_for_s >= c.settle_distance_after_s)
            .zip(vehicle)
            .and_then(|(a, v)| a.hub.distance_from(v))?;
        reading
            .is_some_and(|d| d > settled_m + c.settle_distance_margin_m)
            .then_some(settled_m)
    }

    /// Hysteresis of T1, T2 and T3: unmet above the outer threshold, met below the inner one,
    /// else unchanged.
    fn update_hysteresis(&mut self, cues: &Cues) {
        let c = &self.config;
        let (ex, ey) = (cues.ex, cues.ey);
        if ex.abs() > c.box_x || ey.abs() > c.box_y {
            self.t1_active = true;
        } else if ex.abs() <= c.box_inner_x && ey.abs() <= c.box_inner_y {
            self.t1_active = false;
        }
        match cues.yaw {
            Some(y) if y.abs() > c.yaw_tolerance_outer_deg => self.t2_active = true,
            Some(y) if y.abs() <= c.yaw_tolerance_deg => self.t2_active = false,
            Some(_) => {}
            // Unknown yaw cannot count as met.
            None => self.t2_active = true,
        }
        match cues.derr {
            Some(e) if e.abs() > c.distance_tolerance_outer_m => self.t3_active = true,
            Some(e) if e.abs() <= c.distance_tolerance_m => self.t3_active = false,
            Some(_) => {}
            None => self.t3_active = true,
        }
    }

    /// Done: entered after all inner tolerances held for done_hold_s, left only when a
    /// hysteresis flag trips at its outer threshold. Once settling has begun, the odometry
    /// vouches for the vehicle as well (see `settle_hold_drift_m`): while it still stands where
    /// settling began, at the target distance from the hub fixed then, and the track's distance
    /// still reads at the target, settling goes on and Done holds whatever the image errors
    /// (the hub's image position, the yaw) do.
    fn update_done(&mut self, now: u64, cues: &Cues, vehicle: Option<&VehicleState>) {
        let any_active = self.t1_active || self.t2_active || self.t3_active;
        let anchored = self.anchor_holds(vehicle);
        if self.done && any_active && !anchored {
            self.done = false;
            self.at_target_since_ns = None;
            self.settle_anchor = None;
        }
        if !self.done {
            if (cues.at_target && !any_active) || anchored {
                if self.at_target_since_ns.is_none() {
                    self.at_target_since_ns = Some(now);
                    self.settle_anchor = SettleAnchor::new(vehicle, self.hub_fix);
                }
                let since = self.at_target_since_ns.unwrap_or(now);
                if secs(since, now) >= self.config.done_hold_s {
                    self.done = true;
                }
            } else {
                self.at_target_since_ns = None;
                self.settle_anchor = None;
            }
        }
    }

    /// The settling anchor holds by the odometry (see [`SettleAnchor::holds`]) and the track's
    /// distance agrees (T3 met): a passing reading that fixed a wrong hub cannot vouch for
    /// itself.
    fn anchor_holds(&self, vehicle: Option<&VehicleState>) -> bool {
        !self.t3_active
            && self
                .settle_anchor
                .zip(vehicle)
                .is_some_and(|(a, v)| a.holds(v, &self.config))
    }

    /// The Done command with the image errors inside their tolerances: hover, holding the
    /// station sideways and at the distance on the image.
    fn hold_station(&self, dt: f64, cues: &Cues) -> (ApproachTask, Command, String) {
        let c = &self.config;
        let (yaw, dist) = (cues.yaw, cues.dist);
        let reason = format!(
            "done: {:.2} m, yaw {:.1} deg, hub {:+.2} {:+.2}{}",
            dist.unwrap_or(f64::NAN),
            yaw.unwrap_or(f64::NAN),
            cues.ex,
            cues.ey,
            track_reads(cues)
        );
        // Hover, but hold the station sideways and at the distance: at 5 m a gust that
        // pushes the vehicle 1 m aside turns into ~11° of relative yaw, and one that pushes
        // it back takes it out of 5 ± 0.5 m, which zero velocity would leave until an outer
        // threshold trips. T2's lateral law and a gentle distance law run (slowly, through
        // the rate limit); the image errors are noisier than the drift and wait for their
        // outer thresholds. No forward motion without a distance, as everywhere.
        let vy_t = yaw.map_or(0.0, |y| {
            let lateral_m = dist.unwrap_or(c.nominal_distance_m) * y.to_radians().sin();
            limit_abs(-c.done_lateral_gain_per_s * lateral_m, c.max_lateral_m_s)
        });
        let vx_t = dist.map_or(0.0, |d| {
            limit(
                c.done_distance_gain_per_s * (d - c.target_distance_m),
                -c.max_backward_m_s,
                c.max_forward_m_s,
            )
        });
        (
            ApproachTask::Done,
            self.hover_towards(vx_t, vy_t, dt),
            reason,
        )
    }

    /// A hover that moves forward at `vx_t` and sideways at `vy_t` (limited), through the rate
    /// limit: the station keeping of Done and settling.
    fn hover_towards(&self, vx_t: f64, vy_t: f64, dt: f64) -> Command {
        let c = &self.config;
        let vx_t = limit(vx_t, -c.max_backward_m_s, c.max_forward_m_s);
        let vy_t = limit_abs(vy_t, c.max_lateral_m_s);
        Command {
            vx: slew(self.cmd.vx, vx_t, c.accel_xy_m_s2, dt),
            vy: slew(self.cmd.vy, vy_t, c.accel_xy_m_s2, dt),
            ..Command::default()
        }
    }

    /// The command while settling or done with the image errors out of their tolerances, while
    /// the odometry vouches for the station (see `update_done`): back to where settling began,
    /// on the odometry alone, at the gains of the image-based station keeping.
    fn hold_anchor(
        &self,
        now: u64,
        dt: f64,
        cues: &Cues,
        v: &VehicleState,
    ) -> (ApproachTask, Command, String) {
        let c = &self.config;
        let (Some(a), Some(since)) = (self.settle_anchor, self.at_target_since_ns) else {
            return self.hold_station(dt, cues);
        };
        let [n, e, _] = v.position_ned_m;
        let (dn, de) = (a.north_east[0] - n, a.north_east[1] - e);
        let (sin, cos) = v.yaw_rad.sin_cos();
        let vx_t = c.done_distance_gain_per_s * (cos * dn + sin * de);
        let vy_t = c.done_lateral_gain_per_s * (-sin * dn + cos * de);
        let d = a.hub.distance_from(v).unwrap_or(f64::NAN);
        let off = dn.hypot(de);
        let (task, reason) = if self.done {
            (
                ApproachTask::Done,
                format!("done: {d:.2} m by odometry, {off:.2} m from the station"),
            )
        } else {
            (
                ApproachTask::Approach,
                format!(
                    "T3: at {d:.2} m by odometry, settling {:.1}/{:.1} s",
                    secs(since, now),
                    c.done_hold_s
                ),
            )
        };
        (task, self.hover_towards(vx_t, vy_t, dt), reason)
    }

    /// T1 vertical: always on.
    fn t1_climb_target(&self, cues: &Cues) -> f64 {
        let c = &self.config;
        limit_abs(
            c.climb_gain_m_s * deadband(cues.ey, c.deadband_y),
            c.max_vertical_m_s,
        )
    }

    /// T2 lateral: on in T2 and T3 (keeps the yaw small during the approach), off in T1.
    /// Without a yaw (T2) or a distance (T3: no forward motion) for long, probe sideways: both
    /// cues come from the tower, which from some spots hides behind a blade pointing down,
    /// and a few metres aside the view changes. T2 steering on a known yaw goes first.
    fn lateral_target(&mut self, now: u64, cues: &Cues) -> Lateral {
        let c = &self.config;
        let (yaw, dist) = (cues.yaw, cues.dist);
        let missing_s = if yaw.is_some() && cues.forward_ok {
            self.cue_missing_since_ns = None;
            self.probe_offset_m = 0.0;
            0.0
        } else {
            secs(*self.cue_missing_since_ns.get_or_insert(now), now)
        };
        let probe_span_m =
            dist.unwrap_or(c.nominal_distance_m) * c.yaw_probe_span_deg.to_radians().tan();
        let steering = yaw.is_some() && self.t2_active;
        let probing =
            !steering && !self.t1_active && probe_span_m > 0.0 && missing_s >= c.yaw_probe_after_s;
        let vy_t = match (self.t1_active, yaw) {
            (false, _) if probing => {
                // Sweep between −span and +span around where the probe started.
                if self.probe_offset_m * self.probe_dir >= probe_span_m {
                    self.probe_dir = -self.probe_dir;
                }
                limit_abs(self.probe_dir * c.yaw_probe_speed_m_s, c.max_lateral_m_s)
            }
            (false, Some(y)) => {
                let d = dist.unwrap_or(c.nominal_distance_m);
                let lateral_m = d * y.to_radians().sin();
                // Positive yaw = on the turbine's left = the vehicle must go to its left.
                limit_abs(-c.lateral_gain_per_s * lateral_m, c.max_lateral_m_s)
            }
            _ => 0.0,
        };
        Lateral {
            vy_t,
            probing,
            missing_s,
            probe_span_m,
        }
    }

    /// T3 forward/back, proportional, capped by the margin to min_distance; and whether the
    /// backing-off allowance is spent.
    fn forward_target(&self, cues: &Cues) -> (f64, bool) {
        let c = &self.config;
        // On the image the approach closes in only to where the odometry leg begins.
        let stop_m = c.odometry_leg_from_m().unwrap_or(c.target_distance_m);
        let t3_law = |d: f64| {
            let v = c.forward_gain_per_s * (d - stop_m);
            let cap = c.slowdown_gain_per_s * (d - c.min_distance_m);
            limit(v.min(cap), -c.max_backward_m_s, c.max_forward_m_s)
        };
        let vx_t = match cues.dist {
            // Contradicted by the odometry, the reading is judged by backing away (see
            // `shrink_check_probe_ratio`).
            Some(_) if cues.not_shrinking.is_some_and(|n| n.back_away) => -c.search_backoff_m_s,
            Some(d) if !self.t1_active && !self.t2_active => t3_law(d),
            // Backing away from a hub that is too close is allowed in every task.
            Some(d) if d < c.target_distance_m - c.distance_tolerance_outer_m => t3_law(d).min(0.0),
            _ => 0.0,
        };
        // Backing away must make the distance grow; after max_backoff_m it has not (see the
        // parameter), so the reading is wrong: stop backing.
        let backoff_spent = self.t3_backoff_m >= c.max_backoff_m;
        let vx_t = if backoff_spent { vx_t.max(0.0) } else { vx_t };
        // Never forward without a valid distance in this very track state.
        let vx_t = if cues.forward_ok { vx_t } else { vx_t.min(0.0) };
        (vx_t, backoff_spent)
    }

    /// The command from the targets `[vx, vy, vz]` through the rate limits (counting the
    /// backing off and the probe's sideways travel), with T1's yaw rate for that sideways speed.
    fn rate_limited(&mut self, dt: f64, cues: &Cues, target: [f64; 3], probing: bool) -> Command {
        let c = &self.config;
        let [vx_t, vy_t, vz_t] = target;
        let a_xy = c.accel_xy_m_s2;
        let vx = slew_forward(self.cmd.vx, vx_t, a_xy, c.brake_x_m_s2, dt);
        let vx = if cues.forward_ok { vx } else { vx.min(0.0) };
        if vx < 0.0 && vx_t < 0.0 {
            self.t3_backoff_m += -vx * dt;
        }
        let vy = slew(self.cmd.vy, vy_t, a_xy, dt);
        if probing {
            self.probe_offset_m += vy * dt;
        }
        let vz = slew(self.cmd.vz, vz_t, c.accel_z_m_s2, dt);
        Command {
            vx,
            vy,
            vz,
            yaw_rate: self.t1_yaw_rate(dt, cues, vy),
        }
    }

    /// T1 yaw: proportional to the image error plus the yaw rate that the commanded sideways
    /// motion `vy` needs to keep the hub centred (moving left, the hub drifts right: turn
    /// right), through its rate limit.
    fn t1_yaw_rate(&self, dt: f64, cues: &Cues, vy: f64) -> f64 {
        let c = &self.config;
        let ff = match cues.dist {
            Some(d) => -c.arc_feedforward * vy / d.max(c.min_distance_m),
            None => 0.0,
        };
        let max_r = c.max_yaw_rate_deg_s.to_radians();
        let r_t = limit_abs(
            c.yaw_gain_deg_s.to_radians() * deadband(cues.ex, c.deadband_x) + ff,
            max_r,
        );
        slew(self.cmd.yaw_rate, r_t, c.yaw_accel_deg_s2.to_radians(), dt)
    }

    /// Why T2 is active.
    fn t2_reason(&self, cues: &Cues, lateral: &Lateral) -> String {
        let c = &self.config;
        match cues.yaw {
            Some(y) => {
                let d = cues.dist.unwrap_or(c.nominal_distance_m);
                format!(
                    "T2: yaw {y:.1} deg, {:.1} m off axis (tol {:.1})",
                    d * y.to_radians().sin(),
                    c.yaw_tolerance_deg
                )
            }
            None if lateral.probing => format!(
                "T2: no valid yaw for {:.0} s, probing sideways {:+.1}/{:.1} m",
                lateral.missing_s, self.probe_offset_m, lateral.probe_span_m
            ),
            None => "T2: no valid yaw, holding position".into(),
        }
    }

    /// Why T3 is active (or how it settles before Done).
    fn t3_reason(
        &self,
        now: u64,
        t: &TrackState,
        cues: &Cues,
        lateral: &Lateral,
        backoff_spent: bool,
    ) -> String {
        let c = &self.config;
        match (cues.dist, t.distance_valid) {
            (Some(d), true) if !self.t3_active && cues.at_target => format!(
                "T3: at {d:.2} m, settling {:.1}/{:.1} s{}",
                self.at_target_since_ns.map_or(0.0, |s| secs(s, now)),
                c.done_hold_s,
                track_reads(cues)
            ),
            (Some(d), true) if cues.not_shrinking.is_some() => {
                let (excess, flown, back_away) = cues
                    .not_shrinking
                    .map_or((0.0, 0.0, false), |n| (n.excess_m, n.flown_m, n.back_away));
                if back_away {
                    // Short: the reason travels as 64 bytes.
                    format!("T3: {d:.1} m by odometry, track +{excess:.1} m: backing away")
                } else {
                    format!(
                        "T3: {d:.1} m by odometry; the track reads {excess:.1} m more after {flown:.1} m closer: no forward"
                    )
                }
            }
            (Some(d), true) if backoff_spent => format!(
                "T3: still {d:.1} m after backing {:.1} m: no further back",
                self.t3_backoff_m
            ),
            (Some(d), true) if cues.remembered.is_some() => {
                format!("T3: {d:.1} m to the remembered hub (track {:.1} m)", cues.remembered.unwrap_or(d))
            }
            (Some(d), true) => format!("T3: {d:.1} m to hub, target {:.1} m", c.target_distance_m),
            _ if lateral.probing => format!(
                "T3: no valid distance for {:.0} s, not moving forward, probing sideways {:+.1}/{:.1} m",
                lateral.missing_s, self.probe_offset_m, lateral.probe_span_m
            ),
            _ => "T3: no valid distance, not moving forward".into(),
        }
    }

    /// Starts the odometry leg (see `odometry_leg_fit_margin`) when the camera cannot see the
    /// spinner whole at the target and the image has brought the vehicle to where the leg
    /// begins: hub centred, yaw inside its tolerance, and this step's own distance reading, not
    /// contradicted by the odometry nor bounded by a remembered hub, fixing the hub. Returns the
    /// leg's first step.
    fn start_odometry_leg(
        &mut self,
        now: u64,
        dt: f64,
        cues: &Cues,
        vehicle: Option<&VehicleState>,
    ) -> Option<(ApproachTask, Command, String)> {
        let c = &self.config;
        let from_m = c.odometry_leg_from_m()?;
        let ready = !self.t1_active
            && !self.t2_active
            && cues.forward_ok
            && cues.remembered.is_none()
            && cues
                .dist
                .is_some_and(|d| d <= from_m + c.distance_tolerance_m);
        let fix = self.hub_fix.filter(|f| ready && f.at_ns == now)?;
        let leg = OdometryLeg::start(fix, vehicle?, c, now)?;
        log::info!(
            "approach: the spinner overfills the view below {from_m:.1} m: the last {:.1} m run \
             on the odometry, towards the hub fixed {:.2} m ahead",
            leg.start_distance_m() - c.target_distance_m,
            leg.start_distance_m()
        );
        self.leg = Some(leg);
        self.odometry_leg(now, dt, vehicle)
    }

    /// One step of the odometry leg while it runs; `None` when none runs or it ends here
    /// (position or attitude lost, `odometry_leg_max_s` passed), after which the tasks start
    /// afresh on the image.
    fn odometry_leg(
        &mut self,
        now: u64,
        dt: f64,
        vehicle: Option<&VehicleState>,
    ) -> Option<(ApproachTask, Command, String)> {
        let c = &self.config;
        let mut leg = self.leg?;
        let v = vehicle.filter(|v| v.position_valid && v.attitude_valid);
        let end = match v {
            None => Some("no position and attitude from the autopilot"),
            Some(_) if leg.overdue(c, now) => Some("not at the goal in time"),
            Some(_) => None,
        };
        let (Some(v), None) = (v, end) else {
            log::warn!(
                "approach: odometry leg ends after {:.1} s ({}): back to the image",
                leg.age_s(now),
                end.unwrap_or_default()
            );
            self.reset_tasks();
            return None;
        };
        let s = leg.step(c, now, v);
        self.leg = Some(leg);
        self.last_distance_m = Some(s.distance_m);
        let cmd = if s.settling_s.is_some() {
            self.hover_towards(s.vx, s.vy, dt)
        } else {
            Command {
                vx: slew_forward(self.cmd.vx, s.vx, c.accel_xy_m_s2, c.brake_x_m_s2, dt),
                vy: slew(self.cmd.vy, s.vy, c.accel_xy_m_s2, dt),
                vz: slew(self.cmd.vz, 0.0, c.accel_z_m_s2, dt),
                yaw_rate: slew(
                    self.cmd.yaw_rate,
                    s.yaw_rate,
                    c.yaw_accel_deg_s2.to_radians(),
                    dt,
                ),
            }
        };
        let d = s.distance_m;
        Some(match s.settling_s {
            _ if s.done => (
                ApproachTask::Done,
                cmd,
                format!(
                    "done: {d:.2} m by odometry, {:.2} m off the goal",
                    s.off_goal_m
                ),
            ),
            Some(settling) => (
                ApproachTask::Approach,
                cmd,
                format!(
                    "T3: at {d:.2} m by odometry, settling {settling:.1}/{:.1} s",
                    c.done_hold_s
                ),
            ),
            None => (
                ApproachTask::Approach,
                cmd,
                format!("T3: {d:.1} m to hub by odometry (spinner overfills view)"),
            ),
        })
    }

    /// The filtered distance to act on, and the track's own reading when it is not that:
    /// after a re-acquisition, until the track's distance agrees with the hub remembered from
    /// the last confirmed track (or `reacquire_check_s` has passed), the smaller of the two
    /// (see `reacquire_memory_s`). A confirmed track's distance fixes the hub anew.
    fn bounded_distance(
        &mut self,
        now: u64,
        fix: Option<HubFix>,
        vehicle: Option<&VehicleState>,
    ) -> (Option<f64>, Option<f64>) {
        let c = &self.config;
        let dist = self.dist_f;
        if c.reacquire_memory_s <= 0.0 {
            return (dist, None);
        }
        if let Some(since) = self.reacquired_ns {
            let remembered = self
                .hub_fix
                .zip(vehicle)
                .and_then(|(f, v)| f.distance_from(v));
            match (remembered, dist) {
                // Checked long enough, or nothing to check against: the new track stands alone.
                _ if secs(since, now) > c.reacquire_check_s => self.reacquired_ns = None,
                (None, _) => self.reacquired_ns = None,
                (Some(m), Some(d))
                    if (d - m).abs() <= c.reacquire_margin_m + c.reacquire_margin_frac * m =>
                {
                    self.reacquired_ns = None
                }
                (Some(m), Some(d)) => {
                    let bounded = d.min(m);
                    self.last_distance_m = Some(bounded);
                    return (Some(bounded), (d > m).then_some(d));
                }
                (Some(_), None) => return (None, None),
            }
        }
        if fix.is_some() {
            self.hub_fix = fix;
        }
        (dist, None)
    }

    /// Feeds a new track state to the low-pass filters; invalid estimates empty their filter so
    /// the next valid one starts it afresh rather than blending with stale values.
    fn update_filters(&mut self, t: &TrackState) {
        let c = &self.config;
        let capture = t.stamps.capture_ns;
        if self.filter_capture_ns == Some(capture) {
            // The same track state again: nothing new to filter (validity still applies).
            if !yaw_usable(t) {
                self.yaw_f = None;
            }
            if !distance_usable(t) {
                self.dist_f = None;
            }
            return;
        }
        let dt = self
            .filter_capture_ns
            .map_or(0.0, |p| secs(p, capture).min(c.max_dt_s));
        self.filter_capture_ns = Some(capture);
        // Act only on the significant part of the yaw: shrink it toward 0 by k standard deviations.
        let margin = c.yaw_significance_sigmas
            * if t.yaw_std_deg.is_finite() {
                t.yaw_std_deg.max(0.0)
            } else {
                0.0
            };
        let yaw = t.yaw_deg.signum() * (t.yaw_deg.abs() - margin).max(0.0);
        self.yaw_f = yaw_usable(t).then(|| low_pass(self.yaw_f, yaw, c.yaw_filter_s, dt));
        self.dist_f = distance_usable(t)
            .then(|| low_pass(self.dist_f, t.distance_m, c.distance_filter_s, dt));
        if self.dist_f.is_some() {
            self.last_distance_m = self.dist_f;
        }
    }
}

/// Running estimate of the heading that faces the rotor, radians.
#[derive(Debug, Clone, PartialEq)]
struct TurbineHeading {
    heading_rad: f64,
    /// Sum of the (forgotten) measurement weights.
    weight: f64,
    samples: u32,
    last_ns: u64,
}

impl TurbineHeading {
    /// Takes one heading measurement `meas` (rad) of weight `w` at `now` (ns): old weight is
    /// forgotten exponentially over `filter_s` (steps of at most `max_dt_s`), then a weighted
    /// mean step whose innovation is clipped to `clip` (rad), so outliers have bounded influence.
    fn add(&mut self, meas: f64, w: f64, now: u64, max_dt_s: f64, filter_s: f64, clip: f64) {
        self.samples = self.samples.saturating_add(1);
        let dt = secs(self.last_ns.min(now), now).min(max_dt_s);
        self.last_ns = now;
        self.weight = self.weight * (-dt / filter_s).exp() + w;
        let innovation = wrap_pi(meas - self.heading_rad).clamp(-clip, clip);
        self.heading_rad = wrap_pi(self.heading_rad + (w / self.weight) * innovation);
    }
}

impl Approach {
    /// The relative yaw from the turbine-heading estimate and the current heading toward the
    /// hub (autopilot heading + hub azimuth), degrees; feeds the estimate with a new track
    /// state's yaw, and the network's estimate with its reading, and weighs the two
    /// (`net_heading_weight`). `None` while disabled, without attitude, or before enough
    /// samples of the geometric estimate.
    fn heading_yaw(
        &mut self,
        t: &TrackState,
        vehicle: Option<&VehicleState>,
        new: bool,
    ) -> Option<f64> {
        self.heading_split = None;
        let c = &self.config;
        if c.turbine_heading_filter_s <= 0.0 {
            return None;
        }
        let v = vehicle.filter(|v| v.attitude_valid && v.yaw_rad.is_finite())?;
        let az = t.hub_bearing_deg[0];
        if !az.is_finite() || !matches!(t.mode, TrackMode::Tracking | TrackMode::Coasting) {
            return None;
        }
        let to_hub = v.yaw_rad + az.to_radians();
        if new && yaw_usable(t) {
            // Facing heading = heading toward the hub + relative yaw (a camera on the viewer's
            // right must turn left to see the hub).
            let meas = wrap_pi(to_hub + t.yaw_deg.to_radians());
            let now = t.stamps.capture_ns;
            // Weight ∝ 1/distance²: the hub–tower gap grows as 1/distance, so one metre of
            // gap error is worth far more yaw far away than close in.
            let w = if t.distance_valid && t.distance_m.is_finite() && t.distance_m > 0.0 {
                1.0 / (t.distance_m * t.distance_m)
            } else {
                0.0
            };
            // Close in, an established estimate drops what it would clip (see
            // `turbine_heading_close_m`).
            let close = w > 0.0 && t.distance_m < c.turbine_heading_close_m;
            // Closer still, an established estimate holds (see `turbine_heading_hold_m`).
            let established = self
                .turbine_heading
                .as_ref()
                .is_some_and(|h| h.samples >= c.turbine_heading_min_samples);
            let w = if established && w > 0.0 && t.distance_m < c.turbine_heading_hold_m {
                0.0
            } else {
                w
            };
            let beyond_clip = |h: &TurbineHeading| {
                wrap_pi(meas - h.heading_rad).abs() > c.turbine_heading_clip_deg.to_radians()
            };
            match self.turbine_heading.as_mut() {
                None if w > 0.0 => {
                    self.turbine_heading = Some(TurbineHeading {
                        heading_rad: meas,
                        weight: w,
                        samples: 1,
                        last_ns: now,
                    })
                }
                None => {}
                Some(h)
                    if w > 0.0
                        && !(close
                            && h.samples >= c.turbine_heading_min_samples
                            && beyond_clip(h)) =>
                {
                    h.add(
                        meas,
                        w,
                        now,
                        c.max_dt_s,
                        c.turbine_heading_filter_s,
                        c.turbine_heading_clip_deg.to_radians(),
                    )
                }
                Some(_) => {}
            }
        }
        if new && t.net_yaw_valid && t.net_yaw_deg.is_finite() && c.net_heading_weight > 0.0 {
            let meas = wrap_pi(to_hub + t.net_yaw_deg.to_radians());
            let now = t.stamps.capture_ns;
            match self.net_heading.as_mut() {
                None => {
                    self.net_heading = Some(TurbineHeading {
                        heading_rad: meas,
                        weight: 1.0,
                        samples: 1,
                        last_ns: now,
                    })
                }
                Some(h) => h.add(
                    meas,
                    1.0,
                    now,
                    c.max_dt_s,
                    c.turbine_heading_filter_s,
                    c.turbine_heading_clip_deg.to_radians(),
                ),
            }
        }
        let enough = |h: &&TurbineHeading| h.samples >= c.turbine_heading_min_samples;
        let h = self.turbine_heading.as_ref().filter(enough)?;
        let net = self.net_heading.as_ref().filter(enough);
        let heading = match net {
            Some(n) => wrap_pi(
                h.heading_rad + c.net_heading_weight * wrap_pi(n.heading_rad - h.heading_rad),
            ),
            None => h.heading_rad,
        };
        let relative_deg = |heading: f64| wrap_pi(heading - to_hub).to_degrees();
        self.heading_split = net.map(|n| HeadingDoubt {
            geometric_deg: relative_deg(h.heading_rad),
            network_deg: relative_deg(n.heading_rad),
        });
        let yaw = relative_deg(heading);
        if new {
            log::debug!(
                "turbine heading, frame {}: relative yaw {yaw:+.1} deg from {} samples (weight {:.2e}), the geometric one's {:+.1}, the network's {}; track yaw {} at {}",
                t.stamps.seq,
                h.samples,
                h.weight,
                relative_deg(h.heading_rad),
                self.net_heading.as_ref().map_or("-".into(), |n| format!("{:+.1} ({} samples)", relative_deg(n.heading_rad), n.samples)),
                if yaw_usable(t) { format!("{:+.1}", t.yaw_deg) } else { "-".into() },
                if t.distance_valid { format!("{:.1} m", t.distance_m) } else { "-".into() },
            );
        }
        Some(yaw)
    }
}

/// Wraps an angle to (−π, π].
fn wrap_pi(a: f64) -> f64 {
    let r = a.rem_euclid(std::f64::consts::TAU);
    if r > std::f64::consts::PI {
        r - std::f64::consts::TAU
    } else {
        r
    }
}

/// The yaw can be used: flagged valid and in front of the rotor plane.
fn yaw_usable(t: &TrackState) -> bool {
    t.yaw_valid && t.yaw_deg.is_finite() && t.yaw_deg.abs() < 90.0
}

/// The distance can be used: flagged valid, finite and positive.
fn distance_usable(t: &TrackState) -> bool {
    t.distance_valid && t.distance_m.is_finite() && t.distance_m > 0.0
}

/// Bad data in a track state (abort), or `None`. Only fields the controller uses are checked;
/// an estimate flagged invalid may hold anything.
fn track_data_error(t: &TrackState) -> Option<String> {
    if t.image_width == 0 || t.image_height == 0 {
        return Some(format!("image size {}x{}", t.image_width, t.image_height));
    }
    if !t.time_since_detection_s.is_finite() || t.time_since_detection_s < 0.0 {
        return Some(format!(
            "bad time since detection {}",
            t.time_since_detection_s
        ));
    }
    let positioned = matches!(t.mode, TrackMode::Tracking | TrackMode::Coasting);
    if positioned && !(t.hub_px[0].is_finite() && t.hub_px[1].is_finite()) {
        return Some(format!("non-finite hub position {:?}", t.hub_px));
    }
    if t.distance_valid && !t.distance_m.is_finite() {
        return Some(format!("non-finite distance {}", t.distance_m));
    }
    if t.yaw_valid && !t.yaw_deg.is_finite() {
        return Some(format!("non-finite yaw {}", t.yaw_deg));
    }
    None
}

/// "T1: hub 0.31 right of centre (box 0.10)" for the axis furthest outside its box.
fn t1_reason(ex: f64, ey: f64, c: &ApproachConfig) -> String {
    if ex.abs() / c.box_x >= ey.abs() / c.box_y {
        let side = if ex >= 0.0 { "right of" } else { "left of" };
        format!("T1: hub {:.2} {side} centre (box {:.2})", ex.abs(), c.box_x)
    } else {
        let side = if ey >= 0.0 { "below" } else { "above" };
        format!("T1: hub {:.2} {side} centre (box {:.2})", ey.abs(), c.box_y)
    }
}

#[cfg(test)]
mod tests;
