//! `hubtrack replay`: feeds a recording's inputs to chosen stages in place of their live
//! publishers and records their new outputs next to the old file.
//!
//! The recording is streamed (frames are never all in memory). Everything runs in a private IPC
//! domain, so a live pipeline on the same machine is not disturbed. In lossless mode replay works
//! in lock-step: it publishes the input of frame N, then waits for the last chosen stage's output
//! for N before going on, so nothing is dropped and the stages see exactly the recorded inputs;
//! re-running a deterministic stage then reproduces the recorded output bit for bit.
//!
//! The first chosen stage is fed its recorded inputs (frames for detect, detections for track,
//! track states for control) together with the recorded vehicle states, in the order the live
//! stage took them ([`inputs`]). Control runs in its replay mode (`hubtrack-control --replay`):
//! no MAVLink link, vehicle states from the vehicle service, recorded time.

mod compare;
mod inputs;
mod output;

use crate::launch::{stage_binary, Stage};
use anyhow::bail;
use hubtrack_runtime::config::ConfigArgs;
use hubtrack_runtime::ipc::{
    open_node, FramePublisher, IpcError, MsgPublisher, MsgSubscriber, DOMAIN_ENV,
};
use hubtrack_types::services::{DETECTIONS, SETPOINTS, STATUS, TRACK, VEHICLE};
use hubtrack_types::{Detection, FrameSourceKind, Setpoint, StageStatus, TrackState, VehicleState};
use inputs::{FirstStage, Input, Keyed, Ordered, Reader};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Stages replay can feed, in pipeline order.
const REPLAYABLE: &[&str] = &["detect", "track", "control"];
/// How long lossless replay waits for a stage's output before counting the frame as lost.
const OUTPUT_TIMEOUT: Duration = Duration::from_secs(5);
/// How long a stage may take to send its first heartbeat.
const START_TIMEOUT: Duration = Duration::from_secs(10);
/// Poll period while waiting for an output in lock-step (an output wakes the wait at once).
const OUTPUT_POLL: Duration = Duration::from_millis(50);
/// Time for the recorder to take the last outputs before the stages are stopped.
const RECORDER_SETTLE: Duration = Duration::from_millis(300);
/// How long a stage may take to stop cleanly.
const STOP_TIMEOUT: Duration = Duration::from_secs(10);

/// Arguments of `hubtrack replay`.
#[derive(clap::Args)]
pub struct ReplayArgs {
    #[command(flatten)]
    /// Config file and overrides, passed on to the replayed stages.
    pub config: ConfigArgs,
    /// The recording to replay.
    pub file: PathBuf,
    /// Stages to run on the recorded inputs, comma separated, consecutive in the pipeline:
    /// detect (frames in), track (detections in), control (track states in); vehicle states
    /// are always fed.
    #[arg(long, value_delimiter = ',', required = true)]
    pub into: Vec<String>,
    /// Publish at the recorded pace instead of lossless lock-step.
    #[arg(long)]
    pub paced: bool,
    /// Output recording (default: <file stem>.replay.mcap next to the input). Never the input;
    /// an existing file is refused unless --force.
    #[arg(long, short = 'o')]
    pub output: Option<PathBuf>,
    /// Replace the output file if it exists (once the replay is finished).
    #[arg(long)]
    pub force: bool,
    /// Compare the new outputs with the recorded ones.
    #[arg(long)]
    pub compare: bool,
    /// Feed every recorded input to the first stage. By default only those the live stage
    /// processed (those with a recorded output: detect skips frames to stay on the newest) are
    /// fed, so the replay reproduces the run.
    #[arg(long, alias = "all-frames")]
    pub all_inputs: bool,
}

/// The chosen stages in pipeline order; they must be consecutive.
fn chosen_stages(into: &[String]) -> anyhow::Result<Vec<&'static str>> {
    for s in into {
        if !REPLAYABLE.contains(&s.as_str()) {
            bail!("--into {s}: replay can feed {REPLAYABLE:?}");
        }
    }
    let idx: Vec<usize> = (0..REPLAYABLE.len())
        .filter(|i| into.iter().any(|s| s == REPLAYABLE[*i]))
        .collect();
    if idx.windows(2).any(|w| w[1] != w[0] + 1) {
        bail!(
            "--into {}: the stages must follow each other in the pipeline (detect, track, control)",
            into.join(",")
        );
    }
    Ok(idx.into_iter().map(|i| REPLAYABLE[i]).collect())
}

/// The last chosen stage's outputs, awaited in lock-step.
enum LastOutputs {
    Detections(MsgSubscriber<Detection>),
    Track(MsgSubscriber<TrackState>),
    Setpoints(MsgSubscriber<Setpoint>),
}

impl LastOutputs {
    /// Waits up to `timeout` for the output for frame `seq`.
    fn wait_for(&self, seq: u64, timeout: Duration) -> bool {
        let deadline = Instant::now() + timeout;
        loop {
            let done = match self {
                LastOutputs::Detections(s) => {
                    s.wait(OUTPUT_POLL);
                    std::iter::from_fn(|| s.receive().ok().flatten()).any(|d| d.stamps.seq == seq)
                }
                LastOutputs::Track(s) => {
                    s.wait(OUTPUT_POLL);
                    std::iter::from_fn(|| s.receive().ok().flatten()).any(|t| t.stamps.seq == seq)
                }
                LastOutputs::Setpoints(s) => {
                    s.wait(OUTPUT_POLL);
                    std::iter::from_fn(|| s.receive().ok().flatten()).any(|p| p.stamps.seq == seq)
                }
            };
            if done {
                return true;
            }
            if Instant::now() > deadline {
                return false;
            }
        }
    }
}

/// Publishers for the recorded inputs.
struct InputPublishers {
    node: iceoryx2::prelude::Node<hubtrack_runtime::ipc::Ipc>,
    frames: Option<FramePublisher>,
    detections: Option<MsgPublisher<Detection>>,
    tracks: Option<MsgPublisher<TrackState>>,
    vehicle: MsgPublisher<VehicleState>,
}

impl InputPublishers {
    /// Publishes one input; returns the seq of a driving input.
    fn publish(&mut self, input: Input) -> anyhow::Result<Option<u64>> {
        let seq = input.driver_seq();
        match input {
            Input::Vehicle(v) => {
                self.vehicle.publish(v)?;
            }
            Input::Frame(mut h, pixels) => {
                let publisher = match &self.frames {
                    Some(p) => p,
                    None => self
                        .frames
                        .insert(FramePublisher::new(&self.node, pixels.len())?),
                };
                h.source = FrameSourceKind::Replay;
                h.camera_jpeg_len = 0; // replay carries the pixels only
                publisher.publish_with(h, |buf, _| {
                    buf.copy_from_slice(&pixels);
                    Ok::<(), IpcError>(())
                })?;
            }
            Input::Detection(d) => {
                let p = match &self.detections {
                    Some(p) => p,
                    None => self
                        .detections
                        .insert(MsgPublisher::new(&self.node, &DETECTIONS)?),
                };
                p.publish(d)?;
            }
            Input::Track(t) => {
                let p = match &self.tracks {
                    Some(p) => p,
                    None => self.tracks.insert(MsgPublisher::new(&self.node, &TRACK)?),
                };
                p.publish(t)?;
            }
        }
        Ok(seq)
    }
}

/// Recorded pace: the first input goes now, the others at their live distance from it (by
/// their order keys: when the live stage took a driving input, when a vehicle state was
/// published), so vehicle states fall between the inputs as they did live. Inactive in lock-step.
struct Pace {
    active: bool,
    origin: Option<(u64, Instant)>,
}

impl Pace {
    fn wait(&mut self, key_ns: u64) {
        if !self.active {
            return;
        }
        let (t0, w0) = *self.origin.get_or_insert((key_ns, Instant::now()));
        let due = w0 + Duration::from_nanos(key_ns.saturating_sub(t0));
        if let Some(d) = due.checked_duration_since(Instant::now()) {
            std::thread::sleep(d);
        }
    }
}

/// Starts the recorder and the stages (recorder first), each after the previous one's first
/// heartbeat.
fn start_stages(
    heartbeats: &MsgSubscriber<StageStatus>,
    stages: &[&str],
    cfg_args: &[String],
    output: &std::path::Path,
) -> anyhow::Result<Vec<Stage>> {
    let mut rec_args = cfg_args.to_vec();
    rec_args.extend(["--output".to_string(), output.display().to_string()]);
    let mut processes: Vec<Stage> = Vec::new();
    let with_mode = |s: &str| {
        let mut a = cfg_args.to_vec();
        if s == "control" {
            // No autopilot: vehicle states come from the recording, time from the track states.
            a.push("--replay".into());
        }
        a
    };
    for (name, a) in
        std::iter::once(("recorder", rec_args)).chain(stages.iter().map(|s| (*s, with_mode(s))))
    {
        let stage = Stage::spawn(name, &stage_binary(name)?, &a, false, 0, true)?;
        let pid = stage.pid();
        processes.push(stage);
        let t0 = Instant::now();
        'wait: loop {
            while let Some(hb) = heartbeats.receive()? {
                if hb.pid == pid {
                    break 'wait;
                }
            }
            if t0.elapsed() > START_TIMEOUT || processes.last_mut().and_then(|p| p.poll()).is_some()
            {
                for p in processes.iter_mut().rev() {
                    p.stop(Duration::from_secs(3));
                }
                bail!("stage {name} did not start");
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }
    Ok(processes)
}

hubtrack_runtime::sections! {
    /// The camera section, to check the recording's frames against its calibration.
    struct CameraSection { camera: hubtrack_types::setup::CameraSetup }
}

/// A calibration that cannot describe the recorded frames is said before any stage starts:
/// detect would refuse every frame, each after the replay's wait for an output.
fn check_calibration_fits(args: &ReplayArgs, width: u32, height: u32) -> anyhow::Result<()> {
    let section: CameraSection = args.config.load()?;
    if let Some(calibration) = section.camera.calibrated()? {
        calibration.scaled_to(width, height).map_err(|e| {
            anyhow::anyhow!(
                "{}: its frames cannot be detected with {}: {e}",
                args.file.display(),
                section.camera.calibration
            )
        })?;
    }
    Ok(())
}

/// Runs the command.
pub fn run(args: ReplayArgs) -> anyhow::Result<()> {
    let stages = chosen_stages(&args.into)?;
    // Fail early on a bad config: every stage replayed (and the recorder) checks its sections.
    let mut checked: Vec<String> = stages.iter().map(|s| s.to_string()).collect();
    checked.push("recorder".into());
    crate::config_check::check(&args.config, crate::config_check::Scope::Stages(&checked))?;
    let first = match stages[0] {
        "detect" => FirstStage::Detect,
        "track" => FirstStage::Track,
        _ => FirstStage::Control,
    };
    let last = *stages.last().expect("at least one stage");
    let output = args.output.clone().unwrap_or_else(|| {
        let stem = args
            .file
            .file_stem()
            .map_or("recording".into(), |s| s.to_string_lossy().into_owned());
        args.file.with_file_name(format!("{stem}.replay.mcap"))
    });
    output::check(&args.file, &output, args.force)?;
    // One pass first: what the live first stage took and when, and whether there is anything to feed.
    let survey = inputs::survey(&args.file, first)?;
    if survey.drivers == 0 {
        let mut why = String::new();
        if let Some(e) = &survey.stopped {
            why = format!("; reading stopped: {e}");
        }
        bail!(
            "{} holds no {} to replay (--into {} needs them; topics seen: {:?}{why})",
            args.file.display(),
            first.drivers(),
            first.name(),
            survey.topics.keys().collect::<Vec<_>>()
        );
    }
    if let Some((width, height)) = survey.frame_size {
        check_calibration_fits(&args, width, height)?;
    }
    let mut reader = Reader::open(&args.file, first)?;

    // A private IPC domain for the replayed stages, their recorder and us.
    std::env::set_var(DOMAIN_ENV, format!("replay-{}", std::process::id()));
    let node = open_node("replay")?;
    let heartbeats = MsgSubscriber::<StageStatus>::new(&node, &STATUS, 64)?;
    let mut processes = start_stages(
        &heartbeats,
        &stages,
        &args.config.to_args(),
        &output::partial(&output),
    )?;

    let outputs = match last {
        "detect" => LastOutputs::Detections(MsgSubscriber::new(&node, &DETECTIONS, 64)?),
        "track" => LastOutputs::Track(MsgSubscriber::new(&node, &TRACK, 64)?),
        _ => LastOutputs::Setpoints(MsgSubscriber::new(&node, &SETPOINTS, 64)?),
    };
    let vehicle = MsgPublisher::<VehicleState>::new(&node, &VEHICLE)?;
    let mut publishers = InputPublishers {
        node,
        frames: None,
        detections: None,
        tracks: None,
        vehicle,
    };
    let mut pace = Pace {
        active: args.paced,
        origin: None,
    };
    let (mut sent, mut answered, mut lost, mut vehicles, mut not_taken) =
        (0u64, 0u64, 0u64, 0u64, 0u64);
    let t_start = Instant::now();
    {
        // Inputs the live stage skipped are left out (unless --all-inputs, or nothing says
        // which were taken); the rest keyed by when the live stage took them.
        let feed_all = args.all_inputs || survey.taken.is_empty();
        let keyed = reader.by_ref().filter_map(|input| {
            let key = match input.driver_seq() {
                None => input.publish_ns(),
                Some(seq) => match survey.taken.get(&seq) {
                    Some(&recv_ns) => recv_ns,
                    None if feed_all => input.publish_ns(),
                    None => {
                        not_taken += 1;
                        return None;
                    }
                },
            };
            Some(Keyed { key, input })
        });
        for k in Ordered::new(keyed, survey.vehicles) {
            pace.wait(k.key);
            let Some(seq) = publishers.publish(k.input)? else {
                vehicles += 1;
                continue;
            };
            sent += 1;
            if args.paced {
                continue;
            }
            // Lock-step: wait for the last stage's output for this frame.
            if outputs.wait_for(seq, OUTPUT_TIMEOUT) {
                answered += 1;
            } else {
                lost += 1;
                log::warn!("no {last} output for frame {seq} within {OUTPUT_TIMEOUT:?}");
            }
        }
    }
    // Let the recorder take the last outputs, then stop the stages (recorder last).
    std::thread::sleep(RECORDER_SETTLE);
    for p in processes.iter_mut().rev() {
        p.stop(STOP_TIMEOUT);
    }
    let secs = t_start.elapsed().as_secs_f64();
    println!(
        "replayed {} inputs ({}) and {} vehicle states of {} into {} in {:.1} s ({}): {} answered, {} without output",
        sent,
        first.drivers(),
        vehicles,
        args.file.display(),
        stages.join(","),
        secs,
        if args.paced { "recorded pace" } else { "lossless lock-step" },
        answered,
        lost
    );
    if not_taken > 0 {
        println!(
            "note: {not_taken} recorded {} were not processed live by {} and are not fed (--all-inputs feeds them)",
            first.drivers(),
            first.name()
        );
    }
    if let Some(why) = &reader.stopped {
        println!(
            "note: {} is cut or damaged; replayed what was intact (reading stopped: {why})",
            args.file.display()
        );
    }
    if reader.undecodable > 0 {
        println!(
            "note: {} messages could not be decoded and were skipped",
            reader.undecodable
        );
    }
    if reader.frames_bad > 0 {
        println!(
            "note: {} frames whose image did not decode (corrupt or truncated) were skipped",
            reader.frames_bad
        );
    }
    if reader.frames_lossy > 0 {
        println!(
            "note: {} of the frames were decoded from JPEG/H.264 (lossy): detect's results differ from the live run by the compression; \
             recorder.frame_encoding = \"raw\" (or recorder.raw_every) records frames for bit-exact replay",
            reader.frames_lossy
        );
    }
    if sent == 0 {
        let _ = std::fs::remove_file(output::partial(&output));
        bail!(
            "{} holds no readable {} to replay",
            args.file.display(),
            first.drivers()
        );
    }
    output::publish(&args.file, &output, args.force)?;
    println!("new outputs recorded to {}", output.display());
    if args.compare {
        compare::compare(&args.file, &output, &stages)?;
        if reader.frames_lossy > 0 {
            println!(
                "(inputs decoded from JPEG/H.264: differences in /detections and after are expected from the compression)"
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn into(s: &str) -> Vec<String> {
        s.split(',').map(String::from).collect()
    }

    #[test]
    fn stages_come_in_pipeline_order_and_must_follow_each_other() {
        assert_eq!(
            chosen_stages(&into("control,track")).unwrap(),
            ["track", "control"]
        );
        assert_eq!(
            chosen_stages(&into("detect,track,control")).unwrap(),
            ["detect", "track", "control"]
        );
        assert_eq!(chosen_stages(&into("control")).unwrap(), ["control"]);
        let e = chosen_stages(&into("detect,control"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("follow each other"), "{e}");
        let e = chosen_stages(&into("recorder")).unwrap_err().to_string();
        assert!(e.contains("--into recorder"), "{e}");
    }
}
