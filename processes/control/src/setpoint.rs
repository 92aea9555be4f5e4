//! What live and replayed control share: one approach step per track state, and publishing
//! the setpoint.

use crate::ControlStage;
use hubtrack_approach::{Approach, ApproachInput};
use hubtrack_runtime::ipc::MsgPublisher;
use hubtrack_runtime::status::StatusReporter;
use hubtrack_types::services::SETPOINTS;
use hubtrack_types::time::monotonic_ns;
use hubtrack_types::{Setpoint, Stamps, Text64, TrackState, VehicleState};

/// Track states buffered between loop turns (every one is used, in order).
pub const TRACK_BUFFER: usize = 16;

/// The approach and the setpoints service.
pub struct Controller {
    approach: Approach,
    out: MsgPublisher<Setpoint>,
}

impl Controller {
    /// The approach configured in `[control.approach]`, publishing on the setpoints service.
    pub fn new(stage: &ControlStage) -> anyhow::Result<Controller> {
        let approach = Approach::new(stage.config.control.approach.clone())
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        Ok(Controller {
            approach,
            out: MsgPublisher::new(&stage.node, &SETPOINTS)?,
        })
    }

    /// Steps the approach once for `track`, at its capture time, with `vehicle`; logs a task
    /// change. The setpoint is not sent yet (`sent` false) and carries `recv_ns`, when the track
    /// state arrived.
    pub fn step(&mut self, track: &TrackState, vehicle: &VehicleState, recv_ns: u64) -> Setpoint {
        let out = self.approach.step(&ApproachInput {
            now_ns: track.stamps.capture_ns,
            track: Some(track),
            vehicle: Some(vehicle),
        });
        if let Some(t) = &out.transition {
            log::info!("task {:?} → {:?}: {}", t.from, t.to, t.reason);
            if let Some(d) = t.heading_doubt {
                log::warn!(
                    "done with the turbine heading in doubt: the geometric cues read the relative yaw as {:+.1}°, the yaw network as {:+.1}°; the station holds their weighted mean (control.approach.net_heading_weight) and is square to the rotor only if that is right",
                    d.geometric_deg,
                    d.network_deg
                );
            }
        }
        Setpoint {
            stamps: Stamps {
                seq: track.stamps.seq,
                capture_ns: track.stamps.capture_ns,
                recv_ns,
                publish_ns: 0,
            },
            task: out.task,
            sent: false,
            vx_m_s: out.vx_m_s,
            vy_m_s: out.vy_m_s,
            vz_m_s: out.vz_m_s,
            yaw_rate_rad_s: out.yaw_rate_rad_s,
            reason: Text64::new(&out.reason),
        }
    }

    /// Publishes `setpoint` with its publish stamp and counts it.
    pub fn publish(
        &self,
        mut setpoint: Setpoint,
        status: &mut StatusReporter,
    ) -> anyhow::Result<()> {
        setpoint.stamps.publish_ns = monotonic_ns();
        self.out.publish(setpoint)?;
        status.status.outputs += 1;
        Ok(())
    }
}
