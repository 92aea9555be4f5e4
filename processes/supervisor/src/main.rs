//! `hubtrack`: launches and supervises the stage processes, and hosts the operator tools.

mod bench;
mod detect_cmd;
mod eval;
mod launch;
mod score;
mod track_cmd;

use anyhow::{bail, Context};
use clap::{Parser, Subcommand};
use hubtrack_capture::synthetic::SyntheticSource;
use hubtrack_runtime::config::ConfigArgs;
use hubtrack_runtime::ipc::{open_node, FrameSubscriber, MsgSubscriber};
use hubtrack_runtime::shutdown::Shutdown;
use hubtrack_types::services::STATUS;
use hubtrack_types::time::monotonic_ns;
use hubtrack_types::StageStatus;
use launch::{stage_binary, Stage};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Canonical start order; stages stop in reverse (control first, recorder last, so the vehicle is
/// told to hold first and the recording sees everything).
const PIPELINE_ORDER: &[&str] = &["recorder", "capture", "detect", "track"];
/// Supervisor loop period.
const TICK: Duration = Duration::from_millis(50);

#[derive(Parser)]
#[command(name = "hubtrack", version, about = "Find, track and approach a wind-turbine hub: launcher and tools")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Start the configured stages as separate processes, record every service to MCAP.
    Run(RunArgs),
    /// Copy every readable message of a damaged recording (e.g. after kill -9) into a new, complete file.
    Recover {
        /// The damaged recording.
        input: PathBuf,
        /// Output file (default: <input>.recovered.mcap).
        output: Option<PathBuf>,
    },
    /// Subscribe to the frames service and print one JSON line per frame received.
    Tap(TapArgs),
    /// Render one synthetic frame exactly as the capture stage would publish it.
    Render(RenderArgs),
    /// Detect the hub in photos: one JSON object per image on stdout.
    Detect(detect_cmd::DetectArgs),
    /// Detect and track over an image sequence offline: one JSON object per frame on stdout.
    Track(track_cmd::TrackArgs),
    /// Evaluate the detector on photos with truth and on synthetic frames, all modes side by side.
    Eval(eval::EvalArgs),
    /// Latency per stage and per hop, and end to end, from the stamps in a recording.
    Latency {
        /// The recording (live or replayed; a cut file is read as far as it goes).
        file: PathBuf,
        /// One JSON object with `stages`, `hops` and `end_to_end`.
        #[arg(long)]
        json: bool,
    },
    /// Check a config file (exit 1 with the offending key), or print the defaults as TOML.
    Config {
        #[command(flatten)]
        config: ConfigArgs,
        /// Print the complete configuration (file + overrides, or the defaults) as TOML.
        #[arg(long)]
        print: bool,
    },
    /// Benchmarks (commands that print a table; compare columns within one run).
    #[command(subcommand)]
    Bench(BenchCommand),
}

#[derive(Subcommand)]
enum BenchCommand {
    /// The frames hop over iceoryx2 across real processes vs a Unix-socket copy; renderer cost.
    Frames(bench::FramesBenchArgs),
}

#[derive(clap::Args)]
struct RunArgs {
    #[command(flatten)]
    config: ConfigArgs,
    /// Recording file (default: a timestamped file in [run].record_dir, printed at start).
    #[arg(long, value_name = "PATH.mcap")]
    record: Option<PathBuf>,
    /// Stop after this many seconds (default: run until Ctrl-C / SIGTERM).
    #[arg(long, value_name = "SECONDS")]
    duration: Option<f64>,
}

#[derive(clap::Args)]
struct TapArgs {
    /// Stop after this many frames.
    #[arg(long)]
    count: Option<u64>,
    /// Stop after this many seconds.
    #[arg(long)]
    duration: Option<f64>,
    /// Take only the newest frame each time (like the detector) instead of every frame in order.
    #[arg(long)]
    newest: bool,
}

#[derive(clap::Args)]
struct RenderArgs {
    #[command(flatten)]
    config: ConfigArgs,
    /// Frame sequence number to render (the first one with --frames).
    #[arg(long, default_value_t = 0)]
    seq: u64,
    /// Number of frames: with an `.avi` output, a Motion-JPEG clip; with a folder, one PNG each.
    #[arg(long, default_value_t = 1)]
    frames: u64,
    /// Output: `.png`/`.jpg` an image, `.avi` a video, an existing folder PNGs, anything else raw BGR8 bytes.
    #[arg(long, short = 'o')]
    out: PathBuf,
}

fn main() {
    // Die quietly on a closed pipe (`hubtrack detect ... | head`), as Unix tools do.
    // SAFETY: resetting a signal disposition at start, before any thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    hubtrack_runtime::logging::init("hubtrack");
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(a) => run(a),
        Command::Recover { input, output } => recover(&input, output),
        Command::Tap(a) => tap(a),
        Command::Render(a) => render(a),
        Command::Bench(BenchCommand::Frames(a)) => bench::frames(a),
        Command::Detect(a) => detect_cmd::run(a),
        Command::Eval(a) => eval::run(a),
        Command::Track(a) => track_cmd::run(a),
        Command::Config { config, print } => check_config(&config, print),
        Command::Latency { file, json } => latency(&file, json),
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

/// Config arguments forwarded to every stage.
fn forwarded(config: &ConfigArgs) -> Vec<String> {
    let mut args = Vec::new();
    if let Some(c) = &config.config {
        args.push("--config".into());
        args.push(c.display().to_string());
    }
    for o in &config.overrides {
        args.push("--set".into());
        args.push(o.clone());
    }
    args
}

fn run(args: RunArgs) -> anyhow::Result<()> {
    let config = args.config.load()?;
    let record = args.record.clone().unwrap_or_else(|| config.run.record_dir.join(timestamped_name()));
    let shutdown = Shutdown::install()?;
    let node = open_node("supervisor")?;
    let status_sub = MsgSubscriber::<StageStatus>::new(&node, &STATUS, 64)?;
    let mut statuses: BTreeMap<String, StageStatus> = BTreeMap::new();
    let drain = |statuses: &mut BTreeMap<String, StageStatus>| -> anyhow::Result<()> {
        while let Some(s) = status_sub.receive()? {
            statuses.insert(s.stage.as_str().to_string(), s);
        }
        Ok(())
    };

    let order: Vec<&str> = PIPELINE_ORDER.iter().copied().filter(|s| config.run.stages.iter().any(|c| c == s)).collect();
    let binaries = order.iter().map(|s| stage_binary(s)).collect::<anyhow::Result<Vec<_>>>()?;
    println!("hubtrack run: stages {}; recording to {}", order.join(", "), record.display());

    let mut stages: Vec<Stage> = Vec::new();
    let startup = Duration::from_millis(config.run.startup_timeout_ms);
    let mut failure: Option<String> = None;
    for (name, bin) in order.iter().zip(&binaries) {
        let mut stage_args = forwarded(&args.config);
        if *name == "recorder" {
            stage_args.push("--output".into());
            stage_args.push(record.display().to_string());
        }
        let mut stage = Stage::spawn(name, bin, &stage_args)?;
        log::info!("started {name} (pid {})", stage.pid());
        // Ready = its first heartbeat: its ports exist, so nothing published after this is missed.
        let t0 = Instant::now();
        loop {
            drain(&mut statuses)?;
            if statuses.get(*name).is_some_and(|s| s.pid == stage.pid()) {
                break;
            }
            if let Some(st) = stage.poll() {
                failure = Some(format!("stage {name} exited during start-up ({st})"));
                break;
            }
            if t0.elapsed() > startup || shutdown.requested() {
                failure = Some(format!("stage {name} sent no heartbeat within {startup:?}"));
                break;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        stages.push(stage);
        if failure.is_some() {
            break;
        }
    }

    let started = Instant::now();
    let deadline = args.duration.map(Duration::from_secs_f64);
    while failure.is_none() && !shutdown.requested() {
        if deadline.is_some_and(|d| started.elapsed() >= d) {
            break;
        }
        std::thread::sleep(TICK);
        drain(&mut statuses)?;
        if let Some(s) = stages.iter_mut().find_map(|s| s.poll().is_some().then_some(s)) {
            let st = s.exited.expect("polled");
            if st.success() {
                log::info!("{} finished", s.name);
            } else {
                failure = Some(format!("stage {} exited ({st})", s.name));
            }
            break;
        }
    }
    let elapsed = started.elapsed();

    let timeout = Duration::from_millis(config.run.stop_timeout_ms);
    for stage in stages.iter_mut().rev() {
        let was_running = stage.exited.is_none();
        let st = stage.stop(timeout);
        if was_running {
            log::info!(
                "stopped {} after {:.1} s ({})",
                stage.name,
                stage.started.elapsed().as_secs_f64(),
                st.map_or("unknown".into(), |s| s.to_string())
            );
        }
    }
    // Let the final heartbeats arrive.
    std::thread::sleep(Duration::from_millis(20));
    drain(&mut statuses)?;
    print_summary(elapsed, &statuses, order.contains(&"recorder").then_some(record.as_path()));
    match failure {
        Some(f) => bail!(f),
        None => Ok(()),
    }
}

fn print_summary(elapsed: Duration, statuses: &BTreeMap<String, StageStatus>, record: Option<&Path>) {
    let secs = elapsed.as_secs_f64();
    println!("\n== hubtrack run summary ({secs:.1} s) ==");
    if let Some(c) = statuses.get("capture") {
        println!(
            "  capture   {} frames published ({:.1} fps), {} errors{}",
            c.outputs,
            c.outputs as f64 / secs.max(1e-9),
            c.errors,
            if c.errors > 0 { format!(" (last: {})", c.last_error.as_str()) } else { String::new() }
        );
    }
    if let Some(r) = statuses.get("recorder") {
        println!(
            "  recorder  {} frames received, {} recorded, {} dropped (disk behind or lost in shared memory)",
            r.inputs, r.outputs, r.dropped
        );
    }
    if let Some(path) = record {
        match hubtrack_record::inspect(path) {
            Ok(info) => {
                println!(
                    "  file      {} ({:.1} MB, {})",
                    path.display(),
                    info.size_bytes as f64 / 1e6,
                    if info.finished { "finished" } else { "NOT finished: run `hubtrack recover` on it" }
                );
                let channels: Vec<String> = info.topic_counts.iter().map(|(t, n)| format!("{t} {n}")).collect();
                println!("  channels  {}", channels.join(", "));
                println!("  open it   in Foxglove or Lichtblick (Open local file), or `mcap info {}`", path.display());
            }
            Err(e) => println!("  file      {} unreadable: {e}", path.display()),
        }
    }
}

/// `hubtrack-YYYYmmdd-HHMMSS.mcap` in UTC.
fn timestamped_name() -> String {
    let secs = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs());
    let (days, rem) = (secs / 86_400, secs % 86_400);
    // Civil-from-days (Howard Hinnant's algorithm), proleptic Gregorian, UTC.
    let z = days as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("hubtrack-{y:04}{m:02}{d:02}-{:02}{:02}{:02}.mcap", rem / 3600, rem % 3600 / 60, rem % 60)
}

fn recover(input: &Path, output: Option<PathBuf>) -> anyhow::Result<()> {
    let output = output.unwrap_or_else(|| input.with_extension("recovered.mcap"));
    if output.exists() {
        bail!("output {} already exists", output.display());
    }
    let report = hubtrack_record::recover(input, &output)?;
    println!(
        "recovered {} messages from {} into {}{}",
        report.messages,
        input.display(),
        output.display(),
        if report.input_complete { " (the input was complete)" } else { " (the input was cut short)" }
    );
    if let Some(why) = report.stopped_by {
        println!("reading stopped at: {why}");
    }
    Ok(())
}

fn check_config(args: &ConfigArgs, print: bool) -> anyhow::Result<()> {
    let config = args.load()?;
    if print {
        print!("{}", toml::to_string(&config)?);
    } else {
        println!("{}: ok", args.config.as_ref().map_or("built-in defaults".into(), |p| p.display().to_string()));
    }
    Ok(())
}

fn latency(file: &Path, json: bool) -> anyhow::Result<()> {
    let report = hubtrack_record::latency::analyze(file)?;
    if json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        println!("latency from the stamps in {}", file.display());
        hubtrack_record::latency::print(&report);
    }
    Ok(())
}

fn tap(args: TapArgs) -> anyhow::Result<()> {
    let shutdown = Shutdown::install()?;
    let node = open_node("tap")?;
    let mut frames = FrameSubscriber::new(&node, if args.newest { 1 } else { usize::MAX })?;
    let t0 = Instant::now();
    let mut n = 0u64;
    while !shutdown.requested() {
        if args.count.is_some_and(|c| n >= c) || args.duration.is_some_and(|d| t0.elapsed().as_secs_f64() >= d) {
            break;
        }
        frames.wait(Duration::from_millis(20));
        loop {
            let sample = if args.newest { frames.receive_newest()? } else { frames.receive()? };
            let Some(sample) = sample else { break };
            let recv_ns = monotonic_ns();
            let h = sample.user_header();
            println!(
                "{}",
                serde_json::json!({
                    "seq": h.seq, "width": h.width, "height": h.height, "stride": h.stride,
                    "bytes": sample.payload().len(), "capture_ns": h.capture_ns, "publish_ns": h.publish_ns,
                    "recv_ns": recv_ns, "latency_us": (recv_ns.saturating_sub(h.publish_ns)) as f64 / 1e3,
                    "skipped": frames.skipped, "lost": frames.lost,
                })
            );
            n += 1;
            if args.count.is_some_and(|c| n >= c) {
                break;
            }
        }
    }
    Ok(())
}

fn render(args: RenderArgs) -> anyhow::Result<()> {
    use opencv::prelude::*;
    let config = args.config.load()?;
    let mut source = SyntheticSource::new(&config.capture.synthetic, config.capture.fps)?;
    let (w, h) = source.size();
    let mut pixels = vec![0u8; w as usize * h as usize * 3];
    let ext = args.out.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    let mut video = if ext == "avi" {
        let fourcc = opencv::videoio::VideoWriter::fourcc('M', 'J', 'P', 'G')?;
        let name = args.out.to_str().context("output path is not UTF-8")?;
        let writer = opencv::videoio::VideoWriter::new_def(name, fourcc, config.capture.fps, opencv::core::Size::new(w as i32, h as i32))?;
        if !writer.is_opened()? {
            bail!("cannot write video {}", args.out.display());
        }
        Some(writer)
    } else {
        None
    };
    for seq in args.seq..args.seq + args.frames {
        let truth = source.render_index(seq, &mut pixels)?;
        if let Some(writer) = video.as_mut() {
            let flat = Mat::new_rows_cols_with_data(h as i32, (w * 3) as i32, &pixels)?;
            writer.write(&flat.reshape(3, h as i32)?)?;
        } else if args.out.is_dir() {
            let path = args.out.join(format!("frame_{seq:06}.png"));
            hubtrack_capture::convert::write_bgr_image(&path, w, h, &pixels)?;
        } else if ["png", "jpg", "jpeg", "bmp"].contains(&ext.as_str()) {
            hubtrack_capture::convert::write_bgr_image(&args.out, w, h, &pixels)?;
        } else {
            std::fs::write(&args.out, &pixels).with_context(|| format!("writing {}", args.out.display()))?;
        }
        let t = hubtrack_capture::synthetic::frame_truth(&truth);
        println!("{}", serde_json::json!({"seq": seq, "width": w, "height": h, "out": args.out, "truth": t}));
    }
    if let Some(mut writer) = video {
        writer.release()?;
    }
    Ok(())
}
