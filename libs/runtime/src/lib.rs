//! What every hubtrack process shares, so stage `main`s stay thin:
//! - [`cli`]: command-line value parsers the tools share;
//! - [`config`]: the config file and `--set` overrides, read section by section, strictly, with
//!   errors naming the file and the key;
//! - [`stage`]: what every stage process does before its loop;
//! - [`ipc`]: iceoryx2 node, publishers and subscribers for the services in `hubtrack_types::services`;
//! - [`logging`]: structured logs on stderr (the supervisor prefixes them with the stage name);
//! - [`shutdown`]: SIGINT/SIGTERM as a flag the stage loop checks;
//! - [`status`]: the periodic [`hubtrack_types::StageStatus`] heartbeat of a stage.

#![warn(missing_docs)]

pub mod cli;
pub mod config;
pub mod ipc;
pub mod logging;
pub mod shutdown;
pub mod stage;
mod stale_service;
pub mod status;

pub use config::{ConfigArgs, ConfigError, Sections};

/// Starts a command-line tool (not a stage): logging on stderr as `name`, and a closed pipe
/// (`hubtrack detect ... | head`) ends the process quietly, as Unix tools do. Call it first in
/// `main`, before any thread exists.
pub fn start_tool(name: &'static str) {
    // SAFETY: resetting a signal disposition at start, before any thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    logging::init(name);
}

/// Ends a stage process: on error, logs `error: <cause chain>` (one line, no backtrace dump) and
/// exits with status 1, so the supervisor and the operator see why.
pub fn exit_with<E: std::fmt::Display>(result: Result<(), E>) {
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
