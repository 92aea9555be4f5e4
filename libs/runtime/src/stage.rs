//! What every stage process does before its loop, in one place: logging, config (file +
//! `--set`), SIGINT/SIGTERM handling, the iceoryx2 node (with clean-up of dead nodes) and the
//! heartbeat.

use crate::config::{ConfigArgs, ConfigError, RunSections, Sections};
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
    /// The configuration could not be printed.
    #[error("cannot print the configuration: {0}")]
    Print(String),
}

/// Command-line options of every stage binary.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct StageArgs {
    /// Config file and overrides.
    #[command(flatten)]
    pub config: ConfigArgs,
    /// Check this stage's sections of the config, print `ok` and exit (exit 1 naming the key).
    #[arg(long)]
    pub check_config: bool,
    /// Print this stage's sections (defaults, file and overrides) as TOML and exit.
    #[arg(long)]
    pub print_config: bool,
}

/// A started stage: its config, stop flag, node and heartbeat.
pub struct Stage<C> {
    /// The stage's validated sections.
    pub config: C,
    /// Set on SIGINT/SIGTERM: the loop ends, the stage finishes cleanly.
    pub shutdown: Shutdown,
    /// This process's iceoryx2 node.
    pub node: Node<Ipc>,
    /// Counters and heartbeat of the stage.
    pub status: StatusReporter,
}

impl<C: Sections> Stage<C> {
    /// Starts stage `name` with its sections `C` read from `args`. With `--check-config` or
    /// `--print-config` it does that instead and returns `None`: the process then just exits.
    pub fn start(name: &'static str, args: &StageArgs) -> Result<Option<Stage<C>>, StageError> {
        crate::logging::init(name);
        let doc = args.config.document()?;
        let run = doc.sections::<RunSections>()?.run;
        let config = doc.sections::<C>()?;
        if args.print_config {
            print!("{}", to_toml(&run, &config)?);
            return Ok(None);
        }
        if args.check_config {
            println!("ok");
            return Ok(None);
        }
        let shutdown = Shutdown::install()?;
        let node = open_node(name)?;
        let status = StatusReporter::new(&node, name, run.status_interval_ms)?;
        Ok(Some(Stage {
            config,
            shutdown,
            node,
            status,
        }))
    }
}

/// `[run]` and the stage's sections as one TOML document.
fn to_toml<C: Sections>(run: &crate::config::RunConfig, config: &C) -> Result<String, StageError> {
    let print = |e: toml::ser::Error| StageError::Print(e.to_string());
    let mut table = toml::Table::try_from(RunSections { run: run.clone() }).map_err(print)?;
    table.extend(toml::Table::try_from(config).map_err(print)?);
    toml::to_string(&table).map_err(print)
}
