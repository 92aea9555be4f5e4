//! The simulator with the real firmware flying: ArduCopter SITL (`--model JSON`) steps in lock
//! with our rotorcraft physics.
//!
//! SITL sends its motor PWM once per physics step to the JSON port and waits for the vehicle
//! state; this loop steps the rotorcraft under the scenario's wind by the step SITL asks for and
//! answers. Nothing advances while this loop is away, so SITL's whole flight — its EKF, its
//! controllers, its timeouts — runs on the simulator's time. Until the pilot
//! ([`hubtrack_sim::Pilot`], over `sim.link` to a second SITL serial port) has taken the vehicle
//! to the start pose no frame is published; from then on a camera frame is rendered from the
//! true pose and attitude every 1/fps of simulated time, and in lockstep the loop waits for
//! control's setpoint to that frame before it answers SITL again. The outcome is judged on the
//! true state from the hand-over on, as with the model.

use crate::camera::SimCamera;
use crate::wait_for;
use anyhow::{bail, Context};
use hubtrack_mavlink::{Endpoint, Link, MavHeader};
use hubtrack_runtime::ipc::{MsgPublisher, MsgSubscriber};
use hubtrack_runtime::shutdown::Shutdown;
use hubtrack_runtime::status::StatusReporter;
use hubtrack_sim::sitl_json::{PhysicsState, ServoPacket};
use hubtrack_sim::{
    geometry, FlightRecorder, Multicopter, Pilot, PilotPhase, PilotView, Rotorcraft, Scenario,
    SimConfig, SimPace, Wind,
};
use hubtrack_types::services::{CLOCK, SETPOINTS};
use hubtrack_types::time::monotonic_ns;
use hubtrack_types::{ApproachTask, Setpoint, SimClock};
use std::net::UdpSocket;
use std::path::Path;
use std::time::{Duration, Instant};

/// Longest wait for SITL's next servo packet: SITL itself re-sends after 10 s without an answer,
/// so silence beyond that means it is gone.
const SITL_SILENCE: Duration = Duration::from_secs(15);
/// The pilot's MAVLink identity: a ground station (MAVLink's GCS system id 255, component
/// MAV_COMP_ID_MISSIONPLANNER 190).
const PILOT_SYSTEM_ID: u32 = 255;
const PILOT_COMPONENT_ID: u8 = 190;

/// Runs one flight with ArduCopter SITL until done, the time limit, or shutdown.
pub fn run(
    cfg: &SimConfig,
    scenario: Scenario,
    calibration: Option<&hubtrack_render::Camera>,
    shutdown: &Shutdown,
    node: &iceoryx2::prelude::Node<hubtrack_runtime::ipc::Ipc>,
    status: &mut StatusReporter,
    outcome_path: Option<&Path>,
) -> anyhow::Result<()> {
    let start = scenario.start;
    let mut craft = Rotorcraft::on_ground([0.0; 3], start.yaw_rad, &cfg.rotorcraft);
    let mut mirror = Multicopter::new(&start, &cfg.vehicle);
    let mut wind = Wind::new(cfg.seed, &cfg.wind);
    let mut pilot = Pilot::new(start.position_ned, start.yaw_rad, &cfg.pilot);
    let mut cam = SimCamera::new(node, &cfg.camera, calibration)?;
    let clock = MsgPublisher::<SimClock>::new(node, &CLOCK)?;
    let setpoints = MsgSubscriber::<Setpoint>::new(node, &SETPOINTS, 16)?;

    let socket = UdpSocket::bind(("127.0.0.1", cfg.sitl_json_port)).with_context(|| {
        format!(
            "cannot listen for ArduPilot SITL's physics on UDP 127.0.0.1:{}",
            cfg.sitl_json_port
        )
    })?;
    socket.set_read_timeout(Some(Duration::from_millis(200)))?;
    let endpoint: Endpoint = cfg.link.parse().context("sim.link")?;
    let mut link = Link::open(&endpoint)
        .with_context(|| format!("cannot open the pilot's MAVLink link {endpoint}"))?;
    let mut header = MavHeader {
        system_id: PILOT_SYSTEM_ID,
        component_id: PILOT_COMPONENT_ID,
        sequence: 0,
    };
    log::info!(
        "seed {}: ArduCopter SITL flies; physics on UDP {}, pilot link {endpoint}; start {:.1} m from the hub at {:.1} m height, heading {:.1}°",
        cfg.seed,
        cfg.sitl_json_port,
        scenario.start_distance_m,
        -start.position_ned[2],
        start.yaw_rad.to_degrees()
    );

    let epoch_ns = monotonic_ns();
    let wall0 = Instant::now();
    let frame_period = 1.0 / cfg.fps;
    let lockstep_timeout = Duration::from_millis(cfg.lockstep_timeout_ms);
    let mut flight = FlightRecorder::from_config(cfg.seed, cfg);
    let mut buf = [0u8; 512];
    let mut t = 0.0f64;
    let mut last_count: Option<u32> = None;
    let mut last_heard = Instant::now();
    let mut next_clock_t = 0.0f64;
    let mut handover_t: Option<f64> = None;
    let (mut seq, mut step, mut lockstep_misses, mut bad_packets) = (0u64, 0u64, 0u64, 0u64);
    let mut done_since: Option<f64> = None;
    let end_reason;

    loop {
        if shutdown.requested() {
            end_reason = "stopped";
            break;
        }
        let (n, sitl) = match socket.recv_from(&mut buf) {
            Ok(r) => r,
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                if last_heard.elapsed() > SITL_SILENCE {
                    bail!(
                        "ArduPilot SITL sent no servo packet to UDP port {} for {} s (is it running with --model JSON?)",
                        cfg.sitl_json_port,
                        SITL_SILENCE.as_secs()
                    );
                }
                status.tick();
                continue;
            }
            Err(e) => return Err(e).context("receiving SITL's servo packet"),
        };
        last_heard = Instant::now();
        let packet = match ServoPacket::parse(&buf[..n]) {
            Ok(p) => p,
            Err(e) => {
                bad_packets += 1;
                log::warn!("{e} (from {sitl}); ignored");
                status.error(&e.to_string());
                continue;
            }
        };
        // A repeated count is SITL asking again for the answer it missed: answer, do not step.
        let fresh = last_count != Some(packet.frame_count);
        if let Some(prev) = last_count {
            if packet.frame_count < prev {
                log::warn!(
                    "SITL's frame count went back from {prev} to {}: the firmware restarted; the vehicle flies on",
                    packet.frame_count
                );
            }
        }
        last_count = Some(packet.frame_count);
        if fresh {
            let dt = packet.dt_s();
            let w = wind.step(dt);
            craft.step(dt, &packet.pwm_us, w, cfg.vehicle.drag_per_s);
            t += dt;
            step += 1;
            let [roll, pitch, yaw] = craft.euler();
            mirror.set_position_ned(craft.position_ned());
            mirror.set_velocity_ned(craft.velocity_ned());
            mirror.set_attitude(roll, pitch, yaw);

            // The pilot, until the hand-over.
            if handover_t.is_none() {
                match link.recv(Duration::ZERO) {
                    Ok(msgs) => msgs.iter().for_each(|(h, m)| pilot.handle(h, m)),
                    Err(e) => log::warn!("pilot link: {e}"),
                }
                let v = craft.velocity_ned();
                let view = PilotView {
                    position_ned: craft.position_ned(),
                    speed_m_s: (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt(),
                    yaw_rad: yaw,
                };
                for msg in pilot.poll(t, &view) {
                    header.sequence = header.sequence.wrapping_add(1);
                    if let Err(e) = link.send(header, &msg) {
                        log::warn!("pilot send: {e}");
                    }
                }
                for line in pilot.take_log() {
                    log::info!("pilot: {line}");
                }
                match pilot.phase() {
                    PilotPhase::Failed => {
                        end_reason = "pilot failed";
                        break;
                    }
                    PilotPhase::Ready => {
                        log::info!(
                            "t={t:.1}s: handed over at {:.1} m from the hub ({:.1} s wall)",
                            geometry(&scenario, &mirror).distance_m,
                            wall0.elapsed().as_secs_f64()
                        );
                        handover_t = Some(t);
                        next_clock_t = t;
                    }
                    _ => {}
                }
            }
            if let Some(t0) = handover_t {
                flight.step(t - t0, &mirror, &geometry(&scenario, &mirror));
            }
        }

        if fresh && t + 1e-9 >= next_clock_t {
            let now_ns = epoch_ns + (t * 1e9) as u64;
            if cfg.pace == SimPace::Realtime {
                if let Some(left) = Duration::from_secs_f64(t).checked_sub(wall0.elapsed()) {
                    std::thread::sleep(left);
                }
            }
            clock.publish(SimClock {
                now_ns,
                step,
                publish_ns: monotonic_ns(),
            })?;
            if let Some(t0) = handover_t {
                cam.publish(&scenario, &mirror, seq, now_ns)?;
                status.status.outputs += 1;
                let mut answer: Option<Setpoint> = None;
                if cfg.pace == SimPace::Lockstep {
                    answer = wait_for(&setpoints, lockstep_timeout, shutdown, |s| {
                        s.stamps.seq >= seq
                    })?;
                    if answer.is_none() {
                        lockstep_misses += 1;
                        log::warn!(
                            "t={t:.2}s frame {seq}: no setpoint within {} ms; going on",
                            lockstep_timeout.as_millis()
                        );
                    }
                } else {
                    while let Some(s) = setpoints.receive()? {
                        answer = Some(s);
                    }
                }
                if let Some(s) = answer {
                    status.status.inputs += 1;
                    if s.task == ApproachTask::Done {
                        done_since.get_or_insert(t);
                    } else {
                        done_since = None;
                    }
                }
                seq += 1;
                next_clock_t = t0 + seq as f64 * frame_period;
                if done_since.is_some_and(|d| t - d >= cfg.end_after_done_s) {
                    end_reason = "done";
                    reply(&socket, sitl, &craft, t)?;
                    break;
                }
                if t - t0 >= cfg.max_time_s {
                    end_reason = "time limit";
                    reply(&socket, sitl, &craft, t)?;
                    break;
                }
            } else {
                next_clock_t += frame_period;
            }
            status.tick();
        }
        reply(&socket, sitl, &craft, t)?;
    }

    let t_app = handover_t.map_or(0.0, |t0| t - t0);
    let mut outcome = flight.finish(t_app, &mirror, &geometry(&scenario, &mirror), end_reason);
    outcome.lockstep_misses = lockstep_misses;
    if handover_t.is_none() {
        outcome.success = false;
        outcome.failure = Some(format!(
            "never reached the start pose (pilot stopped in {:?})",
            pilot.phase()
        ));
    }
    log::info!(
        "{seq} frames, {step} physics steps ({t:.1} s simulated) in {:.1} s wall; {bad_packets} bad SITL packets; lockstep misses {lockstep_misses}; pilot link {:?}",
        wall0.elapsed().as_secs_f64(),
        link.stats()
    );
    crate::report_outcome(&outcome, outcome_path)?;
    status.publish_now();
    Ok(())
}

/// Answers SITL with the vehicle state at `t`.
fn reply(
    socket: &UdpSocket,
    to: std::net::SocketAddr,
    craft: &Rotorcraft,
    t: f64,
) -> anyhow::Result<()> {
    let state = PhysicsState {
        timestamp_s: t,
        gyro: craft.body_rates(),
        accel_body: craft.specific_force(),
        position_ned: craft.position_ned(),
        velocity_ned: craft.velocity_ned(),
        quaternion: craft.quaternion(),
    };
    socket
        .send_to(state.to_json_line().as_bytes(), to)
        .with_context(|| format!("answering SITL at {to}"))?;
    Ok(())
}
