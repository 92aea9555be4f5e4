//! `hubtrack-sim`: a simulated multicopter that behaves toward control like ArduCopter in GUIDED
//! mode (HEARTBEAT, ATTITUDE, LOCAL_POSITION_NED; SET_POSITION_TARGET_LOCAL_NED with a 3 s
//! timeout) and publishes its camera — the turbine rendered from its current pose, with exact
//! truth in each frame header — on the frames service, like a capture source.
//!
//! Two paces:
//! - `realtime`: simulated time follows the wall clock (the demo);
//! - `lockstep`: each camera frame waits for the pipeline's answer to it (the control stage's
//!   setpoint for that frame), so simulated time advances as fast as the stages work, and a seed
//!   gives the same flight every time. The simulator's clock is published on the `clock`
//!   service and is the pipeline clock (`capture_ns`) of the run.
//!
//! The flight ends when control has reported `done` for `sim.end_after_done_s`, or at
//! `sim.max_time_s`; the outcome (final distance, yaw, lateral offset, time, path length,
//! closest approach to the rotor plane) is logged and written as JSON to `--outcome`.

use anyhow::Context;
use camera::SimCamera;
use clap::Parser;
use hubtrack_mavlink::{Endpoint, Link, MavHeader, MavMessage};
use hubtrack_runtime::ipc::{MsgPublisher, MsgSubscriber};
use hubtrack_runtime::stage::{Stage, StageArgs};
use hubtrack_sim::{
    geometry, Autopilot, FlightController, FlightRecorder, Multicopter, Scenario, SimPace, Wind,
};
use hubtrack_types::services::{CLOCK, SETPOINTS, VEHICLE};
use hubtrack_types::time::monotonic_ns;
use hubtrack_types::{ApproachTask, Setpoint, SimClock, VehicleState};
use std::path::PathBuf;
use std::time::{Duration, Instant};

mod ardupilot;
mod camera;

/// Poll period while waiting for the pipeline in lockstep.
const LOCKSTEP_POLL: Duration = Duration::from_millis(1);

#[derive(Parser)]
#[command(
    name = "hubtrack-sim",
    about = "Simulated ArduCopter with a rendered camera (demo and `hubtrack fly`)"
)]
struct Args {
    #[command(flatten)]
    stage: StageArgs,
    /// Write the flight's outcome as one JSON object to this file.
    #[arg(long, value_name = "FILE")]
    outcome: Option<PathBuf>,
}

/// What the simulator stage reads: `[sim]`, `[camera]` (a calibration, when given, is the
/// camera the simulator renders through) and `[turbine]` (a profile, when given, is the turbine
/// it draws), so that the world matches what detect and track assume.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
struct SimSections {
    sim: hubtrack_sim::SimConfig,
    camera: hubtrack_types::setup::CameraSetup,
    turbine: hubtrack_types::setup::TurbineSetup,
}

impl hubtrack_runtime::Sections for SimSections {
    fn validate(&self) -> Result<(), hubtrack_runtime::config::ParamError> {
        self.sim.validate()?;
        self.camera.validate()?;
        self.turbine.validate()?;
        hubtrack_mavlink::Endpoint::of_config("sim.link", &self.sim.link).map(|_| ())
    }
}

fn main() {
    hubtrack_runtime::exit_with(run());
}

fn run() -> anyhow::Result<()> {
    let args = Args::parse();
    let Some(Stage {
        config,
        shutdown,
        node,
        mut status,
    }) = Stage::<SimSections>::start("sim", &args.stage)?
    else {
        return Ok(());
    };
    let cfg = &config.sim;
    let mut scenario = Scenario::from_seed(cfg.seed, cfg);
    // With a turbine profile the world shows that turbine, as detect and track assume it.
    if !config.turbine.profile.is_empty() {
        scenario = scenario.with_turbine(&config.turbine);
        let t = &config.turbine;
        log::info!(
            "turbine: {} (hub {} m, rotor radius {} m, tower top {} m)",
            t.name,
            t.hub_height_m,
            t.rotor_radius_m,
            t.tower_top_diameter_m
        );
    }
    let calibration = config.camera.calibrated()?;
    if cfg.flight_controller == FlightController::Ardupilot {
        return ardupilot::run(
            &config.sim,
            scenario,
            calibration.as_ref(),
            &shutdown,
            &node,
            &mut status,
            args.outcome.as_deref(),
        );
    }
    let mut cam = SimCamera::new(&node, &cfg.camera, calibration.as_ref())?;
    let mut vehicle = Multicopter::new(&scenario.start, &cfg.vehicle);
    let mut wind = Wind::new(cfg.seed, &cfg.wind);
    let mut autopilot = Autopilot::new(&cfg.autopilot);
    let endpoint: Endpoint = cfg.link.parse().context("sim.link")?;
    let mut link = Link::open(&endpoint)
        .with_context(|| format!("cannot open the MAVLink link {endpoint}"))?;
    let (sys, comp) = autopilot.identity();
    let mut header = MavHeader {
        system_id: sys.into(),
        component_id: comp,
        sequence: 0,
    };

    let clock = MsgPublisher::<SimClock>::new(&node, &CLOCK)?;
    let setpoints = MsgSubscriber::<Setpoint>::new(&node, &SETPOINTS, 16)?;
    let vehicle_states = MsgSubscriber::<VehicleState>::new(&node, &VEHICLE, 16)?;

    let geo0 = geometry(&scenario, &vehicle);
    log::info!(
        "seed {}: start {:.1} m from the hub, lateral {:+.1} m, height {:+.1} m, relative yaw {:+.1}°, heading error {:+.1}°; {} at {} fps, {}x{}",
        cfg.seed, geo0.distance_m, geo0.lateral_m, geo0.height_m, geo0.relative_yaw_deg, geo0.heading_error_deg,
        match cfg.pace { SimPace::Lockstep => "lockstep", SimPace::Realtime => "realtime" },
        cfg.fps, cam.camera().width, cam.camera().height
    );

    let epoch_ns = monotonic_ns();
    let wall0 = Instant::now();
    let dt = 1.0 / cfg.physics_hz;
    let frame_period = 1.0 / cfg.fps;
    let lockstep_timeout = Duration::from_millis(cfg.lockstep_timeout_ms);
    let mut flight = FlightRecorder::from_config(cfg.seed, cfg);
    let (mut t, mut step, mut seq) = (0.0f64, 0u64, 0u64);
    let mut next_frame_t = 0.0f64;
    let mut outgoing: Vec<MavMessage> = autopilot.outgoing(0.0, &vehicle);
    let mut done_since: Option<f64> = None;
    let mut lockstep_misses = 0u64;
    let end_reason;

    loop {
        if shutdown.requested() {
            end_reason = "stopped";
            break;
        }
        // Physics up to the next camera frame; the autopilot's messages queue up meanwhile.
        while t + 0.5 * dt < next_frame_t {
            let cmd = autopilot.command(t);
            vehicle.step(dt, &cmd, &mut wind);
            t += dt;
            step += 1;
            flight.step(t, &vehicle, &geometry(&scenario, &vehicle));
            outgoing.extend(autopilot.outgoing(t, &vehicle));
        }
        let now_ns = epoch_ns + (t * 1e9) as u64;
        if cfg.pace == SimPace::Realtime {
            // Hold until the wall clock catches up, handling commands as they come.
            while let Some(left) = Duration::from_secs_f64(t).checked_sub(wall0.elapsed()) {
                receive_commands(
                    &mut link,
                    &mut autopilot,
                    t,
                    &vehicle,
                    left.min(Duration::from_millis(5)),
                );
                if shutdown.requested() {
                    break;
                }
            }
        }
        clock.publish(SimClock {
            now_ns,
            step,
            publish_ns: monotonic_ns(),
        })?;
        let sent_any = !outgoing.is_empty();
        let reflected = ReflectedState::of(&outgoing);
        for msg in outgoing.drain(..) {
            header.sequence = header.sequence.wrapping_add(1);
            if let Err(e) = link.send(header, &msg) {
                log::warn!("send: {e}");
                status.error(&e.to_string());
            }
        }
        // Lockstep: detect and track must see the attitude of this instant, so wait until
        // control has published it (it stamps it with this clock). Control publishes a state
        // after each batch it reads, and the batch can end between two of these messages (a
        // HEARTBEAT alone, then the ATTITUDE): the state must show everything sent, or a replay
        // of the recording could see another attitude than the live run did.
        if cfg.pace == SimPace::Lockstep && sent_any {
            let got = wait_for(&vehicle_states, lockstep_timeout, &shutdown, |v| {
                v.recv_ns >= now_ns && reflected.is_shown_by(v)
            })?;
            if got.is_none() {
                lockstep_misses += 1;
                log::warn!(
                    "t={t:.2}s: control did not publish the vehicle state within {} ms; going on",
                    lockstep_timeout.as_millis()
                );
            }
        }

        // The camera frame of this instant.
        cam.publish(&scenario, &vehicle, seq, now_ns)?;
        status.status.outputs += 1;

        // The pipeline's answer: in lockstep wait for control's setpoint of this frame.
        let mut answer: Option<Setpoint> = None;
        if cfg.pace == SimPace::Lockstep {
            answer = wait_for(&setpoints, lockstep_timeout, &shutdown, |s| {
                s.stamps.seq >= seq
            })?;
            if answer.is_none() {
                lockstep_misses += 1;
                log::warn!(
                    "t={t:.2}s frame {seq}: no setpoint within {} ms; going on",
                    lockstep_timeout.as_millis()
                );
            }
            receive_commands(&mut link, &mut autopilot, t, &vehicle, Duration::ZERO);
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
        status.tick();
        seq += 1;
        next_frame_t = seq as f64 * frame_period;

        if done_since.is_some_and(|d| t - d >= cfg.end_after_done_s) {
            end_reason = "done";
            break;
        }
        if t >= cfg.max_time_s {
            end_reason = "time limit";
            break;
        }
    }

    let mut outcome = flight.finish(t, &vehicle, &geometry(&scenario, &vehicle), end_reason);
    outcome.lockstep_misses = lockstep_misses;
    let stats = autopilot.stats();
    log::info!(
        "{} frames in {:.1} s wall ({:.2}x real time); autopilot: {:?}; lockstep misses {lockstep_misses}; link {:?}",
        seq,
        wall0.elapsed().as_secs_f64(),
        t / wall0.elapsed().as_secs_f64().max(1e-9),
        stats,
        link.stats()
    );
    report_outcome(&outcome, args.outcome.as_deref())?;
    status.publish_now();
    Ok(())
}

/// Logs a flight's outcome and writes it as one JSON line to `path` (for `hubtrack fly`).
pub(crate) fn report_outcome(
    outcome: &hubtrack_sim::Outcome,
    path: Option<&std::path::Path>,
) -> anyhow::Result<()> {
    log::info!(
        "seed {} {}: {} after {:.1} s, distance {:.2} m, relative yaw {:+.1}°, lateral {:+.2} m, path {:.1} m, closest to rotor plane {:.2} m{}",
        outcome.seed,
        if outcome.success { "SUCCESS" } else { "FAILED" },
        outcome.end_reason,
        outcome.time_s,
        outcome.final_distance_m,
        outcome.final_yaw_deg,
        outcome.final_lateral_m,
        outcome.path_length_m,
        outcome.min_rotor_plane_m,
        outcome.failure.as_deref().map(|f| format!(" ({f})")).unwrap_or_default()
    );
    if let Some(path) = path {
        std::fs::write(path, serde_json::to_string(outcome)? + "\n")
            .with_context(|| format!("cannot write the outcome to {}", path.display()))?;
    }
    Ok(())
}

/// Hands every command that arrived (waiting at most `wait`) to the autopilot.
fn receive_commands(
    link: &mut Link,
    autopilot: &mut Autopilot,
    t: f64,
    vehicle: &Multicopter,
    wait: Duration,
) {
    match link.recv(wait) {
        Ok(msgs) => {
            for (h, m) in &msgs {
                let r = autopilot.handle(t, h, m, vehicle);
                log::trace!("{r:?}");
            }
        }
        Err(e) => log::warn!("link: {e}"),
    }
}

/// Waits until a message satisfying `ok` arrives on `sub` (the newest such is returned), or the
/// timeout passes, or shutdown.
/// What a vehicle state published by control must show once it has read a batch of the
/// autopilot's messages: the newest ATTITUDE's angles and LOCAL_POSITION_NED's position, compared
/// exactly (control widens the `f32` fields to `f64`, which is exact).
#[derive(Debug, Clone, Copy, Default)]
struct ReflectedState {
    attitude: Option<[f32; 3]>,
    position: Option<[f32; 3]>,
}

impl ReflectedState {
    fn of(messages: &[MavMessage]) -> Self {
        let mut out = Self::default();
        for msg in messages {
            match msg {
                MavMessage::ATTITUDE(a) => out.attitude = Some([a.roll, a.pitch, a.yaw]),
                MavMessage::LOCAL_POSITION_NED(p) => out.position = Some([p.x, p.y, p.z]),
                _ => {}
            }
        }
        out
    }

    fn is_shown_by(&self, v: &VehicleState) -> bool {
        let same =
            |sent: [f32; 3], seen: [f64; 3]| sent.iter().zip(seen).all(|(&a, b)| f64::from(a) == b);
        self.attitude
            .is_none_or(|a| v.attitude_valid && same(a, [v.roll_rad, v.pitch_rad, v.yaw_rad]))
            && self
                .position
                .is_none_or(|p| v.position_valid && same(p, v.position_ned_m))
    }
}

pub(crate) fn wait_for<T: std::fmt::Debug + Copy + iceoryx2::prelude::ZeroCopySend + 'static>(
    sub: &MsgSubscriber<T>,
    timeout: Duration,
    shutdown: &hubtrack_runtime::shutdown::Shutdown,
    ok: impl Fn(&T) -> bool,
) -> anyhow::Result<Option<T>> {
    let t0 = Instant::now();
    let mut found = None;
    loop {
        while let Some(v) = sub.receive()? {
            if ok(&v) {
                found = Some(v);
            }
        }
        if found.is_some() || t0.elapsed() >= timeout || shutdown.requested() {
            return Ok(found);
        }
        sub.wait(LOCKSTEP_POLL);
    }
}
