//! `hubtrack`: launches and supervises the stage processes, and hosts the operator tools.

mod bench;
mod dataset;
mod detect_cmd;
mod eval;
mod eval_seq;
mod fly;
mod launch;
mod replay;
mod score;
mod supervise;
mod track_cmd;
mod train_ranker;

use anyhow::{bail, Context};
use clap::{Parser, Subcommand};
use hubtrack_capture::synthetic::SyntheticSource;
use hubtrack_runtime::config::ConfigArgs;
use hubtrack_runtime::ipc::{open_node, FrameSubscriber, MsgSubscriber};
use hubtrack_runtime::shutdown::Shutdown;
use hubtrack_types::services::STATUS;
use hubtrack_types::services::SUPERVISOR;
use hubtrack_types::time::monotonic_ns;
use hubtrack_types::StageStatus;
use hubtrack_types::SupervisorStatus;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

#[derive(Parser)]
#[command(
    name = "hubtrack",
    version,
    about = "Find, track and approach a wind-turbine hub: launcher and tools"
)]
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
    /// Print the messages of one result service as JSON lines, like `ros2 topic echo`
    /// (detections, track, setpoints, vehicle, status, clock).
    Echo(EchoArgs),
    /// Render one synthetic frame exactly as the capture stage would publish it.
    Render(RenderArgs),
    /// Detect the hub in photos: one JSON object per image on stdout.
    Detect(detect_cmd::DetectArgs),
    /// Write rendered frames with hub truth as the learned heatmap's training set.
    Dataset(dataset::DatasetArgs),
    /// Detect and track over an image sequence offline: one JSON object per frame on stdout.
    Track(track_cmd::TrackArgs),
    /// Evaluate the detector on photos with truth and on synthetic frames, all modes side by side.
    Eval(eval::EvalArgs),
    /// Fit the learned candidate ranker to `eval --candidates` files; prints the weights as TOML.
    TrainRanker(train_ranker::TrainRankerArgs),
    /// Latency per stage and per hop, and end to end, from the stamps in a recording.
    Latency {
        /// The recording (live or replayed; a cut file is read as far as it goes).
        file: PathBuf,
        /// One JSON object with `stages`, `hops` and `end_to_end`.
        #[arg(long)]
        json: bool,
    },
    /// Compare a simulated flight's detections and track with its truth, per band of distance.
    Diagnose {
        /// A recording with truth (`hubtrack fly --record FILE`, or its replay).
        file: PathBuf,
        /// One JSON object with `bands`, `task_frames` and `last`.
        #[arg(long)]
        json: bool,
    },
    /// Fly seeded simulated approaches through the real processes; a table (or JSON lines) of outcomes.
    Fly(fly::FlyArgs),
    /// Replay a recording's inputs through chosen stages and record their new outputs.
    Replay(replay::ReplayArgs),
    /// Show each stage of the running pipeline: pid, state, uptime, restarts, rates, drops, last error.
    Status {
        /// One JSON object with a `stages` list.
        #[arg(long)]
        json: bool,
        /// How long to listen for heartbeats to measure rates, seconds.
        #[arg(long, default_value_t = 1.0)]
        listen: f64,
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
    /// The whole pipeline pinned to 2 cores with the recorder on: latency, CPU and memory per process.
    Pipeline(bench::PipelineBenchArgs),
}

#[derive(clap::Args)]
pub(crate) struct RunArgs {
    #[command(flatten)]
    pub(crate) config: ConfigArgs,
    /// Recording file (default: a timestamped file in [run].record_dir, printed at start).
    #[arg(long, value_name = "PATH.mcap")]
    pub(crate) record: Option<PathBuf>,
    /// Stop after this many seconds (default: run until Ctrl-C / SIGTERM).
    #[arg(long, value_name = "SECONDS")]
    pub(crate) duration: Option<f64>,
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
struct EchoArgs {
    /// The service: detections, track, setpoints, vehicle, status or clock.
    channel: String,
    /// Stop after this many messages.
    #[arg(long)]
    count: Option<u64>,
    /// Stop after this many seconds.
    #[arg(long)]
    duration: Option<f64>,
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
        Command::Run(a) => supervise::run(a),
        Command::Recover { input, output } => recover(&input, output),
        Command::Tap(a) => tap(a),
        Command::Echo(a) => echo(a),
        Command::Render(a) => render(a),
        Command::Bench(BenchCommand::Frames(a)) => bench::frames(a),
        Command::Bench(BenchCommand::Pipeline(a)) => bench::pipeline(a),
        Command::Detect(a) => detect_cmd::run(a),
        Command::Dataset(a) => dataset::run(a),
        Command::Eval(a) => eval::run(a),
        Command::TrainRanker(a) => train_ranker::run(a),
        Command::Track(a) => track_cmd::run(a),
        Command::Config { config, print } => check_config(&config, print),
        Command::Status { json, listen } => status(json, listen),
        Command::Replay(a) => replay::run(a),
        Command::Fly(a) => fly::run(a),
        Command::Latency { file, json } => latency(&file, json),
        Command::Diagnose { file, json } => diagnose(&file, json),
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

/// Config arguments forwarded to every stage.
pub(crate) fn forwarded(config: &ConfigArgs) -> Vec<String> {
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

pub(crate) fn print_summary(
    elapsed: Duration,
    statuses: &BTreeMap<String, StageStatus>,
    segments: &[PathBuf],
) {
    let secs = elapsed.as_secs_f64();
    println!("\n== hubtrack run summary ({secs:.1} s) ==");
    if let Some(c) = statuses.get("capture") {
        let up = c.publish_ns.saturating_sub(c.started_ns) as f64 / 1e9;
        println!(
            "  capture   {} frames published ({:.1} fps), {} errors{}",
            c.outputs,
            c.outputs as f64 / up.max(1e-9),
            c.errors,
            if c.errors > 0 {
                format!(" (last: {})", c.last_error.as_str())
            } else {
                String::new()
            }
        );
    }
    if let Some(s) = statuses.get("sim") {
        println!(
            "  sim       {} frames rendered, {} setpoints seen, {} errors",
            s.outputs, s.inputs, s.errors
        );
    }
    for stage in ["detect", "track", "control"] {
        if let Some(s) = statuses.get(stage) {
            println!(
                "  {stage:<9} {} in, {} out, {} skipped, {} errors",
                s.inputs, s.outputs, s.skipped, s.errors
            );
        }
    }
    if let Some(r) = statuses.get("recorder") {
        println!(
            "  recorder  {} frames received, {} recorded, {} dropped (disk behind or lost in shared memory){}",
            r.inputs,
            r.outputs,
            r.dropped,
            if segments.len() > 1 { " (last segment)" } else { "" }
        );
    }
    for path in segments {
        match hubtrack_record::inspect(path) {
            Ok(info) => {
                println!(
                    "  file      {} ({:.1} MB, {})",
                    path.display(),
                    info.size_bytes as f64 / 1e6,
                    if info.finished {
                        "finished"
                    } else {
                        "NOT finished: run `hubtrack recover` on it"
                    }
                );
                let channels: Vec<String> = info
                    .topic_counts
                    .iter()
                    .map(|(t, n)| format!("{t} {n}"))
                    .collect();
                println!("  channels  {}", channels.join(", "));
            }
            Err(e) => println!("  file      {} unreadable: {e}", path.display()),
        }
    }
    if let Some(path) = segments.first() {
        println!(
            "  open it   in Foxglove or Lichtblick (Open local file), or `hubtrack latency {}`",
            path.display()
        );
    }
}

/// `hubtrack-YYYYmmdd-HHMMSS.mcap` in UTC.
pub(crate) fn timestamped_name() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
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
    format!(
        "hubtrack-{y:04}{m:02}{d:02}-{:02}{:02}{:02}.mcap",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
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
        if report.input_complete {
            " (the input was complete)"
        } else {
            " (the input was cut short)"
        }
    );
    if let Some(why) = report.stopped_by {
        println!("reading stopped at: {why}");
    }
    Ok(())
}

fn status(json: bool, listen: f64) -> anyhow::Result<()> {
    let node = open_node("status")?;
    let sup_sub = MsgSubscriber::<SupervisorStatus>::new(&node, &SUPERVISOR, 4)?;
    let hb_sub = MsgSubscriber::<StageStatus>::new(&node, &STATUS, 64)?;
    let mut sup: Option<SupervisorStatus> = None;
    let mut first: BTreeMap<String, StageStatus> = BTreeMap::new();
    let mut last: BTreeMap<String, StageStatus> = BTreeMap::new();
    let t0 = Instant::now();
    while t0.elapsed().as_secs_f64() < listen.max(0.3) {
        hb_sub.wait(Duration::from_millis(20));
        if let Some(s) = sup_sub.receive_newest()? {
            sup = Some(s);
        }
        while let Some(hb) = hb_sub.receive()? {
            let name = hb.stage.as_str().to_string();
            // A restarted stage (new pid) starts its counters again.
            if first.get(&name).is_none_or(|f| f.pid != hb.pid) {
                first.insert(name.clone(), hb);
            }
            last.insert(name, hb);
        }
    }
    let now = monotonic_ns();
    let mut stages = Vec::new();
    let names: Vec<String> = match &sup {
        Some(s) => s.stages[..s.stage_count as usize]
            .iter()
            .map(|x| x.name.as_str().to_string())
            .collect(),
        None => last.keys().cloned().collect(),
    };
    for name in names {
        let sv = sup
            .as_ref()
            .and_then(|s| s.stages.iter().find(|x| x.name.as_str() == name))
            .copied();
        let hb = last.get(&name).copied();
        let rate = |f: fn(&StageStatus) -> u64| -> Option<f64> {
            let (a, b) = (first.get(&name)?, last.get(&name)?);
            let dt = b.publish_ns.saturating_sub(a.publish_ns) as f64 / 1e9;
            (dt > 0.0).then(|| f(b).saturating_sub(f(a)) as f64 / dt)
        };
        let pid = sv.map(|s| s.pid).or(hb.map(|h| h.pid)).unwrap_or(0);
        let started = sv
            .map(|s| s.started_ns)
            .filter(|n| *n > 0)
            .or(hb.map(|h| h.started_ns));
        let state = sv.map_or(
            if hb.is_some() {
                "running".to_string()
            } else {
                "unknown".into()
            },
            |s| {
                serde_json::to_value(s.state)
                    .ok()
                    .and_then(|v| v.as_str().map(String::from))
                    .unwrap_or_default()
            },
        );
        stages.push(serde_json::json!({
            "name": name, "pid": pid, "state": state,
            "restarts": sv.map_or(0, |s| s.restarts),
            "uptime_s": started.map(|s| now.saturating_sub(s) as f64 / 1e9),
            "inputs_per_s": rate(|h| h.inputs), "outputs_per_s": rate(|h| h.outputs),
            "inputs": hb.map(|h| h.inputs), "outputs": hb.map(|h| h.outputs),
            "skipped": hb.map(|h| h.skipped), "dropped": hb.map(|h| h.dropped), "errors": hb.map(|h| h.errors),
            "last_error": hb.map(|h| h.last_error.as_str().to_string()).filter(|e| !e.is_empty())
                .or(sv.map(|s| s.last_reason.as_str().to_string()).filter(|e| !e.is_empty())),
        }));
    }
    if sup.is_none() && stages.is_empty() {
        bail!(
            "no hubtrack pipeline is running in this IPC domain (HUBTRACK_DOMAIN={})",
            std::env::var(hubtrack_runtime::ipc::DOMAIN_ENV).unwrap_or_default()
        );
    }
    let report = serde_json::json!({"supervisor_pid": sup.map(|s| s.pid), "stages": stages});
    if json {
        println!("{report}");
        return Ok(());
    }
    println!(
        "{:<10}{:>8}{:>12}{:>10}{:>10}{:>10}{:>10}{:>9}{:>8}  last error",
        "stage", "pid", "state", "uptime s", "restarts", "in/s", "out/s", "dropped", "errors"
    );
    let f = |v: &serde_json::Value| v.as_f64().map_or("-".into(), |x| format!("{x:.1}"));
    let n = |v: &serde_json::Value| v.as_u64().map_or("-".into(), |x| x.to_string());
    for s in report["stages"].as_array().into_iter().flatten() {
        println!(
            "{:<10}{:>8}{:>12}{:>10}{:>10}{:>10}{:>10}{:>9}{:>8}  {}",
            s["name"].as_str().unwrap_or(""),
            n(&s["pid"]),
            s["state"].as_str().unwrap_or(""),
            f(&s["uptime_s"]),
            n(&s["restarts"]),
            f(&s["inputs_per_s"]),
            f(&s["outputs_per_s"]),
            n(&s["dropped"]),
            n(&s["errors"]),
            s["last_error"].as_str().unwrap_or("")
        );
    }
    Ok(())
}

fn check_config(args: &ConfigArgs, print: bool) -> anyhow::Result<()> {
    let config = args.load()?;
    if print {
        print!("{}", toml::to_string(&config)?);
    } else {
        println!(
            "{}: ok",
            args.config
                .as_ref()
                .map_or("built-in defaults".into(), |p| p.display().to_string())
        );
    }
    Ok(())
}

/// Prints a recording's report: one JSON object, or a title line and the table.
fn show<R: serde::Serialize>(
    report: &R,
    json: bool,
    title: String,
    table: fn(&R),
) -> anyhow::Result<()> {
    if json {
        println!("{}", serde_json::to_string(report)?);
    } else {
        println!("{title}");
        table(report);
    }
    Ok(())
}

fn latency(file: &Path, json: bool) -> anyhow::Result<()> {
    let report = hubtrack_record::latency::analyze(file)?;
    show(
        &report,
        json,
        format!("latency from the stamps in {}", file.display()),
        hubtrack_record::latency::print,
    )
}

fn diagnose(file: &Path, json: bool) -> anyhow::Result<()> {
    let report = hubtrack_record::flight::analyze(file)?;
    show(
        &report,
        json,
        format!(
            "{} against its truth, per band of true distance",
            file.display()
        ),
        hubtrack_record::flight::print,
    )
}

fn tap(args: TapArgs) -> anyhow::Result<()> {
    let shutdown = Shutdown::install()?;
    let node = open_node("tap")?;
    let mut frames = FrameSubscriber::new(&node, if args.newest { 1 } else { usize::MAX })?;
    let t0 = Instant::now();
    let mut n = 0u64;
    while !shutdown.requested() {
        if args.count.is_some_and(|c| n >= c)
            || args
                .duration
                .is_some_and(|d| t0.elapsed().as_secs_f64() >= d)
        {
            break;
        }
        frames.wait(Duration::from_millis(20));
        loop {
            let sample = if args.newest {
                frames.receive_newest()?
            } else {
                frames.receive()?
            };
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

fn echo(args: EchoArgs) -> anyhow::Result<()> {
    use hubtrack_types::services::{CLOCK, DETECTIONS, SETPOINTS, TRACK, VEHICLE};
    match args.channel.as_str() {
        "detections" => echo_service::<hubtrack_types::Detection>(&DETECTIONS, &args),
        "track" => echo_service::<hubtrack_types::TrackState>(&TRACK, &args),
        "setpoints" => echo_service::<hubtrack_types::Setpoint>(&SETPOINTS, &args),
        "vehicle" => echo_service::<hubtrack_types::VehicleState>(&VEHICLE, &args),
        "status" => echo_service::<StageStatus>(&STATUS, &args),
        "clock" => echo_service::<hubtrack_types::SimClock>(&CLOCK, &args),
        other => bail!("unknown channel {other:?}: one of detections, track, setpoints, vehicle, status, clock"),
    }
}

fn echo_service<T>(
    spec: &hubtrack_types::services::ServiceSpec,
    args: &EchoArgs,
) -> anyhow::Result<()>
where
    T: std::fmt::Debug + Copy + serde::Serialize + iceoryx2::prelude::ZeroCopySend + 'static,
{
    use std::io::Write;
    let shutdown = Shutdown::install()?;
    let node = open_node("echo")?;
    let sub = MsgSubscriber::<T>::new(&node, spec, 64)?;
    let t0 = Instant::now();
    let mut n = 0u64;
    let mut out = std::io::stdout().lock();
    while !shutdown.requested()
        && !args
            .duration
            .is_some_and(|d| t0.elapsed().as_secs_f64() >= d)
    {
        sub.wait(Duration::from_millis(20));
        while let Some(msg) = sub.receive()? {
            writeln!(out, "{}", serde_json::to_string(&msg)?)?;
            n += 1;
            if args.count.is_some_and(|c| n >= c) {
                return Ok(());
            }
        }
        out.flush()?;
    }
    Ok(())
}

fn render(args: RenderArgs) -> anyhow::Result<()> {
    use opencv::prelude::*;
    let config = args.config.load()?;
    let mut source = SyntheticSource::new(&config.capture.synthetic, config.capture.fps)?;
    let (w, h) = source.size();
    let mut pixels = vec![0u8; w as usize * h as usize * 3];
    let ext = args
        .out
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let mut video = if ext == "avi" {
        let fourcc = opencv::videoio::VideoWriter::fourcc('M', 'J', 'P', 'G')?;
        let name = args.out.to_str().context("output path is not UTF-8")?;
        let writer = opencv::videoio::VideoWriter::new_def(
            name,
            fourcc,
            config.capture.fps,
            opencv::core::Size::new(w as i32, h as i32),
        )?;
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
            std::fs::write(&args.out, &pixels)
                .with_context(|| format!("writing {}", args.out.display()))?;
        }
        let t = hubtrack_capture::synthetic::frame_truth(&truth);
        println!(
            "{}",
            serde_json::json!({"seq": seq, "width": w, "height": h, "out": args.out, "truth": t})
        );
    }
    if let Some(mut writer) = video {
        writer.release()?;
    }
    Ok(())
}
