//! [`Tracker`] (gated, attitude-aided, with filtered distance and yaw) and [`BaselineTracker`]
//! (the thesis filter), sharing one implementation.

use hubtrack_types::setup::tower_top_width_px;
use hubtrack_types::{Detection, TrackMode, TrackState, VehicleState};
use nalgebra::{Rotation3, Vector3};

use crate::camera::{
    camera_pose_at, camera_position_at, camera_to_body, dt_s, ego_motion, focal_length_px,
    CameraPose, Pinhole,
};
use crate::estimate::{
    distance_from_spinner, distance_from_tower_width, fuse, fusion_shares, nacelle_excess_sigma,
    off_axis_sin, spinner_rim_reach_px, yaw_from_gap, yaw_from_nacelle, Estimate, HubFromTower,
};
use crate::filter::{CvModel, HubFilter, ScalarFilter};
use crate::parallax::{ParallaxRanger, Sighting};
use crate::params::{ParamError, TrackConfig};
use crate::profile_check::{self, Profile};

/// Variance of a uniform distribution over a unit interval (`w²/12` for width `w`).
const UNIFORM_VAR_PER_WIDTH2: f64 = 1.0 / 12.0;

/// Height / width of the assumed frame before any detection told the size (16:9, as the thesis's
/// 480×270).
const FALLBACK_ASPECT: f64 = 9.0 / 16.0;

/// A run of this many detections contradicting the turbine profile is warned about (and every
/// further such run): 3 s at 30 fps, longer than a wrong object stays in view by chance.
const CONTRADICTION_WARN_EVERY: u64 = 90;

/// What distinguishes the two trackers.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Options {
    /// Gate measurements (also requires `gating.enabled`).
    gating: bool,
    /// Use the vehicle state (also requires `ego_motion.enabled`).
    ego_motion: bool,
    /// Report the thesis's raw per-frame distance and yaw instead of the filtered ones.
    raw_estimates: bool,
    /// Filter with `thesis_filter`'s damping and noise instead of `filter`'s.
    thesis_filter: bool,
}

/// The hub track.
#[derive(Debug, Clone, Copy, PartialEq)]
struct HubTrack {
    filter: HubFilter,
    /// Reached `tracking` (enough consistent detections).
    confirmed: bool,
    /// Consistent detections since the track started.
    consistent: u32,
    /// Declared lost (no accepted detection for `lost_after_s`); still predicted.
    lost: bool,
}

/// Gated-out detections that might be the true hub after a jump.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Candidate {
    px: [f64; 2],
    count: u32,
    t_ns: u64,
}

/// A detection's size-based distances after their consistency checks (see
/// `Core::size_distances` and `Core::check_parallax`).
#[derive(Debug, Clone, Copy, PartialEq)]
struct SizeDistances {
    /// Depth of the tower axis from the band's width; `None` when absent or dropped.
    tower: Option<Estimate>,
    /// Where the hub sits relative to the measured tower point (its yaw is set where used).
    tower_view: Option<HubFromTower>,
    /// Hub distance from the spinner circle; `None` when absent or dropped.
    spinner: Option<Estimate>,
    /// The spinner distance before any check (the gap's fallback depth).
    spinner_seen: Option<Estimate>,
    /// The tower band was dropped.
    tower_rejected: bool,
    /// The spinner or the parallax disputed the tower band.
    tower_disputed: bool,
    /// The band's width over the width the tower has at the spinner's distance, when the band
    /// was dropped for its width (see `gap_max_width_ratio`).
    rejected_width_ratio: Option<f64>,
}

impl SizeDistances {
    /// The hub's distance from the tower band, at relative yaw `yaw`; `None` without a band.
    fn tower_hub(&self, yaw: Estimate) -> Option<Estimate> {
        let (td, view) = self.tower.zip(self.tower_view)?;
        view.with_yaw(yaw).hub_distance(td)
    }
}

/// The shared implementation.
#[derive(Debug, Clone)]
struct Core {
    cfg: TrackConfig,
    opts: Options,
    r_bc: Rotation3<f64>,
    track: Option<HubTrack>,
    candidate: Option<Candidate>,
    /// The track before the last jump and the jump's time (see `gating.jump_fallback_s`).
    before_jump: Option<(HubTrack, u64)>,
    /// Time of the state, ns.
    t_ns: Option<u64>,
    /// Time of the first update, ns.
    first_ns: Option<u64>,
    /// Time of the last accepted detection, ns.
    last_accept_ns: Option<u64>,
    frames_since: u32,
    missed_streak: u32,
    ever_confirmed: bool,
    image: Option<(u32, u32)>,
    /// Newest vehicle state with a valid attitude.
    vehicle: Option<VehicleState>,
    /// Camera pose at `t_ns`.
    pose: Option<CameraPose>,
    distance: ScalarFilter,
    yaw: ScalarFilter,
    /// When a geometric yaw cue (gap, nacelle, blade skew) was last fused, ns (see
    /// `yaw.net_fallback_after_s`).
    yaw_cue_ns: Option<u64>,
    /// Every network yaw reading, filtered like `yaw` (the fallback's reference).
    net_yaw: ScalarFilter,
    /// The network carries the yaw until a geometric cue returns (`yaw.net_fallback_after_s`).
    net_fallback: bool,
    /// The current track's sightings, for the parallax distance.
    parallax: ParallaxRanger,
    /// Raw per-frame (distance, yaw) of the baseline.
    raw: (Option<Estimate>, Option<Estimate>),
    /// This frame's distance cues' shares of the fused measurement: tower, spinner, parallax.
    distance_shares: [f64; 3],
    /// This frame's detection contradicted the turbine profile (see `crate::profile_check`).
    profile_contradiction: bool,
    /// Detections in a row that contradicted the profile.
    contradiction_streak: u64,
    last_seq: u64,
}

impl Core {
    fn new(cfg: TrackConfig, opts: Options) -> Result<Core, ParamError> {
        cfg.validate()?;
        let r_bc = camera_to_body(cfg.camera.mount_pitch_deg.to_radians());
        Ok(Core {
            cfg,
            opts,
            r_bc,
            track: None,
            candidate: None,
            before_jump: None,
            t_ns: None,
            first_ns: None,
            last_accept_ns: None,
            frames_since: 0,
            missed_streak: 0,
            ever_confirmed: false,
            image: None,
            vehicle: None,
            pose: None,
            distance: ScalarFilter::default(),
            yaw: ScalarFilter::default(),
            yaw_cue_ns: None,
            net_yaw: ScalarFilter::default(),
            net_fallback: false,
            parallax: ParallaxRanger::default(),
            raw: (None, None),
            distance_shares: [0.0; 3],
            profile_contradiction: false,
            contradiction_streak: 0,
            last_seq: 0,
        })
    }

    fn reset(&mut self) {
        *self = Core::new(self.cfg.clone(), self.opts).expect("config was validated");
    }

    /// Frame size (the reference resolution until a frame told us).
    fn image_size(&self) -> (u32, u32) {
        self.image.unwrap_or_else(|| {
            let w = self.cfg.filter.reference_width_px.round() as u32;
            (w, (f64::from(w) * FALLBACK_ASPECT).round() as u32)
        })
    }

    /// Resolution scale: image width / reference width.
    fn scale(&self) -> f64 {
        f64::from(self.image_size().0) / self.cfg.filter.reference_width_px
    }

    /// The camera at the frame size: the calibration scaled to it, else a pinhole of the
    /// configured focal length (also should a frame the calibration cannot describe reach here:
    /// the detect stage refuses those).
    fn camera(&self) -> Pinhole {
        let (w, h) = self.image_size();
        let c = &self.cfg.camera;
        if let Some(Ok(model)) = c.lens.calibration().map(|m| m.scaled_to(w, h)) {
            return Pinhole::from_model(model);
        }
        let f = if c.focal_length_per_width > 0.0 {
            c.focal_length_per_width * f64::from(w)
        } else {
            focal_length_px(f64::from(w), c.hfov_deg)
        };
        Pinhole::with_focal(w, h, f)
    }

    /// The filter's (damping, process noise, measurement noise) at the reference width: the
    /// thesis's for the baseline, ours otherwise.
    fn noise(&self) -> (f64, f64, f64) {
        if self.opts.thesis_filter {
            let t = &self.cfg.thesis_filter;
            (t.damping, t.process_noise, t.measurement_noise)
        } else {
            let f = &self.cfg.filter;
            (f.damping, f.process_noise, f.measurement_noise)
        }
    }

    /// Measurement variance R, px² at the frame's resolution.
    fn r(&self) -> f64 {
        self.noise().2 * self.scale().powi(2)
    }

    fn initial_velocity_var(&self) -> f64 {
        (self.cfg.filter.initial_velocity_std_px_s * self.scale()).powi(2)
    }

    fn ego_enabled(&self) -> bool {
        self.opts.ego_motion && self.cfg.ego_motion.enabled
    }

    fn gating_enabled(&self) -> bool {
        self.opts.gating && self.cfg.gating.enabled
    }

    /// Camera pose at `t_ns` from the newest vehicle state.
    fn pose_at(&self, t_ns: u64) -> Option<CameraPose> {
        if !self.ego_enabled() {
            return None;
        }
        let v = self.vehicle.as_ref()?;
        let e = &self.cfg.ego_motion;
        camera_pose_at(v, t_ns, e.max_state_age_s, &self.r_bc, e.use_velocity)
    }

    /// Adopts a new frame size, rescaling everything in pixels.
    fn set_image_size(&mut self, w: u32, h: u32) {
        if w == 0 || h == 0 {
            return;
        }
        if let Some((ow, oh)) = self.image {
            if (ow, oh) != (w, h) {
                let (rx, ry) = (f64::from(w) / f64::from(ow), f64::from(h) / f64::from(oh));
                if let Some(t) = self.track.as_mut() {
                    t.filter.rescale(rx, ry);
                }
                if let Some(c) = self.candidate.as_mut() {
                    c.px = [c.px[0] * rx, c.px[1] * ry];
                }
                log::info!("track: frame size changed {ow}x{oh} → {w}x{h}, state rescaled");
            }
        }
        self.image = Some((w, h));
    }

    /// Moves the state to `t_ns` (never backwards): damped prediction plus the ego-motion
    /// between the stored pose and the pose at `t_ns`.
    fn advance_to(&mut self, t_ns: u64) -> u64 {
        self.first_ns.get_or_insert(t_ns);
        let t0 = self.t_ns.unwrap_or(t_ns);
        let dt = dt_s(t_ns, t0);
        let t = if dt < 0.0 {
            log::warn!(
                "track: time stamp went backwards by {:.3} s; not predicting",
                -dt
            );
            t0
        } else {
            t_ns
        };
        let dt = dt.max(0.0);
        let cam = self.camera();
        let pose1 = self.pose_at(t);
        let (damping, process_noise, _) = self.noise();
        let model = CvModel::from_thesis(
            damping,
            process_noise,
            self.cfg.filter.reference_rate_hz,
            self.scale(),
        );
        let range = self
            .distance
            .estimate()
            .map(|e| e.value)
            .filter(|d| *d >= self.cfg.ego_motion.min_range_m);
        let frac2 = self.cfg.ego_motion.shift_std_fraction.powi(2);
        let pose0 = self.pose;
        let warp = move |px: [f64; 2], range: Option<f64>| match (pose0.as_ref(), pose1.as_ref()) {
            (Some(p0), Some(p1)) => ego_motion(&cam, px, p0, p1, dt, range),
            _ => None,
        };

        // Hub track (and, through its position, the distance and yaw changes).
        let hub_px = self.track.map_or([cam.cx, cam.cy], |t| t.filter.position());
        let ego = warp(hub_px, range);
        // The image shift from `from` to `to` (the ego-motion prediction) and its variance.
        let shift_var = |from: [f64; 2], to: Option<[f64; 2]>| match to {
            Some(p) => {
                let s = [p[0] - from[0], p[1] - from[1]];
                (s, frac2 * (s[0] * s[0] + s[1] * s[1]))
            }
            None => ([0.0, 0.0], 0.0),
        };
        if let Some(track) = self.track.as_mut() {
            let (shift, var) = shift_var(hub_px, ego.map(|m| m.px));
            track.filter.predict(&model, dt, shift, var);
        }
        if let Some((old, _)) = self.before_jump.as_mut() {
            let px = old.filter.position();
            let (shift, var) = shift_var(px, warp(px, range).map(|m| m.px));
            old.filter.predict(&model, dt, shift, var);
        }
        if let Some(c) = self.candidate.as_mut() {
            if let Some(m) = warp(c.px, None) {
                c.px = m.px;
            }
        }
        let d_shift = match (ego.and_then(|m| m.range_m), range) {
            (Some(r1), Some(r0)) => r1 - r0,
            _ => 0.0,
        };
        self.distance.predict(
            dt,
            self.cfg.distance.process_noise_m2_s,
            d_shift,
            frac2 * d_shift * d_shift,
        );
        let y_shift = ego.and_then(|m| m.relative_yaw_change_rad).unwrap_or(0.0);
        let q_yaw = self.cfg.yaw.process_noise_deg2_s * 1f64.to_radians().powi(2);
        self.yaw
            .predict(dt, q_yaw, y_shift, frac2 * y_shift * y_shift);
        self.net_yaw
            .predict(dt, q_yaw, y_shift, frac2 * y_shift * y_shift);

        self.pose = pose1;
        self.t_ns = Some(t);
        t
    }

    /// Declares timeouts: a confirmed track becomes lost, a tentative one is dropped, an old jump
    /// candidate is forgotten.
    fn apply_timeouts(&mut self, t_ns: u64) {
        let lost_after = self.cfg.modes.lost_after_s;
        let since = self.last_accept_ns.map(|a| dt_s(t_ns, a));
        if let (Some(track), Some(since)) = (self.track.as_mut(), since) {
            if since >= lost_after {
                if track.confirmed {
                    if !track.lost {
                        log::info!("track: lost ({since:.2} s without an accepted detection)");
                    }
                    track.lost = true;
                } else {
                    self.track = None;
                }
            }
        }
        if self
            .candidate
            .is_some_and(|c| dt_s(t_ns, c.t_ns) >= lost_after)
        {
            self.candidate = None;
        }
        if self
            .before_jump
            .is_some_and(|(_, at)| dt_s(t_ns, at) > self.cfg.gating.jump_fallback_s)
        {
            self.before_jump = None;
        }
    }

    fn start_track(&mut self, z: [f64; 2], consistent: u32) {
        let confirmed = consistent >= self.cfg.modes.confirm_count;
        self.ever_confirmed |= confirmed;
        self.track = Some(HubTrack {
            filter: HubFilter::new(z, self.r(), self.initial_velocity_var()),
            confirmed,
            consistent,
            lost: false,
        });
        self.candidate = None;
        // Another hub, or the same after a loss: rays of the old one would not meet these.
        self.parallax.clear();
    }

    /// Handles one hub measurement at `t_ns`; returns whether it was accepted into the track,
    /// and whether it also lay within `gating.estimate_gate_px` of the prediction.
    fn measure_hub(&mut self, z: [f64; 2], t_ns: u64) -> (bool, Option<f64>) {
        let r = self.r();
        let gating = self.gating_enabled();
        let g = self.cfg.gating.clone();
        let scale = self.scale();
        let confirm = self.cfg.modes.confirm_count;
        let Some(track) = self.track.as_mut().filter(|t| !t.lost) else {
            // No track, or it is lost: any detection starts a new one.
            self.start_track(z, 1);
            self.before_jump = None;
            return (true, None);
        };
        // Inside a filter's gate: a small Mahalanobis distance or a short innovation.
        let in_gate =
            |nu_norm: f64, d2: f64| d2 <= g.chi2_threshold || nu_norm <= g.min_gate_px * scale;
        let (nu, _, d2) = track.filter.innovation(z, r);
        let inside = !gating || in_gate(nu.norm(), d2);
        let close = (nu.norm() <= g.estimate_gate_px * scale).then_some(nu.norm());
        if inside {
            let robust = gating
                && g.robust_chi2 > 0.0
                && d2 > g.robust_chi2
                && nu.norm() > g.min_gate_px * scale;
            track
                .filter
                .update(z, if robust { r * d2 / g.robust_chi2 } else { r });
            track.consistent = track.consistent.saturating_add(1);
            // The track before a jump is an alternative only while it is elsewhere: once its
            // prediction lies inside this track's gate the two have merged, and with its wide,
            // unupdated gate it would otherwise take the next false detection beside both
            // (`eval --sequence` flight 8: a circle on the nacelle 110 px beside the hub
            // restored it and held the track there for 60 frames).
            if self.before_jump.is_some_and(|(old, _)| {
                let (nu_old, _, d2_old) = track.filter.innovation(old.filter.position(), r);
                in_gate(nu_old.norm(), d2_old)
            }) {
                self.before_jump = None;
            }
            if !track.confirmed && track.consistent >= confirm {
                track.confirmed = true;
                self.ever_confirmed = true;
            }
            self.candidate = None;
            return (true, close);
        }
        if !track.confirmed {
            // Acquiring: an inconsistent detection restarts the tentative track.
            self.start_track(z, 1);
            return (true, None);
        }
        // A confirmed track rejects the measurement. The track before a recent jump may take
        // it back, if it had more support than the new one has.
        let new_support = track.consistent;
        if let Some((mut old, _)) = self
            .before_jump
            .filter(|(old, _)| gating && old.consistent > new_support)
        {
            let (nu_old, _, d2_old) = old.filter.innovation(z, r);
            if in_gate(nu_old.norm(), d2_old) {
                log::info!(
                    "track: back to the track before the jump at ({:.1}, {:.1})",
                    z[0],
                    z[1]
                );
                old.filter.update(z, r);
                old.consistent = old.consistent.saturating_add(1);
                self.track = Some(old);
                self.before_jump = None;
                self.candidate = None;
                return (true, None);
            }
        }
        // Count it towards a persistent jump.
        let radius = g.jump_consistency_px * scale;
        let count = match self.candidate {
            Some(c) if ((c.px[0] - z[0]).powi(2) + (c.px[1] - z[1]).powi(2)).sqrt() <= radius => {
                c.count + 1
            }
            _ => 1,
        };
        if count >= g.jump_accept_count {
            log::info!(
                "track: persistent jump to ({:.1}, {:.1}) accepted after {count} detections",
                z[0],
                z[1]
            );
            let old = *track;
            self.start_track(z, count);
            self.before_jump = (self.cfg.gating.jump_fallback_s > 0.0).then_some((old, t_ns));
            return (true, None);
        }
        log::debug!(
            "track: gated out ({:.1}, {:.1}), Mahalanobis² {d2:.1}",
            z[0],
            z[1]
        );
        self.candidate = Some(Candidate { px: z, count, t_ns });
        (false, None)
    }

    fn update(&mut self, det: &Detection, vehicle: Option<&VehicleState>) -> TrackState {
        if let Some(v) = vehicle.filter(|v| v.attitude_valid) {
            self.vehicle = Some(*v);
        }
        self.set_image_size(det.image_width, det.image_height);
        let t = self.advance_to(det.stamps.capture_ns);
        self.distance_shares = [0.0; 3];

        let usable = det.detected
            && det.confidence >= self.cfg.filter.min_confidence
            && det.hub_px.iter().all(|v| v.is_finite())
            && !self.contradicts_profile(det);
        let (accepted, innovation_px) = if usable {
            self.measure_hub(det.hub_px, t)
        } else {
            (false, None)
        };
        if accepted {
            self.last_accept_ns = Some(t);
            self.missed_streak = 0;
            self.frames_since = 0;
        } else {
            self.missed_streak = self.missed_streak.saturating_add(1);
            self.frames_since = self.frames_since.saturating_add(1);
        }
        if self.opts.raw_estimates {
            self.raw = if usable {
                self.raw_estimates(det)
            } else {
                (None, None)
            };
        } else if let Some(nu) = innovation_px {
            self.filtered_estimates(det, t, nu);
        }
        self.apply_timeouts(t);
        self.last_seq = det.stamps.seq;
        self.output(t, det.stamps.seq, det.stamps.capture_ns)
    }

    /// Whether `det` puts the hub where the turbine profile's hub cannot be; logs the first of
    /// a run and warns when a long run suggests the wrong profile.
    fn contradicts_profile(&mut self, det: &Detection) -> bool {
        let profile = Profile {
            tower_top_diameter_m: self.cfg.distance.tower_diameter_m,
            hub_overhang_m: self.cfg.yaw.hub_tower_offset_m,
            spinner_diameter_m: self.cfg.distance.spinner_diameter_m,
        };
        let found = profile_check::contradiction(det, &profile, &self.cfg.profile_check);
        self.profile_contradiction = found.is_some();
        let Some(why) = found else {
            self.contradiction_streak = 0;
            return false;
        };
        self.contradiction_streak += 1;
        match self.contradiction_streak {
            1 => log::info!("track: detection {} kept out: {why}", det.stamps.seq),
            n if n % CONTRADICTION_WARN_EVERY == 0 => log::warn!(
                "track: the last {n} detections contradict the turbine profile ({why}): is the \
                 turbine profile (--turbine) the turbine in view?"
            ),
            _ => log::debug!("track: detection {} kept out: {why}", det.stamps.seq),
        }
        true
    }

    /// Adds this frame's sighting of the detected hub (the camera's position and the world ray
    /// through the hub pixel) and returns the distance the current track's sightings give.
    fn parallax_distance(&mut self, det: &Detection, t: u64) -> Option<Estimate> {
        let cfg = &self.cfg.parallax;
        if !cfg.enabled {
            return None;
        }
        let v = self.vehicle.as_ref()?;
        let max_age = self.cfg.ego_motion.max_state_age_s;
        let camera_m = camera_position_at(v, t, max_age)?;
        let pose = camera_pose_at(v, t, max_age, &self.r_bc, false)?;
        let ray = pose.r_wc * self.camera().ray(det.hub_px).normalize();
        self.parallax.push(
            Sighting {
                t_ns: t,
                camera_m,
                ray,
            },
            cfg,
        );
        let d = self.parallax.distance_from(&camera_m, &ray, cfg)?;
        log::trace!(
            "parallax distance {:.1}±{:.1} m from {} sightings",
            d.value,
            d.std,
            self.parallax.len()
        );
        Some(d)
    }

    /// Tower-depth measurement of a detection.
    fn tower_depth(&self, det: &Detection) -> Option<Estimate> {
        let d = &self.cfg.distance;
        let s = self.scale();
        if !det.tower_found || det.tower_width_px < d.min_size_px * s {
            return None;
        }
        let width_at_top = tower_top_width_px(
            det.tower_width_px,
            det.tower_width_row - det.tower_top_px[1],
            d.tower_taper,
        );
        distance_from_tower_width(
            self.camera().focal_at(Self::tower_point(det)),
            d.tower_diameter_m,
            width_at_top,
            d.tower_width_std_px * s,
        )
    }

    /// The tower axis point whose width a detection measured, px (the tower top for a row
    /// above it, as in detections that do not say the row).
    fn tower_point(det: &Detection) -> [f64; 2] {
        [
            det.tower_top_px[0],
            det.tower_width_row.max(det.tower_top_px[1]),
        ]
    }

    /// World up in the camera frame: from the attitude at this frame, else a level camera.
    fn up_in_camera(&self) -> Vector3<f64> {
        self.pose
            .as_ref()
            .map_or(Vector3::new(0.0, -1.0, 0.0), |p| {
                p.r_wc.inverse() * Vector3::new(0.0, 0.0, -1.0)
            })
    }

    /// The filtered relative yaw as an exact value (0 before there is one).
    fn yaw_now(&self) -> Estimate {
        Estimate::exact(self.yaw.estimate().map_or(0.0, |e| e.value))
    }

    /// How the hub sits relative to the tower point a detection measured at depth `depth_m`,
    /// at relative yaw 0 (see [`HubFromTower::with_yaw`]).
    fn tower_view(&self, det: &Detection, depth_m: f64) -> HubFromTower {
        let cam = self.camera();
        let rows_below_top = (det.tower_width_row - det.tower_top_px[1]).max(0.0);
        HubFromTower {
            hub_ray: cam.ray(det.hub_px),
            up: self.up_in_camera(),
            yaw: Estimate::exact(0.0),
            overhang_m: self.cfg.yaw.hub_tower_offset_m,
            hub_above_m: self.cfg.distance.hub_above_tower_top_m
                + rows_below_top * depth_m / cam.focal_at(Self::tower_point(det)),
        }
    }

    /// The thesis's per-frame estimates: distance from the tower width (depth of the tower, eq.
    /// 7.2) and yaw from the gap with that distance (eq. 7.14).
    fn raw_estimates(&self, det: &Detection) -> (Option<Estimate>, Option<Estimate>) {
        let tower = self.tower_depth(det);
        let y = &self.cfg.yaw;
        let yaw = tower.and_then(|td| {
            yaw_from_gap(
                det.hub_tower_gap_px,
                y.gap_std_lines_px * self.scale(),
                td,
                self.camera().focal_at(det.hub_px),
                y.hub_tower_offset_m,
                y.max_abs_deg.to_radians(),
            )
        });
        (tower, yaw)
    }

    /// Yaw and distance measurements of an accepted detection into their filters.
    /// `innovation_px`: the hub's distance from the track's prediction.
    fn filtered_estimates(&mut self, det: &Detection, t: u64, innovation_px: f64) {
        let mut sizes = self.size_distances(det);
        let parallax = self.check_parallax(det, t, &mut sizes);
        let (cues, net) = self.yaw_cues(det, &sizes, innovation_px);
        self.update_yaw(t, &cues, net);
        self.update_distance(t, &sizes, parallax);
    }

    /// The hub's distance from one detection alone (see [`Tracker::still_distance`]).
    fn still_distance(&self, det: &Detection) -> Option<f64> {
        let (tower, yaw) = self.raw_estimates(det);
        let from_tower = tower.and_then(|depth| {
            let yaw = Estimate::exact(yaw.map_or(0.0, |y| y.value));
            self.tower_view(det, depth.value)
                .with_yaw(yaw)
                .hub_distance(depth)
        });
        from_tower
            .or_else(|| self.spinner_distance(det))
            .map(|d| d.value)
    }

    /// Distance of the hub from the spinner circle's size, when it is large enough.
    fn spinner_distance(&self, det: &Detection) -> Option<Estimate> {
        let dc = &self.cfg.distance;
        let s = self.scale();
        if det.circle_found && 2.0 * det.circle[2] >= dc.min_size_px * s {
            let centre = [det.circle[0], det.circle[1]];
            // Only the elevation, which the attitude knows: a yaw estimate 20° off close in
            // would hand the distance to the tower exactly where its bands are least sure.
            let oblique = off_axis_sin(self.camera().ray(centre), self.up_in_camera(), 0.0)
                .map_or(0.0, |sin_b| {
                    dc.spinner_oblique_std * sin_b * sin_b * det.circle[2]
                });
            distance_from_spinner(
                self.camera().focal_at(centre),
                dc.spinner_diameter_m,
                det.circle[2],
                (dc.spinner_radius_std_px * s).hypot(oblique),
            )
        } else {
            None
        }
    }

    /// The tower depth and the spinner distance of a detection, checked against each other.
    fn size_distances(&self, det: &Detection) -> SizeDistances {
        let dc = &self.cfg.distance;
        let spinner = self.spinner_distance(det);
        let tower = self.tower_depth(det);
        // A tower whose width disagrees with the spinner's size is a wrong band (a blade beside
        // the tower, tower and blade together): it gives neither distance nor yaw. Which of the
        // two is wrong? The one farther from the filtered distance; without one, both.
        let mut sizes = SizeDistances {
            tower,
            tower_view: tower.map(|td| self.tower_view(det, td.value)),
            spinner,
            spinner_seen: spinner,
            tower_rejected: false,
            tower_disputed: false,
            rejected_width_ratio: None,
        };
        let (Some(sp), Some(view), Some(tower_hub)) = (
            sizes.spinner,
            sizes.tower_view,
            sizes.tower_hub(self.yaw_now()),
        ) else {
            return sizes;
        };
        let view = view.with_yaw(self.yaw_now());
        let chi2 = tower_hub.chi2_to(&sp);
        if chi2 <= dc.consistency_chi2 {
            return sizes;
        }
        sizes.tower_disputed = true;
        match self.distance.estimate() {
            Some(prior)
                if (sp.value - prior.value).abs() < (tower_hub.value - prior.value).abs() =>
            {
                sizes.tower = None
            }
            Some(_) => sizes.spinner = None,
            None => (sizes.tower, sizes.spinner) = (None, None),
        }
        sizes.tower_rejected = sizes.tower.is_none();
        if sizes.tower_rejected {
            sizes.rejected_width_ratio = view.tower_depth(sp.value).map(|depth| {
                let expected_px =
                    self.camera().focal_at(Self::tower_point(det)) * dc.tower_diameter_m / depth;
                det.tower_width_px / expected_px
            });
        }
        log::debug!(
            "tower {:.1} m and spinner {:.1} m disagree (chi2 {chi2:.0}): kept {}",
            tower_hub.value,
            sp.value,
            match (sizes.tower, sizes.spinner) {
                (Some(_), _) => "tower",
                (_, Some(_)) => "spinner",
                _ => "neither",
            }
        );
        sizes
    }

    /// Motion parallax: a size-free distance. A tower or spinner distance it contradicts is
    /// dropped from `sizes`, the tower's gap with it (see `[track.parallax]`).
    fn check_parallax(
        &mut self,
        det: &Detection,
        t: u64,
        sizes: &mut SizeDistances,
    ) -> Option<Estimate> {
        let p = self.parallax_distance(det, t)?;
        let disagrees = |m: Estimate| m.chi2_to(&p) > self.cfg.parallax.consistency_chi2;
        let tower_hub = sizes.tower_hub(self.yaw_now());
        if tower_hub.is_some_and(disagrees) {
            log::debug!(
                "tower {:.1} m disagrees with parallax {:.1}±{:.1} m: dropped",
                tower_hub.map_or(0.0, |e| e.value),
                p.value,
                p.std
            );
            sizes.tower = None;
            sizes.tower_disputed = true;
            sizes.tower_rejected = true;
            sizes.rejected_width_ratio = None;
        }
        if sizes.spinner.is_some_and(disagrees) {
            log::debug!(
                "spinner {:.1} m disagrees with parallax {:.1}±{:.1} m: dropped",
                sizes.spinner.map_or(0.0, |sp| sp.value),
                p.value,
                p.std
            );
            sizes.spinner = None;
        }
        Some(p)
    }

    /// Yaw from the hub–tower gap. The gap needs the depth of the tower axis: this frame's
    /// tower width, else the filtered hub distance plus the overhang.
    fn gap_yaw(
        &self,
        det: &Detection,
        sizes: &SizeDistances,
        yaw_prior: Option<Estimate>,
    ) -> Option<Estimate> {
        let yc = &self.cfg.yaw;
        let offset = yc.hub_tower_offset_m;
        let tower_depth = sizes.tower.or_else(|| {
            let d = self.distance.estimate().or(sizes.spinner_seen)?;
            let view = self
                .tower_view(det, d.value + offset)
                .with_yaw(yaw_prior.unwrap_or(Estimate::exact(0.0)));
            Some(Estimate {
                value: view.tower_depth(d.value)?,
                std: d.std,
            })
        });
        // A band the spinner disputes gives no gap even when the filtered distance sides with it:
        // one of the two is wrong, and a wrong band is most often the blade pointing down merged
        // with the tower, whose axis is not the tower's.
        let band_undisputed = !sizes.tower_disputed;
        let band_on_tower = band_undisputed
            || sizes
                .rejected_width_ratio
                .is_some_and(|r| r <= yc.gap_max_width_ratio && r * yc.gap_max_width_ratio >= 1.0);
        if !(det.tower_found && det.detected && band_on_tower) {
            return None;
        }
        // How well the hub end of the gap is known depends on how the hub was found.
        let gap_std = if det.circle_found {
            yc.gap_std_spinner_px
        } else {
            yc.gap_std_lines_px
        };
        let (s, f) = (self.scale(), self.camera().focal_at(det.hub_px));
        tower_depth.and_then(|td| {
            yaw_from_gap(
                det.hub_tower_gap_px,
                gap_std * s,
                td,
                f,
                offset,
                yc.max_abs_deg.to_radians(),
            )
        })
    }

    /// Yaw from the nacelle's far end: a yaw the tower hidden behind a blade cannot fake (see
    /// `use_nacelle`). The end is measured from the detected hub, whose error it takes whole
    /// (see `nacelle_gate_px`); `spinner` is this frame's checked spinner distance.
    fn nacelle_yaw(
        &self,
        det: &Detection,
        spinner: Option<Estimate>,
        innovation_px: f64,
    ) -> Option<Estimate> {
        let yc = &self.cfg.yaw;
        let (s, f) = (self.scale(), self.camera().focal_at(det.hub_px));
        let hub_settled = yc.nacelle_gate_px <= 0.0 || innovation_px <= yc.nacelle_gate_px * s;
        let on_spinner = det.circle_found || !yc.nacelle_needs_spinner;
        if !(yc.use_nacelle && det.detected && det.nacelle_found && hub_settled && on_spinner) {
            return None;
        }
        let d = self
            .distance
            .estimate()
            .or(spinner)
            .filter(|d| d.value >= yc.nacelle_min_distance_m)?;
        // Only an end beyond the spinner's rim (see `nacelle_rim_clearance_m`).
        let rim_reach_px = spinner_rim_reach_px(
            f,
            self.cfg.distance.spinner_diameter_m / 2.0,
            d.value,
            det.circle_found.then_some(det.circle[2]),
            yc.nacelle_rim_clearance_m,
        );
        if det.nacelle_end_dx_px.abs() < rim_reach_px {
            return None;
        }
        // Only an end well beyond the head-on front corners (see `nacelle_min_excess_sigma`).
        let hub_std = if det.circle_found {
            yc.gap_std_spinner_px
        } else {
            yc.gap_std_lines_px
        };
        let excess = nacelle_excess_sigma(
            det.nacelle_end_dx_px,
            yc.nacelle_std_px.hypot(hub_std) * s,
            d,
            f,
            yc.nacelle_front_m,
            yc.nacelle_half_width_m,
        );
        if excess < yc.nacelle_min_excess_sigma {
            return None;
        }
        let e = yaw_from_nacelle(
            det.nacelle_end_dx_px,
            yc.nacelle_std_px * s,
            d,
            f,
            yc.nacelle_rear_m,
            yc.nacelle_half_width_m,
            yc.max_abs_deg.to_radians(),
        )?;
        // Near zero yaw the side is a toss-up (see `nacelle_min_abs_deg`).
        (e.value.abs() >= yc.nacelle_min_abs_deg.to_radians()).then(|| Estimate {
            value: e.value,
            std: e.std.max(yc.nacelle_min_std_deg.to_radians()),
        })
    }

    /// The learned yaw network's reading (see `use_net`), radians, with its spread floored.
    fn net_yaw_reading(&self, det: &Detection) -> Option<Estimate> {
        let yc = &self.cfg.yaw;
        (yc.use_net && det.detected && det.yaw_net_valid && det.yaw_net_deg.is_finite())
            .then_some(det.yaw_net_std_deg)
            .filter(|s| s.is_finite() && *s <= yc.net_max_std_deg)
            .map(|s| Estimate {
                value: det.yaw_net_deg.to_radians(),
                std: s.max(yc.net_min_std_deg).to_radians(),
            })
    }

    /// The geometric yaw measurements of a detection (gap, nacelle) that
    /// survive each other's and the network's vetoes, and the network's reading.
    fn yaw_cues(
        &self,
        det: &Detection,
        sizes: &SizeDistances,
        innovation_px: f64,
    ) -> (Vec<Estimate>, Option<Estimate>) {
        let yc = &self.cfg.yaw;
        let yaw_prior = self.yaw.estimate();
        let gap = self.gap_yaw(det, sizes, yaw_prior);
        let nacelle = self.nacelle_yaw(det, sizes.spinner, innovation_px);
        // A gap and a nacelle that contradict each other: one is wrong, and neither is used.
        let (gap, nacelle) = match (gap, nacelle) {
            (Some(g), Some(n)) if g.chi2_to(&n) > yc.gate_chi2 => (None, None),
            pair => pair,
        };
        // With `net_vetoes_gap` a gap or nacelle yaw the network contradicts is dropped.
        let net = self.net_yaw_reading(det);
        let contradicts = |m: Option<Estimate>| match (m, net) {
            (Some(m), Some(n)) => yc.net_vetoes_gap && m.chi2_to(&n) > yc.gate_chi2,
            _ => false,
        };
        let gap = if contradicts(gap) { None } else { gap };
        let nacelle = if contradicts(nacelle) { None } else { nacelle };
        // The blade skew gives |ψ|; its sign comes from the gap (and the filtered yaw).
        let show = |e: Option<Estimate>| {
            e.map_or("-".to_string(), |e| {
                format!("{:+.1}±{:.1}°", e.value.to_degrees(), e.std.to_degrees())
            })
        };
        log::debug!(
            "yaw, frame {}: gap {} nacelle {} network {} prior {}",
            det.stamps.seq,
            show(gap),
            show(nacelle),
            show(net),
            show(yaw_prior)
        );
        let cues = [gap, nacelle].into_iter().flatten().collect::<Vec<_>>();
        (cues, net)
    }

    /// The yaw filter from this frame's geometric `cues` and network reading `net`; with no
    /// measurement to fuse, the network's fallback (see
    /// `net_fallback_after_s`).
    fn update_yaw(&mut self, t: u64, cues: &[Estimate], net: Option<Estimate>) {
        let yc = &self.cfg.yaw;
        // The readings the fallback trusts: from `net_fallback_min_distance_m` out (closer, the
        // network's error grows past the approach's yaw tolerance).
        let net_trusted = net.filter(|_| {
            yc.net_fallback_min_distance_m <= 0.0
                || self
                    .distance
                    .estimate()
                    .is_some_and(|d| d.value >= yc.net_fallback_min_distance_m)
        });
        if let Some(n) = net_trusted {
            self.net_yaw
                .update(n, yc.gate_chi2, yc.jump_accept_count, t);
        }
        // The network's reading only vetoes (above): its error is a bias per scene more than noise
        // per frame, and fused it would set the final yaw close in.
        if let Some(m) = fuse(cues) {
            // No jumps close in (see `jump_min_distance_m`): only gated updates.
            let close = self
                .distance
                .estimate()
                .is_some_and(|d| d.value < yc.jump_min_distance_m);
            let jump_count = if close {
                u32::MAX
            } else {
                yc.jump_accept_count
            };
            if self.yaw.update(m, yc.gate_chi2, jump_count, t) && !cues.is_empty() {
                self.yaw_cue_ns = Some(t);
                self.net_fallback = false;
            }
        } else if yc.net_fallback_after_s > 0.0 && net.is_some() {
            self.net_fallback_update(t, net_trusted);
        }
    }

    /// No geometric cue for `net_fallback_after_s` (since the first frame, if never): once the
    /// network's filtered reading stands `net_fallback_min_deg` from the stale yaw, it restarts
    /// the yaw and carries it, every trusted reading fused, until a cue returns.
    fn net_fallback_update(&mut self, t: u64, net_trusted: Option<Estimate>) {
        let yc = &self.cfg.yaw;
        let cue_age_s = self
            .yaw_cue_ns
            .or(self.first_ns)
            .map_or(0.0, |c| dt_s(t, c));
        if self.net_fallback {
            if let Some(n) = net_trusted {
                self.yaw.update(n, yc.gate_chi2, yc.jump_accept_count, t);
            }
        } else if let Some(reference) = self
            .net_yaw
            .estimate()
            .filter(|_| cue_age_s >= yc.net_fallback_after_s)
        {
            let far = self.yaw.estimate().is_none_or(|y| {
                (reference.value - y.value).abs() >= yc.net_fallback_min_deg.to_radians()
            });
            if far {
                let std = reference.std.max(yc.net_min_std_deg.to_radians());
                self.yaw.update(
                    Estimate {
                        value: reference.value,
                        std,
                    },
                    yc.gate_chi2,
                    1,
                    t,
                );
                self.net_fallback = true;
            }
        }
    }

    /// The distance filter from this frame's hub distances: the tower's (its depth taken to the
    /// hub with the updated yaw, see [`HubFromTower`]), the spinner's and the parallax's.
    fn update_distance(&mut self, t: u64, sizes: &SizeDistances, parallax: Option<Estimate>) {
        let dc = &self.cfg.distance;
        let tower_hub = sizes.tower_hub(self.yaw.estimate().unwrap_or(Estimate::exact(0.0)));
        let cues = [tower_hub, sizes.spinner, parallax];
        let Some(m) = fuse(&cues.into_iter().flatten().collect::<Vec<_>>()) else {
            return;
        };
        self.distance_shares = fusion_shares(cues).unwrap_or_default();
        // No jumps close in (see `distance.jump_min_distance_m`): only gated updates, while
        // the filter has accepted a reading within `jump_lockout_max_s`.
        let recent = dc.jump_lockout_max_s <= 0.0
            || self
                .distance
                .last_accept_ns
                .is_some_and(|a| dt_s(t, a) <= dc.jump_lockout_max_s);
        let close = recent
            && self
                .distance
                .estimate()
                .is_some_and(|d| d.value < dc.jump_min_distance_m);
        self.distance.update(
            m,
            dc.gate_chi2,
            if close {
                u32::MAX
            } else {
                dc.jump_accept_count
            },
            t,
        );
    }

    fn mode(&self, t_ns: u64) -> TrackMode {
        match &self.track {
            None if self.ever_confirmed => TrackMode::Lost,
            None => TrackMode::Acquiring,
            Some(tr) if !tr.confirmed => TrackMode::Acquiring,
            Some(tr) if tr.lost => TrackMode::Lost,
            Some(_) => {
                let since = self.time_since_detection(t_ns);
                if self.missed_streak < self.cfg.modes.coast_after_missed {
                    TrackMode::Tracking
                } else if since < self.cfg.modes.lost_after_s {
                    TrackMode::Coasting
                } else {
                    TrackMode::Lost
                }
            }
        }
    }

    /// Seconds since the last accepted detection (since the first frame if there was none).
    fn time_since_detection(&self, t_ns: u64) -> f64 {
        self.last_accept_ns
            .or(self.first_ns)
            .map_or(0.0, |a| dt_s(t_ns, a).max(0.0))
    }

    fn output(&self, t_ns: u64, seq: u64, capture_ns: u64) -> TrackState {
        let (w, h) = self.image_size();
        let mode = self.mode(t_ns);
        let since = self.time_since_detection(t_ns);
        let (hub_px, vel, cov) = match &self.track {
            Some(tr) => {
                let (x, p) = (&tr.filter.x, &tr.filter.p);
                (
                    [x[0], x[1]],
                    [x[2], x[3]],
                    [p[(0, 0)], p[(0, 1)], p[(1, 0)], p[(1, 1)]],
                )
            }
            None => {
                // No track: "anywhere in the image".
                let cam = self.camera();
                let (vx, vy) = (
                    f64::from(w).powi(2) * UNIFORM_VAR_PER_WIDTH2,
                    f64::from(h).powi(2) * UNIFORM_VAR_PER_WIDTH2,
                );
                ([cam.cx, cam.cy], [0.0, 0.0], [vx, 0.0, 0.0, vy])
            }
        };
        let (distance, yaw) = if self.opts.raw_estimates {
            self.raw
        } else {
            let fresh = |f: &ScalarFilter, stale_s: f64, max_std: f64| {
                f.estimate().filter(|e| {
                    e.std <= max_std && f.last_accept_ns.is_some_and(|a| dt_s(t_ns, a) <= stale_s)
                })
            };
            (
                fresh(
                    &self.distance,
                    self.cfg.distance.stale_after_s,
                    self.cfg.distance.max_std_m,
                ),
                fresh(
                    &self.yaw,
                    self.cfg.yaw.stale_after_s,
                    self.cfg.yaw.max_std_deg.to_radians(),
                ),
            )
        };
        // Report the last values (flagged invalid) rather than zeros when they went stale.
        let distance_any = distance.or(if self.opts.raw_estimates {
            None
        } else {
            self.distance.estimate()
        });
        let yaw_any = yaw.or(if self.opts.raw_estimates {
            None
        } else {
            self.yaw.estimate()
        });
        let ray = self.camera().ray(hub_px);
        let hub_bearing_deg = [
            ray.x.atan2(ray.z).to_degrees(),
            (-ray.y).atan2(ray.x.hypot(ray.z)).to_degrees(),
        ];
        // The network's filtered yaw, on the frames whose reading it took.
        let net_yaw = self
            .net_yaw
            .estimate()
            .filter(|_| self.net_yaw.last_accept_ns == Some(t_ns));
        TrackState {
            stamps: hubtrack_types::Stamps {
                seq,
                capture_ns,
                recv_ns: 0,
                publish_ns: 0,
            },
            mode,
            search_requested: matches!(mode, TrackMode::Lost | TrackMode::Acquiring)
                && since >= self.cfg.modes.search_after_s,
            image_width: w,
            image_height: h,
            hub_px,
            hub_velocity_px_s: vel,
            hub_covariance: cov,
            hub_bearing_deg,
            distance_valid: distance.is_some(),
            distance_m: distance_any.map_or(0.0, |e| e.value),
            distance_std_m: distance_any.map_or(0.0, |e| e.std),
            yaw_valid: yaw.is_some(),
            yaw_deg: yaw_any.map_or(0.0, |e| e.value.to_degrees()),
            yaw_std_deg: yaw_any.map_or(0.0, |e| e.std.to_degrees()),
            net_yaw_valid: net_yaw.is_some(),
            net_yaw_deg: net_yaw.map_or(0.0, |e| e.value.to_degrees()),
            net_yaw_std_deg: net_yaw.map_or(0.0, |e| e.std.to_degrees()),
            frames_since_detection: self.frames_since,
            time_since_detection_s: since,
            distance_share_tower: self.distance_shares[0],
            distance_share_spinner: self.distance_shares[1],
            distance_share_parallax: self.distance_shares[2],
            profile_contradiction: self.profile_contradiction,
        }
    }

    fn predict_at(&self, capture_ns: u64) -> TrackState {
        let mut c = self.clone();
        let t = c.advance_to(capture_ns);
        c.apply_timeouts(t);
        c.output(t, self.last_seq, capture_ns)
    }
}

/// The hub tracker (the default): the thesis's damped constant-velocity Kalman filter driven by
/// the frame time stamps, with outlier gating, track modes, attitude-aided prediction, and
/// filtered distance and relative-yaw estimates. See the crate docs.
#[derive(Debug, Clone)]
pub struct Tracker {
    core: Core,
}

impl Tracker {
    /// A tracker with a validated configuration.
    pub fn new(config: crate::params::TrackConfig) -> Result<Tracker, crate::params::ParamError> {
        Ok(Tracker {
            core: Core::new(
                config,
                Options {
                    gating: true,
                    ego_motion: true,
                    raw_estimates: false,
                    thesis_filter: false,
                },
            )?,
        })
    }

    /// One step per processed frame: `detection.detected == false` means a missed frame (predict only).
    ///
    /// `vehicle` is the newest vehicle state (if any); without one, the newest earlier state is
    /// used while it is within `ego_motion.max_state_age_s` of the frame.
    pub fn update(&mut self, detection: &Detection, vehicle: Option<&VehicleState>) -> TrackState {
        self.core.update(detection, vehicle)
    }

    /// Prediction at a time without a new frame (e.g. to publish at a fixed rate); does not change the state.
    ///
    /// The stamps carry the last frame's `seq` and the requested `capture_ns`; the attitude is
    /// extrapolated from the newest vehicle state with its body rates.
    pub fn predict_at(&self, capture_ns: u64) -> TrackState {
        self.core.predict_at(capture_ns)
    }

    /// Forgets everything (back to `acquiring`), keeping the configuration.
    pub fn reset(&mut self) {
        self.core.reset();
    }

    /// The configuration in use.
    pub fn config(&self) -> &TrackConfig {
        &self.core.cfg
    }

    /// The hub's distance from one detection alone, as of a still photo: the depth of the tower
    /// point its width was measured at, taken to the hub by the turbine profile's overhang at
    /// the relative yaw its hub–tower gap gives (0 without one) with the camera level, as the
    /// tracker takes each frame's tower; else the spinner circle's distance; `None` without
    /// either. Forgets the track: a still photo has none.
    pub fn still_distance(&mut self, detection: &Detection) -> Option<f64> {
        self.core.reset();
        self.core.image = Some((detection.image_width, detection.image_height));
        self.core.still_distance(detection)
    }
}

/// The thesis's tracker (section 6.2) for side-by-side evaluation: the same damped
/// constant-velocity filter on real time stamps with the same modes, but **no gating** (every
/// detection is fused), **no vehicle input**, and the thesis's raw per-frame distance (tower
/// width, eq. 7.2, the depth of the tower) and yaw (eq. 7.14 with that distance), valid only on
/// frames that measured them.
#[derive(Debug, Clone)]
pub struct BaselineTracker {
    core: Core,
}

impl BaselineTracker {
    /// A baseline tracker; uses `camera`, `filter`, `modes`, and the sizes and noise of
    /// `distance` and `yaw` from the configuration.
    pub fn new(
        config: crate::params::TrackConfig,
    ) -> Result<BaselineTracker, crate::params::ParamError> {
        Ok(BaselineTracker {
            core: Core::new(
                config,
                Options {
                    gating: false,
                    ego_motion: false,
                    raw_estimates: true,
                    thesis_filter: true,
                },
            )?,
        })
    }

    /// One step per processed frame, as [`Tracker::update`]; `vehicle` is ignored.
    pub fn update(&mut self, detection: &Detection, vehicle: Option<&VehicleState>) -> TrackState {
        let _ = vehicle;
        self.core.update(detection, None)
    }

    /// Prediction at a time without a new frame; does not change the state.
    pub fn predict_at(&self, capture_ns: u64) -> TrackState {
        self.core.predict_at(capture_ns)
    }

    /// Forgets everything, keeping the configuration.
    pub fn reset(&mut self) {
        self.core.reset();
    }
}
