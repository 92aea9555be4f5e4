//! What every stage process does before its loop, in one place: logging, config (file +
//! `--set`), SIGINT/SIGTERM handling, the iceoryx2 node (with clean-up of dead nodes) and the
//! heartbeat.

use crate::config::{Config, ConfigArgs, ConfigError};
use crate::ipc::{open_node, Ipc, IpcError};
use crate::shutdown::Shutdown;
use crate::status::StatusReporter;
use iceoryx2::prelude::Node;

/// Why a stage could not start.
#[derive(Debug, thiserror::Error)]
pub enum StageError {
    /// The configuration is invalid.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// iceoryx2 failed.
    #[error(transparent)]
    Ipc(#[from] IpcError),
    /// Signal handlers could not be installed.
    #[error("cannot install signal handlers: {0}")]
    Signals(#[from] std::io::Error),
}

/// A started stage: its config, stop flag, node and heartbeat.
pub struct Stage {
    /// The validated configuration.
    pub config: Config,
    /// Set on SIGINT/SIGTERM: the loop ends, the stage finishes cleanly.
    pub shutdown: Shutdown,
    /// This process's iceoryx2 node.
    pub node: Node<Ipc>,
    /// Counters and heartbeat of the stage.
    pub status: StatusReporter,
}

impl Stage {
    /// Starts stage `name` with the config from `args`.
    pub fn start(name: &'static str, args: &ConfigArgs) -> Result<Stage, StageError> {
        crate::logging::init(name);
        let config = args.load()?;
        let shutdown = Shutdown::install()?;
        let node = open_node(name)?;
        let status = StatusReporter::new(&node, name, config.run.status_interval_ms)?;
        Ok(Stage {
            config,
            shutdown,
            node,
            status,
        })
    }
}
