//! `hubtrack replay`: feeds a recording's inputs to chosen stages in place of their live
//! publishers and records their new outputs next to the old file.
//!
//! The recording is streamed (frames are never all in memory). Everything runs in a private IPC
//! domain, so a live pipeline on the same machine is not disturbed. In lossless mode replay works
//! in lock-step: it publishes the input of frame N, then waits for the last chosen stage's output
//! for N before going on, so nothing is dropped and the stages see exactly the recorded inputs;
//! re-running a deterministic stage then reproduces the recorded output bit for bit.

use crate::launch::{stage_binary, Stage};
use anyhow::{bail, Context};
use hubtrack_record::raw_image::RawImage;
use hubtrack_record::writer::{ChannelKind, FRAMES_TOPIC};
use hubtrack_runtime::config::ConfigArgs;
use hubtrack_runtime::ipc::{open_node, FramePublisher, IpcError, MsgPublisher, MsgSubscriber, DOMAIN_ENV};
use hubtrack_types::services::{DETECTIONS, STATUS, TRACK, VEHICLE};
use hubtrack_types::{Detection, FrameHeader, FrameSourceKind, StageStatus, TrackState, VehicleState};
use mcap::sans_io::LinearReaderOptions;
use prost::Message as _;
use serde_json::Value;
use std::collections::BTreeMap;
use std::io::BufReader;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Stages replay can feed, with the input channels each needs.
const REPLAYABLE: &[&str] = &["detect", "track"];
/// How long lossless replay waits for a stage's output before counting the frame as lost.
const OUTPUT_TIMEOUT: Duration = Duration::from_secs(5);
/// How long a stage may take to send its first heartbeat.
const START_TIMEOUT: Duration = Duration::from_secs(10);

/// Arguments of `hubtrack replay`.
#[derive(clap::Args)]
pub struct ReplayArgs {
    #[command(flatten)]
    pub config: ConfigArgs,
    /// The recording to replay.
    pub file: PathBuf,
    /// Stages to run on the recorded inputs, comma separated: detect (frames in), track (detections in).
    #[arg(long, value_delimiter = ',', required = true)]
    pub into: Vec<String>,
    /// Publish at the recorded pace instead of lossless lock-step.
    #[arg(long)]
    pub paced: bool,
    /// Output recording (default: <file stem>.replay.mcap next to the input).
    #[arg(long, short = 'o')]
    pub output: Option<PathBuf>,
    /// Compare the new outputs with the recorded ones.
    #[arg(long)]
    pub compare: bool,
    /// Feed every recorded frame to detect. By default only the frames the live detector
    /// processed (those with a recorded detection) are fed, so the replay reproduces the run.
    #[arg(long)]
    pub all_frames: bool,
}

/// What replay sends, in file order.
enum Input {
    Frame(FrameHeader, Vec<u8>),
    Detection(Detection),
    Vehicle(VehicleState),
}

/// Reads the inputs the chosen stages need, streaming; reports why reading stopped early.
struct Inputs {
    reader: mcap::io::MessageReader<BufReader<std::fs::File>>,
    pending_image: Option<(u32, Vec<u8>)>,
    want_frames: bool,
    want_detections: bool,
    /// Why the file ended early, if it did.
    pub stopped: Option<String>,
    /// Messages on topics replay does not use.
    pub ignored: BTreeMap<String, u64>,
    /// Messages that could not be decoded.
    pub undecodable: u64,
}

impl Iterator for Inputs {
    type Item = Input;
    fn next(&mut self) -> Option<Input> {
        loop {
            let m = match self.reader.next()? {
                Ok(m) => m,
                Err(e) => {
                    self.stopped = Some(e.to_string());
                    return None;
                }
            };
            let topic = m.channel.topic.as_str();
            match (topic, ChannelKind::from_topic(topic)) {
                (FRAMES_TOPIC, _) if self.want_frames => match RawImage::decode(m.data.as_ref()) {
                    Ok(img) => self.pending_image = Some((m.sequence, img.data)),
                    Err(_) => self.undecodable += 1,
                },
                (_, Some(ChannelKind::FrameHeader)) if self.want_frames => {
                    let Ok(h) = serde_json::from_slice::<FrameHeader>(&m.data) else {
                        self.undecodable += 1;
                        continue;
                    };
                    // The recorder writes each image right before its header.
                    match self.pending_image.take() {
                        Some((seq, pixels)) if seq == h.seq as u32 && pixels.len() == h.payload_len() => {
                            return Some(Input::Frame(h, pixels));
                        }
                        _ => self.undecodable += 1,
                    }
                }
                (_, Some(ChannelKind::Detection)) if self.want_detections => match serde_json::from_slice(&m.data) {
                    Ok(d) => return Some(Input::Detection(d)),
                    Err(_) => self.undecodable += 1,
                },
                (_, Some(ChannelKind::Vehicle)) => match serde_json::from_slice(&m.data) {
                    Ok(v) => return Some(Input::Vehicle(v)),
                    Err(_) => self.undecodable += 1,
                },
                _ => *self.ignored.entry(topic.to_string()).or_insert(0) += 1,
            }
        }
    }
}

fn open_inputs(path: &Path, want_frames: bool) -> anyhow::Result<Inputs> {
    let mut magic = [0u8; 8];
    let mut f = std::fs::File::open(path).with_context(|| format!("opening {}", path.display()))?;
    use std::io::Read;
    if f.read_exact(&mut magic).is_err() || &magic != hubtrack_record::reader::MCAP_MAGIC {
        bail!("{} is not an MCAP file (empty, or bad magic)", path.display());
    }
    let file = std::fs::File::open(path)?;
    let options = LinearReaderOptions::default().with_skip_end_magic(true);
    Ok(Inputs {
        reader: mcap::io::MessageReader::new_with_options(BufReader::new(file), options),
        pending_image: None,
        want_frames,
        want_detections: !want_frames,
        stopped: None,
        ignored: BTreeMap::new(),
        undecodable: 0,
    })
}

/// Runs the command.
pub fn run(args: ReplayArgs) -> anyhow::Result<()> {
    for s in &args.into {
        if !REPLAYABLE.contains(&s.as_str()) {
            bail!("--into {s}: replay can feed {REPLAYABLE:?}");
        }
    }
    args.config.load()?; // fail early on a bad config
    let stages: Vec<&str> = REPLAYABLE.iter().copied().filter(|s| args.into.iter().any(|i| i == s)).collect();
    let want_frames = stages.contains(&"detect");
    let last = *stages.last().expect("at least one stage");
    let output = args.output.clone().unwrap_or_else(|| {
        let stem = args.file.file_stem().map_or("recording".into(), |s| s.to_string_lossy().into_owned());
        args.file.with_file_name(format!("{stem}.replay.mcap"))
    });
    let mut inputs = open_inputs(&args.file, want_frames)?;
    // The frames the live detector consumed (it takes the newest frame and skips the rest).
    let consumed: Option<std::collections::BTreeSet<u64>> = if want_frames && !args.all_frames {
        let seqs: std::collections::BTreeSet<u64> = outputs(&args.file, "/detections")?.into_keys().collect();
        (!seqs.is_empty()).then_some(seqs)
    } else {
        None
    };
    let mut not_consumed = 0u64;

    // A private IPC domain for the replayed stages, their recorder and us.
    std::env::set_var(DOMAIN_ENV, format!("replay-{}", std::process::id()));
    let node = open_node("replay")?;
    let heartbeats = MsgSubscriber::<StageStatus>::new(&node, &STATUS, 64)?;
    let mut processes = Vec::new();
    let cfg_args = crate::forwarded(&args.config);
    let mut rec_args = cfg_args.clone();
    rec_args.extend(["--output".to_string(), output.display().to_string()]);
    for (name, a) in std::iter::once(("recorder", rec_args)).chain(stages.iter().map(|s| (*s, cfg_args.clone()))) {
        let stage = Stage::spawn(name, &stage_binary(name)?, &a, false)?;
        let pid = stage.pid();
        processes.push(stage);
        let t0 = Instant::now();
        'wait: loop {
            while let Some(hb) = heartbeats.receive()? {
                if hb.pid == pid {
                    break 'wait;
                }
            }
            if t0.elapsed() > START_TIMEOUT || processes.last_mut().and_then(|p| p.poll()).is_some() {
                for p in processes.iter_mut().rev() {
                    p.stop(Duration::from_secs(3));
                }
                bail!("stage {name} did not start");
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    let mut frames: Option<FramePublisher> = None;
    let detections = MsgPublisher::<Detection>::new(&node, &DETECTIONS)?;
    let vehicle = MsgPublisher::<VehicleState>::new(&node, &VEHICLE)?;
    let out_dets = MsgSubscriber::<Detection>::new(&node, &DETECTIONS, 64)?;
    let out_track = MsgSubscriber::<TrackState>::new(&node, &TRACK, 64)?;
    let (mut sent, mut answered, mut lost) = (0u64, 0u64, 0u64);
    let mut pace: Option<(u64, Instant)> = None;
    let t_start = Instant::now();
    for input in inputs.by_ref() {
        let (seq, capture_ns) = match input {
            Input::Vehicle(v) => {
                vehicle.publish(v)?;
                continue;
            }
            Input::Frame(h, _) if consumed.as_ref().is_some_and(|c| !c.contains(&h.seq)) => {
                not_consumed += 1;
                continue;
            }
            Input::Frame(mut h, pixels) => {
                let publisher = match &frames {
                    Some(p) => p,
                    None => frames.insert(FramePublisher::new(&node, pixels.len())?),
                };
                h.source = FrameSourceKind::Replay;
                let (seq, cap) = (h.seq, h.capture_ns);
                wait_pace(&mut pace, cap, args.paced);
                publisher.publish_with(h, |buf, _| {
                    buf.copy_from_slice(&pixels);
                    Ok::<(), IpcError>(())
                })?;
                (seq, cap)
            }
            Input::Detection(d) => {
                wait_pace(&mut pace, d.stamps.capture_ns, args.paced);
                detections.publish(d)?;
                (d.stamps.seq, d.stamps.capture_ns)
            }
        };
        let _ = capture_ns;
        sent += 1;
        if args.paced {
            continue;
        }
        // Lock-step: wait for the last stage's output for this frame.
        let deadline = Instant::now() + OUTPUT_TIMEOUT;
        let got = loop {
            let done = if last == "track" {
                out_track.wait(Duration::from_millis(50));
                std::iter::from_fn(|| out_track.receive().ok().flatten()).any(|t| t.stamps.seq == seq)
            } else {
                out_dets.wait(Duration::from_millis(50));
                std::iter::from_fn(|| out_dets.receive().ok().flatten()).any(|d| d.stamps.seq == seq)
            };
            if done {
                break true;
            }
            if Instant::now() > deadline {
                break false;
            }
        };
        if got {
            answered += 1;
        } else {
            lost += 1;
            log::warn!("no {last} output for frame {seq} within {OUTPUT_TIMEOUT:?}");
        }
    }
    // Let the recorder take the last outputs, then stop the stages (recorder last).
    std::thread::sleep(Duration::from_millis(300));
    for p in processes.iter_mut().rev() {
        p.stop(Duration::from_secs(10));
    }
    let secs = t_start.elapsed().as_secs_f64();
    println!(
        "replayed {} inputs of {} into {} in {:.1} s ({}): {} answered, {} without output",
        sent,
        args.file.display(),
        stages.join(","),
        secs,
        if args.paced { "recorded pace" } else { "lossless lock-step" },
        answered,
        lost
    );
    if not_consumed > 0 {
        println!("note: {not_consumed} recorded frames were skipped live by detect and are not fed (--all-frames feeds them)");
    }
    if let Some(why) = &inputs.stopped {
        println!("note: {} is cut or damaged; replayed what was intact (reading stopped: {why})", args.file.display());
    }
    if inputs.undecodable > 0 {
        println!("note: {} messages could not be decoded and were skipped", inputs.undecodable);
    }
    if sent == 0 {
        bail!(
            "{} holds no {} to replay (topics seen: {:?})",
            args.file.display(),
            if want_frames { "frames" } else { "detections" },
            inputs.ignored.keys().collect::<Vec<_>>()
        );
    }
    println!("new outputs recorded to {}", output.display());
    if args.compare {
        compare(&args.file, &output, &stages)?;
    }
    Ok(())
}

fn wait_pace(pace: &mut Option<(u64, Instant)>, capture_ns: u64, paced: bool) {
    if !paced {
        return;
    }
    let (t0, w0) = *pace.get_or_insert((capture_ns, Instant::now()));
    let due = w0 + Duration::from_nanos(capture_ns.saturating_sub(t0));
    if let Some(d) = due.checked_duration_since(Instant::now()) {
        std::thread::sleep(d);
    }
}

/// Fields that legitimately differ between runs (times measured on this run), removed before comparing.
fn strip_run_specific(topic: &str, mut v: Value) -> Value {
    if let Some(s) = v.get_mut("stamps").and_then(Value::as_object_mut) {
        s.remove("recv_ns");
        s.remove("publish_ns");
    }
    if topic == "/detections" {
        if let Some(o) = v.as_object_mut() {
            o.remove("timings");
            o.remove("frames_skipped");
        }
    }
    v
}

fn largest_difference(a: &Value, b: &Value) -> f64 {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => (x.as_f64().unwrap_or(0.0) - y.as_f64().unwrap_or(0.0)).abs(),
        (Value::Array(x), Value::Array(y)) => x.iter().zip(y).map(|(p, q)| largest_difference(p, q)).fold(0.0, f64::max),
        (Value::Object(x), Value::Object(y)) => {
            x.iter().map(|(k, p)| y.get(k).map_or(f64::INFINITY, |q| largest_difference(p, q))).fold(0.0, f64::max)
        }
        (p, q) if p == q => 0.0,
        _ => f64::INFINITY,
    }
}

fn outputs(path: &Path, topic: &str) -> anyhow::Result<BTreeMap<u64, Value>> {
    let file = std::fs::File::open(path)?;
    let mut out = BTreeMap::new();
    let options = LinearReaderOptions::default().with_skip_end_magic(true);
    for m in mcap::io::MessageReader::new_with_options(BufReader::new(file), options) {
        let Ok(m) = m else { break };
        if m.channel.topic == topic {
            if let Ok(v) = serde_json::from_slice::<Value>(&m.data) {
                let seq = v["stamps"]["seq"].as_u64().unwrap_or(u64::from(m.sequence));
                out.insert(seq, strip_run_specific(topic, v));
            }
        }
    }
    Ok(out)
}

/// Per channel: messages compared, reproduced exactly, and the largest numeric difference.
fn compare(old: &Path, new: &Path, stages: &[&str]) -> anyhow::Result<()> {
    println!("\ncomparison with the recorded outputs (run-specific times excluded):");
    println!("{:<14}{:>10}{:>10}{:>12}{:>12}{:>18}", "channel", "compared", "exact", "only old", "only new", "largest diff");
    for (stage, topic) in [("detect", "/detections"), ("track", "/track")] {
        if !stages.contains(&stage) {
            continue;
        }
        let (a, b) = (outputs(old, topic)?, outputs(new, topic)?);
        let mut exact = 0;
        let mut worst = 0.0f64;
        let mut compared = 0;
        for (seq, va) in &a {
            if let Some(vb) = b.get(seq) {
                compared += 1;
                if va == vb {
                    exact += 1;
                } else {
                    worst = worst.max(largest_difference(va, vb));
                }
            }
        }
        let only_old = a.keys().filter(|k| !b.contains_key(k)).count();
        let only_new = b.keys().filter(|k| !a.contains_key(k)).count();
        println!("{topic:<14}{compared:>10}{exact:>10}{only_old:>12}{only_new:>12}{worst:>18.6}");
    }
    Ok(())
}
