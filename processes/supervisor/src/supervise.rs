//! `hubtrack run`: starts the configured stages, keeps them alive by their restart policy, and
//! stops them in order.
//!
//! Each stage is a small state machine: `starting` (until its first heartbeat) → `running` →
//! (exit, or no heartbeat for `liveness_timeout_ms`: killed) → `restarting` after a back-off that
//! doubles inside the crash-loop window → ... → `failed` after `max_restarts` in `window_s`, or
//! `stopped`. One stage's fate never touches another's: the camera keeps streaming while a
//! detector is restarted. A restarted recorder writes the next segment file (`NAME.1.mcap`, ...).

use crate::launch::{signal, stage_binary, Stage};
use anyhow::bail;
use hubtrack_runtime::config::{ConfigArgs, RestartPolicy, RunConfig};
use hubtrack_runtime::ipc::{open_node, MsgPublisher, MsgSubscriber};
use hubtrack_runtime::logging::LogForwarder;
use hubtrack_runtime::shutdown::Shutdown;
use hubtrack_types::services::{STATUS, SUPERVISOR};
use hubtrack_types::time::monotonic_ns;
use hubtrack_types::{
    StageState, StageStatus, SupervisedStage, SupervisorStatus, Text64, MAX_STAGES,
};
use std::collections::{BTreeMap, VecDeque};
use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};
use std::process::ExitStatus;
use std::time::{Duration, Instant};

/// Canonical start order; stages stop in reverse (control first, so the vehicle is told to hold
/// first; recorder last, so the recording sees everything).
/// The simulator starts last: its first frame finds the whole pipeline ready (in lockstep it
/// would otherwise wait for stages still starting), and it stops first. The live view, a
/// reader like the recorder, starts right after the recorder.
pub const PIPELINE_ORDER: &[&str] = &[
    "recorder", "live", "capture", "detect", "track", "control", "sim",
];
/// The stages that publish frames: a run whose frame source is given up on ends.
const FRAME_SOURCES: &[&str] = &["capture", "sim"];
/// Supervisor loop period (bounds restart and liveness reaction time).
const TICK: Duration = Duration::from_millis(20);
/// How often the supervisor publishes its status.
const STATUS_PERIOD: Duration = Duration::from_millis(250);

/// One supervised stage.
struct Supervised {
    name: &'static str,
    binary: PathBuf,
    policy: RestartPolicy,
    process: Option<Stage>,
    state: StageState,
    /// When restarts happened, for the crash-loop window.
    restart_times: VecDeque<Instant>,
    restarts: u32,
    next_start: Option<Instant>,
    last_heartbeat: Option<Instant>,
    last_exit: i32,
    last_reason: String,
    /// Recorder only: segment number of the current file.
    segment: u32,
    /// Times this stage was given up on (it is retried after `retry_after_s`).
    given_up: u32,
    /// Times it exited with an error status of its own (not killed by a signal or for hanging).
    error_exits: u32,
    /// Why it last exited with an error status of its own.
    last_error_exit: String,
}

fn exit_code(st: ExitStatus) -> i32 {
    st.code().unwrap_or_else(|| -st.signal().unwrap_or(0))
}

/// The recording file of segment `n` (0: the path itself; n: `stem.n.mcap`).
pub fn segment_path(record: &Path, n: u32) -> PathBuf {
    if n == 0 {
        return record.to_path_buf();
    }
    let stem = record
        .file_stem()
        .map_or("recording".into(), |s| s.to_string_lossy().into_owned());
    record.with_file_name(format!("{stem}.{n}.mcap"))
}

struct Supervisor {
    config: RunConfig,
    config_args: ConfigArgs,
    record: PathBuf,
    outcome: Option<PathBuf>,
    stage_stdout_to_stderr: bool,
    stages: Vec<Supervised>,
}

/// How to run the pipeline once.
pub struct RunOptions {
    /// The validated `[run]` section (file + overrides).
    pub config: RunConfig,
    /// The same, as forwarded to the stages.
    pub config_args: ConfigArgs,
    /// Recording file (used when the recorder is among the stages).
    pub record: PathBuf,
    /// Stop after this long.
    pub duration: Option<Duration>,
    /// The simulator writes its flight outcome here.
    pub outcome: Option<PathBuf>,
    /// Print the start banner and the summary, and forward stage stdout to stdout. Off for
    /// tools whose stdout is machine-readable (`hubtrack fly --json`): stage output goes to stderr.
    pub interactive: bool,
}

/// What a run left behind.
pub struct RunReport {
    /// Wall-clock duration.
    pub elapsed: Duration,
    /// Why the run ended early with an error, if it did.
    pub failure: Option<String>,
}

impl Supervisor {
    fn args_for(&self, s: &Supervised) -> Vec<String> {
        let mut args = self.config_args.to_args();
        if s.name == "recorder" {
            args.push("--output".into());
            args.push(segment_path(&self.record, s.segment).display().to_string());
        }
        if let (true, Some(outcome)) = (s.name == "sim", &self.outcome) {
            args.push("--outcome".into());
            args.push(outcome.display().to_string());
        }
        args
    }

    fn start(&mut self, i: usize) -> anyhow::Result<()> {
        let args = self.args_for(&self.stages[i]);
        let s = &mut self.stages[i];
        let nice = self.config.nice_of(s.name);
        let stage = Stage::spawn(
            s.name,
            &s.binary,
            &args,
            self.stage_stdout_to_stderr,
            nice,
            self.config.stop_with_supervisor,
        )?;
        log::info!("started {} (pid {}, nice {nice})", s.name, stage.pid());
        s.process = Some(stage);
        s.state = StageState::Starting;
        s.last_heartbeat = None;
        s.next_start = None;
        Ok(())
    }

    /// A stage ended (by itself, or killed for hanging): decide on a restart.
    fn ended(&mut self, i: usize, code: i32, reason: String, failure: bool) {
        let restart = self.config.restart.clone();
        let s = &mut self.stages[i];
        s.process = None;
        s.last_exit = code;
        s.last_reason = reason.clone();
        if code > 0 {
            s.error_exits += 1;
            s.last_error_exit = reason.clone();
        }
        let wanted = match s.policy {
            RestartPolicy::Never => false,
            RestartPolicy::OnFailure => failure,
            RestartPolicy::Always => true,
        };
        if !wanted {
            s.state = StageState::Stopped;
            log::info!(
                "{} ended ({reason}); policy {:?}: not restarted",
                s.name,
                s.policy
            );
            return;
        }
        let now = Instant::now();
        let window = Duration::from_secs_f64(restart.window_s);
        while s
            .restart_times
            .front()
            .is_some_and(|t| now.duration_since(*t) > window)
        {
            s.restart_times.pop_front();
        }
        if s.restart_times.len() as u32 >= restart.max_restarts {
            s.state = StageState::Failed;
            s.given_up += 1;
            let retry = (restart.retry_after_s > 0.0).then(|| {
                // A fresh crash-loop budget for the retry.
                s.restart_times.clear();
                Duration::from_secs_f64(restart.retry_after_s)
            });
            s.next_start = retry.map(|d| now + d);
            log::error!(
                "{} ended ({reason}) {} times within {:.0} s: giving up on it{}; the other stages keep running",
                s.name,
                restart.max_restarts + 1,
                restart.window_s,
                retry.map_or(String::new(), |d| format!(" (trying again in {:.0} s)", d.as_secs_f64()))
            );
            return;
        }
        let backoff = (restart.backoff_initial_ms << s.restart_times.len().min(20))
            .min(restart.backoff_max_ms);
        s.restart_times.push_back(now);
        s.restarts += 1;
        if s.name == "recorder" {
            s.segment += 1;
        }
        s.state = StageState::Restarting;
        s.next_start = Some(now + Duration::from_millis(backoff));
        log::warn!(
            "{} ended ({reason}): restart {} in {backoff} ms",
            s.name,
            s.restarts
        );
    }

    fn status(&self) -> SupervisorStatus {
        let mut out = SupervisorStatus {
            pid: std::process::id(),
            publish_ns: monotonic_ns(),
            ..Default::default()
        };
        for (slot, s) in out.stages.iter_mut().zip(&self.stages) {
            *slot = SupervisedStage {
                name: Text64::new(s.name),
                pid: s.process.as_ref().map_or(0, |p| p.pid()),
                state: s.state,
                restarts: s.restarts,
                started_ns: s.process.as_ref().map_or(0, |p| p.started_ns),
                last_exit: s.last_exit,
                last_reason: Text64::new(&s.last_reason),
            };
        }
        out.stage_count = self.stages.len().min(MAX_STAGES) as u32;
        out
    }
}

/// `hubtrack run`'s options.
#[derive(clap::Args)]
pub struct RunArgs {
    #[command(flatten)]
    /// Config file and overrides, passed on to every stage.
    pub config: ConfigArgs,
    /// Recording file (default: a timestamped file in [run].record_dir, printed at start).
    #[arg(long, value_name = "PATH.mcap")]
    pub record: Option<PathBuf>,
    /// Stop after this many seconds (default: run until Ctrl-C / SIGTERM).
    #[arg(long, value_name = "SECONDS", value_parser = hubtrack_runtime::cli::seconds)]
    pub duration: Option<f64>,
    /// Serve the live view (Foxglove WebSocket) on this address, e.g. `127.0.0.1:8765`; the
    /// same as `--set live.enabled=true --set live.address=ADDR`.
    #[arg(long, value_name = "IP:PORT")]
    pub live: Option<String>,
}

/// `hubtrack run`: runs the pipeline until the duration ends, a signal arrives, or the source
/// (camera or simulated flight) ends.
pub fn run(mut args: RunArgs) -> anyhow::Result<()> {
    if let Some(addr) = &args.live {
        let addr = toml::Value::String(addr.clone()).to_string();
        args.config.overrides.push("live.enabled=true".into());
        args.config.overrides.push(format!("live.address={addr}"));
    }
    let mut stages = args
        .config
        .load::<hubtrack_runtime::config::RunSections>()?
        .run
        .stages;
    let live = args
        .config
        .load::<hubtrack_runtime::config::LiveSections>()?
        .live;
    if live.enabled && !stages.iter().any(|s| s == "live") {
        stages.push("live".into());
    }
    // Every stage checks its own sections before anything starts, so a bad key stops the run
    // here rather than in a crash loop of one stage.
    let mut config =
        crate::config_check::check(&args.config, crate::config_check::Scope::Stages(&stages))?;
    config.stages = stages;
    let record = args
        .record
        .clone()
        .unwrap_or_else(|| config.record_dir.join(crate::summary::timestamped_name()));
    let report = supervise(RunOptions {
        config,
        config_args: args.config.clone(),
        record,
        duration: args.duration.map(Duration::from_secs_f64),
        outcome: None,
        interactive: true,
    })?;
    match report.failure {
        Some(f) => bail!(f),
        None => Ok(()),
    }
}

/// Runs the stages of `opts.config` once; see the module docs.
pub fn supervise(opts: RunOptions) -> anyhow::Result<RunReport> {
    let RunOptions {
        config,
        config_args,
        record,
        duration,
        outcome,
        interactive,
    } = opts;
    // Before anything is started: one supervisor per IPC domain, no stage of a killed one left.
    let _lock = crate::instance::claim_domain()?;
    let shutdown = Shutdown::install()?;
    let node = open_node("supervisor")?;
    let heartbeats = MsgSubscriber::<StageStatus>::new(&node, &STATUS, 64)?;
    let status_pub = MsgPublisher::<SupervisorStatus>::new(&node, &SUPERVISOR)?;
    // What the supervisor says of the stages (starts, crashes, restarts) goes into the recording.
    let mut logs = LogForwarder::new(&node, "supervisor")?;
    let mut last_status: BTreeMap<String, StageStatus> = BTreeMap::new();

    let names: Vec<&'static str> = PIPELINE_ORDER
        .iter()
        .copied()
        .filter(|s| config.stages.iter().any(|c| c == s))
        .collect();
    let mut stages = Vec::new();
    for name in &names {
        stages.push(Supervised {
            name,
            binary: stage_binary(name)?,
            policy: config.restart.policy_of(name),
            process: None,
            state: StageState::Stopped,
            restart_times: VecDeque::new(),
            restarts: 0,
            next_start: None,
            last_heartbeat: None,
            last_exit: 0,
            last_reason: String::new(),
            segment: 0,
            given_up: 0,
            error_exits: 0,
            last_error_exit: String::new(),
        });
    }
    let recording = names.contains(&"recorder");
    if interactive {
        println!(
            "hubtrack run: stages {}; {}",
            names.join(", "),
            if recording {
                format!("recording to {}", record.display())
            } else {
                "not recording".into()
            }
        );
    }
    let mut sup = Supervisor {
        config: config.clone(),
        config_args,
        record: record.clone(),
        outcome,
        stage_stdout_to_stderr: !interactive,
        stages,
    };
    let startup = Duration::from_millis(config.startup_timeout_ms);
    let liveness = Duration::from_millis(config.restart.liveness_timeout_ms);

    // Start in order, each after the previous one's first heartbeat: its ports exist then, so
    // nothing published later is missed (the recorder sees frame 0). A stage that dies or stays
    // silent at start goes through its restart policy like any other failure.
    let mut failure: Option<String> = None;
    for i in 0..sup.stages.len() {
        if shutdown.requested() {
            break;
        }
        sup.start(i)?;
        let t0 = Instant::now();
        loop {
            drain(&heartbeats, &mut sup, &mut last_status)?;
            logs.forward();
            if sup.stages[i].last_heartbeat.is_some() || shutdown.requested() {
                break;
            }
            if let Some(st) = sup.stages[i].process.as_mut().and_then(|p| p.poll()) {
                sup.ended(i, exit_code(st), format!("exit {st} during start-up"), true);
                break;
            }
            if t0.elapsed() > startup {
                if let Some(p) = sup.stages[i].process.as_mut() {
                    signal(p.pid(), libc::SIGKILL);
                    let _ = p.child.wait();
                }
                sup.ended(
                    i,
                    -9,
                    format!("no heartbeat within {} ms of start", startup.as_millis()),
                    true,
                );
                break;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    let started = Instant::now();
    let deadline = duration;
    let mut status_at = Instant::now() - STATUS_PERIOD;
    while failure.is_none()
        && !shutdown.requested()
        && deadline.is_none_or(|d| started.elapsed() < d)
    {
        std::thread::sleep(TICK);
        drain(&heartbeats, &mut sup, &mut last_status)?;
        logs.forward();
        let now = Instant::now();
        for i in 0..sup.stages.len() {
            let s = &mut sup.stages[i];
            if let Some(p) = s.process.as_mut() {
                if let Some(st) = p.poll() {
                    let code = exit_code(st);
                    let clean = st.success();
                    if clean && FRAME_SOURCES.contains(&s.name) {
                        // The source ended (end of file, max_frames, flight over): the run is complete.
                        log::info!("{} finished: ending the run", s.name);
                        s.process = None;
                        s.state = StageState::Stopped;
                        failure = Some(String::new());
                        break;
                    }
                    let reason = match p.last_error() {
                        Some(e) => format!("{st}: {e}"),
                        None => st.to_string(),
                    };
                    sup.ended(i, code, reason, !clean);
                    let s = &sup.stages[i];
                    if s.state == StageState::Failed && FRAME_SOURCES.contains(&s.name) {
                        // Without frames nothing else can work: say why and end the run.
                        failure = Some(format!(
                            "the frame source {} was given up on ({}); ending the run",
                            s.name, s.last_reason
                        ));
                        break;
                    }
                    continue;
                }
                // Liveness: running stages must keep heart-beating (a SIGSTOPped or deadlocked
                // process still exists but does nothing).
                let last = s.last_heartbeat.unwrap_or(p.started);
                let limit = if s.last_heartbeat.is_some() {
                    liveness
                } else {
                    startup
                };
                if now.duration_since(last) > limit {
                    log::error!(
                        "{} sent no heartbeat for {:?}: killing it (hung)",
                        s.name,
                        now.duration_since(last)
                    );
                    signal(p.pid(), libc::SIGKILL);
                    let st = p.child.wait().ok();
                    let code = st.map_or(-9, exit_code);
                    sup.ended(
                        i,
                        code,
                        format!("no heartbeat for {} ms", limit.as_millis()),
                        true,
                    );
                }
            } else if s.next_start.is_some_and(|t| now >= t) {
                if let Err(e) = sup.start(i) {
                    log::error!("{e:#}");
                    sup.ended(i, -1, format!("{e:#}"), true);
                }
            }
        }
        if status_at.elapsed() >= STATUS_PERIOD {
            status_at = Instant::now();
            let _ = status_pub.publish(sup.status());
        }
    }
    let elapsed = started.elapsed();
    let failure = failure.filter(|f| !f.is_empty());

    let timeout = Duration::from_millis(config.stop_timeout_ms);
    for s in sup.stages.iter_mut().rev() {
        if let Some(p) = s.process.as_mut() {
            let st = p.stop(timeout);
            log::info!(
                "stopped {} after {:.1} s ({})",
                s.name,
                p.started.elapsed().as_secs_f64(),
                st.map_or("unknown".into(), |x| x.to_string())
            );
            s.state = StageState::Stopped;
        }
        s.process = None;
    }
    let _ = status_pub.publish(sup.status());
    std::thread::sleep(Duration::from_millis(20));
    drain(&heartbeats, &mut sup, &mut last_status)?;
    let segments: Vec<PathBuf> = match sup.stages.iter().find(|s| s.name == "recorder") {
        Some(r) => (0..=r.segment)
            .map(|n| segment_path(&record, n))
            .filter(|p| p.exists())
            .collect(),
        None => Vec::new(),
    };
    if interactive {
        crate::summary::print_summary(elapsed, &last_status, &segments);
        for s in &sup.stages {
            if s.restarts > 0 || s.state == StageState::Failed {
                println!(
                    "  {:<9} {} restarts{}",
                    s.name,
                    s.restarts,
                    if s.state == StageState::Failed {
                        ", given up"
                    } else {
                        ""
                    }
                );
            }
        }
    }
    let failure = failure.or_else(|| run_failure(&sup.stages));
    Ok(RunReport { elapsed, failure })
}

/// Why a run that reached its end still failed: every stage given up on (with its last reason)
/// and a recorder that could not write (a recording with a hole is not a good run).
fn run_failure(stages: &[Supervised]) -> Option<String> {
    let mut why: Vec<String> = stages
        .iter()
        .filter(|s| s.given_up > 0)
        .map(|s| {
            format!(
                "stage {} was given up on{} ({})",
                s.name,
                match (s.given_up, s.state == StageState::Failed) {
                    (1, true) => String::new(),
                    (n, true) => format!(" {n} times"),
                    (n, false) => format!(" {n} times (running again at the end)"),
                },
                s.last_reason
            )
        })
        .collect();
    if let Some(r) = stages
        .iter()
        .find(|s| s.name == "recorder" && s.error_exits > 0 && s.given_up == 0)
    {
        why.push(format!(
            "the recorder failed {} time(s) and the recording has holes (last: {})",
            r.error_exits, r.last_error_exit
        ));
    }
    (!why.is_empty()).then(|| why.join("; "))
}

fn drain(
    heartbeats: &MsgSubscriber<StageStatus>,
    sup: &mut Supervisor,
    last: &mut BTreeMap<String, StageStatus>,
) -> anyhow::Result<()> {
    while let Some(hb) = heartbeats.receive()? {
        let name = hb.stage.as_str().to_string();
        if let Some(s) = sup.stages.iter_mut().find(|s| s.name == name) {
            if s.process.as_ref().is_some_and(|p| p.pid() == hb.pid) {
                s.last_heartbeat = Some(Instant::now());
                if s.state == StageState::Starting {
                    s.state = StageState::Running;
                }
            }
        }
        last.insert(name, hb);
    }
    Ok(())
}
