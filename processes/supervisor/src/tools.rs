//! The operator's commands on a running pipeline and on recordings: `status`, `tap`, `echo`,
//! `raw-window`, `recover`, `latency`, `config`.

use crate::config_check;
use anyhow::bail;
use hubtrack_runtime::config::ConfigArgs;
use hubtrack_runtime::ipc::{open_node, FrameSubscriber, MsgPublisher, MsgSubscriber};
use hubtrack_runtime::shutdown::Shutdown;
use hubtrack_types::services::{RAW_WINDOW, STATUS, SUPERVISOR};
use hubtrack_types::time::monotonic_ns;
use hubtrack_types::{LogLevel, RawWindowRequest, StageStatus, SupervisorStatus};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// `hubtrack tap`'s options.
#[derive(clap::Args)]
pub struct TapArgs {
    /// Stop after this many frames.
    #[arg(long)]
    pub count: Option<u64>,
    /// Stop after this many seconds.
    #[arg(long, value_parser = hubtrack_runtime::cli::seconds)]
    pub duration: Option<f64>,
    /// Take only the newest frame each time (like the detector) instead of every frame in order.
    #[arg(long)]
    pub newest: bool,
}

/// `hubtrack echo`'s options.
#[derive(clap::Args)]
pub struct EchoArgs {
    /// The service: detections, track, setpoints, vehicle, status or clock.
    pub channel: String,
    /// Stop after this many messages.
    #[arg(long)]
    pub count: Option<u64>,
    /// Stop after this many seconds.
    #[arg(long, value_parser = hubtrack_runtime::cli::seconds)]
    pub duration: Option<f64>,
}

/// `hubtrack recover`: copies every intact message of a damaged recording into a new file.
/// Fails (exit status 1) when the input is not MCAP or nothing could be recovered; says whether
/// the input was complete, cut short or damaged (and where reading stopped).
pub fn recover(input: &Path, output: Option<PathBuf>) -> anyhow::Result<()> {
    let output = output.unwrap_or_else(|| input.with_extension("recovered.mcap"));
    if output.exists() {
        bail!(
            "output {} already exists (recover never replaces a file)",
            output.display()
        );
    }
    let report = hubtrack_record::recover(input, &output)?;
    if report.messages == 0 {
        let _ = std::fs::remove_file(&output);
        bail!(
            "no message could be recovered from {}{}",
            input.display(),
            report
                .stopped_by
                .map_or(String::new(), |why| format!(" (reading stopped: {why})"))
        );
    }
    println!(
        "recovered {} messages from {} into {}{}",
        report.messages,
        input.display(),
        output.display(),
        match (
            &report.stopped_by,
            report.input_complete,
            &report.summary_damage
        ) {
            (_, true, _) => " (the input was complete)".to_string(),
            (Some(_), _, _) => " (the input is damaged or cut short: the rest is lost)".to_string(),
            (None, false, Some(damage)) => format!(
                " (every message of the input's data section; the input was damaged: {damage})"
            ),
            (None, false, None) => " (the input was cut short)".to_string(),
        }
    );
    if let Some(why) = report.stopped_by {
        println!("reading stopped at: {why}");
    }
    Ok(())
}

/// `hubtrack status`: each stage of the running pipeline, from the supervisor and the heartbeats.
pub fn status(json: bool, listen: f64) -> anyhow::Result<()> {
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

/// `hubtrack config`: checks every section of the configuration, or prints them all.
pub fn check_config(args: &ConfigArgs, print: bool) -> anyhow::Result<()> {
    if print {
        print!("{}", config_check::print(args)?);
    } else {
        config_check::check(args, config_check::Scope::All)?;
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
pub fn show<R: serde::Serialize>(
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

/// `hubtrack latency`: latency per stage and hop from the stamps in a recording.
pub fn latency(file: &Path, json: bool) -> anyhow::Result<()> {
    let report = hubtrack_record::latency::analyze(file)?;
    show(
        &report,
        json,
        format!("latency from the stamps in {}", file.display()),
        hubtrack_record::latency::print,
    )
}

/// `hubtrack log --level`: the least level printed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum LogLevelArg {
    /// Everything.
    Debug,
    /// Info and up.
    Info,
    /// Warnings and errors.
    Warning,
    /// Errors only.
    Error,
}

impl LogLevelArg {
    /// The `foxglove.Log.Level` number of this level.
    fn number(self) -> i32 {
        match self {
            LogLevelArg::Debug => LogLevel::Debug as i32,
            LogLevelArg::Info => LogLevel::Info as i32,
            LogLevelArg::Warning => LogLevel::Warning as i32,
            LogLevelArg::Error => LogLevel::Error as i32,
        }
    }
}

/// `hubtrack log`: the recording's log lines, one per line as the journal shows them (the wall
/// time they were logged, UTC), or as JSON.
pub fn log(file: &Path, least: LogLevelArg, stages: &[String], json: bool) -> anyhow::Result<()> {
    use hubtrack_record::log::{level_name, read};
    let mut read = read(file)?;
    if read.lines.is_empty() && read.undecodable == 0 {
        anyhow::bail!(
            "{} holds no log lines (`/log`: recordings made before it, or by a recorder that \
             ran alone, have none){}",
            file.display(),
            read.stopped
                .as_ref()
                .map_or(String::new(), |s| format!("; reading stopped: {s}"))
        );
    }
    // In the order they were logged: a recorder started after a stage records that stage's
    // first lines when it subscribes (the service's history), after its own.
    let time_ns = |l: &hubtrack_record::log::Log| {
        l.timestamp
            .map_or(0, |t| t.seconds as i128 * 1_000_000_000 + t.nanos as i128)
    };
    read.lines.sort_by_key(time_ns);
    for line in read
        .lines
        .iter()
        .filter(|l| l.level >= least.number() && (stages.is_empty() || stages.contains(&l.name)))
    {
        let ns = time_ns(line);
        if json {
            println!(
                "{}",
                serde_json::json!({"time_ns": ns, "level": level_name(line.level),
                    "stage": line.name, "file": line.file, "line": line.line,
                    "message": line.message})
            );
        } else {
            let time = jiff::Timestamp::from_nanosecond(ns)
                .map_or_else(|_| format!("{ns} ns"), |t| format!("{t:.3}"));
            let level = match level_name(line.level) {
                "WARNING" => "WARN",
                other => other,
            };
            println!("{time} {level:5} {}: {}", line.name, line.message);
        }
    }
    if read.undecodable > 0 {
        eprintln!(
            "note: {} log lines did not decode and were skipped",
            read.undecodable
        );
    }
    if let Some(why) = &read.stopped {
        eprintln!(
            "note: {} is cut or damaged; its lines up to there are shown (reading stopped: {why})",
            file.display()
        );
    }
    Ok(())
}

/// `hubtrack tap`: one JSON line per frame received on the frames service.
pub fn tap(args: TapArgs) -> anyhow::Result<()> {
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

/// `hubtrack echo`: the messages of one result service as JSON lines.
pub fn echo(args: EchoArgs) -> anyhow::Result<()> {
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

/// Longest passphrase read from standard input, bytes (MAVProxy takes any length; a bound keeps
/// `hubtrack signing-key < /dev/zero` from reading forever).
const MAX_PASSPHRASE_BYTES: u64 = 4096;

/// `hubtrack signing-key FILE`: the key of the passphrase on standard input's first line, written
/// as 64 hex digits with mode 0600.
pub fn signing_key(file: &Path) -> anyhow::Result<()> {
    use std::io::Read;
    let mut input = Vec::new();
    std::io::stdin()
        .take(MAX_PASSPHRASE_BYTES + 1)
        .read_to_end(&mut input)?;
    if input.len() as u64 > MAX_PASSPHRASE_BYTES {
        bail!("passphrase longer than {MAX_PASSPHRASE_BYTES} bytes");
    }
    let text = String::from_utf8(input)
        .map_err(|_| anyhow::anyhow!("the passphrase on standard input is not UTF-8 text"))?;
    let passphrase = text.lines().next().unwrap_or("");
    if passphrase.is_empty() {
        bail!(
            "no passphrase on standard input (e.g. `hubtrack signing-key {} < passphrase.txt`)",
            file.display()
        );
    }
    hubtrack_mavlink::SigningKey::from_passphrase(passphrase).save(file)?;
    eprintln!(
        "wrote {} (mode 0600); give the autopilot the same passphrase (MAVProxy: signing setup PASSPHRASE)",
        file.display()
    );
    Ok(())
}

/// How often `raw-window` tries to reach a recorder while it waits for one.
const RAW_WINDOW_RETRY: Duration = Duration::from_millis(100);
/// How long `raw-window` keeps its request alive after sending it.
const RAW_WINDOW_HOLD: Duration = Duration::from_millis(500);

/// `hubtrack raw-window`: sends one request to the running recorder (its log and `/recorder`'s
/// `frames_raw_copies` show the window); an error when no recorder listens within `wait_s`.
pub fn raw_window(seconds: Option<f64>, wait_s: f64) -> anyhow::Result<()> {
    let node = open_node("raw-window")?;
    let publisher = MsgPublisher::<RawWindowRequest>::new(&node, &RAW_WINDOW)?;
    let deadline = Instant::now() + Duration::from_secs_f64(wait_s);
    loop {
        let request = RawWindowRequest {
            seconds: seconds.unwrap_or(0.0),
            publish_ns: monotonic_ns(),
        };
        if publisher.publish(request)? > 0 {
            // A sample lives in its publisher's memory: held until the recorder, which polls
            // every few milliseconds, has taken it.
            std::thread::sleep(RAW_WINDOW_HOLD);
            match seconds {
                Some(s) => println!("asked the recorder for a raw window of {s} s"),
                None => println!("asked the recorder for a raw window (recorder.raw_window_s)"),
            }
            return Ok(());
        }
        if Instant::now() >= deadline {
            bail!(
                "no recorder is running (nothing subscribed to {} within {wait_s} s): start the \
                 pipeline with `hubtrack run` and recording on",
                RAW_WINDOW.name
            );
        }
        std::thread::sleep(RAW_WINDOW_RETRY);
    }
}
