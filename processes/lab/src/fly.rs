//! `hubtrack fly`: seeded simulated approaches through the real processes.
//!
//! Each seed is one run of the pipeline `sim → detect → track → control → (MAVLink) → sim`
//! under the supervisor, with fresh processes (no state carried between flights), the MAVLink
//! link on a free local UDP port, and by default the simulator in lockstep with the stages, so
//! that a seed flies the same flight every time and twenty flights take minutes. The outcome of
//! each flight comes from the simulator's ground truth.

use anyhow::{bail, Context};
use hubtrack_runtime::config::ConfigArgs;
use hubtrack_runtime::ipc::DOMAIN_ENV;
use hubtrack_runtime::shutdown::Shutdown;
use hubtrack_sim::Outcome;
use hubtrack_supervisor::supervise::{supervise, RunOptions};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Wall-clock allowance per flight beyond its simulated duration (start-up, slow machines).
const WALL_MARGIN_S: f64 = 60.0;

/// `hubtrack fly` arguments.
#[derive(clap::Args)]
pub struct FlyArgs {
    #[command(flatten)]
    config: ConfigArgs,
    /// Number of flights (seeds `first_seed .. first_seed + seeds`).
    #[arg(long, default_value_t = 1)]
    seeds: u64,
    /// First seed.
    #[arg(long, default_value_t = 1)]
    first_seed: u64,
    /// One JSON object per flight per line on stdout (stage logs go to stderr).
    #[arg(long)]
    json: bool,
    /// Fly in real time (the simulator follows the wall clock) instead of lockstep.
    #[arg(long)]
    realtime: bool,
    /// Record each flight: `PATH.mcap` for one flight, `PATH-seedN.mcap` for several.
    #[arg(long, value_name = "PATH.mcap")]
    record: Option<PathBuf>,
    /// Who flies the vehicle: `sim` (our model of ArduCopter) or `ardupilot` (the real
    /// ArduCopter firmware as SITL, coupled in lockstep through its JSON physics interface).
    #[arg(long, value_enum, default_value_t = AutopilotKind::Sim)]
    autopilot: AutopilotKind,
    /// Folder with the ArduCopter SITL binary `arducopter` and its `copter.parm` (default:
    /// `HUBTRACK_ARDUPILOT_DIR`, else `../shared/tools/ardupilot`).
    #[arg(long, value_name = "DIR")]
    ardupilot_dir: Option<PathBuf>,
    /// Each seed flies its own camera (the built-in ones and the cross-domain evaluation's
    /// held-out lenses) and turbine (tower top 1.8–3.5 m, rotor 25–63 m, spinner, overhang),
    /// drawn from the seed and given to every stage as a calibration file and a turbine
    /// profile; instead of `--camera` / `--turbine`.
    #[arg(long)]
    random_setup: bool,
}

/// `--autopilot`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
enum AutopilotKind {
    /// Our model of ArduCopter (`libs/sim`).
    Sim,
    /// ArduCopter SITL.
    Ardupilot,
}

/// One flight's result line.
#[derive(serde::Serialize)]
struct FlightLine<'a> {
    #[serde(flatten)]
    outcome: &'a Outcome,
    wall_s: f64,
    recording: Option<String>,
    autopilot: AutopilotKind,
    /// With `--random-setup`: the seed's camera.
    #[serde(skip_serializing_if = "Option::is_none")]
    camera: Option<String>,
    /// With `--random-setup`: the seed's turbine.
    #[serde(skip_serializing_if = "Option::is_none")]
    turbine: Option<String>,
    /// With `--random-setup`: `"training"` when the turbine lies in the learned yaw networks'
    /// training family, `"held-out"` when not.
    #[serde(skip_serializing_if = "Option::is_none")]
    turbine_family: Option<&'static str>,
}

/// Runs the flights and prints the table (or JSON lines).
pub fn run(args: FlyArgs) -> anyhow::Result<()> {
    // Fail on a bad config before starting anything.
    crate::config::load(&args.config)?;
    if args.random_setup && (args.config.camera.is_some() || args.config.turbine.is_some()) {
        bail!("--random-setup draws each seed's camera and turbine: give it without --camera and --turbine");
    }
    let ardupilot = match args.autopilot {
        AutopilotKind::Sim => None,
        AutopilotKind::Ardupilot => {
            let dir = crate::sitl::locate(args.ardupilot_dir.as_deref())?;
            if !crate::sitl::in_private_network() {
                // Everything from here on runs again inside the private network.
                std::process::exit(crate::sitl::rerun_in_private_network()?);
            }
            crate::sitl::loopback_up()?;
            Some(dir)
        }
    };
    let shutdown = Shutdown::install()?;
    let dir = tempdir()?;
    let mut outcomes = Vec::new();
    let mut unfinished = Vec::new();
    if !args.json {
        println!(
            "hubtrack fly: {} flight(s) from seed {}, autopilot {}, {}{}",
            args.seeds,
            args.first_seed,
            match args.autopilot {
                AutopilotKind::Sim => "model",
                AutopilotKind::Ardupilot => "ArduCopter SITL",
            },
            if args.realtime {
                "real time"
            } else {
                "lockstep"
            },
            args.record
                .as_ref()
                .map(|r| format!(", recording to {}", r.display()))
                .unwrap_or_default()
        );
        println!("{}", header());
    }
    let base = std::env::var(DOMAIN_ENV).ok().filter(|d| !d.is_empty());
    for seed in args.first_seed..args.first_seed + args.seeds {
        if shutdown.requested() {
            break;
        }
        // Held for the whole flight: parallel `hubtrack fly` runs never share a link port.
        let (port, _port_lease) = free_udp_port()?;
        // A private IPC domain per flight: flights never see each other's services (nor a
        // pipeline or another `hubtrack fly` running on the machine), and no state is left over.
        let domain = format!(
            "{}fly-{}-{seed}",
            base.as_ref().map(|b| format!("{b}-")).unwrap_or_default(),
            std::process::id()
        );
        // SAFETY (edition 2021: safe): set before any stage starts; the children inherit it.
        std::env::set_var(DOMAIN_ENV, &domain);
        log::info!("seed {seed}: IPC domain {domain} (HUBTRACK_DOMAIN={domain} hubtrack echo setpoints to watch)");
        let record = args
            .record
            .as_ref()
            .map(|r| recording_path(r, seed, args.seeds));
        let mut stages = vec!["detect", "track", "control", "sim"];
        if record.is_some() {
            stages.insert(0, "recorder");
        }
        let mut overrides = args.config.overrides.clone();
        overrides.extend([
            format!("run.stages={stages:?}"),
            format!("sim.seed={seed}"),
            // A killed `hubtrack fly` must not leave simulated flights running.
            "run.stop_with_supervisor=true".to_string(),
            format!(
                "sim.pace=\"{}\"",
                if args.realtime {
                    "realtime"
                } else {
                    "lockstep"
                }
            ),
            "control.clock=\"sim\"".to_string(),
            format!("control.link=\"udpin:127.0.0.1:{port}\""),
            format!("sim.link=\"udpout:127.0.0.1:{port}\""),
        ]);
        // With the firmware: SITL's SERIAL0 goes to control's link, SERIAL1 to the simulator's
        // pilot; the simulator serves SITL's physics.
        let mut sitl = None;
        let mut _pilot_lease = None;
        if let Some(sitl_dir) = &ardupilot {
            let (pilot_port, lease) = free_udp_port()?;
            _pilot_lease = Some(lease);
            overrides.extend([
                "sim.flight_controller=\"ardupilot\"".to_string(),
                format!("sim.link=\"udpin:127.0.0.1:{pilot_port}\""),
            ]);
            sitl = Some(crate::sitl::Sitl::start(
                sitl_dir,
                &dir.join(format!("sitl-seed{seed}")),
                crate::sitl::SitlPorts {
                    control: port,
                    pilot: pilot_port,
                },
            )?);
        }
        let setup = if args.random_setup {
            let s = crate::fly_setup::draw(seed, &dir)?;
            log::info!("seed {seed}: camera {}, turbine {}", s.camera, s.turbine);
            overrides.extend(s.overrides.iter().cloned());
            Some(s)
        } else {
            None
        };
        let config_args = ConfigArgs {
            overrides,
            ..args.config.clone()
        };
        let config = crate::config::load(&config_args)?;
        let outcome_path = dir.join(format!("outcome-{seed}.json"));
        // With the firmware the flight starts on the ground: the pilot's time to the start pose
        // comes first.
        let preflight_s = if ardupilot.is_some() {
            config.sim.pilot.deadline_s
        } else {
            0.0
        };
        let wall_limit = Duration::from_secs_f64(
            (config.sim.max_time_s + preflight_s) * if args.realtime { 1.2 } else { 4.0 }
                + WALL_MARGIN_S,
        );
        let report = supervise(RunOptions {
            config: config.run.clone(),
            config_args,
            record: record.clone().unwrap_or_else(|| dir.join("unused.mcap")),
            duration: Some(wall_limit),
            outcome: Some(outcome_path.clone()),
            interactive: false,
        })?;
        if let Some(mut s) = sitl.take() {
            if !s.running() {
                log::warn!(
                    "ArduCopter SITL had ended before the flight did:\n{}",
                    s.log_tail()
                );
            }
        }
        let outcome: Outcome = match std::fs::read_to_string(&outcome_path) {
            Ok(text) => {
                serde_json::from_str(&text).with_context(|| format!("outcome of seed {seed}"))?
            }
            Err(_) => {
                // Not a flight result but a broken run (a stage given up on, a hang): said now,
                // and the other seeds still fly; the command fails at the end.
                let why = report.failure.unwrap_or_else(|| {
                    format!(
                        "no outcome within {:.0} s wall clock",
                        wall_limit.as_secs_f64()
                    )
                });
                log::error!(
                    "flight seed {seed} did not finish: {why}; going on with the next seed"
                );
                unfinished.push(format!("{seed} ({why})"));
                continue;
            }
        };
        let line = FlightLine {
            outcome: &outcome,
            wall_s: report.elapsed.as_secs_f64(),
            recording: record.as_ref().map(|r| r.display().to_string()),
            autopilot: args.autopilot,
            camera: setup.as_ref().map(|s| s.camera.clone()),
            turbine: setup.as_ref().map(|s| s.turbine.clone()),
            turbine_family: setup.as_ref().map(|s| s.turbine_family.name()),
        };
        if outcome.lockstep_misses > 0 {
            log::warn!(
                "seed {seed}: {} lockstep wait(s) timed out (machine too loaded?): this flight is not reproducible from its seed",
                outcome.lockstep_misses
            );
        }
        if args.json {
            println!("{}", serde_json::to_string(&line)?);
        } else {
            println!("{}", row(&line));
            if let Some(s) = &setup {
                println!("{:>5} camera {}; turbine {}", "", s.camera, s.turbine);
            }
        }
        outcomes.push(outcome);
    }
    let _ = std::fs::remove_dir_all(&dir);
    if !args.json && !outcomes.is_empty() {
        summary(&outcomes, args.record.as_deref(), args.seeds);
    }
    if !unfinished.is_empty() {
        bail!(
            "{} of {} flight(s) did not finish, seed(s): {}",
            unfinished.len(),
            args.seeds,
            unfinished.join("; ")
        );
    }
    Ok(())
}

fn header() -> String {
    format!(
        "{:>5} {:>7} {:>8} {:>8} {:>8} {:>7} {:>7} {:>8} {:>6}  {}",
        "seed",
        "result",
        "dist m",
        "yaw °",
        "lat m",
        "time s",
        "path m",
        "rotor m",
        "wall s",
        "end"
    )
}

fn row(l: &FlightLine) -> String {
    let o = l.outcome;
    format!(
        "{:>5} {:>7} {:>8.2} {:>+8.1} {:>+8.2} {:>7.1} {:>7.1} {:>8.2} {:>6.1}  {}{}",
        o.seed,
        if o.success { "ok" } else { "FAIL" },
        o.final_distance_m,
        o.final_yaw_deg,
        o.final_lateral_m,
        o.time_s,
        o.path_length_m,
        o.min_rotor_plane_m,
        l.wall_s,
        o.end_reason,
        o.failure
            .as_deref()
            .map(|f| format!(": {f}"))
            .unwrap_or_default()
    )
}

fn summary(outcomes: &[Outcome], record: Option<&Path>, seeds: u64) {
    let ok = outcomes.iter().filter(|o| o.success).count();
    let closest = outcomes
        .iter()
        .map(|o| o.min_rotor_plane_m)
        .fold(f64::INFINITY, f64::min);
    let mut times: Vec<f64> = outcomes
        .iter()
        .filter(|o| o.success)
        .map(|o| o.time_s)
        .collect();
    times.sort_by(f64::total_cmp);
    println!(
        "\n{ok}/{} flights ended in hover at the target; closest approach to the rotor plane {closest:.2} m{}",
        outcomes.len(),
        times.get(times.len() / 2).map(|t| format!("; median time {t:.1} s")).unwrap_or_default()
    );
    let perturbed: Vec<String> = outcomes
        .iter()
        .filter(|o| o.lockstep_misses > 0)
        .map(|o| o.seed.to_string())
        .collect();
    if !perturbed.is_empty() {
        println!(
            "lockstep waits timed out in seed(s) {}: those flights are not reproducible from their seeds (the machine was too loaded)",
            perturbed.join(", ")
        );
    }
    if let Some(r) = record {
        let first = recording_path(r, outcomes[0].seed, seeds);
        println!(
            "recordings: {} (open in Foxglove, or `hubtrack latency {}`)",
            if seeds == 1 {
                r.display().to_string()
            } else {
                format!("{}-seed*.mcap", r.with_extension("").display())
            },
            first.display()
        );
    }
}

/// `PATH` for one flight, `PATH-seedN.mcap` for several.
fn recording_path(record: &Path, seed: u64, seeds: u64) -> PathBuf {
    if seeds == 1 {
        return record.to_path_buf();
    }
    let stem = record
        .file_stem()
        .map_or("flight".into(), |s| s.to_string_lossy().into_owned());
    record.with_file_name(format!("{stem}-seed{seed}.mcap"))
}

/// Attempts at a free UDP port before giving up (each one the OS's pick).
const PORT_ATTEMPTS: usize = 64;

/// A UDP port free right now on the loopback interface (the OS picks it), with a lease on it:
/// an exclusive lock on `<temp>/hubtrack-udp-ports/<port>.lock`, held until the lease is
/// dropped and released by the OS if the process dies. The socket that found the port must be
/// closed before control binds it, and in that gap another `hubtrack fly` can be handed the
/// same port by the OS (seen with four runs started together: one flight's control could not
/// bind its link and the flight hung until its wall-clock limit); the lease makes the second
/// one pick again.
fn free_udp_port() -> anyhow::Result<(u16, std::fs::File)> {
    let dir = std::env::temp_dir().join("hubtrack-udp-ports");
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    for _ in 0..PORT_ATTEMPTS {
        let port = {
            let sock =
                std::net::UdpSocket::bind("127.0.0.1:0").context("finding a free UDP port")?;
            sock.local_addr()?.port()
        };
        let path = dir.join(format!("{port}.lock"));
        let lease = std::fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&path)
            .with_context(|| format!("opening {}", path.display()))?;
        match lease.try_lock() {
            Ok(()) => return Ok((port, lease)),
            Err(std::fs::TryLockError::WouldBlock) => {
                log::debug!("UDP port {port} is leased by another flight; picking again")
            }
            Err(std::fs::TryLockError::Error(e)) => {
                return Err(e).with_context(|| format!("locking {}", path.display()))
            }
        }
    }
    anyhow::bail!("no free UDP port for the autopilot link after {PORT_ATTEMPTS} attempts")
}

/// A private folder for the outcome files.
fn tempdir() -> anyhow::Result<PathBuf> {
    let dir = std::env::temp_dir().join(format!("hubtrack-fly-{}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    Ok(dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Leases held together are on different ports, and a held lease locks its port's file
    /// against every other opener until it is dropped.
    #[test]
    fn a_leased_port_is_not_leased_again_while_held() {
        let leases = (0..8).map(|_| free_udp_port().unwrap()).collect::<Vec<_>>();
        let mut ports = leases.iter().map(|(p, _)| *p).collect::<Vec<_>>();
        ports.sort_unstable();
        ports.dedup();
        assert_eq!(ports.len(), leases.len(), "{ports:?}");
        let (port, lease) = free_udp_port().unwrap();
        let path = std::env::temp_dir()
            .join("hubtrack-udp-ports")
            .join(format!("{port}.lock"));
        let other = std::fs::OpenOptions::new().write(true).open(&path).unwrap();
        assert!(
            matches!(other.try_lock(), Err(std::fs::TryLockError::WouldBlock)),
            "held"
        );
        drop(lease);
        other.try_lock().expect("released with the lease");
    }
}
