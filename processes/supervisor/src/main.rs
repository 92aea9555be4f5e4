//! `hubtrack`: the flight computer's command. Launches and supervises the stage processes, and
//! hosts the operator's tools. The lab commands (evaluation, simulated flights, benchmarks,
//! training) live in `hubtrack-lab`; `hubtrack <lab command>` hands over to it.

use clap::{Parser, Subcommand};
use hubtrack_runtime::config::ConfigArgs;
use hubtrack_supervisor::supervise::{self, RunArgs};
use hubtrack_supervisor::tools::{self, EchoArgs, TapArgs};
use std::ffi::OsString;
use std::path::PathBuf;

/// The commands `hubtrack-lab` runs; `hubtrack NAME ...` hands them over.
const LAB_COMMANDS: &[&str] = &[
    "detect",
    "track",
    "eval",
    "fly",
    "bench",
    "dataset",
    "train-ranker",
    "render",
    "diagnose",
    "fuzz",
];

#[derive(Parser)]
#[command(
    name = "hubtrack",
    version,
    about = "Find, track and approach a wind-turbine hub: launcher and operator tools",
    after_help = "Lab commands (run by hubtrack-lab, installed beside hubtrack): detect, track, \
                  eval, fly, bench, dataset, train-ranker, render, diagnose. \
                  `hubtrack-lab --help` lists them."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Start the configured stages as separate processes, record every service to MCAP.
    Run(RunArgs),
    /// Show each stage of the running pipeline: pid, state, uptime, restarts, rates, drops, last error.
    Status {
        /// One JSON object with a `stages` list.
        #[arg(long)]
        json: bool,
        /// How long to listen for heartbeats to measure rates, seconds.
        #[arg(long, default_value_t = 1.0, value_parser = hubtrack_runtime::cli::seconds)]
        listen: f64,
    },
    /// Subscribe to the frames service and print one JSON line per frame received.
    Tap(TapArgs),
    /// Print the messages of one result service as JSON lines, like `ros2 topic echo`
    /// (detections, track, setpoints, vehicle, status, clock).
    Echo(EchoArgs),
    /// Check a config file (exit 1 naming the offending key), or print the whole configuration.
    Config {
        #[command(flatten)]
        config: ConfigArgs,
        /// Print the complete configuration (file + overrides, or the defaults) as TOML.
        #[arg(long)]
        print: bool,
    },
    /// Copy every readable message of a damaged recording (e.g. after kill -9) into a new, complete file.
    Recover {
        /// The damaged recording.
        input: PathBuf,
        /// Output file (default: <input>.recovered.mcap).
        output: Option<PathBuf>,
    },
    /// Latency per stage and per hop, and end to end, from the stamps in a recording.
    Latency {
        /// The recording (live or replayed; a cut file is read as far as it goes).
        file: PathBuf,
        /// One JSON object with `stages`, `hops` and `end_to_end`.
        #[arg(long)]
        json: bool,
    },
    /// Print what the stages logged during a recording (`/log`), as the journal showed it.
    Log {
        /// The recording (a cut file is read as far as it goes).
        file: PathBuf,
        /// Only lines of this level and above.
        #[arg(long, value_enum, default_value = "debug")]
        level: tools::LogLevelArg,
        /// Only the lines of these stages (repeatable), e.g. `--stage control`.
        #[arg(long)]
        stage: Vec<String>,
        /// One JSON object per line (`time_ns`, `level`, `stage`, `file`, `line`, `message`).
        #[arg(long)]
        json: bool,
    },
    /// Replay a recording's inputs through chosen stages and record their new outputs.
    Replay(hubtrack_supervisor::replay::ReplayArgs),
    /// Ask the running recorder to record every frame raw as well (`/frames/raw`, bit-exact,
    /// beside the compressed video) for a while, from the next frame on.
    RawWindow {
        /// Length of the window, seconds of capture time (default: `recorder.raw_window_s`,
        /// capped at `recorder.raw_window_max_s`).
        #[arg(long, value_parser = hubtrack_runtime::cli::seconds)]
        seconds: Option<f64>,
        /// How long to wait for a running recorder, seconds.
        #[arg(long, default_value_t = 3.0, value_parser = hubtrack_runtime::cli::seconds)]
        wait: f64,
    },
    /// Write a MAVLink 2 signing key file (mode 0600) from a passphrase read from standard
    /// input: the key is SHA-256 of the passphrase, as MAVProxy's `signing setup PASSPHRASE`
    /// gives the autopilot. Never replaces a file.
    SigningKey {
        /// The key file to create (then set `control.signing_key_file` to it).
        file: PathBuf,
    },
    /// A lab command, handed over to `hubtrack-lab`.
    #[command(external_subcommand)]
    Lab(Vec<OsString>),
}

fn main() {
    hubtrack_runtime::start_tool("hubtrack");
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(a) => supervise::run(a),
        Command::Status { json, listen } => tools::status(json, listen),
        Command::Tap(a) => tools::tap(a),
        Command::Echo(a) => tools::echo(a),
        Command::Config { config, print } => tools::check_config(&config, print),
        Command::Recover { input, output } => tools::recover(&input, output),
        Command::Latency { file, json } => tools::latency(&file, json),
        Command::Log {
            file,
            level,
            stage,
            json,
        } => tools::log(&file, level, &stage, json),
        Command::Replay(a) => hubtrack_supervisor::replay::run(a),
        Command::RawWindow { seconds, wait } => tools::raw_window(seconds, wait),
        Command::SigningKey { file } => tools::signing_key(&file),
        Command::Lab(args) => hand_over_to_lab(&args),
    };
    hubtrack_runtime::exit_with(result);
}

/// Replaces this process with `hubtrack-lab ARGS` (same stdio, signals and exit status).
fn hand_over_to_lab(args: &[OsString]) -> anyhow::Result<()> {
    use std::os::unix::process::CommandExt;
    let name = args.first().and_then(|a| a.to_str()).unwrap_or("");
    if !LAB_COMMANDS.contains(&name) {
        anyhow::bail!(
            "unknown command `{name}`: `hubtrack --help` lists the flight commands, and these lab \
             commands run through hubtrack-lab: {}",
            LAB_COMMANDS.join(", ")
        );
    }
    let exe = std::env::current_exe()?;
    let lab = exe.with_file_name("hubtrack-lab");
    if !lab.is_file() {
        anyhow::bail!(
            "`hubtrack {name}` is a lab command and {} is not installed (build it with \
             `cargo build --release -p hubtrack-lab` and install it beside hubtrack)",
            lab.display()
        );
    }
    // Named `hubtrack` in its own usage and errors, as the operator typed it.
    let err = std::process::Command::new(&lab)
        .arg0("hubtrack")
        .args(args)
        .exec();
    Err(anyhow::anyhow!("cannot start {}: {err}", lab.display()))
}
