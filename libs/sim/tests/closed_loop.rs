//! End to end: a controller that knows the truth flies through the MAVLink autopilot model to the
//! target hover on several seeds, under the default (gusty) wind, and the outcome rules accept it.

use hubtrack_sim::*;
use mavlink::dialects::common::{
    MavFrame, MavMessage, PositionTargetTypemask, SET_POSITION_TARGET_LOCAL_NED_DATA,
};

fn setpoint(v: [f64; 3], yaw_rate: f64) -> MavMessage {
    MavMessage::SET_POSITION_TARGET_LOCAL_NED(SET_POSITION_TARGET_LOCAL_NED_DATA {
        time_boot_ms: 0,
        x: 0.0,
        y: 0.0,
        z: 0.0,
        vx: v[0] as f32,
        vy: v[1] as f32,
        vz: v[2] as f32,
        afx: 0.0,
        afy: 0.0,
        afz: 0.0,
        yaw: 0.0,
        yaw_rate: yaw_rate as f32,
        type_mask: PositionTargetTypemask::from_bits_retain(1479),
        target_system: 1,
        target_component: 1,
        coordinate_frame: MavFrame::MAV_FRAME_LOCAL_NED,
    })
}

fn fly(seed: u64, cfg: &SimConfig) -> (Outcome, AutopilotStats) {
    let s = Scenario::from_seed(seed, cfg);
    let mut v = Multicopter::new(&s.start, &cfg.vehicle);
    let mut wind = s.wind(&cfg.wind);
    let mut ap = Autopilot::new(&cfg.autopilot);
    let mut rec = FlightRecorder::from_config(seed, cfg);
    let header = mavlink::MavHeader {
        system_id: 1,
        component_id: 191,
        sequence: 0,
    };
    let dt = 1.0 / cfg.physics_hz;
    let steps_per_setpoint = (cfg.physics_hz / 10.0).round() as u64;
    let axis = s.rotor_axis_ned();
    let goal = [
        s.hub_ned[0] + cfg.success.target_distance_m * axis[0],
        s.hub_ned[1] + cfg.success.target_distance_m * axis[1],
        s.hub_ned[2],
    ];
    let mut t = 0.0;
    let mut k = 0u64;
    let reason = loop {
        if k.is_multiple_of(steps_per_setpoint) {
            let g = geometry(&s, &v);
            let p = v.position_ned();
            let mut vel = [
                0.4 * (goal[0] - p[0]),
                0.4 * (goal[1] - p[1]),
                0.4 * (goal[2] - p[2]),
            ];
            let n = vel[0].hypot(vel[1]);
            if n > 2.0 {
                vel[0] *= 2.0 / n;
                vel[1] *= 2.0 / n;
            }
            let yaw_rate = -1.5 * g.heading_error_deg.to_radians();
            let r = ap.handle(t, &header, &setpoint(vel, yaw_rate), &v);
            assert!(r.is_accepted(), "{r}");
        }
        let cmd = ap.command(t);
        v.step(dt, &cmd, &mut wind);
        t += dt;
        k += 1;
        ap.outgoing(t, &v);
        rec.step(t, &v, &geometry(&s, &v));
        if rec.time_at_target_s() > 3.0 {
            break "arrived";
        }
        if t >= cfg.max_time_s {
            break "max_time";
        }
    };
    (rec.finish(t, &v, &geometry(&s, &v), reason), ap.stats())
}

#[test]
fn truth_controller_reaches_the_hover_on_every_seed() {
    let cfg = SimConfig::default();
    for seed in 1..=12 {
        let (o, stats) = fly(seed, &cfg);
        assert!(o.success, "seed {seed}: {o:?}");
        assert_eq!(o.end_reason, "arrived");
        assert!(o.time_s < 60.0, "seed {seed}: {o:?}");
        assert_eq!(stats.rejected, 0);
        assert_eq!(stats.timeouts, 0);
        eprintln!(
            "seed {seed}: {:.1} s, path {:.1} m, final d {:.2} m yaw {:.2}° speed {:.3} m/s",
            o.time_s, o.path_length_m, o.final_distance_m, o.final_yaw_deg, o.final_speed_m_s
        );
    }
    // Deterministic.
    assert_eq!(fly(3, &cfg).0, fly(3, &cfg).0);
}
