//! Tests: scripted track sequences for every rule, config checks, a fuzz for panics and limits,
//! and a closed-loop flight against a kinematic point-mass vehicle.

use super::*;
use hubtrack_types::Stamps;

const W: u32 = 1920;
const H: u32 = 1080;
/// 15 Hz frames.
const FRAME_NS: u64 = 66_666_667;
const EPS: f64 = 1e-9;

/// A tracking state with the hub at normalised `(ex, ey)`, optional distance and yaw.
fn track(ex: f64, ey: f64, dist: Option<f64>, yaw: Option<f64>) -> TrackState {
    TrackState {
        stamps: Stamps::default(),
        mode: TrackMode::Tracking,
        image_width: W,
        image_height: H,
        hub_px: [
            f64::from(W) / 2.0 * (1.0 + ex),
            f64::from(H) / 2.0 * (1.0 + ey),
        ],
        distance_valid: dist.is_some(),
        distance_m: dist.unwrap_or(0.0),
        yaw_valid: yaw.is_some(),
        yaw_deg: yaw.unwrap_or(0.0),
        ..TrackState::default()
    }
}

/// A track in `mode` with the hub at the centre and no estimates.
fn track_mode(mode: TrackMode, since_s: f64) -> TrackState {
    TrackState {
        mode,
        time_since_detection_s: since_s,
        ..track(0.0, 0.0, None, None)
    }
}

fn vehicle(link_ok: bool) -> VehicleState {
    VehicleState {
        link_ok,
        armed: true,
        custom_mode: 4,
        ..VehicleState::default()
    }
}

/// Checks that hold for every output of every test.
fn check_output(out: &ApproachOutput, c: &ApproachConfig) {
    assert!(
        out.reason.len() <= MAX_REASON_BYTES,
        "reason too long: {:?}",
        out.reason
    );
    assert!(!out.reason.is_empty());
    for v in [out.vx_m_s, out.vy_m_s, out.vz_m_s, out.yaw_rate_rad_s] {
        assert!(v.is_finite(), "{out:?}");
    }
    assert!(
        out.vx_m_s <= c.max_forward_m_s + EPS && out.vx_m_s >= -c.max_backward_m_s - EPS,
        "{out:?}"
    );
    assert!(out.vy_m_s.abs() <= c.max_lateral_m_s + EPS, "{out:?}");
    assert!(out.vz_m_s.abs() <= c.max_vertical_m_s + EPS, "{out:?}");
    assert!(
        out.yaw_rate_rad_s.abs() <= c.max_yaw_rate_deg_s.to_radians() + EPS,
        "{out:?}"
    );
    if matches!(out.task, ApproachTask::Hold | ApproachTask::Abort) {
        assert_eq!(
            (out.vx_m_s, out.vy_m_s, out.vz_m_s, out.yaw_rate_rad_s),
            (0.0, 0.0, 0.0, 0.0),
            "{out:?}"
        );
    }
    if out.task == ApproachTask::Done {
        // Hovering, holding the station sideways and the distance (gently: Done is left beyond
        // the outer distance tolerance).
        assert_eq!((out.vz_m_s, out.yaw_rate_rad_s), (0.0, 0.0), "{out:?}");
        assert!(
            out.vx_m_s.abs() <= c.done_distance_gain_per_s * c.distance_tolerance_outer_m + EPS,
            "{out:?}"
        );
    }
    if let Some(t) = &out.transition {
        assert_eq!(t.to, out.task);
        assert_ne!(t.from, t.to);
        assert_eq!(t.reason, out.reason);
    }
}

/// A vehicle with a valid attitude, heading 0.3 rad (the turbine-heading tests).
fn attitude_vehicle() -> VehicleState {
    VehicleState {
        attitude_valid: true,
        yaw_rad: 0.3,
        ..vehicle(true)
    }
}

/// A centred track at `dist` m with the geometric yaw `yaw` and the yaw network's reading `net`.
fn track_with_net(dist: f64, yaw: f64, net: Option<f64>) -> TrackState {
    TrackState {
        net_yaw_valid: net.is_some(),
        net_yaw_deg: net.unwrap_or(0.0),
        ..track(0.0, 0.0, Some(dist), Some(yaw))
    }
}

/// Drives the controller at 15 Hz; the track's capture time is the step time.
struct Rig {
    ap: Approach,
    now: u64,
    vehicle: Option<VehicleState>,
    /// Every output, in order.
    log: Vec<ApproachOutput>,
}

impl Rig {
    fn new() -> Rig {
        Rig::with(ApproachConfig::default())
    }

    fn with(c: ApproachConfig) -> Rig {
        Rig {
            ap: Approach::new(c).unwrap(),
            now: 1_000_000_000,
            vehicle: None,
            log: Vec::new(),
        }
    }

    /// One step with `t` captured now (or no track), then time advances one frame.
    fn step(&mut self, t: Option<TrackState>) -> ApproachOutput {
        let t = t.map(|mut t| {
            t.stamps.capture_ns = self.now;
            t
        });
        let out = self.ap.step(&ApproachInput {
            now_ns: self.now,
            track: t.as_ref(),
            vehicle: self.vehicle.as_ref(),
        });
        check_output(&out, self.ap.config());
        assert_eq!(self.ap.task(), out.task);
        self.now += FRAME_NS;
        self.log.push(out.clone());
        out
    }

    /// Steps for `secs` seconds with the same (re-stamped) track; returns the last output.
    fn run(&mut self, t: Option<TrackState>, secs: f64) -> ApproachOutput {
        let n = ((secs * 1e9 / FRAME_NS as f64).round() as usize).max(1);
        let mut out = None;
        for _ in 0..n {
            out = Some(self.step(t));
        }
        out.unwrap()
    }

    fn tasks_since(&self, from: usize) -> Vec<ApproachTask> {
        let mut v: Vec<ApproachTask> = Vec::new();
        for o in &self.log[from..] {
            if v.last() != Some(&o.task) {
                v.push(o.task);
            }
        }
        v
    }
}

// ---------------------------------------------------------------- config

#[test]
fn defaults_validate_and_new_accepts_them() {
    ApproachConfig::default().validate().unwrap();
    let ap = Approach::new(ApproachConfig::default()).unwrap();
    assert_eq!(ap.task(), ApproachTask::Hold);
    assert_eq!(ap.config(), &ApproachConfig::default());
}

#[test]
fn bad_values_name_their_key() {
    let c = ApproachConfig {
        max_forward_m_s: -1.0,
        ..ApproachConfig::default()
    };
    let e = c.validate().unwrap_err();
    assert_eq!(e.key, "control.approach.max_forward_m_s");
    assert!(
        e.to_string().contains("control.approach.max_forward_m_s"),
        "{e}"
    );
    assert_eq!(
        Approach::new(c).unwrap_err().key,
        "control.approach.max_forward_m_s"
    );

    let cases: Vec<(&str, ApproachConfig)> = vec![
        (
            "target_distance_m",
            ApproachConfig {
                target_distance_m: f64::NAN,
                ..Default::default()
            },
        ),
        (
            "yaw_filter_s",
            ApproachConfig {
                yaw_filter_s: f64::INFINITY,
                ..Default::default()
            },
        ),
        (
            "box_inner_x",
            ApproachConfig {
                box_inner_x: 0.2,
                ..Default::default()
            },
        ),
        (
            "distance_tolerance_m",
            ApproachConfig {
                distance_tolerance_m: 0.6,
                ..Default::default()
            },
        ),
        (
            "yaw_tolerance_deg",
            ApproachConfig {
                yaw_tolerance_deg: 6.0,
                ..Default::default()
            },
        ),
        (
            "deadband_y",
            ApproachConfig {
                deadband_y: 0.09,
                ..Default::default()
            },
        ),
        (
            "min_distance_m",
            ApproachConfig {
                min_distance_m: 6.0,
                ..Default::default()
            },
        ),
        (
            "search_yaw_rate_deg_s",
            ApproachConfig {
                search_yaw_rate_deg_s: 30.0,
                ..Default::default()
            },
        ),
        (
            "max_dt_s",
            ApproachConfig {
                max_dt_s: 0.0,
                ..Default::default()
            },
        ),
    ];
    for (key, c) in cases {
        assert_eq!(
            c.validate().unwrap_err().key,
            format!("control.approach.{key}")
        );
    }
}

#[test]
fn default_config_round_trips_through_toml() {
    let c = ApproachConfig::default();
    let text = toml::to_string(&c).unwrap();
    let back: ApproachConfig = toml::from_str(&text).unwrap();
    assert_eq!(back, c);
    // Keys left out take their defaults; unknown keys are rejected.
    let partial: ApproachConfig = toml::from_str("target_distance_m = 8.0").unwrap();
    assert_eq!(
        partial,
        ApproachConfig {
            target_distance_m: 8.0,
            ..ApproachConfig::default()
        }
    );
    assert!(toml::from_str::<ApproachConfig>("target_distanse_m = 8.0").is_err());
}

// ---------------------------------------------------------------- task signs

#[test]
fn t1_signs() {
    let cases: [(f64, f64, f64, f64); 4] = [
        // (ex, ey, yaw rate sign, vz sign)
        (0.3, 0.0, 1.0, 0.0),
        (-0.3, 0.0, -1.0, 0.0),
        (0.0, -0.3, 0.0, -1.0), // hub above: climb (vz < 0)
        (0.0, 0.3, 0.0, 1.0),   // hub below: descend
    ];
    for (ex, ey, r_sign, vz_sign) in cases {
        let mut rig = Rig::new();
        let out = rig.run(Some(track(ex, ey, Some(30.0), Some(10.0))), 1.0);
        assert_eq!(out.task, ApproachTask::CentreHub, "{ex} {ey}: {out:?}");
        assert_eq!(
            out.yaw_rate_rad_s.signum() * r_sign.abs(),
            r_sign,
            "{out:?}"
        );
        assert_eq!(out.vz_m_s.signum() * vz_sign.abs(), vz_sign, "{out:?}");
        if r_sign == 0.0 {
            assert_eq!(out.yaw_rate_rad_s, 0.0);
        }
        if vz_sign == 0.0 {
            assert_eq!(out.vz_m_s, 0.0);
        }
        // T1 alone moves neither forward nor sideways.
        assert_eq!((out.vx_m_s, out.vy_m_s), (0.0, 0.0));
        assert!(out.reason.starts_with("T1: hub 0.30"), "{}", out.reason);
    }
    let mut rig = Rig::new();
    let out = rig.run(Some(track(0.31, 0.0, Some(30.0), None)), 0.1);
    assert_eq!(out.reason, "T1: hub 0.31 right of centre (box 0.15)");
}

/// A 60° 640×480 camera's vertical focal length in half image heights (`fy / (h / 2)`).
const NARROW_FOCAL_HALF_HEIGHTS: f64 = 692.820_323 / 240.0;

/// A track with the hub seen `elevation_deg` above the optical axis through a camera of
/// `focal_half_heights` (the image row and the calibrated bearing agree), 30 m out.
fn track_seen_at(elevation_deg: f64, focal_half_heights: f64) -> TrackState {
    let ey = -focal_half_heights * elevation_deg.to_radians().tan();
    TrackState {
        hub_bearing_deg: [0.0, elevation_deg],
        ..track(0.0, ey, Some(30.0), Some(0.0))
    }
}

/// A vehicle pitched `pitch_deg` (nose up positive) with a valid attitude.
fn pitched_vehicle(pitch_deg: f64) -> VehicleState {
    VehicleState {
        attitude_valid: true,
        pitch_rad: pitch_deg.to_radians(),
        ..vehicle(true)
    }
}

/// Flying forward nose-down, the body-fixed camera sees a level hub above the image centre;
/// through a narrow lens that is past `box_y` (4° of pitch: 0.20 of the half-height against
/// 0.18), and T1 would stop the approach to climb. With the camera's focal length the vertical
/// error is taken as a level body sees it: the approach goes on, and nothing climbs. A hub that
/// is really above stays T1's, pitched or not, and without the focal length the image decides.
#[test]
fn t1_takes_the_vertical_error_as_a_level_body_sees_it() {
    let k = NARROW_FOCAL_HALF_HEIGHTS;
    let levelled = ApproachConfig::default().with_camera_focal(k);
    // Nose down 4°: the level hub appears 4° up.
    let mut rig = Rig::with(levelled.clone());
    rig.vehicle = Some(pitched_vehicle(-4.0));
    let out = rig.run(Some(track_seen_at(4.0, k)), 1.0);
    assert_eq!(out.task, ApproachTask::Approach, "{out:?}");
    assert_eq!(out.vz_m_s, 0.0, "{out:?}");
    assert!(out.vx_m_s > 0.0, "{out:?}");

    // Without the focal length the same views trip T1, which climbs.
    let mut rig = Rig::new();
    rig.vehicle = Some(pitched_vehicle(-4.0));
    let out = rig.run(Some(track_seen_at(4.0, k)), 1.0);
    assert_eq!(out.task, ApproachTask::CentreHub, "{out:?}");
    assert!(out.vz_m_s < 0.0, "{out:?}");

    // A hub 6° above a level body is above whatever the pitch: seen at 10° nose-down, at 2°
    // nose-up (its row alone would be inside the box).
    for (pitch, seen) in [(-4.0, 10.0), (4.0, 2.0)] {
        let mut rig = Rig::with(levelled.clone());
        rig.vehicle = Some(pitched_vehicle(pitch));
        let out = rig.run(Some(track_seen_at(seen, k)), 1.0);
        assert_eq!(out.task, ApproachTask::CentreHub, "{pitch} {seen}: {out:?}");
        assert!(out.vz_m_s < 0.0, "{pitch} {seen}: {out:?}");
    }

    // No attitude: the image decides.
    let mut rig = Rig::with(levelled);
    rig.vehicle = Some(vehicle(true));
    let out = rig.run(Some(track_seen_at(4.0, k)), 1.0);
    assert_eq!(out.task, ApproachTask::CentreHub, "{out:?}");
}

/// A focal length that is no number or not positive is "not known"; the config stays valid.
#[test]
fn any_camera_focal_leaves_a_valid_config() {
    for (k, kept) in [
        (f64::NAN, 0.0),
        (-1.0, 0.0),
        (0.0, 0.0),
        (NARROW_FOCAL_HALF_HEIGHTS, NARROW_FOCAL_HALF_HEIGHTS),
        (f64::INFINITY, 1e4),
    ] {
        let c = ApproachConfig::default().with_camera_focal(k);
        assert!(c.validate().is_ok(), "{k}: {:?}", c.validate());
        assert_eq!(c.focal_half_heights, kept, "{k}");
    }
}

#[test]
fn t2_positive_yaw_moves_left_and_turns_right() {
    let mut rig = Rig::new();
    let out = rig.run(Some(track(0.0, 0.0, Some(30.0), Some(10.0))), 2.0);
    assert_eq!(out.task, ApproachTask::ReduceYaw);
    assert!(out.vy_m_s < -0.3, "{out:?}");
    // Moving left with the hub ahead: the feed-forward turns right to keep it centred.
    assert!(out.yaw_rate_rad_s > 0.0, "{out:?}");
    assert_eq!(out.vx_m_s, 0.0, "no approach during T2");

    let mut rig = Rig::new();
    let out = rig.run(Some(track(0.0, 0.0, Some(30.0), Some(-10.0))), 2.0);
    assert_eq!(out.task, ApproachTask::ReduceYaw);
    assert!(out.vy_m_s > 0.3 && out.yaw_rate_rad_s < 0.0, "{out:?}");

    // Without a distance the nominal one scales the lateral offset: same sign, still no vx.
    let mut rig = Rig::new();
    let out = rig.run(Some(track(0.0, 0.0, None, Some(10.0))), 2.0);
    assert_eq!(out.task, ApproachTask::ReduceYaw);
    assert!(out.vy_m_s < 0.0 && out.vx_m_s == 0.0, "{out:?}");
}

#[test]
fn t1_preempts_t2_preempts_t3() {
    let mut rig = Rig::new();
    // Everything wrong: T1.
    let out = rig.run(Some(track(0.3, 0.2, Some(30.0), Some(10.0))), 1.0);
    assert_eq!(out.task, ApproachTask::CentreHub);
    assert_eq!((out.vx_m_s, out.vy_m_s), (0.0, 0.0));
    // Hub centred, yaw still large: T2.
    let out = rig.step(Some(track(0.0, 0.0, Some(30.0), Some(10.0))));
    assert_eq!(out.task, ApproachTask::ReduceYaw);
    assert_eq!(
        out.transition,
        Some(Transition {
            from: ApproachTask::CentreHub,
            to: ApproachTask::ReduceYaw,
            reason: out.reason.clone(),
            heading_doubt: None,
        })
    );
    let out = rig.run(Some(track(0.0, 0.0, Some(30.0), Some(10.0))), 1.0);
    assert_eq!(out.vx_m_s, 0.0);
    // Yaw small: T3, moving forward up to the limit.
    let out = rig.run(Some(track(0.0, 0.0, Some(30.0), Some(1.0))), 4.0);
    assert_eq!(out.task, ApproachTask::Approach);
    assert!((out.vx_m_s - 1.5).abs() < EPS, "{out:?}");
    assert!(out.reason.starts_with("T3: 30.0 m"), "{}", out.reason);
    assert_eq!(
        rig.tasks_since(0),
        vec![
            ApproachTask::CentreHub,
            ApproachTask::ReduceYaw,
            ApproachTask::Approach
        ]
    );
    let transitions: Vec<_> = rig
        .log
        .iter()
        .filter_map(|o| o.transition.as_ref().map(|t| (t.from, t.to)))
        .collect();
    assert_eq!(
        transitions,
        vec![
            (ApproachTask::Hold, ApproachTask::CentreHub),
            (ApproachTask::CentreHub, ApproachTask::ReduceYaw),
            (ApproachTask::ReduceYaw, ApproachTask::Approach)
        ]
    );
}

#[test]
fn hub_leaving_the_box_during_t3_reverts_to_t1_then_back() {
    let c = ApproachConfig::default();
    let mut rig = Rig::new();
    rig.run(Some(track(0.0, 0.0, Some(30.0), Some(0.0))), 4.0);
    assert_eq!(rig.ap.task(), ApproachTask::Approach);
    assert!((rig.log.last().unwrap().vx_m_s - 1.5).abs() < EPS);

    // The hub jumps 0.2 right: T1 at once, the forward speed ramps down at the braking limit.
    let mark = rig.log.len();
    let first = rig.step(Some(track(0.2, 0.0, Some(30.0), Some(0.0))));
    assert_eq!(first.task, ApproachTask::CentreHub);
    assert_eq!(
        first.transition.as_ref().map(|t| t.from),
        Some(ApproachTask::Approach)
    );
    let out = rig.run(
        Some(track(0.2, 0.0, Some(30.0), Some(0.0))),
        1.5 / c.brake_x_m_s2 + 0.2,
    );
    assert_eq!(out.task, ApproachTask::CentreHub);
    assert!(out.yaw_rate_rad_s > 0.0);
    assert_eq!(out.vx_m_s, 0.0, "T3 stopped");
    let vx: Vec<f64> = rig.log[mark - 1..].iter().map(|o| o.vx_m_s).collect();
    let dv = c.brake_x_m_s2 * FRAME_NS as f64 * 1e-9;
    for w in vx.windows(2) {
        assert!(
            w[1] <= w[0] + EPS && w[0] - w[1] <= dv + EPS,
            "ramp, not a jump: {w:?}"
        );
    }
    assert!(vx[1] > 1.0, "still moving just after the switch: ramp down");

    // Between the boxes: still T1 (hysteresis).
    let out = rig.run(Some(track(0.07, 0.0, Some(30.0), Some(0.0))), 1.0);
    assert_eq!(out.task, ApproachTask::CentreHub);
    // Inside the inner box: back to T3 and forward again.
    let out = rig.step(Some(track(0.03, 0.0, Some(30.0), Some(0.0))));
    assert_eq!(out.task, ApproachTask::Approach);
    assert_eq!(
        out.transition.as_ref().map(|t| t.from),
        Some(ApproachTask::CentreHub)
    );
    let out = rig.run(Some(track(0.03, 0.0, Some(30.0), Some(0.0))), 3.0);
    assert!(out.vx_m_s > 1.0);
    // And the hub between the boxes during T3 does not interrupt it.
    let out = rig.run(Some(track(-0.09, 0.09, Some(30.0), Some(0.0))), 1.0);
    assert_eq!(out.task, ApproachTask::Approach);
    assert!(
        rig.log[mark..]
            .iter()
            .filter(|o| o.transition.is_some())
            .count()
            == 2,
        "no chatter"
    );
}

#[test]
fn yaw_hysteresis_between_t2_and_t3() {
    let mut rig = Rig::with(ApproachConfig {
        yaw_filter_s: 0.0,
        ..Default::default()
    });
    assert_eq!(
        rig.run(Some(track(0.0, 0.0, Some(30.0), Some(4.0))), 1.0)
            .task,
        ApproachTask::ReduceYaw
    );
    assert_eq!(
        rig.run(Some(track(0.0, 0.0, Some(30.0), Some(2.5))), 1.0)
            .task,
        ApproachTask::Approach
    );
    assert_eq!(
        rig.run(Some(track(0.0, 0.0, Some(30.0), Some(4.5))), 1.0)
            .task,
        ApproachTask::Approach
    );
    let out = rig.step(Some(track(0.0, 0.0, Some(30.0), Some(-5.5))));
    assert_eq!(out.task, ApproachTask::ReduceYaw);
    let out = rig.run(Some(track(0.0, 0.0, Some(30.0), Some(-5.5))), 1.0);
    assert_eq!(out.task, ApproachTask::ReduceYaw);
    assert!(
        out.vy_m_s > 0.0 && out.vx_m_s < 1.0,
        "sideways, the approach ramping down: {out:?}"
    );
}

// ---------------------------------------------------------------- safety: forward motion

#[test]
fn no_forward_motion_without_a_valid_distance() {
    let mut rig = Rig::new();
    for _ in 0..60 {
        let out = rig.step(Some(track(0.0, 0.0, None, Some(0.0))));
        assert_eq!(out.task, ApproachTask::Approach);
        assert!(out.vx_m_s <= 0.0);
        assert!(out.reason.contains("no valid distance"), "{}", out.reason);
    }
    // Moving forward, then the distance goes invalid: forward speed is cut at once.
    rig.run(Some(track(0.0, 0.0, Some(20.0), Some(0.0))), 3.0);
    assert!(rig.log.last().unwrap().vx_m_s > 1.0);
    let out = rig.step(Some(track(0.0, 0.0, None, Some(0.0))));
    assert_eq!(out.vx_m_s, 0.0);
    // A "valid" distance that is zero, negative or flagged invalid with a value is not used.
    let mut t = track(0.0, 0.0, Some(20.0), Some(0.0));
    t.distance_valid = false;
    assert_eq!(rig.run(Some(t), 1.0).vx_m_s, 0.0);
    assert_eq!(
        rig.run(Some(track(0.0, 0.0, Some(0.0), Some(0.0))), 1.0)
            .vx_m_s,
        0.0
    );
    assert_eq!(
        rig.run(Some(track(0.0, 0.0, Some(-3.0), Some(0.0))), 1.0)
            .vx_m_s,
        0.0
    );
}

#[test]
fn no_yaw_for_long_probes_sideways_within_the_span_then_t2_takes_over() {
    let c = ApproachConfig::default();
    let mut rig = Rig::new();
    // Centred, distance known, yaw never valid: hold at first ...
    let out = rig.run(
        Some(track(0.0, 0.0, Some(30.0), None)),
        c.yaw_probe_after_s - 1.0,
    );
    assert_eq!(out.task, ApproachTask::ReduceYaw);
    assert_eq!(out.vy_m_s, 0.0);
    assert!(out.reason.contains("holding"), "{}", out.reason);
    // ... then sweep sideways, never forward, never beyond the span (plus the braking distance).
    let from = rig.log.len();
    rig.run(Some(track(0.0, 0.0, Some(30.0), None)), 60.0);
    let dt = FRAME_NS as f64 / 1e9;
    let mut offset = 0.0f64;
    let (mut min, mut max) = (0.0f64, 0.0f64);
    for o in &rig.log[from..] {
        assert_eq!(o.task, ApproachTask::ReduceYaw);
        assert!(o.vx_m_s <= 0.0, "{o:?}");
        assert!(o.vy_m_s.abs() <= c.yaw_probe_speed_m_s + EPS);
        offset += o.vy_m_s * dt;
        (min, max) = (min.min(offset), max.max(offset));
    }
    let brake = c.yaw_probe_speed_m_s.powi(2) / (2.0 * c.accel_xy_m_s2) + 0.1;
    let span = 30.0 * c.yaw_probe_span_deg.to_radians().tan();
    assert!(max > span - 0.5 && max < span + brake, "{min} .. {max}");
    assert!(min < -span + 0.5 && min > -span - brake, "{min} .. {max}");
    assert!(
        rig.log.last().unwrap().reason.contains("probing"),
        "{}",
        rig.log.last().unwrap().reason
    );
    // A valid yaw ends the probe: T2 proper (positive yaw moves left).
    let out = rig.run(Some(track(0.0, 0.0, Some(30.0), Some(15.0))), 3.0);
    assert!(
        out.vy_m_s < 0.0 && out.reason.starts_with("T2: yaw"),
        "{out:?}"
    );
    // Disabled: holds however long.
    let mut rig = Rig::with(ApproachConfig {
        yaw_probe_span_deg: 0.0,
        ..c
    });
    assert_eq!(
        rig.run(Some(track(0.0, 0.0, Some(30.0), None)), 30.0)
            .vy_m_s,
        0.0
    );
}

#[test]
fn no_distance_for_long_probes_sideways_never_forward() {
    let c = ApproachConfig::default();
    let mut rig = Rig::new();
    // Centred, yaw known and small, distance never valid: T3 cannot move forward ...
    let out = rig.run(
        Some(track(0.0, 0.0, None, Some(1.0))),
        c.yaw_probe_after_s - 1.0,
    );
    assert_eq!(out.task, ApproachTask::Approach);
    assert!(out.vy_m_s.abs() < 0.1 && out.vx_m_s <= 0.0, "{out:?}");
    // ... so after a while it looks from a few metres aside, still never forward.
    let from = rig.log.len();
    rig.run(Some(track(0.0, 0.0, None, Some(1.0))), 20.0);
    assert!(rig.log[from..].iter().all(|o| o.vx_m_s <= 0.0));
    assert!(
        rig.log[from..]
            .iter()
            .any(|o| o.vy_m_s.abs() > 0.9 * c.yaw_probe_speed_m_s),
        "no sideways sweep"
    );
    let last = rig.log.last().unwrap();
    assert!(
        last.reason.starts_with("T3: no valid distance") && last.reason.contains("probing"),
        "{}",
        last.reason
    );
    // A distance ends the probe: forward again.
    let out = rig.run(Some(track(0.0, 0.0, Some(20.0), Some(1.0))), 3.0);
    assert!(
        out.vx_m_s > 0.0 && out.reason.starts_with("T3: 20"),
        "{out:?}"
    );
}

#[test]
fn no_forward_motion_with_a_stale_track() {
    let good = track(0.0, 0.0, Some(20.0), Some(0.0));
    let mut rig = Rig::new();
    rig.run(Some(good), 3.0);
    assert!(rig.log.last().unwrap().vx_m_s > 1.0);

    // Tracking, but the last detection is older than max_track_age_s: Hold.
    let out = rig.step(Some(TrackState {
        time_since_detection_s: 1.1,
        ..good
    }));
    assert_eq!(out.task, ApproachTask::Hold);
    assert!(out.reason.contains("stale"), "{}", out.reason);

    // Coasting within the age limit keeps going; beyond it holds.
    let mut rig = Rig::new();
    rig.run(Some(good), 3.0);
    let coast = |s: f64| TrackState {
        mode: TrackMode::Coasting,
        time_since_detection_s: s,
        ..good
    };
    let out = rig.step(Some(coast(0.3)));
    assert_eq!(out.task, ApproachTask::Approach);
    assert!(out.vx_m_s > 1.0);
    let out = rig.step(Some(coast(1.05)));
    assert_eq!((out.task, out.vx_m_s), (ApproachTask::Hold, 0.0));

    // No new track state for 1.1 s (the same one again): stale by its own age.
    let mut rig = Rig::new();
    rig.run(Some(good), 3.0);
    let mut old = good;
    old.stamps.capture_ns = rig.now - FRAME_NS;
    for i in 0..18 {
        let out = rig.ap.step(&ApproachInput {
            now_ns: rig.now,
            track: Some(&old),
            vehicle: None,
        });
        check_output(&out, rig.ap.config());
        if i >= 16 {
            assert_eq!((out.task, out.vx_m_s), (ApproachTask::Hold, 0.0), "{i}");
        }
        rig.now += FRAME_NS;
    }
}

#[test]
fn too_close_backs_away_in_any_task() {
    let mut rig = Rig::new();
    // Hub off-centre (T1) but only 3.5 m away: back off while centring.
    let out = rig.run(Some(track(0.3, 0.0, Some(3.5), Some(10.0))), 2.0);
    assert_eq!(out.task, ApproachTask::CentreHub);
    assert!(out.vx_m_s < -0.3, "{out:?}");
    // Without a valid distance nothing is known: no motion along x at all.
    let out = rig.run(Some(track(0.3, 0.0, None, Some(10.0))), 2.0);
    assert!(out.vx_m_s <= 0.0);
}

#[test]
fn backing_away_stops_when_the_distance_does_not_follow() {
    let c = ApproachConfig::default();
    // A distance stuck at 3 m (the vehicle backs away, the reading does not grow).
    let mut rig = Rig::new();
    let stuck = Some(track(0.0, 0.0, Some(3.0), Some(0.0)));
    let out = rig.run(stuck, 2.0);
    assert!(out.vx_m_s < -0.3, "backs away at first: {out:?}");
    rig.run(stuck, 30.0);
    let backed: f64 = rig
        .log
        .iter()
        .map(|o| -o.vx_m_s.min(0.0) * FRAME_NS as f64 * 1e-9)
        .sum();
    assert!(
        (backed - c.max_backoff_m).abs() < 0.5,
        "backed off {backed:.2} m, allowance {} m",
        c.max_backoff_m
    );
    let out = rig.run(stuck, 1.0);
    assert_eq!(out.vx_m_s, 0.0, "{out:?}");
    assert!(out.reason.contains("no further back"), "{}", out.reason);
    // A reading at the target restores the allowance: the next too-close reading backs away.
    rig.run(Some(track(0.0, 0.0, Some(5.0), Some(0.0))), 6.0);
    let out = rig.run(stuck, 2.0);
    assert!(out.vx_m_s < -0.3, "{out:?}");

    // A distance that grows as the vehicle backs away: back to the target, never stopped early.
    let mut rig = Rig::new();
    let mut d = 2.0;
    for _ in 0..(20 * 15) {
        let out = rig.step(Some(track(0.0, 0.0, Some(d), Some(0.0))));
        d -= out.vx_m_s * FRAME_NS as f64 * 1e-9;
    }
    assert!(
        (d - c.target_distance_m).abs() < c.distance_tolerance_outer_m,
        "ended at {d:.2} m"
    );
}

#[test]
fn forward_speed_slows_down_near_the_target() {
    let c = ApproachConfig::default();
    let mut last = f64::INFINITY;
    for d in [30.0, 10.0, 8.0, 6.0, 5.5, 5.0, 4.0] {
        let mut rig = Rig::with(ApproachConfig {
            distance_filter_s: 0.0,
            ..c.clone()
        });
        let out = rig.run(Some(track(0.0, 0.0, Some(d), Some(0.0))), 4.0);
        assert!(out.vx_m_s <= c.slowdown_gain_per_s * (d - c.min_distance_m) + EPS);
        assert!(out.vx_m_s <= last, "{d}: {out:?}");
        last = out.vx_m_s;
    }
    assert!(last < 0.0, "inside the target: backing away");
}

// ---------------------------------------------------------------- loss, search, recovery

#[test]
fn lost_holds_then_searches_bounded_then_holds() {
    let c = ApproachConfig::default();
    let mut rig = Rig::new();
    // Hub last seen slightly left of centre.
    rig.run(Some(track(-0.04, 0.0, Some(20.0), Some(0.0))), 3.0);
    assert!(rig.log.last().unwrap().vx_m_s > 1.0);
    let lost = track_mode(TrackMode::Lost, 1.0);
    let out = rig.step(Some(lost));
    assert_eq!(out.task, ApproachTask::Hold);
    assert!(out.reason.starts_with("hold: track lost"), "{}", out.reason);
    let out = rig.run(Some(lost), c.search_after_s - 0.2);
    assert_eq!(out.task, ApproachTask::Hold);
    let mark = rig.log.len();
    let out = rig.run(Some(lost), 0.5);
    assert_eq!(out.task, ApproachTask::Search);
    assert!(
        out.yaw_rate_rad_s < 0.0,
        "towards the last seen side (left)"
    );
    assert!(
        out.reason.starts_with("search left 10 deg/s"),
        "{}",
        out.reason
    );
    // Search for a long time: it turns 360 degrees and then holds.
    rig.run(Some(lost), 60.0);
    let dt = FRAME_NS as f64 * 1e-9;
    let turned: f64 = rig.log[mark..]
        .iter()
        .map(|o| o.yaw_rate_rad_s.abs().to_degrees() * dt)
        .sum();
    assert!(
        (turned - c.search_max_turn_deg).abs() < 1.0,
        "turned {turned}"
    );
    for o in &rig.log[mark..] {
        assert!(o.yaw_rate_rad_s.abs() <= c.search_yaw_rate_deg_s.to_radians() + EPS);
        assert_eq!((o.vx_m_s, o.vy_m_s, o.vz_m_s), (0.0, 0.0, 0.0));
    }
    let out = rig.log.last().unwrap();
    assert_eq!(out.task, ApproachTask::Hold);
    assert!(out.reason.contains("searched 360"), "{}", out.reason);
    assert_eq!(
        rig.tasks_since(mark),
        vec![ApproachTask::Hold, ApproachTask::Search, ApproachTask::Hold]
    );

    // No track at all and never seen: hold, then search to the right.
    let mut rig = Rig::new();
    let out = rig.step(None);
    assert_eq!(out.task, ApproachTask::Hold);
    assert!(out.reason.contains("no track yet"), "{}", out.reason);
    let out = rig.run(None, c.search_after_s + 1.0);
    assert_eq!(out.task, ApproachTask::Search);
    assert!(out.yaw_rate_rad_s > 0.0);
}

#[test]
fn a_tentative_hub_off_centre_sets_the_search_side() {
    let c = ApproachConfig::default();
    // Never confirmed, glimpsed at the left edge: the search turns left.
    let mut rig = Rig::new();
    let glimpsed = TrackState {
        mode: TrackMode::Acquiring,
        search_requested: true,
        ..track(-0.9, -0.8, None, None)
    };
    let out = rig.run(Some(glimpsed), 0.5);
    assert_eq!(out.task, ApproachTask::Search);
    assert!(out.yaw_rate_rad_s < 0.0, "{}", out.reason);
    assert!(out.reason.starts_with("search left"), "{}", out.reason);
    // At the centre (no tentative track reports the principal point): the default side.
    let mut rig = Rig::new();
    let centred = TrackState {
        mode: TrackMode::Acquiring,
        search_requested: true,
        ..track(-0.5 * c.search_side_min_offset, 0.0, None, None)
    };
    let out = rig.run(Some(centred), 0.5);
    assert!(out.yaw_rate_rad_s > 0.0, "{}", out.reason);
}

#[test]
fn search_requested_searches_at_once() {
    let mut rig = Rig::new();
    rig.run(Some(track(0.02, 0.0, Some(20.0), Some(0.0))), 1.0);
    let t = TrackState {
        search_requested: true,
        ..track_mode(TrackMode::Lost, 6.0)
    };
    let out = rig.run(Some(t), 0.5);
    assert_eq!(out.task, ApproachTask::Search);
    assert!(out.yaw_rate_rad_s > 0.0);
    // A zero search budget never searches.
    let mut rig = Rig::with(ApproachConfig {
        search_max_turn_deg: 0.0,
        ..Default::default()
    });
    assert_eq!(rig.run(Some(t), 10.0).task, ApproachTask::Hold);
}

#[test]
fn returning_track_resumes_through_rate_limits_with_fresh_filters() {
    let c = ApproachConfig::default();
    let mut rig = Rig::new();
    rig.run(Some(track(0.0, 0.0, Some(30.0), Some(0.0))), 3.0);
    rig.run(Some(track_mode(TrackMode::Lost, 2.0)), 8.0);
    assert_eq!(rig.ap.task(), ApproachTask::Search);
    assert!(rig.ap.dist_f.is_none(), "filters reset on loss");
    let mark = rig.log.len();
    // The turbine is found again, closer than before.
    let out = rig.step(Some(track(0.0, 0.0, Some(20.0), Some(0.0))));
    assert_ne!(out.task, ApproachTask::Search);
    assert_eq!(
        rig.ap.dist_f,
        Some(20.0),
        "distance filter restarts at the new value"
    );
    let out = rig.run(Some(track(0.0, 0.0, Some(20.0), Some(0.0))), 3.0);
    assert_eq!(out.task, ApproachTask::Approach);
    assert!(out.reason.starts_with("T3: 20.0 m"), "{}", out.reason);
    let dt = FRAME_NS as f64 * 1e-9;
    for w in rig.log[mark - 1..].windows(2) {
        let slowing = w[0].vx_m_s > 0.0 && w[1].vx_m_s < w[0].vx_m_s && w[1].vx_m_s >= -EPS;
        let ax = if slowing {
            c.brake_x_m_s2
        } else {
            c.accel_xy_m_s2
        };
        assert!((w[1].vx_m_s - w[0].vx_m_s).abs() <= ax * dt + EPS);
        assert!(
            (w[1].yaw_rate_rad_s - w[0].yaw_rate_rad_s).abs()
                <= c.yaw_accel_deg_s2.to_radians() * dt + EPS
        );
    }
    // The search budget is renewed by the re-acquisition.
    rig.run(Some(track_mode(TrackMode::Lost, 2.0)), 6.0);
    assert_eq!(rig.ap.task(), ApproachTask::Search);
}

#[test]
fn filters_smooth_yaw_and_distance() {
    let mut rig = Rig::new();
    rig.run(Some(track(0.0, 0.0, Some(30.0), Some(0.0))), 2.0);
    rig.step(Some(track(0.0, 0.0, Some(20.0), Some(10.0))));
    let (d, y) = (rig.ap.dist_f.unwrap(), rig.ap.yaw_f.unwrap());
    let a = 1.0 - (-(FRAME_NS as f64 * 1e-9) / 0.5f64).exp();
    assert!((d - (30.0 - 10.0 * a)).abs() < 1e-9, "{d}");
    assert!((y - 10.0 * a).abs() < 1e-9, "{y}");
    // The same state again is not filtered twice.
    let mut t = track(0.0, 0.0, Some(20.0), Some(10.0));
    t.stamps.capture_ns = rig.now - FRAME_NS;
    rig.ap.step(&ApproachInput {
        now_ns: rig.now,
        track: Some(&t),
        vehicle: None,
    });
    assert_eq!(rig.ap.dist_f.unwrap(), d);
    // Converges.
    rig.run(Some(track(0.0, 0.0, Some(20.0), Some(10.0))), 5.0);
    assert!((rig.ap.dist_f.unwrap() - 20.0).abs() < 0.01);
}

/// The turbine-heading estimate carries the farther measurements; close in, a steady run of
/// yaws far from it (a blade pointing down taken for the tower) is dropped, not clipped
/// (`turbine_heading_close_m`).
#[test]
fn close_in_a_run_of_wrong_yaws_leaves_the_turbine_heading() {
    let run = |close_m: f64| {
        let c = ApproachConfig {
            turbine_heading_close_m: close_m,
            ..ApproachConfig::default()
        };
        let mut rig = Rig::with(c);
        rig.vehicle = Some(attitude_vehicle());
        rig.run(Some(track(0.0, 0.0, Some(20.0), Some(3.0))), 15.0);
        let far = rig.ap.heading_yaw(
            &track(0.0, 0.0, Some(20.0), Some(3.0)),
            rig.vehicle.as_ref(),
            false,
        );
        rig.run(Some(track(0.0, 0.0, Some(6.0), Some(28.0))), 10.0);
        let t = track(0.0, 0.0, Some(6.0), Some(28.0));
        (
            far.unwrap(),
            rig.ap.heading_yaw(&t, rig.vehicle.as_ref(), false).unwrap(),
        )
    };
    let (far, kept) = run(10.0);
    assert!(
        (far - 3.0).abs() < 0.1 && (kept - 3.0).abs() < 0.1,
        "dropped: {far} then {kept}"
    );
    // Clipped, the same run owns the estimate.
    let (_, clipped) = run(0.0);
    assert!(clipped > 20.0, "clipped: {clipped}");
}

/// Close in, an established turbine-heading estimate holds (`turbine_heading_hold_m`): a run
/// of yaws within the clip (which `turbine_heading_close_m` lets through) no longer moves it.
#[test]
fn closer_than_the_hold_distance_the_turbine_heading_holds() {
    let run = |hold_m: f64| {
        let c = ApproachConfig {
            turbine_heading_hold_m: hold_m,
            ..ApproachConfig::default()
        };
        let mut rig = Rig::with(c);
        rig.vehicle = Some(attitude_vehicle());
        rig.run(Some(track(0.0, 0.0, Some(20.0), Some(2.0))), 15.0);
        rig.run(Some(track(0.0, 0.0, Some(7.0), Some(9.0))), 10.0);
        rig.ap
            .heading_yaw(
                &track(0.0, 0.0, Some(7.0), Some(9.0)),
                rig.vehicle.as_ref(),
                false,
            )
            .unwrap()
    };
    let held = run(10.0);
    assert!((held - 2.0).abs() < 0.1, "held: {held}");
    let followed = run(0.0);
    assert!(followed > 7.0, "without the hold: {followed}");
}

/// The learned yaw network's readings build a second turbine heading, weighed in by
/// `net_heading_weight` once both estimates hold enough samples; frames without a network
/// reading leave it alone, and at weight 0 the geometric estimate flies alone.
#[test]
fn the_networks_turbine_heading_is_weighed_in() {
    let with_net = |yaw: f64, net: Option<f64>| track_with_net(12.0, yaw, net);
    let run = |weight: f64| {
        let c = ApproachConfig {
            net_heading_weight: weight,
            ..ApproachConfig::default()
        };
        let mut rig = Rig::with(c);
        rig.vehicle = Some(attitude_vehicle());
        // The tower says 1°, the network −7°.
        rig.run(Some(with_net(1.0, Some(-7.0))), 5.0);
        let both = rig
            .ap
            .heading_yaw(&with_net(1.0, None), rig.vehicle.as_ref(), false)
            .unwrap();
        // Frames without a network reading (closer than its trusted range) keep its heading.
        rig.run(Some(with_net(1.0, None)), 5.0);
        let kept = rig
            .ap
            .heading_yaw(&with_net(1.0, None), rig.vehicle.as_ref(), false)
            .unwrap();
        (both, kept)
    };
    let (both, kept) = run(0.5);
    assert!(
        (both + 3.0).abs() < 0.1 && (kept + 3.0).abs() < 0.1,
        "halfway: {both}, then {kept}"
    );
    let (alone, _) = run(0.0);
    assert!((alone - 1.0).abs() < 0.1, "geometric alone: {alone}");
    let (net, _) = run(1.0);
    assert!((net + 7.0).abs() < 0.1, "network alone: {net}");
    // Without enough network samples the geometric estimate flies alone.
    let c = ApproachConfig {
        net_heading_weight: 0.5,
        ..ApproachConfig::default()
    };
    let mut rig = Rig::with(c.clone());
    rig.vehicle = Some(attitude_vehicle());
    rig.run(Some(with_net(1.0, None)), 5.0);
    for _ in 1..c.turbine_heading_min_samples {
        rig.step(Some(with_net(1.0, Some(-7.0))));
    }
    let few = rig
        .ap
        .heading_yaw(&with_net(1.0, None), rig.vehicle.as_ref(), false)
        .unwrap();
    assert!((few - 1.0).abs() < 0.1, "too few network samples: {few}");
}

/// Entering Done with the geometric and the network's turbine headings further apart than
/// `yaw_tolerance_outer_deg`, the transition says so with both relative yaws (the control stage
/// warns the crew); two estimates that agree, or one alone, raise no doubt.
#[test]
fn done_reports_two_turbine_headings_that_disagree() {
    let at = |yaw: f64, net: Option<f64>| track_with_net(5.1, yaw, net);
    let entering_done = |t: TrackState| {
        let c = ApproachConfig::default();
        let mut rig = Rig::with(c.clone());
        rig.vehicle = Some(attitude_vehicle());
        rig.run(Some(t), c.done_hold_s + 3.0);
        assert_eq!(rig.ap.task(), ApproachTask::Done, "{:?}", rig.log.last());
        rig.log
            .iter()
            .filter_map(|o| o.transition.as_ref())
            .rfind(|tr| tr.to == ApproachTask::Done)
            .unwrap()
            .heading_doubt
    };
    // The tower says +5°, the network −3°: flown on 0.3 × 5 + 0.7 × (−3) = −0.6°, inside the
    // tolerance, but 8° apart.
    let doubt = entering_done(at(5.0, Some(-3.0))).expect("8° apart is a doubt");
    assert!(
        (doubt.geometric_deg - 5.0).abs() < 0.1 && (doubt.network_deg + 3.0).abs() < 0.1,
        "{doubt:?}"
    );
    assert_eq!(entering_done(at(1.0, Some(-1.0))), None, "2° apart");
    assert_eq!(entering_done(at(1.0, None)), None, "no network heading");
}

/// A vehicle at `north` m on the local frame's north axis, facing north, with position and
/// attitude.
fn vehicle_at(north: f64) -> VehicleState {
    VehicleState {
        attitude_valid: true,
        position_valid: true,
        position_ned_m: [north, 0.0, 0.0],
        ..vehicle(true)
    }
}

impl Rig {
    /// One step per 0.1 m along north from `from` to `to` (either way), the track reading
    /// `reading(north)`, centred and level.
    fn fly_north(&mut self, from: f64, to: f64, reading: impl Fn(f64) -> f64) {
        let steps = ((to - from).abs() / 0.1).round() as u32;
        let dir = (to - from).signum();
        for i in 0..=steps {
            let north = from + dir * f64::from(i) * 0.1;
            self.vehicle = Some(vehicle_at(north));
            self.step(Some(track(0.0, 0.0, Some(reading(north)), Some(0.0))));
        }
    }
}

/// Lost at 5 m, a track re-acquired on something that reads 22 m does not fly the vehicle
/// forward: the hub remembered from the last confirmed track bounds its distance until the
/// two agree or `reacquire_check_s` passes (`fly` seed 176 flew into the rotor that way).
#[test]
fn a_reacquired_track_that_reads_too_far_is_bounded_by_the_remembered_hub() {
    let c = ApproachConfig::default();
    let mut rig = Rig::new();
    // Closing in from 8 m to 3.5 m, the readings agreeing with the odometry.
    rig.fly_north(0.0, 4.5, |north| 8.0 - north);
    rig.run(Some(track(0.0, 0.0, Some(3.5), Some(0.0))), 3.0);
    rig.run(Some(track_mode(TrackMode::Lost, 2.0)), 1.0);
    assert_eq!(rig.ap.task(), ApproachTask::Hold);
    // Re-acquired, reading 22 m, while the vehicle is still 3.5 m from the remembered hub.
    let far = track(0.0, 0.0, Some(22.0), Some(0.0));
    let mark = rig.log.len();
    rig.run(Some(far), 3.0);
    assert!(
        rig.log[mark..].iter().all(|o| o.vx_m_s <= EPS),
        "no forward motion toward the remembered hub"
    );
    let bounded = rig.log[mark..]
        .iter()
        .filter(|o| o.reason.starts_with("T3: 3.5 m by odometry"))
        .count();
    assert!(bounded > 10, "{:?}", rig.log.last());
    // Past the check time too: the odometry still contradicts the track.
    let out = rig.run(Some(far), c.reacquire_check_s);
    assert!(out.vx_m_s <= EPS, "{out:?}");

    // Without the odometry check, the remembered hub alone bounds it until the check time.
    let unchecked = ApproachConfig {
        shrink_check_m: 0.0,
        ..c.clone()
    };
    let mut rig = Rig::with(unchecked);
    rig.vehicle = Some(vehicle_at(0.0));
    rig.run(Some(track(0.0, 0.0, Some(3.5), Some(0.0))), 3.0);
    rig.run(Some(track_mode(TrackMode::Lost, 2.0)), 1.0);
    let mark = rig.log.len();
    rig.run(Some(far), 3.0);
    assert!(rig.log[mark..].iter().all(|o| o.vx_m_s <= EPS));
    let bounded = rig.log[mark..]
        .iter()
        .filter(|o| {
            o.reason
                .contains("3.5 m to the remembered hub (track 22.0 m)")
        })
        .count();
    assert!(bounded > 10, "{:?}", rig.log.last());
    let out = rig.run(Some(far), c.reacquire_check_s);
    assert!(
        out.vx_m_s > 0.1 && out.reason.starts_with("T3: 22.0 m"),
        "{out:?}"
    );

    // A re-acquired track that agrees with the remembered hub is not bounded.
    let mut rig = Rig::new();
    rig.vehicle = Some(vehicle_at(0.0));
    rig.run(Some(track(0.0, 0.0, Some(20.0), Some(0.0))), 3.0);
    rig.run(Some(track_mode(TrackMode::Lost, 2.0)), 1.0);
    rig.vehicle = Some(vehicle_at(2.0));
    let out = rig.run(Some(track(0.0, 0.0, Some(18.5), Some(0.0))), 3.0);
    assert!(
        out.vx_m_s > 0.1 && out.reason.starts_with("T3: 18.5 m"),
        "{out:?}"
    );

    // Without the memory (nor the odometry check) the first re-acquired track flies forward
    // at once.
    let mut rig = Rig::with(ApproachConfig {
        reacquire_memory_s: 0.0,
        shrink_check_m: 0.0,
        ..c
    });
    rig.vehicle = Some(vehicle_at(0.0));
    rig.run(Some(track(0.0, 0.0, Some(3.5), Some(0.0))), 3.0);
    rig.run(Some(track_mode(TrackMode::Lost, 2.0)), 1.0);
    let out = rig.run(Some(far), 3.0);
    assert!(out.vx_m_s > 0.1, "{out:?}");
}

// ---------------------------------------------------------------- abort

#[test]
fn link_loss_aborts_sticky_until_good_for_a_while_or_reset() {
    let c = ApproachConfig::default();
    let good = track(0.0, 0.0, Some(20.0), Some(0.0));
    let mut rig = Rig::new();
    rig.vehicle = Some(vehicle(true));
    rig.run(Some(good), 3.0);
    assert!(rig.log.last().unwrap().vx_m_s > 1.0);
    rig.vehicle = Some(vehicle(false));
    let out = rig.step(Some(good));
    assert_eq!(out.task, ApproachTask::Abort);
    assert_eq!(out.reason, "abort: vehicle link lost");
    assert_eq!(
        out.transition.as_ref().map(|t| t.from),
        Some(ApproachTask::Approach)
    );
    // Link back: still aborted for abort_recover_s, then the tasks resume from zero speed.
    rig.vehicle = Some(vehicle(true));
    let out = rig.run(Some(good), c.abort_recover_s - 0.2);
    assert_eq!(out.task, ApproachTask::Abort);
    assert!(
        out.reason.contains("vehicle link lost (ok"),
        "{}",
        out.reason
    );
    let out = rig.run(Some(good), 0.4);
    assert_eq!(out.task, ApproachTask::Approach);
    assert!(
        out.vx_m_s > 0.0 && out.vx_m_s < 0.5,
        "ramping up from zero: {out:?}"
    );
    let back = rig
        .log
        .iter()
        .rev()
        .find(|o| o.transition.is_some())
        .unwrap();
    assert_eq!(back.transition.as_ref().unwrap().from, ApproachTask::Abort);

    // A link flicker during recovery restarts the good-input timer.
    rig.vehicle = Some(vehicle(false));
    rig.step(Some(good));
    rig.vehicle = Some(vehicle(true));
    rig.run(Some(good), 1.5);
    rig.vehicle = Some(vehicle(false));
    rig.step(Some(good));
    rig.vehicle = Some(vehicle(true));
    assert_eq!(rig.run(Some(good), 1.5).task, ApproachTask::Abort);

    // reset() clears it at once.
    rig.ap.reset();
    assert_eq!(rig.ap.task(), ApproachTask::Hold);
    assert_eq!(rig.step(Some(good)).task, ApproachTask::Approach);

    // No vehicle at all is not an abort.
    let mut rig = Rig::new();
    assert_eq!(rig.run(Some(good), 1.0).task, ApproachTask::Approach);
}

#[test]
fn bad_data_aborts() {
    let good = track(0.0, 0.0, Some(20.0), Some(0.0));
    let bad: Vec<(&str, TrackState)> = vec![
        (
            "hub position",
            TrackState {
                hub_px: [f64::NAN, 500.0],
                ..good
            },
        ),
        (
            "hub position",
            TrackState {
                hub_px: [900.0, f64::INFINITY],
                ..good
            },
        ),
        (
            "distance",
            TrackState {
                distance_m: f64::INFINITY,
                ..good
            },
        ),
        (
            "yaw",
            TrackState {
                yaw_deg: f64::NAN,
                ..good
            },
        ),
        (
            "image size",
            TrackState {
                image_width: 0,
                ..good
            },
        ),
        (
            "image size",
            TrackState {
                image_height: 0,
                ..good
            },
        ),
        (
            "time since detection",
            TrackState {
                time_since_detection_s: f64::NAN,
                ..good
            },
        ),
        (
            "time since detection",
            TrackState {
                time_since_detection_s: -1.0,
                ..good
            },
        ),
    ];
    for (what, t) in bad {
        let mut rig = Rig::new();
        rig.run(Some(good), 2.0);
        let out = rig.step(Some(t));
        assert_eq!(out.task, ApproachTask::Abort, "{what}");
        assert!(out.reason.contains(what), "{what}: {}", out.reason);
        // Sticky even though the next input is good.
        assert_eq!(rig.step(Some(good)).task, ApproachTask::Abort);
    }

    // NaN in an estimate flagged invalid, or in a lost track's position, is not used: no abort.
    let mut rig = Rig::new();
    let t = TrackState {
        distance_valid: false,
        distance_m: f64::NAN,
        yaw_valid: false,
        yaw_deg: f64::NAN,
        ..good
    };
    assert_ne!(rig.run(Some(t), 0.5).task, ApproachTask::Abort);
    let t = TrackState {
        hub_px: [f64::NAN; 2],
        ..track_mode(TrackMode::Lost, 2.0)
    };
    assert_eq!(rig.run(Some(t), 0.5).task, ApproachTask::Hold);

    // Track time going backwards.
    let mut rig = Rig::new();
    rig.run(Some(good), 1.0);
    let mut t = good;
    t.stamps.capture_ns = rig.now - 10 * FRAME_NS;
    let out = rig.ap.step(&ApproachInput {
        now_ns: rig.now,
        track: Some(&t),
        vehicle: None,
    });
    assert_eq!(out.task, ApproachTask::Abort);
    assert!(
        out.reason.contains("track time went backwards"),
        "{}",
        out.reason
    );

    // Step time going backwards.
    let mut rig = Rig::new();
    rig.run(Some(good), 1.0);
    rig.now -= 20 * FRAME_NS;
    let mut t = good;
    t.stamps.capture_ns = rig.now + 30 * FRAME_NS; // the track itself is not older
    let out = rig.ap.step(&ApproachInput {
        now_ns: rig.now,
        track: Some(&t),
        vehicle: None,
    });
    assert_eq!(out.task, ApproachTask::Abort);
    assert!(out.reason.contains("time went backwards"), "{}", out.reason);
}

// ---------------------------------------------------------------- done

#[test]
fn done_after_hold_time_and_left_on_a_disturbance() {
    let c = ApproachConfig {
        distance_filter_s: 0.0,
        yaw_filter_s: 0.0,
        ..Default::default()
    };
    let mut rig = Rig::with(c.clone());
    let at = track(0.01, -0.01, Some(5.1), Some(1.0));
    let mark = rig.log.len();
    rig.run(Some(at), c.done_hold_s - 0.2);
    assert_eq!(rig.ap.task(), ApproachTask::Approach);
    assert!(
        rig.log
            .last()
            .unwrap()
            .reason
            .starts_with("T3: at 5.10 m, settling"),
        "{}",
        rig.log.last().unwrap().reason
    );
    let out = rig.run(Some(at), 0.4);
    assert_eq!(out.task, ApproachTask::Done);
    assert!(
        out.reason.starts_with("done: 5.10 m, yaw 1.0 deg"),
        "{}",
        out.reason
    );
    let done_at = rig
        .log
        .iter()
        .position(|o| o.task == ApproachTask::Done)
        .unwrap();
    let held = (done_at - mark) as f64 * FRAME_NS as f64 * 1e-9;
    assert!(
        held >= c.done_hold_s && held < c.done_hold_s + 0.1,
        "{held}"
    );

    // Small disturbances inside the outer thresholds: still Done, still hovering; a residual
    // yaw (drift aside) is held against sideways, toward the rotor axis, and a distance off the
    // target (a gust pushed the vehicle back or forth) forward or back, toward the target.
    for t in [
        track(0.08, 0.0, Some(5.1), Some(1.0)),
        track(0.0, -0.09, Some(5.1), Some(1.0)),
        track(0.0, 0.0, Some(5.45), Some(1.0)),
        track(0.0, 0.0, Some(5.1), Some(-4.5)),
        track(0.0, 0.0, Some(4.6), Some(1.0)),
    ] {
        let out = rig.run(Some(t), 0.5);
        assert_eq!(out.task, ApproachTask::Done);
        // Toward the axis, ramping (rate limit) to about the gain times the offset.
        let target = -c.done_lateral_gain_per_s * 5.1 * t.yaw_deg.to_radians().sin();
        assert!(
            out.vy_m_s * target > 0.0 && out.vy_m_s.abs() <= 1.25 * target.abs(),
            "vy {} for yaw {}, target {target}",
            out.vy_m_s,
            t.yaw_deg
        );
        let toward = c.done_distance_gain_per_s * (t.distance_m - c.target_distance_m);
        assert!(
            out.vx_m_s * toward > 0.0 && out.vx_m_s.abs() <= 1.01 * toward.abs(),
            "vx {} at {} m, target {toward}",
            out.vx_m_s,
            t.distance_m
        );
    }
    // Losing the distance leaves Done for T3, which does not move forward without one: the
    // backward hold of the last Done command (4.6 m) only ramps down.
    let before = rig.log.last().unwrap().vx_m_s;
    let mut no_distance = track(0.0, 0.0, Some(5.1), Some(1.0));
    no_distance.distance_valid = false;
    let out = rig.step(Some(no_distance));
    assert_eq!(
        (out.task, out.reason.as_str()),
        (
            ApproachTask::Approach,
            "T3: no valid distance, not moving forward"
        )
    );
    assert!(
        before < 0.0 && out.vx_m_s <= 0.0 && out.vx_m_s > before,
        "{before} -> {out:?}"
    );
    // Each outer threshold leaves Done for its task; coming back needs the hold again.
    for (t, task) in [
        (
            track(0.0, 0.0, Some(5.6), Some(1.0)),
            ApproachTask::Approach,
        ),
        (
            track(0.0, 0.0, Some(5.1), Some(-5.5)),
            ApproachTask::ReduceYaw,
        ),
        (
            track(0.2, 0.0, Some(5.1), Some(1.0)),
            ApproachTask::CentreHub,
        ),
    ] {
        rig.run(Some(at), c.done_hold_s + 0.2);
        assert_eq!(rig.ap.task(), ApproachTask::Done);
        let out = rig.step(Some(t));
        assert_eq!(out.task, task, "{t:?}");
        assert_eq!(
            out.transition.as_ref().map(|t| t.from),
            Some(ApproachTask::Done)
        );
        let out = rig.step(Some(at));
        assert_ne!(out.task, ApproachTask::Done, "the hold time starts again");
    }
    // Losing the track in Done holds, and Done needs the hold time again after it returns.
    rig.run(Some(at), c.done_hold_s + 0.2);
    assert_eq!(
        rig.step(Some(track_mode(TrackMode::Lost, 1.0))).task,
        ApproachTask::Hold
    );
    assert_ne!(rig.step(Some(at)).task, ApproachTask::Done);
}

// ---------------------------------------------------------------- rate limits and robustness

/// xorshift64: deterministic pseudo-random numbers.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    /// True with probability 1/n.
    fn one_in(&mut self, n: u64) -> bool {
        self.next().is_multiple_of(n)
    }
    /// Uniform in [lo, hi).
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The distance drops at once from 10 m to 5 m at full forward speed (a wrong size that snaps
/// to the truth): the forward speed falls at the braking rate, not the acceleration rate, to a
/// standstill, and only then backs away (at the acceleration rate).
#[test]
fn forward_motion_brakes_faster_than_it_accelerates() {
    let c = ApproachConfig::default();
    assert!(c.brake_x_m_s2 > c.accel_xy_m_s2);
    let mut rig = Rig::with(c.clone());
    let out = rig.run(Some(track(0.0, 0.0, Some(12.0), Some(0.0))), 10.0);
    assert_eq!(out.task, ApproachTask::Approach);
    assert!(out.vx_m_s > 1.0, "cruising: {out:?}");
    let v0 = out.vx_m_s;
    let mark = rig.log.len();
    rig.run(Some(track(0.0, 0.0, Some(4.0), Some(0.0))), 3.0);
    let dt = FRAME_NS as f64 * 1e-9;
    let log = &rig.log[mark - 1..];
    let stop = log.iter().position(|o| o.vx_m_s <= 0.0).expect("stops");
    // The distance low-pass takes a few frames to fall below the cruise law.
    let filter_steps = (c.distance_filter_s / dt).ceil() as usize;
    let steps_at_brake = (v0 / (c.brake_x_m_s2 * dt)).ceil() as usize + filter_steps;
    let steps_at_accel = (v0 / (c.accel_xy_m_s2 * dt)).floor() as usize;
    assert!(steps_at_brake < steps_at_accel);
    assert!(
        stop <= steps_at_brake,
        "stopped after {stop} steps, braking allows {steps_at_brake}"
    );
    for w in log[stop..].windows(2) {
        assert!(
            (w[1].vx_m_s - w[0].vx_m_s).abs() <= c.accel_xy_m_s2 * dt + EPS,
            "backing away accelerates gently"
        );
    }
    assert!(log.last().unwrap().vx_m_s < 0.0, "backs away from 4 m");
}

#[test]
fn rate_limits_hold_between_steps() {
    let c = ApproachConfig::default();
    let mut ap = Approach::new(c.clone()).unwrap();
    let mut rng = Rng(0x1234_5678_9abc_def1);
    let mut now = 1_000_000_000u64;
    let mut prev: Option<(u64, ApproachOutput)> = None;
    let mut t = track(0.0, 0.0, Some(20.0), Some(0.0));
    let mut seen = std::collections::BTreeSet::new();
    for i in 0..5000 {
        if i % 10 == 0 {
            let far = rng.uniform(0.0, 1.0) < 0.3;
            t = track(
                if far {
                    rng.uniform(-0.8, 0.8)
                } else {
                    rng.uniform(-0.06, 0.06)
                },
                if far {
                    rng.uniform(-0.8, 0.8)
                } else {
                    rng.uniform(-0.06, 0.06)
                },
                Some(rng.uniform(4.0, 40.0)),
                Some(rng.uniform(-25.0, 25.0)),
            );
        }
        // Irregular steps, including stalls longer than max_dt_s.
        let gap = if rng.uniform(0.0, 1.0) < 0.02 {
            3_000_000_000
        } else {
            (rng.uniform(0.02, 0.12) * 1e9) as u64
        };
        now += gap;
        t.stamps.capture_ns = now;
        let out = ap.step(&ApproachInput {
            now_ns: now,
            track: Some(&t),
            vehicle: None,
        });
        check_output(&out, &c);
        seen.insert(out.task as u32);
        if let Some((pnow, p)) = &prev {
            let dt = ((now - pnow) as f64 * 1e-9).min(c.max_dt_s);
            let moving = |k: ApproachTask| {
                matches!(
                    k,
                    ApproachTask::CentreHub | ApproachTask::ReduceYaw | ApproachTask::Approach
                )
            };
            if moving(p.task) && moving(out.task) {
                // Forward motion may slow down at the braking rate, to a standstill at most.
                let slowing = p.vx_m_s > 0.0 && out.vx_m_s < p.vx_m_s && out.vx_m_s >= -EPS;
                let ax = if slowing {
                    c.brake_x_m_s2
                } else {
                    c.accel_xy_m_s2
                };
                assert!(
                    (out.vx_m_s - p.vx_m_s).abs() <= ax * dt + EPS,
                    "{i}: vx {p:?} {out:?}"
                );
                assert!(
                    (out.vy_m_s - p.vy_m_s).abs() <= c.accel_xy_m_s2 * dt + EPS,
                    "{i}: vy"
                );
                assert!(
                    (out.vz_m_s - p.vz_m_s).abs() <= c.accel_z_m_s2 * dt + EPS,
                    "{i}: vz"
                );
                assert!(
                    (out.yaw_rate_rad_s - p.yaw_rate_rad_s).abs()
                        <= c.yaw_accel_deg_s2.to_radians() * dt + EPS,
                    "{i}: yaw rate"
                );
            }
        }
        prev = Some((now, out));
    }
    for k in [
        ApproachTask::CentreHub,
        ApproachTask::ReduceYaw,
        ApproachTask::Approach,
    ] {
        assert!(seen.contains(&(k as u32)), "{k:?} not exercised");
    }
}

#[test]
fn garbage_never_panics_and_outputs_stay_limited() {
    let c = ApproachConfig::default();
    let mut ap = Approach::new(c.clone()).unwrap();
    let mut rng = Rng(0xdead_beef_cafe_f00d);
    let specials = [
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        0.0,
        -0.0,
        1e308,
        -1e308,
        f64::MIN_POSITIVE,
        5.0,
    ];
    let pick = |rng: &mut Rng, lo: f64, hi: f64| {
        if rng.one_in(4) {
            specials[(rng.next() % specials.len() as u64) as usize]
        } else {
            rng.uniform(lo, hi)
        }
    };
    let mut now = 0u64;
    for _ in 0..20_000 {
        let jump = rng.next() % 20;
        now = match jump {
            0 => now.saturating_sub(rng.next() % 5_000_000_000),
            1 => now.saturating_add(rng.next() % 100_000_000_000),
            2 => u64::MAX - rng.next() % 1000,
            _ => now.saturating_add(rng.next() % 200_000_000),
        };
        let mode = [
            TrackMode::Acquiring,
            TrackMode::Tracking,
            TrackMode::Coasting,
            TrackMode::Lost,
        ][(rng.next() % 4) as usize];
        let t = TrackState {
            stamps: Stamps {
                capture_ns: if rng.one_in(3) { rng.next() } else { now },
                ..Stamps::default()
            },
            mode,
            search_requested: rng.one_in(5),
            image_width: [0, 1, 640, 1920, u32::MAX][(rng.next() % 5) as usize],
            image_height: [0, 1, 480, 1080, u32::MAX][(rng.next() % 5) as usize],
            hub_px: [
                pick(&mut rng, -5000.0, 5000.0),
                pick(&mut rng, -5000.0, 5000.0),
            ],
            distance_valid: rng.one_in(2),
            distance_m: pick(&mut rng, -10.0, 100.0),
            yaw_valid: rng.one_in(2),
            yaw_deg: pick(&mut rng, -200.0, 200.0),
            time_since_detection_s: pick(&mut rng, 0.0, 2.0),
            ..TrackState::default()
        };
        let v = vehicle(!rng.one_in(10));
        let input = ApproachInput {
            now_ns: now,
            track: (!rng.one_in(8)).then_some(&t),
            vehicle: (!rng.one_in(3)).then_some(&v),
        };
        let out = ap.step(&input);
        check_output(&out, &c);
        if rng.one_in(500) {
            ap.reset();
        }
    }
}

#[test]
fn reasons_are_cut_at_a_char_boundary() {
    let s = "T1: ".to_string() + &"é".repeat(40);
    let t = truncate_reason(s.clone());
    assert!(t.len() <= MAX_REASON_BYTES && s.starts_with(&t) && t.len() >= MAX_REASON_BYTES - 1);
    assert_eq!(truncate_reason("short".into()), "short");
}

// ---------------------------------------------------------------- closed loop

/// A kinematic point-mass multicopter in a world frame with the hub at the origin, the rotor
/// axis along +X (the turbine faces +X), Y to the turbine's left, Z up. Heading `h` is
/// counter-clockwise from +X. Body velocities follow the commands with first-order lags.
struct Sim {
    pos: [f64; 3],
    h: f64,
    /// Actual body velocities vx (fwd), vy (right), vz (down), yaw rate (clockwise), lagging.
    vel: [f64; 4],
}

/// Pinhole focal length / image width (the GoPro HERO3+ wide centre focal length).
#[allow(clippy::approx_constant)] // 833.9 px / 1920 px, not log10(e)
const F_PER_W: f64 = 0.4343;

impl Sim {
    /// The ideal track state the vision pipeline would report, exact geometry.
    fn track(&self, now: u64) -> TrackState {
        let [x, y, z] = self.pos;
        let rel = [-x, -y, -z];
        let fwd = rel[0] * self.h.cos() + rel[1] * self.h.sin();
        let right = rel[0] * self.h.sin() - rel[1] * self.h.cos();
        let down = -rel[2];
        let f = F_PER_W * f64::from(W);
        let dist = (rel[0].powi(2) + rel[1].powi(2) + rel[2].powi(2)).sqrt();
        let u = f64::from(W) / 2.0 + f * right / fwd;
        let v = f64::from(H) / 2.0 + f * down / fwd;
        let visible =
            fwd > 0.5 && (0.0..f64::from(W)).contains(&u) && (0.0..f64::from(H)).contains(&v);
        TrackState {
            stamps: Stamps {
                capture_ns: now,
                ..Stamps::default()
            },
            mode: if visible {
                TrackMode::Tracking
            } else {
                TrackMode::Lost
            },
            image_width: W,
            image_height: H,
            hub_px: if visible {
                [u, v]
            } else {
                [f64::from(W) / 2.0, f64::from(H) / 2.0]
            },
            hub_bearing_deg: [
                right.atan2(fwd).to_degrees(),
                (-down).atan2(fwd).to_degrees(),
            ],
            distance_valid: visible,
            distance_m: dist,
            yaw_valid: visible,
            yaw_deg: y.atan2(x).to_degrees(),
            ..TrackState::default()
        }
    }

    /// The autopilot's view: position in a local north-east-down frame with north along +X
    /// and east along −Y, heading clockwise from north.
    fn vehicle(&self) -> VehicleState {
        let [x, y, z] = self.pos;
        VehicleState {
            position_ned_m: [x, -y, -z],
            yaw_rad: -self.h,
            ..vehicle_at(0.0)
        }
    }

    fn advance(&mut self, cmd: &ApproachOutput, dt: f64) {
        let target = [cmd.vx_m_s, cmd.vy_m_s, cmd.vz_m_s, cmd.yaw_rate_rad_s];
        let taus = [0.3, 0.3, 0.3, 0.15];
        let n = 10;
        let h = dt / n as f64;
        for _ in 0..n {
            for i in 0..4 {
                self.vel[i] += (target[i] - self.vel[i]) * (h / taus[i]).min(1.0);
            }
            let [vx, vy, vz, r] = self.vel;
            let (s, c) = self.h.sin_cos();
            self.pos[0] += (vx * c + vy * s) * h;
            self.pos[1] += (vx * s - vy * c) * h;
            self.pos[2] -= vz * h;
            self.h -= r * h;
        }
    }
}

/// Flies from 35 m out, `lateral` m to the side, `below` m under the hub, with the heading
/// `heading_err_deg` off the hub. Returns (time of Done, distance and |yaw| then, closest
/// distance, tasks in order).
fn fly(
    lateral: f64,
    below: f64,
    heading_err_deg: f64,
) -> (Option<f64>, f64, f64, f64, Vec<ApproachTask>) {
    fly_with(35.0, lateral, below, heading_err_deg, None)
}

/// As [`fly`] from `start` m out; with `noise` = Some(seed) the track gets measurement noise
/// (hub ±3 px, distance ±3 %, yaw ±1 deg, uniform) and arrives one frame late.
fn fly_with(
    start: f64,
    lateral: f64,
    below: f64,
    heading_err_deg: f64,
    noise: Option<u64>,
) -> (Option<f64>, f64, f64, f64, Vec<ApproachTask>) {
    let flight = fly_reading(
        ApproachConfig::default(),
        [start, lateral, below, heading_err_deg],
        noise,
        |d| d,
    );
    assert_eq!(flight.left_image, None, "the hub left the image");
    let (tasks, last) = (flight.tasks, flight.last);
    assert_eq!(
        last.task,
        ApproachTask::Done,
        "ends in Done; tasks {tasks:?}, {last:?}"
    );
    (
        flight.done_at,
        flight.d_done,
        flight.y_done,
        flight.closest,
        tasks,
    )
}

/// What [`fly_reading`] saw.
struct Flight {
    done_at: Option<f64>,
    d_done: f64,
    y_done: f64,
    closest: f64,
    tasks: Vec<ApproachTask>,
    /// Every reason given, in order, without repeats.
    reasons: Vec<String>,
    last: ApproachOutput,
    /// When and where the hub left the image (the flight ends there).
    left_image: Option<String>,
}

/// Two minutes of closed-loop flight from `[start, lateral, below, heading_err_deg]` (see
/// [`fly_with`]) with the autopilot's odometry, the distance reading `reading(true distance)`.
fn fly_reading(
    c: ApproachConfig,
    start: [f64; 4],
    noise: Option<u64>,
    reading: impl Fn(f64) -> f64,
) -> Flight {
    fly_seeing(c, start, noise, |t| TrackState {
        distance_m: reading(t.distance_m),
        ..t
    })
}

/// As [`fly_reading`], the track being `see(exact track)`.
fn fly_seeing(
    c: ApproachConfig,
    [start, lateral, below, heading_err_deg]: [f64; 4],
    noise: Option<u64>,
    see: impl Fn(TrackState) -> TrackState,
) -> Flight {
    let mut rng = Rng(noise.unwrap_or(1));
    let mut delayed: Option<TrackState> = None;
    let mut ap = Approach::new(c.clone()).unwrap();
    let (x, y) = (start, lateral);
    let mut sim = Sim {
        pos: [x, y, -below],
        h: (-y).atan2(-x) + heading_err_deg.to_radians(),
        vel: [0.0; 4],
    };
    let mut now = 5_000_000_000u64;
    let dt = FRAME_NS as f64 * 1e-9;
    let mut closest = f64::INFINITY;
    let mut tasks: Vec<ApproachTask> = Vec::new();
    let mut done_at = None;
    let (mut d_done, mut y_done) = (f64::NAN, f64::NAN);
    let steps = (120.0 / dt) as usize;
    let mut reasons: Vec<String> = Vec::new();
    let mut last = None;
    let mut left_image = None;
    for i in 0..steps {
        let exact = sim.track(now);
        closest = closest.min(exact.distance_m);
        if exact.mode != TrackMode::Tracking {
            left_image = Some(format!("at {:.1} s: {:?}", i as f64 * dt, sim.pos));
            break;
        }
        let truth = see(exact);
        let t = if noise.is_some() {
            let mut m = truth;
            m.hub_px[0] += rng.uniform(-3.0, 3.0);
            m.hub_px[1] += rng.uniform(-3.0, 3.0);
            m.distance_m *= 1.0 + rng.uniform(-0.03, 0.03);
            m.yaw_deg += rng.uniform(-1.0, 1.0);
            // One frame of latency: the controller sees the previous frame's measurement.
            let seen = delayed.unwrap_or(m);
            delayed = Some(m);
            TrackState {
                stamps: truth.stamps,
                ..seen
            }
        } else {
            truth
        };
        let out = ap.step(&ApproachInput {
            now_ns: now,
            track: Some(&t),
            vehicle: Some(&sim.vehicle()),
        });
        check_output(&out, &c);
        if tasks.last() != Some(&out.task) {
            tasks.push(out.task);
        }
        if reasons.last() != Some(&out.reason) {
            reasons.push(out.reason.clone());
        }
        if out.task == ApproachTask::Done && done_at.is_none() {
            done_at = Some(i as f64 * dt);
            d_done = exact.distance_m;
            y_done = exact.yaw_deg.abs();
        }
        sim.advance(&out, dt);
        now += FRAME_NS;
        last = Some(out);
    }
    Flight {
        done_at,
        d_done,
        y_done,
        closest,
        tasks,
        reasons,
        last: last.expect("the hub starts in view"),
        left_image,
    }
}

/// A reading taken in a hover establishes nothing: the tracker's first distance after an
/// acquisition read 10.4 m at 29.4 m and grew over 1.5 s (`fly` seed 19); the approach must
/// not take the growth for a contradiction.
#[test]
fn readings_that_grow_in_a_hover_do_not_stop_the_approach() {
    let mut rig = Rig::new();
    rig.vehicle = Some(vehicle_at(0.0));
    for d in [10.4, 11.9, 13.0, 17.0, 22.0, 27.5, 29.0] {
        rig.run(Some(track(0.0, 0.0, Some(d), Some(0.0))), 0.6);
    }
    let out = rig.run(Some(track(0.0, 0.0, Some(29.0), Some(0.0))), 3.0);
    assert!(
        out.vx_m_s > 0.5 && out.reason.starts_with("T3: 29.0 m"),
        "{out:?}"
    );
}

/// A run of readings far below what the odometry leaves (`fly` seed 20: 1.3–2.6 m at 5 m) is
/// acted on but does not become the reference: the right readings after it are no jump.
#[test]
fn readings_far_too_close_do_not_become_the_reference() {
    let mut rig = Rig::new();
    // Closing in from 12 m to 6 m with agreeing readings.
    rig.fly_north(0.0, 6.0, |north| 12.0 - north);
    // Reading 2 m while the vehicle backs away from 6 m to 7.5 m.
    rig.fly_north(6.0, 4.5, |_| 2.0);
    // Right again: 7.5 m, then closing in.
    rig.vehicle = Some(vehicle_at(4.5));
    let out = rig.run(Some(track(0.0, 0.0, Some(7.5), Some(0.0))), 3.0);
    assert!(
        out.vx_m_s > 0.1 && out.reason.starts_with("T3: 7.5 m"),
        "{out:?}"
    );
}

/// A reading off by a factor shrinks by that factor of the distance flown: it never confirms
/// an anchor, and the right readings after it are no jump (`--autopilot ardupilot` seed 4 read
/// 12.5 m at 37.8 m while closing in, then 30 m).
#[test]
fn a_reading_off_by_a_factor_is_not_confirmed_by_flight() {
    let mut rig = Rig::new();
    rig.fly_north(0.0, 4.5, |north| (37.8 - north) / 3.0);
    rig.vehicle = Some(vehicle_at(4.5));
    let out = rig.run(Some(track(0.0, 0.0, Some(33.3), Some(0.0))), 3.0);
    assert!(
        out.vx_m_s > 0.5 && !out.reason.contains("odometry"),
        "{out:?}"
    );
}

/// A reading off by a factor that drifts shrinks by the distance flown over a window now and
/// then (`fly --random-setup` seed 82: 0.38–0.47× the truth from 35 m to 20 m). One such window
/// confirms nothing: the right reading that follows is no contradiction. Confirmed by a single
/// window, the same readings would hold it back.
#[test]
fn one_window_shrinking_as_flown_confirms_no_anchor() {
    // 35 m from the hub at north 0: 0.45× the truth, then 2 m shrinking as flown, 2 m not
    // shrinking, and 0.44× again.
    let reading = |north: f64| {
        let d = 35.0 - north;
        if north < 7.0 {
            0.45 * d
        } else if north < 9.0 {
            0.45 * 28.0 - (north - 7.0)
        } else if north < 11.0 {
            0.45 * 28.0 - 2.0
        } else {
            0.44 * d
        }
    };
    let run = |c: ApproachConfig| {
        let mut rig = Rig::with(c);
        rig.fly_north(0.0, 15.0, reading);
        rig.vehicle = Some(vehicle_at(15.0));
        rig.run(Some(track(0.0, 0.0, Some(20.0), Some(0.0))), 3.0)
    };
    let out = run(ApproachConfig::default());
    assert!(
        out.vx_m_s > 0.5 && out.reason.starts_with("T3: 20.0 m"),
        "{out:?}"
    );
    let one = run(ApproachConfig {
        shrink_check_confirm_windows: 1,
        ..ApproachConfig::default()
    });
    assert!(
        one.vx_m_s <= 0.0 && one.reason.contains("by odometry"),
        "{one:?}"
    );
}

/// A confirmed anchor can itself be the wrong one: `fly --random-setup` seeds 219 and 231 read
/// 0.35–0.5× the truth from 34 m in, confirmed an anchor ~8 m out, then read right at 21 m and
/// hovered against the latch until the time ran out. Under the latch T3 backs away, and a
/// reading that grows by the distance flown lifts it; with `shrink_check_probe_ratio` 0 the same
/// flight stays held.
#[test]
fn a_right_reading_against_a_wrong_anchor_is_judged_by_backing_away() {
    // The hub 34 m north of the start; readings 20 m short that shrink as flown confirm an
    // anchor, then the right readings contradict it.
    let wrong = |north: f64| 14.0 - north;
    let right = |north: f64| 34.0 - north;
    let run = |probe: bool| {
        let c = ApproachConfig {
            shrink_check_probe_ratio: if probe { 1.5 } else { 0.0 },
            ..ApproachConfig::default()
        };
        let settle_s = c.shrink_check_window_s + 0.5;
        let mut rig = Rig::with(c);
        rig.fly_north(0.0, 6.0, wrong);
        rig.vehicle = Some(vehicle_at(6.0));
        let latched = rig.run(Some(track(0.0, 0.0, Some(right(6.0)), Some(0.0))), settle_s);
        // Back 5 m: more than a window (0.15 of the 28 m reading).
        rig.fly_north(6.0, 1.0, right);
        rig.vehicle = Some(vehicle_at(1.0));
        let after = rig.run(Some(track(0.0, 0.0, Some(right(1.0)), Some(0.0))), 1.0);
        (latched, after)
    };
    let (latched, after) = run(true);
    assert!(
        latched.reason.contains("backing away") && latched.vx_m_s < -0.1,
        "{latched:?}"
    );
    assert!(
        after.vx_m_s > 0.1 && after.reason.contains("m to hub"),
        "{after:?}"
    );
    let (latched, after) = run(false);
    assert!(
        latched.vx_m_s.abs() <= EPS && latched.reason.contains("by odometry"),
        "{latched:?}"
    );
    assert!(
        after.vx_m_s <= EPS && after.reason.contains("by odometry"),
        "{after:?}"
    );
}

/// The anchor right and the reading off by a factor (2.9× the truth once the vehicle came
/// within 9 m, as a blade root taken for the tower reads): backed away under the latch, the
/// reading grows by 2.9 m a metre, so the latch holds to the end, the vehicle no nearer the
/// hub than where it latched.
#[test]
fn a_reading_off_by_a_factor_under_the_latch_never_lifts_it() {
    let c = ApproachConfig::default();
    let misread = std::cell::Cell::new(false);
    let reading = |d: f64| {
        misread.set(misread.get() || d < 9.0);
        if misread.get() {
            2.9 * d
        } else {
            d
        }
    };
    let f = fly_reading(c.clone(), [25.0, 2.0, 1.0, 5.0], None, reading);
    let latched = f
        .reasons
        .iter()
        .position(|r| r.contains("backing away"))
        .unwrap_or_else(|| panic!("never latched: {:?}", f.reasons));
    assert!(
        !f.reasons[latched..].iter().any(|r| r.contains("to hub")),
        "the latch lifted: {:?}",
        &f.reasons[latched..]
    );
    assert!(f.closest >= 8.0, "closest {:.2} m", f.closest);
    assert_ne!(f.last.task, ApproachTask::Done);
}

/// A hover between two windows flown in (stopping to centre the hub) neither counts nor breaks
/// the row: the readings that shrank as flown before and after it confirm the anchor, and a
/// reading that then jumps to more than twice the odometry's distance in a hover is held. Had
/// the hover broken the row, the anchor would be unconfirmed and the jump would fly on, as
/// T3 flew `fly --random-setup` seed 105 (with a detector change tried) on a track that jumped
/// from 12.0 to 32.1 m at 12 m, to 1.1 m from the rotor plane.
#[test]
fn a_hover_between_flown_windows_does_not_break_the_row() {
    // The hub 14 m north of the start; the readings right.
    let right = |north: f64| 14.0 - north;
    let mut rig = Rig::new();
    rig.fly_north(0.0, 2.5, right);
    rig.vehicle = Some(vehicle_at(2.5));
    let hover_s = 1.5 * rig.ap.config().shrink_check_window_s;
    rig.run(Some(track(0.0, 0.0, Some(right(2.5)), Some(0.0))), hover_s);
    rig.fly_north(2.5, 6.0, right);
    rig.vehicle = Some(vehicle_at(6.0));
    let held = rig.run(Some(track(0.0, 0.0, Some(20.0), Some(0.0))), 1.0);
    assert!(
        held.vx_m_s <= EPS && held.reason.contains("by odometry"),
        "{held:?}"
    );
}

/// Close in, the distance reads more the closer the vehicle comes (a narrow lens filled by the
/// rotor: a simulated flight read 7.6 m at 7.0 m and 8.1 m at 5.5 m, then flew past the rotor
/// plane). The autopilot's odometry contradicts it and forward motion stops short of
/// `min_distance_m`; without the check the same flight goes below it.
#[test]
fn a_distance_that_grows_while_closing_in_stops_the_approach() {
    // True below 7 m, then 3 m more for every metre closer.
    let reading = |d: f64| if d < 7.0 { d + 3.0 * (7.0 - d) } else { d };
    let start = [25.0, 2.0, 1.0, 5.0];
    let c = ApproachConfig::default();
    let checked = fly_reading(c.clone(), start, Some(3), reading);
    println!(
        "checked: closest {:.2} m, last {:?}",
        checked.closest, checked.last
    );
    assert!(
        checked.closest >= c.min_distance_m + 1.0,
        "closest {:.2} m; reasons {:?}",
        checked.closest,
        checked.reasons
    );
    assert!(
        checked.reasons.iter().any(|r| r.contains("by odometry")),
        "{:?}",
        checked.reasons
    );
    assert_ne!(checked.last.task, ApproachTask::Done);
    let unchecked = fly_reading(
        ApproachConfig {
            shrink_check_m: 0.0,
            ..c.clone()
        },
        start,
        Some(3),
        reading,
    );
    println!("unchecked: closest {:.2} m", unchecked.closest);
    assert!(
        unchecked.closest < c.min_distance_m,
        "{:.2}",
        unchecked.closest
    );
}

#[test]
fn closed_loop_reaches_done_from_35_m_8_m_lateral_20_deg_off() {
    for (lateral, below, heading) in [
        (8.0, 3.0, 20.0),
        (8.0, 3.0, -20.0),
        (-8.0, -2.0, 20.0),
        (-8.0, 0.0, -20.0),
    ] {
        let (done_at, d, yaw, closest, tasks) = fly(lateral, below, heading);
        let done_at = done_at.unwrap_or_else(|| panic!("no Done: {tasks:?}"));
        println!(
            "lateral {lateral} m, below {below} m, heading {heading} deg: Done after {done_at:.1} s at \
             {d:.2} m, |yaw| {yaw:.2} deg, closest {closest:.2} m, tasks {tasks:?}"
        );
        assert!(done_at <= 120.0);
        assert!((d - 5.0).abs() <= 0.3, "distance {d}");
        assert!(yaw < 3.0, "yaw {yaw}");
        assert!(closest >= 3.0, "closest {closest}");
        assert!(
            tasks.contains(&ApproachTask::CentreHub) && tasks.contains(&ApproachTask::ReduceYaw)
        );
        assert!(tasks.contains(&ApproachTask::Approach));
    }
}

#[test]
fn closed_loop_with_noise_and_latency_from_25_to_40_m() {
    for (seed, start) in [(7, 25.0), (11, 35.0), (13, 40.0)] {
        let (done_at, d, yaw, closest, tasks) = fly_with(start, 8.0, 3.0, 20.0, Some(seed));
        let done_at = done_at.unwrap_or_else(|| panic!("no Done: {tasks:?}"));
        println!(
            "noisy, from {start} m: Done after {done_at:.1} s at {d:.2} m, |yaw| {yaw:.2} deg, closest \
             {closest:.2} m, tasks {tasks:?}"
        );
        assert!(done_at <= 120.0);
        assert!(
            (d - 5.0).abs() <= 0.3 && yaw < 3.0 && closest >= 3.0,
            "{d} {yaw} {closest}"
        );
    }
}

/// Lost while settling at the target, the settling goes on to Done on the odometry's distance
/// from the hub the last confirmed track fixed, and Done holds, for `settle_through_loss_s`;
/// out of tolerance, or past it, the loss is handled as any other (`fly --random-setup` seed 14:
/// lost at 4.8 m through a narrow lens, re-acquired on something else, flown 7 m aside).
#[test]
fn a_track_lost_while_settling_at_the_target_settles_on_odometry() {
    let c = ApproachConfig::default();
    let settle = |lost_north: f64, cfg: ApproachConfig| {
        let mut rig = Rig::with(cfg);
        // The hub 13 m north: readings agree with the odometry, 5 m at north 8.
        rig.fly_north(0.0, 8.0, |north| 13.0 - north);
        rig.run(Some(track(0.0, 0.0, Some(5.0), Some(0.0))), 0.5);
        assert_eq!(
            rig.ap.task(),
            ApproachTask::Approach,
            "settling, not yet done"
        );
        rig.vehicle = Some(vehicle_at(lost_north));
        let mark = rig.log.len();
        rig.run(Some(track_mode(TrackMode::Lost, 1.0)), 3.0);
        (rig, mark)
    };
    let (mut rig, mark) = settle(8.0, c.clone());
    let tasks = rig.tasks_since(mark);
    assert_eq!(
        tasks,
        vec![ApproachTask::Approach, ApproachTask::Done],
        "{:?}",
        rig.log.last()
    );
    assert!(rig.log[mark..]
        .iter()
        .all(|o| o.vx_m_s == 0.0 && o.vy_m_s == 0.0 && o.yaw_rate_rad_s == 0.0));
    assert!(
        rig.log.last().unwrap().reason.contains("by odometry"),
        "{}",
        rig.log.last().unwrap().reason
    );
    // Past `settle_through_loss_s` the loss is a loss.
    rig.run(
        Some(track_mode(TrackMode::Lost, 4.0)),
        c.settle_through_loss_s,
    );
    assert_eq!(rig.ap.task(), ApproachTask::Hold);
    // Drifted out of the distance tolerance, or with the rule off: a loss at once.
    let (rig, mark) = settle(8.0 - 2.0 * c.distance_tolerance_m, c.clone());
    assert_eq!(rig.log[mark].task, ApproachTask::Hold);
    let off = ApproachConfig {
        settle_through_loss_s: 0.0,
        ..c.clone()
    };
    let (rig, mark) = settle(8.0, off);
    assert_eq!(rig.log[mark].task, ApproachTask::Hold);
    assert_eq!(rig.ap.task(), ApproachTask::Hold);
}

/// Settling begun, image errors that jitter across their tolerances while the odometry keeps the
/// vehicle where settling began do not restart it: settling goes on to Done, and Done holds
/// the station on the odometry (`fly --random-setup` seeds 8 and 10: a spinner wider than the
/// view at 5 m, the hub's image position a few rim pixels, settling restarted for a minute).
/// Moved off the station, or with the rule off, the image errors decide as before.
#[test]
fn image_errors_that_jitter_while_settling_do_not_restart_it() {
    let c = ApproachConfig::default();
    let jitter = |cfg: ApproachConfig, drift_m: f64| {
        let mut rig = Rig::with(cfg);
        // The hub 13 m north: readings agree with the odometry, 5 m at north 8.
        rig.fly_north(0.0, 8.0, |north| 13.0 - north);
        // Until settling begins (the distance filter lags).
        for _ in 0..30 {
            let out = rig.step(Some(track(0.0, 0.0, Some(5.0), Some(0.0))));
            if out.reason.contains("settling") {
                break;
            }
        }
        let last = rig.log.last().unwrap();
        assert!(last.reason.contains("settling 0.0"), "{last:?}");
        rig.vehicle = Some(vehicle_at(8.0 - drift_m));
        let mark = rig.log.len();
        // The hub's image position and the yaw beyond their outer tolerances every other frame.
        for i in 0..60 {
            let off = if i % 2 == 0 { 0.0 } else { 0.3 };
            let yaw = if i % 4 == 1 { 8.0 } else { 0.0 };
            rig.step(Some(track(off, -off, Some(5.0 + drift_m), Some(yaw))));
        }
        (rig, mark)
    };
    let (rig, mark) = jitter(c.clone(), 0.0);
    let last = rig.log.last().unwrap();
    assert_eq!(last.task, ApproachTask::Done, "{last:?}");
    // Neither T1 nor T2 takes over; the vehicle stands (nearly) still.
    assert_eq!(
        rig.tasks_since(mark),
        vec![ApproachTask::Approach, ApproachTask::Done]
    );
    assert!(rig.log[mark..]
        .iter()
        .all(|o| o.vx_m_s.abs() < 0.1 && o.vy_m_s.abs() < 0.05));
    assert!(rig.log[rig.log.len() - 10..]
        .iter()
        .all(|o| o.vx_m_s.abs() < 0.05 && o.vy_m_s.abs() < 0.05));
    assert!(
        rig.log[mark..]
            .iter()
            .any(|o| o.reason.starts_with("done:") && o.reason.contains("m by odometry")),
        "{:?}",
        rig.log[mark..]
            .iter()
            .map(|o| &o.reason)
            .collect::<Vec<_>>()
    );
    // Off the station by more than `settle_hold_drift_m`: T1 and T2 steer again.
    let (rig, mark) = jitter(c.clone(), 2.0 * c.settle_hold_drift_m);
    assert!(rig.log[mark..]
        .iter()
        .any(|o| o.task == ApproachTask::CentreHub));
    // The rule off: the image errors alone decide, settling never completes.
    let off = ApproachConfig {
        settle_hold_drift_m: 0.0,
        ..c.clone()
    };
    let (rig, mark) = jitter(off, 0.0);
    assert!(rig.log[mark..].iter().all(|o| o.task != ApproachTask::Done));
}

/// A track that comes back after a loss settled through, while the odometry still vouches for
/// the station, does not restart the tasks: Done goes on (`fly --random-setup` seed 8: each
/// return restarted T1 from scratch, and the flight ran out of time at 5.2 m). Off the station,
/// the return is a re-acquisition as before.
#[test]
fn a_track_back_after_a_loss_settled_through_keeps_the_station() {
    let c = ApproachConfig::default();
    let back = |return_north: f64| {
        let mut rig = Rig::new();
        rig.fly_north(0.0, 8.0, |north| 13.0 - north);
        rig.run(Some(track(0.0, 0.0, Some(5.0), Some(0.0))), 3.0);
        assert_eq!(rig.ap.task(), ApproachTask::Done);
        rig.run(Some(track_mode(TrackMode::Lost, 1.0)), 1.0);
        assert_eq!(rig.ap.task(), ApproachTask::Done, "settled through");
        rig.vehicle = Some(vehicle_at(return_north));
        let mark = rig.log.len();
        // Back, the hub drawn off centre by the rim's few pixels.
        rig.run(
            Some(track(0.2, 0.0, Some(13.0 - return_north), Some(0.0))),
            1.0,
        );
        rig.tasks_since(mark)
    };
    assert_eq!(back(8.0), vec![ApproachTask::Done]);
    assert_eq!(
        back(8.0 - 2.0 * c.settle_hold_drift_m)[0],
        ApproachTask::CentreHub
    );
}

/// Where the camera cannot see the spinner whole (`odometry_leg_fit_margin`): below 6.5 m the
/// track's hub jumps by a quarter of the image and its yaw by ±20° every second, and the
/// distance is gone, as through a narrow lens with a large spinner (`fly --random-setup` seeds
/// 8, 14, 41). With the spinner's fit known, the approach stops on the image where the leg
/// begins, fixes the hub and flies the last metres on the odometry to Done at the target, on
/// the axis; without it, it never gets there.
#[test]
fn where_the_spinner_overfills_the_view_the_last_metres_run_on_the_odometry() {
    let blind_below_m = 6.5;
    let see = |t: TrackState| {
        if t.distance_m >= blind_below_m {
            return t;
        }
        let flip = if (t.stamps.capture_ns / 1_000_000_000).is_multiple_of(2) {
            1.0
        } else {
            -1.0
        };
        TrackState {
            hub_px: [t.hub_px[0] + flip * f64::from(W) / 4.0, t.hub_px[1]],
            yaw_deg: t.yaw_deg + 20.0 * flip,
            distance_valid: false,
            ..t
        }
    };
    // The spinner fits from 6 m: the leg begins at 6.9 m.
    let c = ApproachConfig::default().with_spinner_fit(6.0);
    let from = c.odometry_leg_from_m().unwrap();
    assert!((from - 6.9).abs() < 1e-9, "{from}");
    for start in [[30.0, 6.0, 2.0, 10.0], [25.0, -5.0, -1.0, -15.0]] {
        let f = fly_seeing(c.clone(), start, None, see);
        assert_eq!(f.left_image, None);
        let done_at = f
            .done_at
            .unwrap_or_else(|| panic!("no Done: {:?} {:?}", f.tasks, f.reasons));
        println!(
            "from {start:?}: Done after {done_at:.1} s at {:.2} m, |yaw| {:.2} deg",
            f.d_done, f.y_done
        );
        assert!(
            (f.d_done - 5.0).abs() <= c.distance_tolerance_m,
            "{}",
            f.d_done
        );
        assert!(f.y_done < c.yaw_tolerance_outer_deg, "{}", f.y_done);
        assert!(f.closest >= 5.0 - c.distance_tolerance_m, "{}", f.closest);
        assert_eq!(f.last.task, ApproachTask::Done, "{:?}", f.last);
        assert!(
            f.reasons.iter().any(|r| r.contains("m to hub by odometry")),
            "{:?}",
            f.reasons
        );
    }
    let blind = fly_seeing(ApproachConfig::default(), [30.0, 6.0, 2.0, 10.0], None, see);
    assert!(
        blind.done_at.is_none() || (blind.d_done - 5.0).abs() > c.distance_tolerance_m,
        "the image alone got there: {:?}",
        blind.reasons
    );
}

/// Without a position the leg ends and the tasks start afresh on the image.
#[test]
fn the_odometry_leg_ends_without_a_position() {
    let c = ApproachConfig::default().with_spinner_fit(6.0);
    let mut rig = Rig::with(c.clone());
    // The hub 20 m north: readings agree with the odometry; the leg begins at 6.9 m.
    rig.fly_north(0.0, 13.2, |north| 20.0 - north);
    let last = rig.run(Some(track(0.0, 0.0, Some(6.8), Some(0.0))), 2.0);
    assert!(last.reason.contains("by odometry"), "{last:?}");
    let mut lost = vehicle_at(13.2);
    lost.position_valid = false;
    rig.vehicle = Some(lost);
    let out = rig.step(Some(track(0.0, 0.0, Some(6.8), Some(0.0))));
    assert!(!out.reason.contains("odometry"), "{out:?}");
    assert_eq!(out.task, ApproachTask::Approach, "{out:?}");
    // On the image again, T3 stops where the leg would begin, and the leg cannot begin
    // without a position: no faster forward.
    assert!(out.vx_m_s < last.vx_m_s, "{out:?} after {last:?}");
}

/// The spinner's fit as control computes it can be any number: not a number or not positive is
/// "not known" (no leg), kilometres through a telephoto are cut, and the config stays valid.
#[test]
fn any_spinner_fit_leaves_a_valid_config() {
    let c = ApproachConfig::default();
    for (fit, leg) in [
        (f64::NAN, None),
        (-1.0, None),
        (0.0, None),
        (
            f64::INFINITY,
            Some(c.target_distance_m + c.odometry_leg_max_m),
        ),
        (8.6e3, Some(c.target_distance_m + c.odometry_leg_max_m)),
        (6.0, Some(6.9)),
        (4.0, None),
    ] {
        let with = c.clone().with_spinner_fit(fit);
        assert!(with.validate().is_ok(), "{fit}: {:?}", with.validate());
        let from = with.odometry_leg_from_m();
        match leg {
            None => assert_eq!(from, None, "{fit}"),
            Some(l) => assert!(
                from.is_some_and(|f| (f - l).abs() < 1e-9),
                "{fit}: {from:?}"
            ),
        }
    }
}

/// Settling at the target, a distance reading that jumps away from the hub fixed when settling
/// began is held to it: a tower band on a blade's edge read 6.75 → 7.8 m within 0.5 s at 5.07 m
/// and T3 flew the vehicle to 2.6 m from the rotor plane (a variant of `fly --random-setup`
/// seed 35). Here the reading becomes 1.55× the truth 2 s after the vehicle came within the
/// target's tolerance (settling under way), the shrink check off as when its anchor is not yet
/// confirmed by flight: with the guard the flight ends Done at the target, the reasons naming
/// what the track reads; with it off (margin 100 m), T3 flies the vehicle in to where the long
/// reading says 5 m. The default config, its shrink check confirmed after 20 m of flight, stops
/// short as well.
#[test]
fn a_reading_that_jumps_long_while_settling_is_held_to_the_settled_hub() {
    use std::cell::Cell;
    let jump = |c: ApproachConfig| {
        // When the true distance first came within the inner tolerance of the target.
        let settled_at = Cell::new(None::<u64>);
        fly_seeing(c.clone(), [25.0, 0.0, 0.0, 0.0], None, |t| {
            let near = (t.distance_m - c.target_distance_m).abs() <= c.distance_tolerance_m;
            if near && settled_at.get().is_none() {
                settled_at.set(Some(t.stamps.capture_ns));
            }
            let long = settled_at
                .get()
                .is_some_and(|s| t.stamps.capture_ns > s + 2_000_000_000);
            TrackState {
                distance_m: if long {
                    1.55 * t.distance_m
                } else {
                    t.distance_m
                },
                ..t
            }
        })
    };
    let c = ApproachConfig {
        shrink_check_m: 0.0,
        ..ApproachConfig::default()
    };
    let held = jump(c.clone());
    let tail = |f: &Flight| f.reasons[f.reasons.len().saturating_sub(6)..].to_vec();
    assert_eq!(held.last.task, ApproachTask::Done, "{:?}", tail(&held));
    assert!(
        held.closest > c.target_distance_m - c.distance_tolerance_outer_m,
        "closest {:.2} m",
        held.closest
    );
    assert!(
        held.reasons.iter().any(|r| r.contains("(track reads 7.")),
        "{:?}",
        tail(&held)
    );
    let shrink_only = jump(ApproachConfig {
        settle_distance_margin_m: 100.0,
        ..ApproachConfig::default()
    });
    assert!(
        shrink_only.closest > 4.5,
        "closest {:.2} m",
        shrink_only.closest
    );
    let off = jump(ApproachConfig {
        settle_distance_margin_m: 100.0,
        ..c.clone()
    });
    assert!(
        off.closest < c.target_distance_m / 1.4,
        "without the guard T3 flies in: closest {:.2} m, {:?}",
        off.closest,
        tail(&off)
    );
}
