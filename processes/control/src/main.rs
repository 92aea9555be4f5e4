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
use hubtrack_control_stage::envelope::SpinnerFit;
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
    let Some(mut stage) = Stage::<ControlSections>::start("control", &args.stage)? else {
        return Ok(());
    };
    check_envelope(&mut stage.config);
    if args.replay {
        replay::run(stage)
    } else {
        live::run(stage)
    }
}

/// Says at start-up whether the calibrated camera sees the turbine's spinner whole at the
/// approach's target (see [`SpinnerFit`]); a warning when it does not, and then the approach
/// flies its last metres on the odometry (`control.approach.odometry_leg_fit_margin`). Without
/// a calibration the frame's aspect is unknown and nothing is said (detect and track refuse a
/// bad one). Gives the approach the spinner's closest fit and the camera's vertical focal length
/// (for T1's pitch-levelled vertical error).
fn check_envelope(sections: &mut ControlSections) {
    let Ok(Some(camera)) = sections.camera.calibrated() else {
        log::debug!("no camera calibration: the spinner's fit at the target is not checked");
        return;
    };
    let fit = SpinnerFit::of(
        &camera,
        &sections.turbine,
        sections.control.approach.target_distance_m,
    );
    let approach = std::mem::take(&mut sections.control.approach);
    sections.control.approach = approach
        .with_spinner_fit(fit.closest_fit_m)
        .with_camera_focal(camera.focal_half_heights());
    // With the margin the detector needs, the leg may start even where the spinner just fits.
    let leg = sections
        .control
        .approach
        .odometry_leg_from_m()
        .map(|from| {
            format!(
                "; the approach flies its last {:.1} m, from {from:.1} m, on the autopilot's position",
                from - fit.target_m
            )
        })
        .unwrap_or_default();
    match fit.warning() {
        Some(w) => log::warn!("camera and turbine: {w}{leg}"),
        None => log::info!(
            "camera and turbine: at the {:.1} m target the spinner spans {:.0}° of the camera's {:.0}° narrower field of view{leg}",
            fit.target_m,
            fit.spinner_deg,
            fit.narrow_fov_deg
        ),
    }
}
