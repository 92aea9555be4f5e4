//! The stage heartbeat: a [`StageStatus`] published every `run.status_interval_ms` on the status
//! service. The supervisor uses it for liveness and `hubtrack status`; the recorder records it.
//! Each beat of the loop also hands the stage's log lines to the recorder ([`LogForwarder`]).

use crate::ipc::{Ipc, IpcError, MsgPublisher};
use crate::logging::LogForwarder;
use hubtrack_types::services::STATUS;
use hubtrack_types::time::monotonic_ns;
use hubtrack_types::{StageStatus, Text64};
use iceoryx2::prelude::Node;

/// Counters of one stage plus the publisher of its heartbeat.
pub struct StatusReporter {
    publisher: MsgPublisher<StageStatus>,
    interval_ns: u64,
    last_ns: u64,
    logs: LogForwarder,
    /// The counters; the stage updates them, [`StatusReporter::tick`] publishes them.
    pub status: StageStatus,
}

impl StatusReporter {
    /// Creates the reporter for `stage`, publishing at most every `interval_ms`.
    pub fn new(node: &Node<Ipc>, stage: &str, interval_ms: u64) -> Result<Self, IpcError> {
        let now = monotonic_ns();
        Ok(StatusReporter {
            publisher: MsgPublisher::new(node, &STATUS)?,
            interval_ns: interval_ms * 1_000_000,
            last_ns: 0,
            logs: LogForwarder::new(node, stage)?,
            status: StageStatus {
                stage: Text64::new(stage),
                pid: std::process::id(),
                started_ns: now,
                ..Default::default()
            },
        })
    }

    /// Records an error (counted, and kept as the last error).
    pub fn error(&mut self, message: &str) {
        self.status.errors += 1;
        self.status.last_error = Text64::new(message);
    }

    /// Publishes the log lines logged since the last call, and the status if the interval has
    /// passed. The stage's loop calls it on every turn.
    pub fn tick(&mut self) {
        let now = monotonic_ns();
        if now.saturating_sub(self.last_ns) >= self.interval_ns {
            self.publish_now();
        } else {
            self.logs.forward();
        }
    }

    /// Publishes the status now (e.g. just before exiting, so final counts are seen), and the
    /// log lines logged since the last call.
    pub fn publish_now(&mut self) {
        let now = monotonic_ns();
        self.last_ns = now;
        self.status.publish_ns = now;
        if let Err(e) = self.publisher.publish(self.status) {
            log::warn!("status heartbeat not sent: {e}");
        }
        self.logs.forward();
    }
}
