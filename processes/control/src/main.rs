//! `hubtrack-control`: the approach controller and the MAVLink link to ArduPilot.
//!
//! Reads the newest track state, runs the T1/T2/T3 approach on it, and sends the resulting
//! body-frame velocity + yaw-rate setpoint to the autopilot — only while the autopilot is armed,
//! in GUIDED and heard from, and only while the track is fresh. When the inputs go stale it sends
//! nothing at all, so ArduPilot's own guided-mode timeout stops the vehicle. Every setpoint (sent
//! or not) is published with its task and reason; the autopilot's HEARTBEAT, ATTITUDE and
//! position are published as `VehicleState` for detect (roll) and track (ego-motion). When to
//! send what is decided by the command gate of the library part ([`hubtrack_control_stage::gate`]).
//!
//! With `--replay` (started by `hubtrack replay`) there is no autopilot: the vehicle states come
//! from the recording on the vehicle service, and the same approach and sending rule run on them
//! in recorded time (see [`replay`]).

mod config;
mod live;
mod replay;
mod setpoint;

use clap::Parser;
use config::ControlSections;
use hubtrack_runtime::stage::{Stage, StageArgs};

#[derive(Parser)]
#[command(
    name = "hubtrack-control",
    about = "Fly the T1/T2/T3 approach: track in, MAVLink setpoints out"
)]
struct Args {
    #[command(flatten)]
    stage: StageArgs,
    /// Replay mode (used by `hubtrack replay`): no MAVLink link; vehicle states are read from the
    /// vehicle service, and the time of each step is its track state's capture time.
    #[arg(long)]
    replay: bool,
}

/// The control stage as started: its sections of the config, node and heartbeat.
type ControlStage = Stage<ControlSections>;

fn main() {
    hubtrack_runtime::exit_with(run());
}

fn run() -> anyhow::Result<()> {
    let args = Args::parse();
    let Some(stage) = Stage::<ControlSections>::start("control", &args.stage)? else {
        return Ok(());
    };
    if args.replay {
        replay::run(stage)
    } else {
        live::run(stage)
    }
}
